#include "renderer/methods/registry.hpp"

#include "renderer/base/error.hpp"
#include "renderer/methods/cssm/cssm_method.hpp"
#include "renderer/methods/direct/direct_method.hpp"
#include "renderer/methods/isr/isr_method.hpp"
#include "renderer/methods/vct/vct_method.hpp"
#include "renderer/methods/reference/reference_method.hpp"

#include <algorithm>
#include <cmath>

namespace bounce::methods {
namespace {
std::string join(const std::vector<std::string>& items) {
    std::string text;
    for (const auto& item : items) text += (text.empty() ? "" : ", ") + item;
    return text;
}
}  // namespace

KnobSpec shadow_cascades_knob() {
    return {"shadow_cascades", 0, 4, true,
            "per directional light, shadow maps of shadow_map_size fitted to what the camera sees, nested to depths "
            "far / 3^k: finer shadows near the camera, redrawn when it moves (0: the map over the whole scene alone)"};
}

const std::vector<std::string>& preset_names() {
    static const std::vector<std::string> names = {"draft", "low", "medium", "high", "ultra"};
    return names;
}

const MethodRegistry& MethodRegistry::builtin() {
    static const MethodRegistry registry = [] {
        MethodRegistry r;
        r.add(direct::method_info());
        r.add(vct::method_info());
        r.add(isr::method_info());
        r.add(cssm::method_info());
        r.add(reference::method_info());
        return r;
    }();
    return registry;
}

void MethodRegistry::add(MethodInfo info) {
    const bool gpu = info.device == MethodDevice::gpu;
    BOUNCE_CHECK(gpu ? info.create != nullptr && info.create_cpu == nullptr
                     : info.create_cpu != nullptr && info.create == nullptr,
                 "method '{}' must have exactly the factory of its device ({})", info.name, gpu ? "gpu" : "cpu");
    BOUNCE_CHECK(!gpu || info.estimate != nullptr, "GPU method '{}' must estimate its memory", info.name);
    for (const auto& preset : preset_names()) {
        const auto it = info.presets.find(preset);
        BOUNCE_CHECK(it != info.presets.end(), "method '{}' lacks preset '{}'", info.name, preset);
        for (const auto& knob : info.knobs) {
            BOUNCE_CHECK(it->second.count(knob.name) == 1, "method '{}' preset '{}' lacks knob '{}'", info.name,
                         preset, knob.name);
        }
    }
    methods_.push_back(std::move(info));
}

const MethodInfo& MethodRegistry::find(const std::string& method) const {
    for (const auto& info : methods_) {
        if (info.name == method) return info;
    }
    throw InputError(fmt::format("unknown method '{}' (known: {})", method, join(names())));
}

std::vector<std::string> MethodRegistry::names() const {
    std::vector<std::string> names;
    for (const auto& info : methods_) names.push_back(info.name);
    return names;
}

KnobValues MethodRegistry::resolve(const std::string& method, const std::string& preset,
                                   const KnobValues& overrides) const {
    const MethodInfo& info = find(method);
    const auto preset_it = info.presets.find(preset);
    if (preset_it == info.presets.end()) {
        throw InputError(fmt::format("unknown preset '{}' for method '{}' (known: {})", preset, method,
                                     join(preset_names())));
    }
    KnobValues values = preset_it->second;
    for (const auto& [name, value] : overrides) {
        // Compared by a named reference: clang before 16 does not capture structured bindings.
        const std::string& knob = name;
        const auto spec = std::find_if(info.knobs.begin(), info.knobs.end(),
                                       [&](const KnobSpec& k) { return k.name == knob; });
        if (spec == info.knobs.end()) {
            std::vector<std::string> known;
            for (const auto& k : info.knobs) known.push_back(k.name);
            throw InputError(fmt::format("unknown knob '{}' for method '{}' (knobs: {})", name, method, join(known)));
        }
        if (!std::isfinite(value) || value < spec->min || value > spec->max) {
            throw InputError(fmt::format("knob '{}' of method '{}' is {}, outside [{}, {}]", name, method, value,
                                         spec->min, spec->max));
        }
        if (spec->integer && value != std::floor(value)) {
            throw InputError(fmt::format("knob '{}' of method '{}' must be an integer, got {}", name, method, value));
        }
        values[name] = value;
    }
    return values;
}

std::unique_ptr<Method> MethodRegistry::create(const std::string& method) const {
    const MethodInfo& info = find(method);
    BOUNCE_CHECK(info.device == MethodDevice::gpu, "method '{}' runs on CPU threads, not through the GL renderer", method);
    return info.create();
}

std::unique_ptr<CpuMethod> MethodRegistry::create_cpu(const std::string& method) const {
    const MethodInfo& info = find(method);
    BOUNCE_CHECK(info.device == MethodDevice::cpu, "method '{}' runs on the GPU, not on CPU threads", method);
    return info.create_cpu();
}

}  // namespace bounce::methods
