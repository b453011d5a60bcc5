// glTF 2.0 import (.gltf and .glb) through tinygltf.
#pragma once

#include "renderer/scene/scene.hpp"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace bounce::scene {

// Loads a .gltf or .glb file. Throws InputError with a message that names the fault for broken
// JSON, missing buffers, out-of-range accessors or indices, non-finite positions and unsupported
// required extensions. Unknown optional extensions and missing or undecodable textures only add a
// warning to Scene::warnings (and are logged), and the scene loads with a neutral fallback.
Scene import_gltf_file(const std::filesystem::path& path);

// Loads a binary glTF (.glb) held in memory (an upload). External URIs are refused.
Scene import_glb_memory(std::span<const std::uint8_t> bytes, const std::string& name);

}  // namespace bounce::scene
