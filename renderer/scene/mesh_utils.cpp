#include "renderer/scene/mesh_utils.hpp"

#include <algorithm>

namespace bounce::scene {

// The cross product's length is twice the triangle's area, so summing unnormalized face normals
// weights each face by its area.
std::vector<glm::vec3> vertex_normals(const Primitive& primitive) {
    std::vector<glm::vec3> sums(primitive.positions.size(), glm::vec3(0.0f));
    for (std::size_t t = 0; t + 2 < primitive.indices.size(); t += 3) {
        const std::uint32_t i0 = primitive.indices[t], i1 = primitive.indices[t + 1],
                            i2 = primitive.indices[t + 2];
        const glm::vec3 weighted = glm::cross(primitive.positions[i1] - primitive.positions[i0],
                                              primitive.positions[i2] - primitive.positions[i0]);
        if (!finite(weighted)) continue;
        sums[i0] += weighted;
        sums[i1] += weighted;
        sums[i2] += weighted;
    }
    for (glm::vec3& normal : sums) {
        const float length = glm::length(normal);
        normal = length > 1e-30f && std::isfinite(length) ? normal / length : glm::vec3(0.0f, 1.0f, 0.0f);
    }
    return sums;
}

glm::vec4 fallback_tangent(const glm::vec3& normal) {
    const glm::vec3 helper =
        std::abs(normal.x) < 0.9f ? glm::vec3(1.0f, 0.0f, 0.0f) : glm::vec3(0.0f, 1.0f, 0.0f);
    return {glm::normalize(helper - normal * glm::dot(normal, helper)), 1.0f};
}

// Per-triangle tangent frames from the UV derivatives, accumulated per vertex, then made orthogonal
// to the normal (Gram-Schmidt) with the handedness from the accumulated bitangent, as MikkTSpace does.
// glTF's v runs down the image while a normal map's green axis points up it, so the bitangent is taken
// along -v (MikkTSpace on 1 - v): a plainly mapped quad gets w = +1. A vertex without UV area gets
// fallback_tangent.
std::vector<glm::vec4> uv_tangents(const Primitive& primitive, std::span<const glm::vec2> uvs) {
    const std::size_t vertex_count = primitive.positions.size();
    std::vector<glm::vec3> tangent_sums(vertex_count, glm::vec3(0.0f));
    std::vector<glm::vec3> bitangent_sums(vertex_count, glm::vec3(0.0f));
    for (std::size_t t = 0; t + 2 < primitive.indices.size(); t += 3) {
        const std::uint32_t i0 = primitive.indices[t], i1 = primitive.indices[t + 1],
                            i2 = primitive.indices[t + 2];
        const glm::vec3 edge1 = primitive.positions[i1] - primitive.positions[i0];
        const glm::vec3 edge2 = primitive.positions[i2] - primitive.positions[i0];
        const glm::vec2 duv1 = uvs[i1] - uvs[i0];
        const glm::vec2 duv2 = uvs[i2] - uvs[i0];
        const float determinant = duv1.x * duv2.y - duv2.x * duv1.y;
        if (std::abs(determinant) < 1e-20f || !std::isfinite(determinant)) continue;  // no UV area
        const glm::vec3 tangent = (edge1 * duv2.y - edge2 * duv1.y) / determinant;
        const glm::vec3 bitangent = (edge1 * duv2.x - edge2 * duv1.x) / determinant;
        if (!finite(tangent) || !finite(bitangent)) continue;
        for (const std::uint32_t i : {i0, i1, i2}) {
            tangent_sums[i] += tangent;
            bitangent_sums[i] += bitangent;
        }
    }
    std::vector<glm::vec4> tangents(vertex_count);
    for (std::size_t v = 0; v < vertex_count; ++v) {
        const glm::vec3& normal = primitive.normals[v];
        const glm::vec3 orthogonal = tangent_sums[v] - normal * glm::dot(normal, tangent_sums[v]);
        const float length = glm::length(orthogonal);
        if (!(length > 1e-30f) || !std::isfinite(length)) {
            tangents[v] = fallback_tangent(normal);
            continue;
        }
        const glm::vec3 tangent = orthogonal / length;
        const float handedness =
            glm::dot(glm::cross(normal, tangent), bitangent_sums[v]) < 0.0f ? -1.0f : 1.0f;
        tangents[v] = {tangent, handedness};
    }
    return tangents;
}

glm::vec3 world_triangle_cross(const glm::mat4& transform, const Primitive& primitive, std::size_t triangle) {
    glm::vec3 p[3];
    for (int c = 0; c < 3; ++c) p[c] = glm::vec3(transform * glm::vec4(primitive.positions[primitive.indices[3 * triangle + c]], 1.0f));
    return glm::cross(p[1] - p[0], p[2] - p[0]);
}

float world_triangle_area(const glm::mat4& transform, const Primitive& primitive, std::size_t triangle) {
    return 0.5f * glm::length(world_triangle_cross(transform, primitive, triangle));
}

double surface_area(const Scene& scene) {
    double area = 0.0;
    for (const Object& object : scene.objects) {
        if (object.mesh < 0) continue;
        for (const Primitive& primitive : scene.meshes[static_cast<std::size_t>(object.mesh)].primitives)
            for (std::size_t t = 0; t < primitive.triangle_count(); ++t) {
                const float triangle = world_triangle_area(object.transform, primitive, t);
                if (std::isfinite(triangle)) area += triangle;
            }
    }
    return area;
}

AreaWeightedTriangles::AreaWeightedTriangles(const Scene& scene) {
    for (std::size_t o = 0; o < scene.objects.size(); ++o) {
        const Object& object = scene.objects[o];
        if (object.mesh < 0) continue;
        const auto& primitives = scene.meshes[static_cast<std::size_t>(object.mesh)].primitives;
        for (std::size_t p = 0; p < primitives.size(); ++p) {
            for (std::size_t t = 0; t < primitives[p].triangle_count(); ++t) {
                const double area = world_triangle_area(object.transform, primitives[p], t);
                if (!(area > 0.0) || !std::isfinite(area)) continue;
                triangles_.push_back({static_cast<std::uint32_t>(o), static_cast<std::uint32_t>(p), static_cast<std::uint32_t>(t)});
                total_ += area;
                cumulative_.push_back(total_);
            }
        }
    }
}

const AreaWeightedTriangles::Triangle& AreaWeightedTriangles::pick(double u) const {
    const auto found = std::lower_bound(cumulative_.begin(), cumulative_.end(), u * total_);
    return triangles_[static_cast<std::size_t>(
        std::min<std::ptrdiff_t>(found - cumulative_.begin(), static_cast<std::ptrdiff_t>(triangles_.size()) - 1))];
}

}  // namespace bounce::scene
