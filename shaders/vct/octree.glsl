// The sparse voxel octree as shaders see it: node buffers, descent from the root, lattice and brick
// addressing, float atomics. Layout: vct/vct_layout.h; the C++ side: renderer/methods/vct/.
//
// Leaves (level D) are cells of two lattice spacings; a node's 3x3x3 brick holds the voxels on its
// corners, edge and face midpoints and centre, so neighbouring bricks share their border voxels and
// hardware trilinear filtering inside a brick is exact. A leaf owns lattice points 2c and 2c+1 on
// each axis (its 8 slots); point 2c+2 belongs to the next leaf.
#include "vct/vct_layout.h"

layout(std430, binding = VCT_BINDING_COUNTERS) coherent buffer Counters { uint counters[]; };
layout(std430, binding = VCT_BINDING_NODES) coherent buffer Nodes { uint node_child[]; };

uniform uint u_leaf_level;         // D: the root is level 0, leaves are level D
uniform vec3 u_grid_origin;        // world position of lattice point 0 (the root's min corner)
uniform float u_lattice_spacing;   // world distance between leaf-level voxels (half a leaf)
uniform uint u_bricks_per_axis;    // bricks along each axis of the brick pool
uniform uint u_inner_bricks_per_axis;  // the same for the directional pool (inner nodes only)
#ifdef DENSE
// The dense variant: no nodes; every lattice point of every level is a texel of the pool.
uniform uint u_dense_side;                       // lattice points per axis at the leaf level
uniform int u_dense_z[VCT_MAX_DENSE_LAYERS];     // first z of level l, direction k at l * 6 + k
#endif

// The node at `level` whose cell is `cell` (cell coordinates at that level), or VCT_NODE_NONE where
// the tree is empty.
uint find_node(uvec3 cell, uint level) {
    uint node = 0u;
    for (uint l = 0u; l < level; ++l) {
        uint child = node_child[node];
        if (child == 0u || (child & VCT_NODE_FLAGGED) != 0u) return VCT_NODE_NONE;
        uvec3 bit = (cell >> (level - 1u - l)) & 1u;
        node = child + bit.x + 2u * bit.y + 4u * bit.z;
    }
    return node;
}

uint slot_index(uvec3 slot) { return slot.x + 2u * slot.y + 4u * slot.z; }

// The leaf owning a leaf-level lattice point and the point's slot in it, or VCT_NODE_NONE.
uint owner_leaf(uvec3 lattice) {
    uvec3 cell = lattice >> 1u;
    if (any(greaterThanEqual(cell, uvec3(1u << u_leaf_level)))) return VCT_NODE_NONE;
    return find_node(cell, u_leaf_level);
}

ivec3 brick_origin(uint brick) {
    uint b = u_bricks_per_axis;
    return VCT_BRICK * ivec3(brick % b, (brick / b) % b, brick / (b * b));
}

// Brick of inner node `node` for direction k in the directional pool.
ivec3 directional_brick_origin(uint node, uint k) {
    uint b = u_inner_bricks_per_axis;
    return VCT_BRICK * ivec3(node % b, (node / b) % b, node / (b * b) + k * b);
}

uint pack_lattice(uvec3 lattice) { return lattice.x | (lattice.y << 10u) | (lattice.z << 20u); }
uvec3 unpack_lattice(uint bits) { return uvec3(bits & 1023u, (bits >> 10u) & 1023u, (bits >> 20u) & 1023u); }

// Where a surface lands in the lattice, the way voxelization finds it: in the column through the
// nearest lattice point across the dominant axis of its normal, on the two lattice points that
// bracket the surface along that axis. Two, not the nearest one: trilinear filtering of a
// one-voxel layer is nowhere fully opaque (a cone crossing it keeps e^-2 of its light even with
// infinitely fine steps), while two layers give an opaque plateau a voxel wide, which every cone
// step of at most a voxel samples.
struct SurfaceVoxels {
    ivec3 lower;  // the other is lower + step
    ivec3 step;
};

int dominant_axis(vec3 n) {
    vec3 a = abs(n);
    return a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
}

SurfaceVoxels surface_voxels(vec3 world, vec3 n, int axis) {
    vec3 q = (world - u_grid_origin) / u_lattice_spacing;
    vec3 column = round(q);
    vec3 offset = column - q;
    offset[axis] = 0.0;
    column[axis] = floor(q[axis] - dot(n, offset) / n[axis]);
    SurfaceVoxels voxels;
    voxels.lower = ivec3(column);
    voxels.step = ivec3(0);
    voxels.step[axis] = 1;
    return voxels;
}

layout(std430, binding = VCT_BINDING_NODE_COORDS) buffer NodeCoords { uvec4 node_coord[]; };
