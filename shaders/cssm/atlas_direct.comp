#version 450 core
// Direct light on the atlas: each texel's diffuse exitance from one light with its shadow map
// (added up over the lights), the mean over points of its surface (AtlasTexel::samples), or, first,
// its emission. Where on the texel the lights' light falls goes to its spot sums
// (CSSM_BINDING_TEXEL_SPOTS).
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "common/lights.glsl"
#include "common/shadows.glsl"
#define CSSM_BRDF(l, spread) 1.0
#define CSSM_BRDF_BOUND(l, cone) 1.0
#include "cssm/cssm_tree.glsl"

layout(std430, binding = CSSM_BINDING_TEXEL_OUT) buffer CssmTexelOut { vec4 texel_out[]; };
layout(std430, binding = CSSM_BINDING_TEXEL_SAMPLES) readonly buffer CssmTexelSamples { vec4 texel_samples[]; };
layout(std430, binding = CSSM_BINDING_TEXEL_SPOTS) buffer CssmTexelSpots { vec4 texel_spots[]; };

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
    uint first = t * uint(CSSM_TEXEL_SAMPLES);
    vec3 mean = vec3(0.0);
    for (uint s = 0u; s < uint(CSSM_TEXEL_SAMPLES); ++s) mean += texel_samples[first + s].xyz;
    mean /= float(CSSM_TEXEL_SAMPLES);
    vec3 n = texels[t].normal_map.xyz;
    mat3 frame = tangent_frame(n);
    if (u_emission_only) {
        texel_out[t] = vec4(texels[t].emission.rgb, 0.0);
        vec2 spread = vec2(0.0);
        for (uint s = 0u; s < uint(CSSM_TEXEL_SAMPLES); ++s) {
            vec3 d = texel_samples[first + s].xyz - mean;
            vec2 along = vec2(dot(d, frame[0]), dot(d, frame[1]));
            spread += along * along;
        }
        texel_spots[2u * t] = vec4(0.0);
        texel_spots[2u * t + 1u] = vec4(0.0, 0.0, spread / float(CSSM_TEXEL_SAMPLES));
        return;
    }
    vec3 albedo = texels[t].albedo.rgb;
    PunctualLight light = PunctualLight(u_light_type, u_light_position, u_light_direction, u_light_radiant,
                                        u_light_cos_inner, u_light_cos_outer);
    vec3 irradiance = vec3(0.0);
    vec4 light_sum = vec4(0.0);
    vec2 spread_sum = vec2(0.0);
    for (uint s = 0u; s < uint(CSSM_TEXEL_SAMPLES); ++s) {
        vec3 p = texel_samples[first + s].xyz;
        LightIncidence incidence = light_incidence(light, p);
        float cos_theta = dot(n, incidence.l);
        if (cos_theta <= 0.0) continue;
        vec3 e = incidence.irradiance * cos_theta *
                 shadow_visibility(u_light_type, p, n, u_light_position, incidence.distance);
        irradiance += e;
        // This sample's part of the texel's exitance luminance.
        float w = luminance(finite_or_zero(albedo * INV_PI * e / float(CSSM_TEXEL_SAMPLES)));
        vec3 d = p - mean;
        vec2 along = vec2(dot(d, frame[0]), dot(d, frame[1]));
        light_sum += vec4(w * d, w);
        spread_sum += w * along * along;
    }
    vec3 exitance = albedo * INV_PI * irradiance / float(CSSM_TEXEL_SAMPLES);
    texel_out[t].rgb += finite_or_zero(exitance);
    texel_spots[2u * t] += light_sum;
    texel_spots[2u * t + 1u].xy += spread_sum;
}
