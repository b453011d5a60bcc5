#include "renderer/base/log.hpp"

#include "renderer/base/error.hpp"

#include <fmt/chrono.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>

namespace bounce::log {
namespace {
std::atomic<Level> g_level{Level::info};
std::mutex g_write_mutex;

const char* level_name(Level level) {
    switch (level) {
        case Level::debug: return "debug";
        case Level::info: return "info";
        case Level::warn: return "warn";
        case Level::error: return "error";
    }
    return "?";
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

void write(Level level, std::string_view component, std::string_view message) {
    using namespace std::chrono;
    const auto now = system_clock::now();
    const auto millis = duration_cast<milliseconds>(now.time_since_epoch()).count() % 1000;
    const std::time_t seconds = system_clock::to_time_t(now);
    std::lock_guard lock(g_write_mutex);
    fmt::print(stderr, "{:%Y-%m-%dT%H:%M:%S}.{:03d}Z {} {}: {}\n", fmt::gmtime(seconds), millis, level_name(level),
               component, message);
}

}  // namespace bounce::log
