#include "renderer/methods/cssm/radiosity_solve.hpp"

#include "renderer/passes/light_geometry.hpp"

#include "cssm/cssm_layout.h"

#include <utility>

namespace bounce::methods::cssm {
namespace {

const gpu::ShaderProgram& compute(const FrameContext& frame, const char* path, const GatherTree& tree,
                                  const GatherSettings& settings) {
    const gpu::ShaderProgram& program = frame.shaders.get(gpu::ProgramSource::compute_shader(path));
    program.use();
    tree.bind(program, settings.pcf, settings.threshold);
    program.set("u_texel_count", static_cast<unsigned>(tree.bake.bake().texel_count()));
    return program;
}

}  // namespace

void RadiositySolve::allocate(std::size_t texels) {
    for (gpu::Buffer* buffer : {&direct_, &bounce_, &total_, &irradiance_, &indirect_})
        *buffer = gpu::Buffer(std::max<std::size_t>(1, texels) * sizeof(glm::vec4), nullptr, 0);
    spots_ = gpu::Buffer(std::max<std::size_t>(1, texels) * 2 * sizeof(glm::vec4), nullptr, 0);
}

void RadiositySolve::solve(const FrameContext& frame, const GatherTree& tree, const passes::ShadowMaps& shadows,
                           const GatherSettings& settings) {
    direct_light(frame, tree, shadows, settings);
    glCopyNamedBufferSubData(direct_.id(), total_.id(), 0, 0, static_cast<GLsizeiptr>(direct_.bytes()));
    glCopyNamedBufferSubData(direct_.id(), bounce_.id(), 0, 0, static_cast<GLsizeiptr>(direct_.bytes()));
    glClearNamedBufferData(indirect_.id(), GL_RGBA32F, GL_RGBA, GL_FLOAT, nullptr);
    const int atlas_bounces = settings.per_texel ? settings.bounces : settings.bounces - 1;
    for (int b = 1; b <= atlas_bounces; ++b) bounce(frame, tree, settings, /*from_direct=*/b == 1);
    pull(frame, tree, total_, /*holds_direct=*/true, settings.spots);
}

void RadiositySolve::direct_light(const FrameContext& frame, const GatherTree& tree, const passes::ShadowMaps& shadows,
                                  const GatherSettings& settings) const {
    gpu::GpuTimers::Scope timing(frame.timers, "cssm_atlas_direct");
    const gpu::ShaderProgram& program = compute(frame, "cssm/atlas_direct.comp", tree, settings);
    const std::size_t texel_count = tree.bake.bake().texel_count();
    gpu::bind_storage(CSSM_BINDING_TEXEL_OUT, direct_);
    gpu::bind_storage(CSSM_BINDING_TEXEL_SPOTS, spots_);
    program.set("u_emission_only", 1);
    program.dispatch_threads(texel_count);
    program.set("u_emission_only", 0);
    for (std::size_t l = 0; l < frame.scene.lights.size(); ++l) {
        if (!shadows.has_map(l)) continue;
        gpu::storage_barrier();
        passes::set_light_uniforms(program, frame.scene.lights[l]);
        shadows.bind(program, l);
        program.dispatch_threads(texel_count);
    }
    gpu::storage_barrier();
}

void RadiositySolve::bounce(const FrameContext& frame, const GatherTree& tree, const GatherSettings& settings,
                            bool from_direct) {
    pull(frame, tree, bounce_, from_direct, settings.spots);
    gpu::GpuTimers::Scope timing(frame.timers, "cssm_atlas_gather");
    const std::size_t texel_count = tree.bake.bake().texel_count();
    const gpu::ShaderProgram& gather = compute(frame, "cssm/gather.comp", tree, settings);
    gpu::bind_storage(CSSM_BINDING_TEXEL_OUT, irradiance_);
    const auto& batches = tree.batches.batches();
    for (std::size_t b = 0; b < batches.size(); ++b) {
        gather.set("u_first_root", batches[b].first);
        gather.set("u_root_count", batches[b].count);
        gather.set("u_first_batch", b == 0 ? 1 : 0);
        gather.dispatch_threads(texel_count);
        gpu::storage_barrier();
        frame.interruption_point();
    }
    const gpu::ShaderProgram& finish = compute(frame, "cssm/bounce.comp", tree, settings);
    gpu::bind_storage(CSSM_BINDING_TEXEL_IN, irradiance_);
    gpu::bind_storage(CSSM_BINDING_TEXEL_OUT, total_);
    gpu::bind_storage(CSSM_BINDING_TEXEL_INDIRECT, indirect_);
    finish.dispatch_threads(texel_count);
    gpu::storage_barrier();
    std::swap(bounce_, irradiance_);  // this bounce's exitance is the next one's source
}

void RadiositySolve::pull(const FrameContext& frame, const GatherTree& tree, const gpu::Buffer& source,
                          bool holds_direct, bool spots) const {
    gpu::GpuTimers::Scope timing(frame.timers, "cssm_pull");
    const gpu::ShaderProgram& program = frame.shaders.get(gpu::ProgramSource::compute_shader("cssm/pull.comp"));
    program.use();
    tree.placement.bind();
    gpu::bind_storage(CSSM_BINDING_TEXEL_IN, source);
    gpu::bind_storage(CSSM_BINDING_TEXEL_SPOTS, spots_);
    program.set("u_spots", spots ? 1 : 0);
    program.set("u_holds_direct", holds_direct ? 1 : 0);
    const RadiosityTree& hierarchy = tree.bake.bake().tree;
    const auto node_count = static_cast<unsigned>(hierarchy.nodes.size());
    program.set("u_leaves", 1);
    program.set("u_first", 0u);
    program.set("u_count", node_count);
    program.dispatch_threads(node_count);
    program.set("u_leaves", 0);
    const auto& first = hierarchy.level_first;
    for (std::size_t level = 0; level + 1 < first.size(); ++level) {
        gpu::storage_barrier();
        program.set("u_first", first[level]);
        program.set("u_count", first[level + 1] - first[level]);
        program.dispatch_threads(first[level + 1] - first[level]);
    }
    gpu::storage_barrier();
}

}  // namespace bounce::methods::cssm
