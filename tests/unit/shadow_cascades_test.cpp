// A directional light's view cascades (passes::ShadowMaps::fit_view_cascades): what each must hold,
// how fine it may be, and that neither changes with the scene's scale. CPU only: the fit is geometry.
#include "renderer/passes/shadow_maps.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace bounce::test {
namespace {

using passes::ShadowMaps;

constexpr int kWidth = 128, kHeight = 96, kMapSize = 1024, kCascades = 3;

// A street 400 m square and 20 m high, seen from eye height, looking along it and down a little.
struct Street {
    scene::Aabb bounds{{-200.0f, 0.0f, -200.0f}, {200.0f, 20.0f, 200.0f}};
    glm::vec3 sun = glm::normalize(glm::vec3(0.5f, -0.6f, -0.4f));
    scene::Camera camera = scene::Camera::look_at({-150.0f, 1.7f, 10.0f}, {0.0f, 0.0f, 30.0f}, {0, 1, 0}, 1.0f);
};

glm::vec3 uniform_in(const scene::Aabb& box, std::mt19937& random) {
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    return box.min + glm::vec3(unit(random), unit(random), unit(random)) * (box.max - box.min);
}

// A point of the view's pyramid up to `depth`, uniform in its image and depth.
glm::vec3 in_view(const scene::Camera& camera, float depth, std::mt19937& random) {
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const float tan_vertical = std::tan(0.5f * camera.vertical_fov), aspect = static_cast<float>(kWidth) / kHeight;
    const glm::vec3 forward = camera.forward(), up = camera.up(), right = glm::normalize(glm::cross(forward, up));
    const float d = depth * unit(random);
    return camera.position + d * (forward + (2.0f * unit(random) - 1.0f) * tan_vertical * aspect * right +
                                  (2.0f * unit(random) - 1.0f) * tan_vertical * up);
}

bool inside(const scene::Aabb& box, const glm::vec3& p) {
    return glm::all(glm::greaterThanEqual(p, box.min)) && glm::all(glm::lessThanEqual(p, box.max));
}

// Every point the camera sees of the scene up to a cascade's depth projects inside its window with
// room for what the lookup reads of it: its normal offset (1.5 texels, in any direction) and the
// filter's texel. Every point of the scene, seen or not, lies within its depth range: a caster
// outside the view still casts.
TEST(ShadowCascades, EachHoldsWhatTheViewSeesOfTheSceneUpToItsDepthAndEveryCaster) {
    const Street street;
    const auto cascades =
        ShadowMaps::fit_view_cascades(street.bounds, street.sun, street.camera, kWidth, kHeight, kMapSize, kCascades);
    ASSERT_EQ(cascades.size(), static_cast<std::size_t>(kCascades));
    std::mt19937 random(7);
    for (const auto& cascade : cascades) {
        const float margin = 2.0f * 2.5f / kMapSize;  // 2.5 texels, in clip units
        int seen = 0;
        for (int i = 0; i < 20000; ++i) {
            const glm::vec3 p = in_view(street.camera, cascade.depth, random);
            if (!inside(street.bounds, p)) continue;
            ++seen;
            const glm::vec4 clip = cascade.view_projection * glm::vec4(p, 1.0f);
            EXPECT_LE(std::abs(clip.x), 1.0f - margin)
                << "depth " << cascade.depth << " point " << p.x << "," << p.y << "," << p.z;
            EXPECT_LE(std::abs(clip.y), 1.0f - margin) << "depth " << cascade.depth;
        }
        EXPECT_GT(seen, 1000);
        for (int i = 0; i < 2000; ++i) {
            const glm::vec4 clip = cascade.view_projection * glm::vec4(uniform_in(street.bounds, random), 1.0f);
            EXPECT_LE(std::abs(clip.z), 1.0f);
        }
    }
}

// Finer than the scene's map, coarser outwards, and no coarser than the pyramid they hold asks: its
// width across the light is at most twice its slant edge, depth sqrt(1 + tan_h^2 + tan_v^2); the
// window adds two texels a side and rounds up to a step of 2^(1/4).
TEST(ShadowCascades, AreAsFineAsThePyramidTheyHoldAllows) {
    const Street street;
    const auto cascades =
        ShadowMaps::fit_view_cascades(street.bounds, street.sun, street.camera, kWidth, kHeight, kMapSize, kCascades);
    ASSERT_FALSE(cascades.empty());
    const float scene_texel = glm::length(street.bounds.extent()) / kMapSize;
    const float tan_vertical = std::tan(0.5f * street.camera.vertical_fov);
    const float tan_horizontal = tan_vertical * kWidth / kHeight;
    const float slant = std::sqrt(1.0f + tan_horizontal * tan_horizontal + tan_vertical * tan_vertical);
    float coarser_than = 0.0f;
    for (const auto& cascade : cascades) {
        EXPECT_LT(cascade.texel, scene_texel);
        EXPECT_GT(cascade.texel, coarser_than);
        coarser_than = cascade.texel;
        const float bound = std::exp2(0.25f) * (1.0f + 4.0f / kMapSize) * 2.0f * cascade.depth * slant / kMapSize;
        EXPECT_LE(cascade.texel, bound * 1.0001f) << "depth " << cascade.depth;
    }
    // Here: 0.082, 0.23 and 0.46 m to depths 48, 143 and 429 m, where the scene's map has 0.55 m.
}

// The fit scales with the scene: at 1e-3 and 1e4 times the street, each cascade's texel and depth are
// the street's times the scale, to float precision.
TEST(ShadowCascades, ScaleWithTheScene) {
    const Street street;
    const auto at_one =
        ShadowMaps::fit_view_cascades(street.bounds, street.sun, street.camera, kWidth, kHeight, kMapSize, kCascades);
    for (const float scale : {1e-3f, 1e4f}) {
        const scene::Aabb bounds{street.bounds.min * scale, street.bounds.max * scale};
        scene::Camera camera = street.camera;
        camera.position *= scale;
        const auto scaled =
            ShadowMaps::fit_view_cascades(bounds, street.sun, camera, kWidth, kHeight, kMapSize, kCascades);
        ASSERT_EQ(scaled.size(), at_one.size()) << "scale " << scale;
        for (std::size_t k = 0; k < scaled.size(); ++k) {
            EXPECT_NEAR(scaled[k].texel / (at_one[k].texel * scale), 1.0f, 1e-4f) << "scale " << scale;
            EXPECT_NEAR(scaled[k].depth / (at_one[k].depth * scale), 1.0f, 1e-4f) << "scale " << scale;
        }
    }
}

// None asked, none made; an empty scene has nothing to shadow.
TEST(ShadowCascades, NoneWhereNoneAreAskedOrTheSceneIsEmpty) {
    const Street street;
    const auto fit = [&](const scene::Aabb& bounds, int cascades) {
        return ShadowMaps::fit_view_cascades(bounds, street.sun, street.camera, kWidth, kHeight, kMapSize, cascades);
    };
    EXPECT_TRUE(fit(street.bounds, 0).empty());
    EXPECT_TRUE(fit({}, kCascades).empty());
}

}  // namespace
}  // namespace bounce::test
