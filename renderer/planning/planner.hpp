// The planner behind `budget` and method `auto`: from the device's costs (costs.hpp), the scene's
// measured frames and its analysis (error_model.hpp), it lists every plan it can predict, a method
// with a preset and knobs, and chooses one for a budget:
//
//   max_error E: the fastest plan promised at or under E (Candidate::promised_error: the predicted
//                error with the reference noise its measurements took out counted back), at
//                expected prices among plans whose
//                bounds are within kTargetTimeSlack of the least bound, and of plans priced
//                alike with it (kPriceTie) the most accurate (see choose());
//   max_ms T:    the most accurate plan predicted within T;
//   both:        the fastest meeting both (of those priced alike, the most accurate), else the
//                most accurate within T.
//
// When no plan meets the budget it says so and takes the nearest: the least promised (for E) or
// the fastest (for T). Predicted times are of the frame as it would be rendered now: a warm frame, plus
// what the frame would redo where the lights, the objects or the method's knobs changed since its
// method's last frame (frame_change.hpp).
#pragma once

#include "renderer/methods/knobs.hpp"
#include "renderer/planning/bench_bounds.hpp"
#include "renderer/planning/costs.hpp"
#include "renderer/planning/priors.hpp"
#include "renderer/planning/spot_check.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene_analysis.hpp"

#include <nlohmann/json.hpp>

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace bounce::planning {

struct Budget {
    std::optional<double> max_ms;
    std::optional<double> max_error;  // relMSE against the reference
};

struct Candidate {
    std::string method;
    std::string preset;
    methods::KnobValues knobs;  // over the preset's
    double predicted_ms = 0.0;  // a bound where the scene has not measured what the plan costs
    double predicted_error = 0.0;  // the estimate: what a time budget ranks plans by
    std::string cost_basis, error_basis;
    double scale = 1.0;  // rendered at this fraction of the size and upsampled (resolution.hpp)
    FrameChange redoes = FrameChange::none;  // what its frame would redo now (PlanningInputs::change)
    // Where predicted_ms holds a bound on bounces the scene has not measured: the price at what such
    // bounces typically cost (typical_bounce_cost). Unset: the same as predicted_ms.
    std::optional<double> expected_ms;
    // What a target error is judged by, where more than predicted_error (ErrorPrediction::
    // promised_rel_mse). Unset: predicted_error.
    std::optional<double> promised_error;
};

struct Plan {
    Candidate chosen;
    bool meets_budget = false;
    std::string why;
    int considered = 0;           // plans predicted
    std::vector<std::string> ruled_out;  // "method preset: reason", one per rule
    // GPU plans to render beside a reference plan, at the same view, to measure their own error on
    // this scene (comparisons.hpp): see probes().
    std::vector<Candidate> probes;
    // GPU plans to render first, cheapest first, each compared with `spot_check`'s reference: the
    // first that passes is sent in the chosen reference plan's place (see spot_checks()).
    std::vector<Candidate> checks;
    std::optional<SpotCheck> spot_check;
};

// Of the plans not chosen, GPU presets not yet compared with a reference frame of this scene, one plan
// per preset (its most accurate that fits alone), cheapest first, while their predicted times add
// to at most kProbeShare of a chosen reference plan's. On a GPU they cost little: it is idle while the
// reference traces on CPU threads. Where the GPU is slow (software rasterizers) a GPU frame can cost
// as much as a reference frame, and a smaller share let none fit on the bench corpus, so a GPU
// method's error there was never learned. A preset is probed once per scene, and each one that then
// meets a later budget saves a reference frame on every such request: the probes may take as long as
// the reference plan itself. A preset compared without its error learned (the reference's noise
// drowned it) is probed again beside a reference whose own frame of its bounce count is predicted
// quiet enough to measure it. Then, in what is left of the share, each preset's plan of fewest
// bounces where that is not its first probe's, once per bounce count: an own error is carried to
// fewer bounces as if it and the light they lack added apart. None when the chosen plan is not the
// reference.
// With the scene's analysis, the probes also hold companions, reference plans (method "reference"),
// last: where a probe lacks bounces whose light, with the chosen reference's noise, would drown its
// own error in the comparison, the cheapest reference of the probe's bounce count (at least 16
// samples, its noise at most a third of that own error, FrameComparisons::kMaxNoiseShare of the
// relMSE); such a probe is taken with its companion within
// the share, or not at all. Companions render on CPU threads after the frame is sent. A probe needs
// none where the chosen reference's own frame of the probe's bounce count (its bounce prefix, below
// `prefix_bounces`: methods::reference::Accumulator) is predicted to leave it measurable.
inline constexpr double kProbeShare = 1.0;

// The reference's denoiser, per pixel, where the scene has timed none (SceneMeasurements::
// denoise_ms_per_pixel): the largest of bench/denoise --every-scene's 30 filters (16 ms at 128x128 on
// an AMD EPYC, 2 threads), rounded up. Its time does not depend on the samples.
inline constexpr double kDenoiseMsPerPixel = 1.0e-3;
std::vector<Candidate> probes(const std::vector<Candidate>& all, const Candidate& chosen, const SceneMeasurements* scene,
                              const SceneAnalysis* analysis = nullptr, int prefix_bounces = 0);

// A target error is judged against the cheapest plan that meets it: at most this many times its
// time (bench/planner). For max_error alone, choose() takes the plan of least expected price
// (Candidate::expected_ms) among those promised within E whose predicted_ms, a bound, is at most
// this many times the least predicted_ms within E. A plan priced by a bound on bounces the scene
// has not measured then wins where it typically costs less (the furnished room's cssm draft at 8
// bounces, bound at 2.9 times its 1-bounce frames, took 1.25 to 1.9 times them, and lost its race to
// a reference frame twice as slow); were it to cost its bound, it costs at most this many times the
// plan the bounds chose. A time budget is a promise, and is kept by the bounds.
inline constexpr double kTargetTimeSlack = 1.5;

// Prices the cost model cannot tell apart: its frames land within 4.4% of their predicted time at
// the 75th percentile (105 frames of bench/results/planner.csv, at 6a7933a's code). Among the plans
// a target error may take, choose() takes the most accurate of those priced within this factor of
// the plan it would take: they cost the same as far as anyone can predict, and the more accurate
// one has margin on the target (and, the first time a GPU method is chosen so, the scene measures
// that method's own error for later budgets).
inline constexpr double kPriceTie = 1.05;

// Chooses among predicted plans (a pure function: the planner's unit tests call it on tables).
// Throws InputError when `candidates` is empty or the budget names neither limit.
Plan choose(const std::vector<Candidate>& candidates, const Budget& budget);

struct PlanningInputs {
    const SceneAnalysis& analysis;
    const DeviceCosts& device;
    const SceneMeasurements* scene = nullptr;  // measured frames of this scene, when any
    int width = 0, height = 0;
    std::optional<std::string> method;  // plan within this method only
    // Per GPU method, scales below 1 to offer and the error upsampling adds at each
    // (measure_resample_errors); a method without: its plans at full size only.
    std::map<std::string, std::map<double, double>> resample_errors = {};
    // What a frame of a GPU plan would redo now (SceneResources::change_for, its knobs resolved),
    // rendered at `width` x `height` (a plan at a smaller scale renders smaller, and the suns' view
    // cascades fit the shape it renders at); unset: nothing, every plan priced as a warm frame (the
    // bench's fixed plans are warm frames).
    using ChangeOf = std::function<FrameChange(const std::string& method, const std::string& preset,
                                               const methods::KnobValues& knobs, int width, int height)>;
    ChangeOf change = {};
    // Why a GPU plan's frame, rendered at `width` x `height`, would be refused for memory now
    // (Renderer::memory_refusal); unset, or nullopt: it fits. A refused plan is ruled out, with the reason.
    using MemoryRefusal = std::function<std::optional<std::string>(
        const std::string& method, const std::string& preset, const methods::KnobValues& knobs, int width, int height)>;
    MemoryRefusal memory = {};
    // How bounce counts the scene has not measured are priced: by the most the bench measured them
    // cost (bounce_cost_bound, the planner's predicted_ms), or by what they typically cost
    // (typical_bounce_cost, Candidate::expected_ms).
    enum class BouncePricing { bound, typical };
    BouncePricing bounce_pricing = BouncePricing::bound;
    // The GPU methods' own errors where the scene has measured none; unset: the bench's
    // (OwnErrorPriors::bench()). bench/planner --held-out sets each scene's to the other scenes'.
    const OwnErrorPriors* priors = nullptr;
    const OwnErrorPriors& own_error_priors() const { return priors ? *priors : OwnErrorPriors::bench(); }
};

// PlanningInputs::change for a scene's resources as the scene is now (its lights and geometry hashed
// at the call: make it for each plan), seen from `camera` (SceneResources::view_of the frame's
// request): each plan's knobs resolved as plan_frame resolves them (the registry's preset with its
// overrides), the view cascades they fit at the plan's size (fitted once per map size, cascade
// count and size), then SceneResources::change_for. Plans it cannot resolve count as built anew
// (knobs_and_scene). Call it where change_for may be called.
PlanningInputs::ChangeOf changes_on(const SceneResources& resources, const scene::Camera& camera);

// Every plan the planner predicts for a frame, at full size and at each scale of its method's
// `resample_errors`, with those the analysis rules out left out (and named in `ruled_out`).
// The reference is offered on a ladder of sample counts in steps of about 1.5. With `fill_ms`, a
// time budget, each of its bounce counts is also offered at the most samples predicted within it
// (where that falls between two steps): a step would leave up to a third of the budget unused where
// the reference is the most accurate plan, and its noise falls with every sample. A target error
// keeps the steps, and with them their slack: a frame a little over its time budget still keeps it
// (bench/planner judges frames within 1.2 T), a frame over its target error does not.
std::vector<Candidate> candidates(const PlanningInputs& inputs, std::vector<std::string>* ruled_out = nullptr,
                                  std::optional<double> fill_ms = std::nullopt);

// For a target error E whose chosen plan is the reference (nothing on the scene promises a GPU plan
// within E): GPU plans at full size whose own error is not measured here, which the bench's typical
// own error (the inputs' priors, OwnErrorPriors::typical_of) and the light of the bounces they lack (the analysis') put within E,
// cheapest first, while the spot check's price and their predicted times add to at most kCheckShare
// of the reference plan's: where every one fails, the request costs at most 1 + kCheckShare times
// the plan it stood in for, and the frames rendered are then compared with its reference as probes
// are. The check traces kSpotPixels pixel centres at the fewest bounces that lack at most E/1000
// of light, with samples for its noise per sample (the analysis', as the scene's reference frames
// measured it) to make min(kSpotMaxNoise, E / kSpotSamplesPerNoise) (8 to 4096), priced as a
// reference frame of that many pixels at kSpotPricedSamples times those samples. nullopt when no
// plan qualifies or the budget has a time limit too (a check and its fallback would not keep it).
inline constexpr double kCheckShare = 1.0;
struct Checks {
    std::vector<Candidate> plans;
    SpotCheck check;
};
std::optional<Checks> spot_checks(const std::vector<Candidate>& all, const Candidate& chosen, const Budget& budget,
                                  const PlanningInputs& inputs);

// candidates() then choose().
Plan plan(const PlanningInputs& inputs, const Budget& budget);

// The device line for a preset times the scene's measured ratio (the method's, else the scene's
// over every method, else 1); for the reference, the analysis' time to build the tracer and per
// sample times the samples. For a GPU plan whose frame would redo work (PlanningInputs::change), plus
// that work: what this scene's frames that redid the same measured beyond a warm frame's price at
// their size (the median of the last); else the scene's timing of its shadow maps at the plan's map
// size (none for light_power) plus the rest: where the device's calibration measured the change
// (DeviceCosts::change_cost), its multiple of the plan's warm frame at the size it was measured at,
// times the scene's scale of the calibration where the scene's frames of the method's other
// presets measured one after a change of the class, else its frames after other changes did
// (planner.cpp, scene_scale_of_calibration), else plus change_margin() times
// that frame at kChangePriorPixels; else change_cost_bound(besides_maps)
// times the frame at kChangePriorPixels. With no timing of the maps, change_cost_bound() times that
// frame. A moved camera (view) redoes the suns' view cascades alone: priced, before frames of the
// class were measured, at the scene's timing of the cascades drawn alone, else of all its maps (the
// cascades among them), else change_cost_bound() for a move of the lights; the device's calibration
// plays no part. A switch of knobs from a moved camera that keeps the maps (knobs_and_view), before
// frames of the class were measured: the switch without its maps, and the cascades. The work is the
// scene's (shadow maps, an atlas, an octree), not the frame's pixels: a smaller frame redoes as much.
double predicted_ms(const PlanningInputs& inputs, const std::string& method, const std::string& preset,
                    const methods::KnobValues& knobs, std::string* basis = nullptr);

// The cost line a frame is measured against when recorded in SceneMeasurements (its ratio's denominator):
// the device line, or the analysis' time per sample for the reference. nullopt when neither applies.
std::optional<double> baseline_ms(const SceneAnalysis* analysis, const DeviceCosts& device, const std::string& method,
                                  const std::string& preset, const methods::KnobValues& knobs, int width, int height);

// Records a rendered frame in the scene's measurements: its time against baseline_ms(), the shadow
// maps' passes it timed, and for reference frames of at least 4 samples, their noise per sample. A
// frame that compiled programs (FrameStats::programs_compiled) keeps no time: it paid what the
// daemon pays once, and a change is priced by the frames that redid it alone.
void record_frame(SceneMeasurements& measurements, const SceneAnalysis* analysis, const DeviceCosts& device,
                  const FrameStats& stats, int width, int height);
// The same for a whole result: also the noise of its byproducts (a reference's frames of fewer
// bounces), whose time is the frame's own.
void record_frame(SceneMeasurements& measurements, const SceneAnalysis* analysis, const DeviceCosts& device,
                  const RenderResult& result, int width, int height);

nlohmann::json plan_json(const Plan& plan);

}  // namespace bounce::planning
