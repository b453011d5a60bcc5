// glTF alphaMode in the light transport: a surface cut away by MASK (or BLEND at alpha 0) sends
// no indirect light by any method, and BLEND is coverage — a blocker of alpha a lets 1 - a of the
// light through and shows a of itself, in the GPU frames (screen-door) and in the reference
// (stochastic any-hit) alike, and a blended wall sends a of an opaque one's indirect light. And the
// lit back of a single-sided wall sends nothing.
#include "gpu_fixture.hpp"
#include "renderer/methods/reference/path_tracer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <vector>

namespace bounce::test {
namespace {

constexpr float kPi = 3.14159265358979f;
constexpr int kSize = 96;
const glm::vec3 kSunDirection = glm::normalize(glm::vec3(1.0f, -1.0f, 0.0f));  // from -x, 45 degrees up
constexpr float kSunIrradiance = 2.0f;
constexpr float kFloorAlbedo = 0.8f;
// The sunlit floor's radiance: albedo / pi times the irradiance at 45 degrees.
const float kLitFloor = kFloorAlbedo / kPi * kSunIrradiance * std::sqrt(0.5f);

scene::Material with_alpha(scene::Material material, scene::AlphaMode mode, float alpha) {
    material.alpha_mode = mode;
    material.base_color.a = alpha;
    return material;
}

// A white floor over [-1, 1]^2 under a sun from -x at 45 degrees, and a red wall along its +x edge
// facing it (sunlit; its shadow falls beyond the floor). Without `wall`, a zero-area triangle
// across the wall's diagonal stands in for it: nothing to see or light, but the same scene bounds,
// so every structure fitted to them (voxel grid, light views) is the same with the wall and without.
// `facing` is the wall's front: towards the floor (-x) unless a test turns it away.
scene::Scene floor_and_wall(const std::optional<scene::Material>& wall, const glm::vec3& facing = {-1, 0, 0}) {
    scene::Scene scene;
    scene.materials.push_back(matte(glm::vec3(kFloorAlbedo)));
    add_square(scene, "floor", glm::vec3(0.0f), 1.0f, {0, 1, 0}, 0);
    scene.materials.push_back(wall.value_or(matte(glm::vec3(0.0f))));
    add_square(scene, "wall", glm::vec3(1.0f, 0.5f, 0.0f), 0.5f, facing, 1);
    if (!wall) {
        scene::Primitive& primitive = scene.meshes.back().primitives[0];
        primitive.positions[1] = 0.5f * (primitive.positions[0] + primitive.positions[2]);
        primitive.positions[3] = primitive.positions[1];
    }
    scene.lights.push_back(directional_light(kSunDirection, kSunIrradiance));
    scene.cameras.push_back(top_down_camera(3.0f, 0.9f));
    return scene;
}

// The mean of `frame` (per channel) over the pixels whose ground point `inside` accepts.
glm::dvec3 region_mean(const image::Frame& frame, const scene::Camera& camera,
                       const std::function<bool(const glm::vec3&)>& inside, int* count = nullptr) {
    glm::dvec3 sum(0.0);
    int n = 0;
    for (int y = 0; y < frame.height; ++y) {
        for (int x = 0; x < frame.width; ++x) {
            if (!inside(pixel_on_ground(camera, frame.width, frame.height, x, y))) continue;
            sum += glm::dvec3(glm::vec3(frame.at(x, y)));
            ++n;
        }
    }
    if (count) *count = n;
    return n > 0 ? sum / static_cast<double>(n) : sum;
}

// The floor short of the wall's foot, where direct light is the sun's alone.
bool open_floor(const glm::vec3& p) { return std::abs(p.x) < 0.9f && std::abs(p.z) < 0.9f; }

// What the wall adds to the open floor: the mean of a method's frame there less the mean of its
// frame of the floor alone (the same direct light and whatever the method gives a plane by itself).
glm::dvec3 light_from_wall(const std::string& method, const scene::Material& wall, methods::KnobValues knobs = {},
                           const glm::vec3& facing = {-1, 0, 0}) {
    const RenderRequest request = method_request(method, "high", kSize, std::move(knobs));
    const scene::Camera camera = top_down_camera(3.0f, 0.9f);
    return region_mean(render_scene(floor_and_wall(wall, facing), request).frame, camera, open_floor) -
           region_mean(render_scene(floor_and_wall(std::nullopt), request).frame, camera, open_floor);
}

class AlphaTransport : public ::testing::TestWithParam<std::string> {};

// A wall cut away everywhere (MASK with alpha 0 below the cutoff, or BLEND at alpha 0) sends no
// light: the floor is lit as if the wall were not there (the same structures: the stand-in keeps
// the bounds). The bound, 1e-5 of what the opaque wall sends (4% to 7% of the floor's radiance in
// red), is float rounding (measured: exactly 0); a cut-away wall that still sent light would send
// all of it.
TEST_P(AlphaTransport, ACutAwayWallSendsNoIndirectLight) {
    const scene::Material red = matte(glm::vec3(0.9f, 0.1f, 0.1f));
    const glm::dvec3 opaque = light_from_wall(GetParam(), red);
    ASSERT_GT(opaque.r, 0.01 * kLitFloor) << "the opaque wall must light the floor for the test to mean anything";
    for (const auto& [label, wall] :
         {std::pair{"MASK, alpha 0", with_alpha(red, scene::AlphaMode::mask, 0.0f)},
          std::pair{"BLEND, alpha 0", with_alpha(red, scene::AlphaMode::blend, 0.0f)}}) {
        const glm::dvec3 cut = light_from_wall(GetParam(), wall);
        std::printf("%s: light from the wall opaque (%.3g %.3g %.3g), cut away by %s (%.3g %.3g %.3g)\n",
                    GetParam().c_str(), opaque.r, opaque.g, opaque.b, label, cut.r, cut.g, cut.b);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(cut[c], 0.0, 1e-5 * opaque.r) << label << ", channel " << c;
    }
}

INSTANTIATE_TEST_SUITE_P(Methods, AlphaTransport, ::testing::Values("vct", "isr", "cssm"),
                         [](const ::testing::TestParamInfo<std::string>& param) { return param.param; });

// The back of a single-sided surface absorbs (as in the reference): lit, it sends nothing. Two
// setups, each with the floor's indirect light zero in theory, bound 1e-5 of the sunlit floor's
// radiance (float rounding of the frame; measured 2.5e-7, i.e. 1.4e-6 of it, for isr's composite
// over `direct`). A lit back that reflected would send what a lit front does, 0.026 in red:
// - the wall facing the floor, the sun from beyond it (lighting its back): isr's one bounce on the
//   open floor must add nothing to `direct` (the floor is a plane; the wall's lit side is its back).
//   Its light views once gave such backs the front's flux, sent towards the floor;
// - the wall turned away, the sun on the floor's side lighting its back: cssm sends nothing.
// (vct's voxels have no sides: it lights the floor from either side of a wall, docs/methods.md
// "Extremes"; so vct is not held to this.)
TEST(SingleSidedBacks, ALitBackSendsNoLight) {
    const scene::Material red = matte(glm::vec3(0.9f, 0.1f, 0.1f));
    const scene::Camera camera = top_down_camera(3.0f, 0.9f);
    {
        const glm::dvec3 front = light_from_wall("isr", red);
        scene::Scene from_beyond = floor_and_wall(red);
        from_beyond.lights[0].direction = glm::normalize(glm::vec3(-1.0f, -1.0f, 0.0f));
        const glm::dvec3 added =
            region_mean(render_scene(from_beyond, method_request("isr", "high", kSize)).frame, camera, open_floor) -
            region_mean(render_scene(from_beyond, method_request("direct", "high", kSize)).frame, camera, open_floor);
        std::printf("isr: light from the wall's lit front %.3g, from its lit back (%.3g %.3g %.3g)\n", front.r, added.r,
                    added.g, added.b);
        ASSERT_GT(front.r, 0.01 * kLitFloor);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(added[c], 0.0, 1e-5 * kLitFloor) << "isr, channel " << c;
    }
    {
        const glm::dvec3 front = light_from_wall("cssm", red);
        const glm::dvec3 back = light_from_wall("cssm", red, {}, {1, 0, 0});
        std::printf("cssm: light from the wall's lit front %.3g, from its lit back (%.3g %.3g %.3g)\n", front.r,
                    back.r, back.g, back.b);
        ASSERT_GT(front.r, 0.01 * kLitFloor);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(back[c], 0.0, 1e-5 * kLitFloor) << "cssm, channel " << c;
    }
}

// cssm's atlas gives a blended texel alpha of its area: a wall of alpha 0.5 sends half of an opaque
// wall's light (its direct light is the same; the radiosity is linear in sender area). With one
// bounce and both oracles refining to every leaf (thresholds 0) the only other term is the disk
// form factor's A in pi d^2 + A: texels of ~1e-3 m^2 at d >= 0.1 m bound it below 1e-3 of the
// ratio in the mean. (The presets' adaptive cuts differ with the senders' radiance: 0.5024 at
// `high`.)
TEST(AlphaCoverage, CssmBlendedWallSendsItsCoverageOfTheLight) {
    const scene::Material red = matte(glm::vec3(0.9f, 0.1f, 0.1f));
    const methods::KnobValues exact = {{"bounces", 1}, {"threshold", 0}, {"final_threshold", 0}};
    const double opaque = light_from_wall("cssm", red, exact).r;
    const double half = light_from_wall("cssm", with_alpha(red, scene::AlphaMode::blend, 0.5f), exact).r;
    std::printf("cssm: light from the wall (red) opaque %.4g, blended at 0.5 %.4g: ratio %.5f\n", opaque, half,
                half / opaque);
    EXPECT_NEAR(half / opaque, 0.5, 1e-3);
}

// The same for the path tracer: its any-hit keeps a blended point with probability alpha, so a
// bounce ray from the floor meets the wall half as often. The floor's indirect light (all of it
// the wall's) is the difference of a 1-bounce and a 0-bounce render with one seed. Its noise is
// measured, not assumed: two seeds, the variance of their difference is twice the noise's; the
// ratio's bound is four standard errors of the two region means.
TEST(AlphaCoverage, ReferenceBlendedWallSendsItsCoverageOfTheLight) {
    const scene::Material red = matte(glm::vec3(0.9f, 0.1f, 0.1f));
    const scene::Camera camera = top_down_camera(3.0f, 0.9f);
    constexpr int size = 32, spp = 128;
    auto indirect_red = [&](const scene::Scene& scene) {
        return mean_over_two_seeds([&](std::uint64_t seed) {
            methods::reference::PathTracerSettings one_bounce, direct_only;
            one_bounce.max_bounces = 1;
            direct_only.max_bounces = 0;
            one_bounce.seed = direct_only.seed = seed;
            const image::Frame with = pixel_centre_reference(scene, size, spp, one_bounce);
            const image::Frame without = pixel_centre_reference(scene, size, spp, direct_only);
            std::vector<double> values;
            for (int y = 0; y < size; ++y)
                for (int x = 0; x < size; ++x)
                    if (open_floor(pixel_on_ground(camera, size, size, x, y)))
                        values.push_back(static_cast<double>(with.at(x, y).r) - without.at(x, y).r);
            return values;
        });
    };
    const MeasuredMean measured_opaque = indirect_red(floor_and_wall(red));
    const MeasuredMean measured_half = indirect_red(floor_and_wall(with_alpha(red, scene::AlphaMode::blend, 0.5f)));
    const double opaque = measured_opaque.mean, opaque_error = measured_opaque.standard_error;
    const double half = measured_half.mean, half_error = measured_half.standard_error;
    const double ratio = half / opaque;
    const double ratio_error = ratio * std::hypot(half_error / half, opaque_error / opaque);
    std::printf("reference: floor indirect (red) opaque %.4g +- %.2g, blended at 0.5 %.4g +- %.2g: ratio %.4f +- %.4f\n",
                opaque, opaque_error, half, half_error, ratio, ratio_error);
    EXPECT_NEAR(ratio, 0.5, 4.0 * ratio_error);
    EXPECT_LT(ratio_error, 0.02) << "too noisy to tell coverage from a cut-out";
}

// A black blocker of alpha 0.25 over a sunlit floor, its shadow and itself apart in the frame:
// the shadow lets 0.75 of the sunlight through and the blocker shows 0.75 of the floor behind it.
// Every frame agrees in expectation; each pixel of a GPU frame is one coverage decision (the
// screen-door hash; a shadow pixel filters several shadow-map texels, so at least one), so the
// bound is four binomial standard errors, 4 sqrt(a (1 - a) / pixels), of the lit fraction.
TEST(AlphaCoverage, ABlendedBlockerLetsThroughOneMinusAlpha) {
    scene::Scene scene;
    scene.materials.push_back(matte(glm::vec3(kFloorAlbedo)));
    scene::Material blocker = with_alpha(matte(glm::vec3(0.0f)), scene::AlphaMode::blend, 0.25f);
    blocker.double_sided = true;
    scene.materials.push_back(blocker);
    add_square(scene, "floor", glm::vec3(0.0f), 1.5f, {0, 1, 0}, 0);
    // At height 0.5 over x = -0.6: seen over ground x in [-0.9, -0.54] x 1.2 from the camera at 3,
    // its shadow (45 degrees) over x in [-0.4, 0.2].
    add_square(scene, "blocker", glm::vec3(-0.6f, 0.5f, 0.0f), 0.3f, {0, 1, 0}, 1);
    scene.lights.push_back(directional_light(kSunDirection, kSunIrradiance));
    scene.cameras.push_back(top_down_camera(3.0f, 0.9f));
    const scene::Camera& camera = scene.cameras[0];
    const float inset = 0.06f;  // clear of the shadow's filtered edge
    auto in_shadow = [&](const glm::vec3& p) {
        return p.x > -0.4f + inset && p.x < 0.2f - inset && std::abs(p.z) < 0.3f - inset;
    };
    auto behind_blocker = [&](const glm::vec3& p) {
        return p.x > -1.2f * 0.9f + inset && p.x < -1.2f * 0.3f - inset && std::abs(p.z) < 1.2f * 0.3f - inset;
    };
    constexpr double kLitFraction = 0.75;
    auto check = [&](const std::string& label, const image::Frame& frame, bool one_decision_per_pixel) {
        int shadow_pixels = 0, blocker_pixels = 0;
        const double shadow = region_mean(frame, camera, in_shadow, &shadow_pixels).g / kLitFloor;
        const double seen = region_mean(frame, camera, behind_blocker, &blocker_pixels).g / kLitFloor;
        ASSERT_GT(shadow_pixels, 100);
        ASSERT_GT(blocker_pixels, 100);
        const auto bound = [&](int pixels) {
            return one_decision_per_pixel ? 4.0 * std::sqrt(kLitFraction * (1.0 - kLitFraction) / pixels) : 0.01;
        };
        std::printf("%s: lit fraction in the shadow %.4f (%d pixels, bound %.4f), through the blocker %.4f (%d pixels, "
                    "bound %.4f)\n",
                    label.c_str(), shadow, shadow_pixels, bound(shadow_pixels), seen, blocker_pixels,
                    bound(blocker_pixels));
        EXPECT_NEAR(shadow, kLitFraction, bound(shadow_pixels)) << label;
        EXPECT_NEAR(seen, kLitFraction, bound(blocker_pixels)) << label;
    };
    RenderRequest request = method_request("direct", "high", 128);
    check("direct", render_scene(scene, request).frame, true);
    // The reference averages 256 decisions per pixel over about 400 pixels: its binomial error is
    // about 1e-3; 0.01 is ten of them.
    methods::reference::PathTracerSettings direct_only;
    direct_only.max_bounces = 0;
    check("reference", methods::reference::PathTracer(scene).render(camera, 64, 64, 256, direct_only), false);
}

}  // namespace
}  // namespace bounce::test
