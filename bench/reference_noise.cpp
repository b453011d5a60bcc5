// bench/reference_noise: how well the noise statistics the planner predicts a reference frame's
// error from read the error the frame makes against the truth. For each corpus scene (or --scene),
// per sample count and seed: one trace of --max-bounces bounces through pixel centres, each bounce
// count its prefix (the frame that seed and count would render), and per count:
//   - its relMSE against the truth (the bench's reference at 4096 spp, --truth-bounces);
//   - its own statistic (noise_per_sample over the frame's own luminance, what a reference frame
//     reports and SceneMeasurements::record_noise reads), over the samples;
//   - the same variance over the truth's luminance (what the error against the truth holds of noise),
//     over the samples;
//   - the scene analysis' statistics at the count (noise_per_sample, noise_against_whole) over the
//     samples, and its stopped error;
//   - against the same seed's frame of the sample count before (at most half as many, the smaller:
//     it holds their samples), the noise scale the planner would read off the pair
//     (FrameComparisons::calibrate_noise: their relMSE over the statistic per sample, the larger
//     frame's, times 1/fewer - 1/more), weighed by the larger frame's own values and by its neighbourhoods' medians (image::Weight),
//     and the one the truth reads: the fall of the two frames' relMSE against the truth, over the
//     same (their missing bounces cancel).
// Prints CSV on stdout.
#include "bench/common.hpp"
#include "bench/corpus.hpp"
#include "bench/reference_cache.hpp"
#include "renderer/base/error.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/scene_analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <utility>

using namespace bounce;

namespace {

std::vector<int> integers(const std::string& text) {
    std::vector<int> values;
    for (const double value : bench::numbers(text)) values.push_back(static_cast<int>(value));
    return values;
}

}  // namespace

int main(int argc, char** argv) {
    bench::Arguments arguments(argc, argv, "bounce_bench_reference_noise", "build/bench/bounce_bench_reference_noise");
    std::vector<std::string> scenes;
    std::vector<int> spps = {4, 16, 64}, bounce_counts = {2, 4, 6};
    int seeds = 2, size = 128, max_bounces = 8, truth_bounces = 8, truth_spp = 4096;
    std::string cache = "build/bench-cache";
    try {
        while (arguments.next()) {
            const std::string& flag = arguments.flag();
            if (flag == "--scene") scenes.push_back(arguments.value());
            else if (flag == "--spp") spps = integers(arguments.value());
            else if (flag == "--bounces") bounce_counts = integers(arguments.value());
            else if (flag == "--seeds") seeds = arguments.number();
            else if (flag == "--size") size = arguments.number();
            else if (flag == "--max-bounces") max_bounces = arguments.number();
            else if (flag == "--truth-bounces") truth_bounces = arguments.number();
            else if (flag == "--truth-spp") truth_spp = arguments.number();
            else if (flag == "--cache") cache = arguments.value();
            else {
                std::fprintf(stderr, "usage: bounce_bench_reference_noise [--scene NAME]... [--spp N,N] [--bounces K,K] "
                                     "[--seeds N] [--size N] [--max-bounces N] [--truth-bounces N] [--truth-spp N] "
                                     "[--cache DIR]\n");
                return 2;
            }
        }
        for (const int bounces : bounce_counts) {
            if (bounces < 0 || bounces > max_bounces) throw InputError(fmt::format("bounce count {} outside 0..{}", bounces, max_bounces));
        }
        fmt::print("scene,bounces,spp,seed,rel_mse,own_statistic,against_truth_statistic,analysis_own,analysis_whole,"
                   "analysis_stopped,pair_spp,pair_scale,pair_scale_smoothed,truth_scale\n");
        for (const bench::BenchScene& bench_scene : bench::corpus_scenes()) {
            if (!scenes.empty() && std::find(scenes.begin(), scenes.end(), bench_scene.name) == scenes.end()) continue;
            const methods::reference::PathTracer tracer(bench_scene.scene);
            const image::Frame truth =
                bench::reference_image(bench_scene, tracer, {size, truth_spp, true, cache}, truth_bounces);
            const SceneAnalysis analysis = analyze_scene(bench_scene.scene);
            struct Earlier {
                int spp = 0;
                image::Frame frame;
                double rel_mse = 0.0;
            };
            std::map<std::pair<int, int>, Earlier> earlier;  // by seed and bounce count
            for (const int spp : spps) {
                for (int seed = 0; seed < seeds; ++seed) {
                    methods::reference::Accumulator accumulator(size, size, max_bounces);
                    methods::reference::PathTracerSettings settings;
                    settings.max_bounces = max_bounces;
                    settings.seed = seed == 0 ? 1 : 1000 + seed;  // as bench/planner's repeats
                    settings.pixel_jitter = false;
                    tracer.render(accumulator, bench_scene.scene.cameras.front(), spp, settings);
                    for (const int bounces : bounce_counts) {
                        const bool whole = bounces == max_bounces;
                        const image::Frame frame = whole ? accumulator.frame() : accumulator.prefix_frame(bounces);
                        const double own = whole ? methods::reference::noise_per_sample(accumulator)
                                                 : accumulator.prefix_noise_per_sample(bounces);
                        const std::string against_truth =
                            whole ? "" : fmt::format("{:.5f}", accumulator.prefix_noise_per_sample(bounces, truth) / spp);
                        const double rel_mse = image::compare(frame, truth).rel_mse;
                        std::string pair = ",,,";
                        const auto before = earlier.find({seed, bounces});
                        if (before != earlier.end() && spp >= 2 * before->second.spp && own > 0.0) {
                            const double statistic = own * (1.0 / before->second.spp - 1.0 / spp);
                            pair = fmt::format("{},{:.4f},{:.4f},{:.4f}", before->second.spp,
                                               image::compare(before->second.frame, frame).rel_mse / statistic,
                                               image::compare(before->second.frame, frame, image::Weight::neighbourhood_median).rel_mse / statistic,
                                               (before->second.rel_mse - rel_mse) / statistic);
                        }
                        fmt::print("{},{},{},{},{:.5f},{:.5f},{},{:.5f},{:.5f},{:.5f},{}\n", bench_scene.name, bounces, spp,
                                   settings.seed, rel_mse, own / spp, against_truth,
                                   BounceEnergy::at(analysis.bounces.noise_per_sample, bounces) / spp,
                                   BounceEnergy::at(analysis.bounces.noise_against_whole, bounces) / spp,
                                   BounceEnergy::at(analysis.bounces.stopped_error, bounces), pair);
                        earlier[{seed, bounces}] = Earlier{spp, frame, rel_mse};
                        std::fflush(stdout);
                    }
                }
            }
        }
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "reference_noise: %s\n", error.what());
        return 1;
    }
}
