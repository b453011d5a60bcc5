#version 450 core
// Pull-push hole filling of the imperfect shadow maps (paper §3.2), the pull: level 0 from the
// splatted bits, then each coarser level from the four texels below it, as the mean of those that
// belong to the nearest surface among them (ISM_SAME_SURFACE). A point cloud samples a small near
// occluder sparsely and a large far surface densely, so a map texel that caught only a far sample
// says little; a coarser texel that caught a near one says the occluder is there.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "isr/vpl_tree.glsl"
#include "isr/ism.glsl"

layout(std430, binding = ISR_BINDING_ISM_DEPTH) readonly buffer Depth { uint depth_bits[]; };
layout(std430, binding = ISR_BINDING_ISM_FILLED) buffer Pyramid { float depth_pyramid[]; };

uniform int u_level;  // the level written

void main() {
    int side = u_ism_size >> u_level;
    uint texels = uint(side * side);
    uint thread = thread_index();
    if (thread >= u_ism_maps * texels) return;
    uint map = thread / texels;
    ivec2 texel = ivec2(int(thread % texels) % side, int(thread % texels) / side);
    if (u_level == 0) {
        uint bits = depth_bits[thread];
        depth_pyramid[thread] = bits == 0xFFFFFFFFu ? ISM_EMPTY : uintBitsToFloat(bits);
        return;
    }
    float below[4];
    float nearest = ISM_EMPTY;
    for (int c = 0; c < 4; ++c) {
        below[c] = depth_pyramid[ism_pyramid_index(u_level - 1, map, texel * 2 + ivec2(c & 1, c >> 1))];
        nearest = min(nearest, below[c]);
    }
    float sum = 0.0, count = 0.0;
    for (int c = 0; c < 4; ++c) {
        if (below[c] < ISM_EMPTY && below[c] <= nearest * (1.0 + ISM_SAME_SURFACE)) {
            sum += below[c];
            count += 1.0;
        }
    }
    depth_pyramid[ism_pyramid_index(u_level, map, texel)] = count > 0.0 ? sum / count : ISM_EMPTY;
}
