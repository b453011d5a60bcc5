#version 450 core
// Depth for light-view maps. Point-light cube faces store distance / far, so one comparison works
// for every face; perspective and orthographic maps keep the rasterized depth. Where an
// alpha-masked material is cut away, nothing is stored: light passes there.
#include "common/material.glsl"

in vec3 v_world;
in vec2 v_uv[2];

uniform bool u_store_distance;
uniform vec3 u_light_position;
uniform float u_far;

void main() {
    if (u_alpha_mode != BOUNCE_ALPHA_OPAQUE && cut_out(material_alpha(v_uv))) discard;
    gl_FragDepth = u_store_distance ? clamp(length(v_world - u_light_position) / u_far, 0.0, 1.0)
                                    : gl_FragCoord.z;
}
