// Bindings and constants of `cssm`, shared by C++ and GLSL.
#ifndef BOUNCE_CSSM_LAYOUT_H
#define BOUNCE_CSSM_LAYOUT_H

#define CSSM_BINDING_NODES 0         // CssmNode[]: the radiosity hierarchy, depth-first, child + skip pointers
#define CSSM_BINDING_NODE_RADIANCE 1 // vec4[nodes]: area-weighted mean exitant radiance (pulled)
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

#define CSSM_TABLE_FACE 16

#define CSSM_NONE 0xFFFFFFFFu

#define CSSM_COUNTER_RECEIVERS 0      // receivers (texels or pixels) that gathered
#define CSSM_COUNTER_NODES_LOW 1      // sender nodes gathered, summed over receivers (two words)
#define CSSM_COUNTER_NODES_HIGH 2
#define CSSM_COUNTER_VISITED_LOW 3    // nodes the traversals visited (refined or gathered)
#define CSSM_COUNTER_VISITED_HIGH 4
#define CSSM_COUNTERS 5

#endif
