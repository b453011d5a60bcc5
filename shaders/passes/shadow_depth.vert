#version 450 core
#include "common/shared_layout.h"

layout(location = BOUNCE_ATTR_POSITION) in vec3 a_position;
layout(location = BOUNCE_ATTR_UV0) in vec2 a_uv0;
layout(location = BOUNCE_ATTR_UV1) in vec2 a_uv1;

uniform mat4 u_model;
uniform mat4 u_view_proj;

out vec3 v_world;
out vec2 v_uv[2];  // for alpha-masked materials

void main() {
    vec4 world = u_model * vec4(a_position, 1.0);
    v_world = world.xyz;
    v_uv[0] = a_uv0;
    v_uv[1] = a_uv1;
    gl_Position = u_view_proj * world;
}
