// What the bench measured frames cost on the corpus, for prices before a scene has measured its own:
// the most and the typical cost of further bounces (bench/bounce_cost.py), and the most a frame
// that redoes a change's work cost beyond a warm one (bench/quality, bench/change_margins.py). The
// planner (planner.hpp) prices by them until the scene's frames tell.
#pragma once

#include "renderer/frame_change.hpp"

#include <string>

namespace bounce::planning {

// A preset's own `bounces` knob, or -1 where the method has none.
int preset_bounces(const std::string& method, const std::string& preset);

// What a warm frame at `bounces` may cost, as a multiple of one at the preset's own count, before the
// scene measured the count: 1 at the preset's count or fewer; else the most the bench measured a
// further count cost (bench/bounce_cost.py). A further bounce does not repeat the frame: cssm
// solves its atlas once per lighting and vct injects its second bounce with the light, so a warm
// frame gathers as many pixels whatever the count. What grows is cssm's final gather, which refines
// the radiosity tree wherever more light arrives: warm frames at 2 and 8 bounces took 0.8 to 5.4
// times those at 1, and vct's at 2, 0.7 to 1.3 times.
double bounce_cost_bound(const std::string& method, const std::string& preset, int bounces);
// What such a frame typically costs: the median of the same measurements, never below 1. Where the
// largest is 2.9 (cssm draft: the glossy gallery's 8 bounces), the median is 1.4.
double typical_bounce_cost(const std::string& method, const std::string& preset, int bounces);

// What a frame that redoes `change`'s work may cost beyond a warm one, as a multiple of the preset's
// warm frame at kChangePriorPixels, before the scene measured it: the most the bench measured
// (bench/quality's relit_ms for lights, cold_ms for knobs, against wall_ms, every preset on the
// corpus, 128x128, each cold frame right after the lights changed back: knobs_and_scene; for
// light_power, dimmed_ms: every light dimmed alone, which redraws no shadow map); knobs
// and a moved object as that, since either may rebuild what the knobs select (cssm rebakes an
// object it took for static). `besides_maps`: less the shadow maps such frames drew, for a scene
// that prices those from its own timings (SceneMeasurements::shadow_maps_ms): their cost follows
// the scene's triangles and lights, not the warm frame's pixels. A moved camera (view) as a move of
// the lights, which redraws its cascades and more. 0 for FrameChange::none and for methods the bench
// has no figure of.
inline constexpr double kChangePriorPixels = 128.0 * 128.0;
// What a device's calibrated figure for a change fell short of the bench corpus's frames, at most, in
// warm frames at kChangePriorPixels (bench/change_margins.py): added to it, since the calibration
// scene is the lightest. 0 for none and for methods without a figure.
double change_margin(const std::string& method, FrameChange change);
double change_cost_bound(const std::string& method, const std::string& preset, FrameChange change,
                         bool besides_maps = false);

}  // namespace bounce::planning
