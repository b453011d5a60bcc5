// bounced: the Bounce render daemon.
//
// This build renders offline: it loads a scene (the built-in Cornell box by default, or a glTF
// file), renders one frame with the chosen method and writes it as PNG, JPEG or EXR. Serving
// clients over TCP is the protocol's job (docs/protocol.md) and builds on this same path.
#include "renderer/base/error.hpp"
#include "renderer/base/log.hpp"
#include "renderer/image/codec.hpp"
#include "renderer/renderer.hpp"
#include "renderer/scene/builtin.hpp"

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
};

constexpr const char* kUsage = R"(usage: bounced --render-once OUT.(png|jpg|exr) [options]

Renders one frame and exits.
  --scene NAME          built-in scene name (cornell)                        [cornell]
  --method M            rendering method (direct)                           [direct]
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
        } else {
            usage_error("unknown flag '" + flag + "'");
        }
    }
    if (options.render_once.empty()) usage_error("--render-once OUT is required in this build");
    return options;
}

bounce::scene::Scene load_scene(const std::string& name) {
    const auto builtin = bounce::scene::builtin_scene_names();
    if (std::find(builtin.begin(), builtin.end(), name) != builtin.end()) return bounce::scene::make_builtin_scene(name);
    throw bounce::InputError(fmt::format("unknown scene '{}': this build serves the built-in scenes", name));
}

}  // namespace

int main(int argc, char** argv) {
    try {
        const Options options = parse(argc, argv);
        const auto format = bounce::image::image_format_from_path(options.render_once);
        bounce::scene::Scene scene = load_scene(options.scene);
        for (const auto& warning : scene.warnings) bounce::log::warn("scene", "{}", warning);

        bounce::Renderer renderer(bounce::gpu::DeviceChoice::resolve(options.device));
        auto resources = renderer.upload(scene);
        bounce::RenderRequest request;
        request.method = options.method;
        request.preset = options.preset;
        request.knobs = options.knobs;
        request.width = options.width;
        request.height = options.height;
        request.display = {options.exposure, bounce::image::parse_tone_curve(options.tone)};
        request.make_display_image = format != bounce::image::ImageFormat::exr;
        const auto result = renderer.render(*resources, request);
        const auto bytes = bounce::image::encode_image(result.frame, format);
        bounce::image::write_file_atomic(options.render_once, bytes);
        resources.reset();

        std::string passes;
        for (const auto& pass : result.stats.passes) passes += fmt::format(" {}={:.2f}ms", pass.pass, pass.gpu_ms);
        bounce::log::info("render", "wrote {} ({}x{}, {} bytes) method={} preset={} render={:.1f}ms gpu={:.2f}ms{} "
                          "resident={}B",
                          options.render_once, options.width, options.height, bytes.size(), request.method,
                          request.preset, result.stats.render_ms, result.stats.gpu_ms, passes,
                          result.stats.resident_bytes);
        return 0;
    } catch (const bounce::InputError& error) {
        std::fprintf(stderr, "bounced: %s\n", error.what());
        return 2;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "bounced: error: %s\n", error.what());
        return 1;
    }
}
