// One client connection, and only the connection: reads frames on its strand, answers hello, ping
// and cancel itself, hands every other request to the daemon's RequestHandlers, and writes replies
// through one queue (never two writes at once). Reading pauses while the client has
// `max_in_flight` requests pending; a reader that lets its output pile up is dropped.
#pragma once

#include "protocol/protocol.hpp"
#include "server/byte_budget.hpp"
#include "server/request.hpp"
#include "server/streams.hpp"
#include "server/transport.hpp"

#include <boost/asio.hpp>

#include <array>
#include <atomic>
#include <chrono>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <vector>

namespace bounce::server {

class Daemon;

class Session final : public ReplyChannel, public StreamSink, public std::enable_shared_from_this<Session> {
public:
    Session(Daemon& daemon, std::unique_ptr<Transport> transport);
    void start();
    // Thread-safe: queues a message for this client.
    void send(protocol::Message message) override;
    void send_error(std::uint64_t request_id, const Failure& failure) override;
    void end_request(std::uint64_t request_id) override;
    void send_stream_event(std::uint64_t stream_id, protocol::Message message, std::function<void()> done,
                           bool ends_stream) override;
    // Thread-safe: closes the connection (pending replies are dropped).
    void close();

private:
    using Clock = std::chrono::steady_clock;
    struct Pending {
        std::shared_ptr<std::atomic<bool>> cancelled;
    };
    // What the access line of a request says about it, from its arrival to its final reply.
    struct Access {
        std::string type;
        std::string scene;
        std::size_t bytes_in = 0;
        Clock::time_point received;
    };
    // The request id in logs: connection number and the client's request id, unique in a run.
    std::string log_id(std::uint64_t request_id) const;
    void begin_access(const protocol::Message& message);
    // One access line per request, when its final reply (not progress, not ping) is queued.
    void end_access(std::uint64_t request_id, std::string_view status, std::size_t bytes_out);

    void read_header();
    void read_body(const protocol::Header& header);
    void read_body_chunk(const protocol::Header& header);
    void body_complete(const protocol::Header& header);
    void skip_body(std::size_t remaining);
    void dispatch(protocol::Message message);
    void hello(const protocol::Message& message);
    void cancel(const protocol::Message& message);
    // stream.start, stream.update, stream.stop: answered here, the streams run in the daemon's hub.
    void stream_request(const protocol::Message& message);
    void submit(protocol::Message message);
    void finish(std::uint64_t request_id);
    void fail(std::uint64_t request_id, protocol::ErrorCode code, const std::string& message,
              std::optional<std::string> field = {});
    void broken_frame(const protocol::ProtocolError& error);
    // `written` runs once the bytes are written, or dropped with the connection.
    void enqueue(std::vector<std::uint8_t> bytes, std::function<void()> written = {});
    void write_next();
    void arm_heartbeat();
    void arm_auth_deadline();

    Daemon& daemon_;
    std::unique_ptr<Transport> transport_;
    boost::asio::any_io_executor strand_;
    boost::asio::steady_timer heartbeat_;
    boost::asio::steady_timer auth_deadline_;
    std::array<std::uint8_t, protocol::kHeaderSize> header_{};
    std::vector<std::uint8_t> body_;  // grows as its bytes arrive, each chunk reserved first
    ByteBudget::Reservation body_memory_;
    std::array<std::uint8_t, 16384> skip_scratch_{};
    struct Outgoing {
        std::vector<std::uint8_t> bytes;
        std::function<void()> written;
    };
    std::deque<Outgoing> output_;
    std::set<std::uint64_t> streams_;  // open streams: their events are written, others' dropped
    std::size_t output_bytes_ = 0;
    bool writing_ = false;
    bool reading_paused_ = false;
    bool close_after_write_ = false;
    bool closed_ = false;
    bool authorized_ = false;
    std::map<std::uint64_t, Pending> pending_;
    std::map<std::uint64_t, Access> access_;
    const std::uint64_t connection_number_;
    std::string peer_;
    Clock::time_point last_heard_ = Clock::now();
};

}  // namespace bounce::server
