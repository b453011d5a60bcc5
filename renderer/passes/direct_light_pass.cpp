#include "renderer/passes/direct_light_pass.hpp"

#include "renderer/passes/light_geometry.hpp"

#include <cmath>

namespace bounce::passes {

void DirectLightPass::render(const PassContext& context, const GBufferPass& gbuffer, const ShadowMaps& shadows) const {
    glBindFramebuffer(GL_FRAMEBUFFER, context.output.id());
    glViewport(0, 0, context.width, context.height);
    const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    glClearNamedFramebufferfv(context.output.id(), GL_COLOR, 0, zero);
    gbuffer.bind_textures();
    context.state.apply({.blend = gpu::Blend::additive});
    {
        gpu::GpuTimers::Scope timing(context.timers, "emission");
        context.shaders.get({"common/fullscreen.vert", "passes/emission.frag", {}}).use();
        triangle_.draw();
    }
    gpu::GpuTimers::Scope timing(context.timers, "direct_light");
    const gpu::ShaderProgram& program = context.shaders.get({"common/fullscreen.vert", "passes/direct_light.frag", {}});
    program.use();
    program.set("u_camera_position", context.camera.position);
    for (std::size_t i = 0; i < context.scene.lights.size(); ++i) {
        if (!shadows.has_map(i)) continue;  // no power: contributes nothing
        const scene::Light& light = context.scene.lights[i];
        set_light_uniforms(program, light);
        shadows.bind(program, i, ShadowMaps::Coverage::view);
        triangle_.draw();
    }
}

}  // namespace bounce::passes
