// Bindings, constants and buffer structs of `cssm`, shared by C++ and GLSL: this file compiles as both.
#ifndef BOUNCE_CSSM_LAYOUT_H
#define BOUNCE_CSSM_LAYOUT_H

#define CSSM_BINDING_NODES 0         // CssmNode[]: the radiosity hierarchy, depth-first, child + skip pointers
#define CSSM_BINDING_NODE_LIGHT 1     // CssmNodeLight[nodes]: what each node sends, pulled from its texels
#define CSSM_BINDING_TEXELS 2        // CssmTexel[]: atlas texels (world position, normal, map, albedo)
#define CSSM_BINDING_PIXEL_RUNS 3    // uint[pixels + 1]: each cube pixel's first run
#define CSSM_BINDING_RUN_START 4     // uint[runs]: first map of each run
#define CSSM_BINDING_RUN_DEPTH 5     // uint[(runs + 1) / 2]: 16-bit depths, two per word
#define CSSM_BINDING_TEXEL_IN 6      // vec4[texels]: a per-texel radiance read (pull source, bounce input)
#define CSSM_BINDING_TEXEL_OUT 7     // vec4[texels]: a per-texel radiance written
#define CSSM_BINDING_ROOTS 8         // uint[]: roots of the subtrees the gathers are batched by
#define CSSM_BINDING_LEVEL_NODES 9   // uint[]: internal nodes grouped by depth, deepest first
#define CSSM_BINDING_COUNTERS 10     // uint[CSSM_COUNTERS]
#define CSSM_BINDING_GROUPS 11       // CssmGroup[]: bake groups (the static objects, each moving object)
#define CSSM_BINDING_CSMS 12         // CssmCsm[]: coherent shadow maps of the moving groups
#define CSSM_BINDING_CSM_DIRECTIONS 13  // vec4[]: each CSM's map directions
#define CSSM_BINDING_CSM_NEAREST 14  // uint[]: each CSM's direction table (6 x CSM_TABLE_FACE^2)

#define CSSM_BINDING_TEXEL_INDIRECT 15  // vec4[texels]: irradiance of every bounce, summed (per-texel display)
#define CSSM_BINDING_TEXEL_SAMPLES 16   // vec4[texels * CSSM_TEXEL_SAMPLES]: world points of each texel's surface
#define CSSM_TEXEL_SAMPLES 16           // where its direct light is sampled (AtlasTexel::samples)
// vec4[2 * texels]: where on each texel the lights' light falls, summed over its samples and the
// lights (atlas_direct.comp): [sum e d, sum e] and [sum e d.x^2, sum e d.y^2, mean d.x^2, mean d.y^2],
// with d a sample's place p - m from the samples' mean m (in the normal's tangent_frame for x and y)
// and e its part of the texel's exitance luminance from the lights. pull.comp makes each leaf's spot
// of them (CssmNodeLight::spot).
#define CSSM_BINDING_TEXEL_SPOTS 17

#define CSSM_TABLE_FACE 16

#define CSSM_NONE 0xFFFFFFFFu

#define CSSM_COUNTER_RECEIVERS 0      // receivers (texels or pixels) that gathered
#define CSSM_COUNTER_NODES_LOW 1      // sender nodes gathered, summed over receivers (two words)
#define CSSM_COUNTER_NODES_HIGH 2
#define CSSM_COUNTER_VISITED_LOW 3    // nodes the traversals visited (refined or gathered)
#define CSSM_COUNTER_VISITED_HIGH 4
#define CSSM_COUNTERS 5

// The std430 structs of the buffers above. GLSL reads them as written; C++ reads the same lines
// with GLSL's type names taken from glm, in namespace bounce::methods::cssm::glsl, and checks at
// compile time that each member sits where std430 puts it (vec4, uvec4 and mat4 columns on 16
// bytes), so the two sides cannot drift apart.
#ifdef __cplusplus
#include <glm/glm.hpp>

#include <cstddef>
#include <cstdint>

namespace bounce::methods::cssm::glsl {
using uint = std::uint32_t;
using vec4 = glm::vec4;
using uvec4 = glm::uvec4;
using mat4 = glm::mat4;
#endif

struct CssmNode {
    vec4 centre_radius;
    vec4 normal_cone;  // xyz: mean normal, w: cosine of the cone holding every normal below
    vec4 area;         // x: area, y: leaves below
    uvec4 links;       // child, skip, representative texel, leaf texel (CSSM_NONE for internal nodes)
};

// What a node sends, pulled up from its texels each bounce. A node whose texels face many ways (both
// sides of a sheet, a box's faces) sends light along each of them, not along its mean normal: its
// lobe is the luminance-weighted mean of its texels' normals, v = sum(Y L_i A_i n_i) / sum(Y L_i A_i),
// and where its normals span more than a hemisphere it sends L A (max(0, v.w) + (1 - |v|) / 4)
// towards w: what cancels in v is sent as from normals spread over the sphere, whose mean clamped
// cosine is 1/4. Within a hemisphere it sends L A max(0, v.w) / |v|, as a plane facing v would; a
// planar node's |v| is 1 and both are its L A cos. Either way it sends pi L A in all
// (docs/methods.md, "Hierarchical radiosity").
//
// A leaf sends from its spot (cssm's `texel_spots`): the part of its texel's cell that the lights'
// light falls on, a rectangle along the cell's axes (the normal's tangent_frame) as wide along each
// as the light's spread over its samples is to theirs, about the light's centre; moved from the cell
// as far as what it sends is the lights' light (not a bounce's, nor its emission). Light that falls
// on part of a texel (a strip of sun at a wall's foot, a lamp's pool of light under its shade) is
// otherwise sent from all of it. Near leaves send through the rectangle, the others through the disk
// of the texel's area about the spot's centre. Internal nodes send from their centres
// (docs/methods.md, "Texel spots").
struct CssmNodeLight {
    vec4 radiance;  // rgb: area-weighted mean exitant radiance L
    vec4 lobe;      // xyz: v; w: its length |v|
    vec4 spot;      // xyz: where it sends from; w: packHalf2x16 of its half-widths over the cell's (leaves)
};

struct CssmTexel {
    vec4 position_area;  // world position (where its object is now), area
    vec4 normal_map;     // world normal, w: the texel's map in its group's bake sequence
    vec4 albedo;         // diffuse albedo, w: its group
    vec4 emission;       // emitted radiance
};

struct CssmGroup {
    mat4 world_to_frame;  // into the frame the group was baked in
    uvec4 info;           // x: its cube maps' first pixel-run entry, y: its CSM (CSSM_NONE: static)
    vec4 planes;          // x: near, y: far
};

struct CssmCsm {
    vec4 centre_radius;  // object space
    uvec4 info;          // x: first direction, y: first table entry, z: first pixel-run entry, w: face size
    uint group;
    uint pad0;
    uint pad1;
    uint pad2;
};

#ifdef __cplusplus
static_assert(sizeof(CssmNode) == 64);
static_assert(offsetof(CssmNode, centre_radius) == 0 && offsetof(CssmNode, normal_cone) == 16 &&
              offsetof(CssmNode, area) == 32 && offsetof(CssmNode, links) == 48);
static_assert(sizeof(CssmNodeLight) == 48);
static_assert(offsetof(CssmNodeLight, radiance) == 0 && offsetof(CssmNodeLight, lobe) == 16 &&
              offsetof(CssmNodeLight, spot) == 32);
static_assert(sizeof(CssmTexel) == 64);
static_assert(offsetof(CssmTexel, position_area) == 0 && offsetof(CssmTexel, normal_map) == 16 &&
              offsetof(CssmTexel, albedo) == 32 && offsetof(CssmTexel, emission) == 48);
static_assert(sizeof(CssmGroup) == 96);
static_assert(offsetof(CssmGroup, world_to_frame) == 0 && offsetof(CssmGroup, info) == 64 &&
              offsetof(CssmGroup, planes) == 80);
static_assert(sizeof(CssmCsm) == 48);
static_assert(offsetof(CssmCsm, centre_radius) == 0 && offsetof(CssmCsm, info) == 16 && offsetof(CssmCsm, group) == 32 &&
              offsetof(CssmCsm, pad2) == 44);
}  // namespace bounce::methods::cssm::glsl
#endif

#endif
