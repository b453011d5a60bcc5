#version 450 core
// Pull, finest to coarsest: a texel of level `u_level` that gathered nothing takes the mean of the
// texels below it that hold light (gathered or pulled), so every level ends up holding the light
// of the finer patches inside it. Alpha: at least 1 gathered, 0.5 filled, 0 nothing.
layout(local_size_x = 8, local_size_y = 8) in;
#include "isr/multires.glsl"

layout(binding = ISR_IMAGE_IRRADIANCE, rgba32f) uniform image2D u_irradiance;

uniform int u_level;

void main() {
    ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(texel, u_level_size[u_level]))) return;
    ivec2 at = atlas_texel(u_level, texel);
    if (imageLoad(u_irradiance, at).w >= 1.0) return;  // gathered
    vec3 sum = vec3(0.0);
    float count = 0.0;
    for (int child = 0; child < 4; ++child) {
        ivec2 below = texel * 2 + ivec2(child & 1, child >> 1);
        if (any(greaterThanEqual(below, u_level_size[u_level - 1]))) continue;
        vec4 value = imageLoad(u_irradiance, atlas_texel(u_level - 1, below));
        if (value.w == 0.0) continue;
        sum += value.rgb;
        count += 1.0;
    }
    if (count > 0.0) imageStore(u_irradiance, at, vec4(sum / count, 0.5));
}
