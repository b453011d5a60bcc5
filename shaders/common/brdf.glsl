// The one BRDF every method uses (docs/methods.md, "BRDF"; [ggx], [kulla]; C++ twin:
// renderer/scene/shading.cpp).
// glTF metallic-roughness with KHR_materials_specular: Lambertian diffuse and a GGX lobe
// (height-correlated Smith visibility, Schlick Fresnel); the diffuse part is weighted by what the
// specular lobe leaves in each direction (albedo scaling), so energy is conserved and rough
// dielectrics stay Lambertian.
#include "common/shared_layout.h"
#include "common/math.glsl"

layout(binding = BOUNCE_UNIT_BRDF_ALBEDO) uniform sampler2D u_brdf_albedo;    // (A, B) by n.v, roughness
layout(binding = BOUNCE_UNIT_BRDF_AVERAGE) uniform sampler2D u_brdf_average;  // (A, B) means by roughness

struct SurfaceMaterial {
    vec3 base_color;
    float metallic;
    float roughness;  // perceptual; alpha = roughness^2
    float specular;   // KHR_materials_specular's factor: F90, and F0's scale; 0: pure Lambertian
    vec3 f0;          // the dielectric's F0 colour before that factor: min(((ior-1)/(ior+1))^2 colour, 1)
};

const float MIN_GGX_ALPHA = 1e-3;

float ggx_alpha(float roughness) { return max(roughness * roughness, MIN_GGX_ALPHA); }

float ggx_distribution(float n_dot_h, float alpha) {
    float a2 = alpha * alpha;
    float d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

// Smith height-correlated visibility V = G / (4 n.l n.v).
float smith_visibility(float n_dot_l, float n_dot_v, float alpha) {
    float a2 = alpha * alpha;
    float gv = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    float gl = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    return 0.5 / max(gv + gl, 1e-12);
}

float schlick_weight(float v_dot_h) {
    float m = saturate(1.0 - v_dot_h);
    float m2 = m * m;
    return m2 * m2 * m;
}

// Schlick's Fresnel of the dielectric, F0 = specular f0 and F90 = specular (KHR_materials_specular).
vec3 dielectric_fresnel(SurfaceMaterial m, float cos_angle) {
    return m.specular * (m.f0 + (1.0 - m.f0) * schlick_weight(cos_angle));
}

// The dielectric lobe's directional albedo E = F0 A + F90 B per channel, from the (A, B) split.
vec3 dielectric_albedo(SurfaceMaterial m, vec2 ab) { return m.specular * (m.f0 * ab.x + ab.y); }
vec2 specular_albedo_ab(float n_dot_v, float roughness) {
    return texture(u_brdf_albedo, vec2(saturate(n_dot_v), saturate(roughness))).rg;
}
vec2 specular_average_ab(float roughness) { return texture(u_brdf_average, vec2(saturate(roughness), 0.5)).rg; }

// The Lambertian part of evaluate_brdf, weighted by (1 - E(n.l)) (1 - E(n.v)) / (1 - E_avg): what
// the specular lobe leaves in each direction, normalized so that a white base reflects all of it
// (glTF's 1 - F(v.h) weight instead reflects more than it receives at grazing view, and the
// smooth interface's 1 - F(n.l) darkens rough matte surfaces at grazing light).
vec3 diffuse_brdf(SurfaceMaterial m, float n_dot_l, float n_dot_v) {
    vec3 weight = vec3(1.0);
    if (m.specular > 0.0) {
        vec3 e_l = dielectric_albedo(m, specular_albedo_ab(n_dot_l, m.roughness));
        vec3 e_v = dielectric_albedo(m, specular_albedo_ab(n_dot_v, m.roughness));
        vec3 e_avg = dielectric_albedo(m, specular_average_ab(m.roughness));
        weight = (1.0 - e_l) * (1.0 - e_v) / max(1.0 - e_avg, vec3(1e-4));
    }
    return weight * (1.0 - m.metallic) * m.base_color * INV_PI;
}

// The diffuse reflectance toward a viewer at n.v = n_dot_v of light arriving from every direction:
// (1 - E(n.v)) (1 - metallic) base, the diffuse weight with its incoming factor at its mean.
// What a gathered irradiance turns into on its way to the camera (isr, cssm's texel display).
vec3 diffuse_reflectance_toward(SurfaceMaterial m, float n_dot_v) {
    vec3 e_v = m.specular > 0.0 ? dielectric_albedo(m, specular_albedo_ab(n_dot_v, m.roughness)) : vec3(0.0);
    return (1.0 - e_v) * (1.0 - m.metallic) * m.base_color;
}

// The diffuse reflectance seen from nowhere in particular (voxels keep no view direction): the
// diffuse weight's cosine-weighted mean over both directions, 1 - E_avg.
vec3 diffuse_albedo(SurfaceMaterial m) {
    vec3 e_avg = m.specular > 0.0 ? dielectric_albedo(m, specular_average_ab(m.roughness)) : vec3(0.0);
    return (1.0 - e_avg) * (1.0 - m.metallic) * m.base_color;
}

// The specular part of evaluate_brdf integrated over the hemisphere (its directional albedo), from
// the (A, B) split of scene::specular_albedo_table for this n.v and roughness.
vec3 specular_albedo(SurfaceMaterial m, vec2 ab) {
    vec3 dielectric = dielectric_albedo(m, ab);
    vec3 metal = m.base_color * ab.x + ab.y;
    return mix(dielectric, metal, m.metallic);
}

// f(l, v) for unit vectors; zero when either is below the surface.
vec3 evaluate_brdf(SurfaceMaterial m, vec3 n, vec3 v, vec3 l) {
    float n_dot_l = dot(n, l);
    float n_dot_v = dot(n, v);
    if (n_dot_l <= 0.0) return vec3(0.0);
    // Shading normals can face away from the viewer (normal maps); keep the lobe finite.
    n_dot_v = max(n_dot_v, 1e-4);
    vec3 h = safe_normalize(l + v, n);
    float n_dot_h = saturate(dot(n, h));
    float v_dot_h = saturate(dot(v, h));
    float alpha = ggx_alpha(m.roughness);
    float specular_lobe = ggx_distribution(n_dot_h, alpha) * smith_visibility(n_dot_l, n_dot_v, alpha);
    float fw = schlick_weight(v_dot_h);
    vec3 dielectric_specular = dielectric_fresnel(m, v_dot_h) * specular_lobe;
    vec3 metal_specular = (m.base_color + (1.0 - m.base_color) * fw) * specular_lobe;
    return diffuse_brdf(m, n_dot_l, n_dot_v) + mix(dielectric_specular, metal_specular, m.metallic);
}

// An upper bound (approximate for the specular lobe) of evaluate_brdf over light directions within
// `cone` radians of `l_axis`, for refinement oracles: the diffuse part at its largest, plus the
// GGX lobe at the half vector nearest n that such a direction allows (half the angle from the
// mirror direction), with Smith visibility at the cone's most grazing n.l (kept above 0.1) and
// Fresnel at 1 (metal) or at the specular factor (dielectric).
float brdf_bound(SurfaceMaterial m, vec3 n, vec3 v, vec3 l_axis, float cone) {
    // The diffuse weight is at most 1 / (1 - E_avg) (both directional albedos at 0).
    vec3 e_avg = m.specular > 0.0 ? dielectric_albedo(m, specular_average_ab(m.roughness)) : vec3(0.0);
    vec3 diffuse_bound = m.base_color / max(1.0 - e_avg, vec3(1e-4));
    float diffuse = max(diffuse_bound.r, max(diffuse_bound.g, diffuse_bound.b)) * (1.0 - m.metallic) * INV_PI;
    float fresnel = mix(m.specular, 1.0, m.metallic);
    if (fresnel <= 0.0) return diffuse;
    vec3 mirror = reflect(-v, n);
    float off_mirror = max(acos(clamp(dot(l_axis, mirror), -1.0, 1.0)) - cone, 0.0);
    float alpha = ggx_alpha(m.roughness);
    float n_dot_l = max(cos(min(acos(clamp(dot(n, l_axis), -1.0, 1.0)) + cone, 0.5 * PI)), 0.1);
    float n_dot_v = max(dot(n, v), 1e-4);
    return diffuse + fresnel * ggx_distribution(cos(0.5 * off_mirror), alpha) * smith_visibility(n_dot_l, n_dot_v, alpha);
}
