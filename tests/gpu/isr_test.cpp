// Method `isr` against the path-traced reference with the one bounce it models: with indirect
// visibility (the truth) and without it (what the paper's method approximates), per preset, per
// mode and at the thresholds' limits; its VPL tree kept while only the camera moves.
#include "gpu_fixture.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/reference/path_tracer.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

#include <cstdio>

namespace bounce::test {
namespace {

constexpr int kSize = 64;

image::Frame reference_frame(const scene::Scene& scene, bool indirect_visibility, int spp) {
    reference::PathTracer tracer(scene);
    reference::PathTracerSettings settings;
    settings.max_bounces = 1;
    settings.pixel_jitter = false;  // raster methods shade pixel centres
    settings.indirect_visibility = indirect_visibility;
    return tracer.render(scene.cameras[0], kSize, kSize, spp, settings);
}

RenderResult render_isr(const scene::Scene& scene, const std::string& preset, methods::KnobValues knobs = {}) {
    RenderRequest request;
    request.method = "isr";
    request.preset = preset;
    request.knobs = std::move(knobs);
    request.width = request.height = kSize;
    return render_scene(scene, request);
}

TEST(Isr, Explore) {
    const scene::Scene scene = scene::make_cornell_box();
    const image::Frame truth = reference_frame(scene, true, 1024);
    const image::Frame unoccluded = reference_frame(scene, false, 1024);
    const image::ErrorMetrics vis = image::compare(unoccluded, truth);
    std::printf("no-vis reference vs reference: relMSE %.4f mean %.4f vs %.4f\n", vis.rel_mse, vis.mean_test, vis.mean_reference);
    for (const std::string preset : {"draft", "low", "medium", "high", "ultra"}) {
        for (int mode : {0, 1, 2}) {
            const auto result = render_isr(scene, preset, {{"mode", mode}});
            const image::ErrorMetrics a = image::compare(result.frame, truth);
            const image::ErrorMetrics b = image::compare(result.frame, unoccluded);
            double ms = 0; for (const auto& t : result.stats.passes) if (t.pass.rfind("isr", 0) == 0 || t.pass == "light_view_maps") ms += t.gpu_ms;
            std::printf("%.1f ms ", ms);
            std::printf("isr %-6s mode %d relMSE %.4f (no-vis %.4f) mean %.4f vs %.4f / %.4f  vpl/frag %.0f max %.0f frags %.0f\n",
                        preset.c_str(), mode, a.rel_mse, b.rel_mse, a.mean_test, a.mean_reference, b.mean_reference,
                        result.stats.method_statistics.at("vpls_per_fragment_mean"),
                        result.stats.method_statistics.at("vpls_per_fragment_max"),
                        result.stats.method_statistics.at("multires_fragments"));
        }
    }
}

}  // namespace
}  // namespace bounce::test
