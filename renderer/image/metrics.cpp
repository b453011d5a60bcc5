#include "renderer/image/metrics.hpp"

#include "renderer/base/error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace bounce::image {
namespace {
bool finite_rgb(const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

// The median of channel `c` of `frame` over pixel (x, y)'s 3x3 neighbourhood (clamped at the edges),
// of its finite values; the pixel's own value must be finite.
float neighbourhood_median(const Frame& frame, int x, int y, int c) {
    float window[9];
    int n = 0;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const int sx = std::clamp(x + dx, 0, frame.width - 1), sy = std::clamp(y + dy, 0, frame.height - 1);
            const float value = frame.rgba[(static_cast<std::size_t>(sy) * frame.width + sx) * 4 + c];
            if (std::isfinite(value)) window[n++] = value;
        }
    }
    std::nth_element(window, window + n / 2, window + n);
    return window[n / 2];
}
}  // namespace

ErrorMetrics compare(const Frame& test, const Frame& reference, Weight weight) {
    BOUNCE_CHECK(test.width == reference.width && test.height == reference.height,
                 "cannot compare a {}x{} image with a {}x{} reference", test.width, test.height, reference.width,
                 reference.height);
    const std::size_t pixels = static_cast<std::size_t>(test.width) * static_cast<std::size_t>(test.height);
    BOUNCE_CHECK(test.rgba.size() == pixels * 4 && reference.rgba.size() == pixels * 4,
                 "frame buffers do not match their {}x{} size", test.width, test.height);
    ErrorMetrics metrics;
    double rel = 0.0, squared = 0.0, sum_test = 0.0, sum_reference = 0.0, peak = 0.0;
    std::size_t counted = 0;
    for (std::size_t i = 0; i < pixels; ++i) {
        const float* t = &test.rgba[i * 4];
        const float* r = &reference.rgba[i * 4];
        const bool t_ok = finite_rgb(t), r_ok = finite_rgb(r);
        metrics.non_finite_test += !t_ok;
        metrics.non_finite_reference += !r_ok;
        if (!t_ok || !r_ok) continue;
        for (int c = 0; c < 3; ++c) {
            const double d = static_cast<double>(t[c]) - r[c];
            const double w = weight == Weight::own_value
                                 ? r[c]
                                 : neighbourhood_median(reference, static_cast<int>(i % static_cast<std::size_t>(reference.width)),
                                                        static_cast<int>(i / static_cast<std::size_t>(reference.width)), c);
            rel += d * d / (w * w + 0.01);
            squared += d * d;
            sum_test += t[c];
            sum_reference += r[c];
            peak = std::max(peak, static_cast<double>(r[c]));
        }
        ++counted;
    }
    const double values = static_cast<double>(counted) * 3.0;
    if (counted == 0) return metrics;
    metrics.rel_mse = rel / values;
    const double mse = squared / values;
    metrics.rmse = std::sqrt(mse);
    metrics.psnr_db = mse > 0.0 ? 10.0 * std::log10(std::max(peak * peak, 1e-30) / mse)
                                : std::numeric_limits<double>::infinity();
    metrics.mean_test = sum_test / values;
    metrics.mean_reference = sum_reference / values;
    return metrics;
}

double rel_mse_difference_noise(const Frame& a, const Frame& b, const Frame& reference,
                                const std::vector<float>& luminance_variance) {
    const std::size_t pixels = static_cast<std::size_t>(reference.width) * static_cast<std::size_t>(reference.height);
    BOUNCE_CHECK(a.width == reference.width && a.height == reference.height && b.width == reference.width &&
                     b.height == reference.height && a.rgba.size() == pixels * 4 && b.rgba.size() == pixels * 4 &&
                     reference.rgba.size() == pixels * 4 && luminance_variance.size() == pixels,
                 "cannot weigh the noise of a {}x{} reference against {}x{} and {}x{} frames and {} variances",
                 reference.width, reference.height, a.width, a.height, b.width, b.height, luminance_variance.size());
    double variance = 0.0;
    std::size_t counted = 0;
    for (std::size_t i = 0; i < pixels; ++i) {
        const float *pa = &a.rgba[i * 4], *pb = &b.rgba[i * 4], *r = &reference.rgba[i * 4];
        if (!finite_rgb(pa) || !finite_rgb(pb) || !finite_rgb(r)) continue;
        ++counted;
        const float v = luminance_variance[i];
        const double deviation = std::isfinite(v) ? std::sqrt(std::max(0.0f, v)) : 0.0;
        const double lum = luminance(glm::vec3(r[0], r[1], r[2]));
        double term = 0.0;  // the pixel's sum over channels of the difference's coefficient times sigma_c
        for (int c = 0; c < 3; ++c) {
            const double w = static_cast<double>(r[c]) * r[c] + 0.01;
            const double sigma = lum > 0.0 ? deviation * r[c] / lum : deviation;
            const double ta = pa[c], tb = pb[c], rc = r[c];
            term += (tb - ta) / w * (1.0 + rc * (ta + tb - 2.0 * rc) / w) * sigma;
        }
        variance += term * term;
    }
    if (counted == 0) return 0.0;
    return 2.0 * std::sqrt(variance) / (static_cast<double>(counted) * 3.0);
}

CrossEstimate cross_rel_mse(const Frame& test, const Frame& a, const Frame& b, const Frame& weights) {
    const std::size_t pixels = static_cast<std::size_t>(test.width) * static_cast<std::size_t>(test.height);
    const auto same_size = [&](const Frame& frame) {
        return frame.width == test.width && frame.height == test.height && frame.rgba.size() == pixels * 4;
    };
    BOUNCE_CHECK(test.rgba.size() == pixels * 4 && same_size(a) && same_size(b) && same_size(weights),
                 "cannot estimate the error of a {}x{} frame from {}x{} and {}x{} draws weighed by a {}x{} frame", test.width,
                 test.height, a.width, a.height, b.width, b.height, weights.width, weights.height);
    CrossEstimate estimate;
    double sum = 0.0, sum_of_squares = 0.0;
    for (std::size_t i = 0; i < pixels; ++i) {
        const float *t = &test.rgba[i * 4], *pa = &a.rgba[i * 4], *pb = &b.rgba[i * 4], *w = &weights.rgba[i * 4];
        if (!finite_rgb(t) || !finite_rgb(pa) || !finite_rgb(pb) || !finite_rgb(w)) continue;
        const int x = static_cast<int>(i % static_cast<std::size_t>(test.width));
        const int y = static_cast<int>(i / static_cast<std::size_t>(test.width));
        double pixel = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double weight = neighbourhood_median(weights, x, y, c);
            pixel += (static_cast<double>(t[c]) - pa[c]) * (static_cast<double>(t[c]) - pb[c]) / (weight * weight + 0.01);
        }
        pixel /= 3.0;
        sum += pixel;
        sum_of_squares += pixel * pixel;
        ++estimate.pixels;
    }
    const double n = static_cast<double>(estimate.pixels);
    estimate.rel_mse = estimate.pixels > 0 ? sum / n : 0.0;
    if (estimate.pixels < 2) {  // one value or none has no spread to tell the estimate's error by
        estimate.standard_error = std::numeric_limits<double>::infinity();
        return estimate;
    }
    const double variance = std::max(0.0, sum_of_squares - sum * sum / n) / (n - 1.0);
    estimate.standard_error = std::sqrt(variance / n);
    return estimate;
}

Leak leak(const Frame& test, const Frame& reference) {
    BOUNCE_CHECK(test.width == reference.width && test.height == reference.height &&
                     test.rgba.size() == reference.rgba.size(),
                 "cannot measure leakage of a {}x{} image against a {}x{} reference", test.width, test.height,
                 reference.width, reference.height);
    Leak result;
    double dark = 0.0, lit = 0.0;
    for (std::size_t i = 0; i + 3 < reference.rgba.size(); i += 4) {
        const float* r = &reference.rgba[i];
        const float* t = &test.rgba[i];
        if (!(r[3] > 0.0f) || !finite_rgb(r) || !finite_rgb(t)) continue;
        if (r[0] == 0.0f && r[1] == 0.0f && r[2] == 0.0f) {
            dark += (t[0] + t[1] + t[2]) / 3.0;
            ++result.dark_pixels;
        } else {
            lit += (r[0] + r[1] + r[2]) / 3.0;
            ++result.lit_pixels;
        }
    }
    if (result.dark_pixels > 0 && result.lit_pixels > 0 && lit > 0.0) {
        result.ratio = (dark / static_cast<double>(result.dark_pixels)) / (lit / static_cast<double>(result.lit_pixels));
    }
    return result;
}

}  // namespace bounce::image
