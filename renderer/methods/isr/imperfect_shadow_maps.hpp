// isr's optional indirect visibility: imperfect shadow maps (Ritschel et al. 2008), one small
// paraboloid depth map per VPL-tree patch of one level, splatted from a random point cloud of the
// scene's surfaces (shaders/isr/ism.glsl). Built when the VPL tree is, or when the settings change;
// kept while only the camera moves.
#pragma once

#include "renderer/methods/isr/vpl_tree.hpp"

#include <cstdint>
#include <functional>

namespace bounce::methods::isr {

struct IsmSettings {
    int size = 0;              // texels per side of one map; 0: no visibility
    int points_per_map = 0;    // points splatted into each map
    int levels_below_top = 0;  // maps on the patches this many levels below the ISR_TOP_PATCHES^2 top patches
    // Pyramid levels (2x2 texels, 4x4) from which the push lets a nearer surface replace a texel's own
    // sample that lies behind it (shaders/isr/ism_push.comp): 0 fills empty texels alone.
    int dilation_levels = 2;
    bool operator==(const IsmSettings&) const = default;
};

class ImperfectShadowMaps {
public:
    // Points in the cloud the maps draw their subsets from.
    static constexpr std::uint32_t kCloudPoints = 1u << 18;
    // What build() holds for `views` light views of `rsm_size`^2 texels in a scene of `objects`
    // objects.
    static std::uint64_t bytes_for(std::uint64_t views, int rsm_size, const IsmSettings& settings, std::uint64_t objects);
    // The tree level whose patches carry maps.
    static int map_level(int tree_top_level, const IsmSettings& settings);

    // Splats and fills the maps when `patches` (the content hash of what the tree's patch centres and
    // poles depend on, IsrMethod's) changed since they were, or the settings did; returns whether it
    // did. Between batches of maps it calls `interruption` (which throws for a cancelled frame).
    bool build(const passes::PassContext& context, const VplTree& tree, const IsmSettings& settings,
               std::uint64_t patches, const std::function<void()>& interruption);
    // Binds the filled maps and sets isr/ism.glsl's uniforms (the tree's are VplTree::bind's).
    void bind(const gpu::ShaderProgram& program) const;
    // Frees the maps (a frame without visibility holds none); the next build() makes them again.
    void release();

    std::uint64_t maps() const { return maps_; }
    int level() const { return level_; }
    std::size_t builds() const { return builds_; }
    std::size_t bytes() const {
        return cloud_.bytes() + transforms_.bytes() + depth_.bytes() + filled_.bytes() + frames_.bytes() + coarse_.bytes();
    }

private:
    void make_cloud(const scene::Scene& scene);
    void set_uniforms(const gpu::ShaderProgram& program) const;

    IsmSettings settings_;
    std::uint64_t patches_ = 0;  // build()'s `patches` the maps were made for
    int level_ = 0;
    std::uint64_t maps_ = 0;
    float scene_radius_ = 1.0f;
    std::uint32_t cloud_points_ = 0;
    gpu::Buffer cloud_, transforms_, depth_, filled_, frames_, coarse_;
    std::size_t builds_ = 0;
};

}  // namespace bounce::methods::isr
