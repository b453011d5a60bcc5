// Method `vct`: voxel cone tracing on a GPU-built sparse voxel octree (Crassin et al. 2011,
// [vct] in docs/references.md). Direct light as `direct` renders it, plus one bounce of
// diffuse indirect light gathered by a few wide cones through the octree's mipmapped radiance;
// or the paper's ambient occlusion.
#pragma once

#include "renderer/methods/registry.hpp"

#include <glm/glm.hpp>

#include <vector>

namespace bounce::methods::vct {

MethodInfo method_info();

// A diffuse cone: its axis in the tangent frame (z along the normal) and the integral of cos over
// the directions nearer its axis than any other's (a Voronoi cell of the hemisphere).
struct DiffuseCone {
    glm::vec3 axis{0.0f, 0.0f, 1.0f};
    float weight = 0.0f;
};

// `count` cones spread evenly over the hemisphere (a spherical Fibonacci set); their weights sum to
// pi, so a uniformly lit hemisphere (radiance L) gathers exactly pi L.
std::vector<DiffuseCone> diffuse_cones(int count);

// The half aperture, in radians, that gives `count` cones a solid angle of 2 pi / count each.
float default_cone_aperture(int count);

}  // namespace bounce::methods::vct
