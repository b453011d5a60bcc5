#include "renderer/memory_admission.hpp"

#include "renderer/base/bytes.hpp"
#include "renderer/base/error.hpp"
#include "renderer/gpu/memory_budget.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace bounce {
namespace {

std::uint64_t total(const methods::MemoryEstimate& estimate) {
    std::uint64_t bytes = 0;
    for (const auto& structure : estimate) bytes += structure.bytes;
    return bytes;
}

const methods::KnobSpec* find_knob(const methods::MethodInfo& method, const std::string& name) {
    const auto it = std::find_if(method.knobs.begin(), method.knobs.end(), [&](const auto& knob) { return knob.name == name; });
    return it == method.knobs.end() ? nullptr : &*it;
}

// The largest value of `knob` in [its minimum, the requested value] with which the frame fits, by
// bisection (estimates grow with the knobs that size them); nullopt when not even the minimum fits.
std::optional<double> knob_that_fits(const MemoryCheck& check, const methods::KnobSpec& knob) {
    methods::KnobValues knobs = check.knobs;
    auto fits = [&](double value) {
        knobs[knob.name] = value;
        const methods::EstimateInput input{check.scene, knobs, check.width, check.height};
        return check.held_elsewhere + total(frame_estimate(check.method, input)) <= check.budget;
    };
    double low = knob.min, high = check.knobs.at(knob.name);
    if (!fits(low)) return std::nullopt;
    for (int step = 0; step < 64 && high - low > (knob.integer ? 1.0 : 1e-3 * std::max(1.0, std::abs(high))); ++step) {
        const double middle = knob.integer ? std::floor(0.5 * (low + high)) : 0.5 * (low + high);
        (fits(middle) ? low : high) = middle;
    }
    return low;
}

// The largest frame of the request's aspect ratio that fits; nullopt when not even 1x1 does.
std::optional<std::pair<int, int>> frame_that_fits(const MemoryCheck& check) {
    auto fits = [&](double scale) {
        const int width = std::max(1, static_cast<int>(check.width * scale));
        const int height = std::max(1, static_cast<int>(check.height * scale));
        const methods::EstimateInput input{check.scene, check.knobs, width, height};
        return check.held_elsewhere + total(frame_estimate(check.method, input)) <= check.budget;
    };
    if (!fits(0.0)) return std::nullopt;
    double low = 0.0, high = 1.0;
    for (int step = 0; step < 30; ++step) {
        const double middle = 0.5 * (low + high);
        (fits(middle) ? low : high) = middle;
    }
    return std::pair{std::max(1, static_cast<int>(check.width * low)), std::max(1, static_cast<int>(check.height * low))};
}

}  // namespace

methods::MemoryEstimate frame_estimate(const methods::MethodInfo& method, const methods::EstimateInput& input) {
    methods::MemoryEstimate estimate = method.estimate(input);
    estimate.push_back({"output", static_cast<std::uint64_t>(input.width) * static_cast<std::uint64_t>(input.height) * (16 + 4),
                        "frame size"});
    return estimate;
}

void check_memory_budget(const MemoryCheck& check) {
    if (check.budget == 0) return;
    const methods::EstimateInput input{check.scene, check.knobs, check.width, check.height};
    const methods::MemoryEstimate estimate = frame_estimate(check.method, input);
    const std::uint64_t needed = total(estimate);
    if (check.held_elsewhere + needed <= check.budget) return;

    const auto& largest = *std::max_element(estimate.begin(), estimate.end(),
                                            [](const auto& a, const auto& b) { return a.bytes < b.bytes; });
    std::string advice;
    if (const methods::KnobSpec* knob = find_knob(check.method, largest.scaled_by)) {
        if (const auto value = knob_that_fits(check, *knob)) {
            advice = fmt::format("{}={} would fit", knob->name, *value);
        } else {
            advice = fmt::format("not even {}={} fits", knob->name, knob->min);
        }
    } else if (largest.scaled_by == "frame size") {
        if (const auto size = frame_that_fits(check)) {
            advice = fmt::format("a frame of {}x{} would fit", size->first, size->second);
        } else {
            advice = "no frame size fits";
        }
    } else {
        advice = "the scene itself is too large for it";
    }
    // Named when it matters: more than a hundredth of the budget.
    const std::string elsewhere =
        check.held_elsewhere > check.budget / 100 ? fmt::format(", with {} held by resident scenes and methods (unloading scenes frees it)",
                                               bytes_text(check.held_elsewhere))
                                 : "";
    throw ResourceExhausted(fmt::format(
        "method '{}' would hold about {} for this frame, past the memory budget of {} ({}){}; the largest structure is "
        "'{}' ({}, sized by {}): {}",
        check.method.name, bytes_text(needed), bytes_text(check.budget), check.budget_source, elsewhere,
        largest.name, bytes_text(largest.bytes), largest.scaled_by.empty() ? "the scene" : largest.scaled_by, advice));
}

}  // namespace bounce
