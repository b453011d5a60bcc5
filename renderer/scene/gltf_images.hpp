// The images of a glTF model. While tinygltf loads, nothing is decoded: its image callback only reads
// each image's PNG or JPEG header (size, channels, bit depth, what else the decoder's buffers depend
// on). Once the scene's size was checked
// against its budget (gltf_budget.hpp), the images that materials use are decoded, each once.
#pragma once

#include "renderer/scene/gltf_detail.hpp"
#include "renderer/scene/scene.hpp"

#include <tiny_gltf.h>

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace bounce::scene::gltf {

// What a PNG or JPEG header declares (gltf_detail.hpp); nullopt, with the reason in `why`, for
// anything else and for the variants of either that stb_image does not decode.
std::optional<ImageHeader> read_image_header(std::span<const unsigned char> bytes, std::string& why);

// "8-bit RGBA PNG", "3-component progressive JPEG": the header in words, for messages.
std::string describe(const ImageHeader& header);

// tinygltf's image callback: records the image's header in the LoadContext (`user_data`), or why it
// will have no pixels (not a PNG or JPEG stb_image decodes, more than max_image_side pixels per
// side). It decodes nothing and never fails the load.
bool record_image_header(tinygltf::Image* image, int image_index, std::string* err, std::string* warn,
                         int required_width, int required_height, const unsigned char* bytes, int size,
                         void* user_data);

// For each image, how the textures of materials that the converter reads use it: a mask of
// used_as_srgb (base colour, emissive) and used_as_linear (metallic-roughness, normal); 0 when
// unused. The converter makes one Texture per image and colour space.
inline constexpr unsigned used_as_srgb = 1;
inline constexpr unsigned used_as_linear = 2;
std::vector<unsigned> texture_uses(const tinygltf::Model& model);

// The sampler `index` of the model (-1: none, the defaults) as a TextureSampler. Throws InputError
// naming `where` for an index out of range or a filter or wrap value glTF does not define.
TextureSampler texture_sampler(const tinygltf::Model& model, int index, const std::string& where);

// Decodes each image that a material uses and whose header was recorded, reading its bytes again
// from its bufferView, data: URI or file (`document` holds the URIs). An image whose header is no
// longer the one recorded (a file changed), that cannot be decoded, or that decodes to another size
// than its header declared, is left without pixels and recorded in context.image_failures.
void decode_images(tinygltf::Model& model, const Json& document, LoadContext& context);

}  // namespace bounce::scene::gltf
