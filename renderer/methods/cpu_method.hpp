// The interface of methods that render on CPU threads (the path-traced reference). They never touch
// the GL context, so the daemon runs them on its CPU pool while the render thread serves GPU
// frames. A CPU method reads a snapshot of the scene that nothing mutates while it runs.
#pragma once

#include "renderer/image/frame.hpp"
#include "renderer/methods/knobs.hpp"
#include "renderer/scene/scene.hpp"

#include <atomic>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace bounce::methods {

struct CpuFrameContext {
    const scene::Scene& scene;
    const scene::Camera& camera;
    int width = 0;
    int height = 0;
    const KnobValues& knobs;  // resolved and validated by the registry
    // Set from another thread to stop the frame: render() then throws Cancelled, after at most one
    // pixel's samples on each worker.
    const std::atomic<bool>* cancelled = nullptr;
};

// A frame that a CPU method's work made on the way to the one asked for, as if rendered alone with
// `knobs` (the reference: its paths stopped after fewer bounces).
struct ByproductFrame {
    image::Frame frame;
    KnobValues knobs;
    std::map<std::string, double> statistics;  // as statistics() would give for it alone
};

class CpuMethod {
public:
    virtual ~CpuMethod() = default;
    virtual std::string_view name() const = 0;
    // Linear HDR radiance, RGBA32F, rows top to bottom. Throws Cancelled when frame.cancelled is set.
    virtual image::Frame render(const CpuFrameContext& frame) = 0;
    // Counts that describe the last frame (rays traced, samples), reported with it.
    virtual std::map<std::string, double> statistics() const { return {}; }
    // The last frame's byproducts, moved out (none by default).
    virtual std::vector<ByproductFrame> take_byproducts() { return {}; }
};

}  // namespace bounce::methods
