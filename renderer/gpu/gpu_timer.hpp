// GPU timer queries per pass. Timestamps are read back once per frame, after the frame's readback
// has synchronized anyway, so timing costs no extra stall.
#pragma once

#include "renderer/gpu/gl_objects.hpp"

#include <string>
#include <vector>

namespace bounce::gpu {

struct PassTiming {
    std::string pass;
    double gpu_ms = 0.0;
};

class GpuTimers {
public:
    // Starts timing `pass`; the scope ends it. Scopes must not overlap.
    class Scope {
    public:
        Scope(GpuTimers& timers, std::string pass);
        ~Scope();
        Scope(const Scope&) = delete;
        Scope& operator=(const Scope&) = delete;

    private:
        GpuTimers& timers_;
    };

    void begin_frame();
    // Waits for the results and returns the frame's passes in order (the same name sums up).
    std::vector<PassTiming> resolve();

private:
    struct Interval {
        std::string pass;
        std::size_t begin = 0;
        std::size_t end = 0;
    };
    std::size_t timestamp();
    std::vector<Query> pool_;
    std::size_t used_ = 0;
    std::vector<Interval> intervals_;
};

}  // namespace bounce::gpu
