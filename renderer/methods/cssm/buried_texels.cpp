#include "renderer/methods/cssm/buried_texels.hpp"

#include "renderer/base/error.hpp"
#include "renderer/raytrace/ray_scene.hpp"
#include "renderer/scene/mesh_utils.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace bounce::methods::cssm {
namespace {

// The hemisphere's rays: the normal, and four at 60 degrees from it.
constexpr int kRays = 5;

const scene::Primitive& hit_primitive(const scene::Scene& scene, const raytrace::RayHit& hit) {
    const scene::Object& object = scene.objects[hit.object];
    return scene.meshes[static_cast<std::size_t>(object.mesh)].primitives[hit.primitive];
}

bool double_sided(const scene::Scene& scene, const raytrace::RayHit& hit) {
    const int material = hit_primitive(scene, hit).material;
    return material >= 0 && static_cast<std::size_t>(material) < scene.materials.size() &&
           scene.materials[static_cast<std::size_t>(material)].double_sided;
}

}  // namespace

bool buried_point(const scene::Scene& scene, const raytrace::RayScene& rays, const glm::vec3& point,
                  const glm::vec3& normal, float reach) {
    const glm::vec3 n = glm::normalize(normal);
    const glm::vec3 u(scene::fallback_tangent(n)), v = glm::cross(n, u);
    const float c = 0.5f, s = 0.8660254f;  // 60 degrees
    const std::array<glm::vec3, kRays> directions = {n, c * n + s * u, c * n - s * u, c * n + s * v, c * n - s * v};
    // Off the surface by a little of the reach, so that the point's own face is not met.
    const glm::vec3 origin = point + 1e-4f * reach * n;
    // Inside a column taller than the reach, the ray along the normal meets nothing: misses say nothing.
    // Faces through the point itself (a solid's side standing on a sample point) and faces met
    // edge-on say nothing either: whether a ray meets them turns on rounding, which a scene's scale
    // changes.
    int backs = 0, fronts = 0;
    for (const glm::vec3& direction : directions) {
        const auto hit = rays.intersect(origin, direction, 1e-3f * reach, reach);
        if (!hit) continue;
        const glm::vec3 face = scene::world_triangle_cross(scene.objects[hit->object].transform, hit_primitive(scene, *hit),
                                                            hit->triangle);
        const float facing = glm::dot(glm::normalize(face), direction);
        if (std::abs(facing) < 1e-3f) continue;
        ++(!double_sided(scene, *hit) && facing > 0.0f ? backs : fronts);
    }
    return backs > fronts;
}

BuriedTexels unbury_texels(const scene::Scene& scene, const raytrace::RayScene& rays, SurfaceAtlas& atlas, float reach,
                           const BakeProgress& progress) {
    BuriedTexels counts;
    const auto total = static_cast<std::uint32_t>(atlas.texels.size());
    for (std::uint32_t t = 0; t < total; ++t) {
        if (progress && t % kProgressTexels == 0 && !progress(t, total)) {
            throw Cancelled(fmt::format("bake cancelled after {} of {} texels looked at for solids", t, total));
        }
        AtlasTexel& texel = atlas.texels[t];
        const glm::mat4& transform = scene.objects[texel.object].transform;
        const glm::vec3 normal = glm::normalize(glm::transpose(glm::inverse(glm::mat3(transform))) * texel.normal);
        // The texel's distinct points (repeats stand for cells off its chart).
        std::array<glm::vec3, kTexelSamples> kept{};
        int distinct = 0, left = 0;
        for (int i = 0; i < kTexelSamples; ++i) {
            const glm::vec3& sample = texel.samples[static_cast<std::size_t>(i)];
            bool repeat = false;
            for (int j = 0; j < i && !repeat; ++j) repeat = texel.samples[static_cast<std::size_t>(j)] == sample;
            if (repeat) continue;
            ++distinct;
            if (!buried_point(scene, rays, glm::vec3(transform * glm::vec4(sample, 1.0f)), normal, reach)) {
                kept[static_cast<std::size_t>(left++)] = sample;
            }
        }
        if (left == distinct) continue;
        if (left == 0) {
            texel.area = 0.0f;
            ++counts.wholly;
            continue;
        }
        texel.area *= static_cast<float>(left) / static_cast<float>(distinct);
        // The kept point nearest their centroid: the centroid itself may be buried where a solid's
        // corner leaves an L of the patch.
        texel.position = point_nearest_centroid(std::span<const glm::vec3>(kept.data(), static_cast<std::size_t>(left)));
        for (int i = 0; i < kTexelSamples; ++i) texel.samples[static_cast<std::size_t>(i)] = kept[static_cast<std::size_t>(i % left)];
        ++counts.partly;
    }
    return counts;
}

}  // namespace bounce::methods::cssm
