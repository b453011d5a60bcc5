#version 450 core
// Voxelization (paper §4.2.1): each triangle is projected along the axis its normal is most aligned
// with, so it covers as many lattice columns as it can; the viewport has one pixel per lattice
// column (pixel centres on lattice points).
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;

in vec3 v_position[];
in vec3 v_normal[];
in vec4 v_tangent[];
in vec2 v_uv[][2];

out vec3 g_position;
out vec3 g_normal;
out vec4 g_tangent;
out vec2 g_uv[2];
flat out float g_area;  // surface area per column in lattice-spacing^2: 1 / |n|_max
flat out vec3 g_face_normal;

uniform vec3 u_grid_origin;
uniform float u_lattice_spacing;
uniform float u_viewport_texels;  // lattice points per axis (pixels per side of the viewport)

void main() {
    vec3 face = cross(v_position[1] - v_position[0], v_position[2] - v_position[0]);
    float face_length = length(face);
    if (!(face_length > 0.0)) return;  // degenerate: no area, no fragments
    vec3 a = abs(face / face_length);
    // Screen axes and depth axis per dominant axis (the same choice as surface_lattice_point).
    ivec3 axes = a.x >= a.y && a.x >= a.z ? ivec3(1, 2, 0)
               : a.y >= a.z               ? ivec3(2, 0, 1)
                                          : ivec3(0, 1, 2);
    float area = 1.0 / max(a.x, max(a.y, a.z));
    for (int i = 0; i < 3; ++i) {
        vec3 lattice = (v_position[i] - u_grid_origin) / u_lattice_spacing;  // pixel i's centre at i
        vec2 ndc = (vec2(lattice[axes.x], lattice[axes.y]) + 0.5) / u_viewport_texels * 2.0 - 1.0;
        gl_Position = vec4(ndc, 0.0, 1.0);
        g_position = v_position[i];
        g_normal = v_normal[i];
        g_tangent = v_tangent[i];
        g_uv[0] = v_uv[i][0];
        g_uv[1] = v_uv[i][1];
        g_area = area;
        g_face_normal = face / face_length;
        EmitVertex();
    }
    EndPrimitive();
}
