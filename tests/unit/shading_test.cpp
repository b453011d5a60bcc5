// The CPU material model: pure Lambertian when specular is 0, energy never created (white
// dielectrics reflect all they receive), rough dielectrics Lambertian, reciprocity, finite at the
// extremes, glTF spot falloff.
#include "renderer/scene/shading.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>

namespace bounce::scene {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;

glm::vec3 from_angles(float theta, float phi) {
    return {std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)};
}

// Directional albedo: integral of f cos over the hemisphere, by stratified midpoint quadrature
// in (cos theta, phi), which is exact for constant integrands.
glm::vec3 directional_albedo(const SurfaceMaterial& m, const glm::vec3& v) {
    constexpr int kCos = 1500, kPhi = 750;  // fine enough for roughness 0.2 lobes
    glm::vec3 sum(0.0f);
    const glm::vec3 n{0, 1, 0};
    for (int i = 0; i < kCos; ++i) {
        const float cos_theta = (static_cast<float>(i) + 0.5f) / kCos;
        const float sin_theta = std::sqrt(1.0f - cos_theta * cos_theta);
        for (int j = 0; j < kPhi; ++j) {
            const float phi = (static_cast<float>(j) + 0.5f) / kPhi * 2.0f * kPi;
            const glm::vec3 l{sin_theta * std::cos(phi), cos_theta, sin_theta * std::sin(phi)};
            sum += evaluate_brdf(m, n, v, l) * cos_theta;
        }
    }
    return sum * (2.0f * kPi / (kCos * kPhi));
}

TEST(Brdf, SpecularZeroIsExactlyLambertian) {
    const SurfaceMaterial m{{0.725f, 0.71f, 0.68f}, 0.0f, 1.0f, 0.0f};
    const glm::vec3 n{0, 1, 0};
    for (float theta_l : {0.0f, 0.7f, 1.5f}) {
        for (float theta_v : {0.0f, 0.9f, 1.4f}) {
            const glm::vec3 f = evaluate_brdf(m, n, from_angles(theta_v, 0.3f), from_angles(theta_l, 2.0f));
            EXPECT_FLOAT_EQ(f.r, 0.725f / kPi);
            EXPECT_FLOAT_EQ(f.b, 0.68f / kPi);
        }
    }
    EXPECT_EQ(evaluate_brdf(m, n, from_angles(0.2f, 0.0f), from_angles(1.8f, 0.0f)), glm::vec3(0.0f));
}

TEST(Brdf, WhiteLambertianAlbedoIsOne) {
    const SurfaceMaterial m{{1.0f, 1.0f, 1.0f}, 0.0f, 1.0f, 0.0f};
    EXPECT_NEAR(directional_albedo(m, from_angles(0.5f, 0.0f)).g, 1.0f, 1e-3f);
}

// White materials reflect at most what they receive (quadrature error < 0.5% at this grid), and
// lose no more than single-scattering GGX does (Kulla and Conty 2017: < 20% for roughness <= 0.5).
TEST(Brdf, NeverReflectsMoreThanItReceives) {
    for (float roughness : {0.2f, 0.5f, 1.0f}) {
        for (float metallic : {0.0f, 1.0f}) {
            const SurfaceMaterial m{{1.0f, 1.0f, 1.0f}, metallic, roughness, 1.0f};
            for (float theta_v : {0.0f, 0.8f, 1.3f}) {
                const glm::vec3 albedo = directional_albedo(m, from_angles(theta_v, 0.0f));
                EXPECT_LE(albedo.g, 1.005f) << "roughness " << roughness << " metallic " << metallic
                                            << " theta_v " << theta_v;
                if (roughness <= 0.5f && theta_v < 1.0f) {
                    EXPECT_GT(albedo.g, 0.8f) << roughness << " " << metallic;
                }
            }
        }
    }
}

TEST(Brdf, Reciprocity) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const glm::vec3 n{0, 1, 0};
    for (int i = 0; i < 200; ++i) {
        const SurfaceMaterial m{{u(rng), u(rng), u(rng)}, u(rng), 0.05f + u(rng), u(rng)};
        const glm::vec3 a = from_angles(u(rng) * 1.5f, u(rng) * 6.28f);
        const glm::vec3 b = from_angles(u(rng) * 1.5f, u(rng) * 6.28f);
        const glm::vec3 fab = evaluate_brdf(m, n, a, b);
        const glm::vec3 fba = evaluate_brdf(m, n, b, a);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(fab[c], fba[c], 1e-4f * std::max(1.0f, fab[c]));
    }
}

TEST(Brdf, FiniteAtTheExtremes) {
    const glm::vec3 n{0, 1, 0};
    for (float roughness : {0.0f, 1e-6f, 1.0f}) {
        for (float metallic : {0.0f, 1.0f}) {
            const SurfaceMaterial m{{1.0f, 1.0f, 1.0f}, metallic, roughness, 1.0f};
            // Mirror direction, grazing light, grazing view, view below the surface.
            for (const auto& [v, l] : std::vector<std::pair<glm::vec3, glm::vec3>>{
                     {n, n}, {from_angles(1.5707f, 0), from_angles(1.5707f, 3.14159f)},
                     {from_angles(1.5707963f, 0), n}, {-n, n}, {from_angles(0.3f, 0), from_angles(0.3f, 3.14159f)}}) {
                const glm::vec3 f = evaluate_brdf(m, n, v, l);
                for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isfinite(f[c])) << roughness << " " << metallic;
            }
        }
    }
}

TEST(Lights, SpotFalloffMatchesGltf) {
    Light spot;
    spot.type = LightType::spot;
    spot.inner_cone = 0.2f;
    spot.outer_cone = 0.4f;
    EXPECT_FLOAT_EQ(spot_attenuation(spot, std::cos(0.1f)), 1.0f);
    EXPECT_FLOAT_EQ(spot_attenuation(spot, std::cos(0.5f)), 0.0f);
    const float mid = std::cos(0.3f);
    const float t = (mid - std::cos(0.4f)) / (std::cos(0.2f) - std::cos(0.4f));
    EXPECT_NEAR(spot_attenuation(spot, mid), t * t, 1e-6f);
}

TEST(Lights, InverseSquareAndDirectional) {
    Light point;
    point.position = {0, 2, 0};
    point.intensity = 8.0f;
    const auto incidence = light_incidence(point, {0, 0, 0});
    EXPECT_FLOAT_EQ(incidence.irradiance.x, 2.0f);
    EXPECT_FLOAT_EQ(incidence.distance, 2.0f);
    Light sun;
    sun.type = LightType::directional;
    sun.direction = {0, -1, 0};
    sun.intensity = 5.0f;
    EXPECT_EQ(light_incidence(sun, {1, 2, 3}).irradiance, glm::vec3(5.0f));
    EXPECT_EQ(light_incidence(sun, {1, 2, 3}).l, glm::vec3(0, 1, 0));
    // A light on the surface point: finite.
    const auto coincident = light_incidence(point, point.position);
    EXPECT_TRUE(std::isfinite(coincident.irradiance.x));
}

}  // namespace
}  // namespace bounce::scene

namespace bounce::scene {
namespace {

// The sampling pdf integrates to 1 over the hemisphere (less what falls below it), and estimates
// of the directional albedo with it agree with quadrature: the sampler and pdf are consistent.
TEST(BrdfSampling, PdfIntegratesToOneAndEstimatesAgreeWithQuadrature) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const glm::vec3 n{0, 1, 0};
    for (const SurfaceMaterial& m : {SurfaceMaterial{{0.8f, 0.8f, 0.8f}, 0.0f, 1.0f, 0.0f},
                                     SurfaceMaterial{{0.9f, 0.9f, 0.9f}, 0.0f, 0.4f, 1.0f},
                                     SurfaceMaterial{{0.9f, 0.6f, 0.3f}, 1.0f, 0.5f, 1.0f}}) {
        const glm::vec3 v = glm::normalize(glm::vec3(0.5f, 1.0f, 0.2f));
        double estimate = 0.0, accepted = 0.0;
        constexpr int kSamples = 200000;
        for (int i = 0; i < kSamples; ++i) {
            const BrdfSample s = sample_brdf(m, n, v, u(rng), u(rng), u(rng));
            if (s.pdf <= 0.0f) continue;
            accepted += 1.0;
            estimate += evaluate_brdf(m, n, v, s.l).g * glm::dot(n, s.l) / s.pdf;
        }
        estimate /= kSamples;
        // Quadrature of the same integral on a fine grid.
        double quadrature = 0.0, pdf_integral = 0.0;
        constexpr int kCos = 1000, kPhi = 500;
        for (int i = 0; i < kCos; ++i) {
            const float c = (i + 0.5f) / kCos;
            const float sn = std::sqrt(1.0f - c * c);
            for (int j = 0; j < kPhi; ++j) {
                const float phi = (j + 0.5f) / kPhi * 2.0f * 3.14159265f;
                const glm::vec3 l{sn * std::cos(phi), c, sn * std::sin(phi)};
                quadrature += evaluate_brdf(m, n, v, l).g * c;
                pdf_integral += brdf_pdf(m, n, v, l);
            }
        }
        quadrature *= 2.0 * 3.14159265 / (kCos * kPhi);
        pdf_integral *= 2.0 * 3.14159265 / (kCos * kPhi);
        EXPECT_NEAR(pdf_integral, accepted / kSamples, 0.01) << "metallic " << m.metallic;
        EXPECT_LE(pdf_integral, 1.0 + 1e-3);
        EXPECT_NEAR(estimate, quadrature, 0.01 * quadrature + 1e-3) << "metallic " << m.metallic;
    }
}

}  // namespace
}  // namespace bounce::scene

namespace bounce::scene {
namespace {

// The (A, B) table against brute-force quadrature of evaluate_brdf over the hemisphere: a white
// metal (F0 = 1) integrates to A + B, a black one (F0 = 0) to B. 2% covers both quadratures.
TEST(SpecularAlbedoTable, MatchesHemisphereQuadratureOfTheBrdf) {
    constexpr int kSize = 8;
    const std::vector<glm::vec2> table = specular_albedo_table(kSize, 4096);
    const glm::vec3 n(0.0f, 0.0f, 1.0f);
    for (int row : {1, 3, 6}) {
        for (int column : {1, 4, 7}) {
            const float roughness = (row + 0.5f) / kSize;
            const float n_dot_v = (column + 0.5f) / kSize;
            const glm::vec3 v(std::sqrt(1.0f - n_dot_v * n_dot_v), 0.0f, n_dot_v);
            double white = 0.0, black = 0.0;
            constexpr int kTheta = 1024, kPhi = 512;
            for (int i = 0; i < kTheta; ++i) {
                const double cos_theta = (i + 0.5) / kTheta;  // uniform in cos: d(omega) = d(cos) d(phi)
                const double sin_theta = std::sqrt(1.0 - cos_theta * cos_theta);
                for (int j = 0; j < kPhi; ++j) {
                    const double phi = 2.0 * 3.14159265358979 * (j + 0.5) / kPhi;
                    const glm::vec3 l(static_cast<float>(sin_theta * std::cos(phi)),
                                      static_cast<float>(sin_theta * std::sin(phi)), static_cast<float>(cos_theta));
                    SurfaceMaterial metal{glm::vec3(1.0f), 1.0f, roughness, 1.0f};
                    const double weight = cos_theta * (1.0 / kTheta) * (2.0 * 3.14159265358979 / kPhi);
                    white += evaluate_brdf(metal, n, v, l).x * weight;
                    metal.base_color = glm::vec3(0.0f);
                    black += evaluate_brdf(metal, n, v, l).x * weight;
                }
            }
            const glm::vec2 ab = table[static_cast<std::size_t>(row * kSize + column)];
            EXPECT_NEAR(ab.x + ab.y, white, 0.02 * white) << "roughness " << roughness << " n.v " << n_dot_v;
            EXPECT_NEAR(ab.y, black, 0.02 * white) << "roughness " << roughness << " n.v " << n_dot_v;
        }
    }
}

}  // namespace
}  // namespace bounce::scene

namespace bounce::scene {
namespace {

// The white furnace of glTF's dielectric with albedo scaling (docs/methods.md, "BRDF"): a white
// base reflects exactly what the specular lobe leaves, so every roughness and specular factor
// reflects all it receives. What remains is the 32x32 table's bilinear interpolation and this
// quadrature: measured within 0.12% up to 80 degrees; the bound is 1%. (Below roughness 0.2 the
// quadrature cannot resolve the lobe; grazing past 80 degrees the table's first cells are coarse.)
TEST(Brdf, WhiteDielectricsReflectAllTheyReceive) {
    for (float roughness : {0.2f, 0.35f, 0.5f, 0.75f, 1.0f}) {
        for (float specular : {0.25f, 0.5f, 1.0f}) {
            const SurfaceMaterial m{{1.0f, 1.0f, 1.0f}, 0.0f, roughness, specular};
            std::printf("white dielectric, roughness %.2f, specular %.2f:", roughness, specular);
            for (float degrees : {0.0f, 30.0f, 60.0f, 75.0f, 80.0f}) {
                const float albedo = directional_albedo(m, from_angles(glm::radians(degrees), 0.0f)).g;
                std::printf(" %.0f deg %.4f", degrees, albedo);
                EXPECT_NEAR(albedo, 1.0f, 0.01f) << "roughness " << roughness << " specular " << specular << " at "
                                                 << degrees << " degrees";
            }
            std::printf("\n");
        }
    }
}

// A rough matte dielectric (roughness 1, glTF's default specular) is Lambertian in what it
// reflects: a white one within 3% of Lambert's albedo of 1 at every angle up to 80 degrees, and a
// grey one never darker than Lambert's at grazing light (the smooth-interface weight
// (1 - F(n.l))(1 - F(n.v)) was 5x darker there); it may be brighter by the specular lobe's own
// reflection, E(mu)(1 - base), which is bounded by the table's directional albedo.
TEST(Brdf, RoughDielectricsAreLambertianInWhatTheyReflect) {
    for (float degrees : {0.0f, 20.0f, 40.0f, 60.0f, 70.0f, 80.0f}) {
        const glm::vec3 v = from_angles(glm::radians(degrees), 0.0f);
        const SurfaceMaterial white{{1.0f, 1.0f, 1.0f}, 0.0f, 1.0f, 1.0f};
        EXPECT_NEAR(directional_albedo(white, v).g, 1.0f, 0.03f) << degrees << " degrees";
        const SurfaceMaterial grey{{0.5f, 0.5f, 0.5f}, 0.0f, 1.0f, 1.0f};
        const float albedo = directional_albedo(grey, v).g;
        const glm::vec2 ab = specular_albedo_ab(std::cos(glm::radians(degrees)), 1.0f);
        const float specular_part = kDielectricF0 * ab.x + ab.y;
        EXPECT_GE(albedo, 0.5f * 0.99f) << degrees << " degrees";
        EXPECT_NEAR(albedo, 0.5f + specular_part * 0.5f, 0.005f) << degrees << " degrees";
    }
}

// No material reflects more than it receives: every roughness, metallic and specular factor.
// Quadrature as above (metals and dielectrics below roughness 0.2 are under-resolved, so only the
// upper bound is meaningful there).
TEST(Brdf, NothingReflectsMoreThanItReceives) {
    for (float roughness : {0.05f, 0.2f, 0.5f, 1.0f}) {
        for (float metallic : {0.0f, 0.5f, 1.0f}) {
            for (float specular : {0.0f, 0.5f, 1.0f}) {
                const SurfaceMaterial m{{1.0f, 1.0f, 1.0f}, metallic, roughness, specular};
                for (float degrees : {0.0f, 45.0f, 75.0f, 85.0f}) {
                    EXPECT_LE(directional_albedo(m, from_angles(glm::radians(degrees), 0.0f)).g, 1.01f)
                        << roughness << " " << metallic << " " << specular << " " << degrees;
                }
            }
        }
    }
}

// The tables behind the weights: the averages are the cosine-weighted means of the directional
// albedos (a finer midpoint sum of the lookups agrees within 1%), and both lie in [0, 1].
TEST(BrdfTables, AveragesAreTheMeansOfTheDirectionalAlbedos) {
    for (float roughness : {0.1f, 0.4f, 0.9f}) {
        glm::vec2 mean(0.0f);
        constexpr int kSteps = 2000;
        for (int k = 0; k < kSteps; ++k) {
            const float mu = (k + 0.5f) / kSteps;
            mean += 2.0f * mu * specular_albedo_ab(mu, roughness) / static_cast<float>(kSteps);
        }
        const glm::vec2 average = specular_average_ab(roughness);
        EXPECT_NEAR(average.x, mean.x, 0.01f * mean.x + 1e-3f) << roughness;
        EXPECT_NEAR(average.y, mean.y, 0.01f * mean.y + 1e-3f) << roughness;
        EXPECT_GE(average.x, 0.0f);
        EXPECT_GE(average.y, 0.0f);
        EXPECT_LE(average.x + average.y, 1.001f);  // a white metal's lobe, integrated on 1024 points each
    }
}


// KHR_materials_specular's colour and KHR_materials_ior: F0 per channel. A white base still
// reflects all it receives in every channel (the diffuse weight is per channel), and the model
// stays reciprocal. Tolerances as for the grey F0 above.
TEST(Brdf, TintedDielectricsConserveEnergyPerChannelAndAreReciprocal) {
    scene::Material glaze;
    glaze.ior = 2.4f;
    glaze.specular_color = {1.0f, 0.5f, 0.25f};
    const glm::vec3 f0 = glaze.dielectric_f0();
    EXPECT_NEAR(f0.r, std::pow(1.4f / 3.4f, 2.0f), 1e-6f);
    EXPECT_NEAR(f0.b, 0.25f * std::pow(1.4f / 3.4f, 2.0f), 1e-6f);
    for (float roughness : {0.3f, 1.0f}) {
        const SurfaceMaterial m{{1.0f, 1.0f, 1.0f}, 0.0f, roughness, 1.0f, f0};
        for (float degrees : {0.0f, 45.0f, 75.0f}) {
            const glm::vec3 albedo = directional_albedo(m, from_angles(glm::radians(degrees), 0.0f));
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(albedo[c], 1.0f, 0.01f) << roughness << " " << degrees << " " << c;
        }
    }
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const glm::vec3 n{0, 1, 0};
    for (int i = 0; i < 100; ++i) {
        const SurfaceMaterial m{{u(rng), u(rng), u(rng)}, u(rng), 0.05f + u(rng), u(rng), {u(rng), u(rng), u(rng)}};
        const glm::vec3 a = from_angles(u(rng) * 1.5f, u(rng) * 6.28f), b = from_angles(u(rng) * 1.5f, u(rng) * 6.28f);
        const glm::vec3 fab = evaluate_brdf(m, n, a, b), fba = evaluate_brdf(m, n, b, a);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(fab[c], fba[c], 1e-4f * std::max(1.0f, fab[c]));
    }
}

// The CPU twin's texture lookup follows the texture's glTF sampler, as the GPU's sampler objects
// do: a 2x1 texture, black then white, read at chosen u.
TEST(TextureLookup, FollowsTheSamplersFilterAndWraps) {
    Texture texture;
    texture.width = 2;
    texture.height = 1;
    texture.rgba8 = {0, 0, 0, 255, 255, 255, 255, 255};
    auto red_at = [&](float u) { return sample_texture(texture, {u, 0.5f}).r; };
    // Bilinear, repeat: between texel centres a ramp; across the edge the wrap blends both ends.
    EXPECT_FLOAT_EQ(red_at(0.5f), 0.5f);
    EXPECT_FLOAT_EQ(red_at(0.25f), 0.0f);
    EXPECT_FLOAT_EQ(red_at(0.0f), 0.5f);
    texture.sampler.mag_nearest = true;
    EXPECT_FLOAT_EQ(red_at(0.49f), 0.0f);
    EXPECT_FLOAT_EQ(red_at(0.51f), 1.0f);
    EXPECT_FLOAT_EQ(red_at(1.2f), 0.0f);  // repeat: 0.2
    texture.sampler.wrap_s = TextureSampler::Wrap::clamp_to_edge;
    EXPECT_FLOAT_EQ(red_at(1.2f), 1.0f);
    EXPECT_FLOAT_EQ(red_at(-3.0f), 0.0f);
    texture.sampler.wrap_s = TextureSampler::Wrap::mirrored_repeat;
    EXPECT_FLOAT_EQ(red_at(1.2f), 1.0f);   // mirrored: 0.8
    EXPECT_FLOAT_EQ(red_at(1.7f), 0.0f);   // mirrored: 0.3
    EXPECT_FLOAT_EQ(red_at(-0.2f), 0.0f);  // mirrored: 0.2
    EXPECT_FLOAT_EQ(red_at(2.2f), 0.0f);   // a whole period on: 0.2
    // Non-finite coordinates read a texel, never out of bounds.
    EXPECT_TRUE(std::isfinite(red_at(std::numeric_limits<float>::infinity())));
    EXPECT_TRUE(std::isfinite(red_at(std::nanf(""))));
    texture.sampler.mag_nearest = false;
    EXPECT_TRUE(std::isfinite(red_at(1e30f)));
}

}  // namespace
}  // namespace bounce::scene
