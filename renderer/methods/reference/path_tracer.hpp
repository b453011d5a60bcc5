// Method `reference`'s core: a CPU path tracer on Embree 3 and TBB, over the same scene model,
// units, lights and BRDF (renderer/scene/shading.hpp) as the GL methods. It is the ground truth
// every method is measured against.
//
// - Punctual lights by next-event estimation; emissive triangles as area lights, sampled by power
//   and combined with BRDF sampling by multiple importance sampling (power heuristic).
// - max_bounces counts indirect bounces: 0 is direct light only (emission plus one reflection of
//   every light), as `direct` renders; k adds k further reflections.
// - Frames of fewer bounces come with a frame at no further rays (Accumulator's bounce prefixes):
//   the planner compares GPU methods with the reference of their own bounce count.
// - Russian roulette from the fourth vertex on; deterministic for a seed: sample s of pixel p uses
//   random numbers derived from (seed, p, s) alone, so rendering samples 0..N and then N..M gives
//   exactly the image of 0..M at once (progressive refinement).
// - An ambient-occlusion mode (see PathTracerSettings) measures the AO methods.
// - indirect_visibility = false (with max_bounces 1) drops visibility on the one indirect segment,
//   as instant-radiosity / RSM methods do: the first vertex gathers the reflected direct light of
//   every surface its indirect ray crosses, not just the first one.
// - Objects are Embree instances of per-mesh scenes: moving an object updates its instance
//   transform and rebuilds only the top level.
#pragma once

#include "renderer/image/frame.hpp"
#include "renderer/scene/scene.hpp"

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace bounce::methods::reference {

struct PathTracerSettings {
    int max_bounces = 4;  // indirect bounces; 0 = direct light only
    std::uint64_t seed = 1;
    // Jittered samples average each pixel's footprint (anti-aliased); false puts every camera ray
    // through the pixel centre, as raster methods shade, for like-for-like comparisons.
    bool pixel_jitter = true;
    // Ambient occlusion instead of radiance, as the voxel cone tracing paper defines it (its §6):
    // A(p) = 1/pi * integral over the hemisphere of (1 - f(r) [the ray hits at distance r]) cos,
    // with f(r) = 1 / (1 + lambda r). Written to RGB alike; 0 where a camera ray hits nothing.
    bool ambient_occlusion = false;
    float ao_lambda = 1.0f;  // per metre
    // false: the indirect ray from the first camera hit x passes through every surface y it
    // crosses, adding what each y reflects of direct light (emission and shadow rays at y as for a
    // visible y; emission only from the first y). Direct light at x is unchanged. Needs
    // max_bounces 1 and no ambient occlusion (check_settings).
    bool indirect_visibility = true;
};

// Throws InputError for settings that contradict each other (indirect_visibility = false with
// max_bounces other than 1, or with ambient occlusion). render() checks them too.
void check_settings(const PathTracerSettings& settings);

// What camera rays first meet in a pixel, averaged over its samples: the guides of the denoiser
// (renderer/methods/reference/denoiser.hpp). Pixels whose rays meet nothing have coverage 0.
struct PixelFeatures {
    int width = 0, height = 0;
    std::vector<glm::vec3> albedo;  // base colour at the first hit
    std::vector<glm::vec3> normal;  // shading normal at the first hit (mean, not renormalized)
    std::vector<float> depth;       // distance to the first hit
    std::vector<float> coverage;    // fraction of samples that hit something
    std::vector<float> variance;    // of the pixel's mean luminance: the samples' variance over their count
};

// Running sums of radiance samples per pixel; frame() gives their mean, features() the mean of
// what the camera rays first met. With `bounce_prefixes` = P, also the sums of the same paths
// stopped after each of 0..P-1 bounces: prefix_frame(k) is exactly the frame that the same seed and
// samples give with max_bounces = k, at no further rays (path_tracer.cpp, trace()). P must not
// exceed the frame's max_bounces; prefixes_that_fit() caps it by memory.
class Accumulator {
public:
    Accumulator(int width, int height, int bounce_prefixes = 0);
    int width() const { return width_; }
    int height() const { return height_; }
    int samples() const { return samples_; }
    int bounce_prefixes() const { return bounce_prefixes_; }
    image::Frame frame() const;
    PixelFeatures features() const;
    image::Frame prefix_frame(int bounces) const;
    double prefix_noise_per_sample(int bounces) const;  // noise_per_sample() of prefix_frame(bounces)
    // The same, each pixel's variance over the luminance of `against` (same size) in place of the
    // prefix's own: the relMSE per sample its noise makes against a brighter frame of more bounces.
    double prefix_noise_per_sample(int bounces, const image::Frame& against) const;
    // vertices_shaded()[j]: how many of the samples' paths shaded a vertex after j bounces (next-event
    // estimation and the BRDF-sampled ray, the work of one loop of trace()), over every render into
    // this accumulator; as long as the most bounces rendered plus one. A frame of k bounces does the
    // work of entries 0..k: with the camera rays, what its time is made of.
    const std::vector<std::uint64_t>& vertices_shaded() const { return vertices_shaded_; }

    // Pixels times prefixes kept at most: 28 bytes each, 56 MiB (every prefix of 32 bounces at
    // 256x256; at 1920x1080, the frame without bounces alone).
    static constexpr std::size_t kMaxPrefixValues = std::size_t{1} << 21;
    // The prefixes of a frame of `max_bounces` bounces that fit kMaxPrefixValues, fewest bounces first.
    static int prefixes_that_fit(int width, int height, int max_bounces);

private:
    friend class PathTracer;
    int width_;
    int height_;
    int bounce_prefixes_;
    int samples_ = 0;
    std::vector<double> sums_;  // RGB per pixel
    std::vector<float> feature_sums_;  // per pixel: albedo RGB, normal XYZ, depth, hits, luminance^2
    std::vector<double> prefix_sums(int bounces) const;  // one prefix's RGB per pixel
    std::vector<double> prefix_sums_;  // per pixel, per prefix: RGB
    std::vector<float> prefix_luminance2_;  // per pixel, per prefix
    std::vector<std::uint64_t> vertices_shaded_;
};

// The mean over pixels of one sample's luminance variance over (luminance^2 + 0.01), the luminance
// being the median of the pixel's 3x3 neighbourhood, as image::compare weighs errors: a frame of s
// samples has a relMSE of about this over s (rare bright paths that the accumulated samples never
// met are missing from it).
double noise_per_sample(const Accumulator& accumulator);

// Radiance at chosen pixels of a frame: a reference traced through a subset of a frame's pixels.
// Per pixel, the mean of its even samples and of its odd ones, each with its channels' variance of
// that mean (the samples' variance over their count): two independent estimates, so that what
// weighs an error (relMSE's reference value) need not be the draw that makes it.
struct PixelEstimates {
    std::vector<int> pixels;  // y * width + x
    std::vector<glm::dvec3> mean[2];
    std::vector<glm::dvec3> variance[2];
    int samples = 0;               // of both halves
    int half_samples[2] = {0, 0};  // of each
};

// Adds `more`'s samples (of the same pixels, other sample numbers) to `into`: the halves' means and
// variances of their means as if traced at once.
void merge(PixelEstimates& into, const PixelEstimates& more);

class PathTracer {
public:
    // Builds the acceleration structures; the scene must outlive the tracer.
    explicit PathTracer(const scene::Scene& scene);
    ~PathTracer();
    PathTracer(const PathTracer&) = delete;
    PathTracer& operator=(const PathTracer&) = delete;

    // Re-reads every object's transform (after objects moved); rebuilds only the top level.
    void update_transforms();

    // Adds `count` samples per pixel, continuing from the accumulator's sample count.
    // `cancelled`, when given and set from another thread, stops the work after at most one pixel's
    // samples on each worker and throws Cancelled; the accumulator is then left unchanged in count
    // but partly summed, so it must not be used further.
    void render(Accumulator& accumulator, const scene::Camera& camera, int count, const PathTracerSettings& settings,
                const std::atomic<bool>* cancelled = nullptr) const;

    // Convenience: a fresh image of `spp` samples per pixel.
    image::Frame render(const scene::Camera& camera, int width, int height, int spp,
                        const PathTracerSettings& settings) const;

    // `spp` samples (4 or more) at each of `pixels` (y * width + x) of a width x height frame: the
    // very samples first_sample..first_sample+spp-1 that render() gives those pixels (merge() them
    // with earlier ones to go on). Throws Cancelled as render() does.
    PixelEstimates trace_pixels(const scene::Camera& camera, int width, int height, std::vector<int> pixels, int spp,
                                const PathTracerSettings& settings, const std::atomic<bool>* cancelled = nullptr,
                                int first_sample = 0) const;

    std::uint64_t rays_traced() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace bounce::methods::reference
