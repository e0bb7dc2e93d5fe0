// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file serve.cpp
/// The HTTP side of `ptview -serve` (cpp-httplib): the page's files, the
/// session's data as float arrays, the live diffusion, Save and turntables;
/// the checks that keep other web pages out.

#include "sss/serve/serve.h"

#include <cstdio>
#include <cstring>
#include <new>

#include <sys/socket.h>

#include <httplib.h>

#include "serve_internal.h"
#include "sss/util/messages.h"
#include "sss/util/parse.h"

namespace sss {

namespace {

/// Connections served at once: a browser keeps up to six open to a server,
/// each holding a thread while it is kept alive.
constexpr std::size_t kThreads = 16;
/// The largest request body (option words, turntable tiles).
constexpr std::size_t kMaxBody = 1 << 20;

void reply_text(httplib::Response& res, int status, const std::string& text) {
    res.status = status;
    res.set_content(escape_control(text) + "\n", "text/plain; charset=utf-8");
}

/// Runs a handler, turning the library's errors into answers: the server
/// goes on whatever a request holds.
template <class F>
void answer(httplib::Response& res, F&& handler) {
    try {
        handler();
    } catch (const NotFoundError& e) {
        reply_text(res, 404, e.what());
    } catch (const Cancelled&) {
        reply_text(res, 409, "superseded by a newer request");
    } catch (const UsageError& e) {
        reply_text(res, 400, e.what());
    } catch (const ValueError& e) {
        reply_text(res, 400, e.what());
    } catch (const std::bad_alloc&) {
        reply_text(res, 500, "out of memory");
    } catch (const std::exception& e) {
        reply_text(res, 500, e.what());
    }
}

std::string parameter(const httplib::Request& req, const std::string& name,
                      const std::string& fallback) {
    return req.has_param(name) ? req.get_param_value(name) : fallback;
}

double number_parameter(const httplib::Request& req, const std::string& name,
                        double fallback) {
    if (!req.has_param(name)) return fallback;
    const std::optional<double> v = parse_finite(req.get_param_value(name));
    if (!v)
        throw UsageError("parameter " + name + ": " +
                         quoted(req.get_param_value(name), 40) + " is not a number");
    return *v;
}

int integer_parameter(const httplib::Request& req, const std::string& name, int lo,
                      int hi, int fallback) {
    const double v = number_parameter(req, name, fallback);
    if (v != double(int64_t(v)) || v < lo || v > hi)
        throw UsageError("parameter " + name + ": " + format_number(v) +
                         " is not an integer in [" + std::to_string(lo) + ", " +
                         std::to_string(hi) + "]");
    return int(v);
}

/// The body's lines (option words, one per line).
std::vector<std::string> body_lines(const std::string& body) {
    std::vector<std::string> lines;
    std::size_t start = 0;
    while (start < body.size()) {
        std::size_t end = body.find('\n', start);
        if (end == std::string::npos) end = body.size();
        std::string line = body.substr(start, end - start);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.find('\0') != std::string::npos)
            throw UsageError("a request line holds a NUL byte");
        lines.push_back(std::move(line));
        start = end + 1;
    }
    return lines;
}

/// A binary answer: a little-endian uint32 length, that much JSON, zero
/// bytes up to a multiple of 4, then the floats.
void reply_floats(httplib::Response& res, const std::string& json,
                  const std::vector<float>& values) {
    std::string body(4, '\0');
    const uint32_t n = uint32_t(json.size());
    std::memcpy(body.data(), &n, 4);
    body += json;
    body.resize((body.size() + 3) / 4 * 4, '\0');
    const std::size_t start = body.size();
    body.resize(start + values.size() * sizeof(float));
    if (!values.empty())
        std::memcpy(body.data() + start, values.data(), values.size() * 4);
    res.status = 200;
    res.set_content(body, "application/octet-stream");
    res.set_header("Cache-Control", "no-store");
}

std::string live_json(const LiveResult& r) {
    JsonWriter j;
    j.begin_object();
    j.key("stride").number(double(r.stride));
    j.key("points").number(double(r.points));
    j.key("seconds").number(r.seconds);
    char hash[16];
    std::snprintf(hash, sizeof hash, "%08x", r.hash);
    j.key("hash").string(hash);
    j.key("command").string(r.command);
    j.key("material").strings(r.material);
    j.key("warnings").strings(r.warnings);
    j.end_object();
    return j.text();
}

/// 127.x.x.x (digits and dots only: not a name such as 127.example.com),
/// ::1 or localhost.
bool is_loopback(const std::string& address) {
    if (address == "::1" || address == "localhost") return true;
    if (address.rfind("127.", 0) != 0) return false;
    return address.find_first_not_of("0123456789.") == std::string::npos;
}

bool is_wildcard(const std::string& address) {
    return address == "0.0.0.0" || address == "::" || address.empty();
}

} // namespace

struct ViewServer::Impl {
    ViewSession& session;
    httplib::Server server;
    std::string address;
    int port = 0;

    explicit Impl(ViewSession& s) : session(s), address(s.options().bind_address) {}

    /// Host names the page may be reached under: this machine's loopback
    /// names (any port: an ssh tunnel forwards another one) or the address
    /// bound, so that a web page whose name is made to resolve to 127.0.0.1
    /// (DNS rebinding) is refused. Any name when bound to other addresses.
    bool host_allowed(const std::string& host) const {
        if (!is_loopback(address)) return true;
        std::string name = host;
        if (!name.empty() && name[0] == '[') {
            const std::size_t close = name.find(']');
            name = close == std::string::npos ? "" : name.substr(1, close - 1);
        } else if (const std::size_t colon = name.rfind(':');
                   colon != std::string::npos) {
            name.resize(colon);
        }
        return is_loopback(name) || name == address;
    }

    void routes();
    void diffuse(const httplib::Request& req, httplib::Response& res);
    void save(const httplib::Request& req, httplib::Response& res);
    void turntable(const httplib::Request& req, httplib::Response& res);
};

void ViewServer::Impl::routes() {
    server.set_pre_routing_handler([this](const httplib::Request& req,
                                          httplib::Response& res) {
        if (!host_allowed(req.get_header_value("Host"))) {
            reply_text(res, 403, "this server answers requests to its own address only");
            return httplib::Server::HandlerResponse::Handled;
        }
        // A page of another site may send POSTs here (a form); browsers name
        // its origin, which must be this server.
        if (req.method != "GET" && req.method != "HEAD" && req.has_header("Origin") &&
            req.get_header_value("Origin") != "http://" + req.get_header_value("Host")) {
            reply_text(res, 403, "requests from other pages are refused");
            return httplib::Server::HandlerResponse::Handled;
        }
        return httplib::Server::HandlerResponse::Unhandled;
    });
    server.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
        if (res.body.empty())
            reply_text(res, res.status,
                       res.status == 404
                           ? "not found: " + truncated(req.path, 200)
                           : "request refused (HTTP " + std::to_string(res.status) + ")");
    });
    server.set_exception_handler(
        [](const httplib::Request&, httplib::Response& res, std::exception_ptr) {
            reply_text(res, 500, "internal error");
        });
    if (session.options().log)
        server.set_logger(
            [this](const httplib::Request& req, const httplib::Response& res) {
                session.options().log(req.method + " " +
                                      truncated(escape_control(req.path), 200) + " " +
                                      std::to_string(res.status));
            });

    const auto asset = [](const std::string& path, httplib::Response& res) {
        const ServeAsset* a = find_serve_asset(path);
        if (!a) {
            reply_text(res, 404, "not found: " + path);
            return;
        }
        res.set_content(a->body, a->content_type);
        res.set_header("Cache-Control", "no-cache");
        // The page runs only its own scripts.
        res.set_header("Content-Security-Policy",
                       "default-src 'self'; img-src 'self' data: blob:; "
                       "style-src 'self'; script-src 'self'; connect-src 'self'");
        res.set_header("X-Content-Type-Options", "nosniff");
    };
    server.Get("/", [asset](const httplib::Request&, httplib::Response& res) {
        asset("/index.html", res);
    });
    server.Get(R"(/(index\.html|viewer\.js|viewer_gl\.js|viewer\.css))",
               [asset](const httplib::Request& req, httplib::Response& res) {
                   asset(req.path, res);
               });
    server.Get("/api/scene", [this](const httplib::Request&, httplib::Response& res) {
        answer(res, [&] {
            res.set_content(session.scene_json(), "application/json");
            res.set_header("Cache-Control", "no-store");
        });
    });
    server.Get(R"(/api/data/([A-Za-z0-9.]{1,24})/geometry)",
               [this](const httplib::Request& req, httplib::Response& res) {
                   answer(res, [&] {
                       reply_floats(res, "{}", session.geometry(req.matches[1]));
                   });
               });
    server.Get(R"(/api/data/([A-Za-z0-9.]{1,24})/channel/([0-9]{1,6}))",
               [this](const httplib::Request& req, httplib::Response& res) {
                   answer(res, [&] {
                       reply_floats(
                           res, "{}",
                           session.channel(req.matches[1], std::stoul(req.matches[2])));
                   });
               });
    server.Post("/api/diffuse",
                [this](const httplib::Request& req, httplib::Response& res) {
                    answer(res, [&] { diffuse(req, res); });
                });
    server.Post("/api/save", [this](const httplib::Request& req, httplib::Response& res) {
        answer(res, [&] { save(req, res); });
    });
    server.Post("/api/turntable",
                [this](const httplib::Request& req, httplib::Response& res) {
                    answer(res, [&] { turntable(req, res); });
                });
}

void ViewServer::Impl::diffuse(const httplib::Request& req, httplib::Response& res) {
    LiveRequest r;
    r.cloud = std::size_t(integer_parameter(req, "cloud", 0, 1 << 20, 0));
    r.preview = integer_parameter(req, "preview", 0, 1, 0) == 1;
    r.output_name = parameter(req, "name", "");
    r.words = body_lines(req.body);
    try {
        const LiveResult result = session.diffuse(r);
        reply_floats(res, live_json(result), result.values);
    } catch (const Cancelled&) {
        // An answer, not an error: the page asked again before this one was done.
        reply_floats(res, "{\"cancelled\":true}", {});
    }
}

void ViewServer::Impl::save(const httplib::Request& req, httplib::Response& res) {
    const std::size_t cloud = std::size_t(integer_parameter(req, "cloud", 0, 1 << 20, 0));
    const bool overwrite = integer_parameter(req, "overwrite", 0, 1, 0) == 1;
    const auto [path, result] =
        session.save(cloud, body_lines(req.body), parameter(req, "name", ""), overwrite);
    JsonWriter j;
    j.begin_object();
    j.key("path").string(path);
    char hash[16];
    std::snprintf(hash, sizeof hash, "%08x", result.hash);
    j.key("hash").string(hash);
    j.key("command").string(result.command);
    j.end_object();
    res.set_content(j.text(), "application/json");
}

void ViewServer::Impl::turntable(const httplib::Request& req, httplib::Response& res) {
    TurntableRequest t;
    t.name = parameter(req, "name", "turntable");
    t.frames = integer_parameter(req, "frames", 1, 3600, t.frames);
    t.start_azimuth = number_parameter(req, "azimuth", t.start_azimuth);
    t.elevation = number_parameter(req, "elevation", t.elevation);
    t.up_axis = integer_parameter(req, "up", 0, 2, t.up_axis);
    t.fov = number_parameter(req, "fov", t.fov);
    t.width = integer_parameter(req, "width", 1, 4096, t.width);
    t.height = integer_parameter(req, "height", 1, 4096, t.height);
    if (parameter(req, "exposure", "auto") != "auto")
        t.exposure = number_parameter(req, "exposure", 0.0);
    t.false_color = integer_parameter(req, "falsecolor", 0, 1, 1) == 1;
    t.radius_scale = float(number_parameter(req, "radiusscale", 1.0));
    t.video = parameter(req, "video", t.video);
    t.overwrite = integer_parameter(req, "overwrite", 0, 1, 0) == 1;
    for (const std::string& line : body_lines(req.body)) {
        if (line.empty()) continue;
        const std::size_t space = line.find(' ');
        t.tiles.push_back({line.substr(0, space),
                           space == std::string::npos ? "" : line.substr(space + 1)});
    }
    const TurntableResult r = session.turntable(t);
    JsonWriter j;
    j.begin_object();
    j.key("folder").string(r.folder);
    j.key("frames").strings(r.frames);
    j.key("video").string(r.video);
    j.key("video_note").string(r.video_note);
    j.key("exposure").number(r.exposure);
    j.end_object();
    res.set_content(j.text(), "application/json");
}

ViewServer::ViewServer(ViewSession& session) : m_impl(std::make_unique<Impl>(session)) {
    Impl& s = *m_impl;
    s.server.new_task_queue = [] { return new httplib::ThreadPool(kThreads); };
    s.server.set_payload_max_length(kMaxBody);
    s.server.set_keep_alive_timeout(2);
    // SO_REUSEADDR only: cpp-httplib also sets SO_REUSEPORT, with which a
    // second server on a port in use would share it instead of failing.
    s.server.set_socket_options([](int sock) {
        const int yes = 1;
        ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    s.routes();
    const ServeOptions& o = session.options();
    const std::string where = o.bind_address + ":" + std::to_string(o.port);
    if (o.port == 0) {
        s.port = s.server.bind_to_any_port(o.bind_address);
        if (s.port <= 0)
            throw IoError(where,
                          std::string("cannot listen there: ") + std::strerror(errno));
    } else {
        if (!s.server.bind_to_port(o.bind_address, o.port))
            throw IoError(where, std::string("cannot listen there: ") +
                                     std::strerror(errno) +
                                     " (another program on that port? -port 0 picks a "
                                     "free one)");
        s.port = o.port;
    }
}

ViewServer::~ViewServer() {
    m_impl->server.stop();
}

int ViewServer::port() const {
    return m_impl->port;
}

std::string ViewServer::url() const {
    std::string host = m_impl->address;
    if (is_wildcard(host)) host = "127.0.0.1";
    if (host.find(':') != std::string::npos) host = "[" + host + "]";
    return "http://" + host + ":" + std::to_string(m_impl->port) + "/";
}

void ViewServer::run() {
    m_impl->server.listen_after_bind();
}

void ViewServer::stop() {
    m_impl->server.stop();
}

} // namespace sss
