// What a scene needs of a method, measured on the scene itself: how much of its light arrives after
// each bounce, where a wall is thinner than vct's voxels, and how often indirect light is occluded
// on its way (which isr without its imperfect shadow maps does not model). The planner reads these
// to model only what the scene requires; `scene.describe` shows them.
#pragma once

#include "renderer/scene/scene.hpp"

#include <atomic>
#include <map>
#include <string>
#include <vector>

namespace bounce {

struct AnalysisSettings {
    // Bounce energies: the reference at this size and these samples, traced once with max_bounces;
    // its bounce prefixes are the frames of every fewer bounce count, of one seed, so that the
    // differences between counts are not noise (common random numbers). Camera rays go through pixel
    // centres, as raster methods shade (and as the planner's reference plans do).
    int bounce_image_size = 24;
    // Of one seed, the frames of two bounce counts share their paths, and their difference, squared,
    // carries the later bounces' noise: stopped errors past a bounce or two read high at few samples
    // (the atrium's at 4 bounces: 0.025 at 16, 0.013 at 64, 0.0082 at 512, 0.0078 at 4096), and the
    // first ones low where a few paths carry much of the light (the atrium's at no bounces: 0.31 at
    // 64, 0.325 at 512, 0.328 at 4096): `bounce_bench_planner --analysis-only --analysis-spp N`. An
    // unbiased form (the product of two independent halves' differences) read lower still at 64
    // samples: its typical value misses those few paths, which is no promise to keep. One trace for
    // every bounce count, not one per count, buys 512 samples in less time than 64 took (the
    // furnished room: 464 ms, analysis whole, where 508 ms).
    int bounce_spp = 512;
    // Samples of the frame without bounces that is timed apart (sample_ns: its cost and the trace's
    // give a vertex's).
    int direct_timing_spp = 16;
    int max_bounces = 12;
    int surface_samples = 4096;  // thin walls
    int visibility_pairs = 2048;  // receiver-VPL pairs for indirect visibility
    std::uint32_t seed = 1;
};

struct BounceEnergy {
    // share[k]: the part of the image's light (mean over pixels, all channels) that bounce k adds;
    // share[0] is direct light and emission. Past max_bounces the geometric tail of the last two
    // bounces is added to `tail`, so shares and tail sum to 1.
    std::vector<double> share;
    double tail = 0.0;
    // The fewest indirect bounces whose frame lacks at most `tolerance` of the light.
    int bounces_for(double tolerance) const;
    // values[k] of one of the per-count vectors below, k clamped to the counts measured; 0 for an
    // empty vector (a scene not analysed that far).
    static double at(const std::vector<double>& values, int bounces);
    // How each bounce's light past `bounces` compares with the one before: the shares of bounces
    // d+1..d+3 over those of d..d+2 (three, as one late bounce's share is noisy), at most 0.95; 0
    // where the shares end at d.
    double light_ratio_past(int bounces) const;

    // What the planner predicts from, per bounce count k = 0..max_bounces (renderer/planning/):
    // stopped_error[k]: relMSE (image::compare) of the frame with k bounces against the one with
    // max_bounces: the error of a method that models k bounces and nothing else wrong.
    std::vector<double> stopped_error;
    // noise_per_sample[k]: the mean over pixels of one path sample's luminance variance with k
    // bounces over (luminance^2 + 0.01): the reference's relMSE at s samples is about this over s.
    std::vector<double> noise_per_sample;
    // noise_against_whole[k]: the same variance over the luminance of the frame with max_bounces, the
    // relMSE per sample that the noise of a frame of k bounces makes against the reference with every
    // bounce (what a target error is measured against). Lower than noise_per_sample[k] where the later
    // bounces brighten the pixels: in the atrium 4 bounces at 64 samples measure 0.043 where their own
    // statistic predicted 0.049.
    std::vector<double> noise_against_whole;
    // sample_ns[k]: CPU time per pixel sample with k bounces on this machine's threads: the frame
    // without bounces timed, and each vertex the full trace shaded after bounce 0 at the time the
    // two frames' difference gives one.
    std::vector<double> sample_ns;
    double tracer_build_ms = 0.0;  // building the path tracer's acceleration structures, once a frame
};

struct ThinWalls {
    // Per vct preset: the voxel size (the scene's largest extent over the preset's resolution) and
    // the share of the surface area that is lit directly and is the face of a wall thinner than one
    // voxel between two spaces each wider than one voxel: where vct's voxels carry light through.
    struct Preset {
        double voxel_size = 0.0;
        double leaking_area = 0.0;
    };
    std::map<std::string, Preset> presets;
    double thinnest_separator = -1.0;  // metres; -1 where no lit surface separates two spaces
    static constexpr double kLeakAreaThreshold = 0.01;
    bool leaks(const std::string& preset) const;
};

struct IndirectVisibility {
    int pairs = 0;                   // receiver-VPL pairs that face each other
    // Of those, the share with a surface between them, each pair weighted by the light it could
    // exchange (the form factor's cos cos / d^2).
    double occluded_fraction = 0.0;
    // Where most of it is occluded, a method that gathers indirect light without occlusion (isr
    // without its imperfect shadow maps) is wrong (MethodInfo::unmodelled_indirect_visibility).
    static constexpr double kMostlyOccluded = 0.5;
    bool mostly_occluded() const { return pairs > 0 && occluded_fraction > kMostlyOccluded; }
};

struct SceneAnalysis {
    BounceEnergy bounces;
    ThinWalls thin_walls;
    IndirectVisibility visibility;
    double analysis_ms = 0.0;
};

// Runs on CPU threads (Embree, the reference), from a scene no one mutates meanwhile. Throws
// Cancelled when `cancelled` is set.
SceneAnalysis analyze_scene(const scene::Scene& scene, const AnalysisSettings& settings = {},
                            const std::atomic<bool>* cancelled = nullptr);

}  // namespace bounce
