// A byte count as people read it: "44.0 GiB", "640.0 MiB", "12.0 KiB", "100 bytes".
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <string>

namespace bounce {

inline std::string bytes_text(std::uint64_t bytes) {
    const auto value = static_cast<double>(bytes);
    constexpr double kib = 1024.0;
    if (value >= kib * kib * kib) return fmt::format("{:.1f} GiB", value / (kib * kib * kib));
    if (value >= kib * kib) return fmt::format("{:.1f} MiB", value / (kib * kib));
    if (value >= kib) return fmt::format("{:.1f} KiB", value / kib);
    return fmt::format("{} bytes", bytes);
}

}  // namespace bounce
