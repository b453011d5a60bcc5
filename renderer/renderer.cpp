#include "renderer/renderer.hpp"

#include "renderer/base/hash.hpp"

#include "renderer/base/bytes.hpp"
#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/memory_admission.hpp"
#include "renderer/scene_knobs.hpp"
#include "renderer/passes/light_geometry.hpp"
#include "renderer/passes/shadow_maps.hpp"

#include "common/shared_layout.h"

#include <chrono>

namespace bounce {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Reads a texture back into rows top to bottom (GL's origin is bottom-left).
template <typename T>
std::vector<T> read_texture(const gpu::Texture& texture, GLenum type) {
    const std::size_t row = static_cast<std::size_t>(texture.width()) * 4;
    std::vector<T> bottom_up(row * texture.height());
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glGetTextureImage(texture.id(), 0, GL_RGBA, type, static_cast<GLsizei>(bottom_up.size() * sizeof(T)),
                      bottom_up.data());
    std::vector<T> top_down(bottom_up.size());
    for (int y = 0; y < texture.height(); ++y) {
        std::copy_n(bottom_up.begin() + static_cast<std::ptrdiff_t>(row * y), row,
                    top_down.begin() + static_cast<std::ptrdiff_t>(row * (texture.height() - 1 - y)));
    }
    return top_down;
}

std::uint64_t next_resources_id() {
    static std::atomic<std::uint64_t> next{1};
    return next++;
}

}  // namespace

std::vector<methods::ResidentStructure> SceneResources::resident() const {
    std::vector<methods::ResidentStructure> structures = {
        {"geometry", gpu_scene.geometry_bytes(), "vertex and index buffers of every mesh"},
        {"textures", gpu_scene.texture_bytes(), "material textures with mipmaps"}};
    for (const auto& [name, method] : methods) {
        for (auto structure : method->resident()) {
            structure.name = name + "." + structure.name;
            structures.push_back(std::move(structure));
        }
    }
    return structures;
}

SceneResources::SceneResources(const scene::Scene& scene) : id(next_resources_id()), gpu_scene(scene) {}

SceneResources::~SceneResources() {
    if (live_) live_->erase(this);
}

namespace {

// Knobs a method leaves to the scene (renderer/scene_knobs.hpp), from its analysis as last made:
// made here, on the calling thread, the first time a frame needs it.
void resolve_scene_knobs(SceneResources& resources, const RenderRequest& request, const methods::MethodInfo& info,
                         methods::KnobValues& knobs) {
    if (!leaves_knobs_to_scene(knobs, request.knobs)) return;
    resolve_scene_knobs(resources.latest_analysis(), info, request.knobs, knobs);
}

}  // namespace

std::uint64_t lights_fingerprint(const scene::Scene& scene) {
    Hasher hash;
    for (const scene::Light& light : scene.lights) {
        hash.add(light.type).add(light.position.x).add(light.position.y).add(light.position.z);
        hash.add(light.direction.x).add(light.direction.y).add(light.direction.z);
        hash.add(light.color.r).add(light.color.g).add(light.color.b).add(light.intensity);
        hash.add(light.inner_cone).add(light.outer_cone);
    }
    return hash.value();
}

MethodState SceneResources::state_now(const methods::KnobValues& knobs, const FrameView& view) const {
    const scene::Scene& scene = gpu_scene.scene();
    Hasher places;
    for (const scene::Light& light : scene.lights) places.add(passes::shadow_map_fingerprint(light, 0, 0));
    places.add(scene.lights.size());
    return {knobs, lights_fingerprint(scene), places.value(), passes::geometry_fingerprint(scene),
            view_cascades_now(knobs, view), true};
}

std::uint64_t SceneResources::view_cascades_now(const methods::KnobValues& knobs, const FrameView& view) const {
    const auto size = knobs.find("shadow_map_size");
    const auto cascades = knobs.find("shadow_cascades");
    if (size == knobs.end() || !reads_view_cascades(knobs)) return 0;
    return passes::ShadowMaps::view_fingerprint(gpu_scene.scene(), view.camera, view.width, view.height,
                                                static_cast<int>(size->second), static_cast<int>(cascades->second));
}

FrameView SceneResources::view_of(const RenderRequest& request) const {
    return {camera_for(gpu_scene.scene(), request), request.width, request.height};
}

void SceneResources::record_state(const std::string& method, std::optional<MethodState> state) {
    const std::lock_guard lock(states_mutex_);
    if (state) method_states_[method] = std::move(*state);
    else method_states_.erase(method);
}

FrameChange SceneResources::change_for(const std::string& method, const methods::KnobValues& knobs,
                                       const FrameView& view) const {
    return change_for(method, state_now(knobs, view));
}

FrameChange SceneResources::change_for(const std::string& method, const MethodState& next) const {
    return change_between(state_of(method), next);
}

std::optional<MethodState> SceneResources::state_of(const std::string& method) const {
    const std::lock_guard lock(states_mutex_);
    const auto last = method_states_.find(method);
    return last == method_states_.end() ? std::nullopt : std::optional(last->second);
}

const SceneAnalysis& SceneResources::analysis() {
    const scene::Scene& scene = gpu_scene.scene();
    const std::uint64_t lights = lights_fingerprint(scene);
    if (!analysis_ || analysis_lights_ != lights) {
        analysis_ = analyze_scene(scene);
        analysis_lights_ = lights;
    }
    return *analysis_;
}

bool SceneResources::analysis_current() const {
    return analysis_ && analysis_lights_ == lights_fingerprint(gpu_scene.scene());
}

void SceneResources::install_analysis(SceneAnalysis analysis, std::uint64_t lights) {
    analysis_ = std::move(analysis);
    analysis_lights_ = lights;
}

std::uint64_t SceneResources::resident_bytes() const {
    std::uint64_t bytes = 0;
    for (const auto& structure : resident()) bytes += structure.bytes;
    return bytes;
}

scene::Camera camera_for(const scene::Scene& scene, const RenderRequest& request) {
    if (request.camera) return *request.camera;
    if (!scene.cameras.empty()) return scene.cameras.front();
    return scene::framing_camera(scene.world_bounds());
}

Renderer::Renderer(const gpu::DeviceChoice& device)
    : context_(gpu::EglContext::create(device)), budget_(gpu::default_memory_budget(context_->info())) {
    if (gpu::shader_bounds_checks_enabled()) {
        context_->make_current();
        GLint bindings = 0;
        glGetIntegerv(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS, &bindings);
        BOUNCE_CHECK(bindings > BOUNCE_BINDING_BOUNDS_CHECK,
                     "the bounds-checked shader build needs storage binding {}; this device has {}",
                     BOUNCE_BINDING_BOUNDS_CHECK, bindings);
        bounds_check_.emplace(BOUNCE_BINDING_BOUNDS_CHECK);
    }
}

Renderer::~Renderer() {
    // GL objects must go while the context is current; members are destroyed before context_.
    context_->make_current();
    for (const SceneResources* resources : live_scenes_) const_cast<SceneResources*>(resources)->live_ = nullptr;
}

std::unique_ptr<SceneResources> Renderer::upload(const scene::Scene& scene) {
    context_->make_current();
    if (budget_.bytes > 0) {
        const std::uint64_t needed = gpu::GpuScene::bytes_for(scene), held = resident_bytes();
        if (held + needed > budget_.bytes) {
            throw ResourceExhausted(fmt::format(
                "scene '{}' would hold {} on the GPU (geometry, and textures with their mipmaps), past the memory "
                "budget of {} ({}) with {} already resident: unload a scene first",
                scene.name, bytes_text(needed), bytes_text(budget_.bytes), budget_.source,
                bytes_text(held)));
        }
    }
    auto resources = std::make_unique<SceneResources>(scene);
    resources->live_ = &live_scenes_;
    live_scenes_.insert(resources.get());
    gpu::check_out_of_memory(fmt::format("the upload of scene '{}'", scene.name));
    return resources;
}

std::uint64_t Renderer::resident_bytes() const {
    std::uint64_t bytes = output_.bytes() + tonemap_.bytes() + brdf_tables_.bytes();
    for (const SceneResources* resources : live_scenes_) bytes += resources->resident_bytes();
    return bytes;
}

void Renderer::ensure_output(int width, int height) {
    if (output_ && output_.width() == width && output_.height() == height) return;
    output_ = gpu::Texture({GL_TEXTURE_2D, GL_RGBA32F, width, height});
    output_.set_filter(GL_NEAREST, GL_NEAREST);
    output_framebuffer_ = gpu::Framebuffer();
    output_framebuffer_.attach_color(0, output_);
    output_framebuffer_.set_draw_buffers(1);
    output_framebuffer_.check_complete("the HDR output");
}

FramePlan plan_frame(const RenderRequest& request) {
    if (request.width < 1 || request.height < 1 || request.width > Renderer::kMaxDimension ||
        request.height > Renderer::kMaxDimension) {
        throw InputError(fmt::format("frame size {}x{} is outside 1..{} per side", request.width, request.height,
                                     Renderer::kMaxDimension));
    }
    const auto& registry = methods::MethodRegistry::builtin();
    FramePlan plan;
    plan.site = registry.find(request.method).device == methods::MethodDevice::cpu ? FrameSite::cpu : FrameSite::gpu;
    plan.knobs = registry.resolve(request.method, request.preset, request.knobs);
    return plan;
}

RenderResult render_on_cpu(const scene::Scene& scene, const RenderRequest& request, const FramePlan& plan,
                           const std::atomic<bool>* cancelled) {
    BOUNCE_CHECK(plan.site == FrameSite::cpu, "method '{}' is not a CPU method", request.method);
    const auto start = Clock::now();
    const auto method = methods::MethodRegistry::builtin().create_cpu(request.method);
    const scene::Camera camera = camera_for(scene, request);
    RenderResult result;
    result.frame = method->render({scene, camera, request.width, request.height, plan.knobs, cancelled});
    if (request.make_display_image) image::make_display_image(result.frame, request.display);
    result.stats.method = request.method;
    result.stats.preset = request.preset;
    result.stats.knobs = plan.knobs;
    result.stats.method_statistics = method->statistics();
    result.stats.render_ms = ms_since(start);
    for (methods::ByproductFrame& byproduct : method->take_byproducts()) {
        auto made = std::make_shared<RenderResult>();
        made->frame = std::move(byproduct.frame);
        made->stats.method = request.method;
        made->stats.preset = request.preset;
        made->stats.knobs = std::move(byproduct.knobs);
        made->stats.method_statistics = std::move(byproduct.statistics);
        result.byproducts.push_back(std::move(made));
    }
    return result;
}

void Renderer::fill_stats(FrameStats& stats, const RenderRequest& request, const methods::KnobValues& knobs,
                          const methods::Method& method, const SceneResources& resources) {
    stats.method = request.method;
    stats.preset = request.preset;
    stats.knobs = knobs;
    stats.passes = timers_.resolve();
    for (const auto& pass : stats.passes) stats.gpu_ms += pass.gpu_ms;
    stats.resident = resources.resident();
    stats.method_statistics = method.statistics();
    for (const auto& structure : stats.resident) stats.resident_bytes += structure.bytes;
}

void Renderer::check_frame_memory(const SceneResources& resources, const RenderRequest& request,
                                  const methods::MethodInfo& info, const methods::KnobValues& knobs) const {
    // What this frame replaces (the method's structures and the output target) is not held elsewhere.
    std::uint64_t replaced = output_.bytes() + tonemap_.bytes();
    if (const auto existing = resources.methods.find(request.method); existing != resources.methods.end()) {
        for (const auto& structure : existing->second->resident()) replaced += structure.bytes;
    }
    check_memory_budget({info, resources.gpu_scene.scene(), knobs, request.width, request.height,
                         resident_bytes() - replaced, budget_.bytes, budget_.source});
}

std::optional<std::string> Renderer::memory_refusal(const SceneResources& resources, const RenderRequest& request) const {
    const FramePlan plan = plan_frame(request);
    if (plan.site != FrameSite::gpu) return std::nullopt;
    const auto& info = methods::MethodRegistry::builtin().find(request.method);
    // The knobs unresolved by the scene's analysis: that resolves `bounces` and isr's `ism_dilation`,
    // which size no structure, and asking for the analysis here could make it in the middle of a plan.
    try {
        check_frame_memory(resources, request, info, plan.knobs);
    } catch (const ResourceExhausted& refused) {
        return std::string(refused.what());
    }
    return std::nullopt;
}

template <typename Run>
void Renderer::with_frame(SceneResources& resources, const RenderRequest& request, const methods::Precompute& precompute,
                          Run&& run, const std::atomic<bool>* cancelled) {
    FramePlan plan = plan_frame(request);
    if (plan.site != FrameSite::gpu) throw InputError(fmt::format("method '{}' {}", request.method, kRunsOnCpu));
    context_->make_current();
    const scene::Scene& scene = resources.gpu_scene.scene();
    const auto& info = methods::MethodRegistry::builtin().find(request.method);
    resolve_scene_knobs(resources, request, info, plan.knobs);
    const methods::KnobValues& knobs = plan.knobs;
    check_frame_memory(resources, request, info, knobs);
    auto& method = resources.methods[request.method];
    if (!method) method = info.create();
    gpu::check_out_of_memory("earlier GL work");  // so what follows is this frame's alone

    ensure_output(request.width, request.height);
    brdf_tables_.bind();
    if (bounds_check_) bounds_check_->bind();

    const scene::Camera camera = camera_for(scene, request);
    const float aspect = static_cast<float>(request.width) / static_cast<float>(request.height);
    const glm::mat4 view = camera.view();
    const glm::mat4 projection = camera.projection(aspect, camera.far_plane_for(scene.world_bounds()));
    const methods::FrameContext frame{
        {scene, resources.gpu_scene, shaders_, state_, timers_, output_framebuffer_, request.width, request.height,
         camera, view, projection, projection * view},
        knobs,
        precompute,
        cancelled};
    try {
        run(*method, frame, knobs);
        gpu::check_out_of_memory(fmt::format("a '{}' frame", request.method));
        if (bounds_check_) {
            if (const auto violation = bounds_check_->take()) {
                BOUNCE_FAIL("a '{}' frame ({} preset): {}", request.method, request.preset, violation->describe());
            }
        }
    } catch (const ResourceExhausted&) {
        // Whatever the method allocated is in an unknown state: free it all, so the next frame starts clean.
        resources.methods.erase(request.method);
        resources.record_state(request.method, std::nullopt);
        throw;
    }
}

FrameStats Renderer::prepare(SceneResources& resources, const RenderRequest& request,
                             const std::function<bool(double, const std::string&)>& progress) {
    const auto start = Clock::now();
    if (plan_frame(request).site != FrameSite::gpu) {
        throw InputError(fmt::format("method '{}' has nothing to bake: it {}", request.method, kRunsOnCpu));
    }
    methods::Precompute precompute = precompute_;
    precompute.progress = progress;
    FrameStats stats;
    with_frame(resources, request, precompute, [&](methods::Method& method, const methods::FrameContext& frame,
                                                   const methods::KnobValues& knobs) {
        const FrameView view = resources.view_of(request);
        const FrameChange change = resources.change_for(request.method, knobs, view);
        timers_.begin_frame();
        const bool built = method.prepare(frame);
        fill_stats(stats, request, knobs, method, resources);
        // A bake draws no view cascades: a switch from a moved camera bakes what the knobs select,
        // and a moved camera alone bakes nothing.
        stats.change = !built || change == FrameChange::view ? FrameChange::none
                       : change == FrameChange::knobs_and_view ? FrameChange::knobs
                                                                : change;
        // Structures built for these knobs and this geometry, no light solved with them (unless a
        // frame already did: nothing changed since, or only the view cascades, which a bake does
        // not draw and no structure depends on).
        if (built && change != FrameChange::none && change != FrameChange::view) {
            MethodState unlit = resources.state_now(knobs, view);
            unlit.lit = false;
            resources.record_state(request.method, std::move(unlit));
        }
    });
    stats.render_ms = ms_since(start);
    return stats;
}

std::optional<methods::PendingWork> Renderer::pending_work(SceneResources& resources, const RenderRequest& request) {
    std::optional<methods::PendingWork> work;
    with_frame(resources, request, precompute_,
               [&](methods::Method& method, const methods::FrameContext& frame, const methods::KnobValues&) {
                   work = method.pending_work(frame);
               });
    return work;
}

void Renderer::install(SceneResources& resources, const std::string& method,
                       std::shared_ptr<methods::PrecomputeResult> result) {
    context_->make_current();
    if (const auto it = resources.methods.find(method); it != resources.methods.end()) it->second->install(std::move(result));
}

RenderResult Renderer::render(SceneResources& resources, const RenderRequest& request, const std::atomic<bool>* cancelled) {
    const auto start = Clock::now();
    const std::size_t programs_before = shaders_.size();
    RenderResult result;
    with_frame(resources, request, precompute_, [&](methods::Method& method, const methods::FrameContext& frame,
                                                    const methods::KnobValues& knobs) {
        const FrameView view = resources.view_of(request);
        const std::optional<MethodState> last = resources.state_of(request.method);
        MethodState next = resources.state_now(knobs, view);
        result.stats.change = change_between(last, next);
        // A light dimmed as the camera moved, predicted as a move of the lights (frame_change.hpp).
        const bool dimmed_as_moved = result.stats.change == FrameChange::lights && last && last->lit &&
                                     last->light_places == next.light_places;
        timers_.begin_frame();
        method.render(frame);
        resources.record_state(request.method, std::move(next));
        const gpu::Texture* display = nullptr;
        if (request.make_display_image) display = &tonemap_.run(shaders_, state_, timers_, output_, request.display);

        const auto readback_start = Clock::now();
        result.frame.width = request.width;
        result.frame.height = request.height;
        result.frame.rgba = read_texture<float>(output_, GL_FLOAT);
        if (display) result.frame.display_rgba8 = read_texture<std::uint8_t>(*display, GL_UNSIGNED_BYTE);
        result.stats.readback_ms = ms_since(readback_start);

        fill_stats(result.stats, request, knobs, method, resources);
        // The prediction hashes the cascades the maps would fit (ShadowMaps::view_fingerprint); a
        // frame that drew none all the same redid nothing, and is a warm frame for the planner. A
        // light dimmed as the camera moved is priced as a move of the lights (frame_change.hpp), and
        // said to be what it was: a change of power that drew no shadow map but the cascades, so as
        // not to price the next move of the lights by it.
        if (result.stats.change == FrameChange::view && !result.stats.ran("shadow_view_cascades")) {
            result.stats.change = FrameChange::none;
        }
        if (dimmed_as_moved && !result.stats.ran("shadow_maps")) result.stats.change = FrameChange::light_power;
        if (result.stats.change == FrameChange::knobs_and_view && !result.stats.ran("shadow_view_cascades")) {
            result.stats.change = FrameChange::knobs;
        }
    }, cancelled);
    result.stats.render_ms = ms_since(start);
    result.stats.programs_compiled = shaders_.size() - programs_before;
    return result;
}

}  // namespace bounce
