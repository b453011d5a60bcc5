// bounced: the Bounce render daemon. Serves the protocol of docs/protocol.md; with --render-once
// it instead renders one frame of a scene to a file and exits (no network at all).
#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/codec.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene/builtin.hpp"
#include "renderer/scene/gltf_import.hpp"
#include "server/daemon.hpp"

#include <CLI/CLI.hpp>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
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

[[noreturn]] void usage_error(const std::string& message) {
    std::fprintf(stderr, "bounced: %s\nRun with --help for more information.\n", message.c_str());
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

// The daemon's limits, read as text and checked after parsing so that each refusal names the flag,
// its range and the value given (and byte counts take their suffixes).
struct Limit {
    const char* flag;
    const char* help;
    unsigned long long min, max;
    bool is_bytes;
    std::function<void(unsigned long long, bounce::server::DaemonConfig&)> apply;
    std::string text{};
};

std::vector<Limit> daemon_limits() {
    using Config = bounce::server::DaemonConfig;
    using std::chrono::milliseconds;
    return {
        {"--max-clients", "concurrent connections [64]", 1, 100000, false,
         [](auto v, Config& c) { c.max_clients = v; }},
        {"--max-message-bytes", "largest frame a client may send [256M]", 1024, 4294967295ull, true,
         [](auto v, Config& c) { c.max_message_bytes = v; }},
        {"--max-pixels", "largest width*height a render may ask for [16777216]", 1, 268435456, false,
         [](auto v, Config& c) { c.max_pixels = v; }},
        {"--max-in-flight", "pending requests per connection [8]", 1, 1024, false,
         [](auto v, Config& c) { c.max_in_flight = v; }},
        {"--queue", "render jobs waiting across all clients [64]", 1, 100000, false,
         [](auto v, Config& c) { c.queue_capacity = v; }},
        {"--heartbeat-ms", "ping idle clients; drop them after 3 intervals [15000]", 10, 3600000, false,
         [](auto v, Config& c) { c.heartbeat = milliseconds(v); }},
        {"--max-inflight-bytes", "request bodies held across all clients [1G]", 1u << 20, 1ull << 40, true,
         [](auto v, Config& c) { c.max_inflight_bytes = v; }},
        {"--max-scene-bytes", "a scene's decoded size, geometry and images [2G]", 1024, 1ull << 40, true,
         [](auto v, Config& c) { c.max_scene_bytes = v; }},
        {"--max-scenes", "scenes resident at once [64]", 1, 100000, false, [](auto v, Config& c) { c.max_scenes = v; }},
        {"--gpu-memory-budget",
         "what every scene's GPU structures may hold together; frames past it are refused (resource_exhausted) "
         "[90% of the device's memory, or half the host's for a software rasterizer]",
         1u << 20, 1ull << 50, true, [](auto v, Config& c) { c.gpu_memory_budget = v; }},
        {"--max-unauthenticated", "connections yet to authenticate, with a token [16]", 1, 100000, false,
         [](auto v, Config& c) { c.max_unauthenticated = v; }},
        {"--auth-timeout-ms", "time a connection has to authenticate [10000]", 10, 3600000, false,
         [](auto v, Config& c) { c.auth_timeout = milliseconds(v); }},
        {"--max-output-bytes", "replies a client leaves unread before it is dropped [512M]", 4096, 1ull << 40, true,
         [](auto v, Config& c) { c.max_output_bytes = v; }},
        {"--calibration-size", "pixels a side of the larger frame the device's cost model is measured at, for "
                               "budgets; the smaller is half [64]",
         8, 4096, false, [](auto v, Config& c) { c.calibration_size = static_cast<int>(v); }},
        {"--calibration-change-frames", "frames the cost model times per change a frame may redo (lights moved or "
                                        "dimmed, structures rebuilt), the median counting; 0: none, and changes "
                                        "are priced by the bench's bounds [3]",
         0, 15, false, [](auto v, Config& c) { c.calibration_change_frames = static_cast<int>(v); }},
        {"--drain-seconds", "on SIGTERM, finish in-flight work for at most N s, then cancel it; a second signal "
                            "exits at once [10]",
         0, 3600, false, [](auto v, Config& c) { c.drain_timeout = std::chrono::seconds(v); }},
    };
}

Options parse(int argc, char** argv) {
    Options options;
    CLI::App app{"bounced: the Bounce render daemon (docs/protocol.md). With --render-once it renders one frame "
                 "to a file and exits, with no network at all.",
                 "bounced"};
    app.set_version_flag("--version", std::string("bounced ") + BOUNCE_VERSION, "print the version and exit");
    // A flag given twice takes its last value, so wrappers can append to a default command line.
    app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    app.footer("Byte counts (the -bytes flags, --gpu-memory-budget) take a K, M, G or T suffix (powers of 1024).");

    std::string listen, device, log_level = "info", log_format = "text", size;
    std::string port_file, scene_root, cache_dir, token_file, metrics_listen, http_listen, priors_file;
    std::vector<std::string> knobs;
    std::vector<Limit> limits = daemon_limits();
    const char* daemon_group = "Daemon";
    app.add_option("--listen", listen, "HOST:PORT to serve on (port 0: any free port) [127.0.0.1:7878]")->group(daemon_group);
    app.add_option("--port-file", port_file, "write the bound port (and the ops port) to F once listening")
        ->group(daemon_group);
    app.add_option("--scene-root", scene_root, "scene.load paths resolve inside DIR [loading by path is off]")
        ->group(daemon_group);
    app.add_option("--cache-dir", cache_dir, "where baked structures are cached")->group(daemon_group);
    app.add_option("--priors", priors_file,
                   "budgets: the methods' own-error priors measured on your scenes (bounce_bench_quality --priors-out) "
                   "[the bench corpus']")
        ->group(daemon_group);
    app.add_option("--token-file", token_file, "clients must send this token (required off loopback)")
        ->group(daemon_group);
    auto* metrics_option =
        app.add_option("--metrics-listen", metrics_listen, "ops HTTP on HOST:PORT: /healthz /readyz /metrics [off]")
            ->group(daemon_group);
    app.add_option("--http-listen", http_listen,
                   "HTTP on HOST:PORT: the ops routes, the browser viewer at / and the protocol over WebSocket at /ws [off]")
        ->group(daemon_group)
        ->excludes(metrics_option);
    for (Limit& limit : limits) {
        app.add_option(limit.flag, limit.text, limit.help)->type_name(limit.is_bytes ? "BYTES" : "N")->group(daemon_group);
    }
    app.add_option("--log-format", log_format, "text, or json: one object a line, with request ids [text]")
        ->check(CLI::IsMember({"text", "json"}))
        ->group(daemon_group);

    const char* render_group = "Render once";
    app.add_option("--render-once", options.render_once, "render one frame to OUT.(png|jpg|exr) and exit")->group(render_group);
    app.add_option("--scene", options.scene, "built-in scene name (cornell) or a .gltf/.glb file [cornell]")->group(render_group);
    app.add_option("--method", options.method, "any method, reference included [direct]")->group(render_group);
    app.add_option("--preset", options.preset, "draft, low, medium, high, ultra [medium]")->group(render_group);
    app.add_option("--set", knobs, "override one knob of the method: KNOB=VALUE (repeatable)")
        ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)->group(render_group);
    app.add_option("--size", size, "frame size WxH [512x512]")->group(render_group);
    app.add_option("--exposure", options.exposure, "exposure in stops for PNG/JPEG [0]")->group(render_group);
    app.add_option("--tone", options.tone, "none, reinhard, aces [aces]")->group(render_group);

    app.add_option("--device", device,
                   "auto (a GPU, else the software rasterizer), hardware (a GPU or refuse to start), software, "
                   "or an EGL device index [auto, or $BOUNCE_DEVICE]");
    app.add_option("--log-level", log_level, "debug, info, warn, error [info]")
        ->check(CLI::IsMember({"debug", "info", "warn", "error"}));

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& error) {
        const int code = app.exit(error);
        std::exit(code == 0 ? 0 : 2);
    }

    bounce::log::set_level(bounce::log::parse_level(log_level));
    bounce::log::set_format(bounce::log::parse_format(log_format));
    if (!device.empty()) options.device = device;
    if (!listen.empty()) {
        const auto colon = listen.rfind(':');
        if (colon == std::string::npos) usage_error("--listen expects HOST:PORT, got '" + listen + "'");
        options.daemon.listen_host = listen.substr(0, colon);
        options.daemon.listen_port = static_cast<std::uint16_t>(number("--listen", listen.substr(colon + 1), 0, 65535));
    }
    for (const Limit& limit : limits) {
        if (limit.text.empty()) continue;
        limit.apply(limit.is_bytes ? bytes(limit.flag, limit.text, limit.min, limit.max)
                                   : number(limit.flag, limit.text, limit.min, limit.max),
                    options.daemon);
    }
    for (const std::string& assignment : knobs) {
        const auto equals = assignment.find('=');
        if (equals == std::string::npos) usage_error("--set expects KNOB=VALUE, got '" + assignment + "'");
        try {
            std::size_t end = 0;
            const std::string value = assignment.substr(equals + 1);
            options.knobs[assignment.substr(0, equals)] = std::stod(value, &end);
            if (end != value.size()) throw std::invalid_argument("trailing text");
        } catch (const std::exception&) {
            usage_error("--set " + assignment + ": the value is not a number");
        }
    }
    if (!size.empty()) {
        char end = 0;
        if (std::sscanf(size.c_str(), "%dx%d%c", &options.width, &options.height, &end) != 2) {
            usage_error("--size expects WxH, got '" + size + "'");
        }
    }
    // Empty means "not given" for every path and address (an empty value is no path either).
    if (!port_file.empty()) options.daemon.port_file = port_file;
    if (!scene_root.empty()) options.daemon.scene_root = scene_root;
    if (!cache_dir.empty()) options.daemon.cache_dir = cache_dir;
    if (!priors_file.empty()) options.daemon.priors_file = priors_file;
    if (!token_file.empty()) options.daemon.token_file = token_file;
    if (!metrics_listen.empty()) options.daemon.metrics_listen = metrics_listen;
    if (!http_listen.empty()) {
        options.daemon.metrics_listen = http_listen;
        options.daemon.serve_viewer = true;
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
