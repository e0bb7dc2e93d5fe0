#pragma once
// The bake step the scene and engine targets share: bake_clouds of a scene,
// every cloud checked (fuzz_cloud.h) and written where its shader names it
// (in the scratch folder), so that the render after it can look it up.

#include <cstdio>

#include "fuzz_cloud.h"
#include "fuzz_common.h"
#include "sss/bake/bake.h"
#include "sss/cloud/point_cloud_io.h"

namespace sss::fuzz {

inline void bake_tiny(const Scene& scene) {
    BakeOptions options;
    BakeReport report;
    for (const auto& [path, cloud] : bake_clouds(scene, options, &report)) {
        check_cloud(cloud);
        if (verbose())
            std::fprintf(stderr, "baked %zu points into %s\n", cloud.size(),
                         path.c_str());
        write_point_cloud(cloud, path);
    }
}

} // namespace sss::fuzz
