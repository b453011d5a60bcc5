#include "renderer/planning/calibration.hpp"

#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/scene/builtin.hpp"

#include <algorithm>
#include <chrono>
#include <limits>

namespace bounce::planning {
namespace {

// Every light moved by a thousandth of the scene's size, or turned by a thousandth of a radian: what
// a frame sees as new light places (frame_change.hpp), by amounts no image shows. `sign` alternates.
void move_every_light(scene::Scene& scene, float sign) {
    const float step = 1e-3f * sign * glm::length(scene.world_bounds().extent());
    for (scene::Light& light : scene.lights) {
        light.position += glm::vec3(step, 0.0f, step);
        if (light.type != scene::LightType::point) {
            light.direction = glm::normalize(light.direction + glm::vec3(1e-3f * sign, 0.0f, 0.0f));
        }
    }
}

}  // namespace

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
    if (settings_.change_frames > 0) costs_.set_change_cost(method, preset, measure_changes(renderer, method, preset, ms[1]));
    ++next_;
    // One method's structures at a time.
    if (done() || steps_[next_].first != method) resources_->methods.erase(method);
    measured_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
    return done();
}

ChangeCost Calibration::measure_changes(Renderer& renderer, const std::string& method, const std::string& preset,
                                        double warm_ms) {
    RenderRequest request;
    request.method = method;
    request.preset = preset;
    request.width = request.height = settings_.large_size;
    request.make_display_image = false;
    // With small shadow maps: their time is left out of the figures, and at the presets' sizes (cube
    // maps of 2048 to 4096 texels a side) drawing them made most of a calibration's time on llvmpipe.
    const auto& knobs = methods::MethodRegistry::builtin().find(method).knobs;
    if (std::any_of(knobs.begin(), knobs.end(), [](const auto& knob) { return knob.name == "shadow_map_size"; })) {
        request.knobs["shadow_map_size"] = kChangeMapSize;
        renderer.render(*resources_, request);  // maps of that size
        warm_ms = std::numeric_limits<double>::infinity();
        for (int i = 0; i < 2; ++i) warm_ms = std::min(warm_ms, renderer.render(*resources_, request).stats.render_ms);
    }
    // Beyond the warm frame, less the maps drawn; the median of change_frames frames, each of which
    // redoes the change (the lights alternate between two states, their power among three).
    const auto beyond_warm = [&](const std::function<void(int)>& change) {
        std::vector<double> extra;
        for (int i = 0; i < settings_.change_frames; ++i) {
            change(i);
            const FrameStats stats = renderer.render(*resources_, request).stats;
            extra.push_back(warm_ms > 0.0 ? std::max(0.0, stats.render_ms - stats.pass_ms("shadow_maps") - warm_ms) / warm_ms : 0.0);
        }
        return median(std::move(extra));
    };
    ChangeCost cost;
    cost.pixels = double(settings_.large_size) * settings_.large_size;
    const std::vector<scene::Light> lit = scene_->lights;
    cost.light_power = beyond_warm([&](int i) {
        for (std::size_t l = 0; l < lit.size(); ++l) scene_->lights[l].intensity = lit[l].intensity * (1.0f + 1e-3f * float(i + 1));
    });
    scene_->lights = lit;
    cost.lights = beyond_warm([&](int i) { move_every_light(*scene_, i % 2 == 0 ? 1.0f : -1.0f); });
    // The structures built anew, as a preset switch after a change of the lights builds them.
    cost.rebuild = beyond_warm([&](int i) {
        move_every_light(*scene_, i % 2 == 0 ? 1.0f : -1.0f);
        resources_->methods.erase(method);
    });
    scene_->lights = lit;
    return cost;
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
