#version 450 core
// The end of a bounce: gathered irradiance becomes diffuse exitance (the next bounce's source), and
// is added to the texels' total; the irradiance itself to the sum the per-texel display reads.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#define CSSM_BRDF(l, spread) 1.0
#define CSSM_BRDF_BOUND(l, cone) 1.0
#include "cssm/cssm_tree.glsl"

layout(std430, binding = CSSM_BINDING_TEXEL_IN) buffer CssmTexelIn { vec4 texel_in[]; };     // irradiance in, exitance out
layout(std430, binding = CSSM_BINDING_TEXEL_OUT) buffer CssmTexelOut { vec4 texel_total[]; };
layout(std430, binding = CSSM_BINDING_TEXEL_INDIRECT) buffer CssmTexelIndirect { vec4 texel_indirect[]; };

uniform uint u_texel_count;

void main() {
    uint t = thread_index();
    if (t >= u_texel_count) return;
    texel_indirect[t] = vec4(texel_indirect[t].rgb + texel_in[t].rgb, 0.0);
    vec3 exitance = texels[t].albedo.rgb * INV_PI * texel_in[t].rgb;
    texel_in[t] = vec4(exitance, 0.0);
    texel_total[t] = vec4(texel_total[t].rgb + exitance, 0.0);
}
