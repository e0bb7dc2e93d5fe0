// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file cancel_test.cpp
/// A program embedding the library cancels a diffusion run from its progress
/// callback by returning false, without throwing anything itself.

#include <gtest/gtest.h>

#include <cstdint>

#include "sss/cloud/synthetic.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/error.h"
#include "sss/util/progress.h"

namespace {

sss::PointCloud sphere(std::size_t n) {
    sss::SyntheticParams sp;
    sp.shape = sss::SyntheticShape::Sphere;
    sp.count = n;
    sp.size = 1.0;
    return sss::make_synthetic_cloud(sp);
}

sss::SsDiffusionOptions skin1(sss::Progress* progress) {
    sss::SsDiffusionOptions options;
    options.material.preset = "skin1";
    options.material.unitlength = 0.1;
    options.diffusion.progress = progress;
    return options;
}

} // namespace

TEST(DiffusionCancel, CallbackReturningFalseStopsTheRun) {
    const sss::PointCloud cloud = sphere(20000);
    sss::Progress progress(false);
    int calls = 0;
    uint64_t last_done = 0, last_total = 0;
    progress.set_callback([&](uint64_t done, uint64_t total) {
        ++calls;
        last_done = done;
        last_total = total;
        return done * 10 < total * 3; // cancel from 30 %
    });
    EXPECT_THROW(sss::ssdiffusion(cloud, skin1(&progress)), sss::Cancelled);
    ASSERT_GT(calls, 1);
    // It stopped at the first step at or past 30 %, not at the end.
    EXPECT_GE(last_done * 10, last_total * 3);
    EXPECT_LT(last_done * 10, last_total * 5);
}

TEST(DiffusionCancel, CallbackReturningTrueRunsToTheEnd) {
    const sss::PointCloud cloud = sphere(5000);
    sss::Progress progress(false);
    uint64_t last_done = 0, last_total = 1;
    progress.set_callback([&](uint64_t done, uint64_t total) {
        last_done = done;
        last_total = total;
        return true;
    });
    const sss::PointCloud out = sss::ssdiffusion(cloud, skin1(&progress));
    EXPECT_EQ(out.size(), cloud.size());
    EXPECT_EQ(last_done, last_total);
}
