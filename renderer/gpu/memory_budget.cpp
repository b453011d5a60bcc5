#include "renderer/gpu/memory_budget.hpp"

#include "renderer/base/bytes.hpp"
#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/gpu/gl.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <fstream>

namespace bounce::gpu {
namespace {

// Extension enums (not in glcorearb.h): both report kilobytes.
constexpr GLenum kNvxDedicatedVidmem = 0x9047;  // GPU_MEMORY_INFO_DEDICATED_VIDMEM_NVX
constexpr GLenum kAtiTextureFreeMemory = 0x87FC;  // TEXTURE_FREE_MEMORY_ATI (4 values, the first: total free)

bool has_gl_extension(const char* name) {
    GLint count = 0;
    glGetIntegerv(GL_NUM_EXTENSIONS, &count);
    for (GLint i = 0; i < count; ++i) {
        const auto* extension = reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, static_cast<GLuint>(i)));
        if (extension && std::strcmp(extension, name) == 0) return true;
    }
    return false;
}

std::optional<std::uint64_t> cgroup_limit() {
    for (const char* path : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
        std::ifstream file(path);
        std::string text;
        if (!(file >> text) || text == "max") continue;
        try {
            return std::stoull(text);
        } catch (const std::exception&) {
            continue;
        }
    }
    return std::nullopt;
}

}  // namespace

std::optional<std::uint64_t> reported_device_memory() {
    GLint kilobytes[4] = {0, 0, 0, 0};
    if (has_gl_extension("GL_NVX_gpu_memory_info")) {
        glGetIntegerv(kNvxDedicatedVidmem, kilobytes);
    } else if (has_gl_extension("GL_ATI_meminfo")) {
        glGetIntegerv(kAtiTextureFreeMemory, kilobytes);
    }
    while (glGetError() != GL_NO_ERROR) {
    }
    if (kilobytes[0] <= 0) return std::nullopt;
    return static_cast<std::uint64_t>(kilobytes[0]) * 1024;
}

std::uint64_t host_memory() {
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
    std::uint64_t bytes = pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page) : 0;
    if (const auto limit = cgroup_limit(); limit && (bytes == 0 || *limit < bytes)) bytes = *limit;
    return bytes;
}

MemoryBudget default_memory_budget(const GpuInfo& info) {
    if (!info.software) {
        if (const auto device = reported_device_memory()) {
            return {*device / 10 * 9, fmt::format("90% of the {} of device memory the driver reports", bytes_text(*device))};
        }
    }
    const std::uint64_t host = host_memory();
    return {host / 2, fmt::format("half of the {} of host memory{}", bytes_text(host),
                                  info.software ? " (a software rasterizer allocates there)" : " (the driver reports none)")};
}

void check_out_of_memory(std::string_view work) {
    bool out_of_memory = false;
    for (GLenum error = glGetError(); error != GL_NO_ERROR; error = glGetError()) {
        if (error == GL_OUT_OF_MEMORY) {
            out_of_memory = true;
        } else {
            log::warn("gl", "GL error 0x{:04x} after {}", error, work);
        }
    }
    if (out_of_memory) throw ResourceExhausted(fmt::format("the GPU driver ran out of memory during {}", work));
}


}  // namespace bounce::gpu
