// The scene analysis on built-in scenes and variants of them built here: bounce energies against
// the theory of enclosures, thin walls against vct's voxel sizes, and indirect visibility where a
// shade closes a lamp in.
#include "renderer/scene/builtin.hpp"
#include "renderer/scene_analysis.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

namespace bounce {
namespace {

constexpr float kMm = 0.001f;
constexpr int kWhite = 0;  // the Cornell box's white material

// The Cornell box closed: a wall across its open front and the camera inside, looking at the back.
scene::Scene closed_box() {
    scene::Scene scene = scene::make_cornell_box();
    scene::add_box(scene, "front_wall", glm::vec3(0.0f, 0.0f, -20.0f) * kMm, glm::vec3(556.0f, 548.8f, 0.0f) * kMm, kWhite);
    scene.cameras.front() = scene::Camera::look_at(glm::vec3(278.0f, 273.0f, 40.0f) * kMm,
                                                   glm::vec3(278.0f, 273.0f, 559.2f) * kMm, {0, 1, 0}, 1.2f);
    return scene;
}

// The box taken apart: its floor alone under the light, with the two blocks.
scene::Scene open_floor() {
    scene::Scene scene = scene::make_cornell_box();
    scene.objects.erase(scene.objects.begin());  // the room (its mesh stays, unused)
    scene::add_box(scene, "floor", glm::vec3(0.0f, -20.0f, 0.0f) * kMm, glm::vec3(556.0f, 0.0f, 559.2f) * kMm, kWhite);
    return scene;
}

// The box split left from right by a wall `thickness` thick, floor to ceiling, front to back, off
// the light's side where the tall block stood (taken out: a wall through a block is no wall).
scene::Scene partitioned(float thickness) {
    scene::Scene scene = scene::make_cornell_box();
    scene.objects.erase(scene.objects.begin() + static_cast<std::ptrdiff_t>(*scene.find_object("tall_block")));
    const float x = 400.0f * kMm;
    scene::add_box(scene, "partition", {x, 0.0f, 0.0f}, {x + thickness, 548.8f * kMm, 559.2f * kMm}, kWhite);
    return scene;
}

// The light closed in a shade: an open-bottomed box around it, as a lamp in a furnished room.
scene::Scene shaded_lamp() {
    scene::Scene scene = scene::make_cornell_box();
    const glm::vec3 light = scene.lights.front().position;
    const float half = 0.06f, wall = 0.004f;
    const glm::vec3 lo = light - glm::vec3(half, 0.12f, half), hi = light + glm::vec3(half, 0.06f, half);
    // Four walls and a lid; the bottom stays open, so the light reaches the floor under the shade.
    scene::add_box(scene, "shade_left", lo, {lo.x + wall, hi.y, hi.z}, kWhite);
    scene::add_box(scene, "shade_right", {hi.x - wall, lo.y, lo.z}, hi, kWhite);
    scene::add_box(scene, "shade_front", lo, {hi.x, hi.y, lo.z + wall}, kWhite);
    scene::add_box(scene, "shade_back", {lo.x, lo.y, hi.z - wall}, hi, kWhite);
    scene::add_box(scene, "shade_lid", {lo.x, hi.y - wall, lo.z}, hi, kWhite);
    return scene;
}

TEST(SceneAnalysis, BounceSharesSumToOneAndDirectLightComesFirst) {
    const SceneAnalysis analysis = analyze_scene(scene::make_cornell_box());
    const BounceEnergy& energy = analysis.bounces;
    ASSERT_EQ(energy.share.size(), 13u);  // direct and 12 bounces
    EXPECT_NEAR(std::accumulate(energy.share.begin(), energy.share.end(), 0.0) + energy.tail, 1.0, 1e-9);
    for (double share : energy.share) EXPECT_GE(share, 0.0);
    EXPECT_GT(energy.share[0], energy.share[1]);
    EXPECT_EQ(energy.bounces_for(1.0), 0);
    // Per bounce count, from one trace's prefixes: the frame of every bounce lacks nothing, and a
    // sample costs more the further its path may go (the Cornell box's paths go on past the first
    // vertex: each bounce count adds the vertices shaded after it, at a positive cost).
    ASSERT_EQ(energy.stopped_error.size(), 13u);
    ASSERT_EQ(energy.noise_per_sample.size(), 13u);
    ASSERT_EQ(energy.sample_ns.size(), 13u);
    EXPECT_EQ(energy.stopped_error[12], 0.0);
    ASSERT_EQ(energy.noise_against_whole.size(), 13u);
    EXPECT_EQ(energy.noise_against_whole[12], energy.noise_per_sample[12]);
    for (std::size_t k = 0; k < 12; ++k) EXPECT_LE(energy.noise_against_whole[k], energy.noise_per_sample[k]) << k;
    EXPECT_GT(energy.stopped_error[0], energy.stopped_error[1]);
    EXPECT_GT(energy.sample_ns[0], 0.0);
    // Non-decreasing by construction (each count adds its vertices at a cost clamped at zero); that a
    // vertex costs more than nothing is a timing, which a loaded machine can read as zero, so it is
    // not asserted here.
    for (std::size_t k = 1; k < energy.sample_ns.size(); ++k) EXPECT_GE(energy.sample_ns[k], energy.sample_ns[k - 1]) << k;
}

// Each bounce's light against the one before, past a bounce count: over three bounces, capped at
// 0.95, and 0 where the shares end.
TEST(SceneAnalysis, TheLightRatioPastABounceCountReadsTheShares) {
    BounceEnergy energy;
    for (int k = 0; k <= 12; ++k) energy.share.push_back(std::pow(0.5, k));
    EXPECT_DOUBLE_EQ(energy.light_ratio_past(2), 0.5);
    EXPECT_DOUBLE_EQ(energy.light_ratio_past(11), 0.5);  // one pair left
    EXPECT_EQ(energy.light_ratio_past(12), 0.0);
    energy.share.assign(13, 0.1);
    EXPECT_DOUBLE_EQ(energy.light_ratio_past(3), 0.95);
    EXPECT_EQ(BounceEnergy{}.light_ratio_past(0), 0.0);
}

// In a closed room every bounce lands on a wall, so each bounce carries about the walls' mean
// albedo times the last (the transport operator's largest eigenvalue): never more than the
// brightest albedo, 0.725. On an open floor most light leaves after one bounce.
TEST(SceneAnalysis, AClosedBoxNeedsMoreBouncesThanAnOpenOne) {
    const BounceEnergy closed = analyze_scene(closed_box()).bounces;
    const BounceEnergy open = analyze_scene(open_floor()).bounces;
    for (const double tolerance : {0.1, 0.05, 0.02}) {
        RecordProperty("closed_" + std::to_string(tolerance), closed.bounces_for(tolerance));
        RecordProperty("open_" + std::to_string(tolerance), open.bounces_for(tolerance));
        EXPECT_GT(closed.bounces_for(tolerance), open.bounces_for(tolerance)) << "tolerance " << tolerance;
    }
    // Bounces 4 to 8 against 3 to 7: the common-random-number differences are smooth enough there.
    const double later = closed.share[4] + closed.share[5] + closed.share[6] + closed.share[7] + closed.share[8];
    const double earlier = closed.share[3] + closed.share[4] + closed.share[5] + closed.share[6] + closed.share[7];
    const double ratio = later / earlier;
    RecordProperty("closed_ratio", std::to_string(ratio));
    EXPECT_GT(ratio, 0.4);
    EXPECT_LT(ratio, 0.725);
    EXPECT_LT(open.bounces_for(0.02), 4);
}

TEST(SceneAnalysis, AThinWallIsFlaggedForVctAndAThickOneIsNot) {
    const ThinWalls plain = analyze_scene(scene::make_cornell_box()).thin_walls;
    const ThinWalls thin = analyze_scene(partitioned(0.004f)).thin_walls;  // thinner than every preset's voxel
    const ThinWalls thick = analyze_scene(partitioned(0.1f)).thin_walls;   // thicker than every preset's voxel
    ASSERT_EQ(plain.presets.size(), 5u);
    for (const auto& [name, preset] : thin.presets) {
        SCOPED_TRACE(name);
        EXPECT_GT(preset.voxel_size, 0.004);
        EXPECT_LT(preset.voxel_size, 0.1);
        EXPECT_FALSE(plain.leaks(name)) << plain.presets.at(name).leaking_area;
        EXPECT_TRUE(thin.leaks(name));
        EXPECT_FALSE(thick.leaks(name)) << thick.presets.at(name).leaking_area;
        // Light leaks from a lit face: the partition's face towards the light, 0.307 m² of the
        // scene's 2.29 m² (room 1.538, short block 0.137, partition 0.618), so 0.134; 4096 samples
        // give a binomial deviation of 0.0053, and the tolerance is four of them.
        EXPECT_NEAR(preset.leaking_area, 0.134, 0.021);
        RecordProperty("thin_" + name, std::to_string(preset.leaking_area));
        RecordProperty("thick_" + name, std::to_string(thick.presets.at(name).leaking_area));
        RecordProperty("plain_" + name, std::to_string(plain.presets.at(name).leaking_area));
    }
    EXPECT_NEAR(thin.thinnest_separator, 0.004, 0.001);
}

// A shade around the lamp: the light's first bounces are inside it, and nearly every surface the
// camera sees is hidden from them, which isr (no indirect visibility) cannot know.
TEST(SceneAnalysis, AShadedLampRulesOutUnoccludedGathering) {
    const IndirectVisibility open = analyze_scene(scene::make_cornell_box()).visibility;
    const IndirectVisibility shaded = analyze_scene(shaded_lamp()).visibility;
    EXPECT_GT(open.pairs, 500);
    EXPECT_GT(shaded.pairs, 500);
    RecordProperty("open_occluded", std::to_string(open.occluded_fraction));
    RecordProperty("shaded_occluded", std::to_string(shaded.occluded_fraction));
    EXPECT_FALSE(open.mostly_occluded()) << open.occluded_fraction;
    EXPECT_TRUE(shaded.mostly_occluded()) << shaded.occluded_fraction;
}

TEST(SceneAnalysis, ASceneWithoutLightsOrSurfacesIsAnsweredNotCrashed) {
    scene::Scene dark = scene::make_cornell_box();
    dark.lights.clear();
    const SceneAnalysis analysis = analyze_scene(dark);
    EXPECT_EQ(analysis.visibility.pairs, 0);
    EXPECT_EQ(analysis.bounces.bounces_for(0.01), 0);
    scene::Scene empty;
    const SceneAnalysis nothing = analyze_scene(empty);
    EXPECT_EQ(nothing.thin_walls.thinnest_separator, -1.0);
}

}  // namespace
}  // namespace bounce
