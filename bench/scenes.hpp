// The scenes bench/quality measures: the built-in Cornell box and variants of it that stress what
// the methods approximate (glossy reflection, light that arrives mostly indirectly).
#pragma once

#include "renderer/scene/scene.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace bounce::bench {

struct BenchScene {
    std::string name;
    std::string description;
    scene::Scene scene;
    // A scene read from a file: a hash of its bytes and of the geometry and textures it imported, in
    // the reference cache's key (an edited mesh changes no light, material, transform or camera the
    // key otherwise hashes).
    std::uint64_t file_hash = 0;
};

std::vector<BenchScene> quality_scenes();

}  // namespace bounce::bench
