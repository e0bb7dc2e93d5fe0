// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file byte_io.h
/// Buffered byte input with transparent gzip, buffered byte output (plain or
/// gzip) and little-endian packing: what every binary reader and writer of the
/// project (.ptc, .ply, .bkm) is built on.

#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

namespace sss::detail {

/// Throws IoError unless `path` names a regular file (after symbolic
/// links): an input that is a directory, a FIFO, a socket or a device is
/// refused with what it is, before anything opens it (opening a FIFO would
/// block until a writer came, a device could be endless). `context` follows
/// "cannot open" in the message (e.g. " (ReadArchive at a.rib:3)").
void require_regular_file(const std::string& path, const std::string& context = "");

/// Reads a file byte by byte through a buffer. A gzip stream (magic 1f 8b) is
/// inflated on the fly. Short reads happen only at the end of the data; a
/// corrupt gzip stream throws FormatError, an OS read error IoError.
class ByteSource {
public:
    /// Opens path; IoError if it cannot be opened or is not a regular file
    /// (require_regular_file).
    explicit ByteSource(const std::string& path);
    /// Tag for the constructor that reads standard input.
    struct StandardInput {};
    /// Reads standard input (plain or gzip) without closing it; path() is
    /// "<stdin>" and remaining_bound() is unknown.
    explicit ByteSource(StandardInput);
    ~ByteSource();
    ByteSource(const ByteSource&) = delete;
    ByteSource& operator=(const ByteSource&) = delete;

    const std::string& path() const { return m_path; }
    /// True if the file is a gzip stream.
    bool compressed() const { return m_compressed; }
    /// Reads up to n bytes; returns fewer only at the end of the data.
    std::size_t read(void* dst, std::size_t n);
    /// Reads exactly n bytes; false if the data ends first.
    bool read_exact(void* dst, std::size_t n) { return read(dst, n) == n; }
    /// Next byte, or -1 at the end of the data.
    int get();
    /// Bytes of (decompressed) data consumed so far.
    uint64_t consumed() const { return m_consumed; }
    /// Upper bound of the bytes still to come: exact for a plain regular file,
    /// a bound from the maximum deflate ratio for gzip, nullopt when unknown
    /// (pipes). Lets readers reject absurd counts before allocating.
    std::optional<uint64_t> remaining_bound() const;
    /// For gzip, reads to the end of the stream so that a bad checksum or a
    /// truncated trailer is reported; trailing data is otherwise ignored.
    void finish();

private:
    /// Reads fd (owned from here on) through zlib.
    void attach(int fd);
    std::size_t raw_read(void* dst, std::size_t n);
    bool fill();

    std::string m_path;
    void* m_gz = nullptr; // gzFile (reads plain files transparently); opaque to keep
                          // zlib.h private
    bool m_compressed = false;
    std::vector<unsigned char> m_buf;
    std::size_t m_pos = 0;
    std::size_t m_end = 0;
    bool m_eof = false;
    uint64_t m_consumed = 0;
    std::optional<uint64_t> m_file_size; // on-disk size when it is a regular file
};

/// Writes bytes through a buffer to a file, optionally gzip-compressed.
/// Errors are IoErrors naming display_path (the user's target, not the temporary).
class ByteSink {
public:
    ByteSink(const std::string& file, const std::string& display_path, bool compress);
    ~ByteSink();
    ByteSink(const ByteSink&) = delete;
    ByteSink& operator=(const ByteSink&) = delete;

    void write(const void* src, std::size_t n);
    void write(const std::string& s) { write(s.data(), s.size()); }
    /// Flushes and closes; IoError if anything failed. Must be called before commit.
    void close();

private:
    void flush_buffer();
    [[noreturn]] void fail(const std::string& what, int error_number = 0);
    /// fail() with `what` followed by errno's text, errno as the error number.
    [[noreturn]] void fail_errno(const char* what);

    std::string m_display;
    std::FILE* m_file = nullptr;
    void* m_gz = nullptr;
    std::vector<unsigned char> m_buf;
    std::size_t m_used = 0;
};

/// CRC-32 (zlib's, the gzip/PNG polynomial) of `size` bytes, continuing
/// from `crc` (0 to start).
uint32_t crc32(uint32_t crc, const void* bytes, std::size_t size);

// Little-endian loads and stores, independent of the host byte order.
inline uint16_t load_u16(const unsigned char* p) {
    return static_cast<uint16_t>(p[0] | (p[1] << 8));
}
inline uint32_t load_u32(const unsigned char* p) {
    return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
           (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
inline uint64_t load_u64(const unsigned char* p) {
    return static_cast<uint64_t>(load_u32(p)) |
           (static_cast<uint64_t>(load_u32(p + 4)) << 32);
}
inline int32_t load_i32(const unsigned char* p) {
    return static_cast<int32_t>(load_u32(p));
}
inline float load_f32(const unsigned char* p) {
    return std::bit_cast<float>(load_u32(p));
}
inline double load_f64(const unsigned char* p) {
    return std::bit_cast<double>(load_u64(p));
}

inline void store_u16(unsigned char* p, uint16_t v) {
    p[0] = static_cast<unsigned char>(v);
    p[1] = static_cast<unsigned char>(v >> 8);
}
inline void store_u32(unsigned char* p, uint32_t v) {
    for (int i = 0; i < 4; ++i) p[i] = static_cast<unsigned char>(v >> (8 * i));
}
inline void store_u64(unsigned char* p, uint64_t v) {
    for (int i = 0; i < 8; ++i) p[i] = static_cast<unsigned char>(v >> (8 * i));
}
inline void store_i32(unsigned char* p, int32_t v) {
    store_u32(p, static_cast<uint32_t>(v));
}
inline void store_f32(unsigned char* p, float v) {
    store_u32(p, std::bit_cast<uint32_t>(v));
}
inline void store_f64(unsigned char* p, double v) {
    store_u64(p, std::bit_cast<uint64_t>(v));
}

} // namespace sss::detail
