// The size of a glTF scene, counted from the loaded model before any accessor is read or any image
// decoded, so that a file of a few hundred bytes cannot ask for gigabytes.
#pragma once

#include "renderer/scene/gltf_detail.hpp"

#include <tiny_gltf.h>

#include <cstdint>

namespace bounce::scene::gltf {

// Sums what importing `model` will allocate:
//  - each accessor a primitive reads, as the converter stores it (POSITION and NORMAL as 12-byte
//    vectors, TANGENT 16, TEXCOORD_0 and _1 8, indices 4 bytes), once per primitive that reads it,
//    whether or not it has a bufferView;
//  - each primitive's normals and tangents (made for every vertex), its index list when the file
//    has none, and the triangle lists that strips and fans become;
//  - each image a material uses (images_in_use), from its header (context.image_headers):
//    width x height x 4 bytes, and a third more for its mipmaps.
// Throws ResourceExhausted naming the total and its largest part when the sum is past
// `max_scene_bytes`.
void check_scene_size(const tinygltf::Model& model, const LoadContext& context,
                      std::uint64_t max_scene_bytes);

}  // namespace bounce::scene::gltf
