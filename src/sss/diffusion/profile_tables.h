// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file profile_tables.h
/// The channel profiles as float tables in q = r^2 (values, derivatives and the
/// running maxima the error criterion bounds with), and the tables a receiver
/// reads.

#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/ext/vector_uint3.hpp>

#include "sss/diffusion/diffusion.h"
#include "sss/diffusion/profile.h"

namespace sss::diffusion_detail {

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

// What the error criterion's walk reads at an entry, together (one cache
// line for a node's test).
struct TableBounds {
    float error_bound; // G(q): bound on the quadrupole remainder
    float max_value;   // max_{q' >= q} F(q')
    float max_d1;      // max_{q' >= q} |F'(q')|
    float max_d2;      // max_{q' >= q} |F''(q')|
};

struct ChannelTable {
    std::vector<TableEntry> entries;
    std::vector<TableBounds> bounds;
    float core2 = 0; // core length squared
};

// The tables of channels 0, 1 and 2 (what every receiver of a cloud with one
// material reads) interleaved, kRowFloats per entry k: three groups of eight
// floats, {F, F', F''} in turn, each {v0, s0, v1, s1, v2, s2, 0, 0} where v is
// the channel's value at entry k and s = value(k + 1) - value(k), the same
// float difference the interpolation takes. A block kernel reads a receiver's
// whole lookup in one to three 32-byte loads instead of 6 to 18 scattered
// floats.
constexpr int kRowFloats = 24;

// Per-point materials: every profile's table as rows of kProfileRowFloats
// per entry k, {F, dF, F', dF', F'', dF'', 0, 0} (d: value(k + 1) -
// value(k), as in the interleaved rows), so that each receiver of a block
// reads its own profile per channel with one 32-byte load.
constexpr int kProfileRowFloats = 8;

struct Tables {
    uint32_t bits0 = 0;
    uint32_t count = 0;
    std::vector<ChannelTable> channels;
    std::vector<float> rows; // channels 0-2 interleaved (empty with fewer channels)
    std::vector<float> profile_rows; // with per-point materials, profile p at p * count
    // With per-point materials: the bounds of classes of similar profiles
    // (error_bound and the running maxima, each the largest of its class's;
    // no entries), and each profile's class. A bucket's walk tests its nodes
    // against the few classes of its receivers instead of every profile.
    std::vector<ChannelTable> envelopes;
    std::vector<uint32_t> envelope_of;

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

// The distinct keys (table or class indices) met in a scan, each with its
// position in the caller's list: O(1) per key, reset in O(1) between scans.
class KeyPositions {
public:
    static constexpr uint32_t kNone = UINT32_MAX;
    void reset(std::size_t keys) {
        if (m_stamp.size() < keys) {
            m_stamp.assign(keys, 0);
            m_slot.assign(keys, 0);
        }
        if (++m_generation == 0) {
            std::fill(m_stamp.begin(), m_stamp.end(), 0u);
            m_generation = 1;
        }
    }
    uint32_t find(uint32_t key) const {
        return m_stamp[key] == m_generation ? m_slot[key] : kNone;
    }
    void set(uint32_t key, uint32_t position) {
        m_stamp[key] = m_generation;
        m_slot[key] = position;
    }

private:
    std::vector<uint32_t> m_stamp, m_slot;
    uint32_t m_generation = 0;
};

// Tables of every profile over one q range, from 1e-8 of the smallest core
// length squared out to where the widest profile has lost all but 1e-7.
// With `per_point`, also the profile rows.
Tables build_tables(const std::vector<Profile>& profiles, bool per_point = false);

// Per-point materials: for each material (a triple of profile indices), its
// three channels' {F, dF} interleaved as the one-material rows' first group
// ({v0, s0, v1, s1, v2, s2, 0, 0}, kProfileRowFloats per entry), so that a
// near pair reads a receiver's three channels with one load, as with one
// material. Empty when they would take more than kMaterialRowBytes.
constexpr uint64_t kMaterialRowBytes = uint64_t(64) << 20;
std::vector<float> material_near_rows(const Tables& tables,
                                      const std::vector<glm::u32vec3>& materials);

// The tables and profiles one receiver reads, per channel.
struct ReceiverChannels {
    const ChannelTable* table[3];
    const Profile* profile[3];
    float near_core2; // smallest core^2 of the three channels
    // The sampled profiles (pbd, mc): close source disks are taken as their
    // second-order means (kTaylorDisk2) rather than points or the quadrature.
    bool disk_means;
};

// Whether a receiver with these profiles takes close disks as their means.
inline bool uses_disk_means(const Profile* const profile[3]) {
    for (int ch = 0; ch < 3; ++ch)
        if (profile[ch]->kind() != ProfileKind::Pbd &&
            profile[ch]->kind() != ProfileKind::Mc)
            return false;
    return true;
}

// The channels of a receiver whose profiles are pb.profiles[idx[ch]].
inline ReceiverChannels receiver_channels(const DiffusionProblem& pb,
                                          const Tables& tables, glm::u32vec3 idx) {
    ReceiverChannels rc;
    float core2 = std::numeric_limits<float>::max();
    for (int ch = 0; ch < 3; ++ch) {
        rc.table[ch] = &tables.channels[idx[ch]];
        rc.profile[ch] = &pb.profiles[idx[ch]];
        core2 = std::min(core2, rc.table[ch]->core2);
    }
    rc.near_core2 = core2;
    rc.disk_means = uses_disk_means(rc.profile);
    return rc;
}

} // namespace sss::diffusion_detail
