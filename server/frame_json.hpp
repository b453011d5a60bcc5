// The one place frame statistics become JSON: frame replies, bake replies and scene.describe all
// describe methods, knobs and resident structures the same way (docs/protocol.md, "frame").
#pragma once

#include "renderer/renderer.hpp"
#include "renderer/scene_analysis.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdint>
#include <string_view>
#include <vector>

namespace bounce::server {

// [{"structure", "bytes", "reason"}, ...]
nlohmann::json resident_json(const std::vector<methods::ResidentStructure>& structures);

// method, preset, knobs, resident, resident_bytes, method_stats.
nlohmann::json stats_json(const FrameStats& stats);

// When a frame's request passed each stage, for its timings.
struct FrameClock {
    using Clock = std::chrono::steady_clock;
    Clock::time_point received, started, rendered, encoded;
};

// A frame reply's body: stats_json() plus the scene version, size, format and timings_ms (queue,
// render, gpu, readback, encode, total, passes).
nlohmann::json frame_json(const RenderResult& result, std::uint64_t scene_version, std::string_view format,
                          const FrameClock& clock);

// scene.describe's `analysis`: bounces {share, tail, needed {tolerance: bounces}}, thin_walls
// {thinnest_separator_m, presets {name: {voxel_size_m, leaking_area, leaks}}}, indirect_visibility
// {pairs, occluded_fraction, isr_unsuitable}, analysis_ms.
nlohmann::json analysis_json(const SceneAnalysis& analysis);

double ms_between(FrameClock::Clock::time_point from, FrameClock::Clock::time_point to);

}  // namespace bounce::server
