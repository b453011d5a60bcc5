// Display transform: exposure, a tone curve, then sRGB encoding. Its CPU twin, for frames made on
// CPU threads, is image::make_display_image (renderer/image/tone.cpp): change both together.
#include "common/shared_layout.h"

vec3 tone_curve(vec3 x, int curve) {
    x = max(x, vec3(0.0));
    if (curve == BOUNCE_TONE_REINHARD) return x / (1.0 + x);
    if (curve == BOUNCE_TONE_ACES) {
        // Narkowicz's fit of the ACES filmic reference rendering transform.
        return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    }
    return clamp(x, 0.0, 1.0);
}

vec3 linear_to_srgb(vec3 c) {
    vec3 low = c * 12.92;
    vec3 high = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
    return mix(high, low, lessThanEqual(c, vec3(0.0031308)));
}

// The 8-bit code a display value takes, as the value that code stands for: rounded to nearest as the
// CPU twin rounds (std::lround). A framebuffer write converts float to unorm with the device's own
// rounding, which need not be to nearest (an H200 stored 2% of channels one code lower); the exact
// centre of a code is stored as that code by any conversion within half a code.
vec3 quantize_unorm8(vec3 c) { return floor(clamp(c, 0.0, 1.0) * 255.0 + 0.5) / 255.0; }
