#version 450 core
// Gives every flagged node of one level a tile of 2x2x2 children from the preallocated node pool
// (an atomic counter; the host made room for every flagged node), and writes the children's cells.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "vct/octree.glsl"

uniform uint u_first_node;
uniform uint u_node_count;

void main() {
    uint index = thread_index();
    if (index >= u_node_count) return;
    uint node = u_first_node + index;
    if (node_child[node] != VCT_NODE_FLAGGED) return;
    uint child = atomicAdd(counters[VCT_COUNTER_NODES], 8u);
    uvec4 parent = node_coord[node];
    for (uint i = 0u; i < 8u; ++i) {
        node_child[child + i] = 0u;
        node_coord[child + i] = uvec4(parent.xyz * 2u + uvec3(i & 1u, (i >> 1u) & 1u, (i >> 2u) & 1u), parent.w + 1u);
    }
    node_child[node] = child;
}
