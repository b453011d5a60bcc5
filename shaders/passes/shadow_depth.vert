#version 450 core
#include "common/shared_layout.h"

layout(location = BOUNCE_ATTR_POSITION) in vec3 a_position;

uniform mat4 u_model;
uniform mat4 u_view_proj;

out vec3 v_world;

void main() {
    vec4 world = u_model * vec4(a_position, 1.0);
    v_world = world.xyz;
    gl_Position = u_view_proj * world;
}
