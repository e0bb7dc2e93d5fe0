#include "sss/diffusion/diffusion.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>

#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/parallel_sort.h>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec4.hpp>
#include <glm/vector_relational.hpp>

#include "sss/util/error.h"
#include "sss/util/math.h"
#include "sss/util/name_table.h"
#include "sss/util/progress.h"

namespace sss {

namespace {

// The first name of a criterion is the one written; "prman" and "jensen" are
// accepted aliases.
constexpr NameTable<Criterion, 5> kCriterionNames({{
    {Criterion::Error, "error"},
    {Criterion::SolidAngleBox, "bbox"},
    {Criterion::SolidAngleBox, "prman"},
    {Criterion::SolidAngleCentroid, "centroid"},
    {Criterion::SolidAngleCentroid, "jensen"},
}});

} // namespace

bool parse_criterion(const char* name, Criterion& out) {
    std::optional<Criterion> c = kCriterionNames.parse(name);
    if (c) out = *c;
    return c.has_value();
}

const char* criterion_name(Criterion c) {
    return kCriterionNames.name(c);
}

namespace {

// A source disk is integrated (rather than taken as a point) when its radius
// exceeds kNearKappa times the distance softened by the profile's core length.
// 0.1 keeps a uniformly lit plane within 1 % of albedo x E from well-sampled
// down to spacings of 9 z_r (measured; docs/ptfilter.md).
constexpr double kNearKappa2 = 0.1;

// Quadrature over a disk: 4 Gauss-Legendre nodes in t = (rho'/rho)^2 (uniform
// in area) times 8 angles.
constexpr int kQuadRadial = 4, kQuadAngular = 8;
struct DiskRule {
    double radius[kQuadRadial]; // sqrt(t)
    double weight[kQuadRadial]; // sums to 1 (angular average folded in below)
    double cs[kQuadAngular], sn[kQuadAngular];
    DiskRule() {
        const double x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                             0.8611363115940526};
        const double w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                             0.3478548451374538};
        for (int i = 0; i < kQuadRadial; ++i) {
            radius[i] = std::sqrt(0.5 * (x[i] + 1.0));
            weight[i] = 0.5 * w[i] / kQuadAngular;
        }
        for (int k = 0; k < kQuadAngular; ++k) {
            double a = 2.0 * kPi * (k + 0.5) / kQuadAngular;
            cs[k] = std::cos(a);
            sn[k] = std::sin(a);
        }
    }
};
const DiskRule& disk_rule() {
    static const DiskRule rule;
    return rule;
}

// Orthonormal tangent frame of a source disk; for a zero normal, the disk
// faces the receiver.
void disk_frame(glm::dvec3 n, glm::dvec3 to_receiver, glm::dvec3& u, glm::dvec3& v) {
    double len = glm::length(n);
    if (len < 1e-12) {
        n = to_receiver;
        len = glm::length(n);
        if (len < 1e-300) n = {0, 0, 1}, len = 1;
    }
    n /= len;
    glm::dvec3 a = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    u = glm::normalize(glm::cross(n, a));
    v = glm::cross(n, u);
}

// Calls f(offset, weight) for each quadrature point of a disk of radius rho.
template <class F>
void for_disk_points(double rho, const glm::dvec3& u, const glm::dvec3& v, F&& f) {
    const DiskRule& rule = disk_rule();
    for (int i = 0; i < kQuadRadial; ++i)
        for (int k = 0; k < kQuadAngular; ++k)
            f(rho * rule.radius[i] * (rule.cs[k] * u + rule.sn[k] * v), rule.weight[i]);
}

// ---------------------------------------------------------------------------
// Profile tables in q = r^2. The index is read from the float bits of q, so
// entries are spaced 2^-kPerOctaveBits octaves apart (log-like spacing that
// resolves both the r -> 0 core and the exponential tail) and linear in q
// inside each interval.
constexpr int kPerOctaveBits = 5;
constexpr int kShift = 23 - kPerOctaveBits;
constexpr float kFracScale = 1.0f / float(1u << kShift);

struct TableEntry {
    float f, df, d2f, pad; // F(q), F'(q), F''(q)
};

struct ChannelTable {
    std::vector<TableEntry> entries;
    std::vector<float> error_bound; // G(q): bound on the quadrupole remainder
    std::vector<float> max_value;   // max_{q' >= q} F(q')
    std::vector<float> max_d1;      // max_{q' >= q} |F'(q')|
    std::vector<float> max_d2;      // max_{q' >= q} |F''(q')|
    float core2 = 0;                // core length squared
};

struct Tables {
    uint32_t bits0 = 0;
    uint32_t count = 0;
    std::vector<ChannelTable> channels;

    struct Lookup {
        uint32_t index;
        float frac;
        bool valid;
    };
    Lookup locate(float q) const {
        uint32_t b = std::bit_cast<uint32_t>(q);
        uint32_t off = b > bits0 ? b - bits0 : 0u;
        uint32_t idx = off >> kShift;
        return {idx, float(off & ((1u << kShift) - 1)) * kFracScale, idx + 1 < count};
    }
};

double q_of_bits(uint32_t bits) {
    return double(std::bit_cast<float>(bits));
}

Tables build_tables(const std::vector<Profile>& profiles) {
    Tables t;
    double lmin = std::numeric_limits<double>::infinity(), rmax = 0.0;
    for (const Profile& p : profiles) {
        if (p.total() <= 0.0) continue;
        double core = p.core_length() > 0.0 ? p.core_length() : 1e-2 / p.sigma_tr();
        lmin = std::min(lmin, core);
        rmax = std::max(rmax, p.cutoff_radius(1e-7));
    }
    if (!(rmax > 0.0) || !std::isfinite(lmin)) {
        lmin = 1.0;
        rmax = 1.0;
    }
    float q0 = float(std::max(1e-30, 1e-8 * lmin * lmin));
    t.bits0 = std::bit_cast<uint32_t>(q0);
    double qend = std::min(1e36, std::max(rmax * rmax, 4.0 * double(q0)));
    uint32_t bend = std::bit_cast<uint32_t>(float(qend));
    t.count = ((bend - t.bits0) >> kShift) + 3;
    t.channels.resize(profiles.size());
    for (std::size_t pi = 0; pi < profiles.size(); ++pi) {
        const Profile& p = profiles[pi];
        ChannelTable& ct = t.channels[pi];
        ct.entries.assign(t.count, TableEntry{0, 0, 0, 0});
        ct.error_bound.assign(t.count, 0.0f);
        ct.max_value.assign(t.count, 0.0f);
        ct.max_d1.assign(t.count, 0.0f);
        ct.max_d2.assign(t.count, 0.0f);
        ct.core2 = float(p.core_length() * p.core_length());
        if (p.total() <= 0.0) continue;
        double rcut = p.cutoff_radius(1e-7);
        auto F = [&](double q) { return p.eval(std::sqrt(std::max(q, 0.0))); };
        std::vector<double> g(t.count, 0.0);
        for (uint32_t k = 0; k + 1 < t.count; ++k) {
            double q = q_of_bits(t.bits0 + (k << kShift));
            if (std::sqrt(q) > rcut) break;
            double h = 2e-3 * q;
            double fm2 = F(q - 2 * h), fm = F(q - h), f0 = F(q), fp = F(q + h),
                   fp2 = F(q + 2 * h);
            double d1 = (fp - fm) / (2 * h);
            double d2 = (fp - 2 * f0 + fm) / (h * h);
            double d3 = (fp2 - 2 * fp + 2 * fm - fm2) / (2 * h * h * h);
            ct.entries[k] = {float(f0), float(d1), float(d2), 0.0f};
            double w = std::sqrt(q);
            // Third-order terms dropped by the quadrupole expansion of F(|w - delta|^2):
            // 2 |F''| |w| s^3 + (4/3) |F'''| |w|^3 s^3, per unit s^3 and power.
            g[k] = 2.0 * std::abs(d2) * w + (4.0 / 3.0) * std::abs(d3) * w * w * w;
        }
        // Running maxima from the far end make both bounds valid for every q' >= q.
        double gmax = 0.0, fmax = 0.0, d1max = 0.0, d2max = 0.0;
        for (uint32_t k = t.count; k-- > 0;) {
            gmax = std::max(gmax, g[k]);
            fmax = std::max(fmax, double(ct.entries[k].f));
            d1max = std::max(d1max, std::abs(double(ct.entries[k].df)));
            d2max = std::max(d2max, std::abs(double(ct.entries[k].d2f)));
            ct.error_bound[k] = float(std::min(gmax, 1e30));
            ct.max_value[k] = float(std::min(fmax, 1e30));
            ct.max_d1[k] = float(std::min(d1max, 1e30));
            ct.max_d2[k] = float(std::min(d2max, 1e30));
        }
    }
    return t;
}

// ---------------------------------------------------------------------------
// Octree over Morton-sorted points.
constexpr uint32_t kLeafSize = 8;
constexpr uint32_t kNone = 0xffffffffu;

struct Node {
    glm::vec3 lo, hi;
    uint32_t first = 0, count = 0;
    uint32_t child_first = kNone;
    uint32_t child_count = 0;
    uint32_t parent = kNone;
    float area = 0;
    float radius = 0;  // max |p - c|
    float max_rho = 0; // largest source disk radius
};

// Moments of a node about its centroid c, per colour channel.
struct Expansion {
    glm::vec3 c;
    float phi[3];
    float abs_phi[3];
    float d[3][3];   // sum A E (p - c)
    float q[3][6];   // sum A E (p - c)(p - c)^T: xx xy xz yy yz zz
    float d_norm[3]; // |d[ch]|
};

uint64_t spread_bits(uint64_t x) {
    x &= 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
}

struct Tree {
    std::vector<Node> nodes;
    std::vector<Expansion> expansions;
    std::vector<uint32_t> order; // sorted position -> original index
    // Sorted source data.
    std::vector<glm::vec4> pos_rho2;   // x y z rho^2
    std::vector<glm::vec4> power_area; // A E (rgb), A
    std::vector<glm::vec3> normal;
};

Tree build_tree(const DiffusionProblem& pb) {
    Tree tree;
    const std::size_t n = pb.positions.size();
    glm::dvec3 lo(std::numeric_limits<double>::max()),
        hi(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : pb.positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
    double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 1e-30});
    double scale = double((1u << 21) - 1) / extent;
    std::vector<std::pair<uint64_t, uint32_t>> keys(n);
    oneapi::tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
        glm::dvec3 g = (glm::dvec3(pb.positions[i]) - lo) * scale;
        uint64_t code = spread_bits(uint64_t(g.x)) | spread_bits(uint64_t(g.y)) << 1 |
                        spread_bits(uint64_t(g.z)) << 2;
        keys[i] = {code, uint32_t(i)};
    });
    // Unique (code, index) keys make the order independent of the thread count.
    oneapi::tbb::parallel_sort(keys.begin(), keys.end());
    tree.order.resize(n);
    for (std::size_t i = 0; i < n; ++i) tree.order[i] = keys[i].second;

    tree.pos_rho2.resize(n);
    tree.power_area.resize(n);
    tree.normal.resize(n);
    for (std::size_t s = 0; s < n; ++s) {
        uint32_t i = tree.order[s];
        float a = pb.areas[i];
        tree.pos_rho2[s] = glm::vec4(pb.positions[i], float(a / kPi));
        tree.power_area[s] = glm::vec4(pb.irradiance[i] * a, a);
        tree.normal[s] = pb.normals.empty() ? glm::vec3(0) : pb.normals[i];
    }

    // Breadth-first construction: children are appended contiguously after
    // their parents, so a reverse sweep is bottom-up. No recursion.
    tree.nodes.reserve(n / 2 + 8);
    Node root;
    root.first = 0;
    root.count = uint32_t(n);
    tree.nodes.push_back(root);
    for (std::size_t k = 0; k < tree.nodes.size(); ++k) {
        Node node = tree.nodes[k];
        if (node.count <= kLeafSize) continue;
        uint64_t a = keys[node.first].first, b = keys[node.first + node.count - 1].first;
        uint64_t diff = a ^ b;
        if (diff == 0) continue; // coincident at octree resolution: one big leaf
        int top = 63 - std::countl_zero(diff);
        int shift = (top / 3) * 3;
        uint32_t child_first = uint32_t(tree.nodes.size());
        uint32_t begin = node.first, end = node.first + node.count;
        uint32_t children = 0;
        for (uint32_t s = begin; s < end;) {
            uint64_t digit = (keys[s].first >> shift) & 7u;
            // Codes are sorted and share the bits above `shift`.
            auto it = std::upper_bound(
                keys.begin() + s, keys.begin() + end, digit,
                [shift](uint64_t d, const std::pair<uint64_t, uint32_t>& kv) {
                    return d < ((kv.first >> shift) & 7u);
                });
            uint32_t e = uint32_t(it - keys.begin());
            Node child;
            child.first = s;
            child.count = e - s;
            child.parent = uint32_t(k);
            tree.nodes.push_back(child);
            ++children;
            s = e;
        }
        tree.nodes[k].child_first = child_first;
        tree.nodes[k].child_count = children;
    }

    // Moments from each node's own points (N log N work, in parallel, exact
    // in double about the node centroid).
    tree.expansions.resize(tree.nodes.size());
    oneapi::tbb::parallel_for(std::size_t(0), tree.nodes.size(), [&](std::size_t k) {
        Node& node = tree.nodes[k];
        const uint32_t b = node.first, e = node.first + node.count;
        glm::dvec3 wsum_p(0), asum_p(0), psum(0);
        double wsum = 0, asum = 0;
        glm::dvec3 blo(std::numeric_limits<double>::max()),
            bhi(-std::numeric_limits<double>::max());
        float max_rho2 = 0;
        for (uint32_t s = b; s < e; ++s) {
            glm::dvec3 p(tree.pos_rho2[s]);
            const glm::vec4& pa = tree.power_area[s];
            // |power| weights keep the centroid inside the node even when
            // irradiance is negative or cancels.
            double w = std::abs(pa.x) + std::abs(pa.y) + std::abs(pa.z);
            wsum += w;
            wsum_p += w * p;
            asum += pa.w;
            asum_p += double(pa.w) * p;
            psum += p;
            blo = glm::min(blo, p);
            bhi = glm::max(bhi, p);
            max_rho2 = std::max(max_rho2, tree.pos_rho2[s].w);
        }
        glm::dvec3 c = wsum > 0   ? wsum_p / wsum
                       : asum > 0 ? asum_p / asum
                                  : psum / double(e - b);
        Expansion ex{};
        ex.c = glm::vec3(c);
        double phi[3] = {0, 0, 0}, aphi[3] = {0, 0, 0}, d[3][3] = {}, q[3][6] = {};
        double r2max = 0;
        for (uint32_t s = b; s < e; ++s) {
            glm::dvec3 dp = glm::dvec3(tree.pos_rho2[s]) - c;
            r2max = std::max(r2max, glm::dot(dp, dp));
            const glm::vec4& pa = tree.power_area[s];
            for (int ch = 0; ch < 3; ++ch) {
                double w = pa[ch];
                phi[ch] += w;
                aphi[ch] += std::abs(w);
                d[ch][0] += w * dp.x;
                d[ch][1] += w * dp.y;
                d[ch][2] += w * dp.z;
                q[ch][0] += w * dp.x * dp.x;
                q[ch][1] += w * dp.x * dp.y;
                q[ch][2] += w * dp.x * dp.z;
                q[ch][3] += w * dp.y * dp.y;
                q[ch][4] += w * dp.y * dp.z;
                q[ch][5] += w * dp.z * dp.z;
            }
        }
        for (int ch = 0; ch < 3; ++ch) {
            ex.phi[ch] = float(phi[ch]);
            ex.abs_phi[ch] = float(aphi[ch]);
            for (int i = 0; i < 3; ++i) ex.d[ch][i] = float(d[ch][i]);
            ex.d_norm[ch] = float(std::sqrt(d[ch][0] * d[ch][0] + d[ch][1] * d[ch][1] +
                                            d[ch][2] * d[ch][2]));
            for (int i = 0; i < 6; ++i) ex.q[ch][i] = float(q[ch][i]);
        }
        tree.expansions[k] = ex;
        node.lo = glm::vec3(blo);
        node.hi = glm::vec3(bhi);
        node.area = float(asum);
        node.radius = float(std::sqrt(r2max));
        node.max_rho = std::sqrt(max_rho2);
    });
    return tree;
}

float box_distance2(const glm::vec3& alo, const glm::vec3& ahi, const glm::vec3& blo,
                    const glm::vec3& bhi) {
    glm::vec3 gap = glm::max(glm::vec3(0.0f), glm::max(blo - ahi, alo - bhi));
    return glm::dot(gap, gap);
}

// ---------------------------------------------------------------------------
// Evaluation of one receiver against near sources.

struct ReceiverChannels {
    const ChannelTable* table[3];
    const Profile* profile[3];
    float near_core2; // smallest core^2 of the three channels
};

inline void lookup3(const Tables& tables, const ReceiverChannels& rc, float q,
                    float out[3]) {
    Tables::Lookup l = tables.locate(q);
    if (!l.valid) {
        out[0] = out[1] = out[2] = 0.0f;
        return;
    }
    for (int ch = 0; ch < 3; ++ch) {
        const TableEntry* e = rc.table[ch]->entries.data() + l.index;
        out[ch] = e[0].f + l.frac * (e[1].f - e[0].f);
    }
}

// The last coincident-source disk integral per channel (valid within one
// evaluation, where profiles do not move).
struct DiskMemo {
    const Profile* profile = nullptr;
    double rho = -1.0, value = 0.0;
};

// Contribution of sorted source s to receiver at x (never the receiver itself).
inline void near_source(const Tree& tree, const Tables& tables,
                        const ReceiverChannels& rc, const glm::vec3& x, uint32_t s,
                        double acc[3], DiffusionStats& st, DiskMemo memo[3]) {
    const glm::vec4& pr = tree.pos_rho2[s];
    const glm::vec4& pa = tree.power_area[s];
    glm::vec3 w = x - glm::vec3(pr);
    float q = glm::dot(w, w);
    if (pr.w > kNearKappa2 * (q + rc.near_core2)) {
        ++st.quadrature_terms;
        double rho = std::sqrt(double(pr.w));
        if (q == 0.0f) {
            // Coincident source: its disk is centred on the receiver. Coincident
            // points come in big leaves (O(n^2) pairs), usually of equal area:
            // the last disk value per channel is kept, so a pair costs a
            // multiply rather than a closed form with exponentials.
            for (int ch = 0; ch < 3; ++ch) {
                if (!(pa.w > 0)) continue;
                DiskMemo& m = memo[ch];
                if (m.profile != rc.profile[ch] || m.rho != rho)
                    m = {rc.profile[ch], rho, rc.profile[ch]->disk(rho)};
                acc[ch] += pa[ch] / pa.w * m.value;
            }
            return;
        }
        glm::dvec3 u, v;
        disk_frame(glm::dvec3(tree.normal[s]), glm::dvec3(w), u, v);
        double sum[3] = {0, 0, 0};
        for_disk_points(rho, u, v, [&](const glm::dvec3& off, double wt) {
            glm::vec3 d = w - glm::vec3(off);
            float f[3];
            lookup3(tables, rc, glm::dot(d, d), f);
            for (int ch = 0; ch < 3; ++ch) sum[ch] += wt * f[ch];
        });
        for (int ch = 0; ch < 3; ++ch) acc[ch] += sum[ch] * pa[ch];
        return;
    }
    ++st.near_terms;
    float f[3];
    lookup3(tables, rc, q, f);
    for (int ch = 0; ch < 3; ++ch) acc[ch] += double(f[ch] * pa[ch]);
}

// Far-field term of a node for a receiver at x.
inline void far_node(const Tables& tables, const ReceiverChannels& rc,
                     const Expansion& ex, const glm::vec3& x, bool quadrupole,
                     double acc[3]) {
    glm::vec3 w = x - ex.c;
    float q = glm::dot(w, w);
    Tables::Lookup l = tables.locate(q);
    if (!l.valid) return;
    for (int ch = 0; ch < 3; ++ch) {
        const TableEntry* e = rc.table[ch]->entries.data() + l.index;
        float f = e[0].f + l.frac * (e[1].f - e[0].f);
        float val = ex.phi[ch] * f;
        if (quadrupole) {
            float df = e[0].df + l.frac * (e[1].df - e[0].df);
            float d2f = e[0].d2f + l.frac * (e[1].d2f - e[0].d2f);
            const float* Q = ex.q[ch];
            const float* D = ex.d[ch];
            float tr = Q[0] + Q[3] + Q[5];
            float wd = w.x * D[0] + w.y * D[1] + w.z * D[2];
            float wqw = w.x * (Q[0] * w.x + 2.0f * (Q[1] * w.y + Q[2] * w.z)) +
                        w.y * (Q[3] * w.y + 2.0f * Q[4] * w.z) + w.z * Q[5] * w.z;
            // Taylor expansion of F(|w - delta|^2) to second order in delta.
            val += df * (tr - 2.0f * wd) + 2.0f * d2f * wqw;
        }
        acc[ch] += double(val);
    }
}

// Receivers of one bucket in structure-of-arrays form, so the loops over
// receivers vectorise (one source or node against all receivers at once).
constexpr uint32_t kMaxBucket = 64;
struct BucketBlock {
    uint32_t count = 0;
    alignas(64) float x[kMaxBucket], y[kMaxBucket], z[kMaxBucket];
    alignas(64) int32_t sorted[kMaxBucket];
    alignas(64) float acc[3][kMaxBucket];
};

// Adds the far-field terms of node expansions to every receiver of the
// block; all receivers share the channel tables t[0..2].
template <bool Quadrupole>
void block_far(const Tables& tables, const TableEntry* const t[3], const Expansion& ex,
               BucketBlock& b) {
    const int32_t bits0 = int32_t(tables.bits0), last = int32_t(tables.count) - 1;
    const float cx = ex.c.x, cy = ex.c.y, cz = ex.c.z;
    for (int ch = 0; ch < 3; ++ch) {
        const TableEntry* T = t[ch];
        const float phi = ex.phi[ch];
        const float* Q = ex.q[ch];
        const float* D = ex.d[ch];
        const float tr = Q[0] + Q[3] + Q[5];
        const float q0 = Q[0], q1 = 2.0f * Q[1], q2 = 2.0f * Q[2], q3 = Q[3],
                    q4 = 2.0f * Q[4], q5 = Q[5];
        const float d0 = D[0], d1 = D[1], d2 = D[2];
        float* acc = b.acc[ch];
        const int32_t n = int32_t(b.count);
#pragma GCC ivdep
        for (int32_t r = 0; r < n; ++r) {
            float wx = b.x[r] - cx, wy = b.y[r] - cy, wz = b.z[r] - cz;
            float q = wx * wx + wy * wy + wz * wz;
            // q >= 0, so its bits order like the value (branch-free for SIMD).
            int32_t off = std::max(std::bit_cast<int32_t>(q) - bits0, 0);
            int32_t idx = std::min(off >> kShift, last);
            float frac = float(off & ((1 << kShift) - 1)) * kFracScale;
            float keep = idx < last ? 1.0f : 0.0f;
            idx = std::min(idx, last - 1);
            float f = T[idx].f + frac * (T[idx + 1].f - T[idx].f);
            float val = phi * f;
            if constexpr (Quadrupole) {
                float df = T[idx].df + frac * (T[idx + 1].df - T[idx].df);
                float d2f = T[idx].d2f + frac * (T[idx + 1].d2f - T[idx].d2f);
                float wd = wx * d0 + wy * d1 + wz * d2;
                float wqw = wx * (q0 * wx + q1 * wy + q2 * wz) +
                            wy * (q3 * wy + q4 * wz) + q5 * wz * wz;
                val += df * (tr - 2.0f * wd) + 2.0f * d2f * wqw;
            }
            acc[r] += keep * val;
        }
    }
}

// Adds point sources [first, first + count) to every receiver of the block,
// skipping each receiver's own point. Only called when no pair needs the
// disk quadrature.
void block_near(const Tables& tables, const TableEntry* const t[3], const Tree& tree,
                uint32_t first, uint32_t count, BucketBlock& b) {
    const int32_t bits0 = int32_t(tables.bits0), last = int32_t(tables.count) - 1;
    const int32_t n = int32_t(b.count);
    for (uint32_t j = first; j < first + count; ++j) {
        const glm::vec4 p = tree.pos_rho2[j];
        const glm::vec4 pa = tree.power_area[j];
        const TableEntry* T0 = t[0];
        const TableEntry* T1 = t[1];
        const TableEntry* T2 = t[2];
        float* a0 = b.acc[0];
        float* a1 = b.acc[1];
        float* a2 = b.acc[2];
        const float px = p.x, py = p.y, pz = p.z, e0 = pa.x, e1 = pa.y, e2 = pa.z;
        const int32_t self = int32_t(j);
#pragma GCC ivdep
        for (int32_t r = 0; r < n; ++r) {
            float wx = b.x[r] - px, wy = b.y[r] - py, wz = b.z[r] - pz;
            float q = wx * wx + wy * wy + wz * wz;
            int32_t off = std::max(std::bit_cast<int32_t>(q) - bits0, 0);
            int32_t idx = std::min(off >> kShift, last);
            float frac = float(off & ((1 << kShift) - 1)) * kFracScale;
            float keep = (idx < last && b.sorted[r] != self) ? 1.0f : 0.0f;
            idx = std::min(idx, last - 1);
            float f0 = T0[idx].f + frac * (T0[idx + 1].f - T0[idx].f);
            float f1 = T1[idx].f + frac * (T1[idx + 1].f - T1[idx].f);
            float f2 = T2[idx].f + frac * (T2[idx + 1].f - T2[idx].f);
            a0[r] += keep * f0 * e0;
            a1[r] += keep * f1 * e1;
            a2[r] += keep * f2 * e2;
        }
    }
}

} // namespace

std::vector<glm::vec3> evaluate_diffusion(const DiffusionProblem& pb,
                                          const DiffusionOptions& options,
                                          DiffusionStats* stats_out) {
    const std::size_t n = pb.positions.size();
    std::vector<glm::vec3> result(n, glm::vec3(0.0f));
    if (n == 0) return result;
    if (pb.profiles.size() < 3 && pb.profile_index.empty())
        throw ValueError("diffusion needs three channel profiles");
    Stopwatch watch;
    DiffusionStats stats;
    Tables tables = build_tables(pb.profiles);
    Tree tree = build_tree(pb);
    stats.nodes = tree.nodes.size();
    stats.build_seconds = watch.seconds();

    auto receiver_channels = [&](uint32_t original) {
        ReceiverChannels rc;
        glm::u32vec3 idx =
            pb.profile_index.empty() ? glm::u32vec3(0, 1, 2) : pb.profile_index[original];
        float core2 = std::numeric_limits<float>::max();
        for (int ch = 0; ch < 3; ++ch) {
            rc.table[ch] = &tables.channels[idx[ch]];
            rc.profile[ch] = &pb.profiles[idx[ch]];
            core2 = std::min(core2, rc.table[ch]->core2);
        }
        rc.near_core2 = core2;
        return rc;
    };

    // Receiver buckets: maximal nodes of at most kMaxBucket points share one
    // traversal. The classic criteria are per receiver, as PRMan does.
    const bool classic = options.criterion != Criterion::Error;
    std::vector<uint32_t> buckets; // node index
    {
        std::vector<uint32_t> stack{0};
        while (!stack.empty()) {
            uint32_t k = stack.back();
            stack.pop_back();
            const Node& node = tree.nodes[k];
            if (node.count <= kMaxBucket || node.child_count == 0) {
                buckets.push_back(k);
                continue;
            }
            for (uint32_t c = node.child_count; c-- > 0;)
                stack.push_back(node.child_first + c);
        }
    }

    // Reference magnitude for the error tolerance: the local mean |E| over a
    // region about one diffusion length wide (with a floor at a fraction of the
    // global mean, so dark regions do not demand unbounded work).
    double global_abs[3] = {0, 0, 0};
    for (int ch = 0; ch < 3; ++ch)
        global_abs[ch] = tree.nodes[0].area > 0
                             ? tree.expansions[0].abs_phi[ch] / tree.nodes[0].area
                             : 0.0;
    double region = 0.0;
    for (const Profile& p : pb.profiles)
        if (p.total() > 0)
            region = std::max(region, std::min(p.dmfp(), p.cutoff_radius(1e-3)));
    // Calibrated so that the default (1) gives well under 1 % RMS error on
    // smooth lit objects (docs/ptfilter.md has the measured table).
    const double tau = 4e-3 * options.max_solid_angle;
    // The tolerance scales with albedo x E, what a large, well-sampled surface
    // returns. A cloud can return far less: when the whole object is small
    // against the profile (at most disk(sqrt(total area / pi)), the profile's
    // share inside a disk of the cloud's area) or when the areas cover only a
    // fraction of the surface the points span (tiny areas). Without these
    // bounds every node was dropped as negligible there (100 % error).
    std::vector<double> reach(pb.profiles.size());
    const double rho_all = std::sqrt(double(tree.nodes[0].area) / kPi);
    for (std::size_t k = 0; k < pb.profiles.size(); ++k)
        reach[k] = pb.profiles[k].disk(rho_all);
    const double eps = options.max_solid_angle;

    std::atomic<std::size_t> done{0};
    std::atomic<std::size_t> far_total{0}, near_total{0}, quad_total{0};
    oneapi::tbb::parallel_for(
        oneapi::tbb::blocked_range<std::size_t>(0, buckets.size(), 1),
        [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
            std::vector<uint32_t> far_list, mono_list, near_list, stack;
            auto block_ptr = std::make_unique<BucketBlock>();
            BucketBlock& block = *block_ptr;
            DiffusionStats local;
            DiskMemo memo[3];
            struct {
                uint32_t node = kNone;
                const ChannelTable* table[3] = {nullptr, nullptr, nullptr};
                double sum[3] = {0, 0, 0};
            } coincident;
            for (std::size_t bi = range.begin(); bi != range.end(); ++bi) {
                const Node& bucket = tree.nodes[buckets[bi]];
                // Channels of the bucket's receivers (distinct tables).
                ReceiverChannels first_rc = receiver_channels(tree.order[bucket.first]);
                std::vector<const ChannelTable*> bucket_tables[3];
                std::vector<double> bucket_totals[3], bucket_reach[3];
                for (uint32_t s = bucket.first; s < bucket.first + bucket.count; ++s) {
                    ReceiverChannels rc = pb.profile_index.empty()
                                              ? first_rc
                                              : receiver_channels(tree.order[s]);
                    for (int ch = 0; ch < 3; ++ch) {
                        auto& v = bucket_tables[ch];
                        if (std::find(v.begin(), v.end(), rc.table[ch]) == v.end()) {
                            v.push_back(rc.table[ch]);
                            bucket_totals[ch].push_back(rc.profile[ch]->total());
                            bucket_reach[ch].push_back(
                                reach[std::size_t(rc.profile[ch] - pb.profiles.data())]);
                        }
                    }
                    if (pb.profile_index.empty()) break;
                }
                // Local reference level.
                uint32_t up = buckets[bi];
                while (tree.nodes[up].parent != kNone) {
                    const Node& nd = tree.nodes[up];
                    if (glm::length(nd.hi - nd.lo) >= 2.0 * region) break;
                    up = nd.parent;
                }
                // Area density of the region: its points' areas against a quarter
                // of its squared diagonal (>= 1 for any surface patch that the
                // points sample: a flat square patch gives 2).
                double diag = glm::length(tree.nodes[up].hi - tree.nodes[up].lo);
                double density =
                    diag > 0 ? std::min(1.0, 4.0 * tree.nodes[up].area / (diag * diag))
                             : 1.0;
                double tol[3], skip[3];
                for (int ch = 0; ch < 3; ++ch) {
                    double level =
                        tree.nodes[up].area > 0
                            ? tree.expansions[up].abs_phi[ch] / tree.nodes[up].area
                            : 0.0;
                    level = std::max(level, 0.05 * global_abs[ch]);
                    double tot = *std::min_element(bucket_totals[ch].begin(),
                                                   bucket_totals[ch].end());
                    double reach_min = *std::min_element(bucket_reach[ch].begin(),
                                                         bucket_reach[ch].end());
                    tol[ch] = tau * std::min(tot * density, reach_min) * level;
                    skip[ch] = 0.05 * tol[ch];
                }

                // Builds the far and near lists for receivers inside [blo, bhi].
                auto traverse = [&](const glm::vec3& blo, const glm::vec3& bhi) {
                    far_list.clear();
                    mono_list.clear();
                    near_list.clear();
                    stack.clear();
                    stack.push_back(0);
                    while (!stack.empty()) {
                        uint32_t k = stack.back();
                        stack.pop_back();
                        const Node& node = tree.nodes[k];
                        const Expansion& ex = tree.expansions[k];
                        bool accept = false, drop = false;
                        if (!classic) {
                            float d2 = box_distance2(blo, bhi, node.lo, node.hi);
                            float r = node.radius;
                            // Single points are exact as near terms; the expansion
                            // needs the receivers well outside the node.
                            if (node.count > 1 && d2 > 2.25f * r * r) {
                                Tables::Lookup l = tables.locate(d2);
                                accept = drop = true;
                                bool mono = true;
                                // Farthest receiver from the centroid bounds |w|.
                                glm::vec3 far_corner =
                                    glm::max(glm::abs(blo - ex.c), glm::abs(bhi - ex.c));
                                double wmax = glm::length(far_corner);
                                if (l.valid) {
                                    for (int ch = 0; ch < 3; ++ch) {
                                        for (const ChannelTable* ct : bucket_tables[ch]) {
                                            double ap = ex.abs_phi[ch];
                                            uint32_t i = l.index;
                                            if (ap * r * r * r * ct->error_bound[i] >
                                                tol[ch])
                                                accept = false;
                                            if (ap * ct->max_value[i] > skip[ch])
                                                drop = false;
                                            // Error of dropping the dipole and
                                            // quadrupole terms.
                                            double m2 = ap * r * r;
                                            double mono_err =
                                                ct->max_d1[i] *
                                                    (m2 + 2.0 * wmax * ex.d_norm[ch]) +
                                                2.0 * ct->max_d2[i] * wmax * wmax * m2;
                                            if (mono_err > 0.1 * tol[ch]) mono = false;
                                        }
                                    }
                                }
                                if (accept && !drop && mono) {
                                    mono_list.push_back(k);
                                    continue;
                                }
                            }
                        } else if (options.criterion == Criterion::SolidAngleBox) {
                            glm::vec3 g(node.max_rho);
                            float d2 = box_distance2(blo, bhi, node.lo - g, node.hi + g);
                            accept = d2 > 0.0f && node.area <= eps * d2;
                        } else {
                            bool inside = glm::all(glm::greaterThanEqual(blo, node.lo)) &&
                                          glm::all(glm::lessThanEqual(blo, node.hi));
                            glm::vec3 w = blo - ex.c;
                            accept = !inside && node.area < eps * glm::dot(w, w);
                        }
                        if (drop) continue;
                        if (accept) {
                            far_list.push_back(k);
                        } else if (node.child_count == 0) {
                            near_list.push_back(k);
                        } else {
                            for (uint32_t c = node.child_count; c-- > 0;)
                                stack.push_back(node.child_first + c);
                        }
                    }
                };
                if (!classic) traverse(bucket.lo, bucket.hi);

                // Evaluation. Buckets of one material use the vectorised block
                // loops; mixed materials and the classic criteria go receiver by
                // receiver.
                bool uniform = !classic && bucket.count <= kMaxBucket &&
                               bucket_tables[0].size() == 1 &&
                               bucket_tables[1].size() == 1 &&
                               bucket_tables[2].size() == 1;
                if (uniform) {
                    block.count = bucket.count;
                    for (uint32_t r = 0; r < bucket.count; ++r) {
                        const glm::vec4& pr = tree.pos_rho2[bucket.first + r];
                        block.x[r] = pr.x;
                        block.y[r] = pr.y;
                        block.z[r] = pr.z;
                        block.sorted[r] = int32_t(bucket.first + r);
                        for (int ch = 0; ch < 3; ++ch) block.acc[ch][r] = 0.0f;
                    }
                    const TableEntry* t[3] = {first_rc.table[0]->entries.data(),
                                              first_rc.table[1]->entries.data(),
                                              first_rc.table[2]->entries.data()};
                    for (uint32_t k : far_list)
                        block_far<true>(tables, t, tree.expansions[k], block);
                    for (uint32_t k : mono_list)
                        block_far<false>(tables, t, tree.expansions[k], block);
                    std::size_t plain = 0;
                    for (uint32_t k : near_list) {
                        const Node& leaf = tree.nodes[k];
                        float d2 = box_distance2(bucket.lo, bucket.hi, leaf.lo, leaf.hi);
                        if (leaf.max_rho * leaf.max_rho <=
                            kNearKappa2 * (d2 + first_rc.near_core2)) {
                            block_near(tables, t, tree, leaf.first, leaf.count, block);
                            plain += leaf.count;
                            continue;
                        }
                        // Close, large source disks: per pair, with quadrature where
                        // needed.
                        for (uint32_t r = 0; r < bucket.count; ++r) {
                            uint32_t s = bucket.first + r;
                            glm::vec3 x(block.x[r], block.y[r], block.z[r]);
                            double acc[3] = {0, 0, 0};
                            for (uint32_t j = leaf.first; j < leaf.first + leaf.count;
                                 ++j)
                                if (j != s)
                                    near_source(tree, tables, first_rc, x, j, acc, local,
                                                memo);
                            for (int ch = 0; ch < 3; ++ch)
                                block.acc[ch][r] += float(acc[ch]);
                        }
                    }
                    local.near_terms += plain * bucket.count;
                    local.far_terms +=
                        (far_list.size() + mono_list.size()) * bucket.count;
                    for (uint32_t r = 0; r < bucket.count; ++r) {
                        uint32_t s = bucket.first + r;
                        uint32_t original = tree.order[s];
                        double rho = std::sqrt(double(tree.pos_rho2[s].w));
                        for (int ch = 0; ch < 3; ++ch) {
                            // Self term: the receiver's own disk, integrated exactly.
                            double v = double(block.acc[ch][r]) +
                                       double(pb.irradiance[original][ch]) *
                                           first_rc.profile[ch]->disk(rho);
                            result[original][ch] = std::isfinite(v) ? float(v) : 0.0f;
                        }
                    }
                } else {
                    for (uint32_t s = bucket.first; s < bucket.first + bucket.count;
                         ++s) {
                        uint32_t original = tree.order[s];
                        ReceiverChannels rc = pb.profile_index.empty()
                                                  ? first_rc
                                                  : receiver_channels(original);
                        glm::vec3 x(tree.pos_rho2[s]);
                        if (classic) traverse(x, x); // PRMan and J&B walk per receiver
                        double acc[3];
                        double rho = std::sqrt(double(tree.pos_rho2[s].w));
                        for (int ch = 0; ch < 3; ++ch)
                            acc[ch] = double(pb.irradiance[original][ch]) *
                                      rc.profile[ch]->disk(rho);
                        for (uint32_t k : far_list)
                            far_node(tables, rc, tree.expansions[k], x, !classic, acc);
                        for (uint32_t k : mono_list)
                            far_node(tables, rc, tree.expansions[k], x, false, acc);
                        for (uint32_t k : near_list) {
                            const Node& leaf = tree.nodes[k];
                            if (leaf.count > kLeafSize && leaf.lo == leaf.hi &&
                                x == leaf.lo) {
                                // Identical points (one big leaf): the leaf's sum is
                                // the same for every receiver there, so it is
                                // formed once per material and each receiver
                                // subtracts its own term (O(n), not O(n^2)).
                                if (coincident.node != k ||
                                    !std::equal(rc.table, rc.table + 3,
                                                coincident.table)) {
                                    coincident.node = k;
                                    std::copy(rc.table, rc.table + 3, coincident.table);
                                    std::fill(coincident.sum, coincident.sum + 3, 0.0);
                                    for (uint32_t j = leaf.first;
                                         j < leaf.first + leaf.count; ++j)
                                        near_source(tree, tables, rc, x, j,
                                                    coincident.sum, local, memo);
                                }
                                double own[3] = {0, 0, 0};
                                if (s >= leaf.first && s < leaf.first + leaf.count)
                                    near_source(tree, tables, rc, x, s, own, local, memo);
                                for (int ch = 0; ch < 3; ++ch)
                                    acc[ch] += coincident.sum[ch] - own[ch];
                                continue;
                            }
                            for (uint32_t j = leaf.first; j < leaf.first + leaf.count;
                                 ++j)
                                if (j != s)
                                    near_source(tree, tables, rc, x, j, acc, local, memo);
                        }
                        local.far_terms += far_list.size() + mono_list.size();
                        for (int ch = 0; ch < 3; ++ch) {
                            double v = acc[ch];
                            result[original][ch] = std::isfinite(v) ? float(v) : 0.0f;
                        }
                    }
                }
                std::size_t now = done.fetch_add(bucket.count) + bucket.count;
                if (options.progress) options.progress->update(now, n);
            }
            far_total += local.far_terms;
            near_total += local.near_terms;
            quad_total += local.quadrature_terms;
        });
    stats.far_terms = far_total;
    stats.near_terms = near_total;
    stats.quadrature_terms = quad_total;
    stats.eval_seconds = watch.seconds() - stats.build_seconds;
    if (stats_out) *stats_out = stats;
    return result;
}

std::vector<glm::dvec3>
evaluate_diffusion_exact(const DiffusionProblem& pb,
                         const std::vector<std::size_t>& receivers, Progress* progress) {
    const std::size_t n = pb.positions.size();
    std::vector<std::size_t> rec = receivers;
    if (rec.empty()) {
        rec.resize(n);
        for (std::size_t i = 0; i < n; ++i) rec[i] = i;
    }
    std::vector<glm::dvec3> out(rec.size(), glm::dvec3(0.0));
    std::atomic<std::size_t> done{0};
    oneapi::tbb::parallel_for(std::size_t(0), rec.size(), [&](std::size_t r) {
        const std::size_t i = rec[r];
        glm::u32vec3 idx =
            pb.profile_index.empty() ? glm::u32vec3(0, 1, 2) : pb.profile_index[i];
        const Profile* prof[3] = {&pb.profiles[idx[0]], &pb.profiles[idx[1]],
                                  &pb.profiles[idx[2]]};
        double core2 = std::numeric_limits<double>::max();
        for (int ch = 0; ch < 3; ++ch)
            core2 = std::min(core2, prof[ch]->core_length() * prof[ch]->core_length());
        glm::dvec3 x(pb.positions[i]);
        double acc[3] = {0, 0, 0};
        // Coincident sources usually share their area: keep the last disk.
        double memo_rho = -1.0, memo_disk[3] = {0, 0, 0};
        for (std::size_t j = 0; j < n; ++j) {
            double a = pb.areas[j];
            glm::dvec3 e(pb.irradiance[j]);
            double rho = std::sqrt(a / kPi);
            glm::dvec3 w = x - glm::dvec3(pb.positions[j]);
            double q = glm::dot(w, w);
            if (j == i || q == 0.0) {
                if (rho != memo_rho) {
                    memo_rho = rho;
                    for (int ch = 0; ch < 3; ++ch) memo_disk[ch] = prof[ch]->disk(rho);
                }
                for (int ch = 0; ch < 3; ++ch) acc[ch] += e[ch] * memo_disk[ch];
                continue;
            }
            // Same rule as the hierarchical path (in float there).
            if (float(a / kPi) > float(kNearKappa2 * (q + core2))) {
                glm::dvec3 u, v;
                glm::dvec3 nj =
                    pb.normals.empty() ? glm::dvec3(0) : glm::dvec3(pb.normals[j]);
                disk_frame(nj, w, u, v);
                double sum[3] = {0, 0, 0};
                for_disk_points(rho, u, v, [&](const glm::dvec3& off, double wt) {
                    double r = glm::length(w - off);
                    for (int ch = 0; ch < 3; ++ch) sum[ch] += wt * prof[ch]->eval(r);
                });
                for (int ch = 0; ch < 3; ++ch) acc[ch] += sum[ch] * a * e[ch];
                continue;
            }
            double r = std::sqrt(q);
            for (int ch = 0; ch < 3; ++ch) acc[ch] += prof[ch]->eval(r) * a * e[ch];
        }
        out[r] = glm::dvec3(acc[0], acc[1], acc[2]);
        if (progress) progress->update(done.fetch_add(1) + 1, rec.size());
    });
    return out;
}

} // namespace sss
