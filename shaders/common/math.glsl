// Constants and numerically safe helpers shared by every shader.
const float PI = 3.14159265358979323846;
const float INV_PI = 0.31830988618379067154;

// normalize() of a zero vector is NaN; fall back to a given direction instead.
vec3 safe_normalize(vec3 v, vec3 fallback) {
    float len2 = dot(v, v);
    return len2 > 1e-30 ? v * inversesqrt(len2) : fallback;
}

float saturate(float x) { return clamp(x, 0.0, 1.0); }

// Whether any component is positive (a photon or VPL that carries flux). Component-wise on purpose:
// NVIDIA's driver 580.159 on an H200 evaluates max(x, max(y, z)) > 0.0 as false for positive values
// under about 3e-8, `precise` or not, where each component's own comparison is exact; the photons
// and VPLs of dim lights (a thousandth of the Cornell box's lamp) vanished.
bool any_positive(vec3 v) { return any(greaterThan(v, vec3(0.0))); }

// Replaces NaN and infinities so that no non-finite value can reach a frame.
vec3 finite_or_zero(vec3 v) {
    return vec3(isnan(v.x) || isinf(v.x) ? 0.0 : v.x,
                isnan(v.y) || isinf(v.y) ? 0.0 : v.y,
                isnan(v.z) || isinf(v.z) ? 0.0 : v.z);
}

// A 32-bit integer hash (PCG's output permutation, Jarzynski & Olano 2020): well mixed from
// consecutive inputs, for per-pixel and per-node random numbers without state.
uint pcg_hash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A uniform number in [0, 1) from a hash.
float unit_float(uint h) { return float(h >> 8u) * (1.0 / 16777216.0); }

// An orthonormal frame whose third axis is the unit vector `n` (cone axes, paraboloid maps).
mat3 tangent_frame(vec3 n) {
    vec3 tangent = normalize(abs(n.x) < 0.9 ? cross(n, vec3(1.0, 0.0, 0.0)) : cross(n, vec3(0.0, 1.0, 0.0)));
    return mat3(tangent, cross(n, tangent), n);
}
