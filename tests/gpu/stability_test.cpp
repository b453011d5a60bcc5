// No NaN or Inf reaches a frame at the extremes, and results are invariant to uniform scene scale
// when light intensities scale with it.
#include "gpu_fixture.hpp"
#include "renderer/base/error.hpp"
#include "renderer/scene/builtin.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace bounce::test {
namespace {

scene::Scene cornell_with_intensity(float intensity) {
    scene::Scene scene = scene::make_cornell_box();
    scene.lights[0].intensity = intensity;
    return scene;
}

// The Cornell box scaled by k about the origin, with point intensities scaled by k^2: the same
// radiance everywhere in theory.
scene::Scene scaled_cornell(float k) {
    scene::Scene scaled = scene::make_cornell_box();
    for (auto& object : scaled.objects) object.transform = glm::scale(glm::mat4(1.0f), glm::vec3(k)) * object.transform;
    for (auto& light : scaled.lights) {
        light.position *= k;
        light.intensity *= k * k;
    }
    for (auto& camera : scaled.cameras) camera.position *= k;
    return scaled;
}

// Every test runs for each GPU method.
class Stability : public ::testing::TestWithParam<std::string> {
protected:
    RenderRequest small_request() const {
        RenderRequest request;
        request.method = GetParam();
        request.width = request.height = 48;
        request.preset = "draft";
        return request;
    }
};

TEST_P(Stability, ZeroAndHugeIntensityStayFiniteAndLinear) {
    const auto zero = render_scene(cornell_with_intensity(0.0f), small_request());
    EXPECT_EQ(zero.frame.non_finite_count(), 0u);
    for (std::size_t i = 0; i < zero.frame.rgba.size(); ++i) {
        if (i % 4 != 3) ASSERT_EQ(zero.frame.rgba[i], 0.0f) << "value " << i;
    }

    const auto one = render_scene(cornell_with_intensity(1.0f), small_request());
    const auto huge = render_scene(cornell_with_intensity(1e6f), small_request());
    const auto tiny = render_scene(cornell_with_intensity(1e-6f), small_request());
    EXPECT_EQ(huge.frame.non_finite_count(), 0u);
    EXPECT_EQ(tiny.frame.non_finite_count(), 0u);
    // Every colour channel of every pixel (alpha is coverage, not radiance), to float rounding. vct
    // adds photons with float atomics in whatever order threads run and stores radiance over the
    // frame's largest in half floats, so one ulp of difference in a sum can move a leaf voxel by one
    // code (at most 2^-10 of a normal half's value); each mip level averages the level below and
    // rounds again, adding up to one code more, and a cone's light is a weighted mean of samples:
    // its indirect light, at most the whole pixel, agrees to a code per level. (An H200 measured
    // 1.3e-3 at 1e6 and 3.2e-3 at 1e-6 of the lamp with the box's 5 levels; llvmpipe under 1e-5.)
    const auto levels = one.stats.method_statistics.find("octree_levels");
    const float relative = GetParam() == "vct" && levels != one.stats.method_statistics.end()
                               ? static_cast<float>(levels->second) / 1024.0f
                               : 1e-5f;
    double largest_huge = 0.0, largest_tiny = 0.0;  // relative to the scaled pixel
    for (std::size_t i = 0; i < one.frame.rgba.size(); ++i) {
        if (i % 4 == 3 || one.frame.rgba[i] <= 0.0f) continue;
        const double reference = one.frame.rgba[i];
        largest_huge = std::max(largest_huge, std::abs(huge.frame.rgba[i] / (reference * 1e6) - 1.0));
        largest_tiny = std::max(largest_tiny, std::abs(tiny.frame.rgba[i] / (reference * 1e-6) - 1.0));
    }
    std::printf("%s: largest relative difference from the scaled frame %.3g at 1e6, %.3g at 1e-6 (allowed %.3g)\n",
                GetParam().c_str(), largest_huge, largest_tiny, static_cast<double>(relative));
    for (std::size_t i = 0; i < one.frame.rgba.size(); ++i) {
        if (i % 4 == 3) continue;
        const float reference = one.frame.rgba[i];
        ASSERT_NEAR(huge.frame.rgba[i], reference * 1e6f, relative * reference * 1e6f + 1e-3f)
            << "pixel " << i / 4 << " channel " << i % 4;
        ASSERT_NEAR(tiny.frame.rgba[i], reference * 1e-6f, relative * reference * 1e-6f + 1e-12f)
            << "pixel " << i / 4 << " channel " << i % 4;
    }
    // The display image clips to white instead of wrapping or going black: check the brightest pixel.
    std::size_t brightest = 0;
    for (std::size_t i = 0; i < one.frame.rgba.size(); i += 4) {
        if (one.frame.rgba[i] > one.frame.rgba[brightest]) brightest = i;
    }
    ASSERT_GT(one.frame.rgba[brightest], 0.0f);
    EXPECT_EQ(huge.frame.display_rgba8[brightest], 255);
}

TEST_P(Stability, DegenerateAndCoincidentTrianglesStayFinite) {
    scene::Scene scene = scene::make_cornell_box();
    scene::Primitive degenerate;
    degenerate.material = 0;
    // A zero-area triangle, a line-like sliver, and a triangle coincident with the floor.
    degenerate.positions = {{0.2f, 0.1f, 0.2f}, {0.2f, 0.1f, 0.2f}, {0.2f, 0.1f, 0.2f},
                            {0.1f, 0.2f, 0.1f}, {0.3f, 0.2f, 0.1f}, {0.5f, 0.2f, 0.1f},
                            {0.1f, 0.0f, 0.1f}, {0.4f, 0.0f, 0.1f}, {0.1f, 0.0f, 0.4f}};
    degenerate.normals = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}, {0, 1, 0}};
    degenerate.tangents.assign(9, glm::vec4(1, 0, 0, 1));
    degenerate.indices = {0, 1, 2, 3, 4, 5, 6, 7, 8};
    for (const auto& p : degenerate.positions) degenerate.bounds.extend(p);
    scene::Mesh mesh;
    mesh.name = "degenerate";
    mesh.bounds = degenerate.bounds;
    mesh.primitives.push_back(degenerate);
    scene.meshes.push_back(mesh);
    scene::Object object;
    object.name = "degenerate";
    object.mesh = static_cast<int>(scene.meshes.size()) - 1;
    scene.objects.push_back(object);
    // A light exactly on a surface and a spot with a zero-width cone.
    scene::Light on_surface = scene.lights[0];
    on_surface.name = "on_floor";
    on_surface.position = {0.3f, 0.0f, 0.3f};
    scene.lights.push_back(on_surface);
    scene::Light spot = scene.lights[0];
    spot.name = "needle";
    spot.type = scene::LightType::spot;
    spot.direction = {0, -1, 0};
    spot.inner_cone = spot.outer_cone = 0.0f;
    scene.lights.push_back(spot);
    const auto result = render_scene(scene, small_request());
    EXPECT_EQ(result.frame.non_finite_count(), 0u);
}

// Extreme roughness and metalness with white base colour: a dielectric then has a diffuse albedo,
// so its extremes reach the GI paths (light-view VPLs, voxel radiance, atlas exitance), and a metal
// its specular lobe. Every frame finite, and indirect light present where there is diffuse albedo.
TEST_P(Stability, ExtremeMaterialsStayFinite) {
    const auto direct = [&](const scene::Scene& scene) {
        RenderRequest request = small_request();
        request.method = "direct";
        return render_scene(scene, request);
    };
    for (float roughness : {0.0f, 1e-4f, 1.0f}) {
        for (float metallic : {0.0f, 1.0f}) {
            scene::Scene scene = scene::make_cornell_box();
            for (auto& material : scene.materials) {
                material.roughness = roughness;
                material.metallic = metallic;
                material.specular = 1.0f;
                material.base_color = glm::vec4(1.0f);
            }
            const auto result = render_scene(scene, small_request());
            EXPECT_EQ(result.frame.non_finite_count(), 0u) << "roughness " << roughness << " metallic " << metallic;
            if (metallic == 0.0f && GetParam() != "direct") {
                // The GI path ran on this material: the frame gains on direct light alone.
                double with = 0.0, without = 0.0;
                const auto only_direct = direct(scene);
                for (std::size_t i = 0; i < result.frame.rgba.size(); ++i) {
                    if (i % 4 == 3) continue;
                    with += result.frame.rgba[i];
                    without += only_direct.frame.rgba[i];
                }
                EXPECT_GT(with, 1.05 * without) << "roughness " << roughness << ": no indirect light reached the frame";
            }
        }
    }
}

TEST_P(Stability, TinyAndOddFrameSizes) {
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{1, 1}, {1, 37}, {257, 3}}) {
        RenderRequest request = small_request();
        request.width = w;
        request.height = h;
        const auto result = render_scene(scene::make_cornell_box(), request);
        EXPECT_EQ(result.frame.width, w);
        EXPECT_EQ(result.frame.rgba.size(), static_cast<std::size_t>(w) * h * 4);
        EXPECT_EQ(result.frame.non_finite_count(), 0u);
    }
    RenderRequest bad = small_request();
    bad.width = 0;
    EXPECT_THROW(render_scene(scene::make_cornell_box(), bad), InputError);
}

// Scaling the scene by k and point intensities by k^2 leaves every radiance unchanged.
TEST_P(Stability, UniformScaleInvariance) {
    RenderRequest request = small_request();
    if (GetParam() == "cssm") {
        // cssm's refinement oracle is a hard threshold: rounding at another scale flips decisions
        // right at it (means still agree to 0.01%). With the oracle off, every other part (atlas,
        // bake, visibility, radiosity) must be invariant pixel for pixel.
        request.knobs = {{"threshold", 0.0}, {"final_threshold", 0.0}};
    }
    const auto base = render_scene(scene::make_cornell_box(), request);
    // Scales of no special relation to the grids (1e-3, 1e4) and scales that once put the box's
    // walls on vct's lattice points, where rounding chose between two pairs of voxels (0.1, 10, 1e3).
    for (float k : {1e-3f, 0.1f, 10.0f, 1e3f, 1e4f}) {
        const auto result = render_scene(scaled_cornell(k), request);
        EXPECT_EQ(result.frame.non_finite_count(), 0u);
        double error = 0.0, total = 0.0;
        std::size_t differing = 0;
        for (std::size_t i = 0; i < base.frame.rgba.size(); ++i) {
            if (i % 4 == 3) continue;
            const double d = std::abs(result.frame.rgba[i] - base.frame.rgba[i]);
            error += d;
            total += base.frame.rgba[i];
            differing += d > 0.01 * base.frame.rgba[i] + 1e-4;
        }
        // Shadow-map texels land on slightly different surface points at another scale, so a few
        // pixels on shadow edges may differ; the mean must agree to 1% and 98% of pixels exactly so.
        std::printf("%s at scale %g: mean |difference| %.3g of the mean, %zu channels over 1%%\n", GetParam().c_str(),
                    static_cast<double>(k), error / total, differing);
        EXPECT_LT(error / total, 0.01) << "scale " << k;
        EXPECT_LT(differing, base.frame.rgba.size() * 3 / 4 / 50) << "scale " << k;
    }
}

// The photons and VPLs a light sends do not depend on its intensity: a light at 1e-6 of the Cornell
// lamp injects as many photons into vct's octree, and gives isr's fragments as many VPLs, as the lamp
// itself. An H200's driver dropped every photon under about 3e-8 W (shaders now ask any_positive):
// vct injected none at 1e-4 of the lamp and isr's fragments gathered no VPL at 1e-6. Photon counts
// are exact; isr's traversal compares bounds linear in the intensity with a threshold linear in it,
// so its decisions are the same but where float rounding meets a tie (1% allowed).
TEST(StabilityDimLights, EveryPhotonAndVplOfADimLightIsKept) {
    const auto statistic = [](const std::string& method, float scale, const std::string& name) {
        scene::Scene scene = scene::make_cornell_box();
        scene.lights[0].intensity *= scale;
        RenderRequest request;
        request.method = method;
        request.preset = "draft";
        request.width = request.height = 48;
        const auto result = render_scene(scene, request);
        const auto it = result.stats.method_statistics.find(name);
        return it == result.stats.method_statistics.end() ? -1.0 : it->second;
    };
    const double photons = statistic("vct", 1.0f, "photons_injected");
    const double vpls = statistic("isr", 1.0f, "vpls_per_fragment_mean");
    ASSERT_GT(photons, 0.0);
    ASSERT_GT(vpls, 0.0);
    for (const float scale : {1e-3f, 1e-4f, 1e-6f}) {
        const double dim_photons = statistic("vct", scale, "photons_injected");
        const double dim_vpls = statistic("isr", scale, "vpls_per_fragment_mean");
        std::printf("light at %g of the lamp: vct photons %.0f (lamp %.0f), isr VPLs per fragment %.1f (lamp %.1f)\n", scale,
                    dim_photons, photons, dim_vpls, vpls);
        EXPECT_EQ(dim_photons, photons) << "scale " << scale;
        EXPECT_NEAR(dim_vpls, vpls, 0.01 * vpls) << "scale " << scale;
    }
}

// cssm with its refinement oracle on, as its presets run it: the oracle compares tone-mapped bounds
// with a threshold, the same at any scale, so the cut is the same but for rounding right at the
// threshold; the frame's mean at scale 1e-3 and 1e4 agrees with scale 1's to 1e-3 (each flipped
// decision swaps a node's gather for its children's, a difference far below it). With texel spots
// too (on from medium up): their offsets are world lengths taken from the samples', their widths
// ratios of the samples' spreads.
class StabilityCssm : public ::testing::TestWithParam<bool> {};

TEST_P(StabilityCssm, UniformScaleInvarianceWithTheOracleOn) {
    RenderRequest request;
    request.method = "cssm";
    request.preset = "draft";
    request.knobs = {{"texel_spots", GetParam() ? 1.0 : 0.0}};
    request.width = request.height = 48;
    const auto mean_of = [](const image::Frame& frame) {
        double sum = 0.0;
        for (std::size_t i = 0; i < frame.rgba.size(); ++i)
            if (i % 4 != 3) sum += frame.rgba[i];
        return sum / static_cast<double>(frame.rgba.size() * 3 / 4);
    };
    const double base = mean_of(render_scene(scene::make_cornell_box(), request).frame);
    // Scales of no special relation to the grids (1e-3, 1e4) and scales that once put the box's
    // walls on vct's lattice points, where rounding chose between two pairs of voxels (0.1, 10, 1e3).
    for (float k : {1e-3f, 0.1f, 10.0f, 1e3f, 1e4f}) {
        const auto result = render_scene(scaled_cornell(k), request);
        EXPECT_EQ(result.frame.non_finite_count(), 0u);
        EXPECT_NEAR(mean_of(result.frame), base, 1e-3 * base) << "scale " << k;
    }
}

INSTANTIATE_TEST_SUITE_P(Methods, Stability, ::testing::Values("direct", "vct", "isr", "cssm"),
                         [](const ::testing::TestParamInfo<std::string>& method) { return method.param; });
INSTANTIATE_TEST_SUITE_P(Spots, StabilityCssm, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& spots) { return spots.param ? "spots" : "whole_texels"; });

}  // namespace
}  // namespace bounce::test
