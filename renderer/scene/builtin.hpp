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

// Names of the built-in scenes ("cornell").
std::vector<std::string> builtin_scene_names();
// Throws InputError for an unknown name.
Scene make_builtin_scene(const std::string& name);

}  // namespace bounce::scene
