#version 450 core
// A light-view map texel: the surface a light reaches first (passes/light_view_maps.hpp).
#include "common/shared_layout.h"
#include "common/material.glsl"
#include "common/brdf.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv[2];

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;
layout(location = 2) out vec4 out_albedo;

void main() {
    SurfacePoint s = evaluate_surface(v_normal, v_tangent, v_uv, gl_FrontFacing);
    if (cut_out(s.alpha)) discard;
    out_position = vec4(v_position, 1.0);
    out_normal = vec4(s.normal, 0.0);
    // What the surface re-emits diffusely of the light it receives (virtual point lights). The back
    // of a single-sided surface absorbs, as in the reference: it still occludes, but sends nothing
    // (its front faces the other way, and light must not pass through it).
    vec3 albedo = diffuse_albedo(SurfaceMaterial(s.base_color, s.metallic, s.roughness, s.specular, s.f0));
    out_albedo = vec4(u_double_sided || gl_FrontFacing ? albedo : vec3(0.0), 1.0);
}
