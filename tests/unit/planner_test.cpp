// The planner on tables: for a target error it picks the cheapest plan predicted to meet it, for a
// time budget never one predicted over it (checked on random tables against every candidate), and
// it says so when nothing fits. The error model's arithmetic, the cost lines, the cache file and the
// scene's measured ratios.
#include "renderer/base/error.hpp"
#include "renderer/methods/registry.hpp"
#include "renderer/planning/costs.hpp"
#include "renderer/planning/error_model.hpp"
#include "renderer/planning/plan_order.hpp"
#include "renderer/planning/planner.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>

namespace bounce::planning {
namespace {

Candidate plan_of(std::string method, double ms, double error) {
    return {std::move(method), "medium", {}, ms, error, "table", "table"};
}

std::vector<Candidate> random_table(std::mt19937& random) {
    std::uniform_real_distribution<double> log_ms(0.0, 4.0), log_error(-3.0, 0.0);
    std::uniform_real_distribution<double> unsure(1.0, 3.0);
    std::vector<Candidate> table(1 + random() % 40);
    for (std::size_t i = 0; i < table.size(); ++i) {
        table[i] = plan_of("plan" + std::to_string(i), std::pow(10.0, log_ms(random)), std::pow(10.0, log_error(random)));
        // Half of them measured against noisy references: promised up to three times the estimate.
        if (random() % 2 == 0) table[i].promised_error = table[i].predicted_error * unsure(random);
    }
    return table;
}

TEST(Planner, ForATargetErrorItPicksTheCheapestPlanPredictedToMeetIt) {
    std::mt19937 random(7);
    int met = 0, unmet = 0, tied = 0, unsure_only = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const std::vector<Candidate> table = random_table(random);
        const double target = std::pow(10.0, std::uniform_real_distribution<double>(-3.0, 0.0)(random));
        const Plan plan = choose(table, {std::nullopt, target});
        double least_ms = std::numeric_limits<double>::infinity();
        for (const Candidate& c : table) {
            if (promised_error(c) <= target) least_ms = std::min(least_ms, c.predicted_ms);
            if (c.predicted_error <= target && promised_error(c) > target) ++unsure_only;
        }
        const bool any = std::isfinite(least_ms);
        EXPECT_EQ(plan.meets_budget, any);
        if (any) {
            ++met;
            // What a target is judged by is the promise, never only the estimate.
            EXPECT_LE(promised_error(plan.chosen), target);
            // The cheapest, or a plan priced alike with it (kPriceTie) and the most accurate of those.
            EXPECT_LE(plan.chosen.predicted_ms, kPriceTie * least_ms);
            if (plan.chosen.predicted_ms > least_ms) ++tied;
            for (const Candidate& c : table) {
                if (promised_error(c) > target || c.predicted_ms > kPriceTie * least_ms) continue;
                EXPECT_GE(c.predicted_error, plan.chosen.predicted_error) << c.method << " is priced alike and more accurate";
            }
        } else {
            ++unmet;
            // Nothing is promised within it: the least promised, and the reply says so.
            for (const Candidate& c : table) EXPECT_GE(promised_error(c), promised_error(plan.chosen));
            EXPECT_NE(plan.why.find("no plan is promised within"), std::string::npos) << plan.why;
        }
    }
    EXPECT_GT(met, 100);  // both branches were exercised
    EXPECT_GT(unmet, 100);
    EXPECT_GT(tied, 10);  // and the tie changed the choice
    EXPECT_GT(unsure_only, 100);  // plans estimated within the target but not promised it were in the tables
}

TEST(Planner, ForATimeBudgetItNeverPicksAPlanPredictedOverIt) {
    std::mt19937 random(11);
    int met = 0, unmet = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const std::vector<Candidate> table = random_table(random);
        const double budget = std::pow(10.0, std::uniform_real_distribution<double>(0.0, 4.0)(random));
        const Plan plan = choose(table, {budget, std::nullopt});
        bool any = false;
        for (const Candidate& c : table) {
            if (c.predicted_ms > budget) continue;
            any = true;
            EXPECT_GE(c.predicted_error, plan.chosen.predicted_error) << c.method << " is more accurate within " << budget;
        }
        EXPECT_EQ(plan.meets_budget, any);
        if (any) {
            ++met;
            EXPECT_LE(plan.chosen.predicted_ms, budget);
        } else {
            ++unmet;
            for (const Candidate& c : table) EXPECT_GE(c.predicted_ms, plan.chosen.predicted_ms);  // the fastest
        }
    }
    EXPECT_GT(met, 100);
    EXPECT_GT(unmet, 100);
}

TEST(Planner, WithBothLimitsTheTimeBudgetIsKept) {
    const std::vector<Candidate> table = {plan_of("fast_rough", 10, 0.2), plan_of("mid", 40, 0.08),
                                          plan_of("slow_fine", 400, 0.01)};
    EXPECT_EQ(choose(table, {100.0, 0.1}).chosen.method, "mid");  // the fastest meeting both
    const Plan tight = choose(table, {100.0, 0.02});                // none meets both: the best within 100 ms
    EXPECT_EQ(tight.chosen.method, "mid");
    EXPECT_FALSE(tight.meets_budget);
    EXPECT_EQ(choose(table, {5.0, 0.02}).chosen.method, "fast_rough");  // nothing within 5 ms: the fastest
}

// A target error is judged by what a plan is promised (Candidate::promised_error: its estimate with
// the reference noise its comparisons took out counted back), a time budget ranks by the estimate:
// the glossy box's vct draft at 2 bounces, estimated 0.096 and promised 0.104, measured 0.103.
TEST(Planner, ATargetIsJudgedByThePromiseATimeBudgetByTheEstimate) {
    std::vector<Candidate> table = {plan_of("vct_draft", 54, 0.096), plan_of("isr_draft", 96, 0.094),
                                    plan_of("reference", 230, 0.092)};
    table[0].promised_error = 0.104;
    const Plan target = choose(table, {std::nullopt, 0.1});
    EXPECT_EQ(target.chosen.method, "isr_draft");
    EXPECT_TRUE(target.meets_budget);
    // Promised within the target, it is taken again.
    std::vector<Candidate> surer = table;
    surer[0].promised_error = 0.099;
    EXPECT_EQ(choose(surer, {std::nullopt, 0.1}).chosen.method, "vct_draft");
    // Within 60 ms and 0.1 nothing is promised both: the most accurate within 60 ms, saying so.
    const Plan both = choose(table, {60.0, 0.1});
    EXPECT_EQ(both.chosen.method, "vct_draft");
    EXPECT_FALSE(both.meets_budget);
    // A time budget ranks by the estimates: isr draft's 0.094 over the reference's 0.092 past 100 ms.
    EXPECT_EQ(choose(table, {100.0, std::nullopt}).chosen.method, "isr_draft");
    table[1].predicted_error = 0.097;
    EXPECT_EQ(choose(table, {100.0, std::nullopt}).chosen.method, "vct_draft");
    // A promise under its estimate is no promise: the estimate stands.
    std::vector<Candidate> under = {plan_of("fast", 10, 0.12), plan_of("slow", 50, 0.09)};
    under[0].promised_error = 0.05;
    EXPECT_EQ(choose(under, {std::nullopt, 0.1}).chosen.method, "slow");
    EXPECT_DOUBLE_EQ(promised_error(under[0]), 0.12);
    // The reply carries both.
    EXPECT_DOUBLE_EQ(plan_json(target)["promised_error"].get<double>(), 0.094);
    EXPECT_DOUBLE_EQ(plan_json(choose(surer, {std::nullopt, 0.1}))["promised_error"].get<double>(), 0.099);
    EXPECT_DOUBLE_EQ(plan_json(choose(surer, {std::nullopt, 0.1}))["predicted_error"].get<double>(), 0.096);
    // Nothing promised within the target: the least promised (the reference, estimated 0.098), not
    // the least estimate (vct draft's 0.096, promised 0.104); the reply says so.
    table[1].predicted_error = 0.1;
    table[2].predicted_error = 0.098;
    const Plan none = choose(table, {std::nullopt, 0.05});
    EXPECT_FALSE(none.meets_budget);
    EXPECT_EQ(none.chosen.method, "reference");
    EXPECT_NE(none.why.find("no plan is promised within relMSE 0.05: the least promised"), std::string::npos) << none.why;
}

TEST(Planner, ATargetErrorRacesExpectedPricesAmongBoundsWithinTheSlack) {
    // A GPU plan priced by a bound on bounces not measured (120 ms) and expected at 60 beats the
    // reference's 100; one expected cheaper still but bound past 1.5 x 100 does not.
    Candidate bounded = plan_of("bounded", 120, 0.05);
    bounded.expected_ms = 60;
    Candidate loose = plan_of("loose", 151, 0.05);
    loose.expected_ms = 10;
    const std::vector<Candidate> table = {plan_of("reference", 100, 0.09), bounded, loose, plan_of("rough", 5, 0.2)};
    const Plan plan = choose(table, {std::nullopt, 0.1});
    EXPECT_EQ(plan.chosen.method, "bounded") << plan.why;
    EXPECT_TRUE(plan.meets_budget);
    EXPECT_NE(plan.why.find("expected price"), std::string::npos) << plan.why;
    EXPECT_NE(plan.why.find("reference"), std::string::npos) << plan.why;  // the plan the bounds chose is named
    // A time budget is a promise: the bounds decide, with a target error or without.
    EXPECT_EQ(choose(table, {110.0, 0.1}).chosen.method, "reference");
    EXPECT_EQ(choose(table, {1000.0, std::nullopt}).chosen.method, "bounded");  // the most accurate within it (tie: faster)
    EXPECT_EQ(plan_json(plan)["expected_ms"].get<double>(), 60.0);
    EXPECT_EQ(plan_json(plan)["predicted_ms"].get<double>(), 120.0);

    // On random tables: the chosen plan's bound is within the slack of the least bound within E, and
    // no plan so bounded within E is expected cheaper.
    std::mt19937 random(13);
    int raced = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        std::vector<Candidate> priced = random_table(random);
        for (Candidate& c : priced) {
            if (random() % 2) c.expected_ms = c.predicted_ms * std::uniform_real_distribution<double>(0.3, 1.0)(random);
        }
        const double target = std::pow(10.0, std::uniform_real_distribution<double>(-3.0, 0.0)(random));
        const Plan chosen = choose(priced, {std::nullopt, target});
        if (!chosen.meets_budget) continue;
        double least_bound = std::numeric_limits<double>::infinity();
        for (const Candidate& c : priced) {
            if (promised_error(c) <= target) least_bound = std::min(least_bound, c.predicted_ms);
        }
        EXPECT_LE(promised_error(chosen.chosen), target);
        EXPECT_LE(chosen.chosen.predicted_ms, kTargetTimeSlack * least_bound);
        const auto expected = [](const Candidate& c) { return c.expected_ms.value_or(c.predicted_ms); };
        double least_expected = std::numeric_limits<double>::infinity();
        for (const Candidate& c : priced) {
            if (promised_error(c) > target || c.predicted_ms > kTargetTimeSlack * least_bound) continue;
            least_expected = std::min(least_expected, expected(c));
        }
        // The race's winner, or the most accurate of the raced plans priced alike with it.
        EXPECT_LE(expected(chosen.chosen), kPriceTie * least_expected);
        for (const Candidate& c : priced) {
            if (promised_error(c) > target || c.predicted_ms > kTargetTimeSlack * least_bound) continue;
            if (expected(c) <= kPriceTie * least_expected) {
                EXPECT_GE(c.predicted_error, chosen.chosen.predicted_error) << c.method;
            }
        }
        if (chosen.chosen.predicted_ms > least_bound) ++raced;
    }
    EXPECT_GT(raced, 50);  // the expected prices changed the choice in some trials
}

TEST(Planner, OfPlansPricedAlikeForATargetTheMoreAccurateIsTaken) {
    // The street's first budget of 0.05: a 6-sample reference at 25.3 ms predicted 0.043, isr draft
    // at 26 ms predicted 0.038 from its prior. Within kPriceTie (5%) the cost model cannot tell
    // them apart, so the one with margin on the target is taken.
    const Candidate reference = plan_of("reference", 25.26, 0.043);
    const std::vector<Candidate> alike = {reference, plan_of("isr", 26.0, 0.038), plan_of("rough", 5, 0.2)};
    const Plan plan = choose(alike, {std::nullopt, 0.05});
    EXPECT_EQ(plan.chosen.method, "isr") << plan.why;
    EXPECT_TRUE(plan.meets_budget);
    EXPECT_NE(plan.why.find("most accurate of those priced within 1.05x"), std::string::npos) << plan.why;
    EXPECT_NE(plan.why.find("reference"), std::string::npos) << plan.why;  // the cheapest is named
    // Past the tie (6.9% dearer) the cheapest is taken.
    EXPECT_EQ(choose({reference, plan_of("isr", 27.0, 0.038)}, {std::nullopt, 0.05}).chosen.method, "reference");
    // With a time budget too: the tie counts bounds, and never crosses the budget.
    EXPECT_EQ(choose(alike, {30.0, 0.05}).chosen.method, "isr");
    EXPECT_EQ(choose(alike, {25.5, 0.05}).chosen.method, "reference");
    // A plan over the target is never taken for its price, however accurate.
    EXPECT_EQ(choose({reference, plan_of("isr", 25.0, 0.06)}, {std::nullopt, 0.05}).chosen.method, "reference");
    // The tie is with the race's winner at its expected price: a bounded plan expected at 60 ties
    // with one at 62 that is more accurate, not with the reference whose bound (100) lost the race.
    Candidate bounded = plan_of("bounded", 120, 0.05);
    bounded.expected_ms = 60;
    Candidate alike_bounded = plan_of("alike_bounded", 125, 0.04);
    alike_bounded.expected_ms = 62;
    const Plan raced = choose({plan_of("reference", 100, 0.03), bounded, alike_bounded}, {std::nullopt, 0.1});
    EXPECT_EQ(raced.chosen.method, "alike_bounded") << raced.why;
    EXPECT_NE(raced.why.find("expected price"), std::string::npos) << raced.why;
}

TEST(Planner, AnEmptyTableOrABudgetWithoutLimitsIsRefused) {
    EXPECT_THROW(choose({}, {10.0, std::nullopt}), InputError);
    EXPECT_THROW(choose({plan_of("a", 1, 1)}, {}), InputError);
}

}  // namespace

// The bench's priors without the denoiser's bound: no denoised reference is offered, for tests of
// what the plain reference and the GPU plans do (spot_check_test.cpp takes it too).
const OwnErrorPriors& priors_without_denoiser() {
    static const OwnErrorPriors priors = [] {
        OwnErrorPriors without = OwnErrorPriors::bench();
        without.denoised_largest = 0.0;
        return without;
    }();
    return priors;
}

// An analysis made up for the arithmetic (spot_check_test.cpp takes it too): stopping at k bounces loses 0.1 / 2^k, and one sample of
// the reference has relMSE 0.5 at every bounce count.
SceneAnalysis made_up_analysis() {
    SceneAnalysis analysis;
    for (int k = 0; k <= 12; ++k) {
        analysis.bounces.stopped_error.push_back(k == 12 ? 0.0 : 0.1 / std::pow(2.0, k));
        analysis.bounces.noise_per_sample.push_back(0.5);
        analysis.bounces.sample_ns.push_back(1000.0 * (k + 1));
    }
    analysis.bounces.tracer_build_ms = 2.0;
    for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) analysis.thin_walls.presets[preset] = {0.1, 0.0};
    return analysis;
}

namespace {

// A denoised reference (`denoise` 1) lacks its missing bounces plus what the filter leaves of its
// noise n, and adds: promised the bench's bound, k n^0.7 (bench/denoise --every-scene), at the
// samples that bound was measured at alone (4 to 64); without a bound, none is offered. Its price is
// the trace's plus the filter's per pixel (the bench's, until the scene's frames time it), and no
// frame is compared with it: no probe, no spot check.
TEST(Planner, ADenoisedReferenceIsPromisedTheBenchsBoundOfWhatTheFilterLeaves) {
    const SceneAnalysis analysis = made_up_analysis();
    const methods::KnobValues knobs = {{"spp", 16}, {"bounces", 4}, {"pixel_jitter", 0}, {"denoise", 1}};
    const ErrorPrediction filtered = predict_error(analysis, "reference", "medium", knobs);
    ASSERT_FALSE(filtered.ruled_out);
    const double k = OwnErrorPriors::bench().denoised_largest;
    EXPECT_GT(k, 0.0);
    // Added to what the bounces lack as errors of one sign add: the filter darkens, as they do.
    EXPECT_DOUBLE_EQ(filtered.rel_mse,
                     std::pow(std::sqrt(0.1 / 16.0) + std::sqrt(k * std::pow(0.5 / 16.0, kDenoisedNoiseExponent)), 2.0));
    EXPECT_DOUBLE_EQ(filtered.promised_rel_mse, filtered.rel_mse);
    EXPECT_LT(filtered.rel_mse, 0.1 / 16.0 + 0.5 / 16.0);
    EXPECT_NE(filtered.basis.find("denoised"), std::string::npos) << filtered.basis;
    EXPECT_TRUE(predict_error(analysis, "reference", "medium", knobs, nullptr, priors_without_denoiser()).ruled_out);

    DeviceCosts device("test");
    SceneMeasurements scene;
    PlanningInputs inputs{analysis, device, &scene, 128, 128, std::nullopt};
    methods::KnobValues plain = knobs;
    plain.erase("denoise");
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "reference", "medium", knobs),
                     predicted_ms(inputs, "reference", "medium", plain) + 128.0 * 128.0 * kDenoiseMsPerPixel);
    // A denoised frame recorded: its filter prices the next, and its trace is kept without it.
    FrameStats frame;
    frame.method = "reference";
    frame.preset = "medium";
    frame.knobs = knobs;
    frame.render_ms = 30.0;
    frame.method_statistics = {{"denoise_ms", 8.192}, {"noise_per_sample", 0.5}};
    record_frame(scene, &analysis, device, frame, 128, 128);
    ASSERT_TRUE(scene.denoise_ms_per_pixel());
    EXPECT_DOUBLE_EQ(*scene.denoise_ms_per_pixel(), 8.192 / 16384.0);
    const auto traces = scene.frames("reference", "medium", 4);
    ASSERT_EQ(traces.size(), 1u);
    EXPECT_NEAR(traces.front().measured_ms, 30.0 - 8.192, 1e-9);
    EXPECT_NEAR(predicted_ms(inputs, "reference", "medium", knobs) - predicted_ms(inputs, "reference", "medium", plain),
                8.192, 1e-9);

    std::set<int> offered;
    for (const Candidate& c : candidates(inputs)) {
        if (denoised(c)) offered.insert(static_cast<int>(c.knobs.at("spp")));
    }
    ASSERT_FALSE(offered.empty());
    EXPECT_EQ(*offered.begin(), kDenoisedLeastSpp);
    EXPECT_EQ(*offered.rbegin(), kDenoisedMostSpp);
    inputs.priors = &priors_without_denoiser();
    for (const Candidate& c : candidates(inputs)) EXPECT_FALSE(denoised(c)) << describe(c);
    inputs.priors = nullptr;
    // Nor in a frame smaller than the bound was measured in.
    inputs.height = kDenoisedLeastSide - 1;
    for (const Candidate& c : candidates(inputs)) EXPECT_FALSE(denoised(c)) << describe(c);
    inputs.height = 128;

    // GPU plans at 5 ms, none promised within 0.02 (their priors and the bounces they lack): a target
    // takes the denoised reference, the cheapest promised, with nothing probed beside it, where the
    // plain reference it replaces had GPU presets probed beside it.
    for (const char* method : {"direct", "vct", "isr", "cssm"}) {
        for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) device.set(method, preset, {5.0, 0.0});
    }
    const Plan target = plan(inputs, {std::nullopt, 0.02});
    ASSERT_TRUE(denoised(target.chosen)) << target.why;
    EXPECT_LE(target.chosen.predicted_error, 0.02);
    EXPECT_TRUE(target.probes.empty());
    // GPU plans the bench's typical errors put within 0.02 are still spot-checked first: the check
    // traces its own reference, not the denoised frame.
    ASSERT_TRUE(target.spot_check.has_value()) << target.why;
    EXPECT_FALSE(target.checks.empty());
    EXPECT_EQ(plan_json(target)["knobs"]["denoise"].get<double>(), 1.0);
    // The same frame undenoised costs more samples: the target's plain plan is slower.
    inputs.priors = &priors_without_denoiser();
    const Plan unfiltered = plan(inputs, {std::nullopt, 0.02});
    ASSERT_EQ(unfiltered.chosen.method, "reference") << unfiltered.why;
    EXPECT_FALSE(denoised(unfiltered.chosen));
    EXPECT_GT(unfiltered.chosen.predicted_ms, target.chosen.predicted_ms) << unfiltered.why;
    EXPECT_FALSE(unfiltered.probes.empty()) << unfiltered.why;
}

// A probe that lacks bounces is measured beside a companion reference of its own bounce count; a
// denoised reference, compared with nothing, is never one, however cheap and quiet it is predicted.
TEST(Planner, AProbesCompanionIsNeverADenoisedReference) {
    const SceneAnalysis analysis = made_up_analysis();  // one bounce lacks 0.05, eight 0.0004
    const auto reference = [&](int bounces, int spp, bool filtered, double ms, double error) {
        Candidate c{"reference", "medium", reference_knobs(spp, bounces), ms, error};
        if (filtered) c.knobs["denoise"] = 1;
        return c;
    };
    const Candidate chosen = reference(8, 64, false, 1000.0, 0.1 / 256.0 + 0.5 / 64.0);
    const Candidate isr{"isr", "draft", {}, 10.0, 0.05 + 0.028};  // its own 0.028 drowned by the 0.05 it lacks
    const Candidate plain = reference(1, 64, false, 100.0, 0.05 + 0.5 / 64.0);
    const Candidate filtered = reference(1, 16, true, 30.0, 0.05 + 0.001);
    const std::vector<Candidate> all = {chosen, isr, plain, filtered};
    const std::vector<Candidate> probed = probes(all, chosen, nullptr, &analysis, 0);
    ASSERT_EQ(probed.size(), 2u);
    EXPECT_EQ(probed[0].method, "isr");
    EXPECT_EQ(probed[1].knobs, plain.knobs);
    // Beside a denoised reference chosen, nothing is probed: no frame is compared with it.
    EXPECT_TRUE(probes(all, reference(8, 16, true, 1000.0, 0.01), nullptr, &analysis, 0).empty());
}

TEST(ErrorModel, TheReferenceLacksItsMissingBouncesPlusNoiseOverItsSamples) {
    const SceneAnalysis analysis = made_up_analysis();
    const ErrorPrediction at_64 = predict_error(analysis, "reference", "medium", {{"spp", 64}, {"bounces", 3}});
    EXPECT_DOUBLE_EQ(at_64.rel_mse, 0.1 / 8.0 + 0.5 / 64.0);
    // Frames that measured three times the analysis' noise at 4 bounces raise it at 3 (the nearest).
    SceneMeasurements measured;
    measured.record_noise(4, 3.0, 64);
    EXPECT_DOUBLE_EQ(predict_error(analysis, "reference", "medium", {{"spp", 64}, {"bounces", 3}}, &measured).rel_mse,
                     0.1 / 8.0 + 3.0 * 0.5 / 64.0);
    // A measured ratio under 1 lowers it as much: the view's statistic replaces the analysis' either way.
    SceneMeasurements quieter;
    quieter.record_noise(3, 0.5, 64);
    EXPECT_DOUBLE_EQ(predict_error(analysis, "reference", "medium", {{"spp", 64}, {"bounces", 3}}, &quieter).rel_mse,
                     0.1 / 8.0 + 0.5 * 0.5 / 64.0);
    // Where the analysis has the noise against its frame of every bounce, a prediction (what a target
    // is measured by) takes it; what a comparison with the frame itself takes out stays its own.
    SceneAnalysis brighter = analysis;
    brighter.bounces.noise_against_whole.assign(13, 0.2);
    EXPECT_DOUBLE_EQ(predict_error(brighter, "reference", "medium", {{"spp", 64}, {"bounces", 3}}).rel_mse,
                     0.1 / 8.0 + 0.2 / 64.0);
    EXPECT_DOUBLE_EQ(reference_noise(brighter, 3, 64, &quieter, NoiseAgainst::every_bounce).rel_mse, 0.5 * 0.2 / 64.0);
    EXPECT_DOUBLE_EQ(reference_noise(brighter, 3, 64, &quieter, NoiseAgainst::own_frame).rel_mse, 0.5 * 0.5 / 64.0);
}

TEST(ErrorModel, AGpuMethodAddsItsBenchPriorToTheBouncesItLacks) {
    const SceneAnalysis analysis = made_up_analysis();
    const double prior = *own_error_prior("cssm", "low");
    EXPECT_DOUBLE_EQ(predict_error(analysis, "cssm", "low", {{"bounces", 2}}).rel_mse, 0.1 / 4.0 + prior);
    EXPECT_DOUBLE_EQ(predict_error(analysis, "vct", "high", {}).rel_mse, 0.1 / 2.0 + *own_error_prior("vct", "high"));
    EXPECT_DOUBLE_EQ(predict_error(analysis, "direct", "ultra", {}).rel_mse, 0.1 + *own_error_prior("direct", "ultra"));
}

// The plan's basis says how the frame will resolve what isr's presets leave to the scene: its maps
// undilated in an open scene, dilated behind walls, as the request set them where it did.
TEST(ErrorModel, TheBasisSaysWhetherIsrsMapsAreDilatedAndWhy) {
    SceneAnalysis analysis = made_up_analysis();
    analysis.visibility.pairs = 1000;
    analysis.visibility.occluded_fraction = 0.05;
    const double below = 100.0 * methods::MethodRegistry::builtin().resolve("isr", "low", {}).at("ism_open_below");
    const std::string open = predict_error(analysis, "isr", "low", {}).basis;
    EXPECT_NE(open.find(fmt::format("its maps undilated (5% of the indirect light occluded, under {:.1f}%)", below)),
              std::string::npos)
        << open;
    analysis.visibility.occluded_fraction = 0.3;
    const std::string walled = predict_error(analysis, "isr", "low", {}).basis;
    EXPECT_NE(walled.find(fmt::format("its maps dilated (30% of the indirect light occluded, at least {:.1f}%)", below)),
              std::string::npos)
        << walled;
    EXPECT_EQ(predict_error(analysis, "isr", "low", {{"ism_dilation", 0}}).basis.find("its maps"), std::string::npos);
    EXPECT_EQ(predict_error(analysis, "isr", "draft", {}).basis.find("its maps"), std::string::npos);  // none
    EXPECT_EQ(predict_error(analysis, "cssm", "low", {}).basis.find("its maps"), std::string::npos);
}

TEST(ErrorModel, OccludedIsrIsRuledOutAndLeakingVctPromisedWhatLeakingScenesMeasured) {
    SceneAnalysis analysis = made_up_analysis();
    analysis.thin_walls.presets["draft"].leaking_area = 0.2;
    analysis.visibility.pairs = 1000;
    analysis.visibility.occluded_fraction = 0.8;
    // Where vct draft leaks, it is promised the largest the bench's leaking scenes measured of it,
    // and the basis says why; low, which does not leak, keeps the bench's prior.
    const planning::OwnErrorPriors& bench = planning::OwnErrorPriors::bench();
    const ErrorPrediction leaking = predict_error(analysis, "vct", "draft", {});
    EXPECT_FALSE(leaking.ruled_out.has_value());
    EXPECT_DOUBLE_EQ(leaking.rel_mse, 0.1 / 2.0 + bench.vct_leaking_largest.at("draft"));
    EXPECT_GT(bench.vct_leaking_largest.at("draft"), *bench.largest_of("vct", "draft"));
    EXPECT_NE(leaking.basis.find("where it leaks"), std::string::npos) << leaking.basis;
    EXPECT_NE(leaking.basis.find("thinner than vct draft"), std::string::npos) << leaking.basis;
    EXPECT_DOUBLE_EQ(predict_error(analysis, "vct", "draft", {{"bounces", 2}}).rel_mse,
                     0.1 / 4.0 + bench.vct_second_leaking_largest.at("draft"));
    EXPECT_DOUBLE_EQ(predict_error(analysis, "vct", "low", {}).rel_mse, 0.1 / 2.0 + *bench.largest_of("vct", "low"));
    // With no leaking scene measured at the preset, it is ruled out with the reason, until this
    // scene's own frames measure it; then what they measured stands.
    planning::OwnErrorPriors unmeasured = bench;
    unmeasured.vct_leaking_largest.clear();
    unmeasured.vct_second_leaking_largest.clear();
    const ErrorPrediction unknown = predict_error(analysis, "vct", "draft", {}, nullptr, unmeasured);
    ASSERT_TRUE(unknown.ruled_out.has_value());
    EXPECT_NE(unknown.ruled_out->find("thinner than vct draft"), std::string::npos) << *unknown.ruled_out;
    SceneMeasurements measured;
    measured.record_own_error("vct", "draft", 1, 0.06);
    const ErrorPrediction here = predict_error(analysis, "vct", "draft", {}, &measured, unmeasured);
    EXPECT_FALSE(here.ruled_out.has_value());
    EXPECT_DOUBLE_EQ(here.rel_mse, 0.1 / 2.0 + 0.06);
    EXPECT_DOUBLE_EQ(predict_error(analysis, "vct", "draft", {}, &measured).rel_mse, 0.1 / 2.0 + 0.06);
    // isr draft gathers without visibility; from low up its presets make imperfect shadow maps.
    EXPECT_TRUE(predict_error(analysis, "isr", "draft", {}).ruled_out.has_value());
    EXPECT_FALSE(predict_error(analysis, "isr", "medium", {}).ruled_out.has_value());
    EXPECT_TRUE(predict_error(analysis, "isr", "medium", {{"ism_size", 0}}).ruled_out.has_value());
    // The maps are made in hierarchical mode alone: medium's maps in basic mode model nothing.
    const ErrorPrediction basic = predict_error(analysis, "isr", "medium", {{"mode", 1}});
    ASSERT_TRUE(basic.ruled_out.has_value());
    EXPECT_NE(basic.ruled_out->find("mode 1"), std::string::npos) << *basic.ruled_out;
    EXPECT_NE(predict_error(analysis, "isr", "draft", {}).ruled_out.value_or("").find("ism_size 0"), std::string::npos);
    // Where little is occluded, nothing is ruled out for it.
    SceneAnalysis open = analysis;
    open.visibility.occluded_fraction = 0.3;
    EXPECT_FALSE(predict_error(open, "isr", "draft", {}).ruled_out.has_value());
    // Promised what the bench's occluded Cornell variants measured of it, not the open corpus' figure.
    const ErrorPrediction occluded_low = predict_error(analysis, "isr", "low", {});
    EXPECT_GE(occluded_low.rel_mse, planning::OwnErrorPriors::bench().isr_occluded_largest.at("low"));
    EXPECT_NE(occluded_low.basis.find("occluded Cornell variants"), std::string::npos) << occluded_low.basis;
    // cssm too: its coarse atlases err far more behind walls (the doorway's cssm draft at 8 bounces,
    // promised the open corpus' 0.03, measured 0.26); the open corpus' figure where little is occluded.
    const ErrorPrediction occluded_cssm = predict_error(analysis, "cssm", "draft", {{"bounces", 8}});
    EXPECT_GE(occluded_cssm.rel_mse, planning::OwnErrorPriors::bench().cssm_occluded_largest.at("draft"));
    EXPECT_NE(occluded_cssm.basis.find("occluded Cornell variants"), std::string::npos) << occluded_cssm.basis;
    EXPECT_LT(predict_error(open, "cssm", "draft", {{"bounces", 8}}).rel_mse,
              planning::OwnErrorPriors::bench().cssm_occluded_largest.at("draft"));

    DeviceCosts device("test");
    for (const char* method : {"direct", "vct", "isr", "cssm"}) {
        for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) device.set(method, preset, {1.0, 0.0});
    }
    std::vector<std::string> ruled_out;
    const auto all = candidates({analysis, device, nullptr, 64, 64, std::nullopt}, &ruled_out);
    for (const Candidate& c : all) EXPECT_FALSE(c.method == "isr" && c.preset == "draft") << c.method << " " << c.preset;
    EXPECT_TRUE(std::any_of(all.begin(), all.end(), [](const Candidate& c) {
        return c.method == "vct" && c.preset == "draft";
    }));
    ASSERT_EQ(ruled_out.size(), 1u);  // isr draft
    EXPECT_NE(ruled_out.front().find("isr draft"), std::string::npos) << ruled_out.front();
    PlanningInputs without_leaking_priors{analysis, device, nullptr, 64, 64, std::nullopt};
    without_leaking_priors.priors = &unmeasured;
    ruled_out.clear();
    candidates(without_leaking_priors, &ruled_out);
    EXPECT_EQ(ruled_out.size(), 2u);  // vct draft and isr draft
    EXPECT_NE(ruled_out.front().find("thinner than vct draft"), std::string::npos) << ruled_out.front();
}

// A plan the memory budget would refuse (PlanningInputs::memory, Renderer::memory_refusal in the
// daemon) is ruled out with the refusal, at the sizes refused alone: a smaller frame that fits stays.
TEST(Planner, PlansTheMemoryBudgetWouldRefuseAreRuledOut) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    for (const char* method : {"direct", "vct", "isr", "cssm"}) {
        for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) device.set(method, preset, {1.0, 0.0});
    }
    PlanningInputs inputs{analysis, device, nullptr, 64, 64, std::nullopt};
    inputs.resample_errors = {{"isr", {{0.5, 0.01}}}};
    inputs.memory = [](const std::string& method, const std::string& preset, const methods::KnobValues&, int width,
                       int) -> std::optional<std::string> {
        if (method == "isr" && preset != "draft" && width > 32) return "imperfect_shadow_maps past the budget";
        return std::nullopt;
    };
    std::vector<std::string> ruled_out;
    const auto all = candidates(inputs, &ruled_out);
    int isr_full = 0, isr_half = 0;
    for (const Candidate& c : all) {
        if (c.method != "isr") continue;
        EXPECT_TRUE(c.preset == "draft" || c.scale != 1.0) << c.preset;
        ++(c.scale == 1.0 ? isr_full : isr_half);
    }
    EXPECT_EQ(isr_full, 1);  // draft
    EXPECT_EQ(isr_half, 5);  // every preset at half size
    EXPECT_EQ(ruled_out.size(), 4u);  // low to ultra at 64x64, once each
    for (const std::string& reason : ruled_out) {
        EXPECT_NE(reason.find("at 64x64: imperfect_shadow_maps past the budget"), std::string::npos) << reason;
    }
}

// Where a scene needs more than one bounce, vct is offered with its second (the leaves gather the
// first bounce before the pixels gather from them): half the missing light, with the bench's own
// error of vct at two bounces, priced at the most a second bounce cost on the bench until such
// frames are measured on the scene.
TEST(Planner, VctIsOfferedWithItsSecondBounce) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("vct", "medium", {8.0, 0.0});
    const auto all = candidates({analysis, device, nullptr, 64, 64, std::string("vct")});
    const auto find = [&](int bounces) {
        return std::find_if(all.begin(), all.end(), [&](const Candidate& c) {
            return c.method == "vct" && c.preset == "medium" && c.scale == 1.0 &&
                   methods::knob_or(c.knobs, "bounces", 0.0) == bounces;
        });
    };
    ASSERT_NE(find(1), all.end());
    ASSERT_NE(find(2), all.end());
    EXPECT_DOUBLE_EQ(find(1)->predicted_error, 0.1 / 2.0 + *own_error_prior("vct", "medium", 1));
    EXPECT_DOUBLE_EQ(find(2)->predicted_error, 0.1 / 4.0 + *own_error_prior("vct", "medium", 2));
    EXPECT_GT(*own_error_prior("vct", "medium", 2), *own_error_prior("vct", "medium", 1));
    EXPECT_DOUBLE_EQ(find(1)->predicted_ms, 8.0);
    EXPECT_DOUBLE_EQ(find(2)->predicted_ms, 8.0 * bounce_cost_bound("vct", "medium", 2));
}

TEST(Planner, ATimeBudgetIsFilledWithTheReferencesSamples) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    PlanningInputs inputs{analysis, device, nullptr, 64, 64, std::string("reference")};
    inputs.priors = &priors_without_denoiser();  // a denoised frame's samples are a ladder's alone
    const auto spp_of = [](const Candidate& c) { return static_cast<int>(c.knobs.at("spp")); };
    const auto ms_at = [&](int spp, int bounces) {
        return predicted_ms(inputs, "reference", "medium", {{"spp", spp}, {"bounces", bounces}, {"pixel_jitter", 0}});
    };
    const std::vector<Candidate> ladder = candidates(inputs);
    for (const double budget : {50.0, 500.0, 5000.0}) {
        SCOPED_TRACE(budget);
        const std::vector<Candidate> filled = candidates(inputs, nullptr, budget);
        // Per bounce count, its most samples within the budget: one more would not fit. The ladder's
        // steps of 1.5 leave some of it unused at every bounce count here.
        std::map<int, int> most;
        for (const Candidate& c : filled) {
            const int bounces = static_cast<int>(c.knobs.at("bounces"));
            if (c.predicted_ms <= budget) most[bounces] = std::max(most[bounces], spp_of(c));
        }
        int off_the_ladder = 0;
        for (const auto& [bounces, spp] : most) {
            EXPECT_GT(ms_at(spp + 1, bounces), budget) << bounces << " bounces at " << spp << " spp";
            off_the_ladder += std::none_of(ladder.begin(), ladder.end(), [&](const Candidate& c) {
                return spp_of(c) == spp && c.knobs.at("bounces") == bounces;
            });
        }
        EXPECT_GT(off_the_ladder, 0);
        EXPECT_EQ(filled.size(), ladder.size() + off_the_ladder);  // nothing else added
        const Plan plan_in_time = plan(inputs, {budget, std::nullopt});
        EXPECT_LE(plan_in_time.chosen.predicted_ms, budget);
        EXPECT_GT(ms_at(spp_of(plan_in_time.chosen) + 1, static_cast<int>(plan_in_time.chosen.knobs.at("bounces"))), budget);
        // With a target error too, the time budget is filled as well.
        EXPECT_EQ(plan(inputs, {budget, 0.5}).considered, static_cast<int>(filled.size()));
    }
    // A target error alone keeps the ladder's steps, and their slack.
    EXPECT_EQ(plan(inputs, {std::nullopt, 0.05}).considered, static_cast<int>(ladder.size()));
    // Budgets where no step fits, or every one does, have nothing to fill.
    for (const double extreme : {1e-3, 1e12, std::numeric_limits<double>::infinity()}) {
        EXPECT_EQ(candidates(inputs, nullptr, extreme).size(), ladder.size()) << extreme;
    }
}

// The foliage's figures, near enough: little light past one bounce, paths that mostly end, and frames
// that measured the noise at 2 bounces from 16 samples (high, as few samples read) and at 4 from 64.
TEST(Planner, MoreBouncesAreNeverPredictedQuieterAgainstEveryBounce) {
    SceneAnalysis analysis = made_up_analysis();
    analysis.bounces.stopped_error = {0.0145, 0.00035, 0.00001, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    analysis.bounces.noise_against_whole = {0.0, 0.0088, 0.0105, 0.0111, 0.0114, 0.0115, 0.0115, 0.0115,
                                            0.0115, 0.0115, 0.0115, 0.0115, 0.0115};
    analysis.bounces.sample_ns = {1000, 2000, 2100, 2150, 2160, 2160, 2160, 2160, 2160, 2160, 2160, 2160, 2160};
    SceneMeasurements measured;
    measured.record_noise(2, 1.3, 16);
    measured.record_noise(4, 1.0, 64);
    const ReferenceNoise at_4 = reference_noise(analysis, 4, 64, &measured, NoiseAgainst::every_bounce);
    // 1.3 x 0.0105 at 2 bounces is more than 1.0 x 0.0114 at 4: the floor.
    EXPECT_DOUBLE_EQ(at_4.rel_mse, 1.3 * 0.0105 / 64.0);
    EXPECT_EQ(at_4.floor_bounces, 2);
    EXPECT_NE(predict_error(analysis, "reference", "medium", {{"spp", 64}, {"bounces", 4}}, &measured)
                  .basis.find("the noise of 2 bounces"),
              std::string::npos);
    for (int bounces = 1; bounces <= 12; ++bounces) {
        EXPECT_GE(reference_noise(analysis, bounces, 64, &measured, NoiseAgainst::every_bounce).rel_mse,
                  reference_noise(analysis, bounces - 1, 64, &measured, NoiseAgainst::every_bounce).rel_mse)
            << bounces;
    }
    // Where the statistics already rise, nothing is floored.
    EXPECT_FALSE(reference_noise(analysis, 4, 64, nullptr, NoiseAgainst::every_bounce).floor_bounces);
    EXPECT_DOUBLE_EQ(reference_noise(analysis, 4, 64, nullptr, NoiseAgainst::every_bounce).rel_mse, 0.0114 / 64.0);
    // Against its own frame it may fall: a frame of fewer bounces is darker, its noise weighs more there.
    SceneAnalysis darker = analysis;
    darker.bounces.noise_per_sample = {0.0, 0.03, 0.02, 0.015, 0.0114, 0.0115, 0.0115, 0.0115,
                                       0.0115, 0.0115, 0.0115, 0.0115, 0.0115};
    EXPECT_DOUBLE_EQ(reference_noise(darker, 4, 64, nullptr, NoiseAgainst::own_frame).rel_mse, 0.0114 / 64.0);

    // Within 200 ms the plan takes 2 bounces: 3 and 4 cost more per sample and are no quieter (without
    // the floor 3 won, the nearest ratio to it being 4's), 1 lacks light.
    DeviceCosts device("test");
    const PlanningInputs inputs{analysis, device, &measured, 64, 64, std::string("reference")};
    const Plan within = plan(inputs, {200.0, std::nullopt});
    ASSERT_EQ(within.chosen.method, "reference");
    EXPECT_EQ(within.chosen.knobs.at("bounces"), 2.0) << within.chosen.error_basis;
}

TEST(Costs, ALineThroughTwoFramesAndItsClamps) {
    const CostLine line = CostLine::through(1e6, 12.0, 4e6, 30.0);
    EXPECT_DOUBLE_EQ(line.per_megapixel_ms, 6.0);
    EXPECT_DOUBLE_EQ(line.fixed_ms, 6.0);
    EXPECT_DOUBLE_EQ(line.at(2e6), 18.0);
    // A larger frame measured faster (noise): no negative slope; the line keeps the larger frame's time.
    const CostLine noisy = CostLine::through(1e6, 12.0, 4e6, 10.0);
    EXPECT_DOUBLE_EQ(noisy.per_megapixel_ms, 0.0);
    EXPECT_DOUBLE_EQ(noisy.fixed_ms, 10.0);
}

TEST(Costs, BouncesAreMeasuredApartAndPricedFromTheNearestCountBelow) {
    SceneMeasurements measured;
    measured.record("cssm", "low", 2, 20.0, 10.0);
    measured.record("cssm", "low", 8, 60.0, 15.0);
    EXPECT_DOUBLE_EQ(*measured.ratio("cssm", "low", 8), 4.0);
    EXPECT_DOUBLE_EQ(*measured.ratio("cssm", "low", 2), 2.0);
    bool exact = true;
    const auto raise = [](const std::string&, int measured_bounces) { return measured_bounces == 2 ? 1.5 : 1.25; };
    EXPECT_DOUBLE_EQ(*measured.ratio("cssm", "low", 4, &exact, raise), 3.0);  // not measured: 2 bounces', raised
    EXPECT_FALSE(exact);
    EXPECT_DOUBLE_EQ(*measured.ratio("cssm", "low", 4), 2.0);    // unraised without a rule
    EXPECT_DOUBLE_EQ(*measured.ratio("cssm", "low", 12), 4.0);   // the nearest below is 8
    EXPECT_DOUBLE_EQ(*measured.ratio("cssm", "low", 1), 2.0);    // none below: the fewest above
    EXPECT_DOUBLE_EQ(*measured.ratio("cssm", "high", 4, nullptr, raise), 4.0);  // nor the preset: the method's, each raised
    EXPECT_FALSE(measured.ratio("vct", "low", -1).has_value());

    // Until measured, a further bounce costs at most the most the bench measured one cost: not a
    // repeat of the frame, which would price cssm low at 8 bounces as 8 frames.
    EXPECT_DOUBLE_EQ(bounce_cost_bound("cssm", "low", 1), 1.0);
    EXPECT_GT(bounce_cost_bound("cssm", "low", 2), 1.0);
    EXPECT_EQ(bounce_cost_bound("cssm", "low", 2), bounce_cost_bound("cssm", "low", 8));
    EXPECT_LT(bounce_cost_bound("cssm", "low", 8), 8.0);
    EXPECT_LE(bounce_cost_bound("cssm", "draft", 8), bounce_cost_bound("cssm", "ultra", 8));  // finer refines more
    EXPECT_LT(bounce_cost_bound("vct", "medium", 2), 2.0);
    EXPECT_DOUBLE_EQ(bounce_cost_bound("isr", "medium", 8), 1.0);  // no bounces knob

    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("cssm", "draft", {10.0, 0.0});
    SceneMeasurements scene;
    const PlanningInputs inputs{analysis, device, &scene, 64, 64, std::nullopt};
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "draft", {{"bounces", 1}}), 10.0);
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "draft", {{"bounces", 4}}), 10.0 * bounce_cost_bound("cssm", "draft", 4));
    scene.record("cssm", "draft", 4, 15.0, 10.0);  // measured: 1.5 times the one-bounce line
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "draft", {{"bounces", 4}}), 15.0);
    // 8 from 4: both past the preset's count, so the bound raises them alike: as measured at 4.
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "draft", {{"bounces", 8}}), 15.0);
    // 1 from 4: fewer bounces cost at most what the frames measured, and are not assumed cheaper.
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "draft", {{"bounces", 1}}), 15.0);
}

TEST(Costs, BouncesNotMeasuredAreExpectedAtWhatTheyTypicallyCost) {
    for (const char* method : {"cssm", "vct"}) {
        for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) {
            EXPECT_DOUBLE_EQ(typical_bounce_cost(method, preset, 1), 1.0);  // the preset's own count
            EXPECT_GE(typical_bounce_cost(method, preset, 8), 1.0) << method << " " << preset;
            EXPECT_LE(typical_bounce_cost(method, preset, 8), bounce_cost_bound(method, preset, 8)) << method << " " << preset;
        }
    }
    EXPECT_LT(typical_bounce_cost("cssm", "draft", 8), bounce_cost_bound("cssm", "draft", 8));
    EXPECT_DOUBLE_EQ(typical_bounce_cost("isr", "medium", 8), 1.0);  // no bounces knob

    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("cssm", "draft", {10.0, 0.0});
    SceneMeasurements scene;
    const PlanningInputs inputs{analysis, device, &scene, 64, 64, "cssm"};
    const auto at = [](const std::vector<Candidate>& all, int bounces) {
        const auto it = std::find_if(all.begin(), all.end(), [&](const Candidate& c) {
            return c.preset == "draft" && c.knobs.at("bounces") == bounces && c.scale == 1.0;
        });
        if (it == all.end()) throw std::runtime_error(fmt::format("no cssm draft plan at {} bounces", bounces));
        return *it;
    };
    // Nothing measured: the bound prices it, and the typical cost is its expected price.
    std::vector<Candidate> all = candidates(inputs);
    EXPECT_DOUBLE_EQ(at(all, 8).predicted_ms, 10.0 * bounce_cost_bound("cssm", "draft", 8));
    ASSERT_TRUE(at(all, 8).expected_ms.has_value());
    EXPECT_DOUBLE_EQ(*at(all, 8).expected_ms, 10.0 * typical_bounce_cost("cssm", "draft", 8));
    EXPECT_NE(at(all, 8).cost_basis.find("typically"), std::string::npos) << at(all, 8).cost_basis;
    EXPECT_FALSE(at(all, 1).expected_ms.has_value());  // priced as measured: nothing to expect apart
    // Measured at its count, a plan has one price.
    scene.record("cssm", "draft", 8, 18.0, 10.0);
    all = candidates(inputs);
    EXPECT_DOUBLE_EQ(at(all, 8).predicted_ms, 18.0);
    EXPECT_FALSE(at(all, 8).expected_ms.has_value());
    // From 1 bounce measured, 4 is raised by the typical cost where expected, by the bound where priced.
    SceneMeasurements one;
    one.record("cssm", "draft", 1, 12.0, 10.0);
    const PlanningInputs from_one{analysis, device, &one, 64, 64, "cssm"};
    all = candidates(from_one);
    EXPECT_DOUBLE_EQ(at(all, 4).predicted_ms, 12.0 * bounce_cost_bound("cssm", "draft", 4));
    EXPECT_DOUBLE_EQ(*at(all, 4).expected_ms, 12.0 * typical_bounce_cost("cssm", "draft", 4));
}

TEST(Costs, TheCacheFileRoundTripsAndAnotherDevicesOrAGarbledOneIsIgnored) {
    const auto dir = std::filesystem::temp_directory_path() / ("bounce-costs-" + std::to_string(::getpid()));
    DeviceCosts costs("NVIDIA H100/PCIe/SSE2");
    costs.set("vct", "medium", {3.5, 120.0});
    const auto file = DeviceCosts::cache_path(dir, costs.renderer());
    costs.save(file);
    const auto loaded = DeviceCosts::load(file, "NVIDIA H100/PCIe/SSE2");
    ASSERT_TRUE(loaded);
    EXPECT_DOUBLE_EQ(loaded->line("vct", "medium")->per_megapixel_ms, 120.0);
    EXPECT_FALSE(DeviceCosts::load(file, "llvmpipe"));  // another renderer's
    EXPECT_NE(DeviceCosts::cache_path(dir, "llvmpipe"), file);
    std::ofstream(file) << "{\"version\": 1, \"renderer\": \"NVIDIA H100/PCIe/SSE2\", \"lines\": [{\"method\": 3}]}";
    EXPECT_FALSE(DeviceCosts::load(file, "NVIDIA H100/PCIe/SSE2"));
    std::ofstream(file) << "not json";
    EXPECT_FALSE(DeviceCosts::load(file, "NVIDIA H100/PCIe/SSE2"));
    std::filesystem::remove_all(dir);
}

TEST(Costs, MeasuredFramesScaleTheDeviceLineAndOneSlowFrameDoesNot) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("vct", "medium", {10.0, 0.0});
    device.set("vct", "high", {20.0, 0.0});
    device.set("cssm", "low", {5.0, 0.0});
    SceneMeasurements measured;
    const PlanningInputs inputs{analysis, device, &measured, 64, 64, std::nullopt};
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "medium", {}), 10.0);  // nothing measured: the device's line
    for (const double ms : {30.0, 30.0, 500.0}) measured.record("vct", "medium", -1, ms, 10.0);  // one frame built structures
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "medium", {}), 30.0);
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "high", {}), 60.0);   // the method's ratio
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "low", {}), 15.0);   // the scene's ratio
    // The GPU's ratios say nothing of the CPU's: the reference keeps the analysis' times.
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "reference", "medium", {{"spp", 1}, {"bounces", 0}}),
                     2.0 + 1000.0 * 1e-6 * 64 * 64);
    // The reference: building the tracer plus each sample's time.
    EXPECT_DOUBLE_EQ(predicted_ms({analysis, device, nullptr, 100, 100, std::nullopt}, "reference", "medium",
                                  {{"spp", 8}, {"bounces", 1}}),
                     2.0 + 2000.0 * 1e-6 * 100 * 100 * 8);
}

// A geometry-heavy scene: its frames cost nearly the same at every size, where the calibration box's
// cost was mostly per pixel. One ratio to the device's line, measured at one size, misprices the
// others; the scene's own line through two sizes does not.
TEST(Costs, AScenesOwnLineThroughTwoSizesPricesEverySize) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("vct", "medium", {2.0, 2000.0});  // at 64x64: 10.19 ms, at 16x16: 2.51 ms
    SceneMeasurements scene;
    const double full = 64.0 * 64.0, quarter = 16.0 * 16.0;
    scene.record("vct", "medium", 1, 40.0, device.line("vct", "medium")->at(full), full);
    const PlanningInputs at_16{analysis, device, &scene, 16, 16, std::nullopt};
    // One size measured: the device's line times the ratio, 40 / 10.19 x 2.51 = 9.9 ms.
    EXPECT_NEAR(predicted_ms(at_16, "vct", "medium", {{"bounces", 1}}),
                40.0 / device.line("vct", "medium")->at(full) * device.line("vct", "medium")->at(quarter), 1e-9);
    scene.record("vct", "medium", 1, 37.0, device.line("vct", "medium")->at(quarter), quarter);
    const CostLine own = CostLine::through(quarter, 37.0, full, 40.0);
    EXPECT_NEAR(predicted_ms(at_16, "vct", "medium", {{"bounces", 1}}), 37.0, 1e-9);
    const PlanningInputs at_32{analysis, device, &scene, 32, 32, std::nullopt};
    std::string basis;
    EXPECT_NEAR(predicted_ms(at_32, "vct", "medium", {{"bounces", 1}}, &basis), own.at(32.0 * 32.0), 1e-9);
    EXPECT_NE(basis.find("own line"), std::string::npos) << basis;
    // Sizes closer than kLineSpan apart make no line: two noisy points that near would tilt it anywhere.
    SceneMeasurements near;
    near.record("vct", "medium", 1, 40.0, 10.0, full);
    near.record("vct", "medium", 1, 30.0, 10.0, full / 4.0);
    EXPECT_FALSE(near.line("vct", "medium", 1).has_value());
}

// Another preset of the method takes the shape of the scene's line for the preset measured at
// several sizes (the draft frames that measure upsampling), scaled by the device's ratio between the
// two presets at each size, and by its own frames where it has any: at their size, by their ratio to
// the shape; at another size, raised by the larger of that ratio and their difference from the shape
// (per pixel or fixed: the frames do not say which), never lowered.
TEST(Costs, OtherPresetsTakeTheShapeOfTheMethodsLineOnTheScene) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("cssm", "draft", {1.0, 1000.0});
    device.set("cssm", "medium", {4.0, 8000.0});
    SceneMeasurements scene;
    const double full = 64.0 * 64.0, quarter = 16.0 * 16.0;
    scene.record("cssm", "draft", 1, 20.0, 1.0, quarter);  // draft here: 20 ms at 16x16, 24 ms at 64x64
    scene.record("cssm", "draft", 1, 24.0, 1.0, full);
    const CostLine draft_here = CostLine::through(quarter, 20.0, full, 24.0);
    const auto model = [&](double pixels) {
        return draft_here.at(pixels) * device.line("cssm", "medium")->at(pixels) / device.line("cssm", "draft")->at(pixels);
    };
    const PlanningInputs at_16{analysis, device, &scene, 16, 16, std::nullopt};
    EXPECT_NEAR(predicted_ms(at_16, "cssm", "medium", {{"bounces", 1}}), model(quarter), 1e-9);
    EXPECT_NEAR(predicted_ms(at_16, "cssm", "medium", {{"bounces", 4}}),  // bounces unmeasured
                bounce_cost_bound("cssm", "medium", 4) * model(quarter), 1e-9);
    // The measured preset itself at a bounce count not measured: its line, at the bound.
    EXPECT_NEAR(predicted_ms(at_16, "cssm", "draft", {{"bounces", 4}}), bounce_cost_bound("cssm", "draft", 4) * draft_here.at(quarter),
                1e-9);
    scene.record("cssm", "medium", 1, 1.5 * model(full), 99.0, full);  // medium measured 1.5x the shape at full size
    std::string basis;
    const double as_fixed = model(quarter) + 0.5 * model(full);
    ASSERT_GT(as_fixed, 1.5 * model(quarter));  // the difference, read as fixed, weighs more at the smaller size
    EXPECT_NEAR(predicted_ms(at_16, "cssm", "medium", {{"bounces", 1}}, &basis), as_fixed, 1e-9);
    EXPECT_NE(basis.find("cssm draft"), std::string::npos) << basis;
    const PlanningInputs at_64{analysis, device, &scene, 64, 64, std::nullopt};
    EXPECT_NEAR(predicted_ms(at_64, "cssm", "medium", {{"bounces", 1}}), 1.5 * model(full), 1e-9);  // at its size
    // Measured cheaper than the shape at full size: not assumed cheaper at another.
    scene.record("cssm", "high", 1, 0.5 * model(full), 99.0, full);
    device.set("cssm", "high", {4.0, 8000.0});
    EXPECT_NEAR(predicted_ms(at_16, "cssm", "high", {{"bounces", 1}}), model(quarter), 1e-9);
    EXPECT_NEAR(predicted_ms(at_64, "cssm", "high", {{"bounces", 1}}), 0.5 * model(full), 1e-9);
    // A plan that names no bounce count has its preset's: vct medium's frames, recorded under its
    // resolved knobs (one bounce), scale the shape of vct draft's line.
    device.set("vct", "draft", {1.0, 1000.0});
    device.set("vct", "medium", {2.0, 3000.0});
    scene.record("vct", "draft", 1, 30.0, 1.0, quarter);
    scene.record("vct", "draft", 1, 36.0, 1.0, full);
    const CostLine vct_draft = CostLine::through(quarter, 30.0, full, 36.0);
    const auto vct_model = [&](double pixels) {
        return vct_draft.at(pixels) * device.line("vct", "medium")->at(pixels) / device.line("vct", "draft")->at(pixels);
    };
    scene.record("vct", "medium", 1, 2.0 * vct_model(full), 99.0, full);
    EXPECT_NEAR(predicted_ms(at_16, "vct", "medium", {}),
                std::max(2.0 * vct_model(quarter), vct_model(quarter) + vct_model(full)), 1e-9);
    EXPECT_NEAR(predicted_ms(at_64, "vct", "medium", {}), 2.0 * vct_model(full), 1e-9);
    // Another method's line says nothing of this one's.
    device.set("isr", "draft", {1.0, 1000.0});
    EXPECT_NEAR(predicted_ms(at_16, "isr", "draft", {}), device.line("isr", "draft")->at(quarter) * scene.scene_ratio().value(),
                1e-9);
}

// Reference frames cost a fixed part per frame and a part per sample. Frames measured at 3 ms +
// 1.1x their predicted samples' time (an H200 host's 16 threads: the foliage's one-sample frame took
// 2 to 3 ms where its samples were predicted at a fraction of one) price a one-sample frame at its
// fixed part, where the median ratio of the long frames would price it at its samples alone.
TEST(Costs, ReferenceFramesFitAFixedPartAndAPartPerSample) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    SceneMeasurements measured;
    const PlanningInputs inputs{analysis, device, &measured, 64, 64, std::nullopt};
    const auto at = [&](double spp) {
        return predicted_ms(inputs, "reference", "medium", {{"spp", spp}, {"bounces", 0}});
    };
    const double one_sample = at(1.0);  // 2 ms of tracer build + 1000 ns x 4096 pixels
    EXPECT_DOUBLE_EQ(one_sample, 2.0 + 1000.0 * 1e-6 * 64 * 64);
    EXPECT_FALSE(measured.reference_time().has_value());
    const double baseline_4 = 2.0 + 1000.0 * 1e-6 * 64 * 64 * 4, baseline_64 = 2.0 + 1000.0 * 1e-6 * 64 * 64 * 64;
    // Frames of one length cannot tell a fixed part from a per-sample one: their ratio prices the rest.
    for (int i = 0; i < 3; ++i) measured.record("reference", "medium", 0, 3.0 + 1.1 * baseline_64, baseline_64, 64 * 64);
    EXPECT_FALSE(measured.reference_time().has_value());
    EXPECT_NEAR(at(64.0), 3.0 + 1.1 * baseline_64, 1e-9);
    EXPECT_NEAR(at(1.0), one_sample * (3.0 + 1.1 * baseline_64) / baseline_64, 1e-9);
    measured.record("reference", "medium", 2, 3.0 + 1.1 * baseline_4, baseline_4, 64 * 64);
    const auto fit = measured.reference_time();
    ASSERT_TRUE(fit.has_value());
    EXPECT_EQ(fit->frames, 4);
    EXPECT_NEAR(fit->fixed_ms, 3.0, 1e-9);
    EXPECT_NEAR(fit->scale, 1.1, 1e-12);
    EXPECT_NEAR(at(1.0), 3.0 + 1.1 * one_sample, 1e-9);
    EXPECT_NEAR(at(64.0), 3.0 + 1.1 * baseline_64, 1e-9);
    // Frames that show no fixed part (a negative intercept) are priced in proportion.
    SceneMeasurements proportional;
    proportional.record("reference", "medium", 0, 9.0, 10.0, 64 * 64);
    proportional.record("reference", "medium", 0, 100.0, 110.0, 64 * 64);
    const auto through_origin = proportional.reference_time();
    ASSERT_TRUE(through_origin.has_value());
    EXPECT_DOUBLE_EQ(through_origin->fixed_ms, 0.0);
    // The line through the origin by least squares weighted 1 / measured^2 (residuals relative to each
    // frame): sum(w x y) / sum(w x^2).
    const double weighted_xy = 10.0 / 9.0 + 110.0 / 100.0, weighted_xx = 100.0 / 81.0 + 12100.0 / 10000.0;
    EXPECT_NEAR(through_origin->scale, weighted_xy / weighted_xx, 1e-12);
}

// The analysis prices every vertex of a path alike; a scene's deeper vertices may cost more (in the
// atrium frames of 6 bounces took 1.12 to 1.34 times what the fit through every count priced). A
// bounce count's own frames scale the fit at that count; a count with none takes the larger of its
// nearest measured neighbours', and counts whose frames sit on the fit are priced by it.
TEST(Costs, AReferenceBounceCountIsPricedByItsOwnFramesAgainstTheFit) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    SceneMeasurements measured;
    const PlanningInputs inputs{analysis, device, &measured, 64, 64, std::nullopt};
    const double pixels = 64.0 * 64.0;
    const auto baseline = [&](int bounces, double spp) { return 2.0 + 1000.0 * (bounces + 1) * 1e-6 * pixels * spp; };
    const auto at = [&](int bounces, double spp) {
        return predicted_ms(inputs, "reference", "medium", {{"spp", spp}, {"bounces", bounces}});
    };
    // Counts 0 and 2 on 3 ms + 1.1x; count 6 at 1.3 times that, at two lengths.
    for (const double spp : {4.0, 64.0}) {
        measured.record("reference", "medium", 0, 3.0 + 1.1 * baseline(0, spp), baseline(0, spp), pixels);
        measured.record("reference", "medium", 2, 3.0 + 1.1 * baseline(2, spp), baseline(2, spp), pixels);
    }
    EXPECT_NEAR(at(2, 16.0), 3.0 + 1.1 * baseline(2, 16.0), 1e-9);
    EXPECT_EQ(measured.reference_time(2)->bounce_ratio_of, 2);
    for (const double spp : {8.0, 32.0}) {
        measured.record("reference", "medium", 6, 1.3 * (3.0 + 1.1 * baseline(6, spp)), baseline(6, spp), pixels);
    }
    const auto fit = measured.reference_time();
    ASSERT_TRUE(fit.has_value());
    EXPECT_EQ(fit->frames, 6);
    EXPECT_EQ(fit->bounce_ratio_of, -1);  // no count asked: the fit alone
    // Count 6: the median of its frames against the fit, which they raised too.
    const auto six = measured.reference_time(6);
    ASSERT_TRUE(six.has_value());
    EXPECT_EQ(six->bounce_ratio_of, 6);
    const double first = 1.3 * (3.0 + 1.1 * baseline(6, 8.0)) / fit->at(baseline(6, 8.0));
    const double second = 1.3 * (3.0 + 1.1 * baseline(6, 32.0)) / fit->at(baseline(6, 32.0));
    EXPECT_NEAR(six->bounce_ratio, 0.5 * (first + second), 1e-12);
    EXPECT_GT(six->bounce_ratio, 1.15);
    EXPECT_NEAR(at(6, 64.0), fit->at(baseline(6, 64.0)) * six->bounce_ratio, 1e-9);
    // The frames of 2 bounces sit under the raised fit: their count is priced lower than the fit, as measured.
    EXPECT_LT(measured.reference_time(2)->bounce_ratio, 1.0);
    // Unmeasured counts: 4 and 8 take count 6's (the larger neighbour, the only one above), 1 the
    // larger of counts 0 and 2.
    EXPECT_EQ(measured.reference_time(4)->bounce_ratio_of, 6);
    EXPECT_EQ(measured.reference_time(8)->bounce_ratio_of, 6);
    const auto one = measured.reference_time(1);
    EXPECT_DOUBLE_EQ(one->bounce_ratio, std::max(measured.reference_time(0)->bounce_ratio, measured.reference_time(2)->bounce_ratio));
}

TEST(Costs, AReferenceFrameRecordsItsNoiseAgainstTheAnalysis) {
    const SceneAnalysis analysis = made_up_analysis();
    SceneMeasurements measured;
    FrameStats stats;
    stats.method = "reference";
    stats.preset = "medium";
    stats.knobs = {{"spp", 16}, {"bounces", 4}};
    stats.method_statistics = {{"noise_per_sample", 2.0}};
    stats.render_ms = 50.0;
    record_frame(measured, &analysis, DeviceCosts("test"), stats, 32, 32);
    EXPECT_DOUBLE_EQ(*measured.noise_ratio(4), 4.0);  // 2.0 against the analysis' 0.5
    EXPECT_TRUE(measured.ratio("reference", "medium").has_value());
    // A frame's statistic reads high at few samples: the frames of most samples say, the largest of
    // them where several have as many.
    stats.knobs["spp"] = 64;
    stats.method_statistics["noise_per_sample"] = 1.0;
    record_frame(measured, &analysis, DeviceCosts("test"), stats, 32, 32);
    EXPECT_DOUBLE_EQ(*measured.noise_ratio(4), 2.0);
    stats.knobs["spp"] = 8;
    stats.method_statistics["noise_per_sample"] = 2.5;
    record_frame(measured, &analysis, DeviceCosts("test"), stats, 32, 32);
    EXPECT_DOUBLE_EQ(*measured.noise_ratio(4), 2.0);
    stats.knobs["spp"] = 64;
    stats.method_statistics["noise_per_sample"] = 1.2;
    record_frame(measured, &analysis, DeviceCosts("test"), stats, 32, 32);
    EXPECT_DOUBLE_EQ(*measured.noise_ratio(4), 2.4);
    stats.method_statistics["noise_per_sample"] = 2.0;
    stats.knobs["spp"] = 2;  // too few samples to say
    SceneMeasurements few;
    record_frame(few, &analysis, DeviceCosts("test"), stats, 32, 32);
    EXPECT_FALSE(few.noise_ratio(4).has_value());
}

// A method keeps its structures between frames, so what a frame redoes depends on what changed
// since its method's last frame on the scene.
TEST(FrameChange, AFrameRedoesWhatChangedSinceItsMethodsLastFrame) {
    const MethodState last{.knobs = {{"resolution", 64}}, .lights = 1, .light_places = 5, .geometry = 2, .lit = true};
    EXPECT_EQ(change_between(std::nullopt, last), FrameChange::knobs_and_scene);  // the method's first frame
    EXPECT_EQ(change_between(last, last), FrameChange::none);
    MethodState next = last;
    next.lights = 3;  // a colour or an intensity: the lights' places as they were
    EXPECT_EQ(change_between(last, next), FrameChange::light_power);
    next.light_places = 6;  // a light moved too
    EXPECT_EQ(change_between(last, next), FrameChange::lights);
    next.geometry = 3;
    EXPECT_EQ(change_between(last, next), FrameChange::objects);  // the lights' work and the objects'
    next.knobs["resolution"] = 128;
    EXPECT_EQ(change_between(last, next), FrameChange::knobs_and_scene);  // other knobs after a move
    MethodState switched = last;
    switched.knobs["resolution"] = 128;
    EXPECT_EQ(change_between(last, switched), FrameChange::knobs);  // the scene as it was
    MethodState baked = last;
    baked.lit = false;  // a bake built the structures and solved no light
    EXPECT_EQ(change_between(baked, last), FrameChange::lights);
}

// A camera that moved redraws the view cascades of a method that reads them, and nothing of one
// that does not; with a light's power changed too, the frame redoes the light's work and the
// cascades, and is priced as a move of the lights (which redraws every map).
TEST(FrameChange, AMovedCameraRedrawsTheViewCascadesOfAMethodThatReadsThem) {
    const MethodState last{.knobs = {{"shadow_cascades", 3}}, .lights = 1, .light_places = 5, .geometry = 2, .view = 7,
                           .lit = true};
    MethodState moved = last;
    moved.view = 8;
    EXPECT_EQ(change_between(last, moved), FrameChange::view);
    MethodState without = last, moved_without = moved;
    without.knobs["shadow_cascades"] = 0;
    moved_without.knobs["shadow_cascades"] = 0;
    EXPECT_EQ(change_between(without, moved_without), FrameChange::none);
    MethodState no_knob = last, moved_no_knob = moved;
    no_knob.knobs.clear();
    moved_no_knob.knobs.clear();
    EXPECT_EQ(change_between(no_knob, moved_no_knob), FrameChange::none);  // the reference, say
    moved.lights = 3;
    EXPECT_EQ(change_between(last, moved), FrameChange::lights);
    moved.light_places = 6;
    EXPECT_EQ(change_between(last, moved), FrameChange::lights);
    moved.geometry = 3;
    EXPECT_EQ(change_between(last, moved), FrameChange::objects);
    EXPECT_EQ(to_string(FrameChange::view), "view");
    // Other knobs from a moved camera: the cascades too where the maps are the same, else the maps
    // are all drawn anew as the knobs' own work.
    MethodState switched = last;
    switched.view = 8;
    switched.knobs["bounces"] = 2;
    EXPECT_EQ(change_between(last, switched), FrameChange::knobs_and_view);
    EXPECT_EQ(to_string(FrameChange::knobs_and_view), "knobs_and_view");
    switched.knobs["shadow_map_size"] = 4096;
    EXPECT_EQ(change_between(last, switched), FrameChange::knobs);
    switched.lights = 3;
    EXPECT_EQ(change_between(last, switched), FrameChange::knobs_and_scene);
    // Another count of cascades alone selects no other structure and keeps the maps over the scene:
    // the cascades drawn anew, as for a moved camera, or dropped.
    MethodState recascaded = last;
    recascaded.knobs["shadow_cascades"] = 2;
    recascaded.view = 9;
    EXPECT_TRUE(cascades_alone_differ(last.knobs, recascaded.knobs));
    EXPECT_EQ(change_between(last, recascaded), FrameChange::view);
    MethodState dropped = without;
    dropped.view = 0;  // no cascades, none fitted
    EXPECT_EQ(change_between(last, dropped), FrameChange::none);
    recascaded.light_places = 6;
    EXPECT_EQ(change_between(last, recascaded), FrameChange::lights);
    recascaded = last;
    recascaded.knobs["shadow_cascades"] = 2;
    recascaded.knobs["bounces"] = 2;  // and another knob: a switch
    EXPECT_FALSE(cascades_alone_differ(last.knobs, recascaded.knobs));
    EXPECT_EQ(change_between(last, recascaded), FrameChange::knobs);
    // Ambient occlusion draws no shadow maps: a moved camera redraws no cascades, and a frame of light
    // after it draws every map, a switch of knobs even where the camera stayed.
    MethodState occlusion = last, moved_occlusion = moved;
    occlusion.knobs["ao"] = moved_occlusion.knobs["ao"] = 1;
    moved_occlusion.lights = occlusion.lights;
    moved_occlusion.light_places = occlusion.light_places;
    moved_occlusion.geometry = occlusion.geometry;
    EXPECT_EQ(change_between(occlusion, moved_occlusion), FrameChange::none);
    occlusion.view = 0;  // as fitted for it: none
    EXPECT_FALSE(same_maps(occlusion.knobs, last.knobs));
    EXPECT_EQ(change_between(occlusion, last), FrameChange::knobs);
}

// Frames that redid work are kept apart: a relit frame is not a slow warm frame, and a warm one does
// not lower what relighting costs.
TEST(Costs, FramesThatRedidWorkAreKeptApartFromWarmFrames) {
    SceneMeasurements scene;
    for (const double ms : {30.0, 31.0, 29.0}) scene.record("vct", "medium", 1, ms, 10.0, 4096.0);
    scene.record("vct", "medium", 1, 400.0, 10.0, 4096.0, FrameChange::lights);
    scene.record("vct", "medium", 1, 900.0, 10.0, 4096.0, FrameChange::knobs);
    EXPECT_DOUBLE_EQ(*scene.ratio("vct", "medium", 1), 3.0);
    ASSERT_EQ(scene.changed_frames("vct", "medium", 1, FrameChange::lights).size(), 1u);
    EXPECT_DOUBLE_EQ(scene.changed_frames("vct", "medium", 1, FrameChange::lights).front().measured_ms, 400.0);
    EXPECT_DOUBLE_EQ(scene.changed_frames("vct", "medium", 1, FrameChange::knobs).front().measured_ms, 900.0);
    EXPECT_TRUE(scene.changed_frames("vct", "high", 1, FrameChange::lights).empty());
    EXPECT_EQ(scene.frames("vct", "medium", 1).size(), 3u);
    // The shadow maps of frames that drew them are timed; frames that reused them (a warm frame, a
    // preset of the same maps' size) have no such pass.
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    FrameStats relit;
    relit.method = "vct";
    relit.preset = "medium";
    relit.knobs = {{"shadow_map_size", 2048}};
    relit.passes = {{"shadow_maps", 120.0}, {"vct_cone_trace", 20.0}};
    relit.change = FrameChange::lights;
    FrameStats warm = relit;
    warm.passes = {{"vct_cone_trace", 20.0}};
    warm.change = FrameChange::none;
    record_frame(scene, &analysis, device, relit, 64, 64);
    // As many such frames as are kept: had they counted, they would have pushed the relit frame's out.
    for (std::size_t i = 0; i < SceneMeasurements::kKept; ++i) record_frame(scene, &analysis, device, warm, 64, 64);
    EXPECT_DOUBLE_EQ(*scene.shadow_maps_ms(2048, 0), 120.0);
}

// A frame that compiled programs paid what the daemon pays once: neither its time nor its shadow
// maps' pass prices a later frame, which would compile nothing (on llvmpipe, direct draft's first
// frame on a new renderer took 137 ms, its first on another scene 9 ms).
TEST(Costs, AFrameThatCompiledProgramsKeepsNoTime) {
    SceneMeasurements scene;
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("direct", "draft", {2.0, 0.0});
    FrameStats first;
    first.method = "direct";
    first.preset = "draft";
    first.knobs = {{"shadow_map_size", 512}};
    first.passes = {{"shadow_maps", 150.0}, {"direct_light", 1.0}};
    first.render_ms = 180.0;
    first.change = FrameChange::knobs_and_scene;
    first.programs_compiled = 7;
    record_frame(scene, &analysis, device, first, 64, 64);
    EXPECT_TRUE(scene.changed_frames("direct", "draft", -1, FrameChange::knobs_and_scene).empty());
    EXPECT_FALSE(scene.shadow_maps_ms(512, 0));
    // The same frame with its programs already compiled is kept, as any frame that redid its work.
    first.programs_compiled = 0;
    first.render_ms = 6.0;
    first.passes = {{"shadow_maps", 3.0}, {"direct_light", 1.0}};
    record_frame(scene, &analysis, device, first, 64, 64);
    const auto kept = scene.changed_frames("direct", "draft", -1, FrameChange::knobs_and_scene);
    ASSERT_EQ(kept.size(), 1u);
    EXPECT_DOUBLE_EQ(kept.front().measured_ms, 6.0);
    EXPECT_DOUBLE_EQ(*scene.shadow_maps_ms(512, 0), 3.0);
}

// A light dimmed as the camera moved drew the view cascades besides the light's work: the frame is
// kept as a change of power without them, and the cascades as the camera's, so that neither a
// dimming nor a move of the lights is priced by the other's work.
TEST(Costs, ALightDimmedAsTheCameraMovedIsKeptWithoutItsCascades) {
    SceneMeasurements scene;
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("direct", "ultra", {2.0, 0.0});
    FrameStats dimmed;
    dimmed.method = "direct";
    dimmed.preset = "ultra";
    dimmed.knobs = {{"shadow_map_size", 4096}, {"shadow_cascades", 3}};
    dimmed.passes = {{"shadow_view_cascades", 300.0}, {"direct_light", 1.0}};
    dimmed.render_ms = 303.0;
    dimmed.change = FrameChange::light_power;
    record_frame(scene, &analysis, device, dimmed, 64, 64);
    const auto frames = scene.changed_frames("direct", "ultra", -1, FrameChange::light_power);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_DOUBLE_EQ(frames.front().measured_ms, 3.0);
    EXPECT_DOUBLE_EQ(*scene.view_cascades_ms(4096, 3), 300.0);
    EXPECT_FALSE(scene.shadow_maps_ms(4096, 3));
}

// A plan whose frame would redo work is priced with it: before the scene measured it, the bench's
// bound times the preset's warm frame at 128x128 (the work is the scene's, not the pixels'); once
// measured, what those frames took beyond a warm frame at their size, the median of them.
TEST(Planner, AFrameIsPricedWithWhatItWouldRedo) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("vct", "medium", {10.0, 1.0e3});  // 10 ms + 1 ms per thousand pixels
    SceneMeasurements scene;
    PlanningInputs inputs{analysis, device, &scene, 64, 64, std::nullopt};
    FrameChange now = FrameChange::none;
    inputs.change = [&](const std::string& method, const std::string&, const methods::KnobValues&, int, int) {
        return method == "vct" ? now : FrameChange::none;
    };
    const double warm_64 = 10.0 + 4.096, warm_128 = 10.0 + 16.384;
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "medium", {}), warm_64);
    now = FrameChange::lights;
    const double bound = change_cost_bound("vct", "medium", FrameChange::lights);
    EXPECT_GT(bound, 0.0);
    std::string basis;
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "medium", {}, &basis), warm_64 + bound * warm_128);
    EXPECT_NE(basis.find("the lights changed"), std::string::npos) << basis;
    // Relit frames measured at 32x32 and 128x128: what they took beyond a warm frame there.
    const double warm_32 = 10.0 + 1.024;
    scene.record("vct", "medium", 1, warm_32 + 50.0, warm_32, 32.0 * 32.0, FrameChange::lights);
    scene.record("vct", "medium", 1, warm_128 + 70.0, warm_128, 128.0 * 128.0, FrameChange::lights);
    scene.record("vct", "medium", 1, warm_128 + 400.0, warm_128, 128.0 * 128.0, FrameChange::lights);
    EXPECT_NEAR(predicted_ms(inputs, "vct", "medium", {}, &basis), warm_64 + 70.0, 1e-9);
    EXPECT_NE(basis.find("as 3 such frames"), std::string::npos) << basis;
    // A frame at other knobs is priced by its own kind's frames, the bench's bound until measured.
    now = FrameChange::knobs;
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "medium", {}),
                     warm_64 + change_cost_bound("vct", "medium", FrameChange::knobs) * warm_128);
    EXPECT_GE(change_cost_bound("vct", "medium", FrameChange::knobs), bound);  // structures built redo the light too
    EXPECT_EQ(change_cost_bound("vct", "medium", FrameChange::objects), change_cost_bound("vct", "medium", FrameChange::knobs));
    // A change of power alone redraws no shadow map: the bench's bound on the rest, until measured.
    now = FrameChange::light_power;
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "medium", {}),
                     warm_64 + change_cost_bound("vct", "medium", FrameChange::light_power) * warm_128);
    EXPECT_LT(change_cost_bound("vct", "medium", FrameChange::light_power), bound);  // no maps
    // The reference keeps nothing between frames.
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "reference", "medium", {{"spp", 1}, {"bounces", 0}}), 2.0 + 1e-3 * 64 * 64);
    EXPECT_DOUBLE_EQ(change_cost_bound("vct", "medium", FrameChange::none), 0.0);
}

// Shadow maps cost what the scene's triangles and lights make them cost, not what a warm frame
// does: a scene that timed its maps prices them at that time, and the rest of the work by the
// bench's bound without them.
TEST(Planner, ShadowMapsArePricedFromTheScenesOwnTimingsOfThem) {
    const int cascades = static_cast<int>(methods::MethodRegistry::builtin().resolve("vct", "medium", {}).at("shadow_cascades"));
    ASSERT_GT(cascades, 0);
    SceneMeasurements scene;
    EXPECT_FALSE(scene.shadow_maps_ms(1024, cascades));
    scene.record_view_cascades(4096, cascades, 9.0);  // another kind, sorting before and after these
    scene.record_shadow_maps(1024, cascades, 100.0);
    scene.record_shadow_maps(1024, cascades, 5.0);  // most maps reused
    EXPECT_DOUBLE_EQ(*scene.shadow_maps_ms(1024, cascades), 100.0);
    EXPECT_DOUBLE_EQ(*scene.shadow_maps_ms(2048, cascades), 400.0);  // four times the texels
    EXPECT_DOUBLE_EQ(*scene.shadow_maps_ms(512, cascades), 100.0);   // never lowered
    EXPECT_DOUBLE_EQ(*scene.view_cascades_ms(1024, cascades), 9.0);  // the nearest above, as measured
    // Maps drawn with other cascades, or the cascades drawn alone, are not these maps.
    EXPECT_FALSE(scene.shadow_maps_ms(1024, 0));
    scene.record_shadow_maps(4096, 0, 1.0);
    scene.record_view_cascades(512, cascades, 1.0);
    EXPECT_DOUBLE_EQ(*scene.shadow_maps_ms(2048, cascades), 400.0);
    EXPECT_DOUBLE_EQ(*scene.shadow_maps_ms(4096, 0), 1.0);

    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("vct", "medium", {10.0, 0.0});
    PlanningInputs inputs{analysis, device, &scene, 64, 64, std::nullopt};
    inputs.change = [](const std::string&, const std::string&, const methods::KnobValues&, int, int) {
        return FrameChange::lights;
    };
    const int map_size = static_cast<int>(methods::MethodRegistry::builtin().resolve("vct", "medium", {}).at("shadow_map_size"));
    const double besides = change_cost_bound("vct", "medium", FrameChange::lights, true);
    EXPECT_LE(besides, change_cost_bound("vct", "medium", FrameChange::lights));
    std::string basis;
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "medium", {}, &basis), 10.0 + *scene.shadow_maps_ms(map_size, cascades) + besides * 10.0);
    EXPECT_NE(basis.find("of shadow maps as this scene's frames drew them"), std::string::npos) << basis;
    // Planned with smaller maps: priced at the time of the smaller maps.
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "medium", {{"shadow_map_size", 1024}}), 10.0 + 100.0 + besides * 10.0);
    // A light dimmed: no maps to draw, whatever the scene timed of them.
    inputs.change = [](const std::string&, const std::string&, const methods::KnobValues&, int, int) {
        return FrameChange::light_power;
    };
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "medium", {}, &basis),
                     10.0 + change_cost_bound("vct", "medium", FrameChange::light_power) * 10.0);
    EXPECT_NE(basis.find("colour or intensity"), std::string::npos) << basis;
    // Ambient occlusion draws no maps: a move of the lights is priced without them.
    inputs.change = [](const std::string&, const std::string&, const methods::KnobValues&, int, int) {
        return FrameChange::lights;
    };
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "vct", "medium", {{"ao", 1}}, &basis), 10.0 + besides * 10.0);
    EXPECT_EQ(basis.find("of shadow maps"), std::string::npos) << basis;
}

// A moved camera redraws a sun's view cascades and nothing else: before the scene measured any such
// frame, at most what a move of the lights costs (the bench's bound); once it drew its maps, at most
// their time (the cascades are among them); once it redrew the cascades alone, at that time; once
// frames of the class were measured, at what they took beyond a warm frame. The device's
// calibration of other changes plays no part.
TEST(Planner, AMovedCameraIsPricedAsTheViewCascadesItRedraws) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("direct", "ultra", {2.0, 0.0});
    device.set_change_cost("direct", "ultra", {64.0 * 64.0, 5.0, 5.0, 5.0});  // would show if it counted
    SceneMeasurements scene;
    PlanningInputs inputs{analysis, device, &scene, 64, 64, std::nullopt};
    inputs.change = [](const std::string&, const std::string&, const methods::KnobValues&, int, int) {
        return FrameChange::view;
    };
    const auto resolved = methods::MethodRegistry::builtin().resolve("direct", "ultra", {});
    const int map_size = static_cast<int>(resolved.at("shadow_map_size"));
    const int cascades = static_cast<int>(resolved.at("shadow_cascades"));
    std::string basis;
    const double bound = change_cost_bound("direct", "ultra", FrameChange::lights);
    EXPECT_EQ(change_cost_bound("direct", "ultra", FrameChange::view), bound);
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "direct", "ultra", {}, &basis), 2.0 + bound * 2.0);
    EXPECT_NE(basis.find("the camera moved"), std::string::npos) << basis;
    EXPECT_NE(basis.find("at most a move of the lights"), std::string::npos) << basis;
    scene.record_shadow_maps(map_size, cascades, 600.0);
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "direct", "ultra", {}, &basis), 2.0 + 600.0);
    EXPECT_NE(basis.find("at most the shadow maps"), std::string::npos) << basis;
    scene.record_view_cascades(map_size, cascades, 450.0);
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "direct", "ultra", {}, &basis), 2.0 + 450.0);
    EXPECT_NE(basis.find("redrew them alone"), std::string::npos) << basis;
    // Timings of maps drawn with cascades do not price maps drawn without (the change function here
    // is made up: a plan without cascades redoes no view).
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "direct", "ultra", {{"shadow_cascades", 0}}), 2.0 + bound * 2.0);
    scene.record("direct", "ultra", -1, 2.0 + 300.0, 2.0, 64.0 * 64.0, FrameChange::view);
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "direct", "ultra", {}, &basis), 2.0 + 300.0);
    EXPECT_NE(basis.find("as 1 such frame"), std::string::npos) << basis;
    // Such a frame is no warm frame: the warm line is as the device's.
    EXPECT_FALSE(scene.ratio("direct", "ultra"));
    // A switch of knobs from a moved camera: the switch as such frames were measured, and the
    // cascades, until frames of the two together were.
    inputs.change = [](const std::string&, const std::string&, const methods::KnobValues&, int, int) {
        return FrameChange::knobs_and_view;
    };
    // The switch not measured: the device's calibration of a switch without its maps, which the
    // switch keeps (the 600 ms of all the maps are not counted), and the cascades.
    const double calibrated_switch = 5.0 * 2.0 + change_margin("direct", FrameChange::knobs) * 2.0;
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "direct", "ultra", {}, &basis), 2.0 + calibrated_switch + 300.0);
    EXPECT_NE(basis.find("the switch"), std::string::npos) << basis;
    scene.record("direct", "ultra", -1, 2.0 + 40.0, 2.0, 64.0 * 64.0, FrameChange::knobs);
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "direct", "ultra", {}, &basis), 2.0 + 40.0 + 300.0);
    EXPECT_NE(basis.find("other knobs, and the camera moved"), std::string::npos) << basis;
    scene.record("direct", "ultra", -1, 2.0 + 200.0, 2.0, 64.0 * 64.0, FrameChange::knobs_and_view);
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "direct", "ultra", {}), 2.0 + 200.0);
}

// A device whose calibration timed frames after changes prices what a frame redoes from those
// figures, as a multiple of the plan's warm frame at the size they were measured at, plus the
// scene's own shadow maps; without the scene's maps it keeps the bench's bound, which holds them.
TEST(Planner, ChangesArePricedFromTheDevicesCalibrationOfThem) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("cssm", "low", {2.0, 1.0e3});  // 2 ms + 1 ms per thousand pixels
    device.set_change_cost("cssm", "low", {64.0 * 64.0, 0.25, 0.5, 6.0});
    SceneMeasurements scene;
    PlanningInputs inputs{analysis, device, &scene, 128, 128, std::nullopt};
    FrameChange now = FrameChange::light_power;
    inputs.change = [&](const std::string&, const std::string&, const methods::KnobValues&, int, int) { return now; };
    const double warm_128 = 2.0 + 16.384, warm_64 = 2.0 + 4.096;
    const auto margin = [&](FrameChange change) { return change_margin("cssm", change) * warm_128; };
    std::string basis;
    // A light dimmed draws no map: the device's figure at its size, and the margin for a heavier scene.
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "low", {}, &basis), warm_128 + 0.25 * warm_64 + margin(now));
    EXPECT_NE(basis.find("as the device's calibration measured"), std::string::npos) << basis;
    EXPECT_GT(change_margin("cssm", FrameChange::light_power), 0.0);
    // The lights moved, before the scene timed its maps: the bench's bound, maps and all.
    now = FrameChange::lights;
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "low", {}, &basis),
                     warm_128 + change_cost_bound("cssm", "low", FrameChange::lights) * warm_128);
    EXPECT_NE(basis.find("the most the bench measured"), std::string::npos) << basis;
    const int map_size = static_cast<int>(methods::MethodRegistry::builtin().resolve("cssm", "low", {}).at("shadow_map_size"));
    const int cascades = static_cast<int>(methods::MethodRegistry::builtin().resolve("cssm", "low", {}).at("shadow_cascades"));
    scene.record_shadow_maps(map_size, cascades, 30.0);
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "low", {}, &basis), warm_128 + 30.0 + 0.5 * warm_64 + margin(now));
    EXPECT_NE(basis.find("as the device's calibration measured"), std::string::npos) << basis;
    // A switch of knobs, or a moved object, rebuilds: its own figure, never under the lights'.
    for (const FrameChange change : {FrameChange::knobs, FrameChange::knobs_and_scene, FrameChange::objects}) {
        now = change;
        EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "low", {}), warm_128 + 30.0 + 6.0 * warm_64 + margin(change))
            << to_string(change);
        EXPECT_GE(change_margin("cssm", change), change_margin("cssm", FrameChange::lights));
    }
    device.set_change_cost("cssm", "low", {64.0 * 64.0, 0.25, 0.5, 0.1});
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "low", {}), warm_128 + 30.0 + 0.5 * warm_64 + margin(now));
    // Frames of the change measured on the scene take over from the device's figure.
    scene.record("cssm", "low", 1, warm_128 + 7.0, warm_128, 128.0 * 128.0, FrameChange::objects);
    EXPECT_NEAR(predicted_ms(inputs, "cssm", "low", {}, &basis), warm_128 + 7.0, 1e-9);
    EXPECT_NE(basis.find("as 1 such frame"), std::string::npos) << basis;
    // Kept with the model, and refused when it makes no sense.
    const DeviceCosts read = DeviceCosts::from_json(device.to_json());
    ASSERT_TRUE(read.change_cost("cssm", "low"));
    EXPECT_DOUBLE_EQ(read.change_cost("cssm", "low")->lights, 0.5);
    EXPECT_DOUBLE_EQ(read.change_cost("cssm", "low")->pixels, 64.0 * 64.0);
    EXPECT_FALSE(read.change_cost("cssm", "draft"));
    nlohmann::json broken = device.to_json();
    broken["changes"][0]["rebuild"] = -1.0;
    EXPECT_THROW(DeviceCosts::from_json(broken), Error);
}

// Before a scene measured frames of a plan's own change, its frames of the method's other presets
// after a change of the same class tell how much heavier than the calibration's box it is: the
// device's figure is scaled by the median of what they measured against theirs (never under 1), in
// place of the margin measured on the bench corpus; without such frames, its frames of the method
// after other changes.
TEST(Planner, ASceneScalesTheCalibrationByItsFramesOfTheMethodsOtherPresets) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    device.set("cssm", "low", {2.0, 1.0e3});
    device.set("cssm", "medium", {4.0, 2.0e3});
    device.set_change_cost("cssm", "low", {64.0 * 64.0, 0.25, 0.5, 6.0});
    device.set_change_cost("cssm", "medium", {64.0 * 64.0, 0.25, 0.5, 5.0});
    SceneMeasurements scene;
    const auto& registry = methods::MethodRegistry::builtin();
    const auto map_size = [&](const char* preset) {
        return static_cast<int>(registry.resolve("cssm", preset, {}).at("shadow_map_size"));
    };
    const int cascades = static_cast<int>(registry.resolve("cssm", "low", {}).at("shadow_cascades"));
    ASSERT_EQ(cascades, static_cast<int>(registry.resolve("cssm", "medium", {}).at("shadow_cascades")));
    scene.record_shadow_maps(map_size("low"), cascades, 30.0);
    const double maps_medium = scene.shadow_maps_ms(map_size("medium"), cascades).value();  // as the scene times them
    PlanningInputs inputs{analysis, device, &scene, 128, 128, std::nullopt};
    FrameChange now = FrameChange::knobs_and_scene;
    inputs.change = [&](const std::string&, const std::string&, const methods::KnobValues&, int, int) { return now; };
    const double low_128 = 2.0 + 16.384, low_64 = 2.0 + 4.096;
    const double medium_128 = 4.0 + 32.768, medium_64 = 4.0 + 8.192;
    const int medium_bounces = static_cast<int>(registry.resolve("cssm", "medium", {}).at("bounces"));
    // Nothing of cssm measured here yet: the calibration plus the bench's margin.
    const double unscaled = low_128 + 30.0 + 6.0 * low_64;
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "low", {}), unscaled + change_margin("cssm", now) * low_128);
    // A switch to medium that redid three times its calibrated rebuild beyond its maps: low's is
    // priced at three times its own.
    scene.record("cssm", "medium", medium_bounces, medium_128 + maps_medium + 3.0 * 5.0 * medium_64, medium_128, 128.0 * 128.0,
                 FrameChange::knobs);
    std::string basis;
    EXPECT_NEAR(predicted_ms(inputs, "cssm", "low", {}, &basis), low_128 + 30.0 + 3.0 * 6.0 * low_64, 1e-9);
    EXPECT_NE(basis.find("scaled as 1 frame of the method's other presets measured here"), std::string::npos) << basis;
    // The median of such frames: two more, at 5 and at 0.5 times (counted as 1).
    scene.record("cssm", "medium", medium_bounces, medium_128 + maps_medium + 5.0 * 5.0 * medium_64, medium_128, 128.0 * 128.0,
                 FrameChange::objects);
    scene.record("cssm", "medium", medium_bounces, medium_128 + maps_medium + 0.5 * 5.0 * medium_64, medium_128, 128.0 * 128.0,
                 FrameChange::knobs_and_scene);
    EXPECT_NEAR(predicted_ms(inputs, "cssm", "low", {}), low_128 + 30.0 + 3.0 * 6.0 * low_64, 1e-9);
    // A move of the lights is another class: with no frame of it, the scene's frames after the
    // other changes scale it (their median, 3), not the margin.
    now = FrameChange::lights;
    EXPECT_NEAR(predicted_ms(inputs, "cssm", "low", {}, &basis), low_128 + 30.0 + 3.0 * 0.5 * low_64, 1e-9);
    EXPECT_NE(basis.find("scaled as 3 frames of the method after other changes measured here"), std::string::npos) << basis;
    // A frame of its own class takes over from them. A scene lighter than the box (its frame under
    // the calibration's figure) is priced at the figure.
    scene.record("cssm", "medium", medium_bounces, medium_128 + maps_medium + 0.2 * 0.5 * medium_64, medium_128,
                 128.0 * 128.0, FrameChange::lights);
    EXPECT_NEAR(predicted_ms(inputs, "cssm", "low", {}, &basis), low_128 + 30.0 + 0.5 * low_64, 1e-9);
    EXPECT_NE(basis.find("scaled as 1 frame of the method's other presets"), std::string::npos) << basis;
    // A figure under a twentieth of the warm frame scales nothing: one frame's noise would be its
    // ratio. With no other figure of the method either, the margin.
    device.set_change_cost("cssm", "medium", {64.0 * 64.0, 0.01, 0.01, 0.01});
    EXPECT_DOUBLE_EQ(predicted_ms(inputs, "cssm", "low", {}),
                     low_128 + 30.0 + 0.5 * low_64 + change_margin("cssm", now) * low_128);
    // Once the preset measured its own frame of the change, that prices it.
    scene.record("cssm", "low", static_cast<int>(registry.resolve("cssm", "low", {}).at("bounces")), low_128 + 9.0, low_128, 128.0 * 128.0, FrameChange::lights);
    EXPECT_NEAR(predicted_ms(inputs, "cssm", "low", {}), low_128 + 9.0, 1e-9);
}

// Under a time budget, a plan that fits warm but not with what it would redo gives way to one that
// fits as it would render now, and the plan says what its frame redoes.
TEST(Planner, ATimeBudgetCountsWhatTheFrameWouldRedo) {
    const SceneAnalysis analysis = made_up_analysis();
    DeviceCosts device("test");
    for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) {
        device.set("vct", preset, {20.0, 0.0});
        device.set("direct", preset, {5.0, 0.0});
    }
    SceneMeasurements scene;
    for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) scene.record_own_error("vct", preset, 1, 1e-4);
    PlanningInputs inputs{analysis, device, &scene, 64, 64, std::nullopt};
    inputs.priors = &priors_without_denoiser();  // the GPU plans' prices, not the reference's
    const Budget within_50{50.0, std::nullopt};
    const Plan warm = plan(inputs, within_50);
    ASSERT_EQ(warm.chosen.method, "vct") << warm.why;  // one bounce: more accurate than direct
    EXPECT_EQ(warm.chosen.redoes, FrameChange::none);
    EXPECT_EQ(plan_json(warm)["redoes"].get<std::string>(), "none");
    for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) {
        scene.record("vct", preset, 1, 200.0, 20.0, 64.0 * 64.0, FrameChange::lights);  // a relight: 180 ms more
    }
    inputs.change = [](const std::string& method, const std::string&, const methods::KnobValues&, int, int) {
        return method == "vct" ? FrameChange::lights : FrameChange::none;
    };
    const Plan relit = plan(inputs, within_50);
    EXPECT_EQ(relit.chosen.method, "direct") << relit.why;
    EXPECT_TRUE(relit.meets_budget);
    EXPECT_LE(relit.chosen.predicted_ms, 50.0);
    // Within a budget that holds the relight, vct again, priced with it and saying so.
    const Plan roomy = plan(inputs, {220.0, std::nullopt});
    ASSERT_EQ(roomy.chosen.method, "vct") << roomy.why;
    EXPECT_EQ(roomy.chosen.redoes, FrameChange::lights);
    EXPECT_NEAR(roomy.chosen.predicted_ms, 200.0, 1e-9);
    EXPECT_NE(roomy.why.find("redone"), std::string::npos) << roomy.why;
}

}  // namespace
}  // namespace bounce::planning
