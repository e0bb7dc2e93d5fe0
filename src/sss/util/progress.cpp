/// \file progress.cpp
/// ALF_PROGRESS lines and the stopwatch.

#include "sss/util/progress.h"

#include "sss/util/messages.h"

#include <chrono>
#include <iostream>

namespace sss {

// ---------------------------------------------------------------------------
// Progress
// ---------------------------------------------------------------------------

void Progress::update(uint64_t done, uint64_t total) {
    if (!m_enabled && !m_callback) return;
    int pct = 100;
    if (total > 0 && done < total)
        pct = static_cast<int>((static_cast<unsigned __int128>(done) * 100u) / total);
    // Cheap check first: most calls change nothing and must not serialise.
    if (pct <= m_last.load(std::memory_order_relaxed)) return;
    std::lock_guard<std::mutex> lock(m_mutex);
    if (pct <= m_last.load(std::memory_order_relaxed)) return;
    // Stored first: a callback that throws does not see this step again.
    m_last.store(pct, std::memory_order_relaxed);
    if (m_enabled) {
        std::cout << "ALF_PROGRESS " << pct << "%\n";
        flush_standard_output();
    }
    if (m_callback) m_callback(done, total);
}

void Progress::finish() {
    update(1, 1);
}

// ---------------------------------------------------------------------------
// Stopwatch
// ---------------------------------------------------------------------------

namespace {

int64_t now_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

} // namespace

Stopwatch::Stopwatch() : m_start_ns(now_ns()) {}

double Stopwatch::seconds() const {
    return static_cast<double>(now_ns() - m_start_ns) * 1e-9;
}

} // namespace sss
