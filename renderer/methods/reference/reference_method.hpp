// Method `reference`: the CPU path tracer (path_tracer.hpp) behind the CPU method interface, with
// its knobs and presets in the registry.
#pragma once

#include "renderer/methods/cpu_method.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/methods/registry.hpp"

namespace bounce::methods::reference {

methods::MethodInfo method_info();

struct ReferenceRequest {
    PathTracerSettings settings;
    int spp = 64;
    bool denoise = false;  // filter the frame with denoiser.hpp, guided by the first hits
};
// From knobs resolved by the registry (spp, bounces, seed, ao, ao_lambda, indirect_visibility,
// denoise).
ReferenceRequest request_from_knobs(const methods::KnobValues& knobs);

class ReferenceMethod final : public CpuMethod {
public:
    std::string_view name() const override { return "reference"; }
    // Builds the ray scene for the frame's snapshot and traces request_from_knobs(frame.knobs).
    image::Frame render(const CpuFrameContext& frame) override;
    std::map<std::string, double> statistics() const override;
    // The frame's bounce prefixes (Accumulator): the frames of each fewer bounce count, those that
    // fit Accumulator::kMaxPrefixValues, for the planner's comparisons. None for ambient occlusion
    // or without indirect visibility.
    std::vector<ByproductFrame> take_byproducts() override { return std::move(byproducts_); }

private:
    std::uint64_t rays_traced_ = 0;
    int spp_ = 0;
    double denoise_ms_ = 0.0;
    double noise_per_sample_ = 0.0;  // of the last frame, before any denoising (path_tracer.hpp)
    std::vector<ByproductFrame> byproducts_;
};

}  // namespace bounce::methods::reference
