#version 450 core
// The stenciled gather (paper §3.2.2): every marked fragment of the multiresolution atlas gathers,
// at its patch's centre pixel, the irradiance of the VPLs: the VPL cache (naive or basic image-space
// radiosity), or a walk of the VPL tree from the top patches that opens a patch while the bound on
// what it can contribute exceeds the threshold (hierarchical, §3.5.1).
// With INDIRECT_VISIBILITY (hierarchical only), each VPL's light is shadowed by its patch's imperfect
// shadow map (isr/ism.glsl); the paper gathers without visibility.
// A draw gathers one batch (a range of the cache, or of the top patches over every view) and adds
// it with blending, so no draw runs unbounded work per fragment. Alpha counts the VPLs gathered,
// plus one on the first batch: texels that gathered hold alpha >= 1 (isr/pull.comp).
#include "common/shared_layout.h"
// Stencil before shading: only marked fragments run, as the paper's early stencil cull.
layout(early_fragment_tests) in;
#include "isr/multires.glsl"
#include "isr/vpl_tree.glsl"
#ifdef INDIRECT_VISIBILITY
#define ISM_READ
#include "isr/ism.glsl"
#endif

layout(binding = BOUNCE_UNIT_GBUFFER_POSITION) uniform sampler2D u_gbuffer_position;
layout(binding = BOUNCE_UNIT_GBUFFER_NORMAL) uniform sampler2D u_gbuffer_normal;

uniform uint u_batch_first;
uniform uint u_batch_count;
uniform bool u_first_batch;

#ifdef VPL_CACHE
layout(std430, binding = ISR_BINDING_CACHE) readonly buffer Cache {
    uint vpl_count;
    uint pad[3];
    Vpl vpls[];
};
#else
layout(std430, binding = ISR_BINDING_TREE_INFO) readonly buffer TreeInfo { float tree_info[4]; };
uniform int u_finest_level;
uniform float u_tau;
uniform float u_scene_radius;
#endif

out vec4 out_irradiance;

uint pack_cell(int level, ivec2 cell) { return uint(level) << 24 | uint(cell.y) << 12 | uint(cell.x); }

void main() {
    ivec2 texel;
    int level = atlas_level(ivec2(gl_FragCoord.xy), texel);
    // The patch's centre: its pixel, or the mean of the 2x2 pixels around the centre of a coarser
    // patch (all on one continuous surface, or the patch would not gather).
    vec3 p = vec3(0.0), n = vec3(0.0);
    if (level == 0) {
        p = texelFetch(u_gbuffer_position, texel, 0).xyz;
        n = texelFetch(u_gbuffer_normal, texel, 0).xyz;
    } else {
        ivec2 centre = texel * (1 << level) + (1 << (level - 1));
        float count = 0.0;
        for (int k = 0; k < 4; ++k) {
            ivec2 pixel = centre - ivec2(k & 1, k >> 1);
            vec4 position = texelFetch(u_gbuffer_position, min(pixel, u_level_size[0] - 1), 0);
            if (position.w == 0.0) continue;
            p += position.xyz;
            n += texelFetch(u_gbuffer_normal, min(pixel, u_level_size[0] - 1), 0).xyz;
            count += 1.0;
        }
        p /= max(count, 1.0);
        n = safe_normalize(n, vec3(0.0, 0.0, 1.0));
    }
    vec3 irradiance = vec3(0.0);
    float gathered = 0.0;
#ifdef VPL_CACHE
    uint last = min(u_batch_first + u_batch_count, vpl_count);
    for (uint i = u_batch_first; i < last; ++i) {
        irradiance += vpl_irradiance(p, n, vpls[i].position_area.xyz, vpls[i].normal.xyz, vpls[i].position_area.w,
                                     vpls[i].flux.rgb);
    }
    gathered = float(last > u_batch_first ? last - u_batch_first : 0u);
#else
    // Open a patch where flux / (pi d^2 + A), with d the distance to its bounding sphere, exceeds tau
    // times the irradiance all reflected flux would give from the scene's radius.
    float threshold = u_tau * tree_info[0] / (PI * u_scene_radius * u_scene_radius);
    int top_side = u_rsm_size >> u_top_level;
    uint tops_per_view = uint(top_side * top_side);
    uint stack[ISR_MAX_STACK];
    for (uint top = u_batch_first; top < u_batch_first + u_batch_count; ++top) {
        int view = int(top / tops_per_view);
        int index = int(top % tops_per_view);
        int depth = 0;
        stack[depth++] = pack_cell(u_top_level, ivec2(index % top_side, index / top_side));
        while (depth > 0) {
            uint entry = stack[--depth];
            int node_level = int(entry >> 24);
            ivec2 cell = ivec2(entry & 0xFFFu, (entry >> 12) & 0xFFFu);
            VplNode node = nodes[node_index(view, node_level, cell)];
            if (!any_positive(node.flux_far.rgb)) continue;
            if (node_level > u_finest_level) {
                float d = max(distance(p, node.position_area.xyz) - node.normal_radius.w, 0.0);
                float bound = max_component(node.flux_far.rgb) / (PI * d * d + node.bound_area.x);
                if (bound > threshold) {
                    for (int c = 0; c < 4; ++c) stack[depth++] = pack_cell(node_level - 1, cell * 2 + ivec2(c & 1, c >> 1));
                    continue;
                }
            }
            vec3 light = vpl_irradiance(p, n, node.position_area.xyz, safe_normalize(node.normal_radius.xyz, n),
                                        node.position_area.w, node.flux_far.rgb);
#ifdef INDIRECT_VISIBILITY
            if (any_positive(light)) light *= ism_visibility(view, node_level, cell, p, n);
#endif
            irradiance += light;
            gathered += 1.0;
        }
    }
#endif
    out_irradiance = vec4(finite_or_zero(irradiance), gathered + (u_first_batch ? 1.0 : 0.0));
}
