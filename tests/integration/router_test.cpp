// Scale-out through the client: three real daemons on loopback, six scenes routed by rendezvous
// hashing, each resident on exactly the daemon its hash names, all rendered through the router;
// then a daemon dies and its scenes move to the next daemon in their order, reloaded from source,
// while every other scene stays put. The CLI routes the same way.
#include "client/router.hpp"
#include "daemon_support.hpp"

#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <set>

namespace bounce::test {
namespace {

using client::Endpoint;
using client::Router;

std::vector<std::uint8_t> box_glb() {
    std::ifstream in(kModels + "/BoxTextured-glTF-Binary/BoxTextured.glb", std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Which of a daemon's scenes are not built in.
std::set<std::string> loaded_scenes(const Endpoint& endpoint) {
    Client client(endpoint);
    std::set<std::string> names;
    const auto reply = client.request(MessageType::scene_list);
    for (const auto& scene : reply.body["scenes"]) {
        if (scene.value("source", "") != "builtin") names.insert(scene["name"].get<std::string>());
    }
    return names;
}

struct Fleet {
    std::vector<std::unique_ptr<DaemonProcess>> daemons;
    std::vector<Endpoint> endpoints;
    Fleet() {
        for (int i = 0; i < 3; ++i) {
            daemons.push_back(std::make_unique<DaemonProcess>(std::vector<std::string>{"--scene-root", kModels}));
            endpoints.push_back(daemons.back()->endpoint());
        }
    }
    DaemonProcess& daemon_at(const Endpoint& endpoint) {
        for (std::size_t i = 0; i < endpoints.size(); ++i) {
            if (endpoints[i] == endpoint) return *daemons[i];
        }
        throw std::runtime_error("no daemon at " + endpoint.to_string());
    }
};

// The scene's frame through the router, linear (EXR).
image::DecodedImage frame_of(Router& router, const std::string& scene) {
    const auto reply = router.request(scene, MessageType::render,
                                      {{"scene", scene}, {"width", 16}, {"height", 16}, {"format", "exr"}});
    return image::decode_image(reply.attachment);
}

// The box has no light of its own: one added through the router, so a reload must apply it again.
void add_light(Router& router, const std::string& scene) {
    router.request(scene, MessageType::light_set,
                   {{"scene", scene}, {"light", "key"}, {"type", "point"}, {"position", {1.5, 2.0, 2.5}},
                    {"intensity", 20.0}});
}

TEST(Router, SixScenesOnThreeDaemonsLiveWhereTheirHashSaysAndMoveOnlyWhenTheirDaemonDies) {
    const auto glb = box_glb();
    ASSERT_FALSE(glb.empty());
    Fleet fleet;
    Router router(fleet.endpoints);
    std::vector<std::string> scenes;
    for (int i = 0; i < 6; ++i) {
        const std::string name = "scene-" + std::to_string(i);
        scenes.push_back(name);
        // Half from the daemons' scene root, half uploaded: both kinds of source.
        if (i % 2 == 0) {
            router.load(name, "BoxTextured-glTF/BoxTextured.gltf");
        } else {
            router.upload(name, glb);
        }
        add_light(router, name);
        router.request(name, MessageType::object_set_transform,
                       {{"scene", name}, {"object", 0}, {"rotation_deg", {0.0, 15.0 * i, 0.0}}});
    }

    std::map<std::string, Endpoint> home;
    for (const auto& scene : scenes) home.emplace(scene, client::rendezvous_order(fleet.endpoints, scene).front());
    std::set<std::string> seen;
    for (const Endpoint& endpoint : fleet.endpoints) {
        for (const auto& scene : loaded_scenes(endpoint)) {
            EXPECT_TRUE(seen.insert(scene).second) << scene << " is resident on two daemons";
            EXPECT_EQ(home.at(scene), endpoint) << scene << " is not where its hash puts it";
        }
    }
    EXPECT_EQ(seen, std::set<std::string>(scenes.begin(), scenes.end()));
    // Rendering is deterministic: a frame before the move is the frame after it, exactly, when the
    // scene and its changes came back whole.
    std::map<std::string, std::vector<float>> before;
    for (const auto& scene : scenes) {
        const auto image = frame_of(router, scene);
        EXPECT_GT(rgb_sum(image), 0.0) << scene << ": the light added through the router reaches the frame";
        before[scene] = image.pixels;
    }

    // The first scene's daemon dies without warning; its scenes follow their order to the next
    // daemon and are loaded there from their sources, the rest stay where they are resident.
    const Endpoint lost = home.at(scenes[0]);
    fleet.daemon_at(lost).kill_hard();
    for (const auto& scene : scenes) EXPECT_EQ(frame_of(router, scene).pixels, before[scene]) << scene;
    std::vector<Endpoint> survivors;
    for (const auto& endpoint : fleet.endpoints) {
        if (!(endpoint == lost)) survivors.push_back(endpoint);
    }
    std::map<Endpoint, std::set<std::string>, decltype([](const Endpoint& a, const Endpoint& b) {
                 return a.to_string() < b.to_string();
             })> expected;
    for (const auto& scene : scenes) {
        const auto order = client::rendezvous_order(fleet.endpoints, scene);
        expected[order.front() == lost ? order[1] : order.front()].insert(scene);
        EXPECT_EQ(router.owner(scene), client::rendezvous_order(survivors, scene).front()) << scene;
    }
    for (const auto& endpoint : survivors) EXPECT_EQ(loaded_scenes(endpoint), expected[endpoint]) << endpoint.to_string();
}

TEST(Router, ADaemonThatForgotAScene_GetsItAgainFromItsSource) {
    Fleet fleet;
    Router router(fleet.endpoints);
    router.upload("kept", box_glb());
    add_light(router, "kept");
    const auto before = frame_of(router, "kept").pixels;
    const Endpoint owner = router.owner("kept");
    Client(owner).request(MessageType::scene_unload, {{"name", "kept"}});  // as after a restart
    EXPECT_EQ(frame_of(router, "kept").pixels, before);
    EXPECT_EQ(loaded_scenes(owner), std::set<std::string>{"kept"});
    // A missing object is the daemon's answer, not a missing scene: no reload, the error stands.
    expect_error([&] {
        router.request("kept", MessageType::object_set_transform,
                       {{"scene", "kept"}, {"object", "nothing"}, {"translation", {0.0, 1.0, 0.0}}});
    }, ErrorCode::not_found, "object");
    // Unloaded through the router on purpose: not brought back.
    router.request("kept", MessageType::scene_unload, {{"name", "kept"}});
    expect_error([&] { frame_of(router, "kept"); }, ErrorCode::not_found, "scene");
}

std::pair<int, std::string> run_cli(const std::string& arguments) {
    const std::string command = std::string(BOUNCE_CLI_PATH) + " " + arguments + " 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    std::string output;
    char buffer[4096];
    while (const std::size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
    const int status = pclose(pipe);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

TEST(Router, TheCliRoutesAndListsEveryDaemon) {
    Fleet fleet;
    std::string connect;
    for (const auto& endpoint : fleet.endpoints) connect += (connect.empty() ? "" : ",") + endpoint.to_string();
    const auto out = fleet.daemons[0]->directory() / "frame.png";
    const std::string glb = kModels + "/BoxTextured-glTF-Binary/BoxTextured.glb";

    auto [code, output] = run_cli("--connect " + connect + " upload " + glb + " --name routed");
    ASSERT_EQ(code, 0) << output;
    EXPECT_EQ(loaded_scenes(client::rendezvous_order(fleet.endpoints, "routed").front()), std::set<std::string>{"routed"});
    std::tie(code, output) = run_cli("--connect=" + connect + " render --scene=routed --size 16x16 -o " + out.string());
    ASSERT_EQ(code, 0) << output;
    std::ifstream png(out, std::ios::binary);
    const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(png), std::istreambuf_iterator<char>()};
    EXPECT_EQ(image::decode_image(bytes).width, 16);

    std::tie(code, output) = run_cli("--connect " + connect + " list");
    ASSERT_EQ(code, 0) << output;
    const json lists = json::parse(output);
    EXPECT_EQ(lists.size(), 3u);
    for (const auto& endpoint : fleet.endpoints) EXPECT_TRUE(lists.contains(endpoint.to_string())) << output;

    // A daemon down: list still shows the others and says which one is not there (exit 3).
    fleet.daemons[1]->kill_hard();
    std::tie(code, output) = run_cli("--connect " + connect + " list");
    EXPECT_EQ(code, 3) << output;
    EXPECT_TRUE(json::parse(output)[fleet.endpoints[1].to_string()].contains("error")) << output;
    // Nothing listening at all: a connection failure, not a refusal.
    std::tie(code, output) = run_cli("--connect " + fleet.endpoints[1].to_string() + " render --scene cornell -o " +
                                     out.string());
    EXPECT_EQ(code, 3) << output;
    // A refusal by the daemon: exit 1.
    std::tie(code, output) = run_cli("--connect " + fleet.endpoints[0].to_string() + " render --scene no-such -o " +
                                     out.string());
    EXPECT_EQ(code, 1) << output;
    EXPECT_NE(output.find("not_found"), std::string::npos) << output;
}

// --log-format json: every line one JSON object, one access line per request with its id.
TEST(Logs, JsonLinesCarryRequestIdsAndOneAccessLinePerRequest) {
    std::vector<json> lines;
    {
        DaemonProcess daemon({"--log-level", "info", "--log-format", "json"}, true);
        Client client(daemon.endpoint());
        render(client, {{"scene", "cornell"}, {"width", 8}, {"height", 8}});
        expect_error([&] { render(client, {{"scene", "missing"}}); }, ErrorCode::not_found, "scene");
        EXPECT_EQ(daemon.terminate_and_wait(), 0);
        std::ifstream in(daemon.log_path());
        for (std::string line; std::getline(in, line);) {
            ASSERT_NO_THROW(lines.push_back(json::parse(line))) << line;
        }
    }
    std::vector<json> access;
    for (const auto& line : lines) {
        EXPECT_TRUE(line.contains("ts") && line.contains("level") && line.contains("component")) << line;
        if (line["component"] == "access") access.push_back(line);
    }
    ASSERT_EQ(access.size(), 3u);  // hello, the frame, the refusal
    EXPECT_EQ(access[0]["type"], "hello");
    EXPECT_EQ(access[1]["type"], "render");
    EXPECT_EQ(access[1]["status"], "ok");
    EXPECT_EQ(access[1]["scene"], "cornell");
    EXPECT_GT(access[1]["bytes_out"].get<int>(), 0);
    EXPECT_EQ(access[2]["status"], "not_found");
    std::set<std::string> ids;
    for (const auto& line : access) ids.insert(line["request_id"].get<std::string>());
    EXPECT_EQ(ids.size(), 3u);
}

}  // namespace
}  // namespace bounce::test
