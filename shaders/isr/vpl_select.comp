#version 450 core
// The VPL cache for one level of one light view (paper §3.2.2, §3.4). Naive RSM sampling: one VPL
// per cell of the finest level, the light-view texel at its centre standing for the whole cell.
// Basic image-space radiosity: the patches that need no subdivision while their parent does
// (the finest level takes whatever remains), so VPLs cluster where the light sees one smooth
// surface and split at discontinuities.
layout(local_size_x = 8, local_size_y = 8) in;
#include "isr/vpl_tree.glsl"

layout(std430, binding = ISR_BINDING_CACHE) buffer Cache {
    uint vpl_count;
    uint pad[3];
    Vpl vpls[];
};

uniform int u_view;
uniform int u_level;
uniform int u_finest_level;
uniform int u_mode;

void emit(vec3 position, vec3 normal, vec3 flux, float area) {
    if (!any_positive(flux)) return;
    uint slot = atomicAdd(vpl_count, 1u);
    if (slot >= uint(vpls.length())) return;  // the cache is sized for the finest level: never
    vpls[slot] = Vpl(vec4(position, area), vec4(safe_normalize(normal, vec3(0.0, 0.0, 1.0)), 0.0), vec4(flux, 0.0));
}

void main() {
    ivec2 cell = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(cell, ivec2(u_rsm_size >> u_level)))) return;
    VplNode node = nodes[node_index(u_view, u_level, cell)];
    if (node.flux_far.w < 0.0) return;
    if (u_mode == ISR_MODE_NAIVE) {
        int span = 1 << u_level;
        VplNode sample_texel = nodes[node_index(u_view, 0, cell * span + span / 2)];
        if (sample_texel.flux_far.w < 0.0) return;
        float texels = float(span * span);
        emit(sample_texel.position_area.xyz, sample_texel.normal_radius.xyz, sample_texel.flux_far.rgb * texels,
             sample_texel.position_area.w * texels);
        return;
    }
    bool discontinuous = node.normal_max_flag.w != 0.0;
    if (u_level > u_finest_level && discontinuous) return;
    if (u_level < u_top_level && nodes[node_index(u_view, u_level + 1, cell / 2)].normal_max_flag.w == 0.0) return;
    emit(node.position_area.xyz, node.normal_radius.xyz, node.flux_far.rgb, node.position_area.w);
}
