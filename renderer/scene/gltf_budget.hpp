// The size of a glTF scene, counted from the loaded model before any accessor is read or any image
// decoded, so that a file of a few hundred bytes cannot ask for gigabytes.
#pragma once

#include "renderer/scene/gltf_detail.hpp"

#include <tiny_gltf.h>

#include <cstdint>

namespace bounce::scene::gltf {

// Sums what loading `model` will allocate at its peak:
//  - each accessor a primitive reads, as the converter stores it (POSITION and NORMAL as 12-byte
//    vectors, TANGENT 16, TEXCOORD_0 and _1 8, indices 4 bytes), once per primitive that reads it,
//    whether or not it has a bufferView;
//  - each primitive's normals and tangents (made for every vertex), its index list when the file
//    has none, and the triangle lists that strips and fans become;
//  - the images that materials use (texture_uses), from their headers (context.image_headers),
//    at the peak of three phases that follow one another:
//      decoding:   every image decoded, as tinygltf keeps it until the conversion ends (stb_image
//                  expands every image to 4 channels of its bit depth: 4 or 8 bytes a pixel), and
//                  for the image whose decoding needs the most, the decoder's buffers at their
//                  peak (image_bytes in gltf_budget.cpp: a PNG's inflated rows and its image at the
//                  file's channels and bit depth, or a JPEG's planes; the result while it is copied;
//                  the bytes read again from a URI);
//      converting: the decoded images and each Texture made from them (4 bytes a pixel, one per
//                  image and colour space it is used in: an image used as base colour and as
//                  metallic-roughness makes two);
//      uploading:  the Textures, which the scene keeps, and their GL textures with full mip
//                  chains (4 bytes a texel), which the registry makes as soon as the scene loads;
//                  tinygltf's decoded images are gone by then.
//    The geometry above is held through all three. The budget bounds memory, host and GPU (one
//    and the same with llvmpipe), which is why the GL copy of a texture counts; the GL copy of the
//    geometry is not counted, nor the file's own bytes and tinygltf's copy of its buffers, which
//    its length bounds. Measured with stb_image 2.27, a decode stays within its count but for
//    those and a few hundred KiB of fixed state.
// A PNG whose image data inflates to more than its rows need (stb_image would grow its buffer to
// hold all of it: up to 4 GiB from a file of a few hundred KB) is not decoded: gltf_images.cpp
// inflates the data into a scratch buffer first and stops past the rows' size.
// Throws ResourceExhausted naming the total and its largest part when the sum is past
// `max_scene_bytes`; an image's part is what it holds in the peak phase.
void check_scene_size(const tinygltf::Model& model, const LoadContext& context,
                      std::uint64_t max_scene_bytes);

}  // namespace bounce::scene::gltf
