#include "renderer/methods/isr/multires_buffer.hpp"

#include "common/shared_layout.h"

#include <fmt/format.h>

#include <algorithm>

namespace bounce::methods::isr {
namespace {
int ceil_shift(int value, int level) { return (value + (1 << level) - 1) >> level; }

// The atlas: the finest level, and right of it a column of every coarser level.
glm::ivec2 atlas_extent(int width, int height) {
    glm::ivec2 extent(width, height);
    int column_y = 0;
    for (int level = 1; level < ISR_MAX_LEVELS; ++level) {
        column_y += ceil_shift(height, level);
        extent = glm::max(extent, glm::ivec2(width + ceil_shift(width, level), column_y));
    }
    return extent;
}

void dispatch_2d(const gpu::ShaderProgram& program, glm::ivec2 size) {
    program.use();
    glDispatchCompute(static_cast<GLuint>((size.x + 7) / 8), static_cast<GLuint>((size.y + 7) / 8), 1);
}
}  // namespace

int usable_levels(int requested, int width, int height) {
    int levels = std::clamp(requested, 1, ISR_MAX_LEVELS);
    while (levels > 1 && (std::max(width, height) >> (levels - 1)) < 1) --levels;
    return levels;
}

std::uint64_t MultiresolutionBuffer::bytes_for(int width, int height) {
    const glm::ivec2 extent = atlas_extent(width, height);
    return static_cast<std::uint64_t>(extent.x) * static_cast<std::uint64_t>(extent.y) * (16 + 16 + 8 + 8 + 4);
}

void MultiresolutionBuffer::resize(int width, int height) {
    width_ = width;
    height_ = height;
    int column_y = 0;
    for (int level = 0; level < ISR_MAX_LEVELS; ++level) {
        size_[level] = {ceil_shift(width, level), ceil_shift(height, level)};
        if (level == 0) {
            origin_[level] = {0, 0};
            continue;
        }
        origin_[level] = {width, column_y};
        column_y += size_[level].y;
    }
    const int atlas_width = atlas_extent(width, height).x, atlas_height = atlas_extent(width, height).y;
    irradiance_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA32F, atlas_width, atlas_height});
    depth_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA32F, atlas_width, atlas_height});
    normal_min_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA16F, atlas_width, atlas_height});
    normal_max_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA16F, atlas_width, atlas_height});
    stencil_ = gpu::Texture({GL_TEXTURE_2D, GL_DEPTH24_STENCIL8, atlas_width, atlas_height});
    irradiance_.set_filter(GL_NEAREST, GL_NEAREST);
    framebuffer_.attach_color(0, irradiance_);
    framebuffer_.attach_depth_stencil(stencil_);
    framebuffer_.set_draw_buffers(1);
    framebuffer_.check_complete("the multiresolution illumination atlas");
}

void MultiresolutionBuffer::set_layout(const gpu::ShaderProgram& program) const {
    program.set("u_levels", settings_.levels);
    for (int level = 0; level < settings_.levels; ++level) {
        program.set(fmt::format("u_level_origin[{}]", level), origin_[level]);
        program.set(fmt::format("u_level_size[{}]", level), size_[level]);
    }
    program.set("u_depth_threshold", settings_.depth_threshold);
    program.set("u_normal_threshold", settings_.normal_threshold);
}

void MultiresolutionBuffer::bind_images() const {
    glBindImageTexture(ISR_IMAGE_IRRADIANCE, irradiance_.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    glBindImageTexture(ISR_IMAGE_DEPTH, depth_.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA32F);
    glBindImageTexture(ISR_IMAGE_NORMAL_MIN, normal_min_.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA16F);
    glBindImageTexture(ISR_IMAGE_NORMAL_MAX, normal_max_.id(), 0, GL_FALSE, 0, GL_READ_WRITE, GL_RGBA16F);
}

void MultiresolutionBuffer::refine(const passes::PassContext& context, const passes::GBufferPass& gbuffer,
                                   const MultiresSettings& settings) {
    if (context.width != width_ || context.height != height_) resize(context.width, context.height);
    settings_ = settings;
    settings_.levels = usable_levels(settings.levels, width_, height_);
    bind_images();
    {
        gpu::GpuTimers::Scope timing(context.timers, "isr_minmax_mipmap");
        const gpu::ShaderProgram& program = context.shaders.get(gpu::ProgramSource::compute_shader("isr/minmax.comp"));
        set_layout(program);
        program.set("u_view", context.view);
        gbuffer.bind_textures();
        for (int level = 0; level < settings_.levels; ++level) {
            program.set("u_level", level);
            dispatch_2d(program, size_[level]);
            glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
        }
    }
    gpu::GpuTimers::Scope timing(context.timers, "isr_stencil");
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
    glViewport(0, 0, irradiance_.width(), irradiance_.height());
    context.state.apply({.stencil = gpu::Stencil::mark});
    const float zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    glClearNamedFramebufferfv(framebuffer_.id(), GL_COLOR, 0, zero);
    glClearNamedFramebufferfi(framebuffer_.id(), GL_DEPTH_STENCIL, 0, 1.0f, 0);
    const gpu::ShaderProgram& program = context.shaders.get({"common/fullscreen.vert", "isr/stencil.frag", {}});
    program.use();
    set_layout(program);
    triangle_.draw();
}

void MultiresolutionBuffer::begin_gather(const passes::PassContext& context) const {
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
    glViewport(0, 0, irradiance_.width(), irradiance_.height());
    context.state.apply({.blend = gpu::Blend::additive, .stencil = gpu::Stencil::marked});
}

void MultiresolutionBuffer::count_gathered(const passes::PassContext& context) const {
    bind_images();
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
    const gpu::ShaderProgram& program = context.shaders.get(gpu::ProgramSource::compute_shader("isr/gather_stats.comp"));
    set_layout(program);
    for (int level = 0; level < settings_.levels; ++level) {
        program.set("u_level", level);
        dispatch_2d(program, size_[level]);
    }
    gpu::storage_barrier();
}

void MultiresolutionBuffer::upsample(const passes::PassContext& context) const {
    gpu::GpuTimers::Scope timing(context.timers, "isr_upsample");
    bind_images();
    const gpu::ShaderProgram& pull = context.shaders.get(gpu::ProgramSource::compute_shader("isr/pull.comp"));
    const gpu::ShaderProgram& push = context.shaders.get(gpu::ProgramSource::compute_shader("isr/push.comp"));
    set_layout(pull);
    set_layout(push);
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
    for (int level = 1; level < settings_.levels; ++level) {
        pull.set("u_level", level);
        dispatch_2d(pull, size_[level]);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    for (int level = settings_.levels - 2; level >= 0; --level) {
        push.set("u_level", level);
        dispatch_2d(push, size_[level]);
        glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT);
    }
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
}

std::size_t MultiresolutionBuffer::bytes() const {
    return irradiance_.bytes() + depth_.bytes() + normal_min_.bytes() + normal_max_.bytes() + stencil_.bytes();
}

}  // namespace bounce::methods::isr
