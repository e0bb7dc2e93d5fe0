/// \file point_cloud_lookup.cpp
/// PointCloudLookup: texture3d-like lookups straight on a point cloud, the
/// reference brick maps are checked against. A kd-tree (median splits on the
/// widest axis, leaves of at most 8 points) indexes the positions; points
/// and their data are stored in tree order so a leaf is one contiguous run.

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
/// cos(60 degrees): points whose normal is farther from the query's are ignored.
constexpr float kMinNormalCos = 0.5f;

struct Node {
    glm::vec3 lo{0.0f};
    glm::vec3 hi{0.0f};
    uint32_t begin = 0;
    uint32_t end = 0;
    uint32_t left = 0; ///< first child (the second is left + 1); 0 = leaf
};

float box_distance2(const Node& node, const glm::vec3& p) {
    float d2 = 0.0f;
    for (int a = 0; a < 3; ++a) {
        float d = std::max({node.lo[a] - p[a], 0.0f, p[a] - node.hi[a]});
        d2 += d * d;
    }
    return d2;
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
        if (pn == glm::vec3(0.0f)) return true;
        return glm::dot(pn, n) >= kMinNormalCos;
    }
    /// The up to k + 1 nearest qualifying points, nearest first; returns the count.
    int nearest(const glm::vec3& p, const glm::vec3& n, bool use_normal,
                std::array<Candidate, kNearest + 1>& best) const;
    bool lookup_radius(const glm::vec3& p, const glm::vec3& n, bool use_normal,
                       float radius, float* out) const;
    bool lookup_nearest(const glm::vec3& p, const glm::vec3& n, bool use_normal,
                        float* out) const;
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

    // Iterative build: a stack of nodes still to split.
    if (count > 0)
        nodes.push_back(Node{glm::vec3(0.0f), glm::vec3(0.0f), 0, uint32_t(count), 0});
    std::vector<uint32_t> todo;
    if (count > 0) todo.push_back(0);
    while (!todo.empty()) {
        uint32_t ni = todo.back();
        todo.pop_back();
        Node node = nodes[ni];
        glm::vec3 lo(std::numeric_limits<float>::max());
        glm::vec3 hi(-std::numeric_limits<float>::max());
        for (uint32_t k = node.begin; k < node.end; ++k) {
            lo = glm::min(lo, cloud.positions[order[k]]);
            hi = glm::max(hi, cloud.positions[order[k]]);
        }
        node.lo = lo;
        node.hi = hi;
        glm::vec3 extent = hi - lo;
        if (node.end - node.begin > kLeafSize &&
            (extent.x > 0 || extent.y > 0 || extent.z > 0)) {
            int axis = 0;
            if (extent.y > extent[axis]) axis = 1;
            if (extent.z > extent[axis]) axis = 2;
            uint32_t mid = node.begin + (node.end - node.begin) / 2;
            std::nth_element(order.begin() + node.begin, order.begin() + mid,
                             order.begin() + node.end, [&](uint32_t a, uint32_t b) {
                                 float ca = cloud.positions[a][axis];
                                 float cb = cloud.positions[b][axis];
                                 return ca < cb || (ca == cb && a < b);
                             });
            node.left = uint32_t(nodes.size());
            nodes.push_back(Node{glm::vec3(0.0f), glm::vec3(0.0f), node.begin, mid, 0});
            nodes.push_back(Node{glm::vec3(0.0f), glm::vec3(0.0f), mid, node.end, 0});
            todo.push_back(node.left + 1);
            todo.push_back(node.left);
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

int PointCloudLookup::Impl::nearest(const glm::vec3& p, const glm::vec3& n,
                                    bool use_normal,
                                    std::array<Candidate, kNearest + 1>& best) const {
    constexpr int kWanted = kNearest + 1;
    int found = 0;
    if (nodes.empty()) return 0;
    struct Entry {
        uint32_t node;
        float d2;
    };
    // Depth is about log2(N / 8) + a few; 128 entries cover any 32-bit count.
    std::array<Entry, 128> stack;
    int top = 0;
    stack[top++] = Entry{0, box_distance2(nodes[0], p)};
    while (top > 0) {
        Entry e = stack[--top];
        if (found == kWanted && e.d2 > best[kWanted - 1].d2) continue;
        const Node& node = nodes[e.node];
        if (node.left == 0) {
            for (uint32_t i = node.begin; i < node.end; ++i) {
                if (use_normal && !qualifies(i, n)) continue;
                glm::vec3 d = positions[i] - p;
                Candidate c{glm::dot(d, d), i};
                if (found == kWanted && !(c < best[kWanted - 1])) continue;
                int at = found < kWanted ? found++ : kWanted - 1;
                while (at > 0 && c < best[at - 1]) {
                    best[at] = best[at - 1];
                    --at;
                }
                best[at] = c;
            }
            continue;
        }
        float da = box_distance2(nodes[node.left], p);
        float db = box_distance2(nodes[node.left + 1], p);
        // Push the farther child first so the nearer one is searched first.
        if (da <= db) {
            stack[top++] = Entry{node.left + 1, db};
            stack[top++] = Entry{node.left, da};
        } else {
            stack[top++] = Entry{node.left, da};
            stack[top++] = Entry{node.left + 1, db};
        }
    }
    return found;
}

bool PointCloudLookup::Impl::lookup_nearest(const glm::vec3& p, const glm::vec3& n,
                                            bool use_normal, float* out) const {
    std::array<Candidate, kNearest + 1> best;
    int found = nearest(p, n, use_normal, best);
    if (found == 0) return false;
    int used = std::min(found, kNearest);
    // Tent weights reaching zero at the first point left out, so the result
    // is continuous as the query moves and the neighbour set changes. With
    // fewer points than k + 1 the tent reaches twice the farthest one.
    float reach = found > kNearest ? std::sqrt(best[kNearest].d2)
                                   : 2.0f * std::sqrt(best[used - 1].d2);
    std::array<double, kNearest> w{};
    double wsum = 0.0;
    for (int k = 0; k < used; ++k) {
        w[k] = reach > 0.0f ? std::max(0.0, 1.0 - std::sqrt(double(best[k].d2)) / reach)
                            : 0.0;
        wsum += w[k];
    }
    if (!(wsum > 0.0)) { // all at the same distance: plain mean
        for (int k = 0; k < used; ++k) w[k] = 1.0;
        wsum = used;
    }
    for (int c = 0; c < data_size; ++c) {
        double acc = 0.0;
        for (int k = 0; k < used; ++k)
            acc += w[k] * data[std::size_t(best[k].index) * data_size + c];
        out[c] = float(acc / wsum);
    }
    return true;
}

bool PointCloudLookup::Impl::lookup_radius(const glm::vec3& p, const glm::vec3& n,
                                           bool use_normal, float radius,
                                           float* out) const {
    if (nodes.empty()) return false;
    const float r2 = radius * radius;
    std::vector<double> acc(std::size_t(data_size), 0.0);
    double wsum = 0.0;
    std::array<uint32_t, 128> stack;
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& node = nodes[stack[--top]];
        if (box_distance2(node, p) >= r2) continue;
        if (node.left != 0) {
            stack[top++] = node.left + 1;
            stack[top++] = node.left;
            continue;
        }
        for (uint32_t i = node.begin; i < node.end; ++i) {
            glm::vec3 d = positions[i] - p;
            float d2 = glm::dot(d, d);
            if (d2 >= r2 || (use_normal && !qualifies(i, n))) continue;
            double w = 1.0 - std::sqrt(double(d2)) / radius;
            wsum += w;
            const float* src = data.data() + std::size_t(i) * data_size;
            for (int c = 0; c < data_size; ++c) acc[c] += w * src[c];
        }
    }
    if (!(wsum > 0.0)) return lookup_nearest(p, n, use_normal, out);
    for (int c = 0; c < data_size; ++c) out[c] = float(acc[c] / wsum);
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
    float len = glm::length(n);
    bool use_normal = len > 0.0f && std::isfinite(len);
    glm::vec3 un = use_normal ? n / len : glm::vec3(0.0f);
    bool ok = filter_radius > 0.0f && std::isfinite(filter_radius)
                  ? m_impl->lookup_radius(p, un, use_normal, filter_radius, out)
                  : m_impl->lookup_nearest(p, un, use_normal, out);
    if (!ok) std::fill(out, out + m_impl->data_size, 0.0f);
    return ok;
}

} // namespace sss
