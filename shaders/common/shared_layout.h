// Binding slots and constants shared by C++ and GLSL: this file compiles as both.
#ifndef BOUNCE_SHARED_LAYOUT_H
#define BOUNCE_SHARED_LAYOUT_H

// Vertex attribute locations (renderer/gpu/gpu_scene.cpp sets up the matching vertex format).
#define BOUNCE_ATTR_POSITION 0
#define BOUNCE_ATTR_NORMAL 1
#define BOUNCE_ATTR_TANGENT 2
#define BOUNCE_ATTR_UV0 3
#define BOUNCE_ATTR_UV1 4

// Texture units: material textures.
#define BOUNCE_UNIT_BASE_COLOR 0
#define BOUNCE_UNIT_METALLIC_ROUGHNESS 1
#define BOUNCE_UNIT_NORMAL 2
#define BOUNCE_UNIT_EMISSIVE 3
// KHR_materials_specular's textures. They share units 11 and 12 with vct's brick pools: passes that
// rasterize materials and vct's cone trace each bind what they sample before they draw.
#define BOUNCE_UNIT_SPECULAR 11
#define BOUNCE_UNIT_SPECULAR_COLOR 12
// Texture units: G-buffer.
#define BOUNCE_UNIT_GBUFFER_POSITION 4
#define BOUNCE_UNIT_GBUFFER_NORMAL 5
#define BOUNCE_UNIT_GBUFFER_ALBEDO 6
#define BOUNCE_UNIT_GBUFFER_EMISSIVE 7
#define BOUNCE_UNIT_GBUFFER_SPECULAR 13
// Texture units: light-view maps and frame inputs.
#define BOUNCE_UNIT_SHADOW_2D 8
#define BOUNCE_UNIT_SHADOW_CUBE 9
#define BOUNCE_UNIT_SHADOW_VIEW 16  // a directional light's view cascades, layers of a 2D array
#define BOUNCE_SHADOW_VIEW_CASCADES 4  // at most
#define BOUNCE_UNIT_HDR_INPUT 10
// Texture units: the BRDF's energy-compensation tables (gpu::BrdfTables binds them for every frame;
// methods leave these units alone).
#define BOUNCE_UNIT_BRDF_ALBEDO 14   // RG32F, (A, B) of the specular lobe by n.v (x) and roughness (y)
#define BOUNCE_UNIT_BRDF_AVERAGE 15  // RG32F, their cosine-weighted means by roughness (x)

// Storage binding of the bounds-checked shader build's failure record (renderer/gpu/bounds_check.hpp);
// no pass binds anything else here.
#define BOUNCE_BINDING_BOUNDS_CHECK 31

// glTF alphaMode, as scene::AlphaMode numbers it.
#define BOUNCE_ALPHA_OPAQUE 0
#define BOUNCE_ALPHA_MASK 1
#define BOUNCE_ALPHA_BLEND 2

// G-buffer colour attachments.
#define BOUNCE_GBUFFER_POSITION 0   // RGBA32F: world position, w = 1 where geometry was drawn
#define BOUNCE_GBUFFER_NORMAL 1     // RGBA16F: shading normal, w = perceptual roughness
#define BOUNCE_GBUFFER_ALBEDO 2     // RGBA16F: base colour, w = metallic
#define BOUNCE_GBUFFER_EMISSIVE 3   // RGBA32F: emitted radiance, w = specular factor
#define BOUNCE_GBUFFER_SPECULAR 4   // RGBA16F: the dielectric's F0 colour before the specular factor
#define BOUNCE_GBUFFER_TARGETS 5

// Light types (scene::LightType in the same order).
#define BOUNCE_LIGHT_POINT 0
#define BOUNCE_LIGHT_SPOT 1
#define BOUNCE_LIGHT_DIRECTIONAL 2

// Tone curves (image::ToneCurve in the same order).
#define BOUNCE_TONE_NONE 0
#define BOUNCE_TONE_REINHARD 1
#define BOUNCE_TONE_ACES 2

#endif
