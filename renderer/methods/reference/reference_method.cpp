#include "renderer/methods/reference/reference_method.hpp"

#include "renderer/methods/reference/denoiser.hpp"

#include <chrono>

namespace bounce::methods::reference {

methods::MethodInfo method_info() {
    methods::MethodInfo info;
    info.name = "reference";
    info.description = "CPU path tracer (Embree): the ground truth every method is measured against";
    info.device = methods::MethodDevice::cpu;
    info.create_cpu = [] { return std::make_unique<ReferenceMethod>(); };
    info.knobs = {{"spp", 1, 65536, true, "samples per pixel"},
                  {"bounces", 0, 64, true, "indirect bounces (0: direct light only)"},
                  {"seed", 0, 4294967295.0, true, "random seed; the same seed gives the same image"},
                  {"ao", 0, 1, true, "1: ambient occlusion instead of radiance"},
                  {"ao_lambda", 0, 1e6, false, "ambient occlusion falloff 1 / (1 + lambda r), per metre"},
                  {"indirect_visibility", 0, 1, true,
                   "0: the indirect ray gathers direct light from every surface it crosses, unoccluded, as "
                   "instant-radiosity / RSM methods do (needs bounces = 1)"},
                  {"denoise", 0, 1, true,
                   "1: an edge-avoiding a-trous filter guided by the first hits' albedo, normal and depth"},
                  {"pixel_jitter", 0, 1, true,
                   "1: samples spread over each pixel (antialiased); 0: every camera ray through the pixel "
                   "centre, as the raster methods shade"}};
    auto preset = [](double spp) {
        return methods::KnobValues{{"spp", spp}, {"bounces", 4}, {"seed", 1}, {"ao", 0}, {"ao_lambda", 1},
                                   {"indirect_visibility", 1}, {"denoise", 0}, {"pixel_jitter", 1}};
    };
    info.presets = {{"draft", preset(4)}, {"low", preset(16)}, {"medium", preset(64)}, {"high", preset(256)},
                    {"ultra", preset(1024)}};
    return info;
}

ReferenceRequest request_from_knobs(const methods::KnobValues& knobs) {
    ReferenceRequest request;
    request.spp = static_cast<int>(knobs.at("spp"));
    request.settings.max_bounces = static_cast<int>(knobs.at("bounces"));
    request.settings.seed = static_cast<std::uint64_t>(knobs.at("seed"));
    request.settings.ambient_occlusion = knobs.at("ao") != 0.0;
    request.settings.ao_lambda = static_cast<float>(knobs.at("ao_lambda"));
    request.settings.indirect_visibility = knobs.at("indirect_visibility") != 0.0;
    request.denoise = knobs.at("denoise") != 0.0;
    request.settings.pixel_jitter = knobs.at("pixel_jitter") != 0.0;
    check_settings(request.settings);  // InputError: the daemon answers with an error reply
    return request;
}

image::Frame ReferenceMethod::render(const CpuFrameContext& frame) {
    const ReferenceRequest request = request_from_knobs(frame.knobs);
    const PathTracer tracer(frame.scene);
    const bool plain = !request.settings.ambient_occlusion && request.settings.indirect_visibility;
    Accumulator accumulator(frame.width, frame.height,
                            plain ? Accumulator::prefixes_that_fit(frame.width, frame.height, request.settings.max_bounces) : 0);
    tracer.render(accumulator, frame.camera, request.spp, request.settings, frame.cancelled);
    rays_traced_ = tracer.rays_traced();
    spp_ = request.spp;
    noise_per_sample_ = noise_per_sample(accumulator);
    byproducts_.clear();
    for (int bounces = 0; bounces < accumulator.bounce_prefixes(); ++bounces) {
        methods::KnobValues knobs = frame.knobs;
        knobs["bounces"] = bounces;
        knobs["denoise"] = 0;  // the prefixes are never filtered
        byproducts_.push_back({accumulator.prefix_frame(bounces), std::move(knobs),
                               {{"rays_traced", 0.0},
                                {"samples_per_pixel", static_cast<double>(spp_)},
                                {"denoise_ms", 0.0},
                                {"noise_per_sample", accumulator.prefix_noise_per_sample(bounces)}}});
    }
    denoise_ms_ = 0.0;
    if (!request.denoise) return accumulator.frame();
    const auto start = std::chrono::steady_clock::now();
    image::Frame filtered = denoise(accumulator.frame(), accumulator.features());
    denoise_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return filtered;
}

std::map<std::string, double> ReferenceMethod::statistics() const {
    return {{"rays_traced", static_cast<double>(rays_traced_)}, {"samples_per_pixel", static_cast<double>(spp_)},
            {"denoise_ms", denoise_ms_}, {"noise_per_sample", noise_per_sample_}};
}

}  // namespace bounce::methods::reference
