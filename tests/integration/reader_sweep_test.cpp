// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Bad-input sweeps over the four readers (.ptc plain and gzip, .ply, .bkm,
// RIB): truncation at every offset (or a dense sample), seeded single-bit
// flips, huge header counts under a tight address-space limit, wrong magic and
// NaN/Inf values. The only acceptable outcomes are a typed sss::Error or, for
// a flip that keeps the file valid, a result whose values are all finite.
// Also checks that the fuzzers' seeds (tests/fuzz/corpus) still read; the
// ctests fuzz_replay.<target> run every committed input through the
// targets themselves (docs/fuzzing.md).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/cloud/synthetic.h"
#include "sss/scene/rib.h"
#include "sss/util/error.h"
#include "test_util.h"

#include "sss/util/byte_io.h" // ByteSink: gzip files for the sweeps

#if defined(__SANITIZE_ADDRESS__)
#define SSS_SWEEP_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SSS_SWEEP_ASAN 1
#endif
#endif

namespace fs = std::filesystem;
using sss::test::TempDir;

namespace {

using sss::test::Bytes;
using sss::test::read_bytes;
using sss::test::write_bytes;

enum class Format { Ptc, Ply, Bkm, Rib };

const char* format_name(Format f) {
    switch (f) {
    case Format::Ptc:
        return "ptc";
    case Format::Ply:
        return "ply";
    case Format::Bkm:
        return "bkm";
    case Format::Rib:
        return "rib";
    }
    return "?";
}

void put_u32(Bytes& b, std::size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) b[at + i] = static_cast<unsigned char>(v >> (8 * i));
}
void put_f32(Bytes& b, std::size_t at, float v) {
    uint32_t u = 0;
    std::memcpy(&u, &v, 4);
    put_u32(b, at, u);
}
void put_f64(Bytes& b, std::size_t at, double v) {
    uint64_t u = 0;
    std::memcpy(&u, &v, 8);
    for (int i = 0; i < 8; ++i) b[at + i] = static_cast<unsigned char>(u >> (8 * i));
}
uint32_t get_u32(const Bytes& b, std::size_t at) {
    return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 |
           uint32_t(b[at + 3]) << 24;
}
uint64_t get_u64(const Bytes& b, std::size_t at) {
    return uint64_t(get_u32(b, at)) | (uint64_t(get_u32(b, at + 4)) << 32);
}

bool finite3(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// Empty when the cloud is consistent and finite, else what is wrong.
std::string cloud_problem(const sss::PointCloud& c) {
    const std::size_t n = c.size();
    if (c.normals.size() != n || c.radii.size() != n) return "array sizes disagree";
    for (std::size_t i = 0; i < n; ++i) {
        if (!finite3(c.positions[i]) || !finite3(c.normals[i]))
            return "non-finite vector";
        if (!std::isfinite(c.radii[i]) || c.radii[i] < 0.0f) return "bad radius";
    }
    for (const sss::Channel& ch : c.channels) {
        if (ch.data.size() != n * static_cast<std::size_t>(ch.components()))
            return "channel '" + ch.name + "' has the wrong size";
        for (float v : ch.data)
            if (!std::isfinite(v)) return "non-finite value in '" + ch.name + "'";
    }
    for (float v : c.world_to_eye)
        if (!std::isfinite(v)) return "non-finite world2eye";
    for (float v : c.world_to_ndc)
        if (!std::isfinite(v)) return "non-finite world2ndc";
    return {};
}

/// Opens a brick map and touches every brick (bricks load on demand), plus a
/// few lookups: empty or a description of a broken invariant. Without the
/// checksums, which would catch every change first, so that the sweeps reach
/// the structural checks (the checksums: tests/brick/bkm_integrity_test.cpp).
std::string brick_map_problem(const std::string& path) {
    const sss::BrickMap map(path, 1u << 20, sss::BrickMapChecksums::Ignore);
    const sss::BrickMapInfo& info = map.info();
    std::vector<float> data;
    std::vector<uint8_t> present;
    for (int tree = 0; tree < 7; ++tree) {
        for (int depth = 0; depth < static_cast<int>(info.levels.size()); ++depth) {
            for (const auto& c : map.bricks_at(tree, depth)) {
                if (!map.read_brick(tree, depth, c[0], c[1], c[2], data, present))
                    return "a listed brick cannot be read";
                for (float v : data)
                    if (!std::isfinite(v)) return "non-finite brick value";
            }
        }
    }
    std::vector<float> out(static_cast<std::size_t>(info.data_size));
    for (double f : {0.1, 0.5, 0.9}) {
        const glm::vec3 p(info.cube_min + glm::dvec3(f) * info.cube_side);
        for (const glm::vec3 n :
             {glm::vec3(0.0f), glm::vec3(0, 0, 1), glm::vec3(1, 0, 0)}) {
            if (map.lookup(p, n, 0.0f, out.data())) {
                for (float v : out)
                    if (std::isnan(v)) return "NaN from a lookup";
            }
        }
    }
    return {};
}

enum class Outcome { Read, Error };

/// With write_back: a cloud that was read must also be writable (the readers
/// promise it; a fuzzer found names that were not). Empty or the problem.
std::string write_back_problem(const sss::PointCloud& cloud, const std::string& path) {
    const std::string out = path + ".back.ptc";
    try {
        sss::write_ptc(cloud, out);
        sss::read_ptc(out);
    } catch (const std::exception& e) {
        std::remove(out.c_str());
        return std::string("cannot be written and read back: ") + e.what();
    }
    std::remove(out.c_str());
    return {};
}

/// Reads path as `format`. Returns Read (after checking the result) or Error
/// (an sss::Error, message in *message); any other exception or a broken
/// invariant is a test failure naming `context`. With write_back, clouds are
/// also written and read back.
Outcome read_as(Format format, const std::string& path, const std::string& context,
                std::string* message = nullptr, bool write_back = false) {
    try {
        std::string problem;
        switch (format) {
        case Format::Ptc:
        case Format::Ply: {
            const sss::PointCloud cloud =
                format == Format::Ptc ? sss::read_ptc(path) : sss::read_ply(path);
            problem = cloud_problem(cloud);
            if (problem.empty() && write_back) problem = write_back_problem(cloud, path);
            break;
        }
        case Format::Bkm:
            problem = brick_map_problem(path);
            break;
        case Format::Rib: {
            // Leniently: what is not implemented is skipped, the rest read.
            sss::RibReadOptions options;
            options.lenient = true;
            sss::read_rib(path, options);
            break;
        }
        }
        EXPECT_EQ(problem, "") << format_name(format) << ", " << context;
        return Outcome::Read;
    } catch (const sss::Error& e) {
        if (message) *message = e.what();
        // Every message names the file it is about.
        EXPECT_NE(std::string(e.what()).find(fs::path(path).filename().string()),
                  std::string::npos)
            << format_name(format) << ", " << context << ": " << e.what();
        return Outcome::Error;
    } catch (const std::exception& e) {
        ADD_FAILURE() << format_name(format) << ", " << context
                      << ": exception other than sss::Error: " << e.what();
    } catch (...) {
        ADD_FAILURE() << format_name(format) << ", " << context << ": non-std exception";
    }
    return Outcome::Error;
}

/// The sss::Error message of reading bytes (empty, plus a failure, if it reads).
std::string error_of(Format format, const TempDir& dir, const Bytes& bytes,
                     const std::string& context) {
    const std::string path = dir.file(std::string("case.") + format_name(format));
    write_bytes(path, bytes);
    std::string message;
    EXPECT_EQ(read_as(format, path, context, &message), Outcome::Error)
        << format_name(format) << ", " << context << ": read without an error";
    return message;
}

/// A small cloud with every kind of channel layout the writers produce.
sss::PointCloud small_cloud() {
    sss::SyntheticParams p;
    p.count = 24;
    p.size = 2.0;
    p.light_dir = {0.3, 0.4, 1.0};
    sss::PointCloud c = sss::make_synthetic_cloud(p); // _area, _radiance_t
    sss::Channel& n = c.add_channel("dir", sss::ChannelType::Normal);
    for (std::size_t i = 0; i < n.data.size(); ++i) n.data[i] = 0.25f * float(i % 5);
    c.world_to_eye[3] = 2.0f;
    c.format = {64.0f, 48.0f, 1.0f};
    return c;
}

/// Bytes of the sample file of each format (written by our own writers, so
/// the sweeps start from valid files).
struct Samples {
    TempDir dir{"sss_sweep"};
    sss::PointCloud cloud = small_cloud();
    Bytes ptc, ptc_gz, ply, bkm, rib;
    Samples() {
        sss::PointCloudWriteOptions o;
        o.ptc_version = 2;
        sss::write_ptc(cloud, dir.file("s.ptc"), o);
        o.compress = true;
        o.ptc_version = 1;
        sss::write_ptc(cloud, dir.file("s_gz.ptc"), o);
        sss::write_ply(cloud, dir.file("s.ply"));
        sss::BrickMapBuildOptions b;
        b.max_depth = 1;
        b.max_error = 0.0;
        b.channels = {"_area"};
        sss::build_brick_map({cloud}, b, dir.file("s.bkm"));
        ptc = read_bytes(dir.file("s.ptc"));
        ptc_gz = read_bytes(dir.file("s_gz.ptc"));
        ply = read_bytes(dir.file("s.ply"));
        bkm = read_bytes(dir.file("s.bkm"));
        const std::string text = R"(Format 64 48 1
Projection "perspective" "fov" 40
Translate 0 0 5
Declare "k" "uniform float"
WorldBegin
LightSource "pointlight" 1 "from" [0 4 0] "intensity" [3]
AttributeBegin
Color [1 0.5 0.25]
Surface "matte" "Kd" [0.8]
Sphere 1 -1 1 360 "k" [2]
Polygon "P" [0 0 0 1 0 0 1 1 0 0 1 0] "N" [0 0 1 0 0 1 0 0 1 0 0 1]
PointsPolygons [3 3] [0 1 2 0 2 3] "P" [0 0 0 1 0 0 1 1 0 0 1 0] "uniform color Cs" [1 0 0 0 1 0]
SubdivisionMesh "catmull-clark" [4] [0 1 2 3] ["interpolateboundary" "crease"] [0 0 2 1] [0 1] [5] "P" [0 0 0 1 0 0 1 1 0 0 1 0]
PatchMesh "bilinear" 3 "nonperiodic" 2 "nonperiodic" "P" [0 0 0 1 0 0 2 0 0 0 1 0 1 1 0 2 1 0]
Torus 1 0.25 0 360 360
AttributeEnd
WorldEnd
)";
        rib.assign(text.begin(), text.end());
    }
};

const Samples& samples() {
    static const Samples s;
    return s;
}

struct Case {
    Format format;
    const Bytes* bytes;
    const char* label;
};

std::vector<Case> cases() {
    const Samples& s = samples();
    return {{Format::Ptc, &s.ptc, "ptc"},
            {Format::Ptc, &s.ptc_gz, "ptc gzip"},
            {Format::Ply, &s.ply, "ply"},
            {Format::Bkm, &s.bkm, "bkm"},
            {Format::Rib, &s.rib, "rib"}};
}

/// Soft RLIMIT_AS of the current address space plus `headroom` while alive:
/// an allocation driven by a huge header count then fails (bad_alloc, a test
/// failure) instead of succeeding quietly. Inactive under AddressSanitizer,
/// which reserves terabytes of address space.
class AddressSpaceLimit {
public:
    explicit AddressSpaceLimit(std::size_t headroom) {
#ifndef SSS_SWEEP_ASAN
        std::size_t vm_kb = 0;
        std::ifstream status("/proc/self/status");
        std::string line;
        while (std::getline(status, line)) {
            if (line.rfind("VmSize:", 0) == 0) vm_kb = std::stoul(line.substr(7));
        }
        if (vm_kb == 0 || ::getrlimit(RLIMIT_AS, &m_saved) != 0) return;
        rlimit tight = m_saved;
        tight.rlim_cur = vm_kb * 1024 + headroom;
        if (m_saved.rlim_cur != RLIM_INFINITY && m_saved.rlim_cur < tight.rlim_cur)
            return;
        m_active = ::setrlimit(RLIMIT_AS, &tight) == 0;
#else
        (void)headroom;
#endif
    }
    ~AddressSpaceLimit() {
        if (m_active) ::setrlimit(RLIMIT_AS, &m_saved);
    }
    AddressSpaceLimit(const AddressSpaceLimit&) = delete;
    AddressSpaceLimit& operator=(const AddressSpaceLimit&) = delete;
    bool active() const {
        return m_active;
    }

private:
    rlimit m_saved{};
    bool m_active = false;
};

bool contains(const std::string& s, const std::string& part) {
    return s.find(part) != std::string::npos;
}

} // namespace

// Every prefix of a binary file is an error (the sizes no longer add up or
// the gzip trailer is missing); a RIB prefix may be a valid scene, but must
// never crash. Every offset for the point clouds and RIB; for the brick map
// every offset of everything before the bricks and every 7th inside them.
TEST(ReaderSweep, TruncationAtEveryOffset) {
    TempDir dir;
    for (const Case& c : cases()) {
        const Bytes& good = *c.bytes;
        const std::string path = dir.file(std::string("cut.") + format_name(c.format));
        const std::size_t dense = c.format == Format::Bkm
                                      ? static_cast<std::size_t>(get_u64(good, 280))
                                      : good.size();
        int errors = 0, reads = 0;
        for (std::size_t cut = 0; cut < good.size(); cut += cut < dense ? 1 : 7) {
            write_bytes(path, Bytes(good.begin(), good.begin() + static_cast<long>(cut)));
            const Outcome o = read_as(
                c.format, path, std::string(c.label) + " cut at " + std::to_string(cut));
            (o == Outcome::Error ? errors : reads)++;
            if (c.format != Format::Rib) {
                EXPECT_EQ(o, Outcome::Error) << c.label << " cut at " << cut << " read";
            }
        }
        EXPECT_GT(errors, 0) << c.label;
        // The whole file reads.
        write_bytes(path, good);
        EXPECT_EQ(read_as(c.format, path, std::string(c.label) + " intact"),
                  Outcome::Read)
            << c.label;
        if (c.format == Format::Rib) {
            EXPECT_GT(reads, 0);
        }
    }
}

// 2000 seeded single-bit flips per format: an error, or a result whose values
// are all finite (read_as checks). Most flips in the point data change a
// value and still read; the checks make sure none turns into NaN/Inf.
TEST(ReaderSweep, SeededBitFlips) {
    TempDir dir;
    for (const Case& c : cases()) {
        const Bytes& good = *c.bytes;
        const std::string path = dir.file(std::string("flip.") + format_name(c.format));
        std::mt19937_64 rng(0x5eed0000u + static_cast<unsigned>(c.format) * 7u +
                            static_cast<unsigned>(good.size()));
        int errors = 0, reads = 0;
        for (int k = 0; k < 2000; ++k) {
            Bytes b = good;
            const std::size_t at = static_cast<std::size_t>(rng() % b.size());
            const int bit = static_cast<int>(rng() % 8);
            b[at] ^= static_cast<unsigned char>(1u << bit);
            write_bytes(path, b);
            const Outcome o =
                read_as(c.format, path,
                        std::string(c.label) + " bit " + std::to_string(bit) +
                            " of byte " + std::to_string(at) + " flipped");
            (o == Outcome::Error ? errors : reads)++;
        }
        // Both outcomes occur: the sweep reaches checks and data alike.
        EXPECT_GT(errors, 0) << c.label;
        if (c.format != Format::Ptc || &good != &samples().ptc_gz) {
            EXPECT_GT(reads, 0) << c.label; // a gzip CRC catches every flip
        }
    }
}

// Header counts far beyond the file: an error naming the problem, without
// allocating for the claimed count (address space limited to +256 MB).
TEST(ReaderSweep, HugeCountsFailFastWithoutAllocating) {
    const Samples& s = samples();
    TempDir dir;
    const AddressSpaceLimit limit(256u << 20);
#ifndef SSS_SWEEP_ASAN
    // The limit bites: 512 MB cannot be allocated while it holds.
    ASSERT_TRUE(limit.active());
    EXPECT_THROW(std::vector<char>(std::size_t(512) << 20), std::bad_alloc);
#endif
    const std::size_t n = s.cloud.size();

    // .ptc: the point count is a double at offset 8.
    for (double count : {9007199254740992.0, 1e12, double(n + 1)}) {
        Bytes b = s.ptc;
        put_f64(b, 8, count);
        const std::string what = error_of(Format::Ptc, dir, b, "ptc count");
        EXPECT_TRUE(contains(what, "truncated point data")) << what;
        EXPECT_TRUE(contains(what, "bytes remain")) << what;
    }
    // gzip: a count the compressed size cannot hold fails before reading data;
    // a plausible one fails when the data ends (growing as data arrives).
    for (double count : {1e12, 5e7, double(n + 1), double(n + 100)}) {
        Bytes plain = s.ptc;
        put_f64(plain, 8, count);
        const std::string path = dir.file("count_gz.ptc");
        {
            sss::detail::ByteSink sink(path, path, true);
            sink.write(plain.data(), plain.size());
            sink.close();
        }
        std::string what;
        EXPECT_EQ(read_as(Format::Ptc, path, "gzip ptc count", &what), Outcome::Error);
        EXPECT_TRUE(contains(what, count > 1e6 ? "more than the compressed file can hold"
                                               : "truncated point data"))
            << what;
    }
    // gzip whose size allows the claim (400 KB of trailing bytes, which zlib
    // ignores, raise the bound to 8.9 million points of 48 bytes) but whose
    // data ends after the sample's points: the arrays grow with the data, so
    // the end of the data is reached (a FormatError) long before 8 million
    // points (450 MB of arrays) would have been reserved under the 256 MB
    // limit. The same for a binary and an ASCII PLY.
    {
        const auto gzip_padded = [&](const Bytes& plain, const std::string& name) {
            const std::string path = dir.file(name);
            {
                sss::detail::ByteSink sink(path, path, true);
                sink.write(plain.data(), plain.size());
                sink.close();
            }
            Bytes b = read_bytes(path);
            b.resize(b.size() + (400u << 10), 0);
            write_bytes(path, b);
            return path;
        };
        Bytes plain = s.ptc;
        put_f64(plain, 8, 8e6);
        std::string what;
        EXPECT_EQ(read_as(Format::Ptc, gzip_padded(plain, "padded_gz.ptc"), "padded ptc",
                          &what),
                  Outcome::Error);
        EXPECT_TRUE(contains(what, "header claims 8000000 points, data ends after " +
                                       std::to_string(n)))
            << what;
        std::string text(s.ply.begin(), s.ply.end());
        const std::string key = "element vertex " + std::to_string(n);
        // 5 million vertices of 56 bytes (420 MB of arrays) fit the bound.
        text.replace(text.find(key), key.size(), "element vertex 5000000");
        what.clear();
        EXPECT_EQ(read_as(Format::Ply,
                          gzip_padded(Bytes(text.begin(), text.end()), "padded_gz.ply"),
                          "padded ply", &what),
                  Outcome::Error);
        EXPECT_TRUE(contains(what, "header claims 5000000 vertices, data ends after " +
                                       std::to_string(n)))
            << what;
        std::string ascii = "ply\nformat ascii 1.0\nelement vertex 20000000\n"
                            "property float x\nproperty float y\nproperty float z\n"
                            "end_header\n0 0 0\n1 1 1\n";
        what.clear();
        EXPECT_EQ(read_as(Format::Ply,
                          gzip_padded(Bytes(ascii.begin(), ascii.end()), "ascii_gz.ply"),
                          "padded ascii ply", &what),
                  Outcome::Error);
        EXPECT_TRUE(contains(what, "data ends after 2 (point 2)")) << what;
    }
    // .ply: the vertex count on the element line.
    for (const char* count :
         {"1000000000000", "9007199254740992", "99999999999999999999"}) {
        std::string text(s.ply.begin(), s.ply.end());
        const std::string key = "element vertex " + std::to_string(n);
        const std::size_t at = text.find(key);
        ASSERT_NE(at, std::string::npos);
        text.replace(at, key.size(), std::string("element vertex ") + count);
        const std::string what =
            error_of(Format::Ply, dir, Bytes(text.begin(), text.end()), "ply count");
        EXPECT_TRUE(contains(what, "vertex count") || contains(what, "too short"))
            << what;
    }
    {
        const std::string ascii = "ply\nformat ascii 1.0\nelement vertex 500000000000\n"
                                  "property float x\nproperty float y\nproperty float z\n"
                                  "end_header\n0 0 0\n";
        const std::string what = error_of(
            Format::Ply, dir, Bytes(ascii.begin(), ascii.end()), "ascii ply count");
        EXPECT_TRUE(contains(what, "too short")) << what;
    }
    // .bkm: channel count, data size, provenance length and a tree's node count.
    const std::size_t dir_at = 288 + get_u32(s.bkm, 44) + get_u32(s.bkm, 40);
    const struct {
        std::size_t at;
        uint32_t value;
        const char* expect;
    } bkm_cases[] = {{24, 0xffffffffu, "channel count"},
                     {28, 0x7fffffffu, "data size"},
                     {40, 0xfffffff0u, "provenance length"},
                     {44, 0xfffffff0u, "channel table size"},
                     {dir_at + 8, 0xfffffff0u, "does not fit"},
                     {dir_at + 6 * 16 + 8, 0x10000000u, "does not fit"}};
    for (const auto& bc : bkm_cases) {
        Bytes b = s.bkm;
        put_u32(b, bc.at, bc.value);
        const std::string what = error_of(Format::Bkm, dir, b, bc.expect);
        EXPECT_TRUE(contains(what, bc.expect)) << what;
    }
    // RIB: counts come from the text itself; a huge repeat count is a number.
    {
        const std::string text =
            "WorldBegin\nPatchMesh \"bilinear\" 2000000000 \"nonperiodic\" "
            "2000000000 \"nonperiodic\" \"P\" [0 0 0]\nWorldEnd\n";
        error_of(Format::Rib, dir, Bytes(text.begin(), text.end()), "rib patch counts");
    }
}

TEST(ReaderSweep, WrongMagic) {
    const Samples& s = samples();
    TempDir dir;
    Bytes b = s.ptc;
    b[0] = 'x';
    EXPECT_TRUE(contains(error_of(Format::Ptc, dir, b, "ptc magic"), "not a .ptc file"));
    b = s.ply;
    b[2] = 'x';
    EXPECT_TRUE(contains(error_of(Format::Ply, dir, b, "ply magic"), "not a PLY file"));
    b = s.bkm;
    b[3] = 'x';
    EXPECT_TRUE(contains(error_of(Format::Bkm, dir, b, "bkm magic"), "bad magic"));
    // Each reader given another format's file.
    EXPECT_TRUE(
        contains(error_of(Format::Ptc, dir, s.ply, "ply as ptc"), "not a .ptc file"));
    EXPECT_TRUE(
        contains(error_of(Format::Ply, dir, s.ptc, "ptc as ply"), "not a PLY file"));
    EXPECT_TRUE(contains(error_of(Format::Bkm, dir, s.ptc, "ptc as bkm"), "bkm"));
    EXPECT_TRUE(
        contains(error_of(Format::Ptc, dir, s.bkm, "bkm as ptc"), "not a .ptc file"));
    const std::string rib_error = error_of(Format::Rib, dir, s.ptc, "ptc as rib");
    EXPECT_FALSE(rib_error.empty());
}

// NaN and Inf in the data: a FormatError naming the point (clouds), the brick
// (brick maps) or the line (RIB).
TEST(ReaderSweep, NonFiniteValues) {
    const Samples& s = samples();
    TempDir dir;
    const std::size_t n = s.cloud.size();
    const std::size_t ptc_record = 20 + 4 * static_cast<std::size_t>(s.cloud.data_size());
    const std::size_t ptc_data = s.ptc.size() - n * ptc_record;
    // Our PLY: x y z nx ny nz radius, the 3 bytes of the display colour (the
    // cloud has a color channel), then the channel floats.
    ASSERT_NE(sss::ply_display_channel(s.cloud), nullptr);
    const std::size_t ply_stride =
        4 * (7 + static_cast<std::size_t>(s.cloud.data_size())) + 3;
    const std::size_t ply_data = s.ply.size() - n * ply_stride;
    const float bad[] = {std::nanf(""), INFINITY, -INFINITY};
    for (float v : bad) {
        // .ptc: position x, radius and the last channel float of point 3.
        for (std::size_t field : {std::size_t(0), std::size_t(16), ptc_record - 4}) {
            Bytes b = s.ptc;
            put_f32(b, ptc_data + 3 * ptc_record + field, v);
            const std::string what = error_of(Format::Ptc, dir, b, "ptc non-finite");
            EXPECT_TRUE(contains(what, "non-finite")) << what;
            EXPECT_TRUE(contains(what, "(point 3)")) << what;
        }
        // .ply: x, nx and the last property of vertex 5.
        for (std::size_t field : {std::size_t(0), std::size_t(12), ply_stride - 4}) {
            Bytes b = s.ply;
            put_f32(b, ply_data + 5 * ply_stride + field, v);
            const std::string what = error_of(Format::Ply, dir, b, "ply non-finite");
            EXPECT_TRUE(contains(what, "non-finite")) << what;
            EXPECT_TRUE(contains(what, "(point 5)")) << what;
        }
        // .bkm: the first float of the first brick (after its presence mask).
        Bytes b = s.bkm;
        put_f32(b, static_cast<std::size_t>(get_u64(b, 280)) + 64, v);
        const std::string what = error_of(Format::Bkm, dir, b, "bkm non-finite");
        EXPECT_TRUE(contains(what, "non-finite value in sample")) << what;
        EXPECT_TRUE(contains(what, "brick of tree")) << what;
        // Header values: a matrix entry in each binary format.
        b = s.bkm;
        put_f32(b, 136, v);
        EXPECT_TRUE(contains(error_of(Format::Bkm, dir, b, "bkm matrix"), "world2eye"));
    }
    // ASCII PLY and RIB spell them out.
    for (const char* word : {"nan", "inf", "-inf", "1e39"}) {
        const std::string ply = std::string("ply\nformat ascii 1.0\nelement vertex 2\n"
                                            "property float x\nproperty float y\n"
                                            "property float z\nend_header\n0 0 0\n1 ") +
                                word + " 0\n";
        const std::string what =
            error_of(Format::Ply, dir, Bytes(ply.begin(), ply.end()), "ascii ply");
        EXPECT_TRUE(contains(what, "non-finite")) << what;
        EXPECT_TRUE(contains(what, "(point 1)")) << what;
    }
    for (const char* word : {"nan", "inf", "1e999", "-1e400"}) {
        const std::string rib = std::string("WorldBegin\nTranslate 0 0 1\nSphere 1 -1 ") +
                                word + " 360\nWorldEnd\n";
        const std::string what =
            error_of(Format::Rib, dir, Bytes(rib.begin(), rib.end()), "rib number");
        EXPECT_TRUE(contains(what, ":3:")) << what; // the line
        EXPECT_TRUE(contains(what, word)) << what;
    }
}

namespace {

/// Every file in folder `sub`/<format>/ of tests/fuzz.
std::vector<fs::path> fuzz_files(const std::string& sub, Format format) {
    const fs::path folder =
        fs::path(SSS_TEST_DATA_DIR) / ".." / "fuzz" / sub / format_name(format);
    std::vector<fs::path> files;
    if (fs::is_directory(folder)) {
        for (const auto& e : fs::directory_iterator(folder))
            if (e.is_regular_file()) files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    return files;
}

} // namespace

// The fuzzers' seeds must stay valid files of their format (else the fuzzer
// starts from rejected inputs only). RIB seeds are read from a copy in an
// empty folder, as the fuzzer does.
TEST(FuzzInputs, SeedCorpusReads) {
    TempDir dir;
    for (Format f : {Format::Ptc, Format::Ply, Format::Bkm, Format::Rib}) {
        const std::vector<fs::path> files = fuzz_files("corpus", f);
        EXPECT_GE(files.size(), 1u) << format_name(f);
        for (const fs::path& p : files) {
            const std::string copy = dir.file(p.filename().string());
            fs::copy_file(p, copy, fs::copy_options::overwrite_existing);
            EXPECT_EQ(read_as(f, copy, "seed " + p.string(), nullptr, true),
                      Outcome::Read)
                << p;
        }
    }
}

// A PLY header may not declare more channels than a cloud can have (what
// a .ptc can hold, so that every cloud read can be written), nor more
// properties than those channels could use: a tiny header cannot make the
// reader build hundreds of thousands of channels.
TEST(ReaderSweep, PlyChannelAndPropertyCaps) {
    TempDir dir;
    const auto ply_with = [](int extra) {
        std::string text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                           "property float y\nproperty float z\n";
        for (int i = 0; i < extra; ++i)
            text += "property uchar c" + std::to_string(i) + "\n";
        text += "end_header\n0 0 0";
        for (int i = 0; i < extra; ++i) text += " 1";
        text += "\n";
        return Bytes(text.begin(), text.end());
    };
    const std::string ok = dir.file("ok.ply");
    write_bytes(ok, ply_with(4096));
    EXPECT_EQ(read_as(Format::Ply, ok, "4096 channels"), Outcome::Read);
    std::string what = error_of(Format::Ply, dir, ply_with(4097), "4097 channels");
    EXPECT_TRUE(contains(what, "4097 channels, more than the 4096")) << what;
    what = error_of(Format::Ply, dir, ply_with(7 + 16 * 4096), "too many properties");
    EXPECT_TRUE(contains(what, "more than 65543 vertex properties")) << what;
}

// Found by fuzz_ply: a name with a control character was read as a channel
// name the writers refuse. Both readers reject it now, naming the problem.
TEST(ReaderSweep, ControlCharactersInChannelNames) {
    const Samples& s = samples();
    TempDir dir;
    for (const char* bad : {"a\x01z", "a\x7fz"}) {
        const std::string ply = std::string("ply\nformat ascii 1.0\nelement vertex 1\n"
                                            "property float x\nproperty float y\n"
                                            "property float z\nproperty float ") +
                                bad + "\nend_header\n0 0 0 1\n";
        const std::string what =
            error_of(Format::Ply, dir, Bytes(ply.begin(), ply.end()), "ply name");
        EXPECT_TRUE(contains(what, "control character")) << what;
        const std::string comment =
            std::string("ply\nformat ascii 1.0\ncomment sss_channel "
                        "float ") +
            bad +
            "\nelement vertex 1\nproperty float x\nproperty float "
            "y\nproperty float z\nend_header\n0 0 0\n";
        EXPECT_TRUE(
            contains(error_of(Format::Ply, dir, Bytes(comment.begin(), comment.end()),
                              "ply sss_channel name"),
                     "control character"));
        // .ptc: rename the first channel ("_area", 5 bytes) in its spec line.
        std::string ptc(s.ptc.begin(), s.ptc.end());
        const std::size_t at = ptc.find("float _area\n");
        ASSERT_NE(at, std::string::npos);
        ptc.replace(at + 6, 5, std::string(bad) + "ea");
        EXPECT_TRUE(contains(
            error_of(Format::Ptc, dir, Bytes(ptc.begin(), ptc.end()), "ptc name"),
            "control character"));
    }
}
