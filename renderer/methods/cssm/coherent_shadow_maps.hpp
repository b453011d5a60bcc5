// Coherent shadow maps (CSM, the paper's predecessor, §3.1 and §3.3): for an object that moves,
// orthographic depth maps of it alone from many directions around it, compressed as one depth
// sequence like the surface maps. They answer whether a segment between two points outside the
// object's convex hull passes through the object, wherever the object has moved (the query is
// made in the object's own space).
//
// Conventions shared with shaders/cssm/cssm_tree.glsl: map k looks along directions[k] (unit);
// its basis is csm_basis(d); pixel (x, y) covers [-R, R]^2 around the bounding sphere's centre c
// (x along u, y along w), its depth is (dot(p - c, d) + R) / 2R. A 6 x 16 x 16 cube table maps any
// direction to its nearest map.
#pragma once

#include "renderer/methods/cssm/depth_sequence.hpp"
#include "renderer/methods/cssm/surface_shadow_maps.hpp"

namespace bounce::methods::cssm {

constexpr int kCsmTableFace = 16;

struct CoherentShadowMaps {
    int face_size = 32;
    glm::vec3 centre{0.0f};  // object space
    float radius = 1.0f;
    std::vector<glm::vec4> directions;          // unit, in the sequence's order
    std::vector<std::uint32_t> nearest_map;     // 6 * kCsmTableFace^2: direction cell -> map
    CompressedDepthMaps depth;
    double bake_seconds = 0.0;
};

// (u, w): the map plane's axes for direction d.
void csm_basis(const glm::vec3& d, glm::vec3& u, glm::vec3& w);

// Bakes `directions` maps of `face_size`^2 of the geometry `rays` holds (in object space), bounded
// by the sphere (centre, radius).
CoherentShadowMaps bake_coherent_shadow_maps(const raytrace::RayScene& rays, const glm::vec3& centre, float radius,
                                             int directions, int face_size);

// Whether the segment from `from` to `to` (object space) passes through the object: the CPU twin of
// the GPU query.
bool csm_blocks(const CoherentShadowMaps& maps, const glm::vec3& from, const glm::vec3& to);

}  // namespace bounce::methods::cssm
