// bench/denoise: the reference's denoiser at equal time. For each scene, 128x128, 4 bounces: the
// noisy frame and the denoised frame at N samples per pixel (the filter's time included), and the
// noisy frame at 4N, each against the converged frame (1024 spp): relMSE and milliseconds. Writes
// bench/results/denoise.csv and its section of docs/benchmarks.md.
// With --every-scene: on every bench scene (the Cornell variants and the corpus), at 8 bounces
// through pixel centres as the planner's reference plans trace, the noisy and the denoised frame at
// 4, 16 and 64 spp against bench/planner's ground truth (4096 spp, from its cache): what the filter
// leaves of the noise, scene by scene. Writes bench/results/denoise_scenes.csv and its section.
#include "bench/common.hpp"
#include "bench/corpus.hpp"
#include "bench/markdown_blocks.hpp"
#include "bench/reference_cache.hpp"
#include "bench/scenes.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/reference/denoiser.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace bounce;

namespace {

inline constexpr std::string_view kBegin = "<!-- denoise: bench/denoise writes it -->";
inline constexpr std::string_view kEnd = "<!-- end of denoise -->";
inline constexpr std::string_view kScenesBegin = "<!-- denoise on every scene: bench/denoise --every-scene writes it -->";
inline constexpr std::string_view kScenesEnd = "<!-- end of denoise on every scene -->";
constexpr int kSize = 128;
constexpr int kBounces = 8;

// The --every-scene table: per scene and sample count, the noisy frame's relMSE (its noise: at 8
// bounces it lacks next to no light) and the denoised frame's, against the cached ground truth.
int every_scene(const bench::Arguments& arguments, const fs::path& out, const fs::path& markdown) {
    std::ofstream csv(out / "denoise_scenes.csv");
    csv << "scene,spp,noisy_ms,noisy_rel_mse,filter_ms,denoised_rel_mse,denoised_over_noisy\n";
    std::string table = "| scene | spp | noisy: ms, relMSE | filter ms | denoised relMSE | denoised / noisy |\n"
                        "|---|---|---|---|---|---|\n";
    struct Row {
        std::string scene;
        double noisy = 0.0, denoised = 0.0;
    };
    std::vector<Row> rows;
    std::vector<bench::BenchScene> scenes = bench::quality_scenes();
    for (bench::BenchScene& corpus_scene : bench::corpus_scenes()) scenes.push_back(std::move(corpus_scene));
    for (const bench::BenchScene& bench_scene : scenes) {
        const scene::Scene& scene = bench_scene.scene;
        const methods::reference::PathTracer tracer(scene);
        const image::Frame truth = bench::reference_image(bench_scene, tracer, {kSize, 4096, true}, kBounces);
        methods::reference::PathTracerSettings settings;
        settings.max_bounces = kBounces;
        settings.pixel_jitter = false;
        settings.seed = 1;
        for (int spp : {4, 16, 64}) {
            const auto start = bench::Clock::now();
            methods::reference::Accumulator accumulator(kSize, kSize);
            tracer.render(accumulator, scene.cameras[0], spp, settings);
            const image::Frame frame = accumulator.frame();
            const double noisy_ms = bench::ms_since(start);
            const auto filter_start = bench::Clock::now();
            const image::Frame filtered = methods::reference::denoise(frame, accumulator.features());
            const double filter_ms = bench::ms_since(filter_start);
            const double e_noisy = image::compare(frame, truth).rel_mse, e_denoised = image::compare(filtered, truth).rel_mse;
            csv << fmt::format("{},{},{:.1f},{:.5f},{:.1f},{:.5f},{:.3f}\n", bench_scene.name, spp, noisy_ms, e_noisy,
                               filter_ms, e_denoised, e_denoised / e_noisy);
            table += fmt::format("| {} | {} | {:.0f}, {:.4f} | {:.0f} | {:.4f} | {:.3f} |\n", bench_scene.name, spp, noisy_ms,
                                 e_noisy, filter_ms, e_denoised, e_denoised / e_noisy);
            rows.push_back({bench_scene.name, e_noisy, e_denoised});
            std::fprintf(stderr, "%s %d spp: noisy %.4f, denoised %.4f\n", bench_scene.name.c_str(), spp, e_noisy, e_denoised);
        }
    }
    std::string md = std::string(kScenesBegin) + "\n\n## The denoiser on every bench scene (bench/denoise --every-scene)\n\n";
    md += fmt::format(
        "Written by `{}` on {} on {}. `reference` at 8 bounces through pixel centres (as the planner's reference plans "
        "trace), noisy and with `denoise` 1, against bench/planner's ground truth (4096 spp, 8 bounces, pixel centres). "
        "128x128; times on the CPU. At 8 bounces a frame lacks next to no light, so the noisy frame's relMSE is its "
        "noise, and the denoised frame's is what the filter leaves of it, and adds.\n\n",
        arguments.command(), bench::today(), bench::machine_description());
    md += table;
    // What a bound of the filter's error by the noise would promise: denoised relMSE <= k n^p, the
    // exponent that spreads the scenes' largest k least among a few, and each scene's k.
    std::string fit;
    double least_spread = std::numeric_limits<double>::infinity();
    for (const double exponent : {0.5, 0.6, 0.7, 0.8, 1.0}) {
        std::map<std::string, double> largest;
        for (const Row& row : rows) {
            double& k = largest[row.scene];
            k = std::max(k, row.denoised / std::pow(row.noisy, exponent));
        }
        const auto [low, high] = std::minmax_element(largest.begin(), largest.end(),
                                                     [](const auto& a, const auto& b) { return a.second < b.second; });
        if (high->second / low->second >= least_spread) continue;
        least_spread = high->second / low->second;
        fit = fmt::format("\nAs a bound by the noise n (the noisy frame's relMSE), denoised relMSE <= k n^{:g} spreads the "
                          "scenes' k least of the exponents 0.5 to 1 ({:.1f}x from the least to the largest). Per scene, "
                          "the largest k over its sample counts: ",
                          exponent, least_spread);
        std::vector<std::string> parts;
        for (const auto& [scene, k] : largest) parts.push_back(fmt::format("{} {:.3f}", scene, k));
        fit += fmt::format("{}.\n", fmt::join(parts, ", "));
    }
    md += fit + "\n" + std::string(kScenesEnd) + "\n";
    bench::splice_block(markdown, kScenesBegin, kScenesEnd, md);
    std::printf("%s", md.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    // --every-scene first: report_paths reads the flags after it.
    const bool scenes = argc > 1 && std::string_view(argv[1]) == "--every-scene";
    bench::Arguments arguments(scenes ? argc - 1 : argc, scenes ? argv + 1 : argv, "bounce_bench_denoise",
                               scenes ? "build/bench/bounce_bench_denoise --every-scene" : "build/bench/bounce_bench_denoise");
    const std::optional<bench::ReportPaths> paths =
        bench::report_paths(arguments, "usage: bounce_bench_denoise [--every-scene] [--out DIR] [--markdown FILE]");
    if (!paths) return 2;
    const fs::path& out = paths->out;
    const fs::path& markdown = paths->markdown;
    try {
        fs::create_directories(out);
        if (scenes) return every_scene(arguments, out, markdown);
        std::ofstream csv(out / "denoise.csv");
        csv << "scene,spp,noisy_ms,noisy_rel_mse,denoised_ms,denoised_rel_mse,noisy_4x_ms,noisy_4x_rel_mse\n";
        std::string table = "| scene | spp | noisy: ms, relMSE | denoised: ms, relMSE | noisy at 4x spp: ms, relMSE |\n"
                            "|---|---|---|---|---|\n";
        for (const bench::BenchScene& bench_scene : bench::quality_scenes()) {
            if (bench_scene.name != "cornell" && bench_scene.name != "cornell_glossy") continue;
            const scene::Scene& scene = bench_scene.scene;
            const methods::reference::PathTracer tracer(scene);
            methods::reference::PathTracerSettings settings;
            settings.seed = 7;
            const image::Frame truth = tracer.render(scene.cameras[0], kSize, kSize, 1024, settings);
            settings.seed = 1;
            auto noisy = [&](int spp, double& ms) {
                const auto start = bench::Clock::now();
                methods::reference::Accumulator accumulator(kSize, kSize);
                tracer.render(accumulator, scene.cameras[0], spp, settings);
                image::Frame frame = accumulator.frame();
                ms = bench::ms_since(start);
                return std::pair{frame, accumulator.features()};
            };
            for (int spp : {4, 16, 64}) {
                double noisy_ms = 0.0, wide_ms = 0.0;
                const auto [frame, features] = noisy(spp, noisy_ms);
                const auto start = bench::Clock::now();
                const image::Frame filtered = methods::reference::denoise(frame, features);
                const double denoised_ms = noisy_ms + bench::ms_since(start);
                const image::Frame wide = noisy(4 * spp, wide_ms).first;
                const double e_noisy = image::compare(frame, truth).rel_mse,
                             e_denoised = image::compare(filtered, truth).rel_mse, e_wide = image::compare(wide, truth).rel_mse;
                csv << fmt::format("{},{},{:.1f},{:.5f},{:.1f},{:.5f},{:.1f},{:.5f}\n", bench_scene.name, spp, noisy_ms,
                                   e_noisy, denoised_ms, e_denoised, wide_ms, e_wide);
                table += fmt::format("| {} | {} | {:.0f}, {:.4f} | {:.0f}, {:.4f} | {:.0f}, {:.4f} |\n", bench_scene.name,
                                     spp, noisy_ms, e_noisy, denoised_ms, e_denoised, wide_ms, e_wide);
            }
        }
        std::string md = std::string(kBegin) + "\n\n## The reference's denoiser (bench/denoise)\n\n";
        md += fmt::format(
            "Written by `{}` on {} on {}. `reference` with `denoise` 1: the edge-avoiding a-trous filter "
            "(renderer/methods/reference/denoiser.hpp) guided by the first hits' albedo, normal and depth and by each "
            "pixel's sample variance. 128x128, 4 bounces, against 1024 spp (another seed); times are the trace "
            "(and the filter) on the CPU.\n\n",
            arguments.command(), bench::today(), bench::machine_description());
        md += table + "\n" + std::string(kEnd) + "\n";
        bench::splice_block(markdown, kBegin, kEnd, md);
        std::printf("%s", md.c_str());
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bench/denoise: %s\n", error.what());
        return 1;
    }
}
