#version 450 core
// One batch of the final gather (§4.4): each pixel walks the cut through this batch's subtrees with
// itself as the receiver, weighting every node by the pixel's full BRDF. Batches add up by blending.
#include "common/shared_layout.h"
#include "common/brdf.glsl"

layout(binding = BOUNCE_UNIT_GBUFFER_POSITION) uniform sampler2D u_gbuffer_position;
layout(binding = BOUNCE_UNIT_GBUFFER_NORMAL) uniform sampler2D u_gbuffer_normal;
layout(binding = BOUNCE_UNIT_GBUFFER_ALBEDO) uniform sampler2D u_gbuffer_albedo;
layout(binding = BOUNCE_UNIT_GBUFFER_EMISSIVE) uniform sampler2D u_gbuffer_emissive;
layout(binding = BOUNCE_UNIT_GBUFFER_SPECULAR) uniform sampler2D u_gbuffer_specular;

uniform vec3 u_camera_position;
uniform float u_indirect_scale;  // the lights' power over what the atlas solution was solved for

SurfaceMaterial g_material;
vec3 g_n, g_v;
// The BRDF averaged over a sender node's disk rather than taken at its centre (virtual spherical
// lights, Hasan et al. 2009): the GGX lobe widened by the disk's angular radius in half-vector
// angle, alpha'^2 = alpha^2 + sin^2(theta) / 4, so that a sharp lobe meeting a node reflects about
// the node's radiance instead of a spike of D's peak times its irradiance.
vec3 brdf_over_node(vec3 l, float spread) {
    SurfaceMaterial widened = g_material;
    float alpha = ggx_alpha(g_material.roughness);
    widened.roughness = sqrt(sqrt(alpha * alpha + 0.25 * spread));
    return evaluate_brdf(widened, g_n, g_v, l);
}
#define CSSM_BRDF(l, spread) brdf_over_node(l, spread)
#define CSSM_BRDF_BOUND(l, cone) brdf_bound(g_material, g_n, g_v, l, cone)
#include "cssm/cssm_tree.glsl"

out vec4 out_radiance;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec4 position = texelFetch(u_gbuffer_position, pixel, 0);
    if (position.w == 0.0) discard;
    vec4 normal_roughness = texelFetch(u_gbuffer_normal, pixel, 0);
    vec4 albedo_metallic = texelFetch(u_gbuffer_albedo, pixel, 0);
    float specular = texelFetch(u_gbuffer_emissive, pixel, 0).w;
    g_material = SurfaceMaterial(albedo_metallic.rgb, albedo_metallic.w, normal_roughness.w, specular,
                                               texelFetch(u_gbuffer_specular, pixel, 0).rgb);
    g_n = normal_roughness.xyz;
    g_v = safe_normalize(u_camera_position - position.xyz, g_n);
    // With moving objects, the texel under the pixel tests its own group's occluders from its side.
    uint under = u_csm_count > 0u ? texel_near(position.xyz, g_n) : CSSM_NONE;
    Gathered g = gather_cut(position.xyz, g_n, under);
    count_gather(g);
    out_radiance = vec4(finite_or_zero(u_indirect_scale * g.irradiance), 0.0);
}
