// The material extensions' own objects, read from tinygltf's generic values: KHR_materials_specular
// (factors and textures), KHR_materials_ior, KHR_texture_transform, and the textureInfo objects
// extensions carry. Every member is checked; a malformed one refuses the file (gltf_detail.hpp's
// reject), as the Khronos validator reports it as an error. Part of the glTF importer.
#pragma once

#include "renderer/scene/scene.hpp"

#include <tiny_gltf.h>

#include <functional>
#include <optional>
#include <string>

namespace bounce::scene::gltf {

// An extension's value when it is an object, else null.
const tinygltf::Value* extension_object(const tinygltf::ExtensionMap& extensions, const std::string& name);
// A member's number, when it has one.
std::optional<double> number_member(const tinygltf::Value& object, const std::string& key);
// A number of the document as the float the scene keeps. One past the float range is refused:
// converting it is undefined behaviour, and an infinity would reach the renderer.
float as_float(double value, const std::string& what);

// KHR_texture_transform's matrix, translation(offset) * rotation * scale, as its specification
// composes it; its texCoord, when given, replaces `tex_coord`.
glm::mat3 texture_transform(const tinygltf::Value& value, const std::string& where, int& tex_coord);
// An extension's textureInfo object (index, texCoord, extensions) in tinygltf's form.
tinygltf::TextureInfo texture_info(const tinygltf::Value& value, const std::string& where);

// KHR_materials_specular and KHR_materials_ior of one material into `material`; textures are made
// through `texture_ref` (the importer's, which shares images between materials).
using TextureRefMaker = std::function<TextureRef(const tinygltf::TextureInfo&, bool srgb, const std::string& where)>;
void read_specular_extensions(const tinygltf::ExtensionMap& extensions, Material& material, const std::string& where,
                              const TextureRefMaker& texture_ref);

}  // namespace bounce::scene::gltf
