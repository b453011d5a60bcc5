// Texels whose patch lies partly inside another solid: a floor's texels under a column, or under a
// wall standing on it. A texel sends and receives from one point and bakes its depth cube map there;
// where that point is inside a column, the map sees only the column's inside, and the texel's light
// (its lit part's, beside the column) reaches nothing. In the bench atrium, columns 0.7 m across
// stand on a floor of texels of about a metre, where the sun's patches meet the columns' feet.
#pragma once

#include "renderer/methods/cssm/surface_atlas.hpp"
#include "renderer/methods/cssm/surface_shadow_maps.hpp"

#include <cstddef>
#include <cstdint>

namespace bounce::raytrace {
class RayScene;
}

namespace bounce::methods::cssm {

struct BuriedTexels {
    std::size_t partly = 0;  // texels with some sample points buried, moved to the rest
    std::size_t wholly = 0;  // texels with every sample point buried: their area goes to nothing
};

// Whether a point of a surface facing `normal` lies inside a solid: of rays over the hemisphere it
// faces that meet a face within `reach`, more meet the back of a one-sided face than a front.
bool buried_point(const scene::Scene& scene, const raytrace::RayScene& rays, const glm::vec3& point,
                  const glm::vec3& normal, float reach);

// Takes out of each texel of `atlas` (whose objects `rays` holds, at their current places) the part
// of its patch that lies inside a solid: its buried sample points give way to its others (repeated,
// as for a texel partly off its chart), its area shrinks by their share, and its point (where it
// sends, receives and bakes its map) moves to the point left nearest their centroid. A texel buried whole
// keeps its point and has no area. `reach`: how far a face may be to bury a point (a texel's edge).
// `progress` hears of every kProgressTexels texels (80 rays each); false cancels (bounce::Cancelled).
inline constexpr std::uint32_t kProgressTexels = 4096;
BuriedTexels unbury_texels(const scene::Scene& scene, const raytrace::RayScene& rays, SurfaceAtlas& atlas, float reach,
                           const BakeProgress& progress = {});

}  // namespace bounce::methods::cssm
