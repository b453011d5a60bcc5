#include "renderer/scene_knobs.hpp"

#include <algorithm>
#include <optional>

namespace bounce {
namespace {

// What the scene sets a knob to, from the value the preset asks with (the tolerance, the threshold)
// within the knob's range; nullopt keeps the preset's value.
using Resolver = std::optional<double> (*)(const SceneAnalysis& analysis, double asked, const methods::KnobSpec& range);

std::optional<double> bounces_within_tolerance(const SceneAnalysis& analysis, double tolerance, const methods::KnobSpec& range) {
    return std::clamp(static_cast<double>(analysis.bounces.bounces_for(tolerance)), range.min, range.max);
}

std::optional<double> no_dilation_in_the_open(const SceneAnalysis& analysis, double open_below, const methods::KnobSpec& range) {
    // Without pairs the analysis cannot tell: the preset's dilation stays.
    if (analysis.visibility.pairs > 0 && analysis.visibility.occluded_fraction < open_below) return range.min;
    return std::nullopt;
}

struct SceneKnob {
    const char* asks;  // above 0: the scene sets `sets`
    const char* sets;
    Resolver resolve;
};
constexpr SceneKnob kSceneKnobs[] = {{"bounce_tolerance", "bounces", bounces_within_tolerance},
                                     {"ism_open_below", "ism_dilation", no_dilation_in_the_open}};

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
        if (const std::optional<double> value = knob.resolve(analysis, knobs.at(knob.asks), *range)) knobs[knob.sets] = *value;
    }
}

bool set_by_scene(const methods::KnobValues& preset, const std::string& name) {
    return std::any_of(std::begin(kSceneKnobs), std::end(kSceneKnobs),
                       [&](const SceneKnob& knob) { return name == knob.sets && asks_scene(preset, knob); });
}

}  // namespace bounce
