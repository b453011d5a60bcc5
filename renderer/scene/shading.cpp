#include "renderer/scene/shading.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace bounce::scene {
namespace {
constexpr float kPi = std::numbers::pi_v<float>;

float saturate(float x) { return std::clamp(x, 0.0f, 1.0f); }

float schlick_weight(float v_dot_h) {
    const float m = saturate(1.0f - v_dot_h);
    const float m2 = m * m;
    return m2 * m2 * m;
}
float dielectric_fresnel(float specular, float cos_angle) {
    return specular * (kDielectricF0 + (1.0f - kDielectricF0) * schlick_weight(cos_angle));
}
}  // namespace

SurfaceMaterial SurfaceMaterial::from(const Material& material) {
    return {glm::vec3(material.base_color), material.metallic, material.roughness, material.specular};
}

float ggx_alpha(float roughness) { return std::max(roughness * roughness, kMinGgxAlpha); }

float ggx_distribution(float n_dot_h, float alpha) {
    const float a2 = alpha * alpha;
    const float d = n_dot_h * n_dot_h * (a2 - 1.0f) + 1.0f;
    return a2 / (kPi * d * d);
}

float smith_visibility(float n_dot_l, float n_dot_v, float alpha) {
    const float a2 = alpha * alpha;
    const float gv = n_dot_l * std::sqrt(n_dot_v * n_dot_v * (1.0f - a2) + a2);
    const float gl = n_dot_v * std::sqrt(n_dot_l * n_dot_l * (1.0f - a2) + a2);
    return 0.5f / std::max(gv + gl, 1e-12f);
}

glm::vec3 evaluate_brdf(const SurfaceMaterial& m, const glm::vec3& n, const glm::vec3& v, const glm::vec3& l) {
    const float n_dot_l = glm::dot(n, l);
    if (n_dot_l <= 0.0f) return glm::vec3(0.0f);
    const float n_dot_v = std::max(glm::dot(n, v), 1e-4f);
    const glm::vec3 half = l + v;
    const float half_length = glm::length(half);
    const glm::vec3 h = half_length > 1e-15f ? half / half_length : n;
    const float n_dot_h = saturate(glm::dot(n, h));
    const float v_dot_h = saturate(glm::dot(v, h));
    const float alpha = ggx_alpha(m.roughness);
    const float specular_lobe = ggx_distribution(n_dot_h, alpha) * smith_visibility(n_dot_l, n_dot_v, alpha);
    const float fw = schlick_weight(v_dot_h);

    // The diffuse part keeps what specular reflection leaves on the way in and on the way out;
    // weighting it by 1 - F(v.h) instead (glTF's mix) creates energy at grazing view.
    const float diffuse_weight = (1.0f - dielectric_fresnel(m.specular, n_dot_l)) *
                                 (1.0f - dielectric_fresnel(m.specular, n_dot_v));
    const glm::vec3 dielectric = diffuse_weight * m.base_color / kPi +
                                 glm::vec3(dielectric_fresnel(m.specular, v_dot_h) * specular_lobe);
    const glm::vec3 metal = (m.base_color + (glm::vec3(1.0f) - m.base_color) * fw) * specular_lobe;
    return glm::mix(dielectric, metal, m.metallic);
}

float spot_attenuation(const Light& light, float cos_angle) {
    const float cos_inner = std::cos(light.inner_cone);
    const float cos_outer = std::cos(light.outer_cone);
    const float scale = 1.0f / std::max(cos_inner - cos_outer, 1e-4f);
    const float t = saturate((cos_angle - cos_outer) * scale);
    return t * t;
}

LightIncidence light_incidence(const Light& light, const glm::vec3& p) {
    LightIncidence result;
    if (light.type == LightType::directional) {
        result.l = -light.direction;
        result.distance = std::numeric_limits<float>::infinity();
        result.irradiance = light.radiant();
        return result;
    }
    const glm::vec3 to_light = light.position - p;
    const float d2 = std::max(glm::dot(to_light, to_light), 1e-12f);
    result.distance = std::sqrt(d2);
    result.l = to_light / result.distance;
    result.irradiance = light.radiant() / d2;
    if (light.type == LightType::spot) {
        result.irradiance *= spot_attenuation(light, glm::dot(-result.l, light.direction));
    }
    return result;
}

}  // namespace bounce::scene
