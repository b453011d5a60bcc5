// The device's cost lines (costs.hpp), measured: every GPU method at every preset renders the
// built-in Cornell box at two sizes, warm (after a frame that builds its structures), and a line
// goes through the two times, at the presets' own bounce counts. At the larger size it then times
// what changes redo (ChangeCost): frames after the lights' power changed, after they moved, and
// with the method's structures built anew. Runs on the render thread, once
// per device, a step at a time (Calibration): the daemon caches the result in its cache folder
// under the renderer's name.
#pragma once

#include "renderer/planning/costs.hpp"
#include "renderer/renderer.hpp"

#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace bounce::planning {

struct CalibrationSettings {
    int small_size = 32;  // the two frame sizes, in pixels per side
    int large_size = 64;
    int timed_frames = 1;  // per size, after one untimed frame; the fastest counts
    // Frames per change timed (ChangeCost), the median counting; 0: none, and the planner prices
    // changes by the bench's bound. On llvmpipe they are most of a calibration's time (126 s of
    // 163 at 32 and 64 pixels, three frames each): what a change redoes does not shrink with the frame.
    int change_frames = 3;
    std::vector<std::string> methods;  // the GPU methods to measure; empty: every one
};

// A calibration one method and preset at a time, so that its caller (the daemon's render thread)
// can serve other work between steps. Each step renders the preset at both sizes.
class Calibration {
public:
    Calibration(Renderer& renderer, CalibrationSettings settings);  // uploads the Cornell box

    // Measures the next method and preset; true when every one is measured.
    bool step(Renderer& renderer);
    bool done() const { return next_ >= steps_.size(); }
    double fraction() const { return steps_.empty() ? 1.0 : static_cast<double>(next_) / static_cast<double>(steps_.size()); }
    // What the next step measures ("vct medium"), or "calibrated".
    std::string next_step() const;
    // The measured model; only once done().
    DeviceCosts result() const;

    // Shadow maps' texels a side in frames that time changes (of methods that draw maps).
    static constexpr int kChangeMapSize = 64;

private:
    ChangeCost measure_changes(Renderer& renderer, const std::string& method, const std::string& preset, double warm_ms);
    CalibrationSettings settings_;
    std::unique_ptr<scene::Scene> scene_;  // its resources read it every frame: a stable address
    std::unique_ptr<SceneResources> resources_;
    std::vector<std::pair<std::string, std::string>> steps_;  // method, preset
    std::size_t next_ = 0;
    DeviceCosts costs_;
    double measured_ms_ = 0.0;  // time spent in steps
};

// `progress` (fraction done, what runs) may be empty.
DeviceCosts calibrate(Renderer& renderer, const CalibrationSettings& settings = {},
                      const std::function<void(double, const std::string&)>& progress = {});

// The cached model for this renderer under `cache_dir`, or a fresh calibration saved there (and
// kept only in memory without a cache folder).
DeviceCosts load_or_calibrate(Renderer& renderer, const std::optional<std::filesystem::path>& cache_dir,
                              const CalibrationSettings& settings = {});

}  // namespace bounce::planning
