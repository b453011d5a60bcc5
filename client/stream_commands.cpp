#include "client/stream_commands.hpp"

#include "client/router.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <thread>

namespace bounce::cli {
namespace {

using client::Client;
using client::Endpoint;
using client::ServerError;
using nlohmann::json;
using protocol::MessageType;
using Clock = std::chrono::steady_clock;
using Vec3 = std::array<double, 3>;

// How often a viewer waiting for its next frame looks up to see whether the run is over.
constexpr auto kPollInterval = std::chrono::milliseconds(50);
// After the last move, how long viewers wait to show it before it counts as unseen.
constexpr auto kDrainTime = std::chrono::seconds(60);
// The mover's translations alternate between +kMoveOffset and -kMoveOffset along x (metres):
// small enough to keep the object in view, and every move a change.
constexpr double kMoveOffset = 0.02;

bool is(const protocol::Message& message, MessageType type) {
    return message.type == static_cast<std::uint16_t>(type);
}

// The daemon that holds a scene: the first of its rendezvous order, as every command routes it.
Endpoint scene_daemon(const std::vector<Endpoint>& endpoints, const std::optional<std::string>& token,
                      const std::string& scene) {
    return client::Router(endpoints, token).owner(scene);
}

// Through a temporary file, so that whoever watches the folder never reads half a frame.
void write_frame(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
    std::filesystem::path temporary = path;
    temporary += ".tmp";
    {
        std::ofstream out(temporary, std::ios::binary);
        out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
        if (!out) throw std::runtime_error("cannot write " + temporary.string());
    }
    std::error_code error;
    std::filesystem::rename(temporary, path, error);
    if (error) throw std::runtime_error("cannot write " + path.string() + ": " + error.message());
}

std::string extension_of(const std::string& format) { return format == "jpeg" ? "jpg" : format; }

// The `error` message's "CODE: MESSAGE", as the CLI prints a refusal.
std::string describe_error(const json& body) {
    return body.value("code", "internal") + ": " + body.value("message", "error");
}

// ------------------------------------------------------------------------------------------------
// load-test --stream: the viewers' views.

std::optional<Vec3> vec3_of(const json& value) {
    if (!value.is_array() || value.size() != 3) return std::nullopt;
    Vec3 vector{};
    for (std::size_t i = 0; i < 3; ++i) {
        if (!value[i].is_number()) return std::nullopt;
        vector[i] = value[i].get<double>();
        if (!std::isfinite(vector[i])) return std::nullopt;
    }
    return vector;
}

// (x, z) turned by `radians` about the vertical axis through `centre`.
Vec3 yawed(const Vec3& point, const Vec3& centre, double radians) {
    const double x = point[0] - centre[0], z = point[2] - centre[2];
    return {centre[0] + x * std::cos(radians) + z * std::sin(radians), point[1],
            centre[2] - x * std::sin(radians) + z * std::cos(radians)};
}

// One inline camera per viewer: the scene's first camera (position and view direction) orbited
// about the centre of the scene's bounds by 360°·i/N of yaw, so that no two viewers see the same
// view. A scene without a camera, or whose camera stands on the vertical through the centre
// (where a yaw would not move it), gets a camera framing its bounds from +z instead.
std::vector<json> orbit_cameras(const json& description, int viewers) {
    constexpr double kInfinity = std::numeric_limits<double>::infinity();
    Vec3 low{kInfinity, kInfinity, kInfinity}, high{-kInfinity, -kInfinity, -kInfinity};
    for (const json& object : description.value("objects", json::array())) {
        // Objects without geometry have no bounds (or infinite ones, sent as null).
        const auto min = vec3_of(object.value("bounds_min", json())), max = vec3_of(object.value("bounds_max", json()));
        if (!min || !max) continue;
        for (std::size_t i = 0; i < 3; ++i) {
            low[i] = std::min(low[i], (*min)[i]);
            high[i] = std::max(high[i], (*max)[i]);
        }
    }
    const bool bounded = low[0] <= high[0];
    const Vec3 centre = bounded ? Vec3{(low[0] + high[0]) / 2, (low[1] + high[1]) / 2, (low[2] + high[2]) / 2} : Vec3{};
    const double radius = bounded ? std::max(0.5 * std::hypot(high[0] - low[0], high[1] - low[1], high[2] - low[2]), 1e-3)
                                  : 1.0;

    std::optional<Vec3> position, forward;
    std::optional<double> fov_deg;
    const json cameras = description.value("cameras", json::array());
    if (!cameras.empty()) {
        position = vec3_of(cameras.front().value("position", json()));
        forward = vec3_of(cameras.front().value("forward", json()));
        if (cameras.front().contains("fov_deg") && cameras.front()["fov_deg"].is_number()) {
            fov_deg = cameras.front()["fov_deg"].get<double>();
        }
    }
    Vec3 eye{}, target{};
    if (position && forward && std::hypot((*position)[0] - centre[0], (*position)[2] - centre[2]) > 1e-6 * radius) {
        eye = *position;
        target = {eye[0] + (*forward)[0], eye[1] + (*forward)[1], eye[2] + (*forward)[2]};
    } else {
        constexpr double kFramingFovDeg = 40.0;
        fov_deg = kFramingFovDeg;
        // Far enough that the bounding sphere fills the view.
        const double distance = radius / std::sin(kFramingFovDeg / 2 * std::numbers::pi / 180);
        eye = {centre[0], centre[1], centre[2] + distance};
        target = centre;
    }
    std::vector<json> views;
    for (int i = 0; i < viewers; ++i) {
        const double yaw = 2 * std::numbers::pi * i / viewers;
        json camera = {{"position", yawed(eye, centre, yaw)}, {"look_at", yawed(target, centre, yaw)}};
        if (fov_deg) camera["fov_deg"] = *fov_deg;
        views.push_back(std::move(camera));
    }
    return views;
}

// ------------------------------------------------------------------------------------------------
// load-test --stream: the run, shared by the viewer threads and the mover thread.

struct ViewerRecord {
    bool started = false;  // stream.start answered, or a frame came
    bool ended = false;    // stopped, failed, or never started
    bool failed = false;   // ended by an error, already counted: its unseen moves are not counted again
    std::vector<std::pair<Clock::time_point, std::uint64_t>> frames;  // arrival, the scene_version shown
    bool latest_final = false;                                        // the latest frame was its ladder's last
    std::uint64_t dropped_stale = 0;                                  // from the stream.stop reply
};

struct MoveRecord {
    Clock::time_point replied;  // when the `ok` came back
    std::uint64_t scene_version;
};

// Every field is guarded by `mutex`; `changed` is notified whenever one changes.
struct StreamRun {
    std::mutex mutex;
    std::condition_variable changed;
    std::vector<ViewerRecord> viewers;
    std::vector<MoveRecord> moves;
    std::map<std::string, int> errors;
    std::size_t frames_wanted = 0;
    bool moves_over = false;  // no move follows: viewers stop once they showed the last one
    Clock::time_point drain_deadline;

    bool all_started() const {
        return std::all_of(viewers.begin(), viewers.end(), [](const ViewerRecord& v) { return v.started || v.ended; });
    }
    // Every viewer has its frames (or has ended): no more moves are needed.
    bool enough() const {
        return std::all_of(viewers.begin(), viewers.end(),
                           [&](const ViewerRecord& v) { return v.ended || v.frames.size() >= frames_wanted; });
    }
    // The viewer whose frames pace the moves: viewer 0, or the first one still running.
    std::size_t pacer() const {
        const auto running = std::find_if(viewers.begin(), viewers.end(), [](const ViewerRecord& v) { return !v.ended; });
        return static_cast<std::size_t>(running - viewers.begin());
    }
    bool move_due(std::size_t paced_by, std::size_t frames_at_move, std::size_t move_every) const {
        const std::size_t now_paced_by = pacer();
        if (now_paced_by != paced_by) return true;  // the pacer ended: the next one paces from now
        const ViewerRecord& viewer = viewers[paced_by];
        if (viewer.frames.size() - frames_at_move >= move_every) return true;
        // A ladder at its last rung sends nothing until something changes: without a move now,
        // the run would wait for frames that never come.
        return viewer.latest_final && !viewer.frames.empty() && !moves.empty() &&
               viewer.frames.back().second >= moves.back().scene_version;
    }
    bool may_stop(std::size_t index) const {
        if (!moves_over) return false;
        const ViewerRecord& viewer = viewers[index];
        const bool shows_last_move =
            moves.empty() || (!viewer.frames.empty() && viewer.frames.back().second >= moves.back().scene_version);
        return shows_last_move || Clock::now() >= drain_deadline;
    }
    void fail_viewer(std::size_t index, const std::string& error) {
        ++errors[error];
        viewers[index].ended = viewers[index].failed = true;
        changed.notify_all();
    }
};

void run_viewer(StreamRun& run, std::size_t index, const Endpoint& daemon, const std::optional<std::string>& token,
                const json& start) {
    try {
        Client client(daemon, token);
        const std::uint64_t stream = client.send(MessageType::stream_start, start);
        bool stopping = false;
        while (!stopping) {
            if (!client.wait_readable(kPollInterval)) {
                std::lock_guard lock(run.mutex);
                stopping = run.may_stop(index);
                continue;
            }
            const protocol::Message message = client.read();
            if (message.request_id != stream) continue;
            const auto arrived = Clock::now();
            std::lock_guard lock(run.mutex);
            if (is(message, MessageType::error)) {
                // A refused stream.start, or a frame that failed and ended the stream.
                run.fail_viewer(index, message.body.value("code", "internal"));
                return;
            }
            ViewerRecord& viewer = run.viewers[index];
            viewer.started = true;
            if (is(message, MessageType::frame)) {
                viewer.frames.emplace_back(arrived, message.body.value("scene_version", std::uint64_t{0}));
                viewer.latest_final = message.body.value(json::json_pointer("/stream/final"), false);
            }
            run.changed.notify_all();
            stopping = run.may_stop(index);
        }
        const auto reply = client.request(MessageType::stream_stop, {{"stream", stream}});
        std::lock_guard lock(run.mutex);
        run.viewers[index].dropped_stale = reply.body.value("dropped_stale", std::uint64_t{0});
        run.viewers[index].ended = true;
        run.changed.notify_all();
    } catch (const ServerError& error) {
        std::lock_guard lock(run.mutex);
        run.fail_viewer(index, std::string(protocol::error_code_name(error.code())));
    } catch (const std::exception& error) {
        std::lock_guard lock(run.mutex);
        run.fail_viewer(index, std::string("connection: ") + error.what());
    }
}

// Moves `object` once every stream is up, then each time the pacing viewer received
// `move_every` frames since the previous move, until every viewer has its frames.
void run_mover(StreamRun& run, const Endpoint& daemon, const std::optional<std::string>& token,
               const std::string& scene, const std::string& object, int move_every) {
    try {
        Client mover(daemon, token);
        double offset = kMoveOffset;
        std::unique_lock lock(run.mutex);
        // Moving before the streams are up would time their start-up, not the motion.
        run.changed.wait(lock, [&] { return run.all_started(); });
        while (!run.enough()) {
            const std::size_t paced_by = run.pacer();
            const std::size_t frames_at_move = run.viewers[paced_by].frames.size();
            lock.unlock();
            const auto reply = mover.request(MessageType::object_set_transform,
                                             {{"scene", scene}, {"object", object}, {"translation", {offset, 0.0, 0.0}}});
            const auto replied = Clock::now();
            offset = -offset;
            lock.lock();
            run.moves.push_back({replied, reply.body.value("scene_version", std::uint64_t{0})});
            run.changed.notify_all();
            const auto due = [&] {
                return run.enough() || run.move_due(paced_by, frames_at_move, static_cast<std::size_t>(move_every));
            };
            while (!run.changed.wait_for(lock, kPollInterval, due)) {
                // Between moves the mover sends nothing: answer the daemon's pings, or it hangs up.
                lock.unlock();
                while (mover.wait_readable(std::chrono::milliseconds(0))) mover.read();
                lock.lock();
            }
        }
    } catch (const ServerError& error) {
        std::lock_guard lock(run.mutex);
        ++run.errors[std::string("move: ") + std::string(protocol::error_code_name(error.code()))];
    } catch (const std::exception& error) {
        std::lock_guard lock(run.mutex);
        ++run.errors[std::string("move: connection: ") + error.what()];
    }
    std::lock_guard lock(run.mutex);
    run.moves_over = true;
    run.drain_deadline = Clock::now() + kDrainTime;
    run.changed.notify_all();
}

// The nearest-rank percentile of sorted values, as the render load test reports its latencies.
double percentile(const std::vector<double>& sorted, double p) {
    if (sorted.empty()) return 0.0;
    const auto index = static_cast<std::size_t>(std::min<double>(sorted.size() - 1, p * (sorted.size() - 1) + 0.5));
    return sorted[index];
}

}  // namespace

bool watch(const std::vector<Endpoint>& endpoints, const std::optional<std::string>& token, const json& start,
           const WatchOptions& options) {
    const std::filesystem::path directory(options.directory);
    std::error_code error;
    std::filesystem::create_directories(directory, error);
    if (error) throw std::runtime_error("cannot create " + options.directory + ": " + error.message());
    const std::string extension = extension_of(start.value("format", "jpeg"));

    Client client(scene_daemon(endpoints, token, start.at("scene").get<std::string>()), token);
    const std::uint64_t stream = client.send(MessageType::stream_start, start);
    bool started = false;
    int saved = 0;
    for (;;) {
        const protocol::Message message = client.read();
        if (message.request_id != stream) continue;
        if (is(message, MessageType::error)) {
            // Before the `ok`, stream.start was refused: a refusal like any other command's. After
            // it, a frame failed and the stream ended.
            if (!started && !message.body.value("stream_ended", false)) throw ServerError::from_body(message.body);
            std::cerr << "bounce: " << describe_error(message.body) << "\n";
            return false;
        }
        started = true;
        if (!is(message, MessageType::frame)) continue;  // stream.start's `ok`

        char name[32];
        std::snprintf(name, sizeof name, "frame-%06d.", saved);
        const std::filesystem::path path = directory / (name + extension);
        write_frame(path, message.attachment);
        const json& body = message.body;
        const json info = body.value("stream", json::object());
        const json line = {{"file", path.string()},
                           {"scene_version", body.value("scene_version", std::uint64_t{0})},
                           {"rung", info.value("rung", 0)},
                           {"stage", info.value("stage", "")},
                           {"final", info.value("final", false)},
                           {"width", body.value("width", 0)},
                           {"height", body.value("height", 0)},
                           {"total_ms", body.value(json::json_pointer("/timings_ms/total"), 0.0)}};
        std::cout << line.dump() << std::endl;  // flushed: a pipe's reader sees each frame as it lands
        ++saved;
        if ((options.frames > 0 && saved >= options.frames) || (options.until_final && line["final"].get<bool>())) break;
    }
    client.request(MessageType::stream_stop, {{"stream", stream}});
    return true;
}

bool stream_load_test(const std::vector<Endpoint>& endpoints, const std::optional<std::string>& token,
                      const json& start, const StreamLoadTestOptions& options) {
    const std::string scene = start.at("scene").get<std::string>();
    json description;
    Endpoint daemon;
    {
        // Closed before the run: a connection that reads nothing would miss the daemon's pings.
        client::Router probe(endpoints, token);
        description = probe.request(scene, MessageType::scene_describe, {{"name", scene}}).body;
        // Every connection goes to the daemon that answered: streams show the moves of their own daemon.
        daemon = probe.owner(scene);
    }
    const json objects = description.value("objects", json::array());
    if (objects.empty()) throw std::runtime_error("load-test --stream: scene '" + scene + "' has no object to move");
    const std::string object = objects.back().value("name", "");
    const std::vector<json> cameras = orbit_cameras(description, options.viewers);

    StreamRun run;
    run.viewers.resize(static_cast<std::size_t>(options.viewers));
    run.frames_wanted = static_cast<std::size_t>(options.frames);
    const auto began = Clock::now();
    std::vector<std::thread> threads;
    for (std::size_t i = 0; i < run.viewers.size(); ++i) {
        json body = start;
        body["camera"] = cameras[i];
        threads.emplace_back([&, i, body] { run_viewer(run, i, daemon, token, body); });
    }
    threads.emplace_back([&] { run_mover(run, daemon, token, scene, object, options.move_every); });
    for (auto& thread : threads) thread.join();
    const double seconds = std::chrono::duration<double>(Clock::now() - began).count();

    // Motion to photon of each (move, viewer): from the move's reply to the viewer's first frame
    // that shows the move's version; a frame that showed it before the reply came counts as 0.
    std::vector<double> delays;
    int unseen = 0;
    for (const MoveRecord& move : run.moves) {
        for (const ViewerRecord& viewer : run.viewers) {
            if (viewer.failed) continue;
            const auto shown = std::find_if(viewer.frames.begin(), viewer.frames.end(),
                                            [&](const auto& frame) { return frame.second >= move.scene_version; });
            if (shown == viewer.frames.end()) {
                ++unseen;
                continue;
            }
            delays.push_back(std::max(0.0, std::chrono::duration<double, std::milli>(shown->first - move.replied).count()));
        }
    }
    if (unseen > 0) run.errors["unseen_motion"] += unseen;
    std::sort(delays.begin(), delays.end());

    std::size_t frames = 0, fewest = std::numeric_limits<std::size_t>::max(), most = 0;
    std::uint64_t dropped_stale = 0;
    for (const ViewerRecord& viewer : run.viewers) {
        frames += viewer.frames.size();
        fewest = std::min(fewest, viewer.frames.size());
        most = std::max(most, viewer.frames.size());
        dropped_stale += viewer.dropped_stale;
    }
    json errors = json::object();
    int error_count = 0;
    for (const auto& [code, count] : run.errors) {
        errors[code] = count;
        error_count += count;
    }
    const json summary = {
        {"clients", options.viewers + 1},  // the viewers and the mover
        {"viewers", options.viewers},
        {"moves", run.moves.size()},
        {"frames", frames},
        {"frames_per_second", frames / seconds},
        {"frames_per_viewer",
         {{"min", fewest}, {"mean", static_cast<double>(frames) / options.viewers}, {"max", most}}},
        {"dropped_stale", dropped_stale},
        {"errors", errors},
        {"seconds", seconds},
        {"motion_to_photon_ms",
         {{"p50", percentile(delays, 0.50)}, {"p95", percentile(delays, 0.95)}, {"p99", percentile(delays, 0.99)},
          {"max", delays.empty() ? 0.0 : delays.back()}, {"samples", delays.size()}}}};
    std::cout << summary.dump() << "\n";
    return error_count == 0;
}

}  // namespace bounce::cli
