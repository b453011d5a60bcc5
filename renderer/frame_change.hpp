// What a GPU frame redoes against its method's last frame on the same scene resources. A method keeps
// its structures between frames (methods/method.hpp) and redoes only what a change invalidates, so a
// frame's time depends on what changed since, and the planner prices each case apart
// (planning/costs.hpp):
//
//   none:     nothing: a warm frame, as the bench measures methods;
//   lights:   what the lights feed: shadow maps, vct's injected light, cssm's atlas solve, isr's light
//             views and VPL tree;
//   objects:  an object moved: the lights' work, and what the objects' placement feeds besides (vct
//             voxelizes the moved objects again, cssm rebakes once an object it took for static);
//   knobs:    other knobs than the method's last frame (a preset or bounce count of its own), the
//             scene as it was: the structures those knobs select (an octree, a bake), and whatever of
//             the lights' work they size (maps of another size);
//   knobs_and_scene: other knobs, and the lights or objects changed too, or the method's first frame
//             on the scene: everything. A preset switch costs far more after a change of the lights
//             than before one (presets that share their shadow maps' size keep them otherwise).
#pragma once

#include "renderer/methods/knobs.hpp"

#include <cstdint>
#include <optional>
#include <string_view>

namespace bounce {

enum class FrameChange { none, lights, objects, knobs, knobs_and_scene };

constexpr std::string_view to_string(FrameChange change) {
    switch (change) {
    case FrameChange::none: return "none";
    case FrameChange::lights: return "lights";
    case FrameChange::objects: return "objects";
    case FrameChange::knobs: return "knobs";
    case FrameChange::knobs_and_scene: return "knobs_and_scene";
    }
    return "knobs";
}

// The state a method's structures were last made for on a scene's resources.
struct MethodState {
    methods::KnobValues knobs;
    std::uint64_t lights = 0;    // lights_fingerprint (renderer.hpp)
    std::uint64_t geometry = 0;  // passes::geometry_fingerprint: meshes and their transforms
    bool lit = false;            // a frame lit them: a `bake` request builds structures and solves no light
};

// What a frame in `next` redoes after a method's last frame in `last` (none yet: everything).
inline FrameChange change_between(const std::optional<MethodState>& last, const MethodState& next) {
    if (!last) return FrameChange::knobs_and_scene;
    const bool scene = !last->lit || last->lights != next.lights || last->geometry != next.geometry;
    if (last->knobs != next.knobs) return scene ? FrameChange::knobs_and_scene : FrameChange::knobs;
    if (last->geometry != next.geometry) return FrameChange::objects;
    return scene ? FrameChange::lights : FrameChange::none;
}

}  // namespace bounce
