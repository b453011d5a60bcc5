// The sparse voxel octree of voxel cone tracing (paper §4), built and filled on the GPU.
//
// - Grid: leaf voxels (lattice points) `spacing` apart over the scene bounds plus a margin of
//   2.3 voxels (off the lattice, so no bounding wall lies on a lattice point); the root spans
//   2^(D+1) lattice intervals, so D follows from the scene extent and the requested resolution.
//   Nodes exist only where geometry is.
// - build(): voxelizes every triangle along its dominant axis into a fragment list (no full-size
//   grid), subdivides level by level (nodes in 2x2x2 tiles from a preallocated pool, an atomic
//   counter, the pool grown between levels to what the level flagged), and sums each fragment's
//   area, albedo, normal and emission into the leaf slot of its lattice point.
// - inject(): one photon per light-view texel into the leaves (flux by solid angle), radiance per
//   leaf slot, the leaf bricks, and the Gaussian mipmap of every inner level.
// - Bricks: 3x3x3 voxels on node corners in one RGBA16F 3D pool (premultiplied radiance, opacity),
//   brick i of node i, so hardware trilinear filtering works inside a brick.
// - Dense variant: the same passes over every level's full lattice in one 3D texture, no nodes.
// - Dynamic part: nodes for moving objects appended after the static tree, which is restored from
//   a copy before each update and never rebuilt.
#pragma once

#include "renderer/gpu/counter_buffer.hpp"
#include "renderer/passes/light_view_maps.hpp"
#include "renderer/passes/pass_context.hpp"

#include <array>
#include <functional>
#include <cstdint>
#include <vector>

namespace bounce::methods::vct {

struct OctreeGrid {
    glm::vec3 origin{0.0f};  // lattice point 0: the root's min corner
    float spacing = 1.0f;    // leaf voxel size
    int leaf_level = 0;      // D
    int lattice_max() const { return 2 << leaf_level; }  // last lattice coordinate per axis
};

// The grid with `resolution` leaf voxels across the largest extent of `bounds`. Throws InputError
// when the resolution needs more levels than the lattice packing holds.
OctreeGrid grid_for(const scene::Aabb& bounds, int resolution);

// The cones a gather traces (vct/cone.glsl): tangent-space axes with their cosine weights in w.
struct ConeSettings {
    std::vector<glm::vec4> cones;
    float tan_half_aperture = 0.5f;
    float step = 0.5f;          // in cone diameters
    float max_distance = 1.0f;  // world units
    float ao_lambda = 1.0f;
};

void set_cone_uniforms(const gpu::ShaderProgram& program, const ConeSettings& settings);

class SparseVoxelOctree {
public:
    struct Counts {
        std::size_t fragments = 0;
        std::size_t nodes = 0;
        std::size_t leaves = 0;
        std::size_t dynamic_nodes = 0;   // of `nodes`, appended for moving objects
        std::size_t dynamic_leaves = 0;  // of `leaves`
        std::size_t injected_photons = 0;
        std::size_t dropped_photons = 0;  // landed where no leaf is
        std::size_t stray_slots = 0;      // lattice points with flux but no surface
        float max_radiance = 0.0f;
    };

    // Which objects a voxelization draws (by index in the scene).
    using ObjectFilter = std::function<bool(std::size_t object)>;

    // The static part: the objects `include` accepts, voxelized, subdivided and summed from scratch
    // over a grid fitted to the whole scene. Drops any dynamic part.
    // `dense`: the same pipeline over the full lattice of every level in one 3D texture, with no
    // nodes (the sparse-versus-dense trade, measured).
    void build(const passes::PassContext& context, int resolution, const ObjectFilter& include, bool dense);
    bool dense() const { return dense_; }
    // The defines every program that reads the structure needs (DENSE, ANISOTROPIC).
    std::vector<std::string> program_defines() const;
    // The dynamic part (paper §4.2.2): the static tree is restored as the build left it, then the
    // objects `include` accepts are voxelized and their nodes appended after the static ones, so the
    // static part is never rebuilt. The light must be injected again afterwards.
    void update_dynamic(const passes::PassContext& context, const ObjectFilter& include);
    // How the inner levels filter the leaves:
    //   anisotropic: six directional voxels per inner voxel (paper §9) instead of one;
    //   one_sided:   with anisotropic, a leaf's light goes into the directional voxels of the
    //                directions that look at its surface's front, by the surface's projection across
    //                each (mipmap.comp). A leaf is otherwise lit from every side: a sunlit face's
    //                light reaches the face itself and the box's back, and a convex box's sunlit face
    //                gathered a tenth of its direct light from itself. Leaves stay opaque from every
    //                side, so a surface seen obliquely reads darker (the cones blend the directions by
    //                their squared components): better on scenes of solid walls, worse on the
    //                Cornell box's single sheets (docs/methods.md, "vct").
    struct Filtering {
        bool anisotropic = true;
        bool one_sided = false;
        bool operator==(const Filtering&) const = default;
    };
    // `second_bounce`: the leaves then gather the first bounce with these cones and the bricks and
    // mipmaps are rebuilt, so a gather from the octree sees two bounces.
    void inject(const passes::PassContext& context, const passes::LightViewMaps& maps, Filtering filtering,
                const ConeSettings* second_bounce);
    // Every light's power scaled by `factor` (> 0) since the last injection, and nothing else changed
    // (no surface emits: emission does not scale with the lights): light transport is linear in the
    // lights' power, so the injected radiance and the bounce gathered from it scale by the factor too.
    // The pool stores radiance relative to the brightest voxel, so only that scale changes: the
    // same octree, to the last bit, as an injection at the new power would make up to the order its
    // float atomics add in. False, changing nothing, where the scaled brightest radiance would not
    // be a normal positive float (a factor far enough from 1 to underflow or overflow it): the
    // light must then be injected.
    bool scale_light(float factor);
    int bounces() const { return bounces_; }
    bool anisotropic() const { return filtering_.anisotropic; }
    const Filtering& filtering() const { return filtering_; }
    bool built() const { return built_; }

    // Binds the node buffers and the brick pool, and sets the octree uniforms of vct/octree.glsl
    // and the pool's of vct/cone_trace.frag.
    void bind_for_tracing(const gpu::ShaderProgram& program) const;

    const OctreeGrid& grid() const { return grid_; }
    const Counts& counts() const { return counts_; }
    std::size_t node_bytes() const { return node_children_.bytes() + node_coords_.bytes(); }
    std::size_t leaf_bytes() const {
        return leaf_sums_.bytes() + leaf_light_.bytes() + static_children_.bytes() + static_leaf_sums_.bytes();
    }
    std::size_t pool_bytes() const { return pool_.bytes() + directional_pool_.bytes(); }

    // What build() at this resolution will hold, before it runs. Dense: exact (every level's lattice
    // and every lattice point's leaf data). Sparse: the nodes depend on what the voxelization finds,
    // so leaf nodes are taken as twice the scene's surface area over a leaf node's face (a plane
    // aligned with the grid crosses its area's worth; oblique and curved surfaces up to about
    // twice that), capped by the full lattice.
    static std::uint64_t estimate_bytes(const scene::Scene& scene, int resolution, bool dense, bool anisotropic);

private:
    void voxelize(const passes::PassContext& context, const ObjectFilter& include);
    // Subdivides for the current fragments from the tree as it stands, appending nodes level by level.
    void subdivide(const passes::PassContext& context);
    // Sizes the leaf data for every leaf, keeping the first `kept_slots` slots, and sums the fragments.
    void accumulate_leaves(const passes::PassContext& context, std::size_t kept_slots);
    void allocate_pools();
    void allocate_dense_pool();
    // Leaf data slots: 8 per leaf, or one per lattice point (dense).
    std::size_t slot_count() const;
    // Scales the leaf radiance into the pool, fills the leaf bricks and mipmaps every inner level.
    void resolve_and_mipmap(const passes::PassContext& context);
    void ensure_node_capacity(std::size_t nodes);
    void set_octree_uniforms(const gpu::ShaderProgram& program) const;
    void bind_buffers() const;

    struct LevelRange {
        std::size_t first = 0;
        std::size_t count = 0;
    };

    OctreeGrid grid_;
    // Node ranges per level: one range per level for the static part, a second once a dynamic part
    // was appended. Leaves (level D) are the last range of each part.
    std::vector<std::vector<LevelRange>> levels_;
    std::vector<std::vector<LevelRange>> static_levels_;
    std::size_t static_node_count_ = 0;
    std::size_t static_leaves_ = 0;
    std::size_t node_count_ = 0;
    std::size_t node_capacity_ = 0;
    std::size_t fragment_capacity_ = 1 << 16;
    int bricks_per_axis_ = 0;
    int inner_bricks_per_axis_ = 0;
    Filtering filtering_{false, false};
    bool dense_ = false;
    bool built_ = false;
    std::array<int, 60> dense_z_{};  // VCT_MAX_DENSE_LAYERS: first z of each level's layer
    bool dense_pool_anisotropic_ = false;
    int bounces_ = 1;
    float radiance_scale_ = 1.0f;
    Counts counts_;
    gpu::CounterBuffer counters_;
    gpu::Buffer fragments_, node_children_, node_coords_, leaf_sums_, leaf_light_;
    gpu::Buffer static_children_, static_leaf_sums_;  // the static part as built, restored per update
    gpu::Texture pool_, directional_pool_;
    gpu::Framebuffer voxelize_target_;
};

}  // namespace bounce::methods::vct
