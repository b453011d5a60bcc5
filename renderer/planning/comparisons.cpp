#include "renderer/planning/comparisons.hpp"

#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/registry.hpp"
#include "renderer/planning/error_model.hpp"
#include "renderer/scene_knobs.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace bounce::planning {
namespace {

double knob(const FrameStats& stats, const std::string& name, double otherwise) {
    return methods::knob_or(stats.knobs, name, otherwise);
}

double stopped_at(const SceneAnalysis* analysis, int bounces) {
    return analysis ? BounceEnergy::at(analysis->bounces.stopped_error, bounces) : 0.0;
}

}  // namespace

bool FrameComparisons::usable_draw(const FrameStats& stats) {
    return stats.method == "reference" && knob(stats, "spp", 0.0) >= 1.0 && knob(stats, "denoise", 0.0) == 0.0 &&
           knob(stats, "indirect_visibility", 1.0) != 0.0 && knob(stats, "ao", 0.0) == 0.0 &&
           stats.method_statistics.count("noise_per_sample") > 0;
}

bool FrameComparisons::usable_reference(const FrameStats& stats) {
    return usable_draw(stats) && knob(stats, "spp", 0.0) >= kMinReferenceSpp;
}

namespace {

// Whether two draws estimate one image independently, or one holds the other's samples and the rest.
bool pairable(const RenderResult& fewer, const RenderResult& more) {
    if (!FrameComparisons::usable_draw(fewer.stats) || !FrameComparisons::usable_draw(more.stats)) return false;
    if (fewer.frame.width != more.frame.width || fewer.frame.height != more.frame.height ||
        fewer.frame.rgba.size() != more.frame.rgba.size()) {
        return false;
    }
    if (modelled_bounces("reference", fewer.stats.knobs) != modelled_bounces("reference", more.stats.knobs)) return false;
    if (knob(fewer.stats, "pixel_jitter", 1.0) != knob(more.stats, "pixel_jitter", 1.0)) return false;
    const bool same_seed = knob(fewer.stats, "seed", 1.0) == knob(more.stats, "seed", 1.0);
    return !same_seed || knob(more.stats, "spp", 0.0) > knob(fewer.stats, "spp", 0.0);
}

}  // namespace

std::optional<std::pair<image::Frame, image::Frame>> FrameComparisons::independent_draws(const RenderResult& fewer,
                                                                                        const RenderResult& more) {
    if (!pairable(fewer, more)) return std::nullopt;
    if (knob(fewer.stats, "seed", 1.0) != knob(more.stats, "seed", 1.0)) return std::pair{fewer.frame, more.frame};
    return std::pair{fewer.frame, later_samples(fewer.frame, knob(fewer.stats, "spp", 0.0), more.frame, knob(more.stats, "spp", 0.0))};
}

image::Frame FrameComparisons::later_samples(const image::Frame& fewer, double f, const image::Frame& more, double m) {
    BOUNCE_CHECK(fewer.width == more.width && fewer.height == more.height && fewer.rgba.size() == more.rgba.size(),
                 "cannot take a {}x{} frame's samples out of a {}x{} frame", fewer.width, fewer.height, more.width, more.height);
    BOUNCE_CHECK(f >= 0.0 && m > f, "a frame of {} samples cannot hold one of {}", m, f);
    image::Frame later = more;
    for (std::size_t i = 0; i < later.rgba.size(); ++i) {
        if (i % 4 != 3) later.rgba[i] = static_cast<float>((m * more.rgba[i] - f * fewer.rgba[i]) / (m - f));
    }
    return later;
}

bool FrameComparisons::usable_gpu_frame(const FrameStats& stats, const SceneAnalysis* analysis) {
    if (stats.method == "reference" || !own_error_prior(stats.method, stats.preset)) return false;
    const methods::MethodInfo& info = methods::MethodRegistry::builtin().find(stats.method);
    const auto preset = info.presets.find(stats.preset);
    if (preset == info.presets.end()) return false;
    // What the preset leaves to the scene, as this scene resolves it: a frame whose request set such
    // a knob otherwise is not the preset's. Without the analysis, whatever the scene could set.
    methods::KnobValues own_knobs = preset->second;
    if (analysis) resolve_scene_knobs(*analysis, info, {}, own_knobs);
    for (const auto& [name, value] : stats.knobs) {
        if (name == "bounces") continue;  // the error model separates bounces from the rest
        if (!analysis && set_by_scene(preset->second, name)) continue;
        const auto own = own_knobs.find(name);
        if (own == own_knobs.end() || own->second != value) return false;
    }
    return true;
}

namespace {

// What of a GPU frame's relMSE against `reference` is expected not to be its own: the reference's
// noise, and the light of the bounces the reference has and the frame lacks.
std::pair<double, double> expected_parts(const FrameStats& gpu_frame, const FrameStats& reference,
                                         const SceneAnalysis* analysis, const SceneMeasurements& measurements) {
    const int bounces = modelled_bounces(gpu_frame.method, gpu_frame.knobs);
    const int reference_bounces = modelled_bounces("reference", reference.knobs);
    // The frame's own statistic per sample, or what the scene's frames of most samples read at its
    // bounce count where that is less: a frame's own reads high at few samples
    // (SceneMeasurements::record_noise), and taking out too much would promise the GPU frame less
    // error than it has.
    double per_sample = reference.method_statistics.at("noise_per_sample");
    if (const auto ratio = measurements.noise_ratio(reference_bounces); ratio && analysis) {
        per_sample = std::min(per_sample, *ratio * BounceEnergy::at(analysis->bounces.noise_per_sample, reference_bounces));
    }
    const double noise = measurements.least_noise_scale().value_or(FrameComparisons::kUncalibratedNoiseScale) *
                         per_sample / std::max(1.0, knob(reference, "spp", 1.0));
    // A reference with fewer bounces than the frame counts the frame's extra light as error. That is
    // not the safe side: a frame that lacks light agrees better with a reference that lacks it too
    // (in the glossy gallery cssm draft at 8 bounces read 0.021 against 3 bounces and measures 0.037).
    // compare() keeps such a comparison only where that light is small beside the relMSE.
    const double gap = reference_bounces > bounces
                           ? std::max(0.0, stopped_at(analysis, bounces) - stopped_at(analysis, reference_bounces))
                           : 0.0;
    return {noise, gap};
}

}  // namespace

std::optional<Comparison> FrameComparisons::compare(const RenderResult& gpu_frame, const RenderResult& reference,
                                                    const SceneAnalysis* analysis, SceneMeasurements& measurements,
                                                    const RenderResult* deeper, std::optional<std::uint64_t> view,
                                                    const RenderResult* partner, bool cross_only) {
    if (gpu_frame.frame.width != reference.frame.width || gpu_frame.frame.height != reference.frame.height) return std::nullopt;
    const bool quiet = usable_reference(reference.stats);
    if (!quiet && !partner) return std::nullopt;
    Comparison c;
    c.method = gpu_frame.stats.method;
    c.preset = gpu_frame.stats.preset;
    c.bounces = modelled_bounces(c.method, gpu_frame.stats.knobs);
    c.rel_mse = image::compare(gpu_frame.frame, reference.frame).rel_mse;
    std::tie(c.reference_noise, c.bounce_gap) = expected_parts(gpu_frame.stats, reference.stats, analysis, measurements);
    // The light of the bounces the frame has and the reference lacks: not taken out, but it may hide
    // as much of the frame's error as it adds.
    const double extra_light =
        std::max(0.0, stopped_at(analysis, modelled_bounces("reference", reference.stats.knobs)) - stopped_at(analysis, c.bounces));
    // The own part must be at least half of what was measured: a frame whose error is mostly the
    // reference's noise or the bounces one of them lacks says little of its own, and what it says
    // would be carried to other bounce counts. Where the bounces it lacks were the larger part, the
    // preset is not counted as compared: probed again, it gets a reference of its own bounce count
    // (probes()).
    // The noise taken out is itself uncertain by about its size (pairs of references measured 0.49
    // to 0.93 of the statistic on the bench corpus; in the furnished room a comparison took out
    // 0.028 of 0.062 where its truth implies about 0.009): it may be at most a quarter of the relMSE,
    // so that being wrong by all of it misreads the own error by at most a third.
    const bool drowned = !(c.rel_mse >= 0.0) || c.reference_noise + c.bounce_gap + extra_light > 0.5 * c.rel_mse ||
                         c.reference_noise > kMaxNoiseShare * c.rel_mse;
    // Drowned by the reference's noise alone (a reference of the frame's own bounce count), the
    // comparison still bounds the view's frame's own error, taking out half the noise it expects
    // (kBoundNoiseShare): what the noise adds to a relMSE ranges from under to over the statistic by
    // scene (noisy own-value weights raise it where the noise is in dark pixels, and damp it where it
    // is in bright fireflies), and of it the furnished room's frames measured the least, about 0.6 of
    // the statistic at the corpus' least scale (above). In the street, isr draft against a
    // 16-sample reference of its one bounce reads 0.032 where 0.0086 is expected of the noise and its
    // own error is 0.0016 (0.012 before the cross term): the bound, about 0.018, is under the prior
    // (0.028) that otherwise stands until a quieter reference comes.
    const bool own_count = view && c.rel_mse >= 0.0 && c.bounce_gap == 0.0 && extra_light == 0.0 &&
                           modelled_bounces("reference", reference.stats.knobs) == c.bounces;
    // Drowned, or of too few samples for the noise model, and with a second draw of the reference's
    // bounce count: what the two draws estimate, without their noise (Comparison::cross_estimate).
    // In the street the noise added 2.5 times what its statistic said to isr draft's relMSE against
    // a 16-sample reference of its one bounce (0.032, where its own error is 0.0104); against the
    // 6 samples before it and the 10 after them, the estimate reads 0.0107 +- 0.0013.
    if ((drowned || !quiet) && own_count && partner && partner != &reference) {
        const bool reference_first = knob(reference.stats, "spp", 0.0) < knob(partner->stats, "spp", 0.0);
        const RenderResult& fewer = reference_first ? reference : *partner;
        const RenderResult& more = reference_first ? *partner : reference;
        if (const auto draws = independent_draws(fewer, more)) {
            image::Frame both = more.frame;  // the draws' union weighs the differences
            if (knob(fewer.stats, "seed", 1.0) != knob(more.stats, "seed", 1.0)) {
                const double f = knob(fewer.stats, "spp", 0.0), m = knob(more.stats, "spp", 0.0);
                for (std::size_t i = 0; i < both.rgba.size(); ++i) {
                    if (i % 4 != 3) both.rgba[i] = static_cast<float>((f * fewer.frame.rgba[i] + m * more.frame.rgba[i]) / (f + m));
                }
            }
            const image::CrossEstimate estimate = image::cross_rel_mse(gpu_frame.frame, draws->first, draws->second, both);
            if (estimate.pixels > 0 && 2.0 * estimate.standard_error <= kMaxCrossSpread * estimate.rel_mse) {
                c.cross_estimate = true;
                c.cross_rel_mse = estimate.rel_mse;
                c.cross_standard_error = estimate.standard_error;
            }
        }
    }
    if ((!quiet || cross_only) && !c.cross_estimate) return std::nullopt;  // nothing new: the preset may be probed again
    c.noise_bound = drowned && !c.cross_estimate && own_count;
    if (drowned && !c.noise_bound && !c.cross_estimate) {
        if (!(c.bounce_gap > c.reference_noise)) measurements.record_compared(c.method, c.preset, c.bounces);
        return std::nullopt;
    }
    // What is taken out of the relMSE: the noise expected, half of it for a bound, or for a cross
    // estimate all but the estimate plus one standard error.
    const double noise_taken = c.cross_estimate ? c.rel_mse - (c.cross_rel_mse + c.cross_standard_error)
                               : c.noise_bound  ? kBoundNoiseShare * c.reference_noise
                                                : c.reference_noise;
    measurements.record_compared(c.method, c.preset, c.bounces);
    // Against the frame of more bounces that the reference is a prefix of (the same paths, gone on),
    // the part of the frame's error that lies where the later bounces' light is. The error model adds
    // the bounces' light and the own error as if they were apart; where the frame lacks light where
    // the bounces add it, they add more (in the glossy gallery vct draft measured 0.006 against one
    // bounce, lacks 0.035 of bounces, and is at 0.055, not 0.041). Of the three relMSEs the
    // reference's noise cancels: its own against the deeper frame carries it as the GPU frame's does.
    if (deeper && deeper->frame.width == gpu_frame.frame.width && deeper->frame.height == gpu_frame.frame.height &&
        c.bounce_gap == 0.0) {
        c.crossed = true;
        c.later_light = image::compare(reference.frame, deeper->frame).rel_mse;
        c.cross_term = image::compare(gpu_frame.frame, deeper->frame).rel_mse - c.later_light - c.rel_mse;
        // The deeper frame stops too, and the light past it meets the frame's error as well: in the
        // glossy gallery cssm draft at 3 bounces measured +0.0047 against 4 bounces and was promised
        // 0.033 where it measures 0.040. The term is linear in the later light (-2 <error, light>, each
        // bounce's light a part of it), and late bounces are alike in shape, each the analysis'
        // ratio r of the one before: past the deeper frame's D bounces, bounce D's own part
        // continues as a geometric series, x_D r / (1 - r). Only a positive part is continued (a
        // promise does not count on later light to hide error), and the whole stays within the
        // Cauchy-Schwarz bound 2 sqrt(own x s_b).
        const int deeper_bounces = modelled_bounces("reference", deeper->stats.knobs);
        double last_part = c.cross_term;  // bounce D's part: all of it where D follows the frame's count
        if (deeper_bounces - 1 > c.bounces) {
            for (const auto& byproduct : deeper->byproducts) {
                if (modelled_bounces("reference", byproduct->stats.knobs) != deeper_bounces - 1 ||
                    byproduct->frame.width != gpu_frame.frame.width || byproduct->frame.height != gpu_frame.frame.height) {
                    continue;
                }
                last_part = c.cross_term - (image::compare(gpu_frame.frame, byproduct->frame).rel_mse -
                                            image::compare(reference.frame, byproduct->frame).rel_mse - c.rel_mse);
            }
        }
        const double r = analysis ? analysis->bounces.light_ratio_past(deeper_bounces) : 0.0;
        if (last_part > 0.0 && r > 0.0) {
            const double bound = 2.0 * std::sqrt(std::max(0.0, c.rel_mse - noise_taken) * stopped_at(analysis, c.bounces));
            c.cross_beyond = std::clamp(last_part * r / (1.0 - r), 0.0, std::max(0.0, bound - c.cross_term));
        }
    }
    // Not clamped at 0: where the frame's error fills in the light its bounces lack (light leaked
    // through a wall, or gathered without visibility, standing in for a further bounce), what it
    // adds is negative, and stopped_error[b] plus it is its error against every bounce. Clamped,
    // the furnished room's isr draft (0.067 against 6 bounces) and cssm draft at one bounce (0.085)
    // both read 0, each promised the 0.094 its bounce lacks, and the worse won the tie within
    // 200 ms. Never below -stopped_error[b] (an error is not negative), and carried to other bounce
    // counts as 0 (SceneMeasurements::own_error).
    const double with_noise = c.rel_mse - c.bounce_gap + c.cross_term + c.cross_beyond;
    c.own_error = std::max(-stopped_at(analysis, c.bounces), with_noise - noise_taken);
    // A promise does not count on the noise the statistic took out (Comparison::unsure); a cross
    // estimate's two draws measured it.
    double promised = c.cross_estimate ? c.own_error : std::max(-stopped_at(analysis, c.bounces), with_noise);
    // Against a reference lacking light the frame has, a frame that lacks light itself agrees better
    // than it would with the whole, by up to 2 sqrt(own x lacking) + lacking where the two are
    // missing in the same places (relMSE is a weighted squared norm: the triangle inequality). That
    // bound is recorded: in the furnished room cssm draft at 8 bounces read 0.041 against 6 bounces
    // (lacking 0.005) and measures 0.052 against the whole; the bound says 0.075.
    // A noise bound is kept only where the relMSE is more than the noise taken out (else the noise
    // expected is more than this draw's, and the rest says nothing), never below 0, and only where
    // it says more than the prior, which it would otherwise replace. Its promise is never over that
    // prior: a bound that tells less than the prior does not make the preset worse than unmeasured.
    if (c.noise_bound) {
        if (c.rel_mse <= kBoundNoiseShare * c.reference_noise) return std::nullopt;
        c.own_error = std::max(0.0, c.own_error);
        const std::optional<double> prior = own_error_prior(c.method, c.preset, c.bounces);
        if (!prior || c.own_error >= *prior) return std::nullopt;
        promised = std::clamp(promised, c.own_error, *prior);
    }
    const bool bound = extra_light > 0.0 || c.noise_bound;
    if (extra_light > 0.0) {
        c.own_error = std::pow(std::sqrt(std::max(c.own_error, 0.0)) + std::sqrt(extra_light), 2.0);
        promised = std::pow(std::sqrt(std::max(promised, 0.0)) + std::sqrt(extra_light), 2.0);
    }
    c.unsure = std::max(0.0, promised - c.own_error);
    if (view && !bound) {
        // What is uncertain of it: the noise taken out, or a cross estimate's two standard errors.
        // A cross estimate's cross term still comes from the one reference and the deeper frame it
        // was traced with, whose noise is correlated and about the reference's: that is uncertain too.
        const double uncertain = c.cross_estimate ? 2.0 * c.cross_standard_error + (deeper ? c.reference_noise : 0.0)
                                                  : c.reference_noise;
        measurements.record_own_estimate(c.method, c.preset, c.bounces, c.own_error, *view,
                                         uncertain + c.bounce_gap + c.cross_beyond, c.unsure,
                                         c.crossed ? std::optional(c.cross_term + c.cross_beyond) : std::nullopt);
    } else {
        measurements.record_own_error(c.method, c.preset, c.bounces, c.own_error, bound ? view : std::nullopt, c.unsure);
    }
    return c;
}

std::optional<double> FrameComparisons::calibrate_noise(const RenderResult& fewer, const RenderResult& more,
                                                       const SceneAnalysis* analysis, SceneMeasurements& measurements) {
    if (!usable_reference(fewer.stats) || !usable_reference(more.stats)) return std::nullopt;
    if (fewer.frame.width != more.frame.width || fewer.frame.height != more.frame.height) return std::nullopt;
    if (knob(fewer.stats, "pixel_jitter", 1.0) != knob(more.stats, "pixel_jitter", 1.0)) return std::nullopt;
    const double fewer_spp = knob(fewer.stats, "spp", 1.0), more_spp = knob(more.stats, "spp", 1.0);
    if (more_spp < kCalibrationSpan * fewer_spp) return std::nullopt;
    const double rel_mse = image::compare(fewer.frame, more.frame).rel_mse;
    const int fewer_bounces = modelled_bounces("reference", fewer.stats.knobs);
    const int more_bounces = modelled_bounces("reference", more.stats.knobs);
    const double gap = std::abs(stopped_at(analysis, fewer_bounces) - stopped_at(analysis, more_bounces));
    const bool same_seed = knob(fewer.stats, "seed", 0.0) == knob(more.stats, "seed", 1.0);
    // Of one seed and other bounce counts, the two share their first vertices' noise by an amount
    // neither statistic tells (one frame's bounce prefix and another's frame, say).
    if (same_seed && fewer_bounces != more_bounces) return std::nullopt;
    // Frames of one seed share their first samples (a sample draws from the seed, the pixel and its
    // index alone): the larger holds the smaller, and their difference is the smaller's noise less
    // the larger's, not the sum of the two.
    const bool nested = same_seed;
    const auto statistic_of = [&](double fewer_noise, double more_noise) {
        return nested ? fewer_noise * (1.0 / fewer_spp - 1.0 / more_spp) : fewer_noise / fewer_spp + more_noise / more_spp;
    };
    const double fewer_own = fewer.stats.method_statistics.at("noise_per_sample");
    const double more_own = more.stats.method_statistics.at("noise_per_sample");
    // Two scales. For a reference's predicted error against a converged frame: the pair's relMSE
    // weighed by the larger frame's neighbourhoods' medians (image::Weight::neighbourhood_median: a
    // frame of one seed and more samples holds the smaller's rare bright paths, which raise its own
    // values exactly where the difference is largest), over the statistic per sample as the frame of
    // more samples reads it where both have one bounce count (one quantity, which a frame of few
    // samples reads high: SceneMeasurements::record_noise). On the bench corpus that reads 0.93 to
    // 1.01 of the statistic where the truth reads 0.85 to 1.00, and 0.66 in the foliage where it
    // reads 0.52 to 0.55; weighed by the larger frame's own values, over the same statistic, 0.13 to
    // 0.27 in the furnished room at 4 against 16 samples (bench/reference_noise).
    const double statistic = statistic_of(fewer_bounces == more_bounces ? more_own : fewer_own, more_own);
    // For the noise a comparison takes out of a GPU frame's relMSE against a reference frame: as that
    // comparison weighs it, by image::compare, whose weights hold the reference's own noise, over
    // each frame's own statistic.
    const double compared_statistic = statistic_of(fewer_own, more_own);
    // The bounce gap is the analysis' estimate, noisy itself: a pair whose difference is over a quarter
    // gap says too little of the noise.
    if (!(rel_mse >= 0.0) || !(statistic > kMinCalibrationStatistic) || !(compared_statistic > kMinCalibrationStatistic) ||
        gap > kMaxCalibrationGap * rel_mse) {
        return std::nullopt;
    }
    const double smoothed = image::compare(fewer.frame, more.frame, image::Weight::neighbourhood_median).rel_mse;
    const double scale = std::max(0.0, smoothed - gap) / statistic;
    const double compared_scale = (rel_mse - gap) / compared_statistic;
    measurements.record_noise_scale(scale, compared_scale);
    log::info("planner", "reference noise: {:.0f} against {:.0f} spp{}, relMSE {:.4f} ({:.4f} by image::compare; bounces "
              "{:.4f}) where the noise statistic says {:.4f}: x {:.2f} (compared x {:.2f})",
              fewer_spp, more_spp, nested ? " of one seed" : "", smoothed, rel_mse, gap, statistic, scale, compared_scale);
    return scale;
}

std::shared_ptr<const RenderResult> FrameComparisons::best_reference(const FrameStats& gpu_frame, const SceneAnalysis* analysis,
                                                                    const SceneMeasurements& measurements) const {
    // A reference with at least the frame's bounces, the one whose noise and bounce gap are least;
    // one with fewer would count the frame's extra light as its error, so such a reference is taken
    // only where there is no other (the one with the most bounces).
    const int frame_bounces = modelled_bounces(gpu_frame.method, gpu_frame.knobs);
    std::shared_ptr<const RenderResult> best;
    double best_parts = 0.0;
    for (const auto& [bounces, reference] : references_) {
        if (bounces < frame_bounces) continue;
        const auto [noise, gap] = expected_parts(gpu_frame, reference->stats, analysis, measurements);
        if (!best || noise + gap < best_parts) {
            best = reference;
            best_parts = noise + gap;
        }
    }
    if (!best && !references_.empty()) best = references_.rbegin()->second;
    return best;
}

std::vector<Comparison> FrameComparisons::add(std::uint64_t view, std::shared_ptr<const RenderResult> frame,
                                              const SceneAnalysis* analysis, SceneMeasurements& measurements) {
    const FrameStats& stats = frame->stats;
    const bool is_reference = usable_draw(stats);
    if (!is_reference && !usable_gpu_frame(stats, analysis)) return {};
    // A reference arrives with its frames of fewer bounces: each a reference of its own bounce count.
    std::vector<std::shared_ptr<const RenderResult>> incoming;
    if (is_reference) {
        for (const auto& byproduct : frame->byproducts) {
            if (usable_draw(byproduct->stats)) incoming.push_back(byproduct);
        }
    }
    incoming.push_back(frame);
    std::vector<std::pair<std::shared_ptr<const RenderResult>, std::shared_ptr<const RenderResult>>> calibrations;
    struct Pending {
        std::shared_ptr<const RenderResult> gpu_frame, reference, deeper, partner;
        bool cross_only = false;
    };
    std::vector<Pending> to_compare;
    {
        const std::lock_guard lock(mutex_);
        if (view_ != view) {
            view_ = view;
            references_.clear();
            draws_.clear();
            gpu_frames_.clear();
        }
        if (is_reference) {
            // Every draw first: a byproduct's comparison finds the trace it came from among them
            // (deeper_than()).
            for (const auto& reference : incoming) {
                auto& draws = draws_[modelled_bounces("reference", reference->stats.knobs)];
                draws.push_back(reference);
                std::stable_sort(draws.begin(), draws.end(), [](const auto& a, const auto& b) {
                    return knob(a->stats, "spp", 0.0) > knob(b->stats, "spp", 0.0);
                });
                if (draws.size() > kMaxDraws) draws.pop_back();
            }
            trim_draws();
            std::vector<std::shared_ptr<const RenderResult>> kept_now;
            for (const auto& reference : incoming) {
                const int bounces = modelled_bounces("reference", reference->stats.knobs);
                const auto& draws = draws_[bounces];
                if (!usable_reference(reference->stats)) {
                    // Too few samples to be a reference alone: with a second draw, a cross estimate
                    // of the GPU frames of its bounce count.
                    if (std::find(draws.begin(), draws.end(), reference) == draws.end()) continue;
                    if (const auto partner = partner_of(*reference)) {
                        for (const auto& [key, kept] : gpu_frames_) {
                            if (std::get<2>(key) == bounces) to_compare.push_back({kept.frame, reference, deeper_than(*reference), partner});
                        }
                    }
                    continue;
                }
                // The noise calibration's partner: a kept reference of the same bounce count pairs best
                // (no bounce gap, and of one seed, nested); else the one with the most samples.
                std::shared_ptr<const RenderResult> partner;
                for (const auto& [kept_bounces, kept] : references_) {
                    if (!partner || knob(kept->stats, "spp", 0.0) > knob(partner->stats, "spp", 0.0)) partner = kept;
                }
                if (const auto same = references_.find(bounces); same != references_.end()) partner = same->second;
                if (partner) {
                    if (knob(partner->stats, "spp", 0.0) >= knob(reference->stats, "spp", 0.0)) calibrations.emplace_back(reference, partner);
                    else calibrations.emplace_back(partner, reference);
                }
                // Per bounce count, the one with the most samples: the least noise to subtract.
                auto& kept = references_[bounces];
                if (!kept || knob(kept->stats, "spp", 0.0) < knob(reference->stats, "spp", 0.0)) {
                    kept = reference;
                    kept_now.push_back(reference);
                } else if (std::find(draws.begin(), draws.end(), reference) != draws.end() && partner_of(*kept) == reference) {
                    // Not kept, but the kept one's partner now: the frames it measures, again, by the pair.
                    for (const auto& [key, gpu] : gpu_frames_) {
                        if (best_reference(gpu.frame->stats, analysis, measurements) == kept) {
                            to_compare.push_back({gpu.frame, kept, deeper_than(*kept), reference, true});
                        }
                    }
                }
            }
            // Each GPU frame is compared with the reference that leaves the least of its relMSE not
            // its own: where that is now one of these.
            for (const auto& [key, kept] : gpu_frames_) {
                const auto& gpu_frame = kept.frame;
                const auto best = best_reference(gpu_frame->stats, analysis, measurements);
                if (std::find(kept_now.begin(), kept_now.end(), best) != kept_now.end()) {
                    to_compare.push_back({gpu_frame, best, deeper_than(*best), partner_of(*best)});
                }
            }
        } else {
            const std::tuple key{stats.method, stats.preset, modelled_bounces(stats.method, stats.knobs)};
            if (gpu_frames_.size() >= kMaxFrames && !gpu_frames_.count(key)) drop_a_gpu_frame();
            gpu_frames_[key] = {frame, ++added_};
            const auto reference = best_reference(stats, analysis, measurements);
            if (reference) to_compare.push_back({frame, reference, deeper_than(*reference), partner_of(*reference)});
            // Draws of its own bounce count too few samples to be references: their cross estimate.
            const int bounces = std::get<2>(key);
            if (const auto draws = draws_.find(bounces); draws != draws_.end() && !draws->second.empty() &&
                                                         !usable_reference(draws->second.front()->stats)) {
                const auto& draw = draws->second.front();
                if (const auto partner = partner_of(*draw)) to_compare.push_back({frame, draw, deeper_than(*draw), partner});
            }
        }
    }
    for (const auto& [fewer, more] : calibrations) calibrate_noise(*fewer, *more, analysis, measurements);
    std::vector<Comparison> made;
    for (const auto& [gpu_frame, reference, deeper, partner, cross_only] : to_compare) {
        if (auto c = compare(*gpu_frame, *reference, analysis, measurements, deeper.get(), view, partner.get(), cross_only)) {
            log::info("planner", "{} {} at {} bounces against this view's {}-bounce reference: relMSE {:.4f}, {}own error {:.4f}{}{}",
                      c->method, c->preset, c->bounces, modelled_bounces("reference", reference->stats.knobs), c->rel_mse,
                      deeper ? fmt::format("against the {}-bounce frame it was traced with (which adds {:.4f}) {:+.4f} "
                                           "and past it {:+.4f}, ",
                                           modelled_bounces("reference", deeper->stats.knobs), c->later_light,
                                           c->cross_term, c->cross_beyond)
                             : "",
                      c->own_error,
                      c->noise_bound ? fmt::format(" at most (the reference's noise, {:.4f}, over a quarter of the relMSE: half of it taken out)",
                                                   c->reference_noise)
                      : c->cross_estimate ? fmt::format(" (from two draws of {} and {} samples: {:.4f} +- {:.4f} without their noise)",
                                                        std::min(knob(partner->stats, "spp", 0.0), knob(reference->stats, "spp", 0.0)),
                                                        std::max(knob(partner->stats, "spp", 0.0), knob(reference->stats, "spp", 0.0)),
                                                        c->cross_rel_mse, c->cross_standard_error)
                                          : "",
                      c->unsure > 0.0 ? fmt::format(", promised {:.4f}", c->own_error + c->unsure) : "");
            made.push_back(std::move(*c));
        }
    }
    return made;
}

void FrameComparisons::drop_a_gpu_frame() {
    auto oldest = gpu_frames_.end(), oldest_measured = gpu_frames_.end();
    for (auto it = gpu_frames_.begin(); it != gpu_frames_.end(); ++it) {
        if (oldest == gpu_frames_.end() || it->second.order < oldest->second.order) oldest = it;
        const bool measured = references_.lower_bound(std::get<2>(it->first)) != references_.end();
        if (measured && (oldest_measured == gpu_frames_.end() || it->second.order < oldest_measured->second.order)) {
            oldest_measured = it;
        }
    }
    gpu_frames_.erase(oldest_measured != gpu_frames_.end() ? oldest_measured : oldest);
}

std::shared_ptr<const RenderResult> FrameComparisons::deeper_than(const RenderResult& reference) const {
    const int bounces = modelled_bounces("reference", reference.stats.knobs);
    for (auto kept = references_.rbegin(); kept != references_.rend() && kept->first > bounces; ++kept) {
        for (const auto& byproduct : kept->second->byproducts) {
            if (byproduct.get() == &reference) return kept->second;
        }
    }
    // A draw of too few samples to be kept as a reference came from a trace of its own.
    for (auto kept = draws_.rbegin(); kept != draws_.rend() && kept->first > bounces; ++kept) {
        for (const auto& draw : kept->second) {
            for (const auto& byproduct : draw->byproducts) {
                if (byproduct.get() == &reference) return draw;
            }
        }
    }
    return nullptr;
}

void FrameComparisons::trim_draws() {
    for (;;) {
        // Every draw but each count's first usable reference (the count's reference, kept as such).
        std::vector<std::pair<int, std::size_t>> extra;
        for (const auto& [bounces, draws] : draws_) {
            bool reference_seen = false;
            for (std::size_t i = 0; i < draws.size(); ++i) {
                if (!reference_seen && usable_reference(draws[i]->stats)) {
                    reference_seen = true;
                    continue;
                }
                extra.emplace_back(bounces, i);
            }
        }
        if (extra.size() <= kMaxExtraDraws) return;
        const auto fewest = std::min_element(extra.begin(), extra.end(), [&](const auto& a, const auto& b) {
            return knob(draws_[a.first][a.second]->stats, "spp", 0.0) < knob(draws_[b.first][b.second]->stats, "spp", 0.0);
        });
        auto& draws = draws_[fewest->first];
        draws.erase(draws.begin() + static_cast<std::ptrdiff_t>(fewest->second));
    }
}

std::size_t FrameComparisons::draws_held() const {
    const std::lock_guard lock(mutex_);
    std::size_t held = 0;
    for (const auto& [bounces, draws] : draws_) held += draws.size();
    return held;
}

std::shared_ptr<const RenderResult> FrameComparisons::partner_of(const RenderResult& reference) const {
    const auto draws = draws_.find(modelled_bounces("reference", reference.stats.knobs));
    if (draws == draws_.end()) return nullptr;
    for (const auto& draw : draws->second) {  // the most samples first
        if (draw.get() == &reference) continue;
        const bool fewer = knob(draw->stats, "spp", 0.0) < knob(reference.stats, "spp", 0.0);
        if (fewer ? pairable(*draw, reference) : pairable(reference, *draw)) return draw;
    }
    return nullptr;
}

}  // namespace bounce::planning
