// The device's cost lines (costs.hpp), measured: every GPU method at every preset renders the
// built-in Cornell box at two sizes, warm (after a frame that builds its structures), and a line
// goes through the two times, at the presets' own bounce counts. Runs on the render thread, once per device: the daemon caches the
// result in its cache folder under the renderer's name.
#pragma once

#include "renderer/planning/costs.hpp"
#include "renderer/renderer.hpp"

#include <functional>
#include <string>
#include <vector>

namespace bounce::planning {

struct CalibrationSettings {
    int small_size = 32;  // the two frame sizes, in pixels per side
    int large_size = 64;
    int timed_frames = 1;  // per size, after one untimed frame; the fastest counts
    std::vector<std::string> methods;  // the GPU methods to measure; empty: every one
};

// `progress` (fraction done, what runs) may be empty.
DeviceCosts calibrate(Renderer& renderer, const CalibrationSettings& settings = {},
                      const std::function<void(double, const std::string&)>& progress = {});

// The cached model for this renderer under `cache_dir`, or a fresh calibration saved there (and
// kept only in memory without a cache folder).
DeviceCosts load_or_calibrate(Renderer& renderer, const std::optional<std::filesystem::path>& cache_dir,
                              const CalibrationSettings& settings = {});

}  // namespace bounce::planning
