// The planner's priors (renderer/planning/priors.cpp) are the bench's figures: the largest and the
// median, over the corpus scenes, of each GPU preset's relMSE against the reference with as many
// bounces. A prior left behind when a method changes is no longer a promise (in one change cssm at
// low came to err 0.0738 on the open street where its prior said 0.0628), so this reads the
// committed corpus tables and checks the priors against them; and that the priors of a scene held
// out (bench/planner --held-out) are the other scenes'.
#include "bench/corpus_priors.hpp"
#include "renderer/base/error.hpp"
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

const std::map<std::string, ThinWalls>& walls() {
    static const auto by_scene = bench::corpus_thin_walls();
    return by_scene;
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

TEST(PlannerPriors, AreTheCorpusTablesLargestAndMedianErrors) {
    const planning::OwnErrorPriors corpus = bench::corpus_priors(kCorpus, walls());
    const planning::OwnErrorPriors& committed = planning::OwnErrorPriors::bench();
    EXPECT_EQ(corpus.largest.size(), 20u);  // four GPU methods, five presets
    expect_tables_equal(committed.largest, corpus.largest, "largest");
    expect_tables_equal(committed.typical, corpus.typical, "median");
    for (const auto& [key, by_scene] : bench::read_corpus_errors(kCorpus / "quality.csv")) {
        EXPECT_EQ(by_scene.size(), 5u) << key.first << " " << key.second;
    }
}

TEST(PlannerPriors, VctsSecondBounceIsItsTwoBounceCorpusTable) {
    const planning::OwnErrorPriors corpus = bench::corpus_priors(kCorpus, walls());
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

// Where most of a scene's indirect light is occluded, isr's presets with maps are promised the largest
// error the Cornell variants measured of them (no corpus scene is that occluded), and the error model
// says so.
TEST(PlannerPriors, IsrWhereMostLightIsOccludedIsPromisedTheCornellVariantsLargest) {
    const bench::CorpusErrors cornell = bench::read_corpus_errors(BOUNCE_SOURCE_DIR "/bench/results/quality.csv");
    const planning::OwnErrorPriors& committed = planning::OwnErrorPriors::bench();
    EXPECT_EQ(committed.isr_occluded_largest.size(), 4u);
    for (const std::string preset : {"low", "medium", "high", "ultra"}) {
        SCOPED_TRACE(preset);
        const auto& by_scene = cornell.at({"isr", preset});
        EXPECT_EQ(by_scene.size(), 5u);
        double largest = 0.0;
        for (const auto& [scene, error] : by_scene) largest = std::max(largest, error);
        EXPECT_NEAR(committed.isr_occluded_largest.at(preset), largest, kRounding);
    }
}

// Held out, a scene's own figure counts neither in the largest nor in the median: each prior is the
// other four scenes' (their largest where one does not leak, the mean of their middle two).
TEST(PlannerPriors, AHeldOutScenesPriorsAreTheOtherScenes) {
    const bench::CorpusErrors errors = bench::read_corpus_errors(kCorpus / "quality.csv");
    for (const auto& [scene, thin] : walls()) {
        SCOPED_TRACE(scene);
        const planning::OwnErrorPriors held_out = bench::corpus_priors(kCorpus, walls(), {scene});
        for (const auto& [key, by_scene] : errors) {
            SCOPED_TRACE(key.first + " " + key.second);
            std::vector<double> others, promised;
            for (const auto& [other, error] : by_scene) {
                if (other == scene) continue;
                others.push_back(error);
                if (key.first != "vct" || !walls().at(other).leaks(key.second)) promised.push_back(error);
            }
            ASSERT_EQ(others.size(), 4u);
            if (promised.empty()) promised = others;
            std::sort(others.begin(), others.end());
            EXPECT_DOUBLE_EQ(held_out.largest.at(key), *std::max_element(promised.begin(), promised.end()));
            EXPECT_DOUBLE_EQ(held_out.typical.at(key), 0.5 * (others[1] + others[2]));
        }
        EXPECT_EQ(held_out.vct_second_largest.size(), 5u);
    }
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

    const nlohmann::json file = {{"source", "our atria"}, {"largest", {{"cssm", {{"low", 0.5}}}}},
                                 {"typical", {{"cssm", {{"low", 0.25}}}}}};
    const auto ours = planning::OwnErrorPriors::from_json(file, bench, "atria.json");
    EXPECT_EQ(*ours.largest_of("cssm", "low"), 0.5);
    EXPECT_EQ(*ours.typical_of("cssm", "low"), 0.25);
    EXPECT_EQ(*ours.largest_of("cssm", "draft"), *bench.largest_of("cssm", "draft"));
    EXPECT_EQ(ours.isr_occluded_largest, bench.isr_occluded_largest);
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
    EXPECT_EQ(refusal({{"largets", {}}}),
              "p.json: unknown field 'largets' (known: source, largest, typical, vct_second_largest, "
              "vct_second_typical, isr_occluded_largest)");
    EXPECT_EQ(refusal(nlohmann::json::array()), "p.json: expected an object, not array");

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

// What bench/quality writes of the corpus (corpus_priors, as --priors-out writes it) a daemon reads
// back: the committed tables.
TEST(PlannerPriors, TheBenchsFileOfTheCorpusReadsBackAsTheCommittedTables) {
    const planning::OwnErrorPriors corpus = bench::corpus_priors(kCorpus, walls());
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
