// One client connection: reads frames on its strand, runs requests on the render thread, and
// writes replies through one queue (never two writes at once). Reading pauses while the client
// has `max_in_flight` requests pending; a reader that lets its output pile up is dropped.
#pragma once

#include "protocol/protocol.hpp"

#include <boost/asio.hpp>

#include <array>
#include <atomic>
#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <vector>

namespace bounce {
class Renderer;
struct RenderResult;
}

namespace bounce::server {

class Daemon;
struct RenderOrder;
struct SceneEntry;
class SceneRegistry;

class Session : public std::enable_shared_from_this<Session> {
public:
    Session(Daemon& daemon, boost::asio::ip::tcp::socket socket);
    void start();
    // Thread-safe: queues a message for this client.
    void send(protocol::Message message);
    // Thread-safe: closes the connection (pending replies are dropped).
    void close();

private:
    using Clock = std::chrono::steady_clock;
    struct Pending {
        std::shared_ptr<std::atomic<bool>> cancelled;
    };

    void read_header();
    void read_body(const protocol::Header& header);
    void dispatch(protocol::Message message);
    void submit(protocol::Message message);
    void execute(const protocol::Message& message, Clock::time_point received, Clock::time_point deadline,
                 const std::shared_ptr<std::atomic<bool>>& cancelled, SceneRegistry& registry, Renderer& renderer);
    nlohmann::json bake(std::uint64_t id, const nlohmann::json& body, SceneRegistry& registry, Renderer& renderer,
                        const std::shared_ptr<std::atomic<bool>>& cancelled);
    void render_on_cpu(const protocol::Message& message, const RenderOrder& order, const SceneEntry& entry,
                       Clock::time_point received, const std::shared_ptr<std::atomic<bool>>& cancelled);
    void deliver_frame(std::uint64_t id, const RenderOrder& order, std::shared_ptr<RenderResult> result,
                       std::uint64_t scene_version, Clock::time_point received, Clock::time_point started,
                       Clock::time_point rendered);
    void finish(std::uint64_t request_id);
    void fail(std::uint64_t request_id, protocol::ErrorCode code, const std::string& message,
              std::optional<std::string> field = {});
    void broken_frame(const protocol::ProtocolError& error);
    void enqueue(std::vector<std::uint8_t> bytes);
    void write_next();
    void arm_heartbeat();

    Daemon& daemon_;
    boost::asio::ip::tcp::socket socket_;
    boost::asio::steady_timer heartbeat_;
    std::array<std::uint8_t, protocol::kHeaderSize> header_{};
    std::vector<std::uint8_t> body_;
    std::deque<std::vector<std::uint8_t>> output_;
    std::size_t output_bytes_ = 0;
    bool writing_ = false;
    bool reading_paused_ = false;
    bool close_after_write_ = false;
    bool closed_ = false;
    bool authorized_ = false;
    std::map<std::uint64_t, Pending> pending_;
    Clock::time_point last_heard_ = Clock::now();
};

}  // namespace bounce::server
