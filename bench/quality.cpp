// bench/quality: the speed/accuracy trade, measured. For each scene it renders `reference` once at
// high spp (cached on disk), then every method at every preset, and records wall and GPU time,
// resident memory and the error against the reference; it also measures the reference itself
// (error reached per CPU second). Writes a CSV, a Markdown table (docs/benchmarks.md) and, through
// bench/plot_quality.py, a plot of error against time. The isr and cssm sections of the Markdown are
// bench/isr's and bench/cssm's; it keeps them. With --ladder-only, ladder.csv alone: each preset's own
// error against each cheaper preset's, with the reference's noise in their difference
// (bench/preset_ladder.py reads it).
#include "bench/common.hpp"
#include "bench/reference_cache.hpp"
#include "bench/markdown_blocks.hpp"
#include "bench/corpus.hpp"
#include "bench/corpus_priors.hpp"
#include "bench/scenes.hpp"
#include "renderer/base/hash.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/codec.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/image/tone.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene_analysis.hpp"
#include "renderer/scene/builtin.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

namespace {

namespace fs = std::filesystem;
using namespace bounce;
using bench::Clock;
using bench::linear_request;
using bench::ms_since;

struct Options {
    int size = 128;
    int reference_spp = 1024;
    bool corpus = false;  // bench/corpus.hpp's scenes
    // Over every preset of each method that declares them (--knob NAME=VALUE): `isr` with indirect
    // visibility, say.
    methods::KnobValues knobs;
    // The reference's camera rays through pixel centres, as raster methods shade: the error is then
    // the lighting's alone, not also the antialiasing the reference's jittered pixels add.
    bool pixel_centre = false;
    std::optional<fs::path> previews;  // each scene's reference as PNG, to see what is measured
    int detail = 1;
    int reference_bounces = 4;
    // Also against the one-bounce reference that gathers without visibility, as isr does
    // (--unoccluded): what of a one-bounce method's own error its missing visibility explains.
    bool unoccluded = false;
    int repeats = 3;
    std::vector<std::string> methods;  // measure only these (the reference among them); all when empty
    std::vector<std::string> presets;  // of the GPU methods, only these; all when empty
    // The preset ladder (--ladder-only): one frame of each preset after its warm-up, ladder.csv into
    // --out, no other table, and docs/benchmarks.md as it is. Its references are the ones the ladder
    // names (through pixel centres, say), so it is never written beside a quality.csv.
    bool ladder_only = false;
    fs::path out = "bench/results";
    fs::path cache = "build/bench-cache";
    fs::path markdown = "docs/benchmarks.md";
    std::vector<std::string> scenes;  // empty: all
    // A deployment's own scenes (--gltf FILE ...) instead of the bench's, and the planner's priors
    // measured on them (--priors-out FILE: `bounced --priors FILE` plans with them).
    std::vector<fs::path> gltf_files;
    std::optional<fs::path> priors_out;
    // With --priors-out, bench/placement_ladder.py's files of the same scenes (--placements FILE ...):
    // each scene then counts by its largest over placements, as the bench's priors do.
    std::vector<fs::path> placement_files;
    bench::PlacementErrors placements;
    bool out_given = false, markdown_given = false;
};

struct Row {
    std::string scene, method, preset;
    int bounces = 0;
    double wall_ms = 0, gpu_ms = 0;
    std::string passes;
    std::size_t resident_bytes = 0;
    double rel_mse = 0, rmse = 0, rel_mse_same_bounces = 0, mean_ratio = 0;
    // One-bounce GPU methods with --unoccluded: against the one-bounce reference without visibility.
    std::optional<double> rel_mse_unoccluded, mean_ratio_unoccluded;
    double rays_per_second = 0;
    double cold_ms = 0;  // GPU methods: the first frame, which builds the scene's structures
    // GPU methods: a frame after every light changed (bench::change_every_light): what the lights
    // feed is redone (FrameChange::lights), the structures are kept.
    double relit_ms = 0;
    // GPU methods: the shadow_maps pass of the first and of the relit frame (each draws every map):
    // what the planner prices apart, from the scene's own shadow-map timings (planner.hpp).
    double cold_shadow_ms = 0, relit_shadow_ms = 0;
    // GPU methods: a frame after every light was dimmed by 0.1% alone (FrameChange::light_power: no
    // shadow map redrawn).
    double dimmed_ms = 0;
};

// Each preset of a method on a scene against each cheaper preset of the same bounce count: the
// difference of their own errors (against the reference at those bounces) and the standard
// deviation the reference's noise gives that difference (image::rel_mse_difference_noise). A
// preset's own error falls with its time where each difference is negative, or within two of these.
struct LadderRow {
    std::string scene, method, preset, cheaper;
    int bounces = 0;
    double rel_mse_same_bounces = 0, cheaper_rel_mse_same_bounces = 0, noise = 0;
    // The scene analysis finds walls thinner than a voxel of either preset (vct): the planner rules
    // such a preset out on the scene, whatever its error.
    bool thin_walls = false;
};

void write_ladder_csv(const fs::path& path, const std::vector<LadderRow>& rows) {
    std::ofstream out(path);
    out << "scene,method,preset,cheaper,bounces,rel_mse_same_bounces,cheaper_rel_mse_same_bounces,difference,noise,"
           "thin_walls\n";
    for (const LadderRow& r : rows) {
        out << fmt::format("{},{},{},{},{},{:.9g},{:.9g},{:.9g},{:.3g},{}\n", r.scene, r.method, r.preset, r.cheaper,
                           r.bounces, r.rel_mse_same_bounces, r.cheaper_rel_mse_same_bounces,
                           r.rel_mse_same_bounces - r.cheaper_rel_mse_same_bounces, r.noise, r.thin_walls ? 1 : 0);
    }
}

bench::ReferenceSpec reference_spec(const Options& options) {
    bench::ReferenceSpec spec;
    spec.size = options.size;
    spec.spp = options.reference_spp;
    spec.pixel_centre = options.pixel_centre;
    spec.cache = options.cache;
    return spec;
}

void write_csv(const fs::path& path, const std::vector<Row>& rows) {
    std::ofstream out(path);
    out << "scene,method,preset,bounces,wall_ms,gpu_ms,passes_ms,resident_bytes,rel_mse,rmse,rel_mse_same_bounces,"
           "mean_ratio,rays_per_second,cold_ms,relit_ms,cold_shadow_ms,relit_shadow_ms,dimmed_ms,rel_mse_unoccluded,"
           "mean_ratio_unoccluded\n";
    for (const Row& r : rows) {
        out << fmt::format("{},{},{},{},{:.3f},{:.3f},{},{},{:.6g},{:.6g},{:.6g},{:.5f},{:.4g},", r.scene, r.method,
                           r.preset, r.bounces, r.wall_ms, r.gpu_ms, r.passes, r.resident_bytes, r.rel_mse, r.rmse,
                           r.rel_mse_same_bounces, r.mean_ratio, r.rays_per_second)
            << fmt::format("{:.3f},{:.3f},{:.3f},{:.3f},{:.3f}", r.cold_ms, r.relit_ms, r.cold_shadow_ms,
                           r.relit_shadow_ms, r.dimmed_ms);
        const auto optional = [](const std::optional<double>& value) {
            return value ? fmt::format("{:.6g}", *value) : std::string();
        };
        out << "," << optional(r.rel_mse_unoccluded) << "," << optional(r.mean_ratio_unoccluded) << "\n";
    }
}

// vct in detail: per-pass GPU ms of a cold frame (octree built, light injected, mipmapped, cones
// traced) and of a warm one (cones only), with the octree's size, at each preset and frame size.
std::string vct_passes_markdown(Renderer& renderer, const scene::Scene& scene, const std::vector<int>& sizes) {
    const char* passes[] = {"vct_voxelize", "vct_octree_build", "vct_leaf_sums", "light_view_maps", "vct_inject",
                            "vct_bricks",   "vct_mipmap",       "vct_cone_trace"};
    std::string md =
        "| size | preset | structure | voxelize | octree build | leaf sums | light views | inject | bricks | mipmap | "
        "cone trace | cold GPU ms | warm GPU ms | warm wall ms | nodes | structure MiB | resident MiB |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const int size : sizes) {
        for (const auto& preset : methods::preset_names()) {
            for (const int dense : {0, 1}) {
                auto resources = renderer.upload(scene);
                const RenderRequest request = linear_request("vct", preset, {{"dense", dense}}, size);
                const RenderResult cold = renderer.render(*resources, request);
                const RenderResult warm = renderer.render(*resources, request);
                std::map<std::string, double> ms;
                for (const auto& pass : cold.stats.passes) ms[pass.pass] += pass.gpu_ms;
                md += fmt::format("| {}² | {} | {} ", size, preset, dense ? "dense" : "sparse");
                for (const char* pass : passes) md += fmt::format("| {:.1f} ", ms[pass]);
                md += fmt::format("| {:.1f} | {:.1f} | {:.1f} | {:.0f} | {:.2f} | {:.1f} |\n", cold.stats.gpu_ms,
                                  warm.stats.gpu_ms, warm.stats.render_ms,
                                  cold.stats.method_statistics.at("octree_nodes"),
                                  cold.stats.method_statistics.at("octree_bytes") / 1048576.0,
                                  cold.stats.resident_bytes / 1048576.0);
                log::info("bench", "vct passes {}x{} {} {}: cold {:.0f} ms, warm {:.0f} ms", size, size, preset,
                          dense ? "dense" : "sparse", cold.stats.gpu_ms, warm.stats.gpu_ms);
            }
        }
    }
    return md;
}

// Light leaking through the thin wall: the reference is exactly zero below the slab, so the leak is
// the method's mean radiance over those pixels, relative to the reference's mean over the lit ones.
std::string leak_markdown(Renderer& renderer, const scene::Scene& scene, const image::Frame& truth, int size) {
    std::string md = "| method | preset | anisotropic | leak (dark-pixel mean / lit-pixel mean) |\n|---|---|---|---|\n";
    auto leak_of = [&](const image::Frame& frame) { return image::leak(frame, truth).ratio; };
    auto resources = renderer.upload(scene);
    for (const auto& preset : methods::preset_names()) {
        for (const int anisotropic : {1, 0}) {
            const RenderRequest request = linear_request("vct", preset, {{"anisotropic", anisotropic}}, size);
            const double leak = leak_of(renderer.render(*resources, request).frame);
            md += fmt::format("| vct | {} | {} | {:.4f} |\n", preset, anisotropic ? "on" : "off", leak);
            log::info("bench", "thin_wall leak vct {} anisotropic={}: {:.4f}", preset, anisotropic, leak);
        }
    }
    md += fmt::format("| direct | medium | — | {:.4f} |\n",
                      leak_of(renderer.render(*resources, linear_request("direct", "medium", {}, size)).frame));
    return md;
}

// Rewrites the Markdown file, keeping the isr and cssm sections (bench/isr's and bench/cssm's) as they were.
void write_markdown(const fs::path& path, const std::vector<Row>& rows, const Options& options, const std::string& gpu,
                    const std::string& command, const std::string& details) {
    std::ostringstream md;
    const std::string_view begin = options.corpus ? bench::kCorpusBegin : bench::kQualityBegin;
    const std::string_view end = options.corpus ? bench::kCorpusEnd : bench::kQualityEnd;
    md << begin << "\n\n"
       << (options.corpus ? "## Speed and accuracy on the bench corpus (bench/quality --corpus)\n\n"
                          : "## Speed and accuracy (bench/quality)\n\n")
       << (options.corpus ? "The scenes of bench/corpus.hpp, generated in code (previews of their references in "
                            "bench/results/corpus/).\n\n"
                          : "")
       << "Written by `" << command << "` on " << bench::today() << ".\n\n"
       << "- Machine: " << bench::machine_description() << "\n"
       << "- GPU: " << gpu << "\n"
       << fmt::format("- Frames {0}x{0}; reference: {1} spp, {2} indirect bounces (cached in {3}).\n", options.size,
                      options.reference_spp, options.reference_bounces, options.cache.string())
       << [&] {
              std::string knobs;
              for (const auto& [name, value] : options.knobs) knobs += fmt::format("{}`{}` = {:g}", knobs.empty() ? "" : ", ", name, value);
              return knobs.empty() ? std::string() : "- Knobs over every preset of the methods that have them: " + knobs + ".\n";
          }()
       << "- Error: relMSE = mean over pixels and RGB of (t−r)²/(r²+0.01) on linear HDR, against the full\n"
       << "  reference (`rel_mse`) and against the reference at the bounce count the method models\n"
       << "  (`rel_mse_same_bounces`, which isolates the method's own approximations).\n"
       << "- GPU method times are the median of " << options.repeats << " renders of a static view after one warm-up\n"
       << "  (structures that depend only on the scene, such as shadow maps, are then reused); wall time\n"
       << "  includes readback. Reference times are CPU wall time for a fresh image. `direct`'s presets\n"
       << "  differ only in shadow-map size, which costs time only in frames where the maps are redrawn.\n\n"
       << (options.corpus ? "" : "![error against time](../bench/results/quality.png)\n\n")
       << "| scene | method | preset | bounces | wall ms | GPU ms | resident MiB | relMSE | relMSE same bounces | RMSE | mean / ref |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows) {
        md << fmt::format("| {} | {} | {} | {} | {:.1f} | {:.1f} | {:.1f} | {:.4f} | {:.5f} | {:.4f} | {:.3f} |\n", r.scene,
                          r.method, r.preset, r.bounces, r.wall_ms, r.gpu_ms, r.resident_bytes / 1048576.0, r.rel_mse,
                          r.rel_mse_same_bounces, r.rmse, r.mean_ratio);
    }
    md << "\nReference rows: `preset` is the sample count; its rays per second:\n\n| scene | spp | rays/s |\n|---|---|---|\n";
    for (const Row& r : rows) {
        if (r.method == "reference") md << fmt::format("| {} | {} | {:.3g} |\n", r.scene, r.preset, r.rays_per_second);
    }
    if (options.unoccluded) {
        md << "\nOne-bounce GPU methods against the one-bounce reference and against the same reference gathering\n"
              "without visibility, as isr does (`--unoccluded`; PathTracerSettings::indirect_visibility): where\n"
              "the second is the smaller, missing visibility explains that much of the method's own error.\n\n"
              "| scene | method | preset | relMSE one bounce | relMSE unoccluded | mean / unoccluded |\n"
              "|---|---|---|---|---|---|\n";
        for (const Row& r : rows) {
            if (!r.rel_mse_unoccluded) continue;
            md << fmt::format("| {} | {} | {} | {:.5f} | {:.5f} | {:.3f} |\n", r.scene, r.method, r.preset,
                              r.rel_mse_same_bounces, *r.rel_mse_unoccluded, r.mean_ratio_unoccluded.value_or(0.0));
        }
    }
    md << details << "\n" << end << "\n";
    // Only this bench's block changes: the other benches' sections and the hand-written ones stay.
    if (!fs::exists(path)) std::ofstream(path) << "# Benchmarks\n\n";
    bench::splice_block(path, begin, end, md.str());
}

// A frame tone-mapped to PNG, to see what was measured.
void write_preview(const fs::path& path, image::Frame frame) {
    image::make_display_image(frame, {});
    fs::create_directories(path.parent_path());
    const auto png = image::encode_image(frame, image::ImageFormat::png);
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
}

// The planner's priors from this run's quality.csv: per GPU method and preset, the largest and the
// median over the scenes measured (vct's presets left out where the analysis finds them leaking),
// as the corpus' are computed (bench/corpus_priors.hpp; the committed tables also count the Cornell
// variants for vct, which a run of the corpus alone does not); `bounced --priors FILE` plans with
// them, and with the bench's where this run measured nothing. With --placements, each scene counts
// by its largest over the placements measured of it (and their mean in the median), as the bench's
// own priors do. The file is read back as the daemon reads it before it is written.
void write_priors(const fs::path& file, const Options& options, const std::vector<bench::BenchScene>& scenes) {
    std::vector<bench::BenchScene> measured;
    std::vector<std::string> names;
    for (const auto& scene : scenes) {
        if (!options.scenes.empty() &&
            std::find(options.scenes.begin(), options.scenes.end(), scene.name) == options.scenes.end()) {
            continue;
        }
        measured.push_back(scene);
        names.push_back(scene.name);
    }
    // A two-bounce table in --out is another run's, unless these are the corpus' scenes.
    planning::OwnErrorPriors priors =
        bench::corpus_priors(options.out, bench::thin_walls_of(measured), {}, /*two_bounce_table=*/options.corpus,
                             options.placements);
    priors.source = fmt::format("the scene{} {}", names.size() == 1 ? "" : "s", fmt::join(names, ", "));
    const nlohmann::json tables = priors.to_json();
    if (!tables.contains("largest")) {
        throw std::runtime_error("--priors-out: no GPU method was measured (--method names none?)");
    }
    planning::OwnErrorPriors::from_json(tables, planning::OwnErrorPriors::bench(), file.string());
    if (file.has_parent_path()) fs::create_directories(file.parent_path());
    std::ofstream out(file);
    out << tables.dump(2) << "\n";
    if (!out) throw std::runtime_error(fmt::format("--priors-out: cannot write {}", file.string()));
    log::info("bench", "wrote the planner's priors from {} to {} (bounced --priors {})", priors.source, file.string(),
              file.string());
}

// One row of the corpus's analysis table.
std::string analysis_row(const bench::BenchScene& bench_scene) {
    const SceneAnalysis analysis = analyze_scene(bench_scene.scene);
    std::string leaks;
    for (const auto& preset : methods::preset_names()) {
        if (analysis.thin_walls.leaks(preset)) leaks += (leaks.empty() ? "" : ", ") + preset;
    }
    const BounceEnergy& bounces = analysis.bounces;
    return fmt::format("| {} | {} | {} / {} / {} | {} | {:.2f} | {} |\n", bench_scene.name, bench_scene.scene.triangle_count(),
                       bounces.bounces_for(0.1), bounces.bounces_for(0.05), bounces.bounces_for(0.02),
                       leaks.empty() ? "none" : leaks, analysis.visibility.occluded_fraction,
                       analysis.visibility.mostly_occluded() ? "no" : "yes");
}

}  // namespace

int main(int argc, char** argv) {
    Options options;
    bench::Arguments arguments(argc, argv, "quality", "scripts/bench");
    while (arguments.next()) {
        const std::string& flag = arguments.flag();
        if (flag == "--size") options.size = arguments.number();
        else if (flag == "--reference-spp") options.reference_spp = arguments.number();
        else if (flag == "--reference-bounces") options.reference_bounces = arguments.number();
        else if (flag == "--repeats") options.repeats = std::max(1, arguments.number());
        else if (flag == "--out") options.out = arguments.value(), options.out_given = true;
        else if (flag == "--cache") options.cache = arguments.value();
        else if (flag == "--markdown") options.markdown = arguments.value(), options.markdown_given = true;
        else if (flag == "--gltf") options.gltf_files.emplace_back(arguments.value());
        else if (flag == "--priors-out") options.priors_out = arguments.value();
        else if (flag == "--placements") options.placement_files.emplace_back(arguments.value());
        else if (flag == "--scene") options.scenes.push_back(arguments.value());
        else if (flag == "--corpus") options.corpus = true;
        else if (flag == "--pixel-centre") options.pixel_centre = true;
        else if (flag == "--previews") options.previews = arguments.value();
        else if (flag == "--detail") options.detail = std::max(1, arguments.number());
        else if (flag == "--method") options.methods.push_back(arguments.value());
        else if (flag == "--preset") options.presets.push_back(arguments.value());
        else if (flag == "--ladder-only") options.ladder_only = true;
        else if (flag == "--knob") arguments.knob(options.knobs);
        else if (flag == "--unoccluded") options.unoccluded = true;
        else {
            std::fprintf(stderr,
                         "usage: quality [--size N] [--reference-spp N] [--reference-bounces N] [--repeats N]\n"
                         "               [--scene NAME ...] [--method NAME ...] [--preset NAME ...]\n"
                         "               [--knob NAME=VALUE ...]\n"
                         "               [--corpus [--detail N] | --gltf FILE ...] [--priors-out FILE [--placements FILE ...]]\n"
                         "               [--pixel-centre] [--unoccluded] [--ladder-only]\n"
                         "               [--previews DIR]\n"
                         "               [--out DIR]\n"
                         "               [--cache DIR]\n"
                         "               [--markdown FILE]\n"
                         "(--corpus: bench/corpus.hpp's scenes instead of the Cornell variants)\n"
                         "(the isr sections are bench/isr's: bounce_bench_isr)\n");
            return 2;
        }
    }
    if (options.ladder_only && (options.priors_out || !options.out_given)) {
        std::fprintf(stderr, "quality: --ladder-only writes the ladder alone, into an --out of its own\n");
        return 2;
    }
    if (options.priors_out && (!options.knobs.empty() || !options.presets.empty())) {
        std::fprintf(stderr, "quality: --priors-out measures every preset as it is (not with --knob or --preset)\n");
        return 2;
    }
    if (!options.placement_files.empty()) {
        if (!options.priors_out) {
            std::fprintf(stderr, "quality: --placements is read by --priors-out alone\n");
            return 2;
        }
        // Read before anything is measured: a file that cannot be read would otherwise fail the run at its end.
        try {
            options.placements = bench::read_placement_errors(options.placement_files);
        } catch (const std::exception& error) {
            std::fprintf(stderr, "quality: --placements: %s\n", error.what());
            return 2;
        }
    }
    // An experiment (a preset alone, or knobs of its own) is not the bench's table: it would replace
    // the committed docs/benchmarks.md and bench/results/quality.csv with a part of them.
    if ((!options.knobs.empty() || !options.presets.empty()) && !options.ladder_only &&
        (!options.out_given || !options.markdown_given)) {
        std::fprintf(stderr, "quality: --knob and --preset measure an experiment, into an --out and a --markdown of "
                             "their own (not bench/results/quality.csv and docs/benchmarks.md)\n");
        return 2;
    }
    for (const std::string& preset : options.presets) {
        const auto& names = methods::preset_names();
        if (std::find(names.begin(), names.end(), preset) == names.end()) {
            std::fprintf(stderr, "quality: unknown preset '%s'\n", preset.c_str());
            return 2;
        }
    }
    if (!options.gltf_files.empty() &&
        (options.corpus || !options.out_given || (!options.markdown_given && !options.ladder_only))) {
        std::fprintf(stderr, "quality: --gltf measures your scenes instead of the bench's (not with --corpus), into an "
                             "--out and a --markdown of their own\n");
        return 2;
    }
    const std::string& command = arguments.command();
    for (const std::string& method : options.methods) {
        const auto names = methods::MethodRegistry::builtin().names();
        if (std::find(names.begin(), names.end(), method) == names.end()) {
            std::fprintf(stderr, "quality: unknown method '%s'\n", method.c_str());
            return 2;
        }
    }
    const auto measured = [&](const std::string& method) {
        return options.methods.empty() ||
               std::find(options.methods.begin(), options.methods.end(), method) != options.methods.end();
    };
    try {
        Renderer renderer(gpu::DeviceChoice::resolve(std::nullopt));
        std::vector<Row> rows;
        std::vector<LadderRow> ladder;
        std::string details, analysis_rows;
        const auto& registry = methods::MethodRegistry::builtin();
        const std::vector<bench::BenchScene> scenes =
            !options.gltf_files.empty() ? bench::gltf_scenes(options.gltf_files)
            : options.corpus            ? bench::corpus_scenes(options.detail)
                                        : bench::quality_scenes();
        for (const auto& bench_scene : scenes) {
            if (!options.scenes.empty() &&
                std::find(options.scenes.begin(), options.scenes.end(), bench_scene.name) == options.scenes.end()) {
                continue;
            }
            methods::reference::PathTracer tracer(bench_scene.scene);
            const image::Frame truth = bench::reference_image(bench_scene, tracer, reference_spec(options), options.reference_bounces);
            if (options.previews) write_preview(*options.previews / (bench_scene.name + ".png"), truth);
            std::map<int, image::Frame> truth_by_bounces;
            auto truth_at = [&](int bounces) -> const image::Frame& {
                if (bounces == options.reference_bounces) return truth;
                auto it = truth_by_bounces.find(bounces);
                if (it == truth_by_bounces.end()) {
                    it = truth_by_bounces.emplace(bounces, bench::reference_image(bench_scene, tracer, reference_spec(options), bounces)).first;
                }
                return it->second;
            };
            // The one-bounce reference without visibility, traced when a one-bounce method first needs it.
            std::optional<image::Frame> unoccluded;
            auto unoccluded_truth = [&]() -> const image::Frame& {
                if (!unoccluded) {
                    bench::ReferenceSpec spec = reference_spec(options);
                    spec.indirect_visibility = false;
                    unoccluded = bench::reference_image(bench_scene, tracer, spec, 1);
                }
                return *unoccluded;
            };
            analysis_rows += analysis_row(bench_scene);
            // Where vct's voxels are wider than the scene's walls (the planner rules such presets out).
            const ThinWalls thin_walls = options.ladder_only && measured("vct")
                                             ? bench::thin_walls_of({bench_scene}).at(bench_scene.name)
                                             : ThinWalls{};
            std::map<int, std::vector<float>> variance_by_bounces;  // of the reference at each bounce count
            auto variance_at = [&](int bounces) -> const std::vector<float>& {
                auto it = variance_by_bounces.find(bounces);
                if (it == variance_by_bounces.end()) {
                    const auto spec = reference_spec(options);
                    auto variance = bench::reference_variance(bench_scene, tracer, spec, bounces);
                    it = variance_by_bounces.emplace(bounces, std::move(variance)).first;
                }
                return it->second;
            };
            scene::Scene relit_scene = bench_scene.scene;  // its lights change to time a relit frame
            auto resources = renderer.upload(relit_scene);
            for (const auto& method : registry.names()) {
                if (plan_frame(linear_request(method, "medium", {}, options.size)).site != FrameSite::gpu) {
                    continue;  // CPU methods (the reference) are measured below
                }
                if (!measured(method)) continue;
                methods::KnobValues knobs;
                for (const auto& [name, value] : options.knobs) {
                    const auto& declared = registry.find(method).knobs;
                    const std::string& knob_name = name;  // a lambda may not capture a structured binding (clang)
                    if (std::any_of(declared.begin(), declared.end(), [&](const auto& knob) { return knob.name == knob_name; })) {
                        knobs[name] = value;
                    }
                }
                struct Rung {
                    std::string preset;
                    int bounces;
                    double rel_mse_same_bounces;
                    image::Frame frame;
                };
                std::vector<Rung> rungs;  // the presets measured so far, cheapest first
                for (const auto& preset : methods::preset_names()) {
                    if (!options.presets.empty() &&
                        std::find(options.presets.begin(), options.presets.end(), preset) == options.presets.end()) {
                        continue;
                    }
                    const RenderRequest request = linear_request(method, preset, knobs, options.size);
                    const RenderResult cold = renderer.render(*resources, request);  // warm-up: shaders, structures
                    std::vector<RenderResult> results;
                    const int repeats = options.ladder_only ? 1 : options.repeats;
                    for (int r = 0; r < repeats; ++r) results.push_back(renderer.render(*resources, request));
                    std::sort(results.begin(), results.end(),
                              [](const auto& a, const auto& b) { return a.stats.render_ms < b.stats.render_ms; });
                    const RenderResult& median = results[results.size() / 2];
                    RenderResult relit;  // the ladder times no relit frame
                    double dimmed_ms = 0.0;
                    if (!options.ladder_only) {
                        // Every light changed by amounts no comparison sees; back as they were for the next preset.
                        bench::change_every_light(relit_scene, bench_scene.scene.lights, 1);
                        relit = renderer.render(*resources, request);
                        relit_scene.lights = bench_scene.scene.lights;
                        renderer.render(*resources, request);  // lit as they are again
                        for (scene::Light& light : relit_scene.lights) light.intensity *= 1.001f;
                        dimmed_ms = renderer.render(*resources, request).stats.render_ms;
                        relit_scene.lights = bench_scene.scene.lights;
                    }
                    if (options.previews && preset == "medium") {
                        write_preview(*options.previews / fmt::format("{}-{}.png", bench_scene.name, method), median.frame);
                    }
                    Row row;
                    row.scene = bench_scene.name;
                    row.method = method;
                    row.preset = preset;
                    const auto bounces_knob = median.stats.knobs.find("bounces");
                    row.bounces = bounces_knob == median.stats.knobs.end() ? registry.find(method).indirect_bounces
                                                                           : static_cast<int>(bounces_knob->second);
                    row.wall_ms = median.stats.render_ms;
                    row.gpu_ms = median.stats.gpu_ms;
                    row.cold_ms = cold.stats.render_ms;
                    row.relit_ms = relit.stats.render_ms;
                    row.dimmed_ms = dimmed_ms;
                    row.cold_shadow_ms = cold.stats.pass_ms("shadow_maps");
                    row.relit_shadow_ms = relit.stats.pass_ms("shadow_maps");
                    for (const auto& pass : median.stats.passes) {
                        row.passes += fmt::format("{}{}={:.2f}", row.passes.empty() ? "" : ";", pass.pass, pass.gpu_ms);
                    }
                    row.resident_bytes = median.stats.resident_bytes;
                    const auto full = image::compare(median.frame, truth);
                    row.rel_mse = full.rel_mse;
                    row.rmse = full.rmse;
                    row.mean_ratio = full.mean_reference > 0 ? full.mean_test / full.mean_reference : 0.0;
                    row.rel_mse_same_bounces = image::compare(median.frame, truth_at(row.bounces)).rel_mse;
                    // relMSE skips pixels that are not finite: a frame of them would read as exact. It
                    // is measured as nothing (NaN), which --priors-out refuses to promise.
                    if (const std::size_t bad = median.frame.non_finite_count(); bad > 0) {
                        log::warn("bench", "{} {} {}: {} values not finite; its relMSE is not measured", row.scene,
                                  method, preset, bad);
                        row.rel_mse = row.rel_mse_same_bounces = std::numeric_limits<double>::quiet_NaN();
                    }
                    if (options.unoccluded && row.bounces == 1) {
                        const auto against = image::compare(median.frame, unoccluded_truth());
                        row.rel_mse_unoccluded = against.rel_mse;
                        row.mean_ratio_unoccluded =
                            against.mean_reference > 0 ? against.mean_test / against.mean_reference : 0.0;
                    }
                    std::string cold_passes;
                    for (const auto& pass : cold.stats.passes) {
                        if (pass.gpu_ms >= 1.0) cold_passes += fmt::format(" {}={:.0f}", pass.pass, pass.gpu_ms);
                    }
                    log::info("bench", "{} {} {}: {:.1f} ms (first frame {:.1f} ms, relit {:.1f} ms, GPU ms over 1:{}) relMSE {:.4f} (same bounces {:.5f})",
                              row.scene, method, preset, row.wall_ms, row.cold_ms, row.relit_ms, cold_passes, row.rel_mse,
                              row.rel_mse_same_bounces);
                    rows.push_back(row);
                    if (options.ladder_only && std::isfinite(row.rel_mse_same_bounces)) {
                        for (const Rung& cheaper : rungs) {
                            if (cheaper.bounces != row.bounces) continue;
                            const double noise = image::rel_mse_difference_noise(
                                cheaper.frame, median.frame, truth_at(row.bounces), variance_at(row.bounces));
                            const bool thin =
                                method == "vct" && (thin_walls.leaks(preset) || thin_walls.leaks(cheaper.preset));
                            ladder.push_back({row.scene, method, preset, cheaper.preset, row.bounces,
                                              row.rel_mse_same_bounces, cheaper.rel_mse_same_bounces, noise, thin});
                        }
                        rungs.push_back({preset, row.bounces, row.rel_mse_same_bounces, median.frame});
                    }
                }
            }
            resources.reset();
            if (bench_scene.name == "cornell" && measured("vct") && !options.ladder_only) {
                details += "\n## vct per pass (bench/quality)\n\nThe built-in Cornell box. Cold: a fresh scene, so the "
                           "octree is built, the light injected and mipmapped, then cones traced; warm: the same view "
                           "again (cones only). Sparse: the octree; dense: the same pipeline over every level's "
                           "full lattice (knob `dense`). Structure MiB: nodes, leaf data and voxel pools.\n\n" +
                           vct_passes_markdown(renderer, bench_scene.scene, {256, 512});
            }
            if (bench_scene.name == "thin_wall" && measured("vct") && !options.ladder_only) {
                details += fmt::format("\n## Light leaking through a thin wall (bench/quality, {0}x{0})\n\n"
                                       "thin_wall: a 2 cm slab seals the light above it, so the reference is exactly "
                                       "zero below it.\n\n",
                                       options.size) +
                           leak_markdown(renderer, bench_scene.scene, truth, options.size);
            }
            // The reference itself: error reached per CPU second.
            for (const int spp : {1, 4, 16, 64}) {
                if (!measured("reference") || options.ladder_only) break;
                methods::reference::PathTracerSettings settings;
                settings.max_bounces = options.reference_bounces;
                settings.seed = 7;
                settings.pixel_jitter = !options.pixel_centre;  // as the reference it is compared with
                const auto rays_before = tracer.rays_traced();
                const auto start = Clock::now();
                const image::Frame frame = tracer.render(bench_scene.scene.cameras[0], options.size, options.size, spp, settings);
                Row row;
                row.scene = bench_scene.name;
                row.method = "reference";
                row.preset = std::to_string(spp);
                row.bounces = options.reference_bounces;
                row.wall_ms = ms_since(start);
                row.rays_per_second = static_cast<double>(tracer.rays_traced() - rays_before) / (row.wall_ms / 1000.0);
                const auto error = image::compare(frame, truth);
                row.rel_mse = row.rel_mse_same_bounces = error.rel_mse;
                row.rmse = error.rmse;
                row.mean_ratio = error.mean_reference > 0 ? error.mean_test / error.mean_reference : 0.0;
                log::info("bench", "{} reference {} spp: {:.0f} ms relMSE {:.4f}", row.scene, spp, row.wall_ms, row.rel_mse);
                rows.push_back(row);
            }
        }
        details += "\n## What each scene needs (scene analysis)\n\n`bounce describe --analyze` on each scene "
                   "(renderer/scene_analysis.hpp): the indirect bounces whose frame lacks at most 10%, 5% and 2% "
                   "of the light, the vct presets with walls thinner than a voxel between two spaces, and the "
                   "share of light-to-receiver pairs that are occluded (isr without imperfect shadow maps "
                   "ignores it).\n\n"
                   "| scene | triangles | bounces for 10% / 5% / 2% | vct leaks at | occluded | "
                   "isr draft suitable |\n"
                   "|---|---|---|---|---|---|\n" +
                   analysis_rows;
        fs::create_directories(options.out);
        if (options.ladder_only) {  // never beside a quality.csv of other references
            write_ladder_csv(options.out / "ladder.csv", ladder);
            log::info("bench", "wrote {}", (options.out / "ladder.csv").string());
            return 0;
        }
        write_csv(options.out / "quality.csv", rows);
        write_markdown(options.markdown, rows, options, renderer.gpu_info().summary(), command, details);
        log::info("bench", "wrote {} and {}", (options.out / "quality.csv").string(), options.markdown.string());
        if (options.priors_out) write_priors(*options.priors_out, options, scenes);
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "quality: %s\n", error.what());
        return 1;
    }
}
