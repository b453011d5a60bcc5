#include "renderer/methods/reference/denoiser.hpp"

#include "renderer/base/error.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace bounce::methods::reference {
namespace {

constexpr float kKernel[5] = {1.0f / 16.0f, 1.0f / 4.0f, 3.0f / 8.0f, 1.0f / 4.0f, 1.0f / 16.0f};
constexpr float kAlbedoFloor = 1e-3f;  // below it a pixel is filtered as radiance (black surfaces, misses)

using image::luminance;

}  // namespace

image::Frame denoise(const image::Frame& noisy, const PixelFeatures& features, const DenoiseSettings& settings) {
    const int width = noisy.width, height = noisy.height;
    if (features.width != width || features.height != height) {
        throw InputError(fmt::format("denoise: a {}x{} frame with {}x{} features", width, height, features.width,
                                     features.height));
    }
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    // Demodulate: what each pixel's surface receives (its radiance over its albedo), and the
    // variance of its luminance likewise.
    std::vector<glm::vec3> albedo(pixels), current(pixels), next(pixels);
    std::vector<float> variance(pixels), next_variance(pixels);
    for (std::size_t i = 0; i < pixels; ++i) {
        const glm::vec3 a = features.albedo[i];
        albedo[i] = glm::vec3(a.r > kAlbedoFloor ? a.r : 1.0f, a.g > kAlbedoFloor ? a.g : 1.0f, a.b > kAlbedoFloor ? a.b : 1.0f);
        const glm::vec3 radiance(noisy.rgba[4 * i], noisy.rgba[4 * i + 1], noisy.rgba[4 * i + 2]);
        current[i] = radiance / albedo[i];
        const float a_lum = std::max(luminance(albedo[i]), kAlbedoFloor);
        variance[i] = features.variance.empty() ? 0.0f : features.variance[i] / (a_lum * a_lum);
    }
    // A pixel's own variance estimate is as noisy as its colour: average it over 3x3 first (SVGF).
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            float sum = 0.0f;
            int n = 0;
            for (int j = -1; j <= 1; ++j)
                for (int i = -1; i <= 1; ++i) {
                    const int qx = x + i, qy = y + j;
                    if (qx < 0 || qy < 0 || qx >= width || qy >= height) continue;
                    sum += variance[static_cast<std::size_t>(qy) * width + qx];
                    ++n;
                }
            next_variance[static_cast<std::size_t>(y) * width + x] = sum / static_cast<float>(n);
        }
    }
    std::swap(variance, next_variance);
    for (int iteration = 0; iteration < std::max(settings.iterations, 0); ++iteration) {
        const int hole = 1 << iteration;
        tbb::parallel_for(0, height, [&](int y) {
            for (int x = 0; x < width; ++x) {
                const std::size_t p = static_cast<std::size_t>(y) * width + x;
                const glm::vec3 cp = current[p], np = features.normal[p];
                const float dp = features.depth[p], hit_p = features.coverage[p];
                const float lp = luminance(cp);
                const float colour_scale = settings.sigma_colour * std::sqrt(variance[p]) + 1e-6f * (lp + 1e-6f);
                glm::vec3 sum(0.0f);
                float weights = 0.0f, variance_sum = 0.0f;
                for (int j = -2; j <= 2; ++j) {
                    const int qy = y + j * hole;
                    if (qy < 0 || qy >= height) continue;
                    for (int i = -2; i <= 2; ++i) {
                        const int qx = x + i * hole;
                        if (qx < 0 || qx >= width) continue;
                        const std::size_t q = static_cast<std::size_t>(qy) * width + qx;
                        // Pixels that hit something and pixels that missed do not mix.
                        if ((hit_p > 0.0f) != (features.coverage[q] > 0.0f)) continue;
                        const glm::vec3 cq = current[q];
                        float exponent = std::abs(lp - luminance(cq)) / colour_scale;
                        const glm::vec3 dn = np - features.normal[q];
                        exponent += glm::dot(dn, dn) / (settings.sigma_normal * settings.sigma_normal);
                        if (hit_p > 0.0f) {
                            const float dz = (dp - features.depth[q]) /
                                             (settings.sigma_depth * static_cast<float>(hole) * std::max(dp, 1e-12f));
                            exponent += dz * dz;
                        }
                        const float w = kKernel[i + 2] * kKernel[j + 2] * std::exp(-exponent);
                        sum += w * cq;
                        weights += w;
                        variance_sum += w * w * variance[q];
                    }
                }
                // The centre tap always weighs 9/64: weights > 0.
                next[p] = sum / weights;
                next_variance[p] = variance_sum / (weights * weights);
            }
        });
        std::swap(current, next);
        std::swap(variance, next_variance);
    }
    image::Frame out = noisy;
    for (std::size_t i = 0; i < pixels; ++i) {
        const glm::vec3 radiance = current[i] * albedo[i];
        for (int c = 0; c < 3; ++c) out.rgba[4 * i + c] = std::isfinite(radiance[c]) ? radiance[c] : 0.0f;
    }
    out.display_rgba8.clear();
    return out;
}

}  // namespace bounce::methods::reference
