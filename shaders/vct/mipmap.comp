#version 450 core
// Mipmapping (paper §4.2.3), one level at a time from the leaves up: each voxel of a level-L brick
// gathers the 27 level-(L+1) voxels around the same point with the Gaussian weights 1/4, 1/2, 1/4
// per axis. Those lie in the node's children or, on its border, in its neighbours' children; every
// brick holding a voxel agrees on its value, so any one of them answers.
//
// Isotropic: the weighted average. ANISOTROPIC (paper §9): for each of the six directions a cone
// can travel, each row of three voxels along it is composited front to back (lengths 1/2, 1, 1/2
// of a child voxel, so the row spans the parent voxel), then the nine rows are averaged with their
// weights: a wall stays opaque across itself at every level instead of fading to 1/2, 1/4, ...
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "vct/octree.glsl"
#ifdef ONE_SIDED_LEAVES
#include "vct/leaf_data.glsl"
#endif

layout(binding = VCT_IMAGE_POOL, rgba16f) coherent uniform image3D u_pool;
layout(binding = VCT_IMAGE_DIRECTIONAL_POOL, rgba16f) coherent uniform image3D u_directional_pool;

const float kWeight[3] = float[3](0.25, 0.5, 0.25);

uniform uint u_level;  // the level written; u_level + 1 is read
uniform uint u_first_node;
uniform uint u_node_count;

vec4 load_brick(uint node, ivec3 offset, uint level, uint direction) {
#ifdef ANISOTROPIC
    if (level < u_leaf_level) return imageLoad(u_directional_pool, directional_brick_origin(node, direction) + offset);
#endif
    return imageLoad(u_pool, brick_origin(node) + offset);
}

#ifndef DENSE
// The level-`level` voxel at lattice point `p` (lattice of that level), zero where the tree is empty.
vec4 fetch_voxel(uint level, ivec3 p, uint parent, ivec3 parent_base, uint direction) {
    int side = 1 << level;
    if (any(lessThan(p, ivec3(0))) || any(greaterThan(p, ivec3(2 * side)))) return vec4(0.0);
    uint first_child = node_child[parent];
    // Inside the parent's own children: no descent.
    if (first_child != 0u && all(greaterThanEqual(p, parent_base)) && all(lessThanEqual(p, parent_base + 4))) {
        ivec3 local = min((p - parent_base) >> 1, ivec3(1));
        uint child = first_child + uint(local.x + 2 * local.y + 4 * local.z);
        return load_brick(child, p - (parent_base + 2 * local), level, direction);
    }
    // Any node whose brick holds the point: the cell p/2 (slot 0 or 1) or, for an even coordinate,
    // the cell before it (slot 2).
    for (int k = 0; k < 8; ++k) {
        ivec3 cell;
        bool valid = true;
        for (int axis = 0; axis < 3; ++axis) {
            bool before = ((k >> axis) & 1) != 0;
            cell[axis] = (p[axis] >> 1) - (before ? 1 : 0);
            valid = valid && cell[axis] >= 0 && cell[axis] < side && (!before || (p[axis] & 1) == 0);
        }
        if (!valid) continue;
        uint node = find_node(uvec3(cell), level);
        if (node != VCT_NODE_NONE) return load_brick(node, p - 2 * cell, level, direction);
    }
    return vec4(0.0);
}
#endif

#ifdef ANISOTROPIC
#ifdef ONE_SIDED_LEAVES
// Per direction k (a cone travelling towards +axis for even k, -axis for odd): the share of a leaf's
// light the cone meets, its surface's projection across the axis where the surface faces the cone,
// max(0, -travel . m) / max |m| for the leaf's mean normal m (SparseVoxelOctree::Filtering). Where
// the normals cancel (a thin closed object within the voxel: m's length falls towards 0) it tends
// to every direction's 1, as without.
void leaf_light_shares(ivec3 lattice, out float share[6]) {
    for (int k = 0; k < 6; ++k) share[k] = 1.0;
    if (any(lessThan(lattice, ivec3(0)))) return;
    uint slot = lattice_slot(uvec3(lattice));
    if (slot == VCT_NODE_NONE || !(leaf_sum(slot, 0u) > 0.0)) return;
    vec3 mean_normal = vec3(leaf_sum(slot, 4u), leaf_sum(slot, 5u), leaf_sum(slot, 6u)) / leaf_sum(slot, 0u);
    vec3 projected = abs(mean_normal);
    float dominant = max(projected.x, max(projected.y, projected.z));
    if (!(dominant > 0.0)) return;
    float spread = clamp(length(mean_normal), 0.0, 1.0);
    for (int k = 0; k < 6; ++k) {
        float facing = (k % 2 == 0 ? -1.0 : 1.0) * mean_normal[k / 2];
        share[k] = mix(1.0, max(facing, 0.0) / dominant, spread);
    }
}
#endif

// Composites the rows of `values` (the 27 child voxels around the parent's, x fastest) along
// direction `direction` and averages them with their weights.
vec4 directional_average(vec4 values[27], uint direction) {
    int axis = int(direction / 2u);
    bool forward = (direction % 2u) == 0u;  // the cone travels towards +axis: -1 is in front
    const float kLength[3] = float[3](0.5, 1.0, 0.5);  // in child voxels: the row spans the parent
    ivec3 stride = ivec3(1, 3, 9);
    int along = stride[axis], across_u = stride[(axis + 1) % 3], across_v = stride[(axis + 2) % 3];
    vec4 sum = vec4(0.0);
    for (int v = 0; v < 3; ++v) {
        for (int u = 0; u < 3; ++u) {
            vec3 radiance = vec3(0.0);
            float transmittance = 1.0;
            for (int step = 0; step < 3; ++step) {  // front to back
                int s = forward ? step : 2 - step;
                vec4 child = values[u * across_u + v * across_v + s * along];
                float alpha = clamp(child.a, 0.0, 1.0);
                if (alpha <= 0.0) continue;
                float corrected = 1.0 - pow(max(1.0 - alpha, 0.0), kLength[s]);
                radiance += transmittance * child.rgb * (corrected / alpha);
                transmittance *= 1.0 - corrected;
            }
            sum += kWeight[u] * kWeight[v] * vec4(radiance, 1.0 - transmittance);
        }
    }
    return sum;
}
#endif

#ifdef DENSE
// The level-`level` voxel at lattice point `p`, seen along `direction` where the level is
// anisotropic: a texel of that level's layer.
vec4 fetch_dense(uint level, ivec3 p, uint direction) {
    int side = (1 << (level + 1u)) + 1;
    if (any(lessThan(p, ivec3(0))) || any(greaterThanEqual(p, ivec3(side)))) return vec4(0.0);
#ifdef ANISOTROPIC
    uint k = level < u_leaf_level ? direction : 0u;
#else
    uint k = 0u;
#endif
    return imageLoad(u_pool, p + ivec3(0, 0, u_dense_z[level * 6u + k]));
}
#endif

void main() {
    uint index = thread_index();
#ifdef ANISOTROPIC
    // Above the leaves every direction reads its own voxels; from the isotropic leaves one thread
    // reads the 27 voxels once and writes all six directions.
    const bool from_leaves = u_level + 1u == u_leaf_level;
    uint directions = from_leaves ? 1u : 6u;
#else
    const uint directions = 1u;
#endif
#ifdef DENSE
    uint side = (1u << (u_level + 1u)) + 1u;
    if (index >= side * side * side * directions) return;
    uint direction = index % directions;
    uint point = index / directions;
    ivec3 target = ivec3(point % side, (point / side) % side, point / (side * side));
    ivec3 center = 2 * target;
#else
    if (index >= u_node_count * 27u * directions) return;
    uint direction = index % directions;
    uint node = u_first_node + index / (27u * directions);
    uint voxel = (index / directions) % 27u;
    ivec3 target = ivec3(voxel % 3u, (voxel / 3u) % 3u, voxel / 9u);  // in the node's brick
    ivec3 base = 4 * ivec3(node_coord[node].xyz);  // the children's lattice starts here
    ivec3 center = base + 2 * target;
#endif
    vec4 values[27];
    for (int i = 0; i < 27; ++i) {
        ivec3 o = ivec3(i % 3, (i / 3) % 3, i / 9) - 1;
#ifdef DENSE
        values[i] = fetch_dense(u_level + 1u, center + o, direction);
#else
        values[i] = fetch_voxel(u_level + 1u, center + o, node, base, direction);
#endif
    }
#ifdef ANISOTROPIC
#ifdef ONE_SIDED_LEAVES
    float shares[27][6];  // read above the leaves only
    if (from_leaves) {
        for (int i = 0; i < 27; ++i) leaf_light_shares(center + ivec3(i % 3, (i / 3) % 3, i / 9) - 1, shares[i]);
    }
#endif
    for (uint k = 0u; k < 6u; ++k) {
        if (!from_leaves && k != direction) continue;
        vec4 value;
#ifdef ONE_SIDED_LEAVES
        if (from_leaves) {
            vec4 seen[27];
            for (int i = 0; i < 27; ++i) seen[i] = vec4(values[i].rgb * shares[i][k], values[i].a);
            value = directional_average(seen, k);
        } else {
            value = directional_average(values, k);
        }
#else
        value = directional_average(values, k);
#endif
#ifdef DENSE
        imageStore(u_pool, target + ivec3(0, 0, u_dense_z[u_level * 6u + k]), value);
#else
        imageStore(u_directional_pool, directional_brick_origin(node, k) + target, value);
#endif
    }
#else
    vec4 sum = vec4(0.0);
    for (int i = 0; i < 27; ++i) sum += kWeight[i % 3] * kWeight[(i / 3) % 3] * kWeight[i / 9] * values[i];
#ifdef DENSE
    imageStore(u_pool, target + ivec3(0, 0, u_dense_z[u_level * 6u]), sum);
#else
    imageStore(u_pool, brick_origin(node) + target, sum);
#endif
#endif
}
