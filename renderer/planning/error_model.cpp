#include "renderer/planning/error_model.hpp"

#include "renderer/methods/registry.hpp"
#include "renderer/scene_knobs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace bounce::planning {
namespace {

// A GPU method's own error at a preset on this scene, and where it comes from:
//   - measured here against the scene's reference frames;
//   - else that of the nearest cheaper preset measured here: a costlier preset is not assumed to do
//     better on this scene. Its presets share the method's approximations, and the bench's ratios
//     between presets do not carry over: in the glossy gallery, cssm medium erred as much as draft
//     where the priors' ratio promised 0.41 of it;
//   - else the bench's prior, scaled up where the method's measured (costlier) presets err more
//     than theirs: a cheaper preset errs at least as much, in the priors' proportion. Never scaled
//     down: a costlier preset that does well says little of a cheaper one (in the atrium cssm
//     medium measured 0.18 of its prior, and low, promised as much, measures 0.062 where 0.011 was
//     predicted: its coarser atlas misses the sun's patches);
//   - else the prior.
// Where the analysis finds most of the scene's indirect light occluded, isr's and cssm's priors are
// those of the Cornell variants (OwnErrorPriors::occluded_largest); where vct's preset leaks
// (leaks_through_thin_walls), its priors are those of the bench's scenes where it leaks.
// The estimate, what a target is promised (SceneMeasurements::OwnError::promised: the same where it
// is a prior), and where they come from.
struct OwnErrorOf {
    double estimate = 0.0, promised = 0.0;
    std::string basis;
};
OwnErrorOf own_error(const SceneAnalysis& analysis, const std::string& method, const std::string& preset, int bounces,
                     const SceneMeasurements* measured, const OwnErrorPriors& priors) {
    const std::map<std::string, double>* occluded_table =
        analysis.visibility.mostly_occluded() ? priors.occluded_largest(method) : nullptr;
    const bool occluded = occluded_table && occluded_table->count(preset);
    const auto prior_of = [&](const std::string& name) {
        if (occluded_table) {
            if (const auto it = occluded_table->find(name); it != occluded_table->end()) return it->second;
        }
        return priors.largest_of(method, name, bounces, leaks_through_thin_walls(analysis, method, name)).value_or(0.0);
    };
    const std::string bench =
        "on " + (occluded ? priors.occluded_source
                 : leaks_through_thin_walls(analysis, method, preset) ? priors.leaking_source
                                                                      : priors.source_of(method, preset, bounces));
    const double prior = prior_of(preset);
    if (!measured) return {prior, prior, bench};
    if (const auto own = measured->own_error(method, preset, bounces)) {
        return {own->rel_mse, own->promised,
                fmt::format("as {} comparison{} with this scene's reference frames measured{}", own->frames,
                            own->frames == 1 ? "" : "s", own->exact ? "" : " at other bounce counts")};
    }
    const auto& order = methods::preset_names();
    const auto rank = [&](const std::string& name) { return std::find(order.begin(), order.end(), name) - order.begin(); };
    const std::map<std::string, double> measured_presets = measured->own_errors(method, bounces);
    const std::map<std::string, double> promised_presets = measured->own_errors(method, bounces, /*promised=*/true);
    const std::pair<const std::string, double>* cheaper = nullptr;
    std::vector<double> ratios, promised_ratios;
    for (const auto& entry : measured_presets) {
        if (rank(entry.first) < rank(preset) && (!cheaper || rank(entry.first) > rank(cheaper->first))) cheaper = &entry;
        const double other_prior = prior_of(entry.first);
        if (rank(entry.first) > rank(preset) && other_prior > 0.0) {
            ratios.push_back(entry.second / other_prior);
            promised_ratios.push_back(promised_presets.at(entry.first) / other_prior);
        }
    }
    if (cheaper) {
        return {cheaper->second, promised_presets.at(cheaper->first),
                fmt::format("as this scene's {} {} measured (a costlier preset is not assumed better)", method,
                            cheaper->first)};
    }
    if (ratios.empty() || prior <= 0.0) return {prior, prior, bench};
    const double ratio = median(std::move(ratios));
    // Promised as their promises measured, in the same proportion, never under the estimate.
    const double promised = prior * std::max({1.0, ratio, median(std::move(promised_ratios))});
    if (ratio <= 1.0) return {prior, promised, bench};
    return {prior * ratio, promised,
            fmt::format("({:.3f} {} x {:.2f}, as this scene's costlier {} presets measured)", prior, bench, ratio, method)};
}

}  // namespace

bool leaks_through_thin_walls(const SceneAnalysis& analysis, const std::string& method, const std::string& preset) {
    return method == "vct" && analysis.thin_walls.leaks(preset);
}

std::optional<double> typical_own_error(const std::string& method, const std::string& preset, int bounces) {
    return OwnErrorPriors::bench().typical_of(method, preset, bounces);
}

std::optional<double> own_error_prior(const std::string& method, const std::string& preset, int bounces) {
    return OwnErrorPriors::bench().largest_of(method, preset, bounces);
}

int modelled_bounces(const std::string& method, const methods::KnobValues& knobs) {
    if (method == "direct") return 0;
    return static_cast<int>(methods::knob_or(knobs, "bounces", 1.0));
}

ReferenceNoise reference_noise(const SceneAnalysis& analysis, int bounces, double spp, const SceneMeasurements* measured,
                               NoiseAgainst against) {
    const BounceEnergy& energy = analysis.bounces;
    // Against every bounce: the analysis' statistic over its own frame's luminance where it has no such.
    const bool whole = against == NoiseAgainst::every_bounce && !energy.noise_against_whole.empty();
    const double analysed = BounceEnergy::at(whole ? energy.noise_against_whole : energy.noise_per_sample, bounces);
    // The statistic this scene's reference frames measured in the view, where they did, either way
    // from the analysis': a frame's samples meet rare bright paths that the analysis' miss (the
    // glossy gallery's frames at one bounce measure 26 times its statistic), and its pixels are the
    // view's, not the analysis' 24x24 (the outdoor scene's frames of no bounces measure a tenth).
    ReferenceNoise noise;
    noise.measured_ratio = measured ? measured->noise_ratio(bounces) : std::nullopt;
    noise.scale = measured ? measured->noise_scale() : std::nullopt;
    double per_sample = noise.measured_ratio.value_or(1.0) * analysed;
    // Against every bounce the denominator is one frame's, and a further bounce adds light along the
    // same paths: its variance does not fall. Where two counts' statistics read otherwise (ratios
    // measured from frames of different samples, the analysis' few paths), the fewer bounces' is the
    // floor; else 4 bounces could look quieter than 2 and win a time budget on noise alone (the
    // foliage relit within 200 ms took 4 at 47 samples, 0.00060, where 2 at 48 had measured 0.00053).
    for (int fewer = 0; whole && fewer < bounces; ++fewer) {
        const std::optional<double> ratio = measured ? measured->noise_ratio(fewer) : std::nullopt;
        const double at_fewer = ratio.value_or(1.0) * BounceEnergy::at(energy.noise_against_whole, fewer);
        if (at_fewer > per_sample) {
            per_sample = at_fewer;
            noise.floor_bounces = fewer;
        }
    }
    noise.rel_mse = noise.scale.value_or(1.0) * per_sample / std::max(1.0, spp);
    return noise;
}

ErrorPrediction predict_error(const SceneAnalysis& analysis, const std::string& method, const std::string& preset,
                              const methods::KnobValues& knobs, const SceneMeasurements* measured,
                              const OwnErrorPriors& priors) {
    const BounceEnergy& energy = analysis.bounces;
    const int bounces = modelled_bounces(method, knobs);
    const double stopped = BounceEnergy::at(energy.stopped_error, bounces);
    ErrorPrediction prediction;
    if (method == "reference") {
        const double spp = std::max(1.0, methods::knob_or(knobs, "spp", 1.0));
        const ReferenceNoise expected = reference_noise(analysis, bounces, spp, measured, NoiseAgainst::every_bounce);
        const double noise = expected.rel_mse;
        prediction.rel_mse = stopped + noise;
        prediction.basis = fmt::format("{} bounces lack {:.3f}; noise {:.3f} at {:.0f} spp", bounces, stopped, noise, spp);
        if (methods::knob_or(knobs, "denoise", 0.0) != 0.0) {
            // What the filter leaves of the noise, and adds: at most the bench's bound of it.
            if (!(priors.denoised_largest > 0.0)) {
                prediction.ruled_out = "no bound of the denoiser's error is known";
                return prediction;
            }
            // The filter darkens (a firefly is left out by its neighbours), as the bounces it lacks do:
            // the two add as errors of one sign may, by the triangle inequality, not apart.
            const double left = priors.denoised_largest * std::pow(noise, kDenoisedNoiseExponent);
            prediction.rel_mse = std::pow(std::sqrt(stopped) + std::sqrt(left), 2.0);
            prediction.basis = fmt::format("{} bounces lack {:.3f}; denoised, {:.3f} at most of the noise {:.3f} at {:.0f} "
                                           "spp ({:.3g} n^{:g} on {}), added to what the bounces lack as errors of one "
                                           "sign add",
                                           bounces, stopped, left, noise, spp, priors.denoised_largest,
                                           kDenoisedNoiseExponent, priors.denoised_source);
        }
        prediction.promised_rel_mse = prediction.rel_mse;
        if (expected.floor_bounces) {
            prediction.basis +=
                fmt::format(" (the noise of {} bounces, which more do not lessen", *expected.floor_bounces);
        } else if (expected.measured_ratio) {
            prediction.basis += fmt::format(" ({:.2f}x the analysis' statistic, as this scene's reference frames measured it",
                                            *expected.measured_ratio);
        } else {
            prediction.basis += " (the analysis' statistic";
        }
        prediction.basis += expected.scale ? fmt::format(", x {:.2f}, the relMSE that statistic made between this scene's "
                                                         "reference frames)",
                                                         *expected.scale)
                                           : ")";
        return prediction;
    }
    const OwnErrorOf own = own_error(analysis, method, preset, bounces, measured, priors);
    prediction.rel_mse = std::max(0.0, stopped + own.estimate);  // negative where it fills in what the bounces lack
    prediction.promised_rel_mse = std::max(prediction.rel_mse, stopped + own.promised);
    prediction.basis = fmt::format("{} bounce{} lack {:.3f}; {} {} adds {:.3f} {}", bounces, bounces == 1 ? "" : "s",
                                   stopped, method, preset, own.estimate, own.basis);
    if (prediction.promised_rel_mse > prediction.rel_mse) {
        prediction.basis += fmt::format(", {:.3f} with the reference noise its comparisons took out counted back, "
                                        "which a target is promised",
                                        stopped + own.promised);
    }
    if (leaks_through_thin_walls(analysis, method, preset)) {
        // Promised what the bench's leaking scenes measured, or what this scene's frames did; with
        // neither, nothing is known of how far the light leaks.
        const ThinWalls::Preset& walls = analysis.thin_walls.presets.at(preset);
        const std::string thin = fmt::format("{:.0f}% of the surface is a lit wall thinner than vct {}'s {:.3f} m voxels",
                                             100.0 * walls.leaking_area, preset, walls.voxel_size);
        const bool measured_here = measured && measured->own_error(method, preset, bounces);
        if (measured_here || priors.largest_of(method, preset, bounces, /*leaking=*/true)) {
            prediction.basis += " (" + thin + ")";
        } else {
            prediction.ruled_out = thin + ", and no scene where it leaks has measured it";
        }
    }
    // What the preset leaves to the scene, as the frame will resolve it (renderer/scene_knobs.hpp).
    const methods::MethodRegistry& knob_registry = methods::MethodRegistry::builtin();
    if (const methods::KnobValues resolved = knob_registry.resolve(method, preset, knobs);
        set_by_scene(resolved, "ism_dilation") && !knobs.contains("ism_dilation") && analysis.visibility.pairs > 0) {
        const double below = resolved.at("ism_open_below");
        const bool open = analysis.visibility.occluded_fraction < below;
        prediction.basis += fmt::format("; its maps {} ({:.0f}% of the indirect light occluded, {} {:.1f}%)",
                                        open ? "undilated" : "dilated", 100.0 * analysis.visibility.occluded_fraction,
                                        open ? "under" : "at least", 100.0 * below);
    }
    // A method that lets indirect light through what occludes it (isr without imperfect shadow maps)
    // is ruled out where most of that light is occluded.
    if (analysis.visibility.mostly_occluded()) {
        const methods::MethodRegistry& registry = methods::MethodRegistry::builtin();
        const methods::MethodInfo& info = registry.find(method);
        const std::string unmodelled =
            info.unmodelled_indirect_visibility
                ? info.unmodelled_indirect_visibility(registry.resolve(method, preset, knobs))
                : std::string();
        if (!unmodelled.empty()) {
            prediction.ruled_out =
                fmt::format("{:.0f}% of the indirect light is occluded, which {} {} does not model ({})",
                            100.0 * analysis.visibility.occluded_fraction, method, preset, unmodelled);
        }
    }
    return prediction;
}

}  // namespace bounce::planning
