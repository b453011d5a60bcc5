// What frames cost on this device, for the planner (planner.hpp): per GPU method and preset, a line
// of milliseconds against pixels, measured once on the built-in Cornell box (calibration.hpp) and
// kept in the cache folder under the renderer's name; and per scene, how its measured frames
// compare with that line, since a scene's size and light change what each method costs.
#pragma once

#include "renderer/frame_change.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>
#include <algorithm>

namespace bounce::planning {

// The median of measured values (of frame-time ratios, of own errors); `values` must not be empty.
double median(std::vector<double> values);

struct CostLine {
    double fixed_ms = 0.0;
    double per_megapixel_ms = 0.0;
    double at(double pixels) const { return fixed_ms + per_megapixel_ms * pixels * 1e-6; }
    // The line through two measured frames, neither part below zero.
    static CostLine through(double pixels_a, double ms_a, double pixels_b, double ms_b);
};

// What a frame that redoes a change's work (frame_change.hpp) cost on this device beyond a warm
// frame of its preset at the same size, as a multiple of that warm frame, less the shadow maps it
// drew: measured by the calibration on its scene. Devices differ most here: on llvmpipe cssm's bake
// cost under its warm frame at 128x128 (0.38 to 0.87 of it on the bench corpus), on an H200 3.5 to 6
// times it, where warm frames are cheap and a bake's passes are many. The shadow maps are left out:
// they follow a scene's triangles and lights, and a scene prices them from its own timings.
struct ChangeCost {
    double pixels = 0.0;        // the frame size it was measured at
    double light_power = 0.0;   // every light dimmed: no map
    double lights = 0.0;        // every light moved
    double rebuild = 0.0;       // the method's structures built anew after the lights moved (knobs_and_scene)
    // The multiple for `change`: a moved object and other knobs as a rebuild, which redoes the lights'
    // work too (never priced under it); 0 for none.
    double beyond_warm(FrameChange change) const;
};

class DeviceCosts {
public:
    // Bumped whenever methods change what a preset costs: cached models of older versions are dropped.
    // 4: change costs. 5: vct scales its injected light where every light dimmed alike. 6: vct's
    // light-view maps are not drawn again for a change of power. 7: nor isr's (its VPL tree is
    // rebuilt over them). 8: cssm scales its atlas solution where every light dimmed alike. 9: cssm
    // samples each texel's direct light at 16 points, and double-sided surfaces have texels on both sides.
    // 10: cssm's nodes send light by their lobes, so nodes that face away in the mean gather too.
    // 11: isr low to ultra make imperfect shadow maps. 12: isr's maps splat 8192 points at medium,
    // 16384 at high and ultra (its frames after a change cost more). 13: isr keeps its imperfect
    // shadow maps where only the lights' intensities changed.
    static constexpr int kVersion = 13;

    DeviceCosts() = default;
    explicit DeviceCosts(std::string renderer) : renderer_(std::move(renderer)) {}

    const std::string& renderer() const { return renderer_; }
    double calibration_ms = 0.0;  // how long the calibration took

    void set(const std::string& method, const std::string& preset, CostLine line);
    std::optional<CostLine> line(const std::string& method, const std::string& preset) const;
    bool empty() const { return lines_.empty(); }
    void set_change_cost(const std::string& method, const std::string& preset, ChangeCost cost);
    // nullopt for a model that did not measure it (a made-up one, or a method left out).
    std::optional<ChangeCost> change_cost(const std::string& method, const std::string& preset) const;

    nlohmann::json to_json() const;
    // Throws Error naming what is wrong with the document.
    static DeviceCosts from_json(const nlohmann::json& document);

    // The file a model is cached in under `cache_dir`, named by the renderer string's hash.
    static std::filesystem::path cache_path(const std::filesystem::path& cache_dir, const std::string& renderer);
    // nullopt (and a log line) when the file is absent, unreadable, of another version or renderer.
    static std::optional<DeviceCosts> load(const std::filesystem::path& file, const std::string& renderer);
    // Writes a temporary file and renames it over `file`, so a reader never sees half of it.
    void save(const std::filesystem::path& file) const;

private:
    std::string renderer_;
    std::map<std::pair<std::string, std::string>, CostLine> lines_;
    std::map<std::pair<std::string, std::string>, ChangeCost> changes_;
};

// What frames of one scene measured: their times, against what the device's lines predicted and at
// their sizes, and the reference's noise. Thread-safe: GPU frames are recorded on the render thread,
// CPU frames on the CPU pool.
class SceneMeasurements {
public:
    struct FrameTime {
        double pixels = 0.0;  // 0 where the size is not known
        double measured_ms = 0.0;
        double baseline_ms = 0.0;  // what the device's line (or the analysis, for the reference) predicted
    };

    // `bounces`: the frame's `bounces` knob, or -1 for methods without one. `change`: what the frame
    // redid (frame_change.hpp); only warm frames (none) are what ratio(), frames() and the lines read.
    void record(const std::string& method, const std::string& preset, int bounces, double measured_ms, double predicted_ms,
                double pixels = 0.0, FrameChange change = FrameChange::none);
    // The last frames at this preset and bounce count that redid what `change` redoes, at every size
    // (the planner prices that work as their time beyond a warm frame's).
    std::vector<FrameTime> changed_frames(const std::string& method, const std::string& preset, int bounces,
                                          FrameChange change) const;
    // The last frames of every preset and bounce count of `method` that redid some change's work:
    // how much more than the device's calibration this scene's changes redo (planner.cpp).
    struct ChangedFrame {
        std::string preset;
        int bounces = -1;
        FrameChange change = FrameChange::none;
        FrameTime time;
    };
    std::vector<ChangedFrame> changed_frames_of(const std::string& method) const;
    // What frames measured at `measured_bounces` of a preset are raised by to price another count
    // (bench_bounds.hpp: a bound on what more bounces cost; 1 where the count asked is not more).
    using BounceRaise = std::function<double(const std::string& preset, int measured_bounces)>;
    // The median of the last frames at this preset and bounce count; else, raised by `raise`, of this
    // preset's frames at the nearest count measured below it (the fewest above it where none is
    // below); else the median of the method's other presets, each raised; nullopt when no frame of
    // the method was measured on the scene. Without `raise`, frames of other counts count as they
    // are. `exact`, when given, says whether frames at this preset and bounce count were measured.
    std::optional<double> ratio(const std::string& method, const std::string& preset, int bounces = -1,
                                bool* exact = nullptr, const BounceRaise& raise = {}) const;
    // The reference's frame time on this scene as an affine function of the analysis' prediction:
    // a fixed part per frame (dispatching tiles to the threads, merging them, keeping the frames of
    // fewer bounces) and a part proportional to the samples. Through every reference frame measured
    // here, by least squares on relative residuals (each frame counts as much as any other,
    // whatever its length), where their predictions span kReferenceSpan or more; nullopt otherwise.
    // One ratio prices a one-sample frame as a thousandth of a thousand-sample one, where on 16
    // threads both carry the same few milliseconds of fixed cost.
    //
    // With `bounces`, the fit is then raised or lowered by what frames of that bounce count measured
    // against it (the median of their ratios), or, where none were, by the larger of the nearest
    // counts' below and above it: the analysis prices every vertex of a path alike, and in the atrium
    // frames of 6 bounces took 1.12 to 1.34 times what the fit through every count priced, and frames
    // of none 0.7 times.
    struct AffineTime {
        double fixed_ms = 0.0;
        double scale = 1.0;  // measured ms per predicted ms of samples
        int frames = 0;
        double bounce_ratio = 1.0;  // what frames of the bounce count measured against the fit
        int bounce_ratio_of = -1;   // the bounce count whose frames gave it (-1: none)
        double at(double baseline_ms) const { return (fixed_ms + scale * baseline_ms) * bounce_ratio; }
    };
    std::optional<AffineTime> reference_time(std::optional<int> bounces = std::nullopt) const;
    static constexpr double kReferenceSpan = 4.0;
    // The median over every GPU method measured here: how much heavier the scene is than the
    // calibration scene, for GPU methods not yet measured on it. nullopt when none was.
    std::optional<double> scene_ratio() const;

    // The frames kept at this preset and bounce count, at every size.
    std::vector<FrameTime> frames(const std::string& method, const std::string& preset, int bounces) const;
    // This scene's own cost line at a preset and bounce count: through the median times at the
    // smallest and the largest size measured, where those are at least kLineSpan apart in pixels. A
    // scene's size changes the fixed part of a frame's cost (geometry, structures) and its per-pixel
    // part differently: a line of the device's, scaled by one ratio, misprices the sizes it was not
    // measured at. nullopt until frames of two such sizes were measured.
    std::optional<CostLine> line(const std::string& method, const std::string& preset, int bounces) const;
    struct PresetLine {
        std::string preset;
        int bounces = -1;
        CostLine line;
    };
    // A line of `method` on this scene at any preset (line()), `preset`'s own first: the shape that
    // the method's other presets take on this scene (planner.cpp). nullopt when none was measured.
    std::optional<PresetLine> method_line(const std::string& method, const std::string& preset) const;
    // Sizes this far apart in pixels, at least: a line through two measured times is extrapolated,
    // and 10% of noise in each swings its fixed part by a quarter at 4x apart, by a ninth at 8x. Frames
    // of 64 pixels a side and more have their quarter-size draft (16x); smaller ones keep the ratio.
    static constexpr double kLineSpan = 8.0;

    // The shadow_maps pass of GPU frames that drew maps, by map size and view cascades (the
    // `shadow_map_size` and `shadow_cascades` knobs): every GPU method draws the same maps of the
    // scene's lights, and on a scene of many triangles they are most of what a change of the lights
    // costs (the furnished room's, 262K triangles and lamps in cube maps, took 1.5 s at 2048 texels
    // on llvmpipe, where a warm frame of direct took 7 ms). shadow_maps_ms(): the largest of the last
    // kKept at the size (a frame that reused some maps drew less); else the nearest size measured
    // below it, scaled by the ratio of texels, else the nearest above as measured (never lowered);
    // nullopt when none was measured with that many cascades (they fill their texels with what the
    // camera sees, where the scene's map is mostly empty: 613 against 54 ms in the bench street).
    void record_shadow_maps(int size, int cascades, double ms);
    std::optional<double> shadow_maps_ms(int size, int cascades) const;
    // The same of the shadow_view_cascades pass: frames whose camera moved, which redrew the view
    // cascades alone (FrameChange::view).
    void record_view_cascades(int size, int cascades, double ms);
    std::optional<double> view_cascades_ms(int size, int cascades) const;

    // The reference's denoiser (`denoise` 1), per pixel: its frames' filter time (the reference
    // method's `denoise_ms`), which their recorded time leaves out; denoise_ms_per_pixel(): the
    // largest of the last kKept, nullopt before any.
    void record_denoise(double ms, double pixels);
    std::optional<double> denoise_ms_per_pixel() const;

    // A reference frame's noise per sample (methods::reference::noise_per_sample) at a bounce count,
    // as a multiple of what the analysis measured there: over a whole frame's samples it meets rare
    // bright paths that the analysis' few samples miss. Of `spp` samples: a frame's statistic weighs
    // each pixel's variance by its own neighbourhood's luminance, which few samples read low where
    // a few paths carry the light, so it reads high at few samples (1.25 to 1.30 of the analysis' at
    // 4 samples in the atrium and the furnished room, 0.96 to 1.04 at 64; bench/reference_noise).
    void record_noise(int bounces, double noise_ratio, double spp);
    // The ratio of the frames of most samples recorded at the nearest bounce count (the largest of
    // them; the higher count of two as near); nullopt when none.
    std::optional<double> noise_ratio(int bounces) const;
    // Every bounce count's ratio recorded (for logs and the bench).
    std::map<int, double> noise_ratios() const;

    // How much relMSE a reference frame's noise statistic (noise_per_sample over its samples) makes
    // against a converged frame, on this scene: measured from two reference frames of one view
    // (comparisons.hpp, calibrate_noise). The statistic is a luminance variance over a neighbourhood's
    // value; relMSE weighs each channel by its own value, and the two part on scenes of coloured or
    // high-contrast light (the foliage's frames measure about a half of it). `scale` is for a
    // reference's predicted error (noise_scale(): the largest of the last kKept, as a target error is
    // a promise); `compared_scale` for the noise a comparison takes out of a GPU frame's relMSE
    // against a noisy reference frame, which weighs it by that frame's own values
    // (least_noise_scale(): the smallest of the last kKept, since taking out too much would promise
    // the frame less error than it has). nullopt until measured.
    void record_noise_scale(double scale, double compared_scale);
    std::optional<double> noise_scale() const;
    std::optional<double> least_noise_scale() const;

    // A GPU frame's own error on this scene: its relMSE against a reference frame of the same view,
    // less the reference's noise and the bounces one has and the other lacks (comparisons.hpp).
    // `bound_of_view` marks a bound on the own error of that view's frame, from a reference lacking
    // light the frame has (FrameComparisons::compare): every such bound holds, so of several of one
    // view only the least is kept. The furnished room's cssm draft at 8 bounces, 0.046 against the
    // truth, read 0.184 against a 3-bounce reference and 0.067 against a 6-bounce one, and the
    // first had kept it out of every budget it met (bench/results/gpu/nvidia-h200). Other records,
    // estimates on the safe side, are each kept.
    // `unsure`: what a target's promise adds back (OwnError::promised): the reference's noise that the
    // comparison took out by its statistic, which need not have been in this frame's relMSE.
    void record_own_error(const std::string& method, const std::string& preset, int bounces, double rel_mse,
                          std::optional<std::uint64_t> bound_of_view = std::nullopt, double unsure = 0.0);
    // An estimate of the own error of view `view`'s frame from a comparison that took `taken_out` out
    // of its relMSE (the reference's expected noise, the light of bounces one lacks, the cross term
    // continued past the deeper frame: each uncertain by about its size). A view's frame is one
    // frame, and of its estimates the one that took out least stands: in the street isr draft read
    // 0.0155 against a 16-sample reference (0.0085 taken out), then 0.0037 against a quieter one of
    // 4 bounces (0.0011), and measures 0.0134 whole, where the bounces it lacks make 0.010; kept, the
    // first priced out the cheapest plan that met 0.02 (the planner's took 2.7 times as long). It supersedes the view's bounds, which tell less.
    // `cross`: the part of rel_mse that a deeper frame's later light measured (Comparison::cross_term
    // and cross_beyond), where the reference was the bounce prefix of one. The view's frame meets
    // that light whichever reference measures the rest, so an estimate without it takes the view's
    // (and gives its own to one without): in the street isr draft read 0.0017 against the 1-bounce
    // prefix of a 4-bounce reference (-0.0091 of cross term in it), then 0.0106 against a quieter
    // reference of one bounce alone, which, standing alone, promised 0.0206 for 0.02 where the frame
    // measures 0.0113 and priced the cheapest plan that met it out. A reading against every bounce
    // (a spot check's) passes a cross of 0: it holds the later light already.
    void record_own_estimate(const std::string& method, const std::string& preset, int bounces, double rel_mse,
                             std::uint64_t view, double taken_out, double unsure = 0.0,
                             std::optional<double> cross = std::nullopt);
    struct OwnError {
        double rel_mse = 0.0;
        int frames = 0;      // comparisons it is the largest of
        bool exact = false;  // measured at this bounce count (else at the preset's other counts)
        // The largest of the same comparisons with the noise each took out by the statistic counted
        // back: what a target error is promised. The noise a reference adds to a frame's relMSE is
        // its statistic only on average over scenes and frames; where the frame errs most it may add
        // less (in the glossy box vct draft at 2 bounces read 0.062 against the 2-bounce prefix of a
        // 192-sample reference of 6 bounces, 0.0697 once the cross term was added and the 0.0077 of
        // noise expected taken out, was predicted 0.096 for a target of 0.1 and measured 0.103: the
        // noise had added next to none). A time budget ranks by rel_mse, the estimate.
        double promised = 0.0;
    };
    // The largest of the last comparisons at this preset and bounce count, else at this preset's
    // larger bounce counts (the own error is net of the bounces' light, but each bounce a method
    // computes adds its own error: in the glossy gallery cssm low erred 0.018 at 2 bounces and 0.037
    // at 8, so fewer bounces do not tell more); nullopt when the preset has none such. At its own
    // bounce count it may be negative (the frame's error fills in light the bounces lack:
    // comparisons.hpp); carried from larger counts it is at least 0.
    std::optional<OwnError> own_error(const std::string& method, const std::string& preset, int bounces) const;
    // Every preset of `method` with an own error measured here at `at_least_bounces` or more, with
    // its largest (with `promised`, its largest promise: OwnError::promised).
    std::map<std::string, double> own_errors(const std::string& method, int at_least_bounces = 0,
                                             bool promised = false) const;
    // Whether a frame of the preset (at `bounces`, or at any count) was compared with a reference
    // frame here, whether or not that told its own error (the planner probes a preset once per scene
    // and bounce count it probes), unless the light of the bounces it lacked drowned it (a reference
    // of its own bounce count can still tell).
    void record_compared(const std::string& method, const std::string& preset, int bounces);
    bool compared(const std::string& method, const std::string& preset) const;
    bool compared(const std::string& method, const std::string& preset, int bounces) const;

    static constexpr std::size_t kKept = 5;  // frames kept per preset and size: a median of them ignores one slow frame

private:
    using Key = std::tuple<std::string, std::string, int>;
    std::optional<CostLine> line_locked(const Key& key) const;
    mutable std::mutex mutex_;
    std::map<Key, std::map<double, std::deque<FrameTime>>> frames_;  // warm, by pixels
    std::map<std::pair<Key, FrameChange>, std::deque<FrameTime>> changed_frames_;
    struct NoiseRatio {
        double ratio = 0.0, spp = 0.0;
    };
    std::map<int, NoiseRatio> noise_;
    // By whether the cascades alone were drawn, the cascades, and the map size.
    using MapsKey = std::tuple<bool, int, int>;
    std::map<MapsKey, std::deque<double>> shadow_maps_;
    void record_maps(MapsKey key, double ms);
    std::optional<double> maps_ms(bool view_only, int cascades, int size) const;
    std::deque<double> noise_scales_, compared_noise_scales_;
    std::deque<double> denoise_ms_per_pixel_;
    struct RecordedOwnError {
        double rel_mse = 0.0;
        std::optional<std::uint64_t> view;  // the view's frame it is of, where known
        bool bound = false;                 // a bound (record_own_error with a view), not an estimate
        double taken_out = 0.0;             // an estimate's: what its comparison took out
        double unsure = 0.0;                // what a promise adds back (record_own_error, record_own_estimate)
        std::optional<double> cross;        // an estimate's part from a deeper frame's light (record_own_estimate)
    };
    std::map<std::tuple<std::string, std::string, int>, std::deque<RecordedOwnError>> own_errors_;
    std::set<std::tuple<std::string, std::string, int>> compared_;
};

}  // namespace bounce::planning
