// How many bytes the renderer may keep resident, and the check that the driver had them.
//
// A GPU that reports its memory (NVIDIA's GL_NVX_gpu_memory_info, AMD's GL_ATI_meminfo) gives the
// default budget; a software rasterizer (llvmpipe) allocates from host memory, so there the default
// is a share of the host's memory, a container's limit included.
#pragma once

#include "renderer/gpu/egl_device.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace bounce::gpu {

struct MemoryBudget {
    std::uint64_t bytes = 0;  // 0: no budget
    std::string source;       // where the number came from, for logs and `stats`
};

// Dedicated video memory as the current context's driver reports it; nullopt where it does not.
std::optional<std::uint64_t> reported_device_memory();

// Physical memory, or the cgroup's memory limit when that is lower (containers).
std::uint64_t host_memory();

// The budget a daemon uses when none is given: 90% of the reported device memory, otherwise half
// of host_memory() (llvmpipe, and drivers that report nothing: the host must keep room for the
// daemon's own buffers, the CPU methods and the encoders).
MemoryBudget default_memory_budget(const GpuInfo& info);

// Drains the GL error queue; throws ResourceExhausted naming `work` when the driver reported
// GL_OUT_OF_MEMORY. Other errors are programming faults: logged, not thrown.
void check_out_of_memory(std::string_view work);

}  // namespace bounce::gpu
