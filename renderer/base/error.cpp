#include "renderer/base/error.hpp"

#include <filesystem>

namespace bounce::detail {

void throw_error(const std::string& message, const SourceLine& where) {
    const auto file = std::filesystem::path(where.file).filename().string();
    throw Error(fmt::format("{} ({}:{})", message, file, where.line));
}

}  // namespace bounce::detail
