#include "renderer/base/error.hpp"
#include "renderer/scene/builtin.hpp"
#include "renderer/scene/mesh_utils.hpp"
#include "renderer/scene/scene.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace bounce::scene {
namespace {

// Triangles picked by world area: a 1 m^2 triangle holds the first quarter of [0, 1), one of 3 m^2
// (0.5 m^2 in its mesh, scaled by its object's transform) the rest; one of zero area none of it.
TEST(AreaWeightedTriangles, PickInProportionToWorldArea) {
    Scene scene;
    const auto triangle = [](float leg) {
        Primitive p;
        p.positions = {{0, 0, 0}, {leg, 0, 0}, {0, leg, 0}};
        p.indices = {0, 1, 2};
        return p;
    };
    Primitive degenerate = triangle(1.0f);
    degenerate.positions[2] = {2.0f, 0.0f, 0.0f};
    add_primitive_object(scene, "one", triangle(std::sqrt(2.0f)));
    add_primitive_object(scene, "flat", degenerate);
    add_primitive_object(scene, "three", triangle(1.0f), glm::scale(glm::mat4(1.0f), glm::vec3(std::sqrt(6.0f), std::sqrt(6.0f), 1.0f)));
    const AreaWeightedTriangles picker(scene);
    ASSERT_FALSE(picker.empty());
    EXPECT_EQ(picker.pick(0.0).object, 0u);
    EXPECT_EQ(picker.pick(0.24).object, 0u);
    EXPECT_EQ(picker.pick(0.26).object, 2u);
    EXPECT_EQ(picker.pick(0.999999).object, 2u);
    EXPECT_TRUE(AreaWeightedTriangles(Scene{}).empty());
}

TEST(Aabb, TransformedHoldsAllCorners) {
    Aabb box;
    box.extend({-1, -1, -1});
    box.extend({1, 1, 1});
    const Aabb rotated = box.transformed(glm::rotate(glm::mat4(1.0f), glm::radians(45.0f), glm::vec3(0, 1, 0)));
    EXPECT_NEAR(rotated.max.x, std::sqrt(2.0f), 1e-5f);
    EXPECT_NEAR(rotated.max.y, 1.0f, 1e-5f);
    EXPECT_TRUE(Aabb().empty());
    EXPECT_TRUE(Aabb().transformed(glm::mat4(1.0f)).empty());
}

TEST(Camera, LookAtFacesTheTarget) {
    const Camera camera = Camera::look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 0.8f);
    EXPECT_NEAR(camera.forward().z, -1.0f, 1e-6f);
    EXPECT_NEAR(camera.up().y, 1.0f, 1e-6f);
    const glm::vec4 target_in_view = camera.view() * glm::vec4(0, 0, 0, 1);
    EXPECT_NEAR(target_in_view.z, -5.0f, 1e-5f);
    Aabb bounds;
    bounds.extend({-1, -1, -1});
    bounds.extend({1, 1, 1});
    EXPECT_GT(camera.far_plane_for(bounds), glm::length(glm::vec3(1, 1, 6)));
}

TEST(Scene, LookupsAndDefaults) {
    Scene scene;
    scene.objects.push_back({"a", -1});
    scene.objects.push_back({"b", -1});
    EXPECT_EQ(scene.find_object("b"), 1u);
    EXPECT_FALSE(scene.find_object("c").has_value());
    EXPECT_EQ(&scene.material(-1), &Scene::default_material());
    EXPECT_EQ(&scene.material(3), &Scene::default_material());
    EXPECT_FALSE(Scene::default_material().glossy());
}

TEST(Scene, ValidateFiniteNamesTheFault) {
    Scene scene;
    Mesh mesh;
    mesh.name = "m";
    Primitive primitive;
    primitive.positions = {{0, 0, 0}, {1, 0, 0}, {0, std::numeric_limits<float>::quiet_NaN(), 0}};
    mesh.primitives.push_back(primitive);
    scene.meshes.push_back(mesh);
    try {
        validate_finite(scene);
        FAIL() << "a NaN position must be rejected";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("vertex 2 has a non-finite position"), std::string::npos)
            << error.what();
    }
    scene.meshes.clear();
    Light light;
    light.name = "bad";
    light.intensity = std::numeric_limits<float>::infinity();
    scene.lights.push_back(light);
    EXPECT_THROW(validate_finite(scene), InputError);
}

}  // namespace
}  // namespace bounce::scene
