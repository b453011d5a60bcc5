#version 450 core
// The scale the traversal threshold is relative to: the largest flux channel summed over every
// top-level cell of every view (all the flux the light-view maps reflect).
layout(local_size_x = 1) in;
#include "isr/vpl_tree.glsl"

layout(std430, binding = ISR_BINDING_TREE_INFO) buffer TreeInfo { float tree_info[4]; };

uniform int u_views;

void main() {
    vec3 total = vec3(0.0);
    int side = u_rsm_size >> u_top_level;
    for (int view = 0; view < u_views; ++view) {
        for (int i = 0; i < side * side; ++i) total += nodes[node_index(view, u_top_level, ivec2(i % side, i / side))].flux_far.rgb;
    }
    tree_info[0] = max_component(total);
    tree_info[1] = 0.0;
    tree_info[2] = 0.0;
    tree_info[3] = 0.0;
}
