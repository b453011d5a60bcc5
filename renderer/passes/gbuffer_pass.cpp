#include "renderer/passes/gbuffer_pass.hpp"

#include "common/shared_layout.h"

namespace bounce::passes {

void GBufferPass::resize(int width, int height) {
    if (width == width_ && height == height_) return;
    width_ = width;
    height_ = height;
    position_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA32F, width, height});
    normal_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA16F, width, height});
    albedo_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA16F, width, height});
    emissive_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA32F, width, height});
    specular_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA16F, width, height});
    depth_ = gpu::Texture({GL_TEXTURE_2D, GL_DEPTH_COMPONENT32F, width, height});
    for (gpu::Texture* texture : {&position_, &normal_, &albedo_, &emissive_, &specular_}) {
        texture->set_filter(GL_NEAREST, GL_NEAREST);
    }
    framebuffer_ = gpu::Framebuffer();
    framebuffer_.attach_color(BOUNCE_GBUFFER_POSITION, position_);
    framebuffer_.attach_color(BOUNCE_GBUFFER_NORMAL, normal_);
    framebuffer_.attach_color(BOUNCE_GBUFFER_ALBEDO, albedo_);
    framebuffer_.attach_color(BOUNCE_GBUFFER_EMISSIVE, emissive_);
    framebuffer_.attach_color(BOUNCE_GBUFFER_SPECULAR, specular_);
    framebuffer_.attach_depth(depth_);
    framebuffer_.set_draw_buffers(BOUNCE_GBUFFER_TARGETS);
    framebuffer_.check_complete("the G-buffer");
}

void GBufferPass::render(const PassContext& context) {
    gpu::GpuTimers::Scope timing(context.timers, "gbuffer");
    resize(context.width, context.height);
    const gpu::ShaderProgram& program =
        context.shaders.get({"passes/gbuffer.vert", "passes/gbuffer.frag", {}});

    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
    glViewport(0, 0, width_, height_);
    context.state.apply({.depth_test = true, .depth_write = true, .depth_func = GL_LESS});
    const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    for (int target = 0; target < BOUNCE_GBUFFER_TARGETS; ++target) glClearNamedFramebufferfv(framebuffer_.id(), GL_COLOR, target, zero);
    const float far_depth = 1.0f;
    glClearNamedFramebufferfv(framebuffer_.id(), GL_DEPTH, 0, &far_depth);

    program.use();
    program.set("u_view_proj", context.view_projection);
    context.gpu_scene.for_each_primitive([&](const scene::Object& object, const gpu::GpuPrimitive& primitive) {
        const scene::Material& material = context.scene.material(primitive.material);
        // Single-sided surfaces are culled from behind, as glTF specifies.
        context.state.apply({.depth_test = true, .depth_write = true, .depth_func = GL_LESS,
                             .cull = material.double_sided ? gpu::Cull::none : gpu::Cull::back});
        gpu::set_object_transform(program, object.transform);
        context.gpu_scene.bind_material(program, primitive.material);
        gpu::GpuScene::draw(primitive);
    });
}

void GBufferPass::bind_textures() const {
    glBindTextureUnit(BOUNCE_UNIT_GBUFFER_POSITION, position_.id());
    glBindTextureUnit(BOUNCE_UNIT_GBUFFER_NORMAL, normal_.id());
    glBindTextureUnit(BOUNCE_UNIT_GBUFFER_ALBEDO, albedo_.id());
    glBindTextureUnit(BOUNCE_UNIT_GBUFFER_EMISSIVE, emissive_.id());
    glBindTextureUnit(BOUNCE_UNIT_GBUFFER_SPECULAR, specular_.id());
    for (GLuint unit : {BOUNCE_UNIT_GBUFFER_POSITION, BOUNCE_UNIT_GBUFFER_NORMAL, BOUNCE_UNIT_GBUFFER_ALBEDO,
                        BOUNCE_UNIT_GBUFFER_EMISSIVE, BOUNCE_UNIT_GBUFFER_SPECULAR}) {
        glBindSampler(unit, 0);
    }
}

std::uint64_t GBufferPass::bytes_for(int width, int height) {
    return static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height) * (16 + 8 + 8 + 16 + 8 + 4);
}

std::size_t GBufferPass::bytes() const {
    return position_.bytes() + normal_.bytes() + albedo_.bytes() + emissive_.bytes() + specular_.bytes() + depth_.bytes();
}

}  // namespace bounce::passes
