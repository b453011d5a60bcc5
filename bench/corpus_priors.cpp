#include "bench/corpus_priors.hpp"

#include "bench/corpus.hpp"
#include "renderer/planning/costs.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace bounce::bench {
namespace {

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> fields;
    std::stringstream row(line);
    for (std::string field; std::getline(row, field, ',');) fields.push_back(field);
    if (!line.empty() && line.back() == ',') fields.emplace_back();  // an empty last field
    return fields;
}

std::size_t column_of(const std::vector<std::string>& header, const std::string& name,
                      const std::filesystem::path& csv) {
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw std::runtime_error(fmt::format("{} has no column '{}'", csv.string(), name));
    return static_cast<std::size_t>(it - header.begin());
}

// What the scenes not left out give of one preset: the largest (of the scenes that do not leak) and
// the median (of all) of their errors, each scene's by the largest and the mean of its placements
// where it has them; and, where some of them leak, the largest and the median of those alone.
struct Figures {
    double largest = 0.0, median = 0.0;
    std::optional<std::pair<double, double>> leaking;
};

// nullopt where no scene is left.
std::optional<Figures> figures_of(const std::map<std::string, double>& by_scene,
                                  const std::map<std::string, std::vector<Placement>>& placed,
                                  const std::set<std::string>& left_out, const std::set<std::string>& leaking) {
    std::vector<double> expected, largest_of_all, promised, leaked_largest, leaked_expected;
    for (const auto& [scene, own] : by_scene) {
        if (left_out.count(scene)) continue;
        // A frame bench/quality could not measure (values not finite) leaves nothing to promise.
        if (std::isnan(own)) return Figures{own, own, std::nullopt};
        double largest = own, mean = own;
        if (const auto it = placed.find(scene); it != placed.end() && !it->second.empty()) {
            double sum = 0.0;
            for (const Placement& placement : it->second) {
                const double error = placement.rel_mse;
                if (std::isnan(error)) return Figures{error, error, std::nullopt};
                largest = std::max(largest, error);
                sum += error;
            }
            mean = sum / static_cast<double>(it->second.size());
        }
        expected.push_back(mean);
        largest_of_all.push_back(largest);
        if (leaking.count(scene)) {
            leaked_largest.push_back(largest);
            leaked_expected.push_back(mean);
        } else {
            promised.push_back(largest);
        }
    }
    if (expected.empty()) return std::nullopt;
    Figures figures;
    figures.median = planning::median(expected);
    // Where every scene left leaks, there is no measure of the preset elsewhere: the largest of them
    // all, not none.
    const std::vector<double>& over = promised.empty() ? largest_of_all : promised;
    figures.largest = *std::max_element(over.begin(), over.end());
    if (!leaked_largest.empty()) {
        figures.leaking = std::pair{*std::max_element(leaked_largest.begin(), leaked_largest.end()),
                                    planning::median(std::move(leaked_expected))};
    }
    return figures;
}

const std::map<std::string, std::vector<Placement>>& placed_of(const PlacementErrors& placements,
                                                               const std::pair<std::string, std::string>& key) {
    static const std::map<std::string, std::vector<Placement>> none;
    const auto it = placements.find(key);
    return it == placements.end() ? none : it->second;
}

}  // namespace

CorpusErrors read_corpus_errors(const std::filesystem::path& csv, int bounces) {
    std::ifstream in(csv);
    if (!in) throw std::runtime_error(fmt::format("cannot read {}", csv.string()));
    std::string line;
    std::getline(in, line);
    const std::vector<std::string> header = split(line);
    const auto column = [&](const std::string& name) { return column_of(header, name, csv); };
    const std::size_t scene = column("scene"), method = column("method"), preset = column("preset"),
                      bounce_count = column("bounces"), error = column("rel_mse_same_bounces");
    CorpusErrors errors;
    while (std::getline(in, line)) {
        const std::vector<std::string> fields = split(line);
        if (fields.size() < header.size() || fields[method] == "reference") continue;
        if (bounces >= 0 && std::stoi(fields[bounce_count]) != bounces) continue;
        errors[{fields[method], fields[preset]}][fields[scene]] = std::stod(fields[error]);
    }
    return errors;
}

std::map<std::string, double> denoised_bounds(const std::filesystem::path& csv) {
    std::ifstream in(csv);
    if (!in) throw std::runtime_error(fmt::format("cannot read {}", csv.string()));
    std::string line;
    std::getline(in, line);
    const std::vector<std::string> header = split(line);
    const std::size_t scene = column_of(header, "scene", csv), noisy = column_of(header, "noisy_rel_mse", csv),
                      denoised = column_of(header, "denoised_rel_mse", csv);
    std::map<std::string, double> bounds;
    for (int number_of_line = 2; std::getline(in, line); ++number_of_line) {
        const std::vector<std::string> fields = split(line);
        if (fields.size() < header.size()) {
            throw std::runtime_error(fmt::format("{}:{}: {} fields where the header has {}", csv.string(), number_of_line,
                                                 fields.size(), header.size()));
        }
        const double n = std::stod(fields[noisy]), d = std::stod(fields[denoised]);
        if (!(n > 0.0) || !(d >= 0.0)) {
            throw std::runtime_error(fmt::format("{}:{}: relMSE {} and {} are not a noisy frame's and a denoised one's",
                                                 csv.string(), number_of_line, fields[noisy], fields[denoised]));
        }
        double& k = bounds[fields[scene]];
        k = std::max(k, d / std::pow(n, planning::kDenoisedNoiseExponent));
    }
    return bounds;
}

PlacementErrors read_placement_errors(const std::vector<std::filesystem::path>& csvs) {
    PlacementErrors errors;
    for (const auto& csv : csvs) {
        std::ifstream in(csv);
        if (!in) throw std::runtime_error(fmt::format("cannot read {}", csv.string()));
        std::string line;
        std::getline(in, line);
        const std::vector<std::string> header = split(line);
        const std::size_t scene = column_of(header, "scene", csv), method = column_of(header, "method", csv),
                          preset = column_of(header, "preset", csv), knob = column_of(header, "knob", csv),
                          value = column_of(header, "value", csv),
                          error = column_of(header, "rel_mse_same_bounces", csv);
        for (int number_of_line = 2; std::getline(in, line); ++number_of_line) {
            const std::vector<std::string> fields = split(line);
            if (fields.size() < header.size()) {
                throw std::runtime_error(fmt::format("{}:{}: {} fields where the header has {}", csv.string(), number_of_line,
                                                     fields.size(), header.size()));
            }
            const auto number = [&](std::size_t column) {
                try {
                    std::size_t used = 0;
                    const double parsed = std::stod(fields[column], &used);
                    if (used == fields[column].size()) return parsed;
                } catch (const std::logic_error&) {
                }
                throw std::runtime_error(fmt::format("{}:{}: {} '{}' is not a number", csv.string(), number_of_line,
                                                     header[column], fields[column]));
            };
            errors[{fields[method], fields[preset]}][fields[scene]].push_back(
                {fields[knob], number(value), number(error)});
        }
    }
    return errors;
}

std::vector<std::filesystem::path> placement_files(const std::filesystem::path& results) {
    std::vector<std::filesystem::path> files;
    for (const char* name : {"cssm_placement.csv", "vct_placement.csv"}) {
        if (std::filesystem::exists(results / name)) files.push_back(results / name);
    }
    return files;
}

std::map<std::string, ThinWalls> thin_walls_of(const std::vector<BenchScene>& scenes) {
    AnalysisSettings settings;
    settings.bounce_image_size = 4;
    settings.bounce_spp = 2;
    settings.direct_timing_spp = 1;
    std::map<std::string, ThinWalls> walls;
    for (const BenchScene& scene : scenes) walls[scene.name] = analyze_scene(scene.scene, settings).thin_walls;
    return walls;
}

std::map<std::string, ThinWalls> corpus_thin_walls() { return thin_walls_of(corpus_scenes()); }

std::map<std::string, ThinWalls> bench_thin_walls() {
    std::map<std::string, ThinWalls> walls = corpus_thin_walls();
    walls.merge(thin_walls_of(quality_scenes()));
    return walls;
}

FurtherScenes cornell_vct_tables(const std::filesystem::path& results) { return {results, {"vct"}}; }

namespace {

// `errors` with `csv`'s rows of `methods`, their scenes beside its own.
void add_further(CorpusErrors& errors, const std::filesystem::path& csv, const std::set<std::string>& methods,
                 const std::map<std::string, ThinWalls>& walls, int bounces = -1) {
    for (const auto& [key, by_scene] : read_corpus_errors(csv, bounces)) {
        if (!methods.count(key.first)) continue;
        std::map<std::string, double>& into = errors[key];
        for (const auto& [scene, error] : by_scene) {
            if (!walls.count(scene)) {
                throw std::runtime_error(fmt::format("{}: no thin walls were found for scene '{}'", csv.string(), scene));
            }
            if (!into.emplace(scene, error).second) {
                throw std::runtime_error(fmt::format("{}: scene '{}' is in the corpus too", csv.string(), scene));
            }
        }
    }
}

}  // namespace

planning::OwnErrorPriors corpus_priors(const std::filesystem::path& directory,
                                       const std::map<std::string, ThinWalls>& walls,
                                       const std::set<std::string>& left_out, bool two_bounce_table,
                                       const PlacementErrors& placements, const std::vector<FurtherScenes>& further) {
    const auto leaking = [&](const std::string& method, const std::string& preset) {
        std::set<std::string> scenes;
        if (method != "vct") return scenes;
        for (const auto& [scene, thin] : walls) {
            if (thin.leaks(preset)) scenes.insert(scene);
        }
        return scenes;
    };
    planning::OwnErrorPriors priors;
    if (const auto denoise = directory / ".." / "denoise_scenes.csv"; std::filesystem::exists(denoise)) {
        for (const auto& [scene, k] : denoised_bounds(denoise)) {
            if (!left_out.count(scene)) priors.denoised_largest = std::max(priors.denoised_largest, k);
        }
        if (!left_out.empty()) priors.denoised_source = "the other bench scenes";
    }
    CorpusErrors one_bounce = read_corpus_errors(directory / "quality.csv");
    for (const FurtherScenes& more : further) add_further(one_bounce, more.directory / "quality.csv", more.methods, walls);
    for (const auto& [key, by_scene] : one_bounce) {
        if (const auto figures =
                figures_of(by_scene, placed_of(placements, key), left_out, leaking(key.first, key.second))) {
            priors.largest[key] = figures->largest;
            priors.typical[key] = figures->median;
            if (figures->leaking) {
                std::tie(priors.vct_leaking_largest[key.second], priors.vct_leaking_typical[key.second]) =
                    *figures->leaking;
            }
        }
    }
    if (!two_bounce_table || !std::filesystem::exists(directory / "vct_two_bounce_quality.csv")) return priors;
    CorpusErrors two_bounces = read_corpus_errors(directory / "vct_two_bounce_quality.csv", 2);
    for (const FurtherScenes& more : further) {
        const std::filesystem::path csv = more.directory / "vct_two_bounce_quality.csv";
        if (std::filesystem::exists(csv)) add_further(two_bounces, csv, more.methods, walls, 2);
    }
    for (const auto& [key, by_scene] : two_bounces) {
        if (key.first != "vct") continue;
        // No placements of the second bounce are measured: its own frames alone.
        if (const auto figures = figures_of(by_scene, {}, left_out, leaking(key.first, key.second))) {
            priors.vct_second_largest[key.second] = figures->largest;
            priors.vct_second_typical[key.second] = figures->median;
            if (figures->leaking) {
                std::tie(priors.vct_second_leaking_largest[key.second],
                         priors.vct_second_leaking_typical[key.second]) = *figures->leaking;
            }
        }
    }
    return priors;
}

}  // namespace bounce::bench
