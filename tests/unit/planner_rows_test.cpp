// How bench/planner judges a time budget (bench/planner_rows.hpp): within 1.2 T, with error no worse
// than the most accurate fixed plan within T, by more than the noise floor; a planned frame of the
// comparator's own plan holds whatever it read, its knobs compared once the preset fills them in.
#include "bench/planner_rows.hpp"

#include <gtest/gtest.h>

namespace bounce::bench {
namespace {

Measured frame(const std::string& label, double ms, double rel_mse, const std::string& method,
               const std::string& preset, methods::KnobValues knobs = {}, double scale = 1.0) {
    Measured m{label, ms, rel_mse, 0.0, method, preset, std::move(knobs)};
    m.scale = scale;
    return m;
}

TEST(PlannerRows, AFrameOfTheComparatorsOwnPlanHoldsWhateverItRead) {
    const std::vector<Measured> fixed = {frame("direct ultra", 5.0, 0.319, "direct", "ultra"),
                                         frame("vct draft", 48.0, 0.184500, "vct", "draft"),
                                         frame("isr draft", 60.0, 0.10, "isr", "draft")};  // past T
    // The planner names vct draft's own bounce count; its frame reads a hair over the fixed one's.
    BudgetRow same;
    same.planned = frame("vct draft bounces=1", 58.7, 0.184501, "vct", "draft", {{"bounces", 1}});
    judge_time_budget(same, 50.0, fixed);
    ASSERT_TRUE(same.fixed.has_value());
    EXPECT_EQ(same.fixed->label, "vct draft");  // isr draft is past 50 ms
    EXPECT_TRUE(same.met);                      // 58.7 <= 1.2 x 50
    EXPECT_TRUE(same.holds);
    EXPECT_FALSE(same.holds_strictly);

    // Other knobs, another size, or too slow: not the comparator's plan.
    BudgetRow second_bounce = same;
    second_bounce.planned = frame("vct draft bounces=2", 50.0, 0.184501, "vct", "draft", {{"bounces", 2}});
    judge_time_budget(second_bounce, 50.0, fixed);
    EXPECT_FALSE(second_bounce.holds);
    BudgetRow upsampled = same;
    upsampled.planned = frame("vct draft bounces=1 at 1/2 size", 20.0, 0.184501, "vct", "draft", {{"bounces", 1}}, 0.5);
    judge_time_budget(upsampled, 50.0, fixed);
    EXPECT_FALSE(upsampled.holds);
    BudgetRow slow = same;
    slow.planned.ms = 60.5;
    judge_time_budget(slow, 50.0, fixed);
    EXPECT_FALSE(slow.met);
    EXPECT_FALSE(slow.holds);

    // Another plan holds by its error: no worse than the comparator's, or within the noise floor.
    BudgetRow better;
    better.planned = frame("reference bounces=1 spp=5", 46.0, 0.18, "reference", "medium", {{"spp", 5}, {"bounces", 1}});
    judge_time_budget(better, 50.0, fixed);
    EXPECT_TRUE(better.holds_strictly);
    BudgetRow noisy = better;
    noisy.planned.rel_mse = 0.19;
    noisy.planned.rel_mse_spread = 0.01;
    judge_time_budget(noisy, 50.0, fixed);
    EXPECT_TRUE(noisy.holds);
    EXPECT_FALSE(noisy.holds_strictly);
    noisy.planned.rel_mse_spread = 0.001;
    judge_time_budget(noisy, 50.0, fixed);
    EXPECT_FALSE(noisy.holds);
}

}  // namespace
}  // namespace bounce::bench
