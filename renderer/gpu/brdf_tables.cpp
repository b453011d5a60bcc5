#include "renderer/gpu/brdf_tables.hpp"

#include "common/shared_layout.h"
#include "renderer/scene/shading.hpp"

namespace bounce::gpu {
namespace {

// Linear filtering between cell centres, clamped at the edges: what scene::specular_albedo_ab and
// specular_average_ab compute on the CPU.
Texture table_texture(const std::vector<glm::vec2>& values, int width, int height) {
    Texture texture({GL_TEXTURE_2D, GL_RG32F, width, height});
    glTextureSubImage2D(texture.id(), 0, 0, 0, width, height, GL_RG, GL_FLOAT, values.data());
    texture.set_filter(GL_LINEAR, GL_LINEAR);
    texture.set_wrap(GL_CLAMP_TO_EDGE);
    return texture;
}

}  // namespace

BrdfTables::BrdfTables() {
    const auto& tables = scene::brdf_tables();
    constexpr int size = scene::BrdfTables::kSize;
    albedo_ = table_texture(tables.albedo, size, size);
    average_ = table_texture(tables.average, size, 1);
}

void BrdfTables::bind() const {
    glBindTextureUnit(BOUNCE_UNIT_BRDF_ALBEDO, albedo_.id());
    glBindTextureUnit(BOUNCE_UNIT_BRDF_AVERAGE, average_.id());
}

}  // namespace bounce::gpu
