// Virtual point lights and the VPL tree (paper §3.3-3.5). A VPL is a light-space cell that
// re-emits diffusely the flux it reflects: its flux-weighted mean position and normal, its total
// reflected flux and its surface area.
#include "common/math.glsl"
#include "isr/isr_layout.h"

struct VplNode {
    vec4 position_area;   // flux-weighted mean position; surface area (m^2)
    vec4 normal_radius;   // flux-weighted mean normal (shorter than 1 where normals spread); bounding radius
    vec4 flux_far;        // reflected flux (W); the cell's largest distance from the light
    vec4 normal_min_near; // per-component minimum normal; the cell's smallest distance from the light
    vec4 normal_max_flag; // per-component maximum normal; 1 where the cell holds a discontinuity
    vec4 bound_area;      // x: the smallest area the cell can cover (traversal bound), yzw: 0
};

struct Vpl {
    vec4 position_area;
    vec4 normal;
    vec4 flux;
};

// The irradiance a diffuse disk of area A, normal n_j at p_j, re-emitting flux `flux`, gives a point
// p with normal n: Wallace et al.'s disk-to-point form factor (paper eq. 1) times the disk's radiant
// exitance flux / A, which is flux cos_i cos_j / (pi d^2 + A). No visibility, as in the paper.
vec3 vpl_irradiance(vec3 p, vec3 n, vec3 p_j, vec3 n_j, float area, vec3 flux) {
    vec3 offset = p_j - p;
    float d2 = dot(offset, offset);
    vec3 w = offset * inversesqrt(max(d2, 1e-30));
    float cos_i = dot(n, w);
    float cos_j = -dot(n_j, w);
    if (cos_i <= 0.0 || cos_j <= 0.0) return vec3(0.0);
    return flux * (cos_i * cos_j / (PI * d2 + area));
}

float max_component(vec3 v) { return max(v.r, max(v.g, v.b)); }
