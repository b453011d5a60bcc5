#include "renderer/raytrace/ray_scene.hpp"

#include "renderer/base/error.hpp"
#include "renderer/scene/shading.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <tbb/enumerable_thread_specific.h>

#include <atomic>
#include <cstring>
#include <memory>
#include <limits>
#include <vector>

namespace bounce::raytrace {
namespace {

// The any-hit half of glTF's alphaMode for one primitive, at the hit's base-colour alpha (factor
// times texture, at its UV). MASK: a hit below the cutoff is not a hit. BLEND: a hit is kept with
// probability alpha (coverage), decided by a hash of the ray and the hit, so that a ray tested
// twice against one primitive decides alike and two surfaces along one ray decide independently.
struct AlphaTest {
    const scene::Scene* scene;
    const scene::Primitive* primitive;
    const scene::Material* material;

    float alpha(unsigned triangle, float u, float v) const {
        float alpha = material->base_color.a;
        const scene::TextureRef& ref = material->base_color_texture;
        const std::vector<glm::vec2>& uvs = ref.uv_set == 1 ? primitive->uv1 : primitive->uv0;
        if (ref.valid() && ref.texture < static_cast<int>(scene->textures.size()) && !uvs.empty()) {
            const std::uint32_t* corner = &primitive->indices[3 * static_cast<std::size_t>(triangle)];
            const glm::vec2 uv = (1.0f - u - v) * uvs[corner[0]] + u * uvs[corner[1]] + v * uvs[corner[2]];
            alpha *= scene::sample_texture(scene->textures[static_cast<std::size_t>(ref.texture)], ref.transform(uv)).a;
        }
        return alpha;
    }
};

std::uint64_t mix_bits(std::uint64_t h, float value) {
    std::uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    h ^= bits + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
    // splitmix64's finalizer
    h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ULL;
    h = (h ^ (h >> 27)) * 0x94d049bb133111ebULL;
    return h ^ (h >> 31);
}

// A uniform number in [0, 1) for one ray meeting one point of a primitive.
float coverage_sample(const RTCFilterFunctionNArguments* args, unsigned i) {
    std::uint64_t h = (static_cast<std::uint64_t>(RTCHitN_instID(args->hit, args->N, i, 0)) << 48) ^
                      (static_cast<std::uint64_t>(RTCHitN_geomID(args->hit, args->N, i)) << 32) ^
                      RTCHitN_primID(args->hit, args->N, i);
    for (float value : {RTCRayN_org_x(args->ray, args->N, i), RTCRayN_org_y(args->ray, args->N, i),
                        RTCRayN_org_z(args->ray, args->N, i), RTCRayN_dir_x(args->ray, args->N, i),
                        RTCRayN_dir_y(args->ray, args->N, i), RTCRayN_dir_z(args->ray, args->N, i),
                        RTCHitN_u(args->hit, args->N, i), RTCHitN_v(args->hit, args->N, i)})
        h = mix_bits(h, value);
    return static_cast<float>(h >> 40) * (1.0f / 16777216.0f);
}

void alpha_filter(const RTCFilterFunctionNArguments* args) {
    const auto* test = static_cast<const AlphaTest*>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] == 0) continue;
        const float alpha = test->alpha(RTCHitN_primID(args->hit, args->N, i), RTCHitN_u(args->hit, args->N, i),
                                        RTCHitN_v(args->hit, args->N, i));
        const bool there = test->material->alpha_mode == scene::AlphaMode::blend
                               ? coverage_sample(args, i) < test->material->coverage(alpha)
                               : test->material->coverage(alpha) > 0.0f;
        if (!there) args->valid[i] = 0;  // the ray goes on
    }
}

}  // namespace

struct RayScene::Impl {
    const scene::Scene& scene;
    RTCDevice device = nullptr;
    std::vector<RTCScene> mesh_scenes;  // per mesh; null for meshes no held object uses
    std::vector<RTCGeometry> instances;  // per object; null for objects not held
    std::vector<std::unique_ptr<AlphaTest>> alpha_tests;  // one per masked or blended primitive
    RTCScene top = nullptr;
    // Rays counted per thread: one shared atomic, bumped by every ray of every thread, bounced its
    // cache line between cores and cost a third of the path tracer's time.
    mutable tbb::enumerable_thread_specific<std::uint64_t, tbb::cache_aligned_allocator<std::uint64_t>,
                                            tbb::ets_key_per_instance>
        rays{std::uint64_t{0}};

    Impl(const scene::Scene& s, const std::function<bool(std::size_t)>& include) : scene(s) {
        device = rtcNewDevice(nullptr);
        if (!device) BOUNCE_FAIL("Embree: rtcNewDevice failed (error {})", static_cast<int>(rtcGetDeviceError(nullptr)));
        std::vector<bool> held(scene.objects.size(), false), mesh_used(scene.meshes.size(), false);
        for (std::size_t o = 0; o < scene.objects.size(); ++o) {
            held[o] = scene.objects[o].mesh >= 0 && (!include || include(o));
            if (held[o]) mesh_used[scene.objects[o].mesh] = true;
        }
        mesh_scenes.assign(scene.meshes.size(), nullptr);
        for (std::size_t m = 0; m < scene.meshes.size(); ++m) {
            if (!mesh_used[m]) continue;
            RTCScene mesh_scene = rtcNewScene(device);
            const scene::Mesh& mesh = scene.meshes[m];
            for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
                const scene::Primitive& primitive = mesh.primitives[p];
                if (primitive.triangle_count() == 0) continue;
                RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
                auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
                    geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), primitive.positions.size()));
                for (std::size_t v = 0; v < primitive.positions.size(); ++v) {
                    vertices[3 * v] = primitive.positions[v].x;
                    vertices[3 * v + 1] = primitive.positions[v].y;
                    vertices[3 * v + 2] = primitive.positions[v].z;
                }
                auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
                    geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), primitive.triangle_count()));
                std::copy(primitive.indices.begin(), primitive.indices.end(), indices);
                const scene::Material& material = scene.material(primitive.material);
                if (material.alpha_mode != scene::AlphaMode::opaque) {
                    alpha_tests.push_back(std::make_unique<AlphaTest>(AlphaTest{&scene, &primitive, &material}));
                    rtcSetGeometryUserData(geometry, alpha_tests.back().get());
                    rtcSetGeometryIntersectFilterFunction(geometry, alpha_filter);
                    rtcSetGeometryOccludedFilterFunction(geometry, alpha_filter);
                }
                rtcCommitGeometry(geometry);
                rtcAttachGeometryByID(mesh_scene, geometry, static_cast<unsigned>(p));
                rtcReleaseGeometry(geometry);
            }
            rtcCommitScene(mesh_scene);
            mesh_scenes[m] = mesh_scene;
        }
        top = rtcNewScene(device);
        instances.assign(scene.objects.size(), nullptr);
        for (std::size_t o = 0; o < scene.objects.size(); ++o) {
            if (!held[o]) continue;
            RTCGeometry instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(instance, mesh_scenes[scene.objects[o].mesh]);
            rtcAttachGeometryByID(top, instance, static_cast<unsigned>(o));
            instances[o] = instance;
        }
        update_transforms();
    }

    ~Impl() {
        for (RTCGeometry instance : instances)
            if (instance) rtcReleaseGeometry(instance);
        if (top) rtcReleaseScene(top);
        for (RTCScene mesh_scene : mesh_scenes)
            if (mesh_scene) rtcReleaseScene(mesh_scene);
        if (device) rtcReleaseDevice(device);
    }

    void update_transforms() {
        for (std::size_t o = 0; o < scene.objects.size(); ++o) {
            if (!instances[o]) continue;
            const glm::mat4& transform = scene.objects[o].transform;
            rtcSetGeometryTransform(instances[o], 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR, &transform[0][0]);
            rtcCommitGeometry(instances[o]);
        }
        rtcCommitScene(top);
    }
};

RayScene::RayScene(const scene::Scene& scene, const std::function<bool(std::size_t)>& include)
    : impl_(std::make_unique<Impl>(scene, include)) {}
RayScene::~RayScene() = default;

void RayScene::update_transforms() { impl_->update_transforms(); }

std::optional<RayHit> RayScene::intersect(const glm::vec3& origin, const glm::vec3& direction, float tnear,
                                          float tfar) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit ray_hit{};
    ray_hit.ray.org_x = origin.x;
    ray_hit.ray.org_y = origin.y;
    ray_hit.ray.org_z = origin.z;
    ray_hit.ray.dir_x = direction.x;
    ray_hit.ray.dir_y = direction.y;
    ray_hit.ray.dir_z = direction.z;
    ray_hit.ray.tnear = tnear;
    ray_hit.ray.tfar = tfar;
    ray_hit.ray.mask = 0xFFFFFFFFu;
    ray_hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    ray_hit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(impl_->top, &context, &ray_hit);
    ++impl_->rays.local();
    if (ray_hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    return RayHit{ray_hit.hit.instID[0], ray_hit.hit.geomID, ray_hit.hit.primID, ray_hit.ray.tfar, ray_hit.hit.u,
                  ray_hit.hit.v};
}

bool RayScene::occluded(const glm::vec3& origin, const glm::vec3& direction, float tnear, float tfar) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray{};
    ray.org_x = origin.x;
    ray.org_y = origin.y;
    ray.org_z = origin.z;
    ray.dir_x = direction.x;
    ray.dir_y = direction.y;
    ray.dir_z = direction.z;
    ray.tnear = tnear;
    ray.tfar = tfar;
    ray.mask = 0xFFFFFFFFu;
    rtcOccluded1(impl_->top, &context, &ray);
    ++impl_->rays.local();
    return ray.tfar == -std::numeric_limits<float>::infinity();
}

std::uint64_t RayScene::rays_traced() const {
    return impl_->rays.combine([](std::uint64_t a, std::uint64_t b) { return a + b; });
}

}  // namespace bounce::raytrace
