// The error a plan is predicted to have, as relMSE against the reference with every bounce
// (image::compare), from what the scene analysis measured (renderer/scene_analysis.hpp) and what
// the bench measured of each method:
//
//   - bounces: a method that models k bounces lacks what the analysis' frame with k bounces lacks
//     against its frame with all of them (BounceEnergy::stopped_error[k]);
//   - the method's own approximations at a preset: the relMSE against a reference with as many
//     bounces. Measured on this scene where its frames met a reference frame of the same view
//     (comparisons.hpp); until then a prior, the largest the bench measured on its scenes
//     (bench/quality, `rel_mse_same_bounces`), scaled by how the method's measured presets compare
//     with their priors;
//   - the reference's noise: the per-sample variance over the samples, the larger of the analysis'
//     and what the scene's reference frames measured (SceneMeasurements::noise);
//   - ruled out: vct where walls are thinner than its voxels (light leaks through them), isr where
//     most indirect light is occluded (it gathers without visibility).
//
// The parts add: they are errors of different origin.
#pragma once

#include "renderer/methods/knobs.hpp"
#include "renderer/planning/costs.hpp"
#include "renderer/scene_analysis.hpp"

#include <optional>
#include <string>

namespace bounce::planning {

struct ErrorPrediction {
    double rel_mse = 0.0;
    std::string basis;                   // how it was made, in words
    std::optional<std::string> ruled_out;  // why the plan cannot be trusted on this scene
};

// The bench's measured own error of a GPU method at a preset; nullopt for methods without one.
std::optional<double> own_error_prior(const std::string& method, const std::string& preset);

// The indirect bounces a plan models: 0 for direct, 1 for vct and isr, the `bounces` knob for cssm
// and the reference.
int modelled_bounces(const std::string& method, const methods::KnobValues& knobs);

ErrorPrediction predict_error(const SceneAnalysis& analysis, const std::string& method, const std::string& preset,
                              const methods::KnobValues& knobs, const SceneMeasurements* measured = nullptr);

}  // namespace bounce::planning
