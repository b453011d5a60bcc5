// The string-keyed factory of methods: each method's knobs (with ranges), its presets from
// `draft` to `ultra`, and how to create it. Unknown methods, presets, knobs or out-of-range values
// are InputErrors that name what was wrong and what is accepted.
#pragma once

#include "renderer/methods/cpu_method.hpp"
#include "renderer/methods/method.hpp"

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace bounce::methods {

struct KnobSpec {
    std::string name;
    double min = 0.0;
    double max = 1.0;
    bool integer = false;
    std::string description;
};

// The knob of every GPU method's direct light that sets each directional light's view cascades
// (passes::ShadowMaps), and what every preset sets it to.
KnobSpec shadow_cascades_knob();
inline constexpr double kPresetShadowCascades = 3;

// Presets every method defines, from fastest to most accurate.
const std::vector<std::string>& preset_names();

// Where a method runs: GPU methods render through Renderer on the render thread; CPU methods
// (the path-traced reference) run on their own threads and never hold the GL context. A method has
// the factory of its device and no other.
enum class MethodDevice { gpu, cpu };

struct MethodInfo {
    std::string name;
    std::string description;
    MethodDevice device = MethodDevice::gpu;
    // Indirect bounces the method models when it has no `bounces` knob (what `reference` must be
    // given for a like-for-like comparison).
    int indirect_bounces = 0;
    std::vector<KnobSpec> knobs;
    std::map<std::string, KnobValues> presets;  // every name of preset_names(), every knob set
    std::function<std::unique_ptr<Method>()> create;         // GPU methods
    std::function<std::unique_ptr<CpuMethod>()> create_cpu;  // CPU methods
    // GPU methods: the structures a frame with these knobs will hold, before any is allocated (the
    // renderer refuses frames past its memory budget with it).
    std::function<MemoryEstimate(const EstimateInput&)> estimate;
    // Why a frame with these (resolved) knobs lets indirect light through what occludes it, or empty
    // where the knobs model that visibility: a short reason, which a plan's `ruled_out` gives in
    // parentheses where most of a scene's indirect light is occluded
    // (IndirectVisibility::mostly_occluded). Null: every frame of the method models it, or the
    // method computes no indirect light.
    std::function<std::string(const KnobValues&)> unmodelled_indirect_visibility;
    // The edge of the cells a frame with these knobs gathers light in, in a scene whose largest
    // extent is `extent` (vct: its leaf voxels): a lit wall thinner than that between two spaces
    // lets light through (the scene analysis' thin walls). Null: the method has no such cells.
    std::function<double(const KnobValues&, double extent)> voxel_size;
};

class MethodRegistry {
public:
    // The registry with every built-in method.
    static const MethodRegistry& builtin();

    void add(MethodInfo info);  // throws Error if the info is incomplete
    const MethodInfo& find(const std::string& method) const;
    std::vector<std::string> names() const;
    // The preset's values with `overrides` applied, every value validated.
    KnobValues resolve(const std::string& method, const std::string& preset, const KnobValues& overrides) const;
    // The method's instance; Error when it runs on the other device.
    std::unique_ptr<Method> create(const std::string& method) const;
    std::unique_ptr<CpuMethod> create_cpu(const std::string& method) const;

private:
    std::vector<MethodInfo> methods_;
};

}  // namespace bounce::methods
