// bench/extremes: the extremes matrix (bench/extremes.hpp) as a table — per case and method:
// finite, relMSE against the reference, `direct`'s relMSE, mean radiance against the energy bound,
// and whether the invariants hold (or the documented exception). Writes bench/results/extremes.csv
// and its section of docs/benchmarks.md. tests/gpu/extremes_test.cpp checks the same verdicts.
#include "bench/common.hpp"
#include "bench/extremes.hpp"
#include "bench/markdown_blocks.hpp"
#include "renderer/base/log.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace bounce;

namespace {

inline constexpr std::string_view kBegin = "<!-- extremes: bench/extremes writes it -->";
inline constexpr std::string_view kEnd = "<!-- end of extremes -->";

}  // namespace

int main(int argc, char** argv) {
    bench::Arguments arguments(argc, argv, "bounce_bench_extremes", "build/bench/bounce_bench_extremes");
    const std::optional<bench::ReportPaths> paths =
        bench::report_paths(arguments, "usage: bounce_bench_extremes [--out DIR] [--markdown FILE]");
    if (!paths) return 2;
    const fs::path& out = paths->out;
    const fs::path& markdown = paths->markdown;
    try {
        Renderer renderer(gpu::DeviceChoice::resolve(std::nullopt));
        fs::create_directories(out);
        std::ofstream csv(out / "extremes.csv");
        csv << "case,method,finite,rel_mse,direct_rel_mse,mean,energy_bound,energy_ok,error_ok,within_bounds,exception\n";
        const auto started = bench::Clock::now();
        std::string table = "| case | what | method | finite | relMSE | direct's | mean / bound | holds |\n"
                            "|---|---|---|---|---|---|---|---|\n";
        std::size_t pairs = 0, holding = 0, excepted = 0;
        for (const bench::ExtremeCase& extreme : bench::extreme_cases()) {
            log::info("bench", "extremes: {}", extreme.name);
            const bench::ExtremeTruth truth = bench::extreme_truth(extreme, bench::kExtremeReferenceBounces);
            const bench::ExtremeTruth isr_truth = bench::extreme_truth(extreme, 1, false);
            double direct_rel_mse = 0.0;
            for (const std::string method : {"direct", "vct", "isr", "cssm"}) {
                const bench::ExtremeVerdict v = bench::judge(renderer, extreme, method, truth, isr_truth, direct_rel_mse);
                if (method == "direct") direct_rel_mse = v.rel_mse;
                ++pairs;
                holding += v.within_bounds();
                excepted += !v.exception.empty();
                csv << fmt::format("{},{},{},{:.6g},{:.6g},{:.6g},{:.6g},{},{},{},\"{}\"\n", extreme.name, method, v.finite,
                                   v.rel_mse, v.direct_rel_mse, v.mean, v.energy_bound, v.energy_ok, v.error_ok,
                                   v.within_bounds(), v.exception);
                const std::string ratio = v.energy_bound > 0.0 ? fmt::format("{:.3f}", v.mean / v.energy_bound)
                                                               : (v.mean == 0.0 ? "0 / 0" : fmt::format("{:.3g} / 0", v.mean));
                const std::string holds = !v.within_bounds() ? "**no**"
                                          : v.exception.empty() ? "yes"
                                                                : "exception: " + v.exception;
                table += fmt::format("| {} | {} | `{}` | {} | {:.4f} | {:.4f} | {} | {} |\n", extreme.name, extreme.what,
                                     method, v.finite ? "yes" : "**no**", v.rel_mse, v.direct_rel_mse, ratio, holds);
            }
        }
        const double minutes = bench::ms_since(started) / 60000.0;
        std::string md = std::string(kBegin) + "\n\n## Extremes (bench/extremes)\n\n";
        md += fmt::format(
            "Written by `{}` on {} ({:.1f} min) on {}; {}.\n\n"
            "The Cornell box at the limits (bench/extremes.cpp lists the cases), 32x32 but for the frame shapes and "
            "256 lights (16x16), every method at `high`, against the path tracer through pixel centres (two seeds of 256 spp, "
            "4 bounces; 32 spp for 256 lights). A method holds when its frame is finite, its mean is not above the "
            "reference's beyond four standard errors and its allowance (isr: against the reference without "
            "indirect visibility, +0.5% for its gather's bias; others +2^-10), and its relMSE is not above "
            "`direct`'s; or when a documented exception says why not (light behind walls). \"mean / bound\" is the "
            "frame's mean over that energy bound. {} of {} pairs hold, {} of them by exception. "
            "`tests/gpu/extremes_test.cpp` checks the same verdicts.\n\n",
            arguments.command(), bench::today(), minutes, renderer.gpu_info().summary(), bench::machine_description(),
            holding, pairs, excepted);
        md += table + "\n" + std::string(kEnd) + "\n";
        bench::splice_block(markdown, kBegin, kEnd, md);
        log::info("bench", "wrote the extremes section of {} and {}", markdown.string(), (out / "extremes.csv").string());
        return holding == pairs ? 0 : 1;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bench/extremes: %s\n", error.what());
        return 1;
    }
}
