// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file render_volumes.cpp
/// The shaders render runs besides the surfaces' (docs/render.md, "Volume
/// and imager shaders"): a primitive's Atmosphere on the camera rays that hit
/// it, after its surface shader, and the Imager on every final pixel, after
/// the pixel filter and before the Displays' exposure and quantisation.

#include "render_internal.h"

namespace sss::render_detail {

void run_atmosphere(Renderer& job, ShadingContext& context, const ShaderInstance& shader,
                    ShadingBatch& surface, std::size_t stride, LightList lights) {
    const std::size_t n = stride > 0 ? surface.size / stride : 0;
    if (n == 0) return;
    ShadingBatch batch;
    batch.size = n;
    batch.layout = BatchLayout::Points;
    batch.primitive = surface.primitive;
    batch.time = surface.time;
    batch.ray = surface.ray;
    batch.seed = detail::splitmix64(surface.seed ^ 0x61746D6F73706865ull);
    batch.ray_offset = surface.ray_offset;
    batch.self_distance = surface.self_distance;
    // The camera ray's end: P the hit, I from the ray's origin (the eye,
    // or the lens with depth of field), Ci and Oi as the surface left them.
    // N is the surface's, for the lights' shadow rays leaving P.
    for (auto* v : {&batch.P, &batch.I, &batch.N, &batch.Ng, &batch.Ci, &batch.Oi})
        v->resize(n);
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t i = k * stride;
        batch.P[k] = surface.P[i];
        batch.I[k] = surface.I[i];
        batch.N[k] = surface.N[i];
        batch.Ng[k] = surface.Ng[i];
        batch.Ci[k] = surface.Ci[i];
        batch.Oi[k] = surface.Oi[i];
    }
    context.execute(shader, batch, lights);
    job.nan_points += context.nonfinite_points();
    for (std::size_t k = 0; k < n; ++k) {
        surface.Ci[k * stride] = batch.Ci[k];
        surface.Oi[k * stride] = batch.Oi[k];
    }
}

void run_imager(Renderer& job, Image& image) {
    if (!job.shaders.imager) return;
    const ShaderInstance& shader = *job.shaders.imager;
    const int width = image.width;
    const std::size_t pixels = std::size_t(width) * std::size_t(image.height);
    constexpr std::size_t kBatch = 256;
    const std::size_t batches = (pixels + kBatch - 1) / kBatch;
    tbb::enumerable_thread_specific<std::unique_ptr<ShadingContext>> contexts(
        [&] { return std::make_unique<ShadingContext>(*job.resources, *job.services); });
    tbb::parallel_for(std::size_t(0), batches, [&](std::size_t b) {
        ShadingContext& context = *contexts.local();
        const std::size_t first = b * kBatch;
        const std::size_t n = std::min(kBatch, pixels - first);
        ShadingBatch batch;
        batch.size = n;
        batch.layout = BatchLayout::Points;
        batch.seed = detail::splitmix64(0x696D61676572ull + b);
        batch.P.resize(n);
        batch.Ci.resize(n);
        batch.Oi.resize(n);
        batch.alpha.resize(n);
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t p = first + k;
            const int x = static_cast<int>(p % std::size_t(width));
            const int y = static_cast<int>(p / std::size_t(width));
            const float* v = image.pixel(x, y);
            // P: the pixel's centre in raster space (pixels, y down), z 0.
            batch.P[k] = glm::vec3(float(x) + 0.5f, float(y) + 0.5f, 0.0f);
            batch.Ci[k] = glm::vec3(v[0], v[1], v[2]);
            batch.Oi[k] = glm::vec3(v[3]);
            batch.alpha[k] = v[3];
        }
        context.execute(shader, batch);
        job.nan_points += context.nonfinite_points();
        for (std::size_t k = 0; k < n; ++k) {
            const std::size_t p = first + k;
            float* v = image.pixel(static_cast<int>(p % std::size_t(width)),
                                   static_cast<int>(p / std::size_t(width)));
            for (int c = 0; c < 3; ++c) v[c] = batch.Ci[k][c];
            v[3] = batch.alpha[k];
        }
    });
}

} // namespace sss::render_detail
