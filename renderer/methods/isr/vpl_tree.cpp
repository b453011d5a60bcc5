#include "renderer/methods/isr/vpl_tree.hpp"

#include "renderer/base/error.hpp"
#include "renderer/passes/light_geometry.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace bounce::methods::isr {
namespace {
constexpr std::size_t kNodeBytes = 6 * 16;  // VplNode in shaders/isr/vpl.glsl
constexpr std::size_t kVplBytes = 3 * 16;   // Vpl
constexpr std::size_t kCacheHeaderBytes = 16;
constexpr std::size_t kInfoBytes = 16;

void dispatch_2d(const gpu::ShaderProgram& program, int side) {
    program.use();
    const auto groups = static_cast<GLuint>((side + 7) / 8);
    glDispatchCompute(groups, groups, 1);
}

}  // namespace

std::uint64_t VplTree::bytes_for(std::uint64_t views, int size) {
    int top_level = 0;
    while ((size >> top_level) > ISR_TOP_PATCHES && top_level + 1 < ISR_MAX_TREE_LEVELS) ++top_level;
    std::uint64_t per_view = 0;
    for (int level = 0; level <= top_level; ++level) {
        per_view += static_cast<std::uint64_t>(size >> level) * static_cast<std::uint64_t>(size >> level);
    }
    const std::uint64_t nodes = std::max<std::uint64_t>(views * per_view, 1);
    return nodes * (kNodeBytes + kVplBytes) + kCacheHeaderBytes + kInfoBytes;
}

bool VplTree::build(const passes::PassContext& context, const passes::LightViewMaps& maps, bool inputs_changed,
                    const VplTreeSettings& settings) {
    const bool same_settings = settings.depth_threshold == settings_.depth_threshold &&
                               settings.normal_threshold == settings_.normal_threshold;
    if (!inputs_changed && same_settings && nodes_) return false;
    gpu::GpuTimers::Scope timing(context.timers, "isr_vpl_tree");
    settings_ = settings;
    ++builds_;
    views_ = static_cast<int>(maps.views().size());
    size_ = maps.size();
    BOUNCE_CHECK((size_ & (size_ - 1)) == 0 && size_ >= 1, "VPL tree over light-view maps of {} texels: not a power of two",
                 size_);
    top_level_ = 0;
    while ((size_ >> top_level_) > ISR_TOP_PATCHES && top_level_ + 1 < ISR_MAX_TREE_LEVELS) ++top_level_;
    nodes_per_view_ = 0;
    for (int level = 0; level <= top_level_; ++level) {
        level_offset_[static_cast<std::size_t>(level)] = static_cast<std::uint32_t>(nodes_per_view_);
        nodes_per_view_ += static_cast<std::size_t>(size_ >> level) * static_cast<std::size_t>(size_ >> level);
    }
    const std::size_t node_bytes = std::max<std::size_t>(nodes(), 1) * kNodeBytes;
    if (nodes_.bytes() != node_bytes) nodes_ = gpu::Buffer(node_bytes, nullptr);
    const std::size_t cache_bytes = kCacheHeaderBytes + std::max<std::size_t>(nodes(), 1) * kVplBytes;
    if (cache_.bytes() < cache_bytes) cache_ = gpu::Buffer(cache_bytes, nullptr, GL_DYNAMIC_STORAGE_BIT);
    if (!info_) info_ = gpu::Buffer(kInfoBytes, nullptr);
    if (views_ == 0) return true;

    glBindTextureUnit(0, maps.position().id());
    glBindTextureUnit(1, maps.normal().id());
    glBindTextureUnit(2, maps.albedo().id());
    const gpu::ShaderProgram& leaves = context.shaders.get(gpu::ProgramSource::compute_shader("isr/vpl_leaves.comp"));
    const gpu::ShaderProgram& reduce = context.shaders.get(gpu::ProgramSource::compute_shader("isr/vpl_reduce.comp"));
    bind(leaves);
    bind(reduce);
    reduce.set("u_depth_threshold", settings.depth_threshold);
    reduce.set("u_normal_threshold", settings.normal_threshold);
    for (int view = 0; view < views_; ++view) {
        const passes::LightViewMaps::View& v = maps.views()[static_cast<std::size_t>(view)];
        for (const gpu::ShaderProgram* program : {&leaves, &reduce}) {
            program->set("u_view", view);
            program->set("u_texel_measure", v.texel_measure);
            program->set("u_orthographic", v.orthographic ? 1 : 0);
        }
        leaves.set("u_view_forward", v.forward);
        leaves.set("u_view_origin", v.origin);
        passes::set_light_uniforms(leaves, context.scene.lights[v.light]);
        dispatch_2d(leaves, size_);
        gpu::storage_barrier();
        for (int level = 1; level <= top_level_; ++level) {
            reduce.set("u_level", level);
            dispatch_2d(reduce, size_ >> level);
            gpu::storage_barrier();
        }
    }
    const gpu::ShaderProgram& info = context.shaders.get(gpu::ProgramSource::compute_shader("isr/tree_info.comp"));
    bind(info);
    info.set("u_views", views_);
    info.use();
    glDispatchCompute(1, 1, 1);
    gpu::storage_barrier();
    return true;
}

void VplTree::select(const passes::PassContext& context, int mode, int finest_level) {
    gpu::GpuTimers::Scope timing(context.timers, "isr_vpl_cache");
    const std::uint32_t zero[4] = {0, 0, 0, 0};
    cache_.upload(0, sizeof(zero), zero);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    const gpu::ShaderProgram& program = context.shaders.get(gpu::ProgramSource::compute_shader("isr/vpl_select.comp"));
    bind(program);
    program.set("u_mode", mode);
    program.set("u_finest_level", finest_level);
    for (int view = 0; view < views_; ++view) {
        program.set("u_view", view);
        const int last = mode == ISR_MODE_NAIVE ? finest_level : top_level_;
        for (int level = finest_level; level <= last; ++level) {
            program.set("u_level", level);
            dispatch_2d(program, size_ >> level);
        }
    }
    gpu::storage_barrier();
}

std::uint32_t VplTree::cached_vpls() const {
    std::uint32_t count = 0;
    if (cache_) glGetNamedBufferSubData(cache_.id(), 0, sizeof(count), &count);
    return count;
}

void VplTree::bind(const gpu::ShaderProgram& program) const {
    gpu::bind_storage(ISR_BINDING_NODES, nodes_);
    gpu::bind_storage(ISR_BINDING_CACHE, cache_);
    gpu::bind_storage(ISR_BINDING_TREE_INFO, info_);
    program.set("u_rsm_size", size_);
    program.set("u_top_level", top_level_);
    program.set("u_nodes_per_view", static_cast<unsigned>(nodes_per_view_));
    for (int level = 0; level <= top_level_; ++level) {
        program.set(fmt::format("u_level_offset[{}]", level), static_cast<unsigned>(level_offset_[static_cast<std::size_t>(level)]));
    }
}

}  // namespace bounce::methods::isr
