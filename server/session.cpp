#include "server/session.hpp"

#include "renderer/base/log.hpp"
#include "server/daemon.hpp"
#include "server/request_error.hpp"
#include "server/request_handlers.hpp"

#include <boost/asio/bind_executor.hpp>

namespace bounce::server {
namespace {

namespace asio = boost::asio;
using nlohmann::json;
using protocol::ErrorCode;
using protocol::MessageType;

}  // namespace

Session::Session(Daemon& daemon, asio::ip::tcp::socket socket)
    : daemon_(daemon), socket_(std::move(socket)), heartbeat_(socket_.get_executor()) {
    authorized_ = !daemon_.token().has_value();
}

void Session::start() {
    boost::system::error_code ignored;
    socket_.set_option(asio::ip::tcp::no_delay(true), ignored);
    arm_heartbeat();
    read_header();
}

void Session::read_header() {
    if (closed_) return;
    asio::async_read(socket_, asio::buffer(header_), [self = shared_from_this()](boost::system::error_code error, std::size_t) {
        if (error) {
            self->close();
            return;
        }
        self->last_heard_ = Clock::now();
        try {
            self->read_body(protocol::decode_header(self->header_, self->daemon_.limits()));
        } catch (const protocol::ProtocolError& broken) {
            self->broken_frame(broken);
        }
    });
}

void Session::read_body(const protocol::Header& header) {
    body_.resize(static_cast<std::size_t>(header.json_length) + header.attachment_length);
    asio::async_read(socket_, asio::buffer(body_), [self = shared_from_this(), header](boost::system::error_code error,
                                                                                       std::size_t) {
        if (error) {
            self->close();
            return;
        }
        self->last_heard_ = Clock::now();
        protocol::Message message;
        message.type = header.type;
        message.request_id = header.request_id;
        try {
            message.body = protocol::parse_body(std::span(self->body_).first(header.json_length), header.request_id);
        } catch (const protocol::ProtocolError& broken) {
            self->broken_frame(broken);
            return;
        }
        message.attachment.assign(self->body_.begin() + header.json_length, self->body_.end());
        self->body_.clear();
        self->body_.shrink_to_fit();
        self->dispatch(std::move(message));
        if (self->pending_.size() >= self->daemon_.config().max_in_flight) {
            self->reading_paused_ = true;  // resumes in finish()
        } else {
            self->read_header();
        }
    });
}

// The one boundary of the connection's own requests: whatever a handler throws is answered as
// its error, never escapes the strand.
void Session::dispatch(protocol::Message message) {
    const std::uint64_t id = message.request_id;
    try {
        daemon_.metrics().count_request(std::string(protocol::message_type_name(message.type)));
        if (!protocol::is_known_message_type(message.type)) {
            fail(id, ErrorCode::unsupported, fmt::format("unknown message type {}", message.type));
            return;
        }
        switch (static_cast<MessageType>(message.type)) {
            case MessageType::hello: hello(message); return;
            case MessageType::ping: send({static_cast<std::uint16_t>(MessageType::pong), id, json::object(), {}}); return;
            case MessageType::pong: return;  // liveness only
            case MessageType::ok:
            case MessageType::error:
            case MessageType::frame:
            case MessageType::progress:
                fail(id, ErrorCode::unsupported,
                     fmt::format("'{}' is a reply, not a request", protocol::message_type_name(message.type)));
                return;
            default: break;
        }
        if (!authorized_) {
            fail(id, ErrorCode::unauthorized, "send hello with the daemon's token first");
            return;
        }
        if (daemon_.shutting_down()) {
            fail(id, ErrorCode::shutting_down, "the daemon is shutting down");
            return;
        }
        switch (static_cast<MessageType>(message.type)) {
            case MessageType::cancel: cancel(message); return;
            case MessageType::stream_start:
            case MessageType::stream_stop:
                fail(id, ErrorCode::unsupported,
                     fmt::format("'{}' is not available in this daemon yet", protocol::message_type_name(message.type)));
                return;
            default: submit(std::move(message)); return;
        }
    } catch (...) {
        const Failure failure = describe_failure(std::current_exception());
        if (failure.code == ErrorCode::internal) log::error("session", "request {} failed: {}", id, failure.message);
        fail(id, failure.code, failure.message, failure.field);
    }
}

void Session::hello(const protocol::Message& message) {
    const std::uint64_t id = message.request_id;
    const auto version = protocol::get_optional_integer(message.body, "protocol", 0, INT64_MAX)
                             .value_or(static_cast<std::int64_t>(protocol::kProtocolVersion));
    if (version != protocol::kProtocolVersion) {
        fail(id, ErrorCode::version_mismatch,
             fmt::format("client speaks protocol {}, this daemon speaks {}", version, protocol::kProtocolVersion),
             "protocol");
        return;
    }
    if (daemon_.token()) {
        const auto token = protocol::get_optional_string(message.body, "token").value_or("");
        authorized_ = protocol::same_token(token, *daemon_.token());
        if (!authorized_) {
            fail(id, ErrorCode::unauthorized, "hello: missing or wrong token", "token");
            return;
        }
    }
    send({static_cast<std::uint16_t>(MessageType::hello), id, daemon_.hello_body(), {}});
}

void Session::cancel(const protocol::Message& message) {
    const auto target = static_cast<std::uint64_t>(protocol::get_integer(message.body, "id", 0, INT64_MAX));
    const auto it = pending_.find(target);
    if (it != pending_.end()) it->second.cancelled->store(true);
    send(protocol::make_ok(message.request_id, {{"cancelled", it != pending_.end()}}));
}

void Session::submit(protocol::Message message) {
    const std::uint64_t id = message.request_id;
    if (pending_.count(id)) {
        fail(id, ErrorCode::bad_request, fmt::format("request id {} is already in flight", id));
        return;
    }
    auto request = std::make_shared<Request>(shared_from_this(), std::move(message));
    pending_[id] = {request->cancelled};
    daemon_.request_started();
    daemon_.handlers().admit(request);
}

void Session::send_error(std::uint64_t request_id, const Failure& failure) {
    fail(request_id, failure.code, failure.message, failure.field);
}

void Session::end_request(std::uint64_t request_id) {
    asio::post(socket_.get_executor(), [self = shared_from_this(), request_id] { self->finish(request_id); });
}

void Session::finish(std::uint64_t request_id) {
    if (pending_.erase(request_id) == 0) return;
    daemon_.request_finished();
    if (reading_paused_ && pending_.size() < daemon_.config().max_in_flight) {
        reading_paused_ = false;
        read_header();
    }
}

void Session::fail(std::uint64_t request_id, ErrorCode code, const std::string& message,
                   std::optional<std::string> field) {
    daemon_.metrics().count_error(std::string(protocol::error_code_name(code)));
    log::debug("session", "request {} error {}: {}", request_id, protocol::error_code_name(code), message);
    send(protocol::make_error(request_id, code, message, std::move(field)));
}

void Session::broken_frame(const protocol::ProtocolError& error) {
    log::info("session", "closing a connection after a broken frame: {}", error.what());
    fail(error.request_id.value_or(0), error.code, error.what());
    asio::post(socket_.get_executor(), [self = shared_from_this()] {
        self->close_after_write_ = true;
        if (!self->writing_) self->close();
    });
}

void Session::send(protocol::Message message) {
    auto bytes = protocol::encode(message);
    asio::post(socket_.get_executor(), [self = shared_from_this(), bytes = std::move(bytes)]() mutable {
        self->enqueue(std::move(bytes));
    });
}

void Session::enqueue(std::vector<std::uint8_t> bytes) {
    if (closed_) return;
    output_bytes_ += bytes.size();
    if (output_bytes_ > daemon_.config().max_output_bytes) {
        log::warn("session", "dropping a client that does not read: {} bytes queued", output_bytes_);
        close();
        return;
    }
    output_.push_back(std::move(bytes));
    if (!writing_) write_next();
}

void Session::write_next() {
    if (output_.empty() || closed_) {
        writing_ = false;
        if (close_after_write_) close();
        return;
    }
    writing_ = true;
    asio::async_write(socket_, asio::buffer(output_.front()), [self = shared_from_this()](boost::system::error_code error,
                                                                                          std::size_t) {
        if (error) {
            self->close();
            return;
        }
        self->output_bytes_ -= self->output_.front().size();
        self->output_.pop_front();
        self->write_next();
    });
}

void Session::arm_heartbeat() {
    const auto interval = daemon_.config().heartbeat;
    heartbeat_.expires_after(interval);
    heartbeat_.async_wait([self = shared_from_this(), interval](boost::system::error_code error) {
        if (error || self->closed_) return;
        const auto silent = Clock::now() - self->last_heard_;
        if (silent > 3 * interval && self->pending_.empty()) {
            log::info("session", "closing a connection silent for {} ms",
                      std::chrono::duration_cast<std::chrono::milliseconds>(silent).count());
            self->close();
            return;
        }
        if (silent > interval) self->send({static_cast<std::uint16_t>(MessageType::ping), 0, json::object(), {}});
        self->arm_heartbeat();
    });
}

void Session::close() {
    asio::dispatch(socket_.get_executor(), [self = shared_from_this()] {
        if (self->closed_) return;
        self->closed_ = true;
        boost::system::error_code ignored;
        self->heartbeat_.cancel();
        self->socket_.shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
        self->socket_.close(ignored);
        for (auto& [id, pending] : self->pending_) pending.cancelled->store(true);
        self->daemon_.forget(self.get());
    });
}

}  // namespace bounce::server
