// Method `reference` in the registry: its knobs and presets, and the settings they make.
#pragma once

#include "renderer/methods/registry.hpp"
#include "renderer/methods/reference/path_tracer.hpp"

namespace bounce::methods::reference {

methods::MethodInfo method_info();

struct ReferenceRequest {
    PathTracerSettings settings;
    int spp = 64;
};
// From knobs resolved by the registry (spp, bounces, seed, ao, ao_lambda, indirect_visibility).
ReferenceRequest request_from_knobs(const methods::KnobValues& knobs);

}  // namespace bounce::methods::reference
