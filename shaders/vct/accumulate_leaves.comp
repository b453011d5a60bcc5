#version 450 core
// Sums every voxel fragment into the leaf slot of its lattice point: area, and area-weighted
// albedo, normal and emission. Averages over the fragments of a voxel give its material; the
// length of the mean normal is its normal distribution's spread (Toksvig).
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "vct/octree.glsl"
#include "vct/leaf_data.glsl"

layout(std430, binding = VCT_BINDING_FRAGMENTS) readonly buffer Fragments { uint fragments[]; };

uniform uint u_fragment_count;

void main() {
    uint index = thread_index();
    if (index >= u_fragment_count) return;
    uint base = index * VCT_FRAGMENT_WORDS;
    uvec3 lattice = unpack_lattice(fragments[base]);
    uint slot = lattice_slot(lattice);
    if (slot == VCT_NODE_NONE) return;  // cannot happen: the fragment's own leaf was allocated
    slot *= VCT_LEAF_SUM_WORDS;
    float area = uintBitsToFloat(fragments[base + 6u]);
    vec3 albedo = unpackUnorm4x8(fragments[base + 1u]).rgb;
    vec3 normal = unpackSnorm4x8(fragments[base + 2u]).xyz;
    vec3 emission = vec3(uintBitsToFloat(fragments[base + 3u]), uintBitsToFloat(fragments[base + 4u]),
                         uintBitsToFloat(fragments[base + 5u]));
    add_leaf_sum(slot, area);
    for (uint c = 0u; c < 3u; ++c) {
        add_leaf_sum(slot + 1u + c, area * albedo[c]);
        add_leaf_sum(slot + 4u + c, area * normal[c]);
        add_leaf_sum(slot + 7u + c, area * emission[c]);
    }
}
