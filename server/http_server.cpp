#include "server/http_server.hpp"

#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "server/daemon.hpp"
#include "server/transport.hpp"

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

namespace bounce::server {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using asio::ip::tcp;

std::pair<std::string, std::uint16_t> split_host_port(const std::string& text) {
    const auto colon = text.rfind(':');
    if (colon == std::string::npos) throw InputError(fmt::format("--http-listen expects HOST:PORT, got '{}'", text));
    int port = -1;
    try {
        port = std::stoi(text.substr(colon + 1));
    } catch (const std::exception&) {
    }
    if (port < 0 || port > 65535) throw InputError(fmt::format("--http-listen: '{}' is not a port", text.substr(colon + 1)));
    return {text.substr(0, colon), static_cast<std::uint16_t>(port)};
}

bool is_loopback(const std::string& host) {
    boost::system::error_code error;
    const auto address = asio::ip::make_address(host, error);
    return host == "localhost" || (!error && address.is_loopback());
}

// The host of a Host header ("name:port", "[v6]:port").
std::string host_of(std::string_view header) {
    if (header.starts_with("[")) {
        const auto end = header.find(']');
        return std::string(header.substr(1, end == std::string_view::npos ? std::string_view::npos : end - 1));
    }
    return std::string(header.substr(0, header.find(':')));
}

// One binary WebSocket message a protocol frame out; frames in are read as the bytes of the
// messages, so a client may split or join them as TCP would.
class WebSocketTransport final : public Transport {
public:
    WebSocketTransport(websocket::stream<beast::tcp_stream> ws, std::string peer) : ws_(std::move(ws)), peer_(std::move(peer)) {
        ws_.binary(true);
    }
    asio::any_io_executor executor() override { return ws_.get_executor(); }
    void read(asio::mutable_buffer buffer, Handler handler) override {
        asio::async_read(ws_, buffer, [this, handler = std::move(handler)](boost::system::error_code error, std::size_t bytes) {
            // The protocol is binary: a text message is a client speaking something else.
            if (!error && ws_.got_text()) error = websocket::error::bad_data_frame;
            handler(error, bytes);
        });
    }
    void write(asio::const_buffer buffer, Handler handler) override { ws_.async_write(buffer, std::move(handler)); }
    void close() override {
        boost::system::error_code ignored;
        auto& socket = beast::get_lowest_layer(ws_).socket();
        socket.shutdown(tcp::socket::shutdown_both, ignored);
        socket.close(ignored);
    }
    std::string peer() const override { return peer_; }
    const char* kind() const override { return "websocket"; }

private:
    websocket::stream<beast::tcp_stream> ws_;
    std::string peer_;
};

}  // namespace

// One HTTP exchange: read a request and answer it within the ops timeout, or upgrade /ws.
struct HttpServer::Exchange : std::enable_shared_from_this<Exchange> {
    Exchange(HttpServer& server, tcp::socket socket) : server(server), stream(std::move(socket)) {
        boost::system::error_code error;
        const auto remote = stream.socket().remote_endpoint(error);
        peer = error ? "?" : fmt::format("{}:{}", remote.address().to_string(), remote.port());
    }
    ~Exchange() {
        if (counted) --server.open_exchanges_;
    }

    void start() {
        stream.expires_after(server.daemon_.config().ops_timeout);
        parser.body_limit(0);
        parser.header_limit(8192);
        http::async_read(stream, buffer, parser, [self = shared_from_this()](boost::system::error_code error, std::size_t) {
            if (!error) self->serve();
        });
    }

    void serve() {
        const auto& request = parser.get();
        const std::string target(request.target());
        const std::string path = target.substr(0, target.find('?'));
        if (server.serve_viewer_ && path == "/ws") {
            if (!websocket::is_upgrade(request)) return answer(426, "text/plain", "/ws speaks WebSocket\n");
            if (!same_origin(request)) return answer(403, "text/plain", "cross-origin WebSocket refused\n");
            return upgrade();
        }
        if (server.serve_viewer_ && (path == "/" || path == "/index.html")) {
            if (!trusted_host(request)) return answer(403, "text/plain", "unknown host name\n");
            return answer(200, "text/html; charset=utf-8", std::string(viewer_page()));
        }
        // Health needs no token: it tells nothing but up or ready, and orchestrators' HTTP probes
        // (Kubernetes httpGet, load balancers) cannot carry a secret.
        if (path == "/healthz") return answer(200, "text/plain", "ok\n");
        if (path == "/readyz") {
            return server.daemon_.ready() ? answer(200, "text/plain", "ready\n") : answer(503, "text/plain", "not ready\n");
        }
        if (path == "/metrics") {
            if (server.needs_token_) {
                const auto header = request[http::field::authorization];
                const std::string given = header.starts_with("Bearer ") ? std::string(header.substr(7)) : std::string();
                if (!protocol::same_token(given, *server.daemon_.token())) return answer(401, "text/plain", "unauthorized\n");
            }
            server.daemon_.metrics().set_queue_depth(server.daemon_.render_service().queue_depth());
            return answer(200, "text/plain; version=0.0.4", server.daemon_.metrics().prometheus_text());
        }
        answer(404, "text/plain", "not found\n");
    }

    // Without a token, a page of any site could reach a loopback daemon through the visitor's
    // browser: by a cross-origin WebSocket, or by a name that resolves to 127.0.0.1 (DNS
    // rebinding). So the page is served under addresses and localhost only, unless clients need
    // the token anyway, and a WebSocket must come from the page's own origin (or from no page).
    bool trusted_host(const http::request<http::empty_body>& request) const {
        if (server.daemon_.token()) return true;
        const auto header = request[http::field::host];
        const std::string host = host_of(std::string_view(header.data(), header.size()));
        boost::system::error_code error;
        asio::ip::make_address(host, error);
        return host == "localhost" || !error;
    }
    bool same_origin(const http::request<http::empty_body>& request) const {
        if (!trusted_host(request)) return false;
        const auto origin = request[http::field::origin];
        if (origin.empty()) return true;  // not a browser page
        const std::string host(request[http::field::host]);
        return origin == "http://" + host || origin == "https://" + host;
    }

    void answer(unsigned status, const char* type, std::string body) {
        response.result(status);
        response.version(parser.get().version());
        response.set(http::field::content_type, type);
        response.set(http::field::cache_control, "no-store");
        if (std::string_view(type).starts_with("text/html")) {
            // The page loads nothing from elsewhere and talks only to its own daemon.
            response.set("Content-Security-Policy",
                         "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
                         "img-src blob:; connect-src 'self' ws: wss:");
        }
        response.body() = std::move(body);
        response.keep_alive(false);
        response.prepare_payload();
        http::async_write(stream, response, [self = shared_from_this()](boost::system::error_code, std::size_t) {
            // The exchange is over: it leaves the cap before the peer can see the connection end,
            // so a client that connects again at once is never refused by its own last exchange.
            if (self->counted) {
                --self->server.open_exchanges_;
                self->counted = false;
            }
            boost::system::error_code ignored;
            self->stream.socket().shutdown(tcp::socket::shutdown_both, ignored);
        });
    }

    void upgrade() {
        auto ws = std::make_shared<websocket::stream<beast::tcp_stream>>(std::move(stream));
        // The connection is a client's now: the protocol's heartbeat and limits govern it, not the
        // ops timeout or the ops connection cap.
        beast::get_lowest_layer(*ws).expires_never();
        ws->set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
        ws->read_message_max(server.daemon_.config().max_message_bytes + protocol::kHeaderSize + (1u << 20));
        --server.open_exchanges_;
        counted = false;
        ws->async_accept(parser.get(), [ws, &daemon = server.daemon_, peer = peer](boost::system::error_code error) {
            if (error) {
                log::info("http", "WebSocket handshake with {} failed: {}", peer, error.message());
                return;
            }
            daemon.admit(std::make_unique<WebSocketTransport>(std::move(*ws), peer));
        });
    }

    HttpServer& server;
    beast::tcp_stream stream;
    beast::flat_buffer buffer;
    http::request_parser<http::empty_body> parser;
    http::response<http::string_body> response;
    std::string peer;
    bool counted = true;
};

HttpServer::HttpServer(Daemon& daemon, const std::string& listen, bool serve_viewer)
    : daemon_(daemon), serve_viewer_(serve_viewer), acceptor_(daemon.io()) {
    const auto [host, bind_port] = split_host_port(listen);
    host_ = host;
    needs_token_ = !is_loopback(host);
    if (needs_token_ && !daemon_.token()) {
        throw InputError(fmt::format("HTTP on {} (not loopback) needs --token-file", host));
    }
    const tcp::endpoint endpoint(asio::ip::make_address(host == "localhost" ? "127.0.0.1" : host), bind_port);
    acceptor_.open(endpoint.protocol());
    acceptor_.set_option(tcp::acceptor::reuse_address(true));
    acceptor_.bind(endpoint);
    acceptor_.listen();
    log::info("daemon", "HTTP on {}:{} (/healthz /readyz /metrics{}){}", host, port(),
              serve_viewer_ ? ", the viewer at / and WebSocket at /ws" : "",
              needs_token_ ? ", bearer token required for /metrics" : "");
}

HttpServer::~HttpServer() = default;

std::uint16_t HttpServer::port() const { return acceptor_.local_endpoint().port(); }

void HttpServer::start() { accept(); }

void HttpServer::close() {
    boost::system::error_code ignored;
    acceptor_.close(ignored);
}

void HttpServer::accept() {
    acceptor_.async_accept(asio::make_strand(daemon_.io()), [this](boost::system::error_code error, tcp::socket socket) {
        if (error) return;
        if (open_exchanges_.fetch_add(1) >= daemon_.config().max_ops_connections) {
            --open_exchanges_;
            boost::system::error_code ignored;
            socket.close(ignored);  // over the cap: refused, not queued
        } else {
            std::make_shared<Exchange>(*this, std::move(socket))->start();
        }
        accept();
    });
}

}  // namespace bounce::server
