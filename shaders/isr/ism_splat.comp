#version 450 core
// Splats the point cloud into the imperfect shadow maps (paper §3.1): one thread per map and point;
// each map takes u_points_per_map consecutive points of the cloud (stored in random order) from an
// offset of its own, so each map sees a different sparse subset. The nearest distance per texel wins (atomicMin on the float's bits,
// which order as unsigned integers for non-negative floats).
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "isr/vpl_tree.glsl"
#include "isr/ism.glsl"

layout(std430, binding = ISR_BINDING_ISM_POINTS) readonly buffer Points { vec4 points[]; };  // object space; w: object
layout(std430, binding = ISR_BINDING_ISM_TRANSFORMS) readonly buffer Transforms { mat4 transforms[]; };
layout(std430, binding = ISR_BINDING_ISM_DEPTH) buffer Depth { uint depth_bits[]; };

uniform uint u_first_map;
uniform uint u_maps;            // in this dispatch
uniform uint u_points_per_map;
uniform uint u_cloud_size;

void main() {
    uint thread = thread_index();
    uint local_map = thread / u_points_per_map;
    if (local_map >= u_maps) return;
    uint map = u_first_map + local_map;
    IsmFrame f = ism_frame(map);
    if (!f.valid) return;
    vec4 point = points[(pcg_hash(map) + thread % u_points_per_map) % u_cloud_size];
    vec3 world = (transforms[uint(point.w)] * vec4(point.xyz, 1.0)).xyz;
    vec3 offset = world - f.centre;
    float d = length(offset);
    if (!(d > 0.0)) return;
    vec2 texel;
    if (!ism_project(f, offset / d, texel)) return;
    atomicMin(depth_bits[ism_texel_index(map, ivec2(texel))], floatBitsToUint(d));
}
