// What the benches share besides their scenes: their command lines, requests for linear frames, the
// machine and date their reports name, elapsed time.
#pragma once

#include "renderer/renderer.hpp"

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace bounce::bench {

// A bench's flags, each value after its flag. A missing or malformed value ends the program with
// status 2 and a message that names `program`. command() is the command line as the reports quote
// it: `invocation` and every argument read so far.
class Arguments {
public:
    Arguments(int argc, char** argv, std::string program, std::string invocation);
    // Moves to the next flag; false when there is none.
    bool next();
    const std::string& flag() const { return flag_; }
    std::string value();
    int number();
    // A NAME=VALUE value (--knob), added to `knobs`.
    void knob(methods::KnobValues& knobs);
    const std::string& command() const { return command_; }

private:
    int argc_;
    char** argv_;
    int at_ = 0;
    std::string program_, command_, flag_;
};

// Where a table-writing bench puts its CSVs (--out DIR) and its section (--markdown FILE).
struct ReportPaths {
    std::filesystem::path out = "bench/results";
    std::filesystem::path markdown = "docs/benchmarks.md";
};
// Reads the remaining flags as --out and --markdown; nullopt, after printing `usage` to stderr,
// for any other flag.
std::optional<ReportPaths> report_paths(Arguments& arguments, const char* usage);

// A flag's comma-separated numbers ("0.1,0.05"); std::invalid_argument for one that is not.
std::vector<double> numbers(const std::string& text);

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start);

// A square frame of linear radiance only (no display image).
RenderRequest linear_request(const std::string& method, const std::string& preset, methods::KnobValues knobs, int size);

// Changes every light of `scene` from `original` (its lights before any change) as a client's
// `light.set` would, the worst case for what a frame redoes (frame_change.hpp: every shadow map and
// every light's work), by amounts no comparison sees: the `change`-th change (from 1) moves each
// light by 1e-6 of the scene's extent times 1 + change % 97, turns it by as many radians, and scales
// its intensity by 1 + 1e-4 change, so that no two changes of a run leave the same lights (a method
// last rendered some changes ago still sees them changed). Returns the intensity's factor: light
// transport is linear, so the truth of the changed scene is the truth times it, less what the moves
// change (a point light a tenth of the extent away changes irradiance by at most 2e-3 of itself,
// 4e-6 of relMSE).
double change_every_light(scene::Scene& scene, const std::vector<scene::Light>& original, int change);

// The CPU model and its hardware thread count.
std::string machine_description();

// Today's date in UTC, YYYY-MM-DD.
std::string today();

}  // namespace bounce::bench
