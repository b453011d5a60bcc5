// Exact irradiance from a uniformly bright rectangle, for senders too near a receiver for a point or
// a disk at their centre to stand in (a floor beside the wall that lights it). Lambert's contour
// integral over the rectangle's edges, the rectangle first clipped to the receiver's hemisphere:
// E / L = 1/2 sum_i theta_i (n . unit(v_i x v_(i+1))), v_i its corners as seen from the receiver.
#include "common/math.glsl"

// One edge's term: the angle the edge subtends, along the normal of the plane through it and p.
float contour_edge(vec3 a, vec3 b, vec3 n) {
    vec3 ua = normalize(a), ub = normalize(b);
    vec3 c = cross(ua, ub);
    float s = length(c);
    float angle = atan(s, dot(ua, ub));
    return (s > 1e-7 ? angle / s : 1.0) * dot(n, c);
}

// One edge a -> b of a polygon being clipped to n . v > 0 (Sutherland-Hodgman): emits a where it is
// above, and the crossing where the edge crosses, adding each emitted vertex's edge to `sum`.
void clip_and_sum(vec3 a, vec3 b, vec3 n, inout vec3 first, inout vec3 last, inout int emitted, inout float sum) {
    float da = dot(n, a), db = dot(n, b);
    if (da > 0.0) {
        if (emitted == 0) first = a; else sum += contour_edge(last, a, n);
        last = a;
        ++emitted;
    }
    if ((da > 0.0) != (db > 0.0)) {
        vec3 crossing = a + (da / (da - db)) * (b - a);
        if (emitted == 0) first = crossing; else sum += contour_edge(last, crossing, n);
        last = crossing;
        ++emitted;
    }
}

// Irradiance per unit radiance (pi times the point-to-area form factor) at the origin, normal n,
// from the rectangle of centre c (relative to the receiver), unit axes e1, e2 and half-edges h.x, h.y
// along them; its emitting side is e1 x e2's. 0 where the receiver is behind it or in its plane
// (within a thousandth of its longer edge: the other side of a double-sided sheet, at the same
// place, must receive nothing).
float rectangle_irradiance_factor(vec3 c, vec3 e1, vec3 e2, vec2 h, vec3 n) {
    if (dot(c, cross(e1, e2)) > -2e-3 * max(h.x, h.y)) return 0.0;
    vec3 u = h.x * e1, w = h.y * e2;
    vec3 c0 = c - u - w, c1 = c + u - w, c2 = c + u + w, c3 = c - u + w;
    vec3 first = vec3(0.0), last = vec3(0.0);
    int emitted = 0;
    float sum = 0.0;
    clip_and_sum(c0, c1, n, first, last, emitted, sum);
    clip_and_sum(c1, c2, n, first, last, emitted, sum);
    clip_and_sum(c2, c3, n, first, last, emitted, sum);
    clip_and_sum(c3, c0, n, first, last, emitted, sum);
    if (emitted < 3) return 0.0;
    sum += contour_edge(last, first, n);
    return 0.5 * abs(sum);
}
