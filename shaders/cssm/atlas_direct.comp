#version 450 core
// Direct light on the atlas: each texel's diffuse exitance from one light with its shadow map
// (added up over the lights), the mean over points of its surface (AtlasTexel::samples), or, first,
// its emission.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "common/lights.glsl"
#include "common/shadows.glsl"
#define CSSM_BRDF(l, spread) 1.0
#define CSSM_BRDF_BOUND(l, cone) 1.0
#include "cssm/cssm_tree.glsl"

layout(std430, binding = CSSM_BINDING_TEXEL_OUT) buffer CssmTexelOut { vec4 texel_out[]; };
layout(std430, binding = CSSM_BINDING_TEXEL_SAMPLES) readonly buffer CssmTexelSamples { vec4 texel_samples[]; };

uniform uint u_texel_count;
uniform bool u_emission_only;
uniform int u_light_type;
uniform vec3 u_light_position;
uniform vec3 u_light_direction;
uniform vec3 u_light_radiant;
uniform float u_light_cos_inner;
uniform float u_light_cos_outer;

void main() {
    uint t = thread_index();
    if (t >= u_texel_count) return;
    if (u_emission_only) {
        texel_out[t] = vec4(texels[t].emission.rgb, 0.0);
        return;
    }
    vec3 n = texels[t].normal_map.xyz;
    PunctualLight light = PunctualLight(u_light_type, u_light_position, u_light_direction, u_light_radiant,
                                        u_light_cos_inner, u_light_cos_outer);
    vec3 irradiance = vec3(0.0);
    for (uint s = 0u; s < uint(CSSM_TEXEL_SAMPLES); ++s) {
        vec3 p = texel_samples[t * uint(CSSM_TEXEL_SAMPLES) + s].xyz;
        LightIncidence incidence = light_incidence(light, p);
        float cos_theta = dot(n, incidence.l);
        if (cos_theta <= 0.0) continue;
        irradiance += incidence.irradiance * cos_theta * shadow_visibility(u_light_type, p, n, u_light_position, incidence.distance);
    }
    vec3 exitance = texels[t].albedo.rgb * INV_PI * irradiance / float(CSSM_TEXEL_SAMPLES);
    texel_out[t].rgb += finite_or_zero(exitance);
}
