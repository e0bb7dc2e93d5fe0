// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file error.h
/// Module util: the runtime services every stage uses (errors, atomic output,
/// threads, progress, version, frame patterns, hashing, parsing, name tables,
/// byte streams).
/// May use: no other module (glm, oneTBB and zlib only).
///
/// Typed exceptions thrown by the sss library. Tools catch them in one place
/// (sss::run_tool) and turn them into "<tool> ERROR: ..." lines and exit codes.

#include <cstdint>
#include <stdexcept>
#include <string>

namespace sss {

/// Base class of every error the library reports.
class Error : public std::runtime_error {
public:
    explicit Error(const std::string& what) : std::runtime_error(what) {}
};

/// A malformed command line (unknown option, missing or bad value). Exit code 2.
class UsageError : public Error {
public:
    explicit UsageError(const std::string& what) : Error(what) {}
};

/// A file could not be opened, read or written (operating-system level).
class IoError : public Error {
public:
    /// error_number: the errno behind the failure, 0 when none applies.
    IoError(const std::string& path, const std::string& what, int error_number = 0)
        : Error(path + ": " + what), m_path(path), m_error_number(error_number) {}
    const std::string& path() const { return m_path; }
    /// The operating system's error number (errno), 0 when not known.
    int error_number() const { return m_error_number; }

private:
    std::string m_path;
    int m_error_number;
};

/// A file's content is malformed: bad magic, truncation, inconsistent sizes,
/// NaN/Inf data. Carries the file name and, for per-point data, the point index.
class FormatError : public Error {
public:
    FormatError(const std::string& path, const std::string& what, int64_t point = -1)
        : Error(path + ": " + what +
                (point >= 0 ? " (point " + std::to_string(point) + ")" : "")),
          m_path(path), m_point(point) {}
    const std::string& path() const { return m_path; }
    /// Index of the offending point, or -1 when the error is not about one point.
    int64_t point() const { return m_point; }

protected:
    /// For subclasses that compose their own message (e.g. "file:line: ...").
    struct Composed {};
    FormatError(Composed, const std::string& message, const std::string& path)
        : Error(message), m_path(path), m_point(-1) {}

private:
    std::string m_path;
    int64_t m_point;
};

/// A value that is impossible for the physics (negative lengths, albedo
/// outside [0,1], NaN material parameters, missing channels...).
class ValueError : public Error {
public:
    explicit ValueError(const std::string& what) : Error(what) {}
};

/// A run stopped because a Progress callback returned false (progress.h).
/// Not an Error: nothing went wrong, and no handler of the library's own
/// errors takes it for one; the call that was running leaves with it.
class Cancelled : public std::exception {
public:
    const char* what() const noexcept override { return "cancelled"; }
};

} // namespace sss
