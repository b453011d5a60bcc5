#include "renderer/methods/cssm/surface_shadow_maps.hpp"

#include "renderer/base/error.hpp"
#include "renderer/raytrace/ray_scene.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace bounce::methods::cssm {

CubeLookup cube_lookup(const glm::vec3& v, int face_size, float far_plane) {
    const glm::vec3 a = glm::abs(v);
    const int axis = a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
    const float major = std::max(a[axis], 1e-30f);
    CubeLookup lookup;
    lookup.face = 2 * axis + (v[axis] < 0.0f ? 1 : 0);
    const glm::vec2 uv(v[(axis + 1) % 3] / major, v[(axis + 2) % 3] / major);
    lookup.texel = (uv * 0.5f + 0.5f) * static_cast<float>(face_size);
    const glm::ivec2 pixel = glm::clamp(glm::ivec2(glm::floor(lookup.texel)), glm::ivec2(0), glm::ivec2(face_size - 1));
    lookup.pixel = static_cast<std::uint32_t>((lookup.face * face_size + pixel.y) * face_size + pixel.x);
    lookup.depth = major / far_plane;
    return lookup;
}

glm::vec3 cube_pixel_direction(std::uint32_t pixel, int face_size) {
    const std::uint32_t per_face = static_cast<std::uint32_t>(face_size * face_size);
    const int face = static_cast<int>(pixel / per_face), axis = face / 2;
    const int y = static_cast<int>((pixel % per_face) / face_size), x = static_cast<int>(pixel % face_size);
    glm::vec3 direction(0.0f);
    direction[axis] = (face & 1) ? -1.0f : 1.0f;
    direction[(axis + 1) % 3] = (static_cast<float>(x) + 0.5f) / static_cast<float>(face_size) * 2.0f - 1.0f;
    direction[(axis + 2) % 3] = (static_cast<float>(y) + 0.5f) / static_cast<float>(face_size) * 2.0f - 1.0f;
    return direction;
}

SurfaceShadowMaps bake_surface_shadow_maps(const scene::Scene& scene, const SurfaceAtlas& atlas,
                                           std::vector<std::uint32_t> order, const CubeMapSettings& settings,
                                           const raytrace::RayScene& rays, const BakeProgress& progress) {
    BOUNCE_CHECK(order.size() == atlas.texels.size(), "bake: traversal of {} texels for an atlas of {}", order.size(),
                 atlas.texels.size());
    BOUNCE_CHECK(settings.face_size >= 1 && settings.far_plane > settings.near_plane && settings.near_plane >= 0.0f,
                 "bake: bad cube-map settings (face {}, near {}, far {})", settings.face_size, settings.near_plane,
                 settings.far_plane);
    const auto started = std::chrono::steady_clock::now();
    SurfaceShadowMaps maps;
    maps.settings = settings;
    maps.order = std::move(order);
    maps.map_of_texel.assign(atlas.texels.size(), 0);
    maps.origins.resize(atlas.texels.size());
    std::vector<glm::vec3> normals(atlas.texels.size());
    for (std::size_t t = 0; t < atlas.texels.size(); ++t) {
        const AtlasTexel& texel = atlas.texels[t];
        const glm::mat4& transform = scene.objects[texel.object].transform;
        maps.origins[t] = glm::vec3(transform * glm::vec4(texel.position, 1.0f));
        normals[t] = glm::normalize(glm::transpose(glm::inverse(glm::mat3(transform))) * texel.normal);
    }
    for (std::uint32_t m = 0; m < maps.order.size(); ++m) maps.map_of_texel[maps.order[m]] = m;

    const int face = settings.face_size;
    const std::uint32_t pixels = static_cast<std::uint32_t>(6 * face * face);
    std::vector<glm::vec3> directions(pixels);
    std::vector<float> direction_length(pixels);
    for (std::uint32_t p = 0; p < pixels; ++p) {
        directions[p] = cube_pixel_direction(p, face);
        direction_length[p] = glm::length(directions[p]);
        directions[p] /= direction_length[p];
    }
    // A pixel is "don't care" when even its edge nearest the tangent plane is below it.
    const float below = -2.0f / static_cast<float>(face);

    DepthSequenceCompressor compressor(pixels);
    // Maps are traced a chunk at a time between progress reports (where a cancel stops the bake):
    // about a million cube-map pixels a chunk, a fraction of a second of rays, up to 32 maps.
    const std::uint32_t kChunk = std::clamp<std::uint32_t>((1u << 20) / pixels, 1, 32);
    std::vector<DepthInterval> intervals(static_cast<std::size_t>(kChunk) * pixels);
    const auto total = static_cast<std::uint32_t>(maps.order.size());
    for (std::uint32_t first = 0; first < total; first += kChunk) {
        const std::uint32_t count = std::min(kChunk, total - first);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, static_cast<std::size_t>(count) * 6), [&](const auto& range) {
            for (std::size_t job = range.begin(); job != range.end(); ++job) {
                const std::uint32_t m = static_cast<std::uint32_t>(job / 6);
                const std::uint32_t texel = maps.order[first + m];
                const glm::vec3 origin = maps.origins[texel], normal = normals[texel];
                const std::uint32_t face_first = static_cast<std::uint32_t>(job % 6) * face * face;
                for (std::uint32_t p = face_first; p < face_first + static_cast<std::uint32_t>(face * face); ++p) {
                    DepthInterval& out = intervals[static_cast<std::size_t>(m) * pixels + p];
                    if (glm::dot(directions[p], normal) < below) {
                        out = kDontCare;
                        continue;
                    }
                    // Linear depth z = t / |d| for the unnormalized pixel direction d.
                    const float to_z = 1.0f / direction_length[p];
                    const float tnear = settings.near_plane * direction_length[p];
                    const float tfar = settings.far_plane * direction_length[p];
                    const auto hit = rays.intersect(origin, directions[p], tnear, tfar);
                    if (!hit) {
                        out = admissible_interval(1.0f, 1.0f);
                        continue;
                    }
                    const float first_depth = hit->distance * to_z / settings.far_plane;
                    const auto second = rays.intersect(origin, directions[p], hit->distance * (1.0f + 1e-5f) + 1e-7f * tfar, tfar);
                    const float second_depth = second ? second->distance * to_z / settings.far_plane : 1.0f;
                    // A receiver on the second surface (another lampshade seen through this one's
                    // far side) must stay behind the first.
                    out = biased_interval(first_depth, second_depth, depth_bias(settings, second_depth));
                }
            }
        });
        compressor.append(std::span<const DepthInterval>(intervals.data(), static_cast<std::size_t>(count) * pixels), count);
        if (progress && !progress(first + count, total)) {
            throw Cancelled(fmt::format("bake cancelled after {} of {} cube maps", first + count, total));
        }
    }
    maps.depth = compressor.finish();
    maps.bake_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return maps;
}

float depth_bias(const CubeMapSettings& settings, float depth) {
    return settings.near_plane / settings.far_plane + depth * 2.0f / static_cast<float>(settings.face_size);
}

float cssm_visibility(const SurfaceShadowMaps& maps, std::uint32_t sender_texel, const glm::vec3& receiver, int pcf) {
    const int face = maps.settings.face_size;
    const CubeLookup centre = cube_lookup(receiver - maps.origins[sender_texel], face, maps.settings.far_plane);
    const std::uint32_t map = maps.map_of_texel[sender_texel];
    const float limit = centre.depth - depth_bias(maps.settings, centre.depth);
    const int radius = std::max(0, pcf / 2);
    const glm::ivec2 pixel = glm::clamp(glm::ivec2(glm::floor(centre.texel)), glm::ivec2(0), glm::ivec2(face - 1));
    int lit = 0, taps = 0;
    for (int dy = -radius; dy <= radius; ++dy)
        for (int dx = -radius; dx <= radius; ++dx) {
            const glm::ivec2 q = glm::clamp(pixel + glm::ivec2(dx, dy), glm::ivec2(0), glm::ivec2(face - 1));
            const std::uint32_t p = static_cast<std::uint32_t>((centre.face * face + q.y) * face + q.x);
            const float stored = static_cast<float>(maps.depth.depth(map, p)) / static_cast<float>(kDepthMax);
            lit += stored >= limit ? 1 : 0;
            ++taps;
        }
    return static_cast<float>(lit) / static_cast<float>(taps);
}

}  // namespace bounce::methods::cssm
