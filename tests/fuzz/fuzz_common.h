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
#include <string>

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

/// A scratch path unique to this process ("/dev/shm/sss_fuzz_<tag>_<pid><ext>"),
/// removed at exit. /dev/shm keeps the per-input writes off the disk.
class ScratchFile {
public:
    ScratchFile(const std::string& tag, const std::string& ext) {
        const char* dir = std::getenv("SSS_FUZZ_TMP");
        m_path = std::string(dir && *dir ? dir : "/dev/shm") + "/sss_fuzz_" + tag + "_" +
                 std::to_string(::getpid()) + ext;
    }
    ~ScratchFile() { ::unlink(m_path.c_str()); }
    const std::string& path() const { return m_path; }

    /// Replaces the file's content with data.
    void write(const uint8_t* data, std::size_t size) const {
        const int fd =
            ::open(m_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
        if (fd < 0) finding("cannot create the scratch file " + m_path);
        std::size_t done = 0;
        while (done < size) {
            const ssize_t n = ::write(fd, data + done, size - done);
            if (n <= 0) finding("cannot write the scratch file " + m_path);
            done += static_cast<std::size_t>(n);
        }
        ::close(fd);
    }

private:
    std::string m_path;
};

/// Runs body; sss::Error is an accepted outcome, any other exception a finding.
template <class F>
void run_expecting_errors(F&& body) {
    try {
        body();
    } catch (const sss::Error&) {
        // The reader rejected the input cleanly: the expected outcome.
    } catch (const std::exception& e) {
        finding(std::string("exception other than sss::Error: ") + e.what());
    } catch (...) {
        finding("non-std exception");
    }
}

} // namespace sss::fuzz
