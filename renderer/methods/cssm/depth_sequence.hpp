// A long sequence of depth maps of equal size, compressed per pixel (§3.2 of
// [cssm] in docs/references.md and its CSM predecessor): each pixel's depths along the
// sequence become a piecewise-constant run list. A map need not store its first hit exactly: any
// value between the first and the second hit answers a shadow test the same way (dual depth
// layers), and pixels that no query reads are "don't care". So a run continues while the
// admissible intervals of consecutive maps still overlap, and stores a value inside all of them.
//
// Depths are 16-bit linear depth (0 = the map's origin plane, 65535 = its far plane).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace bounce::methods::cssm {

constexpr std::uint32_t kDepthMax = 65535;

// The stored values a pixel may take: lo..hi inclusive.
struct DepthInterval {
    std::uint16_t lo = 0, hi = kDepthMax;
};

// The interval for a first hit at `first` and second at `second` (linear depth over the far
// plane; 1 or more for no hit). The stored value must not reach `second`: a receiver there is
// behind the first surface.
DepthInterval admissible_interval(float first, float second);
// The same for a lookup that lights a receiver at depth d where the stored value is at least
// d - bias(d) (a surface's cube map: cssm_visibility): the value stays below the second hit less
// its bias there, so that a receiver on the second surface stays behind the first.
DepthInterval biased_interval(float first, float second, float second_bias);
constexpr DepthInterval kDontCare{0, kDepthMax};

struct CompressedDepthMaps {
    std::uint32_t maps = 0;
    std::uint32_t pixels = 0;  // per map
    std::vector<std::uint32_t> pixel_runs;  // pixels + 1 offsets into the run arrays
    std::vector<std::uint32_t> run_start;   // the first map of each run
    std::vector<std::uint16_t> run_depth;   // its stored depth

    // The stored depth of `pixel` in map `map` (binary search over the pixel's runs).
    std::uint16_t depth(std::uint32_t map, std::uint32_t pixel) const;
    std::size_t runs() const { return run_start.size(); }
    std::size_t uncompressed_bytes() const { return static_cast<std::size_t>(maps) * pixels * sizeof(std::uint16_t); }
    std::size_t compressed_bytes() const {
        return pixel_runs.size() * sizeof(std::uint32_t) + run_start.size() * (sizeof(std::uint32_t) + sizeof(std::uint16_t));
    }
};

// Streams maps in sequence order (a chunk at a time), keeping per pixel the open run's interval.
// Greedy extension is optimal: it yields the fewest runs any piecewise-constant choice can.
class DepthSequenceCompressor {
public:
    explicit DepthSequenceCompressor(std::uint32_t pixels);
    // `intervals` holds `count` maps of `pixels` intervals each, map-major.
    void append(std::span<const DepthInterval> intervals, std::uint32_t count);
    CompressedDepthMaps finish();

private:
    struct OpenRun {
        std::uint32_t start = 0;
        std::uint16_t lo = 0, hi = kDepthMax;
    };
    std::uint32_t pixels_;
    std::uint32_t maps_ = 0;
    std::vector<OpenRun> open_;
    std::vector<std::vector<std::uint32_t>> starts_;
    std::vector<std::vector<std::uint16_t>> depths_;
};

}  // namespace bounce::methods::cssm
