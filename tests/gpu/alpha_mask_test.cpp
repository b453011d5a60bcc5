// glTF alphaMode MASK: where base-colour alpha is below the cutoff the surface is not there, for
// the camera (G-buffer), for the lights (shadow maps) and for rays (the reference's and cssm's
// bake's any-hit test). A masked blocker whose texture cuts away its right half must render as a
// blocker that is only its left half; and rays pass where it is cut. The frames are compared away
// from the cut's edge (two pixels either side, where coverage and bilinear alpha differ); 1e-4
// relative is float rounding (the same surfaces under the same lights).
#include "gpu_fixture.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/raytrace/ray_scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace bounce::test {
namespace {

constexpr int kSize = 48;

// A floor at y = 0 under a sun straight down, and a blocker at y = 1 over [-0.6, 0.6]^2: masked
// (a 4x1 texture, alpha 1 1 0 0: kept where u < 0.5) or only that half as geometry.
scene::Scene blocked_floor(bool masked) {
    scene::Scene scene;
    scene.materials.push_back(matte(glm::vec3(0.6f)));
    scene::Material blocker = matte(glm::vec3(0.2f, 0.3f, 0.8f));
    if (masked) {
        scene::Texture texture;
        texture.width = 4;
        texture.height = 1;
        texture.rgba8 = {255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 0, 255, 255, 255, 0};
        scene.textures.push_back(texture);
        blocker.base_color_texture.texture = 0;
        blocker.alpha_mode = scene::AlphaMode::mask;
    }
    scene.materials.push_back(blocker);
    add_square(scene, "floor", glm::vec3(0.0f), 2.0f, {0, 1, 0}, 0);
    add_square(scene, "blocker", glm::vec3(0.0f, 1.0f, 0.0f), 0.6f, {0, 1, 0}, 1);
    if (!masked) {
        // Keep u < 0.5 as geometry: the vertices at u = 1 move halfway back along the u edge.
        auto& primitive = scene.meshes[1].primitives[0];
        const glm::vec3 u_edge = primitive.positions[1] - primitive.positions[0];  // uv (0,0) to (1,0)
        for (std::size_t i = 0; i < primitive.positions.size(); ++i) {
            if (primitive.uv0[i].x > 0.5f) primitive.positions[i] -= 0.5f * u_edge;
        }
        primitive.bounds = {};
        for (const auto& p : primitive.positions) primitive.bounds.extend(p);
        scene.meshes[1].bounds = primitive.bounds;
    }
    scene.lights.push_back(directional_light({0.0f, -1.0f, 0.0f}, 2.0f));
    return scene;
}

// The blocker's texture u direction in the world (unit), from its first edge.
glm::vec3 u_direction(const scene::Scene& scene) {
    const auto& p = scene.meshes[1].primitives[0].positions;
    return glm::normalize(p[1] - p[0]);
}

TEST(AlphaMask, ACutAwaySurfaceIsNotSeenAndCastsNoShadow) {
    const scene::Scene masked = blocked_floor(true), half = blocked_floor(false);
    const glm::vec3 u = u_direction(masked), across = glm::cross(glm::vec3(0, 1, 0), u);
    RenderRequest request;
    request.width = request.height = kSize;
    request.camera = top_down_camera(3.0f, 1.0f);
    const auto a = render_scene(masked, request), b = render_scene(half, request);
    int compared = 0, lit_through_the_cut = 0;
    for (int y = 0; y < kSize; ++y) {
        for (int x = 0; x < kSize; ++x) {
            // The cut runs through the centre across u; it projects onto the floor's centre line.
            const glm::vec3 ground = pixel_on_ground(*request.camera, kSize, kSize, x, y);
            if (std::abs(glm::dot(ground, u)) < 0.2f) continue;  // three pixels either side of the cut
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(a.frame.at(x, y)[c], b.frame.at(x, y)[c], 1e-4f * std::max(1.0f, b.frame.at(x, y)[c]))
                    << x << "," << y;
            }
            ++compared;
            // Through the cut half the sunlit floor shows: albedo 0.6 / pi * 2.
            if (glm::dot(ground, u) > 0.3f && glm::dot(ground, u) < 0.8f && std::abs(glm::dot(ground, across)) < 0.5f) {
                lit_through_the_cut += std::abs(a.frame.at(x, y).g - 0.6f / 3.14159265f * 2.0f) < 1e-3f;
            }
        }
    }
    EXPECT_GT(compared, kSize * kSize / 2);
    EXPECT_GT(lit_through_the_cut, 20);
}

TEST(AlphaMask, RaysPassWhereTheSurfaceIsCutAway) {
    scene::Scene scene = blocked_floor(true);
    const raytrace::RayScene rays(scene);
    const glm::vec3 down(0.0f, -1.0f, 0.0f), u = u_direction(scene);
    const glm::vec3 kept = -0.3f * u, cut = 0.3f * u;  // u = 0.25 and 0.75 on the blocker
    const auto through_kept = rays.intersect(kept + glm::vec3(0, 2, 0), down, 0.0f, 10.0f);
    const auto through_cut = rays.intersect(cut + glm::vec3(0, 2, 0), down, 0.0f, 10.0f);
    ASSERT_TRUE(through_kept && through_cut);
    EXPECT_EQ(through_kept->object, 1u);  // the blocker
    EXPECT_EQ(through_cut->object, 0u);   // the floor, seen through the cut
    EXPECT_TRUE(rays.occluded(kept + glm::vec3(0, 0.01f, 0), -down, 0.0f, 10.0f));
    EXPECT_FALSE(rays.occluded(cut + glm::vec3(0, 0.01f, 0), -down, 0.0f, 10.0f));
}

}  // namespace
}  // namespace bounce::test

namespace bounce::test {
namespace {

// A textured, transformed, alpha-masked asset against the reference: a blocker whose base-colour
// texture (4x4 cells of colour, alpha in a checker) carries a KHR_texture_transform and alphaMode
// MASK, over a floor, under a point light that casts its cut-out shadow there. `direct` and the
// path tracer at zero bounces with rays through pixel centres see the same surfaces, textures,
// cut-outs and shadows (the reference's any-hit test against the G-buffer's discard and the shadow
// maps'); the reference has no noise here (a point light, no indirect light). What remains is the
// shadow maps' filtering and bilinear alpha at the cut-outs' edges: a pixel whose centre falls
// where alpha is within the GPU's filter precision (8-bit weights) of the cutoff, or on a shadow's
// edge, is decided one way by the rasterizer and the other by the ray. Measured on llvmpipe: 27 of
// 4096 pixels off by more than 10% (whole runs where a texel boundary meets a row of pixel centres), every
// other pixel within 1% (37 pixels in all disagree by more, 0.9%), the means within 0.2%. Bounds:
// 97% of the pixels within 1%, the means within 1%; a texture, transform or mask applied wrongly
// moves whole cells (a 4x4 texture over a quarter of the frame: 6% of it each).
TEST(AlphaMask, ATexturedTransformedMaskedAssetMatchesTheReference) {
    scene::Scene scene;
    scene.materials.push_back(matte(glm::vec3(0.7f)));
    scene::Material blocker = matte(glm::vec3(1.0f));
    scene::Texture cells;
    cells.width = cells.height = 4;
    cells.srgb = true;
    for (int y = 0; y < 4; ++y) {
        for (int x = 0; x < 4; ++x) {
            cells.rgba8.insert(cells.rgba8.end(), {static_cast<std::uint8_t>(60 * x + 40), static_cast<std::uint8_t>(60 * y + 40),
                                                   200, static_cast<std::uint8_t>((x + y) % 2 ? 255 : 0)});
        }
    }
    scene.textures.push_back(cells);
    blocker.base_color_texture.texture = 0;
    const float c = std::cos(0.4f), s = std::sin(0.4f);
    blocker.base_color_texture.uv_transform = glm::mat3(1, 0, 0, 0, 1, 0, 0.1f, 0.0f, 1) *
                                              glm::mat3(c, s, 0, -s, c, 0, 0, 0, 1) *
                                              glm::mat3(1.5f, 0, 0, 0, 1.5f, 0, 0, 0, 1);
    blocker.alpha_mode = scene::AlphaMode::mask;
    blocker.double_sided = true;
    scene.materials.push_back(blocker);
    add_square(scene, "floor", glm::vec3(0.0f), 2.0f, {0, 1, 0}, 0);
    add_square(scene, "blocker", glm::vec3(0.0f, 0.5f, 0.0f), 0.7f, {0, 1, 0}, 1);
    scene::Light light;
    light.type = scene::LightType::point;
    light.position = {0.3f, 2.0f, 0.2f};
    light.intensity = 3.0f;
    scene.lights.push_back(light);
    scene.cameras.push_back(top_down_camera(3.0f, 1.0f));

    RenderRequest request;
    request.width = request.height = 64;
    request.preset = "high";
    const auto direct = render_scene(scene, request);
    methods::reference::PathTracerSettings direct_only;
    direct_only.max_bounces = 0;
    const auto truth = pixel_centre_reference(scene, 64, 4, direct_only);
    const image::ErrorMetrics error = image::compare(direct.frame, truth);
    // Pixels whose centre lies where the two decide differently (see above) disagree; every other
    // pixel agrees to 1% in every channel.
    int agreeing = 0;
    for (int y = 0; y < 64; ++y) {
        for (int x = 0; x < 64; ++x) {
            const glm::vec4 a = direct.frame.at(x, y), b = truth.at(x, y);
            float worst = 0.0f;
            for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(a[k] - b[k]) / std::max(b[k], 0.01f));
            agreeing += worst <= 0.01f;
        }
    }
    std::printf("masked asset, direct vs reference (0 bounces, pixel centres): relMSE %.6f, mean %.6f vs %.6f, "
                "%d of 4096 pixels agree within 1%%\n",
                error.rel_mse, error.mean_test, error.mean_reference, agreeing);
    EXPECT_NEAR(error.mean_test, error.mean_reference, 0.01 * error.mean_reference);
    EXPECT_GE(agreeing, 64 * 64 * 97 / 100);  // edges: at most 3% of the frame
}

// An emitter the reference samples by area must be weighed where it samples: a square lamp facing
// down whose right half is cut away (alpha 1 1 0 0, MASK) or dark (emission texture 1 1 0 0) lights
// the floor as a lamp that is only its left half (as geometry) does. Direct light only, floor
// pixels clear of the lamp's silhouette; the bound is four standard errors of the two means
// (measured from two seeds). A sampler that took the lamp's full area at its factor would light the
// floor about twice as much.
TEST(AlphaMask, TheReferenceSamplesEmittersWhereTheyAreAndAsBrightAsTheyAre) {
    enum class Lamp { left_half_geometry, masked, textured };
    auto scene_with = [](Lamp lamp) {
        scene::Scene scene;
        scene.materials.push_back(matte(glm::vec3(0.8f)));
        scene::Material emitter = matte(glm::vec3(0.0f));
        emitter.emissive = glm::vec3(4.0f);
        scene::Texture halves;
        halves.width = 4;
        halves.height = 1;
        if (lamp == Lamp::masked) {
            halves.rgba8 = {255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 0, 255, 255, 255, 0};
            scene.textures.push_back(halves);
            emitter.base_color_texture.texture = 0;
            emitter.alpha_mode = scene::AlphaMode::mask;
        } else if (lamp == Lamp::textured) {
            halves.srgb = true;
            halves.rgba8 = {255, 255, 255, 255, 255, 255, 255, 255, 0, 0, 0, 255, 0, 0, 0, 255};
            scene.textures.push_back(halves);
            emitter.emissive_texture.texture = 0;
        }
        scene.materials.push_back(emitter);
        add_square(scene, "floor", glm::vec3(0.0f), 2.0f, {0, 1, 0}, 0);
        add_square(scene, "lamp", glm::vec3(0.0f, 1.0f, 0.0f), 0.5f, {0, -1, 0}, 1);
        if (lamp == Lamp::left_half_geometry) {
            auto& primitive = scene.meshes[1].primitives[0];
            const glm::vec3 u_edge = primitive.positions[1] - primitive.positions[0];
            for (std::size_t i = 0; i < primitive.positions.size(); ++i) {
                if (primitive.uv0[i].x > 0.5f) primitive.positions[i] -= 0.5f * u_edge;
            }
        }
        scene.cameras.push_back(top_down_camera(3.0f, 1.2f));
        return scene;
    };
    constexpr int size = 32, spp = 32;
    auto floor_mean = [&](const scene::Scene& scene) {
        return mean_over_two_seeds([&](std::uint64_t seed) {
            methods::reference::PathTracerSettings direct_only;
            direct_only.max_bounces = 0;
            direct_only.seed = seed;
            const image::Frame frame = pixel_centre_reference(scene, size, spp, direct_only);
            std::vector<double> values;
            for (int y = 0; y < size; ++y) {
                for (int x = 0; x < size; ++x) {
                    const glm::vec3 p = pixel_on_ground(scene.cameras[0], size, size, x, y);
                    // Clear of the lamp, which hides the floor within 1.5 x its half size.
                    if (std::max(std::abs(p.x), std::abs(p.z)) > 0.8f && std::max(std::abs(p.x), std::abs(p.z)) < 1.9f)
                        values.push_back(frame.at(x, y).g);
                }
            }
            return values;
        });
    };
    const MeasuredMean truth = floor_mean(scene_with(Lamp::left_half_geometry));
    ASSERT_GT(truth.mean, 0.0);
    for (const auto& [label, lamp] : {std::pair{"masked", Lamp::masked}, std::pair{"emission-textured", Lamp::textured}}) {
        const MeasuredMean measured = floor_mean(scene_with(lamp));
        const double bound = 4.0 * std::hypot(truth.standard_error, measured.standard_error);
        std::printf("floor under a %s half lamp %.5f +- %.5f, under the half lamp as geometry %.5f +- %.5f\n", label,
                    measured.mean, measured.standard_error, truth.mean, truth.standard_error);
        EXPECT_NEAR(measured.mean, truth.mean, bound) << label;
        EXPECT_LT(bound, 0.05 * truth.mean) << "too noisy to tell half a lamp from a whole one";
    }
}

}  // namespace
}  // namespace bounce::test

namespace bounce::test {
namespace {

// A cut-out seen from afar: a square under a sun, its texture one-texel stripes (3 columns in 10
// kept) repeated 16 times across it, seen top-down at 32x32 so that each pixel spans about 19
// texels. Every mip above the base level averages the stripes to alpha 0.3, under the cutoff: a
// test on filtered alpha loses the whole square. The reference tests texels, so the square stays
// with its stripes' 30% coverage. Through pixel centres both see the same texels; the tolerance is
// 5% of the mean, for bilinear alpha near the stripes' edges.
TEST(AlphaMask, AMinifiedCutOutKeepsItsCoverage) {
    scene::Scene scene;
    scene::Texture stripes;
    stripes.width = 20;
    stripes.height = 1;
    for (int x = 0; x < stripes.width; ++x) {
        const std::uint8_t alpha = x % 10 < 3 ? 255 : 0;
        stripes.rgba8.insert(stripes.rgba8.end(), {255, 255, 255, alpha});
    }
    scene.textures.push_back(stripes);
    scene::Material cut_out = matte(glm::vec3(0.8f));
    cut_out.base_color_texture.texture = 0;
    cut_out.base_color_texture.uv_transform = glm::mat3(glm::vec3(16, 0, 0), glm::vec3(0, 16, 0), glm::vec3(0, 0, 1));
    cut_out.alpha_mode = scene::AlphaMode::mask;
    scene.materials.push_back(cut_out);
    add_square(scene, "cut_out", glm::vec3(0.0f), 1.0f, {0, 1, 0}, 0);
    scene.lights.push_back(directional_light({0.0f, -1.0f, 0.0f}, 2.0f));
    scene.cameras = {top_down_camera(3.0f, 0.7f)};

    constexpr int kFar = 32;
    methods::reference::PathTracerSettings direct_only;
    direct_only.max_bounces = 0;
    const image::ErrorMetrics error =
        image::compare(render_scene(scene, method_request("direct", "medium", kFar)).frame,
                       pixel_centre_reference(scene, kFar, 4, direct_only));
    RecordProperty("mean_ratio", std::to_string(error.mean_test / error.mean_reference));
    EXPECT_GT(error.mean_reference, 0.0);
    EXPECT_NEAR(error.mean_test, error.mean_reference, 0.05 * error.mean_reference);
}

}  // namespace
}  // namespace bounce::test
