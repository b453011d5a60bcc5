// bench/denoise: the reference's denoiser at equal time. For each scene, 128x128, 4 bounces: the
// noisy frame and the denoised frame at N samples per pixel (the filter's time included), and the
// noisy frame at 4N, each against the converged frame (1024 spp): relMSE and milliseconds. Writes
// bench/results/denoise.csv and its section of docs/benchmarks.md.
#include "bench/common.hpp"
#include "bench/markdown_blocks.hpp"
#include "bench/scenes.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/reference/denoiser.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace bounce;

namespace {

inline constexpr std::string_view kBegin = "<!-- denoise: bench/denoise writes it -->";
inline constexpr std::string_view kEnd = "<!-- end of denoise -->";
constexpr int kSize = 128;

}  // namespace

int main(int argc, char** argv) {
    bench::Arguments arguments(argc, argv, "bounce_bench_denoise", "build/bench/bounce_bench_denoise");
    const std::optional<bench::ReportPaths> paths =
        bench::report_paths(arguments, "usage: bounce_bench_denoise [--out DIR] [--markdown FILE]");
    if (!paths) return 2;
    const fs::path& out = paths->out;
    const fs::path& markdown = paths->markdown;
    try {
        fs::create_directories(out);
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
