// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file image_file.cpp
/// write_image_file(): the one OpenImageIO writer of the library.

#include "sss/image/image_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include "sss/util/atomic_output.h"
#include "sss/util/error.h"

namespace sss {

namespace {

OIIO::TypeDesc type_of(PixelType t) {
    switch (t) {
    case PixelType::UInt8:
        return OIIO::TypeDesc::UINT8;
    case PixelType::UInt16:
        return OIIO::TypeDesc::UINT16;
    case PixelType::Half:
        return OIIO::TypeDesc::HALF;
    case PixelType::Float:
        break;
    }
    return OIIO::TypeDesc::FLOAT;
}

struct AddAttribute {
    OIIO::ImageSpec& spec;
    const std::string& name;
    void operator()(const std::string& v) const { spec.attribute(name, v); }
    void operator()(int v) const { spec.attribute(name, v); }
    void operator()(float v) const { spec.attribute(name, v); }
    void operator()(const std::array<float, 16>& v) const {
        spec.attribute(name, OIIO::TypeMatrix44, v.data());
    }
};

/// The largest side libjpeg writes: beyond it, its error handler calls exit().
constexpr int kJpegMaxSide = 65500;

/// OpenImageIO's writers write into this instead of a FILE: every byte goes
/// to the temporary with pwrite(), and the first failure (a full disk, a
/// quota, an I/O error) is kept to be reported after close(). The writers are
/// always told that the bytes were written: libjpeg's error handler calls
/// exit() on a short write, and libpng's and OpenEXR's writers do not all
/// check the result.
class CheckedFileProxy final : public OIIO::Filesystem::IOProxy {
public:
    CheckedFileProxy(const std::string& path, int fd) : IOProxy(path, Write), m_fd(fd) {}
    const char* proxytype() const override { return "sss_checked_file"; }
    size_t write(const void* buf, size_t size) override {
        pwrite(buf, size, m_pos);
        m_pos += int64_t(size);
        return size;
    }
    size_t pwrite(const void* buf, size_t size, int64_t offset) override {
        std::lock_guard lock(m_mutex);
        const size_t total = size;
        m_end = std::max(m_end, uint64_t(offset) + size);
        const char* p = static_cast<const char*>(buf);
        while (size > 0 && m_errno == 0) {
            const ssize_t n = ::pwrite(m_fd, p, size, offset);
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) {
                m_errno = n < 0 ? errno : ENOSPC;
                break;
            }
            p += n;
            size -= size_t(n);
            offset += n;
        }
        return total;
    }
    size_t read(void* buf, size_t size) override {
        const size_t n = pread(buf, size, m_pos);
        m_pos += int64_t(n);
        return n;
    }
    size_t pread(void* buf, size_t size, int64_t offset) override {
        const ssize_t n = ::pread(m_fd, buf, size, offset);
        return n < 0 ? 0 : size_t(n);
    }
    size_t size() const override { return size_t(m_end); }
    /// The first error (errno), or 0; then the file's size is checked
    /// against what the writer wrote.
    int error_number() const {
        if (m_errno != 0) return m_errno;
        struct stat st {};
        if (::fstat(m_fd, &st) != 0) return errno;
        return uint64_t(st.st_size) == m_end ? 0 : EIO;
    }

private:
    int m_fd;
    uint64_t m_end = 0; ///< the end of the data the writer wrote
    int m_errno = 0;
    std::mutex m_mutex;
};

/// The temporary opened for writing by the proxy, closed (and checked) once.
class TempFd {
public:
    explicit TempFd(const std::string& path)
        : m_fd(::open(path.c_str(), O_RDWR | O_CLOEXEC)) {}
    ~TempFd() {
        if (m_fd >= 0) ::close(m_fd);
    }
    TempFd(const TempFd&) = delete;
    TempFd& operator=(const TempFd&) = delete;
    int get() const { return m_fd; }
    /// close()'s errno, or 0.
    int close() {
        const int rc = ::close(m_fd);
        m_fd = -1;
        return rc == 0 ? 0 : errno;
    }

private:
    int m_fd;
};

/// "cannot write PNG: No space left on device".
std::string write_failure(const ImageFileSpec& spec, int err) {
    return "cannot write " + spec.what + ": " + std::strerror(err);
}

} // namespace

void write_image_file(const std::string& path, const ImageFileSpec& spec, PixelType data,
                      const void* pixels) {
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(spec.format);
    if (!out)
        throw IoError(path, "no '" + spec.format +
                                "' writer in OpenImageIO: " + OIIO::geterror());
    OIIO::ImageSpec oiio(spec.width, spec.height, int(spec.channel_names.size()),
                         type_of(spec.stored));
    oiio.channelnames = spec.channel_names;
    oiio.alpha_channel = spec.alpha_channel;
    oiio.z_channel = spec.z_channel;
    if (!spec.channel_stored.empty())
        for (PixelType t : spec.channel_stored) oiio.channelformats.push_back(type_of(t));
    for (const ImageAttribute& a : spec.attributes)
        std::visit(AddAttribute{oiio, a.name}, a.value);
    if (spec.format == "jpeg" && std::max(spec.width, spec.height) > kJpegMaxSide)
        throw IoError(path, "cannot write " + spec.what + ": a JPEG file holds at most " +
                                std::to_string(kJpegMaxSide) + " pixels a side, not " +
                                std::to_string(std::max(spec.width, spec.height)));
    if (!out->supports("ioproxy"))
        throw IoError(path, "the '" + spec.format +
                                "' writer of OpenImageIO cannot write through a checked "
                                "file");
    AtomicOutput file(path);
    TempFd fd(file.temp_path());
    if (fd.get() < 0)
        throw IoError(path, "cannot open the temporary '" + file.temp_path() +
                                "': " + std::strerror(errno));
    // The temporary is ".<name>.<random>.tmp": the writer is chosen by format
    // name above, so the extension does not matter.
    CheckedFileProxy proxy(file.temp_path(), fd.get());
    if (!out->set_ioproxy(&proxy) || !out->open(file.temp_path(), oiio))
        throw IoError(path, "cannot write " + spec.what + ": " + out->geterror());
    bool ok = out->write_image(type_of(data), pixels);
    ok = out->close() && ok;
    // A full disk first: the writer's own message then says less.
    if (int err = proxy.error_number()) throw IoError(path, write_failure(spec, err));
    if (!ok) throw IoError(path, "cannot write " + spec.what + ": " + out->geterror());
    if (int err = fd.close()) throw IoError(path, write_failure(spec, err));
    file.commit();
}

} // namespace sss
