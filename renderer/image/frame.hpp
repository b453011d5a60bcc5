// A rendered frame: linear HDR radiance, plus the display-referred 8-bit image when one was made.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace bounce::image {

// Rec. 709 luminance of linear RGB: what the path tracer's variances and the denoiser's weights are of.
inline float luminance(const glm::vec3& rgb) { return 0.2126f * rgb.r + 0.7152f * rgb.g + 0.0722f * rgb.b; }

struct Frame {
    int width = 0;
    int height = 0;
    std::vector<float> rgba;  // linear RGBA32F, width * height * 4, rows top to bottom
    std::vector<std::uint8_t> display_rgba8;  // tone-mapped, sRGB-encoded; empty if not made

    glm::vec4 at(int x, int y) const {
        const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 4;
        return {rgba[i], rgba[i + 1], rgba[i + 2], rgba[i + 3]};
    }
    glm::u8vec4 display_at(int x, int y) const {
        const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 4;
        return {display_rgba8[i], display_rgba8[i + 1], display_rgba8[i + 2], display_rgba8[i + 3]};
    }
    // Number of pixels with a NaN or infinite channel.
    std::size_t non_finite_count() const;
};

// `frame`'s linear radiance resampled to width x height, bilinear between pixel centres (edges
// clamped); no display image. Throws InputError for an empty frame or size.
Frame resample_linear(const Frame& frame, int width, int height);

}  // namespace bounce::image
