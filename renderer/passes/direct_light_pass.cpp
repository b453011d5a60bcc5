#include "renderer/passes/direct_light_pass.hpp"

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
        program.set("u_light_type", static_cast<int>(light.type));
        program.set("u_light_position", light.position);
        program.set("u_light_direction", glm::normalize(light.direction));
        program.set("u_light_radiant", light.radiant());
        program.set("u_light_cos_inner", std::cos(light.inner_cone));
        program.set("u_light_cos_outer", std::cos(light.outer_cone));
        shadows.bind(program, i);
        triangle_.draw();
    }
}

}  // namespace bounce::passes
