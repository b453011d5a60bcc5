// KHR_texture_transform on the GPU: a transformed texture samples where the transform sends the
// UVs. A plane whose base-colour texture carries a transform must render exactly as the same plane
// with its UVs transformed in the mesh and no transform (the map is affine, so it commutes with
// the rasterizer's interpolation); and it must differ from the untransformed plane, or nothing
// was tested. Tolerance: 1e-4 relative (float rounding of the same sampling coordinates).
#include "gpu_fixture.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/scene/shading.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace bounce::test {
namespace {

// An 8x8 texture of coloured cells, so that any shift, turn or stretch changes the frame.
scene::Texture cells() {
    scene::Texture texture;
    texture.name = "cells";
    texture.width = texture.height = 8;
    for (int y = 0; y < 8; ++y) {
        for (int x = 0; x < 8; ++x) {
            texture.rgba8.insert(texture.rgba8.end(), {static_cast<std::uint8_t>(32 * x), static_cast<std::uint8_t>(32 * y),
                                                       static_cast<std::uint8_t>((x + y) % 2 ? 255 : 40), 255});
        }
    }
    return texture;
}

glm::mat3 a_transform() {
    const float c = std::cos(0.5f), s = std::sin(0.5f);
    return glm::mat3(1, 0, 0, 0, 1, 0, 0.1f, 0.3f, 1) * glm::mat3(c, s, 0, -s, c, 0, 0, 0, 1) *
           glm::mat3(2.0f, 0, 0, 0, 1.5f, 0, 0, 0, 1);
}

scene::Scene textured_plane(const glm::mat3& transform, bool transform_the_mesh) {
    scene::Scene scene;
    scene::Material material = matte(glm::vec3(1.0f));
    material.base_color_texture.texture = 0;
    if (!transform_the_mesh) material.base_color_texture.uv_transform = transform;
    scene.materials.push_back(material);
    scene.textures.push_back(cells());
    add_square(scene, "floor", glm::vec3(0.0f), 1.0f, {0, 1, 0}, 0);
    if (transform_the_mesh) {
        for (glm::vec2& uv : scene.meshes[0].primitives[0].uv0) uv = glm::vec2(transform * glm::vec3(uv, 1.0f));
    }
    scene.lights.push_back(directional_light({0.0f, -1.0f, 0.0f}, 3.0f));
    return scene;
}

TEST(TextureTransform, SamplesWhereTheTransformSendsTheUvs) {
    RenderRequest request;
    request.width = request.height = 48;
    request.camera = top_down_camera(2.0f, 1.0f);
    const auto transformed = render_scene(textured_plane(a_transform(), false), request);
    const auto baked = render_scene(textured_plane(a_transform(), true), request);
    const auto plain = render_scene(textured_plane(glm::mat3(1.0f), false), request);
    const auto& a = transformed.frame.rgba;
    const auto& b = baked.frame.rgba;
    ASSERT_EQ(a.size(), b.size());
    // The same UVs reach the sampler by two float paths that may differ in their last bits. A texture
    // unit filters with fixed-point weights (8 bits of sub-texel position per axis on current GPUs,
    // as Direct3D 11 requires; llvmpipe filters in float), so such a difference can move each
    // axis's weight by one 2^-8 step: the sample by at most 2 * 2^-8 of the largest texel value,
    // which is at most the brightest pixel here (radiance is linear in the texel). Beyond that,
    // float rounding (1e-4 relative).
    float brightest = 0.0f;
    for (std::size_t i = 0; i < b.size(); ++i) brightest = i % 4 == 3 ? brightest : std::max(brightest, b[i]);
    const float filtering = 2.0f * std::ldexp(brightest, -8);
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], filtering + 1e-4f * std::max(1.0f, b[i])) << i;
    EXPECT_GT(image::compare(transformed.frame, plain.frame).rel_mse, 0.01);
}

// The CPU twin (the reference's and cssm's bake's material lookups) applies the same transform.
TEST(TextureTransform, TheCpuTwinAppliesIt) {
    const scene::Scene scene = textured_plane(a_transform(), false);
    const glm::vec2 uv(0.2f, 0.7f);
    const auto at = scene::textured_material(scene, scene.materials[0], uv, uv);
    const glm::vec2 moved = glm::vec2(a_transform() * glm::vec3(uv, 1.0f));
    const glm::vec4 expected = scene::sample_texture(scene.textures[0], moved);
    EXPECT_NEAR(at.surface.base_color.r, expected.r, 1e-6f);
    EXPECT_NEAR(at.surface.base_color.g, expected.g, 1e-6f);
    EXPECT_NEAR(at.surface.base_color.b, expected.b, 1e-6f);
}

}  // namespace
}  // namespace bounce::test
