// The interface every GPU method implements, and what a frame hands it (CPU methods implement
// cpu_method.hpp's CpuMethod instead).
//
// A method is a plug-in: one folder under renderer/methods/, one class behind this interface,
// registered by name in registry.cpp with its knobs and presets. Nothing outside its folder knows
// its internals. A method instance lives as long as its scene is resident, so it keeps its
// precomputed structures between frames and rebuilds only what a change invalidates.
#pragma once

#include "renderer/methods/knobs.hpp"
#include "renderer/passes/pass_context.hpp"

#include <atomic>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace bounce::methods {

// What long precomputations (bakes) may use: a directory where they persist across restarts, and
// a progress report (fraction done, stage) that cancels the work when it returns false.
struct Precompute {
    std::optional<std::filesystem::path> cache_dir;
    std::function<bool(double fraction, const std::string& stage)> progress;
};

// Everything a method needs to render one frame: the pass context plus the resolved knobs. The
// method draws linear HDR radiance into `output` (RGBA32F, width x height, alpha = coverage),
// clearing it first.
struct FrameContext : passes::PassContext {
    const KnobValues& knobs;
    const Precompute& precompute;
    const std::atomic<bool>* cancelled = nullptr;  // set: the frame is no longer wanted

    // Where long GPU work may stop: between its bounded dispatches. When the frame can be cancelled,
    // waits for the GPU to finish what was submitted (so a cancel is seen within one batch of work,
    // not after the whole queue) and throws Cancelled if it was; without a cancel flag, nothing.
    void interruption_point() const;
    // A knob's value (validated by the registry, so present for every knob the method declares).
    double knob(std::string_view name) const;
    int knob_int(std::string_view name) const { return static_cast<int>(knob(name)); }
};

// What a frame would make a method hold, asked before anything is allocated: the scene, the
// resolved knobs and the frame size.
struct EstimateInput {
    const scene::Scene& scene;
    const KnobValues& knobs;
    int width = 0;
    int height = 0;

    double knob(std::string_view name) const;
    int knob_int(std::string_view name) const { return static_cast<int>(knob(name)); }
};

// One structure of an estimate, and what sizes it: the knob whose value it grows with, "frame size",
// or nothing (the scene alone). Structures whose size depends on what the GPU finds (a sparse
// octree's nodes, compressed depth runs) are estimated from the scene's surface area and say so in
// their method's estimate function.
struct StructureEstimate {
    std::string name;
    std::uint64_t bytes = 0;
    std::string scaled_by;
};
using MemoryEstimate = std::vector<StructureEstimate>;

// What every GPU method holds for direct light: the G-buffer at the frame size and a shadow map per
// light at the `shadow_map_size` knob.
MemoryEstimate direct_light_estimate(const EstimateInput& input);

// The result of a method's long CPU work (a bake), made off the render thread by PendingWork::run and
// handed back to the method that asked for it by Method::install.
class PrecomputeResult {
public:
    virtual ~PrecomputeResult() = default;
};

using PrecomputeProgress = std::function<bool(double fraction, const std::string& stage)>;

// Long CPU work a frame needs first. `run` reads only what it captured (a snapshot of the scene),
// never the method or the live scene, so it may run on any thread while the render thread serves
// other frames; it reports progress and throws Cancelled when `progress` returns false.
struct PendingWork {
    std::string key;  // equal keys: the same work, so frames waiting for it can share one run
    std::function<std::shared_ptr<PrecomputeResult>(const PrecomputeProgress& progress)> run;
};

class Method {
public:
    virtual ~Method() = default;
    virtual std::string_view name() const = 0;
    virtual void render(const FrameContext& frame) = 0;
    // Builds the precomputed structures these knobs need without drawing a frame (the `bake`
    // request), reporting progress through frame.precompute, and returns whether it built any (the
    // next frame at these knobs then redoes only the light, frame_change.hpp). Nothing by default:
    // render() builds what it needs lazily.
    virtual bool prepare(const FrameContext& frame) {
        (void)frame;
        return false;
    }
    // Long CPU work this frame would otherwise do inline on the render thread (render() and prepare()
    // still do it there when nobody ran it first); none by default.
    virtual std::optional<PendingWork> pending_work(const FrameContext& frame) {
        (void)frame;
        return std::nullopt;
    }
    // Takes a finished PendingWork's result; the next frame uses it if it still serves that frame
    // (the scene may have changed meanwhile).
    virtual void install(std::shared_ptr<PrecomputeResult> result) { (void)result; }
    // The structures held right now, with their bytes and the reason each exists.
    virtual std::vector<ResidentStructure> resident() const = 0;
    // Counts that describe the method's state after the last frame (structure sizes, how often each
    // structure was rebuilt), reported with every frame; empty by default.
    virtual std::map<std::string, double> statistics() const { return {}; }
};

}  // namespace bounce::methods
