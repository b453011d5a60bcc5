#include "server/request_handlers.hpp"

#include "renderer/base/hash.hpp"
#include "renderer/base/log.hpp"
#include "renderer/planning/calibration.hpp"
#include "renderer/planning/error_model.hpp"
#include "renderer/planning/resolution.hpp"
#include "renderer/scene_knobs.hpp"
#include "renderer/image/codec.hpp"
#include "server/daemon.hpp"
#include "server/scene_requests.hpp"

namespace bounce::server {
namespace {

using nlohmann::json;
using protocol::ErrorCode;
using protocol::MessageType;
using Clock = std::chrono::steady_clock;

// Frames of one view: the scene's state, the camera and the size (FrameComparisons compares them).
std::uint64_t view_key(std::uint64_t scene_version, const RenderRequest& frame) {
    Hasher hash;
    hash.add(scene_version).add(frame.width).add(frame.height).add(frame.camera.has_value());
    if (const auto& camera = frame.camera) {
        hash.add(camera->position.x).add(camera->position.y).add(camera->position.z);
        hash.add(camera->orientation.x).add(camera->orientation.y).add(camera->orientation.z).add(camera->orientation.w);
        hash.add(camera->vertical_fov).add(camera->z_near).add(camera->z_far);
    }
    return hash.value();
}

// The view a render asks for, as a one-off: the scene's own cameras are untouched.
std::optional<scene::Camera> view_camera(const scene::Scene& scene, const RenderOrder& order) {
    if (!order.view) return std::nullopt;
    try {
        return camera_from(scene, *order.view);
    } catch (const RequestError& error) {
        if (error.code() == ErrorCode::not_found) {
            throw RequestError(ErrorCode::not_found,
                               fmt::format("scene '{}' has no camera '{}'", order.scene, order.view->camera.value_or("")),
                               "camera");
        }
        throw;
    } catch (const protocol::FieldError& error) {
        throw protocol::FieldError(fmt::format("camera.{}", error.field), error.what());
    }
}

// The scene a request changed (its version, its presence), for the streams that show it.
std::optional<std::string> changed_scene(const Request& request) {
    if (request.message().type == static_cast<std::uint16_t>(MessageType::scene_describe)) return std::nullopt;
    return std::visit(
        [](const auto& o) -> std::optional<std::string> {
            using T = std::decay_t<decltype(o)>;
            if constexpr (std::is_same_v<T, LoadOrder> || std::is_same_v<T, SceneNameOrder>) {
                return o.name;  // loaded anew or unloaded
            } else if constexpr (std::is_same_v<T, TransformOrder> || std::is_same_v<T, LightOrder> ||
                                 std::is_same_v<T, RemoveLightOrder> || std::is_same_v<T, CameraOrder>) {
                return o.scene;
            } else {
                return std::nullopt;
            }
        },
        request.order.value());
}

void check_scene_version(const SceneEntry& entry, const RenderOrder& order) {
    if (order.min_scene_version && entry.version < *order.min_scene_version) {
        throw RequestError(ErrorCode::bad_request,
                           fmt::format("scene '{}' is at version {}, below min_scene_version {}", order.scene,
                                       entry.version, *order.min_scene_version),
                           "min_scene_version");
    }
}

// Holds one of the daemon's CPU-frame slots and gives it back however the frame ends.
class CpuSlot {
public:
    explicit CpuSlot(Daemon& daemon) : daemon_(daemon) {}
    ~CpuSlot() { daemon_.finish_cpu_job(); }
    CpuSlot(const CpuSlot&) = delete;
    CpuSlot& operator=(const CpuSlot&) = delete;

private:
    Daemon& daemon_;
};

}  // namespace

void RequestHandlers::admit(const std::shared_ptr<Request>& request) {
    try {
        const json& body = request->message().body;
        if (const auto timeout = protocol::get_optional_integer(body, "timeout_ms", 1, 24ll * 3600 * 1000)) {
            request->arm_deadline(daemon_.io(), std::chrono::milliseconds(*timeout));
        }
        request->order = parse_order(request->message(), daemon_.config().max_pixels);
        const bool queued = daemon_.render_service().submit(
            [this, request](Renderer& renderer, SceneRegistry& registry) { execute(request, renderer, registry); });
        if (!queued) {
            throw RequestError(ErrorCode::busy,
                               fmt::format("the render queue is full ({} jobs)", daemon_.render_service().queue_capacity()));
        }
        daemon_.metrics().set_queue_depth(daemon_.render_service().queue_depth());
    } catch (...) {
        request->fail(std::current_exception());
    }
}

// Runs on the render thread.
void RequestHandlers::execute(const std::shared_ptr<Request>& request, Renderer& renderer, SceneRegistry& registry) {
    const log::RequestScope scope(request->log_id);
    daemon_.metrics().set_queue_depth(daemon_.render_service().queue_depth());
    try {
        request->check_still_wanted();
        if (auto* render = std::get_if<RenderOrder>(&request->order.value()); render && render->budget && !render->planned) {
            registry.get(render->scene);  // an unknown scene is refused before any calibration
            if (!known_device_costs(renderer)) {
                wait_for_calibration(request, renderer);
                return;
            }
            if (wait_for_analysis(request, render->scene, registry.get(render->scene))) return;
            plan_budgeted(*render, renderer, registry);  // before the visit: it changes the order
        } else if (render && !render->budget && render->plan.site == FrameSite::gpu &&
                   leaves_knobs_to_scene(render->plan.knobs, render->request.knobs)) {
            // Knobs left to the scene (renderer/scene_knobs.hpp) read its analysis: the first made on
            // the CPU pool, not on the render thread other clients' frames wait on. After a light
            // changes, the frame reads the analysis as last made while the CPU pool makes it again: a
            // lighting preview's frames do not wait tenths of a second on each move of a light.
            SceneEntry& entry = registry.get(render->scene);
            if (wait_for_analysis(entry.resources->analysis_if_made() ? nullptr : request, render->scene, entry)) return;
        }
        const std::span<const std::uint8_t> attachment = request->message().attachment;
        const json reply = std::visit(
            [&](const auto& order) -> json {
                using T = std::decay_t<decltype(order)>;
                if constexpr (std::is_same_v<T, LoadOrder>) {
                    return load_scene(registry, daemon_.scene_root(), order, attachment);
                } else if constexpr (std::is_same_v<T, SceneNameOrder>) {
                    if (request->message().type == static_cast<std::uint16_t>(MessageType::scene_describe)) {
                        if (!order.analyze) return describe_scene(registry, order);
                        describe_with_analysis(request, order, registry);
                        return nullptr;  // answered from the CPU pool
                    }
                    json unloaded = unload_scene(registry, order);
                    daemon_.metrics().forget_scene(order.name);
                    return unloaded;
                } else if constexpr (std::is_same_v<T, ListOrder>) {
                    return list_scenes(registry);
                } else if constexpr (std::is_same_v<T, StatsOrder>) {
                    return stats(renderer, registry);
                } else if constexpr (std::is_same_v<T, TransformOrder>) {
                    return set_object_transform(registry, order);
                } else if constexpr (std::is_same_v<T, LightOrder>) {
                    return set_light(registry, order);
                } else if constexpr (std::is_same_v<T, RemoveLightOrder>) {
                    return remove_light(registry, order);
                } else if constexpr (std::is_same_v<T, CameraOrder>) {
                    return set_camera(registry, order);
                } else if constexpr (std::is_same_v<T, BakeOrder>) {
                    return bake(request, order, renderer, registry);
                } else {
                    static_assert(std::is_same_v<T, RenderOrder>);
                    if (order.plan.site == FrameSite::cpu && order.spot_check && !order.checks.empty()) {
                        check_before_reference(request, order, renderer, registry);
                    } else if (order.plan.site == FrameSite::cpu) {
                        render_on_cpu(request, order, renderer, registry);
                        render_probes(order, renderer, registry);
                    } else {
                        render_on_gpu(request, order, renderer, registry);
                    }
                    return nullptr;  // frames answer from the encode pool
                }
            },
            request->order.value());
        if (const auto scene = changed_scene(*request)) daemon_.streams().scene_changed(*scene);
        if (!reply.is_null()) request->answer(protocol::make_ok(request->id(), reply));
    } catch (...) {
        request->fail(std::current_exception());
    }
}

void RequestHandlers::render_on_gpu(const std::shared_ptr<Request>& request, const RenderOrder& order,
                                    Renderer& renderer, SceneRegistry& registry) {
    FrameClock clock{request->received, Clock::now(), {}, {}};
    SceneEntry& entry = registry.get(order.scene);
    check_scene_version(entry, order);
    RenderRequest frame = order.request;
    if (auto camera = view_camera(*entry.scene, order)) frame.camera = std::move(camera);
    if (wait_for_pending_work(request, order.scene, entry, frame, renderer)) return;
    auto result = std::make_shared<const RenderResult>(renderer.render(*entry.resources, frame, request->cancelled.get()));
    if (const planning::DeviceCosts* device = known_device_costs(renderer)) {
        planning::record_frame(*entry.resources->measurements, entry.resources->analysis_if_made(), *device, result->stats,
                               frame.width, frame.height);
    }
    if (order.output_size) {
        result = std::make_shared<const RenderResult>(
            planning::upsampled(*result, order.output_size->first, order.output_size->second, frame));
    } else {
        entry.comparisons->add(view_key(entry.version, frame), result, entry.resources->analysis_if_made(),
                               *entry.resources->measurements);
    }
    clock.rendered = Clock::now();
    daemon_.metrics().set_resident_bytes(order.scene, result->stats.resident_bytes);
    daemon_.metrics().set_gpu_memory(renderer.memory_budget().bytes, renderer.resident_bytes());
    deliver(request, order, std::move(result), entry.version, clock);
}

// On the render thread only long enough to snapshot the scene, so the trace on the CPU pool never
// races with later mutations and never holds the render thread.
void RequestHandlers::render_on_cpu(const std::shared_ptr<Request>& request, const RenderOrder& order,
                                    Renderer& renderer, SceneRegistry& registry) {
    const SceneEntry& entry = registry.get(order.scene);
    check_scene_version(entry, order);
    auto snapshot = std::make_shared<const scene::Scene>(*entry.scene);
    RenderRequest frame = order.request;
    if (auto camera = view_camera(*snapshot, order)) frame.camera = std::move(camera);
    if (!daemon_.try_start_cpu_job()) {
        throw RequestError(ErrorCode::busy, fmt::format("{} CPU renders are already queued", Daemon::kMaxCpuJobs));
    }
    auto slot = std::make_shared<CpuSlot>(daemon_);
    const std::uint64_t version = entry.version;
    // What recording the frame for the planner needs, copied: the CPU pool must not read the render
    // thread's state.
    std::shared_ptr<planning::SceneMeasurements> measurements = entry.resources->measurements;
    std::shared_ptr<planning::FrameComparisons> comparisons = entry.comparisons;
    const std::uint64_t view = view_key(entry.version, frame);
    std::optional<SceneAnalysis> analysis;
    if (const SceneAnalysis* made = entry.resources->analysis_if_made()) analysis = *made;
    std::optional<planning::DeviceCosts> device;
    if (const planning::DeviceCosts* known = known_device_costs(renderer)) device = *known;
    boost::asio::post(daemon_.cpu_pool(), [this, request, order, frame, snapshot, version, slot, measurements, comparisons, view,
                                           analysis = std::move(analysis), device = std::move(device)] {
        const log::RequestScope scope(request->log_id);
        try {
            request->check_still_wanted();
            FrameClock clock{request->received, Clock::now(), {}, {}};
            auto result = std::make_shared<const RenderResult>(
                bounce::render_on_cpu(*snapshot, frame, order.plan, request->cancelled.get()));
            if (device) {
                planning::record_frame(*measurements, analysis ? &*analysis : nullptr, *device, *result, frame.width,
                                       frame.height);
            }
            if (order.output_size) {
                result = std::make_shared<const RenderResult>(
                    planning::upsampled(*result, order.output_size->first, order.output_size->second, frame));
            } else {
                comparisons->add(view, result, analysis ? &*analysis : nullptr, *measurements);
            }
            clock.rendered = Clock::now();
            deliver(request, order, std::move(result), version, clock);
        } catch (...) {
            request->fail(std::current_exception());
            return;
        }
        // The probes' companions, after the frame went out; like a probe, one that fails only teaches less.
        for (RenderRequest probe : order.reference_probes) {
            try {
                probe.camera = frame.camera;
                auto result = std::make_shared<const RenderResult>(
                    bounce::render_on_cpu(*snapshot, probe, plan_frame(probe), request->cancelled.get()));
                if (device) {
                    planning::record_frame(*measurements, analysis ? &*analysis : nullptr, *device, *result,
                                           probe.width, probe.height);
                }
                comparisons->add(view, result, analysis ? &*analysis : nullptr, *measurements);
            } catch (const std::exception& error) {
                log::warn("planner", "reference probe at {} bounces failed: {}", methods::knob_or(probe.knobs, "bounces", 0.0),
                          error.what());
            }
        }
    });
}

// The analysis traces rays and paths (tenths of a second on small scenes, more on large ones): on
// the CPU pool, from a snapshot, holding a CPU slot as a CPU frame does.
void RequestHandlers::describe_with_analysis(const std::shared_ptr<Request>& request, const SceneNameOrder& order,
                                            SceneRegistry& registry) {
    json description = describe_scene(registry, order);
    auto snapshot = std::make_shared<const scene::Scene>(*registry.get(order.name).scene);
    if (!daemon_.try_start_cpu_job()) {
        throw RequestError(ErrorCode::busy, fmt::format("{} CPU renders are already queued", Daemon::kMaxCpuJobs));
    }
    auto slot = std::make_shared<CpuSlot>(daemon_);
    boost::asio::post(daemon_.cpu_pool(), [request, snapshot, slot, description = std::move(description)]() mutable {
        const log::RequestScope scope(request->log_id);
        try {
            request->check_still_wanted();
            description["analysis"] = analysis_json(analyze_scene(*snapshot, {}, request->cancelled.get()));
            request->answer(protocol::make_ok(request->id(), std::move(description)));
        } catch (...) {
            request->fail(std::current_exception());
        }
    });
}

void RequestHandlers::deliver(const std::shared_ptr<Request>& request, const RenderOrder& order,
                              std::shared_ptr<const RenderResult> result, std::uint64_t scene_version, FrameClock clock) {
    boost::asio::post(daemon_.encode_pool(), [this, request, order, result = std::move(result), scene_version, clock]() mutable {
        const log::RequestScope scope(request->log_id);
        try {
            const auto format = image::parse_image_format(order.format);
            auto bytes = image::encode_image(result->frame, format, {order.jpeg_quality, order.exr_half});
            clock.encoded = Clock::now();
            json body = frame_json(*result, scene_version, image::image_format_name(format), clock);
            if (order.planned) body["plan"] = *order.planned;
            daemon_.metrics().count_frame(order.request.method, ms_between(clock.started, clock.rendered) / 1000.0,
                                          ms_between(clock.received, clock.encoded) / 1000.0);
            request->answer({static_cast<std::uint16_t>(MessageType::frame), request->id(), std::move(body), std::move(bytes)});
        } catch (...) {
            request->fail(std::current_exception());
        }
    });
}

// Runs on the render thread: builds a method's precomputed structures for a preset and knobs,
// sending `progress` events (at most five a second, and the last) until the `ok` with its stats.
// A `cancel` of this request stops it between steps.
json RequestHandlers::bake(const std::shared_ptr<Request>& request, const BakeOrder& order, Renderer& renderer,
                           SceneRegistry& registry) {
    SceneEntry& entry = registry.get(order.frame.scene);
    // As a render's (execute()): the scene's first analysis off the render thread, a stale one renewed there.
    if (leaves_knobs_to_scene(order.frame.plan.knobs, order.frame.request.knobs) &&
        wait_for_analysis(entry.resources->analysis_if_made() ? nullptr : request, order.frame.scene, entry)) {
        return nullptr;
    }
    if (wait_for_pending_work(request, order.frame.scene, entry, order.frame.request, renderer)) return nullptr;
    const auto started = Clock::now();
    auto last_sent = started - std::chrono::seconds(1);
    const FrameStats stats =
        renderer.prepare(*entry.resources, order.frame.request, [&](double fraction, const std::string& stage) {
            if (request->is_cancelled()) return false;
            const auto now = Clock::now();
            if (now - last_sent >= std::chrono::milliseconds(200) || fraction >= 1.0) {
                request->send(protocol::make_message(MessageType::progress, request->id(),
                                                     {{"fraction", fraction}, {"stage", stage}}));
                last_sent = now;
            }
            return true;
        });
    daemon_.metrics().set_resident_bytes(order.frame.scene, stats.resident_bytes);
    json reply = stats_json(stats);
    reply["scene"] = order.frame.scene;
    reply["bake_ms"] = ms_between(started, Clock::now());
    return reply;
}

bool RequestHandlers::wait_for_pending_work(const std::shared_ptr<Request>& request, const std::string& scene_name,
                                            SceneEntry& entry, const RenderRequest& frame, Renderer& renderer) {
    auto work = renderer.pending_work(*entry.resources, frame);
    if (!work) return false;
    const std::uint64_t resources_id = entry.resources->id;
    const std::string key = fmt::format("{}/{}/{}", resources_id, frame.method, work->key);
    auto& shared = running_work_[key];
    const bool joined = shared != nullptr;
    if (!joined) shared = std::make_shared<SharedWork>();
    shared->add(request);
    if (joined) return true;

    boost::asio::post(daemon_.precompute_pool(), [this, shared, key, resources_id, scene_name, method = frame.method,
                                                  run = std::move(work->run)] {
        std::shared_ptr<methods::PrecomputeResult> result;
        std::exception_ptr failure;
        try {
            result = run([&](double fraction, const std::string& stage) { return shared->progress(fraction, stage); });
        } catch (...) {
            failure = std::current_exception();
        }
        const bool resumed = daemon_.render_service().resume(
            [this, shared, key, resources_id, scene_name, method, result, failure](Renderer& renderer, SceneRegistry& registry) {
                running_work_.erase(key);
                const auto waiters = shared->take();
                if (failure) {
                    for (const auto& waiter : waiters) {
                        try {
                            waiter->check_still_wanted();  // cancelled or timed out: say which
                            waiter->fail(failure);
                        } catch (...) {
                            waiter->fail(std::current_exception());
                        }
                    }
                    return;
                }
                const auto entry = registry.entries().find(scene_name);
                if (entry != registry.entries().end() && entry->second.resources->id == resources_id) {
                    renderer.install(*entry->second.resources, method, result);
                }
                // Each runs as if just dequeued: a scene unloaded or changed meanwhile is handled there.
                for (const auto& waiter : waiters) execute(waiter, renderer, registry);
            });
        if (!resumed) {
            for (const auto& waiter : shared->take()) {
                waiter->fail(std::make_exception_ptr(RequestError(ErrorCode::shutting_down, "the daemon is shutting down")));
            }
        }
    });
    return true;
}

void RequestHandlers::plan_budgeted(RenderOrder& order, Renderer& renderer, SceneRegistry& registry) {
    SceneEntry& entry = registry.get(order.scene);
    const planning::DeviceCosts& device = device_costs(renderer);
    RenderRequest& frame = order.request;
    const std::optional<std::string> method = frame.method == "auto" ? std::nullopt : std::optional(frame.method);
    // What each plan's frame would redo is judged from the view it renders (a camera moved redraws
    // the suns' view cascades).
    RenderRequest seen = frame;
    if (auto camera = view_camera(*entry.scene, order)) seen.camera = std::move(camera);
    const scene::Camera camera = entry.resources->view_of(seen).camera;
    planning::PlanningInputs inputs{entry.resources->analysis(), device, entry.resources->measurements.get(),
                                    frame.width, frame.height, method, resample_errors(order, renderer, entry),
                                    planning::changes_on(*entry.resources, camera)};
    // A plan whose frame the memory budget would refuse is ruled out, not sent to fail.
    inputs.memory = [&](const std::string& name, const std::string& preset, const methods::KnobValues& knobs, int width,
                        int height) {
        RenderRequest candidate = frame;
        candidate.method = name;
        candidate.preset = preset;
        candidate.knobs = knobs;
        candidate.width = width;
        candidate.height = height;
        return renderer.memory_refusal(*entry.resources, candidate);
    };
    inputs.priors = &daemon_.priors();
    const planning::Plan plan = planning::plan(inputs, *order.budget);
    frame.method = plan.chosen.method;
    frame.preset = plan.chosen.preset;
    frame.knobs = plan.chosen.knobs;
    if (plan.chosen.scale != 1.0) {
        order.output_size = {frame.width, frame.height};
        std::tie(frame.width, frame.height) = planning::scaled_size(frame.width, frame.height, plan.chosen.scale);
    }
    order.plan = plan_frame(frame);
    order.planned = planning::plan_json(plan);
    if (plan.spot_check) {
        order.spot_check = plan.spot_check;
        order.checks_target = order.budget->max_error.value_or(0.0);
        for (const planning::Candidate& check : plan.checks) {
            RenderRequest check_frame = frame;
            check_frame.method = check.method;
            check_frame.preset = check.preset;
            check_frame.knobs = check.knobs;
            order.checks.push_back(std::move(check_frame));
        }
    }
    for (const planning::Candidate& probe : plan.probes) {
        RenderRequest probe_frame = frame;
        probe_frame.method = probe.method;
        probe_frame.preset = probe.preset;
        probe_frame.knobs = probe.knobs;
        probe_frame.make_display_image = false;
        (probe.method == "reference" ? order.reference_probes : order.probes).push_back(std::move(probe_frame));
    }
}

// Measured once per scene, frame size (capped: planning::measured_size) and method, on the first
// budgeted view at that size where the method's draft structures are built (a measurement never
// waits for a bake): three draft frames, milliseconds on a GPU. A method without a measurement is
// planned at full size only, and measured on a later view once built. Methods measured are not
// measured again: their draft frames would leave each method's structures at draft, and the
// planned frame would then build its own anew (frame_change.hpp).
planning::ResampleErrors RequestHandlers::resample_errors(const RenderOrder& order, Renderer& renderer, SceneEntry& entry) {
    RenderRequest view = order.request;
    if (auto camera = view_camera(*entry.scene, order)) view.camera = std::move(camera);
    std::tie(view.width, view.height) = planning::measured_size(view.width, view.height);
    Hasher key;
    key.add(view.width).add(view.height);
    if (!entry.resampling || entry.resampling->key != key.value()) entry.resampling = SceneEntry::Resampling{key.value(), {}};
    planning::ResampleErrors& known = entry.resampling->errors;
    std::vector<std::string> ready;
    for (const std::string& method : methods::MethodRegistry::builtin().names()) {
        if (methods::MethodRegistry::builtin().find(method).device != methods::MethodDevice::gpu) continue;
        if (entry.resampling->measured.contains(method)) continue;
        RenderRequest draft = view;
        draft.method = method;
        draft.preset = "draft";
        draft.knobs.clear();
        if (!renderer.pending_work(*entry.resources, draft)) ready.push_back(method);
    }
    if (ready.empty()) return known;
    try {
        planning::ResampleErrors errors = planning::measure_resample_errors(
            renderer, *entry.resources, view, ready, entry.resources->measurements.get(), known_device_costs(renderer));
        for (auto& [method, scales] : errors) known[method] = std::move(scales);
        entry.resampling->measured.insert(ready.begin(), ready.end());  // frames too small to scale have none
        return known;
    } catch (const std::exception& error) {
        log::warn("planner", "no smaller frames planned: measuring what upsampling loses failed: {}", error.what());
        return known;
    }
}

void RequestHandlers::check_before_reference(const std::shared_ptr<Request>& request, const RenderOrder& order,
                                             Renderer& renderer, SceneRegistry& registry) {
    const SceneEntry& entry = registry.get(order.scene);
    check_scene_version(entry, order);
    if (!daemon_.try_start_cpu_job()) {
        // The reference plan answers busy as it would have; a check is not worth a queue of its own.
        render_on_cpu(request, order, renderer, registry);
        return;
    }
    auto slot = std::make_shared<CpuSlot>(daemon_);
    auto snapshot = std::make_shared<const scene::Scene>(*entry.scene);
    RenderRequest view = order.request;
    if (auto camera = view_camera(*snapshot, order)) view.camera = std::move(camera);
    const std::uint64_t version = entry.version;
    boost::asio::post(daemon_.cpu_pool(), [this, request, order, view, snapshot, version, slot]() mutable {
        const log::RequestScope scope(request->log_id);
        std::shared_ptr<const planning::SpotReference> spot;
        try {
            request->check_still_wanted();
            spot = std::make_shared<const planning::SpotReference>(
                planning::trace_spot_reference(*snapshot, view, *order.spot_check, request->cancelled.get()));
        } catch (const std::exception& error) {
            // Cancelled, or past its timeout: the request ends. Anything else: the check only saves
            // time, and without it the reference plan stands.
            if (dynamic_cast<const RequestError*>(&error) || dynamic_cast<const Cancelled*>(&error)) {
                request->fail(std::current_exception());
                return;
            }
            log::warn("planner", "spot check failed, rendering the reference plan: {}", error.what());
        }
        slot.reset();  // before the render thread may ask for a slot of its own
        const bool resumed = daemon_.render_service().resume([this, request, order = std::move(order), spot, version](
                                                                  Renderer& renderer, SceneRegistry& registry) mutable {
            const log::RequestScope inner(request->log_id);
            try {
                try_checked_plans(request, std::move(order), spot, version, renderer, registry);
            } catch (...) {
                request->fail(std::current_exception());
            }
        });
        if (!resumed) {
            request->fail(std::make_exception_ptr(RequestError(ErrorCode::shutting_down, "the daemon is shutting down")));
        }
    });
}

// On the render thread. Each checked plan whose structures are built (a check never waits for a
// bake) is rendered, recorded and compared with the check's reference; the first that passes is
// sent, its plan in the reply's `plan` with what the check read. None passing (or a scene changed
// since the check was traced), the reference plan is rendered, and the frames tried are compared
// with it as probes are.
void RequestHandlers::try_checked_plans(const std::shared_ptr<Request>& request, RenderOrder order,
                                        const std::shared_ptr<const planning::SpotReference>& spot,
                                        std::uint64_t traced_version, Renderer& renderer, SceneRegistry& registry) {
    request->check_still_wanted();
    SceneEntry& entry = registry.get(order.scene);
    check_scene_version(entry, order);
    json tried = json::array();
    if (spot && entry.version == traced_version) {
        const planning::DeviceCosts* device = known_device_costs(renderer);
        const SceneAnalysis* analysis = entry.resources->analysis_if_made();
        for (RenderRequest frame : order.checks) {
            FrameClock clock{request->received, Clock::now(), {}, {}};
            if (auto camera = view_camera(*entry.scene, order)) frame.camera = std::move(camera);
            // Planned within the memory budget, but other scenes may have grown since: such a check is
            // skipped, as one whose structures are not built, and the reference stands.
            if (renderer.memory_refusal(*entry.resources, frame)) continue;
            if (renderer.pending_work(*entry.resources, frame)) continue;
            if (analysis && planning::ruled_out_by_measurements(*entry.resources->measurements, *analysis, frame.method,
                                                                frame.preset, frame.knobs, order.checks_target)) {
                continue;
            }
            auto result = std::make_shared<const RenderResult>(renderer.render(*entry.resources, frame, request->cancelled.get()));
            if (device) {
                planning::record_frame(*entry.resources->measurements, analysis, *device, result->stats, frame.width,
                                       frame.height);
            }
            entry.comparisons->add(view_key(entry.version, frame), result, analysis, *entry.resources->measurements);
            const planning::SpotEstimate estimate =
                planning::estimate(result->frame, spot->estimates, order.spot_check->stopped_error);
            if (analysis) {
                planning::record_spot_check(*entry.resources->measurements, analysis->bounces.stopped_error, frame.method,
                                            frame.preset, frame.knobs, *order.spot_check, estimate,
                                            view_key(entry.version, frame));
            }
            const bool passes = estimate.passes(order.checks_target);
            tried.push_back({{"method", frame.method},
                             {"preset", frame.preset},
                             {"knobs", frame.knobs},
                             {"render_ms", result->stats.render_ms},
                             {"rel_mse", estimate.rel_mse},
                             {"standard_error", estimate.standard_error},
                             {"noise", estimate.noise},
                             {"bound", estimate.bound},
                             {"passed", passes}});
            log::info("planner", "{} {}: {}", frame.method, frame.preset, planning::describe(*order.spot_check, estimate));
            if (!passes) continue;
            clock.rendered = Clock::now();
            if (order.planned) {
                json& plan = *order.planned;
                plan["method"] = frame.method;
                plan["preset"] = frame.preset;
                plan["knobs"] = frame.knobs;
                plan["predicted_error"] = estimate.bound;
                plan["promised_error"] = estimate.bound;
                plan["meets_budget"] = true;
                plan["spot_check"] = {{"pixels", estimate.pixels},
                                      {"spp", spot->estimates.samples},
                                      {"bounces", order.spot_check->bounces},
                                      {"trace_ms", spot->ms},
                                      {"tried", tried}};
                plan["why"] = plan["why"].get<std::string>() +
                              fmt::format("; sent {} {}: {}", frame.method, frame.preset,
                                          planning::describe(*order.spot_check, estimate));
            }
            order.request = frame;
            daemon_.metrics().set_resident_bytes(order.scene, result->stats.resident_bytes);
            deliver(request, order, std::move(result), entry.version, clock);
            return;
        }
    }
    if (order.planned) {
        (*order.planned)["spot_check"] = {{"spp", spot ? spot->estimates.samples : order.spot_check->spp},
                                          {"bounces", order.spot_check->bounces},
                                          {"trace_ms", spot ? spot->ms : 0.0},
                                          {"tried", tried}};
    }
    render_on_cpu(request, order, renderer, registry);
    render_probes(order, renderer, registry);
}

void RequestHandlers::render_probes(const RenderOrder& order, Renderer& renderer, SceneRegistry& registry) {
    if (order.probes.empty()) return;
    SceneEntry& entry = registry.get(order.scene);
    const planning::DeviceCosts* device = known_device_costs(renderer);
    for (RenderRequest probe : order.probes) {
        try {
            if (auto camera = view_camera(*entry.scene, order)) probe.camera = std::move(camera);
            if (renderer.pending_work(*entry.resources, probe)) continue;
            auto result = std::make_shared<const RenderResult>(renderer.render(*entry.resources, probe));
            if (device) {
                planning::record_frame(*entry.resources->measurements, entry.resources->analysis_if_made(), *device,
                                       result->stats, probe.width, probe.height);
            }
            entry.comparisons->add(view_key(entry.version, probe), result, entry.resources->analysis_if_made(),
                                   *entry.resources->measurements);
            // A probe with a companion is measured when the companion is traced, after this: counted as
            // compared now, so that a budget in between does not probe it again.
            const int bounces = planning::modelled_bounces(probe.method, probe.knobs);
            if (std::any_of(order.reference_probes.begin(), order.reference_probes.end(), [&](const RenderRequest& reference) {
                    return planning::modelled_bounces(reference.method, reference.knobs) == bounces;
                })) {
                entry.resources->measurements->record_compared(probe.method, probe.preset, bounces);
            }
        } catch (const std::exception& error) {
            // A probe only teaches the planner: its failure is logged, and the request it rode on stands.
            log::warn("planner", "probe {} {} failed: {}", probe.method, probe.preset, error.what());
        }
    }
}

bool RequestHandlers::wait_for_analysis(const std::shared_ptr<Request>& request, const std::string& scene_name,
                                        SceneEntry& entry) {
    if (entry.resources->analysis_current()) return false;
    const std::uint64_t resources_id = entry.resources->id;
    const std::string key = fmt::format("{}/analysis", resources_id);
    if (const auto running = running_work_.find(key); running != running_work_.end()) {
        if (!request) return false;
        running->second->add(request);
        return true;
    }
    // Every CPU slot taken: analysed here, on the render thread, as a frame that needs it would be.
    if (!daemon_.try_start_cpu_job()) return false;
    auto slot = std::make_shared<CpuSlot>(daemon_);
    auto shared = std::make_shared<SharedWork>();
    if (request) shared->add(request);
    running_work_[key] = shared;
    auto snapshot = std::make_shared<const scene::Scene>(*entry.scene);
    boost::asio::post(daemon_.cpu_pool(), [this, shared, key, resources_id, scene_name, snapshot, slot] {
        std::optional<SceneAnalysis> analysis;
        std::exception_ptr failure;
        try {
            analysis = analyze_scene(*snapshot);
        } catch (...) {
            failure = std::current_exception();
        }
        const std::uint64_t lights = lights_fingerprint(*snapshot);
        const bool resumed = daemon_.render_service().resume(
            [this, shared, key, resources_id, scene_name, lights, analysis = std::move(analysis), failure](
                Renderer& renderer, SceneRegistry& registry) mutable {
                running_work_.erase(key);
                const auto waiters = shared->take();
                if (failure) {
                    for (const auto& waiter : waiters) waiter->fail(failure);
                    return;
                }
                const auto entry = registry.entries().find(scene_name);
                if (entry != registry.entries().end() && entry->second.resources->id == resources_id) {
                    entry->second.resources->install_analysis(std::move(*analysis), lights);
                }
                // Each runs as if just dequeued: lights changed meanwhile start another analysis.
                for (const auto& waiter : waiters) execute(waiter, renderer, registry);
            });
        if (!resumed) {
            for (const auto& waiter : shared->take()) {
                waiter->fail(std::make_exception_ptr(RequestError(ErrorCode::shutting_down, "the daemon is shutting down")));
            }
        }
    });
    return request != nullptr;
}

void RequestHandlers::wait_for_calibration(const std::shared_ptr<Request>& request, Renderer& renderer) {
    if (!calibration_) {
        planning::CalibrationSettings settings;
        settings.large_size = daemon_.config().calibration_size;
        settings.small_size = std::max(1, settings.large_size / 2);
        settings.change_frames = daemon_.config().calibration_change_frames;
        log::info("planner", "calibrating the cost model for '{}' on the Cornell box, a preset at a time",
                  renderer.gpu_info().renderer);
        calibration_ = std::make_unique<planning::Calibration>(renderer, settings);
        if (!daemon_.render_service().post([this](Renderer& r, SceneRegistry& registry) { calibration_step(r, registry); })) {
            calibration_.reset();
            throw RequestError(ErrorCode::shutting_down, "the daemon is shutting down");
        }
    }
    calibration_waiters_.push_back(request);
    request->send(protocol::make_message(MessageType::progress, request->id(),
                                         {{"fraction", calibration_->fraction()},
                                          {"stage", "calibrating the device's costs: " + calibration_->next_step()}}));
}

// One step, then the next queued behind whatever came meanwhile: other clients' frames are served
// between the presets (seconds each at most), not after the whole calibration.
void RequestHandlers::calibration_step(Renderer& renderer, SceneRegistry& registry) {
    std::vector<std::shared_ptr<Request>> waiters;
    try {
        if (!calibration_->step(renderer)) {
            for (const auto& waiter : calibration_waiters_) {
                waiter->send(protocol::make_message(
                    MessageType::progress, waiter->id(),
                    {{"fraction", calibration_->fraction()},
                     {"stage", "calibrating the device's costs: " + calibration_->next_step()}}));
            }
            if (daemon_.render_service().post([this](Renderer& r, SceneRegistry& g) { calibration_step(r, g); })) return;
            throw RequestError(ErrorCode::shutting_down, "the daemon is shutting down");
        }
        device_costs_ = calibration_->result();
        log::info("planner", "calibrated in {:.0f} ms of steps", device_costs_->calibration_ms);
        if (const auto& cache_dir = daemon_.config().cache_dir) {
            try {
                device_costs_->save(planning::DeviceCosts::cache_path(*cache_dir, device_costs_->renderer()));
            } catch (const std::exception& error) {
                log::warn("planner", "the cost model stays in memory only: {}", error.what());
            }
        }
        calibration_.reset();
        waiters.swap(calibration_waiters_);
    } catch (...) {
        // A failed calibration fails its waiters; the next budget starts one afresh.
        calibration_.reset();
        waiters.swap(calibration_waiters_);
        for (const auto& waiter : waiters) waiter->fail(std::current_exception());
        return;
    }
    for (const auto& waiter : waiters) execute(waiter, renderer, registry);  // each as if just dequeued
}

const planning::DeviceCosts& RequestHandlers::device_costs(Renderer& renderer) {
    if (const planning::DeviceCosts* known = known_device_costs(renderer)) return *known;
    device_costs_ = planning::load_or_calibrate(renderer, daemon_.config().cache_dir);
    return *device_costs_;
}

const planning::DeviceCosts* RequestHandlers::known_device_costs(Renderer& renderer) {
    if (!device_costs_ && !looked_for_cached_costs_ && daemon_.config().cache_dir) {
        looked_for_cached_costs_ = true;
        const std::string& name = renderer.gpu_info().renderer;
        device_costs_ = planning::DeviceCosts::load(planning::DeviceCosts::cache_path(*daemon_.config().cache_dir, name), name);
    }
    return device_costs_ ? &*device_costs_ : nullptr;
}

json RequestHandlers::stats(Renderer& renderer, SceneRegistry& registry) {
    json errors = json::object();
    for (const auto& [code, count] : daemon_.metrics().errors()) errors[code] = count;
    json reply = list_scenes(registry);
    reply["frames"] = daemon_.metrics().frames();
    reply["errors"] = errors;
    reply["queue_depth"] = daemon_.render_service().queue_depth();
    reply["renderer"] = renderer.gpu_info().renderer;
    reply["streams"] = daemon_.streams().stats();
    // The device's cost model for budgets: read or measured, being measured, or not yet asked for.
    reply["planner"] = device_costs_  ? json{{"cost_model", "ready"}}
                       : calibration_ ? json{{"cost_model", "calibrating"}, {"calibrated_fraction", calibration_->fraction()}}
                                      : json{{"cost_model", "none"}};
    reply["planner"]["priors"] = daemon_.priors().description();
    reply["gpu_memory"] = {{"budget_bytes", renderer.memory_budget().bytes},
                           {"budget_source", renderer.memory_budget().source},
                           {"resident_bytes", renderer.resident_bytes()}};
    return reply;
}

}  // namespace bounce::server
