#version 450 core
// Jittered frames (§4.5): the running mean of the final gathers since the view, lights or objects
// last changed: mean += (frame - mean) / k.
layout(local_size_x = 8, local_size_y = 8) in;
#include "common/shared_layout.h"

layout(binding = BOUNCE_UNIT_HDR_INPUT) uniform sampler2D u_frame;
layout(binding = 0, rgba32f) uniform image2D u_mean;

uniform ivec2 u_size;
uniform float u_weight;  // 1 / k

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, u_size))) return;
    vec4 mean = imageLoad(u_mean, pixel);
    vec4 frame = texelFetch(u_frame, pixel, 0);
    imageStore(u_mean, pixel, mean + (frame - mean) * u_weight);
}
