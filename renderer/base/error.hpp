// Errors and invariant checks shared by the whole renderer.
//
// Setup failures throw bounce::Error with a formatted message and the source location;
// BOUNCE_CHECK guards invariants and prints the values that broke them.
#pragma once

#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace bounce {

class Error : public std::runtime_error {
public:
    explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Thrown for input a caller supplied (a scene file, a knob value): the message names the fault.
class InputError : public Error {
public:
    using Error::Error;
};

// Input that is well formed but would take more memory than a budget allows (a scene whose decoded
// size is past its limit): the message names the largest part and the budget. It is an InputError,
// so a caller that catches both must catch this one first.
class ResourceExhausted : public InputError {
public:
    using InputError::InputError;
};

// Thrown when long work stops because its caller asked it to (a progress callback returned false).
class Cancelled : public Error {
public:
    using Error::Error;
};

// Where a failure was raised. Filled from __FILE__ and __LINE__ rather than std::source_location,
// which clang before 15 cannot compile with libstdc++ (the fuzz build uses clang-14).
struct SourceLine {
    const char* file;
    unsigned line;
};

namespace detail {
[[noreturn]] void throw_error(const std::string& message, const SourceLine& where);
}

template <typename... Args>
[[noreturn]] void fail(const SourceLine& where, fmt::format_string<Args...> format,
                       Args&&... args) {
    detail::throw_error(fmt::format(format, std::forward<Args>(args)...), where);
}

}  // namespace bounce

#define BOUNCE_HERE (::bounce::SourceLine{__FILE__, __LINE__})

#define BOUNCE_FAIL(...) ::bounce::fail(BOUNCE_HERE, __VA_ARGS__)

#define BOUNCE_CHECK(condition, ...)                                                          \
    do {                                                                                      \
        if (!(condition)) {                                                                   \
            ::bounce::fail(BOUNCE_HERE, "check failed: {}: {}", #condition,                   \
                           fmt::format(__VA_ARGS__));                                         \
        }                                                                                     \
    } while (false)
