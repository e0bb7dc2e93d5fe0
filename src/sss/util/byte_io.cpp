// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file byte_io.cpp
/// Buffered byte input (transparent gzip) and output for the binary formats.

#include "sss/util/byte_io.h"

#include <cerrno>
#include <climits>
#include <cstring>
#include <limits>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include "sss/util/error.h"
#include "sss/util/job_files.h"

namespace sss::detail {

namespace {

constexpr std::size_t kInputBuffer = 1 << 16;
constexpr std::size_t kOutputBuffer = 1 << 20;
// Deflate cannot expand data by more than 1032:1, so a gzip file of S bytes
// holds at most about 1032 * S bytes; a little margin covers headers.
constexpr uint64_t kMaxInflateRatio = 1040;

gzFile as_gz(void* p) {
    return static_cast<gzFile>(p);
}

} // namespace

void require_regular_file(const std::string& path, const std::string& context) {
    check_file_name(path);
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        const int err = errno;
        throw IoError(path, "cannot open" + context + ": " + std::strerror(err), err);
    }
    if (S_ISREG(st.st_mode)) return;
    const char* what = S_ISDIR(st.st_mode)    ? "is a directory"
                       : S_ISFIFO(st.st_mode) ? "is a FIFO (a pipe), not a regular file"
                       : S_ISSOCK(st.st_mode) ? "is a socket, not a regular file"
                       : S_ISCHR(st.st_mode) ? "is a character device, not a regular file"
                       : S_ISBLK(st.st_mode) ? "is a block device, not a regular file"
                                             : "is not a regular file";
    throw IoError(path, std::string(what) + context, S_ISDIR(st.st_mode) ? EISDIR : 0);
}

ByteSource::ByteSource(const std::string& path) : m_path(path), m_buf(kInputBuffer) {
    require_regular_file(path);
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        const int err = errno;
        throw IoError(path, std::string("cannot open: ") + std::strerror(err), err);
    }
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
        const int err = errno;
        ::close(fd);
        throw IoError(path, std::string("cannot stat: ") + std::strerror(err), err);
    }
    if (S_ISDIR(st.st_mode)) {
        ::close(fd);
        throw IoError(path, "is a directory", EISDIR);
    }
    if (S_ISREG(st.st_mode)) m_file_size = static_cast<uint64_t>(st.st_size);
    attach(fd);
}

ByteSource::ByteSource(StandardInput) : m_path("<stdin>"), m_buf(kInputBuffer) {
    // A duplicate: closing the stream must not close the process's stdin.
    const int fd = ::fcntl(STDIN_FILENO, F_DUPFD_CLOEXEC, 0);
    if (fd < 0)
        throw IoError(m_path, std::string("cannot read: ") + std::strerror(errno));
    attach(fd);
}

void ByteSource::attach(int fd) {
    // zlib reads plain files transparently and inflates gzip ones, which gives
    // the gzip sniffing for free.
    gzFile gz = gzdopen(fd, "rb");
    if (!gz) {
        ::close(fd);
        throw IoError(m_path, "cannot open (out of memory)");
    }
    gzbuffer(gz, 1 << 17);
    m_gz = gz;
    m_compressed = gzdirect(gz) == 0; // looks at the first bytes
}

ByteSource::~ByteSource() {
    if (m_gz) gzclose_r(as_gz(m_gz));
}

std::size_t ByteSource::raw_read(void* dst, std::size_t n) {
    if (m_eof || n == 0) return 0;
    const unsigned len = static_cast<unsigned>(std::min<std::size_t>(n, INT_MAX));
    const int got = gzread(as_gz(m_gz), dst, len);
    if (got < 0) {
        int errnum = 0;
        const char* msg = gzerror(as_gz(m_gz), &errnum);
        if (errnum == Z_ERRNO) {
            const int err = errno;
            throw IoError(m_path, std::string("read error: ") + std::strerror(err), err);
        }
        // zlib prefixes the name it was opened with, "<fd:3>" for gzdopen.
        std::string what = msg ? msg : "?";
        if (what.rfind("<fd:", 0) == 0 && what.find(">: ") != std::string::npos)
            what.erase(0, what.find(">: ") + 3);
        throw FormatError(m_path, "corrupt gzip stream: " + what);
    }
    if (got == 0) m_eof = true;
    return static_cast<std::size_t>(got);
}

bool ByteSource::fill() {
    m_pos = 0;
    m_end = raw_read(m_buf.data(), m_buf.size());
    return m_end > 0;
}

std::size_t ByteSource::read(void* dst, std::size_t n) {
    auto* out = static_cast<unsigned char*>(dst);
    std::size_t done = 0;
    while (done < n) {
        if (m_pos < m_end) {
            const std::size_t k = std::min(n - done, m_end - m_pos);
            std::memcpy(out + done, m_buf.data() + m_pos, k);
            m_pos += k;
            done += k;
        } else if (n - done >= m_buf.size()) {
            // Large reads bypass the buffer.
            const std::size_t k = raw_read(out + done, n - done);
            if (k == 0) break;
            done += k;
        } else if (!fill()) {
            break;
        }
    }
    m_consumed += done;
    return done;
}

int ByteSource::get() {
    if (m_pos >= m_end && !fill()) return -1;
    ++m_consumed;
    return m_buf[m_pos++];
}

std::optional<uint64_t> ByteSource::remaining_bound() const {
    if (!m_file_size) return std::nullopt;
    uint64_t total = *m_file_size;
    if (compressed()) {
        total = total > std::numeric_limits<uint64_t>::max() / kMaxInflateRatio
                    ? std::numeric_limits<uint64_t>::max()
                    : total * kMaxInflateRatio;
    }
    return total > m_consumed ? total - m_consumed : 0;
}

void ByteSource::finish() {
    if (!compressed()) return;
    // Drain so that zlib checks the CRC and length in the gzip trailer.
    while (m_pos < m_end || fill()) m_pos = m_end;
    int errnum = Z_OK;
    gzerror(as_gz(m_gz), &errnum);
    if (errnum == Z_BUF_ERROR) throw FormatError(m_path, "gzip stream is truncated");
}

ByteSink::ByteSink(const std::string& file, const std::string& display_path,
                   bool compress)
    : m_display(display_path), m_buf(kOutputBuffer) {
    if (compress) {
        m_gz = gzopen(file.c_str(), "wb");
        if (!m_gz) fail_errno("cannot create: ");
        gzbuffer(as_gz(m_gz), 1 << 17);
    } else {
        m_file = std::fopen(file.c_str(), "wb");
        if (!m_file) fail_errno("cannot create: ");
    }
}

ByteSink::~ByteSink() {
    // Only reached without close() after an error; the AtomicOutput discards the file.
    if (m_gz) gzclose_w(as_gz(m_gz));
    if (m_file) std::fclose(m_file);
}

void ByteSink::fail(const std::string& what, int error_number) {
    throw IoError(m_display, what, error_number);
}

void ByteSink::fail_errno(const char* what) {
    const int err = errno;
    fail(what + std::string(std::strerror(err)), err);
}

void ByteSink::flush_buffer() {
    if (m_used == 0) return;
    if (m_gz) {
        if (gzwrite(as_gz(m_gz), m_buf.data(), static_cast<unsigned>(m_used)) !=
            static_cast<int>(m_used)) {
            int errnum = 0;
            const char* msg = gzerror(as_gz(m_gz), &errnum);
            fail(std::string("write error: ") +
                 (errnum == Z_ERRNO ? std::strerror(errno) : (msg ? msg : "?")));
        }
    } else if (std::fwrite(m_buf.data(), 1, m_used, m_file) != m_used) {
        fail_errno("write error: ");
    }
    m_used = 0;
}

void ByteSink::write(const void* src, std::size_t n) {
    const auto* in = static_cast<const unsigned char*>(src);
    while (n > 0) {
        if (m_used == m_buf.size()) flush_buffer();
        const std::size_t k = std::min(n, m_buf.size() - m_used);
        std::memcpy(m_buf.data() + m_used, in, k);
        m_used += k;
        in += k;
        n -= k;
    }
}

void ByteSink::close() {
    flush_buffer();
    if (m_gz) {
        const int rc = gzclose_w(as_gz(m_gz));
        m_gz = nullptr;
        if (rc != Z_OK) fail("write error while finishing the gzip stream");
    }
    if (m_file) {
        const bool ok = std::fflush(m_file) == 0 && !std::ferror(m_file);
        const int err = errno;
        const bool closed = std::fclose(m_file) == 0;
        m_file = nullptr;
        if (!ok || !closed) fail(std::string("write error: ") + std::strerror(err), err);
    }
}

uint32_t crc32(uint32_t crc, const void* bytes, std::size_t size) {
    return static_cast<uint32_t>(
        ::crc32_z(crc, static_cast<const Bytef*>(bytes), static_cast<z_size_t>(size)));
}

} // namespace sss::detail
