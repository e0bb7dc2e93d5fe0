// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file lexer.cpp
/// The RSL tokenizer: identifiers and keywords, numbers (all floats: `1`,
/// `1.`, `.5`, exponents, a trailing `f`), strings with C escapes (adjacent
/// literals joined), operators, and the comments a text that skipped the
/// preprocessor may still hold.

#include "lexer.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>

namespace sss::detail {

namespace {

// The shader kinds (surface, light, volume...) are not reserved: PRMan
// reads them as kinds only where a shader is defined, and shaders name
// variables `light` and call surface() and displacement().
constexpr std::string_view kKeywords[] = {
    "float", "color",   "point",   "vector",      "normal", "matrix",      "string",
    "void",  "uniform", "varying", "output",      "extern", "if",          "else",
    "while", "for",     "break",   "continue",    "return", "illuminance", "illuminate",
    "solar", "gather",  "texture", "environment", "shadow", "bump"};

bool reserved(std::string_view w) {
    return std::find(std::begin(kKeywords), std::end(kKeywords), w) !=
           std::end(kKeywords);
}

bool ident_start(char c) {
    return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
}
bool ident_char(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
}
bool digit(char c) {
    return std::isdigit(static_cast<unsigned char>(c)) != 0;
}

class Scanner {
public:
    Scanner(const std::string& text, DiagnosticSink& diags)
        : m_text(text), m_diags(diags) {}

    std::vector<Token> run() {
        std::vector<Token> out;
        for (;;) {
            skip_space();
            Token t;
            t.loc = loc();
            if (m_pos >= m_text.size()) {
                out.push_back(std::move(t));
                break;
            }
            const char c = m_text[m_pos];
            if (ident_start(c)) {
                std::size_t b = m_pos;
                while (m_pos < m_text.size() && ident_char(m_text[m_pos])) advance();
                t.text = m_text.substr(b, m_pos - b);
                t.kind = reserved(t.text) ? TokKind::Keyword : TokKind::Ident;
            } else if (digit(c) || (c == '.' && m_pos + 1 < m_text.size() &&
                                    digit(m_text[m_pos + 1]))) {
                number(t);
            } else if (c == '"') {
                string(t);
                if (!out.empty() && out.back().kind == TokKind::String) {
                    out.back().text += t.text; // "a" "b" is "ab"
                    continue;
                }
            } else if (c == '#' && at_line_start()) {
                directive();
                continue;
            } else if (!punct(t)) {
                m_diags.error(t.loc, std::string("unexpected character ") + shown(c));
                advance();
                continue;
            }
            out.push_back(std::move(t));
        }
        return out;
    }

private:
    SrcLoc loc() const { return {m_line, static_cast<int>(m_pos - m_line_start) + 1}; }

    void advance() {
        if (m_text[m_pos] == '\n') {
            ++m_line;
            m_line_start = m_pos + 1;
        }
        ++m_pos;
    }

    static std::string shown(char c) {
        if (std::isprint(static_cast<unsigned char>(c)))
            return std::string("'") + c + "'";
        static const char* hex = "0123456789abcdef";
        const unsigned char u = static_cast<unsigned char>(c);
        return std::string("0x") + hex[u >> 4] + hex[u & 15];
    }

    bool at_line_start() const {
        for (std::size_t i = m_line_start; i < m_pos; ++i)
            if (m_text[i] != ' ' && m_text[i] != '\t') return false;
        return true;
    }

    void skip_space() {
        while (m_pos < m_text.size()) {
            const char c = m_text[m_pos];
            if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' ||
                c == '\v') {
                advance();
            } else if (c == '/' && m_pos + 1 < m_text.size() &&
                       m_text[m_pos + 1] == '/') {
                while (m_pos < m_text.size() && m_text[m_pos] != '\n') advance();
            } else if (c == '/' && m_pos + 1 < m_text.size() &&
                       m_text[m_pos + 1] == '*') {
                const SrcLoc at = loc();
                advance();
                advance();
                while (m_pos < m_text.size() &&
                       !(m_text[m_pos] == '*' && m_pos + 1 < m_text.size() &&
                         m_text[m_pos + 1] == '/'))
                    advance();
                if (m_pos >= m_text.size()) {
                    m_diags.error(at, "unterminated comment");
                    return;
                }
                advance();
                advance();
            } else {
                return;
            }
        }
    }

    // A directive the preprocessor left (#pragma) or text that was not
    // preprocessed: #pragma is ignored, anything else is an error.
    void directive() {
        const SrcLoc at = loc();
        std::size_t b = m_pos;
        while (m_pos < m_text.size() && m_text[m_pos] != '\n') advance();
        std::string line = m_text.substr(b, m_pos - b);
        std::size_t w = line.find_first_not_of(" \t", 1);
        if (w != std::string::npos && line.compare(w, 6, "pragma") == 0) return;
        m_diags.error(at, "preprocessor directive in preprocessed text");
    }

    void number(Token& t) {
        t.kind = TokKind::Number;
        std::size_t b = m_pos;
        while (m_pos < m_text.size() && digit(m_text[m_pos])) advance();
        if (m_pos < m_text.size() && m_text[m_pos] == '.') {
            advance();
            while (m_pos < m_text.size() && digit(m_text[m_pos])) advance();
        }
        if (m_pos < m_text.size() && (m_text[m_pos] == 'e' || m_text[m_pos] == 'E')) {
            std::size_t save = m_pos;
            std::size_t k = m_pos + 1;
            if (k < m_text.size() && (m_text[k] == '+' || m_text[k] == '-')) ++k;
            if (k < m_text.size() && digit(m_text[k])) {
                while (m_pos < k) advance();
                while (m_pos < m_text.size() && digit(m_text[m_pos])) advance();
            } else {
                m_pos = save;
            }
        }
        t.text = m_text.substr(b, m_pos - b);
        t.number = std::strtod(t.text.c_str(), nullptr);
        if (!std::isfinite(t.number) || std::fabs(t.number) > 3.4e38) {
            m_diags.error(t.loc, "number '" + t.text + "' is out of range");
            t.number = 0.0;
        }
        if (m_pos < m_text.size() && (m_text[m_pos] == 'f' || m_text[m_pos] == 'F')) {
            advance();
        } else if (m_pos < m_text.size() && ident_char(m_text[m_pos])) {
            // 0x1f, 1u, 2L...: Aqsis forms we do not accept.
            const SrcLoc at = loc();
            while (m_pos < m_text.size() && ident_char(m_text[m_pos])) advance();
            m_diags.error(at, "malformed number '" + m_text.substr(b, m_pos - b) + "'");
        }
    }

    void string(Token& t) {
        t.kind = TokKind::String;
        advance(); // opening quote
        for (;;) {
            if (m_pos >= m_text.size() || m_text[m_pos] == '\n') {
                m_diags.error(t.loc, "unterminated string");
                return;
            }
            char c = m_text[m_pos];
            advance();
            if (c == '"') return;
            if (c != '\\') {
                t.text += c;
                continue;
            }
            if (m_pos >= m_text.size()) continue;
            char e = m_text[m_pos];
            advance();
            switch (e) {
            case 'n':
                t.text += '\n';
                break;
            case 't':
                t.text += '\t';
                break;
            case 'r':
                t.text += '\r';
                break;
            case 'a':
                t.text += '\a';
                break;
            case 'b':
                t.text += '\b';
                break;
            case 'f':
                t.text += '\f';
                break;
            case 'v':
                t.text += '\v';
                break;
            case '\\':
                t.text += '\\';
                break;
            case '"':
                t.text += '"';
                break;
            case '\'':
                t.text += '\'';
                break;
            case '?':
                t.text += '?';
                break;
            case '\n':
                break; // line splice
            case 'x': {
                int v = 0, n = 0;
                while (n < 2 && m_pos < m_text.size() &&
                       std::isxdigit(static_cast<unsigned char>(m_text[m_pos]))) {
                    char h = m_text[m_pos];
                    v = v * 16 + (digit(h) ? h - '0' : (std::tolower(h) - 'a' + 10));
                    advance();
                    ++n;
                }
                t.text += static_cast<char>(v);
                break;
            }
            default:
                if (e >= '0' && e <= '7') {
                    int v = e - '0', n = 1;
                    while (n < 3 && m_pos < m_text.size() && m_text[m_pos] >= '0' &&
                           m_text[m_pos] <= '7') {
                        v = v * 8 + (m_text[m_pos] - '0');
                        advance();
                        ++n;
                    }
                    t.text += static_cast<char>(v);
                } else {
                    t.text += e;
                }
            }
        }
    }

    bool punct(Token& t) {
        // "->" calls a co-shader's method (RSL 2.0): `s->method(...)`.
        static constexpr std::array<std::string_view, 13> two = {
            "+=", "-=", "*=", "/=", "==", "!=", "<=", ">=", "&&", "||", "++", "--", "->"};
        t.kind = TokKind::Punct;
        if (m_pos + 1 < m_text.size()) {
            std::string_view s(m_text.data() + m_pos, 2);
            if (std::find(two.begin(), two.end(), s) != two.end()) {
                t.text = std::string(s);
                advance();
                advance();
                return true;
            }
        }
        static const std::string_view one = "+-*/^.=<>!?:()[]{},;";
        if (one.find(m_text[m_pos]) == std::string_view::npos) return false;
        t.text = std::string(1, m_text[m_pos]);
        advance();
        return true;
    }

    const std::string& m_text;
    DiagnosticSink& m_diags;
    std::size_t m_pos = 0;
    std::size_t m_line_start = 0;
    int m_line = 0;
};

} // namespace

bool is_keyword(std::string_view word) {
    return reserved(word);
}

std::vector<Token> tokenize(const std::string& text, DiagnosticSink& diags) {
    return Scanner(text, diags).run();
}

std::string describe(const Token& t) {
    switch (t.kind) {
    case TokKind::End:
        return "the end of the file";
    case TokKind::Number:
        return "the number " + t.text;
    case TokKind::String:
        return "a string";
    default:
        return "'" + t.text + "'";
    }
}

} // namespace sss::detail
