// The planner's priors (renderer/planning/priors.cpp) are the bench's figures: the largest and the
// median, over the corpus scenes, of each GPU preset's relMSE against the reference with as many
// bounces. A prior left behind when a method changes is no longer a promise (in one change cssm at
// low came to err 0.0738 on the open street where its prior said 0.0628), so this reads the
// committed corpus tables and checks the priors against them; and that the priors of a scene held
// out (bench/planner --held-out) are the other scenes'.
#include "bench/corpus_priors.hpp"
#include "renderer/planning/error_model.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
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

}  // namespace
}  // namespace bounce
