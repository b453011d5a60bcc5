#include "bench/markdown_blocks.hpp"

#include <fstream>
#include <sstream>

namespace bounce::bench {
namespace {

std::string read_text(const std::filesystem::path& path) {
    if (!std::filesystem::exists(path)) return {};
    std::ostringstream contents;
    contents << std::ifstream(path).rdbuf();
    return contents.str();
}

// [first, past) of the block in `text`, if there.
std::optional<std::pair<std::size_t, std::size_t>> locate(const std::string& text, std::string_view begin, std::string_view end) {
    const auto first = text.find(begin);
    const auto last = first == std::string::npos ? std::string::npos : text.find(end, first);
    if (last == std::string::npos) return std::nullopt;
    std::size_t past = last + end.size();
    if (past < text.size() && text[past] == '\n') ++past;
    return std::make_pair(first, past);
}

}  // namespace

std::optional<std::string> find_block(const std::filesystem::path& path, std::string_view begin, std::string_view end) {
    const std::string text = read_text(path);
    const auto range = locate(text, begin, end);
    if (!range) return std::nullopt;
    return text.substr(range->first, range->second - range->first);
}

void splice_block(const std::filesystem::path& path, std::string_view begin, std::string_view end, const std::string& block) {
    std::string text = read_text(path);
    if (const auto range = locate(text, begin, end)) {
        text.replace(range->first, range->second - range->first, block);
    } else {
        if (!text.empty() && text.back() != '\n') text += '\n';
        text += (text.empty() ? "" : "\n") + block;
    }
    std::ofstream(path) << text;
}

}  // namespace bounce::bench
