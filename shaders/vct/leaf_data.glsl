// Per-leaf-slot data of the octree's leaves (vct/vct_layout.h) and float addition on them by
// compare-and-swap (core GLSL has no float atomics).
layout(std430, binding = VCT_BINDING_LEAF_SUMS) coherent buffer LeafSums { uint leaf_sums[]; };
layout(std430, binding = VCT_BINDING_LEAF_LIGHT) coherent buffer LeafLight { uint leaf_light[]; };

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

#define VCT_DEFINE_FLOAT_ADD(name, buffer)                                                   \
    void name(uint index, float value) {                                                    \
        if (value == 0.0) return;                                                           \
        uint seen = buffer[index];                                                          \
        for (int attempt = 0; attempt < 1000000; ++attempt) {                               \
            uint expected = seen;                                                           \
            seen = atomicCompSwap(buffer[index], expected, floatBitsToUint(uintBitsToFloat(expected) + value)); \
            if (seen == expected) break;                                                    \
        }                                                                                   \
    }

VCT_DEFINE_FLOAT_ADD(add_leaf_sum, leaf_sums)
VCT_DEFINE_FLOAT_ADD(add_leaf_light, leaf_light)

vec3 leaf_light_at(uint slot) {
    return vec3(uintBitsToFloat(leaf_light[slot * 3u]), uintBitsToFloat(leaf_light[slot * 3u + 1u]),
                uintBitsToFloat(leaf_light[slot * 3u + 2u]));
}

float leaf_sum(uint slot, uint word) { return uintBitsToFloat(leaf_sums[slot * VCT_LEAF_SUM_WORDS + word]); }
