#include "renderer/base/error.hpp"
#include "renderer/image/metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace bounce::image {
namespace {

Frame constant(int w, int h, float value) {
    Frame frame;
    frame.width = w;
    frame.height = h;
    frame.rgba.assign(static_cast<std::size_t>(w) * h * 4, value);
    return frame;
}

TEST(Metrics, IdenticalImagesHaveNoError) {
    const Frame a = constant(4, 3, 0.5f);
    const ErrorMetrics m = compare(a, a);
    EXPECT_EQ(m.rel_mse, 0.0);
    EXPECT_EQ(m.rmse, 0.0);
    EXPECT_TRUE(std::isinf(m.psnr_db));
    EXPECT_DOUBLE_EQ(m.mean_test, 0.5);
}

TEST(Metrics, MatchesTheDefinition) {
    // Reference 1.0 everywhere, test 1.1: relMSE = 0.01 / (1 + 0.01), RMSE = 0.1, PSNR = 20 dB.
    const Frame reference = constant(5, 2, 1.0f);
    const Frame test = constant(5, 2, 1.1f);
    const ErrorMetrics m = compare(test, reference);
    EXPECT_NEAR(m.rel_mse, 0.01 / 1.01, 1e-6);
    EXPECT_NEAR(m.rmse, 0.1, 1e-6);
    EXPECT_NEAR(m.psnr_db, 20.0, 1e-4);
    // Alpha is ignored; one channel off by 0.3 on a black reference: 0.09 / 0.01 / 3 per pixel.
    Frame black = constant(1, 1, 0.0f);
    Frame off = black;
    off.rgba[1] = 0.3f;
    off.rgba[3] = 7.0f;
    EXPECT_NEAR(compare(off, black).rel_mse, 0.09 / 0.01 / 3.0, 1e-6);
}

// A rare bright path in a frame of few samples is in the frame of more samples of its seed too, a
// quarter as bright at four times the samples: weighed by the reference's own value the difference
// there counts 6^2 / (3^2 + 0.01), where the converged value 1 says 6^2 / 1.01; weighed by the
// neighbourhood's median it counts as the converged value would weigh it. A non-finite neighbour
// is left out of the median; a non-finite pixel out of the sums, as with the own value.
TEST(Metrics, ANeighbourhoodMedianWeightDoesNotFollowOnePixelsOutlier) {
    Frame fewer = constant(8, 8, 1.0f), more = constant(8, 8, 1.0f);
    const std::size_t outlier = 4 * (3 * 8 + 5);
    for (int c = 0; c < 3; ++c) {
        fewer.rgba[outlier + c] = 9.0f;
        more.rgba[outlier + c] = 3.0f;
    }
    EXPECT_NEAR(compare(fewer, more).rel_mse, 36.0 / 9.01 / 64.0, 1e-7);
    EXPECT_NEAR(compare(fewer, more, Weight::neighbourhood_median).rel_mse, 36.0 / 1.01 / 64.0, 1e-7);
    more.rgba[4 * (2 * 8 + 5)] = std::numeric_limits<float>::infinity();  // a neighbour above, red
    fewer.rgba[0] = std::numeric_limits<float>::quiet_NaN();
    const ErrorMetrics weighed = compare(fewer, more, Weight::neighbourhood_median);
    EXPECT_NEAR(weighed.rel_mse, 36.0 / 1.01 / 62.0, 1e-7);  // the two non-finite pixels left out
    EXPECT_EQ(weighed.non_finite_test, 1u);
    EXPECT_EQ(weighed.non_finite_reference, 1u);
    // At a frame's edges and in a one-pixel frame the neighbourhood is clamped.
    EXPECT_NEAR(compare(constant(1, 1, 2.0f), constant(1, 1, 1.0f), Weight::neighbourhood_median).rel_mse, 1.0 / 1.01, 1e-7);
}

TEST(Metrics, NonFinitePixelsAreCountedAndLeftOut) {
    const Frame reference = constant(2, 1, 1.0f);
    Frame test = reference;
    test.rgba[0] = std::numeric_limits<float>::quiet_NaN();
    test.rgba[4] = std::numeric_limits<float>::infinity();
    const ErrorMetrics m = compare(test, reference);
    EXPECT_EQ(m.non_finite_test, 2u);
    EXPECT_EQ(m.non_finite_reference, 0u);
    EXPECT_EQ(m.rel_mse, 0.0);
}

// Two dark pixels of the reference get 0.1 and 0.3 (mean 0.2); its two lit pixels average 2:
// ratio 0.1. A pixel without geometry is ignored.
TEST(Metrics, LeakIsDarkPixelMeanOverLitPixelMean) {
    Frame reference = constant(5, 1, 0.0f), test = constant(5, 1, 0.0f);
    auto set = [](Frame& frame, int x, float value, float alpha) {
        for (int c = 0; c < 3; ++c) frame.rgba[static_cast<std::size_t>(x) * 4 + c] = value;
        frame.rgba[static_cast<std::size_t>(x) * 4 + 3] = alpha;
    };
    set(reference, 0, 0.0f, 1.0f);
    set(reference, 1, 0.0f, 1.0f);
    set(reference, 2, 1.0f, 1.0f);
    set(reference, 3, 3.0f, 1.0f);
    set(reference, 4, 0.0f, 0.0f);
    set(test, 0, 0.1f, 1.0f);
    set(test, 1, 0.3f, 1.0f);
    set(test, 4, 50.0f, 1.0f);
    const Leak leak = image::leak(test, reference);
    EXPECT_EQ(leak.dark_pixels, 2u);
    EXPECT_EQ(leak.lit_pixels, 2u);
    EXPECT_NEAR(leak.ratio, 0.1, 1e-7);
    EXPECT_EQ(image::leak(reference, reference).ratio, 0.0);
}

TEST(Metrics, SizeMismatchIsAnError) {
    EXPECT_THROW(compare(constant(2, 2, 0.0f), constant(2, 3, 0.0f)), Error);
}

// The reference's noise moves two frames' relMSEs against it together: what it moves their
// difference by is predicted from the frames and the reference's variance alone. The noise is drawn
// as the path tracer's is modelled (one deviate per pixel, each channel its share of the
// luminance's deviation), 1% of the luminance, so terms of second order in it are negligible. Over
// 4000 draws the measured standard deviation has a standard error of 1/sqrt(2 * 4000) = 1.1%: 5% is
// over four of them. Two pairs: frames scattered either side of the truth, and frames both too dark
// by one factor in every channel, where the weight's own change with the reference carries most of
// the difference (the prediction without it is 3 times too large) and the channels' correlation
// the rest (independent channels would give up to 1.7 times too little).
TEST(Metrics, TheReferencesNoiseInADifferenceOfRelMsesIsPredicted) {
    const int w = 24, h = 16;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    Frame truth = constant(w, h, 0.0f), scattered_a = truth, scattered_b = truth, dark_a = truth, dark_b = truth;
    std::vector<float> variance(static_cast<std::size_t>(w) * h);
    std::vector<double> lum(variance.size());
    for (std::size_t i = 0; i < variance.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            const std::size_t v = i * 4 + c;
            truth.rgba[v] = 0.05f + uniform(rng) * (c == 0 ? 2.0f : 1.0f);  // coloured, some near 0.01's scale
            scattered_a.rgba[v] = truth.rgba[v] * (0.8f + 0.4f * uniform(rng));
            scattered_b.rgba[v] = truth.rgba[v] * (0.8f + 0.4f * uniform(rng));
            dark_a.rgba[v] = truth.rgba[v] * 0.6f;
            dark_b.rgba[v] = truth.rgba[v] * 0.7f;
        }
        lum[i] = luminance(glm::vec3(truth.rgba[i * 4], truth.rgba[i * 4 + 1], truth.rgba[i * 4 + 2]));
        variance[i] = static_cast<float>(std::pow(0.01 * lum[i], 2.0));
    }
    std::normal_distribution<double> normal;
    const auto measured = [&](const Frame& a, const Frame& b) {
        const int draws = 4000;
        double sum = 0.0, sum2 = 0.0;
        for (int draw = 0; draw < draws; ++draw) {
            Frame reference = truth;
            for (std::size_t i = 0; i < variance.size(); ++i) {
                const double z = normal(rng) * std::sqrt(variance[i]);
                for (int c = 0; c < 3; ++c) {
                    reference.rgba[i * 4 + c] += static_cast<float>(z * truth.rgba[i * 4 + c] / lum[i]);
                }
            }
            const double difference = compare(b, reference).rel_mse - compare(a, reference).rel_mse;
            sum += difference;
            sum2 += difference * difference;
        }
        const double mean = sum / draws;
        return std::sqrt(sum2 / draws - mean * mean);
    };
    for (const auto& [a, b] : {std::pair{&scattered_a, &scattered_b}, std::pair{&dark_a, &dark_b}}) {
        const double predicted = rel_mse_difference_noise(*a, *b, truth, variance);
        ASSERT_GT(predicted, 0.0);
        const double measure = measured(*a, *b);
        EXPECT_NEAR(measure / predicted, 1.0, 0.05) << "predicted " << predicted << ", measured " << measure;
    }
    // Frames that agree differ by nothing, whatever the reference's noise.
    EXPECT_EQ(rel_mse_difference_noise(dark_a, dark_a, truth, variance), 0.0);
    EXPECT_THROW(rel_mse_difference_noise(dark_a, dark_b, truth, std::vector<float>(3)), Error);
    EXPECT_THROW(rel_mse_difference_noise(constant(h, w, 0.0f), dark_b, truth, variance), Error);
}

// Hostile values: a pixel a frame holds non-finite is left out, as compare() leaves it out (it is not
// counted in the mean either), and a non-finite variance counts as none; the result stays finite.
TEST(Metrics, TheNoiseOfADifferenceLeavesOutWhatIsNotFinite) {
    Frame reference = constant(2, 1, 0.5f), a = constant(2, 1, 0.4f), b = constant(2, 1, 0.6f);
    const std::vector<float> variance = {1e-4f, 1e-4f};
    const double both = rel_mse_difference_noise(a, b, reference, variance);
    ASSERT_GT(both, 0.0);
    // Pixel 1 not finite in a: pixel 0's term alone, over 3 values instead of 6.
    Frame broken = a;
    broken.rgba[4] = std::numeric_limits<float>::quiet_NaN();
    Frame agreeing = b;  // pixel 1 the same in both frames: no term, but still counted
    for (int c = 0; c < 3; ++c) agreeing.rgba[4 + c] = a.rgba[4 + c];
    const double one = rel_mse_difference_noise(a, agreeing, reference, variance);
    EXPECT_NEAR(rel_mse_difference_noise(broken, b, reference, variance), 2.0 * one, 1e-12);
    EXPECT_NEAR(one, both / std::sqrt(2.0), 1e-12);
    // An infinite variance counts as none; a black reference pixel takes the luminance's deviation.
    EXPECT_NEAR(rel_mse_difference_noise(a, b, reference, {1e-4f, std::numeric_limits<float>::infinity()}), one, 1e-12);
    const double black = rel_mse_difference_noise(a, b, constant(2, 1, 0.0f), variance);
    EXPECT_TRUE(std::isfinite(black) && black > 0.0);
}


// A frame of `value` plus noise uniform in [-spread, spread] per value (the same on each channel of
// a pixel, as one path carries all three), drawn from `seed`.
Frame noisy(int size, float value, float spread, unsigned seed) {
    Frame frame = constant(size, size, value);
    std::mt19937 draw(seed);
    std::uniform_real_distribution<float> noise(-spread, spread);
    for (std::size_t i = 0; i < frame.rgba.size(); i += 4) {
        const float n = noise(draw);
        for (int c = 0; c < 3; ++c) frame.rgba[i + c] += n;
    }
    return frame;
}

// Test 1.2 against an image of 1.0: relMSE 0.04 / 1.01. Two draws of the image with noise of
// variance 0.6^2 / 3 = 0.12 per value: against either, the relMSE holds the noise too (about 0.16
// more, four times the frame's own), and the products of the two differences average the noise out.
// Weighed by the image itself the estimate's expectation is the relMSE exactly: within four standard
// errors. Weighed by the draws' union (its neighbourhood's median, noisy itself), 1 / (w^2 + 0.01)
// averages above its value at the mean (its curvature times the median's variance, about 0.011 here:
// +3%): within 5% and four standard errors. Over twenty pairs of draws the estimates spread as their
// standard errors say, within 50% (the spread of twenty draws is itself uncertain by about 16%: three
// times that).
TEST(Metrics, TheCrossEstimateOfTwoIndependentDrawsLeavesTheirNoiseOut) {
    const Frame image = constant(48, 48, 1.0f), test = constant(48, 48, 1.2f);
    const double truth = 0.04 / 1.01;
    std::vector<double> estimates;
    double standard_errors = 0.0;
    for (unsigned pair = 0; pair < 20; ++pair) {
        const Frame a = noisy(48, 1.0f, 0.6f, 2 * pair + 1), b = noisy(48, 1.0f, 0.6f, 2 * pair + 2);
        EXPECT_GT(compare(test, a).rel_mse, 3.0 * truth);
        const CrossEstimate exact_weights = cross_rel_mse(test, a, b, image);
        EXPECT_EQ(exact_weights.pixels, 48u * 48u);
        EXPECT_NEAR(exact_weights.rel_mse, truth, 4.0 * exact_weights.standard_error) << pair;
        EXPECT_LT(exact_weights.standard_error, 0.15 * truth);
        Frame both = a;
        for (std::size_t i = 0; i < both.rgba.size(); ++i) both.rgba[i] = 0.5f * (a.rgba[i] + b.rgba[i]);
        const CrossEstimate estimate = cross_rel_mse(test, a, b, both);
        EXPECT_NEAR(estimate.rel_mse, truth, 0.05 * truth + 4.0 * estimate.standard_error) << pair;
        estimates.push_back(exact_weights.rel_mse);
        standard_errors += exact_weights.standard_error / 20.0;
    }
    double mean = 0.0, spread = 0.0;
    for (const double e : estimates) mean += e / 20.0;
    for (const double e : estimates) spread += (e - mean) * (e - mean) / 19.0;
    EXPECT_NEAR(std::sqrt(spread), standard_errors, 0.5 * standard_errors);
}

TEST(Metrics, TheCrossEstimateLeavesOutWhatIsNotFiniteAndRefusesOtherSizes) {
    Frame a = constant(4, 4, 1.0f), b = a, test = constant(4, 4, 1.1f);
    a.rgba[0] = std::numeric_limits<float>::quiet_NaN();
    b.rgba[4 * 5 + 1] = std::numeric_limits<float>::infinity();
    const CrossEstimate estimate = cross_rel_mse(test, a, b, constant(4, 4, 1.0f));
    EXPECT_EQ(estimate.pixels, 14u);
    EXPECT_NEAR(estimate.rel_mse, 0.01 / 1.01, 1e-6);
    EXPECT_NEAR(estimate.standard_error, 0.0, 1e-9);
    Frame nothing = constant(1, 1, 1.0f);
    nothing.rgba[2] = std::numeric_limits<float>::quiet_NaN();
    const CrossEstimate none = cross_rel_mse(constant(1, 1, 1.0f), nothing, nothing, nothing);
    EXPECT_EQ(none.pixels, 0u);
    EXPECT_TRUE(std::isinf(none.standard_error));
    const CrossEstimate one = cross_rel_mse(constant(1, 1, 1.1f), constant(1, 1, 1.0f), constant(1, 1, 1.0f), constant(1, 1, 1.0f));
    EXPECT_EQ(one.pixels, 1u);
    EXPECT_NEAR(one.rel_mse, 0.01 / 1.01, 1e-6);
    EXPECT_TRUE(std::isinf(one.standard_error));
    EXPECT_THROW(cross_rel_mse(test, a, constant(4, 3, 1.0f), a), Error);
    EXPECT_THROW(cross_rel_mse(test, a, b, constant(3, 4, 1.0f)), Error);
}

}  // namespace
}  // namespace bounce::image
