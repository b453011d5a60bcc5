#include "server/request.hpp"

#include "renderer/base/log.hpp"

namespace bounce::server {

Request::Request(std::shared_ptr<ReplyChannel> channel, protocol::Message message)
    : channel_(std::move(channel)), message_(std::move(message)) {}

void Request::check_still_wanted() const {
    if (is_cancelled()) throw RequestError(protocol::ErrorCode::cancelled, "cancelled before it ran");
    const auto now = Clock::now();
    if (now > deadline) {
        throw RequestError(protocol::ErrorCode::timeout,
                           fmt::format("waited {:.0f} ms in the queue, past timeout_ms",
                                       std::chrono::duration<double, std::milli>(now - received).count()));
    }
}

void Request::send(protocol::Message message) const { channel_->send(std::move(message)); }

bool Request::end() { return !ended_.exchange(true); }

void Request::answer(protocol::Message reply) {
    if (!end()) return;
    channel_->send(std::move(reply));
    channel_->end_request(id());
}

void Request::fail(std::exception_ptr error) {
    if (!end()) return;
    const Failure failure = describe_failure(error);
    if (failure.code == protocol::ErrorCode::internal) {
        log::error("request", "request {} ({}) failed: {}", id(), type_name(), failure.message);
    }
    channel_->send_error(id(), failure);
    channel_->end_request(id());
}

}  // namespace bounce::server
