// What every method, GPU or CPU, shares with the registry: knob values and resident structures.
#pragma once

#include <cstddef>
#include <map>
#include <string>

namespace bounce::methods {

// Knob values by name, after presets and overrides are resolved and validated.
using KnobValues = std::map<std::string, double>;

// A structure a method keeps resident, its size, and why the scene needs it.
struct ResidentStructure {
    std::string name;
    std::size_t bytes = 0;
    std::string reason;
};

}  // namespace bounce::methods
