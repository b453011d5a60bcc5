// bounced: the Bounce render daemon. Serves the protocol of docs/protocol.md; with --render-once
// it instead renders one frame of a scene to a file and exits (no network at all).
#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/codec.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene/builtin.hpp"
#include "renderer/scene/gltf_import.hpp"
#include "server/daemon.hpp"

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace {

struct Options {
    std::optional<std::string> device;
    std::string scene = "cornell";
    std::string method = "direct";
    std::string preset = "medium";
    bounce::methods::KnobValues knobs;
    int width = 512;
    int height = 512;
    float exposure = 0.0f;
    std::string tone = "aces";
    std::string render_once;
    bounce::server::DaemonConfig daemon;
};

constexpr const char* kUsage = R"(usage: bounced [daemon options]
       bounced --version
       bounced --render-once OUT.(png|jpg|exr) [render options]

Daemon options:
  --listen HOST:PORT        address to serve on (port 0: any free port)   [127.0.0.1:7878]
  --port-file F             write the bound port (and the ops port) to F once listening
  --scene-root DIR          scene.load paths resolve inside DIR             [loading by path is off]
  --cache-dir DIR           where baked structures are cached
  --token-file F            clients must send this token (required off loopback)
  --max-clients N           concurrent connections                          [64]
  --max-message-bytes N     largest frame a client may send                 [268435456]
  --max-pixels N            largest width*height a render may ask for       [16777216]
  --max-in-flight N         pending requests per connection                 [8]
  --queue N                 render jobs waiting across all clients          [64]
  --metrics-listen HOST:PORT  ops HTTP: /healthz /readyz /metrics           [off]
  --heartbeat-ms N          ping idle clients; drop them after 3 intervals  [15000]
  --max-inflight-bytes N    request bodies held across all clients          [1073741824]
  --max-scene-bytes N       a scene's decoded size (geometry and images)    [2147483648]
  --max-scenes N            scenes resident at once                         [64]
  --gpu-memory-budget N     what every scene's GPU structures may hold together; frames that
                            would pass it are refused (resource_exhausted)  [90% of the device's
                            memory, or half the host's for a software rasterizer]
  --max-unauthenticated N   connections yet to authenticate (with a token)  [16]
  --auth-timeout-ms N       time a connection has to authenticate           [10000]
  --drain-seconds N         on SIGTERM, finish in-flight work for at most N s, then cancel it;
                            a second signal exits at once                   [10]
  --device D                auto, software or an EGL device index           [auto, or $BOUNCE_DEVICE]
  --log-level L             debug, info, warn, error                        [info]
Byte counts (the -bytes flags, --gpu-memory-budget) take a K, M, G or T suffix (powers of 1024).

Render options (--render-once renders one frame and exits):
  --scene NAME|FILE     built-in scene name (cornell) or a .gltf/.glb file   [cornell]
  --method M            any method, reference included (direct)             [direct]
  --preset P            draft, low, medium, high, ultra                      [medium]
  --set KNOB=VALUE      override one knob of the method (repeatable)
  --size WxH            frame size                                           [512x512]
  --exposure EV         exposure in stops for PNG/JPEG                       [0]
  --tone CURVE          none, reinhard, aces                                 [aces]
  --device D            auto, software or an EGL device index                [auto, or $BOUNCE_DEVICE]
  --log-level L         debug, info, warn, error                             [info]
)";

[[noreturn]] void usage_error(const std::string& message) {
    std::fprintf(stderr, "bounced: %s\n\n%s", message.c_str(), kUsage);
    std::exit(2);
}

unsigned long long number(const std::string& flag, const std::string& text, unsigned long long min,
                          unsigned long long max) {
    try {
        std::size_t end = 0;
        const unsigned long long value = std::stoull(text, &end);
        if (end == text.size() && value >= min && value <= max) return value;
    } catch (const std::exception&) {
    }
    usage_error(flag + " expects a whole number in [" + std::to_string(min) + ", " + std::to_string(max) + "], got '" +
                text + "'");
}

// A byte count: a whole number with an optional binary suffix (K, M, G, T: 2^10 .. 2^40).
unsigned long long bytes(const std::string& flag, const std::string& text, unsigned long long min,
                         unsigned long long max) {
    static const std::string suffixes = "KMGT";
    const std::size_t suffix = text.empty() ? std::string::npos : suffixes.find(static_cast<char>(std::toupper(text.back())));
    if (suffix == std::string::npos) return number(flag, text, min, max);
    const unsigned shift = 10 * static_cast<unsigned>(suffix + 1);
    const unsigned long long scaled = number(flag, text.substr(0, text.size() - 1), 0, max >> shift) << shift;
    if (scaled < min) usage_error(flag + " must be at least " + std::to_string(min) + " bytes, got '" + text + "'");
    return scaled;
}

Options parse(int argc, char** argv) {
    Options options;
    std::vector<std::string> args(argv + 1, argv + argc);
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& flag = args[i];
        auto value = [&]() -> const std::string& {
            if (i + 1 >= args.size()) usage_error(flag + " needs a value");
            return args[++i];
        };
        if (flag == "--help" || flag == "-h") {
            std::fputs(kUsage, stdout);
            std::exit(0);
        } else if (flag == "--version") {
            std::printf("bounced %s\n", BOUNCE_VERSION);
            std::exit(0);
        } else if (flag == "--device") {
            options.device = value();
        } else if (flag == "--scene") {
            options.scene = value();
        } else if (flag == "--method") {
            options.method = value();
        } else if (flag == "--preset") {
            options.preset = value();
        } else if (flag == "--set") {
            const std::string& assignment = value();
            const auto equals = assignment.find('=');
            if (equals == std::string::npos) usage_error("--set expects KNOB=VALUE, got '" + assignment + "'");
            try {
                options.knobs[assignment.substr(0, equals)] = std::stod(assignment.substr(equals + 1));
            } catch (const std::exception&) {
                usage_error("--set " + assignment + ": the value is not a number");
            }
        } else if (flag == "--size") {
            const std::string& size = value();
            if (std::sscanf(size.c_str(), "%dx%d", &options.width, &options.height) != 2) {
                usage_error("--size expects WxH, got '" + size + "'");
            }
        } else if (flag == "--exposure") {
            try {
                options.exposure = std::stof(value());
            } catch (const std::exception&) {
                usage_error("--exposure expects a number");
            }
        } else if (flag == "--tone") {
            options.tone = value();
        } else if (flag == "--render-once") {
            options.render_once = value();
        } else if (flag == "--log-level") {
            bounce::log::set_level(bounce::log::parse_level(value()));
        } else if (flag == "--listen") {
            const std::string& listen = value();
            const auto colon = listen.rfind(':');
            if (colon == std::string::npos) usage_error("--listen expects HOST:PORT, got '" + listen + "'");
            options.daemon.listen_host = listen.substr(0, colon);
            options.daemon.listen_port = static_cast<std::uint16_t>(number(flag, listen.substr(colon + 1), 0, 65535));
        } else if (flag == "--port-file") {
            options.daemon.port_file = value();
        } else if (flag == "--scene-root") {
            options.daemon.scene_root = value();
        } else if (flag == "--cache-dir") {
            options.daemon.cache_dir = value();
        } else if (flag == "--token-file") {
            options.daemon.token_file = value();
        } else if (flag == "--max-clients") {
            options.daemon.max_clients = number(flag, value(), 1, 100000);
        } else if (flag == "--max-message-bytes") {
            options.daemon.max_message_bytes = bytes(flag, value(), 1024, 4294967295ull);
        } else if (flag == "--max-pixels") {
            options.daemon.max_pixels = number(flag, value(), 1, 268435456);
        } else if (flag == "--max-in-flight") {
            options.daemon.max_in_flight = number(flag, value(), 1, 1024);
        } else if (flag == "--queue") {
            options.daemon.queue_capacity = number(flag, value(), 1, 100000);
        } else if (flag == "--metrics-listen") {
            options.daemon.metrics_listen = value();
        } else if (flag == "--max-inflight-bytes") {
            options.daemon.max_inflight_bytes = bytes(flag, value(), 1u << 20, 1ull << 40);
        } else if (flag == "--gpu-memory-budget") {
            options.daemon.gpu_memory_budget = bytes(flag, value(), 1u << 20, 1ull << 50);
        } else if (flag == "--max-scene-bytes") {
            options.daemon.max_scene_bytes = bytes(flag, value(), 1024, 1ull << 40);
        } else if (flag == "--max-scenes") {
            options.daemon.max_scenes = number(flag, value(), 1, 100000);
        } else if (flag == "--max-unauthenticated") {
            options.daemon.max_unauthenticated = number(flag, value(), 1, 100000);
        } else if (flag == "--auth-timeout-ms") {
            options.daemon.auth_timeout = std::chrono::milliseconds(number(flag, value(), 10, 3600000));
        } else if (flag == "--drain-seconds") {
            options.daemon.drain_timeout = std::chrono::seconds(number(flag, value(), 0, 3600));
        } else if (flag == "--heartbeat-ms") {
            options.daemon.heartbeat = std::chrono::milliseconds(number(flag, value(), 10, 3600000));
        } else {
            usage_error("unknown flag '" + flag + "'");
        }
    }
    options.daemon.device = options.device;
    return options;
}

bounce::scene::Scene load_scene(const std::string& name) {
    const auto builtin = bounce::scene::builtin_scene_names();
    if (std::find(builtin.begin(), builtin.end(), name) != builtin.end()) return bounce::scene::make_builtin_scene(name);
    return bounce::scene::import_gltf_file(name);
}

int render_once(const Options& options) {
    const auto format = bounce::image::image_format_from_path(options.render_once);
    const bounce::scene::Scene scene = load_scene(options.scene);
    bounce::RenderRequest request;
    request.method = options.method;
    request.preset = options.preset;
    request.knobs = options.knobs;
    request.width = options.width;
    request.height = options.height;
    request.display = {options.exposure, bounce::image::parse_tone_curve(options.tone)};
    request.make_display_image = format != bounce::image::ImageFormat::exr;
    const bounce::FramePlan plan = bounce::plan_frame(request);

    bounce::RenderResult result;
    if (plan.site == bounce::FrameSite::cpu) {
        result = bounce::render_on_cpu(scene, request, plan);  // no GL context needed
    } else {
        bounce::Renderer renderer(bounce::gpu::DeviceChoice::resolve(options.device));
        auto resources = renderer.upload(scene);
        result = renderer.render(*resources, request);
    }
    const auto bytes = bounce::image::encode_image(result.frame, format);
    bounce::image::write_file_atomic(options.render_once, bytes);

    std::string passes;
    for (const auto& pass : result.stats.passes) passes += fmt::format(" {}={:.2f}ms", pass.pass, pass.gpu_ms);
    bounce::log::info("render", "wrote {} ({}x{}, {} bytes) method={} preset={} render={:.1f}ms gpu={:.2f}ms{} "
                      "resident={}B",
                      options.render_once, options.width, options.height, bytes.size(), request.method,
                      request.preset, result.stats.render_ms, result.stats.gpu_ms, passes, result.stats.resident_bytes);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const Options options = parse(argc, argv);
        if (!options.render_once.empty()) return render_once(options);
        bounce::server::Daemon daemon(options.daemon);
        return daemon.run();
    } catch (const bounce::InputError& error) {
        std::fprintf(stderr, "bounced: %s\n", error.what());
        return 2;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bounced: error: %s\n", error.what());
        return 1;
    }
}
