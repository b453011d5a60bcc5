#version 450 core
// Direct light from one punctual light with its shadow map; passes add up with additive blending.
#include "common/shared_layout.h"
#include "common/math.glsl"
#include "common/brdf.glsl"
#include "common/lights.glsl"
#include "common/shadows.glsl"

layout(binding = BOUNCE_UNIT_GBUFFER_POSITION) uniform sampler2D u_gbuffer_position;
layout(binding = BOUNCE_UNIT_GBUFFER_NORMAL) uniform sampler2D u_gbuffer_normal;
layout(binding = BOUNCE_UNIT_GBUFFER_ALBEDO) uniform sampler2D u_gbuffer_albedo;
layout(binding = BOUNCE_UNIT_GBUFFER_EMISSIVE) uniform sampler2D u_gbuffer_emissive;
layout(binding = BOUNCE_UNIT_GBUFFER_SPECULAR) uniform sampler2D u_gbuffer_specular;

uniform vec3 u_camera_position;
uniform int u_light_type;
uniform vec3 u_light_position;
uniform vec3 u_light_direction;
uniform vec3 u_light_radiant;
uniform float u_light_cos_inner;
uniform float u_light_cos_outer;

out vec4 out_radiance;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec4 position = texelFetch(u_gbuffer_position, pixel, 0);
    if (position.w == 0.0) discard;
    vec4 normal_roughness = texelFetch(u_gbuffer_normal, pixel, 0);
    vec4 albedo_metallic = texelFetch(u_gbuffer_albedo, pixel, 0);
    float specular = texelFetch(u_gbuffer_emissive, pixel, 0).w;

    SurfaceMaterial material = SurfaceMaterial(albedo_metallic.rgb, albedo_metallic.w, normal_roughness.w, specular,
                                               texelFetch(u_gbuffer_specular, pixel, 0).rgb);
    PunctualLight light = PunctualLight(u_light_type, u_light_position, u_light_direction, u_light_radiant,
                                        u_light_cos_inner, u_light_cos_outer);
    vec3 p = position.xyz;
    vec3 n = normal_roughness.xyz;
    vec3 v = safe_normalize(u_camera_position - p, n);

    LightIncidence incidence = light_incidence(light, p);
    float cos_theta = dot(n, incidence.l);
    if (cos_theta <= 0.0) discard;
    float visibility = shadow_visibility(u_light_type, p, n, u_light_position, incidence.distance);
    vec3 radiance = evaluate_brdf(material, n, v, incidence.l) * incidence.irradiance * cos_theta * visibility;
    out_radiance = vec4(finite_or_zero(radiance), 0.0);
}
