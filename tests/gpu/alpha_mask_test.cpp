// glTF alphaMode MASK: where base-colour alpha is below the cutoff the surface is not there, for
// the camera (G-buffer), for the lights (shadow maps) and for rays (the reference's and cssm's
// bake's any-hit test). A masked blocker whose texture cuts away its right half must render as a
// blocker that is only its left half; and rays pass where it is cut. The frames are compared away
// from the cut's edge (two pixels either side, where coverage and bilinear alpha differ); 1e-4
// relative is float rounding (the same surfaces under the same lights).
#include "gpu_fixture.hpp"
#include "renderer/raytrace/ray_scene.hpp"

#include <gtest/gtest.h>

namespace bounce::test {
namespace {

constexpr int kSize = 48;

// A floor at y = 0 under a sun straight down, and a blocker at y = 1 over [-0.6, 0.6]^2: masked
// (a 4x1 texture, alpha 1 1 0 0: kept where u < 0.5) or only that half as geometry.
scene::Scene blocked_floor(bool masked) {
    scene::Scene scene;
    scene.materials.push_back(matte(glm::vec3(0.6f)));
    scene::Material blocker = matte(glm::vec3(0.2f, 0.3f, 0.8f));
    if (masked) {
        scene::Texture texture;
        texture.width = 4;
        texture.height = 1;
        texture.rgba8 = {255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 255, 0, 255, 255, 255, 0};
        scene.textures.push_back(texture);
        blocker.base_color_texture.texture = 0;
        blocker.alpha_cutoff = 0.5f;
    }
    scene.materials.push_back(blocker);
    add_square(scene, "floor", glm::vec3(0.0f), 2.0f, {0, 1, 0}, 0);
    add_square(scene, "blocker", glm::vec3(0.0f, 1.0f, 0.0f), 0.6f, {0, 1, 0}, 1);
    if (!masked) {
        // Keep u < 0.5 as geometry: the vertices at u = 1 move halfway back along the u edge.
        auto& primitive = scene.meshes[1].primitives[0];
        const glm::vec3 u_edge = primitive.positions[1] - primitive.positions[0];  // uv (0,0) to (1,0)
        for (std::size_t i = 0; i < primitive.positions.size(); ++i) {
            if (primitive.uv0[i].x > 0.5f) primitive.positions[i] -= 0.5f * u_edge;
        }
        primitive.bounds = {};
        for (const auto& p : primitive.positions) primitive.bounds.extend(p);
        scene.meshes[1].bounds = primitive.bounds;
    }
    scene::Light sun;
    sun.type = scene::LightType::directional;
    sun.direction = {0.0f, -1.0f, 0.0f};
    sun.intensity = 2.0f;
    scene.lights.push_back(sun);
    return scene;
}

// The blocker's texture u direction in the world (unit), from its first edge.
glm::vec3 u_direction(const scene::Scene& scene) {
    const auto& p = scene.meshes[1].primitives[0].positions;
    return glm::normalize(p[1] - p[0]);
}

TEST(AlphaMask, ACutAwaySurfaceIsNotSeenAndCastsNoShadow) {
    const scene::Scene masked = blocked_floor(true), half = blocked_floor(false);
    const glm::vec3 u = u_direction(masked), across = glm::cross(glm::vec3(0, 1, 0), u);
    RenderRequest request;
    request.width = request.height = kSize;
    request.camera = top_down_camera(3.0f, 1.0f);
    const auto a = render_scene(masked, request), b = render_scene(half, request);
    int compared = 0, lit_through_the_cut = 0;
    for (int y = 0; y < kSize; ++y) {
        for (int x = 0; x < kSize; ++x) {
            // The cut runs through the centre across u; it projects onto the floor's centre line.
            const glm::vec3 ground = pixel_on_ground(*request.camera, kSize, kSize, x, y);
            if (std::abs(glm::dot(ground, u)) < 0.2f) continue;  // three pixels either side of the cut
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(a.frame.at(x, y)[c], b.frame.at(x, y)[c], 1e-4f * std::max(1.0f, b.frame.at(x, y)[c]))
                    << x << "," << y;
            }
            ++compared;
            // Through the cut half the sunlit floor shows: albedo 0.6 / pi * 2.
            if (glm::dot(ground, u) > 0.3f && glm::dot(ground, u) < 0.8f && std::abs(glm::dot(ground, across)) < 0.5f) {
                lit_through_the_cut += std::abs(a.frame.at(x, y).g - 0.6f / 3.14159265f * 2.0f) < 1e-3f;
            }
        }
    }
    EXPECT_GT(compared, kSize * kSize / 2);
    EXPECT_GT(lit_through_the_cut, 20);
}

TEST(AlphaMask, RaysPassWhereTheSurfaceIsCutAway) {
    scene::Scene scene = blocked_floor(true);
    const raytrace::RayScene rays(scene);
    const glm::vec3 down(0.0f, -1.0f, 0.0f), u = u_direction(scene);
    const glm::vec3 kept = -0.3f * u, cut = 0.3f * u;  // u = 0.25 and 0.75 on the blocker
    const auto through_kept = rays.intersect(kept + glm::vec3(0, 2, 0), down, 0.0f, 10.0f);
    const auto through_cut = rays.intersect(cut + glm::vec3(0, 2, 0), down, 0.0f, 10.0f);
    ASSERT_TRUE(through_kept && through_cut);
    EXPECT_EQ(through_kept->object, 1u);  // the blocker
    EXPECT_EQ(through_cut->object, 0u);   // the floor, seen through the cut
    EXPECT_TRUE(rays.occluded(kept + glm::vec3(0, 0.01f, 0), -down, 0.0f, 10.0f));
    EXPECT_FALSE(rays.occluded(cut + glm::vec3(0, 0.01f, 0), -down, 0.0f, 10.0f));
}

}  // namespace
}  // namespace bounce::test
