#include "server/render_service.hpp"

#include "renderer/base/log.hpp"

#include <future>

namespace bounce::server {

RenderService::RenderService(const gpu::DeviceChoice& device, std::size_t queue_capacity) : capacity_(queue_capacity) {
    std::promise<void> ready;
    auto started = ready.get_future();
    thread_ = std::thread([this, device, &ready] { run(device, ready); });
    try {
        started.get();
    } catch (...) {
        thread_.join();
        throw;
    }
}

RenderService::~RenderService() { stop(); }

void RenderService::run(const gpu::DeviceChoice& device, std::promise<void>& ready) {
    std::unique_ptr<Renderer> renderer;
    try {
        renderer = std::make_unique<Renderer>(device);
        gpu_info_ = renderer->gpu_info();
    } catch (...) {
        ready.set_exception(std::current_exception());
        return;
    }
    ready.set_value();  // `ready` dies with the constructor: not touched after this line
    SceneRegistry registry(*renderer);
    for (;;) {
        Job job;
        {
            std::unique_lock lock(mutex_);
            wake_.wait(lock, [&] { return stopping_ || !jobs_.empty(); });
            if (jobs_.empty()) break;  // stopping and drained
            job = std::move(jobs_.front());
            jobs_.pop_front();
        }
        try {
            job(*renderer, registry);
        } catch (const std::exception& error) {
            // Jobs answer their own errors; one that escapes must not end the render thread.
            log::error("render", "job failed: {}", error.what());
        }
    }
}

bool RenderService::submit(Job job) {
    {
        std::lock_guard lock(mutex_);
        if (stopping_ || jobs_.size() >= capacity_) return false;
        jobs_.push_back(std::move(job));
    }
    wake_.notify_one();
    return true;
}

bool RenderService::post(Job job) {
    {
        std::lock_guard lock(mutex_);
        if (stopping_) return false;
        jobs_.push_back(std::move(job));
    }
    wake_.notify_one();
    return true;
}

bool RenderService::resume(Job job) {
    {
        std::lock_guard lock(mutex_);
        if (stopping_) return false;
        jobs_.push_front(std::move(job));
    }
    wake_.notify_one();
    return true;
}

void RenderService::run_and_wait(const Job& job) {
    std::promise<void> done;
    auto future = done.get_future();
    {
        std::lock_guard lock(mutex_);
        jobs_.push_back([&](Renderer& renderer, SceneRegistry& registry) {
            try {
                job(renderer, registry);
                done.set_value();
            } catch (...) {
                done.set_exception(std::current_exception());
            }
        });
    }
    wake_.notify_one();
    future.get();
}

void RenderService::stop() {
    {
        std::lock_guard lock(mutex_);
        stopping_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
}

std::size_t RenderService::queue_depth() const {
    std::lock_guard lock(mutex_);
    return jobs_.size();
}

}  // namespace bounce::server
