#include "renderer/image/tone.hpp"

#include "renderer/base/error.hpp"

#include <algorithm>
#include <cmath>

namespace bounce::image {

ToneCurve parse_tone_curve(std::string_view name) {
    if (name == "none") return ToneCurve::none;
    if (name == "reinhard") return ToneCurve::reinhard;
    if (name == "aces") return ToneCurve::aces;
    throw InputError(fmt::format("unknown tone curve '{}' (expected none, reinhard or aces)", name));
}

std::string_view tone_curve_name(ToneCurve curve) {
    switch (curve) {
        case ToneCurve::none: return "none";
        case ToneCurve::reinhard: return "reinhard";
        case ToneCurve::aces: return "aces";
    }
    return "none";
}

namespace {

// Each function mirrors its namesake in shaders/common/tonemap.glsl, in the same float arithmetic.
float tone_curve(float x, ToneCurve curve) {
    x = std::max(x, 0.0f);
    switch (curve) {
        case ToneCurve::reinhard: return x / (1.0f + x);
        case ToneCurve::aces: return std::clamp((x * (2.51f * x + 0.03f)) / (x * (2.43f * x + 0.59f) + 0.14f), 0.0f, 1.0f);
        case ToneCurve::none: break;
    }
    return std::clamp(x, 0.0f, 1.0f);
}

float linear_to_srgb(float c) {
    return c <= 0.0031308f ? c * 12.92f : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

// GL's conversion of a float to an 8-bit normalized channel: clamp, scale, round to nearest.
std::uint8_t to_unorm8(float value) {
    return static_cast<std::uint8_t>(std::lround(std::clamp(value, 0.0f, 1.0f) * 255.0f));
}

}  // namespace

void make_display_image(Frame& frame, const DisplayTransform& transform) {
    const std::size_t pixels = static_cast<std::size_t>(frame.width) * static_cast<std::size_t>(frame.height);
    BOUNCE_CHECK(frame.width > 0 && frame.height > 0 && frame.rgba.size() == pixels * 4, "frame {}x{} with {} values",
                 frame.width, frame.height, frame.rgba.size());
    const float scale = std::exp2(transform.exposure);
    frame.display_rgba8.resize(pixels * 4);
    for (std::size_t i = 0; i < pixels; ++i) {
        for (std::size_t c = 0; c < 3; ++c) {
            const float radiance = frame.rgba[4 * i + c];
            const float finite = std::isfinite(radiance) ? radiance : 0.0f;
            frame.display_rgba8[4 * i + c] = to_unorm8(linear_to_srgb(tone_curve(finite * scale, transform.curve)));
        }
        frame.display_rgba8[4 * i + 3] = 255;
    }
}

}  // namespace bounce::image
