// bench/isr: method `isr` in the shape of its paper (isr-nichols-2009), on the built-in Cornell box:
// per-stage cost of a cold frame (the paper's Table 1), the error eye-space clustering adds (its
// Fig. 9) and light-space clustering adds (its Fig. 13), and frame-to-frame change of the indirect
// light under a moving light (its Fig. 5). Each writes a CSV under --out (bench/plot_isr.py plots
// them) and a section of docs/benchmarks.md, between the isr markers; the rest of the file is kept.
#include "bench/common.hpp"
#include "bench/markdown_blocks.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene/builtin.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace bounce;
using namespace bounce::bench;

struct Options {
    fs::path out = "bench/results";
    fs::path markdown = "docs/benchmarks.md";
};

// Sizes are chosen so that the sections take about three minutes on llvmpipe with two cores: a
// gather from every VPL costs fragments x VPLs (about 4.5e7 VPLs a second there).
struct IsrSettings {
    int stage_size = 256;                // the stage table's frames
    int repeats = 3;                     // cold frames per mode in the stage table (the median is shown)
    int fig9_size = 256, fig9_rsm = 32;  // Fig. 9: frame, and RSM texels per side of every light view
    int fig13_size = 64, fig13_rsm = 256;
    int temporal_size = 128;
    int temporal_frames = 12;            // light positions of the temporal section
    float temporal_step = 0.002f;        // metres the light moves along x between frames
    int temporal_ideal_rsm = 128;        // the ideal series gathers every VPL of this RSM (medium's)
    int temporal_shadow_map_size = 512;  // direct light only, subtracted out: cheaper maps, same indirect

    // A smoke run in seconds (--quick): every section small.
    void quick() {
        stage_size = fig9_size = fig13_size = temporal_size = 64;
        repeats = 1;
        fig9_rsm = 16;
        fig13_rsm = 64;
        temporal_frames = 3;
        temporal_ideal_rsm = 32;
    }
};

// Sum of the GPU ms of the named passes (a pass may be timed more than once in a frame).
double pass_ms(const RenderResult& result, const std::vector<std::string_view>& names) {
    double ms = 0.0;
    for (const auto& pass : result.stats.passes) {
        for (const auto name : names) {
            if (pass.pass == name) ms += pass.gpu_ms;
        }
    }
    return ms;
}

double statistic(const RenderResult& result, const std::string& name) {
    const auto it = result.stats.method_statistics.find(name);
    return it == result.stats.method_statistics.end() ? 0.0 : it->second;
}

// Mean over pixels and RGB.
double mean_rgb(const image::Frame& frame) {
    double sum = 0.0;
    for (std::size_t i = 0; i < frame.rgba.size(); i += 4) sum += frame.rgba[i] + frame.rgba[i + 1] + frame.rgba[i + 2];
    return frame.rgba.empty() ? 0.0 : sum / (3.0 * static_cast<double>(frame.rgba.size() / 4));
}

// a - b, RGB (alpha from a): the indirect light of an isr frame when b is `direct`'s frame.
image::Frame difference(const image::Frame& a, const image::Frame& b) {
    if (a.rgba.size() != b.rgba.size()) throw std::runtime_error("difference: frame sizes differ");
    image::Frame out = a;
    for (std::size_t i = 0; i < out.rgba.size(); i += 4) {
        for (std::size_t c = 0; c < 3; ++c) out.rgba[i + c] = a.rgba[i + c] - b.rgba[i + c];
    }
    return out;
}

// `direct` with the shadow maps isr draws its direct light with: isr's frame minus this one is
// exactly its indirect light.
RenderRequest direct_request(int size, int shadow_map_size = 2048) {
    return linear_request("direct", "medium", {{"shadow_map_size", static_cast<double>(shadow_map_size)}}, size);
}

// isr medium as the paper has it, without indirect visibility (the preset makes imperfect shadow maps).
RenderRequest paper_request(methods::KnobValues knobs, int size) {
    knobs.try_emplace("ism_size", 0.0);
    return linear_request("isr", "medium", std::move(knobs), size);
}

struct IsrMode {
    std::string label, csv_name;
    methods::KnobValues knobs;  // over preset medium
};

std::vector<IsrMode> isr_modes() {
    return {{"naive RSM (mode 0, max_depth 0)", "naive", {{"mode", 0}, {"max_depth", 0}}},
            {"basic (mode 1)", "basic", {{"mode", 1}}},
            {"hierarchical (mode 2)", "hierarchical", {{"mode", 2}}}};
}

// Table 1's shape: GPU ms per stage of a cold frame (fresh scene resources, so the light-view maps
// are drawn, the VPL tree built and the cache selected in the frame measured).
std::string isr_stages_markdown(Renderer& renderer, const scene::Scene& scene, const IsrSettings& isr,
                                const fs::path& csv_path) {
    struct Stage {
        const char* label;
        const char* csv;
        std::vector<std::string_view> passes;
        double paper;  // ms, < 0: no such stage in the paper's table
    };
    const std::vector<Stage> stages = {
        {"Direct light (gbuffer, shadow maps, emission, direct light)", "direct_light",
         {"gbuffer", "shadow_maps", "emission", "direct_light"}, 1.8},
        {"Generate RSM (light_view_maps)", "generate_rsm", {"light_view_maps"}, 0.9},
        {"VPL tree / cache (isr_vpl_tree + isr_vpl_cache)", "vpl_tree_cache", {"isr_vpl_tree", "isr_vpl_cache"}, -1},
        {"Create min-max mipmap (isr_minmax_mipmap)", "minmax_mipmap", {"isr_minmax_mipmap"}, 0.7},
        {"Multires stencil setup (isr_stencil)", "stencil", {"isr_stencil"}, 0.7},
        {"Multires light gather (isr_gather)", "gather", {"isr_gather"}, 2.5},
        {"Upsample (isr_upsample + isr_composite)", "upsample", {"isr_upsample", "isr_composite"}, 1.6},
    };
    struct Column {
        IsrMode mode;
        RenderResult cold;
        double warm_gpu_ms = 0, warm_wall_ms = 0;
    };
    std::vector<Column> columns;
    for (const IsrMode& mode : isr_modes()) {
        const RenderRequest request = paper_request(mode.knobs, isr.stage_size);
        {
            auto warmup = renderer.upload(scene);  // compiles the shaders: the cold frames exclude that
            renderer.render(*warmup, request);
        }
        std::vector<RenderResult> cold;
        std::unique_ptr<SceneResources> last;
        for (int r = 0; r < isr.repeats; ++r) {
            last = renderer.upload(scene);
            cold.push_back(renderer.render(*last, request));
        }
        std::sort(cold.begin(), cold.end(), [](const auto& a, const auto& b) { return a.stats.gpu_ms < b.stats.gpu_ms; });
        const RenderResult warm = renderer.render(*last, request);  // the same view again: nothing to rebuild
        columns.push_back({mode, cold[cold.size() / 2], warm.stats.gpu_ms, warm.stats.render_ms});
        log::info("bench", "isr stages {}: cold {:.1f} GPU ms, warm {:.1f}", mode.csv_name, columns.back().cold.stats.gpu_ms,
                  warm.stats.gpu_ms);
    }

    std::ofstream csv(csv_path);
    csv << "mode,size,repeats";
    for (const Stage& stage : stages) csv << "," << stage.csv << "_ms";
    csv << ",total_ms,other_ms,cold_wall_ms,warm_gpu_ms,warm_wall_ms,multires_fragments,vpls_per_fragment_mean,"
           "vpls_per_fragment_max,vpl_cache,rsm_views\n";
    for (const Column& column : columns) {
        const RenderResult& r = column.cold;
        double staged = 0.0;
        csv << fmt::format("{},{},{}", column.mode.csv_name, isr.stage_size, isr.repeats);
        for (const Stage& stage : stages) {
            const double ms = pass_ms(r, stage.passes);
            staged += ms;
            csv << fmt::format(",{:.3f}", ms);
        }
        const auto cache = r.stats.method_statistics.find("vpl_cache");  // none in hierarchical mode
        csv << fmt::format(",{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.0f},{:.2f},{:.0f},{},{:.0f}\n", r.stats.gpu_ms,
                           r.stats.gpu_ms - staged, r.stats.render_ms, column.warm_gpu_ms, column.warm_wall_ms,
                           statistic(r, "multires_fragments"), statistic(r, "vpls_per_fragment_mean"),
                           statistic(r, "vpls_per_fragment_max"),
                           cache == r.stats.method_statistics.end() ? std::string() : fmt::format("{:.0f}", cache->second),
                           statistic(r, "rsm_views"));
    }
    csv << "paper_cornell_gtx280_1024,1024,0";
    for (const Stage& stage : stages) csv << (stage.paper < 0 ? "," : fmt::format(",{:.1f}", stage.paper));
    csv << ",8.2,,,,,,256,,,\n";

    std::string md = "| stage (GPU ms, cold frame) ";
    for (const Column& column : columns) md += "| " + column.mode.label + " ";
    md += "| paper: Cornell Box, GTX 280, 1024², 256 VPLs |\n|---";
    for (std::size_t i = 0; i <= columns.size(); ++i) md += "|---";
    md += "|\n";
    for (const Stage& stage : stages) {
        md += fmt::format("| {} ", stage.label);
        for (const Column& column : columns) {
            md += fmt::format("| {:.1f} ", pass_ms(column.cold, stage.passes));
        }
        md += stage.paper < 0 ? "| — |\n" : fmt::format("| {:.1f} |\n", stage.paper);
    }
    auto row = [&](const std::string& label, auto value, const std::string& paper) {
        md += "| " + label + " ";
        for (const Column& column : columns) md += "| " + value(column) + " ";
        md += "| " + paper + " |\n";
    };
    row("… of which shadow maps (direct light)",
        [](const Column& c) { return fmt::format("{:.1f}", pass_ms(c.cold, {"shadow_maps"})); }, "—");
    row("**Total** (every pass of the frame)", [](const Column& c) { return fmt::format("**{:.1f}**", c.cold.stats.gpu_ms); },
        "**8.2**");
    row("cold wall ms (render call, with readback)", [](const Column& c) { return fmt::format("{:.1f}", c.cold.stats.render_ms); },
        "—");
    row("warm frame GPU ms (same view again: RSM, tree, cache reused)",
        [](const Column& c) { return fmt::format("{:.1f}", c.warm_gpu_ms); }, "—");
    row("multiresolution fragments",
        [](const Column& c) { return fmt::format("{:.0f}", statistic(c.cold, "multires_fragments")); }, "—");
    row("VPLs per fragment, mean / max",
        [](const Column& c) {
            return fmt::format("{:.1f} / {:.0f}", statistic(c.cold, "vpls_per_fragment_mean"),
                               statistic(c.cold, "vpls_per_fragment_max"));
        },
        "256 / 256");
    row("VPL cache (VPLs every fragment gathers)",
        [](const Column& c) {
            const auto it = c.cold.stats.method_statistics.find("vpl_cache");
            return it == c.cold.stats.method_statistics.end() ? std::string("— (tree)") : fmt::format("{:.0f}", it->second);
        },
        "256");
    row("light views (RSM faces) × texels",
        [](const Column& c) {
            return fmt::format("{:.0f} × {:.0f}²", statistic(c.cold, "rsm_views"), statistic(c.cold, "rsm_size"));
        },
        "—");
    return md;
}

struct Comparison {
    double rel_mse = 0, rmse = 0, rel_rmse_image_pct = 0, rel_rmse_indirect_pct = 0;
};

Comparison compare_to(const image::Frame& test, const image::Frame& baseline, double baseline_indirect_mean) {
    const auto metrics = image::compare(test, baseline);
    Comparison c;
    c.rel_mse = metrics.rel_mse;
    c.rmse = metrics.rmse;
    c.rel_rmse_image_pct = metrics.mean_reference > 0 ? 100.0 * metrics.rmse / metrics.mean_reference : 0.0;
    c.rel_rmse_indirect_pct = baseline_indirect_mean > 0 ? 100.0 * metrics.rmse / baseline_indirect_mean : 0.0;
    return c;
}

// Fig. 9: error from eye-space clustering alone. The baseline gathers at every pixel (levels 1)
// from the same VPLs (hierarchical with tau 0 down to the texels: every VPL of the RSM).
std::string isr_fig9_markdown(Renderer& renderer, const scene::Scene& scene, const IsrSettings& isr, const fs::path& csv_path,
                              const std::string& png) {
    auto resources = renderer.upload(scene);
    const methods::KnobValues base = {
        {"mode", 2}, {"tau", 0}, {"rsm_size", static_cast<double>(isr.fig9_rsm)}, {"max_depth", 11}};
    const int size = isr.fig9_size;
    auto knobs = [&](std::initializer_list<std::pair<const std::string, double>> extra) {
        methods::KnobValues k = base;
        for (const auto& [name, value] : extra) k[name] = value;
        return k;
    };
    const RenderResult baseline =
        renderer.render(*resources, paper_request(knobs({{"levels", 1}, {"normal_threshold", 0.3}}), size));
    const image::Frame direct = renderer.render(*resources, direct_request(size)).frame;
    const double indirect_mean = mean_rgb(difference(baseline.frame, direct));
    const double pixels = static_cast<double>(size) * size;
    log::info("bench", "isr fig9 baseline: {:.0f} fragments, gather {:.0f} ms", statistic(baseline, "multires_fragments"),
              pass_ms(baseline, {"isr_gather"}));

    std::ofstream csv(csv_path);
    csv << "normal_threshold,depth_threshold,levels,rel_rmse_pct,rel_rmse_indirect_pct,rel_mse,rmse,multires_fragments,"
           "fragments_fraction,gather_ms,total_gpu_ms\n";
    csv << fmt::format("baseline,baseline,1,0,0,0,0,{:.0f},{:.4f},{:.3f},{:.3f}\n", statistic(baseline, "multires_fragments"),
                       statistic(baseline, "multires_fragments") / pixels, pass_ms(baseline, {"isr_gather"}),
                       baseline.stats.gpu_ms);
    std::string md = fmt::format(
        "| normal threshold | depth threshold | RMSE % of image mean | RMSE % of indirect mean | relMSE | multires fragments "
        "| fragments / pixels | gather ms |\n|---|---|---|---|---|---|---|---|\n"
        "| baseline (levels 1) | — | 0 | 0 | 0 | {:.0f} | {:.3f} | {:.1f} |\n",
        statistic(baseline, "multires_fragments"), statistic(baseline, "multires_fragments") / pixels,
        pass_ms(baseline, {"isr_gather"}));
    for (const double normal : {0.3, 2.0}) {
        for (const double depth : {0.0, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0}) {
            const RenderResult test = renderer.render(
                *resources,
                linear_request("isr", "medium",
                               knobs({{"levels", 5}, {"depth_threshold", depth}, {"normal_threshold", normal}}), size));
            const Comparison c = compare_to(test.frame, baseline.frame, indirect_mean);
            const double fragments = statistic(test, "multires_fragments");
            csv << fmt::format("{},{},5,{:.4f},{:.4f},{:.6g},{:.6g},{:.0f},{:.4f},{:.3f},{:.3f}\n", normal, depth,
                               c.rel_rmse_image_pct, c.rel_rmse_indirect_pct, c.rel_mse, c.rmse, fragments, fragments / pixels,
                               pass_ms(test, {"isr_gather"}), test.stats.gpu_ms);
            md += fmt::format("| {} | {} | {:.2f} | {:.2f} | {:.3g} | {:.0f} | {:.3f} | {:.1f} |\n", normal, depth,
                              c.rel_rmse_image_pct, c.rel_rmse_indirect_pct, c.rel_mse, fragments, fragments / pixels,
                              pass_ms(test, {"isr_gather"}));
            log::info("bench", "isr fig9 normal {} depth {}: RMSE {:.2f}% of the image mean, {:.0f} fragments", normal,
                      depth, c.rel_rmse_image_pct, fragments);
        }
    }
    return md + fmt::format("\n![isr error against depth threshold]({})\n", png);
}

// Fig. 13: error from light-space clustering alone. The baseline is multiresolution gathering with
// the same eye-space settings from every VPL of a 256² RSM (tau 0 to the texels).
std::string isr_fig13_markdown(Renderer& renderer, const scene::Scene& scene, const IsrSettings& isr, const fs::path& csv_path,
                               const std::string& png) {
    auto resources = renderer.upload(scene);
    const methods::KnobValues eye = {{"mode", 2},          {"levels", 5}, {"depth_threshold", 0.02},
                                     {"normal_threshold", 0.3}, {"rsm_size", static_cast<double>(isr.fig13_rsm)}};
    const int size = isr.fig13_size;
    auto knobs = [&](double tau, double max_depth) {
        methods::KnobValues k = eye;
        k["tau"] = tau;
        k["max_depth"] = max_depth;
        return k;
    };
    const RenderResult baseline = renderer.render(*resources, paper_request(knobs(0, 11), size));
    const image::Frame direct = renderer.render(*resources, direct_request(size)).frame;
    // The 16^2 top patches sit top_level levels above the texels: max_depth top_level reaches the texels.
    int top_level = 0;
    while ((16 << top_level) < isr.fig13_rsm) ++top_level;
    const double indirect_mean = mean_rgb(difference(baseline.frame, direct));
    log::info("bench", "isr fig13 baseline: {:.0f} VPLs per fragment, gather {:.0f} ms",
              statistic(baseline, "vpls_per_fragment_mean"), pass_ms(baseline, {"isr_gather"}));

    std::ofstream csv(csv_path);
    csv << "max_depth,finest_patch_texels,tau,rel_rmse_pct,rel_rmse_indirect_pct,rel_mse,rmse,vpls_per_fragment_mean,"
           "vpls_per_fragment_max,gather_ms,total_gpu_ms\n";
    csv << fmt::format("baseline,1,0,0,0,0,0,{:.2f},{:.0f},{:.3f},{:.3f}\n", statistic(baseline, "vpls_per_fragment_mean"),
                       statistic(baseline, "vpls_per_fragment_max"), pass_ms(baseline, {"isr_gather"}),
                       baseline.stats.gpu_ms);
    const std::vector<double> taus = {0, 0.0003, 0.001, 0.003, 0.01, 0.03, 0.1, 0.3, 1};
    std::string md = "| max_depth (finest patch) | tau | RMSE % of image mean | RMSE % of indirect mean | relMSE | VPLs per "
                     "fragment (mean) | gather ms |\n|---|---|---|---|---|---|---|\n";
    md += fmt::format("| baseline (every VPL) | 0 | 0 | 0 | 0 | {:.0f} | {:.1f} |\n",
                      statistic(baseline, "vpls_per_fragment_mean"), pass_ms(baseline, {"isr_gather"}));
    for (int max_depth = 1; max_depth <= std::max(1, top_level); ++max_depth) {
        for (const double tau : taus) {
            // tau 0 down to the texels is the baseline's very request: not rendered again.
            const RenderRequest request = paper_request(knobs(tau, max_depth), size);
            const RenderResult test = tau == 0 && max_depth >= top_level ? baseline : renderer.render(*resources, request);
            const Comparison c = compare_to(test.frame, baseline.frame, indirect_mean);
            const double finest = statistic(test, "vpl_finest_patch_texels");
            csv << fmt::format("{},{:.0f},{},{:.4f},{:.4f},{:.6g},{:.6g},{:.2f},{:.0f},{:.3f},{:.3f}\n", max_depth, finest, tau,
                               c.rel_rmse_image_pct, c.rel_rmse_indirect_pct, c.rel_mse, c.rmse,
                               statistic(test, "vpls_per_fragment_mean"), statistic(test, "vpls_per_fragment_max"),
                               pass_ms(test, {"isr_gather"}), test.stats.gpu_ms);
            md += fmt::format("| {} ({:.0f}² texels) | {} | {:.2f} | {:.2f} | {:.3g} | {:.1f} | {:.1f} |\n", max_depth, finest,
                              tau, c.rel_rmse_image_pct, c.rel_rmse_indirect_pct, c.rel_mse,
                              statistic(test, "vpls_per_fragment_mean"), pass_ms(test, {"isr_gather"}));
            log::info("bench", "isr fig13 max_depth {} tau {}: RMSE {:.2f}% of the image mean, {:.1f} VPLs per fragment",
                      max_depth, tau, c.rel_rmse_image_pct, statistic(test, "vpls_per_fragment_mean"));
        }
    }
    return md + fmt::format("\n![isr error against tau]({})\n", png);
}

// Per-pixel mean over RGB of |a - b|.
std::vector<double> abs_delta(const image::Frame& a, const image::Frame& b) {
    std::vector<double> delta(a.rgba.size() / 4);
    for (std::size_t p = 0; p < delta.size(); ++p) {
        double sum = 0.0;
        for (std::size_t c = 0; c < 3; ++c) sum += std::abs(static_cast<double>(a.rgba[p * 4 + c]) - b.rgba[p * 4 + c]);
        delta[p] = sum / 3.0;
    }
    return delta;
}

double percentile(std::vector<double> values, double q) {
    if (values.empty()) return 0.0;
    const auto k = static_cast<std::size_t>(std::min<double>(values.size() - 1, q * static_cast<double>(values.size())));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k];
}

double mean(const std::vector<double>& values) {
    double sum = 0.0;
    for (const double v : values) sum += v;
    return values.empty() ? 0.0 : sum / static_cast<double>(values.size());
}

// Fig. 5: the light moves in small steps; each series keeps one SceneResources (as a session that
// moves the light does), so every frame redraws the light-view maps and rebuilds the tree / cache.
std::string isr_temporal_markdown(Renderer& renderer, const scene::Scene& original, const IsrSettings& isr,
                                  const fs::path& csv_path) {
    scene::Scene scene = original;  // the resources read its light at every frame
    auto light_position = [&](int frame) {
        const float offset = (static_cast<float>(frame) - 0.5f * static_cast<float>(isr.temporal_frames - 1)) * isr.temporal_step;
        return original.lights[0].position + glm::vec3(offset, 0.0f, 0.0f);
    };
    auto render_series = [&](const RenderRequest& request) {
        auto resources = renderer.upload(scene);
        std::vector<RenderResult> frames;
        for (int f = 0; f < isr.temporal_frames; ++f) {
            scene.lights[0].position = light_position(f);
            frames.push_back(renderer.render(*resources, request));
        }
        return frames;
    };
    std::vector<image::Frame> direct;
    const int size = isr.temporal_size;
    for (auto& result : render_series(direct_request(size, isr.temporal_shadow_map_size))) {
        direct.push_back(std::move(result.frame));
    }

    struct Series {
        std::string label, csv_name;
        methods::KnobValues knobs;
        std::vector<image::Frame> indirect;
        double vpls_per_fragment = 0, fragments = 0, rsm_draws = 0, gpu_ms = 0;
    };
    std::vector<Series> series;
    series.push_back({fmt::format("ideal: every VPL of a {}² RSM (mode 2, tau 0, max_depth 11)", isr.temporal_ideal_rsm),
                      "ideal",
                      {{"mode", 2}, {"tau", 0}, {"max_depth", 11}, {"rsm_size", static_cast<double>(isr.temporal_ideal_rsm)}},
                      {}});
    for (const IsrMode& mode : isr_modes()) series.push_back({mode.label, mode.csv_name, mode.knobs, {}});
    for (Series& s : series) {
        s.knobs["shadow_map_size"] = isr.temporal_shadow_map_size;
        const auto frames = render_series(paper_request(s.knobs, size));
        for (std::size_t f = 0; f < frames.size(); ++f) s.indirect.push_back(difference(frames[f].frame, direct[f]));
        s.vpls_per_fragment = statistic(frames.back(), "vpls_per_fragment_mean");
        s.fragments = statistic(frames.back(), "multires_fragments");
        s.rsm_draws = statistic(frames.back(), "rsm_draws");
        for (const auto& frame : frames) s.gpu_ms += frame.stats.gpu_ms / static_cast<double>(frames.size());
        log::info("bench", "isr temporal {}: {} frames, light-view maps drawn {:.0f} times", s.csv_name, frames.size(),
                  s.rsm_draws);
    }

    struct Summary {
        double mean_delta_pct = 0, p99_delta_pct = 0, flicker_pct = 0, p99_flicker_pct = 0, indirect_mean = 0;
    };
    std::ofstream csv(csv_path);
    csv << "series,frame_pair,first_frame_light_x_m,mean_indirect,mean_abs_delta_pct,p99_abs_delta_pct,mean_abs_delta_vs_ideal_pct,"
           "p99_abs_delta_vs_ideal_pct\n";
    std::vector<Summary> summaries;
    const Series& ideal = series.front();
    for (const Series& s : series) {
        Summary summary;
        const int pairs = isr.temporal_frames - 1;
        for (int f = 0; f < pairs; ++f) {
            const image::Frame& a = s.indirect[f];
            const image::Frame& b = s.indirect[f + 1];
            const double indirect = 0.5 * (mean_rgb(a) + mean_rgb(b));
            const std::vector<double> delta = abs_delta(a, b);
            // The change beyond the light's true motion: this series' Δ minus the ideal series' Δ.
            const image::Frame change = difference(b, a);
            const image::Frame ideal_change = difference(ideal.indirect[f + 1], ideal.indirect[f]);
            const std::vector<double> flicker_pixels = abs_delta(change, ideal_change);
            const double flicker = mean(flicker_pixels);
            const double mean_pct = 100.0 * mean(delta) / indirect;
            const double p99_pct = 100.0 * percentile(delta, 0.99) / indirect;
            const double flicker_pct = 100.0 * flicker / indirect;
            const double p99_flicker_pct = 100.0 * percentile(flicker_pixels, 0.99) / indirect;
            csv << fmt::format("{},{},{:.4f},{:.6g},{:.4f},{:.4f},{:.4f},{:.4f}\n", s.csv_name, f, light_position(f).x,
                               indirect, mean_pct, p99_pct, flicker_pct, p99_flicker_pct);
            summary.mean_delta_pct += mean_pct / pairs;
            summary.p99_delta_pct += p99_pct / pairs;
            summary.flicker_pct += flicker_pct / pairs;
            summary.p99_flicker_pct += p99_flicker_pct / pairs;
            summary.indirect_mean += indirect / pairs;
        }
        summaries.push_back(summary);
    }
    std::string md =
        "| series | mean \\|Δ indirect\\| / mean indirect | excess over ideal | 99th pct pixel \\|Δ\\| / mean indirect | excess "
        "over ideal | mean \\|Δ − Δ ideal\\| / mean indirect | 99th pct \\|Δ − Δ ideal\\| / mean indirect | mean "
        "indirect | VPLs per fragment | multires fragments | GPU ms per frame |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (std::size_t i = 0; i < series.size(); ++i) {
        const Summary& s = summaries[i];
        const Summary& base = summaries.front();
        md += fmt::format("| {} | {:.2f} % | {} | {:.2f} % | {} | {:.2f} % | {:.2f} % | {:.4f} | {:.1f} | {:.0f} | {:.1f} |\n",
                          series[i].label, s.mean_delta_pct,
                          i == 0 ? std::string("—") : fmt::format("{:+.2f} pp", s.mean_delta_pct - base.mean_delta_pct),
                          s.p99_delta_pct,
                          i == 0 ? std::string("—") : fmt::format("{:+.2f} pp", s.p99_delta_pct - base.p99_delta_pct),
                          s.flicker_pct, s.p99_flicker_pct, s.indirect_mean, series[i].vpls_per_fragment, series[i].fragments,
                          series[i].gpu_ms);
    }
    return md;
}

// Where `to` lies as seen from the folder of `from_file` (for Markdown image links).
std::string relative_link(const fs::path& to, const fs::path& from_file) {
    const fs::path target = fs::absolute(to).lexically_normal();
    const fs::path base = fs::absolute(from_file).lexically_normal().parent_path();
    return target.lexically_relative(base).generic_string();
}

// Every isr section, between the markers.
std::string isr_markdown(Renderer& renderer, const Options& options, const std::string& command, const IsrSettings& isr) {
    const scene::Scene scene = scene::make_cornell_box();
    fs::create_directories(options.out);
    const auto start = Clock::now();
    const methods::KnobValues medium = methods::MethodRegistry::builtin().resolve("isr", "medium", {{"ism_size", 0.0}});
    std::string md = std::string(bench::kIsrBegin) + "\n\n## isr in detail (bench/isr)\n\n";
    md += fmt::format(
        "Hierarchical image-space radiosity (isr-nichols-2009) on the built-in Cornell box (one point light, so six "
        "light views — RSM faces — where the paper's 90° spot has one). Written by `{}` on {} (bench/isr writes just "
        "these sections, between the HTML comments; `scripts/bench --isr-only` runs it alone). Machine: {}; GPU: {}. "
        "The paper measured on a GeForce GTX 280 at 1024²; here a software rasterizer runs everything, so compare "
        "shapes and ratios, not milliseconds. Frame sizes and RSM sizes are smaller than the paper's so that the "
        "sections run in about three minutes here (a gather from every VPL costs fragments × VPLs, about 4.5e7 VPL evaluations a second "
        "on this machine). CSVs: `isr_stages.csv`, `isr_fig9.csv`, `isr_fig13.csv`, `isr_temporal.csv` in `{}`; "
        "plots by bench/plot_isr.py.\n",
        command, bench::today(), bench::machine_description(), renderer.gpu_info().summary(), options.out.generic_string());

    // One section: its heading and introduction, then what `body` measures, which writes its CSV to
    // the path it is given (isr_<name>.csv). Timed in the log.
    auto section = [&](const char* heading, const std::string& introduction, const char* name, auto&& body) {
        const auto section_start = Clock::now();
        md += fmt::format("\n### {}\n\n{}", heading, introduction);
        md += body(options.out / fmt::format("isr_{}.csv", name));
        log::info("bench", "isr {}: {:.0f} s", name, ms_since(section_start) / 1000.0);
    };
    // The Markdown link to bench/plot_isr.py's isr_<name>.png.
    auto plot = [&](const char* name) {
        return relative_link(options.out / fmt::format("isr_{}.png", name), options.markdown);
    };

    section("isr per stage (paper Table 1 shape)", fmt::format(
        "{0}x{0} frames, preset `medium` without its imperfect shadow maps, as the paper has it (`ism_size` 0; "
        "RSM {1:.0f}² per light view, {2:.0f} eye-space levels, depth threshold {3}, "
        "normal threshold {4}, tau {5}, max_depth {6:.0f}, shadow maps {7:.0f}²) in three modes; naive takes "
        "max_depth 0, i.e. one point sample from each of the 16² = 256 top patches of each light view — the paper's "
        "256 VPLs, but per light view (its cache holds the samples that carry flux). GPU ms of a **cold** frame: "
        "bench/isr renders through `Renderer::render`, whose method objects live in the scene's "
        "`SceneResources`, so each cold frame is rendered on freshly uploaded resources — shadow maps and "
        "light-view maps drawn, the VPL tree built and the VPL cache selected inside the frame measured (shader "
        "programs are compiled beforehand by a throw-away frame). Median of {8} cold frames by total. The warm row "
        "renders the same view again on the same resources (shadow maps, RSM, tree and cache reused), as a "
        "session with a static light does. The paper's \"direct light\" includes all other rendering overhead.\n\n",
        isr.stage_size, medium.at("rsm_size"), medium.at("levels"), medium.at("depth_threshold"),
        medium.at("normal_threshold"), medium.at("tau"), medium.at("max_depth"), medium.at("shadow_map_size"), isr.repeats),
        "stages", [&](const fs::path& csv) { return isr_stages_markdown(renderer, scene, isr, csv); });

    section("isr error vs depth threshold (paper Fig. 9)", fmt::format(
        "Error from eye-space clustering alone, {0}x{0} frames. Baseline: isr gathering at every pixel (levels 1) "
        "from every VPL of a {1}² RSM per light view (mode 2, tau 0, max_depth 11, so traversal always reaches the "
        "texels: {2} VPLs; the paper used a million). Test: the same VPLs, 5 eye-space levels, the depth threshold "
        "varied, normal threshold 0.3 — and 2, which never splits on normals, to isolate depth. RMSE is over pixels "
        "and RGB of the full frame against the baseline's, given relative to the baseline's mean radiance (the "
        "whole image, direct included) and to the mean of its indirect light alone (isr minus `direct`): the direct "
        "light is identical in both, so every difference is indirect light.\n\n",
        isr.fig9_size, isr.fig9_rsm, 6 * isr.fig9_rsm * isr.fig9_rsm),
        "fig9", [&](const fs::path& csv) { return isr_fig9_markdown(renderer, scene, isr, csv, plot("fig9")); });

    section("isr error vs tau (paper Fig. 13)", fmt::format(
        "Error from light-space clustering alone, {0}x{0} frames (small: the baseline gathers every one of "
        "{1} VPLs at each multiresolution fragment). Baseline: multiresolution gathering (5 levels, depth threshold "
        "0.02, normal threshold 0.3) from every VPL of a {2}² RSM per light view (mode 2, tau 0, max_depth 11). "
        "Test: the same eye-space patches, hierarchical traversal with threshold tau, its finest patches "
        "`max_depth` levels below the 16² top patches (the deepest max_depth reaches the texels, so tau 0 there is "
        "the baseline's very request, not rendered again). RMSE relative as in Fig. 9. The paper's Fig. 13 varies "
        "tau over its own bound (eq. 7-8); ours is relative to the irradiance all reflected flux gives from the "
        "scene's radius (knob `tau`), so the scales differ.\n\n",
        isr.fig13_size, 6 * isr.fig13_rsm * isr.fig13_rsm, isr.fig13_rsm),
        "fig13", [&](const fs::path& csv) { return isr_fig13_markdown(renderer, scene, isr, csv, plot("fig13")); });

    section("isr temporal coherence (paper Fig. 5)", fmt::format(
        "{0}x{0} frames. The Cornell box's point light moves along x in {1} steps of {2:.0f} mm ({3:.0f} mm in all, "
        "centred on its place; the box is 556 mm wide). Each series renders its {4} frames in turn on one persistent "
        "`SceneResources`, as a session moving the light does: every frame redraws the shadow and light-view maps "
        "and rebuilds the VPL tree and cache. Modes at preset `medium` as in the stage table (shadow maps "
        "{5}², which only the direct light uses). Indirect light = the isr frame minus `direct`'s frame (same "
        "shadow maps) at the same light position. Per pair of successive frames: the mean over pixels of "
        "|Δ indirect| (RGB mean) and its 99th percentile, each over the pair's mean indirect; the table averages "
        "over the {1} pairs. The ideal series gathers every VPL of a {6}² RSM per view (medium's RSM size: "
        "no clustering, no point sampling) through the same eye-space patches as the modes (medium's levels and "
        "thresholds; the camera does not move, so the patches stay put), so its change is the light's true "
        "motion as that RSM resolves it. (A gather at every pixel from a 256² RSM, as the paper's ideal would be, "
        "costs about 2.6e10 VPL evaluations a frame: minutes per frame here.) \"Excess\" is a series' value "
        "minus the ideal's (percentage points); |Δ − Δ ideal| is the part of a series' change that is not the "
        "light's motion — the flicker Fig. 5 shows.\n\n",
        isr.temporal_size, isr.temporal_frames - 1, isr.temporal_step * 1000.0,
        (isr.temporal_frames - 1) * isr.temporal_step * 1000.0, isr.temporal_frames, isr.temporal_shadow_map_size,
        isr.temporal_ideal_rsm),
        "temporal", [&](const fs::path& csv) { return isr_temporal_markdown(renderer, scene, isr, csv); });

    const double seconds = ms_since(start) / 1000.0;
    log::info("bench", "isr sections: {:.0f} s", seconds);
    md += fmt::format("\nThe isr sections took {:.0f} s.\n\n{}\n", seconds, bench::kIsrEnd);
    return md;
}

}  // namespace

int main(int argc, char** argv) {
    Options options;
    IsrSettings isr;
    bench::Arguments arguments(argc, argv, "bench/isr", "build/bench/bounce_bench_isr");
    while (arguments.next()) {
        const std::string& flag = arguments.flag();
        if (flag == "--quick") isr.quick();
        else if (flag == "--frames") isr.temporal_frames = std::max(2, arguments.number());
        else if (flag == "--step-mm") isr.temporal_step = 0.001f * static_cast<float>(arguments.number());
        else if (flag == "--out") options.out = arguments.value();
        else if (flag == "--markdown") options.markdown = arguments.value();
        else {
            std::fprintf(stderr,
                         "usage: bounce_bench_isr [--quick] [--frames N] [--step-mm N] [--out DIR] [--markdown FILE]\n"
                         "--quick: every section small (a smoke run); --frames, --step-mm: the light positions of\n"
                         "the temporal section and the distance between them\n");
            return 2;
        }
    }
    try {
        Renderer renderer(gpu::DeviceChoice::resolve(std::nullopt));
        const std::string block = isr_markdown(renderer, options, arguments.command(), isr);
        bench::splice_block(options.markdown, bench::kIsrBegin, bench::kIsrEnd, block);
        log::info("bench", "wrote the isr sections of {} and their CSVs in {}", options.markdown.string(),
                  options.out.string());
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bench/isr: %s\n", error.what());
        return 1;
    }
}
