// Imperfect shadow maps (Ritschel et al. 2008, [ism] in docs/references.md): isr's optional
// indirect visibility. The VPL tree's patches of one level each carry a small paraboloid depth map
// of the hemisphere above them, splatted from a few points of a random point cloud of the scene's
// surfaces (isr/ism_splat.comp) with its holes filled by pull-push (isr/ism_pull.comp, ism_push.comp).
// A VPL gathered from the tree is shadowed by the map of its patch at that level: its ancestor's, or
// for a coarser patch its brightest descendant's. Needs isr/vpl_tree.glsl.

uniform int u_ism_size;   // texels per side of one map
uniform int u_ism_level;  // the tree level whose patches carry maps
// The angle one texel spans at a map's centre (the paraboloid's disk is tan(theta / 2)): 4 / size.
uniform float u_ism_texel_angle;
uniform float u_ism_bias_absolute;  // metres, against rounding

struct IsmFrame {
    vec3 centre;
    mat3 frame;  // third axis: the hemisphere's pole, the patch's mean normal
    bool valid;  // false where the patch carries no flux (its map is empty)
};

int ism_side() { return u_rsm_size >> u_ism_level; }
uint ism_count_per_view() { return uint(ism_side() * ism_side()); }

// Per map, made when the maps are (isr/ism_frames.comp): its centre with w = 1 where its patch
// carries flux (an empty patch's map is empty), and its pole; and per tree node above the maps'
// level, the map it is shadowed by. Read once per gathered VPL, they spare the gather the node loads
// and the search below.
layout(std430, binding = ISR_BINDING_ISM_FRAMES) buffer Frames { vec4 ism_frames[]; };
layout(std430, binding = ISR_BINDING_ISM_COARSE) buffer Coarse { uint ism_coarse_maps[]; };

IsmFrame ism_frame(uint ism) {
    vec4 centre = ism_frames[2u * ism];
    IsmFrame f;
    f.valid = centre.w > 0.0;
    f.centre = centre.xyz;
    f.frame = tangent_frame(ism_frames[2u * ism + 1u].xyz);
    return f;
}

// The map a tree node is shadowed by: its ancestor's, or for a coarser node its brightest
// descendant's at the maps' level (a geometric choice, such as the centre, can fall on an empty
// patch at an edge of the lit surface, whose map is empty): ism_coarse_maps.
uint ism_of_node(int view, int level, ivec2 cell) {
    if (level > u_ism_level) return ism_coarse_maps[node_index(view, level, cell)];
    ivec2 at = cell >> (u_ism_level - level);
    return uint(view) * ism_count_per_view() + uint(at.y * ism_side() + at.x);
}

// The paraboloid projection of direction w (unit) about the frame's pole, in texels of one map;
// false for directions below the hemisphere.
bool ism_project(IsmFrame f, vec3 w, out vec2 texel) {
    float up = dot(w, f.frame[2]);
    if (up <= 0.0) return false;
    vec2 disk = vec2(dot(w, f.frame[0]), dot(w, f.frame[1])) / (1.0 + up);
    texel = (disk * 0.5 + 0.5) * float(u_ism_size);
    return true;
}

uint ism_texel_index(uint ism, ivec2 texel) {
    ivec2 clamped = clamp(texel, ivec2(0), ivec2(u_ism_size - 1));
    return ism * uint(u_ism_size * u_ism_size) + uint(clamped.y * u_ism_size + clamped.x);
}

// The filled maps' pyramid (isr/ism_pull.comp, isr/ism_push.comp): level k holds every map at
// (size >> k)^2 texels, maps one after another, levels one after another; level 0 is what the
// gather reads. A texel no sample reached holds ISM_EMPTY.
const float ISM_EMPTY = 3.0e38;
// Samples within this relative depth of the nearest among them are one surface: the others, behind
// it, fell through gaps between its samples.
const float ISM_SAME_SURFACE = 0.2;
uniform uint u_ism_maps;  // over every view

uint ism_level_offset(int level) {
    uint offset = 0u;
    for (int l = 0; l < level; ++l) offset += u_ism_maps * uint((u_ism_size >> l) * (u_ism_size >> l));
    return offset;
}
uint ism_pyramid_index(int level, uint map, ivec2 texel) {
    int side = u_ism_size >> level;
    return ism_level_offset(level) + map * uint(side * side) + uint(texel.y * side + texel.x);
}

#ifdef ISM_READ
layout(std430, binding = ISR_BINDING_ISM_FILLED) readonly buffer Filled { float depth_pyramid[]; };

// How much of the light from the tree node (view, level, cell) reaches p, on a surface of normal n:
// the bilinear weights of the four texels around p's direction in the node's map whose stored depth
// does not occlude p. A texel holds the nearest of the samples over its angle, and where p's own
// surface is seen at a grazing angle those lie nearer than p by up to d * angle / cos_i per texel of
// angle: a sample is an occluder only when nearer than that over two texels (the taps reach one
// texel from p's direction, a push from the level above one more): the slope-scaled bias of
// shadow maps.
float ism_visibility(int view, int level, ivec2 cell, vec3 p, vec3 n) {
    uint map = ism_of_node(view, level, cell);
    IsmFrame f = ism_frame(map);
    if (!f.valid) return 1.0;
    vec3 offset = p - f.centre;
    float d = length(offset);
    vec2 texel;
    if (!(d > 0.0) || !ism_project(f, offset / d, texel)) return 1.0;
    float cos_i = max(-dot(n, offset / d), 0.1);
    float unoccluded_from = d * (1.0 - 2.0 * u_ism_texel_angle / cos_i) - u_ism_bias_absolute;
    vec2 base = texel - 0.5;
    ivec2 corner = ivec2(floor(base));
    vec2 weight = base - vec2(corner);
    float lit = 0.0;
    for (int k = 0; k < 4; ++k) {
        ivec2 o = ivec2(k & 1, k >> 1);
        float w = (o.x == 1 ? weight.x : 1.0 - weight.x) * (o.y == 1 ? weight.y : 1.0 - weight.y);
        if (depth_pyramid[ism_texel_index(map, corner + o)] >= unoccluded_from) lit += w;
    }
    return lit;
}
#endif
