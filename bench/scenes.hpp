// The scenes bench/quality measures: the built-in Cornell box and variants of it that stress what
// the methods approximate (glossy reflection, light that arrives mostly indirectly), or a
// deployment's own glTF files.
#pragma once

#include "renderer/scene/scene.hpp"

#include <cstdint>
#include <filesystem>
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

// Each file as a bench scene named by its stem (its own camera, or the importer's default view; the
// importer logs what it fell back on), with its file_hash. Two files of one stem would share their
// rows in a table: refused (std::runtime_error naming both).
std::vector<BenchScene> gltf_scenes(const std::vector<std::filesystem::path>& files);

}  // namespace bounce::bench
