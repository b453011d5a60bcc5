// bench/cssm: method `cssm` in the shape of its paper ([cssm] in docs/references.md), on
// the built-in Cornell box and on cornell_blob (an organic, UV-less mesh):
// - Table 2: compression per traversal (greedy, zig-zag, spiral) and atlas size, 6x32^2 cube maps;
// - Table 3: cube maps, bytes raw and compressed, ratio and bake time per atlas size, 6x64^2;
// - Fig. 14: how often a cube-map visibility answer disagrees with an exact ray query (Embree),
//   per cube face size, over random pairs of atlas texels that face each other;
// - Table 1: frame times (llvmpipe here) for 1 and 2 bounces;
// - error against the path-traced reference with the same bounce count, per preset, n = 1, 2, 3.
// Writes bench/results/cssm_*.csv and the cssm sections of docs/benchmarks.md.
#include "bench/markdown_blocks.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/cssm/atlas_traversal.hpp"
#include "renderer/methods/cssm/surface_shadow_maps.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/raytrace/ray_scene.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene/builtin.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <random>
#include <thread>

namespace {

namespace fs = std::filesystem;
using namespace bounce;

struct Options {
    fs::path out = "bench/results";
    fs::path markdown = "docs/benchmarks.md";
    bool quick = false;  // every section small: a smoke run
    int size = 64;       // frames for the error and time tables
    int reference_spp = 512;
};

RenderRequest request(const std::string& preset, methods::KnobValues knobs, int size) {
    RenderRequest r;
    r.method = "cssm";
    r.preset = preset;
    r.knobs = std::move(knobs);
    r.width = r.height = size;
    r.make_display_image = false;
    return r;
}

double stat(const FrameStats& stats, const std::string& name) {
    const auto it = stats.method_statistics.find(name);
    return it == stats.method_statistics.end() ? 0.0 : it->second;
}

std::string mib(double bytes) { return fmt::format("{:.1f} MB", bytes / 1e6); }

// Bakes through the daemon's own path (Renderer::prepare, the `bake` request) and reads the stats.
FrameStats bake(Renderer& renderer, const scene::Scene& scene, methods::KnobValues knobs) {
    auto resources = renderer.upload(scene);
    return renderer.prepare(*resources, request("medium", std::move(knobs), 8), {});
}

std::string compression_table(Renderer& renderer, const Options& options, std::ofstream& csv) {
    const scene::Scene scene = scene::make_cornell_box();
    const std::vector<int> atlases = options.quick ? std::vector<int>{16} : std::vector<int>{32, 64, 128};
    std::string md = "| atlas | texels | greedy | zig-zag | spiral |\n|---|---|---|---|---|\n";
    csv << "atlas,traversal,texels,cube_maps,uncompressed_bytes,compressed_bytes,ratio,bake_s\n";
    for (const int atlas : atlases) {
        std::string row;
        double texels = 0.0;
        for (const int traversal : {0, 1, 2}) {
            const FrameStats stats =
                bake(renderer, scene, {{"atlas_resolution", atlas}, {"face_size", 32}, {"traversal", traversal}});
            texels = stat(stats, "atlas_texels");
            row += fmt::format(" {:.1f} : 1 |", stat(stats, "compression_ratio"));
            csv << fmt::format("{},{},{},{},{},{},{:.3f},{:.2f}\n", atlas, traversal, texels, stat(stats, "cube_maps"),
                               stat(stats, "uncompressed_bytes"), stat(stats, "compressed_bytes"),
                               stat(stats, "compression_ratio"), stat(stats, "bake_seconds"));
            log::info("bench", "table 2: atlas {} traversal {}: {:.1f}:1", atlas, traversal, stat(stats, "compression_ratio"));
        }
        md += fmt::format("| {0}x{0} | {1:.0f} |{2}\n", atlas, texels, row);
    }
    md += "| paper (6x32^2, its Cornell box; 32^2 / 64^2 / 128^2) | | 5.6 / 8.8 / 12.8 | 7.1 / 11.2 / 15.7 | 7.4 / 11.7 / 16.9 |\n";
    return md;
}

std::string bake_table(Renderer& renderer, const Options& options, std::ofstream& csv) {
    const std::vector<int> atlases = options.quick ? std::vector<int>{16} : std::vector<int>{32, 64, 128};
    const int face = options.quick ? 16 : 64;
    std::string md = fmt::format("| scene | atlas | cube maps | uncompressed | compressed | ratio | bake time |\n"
                                 "|---|---|---|---|---|---|---|\n");
    csv << "scene,atlas,face,cube_maps,uncompressed_bytes,compressed_bytes,ratio,bake_s\n";
    for (const std::string name : {"cornell", "cornell_blob"}) {
        const scene::Scene scene = scene::make_builtin_scene(name);
        for (const int atlas : atlases) {
            const FrameStats stats = bake(renderer, scene, {{"atlas_resolution", atlas}, {"face_size", face}, {"traversal", 2}});
            md += fmt::format("| {} ({} triangles) | {}x{} | {:.0f} | {} | {} | {:.1f} : 1 | {:.1f} s |\n", name,
                              scene.triangle_count(), atlas, atlas, stat(stats, "cube_maps"), mib(stat(stats, "uncompressed_bytes")),
                              mib(stat(stats, "compressed_bytes")), stat(stats, "compression_ratio"), stat(stats, "bake_seconds"));
            csv << fmt::format("{},{},{},{},{},{},{:.3f},{:.2f}\n", name, atlas, face, stat(stats, "cube_maps"),
                               stat(stats, "uncompressed_bytes"), stat(stats, "compressed_bytes"),
                               stat(stats, "compression_ratio"), stat(stats, "bake_seconds"));
            log::info("bench", "table 3: {} atlas {}: {:.1f}:1 in {:.1f} s", name, atlas, stat(stats, "compression_ratio"),
                      stat(stats, "bake_seconds"));
        }
    }
    md += "| paper: Cornell Box, 34 faces, 6x64^2, GeForce 8800 | 64^2 / 128^2 / 256^2 | 2592 / 10701 / 42226 | 127.4 MB / "
          "525.9 MB / 2.0 GB | 8.0 / 21.5 / 62.1 MB | 15.9 / 24.4 / 33.4 : 1 | 43 s / 3 min / 13 min |\n";
    return md;
}

// Fig. 14 as a number: this needs the CPU twin of the GPU query, so it reads cssm's internals.
std::string visibility_table(const Options& options, std::ofstream& csv) {
    using namespace methods::cssm;
    const scene::Scene scene = scene::make_cornell_box();
    std::vector<std::uint32_t> objects(scene.objects.size());
    std::iota(objects.begin(), objects.end(), 0u);
    AtlasSettings settings;
    const float atlas_resolution = options.quick ? 12.0f : 32.0f;
    settings.texel_size = texel_size_for(surface_area(scene, objects), atlas_resolution);
    const SurfaceAtlas atlas = build_surface_atlas(scene, objects, settings);
    const raytrace::RayScene rays(scene);
    const float far = 1.01f * glm::length(scene.world_bounds().extent());
    const int pairs = options.quick ? 2000 : 40000;
    std::string md = "| cube face | disagree (PCF 1) | of which falsely occluded | disagree (PCF 3, < 50% lit) | "
                     "bytes compressed |\n|---|---|---|---|---|\n";
    csv << "face,pairs,occluded_truth,disagree_pcf1,false_occluded_pcf1,disagree_pcf3\n";
    double occluded_fraction = 0.0;
    for (const int face : options.quick ? std::vector<int>{8, 16} : std::vector<int>{8, 16, 32, 64}) {
        const CubeMapSettings cube{face, 0.25f * settings.texel_size, far};
        const SurfaceShadowMaps maps = bake_surface_shadow_maps(scene, atlas, traverse_atlas(scene, atlas, Traversal::spiral), cube, rays);
        std::mt19937 random(11);
        std::uniform_int_distribution<std::uint32_t> pick(0, static_cast<std::uint32_t>(atlas.texels.size() - 1));
        int done = 0, occluded = 0, disagree1 = 0, false_occluded = 0, disagree3 = 0;
        while (done < pairs) {
            const std::uint32_t sender = pick(random), receiver = pick(random);
            const glm::vec3 from = maps.origins[sender], to = maps.origins[receiver];
            const glm::vec3 d = to - from;
            const float distance = glm::length(d);
            if (distance < 2.0f * settings.texel_size) continue;
            if (glm::dot(atlas.texels[sender].normal, d) <= 0.0f || glm::dot(atlas.texels[receiver].normal, -d) <= 0.0f) continue;
            ++done;
            const bool truth = rays.occluded(from, d / distance, 1e-4f * distance, distance * (1.0f - 1e-4f));
            occluded += truth ? 1 : 0;
            const bool one = cssm_visibility(maps, sender, to, 1) < 0.5f;
            const bool three = cssm_visibility(maps, sender, to, 3) < 0.5f;
            disagree1 += one != truth ? 1 : 0;
            false_occluded += one && !truth ? 1 : 0;
            disagree3 += three != truth ? 1 : 0;
        }
        md += fmt::format("| 6x{0}^2 | {1:.2f}% | {2:.2f}% | {3:.2f}% | {4} |\n", face, 100.0 * disagree1 / done,
                          100.0 * false_occluded / done, 100.0 * disagree3 / done, mib(static_cast<double>(maps.depth.compressed_bytes())));
        csv << fmt::format("{},{},{},{},{},{}\n", face, done, occluded, disagree1, false_occluded, disagree3);
        occluded_fraction = static_cast<double>(occluded) / done;
        log::info("bench", "fig 14: face {}: {:.2f}% disagree", face, 100.0 * disagree1 / done);
    }
    md += fmt::format("\n{} texels ({}x{} atlas); pairs of texels more than two texels apart that face each other; "
                      "{:.0f}% of them are occluded.\n",
                      atlas.texels.size(), atlas_resolution, atlas_resolution, 100.0 * occluded_fraction);
    return md;
}

template <typename Run>
double median_ms(int repeats, Run&& run) {
    std::vector<double> times;
    for (int i = 0; i < repeats; ++i) {
        const auto start = std::chrono::steady_clock::now();
        run();
        times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    }
    std::sort(times.begin(), times.end());
    return times[times.size() / 2];
}

// Frame times (Table 1) and error per preset and bounce count against the reference.
std::string frame_tables(Renderer& renderer, const Options& options, std::ofstream& time_csv, std::ofstream& error_csv) {
    const scene::Scene scene = scene::make_cornell_box();
    const methods::reference::PathTracer tracer(scene);
    std::string md;
    // Table 1: a warm frame (bake done, atlas solved) re-solves nothing; a changed light re-solves the
    // atlas (n - 1 bounces) and gathers again.
    std::string rows;
    double texels = 0.0;
    time_csv << "samples,bounces,warm_ms,relit_ms,nodes_per_pixel,nodes_per_texel\n";
    for (const int per_texel : {0, 1}) {
        for (const int bounces : {1, 2}) {
            scene::Scene lit = scene;
            auto resources = renderer.upload(lit);
            const RenderRequest r = request("medium", {{"bounces", bounces}, {"per_texel", per_texel}}, options.size);
            renderer.render(*resources, r);
            RenderResult last;
            const double warm = median_ms(3, [&] { last = renderer.render(*resources, r); });
            int step = 0;
            const double relit = median_ms(3, [&] {
                lit.lights[0].position.x += 0.001f * static_cast<float>(++step % 2 ? 1 : -1);
                last = renderer.render(*resources, r);
            });
            const char* samples = per_texel ? "texels" : "pixels";
            rows += fmt::format("| {} | {} | {:.0f} ms | {:.0f} ms | {:.0f} | {:.0f} |\n", samples, bounces, warm, relit,
                                stat(last.stats, "nodes_per_pixel_mean"), stat(last.stats, "nodes_per_texel_mean"));
            time_csv << fmt::format("{},{},{:.1f},{:.1f},{:.1f},{:.1f}\n", samples, bounces, warm, relit,
                                    stat(last.stats, "nodes_per_pixel_mean"), stat(last.stats, "nodes_per_texel_mean"));
            texels = stat(last.stats, "atlas_texels");
        }
    }
    md += fmt::format("### Frame times (Table 1's shape), {0}x{0} pixels, preset medium\n\n"
                      "Samples: `pixels` gathers the last bounce per pixel (final gathering); `texels` runs every "
                      "bounce on the atlas ({1:.0f} texels) and pixels read it (view-dependent lightmap, `per_texel` "
                      "1). A camera move re-runs the per-pixel part only; a light move solves the atlas again.\n\n"
                      "| samples | bounces | frame, camera moved | frame, light moved | nodes per pixel | nodes per texel "
                      "|\n|---|---|---|---|---|---|\n",
                      options.size, texels);
    md += rows;
    md += "\nThe paper (GeForce 8800, 640x480 pixels): Cornell Box 5.2 fps (1 bounce), 1.4 fps (2 bounces); as texels "
          "(128x128 view-dependent lightmap) 35.7 and 10.4 fps.\n\n";

    md += fmt::format("### Error against the reference with the same bounces, {0}x{0}\n\n"
                      "| bounces | preset | atlas texels | relMSE | mean / reference | frame ms (cold: bake + solve) | frame ms (warm) |\n"
                      "|---|---|---|---|---|---|---|\n",
                      options.size);
    error_csv << "bounces,preset,texels,rel_mse,mean_ratio,cold_ms,warm_ms,bake_s\n";
    for (const int bounces : {1, 2, 3}) {
        methods::reference::PathTracerSettings settings;
        settings.max_bounces = bounces;
        settings.pixel_jitter = false;
        const image::Frame truth = tracer.render(scene.cameras[0], options.size, options.size, options.reference_spp, settings);
        for (const auto& preset : methods::preset_names()) {
            auto resources = renderer.upload(scene);
            const RenderRequest r = request(preset, {{"bounces", bounces}}, options.size);
            RenderResult result;
            const double cold = median_ms(1, [&] { result = renderer.render(*resources, r); });
            const double warm = median_ms(3, [&] { result = renderer.render(*resources, r); });
            const auto error = image::compare(result.frame, truth);
            md += fmt::format("| {} | {} | {:.0f} | {:.4f} | {:.3f} | {:.0f} | {:.0f} |\n", bounces, preset, stat(result.stats, "atlas_texels"),
                              error.rel_mse, error.mean_test / error.mean_reference, cold, warm);
            error_csv << fmt::format("{},{},{},{:.5f},{:.4f},{:.1f},{:.1f},{:.2f}\n", bounces, preset, stat(result.stats, "atlas_texels"),
                                     error.rel_mse, error.mean_test / error.mean_reference, cold, warm,
                                     stat(result.stats, "bake_seconds"));
            log::info("bench", "n={} {}: relMSE {:.4f} warm {:.0f} ms", bounces, preset, error.rel_mse, warm);
        }
    }
    return md;
}

}  // namespace

int main(int argc, char** argv) {
    Options options;
    std::string command = "build/bench/bounce_bench_cssm";
    for (int i = 1; i < argc; ++i) {
        const std::string flag = argv[i];
        command += " " + flag;
        if (flag == "--quick") {
            options.quick = true;
            options.size = 32;
            options.reference_spp = 64;
        } else if (flag == "--out" && i + 1 < argc) {
            options.out = argv[++i];
            command += std::string(" ") + argv[i];
        } else if (flag == "--markdown" && i + 1 < argc) {
            options.markdown = argv[++i];
            command += std::string(" ") + argv[i];
        } else {
            std::fprintf(stderr, "usage: bounce_bench_cssm [--quick] [--out DIR] [--markdown FILE]\n");
            return 2;
        }
    }
    try {
        Renderer renderer(gpu::DeviceChoice::resolve(std::nullopt));
        fs::create_directories(options.out);
        std::ofstream compression_csv(options.out / "cssm_table2.csv"), bake_csv(options.out / "cssm_table3.csv"),
            visibility_csv(options.out / "cssm_fig14.csv"), time_csv(options.out / "cssm_table1.csv"),
            error_csv(options.out / "cssm_error.csv");
        const auto started = std::chrono::steady_clock::now();
        const std::string compression = compression_table(renderer, options, compression_csv);
        const std::string bakes = bake_table(renderer, options, bake_csv);
        const std::string visibility = visibility_table(options, visibility_csv);
        const std::string frames = frame_tables(renderer, options, time_csv, error_csv);
        const double minutes = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() / 60.0;

        const std::time_t now = std::time(nullptr);
        char date[32];
        std::strftime(date, sizeof(date), "%Y-%m-%d", std::gmtime(&now));
        std::string md = std::string(bench::kCssmBegin) + "\n\n## cssm in detail (bench/cssm)\n\n";
        md += fmt::format("Written by `{}` on {} ({:.1f} min) on {}. Bakes run on the CPU (Embree, {} threads); "
                          "frames on the GPU named. The paper's rows come from its own hardware (GeForce 8800, Core 2 "
                          "Duo): compare shapes, not absolute numbers. CSVs: bench/results/cssm_*.csv.\n\n",
                          command, date, minutes, renderer.gpu_info().summary(), std::thread::hardware_concurrency());
        md += "### Compression per traversal and atlas size (Table 2's shape), Cornell box, 6x32^2 cube maps\n\n" + compression;
        md += "\n### Bakes (Table 3's shape), spiral traversal, 6x" + std::to_string(options.quick ? 16 : 64) +
              "^2 cube maps\n\nBytes: 16-bit depths; compressed = per-pixel run offsets (4 bytes) + runs (4-byte first "
              "map + 2-byte depth).\n\n" + bakes;
        md += "\n### Visibility against exact ray queries (Fig. 14 as a number), Cornell box\n\n" + visibility;
        md += "\n" + frames;
        md += "\n" + std::string(bench::kCssmEnd) + "\n";
        bench::splice_block(options.markdown, bench::kCssmBegin, bench::kCssmEnd, md);
        log::info("bench", "wrote the cssm sections of {} and bench/results/cssm_*.csv", options.markdown.string());
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bench/cssm: %s\n", error.what());
        return 1;
    }
}
