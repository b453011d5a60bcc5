// The conversion from a loaded tinygltf model to the scene model. Internal to the importer.
#pragma once

#include "renderer/scene/gltf_detail.hpp"
#include "renderer/scene/gltf_import.hpp"
#include "renderer/scene/scene.hpp"

#include <tiny_gltf.h>

#include <string>

namespace bounce::scene::gltf {

// The scene `model` describes, its accessors already checked (check_accessor_bounds) and its images
// decoded (decode_images): materials and textures, meshes (normals and tangents generated where the
// file has none or unusable ones), the node hierarchy flattened into objects, lights and cameras,
// and a default camera when there is none. Faults throw InputError; what falls back adds to
// `warnings`.
Scene convert_model(const tinygltf::Model& model, const LoadContext& context, Warnings& warnings,
                    std::string name);

// Every object's world bounds within max_world_coordinate of the origin on each axis, every camera
// and light within max_eye_coordinate (gltf_import.hpp); throws InputError naming the first that
// is not.
void check_world_extent(const Scene& scene);

}  // namespace bounce::scene::gltf
