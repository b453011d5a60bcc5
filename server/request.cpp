#include "server/request.hpp"

#include "renderer/base/log.hpp"

namespace bounce::server {

Request::Request(std::shared_ptr<ReplyChannel> channel, protocol::Message message)
    : channel_(std::move(channel)), message_(std::move(message)) {}

void Request::check_still_wanted() const {
    if (is_cancelled()) throw RequestError(protocol::ErrorCode::cancelled, "cancelled");
    const auto now = Clock::now();
    if (now > deadline) {
        throw RequestError(protocol::ErrorCode::timeout,
                           fmt::format("{:.0f} ms after it arrived, past its timeout_ms",
                                       std::chrono::duration<double, std::milli>(now - received).count()));
    }
}

void Request::arm_deadline(boost::asio::io_context& io, std::chrono::milliseconds timeout) {
    deadline = received + timeout;
    deadline_timer_ = std::make_shared<boost::asio::steady_timer>(io, deadline);
    // The handler holds the request weakly: a request that ended long before its deadline is gone.
    deadline_timer_->async_wait([weak = std::weak_ptr<std::atomic<bool>>(cancelled)](boost::system::error_code error) {
        if (error) return;
        if (const auto flag = weak.lock()) flag->store(true);
    });
}

void Request::send(protocol::Message message) const { channel_->send(std::move(message)); }

bool Request::end() {
    if (ended_.exchange(true)) return false;
    if (deadline_timer_) {
        // Timers are not thread-safe: cancel it on its own executor.
        boost::asio::post(deadline_timer_->get_executor(), [timer = deadline_timer_] { timer->cancel(); });
    }
    return true;
}

void Request::answer(protocol::Message reply) {
    if (!end()) return;
    channel_->send(std::move(reply));
    channel_->end_request(id());
}

void Request::fail(std::exception_ptr error) {
    if (!end()) return;
    Failure failure = describe_failure(error);
    const auto now = Clock::now();
    if (failure.code == protocol::ErrorCode::cancelled && now > deadline) {
        // The deadline cancelled the work (arm_deadline).
        failure = {protocol::ErrorCode::timeout,
                   fmt::format("stopped {:.0f} ms after it arrived, past its timeout_ms",
                               std::chrono::duration<double, std::milli>(now - received).count()),
                   std::nullopt};
    }
    if (failure.code == protocol::ErrorCode::internal) {
        log::error("request", "request {} ({}) failed: {}", log_id, type_name(), failure.message);
    }
    channel_->send_error(id(), failure);
    channel_->end_request(id());
}

}  // namespace bounce::server
