// Spot checks: a GPU frame's relMSE against the reference, estimated from a reference traced through
// a sample of its pixel centres, before the frame is sent for a target error.
//
// With nothing measured on a scene, a GPU plan's own error is the largest the bench measured on its
// corpus, and a target error then often takes the reference: in the furnished room at 0.1, 897 ms of
// tracing where cssm draft (309 ms) meets it. A spot check measures the frame itself, at the
// request's size and view, for a fraction of a reference frame's samples: `pixels` pixel centres,
// one at a random place in each cell of a grid (stratified), each traced with `spp` samples or more
// at a bounce count that lacks little light. Per pixel, the estimate of what the frame errs against
// the converged reference is unbiased in its numerator (the reference samples' variance of the mean
// is taken out of the squared difference) and nearly so in its weight (estimate()); the mean over
// the sample estimates the frame's relMSE, and its standard error, from the spread of the per-pixel
// terms, covers both the choice of pixels and the reference's noise (below, "How a check is sized").
// A frame passes when the estimate plus kSpotConfidence standard errors, with the light of the
// bounces the check's reference lacks against every bounce added by the triangle inequality, is
// within the target.
#pragma once

#include "renderer/image/frame.hpp"
#include "renderer/methods/knobs.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/planning/costs.hpp"
#include "renderer/renderer.hpp"

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

namespace bounce {
struct SceneAnalysis;
}

namespace bounce::planning {

// How a check is sized. Its standard error has two parts: which pixels were drawn, and the
// reference's noise. relMSE is carried by few pixels, edges and dark corners: in the furnished room
// the per-pixel terms of cssm draft spread 5.1 times their mean, and its top 1% of pixels carry 15%
// of it. A frame that can pass errs m under about 0.7 E, so n pixels read it within about
// 3.5 E / sqrt(n) per standard error: at 1024, two of them come to 0.22 E.
// The noise must stay small beside the reference's own value, whatever E: each term is weighed by
// the reference there, and a noisy weight biases the estimate up (spot_weight; in the furnished room
// at a half's noise of 0.17, cssm draft read 0.079 where its pixels err 0.066), so the samples keep
// the noise per pixel under kSpotMaxNoise, and under E / kSpotSamplesPerNoise where that is less
// (about 2.5 E: its own part of the standard error is then as large as the pixels').
inline constexpr int kSpotPixels = 1024;
inline constexpr double kSpotMaxNoise = 0.05;        // relMSE of the reference's noise per pixel
inline constexpr double kSpotSamplesPerNoise = 0.4;  // samples per pixel: this times noise per sample over E
inline constexpr int kSpotMinSamples = 8;            // two halves of four, for each half's variance
// Standard errors above the estimate that must still be within the target: one-sided, a frame over
// the target passes by chance about 2% of the time where the mean is near normal.
inline constexpr double kSpotConfidence = 2.0;

struct SpotCheck {
    int bounces = 0;        // of the check's reference: lacking at most E/1000 of light, and no fewer than the plan's
    int spp = 0;            // per pixel, first traced
    int pixels = 0;         // pixel centres traced
    double predicted_ms = 0.0;
    double stopped_error = 0.0;  // what a reference of `bounces` lacks against every bounce (the analysis')
    // The noise it is sized for (noise_of(), of a half: twice the whole's): where its first `spp`
    // samples read more (the analysis' statistic is of luminance over a neighbourhood, and what the
    // checks took out on the bench scenes and the box was 0.5 to 3.4 times it), more are traced, up
    // to kSpotMostSamples times `spp`. The planner prices kSpotPricedSamples times `spp`.
    double max_noise = 2.0 * kSpotMaxNoise;
};
inline constexpr int kSpotMostSamples = 8;
inline constexpr int kSpotPricedSamples = 2;

// What a reference's noise makes of relMSE at its pixels, as estimate() takes it out: per channel and
// half, the variance of the half's mean as the other half weighs it, averaged (a half's noise: about
// twice the whole's).
double noise_of(const methods::reference::PixelEstimates& reference);

// `count` pixels (at most every one) of a width x height frame, one at a random place in each cell
// of a grid of about `count` cells; the same for the same arguments.
std::vector<int> spot_pixels(int width, int height, int count, std::uint64_t seed = 1);

struct SpotEstimate {
    double rel_mse = 0.0;         // the frame's against the converged reference of the check's bounces
    double standard_error = 0.0;  // of rel_mse
    double noise = 0.0;           // the reference samples' noise taken out, as relMSE
    int pixels = 0;
    int samples = 0;              // per pixel, of the reference
    int non_finite = 0;           // pixels of the frame that are NaN or infinite: the check fails
    // rel_mse plus kSpotConfidence standard errors, and what the check's bounces lack added
    // ((sqrt(a) + sqrt(b))^2): what the frame errs against every bounce, at most, as the check reads it.
    double bound = 0.0;
    bool passes(double max_error) const { return non_finite == 0 && bound <= max_error; }
};

// Compares `frame` (the size the pixels were chosen in) with the reference traced at its pixels.
SpotEstimate estimate(const image::Frame& frame, const methods::reference::PixelEstimates& reference,
                      double stopped_error = 0.0);

// The check's reference for `frame`'s view and size (its camera, else the scene's), traced on the
// calling thread (never the render thread) from a scene no one mutates meanwhile: the reference
// method's samples at those pixel centres (pixel_jitter 0, seed 1), `check.spp` of them, then more
// while their noise is over `check.max_noise` (up to kSpotMostSamples times as many). The samples
// traced depend on the reference alone, never on a frame it judges. `ms` includes building the
// tracer, as a reference frame's time does. Throws Cancelled when `cancelled` is set.
struct SpotReference {
    methods::reference::PixelEstimates estimates;
    double ms = 0.0;
};
SpotReference trace_spot_reference(const scene::Scene& scene, const RenderRequest& frame, const SpotCheck& check,
                                   const std::atomic<bool>* cancelled = nullptr);

// Records what a check read of a GPU plan as its own error on the scene, as a comparison with a
// reference frame would: the estimate plus kSpotConfidence standard errors (the safe side of what it
// read), less the light of the bounces the check's reference has beyond the plan's (the analysis').
// Nothing where the plan models more bounces than the check, whose reference then lacks light the
// plan has. With the `view` its frame was of (the key FrameComparisons files that view's frames by),
// it is an estimate of that view's frame (SceneMeasurements::record_own_estimate, uncertain by the
// standard errors added and the light taken out), which the view's bounds do not then raise: in the
// indirectly lit Cornell box cssm draft at 8 bounces passed no check at 0.02 but read 0.038 of its
// own, and a later comparison of the same view with a one-bounce reference, lacking 0.14 of light
// the frame has, bounded it at 0.89; kept beside the check's, the bound priced it out of every time
// budget after it (cssm draft measures 0.027 there). Without one, a figure of no view.
void record_spot_check(SceneMeasurements& measurements, const std::vector<double>& stopped_error, const std::string& method,
                       const std::string& preset, const methods::KnobValues& knobs, const SpotCheck& check,
                       const SpotEstimate& estimate, std::optional<std::uint64_t> view = std::nullopt);

// Whether a plan to try has been ruled out since the check was planned: the frames tried before it
// recorded own errors (record_spot_check), and the scene now has one for the plan (at its bounce
// count, or at more bounces of its preset, as SceneMeasurements::own_error reads them) that, with
// the light its bounces lack, is over `target`: the planner would no longer offer it. So a failed
// cssm draft at 8 bounces in the atrium (bound 0.147 for 0.05) is not followed by cssm draft at 6.
bool ruled_out_by_measurements(const SceneMeasurements& measured, const SceneAnalysis& analysis, const std::string& method,
                               const std::string& preset, const methods::KnobValues& knobs, double target);

// "a spot check of 1024 pixel centres at 38 spp, 8 bounces: relMSE 0.0249 +- 0.0101 (noise 0.1675
// taken out), at most 0.0475 against every bounce"
std::string describe(const SpotCheck& check, const SpotEstimate& estimate);

}  // namespace bounce::planning
