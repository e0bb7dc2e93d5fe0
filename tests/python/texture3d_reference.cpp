// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file texture3d_reference.cpp
/// The renderer's texture3d, for the Python module's tests to compare with
/// (tests/python/test_point_cloud_lookup.py):
///
///     sss_texture3d_reference TEXTURE QUERIES OUT CHANNEL...
///
/// looks the channels up in TEXTURE (a .ptc/.ply cloud or a brick map)
/// through sss::TextureLibrary::texture3d, the call render's shaders make, at
/// the points of QUERIES (a cloud: P, N, and radius as the filter radius),
/// and writes OUT: the queries' P, a float channel "_v<i>" per component of
/// the result and "_found" (1 or 0).

#include <cstdio>
#include <string>
#include <vector>

#include "sss/binding/texture_library.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/util/error.h"

int main(int argc, char** argv) {
    if (argc < 5) {
        std::fprintf(stderr, "usage: %s TEXTURE QUERIES OUT CHANNEL...\n", argv[0]);
        return 2;
    }
    try {
        const std::string texture = argv[1];
        const sss::PointCloud queries = sss::read_point_cloud(argv[2]);
        const std::vector<std::string> channels(argv + 4, argv + argc);
        const std::size_t n = queries.size();
        sss::TextureLibrary library;
        std::vector<int> floats;
        // Sized for 16 floats a channel (a matrix), the widest there is.
        std::vector<float> out(n * channels.size() * 16, 0.0f);
        std::vector<uint8_t> found(n, 0);
        std::string error;
        if (!library.texture3d(texture, channels, n, queries.positions.data(),
                               queries.normals.data(), queries.radii.data(), nullptr,
                               floats, out.data(), found.data(), &error) ||
            !error.empty()) {
            std::fprintf(stderr, "texture3d: %s\n", error.c_str());
            return 1;
        }
        int width = 0;
        for (int f : floats) width += f;
        sss::PointCloud result;
        result.resize(n);
        result.positions = queries.positions;
        for (int k = 0; k < width; ++k)
            result.add_channel("_v" + std::to_string(k), sss::ChannelType::Float);
        result.add_channel("_found", sss::ChannelType::Float);
        for (std::size_t i = 0; i < n; ++i) {
            for (int k = 0; k < width; ++k)
                result.channels[std::size_t(k)].data[i] = out[i * std::size_t(width) + k];
            result.channels.back().data[i] = found[i] ? 1.0f : 0.0f;
        }
        sss::write_point_cloud(result, argv[3]);
    } catch (const sss::Error& e) {
        std::fprintf(stderr, "texture3d_reference ERROR: %s\n", e.what());
        return 1;
    }
    return 0;
}
