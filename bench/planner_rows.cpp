#include "bench/planner_rows.hpp"

#include "renderer/base/log.hpp"
#include "renderer/methods/registry.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace bounce::bench {

double noise_floor(const BudgetRow& row) {
    return std::max(row.planned.rel_mse_spread, row.fixed ? row.fixed->rel_mse_spread : 0.0);
}

bool same_plan(const Measured& a, const Measured& b) {
    if (a.label == b.label) return true;
    if (a.method.empty() || a.method != b.method || a.preset != b.preset || a.scale != b.scale) return false;
    const auto& registry = methods::MethodRegistry::builtin();
    return registry.resolve(a.method, a.preset, a.knobs) == registry.resolve(b.method, b.preset, b.knobs);
}

// The comparator's own plan holds whatever it read: after a change of the lights, direct medium in the
// furnished room read 0.19384 as planned and as its comparator, apart by less than 5e-6, where the
// comparator's three frames happened to lie closer still; in the atrium vct draft within 50 ms,
// planned with `bounces` 1, read 0.18450 as its comparator did.
void judge_time_budget(BudgetRow& row, double budget, const std::vector<Measured>& comparators) {
    row.met = row.planned.ms <= 1.2 * budget;
    for (const Measured& m : comparators) {
        if (m.ms <= budget && (!row.fixed || m.rel_mse < row.fixed->rel_mse)) row.fixed = m;
    }
    row.holds_strictly = row.met && (!row.fixed || row.planned.rel_mse <= row.fixed->rel_mse);
    row.holds = row.met && (!row.fixed || same_plan(row.planned, *row.fixed) ||
                            row.planned.rel_mse <= row.fixed->rel_mse + noise_floor(row));
}

std::string error_text(const Measured& m) {
    return m.rel_mse_spread >= 0.001 ? fmt::format("{:.3f} ± {:.3f}", m.rel_mse, m.rel_mse_spread / 2.0)
                                  : fmt::format("{:.3f}", m.rel_mse);
}

std::string label(const std::string& method, const std::string& preset, const methods::KnobValues& knobs) {
    std::string text = method == "reference" ? "reference" : method + " " + preset;
    for (const auto& [knob, value] : knobs) {
        if (knob != "pixel_jitter") text += fmt::format(" {}={:g}", knob, value);
    }
    return text;
}

BudgetRow changed_budget_row(int pass, const std::string& scene, std::string budget_text, const planning::Plan& plan,
                             const Measured& planned, double budget, const std::vector<Measured>& comparators) {
    BudgetRow row;
    row.pass = pass;
    row.scene = scene;
    row.budget = std::move(budget_text);
    row.plan = label(plan.chosen.method, plan.chosen.preset, plan.chosen.knobs) +
               (plan.chosen.scale != 1.0 ? fmt::format(" at 1/{:g} size", 1.0 / plan.chosen.scale) : "") +
               fmt::format(" (redoes {})", to_string(plan.chosen.redoes));
    row.predicted_ms = plan.chosen.predicted_ms;
    row.predicted_error = plan.chosen.predicted_error;
    row.why = plan.why;
    log::info("bench", "{} {}: {}", scene, row.budget, plan.why);
    row.planned = planned;
    judge_time_budget(row, budget, comparators);
    return row;
}

std::string how_budgets_are_judged() {
    return "- A target error holds when it is met at no more than 1.5x the time of the cheapest fixed plan "
           "(a method at a preset, or the reference at 4 to 256 spp) that meets it, that plan timed again right "
           "after the planned frame (the time shown; `fixed_ms` in planner.csv is its first); a time budget T holds when "
           "the frame takes at most 1.2 T with error no worse than the best fixed plan within T, by more than the "
           "noise floor: the spread of the relMSEs of one plan's frames (the reference's traced with other seeds, "
           "twice or more under 5 s, its relMSE the mean; a relit comparator's three frames, each after its own change of the "
           "lights, its relMSE that of the frame of median time; `a ± b` is the mean and half the spread, shown from a spread of 0.001); "
           "a frame of the comparator's own plan holds whatever it read.\n"
           "- Frames under 0.5 s, fixed and planned, are rendered three times (under 20 ms, nine; references under 5 s, twice) "
           "and the median time kept (one frame of a "
           "few milliseconds on two loaded cores varies by more than the 1.2x the budgets are judged by); the "
           "reference's own noise, about noise per sample / spp, is in every relMSE measured (under 0.0018 at 4096 "
           "spp on these scenes).\n"
           "- The planner plans after the fixed plans' frame times were recorded, as a daemon records its frames; "
           "their errors are not given to it. It learns a GPU method's error on the scene by comparing its own "
           "frames with its reference frames of the view: the planned frames, and the GPU probes it renders beside "
           "a reference plan (planning::probes), and reads what its spot checks measured: where the plan for a target error is the "
           "reference, the GPU plans it may replace are rendered first and compared with a reference traced at 1024 of the "
           "frame's pixel centres, and the first whose bound is within the target is sent (marked `spot-checked`; its time "
           "includes the check's trace and every frame tried). Pass 2 asks for the same budgets again. The two last passes "
           "(`relit`) ask each time budget right after every light moved by about 1e-5 of the scene's extent, turned "
           "by as many radians and brightened by 0.01% or more (bench::change_every_light: a change no comparison "
           "sees, each frame scaled back by the brightening before it is measured, and no two alike): first as a "
           "client that keeps its budget meets the change, its previous frames the same budget's (rendered as "
           "they come, with the lights before the change, until one redoes nothing, three at most); then right after another budget's frame (`relit after another "
           "budget`), where a plan that differs from the last one switches. The planner "
           "prices what each plan's frame would redo (frame_change.hpp: the light's work, and every structure where "
           "it switches method or preset), and "
           "the frame is rendered as it comes, once, not warmed first; its comparator is the most accurate fixed "
           "plan whose frame right after such a change (built; of three, the one of the median time, with its own "
           "error) fits. The last pass (`camera moved`) asks each time budget of the scene's view right after a "
           "frame of the same budget from a camera moved aside by 2% of the scene's diagonal (before it, the "
           "plan a warm frame would have, then frames of the view as they come until one redoes nothing, "
           "three at most): the frame back draws "
           "each sun's view cascades again; its comparator is the most accurate fixed plan whose frame back so "
           "(of three, the one of the median time) fits. Before any GPU frame "
           "is timed, a small frame of another scene is rendered until the GPU is at the clock it runs the others "
           "at (warm_gpu_clock: an idle GPU clocks down, and right after the reference's CPU-only frames an H200 "
           "took five times as long).\n";
}

}  // namespace bounce::bench
