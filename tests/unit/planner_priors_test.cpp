// The planner's priors (renderer/planning/priors.cpp) are the bench's figures: the largest and the
// median, over the corpus scenes (and for vct the Cornell variants too), of each GPU preset's relMSE
// against the reference with as many bounces, each scene of cssm and vct taken over placements of the
// atlas or grid (its largest in the largest, its mean in the median). A prior left behind when a
// method changes is no longer a promise (in one change cssm at low came to err 0.0738 on the open
// street where its prior said 0.0628), so this reads the committed tables and placement files and
// checks the priors against them, the placement files against the corpus tables (a file left behind
// fails), and that the priors of a scene held out (bench/planner --held-out) are the other scenes'.
#include "bench/corpus_priors.hpp"
#include "renderer/base/error.hpp"
#include "renderer/methods/registry.hpp"
#include "renderer/planning/error_model.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <string>

namespace bounce {
namespace {

const std::filesystem::path kCorpus = BOUNCE_SOURCE_DIR "/bench/results/corpus";

// The corpus scenes' and the Cornell variants'.
const std::map<std::string, ThinWalls>& walls() {
    static const auto by_scene = bench::bench_thin_walls();
    return by_scene;
}

const bench::PlacementErrors& placements() {
    static const auto placed = bench::read_placement_errors(bench::placement_files(kCorpus / ".."));
    return placed;
}

planning::OwnErrorPriors committed_corpus_priors(const std::set<std::string>& left_out = {}) {
    return bench::corpus_priors(kCorpus, walls(), left_out, /*two_bounce_table=*/true, placements(),
                                {bench::cornell_vct_tables(kCorpus / "..")});
}

// The errors the priors count: the corpus', and vct's of the Cornell variants.
bench::CorpusErrors counted_errors() {
    bench::CorpusErrors errors = bench::read_corpus_errors(kCorpus / "quality.csv");
    for (const auto& [key, by_scene] : bench::read_corpus_errors(kCorpus / "../quality.csv")) {
        if (key.first == "vct") errors[key].insert(by_scene.begin(), by_scene.end());
    }
    return errors;
}

// Half the last of the four decimal places the tables hold.
constexpr double kRounding = 5e-5;

void expect_tables_equal(const planning::OwnErrorPriors::Table& committed,
                         const planning::OwnErrorPriors::Table& corpus, const char* which) {
    EXPECT_EQ(committed.size(), corpus.size()) << which;
    for (const auto& [key, figure] : corpus) {
        SCOPED_TRACE(fmt::format("{} {} {}", which, key.first, key.second));
        const auto it = committed.find(key);
        ASSERT_NE(it, committed.end());
        EXPECT_NEAR(it->second, figure, kRounding) << "the table says " << it->second << ", the corpus " << figure;
    }
}

void expect_presets_equal(const std::map<std::string, double>& committed, const std::map<std::string, double>& corpus,
                          const char* which) {
    EXPECT_EQ(committed.size(), corpus.size()) << which;
    for (const auto& [preset, figure] : corpus) {
        SCOPED_TRACE(fmt::format("{} {}", which, preset));
        const auto it = committed.find(preset);
        ASSERT_NE(it, committed.end());
        EXPECT_NEAR(it->second, figure, kRounding) << "the table says " << it->second << ", the corpus " << figure;
    }
}

TEST(PlannerPriors, AreTheCorpusTablesLargestAndMedianErrors) {
    ASSERT_EQ(bench::placement_files(kCorpus / "..").size(), 2u);  // cssm's atlas, vct's grid
    const planning::OwnErrorPriors corpus = committed_corpus_priors();
    const planning::OwnErrorPriors& committed = planning::OwnErrorPriors::bench();
    EXPECT_EQ(corpus.largest.size(), 20u);  // four GPU methods, five presets
    expect_tables_equal(committed.largest, corpus.largest, "largest");
    expect_tables_equal(committed.typical, corpus.typical, "median");
    // Where vct's presets leak, apart: the furnished room leaks at draft and low, the atrium to medium,
    // the thin wall at draft, the doorway at every preset.
    EXPECT_EQ(corpus.vct_leaking_largest.size(), 5u);
    expect_presets_equal(committed.vct_leaking_largest, corpus.vct_leaking_largest, "leaking largest");
    expect_presets_equal(committed.vct_leaking_typical, corpus.vct_leaking_typical, "leaking median");
    expect_presets_equal(committed.vct_second_leaking_largest, corpus.vct_second_leaking_largest,
                         "second bounce leaking largest");
    expect_presets_equal(committed.vct_second_leaking_typical, corpus.vct_second_leaking_typical,
                         "second bounce leaking median");
    for (const auto& [key, by_scene] : bench::read_corpus_errors(kCorpus / "quality.csv")) {
        EXPECT_EQ(by_scene.size(), 5u) << key.first << " " << key.second;
    }
}

// The denoiser's bound is the largest k over bench/denoise --every-scene's scenes, each scene's the
// least that bounds its frames at every sample count; held out, the other scenes'.
TEST(PlannerPriors, TheDenoisersBoundIsTheLargestOverTheBenchScenes) {
    const auto bounds = bench::denoised_bounds(BOUNCE_SOURCE_DIR "/bench/results/denoise_scenes.csv");
    ASSERT_EQ(bounds.size(), 10u);  // the five Cornell variants and the five corpus scenes
    double largest = 0.0;
    for (const auto& [scene, k] : bounds) largest = std::max(largest, k);
    EXPECT_NEAR(planning::OwnErrorPriors::bench().denoised_largest, largest, kRounding);
    EXPECT_NEAR(committed_corpus_priors().denoised_largest, largest, 1e-12);
    for (const auto& [scene, k] : bounds) {
        SCOPED_TRACE(scene);
        double others = 0.0;
        for (const auto& [other, k_other] : bounds) {
            if (other != scene) others = std::max(others, k_other);
        }
        EXPECT_DOUBLE_EQ(committed_corpus_priors({scene}).denoised_largest, others);
    }
}

TEST(PlannerPriors, VctsSecondBounceIsItsTwoBounceCorpusTable) {
    const planning::OwnErrorPriors corpus = committed_corpus_priors();
    const planning::OwnErrorPriors& committed = planning::OwnErrorPriors::bench();
    ASSERT_EQ(corpus.vct_second_largest.size(), 5u);
    EXPECT_EQ(committed.vct_second_largest.size(), 5u);
    for (const auto& [preset, figure] : corpus.vct_second_largest) {
        SCOPED_TRACE(preset);
        EXPECT_EQ(committed.vct_second_largest.count(preset), 1u);
        EXPECT_NEAR(*committed.largest_of("vct", preset, 2), figure, kRounding);
        EXPECT_NEAR(*committed.typical_of("vct", preset, 2), corpus.vct_second_typical.at(preset), kRounding);
        EXPECT_NEAR(*planning::own_error_prior("vct", preset, 2), figure, kRounding);
    }
}

// Where most of a scene's indirect light is occluded, isr's presets with maps and cssm's presets are
// promised the largest error the Cornell variants measured of them (no corpus scene is that
// occluded), and the error model says so.
TEST(PlannerPriors, WhereMostLightIsOccludedTheCornellVariantsLargestIsPromised) {
    const bench::CorpusErrors cornell = bench::read_corpus_errors(BOUNCE_SOURCE_DIR "/bench/results/quality.csv");
    const planning::OwnErrorPriors& committed = planning::OwnErrorPriors::bench();
    EXPECT_EQ(committed.isr_occluded_largest.size(), 4u);
    EXPECT_EQ(committed.cssm_occluded_largest.size(), 5u);
    for (const std::string method : {"isr", "cssm"}) {
        const std::map<std::string, double>* table = committed.occluded_largest(method);
        ASSERT_NE(table, nullptr);
        for (const auto& [preset, promised] : *table) {
            SCOPED_TRACE(method + " " + preset);
            const auto& by_scene = cornell.at({method, preset});
            EXPECT_EQ(by_scene.size(), 5u);
            double largest = 0.0;
            for (const auto& [scene, error] : by_scene) largest = std::max(largest, error);
            EXPECT_NEAR(promised, largest, kRounding);
        }
    }
    EXPECT_EQ(committed.occluded_largest("vct"), nullptr);
    EXPECT_EQ(committed.occluded_largest("direct"), nullptr);
}

// Held out, a scene's own figures count neither in the largest nor in the median: each prior is the
// other scenes' (their largest over placements where one does not leak, the median of their means
// over placements): the other four corpus scenes', and for vct the Cornell variants' too.
TEST(PlannerPriors, AHeldOutScenesPriorsAreTheOtherScenes) {
    const bench::CorpusErrors errors = counted_errors();
    const bench::CorpusErrors corpus = bench::read_corpus_errors(kCorpus / "quality.csv");
    ASSERT_FALSE(corpus.empty());
    for (const auto& [scene, unused] : corpus.begin()->second) {
        SCOPED_TRACE(scene);
        const planning::OwnErrorPriors held_out = committed_corpus_priors({scene});
        for (const auto& [key, by_scene] : errors) {
            SCOPED_TRACE(key.first + " " + key.second);
            std::vector<double> means, largest, promised;
            for (const auto& [other, error] : by_scene) {
                if (other == scene) continue;
                double most = error, sum = 0.0;
                std::size_t count = 0;
                if (placements().count(key) && placements().at(key).count(other)) {
                    for (const bench::Placement& placement : placements().at(key).at(other)) {
                        most = std::max(most, placement.rel_mse);
                        sum += placement.rel_mse;
                        ++count;
                    }
                }
                means.push_back(count ? sum / static_cast<double>(count) : error);
                largest.push_back(most);
                if (key.first != "vct" || !walls().at(other).leaks(key.second)) promised.push_back(most);
            }
            ASSERT_EQ(means.size(), key.first == "vct" ? 9u : 4u);
            const std::vector<double> unsorted_means = means;
            if (promised.empty()) promised = largest;
            EXPECT_DOUBLE_EQ(held_out.largest.at(key), *std::max_element(promised.begin(), promised.end()));
            EXPECT_NEAR(held_out.typical.at(key), planning::median(means), 1e-12);
            if (key.first != "vct") continue;
            // Where the preset leaks, the other scenes that leak there.
            std::vector<double> leaked_largest, leaked_means;
            std::size_t other = 0;  // the index in `largest` and `unsorted_means`
            for (const auto& [name, error] : by_scene) {
                if (name == scene) continue;
                if (walls().at(name).leaks(key.second)) {
                    leaked_largest.push_back(largest[other]);
                    leaked_means.push_back(unsorted_means[other]);
                }
                ++other;
            }
            if (leaked_largest.empty()) {
                EXPECT_EQ(held_out.vct_leaking_largest.count(key.second), 0u);
                continue;
            }
            EXPECT_DOUBLE_EQ(held_out.vct_leaking_largest.at(key.second),
                             *std::max_element(leaked_largest.begin(), leaked_largest.end()));
            EXPECT_NEAR(held_out.vct_leaking_typical.at(key.second), planning::median(leaked_means), 1e-12);
        }
        // The atrium held out, the doorway alone leaks at medium: its largest over its placements.
        if (scene == "atrium") {
            double doorway = errors.at({"vct", "medium"}).at("doorway");
            for (const bench::Placement& placement : placements().at({"vct", "medium"}).at("doorway")) {
                doorway = std::max(doorway, placement.rel_mse);
            }
            EXPECT_DOUBLE_EQ(held_out.vct_leaking_largest.at("medium"), doorway);
        }
        EXPECT_EQ(held_out.vct_second_largest.size(), 5u);
    }
}

// The placement files hold, for each corpus scene, the corpus table's own frame at the preset's own
// value of the knob (bench/results/*_placement.csv are collected from bench/quality runs against
// the same references): a corpus table measured again after a method changed, with the placements
// left behind, fails here rather than leaving the priors promising from two versions of a method.
TEST(PlannerPriors, ThePlacementFilesHoldTheCorpusTablesOwnFrames) {
    const bench::CorpusErrors errors = bench::read_corpus_errors(kCorpus / "quality.csv");
    const auto& registry = methods::MethodRegistry::builtin();
    std::size_t checked = 0;
    for (const auto& [key, by_scene] : placements()) {
        const auto& [method, preset] = key;
        for (const auto& [scene, placed] : by_scene) {
            // The Cornell variants' placements are against jittered references, their tables through pixel centres.
            if (!errors.at(key).count(scene)) continue;
            SCOPED_TRACE(fmt::format("{} {} {}", method, preset, scene));
            ASSERT_GE(placed.size(), 3u);
            const std::string& knob = placed.front().knob;
            const double own_value = registry.resolve(method, preset, {}).at(knob);
            const auto own = std::find_if(placed.begin(), placed.end(), [&](const bench::Placement& placement) {
                return placement.knob == knob && placement.value == own_value;
            });
            ASSERT_NE(own, placed.end()) << "no row at the preset's own " << knob << " " << own_value;
            EXPECT_NEAR(own->rel_mse, errors.at(key).at(scene), kRounding);
            // Placements either side of the preset's own: denser and coarser.
            EXPECT_TRUE(std::any_of(placed.begin(), placed.end(), [&](auto& p) { return p.value < own_value; }));
            EXPECT_TRUE(std::any_of(placed.begin(), placed.end(), [&](auto& p) { return p.value > own_value; }));
            ++checked;
        }
    }
    EXPECT_EQ(checked, 2u * 5u * 5u);  // cssm and vct, five presets each, on the five corpus scenes
}

// How placements enter the priors, on a made-up corpus: a scene counts by its largest placement in
// the largest (its own frame included), by its placements' mean in the median, and a scene with no
// placements by its own frame.
TEST(PlannerPriors, PlacementsRaiseTheLargestAndMoveTheMedianToTheirMean) {
    const auto directory =
        std::filesystem::temp_directory_path() / fmt::format("bounce-priors-placements-{}", ::getpid());
    std::filesystem::create_directories(directory);
    std::ofstream(directory / "quality.csv") << "scene,method,preset,bounces,rel_mse_same_bounces\n"
                                             << "a,cssm,low,1,0.010\nb,cssm,low,1,0.020\nc,cssm,low,1,0.030\n";
    std::ofstream(directory / "cssm_placement.csv")
        << "scene,method,preset,knob,value,rel_mse_same_bounces,wall_ms\n"
        << "a,cssm,low,atlas_resolution,19,0.050,1\na,cssm,low,atlas_resolution,20,0.010,1\n"
        << "a,cssm,low,atlas_resolution,21,0.030,1\n"
        << "b,cssm,low,atlas_resolution,20,0.020,1\nb,cssm,low,atlas_resolution,21,0.004,1\n"
        << "elsewhere,cssm,low,atlas_resolution,20,0.900,1\n";  // not a corpus scene: not counted
    const auto placed = bench::read_placement_errors(bench::placement_files(directory));
    const planning::OwnErrorPriors without = bench::corpus_priors(directory, {}, {}, false);
    const planning::OwnErrorPriors with = bench::corpus_priors(directory, {}, {}, false, placed);
    const planning::OwnErrorPriors held_out = bench::corpus_priors(directory, {}, {"a"}, false, placed);
    const auto refusal = [&](const std::string& text) {
        std::ofstream(directory / "cssm_placement.csv") << text;
        try {
            bench::read_placement_errors(bench::placement_files(directory));
        } catch (const std::runtime_error& error) {
            return std::string(error.what());
        }
        return std::string("(read)");
    };
    const std::string no_knob = refusal("scene,method,preset,value,rel_mse_same_bounces\n");
    const std::string header = "scene,method,preset,knob,value,rel_mse_same_bounces,wall_ms\n";
    const std::string not_a_number = refusal(header + "a,cssm,low,atlas_resolution,20,0.01x,1\n");
    const std::string short_row = refusal(header + "a,cssm,low,atlas_resolution,20\n");
    std::filesystem::remove_all(directory);
    EXPECT_NE(not_a_number.find("cssm_placement.csv:2: rel_mse_same_bounces '0.01x' is not a number"),
              std::string::npos)
        << not_a_number;
    EXPECT_NE(short_row.find("cssm_placement.csv:2: 5 fields where the header has 7"), std::string::npos) << short_row;
    EXPECT_DOUBLE_EQ(without.largest.at({"cssm", "low"}), 0.030);
    EXPECT_DOUBLE_EQ(without.typical.at({"cssm", "low"}), 0.020);
    EXPECT_DOUBLE_EQ(with.largest.at({"cssm", "low"}), 0.050);  // a's placement at 19
    // Means: a 0.030, b 0.012, c (none) 0.030: the median 0.030.
    EXPECT_NEAR(with.typical.at({"cssm", "low"}), 0.030, 1e-12);
    EXPECT_DOUBLE_EQ(held_out.largest.at({"cssm", "low"}), 0.030);  // c's own: b's placements are lower
    EXPECT_NEAR(held_out.typical.at({"cssm", "low"}), 0.5 * (0.012 + 0.030), 1e-12);
    EXPECT_NE(no_knob.find("has no column 'knob'"), std::string::npos) << no_knob;
}

// Further scenes (bench::FurtherScenes: the Cornell variants for vct) count for the methods they name
// alone, beside the corpus' scenes; one without thin walls found, or one the corpus has too, is refused.
TEST(PlannerPriors, FurtherScenesCountForTheirMethodsAlone) {
    const auto root = std::filesystem::temp_directory_path() / fmt::format("bounce-priors-further-{}", ::getpid());
    std::filesystem::create_directories(root / "corpus");
    std::filesystem::create_directories(root / "more");
    std::ofstream(root / "corpus" / "quality.csv") << "scene,method,preset,bounces,rel_mse_same_bounces\n"
                                                   << "a,vct,low,1,0.010\na,cssm,low,1,0.020\n";
    std::ofstream(root / "more" / "quality.csv") << "scene,method,preset,bounces,rel_mse_same_bounces\n"
                                                 << "box,vct,low,1,0.300\nbox,cssm,low,1,0.900\n";
    const std::map<std::string, ThinWalls> walls = {{"a", ThinWalls{}}, {"box", ThinWalls{}}};
    const bench::FurtherScenes more{root / "more", {"vct"}};
    const planning::OwnErrorPriors with = bench::corpus_priors(root / "corpus", walls, {}, false, {}, {more});
    const planning::OwnErrorPriors box_held_out =
        bench::corpus_priors(root / "corpus", walls, {"box"}, false, {}, {more});
    const auto refusal = [&](const std::map<std::string, ThinWalls>& found, const bench::FurtherScenes& further) {
        try {
            bench::corpus_priors(root / "corpus", found, {}, false, {}, {further});
        } catch (const std::runtime_error& error) {
            return std::string(error.what());
        }
        return std::string("(counted)");
    };
    const std::string no_walls = refusal({{"a", ThinWalls{}}}, more);
    std::ofstream(root / "more" / "quality.csv") << "scene,method,preset,bounces,rel_mse_same_bounces\n"
                                                 << "a,vct,low,1,0.300\n";
    const std::string twice = refusal(walls, more);
    std::filesystem::remove_all(root);
    EXPECT_DOUBLE_EQ(with.largest.at({"vct", "low"}), 0.300);
    EXPECT_NEAR(with.typical.at({"vct", "low"}), 0.5 * (0.010 + 0.300), 1e-12);
    EXPECT_DOUBLE_EQ(with.largest.at({"cssm", "low"}), 0.020);  // cssm is not the further scenes' method
    EXPECT_DOUBLE_EQ(box_held_out.largest.at({"vct", "low"}), 0.010);
    EXPECT_NE(no_walls.find("no thin walls were found for scene 'box'"), std::string::npos) << no_walls;
    EXPECT_NE(twice.find("scene 'a' is in the corpus too"), std::string::npos) << twice;
}

// Where vct's preset leaks, its promise is the leaking tables' and never less than the preset's
// promise where it does not leak: the leaking tables come from few scenes (at high and ultra the
// doorway's alone, under a tenth of what the others measured).
TEST(PlannerPriors, ALeakingVctPresetIsPromisedAtLeastWhatItIsElsewhere) {
    const planning::OwnErrorPriors& bench = planning::OwnErrorPriors::bench();
    for (const std::string& preset : methods::preset_names()) {
        for (const int bounces : {1, 2}) {
            SCOPED_TRACE(fmt::format("vct {} at {} bounces", preset, bounces));
            const std::optional<double> leaking = bench.largest_of("vct", preset, bounces, /*leaking=*/true);
            const std::optional<double> elsewhere = bench.largest_of("vct", preset, bounces);
            ASSERT_TRUE(leaking && elsewhere);
            const auto& table = bounces == 1 ? bench.vct_leaking_largest : bench.vct_second_leaking_largest;
            EXPECT_DOUBLE_EQ(*leaking, std::max(table.at(preset), *elsewhere));
        }
    }
    // At high the doorway's one-bounce figure is under the others', so the others' is promised.
    EXPECT_LT(bench.vct_leaking_largest.at("high"), *bench.largest_of("vct", "high"));
    EXPECT_DOUBLE_EQ(*bench.largest_of("vct", "high", 1, true), *bench.largest_of("vct", "high"));
    // A preset without a leaking table is not promised where it leaks.
    planning::OwnErrorPriors without = bench;
    without.vct_leaking_largest.erase("high");
    EXPECT_FALSE(without.largest_of("vct", "high", 1, /*leaking=*/true));
}

// A deployment's priors (`bounced --priors FILE`, written by bench/quality --priors-out): the file's
// entries replace the bench's one by one, the rest stay, and plans name where they were measured.
TEST(PlannerPriors, ADeploymentsFileReplacesWhatItMeasuredAndKeepsTheRest) {
    const planning::OwnErrorPriors& bench = planning::OwnErrorPriors::bench();
    // What the bench writes reads back as it was.
    const auto again = planning::OwnErrorPriors::from_json(bench.to_json(), planning::OwnErrorPriors{}, "bench.json");
    EXPECT_EQ(again.largest, bench.largest);
    EXPECT_EQ(again.typical, bench.typical);
    EXPECT_EQ(again.vct_second_largest, bench.vct_second_largest);
    EXPECT_EQ(again.vct_second_typical, bench.vct_second_typical);
    EXPECT_EQ(again.isr_occluded_largest, bench.isr_occluded_largest);
    EXPECT_EQ(again.cssm_occluded_largest, bench.cssm_occluded_largest);
    EXPECT_EQ(again.vct_leaking_largest, bench.vct_leaking_largest);
    EXPECT_EQ(again.vct_leaking_typical, bench.vct_leaking_typical);
    EXPECT_EQ(again.vct_second_leaking_largest, bench.vct_second_leaking_largest);
    EXPECT_EQ(again.vct_second_leaking_typical, bench.vct_second_leaking_typical);
    // A file's leaking tables are their source where vct leaks, and there alone.
    const auto leaking = planning::OwnErrorPriors::from_json({{"vct_leaking_largest", {{"high", 0.9}}}}, bench, "l.json");
    EXPECT_EQ(*leaking.largest_of("vct", "high", 1, /*leaking=*/true), 0.9);
    EXPECT_EQ(*leaking.largest_of("vct", "draft", 1, true), bench.vct_leaking_largest.at("draft"));
    EXPECT_FALSE(leaking.largest_of("isr", "draft", 1, true).has_value());
    EXPECT_EQ(leaking.leaking_source, "l.json");
    EXPECT_EQ(leaking.source_of("vct", "high"), "the bench scenes");

    const nlohmann::json file = {{"source", "our atria"}, {"largest", {{"cssm", {{"low", 0.5}}}}},
                                 {"typical", {{"cssm", {{"low", 0.25}}}}}};
    const auto ours = planning::OwnErrorPriors::from_json(file, bench, "atria.json");
    EXPECT_EQ(*ours.largest_of("cssm", "low"), 0.5);
    EXPECT_EQ(*ours.typical_of("cssm", "low"), 0.25);
    EXPECT_EQ(*ours.largest_of("cssm", "draft"), *bench.largest_of("cssm", "draft"));
    EXPECT_EQ(ours.isr_occluded_largest, bench.isr_occluded_largest);
    EXPECT_EQ(ours.cssm_occluded_largest, bench.cssm_occluded_largest);
    EXPECT_EQ(ours.source_of("cssm", "low"), "our atria (atria.json)");
    // What the file did not measure is still the bench's, and said to be.
    EXPECT_EQ(ours.source_of("cssm", "draft"), "the bench scenes");
    EXPECT_EQ(ours.source_of("vct", "low", 2), "the bench scenes");
    EXPECT_EQ(ours.description(), "our atria (atria.json) for 1 entry, the bench scenes for the rest");
    EXPECT_EQ(ours.occluded_source, bench.occluded_source);
    // A file of vct's second bounce alone is its source there alone.
    const auto second = planning::OwnErrorPriors::from_json({{"vct_second_largest", {{"low", 0.2}}}}, bench, "v.json");
    EXPECT_EQ(*second.largest_of("vct", "low", 2), 0.2);
    EXPECT_EQ(second.source_of("vct", "low", 2), "v.json");
    EXPECT_EQ(second.source_of("vct", "low", 1), "the bench scenes");

    // A plan's error basis names them.
    SceneAnalysis analysis;
    for (int k = 0; k <= 12; ++k) {
        analysis.bounces.stopped_error.push_back(k == 12 ? 0.0 : 0.1 / std::pow(2.0, k));
        analysis.bounces.noise_per_sample.push_back(0.5);
        analysis.bounces.sample_ns.push_back(1000.0);
    }
    const auto prediction = planning::predict_error(analysis, "cssm", "low", {{"bounces", 8}}, nullptr, ours);
    EXPECT_NEAR(prediction.rel_mse, 0.5 + 0.1 / 256.0, 1e-12);
    EXPECT_NE(prediction.basis.find("on our atria (atria.json)"), std::string::npos) << prediction.basis;
    const auto draft = planning::predict_error(analysis, "cssm", "draft", {{"bounces", 8}}, nullptr, ours);
    EXPECT_NE(draft.basis.find("on the bench scenes"), std::string::npos) << draft.basis;
}

// Every malformed entry is refused naming the file and the entry, before a plan reads it.
TEST(PlannerPriors, AMalformedFileIsRefusedNamingTheEntry) {
    const planning::OwnErrorPriors& bench = planning::OwnErrorPriors::bench();
    const auto refusal = [&](const nlohmann::json& file) {
        try {
            planning::OwnErrorPriors::from_json(file, bench, "p.json");
        } catch (const InputError& error) {
            return std::string(error.what());
        }
        return std::string("(accepted)");
    };
    EXPECT_EQ(refusal({{"largest", {{"photon", {{"low", 0.1}}}}}}),
              "p.json: largest: 'photon' is not a GPU method (known: direct, vct, isr, cssm)");
    EXPECT_EQ(refusal({{"largest", {{"reference", {{"low", 0.1}}}}}}),
              "p.json: largest: 'reference' is not a GPU method (known: direct, vct, isr, cssm)");
    EXPECT_EQ(refusal({{"typical", {{"isr", {{"insane", 0.1}}}}}}),
              "p.json: typical.isr.insane: unknown preset 'insane'");
    EXPECT_EQ(refusal({{"largest", {{"isr", {{"low", -0.1}}}}}}),
              "p.json: largest.isr.low: -0.1 is not a relMSE (a finite number, at least 0)");
    EXPECT_EQ(refusal({{"largest", {{"isr", {{"low", "small"}}}}}}),
              "p.json: largest.isr.low: \"small\" is not a relMSE (a finite number, at least 0)");
    // relMSE has no upper bound: a bright frame over a black reference.
    EXPECT_EQ(refusal({{"largest", {{"isr", {{"low", 1e9}}}}}}), "(accepted)");
    EXPECT_EQ(refusal({{"largest", nlohmann::json::object()}}), "p.json: largest: empty");
    EXPECT_EQ(refusal({{"largest", {{"isr", nlohmann::json::object()}}}}), "p.json: largest.isr: empty");
    EXPECT_EQ(refusal({{"source", 7}, {"largest", {{"isr", {{"low", 0.1}}}}}}), "p.json: source: 7 is not a string");
    EXPECT_EQ(refusal({{"largest", {{"isr", 0.1}}}}), "p.json: largest.isr: expected an object, not number");
    EXPECT_EQ(refusal({{"isr_occluded_largest", {{"huge", 0.1}}}}),
              "p.json: isr_occluded_largest.huge: unknown preset 'huge'");
    EXPECT_EQ(refusal({{"cssm_occluded_largest", {{"draft", -1}}}}),
              "p.json: cssm_occluded_largest.draft: -1 is not a relMSE (a finite number, at least 0)");
    EXPECT_EQ(refusal({{"largets", {}}}),
              "p.json: unknown field 'largets' (known: source, largest, typical, vct_second_largest, "
              "vct_second_typical, isr_occluded_largest, cssm_occluded_largest, vct_leaking_largest, "
              "vct_leaking_typical, vct_second_leaking_largest, vct_second_leaking_typical, denoised_largest)");
    EXPECT_EQ(refusal(nlohmann::json::array()), "p.json: expected an object, not array");
    EXPECT_EQ(refusal({{"denoised_largest", "big"}}),
              "p.json: denoised_largest: \"big\" is not a relMSE (a finite number, at least 0)");
    EXPECT_EQ(refusal({{"denoised_largest", 0.2}}), "(accepted)");

    const auto path =
        std::filesystem::temp_directory_path() / fmt::format("bounce-priors-not-json-{}.json", ::getpid());
    std::ofstream(path) << "{\"largest\": ";
    try {
        planning::OwnErrorPriors::read(path);
        ADD_FAILURE() << "a truncated file was read";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("is not JSON"), std::string::npos) << error.what();
    }
    std::filesystem::remove(path);
}

// The bench's tables as a file (corpus_priors' JSON, as bench/quality --priors-out writes it) a
// daemon reads back as the committed tables.
TEST(PlannerPriors, TheBenchsFileOfTheCorpusReadsBackAsTheCommittedTables) {
    const planning::OwnErrorPriors corpus = committed_corpus_priors();
    const auto path = std::filesystem::temp_directory_path() / fmt::format("bounce-priors-corpus-{}.json", ::getpid());
    std::ofstream(path) << corpus.to_json().dump(2);
    const planning::OwnErrorPriors read = planning::OwnErrorPriors::read(path, planning::OwnErrorPriors{});
    std::filesystem::remove(path);
    const planning::OwnErrorPriors& bench = planning::OwnErrorPriors::bench();
    expect_tables_equal(bench.largest, read.largest, "largest");
    expect_tables_equal(bench.typical, read.typical, "typical");
    for (const auto& [preset, figure] : bench.vct_second_largest) {
        EXPECT_NEAR(read.vct_second_largest.at(preset), figure, kRounding) << preset;
        EXPECT_NEAR(read.vct_second_typical.at(preset), bench.vct_second_typical.at(preset), kRounding) << preset;
    }
    EXPECT_NEAR(read.denoised_largest, bench.denoised_largest, kRounding);
}

// A frame bench/quality could not measure (values not finite: its relMSE written as nan) makes no
// prior: the entry is NaN, whichever scene came first, and a priors file of it is refused.
TEST(PlannerPriors, AFrameTheBenchCouldNotMeasureIsNotPromised) {
    const auto directory = std::filesystem::temp_directory_path() / fmt::format("bounce-priors-nan-{}", ::getpid());
    std::filesystem::create_directories(directory);
    std::ofstream(directory / "quality.csv") << "scene,method,preset,bounces,rel_mse_same_bounces\n"
                                             << "a,cssm,low,1,0.01\nb,cssm,low,1,nan\nc,cssm,low,1,0.02\n"
                                             << "a,cssm,draft,1,0.03\n";
    const planning::OwnErrorPriors priors = bench::corpus_priors(directory, {}, {}, false);
    std::filesystem::remove_all(directory);
    EXPECT_TRUE(std::isnan(priors.largest.at({"cssm", "low"})));
    EXPECT_TRUE(std::isnan(priors.typical.at({"cssm", "low"})));
    EXPECT_EQ(priors.largest.at({"cssm", "draft"}), 0.03);
    try {
        planning::OwnErrorPriors::from_json(priors.to_json(), planning::OwnErrorPriors::bench(), "p.json");
        ADD_FAILURE() << "a prior of a frame not measured was accepted";
    } catch (const InputError& error) {
        EXPECT_NE(std::string(error.what()).find("cssm.low: null is not a relMSE"), std::string::npos) << error.what();
    }
}

}  // namespace
}  // namespace bounce
