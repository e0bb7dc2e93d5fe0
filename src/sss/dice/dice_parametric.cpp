// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_parametric.cpp
/// The REYES dicer of parametric surfaces, shared by quadrics and patches.
///
/// A surface is split recursively in parameter space (REYES style) until
/// each piece can be diced into a grid of at most 256 micropolygons whose
/// edges are about the wanted length; each grid cell is one micropolygon
/// with its area (Gauss-Legendre quadrature of |dPdu x dPdv| in world
/// space), and the grids, stitched where neighbouring sub-patches have
/// different resolutions, become the triangles for the ray tracer.

#include "dice_parametric.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

#include "sss/util/error.h"

namespace sss::detail {

// ---------------------------------------------------------------------------
// The dicer

namespace {

/// REYES grid size: the most micropolygons one sub-patch is diced into.
constexpr double kMaxGridCells = 256.0;
/// Parameter-space halvings allowed per face (2^-40 is far below any useful size).
constexpr int kMaxSplitDepth = 40;
/// Samples per direction used to measure a sub-patch (more for a whole face,
/// whose isoparametric curves may turn a full circle).
constexpr int kMeasureSamples = 5;
constexpr int kFaceMeasureSamples = 9;
/// Estimates (DiceEstimate) count regions of up to this many cells, split
/// like the dicer's grids: 1/16 of its measuring.
constexpr double kEstimateCells = 4096.0;
/// A parametric cross product this much smaller than the sub-patch's typical
/// |dPdu| |dPdv| is rounding noise (poles, collapsed patch edges), not a normal.
constexpr double kDegenerateRatio = 1e-10;
/// Offset, in cells, of the point whose normal replaces a degenerate one.
constexpr double kNudgeCells = 1e-3;

/// Sampled size of a sub-patch: longest u and v isoparametric polylines in
/// world space, and the range of wanted edge lengths over the samples.
struct Extent {
    double ulen = 0.0;
    double vlen = 0.0;
    double emin = 0.0;
    double emax = 0.0;
};

/// Number of cells for a length: at least 1, as a double (may be huge).
double cell_count(double length, double edge) {
    return std::max(1.0, std::ceil(length / edge));
}

/// Dices the faces of one primitive into one DicedSurface.
class Dicer {
public:
    Dicer(const Primitive& prim, const DiceControl& control, DicedSurface& out,
          DiceEstimate* estimate)
        : m_prim(prim), m_control(control), m_out(out), m_estimate(estimate) {
        const Attributes& attr = attributes_of(prim);
        m_rate = attr.shading_rate;
        const Matrix4& m = prim.object_to_world;
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r)
                if (!std::isfinite(m[c][r]))
                    fail(prim, "transform has NaN or infinite entries");
        m_matrix = m;
        m_linear = glm::dmat3(m);
        m_translation = dvec3(m[3]);
        m_affine = m[0][3] == 0.0 && m[1][3] == 0.0 && m[2][3] == 0.0 && m[3][3] == 1.0;
        m_cofactor = cofactor(m_linear);
        m_grids = control.grids;
        const double det = glm::determinant(m);
        // dPw/du x dPw/dv equals cof(A) (dPdu x dPdv) = det(A) A^-T n: the RI
        // normal (A^-T n, see detail::world_normal) up to the sign of det.
        m_normal_sign = ((det < 0.0) != attr.orientation_inside) ? -1.0 : 1.0;
        // User normals: direction of A^-T N.
        m_user_normal_matrix = det < 0.0 ? -m_cofactor : m_cofactor;
        // Whether dicing can size micropolygons at all (spacing, camera, rate)
        // does not depend on the point: check once, naming the primitive.
        try {
            const double e = control.edge_length_at(m_translation, m_rate);
            if (control.spacing > 0.0) m_spacing = e;
        } catch (const ValueError& err) {
            fail(prim, err.what());
        }
    }

    void dice(const Face& face) {
        m_face = &face;
        const Extent e = measure(0.0, 1.0, 0.0, 1.0, kFaceMeasureSamples);
        // Coarsest possible dicing first: a lower bound of the final count.
        const double at_least = cell_count(e.ulen, e.emax) * cell_count(e.vlen, e.emax);
        if (m_estimate) {
            add_estimate(e, at_least);
            return;
        }
        const double room = static_cast<double>(m_control.max_micropolygons) -
                            static_cast<double>(m_out.size());
        if (!(at_least <= room)) too_many(static_cast<double>(m_out.size()) + at_least);
        reserve_output(static_cast<std::size_t>(at_least));
        m_leaves.clear();
        m_planned = 0.0;
        refine(0.0, 1.0, 0.0, 1.0, 0, e);
        stitch();
        for (const Leaf& leaf : m_leaves) emit(leaf);
    }

private:
    /// A sub-patch to dice into nu x nv cells, with the vertex parameters
    /// that neighbouring sub-patches put on each of its sides
    /// (0: v = v0, 1: u = u1, 2: v = v1, 3: u = u0).
    struct Leaf {
        double u0, u1, v0, v1;
        int nu, nv;
        double threshold; ///< |dPw/du x dPw/dv| below this is degenerate
        std::array<std::vector<double>, 4> extra;
    };

    /// One leaf side lying on the line u or v = `line`, over [start, end].
    struct SideRef {
        double line;
        double start;
        double end;
        uint32_t leaf;
        int side;
    };

    /// LimitError: dicing needs at least `count` micropolygons.
    [[noreturn]] void too_many(double count) const {
        too_many_micropolygons(m_prim, m_control, count);
    }

    /// Adds the face's estimate to *m_estimate: its regions of even wanted
    /// edge (split like refine() splits, as long as the edge varies by more
    /// than 2 over a region) each estimated from their samples; never below
    /// `at_least`. Stops splitting once the primitive is surely beyond its
    /// budget.
    void add_estimate(const Extent& e, double at_least) {
        m_face_estimate = DiceEstimate{};
        estimate_region(0.0, 1.0, 0.0, 1.0, 0, e, kFaceMeasureSamples);
        DiceEstimate est = m_face_estimate;
        if (est.micropolygons < at_least) {
            const double scale = at_least / std::max(est.micropolygons, 1.0);
            est.micropolygons *= scale;
            est.vertices *= scale;
            est.triangles *= scale;
        }
        *m_estimate += est;
    }

    /// One region of the face just measured with `samples` per direction,
    /// split as refine() splits (too many cells, or a ShadingRate edge that
    /// varies by more than 2) but into regions of up to kEstimateCells
    /// cells, each counted as refine() counts a leaf: its longest u and v
    /// isoparametric lines over the finest edge, rounded up. Regions of a
    /// thin or sheared patch have far more cells than their area holds.
    void estimate_region(double u0, double u1, double v0, double v1, int depth,
                         const Extent& e, int samples) {
        (void)samples;
        const double budget = 4.0 * static_cast<double>(m_control.max_micropolygons);
        if (m_estimate->micropolygons + m_face_estimate.micropolygons > budget) {
            m_face_estimate.micropolygons += budget; // surely too many: stop here
            return;
        }
        const double nu = cell_count(e.ulen, e.emin), nv = cell_count(e.vlen, e.emin);
        const bool too_big = nu * nv > kEstimateCells;
        const bool uneven = m_spacing <= 0.0 && e.emax > 2.0 * e.emin && nu * nv > 1.0;
        if ((too_big || uneven) && depth < kMaxSplitDepth) {
            if (nu >= nv) {
                const double um = 0.5 * (u0 + u1);
                estimate_region(u0, um, v0, v1, depth + 1,
                                measure(u0, um, v0, v1, kMeasureSamples),
                                kMeasureSamples);
                estimate_region(um, u1, v0, v1, depth + 1,
                                measure(um, u1, v0, v1, kMeasureSamples),
                                kMeasureSamples);
            } else {
                const double vm = 0.5 * (v0 + v1);
                estimate_region(u0, u1, v0, vm, depth + 1,
                                measure(u0, u1, v0, vm, kMeasureSamples),
                                kMeasureSamples);
                estimate_region(u0, u1, vm, v1, depth + 1,
                                measure(u0, u1, vm, v1, kMeasureSamples),
                                kMeasureSamples);
            }
            return;
        }
        // refine() cuts this region into grids of up to kMaxGridCells, each
        // rounding its counts up: about 15% more.
        DiceEstimate est;
        est.micropolygons = 1.15 * nu * nv;
        est.vertices = 1.3 * est.micropolygons + 2.0 * (nu + nv);
        est.triangles = 2.2 * est.micropolygons;
        m_face_estimate += est;
    }

    /// Makes room for `more` micropolygons (and their grids) at once rather
    /// than by repeated doubling; geometric growth is kept across faces.
    void reserve_output(std::size_t more) {
        const std::size_t want = m_out.size() + more;
        if (want <= m_out.centers.capacity()) return;
        const std::size_t n = std::max(want, 2 * m_out.centers.capacity());
        const bool colors = m_face->color.present();
        m_out.centers.reserve(n);
        m_out.normals.reserve(n);
        m_out.areas.reserve(n);
        m_out.radii.reserve(n);
        if (colors) m_out.colors.reserve(n);
        // Grid vertices are about 1.15 per cell; stitching adds side
        // vertices and fan centres.
        const std::size_t verts = m_out.vertices.size() + more + more / 2;
        if (verts > m_out.vertices.capacity()) {
            const std::size_t nv = std::max(verts, 2 * m_out.vertices.capacity());
            m_out.vertices.reserve(nv);
            m_out.vertex_normals.reserve(nv);
            if (m_grids) m_out.vertex_uvst.reserve(nv);
        }
        const std::size_t tris = m_out.triangles.size() + 7 * more;
        if (tris > m_out.triangles.capacity())
            m_out.triangles.reserve(std::max(tris, 2 * m_out.triangles.capacity()));
    }

    double edge_at(const dvec3& world_p) const {
        return m_spacing > 0.0 ? m_spacing : m_control.edge_length_at(world_p, m_rate);
    }

    dvec3 world_point(const dvec3& p) const {
        if (m_affine) return m_linear * p + m_translation;
        const dvec4 h = m_matrix * dvec4(p, 1.0);
        return dvec3(h) / h.w;
    }

    /// World position and world dPdu x dPdv of an object-space sample.
    void to_world(const SurfacePoint& s, dvec3& p, dvec3& cross) const {
        if (m_affine) {
            p = m_linear * s.p + m_translation;
            cross = m_cofactor * glm::cross(s.dpdu, s.dpdv);
            return;
        }
        // Projective transform: quotient rule on the homogeneous point.
        const dvec4 h = m_matrix * dvec4(s.p, 1.0);
        const dvec4 hu = m_matrix * dvec4(s.dpdu, 0.0);
        const dvec4 hv = m_matrix * dvec4(s.dpdv, 0.0);
        p = dvec3(h) / h.w;
        const dvec3 du = (dvec3(hu) - p * hu.w) / h.w;
        const dvec3 dv = (dvec3(hv) - p * hv.w) / h.w;
        cross = glm::cross(du, dv);
    }

    /// Fills `out` with n parameter values from a to b, the last exactly b.
    static void spread(double a, double b, int n, std::vector<double>& out) {
        out.resize(static_cast<std::size_t>(n) + 1);
        const double step = (b - a) / n;
        for (int i = 0; i < n; ++i) out[i] = a + i * step;
        out[n] = b;
    }

    Extent measure(double u0, double u1, double v0, double v1, int samples) {
        spread(u0, u1, samples - 1, m_su);
        spread(v0, v1, samples - 1, m_sv);
        const std::size_t n = static_cast<std::size_t>(samples);
        ensure_size(m_eval, n * n);
        m_face->geometry->evaluate(m_su, m_sv, m_eval.data());
        ensure_size(m_wp, n * n);
        ensure_size(m_we, n * n);
        Extent e;
        e.emin = std::numeric_limits<double>::infinity();
        e.emax = 0.0;
        for (std::size_t k = 0; k < n * n; ++k) {
            m_wp[k] = world_point(m_eval[k].p);
            check_world_point(m_prim, m_wp[k]);
            const double len = edge_at(m_wp[k]);
            m_we[k] = len;
            e.emin = std::min(e.emin, len);
            e.emax = std::max(e.emax, len);
        }
        for (std::size_t j = 0; j < n; ++j) {
            double row = 0.0;
            double col = 0.0;
            for (std::size_t i = 0; i + 1 < n; ++i) {
                row += glm::distance(m_wp[j * n + i], m_wp[j * n + i + 1]);
                col += glm::distance(m_wp[i * n + j], m_wp[(i + 1) * n + j]);
            }
            e.ulen = std::max(e.ulen, row);
            e.vlen = std::max(e.vlen, col);
        }
        if (!std::isfinite(e.ulen) || !std::isfinite(e.vlen))
            fail(m_prim,
                 "surface has NaN or infinite points (check the transform and \"P\")");
        if (!(e.emin > 0.0) || !std::isfinite(e.emax))
            fail(m_prim, "wanted micropolygon size is not a finite number > 0");
        // Every split and grid size follows from these (motion blur replays them).
        e.ulen = m_control.note(e.ulen, m_prim);
        e.vlen = m_control.note(e.vlen, m_prim);
        e.emin = m_control.note(e.emin, m_prim);
        e.emax = m_control.note(e.emax, m_prim);
        return e;
    }

    void refine(double u0, double u1, double v0, double v1, int depth, const Extent& e) {
        const double nu = cell_count(e.ulen, e.emin);
        const double nv = cell_count(e.vlen, e.emin);
        const bool too_big = nu * nv > kMaxGridCells;
        // ShadingRate dicing: the size wanted must not vary much over one grid.
        const bool uneven = m_spacing <= 0.0 && e.emax > 2.0 * e.emin && nu * nv > 1.0;
        if ((too_big || uneven) && depth < kMaxSplitDepth) {
            if (nu >= nv) {
                const double um = 0.5 * (u0 + u1);
                refine(u0, um, v0, v1, depth + 1,
                       measure(u0, um, v0, v1, kMeasureSamples));
                refine(um, u1, v0, v1, depth + 1,
                       measure(um, u1, v0, v1, kMeasureSamples));
            } else {
                const double vm = 0.5 * (v0 + v1);
                refine(u0, u1, v0, vm, depth + 1,
                       measure(u0, u1, v0, vm, kMeasureSamples));
                refine(u0, u1, vm, v1, depth + 1,
                       measure(u0, u1, vm, v1, kMeasureSamples));
            }
            return;
        }
        const double room = static_cast<double>(m_control.max_micropolygons) -
                            static_cast<double>(m_out.size()) - m_planned;
        if (!(nu * nv <= room) || nu > 1e9 || nv > 1e9)
            too_many(static_cast<double>(m_out.size()) + m_planned + nu * nv);
        m_planned += nu * nv;
        // Typical |dPw/du x dPw/dv| of this sub-patch, to recognise noise.
        const double scale = (e.ulen / (u1 - u0)) * (e.vlen / (v1 - v0));
        m_leaves.push_back(Leaf{u0,
                                u1,
                                v0,
                                v1,
                                static_cast<int>(nu),
                                static_cast<int>(nv),
                                kDegenerateRatio * std::abs(scale),
                                {}});
    }

    /// Grid vertex parameters of one side of a leaf, ascending.
    static void side_params(const Leaf& l, int side, std::vector<double>& out) {
        if (side == 0 || side == 2)
            spread(l.u0, l.u1, l.nu, out);
        else
            spread(l.v0, l.v1, l.nv, out);
    }

    /// Neighbouring leaves diced at different rates would leave cracks along
    /// their common side: give each side the other's vertices too, so that
    /// both triangulate the same polyline. Split lines are shared doubles, so
    /// sides on one line compare exactly.
    void stitch() {
        if (m_leaves.size() < 2) return;
        m_hsides.clear();
        m_vsides.clear();
        for (uint32_t k = 0; k < m_leaves.size(); ++k) {
            const Leaf& l = m_leaves[k];
            m_hsides.push_back({l.v0, l.u0, l.u1, k, 0});
            m_hsides.push_back({l.v1, l.u0, l.u1, k, 2});
            m_vsides.push_back({l.u1, l.v0, l.v1, k, 1});
            m_vsides.push_back({l.u0, l.v0, l.v1, k, 3});
        }
        match_sides(m_hsides, 0, 2);
        match_sides(m_vsides, 3, 1);
    }

    /// Along each line, pairs the sides of the leaves beyond it (`after`)
    /// with those before it and exchanges their vertex parameters.
    void match_sides(std::vector<SideRef>& sides, int after, int before) {
        std::sort(sides.begin(), sides.end(), [](const SideRef& a, const SideRef& b) {
            return a.line != b.line ? a.line < b.line : a.start < b.start;
        });
        for (std::size_t g = 0; g < sides.size();) {
            std::size_t h = g;
            m_after.clear();
            m_before.clear();
            for (; h < sides.size() && sides[h].line == sides[g].line; ++h) {
                if (sides[h].side == after) m_after.push_back(sides[h]);
                if (sides[h].side == before) m_before.push_back(sides[h]);
            }
            // Both lists hold disjoint intervals sorted by start: merge them.
            std::size_t i = 0;
            std::size_t j = 0;
            while (i < m_after.size() && j < m_before.size()) {
                const SideRef& a = m_after[i];
                const SideRef& b = m_before[j];
                if (std::max(a.start, b.start) < std::min(a.end, b.end)) {
                    share(a, b);
                    share(b, a);
                }
                if (a.end < b.end)
                    ++i;
                else
                    ++j;
            }
            g = h;
        }
    }

    /// Adds the vertex parameters of side `from` that lie on side `to` to it.
    void share(const SideRef& from, const SideRef& to) {
        side_params(m_leaves[from.leaf], from.side, m_params);
        auto& extra = m_leaves[to.leaf].extra[to.side];
        for (double x : m_params)
            if (x >= to.start && x <= to.end) extra.push_back(x);
    }

    /// Unit normal from a world dPw/du x dPw/dv, or nullopt if degenerate.
    std::optional<dvec3> orient(const dvec3& cross, double threshold) const {
        const double len = glm::length(cross);
        if (!(len > threshold) || !std::isfinite(len)) return std::nullopt;
        return cross * (m_normal_sign / len);
    }

    /// World normal of a user-supplied object-space N, or nullopt if degenerate.
    std::optional<dvec3> user_normal(const dvec3& n) const {
        const dvec3 w = m_user_normal_matrix * n;
        const double len = glm::length(w);
        if (!(len > 0.0) || !std::isfinite(len)) return std::nullopt;
        return w / len;
    }

    /// Geometric normal at one parameter point, if not degenerate there.
    std::optional<dvec3> normal_at(double u, double v, double threshold) const {
        SurfacePoint sp;
        m_face->geometry->evaluate(std::span<const double>(&u, 1),
                                   std::span<const double>(&v, 1), &sp);
        dvec3 p;
        dvec3 cross;
        to_world(sp, p, cross);
        return orient(cross, threshold);
    }

    /// Dices a leaf into nu x nv micropolygons and its grid into triangles.
    void emit(const Leaf& leaf) {
        if (m_control.displace) {
            emit_displaced(leaf);
            return;
        }
        const double u0 = leaf.u0;
        const double u1 = leaf.u1;
        const double v0 = leaf.v0;
        const double v1 = leaf.v1;
        const int nu = leaf.nu;
        const int nv = leaf.nv;
        const double threshold = leaf.threshold;
        const std::size_t nu1 = static_cast<std::size_t>(nu) + 1;
        const std::size_t nv1 = static_cast<std::size_t>(nv) + 1;
        const std::size_t cells =
            static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv);
        const double du = (u1 - u0) / nu;
        const double dv = (v1 - v0) / nv;

        // Grid vertices.
        spread(u0, u1, nu, m_vu);
        spread(v0, v1, nv, m_vv);
        ensure_size(m_eval, std::max(nu1 * nv1, 4 * cells));
        m_face->geometry->evaluate(m_vu, m_vv, m_eval.data());
        ensure_size(m_vert_p, nu1 * nv1);
        ensure_size(m_vert_cross, nu1 * nv1);
        for (std::size_t k = 0; k < nu1 * nv1; ++k)
            to_world(m_eval[k], m_vert_p[k], m_vert_cross[k]);

        // Cell areas: 2x2 Gauss-Legendre of |dPw/du x dPw/dv| per cell; the
        // vector sum is kept as a fallback normal.
        const double g = 0.5 / std::sqrt(3.0);
        m_gu.resize(2 * static_cast<std::size_t>(nu));
        m_gv.resize(2 * static_cast<std::size_t>(nv));
        for (int i = 0; i < nu; ++i) {
            const double c = u0 + (i + 0.5) * du;
            m_gu[2 * i] = c - g * du;
            m_gu[2 * i + 1] = c + g * du;
        }
        for (int j = 0; j < nv; ++j) {
            const double c = v0 + (j + 0.5) * dv;
            m_gv[2 * j] = c - g * dv;
            m_gv[2 * j + 1] = c + g * dv;
        }
        m_face->geometry->evaluate(m_gu, m_gv, m_eval.data());
        m_cell_area.assign(cells, 0.0);
        m_cell_vector.assign(cells, dvec3(0.0));
        const double weight = 0.25 * std::abs(du * dv);
        const std::size_t grow = 2 * static_cast<std::size_t>(nu);
        for (std::size_t gj = 0; gj < 2 * static_cast<std::size_t>(nv); ++gj)
            for (std::size_t gi = 0; gi < grow; ++gi) {
                dvec3 p;
                dvec3 cross;
                to_world(m_eval[gj * grow + gi], p, cross);
                const std::size_t cell = (gj / 2) * static_cast<std::size_t>(nu) + gi / 2;
                m_cell_area[cell] += weight * glm::length(cross);
                m_cell_vector[cell] += cross;
            }
        double total_area = 0.0;
        for (double a : m_cell_area) total_area += a;
        if (!(total_area > 0.0)) return; // a degenerate sub-patch covers nothing

        // Cell centres.
        m_cu.resize(static_cast<std::size_t>(nu));
        m_cv.resize(static_cast<std::size_t>(nv));
        for (int i = 0; i < nu; ++i) m_cu[i] = u0 + (i + 0.5) * du;
        for (int j = 0; j < nv; ++j) m_cv[j] = v0 + (j + 0.5) * dv;
        m_face->geometry->evaluate(m_cu, m_cv, m_eval.data());
        const bool has_color = m_face->color.present();
        const bool has_normal = m_face->normal.present();
        if (has_color) {
            ensure_size(m_values, cells);
            m_face->color.evaluate(m_cu, m_cv, m_values.data());
        }
        if (has_normal) {
            ensure_size(m_user_n, cells);
            m_face->normal.evaluate(m_cu, m_cv, m_user_n.data());
        }
        m_cell_normal.assign(cells, std::nullopt);
        ensure_size(m_cell_p, cells);
        const std::size_t first = m_out.centers.size();
        if (m_grids) evaluate_texture_coordinates(m_cu, m_cv);
        for (int j = 0; j < nv; ++j)
            for (int i = 0; i < nu; ++i) {
                const std::size_t c = static_cast<std::size_t>(j) * nu + i;
                dvec3 p;
                dvec3 cross;
                to_world(m_eval[c], p, cross);
                // Centre normal; else the cell's vector area; else its diagonals.
                std::optional<dvec3> n = orient(cross, threshold);
                if (!n) n = orient(m_cell_vector[c], 0.0);
                const dvec3& p00 = m_vert_p[j * nu1 + i];
                const dvec3& p10 = m_vert_p[j * nu1 + i + 1];
                const dvec3& p01 = m_vert_p[(j + 1) * nu1 + i];
                const dvec3& p11 = m_vert_p[(j + 1) * nu1 + i + 1];
                if (!n) n = orient(glm::cross(p11 - p00, p01 - p10), 0.0);
                if (n && has_normal) {
                    if (auto un = user_normal(m_user_n[c])) n = un;
                }
                m_cell_p[c] = p;
                m_cell_normal[c] = n;
                const double area = m_cell_area[c];
                if (!n || !(area > 0.0) || !std::isfinite(area)) continue;
                const double radius = std::sqrt(std::max(
                    std::max(glm::dot(p00 - p, p00 - p), glm::dot(p10 - p, p10 - p)),
                    std::max(glm::dot(p01 - p, p01 - p), glm::dot(p11 - p, p11 - p))));
                m_out.centers.emplace_back(p);
                m_out.normals.emplace_back(*n);
                m_out.areas.push_back(static_cast<float>(area));
                m_out.radii.push_back(static_cast<float>(radius));
                if (has_color) m_out.colors.emplace_back(m_values[c]);
                if (m_grids)
                    push_parametric(m_eval[c], m_cu[i], m_cv[j], du, dv, m_st[c]);
            }
        // A grid for the shaders only when no cell was dropped.
        if (m_grids && m_out.centers.size() - first == cells)
            m_out.grids.push_back(DicedGrid{first, nu, nv});

        emit_triangles(leaf);
    }

    /// s and t of the face at every (us[i], vs[j]) into m_st: the texture
    /// coordinate variables, else the primitive's u and v.
    void evaluate_texture_coordinates(std::span<const double> us,
                                      std::span<const double> vs) {
        evaluate_texture_coordinates(us, vs, m_st);
    }

    /// The same into `st`.
    void evaluate_texture_coordinates(std::span<const double> us,
                                      std::span<const double> vs,
                                      std::vector<glm::dvec2>& st) {
        const std::size_t n = us.size() * vs.size();
        ensure_size(st, n);
        ensure_size(m_values_s, n);
        ensure_size(m_values_t, n);
        if (m_face->s.present()) m_face->s.evaluate(us, vs, m_values_s.data());
        if (m_face->t.present()) m_face->t.evaluate(us, vs, m_values_t.data());
        for (std::size_t j = 0; j < vs.size(); ++j)
            for (std::size_t i = 0; i < us.size(); ++i) {
                const std::size_t k = j * us.size() + i;
                st[k] = glm::dvec2(m_face->s.present() ? m_values_s[k].x : prim_u(us[i]),
                                   m_face->t.present() ? m_values_t[k].x : prim_v(vs[j]));
            }
    }

    /// Appends DicedSurface::vertex_uvst of the vertices at (us[i], vs[j]),
    /// u fastest (the order they were appended in).
    void push_vertex_uvst(std::span<const double> us, std::span<const double> vs) {
        evaluate_texture_coordinates(us, vs, m_vertex_st);
        for (std::size_t j = 0; j < vs.size(); ++j)
            for (std::size_t i = 0; i < us.size(); ++i) {
                const glm::dvec2& st = m_vertex_st[j * us.size() + i];
                m_out.vertex_uvst.emplace_back(
                    glm::dvec4(prim_u(us[i]), prim_v(vs[j]), st.x, st.y));
            }
    }

    double prim_u(double u) const { return m_face->u_offset + m_face->u_scale * u; }
    double prim_v(double v) const { return m_face->v_offset + m_face->v_scale * v; }

    /// World dP/du and dP/dv of an object-space sample, in the primitive's
    /// parametrisation.
    void world_tangents(const SurfacePoint& s, dvec3& dpdu, dvec3& dpdv) const {
        if (m_affine) {
            dpdu = m_linear * s.dpdu;
            dpdv = m_linear * s.dpdv;
        } else {
            const dvec4 h = m_matrix * dvec4(s.p, 1.0);
            const dvec4 hu = m_matrix * dvec4(s.dpdu, 0.0);
            const dvec4 hv = m_matrix * dvec4(s.dpdv, 0.0);
            const dvec3 p = dvec3(h) / h.w;
            dpdu = (dvec3(hu) - p * hu.w) / h.w;
            dpdv = (dvec3(hv) - p * hv.w) / h.w;
        }
        dpdu /= m_face->u_scale;
        dpdv /= m_face->v_scale;
    }

    /// Appends one micropolygon's parametric data (face coordinates u, v
    /// and steps du, dv).
    void push_parametric(const SurfacePoint& sp, double u, double v, double du, double dv,
                         const glm::dvec2& st) {
        dvec3 dpdu;
        dvec3 dpdv;
        world_tangents(sp, dpdu, dpdv);
        m_out.u.push_back(static_cast<float>(prim_u(u)));
        m_out.v.push_back(static_cast<float>(prim_v(v)));
        m_out.du.push_back(static_cast<float>(du * m_face->u_scale));
        m_out.dv.push_back(static_cast<float>(dv * m_face->v_scale));
        m_out.s.push_back(static_cast<float>(st.x));
        m_out.t.push_back(static_cast<float>(st.y));
        m_out.dPdu.emplace_back(dpdu);
        m_out.dPdv.emplace_back(dpdv);
    }

    /// Normal of a grid or side vertex: user N, else dPw/du x dPw/dv, else
    /// (pole, apex, collapsed edge) the normal a little way into the grid,
    /// else that of the cell `cell`.
    dvec3 vertex_normal(const dvec3& cross, const dvec3* user_n, double un, double vn,
                        double threshold, std::size_t cell) const {
        std::optional<dvec3> n;
        if (user_n) n = user_normal(*user_n);
        if (!n) n = orient(cross, threshold);
        if (!n) n = normal_at(un, vn, threshold);
        if (!n) n = m_cell_normal[cell];
        return n.value_or(dvec3(0.0, 0.0, 1.0));
    }

    /// Grid vertices with normals and triangles: two per cell, or a fan
    /// around the cell centre where a neighbouring leaf with another grid put
    /// extra vertices on the cell's side (see stitch()). Leaves of one face
    /// thus join without cracks; faces of a patch mesh (and the teapot's
    /// patches) meet along their common boundary curve, but with different
    /// vertices where their rates differ, which leaves cracks of the order of
    /// the curve's sagitta over one micropolygon.
    void emit_triangles(const Leaf& leaf) {
        const int nu = leaf.nu;
        const int nv = leaf.nv;
        const double threshold = leaf.threshold;
        const std::size_t nu1 = static_cast<std::size_t>(nu) + 1;
        const std::size_t nv1 = static_cast<std::size_t>(nv) + 1;
        const std::size_t cells =
            static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv);
        std::size_t extras = 0;
        for (const auto& e : leaf.extra) extras += e.size();
        const std::size_t base = m_out.vertices.size();
        if (base + nu1 * nv1 + extras + cells > std::numeric_limits<uint32_t>::max())
            fail(m_prim, "too many triangle vertices for 32-bit indices");
        const bool has_normal = m_face->normal.present() && !m_displacing;
        if (has_normal) {
            ensure_size(m_user_n, nu1 * nv1);
            m_face->normal.evaluate(m_vu, m_vv, m_user_n.data());
        }
        const double du = (leaf.u1 - leaf.u0) / nu;
        const double dv = (leaf.v1 - leaf.v0) / nv;
        for (std::size_t j = 0; j < nv1; ++j)
            for (std::size_t i = 0; i < nu1; ++i) {
                const std::size_t k = j * nu1 + i;
                const double un =
                    m_vu[i] + (i < nu1 - 1 ? kNudgeCells : -kNudgeCells) * du;
                const double vn =
                    m_vv[j] + (j < nv1 - 1 ? kNudgeCells : -kNudgeCells) * dv;
                const std::size_t cell = std::min<std::size_t>(j, nv - 1) * nu +
                                         std::min<std::size_t>(i, nu - 1);
                m_out.vertices.emplace_back(m_vert_p[k]);
                if (m_displacing)
                    m_out.vertex_normals.emplace_back(m_vert_n[k]);
                else
                    m_out.vertex_normals.emplace_back(vertex_normal(
                        m_vert_cross[k], has_normal ? &m_user_n[k] : nullptr, un, vn,
                        threshold, cell));
            }
        if (m_grids) push_vertex_uvst(m_vu, m_vv);

        bool stitched = false;
        for (int s = 0; s < 4; ++s) stitched |= add_side_vertices(leaf, s);

        // Winding follows the final normal: counter-clockwise seen from its side.
        const bool flip = m_normal_sign < 0.0;
        for (std::size_t j = 0; j < static_cast<std::size_t>(nv); ++j)
            for (std::size_t i = 0; i < static_cast<std::size_t>(nu); ++i) {
                const auto i00 = static_cast<uint32_t>(base + j * nu1 + i);
                const auto i10 = i00 + 1;
                const auto i01 = static_cast<uint32_t>(i00 + nu1);
                const auto i11 = i01 + 1;
                if (stitched && fan_cell(leaf, i, j, {i00, i10, i11, i01}, flip))
                    continue;
                add_triangle(i00, flip ? i11 : i10, flip ? i10 : i11);
                add_triangle(i00, flip ? i01 : i11, flip ? i11 : i01);
            }
    }

    /// Adds the vertices that neighbours put inside the cells of one side of
    /// the leaf (m_side_cell / m_side_vertex); false if there are none.
    bool add_side_vertices(const Leaf& leaf, int s) {
        m_side_cell[s].clear();
        m_side_vertex[s].clear();
        if (leaf.extra[s].empty()) return false;
        m_side_x = leaf.extra[s];
        std::sort(m_side_x.begin(), m_side_x.end());
        m_side_x.erase(std::unique(m_side_x.begin(), m_side_x.end()), m_side_x.end());
        side_params(leaf, s, m_params);
        std::size_t kept = 0;
        for (double x : m_side_x) {
            const auto it = std::upper_bound(m_params.begin(), m_params.end(), x);
            if (it == m_params.begin() || it == m_params.end()) continue;
            const auto cell = static_cast<int>(it - m_params.begin()) - 1;
            if (m_params[cell] == x) continue; // already a grid vertex
            m_side_x[kept++] = x;
            m_side_cell[s].push_back(cell);
        }
        m_side_x.resize(kept);
        if (kept == 0) return false;

        const bool along_u = s == 0 || s == 2;
        const double line = s == 0   ? leaf.v0
                            : s == 2 ? leaf.v1
                            : s == 1 ? leaf.u1
                                     : leaf.u0;
        const std::span<const double> xs(m_side_x);
        const std::span<const double> at(&line, 1);
        const auto us = along_u ? xs : at;
        const auto vs = along_u ? at : xs;
        ensure_size(m_eval, kept);
        m_face->geometry->evaluate(us, vs, m_eval.data());
        const bool has_normal = m_face->normal.present();
        if (has_normal) {
            ensure_size(m_user_n, kept);
            m_face->normal.evaluate(us, vs, m_user_n.data());
        }
        // Nudge inwards, across the side, for degenerate normals.
        const double inward = (s == 0 || s == 3) ? kNudgeCells : -kNudgeCells;
        const double du = (leaf.u1 - leaf.u0) / leaf.nu;
        const double dv = (leaf.v1 - leaf.v0) / leaf.nv;
        for (std::size_t k = 0; k < kept; ++k) {
            dvec3 p;
            dvec3 cross;
            to_world(m_eval[k], p, cross);
            const int t = m_side_cell[s][k];
            const std::size_t cell =
                s == 0   ? static_cast<std::size_t>(t)
                : s == 2 ? static_cast<std::size_t>(leaf.nv - 1) * leaf.nu + t
                : s == 1 ? static_cast<std::size_t>(t) * leaf.nu + leaf.nu - 1
                         : static_cast<std::size_t>(t) * leaf.nu;
            const double un = along_u ? m_side_x[k] : line + inward * du;
            const double vn = along_u ? line + inward * dv : m_side_x[k];
            m_side_vertex[s].push_back(static_cast<uint32_t>(m_out.vertices.size()));
            m_out.vertices.emplace_back(p);
            m_out.vertex_normals.emplace_back(
                vertex_normal(cross, has_normal ? &m_user_n[k] : nullptr, un, vn,
                              leaf.threshold, cell));
        }
        // At their own parameters: exactly the neighbour's values there.
        if (m_grids) push_vertex_uvst(us, vs);
        if (m_displacing) displace_side_vertices(leaf, s, us, vs);
        return true;
    }

    /// Displaces the vertices a neighbour put on side s (just added, in
    /// m_side_vertex[s], at parameters m_side_x): as unrelated points, so
    /// that they land where the neighbour's grid put the same points (for
    /// shaders that move a point by its own P, N, u, v, s and t); their
    /// normals interpolate the displaced normals of the side's grid vertices.
    void displace_side_vertices(const Leaf& leaf, int s, std::span<const double> us,
                                std::span<const double> vs) {
        const std::size_t kept = m_side_x.size();
        const std::vector<uint32_t>& index = m_side_vertex[s];
        ensure_size(m_tmp_p, kept);
        ensure_size(m_tmp_n, kept);
        for (std::size_t k = 0; k < kept; ++k) {
            m_tmp_p[k] = dvec3(m_out.vertices[index[k]]);
            m_tmp_n[k] = dvec3(m_out.vertex_normals[index[k]]);
        }
        const double du = (leaf.u1 - leaf.u0) / leaf.nu;
        const double dv = (leaf.v1 - leaf.v0) / leaf.nv;
        run_hook(us, vs, m_eval.data(), m_tmp_p.data(), m_tmp_n.data(), du, dv, false);
        const std::size_t nu1 = static_cast<std::size_t>(leaf.nu) + 1;
        const bool along_u = s == 0 || s == 2;
        for (std::size_t k = 0; k < kept; ++k) {
            const std::size_t t = static_cast<std::size_t>(m_side_cell[s][k]);
            // The side's grid vertices around the point, and its place between them.
            std::size_t a = 0;
            std::size_t b = 0;
            double w = 0.0;
            if (along_u) {
                const std::size_t row = s == 0 ? 0 : static_cast<std::size_t>(leaf.nv);
                a = row * nu1 + t;
                b = a + 1;
                w = (m_side_x[k] - m_vu[t]) / (m_vu[t + 1] - m_vu[t]);
            } else {
                const std::size_t col = s == 3 ? 0 : static_cast<std::size_t>(leaf.nu);
                a = t * nu1 + col;
                b = a + nu1;
                w = (m_side_x[k] - m_vv[t]) / (m_vv[t + 1] - m_vv[t]);
            }
            dvec3 n = (1.0 - w) * m_vert_n[a] + w * m_vert_n[b];
            const double len = glm::length(n);
            n = len > 0.0 && std::isfinite(len) ? n / len : dvec3(m_disp.N[k]);
            dvec3 p(m_disp.P[k]);
            dvec3 undisplaced;
            dvec3 cross;
            to_world(m_eval[k], undisplaced, cross);
            if (!orient(cross, leaf.threshold)) weld(undisplaced, p, n);
            m_out.vertices[index[k]] = glm::vec3(p);
            m_out.vertex_normals[index[k]] = glm::vec3(n);
        }
    }

    /// Degenerate points (poles, apexes, collapsed patch edges), which many
    /// grid vertices share, take the displacement of the first of them:
    /// their normals are nudged into each grid, and would otherwise move
    /// them apart, opening tiny holes.
    void weld(const dvec3& undisplaced, dvec3& p, dvec3& n) {
        for (const Weld& w : m_welds)
            if (w.undisplaced == undisplaced) {
                p = w.p;
                n = w.n;
                return;
            }
        m_welds.push_back({undisplaced, p, n});
    }

    /// Hands n points (tensor grid us x vs, or unrelated points along one
    /// line when !grid) to the displacement hook: positions p and normals n
    /// in, m_disp.P and m_disp.N out (normals replaced by `n` where the
    /// shader left none).
    void run_hook(std::span<const double> us, std::span<const double> vs,
                  const SurfacePoint* sp, const dvec3* p, const dvec3* n, double du,
                  double dv, bool grid) {
        const std::size_t count = us.size() * vs.size();
        evaluate_texture_coordinates(us, vs);
        DisplaceGrid& g = m_disp;
        g.primitive = &m_prim;
        g.grid = grid;
        g.nu = grid ? static_cast<int>(us.size()) : static_cast<int>(count);
        g.nv = grid ? static_cast<int>(vs.size()) : 1;
        g.sequence = m_sequence++;
        g.resize(count);
        for (std::size_t j = 0; j < vs.size(); ++j)
            for (std::size_t i = 0; i < us.size(); ++i) {
                const std::size_t k = j * us.size() + i;
                dvec3 dpdu;
                dvec3 dpdv;
                world_tangents(sp[k], dpdu, dpdv);
                g.P[k] = glm::vec3(p[k]);
                g.N[k] = glm::vec3(n[k]);
                g.Ng[k] = g.N[k];
                g.u[k] = static_cast<float>(prim_u(us[i]));
                g.v[k] = static_cast<float>(prim_v(vs[j]));
                g.du[k] = static_cast<float>(du * m_face->u_scale);
                g.dv[k] = static_cast<float>(dv * m_face->v_scale);
                g.s[k] = static_cast<float>(m_st[k].x);
                g.t[k] = static_cast<float>(m_st[k].y);
                g.dPdu[k] = glm::vec3(dpdu);
                g.dPdv[k] = glm::vec3(dpdv);
            }
        m_control.displace(g);
        if (g.P.size() != count || g.N.size() != count)
            fail(m_prim, "displacement returned a wrong number of points");
        for (std::size_t k = 0; k < count; ++k) {
            const double len = glm::length(glm::dvec3(g.N[k]));
            if (!(len > 0.0) || !std::isfinite(len))
                g.N[k] = glm::vec3(n[k]);
            else
                g.N[k] = glm::vec3(glm::dvec3(g.N[k]) / len);
            if (!finite(glm::dvec3(g.P[k]))) g.P[k] = glm::vec3(p[k]);
        }
    }

    /// emit() with displacement: the grid's vertices and its micropolygon
    /// centres are displaced (two hook calls); areas and radii come from the
    /// displaced vertices (the two triangles of each cell), normals from the
    /// shader.
    void emit_displaced(const Leaf& leaf) {
        m_displacing = true;
        const int nu = leaf.nu;
        const int nv = leaf.nv;
        const double threshold = leaf.threshold;
        const std::size_t nu1 = static_cast<std::size_t>(nu) + 1;
        const std::size_t nv1 = static_cast<std::size_t>(nv) + 1;
        const std::size_t cells =
            static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv);
        const double du = (leaf.u1 - leaf.u0) / nu;
        const double dv = (leaf.v1 - leaf.v0) / nv;

        // Undisplaced centres and their normals (as emit()).
        m_cu.resize(static_cast<std::size_t>(nu));
        m_cv.resize(static_cast<std::size_t>(nv));
        for (int i = 0; i < nu; ++i) m_cu[i] = leaf.u0 + (i + 0.5) * du;
        for (int j = 0; j < nv; ++j) m_cv[j] = leaf.v0 + (j + 0.5) * dv;
        ensure_size(m_cell_eval, cells);
        m_face->geometry->evaluate(m_cu, m_cv, m_cell_eval.data());
        spread(leaf.u0, leaf.u1, nu, m_vu);
        spread(leaf.v0, leaf.v1, nv, m_vv);
        ensure_size(m_vert_eval, nu1 * nv1);
        m_face->geometry->evaluate(m_vu, m_vv, m_vert_eval.data());
        ensure_size(m_vert_p, nu1 * nv1);
        ensure_size(m_vert_cross, nu1 * nv1);
        for (std::size_t k = 0; k < nu1 * nv1; ++k)
            to_world(m_vert_eval[k], m_vert_p[k], m_vert_cross[k]);
        const bool has_normal = m_face->normal.present();
        if (has_normal) {
            ensure_size(m_user_n, cells);
            m_face->normal.evaluate(m_cu, m_cv, m_user_n.data());
        }
        m_cell_normal.assign(cells, std::nullopt);
        ensure_size(m_cell_p, cells);
        ensure_size(m_tmp_n, std::max(cells, nu1 * nv1));
        for (int j = 0; j < nv; ++j)
            for (int i = 0; i < nu; ++i) {
                const std::size_t c = static_cast<std::size_t>(j) * nu + i;
                dvec3 cross;
                to_world(m_cell_eval[c], m_cell_p[c], cross);
                std::optional<dvec3> n = orient(cross, threshold);
                const dvec3& p00 = m_vert_p[j * nu1 + i];
                const dvec3& p10 = m_vert_p[j * nu1 + i + 1];
                const dvec3& p01 = m_vert_p[(j + 1) * nu1 + i];
                const dvec3& p11 = m_vert_p[(j + 1) * nu1 + i + 1];
                if (!n) n = orient(glm::cross(p11 - p00, p01 - p10), 0.0);
                if (n && has_normal) {
                    if (auto un = user_normal(m_user_n[c])) n = un;
                }
                m_cell_normal[c] = n;
                m_tmp_n[c] = n.value_or(dvec3(0.0, 0.0, 1.0));
            }

        // Displaced centres.
        run_hook(m_cu, m_cv, m_cell_eval.data(), m_cell_p.data(), m_tmp_n.data(), du, dv,
                 true);
        ensure_size(m_cell_dp, cells);
        ensure_size(m_cell_dn, cells);
        for (std::size_t c = 0; c < cells; ++c) {
            m_cell_dp[c] = dvec3(m_disp.P[c]);
            m_cell_dn[c] = dvec3(m_disp.N[c]);
        }

        // Undisplaced vertex normals (as emit_triangles()), then displaced vertices.
        if (has_normal) {
            ensure_size(m_user_n, nu1 * nv1);
            m_face->normal.evaluate(m_vu, m_vv, m_user_n.data());
        }
        ensure_size(m_vert_n, nu1 * nv1);
        for (std::size_t j = 0; j < nv1; ++j)
            for (std::size_t i = 0; i < nu1; ++i) {
                const std::size_t k = j * nu1 + i;
                const double un =
                    m_vu[i] + (i < nu1 - 1 ? kNudgeCells : -kNudgeCells) * du;
                const double vn =
                    m_vv[j] + (j < nv1 - 1 ? kNudgeCells : -kNudgeCells) * dv;
                const std::size_t cell = std::min<std::size_t>(j, nv - 1) * nu +
                                         std::min<std::size_t>(i, nu - 1);
                m_vert_n[k] =
                    vertex_normal(m_vert_cross[k], has_normal ? &m_user_n[k] : nullptr,
                                  un, vn, threshold, cell);
            }
        run_hook(m_vu, m_vv, m_vert_eval.data(), m_vert_p.data(), m_vert_n.data(), du, dv,
                 true);
        for (std::size_t k = 0; k < nu1 * nv1; ++k) {
            dvec3 p(m_disp.P[k]);
            dvec3 n(m_disp.N[k]);
            if (!orient(m_vert_cross[k], threshold)) weld(m_vert_p[k], p, n);
            m_vert_p[k] = p;
            m_vert_n[k] = n;
        }

        // Micropolygons of the displaced grid.
        const bool has_color = m_face->color.present();
        if (has_color) {
            ensure_size(m_values, cells);
            m_face->color.evaluate(m_cu, m_cv, m_values.data());
        }
        const std::size_t first = m_out.centers.size();
        if (m_grids) evaluate_texture_coordinates(m_cu, m_cv);
        for (int j = 0; j < nv; ++j)
            for (int i = 0; i < nu; ++i) {
                const std::size_t c = static_cast<std::size_t>(j) * nu + i;
                const dvec3& p00 = m_vert_p[j * nu1 + i];
                const dvec3& p10 = m_vert_p[j * nu1 + i + 1];
                const dvec3& p01 = m_vert_p[(j + 1) * nu1 + i];
                const dvec3& p11 = m_vert_p[(j + 1) * nu1 + i + 1];
                const dvec3& p = m_cell_dp[c];
                // The cell's two triangles, as emit_triangles() cuts it.
                const double area = 0.5 * (glm::length(glm::cross(p10 - p00, p11 - p00)) +
                                           glm::length(glm::cross(p11 - p00, p01 - p00)));
                const bool keep = m_cell_normal[c] && area > 0.0 && std::isfinite(area);
                m_cell_p[c] = p;
                if (!keep) {
                    m_cell_normal[c] = std::nullopt;
                    continue;
                }
                const dvec3 n = m_cell_dn[c];
                m_cell_normal[c] = n;
                const double radius = std::sqrt(std::max(
                    std::max(glm::dot(p00 - p, p00 - p), glm::dot(p10 - p, p10 - p)),
                    std::max(glm::dot(p01 - p, p01 - p), glm::dot(p11 - p, p11 - p))));
                m_out.centers.emplace_back(p);
                m_out.normals.emplace_back(n);
                m_out.areas.push_back(static_cast<float>(area));
                m_out.radii.push_back(static_cast<float>(radius));
                if (has_color) m_out.colors.emplace_back(m_values[c]);
                if (m_grids)
                    push_parametric(m_cell_eval[c], m_cu[i], m_cv[j], du, dv, m_st[c]);
            }
        if (m_grids && m_out.centers.size() - first == cells)
            m_out.grids.push_back(DicedGrid{first, nu, nv});

        emit_triangles(leaf);
        m_displacing = false;
    }

    /// Triangulates cell (i, j) as a fan around its centre if one of its
    /// sides carries extra vertices; false (nothing done) otherwise.
    bool fan_cell(const Leaf& leaf, std::size_t i, std::size_t j,
                  const std::array<uint32_t, 4>& corners, bool flip) {
        const std::size_t nu = static_cast<std::size_t>(leaf.nu);
        const std::size_t nv = static_cast<std::size_t>(leaf.nv);
        // The extra vertices of side s inside its cell t, in side order.
        const auto range = [&](int s, std::size_t t) {
            const auto& cells = m_side_cell[s];
            const auto r =
                std::equal_range(cells.begin(), cells.end(), static_cast<int>(t));
            return std::pair<std::size_t, std::size_t>(r.first - cells.begin(),
                                                       r.second - cells.begin());
        };
        std::pair<std::size_t, std::size_t> side[4] = {{0, 0}, {0, 0}, {0, 0}, {0, 0}};
        if (j == 0) side[0] = range(0, i);
        if (i == nu - 1) side[1] = range(1, j);
        if (j == nv - 1) side[2] = range(2, i);
        if (i == 0) side[3] = range(3, j);
        bool any = false;
        for (const auto& r : side) any |= r.first != r.second;
        if (!any) return false;

        // The cell outline, counter-clockwise in (u, v): bottom and right
        // sides run with their parameter, top and left against it.
        m_poly.clear();
        for (int s = 0; s < 4; ++s) {
            m_poly.push_back(corners[s]);
            const auto& verts = m_side_vertex[s];
            if (s < 2)
                for (std::size_t k = side[s].first; k < side[s].second; ++k)
                    m_poly.push_back(verts[k]);
            else
                for (std::size_t k = side[s].second; k > side[s].first; --k)
                    m_poly.push_back(verts[k - 1]);
        }
        const std::size_t c = j * nu + i;
        const auto centre = static_cast<uint32_t>(m_out.vertices.size());
        m_out.vertices.emplace_back(m_cell_p[c]);
        m_out.vertex_normals.emplace_back(
            m_cell_normal[c].value_or(dvec3(m_out.vertex_normals[corners[0]])));
        if (m_grids)
            push_vertex_uvst(std::span<const double>(&m_cu[i], 1),
                             std::span<const double>(&m_cv[j], 1));
        for (std::size_t k = 0; k < m_poly.size(); ++k) {
            const uint32_t a = m_poly[k];
            const uint32_t b = m_poly[(k + 1) % m_poly.size()];
            add_triangle(centre, flip ? b : a, flip ? a : b);
        }
        return true;
    }

    /// Adds a triangle unless two of its corners coincide (pole fans).
    void add_triangle(uint32_t a, uint32_t b, uint32_t c) {
        const auto& v = m_out.vertices;
        if (v[a] == v[b] || v[b] == v[c] || v[a] == v[c]) return;
        m_out.triangles.insert(m_out.triangles.end(), {a, b, c});
    }

    const Primitive& m_prim;
    const DiceControl& m_control;
    DicedSurface& m_out;
    DiceEstimate* m_estimate = nullptr; ///< set: faces are only estimated
    DiceEstimate m_face_estimate;       ///< the face being estimated
    const Face* m_face = nullptr;
    double m_rate = 1.0;
    double m_spacing = 0.0;
    Matrix4 m_matrix{1.0};
    glm::dmat3 m_linear{1.0};
    dvec3 m_translation{0.0};
    bool m_affine = true;
    glm::dmat3 m_cofactor{1.0};
    glm::dmat3 m_user_normal_matrix{1.0};
    double m_normal_sign = 1.0;
    bool m_grids = false;      ///< fill grids and parametric data
    bool m_displacing = false; ///< emit_displaced() at work
    uint64_t m_sequence = 0;   ///< displacement hook calls so far
    DisplaceGrid m_disp;
    struct Weld {
        dvec3 undisplaced, p, n;
    };
    std::vector<Weld> m_welds; ///< displaced degenerate points of the primitive
    std::vector<SurfacePoint> m_cell_eval, m_vert_eval;
    std::vector<dvec3> m_vert_n, m_cell_dp, m_cell_dn, m_tmp_p, m_tmp_n;
    // Scratch, reused from grid to grid.
    std::vector<glm::dvec2> m_st, m_vertex_st;
    std::vector<dvec3> m_values_s, m_values_t;
    std::vector<double> m_su, m_sv, m_vu, m_vv, m_gu, m_gv, m_cu, m_cv;
    std::vector<SurfacePoint> m_eval;
    std::vector<double> m_we; ///< wanted edge at each of m_wp
    std::vector<dvec3> m_wp, m_vert_p, m_vert_cross, m_cell_vector, m_values, m_user_n;
    std::vector<double> m_cell_area;
    std::vector<std::optional<dvec3>> m_cell_normal;
    std::vector<dvec3> m_cell_p;
    // Leaves of the face being diced, and their stitching.
    std::vector<Leaf> m_leaves;
    double m_planned = 0.0; ///< micropolygons the leaves will make
    std::vector<SideRef> m_hsides, m_vsides, m_after, m_before;
    std::vector<double> m_params, m_side_x;
    std::array<std::vector<int>, 4> m_side_cell;
    std::array<std::vector<uint32_t>, 4> m_side_vertex;
    std::vector<uint32_t> m_poly;
};

} // namespace

/// The dicer of one primitive: what ParametricDicer hides.
struct ParametricDicer::State {
    Dicer dicer;
};

ParametricDicer::ParametricDicer(const Primitive& prim, const DiceControl& control,
                                 DicedSurface& out, DiceEstimate* estimate)
    : m_state(new State{Dicer(prim, control, out, estimate)}) {}

ParametricDicer::~ParametricDicer() = default;

void ParametricDicer::dice(const Face& face) {
    m_state->dicer.dice(face);
}

} // namespace sss::detail
