#include "renderer/scene/gltf_validation.hpp"

#include "renderer/scene/gltf_images.hpp"

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>

namespace bounce::scene::gltf {
namespace {

// Required extensions Bounce honours.
const std::set<std::string, std::less<>> supported_extensions = {
    "KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_specular",
    "KHR_texture_transform", "KHR_mesh_quantization", "KHR_materials_ior"};

// GLB's header and chunk lengths are little-endian.
std::uint32_t read_u32_le(const std::uint8_t* bytes) {
    return std::uint32_t{bytes[0]} | std::uint32_t{bytes[1]} << 8 | std::uint32_t{bytes[2]} << 16 |
           std::uint32_t{bytes[3]} << 24;
}

// ------------------------------------------------------------------------------------------------
// JSON structure check: the property types of the glTF schema that the importer relies on. tinygltf
// silently ignores many mistyped properties (a `primitives` object, a string `scale`), which would
// turn a broken file into a silently different scene.

// An index as tinygltf reads one: a JSON integer in [0, INT_MAX]. A float (1.0) or a larger integer
// would be dropped or wrapped by tinygltf's int fields, so it is refused here instead.
std::optional<std::uint64_t> as_index(const Json& value) {
    if (!value.is_number_integer()) return std::nullopt;
    if (value.is_number_unsigned()) {
        const auto index = value.get<std::uint64_t>();
        return index <= static_cast<std::uint64_t>(INT_MAX) ? std::optional<std::uint64_t>(index) : std::nullopt;
    }
    const auto index = value.get<std::int64_t>();
    return index >= 0 && index <= INT_MAX ? std::optional<std::uint64_t>(static_cast<std::uint64_t>(index)) : std::nullopt;
}

class StructureCheck {
public:
    explicit StructureCheck(Warnings& warnings) : warnings_(warnings) {}

    void document(const Json& root) {
        if (!root.is_object()) {
            reject(fmt::format("the document is a JSON {}, not an object", root.type_name()));
        }
        require(root, "", "asset", Kind::object);
        member(root["asset"], "asset", "version", Kind::string, true);
        member(root, "", "scene", Kind::index);
        string_array(root, "", "extensionsUsed");
        string_array(root, "", "extensionsRequired");
        extensions(root, "");
        each(root, "scenes", [&](const Json& scene, const std::string& path) {
            member(scene, path, "name", Kind::string);
            index_array(scene, path, "nodes");
        });
        each(root, "nodes", [&](const Json& node, const std::string& path) { check_node(node, path); });
        each(root, "meshes", [&](const Json& mesh, const std::string& path) { check_mesh(mesh, path); });
        each(root, "accessors", [&](const Json& accessor, const std::string& path) {
            member(accessor, path, "bufferView", Kind::index);
            member(accessor, path, "byteOffset", Kind::index);
            member(accessor, path, "componentType", Kind::index, true);
            member(accessor, path, "count", Kind::index, true);
            member(accessor, path, "type", Kind::string, true);
            member(accessor, path, "normalized", Kind::boolean);
            member(accessor, path, "sparse", Kind::object);
            number_array(accessor, path, "min", 0);
            number_array(accessor, path, "max", 0);
        });
        each(root, "bufferViews", [&](const Json& view, const std::string& path) {
            member(view, path, "buffer", Kind::index, true);
            member(view, path, "byteOffset", Kind::index);
            member(view, path, "byteLength", Kind::index, true);
            member(view, path, "byteStride", Kind::index);
            member(view, path, "target", Kind::index);
        });
        each(root, "buffers", [&](const Json& buffer, const std::string& path) {
            member(buffer, path, "uri", Kind::string);
            member(buffer, path, "byteLength", Kind::index, true);
        });
        each(root, "materials",
             [&](const Json& material, const std::string& path) { check_material(material, path); });
        each(root, "textures", [&](const Json& texture, const std::string& path) {
            member(texture, path, "sampler", Kind::index);
            member(texture, path, "source", Kind::index);
        });
        each(root, "images", [&](const Json& image, const std::string& path) {
            member(image, path, "uri", Kind::string);
            member(image, path, "mimeType", Kind::string);
            member(image, path, "bufferView", Kind::index);
        });
        each(root, "samplers", [](const Json&, const std::string&) {});
        each(root, "cameras", [&](const Json& camera, const std::string& path) {
            member(camera, path, "type", Kind::string, true);
            if (const Json* perspective = member(camera, path, "perspective", Kind::object)) {
                const std::string inner = path + ".perspective";
                member(*perspective, inner, "yfov", Kind::number, true);
                member(*perspective, inner, "znear", Kind::number, true);
                member(*perspective, inner, "zfar", Kind::number);
                member(*perspective, inner, "aspectRatio", Kind::number);
            }
            member(camera, path, "orthographic", Kind::object);
        });
        each(root, "skins", [](const Json&, const std::string&) {});
        each(root, "animations", [](const Json&, const std::string&) {});
        check_lights(root);
        check_buffer_view_ranges(root);
    }

private:
    enum class Kind { object, array, string, number, boolean, index };

    static const char* describe(Kind kind) {
        switch (kind) {
            case Kind::object: return "an object";
            case Kind::array: return "an array";
            case Kind::string: return "a string";
            case Kind::number: return "a number";
            case Kind::boolean: return "a boolean";
            case Kind::index: return "a non-negative integer";
        }
        return "?";
    }

    static bool matches(const Json& value, Kind kind) {
        switch (kind) {
            case Kind::object: return value.is_object();
            case Kind::array: return value.is_array();
            case Kind::string: return value.is_string();
            case Kind::number: return value.is_number();
            case Kind::boolean: return value.is_boolean();
            case Kind::index: return as_index(value).has_value();
        }
        return false;
    }

    static std::string join(const std::string& path, std::string_view key) {
        return path.empty() ? std::string(key) : fmt::format("{}.{}", path, key);
    }

    static std::string found(const Json& value) {
        if (value.is_number()) return fmt::format("{} {}", value.type_name(), value.dump());
        if (value.is_string()) return fmt::format("string {}", value.dump());
        return value.type_name();
    }

    // The member `key` of `object` when present and of the right kind; throws when it has another kind.
    const Json* member(const Json& object, const std::string& path, const char* key, Kind kind,
                       bool required = false) {
        const auto it = object.find(key);
        if (it == object.end()) {
            if (required) reject(fmt::format("{} is required but missing", join(path, key)));
            return nullptr;
        }
        if (!matches(*it, kind)) {
            reject(fmt::format("{} must be {} (found {})", join(path, key), describe(kind), found(*it)));
        }
        return &*it;
    }

    const Json& require(const Json& object, const std::string& path, const char* key, Kind kind) {
        return *member(object, path, key, kind, true);
    }

    void typed_array(const Json& object, const std::string& path, const char* key, Kind element_kind,
                     std::size_t length, bool required = false) {
        const Json* array = member(object, path, key, Kind::array, required);
        if (array == nullptr) return;
        if (length != 0 && array->size() != length) {
            reject(
                fmt::format("{} must have {} elements (found {})", join(path, key), length, array->size()));
        }
        for (std::size_t i = 0; i < array->size(); ++i) {
            if (!matches((*array)[i], element_kind)) {
                reject(fmt::format("{}[{}] must be {} (found {})", join(path, key), i, describe(element_kind),
                                   found((*array)[i])));
            }
        }
    }
    void number_array(const Json& object, const std::string& path, const char* key, std::size_t length) {
        typed_array(object, path, key, Kind::number, length);
    }
    void index_array(const Json& object, const std::string& path, const char* key) {
        typed_array(object, path, key, Kind::index, 0);
    }
    void string_array(const Json& object, const std::string& path, const char* key) {
        typed_array(object, path, key, Kind::string, 0);
    }

    // Calls `check(element, element_path)` for each element of the array `key` of `object` (at
    // `path`); every element must be an object.
    template <typename Check>
    void objects(const Json& object, const std::string& path, const char* key, Check&& check) {
        const Json* array = member(object, path, key, Kind::array);
        if (array == nullptr) return;
        for (std::size_t i = 0; i < array->size(); ++i) {
            const std::string element_path = fmt::format("{}[{}]", join(path, key), i);
            const Json& element = (*array)[i];
            if (!element.is_object()) {
                reject(fmt::format("{} must be an object (found {})", element_path, found(element)));
            }
            check(element, element_path);
        }
    }

    // objects() for the top-level array `key`, with each element's `name` and `extensions` checked too.
    template <typename Check>
    void each(const Json& root, const char* key, Check&& check) {
        objects(root, "", key, [&](const Json& element, const std::string& path) {
            member(element, path, "name", Kind::string);
            extensions(element, path);
            check(element, path);
        });
    }

    // `extensions` must be an object of objects (glTF's schema; the Khronos validator reports
    // anything else as an error): a malformed value is refused, known extension or not, rather
    // than a known one quietly not applying.
    void extensions(const Json& object, const std::string& path) {
        const Json* map = member(object, path, "extensions", Kind::object);
        if (map == nullptr) return;
        for (const auto& [name, value] : map->items()) {
            if (!value.is_object()) {
                reject(fmt::format("{}.{} must be an object (found {})", join(path, "extensions"), name, found(value)));
            }
        }
    }

    void check_node(const Json& node, const std::string& path) {
        index_array(node, path, "children");
        member(node, path, "mesh", Kind::index);
        member(node, path, "camera", Kind::index);
        member(node, path, "skin", Kind::index);
        number_array(node, path, "matrix", 16);
        number_array(node, path, "translation", 3);
        number_array(node, path, "rotation", 4);
        number_array(node, path, "scale", 3);
        number_array(node, path, "weights", 0);
        const auto ext = node.find("extensions");
        if (ext != node.end()) {
            const auto lights = ext->find("KHR_lights_punctual");
            if (lights != ext->end() && lights->is_object()) {
                member(*lights, join(path, "extensions.KHR_lights_punctual"), "light", Kind::index, true);
            }
        }
    }

    void check_mesh(const Json& mesh, const std::string& path) {
        const Json& primitives = require(mesh, path, "primitives", Kind::array);
        if (primitives.empty()) reject(fmt::format("{}.primitives must not be empty", path));
        number_array(mesh, path, "weights", 0);
        objects(mesh, path, "primitives", [&](const Json& primitive, const std::string& inner) {
            const Json& attributes = require(primitive, inner, "attributes", Kind::object);
            for (const auto& [name, value] : attributes.items()) {
                if (!as_index(value)) {
                    reject(fmt::format("{}.attributes.{} must be {} (found {})", inner, name,
                                       describe(Kind::index), found(value)));
                }
            }
            member(primitive, inner, "indices", Kind::index);
            member(primitive, inner, "material", Kind::index);
            member(primitive, inner, "mode", Kind::index);
            member(primitive, inner, "targets", Kind::array);
            extensions(primitive, inner);
        });
    }

    void texture_info(const Json& object, const std::string& path, const char* key) {
        const Json* info = member(object, path, key, Kind::object);
        if (info == nullptr) return;
        const std::string inner = join(path, key);
        member(*info, inner, "texCoord", Kind::index);
        member(*info, inner, "scale", Kind::number);
        member(*info, inner, "strength", Kind::number);
        member(*info, inner, "index", Kind::index, true);
        extensions(*info, inner);
    }

    void check_material(const Json& material, const std::string& path) {
        if (const Json* pbr = member(material, path, "pbrMetallicRoughness", Kind::object)) {
            const std::string inner = join(path, "pbrMetallicRoughness");
            number_array(*pbr, inner, "baseColorFactor", 4);
            member(*pbr, inner, "metallicFactor", Kind::number);
            member(*pbr, inner, "roughnessFactor", Kind::number);
            texture_info(*pbr, inner, "baseColorTexture");
            texture_info(*pbr, inner, "metallicRoughnessTexture");
            extensions(*pbr, inner);
        }
        texture_info(material, path, "normalTexture");
        texture_info(material, path, "occlusionTexture");
        texture_info(material, path, "emissiveTexture");
        number_array(material, path, "emissiveFactor", 3);
        member(material, path, "alphaMode", Kind::string);
        member(material, path, "alphaCutoff", Kind::number);
        member(material, path, "doubleSided", Kind::boolean);
        const auto ext = material.find("extensions");
        if (ext == material.end()) return;
        const std::string ext_path = join(path, "extensions");
        const auto strength = ext->find("KHR_materials_emissive_strength");
        if (strength != ext->end() && strength->is_object()) {
            member(*strength, join(ext_path, "KHR_materials_emissive_strength"), "emissiveStrength",
                   Kind::number);
        }
        const auto specular = ext->find("KHR_materials_specular");
        if (specular != ext->end() && specular->is_object()) {
            member(*specular, join(ext_path, "KHR_materials_specular"), "specularFactor", Kind::number);
        }
    }

    void check_lights(const Json& root) {
        const auto ext = root.find("extensions");
        if (ext == root.end()) return;
        const auto punctual = ext->find("KHR_lights_punctual");
        if (punctual == ext->end() || !punctual->is_object()) return;
        const auto check_light = [&](const Json& light, const std::string& path) {
            member(light, path, "type", Kind::string, true);
            member(light, path, "name", Kind::string);
            number_array(light, path, "color", 3);
            member(light, path, "intensity", Kind::number);
            member(light, path, "range", Kind::number);
            if (const Json* spot = member(light, path, "spot", Kind::object)) {
                member(*spot, path + ".spot", "innerConeAngle", Kind::number);
                member(*spot, path + ".spot", "outerConeAngle", Kind::number);
            }
        };
        objects(*punctual, "extensions.KHR_lights_punctual", "lights", check_light);
    }

    // tinygltf reads images straight out of their bufferView without a range check, so every
    // bufferView is checked against its buffer's declared length here (tinygltf makes a buffer's data
    // exactly byteLength long, or fails the load).
    static void check_buffer_view_ranges(const Json& root) {
        const auto views = root.find("bufferViews");
        if (views == root.end()) return;
        const auto buffers = root.find("buffers");
        const std::size_t buffer_count = buffers == root.end() ? 0 : buffers->size();
        for (std::size_t i = 0; i < views->size(); ++i) {
            const Json& view = (*views)[i];
            const std::uint64_t buffer = *as_index(view["buffer"]);
            if (buffer >= buffer_count) {
                reject(fmt::format("bufferViews[{}] refers to buffer {} (there are {})", i, buffer,
                                   buffer_count));
            }
            const std::uint64_t buffer_length = *as_index((*buffers)[buffer]["byteLength"]);
            const std::uint64_t offset = view.contains("byteOffset") ? *as_index(view["byteOffset"]) : 0;
            const std::uint64_t length = *as_index(view["byteLength"]);
            if (offset > buffer_length || length > buffer_length - offset) {
                reject(fmt::format("bufferViews[{}] (bytes {}..{}) exceeds buffer {} ({} bytes)", i, offset,
                                   offset + length, buffer, buffer_length));
            }
            if (view.contains("byteStride")) {
                const std::uint64_t stride = *as_index(view["byteStride"]);
                if (stride < 4 || stride > 252) {
                    reject(fmt::format("bufferViews[{}].byteStride {} is outside 4..252", i, stride));
                }
            }
        }
    }

    Warnings& warnings_;
};

// ------------------------------------------------------------------------------------------------
// JSON nesting, counted on the raw text: nlohmann and tinygltf both recurse into nested containers,
// so a file of a few hundred kilobytes of brackets would exhaust the stack of whatever parses it.

void check_json_depth(std::string_view text) {
    int depth = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (in_string) {
            if (c == '\\') {
                ++i;  // an escaped character never ends the string
            } else if (c == '"') {
                in_string = false;
            }
            continue;
        }
        if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            if (++depth > max_json_depth) {
                reject(fmt::format("the JSON nests arrays and objects more than {} levels deep (at byte {})",
                                   max_json_depth, i));
            }
        } else if (c == ']' || c == '}') {
            depth = std::max(depth - 1, 0);  // an unbalanced close is the parser's to report
        }
    }
}

// ------------------------------------------------------------------------------------------------
// URIs and file access. A file import reads only inside the glTF file's folder (context.folder,
// canonical); an upload reads no file at all.

// Calls `visit(key, index, uri)` for each buffer and image that has a URI.
template <typename Visit>
void for_each_uri(const Json& root, Visit&& visit) {
    for (const char* key : {"buffers", "images"}) {
        const auto array = root.find(key);
        if (array == root.end()) continue;
        for (std::size_t i = 0; i < array->size(); ++i) {
            const auto uri = (*array)[i].find("uri");
            if (uri != (*array)[i].end()) visit(key, i, uri->get_ref<const std::string&>());
        }
    }
}

// A URI decoded exactly as tinygltf decodes it before it opens the file (dlib::urldecode): '+' is
// a space, and '%' with at least two characters after it is the byte they give in hex, where a
// character that is not a hex digit counts as 0 ("%zz" is a NUL byte, "%2z" a space).
std::string percent_decoded(std::string_view uri) {
    auto nibble = [](char c) {
        if (c >= '0' && c <= '9') return c - '0';
        if (c >= 'a' && c <= 'f') return c - 'a' + 10;
        if (c >= 'A' && c <= 'F') return c - 'A' + 10;
        return 0;
    };
    std::string out;
    out.reserve(uri.size());
    for (std::size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '+') {
            out += ' ';
        } else if (uri[i] == '%' && uri.size() > i + 2) {
            out += static_cast<char>(nibble(uri[i + 1]) << 4 | nibble(uri[i + 2]));
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}

// The first '%' escape that tinygltf decodes (two characters follow it) but whose two characters
// are not both hex digits; empty when there is none.
std::string_view invalid_escape(std::string_view uri) {
    for (std::size_t i = 0; i + 2 < uri.size(); ++i) {
        if (uri[i] != '%') continue;
        if (!std::isxdigit(static_cast<unsigned char>(uri[i + 1])) ||
            !std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
            return uri.substr(i, 3);
        }
        i += 2;
    }
    return {};
}

// Whether `path` lies inside `folder` (canonical) once `..` and symlinks are resolved.
bool inside_folder(const std::filesystem::path& path, const std::filesystem::path& folder) {
    std::error_code error;
    const std::filesystem::path resolved = std::filesystem::weakly_canonical(path, error);
    if (error) return false;
    const auto [folder_end, unused] =
        std::mismatch(folder.begin(), folder.end(), resolved.begin(), resolved.end());
    return folder_end == folder.end();
}

// tinygltf looks a file up next to the glTF file and then in the working directory; only the first
// counts, and only inside the folder.
bool confined(const std::string& path, const LoadContext& context) {
    std::string prefix = context.folder.string();
    if (!prefix.ends_with('/')) prefix += '/';
    return path.starts_with(prefix) && inside_folder(path, context.folder);
}

bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path) {
    std::error_code code;
    const std::uintmax_t size = std::filesystem::file_size(path, code);
    std::ifstream stream(path, std::ios::binary);
    if (code || size > max_input_bytes || !stream) {
        if (err) *err = code ? code.message() : "cannot open or too large";
        return false;
    }
    out->resize(static_cast<std::size_t>(size));
    if (!stream.read(reinterpret_cast<char*>(out->data()), static_cast<std::streamsize>(size))) {
        if (err) *err = "read error";
        return false;
    }
    return true;
}

bool confined_file_exists(const std::string& path, void* user_data) {
    std::error_code error;
    return confined(path, *static_cast<const LoadContext*>(user_data)) &&
           std::filesystem::is_regular_file(path, error);
}

bool confined_read(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                   void* user_data) {
    if (!confined(path, *static_cast<const LoadContext*>(user_data))) {
        if (err) *err = "outside the folder of the glTF file";
        return false;
    }
    return read_whole_file(out, err, path);
}

// Paths are used as given: no shell-style expansion.
std::string path_as_is(const std::string& path, void*) { return path; }

bool refuse_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err) *err = "the importer does not write files";
    return false;
}

bool refuse_file_exists(const std::string& path, void* user_data) {
    static_cast<LoadContext*>(user_data)->refused_paths.push_back(path);
    return false;
}

bool refuse_read(std::vector<unsigned char>*, std::string* err, const std::string& path, void* user_data) {
    static_cast<LoadContext*>(user_data)->refused_paths.push_back(path);
    if (err) *err = "an uploaded GLB may not read files";
    return false;
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// Container level: GLB header and JSON parsing.

bool has_glb_magic(std::span<const std::uint8_t> bytes) {
    return bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
}

std::string_view glb_json_chunk(std::span<const std::uint8_t> bytes) {
    if (bytes.size() < 20) reject(fmt::format("truncated GLB: {} bytes, header needs 20", bytes.size()));
    if (!has_glb_magic(bytes)) reject("not a binary glTF: bad magic");
    const std::uint32_t version = read_u32_le(bytes.data() + 4);
    if (version != 2) reject(fmt::format("GLB version {} is not supported (need 2)", version));
    const std::uint32_t total_length = read_u32_le(bytes.data() + 8);
    if (total_length > bytes.size()) {
        reject(fmt::format("truncated GLB: header says {} bytes, got {}", total_length, bytes.size()));
    }
    if (total_length < 20) {  // and total_length - 20 below would wrap around
        reject(fmt::format("truncated GLB: header says {} bytes, its headers alone take 20", total_length));
    }
    if (total_length < bytes.size()) {
        reject(fmt::format("GLB: header says {} bytes, the file has {} (data past its end)", total_length,
                           bytes.size()));
    }
    const std::uint32_t json_length = read_u32_le(bytes.data() + 12);
    const std::uint32_t chunk_type = read_u32_le(bytes.data() + 16);
    if (chunk_type != 0x4E4F534Au) reject("GLB: the first chunk is not JSON");
    if (json_length > total_length - 20) {
        reject(fmt::format("truncated GLB: JSON chunk of {} bytes exceeds the file", json_length));
    }
    // Every chunk, not only the JSON one, lies within the file and starts on 4 bytes, as the format
    // requires: tinygltf reads the chunk after the JSON one by its own header, and a JSON length one
    // byte off (a single flipped bit) made it copy past the end of the data.
    for (std::uint64_t offset = 12; offset < total_length;) {
        if (total_length - offset < 8) {
            reject(fmt::format("truncated GLB: a chunk header at byte {} needs 8 bytes, {} are left", offset,
                               total_length - offset));
        }
        const std::uint32_t length = read_u32_le(bytes.data() + offset);
        if (length % 4 != 0) {
            reject(fmt::format("GLB: the chunk at byte {} is {} bytes, not a multiple of 4", offset, length));
        }
        if (length > total_length - offset - 8) {
            reject(fmt::format("truncated GLB: the chunk at byte {} of {} bytes exceeds the file", offset, length));
        }
        offset += 8 + static_cast<std::uint64_t>(length);
    }
    return {reinterpret_cast<const char*>(bytes.data() + 20), json_length};
}

Json parse_json(std::string_view text) {
    check_json_depth(text);
    try {
        return Json::parse(text.begin(), text.end());
    } catch (const Json::exception& error) {
        reject(fmt::format("invalid JSON: {}", error.what()));
    }
}

// ------------------------------------------------------------------------------------------------
// Document level: structure, extensions, URIs.

void check_structure(const Json& root, Warnings& warnings) { StructureCheck(warnings).document(root); }

void check_extensions(const Json& root, Warnings& warnings) {
    if (const auto required = root.find("extensionsRequired"); required != root.end()) {
        for (const Json& name : *required) {
            if (!supported_extensions.contains(name.get<std::string>())) {
                reject(fmt::format("requires the unsupported extension {}", name.get<std::string>()));
            }
        }
    }
    if (const auto used = root.find("extensionsUsed"); used != root.end()) {
        for (const Json& name : *used) {
            if (!supported_extensions.contains(name.get<std::string>())) {
                warnings.add(fmt::format("uses the unsupported optional extension {}; it is ignored",
                                         name.get<std::string>()));
            }
        }
    }
}

void refuse_external_uris(const Json& root) {
    for_each_uri(root, [](const char* key, std::size_t index, const std::string& uri) {
        if (uri.starts_with("data:")) return;
        reject(fmt::format("{}[{}] refers to the external file '{}'; an uploaded GLB must embed all its data",
                           key, index, uri));
    });
}

void confine_uris(const Json& root, const std::filesystem::path& folder) {
    for_each_uri(root, [&](const char* key, std::size_t index, const std::string& uri) {
        if (tinygltf::IsDataURI(uri)) return;  // what tinygltf does not take for data, it reads as a file
        // tinygltf reads such an escape as bytes nobody meant; refused rather than guessed at.
        if (const std::string_view escape = invalid_escape(uri); !escape.empty()) {
            reject(fmt::format("{}[{}].uri '{}' has the invalid percent escape '{}'", key, index, uri, escape));
        }
        const std::string decoded = percent_decoded(uri);
        const std::filesystem::path relative(decoded);
        if (decoded.find('\0') != std::string::npos || relative.has_root_path()) {
            reject(fmt::format("{}[{}].uri '{}' is not a relative path; files must lie in the folder of the "
                               "glTF file",
                               key, index, uri));
        }
        if (!inside_folder(folder / relative, folder)) {
            reject(fmt::format("{}[{}].uri '{}' leads outside the folder of the glTF file", key, index, uri));
        }
    });
}

std::optional<std::vector<unsigned char>> read_uri_file(const std::string& uri, const LoadContext& context) {
    const std::string path = (context.folder / percent_decoded(uri)).string();
    std::vector<unsigned char> bytes;
    if (!confined(path, context) || !read_whole_file(&bytes, nullptr, path)) return std::nullopt;
    return bytes;
}

void install_callbacks(tinygltf::TinyGLTF& loader, LoadContext& context, bool embedded_only) {
    loader.SetImageLoader(&record_image_header, &context);
    if (embedded_only) {
        loader.SetFsCallbacks({&refuse_file_exists, &path_as_is, &refuse_read, &refuse_write, &context});
    } else {
        loader.SetFsCallbacks({&confined_file_exists, &path_as_is, &confined_read, &refuse_write, &context});
    }
}

}  // namespace bounce::scene::gltf
