// The render entry point. plan_frame() decides, once and on any thread, whether a request runs on
// the GPU or on CPU threads and with which knobs. GPU plans go to the Renderer, which owns the EGL
// context and what every GPU method shares (shader cache, state owner, timers, tone mapping, the
// output target); one thread, the render thread, creates it and makes every call on it. CPU plans go
// to render_on_cpu() on any other thread.
#pragma once

#include "renderer/frame_change.hpp"
#include "renderer/gpu/bounds_check.hpp"
#include "renderer/gpu/brdf_tables.hpp"
#include "renderer/gpu/egl_device.hpp"
#include "renderer/gpu/memory_budget.hpp"
#include "renderer/image/frame.hpp"
#include "renderer/image/tone.hpp"
#include "renderer/methods/registry.hpp"
#include "renderer/passes/tonemap_pass.hpp"
#include "renderer/planning/costs.hpp"
#include "renderer/scene_analysis.hpp"

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <vector>
#include <optional>
#include <set>
#include <string>
#include <string_view>

namespace bounce {

struct RenderRequest {
    std::string method = "direct";
    std::string preset = "medium";
    methods::KnobValues knobs;  // overrides of the preset
    int width = 512;
    int height = 512;
    std::optional<scene::Camera> camera;  // default: the scene's first camera
    image::DisplayTransform display;
    bool make_display_image = true;  // tone-map to 8-bit sRGB as well (PNG, JPEG)
};

struct FrameStats {
    std::string method;
    std::string preset;
    methods::KnobValues knobs;
    std::vector<gpu::PassTiming> passes;
    double gpu_ms = 0.0;       // sum of the passes
    double render_ms = 0.0;    // wall time of render() on the render thread
    double readback_ms = 0.0;  // part of render_ms spent reading pixels back
    std::vector<methods::ResidentStructure> resident;
    std::size_t resident_bytes = 0;
    std::map<std::string, double> method_statistics;  // Method::statistics() after this frame
    FrameChange change = FrameChange::none;  // GPU frames: what it redid against its method's last frame
    // GPU frames: programs this frame compiled, each once per daemon (gpu::ShaderCache). Its time
    // and its passes' include theirs (a driver may compile at a program's first draw), which no later
    // frame of the same work pays: the planner keeps no time of such a frame (record_frame).
    std::size_t programs_compiled = 0;

    // The GPU time of the frame's passes named `name` (0 where none ran: shadow_maps runs only in
    // frames that drew maps).
    double pass_ms(std::string_view name) const {
        double ms = 0.0;
        for (const gpu::PassTiming& timing : passes) ms += timing.pass == name ? timing.gpu_ms : 0.0;
        return ms;
    }
    bool ran(std::string_view name) const {
        return std::any_of(passes.begin(), passes.end(), [&](const gpu::PassTiming& timing) { return timing.pass == name; });
    }
};

struct RenderResult {
    image::Frame frame;
    FrameStats stats;
    // Frames the same work made on the way, each as if rendered alone with its stats' knobs: the
    // reference's frames of each fewer bounce count (methods::CpuMethod::take_byproducts). Not
    // delivered; the planner compares GPU frames with them and records their noise.
    std::vector<std::shared_ptr<const RenderResult>> byproducts;
};

// Where a frame is made: on the render thread through the Renderer (GL), or on CPU threads.
enum class FrameSite { gpu, cpu };

struct FramePlan {
    FrameSite site = FrameSite::gpu;
    methods::KnobValues knobs;  // the preset with the request's overrides, validated
};

// The one place that decides where a request runs: validates its method, preset, knobs and size
// (InputError naming the fault) and resolves its knobs. Thread-safe: the daemon plans a request
// before queueing it.
FramePlan plan_frame(const RenderRequest& request);

// Renders a CPU plan on the calling thread (never the render thread) from a scene snapshot that no
// one mutates meanwhile, and tone-maps it on the CPU when the request wants a display image.
// Throws Cancelled when `cancelled` is set during the work.
RenderResult render_on_cpu(const scene::Scene& scene, const RenderRequest& request, const FramePlan& plan,
                           const std::atomic<bool>* cancelled = nullptr);

// The camera a frame sees the scene with and the size it renders at: what the suns' view cascades
// are fitted to besides the scene (of the size, only the shape counts).
struct FrameView {
    scene::Camera camera;
    int width = 0, height = 0;
};

// A scene's resident GPU state: its geometry and textures and the methods that rendered it (with
// their precomputed structures). Destroy it on the render thread, before the Renderer.
class SceneResources {
public:
    explicit SceneResources(const scene::Scene& scene);
    ~SceneResources();
    SceneResources(const SceneResources&) = delete;
    SceneResources& operator=(const SceneResources&) = delete;
    const std::uint64_t id;  // unique in the process: work made for these resources finds them, not a successor
    gpu::GpuScene gpu_scene;
    std::map<std::string, std::unique_ptr<methods::Method>> methods;

    std::vector<methods::ResidentStructure> resident() const;
    std::uint64_t resident_bytes() const;

    // What the scene needs (renderer/scene_analysis.hpp): made on the first frame that asks for it,
    // on the calling thread, and made again when the lights change (moving objects keep it).
    const SceneAnalysis& analysis();
    // The analysis if a frame or a plan made it, without making it.
    const SceneAnalysis* analysis_if_made() const { return analysis_ ? &*analysis_ : nullptr; }
    // The analysis as last made, whatever lights it was made for; made now if none was. What knobs
    // left to the scene read (renderer/scene_knobs.hpp): a frame right after a light's change does
    // not wait for the scene to be analysed again (the daemon makes it anew on the CPU pool).
    const SceneAnalysis& latest_analysis() { return analysis_ ? *analysis_ : analysis(); }
    // Whether analysis() would answer without analysing: made, for the lights the scene has now.
    bool analysis_current() const;
    // Installs an analysis made elsewhere (on CPU threads, from a copy of the scene) for the lights
    // it was made with (lights_fingerprint of that copy); analysis() makes it anew if they changed.
    void install_analysis(SceneAnalysis analysis, std::uint64_t lights);

    // What a frame of `method` at `knobs` (resolved, as plan_frame resolves them) seen as `view`
    // would redo now, against the method's last frame on these resources (frame_change.hpp). On the
    // render thread, or wherever the scene does not change meanwhile (it reads the scene's lights,
    // geometry and bounds); the methods' states are locked.
    FrameChange change_for(const std::string& method, const methods::KnobValues& knobs, const FrameView& view) const;
    // The same for a state made by state_now() (the planner asks for hundreds of plans).
    FrameChange change_for(const std::string& method, const MethodState& next) const;
    // The state the method's structures were last made for here; nullopt before its first frame.
    std::optional<MethodState> state_of(const std::string& method) const;
    // The state a frame at `knobs` seen as `view` would leave now: the scene's lights and geometry as
    // they are, and the suns' view cascades it fits (passes::ShadowMaps::view_fingerprint).
    MethodState state_now(const methods::KnobValues& knobs, const FrameView& view) const;
    // The state's view cascades for other knobs.
    std::uint64_t view_cascades_now(const methods::KnobValues& knobs, const FrameView& view) const;
    // The camera and frame size a request renders with on this scene.
    FrameView view_of(const RenderRequest& request) const;

    // What this scene's frames measured, for the planner (renderer/planning/). Shared: CPU frames
    // record into it from the CPU pool, and may outlive the resources.
    const std::shared_ptr<planning::SceneMeasurements> measurements = std::make_shared<planning::SceneMeasurements>();

private:
    friend class Renderer;
    std::optional<SceneAnalysis> analysis_;
    std::uint64_t analysis_lights_ = 0;  // the lights it was made for
    // Per method, the state its structures were last made for (the render thread writes it).
    void record_state(const std::string& method, std::optional<MethodState> state);
    mutable std::mutex states_mutex_;
    std::map<std::string, MethodState> method_states_;
    std::set<const SceneResources*>* live_ = nullptr;  // the uploading Renderer's list, for its memory budget
};

// A hash of a scene's lights: what its analysis depends on besides geometry, which a scene's
// resources never change.
std::uint64_t lights_fingerprint(const scene::Scene& scene);

class Renderer {
public:
    explicit Renderer(const gpu::DeviceChoice& device);
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    const gpu::GpuInfo& gpu_info() const { return context_->info(); }

    // Uploads a scene; the Scene must outlive the returned resources (they read its transforms,
    // lights and materials at every frame).
    std::unique_ptr<SceneResources> upload(const scene::Scene& scene);

    // Renders a GPU plan. Throws InputError for bad requests (unknown method, preset or knob, size
    // out of range, a method that runs on the CPU).
    // `cancelled`, when given, stops long GPU work between its batches (Cancelled is thrown).
    RenderResult render(SceneResources& resources, const RenderRequest& request,
                        const std::atomic<bool>* cancelled = nullptr);

    // Builds the method's precomputed structures for the request's knobs (Method::prepare) and
    // returns the stats a frame would carry, without drawing one. `progress` may cancel (the
    // method then throws).
    FrameStats prepare(SceneResources& resources, const RenderRequest& request,
                       const std::function<bool(double, const std::string&)>& progress);

    // The long CPU work (a bake) the request's method needs before its next frame, or nullopt; the
    // memory check comes first. A server runs it off the render thread and hands the result back
    // with install(); render() and prepare() do it inline when nobody did.
    std::optional<methods::PendingWork> pending_work(SceneResources& resources, const RenderRequest& request);
    void install(SceneResources& resources, const std::string& method, std::shared_ptr<methods::PrecomputeResult> result);

    // Where methods persist baked structures across restarts (none by default).
    void set_cache_dir(std::optional<std::filesystem::path> dir) { precompute_.cache_dir = std::move(dir); }

    // The bytes every uploaded scene may hold together on the GPU (and, for a software rasterizer,
    // in host memory): a frame whose method estimates more, with what is resident elsewhere, is
    // refused with ResourceExhausted before anything is allocated. The default comes from the device
    // (gpu::default_memory_budget); 0 turns the check off.
    void set_memory_budget(gpu::MemoryBudget budget) { budget_ = std::move(budget); }
    const gpu::MemoryBudget& memory_budget() const { return budget_; }
    // What every uploaded scene holds now, with the output target.
    std::uint64_t resident_bytes() const;
    // Why a frame of `request` would now be refused for memory (the check render() makes first), or
    // nullopt where it fits or is not a GPU frame: the planner rules such plans out.
    std::optional<std::string> memory_refusal(const SceneResources& resources, const RenderRequest& request) const;

    static constexpr int kMaxDimension = 16384;

private:
    std::unique_ptr<gpu::EglContext> context_;  // first member: destroyed last
    methods::Precompute precompute_;
    gpu::ShaderCache shaders_;
    gpu::StateCache state_;
    gpu::GpuTimers timers_;
    gpu::BrdfTables brdf_tables_;  // bound for every frame: every method's BRDF reads them
    passes::TonemapPass tonemap_;
    // With BOUNCE_SHADER_BOUNDS_CHECK: where checked shaders record an out-of-bounds access.
    std::optional<gpu::BoundsCheckBuffer> bounds_check_;
    void ensure_output(int width, int height);
    void fill_stats(FrameStats& stats, const RenderRequest& request, const methods::KnobValues& knobs,
                    const methods::Method& method, const SceneResources& resources);
    // Throws ResourceExhausted where a frame of the method at these (resolved) knobs would pass the budget.
    void check_frame_memory(const SceneResources& resources, const RenderRequest& request,
                            const methods::MethodInfo& info, const methods::KnobValues& knobs) const;
    // Resolves the request's knobs, creates its method if needed, and calls run(method, frame, knobs).
    template <typename Run>
    void with_frame(SceneResources& resources, const RenderRequest& request, const methods::Precompute& precompute,
                    Run&& run, const std::atomic<bool>* cancelled = nullptr);
    static constexpr std::string_view kRunsOnCpu = "runs on CPU threads, not through the GL renderer";
    gpu::Texture output_;
    gpu::Framebuffer output_framebuffer_;
    gpu::MemoryBudget budget_;
    std::set<const SceneResources*> live_scenes_;
};

// The camera a request renders with: its own, the scene's first, or one that frames the scene.
scene::Camera camera_for(const scene::Scene& scene, const RenderRequest& request);

}  // namespace bounce
