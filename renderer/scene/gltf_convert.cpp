#include "renderer/scene/gltf_convert.hpp"

#include "renderer/scene/gltf_accessors.hpp"
#include "renderer/scene/gltf_material_extensions.hpp"
#include "renderer/scene/gltf_images.hpp"
#include "renderer/scene/mesh_utils.hpp"
#include "renderer/scene/units.hpp"

#include <glm/gtc/type_ptr.hpp>
#include <glm/gtx/string_cast.hpp>

#include <algorithm>
#include <climits>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <tuple>
#include <utility>

namespace bounce::scene::gltf {
namespace {

// ------------------------------------------------------------------------------------------------
// Topology: strips and fans.

// Triangle lists from strips and fans, with the winding the spec gives for each triangle. Each
// list is reserved at its size: the scene's budget counts it so (gltf_budget.cpp).
std::vector<std::uint32_t> triangles_from_strip(const std::vector<std::uint32_t>& strip) {
    std::vector<std::uint32_t> out;
    if (strip.size() > 2) out.reserve(3 * (strip.size() - 2));
    for (std::size_t i = 0; i + 2 < strip.size(); ++i) {
        const bool odd = i % 2 == 1;
        out.insert(out.end(), {strip[i], strip[i + (odd ? 2 : 1)], strip[i + (odd ? 1 : 2)]});
    }
    return out;
}

std::vector<std::uint32_t> triangles_from_fan(const std::vector<std::uint32_t>& fan) {
    std::vector<std::uint32_t> out;
    if (fan.size() > 2) out.reserve(3 * (fan.size() - 2));
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

// Whether every coordinate of `point` lies within `limit` of the origin.
bool within(const glm::vec3& point, float limit) {
    return glm::all(glm::lessThanEqual(glm::abs(point), glm::vec3(limit)));  // false for NaN
}

template <typename Vec>
Vec to_vec(const std::vector<double>& values, const Vec& fallback, const std::string& what) {
    if (values.size() != static_cast<std::size_t>(Vec::length())) return fallback;
    Vec out;
    for (int i = 0; i < Vec::length(); ++i) out[i] = as_float(values[static_cast<std::size_t>(i)], what);
    return out;
}

glm::mat4 local_transform(const tinygltf::Node& node, std::size_t index) {
    const std::string where = fmt::format("node {}", index);
    if (node.matrix.size() == 16) {
        glm::mat4 matrix;
        for (int i = 0; i < 16; ++i) {
            glm::value_ptr(matrix)[i] = as_float(node.matrix[std::size_t(i)], where + " matrix");
        }
        return matrix;  // both glTF and glm are column-major
    }
    const glm::vec3 translation = to_vec(node.translation, glm::vec3(0.0f), where + " translation");
    const glm::vec3 scale = to_vec(node.scale, glm::vec3(1.0f), where + " scale");
    const glm::vec4 xyzw = to_vec(node.rotation, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f), where + " rotation");
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
        convert_materials();
        convert_meshes();
        flatten_nodes();
        scene_.fit_bounds();
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
            material.base_color = to_vec(pbr.baseColorFactor, glm::vec4(1.0f), where + " baseColorFactor");
            material.metallic = as_float(pbr.metallicFactor, where + " metallicFactor");
            material.roughness = as_float(pbr.roughnessFactor, where + " roughnessFactor");
            // Emission in nits (cd/m^2, KHR_materials_emissive_strength's unit for factor times
            // texture times strength), converted to radiance below.
            material.emissive = to_vec(source.emissiveFactor, glm::vec3(0.0f), where + " emissiveFactor");
            if (const tinygltf::Value* strength =
                    extension_object(source.extensions, "KHR_materials_emissive_strength")) {
                material.emissive *= as_float(number_member(*strength, "emissiveStrength").value_or(1.0),
                                              where + " emissiveStrength");
                if (!finite(material.emissive)) {
                    reject(fmt::format("{}: its emissive factor times its strength is past the range of a float",
                                       where));
                }
            }
            material.emissive *= static_cast<float>(radiometric_from_photometric(1.0));
            read_specular_extensions(source.extensions, material, where,
                                     [&](const tinygltf::TextureInfo& info, bool srgb, const std::string& what) {
                                         return texture_ref(info, srgb, what);
                                     });
            material.normal_scale = as_float(source.normalTexture.scale, where + " normalTexture.scale");
            material.double_sided = source.doubleSided;
            if (source.alphaMode == "MASK") {
                material.alpha_mode = scene::AlphaMode::mask;
                material.alpha_cutoff = as_float(source.alphaCutoff, where + " alphaCutoff");
                if (!(material.alpha_cutoff >= 0.0f)) reject(fmt::format("{}: alphaCutoff must be at least 0", where));
            } else if (source.alphaMode == "BLEND") {
                material.alpha_mode = scene::AlphaMode::blend;
                warnings_.add(fmt::format("{}: alphaMode BLEND is rendered as coverage, the surface there with "
                                          "probability alpha (dithered in GPU frames; no sorting, no refraction)",
                                          where));
            } else if (source.alphaMode != "OPAQUE" && !source.alphaMode.empty()) {
                reject(fmt::format("{}: alphaMode '{}' is none of OPAQUE, MASK, BLEND", where, source.alphaMode));
            }
            material.base_color_texture =
                texture_ref(pbr.baseColorTexture, true, where + " baseColorTexture");
            material.metallic_roughness_texture =
                texture_ref(pbr.metallicRoughnessTexture, false, where + " metallicRoughnessTexture");
            material.normal_texture = texture_ref(source.normalTexture, false, where + " normalTexture");
            material.emissive_texture = texture_ref(source.emissiveTexture, true, where + " emissiveTexture");
            scene_.materials.push_back(std::move(material));
        }
    }

    // A texture read through a UV set the primitive lacks: the set is filled with (0, 0), so that
    // every method and the reference read the same texel, and the file gets a warning (the Khronos
    // validator calls it an error, MESH_PRIMITIVE_TOO_FEW_TEXCOORDS; the factors still apply).
    void fill_missing_uvs(Primitive& primitive, const std::string& where) {
        if (primitive.material < 0 || static_cast<std::size_t>(primitive.material) >= scene_.materials.size()) return;
        const Material& material = scene_.materials[static_cast<std::size_t>(primitive.material)];
        for (const TextureRef* ref : {&material.base_color_texture, &material.metallic_roughness_texture,
                                      &material.normal_texture, &material.emissive_texture,
                                      &material.specular_texture, &material.specular_color_texture}) {
            if (!ref->valid()) continue;
            std::vector<glm::vec2>& uvs = ref->uv_set == 1 ? primitive.uv1 : primitive.uv0;
            if (uvs.size() == primitive.positions.size()) continue;
            warnings_.add(fmt::format("{}: material '{}' samples TEXCOORD_{}, which the primitive lacks; its "
                                      "textures read UV (0, 0) there", where, material.name, ref->uv_set));
            uvs.assign(primitive.positions.size(), glm::vec2(0.0f));
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
        int tex_coord = info.texCoord;
        if (const auto transform = info.extensions.find("KHR_texture_transform"); transform != info.extensions.end()) {
            ref.uv_transform = texture_transform(transform->second, where + " KHR_texture_transform", tex_coord);
        }
        if (tex_coord > 1) {
            warnings_.add(
                fmt::format("{} uses TEXCOORD_{}; only 0 and 1 are supported, the texture is ignored", where,
                            tex_coord));
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
        const int sampler = model_.textures[static_cast<std::size_t>(info.index)].sampler;
        const auto key = std::tuple{image_index, srgb, sampler};
        if (const auto made = textures_made_.find(key); made != textures_made_.end()) {
            ref.texture = made->second;
        } else {
            std::optional<Texture> texture = convert_image(image_index, info.index);
            if (!texture) return ref;
            texture->srgb = srgb;
            texture->sampler = texture_sampler(model_, sampler, fmt::format("texture {}", info.index));
            ref.texture = static_cast<int>(scene_.textures.size());
            scene_.textures.push_back(std::move(*texture));
            textures_made_[key] = ref.texture;
        }
        ref.uv_set = tex_coord;
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
        constexpr int i8 = TINYGLTF_COMPONENT_TYPE_BYTE, u8 = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
        constexpr int i16 = TINYGLTF_COMPONENT_TYPE_SHORT, u16 = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
        // KHR_mesh_quantization (gltfpack, gltf-transform) admits integer positions, normalized or
        // not (the node's transform dequantizes them), normalized integer normals and tangents, and
        // texture coordinates as any 8- or 16-bit integers.
        const bool quantized = uses_extension("KHR_mesh_quantization");
        const std::initializer_list<int> float_only = {float_type};
        const std::initializer_list<int> any_position = {float_type, i8, u8, i16, u16};
        const std::initializer_list<int> signed_normalized = {float_type, i8, i16};
        const int position_accessor = attribute_accessor(source, "POSITION");
        if (position_accessor < 0) reject(fmt::format("{} has no POSITION attribute", where));
        primitive.positions = read_vectors<glm::vec3>(view_accessor(
            model_, position_accessor, where + " POSITION", TINYGLTF_TYPE_VEC3, quantized ? any_position : float_only,
            false));
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

        // glTF numbers indexed attributes without gaps: TEXCOORD_1 needs a TEXCOORD_0.
        if (source.attributes.count("TEXCOORD_1") != 0 && source.attributes.count("TEXCOORD_0") == 0) {
            reject(fmt::format("{} has TEXCOORD_1 without TEXCOORD_0 (indexed attributes must be numbered "
                               "from 0 without gaps)", where));
        }
        const AttributeRead read{source, where, vertex_count};
        const std::initializer_list<int> uv_core = {float_type, u8, u16};  // named: a list's array lives with it
        const std::initializer_list<int>& uv_components = quantized ? any_position : uv_core;
        primitive.uv0 = read_attribute<glm::vec2>(read, "TEXCOORD_0", TINYGLTF_TYPE_VEC2, uv_components, !quantized);
        primitive.uv1 = read_attribute<glm::vec2>(read, "TEXCOORD_1", TINYGLTF_TYPE_VEC2, uv_components, !quantized);
        const auto file_normals = read_attribute<glm::vec3>(read, "NORMAL", TINYGLTF_TYPE_VEC3,
                                                            quantized ? signed_normalized : float_only, true);
        const auto file_tangents = read_attribute<glm::vec4>(read, "TANGENT", TINYGLTF_TYPE_VEC4,
                                                             quantized ? signed_normalized : float_only, true);

        fill_missing_uvs(primitive, where);
        fill_normals(primitive, file_normals, where);
        fill_tangents(primitive, file_tangents, where);
        for (const glm::vec3& position : primitive.positions) primitive.bounds.extend(position);
        return primitive;
    }

    bool uses_extension(const std::string& name) const {
        return std::find(model_.extensionsUsed.begin(), model_.extensionsUsed.end(), name) != model_.extensionsUsed.end();
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
        std::vector<glm::vec2> uvs = material.normal_texture.uv_set == 1 ? primitive.uv1 : primitive.uv0;
        if (material.normal_texture.valid() && uvs.size() == vertex_count) {
            // The tangent frame follows the normal map's own (transformed) texture space.
            for (glm::vec2& uv : uvs) uv = material.normal_texture.transform(uv);
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
        if (scene_index >= 0) {
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
            const glm::mat4 world = parent_world * local_transform(node, static_cast<std::size_t>(index));
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
                // Checked before the cast: a double past INT_MAX does not convert to int.
                if (!(*light >= 0.0 && *light <= INT_MAX && std::floor(*light) == *light)) {
                    reject(fmt::format("node {} names KHR_lights_punctual light {}, not an index", index, *light));
                }
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
        // Distances: within the scene's reach (max_world_coordinate), so that the projection stays
        // finite; 0 when absent: derived.
        auto distance = [&](double value, const char* field) {
            if (!(value <= max_world_coordinate)) {
                reject(fmt::format("camera {} ('{}') has the {} {:g}, past the limit of {:g} m", node.camera,
                                   source.name, field, value, max_world_coordinate));
            }
            return static_cast<float>(std::max(value, 0.0));
        };
        camera.z_near = distance(source.perspective.znear, "znear");
        camera.z_far = distance(source.perspective.zfar, "zfar");
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
        // The ranges light.set allows (docs/protocol.md, "Numbers"), so that colour times intensity
        // stays finite.
        const std::string what = fmt::format("light {} ('{}')", light_index, source.name);
        light.color = to_vec(source.color, glm::vec3(1.0f), what + " color");
        if (!glm::all(glm::greaterThanEqual(light.color, glm::vec3(0.0f))) ||
            !glm::all(glm::lessThanEqual(light.color, glm::vec3(max_light_color)))) {
            reject(fmt::format("{} has the color {}, outside [0, {:g}]", what, glm::to_string(light.color),
                               max_light_color));
        }
        // KHR_lights_punctual's units: candela for point and spot lights, lux for directional ones.
        if (!(source.intensity >= 0.0 && source.intensity <= max_light_intensity)) {
            reject(fmt::format("{} has the intensity {:g}, outside [0, {:g}]", what, source.intensity,
                               max_light_intensity));
        }
        light.intensity = static_cast<float>(radiometric_from_photometric(source.intensity));
        light.position = glm::vec3(world[3]);
        // The light shines along the node's local -Z.
        light.direction =
            normalized_or(glm::mat3(world) * glm::vec3(0.0f, 0.0f, -1.0f), glm::vec3(0.0f, 0.0f, -1.0f));
        if (light.type == LightType::spot) {
            constexpr float half_pi = 1.57079633f;
            light.outer_cone =
                std::clamp(as_float(source.spot.outerConeAngle, what + " outerConeAngle"), 1e-4f, half_pi);
            light.inner_cone =
                std::clamp(as_float(source.spot.innerConeAngle, what + " innerConeAngle"), 0.0f, light.outer_cone);
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
        if (!within(camera.position, max_eye_coordinate)) {
            reject(fmt::format("the file has no camera, and one that frames the whole scene would stand at {}, "
                               "past the limit of {:g} m from the origin on an axis",
                               glm::to_string(camera.position), max_eye_coordinate));
        }
        camera.name = camera_names_.claim("default", "default");
        scene_.cameras.push_back(std::move(camera));
    }

    const tinygltf::Model& model_;
    const LoadContext& context_;
    Warnings& warnings_;
    Scene scene_;
    std::map<std::tuple<int, bool, int>, int> textures_made_;  // (image, sRGB, sampler)
    std::set<int> images_warned_;
    NameRegistry object_names_;
    NameRegistry camera_names_;
    NameRegistry light_names_;
};

}  // namespace

void check_world_extent(const Scene& scene) {
    auto refuse = [](const std::string& what, const glm::vec3& point, float limit) {
        reject(fmt::format("{} lies at {}, past the limit of {:g} m from the origin on an axis", what,
                           glm::to_string(point), limit));
    };
    for (const Object& object : scene.objects) {
        if (object.mesh < 0 || static_cast<std::size_t>(object.mesh) >= scene.meshes.size()) continue;
        const Aabb bounds = object.world_bounds(scene.meshes[static_cast<std::size_t>(object.mesh)]);
        if (bounds.empty()) continue;
        for (const glm::vec3& corner : {bounds.min, bounds.max}) {
            if (!within(corner, max_world_coordinate)) {
                refuse(fmt::format("object '{}' (its world bounds)", object.name), corner, max_world_coordinate);
            }
        }
    }
    for (const Camera& camera : scene.cameras) {
        if (!within(camera.position, max_eye_coordinate)) {
            refuse(fmt::format("camera '{}'", camera.name), camera.position, max_eye_coordinate);
        }
    }
    for (const Light& light : scene.lights) {
        if (!within(light.position, max_eye_coordinate)) {
            refuse(fmt::format("light '{}'", light.name), light.position, max_eye_coordinate);
        }
    }
}

Scene convert_model(const tinygltf::Model& model, const LoadContext& context, Warnings& warnings,
                    std::string name) {
    return Converter(model, context, warnings).convert(std::move(name));
}

}  // namespace bounce::scene::gltf
