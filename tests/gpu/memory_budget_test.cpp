// The memory budget: each method's estimate against what it then holds, and frames past the budget
// refused before anything is allocated, with advice that holds.
#include "gpu_fixture.hpp"
#include "renderer/base/error.hpp"
#include "renderer/memory_admission.hpp"
#include "renderer/scene/builtin.hpp"
#include "renderer/scene/gltf_import.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <regex>

namespace bounce::test {
namespace {

// Restores the shared renderer's budget however a test ends.
class BudgetScope {
public:
    BudgetScope(Renderer& renderer, std::uint64_t bytes) : renderer_(renderer), saved_(renderer.memory_budget()) {
        renderer.set_memory_budget({bytes, "a test's budget"});
    }
    ~BudgetScope() { renderer_.set_memory_budget(saved_); }

private:
    Renderer& renderer_;
    gpu::MemoryBudget saved_;
};

scene::Scene cornell_with_point_lights(int count) {
    scene::Scene scene = scene::make_cornell_box();
    const scene::Light first = scene.lights.at(0);
    scene.lights.clear();
    for (int i = 0; i < count; ++i) {
        scene::Light light = first;
        light.name = "light" + std::to_string(i);
        light.type = scene::LightType::point;
        light.position.x += 0.01f * static_cast<float>(i);
        scene.lights.push_back(light);
    }
    return scene;
}

// The message of the ResourceExhausted a frame is refused with; empty where it was rendered.
std::string refusal(Renderer& renderer, SceneResources& resources, const RenderRequest& request) {
    try {
        renderer.render(resources, request);
    } catch (const ResourceExhausted& error) {
        return error.what();
    }
    return {};
}

// A frame past the budget: refused naming `structure`, with nothing allocated for it, and the value
// of `knob` its message advises; nullopt (and a failure) otherwise.
std::optional<int> advised_value(Renderer& renderer, SceneResources& resources, const RenderRequest& request,
                                 const std::string& structure, const std::string& knob) {
    const std::uint64_t before = resources.resident_bytes();
    const std::string message = refusal(renderer, resources, request);
    if (message.empty()) {
        ADD_FAILURE() << "a frame past the budget was rendered";
        return std::nullopt;
    }
    EXPECT_EQ(resources.resident_bytes(), before) << "nothing may be allocated for a refused frame";
    EXPECT_NE(message.find("'" + structure + "'"), std::string::npos) << message;
    std::smatch match;
    if (!std::regex_search(message, match, std::regex(knob + "=([0-9]+) would fit"))) {
        ADD_FAILURE() << "no " << knob << " advised: " << message;
        return std::nullopt;
    }
    return std::stoi(match[1]);
}

std::uint64_t held(const std::vector<methods::ResidentStructure>& resident, const std::string& name) {
    for (const auto& structure : resident) {
        if (structure.name == name) return structure.bytes;
    }
    ADD_FAILURE() << "no resident structure " << name;
    return 0;
}

// Structures whose size the knobs, the lights and the frame size fix: the estimate is what the method
// then holds, to the byte. The light-view maps are an upper bound (views that miss the scene are
// culled; the Cornell box's point light sees it through all six).
TEST(MemoryBudget, ClosedFormEstimatesMatchWhatMethodsHold) {
    const scene::Scene scene = cornell_with_point_lights(2);
    const struct {
        std::string method;
        std::vector<std::pair<std::string, std::string>> exact;  // estimate name, resident name
        methods::KnobValues knobs = {};
    } cases[] = {
        {"direct", {{"gbuffer", "gbuffer"}, {"shadow_maps", "shadow_maps"}}},
        {"vct", {{"gbuffer", "gbuffer"}, {"shadow_maps", "shadow_maps"}, {"light_view_maps", "light_view_maps"}}},
        {"isr",
         {{"gbuffer", "gbuffer"},
          {"shadow_maps", "shadow_maps"},
          {"reflective_shadow_maps", "reflective_shadow_maps"},
          {"vpl_tree", "vpl_tree"},
          {"multires_atlas", "multires_atlas"}}},
        {"cssm", {{"gbuffer", "gbuffer"}, {"shadow_maps", "shadow_maps"}}},
        {"isr", {{"imperfect_shadow_maps", "imperfect_shadow_maps"}}, {{"ism_size", 16}}},
    };
    for (const auto& c : cases) {
        SCOPED_TRACE(c.method);
        const RenderRequest request = method_request(c.method, "draft", 40, c.knobs);
        const FramePlan plan = plan_frame(request);
        const auto& info = methods::MethodRegistry::builtin().find(c.method);
        const methods::MemoryEstimate estimate = info.estimate({scene, plan.knobs, 40, 40});
        const RenderResult result = render_scene(scene, request);
        for (const auto& [estimated, resident] : c.exact) {
            const auto it = std::find_if(estimate.begin(), estimate.end(), [&](const auto& s) { return s.name == estimated; });
            ASSERT_NE(it, estimate.end()) << estimated;
            EXPECT_EQ(it->bytes, held(result.stats.resident, c.method + "." + resident)) << estimated;
        }
    }
}

TEST(MemoryBudget, ShadowMapsPastTheBudgetAreRefusedWithASizeThatFits) {
    Renderer& renderer = shared_renderer();
    const scene::Scene scene = cornell_with_point_lights(16);
    auto resources = renderer.upload(scene);
    // 16 point lights x 6 faces x 8192^2 x 4 bytes = 24 GiB of shadow maps; the budget is 64 MiB.
    const BudgetScope budget(renderer, 64ull << 20);
    const RenderRequest huge = method_request("direct", "medium", 32, {{"shadow_map_size", 8192}});
    EXPECT_NE(refusal(renderer, *resources, huge).find("64.0 MiB"), std::string::npos);
    const std::optional<int> advised = advised_value(renderer, *resources, huge, "shadow_maps", "shadow_map_size");
    ASSERT_TRUE(advised.has_value());
    const int fits = *advised;
    // The largest size that fits: 96 maps of fits^2 x 4 bytes with the rest of the frame under 64 MiB.
    EXPECT_GT(fits, 256);
    EXPECT_LT(fits, 8192);

    const RenderResult result = renderer.render(*resources, method_request("direct", "medium", 32, {{"shadow_map_size", fits}}));
    EXPECT_EQ(result.frame.non_finite_count(), 0u);
    EXPECT_LE(renderer.resident_bytes(), 64ull << 20);
    EXPECT_THROW(renderer.render(*resources, method_request("direct", "medium", 32, {{"shadow_map_size", fits + 1}})),
                 ResourceExhausted)
        << "the advice must be the largest size that fits";
}

// isr's imperfect shadow maps at their extremes (a map of 64^2 texels on every texel of a 128^2
// light view: 98304 maps, about 3.7 GB) are refused before anything is allocated, with an
// `ism_size` that fits, and that size renders.
TEST(MemoryBudget, ImperfectShadowMapsPastTheBudgetAreRefusedWithASizeThatFits) {
    Renderer& renderer = shared_renderer();
    const scene::Scene scene = cornell_with_point_lights(1);
    auto resources = renderer.upload(scene);
    const BudgetScope budget(renderer, 256ull << 20);
    const methods::KnobValues extreme = {{"ism_size", 64}, {"ism_points", 16384}, {"ism_levels_below_top", 3}};
    const std::optional<int> advised =
        advised_value(renderer, *resources, method_request("isr", "low", 32, extreme), "imperfect_shadow_maps", "ism_size");
    ASSERT_TRUE(advised.has_value());
    ASSERT_GT(*advised, 0);
    methods::KnobValues fitting = extreme;
    fitting["ism_size"] = *advised;
    fitting["ism_points"] = 16;  // memory does not depend on it; time on a software rasterizer does
    const RenderResult result = renderer.render(*resources, method_request("isr", "low", 32, fitting));
    EXPECT_EQ(result.frame.non_finite_count(), 0u);
    EXPECT_LE(renderer.resident_bytes(), 256ull << 20);
}

// What the planner asks before it offers a plan (Renderer::memory_refusal) is what render() would
// say. Under a budget of 1.25 times what isr draft holds, isr low's imperfect shadow maps (64^2 texels
// on each of a point light's six views' 32^2 patches: 229 MiB) do not fit, and draft does.
TEST(MemoryBudget, TheRefusalThePlannerReadsIsTheOneRenderWouldThrow) {
    Renderer& renderer = shared_renderer();
    const scene::Scene scene = cornell_with_point_lights(1);
    auto resources = renderer.upload(scene);
    const RenderRequest draft = method_request("isr", "draft", 32), low = method_request("isr", "low", 32);
    renderer.render(*resources, draft);
    const BudgetScope budget(renderer, renderer.resident_bytes() / 4 * 5);
    EXPECT_FALSE(renderer.memory_refusal(*resources, draft).has_value());
    EXPECT_FALSE(renderer.memory_refusal(*resources, method_request("reference", "draft", 32)).has_value());  // CPU
    const std::optional<std::string> refused = renderer.memory_refusal(*resources, low);
    ASSERT_TRUE(refused.has_value());
    std::printf("isr low under %.0f MB: %s\n", static_cast<double>(renderer.memory_budget().bytes) / 1e6, refused->c_str());
    EXPECT_NE(refused->find("'imperfect_shadow_maps'"), std::string::npos) << *refused;
    EXPECT_EQ(refusal(renderer, *resources, low), *refused);
    EXPECT_EQ(refusal(renderer, *resources, draft), "");  // what the planner lets through renders
}

TEST(MemoryBudget, WhatOtherScenesHoldCountsAndAFrameSizeIsAdvised) {
    Renderer& renderer = shared_renderer();
    const scene::Scene first_scene = scene::make_cornell_box(), second_scene = scene::make_cornell_box();
    auto first = renderer.upload(first_scene);
    auto second = renderer.upload(second_scene);
    const RenderRequest request = method_request("direct", "draft", 256, {});
    renderer.render(*first, request);
    const std::uint64_t first_holds = first->resident_bytes();
    // Room for the second scene's frame, and for half of what the first one holds.
    std::uint64_t frame_bytes = 0;
    for (const auto& structure : frame_estimate(methods::MethodRegistry::builtin().find("direct"),
                                                {second_scene, plan_frame(request).knobs, 256, 256})) {
        frame_bytes += structure.bytes;
    }
    const BudgetScope budget(renderer, frame_bytes + first_holds / 2);
    const std::string message = refusal(renderer, *second, request);
    ASSERT_FALSE(message.empty()) << "the second scene's frame fit beside the first";
    EXPECT_NE(message.find("held by resident scenes"), std::string::npos) << message;
    EXPECT_NE(message.find("'gbuffer'"), std::string::npos) << message;
    EXPECT_NE(message.find("a frame of"), std::string::npos) << message;
    first.reset();  // unloading the first scene frees room for the second's frame
    EXPECT_NO_THROW(renderer.render(*second, request));
}

// A scene's GPU copy is estimated before upload, to the byte (a textured glTF: vertex and index
// buffers, and its texture with every mip level); past the budget with what is resident, the upload
// is refused and nothing is allocated.
TEST(MemoryBudget, ScenesAreCountedBeforeTheyAreUploaded) {
    Renderer& renderer = shared_renderer();
    const scene::Scene textured = scene::import_gltf_file("/usr/share/assimp/models/glTF2/BoxTextured-glTF/BoxTextured.gltf");
    ASSERT_FALSE(textured.textures.empty());
    const std::uint64_t estimate = gpu::GpuScene::bytes_for(textured);
    {
        auto resources = renderer.upload(textured);
        EXPECT_EQ(resources->resident_bytes(), estimate);
    }
    const BudgetScope budget(renderer, renderer.resident_bytes() + estimate - 1);
    try {
        renderer.upload(textured);
        FAIL() << "the upload passed the budget";
    } catch (const ResourceExhausted& error) {
        EXPECT_NE(std::string(error.what()).find("unload a scene"), std::string::npos) << error.what();
    }
}

}  // namespace
}  // namespace bounce::test
