// Addressing of the VPL tree: per light view, the levels from the light-view map's texels (level 0)
// up to ISR_TOP_PATCHES^2 patches, one after another; views one after another.
#include "isr/vpl.glsl"

layout(std430, binding = ISR_BINDING_NODES) buffer Nodes { VplNode nodes[]; };

uniform int u_rsm_size;
uniform int u_top_level;     // the level of ISR_TOP_PATCHES^2 patches
uniform uint u_nodes_per_view;
uniform uint u_level_offset[ISR_MAX_TREE_LEVELS];
// The view being built: a texel's solid angle on its axis (perspective) or its area (orthographic).
uniform float u_texel_measure;
uniform bool u_orthographic;

uint node_index(int view, int level, ivec2 cell) {
    int side = u_rsm_size >> level;
    return uint(view) * u_nodes_per_view + u_level_offset[level] + uint(cell.y * side + cell.x);
}

// The area term of the traversal bound (paper eq. 3, A_j = omega_j |V_j|^2): with VPLs that carry
// flux a smaller area gives a larger bound, so the cell's smallest distance from the light stands
// in for the paper's largest (which is the conservative choice for its intensity-carrying VPLs).
// Orthographic views: the texels' area across the light's rays.
float patch_bound_area(float texels, float near) {
    return u_orthographic ? texels * u_texel_measure : texels * u_texel_measure * near * near;
}
