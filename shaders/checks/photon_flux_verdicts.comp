#version 450 core
// A self-check the GPU tests run (tests/gpu/shader_checks_test.cpp), not a pass: whether photons of
// a light-view map carry flux, asked as the passes ask it (common/math.glsl's any_positive) and in
// the form a driver miscompiled (max of the components > 0.0, false under about 3e-8 on an H200
// with driver 580.159), the light's uniforms set as the passes set them.
layout(local_size_x = 64) in;
#include "common/shared_layout.h"
#include "common/compute.glsl"
#include "common/light_view.glsl"

layout(std430, binding = 0) readonly buffer Positions { vec4 positions[]; };
layout(std430, binding = 1) writeonly buffer Verdicts { uvec2 verdicts[]; };  // any_positive, the max form

uniform uint u_count;
uniform vec3 u_view_forward;
uniform float u_texel_measure;
uniform int u_light_type;
uniform vec3 u_light_position;
uniform vec3 u_light_direction;
uniform vec3 u_light_radiant;
uniform float u_light_cos_inner;
uniform float u_light_cos_outer;

void main() {
    uint index = thread_index();
    if (index >= u_count) return;
    PunctualLight light = PunctualLight(u_light_type, u_light_position, u_light_direction, u_light_radiant,
                                        u_light_cos_inner, u_light_cos_outer);
    vec3 flux = photon_flux(light, positions[index].xyz, u_view_forward, u_texel_measure);
    verdicts[index] = uvec2(any_positive(flux) ? 1u : 0u, max(flux.r, max(flux.g, flux.b)) > 0.0 ? 1u : 0u);
}
