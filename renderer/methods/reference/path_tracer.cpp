#include "renderer/methods/reference/path_tracer.hpp"

#include "renderer/base/error.hpp"
#include "renderer/raytrace/ray_scene.hpp"
#include "renderer/scene/shading.hpp"

#include <glm/gtc/matrix_inverse.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <optional>
#include <cmath>
#include <limits>

namespace bounce::methods::reference {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

// A small counter-based generator: sample s of pixel p draws from (seed, p, s) alone.
class Random {
public:
    Random(std::uint64_t seed, std::uint64_t pixel, std::uint64_t sample)
        : state_(mix(seed ^ mix(pixel * 0x9E3779B97F4A7C15ull ^ mix(sample + 0x632BE59BD9B4E019ull)))) {}
    float next() {
        state_ += 0x9E3779B97F4A7C15ull;
        return static_cast<float>(mix(state_) >> 40) * (1.0f / 16777216.0f);  // [0, 1)
    }

private:
    static std::uint64_t mix(std::uint64_t z) {  // splitmix64 finalizer
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    std::uint64_t state_;
};

using image::luminance;

// Per pixel in Accumulator::feature_sums_: albedo RGB, normal XYZ, depth, hits, luminance^2.
constexpr std::size_t kFeatureFloats = 9;

// A non-finite sample would poison its pixel forever: it is dropped (counted as 0).
bool finite(const glm::vec3& c) { return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b); }

// A frame's camera rays: from the camera through points of its pixels.
struct CameraRays {
    glm::vec3 origin;
    glm::mat4 clip_to_world;
    int width = 0, height = 0;
};

// The variance of a pixel's mean luminance over `samples` samples (the samples' variance over their
// count), from the sums of their RGB and of their luminance squared.
float mean_luminance_variance(const double* rgb_sum, double luminance2_sum, int samples) {
    if (samples <= 1) return 0.0f;
    const double n = samples;
    const double mean = luminance(glm::vec3(rgb_sum[0] / n, rgb_sum[1] / n, rgb_sum[2] / n));
    return static_cast<float>(std::max(luminance2_sum / n - mean * mean, 0.0) / (n - 1.0));
}

// The mean of `samples` samples per pixel from their RGB sums.
image::Frame mean_frame(const double* sums, int width, int height, int samples) {
    image::Frame frame;
    frame.width = width;
    frame.height = height;
    frame.rgba.resize(static_cast<std::size_t>(width) * height * 4);
    const double scale = samples > 0 ? 1.0 / samples : 0.0;
    for (std::size_t i = 0; i < static_cast<std::size_t>(width) * height; ++i) {
        for (int c = 0; c < 3; ++c) frame.rgba[i * 4 + c] = static_cast<float>(sums[i * 3 + c] * scale);
        frame.rgba[i * 4 + 3] = 1.0f;
    }
    return frame;
}

// noise_per_sample (path_tracer.hpp) of a frame of `samples` samples whose pixels' mean luminance
// has the variances `variance`.
double noise_per_sample_of(const image::Frame& frame, const std::vector<float>& variance, int samples) {
    const int width = frame.width, height = frame.height;
    if (variance.empty() || width == 0 || height == 0) return 0.0;
    std::vector<float> lum(static_cast<std::size_t>(width) * height);
    for (std::size_t i = 0; i < lum.size(); ++i) {
        lum[i] = luminance(glm::vec3(frame.rgba[4 * i], frame.rgba[4 * i + 1], frame.rgba[4 * i + 2]));
    }
    // Each pixel's variance over its value squared, as relMSE weighs it; the value is the median of
    // its 3x3 neighbourhood, not its own mean: a pixel that met a rare bright path is bright because
    // of it, and its own mean would hide the very variance it shows.
    double sum = 0.0;
    float window[9];
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            int n = 0;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int sx = std::clamp(x + dx, 0, width - 1), sy = std::clamp(y + dy, 0, height - 1);
                    window[n++] = lum[static_cast<std::size_t>(sy) * width + sx];
                }
            }
            std::nth_element(window, window + 4, window + 9);
            const double value = window[4];
            const std::size_t i = static_cast<std::size_t>(y) * width + x;
            sum += variance[i] * samples / (value * value + 0.01);
        }
    }
    return sum / static_cast<double>(lum.size());
}

struct Emitter {
    std::uint32_t object, primitive, triangle;
    glm::vec3 p0, p1, p2;
    float area;
};

struct SurfaceHit {
    glm::vec3 position;
    glm::vec3 geometric_normal;  // faces the incoming ray
    glm::vec3 shading_normal;    // same side as geometric_normal
    scene::SurfaceMaterial material;
    glm::vec3 emitted{0.0f};  // radiance towards the incoming ray
    bool front = true;
    std::uint32_t object = 0, primitive = 0, triangle = 0;
    float distance = 0.0f;  // ray parameter of the hit (world units: ray directions are unit)
};

}  // namespace

void check_settings(const PathTracerSettings& settings) {
    if (settings.indirect_visibility) return;
    if (settings.ambient_occlusion) {
        throw InputError("reference: indirect_visibility = 0 does not apply to ambient occlusion (ao = 1)");
    }
    if (settings.max_bounces != 1) {
        throw InputError(fmt::format("reference: indirect_visibility = 0 needs bounces = 1 (visibility is dropped on "
                                     "the single indirect segment only), got bounces = {}",
                                     settings.max_bounces));
    }
}

struct PathTracer::Impl {
    const scene::Scene& scene;
    raytrace::RayScene rays;
    std::vector<glm::mat4> normal_matrices;
    std::vector<Emitter> emitters;
    std::vector<float> emitter_cdf;  // by power
    std::vector<std::vector<int>> emitter_base;  // [object][primitive] -> first emitter index or -1
    float scene_radius = 1.0f;
    tbb::task_arena arena;

    explicit Impl(const scene::Scene& s) : scene(s), rays(s) { update_transforms(); }

    void update_transforms() {
        rays.update_transforms();
        normal_matrices.assign(scene.objects.size(), glm::mat4(1.0f));
        for (std::size_t o = 0; o < scene.objects.size(); ++o) {
            normal_matrices[o] = glm::inverseTranspose(scene.objects[o].transform);
        }
        const scene::Aabb bounds = scene.world_bounds();
        scene_radius = bounds.empty() ? 1.0f : std::max(0.5f * glm::length(bounds.extent()), 1e-12f);
        collect_emitters();
    }

    void collect_emitters() {
        emitters.clear();
        emitter_cdf.clear();
        emitter_base.assign(scene.objects.size(), {});
        float total = 0.0f;
        for (std::size_t o = 0; o < scene.objects.size(); ++o) {
            const scene::Object& object = scene.objects[o];
            if (object.mesh < 0) continue;
            const auto& primitives = scene.meshes[object.mesh].primitives;
            emitter_base[o].assign(primitives.size(), -1);
            for (std::size_t p = 0; p < primitives.size(); ++p) {
                const scene::Primitive& primitive = primitives[p];
                const float power = luminance(scene.material(primitive.material).emissive);
                if (!(power > 0.0f)) continue;
                emitter_base[o][p] = static_cast<int>(emitters.size());
                for (std::size_t t = 0; t < primitive.triangle_count(); ++t) {
                    Emitter e{static_cast<std::uint32_t>(o), static_cast<std::uint32_t>(p), static_cast<std::uint32_t>(t),
                              glm::vec3(object.transform * glm::vec4(primitive.positions[primitive.indices[3 * t]], 1.0f)),
                              glm::vec3(object.transform * glm::vec4(primitive.positions[primitive.indices[3 * t + 1]], 1.0f)),
                              glm::vec3(object.transform * glm::vec4(primitive.positions[primitive.indices[3 * t + 2]], 1.0f)),
                              0.0f};
                    e.area = 0.5f * glm::length(glm::cross(e.p1 - e.p0, e.p2 - e.p0));
                    total += power * e.area;
                    emitters.push_back(e);
                    emitter_cdf.push_back(total);
                }
            }
        }
        if (total > 0.0f) {
            for (float& c : emitter_cdf) c /= total;
        }
    }

    // Probability (per unit area) of choosing a point on emitter `index` by light sampling.
    float emitter_area_pdf(int index) const {
        const float previous = index == 0 ? 0.0f : emitter_cdf[index - 1];
        const float selection = emitter_cdf[index] - previous;
        return emitters[index].area > 0.0f ? selection / emitters[index].area : 0.0f;
    }

    float epsilon(const glm::vec3& p) const {
        const float magnitude = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z), scene_radius});
        return 2e-5f * magnitude;
    }

    // The first surface along the ray beyond `tnear`.
    bool intersect(const glm::vec3& origin, const glm::vec3& direction, SurfaceHit& hit, float tnear = 0.0f) const {
        const std::optional<raytrace::RayHit> ray_hit = rays.intersect(origin, direction, tnear, kInfinity);
        if (!ray_hit) return false;
        hit.object = ray_hit->object;
        hit.primitive = ray_hit->primitive;
        hit.triangle = ray_hit->triangle;
        hit.distance = ray_hit->distance;
        const scene::Object& object = scene.objects[hit.object];
        const scene::Primitive& primitive = scene.meshes[object.mesh].primitives[hit.primitive];
        const std::uint32_t i0 = primitive.indices[3 * hit.triangle], i1 = primitive.indices[3 * hit.triangle + 1],
                            i2 = primitive.indices[3 * hit.triangle + 2];
        const float u = ray_hit->u, v = ray_hit->v, w = 1.0f - u - v;
        const glm::vec3 p0(object.transform * glm::vec4(primitive.positions[i0], 1.0f));
        const glm::vec3 p1(object.transform * glm::vec4(primitive.positions[i1], 1.0f));
        const glm::vec3 p2(object.transform * glm::vec4(primitive.positions[i2], 1.0f));
        hit.position = w * p0 + u * p1 + v * p2;
        glm::vec3 ng = glm::cross(p1 - p0, p2 - p0);
        const float ng_length = glm::length(ng);
        ng = ng_length > 0.0f ? ng / ng_length : -direction;
        hit.front = glm::dot(ng, direction) < 0.0f;
        const scene::Material& material = scene.material(primitive.material);
        glm::vec3 ns = glm::vec3(normal_matrices[hit.object] *
                                 glm::vec4(w * primitive.normals[i0] + u * primitive.normals[i1] + v * primitive.normals[i2], 0.0f));
        const float ns_length = glm::length(ns);
        ns = ns_length > 1e-20f && std::isfinite(ns_length) ? ns / ns_length : ng;
        if (!hit.front) {
            ng = -ng;
            ns = -ns;
        }
        if (glm::dot(ns, ng) < 0.0f) ns = ng;  // a shading normal must not point into the surface
        hit.geometric_normal = ng;
        hit.shading_normal = ns;

        auto uv_of = [&](const std::vector<glm::vec2>& uvs) -> glm::vec2 {
            if (uvs.empty()) return glm::vec2(0.0f);
            return w * uvs[i0] + u * uvs[i1] + v * uvs[i2];
        };
        const glm::vec2 uv0 = uv_of(primitive.uv0);
        const glm::vec2 uv1 = primitive.uv1.empty() ? uv0 : uv_of(primitive.uv1);
        const scene::TexturedMaterial textured = scene::textured_material(scene, material, uv0, uv1);
        const scene::SurfaceMaterial& surface = textured.surface;
        const glm::vec3 emitted = textured.emitted;
        hit.material = surface;
        // Single-sided surfaces emit from their front only, as the raster path draws them.
        hit.emitted = hit.front || material.double_sided ? emitted : glm::vec3(0.0f);
        return true;
    }

    bool occluded(const glm::vec3& origin, const glm::vec3& direction, float distance) const {
        return rays.occluded(origin, direction, 0.0f, distance);
    }

    glm::vec3 offset(const SurfaceHit& hit, const glm::vec3& towards) const {
        const float side = glm::dot(towards, hit.geometric_normal) >= 0.0f ? 1.0f : -1.0f;
        return hit.position + hit.geometric_normal * (side * epsilon(hit.position));
    }

    // An emissive triangle's material at barycentrics (a, b) of vertices 1 and 2.
    scene::TexturedMaterial emitter_material(const Emitter& e, const scene::Material& material, float a, float b) const {
        const scene::Primitive& primitive = scene.meshes[scene.objects[e.object].mesh].primitives[e.primitive];
        const std::uint32_t* corner = &primitive.indices[3 * static_cast<std::size_t>(e.triangle)];
        auto uv_of = [&](const std::vector<glm::vec2>& uvs) {
            return uvs.empty() ? glm::vec2(0.0f) : (1.0f - a - b) * uvs[corner[0]] + a * uvs[corner[1]] + b * uvs[corner[2]];
        };
        const glm::vec2 uv0 = uv_of(primitive.uv0);
        return scene::textured_material(scene, material, uv0, primitive.uv1.empty() ? uv0 : uv_of(primitive.uv1));
    }

    // Direct light at a surface from punctual lights and (MIS) emissive triangles.
    glm::vec3 direct_light(const SurfaceHit& hit, const glm::vec3& v, Random& random) const {
        glm::vec3 total(0.0f);
        const glm::vec3& n = hit.shading_normal;
        for (const scene::Light& light : scene.lights) {
            const scene::LightIncidence incidence = scene::light_incidence(light, hit.position);
            const float cos_theta = glm::dot(n, incidence.l);
            if (cos_theta <= 0.0f || !(glm::dot(incidence.irradiance, glm::vec3(1.0f)) > 0.0f)) continue;
            if (glm::dot(hit.geometric_normal, incidence.l) <= 0.0f) continue;
            const glm::vec3 origin = offset(hit, incidence.l);
            const float distance = std::isinf(incidence.distance) ? kInfinity
                                                                  : incidence.distance * (1.0f - 1e-4f);
            if (occluded(origin, incidence.l, distance)) continue;
            total += scene::evaluate_brdf(hit.material, n, v, incidence.l) * incidence.irradiance * cos_theta;
        }
        if (!emitters.empty()) {
            const float pick = random.next();
            const int index = static_cast<int>(std::lower_bound(emitter_cdf.begin(), emitter_cdf.end(), pick) -
                                               emitter_cdf.begin());
            const Emitter& e = emitters[std::min<std::size_t>(static_cast<std::size_t>(index), emitters.size() - 1)];
            float a = random.next(), b = random.next();
            if (a + b > 1.0f) {
                a = 1.0f - a;
                b = 1.0f - b;
            }
            const glm::vec3 point = e.p0 + a * (e.p1 - e.p0) + b * (e.p2 - e.p0);
            glm::vec3 to_light = point - hit.position;
            const float d2 = glm::dot(to_light, to_light);
            if (d2 > 0.0f) {
                const float d = std::sqrt(d2);
                to_light /= d;
                const float cos_theta = glm::dot(n, to_light);
                glm::vec3 emitter_normal = glm::cross(e.p1 - e.p0, e.p2 - e.p0);
                const float normal_length = glm::length(emitter_normal);
                const float cos_light = normal_length > 0.0f ? -glm::dot(emitter_normal / normal_length, to_light) : 0.0f;
                const scene::Material& material =
                    scene.material(scene.meshes[scene.objects[e.object].mesh].primitives[e.primitive].material);
                const float facing = material.double_sided ? std::abs(cos_light) : cos_light;
                if (cos_theta > 0.0f && facing > 0.0f && glm::dot(hit.geometric_normal, to_light) > 0.0f) {
                    const glm::vec3 origin = offset(hit, to_light);
                    if (!occluded(origin, to_light, d * (1.0f - 1e-4f))) {
                        // The emitter's textures and coverage at the sampled point, as a BRDF-sampled
                        // ray finds them (its any-hit keeps a blended point with probability alpha).
                        const scene::TexturedMaterial emitter = emitter_material(e, material, a, b);
                        const float light_pdf = emitter_area_pdf(static_cast<int>(&e - emitters.data())) * d2 / facing;
                        const float brdf_pdf = scene::brdf_pdf(hit.material, n, v, to_light);
                        const float weight = light_pdf * light_pdf / (light_pdf * light_pdf + brdf_pdf * brdf_pdf);
                        total += scene::evaluate_brdf(hit.material, n, v, to_light) * emitter.emitted *
                                 (emitter.coverage * cos_theta * weight / light_pdf);
                    }
                }
            }
        }
        return total;
    }

    // One cosine-distributed visibility sample of A(p) at the surface a camera ray hits.
    float ambient_occlusion(const glm::vec3& origin, const glm::vec3& direction, float lambda, Random& random) const {
        SurfaceHit hit;
        if (!intersect_from_camera(origin, direction, hit)) return 0.0f;
        glm::vec3 t, b;
        const glm::vec3& n = hit.shading_normal;
        scene::orthonormal_basis(n, t, b);
        const float u = random.next(), phi = 2.0f * 3.14159265358979f * random.next();
        const float r = std::sqrt(u);
        const glm::vec3 l = t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * std::sqrt(std::max(0.0f, 1.0f - u));
        if (glm::dot(l, hit.geometric_normal) <= 0.0f) return 1.0f;
        const glm::vec3 from = offset(hit, l);
        SurfaceHit occluder;
        if (!intersect(from, l, occluder)) return 1.0f;
        const float distance = glm::length(occluder.position - from);
        return 1.0f - 1.0f / (1.0f + lambda * distance);
    }

    // The back of a single-sided surface absorbs light (camera rays pass it: intersect_from_camera).
    bool absorbs(const SurfaceHit& hit) const {
        return !hit.front &&
               !scene.material(scene.meshes[scene.objects[hit.object].mesh].primitives[hit.primitive].material).double_sided;
    }

    // MIS weight of emission found at `next` by a BRDF-sampled ray (density `brdf_pdf`, solid
    // angle) from `from`, against sampling that emitter from `from` by light sampling.
    float emission_weight(const SurfaceHit& from, const SurfaceHit& next, const glm::vec3& direction,
                          float brdf_pdf) const {
        const int base = emitter_base[next.object].empty() ? -1 : emitter_base[next.object][next.primitive];
        if (base < 0) return 1.0f;
        const glm::vec3 to = next.position - from.position;
        const float d2 = glm::dot(to, to);
        const float cos_light = std::abs(glm::dot(next.geometric_normal, direction));
        const float light_pdf =
            cos_light > 0.0f ? emitter_area_pdf(base + static_cast<int>(next.triangle)) * d2 / cos_light : 0.0f;
        return brdf_pdf * brdf_pdf / (brdf_pdf * brdf_pdf + light_pdf * light_pdf);
    }

    // What `hit` reflects towards v of direct light alone, as the last vertex of a path estimates
    // it: next-event estimation plus the MIS-weighted emission a BRDF-sampled ray finds.
    glm::vec3 reflected_direct(const SurfaceHit& hit, const glm::vec3& v, Random& random) const {
        if (absorbs(hit)) return glm::vec3(0.0f);
        glm::vec3 total = direct_light(hit, v, random);
        const scene::BrdfSample sample =
            scene::sample_brdf(hit.material, hit.shading_normal, v, random.next(), random.next(), random.next());
        if (!(sample.pdf > 0.0f) || glm::dot(sample.l, hit.geometric_normal) <= 0.0f) return total;
        const float cos_theta = glm::dot(hit.shading_normal, sample.l);
        const glm::vec3 weight =
            scene::evaluate_brdf(hit.material, hit.shading_normal, v, sample.l) * (cos_theta / sample.pdf);
        if (!(luminance(weight) > 0.0f)) return total;
        SurfaceHit next;
        if (!intersect(offset(hit, sample.l), sample.l, next)) return total;
        if (glm::dot(next.emitted, glm::vec3(1.0f)) > 0.0f) {
            total += weight * next.emitted * emission_weight(hit, next, sample.l, sample.pdf);
        }
        return total;
    }

    // indirect_visibility = false (max_bounces 1, checked by check_settings): the indirect ray
    // from the first vertex `x` gathers the reflected direct light of every surface it crosses.
    // Only the first surface's emission counts: emitters behind it are direct light, occluded.
    glm::vec3 gather_without_visibility(const SurfaceHit& x, const glm::vec3& origin, const glm::vec3& direction,
                                        float brdf_pdf, Random& random) const {
        glm::vec3 total(0.0f);
        float tnear = 0.0f;
        for (bool first = true;; first = false) {
            SurfaceHit y;
            if (!intersect(origin, direction, y, tnear)) break;
            if (first && glm::dot(y.emitted, glm::vec3(1.0f)) > 0.0f) {
                total += y.emitted * emission_weight(x, y, direction, brdf_pdf);
            }
            total += reflected_direct(y, -direction, random);
            // Past this surface (and a coincident one, such as the twin of a shared edge).
            tnear = std::max(y.distance * (1.0f + 1e-5f) + epsilon(y.position), std::nextafter(y.distance, kInfinity));
        }
        return total;
    }

    // The first surface a camera ray sees, as the G-buffer draws them: a single-sided surface seen
    // from behind is culled there (glTF's doubleSided false), so the camera ray passes it. Light
    // transport still meets such backs, which absorb.
    bool intersect_from_camera(const glm::vec3& origin, const glm::vec3& direction, SurfaceHit& hit) const {
        float tnear = 0.0f;
        while (intersect(origin, direction, hit, tnear)) {
            if (!absorbs(hit)) return true;
            tnear = std::max(hit.distance * (1.0f + 1e-5f) + epsilon(hit.position), std::nextafter(hit.distance, kInfinity));
        }
        return false;
    }

    // `first`, when given, receives the first hit's albedo, normal, distance and 1 (8 floats added).
    // `prefixes`, when given, receives the path's radiance after each of its first `prefix_count`
    // bounce counts: prefixes[k] is exactly what trace() with max_bounces = k returns for the same
    // random numbers, since the light of bounce k (next-event estimation at vertex k and the emission
    // its BRDF-sampled ray finds) is all added before the path decides to go on.
    // `vertices`, when given, counts the vertices shaded after each bounce count (max_bounces + 1).
    CameraRays camera_rays(const scene::Camera& camera, int width, int height) const {
        const float aspect = static_cast<float>(width) / static_cast<float>(height);
        return {camera.position,
                glm::inverse(camera.projection(aspect, camera.far_plane_for(scene.world_bounds())) * camera.view()), width,
                height};
    }

    // Sample `sample` of pixel (x, y): its random numbers depend on (seed, pixel, sample) alone, so
    // a pixel traced apart (PathTracer::trace_pixels) gets the samples a whole frame gives it.
    glm::vec3 camera_sample(const CameraRays& view, const PathTracerSettings& settings, int x, int y,
                            std::uint64_t sample, float* first = nullptr, glm::vec3* prefixes = nullptr,
                            int prefix_count = 0, std::uint64_t* vertices = nullptr) const {
        const std::uint64_t pixel = static_cast<std::uint64_t>(y) * static_cast<std::uint64_t>(view.width) + x;
        Random random(settings.seed, pixel, sample);
        const float jx = random.next(), jy = random.next();
        const float ox = settings.pixel_jitter ? jx : 0.5f, oy = settings.pixel_jitter ? jy : 0.5f;
        const float ndc_x = (static_cast<float>(x) + ox) / static_cast<float>(view.width) * 2.0f - 1.0f;
        const float ndc_y = 1.0f - (static_cast<float>(y) + oy) / static_cast<float>(view.height) * 2.0f;
        const glm::vec4 far_point = view.clip_to_world * glm::vec4(ndc_x, ndc_y, 1.0f, 1.0f);
        const glm::vec3 direction = glm::normalize(glm::vec3(far_point) / far_point.w - view.origin);
        return settings.ambient_occlusion
                   ? glm::vec3(ambient_occlusion(view.origin, direction, settings.ao_lambda, random))
                   : trace(view.origin, direction, settings.max_bounces, settings.indirect_visibility, random, first,
                           prefixes, prefix_count, vertices);
    }

    glm::vec3 trace(glm::vec3 origin, glm::vec3 direction, int max_bounces, bool indirect_visibility,
                    Random& random, float* first = nullptr, glm::vec3* prefixes = nullptr, int prefix_count = 0,
                    std::uint64_t* vertices = nullptr) const {
        glm::vec3 radiance(0.0f), throughput(1.0f);
        const int prefixes_wanted = prefixes ? prefix_count : 0;
        int prefixes_done = 0;
        // Where the path ends, the bounce counts not yet written have all of its light.
        const auto finish = [&] {
            for (; prefixes_done < prefixes_wanted; ++prefixes_done) prefixes[prefixes_done] = radiance;
            return radiance;
        };
        SurfaceHit hit;
        if (!intersect_from_camera(origin, direction, hit)) return finish();
        if (first) {
            const float values[8] = {hit.material.base_color.r, hit.material.base_color.g, hit.material.base_color.b,
                                     hit.shading_normal.x,      hit.shading_normal.y,      hit.shading_normal.z,
                                     hit.distance,              1.0f};
            for (int i = 0; i < 8; ++i) first[i] += values[i];
        }
        radiance += hit.emitted;
        for (int bounce = 0;; ++bounce) {
            if (absorbs(hit)) break;
            if (vertices) ++vertices[bounce];
            const glm::vec3 v = -direction;
            radiance += throughput * direct_light(hit, v, random);
            // The BRDF-sampled continuation: its emitter hit is weighted against light sampling.
            const scene::BrdfSample sample =
                scene::sample_brdf(hit.material, hit.shading_normal, v, random.next(), random.next(), random.next());
            if (!(sample.pdf > 0.0f) || glm::dot(sample.l, hit.geometric_normal) <= 0.0f) break;
            const float cos_theta = glm::dot(hit.shading_normal, sample.l);
            throughput *= scene::evaluate_brdf(hit.material, hit.shading_normal, v, sample.l) * (cos_theta / sample.pdf);
            if (!(luminance(throughput) > 0.0f)) break;
            origin = offset(hit, sample.l);
            direction = sample.l;
            if (!indirect_visibility) {
                radiance += throughput * gather_without_visibility(hit, origin, direction, sample.pdf, random);
                break;
            }
            SurfaceHit next;
            if (!intersect(origin, direction, next)) break;
            if (glm::dot(next.emitted, glm::vec3(1.0f)) > 0.0f) {
                radiance += throughput * next.emitted * emission_weight(hit, next, direction, sample.pdf);
            }
            if (prefixes_done < prefixes_wanted) prefixes[prefixes_done++] = radiance;  // bounce `bounce` is complete
            if (bounce >= max_bounces) break;
            hit = next;
            if (bounce >= 2) {
                // Russian roulette: continue with the probability of the path's brightness.
                const float keep = std::clamp(std::max({throughput.r, throughput.g, throughput.b}), 0.05f, 1.0f);
                if (random.next() >= keep) break;
                throughput /= keep;
            }
        }
        return finish();
    }
};

Accumulator::Accumulator(int width, int height, int bounce_prefixes)
    : width_(width), height_(height), bounce_prefixes_(bounce_prefixes),
      sums_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3, 0.0),
      feature_sums_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * kFeatureFloats, 0.0f) {
    BOUNCE_CHECK(width > 0 && height > 0, "accumulator size {}x{}", width, height);
    BOUNCE_CHECK(bounce_prefixes >= 0, "accumulator with {} bounce prefixes", bounce_prefixes);
    const std::size_t values = static_cast<std::size_t>(width) * height * bounce_prefixes;
    BOUNCE_CHECK(values <= kMaxPrefixValues, "{}x{} pixels with {} bounce prefixes: over {} pixel-prefixes", width,
                 height, bounce_prefixes, kMaxPrefixValues);
    prefix_sums_.assign(values * 3, 0.0);
    prefix_luminance2_.assign(values, 0.0f);
}

int Accumulator::prefixes_that_fit(int width, int height, int max_bounces) {
    const std::size_t pixels = static_cast<std::size_t>(std::max(width, 1)) * std::max(height, 1);
    return static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(std::max(max_bounces, 0)), kMaxPrefixValues / pixels));
}

PixelFeatures Accumulator::features() const {
    PixelFeatures features;
    features.width = width_;
    features.height = height_;
    const std::size_t pixels = static_cast<std::size_t>(width_) * height_;
    features.albedo.resize(pixels);
    features.normal.resize(pixels);
    features.depth.resize(pixels);
    features.coverage.resize(pixels);
    features.variance.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) {
        const float* sum = &feature_sums_[i * kFeatureFloats];
        const float hits = sum[7];
        const float per_hit = hits > 0.0f ? 1.0f / hits : 0.0f;
        features.albedo[i] = glm::vec3(sum[0], sum[1], sum[2]) * per_hit;
        features.normal[i] = glm::vec3(sum[3], sum[4], sum[5]) * per_hit;
        features.depth[i] = sum[6] * per_hit;
        features.coverage[i] = samples_ > 0 ? hits / static_cast<float>(samples_) : 0.0f;
        features.variance[i] = mean_luminance_variance(&sums_[i * 3], sum[8], samples_);
    }
    return features;
}

image::Frame Accumulator::frame() const { return mean_frame(sums_.data(), width_, height_, samples_); }

std::vector<double> Accumulator::prefix_sums(int bounces) const {
    BOUNCE_CHECK(bounces >= 0 && bounces < bounce_prefixes_, "bounce prefix {} of {}", bounces, bounce_prefixes_);
    const std::size_t pixels = static_cast<std::size_t>(width_) * height_;
    std::vector<double> sums(pixels * 3);
    for (std::size_t i = 0; i < pixels; ++i) {
        const double* from = &prefix_sums_[(i * bounce_prefixes_ + bounces) * 3];
        std::copy(from, from + 3, &sums[i * 3]);
    }
    return sums;
}

image::Frame Accumulator::prefix_frame(int bounces) const {
    return mean_frame(prefix_sums(bounces).data(), width_, height_, samples_);
}

double Accumulator::prefix_noise_per_sample(int bounces) const {
    return prefix_noise_per_sample(bounces, prefix_frame(bounces));
}

double Accumulator::prefix_noise_per_sample(int bounces, const image::Frame& against) const {
    BOUNCE_CHECK(against.width == width_ && against.height == height_, "noise against a {}x{} frame of a {}x{} accumulator",
                 against.width, against.height, width_, height_);
    const std::vector<double> sums = prefix_sums(bounces);
    const std::size_t pixels = static_cast<std::size_t>(width_) * height_;
    std::vector<float> variance(pixels);
    for (std::size_t i = 0; i < pixels; ++i) {
        variance[i] = mean_luminance_variance(&sums[i * 3], prefix_luminance2_[i * bounce_prefixes_ + bounces], samples_);
    }
    return noise_per_sample_of(against, variance, samples_);
}

PathTracer::PathTracer(const scene::Scene& scene) : impl_(std::make_unique<Impl>(scene)) {}
PathTracer::~PathTracer() = default;

void PathTracer::update_transforms() { impl_->update_transforms(); }

std::uint64_t PathTracer::rays_traced() const { return impl_->rays.rays_traced(); }

void PathTracer::render(Accumulator& accumulator, const scene::Camera& camera, int count,
                        const PathTracerSettings& settings, const std::atomic<bool>* cancelled) const {
    BOUNCE_CHECK(count >= 0, "sample count {}", count);
    check_settings(settings);
    const int width = accumulator.width(), height = accumulator.height();
    const CameraRays view = impl_->camera_rays(camera, width, height);
    const int first_sample = accumulator.samples_;
    const int prefix_count = accumulator.bounce_prefixes_;
    BOUNCE_CHECK(prefix_count == 0 || (prefix_count <= settings.max_bounces && settings.indirect_visibility &&
                                       !settings.ambient_occlusion),
                 "{} bounce prefixes of a frame of {} bounces{}", prefix_count, settings.max_bounces,
                 settings.ambient_occlusion ? " of ambient occlusion" : !settings.indirect_visibility ? " without indirect visibility" : "");
    const std::size_t vertex_slots = settings.ambient_occlusion ? 0 : static_cast<std::size_t>(settings.max_bounces) + 1;
    if (accumulator.vertices_shaded_.size() < vertex_slots) accumulator.vertices_shaded_.resize(vertex_slots, 0);
    // Per thread, summed once the rows are done (or left, cancelled).
    tbb::enumerable_thread_specific<std::vector<std::uint64_t>> vertices_per_thread(std::vector<std::uint64_t>(vertex_slots, 0));
    impl_->arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
            std::vector<glm::vec3> prefixes(static_cast<std::size_t>(prefix_count));
            std::vector<glm::dvec3> prefix_batch(static_cast<std::size_t>(prefix_count), glm::dvec3(0.0));
            std::vector<std::uint64_t>& vertices = vertices_per_thread.local();
            for (int y = rows.begin(); y < rows.end(); ++y) {
                for (int x = 0; x < width; ++x) {
                    if (cancelled && cancelled->load(std::memory_order_relaxed)) return;
                    const std::uint64_t pixel = static_cast<std::uint64_t>(y) * width + x;
                    glm::dvec3 sum(0.0);
                    float* first = &accumulator.feature_sums_[pixel * kFeatureFloats];
                    float* prefix_luminance2 = accumulator.prefix_luminance2_.data() + pixel * prefix_count;
                    for (int s = first_sample; s < first_sample + count; ++s) {
                        const glm::vec3 radiance = impl_->camera_sample(view, settings, x, y, static_cast<std::uint64_t>(s),
                                                                        first, prefixes.data(), prefix_count,
                                                                        vertices.data());
                        if (finite(radiance)) {
                            sum += glm::dvec3(radiance);
                            first[8] += luminance(radiance) * luminance(radiance);
                        }
                        // Each prefix summed as its own frame would sum it, in the same order.
                        for (int k = 0; k < prefix_count; ++k) {
                            if (!finite(prefixes[k])) continue;
                            prefix_batch[k] += glm::dvec3(prefixes[k]);
                            prefix_luminance2[k] += luminance(prefixes[k]) * luminance(prefixes[k]);
                        }
                    }
                    for (int k = 0; k < prefix_count; ++k) {
                        double* prefix_sum = &accumulator.prefix_sums_[(pixel * prefix_count + k) * 3];
                        prefix_sum[0] += prefix_batch[k].x;
                        prefix_sum[1] += prefix_batch[k].y;
                        prefix_sum[2] += prefix_batch[k].z;
                        prefix_batch[k] = glm::dvec3(0.0);
                    }
                    double* out = &accumulator.sums_[pixel * 3];
                    out[0] += sum.x;
                    out[1] += sum.y;
                    out[2] += sum.z;
                }
            }
        });
    });
    vertices_per_thread.combine_each([&](const std::vector<std::uint64_t>& counted) {
        for (std::size_t j = 0; j < counted.size(); ++j) accumulator.vertices_shaded_[j] += counted[j];
    });
    if (cancelled && cancelled->load()) throw Cancelled("reference: the trace was cancelled");
    accumulator.samples_ += count;
}

PixelEstimates PathTracer::trace_pixels(const scene::Camera& camera, int width, int height, std::vector<int> pixels,
                                        int spp, const PathTracerSettings& settings,
                                        const std::atomic<bool>* cancelled, int first_sample) const {
    BOUNCE_CHECK(width > 0 && height > 0, "tracing pixels of a {}x{} frame", width, height);
    if (spp < 4) throw InputError(fmt::format("{} samples per pixel: two halves of two samples at least are needed", spp));
    check_settings(settings);
    const int count = width * height;
    for (const int pixel : pixels) {
        BOUNCE_CHECK(pixel >= 0 && pixel < count, "pixel {} is outside a {}x{} frame", pixel, width, height);
    }
    const CameraRays view = impl_->camera_rays(camera, width, height);
    BOUNCE_CHECK(first_sample >= 0, "first sample {}", first_sample);
    PixelEstimates estimates;
    estimates.samples = spp;
    for (int half = 0; half < 2; ++half) {
        // Samples first_sample..first_sample+spp-1 whose number's parity is `half`.
        estimates.half_samples[half] = (first_sample + spp + 1 - half) / 2 - (first_sample + 1 - half) / 2;
    }
    for (int half = 0; half < 2; ++half) {
        estimates.mean[half].assign(pixels.size(), glm::dvec3(0.0));
        estimates.variance[half].assign(pixels.size(), glm::dvec3(0.0));
    }
    impl_->arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pixels.size()), [&](const tbb::blocked_range<std::size_t>& range) {
            for (std::size_t i = range.begin(); i < range.end(); ++i) {
                if (cancelled && cancelled->load(std::memory_order_relaxed)) return;
                const int x = pixels[i] % width, y = pixels[i] / width;
                glm::dvec3 sum[2] = {glm::dvec3(0.0), glm::dvec3(0.0)}, sum2[2] = {glm::dvec3(0.0), glm::dvec3(0.0)};
                for (int s = first_sample; s < first_sample + spp; ++s) {
                    const glm::vec3 radiance = impl_->camera_sample(view, settings, x, y, static_cast<std::uint64_t>(s));
                    if (!finite(radiance)) continue;
                    sum[s % 2] += glm::dvec3(radiance);
                    sum2[s % 2] += glm::dvec3(radiance) * glm::dvec3(radiance);
                }
                for (int half = 0; half < 2; ++half) {
                    const double count = static_cast<double>(estimates.half_samples[half]);
                    if (count < 1.0) continue;
                    const glm::dvec3 mean = sum[half] / count;
                    estimates.mean[half][i] = mean;
                    if (count > 1.0) {
                        const glm::dvec3 sample_variance =
                            glm::max(sum2[half] / count - mean * mean, glm::dvec3(0.0)) * (count / (count - 1.0));
                        estimates.variance[half][i] = sample_variance / count;
                    }
                }
            }
        });
    });
    if (cancelled && cancelled->load()) throw Cancelled("reference: the trace was cancelled");
    estimates.pixels = std::move(pixels);
    return estimates;
}

void merge(PixelEstimates& into, const PixelEstimates& more) {
    BOUNCE_CHECK(into.pixels == more.pixels, "merging estimates of other pixels");
    for (int half = 0; half < 2; ++half) {
        const double a = into.half_samples[half], b = more.half_samples[half], n = a + b;
        if (b == 0.0) continue;
        for (std::size_t i = 0; i < into.pixels.size(); ++i) {
            const glm::dvec3 mean_a = into.mean[half][i], mean_b = more.mean[half][i];
            const glm::dvec3 mean = (a * mean_a + b * mean_b) / n;
            // Sums of squares about each mean (the samples' variance is the mean's times the count),
            // then about the whole's.
            const glm::dvec3 squares = into.variance[half][i] * a * std::max(a - 1.0, 0.0) +
                                       more.variance[half][i] * b * std::max(b - 1.0, 0.0) +
                                       a * (mean_a - mean) * (mean_a - mean) + b * (mean_b - mean) * (mean_b - mean);
            into.mean[half][i] = mean;
            into.variance[half][i] = n > 1.0 ? squares / (n - 1.0) / n : glm::dvec3(0.0);
        }
        into.half_samples[half] += more.half_samples[half];
    }
    into.samples += more.samples;
}

image::Frame PathTracer::render(const scene::Camera& camera, int width, int height, int spp,
                                const PathTracerSettings& settings) const {
    Accumulator accumulator(width, height);
    render(accumulator, camera, spp, settings);
    return accumulator.frame();
}

double noise_per_sample(const Accumulator& accumulator) {
    return noise_per_sample_of(accumulator.frame(), accumulator.features().variance, accumulator.samples());
}

}  // namespace bounce::methods::reference
