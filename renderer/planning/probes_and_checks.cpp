// The GPU plans a reference plan is rendered with (planner.hpp): probes beside it, which measure
// their own error on the scene, and spot-checked plans before it, one of which may be sent in its
// place.
#include "renderer/planning/planner.hpp"

#include "renderer/planning/comparisons.hpp"
#include "renderer/planning/error_model.hpp"
#include "renderer/planning/plan_order.hpp"
#include "renderer/planning/spot_check.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
#include <vector>

namespace bounce::planning {

std::optional<Checks> spot_checks(const std::vector<Candidate>& all, const Candidate& chosen, const Budget& budget,
                                  const PlanningInputs& inputs) {
    // Beside a denoised reference too: the check traces its own reference, and a plan it passes
    // records its own error (record_spot_check), which the frame it stood in for could not measure.
    if (!budget.max_error || budget.max_ms || chosen.method != "reference" || chosen.scale != 1.0) return std::nullopt;
    const double target = *budget.max_error;
    const SceneAnalysis& analysis = inputs.analysis;
    Checks checks;
    SpotCheck& check = checks.check;
    // Against a reference that lacks little light: what it lacks is added to the frame's bound by the
    // triangle inequality, (sqrt(a) + sqrt(b))^2, and at E/1000 that costs at most 0.07 E.
    const int* enough = std::find_if(std::begin(kReferenceBounces), std::end(kReferenceBounces), [&](int bounces) {
        return BounceEnergy::at(analysis.bounces.stopped_error, bounces) <= 0.001 * target;
    });
    check.bounces = std::max(enough != std::end(kReferenceBounces) ? *enough : kReferenceBounces[std::size(kReferenceBounces) - 1],
                             modelled_bounces(chosen.method, chosen.knobs));
    check.pixels = static_cast<int>(std::min<long long>(kSpotPixels, static_cast<long long>(inputs.width) * inputs.height));
    const double noise_per_sample =
        reference_noise(analysis, check.bounces, 1.0, inputs.scene, NoiseAgainst::every_bounce).rel_mse;
    check.spp = static_cast<int>(
        std::clamp(std::ceil(noise_per_sample * std::max(kSpotSamplesPerNoise / target, 1.0 / kSpotMaxNoise)),
                   static_cast<double>(kSpotMinSamples), 4096.0));
    check.stopped_error = BounceEnergy::at(analysis.bounces.stopped_error, check.bounces);
    check.max_noise = 2.0 * std::min(kSpotMaxNoise, target / kSpotSamplesPerNoise);  // a half's
    PlanningInputs spot = inputs;
    spot.width = check.pixels;
    spot.height = 1;
    check.predicted_ms = predicted_ms(spot, "reference", chosen.preset,
                                      reference_knobs(kSpotPricedSamples * check.spp, check.bounces));
    const double share_ms = kCheckShare * chosen.predicted_ms;
    if (!std::isfinite(check.predicted_ms) || check.predicted_ms >= share_ms) return std::nullopt;
    std::vector<const Candidate*> plausible;
    for (const Candidate& c : all) {
        if (c.method == "reference" || c.scale != 1.0) continue;
        const int bounces = modelled_bounces(c.method, c.knobs);
        // Measured on the scene (at its count, or at more bounces of its preset): the prediction from
        // that stands, and where it is over E the frames tried before have ruled it out
        // (ruled_out_by_measurements); a check would be traced for nothing.
        if (inputs.scene && inputs.scene->own_error(c.method, c.preset, bounces)) continue;
        const auto typical = inputs.own_error_priors().typical_of(
            c.method, c.preset, bounces, leaks_through_thin_walls(analysis, c.method, c.preset));
        if (!typical) continue;
        if (*typical + BounceEnergy::at(analysis.bounces.stopped_error, bounces) > target) continue;
        plausible.push_back(&c);
    }
    std::sort(plausible.begin(), plausible.end(), [](const Candidate* a, const Candidate* b) { return faster(*a, *b); });
    double total_ms = check.predicted_ms;
    for (const Candidate* c : plausible) {
        if (total_ms + c->predicted_ms > share_ms) break;
        total_ms += c->predicted_ms;
        checks.plans.push_back(*c);
    }
    if (checks.plans.empty()) return std::nullopt;
    return checks;
}

namespace {

// Of the full-size GPU plans within `share_ms` that `skip` does not leave out, one per method and
// preset, the one `better` puts first; fastest first. The probes' two rounds differ in what they skip
// and prefer.
template <typename Skip, typename Better>
std::vector<const Candidate*> one_plan_per_preset(const std::vector<Candidate>& all, double share_ms, Skip skip,
                                                  Better better) {
    std::vector<const Candidate*> plans;
    for (const Candidate& c : all) {
        if (c.method == "reference" || c.scale != 1.0 || c.predicted_ms > share_ms || skip(c)) continue;
        const auto same = std::find_if(plans.begin(), plans.end(), [&](const Candidate* other) {
            return other->method == c.method && other->preset == c.preset;
        });
        if (same == plans.end()) plans.push_back(&c);
        else if (better(c, **same)) *same = &c;
    }
    // Stable: plans of one price and error keep the candidates' order, whatever the list's length.
    std::stable_sort(plans.begin(), plans.end(), [](const Candidate* a, const Candidate* b) { return faster(*a, *b); });
    return plans;
}

}  // namespace

std::vector<Candidate> probes(const std::vector<Candidate>& all, const Candidate& chosen, const SceneMeasurements* scene,
                              const SceneAnalysis* analysis, int prefix_bounces) {
    // Only full-size frames are compared: an upsampled one's error is not its method's; nor with a
    // denoised reference, whose error is the filter's too (FrameComparisons leaves such frames out).
    if (chosen.method != "reference" || chosen.scale != 1.0 || denoised(chosen)) return {};
    const double share_ms = kProbeShare * chosen.predicted_ms;
    // Companions. A probe is compared only where the reference's noise and the light of the bounces
    // the probe lacks (both predicted) come to less than its own error (FrameComparisons::compare);
    // where they would not, a reference of the probe's own bounce count has no such light, and the
    // cheapest one whose noise is at most a third of that own error (a quarter of the relMSE,
    // FrameComparisons::kMaxNoiseShare) measures it. A probe that needs one goes
    // with it or not at all: alone, its comparison would be dropped.
    const auto stopped = [&](int bounces) {
        return analysis ? BounceEnergy::at(analysis->bounces.stopped_error, bounces) : 0.0;
    };
    const int chosen_bounces = modelled_bounces(chosen.method, chosen.knobs);
    const double chosen_noise = chosen.predicted_error - stopped(chosen_bounces);
    const auto max_noise = [](double own) {
        return own * FrameComparisons::kMaxNoiseShare / (1.0 - FrameComparisons::kMaxNoiseShare);
    };
    const auto companion_for = [&](int bounces, double own) -> const Candidate* {
        const Candidate* companion = nullptr;
        for (const Candidate& c : all) {
            if (c.method != "reference" || c.scale != 1.0 || modelled_bounces(c.method, c.knobs) != bounces) continue;
            // A denoised frame is compared with nothing: a companion measures by its noise alone.
            if (denoised(c) || methods::knob_or(c.knobs, "spp", 0.0) < FrameComparisons::kMinReferenceSpp) continue;
            if (c.predicted_error - stopped(bounces) > max_noise(own)) continue;
            if (!companion || c.predicted_ms < companion->predicted_ms) companion = &c;
        }
        return companion;
    };
    // The chosen reference's own frame of fewer bounces: as noisy per sample as a reference of
    // that bounce count, at the chosen one's samples, with no bounce gap.
    const auto prefix_noise = [&](int bounces) -> std::optional<double> {
        if (!analysis || bounces >= std::min(chosen_bounces, prefix_bounces)) return std::nullopt;
        if (methods::knob_or(chosen.knobs, "spp", 0.0) < FrameComparisons::kMinReferenceSpp) return std::nullopt;
        // A comparison with the prefix weighs its noise by the prefix's own, darker pixels.
        return reference_noise(*analysis, bounces, methods::knob_or(chosen.knobs, "spp", 1.0), scene, NoiseAgainst::own_frame)
            .rel_mse;
    };
    const auto prefix_measures = [&](const Candidate& c) {
        const int bounces = modelled_bounces(c.method, c.knobs);
        const auto noise = prefix_noise(bounces);
        return noise && *noise <= max_noise(c.predicted_error - stopped(bounces));
    };
    // Per preset, the most accurate plan that fits the share alone (for cssm and vct, the most bounces): a
    // comparison tells a frame's own error only where the bounces it lacks do not drown it.
    // Probed, or compared otherwise, it is left out; unless nothing was learned (the reference's noise
    // drowned it) and this reference's own frame of its bounce count is quiet enough to measure it.
    std::vector<const Candidate*> cheapest = one_plan_per_preset(
        all, share_ms,
        [&](const Candidate& c) {
            return scene && scene->compared(c.method, c.preset) &&
                   (scene->own_errors(c.method).count(c.preset) > 0 || !prefix_measures(c));
        },
        more_accurate);
    // Then, per preset, its plan of fewest bounces where that is not a first-round probe's: the own
    // error measured at one bounce count is carried to fewer (SceneMeasurements::own_error) as if the
    // frame's error and the light it lacks added apart, and they do not (the held-out atrium's vct
    // draft measured own 0.167 at 2 bounces, was promised 0.289 at 1 and measures 0.185 there: its
    // leaked light fills in what the bounce would bring). A time budget takes the fewer bounces.
    // Second, after every preset's first probe, in what is left of the share.
    std::vector<const Candidate*> fewest = one_plan_per_preset(
        all, share_ms,
        [&](const Candidate& c) {
            const int bounces = modelled_bounces(c.method, c.knobs);
            if (!scene || !scene->compared(c.method, c.preset, bounces)) return false;
            const auto own = scene->own_error(c.method, c.preset, bounces);
            return (own && own->exact) || !prefix_measures(c);
        },
        [](const Candidate& a, const Candidate& b) {
            const int a_bounces = modelled_bounces(a.method, a.knobs), b_bounces = modelled_bounces(b.method, b.knobs);
            return a_bounces != b_bounces ? a_bounces < b_bounces : more_accurate(a, b);
        });
    std::erase_if(fewest, [&](const Candidate* c) {
        return std::any_of(cheapest.begin(), cheapest.end(), [&](const Candidate* first) {
            return first->method == c->method && first->preset == c->preset &&
                   modelled_bounces(first->method, first->knobs) <= modelled_bounces(c->method, c->knobs);
        });
    });
    cheapest.insert(cheapest.end(), fewest.begin(), fewest.end());
    std::vector<Candidate> chosen_probes, companions;
    std::set<int> accompanied;  // bounce counts with a companion
    double total_ms = 0.0;
    for (const Candidate* c : cheapest) {
        const int bounces = modelled_bounces(c->method, c->knobs);
        const double own = c->predicted_error - stopped(bounces);
        const auto own_prefix = prefix_noise(bounces);
        const bool whole_measures = chosen_noise <= max_noise(own) &&
                                    chosen_noise + stopped(bounces) - stopped(chosen_bounces) < own;
        const bool needs_companion = analysis && bounces < chosen_bounces && !accompanied.contains(bounces) &&
                                     !(own_prefix && *own_prefix <= max_noise(own)) && !whole_measures;
        const Candidate* companion = needs_companion ? companion_for(bounces, own) : nullptr;
        // Where no companion comes or fits, the reference's own prefix at the probe's bounce count
        // still bounds its own error, noise and all (FrameComparisons::compare): a bound that can
        // come in under the prediction where that noise is less than it.
        const bool bound_tells = own_prefix && *own_prefix < own;
        if (companion && total_ms + c->predicted_ms + companion->predicted_ms > share_ms && bound_tells) companion = nullptr;
        if (needs_companion && !companion && !bound_tells) continue;
        const double ms = c->predicted_ms + (companion ? companion->predicted_ms : 0.0);
        if (total_ms + ms > share_ms) continue;
        total_ms += ms;
        chosen_probes.push_back(*c);
        if (companion) {
            companions.push_back(*companion);
            accompanied.insert(bounces);
        }
    }
    chosen_probes.insert(chosen_probes.end(), companions.begin(), companions.end());
    return chosen_probes;
}

}  // namespace bounce::planning
