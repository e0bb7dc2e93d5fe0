// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_lexer.cpp
/// The RIB tokenizer: white space and comments, numbers, strings with their
/// escapes, words and bracketed arrays, grouped into statements.

#include "rib_lexer.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

#include "sss/scene/rib.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"

namespace sss::rib {

namespace {

bool is_word_start(char c) {
    return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
}

bool is_word_char(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
}

} // namespace

const char* describe(const Value& v) {
    switch (v.kind) {
    case Value::Kind::Number:
        return "a number";
    case Value::Kind::String:
        return "a string";
    case Value::Kind::Array:
        return "an array";
    }
    return "?";
}

bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

std::string lower(std::string_view s) {
    std::string out(s);
    for (char& c : out)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

bool parse_number(std::string_view text, double& out, std::string& error) {
    // Echoed cut: a token may be as long as Limit::TokenLength allows.
    const std::string shown = truncated(text, kMaxEcho);
    std::string_view t = text;
    if (!t.empty() && t[0] == '+') t.remove_prefix(1);
    if (t.empty() || t[0] == '+') {
        error = "malformed number '" + shown + "'";
        return false;
    }
    auto r = std::from_chars(t.data(), t.data() + t.size(), out);
    if (r.ec == std::errc::result_out_of_range) {
        error = "number '" + shown + "' out of range";
        return false;
    }
    if (r.ec != std::errc() || r.ptr != t.data() + t.size()) {
        error = "malformed number '" + shown + "'";
        return false;
    }
    if (!std::isfinite(out)) {
        error = "not a finite number: '" + shown + "'";
        return false;
    }
    return true;
}

Lexer::Lexer(std::string_view text, std::shared_ptr<const std::string> path)
    : m_text(text), m_path(std::move(path)), m_max_string(limit(Limit::StringLength)),
      m_max_token(limit(Limit::TokenLength)) {
    if (m_text.size() >= 2 && static_cast<unsigned char>(m_text[0]) == 0x1f &&
        static_cast<unsigned char>(m_text[1]) == 0x8b)
        throw RibError(*m_path, 0, "",
                       "gzip-compressed RIB is not supported (gunzip it first)");
    if (m_text.starts_with("\xef\xbb\xbf")) m_pos = 3; // UTF-8 byte order mark
}

bool Lexer::next(Statement& st) {
    Token t = take();
    if (t.kind == Tok::End) return false;
    if (t.kind != Tok::Word)
        fail(t.line, "", std::string("expected a statement name, got ") + tok_name(t));
    st.name = std::move(t.text);
    m_statement = st.name;
    st.line = t.line;
    st.file = m_path;
    st.args.clear();
    for (;;) {
        Token a = take();
        if (a.kind == Tok::Word || a.kind == Tok::End) {
            m_peek = std::move(a);
            m_has_peek = true;
            return true;
        }
        Value v;
        if (a.kind == Tok::Number) {
            v.kind = Value::Kind::Number;
            v.number = a.number;
        } else if (a.kind == Tok::String) {
            v.kind = Value::Kind::String;
            v.string = std::move(a.text);
        } else if (a.kind == Tok::Open) {
            read_array(st, a.line, v);
        } else {
            fail(a.line, st.name, "unexpected ']'");
        }
        if (st.args.size() == st.args.capacity())
            check_growth(st.args.size(), sizeof(Value), st.line, "arguments");
        st.args.push_back(std::move(v));
    }
}

void Lexer::fail(int line, const std::string& statement, const std::string& what) {
    throw RibError(*m_path, line, statement, what);
}

std::string Lexer::where(int line) const {
    std::string out = *m_path + ":" + std::to_string(line);
    if (!m_statement.empty()) out += ": " + m_statement;
    return out;
}

void Lexer::check_token(std::size_t length, int line, bool word) const {
    // A word may be the next request's name: no statement then.
    if (length > m_max_token)
        check_limit(Limit::TokenLength, length,
                    word ? *m_path + ":" + std::to_string(line) : where(line));
}

void Lexer::check_growth(std::size_t count, std::size_t element_bytes, int line,
                         const char* what) const {
    // At each doubling from 65536 elements: the vector is about to take
    // twice its size (and its old block is alive while it moves). The text
    // is in memory already, and 2 bytes of it ("0 ") can make a 100-byte
    // argument: this is where a large file becomes a memory bomb.
    if (count < 65536 || (count & (count - 1)) != 0) return;
    check_memory(uint64_t(count) * 3 * element_bytes,
                 where(line) + ": more than " + std::to_string(count) + " " + what,
                 "split the data into smaller statements");
}

std::string Lexer::tok_name(const Token& t) {
    switch (t.kind) {
    case Tok::End:
        return "the end of the file";
    case Tok::Word:
        return std::string("'").append(truncated(t.text, kMaxEcho)).append("'");
    case Tok::Number:
        return "a number";
    case Tok::String:
        return "a string";
    case Tok::Open:
        return "'['";
    case Tok::Close:
        return "']'";
    }
    return "?";
}

void Lexer::read_array(const Statement& st, int open_line, Value& v) {
    v.kind = Value::Kind::Array;
    for (;;) {
        Token t = take();
        switch (t.kind) {
        case Tok::Number:
            if (!v.strings.empty())
                fail(t.line, st.name, "array mixes strings and numbers");
            if (v.numbers.size() == v.numbers.capacity())
                check_growth(v.numbers.size(), sizeof(double), open_line,
                             "numbers in one array");
            v.numbers.push_back(t.number);
            break;
        case Tok::String:
            if (!v.numbers.empty())
                fail(t.line, st.name, "array mixes numbers and strings");
            if (v.strings.size() == v.strings.capacity())
                check_growth(v.strings.size(), sizeof(std::string) + 16, open_line,
                             "strings in one array");
            v.strings.push_back(std::move(t.text));
            v.string_array = true;
            break;
        case Tok::Close:
            return;
        case Tok::Open:
            fail(t.line, st.name, "nested '[' inside an array");
        case Tok::Word:
            fail(open_line, st.name,
                 "unterminated array: no ']' before '" + truncated(t.text, kMaxEcho) +
                     "' on line " + std::to_string(t.line));
        case Tok::End:
            fail(open_line, st.name, "end of file inside an array");
        }
    }
}

Lexer::Token Lexer::take() {
    if (m_has_peek) {
        m_has_peek = false;
        return std::move(m_peek);
    }
    return scan();
}

Lexer::Token Lexer::scan() {
    const std::size_t n = m_text.size();
    // Whitespace and comments ("##RenderMan RIB" headers are comments too).
    while (m_pos < n) {
        char c = m_text[m_pos];
        if (c == '\n') {
            ++m_line;
            ++m_pos;
        } else if (is_space(c)) {
            ++m_pos;
        } else if (c == '#') {
            while (m_pos < n && m_text[m_pos] != '\n') ++m_pos;
        } else {
            break;
        }
    }
    Token t;
    t.line = m_line;
    if (m_pos >= n) return t;
    char c = m_text[m_pos];
    auto uc = static_cast<unsigned char>(c);
    if (c == '"') {
        t.kind = Tok::String;
        t.text = scan_string();
    } else if (c == '[') {
        t.kind = Tok::Open;
        ++m_pos;
    } else if (c == ']') {
        t.kind = Tok::Close;
        ++m_pos;
    } else if (std::isdigit(uc) || c == '+' || c == '-' || c == '.') {
        std::size_t start = m_pos;
        while (m_pos < n && !is_space(m_text[m_pos]) && m_text[m_pos] != '[' &&
               m_text[m_pos] != ']' && m_text[m_pos] != '"' && m_text[m_pos] != '#')
            ++m_pos;
        check_token(m_pos - start, t.line, false);
        std::string error;
        if (!parse_number(m_text.substr(start, m_pos - start), t.number, error))
            fail(t.line, m_statement, error);
        t.kind = Tok::Number;
    } else if (is_word_start(c)) {
        std::size_t start = m_pos;
        while (m_pos < n && is_word_char(m_text[m_pos])) ++m_pos;
        check_token(m_pos - start, t.line, true);
        t.kind = Tok::Word;
        t.text = std::string(m_text.substr(start, m_pos - start));
        std::string l = lower(t.text);
        // A writer printing a NaN or Inf bare would otherwise look like a request.
        if (l == "nan" || l == "inf" || l == "infinity")
            fail(t.line, m_statement,
                 "not a finite number: '" + truncated(t.text, 10) + "'");
    } else if (uc >= 0x80 || uc < 0x20 || uc == 0x7f) {
        char hex[8];
        std::snprintf(hex, sizeof hex, "0x%02x", uc);
        fail(t.line, "",
             std::string("binary RIB is not supported (byte ") + hex +
                 "); convert it to ASCII RIB first");
    } else {
        fail(t.line, m_statement,
             "unexpected character " + sss::quoted(std::string(1, c)));
    }
    return t;
}

std::string Lexer::scan_string() {
    const std::size_t n = m_text.size();
    const int start_line = m_line;
    ++m_pos; // opening quote
    std::string out;
    const std::size_t start = m_pos;
    while (m_pos < n) {
        if (out.size() > m_max_string) {
            // Its whole length (escapes counted as written), for the message.
            std::size_t end = start;
            while (end < n && m_text[end] != '"') end += m_text[end] == '\\' ? 2 : 1;
            check_limit(Limit::StringLength, std::min(end, n) - start, where(start_line));
        }
        char c = m_text[m_pos++];
        if (c == '"') return out;
        if (c == '\n') ++m_line;
        if (c != '\\') {
            out.push_back(c);
            continue;
        }
        if (m_pos >= n) break;
        char e = m_text[m_pos++];
        switch (e) {
        case 'n':
            out.push_back('\n');
            break;
        case 't':
            out.push_back('\t');
            break;
        case 'r':
            out.push_back('\r');
            break;
        case 'b':
            out.push_back('\b');
            break;
        case 'f':
            out.push_back('\f');
            break;
        case '\n': // line continuation
            ++m_line;
            break;
        default:
            if (e >= '0' && e <= '7') {
                int code = e - '0';
                for (int k = 0;
                     k < 2 && m_pos < n && m_text[m_pos] >= '0' && m_text[m_pos] <= '7';
                     ++k)
                    code = code * 8 + (m_text[m_pos++] - '0');
                out.push_back(static_cast<char>(code & 0xff));
            } else {
                out.push_back(e); // \\, \" and any other escaped character
            }
        }
    }
    fail(start_line, m_statement, "unterminated string (no closing '\"')");
}

} // namespace sss::rib
