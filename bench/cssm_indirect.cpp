// bench/cssm_indirect: where cssm's one-bounce indirect light departs from the reference's, on a
// scene of the bench corpus or a Cornell variant of bench/quality. The indirect part alone (cssm
// less `direct high`, against the pixel-centre reference at 1 bounce less at 0), since whole frames
// hide it behind the shared direct light. Prints, per preset:
// - the indirect light over the reference's, on the pixels whose direct light (the reference's at 0
//   bounces) has a luminance over 0.5 ("sunlit") and on the rest;
// - with --region, the same over a rectangle of pixels that `direct` leaves dark;
// - the whole frame's relMSE against the 1-bounce reference, and the share of it its worst pixels
//   carry, with what those pixels read.
// --knob NAME=VALUE sets a cssm knob over each preset's; --lights sun|lamps keeps the directional
// lights or the others; --matte sets every specular and metallic factor to 0. --method vct|isr
// measures that method's indirect light instead; --method direct, its frame against the reference
// at 0 bounces (where the direct light departs, which every method shares). --only OBJECT keeps the
// objects whose name holds OBJECT (a building of the street alone: what it lights of itself).
#include "bench/common.hpp"
#include "bench/corpus.hpp"
#include "bench/scenes.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/renderer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

namespace {

using namespace bounce;

constexpr const char* kUsage =
    "usage: bounce_bench_cssm_indirect --scene NAME [--preset P ...] [--size N] [--spp N] [--lights all|sun|lamps]\n"
    "                                  [--matte] [--region X0,Y0,X1,Y1] [--worst N]\n"
    "                                  [--knob NAME=VALUE ...] [--method cssm|vct|isr|direct] [--only OBJECT]";

struct Options {
    std::string scene;
    std::string method = "cssm";
    std::string only;  // keep the objects whose name holds this
    std::vector<std::string> presets;
    int size = 48;
    int spp = 512;
    std::string lights = "all";
    bool matte = false;
    std::vector<double> region;  // x0, y0, x1, y1 (exclusive), rows top to bottom
    int worst = 10;
    methods::KnobValues knobs;  // over each preset's
};

double luminance(const image::Frame& frame, std::size_t pixel) {
    const float* p = &frame.rgba[pixel * 4];
    return (p[0] + p[1] + p[2]) / 3.0;
}

image::Frame reference(const methods::reference::PathTracer& tracer, const scene::Scene& scene, const Options& options,
                       int bounces) {
    methods::reference::PathTracerSettings settings;
    settings.max_bounces = bounces;
    settings.pixel_jitter = false;
    return tracer.render(scene.cameras[0], options.size, options.size, options.spp, settings);
}

void report(const std::string& preset, const Options& options, const image::Frame& truth, const image::Frame& truth_direct,
            const image::Frame& direct, const image::Frame& cssm) {
    const std::size_t pixels = static_cast<std::size_t>(options.size) * options.size;
    double sunlit = 0.0, sunlit_truth = 0.0, rest = 0.0, rest_truth = 0.0, region = 0.0, region_truth = 0.0;
    int region_pixels = 0;
    std::vector<double> error(pixels, 0.0);
    for (std::size_t i = 0; i < pixels; ++i) {
        const double indirect = luminance(cssm, i) - luminance(direct, i);
        const double expected = luminance(truth, i) - luminance(truth_direct, i);
        (luminance(truth_direct, i) > 0.5 ? sunlit : rest) += indirect;
        (luminance(truth_direct, i) > 0.5 ? sunlit_truth : rest_truth) += expected;
        const int x = static_cast<int>(i % options.size), y = static_cast<int>(i / options.size);
        if (options.region.size() == 4 && x >= options.region[0] && y >= options.region[1] && x < options.region[2] &&
            y < options.region[3] && luminance(direct, i) <= 0.01) {
            region += indirect;
            region_truth += expected;
            ++region_pixels;
        }
        for (int c = 0; c < 3; ++c) {
            const double t = cssm.rgba[i * 4 + c], r = truth.rgba[i * 4 + c];
            error[i] += (t - r) * (t - r) / (r * r + 0.01) / 3.0;  // image::compare's relMSE, per pixel
        }
    }
    if (options.method != "direct") {
        std::printf("%s: indirect over the reference's: sunlit %.3f (%.2f of %.2f), other pixels %.3f (%.2f of %.2f)\n",
                    preset.c_str(), sunlit / sunlit_truth, sunlit, sunlit_truth, rest / rest_truth, rest, rest_truth);
    }
    if (options.region.size() == 4 && options.method != "direct") {
        std::printf("%s: region, %d pixels `direct` leaves dark: %.3f of %.3f, %.2f times\n", preset.c_str(), region_pixels,
                    region, region_truth, region / region_truth);
    }
    const double total = std::accumulate(error.begin(), error.end(), 0.0);
    std::vector<std::size_t> order(pixels);
    std::iota(order.begin(), order.end(), 0);
    const std::size_t worst = std::min<std::size_t>(static_cast<std::size_t>(std::max(options.worst, 0)), pixels);
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(worst), order.end(),
                      [&](std::size_t a, std::size_t b) { return error[a] > error[b]; });
    double share = 0.0;
    for (std::size_t k = 0; k < worst; ++k) share += error[order[k]];
    std::printf("%s: relMSE against %d bounce%s %.5f (image::compare %.5f); the worst %zu pixels carry %.0f%%\n",
                preset.c_str(), options.method == "direct" ? 0 : 1, options.method == "direct" ? "s" : "",
                total / static_cast<double>(pixels), image::compare(cssm, truth).rel_mse, worst, 100.0 * share / total);
    for (std::size_t k = 0; k < worst; ++k) {
        const std::size_t i = order[k];
        std::printf("  pixel (%zu, %zu): %.2f; %s %.3f, direct %.3f, reference %.3f, its direct %.3f\n",
                    i % options.size, i / options.size, error[i], options.method.c_str(), luminance(cssm, i),
                    luminance(direct, i), luminance(truth, i), luminance(truth_direct, i));
    }
}

}  // namespace

int main(int argc, char** argv) {
    bench::Arguments arguments(argc, argv, "bounce_bench_cssm_indirect", "build/bench/bounce_bench_cssm_indirect");
    Options options;
    while (arguments.next()) {
        const std::string& flag = arguments.flag();
        if (flag == "--scene") options.scene = arguments.value();
        else if (flag == "--preset") options.presets.push_back(arguments.value());
        else if (flag == "--size") options.size = arguments.number();
        else if (flag == "--spp") options.spp = arguments.number();
        else if (flag == "--lights") options.lights = arguments.value();
        else if (flag == "--matte") options.matte = true;
        else if (flag == "--region") options.region = bench::numbers(arguments.value());
        else if (flag == "--worst") options.worst = arguments.number();
        else if (flag == "--knob") arguments.knob(options.knobs);
        else if (flag == "--method") options.method = arguments.value();
        else if (flag == "--only") options.only = arguments.value();
        else {
            std::fprintf(stderr, "%s\n", kUsage);
            return 2;
        }
    }
    if (options.presets.empty()) options.presets = {"draft", "high"};
    if (options.size < 1 || options.spp < 1 || (!options.region.empty() && options.region.size() != 4) ||
        (options.lights != "all" && options.lights != "sun" && options.lights != "lamps") ||
        (options.method != "cssm" && options.method != "vct" && options.method != "isr" &&
         options.method != "direct")) {
        std::fprintf(stderr, "%s\n", kUsage);
        return 2;
    }
    try {
        scene::Scene scene;
        for (std::vector<bench::BenchScene> scenes : {bench::corpus_scenes(), bench::quality_scenes()}) {
            for (bench::BenchScene& candidate : scenes) {
                if (candidate.name == options.scene) scene = std::move(candidate.scene);
            }
        }
        if (scene.objects.empty()) {
            std::fprintf(stderr, "bounce_bench_cssm_indirect: no corpus or Cornell scene '%s'\n",
                         options.scene.c_str());
            return 2;
        }
        if (!options.only.empty()) {
            std::erase_if(scene.objects, [&](const scene::Object& object) {
                return object.name.find(options.only) == std::string::npos;
            });
            if (scene.objects.empty()) {
                std::fprintf(stderr, "bounce_bench_cssm_indirect: no object of '%s' is named '%s'\n",
                             options.scene.c_str(), options.only.c_str());
                return 2;
            }
        }
        if (options.lights != "all") {
            const bool sun = options.lights == "sun";
            std::erase_if(scene.lights, [&](const scene::Light& light) {
                return (light.type == scene::LightType::directional) != sun;
            });
        }
        if (options.matte) {
            for (scene::Material& material : scene.materials) {
                material.specular = 0.0f;
                material.metallic = 0.0f;
            }
        }
        const methods::reference::PathTracer tracer(scene);
        const image::Frame truth = reference(tracer, scene, options, 1), truth_direct = reference(tracer, scene, options, 0);
        Renderer renderer(gpu::DeviceChoice::resolve(std::nullopt));
        auto resources = renderer.upload(scene);
        const image::Frame direct = renderer.render(*resources, bench::linear_request("direct", "high", {}, options.size)).frame;
        for (const std::string& preset : options.presets) {
            const RenderRequest request = bench::linear_request(options.method, preset, options.knobs, options.size);
            const image::Frame frame = renderer.render(*resources, request).frame;
            report(preset, options, options.method == "direct" ? truth_direct : truth, truth_direct, direct, frame);
        }
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bounce_bench_cssm_indirect: %s\n", error.what());
        return 1;
    }
}
