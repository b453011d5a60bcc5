#include "renderer/gpu/egl_device.hpp"

#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/gpu/gl.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <charconv>
#include <cstdlib>
#include <map>
#include <mutex>

namespace bounce::gpu {
namespace {

// EGL hands every context on a device the same display, and eglTerminate on it ends them all: each
// context holds a reference, and the last one terminates the display.
class DisplayReferences {
public:
    static void acquire(EGLDisplay display) {
        const std::lock_guard lock(mutex());
        ++counts()[display];
    }
    // Whether the caller held the last reference.
    static bool release(EGLDisplay display) {
        const std::lock_guard lock(mutex());
        auto& held = counts();
        const auto it = held.find(display);
        if (it == held.end() || --it->second > 0) return false;
        held.erase(it);
        return true;
    }

private:
    static std::mutex& mutex() {
        static std::mutex m;
        return m;
    }
    static std::map<EGLDisplay, int>& counts() {
        static std::map<EGLDisplay, int> c;
        return c;
    }
};

struct EglExtensions {
    PFNEGLQUERYDEVICESEXTPROC query_devices = nullptr;
    PFNEGLQUERYDEVICESTRINGEXTPROC query_device_string = nullptr;
    PFNEGLGETPLATFORMDISPLAYEXTPROC get_platform_display = nullptr;

    static const EglExtensions& get() {
        static const EglExtensions extensions = [] {
            EglExtensions e;
            e.query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
            e.query_device_string =
                reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(eglGetProcAddress("eglQueryDeviceStringEXT"));
            e.get_platform_display =
                reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
            return e;
        }();
        return extensions;
    }
};

std::string egl_error_name(EGLint error) {
    switch (error) {
        case EGL_SUCCESS: return "EGL_SUCCESS";
        case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
        case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
        case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
        case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
        case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
        case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
        case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
        case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
        case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
        default: return fmt::format("EGL error 0x{:x}", error);
    }
}

std::vector<EGLDeviceEXT> query_devices() {
    const auto& egl = EglExtensions::get();
    if (!egl.query_devices || !egl.query_device_string || !egl.get_platform_display) {
        BOUNCE_FAIL("EGL lacks EGL_EXT_device_enumeration/EGL_EXT_platform_device; is libEGL (glvnd) "
                    "with a vendor library (Mesa's libegl-mesa0 or NVIDIA's) installed?");
    }
    EGLint count = 0;
    if (!egl.query_devices(0, nullptr, &count) || count <= 0) {
        BOUNCE_FAIL("eglQueryDevicesEXT found no EGL device ({})", egl_error_name(eglGetError()));
    }
    std::vector<EGLDeviceEXT> devices(static_cast<std::size_t>(count));
    egl.query_devices(count, devices.data(), &count);
    devices.resize(static_cast<std::size_t>(count));
    return devices;
}

EglDeviceInfo describe(EGLDeviceEXT device, int index) {
    const auto& egl = EglExtensions::get();
    EglDeviceInfo info;
    info.index = index;
    const char* extensions = egl.query_device_string(device, EGL_EXTENSIONS);
    info.extensions = extensions ? extensions : "";
    info.software = info.extensions.find("EGL_MESA_device_software") != std::string::npos;
    if (info.extensions.find("EGL_EXT_device_drm") != std::string::npos) {
        const char* node = egl.query_device_string(device, EGL_DRM_DEVICE_FILE_EXT);
        if (node) info.drm_node = node;
    }
    return info;
}

std::string describe_all(const std::vector<EglDeviceInfo>& devices) {
    std::string text;
    for (const auto& d : devices) {
        text += fmt::format("{}[{}] {}{}", text.empty() ? "" : "; ", d.index, d.software ? "software" : "hardware",
                            d.drm_node.empty() ? "" : " " + d.drm_node);
    }
    return text.empty() ? "none" : text;
}

int pick_device(const DeviceChoice& choice, const std::vector<EglDeviceInfo>& devices) {
    switch (choice.kind) {
        case DeviceChoice::Kind::index:
            if (choice.index < 0 || choice.index >= static_cast<int>(devices.size())) {
                BOUNCE_FAIL("--device {} is out of range: found {}", choice.index, describe_all(devices));
            }
            return choice.index;
        case DeviceChoice::Kind::software:
            for (const auto& d : devices)
                if (d.software) return d.index;
            BOUNCE_FAIL("--device software: no Mesa software EGL device (install libegl-mesa0 and "
                        "libgl1-mesa-dri); found {}", describe_all(devices));
        case DeviceChoice::Kind::hardware:
            for (const auto& d : devices)
                if (!d.software) return d.index;
            BOUNCE_FAIL("--device hardware: no hardware EGL device (for NVIDIA: the driver's libEGL_nvidia.so.0 "
                        "and glvnd's 10_nvidia.json; in a container, NVIDIA_DRIVER_CAPABILITIES with graphics); "
                        "found {}", describe_all(devices));
        case DeviceChoice::Kind::automatic:
            for (const auto& d : devices)
                if (!d.software) return d.index;
            for (const auto& d : devices)
                if (d.software) return d.index;
            return 0;
    }
    return 0;
}

#ifdef BOUNCE_GL_DEBUG
void APIENTRY debug_message(GLenum, GLenum type, GLuint id, GLenum severity, GLsizei, const GLchar* message,
                              const void*) {
    if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) return;
    const bool serious = type == GL_DEBUG_TYPE_ERROR || severity == GL_DEBUG_SEVERITY_HIGH;
    if (serious) {
        log::error("gl", "id={} {}", id, message);
    } else {
        log::debug("gl", "id={} {}", id, message);
    }
}
#endif

std::string gl_string(GLenum name) {
    const auto* text = reinterpret_cast<const char*>(glGetString(name));
    return text ? text : "";
}

}  // namespace

DeviceChoice DeviceChoice::parse(std::string_view text) {
    if (text == "auto") return {};
    if (text == "software") return {Kind::software, -1};
    if (text == "hardware") return {Kind::hardware, -1};
    int index = -1;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), index);
    if (error != std::errc() || end != text.data() + text.size() || index < 0) {
        throw InputError(fmt::format("invalid device '{}': expected auto, software, hardware or a device index", text));
    }
    return {Kind::index, index};
}

DeviceChoice DeviceChoice::resolve(const std::optional<std::string>& flag) {
    if (flag) return parse(*flag);
    if (const char* env = std::getenv("BOUNCE_DEVICE"); env && *env) return parse(env);
    return {};
}

std::string DeviceChoice::to_string() const {
    switch (kind) {
        case Kind::automatic: return "auto";
        case Kind::software: return "software";
        case Kind::hardware: return "hardware";
        case Kind::index: return std::to_string(index);
    }
    return "auto";
}

std::string GpuInfo::summary() const {
    return fmt::format("{} ({}), OpenGL {}, EGL device {} of {} ({})", renderer, vendor, version, device_index,
                       devices_found.size(), software ? "software" : "hardware");
}

std::vector<EglDeviceInfo> enumerate_egl_devices() {
    const auto devices = query_devices();
    std::vector<EglDeviceInfo> infos;
    for (std::size_t i = 0; i < devices.size(); ++i) infos.push_back(describe(devices[i], static_cast<int>(i)));
    return infos;
}

std::unique_ptr<EglContext> EglContext::create(const DeviceChoice& choice) {
    const auto& egl = EglExtensions::get();
    const auto devices = query_devices();
    std::vector<EglDeviceInfo> infos;
    for (std::size_t i = 0; i < devices.size(); ++i) infos.push_back(describe(devices[i], static_cast<int>(i)));
    const int index = pick_device(choice, infos);

    std::unique_ptr<EglContext> context(new EglContext());
    EGLDisplay display = egl.get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[index], nullptr);
    if (display == EGL_NO_DISPLAY) {
        BOUNCE_FAIL("eglGetPlatformDisplayEXT failed for device {} ({})", index, egl_error_name(eglGetError()));
    }
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor)) {
        BOUNCE_FAIL("eglInitialize failed for device {} ({}); devices: {}", index, egl_error_name(eglGetError()),
                    describe_all(infos));
    }
    context->display_ = display;
    DisplayReferences::acquire(display);
    const std::string display_extensions = eglQueryString(display, EGL_EXTENSIONS);
    for (const char* required : {"EGL_KHR_surfaceless_context", "EGL_KHR_create_context"}) {
        if (display_extensions.find(required) == std::string::npos) {
            BOUNCE_FAIL("EGL device {} lacks {} (EGL {}.{}): headless rendering needs it", index, required, major,
                        minor);
        }
    }
    if (!eglBindAPI(EGL_OPENGL_API)) BOUNCE_FAIL("eglBindAPI(EGL_OPENGL_API) failed: {}", egl_error_name(eglGetError()));

    EGLConfig config = EGL_NO_CONFIG_KHR;
    if (display_extensions.find("EGL_KHR_no_config_context") == std::string::npos) {
        // Drivers without configless contexts still need some config; we never use its surface.
        const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, EGL_PBUFFER_BIT,
                                            EGL_NONE};
        EGLint found = 0;
        if (!eglChooseConfig(display, config_attributes, &config, 1, &found) || found == 0) {
            BOUNCE_FAIL("EGL device {} offers no OpenGL config", index);
        }
    }
    const EGLint context_attributes[] = {
        EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
        EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
#ifdef BOUNCE_GL_DEBUG
        EGL_CONTEXT_OPENGL_DEBUG, EGL_TRUE,
#endif
        EGL_NONE};
    EGLContext gl_context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attributes);
    if (gl_context == EGL_NO_CONTEXT) {
        BOUNCE_FAIL("EGL device {} cannot create an OpenGL 4.5 core context ({}); EGL {}.{}, devices: {}", index,
                    egl_error_name(eglGetError()), major, minor, describe_all(infos));
    }
    context->context_ = gl_context;
    context->make_current();

    GpuInfo& info = context->info_;
    info.vendor = gl_string(GL_VENDOR);
    info.renderer = gl_string(GL_RENDERER);
    info.version = gl_string(GL_VERSION);
    info.glsl_version = gl_string(GL_SHADING_LANGUAGE_VERSION);
    info.device_index = index;
    info.software = infos[index].software;
    info.devices_found = infos;
    GLint gl_major = 0, gl_minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &gl_major);
    glGetIntegerv(GL_MINOR_VERSION, &gl_minor);
    if (gl_major * 10 + gl_minor < 45) {
        BOUNCE_FAIL("device {} gave OpenGL {}.{} ({}), Bounce needs 4.5 core", index, gl_major, gl_minor, info.renderer);
    }
#ifdef BOUNCE_GL_DEBUG
    glEnable(GL_DEBUG_OUTPUT);
    glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
    glDebugMessageCallback(debug_message, nullptr);
#endif
    log::info("egl", "device={} choice={} renderer=\"{}\" vendor=\"{}\" version=\"{}\" devices=\"{}\"", index,
              choice.to_string(), info.renderer, info.vendor, info.version, describe_all(infos));
    return context;
}

void EglContext::make_current() {
    if (eglGetCurrentContext() == context_) return;
    if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
        BOUNCE_FAIL("eglMakeCurrent failed ({})", egl_error_name(eglGetError()));
    }
}

EglContext::~EglContext() {
    if (!display_) return;
    // Only this context is released: another one current on the thread stays current.
    if (context_ && eglGetCurrentContext() == context_) {
        eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
    if (context_) eglDestroyContext(display_, context_);
    if (DisplayReferences::release(display_)) eglTerminate(display_);
}

}  // namespace bounce::gpu
