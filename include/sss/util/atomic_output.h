#pragma once
/// \file atomic_output.h
/// Output files written atomically, and the signal handling that removes an
/// unfinished temporary when a job is interrupted (SIGINT, SIGTERM, SIGHUP).

#include <string>

namespace sss {

/// An output file written atomically: write to temp_path() (a unique file in
/// the target's folder), then commit() renames it over the target. If never
/// committed (error, exception, SIGINT/SIGTERM/SIGHUP), the temporary is removed and
/// the target is untouched.
class AtomicOutput {
public:
    explicit AtomicOutput(const std::string& target);
    ~AtomicOutput();
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;

    const std::string& temp_path() const { return m_temp; }
    const std::string& target() const { return m_target; }
    /// fsyncs the temporary and renames it over the target. Throws IoError.
    void commit();

private:
    std::string m_target;
    std::string m_temp;
    bool m_committed = false;
};

/// Installs the SIGINT/SIGTERM/SIGHUP handlers (once per process) that remove
/// every uncommitted AtomicOutput temporary and then die by the same signal.
/// A signal the parent ignores (nohup) stays ignored.
void install_signal_handlers();

} // namespace sss
