// The surface atlas of `cssm` (§3.2.3 of [cssm] in docs/references.md): the surfaces of
// a set of rigid objects cut into charts and packed into one texel grid, each texel a small patch
// with position, normal, area and material. Texels are the senders and receivers of the radiosity
// solution and the points where depth cube maps are baked.
//
// Charts come from the mesh's second UV set when it is a valid parametrization (every coordinate
// inside [0,1], no two triangles covering the same texel), otherwise from our own segmentation:
// edge-connected triangles of one primitive whose normals stay within a cone of the chart's first
// triangle, projected onto that triangle's plane (so no chart folds over itself), packed by shelves.
//
// A double-sided material's surface is two surfaces, each lit and seen on its own side: a
// lampshade's inside, lit by its bulb, lights the ceiling while its outside stays dim. Its charts
// are copied facing the other way (charts of their own, at the same places), so every texel
// receives and sends on one side, as the radiosity solve assumes.
#pragma once

#include "renderer/scene/scene.hpp"

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace bounce::methods::cssm {

// Points of a texel's own surface where its direct light is sampled: the centres of its 4x4 sub-cells
// that lie on its chart's triangles (those repeated where fewer do). A texel's light from its centre
// alone misses what changes within it: in the furnished room the bulbs sit level with the middle of
// their shades, whose one row of texels fell in the lamp pole's shadow while the upper half of each
// shade, the room's brightest surface, is lit. 2x2 sub-cells caught that half at 64 texels a side
// and missed it at 48.
inline constexpr int kTexelSamplesPerSide = 4;
inline constexpr int kTexelSamples = kTexelSamplesPerSide * kTexelSamplesPerSide;

struct AtlasTexel {
    glm::vec3 position{0.0f};  // object (mesh) space
    glm::vec3 normal{0.0f, 0.0f, 1.0f};  // object space, unit
    float area = 0.0f;  // world units at build time (rigid motions keep it)
    std::uint32_t object = 0;  // index into Scene::objects
    std::uint32_t chart = 0;
    int material = -1;
    glm::vec2 uv0{0.0f}, uv1{0.0f};  // where its material's textures are read
    std::int32_t x = 0, y = 0;  // where it sits in the atlas
    std::array<glm::vec3, kTexelSamples> samples{};  // object space, on its surface (above)
};

struct AtlasChart {
    std::uint32_t object = 0;
    glm::ivec2 min{0}, max{0};  // texel bounds in the atlas, max exclusive
    glm::vec3 centroid{0.0f};   // object space, area-weighted
};

struct AtlasSettings {
    float texel_size = 0.01f;  // texel edge, in the objects' world units at their current scale
    float chart_cone_degrees = 30.0f;  // automatic charts: largest normal deviation from the seed
    bool use_uv1 = true;  // take the glTF's second UV set when it is valid
};

struct SurfaceAtlas {
    int width = 0, height = 0;
    std::vector<AtlasTexel> texels;
    std::vector<AtlasChart> charts;
    std::vector<std::int32_t> texel_at;  // width * height: texel index or -1
    std::vector<std::uint32_t> objects;  // the objects it covers
    std::vector<std::string> uv1_objects;  // objects whose charts came from their second UV set
    float surface_area = 0.0f;  // of the covered triangles, world units (a double-sided one once)

    std::int32_t at(int x, int y) const {
        return x < 0 || y < 0 || x >= width || y >= height ? -1 : texel_at[static_cast<std::size_t>(y) * width + x];
    }
};

// Builds the atlas of `objects` (indices into scene.objects) at their current transforms' scale.
// Throws InputError when texel_size is not positive or the atlas would exceed `max_texels`.
SurfaceAtlas build_surface_atlas(const scene::Scene& scene, const std::vector<std::uint32_t>& objects,
                                 const AtlasSettings& settings, std::size_t max_texels = 1u << 22);

// The texel edge that gives about `texels_per_side`^2 texels over `area`.
float texel_size_for(float area, float texels_per_side);

// The world-space surface area of `objects`.
float surface_area(const scene::Scene& scene, const std::vector<std::uint32_t>& objects);
// The part of it whose material is double-sided: the atlas covers it twice, once per side.
float double_sided_area(const scene::Scene& scene, const std::vector<std::uint32_t>& objects);

// Of a texel's points on its surface, the one nearest their centroid (which itself may lie off the
// surface, or outside an L-shaped part of it). Points about as near (symmetric parts: ties within a
// thousandth of the points' spread) go to the first, whatever the scene's scale and its rounding.
glm::vec3 point_nearest_centroid(std::span<const glm::vec3> points);

}  // namespace bounce::methods::cssm
