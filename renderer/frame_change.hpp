// What a GPU frame redoes against its method's last frame on the same scene resources. A method keeps
// its structures between frames (methods/method.hpp) and redoes only what a change invalidates, so a
// frame's time depends on what changed since, and the planner prices each case apart
// (planning/costs.hpp):
//
//   none:     nothing: a warm frame, as the bench measures methods;
//   view:     the camera moved or turned, or the frame's shape changed, so that the view cascades a
//             directional light casts for the method (passes/shadow_maps.hpp) fit elsewhere, or the
//             `shadow_cascades` knob alone changed: those, redrawn (a camera moved along the light
//             fits the same, and cascades turned off are dropped: `none`);
//   light_power: a light's colour or intensity alone: what its power feeds (vct's injected light,
//             which it scales where every light's power changed by one factor and no surface emits;
//             cssm's atlas solve, isr's light views and VPL tree), not the shadow maps, which hold
//             depths (passes::shadow_map_fingerprint);
//   lights:   a light moved, turned, reshaped or was added or removed: that, and the shadow maps;
//   objects:  an object moved: the lights' work, and what the objects' placement feeds besides (vct
//             voxelizes the moved objects again, cssm rebakes once an object it took for static);
//   knobs:    other knobs than the method's last frame (a preset or bounce count of its own), the
//             scene as it was: the structures those knobs select (an octree, a bake), and whatever of
//             the lights' work they size (maps of another size);
//   knobs_and_view: the same, and the camera moved (view): the view cascades too, which a switch
//             that keeps the maps' size would otherwise keep;
//   knobs_and_scene: other knobs, and the lights or objects changed too, or the method's first frame
//             on the scene: everything. A preset switch costs far more after a change of the lights
//             than before one (presets that share their shadow maps' size keep them otherwise).
#pragma once

#include "renderer/methods/knobs.hpp"

#include <cstdint>
#include <optional>
#include <string_view>

namespace bounce {

enum class FrameChange { none, view, light_power, lights, objects, knobs, knobs_and_view, knobs_and_scene };

constexpr std::string_view to_string(FrameChange change) {
    switch (change) {
    case FrameChange::none: return "none";
    case FrameChange::view: return "view";
    case FrameChange::light_power: return "light_power";
    case FrameChange::lights: return "lights";
    case FrameChange::objects: return "objects";
    case FrameChange::knobs: return "knobs";
    case FrameChange::knobs_and_view: return "knobs_and_view";
    case FrameChange::knobs_and_scene: return "knobs_and_scene";
    }
    return "knobs";
}

// The state a method's structures were last made for on a scene's resources.
struct MethodState {
    methods::KnobValues knobs;
    std::uint64_t lights = 0;        // lights_fingerprint (renderer.hpp)
    std::uint64_t light_places = 0;  // the same without colour and intensity: what shadow maps depend on
    std::uint64_t geometry = 0;  // passes::geometry_fingerprint: meshes and their transforms
    std::uint64_t view = 0;      // passes::ShadowMaps::view_fingerprint: the suns' view cascades; 0: none
    bool lit = false;            // a frame lit them: a `bake` request builds structures and solves no light
};

// Whether a frame at these knobs (resolved) renders ambient occlusion (`ao`) instead of light: vct
// then draws no shadow maps (its light views and injected light are as ever), whatever its map
// knobs say.
inline bool renders_occlusion(const methods::KnobValues& knobs) { return methods::knob_or(knobs, "ao", 0.0) != 0.0; }

// Whether a method at these knobs (resolved) reads view cascades: its `shadow_cascades` knob, where
// it renders light.
inline bool reads_view_cascades(const methods::KnobValues& knobs) {
    return methods::knob_or(knobs, "shadow_cascades", 0.0) > 0.0 && !renders_occlusion(knobs);
}

// Whether two frames' knobs draw the same shadow maps: maps of another size are all drawn anew, and
// another count of cascades draws the cascades anew, whatever the camera did (with other knobs too,
// a switch of knobs' own work, `knobs`; alone, cascades_alone_differ). Frames of ambient occlusion
// draw none: after one, a frame of light draws every map it does not still hold, and is priced as
// drawing them all.
inline bool same_maps(const methods::KnobValues& a, const methods::KnobValues& b) {
    const auto same = [&](const char* name) { return methods::knob_or(a, name, -1.0) == methods::knob_or(b, name, -1.0); };
    return !renders_occlusion(a) && !renders_occlusion(b) && same("shadow_map_size") && same("shadow_cascades");
}

// Whether two frames' knobs differ in their count of view cascades alone. No method's structures
// depend on it, and the maps over the scene are the same: such a switch redraws the cascades (or
// drops them), as a moved camera does, and is classed as one.
inline bool cascades_alone_differ(const methods::KnobValues& a, const methods::KnobValues& b) {
    if (a == b) return false;
    methods::KnobValues a_rest = a, b_rest = b;
    a_rest.erase("shadow_cascades");
    b_rest.erase("shadow_cascades");
    return a_rest == b_rest;
}

// What a frame in `next` redoes after a method's last frame in `last` (none yet: everything). A
// light dimmed while the camera moved redoes the light's work and the cascades: predicted as a move
// of the lights, which redraws every map, the cascades among them (the frame then says
// `light_power`: Renderer::render reads which maps it drew).
inline FrameChange change_between(const std::optional<MethodState>& last, const MethodState& next) {
    if (!last) return FrameChange::knobs_and_scene;
    const bool scene = !last->lit || last->lights != next.lights || last->geometry != next.geometry;
    const bool recascaded = cascades_alone_differ(last->knobs, next.knobs);
    const bool view = last->view != next.view && reads_view_cascades(next.knobs) &&
                      (same_maps(last->knobs, next.knobs) || recascaded);
    if (last->knobs != next.knobs && !recascaded) {
        return scene ? FrameChange::knobs_and_scene : view ? FrameChange::knobs_and_view : FrameChange::knobs;
    }
    if (last->geometry != next.geometry) return FrameChange::objects;
    if (!last->lit || last->light_places != next.light_places) return FrameChange::lights;
    if (scene) return view ? FrameChange::lights : FrameChange::light_power;
    return view ? FrameChange::view : FrameChange::none;
}

}  // namespace bounce
