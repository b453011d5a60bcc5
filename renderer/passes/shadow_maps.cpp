#include "renderer/passes/shadow_maps.hpp"

#include "common/shared_layout.h"
#include "renderer/base/error.hpp"
#include "renderer/base/hash.hpp"
#include "renderer/passes/light_geometry.hpp"

#include <fmt/format.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace bounce::passes {

static_assert(ShadowMaps::kMaxViewCascades == BOUNCE_SHADOW_VIEW_CASCADES, "shaders/common/shadows.glsl's arrays");

namespace {

gpu::Texture make_depth_map(GLenum target, int size, int layers = 1) {
    gpu::Texture texture({target, GL_DEPTH_COMPONENT32F, size, size, layers});
    glTextureParameteri(texture.id(), GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTextureParameteri(texture.id(), GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    texture.set_filter(GL_LINEAR, GL_LINEAR);  // bilinear percentage-closer filtering
    return texture;
}

// A directional light's map looks along the light from twice the scene's bounding radius behind its
// centre, over depths 0.5 r to 3 r: all of the scene, whatever the window across the light.
struct DirectionalFrame {
    glm::mat4 view;
    float radius = 0.0f;
};

DirectionalFrame directional_frame(const scene::Aabb& bounds, const glm::vec3& direction) {
    const float radius = std::max(0.5f * glm::length(bounds.extent()), 1e-6f);
    return {directional_view(bounds.center(), glm::normalize(direction), 2.0f * radius), radius};
}

glm::mat4 directional_projection(const glm::vec2& centre, float half, float radius) {
    return glm::ortho(centre.x - half, centre.x + half, centre.y - half, centre.y + half, 0.5f * radius, 3.0f * radius);
}

std::uint64_t view_cascades_fingerprint(std::uint64_t map, const std::vector<ShadowMaps::ViewCascade>& cascades) {
    Hasher hash;
    hash.add(map);
    for (const ShadowMaps::ViewCascade& cascade : cascades) hash.add(cascade.view_projection).add(cascade.texel);
    return hash.value() | 1u;  // 0 stands for no cascades
}

// A cascade's window across the light: a square about `centre`, `half` wide each way.
struct CascadeWindow {
    glm::vec2 centre{0.0f};
    float half = 0.0f;
};

// The window that holds what the camera sees up to `depth` (the pyramid from its eye to the four
// corners of the view at that depth), cut to the scene, in the light view's x and y; nullopt where
// the view holds none of the scene. Its size is a power of 2^(1/4) of the scene's map's and its
// centre a whole number of texels, so that as the camera moves the texels stay where they were and
// shadow edges do not crawl. A margin of 3.5 texels a side keeps what the lookup reads of a point
// at the view's edge inside: its normal offset (1.5 texels), the filter's texel, and the half texel
// the snapped centre may move, with half a texel to spare.
std::optional<CascadeWindow> cascade_window(const scene::Camera& camera, float aspect, const DirectionalFrame& frame,
                                            const scene::Aabb& bounds, int size, float depth) {
    const float tan_vertical = std::tan(0.5f * camera.vertical_fov), tan_horizontal = tan_vertical * aspect;
    const glm::vec3 forward = camera.forward(), up = camera.up(), right = glm::normalize(glm::cross(forward, up));
    const auto across = [&](const glm::vec3& p) { return glm::vec2(frame.view * glm::vec4(p, 1.0f)); };
    glm::vec2 lo = across(camera.position), hi = lo;
    for (const float x : {-1.0f, 1.0f}) {
        for (const float y : {-1.0f, 1.0f}) {
            const glm::vec2 corner =
                across(camera.position + depth * (forward + x * tan_horizontal * right + y * tan_vertical * up));
            lo = glm::min(lo, corner), hi = glm::max(hi, corner);
        }
    }
    glm::vec2 scene_lo(std::numeric_limits<float>::max()), scene_hi(-std::numeric_limits<float>::max());
    for (int i = 0; i < 8; ++i) {
        const glm::vec2 corner = across(bounds.corner(i));
        scene_lo = glm::min(scene_lo, corner), scene_hi = glm::max(scene_hi, corner);
    }
    lo = glm::max(lo, scene_lo), hi = glm::min(hi, scene_hi);
    const bool finite = std::isfinite(lo.x) && std::isfinite(lo.y) && std::isfinite(hi.x) && std::isfinite(hi.y);
    if (!finite || !(hi.x > lo.x && hi.y > lo.y)) return std::nullopt;
    const float side = std::max(hi.x - lo.x, hi.y - lo.y);
    const float wanted = 0.5f * side * (1.0f + 7.0f / static_cast<float>(size));
    // r 2^(-k/4): the smallest that holds the wanted half-width, and no smaller than r / 1024, where a
    // texel's normal offset still spans a few steps of float depth over the map's 2.5 r at 8192
    // texels (a view that grazes a corner of the scene would otherwise ask for any size).
    constexpr float kFinestSteps = 40.0f;
    const float steps = std::floor(-4.0f * std::log2(std::max(wanted, 1e-30f) / frame.radius));
    CascadeWindow window;
    window.half = frame.radius * std::exp2(-std::clamp(steps, 0.0f, kFinestSteps) / 4.0f);
    if (window.half < wanted) window.half *= std::exp2(0.25f);  // rounding at the step's edge
    const float texel = 2.0f * window.half / static_cast<float>(size);
    window.centre = glm::floor(0.5f * (lo + hi) / texel + 0.5f) * texel;
    return window;
}

}  // namespace

std::vector<ShadowMaps::ViewCascade> ShadowMaps::fit_view_cascades(const scene::Aabb& bounds,
                                                                   const glm::vec3& light_direction,
                                                                   const scene::Camera& camera, int width, int height,
                                                                   int size, int cascades) {
    std::vector<ViewCascade> fitted;
    if (bounds.empty() || size <= 0) return fitted;
    const DirectionalFrame frame = directional_frame(bounds, light_direction);
    const float far = camera.z_far > 0.0f ? camera.z_far : camera.far_plane_for(bounds);
    const float aspect = height > 0 ? static_cast<float>(width) / static_cast<float>(height) : 1.0f;
    const float scene_texel = 2.0f * frame.radius / static_cast<float>(size);
    // Nested depths far / 3^k, finest first: a pixel's footprint grows with its depth, and so may
    // the texels that shadow it.
    for (int k = cascades - 1; k >= 0; --k) {
        const float depth = far / std::pow(3.0f, static_cast<float>(k));
        const auto window = cascade_window(camera, aspect, frame, bounds, size, depth);
        if (!window) continue;
        const float texel = 2.0f * window->half / static_cast<float>(size);
        // One no finer than the scene's map adds nothing; one as fine as the cascade before holds
        // what that one held (it sees farther), and takes its place.
        if (!(texel < scene_texel)) continue;
        if (!fitted.empty() && !(fitted.back().texel < texel)) fitted.pop_back();
        const glm::mat4 projection = directional_projection(window->centre, window->half, frame.radius);
        fitted.push_back({projection * frame.view, texel, depth});
    }
    return fitted;
}

std::uint64_t ShadowMaps::view_fingerprint(const scene::Scene& scene, const scene::Camera& camera, int width, int height,
                                           int size, int cascades) {
    if (cascades <= 0) return 0;
    Hasher hash;
    bool any = false;
    const scene::Aabb bounds = scene.world_bounds();
    for (const scene::Light& light : scene.lights) {
        if (light.type != scene::LightType::directional || !has_power(light)) continue;
        const auto fitted = fit_view_cascades(bounds, light.direction, camera, width, height, size, cascades);
        for (const ViewCascade& cascade : fitted) hash.add(cascade.view_projection).add(cascade.texel);
        hash.add(fitted.size());
        any = any || !fitted.empty();
    }
    return any ? hash.value() | 1u : 0u;
}

void ShadowMaps::render_view_cascades(const PassContext& context, const gpu::ShaderProgram& program, LightMap& map,
                                      int size, std::vector<ViewCascade> cascades) {
    map.view_cascades = std::move(cascades);
    const auto layers = static_cast<int>(map.view_cascades.size());
    if (layers == 0) {
        map.view_depth = gpu::Texture();
        return;
    }
    if (!map.view_depth || map.view_depth.width() != size || map.view_depth.desc().depth != layers) {
        map.view_depth = make_depth_map(GL_TEXTURE_2D_ARRAY, size, layers);
    }
    program.set("u_store_distance", 0);
    const float far_depth = 1.0f;
    for (int layer = 0; layer < layers; ++layer) {
        framebuffer_.attach_depth_layer(map.view_depth, layer);
        framebuffer_.check_complete("a directional light's view cascade");
        glClearNamedFramebufferfv(framebuffer_.id(), GL_DEPTH, 0, &far_depth);
        render_view(context, program, map.view_cascades[static_cast<std::size_t>(layer)].view_projection);
    }
    view_cascades_drawn_ += static_cast<std::size_t>(layers);
}

void ShadowMaps::render_view(const PassContext& context, const gpu::ShaderProgram& program,
                             const glm::mat4& view_projection) {
    program.set("u_view_proj", view_projection);
    context.gpu_scene.for_each_primitive([&](const scene::Object& object, const gpu::GpuPrimitive& primitive) {
        program.set("u_model", object.transform);
        // Masked and blended materials need their alpha and its texture; every other surface only depth.
        if (context.scene.material(primitive.material).alpha_mode != scene::AlphaMode::opaque) {
            context.gpu_scene.bind_material(program, primitive.material);
        } else {
            program.set("u_alpha_mode", static_cast<int>(scene::AlphaMode::opaque));
        }
        gpu::GpuScene::draw(primitive);
    });
}

void ShadowMaps::render(const PassContext& context, int size, int view_cascades) {
    BOUNCE_CHECK(view_cascades >= 0 && view_cascades <= kMaxViewCascades, "{} view cascades", view_cascades);
    const auto& lights = context.scene.lights;
    const std::uint64_t geometry = geometry_fingerprint(context.scene);
    std::vector<std::uint64_t> fingerprints(lights.size()), view_fingerprints(lights.size(), 0);
    std::vector<std::vector<ViewCascade>> fitted(lights.size());
    for (std::size_t i = 0; i < lights.size(); ++i) {
        fingerprints[i] = shadow_map_fingerprint(lights[i], geometry, size);
        if (view_cascades > 0 && lights[i].type == scene::LightType::directional && has_power(lights[i])) {
            fitted[i] = fit_view_cascades(context.scene.world_bounds(), lights[i].direction, context.camera,
                                          context.width, context.height, size, view_cascades);
            if (!fitted[i].empty()) view_fingerprints[i] = view_cascades_fingerprint(fingerprints[i], fitted[i]);
        }
    }
    bool scene_stale = maps_.size() != lights.size(), view_stale = false;
    for (std::size_t i = 0; i < lights.size() && !scene_stale; ++i) {
        scene_stale = maps_[i].fingerprint != fingerprints[i];
        view_stale = view_stale || maps_[i].view_fingerprint != view_fingerprints[i];
    }
    last_reused_ = !scene_stale && !view_stale;
    if (last_reused_) {
        ++frames_reused_;
        return;
    }
    // Timed only where maps are drawn: a frame's `shadow_maps` pass says it drew them, and what that
    // took (the planner prices the maps by it, planning/costs.hpp); one that drew only the view
    // cascades (its camera moved) is timed apart, so as not to pass for a change of the lights.
    gpu::GpuTimers::Scope timing(context.timers, scene_stale ? "shadow_maps" : "shadow_view_cascades");
    ++frames_drawn_;
    maps_.resize(lights.size());
    const scene::Aabb bounds = context.scene.world_bounds();
    if (bounds.empty()) {
        for (std::size_t i = 0; i < maps_.size(); ++i) {
            maps_[i] = LightMap{};
            maps_[i].fingerprint = fingerprints[i];
        }
        return;
    }
    const gpu::ShaderProgram& program =
        context.shaders.get({"passes/shadow_depth.vert", "passes/shadow_depth.frag", {}});
    program.use();
    framebuffer_.set_draw_buffers(0);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.id());
    glViewport(0, 0, size, size);
    // Both faces cast shadows: closed meshes and open single-sided walls alike.
    context.state.apply({.depth_test = true, .depth_write = true, .depth_func = GL_LESS, .cull = gpu::Cull::none});

    for (std::size_t i = 0; i < lights.size(); ++i) {
        LightMap& map = maps_[i];
        if (map.view_fingerprint == view_fingerprints[i]) continue;
        map.view_fingerprint = view_fingerprints[i];
        render_view_cascades(context, program, map, size, std::move(fitted[i]));
    }
    for (std::size_t i = 0; i < lights.size(); ++i) {
        const scene::Light& light = lights[i];
        LightMap& map = maps_[i];
        if (map.fingerprint == fingerprints[i]) continue;  // its light did not move or reshape
        map.fingerprint = fingerprints[i];
        map.valid = has_power(light);
        if (!map.valid) {
            map.depth = gpu::Texture();
            continue;
        }
        ++maps_drawn_;
        map.type = light.type;
        const GLenum target = light.type == scene::LightType::point ? GL_TEXTURE_CUBE_MAP : GL_TEXTURE_2D;
        if (!map.depth || map.depth.width() != size || map.depth.desc().target != target) {
            map.depth = make_depth_map(target, size);
        }
        const float far_depth = 1.0f;
        if (light.type == scene::LightType::point) {
            map.far = scene::far_plane_distance(bounds, light.position);
            map.texel_angle = 2.0f / static_cast<float>(size);  // 90-degree faces
            const glm::mat4 projection = glm::perspective(glm::radians(90.0f), 1.0f, map.far * 1e-4f, map.far);
            static const glm::vec3 forward[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
            static const glm::vec3 up[6] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
            program.set("u_store_distance", 1);
            program.set("u_light_position", light.position);
            program.set("u_far", map.far);
            for (int face = 0; face < 6; ++face) {
                framebuffer_.attach_depth_layer(map.depth, face);
                framebuffer_.check_complete("a point-light shadow cube face");
                glClearNamedFramebufferfv(framebuffer_.id(), GL_DEPTH, 0, &far_depth);
                render_view(context, program,
                            projection * glm::lookAt(light.position, light.position + forward[face], up[face]));
            }
            continue;
        }
        framebuffer_.attach_depth(map.depth);
        framebuffer_.check_complete("a shadow map");
        glClearNamedFramebufferfv(framebuffer_.id(), GL_DEPTH, 0, &far_depth);
        const glm::vec3 direction = glm::normalize(light.direction);
        if (light.type == scene::LightType::spot) {
            map.far = scene::far_plane_distance(bounds, light.position);
            const float half_angle = std::clamp(light.outer_cone, 0.001f, 1.5533f);  // < 89 degrees
            map.texel_angle = 2.0f * std::tan(half_angle) / static_cast<float>(size);
            map.view_projection = glm::perspective(2.0f * half_angle, 1.0f, map.far * 1e-4f, map.far) *
                                  glm::lookAt(light.position, light.position + direction, up_for(direction));
            program.set("u_store_distance", 1);
            program.set("u_light_position", light.position);
            program.set("u_far", map.far);
        } else {
            const DirectionalFrame frame = directional_frame(bounds, direction);
            map.far = 3.0f * frame.radius;
            map.texel_world = 2.0f * frame.radius / static_cast<float>(size);
            map.view_projection = directional_projection(glm::vec2(0.0f), frame.radius, frame.radius) * frame.view;
            program.set("u_store_distance", 0);
        }
        render_view(context, program, map.view_projection);
    }
}

bool ShadowMaps::has_map(std::size_t light_index) const {
    return light_index < maps_.size() && maps_[light_index].valid;
}

void ShadowMaps::bind(const gpu::ShaderProgram& program, std::size_t light_index, Coverage coverage) const {
    BOUNCE_CHECK(has_map(light_index), "light {} has no shadow map", light_index);
    const LightMap& map = maps_[light_index];
    const bool view = coverage == Coverage::view && map.view_depth;
    program.set("u_shadow_view_cascades", view ? static_cast<int>(map.view_cascades.size()) : 0);
    if (view) {
        for (std::size_t k = 0; k < map.view_cascades.size(); ++k) {
            program.set(fmt::format("u_shadow_view_proj[{}]", k), map.view_cascades[k].view_projection);
            program.set(fmt::format("u_shadow_view_texel[{}]", k), map.view_cascades[k].texel);
        }
        glBindTextureUnit(BOUNCE_UNIT_SHADOW_VIEW, map.view_depth.id());
        glBindSampler(BOUNCE_UNIT_SHADOW_VIEW, 0);
    }
    program.set("u_shadows_enabled", 1);
    program.set("u_light_view_proj", map.view_projection);
    program.set("u_shadow_far", map.far);
    program.set("u_shadow_texel_angle", map.texel_angle);
    program.set("u_shadow_texel_world", map.texel_world);
    const GLuint unit = map.type == scene::LightType::point ? BOUNCE_UNIT_SHADOW_CUBE : BOUNCE_UNIT_SHADOW_2D;
    glBindTextureUnit(unit, map.depth.id());
    glBindSampler(unit, 0);
}

std::uint64_t ShadowMaps::bytes_for(const scene::Scene& scene, int size, int view_cascades) {
    std::uint64_t views = light_views_with_power(scene);
    for (const scene::Light& light : scene.lights) {
        if (light.type == scene::LightType::directional && has_power(light)) {
            views += static_cast<std::uint64_t>(view_cascades);
        }
    }
    return views * static_cast<std::uint64_t>(size) * static_cast<std::uint64_t>(size) * 4;
}

std::size_t ShadowMaps::bytes() const {
    std::size_t total = 0;
    for (const auto& map : maps_) total += map.depth.bytes() + map.view_depth.bytes();
    return total;
}

float ShadowMaps::finest_view_texel(std::size_t light_index) const {
    if (light_index >= maps_.size() || maps_[light_index].view_cascades.empty()) return 0.0f;
    return maps_[light_index].view_cascades.front().texel;
}

std::size_t ShadowMaps::map_count() const {
    return static_cast<std::size_t>(
        std::count_if(maps_.begin(), maps_.end(), [](const LightMap& m) { return m.valid; }));
}

}  // namespace bounce::passes
