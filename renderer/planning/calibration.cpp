#include "renderer/planning/calibration.hpp"

#include "renderer/base/log.hpp"
#include "renderer/scene/builtin.hpp"

#include <algorithm>
#include <chrono>
#include <limits>

namespace bounce::planning {

DeviceCosts calibrate(Renderer& renderer, const CalibrationSettings& settings,
                      const std::function<void(double, const std::string&)>& progress) {
    const auto start = std::chrono::steady_clock::now();
    const scene::Scene scene = scene::make_cornell_box();
    const auto resources = renderer.upload(scene);
    DeviceCosts costs(renderer.gpu_info().renderer);
    const auto& registry = methods::MethodRegistry::builtin();
    std::vector<std::string> gpu_methods;
    for (const std::string& name : registry.names()) {
        const bool wanted = settings.methods.empty() ||
                            std::find(settings.methods.begin(), settings.methods.end(), name) != settings.methods.end();
        if (wanted && registry.find(name).device == methods::MethodDevice::gpu) gpu_methods.push_back(name);
    }
    const auto& presets = methods::preset_names();
    const double steps = static_cast<double>(gpu_methods.size() * presets.size());
    int step = 0;
    for (const std::string& method : gpu_methods) {
        for (const std::string& preset : presets) {
            if (progress) progress(step++ / steps, fmt::format("{} {}", method, preset));
            double ms[2] = {0.0, 0.0};
            const int sizes[2] = {settings.small_size, settings.large_size};
            for (int s = 0; s < 2; ++s) {
                RenderRequest request;
                request.method = method;
                request.preset = preset;
                request.width = request.height = sizes[s];
                request.make_display_image = false;
                renderer.render(*resources, request);  // builds what the preset needs
                ms[s] = std::numeric_limits<double>::infinity();
                for (int i = 0; i < std::max(1, settings.timed_frames); ++i) {
                    ms[s] = std::min(ms[s], renderer.render(*resources, request).stats.render_ms);
                }
            }
            const CostLine line = CostLine::through(double(sizes[0]) * sizes[0], ms[0], double(sizes[1]) * sizes[1], ms[1]);
            costs.set(method, preset, line);
        }
        resources->methods.erase(method);  // one method's structures at a time
    }
    costs.calibration_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    if (progress) progress(1.0, "calibrated");
    return costs;
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
