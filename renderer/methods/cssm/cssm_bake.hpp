// What `cssm` precomputes for a scene, and the parameters it depends on: the surface atlas, its
// traversal and the compressed cube maps baked along it, and the radiosity hierarchy over the
// texels. All rigid geometry is baked as one group at its current transforms.
#pragma once

#include "renderer/methods/cssm/atlas_traversal.hpp"
#include "renderer/methods/cssm/radiosity_tree.hpp"
#include "renderer/methods/cssm/surface_shadow_maps.hpp"

#include <cstdint>
#include <string>

namespace bounce::methods::cssm {

struct BakeParameters {
    float atlas_resolution = 32.0f;  // texels along the square root of the surface area
    int face_size = 32;
    Traversal traversal = Traversal::spiral;

    bool operator==(const BakeParameters&) const = default;
};

struct CssmBake {
    BakeParameters parameters;
    std::uint64_t geometry = 0;  // passes::geometry_fingerprint at bake time
    SurfaceAtlas atlas;
    SurfaceShadowMaps maps;
    RadiosityTree tree;
    std::vector<glm::vec3> normals;   // per texel: world normal at bake time
    std::vector<glm::vec3> albedo;    // per texel: diffuse albedo
    std::vector<glm::vec3> emission;  // per texel: emitted radiance
};

// Bakes every object of the scene at its current transform. `progress` as for
// bake_surface_shadow_maps (it may cancel).
CssmBake bake_scene(const scene::Scene& scene, const BakeParameters& parameters, const BakeProgress& progress = {});

// Fills what is derived from the atlas and the scene rather than stored (normals, materials, the
// tree): after baking, or after loading a bake from disk.
void complete_bake(const scene::Scene& scene, CssmBake& bake);

}  // namespace bounce::methods::cssm
