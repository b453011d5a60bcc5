#include "renderer/scene/gltf_material_extensions.hpp"

#include "renderer/scene/gltf_detail.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>

namespace bounce::scene::gltf {

const tinygltf::Value* extension_object(const tinygltf::ExtensionMap& extensions, const std::string& name) {
    const auto it = extensions.find(name);
    if (it == extensions.end() || !it->second.IsObject()) return nullptr;
    return &it->second;
}

std::optional<double> number_member(const tinygltf::Value& object, const std::string& key) {
    if (!object.Has(key) || !object.Get(key).IsNumber()) return std::nullopt;
    return object.Get(key).GetNumberAsDouble();
}

float as_float(double value, const std::string& what) {
    if (!(std::abs(value) <= static_cast<double>(std::numeric_limits<float>::max()))) {
        reject(fmt::format("{} is {:g}, past the range of a float", what, value));
    }
    return static_cast<float>(value);
}

glm::mat3 texture_transform(const tinygltf::Value& value, const std::string& where, int& tex_coord) {
    if (!value.IsObject()) reject(fmt::format("{} must be an object", where));
    const auto pair = [&](const char* key, glm::vec2 fallback) {
        if (!value.Has(key)) return fallback;
        const tinygltf::Value& array = value.Get(key);
        if (!array.IsArray() || array.ArrayLen() != 2 || !array.Get(0).IsNumber() || !array.Get(1).IsNumber()) {
            reject(fmt::format("{} {} must be an array of 2 numbers", where, key));
        }
        return glm::vec2(as_float(array.Get(0).GetNumberAsDouble(), where + " " + key),
                         as_float(array.Get(1).GetNumberAsDouble(), where + " " + key));
    };
    const glm::vec2 offset = pair("offset", glm::vec2(0.0f));
    const glm::vec2 scale = pair("scale", glm::vec2(1.0f));
    float rotation = 0.0f;
    if (value.Has("rotation")) {
        if (!value.Get("rotation").IsNumber()) reject(fmt::format("{} rotation must be a number", where));
        rotation = as_float(value.Get("rotation").GetNumberAsDouble(), where + " rotation");
    }
    if (value.Has("texCoord")) {
        const tinygltf::Value& set = value.Get("texCoord");
        if (!set.IsInt() || set.GetNumberAsInt() < 0) {
            reject(fmt::format("{} texCoord must be a non-negative integer", where));
        }
        tex_coord = set.GetNumberAsInt();
    }
    const float c = std::cos(rotation), s = std::sin(rotation);
    const glm::mat3 translation(1, 0, 0, 0, 1, 0, offset.x, offset.y, 1);
    const glm::mat3 rotate(c, s, 0, -s, c, 0, 0, 0, 1);  // columns, as the specification writes them
    const glm::mat3 scaling(scale.x, 0, 0, 0, scale.y, 0, 0, 0, 1);
    return translation * rotate * scaling;
}

tinygltf::TextureInfo texture_info(const tinygltf::Value& value, const std::string& where) {
    if (!value.IsObject() || !value.Has("index") || !value.Get("index").IsInt()) {
        reject(fmt::format("{} must be an object with an integer index", where));
    }
    tinygltf::TextureInfo info;
    info.index = value.Get("index").GetNumberAsInt();
    if (value.Has("texCoord")) {
        if (!value.Get("texCoord").IsInt()) reject(fmt::format("{} texCoord must be an integer", where));
        info.texCoord = value.Get("texCoord").GetNumberAsInt();
    }
    if (value.Has("extensions")) {
        const tinygltf::Value& extensions = value.Get("extensions");
        if (!extensions.IsObject()) reject(fmt::format("{} extensions must be an object", where));
        for (const std::string& key : extensions.Keys()) info.extensions[key] = extensions.Get(key);
    }
    if (info.index < 0) reject(fmt::format("{} index must be at least 0", where));
    return info;
}

void read_specular_extensions(const tinygltf::ExtensionMap& extensions, Material& material, const std::string& where,
                              const TextureRefMaker& texture_ref) {
    if (const tinygltf::Value* specular = extension_object(extensions, "KHR_materials_specular")) {
        material.specular =
            as_float(number_member(*specular, "specularFactor").value_or(1.0), where + " specularFactor");
        if (specular->Has("specularColorFactor")) {
            const tinygltf::Value& colour = specular->Get("specularColorFactor");
            if (!colour.IsArray() || colour.ArrayLen() != 3) {
                reject(fmt::format("{} specularColorFactor must be an array of 3 numbers", where));
            }
            for (int c = 0; c < 3; ++c) {
                if (!colour.Get(c).IsNumber() || !(colour.Get(c).GetNumberAsDouble() >= 0.0)) {
                    reject(fmt::format("{} specularColorFactor must hold 3 numbers of at least 0", where));
                }
                material.specular_color[c] = as_float(colour.Get(c).GetNumberAsDouble(), where + " specularColorFactor");
            }
        }
        if (specular->Has("specularTexture")) {
            material.specular_texture = texture_ref(texture_info(specular->Get("specularTexture"),
                                                                 where + " specularTexture"),
                                                    false, where + " specularTexture");
        }
        if (specular->Has("specularColorTexture")) {
            material.specular_color_texture = texture_ref(
                texture_info(specular->Get("specularColorTexture"), where + " specularColorTexture"), true,
                where + " specularColorTexture");
        }
    }
    if (const tinygltf::Value* ior = extension_object(extensions, "KHR_materials_ior")) {
        // ior >= 1 (0, the extension's other allowed value, gives F0 = 1 through the same formula).
        const double value = number_member(*ior, "ior").value_or(1.5);
        if (!(value == 0.0 || value >= 1.0) || !std::isfinite(value)) {
            reject(fmt::format("{} ior is {}, not 0 or at least 1", where, value));
        }
        material.ior = static_cast<float>(value);
    }
}

}  // namespace bounce::scene::gltf
