// Shadow maps for punctual lights: a cube map per point light, a perspective map per spot light,
// an orthographic map fitted to the scene per directional light. A light with no power gets no
// map (it cannot reach the view).
//
// A directional light's map spans the scene's bounding sphere, so its texels grow with the scene,
// not with what the camera sees: in the open street (bench corpus) a 2048-texel map has texels of
// 8 cm, and direct light errs 0.067 there against 0.037 at 4096 and 0.022 at 8192. View cascades
// add, per directional light, nested maps of the same size fitted to the camera's view up to depths far / 3^k
// (k = cascades-1 .. 0) and cut to the scene: near the camera their texels are a few times to tens
// of times smaller. Each spans all of the scene along the light, so any point whose footprint lies
// inside a cascade is shadowed by it exactly as by the scene's map; the finest such cascade is
// read, the scene's map past them all. Cascades have the map's size: against a reference through
// pixel centres an edge must be resolved well below a pixel (at 128x128, cascades of 8 texels per
// pixel, 1024, left the street's direct light at ultra erring 0.0166 where 4096 erred 0.0024). Passes
// whose result must not depend on the view (cssm's atlas, lit for every texel whatever is seen) read
// the scene's map alone.
#pragma once

#include "renderer/passes/pass_context.hpp"

#include <cstdint>
#include <vector>

namespace bounce::passes {

class ShadowMaps {
public:
    // Renders a map of `size` texels per side for every light of the scene that has power. Each map is
    // kept while its light's place and shape, the object transforms and the size stay the same
    // (shadow_map_fingerprint): a light dimmed or recoloured keeps it, and a light moved redraws its
    // own map alone.
    // With `view_cascades` (at most kMaxViewCascades) above 0, each directional light also gets that
    // many cascades fitted to context.camera's view, redrawn when the fit moves them (the camera
    // moved by more than a texel, or turned). A frame that redraws only cascades is timed as
    // `shadow_view_cascades`, not `shadow_maps`: the planner prices a change of the lights by the
    // latter.
    void render(const PassContext& context, int size, int view_cascades = 0);
    static constexpr int kMaxViewCascades = 4;
    // Whether the last render() reused every map instead of drawing any.
    bool last_render_reused() const { return last_reused_; }
    std::size_t frames_drawn() const { return frames_drawn_; }
    std::size_t frames_reused() const { return frames_reused_; }
    std::size_t maps_drawn() const { return maps_drawn_; }  // light maps drawn, over every render()
    std::size_t view_cascades_drawn() const { return view_cascades_drawn_; }  // cascades drawn, likewise
    // Whether light `index` has a map (false for lights without power).
    bool has_map(std::size_t light_index) const;
    // Sets the shadow uniforms of common/shadows.glsl on `program` and binds the light's map, and
    // with `Coverage::view` its view cascades (where it has them).
    enum class Coverage { scene, view };
    void bind(const gpu::ShaderProgram& program, std::size_t light_index, Coverage coverage = Coverage::scene) const;
    std::size_t bytes() const;
    // What render(scene, size, view_cascades) will hold: a 32-bit depth map per light with power, six
    // faces for a point light, and the view cascades of each directional light.
    static std::uint64_t bytes_for(const scene::Scene& scene, int size, int view_cascades = 0);
    // A directional light's view cascades of `size` texels for a view of `width` x `height` pixels
    // (what render() draws), finest first: the light's view-projection, its texel edge in world
    // units, and the depth along the view up to which it holds all that the camera sees of the
    // scene. Those that would be no finer than the scene's map (2 r / size) are left out.
    struct ViewCascade {
        glm::mat4 view_projection{1.0f};
        float texel = 0.0f;
        float depth = 0.0f;
    };
    static std::vector<ViewCascade> fit_view_cascades(const scene::Aabb& bounds, const glm::vec3& light_direction,
                                                      const scene::Camera& camera, int width, int height, int size,
                                                      int cascades);
    // A hash of the view cascades render(context, size, cascades) fits for every directional light
    // with power in `scene`, seen by `camera` in a frame of `width` x `height` pixels: what a moved
    // camera changes of the maps (the same cascades, the same hash; 0 where none are fitted). The
    // renderer classifies a frame whose hash changed as redrawing them (frame_change.hpp).
    static std::uint64_t view_fingerprint(const scene::Scene& scene, const scene::Camera& camera, int width, int height,
                                          int size, int cascades);
    // The world texel edge of light `index`'s finest view cascade (0 where it has none): what the
    // view cascades bought, for tests and statistics.
    float finest_view_texel(std::size_t light_index) const;
    std::size_t map_count() const;

private:
    struct LightMap {
        scene::LightType type = scene::LightType::point;
        gpu::Texture depth;
        glm::mat4 view_projection{1.0f};
        float far = 1.0f;
        float texel_angle = 0.0f;  // world texel size per unit distance (perspective maps)
        float texel_world = 0.0f;  // world texel size (orthographic maps)
        bool valid = false;
        std::uint64_t fingerprint = 0;  // shadow_map_fingerprint it was drawn for; 0: never drawn
        // Directional lights: the view cascades, finest first, layers of one array texture.
        gpu::Texture view_depth;
        std::vector<ViewCascade> view_cascades;
        std::uint64_t view_fingerprint = 0;  // the map's and the fitted cascades'; 0: none
    };
    void render_view_cascades(const PassContext& context, const gpu::ShaderProgram& program, LightMap& map, int size,
                              std::vector<ViewCascade> cascades);
    void render_view(const PassContext& context, const gpu::ShaderProgram& program, const glm::mat4& view_projection);
    std::vector<LightMap> maps_;
    gpu::Framebuffer framebuffer_;
    bool last_reused_ = false;
    std::size_t maps_drawn_ = 0;
    std::size_t view_cascades_drawn_ = 0;
    std::size_t frames_drawn_ = 0;
    std::size_t frames_reused_ = 0;
};

}  // namespace bounce::passes
