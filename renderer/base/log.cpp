#include "renderer/base/log.hpp"

#include "renderer/base/error.hpp"

#include <fmt/chrono.h>
#include <nlohmann/json.hpp>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>

namespace bounce::log {
namespace {
std::atomic<Level> g_level{Level::info};
std::atomic<Format> g_format{Format::text};
std::mutex g_write_mutex;
thread_local std::string t_request_id;

const char* level_name(Level level) {
    switch (level) {
        case Level::debug: return "debug";
        case Level::info: return "info";
        case Level::warn: return "warn";
        case Level::error: return "error";
    }
    return "?";
}

std::string timestamp() {
    using namespace std::chrono;
    const auto now = system_clock::now();
    const auto millis = duration_cast<milliseconds>(now.time_since_epoch()).count() % 1000;
    return fmt::format("{:%Y-%m-%dT%H:%M:%S}.{:03d}Z", fmt::gmtime(system_clock::to_time_t(now)), millis);
}

// Text values that hold spaces, quotes or '=' are quoted so that key=value stays parseable.
std::string text_value(const Field& field) {
    if (const auto* text = std::get_if<std::string>(&field.value)) {
        if (!text->empty() && text->find_first_of(" \"=\t\n") == std::string::npos) return *text;
        return nlohmann::json(*text).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    }
    if (const auto* number = std::get_if<double>(&field.value)) return fmt::format("{:.3f}", *number);
    return std::to_string(std::get<std::int64_t>(field.value));
}

}  // namespace

void set_level(Level level) { g_level.store(level); }
Level level() { return g_level.load(); }

Level parse_level(std::string_view name) {
    if (name == "debug") return Level::debug;
    if (name == "info") return Level::info;
    if (name == "warn") return Level::warn;
    if (name == "error") return Level::error;
    throw InputError(fmt::format("unknown log level '{}' (expected debug, info, warn or error)", name));
}

void set_format(Format format) { g_format.store(format); }
Format format() { return g_format.load(); }

Format parse_format(std::string_view name) {
    if (name == "text") return Format::text;
    if (name == "json") return Format::json;
    throw InputError(fmt::format("unknown log format '{}' (expected text or json)", name));
}

RequestScope::RequestScope(std::string request_id) : previous_(std::exchange(t_request_id, std::move(request_id))) {}
RequestScope::~RequestScope() { t_request_id = std::move(previous_); }
const std::string& current_request_id() { return t_request_id; }

void write(Level level, std::string_view component, std::string_view message, std::initializer_list<Field> fields) {
    std::string line;
    if (format() == Format::json) {
        nlohmann::ordered_json event = {{"ts", timestamp()}, {"level", level_name(level)}, {"component", component},
                                        {"msg", message}};
        if (!t_request_id.empty()) event["request_id"] = t_request_id;
        for (const Field& field : fields) {
            std::visit([&](const auto& value) { event[std::string(field.key)] = value; }, field.value);
        }
        // Invalid UTF-8 (a client's scene name, say) is replaced rather than thrown on.
        line = event.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    } else {
        line = fmt::format("{} {} {}: {}", timestamp(), level_name(level), component, message);
        if (!t_request_id.empty()) line += " request_id=" + t_request_id;
        for (const Field& field : fields) line += fmt::format(" {}={}", field.key, text_value(field));
    }
    line += '\n';
    std::lock_guard lock(g_write_mutex);
    std::fwrite(line.data(), 1, line.size(), stderr);
}

}  // namespace bounce::log
