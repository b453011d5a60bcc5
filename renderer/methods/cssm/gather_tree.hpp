// The hierarchy as the gathers walk it: the batches of subtrees each draw or dispatch covers, the
// counters the gathers add to, and everything shaders/cssm/cssm_tree.glsl reads, bound at once.
#pragma once

#include "renderer/gpu/counter_buffer.hpp"
#include "renderer/methods/cssm/resident_bake.hpp"
#include "renderer/methods/cssm/texel_placement.hpp"

#include <cstdint>
#include <vector>

namespace bounce::methods::cssm {

// The knobs the radiosity solve and the display read.
struct GatherSettings {
    int bounces = 1;
    float threshold = 0.0f;        // the radiosity oracle's
    float final_threshold = 0.0f;  // the final gather's
    int pcf = 1;
    int jitter_frames = 0;
    bool per_texel = false;
    bool spots = false;  // leaves send the lights' light from their spots (CssmNodeLight)

    static GatherSettings of(const FrameContext& frame);
};

// Roots of subtrees, grouped into batches whose node counts fit the work one draw or dispatch may
// do per receiver: GPU watchdogs (and software rasterizers' loop limits) cut long draws short.
class GatherBatches {
public:
    struct Batch {
        std::uint32_t first = 0, count = 0;  // roots[first .. first + count)
    };

    // Regrouped when the filter width or the placed hierarchy changed.
    void update(int pcf, const ResidentBake& bake, const TexelPlacement& placement);
    const std::vector<Batch>& batches() const { return batches_; }
    void bind() const;

private:
    std::vector<Batch> batches_;
    gpu::Buffer roots_;
    int pcf_ = -1;
    std::uint64_t placement_version_ = 0;
};

// What the gathers counted (count_gather in cssm_tree.glsl).
struct GatherCounts {
    std::uint64_t receivers = 0;  // texels or pixels
    std::uint64_t gathered = 0;   // sender nodes, summed over the receivers
    std::uint64_t visited = 0;    // nodes the traversals visited

    static GatherCounts read(const gpu::CounterBuffer& counters);
    double per_receiver(std::uint64_t count) const {
        return receivers > 0 ? static_cast<double>(count) / static_cast<double>(receivers) : 0.0;
    }
};

// Everything a gather reads.
struct GatherTree {
    const ResidentBake& bake;
    const TexelPlacement& placement;
    const GatherBatches& batches;
    const gpu::CounterBuffer& counters;
    bool spots = false;  // leaves send from their spots (GatherSettings::spots)

    // Binds every buffer cssm_tree.glsl declares and sets its uniforms, senders unjittered.
    void bind(const gpu::ShaderProgram& program, int pcf, float threshold) const;
};

}  // namespace bounce::methods::cssm
