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
//   knobs:    the method's first frame on the scene, or one at other knobs than its last (a preset or
//             bounce count of its own): the structures those knobs select (an octree, a bake) as well.
#pragma once

#include "renderer/methods/knobs.hpp"

#include <cstdint>
#include <optional>
#include <string_view>

namespace bounce {

enum class FrameChange { none, lights, objects, knobs };

constexpr std::string_view to_string(FrameChange change) {
    switch (change) {
    case FrameChange::none: return "none";
    case FrameChange::lights: return "lights";
    case FrameChange::objects: return "objects";
    case FrameChange::knobs: return "knobs";
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

// What a frame in `next` redoes after a method's last frame in `last` (none yet: knobs).
inline FrameChange change_between(const std::optional<MethodState>& last, const MethodState& next) {
    if (!last || last->knobs != next.knobs) return FrameChange::knobs;
    if (last->geometry != next.geometry) return FrameChange::objects;
    if (!last->lit || last->lights != next.lights) return FrameChange::lights;
    return FrameChange::none;
}

}  // namespace bounce
