// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file serve.h
/// Module serve: `ptview -serve`, an interactive view of point clouds and
/// brick maps in a web browser, with the live diffusion of a baked cloud.
/// May use: view, brick, diffusion, image, cloud and util.
///
/// A small HTTP server (cpp-httplib) on 127.0.0.1 by default. It serves
/// the page (HTML, JavaScript and CSS compiled into the program: nothing is
/// fetched from the network), and the data of the files it was given,
/// addressed by index (never by a path from the request), as arrays of
/// 32-bit floats. A request for anything else is a 404; a malformed one a
/// 400; neither stops the server. Requests whose Host is not this server's
/// (DNS rebinding) and POSTs from another origin are refused (403). See
/// docs/ptview.md, "Interactive view (-serve)".

#include <memory>
#include <string>

#include "sss/serve/view_session.h"

namespace sss {

/// The HTTP server of a ViewSession.
class ViewServer {
public:
    /// Binds to session.options().bind_address and port (0: a free one).
    /// Throws IoError when it cannot (a port in use, an address not here).
    explicit ViewServer(ViewSession& session);
    ~ViewServer();
    ViewServer(const ViewServer&) = delete;
    ViewServer& operator=(const ViewServer&) = delete;

    /// The port bound.
    int port() const;
    /// The page's address: http://ADDRESS:PORT/ (a wildcard address shown as
    /// 127.0.0.1).
    std::string url() const;
    /// Serves until stop(); returns then.
    void run();
    /// Stops run() (from any thread).
    void stop();

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
};

/// The page's files compiled into the program: the body and content type of
/// `path` ("/", "/viewer.js"), or nullptr.
struct ServeAsset {
    const char* path;
    const char* content_type;
    const char* body;
};
const ServeAsset* find_serve_asset(const std::string& path);

} // namespace sss
