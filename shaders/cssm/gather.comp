#version 450 core
// One batch of a diffuse bounce on the atlas (§4.3): every receiver texel gathers irradiance from
// the cut through this batch's subtrees, accumulated over the batches.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#define CSSM_BRDF(l, spread) 1.0
#define CSSM_BRDF_BOUND(l, cone) g_brdf_max
float g_brdf_max;
#include "cssm/cssm_tree.glsl"

layout(std430, binding = CSSM_BINDING_TEXEL_OUT) buffer CssmTexelOut { vec4 texel_out[]; };

uniform uint u_texel_count;
uniform bool u_first_batch;

void main() {
    uint t = thread_index();
    if (t >= u_texel_count) return;
    vec3 albedo = texels[t].albedo.rgb;
    g_brdf_max = max(albedo.r, max(albedo.g, albedo.b)) * INV_PI;
    Gathered g = gather_cut(texels[t].position_area.xyz, texels[t].normal_map.xyz, t);
    count_gather(g);
    vec3 previous = u_first_batch ? vec3(0.0) : texel_out[t].rgb;
    texel_out[t] = vec4(previous + finite_or_zero(g.irradiance), 0.0);
}
