// Structured, leveled logging: one line per event. Text lines read
// `TIME level component: message key=value ...`; with Format::json each line is one JSON object
// (ts, level, component, msg, request_id when a RequestScope is open, plus the event's fields),
// for log shippers that index fields.
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <initializer_list>
#include <string>
#include <string_view>
#include <variant>

namespace bounce::log {

enum class Level { debug = 0, info = 1, warn = 2, error = 3 };
enum class Format { text, json };

void set_level(Level level);
Level level();
// Parses "debug", "info", "warn" or "error"; throws InputError otherwise.
Level parse_level(std::string_view name);

void set_format(Format format);
Format format();
// Parses "text" or "json"; throws InputError otherwise.
Format parse_format(std::string_view name);

// One named value of an event; text lines print it as key=value, JSON lines as a member.
struct Field {
    std::string_view key;
    std::variant<std::string, double, std::int64_t> value;
};

void write(Level level, std::string_view component, std::string_view message,
           std::initializer_list<Field> fields = {});

// Tags every line this thread writes while it lives with a request id (nests; restores the outer).
class RequestScope {
public:
    explicit RequestScope(std::string request_id);
    ~RequestScope();
    RequestScope(const RequestScope&) = delete;
    RequestScope& operator=(const RequestScope&) = delete;

private:
    std::string previous_;
};
// The id of the innermost open RequestScope on this thread, empty when none.
const std::string& current_request_id();

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
