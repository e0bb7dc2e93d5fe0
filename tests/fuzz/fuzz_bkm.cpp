// libFuzzer target: opening a .bkm brick map (header, channel table, node
// tables), then lookups, brick reads and occupancy reads, which load and
// validate bricks on demand, and verify(), which reads them all.
// docs/fuzzing.md.

#include <cmath>
#include <vector>

#include <glm/vec3.hpp>

#include "fuzz_common.h"
#include "sss/brick/brickmap.h"

namespace {

void exercise(const sss::BrickMap& map) {
    const sss::BrickMapInfo& info = map.info();
    using sss::fuzz::require;
    require(info.data_size >= 1 && !info.channels.empty(), "empty channel list");
    int sum = 0;
    for (const auto& [name, type] : info.channels) {
        require(map.channel_offset(name) == sum, "channel offsets disagree");
        sum += sss::channel_type_size(type);
    }
    require(sum == info.data_size, "channel sizes do not add up");

    // Lookups over the root cube, with each tree's normal and none, at the
    // finest level, a middle one and the root.
    std::vector<float> out(static_cast<std::size_t>(info.data_size));
    const glm::vec3 normals[] = {{0, 0, 0},  {1, 0, 0}, {-1, 0, 0}, {0, 1, 0},
                                 {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0.6f, 0.0f, 0.8f}};
    const float radii[] = {0.0f, static_cast<float>(info.cube_side / 64),
                           static_cast<float>(info.cube_side)};
    const double fractions[] = {0.0, 0.31, 0.5, 0.77, 1.0, 1.3};
    for (double f : fractions) {
        const glm::vec3 p(info.cube_min +
                          glm::dvec3(f, 1.0 - f, f * 0.5) * info.cube_side);
        for (const glm::vec3& n : normals) {
            for (float r : radii) {
                if (map.lookup(p, n, r, out.data())) {
                    for (float v : out) require(!std::isnan(v), "NaN from a lookup");
                }
            }
        }
    }

    // Every brick of the first levels, directly from the file.
    std::vector<float> data;
    std::vector<uint8_t> present;
    int reads = 0;
    for (int tree = 0; tree < 7; ++tree) {
        for (int depth = 0; depth < static_cast<int>(info.levels.size()); ++depth) {
            for (const auto& c : map.bricks_at(tree, depth)) {
                if (++reads > 64) return;
                require(map.read_brick(tree, depth, c[0], c[1], c[2], data, present),
                        "bricks_at lists a brick read_brick cannot find");
                require(data.size() == 512u * static_cast<std::size_t>(info.data_size) &&
                            present.size() == 512,
                        "read_brick sizes");
                map.read_occupancy(tree, depth, c[0] / 2, c[1] / 2, c[2] / 2, present);
            }
        }
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const sss::fuzz::ScratchFile in("bkm_in", ".bkm");
    // The header records the file size (offset 16), which almost every
    // length-changing mutation breaks: the target sets it to the real size so
    // that such inputs get past that check into the tables and bricks. For
    // the same reason the map is opened without comparing checksums (every
    // mutation would fail them): the structural checks all still run. (The
    // size and checksum checks themselves are covered by the unit tests:
    // brickmap_test.cpp, bkm_integrity_test.cpp, reader_sweep_test.cpp.)
    std::vector<uint8_t> bytes(data, data + size);
    if (bytes.size() >= 24) {
        for (int i = 0; i < 8; ++i)
            bytes[16 + i] = static_cast<uint8_t>(uint64_t(bytes.size()) >> (8 * i));
    }
    in.write(bytes.data(), bytes.size());
    sss::fuzz::run_expecting_errors([&] {
        // A small cache, so that bricks are also evicted and read again.
        const sss::BrickMap map(in.path(), 64 << 10, sss::BrickMapChecksums::Ignore);
        exercise(map);
        map.verify(); // every brick, in file order
    });
    return 0;
}
