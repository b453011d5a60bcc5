// The hierarchy of `cssm`'s GPU hierarchical radiosity (§4.2 of
// [cssm] in docs/references.md): a binary median-cut tree over the atlas texels with a
// bounding sphere, a normal cone and the area of each node, stored depth-first as a linear array
// with child and skip pointers, so a traversal needs no stack: follow the child to refine, the skip
// to move past a subtree.
#pragma once

#include "renderer/methods/cssm/surface_atlas.hpp"

#include <cstdint>
#include <vector>

namespace bounce::methods::cssm {

constexpr std::uint32_t kNoNode = 0xFFFFFFFFu;

struct RadiosityNode {
    glm::vec3 centre{0.0f};  // world; the sphere holds every texel below
    float radius = 0.0f;
    glm::vec3 normal{0.0f, 0.0f, 1.0f};  // area-weighted mean normal (unit)
    float cone_cos = 1.0f;               // cosine of the cone around `normal` holding every texel normal
    float area = 0.0f;
    std::uint32_t child = kNoNode;  // left child (the next node); kNoNode for a leaf
    std::uint32_t skip = kNoNode;   // the node after this subtree; kNoNode at the end
    std::uint32_t representative = 0;  // the texel nearest the centre: its cube map answers for the node
    std::uint32_t texel = kNoNode;     // leaves: their texel
    std::uint32_t depth = 0;
    std::uint32_t leaves = 0;
};

struct RadiosityTree {
    std::vector<RadiosityNode> nodes;
    std::vector<std::uint32_t> level_nodes;  // internal nodes, deepest level first
    std::vector<std::uint32_t> level_first;  // offsets into level_nodes per level (deepest first), + end
    std::uint32_t depth = 0;

    // Subtree roots with at most `max_leaves` leaves each, maximal, in depth-first order: they
    // partition the leaves.
    std::vector<std::uint32_t> cut(std::uint32_t max_leaves) const;
};

// `positions` and `normals` are the texels' world positions and unit normals; `areas` theirs.
RadiosityTree build_radiosity_tree(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& normals,
                                   const std::vector<float>& areas);

}  // namespace bounce::methods::cssm
