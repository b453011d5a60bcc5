#include "renderer/gpu/bounds_check.hpp"

#include "renderer/base/error.hpp"
#include "renderer/gpu/shader_program.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <set>
#include <string_view>

namespace bounce::gpu {
namespace {

// Sites are numbered for the whole process: programs compile on several contexts.
struct SiteRegistry {
    std::mutex mutex;
    std::vector<std::string> sites;

    unsigned add(std::string description) {
        std::lock_guard lock(mutex);
        sites.push_back(std::move(description));
        return static_cast<unsigned>(sites.size() - 1);
    }
    std::string get(unsigned site) {
        std::lock_guard lock(mutex);
        return site < sites.size() ? sites[site] : fmt::format("unknown site {}", site);
    }
};

SiteRegistry& registry() {
    static SiteRegistry sites;
    return sites;
}

bool identifier_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool identifier_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Words that may stand before an indexed name without declaring it.
bool statement_word(const std::string& word) {
    static const std::set<std::string> words = {"return", "else", "case", "do"};
    return words.contains(word);
}

// The text as tokens the checker cares about: identifiers, and every other non-blank character
// alone. Comments are dropped; preprocessor directives are kept whole as one token, so their
// contents are rewritten only where they are macro definitions.
struct Token {
    enum class Kind { identifier, symbol, directive } kind;
    std::size_t begin, end;  // in the text
};

std::vector<Token> tokenize(const std::string& text, bool directives) {
    std::vector<Token> tokens;
    std::size_t i = 0;
    bool line_start = true;
    while (i < text.size()) {
        const char c = text[i];
        if (c == '\n') {
            line_start = true;
            ++i;
        } else if (std::isspace(static_cast<unsigned char>(c))) {
            ++i;
        } else if (text.compare(i, 2, "//") == 0) {
            while (i < text.size() && text[i] != '\n') ++i;
        } else if (text.compare(i, 2, "/*") == 0) {
            const std::size_t close = text.find("*/", i + 2);
            i = close == std::string::npos ? text.size() : close + 2;
        } else if (c == '#' && line_start && directives) {
            std::size_t end = i;
            while (end < text.size() && !(text[end] == '\n' && text[end - 1] != '\\')) ++end;
            tokens.push_back({Token::Kind::directive, i, end});
            i = end;
        } else if (identifier_start(c)) {
            std::size_t end = i;
            while (end < text.size() && identifier_char(text[end])) ++end;
            tokens.push_back({Token::Kind::identifier, i, end});
            i = end;
            line_start = false;
        } else {
            tokens.push_back({Token::Kind::symbol, i, i + 1});
            ++i;
            line_start = false;
        }
    }
    return tokens;
}

// File and line of each offset in an expanded source, from its #line directives.
class LineMap {
public:
    explicit LineMap(const ExpandedSource& source) : files_(source.files) {
        int file = 0, line = 1;
        for (std::size_t i = 0, start = 0; i <= source.text.size(); ++i) {
            if (i < source.text.size() && source.text[i] != '\n') continue;
            starts_.push_back({start, file, line});
            const std::string_view text(source.text.data() + start, i - start);
            int number = 0, file_number = 0;
            if (text.rfind("#line ", 0) == 0 &&
                std::sscanf(std::string(text).c_str(), "#line %d %d", &number, &file_number) == 2) {
                line = number;
                file = file_number;
            } else {
                ++line;
            }
            start = i + 1;
        }
    }
    std::string where(std::size_t offset) const {
        auto it = std::upper_bound(starts_.begin(), starts_.end(), offset,
                                   [](std::size_t o, const Start& s) { return o < s.offset; });
        const Start& s = *std::prev(it);
        const std::string file = s.file >= 0 && static_cast<std::size_t>(s.file) < files_.size() ? files_[s.file] : "?";
        return fmt::format("{}:{}", file, s.line);
    }

private:
    struct Start {
        std::size_t offset;
        int file, line;
    };
    std::vector<std::string> files_;
    std::vector<Start> starts_;
};

class Rewriter {
public:
    // `directives`: whether preprocessor lines are single tokens (false for a macro body).
    explicit Rewriter(const ExpandedSource& source, bool directives = true)
        : text_(source.text), lines_(source), tokens_(tokenize(source.text, directives)) {
        find_arrays();
    }
    bool has_arrays() const { return !arrays_.empty(); }

    std::string rewrite() { return rewrite_span(0, tokens_.size(), 0, text_.size(), arrays_); }

private:
    std::string word(std::size_t t) const { return text_.substr(tokens_[t].begin, tokens_[t].end - tokens_[t].begin); }
    bool is(std::size_t t, char c) const {
        return t < tokens_.size() && tokens_[t].kind == Token::Kind::symbol && text_[tokens_[t].begin] == c;
    }

    // The token index of the bracket closing the one at `open`, or tokens_.size().
    std::size_t matching(std::size_t open) const {
        int depth = 0;
        for (std::size_t t = open; t < tokens_.size(); ++t) {
            if (tokens_[t].kind == Token::Kind::directive) return tokens_.size();
            if (is(t, '[') || is(t, '(')) ++depth;
            if (is(t, ']') || is(t, ')')) --depth;
            if (depth == 0) return t;
        }
        return tokens_.size();
    }

    // A name declared as an array: `TYPE name[...]` in a block, a struct, a function or a statement.
    bool declaration(std::size_t t) const {
        if (t == 0 || tokens_[t - 1].kind != Token::Kind::identifier) return false;
        return !statement_word(word(t - 1));
    }

    void find_arrays() {
        for (std::size_t t = 0; t + 1 < tokens_.size(); ++t) {
            if (tokens_[t].kind == Token::Kind::identifier && is(t + 1, '[') && declaration(t) &&
                !(t > 0 && is(t - 1, '.'))) {
                arrays_.insert(word(t));
            }
        }
    }

    // Whether token t is an indexed use of one of `arrays` (not its declaration, not a member).
    bool checked_access(std::size_t t, const std::set<std::string>& arrays, std::size_t& close) const {
        if (tokens_[t].kind != Token::Kind::identifier || !is(t + 1, '[') || !arrays.contains(word(t))) return false;
        if (declaration(t) || (t > 0 && is(t - 1, '.'))) return false;
        close = matching(t + 1);
        return close < tokens_.size() && close > t + 2;  // an empty [] indexes nothing
    }

    // `name[index]` as `name[bounce_checked(uint(index), uint(name.length()), site)]`, with the
    // accesses inside the index checked too.
    std::string checked(std::size_t t, std::size_t close, const std::set<std::string>& arrays) {
        const std::string name = word(t);
        const std::string index = rewrite_span(t + 2, close, tokens_[t + 2].begin, tokens_[close].begin, arrays);
        const std::string original = text_.substr(tokens_[t].begin, tokens_[close].end - tokens_[t].begin);
        const unsigned site = registry().add(fmt::format("{}: {}", lines_.where(offset_ + tokens_[t].begin), original));
        return fmt::format("{}[bounce_checked(uint({}), uint({}.length()), {}u)]", name, index, name, site);
    }

    // The text from offset `from` to `to`, which holds tokens [first, last), with every checked access
    // among them rewritten, and every macro definition (rewrite_directive).
    std::string rewrite_span(std::size_t first, std::size_t last, std::size_t from, std::size_t to,
                             const std::set<std::string>& arrays) {
        std::string out;
        std::size_t copied = from;
        for (std::size_t t = first; t < last; ++t) {
            std::string replacement;
            std::size_t end = t;
            if (tokens_[t].kind == Token::Kind::directive) {
                replacement = rewrite_directive(tokens_[t]);
            } else if (checked_access(t, arrays, end)) {
                replacement = checked(t, end, arrays);
            } else {
                continue;
            }
            out.append(text_, copied, tokens_[t].begin - copied);
            out += replacement;
            copied = tokens_[end].end;
            t = end;
        }
        out.append(text_, copied, to - copied);
        return out;
    }

    // A macro's body may index a parameter that stands for an array (`buffer[index]`, with the
    // buffer passed in): those are checked; other directives are left alone.
    std::string rewrite_directive(const Token& directive) {
        const std::string text = text_.substr(directive.begin, directive.end - directive.begin);
        static const std::string define = "#define ";
        if (text.rfind(define, 0) != 0) return text;
        Rewriter inner(ExpandedSource{text, {}}, false);
        inner.lines_ = lines_;
        inner.offset_ = directive.begin;
        std::set<std::string> parameters;
        std::size_t t = 2;  // '#', 'define', the macro's name, then '(' directly after it
        if (inner.tokens_.size() > 3 && inner.is(3, '(') && inner.tokens_[3].begin == inner.tokens_[2].end) {
            for (t = 4; t < inner.tokens_.size() && !inner.is(t, ')'); ++t) {
                if (inner.tokens_[t].kind == Token::Kind::identifier) parameters.insert(inner.word(t));
            }
        }
        std::set<std::string> arrays = arrays_;
        arrays.insert(parameters.begin(), parameters.end());
        const std::size_t from = t < inner.tokens_.size() ? inner.tokens_[t].begin : text.size();
        return text.substr(0, from) + inner.rewrite_span(t, inner.tokens_.size(), from, text.size(), arrays);
    }

    std::string text_;
    LineMap lines_;
    std::vector<Token> tokens_;
    std::set<std::string> arrays_;
    std::size_t offset_ = 0;  // where text_ starts in the source lines_ maps (macro bodies)
};

}  // namespace

bool shader_bounds_checks_enabled() {
    static const bool enabled = [] {
        const char* value = std::getenv("BOUNCE_SHADER_BOUNDS_CHECK");
        return value != nullptr && std::string(value) != "" && std::string(value) != "0";
    }();
    return enabled;
}

ExpandedSource insert_bounds_checks(const ExpandedSource& source, unsigned binding) {
    Rewriter rewriter(source);
    if (!rewriter.has_arrays()) return source;
    std::string body = rewriter.rewrite();
    // The checker goes after #version and #extension (which must come before any code) and before
    // anything that uses it.
    BOUNCE_CHECK(body.rfind("#version", 0) == 0, "a shader to check starts with its #version line");
    std::size_t line_end = body.find('\n');
    while (line_end != std::string::npos && body.compare(line_end + 1, 10, "#extension") == 0) {
        line_end = body.find('\n', line_end + 1);
    }
    BOUNCE_CHECK(line_end != std::string::npos, "a shader to check has code after its #version line");
    const std::string checker = fmt::format(
        "layout(std430, binding = {}) coherent buffer BounceBoundsCheck {{ uint bounce_bounds_check[]; }};\n"
        "uint bounce_checked(uint index, uint length, uint site) {{\n"
        "    if (index < length) return index;\n"
        "    if (atomicAdd(bounce_bounds_check[0], 1u) == 0u) {{\n"
        "        bounce_bounds_check[1] = site;\n"
        "        bounce_bounds_check[2] = index;\n"
        "        bounce_bounds_check[3] = length;\n"
        "    }}\n"
        "    return 0u;\n"
        "}}\n",
        binding);
    body.insert(line_end + 1, checker);
    return {std::move(body), source.files};
}

std::string bounds_check_site(unsigned site) { return registry().get(site); }

std::string BoundsViolation::describe() const {
    return fmt::format("{} shader array access{} out of bounds; the first: {} read index {} of an array of {}", count,
                       count == 1 ? " was" : "es were", site, index, length);
}

BoundsCheckBuffer::BoundsCheckBuffer(unsigned binding) : binding_(binding), counters_(4) {}

void BoundsCheckBuffer::bind() const { counters_.bind(binding_); }

std::optional<BoundsViolation> BoundsCheckBuffer::take() {
    const CounterValues values = counters_.read();
    if (values[0] == 0) return std::nullopt;
    counters_.reset();
    return BoundsViolation{values[0], bounds_check_site(values[1]), values[2], values[3]};
}

}  // namespace bounce::gpu
