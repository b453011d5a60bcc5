// Coherent surface shadow maps (§3.2): a depth cube map at every atlas texel, baked in traversal
// order and compressed as one depth sequence, and the visibility query that reads them.
//
// Cube-map convention (shared with shaders/cssm/cssm_visibility.glsl): face f looks along axis
// a = f / 2 with sign + for even f; its pixel (x, y) covers the minor coordinates
// u = v[(a+1)%3] / |v[a]| and w = v[(a+2)%3] / |v[a]| in [-1, 1]. Depth is linear along the face
// axis (|v[a]|) over the far plane. The near plane keeps a texel from seeing its own surface; the
// far plane is the diameter of what the maps hold. Pixels in the texel's back half-space are
// "don't care".
#pragma once

#include "renderer/methods/cssm/depth_sequence.hpp"
#include "renderer/methods/cssm/surface_atlas.hpp"

#include <functional>

namespace bounce::raytrace {
class RayScene;
}

namespace bounce::methods::cssm {

struct CubeMapSettings {
    int face_size = 32;      // pixels per face side
    float near_plane = 0.0f; // world units
    float far_plane = 1.0f;  // world units
};

struct CubeLookup {
    std::uint32_t pixel = 0;  // (face * F + y) * F + x
    float depth = 0.0f;       // linear, over the far plane
    glm::vec2 texel{0.0f};    // continuous position within the face, in pixels
    int face = 0;
};

// Where direction `v` (need not be unit) falls on a cube map with faces of `face_size`.
CubeLookup cube_lookup(const glm::vec3& v, int face_size, float far_plane);
// The direction through the centre of cube pixel `pixel` (its major component is +-1).
glm::vec3 cube_pixel_direction(std::uint32_t pixel, int face_size);

struct SurfaceShadowMaps {
    CubeMapSettings settings;
    std::vector<std::uint32_t> order;         // texel indices, in baking order
    std::vector<std::uint32_t> map_of_texel;  // texel -> its map in the sequence
    std::vector<glm::vec3> origins;           // per texel: where its cube map sits (world)
    CompressedDepthMaps depth;
    double bake_seconds = 0.0;
};

// Reports maps baked so far and the total; returning false cancels the bake (bounce::Cancelled).
using BakeProgress = std::function<bool(std::uint32_t done, std::uint32_t total)>;

// Bakes a cube map at every texel of `atlas`, visited in `order`, against the geometry `rays`
// holds (first and second hits by ray casting through each pixel centre).
SurfaceShadowMaps bake_surface_shadow_maps(const scene::Scene& scene, const SurfaceAtlas& atlas,
                                           std::vector<std::uint32_t> order, const CubeMapSettings& settings,
                                           const raytrace::RayScene& rays, const BakeProgress& progress = {});

// The depth bias a receiver at linear depth `depth` (over the far plane) needs: the near plane
// plus one pixel's footprint, the slack of a surface seen at 45 degrees.
float depth_bias(const CubeMapSettings& settings, float depth);

// The fraction of the (pcf x pcf) pixels around the receiver's that find it unoccluded from
// `sender_texel`'s cube map: the CPU twin of the GPU query, for tests and benchmarks.
float cssm_visibility(const SurfaceShadowMaps& maps, std::uint32_t sender_texel, const glm::vec3& receiver, int pcf);

}  // namespace bounce::methods::cssm
