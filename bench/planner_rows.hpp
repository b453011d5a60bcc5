// bench/planner's rows: a plan's measured frame, and a budget's verdict against the fixed plans.
#pragma once

#include "renderer/methods/knobs.hpp"
#include "renderer/planning/planner.hpp"

#include <optional>
#include <string>
#include <vector>

namespace bounce::bench {

struct Measured {
    std::string label;
    double ms = 0.0, rel_mse = 0.0;
    // Over the frames rendered of the plan: the largest relMSE less the smallest. A reference's
    // frames are traced with other seeds, so this is how much two frames of one plan differ by
    // chance (the floor under which one plan is not worse than another); GPU frames differ only where
    // float atomics add in another order (vct). A relit comparator's three frames each follow another
    // change of the lights (relit_fixed_plan), as the planned frame follows its own.
    double rel_mse_spread = 0.0;
    std::string method, preset;  // what to render it again with
    methods::KnobValues knobs;
    // A target error's comparator, timed again right after the planned frame (fixed plans are timed
    // first, minutes earlier, and a frame of a few milliseconds on two loaded cores varies between
    // such moments by more than the 1.5x it is judged by: the foliage's `direct high` took 2.2 ms as
    // a fixed plan and 4.0 ms as the planned frame, the same plan). 0 where not timed again.
    double ms_again = 0.0;
    double comparator_ms() const { return ms_again > 0.0 ? ms_again : ms; }
    double scale = 1.0;  // the frame rendered at this fraction of the size and upsampled
};

struct BudgetRow {
    int pass = 1;
    std::string scene, budget, plan;
    double predicted_ms = 0, predicted_error = 0;
    Measured planned;
    std::optional<Measured> fixed;  // the comparator
    bool met = false, holds = false;
    bool holds_strictly = false;  // a time budget's error compared with no noise floor
    std::string why;
    // Spot-checked plans tried before the reference plan (planning::spot_checks), each with the bound
    // its check read, and the check's reference time (included in planned.ms).
    std::string checks;
    double check_ms = 0.0;
};

// How much two frames of the same plan differ by chance, for the planned plan or the comparator.
double noise_floor(const BudgetRow& row);

// Whether two frames are of one plan: the same label, or the same method and preset with the same
// knobs once the preset's own fill them in (the planner names `bounces` 1 where a fixed plan leaves
// it to vct draft).
bool same_plan(const Measured& a, const Measured& b);

// A time budget T holds when the planned frame took at most 1.2 T, with error no worse than the most
// accurate of `comparators` within T: by no more than two frames of one of the two plans differ by
// chance (holds_strictly: by nothing). A planned frame of the comparator's own plan is no worse than
// it whatever it read.
void judge_time_budget(BudgetRow& row, double budget, const std::vector<Measured>& comparators);

// What a run's markdown says of how its budgets are judged (above), how its frames are timed, and
// what each pass asks: the bullets after the machine and the frames' size, each ending in a newline.
std::string how_budgets_are_judged();

// A relMSE, with half its spread where that is 0.001 or more.
std::string error_text(const Measured& m);

// A plan as the tables name it: method and preset (the reference alone), and its knobs.
std::string label(const std::string& method, const std::string& preset, const methods::KnobValues& knobs);

// The row of a time budget asked after a change (the relit and moved-camera passes): its frame
// rendered as it came, judged against `comparators` measured after the same change.
BudgetRow changed_budget_row(int pass, const std::string& scene, std::string budget_text, const planning::Plan& plan,
                             const Measured& planned, double budget, const std::vector<Measured>& comparators);

}  // namespace bounce::bench
