#include "renderer/image/frame.hpp"

#include <cmath>

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

}  // namespace bounce::image
