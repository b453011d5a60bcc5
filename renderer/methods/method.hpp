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

#include <filesystem>
#include <functional>
#include <map>
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

    // A knob's value (validated by the registry, so present for every knob the method declares).
    double knob(std::string_view name) const;
    int knob_int(std::string_view name) const { return static_cast<int>(knob(name)); }
};

class Method {
public:
    virtual ~Method() = default;
    virtual std::string_view name() const = 0;
    virtual void render(const FrameContext& frame) = 0;
    // Builds the precomputed structures these knobs need without drawing a frame (the `bake`
    // request), reporting progress through frame.precompute. Nothing by default: render() builds
    // what it needs lazily.
    virtual void prepare(const FrameContext& frame) { (void)frame; }
    // The structures held right now, with their bytes and the reason each exists.
    virtual std::vector<ResidentStructure> resident() const = 0;
    // Counts that describe the method's state after the last frame (structure sizes, how often each
    // structure was rebuilt), reported with every frame; empty by default.
    virtual std::map<std::string, double> statistics() const { return {}; }
};

}  // namespace bounce::methods
