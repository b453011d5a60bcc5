#version 450 core
// Pull (§4.1.1): leaves take their texel's radiance; each internal node, a level at a time from the
// deepest, the area-weighted mean of its two children.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#define CSSM_BRDF(l, spread) 1.0
#define CSSM_BRDF_BOUND(l, cone) 1.0
#include "cssm/cssm_tree.glsl"

layout(std430, binding = CSSM_BINDING_TEXEL_IN) readonly buffer CssmTexelIn { vec4 texel_in[]; };
layout(std430, binding = CSSM_BINDING_LEVEL_NODES) readonly buffer CssmLevelNodes { uint level_nodes[]; };

uniform bool u_leaves;
uniform uint u_first;
uniform uint u_count;

void main() {
    uint i = thread_index();
    if (i >= u_count) return;
    if (u_leaves) {
        uint node = u_first + i;
        uint texel = nodes[node].links.w;
        if (texel != CSSM_NONE) node_radiance[node] = vec4(texel_in[texel].rgb, 0.0);
        return;
    }
    uint node = level_nodes[u_first + i];
    uint left = nodes[node].links.x;
    uint right = nodes[left].links.y;
    float a_left = nodes[left].area.x, a_right = nodes[right].area.x;
    vec3 sum = node_radiance[left].rgb * a_left + node_radiance[right].rgb * a_right;
    node_radiance[node] = vec4(sum / max(a_left + a_right, 1e-30), 0.0);
}
