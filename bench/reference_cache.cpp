#include "bench/reference_cache.hpp"

#include "bench/common.hpp"
#include "renderer/base/hash.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/codec.hpp"

#include <fstream>
#include <iterator>

namespace bounce::bench {

namespace fs = std::filesystem;

// Changes whenever the reference's results may change; part of the cache key.
constexpr int kReferenceCacheVersion = 1;

namespace {

std::uint64_t scene_hash(const scene::Scene& scene) {
    Hasher hash;
    for (const auto& light : scene.lights) {
        hash.add(light.type).add(light.position).add(light.direction).add(light.color).add(light.intensity);
        hash.add(light.inner_cone).add(light.outer_cone);
    }
    for (const auto& material : scene.materials) {
        hash.add(material.base_color).add(material.metallic).add(material.roughness).add(material.specular);
        hash.add(material.emissive);
    }
    for (const auto& object : scene.objects) hash.add(object.transform);
    for (const auto& camera : scene.cameras) hash.add(camera.position).add(camera.orientation).add(camera.vertical_fov);
    hash.add(kReferenceCacheVersion);
    return hash.value();
}

// The cache's file of the reference image; its per-pixel variance lies beside it.
fs::path cache_path(const BenchScene& bench_scene, const ReferenceSpec& spec, int bounces) {
    const std::string file = bench_scene.file_hash ? fmt::format("-file{:016x}", bench_scene.file_hash) : "";
    const std::string key =
        fmt::format("{}{}-{:016x}-{}px-{}b-{}spp{}{}.exr", bench_scene.name, file, scene_hash(bench_scene.scene),
                    spec.size, bounces, spec.spp, spec.pixel_centre ? "-centre" : "",
                    spec.indirect_visibility ? "" : "-unoccluded");
    return spec.cache / key;
}

fs::path variance_path(const fs::path& image) {
    fs::path path = image;
    return path.replace_extension(".variance.exr");
}

image::Frame read_exr(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const auto decoded = image::decode_image(bytes);
    image::Frame frame;
    frame.width = decoded.width;
    frame.height = decoded.height;
    frame.rgba = decoded.pixels;
    return frame;
}

// Traces the reference and caches it, with the variance of each pixel's mean luminance beside it.
image::Frame trace_reference(const BenchScene& bench_scene, const methods::reference::PathTracer& tracer,
                             const ReferenceSpec& spec, int bounces) {
    const auto start = Clock::now();
    methods::reference::PathTracerSettings settings;
    settings.max_bounces = bounces;
    settings.seed = 20260101;
    settings.pixel_jitter = !spec.pixel_centre;
    settings.indirect_visibility = spec.indirect_visibility;
    methods::reference::check_settings(settings);
    methods::reference::Accumulator accumulator(spec.size, spec.size);
    // In slices, so a long reference shows progress.
    const int slice = std::max(1, spec.spp / 8);
    while (accumulator.samples() < spec.spp) {
        tracer.render(accumulator, bench_scene.scene.cameras[0], std::min(slice, spec.spp - accumulator.samples()),
                      settings);
        log::info("bench", "reference {} bounces={}{}: {}/{} spp, {:.0f} s", bench_scene.name, bounces,
                  spec.indirect_visibility ? "" : " unoccluded", accumulator.samples(), spec.spp,
                  ms_since(start) / 1000.0);
    }
    image::Frame frame = accumulator.frame();
    image::Frame variance = frame;  // the variance in every channel of an image of its own
    const std::vector<float> luminance_variance = accumulator.features().variance;
    for (std::size_t i = 0; i < luminance_variance.size(); ++i) {
        for (int c = 0; c < 3; ++c) variance.rgba[i * 4 + c] = luminance_variance[i];
    }
    const fs::path path = cache_path(bench_scene, spec, bounces);
    fs::create_directories(spec.cache);
    image::write_file_atomic(variance_path(path), image::encode_image(variance, image::ImageFormat::exr));
    image::write_file_atomic(path, image::encode_image(frame, image::ImageFormat::exr));
    return frame;
}

}  // namespace

// The reference image, from the cache when the same scene, camera, size, bounces and code made it.
image::Frame reference_image(const BenchScene& bench_scene, const methods::reference::PathTracer& tracer,
                             const ReferenceSpec& spec, int bounces) {
    const fs::path path = cache_path(bench_scene, spec, bounces);
    if (!fs::exists(path)) return trace_reference(bench_scene, tracer, spec, bounces);
    log::info("bench", "reference {} from the cache", path.filename().string());
    return read_exr(path);
}

// A cache of code before the variance was kept has the image alone: the reference is traced again
// (the same seed and samples: the same image).
std::vector<float> reference_variance(const BenchScene& bench_scene, const methods::reference::PathTracer& tracer,
                                      const ReferenceSpec& spec, int bounces) {
    const fs::path path = variance_path(cache_path(bench_scene, spec, bounces));
    if (!fs::exists(path)) trace_reference(bench_scene, tracer, spec, bounces);
    const image::Frame variance = read_exr(path);
    std::vector<float> values(variance.rgba.size() / 4);
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = variance.rgba[i * 4];
    return values;
}

}  // namespace bounce::bench
