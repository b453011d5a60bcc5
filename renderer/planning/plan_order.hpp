#pragma once
// How plans are ordered and named, and the reference plans' knobs: choose(), the candidates and the
// planner's probes and checks share these.

#include "renderer/planning/planner.hpp"

#include <string>

namespace bounce::planning {

// The bounce counts the reference is offered at.
inline constexpr int kReferenceBounces[] = {0, 1, 2, 3, 4, 6, 8, 12};
// A reference plan's knobs: through pixel centres, as the raster methods shade.
methods::KnobValues reference_knobs(int spp, int bounces);

// "cssm medium bounces=2", "reference spp=12 bounces=1", with " at 1/2 size, upsampled" when scaled.
std::string describe(const Candidate& candidate);
// By predicted time, then predicted error.
bool faster(const Candidate& a, const Candidate& b);
// Its typical price where its bound is not (Candidate::expected_ms), else the bound.
double expected_ms(const Candidate& candidate);
// What a target error is judged by: the larger of Candidate::promised_error and predicted_error.
double promised_error(const Candidate& candidate);
// By predicted error, then predicted time.
bool more_accurate(const Candidate& a, const Candidate& b);
// A reference plan whose frame is filtered (`denoise` 1): no frame is compared with it.
bool denoised(const Candidate& candidate);

}  // namespace bounce::planning
