// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file time_left_test.cpp
/// The terminal progress line's time left (sss::TimeLeftEstimator): fed
/// (elapsed, fraction) as a stage would feed it, without a clock or sleeping.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "sss/util/progress.h"

namespace {

constexpr double kTick = 0.125; // the line's redraw interval

/// What a stage of `seconds` whose fraction done at time t is fraction(t)
/// shows, redrawn every kTick: the worst relative error of a shown time left
/// against the truth after `settle` seconds, how long it showed one, the
/// longest stretch one value was shown, and how long nothing was.
struct StageRun {
    double worst_error = 0.0;
    double shown_seconds = 0.0;
    double longest_same = 0.0;
    double first_shown = -1.0;
};

StageRun run_stage(double seconds, const std::function<double(double)>& fraction,
                   double settle) {
    sss::TimeLeftEstimator estimator;
    StageRun r;
    double value = -2.0, since = 0.0;
    for (int i = 0; i * kTick < seconds; ++i) {
        const double t = i * kTick;
        const double left = estimator.update(t, fraction(t));
        if (left != value) {
            value = left;
            since = t;
        }
        if (left < 0.0) continue;
        r.longest_same = std::max(r.longest_same, t - since);
        r.shown_seconds += kTick;
        if (r.first_shown < 0.0) r.first_shown = t;
        const double truth = seconds - t;
        // Beyond what the rounding up adds (a step: 1 s below a minute ...).
        const double step = left <= 60.0     ? 1.0
                            : left <= 600.0  ? 5.0
                            : left <= 3600.0 ? 30.0
                                             : 60.0;
        if (t >= settle && truth > 2.0)
            r.worst_error =
                std::max(r.worst_error, (std::fabs(left - truth) - step) / truth);
    }
    return r;
}

TEST(TimeLeft, RoundedUpToStepsThatGrowWithTheTime) {
    EXPECT_EQ(sss::rounded_time_left(0.0), 1.0); // never 0:00 while running
    EXPECT_EQ(sss::rounded_time_left(0.4), 1.0);
    EXPECT_EQ(sss::rounded_time_left(4.2), 5.0);
    EXPECT_EQ(sss::rounded_time_left(59.5), 60.0);
    EXPECT_EQ(sss::rounded_time_left(61.0), 65.0);     // 5 s steps below 10 min
    EXPECT_EQ(sss::rounded_time_left(601.0), 630.0);   // 30 s below an hour
    EXPECT_EQ(sss::rounded_time_left(3725.0), 3780.0); // minutes beyond
    EXPECT_EQ(sss::rounded_time_left(1e9), 360000.0);  // shown as 100:00:00 at most
}

TEST(TimeLeft, NothingDuringTheFirstSeconds) {
    sss::TimeLeftEstimator e;
    EXPECT_LT(e.update(0.0, 0.0), 0.0);
    EXPECT_LT(e.update(0.5, 0.2), 0.0);
    EXPECT_LT(e.update(1.9, 0.7), 0.0);
    EXPECT_GT(e.update(2.0, 0.72), 0.0);
}

TEST(TimeLeft, SteadyWorkCountsDownToTheEnd) {
    const StageRun r = run_stage(
        100.0, [](double t) { return t / 100.0; }, 2.0);
    EXPECT_NEAR(r.first_shown, sss::TimeLeftEstimator::kWarmUpSeconds, 1e-9);
    EXPECT_LT(r.worst_error, 0.06);
    EXPECT_GT(r.shown_seconds, 97.0);
    EXPECT_LE(r.longest_same, 5.0 + kTick); // one 5 s step above a minute
}

TEST(TimeLeft, AFastStartDoesNotPromiseTheEndTooSoon) {
    // As ptfilter's diffusion: the first 35 % in 1 s (dark, cheap points),
    // the rest in 19 s. The average since the start said "0:01 left" from
    // 35 % to 86 %; the recent rate knows better once it is past the start.
    auto fraction = [](double t) {
        return t < 1.0 ? 0.35 * t : 0.35 + 0.65 * (t - 1.0) / 19.0;
    };
    const StageRun r = run_stage(20.0, fraction, 5.0);
    EXPECT_LT(r.worst_error, 0.15);
    EXPECT_LE(r.longest_same, 3.0 * 1.0 + kTick);
    // At 50 % (5.4 s in) the truth is 14.6 s; the old estimate was 5.4 s.
    sss::TimeLeftEstimator e;
    double left = -1.0;
    for (double t = 0.0; t <= 5.4; t += kTick) left = e.update(t, fraction(t));
    EXPECT_GT(left, 11.0);
    EXPECT_LT(left, 18.0);
}

TEST(TimeLeft, AStallWithdrawsTheEstimate) {
    // 30 % in 10 s, then nothing for 20 s.
    sss::TimeLeftEstimator e;
    double left = -1.0;
    for (double t = 0.0; t <= 10.0; t += kTick) left = e.update(t, 0.03 * t);
    EXPECT_NEAR(left, 24.0, 3.0);
    for (double t = 10.0 + kTick; t <= 30.0; t += kTick) left = e.update(t, 0.3);
    EXPECT_LT(left, 0.0);
    // Work resumes: an estimate again.
    for (double t = 30.0 + kTick; t <= 40.0; t += kTick)
        left = e.update(t, 0.3 + 0.01 * (t - 30.0));
    EXPECT_GT(left, 0.0);
}

TEST(TimeLeft, NeverTheSameValueForLong) {
    // Work that slows as it goes so that the remaining time at the current
    // rate stays 1.5 s: fraction 1 - exp(-t / 1.5). An estimate that keeps
    // saying 0:02 is disproved every second; it is withdrawn after 3 s.
    const StageRun r = run_stage(
        30.0, [](double t) { return 1.0 - std::exp(-t / 1.5); }, 1e9);
    EXPECT_LE(r.longest_same, 3.0 + kTick);
    // And slowing work in general: no value is shown for more than 3 steps.
    const StageRun s = run_stage(
        200.0, [](double t) { return 1.0 - std::pow(1.0 - t / 200.0, 2.0); }, 1e9);
    EXPECT_LE(s.longest_same, 3.0 * 5.0 + kTick);
    EXPECT_GT(s.shown_seconds, 100.0);
}

TEST(TimeLeft, LongStagesKeepAccurate) {
    // Ten hours of steady work redrawn 8 times a second: the history is
    // thinned, not lost.
    const StageRun r = run_stage(
        36000.0, [](double t) { return t / 36000.0; }, 60.0);
    EXPECT_LT(r.worst_error, 0.03);
    EXPECT_LE(r.longest_same, 60.0 + kTick);
}

} // namespace
