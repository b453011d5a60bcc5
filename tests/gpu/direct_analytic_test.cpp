// `direct` against closed-form radiance: a Lambertian or glossy plane under each light type, a
// blocker's shadow where geometry puts it, and emission. Tolerance: 1% relative at pixel centres
// (the G-buffer stores positions in float and normals/material in half precision).
#include "gpu_fixture.hpp"
#include "renderer/passes/shadow_maps.hpp"
#include "renderer/scene/gltf_import.hpp"
#include "renderer/scene/shading.hpp"

#include <unistd.h>

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <limits>
#include <array>
#include <filesystem>
#include <fstream>
#include <numbers>

namespace bounce::test {
namespace {

constexpr int kSize = 96;
constexpr float kRelativeTolerance = 0.01f;

struct PlaneSetup {
    scene::Scene scene;
    RenderRequest request;
};

PlaneSetup plane_under(const scene::Material& material, const scene::Light& light) {
    PlaneSetup setup;
    setup.scene.name = "plane";
    setup.scene.materials.push_back(material);
    add_square(setup.scene, "floor", glm::vec3(0.0f), 2.0f, {0, 1, 0}, 0);
    setup.scene.lights.push_back(light);
    setup.request.width = setup.request.height = kSize;
    setup.request.camera = top_down_camera(2.0f, 1.2f);
    setup.request.preset = "medium";
    return setup;
}

scene::Light point_light(const glm::vec3& position, float intensity) {
    scene::Light light;
    light.name = "point";
    light.type = scene::LightType::point;
    light.position = position;
    light.intensity = intensity;
    return light;
}

// Expected radiance at a ground point from the C++ twin of the shaders' BRDF and lights.
glm::vec3 expected_radiance(const scene::Material& material, const scene::Light& light,
                            const scene::Camera& camera, const glm::vec3& p) {
    const glm::vec3 n{0, 1, 0};
    const auto incidence = scene::light_incidence(light, p);
    const float cos_theta = std::max(glm::dot(n, incidence.l), 0.0f);
    const glm::vec3 v = glm::normalize(camera.position - p);
    return scene::evaluate_brdf(scene::SurfaceMaterial::from(material), n, v, incidence.l) * incidence.irradiance *
           cos_theta;
}

// Compares every 8th pixel with the closed form; returns how many were compared.
int expect_matches_closed_form(const PlaneSetup& setup, const RenderResult& result, float absolute_floor = 1e-6f) {
    const auto& material = setup.scene.materials[0];
    const auto& light = setup.scene.lights[0];
    int compared = 0;
    for (int y = 4; y < kSize; y += 8) {
        for (int x = 4; x < kSize; x += 8) {
            const glm::vec3 p = pixel_on_ground(*setup.request.camera, kSize, kSize, x, y);
            const glm::vec3 expected = expected_radiance(material, light, *setup.request.camera, p);
            const glm::vec3 actual{result.frame.at(x, y)};
            for (int c = 0; c < 3; ++c) {
                const float tolerance = std::max(kRelativeTolerance * expected[c], absolute_floor);
                EXPECT_NEAR(actual[c], expected[c], tolerance) << "pixel " << x << "," << y << " channel " << c
                                                               << " ground point " << p.x << "," << p.z;
            }
            ++compared;
        }
    }
    return compared;
}

TEST(DirectAnalytic, LambertianPlaneUnderPointLight) {
    const auto material = matte({0.5f, 0.25f, 0.8f});
    const auto setup = plane_under(material, point_light({0.3f, 1.0f, -0.2f}, 2.0f));
    const auto result = render_scene(setup.scene, setup.request);
    EXPECT_EQ(expect_matches_closed_form(setup, result), 144);

    // The closed form itself, independent of the BRDF code: albedo / pi * I cos(theta) / d^2.
    const glm::vec3 p = pixel_on_ground(*setup.request.camera, kSize, kSize, 48, 48);
    const glm::vec3 to_light = glm::vec3(0.3f, 1.0f, -0.2f) - p;
    const float d2 = glm::dot(to_light, to_light);
    const float cos_theta = to_light.y / std::sqrt(d2);
    const float expected_red = 0.5f / std::numbers::pi_v<float> * 2.0f * cos_theta / d2;
    EXPECT_NEAR(result.frame.at(48, 48).r, expected_red, kRelativeTolerance * expected_red);
}

TEST(DirectAnalytic, GlossyDielectricAndMetalMatchTheBrdf) {
    scene::Material dielectric = matte({0.6f, 0.6f, 0.6f});
    dielectric.roughness = 0.5f;
    dielectric.specular = 1.0f;
    scene::Material metal = matte({0.9f, 0.6f, 0.3f});
    metal.metallic = 1.0f;
    metal.roughness = 0.6f;
    metal.specular = 1.0f;
    // KHR_materials_ior and specularColorFactor: F0 = ((2.4 - 1)/(2.4 + 1))^2 (1, 0.5, 0.25), a tinted
    // glaze whose F0 colour reaches the frame through the G-buffer's specular target.
    scene::Material tinted = dielectric;
    tinted.roughness = 0.3f;
    tinted.ior = 2.4f;
    tinted.specular_color = {1.0f, 0.5f, 0.25f};
    for (const auto& material : {dielectric, metal, tinted}) {
        const auto setup = plane_under(material, point_light({0.2f, 0.8f, 0.1f}, 1.0f));
        const auto result = render_scene(setup.scene, setup.request);
        EXPECT_EQ(expect_matches_closed_form(setup, result), 144) << "metallic " << material.metallic;
    }
}

TEST(DirectAnalytic, SpotConeInnerRampAndOutside) {
    scene::Light spot = point_light({0.0f, 1.0f, 0.0f}, 3.0f);
    spot.type = scene::LightType::spot;
    spot.direction = {0.0f, -1.0f, 0.0f};
    spot.inner_cone = glm::radians(20.0f);
    spot.outer_cone = glm::radians(35.0f);
    const auto setup = plane_under(matte({0.7f, 0.7f, 0.7f}), spot);
    const auto result = render_scene(setup.scene, setup.request);
    expect_matches_closed_form(setup, result, 1e-4f);

    // Some compared pixels must lie in each region, or the test would not test the cone.
    int inside = 0, ramp = 0, outside = 0;
    for (int y = 4; y < kSize; y += 8) {
        for (int x = 4; x < kSize; x += 8) {
            const glm::vec3 p = pixel_on_ground(*setup.request.camera, kSize, kSize, x, y);
            const float angle = std::atan2(glm::length(glm::vec2(p.x, p.z)), 1.0f);
            if (angle < spot.inner_cone) ++inside;
            else if (angle < spot.outer_cone) ++ramp;
            else {
                ++outside;
                EXPECT_EQ(result.frame.at(x, y).r, 0.0f) << "outside the cone at " << x << "," << y;
            }
        }
    }
    EXPECT_GT(inside, 4);
    EXPECT_GT(ramp, 4);
    EXPECT_GT(outside, 4);
}

TEST(DirectAnalytic, DirectionalIrradiance) {
    scene::Light sun;
    sun.name = "sun";
    sun.type = scene::LightType::directional;
    sun.direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
    sun.intensity = 3.0f;  // W/m^2 on a surface facing it
    const auto setup = plane_under(matte({0.4f, 0.5f, 0.6f}), sun);
    const auto result = render_scene(setup.scene, setup.request);
    expect_matches_closed_form(setup, result);
    const float cos_theta = -sun.direction.y;
    EXPECT_NEAR(result.frame.at(40, 52).g, 0.5f / std::numbers::pi_v<float> * 3.0f * cos_theta,
                0.5f / std::numbers::pi_v<float> * 3.0f * cos_theta * kRelativeTolerance);
}

TEST(DirectAnalytic, BlockerCastsTheShadowGeometryPredicts) {
    // A square blocker (half size 0.2) at height 0.5 under a light at height 1.5: its shadow on the
    // ground is a square of half size 0.2 * 1.5 / (1.5 - 0.5) = 0.3. The blocker faces down, so
    // the camera above sees through its culled back face to the ground (it still casts shadows).
    auto material = matte({0.6f, 0.6f, 0.6f});
    auto setup = plane_under(material, point_light({0.0f, 1.5f, 0.0f}, 2.0f));
    add_square(setup.scene, "blocker", {0.0f, 0.5f, 0.0f}, 0.2f, {0, -1, 0}, 0);
    const auto result = render_scene(setup.scene, setup.request);

    int umbra = 0, lit = 0;
    for (int y = 0; y < kSize; y += 3) {
        for (int x = 0; x < kSize; x += 3) {
            const glm::vec3 p = pixel_on_ground(*setup.request.camera, kSize, kSize, x, y);
            const float chebyshev = std::max(std::abs(p.x), std::abs(p.z));
            const float actual = result.frame.at(x, y).r;
            if (chebyshev < 0.27f) {
                EXPECT_EQ(actual, 0.0f) << "expected umbra at ground " << p.x << "," << p.z;
                ++umbra;
            } else if (chebyshev > 0.33f && chebyshev < 1.9f) {
                const float expected = expected_radiance(material, setup.scene.lights[0], *setup.request.camera, p).r;
                EXPECT_NEAR(actual, expected, kRelativeTolerance * expected) << "expected light at " << p.x << "," << p.z;
                ++lit;
            }
        }
    }
    EXPECT_GT(umbra, 20);
    EXPECT_GT(lit, 200);
}

// How far shaders/common/shadows.glsl moves a looked-up point along its normal, in texels of the map
// it reads.
constexpr float kShadowNormalOffsetTexels = 1.0f;

// A sun over a ground 400 m wide: its map over the whole scene has texels of 0.28 m at 2048, and a
// blocker 1 m wide above the ground casts a shadow whose edges that map misplaces by more than the
// view cascades allow. In the finest cascade that holds the view (texel t) an edge lies within
// (1.5 + o tan(theta)) t of where the geometry puts it: the normal offset of o = 1 t lifts the
// looked-up point, which moves its shadow along the ground by o t tan(theta) (theta the sun's angle
// off the vertical), the bilinear filter crosses half its value within half a texel of the stored
// edge, and the stored edge lies within a texel of the true one. One pixel's footprint is added for
// where the pixel centre falls. Two suns: 20 degrees off the vertical, and a low one at 70, where
// the offset's share is the largest (an offset of 1.5 t moved it 4.1 t, past the bound, and on the
// bench street such shadow edges on facades carried half of cssm medium's error). The same holds
// with the whole scene scaled by 1e-3 and 1e4 (a ground of 40 cm and of 4 km): the fit, the offsets
// and the depths are all relative to the scene.
TEST(DirectAnalytic, ASunsShadowEdgeInAWideSceneLiesWithinTheViewCascadesTexels) {
    constexpr int kMapSize = 2048;
    const scene::Material material = matte({0.6f, 0.6f, 0.6f});
    struct Sun {
        glm::vec3 direction;
        float blocker_height;  // keeps the shadow in view
    };
    const float tan_70 = std::tan(glm::radians(70.0f));
    for (const Sun& sun_case : {Sun{{0.3f, -1.0f, 0.2f}, 1.0f}, Sun{{tan_70, -1.0f, 0.0f}, 0.3f}}) {
    const scene::Light sun = directional_light(glm::normalize(sun_case.direction), 3.0f);
    const float tan_theta = glm::length(glm::vec2(sun.direction.x, sun.direction.z)) / -sun.direction.y;
    for (const float scale : {1.0f, 1e-3f, 1e4f}) {
        SCOPED_TRACE("scale " + std::to_string(scale) + ", sun tan " + std::to_string(tan_theta));
        auto setup = plane_under(material, sun);
        setup.scene.objects.clear();
        setup.scene.meshes.clear();
        add_square(setup.scene, "ground", glm::vec3(0.0f), 200.0f * scale, {0, 1, 0}, 0);
        // Culled from above, it still casts.
        add_square(setup.scene, "blocker", {0.0f, sun_case.blocker_height * scale, 0.0f}, 0.5f * scale, {0, -1, 0},
                   0);
        setup.request.camera = top_down_camera(3.0f * scale, 1.0f);
        const scene::Camera& camera = *setup.request.camera;
        // The shadow: the blocker moved along the light onto the ground.
        const glm::vec2 shadow_centre =
            sun_case.blocker_height * scale * glm::vec2(sun.direction.x, sun.direction.z) / -sun.direction.y;
        const float shadow_half = 0.5f * scale;

        const auto cascades = passes::ShadowMaps::fit_view_cascades(setup.scene.world_bounds(), sun.direction, camera,
                                                                    kSize, kSize, kMapSize, 3);
        ASSERT_FALSE(cascades.empty());
        const float texel = cascades.front().texel;
        const float footprint =
            glm::distance(pixel_on_ground(camera, kSize, kSize, 0, 0), pixel_on_ground(camera, kSize, kSize, 1, 1));
        const float tolerance = (1.5f + kShadowNormalOffsetTexels * tan_theta) * texel + footprint;
        const float scene_texel = glm::length(setup.scene.world_bounds().extent()) / kMapSize;
        if (scale == 1.0f && tan_theta < 1.0f) {
            RecordProperty("finest_cascade_texel_mm", static_cast<int>(std::lround(1000.0f * texel)));
            RecordProperty("scene_map_texel_mm", static_cast<int>(std::lround(1000.0f * scene_texel)));
        }
        ASSERT_LT(tolerance, 0.5f * shadow_half) << "the test's shadow must be resolved by the cascade";

        // Pixels whose side of the edge differs from the geometry's, farther from it than `tolerance`.
        const auto misplaced = [&](int view_cascades) {
            RenderRequest request = setup.request;
            request.knobs = {{"shadow_map_size", kMapSize}, {"shadow_cascades", view_cascades}};
            const auto result = render_scene(setup.scene, request);
            int far_from_edge = 0, shadowed = 0;
            for (int y = 0; y < kSize; ++y) {
                for (int x = 0; x < kSize; ++x) {
                    const glm::vec3 p = pixel_on_ground(camera, kSize, kSize, x, y);
                    const glm::vec2 offset = glm::abs(glm::vec2(p.x, p.z) - shadow_centre);
                    const float chebyshev = std::max(offset.x, offset.y);
                    const bool in_shadow = chebyshev < shadow_half;
                    const float lit = expected_radiance(material, sun, camera, p).r;
                    const bool dark = result.frame.at(x, y).r < 0.5f * lit;
                    shadowed += in_shadow;
                    if (dark != in_shadow && std::abs(chebyshev - shadow_half) > tolerance) ++far_from_edge;
                }
            }
            EXPECT_GT(shadowed, 200);
            return far_from_edge;
        };
        EXPECT_EQ(misplaced(3), 0) << "cascade texel " << texel << ", tolerance " << tolerance;
        // The scene's map alone, whose texels are larger, fails the same bound: the test tells them apart.
        const int by_the_scene_map = misplaced(0);
        if (scale == 1.0f && tan_theta < 1.0f) {
            RecordProperty("pixels_misplaced_by_the_scene_map", by_the_scene_map);
        }
        EXPECT_GT(by_the_scene_map, 0) << "scene map texel " << scene_texel;
    }
    }
}

// The same ground seen along it, with blockers at 15, 60 and 150 m: each shadow falls in a
// cascade of its own (depths 33, 99 and 297 m here), and every pixel's side of the edges must be
// the geometry's wherever it lies farther from them than the bound above, taken with the texel of
// the cascade the lookup reads there (the finest whose window holds the point moved by its normal
// offset, a texel in from the edge, as shaders/common/shadows.glsl picks it) and that pixel's own
// footprint on the ground (which grows along the view). A cascade read with another's matrix would
// put its shadows metres away.
TEST(DirectAnalytic, ShadowEdgesAlongAWideGroundLieWithinTheTexelsOfTheirCascades) {
    constexpr int kMapSize = 2048, kCascades = 3;
    scene::Light sun = directional_light(glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f)), 3.0f);
    const float tan_theta = glm::length(glm::vec2(sun.direction.x, sun.direction.z)) / -sun.direction.y;
    const scene::Material material = matte({0.6f, 0.6f, 0.6f});
    auto setup = plane_under(material, sun);
    setup.scene.objects.clear();
    setup.scene.meshes.clear();
    add_square(setup.scene, "ground", glm::vec3(0.0f), 200.0f, {0, 1, 0}, 0);
    struct Blocker {
        glm::vec3 centre;
        float half;
    };
    const Blocker blockers[] = {
        {{0.0f, 1.0f, 15.0f}, 1.0f}, {{0.0f, 1.0f, 60.0f}, 4.0f}, {{0.0f, 1.0f, 150.0f}, 10.0f}};
    for (const Blocker& blocker : blockers) {
        add_square(setup.scene, "blocker", blocker.centre, blocker.half, {0, -1, 0}, 0);
    }
    setup.request.camera = scene::Camera::look_at({0.0f, 8.0f, 0.0f}, {0.0f, 0.0f, 40.0f}, {0, 1, 0}, 1.0f);
    const scene::Camera& camera = *setup.request.camera;
    const auto cascades = passes::ShadowMaps::fit_view_cascades(setup.scene.world_bounds(), sun.direction, camera,
                                                                kSize, kSize, kMapSize, kCascades);
    ASSERT_EQ(cascades.size(), static_cast<std::size_t>(kCascades));
    const float scene_texel = glm::length(setup.scene.world_bounds().extent()) / kMapSize;
    // The texel the lookup reads at ground point p, and which cascade (kCascades: the scene's map).
    const auto read_at = [&](const glm::vec3& p) -> std::pair<int, float> {
        for (int k = 0; k < kCascades; ++k) {
            const auto& cascade = cascades[static_cast<std::size_t>(k)];
            const float texel = cascade.texel;
            const glm::vec3 looked_up = p + glm::vec3(0, kShadowNormalOffsetTexels * texel, 0);
            const glm::vec4 clip = cascade.view_projection * glm::vec4(looked_up, 1.0f);
            const glm::vec2 uv = glm::vec2(clip) * 0.5f + 0.5f;
            const float margin = 1.0f / kMapSize;
            if (glm::all(glm::greaterThanEqual(uv, glm::vec2(margin))) &&
                glm::all(glm::lessThanEqual(uv, glm::vec2(1.0f - margin)))) {
                return {k, texel};
            }
        }
        return {kCascades, scene_texel};
    };
    // Distance from p to the nearest shadow edge, and whether p is in a shadow.
    const auto shadows_at = [&](const glm::vec3& p) {
        float nearest = std::numeric_limits<float>::max();
        bool inside = false;
        for (const Blocker& blocker : blockers) {
            const glm::vec2 centre = glm::vec2(blocker.centre.x, blocker.centre.z) +
                                     blocker.centre.y * glm::vec2(sun.direction.x, sun.direction.z) / -sun.direction.y;
            const glm::vec2 offset = glm::abs(glm::vec2(p.x, p.z) - centre) - glm::vec2(blocker.half);
            const bool in = offset.x < 0.0f && offset.y < 0.0f;
            inside = inside || in;
            const float to_edge = in ? -std::max(offset.x, offset.y) : glm::length(glm::max(offset, glm::vec2(0.0f)));
            nearest = std::min(nearest, to_edge);
        }
        return std::pair{inside, nearest};
    };

    const auto misplaced = [&](std::array<int, kCascades + 1>& edge_pixels_read) {
        RenderRequest request = setup.request;
        request.knobs = {{"shadow_map_size", kMapSize}, {"shadow_cascades", kCascades}};
        const auto result = render_scene(setup.scene, request);
        int far_from_edge = 0;
        for (int y = 1; y + 1 < kSize; ++y) {
            for (int x = 1; x + 1 < kSize; ++x) {
                const glm::vec3 p = pixel_on_ground(camera, kSize, kSize, x, y);
                if (!(p.z > 1.0f) || std::abs(p.x) > 190.0f || p.z > 190.0f) continue;  // the sky, past the ground
                float footprint = 0.0f;
                for (const glm::ivec2 step : {glm::ivec2(1, 0), glm::ivec2(-1, 0), glm::ivec2(0, 1), glm::ivec2(0, -1)}) {
                    const glm::vec3 beside = pixel_on_ground(camera, kSize, kSize, x + step.x, y + step.y);
                    footprint = std::max(footprint, glm::distance(p, beside));
                }
                const auto [in_shadow, edge] = shadows_at(p);
                const auto [cascade, texel] = read_at(p);
                const float tolerance = (1.5f + kShadowNormalOffsetTexels * tan_theta) * texel + footprint;
                if (edge < 4.0f * tolerance) ++edge_pixels_read[static_cast<std::size_t>(cascade)];
                const float lit = expected_radiance(material, sun, camera, p).r;
                const bool dark = result.frame.at(x, y).r < 0.5f * lit;
                if (dark != in_shadow && edge > tolerance) ++far_from_edge;
            }
        }
        return far_from_edge;
    };
    std::array<int, kCascades + 1> edge_pixels{};
    EXPECT_EQ(misplaced(edge_pixels), 0);
    // Each cascade shadowed the edges of its own blocker.
    for (int k = 0; k < kCascades; ++k) {
        EXPECT_GT(edge_pixels[static_cast<std::size_t>(k)], 5) << "cascade " << k;
        RecordProperty("edge_pixels_cascade" + std::to_string(k), edge_pixels[static_cast<std::size_t>(k)]);
    }
}

TEST(DirectAnalytic, EmissionIsSeenAsItsRadiance) {
    scene::Scene scene;
    scene::Material glow = matte({0.0f, 0.0f, 0.0f});
    glow.emissive = {2.0f, 1.0f, 0.5f};
    scene.materials.push_back(glow);
    add_square(scene, "glow", glm::vec3(0.0f), 2.0f, {0, 1, 0}, 0);
    RenderRequest request;
    request.width = request.height = 32;
    request.camera = top_down_camera(2.0f, 1.0f);
    const auto result = render_scene(scene, request);
    for (int y = 0; y < 32; y += 5) {
        for (int x = 0; x < 32; x += 5) {
            EXPECT_FLOAT_EQ(result.frame.at(x, y).r, 2.0f);
            EXPECT_FLOAT_EQ(result.frame.at(x, y).g, 1.0f);
            EXPECT_FLOAT_EQ(result.frame.at(x, y).b, 0.5f);
            EXPECT_FLOAT_EQ(result.frame.at(x, y).a, 1.0f);
        }
    }
}

TEST(DirectAnalytic, DoublingIntensityDoublesRadiance) {
    const auto material = matte({0.5f, 0.5f, 0.5f});
    const auto single = plane_under(material, point_light({0.1f, 1.2f, 0.3f}, 1.0f));
    const auto doubled = plane_under(material, point_light({0.1f, 1.2f, 0.3f}, 2.0f));
    const auto a = render_scene(single.scene, single.request);
    const auto b = render_scene(doubled.scene, doubled.request);
    for (std::size_t i = 0; i < a.frame.rgba.size(); i += 4) {
        EXPECT_NEAR(b.frame.rgba[i], 2.0f * a.frame.rgba[i], 1e-5f + 1e-5f * a.frame.rgba[i]);
    }
}

// Lights as a glTF file gives them, in KHR_lights_punctual's photometric units: a point and a spot
// light in candela, a sun in lux, converted at 683 lm/W. The closed forms below are written from
// the file's numbers alone: albedo / pi * (I / 683) cos(theta) / d^2 and albedo / pi * (E / 683)
// cos(theta). Tolerance as above (1%).
TEST(DirectAnalytic, FileLightsAreInCandelaAndLux) {
    const auto path = std::filesystem::temp_directory_path() / ("bounce-lights-" + std::to_string(::getpid()) + ".gltf");
    std::ofstream(path) << R"({"asset": {"version": "2.0"}, "extensionsUsed": ["KHR_lights_punctual"],
      "extensions": {"KHR_lights_punctual": {"lights": [
        {"type": "point", "intensity": 1366},
        {"type": "spot", "intensity": 2049, "spot": {"innerConeAngle": 0.6, "outerConeAngle": 0.7}},
        {"type": "directional", "intensity": 2000}]}},
      "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
      "nodes": [
        {"name": "bulb", "translation": [0.3, 1.0, -0.2], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "torch", "translation": [0.0, 1.0, 0.0], "rotation": [-0.7071067811865476, 0, 0, 0.7071067811865476],
         "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"name": "sun", "rotation": [-0.7071067811865476, 0, 0, 0.7071067811865476],
         "extensions": {"KHR_lights_punctual": {"light": 2}}}]})";
    const scene::Scene file = scene::import_gltf_file(path);
    std::filesystem::remove(path);
    ASSERT_EQ(file.lights.size(), 3u);
    const float albedo = 0.5f;
    const float pi = std::numbers::pi_v<float>;
    struct Case {
        const scene::Light& light;
        glm::vec3 position;  // of the light; unused for the sun
        float photometric;   // cd or lx, as in the file
        bool directional;
    };
    for (const Case& c : {Case{file.lights[0], {0.3f, 1.0f, -0.2f}, 1366.0f, false},
                          Case{file.lights[1], {0.0f, 1.0f, 0.0f}, 2049.0f, false},
                          Case{file.lights[2], {}, 2000.0f, true}}) {
        const auto setup = plane_under(matte(glm::vec3(albedo)), c.light);
        const auto result = render_scene(setup.scene, setup.request);
        const glm::vec3 p = pixel_on_ground(*setup.request.camera, kSize, kSize, 48, 48);
        float expected = albedo / pi * c.photometric / 683.0f;  // the sun shines straight down
        if (!c.directional) {
            const glm::vec3 to_light = c.position - p;
            const float d2 = glm::dot(to_light, to_light);
            expected *= to_light.y / std::sqrt(d2) / d2;
        }
        EXPECT_NEAR(result.frame.at(48, 48).r, expected, kRelativeTolerance * expected) << c.light.name;
        expect_matches_closed_form(setup, result);
    }
}


// KHR_materials_specular's textures: the specular texture's alpha scales the factor and the colour
// texture's RGB (sRGB) the colour, on the GPU as in the CPU twin (textured_material). Constant 1x1
// textures, so that filtering plays no part; tolerance as above.
TEST(DirectAnalytic, SpecularTexturesScaleFactorAndColour) {
    scene::Material glaze = matte({0.6f, 0.6f, 0.6f});
    glaze.roughness = 0.3f;
    glaze.specular = 1.0f;
    glaze.ior = 2.0f;
    scene::Texture alpha, colour;
    alpha.width = alpha.height = colour.width = colour.height = 1;
    alpha.rgba8 = {255, 255, 255, 128};
    colour.rgba8 = {255, 128, 64, 255};
    colour.srgb = true;
    glaze.specular_texture.texture = 0;
    glaze.specular_color_texture.texture = 1;
    auto setup = plane_under(glaze, point_light({0.2f, 0.8f, 0.1f}, 1.0f));
    setup.scene.textures = {alpha, colour};
    const auto result = render_scene(setup.scene, setup.request);
    const auto textured = scene::textured_material(setup.scene, glaze, glm::vec2(0.5f), glm::vec2(0.5f));
    EXPECT_NEAR(textured.surface.specular, 128.0f / 255.0f, 1e-6f);
    EXPECT_LT(textured.surface.f0.b, textured.surface.f0.r);
    const glm::vec3 n{0, 1, 0};
    const auto& light = setup.scene.lights[0];
    int compared = 0;
    for (int y = 4; y < kSize; y += 8) {
        for (int x = 4; x < kSize; x += 8) {
            const glm::vec3 p = pixel_on_ground(*setup.request.camera, kSize, kSize, x, y);
            const auto incidence = scene::light_incidence(light, p);
            const glm::vec3 v = glm::normalize(setup.request.camera->position - p);
            const glm::vec3 expected = scene::evaluate_brdf(textured.surface, n, v, incidence.l) * incidence.irradiance *
                                       std::max(glm::dot(n, incidence.l), 0.0f);
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(result.frame.at(x, y)[c], expected[c], std::max(kRelativeTolerance * expected[c], 1e-6f))
                    << x << "," << y << " channel " << c;
            }
            ++compared;
        }
    }
    EXPECT_EQ(compared, 144);
}

}  // namespace
}  // namespace bounce::test
