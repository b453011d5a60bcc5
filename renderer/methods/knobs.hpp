// What every method, GPU or CPU, shares with the registry: knob values and resident structures.
#pragma once

#include <cstddef>
#include <map>
#include <string>

namespace bounce::methods {

// Knob values by name, after presets and overrides are resolved and validated.
using KnobValues = std::map<std::string, double>;

// A knob's value, or `otherwise` where the values lack it.
inline double knob_or(const KnobValues& knobs, const std::string& name, double otherwise) {
    const auto it = knobs.find(name);
    return it == knobs.end() ? otherwise : it->second;
}

// A structure a method keeps resident, its size, and why the scene needs it.
struct ResidentStructure {
    std::string name;
    std::size_t bytes = 0;
    std::string reason;
};

}  // namespace bounce::methods
