// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file image_check.cpp
/// Image checks without OpenImageIO: headers held against the limits, PNG
/// files read whole (check_image_file, which reads other headers with
/// OpenImageIO, is in image_check_oiio.cpp: a tool that checks only through
/// these does not load OpenImageIO).

#include "sss/image/image_check.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <vector>

#include <zlib.h>

#include "sss/util/error.h"
#include "sss/util/limits.h"

namespace sss {

namespace {

constexpr unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

uint32_t big_endian(const unsigned char* p) {
    return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3];
}

void check_size(const std::string& path, const ImageHeader& h) {
    check_limit(Limit::ImageSide, uint64_t(std::max(h.width, h.height)), path);
    check_limit(Limit::ImagePixels, uint64_t(h.width) * uint64_t(h.height), path);
    if (h.channels > kMaxImageChannels)
        throw FormatError(path, std::to_string(h.channels) +
                                    " channels; an image may have at most " +
                                    std::to_string(kMaxImageChannels));
    if (h.tile_width > 0 && h.tile_height > 0) {
        const long long tiles =
            ((long long)h.width + h.tile_width - 1) / h.tile_width *
            (((long long)h.height + h.tile_height - 1) / h.tile_height);
        if (tiles > kMaxImageTiles)
            throw FormatError(
                path, std::to_string(h.width) + " x " + std::to_string(h.height) +
                          " pixels in " + std::to_string(h.tile_width) + " x " +
                          std::to_string(h.tile_height) +
                          " tiles: " + std::to_string(tiles) + " tiles; at most " +
                          std::to_string(kMaxImageTiles) + " are read");
    }
}

/// A PNG file read chunk by chunk, its image data inflated and counted
/// (never held): libpng, which prints its errors on stderr before OpenImageIO
/// sees them, only ever reads a file that passed.
class PngCheck {
public:
    PngCheck(const std::string& path, std::ifstream& in) : m_path(path), m_in(in) {}
    ~PngCheck() {
        if (m_inflating) inflateEnd(&m_z);
    }
    PngCheck(const PngCheck&) = delete;
    PngCheck& operator=(const PngCheck&) = delete;

    ImageHeader run() {
        bool ended = false, palette = false;
        for (int index = 0; !ended; ++index) {
            unsigned char head[8];
            read(head, 8);
            const uint32_t length = big_endian(head);
            if (length > 0x7fffffffu)
                fail("a chunk of " + std::to_string(length) + " bytes");
            const std::string type(reinterpret_cast<char*>(head) + 4, 4);
            for (char c : type)
                if (!std::isalpha(static_cast<unsigned char>(c)))
                    fail("a chunk type that is not four letters");
            if (index == 0 && type != "IHDR") fail("no IHDR chunk first");
            uLong crc = crc32(0L, head + 4, 4);
            std::vector<unsigned char> data;
            if (type == "IHDR" || type == "IDAT" || type == "PLTE") data.resize(length);
            read_data(length, data, crc);
            unsigned char stored[4];
            read(stored, 4);
            if (big_endian(stored) != uint32_t(crc)) fail("a CRC error in chunk " + type);
            if (type == "IHDR") {
                if (index != 0 || length != 13)
                    fail("an IHDR chunk that is not 13 bytes first");
                header(data.data());
                check_size(m_path, m_header);
            } else if (type == "PLTE") {
                palette = true;
            } else if (type == "IDAT") {
                if (m_color == 3 && !palette) fail("no PLTE chunk before the image data");
                if (m_idat_done) fail("image data chunks that are not consecutive");
                inflate_data(data);
            } else if (type == "IEND") {
                ended = true;
            }
            if (type != "IDAT" && m_inflating) m_idat_done = true;
        }
        if (!m_inflating) fail("no image data");
        if (!m_stream_end || m_rows_bytes != m_expected)
            fail("its image data end after " + std::to_string(m_rows_bytes) + " of " +
                 std::to_string(m_expected) + " bytes (a truncated file?)");
        return m_header;
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw FormatError(m_path, "damaged PNG: " + what);
    }

    void read(unsigned char* p, std::size_t n) {
        if (!m_in.read(reinterpret_cast<char*>(p), std::streamsize(n)))
            fail("the file ends inside a chunk (a truncated file?)");
    }

    /// The chunk's data into `data` when it is kept, else skipped; CRC'd.
    void read_data(uint32_t length, std::vector<unsigned char>& data, uLong& crc) {
        if (!data.empty() || length == 0) {
            // (zlib's crc32 of a null buffer is its initial value, not crc.)
            if (length == 0) return;
            read(data.data(), length);
            crc = crc32(crc, data.data(), uInt(data.size()));
            return;
        }
        std::array<unsigned char, 65536> buf;
        for (uint32_t left = length; left > 0;) {
            const uint32_t n = std::min<uint32_t>(left, uint32_t(buf.size()));
            read(buf.data(), n);
            crc = crc32(crc, buf.data(), n);
            left -= n;
        }
    }

    void header(const unsigned char* d) {
        const uint32_t w = big_endian(d), h = big_endian(d + 4);
        if (w == 0 || h == 0 || w > 0x7fffffffu || h > 0x7fffffffu)
            fail("an image of " + std::to_string(w) + " x " + std::to_string(h) +
                 " pixels");
        const int depth = d[8];
        m_color = d[9];
        static constexpr int kChannels[7] = {1, 0, 3, 1, 2, 0, 4};
        const bool color_ok = m_color <= 6 && kChannels[m_color] != 0;
        const bool depth_ok = color_ok &&
                              (depth == 8 || depth == 16 ||
                               ((m_color == 0 || m_color == 3) &&
                                (depth == 1 || depth == 2 || depth == 4))) &&
                              !(m_color == 3 && depth == 16);
        if (!depth_ok)
            fail("colour type " + std::to_string(m_color) + " with " +
                 std::to_string(depth) + " bits");
        if (d[10] != 0 || d[11] != 0 || d[12] > 1)
            fail("an unknown compression, filter or interlace method");
        m_header.width = int(w);
        m_header.height = int(h);
        m_header.channels = m_color == 3 ? 3 : kChannels[m_color];
        m_bits_per_pixel = kChannels[m_color] * depth;
        m_interlaced = d[12] == 1;
        // The filtered rows' bytes: one filter byte per row (of each pass).
        auto rows = [&](uint64_t pw, uint64_t ph) {
            return pw == 0 || ph == 0 ? 0 : ph * (1 + (pw * m_bits_per_pixel + 7) / 8);
        };
        if (!m_interlaced) {
            m_expected = rows(w, h);
            m_row_bytes = 1 + (uint64_t(w) * m_bits_per_pixel + 7) / 8;
        } else {
            // Adam7: the passes' origins and steps.
            static constexpr int kPass[7][4] = {{0, 0, 8, 8}, {4, 0, 8, 8}, {0, 4, 4, 8},
                                                {2, 0, 4, 4}, {0, 2, 2, 4}, {1, 0, 2, 2},
                                                {0, 1, 1, 2}};
            for (const auto& p : kPass)
                m_expected += rows((uint64_t(w) + p[2] - 1 - p[0]) / p[2],
                                   (uint64_t(h) + p[3] - 1 - p[1]) / p[3]);
        }
    }

    void inflate_data(std::vector<unsigned char>& data) {
        if (!m_inflating) {
            std::memset(&m_z, 0, sizeof m_z);
            if (inflateInit(&m_z) != Z_OK) fail("zlib cannot start");
            m_inflating = true;
        }
        if (m_stream_end) {
            if (!data.empty()) fail("image data after the end of the compressed stream");
            return;
        }
        std::array<unsigned char, 65536> out;
        m_z.next_in = data.data();
        m_z.avail_in = uInt(data.size());
        while (m_z.avail_in > 0 && !m_stream_end) {
            m_z.next_out = out.data();
            m_z.avail_out = uInt(out.size());
            const int rc = inflate(&m_z, Z_NO_FLUSH);
            if (rc != Z_OK && rc != Z_STREAM_END && rc != Z_BUF_ERROR)
                fail("its compressed image data are invalid (" +
                     std::string(m_z.msg ? m_z.msg : "zlib error") + ")");
            const uint64_t produced = out.size() - m_z.avail_out;
            check_filters(out.data(), produced);
            m_rows_bytes += produced;
            if (m_rows_bytes > m_expected)
                fail("more image data than its " + std::to_string(m_header.width) +
                     " x " + std::to_string(m_header.height) + " pixels");
            m_stream_end = rc == Z_STREAM_END;
            if (rc == Z_BUF_ERROR && produced == 0) break;
        }
    }

    /// Each row's first byte is a filter type 0..4 (checked without interlace).
    void check_filters(const unsigned char* p, uint64_t n) {
        if (m_interlaced) return;
        for (uint64_t at = m_rows_bytes; at < m_rows_bytes + n;) {
            const uint64_t into = at % m_row_bytes;
            if (into == 0) {
                if (p[at - m_rows_bytes] > 4)
                    fail("row " + std::to_string(at / m_row_bytes) + " has filter type " +
                         std::to_string(p[at - m_rows_bytes]));
                at += m_row_bytes;
            } else {
                at += m_row_bytes - into;
            }
        }
    }

    const std::string& m_path;
    std::ifstream& m_in;
    ImageHeader m_header;
    int m_color = 0;
    int m_bits_per_pixel = 0;
    bool m_interlaced = false;
    uint64_t m_expected = 0;  ///< the filtered rows' bytes the header declares
    uint64_t m_row_bytes = 0; ///< without interlace: one row with its filter byte
    uint64_t m_rows_bytes = 0;
    z_stream m_z;
    bool m_inflating = false;
    bool m_stream_end = false;
    bool m_idat_done = false;
};

} // namespace

void check_image_header(const std::string& path, const ImageHeader& h) {
    if (h.width <= 0 || h.height <= 0)
        throw FormatError(path, "an image of " + std::to_string(h.width) + " x " +
                                    std::to_string(h.height) + " pixels");
    check_size(path, h);
}

std::optional<ImageHeader> check_png_file(const std::string& path) {
    // A FIFO or device would block or never end: the caller's reader refuses it.
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) return std::nullopt;
    std::ifstream in(path, std::ios::binary);
    unsigned char sig[8] = {};
    if (in && in.read(reinterpret_cast<char*>(sig), 8) &&
        std::memcmp(sig, kPngSignature, 8) == 0) {
        PngCheck png(path, in);
        return png.run();
    }
    return std::nullopt;
}

} // namespace sss
