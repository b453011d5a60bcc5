// bounce: the command-line client of bounced (the interface scripts depend on; README lists it).
#include "client/client.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <thread>

namespace {

using bounce::client::Client;
using bounce::client::ServerError;
using bounce::protocol::MessageType;
using nlohmann::json;

constexpr const char* kUsage = R"(usage: bounce [--connect HOST:PORT] [--token-file F] COMMAND ...
       bounce --version | --help | COMMAND --help
  (--connect and --token-file default to $BOUNCE_CONNECT and $BOUNCE_TOKEN_FILE, then 127.0.0.1:7878)
  render  --scene S [--method M] [--preset P] [--set KNOB=VALUE ...] [--size WxH]
          [--exposure E] [--tone none|reinhard|aces] [--camera NAME] -o OUT.(png|jpg|exr)
  bake    --scene S [--method cssm] [--preset P] [--set KNOB=VALUE ...]   (progress on stderr)
  load    PATH --name S
  upload  FILE.glb --name S
  move    --scene S --object O [--translate X,Y,Z] [--rotate-deg RX,RY,RZ] [--scale K]
  light   --scene S --light L [--type point|spot|directional] [--position X,Y,Z]
          [--direction X,Y,Z] [--color R,G,B] [--intensity I]
  describe --scene S | list | stats
  load-test --scene S --clients N --frames M [--method M] [--size WxH] [--move-every K]
)";

struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// The options each command takes; any other is a usage error (a typo must not pass silently).
const std::map<std::string, std::set<std::string>>& command_options() {
    static const std::set<std::string> frame = {"--scene", "--method", "--preset", "--set", "--size", "--exposure", "--tone"};
    static const std::map<std::string, std::set<std::string>> options = [] {
        std::set<std::string> render = frame;
        render.insert({"--camera", "-o"});
        return std::map<std::string, std::set<std::string>>{
            {"render", render},
            {"bake", frame},
            {"load", {"--name"}},
            {"upload", {"--name"}},
            {"move", {"--scene", "--object", "--translate", "--rotate-deg", "--scale"}},
            {"light", {"--scene", "--light", "--type", "--position", "--direction", "--color", "--intensity"}},
            {"describe", {"--scene"}},
            {"list", {}},
            {"stats", {}},
            {"load-test", {"--scene", "--clients", "--frames", "--method", "--size", "--move-every"}}};
    }();
    return options;
}

struct HelpRequested {};

// Flags of one command: --name value pairs (repeatable ones collect), plus positionals.
struct Args {
    std::multimap<std::string, std::string> flags;
    std::vector<std::string> positional;

    std::optional<std::string> get(const std::string& name) const {
        const auto it = flags.find(name);
        return it == flags.end() ? std::nullopt : std::optional(it->second);
    }
    std::string require(const std::string& name) const {
        const auto value = get(name);
        if (!value) throw UsageError("missing " + name);
        return *value;
    }
};

Args parse_args(const std::string& command, const std::vector<std::string>& words) {
    const auto known = command_options().find(command);
    if (known == command_options().end()) throw UsageError("unknown command '" + command + "'");
    Args args;
    for (std::size_t i = 0; i < words.size(); ++i) {
        const std::string& word = words[i];
        if (word == "--help" || word == "-h") throw HelpRequested{};
        if (word.rfind("--", 0) == 0 || word == "-o") {
            if (!known->second.count(word)) {
                std::string accepted;
                for (const auto& option : known->second) accepted += (accepted.empty() ? "" : " ") + option;
                throw UsageError("unknown option " + word + " for " + command +
                                 (accepted.empty() ? " (it takes none)" : " (it takes: " + accepted + ")"));
            }
            if (i + 1 >= words.size()) throw UsageError(word + " needs a value");
            args.flags.emplace(word, words[++i]);
        } else {
            args.positional.push_back(word);
        }
    }
    return args;
}

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
    if (std::sscanf(text.c_str(), "%dx%d", &width, &height) != 2) throw UsageError("--size expects WxH, got '" + text + "'");
    return {width, height};
}

std::string format_of(const std::string& path) {
    const auto dot = path.rfind('.');
    std::string extension = dot == std::string::npos ? "" : path.substr(dot + 1);
    std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
    if (extension == "png" || extension == "exr") return extension;
    if (extension == "jpg" || extension == "jpeg") return "jpeg";
    throw UsageError("-o must end in .png, .jpg or .exr, got '" + path + "'");
}

json render_body(const Args& args) {
    json body = {{"scene", args.require("--scene")}};
    if (auto v = args.get("--method")) body["method"] = *v;
    if (auto v = args.get("--preset")) body["preset"] = *v;
    if (auto v = args.get("--size")) {
        const auto [w, h] = parse_size(*v);
        body["width"] = w;
        body["height"] = h;
    }
    if (auto v = args.get("--exposure")) body["exposure"] = parse_number(*v, "--exposure");
    if (auto v = args.get("--tone")) body["tone"] = *v;
    json knobs = json::object();
    const auto [begin, end] = args.flags.equal_range("--set");
    for (auto it = begin; it != end; ++it) {
        const auto equals = it->second.find('=');
        if (equals == std::string::npos) throw UsageError("--set expects KNOB=VALUE, got '" + it->second + "'");
        knobs[it->second.substr(0, equals)] = parse_number(it->second.substr(equals + 1), "--set");
    }
    if (!knobs.empty()) body["knobs"] = knobs;
    return body;
}

void write_file(const std::string& path, const std::vector<std::uint8_t>& bytes) {
    const std::string temporary = path + ".tmp";
    {
        std::ofstream out(temporary, std::ios::binary);
        out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
        if (!out) throw std::runtime_error("cannot write " + path);
    }
    std::rename(temporary.c_str(), path.c_str());
}

std::vector<std::uint8_t> read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + path);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

int load_test(const bounce::client::Endpoint& endpoint, const std::optional<std::string>& token, const Args& args) {
    const std::string scene = args.require("--scene");
    const int clients = static_cast<int>(parse_number(args.require("--clients"), "--clients"));
    const int frames = static_cast<int>(parse_number(args.require("--frames"), "--frames"));
    const int move_every = static_cast<int>(parse_number(args.get("--move-every").value_or("0"), "--move-every"));
    if (clients < 1 || clients > 1024 || frames < 1) throw UsageError("--clients 1..1024 and --frames >= 1");
    json body = render_body(args);
    body["format"] = "png";

    std::mutex mutex;
    std::vector<double> latencies;
    std::map<std::string, int> errors;
    std::string object;
    {
        Client probe(endpoint, token);
        const auto description = probe.request(MessageType::scene_describe, {{"name", scene}}).body;
        if (!description["objects"].empty()) object = description["objects"].back()["name"];
    }
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> threads;
    for (int c = 0; c < clients; ++c) {
        threads.emplace_back([&, c] {
            try {
                Client client(endpoint, token);
                for (int f = 0; f < frames; ++f) {
                    if (move_every > 0 && f % move_every == move_every - 1 && !object.empty()) {
                        const double offset = 0.01 * ((c + f) % 5);
                        client.request(MessageType::object_set_transform,
                                       {{"scene", scene}, {"object", object}, {"translation", {offset, 0.0, 0.0}}});
                    }
                    const auto sent = std::chrono::steady_clock::now();
                    try {
                        client.request(MessageType::render, body);
                        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - sent).count();
                        std::lock_guard lock(mutex);
                        latencies.push_back(ms);
                    } catch (const ServerError& error) {
                        std::lock_guard lock(mutex);
                        ++errors[std::string(bounce::protocol::error_code_name(error.code()))];
                    }
                }
            } catch (const std::exception& error) {
                std::lock_guard lock(mutex);
                ++errors[std::string("connection: ") + error.what()];
            }
        });
    }
    for (auto& thread : threads) thread.join();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::sort(latencies.begin(), latencies.end());
    auto percentile = [&](double p) {
        if (latencies.empty()) return 0.0;
        const auto index = static_cast<std::size_t>(std::min<double>(latencies.size() - 1, p * (latencies.size() - 1) + 0.5));
        return latencies[index];
    };
    json error_json = json::object();
    int error_count = 0;
    for (const auto& [code, count] : errors) {
        error_json[code] = count;
        error_count += count;
    }
    const json report = {{"clients", clients}, {"frames", latencies.size()}, {"errors", error_json},
                         {"seconds", seconds}, {"frames_per_second", latencies.size() / seconds},
                         {"latency_ms", {{"p50", percentile(0.50)}, {"p95", percentile(0.95)},
                                         {"p99", percentile(0.99)}, {"max", latencies.empty() ? 0.0 : latencies.back()}}}};
    std::cout << report.dump() << "\n";
    return error_count == 0 ? 0 : 1;
}

int run(const std::vector<std::string>& words) {
    bounce::client::Endpoint endpoint;
    std::optional<std::string> token;
    if (const char* connect = std::getenv("BOUNCE_CONNECT"); connect && *connect) {
        endpoint = bounce::client::Endpoint::parse(connect);
    }
    if (const char* token_file = std::getenv("BOUNCE_TOKEN_FILE"); token_file && *token_file) {
        token = bounce::protocol::read_token_file(token_file);
    }
    std::size_t i = 0;
    for (; i < words.size() && words[i].rfind("-", 0) == 0; i += 2) {
        if (words[i] == "--help" || words[i] == "-h") {
            std::cout << kUsage;
            return 0;
        }
        if (words[i] == "--version") {
            std::cout << "bounce " << BOUNCE_VERSION << "\n";
            return 0;
        }
        if (i + 1 >= words.size()) throw UsageError(words[i] + " needs a value");
        if (words[i] == "--connect") {
            endpoint = bounce::client::Endpoint::parse(words[i + 1]);
        } else if (words[i] == "--token-file") {
            token = bounce::protocol::read_token_file(words[i + 1]);
        } else {
            throw UsageError("unknown option " + words[i]);
        }
    }
    if (i >= words.size()) throw UsageError("no command");
    const std::string command = words[i];
    Args args;
    try {
        args = parse_args(command, {words.begin() + static_cast<std::ptrdiff_t>(i) + 1, words.end()});
    } catch (const HelpRequested&) {
        std::cout << kUsage;
        return 0;
    }

    if (command == "load-test") return load_test(endpoint, token, args);
    Client client(endpoint, token);
    if (command == "render") {
        const std::string out = args.require("-o");
        json body = render_body(args);
        body["format"] = format_of(out);
        if (auto camera = args.get("--camera")) body["camera"] = *camera;
        const auto reply = client.request(MessageType::render, body);
        write_file(out, reply.attachment);
        std::cout << reply.body.dump() << "\n";
    } else if (command == "bake") {
        json body = render_body(args);
        if (!args.get("--method")) body["method"] = "cssm";
        const auto reply = client.request(MessageType::bake, body, {}, [](const json& progress) {
            std::cerr << "bake: " << progress.value("stage", "") << " "
                      << static_cast<int>(100.0 * progress.value("fraction", 0.0)) << "%\n";
        });
        std::cout << reply.body.dump() << "\n";
    } else if (command == "load" || command == "upload") {
        if (args.positional.size() != 1) throw UsageError(command + " takes one file");
        json body = {{"name", args.require("--name")}};
        std::vector<std::uint8_t> attachment;
        if (command == "load") {
            body["path"] = args.positional[0];
        } else {
            attachment = read_file(args.positional[0]);
        }
        std::cout << client.request(MessageType::scene_load, body, std::move(attachment)).body.dump() << "\n";
    } else if (command == "move") {
        json body = {{"scene", args.require("--scene")}, {"object", args.require("--object")}};
        if (auto v = args.get("--translate")) body["translation"] = parse_numbers(*v, 3, "--translate");
        if (auto v = args.get("--rotate-deg")) body["rotation_deg"] = parse_numbers(*v, 3, "--rotate-deg");
        if (auto v = args.get("--scale")) body["scale"] = parse_number(*v, "--scale");
        std::cout << client.request(MessageType::object_set_transform, body).body.dump() << "\n";
    } else if (command == "light") {
        json body = {{"scene", args.require("--scene")}, {"light", args.require("--light")}};
        if (auto v = args.get("--type")) body["type"] = *v;
        if (auto v = args.get("--position")) body["position"] = parse_numbers(*v, 3, "--position");
        if (auto v = args.get("--direction")) body["direction"] = parse_numbers(*v, 3, "--direction");
        if (auto v = args.get("--color")) body["color"] = parse_numbers(*v, 3, "--color");
        if (auto v = args.get("--intensity")) body["intensity"] = parse_number(*v, "--intensity");
        std::cout << client.request(MessageType::light_set, body).body.dump() << "\n";
    } else if (command == "describe") {
        std::cout << client.request(MessageType::scene_describe, {{"name", args.require("--scene")}}).body.dump(2) << "\n";
    } else if (command == "list") {
        std::cout << client.request(MessageType::scene_list).body.dump(2) << "\n";
    } else if (command == "stats") {
        std::cout << client.request(MessageType::stats).body.dump(2) << "\n";
    } else {
        throw UsageError("unknown command '" + command + "'");
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        return run({argv + 1, argv + argc});
    } catch (const UsageError& error) {
        std::cerr << "bounce: " << error.what() << "\n\n" << kUsage;
        return 2;
    } catch (const ServerError& error) {
        std::cerr << "bounce: " << bounce::protocol::error_code_name(error.code()) << ": " << error.what() << "\n";
        return 1;
    } catch (const std::exception& error) {
        std::cerr << "bounce: " << error.what() << "\n";
        return 1;
    }
}
