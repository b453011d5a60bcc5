// Light-view maps (reflective shadow maps): the scene rasterized from every light with power, one
// view per spot or directional light and six per point light, each texel holding the world
// position, normal and diffuse albedo of the surface the light reaches first. Every texel is a
// photon: `photon_flux` in shaders/common/light_view.glsl gives the flux it carries. Views whose
// frustum misses the scene's bounds (cube faces looking out of a room's corner) are not drawn. Maps are kept while the
// lights' places, the object transforms and the size stay the same: a light's colour or intensity
// alone draws none (the maps hold no power; whether a light has any decides its views).
#pragma once

#include "renderer/passes/pass_context.hpp"

#include <cstdint>
#include <vector>

namespace bounce::passes {

class LightViewMaps {
public:
    struct View {
        std::size_t light = 0;
        glm::mat4 view_projection{1.0f};
        glm::vec3 forward{0.0f, 0.0f, -1.0f};
        glm::vec3 origin{0.0f};  // the light's position; orthographic views: the eye behind the scene
        bool orthographic = false;
        // Perspective views: the solid angle of a texel on the view axis (it falls off as cos^3
        // off-axis). Orthographic views: the area of a texel.
        float texel_measure = 0.0f;
    };

    // Draws the maps when anything they depend on changed; returns true when it drew. A light's
    // colour or intensity alone draws nothing: the maps hold places, normals and albedo, and their
    // users take each light's power as they use them (vct's photons, isr's VPLs), so each compares
    // the lights' power itself.
    bool render(const PassContext& context, int size);
    const std::vector<View>& views() const { return views_; }
    int size() const { return size_; }
    // Texture arrays, one layer per view.
    const gpu::Texture& position() const { return position_; }  // RGBA32F: world position, w = 1 where hit
    const gpu::Texture& normal() const { return normal_; }      // RGBA16F: shading normal
    const gpu::Texture& albedo() const { return albedo_; }      // RGBA8: diffuse albedo
    std::size_t bytes() const;
    // At most what render(scene, size) will hold: every view of every light with power (culling
    // may drop some), RGBA32F position, RGBA16F normal, RGBA8 albedo and 32-bit depth per texel.
    static std::uint64_t bytes_for(const scene::Scene& scene, int size);
    std::size_t frames_drawn() const { return frames_drawn_; }
    // Views of lights with power that were not drawn because they cannot see the scene.
    std::size_t views_culled() const { return views_culled_; }

private:
    std::vector<View> views_;
    int size_ = 0;
    gpu::Texture position_, normal_, albedo_, depth_;
    gpu::Framebuffer framebuffer_;
    std::uint64_t fingerprint_ = 0;
    std::size_t frames_drawn_ = 0;
    std::size_t views_culled_ = 0;
};

// The views a light's maps are drawn from (its cube faces, its cone, or an orthographic box around
// the scene bounds); `texel_measure` as in LightViewMaps::View.
std::vector<LightViewMaps::View> light_views(const scene::Light& light, std::size_t index, const scene::Aabb& bounds,
                                             int size);

}  // namespace bounce::passes
