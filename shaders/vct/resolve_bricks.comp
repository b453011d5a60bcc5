#version 450 core
// Fills every leaf's 3x3x3 brick from the slots that own its voxels: premultiplied radiance (scaled
// into half-float range) and opacity 1 where a surface crosses the voxel. A border voxel is read
// from the neighbouring leaf that owns it, so bricks agree where they meet: the gather form of the
// paper's brick-border transfer, with no neighbour links.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "vct/octree.glsl"
#include "vct/leaf_data.glsl"

layout(binding = VCT_IMAGE_POOL, rgba16f) writeonly uniform image3D u_pool;

uniform uint u_leaf_count;
uniform float u_radiance_scale;

void main() {
    uint index = thread_index();
#ifdef DENSE
    // One voxel per lattice point, in the leaf level's layer.
    if (index >= u_dense_side * u_dense_side * u_dense_side) return;
    uvec3 lattice = slot_lattice(index);
    vec4 value = leaf_sum(index, 0u) > 0.0 ? vec4(leaf_light_at(index) * u_radiance_scale, 1.0) : vec4(0.0);
    imageStore(u_pool, ivec3(lattice) + ivec3(0, 0, u_dense_z[u_leaf_level * 6u]), value);
#else
    if (index >= u_leaf_count * 27u) return;
    uint leaf = leaf_node(index / 27u);
    uint voxel = index % 27u;
    uvec3 offset = uvec3(voxel % 3u, (voxel / 3u) % 3u, voxel / 9u);
    uvec3 lattice = node_coord[leaf].xyz * 2u + offset;
    vec4 value = vec4(0.0);
    uint slot = lattice_slot(lattice);
    if (slot != VCT_NODE_NONE && leaf_sum(slot, 0u) > 0.0) value = vec4(leaf_light_at(slot) * u_radiance_scale, 1.0);
    imageStore(u_pool, brick_origin(leaf) + ivec3(offset), value);
#endif
}
