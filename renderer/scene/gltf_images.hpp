// The images of a glTF model. While tinygltf loads, nothing is decoded: its image callback only reads
// each image's width and height from its PNG or JPEG header. Once the scene's size was checked
// against its budget (gltf_budget.hpp), the images that materials use are decoded, each once.
#pragma once

#include "renderer/scene/gltf_detail.hpp"

#include <tiny_gltf.h>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace bounce::scene::gltf {

// Width and height from a PNG or JPEG header; nullopt for anything else.
std::optional<ImageHeader> peek_image_size(const unsigned char* bytes, std::size_t size);

// tinygltf's image callback: records the image's header in the LoadContext (`user_data`), or why it
// will have no pixels (not a PNG or JPEG, more than max_image_side pixels per side). It decodes
// nothing and never fails the load.
bool record_image_header(tinygltf::Image* image, int image_index, std::string* err, std::string* warn,
                         int required_width, int required_height, const unsigned char* bytes, int size,
                         void* user_data);

// For each image, whether a material's texture that the converter reads uses it.
std::vector<bool> images_in_use(const tinygltf::Model& model);

// Decodes each image that a material uses and whose header was recorded, reading its bytes again
// from its bufferView, data: URI or file (`document` holds the URIs). An image that cannot be decoded,
// or decodes to another size than its header declared, is left without pixels and recorded in
// context.image_failures.
void decode_images(tinygltf::Model& model, const Json& document, LoadContext& context);

}  // namespace bounce::scene::gltf
