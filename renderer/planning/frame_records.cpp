// Recording a rendered frame in a scene's measurements (planner.hpp, record_frame): its time, the
// shadow maps it drew, and a reference frame's noise.
#include "renderer/methods/knobs.hpp"
#include "renderer/planning/error_model.hpp"
#include "renderer/planning/planner.hpp"

#include <algorithm>

namespace bounce::planning {

namespace {

// A reference frame's noise per sample, as a ratio to the analysis' at its bounce count.
void record_reference_noise(SceneMeasurements& measurements, const SceneAnalysis* analysis, const FrameStats& stats) {
    const auto noise = stats.method_statistics.find("noise_per_sample");
    const auto spp = stats.knobs.find("spp");
    if (noise != stats.method_statistics.end() && spp != stats.knobs.end() && spp->second >= 4 && analysis) {
        const int bounces = modelled_bounces(stats.method, stats.knobs);
        const double analysed = BounceEnergy::at(analysis->bounces.noise_per_sample, bounces);
        if (analysed > 0.0) measurements.record_noise(bounces, noise->second / analysed, spp->second);
    }
}

}  // namespace

void record_frame(SceneMeasurements& measurements, const SceneAnalysis* analysis, const DeviceCosts& device,
                  const FrameStats& stats, int width, int height) {
    record_reference_noise(measurements, analysis, stats);
    // A frame that compiled programs paid once what no later frame of its work pays: on llvmpipe,
    // direct draft's first frame on a new renderer took 137 ms, compiling 5 programs, and its first on
    // another scene 9 ms (tests/gpu/frame_change_test.cpp). Kept, it priced every later switch to the
    // preset (in the indirectly lit box, 177 ms beyond a warm frame, where its frames after a change
    // of the lights take 4 ms); its shadow maps' pass, compiled at its first draw, every map of its size.
    if (stats.programs_compiled > 0) return;
    if (const auto baseline = baseline_ms(analysis, device, stats.method, stats.preset, stats.knobs, width, height)) {
        // A light dimmed as the camera moved drew the view cascades too: a change of power is kept
        // without them (they are priced as the camera's, from the pass recorded below).
        // A denoised reference is kept as its trace, the filter apart (its time is the pixels').
        const auto filter = stats.method_statistics.find("denoise_ms");
        const double filter_ms = filter != stats.method_statistics.end() ? filter->second : 0.0;
        if (filter_ms > 0.0) measurements.record_denoise(filter_ms, static_cast<double>(width) * height);
        const double measured_ms = stats.change == FrameChange::light_power
                                       ? std::max(0.0, stats.render_ms - stats.pass_ms("shadow_view_cascades"))
                                       : std::max(0.0, stats.render_ms - filter_ms);
        const int bounces = static_cast<int>(methods::knob_or(stats.knobs, "bounces", -1.0));  // -1: no such knob
        measurements.record(stats.method, stats.preset, bounces, measured_ms, *baseline, static_cast<double>(width) * height,
                            stats.change);
    }
    // The passes are timed only in frames that drew maps (passes::ShadowMaps).
    const auto map_size = stats.knobs.find("shadow_map_size");
    if (map_size != stats.knobs.end()) {
        const auto cascades_knob = stats.knobs.find("shadow_cascades");
        const int size = static_cast<int>(map_size->second);
        const int cascades = cascades_knob == stats.knobs.end() ? 0 : static_cast<int>(cascades_knob->second);
        for (const auto& pass : stats.passes) {
            if (pass.pass == "shadow_maps") measurements.record_shadow_maps(size, cascades, pass.gpu_ms);
            if (pass.pass == "shadow_view_cascades") measurements.record_view_cascades(size, cascades, pass.gpu_ms);
        }
    }
}

void record_frame(SceneMeasurements& measurements, const SceneAnalysis* analysis, const DeviceCosts& device,
                  const RenderResult& result, int width, int height) {
    record_frame(measurements, analysis, device, result.stats, width, height);
    for (const auto& byproduct : result.byproducts) record_reference_noise(measurements, analysis, byproduct->stats);
}

}  // namespace bounce::planning
