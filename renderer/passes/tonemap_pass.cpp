#include "renderer/passes/tonemap_pass.hpp"

#include "common/shared_layout.h"

#include <cmath>

namespace bounce::passes {

const gpu::Texture& TonemapPass::run(gpu::ShaderCache& shaders, gpu::StateCache& state, gpu::GpuTimers& timers,
                                     const gpu::Texture& hdr, const image::DisplayTransform& transform) {
    gpu::GpuTimers::Scope timing(timers, "tonemap");
    if (!display_ || display_.width() != hdr.width() || display_.height() != hdr.height()) {
        display_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA8, hdr.width(), hdr.height()});
        framebuffer_ = gpu::Framebuffer();
        framebuffer_.attach_color(0, display_);
        framebuffer_.set_draw_buffers(1);
        framebuffer_.check_complete("the tone-mapped image");
    }
    const gpu::ShaderProgram& program = shaders.get({"common/fullscreen.vert", "passes/tonemap.frag", {}});
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
    glViewport(0, 0, hdr.width(), hdr.height());
    state.apply({});
    program.use();
    program.set("u_exposure_scale", std::exp2(transform.exposure));
    program.set("u_tone_curve", static_cast<int>(transform.curve));
    glBindTextureUnit(BOUNCE_UNIT_HDR_INPUT, hdr.id());
    glBindSampler(BOUNCE_UNIT_HDR_INPUT, 0);
    triangle_.draw();
    return display_;
}

}  // namespace bounce::passes
