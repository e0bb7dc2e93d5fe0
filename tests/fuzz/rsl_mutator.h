#pragma once
// Grammar-aware mutation of RSL source for fuzz_shader (docs/fuzzing.md):
// the text is split into tokens (identifiers and keywords, numbers,
// strings, punctuation; whitespace and comments stay with the token they
// precede) and changed a token at a time, so that most mutants still lex
// and many still parse, reaching the checker and the code generator rather
// than the lexer's first error. The libFuzzer hook itself is in
// fuzz_shader.cpp (only in the fuzzing build; the replay driver has no
// LLVMFuzzerMutate).

#include <cctype>
#include <cstdint>
#include <random>
#include <string>
#include <string_view>
#include <vector>

namespace sss::fuzz {

/// One token: [start, end) in the text; `space` is where the whitespace and
/// comments before it begin.
struct RslToken {
    std::size_t space, start, end;
    bool identifier;
};

/// The tokens of RSL text, roughly as the lexer sees them (exactness does
/// not matter: a mutant is only a new input).
inline std::vector<RslToken> rsl_tokens(std::string_view s) {
    std::vector<RslToken> tokens;
    std::size_t i = 0;
    while (i < s.size()) {
        const std::size_t space = i;
        for (;;) { // whitespace and comments
            if (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) {
                ++i;
            } else if (s.compare(i, 2, "//") == 0) {
                while (i < s.size() && s[i] != '\n') ++i;
            } else if (s.compare(i, 2, "/*") == 0) {
                const std::size_t e = s.find("*/", i + 2);
                i = e == std::string_view::npos ? s.size() : e + 2;
            } else {
                break;
            }
        }
        if (i >= s.size()) break;
        const std::size_t start = i;
        const unsigned char c = static_cast<unsigned char>(s[i]);
        bool identifier = false;
        if (std::isalpha(c) || c == '_') {
            identifier = true;
            while (i < s.size() &&
                   (std::isalnum(static_cast<unsigned char>(s[i])) || s[i] == '_'))
                ++i;
        } else if (std::isdigit(c) ||
                   (c == '.' && i + 1 < s.size() &&
                    std::isdigit(static_cast<unsigned char>(s[i + 1])))) {
            while (
                i < s.size() &&
                (std::isalnum(static_cast<unsigned char>(s[i])) || s[i] == '.' ||
                 ((s[i] == '+' || s[i] == '-') && (s[i - 1] == 'e' || s[i - 1] == 'E'))))
                ++i;
        } else if (c == '"') {
            ++i;
            while (i < s.size() && s[i] != '"' && s[i] != '\n') i += s[i] == '\\' ? 2 : 1;
            i = std::min(i + 1, s.size());
        } else {
            static const char* const kTwo[] = {"==", "!=", "<=", ">=", "&&", "||", "+=",
                                               "-=", "*=", "/=", "->", "++", "--"};
            i += 1;
            for (const char* op : kTwo)
                if (s.compare(start, 2, op) == 0) i = start + 2;
        }
        tokens.push_back({space, start, i, identifier});
    }
    return tokens;
}

/// Keywords, types, shadeops and globals to insert or to put in place of an
/// identifier.
inline const std::vector<std::string>& rsl_words() {
    static const std::vector<std::string> words{
        "surface",     "light",       "displacement",
        "volume",      "imager",      "class",
        "float",       "color",       "point",
        "vector",      "normal",      "matrix",
        "string",      "void",        "shader",
        "uniform",     "varying",     "output",
        "extern",      "return",      "if",
        "else",        "for",         "while",
        "break",       "continue",    "illuminance",
        "illuminate",  "solar",       "gather",
        "texture",     "environment", "shadow",
        "textureinfo", "texture3d",   "bake3d",
        "trace",       "occlusion",   "diffuse",
        "specular",    "ambient",     "normalize",
        "faceforward", "noise",       "mix",
        "smoothstep",  "printf",      "format",
        "concat",      "transform",   "arraylength",
        "push",        "resize",      "comp",
        "setcomp",     "getshader",   "getlights",
        "Ci",          "Oi",          "Cs",
        "Os",          "P",           "N",
        "Ng",          "I",           "L",
        "Cl",          "s",           "t",
        "u",           "v",           "du",
        "PI",          "1e30",        "0",
        "-1",          "\"\"",        "\"world\"",
        "[",           "]",           "{",
        "}",           "(",           ")",
        ";",           ",",           "=",
        "?",           ":",           "."};
    return words;
}

/// Applies one token-level change to `text`; false when none applies (the
/// caller falls back to libFuzzer's byte-level mutation).
inline bool mutate_rsl(std::string& text, std::minstd_rand& rng) {
    const std::vector<RslToken> tok = rsl_tokens(text);
    auto pick = [&](std::size_t n) { return n ? std::size_t(rng() % n) : 0; };
    const std::vector<std::string>& words = rsl_words();
    if (tok.empty()) {
        text += " " + words[pick(words.size())];
        return true;
    }
    // [a, b): a run of tokens with the whitespace before them.
    auto span = [&](std::size_t a, std::size_t b) {
        return text.substr(tok[a].space, tok[b - 1].end - tok[a].space);
    };
    auto replace = [&](std::size_t a, std::size_t b, const std::string& with) {
        text.replace(tok[a].space, tok[b - 1].end - tok[a].space, with);
    };
    // A balanced {...} or (...) starting at a random opening token.
    auto balanced = [&](std::size_t& a, std::size_t& b) {
        for (std::size_t tries = 0; tries < 8; ++tries) {
            const std::size_t i = pick(tok.size());
            const char open = text[tok[i].start];
            if (open != '{' && open != '(') continue;
            const char close = open == '{' ? '}' : ')';
            int depth = 0;
            for (std::size_t j = i; j < tok.size(); ++j) {
                const char c = tok[j].end - tok[j].start == 1 ? text[tok[j].start] : 0;
                depth += c == open ? 1 : c == close ? -1 : 0;
                if (depth == 0) {
                    a = i;
                    b = j + 1;
                    return true;
                }
            }
        }
        return false;
    };
    const std::size_t i = pick(tok.size()), j = pick(tok.size());
    std::size_t a = 0, b = 0;
    switch (rng() % 8) {
    case 0:
        replace(i, i + 1, "");
        return true; // delete a token
    case 1:
        text.insert(tok[i].space, span(i, i + 1));
        return true; // duplicate one
    case 2: {        // swap two
        if (i == j) return false;
        const std::size_t lo = std::min(i, j), hi = std::max(i, j);
        const std::string first = span(lo, lo + 1), second = span(hi, hi + 1);
        replace(hi, hi + 1, first);
        replace(lo, lo + 1, second);
        return true;
    }
    case 3: // delete or duplicate a balanced span
        if (!balanced(a, b)) return false;
        if (rng() % 2)
            replace(a, b, "");
        else
            text.insert(tok[b - 1].end, span(a, b));
        return true;
    case 4: { // an identifier becomes another one of the input
        std::vector<std::size_t> ids;
        for (std::size_t k = 0; k < tok.size(); ++k)
            if (tok[k].identifier) ids.push_back(k);
        if (ids.size() < 2) return false;
        const RslToken& from = tok[ids[pick(ids.size())]];
        const RslToken& to = tok[ids[pick(ids.size())]];
        text.replace(to.start, to.end - to.start,
                     text.substr(from.start, from.end - from.start));
        return true;
    }
    case 5: { // an identifier becomes a word of the language
        if (!tok[i].identifier) return false;
        text.replace(tok[i].start, tok[i].end - tok[i].start, words[pick(words.size())]);
        return true;
    }
    case 6: // insert a word before a token
        text.insert(tok[i].start, words[pick(words.size())] + " ");
        return true;
    default: // move a balanced span elsewhere
        if (!balanced(a, b)) return false;
        {
            const std::string moved = span(a, b);
            const std::size_t at = tok[j].space;
            if (at >= tok[a].space && at < tok[b - 1].end) return false;
            if (at > tok[a].space) {
                text.insert(at, moved);
                replace(a, b, "");
            } else {
                replace(a, b, "");
                text.insert(at, moved);
            }
        }
        return true;
    }
}

} // namespace sss::fuzz
