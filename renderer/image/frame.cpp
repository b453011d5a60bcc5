#include "renderer/image/frame.hpp"

#include "renderer/base/error.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace bounce::image {

std::size_t Frame::non_finite_count() const {
    // Counts pixels, not channels: a pixel with NaN in every channel is one bad sample to the caller.
    std::size_t count = 0;
    const std::size_t pixels = rgba.size() / 4;
    for (std::size_t p = 0; p < pixels; ++p) {
        const float* px = &rgba[p * 4];
        if (!std::isfinite(px[0]) || !std::isfinite(px[1]) || !std::isfinite(px[2]) ||
            !std::isfinite(px[3])) {
            ++count;
        }
    }
    return count;
}

Frame resample_linear(const Frame& frame, int width, int height) {
    if (frame.width <= 0 || frame.height <= 0 || width <= 0 || height <= 0) {
        throw InputError(fmt::format("cannot resample a {}x{} frame to {}x{}", frame.width, frame.height, width, height));
    }
    Frame out;
    out.width = width;
    out.height = height;
    out.rgba.resize(static_cast<std::size_t>(width) * height * 4);
    // A target pixel centre in the source's pixel coordinates, and its two neighbours and weight.
    const auto axis = [](int i, int to, int from) {
        const float x = std::clamp((static_cast<float>(i) + 0.5f) * static_cast<float>(from) / static_cast<float>(to) - 0.5f, 0.0f,
                                   static_cast<float>(from - 1));
        const int lo = static_cast<int>(x);
        return std::tuple{lo, std::min(lo + 1, from - 1), x - static_cast<float>(lo)};
    };
    for (int y = 0; y < height; ++y) {
        const auto [y0, y1, fy] = axis(y, height, frame.height);
        for (int x = 0; x < width; ++x) {
            const auto [x0, x1, fx] = axis(x, width, frame.width);
            const glm::vec4 top = glm::mix(frame.at(x0, y0), frame.at(x1, y0), fx);
            const glm::vec4 bottom = glm::mix(frame.at(x0, y1), frame.at(x1, y1), fx);
            const glm::vec4 value = glm::mix(top, bottom, fy);
            float* px = &out.rgba[(static_cast<std::size_t>(y) * width + x) * 4];
            for (int c = 0; c < 4; ++c) px[c] = value[c];
        }
    }
    return out;
}

}  // namespace bounce::image
