// Executes the requests sessions admit. The path of a request (docs/architecture.md):
//
//   network thread (session strand): parse_order + plan_frame; refused here, nothing queued
//   render thread: scene requests, GPU frames; CPU frames only snapshot the scene here, and frames
//                  that need a bake first only start it
//   precompute pool: bakes (a method's PendingWork); the frames that waited for one go back to the
//                  render thread, ahead of the queue
//   CPU pool: CPU frames (trace, CPU tone map)
//   encode pool: every frame's encoding and reply
//
// Each hop runs inside one boundary that turns any exception into the request's error reply, so
// no input reaches terminate().
#pragma once

#include "renderer/planning/calibration.hpp"
#include "renderer/planning/resolution.hpp"
#include "server/frame_json.hpp"
#include "server/request.hpp"
#include "server/shared_work.hpp"

#include <map>
#include <memory>
#include <string>

namespace bounce {
class Renderer;
}

namespace bounce::server {

class Daemon;
class SceneRegistry;
struct SceneEntry;

class RequestHandlers {
public:
    explicit RequestHandlers(Daemon& daemon) : daemon_(daemon) {}

    // On the network thread: parses and plans the request, then queues it for the render thread.
    // Refusals (bad fields, unknown methods or knobs, a full queue) answer the request at once.
    void admit(const std::shared_ptr<Request>& request);

    // On the render thread: runs an admitted request (its order set) as if just dequeued. Preview
    // streams start their frames here.
    void execute(const std::shared_ptr<Request>& request, Renderer& renderer, SceneRegistry& registry);

private:
    void render_on_gpu(const std::shared_ptr<Request>& request, const RenderOrder& order, Renderer& renderer,
                       SceneRegistry& registry);
    void render_on_cpu(const std::shared_ptr<Request>& request, const RenderOrder& order, Renderer& renderer,
                       SceneRegistry& registry);
    void describe_with_analysis(const std::shared_ptr<Request>& request, const SceneNameOrder& order,
                                SceneRegistry& registry);
    nlohmann::json bake(const std::shared_ptr<Request>& request, const BakeOrder& order, Renderer& renderer,
                        SceneRegistry& registry);
    nlohmann::json stats(Renderer& renderer, SceneRegistry& registry);
    // When the frame's method needs long CPU work first, makes the request wait for it (starting it
    // on the precompute pool, or joining a run of the same work) and returns true: the request runs
    // again once the work is done. False when there is none.
    bool wait_for_pending_work(const std::shared_ptr<Request>& request, const std::string& scene_name,
                               SceneEntry& entry, const RenderRequest& frame, Renderer& renderer);
    // Encodes the frame on the encode pool and answers with it.
    void deliver(const std::shared_ptr<Request>& request, const RenderOrder& order,
                 std::shared_ptr<const RenderResult> result, std::uint64_t scene_version, FrameClock clock);

    // A render with a budget becomes a render of the plan the planner chooses for it.
    void plan_budgeted(RenderOrder& order, Renderer& renderer, SceneRegistry& registry);
    // Queues `request` until the device's costs are calibrated (starting the calibration if none
    // runs); it then runs as if just dequeued. Waiters get `progress` events.
    void wait_for_calibration(const std::shared_ptr<Request>& request, Renderer& renderer);
    void calibration_step(Renderer& renderer, SceneRegistry& registry);
    // A budget needs the scene's analysis for its current lights: made on the CPU pool from a copy
    // of the scene (tenths of a second on the bench scenes, more on larger ones) while the render
    // thread serves others; the requests that need it wait and run again once it is installed.
    // False when it is current, or when every CPU slot is taken (the caller then analyses here).
    // With no request, the analysis is started (if it is not current, runs nowhere and a CPU slot is
    // free) and nothing waits for it: false.
    bool wait_for_analysis(const std::shared_ptr<Request>& request, const std::string& scene_name, SceneEntry& entry);
    // Renders the order's probes whose structures are built (a probe never waits for a bake) and
    // compares each with the reference frame of its view when there is one.
    void render_probes(const RenderOrder& order, Renderer& renderer, SceneRegistry& registry);
    // A reference plan with spot-checked GPU plans before it: traces the check's reference on a CPU
    // slot, then (on the render thread) try_checked_plans(). Without a free slot, the reference plan.
    void check_before_reference(const std::shared_ptr<Request>& request, const RenderOrder& order, Renderer& renderer,
                                SceneRegistry& registry);
    void try_checked_plans(const std::shared_ptr<Request>& request, RenderOrder order,
                           const std::shared_ptr<const planning::SpotReference>& spot, std::uint64_t traced_version,
                           Renderer& renderer, SceneRegistry& registry);
    // The error upsampling adds at each scale for the order's view (planning/resolution.hpp).
    planning::ResampleErrors resample_errors(const RenderOrder& order, Renderer& renderer, SceneEntry& entry);
    // The device's cost model: read from the cache folder, else calibrated (render thread; once).
    const planning::DeviceCosts& device_costs(Renderer& renderer);
    // The same if the cache had one or a plan needed it; nullptr otherwise (frames are then not
    // recorded, since they have no line to be measured against).
    const planning::DeviceCosts* known_device_costs(Renderer& renderer);

    Daemon& daemon_;
    std::map<std::string, std::shared_ptr<SharedWork>> running_work_;  // render thread only, by work key
    std::optional<planning::DeviceCosts> device_costs_;  // render thread only
    bool looked_for_cached_costs_ = false;
    // Budgets that came before the device's costs were known wait for its calibration, which runs
    // a step at a time on the render thread with other jobs served between steps (render thread only).
    std::unique_ptr<planning::Calibration> calibration_;
    std::vector<std::shared_ptr<Request>> calibration_waiters_;
};

}  // namespace bounce::server
