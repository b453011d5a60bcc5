// The scenes bench/quality measures: the built-in Cornell box and variants of it that stress what
// the methods approximate (glossy reflection, light that arrives mostly indirectly).
#pragma once

#include "renderer/scene/scene.hpp"

#include <string>
#include <vector>

namespace bounce::bench {

struct BenchScene {
    std::string name;
    std::string description;
    scene::Scene scene;
};

std::vector<BenchScene> quality_scenes();

}  // namespace bounce::bench
