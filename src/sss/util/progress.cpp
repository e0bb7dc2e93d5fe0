// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file progress.cpp
/// ALF_PROGRESS lines, the terminal progress line and the stopwatch.

#include "sss/util/progress.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include <sys/ioctl.h>
#include <unistd.h>

#include "sss/util/error.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"

namespace sss {

// ---------------------------------------------------------------------------
// Progress
// ---------------------------------------------------------------------------

namespace {

int64_t now_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

constexpr int64_t kShowAfterNs = 500'000'000; // a stage shorter than this shows nothing
constexpr int64_t kRedrawNs = 125'000'000;    // at most 8 redraws a second

// The terminal line is the process's (one stderr): whether it is shown, and
// the lock of everything written to it.
std::mutex g_terminal_mutex;
bool g_terminal_shown = false;

void erase_terminal_line() { // under g_terminal_mutex
    if (!g_terminal_shown) return;
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
    g_terminal_shown = false;
}

std::size_t terminal_width() {
    winsize ws{};
    if (::ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col >= 20) return ws.ws_col;
    return 80;
}

// 1234567 -> "1.23 M ", 512 -> "512 "
std::string si(double x) {
    char buf[32];
    if (x < 1e3)
        std::snprintf(buf, sizeof buf, "%.0f ", x);
    else if (x < 1e6)
        std::snprintf(buf, sizeof buf, "%.1f k ", x / 1e3);
    else if (x < 1e9)
        std::snprintf(buf, sizeof buf, "%.2f M ", x / 1e6);
    else
        std::snprintf(buf, sizeof buf, "%.2f G ", x / 1e9);
    return buf;
}

// The time left of a stage (TimeLeftEstimator).
constexpr double kSampleSpacing = 0.1;    // seconds between kept samples
constexpr std::size_t kMaxSamples = 1024; // then every other one goes
constexpr double kStuckSteps = 3.0;       // a text kept longer than this many steps

// The rounding step of a time left (rounded_time_left).
double time_left_step(double seconds) {
    return seconds < 60.0 ? 1.0 : seconds < 600.0 ? 5.0 : seconds < 3600.0 ? 30.0 : 60.0;
}

} // namespace

double rounded_time_left(double seconds) {
    const double s = std::clamp(seconds, 0.0, 359999.0);
    const double step = time_left_step(s);
    return std::max(1.0, std::ceil(s / step - 1e-9) * step);
}

double TimeLeftEstimator::update(double elapsed, double fraction) {
    if (m_samples.empty() || elapsed - m_samples.back().elapsed >= kSampleSpacing) {
        if (m_samples.size() == kMaxSamples) { // keep the span, at half the density
            std::size_t kept = 0;
            for (std::size_t i = 0; i < m_samples.size(); i += 2)
                m_samples[kept++] = m_samples[i];
            m_samples.resize(kept);
        }
        m_samples.push_back({elapsed, fraction});
    }
    const double last = m_last;
    m_last = elapsed;
    if (elapsed < kWarmUpSeconds || !(fraction < 1.0)) return -1.0;
    // The rate over the recent window: from the last sample at or before its start.
    const double window = std::clamp(0.25 * elapsed, 1.0, 300.0);
    auto after =
        std::upper_bound(m_samples.begin(), m_samples.end(), elapsed - window,
                         [](double t, const Sample& s) { return t < s.elapsed; });
    const Sample& from = after == m_samples.begin() ? m_samples.front() : *(after - 1);
    const double span = elapsed - from.elapsed;
    const double rate = span > 0.0 ? (fraction - from.fraction) / span : 0.0;
    if (!(rate > 0.0)) { // a stall: nothing to extrapolate
        m_finish = -1.0;
        m_shown = -1.0;
        return -1.0;
    }
    const double finish = elapsed + (1.0 - fraction) / rate;
    if (m_finish < 0.0)
        m_finish = finish;
    else
        m_finish +=
            (1.0 - std::exp(-(elapsed - last) / kSmoothingSeconds)) * (finish - m_finish);
    const double shown = rounded_time_left(m_finish - elapsed);
    if (shown != m_shown) {
        m_shown = shown;
        m_shown_since = elapsed;
    }
    // The same text for several steps while time passes: the estimate is
    // being disproved as fast as it is made.
    return elapsed - m_shown_since > kStuckSteps * time_left_step(shown) ? -1.0 : shown;
}

std::string progress_line(const std::string& tool, const std::string& stage, int percent,
                          double rate, const std::string& unit, double seconds_left,
                          std::size_t width) {
    char pct[16];
    std::snprintf(pct, sizeof pct, "%3d%%", percent);
    std::string tail = std::string("  ") + pct;
    if (!unit.empty() && rate >= 0 && std::isfinite(rate))
        tail += "  " + si(rate) + unit + "/s";
    if (seconds_left >= 0 && std::isfinite(seconds_left)) {
        const long s = std::lround(rounded_time_left(seconds_left));
        char left[32];
        if (s >= 3600)
            std::snprintf(left, sizeof left, "  %ld:%02ld:%02ld left", s / 3600,
                          s / 60 % 60, s % 60);
        else
            std::snprintf(left, sizeof left, "  %ld:%02ld left", s / 60, s % 60);
        tail += left;
    }
    std::string head = tool + ": ";
    // The stage gives way first: the line must never wrap (\r returns to
    // the start of the last row only).
    const std::size_t fixed = head.size() + tail.size();
    std::string label = stage;
    if (fixed + label.size() > width) {
        const std::size_t room = width > fixed + 3 ? width - fixed - 3 : 0;
        label = truncated(label, room); // room bytes and "..."
    }
    std::string line = head + label + tail;
    if (line.size() > width) line.resize(width);
    return line;
}

Progress::~Progress() {
    if (!m_terminal) return;
    std::lock_guard<std::mutex> lock(g_terminal_mutex);
    erase_terminal_line();
}

void Progress::show_on_terminal(const std::string& tool) {
    const char* env = std::getenv("SSS_TTY_PROGRESS");
    if (env && std::string(env) == "0") return;
    if (!::isatty(STDERR_FILENO)) return;
    m_tool = tool;
    m_terminal = true;
}

void Progress::set_unit(const std::string& unit) {
    std::lock_guard<std::mutex> lock(m_mutex);
    m_unit = unit;
}

void Progress::draw(uint64_t done, uint64_t total, int64_t now) {
    if (total !=
        m_stage_total.load(std::memory_order_relaxed)) { // a new stage: its clock starts
        m_stage_total.store(total, std::memory_order_relaxed);
        m_stage_done0 = done;
        m_stage_start_ns = now;
        m_time_left = TimeLeftEstimator();
        m_time_left.update(0.0, total > 0 ? double(done) / double(total) : 1.0);
        m_next_draw_ns.store(now + kShowAfterNs, std::memory_order_relaxed);
        return;
    }
    std::lock_guard<std::mutex> lock(g_terminal_mutex);
    if (done >= total) { // the stage is over: its line goes
        erase_terminal_line();
        m_next_draw_ns.store(now + kRedrawNs, std::memory_order_relaxed);
        return;
    }
    if (now - m_stage_start_ns < kShowAfterNs) {
        m_next_draw_ns.store(m_stage_start_ns + kShowAfterNs, std::memory_order_relaxed);
        return;
    }
    const double seconds = double(now - m_stage_start_ns) * 1e-9;
    const double rate = double(done - std::min(done, m_stage_done0)) / seconds;
    const double left = m_time_left.update(seconds, double(done) / double(total));
    const int pct = int((static_cast<unsigned __int128>(done) * 100u) / total);
    const std::string line = progress_line(m_tool, current_stage(), pct, rate, m_unit,
                                           left, terminal_width() - 1);
    std::fputs(("\r" + line + "\033[K").c_str(), stderr);
    std::fflush(stderr);
    g_terminal_shown = true;
    m_next_draw_ns.store(now + kRedrawNs, std::memory_order_relaxed);
}

void Progress::update(uint64_t done, uint64_t total) {
    if (!m_enabled && !m_terminal && !m_callback) return;
    int pct = 100;
    if (total > 0 && done < total)
        pct = static_cast<int>((static_cast<unsigned __int128>(done) * 100u) / total);
    if (m_terminal) {
        const int64_t now = now_ns();
        if (now >= m_next_draw_ns.load(std::memory_order_relaxed) || pct >= 100 ||
            total != m_stage_total.load(std::memory_order_relaxed)) {
            std::lock_guard<std::mutex> lock(m_mutex);
            draw(done, total, now);
        }
    }
    if (!m_enabled && !m_callback) return;
    // Cheap check first: most calls change nothing and must not serialise.
    if (pct <= m_last.load(std::memory_order_relaxed)) return;
    std::lock_guard<std::mutex> lock(m_mutex);
    if (pct <= m_last.load(std::memory_order_relaxed)) return;
    // Stored first: a callback that throws does not see this step again.
    m_last.store(pct, std::memory_order_relaxed);
    if (m_enabled) {
        // The farm line on a line of its own, even when stdout is the
        // terminal the progress line is on (it is redrawn next time).
        std::lock_guard<std::mutex> terminal(g_terminal_mutex);
        erase_terminal_line();
        std::cout << "ALF_PROGRESS " << pct << "%\n";
        flush_standard_output();
    }
    if (m_callback && !m_callback(done, total)) throw Cancelled();
}

void Progress::finish() {
    update(1, 1);
    std::lock_guard<std::mutex> lock(g_terminal_mutex);
    erase_terminal_line();
}

void clear_terminal_progress() {
    std::lock_guard<std::mutex> lock(g_terminal_mutex);
    erase_terminal_line();
}

// ---------------------------------------------------------------------------
// Stopwatch
// ---------------------------------------------------------------------------

Stopwatch::Stopwatch() : m_start_ns(now_ns()) {}

double Stopwatch::seconds() const {
    return static_cast<double>(now_ns() - m_start_ns) * 1e-9;
}

} // namespace sss
