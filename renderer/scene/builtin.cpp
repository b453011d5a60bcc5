#include "renderer/scene/builtin.hpp"

#include "renderer/base/error.hpp"
#include "renderer/scene/mesh_utils.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <array>
#include <map>
#include <cmath>

namespace bounce::scene {
namespace {

using Quad = std::array<glm::vec3, 4>;

constexpr float kMillimetre = 0.001f;

// Appends a quad as two triangles, wound so its geometric normal points along `facing` (the
// published data does not give a consistent winding).
void add_quad(Primitive& primitive, const Quad& corners_mm, const glm::vec3& facing, const glm::vec3& origin) {
    Quad q;
    for (int i = 0; i < 4; ++i) q[i] = corners_mm[i] * kMillimetre - origin;
    glm::vec3 normal = glm::normalize(glm::cross(q[1] - q[0], q[2] - q[0]));
    if (glm::dot(normal, facing) < 0.0f) {
        std::swap(q[1], q[3]);
        normal = -normal;
    }
    const auto base = static_cast<std::uint32_t>(primitive.positions.size());
    const glm::vec2 uvs[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const glm::vec3 tangent = glm::normalize(q[1] - q[0]);
    for (int i = 0; i < 4; ++i) {
        primitive.positions.push_back(q[i]);
        primitive.normals.push_back(normal);
        primitive.tangents.emplace_back(tangent, 1.0f);
        primitive.uv0.push_back(uvs[i]);
        primitive.bounds.extend(q[i]);
    }
    for (std::uint32_t index : {0u, 1u, 2u, 0u, 2u, 3u}) primitive.indices.push_back(base + index);
}

Material lambertian(const std::string& name, const glm::vec3& reflectance) {
    Material material;
    material.name = name;
    material.base_color = glm::vec4(reflectance, 1.0f);
    material.metallic = 0.0f;
    material.roughness = 1.0f;
    material.specular = 0.0f;  // the measured surfaces are matte: pure Lambertian
    return material;
}

// A one-primitive mesh, appended to the scene, and an object that places it at `origin` (metres).
// A block from its five published faces (mm), as an object whose origin is its base centre.
void add_block(Scene& scene, const std::string& name, const std::array<Quad, 5>& faces_mm, int material) {
    glm::vec3 centre_mm(0.0f);
    for (const Quad& face : faces_mm)
        for (const glm::vec3& p : face) centre_mm += p / 20.0f;
    const glm::vec3 origin{centre_mm.x * kMillimetre, 0.0f, centre_mm.z * kMillimetre};

    Primitive primitive;
    primitive.material = material;
    for (const Quad& face : faces_mm) {
        const glm::vec3 face_centre = (face[0] + face[1] + face[2] + face[3]) * 0.25f;
        add_quad(primitive, face, face_centre - centre_mm, origin);  // outward
    }
    add_primitive_object(scene, name, std::move(primitive), glm::translate(glm::mat4(1.0f), origin));
}

}  // namespace

Scene make_cornell_box() {
    Scene scene;
    scene.name = "cornell";
    // Published RGB reflectances of the Cornell box surfaces.
    scene.materials = {lambertian("white", {0.725f, 0.71f, 0.68f}), lambertian("red", {0.63f, 0.065f, 0.05f}),
                       lambertian("green", {0.14f, 0.45f, 0.091f})};
    constexpr int white = 0, red = 1, green = 2;

    // The room (published measured geometry, mm), normals facing into the box.
    const glm::vec3 inside{278.0f, 274.4f, 279.6f};
    const Quad floor{{{552.8f, 0, 0}, {0, 0, 0}, {0, 0, 559.2f}, {549.6f, 0, 559.2f}}};
    const Quad ceiling{{{556.0f, 548.8f, 0}, {556.0f, 548.8f, 559.2f}, {0, 548.8f, 559.2f}, {0, 548.8f, 0}}};
    const Quad back{{{549.6f, 0, 559.2f}, {0, 0, 559.2f}, {0, 548.8f, 559.2f}, {556.0f, 548.8f, 559.2f}}};
    const Quad right{{{0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}}};
    const Quad left{{{552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 0}}};
    Mesh room;
    room.name = "room";
    auto wall_primitive = [&](std::initializer_list<Quad> quads, int material) {
        Primitive primitive;
        primitive.material = material;
        for (const Quad& quad : quads) {
            const glm::vec3 centre = (quad[0] + quad[1] + quad[2] + quad[3]) * 0.25f;
            add_quad(primitive, quad, inside - centre, glm::vec3(0.0f));
        }
        room.bounds.extend(primitive.bounds);
        room.primitives.push_back(std::move(primitive));
    };
    wall_primitive({floor, ceiling, back}, white);
    wall_primitive({left}, red);
    wall_primitive({right}, green);
    scene.meshes.push_back(std::move(room));
    Object room_object;
    room_object.name = "room";
    room_object.mesh = 0;
    scene.objects.push_back(room_object);

    add_block(scene, "short_block",
        {{{{{130.0f, 165.0f, 65.0f}, {82.0f, 165.0f, 225.0f}, {240.0f, 165.0f, 272.0f}, {290.0f, 165.0f, 114.0f}}},
          {{{290.0f, 0.0f, 114.0f}, {290.0f, 165.0f, 114.0f}, {240.0f, 165.0f, 272.0f}, {240.0f, 0.0f, 272.0f}}},
          {{{130.0f, 0.0f, 65.0f}, {130.0f, 165.0f, 65.0f}, {290.0f, 165.0f, 114.0f}, {290.0f, 0.0f, 114.0f}}},
          {{{82.0f, 0.0f, 225.0f}, {82.0f, 165.0f, 225.0f}, {130.0f, 165.0f, 65.0f}, {130.0f, 0.0f, 65.0f}}},
          {{{240.0f, 0.0f, 272.0f}, {240.0f, 165.0f, 272.0f}, {82.0f, 165.0f, 225.0f}, {82.0f, 0.0f, 225.0f}}}}},
        white);
    add_block(scene, "tall_block",
        {{{{{423.0f, 330.0f, 247.0f}, {265.0f, 330.0f, 296.0f}, {314.0f, 330.0f, 456.0f}, {472.0f, 330.0f, 406.0f}}},
          {{{423.0f, 0.0f, 247.0f}, {423.0f, 330.0f, 247.0f}, {472.0f, 330.0f, 406.0f}, {472.0f, 0.0f, 406.0f}}},
          {{{472.0f, 0.0f, 406.0f}, {472.0f, 330.0f, 406.0f}, {314.0f, 330.0f, 456.0f}, {314.0f, 0.0f, 456.0f}}},
          {{{314.0f, 0.0f, 456.0f}, {314.0f, 330.0f, 456.0f}, {265.0f, 330.0f, 296.0f}, {265.0f, 0.0f, 296.0f}}},
          {{{265.0f, 0.0f, 296.0f}, {265.0f, 330.0f, 296.0f}, {423.0f, 330.0f, 247.0f}, {423.0f, 0.0f, 247.0f}}}}},
        white);

    // A white point light 100 mm below the centre of the published ceiling light (343..213 x
    // 227..332). Closer to the ceiling, the ceiling's radiance around it grows as 1/d^3 into a hot
    // spot that no pixel grid resolves.
    Light light;
    light.name = "ceiling_light";
    light.type = LightType::point;
    light.position = glm::vec3(278.0f, 448.8f, 279.5f) * kMillimetre;
    light.color = glm::vec3(1.0f);
    light.intensity = 0.5f;  // W/sr: about 0.57 W/(m^2 sr) off the white floor under it
    scene.lights.push_back(light);

    // The published camera: at (278, 273, -800) mm looking along +z, 35 mm lens on a 25 mm film.
    Camera camera = Camera::look_at(glm::vec3(278.0f, 273.0f, -800.0f) * kMillimetre,
                                    glm::vec3(278.0f, 273.0f, 0.0f) * kMillimetre, {0.0f, 1.0f, 0.0f},
                                    2.0f * std::atan(12.5f / 35.0f));
    camera.name = "default";
    scene.cameras.push_back(camera);
    scene.fit_bounds();
    return scene;
}

int add_primitive_object(Scene& scene, const std::string& name, Primitive primitive, const glm::mat4& transform) {
    Mesh mesh;
    mesh.name = name;
    mesh.bounds = primitive.bounds;
    mesh.primitives.push_back(std::move(primitive));
    scene.meshes.push_back(std::move(mesh));
    Object object;
    object.name = name;
    object.mesh = static_cast<int>(scene.meshes.size()) - 1;
    object.initial_transform = object.transform = transform;
    scene.objects.push_back(std::move(object));
    return static_cast<int>(scene.objects.size()) - 1;
}

int add_box(Scene& scene, const std::string& name, const glm::vec3& lo, const glm::vec3& hi, int material) {
    const glm::vec3 centre = (lo + hi) * 0.5f;
    const glm::vec3 a = (lo - centre) / kMillimetre, b = (hi - centre) / kMillimetre;
    Primitive primitive;
    primitive.material = material;
    const std::array<std::pair<Quad, glm::vec3>, 6> faces{{
        {{{{a.x, a.y, a.z}, {a.x, b.y, a.z}, {a.x, b.y, b.z}, {a.x, a.y, b.z}}}, {-1, 0, 0}},
        {{{{b.x, a.y, a.z}, {b.x, b.y, a.z}, {b.x, b.y, b.z}, {b.x, a.y, b.z}}}, {1, 0, 0}},
        {{{{a.x, a.y, a.z}, {b.x, a.y, a.z}, {b.x, a.y, b.z}, {a.x, a.y, b.z}}}, {0, -1, 0}},
        {{{{a.x, b.y, a.z}, {b.x, b.y, a.z}, {b.x, b.y, b.z}, {a.x, b.y, b.z}}}, {0, 1, 0}},
        {{{{a.x, a.y, a.z}, {b.x, a.y, a.z}, {b.x, b.y, a.z}, {a.x, b.y, a.z}}}, {0, 0, -1}},
        {{{{a.x, a.y, b.z}, {b.x, a.y, b.z}, {b.x, b.y, b.z}, {a.x, b.y, b.z}}}, {0, 0, 1}},
    }};
    for (const auto& [quad, facing] : faces) add_quad(primitive, quad, facing, glm::vec3(0.0f));
    return add_primitive_object(scene, name, std::move(primitive), glm::translate(glm::mat4(1.0f), centre));
}

Scene make_cornell_blob() {
    Scene scene = make_cornell_box();
    scene.name = "cornell_blob";
    // Replace the tall block by the blob, standing where the block stood.
    const glm::mat4 place = scene.objects[2].transform;
    scene.objects.pop_back();
    scene.meshes.pop_back();

    // An icosahedron subdivided four times (5120 triangles), projected to a sphere and displaced
    // along the radius by smooth lobes: a closed, curved surface with concave folds and no UVs.
    std::vector<glm::vec3> vertices;
    std::vector<std::uint32_t> indices;
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    for (const glm::vec3& v : {glm::vec3(-1, t, 0), glm::vec3(1, t, 0), glm::vec3(-1, -t, 0), glm::vec3(1, -t, 0),
                               glm::vec3(0, -1, t), glm::vec3(0, 1, t), glm::vec3(0, -1, -t), glm::vec3(0, 1, -t),
                               glm::vec3(t, 0, -1), glm::vec3(t, 0, 1), glm::vec3(-t, 0, -1), glm::vec3(-t, 0, 1)}) {
        vertices.push_back(glm::normalize(v));
    }
    indices = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
               3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int level = 0; level < 4; ++level) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
        auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            const auto [it, added] = midpoints.emplace(key, static_cast<std::uint32_t>(vertices.size()));
            if (added) vertices.push_back(glm::normalize(vertices[a] + vertices[b]));
            return it->second;
        };
        std::vector<std::uint32_t> finer;
        for (std::size_t i = 0; i < indices.size(); i += 3) {
            const std::uint32_t a = indices[i], b = indices[i + 1], c = indices[i + 2];
            const std::uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            finer.insert(finer.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        indices = std::move(finer);
    }
    Primitive blob;
    blob.material = 0;
    constexpr float kRadius = 0.11f;
    for (glm::vec3 d : vertices) {
        const float lobes = 0.22f * std::sin(3.0f * d.x + 1.0f) * std::sin(2.0f * d.y + 0.5f) * std::cos(3.0f * d.z) +
                            0.12f * std::sin(5.0f * d.y + 2.0f * d.x);
        const glm::vec3 p = d * kRadius * (1.0f + lobes) * glm::vec3(1.0f, 1.6f, 1.0f);
        blob.positions.push_back(p);
    }
    // Lift it onto the floor.
    float lowest = 0.0f;
    for (const glm::vec3& p : blob.positions) lowest = std::min(lowest, p.y);
    for (glm::vec3& p : blob.positions) {
        p.y -= lowest;
        blob.bounds.extend(p);
    }
    blob.indices = indices;
    // Smooth normals, area-weighted (the sphere's winding faces outwards); no UVs, so any tangent.
    blob.normals = vertex_normals(blob);
    for (const glm::vec3& n : blob.normals) blob.tangents.push_back(fallback_tangent(n));
    Mesh mesh;
    mesh.name = "blob";
    mesh.bounds = blob.bounds;
    mesh.primitives.push_back(std::move(blob));
    scene.meshes.push_back(std::move(mesh));
    Object object;
    object.name = "blob";
    object.mesh = static_cast<int>(scene.meshes.size()) - 1;
    object.initial_transform = object.transform = place;
    scene.objects.push_back(object);
    scene.fit_bounds();
    return scene;
}

std::vector<std::string> builtin_scene_names() { return {"cornell", "cornell_blob"}; }

Scene make_builtin_scene(const std::string& name) {
    if (name == "cornell") return make_cornell_box();
    if (name == "cornell_blob") return make_cornell_blob();
    throw InputError(fmt::format("unknown built-in scene '{}' (known: cornell, cornell_blob)", name));
}

}  // namespace bounce::scene
