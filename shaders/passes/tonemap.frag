#version 450 core
// Linear HDR radiance to display-referred sRGB: 2^exposure, tone curve, sRGB transfer.
#include "common/shared_layout.h"
#include "common/math.glsl"
#include "common/tonemap.glsl"

layout(binding = BOUNCE_UNIT_HDR_INPUT) uniform sampler2D u_hdr;
uniform float u_exposure_scale;
uniform int u_tone_curve;

out vec4 out_color;

void main() {
    vec3 radiance = finite_or_zero(texelFetch(u_hdr, ivec2(gl_FragCoord.xy), 0).rgb);
    vec3 display = linear_to_srgb(tone_curve(radiance * u_exposure_scale, u_tone_curve));
    out_color = vec4(quantize_unorm8(display), 1.0);
}
