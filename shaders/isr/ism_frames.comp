#version 450 core
// What the gather reads of each imperfect shadow map besides its depths (isr/ism.glsl): pass 0, per
// map, its patch's centre and pole; pass 1, per tree node of level u_level above the maps' level,
// the map of its brightest descendant at that level, found by descending to the brightest child.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "isr/vpl_tree.glsl"
#include "isr/ism.glsl"

uniform int u_pass;
uniform int u_views;
uniform int u_level;  // pass 1

void main() {
    uint thread = thread_index();
    if (u_pass == 0) {
        if (thread >= u_ism_maps) return;
        int index = int(thread % ism_count_per_view());
        VplNode node = nodes[node_index(int(thread / ism_count_per_view()), u_ism_level,
                                        ivec2(index % ism_side(), index / ism_side()))];
        bool valid = any_positive(node.flux_far.rgb) && dot(node.normal_radius.xyz, node.normal_radius.xyz) > 1e-12;
        ism_frames[2u * thread] = vec4(node.position_area.xyz, valid ? 1.0 : 0.0);
        ism_frames[2u * thread + 1u] = vec4(safe_normalize(node.normal_radius.xyz, vec3(0.0, 0.0, 1.0)), 0.0);
        return;
    }
    int side = u_rsm_size >> u_level;
    uint per_view = uint(side * side);
    if (thread >= uint(u_views) * per_view) return;
    int view = int(thread / per_view);
    ivec2 cell = ivec2(int(thread % per_view) % side, int(thread % per_view) / side);
    ivec2 at = cell;
    for (int l = u_level; l > u_ism_level; --l) {
        ivec2 brightest = at * 2;
        float most = -1.0;
        for (int c = 0; c < 4; ++c) {
            ivec2 child = at * 2 + ivec2(c & 1, c >> 1);
            float flux = dot(nodes[node_index(view, l - 1, child)].flux_far.rgb, vec3(1.0));
            if (flux > most) {
                most = flux;
                brightest = child;
            }
        }
        at = brightest;
    }
    ism_coarse_maps[node_index(view, u_level, cell)] = uint(view) * ism_count_per_view() + uint(at.y * ism_side() + at.x);
}
