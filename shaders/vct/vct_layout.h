// Buffer bindings, image units and constants of the sparse voxel octree, shared by C++ and GLSL.
#ifndef BOUNCE_VCT_LAYOUT_H
#define BOUNCE_VCT_LAYOUT_H

// Shader storage buffers.
#define VCT_BINDING_COUNTERS 0    // uint[VCT_COUNTERS]
#define VCT_BINDING_FRAGMENTS 1   // uint[VCT_FRAGMENT_WORDS * n]: voxel fragments
#define VCT_BINDING_NODES 2       // uint[]: first child of each node (0: none, VCT_NODE_FLAGGED: to subdivide)
#define VCT_BINDING_NODE_COORDS 3 // uvec4[]: node cell at its level, and the level
#define VCT_BINDING_LEAF_SUMS 4   // float[VCT_LEAF_SUM_WORDS * 8 * leaves]: surface sums per leaf slot
#define VCT_BINDING_LEAF_LIGHT 5  // float[3 * 8 * leaves]: photon flux per leaf slot, then its radiance

#define VCT_COUNTER_FRAGMENTS 0
#define VCT_COUNTER_NODES 1
#define VCT_COUNTER_FLAGGED 2
#define VCT_COUNTER_DROPPED_PHOTONS 3
#define VCT_COUNTER_INJECTED_PHOTONS 4
#define VCT_COUNTER_MAX_RADIANCE 5  // float bits: non-negative floats order like their bits
#define VCT_COUNTER_STRAY_SLOTS 6   // lattice points that received flux but hold no surface
#define VCT_COUNTERS 7

// A voxel fragment: packed lattice point (10 bits per axis), unorm4x8 diffuse albedo, snorm4x8
// normal, emitted radiance (3 floats), and the surface area it stands for in lattice-spacing^2
// units (1 / the largest component of the unit face normal: one fragment per column along it).
#define VCT_FRAGMENT_WORDS 7
// Per leaf slot (the 2x2x2 lattice points a leaf owns): area, area-weighted albedo (3), normal (3)
// and emission (3).
#define VCT_LEAF_SUM_WORDS 10

#define VCT_NODE_NONE 0xFFFFFFFFu
#define VCT_NODE_FLAGGED 0x80000000u

// Image units of the brick pools (resolve and mipmap passes) and their texture units (cone
// tracing). The directional pool holds the inner levels' six-direction voxels (paper §9): the
// bricks of direction k (+x, -x, +y, -y, +z, -z: the way a cone travels) stacked k pool-depths up.
#define VCT_IMAGE_POOL 0
#define VCT_IMAGE_DIRECTIONAL_POOL 1
#define VCT_UNIT_POOL 11
#define VCT_UNIT_DIRECTIONAL_POOL 12

// Brick side in voxels: vertex-centred 3x3x3 bricks, voxel centres on node corners (paper §4.1).
#define VCT_BRICK 3
// Dense variant: one 3D texture holds every level's full lattice, stacked along z; the leaf level
// once, each inner level once (isotropic) or six times (anisotropic). Layer index: level * 6 + k.
#define VCT_MAX_DENSE_LAYERS 60
#define VCT_MAX_CONES 32
#define VCT_MAX_LATTICE 1023u

#endif
