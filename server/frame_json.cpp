#include "server/frame_json.hpp"

namespace bounce::server {

using nlohmann::json;

double ms_between(FrameClock::Clock::time_point from, FrameClock::Clock::time_point to) {
    return std::chrono::duration<double, std::milli>(to - from).count();
}

json analysis_json(const SceneAnalysis& analysis) {
    json needed = json::object();
    for (const char* tolerance : {"0.1", "0.05", "0.02", "0.01"}) needed[tolerance] = analysis.bounces.bounces_for(std::stod(tolerance));
    json presets = json::object();
    for (const auto& [name, preset] : analysis.thin_walls.presets) {
        presets[name] = {{"voxel_size_m", preset.voxel_size}, {"leaking_area", preset.leaking_area},
                         {"leaks", analysis.thin_walls.leaks(name)}};
    }
    const double thinnest = analysis.thin_walls.thinnest_separator;
    const BounceEnergy& energy = analysis.bounces;
    return {{"bounces", {{"share", energy.share}, {"tail", energy.tail}, {"needed", needed},
                         {"stopped_error", energy.stopped_error}, {"noise_per_sample", energy.noise_per_sample},
                         {"noise_against_whole", energy.noise_against_whole},
                         {"sample_ns", energy.sample_ns}, {"tracer_build_ms", energy.tracer_build_ms}}},
            {"thin_walls", {{"thinnest_separator_m", thinnest < 0.0 ? json() : json(thinnest)}, {"presets", presets}}},
            // `isr_unsuitable`: most of it occluded, where isr without its maps is not planned (the
            // protocol's name, which clients read).
            {"indirect_visibility", {{"pairs", analysis.visibility.pairs},
                                     {"occluded_fraction", analysis.visibility.occluded_fraction},
                                     {"isr_unsuitable", analysis.visibility.mostly_occluded()}}},
            {"analysis_ms", analysis.analysis_ms}};
}

json resident_json(const std::vector<methods::ResidentStructure>& structures) {
    json resident = json::array();
    for (const auto& s : structures) resident.push_back({{"structure", s.name}, {"bytes", s.bytes}, {"reason", s.reason}});
    return resident;
}

json stats_json(const FrameStats& stats) {
    return {{"method", stats.method},
            {"preset", stats.preset},
            {"knobs", stats.knobs},
            {"resident", resident_json(stats.resident)},
            {"resident_bytes", stats.resident_bytes},
            {"method_stats", stats.method_statistics}};
}

json frame_json(const RenderResult& result, std::uint64_t scene_version, std::string_view format,
                const FrameClock& clock) {
    json passes = json::object();
    for (const auto& pass : result.stats.passes) passes[pass.pass] = pass.gpu_ms;
    json body = stats_json(result.stats);
    body["scene_version"] = scene_version;
    body["width"] = result.frame.width;
    body["height"] = result.frame.height;
    body["format"] = format;
    body["redid"] = to_string(result.stats.change);
    body["programs_compiled"] = result.stats.programs_compiled;
    body["timings_ms"] = {{"queue", ms_between(clock.received, clock.started)},
                          {"render", ms_between(clock.started, clock.rendered)},
                          {"gpu", result.stats.gpu_ms},
                          {"readback", result.stats.readback_ms},
                          {"encode", ms_between(clock.rendered, clock.encoded)},
                          {"total", ms_between(clock.received, clock.encoded)},
                          {"passes", passes}};
    return body;
}

}  // namespace bounce::server
