// The protocol over WebSocket (--http-listen, /ws) and the viewer page: the same frames, the same
// authentication, binary messages only, and no page of another origin may drive the daemon.
#include "daemon_support.hpp"

#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <gtest/gtest.h>

#include <fstream>

namespace bounce::test {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;

const std::string kToken = "correct-horse-battery-staple";

struct WebSocketClient {
    asio::io_context io;
    websocket::stream<asio::ip::tcp::socket> ws{io};

    // Connects and upgrades; `origin`, when given, is sent as a browser page would.
    explicit WebSocketClient(std::uint16_t port, const std::string& origin = "") {
        ws.next_layer().connect({asio::ip::make_address("127.0.0.1"), port});
        ws.set_option(websocket::stream_base::decorator([origin](websocket::request_type& request) {
            if (!origin.empty()) request.set(http::field::origin, origin);
        }));
        ws.handshake("127.0.0.1:" + std::to_string(port), "/ws");
        ws.binary(true);
    }
    void send(MessageType type, std::uint64_t id, const json& body) { ws.write(asio::buffer(frame_bytes(type, id, body))); }
    // One message: exactly one frame.
    protocol::Message receive() {
        beast::flat_buffer buffer;
        ws.read(buffer);
        EXPECT_TRUE(ws.got_binary());
        const auto bytes = static_cast<const std::uint8_t*>(buffer.data().data());
        const std::size_t size = buffer.size();
        EXPECT_GE(size, protocol::kHeaderSize);
        protocol::Limits limits;
        limits.max_attachment_bytes = 64u << 20;
        const auto header = protocol::decode_header(std::span<const std::uint8_t, protocol::kHeaderSize>(bytes, protocol::kHeaderSize), limits);
        EXPECT_EQ(size, protocol::kHeaderSize + header.json_length + header.attachment_length);
        protocol::Message message;
        message.type = header.type;
        message.request_id = header.request_id;
        message.body = protocol::parse_body(std::span(bytes + protocol::kHeaderSize, header.json_length), header.request_id);
        message.attachment.assign(bytes + protocol::kHeaderSize + header.json_length, bytes + size);
        return message;
    }
};

std::string http_request(std::uint16_t port, const std::string& target, const std::string& host = "") {
    asio::io_context io;
    asio::ip::tcp::socket socket(io);
    socket.connect({asio::ip::make_address("127.0.0.1"), port});
    http::request<http::empty_body> request(http::verb::get, target, 11);
    request.set(http::field::host, host.empty() ? "127.0.0.1:" + std::to_string(port) : host);
    http::write(socket, request);
    beast::flat_buffer buffer;
    http::response<http::string_body> response;
    http::read(socket, buffer, response);
    return std::to_string(response.result_int()) + "\n" + response.body();
}

class WebSocketTest : public ::testing::Test {
protected:
    void SetUp() override {
        token_file_ = std::filesystem::temp_directory_path() / ("bounce-ws-token-" + std::to_string(::getpid()));
        std::ofstream(token_file_) << kToken << "\n";
        daemon_ = std::make_unique<DaemonProcess>(
            std::vector<std::string>{"--token-file", token_file_.string(), "--http-listen", "127.0.0.1:0"});
        ASSERT_GT(daemon_->ops_port(), 0);
    }
    void TearDown() override { std::filesystem::remove(token_file_); }
    std::filesystem::path token_file_;
    std::unique_ptr<DaemonProcess> daemon_;
};

TEST_F(WebSocketTest, SpeaksTheProtocolWithItsAuthentication) {
    WebSocketClient client(daemon_->ops_port());
    client.send(MessageType::render, 1, {{"scene", "cornell"}, {"width", 16}, {"height", 16}});
    auto refused = client.receive();
    EXPECT_EQ(refused.type, static_cast<std::uint16_t>(MessageType::error));
    EXPECT_EQ(refused.body["code"], "unauthorized");
    client.send(MessageType::hello, 2, {{"protocol", 1}, {"token", "wrong-token-wrong-token"}});
    EXPECT_EQ(client.receive().body["code"], "unauthorized");
    client.send(MessageType::hello, 3, {{"protocol", 1}, {"token", kToken}});
    const auto hello = client.receive();
    ASSERT_EQ(hello.type, static_cast<std::uint16_t>(MessageType::hello)) << hello.body.dump();

    // The frame over WebSocket is the frame over TCP, byte for byte.
    const json body = {{"scene", "cornell"}, {"width", 32}, {"height", 32}, {"format", "png"}};
    client.send(MessageType::render, 4, body);
    const auto frame = client.receive();
    ASSERT_EQ(frame.type, static_cast<std::uint16_t>(MessageType::frame));
    Client tcp(daemon_->endpoint(), kToken);
    EXPECT_EQ(frame.attachment, tcp.request(MessageType::render, body).attachment);

    // A stream over WebSocket: its ok, then its frames, one message each.
    client.send(MessageType::stream_start, 5, {{"scene", "cornell"}, {"width", 32}, {"height", 32}, {"refine", false}});
    EXPECT_EQ(client.receive().type, static_cast<std::uint16_t>(MessageType::ok));
    const auto streamed = client.receive();
    EXPECT_EQ(streamed.type, static_cast<std::uint16_t>(MessageType::frame));
    EXPECT_EQ(streamed.request_id, 5u);
    EXPECT_EQ(streamed.body["stream"]["stage"], "interactive");
}

TEST_F(WebSocketTest, ATextMessageClosesTheConnection) {
    WebSocketClient client(daemon_->ops_port());
    client.ws.text(true);
    client.ws.write(asio::buffer(std::string("{\"hello\": 1}")));
    beast::flat_buffer buffer;
    boost::system::error_code error;
    client.ws.read(buffer, error);
    EXPECT_TRUE(error) << "the daemon answered a text message";
    Client tcp(daemon_->endpoint(), kToken);  // and serves on
    EXPECT_EQ(render(tcp, {{"scene", "cornell"}, {"width", 8}, {"height", 8}}).width, 8);
}

TEST_F(WebSocketTest, PagesOfOtherOriginsCannotConnect) {
    const std::uint16_t port = daemon_->ops_port();
    EXPECT_THROW(WebSocketClient client(port, "http://evil.example"), boost::system::system_error);
    EXPECT_NO_THROW(WebSocketClient client(port, "http://127.0.0.1:" + std::to_string(port)));
    EXPECT_NO_THROW(WebSocketClient client(port));  // no Origin: not a browser page
}

TEST_F(WebSocketTest, ServesTheViewerPage) {
    const std::string page = http_request(daemon_->ops_port(), "/?scene=cornell");
    EXPECT_EQ(page.rfind("200\n", 0), 0u);
    EXPECT_NE(page.find("<img id=\"view\""), std::string::npos);
    EXPECT_EQ(http_request(daemon_->ops_port(), "/ws").rfind("426\n", 0), 0u);
    EXPECT_EQ(http_request(daemon_->ops_port(), "/healthz"), "200\nok\n");
}

// Without a token, a name that resolves to loopback (DNS rebinding) gets no page and no socket.
TEST(WebSocketWithoutToken, RefusesHostNamesOtherThanLocalhost) {
    DaemonProcess daemon({"--http-listen", "127.0.0.1:0"});
    const std::uint16_t port = daemon.ops_port();
    EXPECT_EQ(http_request(port, "/", "attacker.example:" + std::to_string(port)).rfind("403\n", 0), 0u);
    EXPECT_EQ(http_request(port, "/", "localhost:" + std::to_string(port)).rfind("200\n", 0), 0u);
    EXPECT_EQ(http_request(port, "/").rfind("200\n", 0), 0u);
}

}  // namespace
}  // namespace bounce::test
