#version 450 core
// Adds the accumulated indirect light to the frame, scaled as the lights' power is over the solution's.
#include "common/shared_layout.h"
#include "common/math.glsl"

layout(binding = BOUNCE_UNIT_HDR_INPUT) uniform sampler2D u_indirect;
uniform float u_indirect_scale;

out vec4 out_radiance;

void main() {
    out_radiance = vec4(finite_or_zero(u_indirect_scale * texelFetch(u_indirect, ivec2(gl_FragCoord.xy), 0).rgb), 0.0);
}
