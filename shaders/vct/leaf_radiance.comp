#version 450 core
// Turns the flux each leaf slot received into the radiance its surface leaves with: irradiance is
// flux over the surface area the slot's fragments stand for, reflected by their mean diffuse albedo
// (Lambertian), plus their mean emission. Also finds the largest radiance, which scales the brick
// pool into half-float range.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "common/math.glsl"
#include "vct/octree.glsl"
#include "vct/leaf_data.glsl"

uniform uint u_slot_count;

void main() {
    uint slot = thread_index();
    if (slot >= u_slot_count) return;
    vec3 flux = leaf_light_at(slot);
    float area = leaf_sum(slot, 0u);
    vec3 radiance = vec3(0.0);
    if (area > 0.0) {
        vec3 albedo = vec3(leaf_sum(slot, 1u), leaf_sum(slot, 2u), leaf_sum(slot, 3u)) / area;
        vec3 emission = vec3(leaf_sum(slot, 7u), leaf_sum(slot, 8u), leaf_sum(slot, 9u)) / area;
        float world_area = area * u_lattice_spacing * u_lattice_spacing;
        radiance = finite_or_zero(albedo * INV_PI * flux / world_area + emission);
    } else if (any_positive(flux)) {
        atomicAdd(counters[VCT_COUNTER_STRAY_SLOTS], 1u);
    }
    set_leaf_light(slot, radiance);
    atomicMax(counters[VCT_COUNTER_MAX_RADIANCE], floatBitsToUint(max(radiance.r, max(radiance.g, radiance.b))));
}
