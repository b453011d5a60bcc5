// bounce: the command-line client of bounced (the interface scripts depend on; README lists it).
// Arguments are parsed by CLI11: every command answers --help, unknown options are errors and
// --flag=value works. With several daemons (--connect a:7878,b:7878, or a name that resolves to
// several addresses) every scene goes to one of them by rendezvous hashing (client/router.hpp).
#include "client/router.hpp"
#include "client/stream_commands.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <thread>

namespace {

using bounce::client::ConnectionError;
using bounce::client::Router;
using bounce::client::ServerError;
using bounce::protocol::ErrorCode;
using bounce::protocol::MessageType;
using nlohmann::json;

// Exit codes (README, "The client"): scripts retry 3 and 4, never 1 or 2.
enum ExitCode : int {
    kOk = 0,
    kRefused = 1,      // the daemon refused the request (bad input, not found, ...), or a load test saw errors
    kUsage = 2,        // the command line is wrong
    kUnreachable = 3,  // no daemon could be reached, or the connection broke
    kRetryable = 4,    // the daemon is busy, timed out or shutting down: the same request may succeed later
};

struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

double parse_number(const std::string& text, const std::string& what) {
    try {
        std::size_t end = 0;
        const double value = std::stod(text, &end);
        if (end == text.size()) return value;
    } catch (const std::exception&) {
    }
    throw UsageError(what + ": '" + text + "' is not a number");
}

std::vector<double> parse_numbers(const std::string& text, std::size_t count, const std::string& what) {
    std::vector<double> values;
    std::size_t start = 0;
    while (start <= text.size()) {
        const auto comma = text.find(',', start);
        values.push_back(parse_number(text.substr(start, comma - start), what));
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    if (values.size() != count) throw UsageError(what + " expects " + std::to_string(count) + " comma-separated numbers");
    return values;
}

std::pair<int, int> parse_size(const std::string& text) {
    int width = 0, height = 0;
    char end = 0;
    if (std::sscanf(text.c_str(), "%dx%d%c", &width, &height, &end) != 2) {
        throw UsageError("--size expects WxH, got '" + text + "'");
    }
    return {width, height};
}

// The format an output path asks for; `-` (stdout) takes --format, PNG by default.
std::string format_of(const std::string& path, const std::string& format) {
    if (!format.empty()) return format == "jpg" ? "jpeg" : format;
    if (path == "-") return "png";
    const auto dot = path.rfind('.');
    std::string extension = dot == std::string::npos ? "" : path.substr(dot + 1);
    std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
    if (extension == "png" || extension == "exr") return extension;
    if (extension == "jpg" || extension == "jpeg") return "jpeg";
    throw UsageError("-o must end in .png, .jpg or .exr (or be - with --format), got '" + path + "'");
}

void write_output(const std::string& path, const std::vector<std::uint8_t>& bytes) {
    if (path == "-") {
        std::cout.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
        std::cout.flush();
        if (!std::cout) throw std::runtime_error("cannot write the image to stdout");
        return;
    }
    const std::string temporary = path + ".tmp";
    {
        std::ofstream out(temporary, std::ios::binary);
        out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
        if (!out) throw std::runtime_error("cannot write " + path);
    }
    if (std::rename(temporary.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot write " + path);
}

std::vector<std::uint8_t> read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UsageError("cannot read " + path);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// What every frame-producing command takes (render, bake, watch, load-test).
struct FrameOptions {
    std::string scene, method, preset, size, tone;
    double exposure = 0.0;
    CLI::Option* exposure_given = nullptr;
    std::vector<std::string> knobs;
    double budget_ms = 0.0, target_error = 0.0;
    CLI::Option* budget_ms_given = nullptr;
    CLI::Option* target_error_given = nullptr;

    void add_to(CLI::App& command) {
        command.add_option("--scene", scene, "scene name")->required();
        command.add_option("--method", method, "direct, vct, isr, cssm or reference");
        command.add_option("--preset", preset, "draft, low, medium, high or ultra");
        command.add_option("--set", knobs, "override one knob: KNOB=VALUE (repeatable)")
            ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
        command.add_option("--size", size, "frame size WxH");
        exposure_given = command.add_option("--exposure", exposure, "exposure in stops (PNG/JPEG)");
        command.add_option("--tone", tone, "none, reinhard or aces");
        budget_ms_given = command.add_option("--budget-ms", budget_ms,
                                             "plan the most accurate frame predicted within this many ms (method auto "
                                             "unless --method names one)");
        target_error_given = command.add_option("--target-error", target_error,
                                                "plan the fastest frame promised within this relMSE against the reference");
    }

    json body() const {
        json body = {{"scene", scene}};
        if (!method.empty()) body["method"] = method;
        if (!preset.empty()) body["preset"] = preset;
        if (!size.empty()) {
            const auto [w, h] = parse_size(size);
            body["width"] = w;
            body["height"] = h;
        }
        if (exposure_given && exposure_given->count() > 0) body["exposure"] = exposure;
        if (!tone.empty()) body["tone"] = tone;
        json values = json::object();
        for (const std::string& knob : knobs) {
            const auto equals = knob.find('=');
            if (equals == std::string::npos) throw UsageError("--set expects KNOB=VALUE, got '" + knob + "'");
            values[knob.substr(0, equals)] = parse_number(knob.substr(equals + 1), "--set");
        }
        if (!values.empty()) body["knobs"] = values;
        const bool budget_ms_set = budget_ms_given && budget_ms_given->count() > 0;
        const bool target_error_set = target_error_given && target_error_given->count() > 0;
        if (budget_ms_set || target_error_set) {
            json budget = json::object();
            if (budget_ms_set) budget["max_ms"] = budget_ms;
            if (target_error_set) budget["max_error"] = target_error;
            body["budget"] = budget;
            if (method.empty()) body["method"] = "auto";
        }
        return body;
    }
};

// Where a scene can be loaded from again, for a daemon that does not have it (restarted, or the
// scene moved when its daemon went down).
struct SourceOptions {
    std::string path, file;

    void add_to(CLI::App& command) {
        auto* path_option = command.add_option("--source", path, "if the daemon lacks the scene, load it from PATH (under its --scene-root)");
        command.add_option("--source-file", file, "if the daemon lacks the scene, upload FILE.glb")->excludes(path_option);
    }
    void apply(Router& router, const std::string& scene) const {
        if (!path.empty()) router.remember(scene, {path, {}});
        if (!file.empty()) router.remember(scene, {std::nullopt, read_file(file)});
    }
};

struct LoadTestReport {
    std::mutex mutex;
    std::vector<double> latencies;
    std::map<std::string, int> errors;
};

int load_test(const std::vector<bounce::client::Endpoint>& endpoints, const std::optional<std::string>& token,
              const FrameOptions& frame, int clients, int frames, int move_every) {
    json body = frame.body();
    body["format"] = "png";
    std::string object;
    {
        Router probe(endpoints, token);
        const auto description = probe.request(frame.scene, MessageType::scene_describe, {{"name", frame.scene}}).body;
        if (!description["objects"].empty()) object = description["objects"].back()["name"];
    }
    LoadTestReport report;
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> threads;
    for (int c = 0; c < clients; ++c) {
        threads.emplace_back([&, c] {
            try {
                Router router(endpoints, token);
                for (int f = 0; f < frames; ++f) {
                    if (move_every > 0 && f % move_every == move_every - 1 && !object.empty()) {
                        const double offset = 0.01 * ((c + f) % 5);
                        router.request(frame.scene, MessageType::object_set_transform,
                                       {{"scene", frame.scene}, {"object", object}, {"translation", {offset, 0.0, 0.0}}});
                    }
                    const auto sent = std::chrono::steady_clock::now();
                    try {
                        router.request(frame.scene, MessageType::render, body);
                        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - sent).count();
                        std::lock_guard lock(report.mutex);
                        report.latencies.push_back(ms);
                    } catch (const ServerError& error) {
                        std::lock_guard lock(report.mutex);
                        ++report.errors[std::string(bounce::protocol::error_code_name(error.code()))];
                    }
                }
            } catch (const std::exception& error) {
                std::lock_guard lock(report.mutex);
                ++report.errors[std::string("connection: ") + error.what()];
            }
        });
    }
    for (auto& thread : threads) thread.join();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    auto& latencies = report.latencies;
    std::sort(latencies.begin(), latencies.end());
    auto percentile = [&](double p) {
        if (latencies.empty()) return 0.0;
        const auto index = static_cast<std::size_t>(std::min<double>(latencies.size() - 1, p * (latencies.size() - 1) + 0.5));
        return latencies[index];
    };
    json error_json = json::object();
    int error_count = 0;
    for (const auto& [code, count] : report.errors) {
        error_json[code] = count;
        error_count += count;
    }
    const json summary = {{"clients", clients}, {"frames", latencies.size()}, {"errors", error_json},
                          {"seconds", seconds}, {"frames_per_second", latencies.size() / seconds},
                          {"latency_ms", {{"p50", percentile(0.50)}, {"p95", percentile(0.95)},
                                          {"p99", percentile(0.99)}, {"max", latencies.empty() ? 0.0 : latencies.back()}}}};
    std::cout << summary.dump() << "\n";
    return error_count == 0 ? kOk : kRefused;
}

// A request about no one scene, to every daemon: one daemon prints its reply as it is; several
// print an object keyed by endpoint. Exit 3 when any daemon could not be reached.
int print_from_every_daemon(Router& router, MessageType type) {
    const auto answers = router.broadcast(type);
    int code = kOk;
    if (answers.size() == 1) {
        if (const auto* failure = std::get_if<std::string>(&answers.front().reply)) throw ConnectionError(*failure);
        std::cout << std::get<bounce::protocol::Message>(answers.front().reply).body.dump(2) << "\n";
        return code;
    }
    json all = json::object();
    for (const auto& answer : answers) {
        if (const auto* failure = std::get_if<std::string>(&answer.reply)) {
            all[answer.endpoint.to_string()] = {{"error", *failure}};
            code = kUnreachable;
        } else {
            all[answer.endpoint.to_string()] = std::get<bounce::protocol::Message>(answer.reply).body;
        }
    }
    std::cout << all.dump(2) << "\n";
    return code;
}

int run(int argc, char** argv) {
    CLI::App app{"bounce: the client of bounced, the Bounce render daemon (docs/protocol.md)", "bounce"};
    app.require_subcommand(1);
    app.fallthrough();  // --connect and --token-file may follow the command too
    // A flag given twice takes its last value, so scripts can append to a default command line.
    app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
    app.footer(
        "Exit codes: 0 done; 1 refused by the daemon (or a load test saw errors); 2 usage error;\n"
        "3 no daemon reachable or the connection broke; 4 busy, timeout or shutting down (retry later).");

    std::string connect = "127.0.0.1:7878";
    if (const char* value = std::getenv("BOUNCE_CONNECT"); value && *value) connect = value;
    std::string token_file;
    if (const char* value = std::getenv("BOUNCE_TOKEN_FILE"); value && *value) token_file = value;
    app.add_option("--connect", connect,
                   "HOST:PORT[,HOST:PORT...]; a name that resolves to several addresses gives one daemon each "
                   "[$BOUNCE_CONNECT, else 127.0.0.1:7878]");
    app.add_option("--token-file", token_file, "file holding the daemons' token [$BOUNCE_TOKEN_FILE]");
    app.set_version_flag("--version", std::string("bounce ") + BOUNCE_VERSION, "print the version and exit");

    // Each command binds its own options (CLI11 keeps one Option per command).
    FrameOptions render_frame, bake_frame, watch_frame, test_frame;
    SourceOptions render_source, bake_source;
    std::string output, format, camera;
    auto* render = app.add_subcommand("render", "render a frame to a file (-o -: stdout); prints its stats as JSON");
    render_frame.add_to(*render);
    render_source.add_to(*render);
    render->add_option("-o,--output", output, "OUT.png, OUT.jpg, OUT.exr, or - for stdout")->required();
    render->add_option("--format", format, "png, jpeg or exr (default: from -o's extension; png for -)")
        ->check(CLI::IsMember({"png", "jpeg", "jpg", "exr"}));
    render->add_option("--camera", camera, "one of the scene's named cameras");

    auto* bake = app.add_subcommand("bake", "bake a method's structures (cssm by default), progress on stderr");
    bake_frame.add_to(*bake);
    bake_source.add_to(*bake);

    std::string file, name;
    auto* load = app.add_subcommand("load", "load a scene file by path under the daemon's --scene-root");
    load->add_option("path", file, "PATH under the scene root")->required();
    load->add_option("--name", name, "the scene's name")->required();
    auto* upload = app.add_subcommand("upload", "send a .glb file and load it");
    upload->add_option("file", file, "FILE.glb")->required();
    upload->add_option("--name", name, "the scene's name")->required();
    auto* unload = app.add_subcommand("unload", "drop a scene from its daemon");
    unload->add_option("--scene", name, "scene name")->required();

    std::string scene, object, light, type, translate, rotate, position, direction, color;
    double scale = 1.0, intensity = 0.0;
    auto* move = app.add_subcommand("move", "set an object's transform");
    move->add_option("--scene", scene, "scene name")->required();
    move->add_option("--object", object, "object name or index")->required();
    move->add_option("--translate", translate, "X,Y,Z");
    move->add_option("--rotate-deg", rotate, "RX,RY,RZ in degrees");
    auto* scale_given = move->add_option("--scale", scale, "uniform scale");

    auto* light_command = app.add_subcommand("light", "add or change a light");
    light_command->add_option("--scene", scene, "scene name")->required();
    light_command->add_option("--light", light, "light name or index")->required();
    light_command->add_option("--type", type, "point, spot or directional")
        ->check(CLI::IsMember({"point", "spot", "directional"}));
    light_command->add_option("--position", position, "X,Y,Z");
    light_command->add_option("--direction", direction, "X,Y,Z");
    light_command->add_option("--color", color, "R,G,B");
    auto* intensity_given = light_command->add_option("--intensity", intensity, "candela (point, spot) or lux (directional)");

    auto* describe = app.add_subcommand("describe", "a scene's objects, lights, cameras and resident structures");
    describe->add_option("--scene", scene, "scene name")->required();
    bool analyze = false;
    describe->add_flag("--analyze", analyze,
                       "add the scene analysis: light by bounce, thin walls per vct preset, indirect visibility");
    auto* list = app.add_subcommand("list", "the scenes of every daemon");
    auto* stats = app.add_subcommand("stats", "every daemon's counters");

    bounce::cli::WatchOptions watch_options;
    std::string stream_format = "jpeg", look_at;
    double fov_deg = 0.0;
    int reference_spp = 256;
    bool no_refine = false;
    auto* watch = app.add_subcommand("watch", "stream a view: each frame to DIR, one JSON line per frame");
    watch_frame.add_to(*watch);
    watch->add_option("-o,--output", watch_options.directory, "DIR for frame-NNNNNN.jpg|png|webp (created)")->required();
    watch->add_option("--format", stream_format, "jpeg, png or webp")->check(CLI::IsMember({"jpeg", "jpg", "png", "webp"}));
    auto* position_given = watch->add_option("--position", position, "inline camera: X,Y,Z");
    auto* look_at_given = watch->add_option("--look-at", look_at, "inline camera: X,Y,Z it looks at");
    auto* fov_given = watch->add_option("--fov", fov_deg, "inline camera: vertical field of view in degrees");
    watch->add_flag("--no-refine", no_refine, "stop the ladder at full-size frames of the method (no reference rungs)");
    auto* reference_spp_given = watch->add_option("--reference-spp", reference_spp, "samples per pixel of the last rung")
        ->check(CLI::Range(1, 65536));
    watch->add_option("--frames", watch_options.frames, "stop after N frames (default: no limit)")
        ->check(CLI::Range(1, 1000000000));
    watch->add_flag("--until-final", watch_options.until_final, "stop after the first frame of the ladder's last rung");

    int clients = 1, frames = 1, move_every = 0, viewers = 0;
    bool stream_test = false;
    auto* load_test_command = app.add_subcommand(
        "load-test", "N clients render M frames each (--stream: N viewers receive M frames each); prints one JSON line");
    test_frame.add_to(*load_test_command);
    load_test_command->add_option("--clients", clients, "concurrent clients")->required()->check(CLI::Range(1, 1024));
    load_test_command->add_option("--frames", frames, "frames per client (per viewer with --stream)")
        ->required()
        ->check(CLI::Range(1, 1000000));
    load_test_command->add_option("--move-every", move_every, "move an object every K frames (0: never)")
        ->check(CLI::Range(0, 1000000));
    auto* stream_given = load_test_command->add_flag(
        "--stream", stream_test, "viewers hold streams while one more connection moves an object; measures motion to photon");
    load_test_command->add_option("--viewers", viewers, "stream connections (default: --clients)")
        ->check(CLI::Range(1, 1024))
        ->needs(stream_given);

    try {
        app.parse(argc, argv);
    } catch (const CLI::RequiredError& error) {
        // CLI11 reads an unknown command as a stray argument; name it instead.
        const auto remaining = app.remaining();
        if (app.get_subcommands().empty() && !remaining.empty()) {
            throw UsageError("unknown command '" + remaining.front() +
                             "' (commands: render bake watch load upload unload move light describe list stats load-test)");
        }
        const int code = app.exit(error);
        return code == 0 ? kOk : kUsage;
    } catch (const CLI::ParseError& error) {
        const int code = app.exit(error);
        return code == 0 ? kOk : kUsage;
    }

    std::optional<std::string> token;
    if (!token_file.empty()) {
        try {
            token = bounce::protocol::read_token_file(token_file);
        } catch (const std::exception& error) {
            throw UsageError(std::string("--token-file: ") + error.what());
        }
    }
    std::vector<bounce::client::Endpoint> endpoints;
    try {
        endpoints = bounce::client::resolve_endpoints(connect);
    } catch (const std::invalid_argument& error) {
        throw UsageError(std::string("--connect: ") + error.what());
    }
    if (*load_test_command && stream_test) {
        // Streams of a still scene end at their ladder's last rung, so the run needs moves to go on.
        if (move_every == 0) throw UsageError("load-test --stream needs --move-every K (1 or more)");
        json body = test_frame.body();
        body["format"] = "jpeg";
        const bounce::cli::StreamLoadTestOptions options{viewers > 0 ? viewers : clients, frames, move_every};
        return bounce::cli::stream_load_test(endpoints, token, body, options) ? kOk : kRefused;
    }
    if (*load_test_command) return load_test(endpoints, token, test_frame, clients, frames, move_every);
    if (*watch) {
        json body = watch_frame.body();
        body["format"] = stream_format == "jpg" ? "jpeg" : stream_format;
        // Any camera flag makes an inline view; the fields it leaves out take the scene's camera's.
        json view = json::object();
        if (position_given->count() > 0) view["position"] = parse_numbers(position, 3, "--position");
        if (look_at_given->count() > 0) view["look_at"] = parse_numbers(look_at, 3, "--look-at");
        if (fov_given->count() > 0) view["fov_deg"] = fov_deg;
        if (!view.empty()) body["camera"] = view;
        if (no_refine) body["refine"] = false;
        if (reference_spp_given->count() > 0) body["reference_spp"] = reference_spp;
        return bounce::cli::watch(endpoints, token, body, watch_options) ? kOk : kRefused;
    }
    Router router(endpoints, token);

    if (*render) {
        json body = render_frame.body();
        body["format"] = format_of(output, format);
        if (!camera.empty()) body["camera"] = camera;
        render_source.apply(router, render_frame.scene);
        const auto reply = router.request(render_frame.scene, MessageType::render, body);
        write_output(output, reply.attachment);
        (output == "-" ? std::cerr : std::cout) << reply.body.dump() << "\n";
    } else if (*bake) {
        json body = bake_frame.body();
        if (bake_frame.method.empty()) body["method"] = "cssm";
        bake_source.apply(router, bake_frame.scene);
        const auto reply = router.request(bake_frame.scene, MessageType::bake, body, {}, [](const json& progress) {
            std::cerr << "bake: " << progress.value("stage", "") << " "
                      << static_cast<int>(100.0 * progress.value("fraction", 0.0)) << "%\n";
        });
        std::cout << reply.body.dump() << "\n";
    } else if (*load) {
        std::cout << router.load(name, file).body.dump() << "\n";
    } else if (*upload) {
        std::cout << router.upload(name, read_file(file)).body.dump() << "\n";
    } else if (*unload) {
        std::cout << router.request(name, MessageType::scene_unload, {{"name", name}}).body.dump() << "\n";
    } else if (*move) {
        json body = {{"scene", scene}, {"object", object}};
        if (!translate.empty()) body["translation"] = parse_numbers(translate, 3, "--translate");
        if (!rotate.empty()) body["rotation_deg"] = parse_numbers(rotate, 3, "--rotate-deg");
        if (scale_given->count() > 0) body["scale"] = scale;
        std::cout << router.request(scene, MessageType::object_set_transform, body).body.dump() << "\n";
    } else if (*light_command) {
        json body = {{"scene", scene}, {"light", light}};
        if (!type.empty()) body["type"] = type;
        if (!position.empty()) body["position"] = parse_numbers(position, 3, "--position");
        if (!direction.empty()) body["direction"] = parse_numbers(direction, 3, "--direction");
        if (!color.empty()) body["color"] = parse_numbers(color, 3, "--color");
        if (intensity_given->count() > 0) body["intensity"] = intensity;
        std::cout << router.request(scene, MessageType::light_set, body).body.dump() << "\n";
    } else if (*describe) {
        json body = {{"name", scene}};
        if (analyze) body["analyze"] = true;
        std::cout << router.request(scene, MessageType::scene_describe, body).body.dump(2) << "\n";
    } else if (*list) {
        return print_from_every_daemon(router, MessageType::scene_list);
    } else if (*stats) {
        return print_from_every_daemon(router, MessageType::stats);
    }
    return kOk;
}

bool retryable(const ServerError& error) {
    return error.retryable() || error.code() == ErrorCode::busy || error.code() == ErrorCode::timeout ||
           error.code() == ErrorCode::shutting_down;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const UsageError& error) {
        std::cerr << "bounce: " << error.what() << "\nRun with --help for more information.\n";
        return kUsage;
    } catch (const ServerError& error) {
        std::cerr << "bounce: " << bounce::protocol::error_code_name(error.code()) << ": " << error.what() << "\n";
        return retryable(error) ? kRetryable : kRefused;
    } catch (const ConnectionError& error) {
        std::cerr << "bounce: " << error.what() << "\n";
        return kUnreachable;
    } catch (const std::exception& error) {
        std::cerr << "bounce: " << error.what() << "\n";
        return kRefused;
    }
}
