#include "renderer/methods/direct/direct_method.hpp"

#include "common/shared_layout.h"
#include "renderer/passes/gbuffer_pass.hpp"
#include "renderer/passes/shadow_maps.hpp"

#include <fmt/format.h>

#include <cmath>

namespace bounce::methods::direct {
namespace {

class DirectMethod final : public Method {
public:
    std::string_view name() const override { return "direct"; }

    void render(const FrameContext& frame) override {
        gbuffer_.render(frame);
        shadows_.render(frame, frame.knob_int("shadow_map_size"));

        glBindFramebuffer(GL_FRAMEBUFFER, frame.output.id());
        glViewport(0, 0, frame.width, frame.height);
        const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        glClearNamedFramebufferfv(frame.output.id(), GL_COLOR, 0, zero);
        gbuffer_.bind_textures();
        frame.state.apply({.blend = gpu::Blend::additive});
        {
            gpu::GpuTimers::Scope timing(frame.timers, "emission");
            frame.shaders.get({"common/fullscreen.vert", "direct/emission.frag", {}}).use();
            triangle_.draw();
        }
        gpu::GpuTimers::Scope timing(frame.timers, "direct_light");
        const gpu::ShaderProgram& program = frame.shaders.get({"common/fullscreen.vert", "direct/direct_light.frag", {}});
        program.use();
        program.set("u_camera_position", frame.camera.position);
        for (std::size_t i = 0; i < frame.scene.lights.size(); ++i) {
            if (!shadows_.has_map(i)) continue;  // no power: contributes nothing
            const scene::Light& light = frame.scene.lights[i];
            program.set("u_light_type", static_cast<int>(light.type));
            program.set("u_light_position", light.position);
            program.set("u_light_direction", glm::normalize(light.direction));
            program.set("u_light_radiant", light.radiant());
            program.set("u_light_cos_inner", std::cos(light.inner_cone));
            program.set("u_light_cos_outer", std::cos(light.outer_cone));
            shadows_.bind(program, i);
            triangle_.draw();
        }
    }

    std::vector<ResidentStructure> resident() const override {
        return {{"gbuffer", gbuffer_.bytes(), "surface attributes at the frame size"},
                {"shadow_maps", shadows_.bytes(),
                 fmt::format("{} lights with power, one map each; drawn for {} frames, reused for {} "
                             "(nothing they depend on changed)",
                             shadows_.map_count(), shadows_.frames_drawn(), shadows_.frames_reused())}};
    }

private:
    passes::GBufferPass gbuffer_;
    passes::ShadowMaps shadows_;
    passes::FullscreenTriangle triangle_;
};

}  // namespace

MethodInfo method_info() {
    MethodInfo info;
    info.name = "direct";
    info.description = "emission and direct light with shadow maps; no indirect light";
    info.knobs = {{"shadow_map_size", 16, 8192, true, "texels per side of each shadow map (cube face)"}};
    info.presets = {{"draft", {{"shadow_map_size", 256}}},
                    {"low", {{"shadow_map_size", 512}}},
                    {"medium", {{"shadow_map_size", 1024}}},
                    {"high", {{"shadow_map_size", 2048}}},
                    {"ultra", {{"shadow_map_size", 4096}}}};
    info.create = [] { return std::make_unique<DirectMethod>(); };
    return info;
}

}  // namespace bounce::methods::direct
