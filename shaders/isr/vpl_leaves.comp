#version 450 core
// The VPL tree's finest level: one VPL per light-view texel, carrying the flux the light sends
// through the texel times the surface's diffuse albedo (reflected flux), over the surface area the
// texel covers (common/light_view.glsl). Where the light reaches nothing the VPL is empty.
layout(local_size_x = 8, local_size_y = 8) in;
#include "common/light_view.glsl"
#include "isr/vpl_tree.glsl"

layout(binding = 0) uniform sampler2DArray u_view_position;
layout(binding = 1) uniform sampler2DArray u_view_normal;
layout(binding = 2) uniform sampler2DArray u_view_albedo;

uniform int u_view;
uniform vec3 u_view_forward;
uniform vec3 u_view_origin;  // the light's position; for orthographic views, a point behind the scene
uniform int u_light_type;
uniform vec3 u_light_position;
uniform vec3 u_light_direction;
uniform vec3 u_light_radiant;
uniform float u_light_cos_inner;
uniform float u_light_cos_outer;

void main() {
    ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(texel, ivec2(u_rsm_size)))) return;
    ivec3 at = ivec3(texel, u_view);
    vec4 position = texelFetch(u_view_position, at, 0);
    VplNode node;
    node.position_area = vec4(0.0);
    node.normal_radius = vec4(0.0);
    node.flux_far = vec4(0.0, 0.0, 0.0, -1.0);
    node.normal_min_near = vec4(2.0, 2.0, 2.0, 3.0e38);
    node.normal_max_flag = vec4(-2.0, -2.0, -2.0, 0.0);
    node.bound_area = vec4(0.0);
    if (position.w != 0.0) {
        PunctualLight light = PunctualLight(u_light_type, u_light_position, u_light_direction, u_light_radiant,
                                            u_light_cos_inner, u_light_cos_outer);
        vec3 n = safe_normalize(texelFetch(u_view_normal, at, 0).xyz, -u_view_forward);
        vec3 albedo = texelFetch(u_view_albedo, at, 0).rgb;
        vec3 flux = photon_flux(light, position.xyz, u_view_forward, u_texel_measure) * albedo;
        float area = photon_footprint(light, position.xyz, n, u_view_forward, u_texel_measure);
        float distance = u_light_type == BOUNCE_LIGHT_DIRECTIONAL ? dot(position.xyz - u_view_origin, u_view_forward)
                                                                  : length(position.xyz - u_view_origin);
        node.position_area = vec4(position.xyz, area);
        node.normal_radius = vec4(n, 0.0);
        node.flux_far = vec4(finite_or_zero(max(flux, vec3(0.0))), distance);
        node.normal_min_near = vec4(n, distance);
        node.normal_max_flag = vec4(n, 0.0);
        node.bound_area = vec4(patch_bound_area(1.0, distance), 0.0, 0.0, 0.0);
    }
    nodes[node_index(u_view, 0, texel)] = node;
}
