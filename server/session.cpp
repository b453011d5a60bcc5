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

Session::Session(Daemon& daemon, std::unique_ptr<Transport> transport)
    : daemon_(daemon),
      transport_(std::move(transport)),
      strand_(transport_->executor()),
      heartbeat_(strand_),
      auth_deadline_(strand_),
      body_memory_(daemon.inflight_bytes()),
      connection_number_(daemon.next_connection_number()) {
    authorized_ = !daemon_.token().has_value();
    peer_ = transport_->peer();
}

std::string Session::log_id(std::uint64_t request_id) const { return fmt::format("{}-{}", connection_number_, request_id); }

void Session::begin_access(const protocol::Message& message) {
    if (message.type == static_cast<std::uint16_t>(MessageType::ping) ||
        message.type == static_cast<std::uint16_t>(MessageType::pong)) {
        return;  // liveness, not requests
    }
    Access access;
    access.type = std::string(protocol::message_type_name(message.type));
    if (message.body.is_object()) {
        for (const char* key : {"scene", "name"}) {
            const auto it = message.body.find(key);
            if (it != message.body.end() && it->is_string()) {
                access.scene = it->get<std::string>().substr(0, 256);
                break;
            }
        }
    }
    access.bytes_in = protocol::kHeaderSize + message.attachment.size() + message.body.dump().size();
    access.received = Clock::now();
    access_.emplace(message.request_id, std::move(access));  // a duplicate id keeps the first
}

void Session::end_access(std::uint64_t request_id, std::string_view status, std::size_t bytes_out) {
    const auto it = access_.find(request_id);
    if (it == access_.end()) return;
    const Access& access = it->second;
    if (log::level() <= log::Level::info) {
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - access.received).count();
        log::write(log::Level::info, "access", "request",
                   {{"request_id", log_id(request_id)}, {"peer", peer_}, {"type", access.type}, {"scene", access.scene},
                    {"status", std::string(status)}, {"ms", ms},
                    {"bytes_in", static_cast<std::int64_t>(access.bytes_in)},
                    {"bytes_out", static_cast<std::int64_t>(bytes_out)}});
    }
    access_.erase(it);
}

void Session::start() {
    arm_heartbeat();
    if (!authorized_) arm_auth_deadline();
    read_header();
}

// A connection that has not authenticated in time is closed, whatever else it sends (pings do not
// keep it alive).
void Session::arm_auth_deadline() {
    auth_deadline_.expires_after(daemon_.config().auth_timeout);
    auth_deadline_.async_wait([self = shared_from_this()](boost::system::error_code error) {
        if (error || self->closed_ || self->authorized_) return;
        log::info("session", "closing a connection that did not authenticate within {} ms",
                  self->daemon_.config().auth_timeout.count());
        self->close();
    });
}

void Session::read_header() {
    if (closed_) return;
    transport_->read(asio::buffer(header_), [self = shared_from_this()](boost::system::error_code error, std::size_t) {
        if (error) {
            self->close();
            return;
        }
        self->last_heard_ = Clock::now();
        try {
            // Before authentication a frame may hold no more than a `hello` needs.
            const auto limits = self->authorized_ ? self->daemon_.limits() : Daemon::unauthenticated_limits();
            self->read_body(protocol::decode_header(self->header_, limits));
        } catch (const protocol::ProtocolError& broken) {
            self->broken_frame(broken);
        }
    });
}

void Session::read_body(const protocol::Header& header) {
    body_.clear();
    read_body_chunk(header);
}

// Reads the body in chunks, each reserved in the daemon's byte budget before it is allocated, so
// memory follows the bytes that really arrive, never a header's announcement alone.
void Session::read_body_chunk(const protocol::Header& header) {
    const std::size_t total = static_cast<std::size_t>(header.json_length) + header.attachment_length;
    const std::size_t have = body_.size();
    if (have == total) {
        body_complete(header);
        return;
    }
    constexpr std::size_t kChunk = 256u << 10;
    const std::size_t chunk = std::min(kChunk, total - have);
    // The budget holds what is allocated, so growth is explicit: double the capacity (amortized
    // copies), never past the frame's size, each step reserved before it is allocated.
    const std::size_t capacity =
        have + chunk <= body_.capacity() ? body_.capacity() : std::min(total, std::max(have + chunk, 2 * body_.capacity()));
    if (!body_memory_.grow(capacity - body_.capacity())) {
        // Refused, but the connection stays usable: the rest of the frame is read and dropped.
        fail(header.request_id, ErrorCode::resource_exhausted,
             fmt::format("the daemon holds {} of its {} bytes for request bodies in flight (--max-inflight-bytes); "
                         "this frame's {} bytes do not fit now",
                         daemon_.inflight_bytes().used(), daemon_.inflight_bytes().limit(), total));
        body_.clear();
        body_.shrink_to_fit();
        body_memory_.release();
        skip_body(total - have);
        return;
    }
    body_.reserve(capacity);
    body_.resize(have + chunk);
    transport_->read(asio::buffer(body_.data() + have, chunk),
                     [self = shared_from_this(), header](boost::system::error_code error, std::size_t) {
                         if (error) {
                             self->close();
                             return;
                         }
                         self->last_heard_ = Clock::now();
                         self->read_body_chunk(header);
                     });
}

// Reads and drops `remaining` bytes through a small scratch buffer, then the next frame.
void Session::skip_body(std::size_t remaining) {
    if (remaining == 0) {
        read_header();
        return;
    }
    const std::size_t chunk = std::min(remaining, skip_scratch_.size());
    transport_->read(asio::buffer(skip_scratch_.data(), chunk),
                     [self = shared_from_this(), remaining, chunk](boost::system::error_code error, std::size_t) {
                         if (error) {
                             self->close();
                             return;
                         }
                         self->skip_body(remaining - chunk);
                     });
}

void Session::body_complete(const protocol::Header& header) {
    protocol::Message message;
    message.type = header.type;
    message.request_id = header.request_id;
    try {
        message.body = protocol::parse_body(std::span(body_).first(header.json_length), header.request_id);
    } catch (const protocol::ProtocolError& broken) {
        broken_frame(broken);
        return;
    }
    // The attachment takes the body's storage (the JSON prefix moved out in place): no second copy.
    body_.erase(body_.begin(), body_.begin() + header.json_length);
    message.attachment = std::move(body_);
    body_ = {};
    dispatch(std::move(message));
    body_memory_.release();  // a request that keeps its attachment took its own reservation
    if (pending_.size() >= daemon_.config().max_in_flight) {
        reading_paused_ = true;  // resumes in finish()
    } else {
        read_header();
    }
}

// The one boundary of the connection's own requests: whatever a handler throws is answered as
// its error, never escapes the strand.
void Session::dispatch(protocol::Message message) {
    const std::uint64_t id = message.request_id;
    begin_access(message);
    const log::RequestScope scope(log_id(id));
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
            case MessageType::stream_update:
            case MessageType::stream_stop: stream_request(message); return;
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
        const bool was_authorized = authorized_;
        authorized_ = protocol::same_token(token, *daemon_.token());
        if (!authorized_) {
            if (was_authorized) arm_auth_deadline();  // revoked: authenticate again in time, or go
            fail(id, ErrorCode::unauthorized, "hello: missing or wrong token", "token");
            return;
        }
        if (!was_authorized && !daemon_.authenticated(this)) {
            fail(id, ErrorCode::busy, fmt::format("{} clients are connected (--max-clients)", daemon_.config().max_clients));
            close_after_write_ = true;
            return;
        }
        auth_deadline_.cancel();
    }
    send({static_cast<std::uint16_t>(MessageType::hello), id, daemon_.hello_body(), {}});
}

void Session::cancel(const protocol::Message& message) {
    const auto target = static_cast<std::uint64_t>(protocol::get_integer(message.body, "id", 0, INT64_MAX));
    const auto it = pending_.find(target);
    if (it != pending_.end()) it->second.cancelled->store(true);
    send(protocol::make_ok(message.request_id, {{"cancelled", it != pending_.end()}}));
}

void Session::stream_request(const protocol::Message& message) {
    const std::uint64_t id = message.request_id;
    StreamHub& hub = daemon_.streams();
    switch (static_cast<MessageType>(message.type)) {
        case MessageType::stream_start: {
            if (streams_.count(id)) {
                fail(id, ErrorCode::bad_request, fmt::format("stream {} is already open on this connection", id));
                return;
            }
            const json reply = hub.open(shared_from_this(), connection_number_, id, message.body);
            streams_.insert(id);
            send(protocol::make_ok(id, reply));
            hub.schedule(connection_number_, id);  // after the ok: no frame precedes it
            return;
        }
        case MessageType::stream_update: {
            const auto stream = static_cast<std::uint64_t>(protocol::get_integer(message.body, "stream", 0, INT64_MAX));
            send(protocol::make_ok(id, hub.update(connection_number_, stream, message.body)));
            return;
        }
        default: {
            const auto stream = static_cast<std::uint64_t>(protocol::get_integer(message.body, "stream", 0, INT64_MAX));
            json reply = hub.stop(connection_number_, stream);
            streams_.erase(stream);  // on this strand: no event of it is written after the ok
            send(protocol::make_ok(id, reply));
            return;
        }
    }
}

void Session::send_stream_event(std::uint64_t stream_id, protocol::Message message, std::function<void()> done,
                                bool ends_stream) {
    auto bytes = protocol::encode(message);
    asio::post(strand_, [self = shared_from_this(), stream_id, bytes = std::move(bytes),
                                        done = std::move(done), ends_stream]() mutable {
        if (self->closed_ || !self->streams_.count(stream_id)) {
            if (done) done();
            return;
        }
        if (ends_stream) self->streams_.erase(stream_id);
        self->enqueue(std::move(bytes), std::move(done));
    });
}

void Session::submit(protocol::Message message) {
    const std::uint64_t id = message.request_id;
    if (pending_.count(id)) {
        fail(id, ErrorCode::bad_request, fmt::format("request id {} is already in flight", id));
        return;
    }
    auto request = std::make_shared<Request>(shared_from_this(), std::move(message));
    request->log_id = log_id(id);
    if (!request->message().attachment.empty()) request->memory = std::move(body_memory_);  // held while it runs
    body_memory_ = ByteBudget::Reservation(daemon_.inflight_bytes());
    pending_[id] = {request->cancelled};
    daemon_.request_started();
    daemon_.handlers().admit(request);
}

void Session::send_error(std::uint64_t request_id, const Failure& failure) {
    fail(request_id, failure.code, failure.message, failure.field);
}

void Session::end_request(std::uint64_t request_id) {
    asio::post(strand_, [self = shared_from_this(), request_id] { self->finish(request_id); });
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
    log::debug("session", "request {} error {}: {}", log_id(request_id), protocol::error_code_name(code), message);
    send(protocol::make_error(request_id, code, message, std::move(field)));
}

void Session::broken_frame(const protocol::ProtocolError& error) {
    log::info("session", "closing a connection after a broken frame: {}", error.what());
    fail(error.request_id.value_or(0), error.code, error.what());
    asio::post(strand_, [self = shared_from_this()] {
        self->close_after_write_ = true;
        if (!self->writing_) self->close();
    });
}

void Session::send(protocol::Message message) {
    auto bytes = protocol::encode(message);
    // Replies that end a request: everything but progress events and the daemon's own pings.
    std::string status;
    switch (static_cast<MessageType>(message.type)) {
        case MessageType::error: status = message.body.value("code", "error"); break;
        case MessageType::progress:
        case MessageType::ping: break;
        default: status = "ok"; break;
    }
    asio::post(strand_, [self = shared_from_this(), bytes = std::move(bytes), status = std::move(status),
                                        id = message.request_id]() mutable {
        if (!status.empty()) self->end_access(id, status, bytes.size());
        self->enqueue(std::move(bytes));
    });
}

void Session::enqueue(std::vector<std::uint8_t> bytes, std::function<void()> written) {
    if (closed_) {
        if (written) written();
        return;
    }
    output_bytes_ += bytes.size();
    output_.push_back({std::move(bytes), std::move(written)});
    if (output_bytes_ > daemon_.config().max_output_bytes) {
        log::warn("session", "dropping a client that does not read: {} bytes queued", output_bytes_);
        close();
        return;
    }
    if (!writing_) write_next();
}

void Session::write_next() {
    if (output_.empty() || closed_) {
        writing_ = false;
        if (close_after_write_) close();
        return;
    }
    writing_ = true;
    transport_->write(asio::buffer(output_.front().bytes), [self = shared_from_this()](boost::system::error_code error,
                                                                                        std::size_t) {
        if (error) {
            self->close();
            return;
        }
        Outgoing sent = std::move(self->output_.front());
        self->output_bytes_ -= sent.bytes.size();
        self->output_.pop_front();
        if (sent.written) sent.written();
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
    asio::dispatch(strand_, [self = shared_from_this()] {
        if (self->closed_) return;
        self->closed_ = true;
        self->heartbeat_.cancel();
        self->auth_deadline_.cancel();
        self->transport_->close();
        for (auto& [id, pending] : self->pending_) pending.cancelled->store(true);
        self->daemon_.streams().drop_connection(self->connection_number_);
        self->streams_.clear();
        // What was queued is never written: streams waiting on it learn so.
        for (auto& outgoing : self->output_) {
            if (outgoing.written) std::exchange(outgoing.written, {})();
        }
        self->daemon_.forget(self.get());
    });
}

}  // namespace bounce::server
