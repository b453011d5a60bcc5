#version 450 core
// Pull (§4.1.1): leaves take their texel's radiance and normal; each internal node, a level at a
// time from the deepest, the area-weighted mean of its two children's radiance and the
// luminance-weighted mean of their lobes (CssmNodeLight in cssm/cssm_layout.h).
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
        if (texel != CSSM_NONE) {
            node_light[node].radiance = vec4(texel_in[texel].rgb, 0.0);
            node_light[node].lobe = vec4(texels[texel].normal_map.xyz, 1.0);
        }
        return;
    }
    uint node = level_nodes[u_first + i];
    uint left = nodes[node].links.x;
    uint right = nodes[left].links.y;
    float a_left = nodes[left].area.x, a_right = nodes[right].area.x;
    vec3 l_left = node_light[left].radiance.rgb, l_right = node_light[right].radiance.rgb;
    node_light[node].radiance = vec4((l_left * a_left + l_right * a_right) / max(a_left + a_right, 1e-30), 0.0);
    // Weighted by the light each child sends; where neither sends any, by area (it then sends nothing).
    float w_left = luminance(l_left) * a_left, w_right = luminance(l_right) * a_right;
    if (!(w_left + w_right > 0.0)) {
        w_left = a_left;
        w_right = a_right;
    }
    vec3 v = (node_light[left].lobe.xyz * w_left + node_light[right].lobe.xyz * w_right) / max(w_left + w_right, 1e-30);
    node_light[node].lobe = vec4(v, min(length(v), 1.0));
}
