// How the planner learns a GPU method's error on a scene: frames of one view compared with a
// reference frame of it (planning::FrameComparisons), the own error that leaves once the
// reference's noise and the bounces between them are taken out (exact arithmetic on constant
// frames), which frames may be compared, how the error model uses what was measured, which probes
// the planner renders beside a reference plan, and plans rendered smaller and upsampled.
#include "renderer/image/metrics.hpp"
#include "renderer/methods/registry.hpp"
#include "renderer/planning/comparisons.hpp"
#include "renderer/planning/error_model.hpp"
#include "renderer/planning/planner.hpp"
#include "renderer/planning/resolution.hpp"
#include "renderer/base/error.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include <algorithm>
#include <cmath>

namespace bounce::planning {
namespace {

// Stopping at k bounces loses 0.1 / 2^k (as in planner_test.cpp).
SceneAnalysis made_up_analysis() {
    SceneAnalysis analysis;
    for (int k = 0; k <= 12; ++k) {
        analysis.bounces.stopped_error.push_back(k == 12 ? 0.0 : 0.1 / std::pow(2.0, k));
        analysis.bounces.noise_per_sample.push_back(0.5);
        analysis.bounces.sample_ns.push_back(1000.0);
    }
    return analysis;
}

// A constant 8x8 frame of `value` made by `method` at `preset` with `overrides`, the knobs resolved
// as the renderer resolves them.
std::shared_ptr<const RenderResult> frame(const std::string& method, const std::string& preset, methods::KnobValues overrides,
                                          float value, double noise_per_sample = 0.0) {
    auto result = std::make_shared<RenderResult>();
    result->frame.width = result->frame.height = 8;
    result->frame.rgba.assign(8 * 8 * 4, value);
    for (std::size_t i = 3; i < result->frame.rgba.size(); i += 4) result->frame.rgba[i] = 1.0f;
    result->stats.method = method;
    result->stats.preset = preset;
    result->stats.knobs = methods::MethodRegistry::builtin().resolve(method, preset, overrides);
    if (method == "reference") result->stats.method_statistics["noise_per_sample"] = noise_per_sample;
    return result;
}

std::shared_ptr<const RenderResult> reference(double spp, double noise_per_sample, methods::KnobValues more = {}) {
    more["spp"] = spp;
    more.try_emplace("bounces", 4);
    more["pixel_jitter"] = 0;
    return frame("reference", "medium", more, 1.0f, noise_per_sample);
}

// What a constant frame of 1.5 at 8 bounces records against a reference of `bounces` (value 1.0,
// no noise) in made_up_analysis(): relMSE (1.5 - 1)^2 / (1 + 0.01), plus the light the reference
// lacks by the triangle inequality.
double bound_of_8_bounce_frame_against(int bounces) {
    const double lacking = 0.1 / std::pow(2.0, bounces) - 0.1 / 256.0;
    return std::pow(std::sqrt(0.25 / 1.01) + std::sqrt(lacking), 2.0);
}

// Adds to `view` cssm medium's frame of 1.5 at 8 bounces, then a 3-bounce reference, which bounds it.
void bound_an_8_bounce_frame_by_a_3_bounce_reference(FrameComparisons& comparisons, const SceneAnalysis& analysis,
                                                     SceneMeasurements& measured, std::uint64_t view) {
    comparisons.add(view, frame("cssm", "medium", {{"bounces", 8}}, 1.5f), &analysis, measured);
    ASSERT_EQ(comparisons.add(view, reference(4096, 0.0, {{"bounces", 3}}), &analysis, measured).size(), 1u);
}

TEST(OwnError, TheLargestOfTheLastComparisonsAtABounceCountElseAtThePresetsLargerOnes) {
    SceneMeasurements measured;
    measured.record_own_error("cssm", "low", 2, 0.03);
    measured.record_own_error("cssm", "low", 2, 0.05);
    measured.record_own_error("cssm", "low", 4, 0.02);
    measured.record_own_error("cssm", "low", 4, std::nan(""));  // ignored
    measured.record_own_error("cssm", "low", 4, -0.01);  // kept: a frame that fills in light its bounces lack
    const auto at_2 = measured.own_error("cssm", "low", 2);
    ASSERT_TRUE(at_2);
    EXPECT_DOUBLE_EQ(at_2->rel_mse, 0.05);
    EXPECT_EQ(at_2->frames, 2);
    EXPECT_TRUE(at_2->exact);
    const auto at_4 = measured.own_error("cssm", "low", 4);
    EXPECT_DOUBLE_EQ(at_4->rel_mse, 0.02);
    EXPECT_EQ(at_4->frames, 2);
    // Not measured: the largest at the preset's larger bounce counts (each bounce adds its error).
    const auto at_3 = measured.own_error("cssm", "low", 3);
    EXPECT_DOUBLE_EQ(at_3->rel_mse, 0.02);
    EXPECT_EQ(at_3->frames, 2);
    EXPECT_FALSE(at_3->exact);
    const auto at_1 = measured.own_error("cssm", "low", 1);
    EXPECT_DOUBLE_EQ(at_1->rel_mse, 0.05);
    EXPECT_EQ(at_1->frames, 4);
    EXPECT_FALSE(measured.own_error("cssm", "low", 5));  // fewer bounces do not tell more
    EXPECT_FALSE(measured.own_error("cssm", "high", 2));
    EXPECT_EQ(measured.own_errors("cssm"), (std::map<std::string, double>{{"low", 0.05}}));
    EXPECT_EQ(measured.own_errors("cssm", 3), (std::map<std::string, double>{{"low", 0.02}}));
    EXPECT_TRUE(measured.own_errors("cssm", 5).empty());
    // Only the last kKept are kept.
    for (std::size_t i = 0; i < SceneMeasurements::kKept; ++i) measured.record_own_error("cssm", "low", 2, 0.01);
    EXPECT_DOUBLE_EQ(measured.own_error("cssm", "low", 2)->rel_mse, 0.01);
}

// A comparison against a reference lacking light the frame has records a bound on that view's
// frame; every bound holds, so of one view's the least is its own error, and views still count by
// their largest.
TEST(OwnError, BoundsOfOneViewHoldByTheLeastAndEveryViewAndEstimateCounts) {
    SceneMeasurements measured;
    measured.record_own_error("cssm", "draft", 8, 0.184, 1);
    EXPECT_DOUBLE_EQ(measured.own_error("cssm", "draft", 8)->rel_mse, 0.184);
    measured.record_own_error("cssm", "draft", 8, 0.067, 1);
    measured.record_own_error("cssm", "draft", 8, 0.2, 1);  // looser: says nothing more
    auto own = measured.own_error("cssm", "draft", 8);
    EXPECT_DOUBLE_EQ(own->rel_mse, 0.067);
    EXPECT_EQ(own->frames, 1);
    EXPECT_EQ(measured.own_errors("cssm"), (std::map<std::string, double>{{"draft", 0.067}}));
    // Another view's frame is bounded apart, and the largest of the views is kept.
    measured.record_own_error("cssm", "draft", 8, 0.09, 2);
    EXPECT_DOUBLE_EQ(measured.own_error("cssm", "draft", 8)->rel_mse, 0.09);
    measured.record_own_error("cssm", "draft", 8, 0.05, 2);
    EXPECT_DOUBLE_EQ(measured.own_error("cssm", "draft", 8)->rel_mse, 0.067);
    // An estimate (a reference of the frame's bounces, a spot check) is kept beside them, each one.
    measured.record_own_error("cssm", "draft", 8, 0.08);
    measured.record_own_error("cssm", "draft", 8, 0.03);
    own = measured.own_error("cssm", "draft", 8);
    EXPECT_DOUBLE_EQ(own->rel_mse, 0.08);
    EXPECT_EQ(own->frames, 4);
    // Not a number, or negative: nothing, bound or not.
    measured.record_own_error("cssm", "draft", 8, std::nan(""), 1);
    measured.record_own_error("cssm", "draft", 8, -1.0, 1);
    EXPECT_DOUBLE_EQ(measured.own_error("cssm", "draft", 8)->rel_mse, 0.08);
}

// A view's frame is one frame: of the estimates of its own error, the one whose comparison took out
// least (the quietest reference) stands, whatever the order they came in, and it supersedes the
// view's bounds; views still count by their largest. The street's isr draft: 0.0155 against a
// 16-sample reference that took 0.0085 out, 0.0037 against a 4-bounce one that took 0.0011.
TEST(OwnError, OfAViewsEstimatesTheOneThatTookOutLeastStands) {
    for (const bool noisy_first : {true, false}) {
        SCOPED_TRACE(noisy_first ? "noisy first" : "quiet first");
        SceneMeasurements measured;
        const auto noisy = [&] { measured.record_own_estimate("isr", "draft", 1, 0.0155, 7, 0.0085); };
        const auto quiet = [&] { measured.record_own_estimate("isr", "draft", 1, 0.0037, 7, 0.0011); };
        if (noisy_first) noisy(), quiet();
        else quiet(), noisy();
        auto own = measured.own_error("isr", "draft", 1);
        ASSERT_TRUE(own);
        EXPECT_DOUBLE_EQ(own->rel_mse, 0.0037);
        EXPECT_EQ(own->frames, 1);
        // Another view counts apart, by the largest.
        measured.record_own_estimate("isr", "draft", 1, 0.006, 8, 0.002);
        EXPECT_DOUBLE_EQ(measured.own_error("isr", "draft", 1)->rel_mse, 0.006);
        // A bound of an estimated view says nothing more; an estimate replaces a view's bound.
        measured.record_own_error("isr", "draft", 1, 0.5, 7);
        EXPECT_DOUBLE_EQ(measured.own_error("isr", "draft", 1)->rel_mse, 0.006);
        measured.record_own_error("isr", "draft", 1, 0.3, 9);
        EXPECT_DOUBLE_EQ(measured.own_error("isr", "draft", 1)->rel_mse, 0.3);
        measured.record_own_estimate("isr", "draft", 1, 0.004, 9, 0.003);
        EXPECT_DOUBLE_EQ(measured.own_error("isr", "draft", 1)->rel_mse, 0.006);
        // Not a number, negative, or nothing known of what was taken out: nothing.
        measured.record_own_estimate("isr", "draft", 1, std::nan(""), 7, 0.0);
        measured.record_own_estimate("isr", "draft", 1, -1.0, 7, 0.0);
        measured.record_own_estimate("isr", "draft", 1, 0.9, 7, std::nan(""));
        EXPECT_DOUBLE_EQ(measured.own_error("isr", "draft", 1)->rel_mse, 0.006);
    }
}

// A view's frame meets the later bounces' light alike whichever reference measured the rest: an
// estimate without a deeper frame takes the cross term of the view's estimate that had one, and
// gives it its own when it comes first. The street's isr draft: 0.0017 against the 1-bounce prefix
// of a 4-bounce reference (a cross term of -0.0091 in it, 0.0011 taken out), then 0.0106 against a
// 192-sample reference of one bounce alone (0.0008 taken out); it measures 0.0113 whole, of which
// its bounce lacks 0.010.
TEST(OwnError, AViewsEstimateKeepsTheCrossTermAQuieterReferenceCannotMeasure) {
    for (const bool prefix_first : {true, false}) {
        SCOPED_TRACE(prefix_first ? "the prefix first" : "the reference alone first");
        SceneMeasurements measured;
        const auto prefix = [&] { measured.record_own_estimate("isr", "draft", 1, 0.0017, 7, 0.0011, 0.0011, -0.0091); };
        const auto alone = [&] { measured.record_own_estimate("isr", "draft", 1, 0.0106, 7, 0.0008, 0.0011); };
        if (prefix_first) prefix(), alone();
        else alone(), prefix();
        const auto own = measured.own_error("isr", "draft", 1);
        ASSERT_TRUE(own);
        EXPECT_EQ(own->frames, 1);
        EXPECT_NEAR(own->rel_mse, 0.0106 - 0.0091, 1e-12);  // the quieter reference, with the view's cross term
        EXPECT_NEAR(own->promised, 0.0106 - 0.0091 + 0.0011, 1e-12);
    }
    // Both with a cross term, or neither: the one that took out least, as it is.
    SceneMeasurements both;
    both.record_own_estimate("isr", "draft", 1, 0.0017, 7, 0.0011, 0.0, -0.0091);
    both.record_own_estimate("isr", "draft", 1, 0.0030, 7, 0.0005, 0.0, -0.0050);
    EXPECT_DOUBLE_EQ(both.own_error("isr", "draft", 1)->rel_mse, 0.0030);
    // Another view's cross term is not this view's.
    SceneMeasurements views;
    views.record_own_estimate("isr", "draft", 1, 0.0017, 7, 0.0011, 0.0, -0.0091);
    views.record_own_estimate("isr", "draft", 1, 0.0106, 8, 0.0008, 0.0);
    EXPECT_DOUBLE_EQ(views.own_error("isr", "draft", 1)->rel_mse, 0.0106);
    // A cross term that is not a number records nothing.
    views.record_own_estimate("isr", "draft", 1, 0.5, 9, 0.0, 0.0, std::nan(""));
    EXPECT_DOUBLE_EQ(views.own_error("isr", "draft", 1)->rel_mse, 0.0106);
}

// A target is promised each comparison's own error with the noise its reference's statistic took out
// counted back (SceneMeasurements::OwnError::promised), the largest of them; the estimate stays what a
// time budget ranks by. The glossy box's vct draft at 2 bounces: 0.0697 once 0.0077 of noise was
// taken out, measuring 0.077 against the truth. A promise is never under the estimate, a view's bounds
// keep the least promise, and a promise carried to fewer bounces is the larger counts' largest.
TEST(OwnError, ATargetIsPromisedTheEstimateWithTheNoiseItTookOutCountedBack) {
    SceneMeasurements measured;
    measured.record_own_estimate("vct", "draft", 2, 0.0697, 7, 0.0081, 0.0077);
    auto own = measured.own_error("vct", "draft", 2);
    ASSERT_TRUE(own);
    EXPECT_DOUBLE_EQ(own->rel_mse, 0.0697);
    EXPECT_DOUBLE_EQ(own->promised, 0.0697 + 0.0077);
    // Another view whose estimate is larger but surer: each count is its own largest.
    measured.record_own_estimate("vct", "draft", 2, 0.072, 8, 0.001, 0.001);
    own = measured.own_error("vct", "draft", 2);
    EXPECT_DOUBLE_EQ(own->rel_mse, 0.072);
    EXPECT_DOUBLE_EQ(own->promised, 0.0697 + 0.0077);
    EXPECT_EQ(measured.own_errors("vct"), (std::map<std::string, double>{{"draft", 0.072}}));
    EXPECT_EQ(measured.own_errors("vct", 0, /*promised=*/true), (std::map<std::string, double>{{"draft", 0.0697 + 0.0077}}));
    // Carried to fewer bounces: the larger counts' largest promise.
    EXPECT_DOUBLE_EQ(measured.own_error("vct", "draft", 1)->promised, 0.0697 + 0.0077);
    // Bounds of one view: the least, and the least promise of them.
    measured.record_own_error("cssm", "low", 4, 0.05, 3, 0.02);
    measured.record_own_error("cssm", "low", 4, 0.04, 3, 0.04);
    own = measured.own_error("cssm", "low", 4);
    EXPECT_DOUBLE_EQ(own->rel_mse, 0.04);
    EXPECT_DOUBLE_EQ(own->promised, 0.07);
    measured.record_own_error("cssm", "low", 4, 0.06, 3, 0.0);
    own = measured.own_error("cssm", "low", 4);
    EXPECT_DOUBLE_EQ(own->rel_mse, 0.04);
    EXPECT_DOUBLE_EQ(own->promised, 0.06);
    // Without what was taken out (a prior, a spot check's bound): the promise is the estimate. An
    // unknown or negative share counted back records nothing.
    measured.record_own_error("isr", "draft", 1, 0.01);
    EXPECT_DOUBLE_EQ(measured.own_error("isr", "draft", 1)->promised, 0.01);
    measured.record_own_error("isr", "draft", 1, 0.5, std::nullopt, std::nan(""));
    measured.record_own_estimate("isr", "draft", 1, 0.5, 9, 0.0, -0.1);
    EXPECT_DOUBLE_EQ(measured.own_error("isr", "draft", 1)->promised, 0.01);
}

TEST(OwnError, TheErrorModelUsesWhatTheSceneMeasuredAndNeverPredictsACostlierPresetBetter) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    const double prior_low = *own_error_prior("cssm", "low");
    measured.record_own_error("cssm", "low", 2, 0.25 * prior_low);
    const ErrorPrediction low = predict_error(analysis, "cssm", "low", {{"bounces", 2}}, &measured);
    EXPECT_DOUBLE_EQ(low.rel_mse, 0.1 / 4.0 + 0.25 * prior_low);
    EXPECT_NE(low.basis.find("1 comparison with this scene's reference frames"), std::string::npos) << low.basis;
    // Net of bounces: the same own error at fewer bounces; at more, not measured (the prior).
    EXPECT_DOUBLE_EQ(predict_error(analysis, "cssm", "low", {{"bounces", 1}}, &measured).rel_mse,
                     0.1 / 2.0 + 0.25 * prior_low);
    EXPECT_DOUBLE_EQ(predict_error(analysis, "cssm", "low", {{"bounces", 6}}, &measured).rel_mse, 0.1 / 64.0 + prior_low);
    // A costlier preset of the method: no better than the cheaper one measured.
    const ErrorPrediction medium = predict_error(analysis, "cssm", "medium", {{"bounces", 2}}, &measured);
    EXPECT_DOUBLE_EQ(medium.rel_mse, 0.1 / 4.0 + 0.25 * prior_low);
    EXPECT_NE(medium.basis.find("as this scene's cssm low measured"), std::string::npos) << medium.basis;
    // A cheaper one: its prior, not scaled down for a costlier preset that did well (it says little of
    // a cheaper one)...
    const double prior_draft = *own_error_prior("cssm", "draft");
    const ErrorPrediction draft = predict_error(analysis, "cssm", "draft", {{"bounces", 2}}, &measured);
    EXPECT_NEAR(draft.rel_mse, 0.1 / 4.0 + prior_draft, 1e-12);
    EXPECT_NE(draft.basis.find("on the bench scenes"), std::string::npos) << draft.basis;
    // ...but scaled up where the costlier ones err more than their priors: it errs at least as much.
    SceneMeasurements harder;
    harder.record_own_error("cssm", "low", 2, 2.0 * prior_low);
    const ErrorPrediction hard_draft = predict_error(analysis, "cssm", "draft", {{"bounces", 2}}, &harder);
    EXPECT_NEAR(hard_draft.rel_mse, 0.1 / 4.0 + 2.0 * prior_draft, 1e-12);
    EXPECT_NE(hard_draft.basis.find("as this scene's costlier cssm presets measured"), std::string::npos) << hard_draft.basis;
    EXPECT_NEAR(hard_draft.promised_rel_mse, hard_draft.rel_mse, 1e-12);
    // Promised as their promises measured: a costlier preset estimated under its prior but promised
    // three times it leaves the cheaper one its prior as the estimate and three times it as the promise.
    SceneMeasurements unsure_harder;
    unsure_harder.record_own_estimate("cssm", "low", 2, 0.5 * prior_low, 1, 0.0, 2.5 * prior_low);
    const ErrorPrediction unsure_draft = predict_error(analysis, "cssm", "draft", {{"bounces", 2}}, &unsure_harder);
    EXPECT_NEAR(unsure_draft.rel_mse, 0.1 / 4.0 + prior_draft, 1e-12);
    EXPECT_NEAR(unsure_draft.promised_rel_mse, 0.1 / 4.0 + 3.0 * prior_draft, 1e-12);
    // A measured costlier preset's own error is the nearest cheaper one's, not an older one's.
    measured.record_own_error("cssm", "high", 2, 0.01);
    EXPECT_DOUBLE_EQ(predict_error(analysis, "cssm", "ultra", {{"bounces", 2}}, &measured).rel_mse, 0.1 / 4.0 + 0.01);
    // Another method keeps its prior.
    EXPECT_DOUBLE_EQ(predict_error(analysis, "vct", "low", {}, &measured).rel_mse, 0.1 / 2.0 + *own_error_prior("vct", "low"));
    // A prior, or an own error that took nothing out, is promised as it is.
    EXPECT_DOUBLE_EQ(draft.promised_rel_mse, draft.rel_mse);
    EXPECT_DOUBLE_EQ(low.promised_rel_mse, low.rel_mse);
    // What its comparison took out by the statistic is promised back, to its preset and to the
    // costlier presets that take its error; the estimate is unchanged.
    measured.record_own_estimate("cssm", "low", 2, 0.2 * prior_low, 5, 0.02, 0.01);
    const ErrorPrediction unsure = predict_error(analysis, "cssm", "low", {{"bounces", 2}}, &measured);
    EXPECT_DOUBLE_EQ(unsure.rel_mse, 0.1 / 4.0 + 0.25 * prior_low);
    ASSERT_LT(0.05 * prior_low, 0.01);  // the unsure estimate's promise is the larger
    EXPECT_DOUBLE_EQ(unsure.promised_rel_mse, 0.1 / 4.0 + 0.2 * prior_low + 0.01);
    EXPECT_NE(unsure.basis.find("which a target is promised"), std::string::npos) << unsure.basis;
    const ErrorPrediction unsure_medium = predict_error(analysis, "cssm", "medium", {{"bounces", 2}}, &measured);
    EXPECT_DOUBLE_EQ(unsure_medium.promised_rel_mse, unsure.promised_rel_mse);
}

TEST(FrameComparisons, TheOwnErrorIsTheRelMseLessTheReferencesNoiseAndTheBouncesItLacks) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    // 2.0 against 1.0 everywhere: relMSE (2 - 1)^2 / (1 + 0.01).
    EXPECT_TRUE(comparisons.add(7, frame("cssm", "low", {{"bounces", 2}}, 2.0f), &analysis, measured).empty());
    const auto made = comparisons.add(7, reference(64, 0.64), &analysis, measured);
    ASSERT_EQ(made.size(), 1u);
    // No pair has calibrated the noise statistic yet: the smallest scale the bench corpus measured.
    const double rel_mse = 1.0 / 1.01, noise = FrameComparisons::kUncalibratedNoiseScale * 0.64 / 64.0,
                 gap = 0.1 / 4.0 - 0.1 / 16.0;
    EXPECT_NEAR(made[0].rel_mse, rel_mse, 1e-6);
    EXPECT_DOUBLE_EQ(made[0].reference_noise, noise);
    EXPECT_DOUBLE_EQ(made[0].bounce_gap, gap);
    EXPECT_NEAR(measured.own_error("cssm", "low", 2)->rel_mse, rel_mse - noise - gap, 1e-6);
    // A target is promised the estimate with the noise the statistic took out counted back.
    EXPECT_NEAR(made[0].unsure, noise, 1e-12);
    EXPECT_NEAR(measured.own_error("cssm", "low", 2)->promised, rel_mse - gap, 1e-6);
    // A frame whose error is mostly the bounces it lacks says little of its own: not recorded.
    // (1.25 against 1.0: relMSE 0.062, of which 0.05 - 0.00625 is the light of bounces 1 to 4.)
    EXPECT_TRUE(comparisons.add(7, frame("vct", "high", {}, 1.25f), &analysis, measured).empty());
    EXPECT_FALSE(measured.own_error("vct", "high", 1));
    // Not counted as compared: probed again, a reference of its own bounce count can measure it.
    EXPECT_FALSE(measured.compared("vct", "high"));
    // One the reference's noise drowned is counted: it was compared, and is not probed again.
    // (1.25 against 1.0: relMSE 0.062, of which noise 6.4 / 64 = 0.1; the reference has fewer bounces.)
    FrameComparisons noisy;
    noisy.add(8, frame("cssm", "low", {{"bounces", 6}}, 1.25f), &analysis, measured);
    EXPECT_TRUE(noisy.add(8, reference(64, 6.4), &analysis, measured).empty());
    EXPECT_TRUE(measured.compared("cssm", "low"));
    // A frame with more bounces than the reference keeps the light the reference lacks as error, and
    // records the most its error can be against the whole (the next test).
    const auto more = comparisons.add(7, frame("cssm", "low", {{"bounces", 6}}, 2.0f), &analysis, measured);
    ASSERT_EQ(more.size(), 1u);
    EXPECT_EQ(more[0].bounce_gap, 0.0);
    const double lacking = 0.1 / 16.0 - 0.1 / 64.0;
    EXPECT_NEAR(more[0].own_error, std::pow(std::sqrt(rel_mse - noise) + std::sqrt(lacking), 2.0), 1e-6);
}

// A frame with more bounces than the reference: the light the reference lacks is not taken out, and
// where it is not small beside the relMSE the comparison is left out, since a frame that lacks light
// agrees better with a reference that lacks it too.
TEST(FrameComparisons, AReferenceWithFewerBouncesMeasuresOnlyWhereTheLightItLacksIsSmall) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    // Three bounces lack 0.0125 - 0.1 / 256 = 0.012 of eight's light: over half of 1.1's 0.0099.
    comparisons.add(6, frame("cssm", "low", {{"bounces", 8}}, 1.1f), &analysis, measured);
    EXPECT_TRUE(comparisons.add(6, reference(4096, 0.0, {{"bounces", 3}}), &analysis, measured).empty());
    EXPECT_FALSE(measured.own_error("cssm", "low", 8));
    // Beside 1.5's 0.2475 it is small: kept. What the frame lacks where the reference lacks it too
    // hides from the comparison: recorded is the most it can be against the whole, by the triangle
    // inequality, (sqrt(0.2475) + sqrt(0.012))^2.
    const auto made = comparisons.add(6, frame("cssm", "medium", {{"bounces", 8}}, 1.5f), &analysis, measured);
    ASSERT_EQ(made.size(), 1u);
    EXPECT_EQ(made[0].bounce_gap, 0.0);
    EXPECT_NEAR(made[0].own_error, bound_of_8_bounce_frame_against(3), 1e-6);
}

// A frame of more bounces than any reference of its view: each reference that comes bounds its own
// error, the one of more bounces by less, and the planner keeps the tighter bound. Recorded as
// before, as the largest, the 3-bounce reference's loose bound held cssm draft at 8 bounces out of
// the furnished room's budgets on the GPU (0.184 where it measures 0.046 against the truth).
TEST(FrameComparisons, OfTwoBoundsOnOneViewsFrameTheTighterIsKept) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    bound_an_8_bounce_frame_by_a_3_bounce_reference(comparisons, analysis, measured, 6);
    const double against_3 = bound_of_8_bounce_frame_against(3);
    EXPECT_NEAR(measured.own_error("cssm", "medium", 8)->rel_mse, against_3, 1e-6);
    ASSERT_EQ(comparisons.add(6, reference(4096, 0.0, {{"bounces", 6}}), &analysis, measured).size(), 1u);
    const double against_6 = bound_of_8_bounce_frame_against(6);
    ASSERT_LT(against_6, against_3);
    EXPECT_NEAR(measured.own_error("cssm", "medium", 8)->rel_mse, against_6, 1e-6);
    // The same frame in another view is bounded on its own: its bound counts beside the first view's.
    bound_an_8_bounce_frame_by_a_3_bounce_reference(comparisons, analysis, measured, 7);
    EXPECT_NEAR(measured.own_error("cssm", "medium", 8)->rel_mse, against_3, 1e-6);
}

// The view keeps kMaxFrames GPU frames. A frame of more bounces than any reference has only a bound
// on its own error, so the frames whose bounces a reference has go first, oldest first, and the
// bounded one is still there to be measured when a deeper reference comes.
TEST(FrameComparisons, AFrameOnlyBoundedWaitsForADeeperReference) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    bound_an_8_bounce_frame_by_a_3_bounce_reference(comparisons, analysis, measured, 6);
    std::size_t others = 0;
    for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) {
        comparisons.add(6, frame("direct", preset, {}, 1.2f), &analysis, measured);
        ++others;
    }
    for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) {
        comparisons.add(6, frame("isr", preset, {}, 1.2f), &analysis, measured);
        ++others;
    }
    ASSERT_GT(others + 1, FrameComparisons::kMaxFrames);
    const auto made = comparisons.add(6, reference(4096, 0.0, {{"bounces", 6}}), &analysis, measured);
    const auto cssm = std::find_if(made.begin(), made.end(), [](const Comparison& c) { return c.method == "cssm"; });
    ASSERT_NE(cssm, made.end()) << "the bounded frame was dropped before the deeper reference came";
    EXPECT_NEAR(measured.own_error("cssm", "medium", 8)->rel_mse, bound_of_8_bounce_frame_against(6), 1e-6);
    // Of the measured frames, the oldest went: of eleven, three, the first three direct ones. A
    // reference of no bounces now measures the direct frames still kept: high and ultra.
    const auto direct = comparisons.add(6, reference(4096, 0.0, {{"bounces", 0}}), &analysis, measured);
    std::vector<std::string> kept;
    for (const Comparison& c : direct) kept.push_back(c.method + " " + c.preset);
    std::sort(kept.begin(), kept.end());
    EXPECT_EQ(kept, (std::vector<std::string>{"direct high", "direct ultra"}));
}

TEST(FrameComparisons, OnlyFramesOfOneViewAreCompared) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    comparisons.add(1, frame("vct", "low", {}, 2.0f), &analysis, measured);
    EXPECT_TRUE(comparisons.add(2, reference(64, 0.1), &analysis, measured).empty());  // another view: dropped view 1
    EXPECT_TRUE(comparisons.add(1, reference(256, 0.1), &analysis, measured).empty());  // view 1 again: nothing kept
    EXPECT_FALSE(measured.own_error("vct", "low", 1));
    EXPECT_EQ(comparisons.add(1, frame("vct", "low", {}, 2.0f), &analysis, measured).size(), 1u);
    EXPECT_TRUE(measured.own_error("vct", "low", 1));
    // A frame of another size is no comparison either.
    auto small = std::make_shared<RenderResult>(*frame("vct", "high", {}, 2.0f));
    small->frame.width = small->frame.height = 4;
    small->frame.rgba.resize(4 * 4 * 4);
    EXPECT_TRUE(comparisons.add(1, small, &analysis, measured).empty());
}

// The frame compared again against a quieter reference of its view is one frame estimated twice:
// the estimate that took out least noise stands (SceneMeasurements::record_own_estimate).
TEST(FrameComparisons, AReferenceWithMoreSamplesComparesAgainAndOneWithFewerIsIgnored) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    comparisons.add(1, frame("isr", "medium", {}, 2.0f), &analysis, measured);
    const auto first = comparisons.add(1, reference(64, 0.1), &analysis, measured);
    ASSERT_EQ(first.size(), 1u);
    EXPECT_TRUE(comparisons.add(1, reference(32, 0.1), &analysis, measured).empty());
    const auto again = comparisons.add(1, reference(256, 0.1), &analysis, measured);
    ASSERT_EQ(again.size(), 1u);
    EXPECT_LT(again[0].reference_noise, first[0].reference_noise);
    const auto own = measured.own_error("isr", "medium", 1);
    EXPECT_EQ(own->frames, 1);
    EXPECT_DOUBLE_EQ(own->rel_mse, again[0].own_error);
}

// `direct` lacks every bounce: against a four-bounce reference the missing light (0.094) drowns its
// own error (0.0099), and nothing is recorded. A reference of no bounces, even at 16 samples,
// measures it; a one-bounce frame still goes to the four-bounce reference, the nearer in light.
TEST(FrameComparisons, AFrameIsComparedWithTheReferenceNearestItsOwnBounces) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    comparisons.add(5, frame("direct", "high", {}, 1.1f), &analysis, measured);
    EXPECT_TRUE(comparisons.add(5, reference(64, 0.5), &analysis, measured).empty());
    EXPECT_FALSE(measured.compared("direct", "high"));  // the missing light drowned it: probed again
    EXPECT_FALSE(measured.own_error("direct", "high", 0));
    const auto made = comparisons.add(5, reference(16, 0.0016, {{"bounces", 0}}), &analysis, measured);
    ASSERT_EQ(made.size(), 1u);
    EXPECT_EQ(made[0].bounce_gap, 0.0);
    const double noise = FrameComparisons::kUncalibratedNoiseScale * 0.0016 / 16.0;
    EXPECT_DOUBLE_EQ(made[0].reference_noise, noise);
    EXPECT_NEAR(measured.own_error("direct", "high", 0)->rel_mse, 0.01 / 1.01 - noise, 1e-6);
    // vct (one bounce, 1.5 against 1.0: relMSE 0.2475) goes to the four-bounce reference: the one
    // of no bounces would count its bounce as error, however noisy the four-bounce one is.
    const auto vct = comparisons.add(5, frame("vct", "high", {}, 1.5f), &analysis, measured);
    ASSERT_EQ(vct.size(), 1u);
    EXPECT_DOUBLE_EQ(vct[0].bounce_gap, 0.05 - 0.1 / 16.0);
    // A reference of no bounces with no more samples than the kept one is not kept.
    EXPECT_TRUE(comparisons.add(5, reference(8 * 2, 0.0016, {{"bounces", 0}}), &analysis, measured).empty());
}

// A reference frame brings its frames of fewer bounces (RenderResult::byproducts, the path tracer's
// bounce prefixes): each is a reference of its own bounce count, so `direct` is measured against the
// one of no bounces without a reference traced for it.
TEST(FrameComparisons, AReferencesFramesOfFewerBouncesAreReferencesOfTheirOwnBounceCounts) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    comparisons.add(5, frame("direct", "high", {}, 1.1f), &analysis, measured);
    auto four_bounces = std::make_shared<RenderResult>(*reference(64, 0.5));
    four_bounces->byproducts = {reference(64, 0.0016, {{"bounces", 0}}), reference(64, 0.2, {{"bounces", 1}})};
    const auto made = comparisons.add(5, four_bounces, &analysis, measured);
    ASSERT_EQ(made.size(), 1u);
    EXPECT_EQ(made[0].method, "direct");
    EXPECT_EQ(made[0].bounce_gap, 0.0);
    EXPECT_DOUBLE_EQ(made[0].reference_noise, FrameComparisons::kUncalibratedNoiseScale * 0.0016 / 64.0);
    EXPECT_TRUE(measured.compared("direct", "high"));
    // vct (one bounce) goes to the one-bounce prefix: no bounce gap to subtract.
    const auto vct = comparisons.add(5, frame("vct", "high", {}, 1.5f), &analysis, measured);
    ASSERT_EQ(vct.size(), 1u);
    EXPECT_EQ(vct[0].bounce_gap, 0.0);
    EXPECT_DOUBLE_EQ(vct[0].reference_noise, FrameComparisons::kUncalibratedNoiseScale * 0.2 / 64.0);
    // Their noise is recorded beside the frame's, as a ratio to the analysis' (0.5 per sample).
    record_frame(measured, &analysis, DeviceCosts("test"), *four_bounces, 8, 8);
    EXPECT_DOUBLE_EQ(*measured.noise_ratio(0), 0.0016 / 0.5);
    EXPECT_DOUBLE_EQ(*measured.noise_ratio(1), 0.2 / 0.5);
    EXPECT_DOUBLE_EQ(*measured.noise_ratio(4), 1.0);
}

// A 64-sample reference of 4 bounces at 1.0 (noise 0.5 per sample) whose frame of no bounces (its
// byproduct, noise 0.0016) is at 0.5: the later bounces bring as much light again.
std::shared_ptr<RenderResult> whole_of_a_half_bright_prefix() {
    auto prefix = std::make_shared<RenderResult>(*reference(64, 0.0016, {{"bounces", 0}}));
    for (std::size_t i = 0; i < prefix->frame.rgba.size(); i += 4) {
        for (int c = 0; c < 3; ++c) prefix->frame.rgba[i + c] = 0.5f;
    }
    auto whole = std::make_shared<RenderResult>(*reference(64, 0.5));
    whole->byproducts = {prefix};
    return whole;
}

// Against a bounce prefix, a frame's own error also counts where it meets the later bounces' light:
// `direct` at 0.4 where the frame of no bounces is 0.5 and the later bounces bring it to 1.0 lacks
// light where they add it, and its error against the whole (0.36 / 1.01) is more than the parts apart
// (0.01 / 0.26 against the prefix, 0.25 / 1.01 of bounces). Recorded is what the error model must add
// to the bounces' light to reach the whole: 0.11 / 1.01, less the prefix's noise, and the same
// beyond the whole's 4 bounces.
TEST(FrameComparisons, AgainstABouncePrefixTheOwnErrorCountsWhereItMeetsTheLaterBouncesLight) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    comparisons.add(5, frame("direct", "high", {}, 0.4f), &analysis, measured);
    const auto whole = whole_of_a_half_bright_prefix();
    const auto prefix = whole->byproducts.front();
    const auto made = comparisons.add(5, whole, &analysis, measured);
    ASSERT_EQ(made.size(), 1u);
    const double noise = FrameComparisons::kUncalibratedNoiseScale * 0.0016 / 64.0;
    EXPECT_NEAR(made[0].rel_mse, 0.01 / 0.26, 1e-6);
    const double cross = 0.36 / 1.01 - 0.25 / 1.01 - 0.01 / 0.26;
    EXPECT_NEAR(made[0].cross_term, cross, 1e-6);
    // The analysis has no shares here: nothing is said of the light past the 4 bounces.
    EXPECT_EQ(made[0].cross_beyond, 0.0);
    EXPECT_NEAR(made[0].own_error, 0.11 / 1.01 - noise, 1e-6);
    EXPECT_NEAR(measured.own_error("direct", "high", 0)->rel_mse, 0.11 / 1.01 - noise, 1e-6);
    // A reference of no bounces on its own (no deeper frame of its paths): the parts apart.
    SceneMeasurements alone;
    FrameComparisons other;
    other.add(6, frame("direct", "high", {}, 0.4f), &analysis, alone);
    const auto apart = other.add(6, prefix, &analysis, alone);
    ASSERT_EQ(apart.size(), 1u);
    EXPECT_EQ(apart[0].cross_term, 0.0);
    EXPECT_NEAR(apart[0].own_error, 0.01 / 0.26 - noise, 1e-6);
}

// A frame brighter than its bounce prefix where the later bounces add light fills in part of what it
// lacks: `direct` at 0.6 where the prefix is 0.5 and the whole 1.0 errs 0.16 / 1.01 against the
// whole, less than the 0.25 / 1.01 its bounces lack. What it adds is negative, -0.09 / 1.01 less the
// prefix's noise, and at its own bounce count the error model adds it to the analysis' missing light
// (0.1 here); carried to fewer bounces, an own error is never below 0.
TEST(FrameComparisons, AFrameThatFillsInTheLightItsBouncesLackAddsANegativeOwnError) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    comparisons.add(5, frame("direct", "high", {}, 0.6f), &analysis, measured);
    const auto whole = whole_of_a_half_bright_prefix();
    const auto prefix = whole->byproducts.front();
    const auto made = comparisons.add(5, whole, &analysis, measured);
    ASSERT_EQ(made.size(), 1u);
    const double noise = FrameComparisons::kUncalibratedNoiseScale * 0.0016 / 64.0;
    EXPECT_NEAR(made[0].own_error, -0.09 / 1.01 - noise, 1e-6);
    const auto own = measured.own_error("direct", "high", 0);
    ASSERT_TRUE(own && own->exact);
    EXPECT_NEAR(own->rel_mse, -0.09 / 1.01 - noise, 1e-6);
    EXPECT_NEAR(own->promised, -0.09 / 1.01, 1e-6);  // the noise taken out, counted back
    EXPECT_NEAR(predict_error(analysis, "direct", "high", {}, &measured).rel_mse, 0.1 - 0.09 / 1.01 - noise, 1e-6);
    EXPECT_NEAR(predict_error(analysis, "direct", "high", {}, &measured).promised_rel_mse, 0.1 - 0.09 / 1.01, 1e-6);
    // Never below what the bounces lack: the error against every bounce is not negative.
    SceneMeasurements far;
    FrameComparisons other;
    SceneAnalysis little_missing = analysis;
    little_missing.bounces.stopped_error[0] = 0.01;
    other.add(6, frame("direct", "high", {}, 0.6f), &little_missing, far);
    const auto floored = other.add(6, whole, &little_missing, far);
    ASSERT_EQ(floored.size(), 1u);
    EXPECT_DOUBLE_EQ(floored[0].own_error, -0.01);
    // The floor took in the noise too: nothing is left to count back.
    EXPECT_DOUBLE_EQ(floored[0].unsure, 0.0);
    EXPECT_DOUBLE_EQ(predict_error(little_missing, "direct", "high", {}, &far).rel_mse, 0.0);
    // Carried from 2 bounces to 1, a negative own error counts as 0.
    SceneMeasurements carried;
    carried.record_own_error("cssm", "low", 2, -0.02);
    EXPECT_DOUBLE_EQ(carried.own_error("cssm", "low", 2)->rel_mse, -0.02);
    const auto at_one = carried.own_error("cssm", "low", 1);
    ASSERT_TRUE(at_one && !at_one->exact);
    EXPECT_DOUBLE_EQ(at_one->rel_mse, 0.0);
}

// Past the deeper frame: the cross term is linear in the later light, so the part of it that the
// deeper frame's last bounce brings (against 4 bounces less against 3) goes on as the analysis'
// shares say each bounce's light does, here half the one before: x_4 (1/2) / (1 - 1/2) = x_4.
TEST(FrameComparisons, TheLastBouncesPartOfTheCrossTermGoesOnAsTheLaterLightDoes) {
    SceneAnalysis analysis = made_up_analysis();
    for (int k = 0; k <= 12; ++k) analysis.bounces.share.push_back(std::pow(0.5, k));
    const auto constant = [](std::shared_ptr<const RenderResult> result, float value) {
        auto copy = std::make_shared<RenderResult>(*result);
        for (std::size_t i = 0; i < copy->frame.rgba.size(); i += 4) {
            for (int c = 0; c < 3; ++c) copy->frame.rgba[i + c] = value;
        }
        return copy;
    };
    const auto rel = [](double test, double ref) { return (test - ref) * (test - ref) / (ref * ref + 0.01); };
    SceneMeasurements measured;
    FrameComparisons comparisons;
    comparisons.add(5, frame("direct", "high", {}, 0.4f), &analysis, measured);
    auto whole = std::make_shared<RenderResult>(*reference(64, 0.5));
    whole->byproducts = {constant(reference(64, 0.0016, {{"bounces", 0}}), 0.5f),
                         constant(reference(64, 0.1, {{"bounces", 3}}), 0.7f)};
    const auto made = comparisons.add(5, whole, &analysis, measured);
    ASSERT_EQ(made.size(), 1u);
    const double cross = rel(0.4, 1.0) - rel(0.5, 1.0) - rel(0.4, 0.5);
    const double before_last = rel(0.4, 0.7) - rel(0.5, 0.7) - rel(0.4, 0.5);
    EXPECT_NEAR(made[0].cross_term, cross, 1e-6);
    EXPECT_NEAR(made[0].cross_beyond, cross - before_last, 1e-6);
    // A part that lowers the error is not carried on.
    SceneMeasurements other;
    FrameComparisons lowering;
    lowering.add(6, frame("direct", "high", {}, 0.4f), &analysis, other);
    whole->byproducts[1] = constant(reference(64, 0.1, {{"bounces", 3}}), 0.9f);
    const auto lowered = lowering.add(6, whole, &analysis, other);
    ASSERT_EQ(lowered.size(), 1u);
    EXPECT_LT(lowered[0].cross_term - (rel(0.4, 0.9) - rel(0.5, 0.9) - rel(0.4, 0.5)), 0.0);
    EXPECT_EQ(lowered[0].cross_beyond, 0.0);
}

// Two reference frames of one view tell how much relMSE the noise statistic makes on the scene: here
// the fewer-sample frame is off by +-0.3 in a checkerboard (relMSE 0.09 / 1.01 against the converged
// one) while the statistic per sample, 16 x 0.18, claims 0.18 at its 16 samples (and 16 x 0.18 / 4096
// at the converged frame's): the scene's scale is about a half, and it halves the reference's
// predicted noise and the noise taken out of a GPU frame's comparison. The fewer-sample frame's own
// statistic reads a quarter high, as a frame's does at few samples: of one bounce count, the pair is
// measured against the converged frame's.
TEST(FrameComparisons, TwoReferenceFramesOfAViewMeasureWhatTheirNoiseStatisticMakes) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    const double per_sample = 16.0 * 0.18;
    auto noisy = std::make_shared<RenderResult>(*reference(16, 1.25 * per_sample));
    for (int i = 0; i < 64; ++i) {
        const float offset = ((i % 8 + i / 8) % 2 == 0) ? 0.3f : -0.3f;
        for (int c = 0; c < 3; ++c) noisy->frame.rgba[4 * i + c] += offset;
    }
    auto converged = std::make_shared<RenderResult>(*reference(4096, per_sample));
    converged->stats.knobs["seed"] = 2;  // another seed: the two frames' noise is independent
    comparisons.add(3, converged, &analysis, measured);
    EXPECT_FALSE(measured.noise_scale().has_value());
    comparisons.add(3, noisy, &analysis, measured);  // fewer samples: compared with the kept one, not kept
    ASSERT_TRUE(measured.noise_scale().has_value());
    EXPECT_NEAR(*measured.noise_scale(), (0.09 / 1.01) / (per_sample / 16.0 + per_sample / 4096.0), 1e-6);
    // The error model's noise for the reference, and a comparison's, scale by it.
    const double analysed = analysis.bounces.noise_per_sample[4];
    EXPECT_NEAR(predict_error(analysis, "reference", "medium", {{"spp", 64}, {"bounces", 4}}, &measured).rel_mse,
                analysis.bounces.stopped_error[4] + *measured.noise_scale() * analysed / 64.0, 1e-12);
    // Where the analysis has it, the noise against the frame of every bounce: what a target is
    // measured against.
    SceneAnalysis against_whole = analysis;
    against_whole.bounces.noise_against_whole.assign(13, 0.25);
    EXPECT_NEAR(predict_error(against_whole, "reference", "medium", {{"spp", 64}, {"bounces", 4}}, &measured).rel_mse,
                analysis.bounces.stopped_error[4] + *measured.noise_scale() * 0.25 / 64.0, 1e-12);
    const auto made = comparisons.add(3, frame("cssm", "low", {{"bounces", 4}}, 2.0f), &analysis, measured);
    ASSERT_EQ(made.size(), 1u);
    EXPECT_NEAR(made[0].reference_noise, *measured.least_noise_scale() * per_sample / 4096.0, 1e-12);  // the kept reference's
    // Of one seed, the larger frame holds the smaller's 16 samples: their difference is the smaller's
    // noise less the larger's, 1/16 - 1/4096 of the statistic per sample.
    SceneMeasurements nested;
    EXPECT_NEAR(*FrameComparisons::calibrate_noise(*noisy, *reference(4096, per_sample), &analysis, nested),
                (0.09 / 1.01) / (per_sample * (1.0 / 16.0 - 1.0 / 4096.0)), 1e-6);
    // Not calibrated: references too few samples apart, of other pixel positions, or whose difference
    // is mostly the bounces one lacks.
    SceneMeasurements other;
    EXPECT_FALSE(FrameComparisons::calibrate_noise(*noisy, *reference(24, 0.1), &analysis, other));
    auto jittered = std::make_shared<RenderResult>(*reference(4096, 0.0));
    jittered->stats.knobs["pixel_jitter"] = 1;
    EXPECT_FALSE(FrameComparisons::calibrate_noise(*noisy, *jittered, &analysis, other));
    auto fewer_bounces = std::make_shared<RenderResult>(*noisy);
    fewer_bounces->stats.knobs["bounces"] = 0;  // lacks 0.1 - 0.1 / 16 of the light: over half of 0.089
    EXPECT_FALSE(FrameComparisons::calibrate_noise(*fewer_bounces, *reference(4096, 0.0), &analysis, other));
    // A gap between a quarter and a half of the relMSE: the analysis' own noise in it would swing the
    // scale too far (one bounce lacks 0.05 - 0.00625 = 0.044, 0.49 of 0.089).
    fewer_bounces->stats.knobs["bounces"] = 1;
    EXPECT_FALSE(FrameComparisons::calibrate_noise(*fewer_bounces, *reference(4096, 0.0), &analysis, other));
    // Nor frames with next to no noise (a sun's direct light alone): they measured a scale of 0.
    EXPECT_FALSE(FrameComparisons::calibrate_noise(*reference(16, 1e-4, {{"bounces", 0}}),
                                                   *reference(64, 1e-4, {{"bounces", 0}}), &analysis, other));
    EXPECT_FALSE(other.noise_scale().has_value());
    // The scale is the largest of the last five measured: a target error is a promise. What a
    // comparison takes out of a GPU frame's relMSE is the smallest, for the same reason.
    // Each pair gives two: one for predictions, one for comparisons (calibrate_noise).
    for (const auto& [scale, compared] : {std::pair{0.6, 0.5}, std::pair{0.9, 0.8}, std::pair{0.7, 0.6}}) {
        other.record_noise_scale(scale, compared);
    }
    EXPECT_DOUBLE_EQ(*other.noise_scale(), 0.9);
    EXPECT_DOUBLE_EQ(*other.least_noise_scale(), 0.5);
    FrameComparisons other_view;
    other_view.add(9, frame("cssm", "low", {{"bounces", 4}}, 2.0f), &analysis, other);
    const auto compared = other_view.add(9, reference(64, 0.64), &analysis, other);
    ASSERT_EQ(compared.size(), 1u);
    EXPECT_DOUBLE_EQ(compared[0].reference_noise, 0.5 * 0.64 / 64.0);
    // A frame's own statistic reads high at few samples: where the scene's frames of most samples
    // read less per sample at its bounce count (0.8 x the analysis' 0.5 = 0.4), the less is taken out.
    other.record_noise(4, 0.8, 256);
    FrameComparisons read_lower;
    read_lower.add(10, frame("cssm", "low", {{"bounces", 4}}, 2.0f), &analysis, other);
    const auto lower = read_lower.add(10, reference(64, 0.64), &analysis, other);
    ASSERT_EQ(lower.size(), 1u);
    EXPECT_DOUBLE_EQ(lower[0].reference_noise, 0.5 * 0.4 / 64.0);
    other.record_noise(4, 2.0, 512);  // reading more: the frame's own is the less
    FrameComparisons read_higher;
    read_higher.add(11, frame("cssm", "low", {{"bounces", 4}}, 2.0f), &analysis, other);
    EXPECT_DOUBLE_EQ(read_higher.add(11, reference(64, 0.64), &analysis, other).at(0).reference_noise, 0.5 * 0.64 / 64.0);
}

// calibrate_noise reads a pair of one seed's frames by the neighbourhoods' medians over the larger
// frame's statistic per sample for predictions, and by image::compare's own values over the
// smaller's own statistic (here a quarter high, as at few samples) for comparisons
// (metrics_test.cpp: a rare bright path in both frames, 6^2 / 1.01 against 6^2 / 9.01 at its pixel).
TEST(FrameComparisons, APairIsReadByTheNeighbourhoodsMedianForPredictions) {
    auto fewer = std::make_shared<RenderResult>(*reference(16, 1.25));
    auto more = std::make_shared<RenderResult>(*reference(64, 1.0));
    const std::size_t outlier = 4 * (3 * 8 + 5);
    for (int c = 0; c < 3; ++c) {
        fewer->frame.rgba[outlier + c] = 9.0f;
        more->frame.rgba[outlier + c] = 3.0f;
    }
    SceneMeasurements measured;
    const SceneAnalysis analysis = made_up_analysis();
    const auto scale = FrameComparisons::calibrate_noise(*fewer, *more, &analysis, measured);
    ASSERT_TRUE(scale.has_value());
    const double statistic = 1.0 * (1.0 / 16.0 - 1.0 / 64.0);  // one seed: nested
    EXPECT_NEAR(*scale, 36.0 / 1.01 / 64.0 / statistic, 1e-6);
    EXPECT_NEAR(*measured.noise_scale(), *scale, 1e-12);
    EXPECT_NEAR(*measured.least_noise_scale(), 36.0 / 9.01 / 64.0 / (1.25 * statistic), 1e-6);
}

// The noise taken out is uncertain by about its size: where it would be over a quarter of the
// relMSE no estimate is made. Against a reference of the frame's own bounce count, what is left once
// half that noise (0.54 x 2.2 / 64 = 0.0186) is taken out is recorded as a bound on the view's frame
// where it is under the preset's prior (cssm low's 0.0231): 1.1 against 1.0 reads 0.0099, a bound
// of 0.0006. At 1.25 (0.0619, a bound of 0.053) it would say less than the prior, and at 1.05
// (0.0025, under the noise taken out) nothing: neither is recorded. Without a view, nothing is.
TEST(FrameComparisons, ANoiseOverAQuarterOfTheRelMseLeavesABoundNotAnEstimate) {
    const SceneAnalysis analysis = made_up_analysis();
    const auto drowned = [&](float value, SceneMeasurements& measured) {
        FrameComparisons comparisons;
        comparisons.add(4, frame("cssm", "low", {{"bounces", 4}}, value), &analysis, measured);
        return comparisons.add(4, reference(64, 2.2), &analysis, measured);
    };
    SceneMeasurements measured;
    const auto made = drowned(1.1f, measured);
    ASSERT_EQ(made.size(), 1u);
    EXPECT_TRUE(made[0].noise_bound);
    EXPECT_GT(made[0].reference_noise, FrameComparisons::kMaxNoiseShare * made[0].rel_mse);
    // No bounce gap, no deeper frame: the relMSE less half the noise.
    EXPECT_DOUBLE_EQ(made[0].own_error, made[0].rel_mse - FrameComparisons::kBoundNoiseShare * made[0].reference_noise);
    EXPECT_LT(made[0].own_error, *own_error_prior("cssm", "low", 4));
    ASSERT_TRUE(measured.own_error("cssm", "low", 4));
    EXPECT_DOUBLE_EQ(measured.own_error("cssm", "low", 4)->rel_mse, made[0].own_error);
    // Promised without the half of the noise it took out: the relMSE itself.
    EXPECT_DOUBLE_EQ(made[0].unsure, FrameComparisons::kBoundNoiseShare * made[0].reference_noise);
    EXPECT_NEAR(measured.own_error("cssm", "low", 4)->promised, made[0].rel_mse, 1e-12);
    EXPECT_TRUE(measured.compared("cssm", "low"));
    for (const float value : {1.25f, 1.05f}) {
        SceneMeasurements nothing;
        EXPECT_TRUE(drowned(value, nothing).empty()) << value;
        EXPECT_FALSE(nothing.own_error("cssm", "low", 4)) << value;
        EXPECT_TRUE(nothing.compared("cssm", "low")) << value;
    }
    // Without a view there is no frame to bound: nothing recorded.
    SceneMeasurements viewless;
    EXPECT_FALSE(FrameComparisons::compare(*frame("cssm", "low", {{"bounces", 4}}, 1.1f), *reference(64, 2.2), &analysis,
                                           viewless));
    EXPECT_FALSE(viewless.own_error("cssm", "low", 4));
    // At 0.20 of the relMSE (1.25 against a noise statistic of 1.5), an estimate, the noise taken out.
    FrameComparisons quieter;
    SceneMeasurements estimated;
    quieter.add(5, frame("cssm", "low", {{"bounces", 4}}, 1.25f), &analysis, estimated);
    const auto estimate = quieter.add(5, reference(64, 1.5), &analysis, estimated);
    ASSERT_EQ(estimate.size(), 1u);
    EXPECT_FALSE(estimate[0].noise_bound);
    EXPECT_NEAR(estimated.own_error("cssm", "low", 4)->rel_mse, estimate[0].rel_mse - estimate[0].reference_noise, 1e-12);
}

// A 48x48 frame of `value` plus noise uniform in [-spread, spread] per pixel (on every channel
// alike), drawn from `seed`; no noise where `spread` is 0.
image::Frame noisy_image(float value, float spread, unsigned seed) {
    image::Frame image;
    image.width = image.height = 48;
    image.rgba.assign(48 * 48 * 4, value);
    std::mt19937 draw(seed);
    std::uniform_real_distribution<float> noise(-spread, spread);
    for (std::size_t i = 0; i < image.rgba.size(); i += 4) {
        const float n = spread > 0.0f ? noise(draw) : 0.0f;
        for (int c = 0; c < 3; ++c) image.rgba[i + c] += n;
        image.rgba[i + 3] = 1.0f;
    }
    return image;
}

// `made` with `image` in place of its frame.
std::shared_ptr<const RenderResult> with_image(std::shared_ptr<const RenderResult> made, const image::Frame& image) {
    auto result = std::make_shared<RenderResult>(*made);
    result->frame = image;
    return result;
}

// Draws of an image of 1.0 whose samples have variance 0.5 per value (the statistic says so too): of
// `spp` samples, noise of variance 0.5 / spp, uniform in +-sqrt(1.5 / spp).
image::Frame samples_of(double spp, unsigned seed) { return noisy_image(1.0f, static_cast<float>(std::sqrt(1.5 / spp)), seed); }

// A seed's frame of 16 samples holds its frame of 6: the first 6 samples' mean and the next 10's.
image::Frame sixteen_holding(const image::Frame& six, const image::Frame& ten) {
    image::Frame sixteen = six;
    for (std::size_t i = 0; i < sixteen.rgba.size(); ++i) {
        if (i % 4 != 3) sixteen.rgba[i] = (6.0f * six.rgba[i] + 10.0f * ten.rgba[i]) / 16.0f;
    }
    return sixteen;
}

TEST(FrameComparisons, IndependentDrawsAreTheFramesOfTwoSeedsOrTheLaterSamplesOfOne) {
    const image::Frame six = samples_of(6, 1), ten = samples_of(10, 2);
    const auto fewer = with_image(reference(6, 0.5, {{"seed", 1}}), six);
    const auto more = with_image(reference(16, 0.5, {{"seed", 1}}), sixteen_holding(six, ten));
    const auto draws = FrameComparisons::independent_draws(*fewer, *more);
    ASSERT_TRUE(draws);
    for (std::size_t i = 0; i < ten.rgba.size(); ++i) {
        if (i % 4 != 3) ASSERT_NEAR(draws->second.rgba[i], ten.rgba[i], 1e-5) << i;
    }
    EXPECT_EQ(draws->first.rgba, six.rgba);
    image::Frame smaller = six;
    smaller.width = smaller.height = 24;
    smaller.rgba.resize(24 * 24 * 4);
    EXPECT_THROW(FrameComparisons::later_samples(smaller, 6, ten, 16), Error);
    EXPECT_THROW(FrameComparisons::later_samples(six, 16, ten, 16), Error);
    const auto other_seed = with_image(reference(16, 0.5, {{"seed", 7}}), ten);
    const auto apart = FrameComparisons::independent_draws(*fewer, *other_seed);
    ASSERT_TRUE(apart);
    EXPECT_EQ(apart->second.rgba, ten.rgba);
    // Not a pair: one seed's frames of one count of samples (the same frame), other bounce counts,
    // pixel positions or sizes, a frame that is not a reference's, or denoised.
    EXPECT_FALSE(FrameComparisons::independent_draws(*fewer, *with_image(reference(6, 0.5, {{"seed", 1}}), six)));
    EXPECT_FALSE(FrameComparisons::independent_draws(*fewer, *with_image(reference(16, 0.5, {{"seed", 7}, {"bounces", 2}}), ten)));
    auto jittered = std::make_shared<RenderResult>(*other_seed);
    jittered->stats.knobs["pixel_jitter"] = 1;
    EXPECT_FALSE(FrameComparisons::independent_draws(*fewer, *jittered));
    EXPECT_FALSE(FrameComparisons::independent_draws(*fewer, *reference(16, 0.5, {{"seed", 7}})));
    EXPECT_FALSE(FrameComparisons::independent_draws(*fewer, *with_image(frame("cssm", "low", {}, 1.0f), ten)));
    EXPECT_FALSE(FrameComparisons::independent_draws(*fewer, *with_image(reference(16, 0.5, {{"seed", 7}, {"denoise", 1}}), ten)));
    EXPECT_TRUE(FrameComparisons::usable_draw(fewer->stats));
    EXPECT_FALSE(FrameComparisons::usable_reference(fewer->stats));
}

// cssm low's frame of 1.1 at 4 bounces against draws of 1.0 at 4 bounces: its own error is 0.01 / 1.01.
// Against the 16-sample frame the noise adds about 0.5 / 16 = 0.031 (the statistic expects 0.54 x that
// before a pair has measured it): drowned. With the seed's 6-sample frame beside it, the two draws'
// cross estimate reads the own error: within four standard errors and the 5% the union's noisy weights add
// (Metrics.TheCrossEstimateOfTwoIndependentDrawsLeavesTheirNoiseOut), and recorded as an estimate of
// it plus one standard error, not a bound. Without the second draw, no cross estimate.
TEST(FrameComparisons, ADrownedComparisonWithASecondDrawOfItsSeedTakesTheirCrossEstimate) {
    const SceneAnalysis analysis = made_up_analysis();
    const double truth = 0.01 / 1.01;
    const auto gpu_frame = with_image(frame("cssm", "low", {{"bounces", 4}}, 1.1f), noisy_image(1.1f, 0.0f, 0));
    const image::Frame six = samples_of(6, 11), ten = samples_of(10, 12);
    const auto sixteen = with_image(reference(16, 0.5, {{"seed", 1}}), sixteen_holding(six, ten));
    {
        SceneMeasurements measured;
        FrameComparisons comparisons;
        comparisons.add(3, gpu_frame, &analysis, measured);
        // (a bound here would be over cssm low's prior: nothing is recorded)
        for (const Comparison& c : comparisons.add(3, sixteen, &analysis, measured)) EXPECT_FALSE(c.cross_estimate);
    }
    SceneMeasurements measured;
    FrameComparisons comparisons;
    comparisons.add(3, gpu_frame, &analysis, measured);
    EXPECT_TRUE(comparisons.add(3, with_image(reference(6, 0.5, {{"seed", 1}}), six), &analysis, measured).empty());
    EXPECT_FALSE(measured.compared("cssm", "low"));
    const auto made = comparisons.add(3, sixteen, &analysis, measured);
    ASSERT_EQ(made.size(), 1u);
    const Comparison& c = made[0];
    EXPECT_GT(c.rel_mse, 3.0 * truth);
    EXPECT_GT(c.reference_noise, FrameComparisons::kMaxNoiseShare * c.rel_mse);
    EXPECT_TRUE(c.cross_estimate);
    EXPECT_FALSE(c.noise_bound);
    EXPECT_NEAR(c.cross_rel_mse, truth, 0.05 * truth + 4.0 * c.cross_standard_error);
    EXPECT_LE(2.0 * c.cross_standard_error, FrameComparisons::kMaxCrossSpread * c.cross_rel_mse);
    EXPECT_NEAR(c.own_error, c.cross_rel_mse + c.cross_standard_error, 1e-12);
    ASSERT_TRUE(measured.own_error("cssm", "low", 4));
    EXPECT_DOUBLE_EQ(measured.own_error("cssm", "low", 4)->rel_mse, c.own_error);
    // The two draws measured the noise: nothing taken out by the statistic, so nothing counted back.
    EXPECT_EQ(c.unsure, 0.0);
    EXPECT_DOUBLE_EQ(measured.own_error("cssm", "low", 4)->promised, c.own_error);
    EXPECT_TRUE(measured.compared("cssm", "low"));
    // An estimate: a bound of the view later does not replace it.
    measured.record_own_error("cssm", "low", 4, 0.001, 3);
    EXPECT_DOUBLE_EQ(measured.own_error("cssm", "low", 4)->rel_mse, c.own_error);
    // The 16-sample frame first and another seed's 16 after it (not kept: no more samples): the
    // kept one's partner, two draws as they are, and the frame is measured again by the pair.
    SceneMeasurements apart;
    FrameComparisons seeds;
    seeds.add(4, gpu_frame, &analysis, apart);
    for (const Comparison& bound : seeds.add(4, sixteen, &analysis, apart)) EXPECT_FALSE(bound.cross_estimate);
    const auto again = seeds.add(4, with_image(reference(16, 0.5, {{"seed", 7}}), samples_of(16, 13)), &analysis, apart);
    ASSERT_EQ(again.size(), 1u);
    EXPECT_TRUE(again[0].cross_estimate);
    EXPECT_NEAR(again[0].cross_rel_mse, truth, 0.05 * truth + 4.0 * again[0].cross_standard_error);
    EXPECT_TRUE(apart.own_error("cssm", "low", 4));
}

// Reference plans of loose targets trace few samples (the street's 3 and 6 for 0.1 and 0.05): one such
// draw alone measures nothing, and leaves the frame's preset to be probed again; two of one seed
// measure the frame by their cross estimate. Where that spreads too widely (a frame of next to no
// error, the estimate 0 +- its noise), nothing is recorded either.
TEST(FrameComparisons, DrawsOfTooFewSamplesToBeReferencesMeasureAFrameOnlyAsAPair) {
    const SceneAnalysis analysis = made_up_analysis();
    const image::Frame three = samples_of(3, 21), later_three = samples_of(3, 22);
    image::Frame six = three;
    for (std::size_t i = 0; i < six.rgba.size(); ++i) {
        if (i % 4 != 3) six.rgba[i] = 0.5f * (three.rgba[i] + later_three.rgba[i]);
    }
    const auto measure = [&](float value, SceneMeasurements& measured) {
        FrameComparisons comparisons;
        comparisons.add(9, with_image(reference(3, 0.5, {{"seed", 1}}), three), &analysis, measured);
        EXPECT_TRUE(comparisons.add(9, with_image(frame("cssm", "low", {{"bounces", 4}}, value), noisy_image(value, 0.0f, 0)),
                                    &analysis, measured).empty());
        EXPECT_FALSE(measured.compared("cssm", "low"));
        return comparisons.add(9, with_image(reference(6, 0.5, {{"seed", 1}}), six), &analysis, measured);
    };
    SceneMeasurements measured;
    const auto made = measure(1.3f, measured);  // own error 0.09 / 1.01
    ASSERT_EQ(made.size(), 1u);
    EXPECT_TRUE(made[0].cross_estimate);
    EXPECT_NEAR(made[0].cross_rel_mse, 0.09 / 1.01, 0.05 * 0.09 / 1.01 + 4.0 * made[0].cross_standard_error);
    EXPECT_TRUE(measured.own_error("cssm", "low", 4));
    EXPECT_TRUE(measured.compared("cssm", "low"));
    // A frame that comes after the pair is measured by it as it comes.
    FrameComparisons after;
    SceneMeasurements later;
    after.add(10, with_image(reference(3, 0.5, {{"seed", 1}}), three), &analysis, later);
    after.add(10, with_image(reference(6, 0.5, {{"seed", 1}}), six), &analysis, later);
    const auto came = after.add(10, with_image(frame("cssm", "low", {{"bounces", 4}}, 1.3f), noisy_image(1.3f, 0.0f, 0)),
                                &analysis, later);
    ASSERT_EQ(came.size(), 1u);
    EXPECT_TRUE(came[0].cross_estimate);
    EXPECT_DOUBLE_EQ(came[0].cross_rel_mse, made[0].cross_rel_mse);
    SceneMeasurements unmeasured;
    EXPECT_TRUE(measure(1.0f, unmeasured).empty());
    EXPECT_FALSE(unmeasured.own_error("cssm", "low", 4));
    EXPECT_FALSE(unmeasured.compared("cssm", "low"));
}

// A client that sends reference frames of one sample at every bounce count holds at most
// kMaxExtraDraws of them beside each count's reference, the fewest samples dropped first, and a
// frame after them is still measured.
TEST(FrameComparisons, ManyDrawsOfFewSamplesHoldABoundedNumberOfFrames) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameComparisons comparisons;
    for (int bounces = 0; bounces <= 12; ++bounces) {
        for (const unsigned seed : {1u, 2u, 3u}) {
            comparisons.add(6, with_image(reference(1, 0.5, {{"seed", seed}, {"bounces", bounces}}), samples_of(1, seed)),
                            &analysis, measured);
        }
        comparisons.add(6, with_image(reference(64, 0.5, {{"seed", 9}, {"bounces", bounces}}), samples_of(64, 9)), &analysis,
                        measured);
    }
    // Each count's 64-sample reference and at most kMaxExtraDraws others (a count's own limit may
    // drop one more: kMaxDraws).
    EXPECT_LE(comparisons.draws_held(), 13u + FrameComparisons::kMaxExtraDraws);
    EXPECT_GE(comparisons.draws_held(), 13u + 1u);
    // Draws of more samples displace those of one.
    comparisons.add(6, with_image(reference(8, 0.5, {{"seed", 1}}), samples_of(8, 31)), &analysis, measured);
    comparisons.add(6, with_image(reference(12, 0.5, {{"seed", 2}}), samples_of(12, 32)), &analysis, measured);
    EXPECT_LE(comparisons.draws_held(), 13u + FrameComparisons::kMaxExtraDraws);
    // The frame of a count is still measured: against its reference, or the pair of 8 and 12 samples.
    const auto made = comparisons.add(6, with_image(frame("cssm", "low", {{"bounces", 4}}, 1.3f), noisy_image(1.3f, 0.0f, 0)),
                                      &analysis, measured);
    EXPECT_FALSE(made.empty());
}

TEST(FrameComparisons, NoisyDenoisedOrUnlikeFramesAreNotCompared) {
    const SceneAnalysis analysis = made_up_analysis();
    // The reference's noise over a quarter of the relMSE (0.54 x 0.006 = 0.0032 of 0.0099): the noise taken
    // out is uncertain by about its size, and the own part would be mostly noise.
    {
        SceneMeasurements measured;
        FrameComparisons comparisons;
        comparisons.add(1, frame("direct", "high", {}, 1.1f), &analysis, measured);  // relMSE 0.0099
        EXPECT_TRUE(comparisons.add(1, reference(16, 16 * 0.006), &analysis, measured).empty());
        EXPECT_FALSE(measured.own_error("direct", "high", 0));
    }
    EXPECT_TRUE(FrameComparisons::usable_reference(reference(64, 0.1)->stats));
    EXPECT_FALSE(FrameComparisons::usable_reference(reference(8, 0.1)->stats));
    EXPECT_FALSE(FrameComparisons::usable_reference(reference(64, 0.1, {{"denoise", 1}})->stats));
    EXPECT_FALSE(FrameComparisons::usable_reference(reference(64, 0.1, {{"ao", 1}})->stats));
    EXPECT_FALSE(FrameComparisons::usable_reference(reference(64, 0.1, {{"indirect_visibility", 0}})->stats));
    auto without_noise = std::make_shared<RenderResult>(*reference(64, 0.1));
    without_noise->stats.method_statistics.clear();
    EXPECT_FALSE(FrameComparisons::usable_reference(without_noise->stats));
    // A GPU frame is its preset's, whatever its bounces; another knob makes it another method.
    EXPECT_TRUE(FrameComparisons::usable_gpu_frame(frame("cssm", "high", {{"bounces", 5}}, 1.0f)->stats));
    EXPECT_TRUE(FrameComparisons::usable_gpu_frame(frame("vct", "draft", {}, 1.0f)->stats));
    const auto& vct_knobs = methods::MethodRegistry::builtin().find("vct").presets.at("draft");
    const std::string changed = vct_knobs.begin()->first == "bounces" ? std::next(vct_knobs.begin())->first
                                                                       : vct_knobs.begin()->first;
    auto tuned = std::make_shared<RenderResult>(*frame("vct", "draft", {}, 1.0f));
    tuned->stats.knobs[changed] += 1.0;
    EXPECT_FALSE(FrameComparisons::usable_gpu_frame(tuned->stats)) << changed;
    EXPECT_FALSE(FrameComparisons::usable_gpu_frame(reference(64, 0.1)->stats));
    // What a preset leaves to the scene (isr's ism_dilation) counts as the preset's where it is what
    // the scene resolves, not where the request set it otherwise.
    SceneAnalysis open, walled;
    open.visibility = {1000, 0.05};
    walled.visibility = {1000, 0.6};
    const auto isr_low = [&](double dilation) {
        auto made = std::make_shared<RenderResult>(*frame("isr", "low", {}, 1.0f));
        made->stats.knobs = methods::MethodRegistry::builtin().resolve("isr", "low", {{"ism_dilation", dilation}});
        return made;
    };
    EXPECT_TRUE(FrameComparisons::usable_gpu_frame(isr_low(0)->stats, &open));
    EXPECT_FALSE(FrameComparisons::usable_gpu_frame(isr_low(2)->stats, &open));
    EXPECT_FALSE(FrameComparisons::usable_gpu_frame(isr_low(1)->stats, &open));
    EXPECT_TRUE(FrameComparisons::usable_gpu_frame(isr_low(2)->stats, &walled));
    EXPECT_FALSE(FrameComparisons::usable_gpu_frame(isr_low(0)->stats, &walled));
    EXPECT_TRUE(FrameComparisons::usable_gpu_frame(isr_low(1)->stats));  // no analysis: whatever the scene could set
}

Candidate candidate(std::string method, std::string preset, methods::KnobValues knobs, double ms, double error = 0.1) {
    return {std::move(method), std::move(preset), std::move(knobs), ms, error, "table", "table"};
}

TEST(Probes, BesideAReferencePlanUnmeasuredPresetsCheapestFirstWithinItsTime) {
    const Candidate chosen = candidate("reference", "medium", {{"spp", 64}}, 100.0);
    const std::vector<Candidate> all = {
        chosen,
        candidate("cssm", "low", {{"bounces", 1}}, 5.0, 0.1),
        candidate("cssm", "low", {{"bounces", 2}}, 30.0, 0.05),  // the preset's most accurate that fits alone
        candidate("cssm", "low", {{"bounces", 8}}, 120.0, 0.01),  // over the 100 ms share by itself
        candidate("vct", "draft", {}, 10.0),
        candidate("isr", "medium", {}, 70.0),
        candidate("direct", "high", {}, 50.0),
        candidate("reference", "medium", {{"spp", 4}}, 7.0),
    };
    const auto first = probes(all, chosen, nullptr);
    // 10 + 30 + 50 ms; isr's 70 more would pass 100; then cssm low's plan of fewest bounces (5 ms).
    ASSERT_EQ(first.size(), 4u);
    EXPECT_EQ(first[0].method, "vct");
    EXPECT_EQ(first[1].method, "cssm");
    EXPECT_EQ(first[1].knobs.at("bounces"), 2.0);
    EXPECT_EQ(first[2].method, "direct");
    EXPECT_EQ(first[3].method, "cssm");
    EXPECT_EQ(first[3].knobs.at("bounces"), 1.0);
    // cssm low compared with a reference frame once at each count: no longer probed.
    SceneMeasurements measured;
    measured.record_compared("cssm", "low", 2);
    const auto second = probes(all, chosen, &measured);
    ASSERT_EQ(second.size(), 3u);
    EXPECT_EQ(second[0].method, "vct");
    EXPECT_EQ(second[1].method, "direct");
    EXPECT_EQ(second[2].knobs.at("bounces"), 1.0);
    measured.record_compared("cssm", "low", 1);
    const auto third = probes(all, chosen, &measured);
    ASSERT_EQ(third.size(), 2u);
    EXPECT_EQ(third[0].method, "vct");
    EXPECT_EQ(third[1].method, "direct");
    // A GPU plan chosen: no probes (no reference frame to compare with).
    EXPECT_TRUE(probes(all, all[4], nullptr).empty());
}

// The own error measured at a preset's most bounces is carried to its fewer as if the two parts
// added apart (SceneMeasurements::own_error); a time budget takes the fewer, so they are probed too,
// after every preset's first probe, until measured at their own count.
TEST(Probes, APresetsFewestBouncesAreProbedAfterEveryPresetsFirst) {
    const Candidate chosen = candidate("reference", "medium", {{"spp", 64}, {"bounces", 4}}, 100.0);
    const std::vector<Candidate> all = {
        chosen,
        candidate("vct", "draft", {{"bounces", 1}}, 20.0, 0.2),
        candidate("vct", "draft", {{"bounces", 2}}, 25.0, 0.1),
        candidate("isr", "draft", {}, 40.0),
        candidate("direct", "high", {}, 5.0),
    };
    const auto first = probes(all, chosen, nullptr);
    ASSERT_EQ(first.size(), 4u);  // 5 + 25 + 40, then vct draft's one bounce (20)
    EXPECT_EQ(first[0].method, "direct");
    EXPECT_EQ(first[1].method, "vct");
    EXPECT_EQ(first[1].knobs.at("bounces"), 2.0);
    EXPECT_EQ(first[2].method, "isr");
    EXPECT_EQ(first[3].method, "vct");
    EXPECT_EQ(first[3].knobs.at("bounces"), 1.0);
    // The share is spent on every preset's first probe before any preset's fewer bounces.
    Candidate tight = chosen;
    tight.predicted_ms = 75.0;
    const auto first_tight = probes(all, tight, nullptr);
    ASSERT_EQ(first_tight.size(), 3u);
    EXPECT_TRUE(std::none_of(first_tight.begin(), first_tight.end(),
                             [](const Candidate& c) { return c.knobs.count("bounces") && c.knobs.at("bounces") == 1.0; }));
    // Measured at 2 bounces: the preset's first probe is done, its one bounce is not.
    SceneMeasurements measured;
    measured.record_compared("vct", "draft", 2);
    measured.record_own_error("vct", "draft", 2, 0.1);
    const auto second = probes(all, chosen, &measured);
    ASSERT_EQ(second.size(), 3u);
    EXPECT_EQ(second[2].method, "vct");
    EXPECT_EQ(second[2].knobs.at("bounces"), 1.0);
    // Measured at 1 bounce too: vct draft is no longer probed.
    measured.record_compared("vct", "draft", 1);
    measured.record_own_error("vct", "draft", 1, 0.05);
    const auto third = probes(all, chosen, &measured);
    ASSERT_EQ(third.size(), 2u);
    EXPECT_TRUE(std::none_of(third.begin(), third.end(), [](const Candidate& c) { return c.method == "vct"; }));
}

// The second round takes a preset's fewest bounces, not its cheapest plan; and where the chosen
// reference's own frames of fewer bounces measure a probe (made_up_analysis at 256 samples: noise
// 0.001, under a third of the own errors here), an own error only carried from another bounce count
// is probed again at its own count, while one measured there is not.
TEST(Probes, TheSecondRoundTakesTheFewestBouncesAndReprobesOnlyCarriedErrors) {
    const SceneAnalysis analysis = made_up_analysis();
    const auto stopped = [](int k) { return 0.1 / std::pow(2.0, k); };
    const Candidate chosen = candidate("reference", "medium", {{"spp", 256}, {"bounces", 4}}, 100.0, stopped(4) + 0.002);
    const std::vector<Candidate> all = {
        chosen,
        candidate("cssm", "low", {{"bounces", 4}}, 40.0, stopped(4) + 0.02),  // the first round's
        candidate("cssm", "low", {{"bounces", 2}}, 20.0, stopped(2) + 0.02),  // cheaper, but not the fewest
        candidate("cssm", "low", {{"bounces", 1}}, 30.0, stopped(1) + 0.02),
    };
    const auto first = probes(all, chosen, nullptr, &analysis, 4);
    ASSERT_EQ(first.size(), 2u);
    EXPECT_EQ(first[0].knobs.at("bounces"), 4.0);
    EXPECT_EQ(first[1].knobs.at("bounces"), 1.0);
    // Compared at 4 and 1 bounces, its own error measured at 4 alone: at 1 it is carried, and probed again.
    SceneMeasurements measured;
    measured.record_compared("cssm", "low", 4);
    measured.record_own_error("cssm", "low", 4, 0.02);
    measured.record_compared("cssm", "low", 1);
    ASSERT_TRUE(measured.own_error("cssm", "low", 1).has_value());
    ASSERT_FALSE(measured.own_error("cssm", "low", 1)->exact);
    const auto carried = probes(all, chosen, &measured, &analysis, 4);
    ASSERT_EQ(carried.size(), 1u);
    EXPECT_EQ(carried[0].knobs.at("bounces"), 1.0);
    const auto at_one = [](const std::vector<Candidate>& chosen_probes) {
        return std::any_of(chosen_probes.begin(), chosen_probes.end(),
                           [](const Candidate& c) { return c.knobs.at("bounces") == 1.0; });
    };
    // Without the reference's own frames of fewer bounces nothing would measure it: not probed.
    EXPECT_FALSE(at_one(probes(all, chosen, &measured, &analysis, 0)));
    // Measured at 1 bounce itself: not probed again; the fewest count not yet compared (2) is next.
    measured.record_own_error("cssm", "low", 1, 0.02);
    const auto measured_at_one = probes(all, chosen, &measured, &analysis, 4);
    ASSERT_EQ(measured_at_one.size(), 1u);
    EXPECT_EQ(measured_at_one[0].knobs.at("bounces"), 2.0);
}

// made_up_analysis: stopping at k bounces loses 0.1 / 2^k. Beside a four-bounce reference of noise
// 0.002, direct (own error 0.012) would be drowned by the 0.094 it lacks, and so would vct draft
// (own 0.03, lacking 0.044); cssm at four bounces (own 0.02) would not. Companions: the cheapest
// reference of no bounces, and of one, whose noise is at most a third of the smallest own error there.
TEST(Probes, AProbeTheMissingLightWouldDrownGetsAReferenceOfItsOwnBounces) {
    const SceneAnalysis analysis = made_up_analysis();
    const auto stopped = [](int k) { return 0.1 / std::pow(2.0, k); };
    const Candidate chosen = candidate("reference", "medium", {{"spp", 256}, {"bounces", 4}}, 1000.0, stopped(4) + 0.002);
    std::vector<Candidate> all = {
        chosen,
        candidate("direct", "high", {}, 5.0, stopped(0) + 0.012),
        candidate("vct", "draft", {}, 20.0, stopped(1) + 0.03),
        candidate("cssm", "low", {{"bounces", 4}}, 30.0, stopped(4) + 0.02),
    };
    for (const int bounces : {0, 1}) {
        for (const int spp : {8, 16, 32, 64}) {
            // Noise 0.08 / spp, at most a third of the own error: at no bounces 32 spp (0.0025; 16
            // spp's 0.005 is over 0.012 / 3); at one, 16 spp (0.005, under 0.03 / 3); 8 spp is never
            // a companion (under 16 samples).
            all.push_back(candidate("reference", "medium", {{"spp", spp}, {"bounces", bounces}}, 2.0 * spp * (bounces + 1),
                                    stopped(bounces) + 0.08 / spp));
        }
    }
    const auto chosen_probes = probes(all, chosen, nullptr, &analysis);
    ASSERT_EQ(chosen_probes.size(), 5u);
    EXPECT_EQ(chosen_probes[3].method, "reference");
    EXPECT_EQ(chosen_probes[3].knobs.at("bounces"), 0.0);
    EXPECT_EQ(chosen_probes[3].knobs.at("spp"), 32.0);
    EXPECT_EQ(chosen_probes[4].knobs.at("bounces"), 1.0);
    EXPECT_EQ(chosen_probes[4].knobs.at("spp"), 16.0);
    // A probe whose companion does not fit the share is not taken either: alone, its comparison would
    // be dropped. In 100 ms: direct and its 64 ms companion, then cssm; vct with its 64 ms one would pass.
    Candidate cheap_reference = chosen;
    cheap_reference.predicted_ms = 5.0 + 64.0 + 30.0 + 1.0;
    const auto tight = probes(all, cheap_reference, nullptr, &analysis);
    ASSERT_EQ(tight.size(), 3u);
    EXPECT_EQ(tight[0].method, "direct");
    EXPECT_EQ(tight[1].method, "cssm");
    EXPECT_EQ(tight[2].knobs.at("bounces"), 0.0);
    // Without the analysis, no companion is looked for.
    EXPECT_EQ(probes(all, chosen, nullptr).size(), 3u);
    // Where the chosen reference brings its own frames of 0..3 bounces, their noise at its 256
    // samples (0.54 x 0.5 / 256 = 0.001) is under each probe's own error: no companion is traced.
    const auto with_prefixes = probes(all, chosen, nullptr, &analysis, 4);
    ASSERT_EQ(with_prefixes.size(), 3u);
    for (const Candidate& probe : with_prefixes) EXPECT_NE(probe.method, "reference");
    // direct compared before without its error learned (noise drowned it): probed again beside this
    // reference, whose frame of no bounces measures it; once learned, not again.
    SceneMeasurements drowned;
    drowned.record_compared("direct", "high", 0);
    const auto again = probes(all, chosen, &drowned, &analysis, 4);
    EXPECT_TRUE(std::any_of(again.begin(), again.end(), [](const Candidate& c) { return c.method == "direct"; }));
    const auto without_prefixes = probes(all, chosen, &drowned, &analysis, 0);
    EXPECT_TRUE(std::none_of(without_prefixes.begin(), without_prefixes.end(),
                             [](const Candidate& c) { return c.method == "direct"; }));
    drowned.record_own_error("direct", "high", 0, 0.012);
    const auto learned = probes(all, chosen, &drowned, &analysis, 4);
    EXPECT_TRUE(std::none_of(learned.begin(), learned.end(), [](const Candidate& c) { return c.method == "direct"; }));
    // A prefix is judged by its noise against its own frame, as the comparison takes it out: where
    // that is 4 per sample at no bounces (4 / 256 = 0.016, over a third of direct's 0.012), direct
    // needs its companion, however little the same noise weighs against the frame of every bounce.
    SceneAnalysis dark_prefix = analysis;
    dark_prefix.bounces.noise_per_sample[0] = 4.0;
    dark_prefix.bounces.noise_against_whole.assign(13, 0.5);
    const auto judged_own = probes(all, chosen, nullptr, &dark_prefix, 4);
    ASSERT_EQ(judged_own.size(), 4u);
    EXPECT_EQ(judged_own[3].method, "reference");
    EXPECT_EQ(judged_own[3].knobs.at("bounces"), 0.0);
    // Prefixes of no bounces only (a large frame): vct's one-bounce probe still needs its companion.
    const auto zero_only = probes(all, chosen, nullptr, &analysis, 1);
    ASSERT_EQ(zero_only.size(), 4u);
    EXPECT_EQ(zero_only[3].knobs.at("bounces"), 1.0);
}

// Where no companion fits, a probe goes alone beside the reference's own prefix of its bounce count
// if that prefix's noise is under the probe's predicted own error: noise and all, the comparison
// bounds the own error under the prediction (FrameComparisons::compare). Within 40 ms no companion
// (64 ms) fits: direct (own 0.012) goes alone where the prefix's noise is 2 / 256 = 0.0078, not
// where it is 4 / 256 = 0.016; vct (its prefix quiet, 0.002) goes either way, cssm no longer fits.
TEST(Probes, WithoutACompanionAProbeGoesAloneWhereItsPrefixCanBoundIt) {
    const SceneAnalysis analysis = made_up_analysis();
    const auto stopped = [](int k) { return 0.1 / std::pow(2.0, k); };
    Candidate chosen = candidate("reference", "medium", {{"spp", 256}, {"bounces", 4}}, 40.0, stopped(4) + 0.002);
    const std::vector<Candidate> all = {
        chosen,
        candidate("direct", "high", {}, 5.0, stopped(0) + 0.012),
        candidate("vct", "draft", {}, 20.0, stopped(1) + 0.03),
        candidate("cssm", "low", {{"bounces", 4}}, 30.0, stopped(4) + 0.02),
        candidate("reference", "medium", {{"spp", 32}, {"bounces", 0}}, 64.0, stopped(0) + 0.0025),
    };
    SceneAnalysis bounding = analysis;
    bounding.bounces.noise_per_sample[0] = 2.0;
    const auto alone = probes(all, chosen, nullptr, &bounding, 4);
    ASSERT_EQ(alone.size(), 2u);
    EXPECT_EQ(alone[0].method, "direct");
    EXPECT_EQ(alone[1].method, "vct");
    SceneAnalysis drowning = analysis;
    drowning.bounces.noise_per_sample[0] = 4.0;
    const auto without = probes(all, chosen, nullptr, &drowning, 4);
    ASSERT_EQ(without.size(), 1u);
    EXPECT_EQ(without[0].method, "vct");
    // Where the companion fits, it still goes with the probe: a quieter reference measures, not bounds.
    chosen.predicted_ms = 100.0;
    const auto accompanied = probes(all, chosen, nullptr, &bounding, 4);
    EXPECT_TRUE(std::any_of(accompanied.begin(), accompanied.end(), [](const Candidate& c) {
        return c.method == "reference" && c.knobs.at("bounces") == 0.0;
    }));
}

TEST(Resolution, BilinearUpsamplingBetweenPixelCentres) {
    image::Frame ramp;
    ramp.width = 2;
    ramp.height = 1;
    ramp.rgba = {0, 0, 0, 1, 1, 2, 4, 1};
    const image::Frame up = image::resample_linear(ramp, 4, 2);
    // Target centres at -0.25, 0.25, 0.75 and 1.25 source pixels: clamped at the edges.
    const float expected[] = {0.0f, 0.25f, 0.75f, 1.0f};
    for (int y = 0; y < 2; ++y) {
        for (int x = 0; x < 4; ++x) {
            EXPECT_FLOAT_EQ(up.at(x, y).r, expected[x]) << x << "," << y;
            EXPECT_FLOAT_EQ(up.at(x, y).b, 4.0f * expected[x]);
            EXPECT_FLOAT_EQ(up.at(x, y).a, 1.0f);
        }
    }
    EXPECT_TRUE(up.display_rgba8.empty());
    EXPECT_THROW(image::resample_linear(ramp, 0, 4), InputError);
    EXPECT_THROW(image::resample_linear(image::Frame{}, 4, 4), InputError);
    EXPECT_EQ(scaled_size(64, 48, 0.5), (std::pair{32, 24}));
    EXPECT_EQ(scaled_size(3, 3, 0.25), (std::pair{1, 1}));
    EXPECT_EQ(measured_size(200, 100), (std::pair{200, 100}));
    EXPECT_EQ(measured_size(1920, 1080), (std::pair{256, 144}));
}

TEST(Resolution, AHalfSizePlanIsTakenWhereOnlyItFitsAndPaysWhatUpsamplingLoses) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    for (const char* method : {"direct", "vct"}) {
        for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) device.set(method, preset, {0.0, 1e4});
    }
    // direct: 41 ms at 64x64, 10 ms at 32x32; vct has no measured loss, so full size only.
    PlanningInputs inputs{analysis, device, nullptr, 64, 64, std::nullopt, {{"direct", {{0.5, 0.1}}}}};
    const auto all = candidates(inputs);
    EXPECT_EQ(std::count_if(all.begin(), all.end(), [](const Candidate& c) { return c.scale == 0.5; }), 5);
    for (const Candidate& c : all) EXPECT_TRUE(c.scale == 1.0 || c.method == "direct") << c.method;
    PlanningInputs direct_only = inputs;  // the reference's made-up times would fit too
    direct_only.method = "direct";
    const Plan plan = planning::plan(direct_only, {20.0, std::nullopt});
    ASSERT_TRUE(plan.meets_budget) << plan.why;
    EXPECT_EQ(plan.chosen.scale, 0.5);
    EXPECT_NEAR(plan.chosen.predicted_ms, 1e4 * 32 * 32 * 1e-6, 1e-9);
    EXPECT_DOUBLE_EQ(plan.chosen.predicted_error,
                     predict_error(analysis, "direct", plan.chosen.preset, {}).rel_mse + 0.1);
    EXPECT_NE(plan.why.find("at 1/2 size, upsampled"), std::string::npos) << plan.why;
    EXPECT_EQ(plan_json(plan)["scale"], 0.5);
    // With time for the full size, the full size: it loses nothing to upsampling.
    EXPECT_EQ(planning::plan(direct_only, {100.0, std::nullopt}).chosen.scale, 1.0);
    // A smaller frame is never a probe: its error is not its method's.
    Candidate scaled_reference = candidate("reference", "medium", {{"spp", 64}}, 100.0);
    scaled_reference.scale = 0.5;
    EXPECT_TRUE(probes(all, scaled_reference, nullptr).empty());
    // Beside a 20 ms reference only the half-size direct plans (10 ms) fit the share, and they are
    // not probed; beside a 1000 ms one the full-size plans are, and only they.
    const Candidate quick_reference = candidate("reference", "medium", {{"spp", 64}}, 20.0);
    EXPECT_TRUE(probes(all, quick_reference, nullptr).empty());
    const Candidate reference = candidate("reference", "medium", {{"spp", 64}}, 1000.0);
    const auto full_size = probes(all, reference, nullptr);
    ASSERT_FALSE(full_size.empty());
    for (const Candidate& probe : full_size) EXPECT_EQ(probe.scale, 1.0);
}

}  // namespace
}  // namespace bounce::planning
