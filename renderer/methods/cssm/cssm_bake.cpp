#include "renderer/methods/cssm/cssm_bake.hpp"

#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/methods/cssm/bake_cache.hpp"
#include "renderer/methods/cssm/buried_texels.hpp"
#include "renderer/raytrace/ray_scene.hpp"
#include "renderer/scene/shading.hpp"

#include <algorithm>

namespace bounce::methods::cssm {
namespace {

// A scene holding only `object`, at the identity: what a moving group is baked from.
scene::Scene object_alone(const scene::Scene& scene, std::uint32_t object) {
    scene::Scene alone;
    alone.materials = scene.materials;
    alone.meshes.push_back(scene.meshes[scene.objects[object].mesh]);
    scene::Object copy = scene.objects[object];
    copy.mesh = 0;
    copy.transform = copy.initial_transform = glm::mat4(1.0f);
    alone.objects.push_back(copy);
    return alone;
}

struct Progress {
    const BakeOptions& options;
    std::uint64_t done = 0, total = 1;
    // A point where the bake may stop: reports the progress so far, throws Cancelled when told to.
    void checkpoint(const std::string& stage) const {
        if (options.progress && !options.progress(static_cast<double>(done) / static_cast<double>(total), stage)) {
            throw Cancelled(fmt::format("bake cancelled at {}", stage));
        }
    }
    BakeProgress for_stage(const std::string& stage) {
        if (!options.progress) return {};
        return [this, stage, base = done](std::uint32_t finished, std::uint32_t) {
            return options.progress(static_cast<double>(base + finished) / static_cast<double>(total), stage);
        };
    }
};

void bake_group(const scene::Scene& scene, BakeGroup& group, const BakeParameters& parameters, float texel_size,
                Progress& progress) {
    AtlasSettings atlas_settings;
    atlas_settings.texel_size = texel_size;
    const std::string& first_name = scene.objects[group.objects.front()].name;
    if (group.moving) {
        const std::uint32_t object = group.objects.front();
        const scene::Scene alone = object_alone(scene, object);
        group.atlas = build_surface_atlas(alone, {0}, atlas_settings);
        progress.checkpoint("surface atlas (" + first_name + ")");
        const scene::Aabb bounds = alone.meshes[0].bounds;
        const float radius = std::max(0.5f * glm::length(bounds.extent()) * 1.01f, 1e-30f);
        // The maps hold this object alone, so they need reach no farther than its diameter; a
        // receiver beyond still compares against what lies between.
        const CubeMapSettings cube{parameters.face_size, 0.25f * texel_size, 2.0f * radius};
        const raytrace::RayScene rays(alone);
        auto order = traverse_atlas(alone, group.atlas, parameters.traversal);
        progress.checkpoint("traversal (" + first_name + ")");
        group.maps = bake_surface_shadow_maps(alone, group.atlas, std::move(order), cube, rays,
                                              progress.for_stage("depth cube maps (" + first_name + ")"));
        progress.done += group.atlas.texels.size();
        group.csm = bake_coherent_shadow_maps(rays, bounds.center(), radius, parameters.csm_directions, parameters.face_size);
        progress.done += static_cast<std::uint64_t>(parameters.csm_directions);
        progress.checkpoint("coherent shadow maps (" + first_name + ")");
        for (AtlasTexel& texel : group.atlas.texels) texel.object = object;
        for (AtlasChart& chart : group.atlas.charts) chart.object = object;
        group.atlas.objects = {object};
        return;
    }
    group.atlas = build_surface_atlas(scene, group.objects, atlas_settings);
    progress.checkpoint("surface atlas");
    scene::Aabb bounds;
    for (std::uint32_t o : group.objects) bounds.extend(scene.objects[o].world_bounds(scene.meshes[scene.objects[o].mesh]));
    CubeMapSettings cube{parameters.face_size, 0.25f * texel_size, std::max(1.01f * glm::length(bounds.extent()), 1e-30f)};
    const std::vector<std::uint32_t>& members = group.objects;
    const raytrace::RayScene rays(scene, [&](std::size_t o) {
        return std::binary_search(members.begin(), members.end(), static_cast<std::uint32_t>(o));
    });
    // Reported at the stage's start: the work estimate counts cube maps, and this stage is not one.
    const BakeProgress still_wanted = [&](std::uint32_t, std::uint32_t) {
        progress.checkpoint("texels inside solids");
        return true;
    };
    const BuriedTexels buried = unbury_texels(scene, rays, group.atlas, texel_size, still_wanted);
    if (buried.partly + buried.wholly > 0) {
        log::info("cssm", "{} of {} texels partly inside a solid, moved to the rest of their patch; {} wholly",
                  buried.partly, group.atlas.texels.size(), buried.wholly);
    }
    progress.checkpoint("texels inside solids");
    auto order = traverse_atlas(scene, group.atlas, parameters.traversal);
    progress.checkpoint("traversal");
    group.maps = bake_surface_shadow_maps(scene, group.atlas, std::move(order), cube, rays, progress.for_stage("depth cube maps"));
    progress.done += group.atlas.texels.size();
}

}  // namespace

std::size_t CssmBake::uncompressed_bytes() const {
    std::size_t bytes = 0;
    for (const BakeGroup& group : groups) bytes += group.maps.depth.uncompressed_bytes() + (group.csm ? group.csm->depth.uncompressed_bytes() : 0);
    return bytes;
}

std::size_t CssmBake::compressed_bytes() const {
    std::size_t bytes = 0;
    for (const BakeGroup& group : groups) bytes += group.maps.depth.compressed_bytes() + (group.csm ? group.csm->depth.compressed_bytes() : 0);
    return bytes;
}

std::uint32_t CssmBake::cube_maps() const {
    std::uint32_t maps = 0;
    for (const BakeGroup& group : groups) maps += group.maps.depth.maps;
    return maps;
}

glm::mat4 world_to_group(const scene::Scene& scene, const BakeGroup& group) {
    return group.moving ? glm::inverse(scene.objects[group.objects.front()].transform) : glm::mat4(1.0f);
}

CssmBake bake_scene(const scene::Scene& scene, const BakeParameters& parameters, const std::vector<std::uint32_t>& moving,
                    const BakeOptions& options) {
    CssmBake bake;
    bake.parameters = parameters;
    bake.moving = moving;
    std::vector<std::uint32_t> all, fixed;
    for (std::uint32_t o = 0; o < scene.objects.size(); ++o) {
        if (scene.objects[o].mesh < 0) continue;
        all.push_back(o);
        if (!std::binary_search(moving.begin(), moving.end(), o)) fixed.push_back(o);
    }
    // One texel size for every group, from the whole scene: moving an object in or out of the static
    // group changes no density.
    bake.texel_size = texel_size_for(surface_area(scene, all), parameters.atlas_resolution);
    if (!fixed.empty()) {
        BakeGroup group;
        group.objects = fixed;
        bake.groups.push_back(std::move(group));
    }
    for (std::uint32_t o : moving) {
        if (scene.objects[o].mesh < 0) continue;
        BakeGroup group;
        group.objects = {o};
        group.moving = true;
        bake.groups.push_back(std::move(group));
    }
    Progress progress{options};
    progress.total = 0;
    for (BakeGroup& group : bake.groups) {
        group.key = group_key(scene, group.objects, group.moving, parameters, bake.texel_size);
        if (options.cache_dir) {
            if (auto cached = load_cached_group(*options.cache_dir, group.key, group.objects)) {
                cached->objects = group.objects;
                cached->moving = group.moving;
                cached->loaded = true;
                group = std::move(*cached);
                continue;
            }
        }
        // Work estimate: one unit per cube map or CSM map.
        const float covered = surface_area(scene, group.objects) + double_sided_area(scene, group.objects);
        progress.total += static_cast<std::uint64_t>(covered / (bake.texel_size * bake.texel_size)) +
                          (group.moving ? static_cast<std::uint64_t>(parameters.csm_directions) : 0u);
    }
    progress.total = std::max<std::uint64_t>(progress.total, 1);
    for (BakeGroup& group : bake.groups) {
        if (group.loaded) continue;
        bake_group(scene, group, parameters, bake.texel_size, progress);
        if (options.cache_dir) {
            try {
                store_cached_group(*options.cache_dir, group);
            } catch (const std::exception& error) {
                log::warn("cssm", "bake not cached: {}", error.what());
            }
        }
    }
    if (options.progress) options.progress(1.0, "done");
    bake.baked_transforms.resize(scene.objects.size());
    for (std::size_t o = 0; o < scene.objects.size(); ++o) bake.baked_transforms[o] = scene.objects[o].transform;
    place_texels(scene, bake);
    return bake;
}

void place_texels(const scene::Scene& scene, CssmBake& bake) {
    bake.positions.clear();
    bake.normals.clear();
    bake.albedo.clear();
    bake.emission.clear();
    bake.areas.clear();
    bake.samples.clear();
    bake.texel_group.clear();
    bake.group_first_texel.clear();
    for (std::uint32_t g = 0; g < bake.groups.size(); ++g) {
        const BakeGroup& group = bake.groups[g];
        bake.group_first_texel.push_back(static_cast<std::uint32_t>(bake.positions.size()));
        const glm::mat4 to_world = glm::inverse(world_to_group(scene, group));
        for (std::size_t t = 0; t < group.atlas.texels.size(); ++t) {
            const AtlasTexel& texel = group.atlas.texels[t];
            const glm::mat4& transform = scene.objects[texel.object].transform;
            bake.positions.push_back(glm::vec3(to_world * glm::vec4(group.maps.origins[t], 1.0f)));
            // In the group's frame as the bake placed its texels: a moving object's own space, else the world then.
            const glm::mat4 to_frame = group.moving ? glm::mat4(1.0f) : bake.baked_transforms[texel.object];
            for (const glm::vec3& sample : texel.samples) bake.samples.push_back(glm::vec3(to_world * to_frame * glm::vec4(sample, 1.0f)));
            bake.normals.push_back(glm::normalize(glm::transpose(glm::inverse(glm::mat3(transform))) * texel.normal));
            // The material with its textures at the texel's centre (a texel averages nothing finer).
            const scene::TexturedMaterial material = scene::textured_material(scene, scene.material(texel.material), texel.uv0, texel.uv1);
            // A texel sends light in proportion to the surface it covers: none where alphaMode MASK
            // cuts the surface away, the fraction alpha where BLEND makes it partial.
            bake.areas.push_back(texel.area * material.coverage);
            bake.albedo.push_back(scene::diffuse_albedo(material.surface));
            bake.emission.push_back(material.emitted);
            bake.texel_group.push_back(g);
        }
    }
    bake.group_first_texel.push_back(static_cast<std::uint32_t>(bake.positions.size()));
    bake.tree = build_radiosity_tree(bake.positions, bake.normals, bake.areas);
}

}  // namespace bounce::methods::cssm
