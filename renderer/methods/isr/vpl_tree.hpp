// The light-space side of image-space radiosity (paper §3.3-3.5): every light-view texel is a VPL
// carrying reflected flux; a pyramid of clustered patches over each view (the VPL tree, with the
// light-space min-max data that flags discontinuities) is built when the light-view maps change,
// and a VPL cache of the patches a frame gathers from is selected for the non-hierarchical modes.
#pragma once

#include "renderer/passes/light_view_maps.hpp"

#include <array>
#include <cstdint>

#include "isr/isr_layout.h"

namespace bounce::methods::isr {

struct VplTreeSettings {
    float depth_threshold = 0.0f;   // relative span of distances from the light
    float normal_threshold = 0.0f;  // normal-component span
};

class VplTree {
public:
    // What build() holds for `views` light views of `size`^2 texels: a node per texel of every
    // level up to the top patches, and the VPL cache.
    static std::uint64_t bytes_for(std::uint64_t views, int size);
    // Rebuilds the tree from the maps (every view) when the maps, the lights' power or the settings
    // changed (`inputs_changed`: the maps or the power); returns whether it did.
    bool build(const passes::PassContext& context, const passes::LightViewMaps& maps, bool inputs_changed,
               const VplTreeSettings& settings);
    // Fills the VPL cache from level `finest_level` up: naive point samples or basic clusters.
    void select(const passes::PassContext& context, int mode, int finest_level);
    // Binds the nodes, the cache and the tree's uniforms for a program that includes isr/vpl_tree.glsl.
    void bind(const gpu::ShaderProgram& program) const;
    int views() const { return views_; }
    int size() const { return size_; }
    int top_level() const { return top_level_; }
    // VPLs the last select() put in the cache (reads the count back).
    std::uint32_t cached_vpls() const;
    std::size_t nodes() const { return nodes_per_view_ * static_cast<std::size_t>(views_); }
    std::size_t bytes() const { return nodes_.bytes() + cache_.bytes() + info_.bytes(); }
    std::size_t builds() const { return builds_; }

private:
    int views_ = 0, size_ = 0, top_level_ = 0;
    std::size_t nodes_per_view_ = 0;
    std::array<std::uint32_t, ISR_MAX_TREE_LEVELS> level_offset_{};
    VplTreeSettings settings_;
    gpu::Buffer nodes_, cache_, info_;
    std::size_t builds_ = 0;
};

}  // namespace bounce::methods::isr
