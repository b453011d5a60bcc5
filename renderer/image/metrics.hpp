// The one error metric of the project (design note D1 in docs/references.md): relMSE, RMSE, PSNR
// and non-finite counts, over linear HDR RGB. Tests and bench/quality use this implementation and no other.
#pragma once

#include "renderer/image/frame.hpp"

#include <cstddef>
#include <vector>

namespace bounce::image {

struct ErrorMetrics {
    double rel_mse = 0.0;  // mean over pixels and RGB of (t - r)^2 / (r^2 + 0.01)
    double rmse = 0.0;     // sqrt(mean over pixels and RGB of (t - r)^2)
    double psnr_db = 0.0;  // 10 log10(peak^2 / MSE), peak = the reference's largest RGB value
    double mean_test = 0.0;       // mean RGB radiance of the test image
    double mean_reference = 0.0;  // of the reference
    std::size_t non_finite_test = 0;  // pixels with a NaN or Inf channel (excluded from the means)
    std::size_t non_finite_reference = 0;
};

// What weighs a difference in relMSE: the reference's own value (the metric as defined above), or
// the median of the reference's channel over the pixel's 3x3 neighbourhood (its finite values). The
// second is for two noisy frames of one view (planning::FrameComparisons::calibrate_noise): a rare
// bright path in the reference raises its own pixel's weight exactly where the difference is largest,
// and a neighbourhood's median does not follow one pixel's outlier.
enum class Weight { own_value, neighbourhood_median };

// Compares `test` with `reference`; throws Error if their sizes differ. Pixels where either image
// is non-finite are counted and left out of the error sums.
ErrorMetrics compare(const Frame& test, const Frame& reference, Weight weight = Weight::own_value);

// How far the reference's own noise moves the difference of two frames' relMSEs against it: the
// standard deviation of compare(b, r).rel_mse - compare(a, r).rel_mse over the reference's draws.
// With r = truth + n, to first order in n each value moves that difference by
// -2 (b - a) / w (1 + r (a + b - 2r) / w) n / M, w = r^2 + 0.01 (the weight moves with r too), over
// the M values compared. n's variance per pixel is `luminance_variance` (of the pixel's mean, as the
// path tracer reports it), each channel its share r_c / luminance of the luminance's deviation, the
// three perfectly correlated (the same paths carry them). A difference of the relMSEs beyond two of
// these is the frames', not the reference's draw. Throws Error on a size mismatch; pixels a frame
// holds non-finite are left out as compare() leaves them, and a non-finite variance counts as none.
double rel_mse_difference_noise(const Frame& a, const Frame& b, const Frame& reference,
                                const std::vector<float>& luminance_variance);

// The relMSE of `test` against the expected image of two independent noisy draws of it, `a` and
// `b` (reference frames of other seeds, or the disjoint samples of one seed: planning::
// FrameComparisons), without their noise: the mean over values of (t - a)(t - b) / (w^2 + 0.01).
// Where the draws are unbiased and independent, (t - a)(t - b) has the expectation (t - r)^2 for the
// image r they both estimate: the noise of each multiplies only the other's or the test's
// difference, which average to 0. Subtracting a modelled noise from relMSE(test, a) instead is only
// as good as the model (on the bench corpus the noise added 0.6 to 2.5 times its statistic by scene).
// The weight w is the median of `weights` over the value's 3x3 neighbourhood (Weight::
// neighbourhood_median), a frame of the draws (their union): a pixel's own noisy value would correlate
// with the products it weighs, and the median of nine values, the pixel's among them, follows it far
// less (it still weighs a highlight the draws mostly miss as dark: bench/cross_estimate). `standard_error` is the spread of the pixels' means over the
// three channels (one value each: the same paths carry them) over the square root of their count:
// how far the estimate may be from its expectation by the draws' noise and the test's error's
// own unevenness. Pixels non-finite in any frame are left out; with fewer than two left, the
// standard error is infinite (none: the estimate is 0). Throws Error on a size mismatch.
struct CrossEstimate {
    double rel_mse = 0.0;
    double standard_error = 0.0;
    std::size_t pixels = 0;  // counted
};
CrossEstimate cross_rel_mse(const Frame& test, const Frame& a, const Frame& b, const Frame& weights);

// Light leaking into regions the reference proves dark: the test's mean RGB radiance over the
// pixels where the reference has geometry (alpha > 0) and exactly zero radiance, relative to the
// reference's mean over its lit pixels. 0 when either set is empty. Throws Error on a size mismatch.
struct Leak {
    double ratio = 0.0;
    std::size_t dark_pixels = 0;
    std::size_t lit_pixels = 0;
};
Leak leak(const Frame& test, const Frame& reference);

}  // namespace bounce::image
