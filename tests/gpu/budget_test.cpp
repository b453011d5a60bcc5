// Budgets hold on a small scene: a frame planned for a target error, rendered, is within that
// error of a converged reference. The Cornell box is not among the scenes the error model's priors
// were measured on (bench/corpus), so this is a held-out check of the promise.
//
// The device costs are made up: which plan is cheapest decides what is tested, not whether the
// error promise holds. GPU methods at a few milliseconds make the planner choose among them; the
// reference alone tests its noise model.
#include "gpu_fixture.hpp"
#include "renderer/base/error.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/planning/calibration.hpp"
#include "renderer/planning/planner.hpp"
#include "renderer/planning/resolution.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include <unistd.h>

namespace bounce::test {
namespace {

constexpr int kSize = 48;

// 512 samples through pixel centres with 12 bounces: its own noise adds about the noise per sample
// over 512 (under 0.002 on this box) to every relMSE measured against it, far under the targets.
const image::Frame& truth() {
    static const image::Frame frame = [] {
        methods::reference::PathTracerSettings settings;
        settings.max_bounces = 12;
        settings.seed = 99;
        return pixel_centre_reference(scene::make_cornell_box(), kSize, 512, settings);
    }();
    return frame;
}

// A millisecond for a draft, doubling with each preset: the planner takes the cheapest preset
// predicted to meet the target.
planning::DeviceCosts flat_gpu_costs() {
    planning::DeviceCosts device("made up");
    for (const char* method : {"direct", "vct", "isr", "cssm"}) {
        double ms = 1.0;
        for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) {
            device.set(method, preset, {ms, 0.0});
            ms *= 2.0;
        }
    }
    return device;
}

struct Measured {
    planning::Plan plan;
    double rel_mse = 0.0;
};

Measured plan_and_render(const scene::Scene& scene, const SceneAnalysis& analysis, double target,
                         std::optional<std::string> method) {
    const planning::DeviceCosts device = flat_gpu_costs();
    Measured measured;
    measured.plan = planning::plan({analysis, device, nullptr, kSize, kSize, method}, {std::nullopt, target});
    RenderRequest request = method_request(measured.plan.chosen.method, measured.plan.chosen.preset, kSize,
                                           measured.plan.chosen.knobs);
    const FramePlan frame_plan = plan_frame(request);
    const RenderResult result =
        frame_plan.site == FrameSite::cpu ? render_on_cpu(scene, request, frame_plan) : render_scene(scene, request);
    measured.rel_mse = image::compare(result.frame, truth()).rel_mse;
    ::testing::Test::RecordProperty("plan_" + std::to_string(target), measured.plan.why);
    ::testing::Test::RecordProperty("rel_mse_" + std::to_string(target), std::to_string(measured.rel_mse));
    return measured;
}

TEST(Budgets, ATargetErrorIsMetByTheGpuPlanChosenForIt) {
    const scene::Scene scene = scene::make_cornell_box();
    SceneAnalysis analysis = analyze_scene(scene);
    // The reference's cost is made up too, a thousand times what the analysis timed on this machine's
    // threads: on sixteen of them a 16-sample frame of this box (5.8 ms) undercut the GPU costs above.
    for (double& ns : analysis.bounces.sample_ns) ns *= 1000.0;
    // The priors are the largest own errors over the bench corpus, so on this box no GPU plan is
    // predicted under 0.05: the targets are those some GPU plan is predicted to meet.
    for (const double target : {0.15, 0.1}) {
        const Measured m = plan_and_render(scene, analysis, target, std::nullopt);
        ASSERT_TRUE(m.plan.meets_budget) << m.plan.why;
        EXPECT_NE(m.plan.chosen.method, "reference") << m.plan.why;  // the made-up costs favour the GPU
        EXPECT_LE(m.rel_mse, target) << m.plan.why;
    }
}

TEST(Budgets, ATargetErrorIsMetByTheReferencesSamplesChosenForIt) {
    const scene::Scene scene = scene::make_cornell_box();
    const SceneAnalysis analysis = analyze_scene(scene);
    for (const double target : {0.1, 0.02}) {
        const Measured m = plan_and_render(scene, analysis, target, "reference");
        ASSERT_TRUE(m.plan.meets_budget) << m.plan.why;
        EXPECT_LE(m.rel_mse, target) << m.plan.why;
        // And not far under it: relMSE falls as 1/spp, and a frame under E/8 traced over 8 times the
        // samples E needs, bar two factors of 2 the prediction may have: the analysis' noise
        // statistic reads up to twice a frame's (0.53 to 1.02 of it on the bench corpus,
        // docs/benchmarks.md), and at few samples one sample more can halve the error.
        EXPECT_GT(m.rel_mse, target / 8.0) << m.plan.why;
    }
}

// A denoised reference keeps its promise: at 128x128, the size the denoiser's bound was measured at
// (bench/denoise --every-scene, where the Cornell box's k was 0.048 of the 0.099 promised), each
// target is met by a denoised frame, against 512 samples of 12 bounces. The box is one of the
// scenes the bound was measured on, so this checks the arithmetic of the promise (bounces lacked,
// the noise model, the filter), not that the bound holds elsewhere: bench/planner --held-out does.
TEST(Budgets, ATargetErrorIsMetByADenoisedReference) {
    constexpr int kDenoisedSize = planning::kDenoisedLeastSide;
    const scene::Scene scene = scene::make_cornell_box();
    const SceneAnalysis analysis = analyze_scene(scene);
    methods::reference::PathTracerSettings settings;
    settings.max_bounces = 12;
    settings.seed = 99;
    const image::Frame converged = pixel_centre_reference(scene, kDenoisedSize, 512, settings);
    const planning::DeviceCosts device = flat_gpu_costs();
    for (const double target : {0.1, 0.05, 0.02}) {
        SCOPED_TRACE(target);
        const planning::Plan plan =
            planning::plan({analysis, device, nullptr, kDenoisedSize, kDenoisedSize, std::string("reference")},
                           {std::nullopt, target});
        ASSERT_TRUE(plan.meets_budget) << plan.why;
        ASSERT_EQ(plan.chosen.knobs.count("denoise"), 1u) << plan.why;
        EXPECT_EQ(plan.chosen.knobs.at("denoise"), 1.0) << plan.why;
        const RenderRequest request = method_request("reference", plan.chosen.preset, kDenoisedSize, plan.chosen.knobs);
        const RenderResult result = render_on_cpu(scene, request, plan_frame(request));
        const double error = image::compare(result.frame, converged).rel_mse;
        ::testing::Test::RecordProperty("denoised_" + std::to_string(target), plan.why + ": " + std::to_string(error));
        EXPECT_LE(error, target) << plan.why;
    }
}

// What upsampling loses, measured on a method's draft frames, is what it loses at the method's
// other presets (within the scatter between presets: measured under 10% on this box). isr's presets
// from low up make imperfect shadow maps and draft does not: the maps darken what the blocks hide,
// and high loses 0.83 to 0.84 of what draft lost. There the draft's figure is a bound, on the safe
// side of the error the planner promises, and the test holds it to that side alone.
TEST(Budgets, UpsamplingLosesWhatTheMethodsDraftFramesSay) {
    const scene::Scene scene = scene::make_cornell_box();
    auto resources = shared_renderer().upload(scene);
    constexpr int kLarge = 64;
    const std::vector<std::string> gpu_methods = {"direct", "vct", "isr", "cssm"};
    const auto errors = planning::measure_resample_errors(shared_renderer(), *resources,
                                                          method_request("direct", "draft", kLarge, {}), gpu_methods);
    for (const std::string& method : gpu_methods) {
        ASSERT_EQ(errors.at(method).size(), 2u) << method;  // 1/2 and 1/4: 32 and 16 pixels a side
        EXPECT_GT(errors.at(method).at(0.25), errors.at(method).at(0.5)) << method;
        const RenderRequest full = method_request(method, "high", kLarge, {});
        const image::Frame at_full = shared_renderer().render(*resources, full).frame;
        for (const auto& [scale, predicted] : errors.at(method)) {
            RenderRequest small = full;
            std::tie(small.width, small.height) = planning::scaled_size(kLarge, kLarge, scale);
            const RenderResult up = planning::upsampled(shared_renderer().render(*resources, small), kLarge, kLarge, small);
            const double lost = image::compare(up.frame, at_full).rel_mse;
            std::printf("%s high at 1/%g: upsampling loses %.4f, its draft %.4f\n", method.c_str(), 1.0 / scale, lost,
                        predicted);
            if (method == "isr") {
                EXPECT_LE(lost, 1.1 * predicted) << method << " high at 1/" << 1.0 / scale;
            } else {
                EXPECT_NEAR(lost, predicted, 0.1 * predicted) << method << " high at 1/" << 1.0 / scale;
            }
        }
    }
}

// Measuring upsampling renders each method's draft at three sizes; recorded, those frames give the
// scene its own cost line for the draft (the fixed and per-pixel parts of its cost here, which the
// planner then prices every size and preset of the method from).
TEST(Budgets, MeasuringUpsamplingGivesTheSceneACostLinePerMethod) {
    const scene::Scene scene = scene::make_cornell_box();
    auto resources = shared_renderer().upload(scene);
    planning::DeviceCosts device("made up");
    device.set("direct", "draft", {1.0, 1000.0});
    device.set("cssm", "draft", {1.0, 1000.0});
    planning::SceneMeasurements measurements;
    constexpr int kLarge = 64;
    planning::measure_resample_errors(shared_renderer(), *resources, method_request("direct", "draft", kLarge, {}),
                                      {"direct", "cssm"}, &measurements, &device);
    for (const auto& [method, bounces] : std::vector<std::pair<std::string, int>>{{"direct", -1}, {"cssm", 1}}) {
        std::set<double> sizes;
        for (const auto& frame : measurements.frames(method, "draft", bounces)) sizes.insert(frame.pixels);
        EXPECT_EQ(sizes, (std::set<double>{16.0 * 16.0, 32.0 * 32.0, 64.0 * 64.0})) << method;
        const auto line = measurements.line(method, "draft", bounces);
        ASSERT_TRUE(line.has_value()) << method;
        const SceneAnalysis analysis;
        const planning::PlanningInputs at_16{analysis, device, &measurements, 16, 16, std::nullopt};
        methods::KnobValues knobs;
        if (bounces >= 0) knobs["bounces"] = bounces;
        EXPECT_DOUBLE_EQ(planning::predicted_ms(at_16, method, "draft", knobs), line->at(16.0 * 16.0)) << method;
    }
}

// A plan at half size, the only one within the time, keeps its predicted error against the
// reference: upsampling's loss adds to the method's own and the bounces it lacks.
TEST(Budgets, APlanAtHalfSizeKeepsItsPredictedError) {
    const scene::Scene scene = scene::make_cornell_box();
    const SceneAnalysis analysis = analyze_scene(scene);
    auto resources = shared_renderer().upload(scene);
    planning::DeviceCosts device("made up");
    for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) device.set("cssm", preset, {0.0, 1e5});
    const planning::PlanningInputs inputs{
        analysis, device, nullptr, kSize, kSize, "cssm",
        planning::measure_resample_errors(shared_renderer(), *resources, method_request("cssm", "draft", kSize, {}), {"cssm"})};
    // 48x48 costs 230 ms; 24x24 58 ms.
    const planning::Plan plan = planning::plan(inputs, {100.0, std::nullopt});
    ASSERT_TRUE(plan.meets_budget) << plan.why;
    ASSERT_EQ(plan.chosen.scale, 0.5) << plan.why;
    EXPECT_NE(plan.why.find("at 1/2 size, upsampled"), std::string::npos) << plan.why;
    RenderRequest small = method_request("cssm", plan.chosen.preset, kSize, plan.chosen.knobs);
    std::tie(small.width, small.height) = planning::scaled_size(kSize, kSize, 0.5);
    const RenderResult up = planning::upsampled(shared_renderer().render(*resources, small), kSize, kSize, small);
    const double measured = image::compare(up.frame, truth()).rel_mse;
    std::printf("%s: measured %.4f\n", plan.why.c_str(), measured);
    EXPECT_LE(measured, plan.chosen.predicted_error) << plan.why;
}

// A calibration a step at a time: one preset per step, in order, and a model only once done.
TEST(Budgets, ACalibrationMeasuresOnePresetAStep) {
    planning::CalibrationSettings settings;
    settings.small_size = 8;
    settings.large_size = 16;
    settings.methods = {"direct"};
    planning::Calibration calibration(shared_renderer(), settings);
    EXPECT_EQ(calibration.next_step(), "direct draft");
    EXPECT_DOUBLE_EQ(calibration.fraction(), 0.0);
    EXPECT_THROW(calibration.result(), Error);
    const auto& presets = methods::preset_names();
    for (std::size_t i = 0; i < presets.size(); ++i) {
        EXPECT_EQ(calibration.next_step(), "direct " + presets[i]);
        EXPECT_EQ(calibration.step(shared_renderer()), i + 1 == presets.size());
        EXPECT_DOUBLE_EQ(calibration.fraction(), static_cast<double>(i + 1) / presets.size());
    }
    EXPECT_TRUE(calibration.step(shared_renderer()));  // done stays done
    EXPECT_EQ(calibration.next_step(), "calibrated");
    const planning::DeviceCosts costs = calibration.result();
    for (const std::string& preset : presets) EXPECT_TRUE(costs.line("direct", preset)) << preset;
    EXPECT_FALSE(costs.line("vct", "draft"));
    EXPECT_GT(costs.calibration_ms, 0.0);
}

// Calibration measures a line per preset (two methods here, at small sizes, to keep the test short)
// and what changes redo, and caches both under the renderer's name: the second call reads the file
// instead of measuring.
TEST(Budgets, CalibrationMeasuresEveryPresetAndIsCachedForTheDevice) {
    const auto dir = std::filesystem::temp_directory_path() / ("bounce-calibration-" + std::to_string(::getpid()));
    planning::CalibrationSettings settings;
    settings.small_size = 8;
    settings.large_size = 16;
    settings.change_frames = 1;
    settings.methods = {"direct", "vct"};
    const planning::DeviceCosts measured = planning::load_or_calibrate(shared_renderer(), dir, settings);
    EXPECT_EQ(measured.renderer(), shared_renderer().gpu_info().renderer);
    for (const char* method : {"direct", "vct"}) {
        for (const char* preset : {"draft", "low", "medium", "high", "ultra"}) {
            const auto line = measured.line(method, preset);
            ASSERT_TRUE(line) << method << " " << preset;
            EXPECT_GT(line->at(16 * 16), 0.0) << method << " " << preset;  // a frame takes time
            // What changes redo, timed at the larger size.
            const auto change = measured.change_cost(method, preset);
            ASSERT_TRUE(change) << method << " " << preset;
            EXPECT_DOUBLE_EQ(change->pixels, 16.0 * 16.0);
            for (const double multiple : {change->light_power, change->lights, change->rebuild}) {
                EXPECT_TRUE(std::isfinite(multiple) && multiple >= 0.0) << method << " " << preset << ": " << multiple;
            }
        }
    }
    EXPECT_FALSE(measured.line("cssm", "medium"));  // not asked for
    settings.methods = {"direct"};                  // would measure anew: the cache must answer instead
    const planning::DeviceCosts cached = planning::load_or_calibrate(shared_renderer(), dir, settings);
    EXPECT_DOUBLE_EQ(cached.calibration_ms, measured.calibration_ms);
    EXPECT_DOUBLE_EQ(cached.line("vct", "high")->fixed_ms, measured.line("vct", "high")->fixed_ms);
    EXPECT_DOUBLE_EQ(cached.change_cost("vct", "high")->rebuild, measured.change_cost("vct", "high")->rebuild);
    std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace bounce::test
