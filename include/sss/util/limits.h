// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file limits.h
/// Resource limits as policy (docs/limits.md): the documented ceilings every
/// tool applies to what an input may ask for (vertices, micropolygons, archive
/// nesting, string lengths, image size, bricks), the memory a process may
/// use, and the stage a job is in (for "out of memory while <stage>").
///
/// Every limit has a default, an environment variable that raises (or
/// lowers) it, and an error that names both. Limits are read once per
/// process; set_limit() overrides them (tests, tool options).

#include <cstdint>
#include <string>

#include "sss/util/error.h"

namespace sss {

/// The limits. docs/limits.md lists them with their defaults.
enum class Limit {
    PrimitiveVertices,      ///< vertices (control points) of one primitive or OBJ face
    PrimitiveMicropolygons, ///< micropolygons one primitive may be diced into
    SceneMicropolygons,     ///< micropolygons of a whole scene (all primitives)
    ArchiveDepth,           ///< nesting of ReadArchive / inline archive instances
    StringLength,           ///< bytes of one RIB string or shader source string
    TokenLength,            ///< bytes of one RIB token (request name, number, name)
    ImagePixels,            ///< pixels of one rendered image (width * height)
    ImageSide,              ///< width or height of one rendered image
    Bricks,                 ///< bricks of one brick map
    ShaderOperations,       ///< ops (and loop iterations) one shading batch runs
    ShaderStringLength,     ///< bytes of one string a shader makes
    ShaderArrayLength,      ///< elements of one resizable shader array
    Bake3dPoints,           ///< points bake3d hands over in one job
    Bake3dFiles,            ///< distinct bake3d files of one job
    Count_
};

/// Name as in the environment variable without its prefix and in
/// docs/limits.md, e.g. "PRIMITIVE_VERTICES".
const char* limit_name(Limit which);
/// The environment variable that sets it, e.g. "SSS_LIMIT_PRIMITIVE_VERTICES".
std::string limit_variable(Limit which);
/// What is counted, for messages, e.g. "vertices in one primitive".
const char* limit_what(Limit which);
/// The built-in default.
uint64_t limit_default(Limit which);

/// The value in force: set_limit's, else the environment variable's (a
/// positive integer, 1e9 or with a K/M/G suffix; anything else is a
/// UsageError naming the variable), else the default.
uint64_t limit(Limit which);
/// Overrides the value for this process (0 restores the environment's/default).
void set_limit(Limit which, uint64_t value);

/// An input asked for more than a limit allows.
class LimitError : public Error {
public:
    LimitError(Limit which, const std::string& what) : Error(what), m_which(which) {}
    Limit which() const { return m_which; }

private:
    Limit m_which;
};

/// Throws LimitError when `needed` > limit(which):
/// "<where>: <needed> <what> exceeds the limit of <limit> (set SSS_LIMIT_X to raise it)".
/// `where` names the input ("scene.rib:12: Polygon").
void check_limit(Limit which, uint64_t needed, const std::string& where);

/// "exceeds the limit of <limit> (set SSS_LIMIT_X to raise it)": the tail of
/// a message about `which` whose first part the caller words itself.
std::string limit_exceeded(Limit which);

// ---------------------------------------------------------------------------
// Memory

/// The memory this process may use and what sets it.
struct MemoryBudget {
    uint64_t bytes = 0;
    /// "cgroup memory.max", "ulimit -v", "ulimit -d", "physical memory" or
    /// "SSS_MEMORY_LIMIT".
    std::string source;
};

/// The smallest of: SSS_MEMORY_LIMIT (bytes, K/M/G suffixes), the cgroup's
/// memory.max (v2) or memory.limit_in_bytes (v1) minus what the cgroup already
/// uses besides this process, RLIMIT_AS, RLIMIT_DATA, and physical memory plus
/// swap. Read on each call (cheap: a few small files).
MemoryBudget usable_memory();

/// Memory the process uses now (resident set), in bytes; 0 if unknown.
uint64_t resident_memory();

/// The largest resident set of this program so far, in bytes (VmHWM; 0 if
/// unknown). Unlike getrusage's ru_maxrss it starts at the program's exec: a
/// tool started by a large process (a bench, a Python pipeline) does not
/// report its parent's pages.
uint64_t peak_resident_memory();

/// The process would need more memory than it may use.
class OutOfMemoryError : public Error {
public:
    explicit OutOfMemoryError(const std::string& what) : Error(what) {}
};

/// Throws OutOfMemoryError when `needed_bytes` (an estimate of what the next
/// step allocates, on top of what is resident now) exceeds usable_memory():
/// "<what> needs about 12.3 GB; this process may use 8.0 GB (cgroup
/// memory.max); <remedy>". remedy names the option that reduces the need,
/// e.g. "raise -spacing".
void check_memory(uint64_t needed_bytes, const std::string& what,
                  const std::string& remedy);

/// "12.3 GB", "850 MB", "4.0 KB": sizes in messages (powers of 1024).
std::string format_bytes(uint64_t bytes);

// ---------------------------------------------------------------------------
// Stages

/// Names what the process is doing while alive ("dicing scene.rib",
/// "writing out.exr"); nested stages restore the outer one. run_tool reports
/// std::bad_alloc as "out of memory while <stage>". Set from the main thread.
class ScopedStage {
public:
    explicit ScopedStage(std::string stage);
    ~ScopedStage();
    ScopedStage(const ScopedStage&) = delete;
    ScopedStage& operator=(const ScopedStage&) = delete;

private:
    std::string m_previous;
    int m_uncaught;
};

/// The innermost live stage, or "" when none.
std::string current_stage();

/// The stage to name in an error: the innermost stage an exception unwound
/// out of (the first one), else current_stage().
std::string failure_stage();

} // namespace sss
