#version 450 core
// The per-pixel gather (paper §8.1): from every visible surface point a few wide cones
// (vct/cone.glsl) gather the radiance stored in the octree, and with SPECULAR_CONE one more along
// the mirror direction for glossy materials. Output: the diffuse indirect light,
// added to the direct light; or, in ambient occlusion mode (§6), 1/pi * integral of
// (1 - occlusion * f(r)) cos with f(r) = 1/(1 + lambda r).
#include "common/shared_layout.h"
#include "common/math.glsl"
#include "common/brdf.glsl"
#include "vct/cone.glsl"

layout(binding = BOUNCE_UNIT_GBUFFER_POSITION) uniform sampler2D u_gbuffer_position;
layout(binding = BOUNCE_UNIT_GBUFFER_NORMAL) uniform sampler2D u_gbuffer_normal;
layout(binding = BOUNCE_UNIT_GBUFFER_ALBEDO) uniform sampler2D u_gbuffer_albedo;
layout(binding = BOUNCE_UNIT_GBUFFER_EMISSIVE) uniform sampler2D u_gbuffer_emissive;
layout(binding = BOUNCE_UNIT_GBUFFER_SPECULAR) uniform sampler2D u_gbuffer_specular;

uniform vec3 u_camera_position;
uniform bool u_ambient_occlusion;

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
    vec3 p = position.xyz;
    vec3 n = safe_normalize(normal_roughness.xyz, vec3(0.0, 1.0, 0.0));
    vec3 v = safe_normalize(u_camera_position - p, n);
    mat3 frame = cone_frame(n);

    vec3 indirect = vec3(0.0);
    float unoccluded = 0.0;
    for (int i = 0; i < u_cone_count; ++i) {
        vec3 direction = frame * u_cones[i].xyz;
        ConeResult cone = trace_cone(p, n, direction, u_cone_tan);
        float weight = u_cones[i].w;
        indirect += diffuse_brdf(material, u_cones[i].z, max(dot(n, v), 1e-4)) * weight * cone.radiance;
        unoccluded += weight * INV_PI * (1.0 - cone.occlusion);
    }
#ifdef SPECULAR_CONE
    // One cone along the mirror direction (paper §8.1), as wide as the reflected GGX lobe at half its
    // peak: the half vector's density halves at tan^2 = (sqrt 2 - 1) alpha^2, and reflection doubles
    // angles. It gathers what the specular lobe's directional albedo reflects.
    vec3 r = reflect(-v, n);
    if (!u_ambient_occlusion && (material.metallic > 0.0 || material.specular > 0.0) && dot(r, n) > 0.0) {
        float alpha = ggx_alpha(material.roughness);
        float half_angle = clamp(2.0 * atan(sqrt(sqrt(2.0) - 1.0) * alpha), 0.005, 1.05);
        ConeResult cone = trace_cone(p, n, r, tan(half_angle));
        vec2 ab = specular_albedo_ab(dot(n, v), material.roughness);
        indirect += specular_albedo(material, ab) * cone.radiance;
    }
#endif
    if (u_ambient_occlusion) {
        out_radiance = vec4(vec3(saturate(unoccluded)), 1.0);
    } else {
        out_radiance = vec4(finite_or_zero(indirect * u_radiance_unscale), 0.0);
    }
}
