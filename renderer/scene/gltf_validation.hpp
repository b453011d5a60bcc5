// The glTF importer's checks before tinygltf sees a document, and the callbacks it loads with.
//
// tinygltf silently ignores much that is malformed, so the GLB container, the JSON's shape against
// the schema (property types, bufferView ranges) and the required extensions are checked first; an
// upload's URIs must all be data: URIs. While tinygltf loads, images decode without failing the load
// (an image that is too large or undecodable is recorded in the LoadContext) and file access is
// either plain reads next to the file or, for an upload, refused and recorded.
#pragma once

#include "renderer/scene/gltf_detail.hpp"

#include <tiny_gltf.h>

#include <cstdint>
#include <span>
#include <string_view>

namespace bounce::scene::gltf {

bool has_glb_magic(std::span<const std::uint8_t> bytes);

// The JSON chunk of a GLB, with the header and chunk lengths checked.
std::string_view glb_json_chunk(std::span<const std::uint8_t> bytes);

Json parse_json(std::string_view text);

// The property types of the glTF schema that the importer relies on, and every bufferView against
// its buffer's declared length. Malformed extension values only warn.
void check_structure(const Json& root, Warnings& warnings);

// Required extensions must all be supported; unknown optional ones only warn.
void check_extensions(const Json& root, Warnings& warnings);

// An upload must carry all its data: any buffer or image URI other than a data: URI is refused.
void refuse_external_uris(const Json& root);

// Sets `loader`'s image decoder and file access, both recording into `context`; `embedded_only`
// (an upload) refuses every file access.
void install_callbacks(tinygltf::TinyGLTF& loader, LoadContext& context, bool embedded_only);

}  // namespace bounce::scene::gltf
