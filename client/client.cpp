#include "client/client.hpp"

#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>

namespace bounce::client {
namespace {
namespace asio = boost::asio;
}

ServerError ServerError::from_body(const nlohmann::json& body) {
    const auto code =
        protocol::error_code_from_name(body.value("code", "internal")).value_or(protocol::ErrorCode::internal);
    std::optional<std::string> field;
    if (body.contains("field") && body["field"].is_string()) field = body["field"].get<std::string>();
    return ServerError(code, body.value("message", "error"), field, body.value("retryable", false));
}

Endpoint Endpoint::parse(const std::string& text) {
    const auto colon = text.rfind(':');
    if (colon == std::string::npos || colon == 0) throw std::invalid_argument("expected HOST:PORT, got '" + text + "'");
    Endpoint endpoint;
    endpoint.host = text.substr(0, colon);
    if (endpoint.host.size() >= 2 && endpoint.host.front() == '[' && endpoint.host.back() == ']') {
        endpoint.host = endpoint.host.substr(1, endpoint.host.size() - 2);
    }
    if (endpoint.host.empty()) throw std::invalid_argument("expected HOST:PORT, got '" + text + "'");
    try {
        const int port = std::stoi(text.substr(colon + 1));
        if (port <= 0 || port > 65535) throw std::out_of_range("port");
        endpoint.port = static_cast<std::uint16_t>(port);
    } catch (const std::exception&) {
        throw std::invalid_argument("'" + text.substr(colon + 1) + "' is not a port");
    }
    return endpoint;
}

std::string Endpoint::to_string() const {
    const bool ipv6 = host.find(':') != std::string::npos;
    return (ipv6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

std::vector<Endpoint> resolve_endpoints(const std::string& connect) {
    asio::io_context io;
    asio::ip::tcp::resolver resolver(io);
    std::vector<Endpoint> endpoints;
    std::size_t start = 0;
    while (start <= connect.size()) {
        const auto comma = connect.find(',', start);
        const std::string entry = connect.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        start = comma == std::string::npos ? connect.size() + 1 : comma + 1;
        if (entry.empty()) throw std::invalid_argument("empty endpoint in '" + connect + "'");
        const Endpoint named = Endpoint::parse(entry);
        boost::system::error_code error;
        const auto results = resolver.resolve(named.host, std::to_string(named.port), error);
        if (error) throw ConnectionError("cannot resolve " + named.host + ": " + error.message());
        // A name with IPv4 addresses gives those only: a dual-stack host is one daemon, and
        // "localhost" must not add a [::1] the daemon does not listen on.
        const bool has_ipv4 = std::any_of(results.begin(), results.end(),
                                          [](const auto& result) { return result.endpoint().address().is_v4(); });
        for (const auto& result : results) {
            if (result.endpoint().address().is_v4() != has_ipv4) continue;
            endpoints.push_back({result.endpoint().address().to_string(), result.endpoint().port()});
        }
    }
    std::sort(endpoints.begin(), endpoints.end(),
              [](const Endpoint& a, const Endpoint& b) { return a.to_string() < b.to_string(); });
    endpoints.erase(std::unique(endpoints.begin(), endpoints.end()), endpoints.end());
    return endpoints;
}

Client::Client(const Endpoint& endpoint, std::optional<std::string> token) : socket_(io_) {
    asio::ip::tcp::resolver resolver(io_);
    boost::system::error_code error;
    const auto endpoints = resolver.resolve(endpoint.host, std::to_string(endpoint.port), error);
    if (error) throw ConnectionError("cannot resolve " + endpoint.host + ": " + error.message());
    asio::connect(socket_, endpoints, error);
    if (error) throw ConnectionError("cannot connect to " + endpoint.to_string() + ": " + error.message());
    socket_.set_option(asio::ip::tcp::no_delay(true));
    nlohmann::json body = {{"client", "bounce/0.1"}, {"protocol", protocol::kProtocolVersion}};
    if (token) body["token"] = *token;
    hello_ = request(protocol::MessageType::hello, body).body;
    limits_.max_attachment_bytes = UINT32_MAX;  // trust the daemon's replies up to the format's limit
    limits_.max_json_bytes = 64u << 20;
}

Client::~Client() {
    boost::system::error_code ignored;
    socket_.shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
    socket_.close(ignored);
}

void Client::send_raw(std::span<const std::uint8_t> bytes) {
    boost::system::error_code error;
    asio::write(socket_, asio::buffer(bytes.data(), bytes.size()), error);
    if (error) throw ConnectionError("send failed: " + error.message());
}

protocol::Message Client::read() {
    for (;;) {
        std::array<std::uint8_t, protocol::kHeaderSize> header_bytes{};
        boost::system::error_code error;
        asio::read(socket_, asio::buffer(header_bytes), error);
        if (error) throw ConnectionError("connection closed by the daemon: " + error.message());
        const protocol::Header header = protocol::decode_header(header_bytes, limits_);
        std::vector<std::uint8_t> body(static_cast<std::size_t>(header.json_length) + header.attachment_length);
        asio::read(socket_, asio::buffer(body), error);
        if (error) throw ConnectionError("connection closed mid-frame: " + error.message());
        protocol::Message message;
        message.type = header.type;
        message.request_id = header.request_id;
        message.body = protocol::parse_body(std::span(body).first(header.json_length), header.request_id);
        message.attachment.assign(body.begin() + header.json_length, body.end());
        if (message.type == static_cast<std::uint16_t>(protocol::MessageType::ping)) {
            const auto pong = protocol::encode({static_cast<std::uint16_t>(protocol::MessageType::pong),
                                                message.request_id, nlohmann::json::object(), {}});
            send_raw(pong);
            continue;
        }
        return message;
    }
}

bool Client::wait_readable(std::chrono::milliseconds timeout) {
    // read() takes whole messages straight from the socket, so nothing waits in a buffer of ours:
    // the socket's own readiness is the whole answer.
    pollfd descriptor{socket_.native_handle(), POLLIN, 0};
    const int ready = ::poll(&descriptor, 1, static_cast<int>(timeout.count()));
    if (ready < 0 && errno != EINTR) {
        throw ConnectionError(std::string("waiting for the daemon failed: ") + std::strerror(errno));
    }
    return ready > 0;  // a closed connection is readable too: the next read() says so
}

std::uint64_t Client::send(protocol::MessageType type, nlohmann::json body, std::vector<std::uint8_t> attachment) {
    const std::uint64_t id = next_id_++;
    send_raw(protocol::encode({static_cast<std::uint16_t>(type), id, std::move(body), std::move(attachment)}));
    return id;
}

protocol::Message Client::send_raw_and_read(std::span<const std::uint8_t> bytes) {
    send_raw(bytes);
    return read();
}

protocol::Message Client::request(protocol::MessageType type, nlohmann::json body, std::vector<std::uint8_t> attachment,
                                  const std::function<void(const nlohmann::json&)>& on_progress) {
    const std::uint64_t id = send(type, std::move(body), std::move(attachment));
    for (;;) {
        protocol::Message reply = read();
        if (reply.request_id != id) continue;  // a late reply to an earlier, abandoned request
        if (reply.type == static_cast<std::uint16_t>(protocol::MessageType::progress)) {
            if (on_progress) on_progress(reply.body);
            continue;
        }
        if (reply.type == static_cast<std::uint16_t>(protocol::MessageType::error)) throw ServerError::from_body(reply.body);
        return reply;
    }
}

}  // namespace bounce::client
