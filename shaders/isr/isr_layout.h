// Bindings, image units and constants of image-space radiosity, shared by C++ and GLSL.
#ifndef BOUNCE_ISR_LAYOUT_H
#define BOUNCE_ISR_LAYOUT_H

// Eye space: the multiresolution buffer is flattened into one atlas, full resolution on the left
// and the coarser levels stacked in a column on its right (shaders/isr/multires.glsl).
#define ISR_MAX_LEVELS 8
#define ISR_IMAGE_IRRADIANCE 0  // RGBA32F atlas: irradiance; w: 1 + VPLs gathered, 0.5 filled, 0 none
#define ISR_IMAGE_DEPTH 1       // RGBA32F atlas: min, max view depth, covered fraction, mean depth
#define ISR_IMAGE_NORMAL_MIN 2  // RGBA16F atlas: per-component minimum of the normals
#define ISR_IMAGE_NORMAL_MAX 3  // RGBA16F atlas: per-component maximum

// Light space: the VPL tree. Per light view, the light-view map's texels are the finest VPLs
// (level 0), and level k holds (size >> k)^2 patches of 2^k x 2^k texels, up to the top level of
// ISR_TOP_PATCHES^2 patches, stored level after level (shaders/isr/vpl.glsl).
#define ISR_TOP_PATCHES 16
#define ISR_MAX_TREE_LEVELS 12
#define ISR_BINDING_NODES 0     // VplNode[]
#define ISR_BINDING_CACHE 1     // VPL cache: uint count, 3 pad, then Vpl[]
#define ISR_BINDING_COUNTERS 2  // uint[ISR_COUNTERS]
#define ISR_BINDING_TREE_INFO 3 // float[4]: largest flux channel summed over every VPL, 3 pad
// Imperfect shadow maps (isr/ism.glsl): per map, u_ism_size^2 texels of distances from its patch.
#define ISR_BINDING_ISM_DEPTH 4       // uint[]: the splatted distances' bits, 0xFFFFFFFF where no point fell
#define ISR_BINDING_ISM_FILLED 5      // float[]: the same with holes filled (what the gather reads)
#define ISR_BINDING_ISM_POINTS 6      // vec4[]: the point cloud, object-space position and object index
#define ISR_BINDING_ISM_TRANSFORMS 7  // mat4[]: every object's world transform
#define ISR_BINDING_ISM_FRAMES 8      // vec4[2 per map]: centre (w: 1 where the patch carries flux), pole
#define ISR_BINDING_ISM_COARSE 9      // uint per tree node: the map a node above the maps' level uses

#define ISR_COUNTER_LEVEL_FRAGMENTS 0  // ISR_MAX_LEVELS counters: multiresolution fragments per level
#define ISR_COUNTER_VPLS_LOW 8         // VPLs gathered over every fragment, low and high words
#define ISR_COUNTER_VPLS_HIGH 9
#define ISR_COUNTER_VPLS_MAX 10        // most VPLs one fragment gathered
#define ISR_COUNTER_GATHERED 11        // atlas texels the gather reached (the stencil's marks, if it works)
#define ISR_COUNTERS 12

#define ISR_MODE_NAIVE 0         // one point-sampled VPL per patch of the finest level (plain RSM)
#define ISR_MODE_BASIC 1         // per-frame light patches, clustered where continuous (§3.4)
#define ISR_MODE_HIERARCHICAL 2  // per-fragment traversal of the VPL tree (§3.5)

#define ISR_MAX_STACK 32

#endif
