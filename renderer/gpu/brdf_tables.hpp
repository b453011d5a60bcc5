// The BRDF's energy-compensation tables on the GPU: scene::brdf_tables() as two RG32F textures,
// bound to the units shaders/common/brdf.glsl reads (BOUNCE_UNIT_BRDF_ALBEDO, _AVERAGE). One per
// context, bound for every frame, so that every method's shaders evaluate the same BRDF as the
// CPU twin.
#pragma once

#include "renderer/gpu/gl_objects.hpp"

namespace bounce::gpu {

class BrdfTables {
public:
    BrdfTables();
    void bind() const;
    std::size_t bytes() const { return albedo_.bytes() + average_.bytes(); }

private:
    Texture albedo_;   // kSize x kSize: (A, B) by n.v (x) and roughness (y)
    Texture average_;  // kSize x 1: their means by roughness
};

}  // namespace bounce::gpu
