// The memory check a GPU frame passes before anything is allocated: the method's estimate for the
// request's knobs, lights and size, with what other scenes and methods already hold, must fit the
// renderer's budget. A refusal names the largest structure and a value of what sizes it that fits.
#pragma once

#include "renderer/methods/registry.hpp"

#include <cstdint>
#include <string>

namespace bounce {

struct MemoryCheck {
    const methods::MethodInfo& method;
    const scene::Scene& scene;
    const methods::KnobValues& knobs;
    int width = 0;
    int height = 0;
    std::uint64_t held_elsewhere = 0;  // resident bytes the frame does not replace
    std::uint64_t budget = 0;          // 0: none
    std::string budget_source;         // "--gpu-memory-budget", or where the default came from
};

// The method's estimate with the frame's output target (RGBA32F and its RGBA8 display image).
methods::MemoryEstimate frame_estimate(const methods::MethodInfo& method, const methods::EstimateInput& input);

// Throws ResourceExhausted when the frame would pass the budget.
void check_memory_budget(const MemoryCheck& check);

}  // namespace bounce
