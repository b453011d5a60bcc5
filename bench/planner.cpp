// bounce_bench_planner: whether budgets hold on the bench scenes. Per scene it renders every fixed
// plan (each GPU method at each preset, the reference at 4 to 256 samples), measures each against
// the reference, then plans and renders a frame for each target error and each time budget, and
// compares: a target error E must be met, at no more than 1.5 times the time of the cheapest fixed
// plan that meets it (timed again right after the planned frame); a budget of T ms must be kept
// within 1.2 T, with error no worse than the best fixed plan within T by more than two frames of one
// plan differ by chance (Measured::rel_mse_spread).
// The fixed plans' frames are recorded as the daemon records frames, so the planner predicts from
// this scene's measured costs (and from the device's calibration for what it has not measured).
// Their errors are not given to the planner: it learns a GPU method's error on a scene only as the
// daemon does, by comparing its own frames of one view (planned frames, and the probes it renders
// beside a reference plan) with its reference frames, and from its spot checks: where a target
// error's plan is the reference and GPU plans may meet it (planning::spot_checks), they are tried
// first as the daemon tries them, and the request's time is the check's reference, every frame tried
// and, where none passed, the reference plan's frame. The budgets run in two passes: the second
// after the first's frames were compared; then the time budgets once more, each right after the
// lights change, with frames rendered as they come (what they redo priced and timed); then each
// right after a frame from a camera moved aside (the suns' view cascades drawn again).
#include "bench/common.hpp"
#include "bench/corpus.hpp"
#include "bench/corpus_priors.hpp"
#include "bench/markdown_blocks.hpp"
#include "bench/planner_rows.hpp"
#include "bench/reference_cache.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/planning/calibration.hpp"
#include "renderer/planning/comparisons.hpp"
#include "renderer/planning/error_model.hpp"
#include "renderer/planning/planner.hpp"
#include "renderer/planning/resolution.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene/builtin.hpp"

#include <algorithm>
#include <chrono>
#include <fstream>
#include <limits>
#include <memory>
#include <numeric>
#include <sstream>
#include <tuple>

namespace fs = std::filesystem;
using namespace bounce;

using bench::BudgetRow;
using bench::Measured;
using bench::changed_budget_row;
using bench::error_text;
using bench::judge_time_budget;
using bench::label;

namespace {

struct Options {
    int size = 128;
    // The references' own noise adds to every error measured against them: at 4096 spp it is at most
    // 0.0018 of relMSE on these scenes (noise per sample at 8 bounces under 7.3, scene analysis).
    int reference_spp = 4096;
    int reference_bounces = 8;
    fs::path cache = "build/bench-cache";
    fs::path out = "bench/results";
    fs::path markdown = "docs/benchmarks.md";
    std::vector<std::string> scenes;
    std::vector<double> errors = {0.1, 0.05, 0.02};
    std::vector<double> budgets_ms = {50, 200, 1000};
    bool analysis_only = false;  // print each scene's analysis and stop
    int analysis_spp = AnalysisSettings{}.bounce_spp;  // with --analysis-only: the analysis' samples per pixel
    int analysis_size = AnalysisSettings{}.bounce_image_size;  // with --analysis-only: its frames' side
    bool references_only = false;  // render (or read) each scene's reference and stop: fills the cache
    int passes = 2;
    // The relit passes: each time budget asked right after the lights change, after the same budget's
    // frame, then after another budget's.
    bool relit = true;
    // The moved-camera pass: each time budget asked of a view just left and come back to.
    bool moved = true;
    // With --camera-as-warm, the moved-camera pass plans as if a moved camera redid nothing, as the
    // planner did before FrameChange::view, at first sight (its frames are still kept out of the warm
    // lines, where before they raised them): what pricing the view cascades buys.
    bool camera_as_warm = false;
    // With --held-out, each scene is planned with the GPU methods' own-error priors of the other
    // corpus scenes, and for vct of the Cornell variants too (bench/corpus_priors.hpp, from
    // `corpus_results` and the files beside it): whether the promises hold on a scene the priors never
    // saw. Without, the committed priors, which every scene here made. The placement files
    // (bench/results/*_placement.csv) are read from beside `corpus_results`.
    bool held_out = false;
    fs::path corpus_results = "bench/results/corpus";
    // With --cornell, the bench's Cornell variants (bench/quality's scenes: the closed box, its glossy
    // and indirectly lit versions, the thin wall and the doorway) in place of the corpus. They count in
    // vct's priors (bench::cornell_vct_tables), and in isr's and cssm's where most indirect light is
    // occluded (OwnErrorPriors::occluded_largest); isr's and cssm's other priors are the corpus' alone.
    bool cornell = false;
};

// The scenes a run plans: the corpus, or with --cornell the Cornell variants.
std::vector<bench::BenchScene> planned_scenes(const Options& options) {
    return options.cornell ? bench::quality_scenes() : bench::corpus_scenes();
}

// The corpus' block of docs/benchmarks.md, and the Cornell variants' (--cornell).
constexpr std::string_view kBegin = "<!-- planner: bench/planner writes it -->";
constexpr std::string_view kEnd = "<!-- end of planner -->";
constexpr std::string_view kCornellBegin = "<!-- planner on the Cornell variants: bench/planner --cornell writes it -->";
constexpr std::string_view kCornellEnd = "<!-- end of planner on the Cornell variants -->";

// The key the planned frames and the spot checks file the scene's view by (FrameComparisons::add,
// record_spot_check): every compared frame here is of the scene's own camera at one size.
constexpr std::uint64_t kView = 1;

// A GPU idles at a fraction of its clock and raises it only after a while under load (an H200: 345
// against 1980 MHz). Right after the reference's CPU-only frames, an H200 took five times as long
// for the next GPU frames (isr draft on the atrium: nine frames of 5.9 ms, against 1.3 ms when
// measured among other GPU frames), so a plan timed there looked costlier than the same plan timed
// among the fixed plans, and its time taught the cost model the same. Before a GPU frame is timed,
// a frame of the Cornell box, on resources of its own, is rendered until its GPU time is within 25%
// of the fastest this run has seen (two frames at least, at most half a second): every plan is then
// timed at the clock the others were.
void warm_gpu_clock(Renderer& renderer) {
    static const scene::Scene cornell = scene::make_cornell_box();  // the resources refer to it
    static std::unique_ptr<SceneResources> probe_scene;
    static double fastest_ms = std::numeric_limits<double>::infinity();
    if (!probe_scene) probe_scene = renderer.upload(cornell);
    const RenderRequest probe = bench::linear_request("direct", "draft", {}, 256);
    const auto start = std::chrono::steady_clock::now();
    for (int frame = 0;; ++frame) {
        const FrameStats stats = renderer.render(*probe_scene, probe).stats;
        const double ms = stats.gpu_ms > 0.0 ? stats.gpu_ms : stats.render_ms;
        fastest_ms = std::min(fastest_ms, ms);
        const double elapsed_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
        if ((frame >= 1 && ms <= 1.25 * fastest_ms) || elapsed_ms > 500.0) return;
    }
}

// A frame rendered with every light scaled by `light_factor`, scaled back to the lights the truth
// was traced with (light transport is linear). relMSE is not scale-free: the 0.01 in its denominator
// weighs dark pixels less as the light grows, so a truth scaled with the light instead let the error
// creep up with each change of the pass (bench::change_every_light brightens by 1e-4 a change):
// direct draft in the glossy gallery read 0.0695 on its relit comparator's frames and 0.0701 on the
// planned frame some sixty changes later, the same plan.
image::Frame scaled_back(const image::Frame& frame, double light_factor) {
    image::Frame out = frame;
    for (std::size_t i = 0; i < out.rgba.size(); ++i) {
        if (i % 4 != 3) out.rgba[i] = static_cast<float>(out.rgba[i] / light_factor);
    }
    return out;
}

// Renders a plan as the daemon would (a warm frame for GPU methods), records its time in `costs`,
// and measures it against `truth`.
// With `comparisons`, the frame is also compared with the planner's other frames of the view.
Measured render_plan(Renderer& renderer, SceneResources& resources, const scene::Scene& scene, const SceneAnalysis& analysis,
                     const planning::DeviceCosts& device, planning::SceneMeasurements& costs, const std::string& method,
                     const std::string& preset, const methods::KnobValues& knobs, int size, const image::Frame& truth,
                     planning::FrameComparisons* comparisons = nullptr, double scale = 1.0,
                     image::Frame* kept_frame = nullptr, double light_factor = 1.0) {
    RenderRequest request = bench::linear_request(method, preset, knobs, size);
    std::tie(request.width, request.height) = planning::scaled_size(size, size, scale);
    const FramePlan frame_plan = plan_frame(request);
    if (frame_plan.site == FrameSite::gpu) warm_gpu_clock(renderer);
    // Frames under kRepeatBelowMs are rendered kRepeats times and the median kept (each recorded, as a
    // daemon records every frame): on a loaded two-core machine one frame of a few milliseconds varies
    // by more than the 1.5x and 1.2x that the budgets are judged by. Under kManyBelowMs, kManyRepeats:
    // the foliage's direct high took 2.5 ms as a fixed plan and 3.9 ms as a planned one, medians of three.
    // A reference's error is a draw of its noise: its repeats are traced with other seeds, and under
    // kSeedsBelowMs it is traced twice at least, so that its relMSE is the mean of two draws or more
    // and their spread is measured (Measured::rel_mse_spread).
    constexpr double kRepeatBelowMs = 500.0, kManyBelowMs = 20.0, kSeedsBelowMs = 5000.0;
    constexpr int kRepeats = 3, kManyRepeats = 9;
    const bool stochastic = method == "reference";
    const auto render_once = [&](int repeat) {
        RenderRequest once_request = request;
        if (stochastic && repeat > 0) once_request.knobs["seed"] = 1000 + repeat;
        RenderResult once = frame_plan.site == FrameSite::cpu ? render_on_cpu(scene, once_request, plan_frame(once_request))
                                                               : renderer.render(resources, once_request);
        planning::record_frame(costs, &analysis, device, once, request.width, request.height);
        return once;
    };
    // Builds the structures, recorded as the daemon records every frame: with what it redid
    // (FrameStats::change), apart from warm frames, and its shadow maps' time where it drew them.
    if (frame_plan.site == FrameSite::gpu) {
        planning::record_frame(costs, &analysis, device, renderer.render(resources, request), request.width, request.height);
    }
    std::vector<RenderResult> results;
    results.push_back(render_once(0));
    const double first_ms = results.front().stats.render_ms;
    const std::size_t repeats = first_ms < kManyBelowMs ? kManyRepeats : first_ms < kRepeatBelowMs ? kRepeats
                                : stochastic && first_ms < kSeedsBelowMs ? 2 : 1;
    while (results.size() < repeats) results.push_back(render_once(static_cast<int>(results.size())));
    const auto error_of = [&](const RenderResult& rendered) {
        const image::Frame& frame =
            scale != 1.0 ? planning::upsampled(rendered, size, size, request).frame : rendered.frame;
        return image::compare(scaled_back(frame, light_factor), truth).rel_mse;
    };
    std::vector<double> errors, times;
    for (const RenderResult& rendered : results) {
        errors.push_back(error_of(rendered));
        times.push_back(rendered.stats.render_ms);
    }
    std::sort(times.begin(), times.end());
    // Kept: a GPU plan's frame of the median time; a reference's frame of its own seed, as the daemon
    // renders it (the others' seeds are the bench's).
    std::size_t kept = 0;
    if (!stochastic) {
        kept = static_cast<std::size_t>(std::find_if(results.begin(), results.end(), [&](const RenderResult& r) {
                                            return r.stats.render_ms == times[times.size() / 2];
                                        }) - results.begin());
    }
    RenderResult result = std::move(results[kept]);
    const std::size_t middle = times.size() / 2;  // of an even count, the mean of the middle two
    result.stats.render_ms = times.size() % 2 == 1 ? times[middle] : 0.5 * (times[middle - 1] + times[middle]);
    if (scale != 1.0) result = planning::upsampled(result, size, size, request);
    // GPU frames: the kept frame's error; references: the mean of their seeds'.
    const double error = stochastic ? std::accumulate(errors.begin(), errors.end(), 0.0) / static_cast<double>(errors.size())
                                    : image::compare(scaled_back(result.frame, light_factor), truth).rel_mse;
    const auto [least, most] = std::minmax_element(errors.begin(), errors.end());
    const std::string name = label(method, preset, knobs) + (scale != 1.0 ? fmt::format(" at 1/{:g} size", 1.0 / scale) : "");
    log::info("bench", "{}: {:.1f} ms, relMSE {:.4f}{}", name, result.stats.render_ms, error,
              errors.size() > 1 && *most > *least ? fmt::format(" ({} frames, {:.4f} to {:.4f})", errors.size(), *least, *most) : "");
    Measured measured{name, result.stats.render_ms, error, *most - *least, method, preset, knobs};
    measured.scale = scale;
    if (kept_frame) *kept_frame = result.frame;
    if (comparisons && scale == 1.0) {
        comparisons->add(kView, std::make_shared<const RenderResult>(std::move(result)), &analysis, costs);
    }
    return measured;
}

// The next change of every light (bench::change_every_light), counted in `changes`.
double change_lights(scene::Scene& scene, const std::vector<scene::Light>& original, int& changes) {
    return bench::change_every_light(scene, original, ++changes);
}

// A frame as the daemon renders it on request: not warmed first, timed once, recorded with what it
// redid (FrameStats::change), measured against `truth`.
Measured render_as_it_comes(Renderer& renderer, SceneResources& resources, const scene::Scene& scene,
                            const SceneAnalysis& analysis, const planning::DeviceCosts& device,
                            planning::SceneMeasurements& costs, const planning::Candidate& plan, int size,
                            const image::Frame& truth, double light_factor,
                            const std::optional<scene::Camera>& camera = std::nullopt) {
    RenderRequest request = bench::linear_request(plan.method, plan.preset, plan.knobs, size);
    request.camera = camera;
    std::tie(request.width, request.height) = planning::scaled_size(size, size, plan.scale);
    const FramePlan frame_plan = plan_frame(request);
    if (frame_plan.site == FrameSite::gpu) warm_gpu_clock(renderer);
    RenderResult result = frame_plan.site == FrameSite::cpu ? render_on_cpu(scene, request, frame_plan)
                                                             : renderer.render(resources, request);
    planning::record_frame(costs, &analysis, device, result, request.width, request.height);
    if (plan.scale != 1.0) result = planning::upsampled(result, size, size, request);
    Measured measured{label(plan.method, plan.preset, plan.knobs) +
                          (plan.scale != 1.0 ? fmt::format(" at 1/{:g} size", 1.0 / plan.scale) : ""),
                      result.stats.render_ms, image::compare(scaled_back(result.frame, light_factor), truth).rel_mse, 0.0,
                      plan.method, plan.preset,
                      plan.knobs};
    measured.scale = plan.scale;
    // A reference's error is a draw of its noise, as a warm one's is (render_plan, which traces it
    // with several seeds): its spread is measured by tracing it again with another seed, not timed
    // and not recorded (a daemon would not trace it), so that the noise floor judges it as it judges
    // the others. The frame sent keeps its own error. Only the moved-camera pass renders a reference
    // as it comes.
    if (plan.method == "reference" && frame_plan.site == FrameSite::cpu) {
        RenderRequest again = request;
        again.knobs["seed"] = 1001;
        RenderResult other = render_on_cpu(scene, again, plan_frame(again));
        if (plan.scale != 1.0) other = planning::upsampled(other, size, size, again);
        const double other_error = image::compare(scaled_back(other.frame, light_factor), truth).rel_mse;
        measured.rel_mse_spread = std::abs(other_error - measured.rel_mse);
        log::info("bench", "{}: another seed read relMSE {:.5f}", measured.label, other_error);
    }
    log::info("bench", "{}: {:.1f} ms as it came (redid {}), relMSE {:.5f}", measured.label, measured.ms,
              to_string(result.stats.change), measured.rel_mse);
    return measured;
}

// A fixed GPU plan's frame right after the lights changed, its structures built: of three such
// frames (each after a warm frame and a change), the one of the median time, with its error against
// the truth scaled as its lights were, as the planned frame of the pass is measured (a light moved
// by 1e-5 of the scene can still move a method's error by a percent or two: isr draft in the
// furnished room read 0.2168 warm and 0.2131 right after such a change).
// Not recorded: a daemon would not render it.
Measured relit_fixed_plan(Renderer& renderer, SceneResources& resources, scene::Scene& scene,
                          const std::vector<scene::Light>& original, int& changes, const Measured& fixed, int size,
                          const image::Frame& truth) {
    const RenderRequest request = bench::linear_request(fixed.method, fixed.preset, fixed.knobs, size);
    std::vector<std::pair<double, double>> frames;  // ms, relMSE
    warm_gpu_clock(renderer);
    for (int repeat = 0; repeat < 3; ++repeat) {
        renderer.render(resources, request);
        const double factor = change_lights(scene, original, changes);
        const RenderResult result = renderer.render(resources, request);
        frames.emplace_back(result.stats.render_ms, image::compare(scaled_back(result.frame, factor), truth).rel_mse);
    }
    std::sort(frames.begin(), frames.end());
    Measured relit = fixed;
    std::tie(relit.ms, relit.rel_mse) = frames[1];
    // Its noise floor: how much the plan's frames differ from one change of the lights to the next.
    // isr ultra in the atrium read 0.12207 and 0.12199 after two changes, the same plan.
    const auto [least, most] = std::minmax_element(frames.begin(), frames.end(),
                                                   [](const auto& a, const auto& b) { return a.second < b.second; });
    relit.rel_mse_spread = most->second - least->second;
    return relit;
}

// The scene's camera moved aside by 2% of the scene's diagonal, as a client's preview moves it from
// one frame to the next: far more than a cascade's texel, so every sun's view cascades are fitted
// anew.
scene::Camera moved_aside(const scene::Camera& camera, const scene::Aabb& bounds) {
    scene::Camera aside = camera;
    aside.position += 0.02f * glm::length(bounds.extent()) * (camera.orientation * glm::vec3(1.0f, 0.0f, 0.0f));
    return aside;
}

// A fixed GPU plan's frame of the scene's view right after a frame from `aside`: of three such
// frames (each after a warm frame at the view), the one of the median time, with its error.
// Not recorded: a daemon would not render it.
Measured moved_fixed_plan(Renderer& renderer, SceneResources& resources, const Measured& fixed, int size,
                          const image::Frame& truth, const scene::Camera& aside) {
    const RenderRequest request = bench::linear_request(fixed.method, fixed.preset, fixed.knobs, size);
    RenderRequest aside_request = request;
    aside_request.camera = aside;
    std::vector<std::pair<double, double>> frames;  // ms, relMSE
    warm_gpu_clock(renderer);
    for (int repeat = 0; repeat < 3; ++repeat) {
        renderer.render(resources, request);
        renderer.render(resources, aside_request);
        const RenderResult result = renderer.render(resources, request);
        frames.emplace_back(result.stats.render_ms, image::compare(result.frame, truth).rel_mse);
    }
    std::sort(frames.begin(), frames.end());
    Measured moved = fixed;
    std::tie(moved.ms, moved.rel_mse) = frames[1];
    return moved;
}

}  // namespace

int main(int argc, char** argv) {
    bench::Arguments arguments(argc, argv, "bounce_bench_planner", "build/bench/bounce_bench_planner");
    Options options;
    while (arguments.next()) {
        const std::string& flag = arguments.flag();
        if (flag == "--size") options.size = arguments.number();
        else if (flag == "--reference-spp") options.reference_spp = arguments.number();
        else if (flag == "--reference-bounces") options.reference_bounces = arguments.number();
        else if (flag == "--cache") options.cache = arguments.value();
        else if (flag == "--out") options.out = arguments.value();
        else if (flag == "--markdown") options.markdown = arguments.value();
        else if (flag == "--scene") options.scenes.push_back(arguments.value());
        else if (flag == "--errors") options.errors = bench::numbers(arguments.value());
        else if (flag == "--budgets-ms") options.budgets_ms = bench::numbers(arguments.value());
        else if (flag == "--analysis-only") options.analysis_only = true;
        else if (flag == "--analysis-spp") options.analysis_spp = std::max(2, static_cast<int>(arguments.number()));
        else if (flag == "--analysis-size") options.analysis_size = std::max(4, static_cast<int>(arguments.number()));
        else if (flag == "--references-only") options.references_only = true;
        else if (flag == "--passes") options.passes = arguments.number();
        else if (flag == "--no-relit") options.relit = false;
        else if (flag == "--no-moved") options.moved = false;
        else if (flag == "--camera-as-warm") options.camera_as_warm = true;
        else if (flag == "--held-out") options.held_out = true;
        else if (flag == "--corpus-results") options.corpus_results = arguments.value();
        else if (flag == "--cornell") options.cornell = true;
        else {
            std::fprintf(stderr,
                         "usage: bounce_bench_planner [--size N] [--reference-spp N] [--reference-bounces N] [--cache DIR] "
                         "[--cornell] [--scene NAME]... [--errors E,E] [--budgets-ms T,T] [--passes N] [--no-relit] "
                         "[--no-moved | --camera-as-warm] "
                         "[--held-out [--corpus-results DIR]] [--out DIR] [--markdown FILE] "
                         "[--analysis-only [--analysis-spp N] [--analysis-size N] | --references-only]\n");
            return 2;
        }
    }
    if (options.held_out && (options.out == Options{}.out || options.markdown == Options{}.markdown)) {
        // Its results are not the committed run's: it must not write over bench/results/planner.csv.
        std::fprintf(stderr, "bounce_bench_planner: --held-out needs an --out and a --markdown of its own\n");
        return 2;
    }
    if (options.cornell && (options.held_out || options.out == Options{}.out)) {
        // bench/results/planner.csv is the corpus'. Their block of the markdown is their own. Held out, the
        // occluded tables they make would be left empty (corpus_priors makes no such tables).
        std::fprintf(stderr, "bounce_bench_planner: --cornell needs an --out of its own (its files are not the corpus' "
                             "bench/results/planner.csv), and no --held-out (held out, the tables the Cornell variants "
                             "make where light is occluded would be empty)\n");
        return 2;
    }
    try {
        if (options.analysis_only) {
            for (const bench::BenchScene& bench_scene : planned_scenes(options)) {
                AnalysisSettings settings;
                settings.bounce_spp = options.analysis_spp;
                settings.bounce_image_size = options.analysis_size;
                const SceneAnalysis a = analyze_scene(bench_scene.scene, settings);
                std::string leaks;
                for (const auto& [preset, walls] : a.thin_walls.presets) {
                    if (a.thin_walls.leaks(preset)) leaks += " " + preset;
                }
                fmt::print("{}: {:.0f} ms, tracer built in {:.2f} ms, stopped error {}, noise {}, sample ns {}, occluded {:.3f} "
                           "({} pairs), leaks:{}\n",
                           bench_scene.name, a.analysis_ms, a.bounces.tracer_build_ms, fmt::join(a.bounces.stopped_error, " "),
                           fmt::join(a.bounces.noise_per_sample, " "), fmt::join(a.bounces.sample_ns, " "),
                           a.visibility.occluded_fraction, a.visibility.pairs, leaks);
            }
            return 0;
        }
        if (options.references_only) {
            for (const bench::BenchScene& bench_scene : planned_scenes(options)) {
                if (!options.scenes.empty() &&
                    std::find(options.scenes.begin(), options.scenes.end(), bench_scene.name) == options.scenes.end()) {
                    continue;
                }
                bench::reference_image(bench_scene, methods::reference::PathTracer(bench_scene.scene),
                                       {options.size, options.reference_spp, true, options.cache}, options.reference_bounces);
            }
            return 0;
        }
        Renderer renderer(gpu::DeviceChoice::resolve(std::nullopt));
        const planning::DeviceCosts device = planning::load_or_calibrate(renderer, options.cache);
        const std::map<std::string, ThinWalls> corpus_walls =
            options.held_out ? bench::bench_thin_walls() : std::map<std::string, ThinWalls>{};
        // The committed priors count each corpus scene over placements of cssm's atlas and vct's grid
        // (bench/corpus_priors.hpp); the held-out ones do too, from the placement files beside the corpus'.
        const bench::PlacementErrors corpus_placements =
            options.held_out ? bench::read_placement_errors(bench::placement_files(options.corpus_results / ".."))
                             : bench::PlacementErrors{};
        std::vector<BudgetRow> rows;
        std::vector<std::pair<std::string, Measured>> fixed_rows;  // scene, fixed plan: the Pareto plot's points
        std::string analysis_md =
            "| scene | analysis ms | stopped error at 0 / 1 / 2 / 4 bounces | reference noise per sample (4 bounces) | "
            "occluded (weighted) | vct leaks at |\n|---|---|---|---|---|---|\n";
        for (const bench::BenchScene& bench_scene : planned_scenes(options)) {
            if (!options.scenes.empty() &&
                std::find(options.scenes.begin(), options.scenes.end(), bench_scene.name) == options.scenes.end()) {
                continue;
            }
            scene::Scene scene = bench_scene.scene;  // the relit passes change its lights
            const std::vector<scene::Light> original_lights = scene.lights;
            int light_changes = 0;
            const methods::reference::PathTracer tracer(scene);
            const image::Frame truth = bench::reference_image(
                bench_scene, tracer, {options.size, options.reference_spp, true, options.cache}, options.reference_bounces);
            const SceneAnalysis analysis = analyze_scene(scene);
            const auto& e = analysis.bounces.stopped_error;
            std::string leaks;
            for (const auto& [preset, walls] : analysis.thin_walls.presets) {
                if (analysis.thin_walls.leaks(preset)) leaks += (leaks.empty() ? "" : ", ") + preset;
            }
            analysis_md += fmt::format("| {} | {:.0f} | {:.3f} / {:.3f} / {:.3f} / {:.3f} | {:.3f} | {:.2f} | {} |\n",
                                       bench_scene.name, analysis.analysis_ms, e[0], e[1], e[2], e[4],
                                       analysis.bounces.noise_per_sample[4], analysis.visibility.occluded_fraction,
                                       leaks.empty() ? "none" : leaks);
            auto resources = renderer.upload(scene);
            planning::SceneMeasurements costs;
            std::vector<Measured> fixed;
            for (const std::string& method : methods::MethodRegistry::builtin().names()) {
                if (method == "reference") {
                    for (const std::string preset : {"draft", "low", "medium", "high"}) {
                        fixed.push_back(render_plan(renderer, *resources, scene, analysis, device, costs, method, preset,
                                                    {{"pixel_jitter", 0}}, options.size, truth));
                        fixed.back().label = "reference " + preset;
                    }
                    continue;
                }
                for (const std::string& preset : methods::preset_names()) {
                    fixed.push_back(render_plan(renderer, *resources, scene, analysis, device, costs, method, preset, {},
                                                options.size, truth));
                }
            }
            for (const Measured& m : fixed) fixed_rows.push_back({bench_scene.name, m});
            planning::PlanningInputs inputs{
                analysis, device, &costs, options.size, options.size, std::nullopt,
                planning::measure_resample_errors(renderer, *resources, bench::linear_request("direct", "draft", {}, options.size),
                                                  {"direct", "vct", "isr", "cssm"}, &costs, &device)};
            const planning::OwnErrorPriors held_out_priors =
                options.held_out ? bench::corpus_priors(options.corpus_results, corpus_walls, {bench_scene.name},
                                                        /*two_bounce_table=*/true, corpus_placements,
                                                        {bench::cornell_vct_tables(options.corpus_results / "..")})
                                 : planning::OwnErrorPriors{};
            if (options.held_out) inputs.priors = &held_out_priors;
            // As the daemon plans: a plan the memory budget would refuse is ruled out.
            inputs.memory = [&](const std::string& method, const std::string& preset, const methods::KnobValues& knobs,
                                int width, int height) {
                RenderRequest request = bench::linear_request(method, preset, knobs, width);
                request.height = height;
                return renderer.memory_refusal(*resources, request);
            };
            planning::FrameComparisons comparisons;
            int pass = 1;
            const auto run = [&](const planning::Budget& budget, const std::string& text) {
                const planning::Plan plan = planning::plan(inputs, budget);
                BudgetRow row;
                row.pass = pass;
                row.scene = bench_scene.name;
                row.budget = text;
                row.plan = label(plan.chosen.method, plan.chosen.preset, plan.chosen.knobs) +
                           (plan.chosen.scale != 1.0 ? fmt::format(" at 1/{:g} size", 1.0 / plan.chosen.scale) : "");
                row.predicted_ms = plan.chosen.predicted_ms;
                row.predicted_error = plan.chosen.predicted_error;
                row.why = plan.why;
                log::info("bench", "{} pass {}, {}: {}", bench_scene.name, pass, text, plan.why);
                // Checked plans, as the daemon renders them: the check's reference, then each plan until one
                // passes; the request's time is all of it, and the reference plan's where none passes.
                double checking_ms = 0.0;
                bool checked = false;
                if (plan.spot_check) {
                    const planning::SpotReference spot = planning::trace_spot_reference(
                        scene, bench::linear_request("reference", "medium", {}, options.size), *plan.spot_check);
                    checking_ms = spot.ms;
                    double predicted_ms = plan.spot_check->predicted_ms;
                    for (const planning::Candidate& candidate : plan.checks) {
                        if (planning::ruled_out_by_measurements(costs, analysis, candidate.method, candidate.preset,
                                                                candidate.knobs, *budget.max_error)) {
                            continue;
                        }
                        image::Frame frame;
                        const Measured tried = render_plan(renderer, *resources, scene, analysis, device, costs,
                                                           candidate.method, candidate.preset, candidate.knobs,
                                                           options.size, truth, &comparisons, 1.0, &frame);
                        checking_ms += tried.ms;
                        const planning::SpotEstimate estimate =
                            planning::estimate(frame, spot.estimates, plan.spot_check->stopped_error);
                        // The same pixels against the truth, no noise: what the choice of pixels alone reads.
                        methods::reference::PixelEstimates at_truth = spot.estimates;
                        for (std::size_t i = 0; i < at_truth.pixels.size(); ++i) {
                            const float* p = &truth.rgba[static_cast<std::size_t>(at_truth.pixels[i]) * 4];
                            for (int half = 0; half < 2; ++half) {
                                at_truth.mean[half][i] = glm::dvec3(p[0], p[1], p[2]);
                                at_truth.variance[half][i] = glm::dvec3(0.0);
                            }
                        }
                        const planning::SpotEstimate pixels_alone = planning::estimate(frame, at_truth);
                        planning::record_spot_check(costs, analysis.bounces.stopped_error, candidate.method,
                                                    candidate.preset, candidate.knobs, *plan.spot_check, estimate,
                                                    kView);
                        log::info("bench", "{} pass {}, {}: {} ({:.1f} ms): {}; measures {:.4f} ({:.4f} +- {:.4f} at "
                                  "the check's pixels against the truth)", bench_scene.name, pass, text, tried.label,
                                  tried.ms, planning::describe(*plan.spot_check, estimate), tried.rel_mse,
                                  pixels_alone.rel_mse, pixels_alone.standard_error);
                        row.checks += fmt::format("{}{} {:.4f}{}", row.checks.empty() ? "" : "; ", tried.label,
                                                  estimate.bound, estimate.passes(*budget.max_error) ? " passed" : "");
                        predicted_ms += candidate.predicted_ms;
                        if (estimate.passes(*budget.max_error)) {
                            row.predicted_ms = predicted_ms;
                            row.predicted_error = estimate.bound;
                            row.planned = tried;
                            row.planned.ms = checking_ms;
                            row.plan = tried.label + " (spot-checked)";
                            checked = true;
                            break;
                        }
                    }
                    row.check_ms = spot.ms;
                }
                if (!checked) {
                    row.planned = render_plan(renderer, *resources, scene, analysis, device, costs, plan.chosen.method,
                                              plan.chosen.preset, plan.chosen.knobs, options.size, truth, &comparisons,
                                              plan.chosen.scale);
                    row.planned.ms += checking_ms;
                }
                for (const planning::Candidate& probe : plan.probes) {
                    render_plan(renderer, *resources, scene, analysis, device, costs, probe.method, probe.preset, probe.knobs,
                                options.size, truth, &comparisons);
                }
                return row;
            };
            for (; pass <= options.passes; ++pass) {
            for (const double error : options.errors) {
                BudgetRow row = run({std::nullopt, error}, fmt::format("relMSE ≤ {:g}", error));
                row.met = row.planned.rel_mse <= error;
                for (const Measured& m : fixed) {
                    if (m.rel_mse <= error && (!row.fixed || m.ms < row.fixed->ms)) row.fixed = m;
                }
                if (row.fixed) {
                    // Not recorded in the scene's measurements: a daemon would not render it.
                    planning::SceneMeasurements untouched;
                    row.fixed->ms_again = render_plan(renderer, *resources, scene, analysis, device, untouched,
                                                      row.fixed->method, row.fixed->preset, row.fixed->knobs, options.size,
                                                      truth)
                                              .ms;
                }
                row.holds = row.met && (!row.fixed || row.planned.ms <= 1.5 * row.fixed->comparator_ms());
                row.holds_strictly = row.holds;
                rows.push_back(row);
            }
            for (const double budget : options.budgets_ms) {
                BudgetRow row = run({budget, std::nullopt}, fmt::format("≤ {:g} ms", budget));
                judge_time_budget(row, budget, fixed);
                rows.push_back(row);
            }
            }
            // The relit passes: each time budget asked right after the lights changed, the frame rendered as
            // it comes (what it redoes, and a switch of method or preset, included); the comparator is
            // the most accurate fixed plan whose relit frame fits, timed and measured the same way.
            // First as a client with a budget meets a change: its previous frame was the same budget's
            // (the planner may keep that plan's structures or switch); then right after another budget's
            // frame, where every plan but the last one's switches.
            if (options.relit && !options.budgets_ms.empty()) {
                const double largest = *std::max_element(options.budgets_ms.begin(), options.budgets_ms.end());
                std::vector<Measured> relit_fixed;
                for (const Measured& m : fixed) {
                    if (m.ms > largest) continue;
                    const Measured relit = m.method == "reference"
                                               ? m
                                               : relit_fixed_plan(renderer, *resources, scene, original_lights,
                                                                  light_changes, m, options.size, truth);
                    log::info("bench", "{} fixed {}: {:.1f} ms warm, {:.1f} ms relit (relMSE {:.4f}, {:.4f} relit)",
                              bench_scene.name, m.label, m.ms, relit.ms, m.rel_mse, relit.rel_mse);
                    relit_fixed.push_back(relit);
                }
                planning::PlanningInputs relit_inputs = inputs;
                // The lights as the comparators' frames left them (their last change, set again: no change).
                double light_factor =
                    light_changes > 0 ? bench::change_every_light(scene, original_lights, light_changes) : 1.0;
                // A frame as the daemon renders it for `budget`, with the lights as they are now.
                const auto plan_and_render = [&](double budget) {
                    // Of the scene as it is now, seen from its camera.
                    relit_inputs.change = planning::changes_on(
                        *resources, resources->view_of(bench::linear_request("direct", "draft", {}, options.size)).camera);
                    const planning::Plan plan = planning::plan(relit_inputs, {budget, std::nullopt});
                    // The reference keeps nothing between frames: rendered as in the other passes (its
                    // error the mean over seeds); a GPU plan as it comes.
                    const Measured frame =
                        plan.chosen.method == "reference"
                            ? render_plan(renderer, *resources, scene, analysis, device, costs, plan.chosen.method,
                                          plan.chosen.preset, plan.chosen.knobs, options.size, truth, nullptr, 1.0, nullptr,
                                          light_factor)
                            : render_as_it_comes(renderer, *resources, scene, analysis, device, costs, plan.chosen,
                                                 options.size, truth, light_factor);
                    return std::pair{plan, frame};
                };
                for (const bool after_its_own : {true, false}) {
                    for (const double budget : options.budgets_ms) {
                        // A client that has asked this budget a while: its frames, as they come, until one
                        // redoes nothing (the comparators' frames moved the lights and switched presets
                        // since pass 2), three at most.
                        for (int before = 0; after_its_own && before < 3; ++before) {
                            const auto [steady, frame] = plan_and_render(budget);
                            log::info("bench", "{} before the change, ≤ {:g} ms: {} (redid {}, {:.1f} ms)",
                                      bench_scene.name, budget, frame.label, to_string(steady.chosen.redoes), frame.ms);
                            if (steady.chosen.redoes == FrameChange::none) break;
                        }
                        light_factor = change_lights(scene, original_lights, light_changes);
                        const auto [plan, planned] = plan_and_render(budget);
                        rows.push_back(changed_budget_row(
                            options.passes + (after_its_own ? 1 : 2), bench_scene.name,
                            fmt::format("≤ {:g} ms, relit{}", budget, after_its_own ? "" : " after another budget"), plan,
                            planned, budget, relit_fixed));
                    }
                }
                scene.lights = original_lights;
            }
            // The moved-camera pass: each time budget asked of the scene's view by a client that had it
            // a while, then moved the camera aside for a frame and back. The frame back redraws the
            // suns' view cascades (FrameChange::view); the comparator is the most accurate fixed plan
            // whose frame back fits, timed and measured the same way.
            if (options.moved && !options.budgets_ms.empty()) {
                const double largest = *std::max_element(options.budgets_ms.begin(), options.budgets_ms.end());
                const scene::Camera aside =
                    moved_aside(camera_for(scene, bench::linear_request("direct", "draft", {}, options.size)),
                                scene.world_bounds());
                std::vector<Measured> moved_fixed;
                for (const Measured& m : fixed) {
                    if (m.ms > largest) continue;
                    moved_fixed.push_back(m.method == "reference"
                                              ? m
                                              : moved_fixed_plan(renderer, *resources, m, options.size, truth, aside));
                    log::info("bench", "{} fixed {}: {:.1f} ms warm, {:.1f} ms back from a view aside", bench_scene.name,
                              m.label, m.ms, moved_fixed.back().ms);
                }
                planning::PlanningInputs moved_inputs = inputs;
                // A frame as the daemon renders it for `budget`, seen from `camera` (the scene's own: none).
                const auto plan_and_render = [&](double budget, const std::optional<scene::Camera>& camera) {
                    RenderRequest seen = bench::linear_request("direct", "draft", {}, options.size);
                    seen.camera = camera;
                    moved_inputs.change = planning::changes_on(*resources, resources->view_of(seen).camera);
                    if (options.camera_as_warm) {
                        moved_inputs.change = [changes = moved_inputs.change](const std::string& method,
                                                                              const std::string& preset,
                                                                              const methods::KnobValues& knobs,
                                                                              int width, int height) {
                            const FrameChange change = changes(method, preset, knobs, width, height);
                            return change == FrameChange::view             ? FrameChange::none
                                   : change == FrameChange::knobs_and_view ? FrameChange::knobs
                                                                           : change;
                        };
                    }
                    const planning::Plan plan = planning::plan(moved_inputs, {budget, std::nullopt});
                    const Measured frame =
                        plan.chosen.method == "reference" && !camera
                            ? render_plan(renderer, *resources, scene, analysis, device, costs, plan.chosen.method,
                                          plan.chosen.preset, plan.chosen.knobs, options.size, truth)
                            : render_as_it_comes(renderer, *resources, scene, analysis, device, costs, plan.chosen,
                                                 options.size, truth, 1.0, camera);
                    return std::pair{plan, frame};
                };
                for (const double budget : options.budgets_ms) {
                    // A client that had the view a while: its plan the one a warm frame would have
                    // (the comparators' frames since switched every method's structures), then its
                    // frames as they come until one redoes nothing.
                    const planning::Plan settled = planning::plan(inputs, {budget, std::nullopt});
                    if (settled.chosen.method != "reference") {
                        render_as_it_comes(renderer, *resources, scene, analysis, device, costs, settled.chosen,
                                           options.size, truth, 1.0);
                    }
                    for (int before = 0; before < 3; ++before) {
                        const auto [steady, frame] = plan_and_render(budget, std::nullopt);
                        if (steady.chosen.redoes == FrameChange::none) break;
                    }
                    const auto [away, away_frame] = plan_and_render(budget, aside);
                    log::info("bench", "{} aside, ≤ {:g} ms: {} (redid {}, {:.1f} ms; its error is not of this view)",
                              bench_scene.name, budget, away_frame.label, to_string(away.chosen.redoes), away_frame.ms);
                    const auto [plan, planned] = plan_and_render(budget, std::nullopt);
                    rows.push_back(changed_budget_row(options.passes + (options.relit ? 3 : 1), bench_scene.name,
                                                      fmt::format("≤ {:g} ms, camera moved", budget), plan, planned, budget,
                                                      moved_fixed));
                }
            }
            std::string ratios;
            for (const auto& [bounces, ratio] : costs.noise_ratios()) ratios += fmt::format(" {}:{:.2f}", bounces, ratio);
            log::info("bench", "{}: reference noise measured / analysed, by bounces:{}", bench_scene.name, ratios);
        }
        fs::create_directories(options.out);
        std::ofstream fixed_csv(options.out / "planner_fixed.csv");
        fixed_csv << "scene,plan,measured_ms,measured_rel_mse,rel_mse_spread\n";
        for (const auto& [scene_name, m] : fixed_rows) {
            fixed_csv << fmt::format("{},\"{}\",{:.2f},{:.5f},{:.5f}\n", scene_name, m.label, m.ms, m.rel_mse, m.rel_mse_spread);
        }
        std::ofstream csv(options.out / "planner.csv");
        csv << "pass,scene,budget,plan,predicted_ms,predicted_rel_mse,measured_ms,measured_rel_mse,met,fixed_plan,fixed_ms,"
               "fixed_rel_mse,holds,holds_strictly,measured_rel_mse_spread,fixed_rel_mse_spread,fixed_ms_again,checks,check_ms\n";
        std::string table = "| pass | scene | budget | plan | predicted ms / relMSE | measured ms / relMSE | met | comparator: fixed plan, ms / relMSE | holds |\n"
                            "|---|---|---|---|---|---|---|---|---|\n";
        std::map<int, std::tuple<int, int, int>> holding;  // per pass: holds, holds strictly, rows
        for (const BudgetRow& r : rows) {
            csv << fmt::format("{},{},\"{}\",\"{}\",{:.2f},{:.5f},{:.2f},{:.5f},{},\"{}\",{:.2f},{:.5f},{},{},{:.5f},{:.5f},{:.2f},\"{}\",{:.2f}\n",
                               r.pass, r.scene, r.budget, r.plan, r.predicted_ms, r.predicted_error, r.planned.ms,
                               r.planned.rel_mse, r.met, r.fixed ? r.fixed->label : "", r.fixed ? r.fixed->ms : 0.0,
                               r.fixed ? r.fixed->rel_mse : 0.0, r.holds, r.holds_strictly, r.planned.rel_mse_spread,
                               r.fixed ? r.fixed->rel_mse_spread : 0.0, r.fixed ? r.fixed->ms_again : 0.0, r.checks,
                               r.check_ms);
            table += fmt::format("| {} | {} | {} | {} | {:.0f} / {:.3f} | {:.0f} / {} | {} | {} | {} |\n", r.pass, r.scene,
                                 r.budget, r.plan, r.predicted_ms, r.predicted_error, r.planned.ms, error_text(r.planned),
                                 r.met ? "yes" : "**no**",
                                 r.fixed ? fmt::format("{}, {:.0f} / {}", r.fixed->label, r.fixed->comparator_ms(),
                                                       error_text(*r.fixed))
                                         : "none meets it",
                                 r.holds ? (r.holds_strictly                      ? "yes"
                                            : r.fixed && same_plan(*r.fixed, r.planned) ? "yes, the same plan"
                                                                                           : "yes, within the noise floor")
                                         : "**no**");
            auto& [holds, strictly, count] = holding[r.pass];
            holds += r.holds ? 1 : 0;
            strictly += r.holds_strictly ? 1 : 0;
            count += 1;
        }
        std::string held;
        for (const auto& [pass, counts] : holding) {
            const auto& [holds, strictly, count] = counts;
            held += fmt::format("{}pass {}: {} of {} budgets hold ({} with no noise floor)", held.empty() ? "" : "; ", pass,
                                holds, count, strictly);
        }
        std::ostringstream md;
        const std::string_view begin = options.cornell ? kCornellBegin : kBegin, end = options.cornell ? kCornellEnd : kEnd;
        md << begin << "\n\n## Budgets on the " << (options.cornell ? "Cornell variants" : "bench corpus")
           << " (bench/planner)\n\n"
           << "Written by `" << arguments.command() << "` on " << bench::today() << ".\n\n"
           << "- Machine: " << bench::machine_description() << "\n- GPU: " << renderer.gpu_info().summary() << "\n"
           << fmt::format("- Frames {0}x{0}, against the reference at {1} spp and {2} bounces through pixel centres; "
                          "device costs calibrated in {3:.0f} ms (or read from the cache).\n",
                          options.size, options.reference_spp, options.reference_bounces, device.calibration_ms)
           << (options.held_out ? "- Held out: each scene planned with the GPU methods' own-error priors of the other "
                                  "four corpus scenes, and for vct of the Cornell variants too (bench/corpus_priors.hpp), "
                                  "as if the bench had never seen it.\n"
                                : "")
           << bench::how_budgets_are_judged() << "\n"
           << held << ".\n\n![error against time: fixed plans, their Pareto front and the planner's frames]("
           << (options.out.is_relative() ? "../" : "") << options.out.generic_string()
           << "/planner.png)\n\n" << table
           << "\nWhat the planner's error model reads from the scene analysis:\n\n" << analysis_md << "\n" << end << "\n";
        bench::splice_block(options.markdown, begin, end, md.str());
        log::info("bench", "{}; wrote {} and {}", held, (options.out / "planner.csv").string(),
                  options.markdown.string());
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "planner: %s\n", error.what());
        return 1;
    }
}
