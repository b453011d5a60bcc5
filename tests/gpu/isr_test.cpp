// Method `isr` against the path-traced reference with the one bounce it models: with indirect
// visibility (the truth) and without it (what the paper's method computes: every directly lit
// surface lights every point it faces), per preset, per light type and at the thresholds' limits;
// its upsampling, its VPL selection modes, and what it keeps between frames.
#include "bench/extremes.hpp"
#include "gpu_fixture.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/methods/registry.hpp"
#include "renderer/scene/builtin.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <string>

namespace bounce::test {
namespace {

constexpr int kSize = 64;

image::Frame reference_frame(const scene::Scene& scene, bool indirect_visibility, int spp, int bounces = 1) {
    methods::reference::PathTracerSettings settings;
    settings.max_bounces = bounces;
    settings.indirect_visibility = indirect_visibility;
    return pixel_centre_reference(scene, kSize, spp, settings);
}

// The Cornell box's two references, traced once for the whole test program.
const image::Frame& cornell_reference(bool indirect_visibility) {
    static const image::Frame with = reference_frame(scene::make_cornell_box(), true, 1024);
    static const image::Frame without = reference_frame(scene::make_cornell_box(), false, 1024);
    return indirect_visibility ? with : without;
}

RenderRequest isr_request(const std::string& preset, methods::KnobValues knobs = {}) {
    return method_request("isr", preset, kSize, std::move(knobs));
}

RenderResult render_isr(const scene::Scene& scene, const std::string& preset, methods::KnobValues knobs = {}) {
    return render_scene(scene, isr_request(preset, std::move(knobs)));
}

// Every pixel gathers, from every light-view texel: no eye-space or light-space clustering left.
const methods::KnobValues kFullGather = {{"levels", 1}, {"mode", 2}, {"tau", 0}, {"max_depth", 11}, {"ism_size", 0}};

// The paper's isr, without indirect visibility: the presets from low up make imperfect shadow maps.
methods::KnobValues without_visibility(methods::KnobValues knobs = {}) {
    knobs["ism_size"] = 0;
    return knobs;
}

// `direct` with isr's shadow maps: subtracted from an isr frame, it leaves the indirect light.
image::Frame direct_frame(const scene::Scene& scene) {
    return render_scene(scene, method_request("direct", "high", kSize, {{"shadow_map_size", 2048}})).frame;
}

image::Frame difference(image::Frame a, const image::Frame& b) {
    for (std::size_t i = 0; i < a.rgba.size(); ++i) {
        if (i % 4 != 3) a.rgba[i] -= b.rgba[i];
    }
    return a;
}

// An isr frame's indirect light (minus `direct`) against the unoccluded reference's (one bounce
// minus none).
image::ErrorMetrics indirect_error(const scene::Scene& scene, const image::Frame& frame) {
    return image::compare(difference(frame, direct_frame(scene)),
                          difference(reference_frame(scene, false, 1024), reference_frame(scene, true, 64, 0)));
}

double stat(const RenderResult& result, const char* name) { return result.stats.method_statistics.at(name); }

// A floor, and a wall behind it lit by `light`; the floor's light is mostly what the wall reflects.
// Seen from above.
scene::Scene wall_and_floor(const scene::Light& light) {
    scene::Scene scene;
    scene.materials.push_back(matte({0.8f, 0.8f, 0.8f}));
    scene.materials.push_back(matte({0.9f, 0.5f, 0.3f}));
    add_square(scene, "floor", {0.0f, 0.0f, 0.0f}, 1.0f, {0.0f, 1.0f, 0.0f}, 0);
    add_square(scene, "wall", {0.0f, 1.0f, -1.0f}, 1.0f, {0.0f, 0.0f, 1.0f}, 1);
    scene.lights.push_back(light);
    scene.cameras.push_back(top_down_camera(3.0f, 0.9f));
    return scene;
}

scene::Light light_of_type(scene::LightType type) {
    scene::Light light;
    light.type = type;
    light.position = {0.0f, 1.0f, 0.2f};
    // Spot: at the wall; directional: down onto the wall and the floor.
    light.direction = glm::normalize(type == scene::LightType::directional ? glm::vec3(0.0f, -0.5f, -1.0f)
                                                                            : glm::vec3(0.0f, 0.15f, -1.0f));
    light.intensity = type == scene::LightType::directional ? 3.0f : 4.0f;
    light.inner_cone = 0.5f;
    light.outer_cone = 0.9f;  // wider than the paper's 90-degree spot
    return light;
}

// Against the reference with the one bounce isr models, per preset (medium is the default).
// Measured on llvmpipe (64x64), hierarchical mode: against the reference without indirect
// visibility, relMSE draft 0.0031, low 0.0025, medium 0.0018, high 0.0014, ultra 0.0011 (draft
// 0.0142 while its eye-space patches spanned normals 0.5 apart, low's 0.4: 0.0026); against
// the true reference 0.108-0.111 at every preset, means 3-4% high. The two references differ by
// relMSE 0.107 (mean 3% apart): nearly all of isr's error is the visibility the paper ignores
// (the blocks' inner faces and the floor between them receive light through the blocks).
TEST(Isr, CornellAgainstReferencePerPreset) {
    const scene::Scene scene = scene::make_cornell_box();
    const image::Frame& truth = cornell_reference(true);
    const image::Frame& unoccluded = cornell_reference(false);
    const double visibility = image::compare(unoccluded, truth).rel_mse;
    std::printf("reference without indirect visibility: relMSE %.4f against the reference\n", visibility);
    double previous = 1e30, draft = 0.0, ultra = 0.0;
    for (const std::string preset : {"draft", "low", "medium", "high", "ultra"}) {
        const auto result = render_isr(scene, preset, without_visibility());
        const image::ErrorMetrics error = image::compare(result.frame, truth);
        const image::ErrorMetrics approximation = image::compare(result.frame, unoccluded);
        std::printf("isr %-6s relMSE %.4f (without visibility %.4f) mean %.4f vs %.4f; VPLs per fragment %.0f\n",
                    preset.c_str(), error.rel_mse, approximation.rel_mse, error.mean_test, error.mean_reference,
                    stat(result, "vpls_per_fragment_mean"));
        EXPECT_EQ(error.non_finite_test, 0u) << preset;
        EXPECT_NEAR(error.mean_test, error.mean_reference, 0.06 * error.mean_reference) << preset;
        EXPECT_LE(error.rel_mse, 0.15) << preset;
        EXPECT_LE(approximation.rel_mse, 1.10 * previous) << preset;  // tighter thresholds, smaller error
        // Visibility's share: at every preset isr's own approximation is under a twentieth of the
        // error (draft's was 0.13 of it while its eye-space patches spanned normals 0.5 apart).
        EXPECT_LE(approximation.rel_mse, 0.05 * visibility) << preset;
        if (preset == "high") EXPECT_LE(approximation.rel_mse, 0.004);
        if (preset == "draft") draft = approximation.rel_mse;
        if (preset == "ultra") ultra = approximation.rel_mse;
        previous = approximation.rel_mse;
    }
    // The presets buy something: ultra's approximation at most half draft's.
    EXPECT_LT(ultra, 0.5 * draft);
}

// With no clustering left, isr computes exactly the integral the unoccluded reference estimates:
// measured relMSE 0.0012 with means 0.03% apart. Naive sampling and basic clustering at the finest
// level gather the same VPLs as the full traversal, so all three give one image.
TEST(Isr, FullGatherMatchesTheUnoccludedReference) {
    const scene::Scene scene = scene::make_cornell_box();
    const auto hierarchical = render_isr(scene, "low", kFullGather);
    const image::ErrorMetrics error = image::compare(hierarchical.frame, cornell_reference(false));
    std::printf("full gather: relMSE %.5f mean %.5f vs %.5f\n", error.rel_mse, error.mean_test, error.mean_reference);
    EXPECT_LE(error.rel_mse, 0.003);
    EXPECT_NEAR(error.mean_test, error.mean_reference, 0.01 * error.mean_reference);

    methods::KnobValues knobs = kFullGather;
    knobs["mode"] = 0;
    const auto naive = render_isr(scene, "low", knobs);
    knobs["mode"] = 1;
    knobs["depth_threshold"] = 0;  // every light patch splits: basic keeps every texel
    knobs["normal_threshold"] = 0;
    const auto basic = render_isr(scene, "low", knobs);
    EXPECT_EQ(stat(naive, "vpl_cache"), stat(basic, "vpl_cache"));
    EXPECT_EQ(stat(hierarchical, "vpls_per_fragment_max"), stat(naive, "vpl_cache"));  // tau 0 opens every patch
    EXPECT_LE(image::compare(naive.frame, hierarchical.frame).rel_mse, 1e-8);
    EXPECT_LE(image::compare(basic.frame, hierarchical.frame).rel_mse, 1e-8);
}

// Eqs. 2-5 for every light type: the full gather's indirect light (isr minus `direct`) against the
// unoccluded reference's (one bounce minus none) on a wall that lights a floor, with a spot wider
// than the paper's 90 degrees, a point light (six views) and a directional light (an orthographic
// view). Measured relMSE: spot 0.0003, point 0.0010, directional 0.0013; means within 1%.
// (The direct light is taken out: in this symmetric view the pixel centres of two diagonals meet
// the wall's side edges exactly, where raster draws the lit edge and the path tracer's edge hits
// come back black; relMSE 0.011 and 0.068 in the whole frames, none of it isr's.)
TEST(Isr, EveryLightTypeMatchesTheUnoccludedReference) {
    for (const auto type : {scene::LightType::spot, scene::LightType::point, scene::LightType::directional}) {
        const scene::Scene scene = wall_and_floor(light_of_type(type));
        const auto result = render_isr(scene, "low", kFullGather);
        const image::ErrorMetrics error = indirect_error(scene, result.frame);
        std::printf("light type %d: indirect relMSE %.5f mean %.5f vs %.5f, %g views (%g culled)\n",
                    static_cast<int>(type), error.rel_mse, error.mean_test, error.mean_reference,
                    stat(result, "rsm_views"), stat(result, "rsm_views_culled"));
        EXPECT_LE(error.rel_mse, 0.004) << static_cast<int>(type);
        EXPECT_NEAR(error.mean_test, error.mean_reference, 0.02 * error.mean_reference) << static_cast<int>(type);
    }
}

// A point light above everything: its upward cube face sees nothing of the scene and is not drawn,
// and nothing is lost by it.
TEST(Isr, LightViewsThatCannotSeeTheSceneAreNotDrawn) {
    scene::Light light = light_of_type(scene::LightType::point);
    light.position = {0.0f, 2.5f, 0.0f};
    const scene::Scene scene = wall_and_floor(light);
    const auto result = render_isr(scene, "low", kFullGather);
    EXPECT_EQ(stat(result, "rsm_views"), 5.0);
    EXPECT_EQ(stat(result, "rsm_views_culled"), 1.0);
    const image::ErrorMetrics error = indirect_error(scene, result.frame);
    std::printf("point light above the scene: indirect relMSE %.5f mean %.5f vs %.5f\n", error.rel_mse,
                error.mean_test, error.mean_reference);
    EXPECT_LE(error.rel_mse, 0.004);
    EXPECT_NEAR(error.mean_test, error.mean_reference, 0.02 * error.mean_reference);
}

// Depth and normal thresholds of zero split every patch: every covered pixel gathers on its own,
// and the image is the single-level one.
TEST(Isr, ZeroThresholdsGatherAtEveryPixel) {
    const scene::Scene scene = scene::make_cornell_box();
    const auto single = render_isr(scene, "low", {{"levels", 1}});
    const auto multires = render_isr(scene, "low", {{"levels", 6}, {"depth_threshold", 0}, {"normal_threshold", 0}});
    EXPECT_EQ(stat(multires, "multires_fragments"), stat(multires, "multires_fragments_level_0"));
    EXPECT_EQ(stat(multires, "multires_fragments"), stat(single, "multires_fragments"));
    EXPECT_LE(image::compare(multires.frame, single.frame).rel_mse, 1e-8);
    // The default thresholds gather at far fewer fragments, and the stenciled gather reaches exactly
    // the fragments the refinement marked (none of the atlas's other texels).
    const auto coarse = render_isr(scene, "low");
    EXPECT_LT(stat(coarse, "multires_fragments"), 0.5 * stat(single, "multires_fragments"));
    EXPECT_EQ(stat(coarse, "gathered_texels"), stat(coarse, "multires_fragments"));
    EXPECT_EQ(stat(multires, "gathered_texels"), stat(multires, "multires_fragments"));
}

// Upsampling blends neighbouring patches through every level between them: a floor lit by a wall
// comes out of five levels of patches (up to 16 pixels wide) with no steps at patch borders: on the
// floor away from the wall, no two neighbouring pixels of indirect light differ much more than the
// per-pixel gather's neighbours do (nearest-patch upsampling would step by the gradient times a
// patch width there).
// Near the wall, where irradiance rises steeply, coarse patches read low: that is the eye-space
// clustering error the thresholds trade (paper Fig. 9), bounded here by relMSE.
TEST(Isr, UpsamplingLeavesNoStairSteps) {
    const scene::Scene scene = wall_and_floor(light_of_type(scene::LightType::spot));
    const auto fine = render_isr(scene, "low", {{"levels", 1}, {"tau", 0}});
    const auto coarse = render_isr(scene, "low", {{"levels", 5}, {"tau", 0}, {"depth_threshold", 1}, {"normal_threshold", 1}});
    EXPECT_GT(stat(coarse, "multires_fragments_level_4"), 0.0);
    const image::Frame direct = direct_frame(scene);
    // Largest step of the indirect light between horizontal or vertical neighbours on the floor, away from the wall.
    auto largest_step = [&](const image::Frame& frame) {
        double largest = 0.0;
        for (int y = kSize / 3; y + 1 < kSize; ++y) {
            for (int x = 0; x + 1 < kSize; ++x) {
                const glm::vec4 p = frame.at(x, y) - direct.at(x, y), right = frame.at(x + 1, y) - direct.at(x + 1, y),
                                below = frame.at(x, y + 1) - direct.at(x, y + 1);
                if (frame.at(x, y).a == 0.0f) continue;
                if (frame.at(x + 1, y).a != 0.0f) largest = std::max(largest, std::abs(static_cast<double>(right.g) - p.g));
                if (frame.at(x, y + 1).a != 0.0f) largest = std::max(largest, std::abs(static_cast<double>(below.g) - p.g));
            }
        }
        return largest;
    };
    const double fine_step = largest_step(fine.frame), coarse_step = largest_step(coarse.frame);
    const double rel_mse = image::compare(coarse.frame, fine.frame).rel_mse;
    std::printf("upsampled vs per-pixel: relMSE %.6f, largest neighbour step %.5f vs %.5f, fragments %g vs %g\n",
                rel_mse, coarse_step, fine_step, stat(coarse, "multires_fragments"), stat(fine, "multires_fragments"));
    // Measured: 0.00182 against 0.00182 (the gradient's own step); 16-pixel steps would be ~16x.
    EXPECT_LE(coarse_step, 1.25 * fine_step);
    EXPECT_LE(rel_mse, 2e-3);
}

// Raising tau gathers fewer VPLs per fragment, and the error against the full traversal grows
// (never by more than measurement noise from one tau to the next).
TEST(Isr, TauTradesVplsForError) {
    const scene::Scene scene = scene::make_cornell_box();
    const auto full = render_isr(scene, "medium", {{"tau", 0}, {"max_depth", 11}});
    double previous_vpls = stat(full, "vpls_per_fragment_mean"), previous_error = 0.0;
    for (const double tau : {0.001, 0.01, 0.1, 1.0}) {
        const auto result = render_isr(scene, "medium", {{"tau", tau}, {"max_depth", 11}});
        const double error = image::compare(result.frame, full.frame).rel_mse;
        std::printf("tau %g: %.0f VPLs per fragment, relMSE %.6f against tau 0\n", tau,
                    stat(result, "vpls_per_fragment_mean"), error);
        EXPECT_LT(stat(result, "vpls_per_fragment_mean"), previous_vpls) << tau;
        EXPECT_GE(error, 0.9 * previous_error) << tau;
        previous_vpls = stat(result, "vpls_per_fragment_mean");
        previous_error = error;
    }
    EXPECT_GT(previous_error, 0.0);
}

// The reflective shadow maps and the VPL tree stay while only the camera moves; a light move
// redraws and rebuilds them once.
TEST(Isr, VplTreeKeptWhileOnlyTheCameraMoves) {
    scene::Scene scene = scene::make_cornell_box();
    auto resources = shared_renderer().upload(scene);
    RenderRequest request = isr_request("low");
    shared_renderer().render(*resources, request);
    scene::Camera moved = scene.cameras[0];
    moved.position += glm::vec3(0.05f, 0.0f, 0.0f);
    request.camera = moved;
    const auto camera_moved = shared_renderer().render(*resources, request);
    EXPECT_EQ(stat(camera_moved, "vpl_tree_builds"), 1.0);
    EXPECT_EQ(stat(camera_moved, "rsm_draws"), 1.0);
    scene.lights[0].position += glm::vec3(0.02f, 0.0f, 0.0f);
    const auto light_moved = shared_renderer().render(*resources, request);
    EXPECT_EQ(stat(light_moved, "vpl_tree_builds"), 2.0);
    EXPECT_EQ(stat(light_moved, "rsm_draws"), 2.0);
}

// -- Indirect visibility: imperfect shadow maps (ism_size) ---------------------------------------

const methods::KnobValues kVisibility = {{"ism_size", 32}, {"ism_points", 1024}, {"ism_levels_below_top", 1}};

methods::KnobValues with_visibility(methods::KnobValues knobs) {
    for (const auto& [name, value] : kVisibility) knobs[name] = value;
    return knobs;
}

// The light-view maps hold places, normals and albedo, no power: a light dimmed or recoloured
// rebuilds the VPL tree over the kept maps (each VPL takes its flux from its light), and a light
// moved draws them again. The imperfect shadow maps sit at the tree's flux-weighted patch centres,
// which a light's intensity alone does not move: they are kept for a dimming (and a light a million
// times brighter), made again for a recolouring, a move, or a light turned off. The frames match
// frames rendered afresh at the new lights, indirect light alone: the same maps and the same tree
// passes make the same VPLs, so the bound is float noise (measured 0 on llvmpipe), with and without
// the imperfect shadow maps made afresh. Kept maps were made at patch centres that float rounding
// of the flux-weighted means (and near-ties between equally bright patches, which stand for the
// coarser nodes) put a few ulps from a fresh tree's. So the bound there is what the frame rendered
// afresh moves by when the light moves by 1e-5 of the scene (the bench's imperceptible change,
// bench::change_every_light, a hundred times a rounding's move): measured 5.4e-6 and 1.4e-5 for the
// kept maps (dimmed, and a million times brighter), against 1.1e-5 and 2.1e-5 for such a move.
TEST(Isr, ALightDimmedRebuildsTheVplTreeOverTheKeptMaps) {
    for (const bool visibility : {false, true}) {
        SCOPED_TRACE(visibility ? "with imperfect shadow maps" : "without");
        scene::Scene scene = scene::make_cornell_box();
        auto resources = shared_renderer().upload(scene);
        const RenderRequest request = isr_request("low", visibility ? kVisibility : without_visibility());
        const auto first = shared_renderer().render(*resources, request);
        // What the indirect light rendered afresh moves by when the light moves by 1e-5 of the scene.
        const auto imperceptible_move = [&] {
            scene::Scene nudged = scene;
            nudged.lights[0].position += glm::vec3(1e-5f * glm::length(scene.world_bounds().extent()), 0.0f, 0.0f);
            const image::Frame direct = direct_frame(scene);
            const double moved = image::compare(difference(render_scene(nudged, request).frame, direct_frame(nudged)),
                                                difference(render_scene(scene, request).frame, direct))
                                     .rel_mse;
            std::printf("%s: indirect relMSE %.3g after a move of 1e-5 of the scene\n", visibility ? "ism" : "plain",
                        moved);
            return moved;
        };
        const auto indirect_error = [&](const RenderResult& kept) {
            const image::Frame direct = direct_frame(scene);
            const image::Frame afresh = render_scene(scene, request).frame;
            const image::ErrorMetrics error = image::compare(difference(kept.frame, direct), difference(afresh, direct));
            std::printf("%s: indirect relMSE %.3g against a frame rendered afresh\n", visibility ? "ism" : "plain",
                        error.rel_mse);
            return error.rel_mse;
        };
        const auto kept_maps_bound = [&] { return visibility ? imperceptible_move() : 1e-10; };
        scene.lights[0].intensity *= 0.37f;
        const auto dimmed = shared_renderer().render(*resources, request);
        EXPECT_EQ(dimmed.stats.change, FrameChange::light_power);
        EXPECT_EQ(stat(dimmed, "rsm_draws"), stat(first, "rsm_draws"));
        EXPECT_EQ(stat(dimmed, "vpl_tree_builds"), stat(first, "vpl_tree_builds") + 1.0);
        EXPECT_EQ(stat(dimmed, "ism_builds"), stat(first, "ism_builds"));
        EXPECT_LE(indirect_error(dimmed), kept_maps_bound());
        scene.lights[0].color.g *= 0.5f;  // one channel: not a scale of the light
        const auto recoloured = shared_renderer().render(*resources, request);
        EXPECT_EQ(stat(recoloured, "rsm_draws"), stat(first, "rsm_draws"));
        EXPECT_EQ(stat(recoloured, "vpl_tree_builds"), stat(first, "vpl_tree_builds") + 2.0);
        EXPECT_EQ(stat(recoloured, "ism_builds"), stat(first, "ism_builds") + (visibility ? 1.0 : 0.0));
        EXPECT_LE(indirect_error(recoloured), 1e-10);
        const auto warm = shared_renderer().render(*resources, request);
        EXPECT_EQ(stat(warm, "vpl_tree_builds"), stat(recoloured, "vpl_tree_builds"));
        scene.lights[0].position += glm::vec3(0.02f, 0.0f, 0.0f);
        const auto moved = shared_renderer().render(*resources, request);
        EXPECT_EQ(stat(moved, "rsm_draws"), stat(first, "rsm_draws") + 1.0);
        EXPECT_EQ(stat(moved, "vpl_tree_builds"), stat(first, "vpl_tree_builds") + 3.0);
        EXPECT_EQ(stat(moved, "ism_builds"), stat(first, "ism_builds") + (visibility ? 2.0 : 0.0));
        EXPECT_LE(indirect_error(moved), 1e-10);
        // The extremes: a million times brighter over the kept maps, then turned off, which leaves
        // the light no view (the maps are drawn again, with none of it).
        scene.lights[0].intensity *= 1.0e6f;
        const auto blinding = shared_renderer().render(*resources, request);
        EXPECT_EQ(stat(blinding, "rsm_draws"), stat(moved, "rsm_draws"));
        EXPECT_EQ(stat(blinding, "ism_builds"), stat(moved, "ism_builds"));
        EXPECT_EQ(blinding.frame.non_finite_count(), 0u);
        EXPECT_LE(indirect_error(blinding), kept_maps_bound());
        scene.lights[0].intensity = 0.0f;
        const auto off = shared_renderer().render(*resources, request);
        EXPECT_EQ(stat(off, "rsm_draws"), stat(moved, "rsm_draws") + 1.0);
        EXPECT_EQ(stat(off, "rsm_views"), 0.0);
        EXPECT_EQ(stat(off, "ism_builds"), stat(moved, "ism_builds") + (visibility ? 1.0 : 0.0));
        EXPECT_EQ(off.frame.non_finite_count(), 0u);
        EXPECT_LE(indirect_error(off), 1e-10);
    }
}

// The same on a file as a CAD exporter writes it (assimp's sample 2CylinderEngine: 67 nodes, no
// light of its own: a sun is added): the sun halved rebuilds the tree over the kept maps, keeps
// low's imperfect shadow maps, and the frame's indirect light matches one rendered afresh (float
// noise: measured 0 on llvmpipe, kept maps and all).
TEST(Isr, ASunHalvedOverARealFileRebuildsTheTreeAsRenderedAfresh) {
    scene::Scene file = sunlit_engine();
    auto resources = shared_renderer().upload(file);
    const RenderRequest request = isr_request("low");
    const auto first = shared_renderer().render(*resources, request);
    file.lights.back().intensity *= 0.5f;
    const auto halved = shared_renderer().render(*resources, request);
    EXPECT_EQ(stat(halved, "rsm_draws"), stat(first, "rsm_draws"));
    EXPECT_EQ(stat(halved, "vpl_tree_builds"), stat(first, "vpl_tree_builds") + 1.0);
    EXPECT_GT(stat(halved, "ism_maps"), 0.0);
    EXPECT_EQ(stat(halved, "ism_builds"), stat(first, "ism_builds"));
    const image::Frame direct = direct_frame(file);
    const double error = image::compare(difference(halved.frame, direct),
                                        difference(render_scene(file, request).frame, direct)).rel_mse;
    std::printf("engine, sun halved: indirect relMSE %.3g against a frame rendered afresh\n", error);
    EXPECT_LE(error, 1e-10);
}

// A panel on the left half of the back (1 to 2 m up) lit by a horizontal sun, a floor, and a black
// divider between the panel and the floor's right half. The sun grazes the floor (no direct light there) and nothing reaches the
// right half from the wall: with one bounce its light is exactly zero. Seen from above.
scene::Scene divided_floor() {
    scene::Scene scene;
    scene.materials.push_back(matte({0.8f, 0.8f, 0.8f}));
    scene.materials.push_back(matte({0.9f, 0.5f, 0.3f}));
    scene.materials.push_back(matte({0.0f, 0.0f, 0.0f}));
    add_square(scene, "floor", {0.0f, 0.0f, 0.0f}, 1.0f, {0.0f, 1.0f, 0.0f}, 0);
    add_square(scene, "wall", {-0.5f, 1.5f, -1.0f}, 0.5f, {0.0f, 0.0f, 1.0f}, 1);
    add_square(scene, "divider", {0.0f, 1.0f, 0.0f}, 1.0f, {1.0f, 0.0f, 0.0f}, 2);
    scene.lights.push_back(directional_light({0.0f, 0.0f, -1.0f}, 3.0f));
    scene.cameras.push_back(top_down_camera(3.0f, 0.9f));
    return scene;
}

// Mean luminance over the floor's pixels with x in [x0, x1] (clear of the divider's line).
double floor_mean(const scene::Scene& scene, const image::Frame& frame, float x0, float x1) {
    double sum = 0.0;
    int count = 0;
    for (int y = 0; y < frame.height; ++y) {
        for (int x = 0; x < frame.width; ++x) {
            const glm::vec3 at = pixel_on_ground(scene.cameras[0], frame.width, frame.height, x, y);
            if (at.x < x0 || at.x > x1 || std::abs(at.z) > 0.9f) continue;
            const float* texel = &frame.rgba[4 * (static_cast<std::size_t>(y) * frame.width + x)];
            sum += (texel[0] + texel[1] + texel[2]) / 3.0;
            ++count;
        }
    }
    return count > 0 ? sum / count : 0.0;
}

// Behind the divider the one-bounce light is zero; without visibility isr lights it about half as
// much as the open half. Every ray from the wall to the floor at x > 0.25 meets the divider at most
// 0.8 of the way, so what still reaches it comes through the maps' gaps, where a map holds a sample
// of the floor behind the divider and none of the divider near it: fewer with more points per map.
// The requirements: at least three quarters of the hidden light gone at 1024 points, less left at
// 4096, and at least 85% of the open half's kept (the slope-scaled bias lets a receiver's own
// surface pass; the pull-push fill darkens near the divider's foot). Measured on llvmpipe (64x64):
// 16% and 11% of the hidden light left, 92% of the open half's kept.
TEST(Isr, ImperfectShadowMapsDarkenWhatADividerHides) {
    const scene::Scene scene = divided_floor();
    // Every pixel gathers (levels 1): seen from straight above the divider covers no pixel, and isr's
    // coarser eye-space patches would reach across it (its upsampling, not its visibility).
    const auto open = render_isr(scene, "low", without_visibility({{"levels", 1}}));
    const auto shadowed = render_isr(scene, "low", with_visibility({{"levels", 1}}));
    const image::Frame truth = reference_frame(scene, true, 256);
    const double hidden_open = floor_mean(scene, open.frame, 0.25f, 0.9f);
    const double hidden_shadowed = floor_mean(scene, shadowed.frame, 0.25f, 0.9f);
    const double lit_open = floor_mean(scene, open.frame, -0.9f, -0.1f);
    const double lit_shadowed = floor_mean(scene, shadowed.frame, -0.9f, -0.1f);
    const double lit_truth = floor_mean(scene, truth, -0.9f, -0.1f);
    methods::KnobValues denser = with_visibility({{"levels", 1}});
    denser["ism_points"] = 4096;
    const double hidden_denser = floor_mean(scene, render_isr(scene, "low", denser).frame, 0.25f, 0.9f);
    std::printf("behind the divider: %.5f without visibility, %.5f with, %.5f with 4096 points (reference %.5f); "
                "open half: %.5f, %.5f (reference %.5f); %g maps\n",
                hidden_open, hidden_shadowed, hidden_denser, floor_mean(scene, truth, 0.25f, 0.9f), lit_open, lit_shadowed,
                lit_truth, stat(shadowed, "ism_maps"));
    EXPECT_EQ(stat(shadowed, "indirect_visibility"), 1.0);
    EXPECT_GT(stat(shadowed, "ism_maps"), 0.0);
    EXPECT_GT(hidden_open, 0.2 * lit_open);  // the scene does hide light that isr alone would gather
    EXPECT_LE(hidden_shadowed, 0.25 * hidden_open);
    EXPECT_LT(hidden_denser, hidden_shadowed);
    EXPECT_GE(lit_shadowed, 0.85 * lit_open);
}

// The push's dilation (ism_dilation, shaders/isr/ism_push.comp) lets a nearer surface replace a
// sample behind it: it closes the gaps a sparse near occluder leaves, and dilates every silhouette.
// In the open Cornell box that dilation is most of isr high's error with the maps (bench/quality at
// 128x128: 0.0148 with it, 0.0030 without, docs/benchmarks.md "The maps' hole filling"): without it
// at most half must be left. Behind the divider, without it more of the hidden light must leak
// through the gaps than with it (the bench's thin wall: 0.386 against 0.106).
TEST(Isr, TheMapsDilationTakesLightInTheOpenAndKeepsItFromLeakingBehindWalls) {
    const scene::Scene box = scene::make_cornell_box();
    const image::Frame& truth = cornell_reference(true);
    const double dilated = image::compare(render_isr(box, "high", {{"ism_dilation", 2}}).frame, truth).rel_mse;
    const double filled = image::compare(render_isr(box, "high", {{"ism_dilation", 0}}).frame, truth).rel_mse;
    const scene::Scene divided = divided_floor();
    const auto hidden = [&](double dilation) {
        methods::KnobValues knobs = with_visibility({{"levels", 1}});
        knobs["ism_dilation"] = dilation;
        return floor_mean(divided, render_isr(divided, "low", knobs).frame, 0.25f, 0.9f);
    };
    const double hidden_dilated = hidden(2), hidden_filled = hidden(0);
    std::printf("Cornell box, isr high: relMSE %.5f with the dilation, %.5f without; behind the divider %.5f with, "
                "%.5f without\n",
                dilated, filled, hidden_dilated, hidden_filled);
    EXPECT_LE(filled, 0.5 * dilated);
    EXPECT_GT(hidden_filled, hidden_dilated);
}

// The presets leave the dilation to the scene (`ism_open_below`, renderer/scene_knobs.hpp): the
// open Cornell box renders without it, exactly as if the request had asked for none, and a slab
// sealing its light in (the bench's thin wall, which leaks 3.6 times the light without it) with it;
// a request's own value wins. The frames' stats say what they rendered with.
TEST(Isr, ThePresetsDilateTheMapsBehindWallsAndNotInTheOpen) {
    const scene::Scene box = scene::make_cornell_box();
    const RenderResult preset = render_isr(box, "low");
    EXPECT_EQ(preset.stats.knobs.at("ism_dilation"), 0.0);
    const RenderResult filled = render_isr(box, "low", {{"ism_dilation", 0}});
    EXPECT_EQ(preset.frame.rgba, filled.frame.rgba);
    EXPECT_EQ(render_isr(box, "low", {{"ism_dilation", 2}}).stats.knobs.at("ism_dilation"), 2.0);

    scene::Scene sealed = scene::make_cornell_box();
    scene::add_box(sealed, "slab", {-0.01f, 0.36f, -0.01f}, {0.57f, 0.38f, 0.57f}, 0);
    EXPECT_EQ(render_isr(sealed, "low").stats.knobs.at("ism_dilation"), 2.0);
    EXPECT_EQ(render_isr(sealed, "low", {{"ism_dilation", 0}}).stats.knobs.at("ism_dilation"), 0.0);
}

// What the presets leave to the scene reads its analysis as last made: a frame right after a light
// moves does not analyse the scene again on the render thread (tenths of a second, where a GPU
// renders the frame in milliseconds); the daemon makes it anew on its CPU pool.
TEST(Isr, AFrameAfterALightMovesReadsTheAnalysisAsLastMade) {
    scene::Scene scene = scene::make_cornell_box();
    auto resources = shared_renderer().upload(scene);
    const RenderRequest request = isr_request("low", {});
    EXPECT_EQ(resources->analysis_if_made(), nullptr);
    const auto first = shared_renderer().render(*resources, request);
    ASSERT_TRUE(resources->analysis_current());  // made for the first frame
    EXPECT_EQ(first.stats.knobs.at("ism_dilation"), 0.0);
    scene.lights[0].position += glm::vec3(0.02f, 0.0f, 0.0f);
    const auto moved = shared_renderer().render(*resources, request);
    EXPECT_FALSE(resources->analysis_current());
    EXPECT_EQ(moved.stats.knobs.at("ism_dilation"), 0.0);
}

// The Cornell box against the reference with indirect visibility: CornellAgainstReferencePerPreset
// shows that nearly all of isr's error there is the visibility it lacks (relMSE 0.108 to 0.111 at
// every preset). With the maps at least three quarters of it must go, and the mean come nearer the
// reference's. Measured on llvmpipe (64x64), with these maps of 32^2 texels and 1024 points left
// undilated in the open box (ism_open_below): relMSE 0.0121 (draft) and 0.0183 (medium), means 2.7%
// under and 0.9% over the reference's where they were 3.4% over.
TEST(Isr, ImperfectShadowMapsBringTheCornellBoxToTheOccludedReference) {
    const scene::Scene scene = scene::make_cornell_box();
    const image::Frame& truth = cornell_reference(true);
    for (const std::string preset : {"draft", "medium"}) {
        const auto open = render_isr(scene, preset, without_visibility());
        const auto shadowed = render_isr(scene, preset, kVisibility);
        const image::ErrorMetrics without = image::compare(open.frame, truth);
        const image::ErrorMetrics with = image::compare(shadowed.frame, truth);
        std::printf("isr %s: relMSE %.4f without visibility, %.4f with; means %.4f, %.4f vs %.4f; %g maps, %.1f ms vs "
                    "%.1f ms\n",
                    preset.c_str(), without.rel_mse, with.rel_mse, without.mean_test, with.mean_test, with.mean_reference,
                    stat(shadowed, "ism_maps"), shadowed.stats.gpu_ms, open.stats.gpu_ms);
        EXPECT_EQ(with.non_finite_test, 0u);
        EXPECT_LE(with.rel_mse, 0.25 * without.rel_mse) << preset;
        EXPECT_LT(std::abs(with.mean_test - with.mean_reference), std::abs(without.mean_test - without.mean_reference))
            << preset;
    }
}

// The presets from low up carry the maps (64^2 texels, 4096 points or more), draft does not: the
// requirement is the test's above, three quarters of the error gone at each preset against the same
// preset without maps, and the preset's error fall from draft's to at most half by low.
TEST(Isr, PresetsFromLowUpCarryImperfectShadowMaps) {
    const scene::Scene scene = scene::make_cornell_box();
    const image::Frame& truth = cornell_reference(true);
    double draft = 0.0;
    for (const std::string preset : {"draft", "low", "medium", "high", "ultra"}) {
        const auto as_preset = render_isr(scene, preset);
        const double with = image::compare(as_preset.frame, truth).rel_mse;
        const double without = image::compare(render_isr(scene, preset, without_visibility()).frame, truth).rel_mse;
        std::printf("isr %-6s relMSE %.4f, %.4f without maps; %g maps\n", preset.c_str(), with, without,
                    stat(as_preset, "ism_maps"));
        EXPECT_EQ(as_preset.frame.non_finite_count(), 0u) << preset;
        if (preset == "draft") {
            EXPECT_EQ(stat(as_preset, "indirect_visibility"), 0.0);
            EXPECT_EQ(with, without);
            draft = with;
            continue;
        }
        EXPECT_EQ(stat(as_preset, "indirect_visibility"), 1.0) << preset;
        EXPECT_LE(with, 0.25 * without) << preset;
        EXPECT_LE(with, 0.5 * draft) << preset;
    }
}

// From medium up the presets' maps splat more of the point cloud (8192 points at medium, 16384 at
// high and ultra, 4096 at low): a map's points are a run of the cloud from an offset of its own, so
// a denser map holds every sample of a sparser one and more, and fewer of its texels see through a
// near occluder to the floor behind it. Behind the divider, where the one-bounce light is zero, each
// denser preset must leave less light than the sparser one before it (the bench's walled scenes: the
// thin wall's one-bounce relMSE 0.104 at low, 0.094 at medium, 0.078 at high), ultra less than low.
// Measured on llvmpipe: 0.00037, 0.00020, 0.00006 and 0.00006 of light left.
TEST(Isr, PresetsFromMediumUpSampleOccludersMoreDensely) {
    const scene::Scene scene = divided_floor();
    const methods::MethodRegistry& registry = methods::MethodRegistry::builtin();
    const auto points = [&](const std::string& preset) { return registry.resolve("isr", preset, {}).at("ism_points"); };
    std::map<std::string, double> hidden;
    for (const std::string preset : {"low", "medium", "high", "ultra"}) {
        // Every pixel gathers, as in the divider's test above: the eye-space patches would reach across it.
        hidden[preset] = floor_mean(scene, render_isr(scene, preset, {{"levels", 1}}).frame, 0.25f, 0.9f);
        std::printf("behind the divider, isr %-6s (%g points per map): %.5f\n", preset.c_str(),
                    points(preset), hidden[preset]);
    }
    EXPECT_LT(points("low"), points("medium"));
    EXPECT_LT(points("medium"), points("high"));
    EXPECT_LT(hidden["medium"], hidden["low"]);
    EXPECT_LT(hidden["high"], hidden["medium"]);
    EXPECT_LT(hidden["ultra"], hidden["low"]);
}

// The maps are made with the VPL tree: kept while only the camera moves, remade when a light or an
// object moves, or their knobs change.
TEST(Isr, ImperfectShadowMapsKeptWhileOnlyTheCameraMoves) {
    scene::Scene scene = scene::make_cornell_box();
    auto resources = shared_renderer().upload(scene);
    RenderRequest request = isr_request("low", kVisibility);
    shared_renderer().render(*resources, request);
    scene::Camera moved = scene.cameras[0];
    moved.position += glm::vec3(0.05f, 0.0f, 0.0f);
    request.camera = moved;
    EXPECT_EQ(stat(shared_renderer().render(*resources, request), "ism_builds"), 1.0);
    scene.lights[0].position += glm::vec3(0.02f, 0.0f, 0.0f);
    EXPECT_EQ(stat(shared_renderer().render(*resources, request), "ism_builds"), 2.0);
    // A moved object: its points move with it (the cloud is kept in object space).
    scene.objects[1].transform = glm::translate(glm::mat4(1.0f), glm::vec3(0.03f, 0.0f, 0.0f)) * scene.objects[1].transform;
    EXPECT_EQ(stat(shared_renderer().render(*resources, request), "ism_builds"), 3.0);
    request.knobs["ism_size"] = 16;
    EXPECT_EQ(stat(shared_renderer().render(*resources, request), "ism_builds"), 4.0);
}

// The extremes matrix's case of a light inside a closed block (bench/extremes.cpp): the reference's
// room is dark, and isr without visibility lights it through the block's walls (its documented
// exception there, relMSE about 12). The hard case for a point cloud: the block's walls are a small
// part of the scene's area but fill most of each map's hemisphere, so their samples are sparse
// there, while the room behind them is sampled densely. The requirements: at least
// two thirds of the light gone at 1024 points per map, and less left at 4096. Measured on llvmpipe
// (32x32): 26% and 16% left.
TEST(Isr, ImperfectShadowMapsKeepALightInsideAClosedBlock) {
    std::optional<bench::ExtremeCase> closed;
    for (bench::ExtremeCase& extreme : bench::extreme_cases()) {
        if (extreme.name == "geometry/light_inside_closed") closed = std::move(extreme);
    }
    ASSERT_TRUE(closed.has_value());
    const bench::ExtremeTruth truth = bench::extreme_truth(*closed, bench::kExtremeReferenceBounces);
    const auto request = [&](methods::KnobValues knobs) {
        RenderRequest r = method_request("isr", "high", closed->width, std::move(knobs));
        r.height = closed->height;
        return r;
    };
    const auto open = render_scene(closed->scene, request(without_visibility()));
    const auto shadowed = render_scene(closed->scene, request(kVisibility));
    methods::KnobValues denser = kVisibility;
    denser["ism_points"] = 4096;
    const auto shadowed_denser = render_scene(closed->scene, request(denser));
    const image::ErrorMetrics without = image::compare(open.frame, truth.frame);
    const image::ErrorMetrics with = image::compare(shadowed.frame, truth.frame);
    const image::ErrorMetrics with_denser = image::compare(shadowed_denser.frame, truth.frame);
    std::printf("light inside a closed block: relMSE %.4f without visibility, %.4f with, %.4f with 4096 points; means "
                "%.5f, %.5f, %.5f (reference %.5f +- %.5f)\n",
                without.rel_mse, with.rel_mse, with_denser.rel_mse, without.mean_test, with.mean_test,
                with_denser.mean_test, truth.mean, truth.mean_error);
    EXPECT_LE(with.mean_test - truth.mean, (without.mean_test - truth.mean) / 3.0 + 3.0 * truth.mean_error);
    EXPECT_LT(with_denser.mean_test, with.mean_test);
}

// The point cloud is kept in each object's space and moved by its transform: the Cornell box with its
// blocks placed by their transforms (moved 5 cm off their spots) gives the frame that the same
// geometry gives with the transforms baked into its vertices. Both clouds pick the same triangles
// along the same cumulative areas, so the maps may add to the two frames' difference without maps
// (float rounding of moved against baked vertices) no more than a thousandth of what the maps do to
// the frame; points left where the blocks were would shift their shadows by 5 cm. Measured on
// llvmpipe: 2.2e-6 against 1.6e-6 without maps; the maps change the frame by 0.095.
TEST(Isr, ImperfectShadowMapsFollowObjectTransforms) {
    scene::Scene placed = scene::make_cornell_box();
    for (scene::Object& object : placed.objects) {
        if (object.name.find("block") != std::string::npos) {
            object.transform = glm::translate(glm::mat4(1.0f), glm::vec3(0.04f, 0.0f, -0.03f)) * object.transform;
        }
    }
    const scene::Scene baked = with_transforms_baked(placed);
    const auto with_transforms = render_isr(placed, "draft", kVisibility);
    const auto with_vertices = render_isr(baked, "draft", kVisibility);
    const double between = image::compare(with_transforms.frame, with_vertices.frame).rel_mse;
    // What the rest of the frame differs by between the two scenes (rasterizing moved and baked vertices).
    const double floor = image::compare(render_isr(placed, "draft").frame, render_isr(baked, "draft").frame).rel_mse;
    const double visibility = image::compare(render_isr(placed, "draft").frame, with_transforms.frame).rel_mse;
    std::printf("blocks placed by transforms against baked: relMSE %.2e (%.2e without maps); the maps change the "
                "frame by %.4f\n",
                between, floor, visibility);
    EXPECT_LE(between, floor + 1e-3 * visibility);
}

// A file as a CAD exporter writes it (assimp's sample 2CylinderEngine: 67 nodes, each mesh placed by
// its node's transform, no light of its own: a sun is added). Visibility only takes light away: each
// VPL's term is multiplied by a visibility in [0, 1], and the eye-space upsampling is a weighted
// mean, so no pixel may gain light from the maps (beyond float rounding, 1e-5 of the pixel). So with
// draft and 32^2 maps, and with the low preset's own maps (64^2 texels of 4096 points) against low
// without them.
TEST(Isr, ImperfectShadowMapsOnlyTakeLightAwayOnARealFile) {
    const scene::Scene file = sunlit_engine();
    ASSERT_GT(file.objects.size(), 10u);
    const auto check = [&](const std::string& preset, const methods::KnobValues& maps) {
        SCOPED_TRACE(preset);
        const auto open = render_isr(file, preset, without_visibility());
        const auto shadowed = render_isr(file, preset, maps);
        EXPECT_EQ(shadowed.frame.non_finite_count(), 0u);
        EXPECT_GT(stat(shadowed, "ism_maps"), 0.0);
        std::size_t brighter = 0;
        double open_sum = 0.0, shadowed_sum = 0.0;
        for (std::size_t i = 0; i < open.frame.rgba.size(); ++i) {
            if (i % 4 == 3) continue;
            open_sum += open.frame.rgba[i];
            shadowed_sum += shadowed.frame.rgba[i];
            if (shadowed.frame.rgba[i] > open.frame.rgba[i] * (1.0f + 1e-5f) + 1e-7f) ++brighter;
        }
        std::printf("2CylinderEngine, isr %s: %zu objects, %g maps; mean %.5f without maps, %.5f with; %zu channels "
                    "brighter\n",
                    preset.c_str(), file.objects.size(), stat(shadowed, "ism_maps"), open_sum, shadowed_sum, brighter);
        EXPECT_EQ(brighter, 0u);
        EXPECT_LT(shadowed_sum, open_sum);  // the engine shadows itself
    };
    check("draft", kVisibility);
    check("low", {});
}

// Hostile knob values: a map side that is not a power of two (its pyramid's odd rows take the texel
// above nearest them), the smallest map, and visibility asked in a mode without a tree (ignored,
// and the maps of an earlier frame freed). Every frame finite; the odd side meets the Cornell box's
// requirement as 32 does.
TEST(Isr, ImperfectShadowMapsTakeOddSidesAndAreFreedWhenUnused) {
    const scene::Scene scene = scene::make_cornell_box();
    const image::Frame& truth = cornell_reference(true);
    const double without = image::compare(render_isr(scene, "draft").frame, truth).rel_mse;
    methods::KnobValues odd = kVisibility;
    odd["ism_size"] = 33;
    const auto odd_frame = render_isr(scene, "draft", odd);
    EXPECT_EQ(odd_frame.frame.non_finite_count(), 0u);
    EXPECT_LE(image::compare(odd_frame.frame, truth).rel_mse, 0.25 * without);
    methods::KnobValues smallest = kVisibility;
    smallest["ism_size"] = 1;
    EXPECT_EQ(render_isr(scene, "draft", smallest).frame.non_finite_count(), 0u);

    auto resources = shared_renderer().upload(scene);
    const auto with_maps = shared_renderer().render(*resources, isr_request("draft", kVisibility));
    methods::KnobValues naive = kVisibility;
    naive["mode"] = 0;
    const auto naive_frame = shared_renderer().render(*resources, isr_request("draft", naive));
    EXPECT_EQ(stat(naive_frame, "indirect_visibility"), 0.0);
    EXPECT_EQ(naive_frame.frame.non_finite_count(), 0u);
    std::size_t maps_bytes = 0;
    for (const auto& structure : naive_frame.stats.resident) {
        if (structure.name == "isr.imperfect_shadow_maps") maps_bytes = structure.bytes;
    }
    EXPECT_EQ(maps_bytes, 0u) << "maps kept by a frame that does not use them";
    EXPECT_GT(stat(with_maps, "ism_maps"), 0.0);
}

}  // namespace
}  // namespace bounce::test
