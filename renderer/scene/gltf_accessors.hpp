// Accessors of a loaded glTF model: bounds checks and typed reads. Every bufferView is checked
// against its buffer and every accessor against its bufferView before anything is read.
#pragma once

#include "renderer/scene/gltf_detail.hpp"

#include <tiny_gltf.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <string>
#include <vector>

namespace bounce::scene::gltf {

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
void check_accessor_bounds(const tinygltf::Model& model);

// An accessor the caller wants to read, checked for its type and allowed component types.
AccessorView view_accessor(const tinygltf::Model& model, int index, const std::string& what, int wanted_type,
                           std::initializer_list<int> allowed_components, bool needs_normalized_ints);

// The elements as float vectors (glm::vec2, vec3 or vec4); normalized integers map to [0, 1] or
// [-1, 1] as the spec says.
template <typename Vec>
std::vector<Vec> read_vectors(const AccessorView& view);

std::vector<std::uint32_t> read_indices(const AccessorView& view);

template <typename T>
T load_unaligned(const std::uint8_t* at) {
    T value;
    std::memcpy(&value, at, sizeof(T));
    return value;
}

}  // namespace bounce::scene::gltf
