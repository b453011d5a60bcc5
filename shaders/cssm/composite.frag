#version 450 core
// Adds the accumulated indirect light to the frame.
#include "common/shared_layout.h"

layout(binding = BOUNCE_UNIT_HDR_INPUT) uniform sampler2D u_indirect;

out vec4 out_radiance;

void main() {
    out_radiance = vec4(texelFetch(u_indirect, ivec2(gl_FragCoord.xy), 0).rgb, 0.0);
}
