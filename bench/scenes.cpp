#include "bench/scenes.hpp"

#include "renderer/base/hash.hpp"
#include "renderer/scene/builtin.hpp"
#include "renderer/scene/gltf_import.hpp"

#include <fmt/format.h>

#include <fstream>
#include <iterator>
#include <span>
#include <stdexcept>

namespace bounce::bench {
namespace {

// What a scene read from a file renders from: its file's bytes, and the geometry and textures it
// imported (a .gltf's buffers and images may be files of their own).
std::uint64_t imported_content_hash(const std::string& file_bytes, const scene::Scene& scene) {
    Hasher hash;
    hash.add(hash_bytes(file_bytes.data(), file_bytes.size()));
    for (const auto& mesh : scene.meshes) {
        for (const auto& primitive : mesh.primitives) {
            hash.add_span<glm::vec3>(primitive.positions);
            hash.add_span<std::uint32_t>(primitive.indices);
            hash.add_span<glm::vec2>(primitive.uv0);
            hash.add(primitive.material);
        }
    }
    for (const auto& texture : scene.textures) hash.add_span<std::uint8_t>(texture.rgba8);
    return hash.value();
}

}  // namespace

std::vector<BenchScene> gltf_scenes(const std::vector<std::filesystem::path>& files) {
    std::vector<BenchScene> scenes;
    for (const std::filesystem::path& file : files) {
        const std::string name = file.stem().string();
        for (const auto& other : scenes) {
            if (other.name == name) {
                throw std::runtime_error(fmt::format("--gltf {} and {}: two scenes named '{}' (rename one)",
                                                     other.description, file.string(), name));
            }
        }
        std::ifstream in(file, std::ios::binary);
        const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
        scene::Scene scene = scene::import_gltf_file(file);
        const std::uint64_t hash = imported_content_hash(bytes, scene);
        scenes.push_back({name, file.string(), std::move(scene), hash});
    }
    return scenes;
}

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

    // A sealed slab 2 cm thick across the whole box, 7 cm under the light (above both blocks): nothing below it is lit,
    // so any radiance there is light leaking through a thin wall (exactly zero in the reference).
    scene::Scene thin = scene::make_cornell_box();
    thin.name = "thin_wall";
    scene::add_box(thin, "slab", {-0.01f, 0.36f, -0.01f}, {0.57f, 0.38f, 0.57f}, 0);
    scenes.push_back({"thin_wall", "a 2 cm slab seals the light above it: radiance below is leakage", std::move(thin)});

    // A wall 4 cm thick across the box with a doorway; the light is behind it, the camera in front:
    // the front half is lit only through the door, mostly by light that bounced.
    scene::Scene doorway = scene::make_cornell_box();
    doorway.name = "doorway";
    doorway.lights[0].position.z = 0.45f;
    doorway.lights[0].position.y = 0.30f;
    doorway.objects.erase(doorway.objects.begin() + 2);  // the tall block would stand in the wall
    constexpr float z0 = 0.33f, z1 = 0.37f;
    scene::add_box(doorway, "wall_left", {-0.01f, -0.01f, z0}, {0.22f, 0.56f, z1}, 0);
    scene::add_box(doorway, "wall_right", {0.34f, -0.01f, z0}, {0.57f, 0.56f, z1}, 0);
    scene::add_box(doorway, "lintel", {0.22f, 0.36f, z0}, {0.34f, 0.56f, z1}, 0);
    scenes.push_back({"doorway", "light behind a wall with a doorway: the visible room is lit through it", std::move(doorway)});
    return scenes;
}

}  // namespace bounce::bench
