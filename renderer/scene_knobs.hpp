// Knobs a method leaves to the scene: set from its analysis (renderer/scene_analysis.hpp) when a
// frame is planned or rendered, unless the request set them itself.
//   - `bounce_tolerance` above 0 sets `bounces` (cssm): the fewest whose frame lacks at most that
//     share of the light, within the knob's range;
//   - `ism_open_below` above 0 sets `ism_dilation` (isr) to 0 where the analysis finds less than
//     that share of the indirect light occluded: in an open room the maps' dilation takes light
//     that reaches its receivers, and behind walls it keeps light from leaking (docs/methods.md,
//     "The maps' hole filling").
// The renderer and the planner resolve them alike, so that a plan's knobs are its frame's.
#pragma once

#include "renderer/methods/knobs.hpp"
#include "renderer/methods/registry.hpp"
#include "renderer/scene_analysis.hpp"

#include <string>

namespace bounce {

// Whether `knobs` (a preset's, with the request's over them) leave a knob to the scene that
// `requested` (the request's own knobs) did not set.
bool leaves_knobs_to_scene(const methods::KnobValues& knobs, const methods::KnobValues& requested);

// Sets, in `knobs`, what they leave to the scene and `requested` did not set.
void resolve_scene_knobs(const SceneAnalysis& analysis, const methods::MethodInfo& info,
                         const methods::KnobValues& requested, methods::KnobValues& knobs);

// Whether `name` is a knob that `preset` (a preset's knobs) leaves to the scene: its value in a
// frame of the preset depends on the scene.
bool set_by_scene(const methods::KnobValues& preset, const std::string& name);

}  // namespace bounce
