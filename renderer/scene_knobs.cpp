#include "renderer/scene_knobs.hpp"

#include <algorithm>

namespace bounce {
namespace {

struct SceneKnob {
    const char* asks;  // above 0: the scene sets `sets`
    const char* sets;
};
constexpr SceneKnob kSceneKnobs[] = {{"bounce_tolerance", "bounces"}, {"ism_open_below", "ism_dilation"}};

bool asks_scene(const methods::KnobValues& knobs, const SceneKnob& knob) {
    const auto it = knobs.find(knob.asks);
    return it != knobs.end() && it->second > 0.0;
}

}  // namespace

bool leaves_knobs_to_scene(const methods::KnobValues& knobs, const methods::KnobValues& requested) {
    return std::any_of(std::begin(kSceneKnobs), std::end(kSceneKnobs), [&](const SceneKnob& knob) {
        return asks_scene(knobs, knob) && !requested.contains(knob.sets);
    });
}

void resolve_scene_knobs(const SceneAnalysis& analysis, const methods::MethodInfo& info,
                         const methods::KnobValues& requested, methods::KnobValues& knobs) {
    for (const SceneKnob& knob : kSceneKnobs) {
        if (!asks_scene(knobs, knob) || requested.contains(knob.sets)) continue;
        const auto range = std::find_if(info.knobs.begin(), info.knobs.end(), [&](const auto& k) { return k.name == knob.sets; });
        if (range == info.knobs.end()) continue;
        const double threshold = knobs.at(knob.asks);
        if (std::string(knob.sets) == "bounces") {
            knobs["bounces"] = std::clamp(static_cast<double>(analysis.bounces.bounces_for(threshold)), range->min, range->max);
        } else if (analysis.visibility.pairs > 0 && analysis.visibility.occluded_fraction < threshold) {
            knobs[knob.sets] = range->min;  // no dilation
        }
    }
}

bool set_by_scene(const methods::KnobValues& preset, const std::string& name) {
    return std::any_of(std::begin(kSceneKnobs), std::end(kSceneKnobs),
                       [&](const SceneKnob& knob) { return name == knob.sets && asks_scene(preset, knob); });
}

}  // namespace bounce
