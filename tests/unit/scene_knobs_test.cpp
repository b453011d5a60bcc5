// Knobs a method leaves to the scene (renderer/scene_knobs.hpp): isr's presets turn the maps'
// dilation off in an open room and keep it behind walls, cssm's bounce tolerance picks bounces, and
// a request's own value always wins.
#include "renderer/methods/registry.hpp"
#include "renderer/scene/builtin.hpp"
#include "renderer/scene_analysis.hpp"
#include "renderer/scene_knobs.hpp"

#include <gtest/gtest.h>

namespace bounce {
namespace {

constexpr float kMm = 0.001f;

SceneAnalysis with_occluded(double fraction, int pairs = 1000) {
    SceneAnalysis analysis;
    analysis.visibility.pairs = pairs;
    analysis.visibility.occluded_fraction = fraction;
    return analysis;
}

// isr's preset knobs as the renderer resolves them on a scene of that analysis, the request's
// `requested` over them.
methods::KnobValues isr_on(const SceneAnalysis& analysis, const std::string& preset, const methods::KnobValues& requested = {}) {
    const auto& registry = methods::MethodRegistry::builtin();
    methods::KnobValues knobs = registry.resolve("isr", preset, requested);
    if (leaves_knobs_to_scene(knobs, requested)) resolve_scene_knobs(analysis, registry.find("isr"), requested, knobs);
    return knobs;
}

double open_below(const std::string& preset) {
    return methods::MethodRegistry::builtin().resolve("isr", preset, {}).at("ism_open_below");
}

TEST(SceneKnobs, IsrsMapsAreDilatedBehindWallsAndNotInTheOpen) {
    for (const std::string preset : {"low", "medium", "high", "ultra"}) {
        const double threshold = open_below(preset);
        EXPECT_EQ(isr_on(with_occluded(0.0), preset).at("ism_dilation"), 0.0) << preset;
        EXPECT_EQ(isr_on(with_occluded(threshold * 0.99), preset).at("ism_dilation"), 0.0) << preset;
        // At the threshold and past it, the preset's own dilation.
        EXPECT_EQ(isr_on(with_occluded(threshold), preset).at("ism_dilation"), 2.0) << preset;
        EXPECT_EQ(isr_on(with_occluded(0.9), preset).at("ism_dilation"), 2.0) << preset;
        // A request's own dilation is kept, either way.
        EXPECT_EQ(isr_on(with_occluded(0.0), preset, {{"ism_dilation", 1}}).at("ism_dilation"), 1.0) << preset;
        EXPECT_EQ(isr_on(with_occluded(0.9), preset, {{"ism_dilation", 0}}).at("ism_dilation"), 0.0) << preset;
        // An analysis that found no pairs of receivers and lights knows nothing of the occlusion.
        EXPECT_EQ(isr_on(with_occluded(0.0, 0), preset).at("ism_dilation"), 2.0) << preset;
    }
    // Without maps there is nothing to dilate, and nothing is asked of the scene.
    const auto& registry = methods::MethodRegistry::builtin();
    EXPECT_FALSE(leaves_knobs_to_scene(registry.resolve("isr", "draft", {}), {}));
    EXPECT_TRUE(leaves_knobs_to_scene(registry.resolve("isr", "low", {}), {}));
    EXPECT_FALSE(leaves_knobs_to_scene(registry.resolve("isr", "low", {}), {{"ism_dilation", 2}}));
    EXPECT_FALSE(leaves_knobs_to_scene(registry.resolve("isr", "low", {{"ism_open_below", 0}}), {{"ism_open_below", 0}}));
}

// On the scenes themselves: the Cornell box is open, and a slab sealing its light in (the bench's
// thin wall, where the maps without dilation leak 3.6 times the light: docs/benchmarks.md) is not.
TEST(SceneKnobs, TheCornellBoxIsOpenAndASlabUnderItsLightIsNot) {
    const SceneAnalysis open = analyze_scene(scene::make_cornell_box());
    EXPECT_EQ(isr_on(open, "high").at("ism_dilation"), 0.0) << open.visibility.occluded_fraction;

    scene::Scene sealed = scene::make_cornell_box();
    scene::add_box(sealed, "slab", glm::vec3(-10.0f, 360.0f, -10.0f) * kMm, glm::vec3(570.0f, 380.0f, 570.0f) * kMm, 0);
    const SceneAnalysis behind = analyze_scene(sealed);
    EXPECT_GT(behind.visibility.pairs, 100);
    EXPECT_EQ(isr_on(behind, "high").at("ism_dilation"), 2.0) << behind.visibility.occluded_fraction;
}

TEST(SceneKnobs, OnlyKnobsAPresetLeavesToTheSceneAreSetByIt) {
    const auto& registry = methods::MethodRegistry::builtin();
    EXPECT_TRUE(set_by_scene(registry.resolve("isr", "low", {}), "ism_dilation"));
    EXPECT_FALSE(set_by_scene(registry.resolve("isr", "draft", {}), "ism_dilation"));
    EXPECT_FALSE(set_by_scene(registry.resolve("isr", "low", {}), "ism_points"));
    EXPECT_FALSE(set_by_scene(registry.resolve("cssm", "low", {}), "bounces"));  // the presets bounce once
    EXPECT_TRUE(set_by_scene(registry.resolve("cssm", "low", {{"bounce_tolerance", 0.05}}), "bounces"));
}

// cssm's bounce tolerance: the fewest bounces whose frame lacks at most that share, in the knob's range.
TEST(SceneKnobs, ABounceToleranceTakesTheBouncesTheAnalysisNeeds) {
    const auto& registry = methods::MethodRegistry::builtin();
    const SceneAnalysis analysis = analyze_scene(scene::make_cornell_box());
    const methods::KnobValues requested{{"bounce_tolerance", 0.05}};
    methods::KnobValues knobs = registry.resolve("cssm", "medium", requested);
    ASSERT_TRUE(leaves_knobs_to_scene(knobs, requested));
    resolve_scene_knobs(analysis, registry.find("cssm"), requested, knobs);
    EXPECT_EQ(knobs.at("bounces"), analysis.bounces.bounces_for(0.05));
    EXPECT_GT(knobs.at("bounces"), 1.0);  // a closed-ish white box carries light past one bounce
}

}  // namespace
}  // namespace bounce
