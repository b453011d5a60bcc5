// The extremes matrix: the Cornell box pushed to the limits of materials, geometry, light, frame
// shape, scale and intensity, and the invariants every method must keep there. tests/gpu checks
// the invariants case by case; bench/extremes writes the matrix to docs/benchmarks.md.
//
// Invariants, per case and method:
// - finite: no NaN or Inf in the frame;
// - energy: the frame's mean radiance is not above the reference's beyond its noise (four
//   standard errors, measured from two seeds) and an allowance (energy_allowance: half-float
//   rounding, 2^-10 of the mean, as the G-buffer stores albedo and normals in 16-bit floats; isr's
//   measured gather bias). isr models one bounce without indirect visibility, so its reference is
//   the path tracer's one-bounce frame without it;
// - error: the relMSE against the reference is not above `direct`'s (which leaves all indirect
//   light out): a method that cannot model an effect must leave it out, not add a wrong one.
// A (case, method) pair may carry a documented exception instead: its reason is printed with it.
#pragma once

#include "renderer/image/frame.hpp"
#include "renderer/methods/knobs.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene/scene.hpp"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace bounce::bench {

struct ExtremeCase {
    std::string name;   // "material/roughness_0"
    std::string what;   // one line for the table
    scene::Scene scene;
    int width = 32, height = 32;
    std::map<std::string, methods::KnobValues> knobs;  // per method, on top of its `high`
    int reference_spp = 256;
};

std::vector<ExtremeCase> extreme_cases();

// The path-traced truth of a case through pixel centres (as raster methods shade; a 1x1 frame is
// its centre's ray, not the pixel's area): two seeds averaged, with the standard error of its mean.
struct ExtremeTruth {
    image::Frame frame;
    double mean = 0.0;
    double mean_error = 0.0;
};
ExtremeTruth extreme_truth(const ExtremeCase& extreme, int bounces, bool indirect_visibility = true);

struct ExtremeVerdict {
    std::string method;
    bool finite = true;
    double rel_mse = 0.0;
    double direct_rel_mse = 0.0;
    double mean = 0.0;
    double energy_bound = 0.0;  // the reference's mean plus its allowance
    bool energy_ok = true;
    bool error_ok = true;
    std::string exception;  // a documented reason when a bound does not hold by design; empty otherwise
    bool within_bounds() const { return finite && ((energy_ok && error_ok) || !exception.empty()); }
};

// Renders `method` (preset high) on the case and judges it. `truth` is the 4-bounce reference,
// `isr_truth` the one-bounce reference without indirect visibility (used for isr's energy).
ExtremeVerdict judge(Renderer& renderer, const ExtremeCase& extreme, const std::string& method,
                     const ExtremeTruth& truth, const ExtremeTruth& isr_truth, double direct_rel_mse);

// The energy allowance beyond the reference's noise, as a fraction of its mean: half-float rounding
// (2^-10) for every method, and isr's measured gather bias (0.5%) for isr.
double energy_allowance(const std::string& method);

// The documented exception for a case and method, if any.
std::optional<std::string> extreme_exception(const std::string& case_name, const std::string& method);

inline constexpr int kExtremeReferenceBounces = 4;

}  // namespace bounce::bench
