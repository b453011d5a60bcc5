// Preview streams against a real daemon (docs/protocol.md, "stream.start"): the ladder, newest
// wins, round-robin fairness, per-connection views, and their ends. Frames are compared with the
// one-off renders of what each rung names, byte for byte: every method here is deterministic (the
// GPU methods on llvmpipe, the reference for a fixed seed), and so are the encoders.
#include "daemon_support.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <set>
#include <thread>

namespace bounce::test {
namespace {

using Clock = std::chrono::steady_clock;

const json kEye = {{"position", {0.0, 1.0, 3.4}}, {"look_at", {0.0, 1.0, 0.0}}, {"fov_deg", 40}};

json stream_fields(json extra = json::object()) {
    json fields = {{"scene", "cornell"}, {"width", 64}, {"height", 64}, {"camera", kEye}, {"reference_spp", 64}};
    for (const auto& [key, value] : extra.items()) fields[key] = value;
    return fields;
}

// Opens a stream on `client` with request id `id`; returns the ok's body.
json open_stream(Client& client, std::uint64_t id, const json& fields) {
    client.send_raw(frame_bytes(MessageType::stream_start, id, fields));
    const auto reply = reply_to(client, id);
    EXPECT_EQ(reply.type, static_cast<std::uint16_t>(MessageType::ok)) << reply.body.dump();
    return reply.body;
}

// The next event of stream `id` (frames or the error that ends it); replies to other ids are kept
// out of the way by the callers, who wait for those with reply_to before reading frames again.
protocol::Message next_event(Client& client, std::uint64_t id) {
    for (;;) {
        auto message = client.read();
        if (message.request_id == id) return message;
    }
}

protocol::Message next_frame(Client& client, std::uint64_t id) {
    auto message = next_event(client, id);
    EXPECT_EQ(message.type, static_cast<std::uint16_t>(MessageType::frame)) << message.body.dump();
    return message;
}

// Sends a request while a stream may be pushing frames on the same connection; returns its reply.
protocol::Message request_beside(Client& client, std::uint64_t id, MessageType type, const json& body,
                                 std::vector<protocol::Message>* frames = nullptr) {
    client.send_raw(frame_bytes(type, id, body));
    for (;;) {
        auto message = client.read();
        if (message.request_id == id) return message;
        if (frames) frames->push_back(std::move(message));
    }
}

// The one-off render of a rung: what its frame must be, byte for byte.
std::vector<std::uint8_t> one_off(Client& client, json body) {
    body["scene"] = "cornell";
    body["camera"] = kEye;
    return client.request(MessageType::render, body).attachment;
}

TEST(Streams, TheLadderClimbsThroughTheFramesItNames) {
    DaemonProcess daemon;
    Client viewer(daemon.endpoint());
    const json ok = open_stream(viewer, 7, stream_fields());
    EXPECT_EQ(ok["stream"], 7);
    // interactive, still, reference at 16 (denoised) and 64 samples.
    ASSERT_EQ(ok["rungs"], 4);
    std::vector<protocol::Message> frames;
    for (int rung = 0; rung < 4; ++rung) {
        frames.push_back(next_frame(viewer, 7));
        const json& marks = frames.back().body["stream"];
        EXPECT_EQ(marks["rung"], rung);
        EXPECT_EQ(marks["final"], rung == 3);
        EXPECT_EQ(frames.back().body["scene_version"], 0);
    }
    EXPECT_EQ(frames[0].body["stream"]["stage"], "interactive");
    EXPECT_EQ(frames[0].body["width"], 32);  // interactive_scale 0.5
    EXPECT_EQ(frames[1].body["stream"]["stage"], "still");
    EXPECT_EQ(frames[3].body["stream"]["stage"], "reference");

    Client other(daemon.endpoint());
    EXPECT_EQ(frames[0].attachment, one_off(other, {{"method", "direct"}, {"preset", "draft"}, {"width", 32}, {"height", 32},
                                                    {"format", "jpeg"}, {"jpeg_quality", 50}}));
    EXPECT_EQ(frames[1].attachment,
              one_off(other, {{"method", "direct"}, {"width", 64}, {"height", 64}, {"format", "jpeg"}}));
    // The top rung is the path-traced reference itself: a still view converges to the ground truth.
    EXPECT_EQ(frames[3].attachment,
              one_off(other, {{"method", "reference"}, {"preset", "medium"}, {"width", 64}, {"height", 64}, {"format", "jpeg"},
                              {"knobs", {{"spp", 64}, {"seed", 3}, {"denoise", 0}}}}));
}

// A change restarts the ladder at rung 0 within one frame: a reference rung still running when the
// scene moves is stopped, and the first frame after the mutation's reply shows the mutation.
TEST(Streams, AChangeStopsTheRunningRungAndRestartsTheLadder) {
    DaemonProcess daemon;
    Client viewer(daemon.endpoint());
    // The last rung: 4096 samples at 64x64, seconds on two cores; the change comes while it runs.
    open_stream(viewer, 7, stream_fields({{"reference_spp", 4096}}));
    for (;;) {
        const auto frame = next_frame(viewer, 7);
        if (frame.body["stream"]["rung"] == 3) break;  // 256 samples done: the 1024 rung runs now
    }
    std::vector<protocol::Message> early;
    const auto moved = request_beside(viewer, 8, MessageType::object_set_transform,
                                      {{"scene", "cornell"}, {"object", "short_block"}, {"translation", {0.1, 0.0, 0.0}}},
                                      &early);
    ASSERT_EQ(moved.type, static_cast<std::uint16_t>(MessageType::ok)) << moved.body.dump();
    const std::uint64_t version = moved.body["scene_version"];
    for (const auto& frame : early) EXPECT_LT(frame.body["scene_version"].get<std::uint64_t>(), version);
    const auto first = next_frame(viewer, 7);
    EXPECT_EQ(first.body["scene_version"], version);
    EXPECT_EQ(first.body["stream"]["rung"], 0);

    Client other(daemon.endpoint());
    const json stats = other.request(MessageType::stats).body["streams"];
    EXPECT_EQ(stats["active"], 1);
    EXPECT_GE(stats["rungs_stopped"].get<int>(), 1);
}

TEST(Streams, UpdatesMergeIntoTheViewAndBadOnesChangeNothing) {
    DaemonProcess daemon;
    Client viewer(daemon.endpoint());
    open_stream(viewer, 7, stream_fields({{"refine", false}}));
    next_frame(viewer, 7);
    next_frame(viewer, 7);  // interactive, still: converged

    const auto refused = request_beside(viewer, 8, MessageType::stream_update, {{"stream", 7}, {"width", 0}});
    ASSERT_EQ(refused.type, static_cast<std::uint16_t>(MessageType::error));
    EXPECT_EQ(refused.body["field"], "width");
    const auto unknown = request_beside(viewer, 9, MessageType::stream_update, {{"stream", 99}, {"width", 32}});
    ASSERT_EQ(unknown.type, static_cast<std::uint16_t>(MessageType::error));
    EXPECT_EQ(unknown.body["code"], "not_found");
    EXPECT_EQ(unknown.body["field"], "stream");

    // A merge patch: the camera's fov alone changes, its position and target stay. The new view's
    // frames may come before the reply (the protocol orders them by view_version, not by the reply),
    // so those that do are kept.
    std::vector<protocol::Message> early;
    const auto updated = request_beside(viewer, 10, MessageType::stream_update,
                                        {{"stream", 7}, {"camera", {{"fov_deg", 60}}}}, &early);
    ASSERT_EQ(updated.type, static_cast<std::uint16_t>(MessageType::ok)) << updated.body.dump();
    EXPECT_EQ(updated.body["view_version"], 1);
    std::vector<protocol::Message> of_new_view;
    for (auto& frame : early) {
        if (frame.request_id == 7 && frame.body["stream"]["view_version"] == 1) of_new_view.push_back(std::move(frame));
    }
    while (of_new_view.size() < 2) of_new_view.push_back(next_frame(viewer, 7));  // interactive, still
    const auto& still = of_new_view[1];
    EXPECT_EQ(still.body["stream"]["view_version"], 1);
    EXPECT_EQ(still.body["stream"]["final"], true);
    Client other(daemon.endpoint());
    json body = {{"scene", "cornell"}, {"method", "direct"}, {"width", 64}, {"height", 64}, {"format", "jpeg"}, {"camera", kEye}};
    body["camera"]["fov_deg"] = 60;
    EXPECT_EQ(still.attachment, other.request(MessageType::render, body).attachment);
}

// Views belong to their connections: two viewers with their own cameras each see their own view,
// and a third client's render of the scene's default camera is what it was before them.
TEST(Streams, InlineCamerasAreIsolated) {
    DaemonProcess daemon;
    Client third(daemon.endpoint());
    const json plain = {{"scene", "cornell"}, {"width", 64}, {"height", 64}, {"format", "png"}};
    const auto before = third.request(MessageType::render, plain).attachment;

    const json left = {{"position", {-0.6, 1.0, 3.0}}, {"look_at", {0.0, 1.0, 0.0}}};
    const json right = {{"position", {0.6, 1.2, 3.0}}, {"look_at", {0.0, 0.8, 0.0}}, {"fov_deg", 50}};
    Client a(daemon.endpoint()), b(daemon.endpoint());
    open_stream(a, 1, stream_fields({{"camera", left}, {"refine", false}, {"format", "png"}}));
    open_stream(b, 1, stream_fields({{"camera", right}, {"refine", false}, {"format", "png"}}));
    next_frame(a, 1);
    next_frame(b, 1);
    const auto seen_a = next_frame(a, 1).attachment;
    const auto seen_b = next_frame(b, 1).attachment;
    EXPECT_NE(seen_a, seen_b);
    json with_left = plain, with_right = plain;
    with_left["camera"] = left;
    with_right["camera"] = right;
    EXPECT_EQ(seen_a, third.request(MessageType::render, with_left).attachment);
    EXPECT_EQ(seen_b, third.request(MessageType::render, with_right).attachment);
    EXPECT_EQ(before, third.request(MessageType::render, plain).attachment);
    // A render's inline camera is refused field by field, like camera.set.
    expect_error([&] { third.request(MessageType::render, {{"scene", "cornell"}, {"camera", {{"fov_deg", 500}}}}); },
                 ErrorCode::bad_request, "camera.fov_deg");
    expect_error([&] { third.request(MessageType::render, {{"scene", "cornell"}, {"camera", 3}}); }, ErrorCode::bad_request,
                 "camera");
}

// A viewer that does not read: its daemon holds at most one frame of the stream, so even with
// room for only three frames of unread output (--max-output-bytes) it is not dropped however many
// changes come, it is sent no more frames than the kernel's socket buffers hold, and once it reads
// it is shown the newest state.
TEST(Streams, ASlowReaderNeverHasMoreThanOneFrameQueued) {
    DaemonProcess daemon({"--max-output-bytes", "200K"});
    boost::asio::io_context io;
    boost::asio::ip::tcp::socket slow(io);
    slow.open(boost::asio::ip::tcp::v4());
    slow.set_option(boost::asio::socket_base::receive_buffer_size(4096));  // the kernel holds little for it
    slow.connect({boost::asio::ip::make_address("127.0.0.1"), daemon.endpoint().port});
    const json fields = {{"scene", "cornell"}, {"width", 256}, {"height", 256}, {"format", "png"}, {"refine", false},
                         {"interactive_scale", 1}, {"preset", "draft"}};
    boost::asio::write(slow, boost::asio::buffer(frame_bytes(MessageType::stream_start, 5, fields)));

    // Changes for 4 s, faster than frames are made: a queue per change would pass 200 KB in the first
    // second once the socket buffers are full.
    constexpr int kChanges = 200;
    Client mover(daemon.endpoint());
    std::uint64_t version = 0;
    for (int i = 0; i < kChanges; ++i) {
        version = mover.request(MessageType::object_set_transform, {{"scene", "cornell"}, {"object", "short_block"},
                                                                     {"translation", {0.0005 * i, 0.0, 0.0}}})
                      .body["scene_version"];
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::uint64_t last_version = 0;
    int frames = 0;
    std::size_t smallest_frame = SIZE_MAX;
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    protocol::Limits limits;
    limits.max_attachment_bytes = 64u << 20;
    while (last_version < version && Clock::now() < deadline) {
        std::array<std::uint8_t, protocol::kHeaderSize> header_bytes{};
        boost::asio::read(slow, boost::asio::buffer(header_bytes));
        const auto header = protocol::decode_header(header_bytes, limits);
        std::vector<std::uint8_t> body(header.json_length + header.attachment_length);
        boost::asio::read(slow, boost::asio::buffer(body));
        const json message = protocol::parse_body(std::span(body).first(header.json_length), header.request_id);
        if (header.type == static_cast<std::uint16_t>(MessageType::frame)) {
            ++frames;
            last_version = message["scene_version"];
            smallest_frame = std::min(smallest_frame, body.size() + protocol::kHeaderSize);
        }
    }
    EXPECT_EQ(last_version, version);
    // What the kernel may hold on the way: the daemon's send buffer at its largest (tcp_wmem's
    // maximum, which the kernel passes by up to one 64 KB segment) and the reader's receive buffer
    // (twice what was asked, as Linux books it); plus the frame being written and the newest.
    std::size_t send_buffer_max = 4u << 20;
    std::ifstream("/proc/sys/net/ipv4/tcp_wmem") >> send_buffer_max >> send_buffer_max >> send_buffer_max;
    const auto bound = static_cast<int>((send_buffer_max + 65536 + 2 * 4096) / smallest_frame + 2);
    RecordProperty("smallest_frame", static_cast<int>(smallest_frame));
    RecordProperty("frames", frames);
    RecordProperty("bound", bound);
    EXPECT_LE(frames, bound);
    EXPECT_LT(bound, kChanges) << "the test needs more changes than the kernel can buffer frames";
    const json stats = mover.request(MessageType::stats).body["streams"];
    EXPECT_GT(stats["dropped_stale"].get<int>(), 0);
}

// Round-robin: eight viewers all get frames while a ninth client keeps the render queue full of
// one-off renders and the scene changes. Each round serves every viewer that wants a frame once, so
// their counts differ by the rounds in which a viewer's last frame was still being written: a few.
TEST(Streams, EightViewersAreServedFairlyUnderLoad) {
    DaemonProcess daemon;
    std::atomic<bool> running{true};
    std::thread load([&] {
        Client client(daemon.endpoint());
        int i = 0;
        while (running) {
            if (i % 4 == 0) {
                client.request(MessageType::object_set_transform,
                               {{"scene", "cornell"}, {"object", "tall_block"}, {"translation", {0.001 * (i % 50), 0.0, 0.0}}});
            }
            client.request(MessageType::render, {{"scene", "cornell"}, {"width", 64}, {"height", 64}});
            ++i;
        }
    });
    std::vector<int> counts(8, 0);
    std::vector<std::thread> viewers;
    for (int v = 0; v < 8; ++v) {
        viewers.emplace_back([&, v] {
            Client client(daemon.endpoint());
            json camera = kEye;
            camera["position"] = {-0.4 + 0.1 * v, 1.0, 3.4};
            open_stream(client, 1, stream_fields({{"camera", camera}, {"refine", false}}));
            const auto end = Clock::now() + std::chrono::seconds(8);
            while (Clock::now() < end) {
                next_frame(client, 1);
                ++counts[v];
            }
        });
    }
    for (auto& viewer : viewers) viewer.join();
    running = false;
    load.join();
    const int least = *std::min_element(counts.begin(), counts.end());
    const int most = *std::max_element(counts.begin(), counts.end());
    for (int v = 0; v < 8; ++v) RecordProperty("viewer_" + std::to_string(v), counts[v]);
    EXPECT_GE(least, 5);
    EXPECT_GE(2 * least, most);
}

// Reference rungs take every core, so they render one at a time across streams, and a view that
// has just changed gets its first path-traced frame before the others get more of theirs: between
// its still frame and its first reference frame at most one other reference frame comes (the one
// rendering when it asked). Were the rungs queued as they came, its first would wait behind as many
// as the CPU queue holds (four), each up to seconds of samples.
TEST(Streams, AChangedViewsFirstReferenceRungGoesBeforeOthersLaterRungs) {
    DaemonProcess daemon;
    Client viewer(daemon.endpoint());
    constexpr int kStreams = 6;
    // 32x32 up to 4096 samples: each stream's ladder is seconds of tracing, so all are climbing.
    for (int id = 1; id <= kStreams; ++id) {
        json camera = kEye;
        camera["position"] = {-0.3 + 0.1 * id, 1.0, 3.4};
        open_stream(viewer, id, stream_fields({{"width", 32}, {"height", 32}, {"camera", camera}, {"reference_spp", 4096}}));
    }
    // Every stream past its first reference rung.
    std::set<std::uint64_t> refining;
    while (refining.size() < kStreams) {
        const auto frame = viewer.read();
        ASSERT_EQ(frame.type, static_cast<std::uint16_t>(MessageType::frame)) << frame.body.dump();
        if (frame.body["stream"]["rung"].get<int>() >= 2) refining.insert(frame.request_id);
    }
    constexpr std::uint64_t kChanged = 1;
    std::vector<protocol::Message> frames;
    const auto updated = request_beside(viewer, 100, MessageType::stream_update,
                                        {{"stream", kChanged}, {"camera", {{"fov_deg", 45}}}}, &frames);
    ASSERT_EQ(updated.type, static_cast<std::uint16_t>(MessageType::ok)) << updated.body.dump();
    const std::uint64_t view_version = updated.body["view_version"];
    // Read on until the changed view's first reference frame.
    const auto of_changed_view = [&](const protocol::Message& frame, int rung) {
        return frame.request_id == kChanged && frame.body["stream"]["view_version"] == view_version &&
               frame.body["stream"]["rung"] == rung;
    };
    while (frames.empty() || !of_changed_view(frames.back(), 2)) {
        frames.push_back(viewer.read());
        ASSERT_EQ(frames.back().type, static_cast<std::uint16_t>(MessageType::frame)) << frames.back().body.dump();
    }
    const auto still = std::find_if(frames.begin(), frames.end(), [&](const auto& frame) { return of_changed_view(frame, 1); });
    ASSERT_NE(still, frames.end());
    const auto others_reference = std::count_if(still, frames.end(), [&](const protocol::Message& frame) {
        return frame.request_id != kChanged && frame.body["stream"]["stage"] == "reference";
    });
    EXPECT_LE(others_reference, 1);
    for (int id = 1; id <= kStreams; ++id) {
        const auto stopped = request_beside(viewer, 200 + id, MessageType::stream_stop, {{"stream", id}});
        EXPECT_EQ(stopped.type, static_cast<std::uint16_t>(MessageType::ok)) << stopped.body.dump();
    }
}

TEST(Streams, StopEndsTheEventsAndAnUnloadedSceneEndsTheStream) {
    DaemonProcess daemon;
    Client viewer(daemon.endpoint());
    open_stream(viewer, 7, stream_fields({{"refine", false}}));
    next_frame(viewer, 7);
    const auto stopped = request_beside(viewer, 8, MessageType::stream_stop, {{"stream", 7}});
    ASSERT_EQ(stopped.type, static_cast<std::uint16_t>(MessageType::ok));
    EXPECT_GE(stopped.body["frames"].get<int>(), 1);
    // Nothing of stream 7 follows its stop: the next message is the reply to a ping.
    viewer.send_raw(frame_bytes(MessageType::ping, 9, json::object()));
    const auto next = viewer.read();
    EXPECT_EQ(next.request_id, 9u);
    EXPECT_EQ(next.type, static_cast<std::uint16_t>(MessageType::pong));
    expect_error([&] { viewer.request(MessageType::stream_stop, {{"stream", 7}}); }, ErrorCode::not_found, "stream");

    Client owner(daemon.endpoint());
    owner.request(MessageType::scene_load, {{"name", "box"}, {"builtin", "cornell"}});
    open_stream(viewer, 11, stream_fields({{"scene", "box"}, {"refine", false}}));
    next_frame(viewer, 11);
    next_frame(viewer, 11);
    owner.request(MessageType::scene_unload, {{"name", "box"}});
    const auto ended = next_event(viewer, 11);
    ASSERT_EQ(ended.type, static_cast<std::uint16_t>(MessageType::error));
    EXPECT_EQ(ended.body["code"], "not_found");
    EXPECT_EQ(ended.body["stream_ended"], true);
    EXPECT_EQ(owner.request(MessageType::stats).body["streams"]["active"], 0);
    // Fields a stream refuses, before anything runs.
    expect_error([&] { viewer.request(MessageType::stream_start, stream_fields({{"format", "exr"}})); }, ErrorCode::bad_request,
                 "format");
    expect_error([&] { viewer.request(MessageType::stream_start, stream_fields({{"timeout_ms", 10}})); }, ErrorCode::bad_request,
                 "timeout_ms");
    expect_error([&] { viewer.request(MessageType::stream_start, stream_fields({{"interactive_scale", 2}})); },
                 ErrorCode::bad_request, "interactive_scale");
}

}  // namespace
}  // namespace bounce::test
