// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file point_cloud_lookup.cpp
/// PointCloudLookup: texture3d-like lookups straight on a point cloud (the
/// renderer's texture3d on .ptc/.ply files, and the reference brick maps are
/// checked against). A kd-tree (median splits on the widest axis, leaves of
/// at most 8 points, tight boxes) indexes the positions; points and their
/// data are stored in tree order so a leaf is one contiguous run.
///
/// The k + 1 nearest qualifying points are found exactly, ties broken by
/// tree order, so a result depends only on its query.

#include "sss/cloud/point_cloud_lookup.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <unordered_set>

#include <glm/geometric.hpp>

#include "sss/util/error.h"

namespace sss {

namespace {

constexpr uint32_t kLeafSize = 8;
/// Points averaged when the filter radius is 0 (and the fallback count).
constexpr int kNearest = 8;
/// Points searched: one more than averaged, where the tent weights reach 0.
constexpr int kWanted = kNearest + 1;
/// cos(60 degrees): points whose normal is farther from the query's are ignored.
constexpr float kMinNormalCos = 0.5f;
constexpr float kInfinity = std::numeric_limits<float>::infinity();

/// 32 bytes: two nodes per cache line.
struct Node {
    glm::vec3 lo{0.0f};
    glm::vec3 hi{0.0f};
    uint32_t first = 0; ///< leaf: first point; inner: first child (then first + 1)
    uint32_t count = 0; ///< leaf: its points (at least 1); inner: 0
};

inline float box_distance2(const Node& node, const glm::vec3& p) {
    const float dx = std::max(std::max(node.lo.x - p.x, p.x - node.hi.x), 0.0f);
    const float dy = std::max(std::max(node.lo.y - p.y, p.y - node.hi.y), 0.0f);
    const float dz = std::max(std::max(node.lo.z - p.z, p.z - node.hi.z), 0.0f);
    return dx * dx + dy * dy + dz * dz;
}

/// A neighbour candidate: squared distance and tree-order index. Ordering by
/// (distance, index) makes ties deterministic.
struct Candidate {
    float d2;
    uint32_t index;
    bool operator<(const Candidate& o) const {
        return d2 < o.d2 || (d2 == o.d2 && index < o.index);
    }
};

/// The k + 1 best candidates so far, nearest first.
struct Best {
    std::array<Candidate, kWanted> c;
    int count = 0;

    float d2(int k) const { return c[k].d2; }
    uint32_t index(int k) const { return c[k].index; }
    int found() const { return count; }
    bool full() const { return count == kWanted; }
    /// Squared distance beyond which nothing can enter.
    float limit() const { return count == kWanted ? c[kWanted - 1].d2 : kInfinity; }
    void offer(float d2, uint32_t index) {
        const Candidate x{d2, index};
        if (count == kWanted && !(x < c[kWanted - 1])) return;
        int at = count < kWanted ? count++ : kWanted - 1;
        while (at > 0 && x < c[at - 1]) {
            c[at] = c[at - 1];
            --at;
        }
        c[at] = x;
    }
};

/// The nearest-point weights of one lookup: the points averaged, in order.
struct Weights {
    std::array<uint32_t, kNearest> index;
    std::array<double, kNearest> w;
    int used = 0;
    double sum = 0.0;
};

} // namespace

struct PointCloudLookup::Impl {
    std::vector<std::pair<std::string, ChannelType>> channels;
    int data_size = 0;
    // Tree order.
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals; ///< unit, or zero (no normal)
    std::vector<float> data;        ///< data_size floats per point
    std::vector<Node> nodes;

    void build(const PointCloud& cloud, const std::vector<const Channel*>& sources);
    bool qualifies(uint32_t i, const glm::vec3& n) const {
        const glm::vec3& pn = normals[i];
        return glm::dot(pn, n) >= kMinNormalCos || pn == glm::vec3(0.0f);
    }
    /// Offers the leaf's qualifying points to best, the distance test (which
    /// rejects most of them) first.
    void scan_leaf(const Node& leaf, const glm::vec3& p, const glm::vec3& n,
                   bool use_normal, Best& best) const {
        const uint32_t end = leaf.first + leaf.count;
        for (uint32_t i = leaf.first; i < end; ++i) {
            const glm::vec3 d = positions[i] - p;
            const float d2 = glm::dot(d, d);
            if (d2 > best.limit()) continue;
            if (use_normal && !qualifies(i, n)) continue;
            best.offer(d2, i);
        }
    }
    /// The up to k + 1 nearest qualifying points, by the tree.
    void nearest_tree(const glm::vec3& p, const glm::vec3& n, bool use_normal,
                      Best& best) const;
    bool nearest_weights(const glm::vec3& p, const glm::vec3& n, bool use_normal,
                         Weights& w, float* nearest_d2) const;
    bool lookup_radius(const glm::vec3& p, const glm::vec3& n, bool use_normal,
                       float radius, std::span<const Range> ranges, float* out,
                       float* nearest_d2) const;
    bool lookup_nearest(const glm::vec3& p, const glm::vec3& n, bool use_normal,
                        std::span<const Range> ranges, float* out,
                        float* nearest_d2) const;
};

void PointCloudLookup::Impl::build(const PointCloud& cloud,
                                   const std::vector<const Channel*>& sources) {
    const std::size_t count = cloud.size();
    if (count >= std::size_t(0xffffffffu))
        throw ValueError("point cloud lookup: too many points (" + std::to_string(count) +
                         ")");
    std::vector<uint32_t> order(count);
    std::iota(order.begin(), order.end(), 0u);
    if (count > 0) nodes.reserve(2 * (count / kLeafSize + 1));

    // Iterative build: a stack of nodes still to split. A node holds its
    // range of `order` in (first, count) until it is split.
    if (count > 0)
        nodes.push_back(Node{glm::vec3(0.0f), glm::vec3(0.0f), 0, uint32_t(count)});
    std::vector<uint32_t> todo;
    if (count > 0) todo.push_back(0);
    while (!todo.empty()) {
        const uint32_t ni = todo.back();
        todo.pop_back();
        Node node = nodes[ni];
        const uint32_t begin = node.first, end = node.first + node.count;
        glm::vec3 lo(std::numeric_limits<float>::max());
        glm::vec3 hi(-std::numeric_limits<float>::max());
        for (uint32_t k = begin; k < end; ++k) {
            lo = glm::min(lo, cloud.positions[order[k]]);
            hi = glm::max(hi, cloud.positions[order[k]]);
        }
        node.lo = lo;
        node.hi = hi;
        const glm::vec3 extent = hi - lo;
        if (end - begin > kLeafSize && (extent.x > 0 || extent.y > 0 || extent.z > 0)) {
            int axis = 0;
            if (extent.y > extent[axis]) axis = 1;
            if (extent.z > extent[axis]) axis = 2;
            const uint32_t mid = begin + (end - begin) / 2;
            std::nth_element(order.begin() + begin, order.begin() + mid,
                             order.begin() + end, [&](uint32_t a, uint32_t b) {
                                 float ca = cloud.positions[a][axis];
                                 float cb = cloud.positions[b][axis];
                                 return ca < cb || (ca == cb && a < b);
                             });
            const uint32_t left = uint32_t(nodes.size());
            nodes.push_back(Node{glm::vec3(0.0f), glm::vec3(0.0f), begin, mid - begin});
            nodes.push_back(Node{glm::vec3(0.0f), glm::vec3(0.0f), mid, end - mid});
            node.first = left;
            node.count = 0;
            todo.push_back(left + 1);
            todo.push_back(left);
        }
        // Coincident points (zero extent) stay in one leaf whatever their number.
        nodes[ni] = node;
    }

    positions.resize(count);
    normals.resize(count);
    data.resize(count * std::size_t(data_size));
    for (std::size_t k = 0; k < count; ++k) {
        uint32_t src = order[k];
        positions[k] = cloud.positions[src];
        glm::vec3 pn = src < cloud.normals.size() ? cloud.normals[src] : glm::vec3(0.0f);
        float len = glm::length(pn);
        normals[k] = (len > 0.0f && std::isfinite(len)) ? pn / len : glm::vec3(0.0f);
        float* dst = data.data() + k * std::size_t(data_size);
        for (const Channel* ch : sources) {
            int c = ch->components();
            std::memcpy(dst, ch->data.data() + std::size_t(src) * c, sizeof(float) * c);
            dst += c;
        }
    }
}

void PointCloudLookup::Impl::nearest_tree(const glm::vec3& p, const glm::vec3& n,
                                          bool use_normal, Best& best) const {
    if (nodes.empty()) return;
    // Nodes to visit and their squared box distances, in two arrays: a
    // pair stored as two halves and read back whole stalls the load.
    // Depth is about log2(N / 8) + a few; 128 entries cover any 32-bit count.
    std::array<uint32_t, 128> stack;
    std::array<float, 128> stack_d2;
    int top = 0;
    stack[top] = 0;
    stack_d2[top++] = box_distance2(nodes[0], p);
    while (top > 0) {
        --top;
        if (stack_d2[top] > best.limit()) continue;
        const Node& node = nodes[stack[top]];
        if (node.count != 0) {
            scan_leaf(node, p, n, use_normal, best);
            continue;
        }
        const float da = box_distance2(nodes[node.first], p);
        const float db = box_distance2(nodes[node.first + 1], p);
        // Push the farther child first so the nearer one is searched first.
        const bool a_first = da <= db;
        stack[top] = a_first ? node.first + 1 : node.first;
        stack_d2[top++] = a_first ? db : da;
        stack[top] = a_first ? node.first : node.first + 1;
        stack_d2[top++] = a_first ? da : db;
    }
}

bool PointCloudLookup::Impl::nearest_weights(const glm::vec3& p, const glm::vec3& n,
                                             bool use_normal, Weights& w,
                                             float* nearest_d2) const {
    Best best;
    nearest_tree(p, n, use_normal, best);
    const int found = best.found();
    if (found == 0) return false;
    if (nearest_d2) *nearest_d2 = best.d2(0);
    const int used = std::min(found, kNearest);
    // Tent weights reaching zero at the first point left out, so the result
    // is continuous as the query moves and the neighbour set changes. With
    // fewer points than k + 1 the tent reaches twice the farthest one.
    const float reach = found > kNearest ? std::sqrt(best.d2(kNearest))
                                         : 2.0f * std::sqrt(best.d2(used - 1));
    w.used = used;
    w.sum = 0.0;
    for (int k = 0; k < used; ++k) {
        w.index[k] = best.index(k);
        w.w[k] = reach > 0.0f ? std::max(0.0, 1.0 - std::sqrt(double(best.d2(k))) / reach)
                              : 0.0;
        w.sum += w.w[k];
    }
    if (!(w.sum > 0.0)) { // all at the same distance: plain mean
        for (int k = 0; k < used; ++k) w.w[k] = 1.0;
        w.sum = used;
    }
    return true;
}

bool PointCloudLookup::Impl::lookup_nearest(const glm::vec3& p, const glm::vec3& n,
                                            bool use_normal,
                                            std::span<const Range> ranges, float* out,
                                            float* nearest_d2) const {
    Weights w;
    if (!nearest_weights(p, n, use_normal, w, nearest_d2)) return false;
    for (const Range& r : ranges) {
        for (int c = r.offset; c < r.offset + r.floats; ++c) {
            double acc = 0.0;
            for (int k = 0; k < w.used; ++k)
                acc += w.w[k] * data[std::size_t(w.index[k]) * data_size + c];
            *out++ = float(acc / w.sum);
        }
    }
    return true;
}

bool PointCloudLookup::Impl::lookup_radius(const glm::vec3& p, const glm::vec3& n,
                                           bool use_normal, float radius,
                                           std::span<const Range> ranges, float* out,
                                           float* nearest_d2) const {
    if (nodes.empty()) return false;
    const float r2 = radius * radius;
    // The sums, one per float asked for; kept per thread (no allocation
    // per lookup).
    thread_local std::vector<double> t_acc;
    std::size_t floats = 0;
    for (const Range& r : ranges) floats += std::size_t(r.floats);
    t_acc.assign(floats, 0.0);
    double* acc = t_acc.data();
    double wsum = 0.0;
    float closest = kInfinity;
    std::array<uint32_t, 128> stack;
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = nodes[stack[--top]];
        if (box_distance2(node, p) >= r2) continue;
        if (node.count == 0) {
            stack[top++] = node.first + 1;
            stack[top++] = node.first;
            continue;
        }
        const uint32_t end = node.first + node.count;
        for (uint32_t i = node.first; i < end; ++i) {
            const glm::vec3 d = positions[i] - p;
            const float d2 = glm::dot(d, d);
            if (d2 >= r2 || (use_normal && !qualifies(i, n))) continue;
            closest = std::min(closest, d2);
            const double w = 1.0 - std::sqrt(double(d2)) / radius;
            wsum += w;
            const float* src = data.data() + std::size_t(i) * data_size;
            double* a = acc;
            for (const Range& r : ranges)
                for (int c = r.offset; c < r.offset + r.floats; ++c) *a++ += w * src[c];
        }
    }
    if (!(wsum > 0.0)) return lookup_nearest(p, n, use_normal, ranges, out, nearest_d2);
    if (nearest_d2) *nearest_d2 = closest;
    for (std::size_t c = 0; c < floats; ++c) out[c] = float(acc[c] / wsum);
    return true;
}

PointCloudLookup::PointCloudLookup(const PointCloud& cloud,
                                   std::vector<std::string> channels)
    : m_impl(std::make_unique<Impl>()) {
    std::vector<const Channel*> sources;
    if (channels.empty()) {
        for (const Channel& ch : cloud.channels)
            if (ch.type == ChannelType::Float || ch.type == ChannelType::Color)
                sources.push_back(&ch);
    } else {
        std::unordered_set<std::string> seen;
        for (const std::string& name : channels) {
            if (!seen.insert(name).second)
                throw ValueError("point cloud lookup: channel '" + name +
                                 "' named twice");
            const Channel* ch = cloud.find_channel(name);
            if (!ch) throw ValueError("point cloud lookup: no channel '" + name + "'");
            sources.push_back(ch);
        }
    }
    for (const Channel* ch : sources) {
        if (ch->data.size() != cloud.size() * std::size_t(ch->components()))
            throw ValueError("point cloud lookup: channel '" + ch->name +
                             "' does not have one value per point");
        m_impl->channels.emplace_back(ch->name, ch->type);
        m_impl->data_size += ch->components();
    }
    m_impl->build(cloud, sources);
}

PointCloudLookup::~PointCloudLookup() = default;

int PointCloudLookup::data_size() const {
    return m_impl->data_size;
}

const std::vector<std::pair<std::string, ChannelType>>&
PointCloudLookup::channels() const {
    return m_impl->channels;
}

bool PointCloudLookup::lookup(const glm::vec3& p, const glm::vec3& n, float filter_radius,
                              float* out) const {
    const Range all{0, m_impl->data_size};
    return lookup(p, n, filter_radius, std::span<const Range>(&all, 1), out);
}

bool PointCloudLookup::lookup(const glm::vec3& p, const glm::vec3& n, float filter_radius,
                              std::span<const Range> ranges, float* out,
                              float* nearest) const {
    for (const Range& r : ranges)
        if (r.offset < 0 || r.floats < 0 || r.offset + r.floats > m_impl->data_size)
            throw ValueError("point cloud lookup: range outside the data");
    const float len = glm::length(n);
    const bool use_normal = len > 0.0f && std::isfinite(len);
    const glm::vec3 un = use_normal ? n / len : glm::vec3(0.0f);
    float d2 = kInfinity;
    const bool ok =
        filter_radius > 0.0f && std::isfinite(filter_radius)
            ? m_impl->lookup_radius(p, un, use_normal, filter_radius, ranges, out, &d2)
            : m_impl->lookup_nearest(p, un, use_normal, ranges, out, &d2);
    if (nearest) *nearest = ok ? std::sqrt(d2) : kInfinity;
    if (!ok) {
        std::size_t floats = 0;
        for (const Range& r : ranges) floats += std::size_t(r.floats);
        std::fill(out, out + floats, 0.0f);
    }
    return ok;
}

} // namespace sss
