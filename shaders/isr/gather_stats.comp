#version 450 core
// Counts, over every texel that gathered, the VPLs it gathered (alpha - 1 after the batches): their
// sum and the largest, and how many texels gathered at all, for the frame's statistics.
layout(local_size_x = 8, local_size_y = 8) in;
#include "isr/multires.glsl"

layout(binding = ISR_IMAGE_IRRADIANCE, rgba32f) readonly uniform image2D u_irradiance;
layout(std430, binding = ISR_BINDING_COUNTERS) buffer Counters { uint counters[]; };

uniform int u_level;

void main() {
    ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(texel, u_level_size[u_level]))) return;
    float alpha = imageLoad(u_irradiance, atlas_texel(u_level, texel)).w;
    if (alpha < 1.0) return;
    uint gathered = uint(alpha - 1.0 + 0.5);
    uint previous = atomicAdd(counters[ISR_COUNTER_VPLS_LOW], gathered);
    if (previous + gathered < previous) atomicAdd(counters[ISR_COUNTER_VPLS_HIGH], 1u);
    atomicMax(counters[ISR_COUNTER_VPLS_MAX], gathered);
    atomicAdd(counters[ISR_COUNTER_GATHERED], 1u);
}
