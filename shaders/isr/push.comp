#version 450 core
// Push, coarsest to finest (the upsample-and-interpolate of paper §3.2.2 / [NW09]): a texel of
// level `u_level` that gathered nothing takes the bilinear interpolation of the level above, which
// by then holds light everywhere its patches or finer ones gathered. Neighbours more than one level
// apart therefore blend through every level between them: no stair steps. Neighbours on another
// surface (depth ranges apart, or normals that together span more than twice the normal threshold)
// weigh a thousand times less, so light does not bleed across silhouettes or creases; the texel
// above that holds the target lies inside the target's own continuous patch and always counts.
layout(local_size_x = 8, local_size_y = 8) in;
#include "isr/multires.glsl"

layout(binding = ISR_IMAGE_IRRADIANCE, rgba32f) uniform image2D u_irradiance;
layout(binding = ISR_IMAGE_DEPTH, rgba32f) readonly uniform image2D u_depth;
layout(binding = ISR_IMAGE_NORMAL_MIN, rgba16f) readonly uniform image2D u_normal_min;
layout(binding = ISR_IMAGE_NORMAL_MAX, rgba16f) readonly uniform image2D u_normal_max;

uniform int u_level;

void main() {
    ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(texel, u_level_size[u_level]))) return;
    ivec2 at = atlas_texel(u_level, texel);
    if (imageLoad(u_irradiance, at).w >= 1.0) return;  // gathered
    vec4 depth = imageLoad(u_depth, at);
    if (patch_empty(depth)) return;
    vec3 normal_min = imageLoad(u_normal_min, at).xyz, normal_max = imageLoad(u_normal_max, at).xyz;
    float tolerance = max(u_depth_threshold, 0.01) * depth.x;
    // Texel centres: level i's texel t sits at (t + 0.5) / 2 - 0.5 in level i + 1's texels.
    vec2 above = (vec2(texel) + 0.5) * 0.5 - 0.5;
    ivec2 base = ivec2(floor(above));
    vec2 f = above - vec2(base);
    ivec2 size = u_level_size[u_level + 1];
    vec3 sum = vec3(0.0);
    float weight_sum = 0.0;
    for (int corner = 0; corner < 4; ++corner) {
        ivec2 offset = ivec2(corner & 1, corner >> 1);
        ivec2 source = clamp(base + offset, ivec2(0), size - 1);
        ivec2 source_at = atlas_texel(u_level + 1, source);
        vec4 value = imageLoad(u_irradiance, source_at);
        if (value.w == 0.0) continue;
        vec2 w2 = mix(1.0 - f, f, vec2(offset));
        float w = w2.x * w2.y;
        vec4 source_depth = imageLoad(u_depth, source_at);
        // Depth ranges that meet, and normals that together span at most twice the threshold: a
        // source straddling a crease spans both faces' normals and is rejected by either face.
        vec3 normal_span = max(normal_max, imageLoad(u_normal_max, source_at).xyz) -
                           min(normal_min, imageLoad(u_normal_min, source_at).xyz);
        bool same_surface = source_depth.x <= depth.y + tolerance && source_depth.y + tolerance >= depth.x &&
                            all(lessThanEqual(normal_span, vec3(2.0 * max(u_normal_threshold, 0.05))));
        w *= same_surface ? 1.0 : 1e-3;
        sum += w * value.rgb;
        weight_sum += w;
    }
    if (weight_sum > 0.0) imageStore(u_irradiance, at, vec4(sum / weight_sum, 0.5));
}
