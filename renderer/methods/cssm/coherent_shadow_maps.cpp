#include "renderer/methods/cssm/coherent_shadow_maps.hpp"

#include "renderer/methods/cssm/atlas_traversal.hpp"
#include "renderer/raytrace/ray_scene.hpp"

#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <numbers>

namespace bounce::methods::cssm {

void csm_basis(const glm::vec3& d, glm::vec3& u, glm::vec3& w) {
    const glm::vec3 helper = std::abs(d.y) < 0.99f ? glm::vec3(0.0f, 1.0f, 0.0f) : glm::vec3(1.0f, 0.0f, 0.0f);
    u = glm::normalize(glm::cross(helper, d));
    w = glm::cross(d, u);
}

CoherentShadowMaps bake_coherent_shadow_maps(const raytrace::RayScene& rays, const glm::vec3& centre, float radius,
                                             int directions, int face_size) {
    const auto started = std::chrono::steady_clock::now();
    CoherentShadowMaps maps;
    maps.face_size = face_size;
    maps.centre = centre;
    maps.radius = std::max(radius, 1e-30f);
    // Evenly spread directions (a Fibonacci lattice), visited in a greedy nearest-neighbour order so
    // consecutive maps look from nearby directions.
    std::vector<glm::vec3> lattice(static_cast<std::size_t>(directions));
    const float golden = std::numbers::pi_v<float> * (3.0f - std::sqrt(5.0f));
    for (int i = 0; i < directions; ++i) {
        const float z = 1.0f - 2.0f * (static_cast<float>(i) + 0.5f) / static_cast<float>(directions);
        const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
        lattice[static_cast<std::size_t>(i)] = {r * std::cos(golden * static_cast<float>(i)), r * std::sin(golden * static_cast<float>(i)), z};
    }
    for (std::uint32_t i : greedy_walk(lattice)) maps.directions.emplace_back(lattice[i], 0.0f);

    maps.nearest_map.resize(6 * kCsmTableFace * kCsmTableFace);
    for (std::uint32_t cell = 0; cell < maps.nearest_map.size(); ++cell) {
        const glm::vec3 d = glm::normalize(cube_pixel_direction(cell, kCsmTableFace));
        float best = -2.0f;
        for (std::uint32_t k = 0; k < maps.directions.size(); ++k) {
            const float c = glm::dot(d, glm::vec3(maps.directions[k]));
            if (c > best) {
                best = c;
                maps.nearest_map[cell] = k;
            }
        }
    }

    const auto pixels = static_cast<std::uint32_t>(face_size * face_size);
    DepthSequenceCompressor compressor(pixels);
    std::vector<DepthInterval> intervals(static_cast<std::size_t>(pixels));
    const float span = 2.0f * maps.radius;
    for (const glm::vec4& direction : maps.directions) {
        const glm::vec3 d(direction);
        glm::vec3 u, w;
        csm_basis(d, u, w);
        tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, pixels, 64), [&](const auto& range) {
            for (std::uint32_t p = range.begin(); p != range.end(); ++p) {
                const float x = ((static_cast<float>(p % face_size) + 0.5f) / static_cast<float>(face_size) * 2.0f - 1.0f) * maps.radius;
                const float y = ((static_cast<float>(p / face_size) + 0.5f) / static_cast<float>(face_size) * 2.0f - 1.0f) * maps.radius;
                const glm::vec3 origin = centre - d * maps.radius + u * x + w * y;
                const auto first = rays.intersect(origin, d, 0.0f, span);
                if (!first) {
                    intervals[p] = admissible_interval(1.0f, 1.0f);
                    continue;
                }
                const auto second = rays.intersect(origin, d, first->distance * (1.0f + 1e-5f) + 1e-7f * span, span);
                intervals[p] = admissible_interval(first->distance / span, second ? second->distance / span : 1.0f);
            }
        });
        compressor.append(intervals, 1);
    }
    maps.depth = compressor.finish();
    maps.bake_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return maps;
}

bool csm_blocks(const CoherentShadowMaps& maps, const glm::vec3& from, const glm::vec3& to) {
    const glm::vec3 segment = to - from;
    if (!(glm::dot(segment, segment) > 0.0f)) return false;
    const CubeLookup cell = cube_lookup(segment, kCsmTableFace, 1.0f);
    const std::uint32_t k = maps.nearest_map[cell.pixel];
    const glm::vec3 d(maps.directions[k]);
    glm::vec3 u, w;
    csm_basis(d, u, w);
    const glm::vec3 offset = to - maps.centre;
    const glm::vec2 lateral = glm::vec2(glm::dot(offset, u), glm::dot(offset, w)) / maps.radius;
    if (std::abs(lateral.x) >= 1.0f || std::abs(lateral.y) >= 1.0f) return false;
    const glm::ivec2 pixel = glm::clamp(glm::ivec2(glm::floor((lateral * 0.5f + 0.5f) * static_cast<float>(maps.face_size))),
                                        glm::ivec2(0), glm::ivec2(maps.face_size - 1));
    const float stored = static_cast<float>(maps.depth.depth(k, static_cast<std::uint32_t>(pixel.y * maps.face_size + pixel.x))) /
                         static_cast<float>(kDepthMax);
    if (stored >= 1.0f) return false;
    const float span = 2.0f * maps.radius;
    const float bias = 2.0f / static_cast<float>(maps.face_size);
    const float depth_from = (glm::dot(from - maps.centre, d) + maps.radius) / span;
    const float depth_to = (glm::dot(offset, d) + maps.radius) / span;
    return stored > depth_from + bias && stored < depth_to - bias;
}

}  // namespace bounce::methods::cssm
