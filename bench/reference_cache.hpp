// The benches' ground truth: the reference image of a bench scene, rendered once and kept in a
// cache folder under a key of the scene, size, bounces, samples and code version.
#pragma once

#include "bench/scenes.hpp"
#include "renderer/image/frame.hpp"
#include "renderer/methods/reference/path_tracer.hpp"

#include <filesystem>
#include <vector>

namespace bounce::bench {

struct ReferenceSpec {
    int size = 128;
    int spp = 1024;
    // Camera rays through pixel centres, as raster methods shade: the error is then the lighting's
    // alone, not also the antialiasing that jittered pixels add.
    bool pixel_centre = false;
    std::filesystem::path cache = "build/bench-cache";
    // false: the one indirect bounce gathers without visibility, as isr does (PathTracerSettings::
    // indirect_visibility); needs bounces 1.
    bool indirect_visibility = true;
};

// From the cache when the same scene, camera, size, bounces and code made it; else rendered (with
// progress in the log) and cached.
image::Frame reference_image(const BenchScene& bench_scene, const methods::reference::PathTracer& tracer,
                             const ReferenceSpec& spec, int bounces);

// The variance of each pixel's mean luminance in that reference (PixelFeatures::variance), cached
// beside it: what its noise weighs (image::rel_mse_difference_noise).
std::vector<float> reference_variance(const BenchScene& bench_scene, const methods::reference::PathTracer& tracer,
                                      const ReferenceSpec& spec, int bounces);

}  // namespace bounce::bench
