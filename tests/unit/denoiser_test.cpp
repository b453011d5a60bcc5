// The reference's denoiser (renderer/methods/reference/denoiser.hpp): it keeps what is already
// right (a noise-free constant image, an edge between surfaces of different normals) and lowers
// the error of a noisy frame against the converged one.
#include "renderer/base/error.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/reference/denoiser.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

#include <cstdio>

namespace bounce::methods::reference {
namespace {

PixelFeatures flat_features(int width, int height, const glm::vec3& normal) {
    PixelFeatures features;
    features.width = width;
    features.height = height;
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    features.albedo.assign(pixels, glm::vec3(0.5f));
    features.normal.assign(pixels, normal);
    features.depth.assign(pixels, 2.0f);
    features.coverage.assign(pixels, 1.0f);
    features.variance.assign(pixels, 0.0f);
    return features;
}

image::Frame filled(int width, int height, const std::function<glm::vec3(int, int)>& colour) {
    image::Frame frame;
    frame.width = width;
    frame.height = height;
    frame.rgba.resize(static_cast<std::size_t>(width) * height * 4);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const glm::vec3 c = colour(x, y);
            float* out = &frame.rgba[(static_cast<std::size_t>(y) * width + x) * 4];
            out[0] = c.r, out[1] = c.g, out[2] = c.b, out[3] = 1.0f;
        }
    return frame;
}

// The filter's weights are normalized: a constant image comes back unchanged (float rounding).
TEST(Denoiser, KeepsAConstantImage) {
    const image::Frame flat = filled(40, 30, [](int, int) { return glm::vec3(0.3f, 0.2f, 0.1f); });
    const image::Frame out = denoise(flat, flat_features(40, 30, {0, 1, 0}));
    for (std::size_t i = 0; i < out.rgba.size(); ++i) EXPECT_NEAR(out.rgba[i], flat.rgba[i], 1e-6f) << i;
}

// Two surfaces at right angles meet along a column, one lit and one dark, both noisy (large
// variance): the lit side must not bleed into the dark one. Across the edge a tap weighs
// exp(-|n_p - n_q|^2 / sigma_n^2) = exp(-2 / 0.09), about 2e-10 of a like tap.
TEST(Denoiser, DoesNotBlurAcrossAnEdgeBetweenNormals) {
    PixelFeatures features = flat_features(32, 16, {0, 1, 0});
    for (int y = 0; y < 16; ++y)
        for (int x = 16; x < 32; ++x) features.normal[static_cast<std::size_t>(y) * 32 + x] = {1, 0, 0};
    features.variance.assign(features.variance.size(), 1.0f);
    const image::Frame edge = filled(32, 16, [](int x, int) { return glm::vec3(x < 16 ? 1.0f : 0.0f); });
    const image::Frame out = denoise(edge, features);
    for (int y = 0; y < 16; ++y) {
        EXPECT_NEAR(out.at(15, y).r, 1.0f, 1e-6f);
        EXPECT_NEAR(out.at(16, y).r, 0.0f, 1e-6f);
    }
}

TEST(Denoiser, RefusesFeaturesOfAnotherSize) {
    const image::Frame frame = filled(8, 8, [](int, int) { return glm::vec3(1.0f); });
    EXPECT_THROW(denoise(frame, flat_features(8, 4, {0, 1, 0})), InputError);
}

// On the Cornell box at 64x64, 16 samples per pixel, the filtered frame is closer to the converged
// one (1024 spp) than the noisy frame is, in relMSE, for each of three seeds. The filter is biased
// darker: a firefly differs from its neighbours by many standard deviations, so they leave it out
// of their sums while it still averages with them (measured: the mean falls 1.3% to 1.7% from the
// noisy frame's). The means are held within 3% of each other: a wrong normalization or
// demodulation moves light wholesale, by tens of percent.
TEST(Denoiser, LowersTheErrorOfANoisyCornellFrame) {
    const scene::Scene scene = scene::make_cornell_box();
    const PathTracer tracer(scene);
    PathTracerSettings settings;
    const image::Frame truth = tracer.render(scene.cameras[0], 64, 64, 1024, settings);
    for (std::uint64_t seed : {2u, 3u, 4u}) {
        settings.seed = seed;
        Accumulator accumulator(64, 64);
        tracer.render(accumulator, scene.cameras[0], 16, settings);
        const image::Frame noisy = accumulator.frame();
        const image::Frame filtered = denoise(noisy, accumulator.features());
        const image::ErrorMetrics before = image::compare(noisy, truth), after = image::compare(filtered, truth);
        std::printf("seed %llu: relMSE noisy %.4f, denoised %.4f; mean %.4f -> %.4f (converged %.4f)\n",
                    static_cast<unsigned long long>(seed), before.rel_mse, after.rel_mse, before.mean_test,
                    after.mean_test, after.mean_reference);
        EXPECT_LT(after.rel_mse, before.rel_mse);
        EXPECT_NEAR(after.mean_test, before.mean_test, 0.03 * before.mean_test);
    }
}

}  // namespace
}  // namespace bounce::methods::reference
