// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Unit tests for the serve module (ptview -serve): sources and their arrays,
// the live diffusion (the library's values bit for bit, the subsample,
// cancellation by a newer request), Save, turntables, brick-map voxels, and
// the HTTP server on a real socket: the page, 404s, refused hosts and
// origins, malformed requests that leave it running.

#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "../../src/sss/serve/serve_internal.h"
#include "sss/brick/brickmap.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/cloud/synthetic.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/serve/serve.h"
#include "sss/util/error.h"
#include "sss/view/point_view.h"
#include "test_util.h"

namespace {

using sss::test::TempDir;

/// The page's words as the tool parses them, in miniature: "-material NAME"
/// and "-unitlength U" (the real parser is ptfilter's, tested by the CLI
/// tests); anything else is refused.
sss::SsDiffusionOptions parse_words(const std::vector<std::string>& words) {
    sss::SsDiffusionOptions o;
    for (std::size_t i = 0; i < words.size(); i += 2) {
        if (i + 1 >= words.size()) throw sss::UsageError("a word without a value");
        if (words[i] == "-material")
            o.material.preset = words[i + 1];
        else if (words[i] == "-unitlength")
            o.material.unitlength = std::stod(words[i + 1]);
        else
            throw sss::UsageError("option " + words[i] + " is not offered");
    }
    return o;
}

std::string command(const std::vector<std::string>& words, const std::string& in,
                    const std::string& out) {
    std::string c = "ptfilter -ssdiffusion";
    for (const std::string& w : words) c += " " + w;
    return c + " " + in + " " + out;
}

/// A baked sphere of n points in dir/name.
std::string write_sphere(const TempDir& dir, const std::string& name, std::size_t n) {
    sss::SyntheticParams p;
    p.count = n;
    p.size = 10.0;
    p.light_dir = {1, 1, 1};
    sss::write_point_cloud(sss::make_synthetic_cloud(p), dir.file(name));
    return dir.file(name);
}

sss::ServeOptions options(std::vector<std::string> inputs,
                          std::size_t live_points = 50000) {
    sss::ServeOptions o;
    o.inputs = std::move(inputs);
    o.live_points = live_points;
    o.parse_diffusion = parse_words;
    o.diffusion_command = command;
    o.ffmpeg = "";
    o.software = "sss ptview test";
    return o;
}

TEST(ServeSourceId, ParsesOnlyItsForms) {
    EXPECT_EQ(sss::ViewSourceId::parse("c0").text(), "c0");
    EXPECT_EQ(sss::ViewSourceId::parse("l12").kind, sss::ViewSourceId::Kind::Live);
    const sss::ViewSourceId b = sss::ViewSourceId::parse("b3.7");
    EXPECT_EQ(b.kind, sss::ViewSourceId::Kind::BrickLevel);
    EXPECT_EQ(b.input, 3u);
    EXPECT_EQ(b.depth, 7);
    for (const char* bad : {"", "c", "x0", "c-1", "c1x", "../c0", "b1", "b1.", "b.1",
                            "b1.99", "c12345678901234567890", "c0 ", "/etc/passwd"})
        EXPECT_THROW(sss::ViewSourceId::parse(bad), sss::NotFoundError) << bad;
}

TEST(ServeNames, PlainFileNamesOnly) {
    EXPECT_TRUE(sss::is_plain_file_name("teapot_ssd.ptc"));
    EXPECT_TRUE(sss::is_plain_file_name("a+b@2.ply"));
    for (const char* bad : {"", ".", "..", ".hidden.ptc", "-x.ptc", "a/b.ptc", "../x.ptc",
                            "a b.ptc", "a\nb.ptc", "a$b.ptc", "a'b.ptc"})
        EXPECT_FALSE(sss::is_plain_file_name(bad)) << bad;
    EXPECT_EQ(sss::default_result_name("scenes/teapot.ptc"), "teapot_ssd.ptc");
    EXPECT_EQ(sss::default_result_name("odd name!.ply"), "odd_name__ssd.ptc");
    EXPECT_EQ(sss::default_result_name(".ptc"), "ptc_ssd.ptc");
}

TEST(ServeJson, EscapesAndNumbers) {
    sss::JsonWriter j;
    j.begin_object();
    j.key("s").string("a\"b\\c\n\x01");
    j.key("n").number(0.1);
    const float f[2] = {0.05f, 1.0f};
    j.key("f").numbers(f, 2);
    j.key("b").boolean(true);
    j.key("e").begin_array().end_array();
    j.end_object();
    EXPECT_EQ(
        j.text(),
        R"({"s":"a\"b\\c\u000a\u0001","n":0.1,"f":[0.0500000007,1],"b":true,"e":[]})");
}

TEST(ServeSession, BadInputsFailAtStartWithTheReadersErrors) {
    TempDir dir;
    EXPECT_THROW(sss::ViewSession(options({dir.file("missing.ptc")})), sss::IoError);
    sss::test::write_text(dir.file("short.ptc"), "pointcloud");
    EXPECT_THROW(sss::ViewSession(options({dir.file("short.ptc")})), sss::FormatError);
    sss::test::write_text(dir.file("bad.bkm"), "not a brick map");
    EXPECT_THROW(sss::ViewSession(options({dir.file("bad.bkm")})), sss::FormatError);
    EXPECT_THROW(sss::ViewSession(options({})), sss::UsageError);
}

TEST(ServeSession, SceneGeometryAndChannels) {
    TempDir dir;
    const std::string path = write_sphere(dir, "s.ptc", 1000);
    sss::ViewSession session(options({path}));
    const std::string json = session.scene_json();
    EXPECT_NE(json.find("\"points\":1000"), std::string::npos) << json;
    EXPECT_NE(json.find("\"live\":true"), std::string::npos);
    EXPECT_NE(json.find("\"name\":\"marble\""), std::string::npos);
    EXPECT_NE(json.find("\"classic\""), std::string::npos);
    const sss::PointCloud cloud = sss::read_point_cloud(path);
    const std::vector<float> g = session.geometry("c0");
    ASSERT_EQ(g.size(), 7u * 1000u);
    EXPECT_EQ(g[3 * 17 + 1], cloud.positions[17].y);
    EXPECT_EQ(g[3000 + 3 * 17 + 2], cloud.normals[17].z);
    EXPECT_EQ(g[6000 + 17], cloud.radii[17]);
    const std::vector<float> radiance = session.channel("c0", 1);
    EXPECT_EQ(radiance, cloud.channels[1].data);
    EXPECT_THROW(session.channel("c0", 2), sss::NotFoundError);
    EXPECT_THROW(session.geometry("c1"), sss::NotFoundError);
    EXPECT_THROW(session.geometry("l0"), sss::NotFoundError); // no live result yet
    EXPECT_THROW(session.geometry("b0.0"), sss::NotFoundError);
}

TEST(ServeSession, LiveDiffusionIsTheLibrarysBitForBit) {
    TempDir dir;
    const std::string path = write_sphere(dir, "s.ptc", 3000);
    sss::ViewSession session(options({path}, 1000));
    const std::vector<std::string> words = {"-material", "skin1", "-unitlength", "0.5"};
    const sss::LiveResult whole = session.diffuse({0, words, false, ""});
    const sss::PointCloud expected =
        sss::ssdiffusion(sss::read_point_cloud(path), parse_words(words));
    EXPECT_EQ(whole.stride, 1u);
    EXPECT_EQ(whole.points, 3000u);
    EXPECT_EQ(whole.values, expected.find_channel("_ssdiffusion")->data);
    EXPECT_EQ(whole.hash, sss::value_hash(whole.values));
    EXPECT_EQ(whole.command, "ptfilter -ssdiffusion -material skin1 -unitlength 0.5 " +
                                 path + " " + dir.file("s_ssd.ptc"));
    // The live source is the whole result.
    EXPECT_EQ(session.channel("l0", 0), whole.values);

    // The preview: every third point, each standing for three.
    const sss::LiveResult preview = session.diffuse({0, words, true, "other.ptc"});
    EXPECT_EQ(preview.stride, 3u);
    EXPECT_EQ(preview.points, 1000u);
    EXPECT_NE(preview.command.find(dir.file("other.ptc")), std::string::npos);
    sss::PointCloud full = sss::read_point_cloud(path), sub = full.points_only();
    sub.resize(0);
    for (const sss::Channel& c : full.channels) sub.add_channel(c.name, c.type);
    sub.resize(1000);
    for (std::size_t j = 0; j < 1000; ++j) {
        sub.positions[j] = full.positions[3 * j];
        sub.normals[j] = full.normals[3 * j];
        sub.radii[j] = full.radii[3 * j] * float(std::sqrt(3.0));
        sub.channels[0].data[j] = full.channels[0].data[3 * j] * 3.0f;
        for (int k = 0; k < 3; ++k)
            sub.channels[1].data[3 * j + k] = full.channels[1].data[9 * j + k];
    }
    EXPECT_EQ(
        preview.values,
        sss::ssdiffusion(sub, parse_words(words)).find_channel("_ssdiffusion")->data);
    // A preview does not replace the whole result.
    EXPECT_EQ(session.channel("l0", 0), whole.values);

    EXPECT_THROW(session.diffuse({0, {"-blocker", "x.ptc"}, false, ""}), sss::UsageError);
    EXPECT_THROW(session.diffuse({0, {"-material", "skin11"}, false, ""}),
                 sss::UsageError);
    EXPECT_THROW(session.diffuse({1, words, false, ""}), sss::NotFoundError);
}

TEST(ServeSession, ANewerRequestCancelsTheRunningOne) {
    TempDir dir;
    const std::string path = write_sphere(dir, "s.ptc", 200000);
    std::mutex mutex;
    std::condition_variable cv;
    bool parsed = false;
    sss::ServeOptions o = options({path});
    o.parse_diffusion = [&](const std::vector<std::string>& words) {
        if (!words.empty() && words[0] == "-material" && words[1] == "marble") {
            const std::lock_guard<std::mutex> lock(mutex);
            parsed = true;
            cv.notify_all();
        }
        return parse_words(words);
    };
    sss::ViewSession session(o);
    std::atomic<int> outcome{0}; // 1 finished, 2 cancelled
    std::thread first([&] {
        try {
            session.diffuse({0, {"-material", "marble"}, false, ""});
            outcome = 1;
        } catch (const sss::Cancelled&) {
            outcome = 2;
        }
    });
    {
        std::unique_lock<std::mutex> lock(mutex);
        cv.wait(lock, [&] { return parsed; });
    }
    const sss::LiveResult second = session.diffuse({0, {"-material", "skin1"}, true, ""});
    first.join();
    EXPECT_EQ(outcome.load(), 2) << "the older request was not cancelled";
    EXPECT_EQ(second.points, 50000u);
}

TEST(ServeSession, SaveWritesWhatPtfilterWrites) {
    TempDir dir;
    const std::string path = write_sphere(dir, "s.ptc", 2000);
    sss::ViewSession session(options({path}));
    const std::vector<std::string> words = {"-material", "ketchup"};
    const sss::LiveResult shown = session.diffuse({0, words, false, ""});
    const auto [written, result] = session.save(0, words, "out.ptc", false);
    EXPECT_EQ(written, dir.file("out.ptc"));
    EXPECT_EQ(result.hash, shown.hash);
    sss::write_point_cloud(
        sss::ssdiffusion(sss::read_point_cloud(path), parse_words(words)),
        dir.file("expected.ptc"));
    EXPECT_EQ(sss::test::read_bytes(written),
              sss::test::read_bytes(dir.file("expected.ptc")));
    // Other words: computed for the save.
    session.save(0, {"-material", "apple"}, "apple.ply", false);
    EXPECT_TRUE(std::filesystem::exists(dir.file("apple.ply")));
    EXPECT_THROW(session.save(0, words, "out.ptc", false), sss::UsageError); // exists
    EXPECT_NO_THROW(session.save(0, words, "out.ptc", true));
    EXPECT_THROW(session.save(0, words, "s.ptc", true), sss::UsageError); // the input
    for (const char* bad :
         {"../out.ptc", "/tmp/out.ptc", "out.txt", ".out.ptc", "o ut.ptc"})
        EXPECT_THROW(session.save(0, words, bad, true), sss::UsageError) << bad;
}

TEST(ServeSession, TurntableFramesArePtviewPictures) {
    TempDir dir;
    const std::string path = write_sphere(dir, "s.ptc", 3000);
    sss::ViewSession session(options({path}));
    sss::TurntableRequest r;
    r.tiles = {{"c0", "_radiance_t"}};
    r.name = "spin";
    r.frames = 3;
    r.width = r.height = 64;
    r.elevation = 10;
    r.video = "mp4"; // no ffmpeg configured: the frames only
    const sss::TurntableResult t = session.turntable(r);
    ASSERT_EQ(t.frames.size(), 3u);
    EXPECT_EQ(t.frames[1], "spin.0002.png");
    EXPECT_EQ(t.video, "");
    EXPECT_FALSE(t.video_note.empty());
    // Frame 2 is ptview -orbit 120 10 with the exposure of frame 1.
    const sss::PointCloud cloud = sss::read_point_cloud(path);
    sss::PointViewOptions view;
    view.channels = {sss::parse_view_channel("_radiance_t")};
    view.exposure = t.exposure;
    const sss::PointViewImage image = sss::render_point_view(
        {{&cloud, path}}, sss::orbit_camera(cloud.bounds(), 120, 10, 1, 30, 64, 64),
        view);
    sss::write_point_view_image(image, dir.file("expected.png"), "sss ptview test");
    EXPECT_EQ(sss::test::read_bytes(t.folder + "/spin.0002.png"),
              sss::test::read_bytes(dir.file("expected.png")));
    EXPECT_THROW(session.turntable(r), sss::UsageError); // the folder exists
    r.overwrite = true;
    EXPECT_NO_THROW(session.turntable(r));
    r.name = "../up";
    EXPECT_THROW(session.turntable(r), sss::UsageError);
    r.name = "x";
    r.tiles = {{"l0", ""}};
    EXPECT_THROW(session.turntable(r), sss::NotFoundError); // no live result yet
}

TEST(ServeSession, BrickMapVoxels) {
    TempDir dir;
    const std::string path = write_sphere(dir, "s.ptc", 3000);
    sss::PointCloud cloud = sss::read_point_cloud(path);
    sss::BrickMapBuildOptions build;
    build.max_depth = 3;
    sss::build_brick_map({cloud}, build, dir.file("s.bkm"));
    sss::ViewSession session(options({dir.file("s.bkm")}));
    const std::string json = session.scene_json();
    EXPECT_NE(json.find("\"kind\":\"brickmap\""), std::string::npos);
    const std::vector<float> g = session.geometry("b0.1");
    ASSERT_GT(g.size(), 0u);
    const std::size_t n = g.size() / 7;
    EXPECT_EQ(g[3 * n], 0.0f); // no normals: drawn as spheres or squares
    EXPECT_GT(g[6 * n], 0.0f); // radius: half the spacing
    EXPECT_EQ(session.channel("b0.1", 1).size(), 3 * n); // _radiance_t
    EXPECT_THROW(session.geometry("b0.9"), sss::NotFoundError);
    EXPECT_THROW(session.geometry("c0"), sss::NotFoundError);
    EXPECT_THROW(session.diffuse({0, {}, false, ""}), sss::NotFoundError);
}

/// One HTTP exchange on a fresh connection: the raw answer. `half_close`:
/// end the request by closing the sending side (for requests that never end
/// otherwise).
std::string http_exchange(int port, const std::string& request, bool half_close = false) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(uint16_t(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
        ::close(fd);
        return "";
    }
    std::size_t sent = 0;
    while (sent < request.size()) {
        const ssize_t n =
            ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
        if (n <= 0) break;
        sent += std::size_t(n);
    }
    if (half_close) ::shutdown(fd, SHUT_WR);
    std::string answer;
    char buf[65536];
    for (ssize_t n; (n = ::recv(fd, buf, sizeof buf, 0)) > 0;)
        answer.append(buf, std::size_t(n));
    ::close(fd);
    return answer;
}

std::string get(int port, const std::string& path, const std::string& host = "") {
    return http_exchange(port,
                         "GET " + path + " HTTP/1.1\r\nHost: " +
                             (host.empty() ? "127.0.0.1:" + std::to_string(port) : host) +
                             "\r\nConnection: close\r\n\r\n");
}

std::string post(int port, const std::string& path, const std::string& body,
                 const std::string& extra = "") {
    return http_exchange(
        port, "POST " + path + " HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(port) +
                  "\r\nConnection: close\r\n" + extra +
                  "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body);
}

int status(const std::string& answer) {
    return answer.size() > 12 ? std::atoi(answer.c_str() + 9) : 0;
}

TEST(ServeServer, AnswersRefusesAndSurvivesMalformedRequests) {
    TempDir dir;
    const std::string path = write_sphere(dir, "s.ptc", 2000);
    sss::ViewSession session(options({path}));
    sss::ViewServer server(session);
    std::thread running([&] { server.run(); });
    const int port = server.port();
    ASSERT_GT(port, 0);
    EXPECT_EQ(server.url(), "http://127.0.0.1:" + std::to_string(port) + "/");

    std::string a = get(port, "/");
    EXPECT_EQ(status(a), 200) << a;
    EXPECT_NE(a.find("viewer.js"), std::string::npos);
    EXPECT_NE(a.find("Content-Security-Policy"), std::string::npos);
    a = get(port, "/viewer.js");
    EXPECT_NE(a.find("text/javascript"), std::string::npos);
    EXPECT_EQ(status(get(port, "/api/scene")), 200);
    a = get(port, "/api/data/c0/geometry");
    EXPECT_EQ(status(a), 200);
    // 4 bytes of length, "{}", padding, then 7 floats per point.
    EXPECT_EQ(a.size() - a.find("\r\n\r\n") - 4, 8u + 7u * 2000u * 4u);
    for (const char* missing :
         {"/nothing", "/api/data/c1/geometry", "/api/data/c0/channel/9",
          "/api/data/q/geometry", "/../../etc/passwd",
          "/api/data/..%2F..%2Fetc%2Fpasswd/geometry", "/index.html/x"}) {
        a = get(port, missing);
        EXPECT_EQ(status(a), 404) << missing << "\n" << a;
    }
    EXPECT_NE(get(port, "/nothing").find("not found"), std::string::npos);
    // Other sites: a rebound name, a POST from another page.
    EXPECT_EQ(status(get(port, "/api/scene", "evil.example:" + std::to_string(port))),
              403);
    EXPECT_EQ(status(get(port, "/api/scene", "127.evil.example")), 403);
    EXPECT_EQ(status(get(port, "/api/scene", "localhost:9999")), 200); // an ssh tunnel
    EXPECT_EQ(status(post(port, "/api/diffuse?cloud=0", "-material\nskin1",
                          "Origin: http://evil.example\r\n")),
              403);
    // The live diffusion: floats, a 400 for words refused, cancelled never.
    a = post(port, "/api/diffuse?cloud=0&preview=0", "-material\nskin1");
    EXPECT_EQ(status(a), 200) << a;
    EXPECT_NE(a.find("ptfilter -ssdiffusion -material skin1"), std::string::npos);
    a = post(port, "/api/diffuse?cloud=0", "-blocker\n/etc/passwd");
    EXPECT_EQ(status(a), 400);
    EXPECT_NE(a.find("not offered"), std::string::npos);
    EXPECT_EQ(status(post(port, "/api/diffuse?cloud=abc", "")), 400);
    EXPECT_EQ(status(post(port, "/api/diffuse?cloud=7", "")), 404);
    EXPECT_EQ(status(post(port, "/api/save?cloud=0&name=..%2Fx.ptc", "-material\nskin1")),
              400);
    EXPECT_EQ(status(post(port, "/api/turntable?frames=0", "c0")), 400);
    EXPECT_EQ(status(post(port, "/api/diffuse", std::string(2 << 20, 'x'))), 413);
    // Garbage: the server answers 400 or closes, and goes on.
    for (const std::string& junk :
         {std::string("\r\n\r\n"), std::string("GET\r\n\r\n"),
          std::string("BREW / HTCPCP/1.0\r\n\r\n"),
          std::string("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: -5\r\n\r\n"),
          std::string("POST /api/diffuse HTTP/1.1\r\nContent-Length: 100\r\n\r\nshort"),
          std::string("GET /") + std::string(20000, 'a') + " HTTP/1.1\r\n\r\n",
          std::string("\x00\xff\x16\x03\x01 binary", 12)})
        http_exchange(port, junk, true);
    EXPECT_EQ(status(get(port, "/api/scene")), 200);
    server.stop();
    running.join();
}

} // namespace
