// Shadow-map visibility for the light types of lights.glsl, with hardware depth comparison.
// Point lights use a cube map and spot lights a 2D map, both storing distance / far (uniform
// precision over the range); directional lights an orthographic depth map.
#include "common/shared_layout.h"

layout(binding = BOUNCE_UNIT_SHADOW_2D) uniform sampler2DShadow u_shadow_map;
layout(binding = BOUNCE_UNIT_SHADOW_CUBE) uniform samplerCubeShadow u_shadow_cube;
layout(binding = BOUNCE_UNIT_SHADOW_VIEW) uniform sampler2DArrayShadow u_shadow_view;

uniform bool u_shadows_enabled;
uniform mat4 u_light_view_proj;   // spot and directional
uniform float u_shadow_far;       // point and spot: distance stored as distance / far
uniform float u_shadow_texel_angle;  // world size of one texel at unit distance (perspective maps)
uniform float u_shadow_texel_world;  // world size of one texel (orthographic maps)
// A directional light's view cascades (passes/shadow_maps.hpp), finest first; 0 where the pass reads
// the scene's map alone.
uniform int u_shadow_view_cascades;
uniform mat4 u_shadow_view_proj[BOUNCE_SHADOW_VIEW_CASCADES];
uniform float u_shadow_view_texel[BOUNCE_SHADOW_VIEW_CASCADES];

// Surfaces are pushed towards their normal by one texel before the lookup: a slope-free bias that
// removes acne without detaching contact shadows. At 1.5 texels a shadow's edge on a wall moved
// into the shade by a pixel or more, and the pixels between, lit on the GPU and in shade in the
// reference, carried half of cssm medium's error on the street; at 0.5 the atrium's sunlit floor
// shows acne (`direct` high 0.0017 -> 0.0058; docs/benchmarks.md, "What the corpus shows").
float shadow_visibility(int type, vec3 p, vec3 n, vec3 light_position, float distance) {
    if (!u_shadows_enabled) return 1.0;
    if (type == BOUNCE_LIGHT_DIRECTIONAL && u_shadow_view_cascades > 0) {
        // The finest cascade whose filter footprint holds the point: each spans the scene along the
        // light, so inside its window it answers as the scene's map would, with smaller texels.
        float margin = 1.0 / float(textureSize(u_shadow_view, 0).x);
        for (int k = 0; k < u_shadow_view_cascades; ++k) {
            vec3 uvz = (u_shadow_view_proj[k] * vec4(p + n * u_shadow_view_texel[k], 1.0)).xyz * 0.5 + 0.5;
            if (all(greaterThanEqual(uvz.xy, vec2(margin))) && all(lessThanEqual(uvz.xy, vec2(1.0 - margin)))) {
                return texture(u_shadow_view, vec4(uvz.xy, float(k), min(uvz.z, 1.0)));
            }
        }
    }
    float texel = type == BOUNCE_LIGHT_DIRECTIONAL ? u_shadow_texel_world : u_shadow_texel_angle * distance;
    vec3 offset_p = p + n * texel;
    if (type == BOUNCE_LIGHT_POINT) {
        vec3 from_light = offset_p - light_position;
        float stored_ref = (length(from_light) - texel) / u_shadow_far;
        return texture(u_shadow_cube, vec4(from_light, stored_ref));
    }
    vec4 clip = u_light_view_proj * vec4(offset_p, 1.0);
    if (clip.w <= 0.0) return 0.0;
    vec3 uvz = (clip.xyz / clip.w) * 0.5 + 0.5;
    if (any(lessThan(uvz.xy, vec2(0.0))) || any(greaterThan(uvz.xy, vec2(1.0)))) {
        // Outside a directional map nothing was drawn to occlude; outside a spot map the cone is 0.
        return type == BOUNCE_LIGHT_DIRECTIONAL ? 1.0 : 0.0;
    }
    float reference = type == BOUNCE_LIGHT_SPOT ? (length(offset_p - light_position) - texel) / u_shadow_far
                                                : uvz.z;
    return texture(u_shadow_map, vec3(uvz.xy, min(reference, 1.0)));
}
