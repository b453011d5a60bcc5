#include "renderer/methods/cssm/radiosity_tree.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace bounce::methods::cssm {
namespace {

struct Builder {
    const std::vector<glm::vec3>& positions;
    const std::vector<glm::vec3>& normals;
    const std::vector<float>& areas;
    RadiosityTree& tree;
    glm::vec3 grid_origin{0.0f};
    glm::vec3 grid_scale{1.0f};  // 2^16 cells across the atlas's box per axis

    // Builds the subtree over texels [first, last) of `order`; returns its node index.
    std::uint32_t build(std::vector<std::uint32_t>& order, std::size_t first, std::size_t last, std::uint32_t depth) {
        const auto index = static_cast<std::uint32_t>(tree.nodes.size());
        tree.nodes.emplace_back();
        tree.depth = std::max(tree.depth, depth);
        RadiosityNode node;
        node.depth = depth;
        node.leaves = static_cast<std::uint32_t>(last - first);
        scene::Aabb bounds;
        glm::vec3 weighted_normal(0.0f), centroid(0.0f);
        for (std::size_t i = first; i < last; ++i) {
            const std::uint32_t t = order[i];
            bounds.extend(positions[t]);
            weighted_normal += areas[t] * normals[t];
            centroid += areas[t] * positions[t];
            node.area += areas[t];
        }
        node.centre = bounds.center();
        centroid = node.area > 0.0f ? centroid / node.area : node.centre;
        const float normal_length = glm::length(weighted_normal);
        node.normal = normal_length > 1e-20f ? weighted_normal / normal_length : normals[order[first]];
        float nearest = std::numeric_limits<float>::max();
        node.cone_cos = 1.0f;
        for (std::size_t i = first; i < last; ++i) {
            const std::uint32_t t = order[i];
            node.radius = std::max(node.radius, glm::length(positions[t] - node.centre));
            node.cone_cos = std::min(node.cone_cos, glm::dot(node.normal, normals[t]));
            // Nearest on a grid of 1/4096 of the extent, ties to the lower index: the same texel at
            // any scale (a regular grid of texels has many equidistant ones).
            const float d = std::floor(glm::length((positions[t] - centroid) * grid_scale) * (1.0f / 16.0f));
            if (d < nearest) {
                nearest = d;
                node.representative = t;
            }
        }
        if (last - first == 1) {
            node.texel = order[first];
        } else {
            // Median cut along the longest axis of the texels' box.
            const glm::vec3 extent = bounds.extent();
            const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
            const std::size_t middle = first + (last - first) / 2;
            // Keys on a grid over the whole atlas, ties broken by texel index: the tree is the same
            // at any uniform scale (coplanar texels tie exactly, and rounding must not reorder them).
            auto key = [&](std::uint32_t t) {
                return std::make_pair(static_cast<std::int64_t>(std::floor((positions[t][axis] - grid_origin[axis]) * grid_scale[axis])), t);
            };
            std::nth_element(order.begin() + static_cast<std::ptrdiff_t>(first), order.begin() + static_cast<std::ptrdiff_t>(middle),
                             order.begin() + static_cast<std::ptrdiff_t>(last),
                             [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
            node.child = build(order, first, middle, depth + 1);
            build(order, middle, last, depth + 1);
        }
        tree.nodes[index] = node;  // skip pointers are linked once the whole tree stands
        return index;
    }
};

// Skip pointers: a right child's skip is its parent's skip.
void link_skips(RadiosityTree& tree, std::uint32_t node, std::uint32_t after) {
    tree.nodes[node].skip = after;
    const std::uint32_t left = tree.nodes[node].child;
    if (left == kNoNode) return;
    const std::uint32_t right = left + 2 * tree.nodes[left].leaves - 1;  // depth-first: right follows the left subtree
    link_skips(tree, left, right);
    link_skips(tree, right, after);
}

}  // namespace

std::vector<std::uint32_t> RadiosityTree::cut(std::uint32_t max_leaves) const {
    std::vector<std::uint32_t> roots;
    if (nodes.empty()) return roots;
    std::uint32_t node = 0;
    while (node != kNoNode) {
        if (nodes[node].leaves <= std::max(max_leaves, 1u) || nodes[node].child == kNoNode) {
            roots.push_back(node);
            node = nodes[node].skip;
        } else {
            node = nodes[node].child;
        }
    }
    return roots;
}

RadiosityTree build_radiosity_tree(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& normals,
                                   const std::vector<float>& areas) {
    RadiosityTree tree;
    if (positions.empty()) return tree;
    std::vector<std::uint32_t> order(positions.size());
    std::iota(order.begin(), order.end(), 0u);
    tree.nodes.reserve(2 * positions.size());
    scene::Aabb bounds;
    for (const glm::vec3& p : positions) bounds.extend(p);
    const glm::vec3 extent = glm::max(bounds.extent(), glm::vec3(1e-30f));
    Builder{positions, normals, areas, tree, bounds.min, glm::vec3(65536.0f) / extent}.build(order, 0, order.size(), 0);
    link_skips(tree, 0, kNoNode);
    // Internal nodes by level, deepest first, for the pull.
    std::vector<std::vector<std::uint32_t>> by_level(tree.depth + 1);
    for (std::uint32_t n = 0; n < tree.nodes.size(); ++n)
        if (tree.nodes[n].child != kNoNode) by_level[tree.nodes[n].depth].push_back(n);
    for (std::size_t level = by_level.size(); level-- > 0;) {
        if (by_level[level].empty()) continue;
        tree.level_first.push_back(static_cast<std::uint32_t>(tree.level_nodes.size()));
        tree.level_nodes.insert(tree.level_nodes.end(), by_level[level].begin(), by_level[level].end());
    }
    tree.level_first.push_back(static_cast<std::uint32_t>(tree.level_nodes.size()));
    return tree;
}

}  // namespace bounce::methods::cssm
