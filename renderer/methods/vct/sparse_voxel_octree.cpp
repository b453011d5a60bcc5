#include "renderer/methods/vct/sparse_voxel_octree.hpp"

#include "renderer/base/error.hpp"
#include "renderer/passes/light_geometry.hpp"
#include "renderer/scene/mesh_utils.hpp"
#include "vct/vct_layout.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>

namespace bounce::methods::vct {
namespace {

constexpr int kMaxLeafLevel = 8;  // lattice coordinates up to 2^9 fit the 10-bit packing
constexpr int kMaxDenseLeafLevel = 6;  // 129^3 lattice points: 86 MiB of leaf sums already

std::size_t grown(std::size_t needed) { return std::max<std::size_t>(needed + needed / 2, 1024); }

void clear_buffer(const gpu::Buffer& buffer) {
    glClearNamedBufferData(buffer.id(), GL_R32UI, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
}

int cube_side_for(std::size_t bricks) {
    int side = std::max(1, static_cast<int>(std::ceil(std::cbrt(static_cast<double>(bricks)) - 1e-9)));
    while (static_cast<std::size_t>(side) * side * side < bricks) ++side;
    return side;
}

gpu::Buffer copy_grown(const gpu::Buffer& old, std::size_t bytes) {
    gpu::Buffer bigger(bytes, nullptr);
    if (old) glCopyNamedBufferSubData(old.id(), bigger.id(), 0, 0, static_cast<GLsizeiptr>(old.bytes()));
    return bigger;
}

}  // namespace

void set_cone_uniforms(const gpu::ShaderProgram& program, const ConeSettings& settings) {
    glProgramUniform4fv(program.id(), glGetUniformLocation(program.id(), "u_cones"),
                        static_cast<GLsizei>(settings.cones.size()), &settings.cones[0].x);
    program.set("u_cone_count", static_cast<int>(settings.cones.size()));
    program.set("u_cone_tan", settings.tan_half_aperture);
    program.set("u_step", settings.step);
    program.set("u_max_distance", settings.max_distance);
    program.set("u_ao_lambda", settings.ao_lambda);
}

// Lattice spacings between the scene bounds and the grid's first lattice point (grid_for).
constexpr float kGridMargin = 2.3f;

OctreeGrid grid_for(const scene::Aabb& bounds, int resolution) {
    if (bounds.empty()) BOUNCE_FAIL("the scene has no geometry to voxelize");
    const glm::vec3 extent = bounds.extent();
    const float largest = std::max({extent.x, extent.y, extent.z});
    OctreeGrid grid;
    grid.spacing = largest > 0.0f ? largest / static_cast<float>(resolution) : 1.0f;
    // A margin of over two voxels on each side keeps every surface voxel's neighbours inside the
    // root. It is not a whole number of voxels: voxelization and light injection bracket a surface
    // between two lattice points by floor() along its normal, and a surface on a lattice point (the
    // scene's bounding walls, with a whole margin) is bracketed by one pair or the next as rounding
    // goes, so its area and its photons took different pairs at one scale and the same at another
    // (vct's frame moved by 1% between scales, 2.5x at single pixels). 0.3 of a voxel puts
    // surfaces at any binary fraction of a voxel from the bounds far from both floor()'s ties and
    // round()'s, which picks the column across the normal.
    const int intervals = resolution + 5;
    grid.leaf_level = std::max(1, static_cast<int>(std::ceil(std::log2(static_cast<double>(intervals)))) - 1);
    if (grid.leaf_level > kMaxLeafLevel) {
        throw InputError(fmt::format("vct resolution {} needs octree depth {}; at most {} levels are supported",
                                     resolution, grid.leaf_level, kMaxLeafLevel));
    }
    grid.origin = bounds.min - kGridMargin * grid.spacing;
    return grid;
}

std::uint64_t SparseVoxelOctree::estimate_bytes(const scene::Scene& scene, int resolution, bool dense, bool anisotropic) {
    const scene::Aabb bounds = scene.world_bounds();
    if (bounds.empty()) return 0;
    const OctreeGrid grid = grid_for(bounds, resolution);
    const std::uint64_t side = static_cast<std::uint64_t>(grid.lattice_max()) + 1;
    constexpr std::uint64_t kSlotBytes = VCT_LEAF_SUM_WORDS * 4 + 3 * sizeof(float);  // leaf sums, leaf light
    constexpr std::uint64_t kBrickBytes = VCT_BRICK * VCT_BRICK * VCT_BRICK * 8;       // RGBA16F
    if (dense) {
        std::uint64_t z = side;
        for (int level = grid.leaf_level - 1; level >= 0; --level) z += (anisotropic ? 6u : 1u) * ((2u << level) + 1u);
        return side * side * z * 8 + side * side * side * kSlotBytes;
    }
    const double leaf_face = 2.0 * static_cast<double>(grid.spacing);
    const double leaf_nodes_across = static_cast<double>(1u << grid.leaf_level);
    const double leaves = std::clamp(2.0 * scene::surface_area(scene) / (leaf_face * leaf_face), 1.0,
                                     leaf_nodes_across * leaf_nodes_across * leaf_nodes_across);
    const auto nodes = static_cast<std::uint64_t>(leaves * 4.0 / 3.0);  // each level up: a quarter of the one below
    const auto bricks_per_axis = static_cast<std::uint64_t>(cube_side_for(nodes));
    const std::uint64_t pool = bricks_per_axis * bricks_per_axis * bricks_per_axis * kBrickBytes;
    const std::uint64_t directional = anisotropic ? static_cast<std::uint64_t>(6.0 * leaves / 3.0) * kBrickBytes : 0;
    return pool + directional + static_cast<std::uint64_t>(8.0 * leaves) * kSlotBytes + nodes * 9 * sizeof(std::uint32_t);
}

void SparseVoxelOctree::build(const passes::PassContext& context, int resolution, const ObjectFilter& include,
                              bool dense) {
    grid_ = grid_for(context.scene.world_bounds(), resolution);
    dense_ = dense;
    if (dense && grid_.leaf_level > kMaxDenseLeafLevel) {
        throw InputError(fmt::format("vct dense: resolution {} needs a {}^3 lattice; at most resolution {} ({}^3) is "
                                     "supported densely (the sparse octree has no such limit)",
                                     resolution, grid_.lattice_max() + 1, (2 << kMaxDenseLeafLevel) - 5,
                                     (2 << kMaxDenseLeafLevel) + 1));
    }
    if (!counters_) counters_ = gpu::CounterBuffer(VCT_COUNTERS);
    voxelize(context, include);
    if (dense) {
        node_children_ = gpu::Buffer();
        node_coords_ = gpu::Buffer();
        node_capacity_ = 0;
        node_count_ = 0;
        levels_.clear();
        static_levels_.clear();
        counts_.nodes = counts_.leaves = counts_.dynamic_nodes = counts_.dynamic_leaves = 0;
        accumulate_leaves(context, 0);
        fragments_ = gpu::Buffer();
        static_children_ = gpu::Buffer();
        static_leaf_sums_ = gpu::Buffer(leaf_sums_.bytes(), nullptr);
        glCopyNamedBufferSubData(leaf_sums_.id(), static_leaf_sums_.id(), 0, 0, static_cast<GLsizeiptr>(leaf_sums_.bytes()));
        allocate_pools();
        built_ = true;
        return;
    }
    node_count_ = 1;
    ensure_node_capacity(std::max<std::size_t>(node_capacity_, 4096));
    clear_buffer(node_children_);
    clear_buffer(node_coords_);  // the root: cell 0, level 0
    levels_.assign(1, {{0, 1}});
    subdivide(context);
    static_leaves_ = levels_.back().front().count;
    counts_.leaves = static_leaves_;
    counts_.dynamic_nodes = counts_.dynamic_leaves = 0;
    accumulate_leaves(context, 0);
    fragments_ = gpu::Buffer();  // only builds read them

    // What update_dynamic() restores.
    static_levels_ = levels_;
    static_node_count_ = node_count_;
    static_children_ = gpu::Buffer(node_count_ * sizeof(std::uint32_t), nullptr);
    glCopyNamedBufferSubData(node_children_.id(), static_children_.id(), 0, 0,
                             static_cast<GLsizeiptr>(static_children_.bytes()));
    static_leaf_sums_ = gpu::Buffer(leaf_sums_.bytes(), nullptr);
    glCopyNamedBufferSubData(leaf_sums_.id(), static_leaf_sums_.id(), 0, 0, static_cast<GLsizeiptr>(leaf_sums_.bytes()));
    allocate_pools();
    built_ = true;
}

void SparseVoxelOctree::update_dynamic(const passes::PassContext& context, const ObjectFilter& include) {
    BOUNCE_CHECK(built(), "vct: dynamic objects voxelized before the static octree was built");
    if (dense_) {
        voxelize(context, include);
        accumulate_leaves(context, slot_count());
        fragments_ = gpu::Buffer();
        return;
    }
    glCopyNamedBufferSubData(static_children_.id(), node_children_.id(), 0, 0,
                             static_cast<GLsizeiptr>(static_children_.bytes()));
    levels_ = static_levels_;
    node_count_ = static_node_count_;
    voxelize(context, include);
    subdivide(context);
    counts_.dynamic_nodes = node_count_ - static_node_count_;
    counts_.dynamic_leaves = levels_.back().size() > 1 ? levels_.back().back().count : 0;
    counts_.leaves = static_leaves_ + counts_.dynamic_leaves;
    const std::size_t static_slots = static_leaves_ * 8;
    accumulate_leaves(context, static_slots);
    fragments_ = gpu::Buffer();
    allocate_pools();
}

std::size_t SparseVoxelOctree::slot_count() const {
    if (!dense_) return counts_.leaves * 8;
    const auto side = static_cast<std::size_t>(grid_.lattice_max() + 1);
    return side * side * side;
}

std::vector<std::string> SparseVoxelOctree::program_defines() const {
    std::vector<std::string> defines;
    if (dense_) defines.push_back("DENSE");
    if (filtering_.anisotropic) defines.push_back("ANISOTROPIC");
    if (filtering_.anisotropic && filtering_.one_sided) defines.push_back("ONE_SIDED_LEAVES");
    return defines;
}

void SparseVoxelOctree::allocate_dense_pool() {
    if (pool_ && dense_pool_anisotropic_ == filtering_.anisotropic) return;
    // Level D once, then every inner level once or (anisotropic) six times, stacked along z.
    const int side = grid_.lattice_max() + 1;
    int z = 0;
    dense_z_.fill(0);
    dense_z_[static_cast<std::size_t>(grid_.leaf_level * 6)] = z;
    z += side;
    for (int level = grid_.leaf_level - 1; level >= 0; --level) {
        for (int k = 0; k < (filtering_.anisotropic ? 6 : 1); ++k) {
            dense_z_[static_cast<std::size_t>(level * 6 + k)] = z;
            z += (2 << level) + 1;
        }
    }
    GLint max_3d = 0;
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_3d);
    if (z > max_3d) {
        throw InputError(fmt::format("vct dense: the levels need a {}x{}x{} texture; the GPU allows {} per side", side,
                                     side, z, max_3d));
    }
    pool_ = gpu::Texture({GL_TEXTURE_3D, GL_RGBA16F, side, side, z});
    pool_.set_filter(GL_LINEAR, GL_LINEAR);
    pool_.set_wrap(GL_CLAMP_TO_EDGE);
    dense_pool_anisotropic_ = filtering_.anisotropic;
}

void SparseVoxelOctree::allocate_pools() {
    leaf_light_ = gpu::Buffer(std::max<std::size_t>(slot_count(), 1) * 3 * sizeof(float), nullptr);
    directional_pool_ = gpu::Texture();  // sized at injection
    if (dense_) {
        pool_ = gpu::Texture();  // sized at injection, by the anisotropic knob
        return;
    }
    const int bricks_per_axis = cube_side_for(node_count_);
    if (pool_ && bricks_per_axis == bricks_per_axis_) return;
    bricks_per_axis_ = bricks_per_axis;
    GLint max_3d = 0;
    glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_3d);
    const int pool_side = VCT_BRICK * bricks_per_axis_;
    if (pool_side > max_3d) {
        throw InputError(fmt::format("vct: {} octree nodes need a {}^3 brick pool; the GPU allows {}^3 (lower "
                                     "the resolution)",
                                     node_count_, pool_side, max_3d));
    }
    pool_ = gpu::Texture({GL_TEXTURE_3D, GL_RGBA16F, pool_side, pool_side, pool_side});
    pool_.set_filter(GL_LINEAR, GL_LINEAR);
    pool_.set_wrap(GL_CLAMP_TO_EDGE);
}

void SparseVoxelOctree::voxelize(const passes::PassContext& context, const ObjectFilter& include) {
    gpu::GpuTimers::Scope timing(context.timers, "vct_voxelize");
    const int lattice_points = grid_.lattice_max() + 1;
    glNamedFramebufferParameteri(voxelize_target_.id(), GL_FRAMEBUFFER_DEFAULT_WIDTH, lattice_points);
    glNamedFramebufferParameteri(voxelize_target_.id(), GL_FRAMEBUFFER_DEFAULT_HEIGHT, lattice_points);
    const gpu::ShaderProgram& program =
        context.shaders.get({"passes/gbuffer.vert", "vct/voxelize.frag", {}, "vct/voxelize.geom", ""});
    program.use();
    program.set("u_view_proj", glm::mat4(1.0f));
    program.set("u_grid_origin", grid_.origin);
    program.set("u_lattice_spacing", grid_.spacing);
    program.set("u_viewport_texels", static_cast<float>(lattice_points));
    program.set("u_lattice_max", static_cast<unsigned>(grid_.lattice_max()));
    context.state.apply({.depth_test = false, .depth_write = false, .cull = gpu::Cull::none});
    glBindFramebuffer(GL_FRAMEBUFFER, voxelize_target_.id());
    glViewport(0, 0, lattice_points, lattice_points);
    for (int attempt = 0; attempt < 2; ++attempt) {
        if (!fragments_ || fragments_.bytes() < fragment_capacity_ * VCT_FRAGMENT_WORDS * 4) {
            fragments_ = gpu::Buffer(fragment_capacity_ * VCT_FRAGMENT_WORDS * 4, nullptr);
        }
        counters_.reset();
        counters_.bind(VCT_BINDING_COUNTERS);
        gpu::bind_storage(VCT_BINDING_FRAGMENTS, fragments_);
        program.set("u_fragment_capacity", static_cast<unsigned>(fragment_capacity_));
        context.gpu_scene.for_each_primitive([&](const scene::Object& object, const gpu::GpuPrimitive& primitive) {
            if (!include(static_cast<std::size_t>(&object - context.scene.objects.data()))) return;
            gpu::set_object_transform(program, object.transform);
            context.gpu_scene.bind_material(program, primitive.material);
            gpu::GpuScene::draw(primitive);
        });
        gpu::storage_barrier();
        counts_.fragments = counters_.read()[VCT_COUNTER_FRAGMENTS];
        if (counts_.fragments <= fragment_capacity_) return;
        fragment_capacity_ = grown(counts_.fragments);  // the list overflowed: voxelize again, once
    }
    BOUNCE_FAIL("vct voxelization kept overflowing its fragment list ({} fragments)", counts_.fragments);
}

void SparseVoxelOctree::subdivide(const passes::PassContext& context) {
    gpu::GpuTimers::Scope timing(context.timers, "vct_octree_build");
    const gpu::ShaderProgram& flag = context.shaders.get(gpu::ProgramSource::compute_shader("vct/flag_nodes.comp"));
    const gpu::ShaderProgram& allocate =
        context.shaders.get(gpu::ProgramSource::compute_shader("vct/allocate_nodes.comp"));
    set_octree_uniforms(flag);
    set_octree_uniforms(allocate);
    flag.set("u_fragment_count", static_cast<unsigned>(counts_.fragments));
    const bool appending = levels_.size() > 1;  // a static tree is there: new nodes go after it
    for (int level = 0; level < grid_.leaf_level; ++level) {
        std::array<std::uint32_t, VCT_COUNTERS> counters{};
        counters[VCT_COUNTER_NODES] = static_cast<std::uint32_t>(node_count_);
        counters_.write(counters);
        bind_buffers();
        flag.set("u_level", static_cast<unsigned>(level));
        flag.dispatch_threads(counts_.fragments);
        gpu::storage_barrier();
        const std::size_t flagged = counters_.read()[VCT_COUNTER_FLAGGED];
        ensure_node_capacity(node_count_ + 8 * flagged);
        bind_buffers();
        for (const LevelRange& range : levels_[static_cast<std::size_t>(level)]) {
            allocate.set("u_first_node", static_cast<unsigned>(range.first));
            allocate.set("u_node_count", static_cast<unsigned>(range.count));
            allocate.dispatch_threads(range.count);
        }
        gpu::storage_barrier();
        const LevelRange children{node_count_, 8 * flagged};
        if (!appending) {
            levels_.push_back({children});
        } else if (flagged > 0) {
            levels_[static_cast<std::size_t>(level) + 1].push_back(children);
        }
        node_count_ += 8 * flagged;
        const std::size_t allocated = counters_.read()[VCT_COUNTER_NODES];
        BOUNCE_CHECK(allocated == node_count_, "vct octree level {}: {} nodes allocated, {} expected", level + 1,
                     allocated, node_count_);
    }
    counts_.nodes = node_count_;
}

void SparseVoxelOctree::accumulate_leaves(const passes::PassContext& context, std::size_t kept_slots) {
    gpu::GpuTimers::Scope timing(context.timers, "vct_leaf_sums");
    leaf_sums_ = gpu::Buffer(std::max<std::size_t>(slot_count(), 1) * VCT_LEAF_SUM_WORDS * 4, nullptr);
    clear_buffer(leaf_sums_);
    if (kept_slots > 0) {
        glCopyNamedBufferSubData(static_leaf_sums_.id(), leaf_sums_.id(), 0, 0,
                                 static_cast<GLsizeiptr>(kept_slots * VCT_LEAF_SUM_WORDS * 4));
    }
    const gpu::ShaderProgram& program =
        context.shaders.get(gpu::ProgramSource::compute_shader("vct/accumulate_leaves.comp", program_defines()));
    set_octree_uniforms(program);
    program.set("u_fragment_count", static_cast<unsigned>(counts_.fragments));
    bind_buffers();
    gpu::bind_storage(VCT_BINDING_FRAGMENTS, fragments_);
    program.dispatch_threads(counts_.fragments);
    gpu::storage_barrier();
}

void SparseVoxelOctree::inject(const passes::PassContext& context, const passes::LightViewMaps& maps,
                               Filtering filtering, const ConeSettings* second_bounce) {
    BOUNCE_CHECK(built(), "vct: light injected before the octree was built");
    filtering_ = filtering;
    const std::size_t slots = slot_count();
    {
        gpu::GpuTimers::Scope timing(context.timers, "vct_inject");
        clear_buffer(leaf_light_);
        counters_.reset();
        bind_buffers();
        const gpu::ShaderProgram& program = context.shaders.get(gpu::ProgramSource::compute_shader("vct/inject.comp", program_defines()));
        set_octree_uniforms(program);
        glBindTextureUnit(0, maps.position().id());
        glBindTextureUnit(1, maps.normal().id());
        program.set("u_size", maps.size());
        for (std::size_t v = 0; v < maps.views().size(); ++v) {
            const passes::LightViewMaps::View& view = maps.views()[v];
            const scene::Light& light = context.scene.lights[view.light];
            program.set("u_layer", static_cast<int>(v));
            program.set("u_view_forward", view.forward);
            program.set("u_texel_measure", view.texel_measure);
            passes::set_light_uniforms(program, light);
            program.dispatch_threads(static_cast<std::size_t>(maps.size()) * static_cast<std::size_t>(maps.size()));
        }
        gpu::storage_barrier();
        const gpu::ShaderProgram& radiance =
            context.shaders.get(gpu::ProgramSource::compute_shader("vct/leaf_radiance.comp", program_defines()));
        set_octree_uniforms(radiance);
        radiance.set("u_slot_count", static_cast<unsigned>(slots));
        radiance.dispatch_threads(slots);
        gpu::storage_barrier();
    }
    const gpu::CounterValues counters = counters_.read();
    counts_.injected_photons = counters[VCT_COUNTER_INJECTED_PHOTONS];
    counts_.dropped_photons = counters[VCT_COUNTER_DROPPED_PHOTONS];
    counts_.stray_slots = counters[VCT_COUNTER_STRAY_SLOTS];
    resolve_and_mipmap(context);
    bounces_ = 1;
    if (second_bounce == nullptr) return;
    {
        gpu::GpuTimers::Scope timing(context.timers, "vct_second_bounce");
        const gpu::ShaderProgram& program =
            context.shaders.get(gpu::ProgramSource::compute_shader("vct/bounce.comp", program_defines()));
        bind_for_tracing(program);
        set_cone_uniforms(program, *second_bounce);
        program.set("u_slot_count", static_cast<unsigned>(slots));
        program.dispatch_threads(slots);
        gpu::storage_barrier();
    }
    resolve_and_mipmap(context);
    bounces_ = 2;
}

bool SparseVoxelOctree::scale_light(float factor) {
    if (!(factor > 0.0f) || !std::isfinite(factor)) return false;
    if (!(counts_.max_radiance > 0.0f) || !std::isfinite(counts_.max_radiance)) return true;  // no voxel was lit
    const float scaled = counts_.max_radiance * factor;
    if (!std::isnormal(scaled) || !std::isnormal(1.0f / scaled)) return false;
    counts_.max_radiance = scaled;
    radiance_scale_ = 1.0f / scaled;
    return true;
}

void SparseVoxelOctree::resolve_and_mipmap(const passes::PassContext& context) {
    const bool anisotropic = filtering_.anisotropic;
    const gpu::CounterValues counters = counters_.read();
    counts_.max_radiance = std::bit_cast<float>(counters[VCT_COUNTER_MAX_RADIANCE]);
    // Half floats hold up to 65504: the pool stores radiance relative to the brightest voxel.
    radiance_scale_ = counts_.max_radiance > 0.0f && std::isfinite(counts_.max_radiance) ? 1.0f / counts_.max_radiance
                                                                                          : 1.0f;
    if (dense_) allocate_dense_pool();
    glBindImageTexture(VCT_IMAGE_POOL, pool_.id(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_RGBA16F);

    {
        gpu::GpuTimers::Scope timing(context.timers, "vct_bricks");
        const gpu::ShaderProgram& resolve =
            context.shaders.get(gpu::ProgramSource::compute_shader("vct/resolve_bricks.comp", program_defines()));
        set_octree_uniforms(resolve);
        resolve.set("u_leaf_count", static_cast<unsigned>(counts_.leaves));
        resolve.set("u_radiance_scale", radiance_scale_);
        resolve.dispatch_threads(dense_ ? slot_count() : counts_.leaves * 27);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    if (!anisotropic || dense_) {
        directional_pool_ = gpu::Texture();
    } else if (!directional_pool_) {
        // Inner nodes come before the last leaves: their bricks, six each, indexed by node.
        const std::size_t inner = levels_.back().back().first;
        inner_bricks_per_axis_ = cube_side_for(inner);
        const int side = VCT_BRICK * inner_bricks_per_axis_;
        GLint max_3d = 0;
        glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_3d);
        if (6 * side > max_3d) {
            throw InputError(fmt::format("vct: {} inner nodes need a {}x{}x{} directional pool; the GPU allows {} "
                                         "per side (lower the resolution or turn anisotropic off)",
                                         inner, side, side, 6 * side, max_3d));
        }
        directional_pool_ = gpu::Texture({GL_TEXTURE_3D, GL_RGBA16F, side, side, 6 * side});
        directional_pool_.set_filter(GL_LINEAR, GL_LINEAR);
        directional_pool_.set_wrap(GL_CLAMP_TO_EDGE);
    }
    if (directional_pool_) {
        glBindImageTexture(VCT_IMAGE_DIRECTIONAL_POOL, directional_pool_.id(), 0, GL_TRUE, 0, GL_READ_WRITE,
                           GL_RGBA16F);
    }
    gpu::GpuTimers::Scope timing(context.timers, "vct_mipmap");
    const gpu::ShaderProgram& mipmap =
        context.shaders.get(gpu::ProgramSource::compute_shader("vct/mipmap.comp", program_defines()));
    set_octree_uniforms(mipmap);
    for (int level = grid_.leaf_level - 1; level >= 0; --level) {
        mipmap.set("u_level", static_cast<unsigned>(level));
        // Anisotropic levels above the leaves take a thread per direction (see mipmap.comp).
        const std::size_t per_voxel = anisotropic && level + 1 < grid_.leaf_level ? 6 : 1;
        if (dense_) {
            const auto side = static_cast<std::size_t>((2 << level) + 1);
            mipmap.dispatch_threads(side * side * side * per_voxel);
            glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
            continue;
        }
        for (const LevelRange& range : levels_[static_cast<std::size_t>(level)]) {
            mipmap.set("u_first_node", static_cast<unsigned>(range.first));
            mipmap.set("u_node_count", static_cast<unsigned>(range.count));
            mipmap.dispatch_threads(range.count * 27 * per_voxel);
        }
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
}

void SparseVoxelOctree::bind_for_tracing(const gpu::ShaderProgram& program) const {
    set_octree_uniforms(program);
    bind_buffers();
    glBindTextureUnit(VCT_UNIT_POOL, pool_.id());
    program.set("u_pool_texel", 1.0f / glm::vec3(pool_.desc().width, pool_.desc().height, pool_.desc().depth));
    if (directional_pool_) {
        glBindTextureUnit(VCT_UNIT_DIRECTIONAL_POOL, directional_pool_.id());
        const float side = static_cast<float>(directional_pool_.width());
        program.set("u_directional_pool_texel", glm::vec3(1.0f / side, 1.0f / side, 1.0f / (6.0f * side)));
    }
    program.set("u_radiance_unscale", 1.0f / radiance_scale_);
}

void SparseVoxelOctree::ensure_node_capacity(std::size_t nodes) {
    if (nodes <= node_capacity_ && node_children_) return;
    const std::size_t capacity = std::max(nodes, grown(node_capacity_));
    node_children_ = copy_grown(node_children_, capacity * sizeof(std::uint32_t));
    node_coords_ = copy_grown(node_coords_, capacity * 4 * sizeof(std::uint32_t));
    node_capacity_ = capacity;
}

void SparseVoxelOctree::set_octree_uniforms(const gpu::ShaderProgram& program) const {
    program.set("u_leaf_level", static_cast<unsigned>(grid_.leaf_level));
    program.set("u_grid_origin", grid_.origin);
    program.set("u_lattice_spacing", grid_.spacing);
    program.set("u_bricks_per_axis", static_cast<unsigned>(std::max(bricks_per_axis_, 1)));
    program.set("u_inner_bricks_per_axis", static_cast<unsigned>(std::max(inner_bricks_per_axis_, 1)));
    if (dense_) {
        program.set("u_dense_side", static_cast<unsigned>(grid_.lattice_max() + 1));
        glProgramUniform1iv(program.id(), glGetUniformLocation(program.id(), "u_dense_z"),
                            static_cast<GLsizei>(dense_z_.size()), dense_z_.data());
    }
    const bool has_dynamic = levels_.size() > 1 && levels_.back().size() > 1;
    program.set("u_first_leaf", static_cast<unsigned>(levels_.empty() ? 0 : levels_.back().front().first));
    program.set("u_static_leaf_count", static_cast<unsigned>(static_leaves_));
    program.set("u_first_dynamic_leaf",
                has_dynamic ? static_cast<unsigned>(levels_.back().back().first) : 0xFFFFFFFFu);
}

void SparseVoxelOctree::bind_buffers() const {
    if (counters_) counters_.bind(VCT_BINDING_COUNTERS);
    gpu::bind_storage(VCT_BINDING_NODES, node_children_);
    gpu::bind_storage(VCT_BINDING_NODE_COORDS, node_coords_);
    gpu::bind_storage(VCT_BINDING_LEAF_SUMS, leaf_sums_);
    gpu::bind_storage(VCT_BINDING_LEAF_LIGHT, leaf_light_);
}

}  // namespace bounce::methods::vct
