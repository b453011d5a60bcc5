#version 450 core
// Octree build, one level at a time (paper §4.2.1, with a level-by-level order in place of the
// deferred-thread list): every voxel fragment flags the node of level u_level that holds it, and
// the first to flag a node counts it, so the host can size the pool before allocate_nodes.comp
// gives each flagged node its 2x2x2 children. No thread ever waits on another.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "vct/octree.glsl"

layout(std430, binding = VCT_BINDING_FRAGMENTS) readonly buffer Fragments { uint fragments[]; };

uniform uint u_level;
uniform uint u_fragment_count;

void main() {
    uint index = thread_index();
    if (index >= u_fragment_count) return;
    uvec3 leaf_cell = unpack_lattice(fragments[index * VCT_FRAGMENT_WORDS]) >> 1u;
    // The lattice's last point (2^(D+1), which the dense variant keeps) has no leaf: find_node reads
    // only a cell's low D bits, and would flag the leaf at the grid's other side.
    if (any(greaterThanEqual(leaf_cell, uvec3(1u << u_leaf_level)))) return;
    uint node = find_node(leaf_cell >> (u_leaf_level - u_level), u_level);
    if (node == VCT_NODE_NONE || node_child[node] != 0u) return;
    if (atomicOr(node_child[node], VCT_NODE_FLAGGED) == 0u) atomicAdd(counters[VCT_COUNTER_FLAGGED], 1u);
}
