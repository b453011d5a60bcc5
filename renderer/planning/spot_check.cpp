#include "renderer/planning/spot_check.hpp"

#include "renderer/base/error.hpp"
#include "renderer/planning/error_model.hpp"
#include "renderer/scene_analysis.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <random>

namespace bounce::planning {

std::vector<int> spot_pixels(int width, int height, int count, std::uint64_t seed) {
    BOUNCE_CHECK(width > 0 && height > 0 && count > 0, "{} spot pixels of a {}x{} frame", count, width, height);
    const long long all = static_cast<long long>(width) * height;
    std::vector<int> pixels;
    if (count >= all) {
        pixels.resize(static_cast<std::size_t>(all));
        for (long long i = 0; i < all; ++i) pixels[static_cast<std::size_t>(i)] = static_cast<int>(i);
        return pixels;
    }
    // A grid of about `count` cells shaped like the frame.
    const double side = std::sqrt(static_cast<double>(all) / count);
    const int columns = std::clamp(static_cast<int>(std::lround(width / side)), 1, width);
    const int rows = std::clamp(static_cast<int>(std::lround(static_cast<double>(count) / columns)), 1, height);
    std::mt19937_64 random(seed);
    pixels.reserve(static_cast<std::size_t>(columns) * rows);
    for (int row = 0; row < rows; ++row) {
        const int y0 = row * height / rows, y1 = (row + 1) * height / rows;
        for (int column = 0; column < columns; ++column) {
            const int x0 = column * width / columns, x1 = (column + 1) * width / columns;
            const int x = x0 + static_cast<int>(random() % static_cast<std::uint64_t>(x1 - x0));
            const int y = y0 + static_cast<int>(random() % static_cast<std::uint64_t>(y1 - y0));
            pixels.push_back(y * width + x);
        }
    }
    return pixels;
}

namespace {

// 1 / (r^2 + 0.01) from an estimate r^ of variance v: X = r^2 - v + 0.01 is unbiased, but 1/X is
// convex and over-weighs where r^ is noisy (E[1/X] ~ (1 + Var X / X^2) / X, Var X = 4 r^2 v + 2 v^2).
// Less that second-order term it is nearly unbiased while Var X / X^2 is small: in the furnished
// room at a noise of 0.094, cssm draft read 0.065 for 0.049 with 1/X and 0.053 with the correction.
// Past a quarter the expansion fails (at a noise of 0.1 per pixel, normal, the corrected weights
// read a fifth of the relMSE), and 1/X, on the safe side, is kept.
double spot_weight(double r, double v) {
    const double x = std::max(r * r - v, 0.0) + 0.01;
    const double relative_variance = (4.0 * r * r * v + 2.0 * v * v) / (x * x);
    if (relative_variance > 0.25) return 1.0 / x;
    return (1.0 - relative_variance) / x;
}

}  // namespace

SpotEstimate estimate(const image::Frame& frame, const methods::reference::PixelEstimates& reference,
                      double stopped_error) {
    for (int half = 0; half < 2; ++half) {
        BOUNCE_CHECK(reference.mean[half].size() == reference.pixels.size() &&
                         reference.variance[half].size() == reference.pixels.size(),
                     "a spot reference of {} pixels with {} means and {} variances", reference.pixels.size(),
                     reference.mean[half].size(), reference.variance[half].size());
    }
    const std::size_t frame_pixels = static_cast<std::size_t>(frame.width) * static_cast<std::size_t>(frame.height);
    BOUNCE_CHECK(frame.rgba.size() == frame_pixels * 4, "a {}x{} frame of {} values", frame.width, frame.height,
                 frame.rgba.size());
    SpotEstimate result;
    result.samples = reference.samples;
    std::vector<double> terms;
    terms.reserve(reference.pixels.size());
    double noise = 0.0, noise_variance = 0.0;
    for (std::size_t i = 0; i < reference.pixels.size(); ++i) {
        const std::size_t pixel = static_cast<std::size_t>(reference.pixels[i]);
        BOUNCE_CHECK(pixel < frame_pixels, "spot pixel {} outside a {}x{} frame", pixel, frame.width, frame.height);
        const float* g = &frame.rgba[pixel * 4];
        if (!std::isfinite(g[0]) || !std::isfinite(g[1]) || !std::isfinite(g[2])) {
            ++result.non_finite;
            continue;
        }
        // Per channel, as image::compare weighs it: (g - r)^2 / (r^2 + 0.01). One half's mean r^ makes
        // the difference, and E[(g - r^)^2] is (g - r)^2 plus its variance v, taken out; the other
        // half weighs it (spot_weight). Drawn from the same samples, the weight would be small exactly
        // where a rare bright path made the difference large: in the furnished room at 35 samples that
        // read cssm draft's 0.065 as 0.033. Each half takes each part, and the two are averaged. The
        // term's own noise, were r^ normal: Var (g - r^)^2 = 4 (g - r)^2 v + 2 v^2, the channels taken
        // as fully correlated (the mean of their deviations, squared).
        double term = 0.0, pixel_noise = 0.0, variance = 0.0;
        for (int half = 0; half < 2; ++half) {
            const glm::dvec3& r = reference.mean[half][i];
            const glm::dvec3& v = reference.variance[half][i];
            const glm::dvec3& weigher = reference.mean[1 - half][i];
            const glm::dvec3& weigher_variance = reference.variance[1 - half][i];
            double deviation = 0.0;
            for (int c = 0; c < 3; ++c) {
                const double d = static_cast<double>(g[c]) - r[c];
                const double weight = spot_weight(weigher[c], weigher_variance[c]);
                term += (d * d - v[c]) * weight / 6.0;
                pixel_noise += v[c] * weight / 6.0;
                deviation += std::sqrt(4.0 * std::max(d * d - v[c], 0.0) * v[c] + 2.0 * v[c] * v[c]) * weight / 3.0;
            }
            variance += deviation * deviation / 4.0;  // of the mean of two independent halves
        }
        terms.push_back(term);
        noise += pixel_noise;
        noise_variance += variance;
    }
    result.pixels = static_cast<int>(terms.size());
    if (terms.size() < 2) {
        result.standard_error = result.bound = std::numeric_limits<double>::infinity();
        return result;
    }
    const double n = static_cast<double>(terms.size());
    double mean = 0.0;
    for (const double t : terms) mean += t;
    mean /= n;
    double spread = 0.0;
    for (const double t : terms) spread += (t - mean) * (t - mean);
    spread /= n - 1.0;
    noise_variance /= n;
    // The terms' spread is the pixels' own plus the noise's. The pixels' part shrinks by the share of
    // the frame drawn (none where every pixel is); the noise's does not. Taken as a simple random
    // sample: stratified pixels vary less between draws, so this is on the safe side.
    const double frame_pixels_count = static_cast<double>(frame_pixels);
    const double own_spread = std::max(spread - noise_variance, 0.0) * std::max(1.0 - n / frame_pixels_count, 0.0);
    result.standard_error = std::sqrt((own_spread + std::min(noise_variance, spread)) / n);
    result.rel_mse = std::max(mean, 0.0);
    result.noise = noise / n;
    const double upper = result.rel_mse + kSpotConfidence * result.standard_error;
    result.bound = std::pow(std::sqrt(upper) + std::sqrt(std::max(stopped_error, 0.0)), 2.0);
    return result;
}

SpotReference trace_spot_reference(const scene::Scene& scene, const RenderRequest& frame, const SpotCheck& check,
                                   const std::atomic<bool>* cancelled) {
    BOUNCE_CHECK(check.pixels > 0 && check.spp > 0 && check.bounces >= 0, "a spot check of {} pixels at {} spp, {} bounces",
                 check.pixels, check.spp, check.bounces);
    const auto start = std::chrono::steady_clock::now();
    const methods::reference::PathTracer tracer(scene);
    methods::reference::PathTracerSettings settings;
    settings.max_bounces = check.bounces;
    settings.pixel_jitter = false;  // as the raster methods shade, and as the planner's reference plans trace
    settings.seed = 1;
    SpotReference reference;
    const scene::Camera camera = camera_for(scene, frame);
    reference.estimates = tracer.trace_pixels(camera, frame.width, frame.height,
                                              spot_pixels(frame.width, frame.height, check.pixels), check.spp, settings,
                                              cancelled);
    // Noise falls as 1/samples: the samples that bring it to max_noise, within the cap.
    const double noise = noise_of(reference.estimates);
    const int wanted = static_cast<int>(std::min(std::ceil(check.spp * noise / std::max(check.max_noise, 1e-9)),
                                                 static_cast<double>(kSpotMostSamples) * check.spp));
    if (wanted > check.spp) {
        const int more = std::max(wanted - check.spp, 4);
        merge(reference.estimates, tracer.trace_pixels(camera, frame.width, frame.height, reference.estimates.pixels,
                                                       more, settings, cancelled, check.spp));
    }
    reference.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return reference;
}

double noise_of(const methods::reference::PixelEstimates& reference) {
    if (reference.pixels.empty()) return 0.0;
    double noise = 0.0;
    for (std::size_t i = 0; i < reference.pixels.size(); ++i) {
        for (int half = 0; half < 2; ++half) {
            for (int c = 0; c < 3; ++c) {
                noise += reference.variance[half][i][c] *
                         spot_weight(reference.mean[1 - half][i][c], reference.variance[1 - half][i][c]) / 6.0;
            }
        }
    }
    return noise / static_cast<double>(reference.pixels.size());
}

void record_spot_check(SceneMeasurements& measurements, const std::vector<double>& stopped_error, const std::string& method,
                       const std::string& preset, const methods::KnobValues& knobs, const SpotCheck& check,
                       const SpotEstimate& estimate, std::optional<std::uint64_t> view) {
    const int bounces = modelled_bounces(method, knobs);
    if (bounces > check.bounces || estimate.non_finite > 0 || estimate.pixels == 0) return;
    const double lacking = BounceEnergy::at(stopped_error, bounces) - BounceEnergy::at(stopped_error, check.bounces);
    // As FrameComparisons drops a comparison where missing bounces make over half of the relMSE: the
    // own part would be mostly what they lack, and where the frame's error meets that light the two
    // do not add.
    if (lacking > 0.5 * estimate.rel_mse) return;
    const double own = estimate.rel_mse + kSpotConfidence * estimate.standard_error - std::max(lacking, 0.0);
    if (view) {
        // Against (nearly) every bounce: the later light is in the reading, and a cross term of 0 keeps
        // the view's comparisons from adding theirs to it (SceneMeasurements::record_own_estimate).
        measurements.record_own_estimate(method, preset, bounces, std::max(own, 0.0), *view,
                                         kSpotConfidence * estimate.standard_error + std::max(lacking, 0.0),
                                         /*unsure=*/0.0, /*cross=*/0.0);
    } else {
        measurements.record_own_error(method, preset, bounces, std::max(own, 0.0));
    }
    measurements.record_compared(method, preset, bounces);
}

bool ruled_out_by_measurements(const SceneMeasurements& measured, const SceneAnalysis& analysis, const std::string& method,
                               const std::string& preset, const methods::KnobValues& knobs, double target) {
    if (!measured.own_error(method, preset, modelled_bounces(method, knobs))) return false;
    return predict_error(analysis, method, preset, knobs, &measured).promised_rel_mse > target;
}

std::string describe(const SpotCheck& check, const SpotEstimate& estimate) {
    return fmt::format("a spot check of {} pixel centres at {} spp, {} bounces: relMSE {:.4f} +- {:.4f} (noise {:.4f} "
                       "taken out){}, at most {:.4f} against every bounce",
                       estimate.pixels, estimate.samples, check.bounces, estimate.rel_mse, estimate.standard_error,
                       estimate.noise, estimate.non_finite ? fmt::format(", {} pixels not finite", estimate.non_finite) : "",
                       estimate.bound);
}

}  // namespace bounce::planning
