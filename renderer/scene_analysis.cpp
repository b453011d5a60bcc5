#include "renderer/scene_analysis.hpp"

#include "renderer/base/error.hpp"
#include "renderer/image/metrics.hpp"
#include "renderer/methods/registry.hpp"
#include "renderer/raytrace/ray_scene.hpp"
#include "renderer/scene/mesh_utils.hpp"
#include "renderer/methods/reference/path_tracer.hpp"

#include <glm/gtc/constants.hpp>
#include <glm/gtx/component_wise.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <optional>
#include <random>

namespace bounce {
namespace {

using Random = std::mt19937;

double uniform(Random& random) { return std::uniform_real_distribution<double>(0.0, 1.0)(random); }

void check_cancelled(const std::atomic<bool>* cancelled) {
    if (cancelled && cancelled->load()) throw Cancelled("the scene analysis was cancelled");
}

// One triangle of the scene in world space.
struct WorldTriangle {
    glm::vec3 a, b, c;
    glm::vec3 normal() const { return glm::normalize(glm::cross(b - a, c - a)); }
};

WorldTriangle world_triangle(const scene::Scene& scene, std::uint32_t object, std::uint32_t primitive,
                             std::uint32_t triangle) {
    const scene::Object& o = scene.objects[object];
    const scene::Primitive& p = scene.meshes[static_cast<std::size_t>(o.mesh)].primitives[primitive];
    const std::uint32_t* corner = &p.indices[3 * static_cast<std::size_t>(triangle)];
    const auto at = [&](std::uint32_t i) { return glm::vec3(o.transform * glm::vec4(p.positions[corner[i]], 1.0f)); };
    return {at(0), at(1), at(2)};
}

struct SurfacePoint {
    glm::vec3 position, normal;
};

// Points spread over the scene's surfaces by area (triangles chosen with probability
// proportional to their area, points uniform within them).
class SurfaceSampler {
public:
    explicit SurfaceSampler(const scene::Scene& scene) : scene_(scene), triangles_(scene) {}
    bool empty() const { return triangles_.empty(); }

    SurfacePoint sample(Random& random) const {
        const scene::AreaWeightedTriangles::Triangle& picked = triangles_.pick(uniform(random));
        const WorldTriangle t = world_triangle(scene_, picked.object, picked.primitive, picked.triangle);
        double u = uniform(random), v = uniform(random);
        if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
        const glm::vec3 position = t.a + static_cast<float>(u) * (t.b - t.a) + static_cast<float>(v) * (t.c - t.a);
        return {position, t.normal()};
    }

private:
    const scene::Scene& scene_;
    scene::AreaWeightedTriangles triangles_;
};

struct Hit {
    glm::vec3 position, normal;
    float distance;
};

std::optional<Hit> trace(const scene::Scene& scene, const raytrace::RayScene& rays, const glm::vec3& origin,
                         const glm::vec3& direction, float tnear, float tfar) {
    const auto hit = rays.intersect(origin, direction, tnear, tfar);
    if (!hit) return std::nullopt;
    return Hit{origin + hit->distance * direction, world_triangle(scene, hit->object, hit->primitive, hit->triangle).normal(),
               hit->distance};
}

// -- Bounce energies ---------------------------------------------------------------------------

double mean_radiance(const image::Frame& frame) {
    double sum = 0.0;
    for (std::size_t i = 0; i < frame.rgba.size(); i += 4) sum += frame.rgba[i] + frame.rgba[i + 1] + frame.rgba[i + 2];
    return sum / (3.0 * static_cast<double>(frame.width) * frame.height);
}

BounceEnergy bounce_energy(const scene::Scene& scene, const AnalysisSettings& settings, const std::atomic<bool>* cancelled) {
    // One tracer (one acceleration structure) for every bounce count.
    const auto build_start = std::chrono::steady_clock::now();
    const methods::reference::PathTracer tracer(scene);
    const double tracer_build_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - build_start).count();
    const scene::Camera camera = scene.cameras.empty() ? scene::framing_camera(scene.world_bounds()) : scene.cameras.front();
    BounceEnergy energy;
    energy.tracer_build_ms = tracer_build_ms;
    std::vector<double> totals;  // the image's mean with 0, 1, ... bounces
    std::vector<image::Frame> frames;
    const int pixels = settings.bounce_image_size * settings.bounce_image_size;
    {
        // Untimed: the first render starts the worker threads, which is no sample's cost.
        methods::reference::Accumulator warm_up(4, 4);
        tracer.render(warm_up, camera, 1, {}, cancelled);
    }
    methods::reference::PathTracerSettings trace;
    trace.seed = settings.seed;
    trace.pixel_jitter = false;
    // Timed: a sample's cost with no bounces (its camera ray and one vertex), apart.
    const auto timed_render = [&](methods::reference::Accumulator& accumulator, int spp) {
        const auto start = std::chrono::steady_clock::now();
        tracer.render(accumulator, camera, spp, trace, cancelled);
        return std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count() /
               (static_cast<double>(pixels) * spp);
    };
    trace.max_bounces = 0;
    methods::reference::Accumulator direct(settings.bounce_image_size, settings.bounce_image_size);
    const double direct_ns = timed_render(direct, settings.direct_timing_spp);
    // Every bounce count from one trace: its bounce prefixes are, bit for bit, the frames of the same
    // seed at fewer bounces (common random numbers: the differences between counts are not noise).
    trace.max_bounces = settings.max_bounces;
    methods::reference::Accumulator all(settings.bounce_image_size, settings.bounce_image_size, settings.max_bounces);
    const double all_ns = timed_render(all, settings.bounce_spp);
    const image::Frame whole_frame = all.frame();
    for (int bounces = 0; bounces <= settings.max_bounces; ++bounces) {
        const bool prefix = bounces < settings.max_bounces;
        energy.noise_per_sample.push_back(prefix ? all.prefix_noise_per_sample(bounces)
                                                 : methods::reference::noise_per_sample(all));
        energy.noise_against_whole.push_back(prefix ? all.prefix_noise_per_sample(bounces, whole_frame)
                                                    : energy.noise_per_sample.back());
        frames.push_back(prefix ? all.prefix_frame(bounces) : whole_frame);
        totals.push_back(mean_radiance(frames.back()));
    }
    // A sample's time with k bounces: its camera ray, and the vertices its path shades after 0..k
    // bounces, each alike. The two timed frames give the two costs; the trace counted the vertices.
    const std::vector<std::uint64_t>& vertices = all.vertices_shaded();
    const double samples = static_cast<double>(pixels) * settings.bounce_spp;
    std::vector<double> vertices_by(vertices.size());  // per sample, with 0..k bounces
    for (std::size_t k = 0; k < vertices.size(); ++k) {
        vertices_by[k] = (k == 0 ? 0.0 : vertices_by[k - 1]) + static_cast<double>(vertices[k]) / samples;
    }
    const double later_vertices = vertices_by.back() - vertices_by.front();
    const double vertex_ns = later_vertices > 0.0 ? std::max(0.0, all_ns - direct_ns) / later_vertices : 0.0;
    for (std::size_t k = 0; k < vertices_by.size(); ++k) {
        energy.sample_ns.push_back(direct_ns + vertex_ns * (vertices_by[k] - vertices_by.front()));
    }
    for (const image::Frame& frame : frames) energy.stopped_error.push_back(image::compare(frame, frames.back()).rel_mse);
    std::vector<double> added(totals.size());
    for (std::size_t k = 0; k < totals.size(); ++k) added[k] = std::max(0.0, k == 0 ? totals[0] : totals[k] - totals[k - 1]);
    // Beyond the last bounce traced the bounces fall geometrically. The ratio and the last term come
    // from a geometric fit to the last four bounces, not from the last two alone: late bounces
    // carry little light and their differences are noisy.
    double tail = 0.0;
    constexpr std::size_t kWindow = 4;
    if (added.size() >= kWindow + 2) {
        const auto window_sum = [&](std::size_t end) {
            return std::accumulate(added.end() - static_cast<std::ptrdiff_t>(end + kWindow),
                                   added.end() - static_cast<std::ptrdiff_t>(end), 0.0);
        };
        const double later = window_sum(0), earlier = window_sum(1);
        if (earlier > 0.0 && later > 0.0) {
            const double ratio = std::min(later / earlier, 0.95);
            // s, s r, s r^2, s r^3 sum to `later`: the last of them is s r^3.
            const double last = later * (1.0 - ratio) / (1.0 - std::pow(ratio, kWindow)) * std::pow(ratio, kWindow - 1);
            tail = last * ratio / (1.0 - ratio);
        }
    }
    const double whole = std::accumulate(added.begin(), added.end(), 0.0) + tail;
    for (double part : added) energy.share.push_back(whole > 0.0 ? part / whole : 0.0);
    energy.tail = whole > 0.0 ? tail / whole : 0.0;
    return energy;
}

// -- Thin walls ---------------------------------------------------------------------------------

// Behind a surface point (against its normal): how thick the wall it belongs to is, and how wide the
// space past it is. A sheet (one face, nothing behind it before another surface facing it) is 0
// thick; a solid is as thick as the distance to where the ray leaves it. A point with nothing
// behind it bounds the scene and separates nothing.
struct Separation {
    float thickness, space_beyond;
};

// Whether `point` lies inside a solid (an object's closed or open-bottomed shell): rays along the
// six axes meet the backs of faces more often than their fronts.
bool inside_solid(const scene::Scene& scene, const raytrace::RayScene& rays, const glm::vec3& point, float reach) {
    int backs = 0, fronts = 0;
    for (int axis = 0; axis < 3; ++axis) {
        for (const float sign : {-1.0f, 1.0f}) {
            glm::vec3 direction(0.0f);
            direction[axis] = sign;
            const auto hit = trace(scene, rays, point, direction, 0.0f, reach);
            if (!hit) continue;
            ++(glm::dot(hit->normal, direction) > 0.0f ? backs : fronts);
        }
    }
    return backs > fronts;
}

std::optional<Separation> separation_behind(const scene::Scene& scene, const raytrace::RayScene& rays,
                                            const SurfacePoint& point, float epsilon, float reach) {
    const glm::vec3 back = -point.normal;
    const auto first = trace(scene, rays, point.position, back, epsilon, reach);
    if (!first) return std::nullopt;
    Separation separation{0.0f, first->distance};  // a sheet, and the space behind it
    glm::vec3 far_side = point.position;
    if (glm::dot(first->normal, back) > 0.0f) {
        // Leaving a solid: what lies past its far face?
        const auto beyond = trace(scene, rays, first->position, back, epsilon, reach);
        if (!beyond) return std::nullopt;
        separation = {first->distance, beyond->distance};
        far_side = first->position;
    }
    // The space past the wall must be a space, not the inside of another shell (the hollow of a block
    // whose top is a sheet over the floor).
    if (inside_solid(scene, rays, far_side + 0.5f * separation.space_beyond * back, reach)) return std::nullopt;
    return separation;
}

// Whether any light reaches `point` directly, on the side its normal faces.
bool directly_lit(const scene::Scene& scene, const raytrace::RayScene& rays, const SurfacePoint& point, float epsilon,
                  float reach) {
    for (const scene::Light& light : scene.lights) {
        if (!(glm::compMax(light.radiant()) > 0.0f)) continue;
        glm::vec3 to_light;
        float distance = reach;
        if (light.type == scene::LightType::directional) {
            to_light = -light.direction;
        } else {
            const glm::vec3 offset = light.position - point.position;
            distance = glm::length(offset);
            if (!(distance > epsilon)) continue;
            to_light = offset / distance;
            if (light.type == scene::LightType::spot && glm::dot(-to_light, light.direction) < std::cos(light.outer_cone)) {
                continue;
            }
        }
        if (glm::dot(to_light, point.normal) <= 0.0f) continue;
        if (!rays.occluded(point.position, to_light, epsilon, distance - epsilon)) return true;
    }
    return false;
}

ThinWalls thin_walls(const scene::Scene& scene, const raytrace::RayScene& rays, const SurfaceSampler& surfaces,
                     const AnalysisSettings& settings, const std::atomic<bool>* cancelled) {
    const scene::Aabb bounds = scene.world_bounds();
    const float extent = glm::compMax(bounds.extent());
    ThinWalls walls;
    const methods::MethodInfo& vct = methods::MethodRegistry::builtin().find("vct");
    for (const auto& [name, knobs] : vct.presets) walls.presets[name].voxel_size = vct.voxel_size(knobs, extent);
    if (surfaces.empty() || !(extent > 0.0f)) return walls;

    const float epsilon = 1e-5f * extent;  // past the surface the ray starts on
    Random random(settings.seed);
    std::map<std::string, int> leaking;
    for (int i = 0; i < settings.surface_samples; ++i) {
        if (i % 256 == 0) check_cancelled(cancelled);
        // Light leaks from a lit face through its wall into the space behind it.
        const SurfacePoint point = surfaces.sample(random);
        if (!directly_lit(scene, rays, point, epsilon, 4.0f * extent)) continue;
        const auto separation = separation_behind(scene, rays, point, epsilon, 2.0f * extent);
        if (!separation) continue;
        for (const auto& [name, preset] : walls.presets) {
            const auto voxel = static_cast<float>(preset.voxel_size);
            if (separation->thickness < voxel && separation->space_beyond > voxel) ++leaking[name];
        }
        // The thinnest wall between spaces wider than the finest voxel any preset uses.
        const double finest = std::min_element(walls.presets.begin(), walls.presets.end(), [](const auto& a, const auto& b) {
                                  return a.second.voxel_size < b.second.voxel_size;
                              })->second.voxel_size;
        if (separation->space_beyond > finest &&
            (walls.thinnest_separator < 0.0 || separation->thickness < walls.thinnest_separator)) {
            walls.thinnest_separator = separation->thickness;
        }
    }
    for (auto& [name, preset] : walls.presets) preset.leaking_area = static_cast<double>(leaking[name]) / settings.surface_samples;
    return walls;
}

// -- Indirect visibility -----------------------------------------------------------------------

// Where a light puts its first bounce: surface points hit by rays leaving the lights, each light's
// share of rays proportional to its power (a directional light's over the scene's cross-section).
std::vector<SurfacePoint> light_hits(const scene::Scene& scene, const raytrace::RayScene& rays, int count, Random& random) {
    const scene::Aabb bounds = scene.world_bounds();
    const float extent = glm::compMax(bounds.extent());
    const float radius = 0.5f * glm::length(bounds.extent());
    std::vector<double> power;
    for (const scene::Light& light : scene.lights) {
        const glm::vec3 radiant = light.radiant();
        const double strength = (radiant.r + radiant.g + radiant.b) / 3.0;
        power.push_back(light.type == scene::LightType::directional ? strength * glm::pi<double>() * radius * radius
                                                                    : strength * 4.0 * glm::pi<double>());
    }
    const double total = std::accumulate(power.begin(), power.end(), 0.0);
    std::vector<SurfacePoint> hits;
    if (!(total > 0.0) || !(extent > 0.0f)) return hits;
    std::discrete_distribution<std::size_t> pick(power.begin(), power.end());
    for (int attempt = 0; attempt < 4 * count && static_cast<int>(hits.size()) < count; ++attempt) {
        const scene::Light& light = scene.lights[pick(random)];
        glm::vec3 origin, direction;
        // A uniform direction on the sphere (spot lights keep those inside their outer cone).
        const double z = 1.0 - 2.0 * uniform(random), phi = 2.0 * glm::pi<double>() * uniform(random);
        const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
        const glm::vec3 sphere(static_cast<float>(r * std::cos(phi)), static_cast<float>(r * std::sin(phi)), static_cast<float>(z));
        if (light.type == scene::LightType::directional) {
            // From a disc across the bounds, upstream of them, along the light.
            direction = light.direction;
            const glm::vec3 helper = std::abs(direction.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
            const glm::vec3 u = glm::normalize(glm::cross(direction, helper)), v = glm::cross(direction, u);
            const double rr = radius * std::sqrt(uniform(random)), angle = 2.0 * glm::pi<double>() * uniform(random);
            origin = bounds.center() - 2.0f * radius * direction + static_cast<float>(rr * std::cos(angle)) * u +
                     static_cast<float>(rr * std::sin(angle)) * v;
        } else {
            origin = light.position;
            direction = sphere;
            if (light.type == scene::LightType::spot && glm::dot(direction, light.direction) < std::cos(light.outer_cone)) continue;
        }
        const auto hit = trace(scene, rays, origin, direction, 0.0f, 4.0f * radius + extent);
        if (!hit) continue;
        // The side the light arrives on.
        hits.push_back({hit->position, glm::dot(hit->normal, direction) < 0.0f ? hit->normal : -hit->normal});
    }
    return hits;
}

// Where the camera looks: first hits of rays through a grid over the default view.
std::vector<SurfacePoint> camera_hits(const scene::Scene& scene, const raytrace::RayScene& rays, int count, Random& random) {
    const scene::Camera camera =
        scene.cameras.empty() ? scene::framing_camera(scene.world_bounds()) : scene.cameras.front();
    const float reach = camera.far_plane_for(scene.world_bounds());
    const glm::vec3 forward = camera.forward(), up = camera.up(), right = glm::cross(forward, up);
    const float half = std::tan(0.5f * camera.vertical_fov);
    std::vector<SurfacePoint> hits;
    for (int attempt = 0; attempt < 4 * count && static_cast<int>(hits.size()) < count; ++attempt) {
        const auto x = static_cast<float>(2.0 * uniform(random) - 1.0), y = static_cast<float>(2.0 * uniform(random) - 1.0);
        const glm::vec3 direction = glm::normalize(forward + x * half * right + y * half * up);
        const auto hit = trace(scene, rays, camera.position, direction, 0.0f, reach);
        if (!hit) continue;
        hits.push_back({hit->position, glm::dot(hit->normal, direction) < 0.0f ? hit->normal : -hit->normal});
    }
    return hits;
}

IndirectVisibility indirect_visibility(const scene::Scene& scene, const raytrace::RayScene& rays,
                                       const AnalysisSettings& settings, const std::atomic<bool>* cancelled) {
    Random random(settings.seed + 1);
    const std::vector<SurfacePoint> senders = light_hits(scene, rays, settings.visibility_pairs, random);
    const std::vector<SurfacePoint> receivers = camera_hits(scene, rays, settings.visibility_pairs, random);
    IndirectVisibility visibility;
    if (senders.empty() || receivers.empty()) return visibility;
    const float epsilon = 1e-4f * glm::compMax(scene.world_bounds().extent());
    // Each pair weighs as much as the light it could exchange: the form factor's kernel
    // cos cos / d^2, with d no shorter than a twentieth of the scene (a pair touching at a corner
    // does not outweigh the room). Distant pairs are occluded most often and exchange least.
    const float shortest = 0.05f * glm::compMax(scene.world_bounds().extent());
    double weight = 0.0, occluded = 0.0;
    for (std::size_t i = 0; i < std::max(senders.size(), receivers.size()); ++i) {
        if (i % 256 == 0) check_cancelled(cancelled);
        const SurfacePoint& sender = senders[i % senders.size()];
        const SurfacePoint& receiver = receivers[(i * 7919) % receivers.size()];  // not paired in step
        const glm::vec3 between = sender.position - receiver.position;
        const float distance = glm::length(between);
        if (!(distance > 2.0f * epsilon)) continue;
        const glm::vec3 direction = between / distance;
        // Only pairs that could exchange light: each in front of the other.
        const float cos_receiver = glm::dot(receiver.normal, direction), cos_sender = glm::dot(sender.normal, -direction);
        if (cos_receiver <= 0.0f || cos_sender <= 0.0f) continue;
        ++visibility.pairs;
        const double w = cos_receiver * cos_sender / std::max(distance * distance, shortest * shortest);
        weight += w;
        if (rays.occluded(receiver.position, direction, epsilon, distance - epsilon)) occluded += w;
    }
    visibility.occluded_fraction = weight > 0.0 ? occluded / weight : 0.0;
    return visibility;
}

}  // namespace

double BounceEnergy::at(const std::vector<double>& values, int bounces) {
    if (values.empty()) return 0.0;
    return values[static_cast<std::size_t>(std::clamp(bounces, 0, static_cast<int>(values.size()) - 1))];
}

double BounceEnergy::light_ratio_past(int bounces) const {
    double before = 0.0, after = 0.0;
    for (int j = std::max(bounces, 0); j < bounces + 3 && j + 1 < static_cast<int>(share.size()); ++j) {
        before += share[static_cast<std::size_t>(j)];
        after += share[static_cast<std::size_t>(j) + 1];
    }
    return before > 0.0 ? std::clamp(after / before, 0.0, 0.95) : 0.0;
}

int BounceEnergy::bounces_for(double tolerance) const {
    // A dark frame needs no bounce.
    double missing = std::accumulate(share.begin(), share.end(), 0.0) + tail;
    for (std::size_t k = 0; k < share.size(); ++k) {
        missing -= share[k];
        if (missing <= tolerance) return static_cast<int>(k);
    }
    return static_cast<int>(share.size());  // past what was traced: at least one more than max_bounces
}

bool ThinWalls::leaks(const std::string& preset) const {
    const auto it = presets.find(preset);
    return it != presets.end() && it->second.leaking_area > kLeakAreaThreshold;
}

SceneAnalysis analyze_scene(const scene::Scene& scene, const AnalysisSettings& settings, const std::atomic<bool>* cancelled) {
    const auto start = std::chrono::steady_clock::now();
    SceneAnalysis analysis;
    analysis.bounces = bounce_energy(scene, settings, cancelled);
    const raytrace::RayScene rays(scene);
    const SurfaceSampler surfaces(scene);
    analysis.thin_walls = thin_walls(scene, rays, surfaces, settings, cancelled);
    analysis.visibility = indirect_visibility(scene, rays, settings, cancelled);
    analysis.analysis_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return analysis;
}

}  // namespace bounce
