// The display transform applied to PNG and JPEG output: exposure in stops, then a tone curve,
// then sRGB encoding. EXR output stays linear and untouched.
#pragma once

#include "renderer/image/frame.hpp"

#include <string>
#include <string_view>

namespace bounce::image {

enum class ToneCurve { none = 0, reinhard = 1, aces = 2 };  // matches BOUNCE_TONE_* in shared_layout.h

// "none", "reinhard" or "aces"; throws InputError otherwise.
ToneCurve parse_tone_curve(std::string_view name);
std::string_view tone_curve_name(ToneCurve curve);

struct DisplayTransform {
    float exposure = 0.0f;  // stops: radiance is scaled by 2^exposure
    ToneCurve curve = ToneCurve::aces;
};

// The CPU twin of the tone-map pass (shaders/passes/tonemap.frag, shaders/common/tonemap.glsl):
// fills frame.display_rgba8 from frame.rgba, non-finite radiance as black, alpha 255. Frames made
// on CPU threads (the path-traced reference) go through this one; the GPU tests hold the two to
// one 8-bit step of each other.
void make_display_image(Frame& frame, const DisplayTransform& transform);

}  // namespace bounce::image
