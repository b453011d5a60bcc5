#include "renderer/methods/cssm/hull_overlap.hpp"

#include <algorithm>
#include <array>

namespace bounce::methods::cssm {
namespace {

glm::vec3 support(const std::vector<glm::vec3>& points, const glm::vec3& d) {
    glm::vec3 best = points[0];
    float best_dot = glm::dot(best, d);
    for (const glm::vec3& p : points) {
        const float dot = glm::dot(p, d);
        if (dot > best_dot) {
            best_dot = dot;
            best = p;
        }
    }
    return best;
}

bool same_direction(const glm::vec3& a, const glm::vec3& b) { return glm::dot(a, b) > 0.0f; }

// Reduces the simplex (newest point first) to the feature nearest the origin and sets the next
// search direction; true when the simplex encloses the origin.
bool next_simplex(std::array<glm::vec3, 4>& s, int& size, glm::vec3& d) {
    const glm::vec3 a = s[0];
    const glm::vec3 ao = -a;
    if (size == 2) {
        const glm::vec3 ab = s[1] - a;
        if (same_direction(ab, ao)) {
            d = glm::cross(glm::cross(ab, ao), ab);
            if (glm::dot(d, d) < 1e-30f) return true;  // the origin lies on the segment
        } else {
            size = 1;
            d = ao;
        }
        return false;
    }
    if (size == 3) {
        const glm::vec3 b = s[1], c = s[2];
        const glm::vec3 ab = b - a, ac = c - a, abc = glm::cross(ab, ac);
        if (same_direction(glm::cross(abc, ac), ao)) {
            if (same_direction(ac, ao)) {
                s = {a, c, {}, {}};
                size = 2;
                d = glm::cross(glm::cross(ac, ao), ac);
            } else {
                s = {a, b, {}, {}};
                size = 2;
                return next_simplex(s, size, d);
            }
        } else if (same_direction(glm::cross(ab, abc), ao)) {
            s = {a, b, {}, {}};
            size = 2;
            return next_simplex(s, size, d);
        } else {
            const float side = glm::dot(abc, ao);
            if (std::abs(side) < 1e-30f) return true;  // in the triangle's plane, inside it
            if (side > 0.0f) {
                d = abc;
            } else {
                s = {a, c, b, {}};
                d = -abc;
            }
        }
        return false;
    }
    // Tetrahedron.
    const glm::vec3 b = s[1], c = s[2], dd = s[3];
    const glm::vec3 ab = b - a, ac = c - a, ad = dd - a;
    const glm::vec3 abc = glm::cross(ab, ac), acd = glm::cross(ac, ad), adb = glm::cross(ad, ab);
    if (same_direction(abc, ao)) {
        s = {a, b, c, {}};
        size = 3;
        return next_simplex(s, size, d);
    }
    if (same_direction(acd, ao)) {
        s = {a, c, dd, {}};
        size = 3;
        return next_simplex(s, size, d);
    }
    if (same_direction(adb, ao)) {
        s = {a, dd, b, {}};
        size = 3;
        return next_simplex(s, size, d);
    }
    return true;
}

}  // namespace

bool convex_hulls_intersect(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
    if (a.empty() || b.empty()) return false;
    auto minkowski = [&](const glm::vec3& d) { return support(a, d) - support(b, -d); };
    glm::vec3 d = a[0] - b[0];
    if (glm::dot(d, d) < 1e-30f) d = glm::vec3(1.0f, 0.0f, 0.0f);
    std::array<glm::vec3, 4> simplex{minkowski(d)};
    int size = 1;
    d = -simplex[0];
    for (int iteration = 0; iteration < 64; ++iteration) {
        if (glm::dot(d, d) < 1e-30f) return true;  // the origin is on the simplex
        const glm::vec3 p = minkowski(d);
        if (glm::dot(p, d) <= 0.0f) return false;  // a separating direction
        for (int i = size; i > 0; --i) simplex[i] = simplex[i - 1];
        simplex[0] = p;
        ++size;
        if (next_simplex(simplex, size, d)) return true;
    }
    return false;  // no progress: treat as touching, not overlapping
}

std::vector<HullOverlap> find_hull_overlaps(const scene::Scene& scene, const std::vector<std::uint32_t>& moving) {
    std::vector<HullOverlap> overlaps;
    for (std::uint32_t m : moving) {
        const scene::Object& object = scene.objects[m];
        if (object.mesh < 0) continue;
        std::vector<glm::vec3> hull;
        for (const scene::Primitive& primitive : scene.meshes[object.mesh].primitives)
            for (const glm::vec3& p : primitive.positions) hull.push_back(glm::vec3(object.transform * glm::vec4(p, 1.0f)));
        if (hull.empty()) continue;
        glm::vec3 centroid(0.0f);
        for (const glm::vec3& p : hull) centroid += p / static_cast<float>(hull.size());
        scene::Aabb bounds;
        for (glm::vec3& p : hull) {
            p = centroid + (p - centroid) * 0.999f;  // touching is not overlapping
            bounds.extend(p);
        }
        for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
            const scene::Object& other = scene.objects[o];
            if (o == m || other.mesh < 0) continue;
            const scene::Aabb other_bounds = other.world_bounds(scene.meshes[other.mesh]);
            if (glm::any(glm::lessThan(other_bounds.max, bounds.min)) || glm::any(glm::greaterThan(other_bounds.min, bounds.max))) continue;
            bool found = false;
            for (const scene::Primitive& primitive : scene.meshes[other.mesh].primitives) {
                for (std::size_t t = 0; t < primitive.triangle_count() && !found; ++t) {
                    std::vector<glm::vec3> triangle(3);
                    for (int c = 0; c < 3; ++c) {
                        triangle[c] = glm::vec3(other.transform * glm::vec4(primitive.positions[primitive.indices[3 * t + c]], 1.0f));
                    }
                    found = convex_hulls_intersect(hull, triangle);
                }
                if (found) break;
            }
            if (found) overlaps.push_back({m, o});
        }
    }
    return overlaps;
}

}  // namespace bounce::methods::cssm
