// bounce_soak: a soak test of a running bounced. N client threads send a seeded random mix of valid
// and invalid requests (and broken frames, and abrupt hang-ups) for a bounded time and check every
// reply; then the driver checks that nothing leaked: the queue drains, every CPU slot is free
// again and, given the daemon's pid, its resident memory is back near what it was after a warm-up.
//
//   bounce_soak HOST:PORT [--seconds S] [--threads N] [--seed S] [--token T] [--pid PID]
//
// Prints one JSON summary line and exits 1 on any violation (each is also printed to stderr).
#include "client/client.hpp"
#include "renderer/image/codec.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace {

using bounce::client::Client;
using bounce::client::Endpoint;
using bounce::protocol::ErrorCode;
using bounce::protocol::MessageType;
using nlohmann::json;
using Clock = std::chrono::steady_clock;
namespace protocol = bounce::protocol;

struct Options {
    Endpoint endpoint;
    std::optional<std::string> token;
    double seconds = 60.0;
    int threads = 4;
    std::uint64_t seed = 0;
    int pid = -1;
};

// What a run counted; each thread keeps its own and they are summed at the end.
struct Tally {
    long requests = 0;
    std::map<std::string, long> replies;  // by kind: ok, frame, pong, hello, or an error code
    long violations = 0;
    long closed_by_daemon = 0;
    long abrupt_disconnects = 0;
    long reconnects = 0;

    void add(const Tally& other) {
        requests += other.requests;
        for (const auto& [kind, count] : other.replies) replies[kind] += count;
        violations += other.violations;
        closed_by_daemon += other.closed_by_daemon;
        abrupt_disconnects += other.abrupt_disconnects;
        reconnects += other.reconnects;
    }
};

std::mutex g_output;

void violation(Tally& tally, const std::string& where, const std::string& what) {
    ++tally.violations;
    std::lock_guard lock(g_output);
    std::cerr << "soak: violation [" << where << "] " << what << "\n";
}

// The replies a request may get: reply kinds (ok, frame, pong, hello, or error codes), and for a
// frame the size asked for.
struct Expect {
    std::string what;
    std::set<std::string> allowed;
    int width = 0;
    int height = 0;
};

struct Request {
    std::uint16_t type = 0;
    json body = json::object();
    Expect expect;
};

// The kind of a reply: its type's name, or for an error its code.
std::string reply_kind(const protocol::Message& reply) {
    if (reply.is(MessageType::error)) return reply.body.value("code", std::string("<no code>"));
    return std::string(protocol::message_type_name(reply.type));
}

// Checks what every reply must be, whatever it answers: an error has a known code and a message;
// a frame decodes to the size it states. Returns the fault, or an empty string.
std::string malformed(const protocol::Message& reply, const Expect& expect) {
    if (reply.is(MessageType::error)) {
        if (!reply.body.contains("code") || !reply.body["code"].is_string()) return "error without a code";
        if (!protocol::error_code_from_name(reply.body["code"].get<std::string>())) {
            return "unknown error code '" + reply.body["code"].get<std::string>() + "'";
        }
        if (!reply.body.contains("message") || !reply.body["message"].is_string() ||
            reply.body["message"].get<std::string>().empty()) {
            return "error without a message";
        }
        return {};
    }
    if (reply.is(MessageType::frame)) {
        try {
            const auto image = bounce::image::decode_image(reply.attachment);
            if (image.width != expect.width || image.height != expect.height) {
                return "frame decodes to " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                       ", asked " + std::to_string(expect.width) + "x" + std::to_string(expect.height);
            }
        } catch (const std::exception& error) {
            return std::string("frame does not decode: ") + error.what();
        }
        if (reply.body.value("width", -1) != expect.width || reply.body.value("height", -1) != expect.height) {
            return "frame body states another size: " + reply.body.dump();
        }
        return {};
    }
    if (!reply.body.is_object()) return "reply body is not an object";
    return {};
}

std::string join(const std::set<std::string>& kinds) {
    std::string text;
    for (const auto& kind : kinds) text += (text.empty() ? "" : ",") + kind;
    return text;
}

// One connection and the requests on it still waiting for their reply (an id sent twice waits
// twice).
class Connection {
public:
    Connection(const Options& options, std::string where, Tally& tally)
        : options_(options), where_(std::move(where)), tally_(tally) {
        connect();
    }

    void connect() {
        client_ = std::make_unique<Client>(options_.endpoint, options_.token);
        pending_.clear();
        log_.clear();
    }
    void reconnect() {
        ++tally_.reconnects;
        connect();
    }
    void hang_up() { client_.reset(); }

    std::uint64_t next_id() { return next_id_++; }

    std::uint64_t send(const Request& request, std::optional<std::uint64_t> id = std::nullopt) {
        const std::uint64_t rid = id.value_or(next_id());
        client_->send_raw(protocol::encode({request.type, rid, request.body, {}}));
        pending_[rid].push_back(request.expect);
        ++tally_.requests;
        return rid;
    }
    void send_bytes(const std::vector<std::uint8_t>& bytes, std::uint64_t id, Expect expect) {
        client_->send_raw(bytes);
        pending_[id].push_back(std::move(expect));
        ++tally_.requests;
    }

    // Reads until every pending request is answered; false when the daemon closed the connection.
    bool drain() {
        while (!pending_.empty()) {
            protocol::Message reply;
            try {
                reply = client_->read();
            } catch (const protocol::ProtocolError& error) {
                violation(tally_, where_, std::string("the daemon sent a broken frame: ") + error.what());
                return false;
            } catch (const std::runtime_error&) {
                return false;
            }
            if (reply.is(MessageType::progress)) continue;
            const std::string kind = reply_kind(reply);
            ++tally_.replies[kind];
            log_[reply.request_id].push_back({kind, reply.body});
            auto it = pending_.find(reply.request_id);
            if (it == pending_.end()) {
                violation(tally_, where_, "a reply (" + kind + ") to id " + std::to_string(reply.request_id) +
                                              " that has no request waiting: " + reply.body.dump());
                continue;
            }
            auto& waiting = it->second;
            auto match = std::find_if(waiting.begin(), waiting.end(),
                                      [&](const Expect& e) { return e.allowed.count(kind) != 0; });
            if (match == waiting.end()) {
                violation(tally_, where_, waiting.front().what + " (id " + std::to_string(reply.request_id) +
                                              "): reply '" + kind + "' is not one of {" + join(waiting.front().allowed) +
                                              "}: " + reply.body.dump().substr(0, 300));
                match = waiting.begin();
            } else if (const auto fault = malformed(reply, *match); !fault.empty()) {
                violation(tally_, where_, match->what + " (id " + std::to_string(reply.request_id) + "): " + fault);
            }
            waiting.erase(match);
            if (waiting.empty()) pending_.erase(it);
        }
        return true;
    }

    // After a broken frame: the daemon must close the connection and send nothing more.
    void expect_closed() {
        try {
            const auto extra = client_->read();
            violation(tally_, where_, "the daemon kept a connection open after a broken frame and sent " +
                                          reply_kind(extra));
        } catch (const std::runtime_error&) {
        }
        ++tally_.closed_by_daemon;
    }

    std::size_t pending() const { return pending_.size(); }
    // The replies since the last connect, by request id: (kind, body).
    const std::map<std::uint64_t, std::vector<std::pair<std::string, json>>>& log() const { return log_; }
    void clear_log() { log_.clear(); }
    const json& hello() const { return client_->hello(); }

private:
    const Options& options_;
    std::string where_;
    Tally& tally_;
    std::unique_ptr<Client> client_;
    std::uint64_t next_id_ = 1000;
    std::map<std::uint64_t, std::vector<Expect>> pending_;
    std::map<std::uint64_t, std::vector<std::pair<std::string, json>>> log_;
};

std::vector<std::uint8_t> frame_bytes(std::uint16_t version, std::uint16_t type, std::uint64_t id,
                                      std::uint32_t json_length, std::uint32_t attachment_length,
                                      const std::string& body = "") {
    std::vector<std::uint8_t> bytes(protocol::kHeaderSize);
    protocol::encode_header({version, type, id, json_length, attachment_length}, bytes.data());
    bytes.insert(bytes.end(), body.begin(), body.end());
    return bytes;
}

// Sends bytes as the first of a new connection, without a hello, and returns what the daemon
// answers until it hangs up.
std::vector<protocol::Message> exchange_before_hello(const Endpoint& endpoint, const std::vector<std::uint8_t>& bytes) {
    namespace asio = boost::asio;
    asio::io_context io;
    asio::ip::tcp::socket socket(io);
    asio::ip::tcp::resolver resolver(io);
    asio::connect(socket, resolver.resolve(endpoint.host, std::to_string(endpoint.port)));
    asio::write(socket, asio::buffer(bytes));
    protocol::FrameDecoder decoder({64u << 20, UINT32_MAX});
    std::vector<protocol::Message> messages;
    std::array<std::uint8_t, 4096> buffer{};
    for (;;) {
        boost::system::error_code error;
        const std::size_t received = socket.read_some(asio::buffer(buffer), error);
        if (error) break;
        decoder.feed(std::span(buffer).first(received));
        while (auto message = decoder.next()) messages.push_back(std::move(*message));
    }
    return messages;
}

const std::vector<std::string> kMethods = {"direct", "vct", "isr"};
const std::vector<std::string> kFormats = {"png", "jpeg", "exr"};
const std::vector<std::string> kObjects = {"short_block", "tall_block"};

// One client thread's random mix. Every choice comes from its generator, seeded from the run's
// seed and the thread's index, so a seed replays the same sequence of requests.
class Worker {
public:
    Worker(const Options& options, int index)
        : options_(options), index_(index), scene_("soak-" + std::to_string(index)),
          rng_(options.seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(index) + 1),
          connection_(options, "thread " + std::to_string(index), tally_) {}

    // Loads the thread's private scene, then sends every kind of request once, so that the caches
    // they fill exist before the baseline of resident memory is taken.
    void warm_up() {
        Request load{static_cast<std::uint16_t>(MessageType::scene_load), {{"name", scene_}, {"builtin", "cornell"}},
                     {"scene.load", {"ok"}}};
        connection_.send(load);
        if (!connection_.drain()) violation(tally_, where(), "the daemon closed the connection during scene.load");
        for (int kind = 0; kind < kRequestKinds; ++kind) batch({make_request(kind)});
        for (const auto& method : kMethods) {
            for (const auto& scene : {std::string("cornell"), scene_}) {
                batch({render(scene, method, "draft", 16, 16, "png")});
            }
        }
        for (int kind = 0; kind < kJunkKinds; ++kind) {
            junk(kind, false);
            junk(kind, true);
        }
        cancel_batch();
        abrupt();
    }

    void run(Clock::time_point until) {
        while (Clock::now() < until) {
            const int roll = pick(0, 99);
            if (roll < 70) {
                std::vector<Request> requests;
                const int count = pick(1, 4);
                for (int i = 0; i < count; ++i) requests.push_back(make_request(pick(0, kRequestKinds - 1)));
                batch(requests, pick(0, 19) == 0);
            } else if (roll < 82) {
                cancel_batch();
            } else if (roll < 94) {
                junk(pick(0, kJunkKinds - 1), pick(0, 2) == 0);
            } else {
                abrupt();
            }
        }
    }

    const Tally& tally() const { return tally_; }
    // A failure that ends the thread's run (the daemon gone, say).
    void fail(const std::string& what) { violation(tally_, where(), what); }

private:
    static constexpr int kRequestKinds = 24;
    static constexpr int kJunkKinds = 6;

    int pick(int low, int high) { return std::uniform_int_distribution<int>(low, high)(rng_); }
    double uniform(double low, double high) { return std::uniform_real_distribution<double>(low, high)(rng_); }
    template <typename T>
    const T& one_of(const std::vector<T>& values) {
        return values[static_cast<std::size_t>(pick(0, static_cast<int>(values.size()) - 1))];
    }
    std::string where() const { return "thread " + std::to_string(index_); }

    static Request make(MessageType type, json body, std::string what, std::set<std::string> allowed) {
        return {static_cast<std::uint16_t>(type), std::move(body), {std::move(what), std::move(allowed)}};
    }
    // Requests that run on the render thread may also find the shared queue full.
    static Request queued(MessageType type, json body, std::string what, std::set<std::string> allowed) {
        allowed.insert("busy");
        return make(type, std::move(body), std::move(what), std::move(allowed));
    }

    Request render(const std::string& scene, const std::string& method, const std::string& preset, int width, int height,
                   const std::string& format) {
        json body = {{"scene", scene}, {"method", method}, {"preset", preset}, {"width", width},
                     {"height", height}, {"format", format}};
        if (method == "reference") body["knobs"] = {{"spp", pick(1, 2)}};
        Request request = queued(MessageType::render, body, "render " + method + " " + std::to_string(width) + "x" +
                                                                 std::to_string(height) + " of " + scene, {"frame"});
        request.expect.width = width;
        request.expect.height = height;
        return request;
    }

    Request valid_render() {
        const std::string scene = pick(0, 1) ? scene_ : "cornell";
        const std::string format = one_of(kFormats);
        const int width = pick(8, 32);
        const int height = pick(8, 32);
        if (pick(0, 3) == 0) return render(scene, "reference", "medium", width, height, format);
        return render(scene, one_of(kMethods), "draft", width, height, format);
    }

    json vec3(double low, double high) { return {uniform(low, high), uniform(low, high), uniform(low, high)}; }

    Request make_request(int kind) {
        switch (kind) {
            // Valid.
            case 0:
            case 1:
            case 2: return valid_render();
            case 3: return queued(MessageType::scene_describe, {{"name", pick(0, 1) ? scene_ : "cornell"}}, "scene.describe", {"ok"});
            case 4: return queued(MessageType::scene_list, json::object(), "scene.list", {"ok"});
            case 5:
                return queued(MessageType::object_set_transform,
                              {{"scene", scene_}, {"object", one_of(kObjects)}, {"translation", vec3(-0.05, 0.05)},
                               {"rotation_deg", {0.0, uniform(-20, 20), 0.0}}},
                              "object.set_transform", {"ok"});
            case 6:
                return queued(MessageType::light_set,
                              {{"scene", scene_}, {"light", "soak"}, {"type", "point"},
                               {"position", {uniform(-0.3, 0.3), uniform(0.2, 0.5), uniform(-0.3, 0.3)}},
                               {"color", {1.0, 0.9, 0.8}}, {"intensity", uniform(0.1, 2.0)}},
                              "light.set", {"ok"});
            case 7:
                return queued(MessageType::camera_set,
                              {{"scene", scene_}, {"position", {uniform(-0.1, 0.1), uniform(0.2, 0.3), uniform(1.2, 1.5)}},
                               {"look_at", {0.0, 0.25, 0.0}}, {"fov_deg", uniform(30, 60)}},
                              "camera.set", {"ok"});
            case 8: return queued(MessageType::stats, json::object(), "stats", {"ok"});
            case 9: return make(MessageType::ping, json::object(), "ping", {"pong"});
            case 10:  // an id this connection never used: nothing to cancel
                return make(MessageType::cancel, {{"id", 1}}, "cancel of an unknown id", {"ok"});
            // Invalid.
            case 11:
                // Between cancel (8) and scene.load (16), or past stream.update (29), the highest the
                // protocol defines.
                return make(static_cast<MessageType>(pick(0, 1) ? pick(9, 15)
                                                                : pick(static_cast<int>(MessageType::stream_update) + 1, 65535)),
                            {{"x", 1}},
                            "unknown message type", {"unsupported"});
            case 12:
                return make(MessageType::render, {{"scene", "cornell"}, {"width", 0}, {"height", 8}}, "render width 0",
                            {"bad_request"});
            case 13:
                return make(MessageType::render, {{"scene", "cornell"}, {"width", "wide"}}, "render width of the wrong type",
                            {"bad_request"});
            case 14:
                return make(MessageType::object_set_transform,
                            {{"scene", scene_}, {"object", one_of(kObjects)}, {"translation", {1e39, 0, 0}}},
                            "translation past float range", {"bad_request"});
            case 15:
                return make(MessageType::render, {{"scene", "cornell"}, {"method", "photon-soup"}}, "unknown method",
                            {"bad_request"});
            case 16:
                return make(MessageType::render, {{"scene", "cornell"}, {"method", "direct"}, {"knobs", {{"warp_factor", 9}}}},
                            "unknown knob", {"bad_request"});
            case 17:
                return queued(MessageType::render, {{"scene", "no-such-scene"}, {"width", 8}, {"height", 8}},
                              "unknown scene", {"not_found"});
            case 18:
                return queued(MessageType::object_set_transform, {{"scene", scene_}, {"object", "ghost"}, {"scale", 2}},
                              "unknown object", {"not_found"});
            case 19: return make(MessageType::hello, {{"protocol", "1"}}, "hello with protocol \"1\"", {"bad_request"});
            case 20:
                return make(MessageType::light_set, {{"scene", scene_}, {"light", "soak"}, {"intensity", -1}},
                            "negative intensity", {"bad_request"});
            case 21:
                return make(MessageType::render, {{"scene", "cornell"}, {"width", 16384}, {"height", 16384}},
                            "render past max_pixels", {"too_large"});
            case 22: return make(MessageType::ok, json::object(), "a reply sent as a request", {"unsupported"});
            default:
                return make(MessageType::camera_set, {{"scene", scene_}, {"fov_deg", 500}}, "fov out of range", {"bad_request"});
        }
    }

    // Sends the requests pipelined (with_duplicate: one id twice) and waits for every reply.
    void batch(const std::vector<Request>& requests, bool with_duplicate = false) {
        try {
            std::uint64_t last = 0;
            for (const auto& request : requests) last = connection_.send(request);
            if (with_duplicate) {
                // The second copy is refused while the first is in flight, or answered like it.
                Request again = requests.back();
                again.expect.allowed.insert("bad_request");
                again.expect.what += " (duplicate id)";
                connection_.send(again, last);
            }
        } catch (const std::runtime_error& error) {
            violation(tally_, where(), std::string("send failed: ") + error.what());
        }
        finish_batch();
    }

    void finish_batch() {
        if (!connection_.drain()) {
            violation(tally_, where(), "the daemon closed the connection with " + std::to_string(connection_.pending()) +
                                           " requests unanswered");
            connection_.reconnect();
        }
        connection_.clear_log();
    }

    // A render and a cancel of it: the cancel answers ok {"cancelled": bool}, the render a frame,
    // or `cancelled` only when the cancel found it.
    void cancel_batch() {
        Request target = valid_render();
        target.expect.allowed.insert("cancelled");
        try {
            const std::uint64_t id = connection_.send(target);
            if (pick(0, 1)) std::this_thread::sleep_for(std::chrono::milliseconds(pick(1, 30)));
            const std::uint64_t cancel = connection_.send(make(MessageType::cancel, {{"id", id}}, "cancel", {"ok"}));
            if (!connection_.drain()) {
                violation(tally_, where(), "the daemon closed the connection during a cancel");
                connection_.reconnect();
                return;
            }
            const auto& log = connection_.log();
            const auto cancel_reply = log.find(cancel);
            const auto target_reply = log.find(id);
            if (cancel_reply == log.end() || target_reply == log.end()) return;  // reported by drain
            const json& body = cancel_reply->second.front().second;
            if (!body.contains("cancelled") || !body["cancelled"].is_boolean()) {
                violation(tally_, where(), "cancel reply without a boolean 'cancelled': " + body.dump());
            } else if (target_reply->second.front().first == "cancelled" && !body["cancelled"].get<bool>()) {
                violation(tally_, where(), "a request was answered 'cancelled' by a cancel that said it found nothing");
            }
        } catch (const std::runtime_error& error) {
            violation(tally_, where(), std::string("send failed: ") + error.what());
        }
        connection_.clear_log();
    }

    // A broken frame on a quiet connection, or as the first bytes of a new one that never said
    // hello: one error with its code, then the daemon hangs up.
    void junk(int kind, bool before_hello) {
        const std::uint64_t id = connection_.next_id();
        std::vector<std::uint8_t> bytes;
        std::string code = "broken_frame";
        std::uint64_t reply_id = id;
        const auto render = static_cast<std::uint16_t>(MessageType::render);
        switch (kind) {
            case 0: {  // random bytes: without the magic, no id can be read
                bytes.push_back(static_cast<std::uint8_t>(pick(0, 0x41)));  // never 'B'
                const int length = pick(24, 300);
                while (static_cast<int>(bytes.size()) < length) bytes.push_back(static_cast<std::uint8_t>(pick(0, 255)));
                reply_id = 0;
                break;
            }
            case 1: {  // JSON that does not parse, or is not one object
                static const std::vector<std::string> bodies = {"{nope", "{\"scene\": ", "[1, 2, 3]", "\"text\"",
                                                                "{\"a\": \"\xff\xfe\"}", std::string(100, '[')};
                const std::string& body = one_of(bodies);
                bytes = frame_bytes(1, render, id, static_cast<std::uint32_t>(body.size()), 0, body);
                break;
            }
            case 2: {  // a JSON body past the daemon's limit
                const auto limit = connection_.hello()["limits"].value("max_json_bytes", 1u << 20);
                bytes = frame_bytes(1, render, id, limit + 1 + static_cast<std::uint32_t>(pick(0, 1000)), 0);
                code = "too_large";
                break;
            }
            case 3: {  // an attachment past the daemon's limit
                const auto limit = connection_.hello()["limits"].value("max_attachment_bytes", 256u << 20);
                bytes = frame_bytes(1, render, id, 2, limit + 1, "{}");
                code = "too_large";
                break;
            }
            case 4:
                bytes = frame_bytes(static_cast<std::uint16_t>(pick(2, 9)), render, id, 2, 0, "{}");
                code = "version_mismatch";
                break;
            default: {  // a valid header, then junk where the JSON should be
                bytes = frame_bytes(1, render, id, 64, 0);
                for (int i = 0; i < 64; ++i) bytes.push_back(static_cast<std::uint8_t>(pick(0x80, 0xff)));
                break;
            }
        }
        const Expect expect{"broken frame (" + code + ")", {code}};
        if (before_hello) {
            junk_before_hello(bytes, reply_id, expect);
            return;
        }
        try {
            connection_.send_bytes(bytes, reply_id, expect);
            if (connection_.drain()) {
                connection_.expect_closed();
            } else {
                violation(tally_, where(), "the daemon hung up on a broken frame (" + code + ") without an error reply");
            }
        } catch (const std::runtime_error& error) {
            violation(tally_, where(), std::string("send failed: ") + error.what());
        }
        connection_.reconnect();
    }

    void junk_before_hello(const std::vector<std::uint8_t>& bytes, std::uint64_t reply_id, const Expect& expect) {
        ++tally_.requests;
        try {
            const auto replies = exchange_before_hello(options_.endpoint, bytes);
            ++tally_.closed_by_daemon;
            for (const auto& reply : replies) ++tally_.replies[reply_kind(reply)];
            if (replies.size() != 1) {
                violation(tally_, where(), expect.what + " before hello: " + std::to_string(replies.size()) +
                                               " replies before the daemon hung up, expected 1");
                return;
            }
            const auto& reply = replies.front();
            if (!expect.allowed.count(reply_kind(reply)) || reply.request_id != reply_id) {
                violation(tally_, where(), expect.what + " before hello: reply '" + reply_kind(reply) + "' to id " +
                                               std::to_string(reply.request_id) + ", expected id " + std::to_string(reply_id));
            } else if (const auto fault = malformed(reply, expect); !fault.empty()) {
                violation(tally_, where(), expect.what + " before hello: " + fault);
            }
        } catch (const std::exception& error) {
            violation(tally_, where(), expect.what + " before hello: " + error.what());
        }
    }

    // Requests in flight, then a hang-up without reading: the daemon cancels them and goes on.
    void abrupt() {
        try {
            const int count = pick(1, 3);
            for (int i = 0; i < count; ++i) {
                connection_.send(pick(0, 1) ? render("cornell", "reference", "medium", 32, 32, "png") : valid_render());
            }
            if (pick(0, 1)) std::this_thread::sleep_for(std::chrono::milliseconds(pick(1, 40)));
        } catch (const std::runtime_error& error) {
            violation(tally_, where(), std::string("send failed: ") + error.what());
        }
        connection_.hang_up();
        ++tally_.abrupt_disconnects;
        connection_.reconnect();
    }

    const Options& options_;
    int index_;
    std::string scene_;
    std::mt19937_64 rng_;
    Tally tally_;
    Connection connection_;
};

// VmRSS of a process in kB, or -1 when it cannot be read.
long resident_kb(int pid) {
    std::ifstream status("/proc/" + std::to_string(pid) + "/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("VmRSS:", 0) == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
    }
    return -1;
}

std::uint64_t queue_depth(Client& client) {
    return client.request(MessageType::stats).body.value("queue_depth", std::uint64_t{999999});
}

// After the mix: the render queue drains, and five reference renders all get frames, the first
// four at once, so every one of the daemon's four CPU slots must have been given back. A trace
// cancelled by a hang-up may still be stopping when this starts, so `busy` is retried for a few
// seconds; a slot that leaked stays busy for good.
void check_nothing_leaked(const Options& options, Tally& tally, json& summary) {
    Client client(options.endpoint, options.token);
    std::uint64_t depth = queue_depth(client);
    for (int i = 0; i < 50 && depth != 0; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        depth = queue_depth(client);
    }
    summary["queue_depth"] = depth;
    if (depth != 0) violation(tally, "final", "queue_depth is " + std::to_string(depth) + " after 10 s of quiet");

    Connection connection(options, "final", tally);
    const json body = {{"scene", "cornell"}, {"method", "reference"}, {"width", 16}, {"height", 16}, {"knobs", {{"spp", 1}}}};
    const Request reference{static_cast<std::uint16_t>(MessageType::render), body,
                            {"final reference render", {"frame", "busy"}, 16, 16}};
    // Sends `count` at once; true when all of them got frames.
    auto all_frames = [&](int count) {
        connection.clear_log();
        for (int i = 0; i < count; ++i) connection.send(reference);
        if (!connection.drain()) {
            violation(tally, "final", "the daemon closed the connection during the final renders");
            connection.reconnect();
            return false;
        }
        int frames = 0;
        for (const auto& [id, replies] : connection.log()) {
            for (const auto& reply : replies) frames += reply.first == "frame" ? 1 : 0;
        }
        return frames == count;
    };
    int attempts = 0;
    bool ok = false;
    while (!ok && attempts < 10) {
        if (attempts++ > 0) std::this_thread::sleep_for(std::chrono::milliseconds(500));
        ok = all_frames(4) && all_frames(1);
    }
    summary["final_reference_attempts"] = attempts;
    if (!ok) violation(tally, "final", "5 reference renders (4 at once, then 1) still got busy after 10 attempts: a CPU slot leaked");
}

std::optional<Options> parse(int argc, char** argv) {
    if (argc < 2) return std::nullopt;
    Options options;
    options.endpoint = Endpoint::parse(argv[1]);
    options.seed = std::random_device{}();
    for (int i = 2; i < argc; i += 2) {
        const std::string flag = argv[i];
        if (i + 1 >= argc) return std::nullopt;
        const std::string value = argv[i + 1];
        if (flag == "--seconds") options.seconds = std::stod(value);
        else if (flag == "--threads") options.threads = std::stoi(value);
        else if (flag == "--seed") options.seed = std::stoull(value);
        else if (flag == "--token") options.token = value;
        else if (flag == "--pid") options.pid = std::stoi(value);
        else return std::nullopt;
    }
    if (!(options.seconds > 0 && options.seconds <= 86400) || options.threads < 1 || options.threads > 64) {
        return std::nullopt;
    }
    return options;
}

// Resident memory may end this much above the baseline: 10%, plus an absolute allowance for what
// a long-lived process keeps without leaking: glibc's per-thread malloc arenas (the daemon's
// network, encode, CPU and TBB threads) keep freed chunks instead of returning them to the kernel,
// and fragmentation after thousands of differently sized frames and scene snapshots moves their
// high-water marks by a few MiB. A leak of a frame, a snapshot or a session per request passes
// this allowance within seconds of a 60 s run. (On llvmpipe the daemon holds about 1.3 GB after
// the warm-up and ends a 60 s run 3 to 5% above it.)
constexpr double kRssGrowth = 0.10;
constexpr long kRssAllowanceKb = 32 * 1024;

}  // namespace

int main(int argc, char** argv) {
    std::optional<Options> parsed;
    try {
        parsed = parse(argc, argv);
    } catch (const std::exception&) {
    }
    if (!parsed) {
        std::cerr << "usage: bounce_soak HOST:PORT [--seconds S] [--threads N] [--seed S] [--token T] [--pid PID]\n";
        return 2;
    }
    const Options options = *parsed;
    std::cout << "soak: seed " << options.seed << ", " << options.threads << " threads, " << options.seconds << " s"
              << std::endl;

    // Bounded whatever the daemon does: a reply that never comes ends the run as a failure.
    const auto hard_limit = std::chrono::duration<double>(options.seconds + 120.0);
    std::thread([hard_limit] {
        std::this_thread::sleep_for(hard_limit);
        std::lock_guard lock(g_output);
        std::cerr << "soak: violation: still running " << hard_limit.count() << " s after the start; a reply never came"
                  << std::endl;
        std::_Exit(1);
    }).detach();

    Tally total;
    json summary = {{"seed", options.seed}, {"threads", options.threads}, {"seconds", options.seconds}};
    try {
        std::vector<std::unique_ptr<Worker>> workers;
        for (int i = 0; i < options.threads; ++i) workers.push_back(std::make_unique<Worker>(options, i));
        auto run_all = [&](auto&& phase) {
            std::vector<std::thread> threads;
            for (auto& worker : workers) {
                threads.emplace_back([&worker, &phase] {
                    try {
                        phase(*worker);
                    } catch (const std::exception& error) {
                        worker->fail(std::string("the thread stopped: ") + error.what());
                    }
                });
            }
            for (auto& thread : threads) thread.join();
        };
        run_all([](Worker& worker) { worker.warm_up(); });
        long baseline_kb = -1;
        if (options.pid > 0) {
            std::this_thread::sleep_for(std::chrono::seconds(1));
            baseline_kb = resident_kb(options.pid);
        }
        const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(options.seconds));
        run_all([until](Worker& worker) { worker.run(until); });
        for (const auto& worker : workers) total.add(worker->tally());
        check_nothing_leaked(options, total, summary);
        if (options.pid > 0) {
            std::this_thread::sleep_for(std::chrono::seconds(1));
            const long final_kb = resident_kb(options.pid);
            const long limit_kb = static_cast<long>(static_cast<double>(baseline_kb) * (1.0 + kRssGrowth)) + kRssAllowanceKb;
            summary["rss_kb"] = {{"baseline", baseline_kb}, {"final", final_kb}, {"limit", limit_kb}};
            if (baseline_kb <= 0 || final_kb <= 0) {
                violation(total, "final", "cannot read VmRSS of pid " + std::to_string(options.pid));
            } else if (final_kb > limit_kb) {
                violation(total, "final", "resident memory grew from " + std::to_string(baseline_kb) + " kB to " +
                                              std::to_string(final_kb) + " kB, past the limit of " +
                                              std::to_string(limit_kb) + " kB");
            }
        }
    } catch (const std::exception& error) {
        violation(total, "driver", error.what());
    }
    summary["requests"] = total.requests;
    summary["replies"] = total.replies;
    summary["closed_by_daemon"] = total.closed_by_daemon;
    summary["abrupt_disconnects"] = total.abrupt_disconnects;
    summary["reconnects"] = total.reconnects;
    summary["violations"] = total.violations;
    {
        std::lock_guard lock(g_output);
        std::cout << summary.dump() << std::endl;
    }
    return total.violations == 0 ? 0 : 1;
}
