#version 450 core
// Emitted radiance seen directly; coverage goes to alpha.
#include "common/shared_layout.h"

layout(binding = BOUNCE_UNIT_GBUFFER_POSITION) uniform sampler2D u_gbuffer_position;
layout(binding = BOUNCE_UNIT_GBUFFER_EMISSIVE) uniform sampler2D u_gbuffer_emissive;

out vec4 out_radiance;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    float coverage = texelFetch(u_gbuffer_position, pixel, 0).w;
    out_radiance = vec4(texelFetch(u_gbuffer_emissive, pixel, 0).rgb * coverage, coverage);
}
