#include "bench/common.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <sstream>
#include <thread>

namespace bounce::bench {

Arguments::Arguments(int argc, char** argv, std::string program, std::string invocation)
    : argc_(argc), argv_(argv), program_(std::move(program)), command_(std::move(invocation)) {}

bool Arguments::next() {
    if (++at_ >= argc_) return false;
    flag_ = argv_[at_];
    command_ += " " + flag_;
    return true;
}

std::string Arguments::value() {
    if (at_ + 1 >= argc_) {
        std::fprintf(stderr, "%s: %s needs a value\n", program_.c_str(), flag_.c_str());
        std::exit(2);
    }
    const std::string text = argv_[++at_];
    command_ += " " + text;
    return text;
}

int Arguments::number() {
    const std::string text = value();
    try {
        return std::stoi(text);
    } catch (const std::exception&) {
        std::fprintf(stderr, "%s: %s expects a number, got '%s'\n", program_.c_str(), flag_.c_str(), text.c_str());
        std::exit(2);
    }
}

void Arguments::knob(methods::KnobValues& knobs) {
    const std::string assignment = value();
    const auto equals = assignment.find('=');
    char* end = nullptr;
    const double number = equals == std::string::npos ? 0.0 : std::strtod(assignment.c_str() + equals + 1, &end);
    if (equals == std::string::npos || equals == 0 || end == assignment.c_str() + equals + 1 || *end != '\0') {
        std::fprintf(stderr, "%s: %s takes NAME=VALUE, not '%s'\n", program_.c_str(), flag_.c_str(),
                     assignment.c_str());
        std::exit(2);
    }
    knobs[assignment.substr(0, equals)] = number;
}

double ms_since(Clock::time_point start) { return std::chrono::duration<double, std::milli>(Clock::now() - start).count(); }

RenderRequest linear_request(const std::string& method, const std::string& preset, methods::KnobValues knobs, int size) {
    RenderRequest request;
    request.method = method;
    request.preset = preset;
    request.knobs = std::move(knobs);
    request.width = request.height = size;
    request.make_display_image = false;
    return request;
}

std::vector<double> numbers(const std::string& text) {
    std::vector<double> values;
    std::stringstream in(text);
    for (std::string item; std::getline(in, item, ',');) values.push_back(std::stod(item));
    return values;
}

double change_every_light(scene::Scene& scene, const std::vector<scene::Light>& original, int change) {
    const float step = static_cast<float>(1 + change % 97);
    const float extent = glm::length(scene.world_bounds().extent());
    const double factor = 1.0 + 1e-4 * change;
    for (std::size_t i = 0; i < scene.lights.size() && i < original.size(); ++i) {
        scene::Light& light = scene.lights[i];
        light.position = original[i].position + glm::vec3(1e-6f * step * extent, 0.0f, 0.0f);
        const glm::vec3 turned = original[i].direction + glm::vec3(0.0f, 0.0f, 1e-6f * step);
        light.direction = glm::normalize(turned);
        light.intensity = static_cast<float>(original[i].intensity * factor);
    }
    return factor;
}

std::string machine_description() {
    std::ifstream cpuinfo("/proc/cpuinfo");
    std::string line, model = "unknown CPU";
    while (std::getline(cpuinfo, line)) {
        if (line.rfind("model name", 0) == 0) {
            model = line.substr(line.find(':') + 2);
            break;
        }
    }
    return fmt::format("{}, {} hardware threads", model, std::thread::hardware_concurrency());
}

std::optional<ReportPaths> report_paths(Arguments& arguments, const char* usage) {
    ReportPaths paths;
    while (arguments.next()) {
        if (arguments.flag() == "--out") {
            paths.out = arguments.value();
        } else if (arguments.flag() == "--markdown") {
            paths.markdown = arguments.value();
        } else {
            std::fprintf(stderr, "%s\n", usage);
            return std::nullopt;
        }
    }
    return paths;
}

std::string today() {
    const std::time_t now = std::time(nullptr);
    char date[32];
    std::strftime(date, sizeof(date), "%Y-%m-%d", std::gmtime(&now));
    return date;
}

}  // namespace bounce::bench
