#include "renderer/methods/cssm/cssm_bake.hpp"

#include "renderer/passes/light_geometry.hpp"
#include "renderer/reference/ray_scene.hpp"
#include "renderer/scene/shading.hpp"

#include <numeric>

namespace bounce::methods::cssm {

CssmBake bake_scene(const scene::Scene& scene, const BakeParameters& parameters, const BakeProgress& progress) {
    CssmBake bake;
    bake.parameters = parameters;
    std::vector<std::uint32_t> objects;
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o)
        if (scene.objects[o].mesh >= 0) objects.push_back(o);
    AtlasSettings atlas_settings;
    const float area = surface_area(scene, objects);
    atlas_settings.texel_size = texel_size_for(area, parameters.atlas_resolution);
    bake.atlas = build_surface_atlas(scene, objects, atlas_settings);

    const scene::Aabb bounds = scene.world_bounds();
    CubeMapSettings cube;
    cube.face_size = parameters.face_size;
    cube.far_plane = std::max(1.01f * glm::length(bounds.extent()), 1e-30f);
    // Close enough that a texel still sees a surface meeting its own at a right angle half a
    // texel away; far enough that its own plane stays out of the maps.
    cube.near_plane = 0.25f * atlas_settings.texel_size;
    const reference::RayScene rays(scene);
    bake.maps = bake_surface_shadow_maps(scene, bake.atlas, traverse_atlas(scene, bake.atlas, parameters.traversal), cube,
                                         rays, progress);

    complete_bake(scene, bake);
    return bake;
}

void complete_bake(const scene::Scene& scene, CssmBake& bake) {
    bake.geometry = passes::geometry_fingerprint(scene);
    const std::size_t texels = bake.atlas.texels.size();
    std::vector<float> areas(texels);
    bake.normals.resize(texels);
    bake.albedo.resize(texels);
    bake.emission.resize(texels);
    for (std::size_t t = 0; t < texels; ++t) {
        const AtlasTexel& texel = bake.atlas.texels[t];
        const glm::mat4& transform = scene.objects[texel.object].transform;
        bake.normals[t] = glm::normalize(glm::transpose(glm::inverse(glm::mat3(transform))) * texel.normal);
        areas[t] = texel.area;
        const scene::Material& material = scene.material(texel.material);
        bake.albedo[t] = scene::diffuse_albedo(scene::SurfaceMaterial::from(material));
        bake.emission[t] = material.emissive;
    }
    bake.tree = build_radiosity_tree(bake.maps.origins, bake.normals, areas);
}

}  // namespace bounce::methods::cssm
