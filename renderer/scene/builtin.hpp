// Scenes built into the daemon, so it serves frames with no files at all.
#pragma once

#include "renderer/scene/scene.hpp"

#include <string>
#include <vector>

namespace bounce::scene {

// The Cornell box: the published measured geometry (converted from millimetres to metres),
// its RGB reflectances, its camera, the two blocks as movable objects and a point light just
// below the ceiling.
Scene make_cornell_box();

// The Cornell box with its tall block replaced by an organic shape: a smoothly lobed, subdivided
// icosphere (5120 triangles, no UVs) standing where the block stood. A curved mesh that atlas
// charting and the cube-map bake must handle without a parametrization.
Scene make_cornell_blob();

// Appends `primitive` (its bounds set) as a mesh of its own and an object of that name placed by
// `transform`; returns the object's index.
int add_primitive_object(Scene& scene, const std::string& name, Primitive primitive,
                         const glm::mat4& transform = glm::mat4(1.0f));

// Appends an axis-aligned box [lo, hi] (metres, faces outward) as a movable object whose origin is
// its centre; returns the object's index.
int add_box(Scene& scene, const std::string& name, const glm::vec3& lo, const glm::vec3& hi, int material);

// Names of the built-in scenes ("cornell", "cornell_blob").
std::vector<std::string> builtin_scene_names();
// Throws InputError for an unknown name.
Scene make_builtin_scene(const std::string& name);

}  // namespace bounce::scene
