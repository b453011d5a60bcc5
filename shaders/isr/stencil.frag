#version 450 core
// One-pass stencil refinement (paper §3.2.1): over the whole flattened atlas, a fragment survives
// (and the stencil marks it) where its cell needs no subdivision but the next coarser cell does,
// or it is a full-resolution pixel, or a continuous cell of the coarsest level.
#include "isr/multires.glsl"

layout(binding = ISR_IMAGE_DEPTH, rgba32f) readonly uniform image2D u_depth;
layout(binding = ISR_IMAGE_NORMAL_MIN, rgba16f) readonly uniform image2D u_normal_min;
layout(binding = ISR_IMAGE_NORMAL_MAX, rgba16f) readonly uniform image2D u_normal_max;
layout(std430, binding = ISR_BINDING_COUNTERS) buffer Counters { uint counters[]; };

out vec4 out_irradiance;

bool discontinuous(int level, ivec2 texel) {
    ivec2 at = atlas_texel(level, texel);
    return patch_discontinuous(imageLoad(u_depth, at), imageLoad(u_normal_min, at).xyz,
                               imageLoad(u_normal_max, at).xyz);
}

void main() {
    ivec2 texel;
    int level = atlas_level(ivec2(gl_FragCoord.xy), texel);
    if (level < 0) discard;
    if (patch_empty(imageLoad(u_depth, atlas_texel(level, texel)))) discard;
    if (level > 0 && discontinuous(level, texel)) discard;                       // needs subdivision
    if (level + 1 < u_levels && !discontinuous(level + 1, texel / 2)) discard;  // the parent suffices
    atomicAdd(counters[ISR_COUNTER_LEVEL_FRAGMENTS + level], 1u);
    out_irradiance = vec4(0.0);
}
