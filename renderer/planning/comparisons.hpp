// A scene's frames of one view, compared: a GPU frame and a reference frame of the same scene state,
// camera and size measure the GPU method's own error on this scene, which the error model then uses
// in place of the bench's prior (error_model.hpp). Frames come from wherever the scene renders them:
// a stream's still frame and reference rungs, a client's renders, the planner's own reference plans.
//
// own error = relMSE(GPU frame, reference frame) - the reference's noise (its measured noise per
// sample over its samples) - the light of the bounces the reference has and the GPU frame lacks
// (stopped_error[k] - stopped_error[b] from the analysis) + where the reference is a bounce prefix
// of a frame of more bounces, what the GPU frame's error adds to the later bounces' light beyond
// their sum (Comparison::cross_term); negative where the frame's error fills in that later light, never
// below -stopped_error[b]. The noise is the reference's statistic
// scaled by what two reference frames of a view measured it to make (calibrate_noise). Left out: comparisons where those two
// are over half of the relMSE (the own part would be mostly noise or missing light), references
// that are denoised, without indirect visibility, with ambient occlusion or under 16 samples, and
// GPU frames whose knobs are not their preset's (other than `bounces` and what the preset leaves to
// the scene). Where the noise alone is too large a share, against a reference of the frame's own
// bounce count, what is left once half the noise is taken out is recorded as a bound, not an
// estimate (compare()); where the view holds a second, independent draw of that reference's bounce
// count (another seed's frame, or the seed's frame of fewer samples, whose later samples the first
// holds apart), the two draws' cross estimate (image::cross_rel_mse) measures the frame without
// their noise, and is recorded as an estimate where its standard error is small beside it. Draws of
// under 16 samples measure a frame only so, as a pair.
#pragma once

#include "renderer/planning/costs.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene_analysis.hpp"

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace bounce::planning {

// What one comparison measured (for logs and tests).
struct Comparison {
    std::string method, preset;
    int bounces = 0;
    double rel_mse = 0.0;         // against the reference frame
    double reference_noise = 0.0;  // its expected share of rel_mse
    double bounce_gap = 0.0;       // the light of bounces the reference has and the frame lacks
    // Where the reference is the bounce prefix of a frame of more bounces (RenderResult::byproducts):
    // relMSE(frame, deeper) - relMSE(reference, deeper) - rel_mse, what the frame's error adds to the
    // light of the later bounces beyond their sum (negative where the frame adds light where they do).
    double cross_term = 0.0;
    double later_light = 0.0;  // relMSE(reference, deeper): the later bounces' light, with their noise
    bool crossed = false;      // measured against a deeper frame: cross_term and cross_beyond hold
    // The same past the deeper frame's D bounces: the term is linear in the later light, so bounce D's
    // part of it (cross_term less the same against the frame of D - 1 bounces) goes on as the later
    // bounces' light does, by the analysis' ratio r per bounce: x_D r / (1 - r), where x_D > 0, and
    // never past the Cauchy-Schwarz bound 2 sqrt(own x stopped_error[b]) in all.
    double cross_beyond = 0.0;
    // What was recorded: rel_mse - reference_noise - bounce_gap + cross_term + cross_beyond; against a reference of
    // fewer bounces than the frame, (sqrt of that + sqrt of the light the reference lacks)^2.
    double own_error = 0.0;
    // Where the reference's noise drowns the rest (over kMaxNoiseShare of rel_mse) and the reference
    // has the frame's bounce count: own_error, half the noise taken out and never below 0, recorded as
    // a bound on the view's frame (SceneMeasurements::record_own_error) where it is under the
    // preset's prior; a quieter reference's estimate of the view supersedes it.
    bool noise_bound = false;
    // Where the reference's noise drowns the rest (or the reference has under kMinReferenceSpp
    // samples) and the view holds a second, independent draw of the reference's bounce count
    // (independent_draws()): the frame's relMSE against what the two estimate, without their noise
    // (image::cross_rel_mse), and its standard error. Taken where twice that error is at most
    // kMaxCrossSpread of the estimate: the estimate plus one standard error stands in for the relMSE
    // less the noise, and what is recorded is an estimate, not a bound.
    bool cross_estimate = false;
    double cross_rel_mse = 0.0;
    double cross_standard_error = 0.0;
    // What a target's promise adds to own_error (SceneMeasurements::OwnError::promised): the noise
    // taken out by the reference's statistic (all of it for an estimate, the half of a bound), which
    // the frame's relMSE need not have held; less where own_error is clamped (at -stopped_error[b],
    // or a bound's promise at the preset's prior), and through the triangle inequality where the
    // reference lacks light the frame has ((sqrt(promise) + sqrt(l))^2 - (sqrt(own) + sqrt(l))^2).
    // 0 for a cross estimate, whose two draws measure the noise.
    double unsure = 0.0;
};

class FrameComparisons {
public:
    static constexpr std::size_t kMaxFrames = 8;  // GPU frames kept for the latest view
    static constexpr int kMinReferenceSpp = 16;

    // Adds a frame of the view `view` (a key of the scene's state, the camera and the size: frames
    // are compared only with frames of the same key) and records, in `measurements`, the own error
    // of every GPU frame that now has a reference frame to be compared with. References are kept
    // per bounce count (the one with the most samples), and a GPU frame is compared with the one of
    // at least its bounces whose noise and missing bounces leave least of its relMSE unexplained: a
    // reference of the frame's own bounce count measures a frame whose own error the missing light
    // would drown (`direct` against a multi-bounce reference). A reference's byproducts (its frames
    // of fewer bounces, RenderResult::byproducts) are added first, each a reference of its own bounce
    // count. A new view drops the frames of the old one. Thread-safe: GPU frames come from the render
    // thread, reference frames from the CPU pool. Returns the comparisons made.
    std::vector<Comparison> add(std::uint64_t view, std::shared_ptr<const RenderResult> frame, const SceneAnalysis* analysis,
                                SceneMeasurements& measurements);

    // Whether a frame's stats make it a reference to compare with, or a GPU frame to compare.
    static bool usable_reference(const FrameStats& stats);
    // A reference frame that, with another draw of its view and bounce count, may measure a GPU frame
    // by the two draws' cross estimate (Comparison::cross_estimate): usable_reference's conditions
    // but any number of samples. The planner's reference plans for loose targets trace a few samples
    // (3 and 6 in the street for 0.1 and 0.05); a pair of them measures a GPU frame probed beside them.
    static bool usable_draw(const FrameStats& stats);
    // Two independent draws of the image `fewer` and `more` estimate (reference frames of one size,
    // bounce count and pixel positions), `fewer`'s first: of two seeds, the frames themselves; of one
    // seed, `more` holds `fewer`'s samples (a sample draws from the seed, the pixel and its index
    // alone), and its later samples alone are (m more - f fewer) / (m - f). nullopt where they are not
    // such a pair.
    static std::optional<std::pair<image::Frame, image::Frame>> independent_draws(const RenderResult& fewer,
                                                                                 const RenderResult& more);
    // Of one seed's frames of f and m > f samples, the mean of the m - f samples after the first f.
    // Throws Error for frames of two sizes or m <= f.
    static image::Frame later_samples(const image::Frame& fewer, double f, const image::Frame& more, double m);
    // `analysis`: the scene's, for the knobs its presets leave to it (renderer/scene_knobs.hpp).
    static bool usable_gpu_frame(const FrameStats& stats, const SceneAnalysis* analysis = nullptr);

    // One comparison, made and recorded (add() calls it; public for tests). `view` is the frames'
    // view, where known: against a reference lacking light the frame has, what is recorded is a
    // bound on that view's frame, and of several bounds of one view the least holds
    // (SceneMeasurements::record_own_error).
    // `partner`: another draw of the reference's view and bounce count (usable_draw()), for the
    // cross estimate where the reference's noise drowns the comparison or the reference has under
    // kMinReferenceSpp samples (then it is the only way to compare: without it, or where its spread
    // is too wide, nothing is recorded). `cross_only`: nothing but a cross estimate is recorded or
    // returned (a frame measured before, compared again because its reference has a new partner).
    static std::optional<Comparison> compare(const RenderResult& gpu_frame, const RenderResult& reference,
                                             const SceneAnalysis* analysis, SceneMeasurements& measurements,
                                             const RenderResult* deeper = nullptr,
                                             std::optional<std::uint64_t> view = std::nullopt,
                                             const RenderResult* partner = nullptr, bool cross_only = false);

    // Two reference frames of one view, the second with at least kCalibrationSpan times the samples:
    // relMSE between them, less the light of the bounces one has beyond the other, over what their noise
    // statistics say (noise_per_sample / spp of each, or of the smaller less the larger where one seed
    // made both and the larger holds the smaller's samples) is how much relMSE the statistic makes on this
    // scene (SceneMeasurements::noise_scale), recorded and returned. nullopt, recording nothing, where
    // they are not so (other sizes, pixel positions or too few samples apart) or the bounces make over
    // a quarter of the relMSE. add() calls it whenever a reference frame meets the view's kept one.
    static std::optional<double> calibrate_noise(const RenderResult& fewer, const RenderResult& more,
                                                 const SceneAnalysis* analysis, SceneMeasurements& measurements);
    static constexpr double kCalibrationSpan = 2.0;
    static constexpr double kMaxCalibrationGap = 0.25;
    // Pairs whose statistic is under this say nothing of the noise: frames with next to none (a
    // sun's direct light alone is exact at one sample) measured a scale of 0. It is 1/2000 of the
    // smallest error a budget on the bench asks for (0.02), and far above float rounding.
    static constexpr double kMinCalibrationStatistic = 1e-5;
    // The noise scale a comparison takes before a pair of the scene's references has measured one:
    // the smallest that pairs measured on the bench corpus (0.54 to 0.93). The statistic as it is
    // (1.0) took out twice the noise there was in the furnished room, and promised cssm draft 0.044
    // where it measures 0.052.
    static constexpr double kUncalibratedNoiseScale = 0.54;
    // The most of a comparison's relMSE that the reference's expected noise may be (compare()).
    static constexpr double kMaxNoiseShare = 0.25;
    // Of the noise expected, what a comparison it drowns takes out before it records a bound (compare()).
    static constexpr double kBoundNoiseShare = 0.5;
    // The widest a cross estimate is taken: twice its standard error over the estimate. On the bench
    // corpus (bench/cross_estimate, bench/results/corpus/cross_estimate.csv), of the comparisons the
    // noise drowns, the estimates within this spread read 0.86 to 2.4 times the truth; the glossy
    // gallery's (highlights a few samples miss, where the neighbourhood's median weighs them as dark)
    // spread to 2 to 4 times the estimate and are left out.
    static constexpr double kMaxCrossSpread = 0.5;
    // Draws kept per bounce count, the most samples first.
    static constexpr std::size_t kMaxDraws = 3;
    // Draws kept over the view besides each bounce count's reference (the one of most samples, at
    // least kMinReferenceSpp), the fewest samples dropped first: a client's reference frames of one
    // sample at every bounce count would otherwise hold three frames a count (a 4096x4096 frame is
    // 268 MB).
    static constexpr std::size_t kMaxExtraDraws = 4;
    // The reference frames the view holds (tests).
    std::size_t draws_held() const;

private:
    // The kept reference of the most bounces whose byproduct `reference` is; null if none.
    std::shared_ptr<const RenderResult> deeper_than(const RenderResult& reference) const;

    // Of the kept references with at least a GPU frame's bounces, the one whose noise and missing
    // bounces leave least of its relMSE unexplained (one of the frame's own bounce count has no bounce
    // gap); with none such, the one with the most bounces.
    std::shared_ptr<const RenderResult> best_reference(const FrameStats& gpu_frame, const SceneAnalysis* analysis,
                                                       const SceneMeasurements& measurements) const;

    mutable std::mutex mutex_;
    std::optional<std::uint64_t> view_;
    std::map<int, std::shared_ptr<const RenderResult>> references_;  // by bounce count
    std::map<int, std::vector<std::shared_ptr<const RenderResult>>> draws_;  // usable_draw(), by bounce count
    // Of the view's draws of `reference`'s bounce count, the one of most samples that is independent
    // of it or that it holds (independent_draws()); null if none.
    std::shared_ptr<const RenderResult> partner_of(const RenderResult& reference) const;
    void trim_draws();  // to kMaxExtraDraws
    // Where the view's GPU frames are full, the one to drop for a new one: the oldest whose bounces a
    // kept reference has (its own error is measured), else the oldest. A frame of more bounces than
    // any reference so far has only a bound on its own error, which a deeper reference can tighten:
    // dropped first by the order of their keys, cssm's frames went before the view's 6-bounce
    // reference came, and the furnished room's cssm draft at 8 bounces kept a bound of 0.18 where it
    // measures 0.046 against the truth.
    void drop_a_gpu_frame();

    struct KeptFrame {
        std::shared_ptr<const RenderResult> frame;
        std::uint64_t order = 0;  // when it was added
    };
    std::uint64_t added_ = 0;
    std::map<std::tuple<std::string, std::string, int>, KeptFrame> gpu_frames_;
};

}  // namespace bounce::planning
