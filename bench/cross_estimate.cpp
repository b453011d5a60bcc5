// bench/cross_estimate: how well two noisy reference frames of a view measure a GPU frame's error
// without their noise (image::cross_rel_mse, planning::FrameComparisons' cross estimate), against
// what the relMSE against one of them reads. For each corpus scene (or --scene), GPU frames of a few
// presets at one bounce (direct at none), and draws of the reference through pixel centres, seed 1,
// at 3, 6, 16 and 32 samples, of one bounce and of 8; each pair of consecutive counts (the seed's
// frame of more samples holds the fewer's, FrameComparisons::independent_draws) against the frame:
//   - truth: its relMSE against the bench's reference of the draws' bounces (1024 samples);
//   - naive: its relMSE against the draw of more samples;
//   - cross, standard_error: the cross estimate, weighed by the draw of more samples' neighbourhood medians;
//   - taken: whether the planner would take it (twice the standard error at most
//     FrameComparisons::kMaxCrossSpread of it);
//   - drowned: whether the noise is over a quarter of the naive relMSE (naive - truth, as the truth
//     measures it), where the planner turns to a cross estimate.
// Writes the CSV (--out, default bench/results/corpus/cross_estimate.csv) and prints, for the
// comparisons drowned and taken, the range of the estimate over the truth.
#include "bench/common.hpp"
#include "bench/corpus.hpp"
#include "bench/reference_cache.hpp"
#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/planning/comparisons.hpp"
#include "renderer/planning/error_model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>

using namespace bounce;

int main(int argc, char** argv) {
    bench::Arguments arguments(argc, argv, "bounce_bench_cross_estimate", "build/bench/bounce_bench_cross_estimate");
    std::vector<std::string> scenes;
    std::filesystem::path out = "bench/results/corpus/cross_estimate.csv";
    std::string cache = "build/bench-cache";
    constexpr int kSize = 128, kTruthSpp = 1024;
    try {
        while (arguments.next()) {
            const std::string& flag = arguments.flag();
            if (flag == "--scene") scenes.push_back(arguments.value());
            else if (flag == "--out") out = arguments.value();
            else if (flag == "--cache") cache = arguments.value();
            else {
                std::fprintf(stderr, "usage: bounce_bench_cross_estimate [--scene NAME]... [--out FILE.csv] [--cache DIR]\n");
                return 2;
            }
        }
        Renderer renderer(gpu::DeviceChoice::resolve(std::nullopt));
        std::ofstream csv(out);
        if (!csv) throw InputError(fmt::format("cannot write {}", out.string()));
        csv << "scene,frame,bounces,reference_bounces,fewer_spp,more_spp,truth,naive,cross,standard_error,taken,drowned\n";
        double least = std::numeric_limits<double>::infinity(), most = 0.0;
        int drowned_taken = 0, drowned_left = 0;
        const std::vector<std::pair<std::string, std::string>> presets = {
            {"isr", "draft"}, {"isr", "medium"}, {"vct", "draft"}, {"vct", "high"}, {"cssm", "draft"}, {"direct", "draft"}};
        const std::vector<int> spps = {3, 6, 16, 32};
        for (const bench::BenchScene& bench_scene : bench::corpus_scenes()) {
            if (!scenes.empty() && std::find(scenes.begin(), scenes.end(), bench_scene.name) == scenes.end()) continue;
            const methods::reference::PathTracer tracer(bench_scene.scene);
            const auto resources = renderer.upload(bench_scene.scene);
            std::map<int, std::map<int, image::Frame>> draws;  // by bounces, then samples
            for (const int spp : spps) {
                methods::reference::Accumulator accumulator(kSize, kSize, 8);
                methods::reference::PathTracerSettings settings;
                settings.max_bounces = 8;
                settings.seed = 1;
                settings.pixel_jitter = false;
                tracer.render(accumulator, bench_scene.scene.cameras.front(), spp, settings);
                draws[1][spp] = accumulator.prefix_frame(1);
                draws[8][spp] = accumulator.frame();
            }
            for (const auto& [method, preset] : presets) {
                methods::KnobValues knobs;
                if (method == "vct" || method == "cssm") knobs["bounces"] = 1;
                const RenderRequest request = bench::linear_request(method, preset, knobs, kSize);
                renderer.render(*resources, request);  // builds what the method keeps
                const RenderResult gpu = renderer.render(*resources, request);
                const int bounces = planning::modelled_bounces(method, gpu.stats.knobs);
                for (const int reference_bounces : {1, 8}) {
                    if (reference_bounces < bounces) continue;
                    const image::Frame truth = bench::reference_image(bench_scene, tracer, {kSize, kTruthSpp, true, cache},
                                                                      reference_bounces);
                    const double truth_error = image::compare(gpu.frame, truth).rel_mse;
                    for (std::size_t i = 0; i + 1 < spps.size(); ++i) {
                        const int fewer = spps[i], more = spps[i + 1];
                        const image::Frame& a = draws[reference_bounces][fewer];
                        const image::Frame& m = draws[reference_bounces][more];
                        const image::Frame later = planning::FrameComparisons::later_samples(a, fewer, m, more);
                        const image::CrossEstimate cross = image::cross_rel_mse(gpu.frame, a, later, m);
                        const double naive = image::compare(gpu.frame, m).rel_mse;
                        const bool taken = 2.0 * cross.standard_error <= planning::FrameComparisons::kMaxCrossSpread * cross.rel_mse;
                        const bool drowned = naive - truth_error > planning::FrameComparisons::kMaxNoiseShare * naive;
                        if (drowned && taken) {
                            ++drowned_taken;
                            least = std::min(least, cross.rel_mse / truth_error);
                            most = std::max(most, cross.rel_mse / truth_error);
                        } else if (drowned) {
                            ++drowned_left;
                        }
                        csv << fmt::format("{},{} {},{},{},{},{},{:.5f},{:.5f},{:.5f},{:.5f},{},{}\n", bench_scene.name, method, preset,
                                           bounces, reference_bounces, fewer, more, truth_error, naive, cross.rel_mse,
                                           cross.standard_error, taken, drowned);
                    }
                }
            }
            log::info("bench", "{} done", bench_scene.name);
        }
        fmt::print("comparisons drowned by the reference's noise: {} with a cross estimate taken, reading {:.2f} to {:.2f} "
                   "times the truth; {} left out as too wide; wrote {}\n",
                   drowned_taken, least, most, drowned_left, out.string());
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "cross_estimate: %s\n", error.what());
        return 1;
    }
}
