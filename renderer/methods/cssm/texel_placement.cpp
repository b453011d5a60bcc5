#include "renderer/methods/cssm/texel_placement.hpp"

#include "renderer/base/log.hpp"
#include "renderer/passes/light_geometry.hpp"

#include "cssm/cssm_layout.h"

#include <fmt/format.h>

namespace bounce::methods::cssm {

void TexelPlacement::upload(const scene::Scene& scene, const ResidentBake& resident) {
    const CssmBake& bake = resident.bake();
    const std::size_t texel_count = bake.texel_count();
    std::vector<glsl::CssmTexel> texels(texel_count);
    for (std::size_t t = 0; t < texel_count; ++t) {
        const std::uint32_t g = bake.texel_group[t];
        const std::uint32_t local = static_cast<std::uint32_t>(t - bake.group_first_texel[g]);
        texels[t] = {glm::vec4(bake.positions[t], bake.areas[t]),
                     glm::vec4(bake.normals[t], static_cast<float>(bake.groups[g].maps.map_of_texel[local])),
                     glm::vec4(bake.albedo[t], static_cast<float>(g)), glm::vec4(bake.emission[t], 0.0f)};
    }
    std::vector<glsl::CssmGroup> groups(bake.groups.size());
    for (std::size_t g = 0; g < groups.size(); ++g) {
        const BakeGroup& group = bake.groups[g];
        std::uint32_t csm = kNoNode;
        for (std::uint32_t c = 0, seen = 0; c <= g; ++c)
            if (bake.groups[c].csm) {
                if (c == g) csm = seen;
                ++seen;
            }
        groups[g] = {world_to_group(scene, group), glm::uvec4(resident.group_run_base(g), csm, 0, 0),
                     glm::vec4(group.maps.settings.near_plane, group.maps.settings.far_plane, 0.0f, 0.0f)};
    }
    std::vector<glsl::CssmNode> nodes(bake.tree.nodes.size());
    for (std::size_t n = 0; n < nodes.size(); ++n) {
        const RadiosityNode& node = bake.tree.nodes[n];
        nodes[n] = {glm::vec4(node.centre, node.radius), glm::vec4(node.normal, node.cone_cos),
                    glm::vec4(node.area, static_cast<float>(node.leaves), 0, 0),
                    glm::uvec4(node.child, node.skip, node.representative, node.texel)};
    }
    static_assert(CSSM_TEXEL_SAMPLES == kTexelSamples);
    std::vector<glm::vec4> samples(bake.samples.size());
    for (std::size_t i = 0; i < samples.size(); ++i) samples[i] = glm::vec4(bake.samples[i], 1.0f);
    texels_ = gpu::storage_of(texels);
    samples_ = gpu::storage_of(samples);
    groups_ = gpu::storage_of(groups);
    nodes_ = gpu::storage_of(nodes);
    node_light_ = gpu::Buffer(std::max<std::size_t>(1, nodes.size()) * sizeof(glsl::CssmNodeLight), nullptr, 0);
    level_nodes_ = gpu::storage_of(bake.tree.level_nodes);
    atlas_bytes_ = texels_.bytes() + samples_.bytes() + groups_.bytes();
    tree_bytes_ = nodes_.bytes() + node_light_.bytes() + level_nodes_.bytes();
    ++version_;
    check_overlaps(scene, bake.moving);
    placed_geometry_ = passes::geometry_fingerprint(scene);
}

void TexelPlacement::follow(const scene::Scene& scene, ResidentBake& resident) {
    if (passes::geometry_fingerprint(scene) == placed_geometry_) return;
    place_texels(scene, resident.bake());
    upload(scene, resident);
    ++placements_;
}

void TexelPlacement::check_overlaps(const scene::Scene& scene, const std::vector<std::uint32_t>& moving) {
    overlaps_ = find_hull_overlaps(scene, moving);
    for (const HullOverlap& overlap : overlaps_) {
        log::warn("cssm", "object '{}' reaches into the convex hull of moving object '{}': visibility through '{}' "
                  "is unreliable there (CSMs answer only outside their object's hull)",
                  scene.objects[overlap.other].name, scene.objects[overlap.moving].name, scene.objects[overlap.moving].name);
    }
}

void TexelPlacement::bind() const {
    gpu::bind_storage(CSSM_BINDING_NODES, nodes_);
    gpu::bind_storage(CSSM_BINDING_NODE_LIGHT, node_light_);
    gpu::bind_storage(CSSM_BINDING_LEVEL_NODES, level_nodes_);
    gpu::bind_storage(CSSM_BINDING_TEXELS, texels_);
    gpu::bind_storage(CSSM_BINDING_TEXEL_SAMPLES, samples_);
    gpu::bind_storage(CSSM_BINDING_GROUPS, groups_);
}

ResidentStructure TexelPlacement::atlas_structure(const CssmBake& bake, std::size_t radiance_bytes) const {
    return {"surface_atlas", atlas_bytes_ + radiance_bytes,
            fmt::format("{} texels over {} groups: senders, receivers and cube-map origins; radiance of each bounce",
                        bake.texel_count(), bake.groups.size())};
}

ResidentStructure TexelPlacement::tree_structure(const CssmBake& bake) const {
    return {"radiosity_tree", tree_bytes_,
            fmt::format("median-cut hierarchy of {} nodes, depth {}", bake.tree.nodes.size(), bake.tree.depth)};
}

void TexelPlacement::add_statistics(std::map<std::string, double>& stats, const CssmBake& bake) const {
    stats.insert({{"hull_overlaps", static_cast<double>(overlaps_.size())},
                  {"placements", static_cast<double>(placements_)},
                  {"tree_nodes", static_cast<double>(bake.tree.nodes.size())}});
}

}  // namespace bounce::methods::cssm
