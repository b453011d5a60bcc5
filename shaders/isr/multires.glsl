// The flattened multiresolution buffer (paper §3.2.1): level i holds ceil(size / 2^i) texels, each
// an eye-space cell of 2^i x 2^i pixels. Level 0 sits at the atlas origin, the coarser levels in a
// column to its right.
#include "isr/isr_layout.h"

uniform int u_levels;
uniform ivec2 u_level_origin[ISR_MAX_LEVELS];
uniform ivec2 u_level_size[ISR_MAX_LEVELS];
uniform float u_depth_threshold;   // relative: a cell is discontinuous where (max - min) > this * min
uniform float u_normal_threshold;  // a cell is discontinuous where a normal component spans more

// The level an atlas texel belongs to, and its texel within the level; -1 outside every level.
int atlas_level(ivec2 atlas, out ivec2 texel) {
    for (int level = 0; level < u_levels; ++level) {
        texel = atlas - u_level_origin[level];
        if (all(greaterThanEqual(texel, ivec2(0))) && all(lessThan(texel, u_level_size[level]))) return level;
    }
    texel = ivec2(-1);
    return -1;
}

ivec2 atlas_texel(int level, ivec2 texel) { return u_level_origin[level] + texel; }

// Discontinuity tests on the min-max pyramid's entries (depth: min, max, covered fraction).
bool patch_empty(vec4 depth) { return depth.z <= 0.0; }

bool patch_discontinuous(vec4 depth, vec3 normal_min, vec3 normal_max) {
    if (depth.z < 1.0) return true;  // part background, part surface
    // Spans at the threshold split too, so 0 means full resolution even on fronto-parallel walls.
    if (depth.y - depth.x >= u_depth_threshold * depth.x) return true;
    return any(greaterThanEqual(normal_max - normal_min, vec3(u_normal_threshold)));
}
