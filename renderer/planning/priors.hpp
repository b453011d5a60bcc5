// What the bench measured of each GPU method's own error, the planner's prior where a scene has
// measured nothing of it (error_model.hpp): per method and preset, the relMSE against the reference
// with as many bounces, at 128x128 through pixel centres, the largest (a promise) and the median (what
// a spot check expects) over the bench corpus' scenes, and for vct the Cornell variants' too. The
// daemon plans with the committed tables (bench()), or with a deployment's own (`bounced --priors
// FILE`, measured on its own scenes by `bounce_bench_quality --gltf FILE --priors-out FILE`);
// bench/planner --held-out plans each scene with the tables of the others, which says whether the
// promises hold on a scene the priors never saw.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>

namespace bounce::planning {

// The exponent of the denoiser's bound (OwnErrorPriors::denoised_largest): of 0.5 to 1, the one that
// spread the bench scenes' k least (2.6x at 0.7, 3.6x at 0.5, 9.4x at 1).
inline constexpr double kDenoisedNoiseExponent = 0.7;
// The samples per pixel the denoiser's bound was measured at: a denoised reference is offered there
// alone, and in frames at least as large as it was measured in, 128 pixels a side. The filter's
// holes reach 16 pixels and its last pass 32 either side whatever the frame's size: in a smaller
// frame they blur across more of the scene (at 48x48 the Cornell box's denoised frame of one
// bounce erred 0.102 where 0.099 was promised).
inline constexpr int kDenoisedLeastSpp = 4;
inline constexpr int kDenoisedMostSpp = 64;
inline constexpr int kDenoisedLeastSide = 128;

struct OwnErrorPriors {
    using Table = std::map<std::pair<std::string, std::string>, double>;  // by (method, preset)
    Table largest, typical;
    // vct with its second bounce (`bounces` 2), against the two-bounce reference, by preset: the
    // leaves' gather adds its own error, so the one-bounce tables do not carry over.
    std::map<std::string, double> vct_second_largest, vct_second_typical;
    // isr's presets that make imperfect shadow maps, where most of a scene's indirect light is
    // occluded (IndirectVisibility::mostly_occluded): no corpus scene is, and the largest over the
    // Cornell variants (bench/results/quality.csv), with walls between light and receivers, is
    // promised there.
    std::map<std::string, double> isr_occluded_largest;
    // cssm's presets there, the same way: its coarser atlases err far more behind walls than the open
    // corpus measured (draft 0.19 on the thin wall and 0.10 in the doorway, 0.029 at most on the
    // corpus), and in the doorway cssm draft at 8 bounces, promised 0.030, measured 0.26.
    std::map<std::string, double> cssm_occluded_largest;
    // The table above for `method` (nullptr for methods without one).
    const std::map<std::string, double>* occluded_largest(const std::string& method) const;
    // vct's presets where the analysis finds walls thinner than their voxels (ThinWalls::leaks), by
    // preset: the largest and the median over the bench scenes where that preset leaks (each, as the
    // tables above, over placements of its grid), and the same of its second bounce. Leaked light is
    // measured on few scenes and errs far more (vct draft in the furnished room 0.76 to 2.7 against
    // the reference of one bounce), so what is promised there is that, and never less than the
    // preset's table where it does not leak (largest_of); a preset with no such table is ruled out
    // where it leaks, until the scene's own frames measure it (error_model.hpp).
    std::map<std::string, double> vct_leaking_largest, vct_leaking_typical;
    std::map<std::string, double> vct_second_leaking_largest, vct_second_leaking_typical;
    // The reference's denoiser (`denoise` 1): what it leaves of a frame's noise n (the relMSE the
    // noisy frame would have), and adds, is at most denoised_largest * n^kDenoisedNoiseExponent, the
    // largest k over the bench scenes at 4 to 64 spp, 8 bounces, 128x128 through pixel centres
    // (bench/denoise --every-scene: bench/results/denoise_scenes.csv). 0: not known, and the planner
    // offers no denoised reference; to_json() leaves it out then, so that a file of tables measured
    // without it keeps the base's.
    double denoised_largest = 0.0;
    std::string denoised_source = "the bench scenes";
    // Where the tables were measured, as a plan's `why` names them ("on the bench scenes"): every
    // entry's, or, where `from_file` is not empty, the entries it lists (a file's), the others
    // `base_source`'s.
    std::string source = "the bench scenes";
    std::string base_source = "the bench scenes";
    std::set<std::pair<std::string, std::string>> from_file;  // (method, preset); vct's second bounce as "vct-2"
    std::string occluded_source = "the bench's occluded Cornell variants";
    std::string leaking_source = "the bench scenes where it leaks";
    // Where the prior of `method` at `preset` and `bounces` was measured.
    const std::string& source_of(const std::string& method, const std::string& preset, int bounces = 1) const;
    // Where all of them were: "SOURCE", or "SOURCE for N entries, BASE for the rest".
    std::string description() const;

    // The largest at `bounces` where measured apart at that count (vct's second bounce), else at the
    // preset's own; nullopt for methods without one.
    // `leaking`: where the scene's walls are thinner than vct's voxels at the preset, the leaking
    // tables, and for the largest at least what the preset's table promises where it does not leak
    // (nullopt where they have no entry; methods other than vct have none).
    std::optional<double> largest_of(const std::string& method, const std::string& preset, int bounces = 1,
                                     bool leaking = false) const;
    std::optional<double> typical_of(const std::string& method, const std::string& preset, int bounces = 1,
                                     bool leaking = false) const;

    // The committed corpus tables (tests/unit/planner_priors_test.cpp checks them against
    // bench/results/corpus).
    static const OwnErrorPriors& bench();

    // The tables as JSON: {"source", "largest": {METHOD: {PRESET: relMSE}}, "typical": {...},
    // "vct_second_largest": {PRESET: relMSE}, "vct_second_typical", "isr_occluded_largest", "cssm_occluded_largest",
    // "vct_leaking_largest", "vct_leaking_typical", "vct_second_leaking_largest",
    // "vct_second_leaking_typical", "denoised_largest": k}; the tables left empty (and k at 0) are left out.
    nlohmann::json to_json() const;
    // `base` (one source's tables, as bench() is) with what `file` measured in its place, entry by
    // entry (a file may give some methods or presets alone); its `source` names the file's scenes in
    // plans of its entries, with the file. Throws
    // InputError naming the file and the entry: a field other than those above, a table or method
    // that is not an object, an empty table, a method that is not a GPU method, an unknown preset, a
    // value that is not a finite relMSE (at least 0), a `source` that is not a string.
    static OwnErrorPriors read(const std::filesystem::path& file, const OwnErrorPriors& base = bench());
    static OwnErrorPriors from_json(const nlohmann::json& tables, const OwnErrorPriors& base, const std::string& where);
};

}  // namespace bounce::planning
