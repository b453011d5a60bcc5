#include "renderer/gpu/gpu_timer.hpp"

#include <algorithm>

namespace bounce::gpu {

GpuTimers::Scope::Scope(GpuTimers& timers, std::string pass) : timers_(timers) {
    const std::size_t begin = timers_.timestamp();
    timers_.intervals_.push_back({std::move(pass), begin, begin});
}

GpuTimers::Scope::~Scope() { timers_.intervals_.back().end = timers_.timestamp(); }

void GpuTimers::begin_frame() {
    used_ = 0;
    intervals_.clear();
}

std::size_t GpuTimers::timestamp() {
    if (used_ == pool_.size()) pool_.push_back(make_query(GL_TIMESTAMP));
    glQueryCounter(pool_[used_].id(), GL_TIMESTAMP);
    // Submit now: a driver that batches draws until a flush (llvmpipe among them) would otherwise
    // stamp the query when the batch runs, after compute work dispatched since, and charge that
    // work to the wrong pass.
    glFlush();
    return used_++;
}

std::vector<PassTiming> GpuTimers::resolve() {
    std::vector<PassTiming> timings;
    for (const Interval& interval : intervals_) {
        GLuint64 begin = 0, end = 0;
        glGetQueryObjectui64v(pool_[interval.begin].id(), GL_QUERY_RESULT, &begin);
        glGetQueryObjectui64v(pool_[interval.end].id(), GL_QUERY_RESULT, &end);
        const double ms = end > begin ? static_cast<double>(end - begin) * 1e-6 : 0.0;
        auto same = std::find_if(timings.begin(), timings.end(), [&](const PassTiming& t) { return t.pass == interval.pass; });
        if (same != timings.end()) {
            same->gpu_ms += ms;
        } else {
            timings.push_back({interval.pass, ms});
        }
    }
    intervals_.clear();
    used_ = 0;
    return timings;
}

}  // namespace bounce::gpu
