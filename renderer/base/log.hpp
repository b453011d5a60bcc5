// Structured, leveled logging: one line per event, `level component: message key=value ...`.
#pragma once

#include <fmt/format.h>

#include <string_view>

namespace bounce::log {

enum class Level { debug = 0, info = 1, warn = 2, error = 3 };

void set_level(Level level);
Level level();
// Parses "debug", "info", "warn" or "error"; throws InputError otherwise.
Level parse_level(std::string_view name);
void write(Level level, std::string_view component, std::string_view message);

template <typename... Args>
void debug(std::string_view component, fmt::format_string<Args...> format, Args&&... args) {
    if (level() <= Level::debug) write(Level::debug, component, fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void info(std::string_view component, fmt::format_string<Args...> format, Args&&... args) {
    if (level() <= Level::info) write(Level::info, component, fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void warn(std::string_view component, fmt::format_string<Args...> format, Args&&... args) {
    if (level() <= Level::warn) write(Level::warn, component, fmt::format(format, std::forward<Args>(args)...));
}
template <typename... Args>
void error(std::string_view component, fmt::format_string<Args...> format, Args&&... args) {
    write(Level::error, component, fmt::format(format, std::forward<Args>(args)...));
}

}  // namespace bounce::log
