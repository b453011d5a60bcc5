// bounced against hostile and careless clients: connections that never authenticate, bodies
// announced but not sent, budgets, shutdown under load, what errors reveal.
#include "daemon_support.hpp"
#include "support/hostile_gltf.hpp"

#include <boost/asio.hpp>

#include <array>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <thread>
#include <unistd.h>

namespace bounce::test {
namespace {

// A plain TCP connection that speaks raw frames, for clients that misbehave.
struct RawConnection {
    boost::asio::io_context io;
    boost::asio::ip::tcp::socket socket{io};
    explicit RawConnection(const client::Endpoint& endpoint) {
        socket.connect({boost::asio::ip::make_address(endpoint.host), endpoint.port});
    }
    void send(const std::vector<std::uint8_t>& bytes) { boost::asio::write(socket, boost::asio::buffer(bytes)); }
    // True when the daemon closed the connection (reads end) within `limit`.
    bool closed_by_daemon(std::chrono::milliseconds limit) {
        socket.non_blocking(true);
        const auto deadline = std::chrono::steady_clock::now() + limit;
        std::array<std::uint8_t, 4096> scratch{};
        while (std::chrono::steady_clock::now() < deadline) {
            boost::system::error_code error;
            socket.read_some(boost::asio::buffer(scratch), error);
            if (error == boost::asio::error::eof || error == boost::asio::error::connection_reset) return true;
            if (error && error != boost::asio::error::would_block) return true;
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        return false;
    }
};

// Before authentication: frames hold no more than a hello; connections that never authenticate
// are closed at the auth deadline and have their own cap, the oldest making way, so a flood of
// them that only ping cannot lock out a client with the token.
TEST(DaemonHardening, UnauthenticatedConnectionsCannotLockOutAClient) {
    const auto token_file = std::filesystem::temp_directory_path() / ("bounce-token-" + std::to_string(::getpid()));
    std::ofstream(token_file) << "correct-horse-battery-staple\n";
    DaemonProcess daemon({"--token-file", token_file.string(), "--max-unauthenticated", "4", "--auth-timeout-ms", "1500"});
    std::vector<std::unique_ptr<RawConnection>> flood;
    for (int i = 0; i < 20; ++i) {
        flood.push_back(std::make_unique<RawConnection>(daemon.endpoint()));
        flood.back()->send(frame_bytes(MessageType::ping, 1, json::object()));
    }
    Client client(daemon.endpoint(), "correct-horse-battery-staple");
    EXPECT_EQ(render(client, {{"scene", "cornell"}, {"width", 16}, {"height", 16}}).width, 16);
    // The first 16 of the flood were closed to make room (cap 4).
    for (int i = 0; i < 16; ++i) EXPECT_TRUE(flood[i]->closed_by_daemon(std::chrono::milliseconds(2000))) << i;
    // The newest ones are closed at the auth deadline, pings notwithstanding.
    flood[19]->send(frame_bytes(MessageType::ping, 2, json::object()));
    EXPECT_TRUE(flood[19]->closed_by_daemon(std::chrono::milliseconds(5000)));
    // A frame larger than a hello before authentication: too_large, and the connection closes.
    RawConnection big(daemon.endpoint());
    big.send(frame_bytes(MessageType::scene_list, 3, {{"padding", std::string(5000, 'x')}}));
    EXPECT_TRUE(big.closed_by_daemon(std::chrono::milliseconds(2000)));
    std::filesystem::remove(token_file);
}

// Memory follows arrival: headers announcing 200 MiB bodies that never come cost the daemon
// nothing like it, and an upload past --max-inflight-bytes is refused with resource_exhausted
// while other clients are served.
TEST(DaemonHardening, AnnouncedBodiesCostNothingUntilTheyArrive) {
    DaemonProcess daemon({"--max-inflight-bytes", "4194304"});
    const auto baseline = cornell_frame(daemon.endpoint());
    const long before_kb = daemon.resident_kb();
    std::vector<std::unique_ptr<RawConnection>> announcers;
    for (int i = 0; i < 8; ++i) {
        announcers.push_back(std::make_unique<RawConnection>(daemon.endpoint()));
        protocol::Header header;
        header.type = static_cast<std::uint16_t>(MessageType::scene_load);
        header.request_id = 1;
        header.json_length = 2;
        header.attachment_length = 200u << 20;
        const auto bytes = protocol::encode_header(header);
        announcers.back()->send(std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
        announcers.back()->send({'{', '}'});
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    // Each announcer holds at most its first 256 KiB chunk: 2 MiB in all, against the 1.6 GiB
    // announced; 64 MiB leaves room for the allocator's own bookkeeping.
    EXPECT_LT(daemon.resident_kb() - before_kb, 64 * 1024);
    // 8 x 256 KiB of the 4 MiB budget are held; a 6 MiB upload cannot fit.
    Client client(daemon.endpoint());
    expect_error([&] { client.request(MessageType::scene_load, {{"name", "big"}}, std::vector<std::uint8_t>(6u << 20, 0)); },
                 ErrorCode::resource_exhausted);
    expect_still_serving(daemon.endpoint(), baseline);
}

// A second SIGTERM exits at once; after the first, in-flight work is cancelled at the drain
// deadline, an hours-long reference trace included, and the daemon exits 0.
TEST(DaemonHardening, DrainDeadlineCancelsRunningWorkAndASecondSignalExitsAtOnce) {
    const json hours = {{"scene", "cornell"}, {"method", "reference"}, {"width", 128}, {"height", 128},
                        {"knobs", {{"spp", 65536}}}};
    {
        DaemonProcess daemon({"--drain-seconds", "1"});
        Client client(daemon.endpoint());
        client.send_raw(frame_bytes(MessageType::render, 5, hours));
        std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the trace is running
        daemon.send_signal(SIGTERM);
        // Drained for one second, then cancelled: exit 0, long before the SIGKILL at 15 s.
        EXPECT_EQ(daemon.wait_for_exit(std::chrono::seconds(15)), 0);
    }
    {
        DaemonProcess daemon({"--drain-seconds", "600"});
        Client client(daemon.endpoint());
        client.send_raw(frame_bytes(MessageType::render, 5, hours));
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        daemon.send_signal(SIGTERM);
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        daemon.send_signal(SIGTERM);
        EXPECT_EQ(daemon.wait_for_exit(std::chrono::seconds(15)), 128 + SIGTERM);
    }
}

// The import budget through the daemon: a scene past --max-scene-bytes is resource_exhausted
// naming its largest part, scenes past --max-scenes are refused, and serving goes on.
TEST(DaemonHardening, SceneBudgetsAreResourceExhausted) {
    DaemonProcess daemon({"--max-scene-bytes", "100000", "--max-scenes", "2"});
    const auto baseline = cornell_frame(daemon.endpoint());
    Client client(daemon.endpoint());
    std::ifstream in(kModels + "/BoxTextured-glTF-Binary/BoxTextured.glb", std::ios::binary);
    const std::vector<std::uint8_t> glb{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    ASSERT_FALSE(glb.empty());
    try {
        client.request(MessageType::scene_load, {{"name", "box"}}, glb);
        ADD_FAILURE() << "expected resource_exhausted";
    } catch (const ServerError& error) {
        EXPECT_EQ(error.code(), ErrorCode::resource_exhausted) << error.what();
        EXPECT_NE(std::string(error.what()).find("image 0"), std::string::npos) << error.what();
    }
    client.request(MessageType::scene_load, {{"name", "second"}, {"builtin", "cornell"}});  // cornell + second
    expect_error([&] { client.request(MessageType::scene_load, {{"name", "third"}, {"builtin", "cornell"}}); },
                 ErrorCode::resource_exhausted, "name");
    client.request(MessageType::scene_load, {{"name", "second"}, {"builtin", "cornell_blob"}});  // a replacement fits
    expect_still_serving(daemon.endpoint(), baseline);
}

// 16 point lights with 8192^2 shadow maps would take 24 GiB: under a 256 MiB GPU budget the
// frame is refused before anything is allocated, the refusal names the shadow maps and a size that
// fits, that size renders, and the daemon's peak resident memory stays within the budget of where
// it started (llvmpipe allocates GPU memory on the host).
TEST(DaemonHardening, GpuMemoryBudgetRefusesFramesThatWouldPassIt) {
    DaemonProcess daemon({"--gpu-memory-budget", "256M"});
    const auto baseline = cornell_frame(daemon.endpoint());
    const long started_kb = daemon.peak_resident_kb();
    Client client(daemon.endpoint());
    client.request(MessageType::scene_load, {{"name", "lights"}, {"builtin", "cornell"}});
    for (int i = 0; i < 15; ++i) {
        client.request(MessageType::light_set, {{"scene", "lights"}, {"light", "extra" + std::to_string(i)}, {"type", "point"},
                                                {"position", {0.1 * i - 0.7, 1.5, 0.0}}, {"intensity", 0.1}});
    }
    json request = {{"scene", "lights"}, {"method", "direct"}, {"width", 64}, {"height", 64},
                    {"knobs", {{"shadow_map_size", 8192}}}};
    std::string message;
    try {
        client.request(MessageType::render, request);
        ADD_FAILURE() << "a 24 GiB frame was rendered under a 256 MiB budget";
    } catch (const ServerError& error) {
        EXPECT_EQ(error.code(), ErrorCode::resource_exhausted) << error.what();
        message = error.what();
    }
    EXPECT_NE(message.find("'shadow_maps'"), std::string::npos) << message;
    std::smatch match;
    ASSERT_TRUE(std::regex_search(message, match, std::regex("shadow_map_size=([0-9]+) would fit"))) << message;
    request["knobs"]["shadow_map_size"] = std::stoi(match[1]);
    const auto frame = render(client, request);
    EXPECT_GT(rgb_sum(frame), 0.0);
    const json stats = client.request(MessageType::stats, json::object()).body;
    EXPECT_EQ(stats.at("gpu_memory").at("budget_bytes"), 256u << 20) << stats.dump();
    EXPECT_LE(stats.at("gpu_memory").at("resident_bytes").get<std::uint64_t>(), 256u << 20) << stats.dump();
    EXPECT_LT(daemon.peak_resident_kb() - started_kb, 256 * 1024 + 64 * 1024)
        << "peak resident memory past the budget (with 64 MiB for the frame's readback and encoding)";
    expect_still_serving(daemon.endpoint(), baseline);
}

// The daemon's CPU use over one second, starting one second from now: a daemon with nothing to do
// measures about 0.01 s; a bake or a trace that kept running would measure close to the core count.
double cpu_seconds_a_second_later(const DaemonProcess& daemon) {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    const double before = daemon.cpu_seconds();
    std::this_thread::sleep_for(std::chrono::seconds(1));
    return daemon.cpu_seconds() - before;
}

// The next message for request `id`, a progress event included.
protocol::Message next_for(Client& client, std::uint64_t id) {
    for (;;) {
        auto message = client.read();
        if (message.request_id == id) return message;
    }
}

// A cssm frame whose bake would take hours (atlas_resolution 1024: about a million cube maps). The
// bake runs off the render thread and reports progress; another client's frame is served while it
// runs; a cancel, a timeout_ms and a disconnect each stop it, and the daemon is idle a second later.
TEST(DaemonHardening, LongBakesHoldNoOtherFramesAndStopWhenNoLongerWanted) {
    DaemonProcess daemon;
    const auto baseline = cornell_frame(daemon.endpoint());
    const json hours = {{"scene", "cornell"}, {"method", "cssm"}, {"width", 32}, {"height", 32},
                        {"knobs", {{"atlas_resolution", 1024}, {"face_size", 32}}}};
    {
        Client baker(daemon.endpoint());
        baker.send_raw(protocol::encode({static_cast<std::uint16_t>(MessageType::render), 200, hours, {}}));
        const auto event = next_for(baker, 200);
        ASSERT_EQ(event.type, static_cast<std::uint16_t>(MessageType::progress)) << event.body.dump();
        EXPECT_LT(event.body.at("fraction").get<double>(), 0.01);
        expect_still_serving(daemon.endpoint(), baseline);  // while the bake runs
        baker.send_raw(protocol::encode({static_cast<std::uint16_t>(MessageType::cancel), 201, {{"id", 200}}, {}}));
        const auto reply = reply_to(baker, 200);
        ASSERT_EQ(reply.type, static_cast<std::uint16_t>(MessageType::error));
        EXPECT_EQ(reply.body.at("code").get<std::string>(), "cancelled") << reply.body.dump();
        EXPECT_LT(cpu_seconds_a_second_later(daemon), 0.25) << "the cancelled bake kept running";

        json timed = hours;
        timed["timeout_ms"] = 1500;
        baker.send_raw(protocol::encode({static_cast<std::uint16_t>(MessageType::render), 202, timed, {}}));
        const auto timeout = reply_to(baker, 202);
        ASSERT_EQ(timeout.type, static_cast<std::uint16_t>(MessageType::error));
        EXPECT_EQ(timeout.body.at("code").get<std::string>(), "timeout") << timeout.body.dump();
        EXPECT_LT(cpu_seconds_a_second_later(daemon), 0.25) << "the timed-out bake kept running";

        baker.send_raw(protocol::encode({static_cast<std::uint16_t>(MessageType::render), 203, hours, {}}));
        ASSERT_EQ(next_for(baker, 203).type, static_cast<std::uint16_t>(MessageType::progress));
    }  // the client disconnects mid-bake
    EXPECT_LT(cpu_seconds_a_second_later(daemon), 0.25) << "the abandoned bake kept running";
    expect_still_serving(daemon.endpoint(), baseline);
}

// The three hostile uploads of the attack table, against a real daemon with its default budgets:
// JSON nested 300,000 deep (a stack overflow in a recursive parser), a 300-byte GLB whose accessor
// without a bufferView decodes to 44 GiB, and 32 images sharing one PNG that declares 16384^2. Each
// is refused naming its fault, the daemon's peak resident memory rises by less than 64 MiB (the
// uploads themselves are under 1 MiB; the attacks took 15 GiB), and it keeps serving.
TEST(DaemonHardening, HostileUploadsAreRefusedWithoutTheirMemory) {
    DaemonProcess daemon;
    const auto baseline = cornell_frame(daemon.endpoint());
    const long started_kb = daemon.peak_resident_kb();
    Client client(daemon.endpoint());
    const auto refused = [&](const std::vector<std::uint8_t>& glb, ErrorCode code, const std::string& says) {
        try {
            client.request(MessageType::scene_load, {{"name", "hostile"}}, glb);
            ADD_FAILURE() << "loaded: " << says;
        } catch (const ServerError& error) {
            EXPECT_EQ(error.code(), code) << error.what();
            EXPECT_NE(std::string(error.what()).find(says), std::string::npos) << error.what();
        }
    };
    refused(hostile::make_glb(hostile::deeply_nested(300000)), ErrorCode::bad_request, "more than 128 levels deep");
    refused(hostile::make_glb(R"({"asset":{"version":"2.0"},"accessors":[{"componentType":5126,"count":268435455,)"
                              R"("type":"VEC3"}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}},)"
                              R"({"attributes":{"POSITION":0}},{"attributes":{"POSITION":0}},{"attributes":{"POSITION":0}}]}]})"),
            ErrorCode::resource_exhausted, "accessor 0 (POSITION of 4 primitives)");
    refused(hostile::glb_with_images(hostile::png_declaring(16384), 32), ErrorCode::resource_exhausted,
            "image 0 (16384x16384");
    EXPECT_LT(daemon.peak_resident_kb() - started_kb, 64 * 1024);
    expect_still_serving(daemon.endpoint(), baseline);
}

// One HTTP/1.1 GET on the ops port; the whole response (the daemon closes after it).
std::string http_get(std::uint16_t port, const std::string& target, const std::string& bearer = "") {
    RawConnection connection({"127.0.0.1", port});
    const std::string request = "GET " + target + " HTTP/1.1\r\nHost: localhost\r\n" +
                                (bearer.empty() ? "" : "Authorization: Bearer " + bearer + "\r\n") + "\r\n";
    connection.send(std::vector<std::uint8_t>(request.begin(), request.end()));
    std::string response;
    std::array<char, 4096> buffer{};
    boost::system::error_code error;
    for (;;) {
        const std::size_t n = connection.socket.read_some(boost::asio::buffer(buffer), error);
        response.append(buffer.data(), n);
        if (error) break;
    }
    return response;
}

// The ops listener: a scene name chosen to forge a metric line shows up escaped; connections past
// the cap are closed at once while the ones held wait for their timeout; off loopback without a
// token the daemon refuses to start (nothing is bound).
TEST(DaemonHardening, OpsHttpEscapesLabelsCapsConnectionsAndNeedsATokenOffLoopback) {
    DaemonProcess daemon({"--metrics-listen", "127.0.0.1:0"});
    ASSERT_GT(daemon.ops_port(), 0);
    Client client(daemon.endpoint());
    const std::string evil = "evil\"} 1\nbounce_fake_total{a=\"";
    client.request(MessageType::scene_load, {{"name", evil}, {"builtin", "cornell"}});
    render(client, {{"scene", evil}, {"width", 8}, {"height", 8}});  // its resident bytes become a metric
    const std::string metrics = http_get(daemon.ops_port(), "/metrics");
    EXPECT_EQ(metrics.rfind("HTTP/1.1 200", 0), 0u) << metrics.substr(0, 200);
    EXPECT_EQ(metrics.find("\nbounce_fake_total"), std::string::npos);
    EXPECT_NE(metrics.find("bounce_resident_bytes{scene=\"evil\\\"} 1\\nbounce_fake_total{a=\\\"\"}"), std::string::npos);

    std::vector<std::unique_ptr<RawConnection>> held;
    for (int i = 0; i < 16; ++i) held.push_back(std::make_unique<RawConnection>(client::Endpoint{"127.0.0.1", daemon.ops_port()}));
    std::this_thread::sleep_for(std::chrono::milliseconds(200));  // all 16 accepted
    RawConnection over({"127.0.0.1", daemon.ops_port()});
    EXPECT_TRUE(over.closed_by_daemon(std::chrono::milliseconds(2000)));
    EXPECT_FALSE(held.back()->closed_by_daemon(std::chrono::milliseconds(300)));  // waits for its 10 s timeout
    held.clear();
    // Their exchanges end as the daemon reads their close: once it has, the listener serves again
    // (within 5 s even on a loaded machine; before, a new connection is refused at once).
    std::string health;
    for (const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
         std::chrono::steady_clock::now() < deadline;) {
        health = http_get(daemon.ops_port(), "/healthz");
        if (!health.empty()) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    EXPECT_EQ(health.rfind("HTTP/1.1 200", 0), 0u) << health;

    EXPECT_THROW(DaemonProcess({"--metrics-listen", "0.0.0.0:0"}), std::runtime_error);
}

// Off loopback the metrics need the token as a bearer, but health does not: Kubernetes' HTTP probes
// cannot send a secret. (Bound to every interface; the test speaks to it on loopback only.)
TEST(DaemonHardening, OffLoopbackMetricsNeedTheTokenAndHealthDoesNot) {
    const auto token_file = std::filesystem::temp_directory_path() / ("bounce-ops-token-" + std::to_string(::getpid()));
    const std::string token = "correct-horse-battery-staple";
    std::ofstream(token_file) << token << "\n";
    DaemonProcess daemon({"--token-file", token_file.string(), "--metrics-listen", "0.0.0.0:0"});
    ASSERT_GT(daemon.ops_port(), 0);
    EXPECT_EQ(http_get(daemon.ops_port(), "/healthz").rfind("HTTP/1.1 200", 0), 0u);
    EXPECT_EQ(http_get(daemon.ops_port(), "/readyz").rfind("HTTP/1.1 200", 0), 0u);
    EXPECT_EQ(http_get(daemon.ops_port(), "/metrics").rfind("HTTP/1.1 401", 0), 0u);
    EXPECT_EQ(http_get(daemon.ops_port(), "/metrics", "wrong-token-of-some-length").rfind("HTTP/1.1 401", 0), 0u);
    const std::string metrics = http_get(daemon.ops_port(), "/metrics", token);
    EXPECT_EQ(metrics.rfind("HTTP/1.1 200", 0), 0u) << metrics.substr(0, 200);
    EXPECT_NE(metrics.find("bounce_build_info"), std::string::npos);
    EXPECT_EQ(http_get(daemon.ops_port(), "/nothing", token).rfind("HTTP/1.1 404", 0), 0u);
    std::filesystem::remove(token_file);
}

// not_found names the scene asked for and no other client's.
TEST(DaemonHardening, NotFoundDoesNotListOtherScenes) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    client.request(MessageType::scene_load, {{"name", "secret-project-x"}, {"builtin", "cornell"}});
    try {
        client.request(MessageType::scene_describe, {{"name", "nope"}});
        ADD_FAILURE() << "expected not_found";
    } catch (const ServerError& error) {
        EXPECT_EQ(error.code(), ErrorCode::not_found);
        EXPECT_EQ(std::string(error.what()).find("secret-project-x"), std::string::npos) << error.what();
    }
}

}  // namespace
}  // namespace bounce::test