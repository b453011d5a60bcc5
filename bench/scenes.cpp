#include "bench/scenes.hpp"

#include "renderer/scene/builtin.hpp"

namespace bounce::bench {

std::vector<BenchScene> quality_scenes() {
    std::vector<BenchScene> scenes;
    scenes.push_back({"cornell", "the built-in Cornell box", scene::make_cornell_box()});

    scene::Scene glossy = scene::make_cornell_box();
    glossy.name = "cornell_glossy";
    // The white surfaces become a glossy dielectric (floor, ceiling, back wall and both blocks).
    glossy.materials[0].roughness = 0.3f;
    glossy.materials[0].specular = 1.0f;
    scenes.push_back({"cornell_glossy", "Cornell box with glossy white surfaces (roughness 0.3)", std::move(glossy)});

    scene::Scene indirect = scene::make_cornell_box();
    indirect.name = "cornell_indirect";
    // A spot aimed at the ceiling: everything but the ceiling is lit indirectly.
    scene::Light& light = indirect.lights[0];
    light.type = scene::LightType::spot;
    light.position.y = 0.30f;
    light.direction = {0.0f, 1.0f, 0.0f};
    light.inner_cone = 0.6f;
    light.outer_cone = 0.8f;
    light.intensity = 2.0f;
    scenes.push_back({"cornell_indirect", "a spot aimed at the ceiling: the room is lit indirectly", std::move(indirect)});
    return scenes;
}

}  // namespace bounce::bench
