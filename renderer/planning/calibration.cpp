#include "renderer/planning/calibration.hpp"

#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/scene/builtin.hpp"

#include <algorithm>
#include <chrono>
#include <limits>

namespace bounce::planning {

Calibration::Calibration(Renderer& renderer, CalibrationSettings settings)
    : settings_(std::move(settings)), costs_(renderer.gpu_info().renderer) {
    scene_ = std::make_unique<scene::Scene>(scene::make_cornell_box());
    resources_ = renderer.upload(*scene_);
    const auto& registry = methods::MethodRegistry::builtin();
    for (const std::string& name : registry.names()) {
        const bool wanted = settings_.methods.empty() ||
                            std::find(settings_.methods.begin(), settings_.methods.end(), name) != settings_.methods.end();
        if (!wanted || registry.find(name).device != methods::MethodDevice::gpu) continue;
        for (const std::string& preset : methods::preset_names()) steps_.emplace_back(name, preset);
    }
}

std::string Calibration::next_step() const {
    return done() ? std::string("calibrated") : steps_[next_].first + " " + steps_[next_].second;
}

bool Calibration::step(Renderer& renderer) {
    if (done()) return true;
    const auto begin = std::chrono::steady_clock::now();
    const auto& [method, preset] = steps_[next_];
    double ms[2] = {0.0, 0.0};
    const int sizes[2] = {settings_.small_size, settings_.large_size};
    for (int s = 0; s < 2; ++s) {
        RenderRequest request;
        request.method = method;
        request.preset = preset;
        request.width = request.height = sizes[s];
        request.make_display_image = false;
        renderer.render(*resources_, request);  // builds what the preset needs
        ms[s] = std::numeric_limits<double>::infinity();
        for (int i = 0; i < std::max(1, settings_.timed_frames); ++i) {
            ms[s] = std::min(ms[s], renderer.render(*resources_, request).stats.render_ms);
        }
    }
    costs_.set(method, preset, CostLine::through(double(sizes[0]) * sizes[0], ms[0], double(sizes[1]) * sizes[1], ms[1]));
    ++next_;
    // One method's structures at a time.
    if (done() || steps_[next_].first != method) resources_->methods.erase(method);
    measured_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    return done();
}

DeviceCosts Calibration::result() const {
    BOUNCE_CHECK(done(), "the calibration has {} steps left", steps_.size() - next_);
    DeviceCosts costs = costs_;
    costs.calibration_ms = measured_ms_;  // the steps' own time, not the work served between them
    return costs;
}

DeviceCosts calibrate(Renderer& renderer, const CalibrationSettings& settings,
                      const std::function<void(double, const std::string&)>& progress) {
    Calibration calibration(renderer, settings);
    while (!calibration.done()) {
        if (progress) progress(calibration.fraction(), calibration.next_step());
        calibration.step(renderer);
    }
    if (progress) progress(1.0, "calibrated");
    return calibration.result();
}

DeviceCosts load_or_calibrate(Renderer& renderer, const std::optional<std::filesystem::path>& cache_dir,
                              const CalibrationSettings& settings) {
    const std::string& name = renderer.gpu_info().renderer;
    std::optional<std::filesystem::path> file;
    if (cache_dir) {
        file = DeviceCosts::cache_path(*cache_dir, name);
        if (auto cached = DeviceCosts::load(*file, name)) return std::move(*cached);
    }
    log::info("planner", "calibrating the cost model for '{}' on the Cornell box", name);
    DeviceCosts costs = calibrate(renderer, settings);
    log::info("planner", "calibrated in {:.0f} ms", costs.calibration_ms);
    if (file) {
        try {
            costs.save(*file);
        } catch (const std::exception& error) {
            log::warn("planner", "the cost model stays in memory only: {}", error.what());
        }
    }
    return costs;
}

}  // namespace bounce::planning
