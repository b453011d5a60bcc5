#include "server/streams.hpp"

#include "renderer/base/log.hpp"
#include "server/daemon.hpp"
#include "server/request_error.hpp"

#include <boost/asio/steady_timer.hpp>

#include <algorithm>
#include <atomic>
#include <optional>

namespace bounce::server {

using nlohmann::json;
using protocol::ErrorCode;
using protocol::MessageType;

struct StreamHub::Stream {
    std::uint64_t connection = 0;
    std::uint64_t id = 0;
    std::weak_ptr<StreamSink> sink;
    json fields;  // as last set: updates are merged into these
    StreamOrder order;
    std::uint64_t view_version = 0;

    bool scheduled = false;  // its `ok` is queued: frames may follow
    bool stopped = false;
    bool owes_tick = false;  // a tick on the render queue is meant for it
    bool in_flight = false;  // from the tick that starts a frame until its bytes are written
    bool waits_for_cpu = false;  // its next rung renders on the CPU, which another stream's rung holds
    int in_flight_rung = -1;
    std::shared_ptr<std::atomic<bool>> in_flight_cancel;
    std::unique_ptr<boost::asio::steady_timer> retry_timer;

    // The state and rung of the last frame started: the ladder climbs from there while the state
    // stays, and restarts at rung 0 when it changes.
    std::optional<std::uint64_t> shown_scene_version;
    std::uint64_t shown_view_version = 0;
    int shown_rung = -1;
    std::uint64_t unshown_changes = 1;  // states since the last rung 0 started (opening is one)

    std::uint64_t frames = 0, dropped_stale = 0;
};

// The reply channel of one stream frame: the frame goes out as the stream's event, marked with
// its rung, and the stream learns when it has been written; a failure goes to the hub.
class StreamHub::FrameChannel final : public ReplyChannel {
public:
    FrameChannel(StreamHub& hub, StreamPtr stream, json marks) : hub_(hub), stream_(std::move(stream)), marks_(std::move(marks)) {}

    void send(protocol::Message message) override {
        const auto sink = stream_->sink.lock();
        const bool is_frame = message.type == static_cast<std::uint16_t>(MessageType::frame);
        if (!sink) {
            if (is_frame) hub_.frame_done(stream_);
            return;
        }
        if (!is_frame) {  // progress of a bake the frame waits for
            sink->send_stream_event(stream_->id, std::move(message), {}, false);
            return;
        }
        {
            std::lock_guard lock(hub_.mutex_);
            hub_.release_cpu(stream_);  // rendered: the next CPU rung need not wait for this one's writing
            ++stream_->frames;
            ++hub_.frames_;
            marks_["frames"] = stream_->frames;
            marks_["dropped_stale"] = stream_->dropped_stale;
        }
        hub_.daemon_.metrics().count_stream_frame();
        message.body["stream"] = marks_;
        sink->send_stream_event(stream_->id, std::move(message), [&hub = hub_, stream = stream_] { hub.frame_done(stream); },
                                false);
    }
    void send_error(std::uint64_t, const Failure& failure) override { hub_.frame_failed(stream_, failure); }
    void end_request(std::uint64_t) override {}

private:
    StreamHub& hub_;
    StreamPtr stream_;
    json marks_;
};

StreamHub::StreamPtr StreamHub::find(std::uint64_t connection, std::uint64_t id) const {
    for (const auto& stream : streams_) {
        if (stream->connection == connection && stream->id == id) return stream;
    }
    throw RequestError(ErrorCode::not_found, fmt::format("this connection has no stream {}", id), "stream");
}

json StreamHub::open(std::shared_ptr<StreamSink> sink, std::uint64_t connection, std::uint64_t id, const json& fields) {
    auto stream = std::make_shared<Stream>();
    stream->connection = connection;
    stream->id = id;
    stream->sink = std::move(sink);
    stream->fields = fields;
    stream->fields.erase("stream");
    stream->order = parse_stream(stream->fields, daemon_.config().max_pixels);

    std::lock_guard lock(mutex_);
    if (stopped_) throw RequestError(ErrorCode::shutting_down, "the daemon is shutting down");
    const auto mine = std::count_if(streams_.begin(), streams_.end(), [&](const StreamPtr& s) { return s->connection == connection; });
    if (static_cast<std::size_t>(mine) >= kMaxStreamsPerConnection) {
        throw RequestError(ErrorCode::resource_exhausted,
                           fmt::format("this connection has {} streams, the most it may have", kMaxStreamsPerConnection));
    }
    if (std::any_of(streams_.begin(), streams_.end(), [&](const StreamPtr& s) { return s->connection == connection && s->id == id; })) {
        throw RequestError(ErrorCode::bad_request, fmt::format("stream {} is already open on this connection", id));
    }
    streams_.push_back(stream);
    daemon_.metrics().set_streams_active(streams_.size());
    return {{"stream", id}, {"view_version", 0}, {"rungs", stream->order.ladder.size()}};
}

void StreamHub::schedule(std::uint64_t connection, std::uint64_t id) {
    std::lock_guard lock(mutex_);
    for (const auto& stream : streams_) {
        if (stream->connection == connection && stream->id == id) {
            stream->scheduled = true;
            wake(stream);
        }
    }
}

json StreamHub::update(std::uint64_t connection, std::uint64_t id, const json& patch) {
    json fields;
    {
        std::lock_guard lock(mutex_);
        fields = find(connection, id)->fields;
    }
    json changes = patch;
    changes.erase("stream");
    fields.merge_patch(changes);
    StreamOrder order = parse_stream(fields, daemon_.config().max_pixels);  // throws: nothing changed

    std::lock_guard lock(mutex_);
    const StreamPtr stream = find(connection, id);  // it may have ended meanwhile
    stream->fields = std::move(fields);
    stream->order = std::move(order);
    ++stream->view_version;
    changed(*stream);
    wake(stream);
    return {{"stream", id}, {"view_version", stream->view_version}, {"rungs", stream->order.ladder.size()}};
}

json StreamHub::stop(std::uint64_t connection, std::uint64_t id) {
    std::lock_guard lock(mutex_);
    const StreamPtr stream = find(connection, id);
    remove(stream);
    return {{"stream", id}, {"frames", stream->frames}, {"dropped_stale", stream->dropped_stale}};
}

void StreamHub::drop_connection(std::uint64_t connection) {
    std::lock_guard lock(mutex_);
    std::vector<StreamPtr> theirs;
    for (const auto& stream : streams_) {
        if (stream->connection == connection) theirs.push_back(stream);
    }
    for (const auto& stream : theirs) remove(stream);
}

void StreamHub::stop_all() {
    std::lock_guard lock(mutex_);
    stopped_ = true;
    while (!streams_.empty()) remove(streams_.back());
}

void StreamHub::remove(const StreamPtr& stream) {
    stream->stopped = true;
    stream->waits_for_cpu = false;
    if (stream->in_flight_cancel) stream->in_flight_cancel->store(true);
    const auto it = std::find(streams_.begin(), streams_.end(), stream);
    if (it == streams_.end()) return;
    const auto index = static_cast<std::size_t>(it - streams_.begin());
    streams_.erase(it);
    if (cursor_ > index) --cursor_;
    daemon_.metrics().set_streams_active(streams_.size());
}

void StreamHub::scene_changed(const std::string& scene) {
    std::lock_guard lock(mutex_);
    for (const auto& stream : streams_) {
        if (stream->order.view.scene != scene) continue;
        changed(*stream);
        wake(stream);
    }
}

// A new state: it restarts the ladder. A refinement rung still running shows an old state at a cost
// (a reference rung takes seconds): it is stopped. Rung 0 is left to finish: it is the quick frame a
// moving view needs, and stopping it each time would leave a view that never stops moving with none.
void StreamHub::changed(Stream& stream) {
    ++stream.unshown_changes;
    if (stream.in_flight && stream.in_flight_rung >= 1 && stream.in_flight_cancel) stream.in_flight_cancel->store(true);
}

void StreamHub::wake(const StreamPtr& stream) {
    if (stopped_ || stream->stopped || !stream->scheduled || stream->owes_tick || stream->in_flight) return;
    stream->waits_for_cpu = false;  // a change sends it back to rung 0; a freed CPU lets it go on
    stream->owes_tick = true;
    daemon_.render_service().post([this](Renderer& renderer, SceneRegistry& registry) { tick(renderer, registry); });
}

void StreamHub::tick(Renderer& renderer, SceneRegistry& registry) {
    StreamPtr stream;
    std::shared_ptr<Request> request;
    std::optional<Failure> missing_scene;
    {
        std::lock_guard lock(mutex_);
        if (stopped_ || streams_.empty()) return;
        // Round-robin over the streams owed a tick. One whose next rung needs the CPU while another
        // stream's CPU rung renders waits for it (release_cpu) and the tick goes to the next one.
        for (std::size_t k = 0; k < streams_.size() && !stream; ++k) {
            const std::size_t index = (cursor_ + k) % streams_.size();
            const StreamPtr& candidate = streams_[index];
            if (!candidate->owes_tick) continue;
            candidate->owes_tick = false;
            if (candidate->stopped || candidate->in_flight) continue;
            const auto entry = registry.entries().find(candidate->order.view.scene);
            if (entry == registry.entries().end()) {
                missing_scene = Failure{ErrorCode::not_found,
                                        fmt::format("scene '{}' is not loaded", candidate->order.view.scene), "scene"};
                candidate->in_flight = true;
                stream = candidate;
                cursor_ = index + 1;
                break;
            }
            const std::uint64_t version = entry->second.version;
            const bool state_changed =
                candidate->shown_scene_version != version || candidate->shown_view_version != candidate->view_version;
            const int rung = state_changed ? 0 : candidate->shown_rung + 1;
            if (rung >= static_cast<int>(candidate->order.ladder.size())) continue;  // converged: idle until a change
            const Rung& step = candidate->order.ladder[static_cast<std::size_t>(rung)];
            const bool on_cpu = step.frame.plan.site == FrameSite::cpu;
            if (on_cpu && cpu_holder_ && cpu_holder_ != candidate) {
                candidate->waits_for_cpu = true;
                continue;
            }
            stream = candidate;
            cursor_ = index + 1;
            if (on_cpu) cpu_holder_ = stream;

            if (state_changed) {
                // States that came and went while the last frame was in flight were never rendered.
                const std::uint64_t superseded = stream->unshown_changes > 1 ? stream->unshown_changes - 1 : 0;
                stream->dropped_stale += superseded;
                dropped_stale_ += superseded;
                if (superseded > 0) daemon_.metrics().count_stream_dropped(superseded);
                stream->unshown_changes = 0;
            }
            stream->shown_scene_version = version;
            stream->shown_view_version = stream->view_version;
            stream->shown_rung = rung;

            const int rungs = static_cast<int>(stream->order.ladder.size());
            json marks = {{"id", stream->id}, {"view_version", stream->view_version}, {"rung", rung}, {"rungs", rungs},
                          {"stage", step.stage}, {"final", rung + 1 == rungs}};
            auto channel = std::make_shared<FrameChannel>(*this, stream, std::move(marks));
            request = std::make_shared<Request>(
                channel, protocol::Message{static_cast<std::uint16_t>(MessageType::render), stream->id, stream->fields, {}});
            request->log_id = fmt::format("{}-{}/{}", stream->connection, stream->id, rung);
            request->order = step.frame;
            stream->in_flight = true;
            stream->in_flight_rung = rung;
            stream->in_flight_cancel = request->cancelled;
        }
        if (!stream) return;
    }
    if (missing_scene) {
        frame_failed(stream, *missing_scene);
        return;
    }
    daemon_.handlers().execute(request, renderer, registry);
}

void StreamHub::frame_done(const StreamPtr& stream) {
    std::lock_guard lock(mutex_);
    release_cpu(stream);
    stream->in_flight = false;
    stream->in_flight_cancel.reset();
    wake(stream);
}

void StreamHub::frame_failed(const StreamPtr& stream, const Failure& failure) {
    std::shared_ptr<StreamSink> sink;
    {
        std::lock_guard lock(mutex_);
        release_cpu(stream);
        stream->in_flight = false;
        stream->in_flight_cancel.reset();
        if (stream->stopped) return;
        if (failure.code == ErrorCode::cancelled) {  // a rung the view's change stopped
            ++rungs_stopped_;
            wake(stream);
            return;
        }
        if (failure.code == ErrorCode::busy) {  // every CPU frame slot is taken: the same rung, soon
            --stream->shown_rung;
            retry_later(stream);
            return;
        }
        sink = stream->sink.lock();
        remove(stream);
    }
    daemon_.metrics().count_error(std::string(protocol::error_code_name(failure.code)));
    log::info("stream", "stream {}-{} ended: {}", stream->connection, stream->id, failure.message);
    if (!sink) return;
    protocol::Message message = protocol::make_error(stream->id, failure.code, failure.message, failure.field);
    message.body["stream"] = stream->id;
    message.body["stream_ended"] = true;
    sink->send_stream_event(stream->id, std::move(message), {}, true);
}

void StreamHub::release_cpu(const StreamPtr& stream) {
    if (cpu_holder_ != stream) return;
    cpu_holder_.reset();
    // The least refined view waiting goes next (the lowest rung; the earliest in round-robin order
    // from the cursor among equals): a view at its first reference rung is worth more samples than
    // one already at its last.
    StreamPtr next;
    for (std::size_t k = 0; k < streams_.size(); ++k) {
        const StreamPtr& candidate = streams_[(cursor_ + k) % streams_.size()];
        if (candidate->waits_for_cpu && (!next || candidate->shown_rung < next->shown_rung)) next = candidate;
    }
    if (next) wake(next);
}

void StreamHub::retry_later(const StreamPtr& stream) {
    if (!stream->retry_timer) stream->retry_timer = std::make_unique<boost::asio::steady_timer>(daemon_.io());
    stream->retry_timer->expires_after(std::chrono::milliseconds(100));
    stream->retry_timer->async_wait([this, stream](boost::system::error_code error) {
        if (error) return;
        std::lock_guard lock(mutex_);
        wake(stream);
    });
}

json StreamHub::stats() const {
    std::lock_guard lock(mutex_);
    return {{"active", streams_.size()}, {"frames", frames_}, {"dropped_stale", dropped_stale_},
            {"rungs_stopped", rungs_stopped_}};
}

}  // namespace bounce::server
