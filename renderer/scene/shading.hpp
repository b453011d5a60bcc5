// The material model and punctual lights on the CPU: the twin of shaders/common/brdf.glsl and
// shaders/common/lights.glsl, used by the reference path tracer and by tests as the analytic
// answer. docs/methods.md states the model; both implementations must agree.
#pragma once

#include "renderer/scene/scene.hpp"

#include <glm/glm.hpp>

#include <vector>

namespace bounce::scene {

// glTF's default dielectric F0: ((1.5 - 1)/(1.5 + 1))^2 for the default ior.
inline constexpr float kDielectricF0 = 0.04f;

struct SurfaceMaterial {
    glm::vec3 base_color{0.8f};
    float metallic = 0.0f;
    float roughness = 1.0f;
    float specular = 1.0f;                 // F90, and F0's scale (KHR_materials_specular's factor)
    glm::vec3 f0{kDielectricF0};           // the dielectric's F0 colour before that factor

    static SurfaceMaterial from(const Material& material);
};

inline constexpr float kMinGgxAlpha = 1e-3f;

float ggx_alpha(float roughness);
float ggx_distribution(float n_dot_h, float alpha);
float smith_visibility(float n_dot_l, float n_dot_v, float alpha);

// f(l, v): n, v, l unit vectors, v towards the viewer, l towards the light.
glm::vec3 evaluate_brdf(const SurfaceMaterial& material, const glm::vec3& n, const glm::vec3& v,
                        const glm::vec3& l);

// A lookup as the texture's sampler magnifies (nearest or bilinear, wrapped per axis; no
// mipmaps), decoding sRGB textures to linear; white for an empty texture.
glm::vec4 sample_texture(const Texture& texture, const glm::vec2& uv);

// A material at a surface point with its textures applied (base colour and its alpha,
// metallic-roughness, specular, emission) at the point's UV sets.
struct TexturedMaterial {
    SurfaceMaterial surface;
    glm::vec3 emitted{0.0f};
    float coverage = 1.0f;  // Material::coverage of the point's base-colour alpha
};
TexturedMaterial textured_material(const Scene& scene, const Material& material, const glm::vec2& uv0,
                                   const glm::vec2& uv1);

// The diffuse lobe's albedo averaged over incoming and outgoing directions (cosine-weighted): what
// a diffuse-only transport (radiosity) reflects, (1 - E_avg)(1 - metallic) base. Twin of
// diffuse_albedo in brdf.glsl.
glm::vec3 diffuse_albedo(const SurfaceMaterial& material);

// Importance sampling of f(l, v) cos: a mixture of GGX normal-distribution sampling (the specular
// lobe) and cosine-weighted hemisphere sampling (the diffuse lobe).
struct BrdfSample {
    glm::vec3 l{0.0f};
    float pdf = 0.0f;  // solid angle, of the whole mixture
};
// The probability of picking the specular lobe: 0 for a pure Lambertian surface.
float specular_sampling_probability(const SurfaceMaterial& material);
// u1, u2, u3 uniform in [0, 1). pdf 0 means the sample is below the surface: discard it.
BrdfSample sample_brdf(const SurfaceMaterial& material, const glm::vec3& n, const glm::vec3& v, float u1, float u2,
                       float u3);
float brdf_pdf(const SurfaceMaterial& material, const glm::vec3& n, const glm::vec3& v, const glm::vec3& l);
// The specular lobe's directional albedo, split by Fresnel: for view cosine `n_dot_v` and
// perceptual roughness, (A, B) with integral of D V (F0 + (1 - F0) Fw) cos over the hemisphere
// = F0 A + B (Fw: Schlick's weight of v.h). Row-major, `size` x `size`, rows by roughness, columns
// by n.v, both sampled at cell centres; by GGX importance sampling of the half vector.
std::vector<glm::vec2> specular_albedo_table(int size, int samples_per_entry);
// Per roughness row (cell centres as above), the (A, B) split of the lobe's cosine-weighted mean
// albedo over view directions, E_avg = 2 integral of E(mu) mu dmu, by midpoint quadrature over
// `mu_steps` view cosines of `samples_per_entry` samples each.
std::vector<glm::vec2> specular_average_table(int size, int mu_steps, int samples_per_entry);

// The tables the BRDF's energy compensation reads (docs/methods.md, "BRDF"), computed once: the
// GPU gets the same numbers as textures (gpu::BrdfTables) and samples them with the same bilinear
// filter as these lookups.
struct BrdfTables {
    static constexpr int kSize = 32;
    std::vector<glm::vec2> albedo;   // kSize x kSize: rows by roughness, columns by n.v
    std::vector<glm::vec2> average;  // kSize: by roughness
};
const BrdfTables& brdf_tables();
// (A, B) at a view cosine and roughness, and their hemispherical means at a roughness, filtered
// bilinearly (clamped to the edges) as a GL_LINEAR sampler does.
glm::vec2 specular_albedo_ab(float n_dot_v, float roughness);
glm::vec2 specular_average_ab(float roughness);

// An orthonormal basis (t, b, n) for a unit n, continuous except at n = (0, 0, -1).
void orthonormal_basis(const glm::vec3& n, glm::vec3& t, glm::vec3& b);

// glTF's spot falloff for the cosine of the angle from the spot axis.
float spot_attenuation(const Light& light, float cos_angle);

struct LightIncidence {
    glm::vec3 l{0.0f};       // unit direction towards the light
    float distance = 0.0f;   // infinite for directional lights
    glm::vec3 irradiance{0.0f};  // on a surface facing the light, before cos and visibility
};

LightIncidence light_incidence(const Light& light, const glm::vec3& p);

}  // namespace bounce::scene
