// How `cssm` shows its indirect light, added to the frame's direct light: the final gather (§4.4),
// each pixel walking the cut through the hierarchy with its own BRDF, which makes the last bounce;
// the same with senders jittered anew each frame and the frames' mean shown while nothing changes
// (§4.5); or the per-texel display (§5), pixels reading the irradiance every bounce left on the
// texels around them.
#pragma once

#include "renderer/methods/cssm/gather_tree.hpp"
#include "renderer/passes/gbuffer_pass.hpp"

#include <cstdint>

namespace bounce::methods::cssm {

class CssmDisplay {
public:
    explicit CssmDisplay(const passes::GBufferPass& gbuffer) : gbuffer_(gbuffer) {}

    // Adds the indirect light to frame.output in the display the settings choose, times `scale` (the
    // lights' power over what the solution was solved for). `indirect` is the solve's per-texel
    // irradiance; `solution` changes whenever the solution is made anew (not when it is scaled: the
    // jittered frames' mean is of the solution, and scaled as it is shown).
    void draw(const FrameContext& frame, const GatherTree& tree, const gpu::Buffer& indirect,
              const GatherSettings& settings, std::uint64_t solution, float scale);
    int jittered_frames() const { return jittered_frames_; }

private:
    // Draws the final gather's batches, added up into `target` (which holds the direct light, or
    // nothing). A non-zero `jitter_seed` moves every sender to a random point of its area.
    void final_gather(const FrameContext& frame, const GatherTree& tree, const gpu::Framebuffer& target,
                      float threshold, int pcf, unsigned jitter_seed, float scale) const;
    // While nothing changes, each frame gathers from senders jittered anew and the frames' mean is
    // shown, converging over `jitter_frames` frames (then kept without gathering).
    void jittered_final_gather(const FrameContext& frame, const GatherTree& tree, const GatherSettings& settings,
                               std::uint64_t solution, float scale);
    // The view-dependent lightmap: one draw, each pixel blending the summed irradiance of the
    // texels around it.
    void texel_display(const FrameContext& frame, const GatherTree& tree, const gpu::Buffer& indirect, int pcf,
                       float scale) const;
    // Fullscreen draws from here on add into `target`, over the whole frame.
    void add_into(const FrameContext& frame, const gpu::Framebuffer& target) const;

    const passes::GBufferPass& gbuffer_;
    passes::FullscreenTriangle triangle_;
    gpu::Texture jitter_mean_, jitter_frame_;
    gpu::Framebuffer jitter_target_;
    std::uint64_t jitter_view_ = 0;
    int jittered_frames_ = 0;
};

}  // namespace bounce::methods::cssm
