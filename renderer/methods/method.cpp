#include "renderer/methods/method.hpp"

#include "renderer/base/error.hpp"
#include "renderer/gpu/gl.hpp"
#include "renderer/passes/gbuffer_pass.hpp"
#include "renderer/passes/shadow_maps.hpp"

namespace bounce::methods {

namespace {
double resolved_knob(const KnobValues& knobs, std::string_view name) {
    const auto it = knobs.find(std::string(name));
    BOUNCE_CHECK(it != knobs.end(), "knob '{}' was not resolved for this frame", name);
    return it->second;
}
}  // namespace

double FrameContext::knob(std::string_view name) const { return resolved_knob(knobs, name); }

void FrameContext::interruption_point() const {
    if (!cancelled) return;
    glFinish();
    if (cancelled->load()) throw Cancelled("frame cancelled while the GPU worked on it");
}

double EstimateInput::knob(std::string_view name) const { return resolved_knob(knobs, name); }

MemoryEstimate direct_light_estimate(const EstimateInput& input) {
    return {{"gbuffer", passes::GBufferPass::bytes_for(input.width, input.height), "frame size"},
            {"shadow_maps", passes::ShadowMaps::bytes_for(input.scene, input.knob_int("shadow_map_size"),
                                                                        input.knob_int("shadow_cascades")),
             "shadow_map_size"}};
}

}  // namespace bounce::methods
