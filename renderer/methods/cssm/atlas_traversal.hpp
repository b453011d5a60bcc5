// The order in which `cssm` visits atlas texels to bake their depth cube maps (§3.2.3): coherent
// orders keep consecutive cube maps close together, so each depth pixel's sequence changes rarely
// and compresses well.
//
// - zig-zag: each chart's bounding box row by row, alternating direction, skipping foreign texels;
// - spiral: along each chart's border with the outside on the left, inwards, backtracking when
//   boxed in;
// - greedy: no charts at all: from texel to the nearest unvisited texel in 3D (the paper's walk
//   over evenly spread surface samples, for meshes without a usable parametrization).
// Chart strategies chain charts by going next to the unvisited chart whose centroid is nearest the
// last texel visited.
#pragma once

#include "renderer/methods/cssm/surface_atlas.hpp"

#include <cstdint>
#include <string_view>
#include <vector>

namespace bounce::methods::cssm {

enum class Traversal { greedy = 0, zigzag = 1, spiral = 2 };

std::string_view traversal_name(Traversal traversal);

// Every texel index of the atlas exactly once, in visiting order. Positions are compared in world
// space at the objects' current transforms.
std::vector<std::uint32_t> traverse_atlas(const scene::Scene& scene, const SurfaceAtlas& atlas, Traversal traversal);

// The greedy walk alone: from the first point to the nearest unvisited one, each point once.
std::vector<std::uint32_t> greedy_walk(const std::vector<glm::vec3>& positions);

}  // namespace bounce::methods::cssm
