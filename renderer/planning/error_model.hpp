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
//   - where walls are thinner than vct's voxels (light leaks through them), vct's prior is the
//     largest the bench measured on its scenes where the preset leaks (OwnErrorPriors::
//     vct_leaking_largest), far above the rest: it is chosen only where nothing else is predicted
//     better, and probed beside a reference until the scene's own frames measure it. Where no such
//     scene has measured the preset, and the scene has not, it is ruled out;
//   - ruled out where most indirect light is occluded: a frame whose method gives a reason it lets
//     that light through (MethodInfo::unmodelled_indirect_visibility: isr without imperfect shadow
//     maps).
//
// The parts add: they are errors of different origin.
#pragma once

#include "renderer/methods/knobs.hpp"
#include "renderer/planning/costs.hpp"
#include "renderer/planning/priors.hpp"
#include "renderer/scene_analysis.hpp"

#include <optional>
#include <string>

namespace bounce::planning {

struct ErrorPrediction {
    double rel_mse = 0.0;
    // What a target error is promised: rel_mse, or more where the own error measured here took the
    // reference's noise out by its statistic (SceneMeasurements::OwnError::promised). A reference's
    // is its rel_mse.
    double promised_rel_mse = 0.0;
    std::string basis;                   // how it was made, in words
    std::optional<std::string> ruled_out;  // why the plan cannot be trusted on this scene
};

// The bench's measured own error of a GPU method at a preset (OwnErrorPriors::bench().largest_of).
std::optional<double> own_error_prior(const std::string& method, const std::string& preset, int bounces = 1);

// The median of the same over the bench's scenes (OwnErrorPriors::bench().typical_of): what to expect of
// a GPU plan on a scene where nothing is measured (spot checks try such plans), never what to promise.
std::optional<double> typical_own_error(const std::string& method, const std::string& preset, int bounces = 1);

// Whether vct's voxels at `preset` are thicker than the scene's lit walls (ThinWalls::leaks); false
// for other methods.
bool leaks_through_thin_walls(const SceneAnalysis& analysis, const std::string& method, const std::string& preset);

// The indirect bounces a plan models: 0 for direct, 1 for vct and isr, the `bounces` knob for cssm
// and the reference.
int modelled_bounces(const std::string& method, const methods::KnobValues& knobs);

// A reference frame's expected noise, as relMSE: the analysis' statistic at its bounce count over
// its samples, times what this scene's reference frames measured of it in the view and the relMSE
// that statistic makes on the scene (SceneMeasurements). Against every bounce (what a target error
// is measured by: a frame of fewer bounces is darker than that, and its noise weighs less there) or
// against its own frame (what a comparison with it takes out of a GPU frame's relMSE). Against
// every bounce, where the analysis has noise_against_whole, it never falls with more bounces.
enum class NoiseAgainst { every_bounce, own_frame };
struct ReferenceNoise {
    double rel_mse = 0.0;
    std::optional<double> measured_ratio, scale;  // what it was scaled by, where measured
    std::optional<int> floor_bounces;  // against every bounce: fewer bounces whose noise was more, and taken
};
ReferenceNoise reference_noise(const SceneAnalysis& analysis, int bounces, double spp, const SceneMeasurements* measured,
                               NoiseAgainst against);

ErrorPrediction predict_error(const SceneAnalysis& analysis, const std::string& method, const std::string& preset,
                              const methods::KnobValues& knobs, const SceneMeasurements* measured = nullptr,
                              const OwnErrorPriors& priors = OwnErrorPriors::bench());

}  // namespace bounce::planning
