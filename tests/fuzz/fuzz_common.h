#pragma once
// Shared by the libFuzzer targets (docs/fuzzing.md): a per-process scratch
// file in /dev/shm for the readers that take paths, and the verdict rules. An
// sss::Error is the expected outcome of a bad input; anything else (another
// exception, a crash, a sanitizer report, an invariant broken by a result
// that was read successfully) aborts, and libFuzzer keeps the input.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

#include "sss/util/error.h"

namespace sss::fuzz {

/// Reports a finding and aborts (libFuzzer saves the crashing input).
[[noreturn]] inline void finding(const std::string& what) {
    std::fprintf(stderr, "FUZZ FINDING: %s\n", what.c_str());
    std::fflush(stderr);
    std::abort();
}

/// Checks an invariant of a successfully read result.
inline void require(bool ok, const std::string& what) {
    if (!ok) finding(what);
}

/// The folder for scratch files: $SSS_FUZZ_TMP, else /dev/shm (keeps the
/// per-input writes off the disk).
inline std::string scratch_root() {
    const char* dir = std::getenv("SSS_FUZZ_TMP");
    return dir && *dir ? dir : "/dev/shm";
}

/// Replaces the content of the file at path with data.
inline void write_file(const std::string& path, const uint8_t* data, std::size_t size) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd < 0) finding("cannot create the scratch file " + path);
    std::size_t done = 0;
    while (done < size) {
        const ssize_t n = ::write(fd, data + done, size - done);
        if (n <= 0) finding("cannot write the scratch file " + path);
        done += static_cast<std::size_t>(n);
    }
    ::close(fd);
}

/// A scratch path unique to this process ("/dev/shm/sss_fuzz_<tag>_<pid><ext>"),
/// removed at exit.
class ScratchFile {
public:
    ScratchFile(const std::string& tag, const std::string& ext) {
        m_path =
            scratch_root() + "/sss_fuzz_" + tag + "_" + std::to_string(::getpid()) + ext;
    }
    ~ScratchFile() { ::unlink(m_path.c_str()); }
    const std::string& path() const { return m_path; }

    /// Replaces the file's content with data.
    void write(const uint8_t* data, std::size_t size) const {
        write_file(m_path, data, size);
    }

private:
    std::string m_path;
};

/// An empty folder unique to this process ("/dev/shm/sss_fuzz_<tag>_XXXXXX"),
/// removed with its content at exit. With `enter`, it also becomes the
/// current directory, so that relative names an input writes (bake3d files
/// of a render) or reads (textures, clouds, shaders) stay inside it; the
/// paths given to libFuzzer must then be absolute (scripts/fuzz does that).
class ScratchFolder {
public:
    ScratchFolder(const std::string& tag, bool enter) {
        std::string pattern = scratch_root() + "/sss_fuzz_" + tag + "_XXXXXX";
        if (!::mkdtemp(pattern.data()))
            finding("cannot create a temporary folder in " + scratch_root());
        m_path = pattern;
        if (enter && ::chdir(m_path.c_str()) != 0)
            finding("cannot enter the temporary folder " + m_path);
    }
    ~ScratchFolder() {
        std::error_code ec;
        std::filesystem::remove_all(m_path, ec);
    }
    const std::string& path() const { return m_path; }
    std::string file(std::string_view name) const {
        return m_path + "/" + std::string(name);
    }
    /// Removes everything in the folder (what the last input wrote).
    void clear() const {
        std::error_code ec;
        for (const auto& e : std::filesystem::directory_iterator(m_path, ec))
            std::filesystem::remove_all(e.path(), ec);
    }

private:
    std::string m_path;
};

/// True when the input could name a file outside the scratch folder: a '/'
/// (absolute or nested paths) or a backslash (a RIB string escape such as
/// \057 can spell '/'). Such inputs are skipped by the targets that read or
/// write the files a scene names, so a fuzzer never reads /dev/zero, a FIFO
/// or the project's files, or writes anywhere but its scratch folder.
inline bool may_name_outside_files(std::string_view text) {
    return text.find('/') != std::string_view::npos ||
           text.find('\\') != std::string_view::npos;
}

/// True when SSS_FUZZ_VERBOSE is set: the targets then print the errors
/// that rejected an input (to see why a seed goes no further).
inline bool verbose() {
    static const bool on = [] {
        const char* v = std::getenv("SSS_FUZZ_VERBOSE");
        return v && *v && std::string(v) != "0";
    }();
    return on;
}

/// Runs body; sss::Error is an accepted outcome, any other exception a finding.
template <class F>
void run_expecting_errors(F&& body) {
    try {
        body();
    } catch (const sss::Error& e) {
        // The reader rejected the input cleanly: the expected outcome.
        if (verbose()) std::fprintf(stderr, "rejected: %s\n", e.what());
    } catch (const std::exception& e) {
        finding(std::string("exception other than sss::Error: ") + e.what());
    } catch (...) {
        finding("non-std exception");
    }
}

} // namespace sss::fuzz
