#version 450 core
// Indirect light at full resolution: the upsampled irradiance times the pixel's own diffuse
// reflectance toward the camera (paper eq. 5's rho_i), added to the direct light.
#include "common/shared_layout.h"
#include "common/brdf.glsl"

layout(binding = BOUNCE_UNIT_GBUFFER_POSITION) uniform sampler2D u_gbuffer_position;
layout(binding = BOUNCE_UNIT_GBUFFER_NORMAL) uniform sampler2D u_gbuffer_normal;
layout(binding = BOUNCE_UNIT_GBUFFER_ALBEDO) uniform sampler2D u_gbuffer_albedo;
layout(binding = BOUNCE_UNIT_GBUFFER_EMISSIVE) uniform sampler2D u_gbuffer_emissive;
layout(binding = BOUNCE_UNIT_GBUFFER_SPECULAR) uniform sampler2D u_gbuffer_specular;
layout(binding = BOUNCE_UNIT_HDR_INPUT) uniform sampler2D u_irradiance;

uniform vec3 u_camera_position;

out vec4 out_radiance;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    if (texelFetch(u_gbuffer_position, pixel, 0).w == 0.0) discard;
    vec4 albedo_metallic = texelFetch(u_gbuffer_albedo, pixel, 0);
    SurfaceMaterial material = SurfaceMaterial(albedo_metallic.rgb, albedo_metallic.w,
                                               texelFetch(u_gbuffer_normal, pixel, 0).w,
                                               texelFetch(u_gbuffer_emissive, pixel, 0).w,
                                               texelFetch(u_gbuffer_specular, pixel, 0).rgb);
    vec3 irradiance = texelFetch(u_irradiance, pixel, 0).rgb;
    vec3 n = texelFetch(u_gbuffer_normal, pixel, 0).xyz;
    vec3 v = normalize(u_camera_position - texelFetch(u_gbuffer_position, pixel, 0).xyz);
    vec3 reflectance = diffuse_reflectance_toward(material, max(dot(n, v), 1e-4));
    out_radiance = vec4(finite_or_zero(reflectance * INV_PI * irradiance), 0.0);
}
