// Sections of docs/benchmarks.md that one bench writes and the others keep: each between an HTML
// comment that opens it and one that closes it.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace bounce::bench {

// The opening comment keeps the text docs/benchmarks.md has always had, so that the block is found.
inline constexpr std::string_view kIsrBegin = "<!-- isr sections: bench/quality writes them (alone with --isr-only) -->";
inline constexpr std::string_view kIsrEnd = "<!-- end of isr sections -->";

// bench/quality's Cornell variants, and the same tables for the bench corpus (--corpus).
inline constexpr std::string_view kQualityBegin = "<!-- quality: bench/quality writes it -->";
inline constexpr std::string_view kQualityEnd = "<!-- end of quality -->";
inline constexpr std::string_view kCorpusBegin = "<!-- corpus: bench/quality --corpus writes it -->";
inline constexpr std::string_view kCorpusEnd = "<!-- end of corpus -->";

inline constexpr std::string_view kCssmBegin = "<!-- cssm sections: bench/cssm writes them -->";
inline constexpr std::string_view kCssmEnd = "<!-- end of cssm sections -->";

// The block from `begin` through `end` (and its newline), if the file has it.
std::optional<std::string> find_block(const std::filesystem::path& path, std::string_view begin, std::string_view end);

// Replaces that block with `block` (which starts with `begin` and ends with `end`), or appends it.
void splice_block(const std::filesystem::path& path, std::string_view begin, std::string_view end, const std::string& block);

}  // namespace bounce::bench
