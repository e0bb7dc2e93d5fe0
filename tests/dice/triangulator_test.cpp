// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file triangulator_test.cpp
/// Tests of the polygon triangulator (src/sss/dice/triangulator.h): for
/// simple polygons, with and without holes, small (linear scans) and large
/// (spatial indexes), the triangles are counter-clockwise, lie inside the
/// polygon and outside its holes, and their areas add up to the polygon's;
/// degenerate and self-intersecting input ends without error; and the
/// BoxIndex the large polygons use answers like a linear scan.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <set>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "../../src/sss/dice/triangulator.h"

namespace {

using glm::dvec2;
using Loops = std::vector<std::vector<dvec2>>;
using Triangles = std::vector<std::array<int, 3>>;

double signed_area(const std::vector<dvec2>& loop) {
    double a = 0.0;
    for (std::size_t i = 0; i < loop.size(); ++i) {
        const dvec2 &p = loop[i], &q = loop[(i + 1) % loop.size()];
        a += p.x * q.y - q.x * p.y;
    }
    return 0.5 * a;
}

double tri_area(const dvec2& a, const dvec2& b, const dvec2& c) {
    return 0.5 * ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
}

/// Even-odd point-in-loop test.
bool inside(const std::vector<dvec2>& loop, const dvec2& p) {
    bool in = false;
    for (std::size_t i = 0, j = loop.size() - 1; i < loop.size(); j = i++) {
        const dvec2 &a = loop[i], &b = loop[j];
        if ((a.y > p.y) != (b.y > p.y) &&
            p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x)
            in = !in;
    }
    return in;
}

struct Flat {
    std::vector<dvec2> points;
    std::vector<int> sizes;
};

Flat flatten(const Loops& loops) {
    Flat f;
    for (const auto& l : loops) {
        f.points.insert(f.points.end(), l.begin(), l.end());
        f.sizes.push_back(static_cast<int>(l.size()));
    }
    return f;
}

Triangles triangulate(const Loops& loops) {
    const Flat f = flatten(loops);
    Triangles out;
    sss::detail::Triangulator().run(f.points, f.sizes, out);
    return out;
}

/// A simple polygon (outer loop first, then holes inside it, in any
/// winding) is covered exactly: valid indices, counter-clockwise triangles
/// whose centroids lie inside the outer loop and outside every hole, n - 2 +
/// 2 * holes triangles, and areas that add up.
void expect_exact(const Loops& loops) {
    const Flat f = flatten(loops);
    Triangles out;
    sss::detail::Triangulator().run(f.points, f.sizes, out);
    double want = std::abs(signed_area(loops[0]));
    for (std::size_t l = 1; l < loops.size(); ++l)
        want -= std::abs(signed_area(loops[l]));
    EXPECT_EQ(out.size(), f.points.size() - 2 + 2 * (loops.size() - 1));
    double sum = 0.0;
    for (const auto& t : out) {
        for (int k : t) {
            ASSERT_GE(k, 0);
            ASSERT_LT(k, static_cast<int>(f.points.size()));
        }
        const dvec2 &a = f.points[t[0]], &b = f.points[t[1]], &c = f.points[t[2]];
        const double area = tri_area(a, b, c);
        ASSERT_GT(area, 0.0) << "clockwise or flat triangle";
        sum += area;
        const dvec2 centroid = (a + b + c) / 3.0;
        ASSERT_TRUE(inside(loops[0], centroid)) << centroid.x << " " << centroid.y;
        for (std::size_t l = 1; l < loops.size(); ++l)
            ASSERT_FALSE(inside(loops[l], centroid)) << "triangle in hole " << l;
    }
    EXPECT_NEAR(sum, want, 1e-9 * std::abs(signed_area(loops[0])));
}

std::vector<dvec2> circle(int n, double r, dvec2 centre = dvec2(0.0),
                          double phase = 0.0) {
    std::vector<dvec2> loop;
    for (int k = 0; k < n; ++k) {
        const double a = 2.0 * std::numbers::pi * k / n + phase;
        loop.emplace_back(centre.x + r * std::cos(a), centre.y + r * std::sin(a));
    }
    return loop;
}

std::vector<dvec2> star(int n, double r_out, double r_in) {
    std::vector<dvec2> loop;
    for (int k = 0; k < n; ++k) {
        const double a = 2.0 * std::numbers::pi * k / n;
        const double r = k % 2 ? r_in : r_out;
        loop.emplace_back(r * std::cos(a), r * std::sin(a));
    }
    return loop;
}

std::vector<dvec2> square(dvec2 lo, double side, bool clockwise = false) {
    std::vector<dvec2> l{lo, lo + dvec2(side, 0), lo + dvec2(side, side),
                         lo + dvec2(0, side)};
    if (clockwise) std::reverse(l.begin(), l.end());
    return l;
}

/// A comb: `teeth` narrow teeth standing on a base (many reflex vertices,
/// long thin ears).
std::vector<dvec2> comb(int teeth) {
    std::vector<dvec2> loop{{0.0, -1.0}, {double(teeth), -1.0}};
    for (int i = teeth - 1; i >= 0; --i) {
        loop.emplace_back(i + 0.5, 0.1);
        loop.emplace_back(i + 0.5, 10.0);
        loop.emplace_back(i, 10.0);
        loop.emplace_back(i, 0.0);
    }
    return loop;
}

TEST(Triangulator, SmallSimplePolygons) {
    expect_exact({{{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}}); // L
    expect_exact({star(10, 1.0, 0.4)});
    expect_exact({circle(7, 1.0)});
    // Clockwise input is accepted.
    auto cw = star(12, 1.0, 0.5);
    std::reverse(cw.begin(), cw.end());
    expect_exact({cw});
}

TEST(Triangulator, LargeSimplePolygons) {
    // Beyond the linear-scan size: the k-d trees answer the ear tests.
    expect_exact({circle(2000, 1.0)});
    expect_exact({star(2000, 1.0, 0.8)});
    expect_exact({comb(300)});
    // A spiral band: ears are few and far between.
    std::vector<dvec2> spiral;
    const int m = 1500;
    for (int i = 0; i < m; ++i) {
        const double t = 20.0 * i / m;
        spiral.emplace_back((1.0 + t) * std::cos(t), (1.0 + t) * std::sin(t));
    }
    for (int i = m - 1; i >= 0; --i) {
        const double t = 20.0 * i / m;
        spiral.emplace_back((1.5 + t) * std::cos(t), (1.5 + t) * std::sin(t));
    }
    expect_exact({spiral});
}

TEST(Triangulator, HolesAreRespected) {
    // Few holes (linear scans), then a grid of many (indexes), in either winding.
    expect_exact({square({0, 0}, 4), square({1, 1}, 1, true), square({2.5, 2.5}, 1)});
    Loops grid{square({0, 0}, 1)};
    const int g = 12;
    for (int i = 0; i < g; ++i)
        for (int j = 0; j < g; ++j)
            grid.push_back(
                square({(i + 0.25) / g, (j + 0.25) / g}, 0.5 / g, (i + j) % 2));
    expect_exact(grid);
    // Round holes in a many-sided disk.
    Loops disk{circle(400, 10.0)};
    for (int k = 0; k < 6; ++k)
        disk.push_back(
            circle(40, 1.0, dvec2(6.0 * std::cos(k), 6.0 * std::sin(k)), 0.1 * k));
    expect_exact(disk);
}

TEST(Triangulator, HolesTouchingAlongTheBridgeRayShareVertices) {
    // Two holes on one horizontal line: the second's bridge ray meets the
    // first's bridge; both stay holes.
    expect_exact({square({0, 0}, 10), square({2, 4}, 2), square({6, 4}, 2)});
}

TEST(Triangulator, DegenerateInputEndsCleanly) {
    Triangles out;
    // Collinear: no area, nothing.
    EXPECT_TRUE(triangulate({{{0, 0}, {1, 0}, {2, 0}, {3, 0}}}).empty());
    // Repeated and collinear vertices along the sides of a square.
    const std::vector<dvec2> sq{{0, 0}, {0.5, 0}, {0.5, 0}, {1, 0},  {1, 0.5},
                                {1, 1}, {1, 1},   {0, 1},   {0, 0.5}};
    out = triangulate({sq});
    double sum = 0.0;
    for (const auto& t : out) sum += std::abs(tri_area(sq[t[0]], sq[t[1]], sq[t[2]]));
    EXPECT_NEAR(sum, 1.0, 1e-12);
    // A zero-area hole removes nothing; a hole outside the outer loop is ignored.
    out = triangulate({square({0, 0}, 2), {{0.5, 0.5}, {1, 1}, {1.5, 1.5}}});
    EXPECT_EQ(out.size(), 2u);
    out = triangulate({square({0, 0}, 1), square({5, 5}, 1)});
    sum = 0.0;
    const Flat f = flatten({square({0, 0}, 1), square({5, 5}, 1)});
    for (const auto& t : out)
        sum += std::abs(tri_area(f.points[t[0]], f.points[t[1]], f.points[t[2]]));
    EXPECT_NEAR(sum, 1.0, 1e-12);
    // Every vertex the same: nothing.
    EXPECT_TRUE(triangulate({{{1, 1}, {1, 1}, {1, 1}, {1, 1}}}).empty());
}

TEST(Triangulator, SelfIntersectingLoopsEndWithValidIndices) {
    // A bowtie, and random points in random order, small and large: the
    // triangulator must end (no ear is found) with at most n - 2 triangles.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int n : {4, 12, 3000}) {
        std::vector<dvec2> loop;
        if (n == 4)
            loop = {{0, 0}, {1, 1}, {1, 0}, {0, 1}};
        else
            for (int i = 0; i < n; ++i) loop.emplace_back(u(rng), u(rng));
        const Triangles out = triangulate({loop});
        EXPECT_LE(out.size(), loop.size() - 2) << n;
        for (const auto& t : out)
            for (int k : t) {
                ASSERT_GE(k, 0);
                ASSERT_LT(k, n);
            }
    }
}

TEST(Triangulator, ConvexPolygonsAreNotFannedIntoSlivers) {
    // Best-first ear clipping halves a convex polygon level by level: each
    // of the log2(n) levels adds up to about the perimeter in longest sides,
    // where a fan from one vertex adds up to about 1.27 n radii (1300 here).
    const int n = 1024;
    const std::vector<dvec2> disk = circle(n, 1.0);
    const Triangles out = triangulate({disk});
    double longest_sum = 0.0;
    for (const auto& t : out) {
        const dvec2 &a = disk[t[0]], &b = disk[t[1]], &c = disk[t[2]];
        longest_sum +=
            std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    }
    EXPECT_LT(longest_sum, 2.0 * std::numbers::pi * std::log2(n));
}

TEST(BoxIndex, AnswersLikeALinearScan) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 100.0);
    sss::detail::BoxIndex index;
    std::vector<sss::detail::BoxIndex::Box> boxes;
    std::vector<char> present;
    const auto random_box = [&] {
        const dvec2 a(u(rng), u(rng)), b = a + dvec2(u(rng), u(rng)) * 0.05;
        return sss::detail::BoxIndex::Box{a, b};
    };
    index.reset(0);
    std::vector<std::pair<sss::detail::BoxIndex::Box, int>> bulk;
    for (int i = 0; i < 500; ++i) {
        boxes.push_back(random_box());
        present.push_back(1);
        bulk.emplace_back(boxes.back(), i);
    }
    index.insert(bulk);
    for (int step = 0; step < 1500; ++step) {
        const int op = static_cast<int>(u(rng)) % 3;
        if (op == 0) { // insert
            boxes.push_back(random_box());
            present.push_back(1);
            index.insert(boxes.back(), static_cast<int>(boxes.size()) - 1);
        } else if (op == 1) { // erase a present one
            const int id =
                static_cast<int>(u(rng) / 100.0 * static_cast<double>(boxes.size()));
            if (present[static_cast<std::size_t>(id)]) {
                index.erase(id);
                present[static_cast<std::size_t>(id)] = 0;
            }
        }
        const auto q = random_box();
        const sss::detail::BoxIndex::Box query{q.lo, q.lo + dvec2(10.0, 7.0)};
        const auto hit = [&](const sss::detail::BoxIndex::Box& b) {
            return b.lo.x <= query.hi.x && query.lo.x <= b.hi.x && b.lo.y <= query.hi.y &&
                   query.lo.y <= b.hi.y;
        };
        std::set<int> got, want;
        index.query(hit, [&](int id) {
            if (hit(boxes[static_cast<std::size_t>(id)])) got.insert(id);
        });
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            EXPECT_EQ(index.contains(static_cast<int>(i)), present[i] != 0);
            if (present[i] && hit(boxes[i])) want.insert(static_cast<int>(i));
        }
        ASSERT_EQ(got, want) << "step " << step;
    }
}

} // namespace
