#include "renderer/planning/bench_bounds.hpp"

#include "renderer/methods/registry.hpp"

#include <algorithm>

namespace bounce::planning {
namespace {

// The most a warm frame at a further bounce count cost, as a multiple of the preset's at its own
// count (bench/bounce_cost.py, bench/results/bounce_cost.csv: every preset on the corpus and the
// Cornell box at 2 and 8 bounces against 1): the largest ratio measured, raised to the largest of
// the coarser presets', since a finer threshold refines at least as much where the light arrives.
struct MostBounceCost {
    const char* method;
    const char* preset;
    double ratio;
};
constexpr MostBounceCost kMostBounceCost[] = {
    {"cssm", "draft", 2.91}, {"cssm", "low", 2.91}, {"cssm", "medium", 3.12}, {"cssm", "high", 5.30}, {"cssm", "ultra", 5.37},
    {"vct", "draft", 1.23},  {"vct", "low", 1.23},  {"vct", "medium", 1.23},  {"vct", "high", 1.29},  {"vct", "ultra", 1.32}};
// The median of the same ratios (12 per cssm preset, 6 per vct preset), never below 1: what the
// planner races plans at for a target error (choose(), kTargetTimeSlack).
constexpr MostBounceCost kTypicalBounceCost[] = {
    {"cssm", "draft", 1.40}, {"cssm", "low", 1.50}, {"cssm", "medium", 1.63}, {"cssm", "high", 1.15}, {"cssm", "ultra", 1.52},
    {"vct", "draft", 1.06},  {"vct", "low", 1.02},  {"vct", "medium", 1.0},   {"vct", "high", 1.0},   {"vct", "ultra", 1.01}};

// Where the device's calibration has no figure of a change (DeviceCosts::change_cost): the most a
// frame that redid a change's work cost beyond a warm frame of its preset, as a multiple
// of that warm frame, at 128x128 on the bench corpus on llvmpipe, the largest over two runs (bench/quality
// --corpus, every light changed: relit_ms and cold_ms against wall_ms; dimmed_ms in the second;
// bench/results/corpus/frame_changes.csv, bench/frame_changes.py): in all, and less
// the shadow maps the frame drew (relit_shadow_ms, cold_shadow_ms), which a scene prices from its
// own timings of them. A cold frame's includes compiling the method's shaders for its first preset,
// which a daemon does once.
struct MostChangeCost {
    const char* method;
    const char* preset;
    double lights, lights_besides_maps;
    double knobs, knobs_besides_maps;  // an object's move is priced as knobs: it may rebuild what they select
    double light_power;  // a frame after every light was dimmed alone (bench/quality's dimmed_ms): no map
};
constexpr MostChangeCost kMostChangeCost[] = {
    {"direct", "draft", 6.9, 0.464, 12.1, 5.33, 0.0},     {"direct", "low", 22, 0.625, 23.9, 0.536, 0.0491},
    {"direct", "medium", 83.8, 0.651, 90.6, 1.1, 0.594},  {"direct", "high", 255, 0.54, 247, 1.28, 0.169},
    {"direct", "ultra", 1120, 0.917, 1200, 0.973, 0.558},
    {"vct", "draft", 2.61, 1.35, 2.96, 1.53, 1.26},       {"vct", "low", 4.94, 2.34, 5.37, 2.39, 2.25},
    {"vct", "medium", 7.28, 1.23, 6.34, 1.48, 1.1},       {"vct", "high", 5.82, 2.73, 6.16, 2.93, 2.9},
    {"vct", "ultra", 2.24, 1.29, 1.92, 1.02, 1.27},
    // isr's from two runs on 2026-12-07, when its maps splat 8192 points at medium and 16384 from high
    // and are kept for a change of intensity alone: the runs above predate its maps (2026-11-29),
    // which a frame after a move of the lights splats again, so its figures besides the shadow maps
    // rose from at most 0.6 to 2.7 to 5.5; a dimmed frame's stay under 0.11.
    {"isr", "draft", 15.5, 0.14, 16.1, 0.506, 0.05},      {"isr", "low", 7.59, 5.14, 6.14, 6.14, 0.029},
    {"isr", "medium", 7.38, 5.52, 5.51, 5.51, 0.04},      {"isr", "high", 5.37, 4.45, 4.45, 4.45, 0.107},
    {"isr", "ultra", 3.28, 2.74, 2.76, 2.76, 0.067},
    {"cssm", "draft", 6.73, 0.342, 7.01, 0.381, 0.0859},  {"cssm", "low", 2.89, 0.433, 2.04, 0.763, 0.53},
    {"cssm", "medium", 1.31, 0.587, 0.989, 0.504, 0.0857}, {"cssm", "high", 0.193, 0.0, 0.603, 0.44, 0.4},
    {"cssm", "ultra", 0.284, 0.198, 0.99, 0.874, 0.213}};

const MostChangeCost* most_change_cost(const std::string& method, const std::string& preset) {
    for (const MostChangeCost& most : kMostChangeCost) {
        if (method == most.method && preset == most.preset) return &most;
    }
    return nullptr;
}

// What a calibrated device's figure for a change (ChangeCost, measured on the Cornell box) fell short
// of what the bench corpus's frames redid, at most, in warm frames of the scene at 128x128, rounded
// up: the calibration scene is the lightest, and heavier scenes redo more of their warm frame. On
// llvmpipe (bench/change_margins.py on bench/results/corpus/frame_changes.csv and
// cost_model_llvmpipe.json, both runs; vct high in the furnished room sets vct's). Much of it is the
// noise of single frames on two cores. isr's against cost_model_llvmpipe_v13.json, the first
// calibration whose isr frames splat imperfect shadow maps (2026-12-07): a scene's maps follow its
// lights' views, not its pixels, and the furnished room's lamps make the most (isr medium there sets
// it; before, against frames without maps, 0.6 to 0.7). A change of intensity alone keeps the maps.
struct ChangeMargin {
    const char* method;
    double lights, knobs, light_power;
};
constexpr ChangeMargin kChangeMargin[] = {
    {"cssm", 0.6, 0.8, 0.6}, {"direct", 0.9, 1.3, 0.6}, {"isr", 4.1, 4.1, 0.1}, {"vct", 1.4, 1.4, 1.7}};

}  // namespace

int preset_bounces(const std::string& method, const std::string& preset) {
    const auto& presets = methods::MethodRegistry::builtin().find(method).presets;
    const auto own = presets.find(preset);
    return own != presets.end() && own->second.count("bounces") ? static_cast<int>(own->second.at("bounces")) : -1;
}

double bounce_cost_bound(const std::string& method, const std::string& preset, int bounces) {
    const int own = preset_bounces(method, preset);
    if (own < 0 || bounces <= own) return 1.0;
    for (const MostBounceCost& most : kMostBounceCost) {
        if (method == most.method && preset == most.preset) return most.ratio;
    }
    return static_cast<double>(bounces) / std::max(1, own);  // not measured: as if each bounce repeated the frame
}

double typical_bounce_cost(const std::string& method, const std::string& preset, int bounces) {
    const int own = preset_bounces(method, preset);
    if (own < 0 || bounces <= own) return 1.0;
    for (const MostBounceCost& typical : kTypicalBounceCost) {
        if (method == typical.method && preset == typical.preset) return std::max(1.0, typical.ratio);
    }
    return bounce_cost_bound(method, preset, bounces);  // not measured: nothing typical is known
}

double change_margin(const std::string& method, FrameChange change) {
    for (const ChangeMargin& margin : kChangeMargin) {
        if (method != margin.method) continue;
        return change == FrameChange::none          ? 0.0
               : change == FrameChange::light_power ? margin.light_power
               : change == FrameChange::lights || change == FrameChange::view ? margin.lights
                                                    : margin.knobs;
    }
    return 0.0;
}

double change_cost_bound(const std::string& method, const std::string& preset, FrameChange change, bool besides_maps) {
    const MostChangeCost* most = most_change_cost(method, preset);
    if (change == FrameChange::none || !most) return 0.0;
    // A light's power alone redraws no map: measured apart, since a relit frame less its maps'
    // pass read less than a dimmed frame took (isr draft in the furnished room: 0.07 against 0.40).
    if (change == FrameChange::light_power) return most->light_power;
    const double lights = besides_maps ? most->lights_besides_maps : most->lights;
    // A moved camera redraws the view cascades, which a move of the lights redraws with the rest.
    if (change == FrameChange::lights || change == FrameChange::view) return lights;
    // Structures built anew redo the lights' work too (a cold frame measured under a relit one only
    // where it kept maps of the same size, or by the noise of one frame).
    return std::max(lights, besides_maps ? most->knobs_besides_maps : most->knobs);
}

}  // namespace bounce::planning
