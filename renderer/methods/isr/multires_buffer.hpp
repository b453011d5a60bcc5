// The eye-space side of image-space radiosity (paper §3.1-3.2): a min-max pyramid of view depth and
// normals over the G-buffer, the one-pass stencil refinement that marks which patch of which level
// gathers light, and the pull-push upsampling of the gathered light to full resolution. All levels
// live in one flattened atlas (layout in shaders/isr/multires.glsl).
#pragma once

#include "renderer/passes/gbuffer_pass.hpp"

#include <array>

#include "isr/isr_layout.h"

namespace bounce::methods::isr {

struct MultiresSettings {
    int levels = 1;               // level 0 is full resolution; level i patches are 2^i pixels wide
    float depth_threshold = 0.0;  // relative view-depth span that makes a patch discontinuous
    float normal_threshold = 0.0; // normal-component span that makes a patch discontinuous
};

class MultiresolutionBuffer {
public:
    // What resize(width, height) allocates: an atlas of every level (the finest, then a column of
    // the coarser ones) with irradiance and depth RGBA32F, two RGBA16F normal bounds and a stencil.
    static std::uint64_t bytes_for(int width, int height);
    // Builds the min-max pyramid and marks the patches that gather (stencil = 1).
    void refine(const passes::PassContext& context, const passes::GBufferPass& gbuffer, const MultiresSettings& settings);
    // Binds the atlas with the stencil test on and additive blending: full-screen draws reach the
    // marked patches only, and batches add up.
    void begin_gather(const passes::PassContext& context) const;
    // The level rectangles and thresholds, for any program that includes isr/multires.glsl.
    void set_layout(const gpu::ShaderProgram& program) const;
    // Adds the VPLs each gathering texel used (sum and largest) to the counters bound at
    // ISR_BINDING_COUNTERS.
    void count_gathered(const passes::PassContext& context) const;
    // Pull-push: every pixel of level 0 then holds irradiance (its own patch's, interpolated).
    void upsample(const passes::PassContext& context) const;
    // Level 0 of the atlas (the full-resolution irradiance) and the rest.
    const gpu::Texture& irradiance() const { return irradiance_; }
    int levels() const { return settings_.levels; }
    std::size_t bytes() const;

private:
    void resize(int width, int height);
    void bind_images() const;
    MultiresSettings settings_;
    int width_ = 0, height_ = 0;
    std::array<glm::ivec2, ISR_MAX_LEVELS> origin_{}, size_{};
    gpu::Texture irradiance_, depth_, normal_min_, normal_max_, stencil_;
    gpu::Framebuffer framebuffer_;
    passes::FullscreenTriangle triangle_;
};

// The levels a frame of this size can have: each coarser level at least one texel wide.
int usable_levels(int requested, int width, int height);

}  // namespace bounce::methods::isr
