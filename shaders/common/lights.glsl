// Punctual lights in radiometric units (docs/methods.md): point and spot lights carry radiant
// intensity (W/sr), directional lights irradiance (W/m^2). C++ twin: renderer/scene/shading.cpp.
#include "common/math.glsl"
#include "common/shared_layout.h"

struct PunctualLight {
    int type;
    vec3 position;
    vec3 direction;  // the way light travels
    vec3 radiant;    // colour * intensity
    float cos_inner;
    float cos_outer;
};

// glTF's smooth spot falloff: 1 inside the inner cone, 0 outside the outer, squared linear ramp.
float spot_attenuation(PunctualLight light, float cos_angle) {
    float scale = 1.0 / max(light.cos_inner - light.cos_outer, 1e-4);
    float t = saturate((cos_angle - light.cos_outer) * scale);
    return t * t;
}

// Direction towards the light, its distance, and the irradiance it gives a surface facing it.
struct LightIncidence {
    vec3 l;
    float distance;
    vec3 irradiance;
};

LightIncidence light_incidence(PunctualLight light, vec3 p) {
    LightIncidence result;
    if (light.type == BOUNCE_LIGHT_DIRECTIONAL) {
        result.l = -light.direction;
        result.distance = 3.0e38;
        result.irradiance = light.radiant;
        return result;
    }
    vec3 to_light = light.position - p;
    float d2 = max(dot(to_light, to_light), 1e-12);
    result.distance = sqrt(d2);
    result.l = to_light / result.distance;
    result.irradiance = light.radiant / d2;
    if (light.type == BOUNCE_LIGHT_SPOT) {
        result.irradiance *= spot_attenuation(light, dot(-result.l, light.direction));
    }
    return result;
}
