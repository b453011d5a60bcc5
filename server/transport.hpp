// What a client connection runs over: a TCP socket, or a WebSocket (the browser viewer's `/ws`).
// Session speaks the protocol's frames through this and nothing else, so both carry the same
// protocol with the same limits, authentication and flow control.
#pragma once

#include <utility>  // before Asio: its headers use std::exchange

#include <boost/asio.hpp>

#include <cstddef>
#include <functional>
#include <memory>
#include <string>

namespace bounce::server {

class Transport {
public:
    using Handler = std::function<void(boost::system::error_code, std::size_t)>;
    virtual ~Transport() = default;

    // The connection's strand: every handler runs on it.
    virtual boost::asio::any_io_executor executor() = 0;
    // Reads exactly buffer.size() bytes (frames may span WebSocket messages: the stream is bytes).
    virtual void read(boost::asio::mutable_buffer buffer, Handler handler) = 0;
    // Writes one whole protocol frame: on a WebSocket, exactly one binary message.
    virtual void write(boost::asio::const_buffer buffer, Handler handler) = 0;
    // Closes at once; pending operations complete with an error.
    virtual void close() = 0;
    // "ADDRESS:PORT" of the client, for logs.
    virtual std::string peer() const = 0;
    // "tcp" or "websocket".
    virtual const char* kind() const = 0;
};

std::unique_ptr<Transport> make_tcp_transport(boost::asio::ip::tcp::socket socket);

}  // namespace bounce::server
