// Cone tracing through the octree (paper §5, §7): front-to-back accumulation with opacity
// corrected for the step length, each sample at the level whose voxels match the cone's diameter
// (quadrilinear: trilinear in two levels, blended). Shared by the per-pixel gather and the
// second-bounce gather at the leaves.
#include "common/math.glsl"
#include "vct/octree.glsl"

layout(binding = VCT_UNIT_POOL) uniform sampler3D u_pool;
layout(binding = VCT_UNIT_DIRECTIONAL_POOL) uniform sampler3D u_directional_pool;


uniform vec3 u_pool_texel;           // 1 / pool size in texels
uniform vec3 u_directional_pool_texel;
uniform float u_radiance_unscale;    // the pool holds radiance / this
uniform int u_cone_count;
uniform vec4 u_cones[VCT_MAX_CONES];  // tangent-space axis (z = normal), w = integral of cos over its cell
uniform float u_cone_tan;            // tangent of the diffuse cones' half aperture
uniform float u_step;                // step length in cone diameters
uniform float u_max_distance;
uniform float u_ao_lambda;

// Trilinear sample of level `level` at a world point, seen by a cone travelling along `direction`:
// zero outside the tree. Anisotropic inner levels blend the three directional voxels facing the
// cone by the squared components of its direction (they sum to one).
vec4 sample_level(vec3 world, uint level, vec3 direction) {
    float spacing = u_lattice_spacing * exp2(float(u_leaf_level - level));
    vec3 q = (world - u_grid_origin) / spacing;
    float side = exp2(float(level));
    if (any(lessThan(q, vec3(0.0))) || any(greaterThan(q, vec3(2.0 * side)))) return vec4(0.0);
#ifdef DENSE
    vec3 texel = q + 0.5;  // every lattice point is a texel of its level's layer
#else
    uvec3 cell = uvec3(min(floor(q * 0.5), vec3(side - 1.0)));
    uint node = find_node(cell, level);
    if (node == VCT_NODE_NONE) return vec4(0.0);
    vec3 in_brick = (q - 2.0 * vec3(cell)) + 0.5;
#endif
#ifdef ANISOTROPIC
    if (level < u_leaf_level) {
        vec3 share = direction * direction;
        vec4 value = vec4(0.0);
        for (uint axis = 0u; axis < 3u; ++axis) {
            if (share[axis] <= 0.0) continue;
            uint k = 2u * axis + (direction[axis] >= 0.0 ? 0u : 1u);
#ifdef DENSE
            vec3 uvw = (texel + vec3(0.0, 0.0, float(u_dense_z[level * 6u + k]))) * u_pool_texel;
            value += share[axis] * textureLod(u_pool, uvw, 0.0);
#else
            vec3 uvw = (vec3(directional_brick_origin(node, k)) + in_brick) * u_directional_pool_texel;
            value += share[axis] * textureLod(u_directional_pool, uvw, 0.0);
#endif
        }
        return value;
    }
#endif
#ifdef DENSE
    return textureLod(u_pool, (texel + vec3(0.0, 0.0, float(u_dense_z[level * 6u]))) * u_pool_texel, 0.0);
#else
    return textureLod(u_pool, (vec3(brick_origin(node)) + in_brick) * u_pool_texel, 0.0);
#endif
}

vec4 sample_quadrilinear(vec3 world, float level, vec3 direction) {
    uint fine = uint(ceil(level));
    uint coarse = uint(floor(level));
    vec4 value = sample_level(world, fine, direction);
    if (fine == coarse) return value;
    return mix(sample_level(world, coarse, direction), value, level - float(coarse));
}

struct ConeResult {
    vec3 radiance;
    float occlusion;  // the hit probability weighted by f(r)
};

ConeResult trace_cone(vec3 p, vec3 n, vec3 direction, float cone_tan) {
    ConeResult result = ConeResult(vec3(0.0), 0.0);
    float opacity = 0.0;
    float t = u_lattice_spacing;
    float leaf_level = float(u_leaf_level);
    while (t < u_max_distance && opacity < 0.99) {
        float diameter = max(2.0 * t * cone_tan, u_lattice_spacing);
        float level = clamp(leaf_level - log2(diameter / u_lattice_spacing), 0.0, leaf_level);
        float voxel = u_lattice_spacing * exp2(leaf_level - level);
        // A surface's own voxels reach about one voxel of each level from it (the mipmap's support)
        // and trilinear filtering one more: samples stay two voxels of their level above the
        // tangent plane, or the surface would occlude every cone it sends.
        float height = dot(direction, n) * t;
        vec3 offset = direction * t + n * max(0.0, 2.0 * voxel - height);
        vec4 v = sample_quadrilinear(p + offset, level, direction);
        float step = u_step * diameter;
        float alpha = saturate(v.a);
        if (alpha > 0.0) {
            // A voxel's opacity is for a path of its own size; this step is step/voxel of those.
            float corrected = 1.0 - pow(1.0 - min(alpha, 0.9999), step / voxel);
            float weight = (1.0 - opacity) * corrected;
            result.radiance += weight * v.rgb / alpha;
            result.occlusion += weight / (1.0 + u_ao_lambda * length(offset));
            opacity += weight;
        }
        t += step;
    }
    return result;
}

// The tangent frame of the cone axes (z along `n`).
mat3 cone_frame(vec3 n) { return tangent_frame(n); }
