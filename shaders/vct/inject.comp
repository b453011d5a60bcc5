#version 450 core
// Light injection (paper §8.2): every texel of a light-view map is a photon that carries the flux
// the light sends through it, splatted into the leaf slots of the voxels where it lands (counted
// per voxel: a photon that reaches both of its pair counts twice).
// The flux per texel is common/light_view.glsl's photon_flux.
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#include "common/light_view.glsl"
#include "vct/octree.glsl"
#include "vct/leaf_data.glsl"

layout(binding = 0) uniform sampler2DArray u_view_position;
layout(binding = 1) uniform sampler2DArray u_view_normal;

uniform int u_layer;
uniform int u_size;
uniform vec3 u_view_forward;
uniform float u_texel_measure;
uniform int u_light_type;
uniform vec3 u_light_position;
uniform vec3 u_light_direction;
uniform vec3 u_light_radiant;
uniform float u_light_cos_inner;
uniform float u_light_cos_outer;

void main() {
    uint index = thread_index();
    if (index >= uint(u_size * u_size)) return;
    ivec3 texel = ivec3(int(index) % u_size, int(index) / u_size, u_layer);
    vec4 position = texelFetch(u_view_position, texel, 0);
    if (position.w == 0.0) return;
    vec3 normal = texelFetch(u_view_normal, texel, 0).xyz;
    PunctualLight light = PunctualLight(u_light_type, u_light_position, u_light_direction, u_light_radiant,
                                        u_light_cos_inner, u_light_cos_outer);
    vec3 flux = photon_flux(light, position.xyz, u_view_forward, u_texel_measure);
    if (!any_positive(flux)) return;
    vec3 n = safe_normalize(normal, u_view_forward);
    SurfaceVoxels voxels = surface_voxels(position.xyz, n, dominant_axis(n));
    // Half the flux to each voxel of the pair, as voxelization gives each half the area.
    for (int i = 0; i < 2; ++i) {
        ivec3 lattice = voxels.lower + i * voxels.step;
        uint slot = any(lessThan(lattice, ivec3(0))) ? VCT_NODE_NONE : lattice_slot(uvec3(lattice));
        if (slot == VCT_NODE_NONE) {
            atomicAdd(counters[VCT_COUNTER_DROPPED_PHOTONS], 1u);
            continue;
        }
        atomicAdd(counters[VCT_COUNTER_INJECTED_PHOTONS], 1u);
        add_leaf_light(slot * 3u, 0.5 * flux.r);
        add_leaf_light(slot * 3u + 1u, 0.5 * flux.g);
        add_leaf_light(slot * 3u + 2u, 0.5 * flux.b);
    }
}
