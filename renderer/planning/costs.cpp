#include "renderer/planning/costs.hpp"

#include "renderer/base/error.hpp"
#include "renderer/base/hash.hpp"
#include "renderer/base/log.hpp"

#include <algorithm>
#include <iterator>
#include <limits>
#include <cmath>
#include <fstream>
#include <vector>

namespace bounce::planning {
using nlohmann::json;

double median(std::vector<double> values) {
    BOUNCE_CHECK(!values.empty(), "the median of no values");
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

CostLine CostLine::through(double pixels_a, double ms_a, double pixels_b, double ms_b) {
    CostLine line;
    if (pixels_b != pixels_a) line.per_megapixel_ms = std::max(0.0, (ms_b - ms_a) / ((pixels_b - pixels_a) * 1e-6));
    // The fixed part from the larger frame, so that the line passes through it when the slope was clamped.
    const bool b_larger = pixels_b >= pixels_a;
    line.fixed_ms = std::max(0.0, (b_larger ? ms_b : ms_a) - line.per_megapixel_ms * (b_larger ? pixels_b : pixels_a) * 1e-6);
    return line;
}

double ChangeCost::beyond_warm(FrameChange change) const {
    switch (change) {
    case FrameChange::none:
    case FrameChange::view: return 0.0;  // its cascades are all it redoes, priced as the scene's maps
    case FrameChange::light_power: return light_power;
    case FrameChange::lights: return lights;
    case FrameChange::objects:
    case FrameChange::knobs:
    case FrameChange::knobs_and_view:
    case FrameChange::knobs_and_scene: return std::max(lights, rebuild);
    }
    return std::max(lights, rebuild);
}

void DeviceCosts::set_change_cost(const std::string& method, const std::string& preset, ChangeCost cost) {
    changes_[{method, preset}] = cost;
}

namespace {
template <typename Value>
std::optional<Value> find_preset(const std::map<std::pair<std::string, std::string>, Value>& by_preset,
                                 const std::string& method, const std::string& preset) {
    const auto it = by_preset.find({method, preset});
    if (it == by_preset.end()) return std::nullopt;
    return it->second;
}
}  // namespace

std::optional<ChangeCost> DeviceCosts::change_cost(const std::string& method, const std::string& preset) const {
    return find_preset(changes_, method, preset);
}

void DeviceCosts::set(const std::string& method, const std::string& preset, CostLine line) {
    lines_[{method, preset}] = line;
}

std::optional<CostLine> DeviceCosts::line(const std::string& method, const std::string& preset) const {
    return find_preset(lines_, method, preset);
}

json DeviceCosts::to_json() const {
    json lines = json::array();
    for (const auto& [key, line] : lines_) {
        lines.push_back({{"method", key.first}, {"preset", key.second}, {"fixed_ms", line.fixed_ms},
                         {"per_megapixel_ms", line.per_megapixel_ms}});
    }
    json changes = json::array();
    for (const auto& [key, change] : changes_) {
        changes.push_back({{"method", key.first}, {"preset", key.second}, {"pixels", change.pixels},
                           {"light_power", change.light_power}, {"lights", change.lights}, {"rebuild", change.rebuild}});
    }
    return {{"version", kVersion}, {"renderer", renderer_}, {"calibration_ms", calibration_ms}, {"lines", lines},
            {"changes", changes}};
}

DeviceCosts DeviceCosts::from_json(const json& document) {
    try {
        if (document.at("version").get<int>() != kVersion) {
            throw Error(fmt::format("cost model version {} is not {}", document.at("version").get<int>(), kVersion));
        }
        DeviceCosts costs(document.at("renderer").get<std::string>());
        costs.calibration_ms = document.value("calibration_ms", 0.0);
        for (const json& line : document.at("lines")) {
            const CostLine cost{line.at("fixed_ms").get<double>(), line.at("per_megapixel_ms").get<double>()};
            if (!(cost.fixed_ms >= 0.0) || !(cost.per_megapixel_ms >= 0.0)) {
                throw Error("a cost line is negative or not a number");
            }
            costs.set(line.at("method").get<std::string>(), line.at("preset").get<std::string>(), cost);
        }
        for (const json& change : document.value("changes", json::array())) {
            const ChangeCost cost{change.at("pixels").get<double>(), change.at("light_power").get<double>(),
                                  change.at("lights").get<double>(), change.at("rebuild").get<double>()};
            if (!(cost.pixels > 0.0) || !(cost.light_power >= 0.0) || !(cost.lights >= 0.0) || !(cost.rebuild >= 0.0) ||
                !std::isfinite(cost.light_power + cost.lights + cost.rebuild)) {
                throw Error("a change cost is negative, not a number, or measured at no size");
            }
            costs.set_change_cost(change.at("method").get<std::string>(), change.at("preset").get<std::string>(), cost);
        }
        return costs;
    } catch (const json::exception& error) {
        throw Error(fmt::format("cost model: {}", error.what()));
    }
}

std::filesystem::path DeviceCosts::cache_path(const std::filesystem::path& cache_dir, const std::string& renderer) {
    Hasher hash;
    hash.add_string(renderer);
    return cache_dir / "cost-model" / fmt::format("{:016x}-v{}.json", hash.value(), kVersion);
}

std::optional<DeviceCosts> DeviceCosts::load(const std::filesystem::path& file, const std::string& renderer) {
    std::ifstream in(file);
    if (!in) return std::nullopt;
    try {
        DeviceCosts costs = from_json(json::parse(in));
        if (costs.renderer() != renderer) {
            log::info("planner", "cost model {} is for '{}', not '{}': calibrating anew", file.string(), costs.renderer(), renderer);
            return std::nullopt;
        }
        return costs;
    } catch (const std::exception& error) {
        log::warn("planner", "cost model {} is unreadable ({}): calibrating anew", file.string(), error.what());
        return std::nullopt;
    }
}

void DeviceCosts::save(const std::filesystem::path& file) const {
    std::filesystem::create_directories(file.parent_path());
    const std::filesystem::path temporary = file.string() + ".tmp";
    {
        std::ofstream out(temporary);
        out << to_json().dump(2) << '\n';
        if (!out) throw Error(fmt::format("cannot write the cost model to {}", temporary.string()));
    }
    std::filesystem::rename(temporary, file);
}

void SceneMeasurements::record(const std::string& method, const std::string& preset, int bounces, double measured_ms,
                               double predicted_ms, double pixels, FrameChange change) {
    if (!(predicted_ms > 0.0) || !(measured_ms >= 0.0) || !(pixels >= 0.0)) return;
    const std::lock_guard lock(mutex_);
    auto& kept = change == FrameChange::none ? frames_[{method, preset, bounces}][pixels]
                                             : changed_frames_[{{method, preset, bounces}, change}];
    kept.push_back({pixels, measured_ms, predicted_ms});
    if (kept.size() > kKept) kept.pop_front();
}

void SceneMeasurements::record_maps(MapsKey key, double ms) {
    if (std::get<2>(key) <= 0 || !(ms >= 0.0)) return;
    const std::lock_guard lock(mutex_);
    auto& kept = shadow_maps_[key];
    kept.push_back(ms);
    if (kept.size() > kKept) kept.pop_front();
}

std::optional<double> SceneMeasurements::maps_ms(bool view_only, int cascades, int size) const {
    const std::lock_guard lock(mutex_);
    const auto largest = [](const std::deque<double>& kept) { return *std::max_element(kept.begin(), kept.end()); };
    const auto same_kind = [&](const auto it) {
        return it != shadow_maps_.end() && std::get<0>(it->first) == view_only && std::get<1>(it->first) == cascades;
    };
    const auto above = shadow_maps_.lower_bound({view_only, cascades, size});
    if (same_kind(above) && std::get<2>(above->first) == size) return largest(above->second);
    if (above != shadow_maps_.begin() && same_kind(std::prev(above))) {
        const auto below = std::prev(above);
        const double texels = static_cast<double>(size) / std::get<2>(below->first);
        return largest(below->second) * texels * texels;
    }
    if (same_kind(above)) return largest(above->second);
    return std::nullopt;
}

void SceneMeasurements::record_denoise(double ms, double pixels) {
    if (!(ms >= 0.0) || !(pixels > 0.0)) return;
    const std::lock_guard lock(mutex_);
    denoise_ms_per_pixel_.push_back(ms / pixels);
    if (denoise_ms_per_pixel_.size() > kKept) denoise_ms_per_pixel_.pop_front();
}

std::optional<double> SceneMeasurements::denoise_ms_per_pixel() const {
    const std::lock_guard lock(mutex_);
    if (denoise_ms_per_pixel_.empty()) return std::nullopt;
    return *std::max_element(denoise_ms_per_pixel_.begin(), denoise_ms_per_pixel_.end());
}

void SceneMeasurements::record_shadow_maps(int size, int cascades, double ms) { record_maps({false, cascades, size}, ms); }

std::optional<double> SceneMeasurements::shadow_maps_ms(int size, int cascades) const {
    return maps_ms(false, cascades, size);
}

void SceneMeasurements::record_view_cascades(int size, int cascades, double ms) { record_maps({true, cascades, size}, ms); }

std::optional<double> SceneMeasurements::view_cascades_ms(int size, int cascades) const {
    return maps_ms(true, cascades, size);
}

std::vector<SceneMeasurements::FrameTime> SceneMeasurements::changed_frames(const std::string& method,
                                                                            const std::string& preset, int bounces,
                                                                            FrameChange change) const {
    const std::lock_guard lock(mutex_);
    const auto it = changed_frames_.find({{method, preset, bounces}, change});
    if (it == changed_frames_.end()) return {};
    return {it->second.begin(), it->second.end()};
}

std::vector<SceneMeasurements::ChangedFrame> SceneMeasurements::changed_frames_of(const std::string& method) const {
    const std::lock_guard lock(mutex_);
    std::vector<ChangedFrame> frames;
    for (const auto& [key, kept] : changed_frames_) {
        const auto& [preset_key, change] = key;
        if (std::get<0>(preset_key) != method) continue;
        for (const FrameTime& time : kept) frames.push_back({std::get<1>(preset_key), std::get<2>(preset_key), change, time});
    }
    return frames;
}

namespace {
using FrameTime = SceneMeasurements::FrameTime;

// The median measured/baseline ratio of one key's frames, over every size.
std::optional<double> median_ratio(const std::map<double, std::deque<FrameTime>>& by_size) {
    std::vector<double> ratios;
    for (const auto& [pixels, kept] : by_size) {
        for (const FrameTime& frame : kept) ratios.push_back(frame.measured_ms / frame.baseline_ms);
    }
    if (ratios.empty()) return std::nullopt;
    return median(std::move(ratios));
}
}  // namespace

std::optional<double> SceneMeasurements::ratio(const std::string& method, const std::string& preset, int bounces,
                                               bool* exact, const BounceRaise& raise) const {
    const std::lock_guard lock(mutex_);
    if (exact) *exact = false;
    const auto raised = [&](const Key& key, double ratio) {
        return raise ? ratio * raise(std::get<1>(key), std::get<2>(key)) : ratio;
    };
    // This preset's counts: the one asked, else the nearest below, else the fewest above.
    const auto distance = [&](int count) { return count <= bounces ? bounces - count : (1 << 20) + count; };
    const Key* nearest = nullptr;
    std::optional<double> nearest_ratio;
    for (const auto& [key, by_size] : frames_) {
        if (std::get<0>(key) != method || std::get<1>(key) != preset) continue;
        const auto r = median_ratio(by_size);
        if (!r || (nearest && distance(std::get<2>(key)) >= distance(std::get<2>(*nearest)))) continue;
        nearest = &key;
        nearest_ratio = r;
    }
    if (nearest && std::get<2>(*nearest) == bounces) {
        if (exact) *exact = true;
        return nearest_ratio;
    }
    if (nearest) return raised(*nearest, *nearest_ratio);
    std::vector<double> others;
    for (const auto& [key, by_size] : frames_) {
        if (std::get<0>(key) != method) continue;
        if (const auto r = median_ratio(by_size)) others.push_back(raised(key, *r));
    }
    if (others.empty()) return std::nullopt;
    return median(std::move(others));
}

std::optional<SceneMeasurements::AffineTime> SceneMeasurements::reference_time(std::optional<int> bounces) const {
    const std::lock_guard lock(mutex_);
    // Weighted least squares with weights 1/measured^2: the residuals relative to each frame.
    double s = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0, smallest = 0.0, largest = 0.0;
    int frames = 0;
    for (const auto& [key, by_size] : frames_) {
        if (std::get<0>(key) != "reference") continue;
        for (const auto& [pixels, kept] : by_size) {
            for (const FrameTime& frame : kept) {
                if (!(frame.baseline_ms > 0.0) || !(frame.measured_ms > 0.0)) continue;
                const double w = 1.0 / (frame.measured_ms * frame.measured_ms);
                const double x = frame.baseline_ms, y = frame.measured_ms;
                s += w, sx += w * x, sy += w * y, sxx += w * x * x, sxy += w * x * y;
                smallest = frames == 0 ? x : std::min(smallest, x);
                largest = frames == 0 ? x : std::max(largest, x);
                ++frames;
            }
        }
    }
    if (frames < 2 || largest < kReferenceSpan * smallest) return std::nullopt;
    AffineTime fit;
    fit.frames = frames;
    const double determinant = s * sxx - sx * sx;
    if (determinant > 0.0) {
        fit.scale = (s * sxy - sx * sy) / determinant;
        fit.fixed_ms = (sy - fit.scale * sx) / s;
    }
    if (!(determinant > 0.0) || fit.fixed_ms < 0.0 || !(fit.scale > 0.0)) {
        // No fixed part the frames can see: proportional, through the origin.
        fit.fixed_ms = 0.0;
        fit.scale = sxy / sxx;
    }
    if (!(fit.scale > 0.0) || !std::isfinite(fit.scale) || !std::isfinite(fit.fixed_ms)) return std::nullopt;
    if (!bounces) return fit;
    std::map<int, std::vector<double>> ratios;  // measured over the fit, by bounce count
    for (const auto& [key, by_size] : frames_) {
        if (std::get<0>(key) != "reference" || std::get<2>(key) < 0) continue;
        for (const auto& [pixels, kept] : by_size) {
            for (const FrameTime& frame : kept) {
                if (!(frame.baseline_ms > 0.0) || !(frame.measured_ms > 0.0)) continue;
                ratios[std::get<2>(key)].push_back(frame.measured_ms / fit.at(frame.baseline_ms));
            }
        }
    }
    const auto at_count = [&](std::map<int, std::vector<double>>::const_iterator it) {
        fit.bounce_ratio_of = it->first;
        return median(it->second);
    };
    const auto above = ratios.lower_bound(*bounces);
    if (above != ratios.end() && above->first == *bounces) {
        fit.bounce_ratio = at_count(above);
    } else if (!ratios.empty()) {
        const double above_ratio = above != ratios.end() ? median(above->second) : 0.0;
        const double below_ratio = above != ratios.begin() ? median(std::prev(above)->second) : 0.0;
        fit.bounce_ratio = at_count(above_ratio >= below_ratio ? above : std::prev(above));
    }
    return fit;
}

std::optional<double> SceneMeasurements::scene_ratio() const {
    const std::lock_guard lock(mutex_);
    std::vector<double> all;
    for (const auto& [key, by_size] : frames_) {
        // The reference runs on CPU threads: its ratio says nothing of the GPU's.
        if (std::get<0>(key) == "reference") continue;
        if (const auto r = median_ratio(by_size)) all.push_back(*r);
    }
    if (all.empty()) return std::nullopt;
    return median(all);
}

std::vector<SceneMeasurements::FrameTime> SceneMeasurements::frames(const std::string& method, const std::string& preset,
                                                                    int bounces) const {
    const std::lock_guard lock(mutex_);
    std::vector<FrameTime> all;
    if (const auto it = frames_.find({method, preset, bounces}); it != frames_.end()) {
        for (const auto& [pixels, kept] : it->second) all.insert(all.end(), kept.begin(), kept.end());
    }
    return all;
}

std::optional<CostLine> SceneMeasurements::line_locked(const Key& key) const {
    const auto it = frames_.find(key);
    if (it == frames_.end()) return std::nullopt;
    const std::map<double, std::deque<FrameTime>>& by_size = it->second;
    const auto smallest = by_size.upper_bound(0.0);  // sizes not known are left out
    if (smallest == by_size.end() || smallest->second.empty()) return std::nullopt;
    const auto& [large_pixels, large] = *by_size.rbegin();
    if (large_pixels < kLineSpan * smallest->first || large.empty()) return std::nullopt;
    const auto median_ms = [](const std::deque<FrameTime>& kept) {
        std::vector<double> ms;
        for (const FrameTime& frame : kept) ms.push_back(frame.measured_ms);
        return median(std::move(ms));
    };
    return CostLine::through(smallest->first, median_ms(smallest->second), large_pixels, median_ms(large));
}

std::optional<CostLine> SceneMeasurements::line(const std::string& method, const std::string& preset, int bounces) const {
    const std::lock_guard lock(mutex_);
    return line_locked({method, preset, bounces});
}

std::optional<SceneMeasurements::PresetLine> SceneMeasurements::method_line(const std::string& method,
                                                                          const std::string& preset) const {
    const std::lock_guard lock(mutex_);
    std::optional<PresetLine> found;
    for (const auto& [key, by_size] : frames_) {
        if (std::get<0>(key) != method) continue;
        const auto line = line_locked(key);
        if (!line) continue;
        const bool same_preset = std::get<1>(key) == preset;
        if (!found || (same_preset && found->preset != preset)) found = PresetLine{std::get<1>(key), std::get<2>(key), *line};
    }
    return found;
}

void SceneMeasurements::record_noise(int bounces, double noise_ratio, double spp) {
    if (!(noise_ratio >= 0.0) || !std::isfinite(noise_ratio) || !(spp > 0.0)) return;
    const std::lock_guard lock(mutex_);
    NoiseRatio& kept = noise_[bounces];
    if (spp > kept.spp) kept = {noise_ratio, spp};
    else if (spp == kept.spp) kept.ratio = std::max(kept.ratio, noise_ratio);
}

std::optional<double> SceneMeasurements::noise_ratio(int bounces) const {
    const std::lock_guard lock(mutex_);
    const auto above = noise_.lower_bound(bounces);
    if (above != noise_.end() && above->first == bounces) return above->second.ratio;
    if (above == noise_.begin()) return above == noise_.end() ? std::nullopt : std::optional(above->second.ratio);
    const auto below = std::prev(above);
    if (above == noise_.end() || bounces - below->first < above->first - bounces) return below->second.ratio;
    return above->second.ratio;
}

std::map<int, double> SceneMeasurements::noise_ratios() const {
    const std::lock_guard lock(mutex_);
    std::map<int, double> ratios;
    for (const auto& [bounces, kept] : noise_) ratios[bounces] = kept.ratio;
    return ratios;
}

void SceneMeasurements::record_noise_scale(double scale, double compared_scale) {
    const std::lock_guard lock(mutex_);
    const auto keep = [](std::deque<double>& kept, double value) {
        if (!(value > 0.0) || !std::isfinite(value)) return;
        kept.push_back(value);
        if (kept.size() > kKept) kept.pop_front();
    };
    keep(noise_scales_, scale);
    keep(compared_noise_scales_, compared_scale);
}

// The largest, as for own errors: a target error is a promise.
std::optional<double> SceneMeasurements::noise_scale() const {
    const std::lock_guard lock(mutex_);
    if (noise_scales_.empty()) return std::nullopt;
    return *std::max_element(noise_scales_.begin(), noise_scales_.end());
}

std::optional<double> SceneMeasurements::least_noise_scale() const {
    const std::lock_guard lock(mutex_);
    if (compared_noise_scales_.empty()) return std::nullopt;
    return *std::min_element(compared_noise_scales_.begin(), compared_noise_scales_.end());
}

void SceneMeasurements::record_own_error(const std::string& method, const std::string& preset, int bounces, double rel_mse,
                                         std::optional<std::uint64_t> bound_of_view, double unsure) {
    if (!std::isfinite(rel_mse) || !(unsure >= 0.0)) return;
    const std::lock_guard lock(mutex_);
    auto& kept = own_errors_[{method, preset, bounces}];
    if (bound_of_view) {
        for (auto& recorded : kept) {
            if (recorded.view != bound_of_view) continue;
            // The least bound holds, and the least promise of them; an estimate of the view tells more
            // than any bound.
            if (recorded.bound) {
                const double promised = std::min(recorded.rel_mse + recorded.unsure, rel_mse + unsure);
                recorded.rel_mse = std::min(recorded.rel_mse, rel_mse);
                recorded.unsure = promised - recorded.rel_mse;
            }
            return;
        }
    }
    kept.push_back({rel_mse, bound_of_view, bound_of_view.has_value(), 0.0, unsure});
    if (kept.size() > kKept) kept.pop_front();
}

void SceneMeasurements::record_own_estimate(const std::string& method, const std::string& preset, int bounces,
                                            double rel_mse, std::uint64_t view, double taken_out, double unsure,
                                            std::optional<double> cross) {
    if (!std::isfinite(rel_mse) || !(taken_out >= 0.0) || !(unsure >= 0.0) || (cross && !std::isfinite(*cross))) return;
    const std::lock_guard lock(mutex_);
    auto& kept = own_errors_[{method, preset, bounces}];
    RecordedOwnError estimate{rel_mse, view, false, taken_out, unsure, cross};
    for (auto& recorded : kept) {
        if (recorded.view != view) continue;
        if (!recorded.bound) {
            // One frame's error meets the later light alike, whichever reference measured the rest.
            if (recorded.cross && !estimate.cross) {
                estimate.rel_mse += *recorded.cross;
                estimate.cross = recorded.cross;
            } else if (estimate.cross && !recorded.cross) {
                recorded.rel_mse += *estimate.cross;
                recorded.cross = estimate.cross;
            }
        }
        if (recorded.bound || taken_out < recorded.taken_out) recorded = estimate;
        return;
    }
    kept.push_back(estimate);
    if (kept.size() > kKept) kept.pop_front();
}

namespace {

template <typename Records>
double largest_own_error(const Records& kept) {
    double largest = -std::numeric_limits<double>::infinity();
    for (const auto& recorded : kept) largest = std::max(largest, recorded.rel_mse);
    return largest;
}

template <typename Records>
double largest_promise(const Records& kept) {
    double largest = -std::numeric_limits<double>::infinity();
    for (const auto& recorded : kept) largest = std::max(largest, recorded.rel_mse + recorded.unsure);
    return largest;
}

}  // namespace

// The largest, not the median: a target error is a promise, and views differ in what a method gets wrong.
std::optional<SceneMeasurements::OwnError> SceneMeasurements::own_error(const std::string& method, const std::string& preset,
                                                                       int bounces) const {
    const std::lock_guard lock(mutex_);
    if (const auto it = own_errors_.find({method, preset, bounces}); it != own_errors_.end() && !it->second.empty()) {
        return OwnError{largest_own_error(it->second), static_cast<int>(it->second.size()), true,
                        largest_promise(it->second)};
    }
    std::optional<OwnError> found;
    for (const auto& [key, kept] : own_errors_) {
        if (std::get<0>(key) != method || std::get<1>(key) != preset || std::get<2>(key) < bounces || kept.empty()) continue;
        if (!found) found = OwnError{0.0, 0, false, 0.0};
        found->rel_mse = std::max(found->rel_mse, largest_own_error(kept));
        found->promised = std::max(found->promised, largest_promise(kept));
        found->frames += static_cast<int>(kept.size());
    }
    return found;
}

std::map<std::string, double> SceneMeasurements::own_errors(const std::string& method, int at_least_bounces,
                                                            bool promised) const {
    const std::lock_guard lock(mutex_);
    std::map<std::string, double> largest;
    for (const auto& [key, kept] : own_errors_) {
        if (std::get<0>(key) != method || std::get<2>(key) < at_least_bounces || kept.empty()) continue;
        double& value = largest[std::get<1>(key)];
        value = std::max(value, promised ? largest_promise(kept) : largest_own_error(kept));
    }
    return largest;
}

void SceneMeasurements::record_compared(const std::string& method, const std::string& preset, int bounces) {
    const std::lock_guard lock(mutex_);
    compared_.insert({method, preset, bounces});
}

bool SceneMeasurements::compared(const std::string& method, const std::string& preset) const {
    const std::lock_guard lock(mutex_);
    const auto first = compared_.lower_bound({method, preset, std::numeric_limits<int>::min()});
    return first != compared_.end() && std::get<0>(*first) == method && std::get<1>(*first) == preset;
}

bool SceneMeasurements::compared(const std::string& method, const std::string& preset, int bounces) const {
    const std::lock_guard lock(mutex_);
    return compared_.count({method, preset, bounces}) > 0;
}

}  // namespace bounce::planning
