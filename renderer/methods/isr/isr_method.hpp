// Method `isr`: hierarchical image-space radiosity (Nichols, Shopf and Wyman 2009,
// [isr] in docs/references.md). Direct light as `direct` renders it, plus one diffuse
// bounce gathered from virtual point lights on the lights' reflective shadow maps, at the eye-space
// resolution each part of the image needs: naive RSM sampling, per-frame light patches (basic), or
// per-fragment traversal of a VPL tree (hierarchical). Like the paper, no visibility between a VPL
// and the point it lights, unless `ism_size` asks for imperfect shadow maps (imperfect_shadow_maps.hpp).
#pragma once

#include "renderer/methods/registry.hpp"

namespace bounce::methods::isr {

MethodInfo method_info();

}  // namespace bounce::methods::isr
