// The assumption moving objects rest on (§3.3): a CSM answers only for points outside its object's
// convex hull, so no other surface may reach inside the hull of a moving object. This finds the
// places where one does, by GJK between each moving object's hull (shrunk by a hair, so resting on
// a floor is not an overlap) and the other objects' triangles.
#pragma once

#include "renderer/scene/scene.hpp"

#include <cstdint>
#include <vector>

namespace bounce::methods::cssm {

// GJK: whether the convex hulls of two point sets intersect.
bool convex_hulls_intersect(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b);

struct HullOverlap {
    std::uint32_t moving = 0;  // object whose hull is entered
    std::uint32_t other = 0;   // object with surface inside it
};

std::vector<HullOverlap> find_hull_overlaps(const scene::Scene& scene, const std::vector<std::uint32_t>& moving);

}  // namespace bounce::methods::cssm
