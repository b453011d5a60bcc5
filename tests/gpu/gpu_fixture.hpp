// Shared helpers for GPU tests: one Renderer per test process (llvmpipe where there is no GPU),
// small analytic scenes, and the world point a pixel centre sees.
#pragma once

#include "renderer/methods/reference/path_tracer.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene/scene.hpp"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace bounce::test {

Renderer& shared_renderer();

// A square frame of `method` at `preset` with `knobs` on top.
RenderRequest method_request(const std::string& method, const std::string& preset, int size,
                             methods::KnobValues knobs = {});

// The path-traced reference from the scene's first camera through pixel centres (as raster methods
// shade), square, with `settings` otherwise.
image::Frame pixel_centre_reference(const scene::Scene& scene, int size, int spp,
                                    methods::reference::PathTracerSettings settings);

// A Monte Carlo region mean with its noise measured, not assumed: `sample(seed)` renders with a
// seed and returns one value per pixel of the region; two seeds' means are averaged, and the
// variance of their per-pixel difference (twice one render's noise) gives the standard error.
struct MeasuredMean {
    double mean = 0.0;
    double standard_error = 0.0;
};
MeasuredMean mean_over_two_seeds(const std::function<std::vector<double>(std::uint64_t seed)>& sample);

// The largest difference of any colour channel of `test` from `expected`, relative to that channel
// (channels that are 0 in `expected` left out).
double largest_relative_difference(const image::Frame& test, const image::Frame& expected);

// Renders `scene` once with fresh resources.
RenderResult render_scene(const scene::Scene& scene, const RenderRequest& request);

scene::Material matte(const glm::vec3& albedo);

// A directional light shining along `direction` (unit) with `irradiance` W/m^2 on a surface facing it.
scene::Light directional_light(const glm::vec3& direction, float irradiance);

// assimp's sample 2CylinderEngine, as a CAD exporter writes it (67 nodes, 65 of them rotated, no
// light of its own), with a sun added and, where the file has no camera, one framing it.
scene::Scene sunlit_engine();

// Adds a one-primitive object: a square of `half_size` centred at `centre`, facing `normal`.
void add_square(scene::Scene& scene, const std::string& name, const glm::vec3& centre, float half_size,
                const glm::vec3& normal, int material);

// A camera at height `height` above the origin looking straight down (+x right, -z up on screen).
scene::Camera top_down_camera(float height, float vertical_fov);

// The point where the ray through pixel (x, y)'s centre (rows top to bottom) meets the plane y = 0.
glm::vec3 pixel_on_ground(const scene::Camera& camera, int width, int height, int x, int y);

// The pixel whose centre sees `world` (rows top to bottom).
glm::ivec2 project_to_pixel(const scene::Camera& camera, int width, int height, const glm::vec3& world);

// The same scene with every object's transform baked into its vertices (one object per primitive,
// its bounds made around its moved vertices), as an exporter that applies transforms writes it.
scene::Scene with_transforms_baked(const scene::Scene& source);

}  // namespace bounce::test
