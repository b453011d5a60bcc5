#include "renderer/scene/shading.hpp"

#include <algorithm>
#include <cstdint>
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
// Schlick's Fresnel of the dielectric: F0 = specular f0, F90 = specular (KHR_materials_specular).
glm::vec3 dielectric_fresnel(const SurfaceMaterial& m, float cos_angle) {
    return m.specular * (m.f0 + (glm::vec3(1.0f) - m.f0) * schlick_weight(cos_angle));
}

// The dielectric lobe's directional albedo from its (A, B) split, per channel: F0 A + F90 B.
glm::vec3 dielectric_albedo(const SurfaceMaterial& m, const glm::vec2& ab) { return m.specular * (m.f0 * ab.x + ab.y); }

// What the diffuse base may reflect, between the specular directional albedos on the way in and
// out, normalized so that a white base reflects exactly what the specular lobe leaves
// (docs/methods.md, "BRDF": albedo scaling, reciprocal).
glm::vec3 diffuse_weight(const SurfaceMaterial& m, float n_dot_l, float n_dot_v) {
    if (m.specular <= 0.0f) return glm::vec3(1.0f);
    const glm::vec3 e_l = dielectric_albedo(m, specular_albedo_ab(n_dot_l, m.roughness));
    const glm::vec3 e_v = dielectric_albedo(m, specular_albedo_ab(n_dot_v, m.roughness));
    const glm::vec3 e_avg = dielectric_albedo(m, specular_average_ab(m.roughness));
    return (glm::vec3(1.0f) - e_l) * (glm::vec3(1.0f) - e_v) / glm::max(glm::vec3(1.0f) - e_avg, glm::vec3(1e-4f));
}
}  // namespace

SurfaceMaterial SurfaceMaterial::from(const Material& material) {
    return {glm::vec3(material.base_color), material.metallic, material.roughness, material.specular,
            material.dielectric_f0()};
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

    // glTF's mix weights the diffuse part by 1 - F(v.h); albedo scaling weights it by what the
    // specular lobe leaves in each direction instead, which conserves energy and is reciprocal.
    const glm::vec3 dielectric = diffuse_weight(m, n_dot_l, n_dot_v) * m.base_color / kPi +
                                 dielectric_fresnel(m, v_dot_h) * specular_lobe;
    const glm::vec3 metal = (m.base_color + (glm::vec3(1.0f) - m.base_color) * fw) * specular_lobe;
    return glm::mix(dielectric, metal, m.metallic);
}

namespace {
float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }
}  // namespace

namespace {

// A texel coordinate folded into [0, size) by a glTF wrap mode.
int wrap_texel(int i, int size, TextureSampler::Wrap wrap) {
    switch (wrap) {
    case TextureSampler::Wrap::clamp_to_edge: return std::clamp(i, 0, size - 1);
    case TextureSampler::Wrap::mirrored_repeat: {
        const int period = 2 * size;
        const int folded = ((i % period) + period) % period;
        return folded < size ? folded : period - 1 - folded;
    }
    case TextureSampler::Wrap::repeat: break;
    }
    return ((i % size) + size) % size;
}

}  // namespace

glm::vec4 sample_texture(const Texture& texture, const glm::vec2& uv) {
    if (texture.width <= 0 || texture.height <= 0 || texture.rgba8.empty()) return glm::vec4(1.0f);
    auto texel = [&](int ix, int iy) {
        ix = wrap_texel(ix, texture.width, texture.sampler.wrap_s);
        iy = wrap_texel(iy, texture.height, texture.sampler.wrap_t);
        const std::size_t i = (static_cast<std::size_t>(iy) * texture.width + ix) * 4;
        glm::vec4 c(texture.rgba8[i], texture.rgba8[i + 1], texture.rgba8[i + 2], texture.rgba8[i + 3]);
        c /= 255.0f;
        if (texture.srgb) c = glm::vec4(srgb_to_linear(c.r), srgb_to_linear(c.g), srgb_to_linear(c.b), c.a);
        return c;
    };
    const float x = uv.x * static_cast<float>(texture.width), y = uv.y * static_cast<float>(texture.height);
    if (!std::isfinite(x) || !std::isfinite(y)) return texel(0, 0);
    if (texture.sampler.mag_nearest) {
        return texel(static_cast<int>(std::floor(std::clamp(x, -1e9f, 1e9f))),
                     static_cast<int>(std::floor(std::clamp(y, -1e9f, 1e9f))));
    }
    const float fx = std::floor(std::clamp(x - 0.5f, -1e9f, 1e9f)), fy = std::floor(std::clamp(y - 0.5f, -1e9f, 1e9f));
    const float tx = x - 0.5f - fx, ty = y - 0.5f - fy;
    const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
    return glm::mix(glm::mix(texel(ix, iy), texel(ix + 1, iy), tx), glm::mix(texel(ix, iy + 1), texel(ix + 1, iy + 1), tx),
                    ty);
}

TexturedMaterial textured_material(const Scene& scene, const Material& material, const glm::vec2& uv0,
                                   const glm::vec2& uv1) {
    TexturedMaterial result{SurfaceMaterial::from(material), material.emissive};
    auto texture = [&](const TextureRef& ref) -> const Texture* {
        return ref.valid() && ref.texture < static_cast<int>(scene.textures.size()) ? &scene.textures[ref.texture] : nullptr;
    };
    auto uv = [&](const TextureRef& ref) { return ref.transform(ref.uv_set == 1 ? uv1 : uv0); };
    float alpha = material.base_color.a;
    if (const Texture* t = texture(material.base_color_texture)) {
        const glm::vec4 texel = sample_texture(*t, uv(material.base_color_texture));
        result.surface.base_color *= glm::vec3(texel);
        alpha *= texel.a;
    }
    result.coverage = material.coverage(alpha);
    if (const Texture* t = texture(material.metallic_roughness_texture)) {
        const glm::vec4 mr = sample_texture(*t, uv(material.metallic_roughness_texture));
        result.surface.roughness *= mr.g;
        result.surface.metallic *= mr.b;
    }
    // KHR_materials_specular's textures scale the factor (alpha) and the colour (RGB); F0's colour
    // is then min(((ior - 1)/(ior + 1))^2 colour, 1), as Material::dielectric_f0 for the factors.
    if (const Texture* t = texture(material.specular_texture)) {
        result.surface.specular *= sample_texture(*t, uv(material.specular_texture)).a;
    }
    if (const Texture* t = texture(material.specular_color_texture)) {
        const float r = (material.ior - 1.0f) / (material.ior + 1.0f);
        const glm::vec3 colour = material.specular_color * glm::vec3(sample_texture(*t, uv(material.specular_color_texture)));
        result.surface.f0 = glm::min(r * r * colour, glm::vec3(1.0f));
    }
    if (const Texture* t = texture(material.emissive_texture)) {
        result.emitted *= glm::vec3(sample_texture(*t, uv(material.emissive_texture)));
    }
    result.surface.base_color = glm::clamp(result.surface.base_color, 0.0f, 1.0f);
    return result;
}

glm::vec3 diffuse_albedo(const SurfaceMaterial& m) {
    // The diffuse weight's cosine-weighted mean over both directions is (1 - E_avg)^2 / (1 - E_avg).
    const glm::vec3 e_avg =
        m.specular > 0.0f ? dielectric_albedo(m, specular_average_ab(m.roughness)) : glm::vec3(0.0f);
    return (glm::vec3(1.0f) - e_avg) * (1.0f - m.metallic) * m.base_color;
}

void orthonormal_basis(const glm::vec3& n, glm::vec3& t, glm::vec3& b) {
    // Duff et al. 2017, "Building an Orthonormal Basis, Revisited".
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float c = n.x * n.y * a;
    t = glm::vec3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = glm::vec3(c, sign + n.y * n.y * a, -n.y);
}

float specular_sampling_probability(const SurfaceMaterial& m) {
    if (m.metallic <= 0.0f && m.specular <= 0.0f) return 0.0f;
    // Roughly the share of reflected energy in the specular lobe, kept away from 0 and 1 so both
    // lobes are always explored.
    const float dielectric_share = m.specular * std::max({m.f0.r, m.f0.g, m.f0.b}) * 2.0f;
    return std::clamp(dielectric_share + (1.0f - dielectric_share) * m.metallic, 0.1f, 0.9f);
}

float brdf_pdf(const SurfaceMaterial& m, const glm::vec3& n, const glm::vec3& v, const glm::vec3& l) {
    const float n_dot_l = glm::dot(n, l);
    if (n_dot_l <= 0.0f) return 0.0f;
    const float p_specular = specular_sampling_probability(m);
    float pdf = (1.0f - p_specular) * n_dot_l / kPi;
    if (p_specular > 0.0f) {
        const glm::vec3 half = l + v;
        const float length = glm::length(half);
        if (length > 1e-12f) {
            const glm::vec3 h = half / length;
            const float v_dot_h = glm::dot(v, h);
            if (v_dot_h > 0.0f) {
                const float alpha = ggx_alpha(m.roughness);
                pdf += p_specular * ggx_distribution(saturate(glm::dot(n, h)), alpha) * saturate(glm::dot(n, h)) /
                       (4.0f * v_dot_h);
            }
        }
    }
    return pdf;
}

BrdfSample sample_brdf(const SurfaceMaterial& m, const glm::vec3& n, const glm::vec3& v, float u1, float u2, float u3) {
    glm::vec3 t, b;
    orthonormal_basis(n, t, b);
    BrdfSample sample;
    if (u1 < specular_sampling_probability(m)) {
        // GGX: cos^2(theta_h) = (1 - u) / (1 + (alpha^2 - 1) u), l = reflect(-v, h).
        const float alpha = ggx_alpha(m.roughness);
        const float phi = 2.0f * kPi * u2;
        const float cos_h = std::sqrt((1.0f - u3) / (1.0f + (alpha * alpha - 1.0f) * u3));
        const float sin_h = std::sqrt(std::max(0.0f, 1.0f - cos_h * cos_h));
        const glm::vec3 h = t * (sin_h * std::cos(phi)) + b * (sin_h * std::sin(phi)) + n * cos_h;
        sample.l = 2.0f * glm::dot(v, h) * h - v;
    } else {
        const float r = std::sqrt(u2);
        const float phi = 2.0f * kPi * u3;
        const float z = std::sqrt(std::max(0.0f, 1.0f - u2));
        sample.l = t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * z;
    }
    sample.pdf = brdf_pdf(m, n, v, sample.l);
    return sample;
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

namespace {
// The specular lobe's (A, B) at one view cosine and roughness, by GGX importance sampling of the
// half vector on Hammersley points.
glm::vec2 specular_albedo_ab_integral(float n_dot_v, float roughness, int samples_per_entry) {
    const float alpha = ggx_alpha(roughness);
    const glm::vec3 v(std::sqrt(std::max(0.0f, 1.0f - n_dot_v * n_dot_v)), 0.0f, n_dot_v);
    double a = 0.0, b = 0.0;
    for (int i = 0; i < samples_per_entry; ++i) {
        // Hammersley points; h with density D(h) cos(theta_h).
        const float u1 = (static_cast<float>(i) + 0.5f) / static_cast<float>(samples_per_entry);
        std::uint32_t bits = static_cast<std::uint32_t>(i);
        bits = (bits << 16u) | (bits >> 16u);
        bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
        bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
        bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
        bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
        const float u2 = static_cast<float>(bits) * 2.3283064365386963e-10f;
        const float tan2 = alpha * alpha * u1 / (1.0f - u1);
        const float cos_h = 1.0f / std::sqrt(1.0f + tan2);
        const float sin_h = std::sqrt(std::max(0.0f, 1.0f - cos_h * cos_h));
        const float phi = 2.0f * 3.14159265358979f * u2;
        const glm::vec3 h(sin_h * std::cos(phi), sin_h * std::sin(phi), cos_h);
        const float v_dot_h = glm::dot(v, h);
        const glm::vec3 l = 2.0f * v_dot_h * h - v;
        if (l.z <= 0.0f || v_dot_h <= 0.0f) continue;
        // D V cos_l / pdf(l), pdf(l) = D cos_h / (4 v.h): the D cancels.
        const float weight = smith_visibility(l.z, n_dot_v, alpha) * l.z * 4.0f * v_dot_h / cos_h;
        const float m = 1.0f - v_dot_h;
        const float fresnel_weight = m * m * m * m * m;
        a += weight * (1.0f - fresnel_weight);
        b += weight * fresnel_weight;
    }
    return glm::vec2(static_cast<float>(a / samples_per_entry), static_cast<float>(b / samples_per_entry));
}

float cell_centre(int index, int size) { return (static_cast<float>(index) + 0.5f) / static_cast<float>(size); }

// Bilinear weights and clamped indices of `x` in [0, 1] over `size` cell centres, as GL_LINEAR
// with GL_CLAMP_TO_EDGE filters.
struct Tap {
    int i0, i1;
    float t;
};
Tap tap(float x, int size) {
    const float position = std::clamp(x, 0.0f, 1.0f) * static_cast<float>(size) - 0.5f;
    const float floor = std::floor(position);
    return {std::clamp(static_cast<int>(floor), 0, size - 1), std::clamp(static_cast<int>(floor) + 1, 0, size - 1),
            position - floor};
}
}  // namespace

std::vector<glm::vec2> specular_albedo_table(int size, int samples_per_entry) {
    std::vector<glm::vec2> table(static_cast<std::size_t>(size) * static_cast<std::size_t>(size));
    for (int row = 0; row < size; ++row) {
        for (int column = 0; column < size; ++column) {
            table[static_cast<std::size_t>(row * size + column)] =
                specular_albedo_ab_integral(cell_centre(column, size), cell_centre(row, size), samples_per_entry);
        }
    }
    return table;
}

std::vector<glm::vec2> specular_average_table(int size, int mu_steps, int samples_per_entry) {
    std::vector<glm::vec2> table(static_cast<std::size_t>(size));
    for (int row = 0; row < size; ++row) {
        glm::vec2 sum(0.0f);
        for (int k = 0; k < mu_steps; ++k) {
            const float mu = cell_centre(k, mu_steps);
            sum += 2.0f * mu * specular_albedo_ab_integral(mu, cell_centre(row, size), samples_per_entry);
        }
        table[static_cast<std::size_t>(row)] = sum / static_cast<float>(mu_steps);
    }
    return table;
}

const BrdfTables& brdf_tables() {
    static const BrdfTables tables{specular_albedo_table(BrdfTables::kSize, 1024),
                                   specular_average_table(BrdfTables::kSize, 128, 256)};
    return tables;
}

glm::vec2 specular_albedo_ab(float n_dot_v, float roughness) {
    const auto& table = brdf_tables().albedo;
    constexpr int size = BrdfTables::kSize;
    const Tap column = tap(n_dot_v, size), row = tap(roughness, size);
    const auto at = [&](int r, int c) { return table[static_cast<std::size_t>(r * size + c)]; };
    return glm::mix(glm::mix(at(row.i0, column.i0), at(row.i0, column.i1), column.t),
                    glm::mix(at(row.i1, column.i0), at(row.i1, column.i1), column.t), row.t);
}

glm::vec2 specular_average_ab(float roughness) {
    const auto& table = brdf_tables().average;
    const Tap row = tap(roughness, BrdfTables::kSize);
    return glm::mix(table[static_cast<std::size_t>(row.i0)], table[static_cast<std::size_t>(row.i1)], row.t);
}

}  // namespace bounce::scene
