#include "renderer/planning/planner.hpp"

#include "renderer/base/error.hpp"
#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/methods/registry.hpp"
#include "renderer/planning/comparisons.hpp"
#include "renderer/planning/error_model.hpp"
#include "renderer/planning/plan_order.hpp"
#include "renderer/planning/resolution.hpp"
#include "renderer/scene_knobs.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <tuple>

namespace bounce::planning {
namespace {

// The reference's plans: sample counts it is offered at (its bounce counts: plan_order.hpp).
// Steps of about 1.5, so that a plan meets a target error with at most that much time to spare.
constexpr int kReferenceSpp[] = {1,  2,  3,  4,   6,   8,   12,  16,  24,  32,   48,   64,   96,  128,
                                 192, 256, 384, 512, 768, 1024, 1536, 2048, 3072, 4096};
// cssm's bounce counts (its `bounces` knob).
constexpr int kCssmBounces[] = {1, 2, 3, 4, 6, 8};
// vct's: its second bounce gathers at the octree's leaves before the pixels gather from them.
constexpr int kVctBounces[] = {1, 2};

std::optional<int> bounces_knob(const methods::KnobValues& knobs) {
    const auto it = knobs.find("bounces");
    if (it == knobs.end()) return std::nullopt;
    return static_cast<int>(it->second);
}

}  // namespace

std::optional<double> baseline_ms(const SceneAnalysis* analysis, const DeviceCosts& device, const std::string& method,
                                  const std::string& preset, const methods::KnobValues& knobs, int width, int height) {
    const double pixels = static_cast<double>(width) * height;
    if (method == "reference") {
        if (!analysis || analysis->bounces.sample_ns.empty()) return std::nullopt;
        const double ns = BounceEnergy::at(analysis->bounces.sample_ns, modelled_bounces(method, knobs));
        const double spp = methods::knob_or(knobs, "spp", 1.0);
        return analysis->bounces.tracer_build_ms + ns * 1e-6 * pixels * spp;
    }
    const auto line = device.line(method, preset);
    if (!line) return std::nullopt;
    return line->at(pixels);
}

namespace {

using BouncePricing = PlanningInputs::BouncePricing;

// What a frame at `bounces` costs over one at the preset's own count, by `pricing`'s table.
double bounce_cost(BouncePricing pricing, const std::string& method, const std::string& preset, int bounces) {
    return pricing == BouncePricing::bound ? bounce_cost_bound(method, preset, bounces)
                                           : typical_bounce_cost(method, preset, bounces);
}

// How bounces not yet measured are priced, for a plan's cost basis.
std::string bounce_raise_text(BouncePricing pricing, double factor) {
    return pricing == BouncePricing::bound ? fmt::format(", x {:.2g} for bounces not yet measured", factor)
                                           : fmt::format(", x {:.2g}, what bounces not yet measured typically cost", factor);
}

// What frames of `measured_preset` at `measured` bounces are raised by to price `preset` at `bounces`:
// the ratio of `pricing`'s figures, never below 1 (fewer bounces are priced as the frames measured).
double bounce_raise(BouncePricing pricing, const std::string& method, const std::string& preset, int bounces,
                    const std::string& measured_preset, int measured) {
    if (method == "reference") return 1.0;  // its baseline prices each count (the analysis' time per sample)
    return std::max(1.0, bounce_cost(pricing, method, preset, bounces) / bounce_cost(pricing, method, measured_preset, measured));
}

// A GPU preset's time on this scene from the scene's own lines (SceneMeasurements::line), where it
// has any for the method: the preset's own line; else the device's line for the preset bent to the
// scene's line of another preset of the method (at each size, that preset's time here times the
// device's ratio between the two), scaled by this preset's frames measured here, if any.
std::optional<double> scene_line_ms(const PlanningInputs& inputs, const std::string& method, const std::string& preset,
                                    const methods::KnobValues& knobs, double pixels, std::string* basis) {
    // Frames are recorded under their resolved knobs: a plan that names no bounce count has its preset's.
    const int bounces = bounces_knob(knobs).value_or(preset_bounces(method, preset));
    if (const auto own = inputs.scene->line(method, preset, bounces)) {
        if (basis) *basis = "this scene's own line for the preset, from its frames at two sizes or more";
        return own->at(pixels);
    }
    const auto shape = inputs.scene->method_line(method, preset);
    const auto device_line = inputs.device.line(method, preset);
    const auto shape_device_line = shape ? inputs.device.line(method, shape->preset) : std::nullopt;
    if (!shape || !device_line || !shape_device_line) return std::nullopt;
    const auto model = [&](double p) {
        const double device_shape_ms = shape_device_line->at(p);
        return device_shape_ms > 0.0 ? shape->line.at(p) * device_line->at(p) / device_shape_ms : shape->line.at(p);
    };
    // The preset's frames at this size, else at the measured size nearest it (in the ratio of pixels).
    std::map<double, std::vector<const SceneMeasurements::FrameTime*>> by_size;
    const std::vector<SceneMeasurements::FrameTime> frames = inputs.scene->frames(method, preset, bounces);
    for (const SceneMeasurements::FrameTime& frame : frames) {
        if (frame.pixels > 0.0 && model(frame.pixels) > 0.0) by_size[frame.pixels].push_back(&frame);
    }
    if (by_size.empty()) {
        const double factor = bounce_raise(inputs.bounce_pricing, method, preset, bounces, shape->preset, shape->bounces);
        if (basis) {
            *basis = fmt::format("this scene's line for {} {} (frames at two sizes or more) x the device's ratio of the "
                                 "presets",
                                 method, shape->preset);
            if (factor > 1.0) *basis += bounce_raise_text(inputs.bounce_pricing, factor);
        }
        return model(pixels) * factor;
    }
    const auto distance = [&](double size) { return std::abs(std::log(size / pixels)); };
    const auto nearest = std::min_element(by_size.begin(), by_size.end(), [&](const auto& a, const auto& b) {
        return distance(a.first) < distance(b.first);
    });
    std::vector<double> ratios, times;
    for (const SceneMeasurements::FrameTime* frame : nearest->second) {
        ratios.push_back(frame->measured_ms / model(frame->pixels));
        times.push_back(frame->measured_ms);
    }
    const double ratio = median(ratios);
    if (nearest->first == pixels) {
        if (basis) {
            *basis = fmt::format("this scene's line for {} {} (frames at two sizes or more) x the device's ratio of the "
                                 "presets x {:.2f} as this preset measured here at this size",
                                 method, shape->preset, ratio);
        }
        return model(pixels) * ratio;
    }
    // Measured at another size only: how the preset's time there departs from the model does not say
    // whether the departure is in the frame's fixed part or its part per pixel, and the two carry to
    // another size differently (vct medium in the glossy gallery took 0.60 of the model at 128x128
    // and 1.1 at 32x32; cssm draft at 8 bounces in the furnished room, priced by its 2-bounce line,
    // 0.84 at 128x128 and 2.5 at 32x32). The price is the largest of the three readings (the model;
    // the ratio, as if it were per pixel; the difference, as if it were fixed), so a measurement never
    // lowers the price at a size it was not made at.
    const double measured_ms = median(times);
    const double at_size = model(pixels);
    const double difference = measured_ms - model(nearest->first);
    const double price = std::max({at_size, at_size * ratio, at_size + difference});
    if (basis) {
        *basis = fmt::format("this scene's line for {} {} (frames at two sizes or more) x the device's ratio of the "
                             "presets, raised by this preset's frames at {:.0f} pixels ({:.2f}x, {:+.1f} ms there), "
                             "never lowered",
                             method, shape->preset, nearest->first, ratio, difference);
    }
    return price;
}

}  // namespace

namespace {

// A warm frame's price (predicted_ms without the work a change redoes).
double warm_ms(const PlanningInputs& inputs, const std::string& method, const std::string& preset,
               const methods::KnobValues& knobs, std::string* basis) {
    const auto base = baseline_ms(&inputs.analysis, inputs.device, method, preset, knobs, inputs.width, inputs.height);
    if (!base) return std::numeric_limits<double>::infinity();
    if (inputs.scene && method != "reference") {
        const double pixels = static_cast<double>(inputs.width) * inputs.height;
        if (const auto ms = scene_line_ms(inputs, method, preset, knobs, pixels, basis)) return *ms;
    }
    if (inputs.scene && method == "reference") {
        const int bounces = modelled_bounces(method, knobs);
        if (const auto fit = inputs.scene->reference_time(bounces)) {
            if (basis) {
                *basis = fmt::format("the analysis' times as this scene's {} reference frames measured them: "
                                     "{:.1f} ms + {:.2f}x",
                                     fit->frames, fit->fixed_ms, fit->scale);
                if (fit->bounce_ratio_of >= 0 && std::abs(fit->bounce_ratio - 1.0) >= 0.005) {
                    *basis += fmt::format(", x {:.2f} as its frames of {} bounce{} measured against that", fit->bounce_ratio,
                                          fit->bounce_ratio_of, fit->bounce_ratio_of == 1 ? "" : "s");
                }
            }
            return fit->at(*base);
        }
    }
    // Frames are recorded under their resolved knobs: a plan that names no bounce count has its preset's.
    const int bounces = bounces_knob(knobs).value_or(preset_bounces(method, preset));
    std::optional<double> ratio, scene_ratio;
    if (inputs.scene) {
        const SceneMeasurements::BounceRaise raise = [&](const std::string& measured_preset, int measured) {
            return bounce_raise(inputs.bounce_pricing, method, preset, bounces, measured_preset, measured);
        };
        ratio = inputs.scene->ratio(method, preset, bounces, nullptr, raise);
        if (!ratio && method != "reference") scene_ratio = inputs.scene->scene_ratio();
    }
    // Measured on this scene, the ratio carries its bounces' cost already; else the device's line is at the preset's own count.
    const double bounce_factor =
        method != "reference" && !ratio ? bounce_cost(inputs.bounce_pricing, method, preset, bounces) : 1.0;
    const std::string source = method == "reference" ? "the analysis' times" : "the device's calibration";
    if (basis) {
        *basis = ratio         ? fmt::format("{} x {:.2f} measured on this scene", source, *ratio)
                 : scene_ratio ? fmt::format("{} x {:.2f}, this scene's ratio over other methods", source, *scene_ratio)
                               : source;
        if (bounce_factor > 1.0) *basis += bounce_raise_text(inputs.bounce_pricing, bounce_factor);
    }
    return *base * ratio.value_or(scene_ratio.value_or(1.0)) * bounce_factor;
}

// The same inputs for a frame of `pixels` pixels (prices read the pixel count, not the shape).
PlanningInputs at_pixels(const PlanningInputs& inputs, double pixels) {
    PlanningInputs sized = inputs;
    sized.width = static_cast<int>(std::lround(pixels));
    sized.height = 1;
    return sized;
}

// A change's class in the device's calibration (ChangeCost::beyond_warm): a dimming, a move of the
// lights, or structures built anew. A moved camera has none (its cascades are all it redoes).
int calibration_class(FrameChange change) {
    return change == FrameChange::view          ? -1
           : change == FrameChange::light_power ? 0
           : change == FrameChange::lights      ? 1
                                                : 2;
}

// A plan's `shadow_map_size` and `shadow_cascades` knobs, resolved; nullopt for a method without maps.
std::optional<std::pair<int, int>> map_knobs(const std::string& method, const std::string& preset,
                                             const methods::KnobValues& knobs) {
    const methods::KnobValues resolved = methods::MethodRegistry::builtin().resolve(method, preset, knobs);
    const auto map_size = resolved.find("shadow_map_size");
    if (map_size == resolved.end()) return std::nullopt;
    const auto cascades = resolved.find("shadow_cascades");
    return std::pair{static_cast<int>(map_size->second), cascades == resolved.end() ? 0 : static_cast<int>(cascades->second)};
}

// The shadow maps a frame of the preset draws after `change`: none for a change of power alone; the
// scene's timing of them at the preset's map size and cascades; nullopt where the scene has none.
// After a moved camera (with or without a switch of knobs that keeps the maps' size), the view
// cascades alone, as this scene's frames that redrew them alone took; before any did, as its frames
// that drew every map took (the cascades are a part of those).
std::optional<double> maps_redrawn_ms(const PlanningInputs& inputs, const std::string& method, const std::string& preset,
                                      const methods::KnobValues& knobs, FrameChange change) {
    if (change == FrameChange::light_power) return 0.0;
    const auto maps = map_knobs(method, preset, knobs);
    if (!inputs.scene || !maps) return std::nullopt;
    const auto [size, cascades] = *maps;
    if (change == FrameChange::view || change == FrameChange::knobs_and_view) {
        if (const auto view = inputs.scene->view_cascades_ms(size, cascades)) return view;
    }
    return inputs.scene->shadow_maps_ms(size, cascades);
}

// How many times what the device's calibration priced it this scene's frames of the method redid
// after a change of the same class, less their shadow maps: the median over the method's frames of
// other presets, bounce counts or kinds of the class (frames of the plan's own price it directly),
// never under 1 (the calibration's box is the lightest scene). A scene's frames tell its weight
// where no table can: on the corpus (bench/change_margins.py), cssm's switches redid a median 2.6
// times the calibration's figure on llvmpipe and 2.8 on an H200, up to 11 on both (on the H200,
// the outdoor scene's 1.6 to 2.1, the atrium's 1.6 to 10.9, rising with the preset); the margin in
// llvmpipe's warm frames (kChangeMargin) priced isr ultra's switch in the atrium at 27 ms on the
// H200, where it took 15. Frames whose calibrated figure is under a twentieth of their warm frame
// are left out: the noise of one frame would be their ratio.
// Where the scene has no frame of the class, its frames of the method after other changes (the
// first of each preset builds its structures) scale it: the scene's weight is one for every class.
// On the corpus the lights' moves priced so fell short by a median of -0.18 to 0.08 warm frames on
// llvmpipe and -0.23 to -0.01 on an H200, by more than 0.2 in 30 of 200 frames and 7 of 100 (16 and
// 6 of them direct's, whose maps are most of it), where llvmpipe's margin, the most its corpus fell
// short by, overpriced them by a median of 0.6 to 1.6 warm frames (bench/change_margins.py).
struct SceneScale {
    double scale = 1.0;
    std::size_t frames = 0;
    bool other_classes = false;  // measured after changes of other classes
};
std::optional<SceneScale> scene_scale_of_calibration(const PlanningInputs& inputs, const std::string& method,
                                                     const std::string& preset, int bounces, FrameChange change) {
    if (!inputs.scene) return std::nullopt;
    const std::vector<SceneMeasurements::ChangedFrame> changed = inputs.scene->changed_frames_of(method);
    for (const bool same_class : {true, false}) {
        std::vector<double> scales;
        for (const SceneMeasurements::ChangedFrame& frame : changed) {
            if ((calibration_class(frame.change) == calibration_class(change)) != same_class || !(frame.time.pixels > 0.0)) {
                continue;
            }
            if (frame.preset == preset && frame.bounces == bounces && frame.change == change) continue;
            const auto calibrated = inputs.device.change_cost(method, frame.preset);
            if (!calibrated) continue;
            methods::KnobValues knobs;
            if (frame.bounces >= 0 && bounces_knob(methods::MethodRegistry::builtin().resolve(method, frame.preset, {}))) {
                knobs["bounces"] = frame.bounces;
            }
            const auto maps_ms = maps_redrawn_ms(inputs, method, frame.preset, knobs, frame.change);
            const double warm_there = warm_ms(at_pixels(inputs, frame.time.pixels), method, frame.preset, knobs, nullptr);
            const double priced = calibrated->beyond_warm(frame.change) *
                                  warm_ms(at_pixels(inputs, calibrated->pixels), method, frame.preset, knobs, nullptr);
            if (!maps_ms || !std::isfinite(warm_there) || !std::isfinite(priced) || !(priced >= 0.05 * warm_there)) continue;
            scales.push_back(std::max(0.0, frame.time.measured_ms - warm_there - *maps_ms) / priced);
        }
        if (!scales.empty()) return SceneScale{std::max(1.0, median(scales)), scales.size(), !same_class};
    }
    return std::nullopt;
}

}  // namespace

PlanningInputs::ChangeOf changes_on(const SceneResources& resources, const scene::Camera& camera) {
    const MethodState now = resources.state_now({}, {camera, 0, 0});  // the scene's lights and geometry, hashed once
    // The fit, per map size, cascade count, frame size and whether the knobs draw maps at all (vct's
    // ambient occlusion does not): the planner asks for hundreds of plans.
    using FitKey = std::tuple<int, int, int, int, bool>;
    auto fits = std::make_shared<std::map<FitKey, std::uint64_t>>();
    return [&resources, now, camera, fits](const std::string& method, const std::string& preset,
                                          const methods::KnobValues& knobs, int width, int height) {
        try {
            MethodState next = now;
            next.knobs = methods::MethodRegistry::builtin().resolve(method, preset, knobs);  // as plan_frame does
            if (const SceneAnalysis* analysis = resources.analysis_if_made()) {  // and as the renderer then does
                resolve_scene_knobs(*analysis, methods::MethodRegistry::builtin().find(method), knobs, next.knobs);
            }
            const FitKey key{static_cast<int>(methods::knob_or(next.knobs, "shadow_map_size", 0.0)),
                             static_cast<int>(methods::knob_or(next.knobs, "shadow_cascades", 0.0)), width, height,
                             renders_occlusion(next.knobs)};
            auto fit = fits->find(key);
            if (fit == fits->end()) {
                fit = fits->emplace(key, resources.view_cascades_now(next.knobs, {camera, width, height})).first;
            }
            next.view = fit->second;
            return resources.change_for(method, next);
        } catch (const InputError&) {
            return FrameChange::knobs_and_scene;
        }
    };
}

namespace {

// What a frame of the plan that redoes `change` takes beyond its warm frame, and whence (`source`):
// predicted_ms's pricing (planner.hpp). `maps_kept`: the frame keeps the shadow maps (a switch
// that keeps their size), so none of them is priced here.
double redone_ms(const PlanningInputs& inputs, const std::string& method, const std::string& preset,
                 const methods::KnobValues& knobs, int bounces, FrameChange change, std::string& source,
                 bool maps_kept = false) {
    std::vector<double> beyond_warm;
    if (inputs.scene) {
        for (const SceneMeasurements::FrameTime& frame : inputs.scene->changed_frames(method, preset, bounces, change)) {
            if (!(frame.pixels > 0.0)) continue;
            const double warm_there = warm_ms(at_pixels(inputs, frame.pixels), method, preset, knobs, nullptr);
            if (std::isfinite(warm_there)) beyond_warm.push_back(frame.measured_ms - warm_there);
        }
    }
    double extra = 0.0;
    if (!beyond_warm.empty()) {
        extra = std::max(0.0, median(beyond_warm));
        source = fmt::format("as {} such frame{} of the preset measured here beyond a warm one", beyond_warm.size(),
                             beyond_warm.size() == 1 ? "" : "s");
    } else if (change == FrameChange::view) {
        // The cascades are all a moved camera redoes: as this scene timed them, else at most what a
        // move of the lights costs, which redraws them and more.
        const auto maps = map_knobs(method, preset, knobs);
        const auto alone = inputs.scene && maps ? inputs.scene->view_cascades_ms(maps->first, maps->second) : std::nullopt;
        if (const auto maps_ms = maps_redrawn_ms(inputs, method, preset, knobs, change)) {
            extra = *maps_ms;
            source = alone ? "the view cascades, as this scene's frames redrew them alone"
                           : "at most the shadow maps, cascades among them, as this scene's frames drew them all";
        } else {
            const double bound = change_cost_bound(method, preset, FrameChange::lights);
            extra = bound * warm_ms(at_pixels(inputs, kChangePriorPixels), method, preset, knobs, nullptr);
            source = fmt::format("at most a move of the lights, {:.2g} x its warm frame at 128x128, the most the bench "
                                 "measured",
                                 bound);
        }
    } else {
        // The shadow maps from this scene's own timings of them at the plan's map size, where it has
        // any, and the rest from the device's calibration of such frames as a multiple of a warm
        // one, scaled as the scene's frames of the method's other presets measured it, else plus
        // the margin for a heavier scene; without the scene's maps, or without the device's
        // figure, all from the bench's bound.
        // Knobs that draw no maps (vct's ambient occlusion) have none to redraw.
        maps_kept = maps_kept || renders_occlusion(methods::MethodRegistry::builtin().resolve(method, preset, knobs));
        const bool maps_drawn = change != FrameChange::light_power && !maps_kept;
        const auto maps_ms = maps_kept ? std::optional(0.0) : maps_redrawn_ms(inputs, method, preset, knobs, change);
        const auto calibrated = inputs.device.change_cost(method, preset);
        const std::string maps_text =
            maps_drawn && maps_ms ? fmt::format("{:.1f} ms of shadow maps as this scene's frames drew them, and ", *maps_ms)
                                  : "";
        if (calibrated && maps_ms) {
            const double ratio = calibrated->beyond_warm(change);
            const double at_calibration = ratio * warm_ms(at_pixels(inputs, calibrated->pixels), method, preset, knobs, nullptr);
            const auto scene_scale = scene_scale_of_calibration(inputs, method, preset, bounces, change);
            if (scene_scale) {
                extra = scene_scale->scale * at_calibration + *maps_ms;
                source = fmt::format("{}{:.2g} x {:.2g} x its warm frame at {:.0f} pixels besides: the device's "
                                     "calibration, scaled as {} frame{} of the method{} measured here",
                                     maps_text, scene_scale->scale, ratio, calibrated->pixels, scene_scale->frames,
                                     scene_scale->frames == 1 ? "" : "s",
                                     scene_scale->other_classes ? " after other changes" : "'s other presets");
            } else {
                const double margin = change_margin(method, change);
                extra = at_calibration + margin * warm_ms(at_pixels(inputs, kChangePriorPixels), method, preset, knobs, nullptr) +
                        *maps_ms;
                source = fmt::format("{}{:.2g} x its warm frame at {:.0f} pixels besides, as the device's calibration "
                                     "measured, + {:.2g} x it at 128x128 for a scene heavier than the calibration's",
                                     maps_text, ratio, calibrated->pixels, margin);
            }
        } else {
            const double warm_at_prior = warm_ms(at_pixels(inputs, kChangePriorPixels), method, preset, knobs, nullptr);
            const bool besides_maps = (maps_drawn && maps_ms) || maps_kept;
            const double bound = change_cost_bound(method, preset, change, besides_maps);
            extra = bound * warm_at_prior + (besides_maps ? *maps_ms : 0.0);
            source = fmt::format("{}{:.2g} x its warm frame at 128x128{}, the most the bench measured", maps_text, bound,
                                 besides_maps ? " besides its maps" : "");
        }
    }
    return extra;
}

}  // namespace

double predicted_ms(const PlanningInputs& inputs, const std::string& method, const std::string& preset,
                    const methods::KnobValues& knobs, std::string* basis) {
    const double warm = warm_ms(inputs, method, preset, knobs, basis);
    if (method == "reference" && methods::knob_or(knobs, "denoise", 0.0) != 0.0 && std::isfinite(warm)) {
        // The filter works per pixel, whatever the samples: this scene's filters, else the bench's.
        const auto measured = inputs.scene ? inputs.scene->denoise_ms_per_pixel() : std::nullopt;
        const double filter = measured.value_or(kDenoiseMsPerPixel) * inputs.width * inputs.height;
        if (basis) {
            *basis += fmt::format("; + {:.1f} ms to denoise ({})", filter,
                                  measured ? "as this scene's filters took" : "the bench's filter, per pixel");
        }
        return warm + filter;
    }
    if (!std::isfinite(warm) || !inputs.change || method == "reference") return warm;
    const FrameChange change = inputs.change(method, preset, knobs, inputs.width, inputs.height);
    if (change == FrameChange::none) return warm;
    const int bounces = bounces_knob(knobs).value_or(preset_bounces(method, preset));
    std::string source;
    double extra = 0.0;
    const bool measured =
        inputs.scene && !inputs.scene->changed_frames(method, preset, bounces, change).empty();
    if (change == FrameChange::knobs_and_view && !measured) {
        // Before such frames were measured: a switch that keeps the maps (priced without them), and
        // the cascades it redraws.
        std::string switched, moved;
        extra = redone_ms(inputs, method, preset, knobs, bounces, FrameChange::knobs, switched, /*maps_kept=*/true) +
                redone_ms(inputs, method, preset, knobs, bounces, FrameChange::view, moved);
        source = fmt::format("the switch {}; the cascades {}", switched, moved);
    } else {
        extra = redone_ms(inputs, method, preset, knobs, bounces, change, source);
    }
    if (basis) {
        *basis += fmt::format("; + {:.1f} ms redone: {} ({})", extra,
                              change == FrameChange::view ? "the camera moved since the method's last frame, and with it "
                                                            "the sun's view cascades"
                              : change == FrameChange::light_power ? "a light's colour or intensity changed since the method's last frame"
                              : change == FrameChange::lights  ? "the lights changed since the method's last frame"
                              : change == FrameChange::objects ? "objects moved since the method's last frame"
                              : change == FrameChange::knobs   ? "the method's last frame here had other knobs"
                              : change == FrameChange::knobs_and_view ? "the method's last frame here had other knobs, "
                                                                        "and the camera moved since"
                                                               : "the method's last frame here had other knobs, or none, "
                                                                 "and the scene changed since",
                              source);
    }
    return warm + extra;
}

std::vector<Candidate> candidates(const PlanningInputs& inputs, std::vector<std::string>* ruled_out,
                                  std::optional<double> fill_ms) {
    const auto& registry = methods::MethodRegistry::builtin();
    std::vector<Candidate> all;
    const auto add = [&](const std::string& method, const std::string& preset, const methods::KnobValues& knobs) {
        const ErrorPrediction error = predict_error(inputs.analysis, method, preset, knobs, inputs.scene,
                                                     inputs.own_error_priors());
        if (error.ruled_out) {
            const std::string reason = fmt::format("{} {}: {}", method, preset, *error.ruled_out);
            if (ruled_out && std::find(ruled_out->begin(), ruled_out->end(), reason) == ruled_out->end()) {
                ruled_out->push_back(reason);  // once per preset, whatever its knobs
            }
            return;
        }
        std::map<double, double> scales;
        if (const auto it = inputs.resample_errors.find(method); it != inputs.resample_errors.end()) scales = it->second;
        scales[1.0] = 0.0;
        for (const auto& [scale, resample_error] : scales) {
            Candidate candidate{method, preset, knobs, 0.0, error.rel_mse + resample_error, {}, error.basis, scale};
            if (error.promised_rel_mse > error.rel_mse) candidate.promised_error = error.promised_rel_mse + resample_error;
            PlanningInputs scaled = inputs;
            std::tie(scaled.width, scaled.height) = scaled_size(inputs.width, inputs.height, scale);
            if (inputs.memory && method != "reference") {
                if (const auto refused = inputs.memory(method, preset, knobs, scaled.width, scaled.height)) {
                    const std::string reason = fmt::format("{} {} at {}x{}: {}", method, preset, scaled.width,
                                                           scaled.height, *refused);
                    if (ruled_out && std::find(ruled_out->begin(), ruled_out->end(), reason) == ruled_out->end()) {
                        ruled_out->push_back(reason);
                    }
                    continue;
                }
            }
            if (scale != 1.0) {
                candidate.error_basis +=
                    fmt::format("; upsampling adds {:.3f} (this scene's {} draft frames)", resample_error, method);
            }
            candidate.predicted_ms = predicted_ms(scaled, method, preset, knobs, &candidate.cost_basis);
            if (method != "reference" && std::isfinite(candidate.predicted_ms)) {
                PlanningInputs typical = scaled;
                typical.bounce_pricing = PlanningInputs::BouncePricing::typical;
                std::string typical_basis;
                const double expected = predicted_ms(typical, method, preset, knobs, &typical_basis);
                if (expected < candidate.predicted_ms) {
                    candidate.expected_ms = expected;
                    candidate.cost_basis += fmt::format("; expected {:.1f} ms: {}", expected, typical_basis);
                }
            }
            if (inputs.change && method != "reference") {
                candidate.redoes = inputs.change(method, preset, knobs, scaled.width, scaled.height);
            }
            if (std::isfinite(candidate.predicted_ms)) all.push_back(std::move(candidate));
        }
    };
    for (const std::string& method : registry.names()) {
        if (inputs.method && *inputs.method != method) continue;
        if (method == "reference") {
            for (const int bounces : kReferenceBounces) {
                int within = 0, past = 0;  // the ladder's last step within fill_ms, and its first past it
                for (const int spp : kReferenceSpp) {
                    const std::size_t offered = all.size();
                    add(method, "medium", reference_knobs(spp, bounces));
                    if (!fill_ms || past || all.size() == offered) continue;
                    (all.back().predicted_ms <= *fill_ms ? within : past) = spp;
                }
                // Filled by bisection: its price rises with every sample.
                int below = within, above = past;
                while (within && above - below > 1) {
                    const int spp = (below + above) / 2;
                    const double ms = predicted_ms(inputs, method, "medium", reference_knobs(spp, bounces));
                    (ms <= *fill_ms ? below : above) = spp;
                }
                if (below > within) add(method, "medium", reference_knobs(below, bounces));
                // Denoised, at the samples the denoiser's bound was measured at (OwnErrorPriors::denoised_largest).
                if (inputs.own_error_priors().denoised_largest > 0.0 &&
                    std::min(inputs.width, inputs.height) >= kDenoisedLeastSide) {
                    for (const int spp : kReferenceSpp) {
                        if (spp < kDenoisedLeastSpp || spp > kDenoisedMostSpp) continue;
                        methods::KnobValues knobs = reference_knobs(spp, bounces);
                        knobs["denoise"] = 1;
                        add(method, "medium", knobs);
                    }
                }
            }
            continue;
        }
        for (const std::string& preset : methods::preset_names()) {
            if (method == "cssm") {
                for (const int bounces : kCssmBounces) add(method, preset, {{"bounces", bounces}});
            } else if (method == "vct") {
                for (const int bounces : kVctBounces) add(method, preset, {{"bounces", bounces}});
            } else {
                add(method, preset, {});
            }
        }
    }
    return all;
}

Plan plan(const PlanningInputs& inputs, const Budget& budget) {
    std::vector<std::string> ruled_out;
    const std::vector<Candidate> all = candidates(inputs, &ruled_out, budget.max_ms);
    if (all.empty()) {
        throw InputError(fmt::format("no plan can be predicted for {}: {}", inputs.method.value_or("any method"),
                                     ruled_out.empty() ? "no cost is known" : fmt::format("{}", fmt::join(ruled_out, "; "))));
    }
    Plan chosen = choose(all, budget);
    chosen.ruled_out = std::move(ruled_out);
    chosen.probes = probes(all, chosen.chosen, inputs.scene, &inputs.analysis,
                           methods::reference::Accumulator::prefixes_that_fit(
                               inputs.width, inputs.height, modelled_bounces(chosen.chosen.method, chosen.chosen.knobs)));
    if (auto checks = spot_checks(all, chosen.chosen, budget, inputs)) {
        // A checked plan is compared with the reference as a probe is, where it falls back to it.
        std::erase_if(chosen.probes, [&](const Candidate& probe) {
            return std::any_of(checks->plans.begin(), checks->plans.end(), [&](const Candidate& c) {
                return c.method == probe.method && c.preset == probe.preset;
            });
        });
        chosen.why += fmt::format("; first {} plan{} spot-checked against {} pixel centres of the reference at {} spp: {}",
                                  checks->plans.size(), checks->plans.size() == 1 ? "" : "s", checks->check.pixels,
                                  checks->check.spp, [&] {
                                      std::vector<std::string> labels;
                                      for (const Candidate& c : checks->plans) labels.push_back(describe(c));
                                      return fmt::format("{}", fmt::join(labels, ", "));
                                  }());
        chosen.checks = std::move(checks->plans);
        chosen.spot_check = checks->check;
    }
    return chosen;
}

nlohmann::json plan_json(const Plan& plan) {
    std::vector<std::string> probe_labels;
    for (const Candidate& probe : plan.probes) probe_labels.push_back(describe(probe));
    std::vector<std::string> check_labels;
    for (const Candidate& check : plan.checks) check_labels.push_back(describe(check));
    return {{"method", plan.chosen.method},
            {"preset", plan.chosen.preset},
            {"knobs", plan.chosen.knobs},
            {"scale", plan.chosen.scale},
            {"predicted_ms", plan.chosen.predicted_ms},
            {"expected_ms", expected_ms(plan.chosen)},
            {"predicted_error", plan.chosen.predicted_error},
            {"promised_error", promised_error(plan.chosen)},
            {"redoes", to_string(plan.chosen.redoes)},
            {"meets_budget", plan.meets_budget},
            {"considered", plan.considered},
            {"ruled_out", plan.ruled_out},
            {"probes", probe_labels},
            {"checks", check_labels},
            {"why", plan.why}};
}

}  // namespace bounce::planning
