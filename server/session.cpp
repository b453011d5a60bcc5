#include "server/session.hpp"

#include "renderer/base/log.hpp"
#include "renderer/image/codec.hpp"
#include "server/daemon.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/methods/reference/reference_method.hpp"
#include "server/request_error.hpp"

#include <boost/asio/bind_executor.hpp>

namespace bounce::server {
namespace {

namespace asio = boost::asio;
using nlohmann::json;
using protocol::ErrorCode;
using protocol::MessageType;

double ms_between(std::chrono::steady_clock::time_point from, std::chrono::steady_clock::time_point to) {
    return std::chrono::duration<double, std::milli>(to - from).count();
}

// Constant-time comparison, so a wrong token's timing says nothing about the right one.
bool same_token(const std::string& a, const std::string& b) {
    unsigned difference = a.size() == b.size() ? 0u : 1u;
    for (std::size_t i = 0; i < a.size(); ++i) difference |= static_cast<unsigned>(a[i] ^ b[i % std::max<std::size_t>(b.size(), 1)]);
    return difference == 0;
}

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

void Session::dispatch(protocol::Message message) {
    const auto type = protocol::message_type_name(message.type);
    daemon_.metrics().count_request(std::string(type));
    const std::uint64_t id = message.request_id;
    if (!protocol::is_known_message_type(message.type)) {
        fail(id, ErrorCode::unsupported, fmt::format("unknown message type {}", message.type));
        return;
    }
    switch (static_cast<MessageType>(message.type)) {
        case MessageType::hello: {
            const auto version = message.body.value("protocol", static_cast<std::int64_t>(protocol::kProtocolVersion));
            if (version != protocol::kProtocolVersion) {
                fail(id, ErrorCode::version_mismatch,
                     fmt::format("client speaks protocol {}, this daemon speaks {}", version, protocol::kProtocolVersion),
                     "protocol");
                return;
            }
            if (daemon_.token()) {
                const auto token = message.body.contains("token") && message.body["token"].is_string()
                                       ? message.body["token"].get<std::string>()
                                       : std::string();
                if (!same_token(token, *daemon_.token())) {
                    fail(id, ErrorCode::unauthorized, "hello: missing or wrong token", "token");
                    return;
                }
                authorized_ = true;
            }
            send({static_cast<std::uint16_t>(MessageType::hello), id, daemon_.hello_body(), {}});
            return;
        }
        case MessageType::ping:
            send({static_cast<std::uint16_t>(MessageType::pong), id, json::object(), {}});
            return;
        case MessageType::pong:
            return;  // liveness only
        case MessageType::ok:
        case MessageType::error:
        case MessageType::frame:
        case MessageType::progress:
            fail(id, ErrorCode::unsupported, fmt::format("'{}' is a reply, not a request", type));
            return;
        default:
            break;
    }
    if (!authorized_) {
        fail(id, ErrorCode::unauthorized, "send hello with the daemon's token first");
        return;
    }
    if (daemon_.shutting_down()) {
        fail(id, ErrorCode::shutting_down, "the daemon is shutting down");
        return;
    }
    if (static_cast<MessageType>(message.type) == MessageType::cancel) {
        try {
            const auto target = static_cast<std::uint64_t>(protocol::get_integer(message.body, "id", 0, INT64_MAX));
            const auto it = pending_.find(target);
            if (it != pending_.end()) it->second.cancelled->store(true);
            send(protocol::make_ok(id, {{"cancelled", it != pending_.end()}}));
        } catch (const protocol::ProtocolError& error) {
            fail(id, error.code, error.what());
        }
        return;
    }
    if (static_cast<MessageType>(message.type) == MessageType::stream_start ||
        static_cast<MessageType>(message.type) == MessageType::stream_stop) {
        fail(id, ErrorCode::unsupported, fmt::format("'{}' is not available in this daemon yet", type));
        return;
    }
    if (pending_.count(id)) {
        fail(id, ErrorCode::bad_request, fmt::format("request id {} is already in flight", id));
        return;
    }
    submit(std::move(message));
}

void Session::submit(protocol::Message message) {
    const std::uint64_t id = message.request_id;
    const auto received = Clock::now();
    auto deadline = Clock::time_point::max();
    try {
        if (const auto timeout = protocol::get_optional_integer(message.body, "timeout_ms", 1, 24ll * 3600 * 1000)) {
            deadline = received + std::chrono::milliseconds(*timeout);
        }
    } catch (const protocol::ProtocolError& error) {
        fail(id, error.code, error.what(), "timeout_ms");
        return;
    }
    auto cancelled = std::make_shared<std::atomic<bool>>(false);
    pending_[id] = {cancelled};
    daemon_.request_started();
    auto job = [self = shared_from_this(), message = std::move(message), received, deadline, cancelled](
                   Renderer& renderer, SceneRegistry& registry) {
        self->execute(message, received, deadline, cancelled, registry, renderer);
    };
    if (!daemon_.render_service().submit(std::move(job))) {
        fail(id, ErrorCode::busy, fmt::format("the render queue is full ({} jobs)", daemon_.render_service().queue_capacity()));
        finish(id);
        return;
    }
    daemon_.metrics().set_queue_depth(daemon_.render_service().queue_depth());
}

// Runs on the render thread.
void Session::execute(const protocol::Message& message, Clock::time_point received, Clock::time_point deadline,
                      const std::shared_ptr<std::atomic<bool>>& cancelled, SceneRegistry& registry,
                      Renderer& renderer) {
    const std::uint64_t id = message.request_id;
    const auto started = Clock::now();
    daemon_.metrics().set_queue_depth(daemon_.render_service().queue_depth());
    auto done = [&](protocol::Message reply) {
        send(std::move(reply));
        asio::post(socket_.get_executor(), [self = shared_from_this(), id] { self->finish(id); });
    };
    try {
        if (cancelled->load()) throw RequestError(ErrorCode::cancelled, "cancelled before it ran");
        if (started > deadline) {
            throw RequestError(ErrorCode::timeout, fmt::format("waited {:.0f} ms in the queue, past timeout_ms",
                                                               ms_between(received, started)));
        }
        const json& body = message.body;
        json reply;
        switch (static_cast<MessageType>(message.type)) {
            case MessageType::scene_load:
                reply = load_scene(registry, daemon_.scene_root(), body, message.attachment);
                break;
            case MessageType::scene_unload:
                reply = unload_scene(registry, body);
                daemon_.metrics().forget_scene(body.value("name", ""));
                break;
            case MessageType::scene_list: reply = list_scenes(registry); break;
            case MessageType::scene_describe: reply = describe_scene(registry, body); break;
            case MessageType::object_set_transform: reply = set_object_transform(registry, body); break;
            case MessageType::light_set: reply = set_light(registry, body); break;
            case MessageType::light_remove: reply = remove_light(registry, body); break;
            case MessageType::camera_set: reply = set_camera(registry, body); break;
            case MessageType::stats: {
                json errors = json::object();
                for (const auto& [code, count] : daemon_.metrics().errors()) errors[code] = count;
                reply = list_scenes(registry);
                reply["frames"] = daemon_.metrics().frames();
                reply["errors"] = errors;
                reply["queue_depth"] = daemon_.render_service().queue_depth();
                reply["renderer"] = renderer.gpu_info().renderer;
                break;
            }
            case MessageType::render: {
                const RenderOrder order = parse_render(body, daemon_.config().max_pixels);
                SceneEntry& entry = registry.get(order.scene);
                if (order.min_scene_version && entry.version < *order.min_scene_version) {
                    throw RequestError(ErrorCode::bad_request,
                                       fmt::format("scene '{}' is at version {}, below min_scene_version {}", order.scene,
                                                   entry.version, *order.min_scene_version),
                                       "min_scene_version");
                }
                if (methods::MethodRegistry::builtin().find(order.request.method).device == methods::MethodDevice::cpu) {
                    render_on_cpu(message, order, entry, received, cancelled);
                    return;
                }
                RenderRequest request = order.request;
                if (order.camera) {
                    // A camera of the scene for this render only; the scene's own view is untouched.
                    const auto index = entry.scene->find_camera(*order.camera);
                    if (!index) {
                        throw RequestError(ErrorCode::not_found,
                                           fmt::format("scene '{}' has no camera '{}'", order.scene, *order.camera),
                                           "camera");
                    }
                    request.camera = entry.scene->cameras[*index];
                }
                auto result = std::make_shared<RenderResult>(renderer.render(*entry.resources, request));
                daemon_.metrics().set_resident_bytes(order.scene, result->stats.resident_bytes);
                deliver_frame(id, order, result, entry.version, received, started, Clock::now());
                return;
            }
            case MessageType::bake: reply = bake(id, body, registry, renderer, cancelled); break;
            default:
                throw RequestError(ErrorCode::unsupported, "not a request the render thread runs");
        }
        done(protocol::make_ok(id, std::move(reply)));
    } catch (...) {
        const Failure failure = describe_failure(std::current_exception());
        if (failure.code == ErrorCode::internal) {
            log::error("session", "request {} ({}) failed: {}", id, protocol::message_type_name(message.type),
                       failure.message);
        }
        fail(id, failure.code, failure.message, failure.field);
        asio::post(socket_.get_executor(), [self = shared_from_this(), id] { self->finish(id); });
    }
}

// Runs on the render thread: builds a method's precomputed structures for a preset and knobs,
// sending `progress` events (at most five a second, and the last) until the `ok` with its stats.
// A `cancel` of this request stops it between steps.
json Session::bake(std::uint64_t id, const json& body, SceneRegistry& registry, Renderer& renderer,
                   const std::shared_ptr<std::atomic<bool>>& cancelled) {
    const RenderOrder order = parse_render(body, daemon_.config().max_pixels);
    SceneEntry& entry = registry.get(order.scene);
    auto last_sent = Clock::now() - std::chrono::seconds(1);
    const auto started = Clock::now();
    FrameStats stats;
    try {
        stats = renderer.prepare(*entry.resources, order.request, [&](double fraction, const std::string& stage) {
            if (cancelled->load()) return false;
            const auto now = Clock::now();
            if (now - last_sent >= std::chrono::milliseconds(200) || fraction >= 1.0) {
                send(protocol::make_message(MessageType::progress, id, {{"fraction", fraction}, {"stage", stage}}));
                last_sent = now;
            }
            return true;
        });
    } catch (const Cancelled& stop) {
        throw RequestError(ErrorCode::cancelled, stop.what());
    }
    daemon_.metrics().set_resident_bytes(order.scene, stats.resident_bytes);
    json resident = json::array();
    for (const auto& structure : stats.resident)
        resident.push_back({{"structure", structure.name}, {"bytes", structure.bytes}, {"reason", structure.reason}});
    return {{"scene", order.scene},
            {"method", stats.method},
            {"preset", stats.preset},
            {"knobs", stats.knobs},
            {"bake_ms", ms_between(started, Clock::now())},
            {"resident", resident},
            {"resident_bytes", stats.resident_bytes},
            {"method_stats", stats.method_statistics}};
}

// Runs on the render thread: snapshots the scene, so the trace on the CPU pool never races with
// later mutations and never holds the render thread.
void Session::render_on_cpu(const protocol::Message& message, const RenderOrder& order, const SceneEntry& entry,
                            Clock::time_point received, const std::shared_ptr<std::atomic<bool>>& cancelled) {
    const std::uint64_t id = message.request_id;
    const auto& registry = methods::MethodRegistry::builtin();
    const methods::KnobValues knobs = registry.resolve(order.request.method, order.request.preset, order.request.knobs);
    const methods::reference::ReferenceRequest traced = methods::reference::request_from_knobs(knobs);
    auto snapshot = std::make_shared<const scene::Scene>(*entry.scene);
    scene::Camera camera = camera_for(*snapshot, order.request);
    if (order.camera) {
        const auto index = snapshot->find_camera(*order.camera);
        if (!index) {
            throw RequestError(ErrorCode::not_found, fmt::format("scene '{}' has no camera '{}'", order.scene, *order.camera),
                               "camera");
        }
        camera = snapshot->cameras[*index];
    }
    if (!daemon_.try_start_cpu_job()) {
        throw RequestError(ErrorCode::busy, fmt::format("{} CPU renders are already queued", Daemon::kMaxCpuJobs));
    }
    const std::uint64_t version = entry.version;
    asio::post(daemon_.cpu_pool(), [self = shared_from_this(), id, order, snapshot, camera, knobs, traced, version,
                                    received, cancelled] {
        Daemon& daemon = self->daemon_;
        try {
            if (cancelled->load()) throw RequestError(ErrorCode::cancelled, "cancelled before it ran");
            const auto started = Clock::now();
            auto result = std::make_shared<RenderResult>();
            const methods::reference::PathTracer tracer(*snapshot);
            result->frame = tracer.render(camera, order.request.width, order.request.height, traced.spp, traced.settings);
            const auto rendered = Clock::now();
            daemon.finish_cpu_job();
            result->stats.method = order.request.method;
            result->stats.preset = order.request.preset;
            result->stats.knobs = knobs;
            result->stats.render_ms = ms_between(started, rendered);
            if (!order.request.make_display_image) {
                self->deliver_frame(id, order, result, version, received, started, rendered);
                return;
            }
            // The display transform is the GPU pass every frame goes through, on the render thread.
            const bool queued = daemon.render_service().submit(
                [self, id, order, result, version, received, started, rendered](Renderer& renderer, SceneRegistry&) {
                    try {
                        renderer.make_display_image(result->frame, order.request.display);
                        self->deliver_frame(id, order, result, version, received, started, rendered);
                    } catch (const std::exception& error) {
                        self->fail(id, ErrorCode::internal, fmt::format("tone mapping failed: {}", error.what()));
                        asio::post(self->socket_.get_executor(), [self, id] { self->finish(id); });
                    }
                });
            if (!queued) throw RequestError(ErrorCode::busy, "the render queue is full (tone mapping the traced frame)");
        } catch (...) {
            const Failure failure = describe_failure(std::current_exception());
            self->fail(id, failure.code, failure.message, failure.field);
            asio::post(self->socket_.get_executor(), [self, id] { self->finish(id); });
        }
    });
}

// Encodes a finished frame on the encode pool, sends it, and ends the request.
void Session::deliver_frame(std::uint64_t id, const RenderOrder& order, std::shared_ptr<RenderResult> result,
                            std::uint64_t scene_version, Clock::time_point received, Clock::time_point started,
                            Clock::time_point rendered) {
    asio::post(daemon_.encode_pool(), [self = shared_from_this(), id, order, result, scene_version, received, started,
                                       rendered] {
        try {
            const auto format = image::parse_image_format(order.format);
            const auto bytes = image::encode_image(result->frame, format, {order.jpeg_quality, order.exr_half});
            const auto encoded = Clock::now();
            json passes = json::object();
            for (const auto& pass : result->stats.passes) passes[pass.pass] = pass.gpu_ms;
            json resident = json::array();
            for (const auto& s : result->stats.resident) {
                resident.push_back({{"structure", s.name}, {"bytes", s.bytes}, {"reason", s.reason}});
            }
            const double total_ms = ms_between(received, encoded);
            json stats = {{"scene_version", scene_version}, {"width", result->frame.width},
                          {"height", result->frame.height}, {"format", image::image_format_name(format)},
                          {"method", result->stats.method}, {"preset", result->stats.preset},
                          {"knobs", result->stats.knobs},
                          {"timings_ms", {{"queue", ms_between(received, started)},
                                          {"render", ms_between(started, rendered)},
                                          {"gpu", result->stats.gpu_ms},
                                          {"readback", result->stats.readback_ms},
                                          {"encode", ms_between(rendered, encoded)},
                                          {"total", total_ms}, {"passes", passes}}},
                          {"resident", resident}, {"resident_bytes", result->stats.resident_bytes},
                          {"method_stats", result->stats.method_statistics}};
            self->daemon_.metrics().count_frame(ms_between(started, rendered), total_ms);
            self->send({static_cast<std::uint16_t>(MessageType::frame), id, std::move(stats), bytes});
        } catch (const std::exception& error) {
            self->fail(id, ErrorCode::internal, fmt::format("encoding failed: {}", error.what()));
        }
        asio::post(self->socket_.get_executor(), [self, id] { self->finish(id); });
    });
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
