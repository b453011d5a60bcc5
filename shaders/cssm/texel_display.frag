#version 450 core
// The per-texel display (the paper's view-dependent lightmap, §5): indirect light is not gathered
// per pixel but read from the atlas, where every bounce already summed its irradiance per texel.
// A pixel blends the texels near it (within two texel edges, on surfaces facing its way), weighted
// by distance, and reflects the result with its own diffuse reflectance toward the camera.
#include "common/shared_layout.h"
#include "common/brdf.glsl"
#define CSSM_BRDF(l, spread) 1.0
#define CSSM_BRDF_BOUND(l, cone) 1.0
#include "cssm/cssm_tree.glsl"

layout(binding = BOUNCE_UNIT_GBUFFER_POSITION) uniform sampler2D u_gbuffer_position;
layout(binding = BOUNCE_UNIT_GBUFFER_NORMAL) uniform sampler2D u_gbuffer_normal;
layout(binding = BOUNCE_UNIT_GBUFFER_ALBEDO) uniform sampler2D u_gbuffer_albedo;
layout(binding = BOUNCE_UNIT_GBUFFER_EMISSIVE) uniform sampler2D u_gbuffer_emissive;
layout(binding = BOUNCE_UNIT_GBUFFER_SPECULAR) uniform sampler2D u_gbuffer_specular;
layout(std430, binding = CSSM_BINDING_TEXEL_INDIRECT) readonly buffer CssmTexelIndirect { vec4 texel_indirect[]; };

uniform vec3 u_camera_position;
uniform float u_indirect_scale;  // the lights' power over what the atlas solution was solved for

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
    vec3 p = position.xyz, n = normal_roughness.xyz;

    float radius = 2.0 * u_texel_size;
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    uint root = neighbourhood(p, 64u);
    uint end = nodes[root].links.y;
    for (uint node = root; node != end; node = nodes[node].links.x != CSSM_NONE ? nodes[node].links.x : nodes[node].links.y) {
        uint texel = nodes[node].links.w;
        if (texel == CSSM_NONE) continue;
        float d = length(texels[texel].position_area.xyz - p);
        float w = max(0.0, 1.0 - d / radius) * step(0.7, dot(texels[texel].normal_map.xyz, n));
        sum += w * texel_indirect[texel].rgb;
        weight += w;
    }
    vec3 irradiance = weight > 0.0 ? sum / weight : vec3(0.0);
    vec3 v = normalize(u_camera_position - p);
    vec3 reflectance = diffuse_reflectance_toward(material, max(dot(n, v), 1e-4));
    out_radiance = vec4(finite_or_zero(u_indirect_scale * reflectance * INV_PI * irradiance), 0.0);
}
