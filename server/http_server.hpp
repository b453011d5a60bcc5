// The daemon's HTTP listener (--http-listen, or --metrics-listen for the ops routes alone):
// /healthz, /readyz and /metrics for orchestrators; with the viewer, the page at / and the protocol
// over WebSocket at /ws, each upgraded connection handed to the daemon as a client connection.
#pragma once

#include <utility>  // before Asio: its headers use std::exchange

#include <boost/asio.hpp>

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace bounce::server {

class Daemon;

// The embedded viewer page (server/viewer/index.html).
std::string_view viewer_page();

class HttpServer {
public:
    // Binds `listen` (HOST:PORT); throws InputError for a bad address, or for one off loopback
    // without the daemon's token.
    HttpServer(Daemon& daemon, const std::string& listen, bool serve_viewer);
    ~HttpServer();
    std::uint16_t port() const;
    void start();
    void close();

private:
    struct Exchange;
    void accept();

    Daemon& daemon_;
    bool serve_viewer_;
    bool needs_token_;
    std::string host_;
    boost::asio::ip::tcp::acceptor acceptor_;
    std::atomic<std::size_t> open_exchanges_{0};
};

}  // namespace bounce::server
