#version 450 core
// One level of the eye-space min-max pyramid (paper Fig. 2b-c): level 0 from the G-buffer, each
// coarser level from the 2x2 texels below it. Depth is view depth; background pixels count as
// uncovered and leave the extremes alone.
layout(local_size_x = 8, local_size_y = 8) in;
#include "common/shared_layout.h"
#include "isr/multires.glsl"

layout(binding = BOUNCE_UNIT_GBUFFER_POSITION) uniform sampler2D u_gbuffer_position;
layout(binding = BOUNCE_UNIT_GBUFFER_NORMAL) uniform sampler2D u_gbuffer_normal;
layout(binding = ISR_IMAGE_DEPTH, rgba32f) uniform image2D u_depth;
layout(binding = ISR_IMAGE_NORMAL_MIN, rgba16f) uniform image2D u_normal_min;
layout(binding = ISR_IMAGE_NORMAL_MAX, rgba16f) uniform image2D u_normal_max;

uniform int u_level;
uniform mat4 u_view;

const float FAR = 3.0e38;

void main() {
    ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(texel, u_level_size[u_level]))) return;
    vec4 depth = vec4(FAR, -FAR, 0.0, 0.0);
    vec3 normal_min = vec3(2.0), normal_max = vec3(-2.0);
    if (u_level == 0) {
        vec4 position = texelFetch(u_gbuffer_position, texel, 0);
        if (position.w != 0.0) {
            float z = -(u_view * vec4(position.xyz, 1.0)).z;
            vec3 n = texelFetch(u_gbuffer_normal, texel, 0).xyz;
            depth = vec4(z, z, 1.0, z);
            normal_min = n;
            normal_max = n;
        }
    } else {
        float covered = 0.0, children = 0.0, depth_sum = 0.0;
        for (int child = 0; child < 4; ++child) {
            ivec2 below = texel * 2 + ivec2(child & 1, child >> 1);
            if (any(greaterThanEqual(below, u_level_size[u_level - 1]))) continue;
            ivec2 at = atlas_texel(u_level - 1, below);
            vec4 d = imageLoad(u_depth, at);
            children += 1.0;
            if (patch_empty(d)) continue;
            depth.x = min(depth.x, d.x);
            depth.y = max(depth.y, d.y);
            covered += d.z;
            depth_sum += d.w * d.z;
            normal_min = min(normal_min, imageLoad(u_normal_min, at).xyz);
            normal_max = max(normal_max, imageLoad(u_normal_max, at).xyz);
        }
        depth.z = covered / max(children, 1.0);
        depth.w = covered > 0.0 ? depth_sum / covered : 0.0;
    }
    ivec2 at = atlas_texel(u_level, texel);
    imageStore(u_depth, at, depth);
    imageStore(u_normal_min, at, vec4(normal_min, 0.0));
    imageStore(u_normal_max, at, vec4(normal_max, 0.0));
}
