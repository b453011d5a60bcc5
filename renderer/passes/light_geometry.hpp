// What passes that draw from the lights' point of view share: which lights have power (how far a
// light's view must reach is scene::far_plane_distance), a stable up vector, the fingerprints that decide when maps are redrawn,
// and the light uniforms of common/lights.glsl.
#pragma once

#include "renderer/gpu/shader_program.hpp"
#include "renderer/scene/scene.hpp"

#include <cstdint>
#include <optional>
#include <vector>

namespace bounce::passes {

// A light without power sends nothing: no map, no photons.
bool has_power(const scene::Light& light);

// The views a light-space map needs across the lights with power: six faces per point light, one
// per spot or directional light.
std::uint64_t light_views_with_power(const scene::Scene& scene);

// An up vector that is not parallel to `direction`.
glm::vec3 up_for(const glm::vec3& direction);

// The view of a directional light: from `distance` behind `center` against `direction`, looking at
// it. Built about the centre, then moved there, so a scene small against its distance from the
// origin (where centre - direction * distance rounds onto the centre) still gets a finite view.
glm::mat4 directional_view(const glm::vec3& center, const glm::vec3& direction, float distance);

// The content hash (renderer/base/hash.hpp) of every object's mesh and transform (geometry itself is immutable once uploaded).
std::uint64_t geometry_fingerprint(const scene::Scene& scene);

// The content hash of what light-view maps depend on: the lights, the geometry and the map size.
// `with_power`: the lights' colour and intensity too (what isr's VPL tree and cssm's solution are
// built from); else only whether each light has power, which decides whether its views exist: the
// maps themselves hold none (LightViewMaps).
std::uint64_t light_view_fingerprint(const scene::Scene& scene, int size, bool with_power = true);

// The content hash of what one light's shadow map depends on: where the light is and how it shines
// (not its colour or intensity: a depth map holds none, save whether it has power at all), the
// geometry (occluders, and the bounds a directional map is fitted to) and the map size.
std::uint64_t shadow_map_fingerprint(const scene::Light& light, std::uint64_t geometry, int size);

// The one factor by which every light's power (colour times intensity, each channel) changed from
// `before` to `now`, where nothing else of any light did: light transport is linear in it, so a
// method may scale the light it computed instead of computing it again (vct's injected light, cssm's
// atlas solution), where no surface emits (emits_light). 1 where no light's power changed; nullopt
// where the lights differ otherwise (in number, place or shape), or by no one positive, finite
// factor (a light turned off changes which views have photons).
std::optional<float> common_power_scale(const std::vector<scene::Light>& before, const std::vector<scene::Light>& now);

// Whether any surface emits: emission is light that does not scale with the lights'.
bool emits_light(const scene::Scene& scene);

// Sets u_light_type, u_light_position, u_light_direction, u_light_radiant, u_light_cos_inner and
// u_light_cos_outer.
void set_light_uniforms(const gpu::ShaderProgram& program, const scene::Light& light);

}  // namespace bounce::passes
