#include "gpu_fixture.hpp"

#include "renderer/scene/builtin.hpp"
#include "renderer/scene/gltf_import.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <memory>

namespace bounce::test {

Renderer& shared_renderer() {
    static const std::unique_ptr<Renderer> renderer =
        std::make_unique<Renderer>(gpu::DeviceChoice::resolve(std::nullopt));
    return *renderer;
}

RenderRequest method_request(const std::string& method, const std::string& preset, int size,
                             methods::KnobValues knobs) {
    RenderRequest request;
    request.method = method;
    request.preset = preset;
    request.knobs = std::move(knobs);
    request.width = request.height = size;
    return request;
}

image::Frame pixel_centre_reference(const scene::Scene& scene, int size, int spp,
                                    methods::reference::PathTracerSettings settings) {
    settings.pixel_jitter = false;
    return methods::reference::PathTracer(scene).render(scene.cameras[0], size, size, spp, settings);
}

MeasuredMean mean_over_two_seeds(const std::function<std::vector<double>(std::uint64_t seed)>& sample) {
    const std::vector<double> a = sample(1), b = sample(2);
    if (a.empty() || a.size() != b.size()) return {};
    double sum = 0.0, noise = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        sum += a[i] + b[i];
        noise += (a[i] - b[i]) * (a[i] - b[i]) / 2.0;  // one render's noise variance, per pixel
    }
    const double n = static_cast<double>(a.size());
    // The two-seed mean's variance: one render's summed variance / n^2, halved.
    return {sum / (2.0 * n), std::sqrt(noise / 2.0) / n};
}

double largest_relative_difference(const image::Frame& test, const image::Frame& expected) {
    double largest = 0.0;
    for (std::size_t i = 0; i < expected.rgba.size(); ++i) {
        if (i % 4 == 3 || expected.rgba[i] <= 0.0f) continue;
        largest = std::max(largest, std::abs(static_cast<double>(test.rgba[i]) / expected.rgba[i] - 1.0));
    }
    return largest;
}

RenderResult render_scene(const scene::Scene& scene, const RenderRequest& request) {
    auto resources = shared_renderer().upload(scene);
    return shared_renderer().render(*resources, request);
}

scene::Material matte(const glm::vec3& albedo) {
    scene::Material material;
    material.name = "matte";
    material.base_color = glm::vec4(albedo, 1.0f);
    material.metallic = 0.0f;
    material.roughness = 1.0f;
    material.specular = 0.0f;
    return material;
}

scene::Light directional_light(const glm::vec3& direction, float irradiance) {
    scene::Light light;
    light.name = "sun";
    light.type = scene::LightType::directional;
    light.direction = direction;
    light.intensity = irradiance;
    return light;
}

scene::Scene sunlit_engine() {
    scene::Scene file =
        scene::import_gltf_file("/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
    file.lights.push_back(directional_light(glm::normalize(glm::vec3(-0.3f, -1.0f, -0.5f)), 3.0f));
    if (file.cameras.empty()) file.cameras.push_back(scene::framing_camera(file.world_bounds()));
    return file;
}

void add_square(scene::Scene& scene, const std::string& name, const glm::vec3& centre, float half_size,
                const glm::vec3& normal, int material) {
    const glm::vec3 n = glm::normalize(normal);
    const glm::vec3 helper = std::abs(n.y) > 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    const glm::vec3 u = glm::normalize(glm::cross(helper, n)) * half_size;
    const glm::vec3 v = glm::cross(n, u);  // u x v = n |u|^2: counter-clockwise seen from the front
    scene::Primitive primitive;
    primitive.material = material;
    primitive.positions = {-u - v, u - v, u + v, -u + v};
    primitive.normals.assign(4, n);
    primitive.tangents.assign(4, glm::vec4(glm::normalize(u), 1.0f));
    primitive.uv0 = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    primitive.indices = {0, 1, 2, 0, 2, 3};
    for (const auto& p : primitive.positions) primitive.bounds.extend(p);
    scene::add_primitive_object(scene, name, std::move(primitive), glm::translate(glm::mat4(1.0f), centre));
}

scene::Camera top_down_camera(float height, float vertical_fov) {
    return scene::Camera::look_at({0.0f, height, 0.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, -1.0f}, vertical_fov);
}

glm::vec3 pixel_on_ground(const scene::Camera& camera, int width, int height, int x, int y) {
    const float aspect = static_cast<float>(width) / static_cast<float>(height);
    const glm::mat4 inverse = glm::inverse(camera.projection(aspect, 100.0f) * camera.view());
    const float ndc_x = (static_cast<float>(x) + 0.5f) / static_cast<float>(width) * 2.0f - 1.0f;
    const float ndc_y = 1.0f - (static_cast<float>(y) + 0.5f) / static_cast<float>(height) * 2.0f;
    glm::vec4 far_point = inverse * glm::vec4(ndc_x, ndc_y, 1.0f, 1.0f);
    const glm::vec3 direction = glm::normalize(glm::vec3(far_point) / far_point.w - camera.position);
    const float t = -camera.position.y / direction.y;
    return camera.position + t * direction;
}

glm::ivec2 project_to_pixel(const scene::Camera& camera, int width, int height, const glm::vec3& world) {
    const float aspect = static_cast<float>(width) / static_cast<float>(height);
    const glm::vec4 clip = camera.projection(aspect, 100.0f) * camera.view() * glm::vec4(world, 1.0f);
    const glm::vec2 ndc = glm::vec2(clip) / clip.w;
    return {static_cast<int>((ndc.x * 0.5f + 0.5f) * static_cast<float>(width)),
            static_cast<int>((0.5f - ndc.y * 0.5f) * static_cast<float>(height))};
}

scene::Scene with_transforms_baked(const scene::Scene& source) {
    scene::Scene baked;
    baked.textures = source.textures;
    baked.materials = source.materials;
    baked.lights = source.lights;
    baked.cameras = source.cameras;
    for (const scene::Object& object : source.objects) {
        if (object.mesh < 0) continue;
        const glm::mat3 normal_matrix = glm::transpose(glm::inverse(glm::mat3(object.transform)));
        int part = 0;
        for (scene::Primitive primitive : source.meshes[static_cast<std::size_t>(object.mesh)].primitives) {
            primitive.bounds = scene::Aabb{};
            for (glm::vec3& position : primitive.positions) {
                position = glm::vec3(object.transform * glm::vec4(position, 1.0f));
                primitive.bounds.extend(position);
            }
            for (glm::vec3& normal : primitive.normals) normal = glm::normalize(normal_matrix * normal);
            for (glm::vec4& tangent : primitive.tangents) {
                tangent = glm::vec4(glm::normalize(glm::mat3(object.transform) * glm::vec3(tangent)), tangent.w);
            }
            scene::add_primitive_object(baked, object.name + "#" + std::to_string(part++), std::move(primitive));
        }
    }
    return baked;
}

}  // namespace bounce::test
