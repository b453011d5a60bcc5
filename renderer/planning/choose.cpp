#include "renderer/planning/plan_order.hpp"

#include "renderer/base/error.hpp"
#include "renderer/methods/knobs.hpp"

#include <algorithm>

#include <fmt/format.h>

namespace bounce::planning {

methods::KnobValues reference_knobs(int spp, int bounces) {
    return {{"spp", spp}, {"bounces", bounces}, {"pixel_jitter", 0}};
}

std::string describe(const Candidate& candidate) {
    std::string text = candidate.method == "reference" ? "reference" : candidate.method + " " + candidate.preset;
    for (const auto& [knob, value] : candidate.knobs) {
        if (knob == "pixel_jitter") continue;
        text += fmt::format(" {}={:g}", knob, value);
    }
    if (candidate.scale != 1.0) text += fmt::format(" at 1/{:g} size, upsampled", 1.0 / candidate.scale);
    return text;
}

bool faster(const Candidate& a, const Candidate& b) {
    return a.predicted_ms != b.predicted_ms ? a.predicted_ms < b.predicted_ms : a.predicted_error < b.predicted_error;
}
double expected_ms(const Candidate& candidate) { return candidate.expected_ms.value_or(candidate.predicted_ms); }
double promised_error(const Candidate& candidate) {
    return std::max(candidate.predicted_error, candidate.promised_error.value_or(candidate.predicted_error));
}
bool more_accurate(const Candidate& a, const Candidate& b) {
    return a.predicted_error != b.predicted_error ? a.predicted_error < b.predicted_error : a.predicted_ms < b.predicted_ms;
}

bool denoised(const Candidate& candidate) {
    return candidate.method == "reference" && methods::knob_or(candidate.knobs, "denoise", 0.0) != 0.0;
}

namespace {

// By expected price, then as faster(): the race of a target error alone.
bool faster_expected(const Candidate& a, const Candidate& b) {
    return expected_ms(a) != expected_ms(b) ? expected_ms(a) < expected_ms(b) : faster(a, b);
}

}  // namespace

Plan choose(const std::vector<Candidate>& candidates, const Budget& budget) {
    if (candidates.empty()) throw InputError("no plan to choose from");
    if (!budget.max_ms && !budget.max_error) throw InputError("a budget needs max_ms or max_error");
    const auto within_time = [&](const Candidate& c) { return !budget.max_ms || c.predicted_ms <= *budget.max_ms; };
    // A target is a promise: judged by what a plan is promised, which counts the noise its comparisons
    // took out (Candidate::promised_error); the time budget's ranking by the estimate.
    const auto within_error = [&](const Candidate& c) { return !budget.max_error || promised_error(c) <= *budget.max_error; };
    const Candidate* best = nullptr;
    for (const Candidate& c : candidates) {
        if (within_time(c) && within_error(c) && (!best || (budget.max_error ? faster(c, *best) : more_accurate(c, *best)))) best = &c;
    }
    // A target error alone races at expected prices, among plans whose bounds keep kTargetTimeSlack.
    const Candidate* fastest_bound = best;
    if (best && budget.max_error && !budget.max_ms) {
        for (const Candidate& c : candidates) {
            if (within_error(c) && c.predicted_ms <= kTargetTimeSlack * fastest_bound->predicted_ms &&
                faster_expected(c, *best)) {
                best = &c;
            }
        }
    }
    // Among plans priced alike (kPriceTie), the most accurate; a target alone keeps to the race's bound.
    const Candidate* cheapest = best;
    if (best && budget.max_error) {
        const auto price = [&](const Candidate& c) { return budget.max_ms ? c.predicted_ms : expected_ms(c); };
        for (const Candidate& c : candidates) {
            const bool raced = budget.max_ms || c.predicted_ms <= kTargetTimeSlack * fastest_bound->predicted_ms;
            if (within_time(c) && within_error(c) && raced && price(c) <= kPriceTie * price(*cheapest) &&
                more_accurate(c, *best)) {
                best = &c;
            }
        }
    }
    Plan plan;
    plan.considered = static_cast<int>(candidates.size());
    const std::string error_text = budget.max_error ? fmt::format("relMSE {:g}", *budget.max_error) : "";
    const std::string time_text = budget.max_ms ? fmt::format("{:g} ms", *budget.max_ms) : "";
    if (best) {
        plan.meets_budget = true;
        plan.chosen = *best;
        plan.why = budget.max_error
                       ? fmt::format("the fastest of {} plans promised within {}{}", plan.considered, error_text,
                                     budget.max_ms ? " and " + time_text : "")
                       : fmt::format("the most accurate of {} plans predicted within {}", plan.considered, time_text);
        if (cheapest != fastest_bound) {
            plan.why = fmt::format("of {} plans, the fastest at its expected price ({:.1f} ms) of those promised within {} "
                                   "whose bound on time is at most {:g}x the least ({} at {:.1f} ms)",
                                   plan.considered, expected_ms(*cheapest), error_text, kTargetTimeSlack,
                                   describe(*fastest_bound), fastest_bound->predicted_ms);
        }
        if (best != cheapest) {
            plan.why += fmt::format("; the most accurate of those priced within {:g}x of it ({}: {:.1f} ms, relMSE {:.3f})",
                                    kPriceTie, describe(*cheapest), budget.max_ms ? cheapest->predicted_ms
                                                                                  : expected_ms(*cheapest),
                                    cheapest->predicted_error);
        }
    } else if (budget.max_ms && std::any_of(candidates.begin(), candidates.end(), within_time)) {
        for (const Candidate& c : candidates) {
            if (within_time(c) && (!best || more_accurate(c, *best))) best = &c;
        }
        plan.chosen = *best;
        plan.why = fmt::format("no plan is promised within {} and predicted within {}: the most accurate within {}", error_text,
                               time_text, time_text);
    } else if (budget.max_ms) {
        plan.chosen = *std::min_element(candidates.begin(), candidates.end(), faster);
        plan.why = fmt::format("no plan is predicted within {}: the fastest", time_text);
    } else {
        // The nearest to the target: the least promise, then the least estimate.
        plan.chosen = *std::min_element(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
            return promised_error(a) != promised_error(b) ? promised_error(a) < promised_error(b) : more_accurate(a, b);
        });
        plan.why = fmt::format("no plan is promised within {}: the least promised", error_text);
    }
    plan.why += fmt::format(", {}: {:.1f} ms ({}), relMSE {:.3f} ({})", describe(plan.chosen), plan.chosen.predicted_ms,
                            plan.chosen.cost_basis, plan.chosen.predicted_error, plan.chosen.error_basis);
    return plan;
}

}  // namespace bounce::planning
