// A material evaluated at a rasterized surface point: factors times textures, the normal map
// applied. Shared by every pass that rasterizes materials (G-buffer, light-view maps, voxelization).
#include "common/shared_layout.h"
#include "common/math.glsl"

layout(binding = BOUNCE_UNIT_BASE_COLOR) uniform sampler2D u_base_color_map;
layout(binding = BOUNCE_UNIT_METALLIC_ROUGHNESS) uniform sampler2D u_metallic_roughness_map;
layout(binding = BOUNCE_UNIT_NORMAL) uniform sampler2D u_normal_map;
layout(binding = BOUNCE_UNIT_EMISSIVE) uniform sampler2D u_emissive_map;
layout(binding = BOUNCE_UNIT_SPECULAR) uniform sampler2D u_specular_map;
layout(binding = BOUNCE_UNIT_SPECULAR_COLOR) uniform sampler2D u_specular_color_map;

uniform vec4 u_base_color;
uniform float u_metallic;
uniform float u_roughness;
uniform float u_specular;
uniform vec3 u_specular_f0;  // the dielectric's F0 colour before the specular factor (ior, specularColorFactor)
uniform vec3 u_specular_color;  // specularColorFactor, for the colour texture
uniform float u_ior_f0;         // ((ior - 1)/(ior + 1))^2
uniform vec3 u_emissive;
uniform float u_normal_scale;
uniform int u_alpha_mode;      // BOUNCE_ALPHA_OPAQUE, _MASK or _BLEND
uniform float u_alpha_cutoff;  // alphaMode MASK: below it the surface is not there
uniform bool u_double_sided;
// UV set per texture, or -1 when the material has none.
uniform int u_base_color_uv;
uniform int u_metallic_roughness_uv;
uniform int u_normal_uv;
uniform int u_emissive_uv;
uniform int u_specular_uv;
uniform int u_specular_color_uv;
// KHR_texture_transform per texture (identity when the file gives none): uv' = (M (uv, 1)).xy.
uniform mat3 u_base_color_uv_transform;
uniform mat3 u_metallic_roughness_uv_transform;
uniform mat3 u_normal_uv_transform;
uniform mat3 u_emissive_uv_transform;
uniform mat3 u_specular_uv_transform;
uniform mat3 u_specular_color_uv_transform;

vec2 texture_uv(vec2 uv[2], int set, mat3 transform) { return (transform * vec3(uv[clamp(set, 0, 1)], 1.0)).xy; }

struct SurfacePoint {
    vec3 normal;  // shading normal, towards the viewer for double-sided surfaces seen from behind
    vec3 base_color;
    float metallic;
    float roughness;
    float specular;
    vec3 f0;
    vec3 emissive;
    float alpha;  // base-colour alpha, factor times texture
};

// glTF alphaMode: whether the surface is absent at this fragment (every rasterizing pass discards
// it). MASK cuts it away below the cutoff. BLEND is coverage: the fragment stays with probability
// alpha, decided by a hash of its window position and depth, so that two layers at one pixel
// decide independently and filtered lookups (shadow-map PCF, voxel mips) see the fraction alpha.
bool cut_out(float alpha) {
    if (u_alpha_mode == BOUNCE_ALPHA_MASK) return alpha < u_alpha_cutoff;
    if (u_alpha_mode != BOUNCE_ALPHA_BLEND) return false;
    uvec2 pixel = uvec2(gl_FragCoord.xy);
    uint h = pcg_hash(pixel.x ^ pcg_hash(pixel.y ^ pcg_hash(floatBitsToUint(gl_FragCoord.z))));
    return alpha <= unit_float(h);
}

// MASK tests the base level's alpha, as the reference does (it has no mipmaps). A mip averages a
// cut-out's alpha, which falls below the cutoff where most texels under it are above: minified
// foliage would lose its leaves. BLEND keeps the filtered alpha, whose average is its coverage.
float mask_alpha(vec2 uv[2]) {
    float alpha = u_base_color.a;
    if (u_base_color_uv >= 0) {
        alpha *= textureLod(u_base_color_map, texture_uv(uv, u_base_color_uv, u_base_color_uv_transform), 0.0).a;
    }
    return alpha;
}

// The base-colour alpha alone, for passes that need nothing else (shadow maps).
float material_alpha(vec2 uv[2]) {
    if (u_alpha_mode == BOUNCE_ALPHA_MASK) return mask_alpha(uv);
    float alpha = u_base_color.a;
    if (u_base_color_uv >= 0) alpha *= texture(u_base_color_map, texture_uv(uv, u_base_color_uv, u_base_color_uv_transform)).a;
    return alpha;
}

SurfacePoint evaluate_surface(vec3 interpolated_normal, vec4 tangent, vec2 uv[2], bool front_facing) {
    SurfacePoint s;
    vec3 n = safe_normalize(interpolated_normal, vec3(0.0, 1.0, 0.0));
    if (u_double_sided && !front_facing) n = -n;

    vec4 base = u_base_color;
    if (u_base_color_uv >= 0) base *= texture(u_base_color_map, texture_uv(uv, u_base_color_uv, u_base_color_uv_transform));
    s.metallic = u_metallic;
    s.roughness = u_roughness;
    if (u_metallic_roughness_uv >= 0) {
        vec4 mr = texture(u_metallic_roughness_map,
                          texture_uv(uv, u_metallic_roughness_uv, u_metallic_roughness_uv_transform));
        s.roughness *= mr.g;
        s.metallic *= mr.b;
    }
    vec3 emissive = u_emissive;
    if (u_emissive_uv >= 0) emissive *= texture(u_emissive_map, texture_uv(uv, u_emissive_uv, u_emissive_uv_transform)).rgb;
    if (u_normal_uv >= 0) {
        vec3 t = tangent.xyz - n * dot(n, tangent.xyz);
        t = safe_normalize(t, abs(n.x) < 0.9 ? normalize(cross(n, vec3(1, 0, 0))) : normalize(cross(n, vec3(0, 1, 0))));
        vec3 b = cross(n, t) * (tangent.w < 0.0 ? -1.0 : 1.0);
        vec3 tangent_normal = texture(u_normal_map, texture_uv(uv, u_normal_uv, u_normal_uv_transform)).xyz * 2.0 - 1.0;
        tangent_normal.xy *= u_normal_scale;
        n = safe_normalize(mat3(t, b, n) * tangent_normal, n);
    }
    s.normal = n;
    s.base_color = clamp(base.rgb, 0.0, 1.0);
    s.alpha = u_alpha_mode == BOUNCE_ALPHA_MASK ? mask_alpha(uv) : base.a;
    s.metallic = saturate(s.metallic);
    s.roughness = saturate(s.roughness);
    s.specular = u_specular;
    if (u_specular_uv >= 0) s.specular *= texture(u_specular_map, texture_uv(uv, u_specular_uv, u_specular_uv_transform)).a;
    s.specular = saturate(s.specular);
    s.f0 = u_specular_f0;
    if (u_specular_color_uv >= 0) {
        vec3 colour = u_specular_color * texture(u_specular_color_map,
                                                 texture_uv(uv, u_specular_color_uv, u_specular_color_uv_transform)).rgb;
        s.f0 = min(u_ior_f0 * colour, vec3(1.0));
    }
    s.f0 = clamp(s.f0, 0.0, 1.0);
    s.emissive = finite_or_zero(max(emissive, vec3(0.0)));
    return s;
}
