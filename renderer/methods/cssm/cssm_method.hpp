// Method `cssm`: coherent surface shadow maps with GPU hierarchical radiosity and final gathering
// (Ritschel, Grosch, Kautz and Seidel 2008, [cssm] in docs/references.md). Direct light
// as `direct` renders it; n diffuse bounces computed on a surface atlas by hierarchical radiosity
// with clustering, with visibility from depth cube maps baked at every atlas texel; the last
// bounce gathered per pixel through the same hierarchy.
#pragma once

#include "renderer/methods/registry.hpp"

namespace bounce::methods::cssm {

MethodInfo method_info();

}  // namespace bounce::methods::cssm
