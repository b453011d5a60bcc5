#version 450 core
// One coarser level of the VPL tree from the 2x2 patches below (the light-space min-max mipmap of
// paper §3.4, plus the cluster each cell stands for): flux and area add up; position and normal
// are flux-weighted means (area-weighted where nothing is lit); the bounding sphere holds the
// children's; a cell is discontinuous where a child is, where it mixes covered and empty texels,
// or where its distances from the light or its normals spread past the thresholds.
layout(local_size_x = 8, local_size_y = 8) in;
#include "isr/vpl_tree.glsl"

uniform int u_view;
uniform int u_level;
uniform float u_depth_threshold;
uniform float u_normal_threshold;

bool empty(VplNode node) { return node.flux_far.w < 0.0; }

void main() {
    ivec2 cell = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(cell, ivec2(u_rsm_size >> u_level)))) return;
    VplNode children[4];
    int covered = 0;
    bool flagged = false;
    vec3 flux = vec3(0.0);
    float area = 0.0, weight_sum = 0.0, far = -1.0, near = 3.0e38;
    vec3 position = vec3(0.0), normal = vec3(0.0), normal_min = vec3(2.0), normal_max = vec3(-2.0);
    for (int c = 0; c < 4; ++c) {
        children[c] = nodes[node_index(u_view, u_level - 1, cell * 2 + ivec2(c & 1, c >> 1))];
        if (empty(children[c])) continue;
        ++covered;
        flagged = flagged || children[c].normal_max_flag.w != 0.0;
        flux += children[c].flux_far.rgb;
        area += children[c].position_area.w;
        far = max(far, children[c].flux_far.w);
        near = min(near, children[c].normal_min_near.w);
        normal_min = min(normal_min, children[c].normal_min_near.xyz);
        normal_max = max(normal_max, children[c].normal_max_flag.xyz);
    }
    // Weights: flux luminance, or area where the cell reflects nothing (shadowed surfaces).
    bool lit = any_positive(flux);
    for (int c = 0; c < 4; ++c) {
        if (empty(children[c])) continue;
        float w = lit ? dot(children[c].flux_far.rgb, vec3(0.2126, 0.7152, 0.0722)) : children[c].position_area.w;
        w = max(w, 0.0);
        position += w * children[c].position_area.xyz;
        normal += w * children[c].normal_radius.xyz;
        weight_sum += w;
    }
    VplNode node;
    node.normal_max_flag.w = 0.0;
    if (covered == 0) {
        node.position_area = vec4(0.0);
        node.normal_radius = vec4(0.0);
        node.flux_far = vec4(0.0, 0.0, 0.0, -1.0);
        node.normal_min_near = vec4(2.0, 2.0, 2.0, 3.0e38);
        node.normal_max_flag = vec4(-2.0, -2.0, -2.0, 0.0);
        node.bound_area = vec4(0.0);
    } else {
        if (weight_sum > 0.0) {
            position /= weight_sum;
            normal /= weight_sum;
        } else {  // zero-area children: any of them stands for the cell
            for (int c = 3; c >= 0; --c) {
                if (!empty(children[c])) { position = children[c].position_area.xyz; normal = children[c].normal_radius.xyz; }
            }
        }
        float radius = 0.0;
        for (int c = 0; c < 4; ++c) {
            if (empty(children[c])) continue;
            radius = max(radius, distance(children[c].position_area.xyz, position) + children[c].normal_radius.w);
        }
        bool discontinuous = flagged || covered < 4 || far - near >= u_depth_threshold * near ||
                             any(greaterThanEqual(normal_max - normal_min, vec3(u_normal_threshold)));
        node.position_area = vec4(position, area);
        node.normal_radius = vec4(normal, radius);
        node.flux_far = vec4(flux, far);
        node.normal_min_near = vec4(normal_min, near);
        node.normal_max_flag = vec4(normal_max, discontinuous ? 1.0 : 0.0);
        node.bound_area = vec4(patch_bound_area(float(1 << (2 * u_level)), near), 0.0, 0.0, 0.0);
    }
    nodes[node_index(u_view, u_level, cell)] = node;
}
