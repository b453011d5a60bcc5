// glTF 2.0 import through tinygltf.
//
// The input is untrusted (uploads reach import_glb_memory), so the importer does not rely on
// tinygltf's own validation: before tinygltf sees the document, the JSON is type-checked and every
// bufferView is checked against its buffer; after loading, every accessor is checked against its
// bufferView and every index against the vertex count before anything is read.
#include "renderer/scene/gltf_import.hpp"

#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/scene/mesh_utils.hpp"

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <glm/gtc/type_ptr.hpp>
#include <glm/gtx/string_cast.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string_view>
#include <utility>

namespace bounce::scene {
namespace {

using Json = nlohmann::json;

// Limits that keep a hostile file from asking for unbounded memory.
constexpr std::uint64_t max_accessor_count = std::uint64_t{1} << 28;
constexpr int max_image_side = 16384;
constexpr std::uint64_t max_input_bytes = 0xFFFFFFFFull;  // tinygltf takes lengths as unsigned int

// Required extensions Bounce can honour (KHR_texture_transform loads, but the transform is not applied:
// the scene model has no UV transform; a warning says so).
const std::set<std::string, std::less<>> supported_extensions = {
    "KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_specular",
    "KHR_texture_transform"};

[[noreturn]] void reject(const std::string& message) { throw InputError(message); }

// Warnings go to the log and to Scene::warnings.
class Warnings {
public:
    explicit Warnings(std::string source) : source_(std::move(source)) {}
    void add(const std::string& message) {
        log::warn("gltf", "{}: {}", source_, message);
        list_.push_back(message);
    }
    std::vector<std::string> take() { return std::move(list_); }

private:
    std::string source_;
    std::vector<std::string> list_;
};

// ------------------------------------------------------------------------------------------------
// Container level: GLB header and JSON parsing.

std::uint32_t read_u32_le(const std::uint8_t* bytes) {
    return std::uint32_t{bytes[0]} | std::uint32_t{bytes[1]} << 8 | std::uint32_t{bytes[2]} << 16 |
           std::uint32_t{bytes[3]} << 24;
}

bool has_glb_magic(std::span<const std::uint8_t> bytes) {
    return bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
}

// The JSON chunk of a GLB, with the header and chunk lengths checked.
std::string_view glb_json_chunk(std::span<const std::uint8_t> bytes) {
    if (bytes.size() < 20) reject(fmt::format("truncated GLB: {} bytes, header needs 20", bytes.size()));
    if (!has_glb_magic(bytes)) reject("not a binary glTF: bad magic");
    const std::uint32_t version = read_u32_le(bytes.data() + 4);
    if (version != 2) reject(fmt::format("GLB version {} is not supported (need 2)", version));
    const std::uint32_t total_length = read_u32_le(bytes.data() + 8);
    if (total_length > bytes.size()) {
        reject(fmt::format("truncated GLB: header says {} bytes, got {}", total_length, bytes.size()));
    }
    const std::uint32_t json_length = read_u32_le(bytes.data() + 12);
    const std::uint32_t chunk_type = read_u32_le(bytes.data() + 16);
    if (chunk_type != 0x4E4F534Au) reject("GLB: the first chunk is not JSON");
    if (json_length > total_length - 20) {
        reject(fmt::format("truncated GLB: JSON chunk of {} bytes exceeds the file", json_length));
    }
    return {reinterpret_cast<const char*>(bytes.data() + 20), json_length};
}

Json parse_json(std::string_view text) {
    try {
        return Json::parse(text.begin(), text.end());
    } catch (const Json::exception& error) {
        reject(fmt::format("invalid JSON: {}", error.what()));
    }
}

// ------------------------------------------------------------------------------------------------
// JSON structure check: the property types of the glTF schema that the importer relies on. tinygltf
// silently ignores many mistyped properties (a `primitives` object, a string `scale`), which would
// turn a broken file into a silently different scene.

std::optional<std::uint64_t> as_index(const Json& value) {
    if (value.is_number_unsigned()) return value.get<std::uint64_t>();
    if (value.is_number_integer()) {
        const auto signed_value = value.get<std::int64_t>();
        if (signed_value >= 0) return static_cast<std::uint64_t>(signed_value);
        return std::nullopt;
    }
    if (value.is_number_float()) {
        const double number = value.get<double>();
        if (number >= 0.0 && number < 9.0e15 && std::floor(number) == number) {
            return static_cast<std::uint64_t>(number);
        }
    }
    return std::nullopt;
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

    // Calls `check(element, path)` for each element of the top-level array `key`; every element
    // must be an object, and its `name` and `extensions` are checked too.
    template <typename Check>
    void each(const Json& root, const char* key, Check&& check) {
        const Json* array = member(root, "", key, Kind::array);
        if (array == nullptr) return;
        for (std::size_t i = 0; i < array->size(); ++i) {
            const std::string path = fmt::format("{}[{}]", key, i);
            const Json& element = (*array)[i];
            if (!element.is_object()) {
                reject(fmt::format("{} must be an object (found {})", path, found(element)));
            }
            member(element, path, "name", Kind::string);
            extensions(element, path);
            check(element, path);
        }
    }

    // `extensions` must be an object. A malformed extension value is ignored with a warning: an
    // unknown extension must not break a file, and a known one then simply does not apply.
    void extensions(const Json& object, const std::string& path) {
        const Json* map = member(object, path, "extensions", Kind::object);
        if (map == nullptr) return;
        for (const auto& [name, value] : map->items()) {
            if (!value.is_object()) {
                warnings_.add(fmt::format("{}.{} must be an object (found {}); the extension is ignored",
                                          join(path, "extensions"), name, found(value)));
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
        for (std::size_t p = 0; p < primitives.size(); ++p) {
            const std::string inner = fmt::format("{}.primitives[{}]", path, p);
            const Json& primitive = primitives[p];
            if (!primitive.is_object()) {
                reject(fmt::format("{} must be an object (found {})", inner, found(primitive)));
            }
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
        }
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
        const std::string path = "extensions.KHR_lights_punctual";
        const Json* lights = member(*punctual, path, "lights", Kind::array);
        if (lights == nullptr) return;
        for (std::size_t i = 0; i < lights->size(); ++i) {
            const std::string inner = fmt::format("{}.lights[{}]", path, i);
            const Json& light = (*lights)[i];
            if (!light.is_object()) {
                reject(fmt::format("{} must be an object (found {})", inner, found(light)));
            }
            member(light, inner, "type", Kind::string, true);
            member(light, inner, "name", Kind::string);
            number_array(light, inner, "color", 3);
            member(light, inner, "intensity", Kind::number);
            member(light, inner, "range", Kind::number);
            if (const Json* spot = member(light, inner, "spot", Kind::object)) {
                member(*spot, inner + ".spot", "innerConeAngle", Kind::number);
                member(*spot, inner + ".spot", "outerConeAngle", Kind::number);
            }
        }
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

// Required extensions must all be supported; unknown optional ones only warn.
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

// An upload must carry all its data: any buffer or image URI other than a data: URI is refused.
void refuse_external_uris(const Json& root) {
    for (const char* key : {"buffers", "images"}) {
        const auto array = root.find(key);
        if (array == root.end()) continue;
        for (std::size_t i = 0; i < array->size(); ++i) {
            const auto uri = (*array)[i].find("uri");
            if (uri == (*array)[i].end()) continue;
            const std::string& text = uri->get_ref<const std::string&>();
            if (!text.starts_with("data:")) {
                reject(
                    fmt::format("{}[{}] refers to the external file '{}'; an uploaded GLB must embed all "
                                "its data",
                                key, i, text));
            }
        }
    }
}

// ------------------------------------------------------------------------------------------------
// tinygltf callbacks: image decoding that never fails the load, and file access.

struct LoadContext {
    std::map<int, std::string> image_failures;  // image index -> why it has no pixels
    std::vector<std::string> refused_paths;     // file reads refused for an upload
};

// Width and height from a PNG or JPEG header, so that oversized images are refused before decoding.
std::optional<std::pair<std::uint64_t, std::uint64_t>> peek_image_size(const unsigned char* bytes,
                                                                       std::size_t size) {
    static constexpr unsigned char png_signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    auto be16 = [&](std::size_t at) { return std::uint64_t{bytes[at]} << 8 | bytes[at + 1]; };
    auto be32 = [&](std::size_t at) { return be16(at) << 16 | be16(at + 2); };
    if (size >= 24 && std::memcmp(bytes, png_signature, 8) == 0) return std::pair{be32(16), be32(20)};
    if (size >= 4 && bytes[0] == 0xFF && bytes[1] == 0xD8) {
        std::size_t at = 2;
        while (at + 9 < size) {
            if (bytes[at] != 0xFF) return std::nullopt;
            const unsigned char marker = bytes[at + 1];
            if (marker == 0xFF) {
                ++at;  // fill byte
                continue;
            }
            const bool start_of_frame =
                marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
            if (start_of_frame) return std::pair{be16(at + 7), be16(at + 5)};
            at += 2 + be16(at + 2);
        }
    }
    return std::nullopt;
}

bool decode_image(tinygltf::Image* image, const int image_index, std::string* /*err*/, std::string* warn,
                  int required_width, int required_height, const unsigned char* bytes, int size,
                  void* user_data) {
    auto& context = *static_cast<LoadContext*>(user_data);
    // A failed image must not fail the scene: record why, leave the pixels empty and carry on.
    auto give_up = [&](std::string reason) {
        image->image.clear();
        image->width = image->height = 0;
        context.image_failures[image_index] = std::move(reason);
        return true;
    };
    if (const auto dimensions = peek_image_size(bytes, static_cast<std::size_t>(size))) {
        if (dimensions->first > max_image_side || dimensions->second > max_image_side) {
            return give_up(fmt::format("{}x{} pixels exceeds the limit of {} per side", dimensions->first,
                                       dimensions->second, max_image_side));
        }
    }
    std::string decode_error;
    // No user data: tinygltf's defaults, which expand every image to four channels.
    if (!tinygltf::LoadImageData(image, image_index, &decode_error, warn, required_width, required_height,
                                 bytes, size, nullptr)) {
        while (!decode_error.empty() && decode_error.back() == '\n') decode_error.pop_back();
        return give_up(decode_error.empty() ? "it could not be decoded" : decode_error);
    }
    if (image->width > max_image_side || image->height > max_image_side) {
        return give_up(fmt::format("{}x{} pixels exceeds the limit of {} per side", image->width,
                                   image->height, max_image_side));
    }
    return true;
}

bool file_exists(const std::string& path, void*) {
    std::error_code error;
    return std::filesystem::is_regular_file(path, error);
}

// Paths are used as given: no shell-style expansion.
std::string path_as_is(const std::string& path, void*) { return path; }

bool read_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void*) {
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

// ------------------------------------------------------------------------------------------------
// Accessors: bounds checks and typed reads.

const char* component_name(int component_type) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE: return "BYTE";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "UNSIGNED_BYTE";
        case TINYGLTF_COMPONENT_TYPE_SHORT: return "SHORT";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "UNSIGNED_SHORT";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "UNSIGNED_INT";
        case TINYGLTF_COMPONENT_TYPE_FLOAT: return "FLOAT";
        default: return "an invalid component type";
    }
}

const char* type_name(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR: return "SCALAR";
        case TINYGLTF_TYPE_VEC2: return "VEC2";
        case TINYGLTF_TYPE_VEC3: return "VEC3";
        case TINYGLTF_TYPE_VEC4: return "VEC4";
        case TINYGLTF_TYPE_MAT2: return "MAT2";
        case TINYGLTF_TYPE_MAT3: return "MAT3";
        case TINYGLTF_TYPE_MAT4: return "MAT4";
        default: return "an invalid type";
    }
}

int component_size(int component_type) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
        default: return 0;
    }
}

int component_count(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR: return 1;
        case TINYGLTF_TYPE_VEC2: return 2;
        case TINYGLTF_TYPE_VEC3: return 3;
        case TINYGLTF_TYPE_VEC4: return 4;
        case TINYGLTF_TYPE_MAT2: return 4;
        case TINYGLTF_TYPE_MAT3: return 9;
        case TINYGLTF_TYPE_MAT4: return 16;
        default: return 0;
    }
}

// Where an accessor's elements lie, after its bounds were checked. `data` is null for an accessor
// without a bufferView (all zeros).
struct AccessorView {
    const std::uint8_t* data = nullptr;
    std::size_t stride = 0;
    std::size_t count = 0;
    int component_type = 0;
    int components = 0;
    bool normalized = false;
};

// Checks every bufferView against its buffer and every accessor against its bufferView.
void check_accessor_bounds(const tinygltf::Model& model) {
    for (std::size_t v = 0; v < model.bufferViews.size(); ++v) {
        const tinygltf::BufferView& view = model.bufferViews[v];
        if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size()) {
            reject(fmt::format("bufferView {} refers to buffer {} (there are {})", v, view.buffer,
                               model.buffers.size()));
        }
        const std::size_t buffer_size = model.buffers[static_cast<std::size_t>(view.buffer)].data.size();
        if (view.byteOffset > buffer_size || view.byteLength > buffer_size - view.byteOffset) {
            reject(fmt::format("bufferView {} (bytes {}..{}) exceeds buffer {} ({} bytes)", v,
                               view.byteOffset, view.byteOffset + view.byteLength, view.buffer, buffer_size));
        }
    }
    for (std::size_t a = 0; a < model.accessors.size(); ++a) {
        const tinygltf::Accessor& accessor = model.accessors[a];
        const int element_components = component_count(accessor.type);
        const int size = component_size(accessor.componentType);
        if (size == 0) {
            reject(fmt::format("accessor {} has the invalid componentType {}", a, accessor.componentType));
        }
        if (element_components == 0) reject(fmt::format("accessor {} has an invalid type", a));
        if (accessor.count > max_accessor_count) {
            reject(fmt::format("accessor {} has {} elements, more than the limit of {}", a, accessor.count,
                               max_accessor_count));
        }
        if (accessor.bufferView < 0 || accessor.count == 0) continue;
        if (static_cast<std::size_t>(accessor.bufferView) >= model.bufferViews.size()) {
            reject(fmt::format("accessor {} refers to bufferView {} (there are {})", a, accessor.bufferView,
                               model.bufferViews.size()));
        }
        const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(accessor.bufferView)];
        const std::size_t element_size = static_cast<std::size_t>(size) * element_components;
        const std::size_t stride = view.byteStride != 0 ? view.byteStride : element_size;
        if (stride < element_size) {
            reject(fmt::format("accessor {}: byteStride {} is smaller than its {}-byte elements", a, stride,
                               element_size));
        }
        // count <= 2^28 and stride <= 252 (checked on the JSON), so this cannot overflow.
        const std::size_t span = (accessor.count - 1) * stride + element_size;
        if (accessor.byteOffset > view.byteLength || span > view.byteLength - accessor.byteOffset) {
            reject(
                fmt::format("accessor {} (byteOffset {} + {} elements of stride {} = {} bytes) exceeds "
                            "bufferView {} ({} bytes)",
                            a, accessor.byteOffset, accessor.count, stride, accessor.byteOffset + span,
                            accessor.bufferView, view.byteLength));
        }
    }
}

// An accessor the caller wants to read, checked for its type and allowed component types.
AccessorView view_accessor(const tinygltf::Model& model, int index, const std::string& what, int wanted_type,
                           std::initializer_list<int> allowed_components, bool needs_normalized_ints) {
    if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) {
        reject(fmt::format("{} refers to accessor {} (there are {})", what, index, model.accessors.size()));
    }
    const tinygltf::Accessor& accessor = model.accessors[static_cast<std::size_t>(index)];
    if (accessor.sparse.isSparse) reject(fmt::format("{}: sparse accessor {} is not supported", what, index));
    const bool component_ok = std::find(allowed_components.begin(), allowed_components.end(),
                                        accessor.componentType) != allowed_components.end();
    const bool normalization_ok = !needs_normalized_ints || accessor.normalized ||
                                  accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT;
    if (accessor.type != wanted_type || !component_ok || !normalization_ok) {
        std::string allowed;
        for (int component : allowed_components) {
            allowed += fmt::format("{}{}", allowed.empty() ? "" : "/", component_name(component));
        }
        reject(fmt::format("{}: accessor {} is {}{} of {}, expected {} of {}", what, index,
                           accessor.normalized ? "normalized " : "", type_name(accessor.type),
                           component_name(accessor.componentType), type_name(wanted_type), allowed));
    }
    AccessorView view;
    view.count = accessor.count;
    view.component_type = accessor.componentType;
    view.components = component_count(accessor.type);
    view.normalized = accessor.normalized;
    view.stride = static_cast<std::size_t>(component_size(accessor.componentType)) * view.components;
    if (accessor.bufferView >= 0 && accessor.count > 0) {
        const tinygltf::BufferView& buffer_view =
            model.bufferViews[static_cast<std::size_t>(accessor.bufferView)];
        if (buffer_view.byteStride != 0) view.stride = buffer_view.byteStride;
        view.data = model.buffers[static_cast<std::size_t>(buffer_view.buffer)].data.data() +
                    buffer_view.byteOffset + accessor.byteOffset;
    }
    return view;
}

template <typename T>
T load_unaligned(const std::uint8_t* at) {
    T value;
    std::memcpy(&value, at, sizeof(T));
    return value;
}

// One component as a float; normalized integers map to [0, 1] or [-1, 1] as the spec says.
float read_component(const std::uint8_t* at, int component_type, bool normalized) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: return load_unaligned<float>(at);
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
            const float value = load_unaligned<std::uint8_t>(at);
            return normalized ? value / 255.0f : value;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            const float value = load_unaligned<std::uint16_t>(at);
            return normalized ? value / 65535.0f : value;
        }
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            const float value = load_unaligned<std::int8_t>(at);
            return normalized ? std::max(value / 127.0f, -1.0f) : value;
        }
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            const float value = load_unaligned<std::int16_t>(at);
            return normalized ? std::max(value / 32767.0f, -1.0f) : value;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
            const auto value = static_cast<float>(load_unaligned<std::uint32_t>(at));
            return normalized ? value / 4294967295.0f : value;
        }
        default: return 0.0f;
    }
}

template <typename Vec>
std::vector<Vec> read_vectors(const AccessorView& view) {
    std::vector<Vec> out(view.count, Vec(0.0f));
    if (view.data == nullptr) return out;
    const int size = component_size(view.component_type);
    for (std::size_t i = 0; i < view.count; ++i) {
        const std::uint8_t* element = view.data + i * view.stride;
        for (int c = 0; c < Vec::length(); ++c) {
            out[i][c] = read_component(element + c * size, view.component_type, view.normalized);
        }
    }
    return out;
}

std::vector<std::uint32_t> read_indices(const AccessorView& view) {
    std::vector<std::uint32_t> out(view.count, 0);
    if (view.data == nullptr) return out;
    for (std::size_t i = 0; i < view.count; ++i) {
        const std::uint8_t* element = view.data + i * view.stride;
        switch (view.component_type) {
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: out[i] = load_unaligned<std::uint8_t>(element); break;
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
                out[i] = load_unaligned<std::uint16_t>(element);
                break;
            default: out[i] = load_unaligned<std::uint32_t>(element); break;
        }
    }
    return out;
}

// ------------------------------------------------------------------------------------------------
// Topology: strips and fans.

// Triangle lists from strips and fans, with the winding the spec gives for each triangle.
std::vector<std::uint32_t> triangles_from_strip(const std::vector<std::uint32_t>& strip) {
    std::vector<std::uint32_t> out;
    for (std::size_t i = 0; i + 2 < strip.size(); ++i) {
        const bool odd = i % 2 == 1;
        out.insert(out.end(), {strip[i], strip[i + (odd ? 2 : 1)], strip[i + (odd ? 1 : 2)]});
    }
    return out;
}

std::vector<std::uint32_t> triangles_from_fan(const std::vector<std::uint32_t>& fan) {
    std::vector<std::uint32_t> out;
    for (std::size_t i = 1; i + 1 < fan.size(); ++i) out.insert(out.end(), {fan[i], fan[i + 1], fan[0]});
    return out;
}

// ------------------------------------------------------------------------------------------------
// The conversion from the tinygltf model to the scene model.

// Unique names within one kind of thing: "name", "name_2", ...; `fallback` when the file has none.
class NameRegistry {
public:
    std::string claim(const std::string& wanted, const std::string& fallback) {
        const std::string base = wanted.empty() ? fallback : wanted;
        std::string name = base;
        for (int suffix = 2; used_.contains(name); ++suffix) name = fmt::format("{}_{}", base, suffix);
        used_.insert(name);
        return name;
    }

private:
    std::set<std::string> used_;
};

const tinygltf::Value* extension_object(const tinygltf::ExtensionMap& extensions, const std::string& name) {
    const auto it = extensions.find(name);
    if (it == extensions.end() || !it->second.IsObject()) return nullptr;
    return &it->second;
}

std::optional<double> number_member(const tinygltf::Value& object, const std::string& key) {
    if (!object.Has(key) || !object.Get(key).IsNumber()) return std::nullopt;
    return object.Get(key).GetNumberAsDouble();
}

template <typename Vec>
Vec to_vec(const std::vector<double>& values, const Vec& fallback) {
    if (values.size() != static_cast<std::size_t>(Vec::length())) return fallback;
    Vec out;
    for (int i = 0; i < Vec::length(); ++i) out[i] = static_cast<float>(values[static_cast<std::size_t>(i)]);
    return out;
}

glm::mat4 local_transform(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) {
        glm::mat4 matrix;
        for (int i = 0; i < 16; ++i) {
            glm::value_ptr(matrix)[i] = static_cast<float>(node.matrix[std::size_t(i)]);
        }
        return matrix;  // both glTF and glm are column-major
    }
    const glm::vec3 translation = to_vec(node.translation, glm::vec3(0.0f));
    const glm::vec3 scale = to_vec(node.scale, glm::vec3(1.0f));
    const glm::vec4 xyzw = to_vec(node.rotation, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
    glm::quat rotation(xyzw.w, xyzw.x, xyzw.y, xyzw.z);
    const float length = glm::length(rotation);
    rotation = length > 1e-12f ? rotation / length : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
    glm::mat4 matrix = glm::mat4_cast(rotation);
    matrix[0] *= scale.x;
    matrix[1] *= scale.y;
    matrix[2] *= scale.z;
    matrix[3] = glm::vec4(translation, 1.0f);
    return matrix;
}

glm::vec3 normalized_or(const glm::vec3& v, const glm::vec3& fallback) {
    const float length = glm::length(v);
    return length > 1e-12f && std::isfinite(length) ? v / length : fallback;
}

// The rotation of a world transform with scale and shear removed; -Z (forward) and +Y (up) are kept.
glm::quat rotation_of(const glm::mat4& world) {
    const glm::vec3 back = normalized_or(glm::vec3(world[2]), glm::vec3(0.0f, 0.0f, 1.0f));
    glm::vec3 up = glm::vec3(world[1]) - back * glm::dot(back, glm::vec3(world[1]));
    up = normalized_or(up,
                       std::abs(back.y) < 0.9f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f));
    up = glm::normalize(up - back * glm::dot(back, up));
    const glm::vec3 right = glm::cross(up, back);
    return glm::normalize(glm::quat_cast(glm::mat3(right, up, back)));
}

class Converter {
public:
    Converter(const tinygltf::Model& model, const LoadContext& context, Warnings& warnings)
        : model_(model), context_(context), warnings_(warnings) {}

    Scene convert(std::string name) {
        scene_.name = std::move(name);
        check_accessor_bounds(model_);
        convert_materials();
        convert_meshes();
        flatten_nodes();
        if (scene_.cameras.empty()) add_default_camera();
        warn_if_unlit();
        return std::move(scene_);
    }

private:
    // -- materials and textures

    void convert_materials() {
        for (std::size_t m = 0; m < model_.materials.size(); ++m) {
            const tinygltf::Material& source = model_.materials[m];
            const tinygltf::PbrMetallicRoughness& pbr = source.pbrMetallicRoughness;
            const std::string where = fmt::format("material {} ('{}')", m, source.name);
            Material material;
            material.name = source.name.empty() ? fmt::format("material_{}", m) : source.name;
            material.base_color = to_vec(pbr.baseColorFactor, glm::vec4(1.0f));
            material.metallic = static_cast<float>(pbr.metallicFactor);
            material.roughness = static_cast<float>(pbr.roughnessFactor);
            material.emissive = to_vec(source.emissiveFactor, glm::vec3(0.0f));
            if (const tinygltf::Value* strength =
                    extension_object(source.extensions, "KHR_materials_emissive_strength")) {
                material.emissive *=
                    static_cast<float>(number_member(*strength, "emissiveStrength").value_or(1.0));
            }
            if (const tinygltf::Value* specular =
                    extension_object(source.extensions, "KHR_materials_specular")) {
                material.specular =
                    static_cast<float>(number_member(*specular, "specularFactor").value_or(1.0));
            }
            material.normal_scale = static_cast<float>(source.normalTexture.scale);
            material.double_sided = source.doubleSided;
            material.base_color_texture =
                texture_ref(pbr.baseColorTexture, true, where + " baseColorTexture");
            material.metallic_roughness_texture =
                texture_ref(pbr.metallicRoughnessTexture, false, where + " metallicRoughnessTexture");
            material.normal_texture = texture_ref(source.normalTexture, false, where + " normalTexture");
            material.emissive_texture = texture_ref(source.emissiveTexture, true, where + " emissiveTexture");
            scene_.materials.push_back(std::move(material));
        }
    }

    // A texture reference; on any problem the reference is none, so the factor alone applies.
    // An image used both as sRGB and as linear data becomes two Textures, one per colour space.
    template <typename Info>
    TextureRef texture_ref(const Info& info, bool srgb, const std::string& where) {
        TextureRef ref;
        if (info.index < 0) return ref;
        if (static_cast<std::size_t>(info.index) >= model_.textures.size()) {
            reject(fmt::format("{} refers to texture {} (there are {})", where, info.index,
                               model_.textures.size()));
        }
        if (info.extensions.count("KHR_texture_transform") != 0) {
            warnings_.add(fmt::format("{}: KHR_texture_transform is not applied", where));
        }
        if (info.texCoord > 1) {
            warnings_.add(
                fmt::format("{} uses TEXCOORD_{}; only 0 and 1 are supported, the texture is ignored", where,
                            info.texCoord));
            return ref;
        }
        const int image_index = model_.textures[static_cast<std::size_t>(info.index)].source;
        if (image_index < 0) {
            warnings_.add(fmt::format("{}: texture {} has no image Bounce can read; the texture is ignored",
                                      where, info.index));
            return ref;
        }
        if (static_cast<std::size_t>(image_index) >= model_.images.size()) {
            reject(fmt::format("texture {} refers to image {} (there are {})", info.index, image_index,
                               model_.images.size()));
        }
        const auto key = std::pair{image_index, srgb};
        if (const auto made = textures_made_.find(key); made != textures_made_.end()) {
            ref.texture = made->second;
        } else {
            std::optional<Texture> texture = convert_image(image_index, info.index);
            if (!texture) return ref;
            texture->srgb = srgb;
            ref.texture = static_cast<int>(scene_.textures.size());
            scene_.textures.push_back(std::move(*texture));
            textures_made_[key] = ref.texture;
        }
        ref.uv_set = info.texCoord;
        return ref;
    }

    std::optional<Texture> convert_image(int image_index, int texture_index) {
        const tinygltf::Image& image = model_.images[static_cast<std::size_t>(image_index)];
        const std::string label = !image.uri.empty()    ? image.uri
                                  : !image.name.empty() ? image.name
                                                        : fmt::format("image_{}", image_index);
        auto unusable = [&](const std::string& reason) -> std::optional<Texture> {
            if (images_warned_.insert(image_index).second) {
                warnings_.add(fmt::format("texture {} (image {} '{}'): {}; materials use their factors alone",
                                          texture_index, image_index, label, reason));
            }
            return std::nullopt;
        };
        if (const auto failure = context_.image_failures.find(image_index);
            failure != context_.image_failures.end()) {
            return unusable(failure->second);
        }
        if (image.image.empty()) return unusable("the image file is missing or unreadable");
        const int bytes_per_channel = image.bits == 16 ? 2 : 1;
        const std::size_t pixels =
            static_cast<std::size_t>(std::max(image.width, 0)) * std::max(image.height, 0);
        if (image.bits != 8 && image.bits != 16) {
            return unusable(fmt::format("{}-bit images are not supported", image.bits));
        }
        if (image.component < 1 || image.component > 4 || pixels == 0 ||
            image.image.size() != pixels * image.component * bytes_per_channel) {
            return unusable("the decoded pixel data has an unexpected layout");
        }
        Texture texture;
        texture.name = label;
        texture.width = image.width;
        texture.height = image.height;
        texture.rgba8.resize(pixels * 4);
        auto channel = [&](std::size_t index) -> std::uint8_t {
            if (bytes_per_channel == 1) return image.image[index];
            // 16-bit samples are in host order (stb_image); keep the high byte, rounded.
            const auto value = load_unaligned<std::uint16_t>(image.image.data() + index * 2);
            return static_cast<std::uint8_t>((value * 255u + 32767u) / 65535u);
        };
        const std::size_t components = static_cast<std::size_t>(image.component);
        for (std::size_t p = 0; p < pixels; ++p) {
            const std::size_t in = p * components;
            std::uint8_t* out = texture.rgba8.data() + p * 4;
            if (components <= 2) {  // grey or grey + alpha
                out[0] = out[1] = out[2] = channel(in);
                out[3] = components == 2 ? channel(in + 1) : 255;
            } else {
                out[0] = channel(in);
                out[1] = channel(in + 1);
                out[2] = channel(in + 2);
                out[3] = components == 4 ? channel(in + 3) : 255;
            }
        }
        return texture;
    }

    // -- meshes

    void convert_meshes() {
        for (std::size_t m = 0; m < model_.meshes.size(); ++m) {
            const tinygltf::Mesh& source = model_.meshes[m];
            Mesh mesh;
            mesh.name = source.name.empty() ? fmt::format("mesh_{}", m) : source.name;
            for (std::size_t p = 0; p < source.primitives.size(); ++p) {
                std::optional<Primitive> primitive = convert_primitive(source.primitives[p], m, p);
                if (!primitive) continue;
                mesh.bounds.extend(primitive->bounds);
                mesh.primitives.push_back(std::move(*primitive));
            }
            scene_.meshes.push_back(std::move(mesh));
        }
    }

    std::optional<Primitive> convert_primitive(const tinygltf::Primitive& source, std::size_t mesh_index,
                                               std::size_t primitive_index) {
        const std::string where = fmt::format("mesh {} primitive {}", mesh_index, primitive_index);
        const int mode = source.mode < 0 ? TINYGLTF_MODE_TRIANGLES : source.mode;
        if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
            mode == TINYGLTF_MODE_LINE_STRIP) {
            warnings_.add(
                fmt::format("{}: points and lines (mode {}) are not rendered; skipped", where, mode));
            return std::nullopt;
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            mode != TINYGLTF_MODE_TRIANGLE_FAN) {
            reject(fmt::format("{}: unknown primitive mode {}", where, mode));
        }
        if (!source.targets.empty()) {
            warnings_.add(fmt::format("{}: morph targets are ignored (the base shape is used)", where));
        }

        Primitive primitive;
        primitive.material = source.material;
        if (source.material >= 0 && static_cast<std::size_t>(source.material) >= model_.materials.size()) {
            reject(fmt::format("{} refers to material {} (there are {})", where, source.material,
                               model_.materials.size()));
        }

        constexpr int float_type = TINYGLTF_COMPONENT_TYPE_FLOAT;
        const int position_accessor = attribute_accessor(source, "POSITION");
        if (position_accessor < 0) reject(fmt::format("{} has no POSITION attribute", where));
        primitive.positions = read_vectors<glm::vec3>(view_accessor(
            model_, position_accessor, where + " POSITION", TINYGLTF_TYPE_VEC3, {float_type}, false));
        const std::size_t vertex_count = primitive.positions.size();
        for (std::size_t v = 0; v < vertex_count; ++v) {
            if (!finite(primitive.positions[v])) {
                reject(fmt::format("{}: vertex {} has a non-finite position {}", where, v,
                                   glm::to_string(primitive.positions[v])));
            }
        }

        primitive.indices = read_primitive_indices(source, where, vertex_count);
        if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) primitive.indices = triangles_from_strip(primitive.indices);
        if (mode == TINYGLTF_MODE_TRIANGLE_FAN) primitive.indices = triangles_from_fan(primitive.indices);
        if (primitive.indices.size() % 3 != 0) {
            reject(fmt::format("{}: {} vertex indices do not make whole triangles (not a multiple of 3)",
                               where, primitive.indices.size()));
        }

        const AttributeRead read{source, where, vertex_count};
        const std::initializer_list<int> uv_components = {float_type, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                                          TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT};
        primitive.uv0 =
            read_attribute<glm::vec2>(read, "TEXCOORD_0", TINYGLTF_TYPE_VEC2, uv_components, true);
        primitive.uv1 =
            read_attribute<glm::vec2>(read, "TEXCOORD_1", TINYGLTF_TYPE_VEC2, uv_components, true);
        const auto file_normals =
            read_attribute<glm::vec3>(read, "NORMAL", TINYGLTF_TYPE_VEC3, {float_type}, false);
        const auto file_tangents =
            read_attribute<glm::vec4>(read, "TANGENT", TINYGLTF_TYPE_VEC4, {float_type}, false);

        fill_normals(primitive, file_normals, where);
        fill_tangents(primitive, file_tangents, where);
        for (const glm::vec3& position : primitive.positions) primitive.bounds.extend(position);
        return primitive;
    }

    static int attribute_accessor(const tinygltf::Primitive& source, const char* name) {
        const auto it = source.attributes.find(name);
        return it == source.attributes.end() ? -1 : it->second;
    }

    struct AttributeRead {
        const tinygltf::Primitive& source;
        const std::string& where;
        std::size_t vertex_count;
    };

    // An optional vertex attribute (empty when absent); it must match POSITION element for element.
    template <typename Vec>
    std::vector<Vec> read_attribute(const AttributeRead& read, const char* name, int type,
                                    std::initializer_list<int> components, bool normalized_ints) const {
        const int accessor = attribute_accessor(read.source, name);
        if (accessor < 0) return {};
        std::vector<Vec> values = read_vectors<Vec>(view_accessor(
            model_, accessor, fmt::format("{} {}", read.where, name), type, components, normalized_ints));
        if (values.size() != read.vertex_count) {
            reject(fmt::format("{}: {} has {} elements but POSITION has {}", read.where, name, values.size(),
                               read.vertex_count));
        }
        return values;
    }

    std::vector<std::uint32_t> read_primitive_indices(const tinygltf::Primitive& source,
                                                      const std::string& where, std::size_t vertex_count) {
        if (source.indices < 0) {  // non-indexed: the vertices in order
            std::vector<std::uint32_t> indices(vertex_count);
            for (std::size_t i = 0; i < vertex_count; ++i) indices[i] = static_cast<std::uint32_t>(i);
            return indices;
        }
        std::vector<std::uint32_t> indices = read_indices(
            view_accessor(model_, source.indices, where + " indices", TINYGLTF_TYPE_SCALAR,
                          {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                           TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
                          false));
        for (std::size_t i = 0; i < indices.size(); ++i) {
            if (indices[i] >= vertex_count) {
                reject(fmt::format("{}: index {} at position {} is out of range ({} vertices)", where,
                                   indices[i], i, vertex_count));
            }
        }
        return indices;
    }

    void fill_normals(Primitive& primitive, const std::vector<glm::vec3>& file_normals,
                      const std::string& where) {
        if (file_normals.empty()) {
            primitive.normals = vertex_normals(primitive);
            return;
        }
        primitive.normals = file_normals;
        std::vector<glm::vec3> generated;  // only when the file has unusable normals
        std::size_t replaced = 0;
        for (std::size_t v = 0; v < primitive.normals.size(); ++v) {
            glm::vec3& normal = primitive.normals[v];
            const float length = glm::length(normal);
            if (length > 1e-12f && std::isfinite(length)) {
                normal /= length;
                continue;
            }
            if (generated.empty()) generated = vertex_normals(primitive);
            normal = generated[v];
            ++replaced;
        }
        if (replaced > 0) {
            warnings_.add(
                fmt::format("{}: {} zero or non-finite normals replaced by generated ones", where, replaced));
        }
    }

    void fill_tangents(Primitive& primitive, const std::vector<glm::vec4>& file_tangents,
                       const std::string& where) {
        const std::size_t vertex_count = primitive.positions.size();
        if (!file_tangents.empty()) {
            // Made orthogonal to the (possibly repaired) normal; one along the normal gives no frame.
            primitive.tangents.resize(vertex_count);
            std::size_t replaced = 0;
            for (std::size_t v = 0; v < vertex_count; ++v) {
                const glm::vec3& normal = primitive.normals[v];
                const glm::vec3 xyz(file_tangents[v]);
                const glm::vec3 orthogonal = xyz - normal * glm::dot(normal, xyz);
                const float length = glm::length(orthogonal);
                if (length > 1e-6f * std::max(glm::length(xyz), 1e-30f) && std::isfinite(length)) {
                    primitive.tangents[v] = {orthogonal / length, file_tangents[v].w < 0.0f ? -1.0f : 1.0f};
                } else {
                    primitive.tangents[v] = fallback_tangent(normal);
                    ++replaced;
                }
            }
            if (replaced > 0) {
                warnings_.add(
                    fmt::format("{}: {} tangents that are zero, non-finite or along the normal "
                                "were replaced",
                                where, replaced));
            }
            return;
        }
        const Material& material = scene_.material(primitive.material);
        const std::vector<glm::vec2>& uvs =
            material.normal_texture.uv_set == 1 ? primitive.uv1 : primitive.uv0;
        if (material.normal_texture.valid() && uvs.size() == vertex_count) {
            primitive.tangents = uv_tangents(primitive, uvs);
            return;
        }
        primitive.tangents.resize(vertex_count);
        for (std::size_t v = 0; v < vertex_count; ++v) {
            primitive.tangents[v] = fallback_tangent(primitive.normals[v]);
        }
    }

    // -- node hierarchy, lights and cameras

    const std::string& node_label(std::size_t index) const { return model_.nodes[index].name; }

    // Each node's parent (-1 for roots); a node with two parents or a cycle is refused, which also
    // bounds the traversal below by the node count.
    std::vector<int> parents() const {
        const std::size_t node_count = model_.nodes.size();
        std::vector<int> parent(node_count, -1);
        for (std::size_t n = 0; n < node_count; ++n) {
            for (const int child : model_.nodes[n].children) {
                if (child < 0 || static_cast<std::size_t>(child) >= node_count) {
                    reject(fmt::format("node {} ('{}') has child {} (there are {} nodes)", n, node_label(n),
                                       child, node_count));
                }
                if (static_cast<std::size_t>(child) == n) {
                    reject(fmt::format("node {} ('{}') is its own child: the node hierarchy has a cycle", n,
                                       node_label(n)));
                }
                int& slot = parent[static_cast<std::size_t>(child)];
                if (slot >= 0) {
                    reject(fmt::format("node {} ('{}') has two parents, nodes {} and {}", child,
                                       node_label(static_cast<std::size_t>(child)), slot, n));
                }
                slot = static_cast<int>(n);
            }
        }
        // Walk up from each node; meeting a node of the current walk again means a cycle.
        enum class State : std::uint8_t { unknown, walking, done };
        std::vector<State> state(node_count, State::unknown);
        std::vector<std::size_t> walk;
        for (std::size_t start = 0; start < node_count; ++start) {
            walk.clear();
            int at = static_cast<int>(start);
            while (at >= 0 && state[static_cast<std::size_t>(at)] == State::unknown) {
                state[static_cast<std::size_t>(at)] = State::walking;
                walk.push_back(static_cast<std::size_t>(at));
                at = parent[static_cast<std::size_t>(at)];
            }
            if (at >= 0 && state[static_cast<std::size_t>(at)] == State::walking) {
                reject(fmt::format("node {} ('{}') is its own ancestor: the node hierarchy has a cycle", at,
                                   node_label(static_cast<std::size_t>(at))));
            }
            for (const std::size_t n : walk) state[n] = State::done;
        }
        return parent;
    }

    std::vector<int> root_nodes(const std::vector<int>& parent) {
        const int scene_index =
            model_.defaultScene >= 0 ? model_.defaultScene : (model_.scenes.empty() ? -1 : 0);
        if (scene_index >= 0 && static_cast<std::size_t>(scene_index) < model_.scenes.size()) {
            return model_.scenes[static_cast<std::size_t>(scene_index)].nodes;
        }
        if (scene_index >= 0 && !model_.scenes.empty()) {
            reject(fmt::format("the default scene {} does not exist (there are {} scenes)", scene_index,
                               model_.scenes.size()));
        }
        std::vector<int> roots;
        for (std::size_t n = 0; n < parent.size(); ++n) {
            if (parent[n] < 0) roots.push_back(static_cast<int>(n));
        }
        if (!model_.nodes.empty()) {
            warnings_.add(fmt::format("the file has no scenes; all {} root nodes are used", roots.size()));
        }
        return roots;
    }

    void flatten_nodes() {
        const std::vector<int> parent = parents();
        const std::vector<int> roots = root_nodes(parent);
        std::vector<bool> visited(model_.nodes.size(), false);
        std::vector<std::pair<int, glm::mat4>> pending;  // explicit stack: deep hierarchies are fine
        for (auto root = roots.rbegin(); root != roots.rend(); ++root) {
            if (*root < 0 || static_cast<std::size_t>(*root) >= model_.nodes.size()) {
                reject(
                    fmt::format("the scene lists node {} (there are {} nodes)", *root, model_.nodes.size()));
            }
            pending.emplace_back(*root, glm::mat4(1.0f));
        }
        while (!pending.empty()) {
            const auto [index, parent_world] = pending.back();
            pending.pop_back();
            if (visited[static_cast<std::size_t>(index)]) {
                warnings_.add(
                    fmt::format("node {} is reached twice from the scene; its second use is skipped", index));
                continue;
            }
            visited[static_cast<std::size_t>(index)] = true;
            const tinygltf::Node& node = model_.nodes[static_cast<std::size_t>(index)];
            const glm::mat4 world = parent_world * local_transform(node);
            add_node_contents(static_cast<std::size_t>(index), node, world);
            for (auto child = node.children.rbegin(); child != node.children.rend(); ++child) {
                pending.emplace_back(*child, world);
            }
        }
    }

    void add_node_contents(std::size_t index, const tinygltf::Node& node, const glm::mat4& world) {
        if (node.mesh >= 0) {
            if (static_cast<std::size_t>(node.mesh) >= scene_.meshes.size()) {
                reject(fmt::format("node {} ('{}') refers to mesh {} (there are {})", index, node.name,
                                   node.mesh, scene_.meshes.size()));
            }
            if (node.skin >= 0) warnings_.add(fmt::format("node {}: skinning is ignored (bind pose)", index));
            Object object;
            object.name = object_names_.claim(node.name, fmt::format("object_{}", scene_.objects.size()));
            object.mesh = node.mesh;
            object.initial_transform = object.transform = world;
            scene_.objects.push_back(std::move(object));
        }
        if (node.camera >= 0) add_camera(index, node, world);
        if (const tinygltf::Value* punctual = extension_object(node.extensions, "KHR_lights_punctual")) {
            if (const std::optional<double> light = number_member(*punctual, "light")) {
                add_light(index, node, static_cast<int>(*light), world);
            }
        }
    }

    void add_camera(std::size_t node_index, const tinygltf::Node& node, const glm::mat4& world) {
        if (static_cast<std::size_t>(node.camera) >= model_.cameras.size()) {
            reject(fmt::format("node {} ('{}') refers to camera {} (there are {})", node_index, node.name,
                               node.camera, model_.cameras.size()));
        }
        const tinygltf::Camera& source = model_.cameras[static_cast<std::size_t>(node.camera)];
        if (source.type != "perspective") {
            warnings_.add(
                fmt::format("camera {} ('{}') is {}; only perspective cameras are supported, skipped",
                            node.camera, source.name, source.type));
            return;
        }
        const double yfov = source.perspective.yfov;
        if (!(yfov > 0.0 && yfov < 3.14159265358979)) {
            reject(fmt::format("camera {} ('{}') has the vertical field of view {} (must be in (0, pi))",
                               node.camera, source.name, yfov));
        }
        Camera camera;
        camera.name = camera_names_.claim(!node.name.empty() ? node.name : source.name,
                                          fmt::format("camera_{}", scene_.cameras.size()));
        camera.position = glm::vec3(world[3]);
        camera.orientation = rotation_of(world);
        camera.vertical_fov = static_cast<float>(yfov);
        camera.z_near = static_cast<float>(std::max(source.perspective.znear, 0.0));
        camera.z_far = static_cast<float>(std::max(source.perspective.zfar, 0.0));  // 0 when absent: derived
        scene_.cameras.push_back(std::move(camera));
    }

    void add_light(std::size_t node_index, const tinygltf::Node& node, int light_index,
                   const glm::mat4& world) {
        if (light_index < 0 || static_cast<std::size_t>(light_index) >= model_.lights.size()) {
            reject(fmt::format("node {} ('{}') refers to light {} (there are {})", node_index, node.name,
                               light_index, model_.lights.size()));
        }
        const tinygltf::Light& source = model_.lights[static_cast<std::size_t>(light_index)];
        Light light;
        if (source.type == "point") {
            light.type = LightType::point;
        } else if (source.type == "spot") {
            light.type = LightType::spot;
        } else if (source.type == "directional") {
            light.type = LightType::directional;
        } else {
            warnings_.add(
                fmt::format("light {} has the unknown type '{}'; skipped", light_index, source.type));
            return;
        }
        light.name = light_names_.claim(!source.name.empty() ? source.name : node.name,
                                        fmt::format("light_{}", scene_.lights.size()));
        light.color = to_vec(source.color, glm::vec3(1.0f));
        // The number is taken as is and read radiometrically: W/sr for point and spot lights,
        // W/m^2 for directional ones (KHR_lights_punctual's photometric units are not converted).
        light.intensity = static_cast<float>(source.intensity);
        light.position = glm::vec3(world[3]);
        // The light shines along the node's local -Z.
        light.direction =
            normalized_or(glm::mat3(world) * glm::vec3(0.0f, 0.0f, -1.0f), glm::vec3(0.0f, 0.0f, -1.0f));
        if (light.type == LightType::spot) {
            constexpr float half_pi = 1.57079633f;
            light.outer_cone = std::clamp(static_cast<float>(source.spot.outerConeAngle), 1e-4f, half_pi);
            light.inner_cone =
                std::clamp(static_cast<float>(source.spot.innerConeAngle), 0.0f, light.outer_cone);
        }
        scene_.lights.push_back(std::move(light));
    }

    // Physically, a scene without lights or emission renders black; say so instead of leaving a
    // user to wonder (light.set adds a light).
    void warn_if_unlit() {
        if (!scene_.lights.empty()) return;
        for (const Material& material : scene_.materials) {
            if (glm::any(glm::greaterThan(material.emissive, glm::vec3(0.0f)))) return;
        }
        warnings_.add("the scene has no lights and no emissive materials: frames will be black until "
                      "a light is added (light.set)");
    }

    // A camera that sees the whole scene.
    void add_default_camera() {
        Camera camera = framing_camera(scene_.world_bounds());
        camera.name = camera_names_.claim("default", "default");
        scene_.cameras.push_back(std::move(camera));
    }

    const tinygltf::Model& model_;
    const LoadContext& context_;
    Warnings& warnings_;
    Scene scene_;
    std::map<std::pair<int, bool>, int> textures_made_;
    std::set<int> images_warned_;
    NameRegistry object_names_;
    NameRegistry camera_names_;
    NameRegistry light_names_;
};

// ------------------------------------------------------------------------------------------------
// The pipeline shared by both entry points.

struct Source {
    std::span<const std::uint8_t> bytes;
    std::string scene_name;
    std::string base_dir;        // where external files are looked up (files only)
    bool embedded_only = false;  // an upload: no file access at all
};

void log_tinygltf_warnings(const std::string& label, const std::string& text) {
    std::size_t start = 0;
    while (start < text.size()) {
        const std::size_t end = std::min(text.find('\n', start), text.size());
        if (end > start) log::warn("gltf", "{}: tinygltf: {}", label, text.substr(start, end - start));
        start = end + 1;
    }
}

std::string trimmed(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    return text;
}

Scene import_bytes(const Source& source, const std::string& label) {
    if (source.bytes.empty()) reject("the file is empty");
    if (source.bytes.size() > max_input_bytes) {
        reject(fmt::format("{} bytes is more than the limit of {}", source.bytes.size(), max_input_bytes));
    }
    Warnings warnings(label);
    const bool binary = has_glb_magic(source.bytes);
    const std::string_view json_text =
        binary ? glb_json_chunk(source.bytes)
               : std::string_view(reinterpret_cast<const char*>(source.bytes.data()), source.bytes.size());
    const Json document = parse_json(json_text);
    StructureCheck(warnings).document(document);
    check_extensions(document, warnings);
    if (source.embedded_only) refuse_external_uris(document);

    LoadContext context;
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(&decode_image, &context);
    if (source.embedded_only) {
        loader.SetFsCallbacks({&refuse_file_exists, &path_as_is, &refuse_read, &refuse_write, &context});
    } else {
        loader.SetFsCallbacks({&file_exists, &path_as_is, &read_file, &refuse_write, nullptr});
    }
    tinygltf::Model model;
    std::string error;
    std::string warning;
    const auto length = static_cast<unsigned int>(source.bytes.size());
    const bool loaded = binary ? loader.LoadBinaryFromMemory(&model, &error, &warning, source.bytes.data(),
                                                             length, source.base_dir)
                               : loader.LoadASCIIFromString(&model, &error, &warning, json_text.data(),
                                                            length, source.base_dir);
    if (!context.refused_paths.empty()) {
        reject(fmt::format("refers to the external file '{}'; an uploaded GLB must embed all its data",
                           context.refused_paths.front()));
    }
    if (!loaded) {
        reject(fmt::format("tinygltf could not load it: {}{}", trimmed(error),
                           warning.empty() ? "" : fmt::format(" (warnings: {})", trimmed(warning))));
    }
    log_tinygltf_warnings(label, warning);
    if (!error.empty()) log_tinygltf_warnings(label, error);  // non-fatal complaints

    Scene scene = Converter(model, context, warnings).convert(source.scene_name);
    scene.warnings = warnings.take();
    validate_finite(scene);
    return scene;
}

// Runs `import` and prefixes every InputError with the name of what was loaded.
template <typename Import>
Scene naming_faults(const std::string& label, Import&& import) {
    try {
        return import();
    } catch (const InputError& error) {
        throw InputError(fmt::format("{}: {}", label, error.what()));
    }
}

}  // namespace

Scene import_gltf_file(const std::filesystem::path& path) {
    const std::string label = path.filename().string();
    return naming_faults(label, [&] {
        std::error_code code;
        const std::uintmax_t size = std::filesystem::file_size(path, code);
        if (code) reject(fmt::format("cannot read {}: {}", path.string(), code.message()));
        if (size > max_input_bytes) {
            reject(fmt::format("{} bytes is more than the limit of {}", size, max_input_bytes));
        }
        std::ifstream stream(path, std::ios::binary);
        std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
        if (!stream ||
            !stream.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size))) {
            reject(fmt::format("cannot read {}", path.string()));
        }
        std::string extension = path.extension().string();
        std::transform(extension.begin(), extension.end(), extension.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (extension == ".glb" && !has_glb_magic(bytes)) reject("not a binary glTF: bad magic");
        Source source;
        source.bytes = bytes;
        source.scene_name = path.stem().string();
        source.base_dir = path.parent_path().string();
        return import_bytes(source, label);
    });
}

Scene import_glb_memory(std::span<const std::uint8_t> bytes, const std::string& name) {
    return naming_faults(name, [&] {
        if (!has_glb_magic(bytes)) reject("not a binary glTF: bad magic");
        Source source;
        source.bytes = bytes;
        source.scene_name = name;
        source.embedded_only = true;
        return import_bytes(source, name);
    });
}

}  // namespace bounce::scene
