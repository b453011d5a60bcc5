// What a raster pass needs from the frame it runs in.
#pragma once

#include "renderer/gpu/gl_objects.hpp"
#include "renderer/gpu/gpu_scene.hpp"
#include "renderer/gpu/gpu_timer.hpp"
#include "renderer/gpu/pipeline_state.hpp"
#include "renderer/gpu/shader_program.hpp"
#include "renderer/scene/scene.hpp"

namespace bounce::passes {

struct PassContext {
    const scene::Scene& scene;
    const gpu::GpuScene& gpu_scene;
    gpu::ShaderCache& shaders;
    gpu::StateCache& state;
    gpu::GpuTimers& timers;
    const gpu::Framebuffer& output;  // linear HDR target, RGBA32F
    int width = 0;
    int height = 0;
    scene::Camera camera;
    glm::mat4 view{1.0f};
    glm::mat4 projection{1.0f};
    glm::mat4 view_projection{1.0f};
};

// A triangle covering the viewport (core profile needs a vertex array bound, even an empty one).
class FullscreenTriangle {
public:
    FullscreenTriangle() : vertex_array_(gpu::make_vertex_array()) {}
    void draw() const {
        glBindVertexArray(vertex_array_.id());
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }

private:
    gpu::VertexArray vertex_array_;
};

}  // namespace bounce::passes
