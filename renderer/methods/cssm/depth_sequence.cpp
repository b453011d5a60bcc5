#include "renderer/methods/cssm/depth_sequence.hpp"

#include "renderer/base/error.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace bounce::methods::cssm {

DepthInterval admissible_interval(float first, float second) {
    if (!(first < 1.0f)) return {kDepthMax, kDepthMax};  // nothing within the far plane
    const float scale = static_cast<float>(kDepthMax);
    const auto lo = static_cast<std::uint32_t>(std::ceil(std::max(first, 0.0f) * scale));
    // Strictly before the second hit; a lone surface (no second hit) allows up to the far plane.
    const std::uint32_t hi = second >= 1.0f ? kDepthMax
                                            : static_cast<std::uint32_t>(std::max(0.0f, std::ceil(second * scale) - 1.0f));
    if (hi < lo) {
        // The two hits fall in one quantization step (a sheet thinner than 1/65535 of the far
        // plane): the first hit, rounded, is the closest admissible answer.
        const auto value = static_cast<std::uint16_t>(std::min(lo, kDepthMax));
        return {value, value};
    }
    return {static_cast<std::uint16_t>(std::min(lo, kDepthMax)), static_cast<std::uint16_t>(std::min(hi, kDepthMax))};
}

DepthInterval biased_interval(float first, float second, float second_bias) {
    if (!(first < 1.0f)) return {kDepthMax, kDepthMax};  // nothing within the far plane
    return admissible_interval(first, second < 1.0f ? second - second_bias : second);
}

std::uint16_t CompressedDepthMaps::depth(std::uint32_t map, std::uint32_t pixel) const {
    BOUNCE_CHECK(pixel < pixels && map < maps, "depth lookup out of range: map {} of {}, pixel {} of {}", map, maps, pixel,
                 pixels);
    std::uint32_t lo = pixel_runs[pixel], hi = pixel_runs[pixel + 1] - 1;  // runs [lo, hi]; run lo starts at map 0
    while (lo < hi) {
        const std::uint32_t mid = (lo + hi + 1) / 2;
        if (run_start[mid] <= map) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    return run_depth[lo];
}

DepthSequenceCompressor::DepthSequenceCompressor(std::uint32_t pixels)
    : pixels_(pixels), open_(pixels), starts_(pixels), depths_(pixels) {}

void DepthSequenceCompressor::append(std::span<const DepthInterval> intervals, std::uint32_t count) {
    BOUNCE_CHECK(intervals.size() == static_cast<std::size_t>(count) * pixels_, "compressor: {} intervals for {} maps of {} pixels",
                 intervals.size(), count, pixels_);
    const std::uint32_t first_map = maps_;
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, pixels_, 256), [&](const tbb::blocked_range<std::uint32_t>& range) {
        for (std::uint32_t p = range.begin(); p != range.end(); ++p) {
            OpenRun& run = open_[p];
            for (std::uint32_t m = 0; m < count; ++m) {
                const DepthInterval next = intervals[static_cast<std::size_t>(m) * pixels_ + p];
                const std::uint32_t map = first_map + m;
                if (map == 0) {
                    run = {0, next.lo, next.hi};
                    continue;
                }
                const std::uint16_t lo = std::max(run.lo, next.lo), hi = std::min(run.hi, next.hi);
                if (lo <= hi) {
                    run.lo = lo;
                    run.hi = hi;
                    continue;
                }
                starts_[p].push_back(run.start);
                depths_[p].push_back(static_cast<std::uint16_t>((static_cast<std::uint32_t>(run.lo) + run.hi) / 2));
                run = {map, next.lo, next.hi};
            }
        }
    });
    maps_ += count;
}

CompressedDepthMaps DepthSequenceCompressor::finish() {
    CompressedDepthMaps result;
    result.maps = maps_;
    result.pixels = pixels_;
    result.pixel_runs.resize(static_cast<std::size_t>(pixels_) + 1, 0);
    std::size_t total = 0;
    for (std::uint32_t p = 0; p < pixels_; ++p) {
        result.pixel_runs[p] = static_cast<std::uint32_t>(total);
        total += starts_[p].size() + (maps_ > 0 ? 1 : 0);
    }
    result.pixel_runs[pixels_] = static_cast<std::uint32_t>(total);
    result.run_start.reserve(total);
    result.run_depth.reserve(total);
    for (std::uint32_t p = 0; p < pixels_; ++p) {
        result.run_start.insert(result.run_start.end(), starts_[p].begin(), starts_[p].end());
        result.run_depth.insert(result.run_depth.end(), depths_[p].begin(), depths_[p].end());
        if (maps_ > 0) {
            // The open run: the middle of what every map in it admits (the widest margin to both hits).
            result.run_start.push_back(open_[p].start);
            result.run_depth.push_back(static_cast<std::uint16_t>((static_cast<std::uint32_t>(open_[p].lo) + open_[p].hi) / 2));
        }
        std::vector<std::uint32_t>().swap(starts_[p]);
        std::vector<std::uint16_t>().swap(depths_[p]);
    }
    return result;
}

}  // namespace bounce::methods::cssm
