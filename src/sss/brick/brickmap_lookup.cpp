// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file brickmap_lookup.cpp
/// BrickMap: opens a .bkm file (header and node tables validated at once),
/// loads bricks on demand into a bounded cache and answers texture3d-style
/// lookups.
///
/// Bricks in memory keep only their present samples, as in the file (about a
/// quarter of all 512 for surface data), with the presence bits and per-word
/// ranks in front: one block per brick. A lookup finds its 8 corners' values
/// by rank, without branches on which are present. Only the first load of a
/// brick pays for reading, checking (CRC-32, mask, finite values) and
/// unpacking it.
///
/// Cache: one atomic pointer per data brick. A lookup that finds its bricks
/// loaded takes no lock and allocates nothing; it only "pins" itself (two
/// atomic adds on a counter mostly private to its thread) so that a brick
/// another thread evicts meanwhile is not freed under it. Eviction (least
/// recently used, by a stamp next to each brick's pointer) unlinks bricks at
/// once and frees them after a grace period: epoch-based reclamation with
/// two parities. Misses read the brick with pread outside the lock and
/// install it under a mutex. Memory: live bricks stay within the budget (plus the
/// brick being installed) and bricks awaiting their grace period within
/// about another budget; past that, misses are served from a private copy
/// that is not cached.

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <new>
#include <string>
#include <vector>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "brickmap_format.h"
#include "sss/brick/brickmap.h"
#include "sss/util/byte_io.h"
#include "sss/util/error.h"

namespace sss {

namespace {

using namespace detail;

constexpr double kCos55 = 0.57357643635104609611; // trees within 55 degrees of n
constexpr int kStripes = 64;
constexpr int kCoordBits = kBkmMaxDepth; // node coordinates at the deepest depth

/// Readers pinned in each epoch parity. A thread always uses the same stripe,
/// so with fewer than kStripes threads the counters are never shared.
struct alignas(64) PinStripe {
    std::atomic<uint64_t> count[2] = {0, 0};
};

std::atomic<unsigned> g_next_stripe{0};

unsigned thread_stripe() {
    thread_local const unsigned stripe =
        g_next_stripe.fetch_add(1, std::memory_order_relaxed) % kStripes;
    return stripe;
}

/// A brick in memory: one cache-line aligned block holding this header,
/// then the present samples only (data_size floats each, in sample index
/// order, as in the file) and one sample of zeros. Packed, a map's bricks
/// take about a quarter of the memory of all 512 samples (surface data fills
/// few of them), so more of them stay in the processor's caches, and a
/// lookup's loads of the presence bits and of the samples depend only on the
/// brick's address and go to memory together.
struct alignas(64) CachedBrick {
    /// Presence bits: bit s % 64 of word s / 64; byte j + 8 k is the row of
    /// samples (0..7, j, k).
    uint64_t mask[8] = {};
    /// Present samples before word w: sample s's values are at index
    /// rank[s / 64] + (present samples before s in its word).
    uint16_t rank[8] = {};
    uint32_t id = 0;
    uint32_t count = 0;    ///< present samples
    std::size_t bytes = 0; ///< of the whole block

    float* data() { return reinterpret_cast<float*>(this + 1); }
    const float* data() const { return reinterpret_cast<const float*>(this + 1); }

    /// A block for count present samples of data_size floats, its last
    /// sample zeroed.
    static CachedBrick* create(uint32_t count, int data_size) {
        const std::size_t floats = (std::size_t(count) + 1) * std::size_t(data_size);
        const std::size_t bytes = sizeof(CachedBrick) + floats * sizeof(float);
        void* raw = ::operator new(bytes, std::align_val_t(alignof(CachedBrick)));
        CachedBrick* b = new (raw) CachedBrick;
        b->count = count;
        b->bytes = bytes;
        std::fill(b->data() + floats - data_size, b->data() + floats, 0.0f);
        return b;
    }
    static void destroy(CachedBrick* b) {
        if (!b) return;
        b->~CachedBrick();
        ::operator delete(static_cast<void*>(b), std::align_val_t(alignof(CachedBrick)));
    }
};

struct CachedBrickDeleter {
    void operator()(CachedBrick* b) const { CachedBrick::destroy(b); }
};
using CachedBrickPtr = std::unique_ptr<CachedBrick, CachedBrickDeleter>;

/// A data brick's cache slot: the brick when it is loaded, and its last use
/// (for LRU eviction) next to it, so that a hit touches one line.
struct BrickSlot {
    std::atomic<CachedBrick*> brick{nullptr};
    std::atomic<uint64_t> stamp{0};
};

/// A data node, for descending: children with data only. Its brick id is
/// the tree's first brick id plus its index in the tree's array.
struct LookupNode {
    uint32_t first_child = 0; ///< index of the first data child in the tree's array
    uint8_t child_mask = 0;
};

/// The top depths of a tree are looked up in tables (8^d entries at depth
/// d, by Morton code of the node) instead of descended node by node: their
/// loads do not wait for each other.
constexpr int kTableDepth = 4;
constexpr uint32_t kNoNode = 0xffffffffu;

/// A tree's data nodes for lookups.
struct LookupTree {
    std::vector<LookupNode> nodes; ///< breadth first, as in the file
    int table_depth = 0;           ///< tables for depths 1..table_depth
    /// Node index (or kNoNode) by Morton code, depth d's table at
    /// table_offset(d).
    std::vector<uint32_t> tables;

    static std::size_t table_offset(int d) { return kOffsets[d]; }
    /// 8 + 64 + ... + 8^(d - 1).
    static constexpr std::array<std::size_t, kTableDepth + 2> kOffsets = [] {
        std::array<std::size_t, kTableDepth + 2> o{};
        for (int d = 2; d < kTableDepth + 2; ++d)
            o[d] = o[d - 1] + (std::size_t(1) << (3 * (d - 1)));
        return o;
    }();
};

/// Bits 0..3 of i spread to bits 0, 3, 6, 9 (Morton codes of the top depths).
constexpr std::array<uint32_t, 16> kSpread4 = [] {
    std::array<uint32_t, 16> t{};
    for (uint32_t i = 0; i < 16; ++i)
        t[i] = (i & 1) | ((i & 2) << 2) | ((i & 4) << 4) | ((i & 8) << 6);
    return t;
}();
static_assert(kTableDepth == 4, "kSpread4 spreads kTableDepth bits");

/// Set bits of a byte, by table: std::popcount is a library call in a
/// baseline x86-64 build (no POPCNT instruction).
constexpr std::array<uint8_t, 256> kPopcount8 = [] {
    std::array<uint8_t, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = static_cast<uint8_t>(std::popcount(unsigned(i)));
    return t;
}();

/// Set bits of a word: the POPCNT instruction where the build has it, else
/// a few shifts and adds (not a library call).
inline unsigned popcount64(uint64_t x) {
#ifdef __POPCNT__
    return static_cast<unsigned>(std::popcount(x));
#else
    x = x - ((x >> 1) & 0x5555555555555555ull);
    x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
    x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0full;
    return static_cast<unsigned>((x * 0x0101010101010101ull) >> 56);
#endif
}

/// Index of a node in a full node table, found by descending from the root;
/// -1 if absent.
int64_t find_node(const std::vector<BkmNode>& nodes, int depth, uint32_t ix, uint32_t iy,
                  uint32_t iz) {
    if (nodes.empty() || depth < 0 || depth > kBkmMaxDepth) return -1;
    const uint64_t limit = uint64_t(1) << depth;
    if (ix >= limit || iy >= limit || iz >= limit) return -1;
    std::size_t i = 0;
    for (int d = 1; d <= depth; ++d) {
        const int shift = depth - d;
        const int o =
            ((ix >> shift) & 1) | (((iy >> shift) & 1) << 1) | (((iz >> shift) & 1) << 2);
        const BkmNode& n = nodes[i];
        if (!((n.child_mask >> o) & 1)) return -1;
        i = n.first_child + std::popcount(unsigned(n.child_mask) & ((1u << o) - 1));
    }
    return static_cast<int64_t>(i);
}

/// Trees to try for a lookup with normal n, into order; returns how many:
/// the tree of n's dominant axis, the others whose axis is within 55 degrees
/// of n (closest first), then the no-normal tree.
int tree_order(const glm::vec3& n, bool ignore_normals, int order[4]) {
    int count = 0;
    const double nx = n.x, ny = n.y, nz = n.z;
    const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
    if (!ignore_normals && len > 0.0 && std::isfinite(len)) {
        const double c[3] = {nx / len, ny / len, nz / len};
        const double m[3] = {std::abs(c[0]), std::abs(c[1]), std::abs(c[2])};
        int axes[3] = {0, 1, 2}; // by decreasing |component|
        if (m[axes[1]] > m[axes[0]]) std::swap(axes[0], axes[1]);
        if (m[axes[2]] > m[axes[1]]) std::swap(axes[1], axes[2]);
        if (m[axes[1]] > m[axes[0]]) std::swap(axes[0], axes[1]);
        for (int k = 0; k < 3; ++k) {
            const int a = axes[k];
            if (k == 0 || std::abs(c[a]) >= kCos55)
                order[count++] = 1 + 2 * a + (c[a] < 0.0 ? 1 : 0);
        }
    }
    order[count++] = 0;
    return count;
}

/// tree_order's first tree for a normal with finite components one of which
/// is strictly the largest in magnitude, or -1, without tree_order's square
/// root and divisions. Dividing by the length rounds each quotient by a
/// relative 2^-53 at most, so a component larger than the others by more
/// than a relative 2^-40 (any two different floats differ by 2^-24 or more)
/// is still strictly the largest after it: the same tree.
int dominant_tree(const glm::vec3& n) {
    const double a[3] = {std::abs(double(n.x)), std::abs(double(n.y)),
                         std::abs(double(n.z))};
    if (!(a[0] + a[1] + a[2] < 1e300)) return -1; // NaN or infinite
    const int i = a[1] > a[0] ? (a[2] > a[1] ? 2 : 1) : (a[2] > a[0] ? 2 : 0);
    const double second = std::max(a[(i + 1) % 3], a[(i + 2) % 3]);
    constexpr double kMargin = 1.0 + 0x1p-40;
    if (!(a[i] > second * kMargin)) return -1; // no clear dominance (or n = 0)
    return 1 + 2 * i + (n[i] < 0.0f ? 1 : 0);
}

} // namespace

struct BrickMap::Impl {
    std::string path;
    int fd = -1;
    BkmContents contents;
    int ds = 0;
    double cube_min[3] = {0, 0, 0};
    double side = 1.0;
    double inv_side = 1.0;
    std::array<LookupTree, kBkmTrees> trees;
    std::array<uint32_t, kBkmTrees> first_brick{};      ///< brick id of each tree's root
    std::vector<std::pair<int, const BkmNode*>> bricks; ///< by id: tree, record
    std::unique_ptr<BrickSlot[]> slots;
    std::size_t budget = 0;
    bool checksums = true;

    // Cache bookkeeping; everything below the mutex is guarded by it.
    mutable PinStripe stripes[kStripes];
    mutable std::atomic<uint64_t> epoch{2};
    mutable std::atomic<uint64_t> tick{1};
    mutable std::atomic<std::size_t> loaded{0};
    mutable std::atomic<std::size_t> cached{0};
    mutable std::mutex mutex;
    mutable std::vector<CachedBrick*> live;
    mutable std::vector<CachedBrick*> pending; ///< unlinked in the current epoch
    mutable std::vector<CachedBrick*> waiting; ///< unlinked before the last flip
    mutable std::size_t live_bytes = 0;
    mutable std::size_t retired_bytes = 0;
    struct Stamped {
        uint64_t stamp;
        uint32_t id;
        CachedBrick* brick;
    };
    mutable std::vector<Stamped> order; ///< eviction scratch

    ~Impl() {
        if (slots) {
            for (std::size_t i = 0; i < bricks.size(); ++i) slots[i].brick.store(nullptr);
        }
        for (CachedBrick* b : live) CachedBrick::destroy(b);
        for (CachedBrick* b : pending) CachedBrick::destroy(b);
        for (CachedBrick* b : waiting) CachedBrick::destroy(b);
        if (fd >= 0) ::close(fd);
    }

    /// RAII pin of the calling thread for one lookup.
    class Pin {
    public:
        explicit Pin(const Impl& m) : m_stripe(m.stripes[thread_stripe()]) {
            for (;;) {
                const uint64_t e = m.epoch.load(std::memory_order_seq_cst);
                std::atomic<uint64_t>& c = m_stripe.count[e & 1];
                c.fetch_add(1, std::memory_order_seq_cst);
                if (m.epoch.load(std::memory_order_seq_cst) == e) {
                    m_parity = static_cast<int>(e & 1);
                    return;
                }
                c.fetch_sub(1, std::memory_order_release); // a flip raced us: retry
            }
        }
        ~Pin() { m_stripe.count[m_parity].fetch_sub(1, std::memory_order_release); }
        Pin(const Pin&) = delete;
        Pin& operator=(const Pin&) = delete;

    private:
        PinStripe& m_stripe;
        int m_parity = 0;
    };

    bool drained(int parity) const {
        for (const PinStripe& s : stripes) {
            if (s.count[parity].load(std::memory_order_seq_cst) != 0) return false;
        }
        return true;
    }

    /// Frees retired bricks whose grace period is over and starts a new one.
    /// Never waits. Caller holds the mutex.
    void reclaim() const {
        const uint64_t e = epoch.load(std::memory_order_relaxed);
        // Readers of epoch e - 1 gone: nothing unlinked before the flip to e
        // can still be in use, and the epoch may advance.
        if (!drained(static_cast<int>((e - 1) & 1))) return;
        for (CachedBrick* b : waiting) {
            retired_bytes -= b->bytes;
            CachedBrick::destroy(b);
        }
        waiting.clear();
        if (!pending.empty()) {
            waiting.swap(pending);
            epoch.store(e + 1, std::memory_order_seq_cst);
        }
    }

    /// Unlinks least recently used bricks until the live bytes are back to
    /// 7/8 of the budget (so that eviction work is amortised), keeping keep.
    void evict(const CachedBrick* keep) const {
        if (live_bytes <= budget) return;
        const std::size_t target = budget - budget / 8;
        // Readers keep stamping bricks while we sort: sort a snapshot (a
        // comparator whose keys change under std::sort is undefined behaviour).
        order.clear();
        for (CachedBrick* b : live)
            order.push_back(
                {slots[b->id].stamp.load(std::memory_order_relaxed), b->id, b});
        std::sort(order.begin(), order.end(), [](const Stamped& a, const Stamped& b) {
            return a.stamp != b.stamp ? a.stamp < b.stamp : a.id < b.id;
        });
        std::size_t out = 0;
        for (std::size_t i = 0; i < order.size(); ++i) {
            CachedBrick* b = order[i].brick;
            if (live_bytes > target && b != keep) {
                slots[b->id].brick.store(nullptr, std::memory_order_release);
                live_bytes -= b->bytes;
                retired_bytes += b->bytes;
                pending.push_back(b);
            } else {
                live[out++] = b;
            }
        }
        live.resize(out); // survivors, oldest first
    }

    void touch(uint32_t id) const {
        const uint64_t now = tick.load(std::memory_order_relaxed);
        std::atomic<uint64_t>& stamp = slots[id].stamp;
        if (stamp.load(std::memory_order_relaxed) != now)
            stamp.store(now, std::memory_order_relaxed);
    }

    /// The brick with this id, loading it on a miss. Caller is pinned.
    const CachedBrick* fetch(uint32_t id) const {
        CachedBrick* b = slots[id].brick.load(std::memory_order_acquire);
        if (b) {
            touch(id);
            return b;
        }
        return load(id);
    }

    const CachedBrick* load(uint32_t id) const {
        const auto [tree, node] = bricks[id];
        const std::size_t size = static_cast<std::size_t>(bkm_brick_size(*node, ds));
        std::vector<unsigned char> bytes(size);
        bkm_pread(fd, path, bytes.data(), size, node->offset);
        if (checksums) bkm_check_brick_crc(bytes.data(), *node, tree, ds, path);
        CachedBrickPtr fresh(CachedBrick::create(node->samples, ds));
        bkm_decode_brick(bytes.data(), *node, tree, ds, path, fresh->mask, nullptr,
                         fresh->data());
        fresh->id = id;
        unsigned before = 0;
        for (int w = 0; w < 8; ++w) {
            fresh->rank[w] = static_cast<uint16_t>(before);
            before += popcount64(fresh->mask[w]);
        }

        loaded.fetch_add(1, std::memory_order_relaxed);
        std::lock_guard<std::mutex> lock(mutex);
        if (CachedBrick* other = slots[id].brick.load(std::memory_order_relaxed)) {
            touch(id); // another thread loaded it meanwhile
            return other;
        }
        reclaim();
        if (retired_bytes > budget) {
            // Lookups that started long ago (a preempted thread) still pin a
            // budget's worth of evicted bricks: rather than grow the cache,
            // serve this miss from a private copy, valid until this thread's
            // next private load (the caller uses it at once).
            thread_local CachedBrickPtr t_private;
            t_private = std::move(fresh);
            cached.store(live_bytes + retired_bytes, std::memory_order_relaxed);
            return t_private.get();
        }
        CachedBrick* b = fresh.release();
        slots[id].stamp.store(tick.fetch_add(1, std::memory_order_relaxed) + 1,
                              std::memory_order_relaxed);
        live.push_back(b);
        live_bytes += b->bytes;
        slots[id].brick.store(b, std::memory_order_release);
        evict(b);
        reclaim();
        cached.store(live_bytes + retired_bytes, std::memory_order_relaxed);
        return b;
    }

    /// Trilinear value at lattice position x (in sample units of node's
    /// brick, each in [0, 7]) over the present corners, times weight, added
    /// to out. False if no corner with a positive weight has data.
    ///
    /// Branch-free over the corners: an absent corner gets weight +0, which
    /// adds exactly nothing to the sum of weights (a sum of non-negative
    /// terms starting at +0) nor to out (out starts at +0, so it is never -0,
    /// and x + (+-0) == x for any other x; samples are finite). The values are
    /// therefore bit for bit those of skipping the absent corners.
    bool eval_brick(const CachedBrick& b, const double x[3], double weight,
                    float* out) const {
        int i0[3];
        double f[3];
        for (int a = 0; a < 3; ++a) {
            i0[a] = std::min(static_cast<int>(x[a]), 6);
            f[a] = x[a] - i0[a];
        }
        // The corners are bits i0, i0 + 1 of rows j0 and j0 + 1 of planes k0
        // (word k0 of the mask) and k0 + 1. Their values: at their rank among
        // the present samples. An absent corner reads the next present sample
        // (or the block's zero sample) with weight 0.
        const unsigned shift = static_cast<unsigned>(i0[0] + 8 * i0[1]);
        uint64_t rows[2];
        unsigned ranks[2][2]; // [plane][row]: rank of the row's corner i0
        for (int p = 0; p < 2; ++p) {
            const uint64_t word = b.mask[i0[2] + p];
            rows[p] = word >> shift;
            ranks[p][0] =
                b.rank[i0[2] + p] + popcount64(word & ((uint64_t(1) << shift) - 1));
            ranks[p][1] = ranks[p][0] + kPopcount8[rows[p] & 0xff];
        }
        const double g[3][2] = {
            {1.0 - f[0], f[0]}, {1.0 - f[1], f[1]}, {1.0 - f[2], f[2]}};
        double w[8];
        const float* v[8];
        double sum = 0.0;
        for (int c = 0; c < 8; ++c) {
            const int cx = c & 1, cy = (c >> 1) & 1, cz = c >> 2;
            const uint64_t row = rows[cz] >> (8 * cy);
            const uint64_t bit = (row >> cx) & 1;
            w[c] = g[0][cx] * g[1][cy] * g[2][cz] * double(bit);
            sum += w[c];
            const unsigned rank = ranks[cz][cy] + (cx ? unsigned(row & 1) : 0u);
            v[c] = b.data() + static_cast<std::size_t>(rank) * ds;
        }
        if (!(sum > 0.0)) return false;
        const double scale = weight / sum;
        switch (ds) {
        case 1:
            blend<1>(v, w, scale, out);
            break;
        case 2:
            blend<2>(v, w, scale, out);
            break;
        case 3:
            blend<3>(v, w, scale, out);
            break;
        case 4:
            blend<4>(v, w, scale, out);
            break;
        default:
            blend<0>(v, w, scale, out);
            break;
        }
        return true;
    }

    /// out[k] += float(w[c] * scale) * v[c][k], corner by corner in order c =
    /// 0..7 (the
    /// order of the sums is part of the result). DS: floats per sample, or 0
    /// for ds (the compiler keeps the sums of a small DS in registers).
    template <int DS>
    void blend(const float* const* v, const double* w, double scale, float* out) const {
        const int n = DS > 0 ? DS : ds;
        if constexpr (DS > 0) {
            float acc[DS];
            for (int k = 0; k < DS; ++k) acc[k] = out[k];
            for (int c = 0; c < 8; ++c) {
                const float wc = static_cast<float>(w[c] * scale);
                for (int k = 0; k < DS; ++k) acc[k] += wc * v[c][k];
            }
            for (int k = 0; k < DS; ++k) out[k] = acc[k];
        } else {
            for (int c = 0; c < 8; ++c) {
                const float wc = static_cast<float>(w[c] * scale);
                for (int k = 0; k < n; ++k) out[k] += wc * v[c][k];
            }
        }
    }

    /// Value of the level starting at depth `start` along path (falling back
    /// to coarser depths where there is no data), times weight, added to out.
    /// Returns the depth used, or -1.
    int eval_level(int tree, const uint32_t* path, int start, const double u[3],
                   const uint32_t q[3], double weight, float* out) const {
        for (int d = start; d >= 0; --d) {
            const CachedBrick& b = *fetch(first_brick[tree] + path[d]);
            const double scale = kBkmBrickEdge * double(1u << d);
            double x[3];
            for (int a = 0; a < 3; ++a) {
                const uint32_t node = q[a] >> (kCoordBits - d);
                x[a] = std::clamp(u[a] * scale - kBkmBrickEdge * double(node), 0.0,
                                  double(kBkmBrickEdge));
            }
            if (eval_brick(b, x, weight, out)) return d;
        }
        return -1;
    }

    /// max_depth: the finest depth read (a filter radius 0 lookup: the
    /// finest data there, or data no finer than max_depth).
    bool lookup_tree(int tree, const double u[3], float filter_radius, float* out,
                     float* scratch, int max_depth = kBkmMaxDepth) const {
        const LookupTree& t = trees[tree];
        if (t.nodes.empty()) return false;
        uint32_t q[3];
        for (int a = 0; a < 3; ++a) {
            q[a] = static_cast<uint32_t>(std::min(u[a] * double(1u << kCoordBits),
                                                  double((1u << kCoordBits) - 1)));
        }
        // The node at depth d containing p: its Morton code is that of q's
        // top d bits.
        const uint32_t top = kSpread4[q[0] >> (kCoordBits - kTableDepth)] |
                             (kSpread4[q[1] >> (kCoordBits - kTableDepth)] << 1) |
                             (kSpread4[q[2] >> (kCoordBits - kTableDepth)] << 2);
        uint32_t path[kBkmMaxDepth + 1];
        path[0] = 0;
        int deepest = 0;
        for (int d = 1; d <= t.table_depth; ++d) {
            const uint32_t i =
                t.tables[LookupTree::table_offset(d) + (top >> (3 * (kTableDepth - d)))];
            if (i == kNoNode) break;
            path[d] = i;
            deepest = d;
        }
        if (deepest == t.table_depth) {
            for (int d = deepest + 1; d <= kBkmMaxDepth; ++d) {
                const LookupNode& n = t.nodes[path[d - 1]];
                const int shift = kCoordBits - d;
                const unsigned o = ((q[0] >> shift) & 1) | (((q[1] >> shift) & 1) << 1) |
                                   (((q[2] >> shift) & 1) << 2);
                if (!((n.child_mask >> o) & 1)) break;
                path[d] = n.first_child + kPopcount8[n.child_mask & ((1u << o) - 1)];
                deepest = d;
            }
        }
        if (!(filter_radius > 0.0f))
            return eval_level(tree, path, std::min(deepest, max_depth), u, q, 1.0, out) >=
                   0;
        // Level whose sample spacing side / (7 * 2^d) matches the filter's
        // diameter: the level brickmake splats a point of that radius into.
        const double level =
            std::log2(side / (kBkmBrickEdge * 2.0 * double(filter_radius)));
        if (!(level > 0.0)) return eval_level(tree, path, 0, u, q, 1.0, out) >= 0;
        const int d0 = static_cast<int>(std::floor(level));
        const double f = level - d0;
        if (d0 >= deepest) return eval_level(tree, path, deepest, u, q, 1.0, out) >= 0;
        // The finer level first: where it falls back to d0 or coarser, both
        // levels are the same value.
        const int fine = eval_level(tree, path, d0 + 1, u, q, 1.0, out);
        if (fine < 0) return false;
        if (fine <= d0 || f >= 1.0) return true;
        std::fill(scratch, scratch + ds, 0.0f);
        if (eval_level(tree, path, d0, u, q, 1.0, scratch) < 0) return true;
        const float wf = static_cast<float>(f), wc = static_cast<float>(1.0 - f);
        for (int k = 0; k < ds; ++k) out[k] = wf * out[k] + wc * scratch[k];
        return true;
    }

    static constexpr int kBkmBrickEdge = 7; ///< sample steps per brick edge
};

BrickMap::BrickMap(const std::string& path, std::size_t cache_bytes,
                   BrickMapChecksums checksums)
    : m_impl(std::make_unique<Impl>()) {
    Impl& m = *m_impl;
    m.path = path;
    m.budget = cache_bytes;
    m.checksums = checksums == BrickMapChecksums::Verify;
    detail::require_regular_file(path); // before open(): a FIFO would block it
    m.fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (m.fd < 0)
        throw IoError(path, std::string("cannot open: ") + std::strerror(errno));
    struct stat st {};
    if (::fstat(m.fd, &st) != 0)
        throw IoError(path, std::string("cannot stat: ") + std::strerror(errno));
    if (S_ISDIR(st.st_mode)) throw IoError(path, "is a directory");
    if (!S_ISREG(st.st_mode)) throw IoError(path, "not a regular file");
    m.contents =
        bkm_read_head(m.fd, path, static_cast<uint64_t>(st.st_size), m.checksums);
    const BrickMapInfo& info = m.contents.info;
    m.ds = info.data_size;
    for (int a = 0; a < 3; ++a) m.cube_min[a] = info.cube_min[a];
    m.side = info.cube_side;
    m.inv_side = 1.0 / info.cube_side;

    // Data-only trees for descending; brick ids in file order.
    for (int t = 0; t < kBkmTrees; ++t) {
        const std::vector<BkmNode>& nodes = m.contents.trees[t];
        std::vector<int64_t> index(nodes.size(), -1);
        std::vector<LookupNode>& out = m.trees[t].nodes;
        m.first_brick[t] = static_cast<uint32_t>(m.bricks.size());
        for (std::size_t i = 0; i < nodes.size(); ++i) {
            if (!nodes[i].has_data()) continue;
            index[i] = static_cast<int64_t>(out.size());
            m.bricks.emplace_back(t, &nodes[i]);
            out.push_back(LookupNode{});
        }
        // Data nodes are closed under "parent of" and in breadth-first order,
        // so the data children of a node stay contiguous and in octant order.
        for (std::size_t i = 0; i < nodes.size(); ++i) {
            if (index[i] < 0 || nodes[i].child_mask == 0) continue;
            LookupNode& n = out[static_cast<std::size_t>(index[i])];
            int k = 0;
            for (int o = 0; o < 8; ++o) {
                if (!((nodes[i].child_mask >> o) & 1)) continue;
                const std::size_t c = nodes[i].first_child + k++;
                if (index[c] < 0) continue;
                if (n.child_mask == 0) n.first_child = static_cast<uint32_t>(index[c]);
                n.child_mask |= uint8_t(1u << o);
            }
        }
    }
    for (int t = 0; t < kBkmTrees; ++t) {
        LookupTree& tree = m.trees[t];
        if (tree.nodes.empty()) continue;
        int depth = 0;
        for (std::size_t i = 0; i < tree.nodes.size(); ++i)
            depth = std::max<int>(depth, m.bricks[m.first_brick[t] + i].second->depth);
        tree.table_depth = std::min(depth, kTableDepth);
        tree.tables.assign(LookupTree::table_offset(tree.table_depth + 1), kNoNode);
        for (std::size_t i = 0; i < tree.nodes.size(); ++i) {
            const BkmNode& n = *m.bricks[m.first_brick[t] + i].second;
            if (n.depth < 1 || n.depth > tree.table_depth) continue;
            tree.tables[LookupTree::table_offset(n.depth) +
                        bkm_morton(n.ix, n.iy, n.iz)] = static_cast<uint32_t>(i);
        }
    }
    m.slots = std::make_unique<BrickSlot[]>(m.bricks.size());
}

BrickMap::~BrickMap() = default;

const BrickMapInfo& BrickMap::info() const {
    return m_impl->contents.info;
}

int BrickMap::channel_index(const std::string& name) const {
    const auto& channels = m_impl->contents.info.channels;
    for (std::size_t i = 0; i < channels.size(); ++i)
        if (channels[i].first == name) return static_cast<int>(i);
    return -1;
}

int BrickMap::channel_offset(const std::string& name) const {
    int offset = 0;
    for (const auto& [n, type] : m_impl->contents.info.channels) {
        if (n == name) return offset;
        offset += channel_type_size(type);
    }
    return -1;
}

bool BrickMap::lookup(const glm::vec3& p, const glm::vec3& n, float filter_radius,
                      float* out) const {
    return lookup(p, n, filter_radius, kBkmMaxDepth, out);
}

bool BrickMap::lookup_depth(const glm::vec3& p, const glm::vec3& n, int depth,
                            float* out) const {
    return lookup(p, n, 0.0f, std::clamp(depth, 0, kBkmMaxDepth), out);
}

bool BrickMap::lookup(const glm::vec3& p, const glm::vec3& n, float filter_radius,
                      int max_depth, float* out) const {
    const Impl& m = *m_impl;
    std::fill(out, out + m.ds, 0.0f);
    double u[3];
    for (int a = 0; a < 3; ++a) {
        u[a] = (double(p[a]) - m.cube_min[a]) * m.inv_side;
        if (!(u[a] >= 0.0 && u[a] <= 1.0)) return false; // outside the cube, or NaN
    }
    // The tree of n's dominant axis first, found without tree_order's
    // square root and divisions (which a random normal would also make the
    // processor mispredict) when one axis clearly dominates; the other trees
    // only if it has no data at p.
    const int first = m.contents.info.ignore_normals ? 0 : dominant_tree(n);
    float scratch[kBkmMaxDataSize];
    const Impl::Pin pin(m);
    if (first >= 0) {
        if (m.lookup_tree(first, u, filter_radius, out, scratch, max_depth)) return true;
        std::fill(out, out + m.ds, 0.0f);
    }
    int order[4];
    const int count = tree_order(n, m.contents.info.ignore_normals, order);
    for (int k = 0; k < count; ++k) {
        if (order[k] == first) continue; // tried
        if (m.lookup_tree(order[k], u, filter_radius, out, scratch, max_depth))
            return true;
        std::fill(out, out + m.ds, 0.0f);
    }
    return false;
}

bool BrickMap::read_brick(int tree, int depth, uint32_t ix, uint32_t iy, uint32_t iz,
                          std::vector<float>& data, std::vector<uint8_t>& present) const {
    const Impl& m = *m_impl;
    if (tree < 0 || tree >= kBkmTrees) return false;
    const std::vector<BkmNode>& nodes = m.contents.trees[tree];
    const int64_t i = find_node(nodes, depth, ix, iy, iz);
    if (i < 0 || !nodes[i].has_data()) return false;
    const BkmNode& node = nodes[i];
    std::vector<unsigned char> bytes(bkm_brick_size(node, m.ds));
    bkm_pread(m.fd, m.path, bytes.data(), bytes.size(), node.offset);
    if (m.checksums) bkm_check_brick_crc(bytes.data(), node, tree, m.ds, m.path);
    uint64_t mask[8];
    data.assign(static_cast<std::size_t>(kBrickSamples) * m.ds, 0.0f);
    bkm_decode_brick(bytes.data(), node, tree, m.ds, m.path, mask, data.data());
    present.assign(kBrickSamples, 0);
    for (int s = 0; s < kBrickSamples; ++s) present[s] = (mask[s >> 6] >> (s & 63)) & 1;
    return true;
}

bool BrickMap::read_occupancy(int tree, int depth, uint32_t ix, uint32_t iy, uint32_t iz,
                              std::vector<uint8_t>& present) const {
    const Impl& m = *m_impl;
    if (tree < 0 || tree >= kBkmTrees) return false;
    const std::vector<BkmNode>& nodes = m.contents.trees[tree];
    const int64_t i = find_node(nodes, depth, ix, iy, iz);
    if (i < 0) return false;
    const BkmNode& node = nodes[i];
    // The whole brick: its checksum covers the data too.
    std::vector<unsigned char> bytes(bkm_brick_size(node, m.ds));
    bkm_pread(m.fd, m.path, bytes.data(), bytes.size(), node.offset);
    if (m.checksums) bkm_check_brick_crc(bytes.data(), node, tree, m.ds, m.path);
    uint64_t mask[8];
    bkm_decode_brick(bytes.data(), node, tree, m.ds, m.path, mask, nullptr);
    present.assign(kBrickSamples, 0);
    for (int s = 0; s < kBrickSamples; ++s) present[s] = (mask[s >> 6] >> (s & 63)) & 1;
    return true;
}

std::vector<std::array<uint32_t, 3>> BrickMap::bricks_at(int tree, int depth) const {
    std::vector<std::array<uint32_t, 3>> out;
    if (tree < 0 || tree >= kBkmTrees) return out;
    for (const BkmNode& n : m_impl->contents.trees[tree]) {
        if (n.depth == depth && n.has_data()) out.push_back({n.ix, n.iy, n.iz});
    }
    return out;
}

std::vector<std::array<uint32_t, 3>> BrickMap::nodes_at(int tree, int depth) const {
    std::vector<std::array<uint32_t, 3>> out;
    if (tree < 0 || tree >= kBkmTrees) return out;
    for (const BkmNode& n : m_impl->contents.trees[tree]) {
        if (n.depth == depth) out.push_back({n.ix, n.iy, n.iz});
    }
    return out;
}

std::size_t BrickMap::verify() const {
    const Impl& m = *m_impl;
    // The bricks follow each other in table order: read them in large
    // sequential chunks, each holding whole bricks.
    constexpr std::size_t kChunk = 4u << 20;
    std::vector<unsigned char> buffer;
    uint64_t mask[8];
    std::size_t checked = 0;
    for (int t = 0; t < kBkmTrees; ++t) {
        const std::vector<BkmNode>& nodes = m.contents.trees[t];
        for (std::size_t i = 0; i < nodes.size();) {
            std::size_t end = i;
            uint64_t bytes = 0;
            while (end < nodes.size() &&
                   (end == i || bytes + bkm_brick_size(nodes[end], m.ds) <= kChunk)) {
                bytes += bkm_brick_size(nodes[end], m.ds);
                ++end;
            }
            buffer.resize(static_cast<std::size_t>(bytes));
            bkm_pread(m.fd, m.path, buffer.data(), buffer.size(), nodes[i].offset);
            const unsigned char* p = buffer.data();
            for (; i < end; ++i) {
                if (m.checksums) bkm_check_brick_crc(p, nodes[i], t, m.ds, m.path);
                bkm_decode_brick(p, nodes[i], t, m.ds, m.path, mask, nullptr);
                p += bkm_brick_size(nodes[i], m.ds);
                ++checked;
            }
        }
    }
    return checked;
}

std::size_t BrickMap::bricks_loaded() const {
    return m_impl->loaded.load(std::memory_order_relaxed);
}

std::size_t BrickMap::cached_bytes() const {
    return m_impl->cached.load(std::memory_order_relaxed);
}

} // namespace sss
