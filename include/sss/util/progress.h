#pragma once
/// \file progress.h
/// Progress lines for render farms (ALF_PROGRESS) and a wall-clock stopwatch.

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>

namespace sss {

/// Thread-safe progress reporter for render farms: prints "ALF_PROGRESS NN%"
/// on stdout, flushed, each time the integer percentage grows.
class Progress {
public:
    /// Receives (done, total) each time the integer percentage grows.
    using Callback = std::function<void(uint64_t done, uint64_t total)>;

    explicit Progress(bool enabled) : m_enabled(enabled) {}
    /// Reports that `done` of `total` units are finished.
    void update(uint64_t done, uint64_t total);
    /// Prints 100% if not printed yet.
    void finish();
    bool enabled() const { return m_enabled; }
    /// Also (or, when not enabled, only) calls `callback` each time the
    /// percentage grows, serialised (one call at a time, percentages in
    /// order), from whichever thread made the progress. An exception it
    /// throws leaves update() and ends the caller's work (the Python module
    /// cancels a run this way). Set it before the work starts.
    void set_callback(Callback callback) { m_callback = std::move(callback); }

private:
    bool m_enabled;
    Callback m_callback;
    std::atomic<int> m_last{-1};
    std::mutex m_mutex;
};

/// Wall-clock stopwatch in seconds.
class Stopwatch {
public:
    Stopwatch();
    double seconds() const;

private:
    int64_t m_start_ns;
};

} // namespace sss
