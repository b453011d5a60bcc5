// A real bounced on an ephemeral loopback port, driven through the client library.
#include "daemon_support.hpp"
#include "support/hostile_gltf.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>
#include <unistd.h>

namespace bounce::test {
namespace {
TEST(Daemon, HelloAnnouncesLimitsAndRenderer) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    const json& hello = client.hello();
    EXPECT_EQ(hello["protocol"], 1);
    EXPECT_FALSE(hello["renderer"].get<std::string>().empty());
    EXPECT_GT(hello["limits"]["max_json_bytes"].get<std::uint64_t>(), 0u);
    EXPECT_EQ(client.request(MessageType::ping).type, static_cast<std::uint16_t>(MessageType::pong));
}

TEST(Daemon, RendersEveryFormatAndDescribes) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    const auto described = client.request(MessageType::scene_describe, {{"name", "cornell"}}).body;
    EXPECT_EQ(described["objects"].size(), 3u);
    EXPECT_EQ(described["lights"].size(), 1u);
    for (const std::string format : {"png", "jpeg", "exr"}) {
        const auto reply = client.request(MessageType::render, {{"scene", "cornell"}, {"width", 40}, {"height", 30},
                                                                {"format", format}});
        const auto decoded = image::decode_image(reply.attachment);
        EXPECT_EQ(decoded.width, 40) << format;
        EXPECT_EQ(decoded.height, 30) << format;
        const json& stats = reply.body;
        EXPECT_EQ(stats["format"], format);
        EXPECT_GT(stats["timings_ms"]["passes"]["gbuffer"].get<double>(), 0.0);
        for (const char* key : {"queue", "render", "readback", "encode", "total"}) {
            EXPECT_GE(stats["timings_ms"][key].get<double>(), 0.0) << key;
        }
        EXPECT_GT(stats["resident_bytes"].get<std::uint64_t>(), 0u);
    }
}

TEST(Daemon, LoadsFromTheSceneRootAndUploads) {
    DaemonProcess daemon({"--scene-root", kModels});
    Client client(daemon.endpoint());
    const auto loaded = client.request(MessageType::scene_load, {{"name", "box"}, {"path", "BoxTextured-glTF/BoxTextured.gltf"}});
    EXPECT_EQ(loaded.body["objects"], 1);
    std::ifstream in(kModels + "/BoxTextured-glTF-Binary/BoxTextured.glb", std::ios::binary);
    std::vector<std::uint8_t> glb{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    ASSERT_FALSE(glb.empty());
    client.request(MessageType::scene_load, {{"name", "uploaded"}}, glb);
    const auto list = client.request(MessageType::scene_list).body["scenes"];
    EXPECT_EQ(list.size(), 3u);
    const auto image = render(client, {{"scene", "uploaded"}, {"width", 16}, {"height", 16}});
    EXPECT_EQ(image.width, 16);
    client.request(MessageType::scene_unload, {{"name", "uploaded"}});
    expect_error([&] { render(client, {{"scene", "uploaded"}}); }, ErrorCode::not_found, "scene");
}

TEST(Daemon, PathsEscapingTheSceneRootAreRefused) {
    DaemonProcess daemon({"--scene-root", kModels});
    const auto baseline = cornell_frame(daemon.endpoint());
    Client client(daemon.endpoint());
    for (const std::string path : {"../glTF2/BoxTextured-glTF/BoxTextured.gltf", "/etc/passwd",
                                   "BoxTextured-glTF/../../../../etc/passwd"}) {
        expect_error([&] { client.request(MessageType::scene_load, {{"name", "x"}, {"path", path}}); },
                     ErrorCode::bad_request, "path");
    }
    expect_error([&] { client.request(MessageType::scene_load, {{"name", "x"}, {"path", "nothing/here.gltf"}}); },
                 ErrorCode::not_found, "path");
    expect_still_serving(daemon.endpoint(), baseline);
}

TEST(Daemon, SymlinkOutOfTheSceneRootIsRefused) {
    const auto root = std::filesystem::temp_directory_path() / "bounce-root-test";
    std::filesystem::remove_all(root);
    std::filesystem::create_directories(root);
    std::filesystem::create_symlink(kModels + "/BoxTextured-glTF/BoxTextured.gltf", root / "escape.gltf");
    DaemonProcess daemon({"--scene-root", root.string()});
    Client client(daemon.endpoint());
    expect_error([&] { client.request(MessageType::scene_load, {{"name", "x"}, {"path", "escape.gltf"}}); },
                 ErrorCode::bad_request, "path");
    std::filesystem::remove_all(root);
}

TEST(Daemon, MovingABlockChangesTheFrameWhereItWasAndIs) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    const json request = {{"scene", "cornell"}, {"width", 64}, {"height", 64}, {"format", "exr"}};
    const auto before = render(client, request);
    const auto moved = client.request(MessageType::object_set_transform,
                                      {{"scene", "cornell"}, {"object", "short_block"}, {"translation", {0.0, 0.0, 0.15}}});
    EXPECT_EQ(moved.body["scene_version"], 1);
    json after_request = request;
    after_request["min_scene_version"] = 1;
    const auto after = render(client, after_request);
    // The block's old top (left-bottom quarter of the image) changed; the top-left wall did not.
    auto at = [](const image::DecodedImage& image, int x, int y) { return image.at(x, y, 0) + image.at(x, y, 1); };
    EXPECT_EQ(at(before, 4, 10), at(after, 4, 10));
    int changed = 0;
    for (int y = 32; y < 64; ++y)
        for (int x = 16; x < 40; ++x) changed += std::abs(at(before, x, y) - at(after, x, y)) > 1e-4f;
    EXPECT_GT(changed, 40);
    expect_error([&] { client.request(MessageType::render, {{"scene", "cornell"}, {"min_scene_version", 9}}); },
                 ErrorCode::bad_request, "min_scene_version");
}

// A matte 2 m square on y = 0 under a 1000 cd point light, seen from above, as a GLB.
std::vector<std::uint8_t> lit_square_glb() {
    std::vector<std::uint8_t> bin;
    const auto put_float = [&](float value) {
        std::uint32_t bits;
        std::memcpy(&bits, &value, 4);
        hostile::put_u32(bin, bits);
    };
    for (const float x : {-1.0f, 1.0f})
        for (const float z : {-1.0f, 1.0f}) {
            put_float(x), put_float(0.0f), put_float(z);
        }
    for (int i = 0; i < 4; ++i) put_float(0.0f), put_float(1.0f), put_float(0.0f);
    for (const std::uint16_t index : {0, 1, 2, 2, 1, 3}) bin.push_back(index & 0xff), bin.push_back(index >> 8);
    return hostile::make_glb(R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual"],
      "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1, 0.8, 0.6], "intensity": 1000}]}},
      "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
      "nodes": [{"name": "square", "mesh": 0},
                {"name": "bulb", "translation": [0.2, 1.5, -0.3], "extensions": {"KHR_lights_punctual": {"light": 0}}},
                {"name": "above", "camera": 0, "translation": [0, 3, 0],
                 "rotation": [-0.7071067811865476, 0, 0, 0.7071067811865476]}],
      "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}],
      "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
      "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0, "roughnessFactor": 1}}],
      "buffers": [{"byteLength": 108}],
      "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                      {"buffer": 0, "byteOffset": 96, "byteLength": 12}],
      "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]},
                    {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
                    {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}]})",
                             bin);
}

// One convention for files and for light.set: the file's light, removed and set again over the
// protocol with the numbers the file gives (candela), renders the same frame; describe answers in
// the same units.
TEST(Daemon, ALightSetWithAFilesNumbersGivesTheFilesFrame) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    client.request(MessageType::scene_load, {{"name", "square"}}, lit_square_glb());
    const json request = {{"scene", "square"}, {"width", 32}, {"height", 32}, {"format", "exr"}};
    const auto from_file = render(client, request);
    const auto description = client.request(MessageType::scene_describe, {{"name", "square"}}).body;
    EXPECT_NEAR(description["lights"][0]["intensity"].get<double>(), 1000.0, 1e-3);
    client.request(MessageType::light_remove, {{"scene", "square"}, {"light", "bulb"}});
    client.request(MessageType::light_set, {{"scene", "square"}, {"light", "bulb"}, {"type", "point"},
                                            {"position", {0.2, 1.5, -0.3}}, {"color", {1, 0.8, 0.6}},
                                            {"intensity", 1000}});
    const auto from_protocol = render(client, request);
    ASSERT_EQ(from_file.pixels.size(), from_protocol.pixels.size());
    double lit = 0.0;
    for (std::size_t i = 0; i < from_file.pixels.size(); ++i) {
        EXPECT_NEAR(from_protocol.pixels[i], from_file.pixels[i], 1e-6f + 1e-6f * from_file.pixels[i]) << i;
        lit += from_file.pixels[i];
    }
    EXPECT_GT(lit, 0.0);
}

TEST(Daemon, DoublingLightIntensityDoublesRadiance) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    const json request = {{"scene", "cornell"}, {"width", 48}, {"height", 48}, {"format", "exr"}};
    // Candela, as in files: 341.5 cd and 683 cd are 0.5 and 1 W/sr.
    client.request(MessageType::light_set, {{"scene", "cornell"}, {"light", "ceiling_light"}, {"intensity", 341.5}});
    const auto single = render(client, request);
    client.request(MessageType::light_set, {{"scene", "cornell"}, {"light", "ceiling_light"}, {"intensity", 683.0}});
    const auto doubled = render(client, request);
    int compared = 0;
    for (std::size_t i = 0; i < single.pixels.size(); ++i) {
        if (i % 4 == 3 || single.pixels[i] < 1e-3f) continue;
        EXPECT_NEAR(doubled.pixels[i], 2.0f * single.pixels[i], 0.01f * 2.0f * single.pixels[i]) << "value " << i;
        ++compared;
    }
    EXPECT_GT(compared, 1000);
}

TEST(Daemon, EightClientsRenderAndMoveConcurrently) {
    DaemonProcess daemon;
    std::atomic<int> frames{0}, failures{0};
    std::vector<std::thread> clients;
    for (int c = 0; c < 8; ++c) {
        clients.emplace_back([&, c] {
            try {
                Client client(daemon.endpoint());
                for (int f = 0; f < 4; ++f) {
                    client.request(MessageType::object_set_transform,
                                   {{"scene", "cornell"}, {"object", c % 2 ? "short_block" : "tall_block"},
                                    {"translation", {0.01 * f, 0.0, 0.0}}});
                    const auto reply = client.request(MessageType::render,
                                                      {{"scene", "cornell"}, {"width", 24}, {"height", 24}});
                    if (image::decode_image(reply.attachment).width == 24) ++frames;
                }
            } catch (const std::exception& error) {
                ++failures;
                ADD_FAILURE() << "client " << c << ": " << error.what();
            }
        });
    }
    for (auto& thread : clients) thread.join();
    EXPECT_EQ(failures.load(), 0);
    EXPECT_EQ(frames.load(), 32);
}

// The path-traced reference through the protocol: deterministic for its seed, the same light as
// `direct` at zero bounces, and run on the CPU pool so GPU renders keep flowing meanwhile.
TEST(Daemon, ReferenceRendersOnTheCpuWithoutBlockingGpuFrames) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    const json traced = {{"scene", "cornell"}, {"method", "reference"}, {"knobs", {{"spp", 16}, {"bounces", 0}}},
                         {"width", 64}, {"height", 64}, {"format", "exr"}};
    const auto first = render(client, traced);
    const auto second = render(client, traced);
    EXPECT_TRUE(first.pixels == second.pixels) << "the same seed must give the same image";
    const auto direct = render(client, {{"scene", "cornell"}, {"width", 64}, {"height", 64}, {"format", "exr"}});
    const double traced_sum = rgb_sum(first), direct_sum = rgb_sum(direct);
    // Same lights and BRDF at zero bounces: the means agree within Monte Carlo noise (16 spp over
    // 4096 pixels: well under 0.5%) plus the difference between the reference's pixel-area average
    // and direct's pixel-centre shading of the ceiling's hot spot (0.7% measured at 96^2, 3.6% at
    // 24^2, hence 64^2 here).
    EXPECT_NEAR(traced_sum / direct_sum, 1.0, 0.02);
    const auto reply = client.request(MessageType::render, {{"scene", "cornell"}, {"method", "reference"},
                                                            {"preset", "draft"}, {"width", 16}, {"height", 16}});
    EXPECT_EQ(reply.body["method"], "reference");
    EXPECT_EQ(reply.body["knobs"]["spp"], 4);
    EXPECT_EQ(image::decode_image(reply.attachment).width, 16) << "PNG through the GPU tone-map pass";

    // A long trace on one connection; GPU frames on another finish while it runs.
    std::atomic<bool> long_trace_done{false};
    std::thread tracer([&] {
        Client slow(daemon.endpoint());
        render(slow, {{"scene", "cornell"}, {"method", "reference"}, {"knobs", {{"spp", 256}, {"bounces", 4}}},
                      {"width", 128}, {"height", 128}, {"format", "exr"}});
        long_trace_done = true;
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    int frames_during_trace = 0;
    for (int i = 0; i < 3; ++i) {
        render(client, {{"scene", "cornell"}, {"width", 32}, {"height", 32}, {"format", "exr"}});
        frames_during_trace += long_trace_done ? 0 : 1;
    }
    tracer.join();
    EXPECT_EQ(frames_during_trace, 3) << "GPU frames waited for the CPU trace";
    expect_error([&] {
        client.request(MessageType::render, {{"scene", "cornell"}, {"method", "reference"}, {"knobs", {{"spp", 0}}}});
    }, ErrorCode::bad_request);
}

// isr through the protocol: its frame adds one bounce to the direct light, its counts come back in
// method_stats, and knob combinations it or the reference refuse are bad requests.
TEST(Daemon, IsrRendersWithItsStatsAndRefusesBadKnobs) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    const json body = {{"scene", "cornell"}, {"method", "isr"}, {"preset", "draft"},
                       {"width", 64}, {"height", 64}, {"format", "exr"}};
    const auto reply = client.request(MessageType::render, body);
    const json& stats = reply.body["method_stats"];
    EXPECT_GT(stats["vpls_per_fragment_mean"].get<double>(), 0.0);
    EXPECT_GE(stats["vpls_per_fragment_max"].get<double>(), stats["vpls_per_fragment_mean"].get<double>());
    EXPECT_GT(stats["multires_fragments"].get<double>(), 0.0);
    EXPECT_EQ(stats["rsm_views"].get<double>(), 6.0);  // the Cornell box's point light: a cube
    const auto isr = image::decode_image(reply.attachment);
    const auto direct = render(client, {{"scene", "cornell"}, {"width", 64}, {"height", 64}, {"format", "exr"}});
    const double isr_sum = rgb_sum(isr), direct_sum = rgb_sum(direct);
    // One bounce in a closed white box adds 40-60% to the direct light (reference: 0.67 vs 0.45).
    EXPECT_GT(isr_sum, 1.2 * direct_sum);
    EXPECT_LT(isr_sum, 2.0 * direct_sum);
    expect_error([&] {
        client.request(MessageType::render, {{"scene", "cornell"}, {"method", "isr"}, {"knobs", {{"mode", 3}}}});
    }, ErrorCode::bad_request);
    expect_error([&] {
        client.request(MessageType::render, {{"scene", "cornell"}, {"method", "reference"},
                                             {"knobs", {{"indirect_visibility", 0}, {"bounces", 2}}}});
    }, ErrorCode::bad_request);
    EXPECT_EQ(render(client, body).width, 64) << "serving continues";
}

// isr's presets leave the maps' dilation to the scene (renderer/scene_knobs.hpp; the daemon makes
// the analysis on its CPU pool, docs/architecture.md): the open Cornell box renders without it, and
// the reply's knobs say so; a request's own value wins, and a threshold out of range is refused.
TEST(Daemon, IsrsPresetsTakeTheMapsDilationFromTheScene) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    const json body = {{"scene", "cornell"}, {"method", "isr"}, {"preset", "low"}, {"width", 32}, {"height", 32}};
    EXPECT_EQ(client.request(MessageType::render, body).body["knobs"]["ism_dilation"], 0);
    json asked = body;
    asked["knobs"] = {{"ism_dilation", 2}};
    EXPECT_EQ(client.request(MessageType::render, asked).body["knobs"]["ism_dilation"], 2);
    json no_scene = body;
    no_scene["knobs"] = {{"ism_open_below", 0}};
    EXPECT_EQ(client.request(MessageType::render, no_scene).body["knobs"]["ism_dilation"], 2);
    asked["knobs"] = {{"ism_open_below", 1.5}};
    expect_error([&] { client.request(MessageType::render, asked); }, ErrorCode::bad_request);
}

// The same through a bake, and after a light moves, where the frame goes on with the analysis as
// last made while the daemon makes it again with no request waiting on it: each reply comes, with
// the scene's setting (where the analysis is made, this test does not see).
TEST(Daemon, IsrsSceneKnobsAfterABakeAndALightMove) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    const json body = {{"scene", "cornell"}, {"method", "isr"}, {"preset", "low"}, {"width", 32}, {"height", 32}};
    EXPECT_EQ(client.request(MessageType::bake, body).body["knobs"]["ism_dilation"], 0);
    client.request(MessageType::light_set, {{"scene", "cornell"}, {"light", "ceiling_light"}, {"position", {0.27, 0.44, 0.28}}});
    EXPECT_EQ(client.request(MessageType::render, body).body["knobs"]["ism_dilation"], 0);
    EXPECT_EQ(client.request(MessageType::render, body).body["knobs"]["ism_dilation"], 0);
}

// A directory for --cache-dir that outlives the daemons of one test.
struct CacheDir {
    CacheDir() : path(std::filesystem::temp_directory_path() / ("bounce-cache-" + std::to_string(::getpid()) + "-" +
                                                                 std::to_string(counter++))) {
        std::filesystem::create_directories(path);
    }
    ~CacheDir() {
        std::error_code ignored;
        std::filesystem::remove_all(path, ignored);
    }
    std::vector<std::filesystem::path> files() const {
        std::vector<std::filesystem::path> found;
        for (const auto& entry : std::filesystem::directory_iterator(path)) found.push_back(entry.path().filename());
        return found;
    }
    std::filesystem::path path;
    static inline int counter = 0;
};

TEST(Daemon, CssmBakeReportsProgressAndARestartedDaemonReusesItsCache) {
    CacheDir cache;
    const json bake = {{"scene", "cornell"}, {"method", "cssm"}, {"preset", "low"}};
    {
        DaemonProcess daemon({"--cache-dir", cache.path.string()});
        Client client(daemon.endpoint());
        std::vector<double> fractions;
        const auto reply = client.request(MessageType::bake, bake, {}, [&](const json& progress) {
            fractions.push_back(progress.at("fraction").get<double>());
            const std::string stage = progress.at("stage").get<std::string>();
            EXPECT_TRUE(stage == "surface atlas" || stage == "texels inside solids" || stage == "traversal" ||
                        stage == "depth cube maps" || stage == "done")
                << stage;
        });
        ASSERT_FALSE(fractions.empty());
        EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
        EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
        const json& stats = reply.body.at("method_stats");
        EXPECT_EQ(stats.at("bakes").get<double>(), 1.0);
        EXPECT_EQ(stats.at("bakes_loaded").get<double>(), 0.0);
        EXPECT_GT(stats.at("cube_maps").get<double>(), 100.0);
        EXPECT_LT(stats.at("compressed_bytes").get<double>(), stats.at("uncompressed_bytes").get<double>());
        ASSERT_EQ(cache.files().size(), 1u);  // the bake, and no temporary file left over
        // A render with the same knobs uses the bake already resident.
        const auto frame = client.request(MessageType::render, {{"scene", "cornell"}, {"method", "cssm"}, {"preset", "low"},
                                                                {"width", 32}, {"height", 32}, {"format", "exr"}});
        EXPECT_EQ(frame.body.at("method_stats").at("bakes").get<double>(), 1.0);
        expect_error([&] { client.request(MessageType::bake, {{"scene", "cornell"}, {"method", "reference"}}); },
                     ErrorCode::bad_request);
    }
    DaemonProcess restarted({"--cache-dir", cache.path.string()});
    Client client(restarted.endpoint());
    const auto frame = client.request(MessageType::render, {{"scene", "cornell"}, {"method", "cssm"}, {"preset", "low"},
                                                            {"width", 32}, {"height", 32}, {"format", "exr"}});
    const json& stats = frame.body.at("method_stats");
    EXPECT_EQ(stats.at("bakes").get<double>(), 0.0) << "the restarted daemon baked again";
    EXPECT_EQ(stats.at("bakes_loaded").get<double>(), 1.0);
}

// vct's bake builds its octree and injects no light: the frame after it voxelizes nothing and redoes
// the light alone.
TEST(Daemon, VctBakeBuildsTheOctreeAndTheNextFrameRedoesOnlyTheLight) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    const json baked = client.request(MessageType::bake, {{"scene", "cornell"}, {"method", "vct"}, {"preset", "draft"}})
                           .body.at("method_stats");
    EXPECT_EQ(baked.at("octree_builds").get<double>(), 1.0);
    EXPECT_EQ(baked.at("light_injections").get<double>(), 0.0);
    const auto frame = client.request(MessageType::render, {{"scene", "cornell"}, {"method", "vct"}, {"preset", "draft"},
                                                            {"width", 32}, {"height", 32}, {"format", "exr"}});
    EXPECT_EQ(frame.body.at("method_stats").at("octree_builds").get<double>(), 1.0);
    EXPECT_EQ(frame.body.at("method_stats").at("light_injections").get<double>(), 1.0);
    EXPECT_EQ(frame.body.at("redid"), "lights");
}

TEST(Daemon, ObjectsDeclaredDynamicAtLoadMoveWithoutARebake) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    client.request(MessageType::scene_load, {{"name", "box"}, {"builtin", "cornell"}, {"dynamic", {"tall_block"}}});
    const json body = {{"scene", "box"}, {"method", "cssm"}, {"preset", "draft"}, {"width", 32}, {"height", 32}, {"format", "exr"}};
    const json before = client.request(MessageType::render, body).body.at("method_stats");
    EXPECT_EQ(before.at("moving_objects").get<double>(), 1.0);
    EXPECT_EQ(before.at("bake_groups").get<double>(), 2.0);
    client.request(MessageType::object_set_transform, {{"scene", "box"}, {"object", "tall_block"}, {"translation", {0.3, 0.0, 0.3}}});
    const json after = client.request(MessageType::render, body).body.at("method_stats");
    EXPECT_EQ(after.at("bakes").get<double>(), before.at("bakes").get<double>());
    EXPECT_EQ(after.at("placements").get<double>(), 1.0);
    expect_error([&] { client.request(MessageType::scene_load, {{"name", "x"}, {"builtin", "cornell"}, {"dynamic", {"teapot"}}}); },
                 ErrorCode::not_found, "dynamic");
    expect_error([&] { client.request(MessageType::scene_load, {{"name", "x"}, {"builtin", "sponza"}}); }, ErrorCode::bad_request,
                 "builtin");
}

TEST(Daemon, ABakeKilledMidwayLeavesTheCacheUsable) {
    CacheDir cache;
    {
        DaemonProcess daemon({"--cache-dir", cache.path.string()});
        Client client(daemon.endpoint());
        // Ask for a long bake, and kill the daemon as soon as it reports progress.
        client.send_raw(protocol::encode({static_cast<std::uint16_t>(MessageType::bake), 7,
                                          {{"scene", "cornell"}, {"method", "cssm"}, {"preset", "ultra"}, {"knobs", {{"face_size", 64}}}},
                                          {}}));
        const auto event = client.read();
        ASSERT_EQ(event.type, static_cast<std::uint16_t>(MessageType::progress));
        EXPECT_LT(event.body.at("fraction").get<double>(), 1.0);
        daemon.kill_hard();
    }
    // Bakes are written only once complete (to a temporary name, renamed into place): nothing here.
    EXPECT_TRUE(cache.files().empty());
    DaemonProcess restarted({"--cache-dir", cache.path.string()});
    Client client(restarted.endpoint());
    const json bake = {{"scene", "cornell"}, {"method", "cssm"}, {"preset", "draft"}};
    EXPECT_EQ(client.request(MessageType::bake, bake).body.at("method_stats").at("bakes").get<double>(), 1.0);
    // A cancelled bake answers `cancelled` and the daemon keeps serving.
    client.send_raw(protocol::encode({static_cast<std::uint16_t>(MessageType::bake), 100,
                                      {{"scene", "cornell"}, {"method", "cssm"}, {"preset", "ultra"}, {"knobs", {{"face_size", 64}}}},
                                      {}}));
    ASSERT_EQ(client.read().type, static_cast<std::uint16_t>(MessageType::progress));
    client.send_raw(protocol::encode({static_cast<std::uint16_t>(MessageType::cancel), 101, {{"id", 100}}, {}}));
    bool cancelled = false;
    for (int i = 0; i < 1000 && !cancelled; ++i) {
        const auto message = client.read();
        if (message.request_id == 100 && message.type == static_cast<std::uint16_t>(MessageType::error)) {
            EXPECT_EQ(message.body.at("code").get<std::string>(), "cancelled");
            cancelled = true;
        }
    }
    EXPECT_TRUE(cancelled);
    const json stats = client.request(MessageType::bake, bake).body.at("method_stats");
    EXPECT_EQ(stats.at("bakes").get<double>(), 1.0) << "the draft bake was lost";
    EXPECT_EQ(stats.at("bakes_loaded").get<double>(), 0.0) << "the draft bake should have stayed resident";
}

TEST(Daemon, BadRequestsGetTheRightErrorAndServingContinues) {
    DaemonProcess daemon;
    const auto baseline = cornell_frame(daemon.endpoint());
    Client client(daemon.endpoint());
    expect_error([&] { client.request(MessageType::render, {{"scene", "nope"}}); }, ErrorCode::not_found, "scene");
    expect_error([&] { client.request(MessageType::render, {{"scene", "cornell"}, {"camera", "nope"}}); },
                 ErrorCode::not_found, "camera");
    expect_error([&] { client.request(MessageType::render, {{"scene", "cornell"}, {"width", 0}}); },
                 ErrorCode::bad_request, "width");
    expect_error([&] { client.request(MessageType::render, {{"scene", "cornell"}, {"method", "magic"}}); },
                 ErrorCode::bad_request, "method");
    expect_error([&] { client.request(MessageType::render, {{"scene", "cornell"}, {"preset", "best"}}); },
                 ErrorCode::bad_request, "preset");
    expect_error([&] { client.request(MessageType::render, {{"scene", "cornell"}, {"knobs", {{"bogus", 1}}}}); },
                 ErrorCode::bad_request, "knobs");
    expect_error([&] { client.request(MessageType::render, {{"scene", "cornell"}, {"width", 16384}, {"height", 16384}}); },
                 ErrorCode::too_large, "width");
    // NaN cannot be written in JSON; a client sends null or a number past float range instead.
    expect_error([&] {
        client.request(MessageType::object_set_transform,
                       {{"scene", "cornell"}, {"object", "short_block"}, {"translation", {nullptr, 0, 0}}});
    }, ErrorCode::bad_request, "translation");
    expect_error([&] {
        json matrix = json::array();
        for (int i = 0; i < 16; ++i) matrix.push_back(i == 5 ? 1e39 : 1.0);
        client.request(MessageType::object_set_transform, {{"scene", "cornell"}, {"object", "short_block"}, {"matrix", matrix}});
    }, ErrorCode::bad_request, "matrix");
    expect_error([&] { client.request(MessageType::object_set_transform, {{"scene", "cornell"}, {"object", "ghost"}, {"scale", 2}}); },
                 ErrorCode::not_found, "object");
    expect_error([&] { client.request(MessageType::light_set, {{"scene", "cornell"}, {"light", "l"}, {"intensity", -1}}); },
                 ErrorCode::bad_request, "intensity");
    expect_error([&] { client.request(static_cast<MessageType>(999)); }, ErrorCode::unsupported);
    expect_error([&] { client.request(MessageType::scene_load, {{"name", "x"}, {"path", "a.gltf"}}); },
                 ErrorCode::unsupported, "path");  // no --scene-root
    // The same connection still renders correctly.
    const auto image = render(client, {{"scene", "cornell"}, {"width", 8}, {"height", 8}});
    EXPECT_EQ(image.width, 8);
    expect_still_serving(daemon.endpoint(), baseline);
}

TEST(Daemon, BrokenFramesCloseOnlyThatConnection) {
    DaemonProcess daemon({"--max-message-bytes", "65536"});
    const auto baseline = cornell_frame(daemon.endpoint());
    Client bystander(daemon.endpoint());
    auto header = [](std::uint32_t json_length, std::uint32_t attachment_length, std::uint16_t version = 1) {
        protocol::Header h{version, static_cast<std::uint16_t>(MessageType::render), 77, json_length, attachment_length};
        std::vector<std::uint8_t> bytes(protocol::kHeaderSize);
        protocol::encode_header(h, bytes.data());
        return bytes;
    };
    struct Case {
        std::string name;
        std::vector<std::uint8_t> bytes;
        ErrorCode code;
    };
    std::vector<std::uint8_t> garbage(100);
    for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<std::uint8_t>(i * 37 + 11);
    auto invalid_json = header(5, 0);
    for (char c : std::string("{nope")) invalid_json.push_back(static_cast<std::uint8_t>(c));
    const std::vector<Case> cases = {
        {"random bytes", garbage, ErrorCode::broken_frame},
        {"json past the cap", header(1u << 30, 0), ErrorCode::too_large},
        {"attachment past the cap", header(2, 1u << 20), ErrorCode::too_large},
        {"wrong version", header(2, 0, 9), ErrorCode::version_mismatch},
        {"invalid json", invalid_json, ErrorCode::broken_frame},
    };
    for (const auto& c : cases) {
        Client victim(daemon.endpoint());
        const auto reply = victim.send_raw_and_read(c.bytes);
        EXPECT_EQ(reply.type, static_cast<std::uint16_t>(MessageType::error)) << c.name;
        EXPECT_EQ(reply.body.value("code", ""), protocol::error_code_name(c.code)) << c.name;
        EXPECT_THROW(victim.read(), std::runtime_error) << c.name << ": the connection should be closed";
    }
    {
        // A truncated header followed by a hang-up: nothing to answer, nothing else affected.
        Client truncated(daemon.endpoint());
        const auto partial = header(2, 0);
        truncated.send_raw(std::span(partial).first(10));
    }
    const auto image = render(bystander, {{"scene", "cornell"}, {"width", 8}, {"height", 8}});
    EXPECT_EQ(image.width, 8);
    expect_still_serving(daemon.endpoint(), baseline);
}

// Pipelined requests past the queue's capacity: each gets exactly one reply, a frame or `busy`;
// requests whose deadline passes in the queue get `timeout`.
TEST(Daemon, FullQueueAnswersBusyAndDeadlinesAnswerTimeout) {
    DaemonProcess daemon({"--queue", "2", "--max-in-flight", "64"});
    Client client(daemon.endpoint());
    constexpr int kRequests = 24;
    std::vector<std::uint8_t> burst;
    for (int i = 0; i < kRequests; ++i) {
        json body = {{"scene", "cornell"}, {"width", 192}, {"height", 192}};
        if (i % 2 == 1) body["timeout_ms"] = 1;
        const auto frame = protocol::encode(protocol::make_message(MessageType::render, 1000 + i, body));
        burst.insert(burst.end(), frame.begin(), frame.end());
    }
    client.send_raw(burst);
    std::map<std::uint64_t, std::string> replies;
    for (int i = 0; i < kRequests; ++i) {
        const auto reply = client.read();
        const std::string kind = reply.type == static_cast<std::uint16_t>(MessageType::frame)
                                     ? "frame"
                                     : reply.body.value("code", "?");
        EXPECT_TRUE(replies.emplace(reply.request_id, kind).second) << "two replies to " << reply.request_id;
    }
    std::map<std::string, int> counts;
    for (const auto& [id, kind] : replies) ++counts[kind];
    EXPECT_EQ(replies.size(), static_cast<std::size_t>(kRequests));
    EXPECT_GE(counts["frame"], 1);
    EXPECT_GE(counts["busy"], 1);
    EXPECT_EQ(counts["frame"] + counts["busy"] + counts["timeout"], kRequests);
    EXPECT_GE(counts["timeout"], 1) << "queued renders with a 1 ms deadline wait longer than that";
    for (const auto& [id, kind] : replies) {
        if (kind == "timeout") {
            EXPECT_EQ(id % 2, 1u) << "only requests with timeout_ms may time out";
        }
    }
}

TEST(Daemon, TokenIsRequiredWhenConfigured) {
    const auto token_file = std::filesystem::temp_directory_path() / "bounce-token-test";
    std::ofstream(token_file) << "correct-horse-battery-staple\n";
    DaemonProcess daemon({"--token-file", token_file.string()});
    try {
        Client wrong(daemon.endpoint(), std::string("wrong-token-wrong-token"));
        ADD_FAILURE() << "a wrong token was accepted";
    } catch (const ServerError& error) {
        EXPECT_EQ(error.code(), ErrorCode::unauthorized);
    }
    Client right(daemon.endpoint(), std::string("correct-horse-battery-staple"));
    EXPECT_EQ(render(right, {{"scene", "cornell"}, {"width", 8}, {"height", 8}}).width, 8);
    std::filesystem::remove(token_file);
}

TEST(Daemon, NonLoopbackListenWithoutTokenIsRefused) {
    EXPECT_THROW(DaemonProcess({"--listen", "0.0.0.0:0"}), std::runtime_error);
}

TEST(Daemon, SigtermExitsCleanly) {
    DaemonProcess daemon;
    {
        Client client(daemon.endpoint());
        render(client, {{"scene", "cornell"}, {"width", 16}, {"height", 16}});
    }
    EXPECT_EQ(daemon.terminate_and_wait(), 0);
}

// A cancelled `reference` render answers `cancelled` and gives its CPU slot back, whether the
// cancel arrives before the trace starts or during it: six cancels in a row (the daemon has four
// slots) and a render after them still gets a frame, not `busy`.
TEST(Daemon, CancelledReferenceRendersFreeTheirSlots) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    const json hours = {{"scene", "cornell"}, {"method", "reference"}, {"width", 128}, {"height", 128},
                        {"knobs", {{"spp", 65536}}}};
    for (std::uint64_t id = 100; id < 106; ++id) {
        client.send_raw(protocol::encode({static_cast<std::uint16_t>(MessageType::render), id, hours, {}}));
        // Every other one is cancelled while it traces, the rest while queued or at once.
        if (id % 2 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(300));
        client.send_raw(protocol::encode({static_cast<std::uint16_t>(MessageType::cancel), id + 1000, {{"id", id}}, {}}));
        const auto reply = reply_to(client, id);
        ASSERT_EQ(reply.type, static_cast<std::uint16_t>(MessageType::error));
        EXPECT_EQ(reply.body.at("code").get<std::string>(), "cancelled") << reply.body.dump();
    }
    const auto frame = render(client, {{"scene", "cornell"}, {"method", "reference"}, {"width", 16}, {"height", 16},
                                       {"knobs", {{"spp", 1}}}});
    EXPECT_EQ(frame.width, 16);
}

// Validation happens before queueing: an unknown knob or method is refused with the field's
// fault, and a malformed `hello` field is a bad request, not the end of the connection.
TEST(Daemon, FieldsAreCheckedBeforeQueueingAndHelloSurvivesBadTypes) {
    DaemonProcess daemon;
    Client client(daemon.endpoint());
    expect_error([&] { client.request(MessageType::render, {{"scene", "cornell"}, {"method", "photon"}}); },
                 ErrorCode::bad_request);
    expect_error([&] { client.request(MessageType::render, {{"scene", "cornell"}, {"knobs", {{"warp", 1}}}}); },
                 ErrorCode::bad_request);
    expect_error([&] { client.request(MessageType::bake, {{"scene", "cornell"}, {"method", "reference"}}); },
                 ErrorCode::bad_request, "method");
    expect_error([&] { client.request(MessageType::light_set, {{"scene", "cornell"}, {"light", "l"},
                                                                {"position", {1e39, 0, 0}}}); },
                 ErrorCode::bad_request, "position");
    for (const json& protocol : {json("1"), json::array({1}), json(-1)}) {
        expect_error([&] { client.request(MessageType::hello, {{"protocol", protocol}}); }, ErrorCode::bad_request,
                     "protocol");
    }
    EXPECT_EQ(client.request(MessageType::ping).type, static_cast<std::uint16_t>(MessageType::pong));
}

// `bounced --render-once` renders every method, the CPU reference included (without a GL
// context), and writes a decodable frame of the asked size.
TEST(RenderOnce, WritesAFrameForEveryMethod) {
    const auto directory = std::filesystem::temp_directory_path() / ("bounce-render-once-" + std::to_string(::getpid()));
    std::filesystem::create_directories(directory);
    for (const std::string method : {"direct", "reference"}) {
        const auto out = directory / (method + ".png");
        const std::string command = std::string(BOUNCED_PATH) + " --render-once " + out.string() + " --method " + method +
                                    " --preset draft --size 24x16 --log-level warn";
        ASSERT_EQ(std::system(command.c_str()), 0) << command;
        std::ifstream in(out, std::ios::binary);
        const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const auto image = image::decode_image(bytes);
        EXPECT_EQ(image.width, 24) << method;
        EXPECT_EQ(image.height, 16) << method;
    }
    std::filesystem::remove_all(directory);
}

}  // namespace
}  // namespace bounce::test
