#version 450 core
// Writes the surface attributes every lighting pass reads (layout in common/shared_layout.h).
#include "common/shared_layout.h"
#include "common/math.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv[2];

layout(binding = BOUNCE_UNIT_BASE_COLOR) uniform sampler2D u_base_color_map;
layout(binding = BOUNCE_UNIT_METALLIC_ROUGHNESS) uniform sampler2D u_metallic_roughness_map;
layout(binding = BOUNCE_UNIT_NORMAL) uniform sampler2D u_normal_map;
layout(binding = BOUNCE_UNIT_EMISSIVE) uniform sampler2D u_emissive_map;

uniform vec4 u_base_color;
uniform float u_metallic;
uniform float u_roughness;
uniform float u_specular;
uniform vec3 u_emissive;
uniform float u_normal_scale;
uniform bool u_double_sided;
// UV set per texture, or -1 when the material has none.
uniform int u_base_color_uv;
uniform int u_metallic_roughness_uv;
uniform int u_normal_uv;
uniform int u_emissive_uv;

layout(location = BOUNCE_GBUFFER_POSITION) out vec4 out_position;
layout(location = BOUNCE_GBUFFER_NORMAL) out vec4 out_normal;
layout(location = BOUNCE_GBUFFER_ALBEDO) out vec4 out_albedo;
layout(location = BOUNCE_GBUFFER_EMISSIVE) out vec4 out_emissive;

vec2 uv_for(int set) { return v_uv[clamp(set, 0, 1)]; }

void main() {
    vec3 n = safe_normalize(v_normal, vec3(0.0, 1.0, 0.0));
    if (u_double_sided && !gl_FrontFacing) n = -n;

    vec4 base = u_base_color;
    if (u_base_color_uv >= 0) base *= texture(u_base_color_map, uv_for(u_base_color_uv));
    float metallic = u_metallic;
    float roughness = u_roughness;
    if (u_metallic_roughness_uv >= 0) {
        vec4 mr = texture(u_metallic_roughness_map, uv_for(u_metallic_roughness_uv));
        roughness *= mr.g;
        metallic *= mr.b;
    }
    vec3 emissive = u_emissive;
    if (u_emissive_uv >= 0) emissive *= texture(u_emissive_map, uv_for(u_emissive_uv)).rgb;
    if (u_normal_uv >= 0) {
        vec3 t = v_tangent.xyz - n * dot(n, v_tangent.xyz);
        t = safe_normalize(t, abs(n.x) < 0.9 ? normalize(cross(n, vec3(1, 0, 0))) : normalize(cross(n, vec3(0, 1, 0))));
        vec3 b = cross(n, t) * (v_tangent.w < 0.0 ? -1.0 : 1.0);
        vec3 tangent_normal = texture(u_normal_map, uv_for(u_normal_uv)).xyz * 2.0 - 1.0;
        tangent_normal.xy *= u_normal_scale;
        n = safe_normalize(mat3(t, b, n) * tangent_normal, n);
    }

    out_position = vec4(v_position, 1.0);
    out_normal = vec4(n, saturate(roughness));
    out_albedo = vec4(clamp(base.rgb, 0.0, 1.0), saturate(metallic));
    out_emissive = vec4(finite_or_zero(max(emissive, vec3(0.0))), saturate(u_specular));
}
