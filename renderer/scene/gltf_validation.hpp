// The glTF importer's checks before tinygltf sees a document, and the callbacks it loads with.
//
// tinygltf silently ignores much that is malformed, so the GLB container, the JSON's nesting depth
// and shape against the schema (property types, bufferView ranges) and the required extensions are
// checked first; an upload's URIs must all be data: URIs, and a file's must stay inside its folder.
// While tinygltf loads, images are not decoded, only their headers read (gltf_images.hpp), and file
// access is either reads inside the glTF file's folder or, for an upload, refused and recorded.
#pragma once

#include "renderer/scene/gltf_detail.hpp"

#include <tiny_gltf.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace bounce::scene::gltf {

bool has_glb_magic(std::span<const std::uint8_t> bytes);

// The JSON chunk of a GLB, with the header and chunk lengths checked.
std::string_view glb_json_chunk(std::span<const std::uint8_t> bytes);

// The document, once its arrays and objects are known to nest no deeper than max_json_depth (the
// raw text is scanned first: the parsers recurse).
Json parse_json(std::string_view text);

// The property types of the glTF schema that the importer relies on, and every bufferView against
// its buffer's declared length. Malformed extension values only warn.
void check_structure(const Json& root, Warnings& warnings);

// Required extensions must all be supported; unknown optional ones only warn.
void check_extensions(const Json& root, Warnings& warnings);

// An upload must carry all its data: any buffer or image URI other than a data: URI is refused.
void refuse_external_uris(const Json& root);

// A file's buffer and image URIs other than data: URIs must be relative paths that stay inside
// `folder` (the glTF file's canonical folder) once percent-decoded as tinygltf decodes them and
// `..` and symlinks are resolved; a '%' escape that is not two hex digits is refused.
void confine_uris(const Json& root, const std::filesystem::path& folder);

// The file an external URI names, read again from context.folder as tinygltf read it; nullopt when
// it is missing, unreadable or outside the folder.
std::optional<std::vector<unsigned char>> read_uri_file(const std::string& uri, const LoadContext& context);

// Sets `loader`'s image callback (headers only) and file access, both recording into `context`;
// `embedded_only` (an upload) refuses every file access, otherwise files are read inside
// context.folder only.
void install_callbacks(tinygltf::TinyGLTF& loader, LoadContext& context, bool embedded_only);

}  // namespace bounce::scene::gltf
