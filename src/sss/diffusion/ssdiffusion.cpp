// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file ssdiffusion.cpp
/// The ptfilter -ssdiffusion job in phases: the cloud read into a problem in mm,
/// the materials as (quantised) profiles, the evaluation, the output cloud.

#include "sss/diffusion/ssdiffusion.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>

#include <sys/stat.h>

#include <glm/common.hpp>
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>

#include "ssdiffusion_volume.h"
#include "sss/util/error.h"
#include "sss/util/limits.h"
#include "sss/util/math.h"
#include "sss/util/parse.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"

namespace sss {

namespace {

// Albedo at or above 1 is clamped here (with one warning), as PRMan does at 0.999.
constexpr double kMaxAlbedo = 0.99999;
// Per-point materials share profile tables: at most this many distinct ones.
// Each point's result is then scaled by its own albedo over its table's
// (DiffusionProblem::receiver_gain), so that what the sharing leaves is the
// small change of the profile's shape across a quantisation step. Every
// profile costs time where it meets others (its own local expansions and
// bounds) and in the set-up; 128 keeps a painted 1M-point cloud within 1.5
// times one material's time (docs/ptfilter.md).
constexpr std::size_t kMaxDistinctProfiles = 128;
// The quantisation levels: the finest has the mean free path in 2^(1/1024)
// steps and the albedo in 1/4096; each coarser level doubles the albedo's
// step and the mean free path's in turn (the count of distinct values falls
// about twofold a level), down to one step per octave and quarters of albedo.
// The profile's shape changes with the mean free path's scale, its total
// (which the gain restores) with the albedo, so albedo steps are two to four
// times as coarse relative to their effect.
struct QuantisationLevel {
    int albedo_steps, dmfp_steps;
};
constexpr int kLastLevel = 20;
QuantisationLevel quantisation_level(int level) {
    return {4096 >> ((level + 1) / 2), 1024 >> (level / 2)};
}

// x rounded to the nearest integer (llround's libm call was a tenth of the
// quantisation's time).
int64_t nearest(double x) {
    const double y = x + 0.5;
    const int64_t t = int64_t(y);
    return double(t) > y ? t - 1 : t;
}

// Per-point albedo quantisation: steps of 1/albedo_steps, except below 2^-8,
// where such a step is a large fraction of the value: there a + 2^-24 keeps
// log2(albedo_steps) - 8 significant bits (at least one). Small albedos get
// negative keys.
constexpr double kSmallAlbedo = 1.0 / 256.0, kTinyAlbedo = 1.0 / 16777216.0;
int small_albedo_drop(int albedo_steps) {
    int bits = std::max(1, int(std::bit_width(unsigned(albedo_steps))) - 1 - 8);
    return 23 - bits;
}
int64_t albedo_key(double a, int albedo_steps) {
    if (a >= kSmallAlbedo) return nearest(a * albedo_steps);
    const int drop = small_albedo_drop(albedo_steps);
    uint32_t b = std::bit_cast<uint32_t>(float(a + kTinyAlbedo));
    return -1 - int64_t((b + (1u << (drop - 1))) >> drop);
}
double albedo_of_key(int64_t key, int albedo_steps) {
    if (key >= 0) return std::min(double(key) / albedo_steps, kMaxAlbedo);
    uint32_t b = uint32_t(-1 - key) << small_albedo_drop(albedo_steps);
    return std::max(0.0, double(std::bit_cast<float>(b)) - kTinyAlbedo);
}

std::string fmt3(const glm::dvec3& v) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "%.6g %.6g %.6g", v.x, v.y, v.z);
    return buf;
}

const Channel& require_channel(const PointCloud& cloud, const std::string& name,
                               int components, MissingChannelError::Role role) {
    const Channel* c = cloud.find_channel(name);
    if (!c) {
        std::string have;
        for (const Channel& ch : cloud.channels)
            have += (have.empty() ? "" : ", ") + std::string(channel_type_name(ch.type)) +
                    " " + ch.name;
        throw MissingChannelError(role, name, have.empty() ? "none" : have);
    }
    if (c->components() != components)
        throw ValueError("channel '" + name + "' is " + channel_type_name(c->type) +
                         ", expected " + (components == 1 ? "float" : "color"));
    return *c;
}

// The constant (whole-cloud) channel profiles, with lengths in units of
// 1/u mm (u = unitlength: scene units; u = 1: mm).
std::vector<Profile> constant_profiles(const SsDiffusionOptions& o, double u) {
    const MaterialSpec& m = o.material;
    m.validate();
    const double ior = m.resolved_ior();
    std::vector<Profile> out;
    if (m.uses_albedo_form()) {
        glm::dvec3 albedo, dmfp;
        m.resolve_albedo_dmfp(albedo, dmfp);
        for (int ch = 0; ch < 3; ++ch)
            out.push_back(Profile::from_albedo_dmfp(
                o.profile, std::min(albedo[ch], kMaxAlbedo), dmfp[ch] * u, ior));
    } else {
        glm::dvec3 ss, sa;
        m.resolve_coefficients(ss, sa);
        for (int ch = 0; ch < 3; ++ch)
            out.push_back(
                Profile::from_coefficients(o.profile, {ss[ch] / u, sa[ch] / u, ior}));
    }
    return out;
}

} // namespace

std::vector<std::string> describe_material(const SsDiffusionOptions& o) {
    const MaterialSpec& m = o.material;
    std::vector<Profile> p = constant_profiles(o, m.unitlength);
    std::vector<std::string> lines;
    std::string source = m.uses_albedo_form()             ? "albedo/diffusemeanfreepath"
                         : (m.scattering || m.absorption) ? "scattering/absorption"
                                                          : "material " + m.preset;
    lines.push_back("material: " + source + ", profile " + profile_kind_name(o.profile) +
                    ", unitlength " + std::to_string(m.unitlength));
    glm::dvec3 albedo, dmfp, ss, sa;
    for (int ch = 0; ch < 3; ++ch) {
        albedo[ch] = p[ch].total();
        dmfp[ch] = p[ch].dmfp();
        ss[ch] = p[ch].alpha_prime() * p[ch].sigma_t_prime();
        sa[ch] = p[ch].sigma_t_prime() - ss[ch];
    }
    lines.push_back("  albedo " + fmt3(albedo) +
                    (m.albedo_from_file ? " (per point from file)" : ""));
    lines.push_back("  diffusemeanfreepath " + fmt3(dmfp) + " (scene units)" +
                    (m.dmfp_from_file ? " (per point from file)" : ""));
    if (o.profile != ProfileKind::Burley) {
        lines.push_back("  scattering (sigma_s') " + fmt3(ss) + " (1/scene unit)");
        lines.push_back("  absorption (sigma_a) " + fmt3(sa) + " (1/scene unit)");
    }
    lines.push_back("  ior " + std::to_string(m.resolved_ior()));
    return lines;
}

namespace {

// The points as a diffusion problem in mm (positions, normals, areas,
// irradiance), a cloud or chunk of one at a time (the streamed job reads its
// inputs in chunks); finish() checks the channels as a whole cloud.
//
// The diffusion is evaluated in mm, the material's own unit, not in scene
// units: its profile tables are floats whose entries go as powers of the
// material's lengths (R ~ 1/l^2, its r^2-derivatives up to ~1/l^8), which
// overflowed or underflowed for marble (dmfp 4-8.5 mm) at -unitlength below
// ~1e-6 or above ~1e5: a cm scene scaled by 1e-5 or 3e6. In mm, real
// materials' lengths are 0.01 to 100 and sum R A E is the same (R A has no
// unit), so the result does not depend on the scene's scale.
class ProblemReader {
public:
    // `header`: the whole (merged) cloud's channels, with or without data.
    ProblemReader(const PointCloud& header, const SsDiffusionOptions& o)
        : m_o(o), m_to_mm(1.0 / o.material.unitlength),
          m_area(header.find_channel(o.area_channel)),
          m_radiance(header.find_channel(o.radiance_channel)) {}

    void reserve(std::size_t n) {
        m_pb.positions.reserve(n);
        m_pb.normals.reserve(n);
        m_pb.areas.reserve(n);
        m_pb.irradiance.reserve(n);
    }

    // Appends the first k points of `chunk` (its channels as the header's, or
    // absent: zeros).
    void add(const PointCloud& chunk, std::size_t k) {
        const std::size_t base = m_pb.positions.size();
        m_pb.positions.resize(base + k);
        m_pb.normals.insert(m_pb.normals.end(), chunk.normals.begin(),
                            chunk.normals.begin() + std::ptrdiff_t(k));
        // Area: the explicit channel, else the disk of the stored radius.
        const bool area_channel = m_area && m_area->components() == 1;
        const Channel* a = area_channel ? chunk.find_channel(m_o.area_channel) : nullptr;
        if (area_channel || !m_area) m_pb.areas.resize(base + k);
        const bool radiance = m_radiance && m_radiance->components() == 3;
        const Channel* e = radiance ? chunk.find_channel(m_o.radiance_channel) : nullptr;
        if (radiance) m_pb.irradiance.resize(base + k);
        // In parallel; the first impossible area is the one reported.
        std::atomic<std::size_t> bad{k};
        oneapi::tbb::parallel_for(
            oneapi::tbb::blocked_range<std::size_t>(0, k, 4096),
            [&](const oneapi::tbb::blocked_range<std::size_t>& range) {
                for (std::size_t j = range.begin(); j != range.end(); ++j) {
                    m_pb.positions[base + j] =
                        glm::vec3(glm::dvec3(chunk.positions[j]) * m_to_mm);
                    if (area_channel) {
                        const float v = a ? a->data[j] : 0.0f;
                        if (!(v >= 0.0f) || !std::isfinite(v)) lower_to(bad, j);
                        m_pb.areas[base + j] = float(v * m_to_mm * m_to_mm);
                    } else if (!m_area) {
                        const float r = chunk.radii[j];
                        m_pb.areas[base + j] = float(kPi * (r * m_to_mm) * (r * m_to_mm));
                    }
                    if (radiance)
                        m_pb.irradiance[base + j] =
                            e ? glm::vec3(e->data[3 * j], e->data[3 * j + 1],
                                          e->data[3 * j + 2])
                              : glm::vec3(0.0f);
                }
            });
        if (bad.load() < k && !m_bad_area)
            m_bad_area.emplace(base + bad.load(), a->data[bad.load()]);
    }

    std::size_t size() const { return m_pb.positions.size(); }

    // The channel checks, in the order they always had (type of the area
    // channel, the first impossible area, the radiance channel), and the
    // problem.
    DiffusionProblem finish(const PointCloud& header, SsDiffusionReport& rep) {
        const std::size_t n = size();
        if (m_area || n == 0) {
            if (m_area && m_area->components() != 1)
                throw ValueError("channel '" + m_o.area_channel + "' is " +
                                 channel_type_name(m_area->type) + ", expected float");
            if (m_bad_area)
                throw ValueError("channel '" + m_o.area_channel +
                                 "': negative or invalid area " +
                                 std::to_string(m_bad_area->second) + " at point " +
                                 std::to_string(m_bad_area->first));
        } else {
            rep.warnings.push_back("no '" + m_o.area_channel +
                                   "' channel: using pi * radius^2 as each point's area");
        }
        if (n > 0)
            require_channel(header, m_o.radiance_channel, 3,
                            MissingChannelError::Role::Radiance);
        m_pb.areas.resize(n);      // n == 0: the unread area channel
        m_pb.irradiance.resize(n); // n == 0 only: the channel is required otherwise
        return std::move(m_pb);
    }

private:
    const SsDiffusionOptions& m_o;
    const double m_to_mm;
    const Channel* m_area;     // in the header
    const Channel* m_radiance; // in the header
    DiffusionProblem m_pb;
    std::optional<std::pair<std::size_t, float>> m_bad_area; // the first one
};

// A whole cloud's points as a diffusion problem in mm, the channels checked.
DiffusionProblem read_points(const PointCloud& in, const SsDiffusionOptions& o,
                             SsDiffusionReport& rep) {
    ProblemReader reader(in, o);
    reader.reserve(in.size());
    reader.add(in, in.size());
    return reader.finish(in, rep);
}

// Where the per-point material values come from: a channel, else the
// constant material's value.
struct PointMaterialSource {
    const Channel* albedo = nullptr;
    const Channel* dmfp = nullptr;
    glm::dvec3 albedo0, dmfp0;
    const SsDiffusionOptions* options = nullptr;

    // Point i's albedo (clamped below 1; `clamped` notes it) and mean free
    // path in channel ch; false when either is impossible.
    bool checked_values(std::size_t i, int ch, double& a, double& d,
                        bool& clamped) const {
        a = albedo ? albedo->data[3 * i + ch] : albedo0[ch];
        d = dmfp ? dmfp->data[3 * i + ch] : dmfp0[ch];
        if (!(a >= 0.0) || !std::isfinite(a) || !(d > 0.0) || !std::isfinite(d))
            return false;
        if (a > kMaxAlbedo) a = kMaxAlbedo, clamped = true;
        return true;
    }
    // Throws the error of point i's first impossible value, if any.
    void check_point(std::size_t i) const {
        for (int c = 0; c < 3; ++c) {
            double a, d;
            bool clamped = false;
            if (checked_values(i, c, a, d, clamped)) continue;
            if (!(a >= 0.0) || !std::isfinite(a))
                throw ValueError("channel '" + options->albedo_channel +
                                 "': impossible albedo " + std::to_string(a) +
                                 " at point " + std::to_string(i));
            throw ValueError("channel '" + options->dmfp_channel +
                             "': diffuse mean free path must be positive, got " +
                             std::to_string(d) + " at point " + std::to_string(i));
        }
    }
};

// The distinct (albedo, dmfp) keys of one quantisation level and their
// indices, in the order first met: open addressing in a table four times
// the largest count (a level that would pass it is abandoned).
class MaterialKeys {
public:
    explicit MaterialKeys(std::size_t most)
        : m_most(most), m_slots(std::bit_ceil(4 * most + 4), kEmpty) {}
    // The key's index, added if new; kFull when it would be one too many.
    uint32_t find_or_add(int64_t ka, int64_t kd) {
        const std::size_t mask = m_slots.size() - 1;
        uint64_t h =
            uint64_t(ka) * 0x9E3779B97F4A7C15ull ^ uint64_t(kd) * 0xC2B2AE3D27D4EB4Full;
        for (std::size_t at = std::size_t(h >> 40) & mask;; at = (at + 1) & mask) {
            const uint32_t k = m_slots[at];
            if (k == kEmpty) {
                if (m_keys.size() >= m_most) return kFull;
                m_slots[at] = uint32_t(m_keys.size());
                m_keys.push_back({ka, kd});
                return m_slots[at];
            }
            if (m_keys[k].first == ka && m_keys[k].second == kd) return k;
        }
    }
    const std::vector<std::pair<int64_t, int64_t>>& keys() const { return m_keys; }
    static constexpr uint32_t kFull = UINT32_MAX - 1;

private:
    static constexpr uint32_t kEmpty = UINT32_MAX;
    std::size_t m_most;
    std::vector<uint32_t> m_slots;
    std::vector<std::pair<int64_t, int64_t>> m_keys;
};

// One quantisation level of the per-point materials: sets pb.profile_index,
// pb.receiver_gain (each point's albedo over its profile's: the albedo is
// the profile's total reflectance, every kind is made so from it), the
// distinct keys and each one's albedo. False when there would be more keys
// than `keys` holds. In parallel over fixed chunks of points whose own keys,
// joined in chunk order, are the keys in the order first met: the same
// profiles, indices and errors whatever the thread count.
bool quantise_materials(const PointMaterialSource& src, int albedo_steps, int dmfp_steps,
                        std::size_t most, DiffusionProblem& pb, MaterialKeys& keys,
                        std::vector<double>& key_albedo, bool& clamped) {
    const std::size_t n = pb.positions.size();
    constexpr std::size_t kChunk = 16384;
    key_albedo.clear();
    struct Chunk {
        std::optional<MaterialKeys> keys;
        std::vector<uint32_t> global; // local key -> keys' index
        bool full = false, clamped = false;
        // The first point with an impossible value (the chunk stops there).
        std::size_t bad = SIZE_MAX;
    };
    std::vector<Chunk> chunks((n + kChunk - 1) / kChunk);
    pb.profile_index.resize(n);
    pb.receiver_gain.resize(n);
    oneapi::tbb::parallel_for(std::size_t(0), chunks.size(), [&](std::size_t c) {
        Chunk& ck = chunks[c];
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        ck.keys.emplace(std::min(most, 3 * kChunk));
        for (std::size_t i = c * kChunk; i < end && !ck.full && ck.bad == SIZE_MAX; ++i)
            for (int ch = 0; ch < 3; ++ch) {
                double a, d;
                if (!src.checked_values(i, ch, a, d, ck.clamped)) {
                    ck.bad = i;
                    break;
                }
                const uint32_t k =
                    ck.keys->find_or_add(albedo_key(a, albedo_steps),
                                         nearest(std::log2(d) * double(dmfp_steps)));
                if (k == MaterialKeys::kFull) {
                    ck.full = true;
                    break;
                }
                pb.profile_index[i][ch] = k;
            }
    });
    // A coarser level first (every chunk then reads up to its first impossible
    // value, if any): the error names the first in the cloud's order.
    for (const Chunk& ck : chunks)
        if (ck.full) return false;
    for (const Chunk& ck : chunks) {
        if (ck.bad != SIZE_MAX) src.check_point(ck.bad); // throws its error
        clamped = clamped || ck.clamped;
    }
    for (Chunk& ck : chunks) {
        for (auto [ka, kd] : ck.keys->keys()) {
            const uint32_t k = keys.find_or_add(ka, kd);
            if (k == MaterialKeys::kFull) return false;
            if (k == key_albedo.size())
                key_albedo.push_back(albedo_of_key(ka, albedo_steps));
            ck.global.push_back(k);
        }
        ck.keys.reset();
    }
    oneapi::tbb::parallel_for(std::size_t(0), chunks.size(), [&](std::size_t c) {
        const std::size_t end = std::min(n, (c + 1) * kChunk);
        bool unused = false;
        for (std::size_t i = c * kChunk; i < end; ++i)
            for (int ch = 0; ch < 3; ++ch) {
                double a, d;
                src.checked_values(i, ch, a, d, unused);
                const uint32_t k = chunks[c].global[pb.profile_index[i][ch]];
                pb.profile_index[i][ch] = k;
                pb.receiver_gain[i][ch] =
                    key_albedo[k] > 0.0 ? float(a / key_albedo[k]) : 1.0f;
            }
    });
    return true;
}

// Whether the keys of every stride-th point fit `keys` at a level: a cheap
// first guess of the level (the whole cloud has at least as many).
bool sample_fits(const PointMaterialSource& src, std::size_t n, std::size_t stride,
                 int albedo_steps, int dmfp_steps, MaterialKeys& keys) {
    bool clamped = false;
    for (std::size_t i = 0; i < n; i += stride)
        for (int ch = 0; ch < 3; ++ch) {
            double a, d;
            // (The whole pass names the first impossible value.)
            if (!src.checked_values(i, ch, a, d, clamped)) return true;
            if (keys.find_or_add(albedo_key(a, albedo_steps),
                                 nearest(std::log2(d) * double(dmfp_steps))) ==
                MaterialKeys::kFull)
                return false;
        }
    return true;
}

// Per-point materials from the _albedo / _diffusemeanfreepath channels:
// pb.profiles, pb.profile_index and pb.receiver_gain.
void per_point_profiles(const PointCloud& in, const SsDiffusionOptions& o,
                        DiffusionProblem& pb, SsDiffusionReport& rep) {
    const MaterialSpec& m = o.material;
    PointMaterialSource src;
    src.options = &o;
    src.albedo = m.albedo_from_file ? &require_channel(in, o.albedo_channel, 3,
                                                       MissingChannelError::Role::Albedo)
                                    : nullptr;
    src.dmfp = m.dmfp_from_file ? &require_channel(in, o.dmfp_channel, 3,
                                                   MissingChannelError::Role::Dmfp)
                                : nullptr;
    m.resolve_albedo_dmfp(src.albedo0, src.dmfp0);
    const double ior = m.resolved_ior();
    bool clamped = false;
    // The finest level whose distinct profiles fit; the coarsest (one dmfp
    // step per octave, albedo in quarters) keeps every distinct value
    // rather than stopping half-way.
    std::vector<double> key_albedo;
    const std::size_t n = pb.positions.size();
    int level = 0;
    for (; level < kLastLevel; ++level) {
        MaterialKeys keys(kMaxDistinctProfiles);
        const QuantisationLevel q = quantisation_level(level);
        if (sample_fits(src, n, 61, q.albedo_steps, q.dmfp_steps, keys)) break;
    }
    for (;; ++level) {
        const int albedo_steps = quantisation_level(level).albedo_steps;
        const int dmfp_steps = quantisation_level(level).dmfp_steps;
        const bool last = level == kLastLevel;
        MaterialKeys keys(last ? 3 * n : kMaxDistinctProfiles);
        if (!quantise_materials(src, albedo_steps, dmfp_steps,
                                last ? SIZE_MAX : kMaxDistinctProfiles, pb, keys,
                                key_albedo, clamped))
            continue;
        pb.profiles.assign(keys.keys().size(), Profile{});
        oneapi::tbb::parallel_for(std::size_t(0), pb.profiles.size(), [&](std::size_t k) {
            pb.profiles[k] = Profile::from_albedo_dmfp(
                o.profile, key_albedo[k],
                std::exp2(double(keys.keys()[k].second) / dmfp_steps), ior); // in mm
        });
        rep.distinct_profiles = keys.keys().size();
        break;
    }
    if (std::all_of(pb.receiver_gain.begin(), pb.receiver_gain.end(),
                    [](const glm::vec3& g) { return g == glm::vec3(1.0f); }))
        pb.receiver_gain.clear();
    if (clamped)
        rep.warnings.push_back("albedo values >= 1 were clamped to " +
                               std::to_string(kMaxAlbedo));
}

// Material: constant, or per point from the _albedo / _diffusemeanfreepath channels.
// `in` holds the channels (the per-point material channels with their data);
// n is the number of points.
void assign_profiles(const PointCloud& in, std::size_t n, const SsDiffusionOptions& o,
                     DiffusionProblem& pb, SsDiffusionReport& rep) {
    const MaterialSpec& m = o.material;
    const std::vector<Profile> constant = constant_profiles(o, 1.0); // in mm
    if ((m.albedo_from_file || m.dmfp_from_file) && n > 0) {
        per_point_profiles(in, o, pb, rep);
    } else {
        pb.profiles = constant;
        rep.distinct_profiles = 3;
    }
}

// The diffusion at every point: all pairs with -exact, else the octree.
std::vector<glm::vec3> evaluate(const DiffusionProblem& pb, const SsDiffusionOptions& o,
                                SsDiffusionReport& rep) {
    const std::size_t n = pb.positions.size();
    std::vector<glm::vec3> result;
    if (o.exact) {
        ScopedStage stage("evaluating the diffusion (all pairs)");
        std::vector<glm::dvec3> exact =
            evaluate_diffusion_exact(pb, {}, o.diffusion.progress);
        result.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            glm::dvec3 v = exact[i];
            for (int ch = 0; ch < 3; ++ch)
                result[i][ch] = std::isfinite(v[ch]) ? float(v[ch]) : 0.0f;
        }
    } else {
        result = evaluate_diffusion(pb, o.diffusion, &rep.stats);
    }
    if (o.diffusion.progress) o.diffusion.progress->finish();
    return result;
}

// The output cloud: the input's points and header, the result as a color
// channel (after the input channels with keep_channels).
PointCloud output_cloud(const PointCloud& in, const SsDiffusionOptions& o,
                        const std::vector<glm::vec3>& result) {
    const std::size_t n = in.size();
    PointCloud out = in.points_only();
    if (o.keep_channels)
        for (const Channel& c : in.channels)
            if (c.name != o.output_channel) out.channels.push_back(c);
    Channel& dst = out.add_channel(o.output_channel, ChannelType::Color);
    dst.data.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i)
        for (int ch = 0; ch < 3; ++ch) dst.data[3 * i + ch] = result[i][ch];
    return out;
}

// The output records of some points (points[k] gets result[k]): what
// output_cloud() holds at those indices, with the same header and channels.
PointCloud output_points(const PointCloud& in, const SsDiffusionOptions& o,
                         const std::vector<uint32_t>& points,
                         const std::vector<glm::vec3>& result) {
    const std::size_t m = points.size();
    PointCloud out;
    out.positions.resize(m);
    out.normals.resize(m);
    out.radii.resize(m);
    for (std::size_t k = 0; k < m; ++k) {
        out.positions[k] = in.positions[points[k]];
        out.normals[k] = in.normals[points[k]];
        out.radii[k] = in.radii[points[k]];
    }
    out.world_to_eye = in.world_to_eye;
    out.world_to_ndc = in.world_to_ndc;
    out.format = in.format;
    if (o.keep_channels)
        for (const Channel& c : in.channels) {
            if (c.name == o.output_channel) continue;
            Channel kept{c.name, c.type, {}};
            const std::size_t w = std::size_t(c.components());
            kept.data.resize(w * m);
            for (std::size_t k = 0; k < m; ++k)
                std::copy_n(c.data.begin() + std::ptrdiff_t(w * points[k]), w,
                            kept.data.begin() + std::ptrdiff_t(w * k));
            out.channels.push_back(std::move(kept));
        }
    Channel& dst = out.add_channel(o.output_channel, ChannelType::Color);
    dst.data.resize(3 * m);
    for (std::size_t k = 0; k < m; ++k)
        for (int ch = 0; ch < 3; ++ch) dst.data[3 * k + ch] = result[k][ch];
    return out;
}

// What stays fixed while a file is the same: compared before it is read again.
struct FileIdentity {
    dev_t device = 0;
    ino_t inode = 0;
    off_t size = 0;
    int64_t mtime_ns = 0;
    bool operator==(const FileIdentity&) const = default;
};

FileIdentity identify(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        const int err = errno;
        throw IoError(path, std::string("cannot open: ") + std::strerror(err), err);
    }
    return {st.st_dev, st.st_ino, st.st_size,
            int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec};
}

// What the filter holds per point at its peak, the evaluation's (the octree's
// nodes and expansions, the sorted sources, the results; measured: 95-105
// bytes on spheres, tests/cli/test_ptfilter_memory.sh), with room for a
// denser octree.
constexpr uint64_t kFilterBytesPerPoint = 130;

// OutOfMemoryError, before anything is read, when the filter of `points`
// points (and `extra` bytes per point: per-point materials) cannot fit.
void check_filter_memory(uint64_t points, uint64_t extra, const std::string& inputs) {
    const uint64_t per_point = kFilterBytesPerPoint + extra;
    const uint64_t bytes =
        points > UINT64_MAX / per_point ? UINT64_MAX : points * per_point;
    check_memory(bytes,
                 "filtering the " + std::to_string(points) + " points of " + inputs,
                 "filter fewer points at once, or run it where more memory is available");
}

// Points per chunk of the streamed reads and writes (a few MB of buffers).
constexpr std::size_t kChunkPoints = std::size_t(1) << 16;

// Appends the values of channel `name` of a chunk of `points` points to `out`
// (`width` zeros per point when the chunk's input lacks it, as
// PointCloud::append fills).
void append_channel(const PointCloud& chunk, std::size_t points, const std::string& name,
                    std::size_t width, std::vector<float>& out) {
    const Channel* c = chunk.find_channel(name);
    if (c) {
        out.insert(out.end(), c->data.begin(), c->data.end());
    } else {
        out.resize(out.size() + width * points, 0.0f);
    }
}

} // namespace

struct SsDiffusionFiles::Input {
    std::string path;
    std::unique_ptr<PointCloudReader> reader; // open from the constructor to filter()
    FileIdentity identity;
    std::size_t points = 0;
};

SsDiffusionFiles::SsDiffusionFiles(std::vector<std::string> inputs,
                                   SsDiffusionOptions options)
    : m_paths(std::move(inputs)), m_options(std::move(options)) {
    for (std::size_t i = 0; i < m_paths.size(); ++i) {
        ScopedStage stage("reading " + m_paths[i]);
        Input in;
        in.path = m_paths[i];
        in.identity = identify(in.path);
        in.reader = std::make_unique<PointCloudReader>(in.path);
        const PointCloud& h = in.reader->header();
        if (i == 0) {
            m_merged = h;
        } else {
            // PointCloud::append's channel rules: matched by name and type.
            PointCloud other = h;
            m_merged.append(other);
        }
        m_inputs.push_back(std::move(in));
    }
}

SsDiffusionFiles::~SsDiffusionFiles() = default;

namespace {

// The summary of values[k] (the output's point index(k)): min, mean and max
// in fixed chunks combined in order (the same numbers at any thread count),
// and kSample points spread evenly.
template <class Index>
ValueSummary summarize_values(const std::vector<glm::vec3>& values, Index index) {
    constexpr std::size_t kSample = 8, kChunk = 1 << 16;
    ValueSummary out;
    const std::size_t n = values.size();
    out.count = n;
    if (n == 0) return out;
    struct Part {
        glm::dvec3 lo{0.0}, hi{0.0}, sum{0.0};
    };
    std::vector<Part> parts((n + kChunk - 1) / kChunk);
    oneapi::tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t c) {
        Part& p = parts[c];
        const std::size_t b = c * kChunk, e = std::min(n, b + kChunk);
        p.lo = p.hi = glm::dvec3(values[b]);
        for (std::size_t k = b; k < e; ++k) {
            const glm::dvec3 v(values[k]);
            p.lo = glm::min(p.lo, v);
            p.hi = glm::max(p.hi, v);
            p.sum += v;
        }
    });
    out.min = parts[0].lo;
    out.max = parts[0].hi;
    glm::dvec3 sum(0.0);
    for (const Part& p : parts) {
        out.min = glm::min(out.min, p.lo);
        out.max = glm::max(out.max, p.hi);
        sum += p.sum;
    }
    out.mean = sum / double(n);
    const std::size_t m = std::min(n, kSample);
    for (std::size_t i = 0; i < m; ++i) {
        const std::size_t k = m == 1 ? 0 : i * (n - 1) / (m - 1);
        out.sample.push_back({uint64_t(index(k)), values[k]});
    }
    // A part's points are in the octree's order: list them by index.
    std::sort(out.sample.begin(), out.sample.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    return out;
}

} // namespace

void SsDiffusionFiles::filter(SsDiffusionReport* report) {
    Stopwatch watch;
    const SsDiffusionOptions& o = m_options;
    SsDiffusionReport local;
    SsDiffusionReport& rep = report ? *report : local;
    rep.material_lines = describe_material(o);
    diffusion_detail::check_volume_options(o);
    const MaterialSpec& m = o.material;

    // Per-point materials: their channels with data, the others without.
    PointCloud materials = m_merged;
    std::vector<Channel*> material_channels;
    if (m.albedo_from_file || m.dmfp_from_file)
        for (Channel& c : materials.channels)
            if (((m.albedo_from_file && c.name == o.albedo_channel) ||
                 (m.dmfp_from_file && c.name == o.dmfp_channel)) &&
                c.components() == 3)
                material_channels.push_back(&c);

    ProblemReader points(m_merged, o);
    bool verified = true;
    uint64_t claimed = 0;
    for (const Input& in : m_inputs) {
        verified = verified && in.reader->size_verified();
        claimed += in.reader->size();
    }
    // Before reading: the headers' counts say what the filter will hold.
    // (Per-point materials: 12 bytes per channel read and 12 for the gains.)
    check_filter_memory(
        claimed, 12 * material_channels.size() + (material_channels.empty() ? 0 : 12),
        join(m_paths));
    if (verified) points.reserve(std::size_t(claimed));
    PointCloud chunk;
    for (Input& in : m_inputs) {
        ScopedStage stage("reading " + in.path);
        in.points = 0;
        while (std::size_t k = in.reader->read(chunk, kChunkPoints)) {
            for (std::size_t j = 0; j < k; ++j) {
                const glm::vec3& p = chunk.positions[j];
                if (points.size() + j == 0) m_bounds.lo = m_bounds.hi = p;
                m_bounds.lo = glm::min(m_bounds.lo, p);
                m_bounds.hi = glm::max(m_bounds.hi, p);
                m_max_radius = std::max(m_max_radius, chunk.radii[j]);
            }
            points.add(chunk, k);
            for (Channel* c : material_channels)
                append_channel(chunk, k, c->name, 3, c->data);
            in.points += k;
        }
    }
    chunk = PointCloud{};
    for (Input& in : m_inputs) in.reader.reset(); // close the inputs
    const std::size_t n = points.size();
    m_points = n;
    m_read_seconds = watch.seconds();
    DiffusionProblem pb = points.finish(m_merged, rep);
    assign_profiles(materials, n, o, pb, rep);
    materials = PointCloud{};
    diffusion_detail::VolumeInput volume = diffusion_detail::volume_input(pb, o);

    if (o.exact) {
        m_result = evaluate(pb, o, rep);
    } else {
        m_result = evaluate_diffusion(std::move(pb), o.diffusion, &rep.stats);
        if (o.diffusion.progress) o.diffusion.progress->finish();
    }
    diffusion_detail::apply_volume(o, std::move(volume), m_result, rep);
    if (report) rep.values = summarize_values(m_result, [](std::size_t k) { return k; });
    m_filtered = true;
    rep.seconds = watch.seconds();
}

void SsDiffusionFiles::write(const std::string& path,
                             const PointCloudWriteOptions& options) {
    if (!m_filtered) throw Error("internal error: SsDiffusionFiles::write before filter");
    const SsDiffusionOptions& o = m_options;
    // The output's header: output_cloud()'s channels.
    PointCloud header = m_merged;
    header.channels.clear();
    if (o.keep_channels)
        for (const Channel& c : m_merged.channels)
            if (c.name != o.output_channel) header.channels.push_back(c);
    header.add_channel(o.output_channel, ChannelType::Color);
    PointCloudWriter writer(path, header, m_points, m_bounds, m_max_radius, options);
    PointCloud chunk, out = header;
    std::size_t done = 0;
    for (const Input& in : m_inputs) {
        if (identify(in.path) != in.identity)
            throw IoError(in.path, "the input changed while it was being filtered");
        PointCloudReader reader(in.path);
        if (reader.size() != in.points)
            throw IoError(in.path, "the input changed while it was being filtered");
        while (std::size_t k = reader.read(chunk, kChunkPoints)) {
            out.positions.swap(chunk.positions);
            out.normals.swap(chunk.normals);
            out.radii.swap(chunk.radii);
            for (Channel& c : out.channels) {
                c.data.clear();
                if (c.name == o.output_channel) {
                    c.data.resize(3 * k);
                    for (std::size_t j = 0; j < k; ++j)
                        for (int ch = 0; ch < 3; ++ch)
                            c.data[3 * j + ch] = m_result[done + j][ch];
                } else {
                    append_channel(chunk, k, c.name, std::size_t(c.components()), c.data);
                }
            }
            writer.write(out);
            done += k;
        }
    }
    writer.commit();
}

PointCloud ssdiffusion(const PointCloud& in, const SsDiffusionOptions& o,
                       SsDiffusionReport* report) {
    Stopwatch watch;
    SsDiffusionReport local;
    SsDiffusionReport& rep = report ? *report : local;
    rep.material_lines = describe_material(o);
    diffusion_detail::check_volume_options(o);
    DiffusionProblem pb = read_points(in, o, rep);
    assign_profiles(in, in.size(), o, pb, rep);
    diffusion_detail::VolumeInput volume = diffusion_detail::volume_input(pb, o);
    std::vector<glm::vec3> result;
    if (o.exact) {
        result = evaluate(pb, o, rep);
    } else {
        result = evaluate_diffusion(std::move(pb), o.diffusion, &rep.stats);
        if (o.diffusion.progress) o.diffusion.progress->finish();
    }
    diffusion_detail::apply_volume(o, std::move(volume), result, rep);
    if (report) rep.values = summarize_values(result, [](std::size_t k) { return k; });
    PointCloud out = output_cloud(in, o, result);
    rep.seconds = watch.seconds();
    return out;
}

SsDiffusionPart ssdiffusion_part(PointCloud in, const SsDiffusionOptions& o,
                                 std::size_t part, std::size_t parts,
                                 SsDiffusionReport* report) {
    Stopwatch watch;
    SsDiffusionReport local;
    SsDiffusionReport& rep = report ? *report : local;
    rep.material_lines = describe_material(o);
    part_range(in.size(), part, parts); // validates part and parts first
    check_filter_memory(in.size(), 0, "the cloud");
    if (o.volume || !o.blockers.empty())
        throw ValueError(
            "the volume diffusion (-volume, -blocker) couples every point with "
            "every other through the volume: it cannot run in parts");
    DiffusionProblem pb = read_points(in, o, rep);
    assign_profiles(in, in.size(), o, pb, rep);
    SsDiffusionPart out;
    out.total = in.size();
    // The part's receivers in the octree's order; their output records are
    // taken now, so that the input cloud is freed before the octree is built
    // (a part holds the whole cloud once, in the problem and the octree).
    std::vector<uint32_t> receivers;
    {
        ScopedStage stage("sorting the points");
        std::vector<uint32_t> order = space_filling_order(pb);
        const auto [first, end] = part_range(order.size(), part, parts);
        out.first = first;
        receivers.assign(order.begin() + std::ptrdiff_t(first),
                         order.begin() + std::ptrdiff_t(end));
    }
    out.points =
        output_points(in, o, receivers, std::vector<glm::vec3>(receivers.size()));
    in = PointCloud{};
    std::vector<glm::vec3> result;
    if (o.exact) {
        ScopedStage stage("evaluating the diffusion (all pairs)");
        std::vector<std::size_t> wanted(receivers.begin(), receivers.end());
        std::vector<glm::dvec3> exact =
            wanted.empty() ? std::vector<glm::dvec3>{}
                           : evaluate_diffusion_exact(pb, wanted, o.diffusion.progress);
        result.resize(exact.size());
        for (std::size_t k = 0; k < exact.size(); ++k)
            for (int ch = 0; ch < 3; ++ch)
                result[k][ch] = std::isfinite(exact[k][ch]) ? float(exact[k][ch]) : 0.0f;
    } else {
        DiffusionPart dp =
            evaluate_diffusion_part(std::move(pb), o.diffusion, part, parts, &rep.stats);
        // The octree's order is the one computed above.
        if (dp.first != out.first || dp.receivers != receivers)
            throw Error("internal error: the part's receivers changed order");
        result = std::move(dp.result);
    }
    if (o.diffusion.progress) o.diffusion.progress->finish();
    out.indices.assign(receivers.begin(), receivers.end());
    if (report)
        rep.values =
            summarize_values(result, [&](std::size_t k) { return out.indices[k]; });
    Channel* dst = out.points.find_channel(o.output_channel);
    for (std::size_t k = 0; k < result.size(); ++k)
        for (int ch = 0; ch < 3; ++ch) dst->data[3 * k + ch] = result[k][ch];
    rep.seconds = watch.seconds();
    return out;
}

std::string ssdiffusion_signature(const SsDiffusionOptions& o) {
    // Every value as exact text (%a): two runs with the same signature compute
    // the same numbers from the same cloud.
    const MaterialSpec& m = o.material;
    std::string s = "ssdiffusion 1";
    auto add = [&](const char* key, const std::string& value) {
        s += std::string("; ") + key + "=" + value;
    };
    auto num = [](double v) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%a", v);
        return std::string(buf);
    };
    auto vec = [&](const std::optional<glm::dvec3>& v) {
        return v ? num(v->x) + " " + num(v->y) + " " + num(v->z) : std::string("-");
    };
    // The resolved material (whatever way it was given) and how it was given.
    for (const std::string& line : describe_material(o)) add("material", line);
    add("preset", m.preset);
    add("scattering", vec(m.scattering));
    add("absorption", vec(m.absorption));
    add("albedo", m.albedo_from_file ? "fromfile" : vec(m.albedo));
    add("dmfp", m.dmfp_from_file ? "fromfile" : vec(m.dmfp));
    add("ior", m.ior ? num(*m.ior) : "-");
    add("unitlength", num(m.unitlength));
    add("profile", profile_kind_name(o.profile));
    add("maxsolidangle", num(o.diffusion.max_solid_angle));
    add("criterion", criterion_name(o.diffusion.criterion));
    add("exact", o.exact ? "1" : "0");
    add("areachannel", o.area_channel);
    add("radiancechannel", o.radiance_channel);
    add("albedochannel", o.albedo_channel);
    add("dmfpchannel", o.dmfp_channel);
    add("outputchannel", o.output_channel);
    add("keepchannels", o.keep_channels ? "1" : "0");
    return s;
}

MissingChannelError::MissingChannelError(Role role, std::string channel,
                                         std::string present, std::string inputs)
    : ValueError((inputs.empty() ? "" : inputs + ": ") + "input has no channel '" +
                 channel + "' (channels present: " + present + ")"),
      m_role(role), m_channel(std::move(channel)), m_present(std::move(present)),
      m_inputs(std::move(inputs)) {}

} // namespace sss
