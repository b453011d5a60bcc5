// The G-buffer: surface position, shading normal, material and emission per pixel, from the
// camera (layout in shaders/common/shared_layout.h).
#pragma once

#include "renderer/passes/pass_context.hpp"

namespace bounce::passes {

class GBufferPass {
public:
    void render(const PassContext& context);
    // Binds the G-buffer textures to their units for a lighting pass.
    void bind_textures() const;
    const gpu::Texture& position() const { return position_; }
    const gpu::Texture& normal() const { return normal_; }
    std::size_t bytes() const;
    // What a G-buffer of this size holds (position and emission RGBA32F, normal and albedo RGBA16F,
    // depth 32F), before it is allocated.
    static std::uint64_t bytes_for(int width, int height);

private:
    void resize(int width, int height);
    int width_ = 0;
    int height_ = 0;
    gpu::Texture position_, normal_, albedo_, emissive_, specular_, depth_;
    gpu::Framebuffer framebuffer_;
};

}  // namespace bounce::passes
