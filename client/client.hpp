// The Bounce client library: one blocking connection to bounced. Every call sends one request and
// waits for its reply; pings from the daemon are answered while waiting. A reply `error` throws
// ServerError carrying the daemon's code, message and field.
#pragma once

#include "protocol/protocol.hpp"

#include <boost/asio.hpp>

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace bounce::client {

class ServerError : public std::runtime_error {
public:
    ServerError(protocol::ErrorCode code, const std::string& message, std::optional<std::string> field, bool retryable)
        : std::runtime_error(message), code_(code), field_(std::move(field)), retryable_(retryable) {}
    // The error an `error` message's body stands for; a code this client does not know reads as
    // `internal`.
    static ServerError from_body(const nlohmann::json& body);
    protocol::ErrorCode code() const { return code_; }
    const std::optional<std::string>& field() const { return field_; }
    bool retryable() const { return retryable_; }

private:
    protocol::ErrorCode code_;
    std::optional<std::string> field_;
    bool retryable_;
};

// The daemon could not be reached, or the connection broke: nothing was answered, and another
// daemon (or a retry later) may serve the request.
class ConnectionError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

struct Endpoint {
    std::string host = "127.0.0.1";
    std::uint16_t port = 7878;
    // "HOST:PORT" or "[IPV6]:PORT"; throws std::invalid_argument naming the problem.
    static Endpoint parse(const std::string& text);
    // "HOST:PORT", IPv6 addresses in brackets.
    std::string to_string() const;
    bool operator==(const Endpoint&) const = default;
};

// Every daemon a connect string names: comma-separated HOST:PORT entries, each resolved to all of
// its addresses (a Kubernetes headless Service's name gives one per pod; IPv4 ones only where a
// name has both families). Each endpoint's host is a numeric address, so that every client keys a
// daemon the same way; duplicates removed, sorted.
// Throws ConnectionError when a name does not resolve, std::invalid_argument when malformed.
std::vector<Endpoint> resolve_endpoints(const std::string& connect);

class Client {
public:
    // Connects and says hello (with the token when given). Throws on failure.
    Client(const Endpoint& endpoint, std::optional<std::string> token = {});
    ~Client();

    const nlohmann::json& hello() const { return hello_; }

    // Sends a request and returns its reply (`ok`, `frame`, `hello` or `pong`); throws ServerError
    // for an `error` reply and ConnectionError when the connection fails. `progress` events of
    // the request (a bake's) go to `on_progress` when given.
    protocol::Message request(protocol::MessageType type, nlohmann::json body = nlohmann::json::object(),
                              std::vector<std::uint8_t> attachment = {},
                              const std::function<void(const nlohmann::json&)>& on_progress = {});
    // Sends a request without waiting for its reply and returns the id it carries: the reply, and
    // the events of a stream it starts, come with that id, to be read with read().
    std::uint64_t send(protocol::MessageType type, nlohmann::json body = nlohmann::json::object(),
                       std::vector<std::uint8_t> attachment = {});
    // Sends raw bytes (tests use this to send broken frames) and reads one reply.
    protocol::Message send_raw_and_read(std::span<const std::uint8_t> bytes);
    void send_raw(std::span<const std::uint8_t> bytes);
    // Reads the next message, answering pings; throws when the connection closes.
    protocol::Message read();
    // Waits up to `timeout` for the daemon's next bytes; false when none came. A reader of stream
    // events uses it to look up from the connection now and then, since read() blocks.
    bool wait_readable(std::chrono::milliseconds timeout);
    bool connected() const { return socket_.is_open(); }

private:
    boost::asio::io_context io_;
    boost::asio::ip::tcp::socket socket_;
    std::uint64_t next_id_ = 1;
    nlohmann::json hello_;
    protocol::Limits limits_;
};


}  // namespace bounce::client
