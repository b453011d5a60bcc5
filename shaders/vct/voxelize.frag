#version 450 core
// Appends two voxel fragments per rasterized lattice column, on the lattice points that bracket the
// surface along the projection axis (surface_voxels in vct/octree.glsl), each standing for half
// the column's area, with the material's diffuse albedo, normal and emission there. No colour
// output, no depth test.
#include "common/brdf.glsl"
#include "common/material.glsl"
#include "vct/octree.glsl"

layout(std430, binding = VCT_BINDING_FRAGMENTS) writeonly buffer Fragments { uint fragments[]; };

in vec3 g_position;
in vec3 g_normal;
in vec4 g_tangent;
in vec2 g_uv[2];
flat in float g_area;
flat in vec3 g_face_normal;

uniform uint u_lattice_max;  // largest lattice coordinate of the grid
uniform uint u_fragment_capacity;

void main() {
    int axis = dominant_axis(g_face_normal);
    SurfaceVoxels voxels = surface_voxels(g_position, g_face_normal, axis);
    SurfacePoint s = evaluate_surface(g_normal, g_tangent, g_uv, true);
    if (cut_out(s.alpha)) return;  // no voxels where the surface is cut away
    SurfaceMaterial m = SurfaceMaterial(s.base_color, s.metallic, s.roughness, s.specular, s.f0);
    uint albedo = packUnorm4x8(vec4(diffuse_albedo(m), 1.0));
    uint normal = packSnorm4x8(vec4(s.normal, 0.0));
    for (int i = 0; i < 2; ++i) {
        ivec3 lattice = voxels.lower + i * voxels.step;
        if (any(lessThan(lattice, ivec3(0))) || any(greaterThan(lattice, ivec3(u_lattice_max)))) continue;
        uint index = atomicAdd(counters[VCT_COUNTER_FRAGMENTS], 1u);
        if (index >= u_fragment_capacity) continue;  // counted: the host grows the list and voxelizes again
        uint base = index * VCT_FRAGMENT_WORDS;
        fragments[base + 0u] = pack_lattice(uvec3(lattice));
        fragments[base + 1u] = albedo;
        fragments[base + 2u] = normal;
        fragments[base + 3u] = floatBitsToUint(s.emissive.r);
        fragments[base + 4u] = floatBitsToUint(s.emissive.g);
        fragments[base + 5u] = floatBitsToUint(s.emissive.b);
        fragments[base + 6u] = floatBitsToUint(0.5 * g_area);
    }
}
