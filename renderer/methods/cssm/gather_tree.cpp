#include "renderer/methods/cssm/gather_tree.hpp"

#include "cssm/cssm_layout.h"

#include <algorithm>
#include <cmath>

namespace bounce::methods::cssm {
namespace {

// Work one gather draw or dispatch may do per receiver, in node visits times the visibility
// query's loop steps.
constexpr double kStepsPerBatch = 40000.0;

}  // namespace

GatherSettings GatherSettings::of(const FrameContext& frame) {
    GatherSettings settings;
    settings.bounces = frame.knob_int("bounces");
    settings.threshold = static_cast<float>(frame.knob("threshold"));
    settings.final_threshold = static_cast<float>(frame.knob("final_threshold"));
    settings.pcf = frame.knob_int("pcf");
    settings.jitter_frames = frame.knob_int("jitter_frames");
    settings.per_texel = frame.knob_int("per_texel") != 0;
    settings.spots = frame.knob_int("texel_spots") != 0;
    return settings;
}

void GatherBatches::update(int pcf, const ResidentBake& resident, const TexelPlacement& placement) {
    if (pcf == pcf_ && placement.version() == placement_version_) return;
    pcf_ = pcf;
    placement_version_ = placement.version();
    const CssmBake& bake = resident.bake();
    const double search_steps = std::log2(std::max<double>(2.0, bake.cube_maps())) + 2.0;
    // A visibility query: the sender's PCF taps, the receiver's (with moving objects), and each
    // CSM's lookup.
    const double csm_count = resident.csm_count();
    const double queries = csm_count > 0 ? 2.0 : 1.0;
    const double steps_per_node = static_cast<double>(pcf * pcf) * search_steps * queries +
                                  csm_count * (search_steps + 8.0) + 8.0 + 64.0 * (queries - 1.0);
    const auto budget = static_cast<std::uint32_t>(std::max(1.0, kStepsPerBatch / steps_per_node));
    const std::vector<std::uint32_t> roots = bake.tree.cut((budget + 1) / 2);
    batches_.clear();
    std::uint32_t first = 0, nodes = 0;
    for (std::uint32_t r = 0; r < roots.size(); ++r) {
        const std::uint32_t subtree = 2 * bake.tree.nodes[roots[r]].leaves - 1;
        if (r > first && nodes + subtree > budget) {
            batches_.push_back({first, r - first});
            first = r;
            nodes = 0;
        }
        nodes += subtree;
    }
    batches_.push_back({first, static_cast<std::uint32_t>(roots.size()) - first});
    roots_ = gpu::storage_of(roots);
}

void GatherBatches::bind() const { gpu::bind_storage(CSSM_BINDING_ROOTS, roots_); }

GatherCounts GatherCounts::read(const gpu::CounterBuffer& counters) {
    const gpu::CounterValues values = counters.read();
    return {values[CSSM_COUNTER_RECEIVERS], values.wide(CSSM_COUNTER_NODES_LOW, CSSM_COUNTER_NODES_HIGH),
            values.wide(CSSM_COUNTER_VISITED_LOW, CSSM_COUNTER_VISITED_HIGH)};
}

void GatherTree::bind(const gpu::ShaderProgram& program, int pcf, float threshold) const {
    bake.bind(program);
    placement.bind();
    batches.bind();
    counters.bind(CSSM_BINDING_COUNTERS);
    program.set("u_pcf", pcf);
    program.set("u_threshold", threshold);
    program.set("u_jitter_seed", 0u);
    program.set("u_spots", spots ? 1 : 0);
}

}  // namespace bounce::methods::cssm
