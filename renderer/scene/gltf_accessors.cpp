#include "renderer/scene/gltf_accessors.hpp"

#include <glm/glm.hpp>

#include <algorithm>

namespace bounce::scene::gltf {
namespace {

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

}  // namespace

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

template std::vector<glm::vec2> read_vectors<glm::vec2>(const AccessorView&);
template std::vector<glm::vec3> read_vectors<glm::vec3>(const AccessorView&);
template std::vector<glm::vec4> read_vectors<glm::vec4>(const AccessorView&);

}  // namespace bounce::scene::gltf
