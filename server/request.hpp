// A request on its way through the daemon, and the connection that answers it. A session admits a
// request; handlers (request_handlers.hpp) carry it across the render thread, the CPU pool and the
// encode pool; exactly one of answer() and fail() ends it, on whichever thread it is.
#pragma once

#include "protocol/protocol.hpp"
#include "server/byte_budget.hpp"
#include "server/orders.hpp"
#include "server/request_error.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

namespace bounce::server {

// Where a request's replies go: its connection. Every call is thread-safe; Session implements it.
class ReplyChannel {
public:
    virtual ~ReplyChannel() = default;
    virtual void send(protocol::Message message) = 0;
    // An error reply, counted in the metrics.
    virtual void send_error(std::uint64_t request_id, const Failure& failure) = 0;
    // The request is answered: its in-flight slot is free again.
    virtual void end_request(std::uint64_t request_id) = 0;
};

class Request {
public:
    using Clock = std::chrono::steady_clock;

    Request(std::shared_ptr<ReplyChannel> channel, protocol::Message message);
    Request(const Request&) = delete;
    Request& operator=(const Request&) = delete;

    std::uint64_t id() const { return message_.request_id; }
    const protocol::Message& message() const { return message_; }
    std::string_view type_name() const { return protocol::message_type_name(message_.type); }

    // The request's id in logs (log::RequestScope), unique across connections.
    std::string log_id;
    // Set once admitted (parse_order), before the request is queued.
    std::optional<Order> order;
    const Clock::time_point received = Clock::now();
    Clock::time_point deadline = Clock::time_point::max();
    const std::shared_ptr<std::atomic<bool>> cancelled = std::make_shared<std::atomic<bool>>(false);
    // The bytes of its body in the daemon's ByteBudget, held until the request ends.
    ByteBudget::Reservation memory;

    bool is_cancelled() const { return cancelled->load(); }
    // Makes the deadline stop running work: when it passes, the request is cancelled (CPU frames and
    // bakes stop as for `cancel`) and its error is `timeout`. The timer goes when the request ends.
    void arm_deadline(boost::asio::io_context& io, std::chrono::milliseconds timeout);
    // Throws RequestError `cancelled` or `timeout` when the request should not start.
    void check_still_wanted() const;

    // A message that does not end the request (progress events).
    void send(protocol::Message message) const;
    // Ends the request with its reply.
    void answer(protocol::Message reply);
    // Ends the request with the error an exception means; `internal` errors are logged.
    void fail(std::exception_ptr error);

private:
    bool end();  // true the first time
    std::shared_ptr<ReplyChannel> channel_;
    std::shared_ptr<boost::asio::steady_timer> deadline_timer_;
    protocol::Message message_;
    std::atomic<bool> ended_{false};
};

}  // namespace bounce::server
