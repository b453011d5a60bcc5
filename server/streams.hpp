// Preview streams (docs/protocol.md, "stream.start, stream.update, stream.stop"): views the daemon
// keeps rendering for their connections. Newest state wins: a stream has at most one frame in
// flight, from the render thread until its bytes are written to the connection, and the next frame
// is chosen when that one is done, from the state then current; states superseded meanwhile are
// never rendered. Streams are served round-robin: each stream that wants a frame owes one tick on
// the render queue, and each tick serves the next such stream after the last one served.
#pragma once

#include "protocol/protocol.hpp"
#include "server/request.hpp"
#include "server/stream_ladder.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace bounce {
class Renderer;
}

namespace bounce::server {

class Daemon;
class SceneRegistry;

// What a stream's connection offers: events queued in order, and word once each is written.
class StreamSink {
public:
    virtual ~StreamSink() = default;
    // Thread-safe. Queues an event of stream `stream_id`; `done` runs once its bytes are written, or
    // when it is dropped (the stream stopped, the connection closed). `ends_stream`: the connection
    // forgets the stream after this event (an error that ended it).
    virtual void send_stream_event(std::uint64_t stream_id, protocol::Message message, std::function<void()> done,
                                   bool ends_stream) = 0;
};

class StreamHub {
public:
    explicit StreamHub(Daemon& daemon) : daemon_(daemon) {}

    static constexpr std::size_t kMaxStreamsPerConnection = 16;

    // On the connection's thread. open() checks the fields and registers the stream (throwing
    // FieldError, RequestError for a bad field or past the per-connection cap) and returns the
    // `ok` body; schedule() starts it, once the `ok` is queued so that no frame precedes it.
    nlohmann::json open(std::shared_ptr<StreamSink> sink, std::uint64_t connection, std::uint64_t id,
                        const nlohmann::json& fields);
    void schedule(std::uint64_t connection, std::uint64_t id);
    // Merges `patch` into the stream's fields; a bad field leaves the stream as it was.
    nlohmann::json update(std::uint64_t connection, std::uint64_t id, const nlohmann::json& patch);
    nlohmann::json stop(std::uint64_t connection, std::uint64_t id);
    void drop_connection(std::uint64_t connection);
    // No frame starts after this (the daemon is draining).
    void stop_all();

    // On the render thread, after a request changed, loaded or unloaded `scene`.
    void scene_changed(const std::string& scene);

    nlohmann::json stats() const;

private:
    struct Stream;
    class FrameChannel;
    using StreamPtr = std::shared_ptr<Stream>;

    StreamPtr find(std::uint64_t connection, std::uint64_t id) const;  // mutex_ held; not_found otherwise
    void changed(Stream& stream);                                      // mutex_ held
    void wake(const StreamPtr& stream);                                // mutex_ held
    void remove(const StreamPtr& stream);                              // mutex_ held
    void tick(Renderer& renderer, SceneRegistry& registry);            // render thread
    void frame_done(const StreamPtr& stream);
    void frame_failed(const StreamPtr& stream, const Failure& failure);
    void retry_later(const StreamPtr& stream);
    void release_cpu(const StreamPtr& stream);  // mutex_ held: its CPU rung has rendered or ended

    Daemon& daemon_;
    mutable std::mutex mutex_;
    std::vector<StreamPtr> streams_;  // in order of opening; the round-robin walks it
    std::size_t cursor_ = 0;          // where the next tick starts looking
    // The stream whose CPU rung (a `reference` frame) is rendering. One at a time: the path tracer
    // takes every core, so a second would only queue behind it, in the order the rungs came, where
    // the hub serves the least refined view first (streams waiting for the CPU hold waits_for_cpu).
    StreamPtr cpu_holder_;
    bool stopped_ = false;
    std::uint64_t frames_ = 0, dropped_stale_ = 0, rungs_stopped_ = 0;
};

}  // namespace bounce::server
