// What `cssm` precomputes for a scene, and the parameters it depends on. Objects are baked in
// groups that move rigidly as one: every object that stays put together (the static group, in
// world space), and each moving object alone (in its own space, with a CSM as well). A group is a
// surface atlas, its traversal and the compressed cube maps baked along it. Over all groups'
// texels, at their current places, stands one radiosity hierarchy.
#pragma once

#include "renderer/methods/cssm/atlas_traversal.hpp"
#include "renderer/methods/cssm/coherent_shadow_maps.hpp"
#include "renderer/methods/cssm/radiosity_tree.hpp"
#include "renderer/methods/cssm/surface_shadow_maps.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

namespace bounce::methods::cssm {

struct BakeParameters {
    float atlas_resolution = 32.0f;  // texels along the square root of the scene's surface area
    int face_size = 32;
    Traversal traversal = Traversal::spiral;
    int csm_directions = 256;  // maps per moving object's CSM

    bool operator==(const BakeParameters&) const = default;
};

struct BakeGroup {
    std::vector<std::uint32_t> objects;
    bool moving = false;  // one object, baked in its own space
    std::string key;      // the cache key of what it depends on
    SurfaceAtlas atlas;
    SurfaceShadowMaps maps;  // origins in the group's frame: world (static) or object space (moving)
    std::optional<CoherentShadowMaps> csm;  // moving groups
    bool loaded = false;  // came from the cache
};

struct CssmBake {
    BakeParameters parameters;
    float texel_size = 0.0f;
    std::vector<BakeGroup> groups;  // the static group first (when any object is static)
    std::vector<std::uint32_t> moving;  // objects baked as moving
    std::vector<glm::mat4> baked_transforms;  // per object, as the bake saw it
    // Per texel of all groups, in group order, at the objects' current places.
    std::vector<std::uint32_t> texel_group;
    std::vector<std::uint32_t> group_first_texel;  // + end
    std::vector<glm::vec3> positions, normals, albedo, emission;
    std::vector<float> areas;
    std::vector<glm::vec3> samples;  // kTexelSamples per texel: where its direct light is sampled (AtlasTexel)
    RadiosityTree tree;

    std::size_t texel_count() const { return positions.size(); }
    std::size_t uncompressed_bytes() const;
    std::size_t compressed_bytes() const;
    std::uint32_t cube_maps() const;
};

struct BakeOptions {
    std::optional<std::filesystem::path> cache_dir;
    // Fraction of all groups' maps done, and what is being baked; false cancels (bounce::Cancelled).
    std::function<bool(double fraction, const std::string& stage)> progress;
};

// Bakes the scene with `moving` objects (sorted indices) as moving groups, loading groups from and
// storing them to the cache directory when one is given.
CssmBake bake_scene(const scene::Scene& scene, const BakeParameters& parameters, const std::vector<std::uint32_t>& moving,
                    const BakeOptions& options = {});

// Places every group's texels where their objects are now, with their materials, and rebuilds the
// hierarchy over them: after baking, loading, or moving objects.
void place_texels(const scene::Scene& scene, CssmBake& bake);

// The transform that takes world points into a group's bake frame.
glm::mat4 world_to_group(const scene::Scene& scene, const BakeGroup& group);

}  // namespace bounce::methods::cssm
