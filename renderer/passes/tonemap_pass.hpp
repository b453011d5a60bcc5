// Linear HDR to display-referred sRGB 8-bit (shaders/passes/tonemap.frag).
#pragma once

#include "renderer/image/tone.hpp"
#include "renderer/passes/pass_context.hpp"

namespace bounce::passes {

class TonemapPass {
public:
    // Reads `hdr` and returns the RGBA8 texture it wrote (owned by the pass, valid until the next run).
    const gpu::Texture& run(gpu::ShaderCache& shaders, gpu::StateCache& state, gpu::GpuTimers& timers,
                            const gpu::Texture& hdr, const image::DisplayTransform& transform);
    std::size_t bytes() const { return display_.bytes(); }

private:
    gpu::Texture display_;
    gpu::Framebuffer framebuffer_;
    FullscreenTriangle triangle_;
};

}  // namespace bounce::passes
