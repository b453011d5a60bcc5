#version 450 core
// Writes the surface attributes every lighting pass reads (layout in common/shared_layout.h).
#include "common/shared_layout.h"
#include "common/material.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv[2];

layout(location = BOUNCE_GBUFFER_POSITION) out vec4 out_position;
layout(location = BOUNCE_GBUFFER_NORMAL) out vec4 out_normal;
layout(location = BOUNCE_GBUFFER_ALBEDO) out vec4 out_albedo;
layout(location = BOUNCE_GBUFFER_EMISSIVE) out vec4 out_emissive;
layout(location = BOUNCE_GBUFFER_SPECULAR) out vec4 out_specular;

void main() {
    SurfacePoint s = evaluate_surface(v_normal, v_tangent, v_uv, gl_FrontFacing);
    if (cut_out(s.alpha)) discard;
    out_position = vec4(v_position, 1.0);
    out_normal = vec4(s.normal, s.roughness);
    out_albedo = vec4(s.base_color, s.metallic);
    out_emissive = vec4(s.emissive, s.specular);
    out_specular = vec4(s.f0, 0.0);
}
