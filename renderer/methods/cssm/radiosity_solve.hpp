// The hierarchical-radiosity solve on the `cssm` atlas (§4.1 to §4.3): direct light on every texel
// from the shadow-mapped lights (and emission), then each bounce gathered per texel over the cut
// through the hierarchy, batch by batch of subtrees, with the texels' exitance pulled up the tree
// before each gather and, at the end, their total for the final gather.
#pragma once

#include "renderer/methods/cssm/gather_tree.hpp"
#include "renderer/passes/shadow_maps.hpp"

namespace bounce::methods::cssm {

class RadiositySolve {
public:
    // Per-texel radiance for a bake of `texels` texels.
    void allocate(std::size_t texels);

    // Direct light on the atlas, then bounces 1 .. n-1 by hierarchical radiosity; the texels'
    // total exitance is pulled up the tree for the final gather (which makes bounce n). For the
    // per-texel display it runs all n bounces instead and sums their irradiance per texel.
    void solve(const FrameContext& frame, const GatherTree& tree, const passes::ShadowMaps& shadows,
               const GatherSettings& settings);

    // Each texel's irradiance of every bounce, summed (the per-texel display's).
    const gpu::Buffer& indirect() const { return indirect_; }
    std::size_t bytes() const {
        return direct_.bytes() + bounce_.bytes() + total_.bytes() + irradiance_.bytes() + indirect_.bytes() +
               spots_.bytes();
    }

private:
    void direct_light(const FrameContext& frame, const GatherTree& tree, const passes::ShadowMaps& shadows,
                      const GatherSettings& settings) const;
    // One bounce: every texel gathers from bounce_ into irradiance_; its exitance becomes the next
    // bounce's source and is added to total_. The first gathers the direct light (`from_direct`).
    void bounce(const FrameContext& frame, const GatherTree& tree, const GatherSettings& settings, bool from_direct);
    // The nodes' area-weighted mean of `source`, leaves first, then a level at a time upwards; with
    // `spots`, where it holds the lights' light (`holds_direct`), leaves send it from their spots.
    void pull(const FrameContext& frame, const GatherTree& tree, const gpu::Buffer& source, bool holds_direct,
              bool spots) const;

    gpu::Buffer direct_, bounce_, total_, irradiance_, indirect_;
    gpu::Buffer spots_;  // where the lights' light falls on each texel (CSSM_BINDING_TEXEL_SPOTS)
};

}  // namespace bounce::methods::cssm
