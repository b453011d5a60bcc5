// The planner's own-error priors (renderer/planning/priors.hpp) as bench/quality's corpus tables give
// them: per GPU method and preset, the largest and the median over the corpus scenes of the relMSE
// against the reference with as many bounces, counting vct's presets apart where the analysis finds
// them leaking (OwnErrorPriors::vct_leaking_largest: what the planner promises of them on such
// scenes). With scenes left out, the priors a scene would have had if the bench had never seen it
// (bench/planner --held-out).
#pragma once

#include "renderer/planning/priors.hpp"
#include "bench/scenes.hpp"
#include "renderer/scene_analysis.hpp"

#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace bounce::bench {

// relMSE against the reference with as many bounces, by (method, preset), then by scene.
using CorpusErrors = std::map<std::pair<std::string, std::string>, std::map<std::string, double>>;

// The same at nearby placements of a preset's samples (its atlas or voxel grid a little denser or
// coarser, everything else the preset's), by (method, preset), then by scene: one figure per
// placement, in the order the files give them.
struct Placement {
    std::string knob;  // what moves the samples: atlas_resolution, resolution
    double value = 0.0;
    double rel_mse = 0.0;
};
using PlacementErrors = std::map<std::pair<std::string, std::string>, std::map<std::string, std::vector<Placement>>>;

// The GPU rows of a bench/quality CSV (`rel_mse_same_bounces`) at `bounces`; -1: at every count (the
// presets' own). Throws std::runtime_error, naming the file, where it cannot be read or lacks a column.
CorpusErrors read_corpus_errors(const std::filesystem::path& csv, int bounces = -1);

// The rows of bench/placement_ladder.py's files (scene, method, preset, knob, value,
// rel_mse_same_bounces). Throws std::runtime_error, naming the file, as read_corpus_errors does.
PlacementErrors read_placement_errors(const std::vector<std::filesystem::path>& csvs);

// Per scene of bench/denoise --every-scene's table, the least k for which its denoised frames' relMSE
// is at most k n^kDenoisedNoiseExponent at every sample count (n the noisy frame's). Throws
// std::runtime_error, naming the file, as read_corpus_errors does.
std::map<std::string, double> denoised_bounds(const std::filesystem::path& csv);

// The committed placement files under `results` (bench/results): cssm's atlas, vct's grid.
std::vector<std::filesystem::path> placement_files(const std::filesystem::path& results);

// Each scene's thin walls, as the planner's analysis finds them (its bounce frames kept small: only
// the walls are wanted); the corpus scenes'.
std::map<std::string, ThinWalls> thin_walls_of(const std::vector<BenchScene>& scenes);
std::map<std::string, ThinWalls> corpus_thin_walls();
// The corpus scenes' and the Cornell variants' (bench/quality's): every scene the priors count.
std::map<std::string, ThinWalls> bench_thin_walls();

// Tables of bench scenes outside the corpus directory that count beside its scenes, for `methods`
// alone: bench/quality's CSVs under `directory` (quality.csv, and vct_two_bounce_quality.csv where
// it has one).
struct FurtherScenes {
    std::filesystem::path directory;
    std::set<std::string> methods;
};
// The Cornell variants' tables under `results` (bench/results) for vct. vct's own error depends on
// how its voxels meet the scene's walls and how much of the frame its cones light: in the closed,
// indirectly lit box vct draft errs 0.31 at one bounce and 0.28 at two, where the open corpus' largest
// was 0.066 and 0.038, and bench/planner --cornell measured the promise broken (0.233 where 0.073
// was promised). isr's and cssm's Cornell figures are not taken in: where most light is occluded
// they have tables of their own (OwnErrorPriors::occluded_largest), and in the open boxes their
// planned frames kept the corpus' promises. The Cornell variants' rows of the placement files count
// as the corpus' do, though they are against jittered references where the tables are through pixel
// centres (the closed box's vct draft 0.041 at its own grid, 0.048 in its table): in the indirectly
// lit box vct draft reads 0.31 at its own grid, 0.61 at a grid of 26 and 0.53 at 22.
FurtherScenes cornell_vct_tables(const std::filesystem::path& results);

// The priors from `directory`'s quality.csv (one bounce) and, with `two_bounce_table` and where it
// has one, vct_two_bounce_quality.csv, over the scenes not in `left_out`. Where `placements` holds a
// scene's preset at nearby placements, that scene counts by the largest of them (and its own
// frame) in the largest, and by their mean in the median (the leaking tables likewise, over the
// scenes where vct's preset leaks): a preset's error at its own placement is
// one draw (cssm draft's in the atrium 0.018, 0.018 to 0.029 over five), and a promise must hold
// wherever a scene's surfaces fall in the atlas or grid. `further` adds other bench scenes' tables
// for the methods each names; `walls` must hold those scenes too (std::runtime_error naming the
// scene where it does not, or where a scene is in both). Where `directory`/../denoise_scenes.csv is
// (bench/denoise --every-scene), the denoiser's bound too (OwnErrorPriors::denoised_largest): the
// largest of denoised_bounds() over the scenes not left out.
planning::OwnErrorPriors corpus_priors(const std::filesystem::path& directory,
                                       const std::map<std::string, ThinWalls>& walls,
                                       const std::set<std::string>& left_out = {}, bool two_bounce_table = true,
                                       const PlacementErrors& placements = {},
                                       const std::vector<FurtherScenes>& further = {});

}  // namespace bounce::bench
