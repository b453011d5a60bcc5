// Spot checks (renderer/planning/spot_check.hpp): the pixels drawn, the reference traced at them
// (the frame's own samples), the estimate of a frame's relMSE from them and its bound, what a check
// records for the planner, and which plans the planner checks before a reference plan.
#include "renderer/base/error.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/planning/error_model.hpp"
#include "renderer/planning/planner.hpp"
#include "renderer/planning/spot_check.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <set>

namespace bounce::planning {

// planner_test.cpp's: stopping at k bounces loses 0.1 / 2^k; one sample's relMSE is 0.5; a sample of
// k bounces takes (k + 1) microseconds.
SceneAnalysis made_up_analysis();
// planner_test.cpp's: the bench's priors with no denoised reference offered.
const OwnErrorPriors& priors_without_denoiser();

namespace {

// The box's tracer and a setting of `bounces` through pixel centres.
methods::reference::PathTracerSettings centres(int bounces) {
    methods::reference::PathTracerSettings settings;
    settings.max_bounces = bounces;
    settings.pixel_jitter = false;
    return settings;
}

TEST(SpotCheck, PixelsAreOnePerCellOfAGridShapedLikeTheFrame) {
    // 128x64 in 512 cells: a 32x16 grid of 4x4 cells.
    const std::vector<int> pixels = spot_pixels(128, 64, 512, 7);
    ASSERT_EQ(pixels.size(), 512u);
    std::set<int> cells;
    for (const int pixel : pixels) {
        ASSERT_GE(pixel, 0);
        ASSERT_LT(pixel, 128 * 64);
        cells.insert((pixel / 128 / 4) * 32 + (pixel % 128) / 4);
    }
    EXPECT_EQ(cells.size(), 512u);  // one in every cell
    EXPECT_EQ(spot_pixels(128, 64, 512, 7), pixels);
    EXPECT_NE(spot_pixels(128, 64, 512, 8), pixels);
    // As many as the frame has, or more: every pixel, once.
    const std::vector<int> all = spot_pixels(16, 8, 1024);
    ASSERT_EQ(all.size(), 128u);
    EXPECT_EQ(std::set<int>(all.begin(), all.end()).size(), 128u);
    EXPECT_THROW(spot_pixels(0, 8, 16), Error);
}

// The check's reference at a pixel is the mean of the samples a whole frame gives that pixel: its
// two halves (even and odd samples) average to the frame's value there.
TEST(SpotCheck, TracedPixelsAreTheFramesOwnSamples) {
    const scene::Scene scene = scene::make_cornell_box();
    const methods::reference::PathTracer tracer(scene);
    const methods::reference::PathTracerSettings settings = centres(2);
    const image::Frame frame = tracer.render(scene.cameras.at(0), 16, 16, 8, settings);
    const std::vector<int> pixels = {0, 37, 136, 255};
    const methods::reference::PixelEstimates traced = tracer.trace_pixels(scene.cameras.at(0), 16, 16, pixels, 8, settings);
    ASSERT_EQ(traced.pixels, pixels);
    double lit = 0.0;
    for (std::size_t i = 0; i < pixels.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            const double value = frame.rgba[static_cast<std::size_t>(pixels[i]) * 4 + c];
            EXPECT_NEAR(0.5 * (traced.mean[0][i][c] + traced.mean[1][i][c]), value, 1e-5 * std::max(1.0, value));
            EXPECT_GE(traced.variance[0][i][c], 0.0);
            lit += value;
        }
    }
    EXPECT_GT(lit, 0.0);
    EXPECT_THROW(tracer.trace_pixels(scene.cameras.at(0), 16, 16, pixels, 3, settings), InputError);
    EXPECT_THROW(tracer.trace_pixels(scene.cameras.at(0), 16, 16, {256}, 8, settings), Error);
}

// Samples traced in two goes and merged are the samples traced at once.
TEST(SpotCheck, SamplesTracedInTwoGoesMergeIntoTheSamplesTracedAtOnce) {
    const scene::Scene scene = scene::make_cornell_box();
    const methods::reference::PathTracer tracer(scene);
    const methods::reference::PathTracerSettings settings = centres(3);
    const std::vector<int> pixels = spot_pixels(24, 24, 64);
    const auto at_once = tracer.trace_pixels(scene.cameras.at(0), 24, 24, pixels, 13, settings);
    auto in_two = tracer.trace_pixels(scene.cameras.at(0), 24, 24, pixels, 5, settings);
    methods::reference::merge(in_two, tracer.trace_pixels(scene.cameras.at(0), 24, 24, pixels, 8, settings, nullptr, 5));
    EXPECT_EQ(in_two.samples, 13);
    EXPECT_EQ(in_two.half_samples[0], 7);  // samples 0, 2, ..., 12
    EXPECT_EQ(in_two.half_samples[1], 6);
    for (int half = 0; half < 2; ++half) {
        for (std::size_t i = 0; i < pixels.size(); ++i) {
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(in_two.mean[half][i][c], at_once.mean[half][i][c], 1e-9 * (1.0 + at_once.mean[half][i][c]));
                EXPECT_NEAR(in_two.variance[half][i][c], at_once.variance[half][i][c], 1e-9 * (1.0 + at_once.variance[half][i][c]));
            }
        }
    }
}

// A check's reference noisier than it was sized for traces more samples, up to kSpotMostSamples
// times its own; one quiet enough traces none.
TEST(SpotCheck, AReferenceNoisierThanItsSizeTracesMoreSamplesWithinTheCap) {
    const scene::Scene scene = scene::make_cornell_box();
    RenderRequest frame;
    frame.method = "reference";
    frame.width = frame.height = 24;
    SpotCheck check;
    check.bounces = 4;
    check.spp = 8;
    check.pixels = 256;
    check.max_noise = 1e9;
    const SpotReference quiet_enough = trace_spot_reference(scene, frame, check);
    EXPECT_EQ(quiet_enough.estimates.samples, 8);
    const double noise = noise_of(quiet_enough.estimates);
    ASSERT_GT(noise, 0.0);
    check.max_noise = noise / 2.0;
    const SpotReference doubled = trace_spot_reference(scene, frame, check);
    EXPECT_EQ(doubled.estimates.samples, 16);
    // Noise falls as 1/samples: 16's is half of 8's in expectation. Each pixel's variance comes from
    // 4 and 8 samples a half, whose spread rare bright paths widen; a bound of 0.75 still fails a
    // check that traced no more (1.0), or fewer than 12 (0.67 expected).
    EXPECT_LT(noise_of(doubled.estimates), 0.75 * noise);
    check.max_noise = noise / 100.0;
    EXPECT_EQ(trace_spot_reference(scene, frame, check).estimates.samples, kSpotMostSamples * 8);
}

// A truth frame of log-uniform values with a tenth of its pixels black, a frame that errs by 20%
// per channel, and reference halves drawn around the truth with normal noise of a known variance.
struct Synthetic {
    image::Frame truth, frame;
    double rel_mse = 0.0;
};

Synthetic synthetic_frames(int size, std::mt19937_64& random) {
    Synthetic made;
    made.truth.width = made.frame.width = size;
    made.truth.height = made.frame.height = size;
    made.truth.rgba.assign(static_cast<std::size_t>(size) * size * 4, 1.0f);
    made.frame.rgba = made.truth.rgba;
    std::uniform_real_distribution<double> log_value(-2.0, 0.0), unit(0.0, 1.0);
    std::normal_distribution<double> normal;
    for (std::size_t p = 0; p < static_cast<std::size_t>(size) * size; ++p) {
        const bool black = unit(random) < 0.1;
        for (int c = 0; c < 3; ++c) {
            const double r = black ? 0.0 : std::pow(10.0, log_value(random));
            made.truth.rgba[p * 4 + c] = static_cast<float>(r);
            made.frame.rgba[p * 4 + c] = static_cast<float>(std::max(0.0, r * (1.0 + 0.2 * normal(random)) + 0.005 * normal(random)));
        }
    }
    made.rel_mse = image::compare(made.frame, made.truth).rel_mse;
    return made;
}

// Reference halves at `pixels` whose mean has relMSE `noise` per pixel against the truth.
methods::reference::PixelEstimates noisy_reference(const image::Frame& truth, const std::vector<int>& pixels, double noise,
                                                   std::mt19937_64& random) {
    methods::reference::PixelEstimates reference;
    reference.pixels = pixels;
    reference.samples = 64;
    std::normal_distribution<double> normal;
    for (int half = 0; half < 2; ++half) {
        reference.mean[half].resize(pixels.size());
        reference.variance[half].resize(pixels.size());
        for (std::size_t i = 0; i < pixels.size(); ++i) {
            for (int c = 0; c < 3; ++c) {
                const double r = truth.rgba[static_cast<std::size_t>(pixels[i]) * 4 + c];
                const double variance = 2.0 * noise * (r * r + 0.01);  // a half has half the samples
                reference.mean[half][i][c] = r + std::sqrt(variance) * normal(random);
                reference.variance[half][i][c] = variance;
            }
        }
    }
    return reference;
}

// Over many draws of pixels and noise, the estimate plus two standard errors is at least the frame's
// relMSE in about 97.7% of draws (at least 94% here: 400 draws of a bound that holds 97.7% of the
// time fall under 94% with odds of about 1 in 1000). Where the reference's noise is small beside
// its value the estimate's mean is the frame's relMSE (within 6%: the weight's second-order
// correction leaves a bias of the order of the noise squared); where it is not (a noise of 0.1 per
// pixel, five times this frame's relMSE) the weight is left uncorrected and reads high, never low.
TEST(SpotCheck, TheEstimateIsNearlyUnbiasedAndItsBoundCoversTheFramesRelMse) {
    std::mt19937_64 random(11);
    const Synthetic made = synthetic_frames(96, random);
    ASSERT_GT(made.rel_mse, 0.01);
    for (const double noise : {0.0, 0.02, 0.1}) {
        constexpr int kDraws = 400;
        double sum = 0.0;
        int covered = 0;
        for (int draw = 0; draw < kDraws; ++draw) {
            const std::vector<int> pixels = spot_pixels(96, 96, 1024, static_cast<std::uint64_t>(draw) + 1);
            const SpotEstimate estimate = planning::estimate(made.frame, noisy_reference(made.truth, pixels, noise, random));
            ASSERT_EQ(estimate.pixels, 1024);
            sum += estimate.rel_mse;
            covered += estimate.bound >= made.rel_mse;
        }
        std::printf("noise %g: mean %.4f of %.4f (%.3f), covered %d of %d\n", noise, sum / kDraws, made.rel_mse, sum / kDraws / made.rel_mse, covered, kDraws);
        if (noise <= 0.02) {
            EXPECT_NEAR(sum / kDraws, made.rel_mse, 0.06 * made.rel_mse) << "noise " << noise;
        } else {
            EXPECT_GT(sum / kDraws, made.rel_mse) << "noise " << noise;
        }
        EXPECT_GE(covered, static_cast<int>(0.94 * kDraws)) << "noise " << noise;
    }
}

TEST(SpotCheck, EveryPixelWithoutNoiseReadsTheExactRelMse) {
    std::mt19937_64 random(3);
    const Synthetic made = synthetic_frames(24, random);
    const std::vector<int> pixels = spot_pixels(24, 24, 4096);
    const SpotEstimate estimate = planning::estimate(made.frame, noisy_reference(made.truth, pixels, 0.0, random));
    EXPECT_NEAR(estimate.rel_mse, made.rel_mse, 1e-6 * made.rel_mse);
    EXPECT_NEAR(estimate.standard_error, 0.0, 1e-12);  // nothing left to chance
    EXPECT_TRUE(estimate.passes(made.rel_mse * 1.000001));
    EXPECT_FALSE(estimate.passes(made.rel_mse * 0.99));
    // What the check's reference lacks against every bounce is added by the triangle inequality.
    const SpotEstimate lacking = planning::estimate(made.frame, noisy_reference(made.truth, pixels, 0.0, random), 0.01);
    EXPECT_NEAR(lacking.bound, std::pow(std::sqrt(made.rel_mse) + 0.1, 2.0), 1e-6);
}

TEST(SpotCheck, AFrameWithANonFinitePixelFails) {
    std::mt19937_64 random(5);
    Synthetic made = synthetic_frames(32, random);
    const std::vector<int> pixels = spot_pixels(32, 32, 256);
    made.frame.rgba[static_cast<std::size_t>(pixels[17]) * 4 + 1] = std::nanf("");
    const SpotEstimate estimate = planning::estimate(made.frame, noisy_reference(made.truth, pixels, 0.0, random));
    EXPECT_EQ(estimate.non_finite, 1);
    EXPECT_FALSE(estimate.passes(1e9));
}

// A check's reading of 1024 pixels, as estimate() would give it.
SpotEstimate reading(double rel_mse, double standard_error) {
    SpotEstimate read;
    read.rel_mse = rel_mse;
    read.standard_error = standard_error;
    read.pixels = 1024;
    return read;
}

// A check is recorded as a comparison would be: the safe side of what it read, less the light of the
// bounces the check's reference has beyond the plan's; not where that light is most of it, nor for a
// plan of more bounces than the check.
TEST(SpotCheck, WhatACheckReadsIsRecordedAsThePlansOwnError) {
    const std::vector<double> stopped = {0.08, 0.02, 0.005, 0.0};
    SpotCheck check;
    check.bounces = 3;
    SpotEstimate read = reading(0.05, 0.005);
    SceneMeasurements measured;
    record_spot_check(measured, stopped, "cssm", "low", {{"bounces", 2}}, check, read);
    const auto own = measured.own_error("cssm", "low", 2);
    ASSERT_TRUE(own.has_value());
    EXPECT_NEAR(own->rel_mse, 0.05 + kSpotConfidence * 0.005 - 0.005, 1e-12);
    EXPECT_TRUE(measured.compared("cssm", "low"));
    // vct at one bounce lacks 0.02 of light the check has: over half of 0.03, not recorded.
    read.rel_mse = 0.03;
    record_spot_check(measured, stopped, "vct", "high", {}, check, read);
    EXPECT_FALSE(measured.own_error("vct", "high", 1).has_value());
    // cssm at 6 bounces against a check of 3: the check lacks light the plan has.
    record_spot_check(measured, stopped, "cssm", "high", {{"bounces", 6}}, check, read);
    EXPECT_FALSE(measured.own_error("cssm", "high", 6).has_value());
}

// A check of a view's frame is an estimate of that frame: a later bound on the same view, from a
// reference lacking light the frame has, does not raise it (the indirectly lit Cornell box: cssm
// draft at 8 bounces checked at 0.038, then bounded at 0.89 against a one-bounce reference, and the
// bound priced it out of every time budget). A bound of another view still counts, and so does one
// where the check was filed under no view.
TEST(SpotCheck, ACheckOfAViewIsNotRaisedByThatViewsBounds) {
    const std::vector<double> stopped = {0.5, 0.14, 0.035, 0.004, 0.0005, 0.0};
    SpotCheck check;
    check.bounces = 5;
    const SpotEstimate read = reading(0.02, 0.004);
    const double checked = 0.02 + kSpotConfidence * 0.004;  // the plan and the check both lack nothing to speak of
    SceneMeasurements measured;
    record_spot_check(measured, stopped, "cssm", "draft", {{"bounces", 5}}, check, read, /*view=*/7);
    ASSERT_TRUE(measured.own_error("cssm", "draft", 5).has_value());
    EXPECT_NEAR(measured.own_error("cssm", "draft", 5)->rel_mse, checked, 1e-12);
    measured.record_own_error("cssm", "draft", 5, 0.89, /*bound_of_view=*/7);
    EXPECT_NEAR(measured.own_error("cssm", "draft", 5)->rel_mse, checked, 1e-12);
    measured.record_own_error("cssm", "draft", 5, 0.3, /*bound_of_view=*/8);
    EXPECT_NEAR(measured.own_error("cssm", "draft", 5)->rel_mse, 0.3, 1e-12);
    // A check reads the frame against every bounce: a comparison of the view that measured a cross
    // term against a deeper frame does not add it to the check's reading, before or after it.
    for (const bool comparison_first : {true, false}) {
        SCOPED_TRACE(comparison_first ? "the comparison first" : "the check first");
        SceneMeasurements crossed;
        const auto compared = [&] { crossed.record_own_estimate("cssm", "draft", 5, 0.01, 7, 0.05, 0.0, -0.03); };
        if (comparison_first) compared();
        record_spot_check(crossed, stopped, "cssm", "draft", {{"bounces", 5}}, check, read, /*view=*/7);
        if (!comparison_first) compared();
        EXPECT_NEAR(crossed.own_error("cssm", "draft", 5)->rel_mse, checked, 1e-12);  // it took out less
    }

    SceneMeasurements unfiled;
    record_spot_check(unfiled, stopped, "cssm", "draft", {{"bounces", 5}}, check, read);
    unfiled.record_own_error("cssm", "draft", 5, 0.89, /*bound_of_view=*/7);
    EXPECT_NEAR(unfiled.own_error("cssm", "draft", 5)->rel_mse, 0.89, 1e-12);
}
// What a failed try recorded rules out the plans the planner would no longer offer: the preset at
// fewer bounces (its own error read from the count measured above it), not another preset, and not
// where what was read leaves room under the target.
TEST(SpotCheck, AFailedTryRulesOutThePresetAtFewerBouncesAndNothingElse) {
    const SceneAnalysis analysis = made_up_analysis();  // 8 bounces lack 0.1 / 256, 6 lack 0.1 / 64
    SpotCheck check;
    check.bounces = 12;
    SceneMeasurements measured;
    EXPECT_FALSE(ruled_out_by_measurements(measured, analysis, "cssm", "draft", {{"bounces", 6}}, 0.05));  // nothing read
    record_spot_check(measured, analysis.bounces.stopped_error, "cssm", "draft", {{"bounces", 8}}, check, reading(0.10, 0.02));
    EXPECT_TRUE(ruled_out_by_measurements(measured, analysis, "cssm", "draft", {{"bounces", 8}}, 0.05));
    EXPECT_TRUE(ruled_out_by_measurements(measured, analysis, "cssm", "draft", {{"bounces", 6}}, 0.05));
    EXPECT_FALSE(ruled_out_by_measurements(measured, analysis, "cssm", "low", {{"bounces", 6}}, 0.05));
    EXPECT_FALSE(ruled_out_by_measurements(measured, analysis, "cssm", "draft", {{"bounces", 6}}, 0.2));
    // Read well under the target: the preset at fewer bounces stays to try.
    SceneMeasurements passed;
    record_spot_check(passed, analysis.bounces.stopped_error, "cssm", "draft", {{"bounces", 8}}, check, reading(0.01, 0.002));
    EXPECT_FALSE(ruled_out_by_measurements(passed, analysis, "cssm", "draft", {{"bounces", 6}}, 0.05));
    // Estimated under the target by a comparison that took noise out, promised over it: ruled out
    // (a target is judged by the promise).
    SceneMeasurements unsure;
    unsure.record_own_estimate("cssm", "draft", 8, 0.02, 1, 0.03, 0.03);
    ASSERT_LT(predict_error(analysis, "cssm", "draft", {{"bounces", 8}}, &unsure).rel_mse, 0.05);
    EXPECT_TRUE(ruled_out_by_measurements(unsure, analysis, "cssm", "draft", {{"bounces", 8}}, 0.05));
    EXPECT_FALSE(ruled_out_by_measurements(unsure, analysis, "cssm", "draft", {{"bounces", 8}}, 0.06));
}

DeviceCosts costs_for_checks() {
    DeviceCosts device("test");
    for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) {
        device.set("direct", preset, {1.0, 0.0});
        device.set("vct", preset, {20.0, 0.0});
        device.set("isr", preset, {30.0, 0.0});
        device.set("cssm", preset, {5.0, 0.0});
    }
    return device;
}

// At 0.02 no GPU plan is promised (their bench priors are the largest the corpus measured, 0.0265
// and up), so the reference is the plan; GPU plans whose typical own error with the light their
// bounces lack fits 0.02 are checked first, cheapest first, within the reference's time.
TEST(Planner, ATargetErrorTriesPlausibleGpuPlansWithASpotCheckBeforeTheReference) {
    const SceneAnalysis analysis = made_up_analysis();
    const DeviceCosts device = costs_for_checks();
    PlanningInputs inputs{analysis, device, nullptr, 128, 128, std::nullopt};
    inputs.priors = &priors_without_denoiser();  // a denoised reference would be the plan, and none is checked beside it
    constexpr double kTarget = 0.02;
    const Plan plan = planning::plan(inputs, {std::nullopt, kTarget});
    ASSERT_EQ(plan.chosen.method, "reference");
    ASSERT_TRUE(plan.spot_check.has_value()) << plan.why;  // the check and cssm fit its time at 128x128
    ASSERT_FALSE(plan.checks.empty());
    EXPECT_EQ(plan.spot_check->bounces, 12);  // lacks nothing
    EXPECT_EQ(plan.spot_check->pixels, kSpotPixels);
    EXPECT_EQ(plan.spot_check->spp, 10);  // 0.5 x 20
    EXPECT_DOUBLE_EQ(plan.spot_check->max_noise, 2.0 * kSpotMaxNoise);
    double total = plan.spot_check->predicted_ms;
    double previous = 0.0;
    for (const Candidate& c : plan.checks) {
        EXPECT_NE(c.method, "reference");
        EXPECT_EQ(c.scale, 1.0);
        const int bounces = modelled_bounces(c.method, c.knobs);
        EXPECT_LE(*typical_own_error(c.method, c.preset, bounces) + analysis.bounces.stopped_error[bounces], kTarget)
            << c.method << " " << c.preset;
        EXPECT_GE(c.predicted_ms, previous);
        previous = c.predicted_ms;
        total += c.predicted_ms;
    }
    EXPECT_LE(total, kCheckShare * plan.chosen.predicted_ms);
    // The cheapest plausible plan is the first tried.
    const std::vector<Candidate> all = candidates(inputs);
    for (const Candidate& c : all) {
        if (c.method == "reference" || c.scale != 1.0) continue;
        const int bounces = modelled_bounces(c.method, c.knobs);
        const auto typical = typical_own_error(c.method, c.preset, bounces);
        if (typical && *typical + analysis.bounces.stopped_error[bounces] <= kTarget) {
            EXPECT_GE(c.predicted_ms, plan.checks.front().predicted_ms) << c.method << " " << c.preset;
        }
    }
    EXPECT_NE(plan.why.find("spot-checked"), std::string::npos) << plan.why;

    // None with a time limit too (a failed check and its reference would not keep it), none where a
    // GPU plan is chosen, and a plan whose own error the scene measured is not checked again.
    EXPECT_FALSE(planning::plan(inputs, {1e6, 0.05}).spot_check.has_value());
    EXPECT_FALSE(planning::plan(inputs, {std::nullopt, 0.5}).spot_check.has_value());
    SceneMeasurements measured;
    const Candidate first = plan.checks.front();
    measured.record_own_error(first.method, first.preset, modelled_bounces(first.method, first.knobs), 0.2);
    PlanningInputs with_measured{analysis, device, &measured, 128, 128, std::nullopt};
    with_measured.priors = inputs.priors;
    const Plan again = planning::plan(with_measured, {std::nullopt, 0.05});
    ASSERT_FALSE(again.checks.empty()) << again.why;
    for (const Candidate& c : again.checks) EXPECT_FALSE(c.method == first.method && c.preset == first.preset && c.knobs == first.knobs);
    // Nor the preset at fewer bounces: its own error reads from the count measured above it.
    const int first_bounces = modelled_bounces(first.method, first.knobs);
    for (const Candidate& c : again.checks) {
        EXPECT_FALSE(c.method == first.method && c.preset == first.preset && modelled_bounces(c.method, c.knobs) <= first_bounces)
            << c.method << " " << c.preset << " at " << modelled_bounces(c.method, c.knobs);
    }
}

// A spot check expects of vct, where its preset leaks, what the bench's leaking scenes measured
// (OwnErrorPriors::vct_leaking_typical), not the corpus' median: a plan expected to fit the target
// elsewhere is not traced where its walls leak.
TEST(Planner, ASpotCheckExpectsOfLeakingVctWhatLeakingScenesMeasured) {
    SceneAnalysis analysis = made_up_analysis();
    const DeviceCosts device = costs_for_checks();
    OwnErrorPriors priors = priors_without_denoiser();
    for (auto& [key, largest] : priors.largest) largest = 1.0;  // nothing promised: the reference is the plan
    for (auto& [preset, largest] : priors.vct_second_largest) largest = 1.0;
    priors.vct_second_typical["draft"] = 0.001;  // with the 0.025 that 2 bounces lack, within 0.05
    PlanningInputs inputs{analysis, device, nullptr, 128, 128, std::nullopt};
    inputs.priors = &priors;
    const auto checks_vct_draft = [&](const PlanningInputs& in) {
        const Plan plan = planning::plan(in, {std::nullopt, 0.05});
        EXPECT_EQ(plan.chosen.method, "reference") << plan.why;
        return std::any_of(plan.checks.begin(), plan.checks.end(),
                           [](const Candidate& c) { return c.method == "vct" && c.preset == "draft"; });
    };
    EXPECT_TRUE(checks_vct_draft(inputs));
    analysis.thin_walls.presets["draft"].leaking_area = 0.2;
    ASSERT_GT(priors.vct_second_leaking_typical.at("draft") + 0.025, 0.05);
    EXPECT_FALSE(checks_vct_draft(inputs));
}

}  // namespace
}  // namespace bounce::planning
