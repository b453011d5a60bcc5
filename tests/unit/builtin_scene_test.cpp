// The built-in Cornell box carries the published data.
#include "renderer/base/error.hpp"
#include "renderer/scene/builtin.hpp"

#include <gtest/gtest.h>

#include <map>

#include <cmath>

namespace bounce::scene {
namespace {

TEST(CornellBox, PublishedGeometryInMetres) {
    const Scene scene = make_cornell_box();
    EXPECT_EQ(scene.name, "cornell");
    const Aabb bounds = scene.world_bounds();
    EXPECT_NEAR(bounds.min.x, 0.0f, 1e-6f);
    EXPECT_NEAR(bounds.max.x, 0.556f, 1e-6f);
    EXPECT_NEAR(bounds.max.y, 0.5488f, 1e-6f);
    EXPECT_NEAR(bounds.max.z, 0.5592f, 1e-6f);
    // 5 walls + 5 faces per block, two triangles each.
    EXPECT_EQ(scene.triangle_count(), 30u);
    ASSERT_TRUE(scene.find_object("short_block").has_value());
    ASSERT_TRUE(scene.find_object("tall_block").has_value());
    const Object& tall = scene.objects[*scene.find_object("tall_block")];
    const Aabb tall_bounds = tall.world_bounds(scene.meshes[tall.mesh]);
    EXPECT_NEAR(tall_bounds.max.y, 0.330f, 1e-6f);
    EXPECT_NEAR(tall_bounds.min.x, 0.265f, 1e-6f);
    EXPECT_NEAR(tall_bounds.max.x, 0.472f, 1e-6f);
}

TEST(CornellBox, PublishedReflectancesAndMatteSurfaces) {
    const Scene scene = make_cornell_box();
    ASSERT_EQ(scene.materials.size(), 3u);
    EXPECT_EQ(glm::vec3(scene.materials[0].base_color), glm::vec3(0.725f, 0.71f, 0.68f));
    EXPECT_EQ(glm::vec3(scene.materials[1].base_color), glm::vec3(0.63f, 0.065f, 0.05f));
    EXPECT_EQ(glm::vec3(scene.materials[2].base_color), glm::vec3(0.14f, 0.45f, 0.091f));
    EXPECT_FALSE(scene.has_glossy_material());
}

TEST(CornellBox, NormalsFaceIntoTheRoomAndOutOfTheBlocks) {
    const Scene scene = make_cornell_box();
    const glm::vec3 room_centre{0.278f, 0.2744f, 0.2796f};
    for (const Object& object : scene.objects) {
        for (const Primitive& primitive : scene.meshes[object.mesh].primitives) {
            for (std::size_t t = 0; t < primitive.indices.size(); t += 3) {
                const glm::vec3 a = glm::vec3(object.transform * glm::vec4(primitive.positions[primitive.indices[t]], 1));
                const glm::vec3 b = glm::vec3(object.transform * glm::vec4(primitive.positions[primitive.indices[t + 1]], 1));
                const glm::vec3 c = glm::vec3(object.transform * glm::vec4(primitive.positions[primitive.indices[t + 2]], 1));
                const glm::vec3 geometric = glm::normalize(glm::cross(b - a, c - a));
                EXPECT_GT(glm::dot(geometric, primitive.normals[primitive.indices[t]]), 0.99f) << object.name;
                if (object.name == "room") {
                    EXPECT_GT(glm::dot(geometric, room_centre - a), 0.0f) << "wall faces out of the room";
                } else {
                    const glm::vec3 block_centre = glm::vec3(object.transform[3]) + glm::vec3(0, 0.08f, 0);
                    EXPECT_GT(glm::dot(geometric, (a + b + c) / 3.0f - block_centre), 0.0f) << object.name;
                }
            }
        }
    }
}

TEST(CornellBox, PublishedCamera) {
    const Scene scene = make_cornell_box();
    ASSERT_EQ(scene.cameras.size(), 1u);
    const Camera& camera = scene.cameras[0];
    EXPECT_NEAR(camera.position.x, 0.278f, 1e-6f);
    EXPECT_NEAR(camera.position.z, -0.8f, 1e-6f);
    EXPECT_NEAR(camera.forward().z, 1.0f, 1e-6f);
    EXPECT_NEAR(camera.vertical_fov, 2.0f * std::atan(12.5f / 35.0f), 1e-6f);  // 35 mm lens, 25 mm film
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_LT(scene.lights[0].position.y, 0.5488f);
}

TEST(BuiltinScenes, UnknownNameIsAnInputError) {
    EXPECT_THROW(make_builtin_scene("sponza"), InputError);
    EXPECT_EQ(make_builtin_scene("cornell").name, "cornell");
}

}  // namespace
}  // namespace bounce::scene

namespace bounce::scene {
namespace {

TEST(BuiltinScene, TheBlobIsAClosedOutwardFacingMeshStandingOnTheFloor) {
    const Scene scene = make_builtin_scene("cornell_blob");
    const auto index = scene.find_object("blob");
    ASSERT_TRUE(index.has_value());
    EXPECT_FALSE(scene.find_object("tall_block").has_value());
    const Object& blob = scene.objects[*index];
    const Primitive& p = scene.meshes[blob.mesh].primitives[0];
    EXPECT_EQ(p.triangle_count(), 5120u);
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
    glm::vec3 centre(0.0f);
    for (const glm::vec3& v : p.positions) centre += v / static_cast<float>(p.positions.size());
    double signed_volume = 0.0;
    for (std::size_t t = 0; t < p.triangle_count(); ++t) {
        const std::uint32_t a = p.indices[3 * t], b = p.indices[3 * t + 1], c = p.indices[3 * t + 2];
        for (auto [u, v] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}}) ++edges[{std::min(u, v), std::max(u, v)}];
        signed_volume += glm::dot(p.positions[a] - centre, glm::cross(p.positions[b] - centre, p.positions[c] - centre)) / 6.0;
    }
    for (const auto& [edge, count] : edges) ASSERT_EQ(count, 2) << "an open or non-manifold edge";
    EXPECT_GT(signed_volume, 0.0) << "triangles wound inwards";
    const Aabb world = blob.world_bounds(scene.meshes[blob.mesh]);
    EXPECT_NEAR(world.min.y, 0.0f, 1e-5f);
}

}  // namespace
}  // namespace bounce::scene
