// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_blobby.cpp
/// Blobby implicit surfaces (RISpec 3.2 5.6): the field of the decoded
/// program (blobby.h) is polygonized by surface nets on a regular grid in
/// object space, one vertex per grid cell the surface crosses, moved onto
/// the surface by Newton steps along the field's analytic gradient, and one
/// quad around every grid edge the surface crosses. The mesh, with normals
/// from the gradient and the per-leaf primitive variables blended by the
/// leaves' fields, is diced by the polygon dicer like Curves' ribbons, so
/// that displacement, Cs, the texture coordinates and baking work as on any
/// mesh.
///
/// The grid's cell is four micropolygon edges (finer for small blobs), at
/// most kMaxCellsPerSide cells along a side and kMaxCells in all (fewer
/// with a small micropolygon budget); the grid is swept one layer of cells
/// at a time, so memory grows with a layer, not with the volume. Its outermost points
/// count as outside, so the mesh is closed even where a constant field would reach beyond
/// the blobs.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>
#include <glm/vector_relational.hpp>

#include "dice_common.h"
#include "mesh_common.h"
#include "sss/scene/blobby.h"
#include "sss/util/math.h"
#include "sss/util/messages.h"

namespace sss::detail {

namespace {

using glm::dvec3;

/// The grid's size limits: memory is two layers of points and cells, time
/// the number of points.
constexpr std::size_t kMaxCellsPerSide = 1024;
constexpr double kMaxCells = 33554432.0; // 2^25
/// Cells per support radius of the smallest blob wanted, and the fewest
/// tolerated when the grid is capped (for blobs of a radius of two
/// micropolygon edges or more; smaller ones may then vanish).
constexpr double kCellsPerRadius = 4.0;
constexpr double kFewestCellsPerRadius = 2.0;
/// Micropolygon edges per grid cell (the polygon dicer dices the quads).
constexpr double kEdgesPerCell = 4.0;
/// Grid cells allowed per micropolygon of the budget
/// (DiceControl::max_micropolygons).
constexpr double kCellsPerMicropolygon = 64.0;

/// A field value and its gradient (object space).
struct Dual {
    double v = 0.0;
    dvec3 g{0.0};
};

/// An axis-aligned box in object space.
struct Box {
    dvec3 lo{std::numeric_limits<double>::infinity()};
    dvec3 hi{-std::numeric_limits<double>::infinity()};
    bool empty() const { return !(lo.x <= hi.x); }
    void add(const dvec3& p) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    void add(const Box& b) {
        if (!b.empty()) {
            add(b.lo);
            add(b.hi);
        }
    }
    bool contains(const dvec3& p) const {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z &&
               p.z <= hi.z;
    }
};

dvec3 affine(const Matrix4& m, const dvec3& p) {
    return dvec3(m * glm::dvec4(p, 1.0));
}

/// The soft-object falloff of r^2 in [0, 1): (1 - r^2)^3, and its derivative.
double falloff(double r2) {
    const double a = 1.0 - r2;
    return a * a * a;
}
double falloff_slope(double r2) {
    const double a = 1.0 - r2;
    return -3.0 * a * a;
}

/// The ellipsoids and segments whose supports overlap each bin of a
/// regular grid over their bounds: the only leaves that can be non-zero at
/// a point are those of its bin.
class LeafBins {
public:
    LeafBins() = default;
    LeafBins(const Box& bounds, const std::vector<std::size_t>& items,
             const std::vector<Box>& boxes) {
        m_lo = bounds.lo;
        // Bins about half the size of a blob, at most kMaxBins along a side.
        dvec3 mean(0.0);
        for (std::size_t k : items) mean += boxes[k].hi - boxes[k].lo;
        mean /= static_cast<double>(items.size());
        const dvec3 extent = bounds.hi - bounds.lo;
        for (int a = 0; a < 3; ++a) {
            const double n =
                std::clamp(std::floor(2.0 * extent[a] / mean[a]), 1.0, kMaxBins);
            m_n[a] = static_cast<std::size_t>(n);
            m_size[a] = extent[a] / n;
        }
        std::vector<std::vector<uint32_t>> lists(m_n[0] * m_n[1] * m_n[2]);
        for (std::size_t k : items) {
            const std::array<std::size_t, 3> lo = bin(boxes[k].lo), hi = bin(boxes[k].hi);
            for (std::size_t z = lo[2]; z <= hi[2]; ++z)
                for (std::size_t y = lo[1]; y <= hi[1]; ++y)
                    for (std::size_t x = lo[0]; x <= hi[0]; ++x)
                        lists[index(x, y, z)].push_back(static_cast<uint32_t>(k));
        }
        m_first.reserve(lists.size() + 1);
        for (const auto& l : lists) {
            m_first.push_back(m_items.size());
            m_items.insert(m_items.end(), l.begin(), l.end());
        }
        m_first.push_back(m_items.size());
    }

    /// The items of the bin of p (p inside the bounds).
    std::pair<const uint32_t*, const uint32_t*> at(const dvec3& p) const {
        const std::array<std::size_t, 3> b = bin(p);
        const std::size_t i = index(b[0], b[1], b[2]);
        return {m_items.data() + m_first[i], m_items.data() + m_first[i + 1]};
    }

private:
    static constexpr double kMaxBins = 64.0;

    std::array<std::size_t, 3> bin(const dvec3& p) const {
        std::array<std::size_t, 3> b{};
        for (int a = 0; a < 3; ++a) {
            const double x = std::floor((p[a] - m_lo[a]) / m_size[a]);
            b[a] = static_cast<std::size_t>(std::clamp(x, 0.0, double(m_n[a] - 1)));
        }
        return b;
    }
    std::size_t index(std::size_t x, std::size_t y, std::size_t z) const {
        return (z * m_n[1] + y) * m_n[0] + x;
    }

    dvec3 m_lo{0.0}, m_size{1.0};
    std::array<std::size_t, 3> m_n{1, 1, 1};
    std::vector<std::size_t> m_first;
    std::vector<uint32_t> m_items;
};

/// An item that uses another: how many times, the first at which operand.
struct Link {
    uint32_t parent = 0;
    uint32_t count = 0;
    uint32_t first = 0;
};

/// The field of a Blobby program in its object space. Ellipsoids and
/// segments vanish outside their supports, so a point evaluates only the
/// leaves whose support holds it and the items that depend on them; every
/// other item keeps its background value (all such leaves 0). Not to be
/// shared between threads (scratch space).
class BlobbyField {
public:
    BlobbyField(const Primitive& prim, const DiceControl& control) {
        try {
            m_program = decode_blobby(prim);
        } catch (const ValueError& e) {
            fail(prim, e.what());
        }
        const std::size_t n = m_program.items.size();
        m_boxes.resize(n);
        m_parents.resize(n);
        m_grounds.resize(n);
        for (std::size_t k = 0; k < n; ++k) {
            const BlobbyItem& item = m_program.items[k];
            if (item.op == BlobbyOp::Plugin)
                fail(prim,
                     std::string("code[") + std::to_string(item.code_begin) + "]: the " +
                         blobby_op_name(item.op) +
                         " is not supported (the RIB reader makes it 0 with -lenient)");
            if (item.op == BlobbyOp::GroundPlane) add_ground(prim, control, k);
            if (item.op == BlobbyOp::Ellipsoid || item.op == BlobbyOp::Segment) {
                m_boxes[k] = support_box(item);
                m_bounds.add(m_boxes[k]);
                m_bounded.push_back(k);
                m_radii.push_back(support_radius(item));
            }
            if (item.op == BlobbyOp::Constant) m_constant_leaves.push_back(k);
            for (std::size_t at = 0; at < item.operands.size(); ++at) {
                std::vector<Link>& parents =
                    m_parents[static_cast<std::size_t>(item.operands[at])];
                if (!parents.empty() && parents.back().parent == k)
                    ++parents.back().count;
                else
                    parents.push_back(
                        {static_cast<uint32_t>(k), 1, static_cast<uint32_t>(at)});
            }
        }
        if (m_bounded.empty())
            fail(prim, "no ellipsoid or segment field: the surface is not bounded");
        m_bins = LeafBins(m_bounds, m_bounded, m_boxes);
        m_stamp.assign(n, 0);
        m_background.resize(n);
        m_sum = !m_dense && sum_of_leaves();
        m_step = 1e-4 * glm::length(m_bounds.hi - m_bounds.lo);
        // Beyond every support only the constants remain.
        for (std::size_t k = 0; k < n; ++k) {
            const BlobbyItem& item = m_program.items[k];
            m_background[k] =
                item.leaf >= 0
                    ? Dual{item.op == BlobbyOp::Constant ? item.value : 0.0, dvec3(0.0)}
                    : combine<false>(k, m_background);
        }
        m_values = m_background; // between evaluations
        prepare_sparse();
    }

    const BlobbyProgram& program() const { return m_program; }
    /// The box outside which every ellipsoid and segment field is 0.
    const Box& bounds() const { return m_bounds; }
    /// The radius (object space, a lower bound) of each ellipsoid or
    /// segment support, in the order of bounded().
    const std::vector<double>& radii() const { return m_radii; }
    /// Items of the ellipsoids and segments.
    const std::vector<std::size_t>& bounded() const { return m_bounded; }

    double value(const dvec3& p) const { return evaluate<false>(p).v; }
    Dual value_gradient(const dvec3& p) const { return evaluate<true>(p); }

    /// Every leaf's field at p, by leaf number.
    void leaf_fields(const dvec3& p, std::vector<double>& out) const {
        out.assign(static_cast<std::size_t>(m_program.leaves), 0.0);
        for (std::size_t k : m_constant_leaves) {
            const BlobbyItem& item = m_program.items[k];
            out[static_cast<std::size_t>(item.leaf)] = item.value;
        }
        for (std::size_t k = 0; k < m_grounds.size(); ++k)
            if (m_grounds[k].map)
                out[static_cast<std::size_t>(m_program.items[k].leaf)] =
                    ground<false>(k, p).v;
        if (!m_bounds.contains(p)) return;
        const auto [begin, end] = m_bins.at(p);
        for (const uint32_t* k = begin; k != end; ++k) {
            const BlobbyItem& item = m_program.items[*k];
            out[static_cast<std::size_t>(item.leaf)] = leaf<false>(item, *k, p).v;
        }
    }

private:
    /// A repelling ground plane's depth map, the primitive's object space to
    /// its camera and screen, and its shape (A, B, C, D).
    struct Ground {
        std::shared_ptr<const DepthGrid> map;
        Matrix4 to_camera{1.0}, to_screen{1.0};
        std::array<double, 4> repel{};
    };

    void add_ground(const Primitive& prim, const DiceControl& control, std::size_t k) {
        const BlobbyItem& item = m_program.items[k];
        if (!control.depth_maps)
            fail(prim, "code[" + std::to_string(item.code_begin) +
                           "]: the repelling ground plane needs its depth map " +
                           sss::quoted(item.depth_map) +
                           ", which only ptbake and render read");
        Ground& g = m_grounds[k];
        try {
            g.map = control.depth_maps(item.depth_map);
        } catch (const Error& e) {
            fail(prim, "code[" + std::to_string(item.code_begin) +
                           "]: the repelling ground plane: " + e.what());
        }
        if (!g.map || g.map->width < 1 || g.map->height < 1 ||
            g.map->depth.size() != std::size_t(g.map->width) * std::size_t(g.map->height))
            fail(prim, "the depth map " + sss::quoted(item.depth_map) + " is empty");
        g.to_camera = g.map->world_to_camera * prim.object_to_world;
        g.to_screen = g.map->world_to_screen * prim.object_to_world;
        g.repel = item.repel;
        m_dense = true;
    }

    /// How far p lies above the depth map's surface, along the map
    /// camera's view: false where p is off the map, behind its camera or
    /// over texels without a surface.
    static bool height_above(const Ground& g, const dvec3& p, double& z) {
        const glm::dvec4 s = g.to_screen * glm::dvec4(p, 1.0);
        if (!(s.w > 0.0)) return false;
        const double x = s.x / s.w, y = s.y / s.w;
        if (!(x >= -1.0 && x <= 1.0 && y >= -1.0 && y <= 1.0)) return false;
        const DepthGrid& m = *g.map;
        const double fx = 0.5 * (x + 1.0) * m.width - 0.5;
        const double fy = 0.5 * (1.0 - y) * m.height - 0.5;
        const int x0 = std::clamp(static_cast<int>(std::floor(fx)), 0, m.width - 1);
        const int y0 = std::clamp(static_cast<int>(std::floor(fy)), 0, m.height - 1);
        const int x1 = std::min(x0 + 1, m.width - 1), y1 = std::min(y0 + 1, m.height - 1);
        const double tx = std::clamp(fx - x0, 0.0, 1.0),
                     ty = std::clamp(fy - y0, 0.0, 1.0);
        const auto at = [&](int xx, int yy) {
            return double(
                m.depth[std::size_t(yy) * std::size_t(m.width) + std::size_t(xx)]);
        };
        const double d00 = at(x0, y0), d10 = at(x1, y0), d01 = at(x0, y1),
                     d11 = at(x1, y1);
        const double none = 0.5 * DepthGrid::kNoDepth;
        if (!(d00 < none && d10 < none && d01 < none && d11 < none)) return false;
        const double surface =
            (d00 * (1 - tx) + d10 * tx) * (1 - ty) + (d01 * (1 - tx) + d11 * tx) * ty;
        z = surface - (g.to_camera * glm::dvec4(p, 1.0)).z;
        return std::isfinite(z);
    }

    /// Application Note #31's repulsion at height z: a barrier -B/z under a
    /// bulge of height D peaking at z = C, eased to 0 at z = A.
    static double repulsion(double z, const std::array<double, 4>& r) {
        const double a = r[0], b = r[1], c = r[2], d = r[3];
        if (!(a > 0.0) || z >= a) return 0.0;
        z = std::max(z, 1e-6);
        const auto bump = [](double t) {
            return t <= 0.0 || t >= 2.0 ? 0.0
                                        : (((6.0 - t) * t - 12.0) * t + 8.0) * t * t * t;
        };
        const auto ease = [](double t) {
            return t <= 0.0 ? 0.0 : t >= 1.0 ? 1.0 : t * t * (3.0 - 2.0 * t);
        };
        const double bulge = c > 0.0 ? d * bump(z / c) : 0.0;
        return (bulge - b / z) * (1.0 - ease(z / a));
    }

    /// A ground plane's field at p (its gradient by central differences:
    /// the depth map is sampled, it has no closed form).
    template <bool Gradient>
    Dual ground(std::size_t k, const dvec3& p) const {
        const Ground& g = m_grounds[k];
        const auto field = [&](const dvec3& q) {
            double z = 0.0;
            return height_above(g, q, z) ? repulsion(z, g.repel) : 0.0;
        };
        Dual out;
        out.v = field(p);
        if (Gradient)
            for (int a = 0; a < 3; ++a) {
                dvec3 lo = p, hi = p;
                lo[a] -= m_step;
                hi[a] += m_step;
                out.g[a] = (field(hi) - field(lo)) / (2.0 * m_step);
            }
        return out;
    }

    /// Every item at p, in program order: the fields of ground planes reach
    /// everywhere, so no item keeps a background value.
    template <bool Gradient>
    Dual evaluate_dense(const dvec3& p) const {
        const std::size_t n = m_program.items.size();
        for (std::size_t k = 0; k < n; ++k) {
            const BlobbyItem& item = m_program.items[k];
            m_values[k] = m_grounds[k].map ? ground<Gradient>(k, p)
                          : item.leaf >= 0 ? leaf<Gradient>(item, k, p)
                                           : combine<Gradient>(k, m_values);
        }
        return m_values[n - 1];
    }

    /// The object-space box of the unit ball (ellipsoid) or of the capsule
    /// (segment) of blob space.
    static Box support_box(const BlobbyItem& item) {
        Box blob;
        if (item.op == BlobbyOp::Ellipsoid) {
            blob.lo = dvec3(-1.0);
            blob.hi = dvec3(1.0);
        } else {
            blob.lo = glm::min(item.start, item.end) - dvec3(item.radius);
            blob.hi = glm::max(item.start, item.end) + dvec3(item.radius);
        }
        Box out;
        for (int c = 0; c < 8; ++c)
            out.add(affine(item.to_object, dvec3(c & 1 ? blob.hi.x : blob.lo.x,
                                                 c & 2 ? blob.hi.y : blob.lo.y,
                                                 c & 4 ? blob.hi.z : blob.lo.z)));
        return out;
    }

    /// A lower bound of the support's smallest object-space radius: the
    /// blob-space radius over the largest stretch of the inverse matrix
    /// (bounded by its Frobenius norm).
    static double support_radius(const BlobbyItem& item) {
        const glm::dmat3 inv(item.to_blob);
        double f2 = 0.0;
        for (int c = 0; c < 3; ++c) f2 += glm::dot(inv[c], inv[c]);
        const double r = item.op == BlobbyOp::Segment ? item.radius : 1.0;
        return r / std::sqrt(f2);
    }

    /// Whether the field is the plain sum of the leaves (adds and
    /// identities over leaves, each used once): then a point sums the
    /// leaves of its bin, whatever the size of the program.
    bool sum_of_leaves() {
        std::vector<int> uses(m_program.items.size(), 0);
        std::vector<std::size_t> stack{m_program.items.size() - 1};
        while (!stack.empty()) {
            const std::size_t k = stack.back();
            stack.pop_back();
            const BlobbyItem& item = m_program.items[k];
            if (++uses[k] > 1) return false;
            if (item.op == BlobbyOp::Constant) {
                m_constants += item.value;
            } else if (item.op == BlobbyOp::Add || item.op == BlobbyOp::Identity) {
                for (int o : item.operands) stack.push_back(static_cast<std::size_t>(o));
            } else if (item.leaf < 0) {
                return false;
            }
        }
        for (std::size_t k : m_bounded)
            if (uses[k] == 0) return false;
        return true;
    }

    template <bool Gradient>
    Dual leaf(const BlobbyItem& item, std::size_t k, const dvec3& p) const {
        Dual out;
        if (item.op == BlobbyOp::Constant) {
            out.v = item.value;
            return out;
        }
        if (!m_boxes[k].contains(p)) return out;
        const dvec3 q = affine(item.to_blob, p);
        dvec3 d = q;
        double scale = 1.0;
        if (item.op == BlobbyOp::Segment) {
            const dvec3 ab = item.end - item.start;
            const double len2 = glm::dot(ab, ab);
            const double t =
                len2 > 0.0 ? std::clamp(glm::dot(q - item.start, ab) / len2, 0.0, 1.0)
                           : 0.0;
            d = q - (item.start + t * ab);
            scale = 1.0 / (item.radius * item.radius);
        }
        const double r2 = glm::dot(d, d) * scale;
        if (!(r2 < 1.0)) return out;
        out.v = falloff(r2);
        if (Gradient) {
            // d(r^2)/dq = 2 d scale (the segment's nearest point moves along
            // the segment only), then to object space through to_blob.
            const dvec3 dq = falloff_slope(r2) * 2.0 * scale * d;
            out.g = glm::transpose(glm::dmat3(item.to_blob)) * dq;
        }
        return out;
    }

    /// Operator k over its operands' values in `v`.
    template <bool Gradient>
    Dual combine(std::size_t k, const std::vector<Dual>& v) const {
        const BlobbyItem& item = m_program.items[k];
        const auto at = [&](std::size_t o) -> const Dual& {
            return v[static_cast<std::size_t>(item.operands[o])];
        };
        Dual r = at(0);
        switch (item.op) {
        case BlobbyOp::Add:
            for (std::size_t o = 1; o < item.operands.size(); ++o) {
                r.v += at(o).v;
                if (Gradient) r.g += at(o).g;
            }
            break;
        case BlobbyOp::Multiply:
            for (std::size_t o = 1; o < item.operands.size(); ++o) {
                const Dual& b = at(o);
                if (Gradient) r.g = r.g * b.v + b.g * r.v;
                r.v *= b.v;
            }
            break;
        case BlobbyOp::Max:
        case BlobbyOp::Min:
            for (std::size_t o = 1; o < item.operands.size(); ++o) {
                const Dual& b = at(o);
                if (item.op == BlobbyOp::Max ? b.v > r.v : b.v < r.v) r = b;
            }
            break;
        case BlobbyOp::Subtract:
            r.v -= at(1).v;
            if (Gradient) r.g -= at(1).g;
            break;
        case BlobbyOp::Divide: {
            // x / 0 is 0: no infinity or NaN leaves a Blobby.
            const Dual& b = at(1);
            if (b.v == 0.0) {
                r = Dual{};
            } else {
                if (Gradient) r.g = (r.g * b.v - b.g * r.v) / (b.v * b.v);
                r.v /= b.v;
            }
            break;
        }
        case BlobbyOp::Negate:
            r.v = -r.v;
            r.g = -r.g;
            break;
        default: // Identity
            break;
        }
        return r;
    }

    /// Add, max and min of many operands combine only their active ones
    /// with what the others give in the background: max and min keep their
    /// operands' positions ordered by background value, best first.
    void prepare_sparse() {
        const std::size_t n = m_program.items.size();
        m_sparse.assign(n, 0);
        m_order.resize(n);
        m_children.resize(n);
        for (std::size_t k = 0; k < n; ++k) {
            const BlobbyItem& item = m_program.items[k];
            const bool nary = item.op == BlobbyOp::Add || item.op == BlobbyOp::Max ||
                              item.op == BlobbyOp::Min;
            if (!nary || item.operands.size() <= kSparseOperands) continue;
            m_sparse[k] = 1;
            if (item.op == BlobbyOp::Add) continue;
            std::vector<uint32_t>& order = m_order[k];
            order.resize(item.operands.size());
            for (std::size_t at = 0; at < order.size(); ++at)
                order[at] = static_cast<uint32_t>(at);
            const bool max = item.op == BlobbyOp::Max;
            std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
                const double va = background_of(item, a), vb = background_of(item, b);
                return max ? va > vb : va < vb;
            });
        }
    }

    double background_of(const BlobbyItem& item, uint32_t at) const {
        return m_background[static_cast<std::size_t>(item.operands[at])].v;
    }

    /// A sparse operator: its background with its active operands'
    /// values in (m_children[k], which were computed before it).
    template <bool Gradient>
    Dual combine_sparse(std::size_t k) const {
        const BlobbyItem& item = m_program.items[k];
        const std::vector<uint32_t>& active = m_children[k];
        if (item.op == BlobbyOp::Add) {
            Dual r = m_background[k];
            for (uint32_t c : active) {
                const double count = link(c, k).count;
                r.v += count * (m_values[c].v - m_background[c].v);
                if (Gradient) r.g += count * m_values[c].g;
            }
            return r;
        }
        // The first of the best by value, ties to the earlier operand, as
        // the dense loop takes them.
        const bool max = item.op == BlobbyOp::Max;
        Dual r;
        uint32_t best = std::numeric_limits<uint32_t>::max();
        for (uint32_t at : m_order[k]) {
            const auto o = static_cast<std::size_t>(item.operands[at]);
            if (m_stamp[o] == m_epoch) continue;
            r = m_background[o];
            best = at;
            break;
        }
        for (uint32_t c : active) {
            const uint32_t at = link(c, k).first;
            const Dual& v = m_values[c];
            const bool better = best == std::numeric_limits<uint32_t>::max() ||
                                (max ? v.v > r.v : v.v < r.v) ||
                                (v.v == r.v && at < best);
            if (better) {
                r = v;
                best = at;
            }
        }
        return r;
    }

    const Link& link(uint32_t child, std::size_t parent) const {
        for (const Link& l : m_parents[child])
            if (l.parent == parent) return l;
        return m_parents[child].front(); // unreachable: children are linked
    }

    template <bool Gradient>
    Dual evaluate(const dvec3& p) const {
        if (m_dense) return evaluate_dense<Gradient>(p);
        const std::size_t last = m_program.items.size() - 1;
        if (!m_bounds.contains(p)) return m_background[last];
        const auto [begin, end] = m_bins.at(p);
        if (m_sum) {
            Dual r{m_constants, dvec3(0.0)};
            for (const uint32_t* k = begin; k != end; ++k) {
                const Dual d = leaf<Gradient>(m_program.items[*k], *k, p);
                r.v += d.v;
                if (Gradient) r.g += d.g;
            }
            return r;
        }
        // The leaves whose support holds p, and every item above them, in
        // program order; the rest keep their background values.
        if (++m_epoch == 0) {
            std::fill(m_stamp.begin(), m_stamp.end(), 0u);
            m_epoch = 1;
        }
        m_active.clear();
        for (const uint32_t* k = begin; k != end; ++k)
            if (m_boxes[*k].contains(p)) {
                m_stamp[*k] = m_epoch;
                m_active.push_back(*k);
            }
        if (m_active.empty()) return m_background[last];
        for (std::size_t a = 0; a < m_active.size(); ++a)
            for (const Link& l : m_parents[m_active[a]])
                if (m_stamp[l.parent] != m_epoch) {
                    m_stamp[l.parent] = m_epoch;
                    m_active.push_back(l.parent);
                }
        std::sort(m_active.begin(), m_active.end());
        for (uint32_t k : m_active) {
            const BlobbyItem& item = m_program.items[k];
            m_values[k] = item.leaf >= 0 ? leaf<Gradient>(item, k, p)
                          : m_sparse[k]  ? combine_sparse<Gradient>(k)
                                         : combine<Gradient>(k, m_values);
            for (const Link& l : m_parents[k])
                if (m_sparse[l.parent]) m_children[l.parent].push_back(k);
        }
        const Dual r = m_values[last];
        for (uint32_t k : m_active) {
            m_values[k] = m_background[k];
            m_children[k].clear();
        }
        return r;
    }

    /// Operators of more operands than this combine only the active ones.
    static constexpr std::size_t kSparseOperands = 8;

    BlobbyProgram m_program;
    std::vector<Box> m_boxes;
    std::vector<std::vector<Link>> m_parents;
    std::vector<uint8_t> m_sparse;
    std::vector<std::vector<uint32_t>> m_order;
    mutable std::vector<std::vector<uint32_t>> m_children;
    std::vector<std::size_t> m_bounded, m_constant_leaves;
    Box m_bounds;
    LeafBins m_bins;
    std::vector<double> m_radii;
    bool m_sum = false;
    /// A ground plane makes every evaluation run the whole program.
    bool m_dense = false;
    std::vector<Ground> m_grounds; ///< by item (map null: not a ground plane)
    double m_step = 1e-6;          ///< of the ground planes' differences
    double m_constants = 0.0;
    std::vector<Dual> m_background;
    mutable std::vector<Dual> m_values;
    mutable std::vector<uint32_t> m_stamp;
    mutable uint32_t m_epoch = 0;
    mutable std::vector<uint32_t> m_active;
};

/// The grid: origin, cell size and cells per side.
struct Grid {
    dvec3 origin{0.0};
    double h = 1.0;
    std::array<std::size_t, 3> n{1, 1, 1};

    dvec3 point(std::size_t i, std::size_t j, std::size_t k) const {
        return origin + h * dvec3(static_cast<double>(i), static_cast<double>(j),
                                  static_cast<double>(k));
    }
};

/// How much the object-to-world transform stretches the object's axes at
/// most (the scale of a similarity): world lengths over it are object
/// lengths.
double largest_stretch(const Matrix4& m) {
    const glm::dmat3 a(m);
    return std::max({glm::length(a[0]), glm::length(a[1]), glm::length(a[2])});
}

/// The finest micropolygon edge (world units) over the box's corners and
/// centre.
double finest_edge(const Primitive& prim, const DiceControl& control, const Box& box) {
    const double rate = attributes_of(prim).shading_rate;
    double e = std::numeric_limits<double>::infinity();
    for (int c = 0; c < 9; ++c) {
        const dvec3 p =
            c == 8 ? 0.5 * (box.lo + box.hi)
                   : dvec3(c & 1 ? box.hi.x : box.lo.x, c & 2 ? box.hi.y : box.lo.y,
                           c & 4 ? box.hi.z : box.lo.z);
        const dvec3 world = to_world(prim.object_to_world, p);
        check_world_point(prim, world);
        e = std::min(e, edge_length(prim, control, world, rate));
    }
    return e;
}

/// The grid over the field's bounds, with a margin of one cell: cells of
/// kEdgesPerCell micropolygons (object space), finer for small blobs,
/// coarser when the caps require it.
Grid plan_grid(const Primitive& prim, const DiceControl& control,
               const BlobbyField& field) {
    const Box& b = field.bounds();
    const double edge = finest_edge(prim, control, b) /
                        std::max(largest_stretch(prim.object_to_world), 1e-300);
    const std::vector<double>& radii = field.radii();
    const double r = *std::min_element(radii.begin(), radii.end());
    // Every blob gets cells of a quarter of its radius at least, even one
    // smaller than a micropolygon: a blob of a pixel or two must not fall
    // between the grid's points.
    double h = std::min(kEdgesPerCell * edge, r / kCellsPerRadius);
    // The caps may coarsen that until blobs under about a micropolygon
    // could vanish, but no larger one.
    double resolved = std::numeric_limits<double>::infinity();
    for (double x : radii)
        if (x >= kFewestCellsPerRadius * edge) resolved = std::min(resolved, x);
    const dvec3 extent = b.hi - b.lo;
    const auto cells = [&](double size) {
        std::array<double, 3> n{};
        for (int a = 0; a < 3; ++a) n[a] = std::ceil(extent[a] / size) + 2.0;
        return n;
    };
    // A surface crossing a grid of n^3 cells makes some n^2 quads (each at
    // least a micropolygon): a grid far beyond the micropolygon budget
    // would only be swept to fail.
    const double budget =
        std::min(kMaxCells,
                 kCellsPerMicropolygon * static_cast<double>(control.max_micropolygons));
    for (int round = 0;; ++round) {
        const std::array<double, 3> n = cells(h);
        const double most = std::max({n[0], n[1], n[2]});
        if (most <= static_cast<double>(kMaxCellsPerSide) &&
            n[0] * n[1] * n[2] <= budget && std::isfinite(most))
            break;
        h *= 1.25;
        if (!(h <= resolved / kFewestCellsPerRadius) || round > 200) {
            if (budget < kMaxCells && most <= static_cast<double>(kMaxCellsPerSide))
                too_many_micropolygons(prim, control,
                                       n[0] * n[1] * n[2] / kCellsPerMicropolygon);
            char buf[256];
            std::snprintf(buf, sizeof buf,
                          "its blobs span %.4g x %.4g x %.4g (object space) but one "
                          "has a radius of %.4g: more than %zu grid cells along a side "
                          "(or %.0f in all) would be needed to polygonize it at the "
                          "dicing rate (dice coarser, or split the Blobby)",
                          extent.x, extent.y, extent.z, resolved, kMaxCellsPerSide,
                          kMaxCells);
            fail(prim, buf);
        }
    }
    Grid g;
    // The grid's cell and counts (motion blur dices every time step with
    // those of the first).
    g.h = control.note(h, prim);
    const std::array<double, 3> n = cells(h);
    for (int a = 0; a < 3; ++a) {
        g.n[a] = static_cast<std::size_t>(control.note(n[a], prim));
        g.origin[a] = 0.5 * (b.lo[a] + b.hi[a]) - 0.5 * g.h * static_cast<double>(g.n[a]);
    }
    return g;
}

/// The surface-nets mesh of a field, in object space.
class Mesher {
public:
    Mesher(const Primitive& prim, const DiceControl& control, const BlobbyField& field,
           const Grid& grid)
        : m_prim(prim), m_control(control), m_field(field), m_g(grid) {}

    void run(std::vector<dvec3>& points, std::vector<int>& quads) {
        const std::size_t nx = m_g.n[0], ny = m_g.n[1], nz = m_g.n[2];
        const std::size_t layer_points = (nx + 1) * (ny + 1);
        std::array<std::vector<double>, 2> f{std::vector<double>(layer_points),
                                             std::vector<double>(layer_points)};
        std::array<std::vector<int>, 2> cell{std::vector<int>(nx * ny, -1),
                                             std::vector<int>(nx * ny, -1)};
        sample_layer(0, f[0]);
        for (std::size_t k = 0; k < nz; ++k) {
            const std::vector<double>& below = f[k % 2];
            std::vector<double>& above = f[(k + 1) % 2];
            sample_layer(k + 1, above);
            std::vector<int>& here = cell[k % 2];
            for (std::size_t j = 0; j < ny; ++j)
                for (std::size_t i = 0; i < nx; ++i)
                    here[j * nx + i] = make_vertex(i, j, k, below, above, points);
            emit_quads(k, below, above, cell[(k + 1) % 2], here, quads);
        }
    }

private:
    std::size_t at(std::size_t i, std::size_t j) const { return j * (m_g.n[0] + 1) + i; }

    /// The field at every point of layer k; the grid's outermost points
    /// count as outside.
    void sample_layer(std::size_t k, std::vector<double>& out) {
        const std::size_t nx = m_g.n[0], ny = m_g.n[1], nz = m_g.n[2];
        const double outside = kBlobbyThreshold - 1.0;
        for (std::size_t j = 0; j <= ny; ++j)
            for (std::size_t i = 0; i <= nx; ++i) {
                const bool border =
                    i == 0 || j == 0 || k == 0 || i == nx || j == ny || k == nz;
                double v = outside;
                if (!border) {
                    const dvec3 p = m_g.point(i, j, k);
                    v = m_field.value(p);
                    if (!std::isfinite(v)) not_finite(p);
                }
                out[at(i, j)] = v;
            }
    }

    [[noreturn]] void not_finite(const dvec3& p) const {
        char buf[160];
        std::snprintf(buf, sizeof buf,
                      "the field is not a finite number at (%.6g, %.6g, %.6g) (object "
                      "space): check its multiply and divide operators",
                      p.x, p.y, p.z);
        fail(m_prim, buf);
    }

    static bool inside(double v) { return v >= kBlobbyThreshold; }

    /// The vertex of cell (i, j, k) if the surface crosses it (else -1):
    /// the mean of its edges' crossings, moved onto the surface.
    int make_vertex(std::size_t i, std::size_t j, std::size_t k,
                    const std::vector<double>& below, const std::vector<double>& above,
                    std::vector<dvec3>& points) const {
        std::array<double, 8> v{};
        int in = 0;
        for (int c = 0; c < 8; ++c) {
            const std::vector<double>& layer = c & 4 ? above : below;
            v[c] = layer[at(i + (c & 1), j + ((c >> 1) & 1))];
            in += inside(v[c]) ? 1 : 0;
        }
        if (in == 0 || in == 8) return -1;
        dvec3 sum(0.0);
        int crossings = 0;
        for (int a = 0; a < 8; ++a)
            for (int axis = 0; axis < 3; ++axis) {
                const int b = a | (1 << axis);
                if (b == a || inside(v[a]) == inside(v[b])) continue;
                const double t = (kBlobbyThreshold - v[a]) / (v[b] - v[a]);
                dvec3 p(a & 1, (a >> 1) & 1, (a >> 2) & 1);
                p[axis] += t;
                sum += p;
                ++crossings;
            }
        const dvec3 corner = m_g.point(i, j, k);
        dvec3 p = corner + m_g.h * sum / static_cast<double>(crossings);
        project(p, corner - dvec3(0.5 * m_g.h), corner + dvec3(1.5 * m_g.h));
        if (points.size() >= static_cast<std::size_t>(std::numeric_limits<int>::max()))
            fail(m_prim, "too many vertices");
        points.push_back(p);
        return static_cast<int>(points.size() - 1);
    }

    /// Newton steps along the gradient towards the surface, halved while
    /// they would leave [lo, hi] (the cell and half a cell around) or not
    /// come closer.
    void project(dvec3& p, const dvec3& lo, const dvec3& hi) const {
        Dual d = m_field.value_gradient(p);
        for (int iteration = 0; iteration < 10; ++iteration) {
            const double miss = d.v - kBlobbyThreshold;
            const double g2 = glm::dot(d.g, d.g);
            if (std::abs(miss) < 1e-13 || !(g2 > 1e-300)) return;
            dvec3 step = (miss / g2) * d.g;
            bool moved = false;
            for (int halving = 0; halving < 8 && !moved; ++halving, step *= 0.5) {
                const dvec3 q = p - step;
                if (!(glm::all(glm::greaterThanEqual(q, lo)) &&
                      glm::all(glm::lessThanEqual(q, hi))))
                    continue;
                const Dual e = m_field.value_gradient(q);
                if (std::abs(e.v - kBlobbyThreshold) < std::abs(miss)) {
                    p = q;
                    d = e;
                    moved = true;
                }
            }
            if (!moved) return;
        }
    }

    /// One quad around a crossed edge along `axis` from a point, its
    /// corners the vertices of the four cells around the edge (cells
    /// (du, dv) = (-1, -1), (0, -1), (0, 0), (-1, 0) across it: anticlockwise
    /// about the axis), turned to face the outside.
    void quad(const std::array<int, 4>& v, bool outward_along_axis,
              std::vector<int>& quads) {
        if (v[0] < 0 || v[1] < 0 || v[2] < 0 || v[3] < 0)
            fail(m_prim, "internal error: a crossed edge without its four cells");
        if (outward_along_axis)
            quads.insert(quads.end(), {v[0], v[1], v[2], v[3]});
        else
            quads.insert(quads.end(), {v[0], v[3], v[2], v[1]});
        if (quads.size() / 4 > m_control.max_micropolygons)
            too_many_micropolygons(m_prim, m_control,
                                   static_cast<double>(quads.size() / 4));
    }

    /// The quads of the edges whose cells are all made once cell layer k
    /// is: edges along z from point layer k to k + 1 (cells of layer k),
    /// and edges along x and y in point layer k (cells of layers k - 1, k).
    void emit_quads(std::size_t k, const std::vector<double>& below,
                    const std::vector<double>& above, const std::vector<int>& previous,
                    const std::vector<int>& here, std::vector<int>& quads) {
        const std::size_t nx = m_g.n[0], ny = m_g.n[1];
        const auto c = [&](const std::vector<int>& layer, std::size_t i, std::size_t j) {
            return layer[j * nx + i];
        };
        for (std::size_t j = 1; j < ny; ++j)
            for (std::size_t i = 1; i < nx; ++i) {
                const bool a = inside(below[at(i, j)]);
                if (a == inside(above[at(i, j)])) continue;
                // z: (u, v) = (x, y).
                quad({c(here, i - 1, j - 1), c(here, i, j - 1), c(here, i, j),
                      c(here, i - 1, j)},
                     a, quads);
            }
        if (k == 0) return;
        for (std::size_t j = 1; j < ny; ++j)
            for (std::size_t i = 0; i < nx; ++i) {
                const bool a = inside(below[at(i, j)]);
                if (a == inside(below[at(i + 1, j)])) continue;
                // x: (u, v) = (y, z).
                quad({c(previous, i, j - 1), c(previous, i, j), c(here, i, j),
                      c(here, i, j - 1)},
                     a, quads);
            }
        for (std::size_t j = 0; j < ny; ++j)
            for (std::size_t i = 1; i < nx; ++i) {
                const bool a = inside(below[at(i, j)]);
                if (a == inside(below[at(i, j + 1)])) continue;
                // y: (u, v) = (z, x).
                quad({c(previous, i - 1, j), c(here, i - 1, j), c(here, i, j),
                      c(previous, i, j)},
                     a, quads);
            }
    }

    const Primitive& m_prim;
    const DiceControl& m_control;
    const BlobbyField& m_field;
    const Grid m_g;
};

/// A parameter of the mesh: constant (copied) or per vertex (blended).
Param mesh_param(const Param& q) {
    Param out = q;
    out.numbers.clear();
    out.strings.clear();
    const bool single =
        q.storage == ParamClass::Constant || q.storage == ParamClass::Uniform;
    out.storage = single ? ParamClass::Constant : ParamClass::Vertex;
    if (single) {
        const auto n = static_cast<std::size_t>(q.element_size());
        if (q.type == ParamType::String)
            out.strings.assign(q.strings.begin(), q.strings.begin() + 1);
        else
            out.numbers.assign(q.numbers.begin(),
                               q.numbers.begin() + static_cast<std::ptrdiff_t>(n));
    }
    return out;
}

/// The per-vertex values of the mesh's points: each per-leaf value blended
/// by the leaves' |field| there (equal weights where every field is 0);
/// strings take the value of the leaf of largest weight.
void blend_params(const Primitive& prim, const BlobbyField& field,
                  const std::vector<dvec3>& points, ParamList& out) {
    const auto leaves = static_cast<std::size_t>(field.program().leaves);
    std::vector<const Param*> blended;
    for (const Param& q : prim.params.items) {
        if (q.name == "P" || q.name == "N") continue;
        const bool single =
            q.storage == ParamClass::Constant || q.storage == ParamClass::Uniform;
        const std::size_t want = single ? 1 : leaves;
        if (q.element_count() != want)
            fail(prim, "\"" + q.name + "\" has " + std::to_string(q.element_count()) +
                           " values, expected " + std::to_string(want));
        if (single)
            out.set(mesh_param(q));
        else
            blended.push_back(&q);
    }
    if (blended.empty()) return;
    std::vector<Param> values;
    for (const Param* q : blended) values.push_back(mesh_param(*q));
    std::vector<double> w;
    for (const dvec3& p : points) {
        field.leaf_fields(p, w);
        double total = 0.0;
        std::size_t strongest = 0;
        for (std::size_t l = 0; l < leaves; ++l) {
            w[l] = std::abs(w[l]);
            total += w[l];
            if (w[l] > w[strongest]) strongest = l;
        }
        for (double& x : w)
            x = total > 0.0 ? x / total : 1.0 / static_cast<double>(leaves);
        for (std::size_t b = 0; b < blended.size(); ++b) {
            const Param* q = blended[b];
            Param& o = values[b];
            if (q->type == ParamType::String) {
                o.strings.push_back(q->strings[strongest]);
                continue;
            }
            const auto n = static_cast<std::size_t>(q->element_size());
            for (std::size_t c = 0; c < n; ++c) {
                double v = 0.0;
                for (std::size_t l = 0; l < leaves; ++l)
                    if (w[l] != 0.0) v += w[l] * q->numbers[l * n + c];
                o.numbers.push_back(v);
            }
        }
    }
    for (Param& q : values) out.set(std::move(q));
}

Param vertex_param(const char* name, ParamType type) {
    Param q;
    q.name = name;
    q.type = type;
    q.storage = ParamClass::Vertex;
    return q;
}

/// Estimate: each ellipsoid and segment as a surface at 0.6 of its support
/// radius (between the lone blob's 0.454 and the support), rather over than
/// under for blobs that merge, and at least a micropolygon per grid cell
/// of that area.
void estimate_blobby(const Primitive& prim, const DiceControl& control,
                     const BlobbyField& field, DiceEstimate& estimate) {
    const double e = finest_edge(prim, control, field.bounds());
    const glm::dmat3 world(prim.object_to_world);
    double area = 0.0;
    for (std::size_t k : field.bounded()) {
        const BlobbyItem& item = field.program().items[k];
        const glm::dmat3 m = world * glm::dmat3(item.to_object);
        const double a = glm::length(m[0]), b = glm::length(m[1]), c = glm::length(m[2]);
        const double r = 0.6 * (item.op == BlobbyOp::Segment ? item.radius : 1.0);
        const double mean2 = (a * b + b * c + c * a) / 3.0;
        area += 4.0 * kPi * r * r * mean2;
        if (item.op == BlobbyOp::Segment)
            area += 2.0 * kPi * r * std::sqrt(mean2) *
                    glm::length(m * (item.end - item.start));
    }
    // Every quad of the mesh is at least one micropolygon: a grid finer
    // than the dicing rate (for small blobs) makes more of them.
    const double stretch = largest_stretch(prim.object_to_world);
    const std::vector<double>& radii = field.radii();
    const double r = *std::min_element(radii.begin(), radii.end());
    const double cell = std::min(kEdgesPerCell * e, stretch * r / kCellsPerRadius);
    estimate += estimate_flat_face(area, 0.0, e, area / (cell * cell) + 1.0);
}

} // namespace

Primitive blobby_mesh(const Primitive& prim, const DiceControl& control) {
    const BlobbyField field(prim, control);
    const Grid grid = plan_grid(prim, control, field);
    std::vector<dvec3> points;
    std::vector<int> quads;
    Mesher(prim, control, field, grid).run(points, quads);

    Primitive m;
    m.kind = PrimitiveKind::PointsPolygons;
    m.object_to_world = prim.object_to_world;
    m.attributes = prim.attributes;
    m.source = prim.source;
    if (quads.empty()) return m;
    m.nverts.assign(quads.size() / 4, 4);
    m.verts = std::move(quads);
    blend_params(prim, field, points, m.params);
    // Normals: the field falls outward; Orientation "inside" turns them in,
    // as it turns the quads' geometric normals.
    const double sign = attributes_of(prim).orientation_inside ? 1.0 : -1.0;
    Param P = vertex_param("P", ParamType::Point);
    Param N = vertex_param("N", ParamType::Normal);
    for (const dvec3& p : points) {
        const dvec3 g = field.value_gradient(p).g;
        const double len = glm::length(g);
        const dvec3 n = len > 0.0 && std::isfinite(len) ? sign * g / len : dvec3(0.0);
        P.numbers.insert(P.numbers.end(), {p.x, p.y, p.z});
        N.numbers.insert(N.numbers.end(), {n.x, n.y, n.z});
    }
    m.params.set(std::move(P));
    m.params.set(std::move(N));
    // Default texture coordinates: x and y across the blobs' box.
    if (!prim.params.has("s") && !prim.params.has("t") && !prim.params.has("st")) {
        const Box& b = field.bounds();
        Param s = vertex_param("s", ParamType::Float),
              t = vertex_param("t", ParamType::Float);
        for (const dvec3& p : points) {
            s.numbers.push_back((p.x - b.lo.x) / (b.hi.x - b.lo.x));
            t.numbers.push_back((p.y - b.lo.y) / (b.hi.y - b.lo.y));
        }
        m.params.set(std::move(s));
        m.params.set(std::move(t));
    }
    return m;
}

DicedSurface dice_blobby(const Primitive& prim, const DiceControl& control,
                         DiceEstimate* estimate) {
    if (estimate) {
        const BlobbyField field(prim, control);
        estimate_blobby(prim, control, field, *estimate);
        return {};
    }
    const Primitive mesh = blobby_mesh(prim, control);
    if (mesh.nverts.empty()) return {};
    return dice_polygons(mesh, control, nullptr);
}

} // namespace sss::detail
