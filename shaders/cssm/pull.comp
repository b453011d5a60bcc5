#version 450 core
// Pull (§4.1.1): leaves take their texel's radiance, normal and spot; each internal node, a level at
// a time from the deepest, the area-weighted mean of its two children's radiance and the
// luminance-weighted mean of their lobes, and sends from its centre (CssmNodeLight in
// cssm/cssm_layout.h).
layout(local_size_x = 64) in;
#include "common/compute.glsl"
#define CSSM_BRDF(l, spread) 1.0
#define CSSM_BRDF_BOUND(l, cone) 1.0
#include "cssm/cssm_tree.glsl"

layout(std430, binding = CSSM_BINDING_TEXEL_IN) readonly buffer CssmTexelIn { vec4 texel_in[]; };
layout(std430, binding = CSSM_BINDING_LEVEL_NODES) readonly buffer CssmLevelNodes { uint level_nodes[]; };
layout(std430, binding = CSSM_BINDING_TEXEL_SPOTS) readonly buffer CssmTexelSpots { vec4 texel_spots[]; };

uniform bool u_leaves;
uniform bool u_holds_direct;  // the source holds the lights' light on the texels
uniform uint u_first;
uniform uint u_count;

// The width of a texel's lit part over its cell's along one axis, from the light's spread there
// (`lit`) and the samples' own (`all`). The samples stand at the middles of k = 4 sub-cells a side:
// j lit in a row spread s^2 (j^2 - 1) / 12 for sub-cells of width s, where the j sub-cells they
// stand for spread s^2 j^2 / 12, and all k samples s^2 (k^2 - 1) / 12. So the width is
// sqrt(((k^2 - 1) lit + all) / (k^2 all)): a quarter for one row, a half for two, all of it for four.
float lit_width(float lit, float all) {
    const float k2 = float(CSSM_TEXEL_SAMPLES);
    return all > 0.0 ? clamp(sqrt(((k2 - 1.0) * lit + all) / (k2 * all)), inversesqrt(k2), 1.0) : 1.0;
}

// A leaf's spot (CssmNodeLight in cssm/cssm_layout.h), `radiance` being all it sends. The light's
// offset is from the samples' mean; a texel its chart covers in part stands at its sample nearest
// their centroid and repeats samples, so there the spot is off by as much as that point is from the
// mean, and the widths, which take a full 4x4 grid, shrink less than the light's part: both err
// towards sending from the whole texel.
vec4 leaf_spot(uint texel, vec3 radiance) {
    vec3 position = texels[texel].position_area.xyz;
    vec4 light_sum = texel_spots[2u * texel];
    float whole = uintBitsToFloat(packHalf2x16(vec2(1.0)));
    if (!u_spots || !u_holds_direct || !(light_sum.w > 0.0)) return vec4(position, whole);
    float share = clamp(light_sum.w / max(luminance(radiance), 1e-30), 0.0, 1.0);
    vec3 offset = light_sum.xyz / light_sum.w;
    mat3 frame = tangent_frame(texels[texel].normal_map.xyz);
    vec2 along = vec2(dot(offset, frame[0]), dot(offset, frame[1]));
    vec4 spreads = texel_spots[2u * texel + 1u];
    vec2 lit = max(spreads.xy / light_sum.w - along * along, vec2(0.0));
    vec2 widths = vec2(lit_width(lit.x, spreads.z), lit_width(lit.y, spreads.w));
    return vec4(position + share * offset, uintBitsToFloat(packHalf2x16(mix(vec2(1.0), widths, share))));
}

void main() {
    uint i = thread_index();
    if (i >= u_count) return;
    if (u_leaves) {
        uint node = u_first + i;
        uint texel = nodes[node].links.w;
        if (texel != CSSM_NONE) {
            node_light[node].radiance = vec4(texel_in[texel].rgb, 0.0);
            node_light[node].lobe = vec4(texels[texel].normal_map.xyz, 1.0);
            node_light[node].spot = leaf_spot(texel, texel_in[texel].rgb);
        }
        return;
    }
    uint node = level_nodes[u_first + i];
    uint left = nodes[node].links.x;
    uint right = nodes[left].links.y;
    float a_left = nodes[left].area.x, a_right = nodes[right].area.x;
    vec3 l_left = node_light[left].radiance.rgb, l_right = node_light[right].radiance.rgb;
    node_light[node].radiance = vec4((l_left * a_left + l_right * a_right) / max(a_left + a_right, 1e-30), 0.0);
    // Weighted by the light each child sends; where neither sends any, by area (it then sends nothing).
    float w_left = luminance(l_left) * a_left, w_right = luminance(l_right) * a_right;
    if (!(w_left + w_right > 0.0)) {
        w_left = a_left;
        w_right = a_right;
    }
    vec3 v = (node_light[left].lobe.xyz * w_left + node_light[right].lobe.xyz * w_right) / max(w_left + w_right, 1e-30);
    node_light[node].lobe = vec4(v, min(length(v), 1.0));
    node_light[node].spot = vec4(nodes[node].centre_radius.xyz, uintBitsToFloat(packHalf2x16(vec2(1.0))));
}
