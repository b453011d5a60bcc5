// Light-view map texels as photons (passes/light_view_maps.hpp). Point and spot views are
// perspective: a texel subtends `texel_measure` * cos^3 of its angle off the view axis, so it carries
// intensity times that solid angle. Directional views are orthographic: a texel is `texel_measure`
// of area under the light's irradiance.
#include "common/lights.glsl"

// The flux the light sends through the texel whose surface lies at `position`.
vec3 photon_flux(PunctualLight light, vec3 position, vec3 view_forward, float texel_measure) {
    if (light.type == BOUNCE_LIGHT_DIRECTIONAL) return light.radiant * texel_measure;
    vec3 direction = normalize(position - light.position);
    float cos_axis = dot(direction, view_forward);
    vec3 flux = light.radiant * (texel_measure * cos_axis * cos_axis * cos_axis);
    if (light.type == BOUNCE_LIGHT_SPOT) flux *= spot_attenuation(light, dot(direction, light.direction));
    return flux;
}

// The area of the surface the texel covers, with normal `normal`: its footprint across the light's
// rays divided by the cosine of incidence (kept above 1/20: grazing texels are not unbounded).
float photon_footprint(PunctualLight light, vec3 position, vec3 normal, vec3 view_forward, float texel_measure) {
    if (light.type == BOUNCE_LIGHT_DIRECTIONAL) return texel_measure / max(abs(dot(normal, light.direction)), 0.05);
    vec3 offset = position - light.position;
    float distance2 = dot(offset, offset);
    vec3 direction = offset * inversesqrt(max(distance2, 1e-30));
    float cos_axis = dot(direction, view_forward);
    return texel_measure * cos_axis * cos_axis * cos_axis * distance2 / max(abs(dot(normal, direction)), 0.05);
}
