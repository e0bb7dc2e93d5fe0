// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file progress.h
/// Progress of a job: ALF_PROGRESS lines for render farms, one updating line
/// for a person at a terminal, and a wall-clock stopwatch.

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <type_traits>
#include <vector>

namespace sss {

/// `seconds` rounded up to the step the terminal line shows a time left in:
/// 1 s below a minute, 5 s below ten minutes, 30 s below an hour, a minute
/// beyond; at least 1 s (work that is still running never reads "0:00").
double rounded_time_left(double seconds);

/// The time left of a stage, estimated from how far it has come: the
/// terminal line's "0:05 left". A function of what it is fed, with no clock
/// of its own, so that it is tested without waiting.
///
/// The rate is measured over a recent window (a quarter of the stage's time,
/// 1 s to 5 min), not since the stage began: the work per percent often
/// changes within a stage (ptfilter's dark points are cheap and its lit
/// ones dear), and an average since the start then promises the end far too
/// soon. The estimated end time is smoothed (2 s), so the time left counts
/// down instead of jumping with every update. There is no estimate in the
/// first 2 s of a stage, nor while the window shows no progress (a stall);
/// and a time left that reads the same for more than 3 steps of its
/// rounding (at least 3 s) while the work goes on is one that time keeps
/// disproving: it is withdrawn until the estimate moves.
class TimeLeftEstimator {
public:
    /// Records that `fraction` (0 to 1) of the stage was done `elapsed`
    /// seconds after it began (elapsed never decreasing) and returns the
    /// time left to show, rounded_time_left(), or -1 for none.
    double update(double elapsed, double fraction);

    static constexpr double kWarmUpSeconds = 2.0;
    static constexpr double kSmoothingSeconds = 2.0;

private:
    struct Sample {
        double elapsed, fraction;
    };
    std::vector<Sample> m_samples; ///< at least 0.1 s apart, thinned when long
    double m_finish = -1.0;        ///< smoothed end time (elapsed), < 0: none
    double m_last = 0.0;           ///< elapsed of the last update
    double m_shown = -1.0;         ///< the rounded time left last returned
    double m_shown_since = 0.0;    ///< when m_shown was first returned
};

/// Thread-safe progress reporter. Two displays, independent of each other:
/// - farm lines (`enabled`, -progress): "ALF_PROGRESS NN%" on stdout,
///   flushed, each time the integer percentage grows;
/// - a terminal line (show_on_terminal()): when stderr is a terminal, one
///   line rewritten in place, "<tool>: <stage>  43%  1.2 M points/s  0:05
///   left", where the stage is current_stage() (sss/util/limits.h). It appears
///   once a stage has run for half a second, is redrawn at most 8 times a
///   second, and is erased when the stage reaches 100 %, by finish(), or
///   before an error or warning is printed (clear_terminal_progress()).
///   Farm logs are never terminals, so they keep only the ALF lines.
class Progress {
public:
    /// Receives (done, total) each time the integer percentage grows, and
    /// returns whether the work goes on: false cancels it (update() throws
    /// sss::Cancelled, which leaves the library call that was running).
    using Callback = std::function<bool(uint64_t done, uint64_t total)>;

    explicit Progress(bool enabled) : m_enabled(enabled) {}
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    /// Shows the terminal line, prefixed "<tool>: ", when stderr is a
    /// terminal and the environment variable SSS_TTY_PROGRESS is not "0".
    void show_on_terminal(const std::string& tool);
    /// The unit of update()'s counts ("points"), for the terminal line's
    /// rate; "" (the default) shows no rate. Set before the updates.
    void set_unit(const std::string& unit);
    /// Reports that `done` of `total` units are finished. A new `total`
    /// starts a new stage of the terminal line (its rate and time left).
    void update(uint64_t done, uint64_t total);
    /// Prints 100% if not printed yet; erases the terminal line.
    void finish();
    bool enabled() const { return m_enabled; }
    /// Whether the terminal line is on (show_on_terminal() found a terminal).
    bool on_terminal() const { return m_terminal; }
    /// Also (or, when not enabled, only) calls `callback` each time the
    /// percentage grows, serialised (one call at a time, percentages in
    /// order), from whichever thread made the progress. When it returns
    /// false, the running library call stops at its next progress step and
    /// throws sss::Cancelled (sss/util/error.h); a callback that returns
    /// nothing never cancels. An exception it throws leaves update() the
    /// same way (the Python module cancels a run so). Set it before the work
    /// starts. This is how a program embedding the library shows progress and
    /// offers a Cancel button:
    ///
    ///     sss::Progress progress(false);
    ///     progress.set_callback([&](uint64_t done, uint64_t total) {
    ///         bar.set(double(done) / total);
    ///         return !cancel_pressed.load();
    ///     });
    ///     options.progress = &progress;
    ///     try { out = sss::ssdiffusion(cloud, options); }
    ///     catch (const sss::Cancelled&) { /* the user cancelled */ }
    template <class F>
    void set_callback(F callback) {
        if constexpr (std::is_void_v<std::invoke_result_t<F&, uint64_t, uint64_t>>) {
            m_callback = [f = std::move(callback)](uint64_t done,
                                                   uint64_t total) mutable {
                f(done, total);
                return true;
            };
        } else {
            m_callback = std::move(callback);
        }
    }

private:
    void draw(uint64_t done, uint64_t total, int64_t now_ns); // under m_mutex
    void erase();                                             // under m_mutex

    bool m_enabled;
    bool m_terminal = false;
    std::string m_tool, m_unit;
    Callback m_callback;
    std::atomic<int> m_last{-1};
    std::mutex m_mutex;
    // The terminal line's stage: its total, start time and first count.
    std::atomic<uint64_t> m_stage_total{0};
    uint64_t m_stage_done0 = 0;
    int64_t m_stage_start_ns = 0;
    std::atomic<int64_t> m_next_draw_ns{0};
    bool m_shown = false;
    TimeLeftEstimator m_time_left; ///< of the current stage
};

/// Erases the terminal line of the job's Progress if one is shown (before a
/// message is written to stderr or a terminal on stdout).
void clear_terminal_progress();

/// The terminal line's text: "<tool>: <stage>  43%  1.2 M points/s  0:05
/// left", at most `width` columns (the stage is shortened with "..."). No
/// rate without a unit or below 0; no time left when seconds_left < 0, else
/// rounded_time_left(seconds_left).
std::string progress_line(const std::string& tool, const std::string& stage, int percent,
                          double rate, const std::string& unit, double seconds_left,
                          std::size_t width);

/// Wall-clock stopwatch in seconds.
class Stopwatch {
public:
    Stopwatch();
    double seconds() const;

private:
    int64_t m_start_ns;
};

} // namespace sss
