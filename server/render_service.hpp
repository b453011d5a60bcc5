// The render thread: it alone owns the GL context (through Renderer) and the scene registry, and
// runs jobs from a bounded queue in arrival order. Network threads only submit jobs.
#pragma once

#include "renderer/renderer.hpp"
#include "server/scene_registry.hpp"

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <mutex>
#include <thread>

namespace bounce::server {

class RenderService {
public:
    using Job = std::function<void(Renderer&, SceneRegistry&)>;

    // Starts the thread and creates the GL context on it; throws what context creation threw.
    RenderService(const gpu::DeviceChoice& device, std::size_t queue_capacity);
    ~RenderService();  // stop()
    RenderService(const RenderService&) = delete;
    RenderService& operator=(const RenderService&) = delete;

    // Queues a job; false when the queue is full (the caller answers `busy`) or stopping.
    bool submit(Job job);
    // Queues a job at the back past the capacity: work whose count is bounded elsewhere (a preview
    // stream's tick: one per stream at most). False only when stopping.
    bool post(Job job);
    // Queues a job ahead of the others, past the capacity: the continuation of work already admitted
    // (a frame whose bake finished off the thread). False only when stopping.
    bool resume(Job job);
    // Runs a job and waits for it (startup work); rethrows what the job threw.
    void run_and_wait(const Job& job);
    // Finishes queued jobs, then ends the thread. Idempotent.
    void stop();

    std::size_t queue_depth() const;
    std::size_t queue_capacity() const { return capacity_; }
    const gpu::GpuInfo& gpu_info() const { return gpu_info_; }

private:
    void run(const gpu::DeviceChoice& device, std::promise<void>& ready);

    std::size_t capacity_;
    mutable std::mutex mutex_;
    std::condition_variable wake_;
    std::deque<Job> jobs_;
    bool stopping_ = false;
    gpu::GpuInfo gpu_info_;
    std::thread thread_;
};

}  // namespace bounce::server
