#include "bench/corpus.hpp"

#include "renderer/scene/builtin.hpp"
#include "renderer/scene/mesh_utils.hpp"

#include <glm/gtc/constants.hpp>

#include <cmath>
#include <string>

namespace bounce::bench {
namespace {

using glm::vec2;
using glm::vec3;

// Triangles of one material, wound so that each faces the way its caller says.
class PrimitiveBuilder {
public:
    explicit PrimitiveBuilder(int material) { primitive_.material = material; }

    std::uint32_t vertex(const vec3& position, const vec3& normal, const vec2& uv) {
        primitive_.positions.push_back(position);
        primitive_.normals.push_back(glm::normalize(normal));
        primitive_.tangents.push_back(scene::fallback_tangent(glm::normalize(normal)));
        primitive_.uv0.push_back(uv);
        primitive_.bounds.extend(position);
        return static_cast<std::uint32_t>(primitive_.positions.size() - 1);
    }
    // A triangle whose geometric normal points along `facing`.
    void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, const vec3& facing) {
        const auto& p = primitive_.positions;
        if (glm::dot(glm::cross(p[b] - p[a], p[c] - p[a]), facing) < 0.0f) std::swap(b, c);
        primitive_.indices.insert(primitive_.indices.end(), {a, b, c});
    }
    // A flat quad a-b-c-d (in order around it) facing along `facing`; UVs span `uv_scale`.
    void quad(const vec3& a, const vec3& b, const vec3& c, const vec3& d, const vec3& facing, vec2 uv_scale = {1, 1}) {
        vec3 normal = glm::normalize(glm::cross(b - a, c - a));
        if (glm::dot(normal, facing) < 0.0f) normal = -normal;
        const std::uint32_t i0 = vertex(a, normal, {0, 0}), i1 = vertex(b, normal, {uv_scale.x, 0});
        const std::uint32_t i2 = vertex(c, normal, uv_scale), i3 = vertex(d, normal, {0, uv_scale.y});
        triangle(i0, i1, i2, normal);
        triangle(i0, i2, i3, normal);
    }
    // The side of a vertical cylinder (smooth normals, outward), without caps: a column, or a
    // lampshade when its material is double-sided.
    void cylinder(const vec3& base, float radius, float height, int segments) {
        for (int i = 0; i < segments; ++i) {
            const float a0 = glm::two_pi<float>() * i / segments, a1 = glm::two_pi<float>() * (i + 1) / segments;
            const vec3 n0(std::cos(a0), 0, std::sin(a0)), n1(std::cos(a1), 0, std::sin(a1));
            const float u0 = static_cast<float>(i) / segments, u1 = static_cast<float>(i + 1) / segments;
            const std::uint32_t b0 = vertex(base + radius * n0, n0, {u0, 0}), b1 = vertex(base + radius * n1, n1, {u1, 0});
            const std::uint32_t t1 = vertex(base + radius * n1 + vec3(0, height, 0), n1, {u1, 1});
            const std::uint32_t t0 = vertex(base + radius * n0 + vec3(0, height, 0), n0, {u0, 1});
            const vec3 outward = n0 + n1;
            triangle(b0, b1, t1, outward);
            triangle(b0, t1, t0, outward);
        }
    }
    // A UV sphere, smooth normals outward.
    void sphere(const vec3& centre, float radius, int segments) {
        const int rings = std::max(2, segments / 2);
        const auto at = [&](int ring, int segment) {
            const float theta = glm::pi<float>() * ring / rings, phi = glm::two_pi<float>() * segment / segments;
            const vec3 n(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
            return vertex(centre + radius * n, n, {static_cast<float>(segment) / segments, static_cast<float>(ring) / rings});
        };
        for (int r = 0; r < rings; ++r) {
            for (int s = 0; s < segments; ++s) {
                const std::uint32_t a = at(r, s), b = at(r, s + 1), c = at(r + 1, s + 1), d = at(r + 1, s);
                const auto& p = primitive_.positions;
                const vec3 outward = (p[a] + p[b] + p[c] + p[d]) * 0.25f - centre;
                if (r > 0) triangle(a, b, c, outward);
                if (r + 1 < rings) triangle(a, c, d, outward);
            }
        }
    }
    scene::Primitive take() { return std::move(primitive_); }

private:
    scene::Primitive primitive_;
};

void add(scene::Scene& scene, const std::string& name, PrimitiveBuilder& builder) {
    scene::add_primitive_object(scene, name, builder.take());
}

int material(scene::Scene& scene, const std::string& name, const vec3& colour, float roughness = 1.0f,
             float metallic = 0.0f, float specular = 0.0f) {
    scene::Material m;
    m.name = name;
    m.base_color = glm::vec4(colour, 1.0f);
    m.roughness = roughness;
    m.metallic = metallic;
    m.specular = specular;
    scene.materials.push_back(m);
    return static_cast<int>(scene.materials.size() - 1);
}

// A thin sheet seen from both sides (cloth, a lampshade, a leaf card).
int sheet_material(scene::Scene& scene, const std::string& name, const vec3& colour) {
    const int index = material(scene, name, colour);
    scene.materials[static_cast<std::size_t>(index)].double_sided = true;
    return index;
}

scene::Light point_light(const std::string& name, const vec3& position, float intensity, const vec3& colour = vec3(1)) {
    scene::Light light;
    light.name = name;
    light.type = scene::LightType::point;
    light.position = position;
    light.intensity = intensity;
    light.color = colour;
    return light;
}

scene::Light sun(const vec3& direction, float intensity) {
    scene::Light light;
    light.name = "sun";
    light.type = scene::LightType::directional;
    light.direction = glm::normalize(direction);
    light.intensity = intensity;
    light.color = {1.0f, 0.95f, 0.88f};
    return light;
}

void set_camera(scene::Scene& scene, const vec3& eye, const vec3& target, float fov_deg) {
    scene::Camera camera = scene::Camera::look_at(eye, target, {0, 1, 0}, glm::radians(fov_deg));
    camera.name = "default";
    scene.cameras = {camera};
}

// A closed room [0, size] of walls `thickness` thick, whose +x wall has a window: the wall is built
// around the opening [window_lo, window_hi] (in y, z); an empty opening leaves the wall whole.
void add_room(scene::Scene& scene, const vec3& size, float thickness, int walls, int floor, const vec2& window_lo,
              const vec2& window_hi) {
    const float t = thickness;
    scene::add_box(scene, "floor", {-t, -t, -t}, {size.x + t, 0, size.z + t}, floor);
    scene::add_box(scene, "ceiling", {-t, size.y, -t}, {size.x + t, size.y + t, size.z + t}, walls);
    scene::add_box(scene, "wall_back", {-t, 0, size.z}, {size.x + t, size.y, size.z + t}, walls);
    scene::add_box(scene, "wall_front", {-t, 0, -t}, {size.x + t, size.y, 0}, walls);
    scene::add_box(scene, "wall_left", {-t, 0, 0}, {0, size.y, size.z}, walls);
    const float x0 = size.x, x1 = size.x + t;
    if (!(window_hi.x > window_lo.x && window_hi.y > window_lo.y)) {
        scene::add_box(scene, "wall_right", {x0, 0, 0}, {x1, size.y, size.z}, walls);
        return;
    }
    scene::add_box(scene, "wall_right_below", {x0, 0, 0}, {x1, window_lo.x, size.z}, walls);
    scene::add_box(scene, "wall_right_above", {x0, window_hi.x, 0}, {x1, size.y, size.z}, walls);
    scene::add_box(scene, "wall_right_side0", {x0, window_lo.x, 0}, {x1, window_hi.x, window_lo.y}, walls);
    scene::add_box(scene, "wall_right_side1", {x0, window_lo.x, window_hi.y}, {x1, window_hi.x, size.z}, walls);
}

// A furnished room: the sun through a window, two floor lamps whose bulbs sit inside thin shades,
// a table, a sofa, shelves and a rug. Most of the light reaches the eye after several bounces, and
// the shades hide the bulbs from nearly everything.
BenchScene furnished_room(int detail) {
    scene::Scene scene;
    scene.name = "furnished_room";
    const int plaster = material(scene, "plaster", {0.8f, 0.78f, 0.74f});
    const int oak = material(scene, "oak", {0.45f, 0.3f, 0.18f}, 0.5f, 0.0f, 0.5f);
    const int fabric = material(scene, "fabric", {0.25f, 0.35f, 0.6f});
    const int rug = material(scene, "rug", {0.6f, 0.2f, 0.15f});
    const int metal = material(scene, "brass", {0.9f, 0.7f, 0.4f}, 0.35f, 1.0f, 1.0f);
    const int shade = sheet_material(scene, "linen", {0.85f, 0.82f, 0.75f});
    const vec3 room{6.0f, 3.0f, 5.0f};
    add_room(scene, room, 0.15f, plaster, oak, {0.9f, 1.5f}, {2.3f, 3.5f});

    scene::add_box(scene, "rug", {1.5f, 0.0f, 1.2f}, {4.5f, 0.01f, 3.8f}, rug);
    // A table: top and four legs.
    scene::add_box(scene, "table_top", {2.2f, 0.72f, 2.0f}, {3.8f, 0.76f, 3.0f}, oak);
    for (int i = 0; i < 4; ++i) {
        const float x = i % 2 ? 3.7f : 2.25f, z = i / 2 ? 2.9f : 2.05f;
        scene::add_box(scene, "table_leg" + std::to_string(i), {x, 0.0f, z}, {x + 0.05f, 0.72f, z + 0.05f}, oak);
    }
    // A sofa against the back wall: seat, back, arms.
    scene::add_box(scene, "sofa_seat", {1.8f, 0.0f, 4.1f}, {4.2f, 0.45f, 4.9f}, fabric);
    scene::add_box(scene, "sofa_back", {1.8f, 0.45f, 4.7f}, {4.2f, 0.95f, 4.95f}, fabric);
    scene::add_box(scene, "sofa_arm_left", {1.6f, 0.0f, 4.1f}, {1.8f, 0.65f, 4.95f}, fabric);
    scene::add_box(scene, "sofa_arm_right", {4.2f, 0.0f, 4.1f}, {4.4f, 0.65f, 4.95f}, fabric);
    // Shelves on the left wall.
    scene::add_box(scene, "shelf_side0", {0.0f, 0.0f, 0.6f}, {0.35f, 2.0f, 0.63f}, oak);
    scene::add_box(scene, "shelf_side1", {0.0f, 0.0f, 1.8f}, {0.35f, 2.0f, 1.83f}, oak);
    for (int i = 0; i < 5; ++i) {
        const float y = 0.1f + 0.45f * i;
        scene::add_box(scene, "shelf" + std::to_string(i), {0.0f, y, 0.63f}, {0.35f, y + 0.03f, 1.8f}, oak);
    }
    // Two floor lamps: a pole, and a bulb inside an open-ended linen shade.
    const int segments = 24 * detail;
    for (int i = 0; i < 2; ++i) {
        const vec3 foot = i == 0 ? vec3(1.2f, 0.0f, 4.5f) : vec3(4.9f, 0.0f, 4.5f);
        scene::add_box(scene, "lamp_pole" + std::to_string(i), foot + vec3(-0.015f, 0, -0.015f), foot + vec3(0.015f, 1.45f, 0.015f), metal);
        PrimitiveBuilder lampshade(shade);
        lampshade.cylinder(foot + vec3(0, 1.3f, 0), 0.22f, 0.32f, segments);
        add(scene, "lamp_shade" + std::to_string(i), lampshade);
        scene.lights.push_back(point_light("lamp" + std::to_string(i), foot + vec3(0, 1.45f, 0), 1.2f, {1.0f, 0.85f, 0.65f}));
    }
    // Low sun through the window, across the floor.
    scene.lights.push_back(sun({-1.0f, -0.55f, 0.25f}, 6.0f));
    set_camera(scene, {0.6f, 1.6f, 0.4f}, {4.2f, 0.9f, 3.6f}, 65.0f);
    return {"furnished_room", "a room lit by the sun through a window and two lamps inside thin shades", std::move(scene)};
}

// A colonnaded atrium: the sun through skylights, galleries on columns along both sides, cloth
// banners hanging from the roof.
BenchScene atrium(int detail) {
    scene::Scene scene;
    scene.name = "atrium";
    const int stone = material(scene, "stone", {0.7f, 0.66f, 0.6f});
    const int floor = material(scene, "marble", {0.75f, 0.72f, 0.68f}, 0.3f, 0.0f, 0.5f);
    const int red_cloth = sheet_material(scene, "red_cloth", {0.6f, 0.1f, 0.08f});
    const int blue_cloth = sheet_material(scene, "blue_cloth", {0.1f, 0.2f, 0.55f});
    const vec3 hall{20.0f, 12.0f, 14.0f};
    const float t = 0.4f;
    scene::add_box(scene, "floor", {-t, -t, -t}, {hall.x + t, 0, hall.z + t}, floor);
    scene::add_box(scene, "wall_back", {-t, 0, hall.z}, {hall.x + t, hall.y, hall.z + t}, stone);
    scene::add_box(scene, "wall_front", {-t, 0, -t}, {hall.x + t, hall.y, 0}, stone);
    scene::add_box(scene, "wall_left", {-t, 0, 0}, {0, hall.y, hall.z}, stone);
    scene::add_box(scene, "wall_right", {hall.x, 0, 0}, {hall.x + t, hall.y, hall.z}, stone);
    // The roof in strips along x, with two skylights between them.
    scene::add_box(scene, "roof0", {-t, hall.y, -t}, {hall.x + t, hall.y + t, 4.0f}, stone);
    scene::add_box(scene, "roof1", {-t, hall.y, 5.5f}, {hall.x + t, hall.y + t, 8.5f}, stone);
    scene::add_box(scene, "roof2", {-t, hall.y, 10.0f}, {hall.x + t, hall.y + t, hall.z + t}, stone);
    // Galleries at 6 m along both long walls, each on a row of columns.
    const int segments = 16 * detail;
    for (int side = 0; side < 2; ++side) {
        const float z0 = side == 0 ? 0.0f : hall.z - 3.0f, z1 = side == 0 ? 3.0f : hall.z;
        scene::add_box(scene, "gallery" + std::to_string(side), {0.0f, 6.0f, z0}, {hall.x, 6.4f, z1}, stone);
        PrimitiveBuilder columns(stone);
        const float z = side == 0 ? 3.0f : hall.z - 3.0f;
        for (int i = 0; i < 7; ++i) columns.cylinder({1.5f + 2.833f * i, 0.0f, z}, 0.35f, 6.0f, segments);
        add(scene, "columns" + std::to_string(side), columns);
    }
    // Banners hanging from the roof over the nave, subdivided so that they have vertices to spare.
    for (int i = 0; i < 4; ++i) {
        PrimitiveBuilder banner(i % 2 ? blue_cloth : red_cloth);
        const float x = 4.0f + 4.0f * i, rows = static_cast<float>(4 * detail);
        for (int r = 0; r < static_cast<int>(rows); ++r) {
            const float y0 = hall.y - 7.0f * r / rows, y1 = hall.y - 7.0f * (r + 1) / rows;
            banner.quad({x, y0, 6.0f}, {x, y0, 8.0f}, {x, y1, 8.0f}, {x, y1, 6.0f}, {1, 0, 0});
        }
        add(scene, "banner" + std::to_string(i), banner);
    }
    scene.lights.push_back(sun({0.35f, -1.0f, 0.15f}, 8.0f));
    set_camera(scene, {1.0f, 1.7f, 7.0f}, {19.0f, 5.0f, 7.0f}, 70.0f);
    return {"atrium", "a colonnaded atrium lit by the sun through skylights, banners hanging in the nave", std::move(scene)};
}

// An open street: buildings and trees on a ground plane under a low sun; most light that leaves a
// surface leaves the scene.
BenchScene outdoor(int detail) {
    scene::Scene scene;
    scene.name = "outdoor";
    const int ground = material(scene, "asphalt", {0.2f, 0.2f, 0.2f});
    const int facade = material(scene, "facade", {0.7f, 0.6f, 0.5f});
    const int bark = material(scene, "bark", {0.3f, 0.2f, 0.12f});
    const int leaves = material(scene, "leaves", {0.15f, 0.35f, 0.1f});
    scene::add_box(scene, "ground", {-60.0f, -0.2f, -60.0f}, {60.0f, 0.0f, 60.0f}, ground);
    for (int i = 0; i < 6; ++i) {
        const float x = -15.0f + 6.0f * i, height = 6.0f + 3.0f * static_cast<float>((i * 7) % 4);
        scene::add_box(scene, "building_left" + std::to_string(i), {x, 0.0f, 4.0f}, {x + 5.0f, height, 10.0f}, facade);
        scene::add_box(scene, "building_right" + std::to_string(i), {x, 0.0f, -10.0f}, {x + 5.0f, height * 0.8f, -4.0f}, facade);
    }
    PrimitiveBuilder trunks(bark), crowns(leaves);
    for (int i = 0; i < 5; ++i) {
        const vec3 foot{-12.0f + 6.0f * i, 0.0f, 2.5f};
        trunks.cylinder(foot, 0.15f, 2.5f, 8 * detail);
        crowns.sphere(foot + vec3(0, 3.2f, 0), 1.1f, 12 * detail);
    }
    add(scene, "trunks", trunks);
    add(scene, "crowns", crowns);
    scene.lights.push_back(sun({0.5f, -0.6f, -0.4f}, 10.0f));
    set_camera(scene, {-18.0f, 1.7f, 0.0f}, {10.0f, 3.0f, 0.0f}, 60.0f);
    return {"outdoor", "an open street of buildings and trees under a low sun", std::move(scene)};
}

// A gallery of glossy and metallic things under spot lights: floor and plinths glossy, spheres of
// gold and copper, a polished steel panel.
BenchScene glossy_gallery(int detail) {
    scene::Scene scene;
    scene.name = "glossy_gallery";
    const int walls = material(scene, "walls", {0.75f, 0.75f, 0.75f});
    const int floor = material(scene, "polished_floor", {0.3f, 0.3f, 0.32f}, 0.12f, 0.0f, 1.0f);
    const int plinth = material(scene, "lacquer", {0.8f, 0.8f, 0.78f}, 0.25f, 0.0f, 1.0f);
    const int gold = material(scene, "gold", {1.0f, 0.78f, 0.34f}, 0.2f, 1.0f, 1.0f);
    const int copper = material(scene, "copper", {0.95f, 0.64f, 0.54f}, 0.4f, 1.0f, 1.0f);
    const int steel = material(scene, "steel", {0.8f, 0.8f, 0.82f}, 0.06f, 1.0f, 1.0f);
    const vec3 room{8.0f, 4.0f, 6.0f};
    add_room(scene, room, 0.2f, walls, floor, {0.0f, 0.0f}, {0.0f, 0.0f});  // no window
    scene::add_box(scene, "steel_panel", {2.0f, 0.5f, 5.9f}, {6.0f, 3.0f, 6.0f}, steel);
    for (int i = 0; i < 3; ++i) {
        const float x = 1.8f + 2.2f * i;
        scene::add_box(scene, "plinth" + std::to_string(i), {x - 0.4f, 0.0f, 3.0f}, {x + 0.4f, 1.0f, 3.8f}, plinth);
        PrimitiveBuilder ball(i == 1 ? copper : gold);
        ball.sphere({x, 1.45f, 3.4f}, 0.45f, 24 * detail);
        add(scene, "sphere" + std::to_string(i), ball);
        scene::Light spot = point_light("spot" + std::to_string(i), {x, 3.8f, 2.2f}, 12.0f);
        spot.type = scene::LightType::spot;
        spot.direction = glm::normalize(vec3(0.0f, -2.3f, 1.2f));
        spot.inner_cone = 0.35f;
        spot.outer_cone = 0.6f;
        scene.lights.push_back(spot);
    }
    set_camera(scene, {4.0f, 2.1f, 0.3f}, {4.0f, 1.2f, 3.4f}, 80.0f);
    return {"glossy_gallery", "glossy floor and plinths, gold and copper spheres, a steel panel, under spot lights",
            std::move(scene)};
}

// A procedural leaf texture: leaves as ellipses on transparent ground (alpha 0 between them).
scene::Texture leaf_texture() {
    scene::Texture texture;
    texture.name = "leaves";
    texture.width = texture.height = 64;
    texture.srgb = true;
    texture.rgba8.resize(64 * 64 * 4);
    for (int y = 0; y < 64; ++y) {
        for (int x = 0; x < 64; ++x) {
            // Four leaves, each an ellipse in its quadrant.
            const float u = (x % 32 - 15.5f) / 14.0f, v = (y % 32 - 15.5f) / 8.0f;
            const bool leaf = u * u + v * v < 1.0f;
            std::uint8_t* p = &texture.rgba8[static_cast<std::size_t>(y * 64 + x) * 4];
            p[0] = 60, p[1] = static_cast<std::uint8_t>(110 + (x * 3 + y) % 40), p[2] = 40, p[3] = leaf ? 255 : 0;
        }
    }
    return texture;
}

// A garden: leaf cards (alpha-masked, double-sided) in clusters on trunks over a lawn, sun through
// them: light and shadow both pass the leaves' holes.
BenchScene foliage(int detail) {
    scene::Scene scene;
    scene.name = "foliage";
    scene.textures.push_back(leaf_texture());
    const int lawn = material(scene, "lawn", {0.2f, 0.4f, 0.12f});
    const int bark = material(scene, "bark", {0.3f, 0.2f, 0.12f});
    const int leaf = sheet_material(scene, "leaf", {1.0f, 1.0f, 1.0f});
    scene::Material& leaf_material = scene.materials[static_cast<std::size_t>(leaf)];
    leaf_material.alpha_mode = scene::AlphaMode::mask;
    leaf_material.alpha_cutoff = 0.5f;
    leaf_material.base_color_texture.texture = 0;
    const int wall = material(scene, "wall", {0.7f, 0.65f, 0.6f});
    scene::add_box(scene, "lawn", {-10.0f, -0.1f, -10.0f}, {10.0f, 0.0f, 10.0f}, lawn);
    scene::add_box(scene, "garden_wall", {-10.0f, 0.0f, 6.0f}, {10.0f, 3.0f, 6.4f}, wall);
    PrimitiveBuilder trunks(bark), cards(leaf);
    const int cards_per_tree = 40 * detail;
    for (int t = 0; t < 3; ++t) {
        const vec3 foot{-4.0f + 4.0f * t, 0.0f, 2.0f + (t % 2)};
        trunks.cylinder(foot, 0.12f, 2.2f, 8);
        for (int c = 0; c < cards_per_tree; ++c) {
            // Cards around the crown, turned by a golden angle each, tilted alternately.
            const float angle = 2.39996f * c, height = 2.0f + 1.6f * c / cards_per_tree;
            const float radius = 0.4f + 0.5f * std::sin(glm::pi<float>() * c / cards_per_tree);
            const vec3 centre = foot + vec3(radius * std::cos(angle), height, radius * std::sin(angle));
            const vec3 across = glm::normalize(vec3(-std::sin(angle), (c % 2) ? 0.4f : -0.3f, std::cos(angle))) * 0.35f;
            const vec3 up(0.0f, 0.35f, 0.0f);
            cards.quad(centre - across - up, centre + across - up, centre + across + up, centre - across + up,
                       glm::cross(across, up), {2.0f, 2.0f});
        }
    }
    add(scene, "trunks", trunks);
    add(scene, "leaf_cards", cards);
    scene.lights.push_back(sun({0.3f, -0.8f, 0.5f}, 8.0f));
    set_camera(scene, {0.0f, 1.6f, -5.0f}, {0.0f, 2.0f, 3.0f}, 60.0f);
    return {"foliage", "alpha-masked leaf cards on three trees before a garden wall, in the sun", std::move(scene)};
}

}  // namespace

std::vector<BenchScene> corpus_scenes(int detail) {
    std::vector<BenchScene> scenes;
    scenes.push_back(furnished_room(detail));
    scenes.push_back(atrium(detail));
    scenes.push_back(outdoor(detail));
    scenes.push_back(glossy_gallery(detail));
    scenes.push_back(foliage(detail));
    return scenes;
}

}  // namespace bounce::bench
