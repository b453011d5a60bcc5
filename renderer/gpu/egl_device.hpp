// Headless EGL: device enumeration, a surfaceless OpenGL 4.5 core context, no display.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace bounce::gpu {

// Which EGL device to use: `auto` prefers a hardware device and falls back to Mesa's software
// device; `software` demands the software device; an index picks one device from the enumeration.
struct DeviceChoice {
    // hardware: the first device that is not a software rasterizer, or fail (a GPU node whose
    // driver libraries are missing must not quietly serve from llvmpipe).
    enum class Kind { automatic, software, hardware, index };
    Kind kind = Kind::automatic;
    int index = -1;

    // Parses "auto", "software", "hardware" or a device index; throws InputError otherwise.
    static DeviceChoice parse(std::string_view text);
    // The --device flag when given, else the BOUNCE_DEVICE environment variable, else auto.
    static DeviceChoice resolve(const std::optional<std::string>& flag);
    std::string to_string() const;
};

struct EglDeviceInfo {
    int index = 0;
    bool software = false;
    std::string extensions;
    std::string drm_node;  // empty when the device has none
};

struct GpuInfo {
    std::string vendor;
    std::string renderer;
    std::string version;
    std::string glsl_version;
    int device_index = 0;
    bool software = false;
    std::vector<EglDeviceInfo> devices_found;

    std::string summary() const;  // "renderer (vendor), OpenGL version, device N of M"
};

// Owns an OpenGL 4.5 core context on an EGL device's display, current on the thread that created it.
// Exactly one thread (the render thread) may create and use it. Several contexts may share one device:
// EGL gives them one display, which is terminated only when the last of them goes, and destroying one
// leaves another that is current on the thread current.
class EglContext {
public:
    // Throws Error naming the devices found and what they offered when no device fits or the
    // context cannot be made 4.5 core.
    static std::unique_ptr<EglContext> create(const DeviceChoice& choice);
    ~EglContext();
    EglContext(const EglContext&) = delete;
    EglContext& operator=(const EglContext&) = delete;

    const GpuInfo& info() const { return info_; }
    // Makes this context current on the calling thread, unless it already is: GL work that follows
    // another context's creation must bind its own first.
    void make_current();

private:
    EglContext() = default;
    void* display_ = nullptr;
    void* context_ = nullptr;
    GpuInfo info_;
};

// Lists the EGL devices without creating a context (for logs and `--device` help).
std::vector<EglDeviceInfo> enumerate_egl_devices();

}  // namespace bounce::gpu
