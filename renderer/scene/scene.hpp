// The scene model every method, the reference and the daemon share.
//
// Units are linear radiometric: point and spot intensity is radiant intensity (W/sr),
// directional intensity is irradiance (W/m^2), emission is radiance (W/(m^2 sr)).
// Lengths are metres.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace bounce::scene {

struct Aabb {
    glm::vec3 min{std::numeric_limits<float>::max()};
    glm::vec3 max{-std::numeric_limits<float>::max()};

    bool empty() const { return min.x > max.x || min.y > max.y || min.z > max.z; }
    // Corner i: bit 0 picks max.x, bit 1 max.y, bit 2 max.z.
    glm::vec3 corner(int i) const {
        return {(i & 1) ? max.x : min.x, (i & 2) ? max.y : min.y, (i & 4) ? max.z : min.z};
    }
    float farthest_distance(const glm::vec3& from) const {
        float farthest = 0.0f;
        for (int i = 0; i < 8; ++i) farthest = std::max(farthest, glm::length(corner(i) - from));
        return farthest;
    }
    void extend(const glm::vec3& p) {
        min = glm::min(min, p);
        max = glm::max(max, p);
    }
    void extend(const Aabb& other) {
        if (other.empty()) return;
        extend(other.min);
        extend(other.max);
    }
    glm::vec3 center() const { return 0.5f * (min + max); }
    glm::vec3 extent() const { return empty() ? glm::vec3(0.0f) : max - min; }
    // The box that holds this box after `transform` (all eight corners transformed).
    Aabb transformed(const glm::mat4& transform) const;
};

// An 8-bit RGBA texture as decoded from the file; `srgb` tells how the sampler reads it.
// A glTF sampler: how a texture is filtered and wrapped, as OpenGL defines the modes. Absent
// filters are trilinear, absent wraps repeat.
struct TextureSampler {
    enum class Wrap : std::uint8_t { repeat, clamp_to_edge, mirrored_repeat };
    enum class MinFilter : std::uint8_t {
        nearest, linear, nearest_mipmap_nearest, linear_mipmap_nearest, nearest_mipmap_linear, linear_mipmap_linear
    };
    Wrap wrap_s = Wrap::repeat, wrap_t = Wrap::repeat;
    bool mag_nearest = false;  // magFilter NEAREST; the CPU twin, which has no mipmaps, samples as magnified
    MinFilter min_filter = MinFilter::linear_mipmap_linear;
    bool operator==(const TextureSampler&) const = default;
};

struct Texture {
    std::string name;
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgba8;  // width * height * 4, rows top to bottom
    bool srgb = false;
    TextureSampler sampler;
};

// A texture reference inside a material: an index into Scene::textures and the UV set it reads.
struct TextureRef {
    int texture = -1;  // -1: none
    int uv_set = 0;    // 0 or 1
    // KHR_texture_transform: uv' = (uv_transform * (uv, 1)).xy, translation * rotation * scale.
    glm::mat3 uv_transform{1.0f};
    bool valid() const { return texture >= 0; }
    glm::vec2 transform(const glm::vec2& uv) const { return glm::vec2(uv_transform * glm::vec3(uv, 1.0f)); }
};

// glTF alphaMode. BLEND is coverage, not compositing: a point with alpha a is there with
// probability a, for camera, shadow and GI alike (screen-door on the GPU, any-hit on the CPU).
// The numbers are shaders/common/shared_layout.h's BOUNCE_ALPHA_*.
enum class AlphaMode : int { opaque = 0, mask = 1, blend = 2 };

// glTF metallic-roughness material plus KHR_materials_emissive_strength and the
// KHR_materials_specular factor (0 turns the dielectric specular lobe off: pure Lambertian).
// docs/methods.md gives the BRDF; renderer/scene/brdf.hpp and shaders/common/brdf.glsl implement it.
struct Material {
    std::string name;
    glm::vec4 base_color{1.0f};  // linear RGB reflectance + alpha
    float metallic = 1.0f;
    float roughness = 1.0f;
    float specular = 1.0f;  // KHR_materials_specular specularFactor
    glm::vec3 specular_color{1.0f};  // KHR_materials_specular specularColorFactor
    float ior = 1.5f;                // KHR_materials_ior
    // The dielectric's F0 colour before the specular factor: min(((ior - 1)/(ior + 1))^2 colour, 1).
    glm::vec3 dielectric_f0() const;
    glm::vec3 emissive{0.0f};  // radiance, emissive_strength already applied
    float normal_scale = 1.0f;
    bool double_sided = false;
    // glTF alphaMode, for every pass and ray; alpha is base-colour alpha (factor times texture).
    AlphaMode alpha_mode = AlphaMode::opaque;
    float alpha_cutoff = 0.5f;  // MASK: below it the surface is not there
    // The fraction of a point with base-colour alpha `alpha` that the surface covers: 1 when
    // opaque, 0 or 1 for MASK, alpha (clamped to [0, 1]) for BLEND.
    float coverage(float alpha) const;
    TextureRef base_color_texture;          // sRGB
    TextureRef metallic_roughness_texture;  // linear: G = roughness, B = metallic
    TextureRef normal_texture;              // linear, tangent space
    TextureRef emissive_texture;            // sRGB
    TextureRef specular_texture;            // linear: A scales the specular factor
    TextureRef specular_color_texture;      // sRGB: RGB scales the specular colour

    bool glossy() const;  // has a specular lobe that is not negligible
};

// One triangle list with one material. Vertex attributes are parallel arrays; normals and
// tangents are always present after import (generated when the file has none).
struct Primitive {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;
    std::vector<glm::vec4> tangents;  // xyz tangent, w handedness
    std::vector<glm::vec2> uv0;       // empty when the file has no UVs
    std::vector<glm::vec2> uv1;
    std::vector<std::uint32_t> indices;  // always indexed after import; size % 3 == 0
    int material = -1;  // -1: the default material
    Aabb bounds;

    std::size_t triangle_count() const { return indices.size() / 3; }
};

struct Mesh {
    std::string name;
    std::vector<Primitive> primitives;
    Aabb bounds;  // in mesh space
};

// A rigid object: one glTF node with a mesh, its world transform the product of its ancestors'.
// Clients address objects by name (unique within a scene) or index and move them.
struct Object {
    std::string name;
    int mesh = -1;
    glm::mat4 initial_transform{1.0f};  // as loaded
    glm::mat4 transform{1.0f};          // current world transform
    // Declared movable when the scene was loaded: methods that precompute (cssm) prepare it for
    // motion up front instead of when it first moves.
    bool dynamic = false;

    // The box around the mesh's vertices at `fitted_transform` (Scene::fit_bounds). Lights' views,
    // shadow maps and voxel grids are fitted to these boxes, and the corners of a rotated mesh box
    // hold space its mesh does not fill: fitted to the mesh's box, a frame would depend on whether
    // the file's exporter rotated its nodes or its vertices.
    Aabb fitted_bounds;
    std::optional<glm::mat4> fitted_transform;
    // fitted_bounds at the transform they were fitted at; at another, the mesh box's corners
    // transformed (looser, never too small).
    Aabb world_bounds(const Mesh& mesh_data) const {
        return fitted_transform && *fitted_transform == transform ? fitted_bounds : mesh_data.bounds.transformed(transform);
    }
};

enum class LightType { point, spot, directional };

struct Light {
    std::string name;
    LightType type = LightType::point;
    glm::vec3 position{0.0f};
    glm::vec3 direction{0.0f, 0.0f, -1.0f};  // the way light travels (spot, directional); unit
    glm::vec3 color{1.0f};                    // linear RGB, multiplies intensity
    float intensity = 1.0f;                   // W/sr (point, spot) or W/m^2 (directional)
    float inner_cone = 0.0f;                  // radians, spot only
    float outer_cone = 0.78539816f;           // radians, spot only (glTF default pi/4)

    glm::vec3 radiant() const { return color * intensity; }
};

struct Camera {
    std::string name;
    glm::vec3 position{0.0f};
    glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};  // looks along -Z of this frame, +Y up
    float vertical_fov = 0.8f;  // radians
    float z_near = 0.0f;  // 0: derived from the far plane (scale-invariant)
    float z_far = 0.0f;   // 0: derived from the scene bounds

    glm::vec3 forward() const { return orientation * glm::vec3(0.0f, 0.0f, -1.0f); }
    glm::vec3 up() const { return orientation * glm::vec3(0.0f, 1.0f, 0.0f); }
    glm::mat4 view() const;
    // Perspective projection for `aspect` = width / height; `far` is used when z_far is 0.
    glm::mat4 projection(float aspect, float far) const;
    // The far plane that holds `bounds` as seen from this camera.
    float far_plane_for(const Aabb& bounds) const;
    // A camera at `eye` looking at `target`.
    static Camera look_at(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up,
                          float vertical_fov);
};

// The far-plane distance of a view from `from` that must hold all of `bounds`: the farthest corner
// plus 5%, so rounding never clips it; never zero. Cameras and light views share it.
float far_plane_distance(const Aabb& bounds, const glm::vec3& from);

// The view of a scene that has no camera: from +Z towards the centre of `bounds`, all of them in view.
Camera framing_camera(const Aabb& bounds);

struct Scene {
    std::string name;
    std::vector<Texture> textures;
    std::vector<Material> materials;
    std::vector<Mesh> meshes;
    std::vector<Object> objects;
    std::vector<Light> lights;
    std::vector<Camera> cameras;  // cameras[0] is the default view
    std::vector<std::string> warnings;  // what the importer fell back on

    Aabb world_bounds() const;
    // Fits each object's bounds (one object's) to its mesh's vertices at its transform
    // (Object::fitted_bounds): the importers do it, and whoever moves an object or changes a mesh's
    // vertices does it again; until then the object keeps its looser box.
    void fit_bounds();
    void fit_bounds(std::size_t object);
    // The material a primitive uses (the default material for -1).
    const Material& material(int index) const;
    std::optional<std::size_t> find_object(const std::string& name) const;
    std::optional<std::size_t> find_light(const std::string& name) const;
    std::optional<std::size_t> find_camera(const std::string& name) const;
    std::size_t triangle_count() const;
    bool has_glossy_material() const;

    static const Material& default_material();
};

// Throws InputError naming the first non-finite position, normal or transform found.
void validate_finite(const Scene& scene);

}  // namespace bounce::scene
