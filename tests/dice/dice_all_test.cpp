// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_all_test.cpp
/// Tests of dice_all (sss/dice/dice.h): the same surfaces as dice_primitive
/// whatever the thread count, empty surfaces for primitives not requested,
/// the finish callback, and the first failure in request order as the error.
///
/// Suite names all start with "DiceAll".

#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <tbb/task_arena.h>

#include "sss/dice/dice.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"

namespace {

using sss::PrimitiveKind;

sss::Primitive make_prim(PrimitiveKind kind, std::vector<double> args,
                         const std::string& source) {
    sss::Primitive p;
    p.kind = kind;
    p.args = std::move(args);
    p.attributes = std::make_shared<sss::Attributes>();
    p.source = source;
    return p;
}

/// Spheres, tori and cones of several sizes, so that the tasks take
/// different times and finish out of order.
sss::Scene make_scene(int count) {
    sss::Scene scene;
    for (int i = 0; i < count; ++i) {
        const std::string source = "all.rib:" + std::to_string(i + 1);
        const double r = 0.5 + 0.25 * (i % 5);
        switch (i % 3) {
        case 0:
            scene.primitives.push_back(
                make_prim(PrimitiveKind::Sphere, {r, -r, r, 360.0}, source));
            break;
        case 1:
            scene.primitives.push_back(
                make_prim(PrimitiveKind::Torus, {r, 0.2, 0.0, 360.0, 360.0}, source));
            break;
        default:
            scene.primitives.push_back(
                make_prim(PrimitiveKind::Cone, {r, 0.5 * r, 300.0}, source));
            break;
        }
    }
    return scene;
}

std::vector<sss::DiceRequest> every_primitive(const sss::Scene& scene, double spacing) {
    std::vector<sss::DiceRequest> requests;
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        sss::DiceRequest r;
        r.primitive = i;
        r.control.spacing = spacing;
        requests.push_back(r);
    }
    return requests;
}

void expect_same(const sss::DicedSurface& a, const sss::DicedSurface& b) {
    EXPECT_EQ(a.centers, b.centers);
    EXPECT_EQ(a.normals, b.normals);
    EXPECT_EQ(a.areas, b.areas);
    EXPECT_EQ(a.radii, b.radii);
    EXPECT_EQ(a.colors, b.colors);
    EXPECT_EQ(a.vertices, b.vertices);
    EXPECT_EQ(a.vertex_normals, b.vertex_normals);
    EXPECT_EQ(a.triangles, b.triangles);
}

/// dice_all run inside an arena of `threads` threads.
template <class F>
auto with_threads(int threads, F&& f) {
    tbb::task_arena arena(threads);
    return arena.execute(f);
}

/// The message dice_all throws (ValueError), or "" when it does not.
std::string dice_all_error(const sss::Scene& scene,
                           const std::vector<sss::DiceRequest>& requests,
                           const sss::DiceFinish& finish = {}) {
    try {
        sss::dice_all(scene, requests, finish);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

TEST(DiceAll, SameSurfacesForOneAndTwoThreadsAsDicePrimitive) {
    const sss::Scene scene = make_scene(12);
    const auto requests = every_primitive(scene, 0.05);
    const auto one = with_threads(1, [&] { return sss::dice_all(scene, requests); });
    const auto two = with_threads(2, [&] { return sss::dice_all(scene, requests); });
    ASSERT_EQ(one.size(), scene.primitives.size());
    ASSERT_EQ(two.size(), scene.primitives.size());
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        SCOPED_TRACE(i);
        EXPECT_GT(one[i].size(), 0u);
        expect_same(one[i], two[i]);
        expect_same(one[i],
                    sss::dice_primitive(scene.primitives[i], requests[i].control));
    }
}

TEST(DiceAll, EachRequestHasItsOwnControlAndOthersStayEmpty) {
    const sss::Scene scene = make_scene(6);
    std::vector<sss::DiceRequest> requests(2);
    requests[0].primitive = 1;
    requests[0].control.spacing = 0.05;
    requests[1].primitive = 4;
    requests[1].control.spacing = 0.1;
    requests[1].control.coarsening = 2.0;
    const auto diced = sss::dice_all(scene, requests);
    ASSERT_EQ(diced.size(), scene.primitives.size());
    for (std::size_t i : {0u, 2u, 3u, 5u}) {
        EXPECT_EQ(diced[i].size(), 0u) << i;
        EXPECT_TRUE(diced[i].triangles.empty()) << i;
    }
    expect_same(diced[1], sss::dice_primitive(scene.primitives[1], requests[0].control));
    expect_same(diced[4], sss::dice_primitive(scene.primitives[4], requests[1].control));
}

TEST(DiceAll, FinishRunsOnceOnEverySurfaceItWasGiven) {
    const sss::Scene scene = make_scene(9);
    const auto requests = every_primitive(scene, 0.1);
    std::vector<std::atomic<int>> calls(scene.primitives.size());
    const auto diced =
        sss::dice_all(scene, requests, [&](std::size_t i, sss::DicedSurface& d) {
            ++calls[i];
            d.areas.assign(d.size(), static_cast<float>(i));
        });
    for (std::size_t i = 0; i < scene.primitives.size(); ++i) {
        EXPECT_EQ(calls[i].load(), 1) << i;
        for (float a : diced[i].areas) ASSERT_EQ(a, static_cast<float>(i)) << i;
    }
}

TEST(DiceAll, FirstFailureInRequestOrderIsTheError) {
    sss::Scene scene = make_scene(10);
    // Two bad primitives: whichever fails first in time, the earlier
    // request's message is the one thrown.
    scene.primitives[3].args[0] = -1.0; // Sphere: radius must be > 0
    scene.primitives[8].args[1] = 0.0;  // Cone: radius must be > 0
    const auto requests = every_primitive(scene, 0.02);
    const std::string want = "all.rib:4: Sphere: radius must be > 0";
    for (int threads : {1, 2}) {
        SCOPED_TRACE(threads);
        EXPECT_EQ(with_threads(threads, [&] { return dice_all_error(scene, requests); }),
                  want);
    }
    // Request order decides, not primitive order.
    std::vector<sss::DiceRequest> reversed(requests.rbegin(), requests.rend());
    EXPECT_EQ(dice_all_error(scene, reversed), "all.rib:9: Cone: radius must be > 0");
}

TEST(DiceAll, FinishFailuresCountLikeDicingFailures) {
    sss::Scene scene = make_scene(6);
    scene.primitives[4].args[0] = -1.0; // dicing fails at request 4
    const auto requests = every_primitive(scene, 0.1);
    const auto finish = [](std::size_t i, sss::DicedSurface&) {
        if (i == 2) throw std::runtime_error("finish failed on 2");
    };
    for (int threads : {1, 2}) {
        SCOPED_TRACE(threads);
        EXPECT_EQ(with_threads(threads,
                               [&] { return dice_all_error(scene, requests, finish); }),
                  "finish failed on 2");
    }
    // The failure keeps its type (a bad_alloc stays one, for "out of memory").
    EXPECT_THROW(sss::dice_all(scene, requests, finish), std::runtime_error);
}

} // namespace
