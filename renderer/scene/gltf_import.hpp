// glTF 2.0 import (.gltf and .glb) through tinygltf.
#pragma once

#include "renderer/scene/scene.hpp"

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

namespace bounce::scene {

// How far from the origin, on any axis, a scene's objects may reach, in metres: an import whose
// objects (as placed) lie farther is refused, and so is an object.set_transform that would take an
// object farther (server/scene_requests.cpp). Within it, the distances, far planes and projections
// a render derives from the scene stay finite in float.
inline constexpr float max_world_coordinate = 1e15f;

// How far from the origin, on any axis, a camera or light may stand: the range camera.set and
// light.set allow (docs/protocol.md, "Numbers"). Views are built looking from a position towards
// the position plus a unit vector, and past 2^24 m a float can no longer tell the two apart (the
// view is NaN), so an import whose cameras or lights stand farther is refused, as is one without a
// camera that is too large for a default camera within this range to frame it.
inline constexpr float max_eye_coordinate = 1e7f;

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
// non-finite positions, numbers past the range of a float, objects past max_world_coordinate,
// cameras or lights past max_eye_coordinate, light colours and intensities outside the ranges
// light.set allows, unsupported required extensions and buffer or image URIs that lead outside
// the file's folder; throws ResourceExhausted (an InputError) naming the largest part when the
// scene is larger than `limits` allow. Unknown optional extensions and missing or undecodable
// textures only add a warning to Scene::warnings (and are logged), and the scene loads with a
// neutral fallback.
Scene import_gltf_file(const std::filesystem::path& path, const ImportLimits& limits = {});

// Loads a binary glTF (.glb) held in memory (an upload). External URIs are refused.
Scene import_glb_memory(std::span<const std::uint8_t> bytes, const std::string& name,
                        const ImportLimits& limits = {});

}  // namespace bounce::scene
