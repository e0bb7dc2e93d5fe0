// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file atomic_output.h
/// Output files written atomically, sets of outputs replaced all together,
/// and the signal handling that removes unfinished temporaries when a job is
/// interrupted (SIGINT, SIGTERM, SIGHUP). The user-facing rules are in
/// docs/cli-conventions.md ("Outputs").

#include <string>
#include <vector>

namespace sss {

class OutputSet;

/// An output file written atomically: write to temp_path(), then commit()
/// puts it in place. If never committed (error, exception, SIGINT/SIGTERM/
/// SIGHUP), the temporary is removed and the target is untouched.
///
/// What the target is decides how it is replaced:
///  - a new name or a regular file: the temporary is made in the target's
///    folder and renamed over it;
///  - a symbolic link (to a file, or dangling): the file at the end of the
///    link chain is replaced as above; the link itself stays;
///  - an existing device, FIFO or socket: the temporary is made in $TMPDIR
///    (else /tmp) and commit() writes its bytes into the target, which is
///    opened for writing and never renamed over or removed;
///  - a folder: IoError when the AtomicOutput is made.
///
/// Temporaries are named ".<name>.<host>.<pid>.<8 random letters/digits>.tmp"
/// and locked (flock) by their writer while it lives. Making an AtomicOutput
/// first removes the stale temporaries of the same name in the folder it
/// uses: those of this host whose writer process is gone and which nobody
/// holds locked (a writer killed by SIGKILL). A live job's temporary is never
/// touched.
///
/// While an OutputSet is active, commit() completes the temporary and hands
/// it to the set, which replaces every target at once in OutputSet::commit().
class AtomicOutput {
public:
    /// Reserves the temporary. Throws IoError (a folder as target, a missing
    /// or unwritable folder, too many symbolic links).
    explicit AtomicOutput(const std::string& target);
    ~AtomicOutput();
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;

    /// The file a writer writes (it may truncate and rewrite it, not remove it).
    const std::string& temp_path() const { return m_temp; }
    /// The name given.
    const std::string& target() const { return m_target; }
    /// The file commit() replaces or writes into: the target, symbolic links
    /// followed.
    const std::string& destination() const { return m_destination; }
    /// Whether the target is a device, FIFO or socket, written into on commit.
    bool writes_into() const { return m_special; }
    /// Flushes the temporary to disk and puts it in place (or hands it to the
    /// active OutputSet). Throws IoError; a second call does nothing.
    void commit();

private:
    friend class OutputSet;
    std::string m_target;
    std::string m_destination;
    std::string m_temp;
    int m_fd = -1; ///< the temporary, open and flock'ed while this process owns it
    bool m_special = false;
    bool m_done = false; ///< committed, or handed to an OutputSet
};

/// A job's outputs, replaced all together or not at all. While a set is
/// alive it is the active one (sets nest: an inner set's commit() hands its
/// files to the outer set): AtomicOutput::commit() only completes the
/// temporary and hands it over. commit() then writes the device/FIFO targets
/// and renames every other temporary over its target, with SIGINT, SIGTERM
/// and SIGHUP held until every rename is done. A set destroyed without
/// commit() (an exception, a later output that failed) removes every
/// temporary it holds: no target changes.
class OutputSet {
public:
    OutputSet();
    ~OutputSet();
    OutputSet(const OutputSet&) = delete;
    OutputSet& operator=(const OutputSet&) = delete;

    /// Replaces every target. Throws IoError (a device or FIFO that cannot be
    /// written, a rename that fails: what was renamed before stays).
    void commit();
    /// The targets handed over so far.
    std::vector<std::string> targets() const;

private:
    friend class AtomicOutput;
    struct Pending {
        std::string target;
        std::string destination;
        std::string temp;
        int fd = -1;
        bool special = false;
    };
    void adopt(AtomicOutput& out);
    std::vector<Pending> m_pending;
    OutputSet* m_outer = nullptr;
};

/// Checks, before any work, that `path` can be written as an output: not a
/// folder, and (unless it is a device, FIFO or socket) in a folder that
/// exists and this process may write into. Throws IoError naming `path`.
void check_output_target(const std::string& path);

/// Whether `path` names an existing device, FIFO or socket (symbolic links
/// followed): an output written into, whose name says nothing about a format.
bool writes_into_existing(const std::string& path);

/// Whether `path` names the file, pipe or terminal that standard output is
/// (/dev/stdout, /proc/self/fd/1, or the name of the file it was redirected
/// to): an output that shares standard output with what the tool prints.
bool is_standard_output(const std::string& path);

/// Installs the SIGINT/SIGTERM/SIGHUP handlers (once per process) that remove
/// every uncommitted AtomicOutput temporary and then die by the same signal.
/// A signal the parent ignores (nohup) stays ignored.
void install_signal_handlers();

/// Writes `text` to `path` through an AtomicOutput (a report, a table, a
/// plot). Throws IoError.
void write_text_file(const std::string& path, const std::string& text);

} // namespace sss
