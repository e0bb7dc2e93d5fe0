// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file progress_callback_test.cpp
/// sss::Progress::set_callback: what the Python module's progress callbacks
/// and cancellation rest on.

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "sss/util/error.h"
#include "sss/util/progress.h"

TEST(ProgressCallback, CalledOncePerPercentWhenNotPrinting) {
    testing::internal::CaptureStdout();
    std::vector<std::pair<uint64_t, uint64_t>> calls;
    sss::Progress progress(false);
    progress.set_callback(
        [&](uint64_t done, uint64_t total) { calls.emplace_back(done, total); });
    progress.update(0, 200);   // 0%
    progress.update(1, 200);   // still 0%
    progress.update(3, 200);   // 1%
    progress.update(2, 200);   // going back: nothing
    progress.update(100, 200); // 50%
    progress.finish();         // 100%
    progress.finish();         // already reported
    EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
    const std::vector<std::pair<uint64_t, uint64_t>> expected = {
        {0, 200}, {3, 200}, {100, 200}, {1, 1}};
    EXPECT_EQ(calls, expected);
}

TEST(ProgressCallback, PrintsToo) {
    testing::internal::CaptureStdout();
    int calls = 0;
    sss::Progress progress(true);
    progress.set_callback([&](uint64_t, uint64_t) { ++calls; });
    progress.update(1, 2);
    progress.finish();
    EXPECT_EQ(testing::internal::GetCapturedStdout(),
              "ALF_PROGRESS 50%\nALF_PROGRESS 100%\n");
    EXPECT_EQ(calls, 2);
}

TEST(ProgressCallback, ThrowingCallbackReachesTheCaller) {
    int calls = 0;
    sss::Progress progress(false);
    progress.set_callback([&](uint64_t done, uint64_t) {
        ++calls;
        if (done >= 5) throw std::runtime_error("stop");
    });
    progress.update(1, 10);
    EXPECT_THROW(progress.update(5, 10), std::runtime_error);
    // The step that threw is not reported again; later ones are.
    progress.update(5, 10);
    EXPECT_EQ(calls, 2);
    EXPECT_THROW(progress.update(6, 10), std::runtime_error);
    EXPECT_EQ(calls, 3);
}

TEST(ProgressCallback, SerialisedAndMonotoneAcrossThreads) {
    sss::Progress progress(false);
    std::atomic<int> inside{0};
    bool overlapped = false;
    std::vector<int> seen;
    progress.set_callback([&](uint64_t done, uint64_t total) {
        if (inside.fetch_add(1) != 0) overlapped = true;
        seen.push_back(int(done * 100 / total));
        inside.fetch_sub(1);
    });
    constexpr uint64_t total = 100000;
    std::atomic<uint64_t> done{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < 4; ++t)
        threads.emplace_back([&] {
            for (;;) {
                const uint64_t d = done.fetch_add(1) + 1;
                if (d > total) break;
                progress.update(d, total);
            }
        });
    for (auto& t : threads) t.join();
    EXPECT_FALSE(overlapped);
    ASSERT_FALSE(seen.empty());
    for (std::size_t i = 1; i < seen.size(); ++i) EXPECT_LT(seen[i - 1], seen[i]);
    EXPECT_EQ(seen.back(), 100);
}

TEST(ProgressCallback, ReturningFalseCancels) {
    std::vector<uint64_t> seen;
    sss::Progress progress(false);
    progress.set_callback([&](uint64_t done, uint64_t) {
        seen.push_back(done);
        return done < 3;
    });
    progress.update(1, 10);
    EXPECT_THROW(progress.update(3, 10), sss::Cancelled);
    EXPECT_STREQ(sss::Cancelled().what(), "cancelled");
    const std::vector<uint64_t> expected = {1, 3};
    EXPECT_EQ(seen, expected);
}
