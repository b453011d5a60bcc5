#include "renderer/methods/cssm/cssm_display.hpp"

#include "renderer/base/hash.hpp"

#include "cssm/cssm_layout.h"
#include "common/shared_layout.h"


namespace bounce::methods::cssm {

void CssmDisplay::draw(const FrameContext& frame, const GatherTree& tree, const gpu::Buffer& indirect,
                       const GatherSettings& settings, std::uint64_t solution, float scale) {
    if (settings.per_texel) {
        texel_display(frame, tree, indirect, settings.pcf, scale);
    } else if (settings.jitter_frames > 1) {
        jittered_final_gather(frame, tree, settings, solution, scale);
    } else {
        final_gather(frame, tree, frame.output, settings.final_threshold, settings.pcf, 0, scale);
    }
}

void CssmDisplay::add_into(const FrameContext& frame, const gpu::Framebuffer& target) const {
    glBindFramebuffer(GL_FRAMEBUFFER, target.id());
    glViewport(0, 0, frame.width, frame.height);
    frame.state.apply({.blend = gpu::Blend::additive});
}

void CssmDisplay::final_gather(const FrameContext& frame, const GatherTree& tree, const gpu::Framebuffer& target,
                               float threshold, int pcf, unsigned jitter_seed, float scale) const {
    gpu::GpuTimers::Scope timing(frame.timers, "cssm_final_gather");
    const gpu::ShaderProgram& program = frame.shaders.get({"common/fullscreen.vert", "cssm/final_gather.frag", {}});
    program.use();
    tree.bind(program, pcf, threshold);
    program.set("u_jitter_seed", jitter_seed);
    program.set("u_indirect_scale", scale);
    program.set("u_camera_position", frame.camera.position);
    gbuffer_.bind_textures();
    add_into(frame, target);
    for (const GatherBatches::Batch& batch : tree.batches.batches()) {
        program.set("u_first_root", batch.first);
        program.set("u_root_count", batch.count);
        triangle_.draw();
        frame.interruption_point();
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
}

void CssmDisplay::jittered_final_gather(const FrameContext& frame, const GatherTree& tree, const GatherSettings& settings,
                                        std::uint64_t solution, float scale) {
    // What the accumulated mean depends on: a change of any of it starts the mean anew.
    Hasher hash;
    hash.add(solution).add(settings.final_threshold).add(settings.pcf).add(frame.width).add(frame.height);
    hash.add(frame.view_projection);
    const std::uint64_t view = hash.value();
    if (!jitter_mean_ || jitter_mean_.width() != frame.width || jitter_mean_.height() != frame.height) {
        jitter_mean_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA32F, frame.width, frame.height});
        jitter_frame_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA32F, frame.width, frame.height});
        jitter_frame_.set_filter(GL_NEAREST, GL_NEAREST);
        jitter_mean_.set_filter(GL_NEAREST, GL_NEAREST);
        jitter_target_ = gpu::Framebuffer();
        jitter_target_.attach_color(0, jitter_frame_);
        jitter_target_.set_draw_buffers(1);
        jitter_target_.check_complete("the cssm jitter frame");
        jitter_view_ = ~view;
    }
    if (view != jitter_view_) {
        jitter_view_ = view;
        jittered_frames_ = 0;
        glClearTexImage(jitter_mean_.id(), 0, GL_RGBA, GL_FLOAT, nullptr);
    }
    if (jittered_frames_ < settings.jitter_frames) {
        ++jittered_frames_;
        glClearTexImage(jitter_frame_.id(), 0, GL_RGBA, GL_FLOAT, nullptr);
        final_gather(frame, tree, jitter_target_, settings.final_threshold, settings.pcf,
                     static_cast<unsigned>(jittered_frames_), 1.0f);
        gpu::GpuTimers::Scope timing(frame.timers, "cssm_accumulate");
        const gpu::ShaderProgram& accumulate = frame.shaders.get(gpu::ProgramSource::compute_shader("cssm/accumulate.comp"));
        accumulate.use();
        glBindTextureUnit(BOUNCE_UNIT_HDR_INPUT, jitter_frame_.id());
        glBindImageTexture(0, jitter_mean_.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
        accumulate.set("u_size", glm::ivec2(frame.width, frame.height));
        accumulate.set("u_weight", 1.0f / static_cast<float>(jittered_frames_));
        accumulate.dispatch_grid({frame.width, frame.height}, {8, 8});
        glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    const gpu::ShaderProgram& composite = frame.shaders.get({"common/fullscreen.vert", "cssm/composite.frag", {}});
    composite.use();
    composite.set("u_indirect_scale", scale);
    glBindTextureUnit(BOUNCE_UNIT_HDR_INPUT, jitter_mean_.id());
    add_into(frame, frame.output);
    triangle_.draw();
}

void CssmDisplay::texel_display(const FrameContext& frame, const GatherTree& tree, const gpu::Buffer& indirect,
                                int pcf, float scale) const {
    gpu::GpuTimers::Scope timing(frame.timers, "cssm_texel_display");
    const gpu::ShaderProgram& program = frame.shaders.get({"common/fullscreen.vert", "cssm/texel_display.frag", {}});
    program.use();
    program.set("u_camera_position", frame.camera.position);
    program.set("u_indirect_scale", scale);
    tree.bind(program, pcf, 0.0f);
    gpu::bind_storage(CSSM_BINDING_TEXEL_INDIRECT, indirect);
    gbuffer_.bind_textures();
    add_into(frame, frame.output);
    triangle_.draw();
}

}  // namespace bounce::methods::cssm
