// Where the resident bake's texels stand now, on the GPU: every texel at its object's current
// place with its material, every group's frame (which moves with its object), and the radiosity
// hierarchy over all texels, rebuilt whenever objects move; with the hull overlaps that make the
// moving objects' CSMs unreliable where they occur.
#pragma once

#include "renderer/methods/cssm/hull_overlap.hpp"
#include "renderer/methods/cssm/resident_bake.hpp"

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace bounce::methods::cssm {

class TexelPlacement {
public:
    // After a new bake: its texels as it placed them.
    void upload(const scene::Scene& scene, const ResidentBake& bake);
    // When objects moved since the last placement: their texels and the hierarchy over all texels
    // follow, on the CPU and the GPU; no bake.
    void follow(const scene::Scene& scene, ResidentBake& bake);
    // Counts uploads: what depends on the hierarchy's shape is redone when it changes.
    std::uint64_t version() const { return version_; }

    // The hierarchy, its pulled radiance and levels, the texels and the groups' frames.
    void bind() const;

    // The atlas's structure holds the solve's per-texel radiance too (`radiance_bytes`).
    ResidentStructure atlas_structure(const CssmBake& bake, std::size_t radiance_bytes) const;
    ResidentStructure tree_structure(const CssmBake& bake) const;
    std::size_t bytes() const { return atlas_bytes_ + tree_bytes_; }
    // Hull overlaps, placements, hierarchy nodes.
    void add_statistics(std::map<std::string, double>& stats, const CssmBake& bake) const;

private:
    void check_overlaps(const scene::Scene& scene, const std::vector<std::uint32_t>& moving);

    gpu::Buffer texels_, samples_, groups_, nodes_, node_light_, level_nodes_;
    std::vector<HullOverlap> overlaps_;
    std::uint64_t placed_geometry_ = 0, version_ = 0;
    std::size_t placements_ = 0, atlas_bytes_ = 0, tree_bytes_ = 0;
};

}  // namespace bounce::methods::cssm
