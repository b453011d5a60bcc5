// Emission plus direct light from every punctual light with its shadow map, added into the frame's
// output from the G-buffer. `direct` is exactly this; every GI method adds its indirect light to it.
#pragma once

#include "renderer/passes/gbuffer_pass.hpp"
#include "renderer/passes/shadow_maps.hpp"

namespace bounce::passes {

class DirectLightPass {
public:
    // Clears the output, then adds emission and each light's reflected radiance.
    void render(const PassContext& context, const GBufferPass& gbuffer, const ShadowMaps& shadows) const;

private:
    FullscreenTriangle triangle_;
};

}  // namespace bounce::passes
