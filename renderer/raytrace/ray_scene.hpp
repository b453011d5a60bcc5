// Rigid objects as Embree instances of per-mesh scenes: the ray queries the path tracer and the
// `cssm` bake share. Moving an object updates its instance transform and rebuilds only the top
// level. Queries are thread-safe once built.
#pragma once

#include "renderer/scene/scene.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

namespace bounce::raytrace {

struct RayHit {
    std::uint32_t object = 0, primitive = 0, triangle = 0;
    float distance = 0.0f;  // ray parameter: world units when the direction is unit
    float u = 0.0f, v = 0.0f;  // barycentrics of vertices 1 and 2
};

class RayScene {
public:
    // Holds the objects `include` accepts (every object with a mesh when it is empty). The scene
    // must outlive the RayScene.
    explicit RayScene(const scene::Scene& scene, const std::function<bool(std::size_t object)>& include = {});
    ~RayScene();
    RayScene(const RayScene&) = delete;
    RayScene& operator=(const RayScene&) = delete;

    // Re-reads the held objects' transforms.
    void update_transforms();

    // The first surface along the ray within (tnear, tfar).
    std::optional<RayHit> intersect(const glm::vec3& origin, const glm::vec3& direction, float tnear,
                                    float tfar) const;
    bool occluded(const glm::vec3& origin, const glm::vec3& direction, float tnear, float tfar) const;

    std::uint64_t rays_traced() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace bounce::raytrace
