// Method `direct`: emission plus direct light from every punctual light with shadow maps. No
// indirect light; the baseline every GI method adds to, and what `reference` with zero bounces
// must match.
#pragma once

#include "renderer/methods/registry.hpp"

namespace bounce::methods::direct {

MethodInfo method_info();

}  // namespace bounce::methods::direct
