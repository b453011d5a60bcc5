// Vertex attributes derived from a triangle list: normals and tangent frames, for meshes whose
// source has none (glTF files without NORMAL or TANGENT, the built-in scenes); and triangles' world
// areas, summed or sampled.
#pragma once

#include "renderer/scene/scene.hpp"

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace bounce::scene {

// All three components finite.
inline bool finite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Area-weighted vertex normals of `primitive`'s triangles (positions and indices). A vertex that
// only zero-area or non-finite triangles touch gets +Y rather than NaN.
std::vector<glm::vec3> vertex_normals(const Primitive& primitive);

// A unit tangent orthogonal to `normal` (w = +1), for vertices without a UV parameterization.
glm::vec4 fallback_tangent(const glm::vec3& normal);

// Tangent frames from the UV derivatives of `primitive`'s triangles (`uvs` per vertex; the primitive's
// normals must be set), orthogonal to the normal, with the handedness in w.
std::vector<glm::vec4> uv_tangents(const Primitive& primitive, std::span<const glm::vec2> uvs);

// The cross product of `primitive`'s triangle `triangle`'s edges once `transform` places it in the
// world: its geometric normal (by its winding) times twice its area.
glm::vec3 world_triangle_cross(const glm::mat4& transform, const Primitive& primitive, std::size_t triangle);
// The area of `primitive`'s triangle `triangle` once `transform` places it in the world.
float world_triangle_area(const glm::mat4& transform, const Primitive& primitive, std::size_t triangle);

// The world-space area of every object's triangles (a mesh placed twice counts twice).
double surface_area(const Scene& scene);

// Picks the scene's triangles with probability proportional to their world area (point clouds,
// surface samples). Triangles of zero or non-finite area are never picked.
class AreaWeightedTriangles {
public:
    struct Triangle {
        std::uint32_t object = 0, primitive = 0, triangle = 0;
    };
    explicit AreaWeightedTriangles(const Scene& scene);
    bool empty() const { return triangles_.empty(); }
    // The triangle that `u` (uniform in [0, 1)) falls on along the cumulative area; not on an empty set.
    const Triangle& pick(double u) const;

private:
    std::vector<Triangle> triangles_;
    std::vector<double> cumulative_;
    double total_ = 0.0;
};

}  // namespace bounce::scene
