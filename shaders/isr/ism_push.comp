#version 450 core
// Pull-push hole filling, the push: from coarse to fine, a texel takes the value of the texel above
// it where it caught no sample, or where its own lies behind that surface within a few texels (a far
// sample seen through a gap in a nearer surface's samples).
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "isr/vpl_tree.glsl"
#include "isr/ism.glsl"

layout(std430, binding = ISR_BINDING_ISM_FILLED) buffer Pyramid { float depth_pyramid[]; };

uniform int u_level;  // the level written, from the one above it

// A sample is replaced by a nearer surface's only from the levels this near (at most 2: 2x2 and 4x4
// texels): a coarse texel holds the nearest surface of a wide region, which is not what every texel
// of it sees. The replacement dilates every near silhouette too: in the open Cornell boxes it is
// most of isr's error with the maps, behind thin walls it is what keeps light from leaking
// (docs/benchmarks.md, "The maps' hole filling"). 0: holes are filled, nothing else.
uniform int u_dilation_levels;

void main() {
    int side = u_ism_size >> u_level;
    uint texels = uint(side * side);
    uint thread = thread_index();
    if (thread >= u_ism_maps * texels) return;
    uint map = thread / texels;
    ivec2 texel = ivec2(int(thread % texels) % side, int(thread % texels) / side);
    uint at = ism_pyramid_index(u_level, map, texel);
    float own = depth_pyramid[at];
    // An odd side's last row and column have no texel above of their own: they take the nearest.
    int side_above = u_ism_size >> (u_level + 1);
    float above = depth_pyramid[ism_pyramid_index(u_level + 1, map, min(texel / 2, ivec2(side_above - 1)))];
    bool behind = own > above * (1.0 + ISM_SAME_SURFACE) && u_level + 1 <= u_dilation_levels;
    if (above < ISM_EMPTY && (own >= ISM_EMPTY || behind)) depth_pyramid[at] = above;
}
