#version 450 core
// Fills the holes a sparse splat leaves, as the paper's pull-push does at its first level: a texel
// takes the mean depth of the nearest surface's samples within one texel of it (those within 20% of
// the nearest distance there) when it holds none, or when its own sample lies farther behind them:
// a point of a far surface that fell through a gap between a nearer surface's points (without
// this, light leaks through walls wherever the far side happens to be sampled and the near side
// not). A texel with no sample near stays empty: nothing occludes there.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "isr/vpl_tree.glsl"
#include "isr/ism.glsl"

layout(std430, binding = ISR_BINDING_ISM_DEPTH) readonly buffer Depth { uint depth_bits[]; };
layout(std430, binding = ISR_BINDING_ISM_FILLED) writeonly buffer Filled { float depth_filled[]; };

uniform uint u_map_count;

const uint kEmpty = 0xFFFFFFFFu;
const int kFillRadius = 1;
const float kSameSurface = 0.2;  // relative depth span of one surface's samples

void main() {
    uint thread = thread_index();
    uint texels = uint(u_ism_size * u_ism_size);
    if (thread >= u_map_count * texels) return;
    uint map = thread / texels;
    ivec2 texel = ivec2(int(thread % texels) % u_ism_size, int(thread % texels) / u_ism_size);
    float nearest = 3.0e38;
    for (int y = -kFillRadius; y <= kFillRadius; ++y) {
        for (int x = -kFillRadius; x <= kFillRadius; ++x) {
            ivec2 at = texel + ivec2(x, y);
            if (any(lessThan(at, ivec2(0))) || any(greaterThanEqual(at, ivec2(u_ism_size)))) continue;
            uint bits = depth_bits[ism_texel_index(map, at)];
            if (bits != kEmpty) nearest = min(nearest, uintBitsToFloat(bits));
        }
    }
    uint own = depth_bits[thread];
    float limit = nearest * (1.0 + kSameSurface);
    if (own != kEmpty && uintBitsToFloat(own) <= limit) {
        depth_filled[thread] = uintBitsToFloat(own);
        return;
    }
    float sum = 0.0, count = 0.0;
    for (int y = -kFillRadius; y <= kFillRadius; ++y) {
        for (int x = -kFillRadius; x <= kFillRadius; ++x) {
            ivec2 at = texel + ivec2(x, y);
            if (any(lessThan(at, ivec2(0))) || any(greaterThanEqual(at, ivec2(u_ism_size)))) continue;
            uint bits = depth_bits[ism_texel_index(map, at)];
            if (bits == kEmpty || uintBitsToFloat(bits) > limit) continue;
            sum += uintBitsToFloat(bits);
            count += 1.0;
        }
    }
    depth_filled[thread] = count > 0.0 ? sum / count : 3.0e38;
}
