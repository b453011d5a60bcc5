#include "renderer/gpu/pipeline_state.hpp"

namespace bounce::gpu {
namespace {
void set_enabled(GLenum capability, bool enabled) {
    if (enabled) {
        glEnable(capability);
    } else {
        glDisable(capability);
    }
}
}  // namespace

void StateCache::apply(const PipelineState& state) {
    const bool all = !current_.has_value();
    const PipelineState& old = all ? state : *current_;
    if (all || old.depth_test != state.depth_test) set_enabled(GL_DEPTH_TEST, state.depth_test);
    if (all || old.depth_write != state.depth_write) glDepthMask(state.depth_write ? GL_TRUE : GL_FALSE);
    if (all || old.depth_func != state.depth_func) glDepthFunc(state.depth_func);
    if (all || old.cull != state.cull) {
        set_enabled(GL_CULL_FACE, state.cull != Cull::none);
        if (state.cull != Cull::none) glCullFace(state.cull == Cull::back ? GL_BACK : GL_FRONT);
    }
    if (all || old.blend != state.blend) {
        set_enabled(GL_BLEND, state.blend != Blend::none);
        if (state.blend == Blend::additive) {
            glBlendEquation(GL_FUNC_ADD);
            glBlendFunc(GL_ONE, GL_ONE);
        }
    }
    if (all || old.stencil != state.stencil) {
        set_enabled(GL_STENCIL_TEST, state.stencil != Stencil::none);
        // The write mask also gates stencil clears, so it stays open unless a pass only tests.
        glStencilMask(state.stencil == Stencil::marked ? 0x00 : 0xFF);
        glStencilFunc(state.stencil == Stencil::marked ? GL_EQUAL : GL_ALWAYS, 1, 0xFF);
        glStencilOp(GL_KEEP, GL_KEEP, state.stencil == Stencil::mark ? GL_REPLACE : GL_KEEP);
    }
    if (all || old.polygon_offset_factor != state.polygon_offset_factor ||
        old.polygon_offset_units != state.polygon_offset_units) {
        const bool offset = state.polygon_offset_factor != 0.0f || state.polygon_offset_units != 0.0f;
        set_enabled(GL_POLYGON_OFFSET_FILL, offset);
        glPolygonOffset(state.polygon_offset_factor, state.polygon_offset_units);
    }
    if (all) {
        // Constant for the whole renderer: seamless cube filtering, no scissor, no dithering.
        glEnable(GL_TEXTURE_CUBE_MAP_SEAMLESS);
        glDisable(GL_SCISSOR_TEST);
        glDisable(GL_DITHER);
    }
    current_ = state;
}

}  // namespace bounce::gpu
