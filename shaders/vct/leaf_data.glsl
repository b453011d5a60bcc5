// Per-leaf-slot data of the octree's leaves (vct/vct_layout.h), summed by many threads at once
// (common/float_atomics.glsl).
#include "common/float_atomics.glsl"

layout(std430, binding = VCT_BINDING_LEAF_SUMS) coherent buffer LeafSums { FLOAT_WORD leaf_sums[]; };
layout(std430, binding = VCT_BINDING_LEAF_LIGHT) coherent buffer LeafLight { FLOAT_WORD leaf_light[]; };

// Leaves are allocated last, contiguously: the static part's, then (after the dynamic part's inner
// nodes) the dynamic part's. Leaf data holds the static leaves, then the dynamic ones.
uniform uint u_first_leaf;
uniform uint u_static_leaf_count;
uniform uint u_first_dynamic_leaf;  // 0xFFFFFFFF without a dynamic part

uint leaf_index(uint leaf) {
    return leaf >= u_first_dynamic_leaf ? u_static_leaf_count + (leaf - u_first_dynamic_leaf) : leaf - u_first_leaf;
}

// The node of leaf number `index` (the inverse of leaf_index).
uint leaf_node(uint index) {
    return index < u_static_leaf_count ? u_first_leaf + index : u_first_dynamic_leaf + (index - u_static_leaf_count);
}

uint leaf_slot(uint leaf, uint slot) { return leaf_index(leaf) * 8u + slot; }

#ifdef DENSE
// The dense variant: one slot per leaf-level lattice point.
uint lattice_slot(uvec3 lattice) {
    if (any(greaterThanEqual(lattice, uvec3(u_dense_side)))) return VCT_NODE_NONE;
    return lattice.x + u_dense_side * (lattice.y + u_dense_side * lattice.z);
}
uvec3 slot_lattice(uint slot) {
    return uvec3(slot % u_dense_side, (slot / u_dense_side) % u_dense_side, slot / (u_dense_side * u_dense_side));
}
#else
// The slot of a lattice point: in the leaf that owns it, VCT_NODE_NONE where there is none.
uint lattice_slot(uvec3 lattice) {
    uint leaf = owner_leaf(lattice);
    return leaf == VCT_NODE_NONE ? VCT_NODE_NONE : leaf_slot(leaf, slot_index(lattice & 1u));
}
uvec3 slot_lattice(uint slot) {
    uint s = slot % 8u;
    return node_coord[leaf_node(slot / 8u)].xyz * 2u + uvec3(s & 1u, (s >> 1u) & 1u, s >> 2u);
}
#endif

FLOAT_ADD_FUNCTION(add_leaf_sum, leaf_sums)
FLOAT_ADD_FUNCTION(add_leaf_light, leaf_light)

vec3 leaf_light_at(uint slot) {
    return vec3(float_word_value(leaf_light[slot * 3u]), float_word_value(leaf_light[slot * 3u + 1u]),
                float_word_value(leaf_light[slot * 3u + 2u]));
}

void set_leaf_light(uint slot, vec3 value) {
    leaf_light[slot * 3u] = float_word(value.r);
    leaf_light[slot * 3u + 1u] = float_word(value.g);
    leaf_light[slot * 3u + 2u] = float_word(value.b);
}

float leaf_sum(uint slot, uint word) { return float_word_value(leaf_sums[slot * VCT_LEAF_SUM_WORDS + word]); }
