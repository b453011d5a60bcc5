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

}  // namespace

// The reference image, from the cache when the same scene, camera, size, bounces and code made it.
image::Frame reference_image(const BenchScene& bench_scene, const methods::reference::PathTracer& tracer,
                             const ReferenceSpec& spec, int bounces) {
    const std::string file = bench_scene.file_hash ? fmt::format("-file{:016x}", bench_scene.file_hash) : "";
    const std::string key =
        fmt::format("{}{}-{:016x}-{}px-{}b-{}spp{}{}.exr", bench_scene.name, file, scene_hash(bench_scene.scene),
                    spec.size, bounces, spec.spp, spec.pixel_centre ? "-centre" : "",
                    spec.indirect_visibility ? "" : "-unoccluded");
    const fs::path path = spec.cache / key;
    if (fs::exists(path)) {
        std::ifstream in(path, std::ios::binary);
        const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
        const auto decoded = image::decode_image(bytes);
        image::Frame frame;
        frame.width = decoded.width;
        frame.height = decoded.height;
        frame.rgba = decoded.pixels;
        log::info("bench", "reference {} from the cache", key);
        return frame;
    }
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
    fs::create_directories(spec.cache);
    image::write_file_atomic(path, image::encode_image(frame, image::ImageFormat::exr));
    return frame;
}


}  // namespace bounce::bench
