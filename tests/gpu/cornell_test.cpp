// The built-in Cornell box renders with `direct` to PNG and EXR, with absolute radiance where the
// geometry gives a closed form.
#include "gpu_fixture.hpp"
#include "renderer/image/codec.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace bounce::test {
namespace {

TEST(Cornell, FloorRadianceMatchesInverseSquareLaw) {
    const scene::Scene scene = scene::make_cornell_box();
    RenderRequest request;
    request.width = request.height = 128;
    const auto result = render_scene(scene, request);
    const scene::Camera& camera = scene.cameras[0];
    const scene::Light& light = scene.lights[0];

    // A floor point in front of the tall block with a clear line to the light and to the camera.
    const glm::ivec2 pixel = project_to_pixel(camera, 128, 128, {0.42f, 0.0f, 0.12f});
    const glm::vec3 p = pixel_on_ground(camera, 128, 128, pixel.x, pixel.y);
    const glm::vec3 to_light = light.position - p;
    const float d2 = glm::dot(to_light, to_light);
    const float irradiance = light.intensity * to_light.y / std::sqrt(d2) / d2;
    const glm::vec3 white{0.725f, 0.71f, 0.68f};
    const glm::vec3 expected = white / std::numbers::pi_v<float> * irradiance;
    const glm::vec4 actual = result.frame.at(pixel.x, pixel.y);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(actual[c], expected[c], 0.01f * expected[c]) << "channel " << c;
}

TEST(Cornell, RedWallLeftGreenWallRight) {
    RenderRequest request;
    request.width = request.height = 64;
    const auto result = render_scene(scene::make_cornell_box(), request);
    const glm::vec4 left = result.frame.at(3, 32);
    const glm::vec4 right = result.frame.at(60, 32);
    // Reflectances: red (0.63, 0.065, 0.05), green (0.14, 0.45, 0.091); the light is white, so the
    // channel ratios of a lit wall are the reflectance ratios.
    EXPECT_NEAR(left.g / left.r, 0.065f / 0.63f, 0.01f);
    EXPECT_NEAR(right.r / right.g, 0.14f / 0.45f, 0.01f);
    EXPECT_EQ(result.frame.non_finite_count(), 0u);
}

TEST(Cornell, EncodesToPngAndLosslessExr) {
    RenderRequest request;
    request.width = 96;
    request.height = 64;
    const auto result = render_scene(scene::make_cornell_box(), request);

    const auto png = image::encode_image(result.frame, image::ImageFormat::png);
    const auto decoded_png = image::decode_image(png);
    EXPECT_EQ(decoded_png.width, 96);
    EXPECT_EQ(decoded_png.height, 64);
    EXPECT_EQ(decoded_png.format, "png");
    for (int y = 0; y < 64; y += 7) {
        for (int x = 0; x < 96; x += 7) {
            EXPECT_FLOAT_EQ(decoded_png.at(x, y, 0), result.frame.display_at(x, y).r / 255.0f);
        }
    }

    const auto exr = image::encode_image(result.frame, image::ImageFormat::exr);
    const auto decoded_exr = image::decode_image(exr);
    ASSERT_EQ(decoded_exr.channels, 4);
    ASSERT_EQ(decoded_exr.pixels.size(), result.frame.rgba.size());
    for (std::size_t i = 0; i < result.frame.rgba.size(); ++i) {
        ASSERT_EQ(decoded_exr.pixels[i], result.frame.rgba[i]) << "value " << i;
    }
}

TEST(Cornell, MovingABlockChangesOnlyWhereItWasAndIs) {
    scene::Scene scene = scene::make_cornell_box();
    RenderRequest request;
    request.width = request.height = 64;
    auto resources = shared_renderer().upload(scene);
    const auto before = shared_renderer().render(*resources, request);
    const auto index = scene.find_object("short_block");
    ASSERT_TRUE(index.has_value());
    scene.objects[*index].transform[3] += glm::vec4(0.0f, 0.0f, 0.15f, 0.0f);  // 15 cm back
    const auto after = shared_renderer().render(*resources, request);
    // The top-left corner (the red wall, high up) is untouched; the block's old place changed.
    EXPECT_EQ(before.frame.at(4, 10), after.frame.at(4, 10));
    const glm::ivec2 old_top = project_to_pixel(scene.cameras[0], 64, 64, {0.17f, 0.165f, 0.10f});
    EXPECT_NE(before.frame.at(old_top.x, old_top.y), after.frame.at(old_top.x, old_top.y));
}

}  // namespace
}  // namespace bounce::test

namespace bounce::test {
namespace {

// `direct` and `reference` with zero bounces render the same light transport with the same BRDF.
// With camera rays through pixel centres, as raster shades, the reference is exact here (point
// light, no indirect light: no noise at all), so what remains is the shadow maps' filtering along
// shadow edges. Measured on llvmpipe: relMSE 1.8e-5, means within 0.02% (shadow_map_size 2048,
// `high`). The bound, 2e-4, leaves room for another driver's rasterization of those edges; a wrong
// BRDF, light or unit moves every pixel and the mean, far past it.
TEST(Cornell, DirectAgreesWithTheReferenceAtZeroBounces) {
    const scene::Scene scene = scene::make_cornell_box();
    RenderRequest request;
    request.width = request.height = 64;
    request.preset = "high";
    const auto direct = render_scene(scene, request);
    methods::reference::PathTracer tracer(scene);
    methods::reference::PathTracerSettings settings;
    settings.max_bounces = 0;
    settings.pixel_jitter = false;
    const auto truth = tracer.render(scene.cameras[0], 64, 64, 4, settings);
    const image::ErrorMetrics error = image::compare(direct.frame, truth);
    std::printf("direct vs reference (0 bounces, 64x64, pixel centres): relMSE %.6f RMSE %.6f mean %.6f vs %.6f\n",
                error.rel_mse, error.rmse, error.mean_test, error.mean_reference);
    EXPECT_NEAR(error.mean_test, error.mean_reference, 0.005 * error.mean_reference);
    EXPECT_LT(error.rel_mse, 2e-4);
}

}  // namespace
}  // namespace bounce::test
