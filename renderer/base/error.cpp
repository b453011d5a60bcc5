#include "renderer/base/error.hpp"

#include <filesystem>

namespace bounce::detail {

void throw_error(const std::string& message, const std::source_location& where) {
    const auto file = std::filesystem::path(where.file_name()).filename().string();
    throw Error(fmt::format("{} ({}:{})", message, file, where.line()));
}

}  // namespace bounce::detail
