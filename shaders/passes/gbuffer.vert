#version 450 core
#include "common/shared_layout.h"

layout(location = BOUNCE_ATTR_POSITION) in vec3 a_position;
layout(location = BOUNCE_ATTR_NORMAL) in vec3 a_normal;
layout(location = BOUNCE_ATTR_TANGENT) in vec4 a_tangent;
layout(location = BOUNCE_ATTR_UV0) in vec2 a_uv0;
layout(location = BOUNCE_ATTR_UV1) in vec2 a_uv1;

uniform mat4 u_model;
uniform mat3 u_normal_matrix;  // inverse transpose of the model's upper 3x3
uniform mat4 u_view_proj;

out vec3 v_position;
out vec3 v_normal;
out vec4 v_tangent;
out vec2 v_uv[2];

void main() {
    vec4 world = u_model * vec4(a_position, 1.0);
    v_position = world.xyz;
    v_normal = u_normal_matrix * a_normal;
    v_tangent = vec4(mat3(u_model) * a_tangent.xyz, a_tangent.w);
    v_uv[0] = a_uv0;
    v_uv[1] = a_uv1;
    gl_Position = u_view_proj * world;
}
