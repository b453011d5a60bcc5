#include "server/transport.hpp"

#include <fmt/format.h>

namespace bounce::server {
namespace {

namespace asio = boost::asio;

class TcpTransport final : public Transport {
public:
    explicit TcpTransport(asio::ip::tcp::socket socket) : socket_(std::move(socket)) {
        boost::system::error_code error;
        socket_.set_option(asio::ip::tcp::no_delay(true), error);
        const auto remote = socket_.remote_endpoint(error);
        peer_ = error ? "?" : fmt::format("{}:{}", remote.address().to_string(), remote.port());
    }
    asio::any_io_executor executor() override { return socket_.get_executor(); }
    void read(asio::mutable_buffer buffer, Handler handler) override { asio::async_read(socket_, buffer, std::move(handler)); }
    void write(asio::const_buffer buffer, Handler handler) override { asio::async_write(socket_, buffer, std::move(handler)); }
    void close() override {
        boost::system::error_code ignored;
        socket_.shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
        socket_.close(ignored);
    }
    std::string peer() const override { return peer_; }
    const char* kind() const override { return "tcp"; }

private:
    asio::ip::tcp::socket socket_;
    std::string peer_;
};

}  // namespace

std::unique_ptr<Transport> make_tcp_transport(asio::ip::tcp::socket socket) {
    return std::make_unique<TcpTransport>(std::move(socket));
}

}  // namespace bounce::server
