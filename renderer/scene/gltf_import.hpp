// glTF 2.0 import (.gltf and .glb) through tinygltf.
#pragma once

#include "renderer/scene/scene.hpp"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace bounce::scene {

// What one import may cost. The scene's size is counted from the file before anything is decoded:
// every accessor as the importer materializes it (once per primitive that reads it), the normals,
// tangents and indices each primitive gets, and the images materials use at the peak of their
// decoding, conversion to Textures and upload with mipmaps, from what their PNG or JPEG headers
// declare (size, channels, bit depth; gltf_budget.hpp says what is counted).
struct ImportLimits {
    std::uint64_t max_scene_bytes = std::uint64_t{2} << 30;  // 2 GiB
};

// Loads a .gltf or .glb file. Throws InputError with a message that names the fault for broken
// JSON (or JSON nested deeper than 128 levels), missing buffers, out-of-range accessors or indices,
// non-finite positions, unsupported required extensions and buffer or image URIs that lead outside
// the file's folder; throws ResourceExhausted (an InputError) naming the largest part when the
// scene is larger than `limits` allow. Unknown optional extensions and missing or undecodable
// textures only add a warning to Scene::warnings (and are logged), and the scene loads with a
// neutral fallback.
Scene import_gltf_file(const std::filesystem::path& path, const ImportLimits& limits = {});

// Loads a binary glTF (.glb) held in memory (an upload). External URIs are refused.
Scene import_glb_memory(std::span<const std::uint8_t> bytes, const std::string& name,
                        const ImportLimits& limits = {});

}  // namespace bounce::scene
