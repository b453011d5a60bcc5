#version 450 core
// A second bounce: every leaf voxel with a surface gathers the first bounce's radiance from the
// octree with the diffuse cones around its mean normal, and adds what its mean albedo reflects
// (Lambertian) to its radiance. The bricks and mipmaps are then rebuilt from the result, so the
// per-pixel gather sees light that bounced twice.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "vct/cone.glsl"
#include "vct/leaf_data.glsl"

uniform uint u_slot_count;

void main() {
    uint slot = thread_index();
    if (slot >= u_slot_count) return;
    float area = leaf_sum(slot, 0u);
    if (!(area > 0.0)) return;
    vec3 normal_sum = vec3(leaf_sum(slot, 4u), leaf_sum(slot, 5u), leaf_sum(slot, 6u));
    if (!(dot(normal_sum, normal_sum) > 0.0)) return;  // opposite faces cancel: no side to gather from
    vec3 n = normalize(normal_sum);
    vec3 albedo = vec3(leaf_sum(slot, 1u), leaf_sum(slot, 2u), leaf_sum(slot, 3u)) / area;
    uvec3 lattice = slot_lattice(slot);
    vec3 p = u_grid_origin + vec3(lattice) * u_lattice_spacing;
    mat3 frame = cone_frame(n);
    vec3 irradiance = vec3(0.0);
    for (int i = 0; i < u_cone_count; ++i) {
        irradiance += u_cones[i].w * trace_cone(p, n, frame * u_cones[i].xyz, u_cone_tan).radiance;
    }
    vec3 radiance = leaf_light_at(slot) + finite_or_zero(albedo * INV_PI * irradiance * u_radiance_unscale);
    set_leaf_light(slot, radiance);
    atomicMax(counters[VCT_COUNTER_MAX_RADIANCE], floatBitsToUint(max(radiance.r, max(radiance.g, radiance.b))));
}
