// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file preprocess.cpp
/// The C preprocessor for shaders (preprocess.h).
///
/// Each file is first cut into logical lines: line splices removed,
/// comments replaced by one space, every character keeping its physical
/// line and column. A logical line then is either a directive or text whose
/// macros are expanded with Prosser's hide-set algorithm (the one the C
/// standard's rules describe): every token carries the set of macros it came
/// out of, and a macro is not expanded again inside its own replacement.
///
/// Output: one line per logical line, followed by an empty line for every
/// further physical line it spanned (multi-line comments, splices, macro
/// arguments over several lines), so that the line map stays simple and the
/// compiler's line numbers stay right. Directives and skipped lines become
/// empty lines; an #include becomes the included file's lines.
///
/// Limits keep hostile input (fuzzers) bounded: include depth, macro
/// expansions, tokens in flight, output size, nesting of arguments and of
/// #if expressions.
///
/// This file: logical lines, tokens, files and output. Macro expansion,
/// directives and #if expressions are in preprocess_macros.cpp,
/// preprocess_directives.cpp and preprocess_expr.cpp (preprocess_internal.h).
#include "preprocess_internal.h"

namespace sss {

PreprocessError::PreprocessError(std::string file, int line, int column,
                                 const std::string& message,
                                 const std::string& source_line)
    : ValueError(file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " +
                 message),
      m_file(std::move(file)), m_line(line), m_column(column),
      m_source_line(source_line) {}

} // namespace sss

namespace sss::preprocess_detail {

std::vector<std::string> split_raw_lines(const std::string& data) {
    std::vector<std::string> lines;
    std::string cur;
    for (char c : data) {
        if (c == '\n') {
            if (!cur.empty() && cur.back() == '\r') cur.pop_back();
            lines.push_back(std::move(cur));
            cur.clear();
        } else {
            cur += c;
        }
    }
    if (!cur.empty()) lines.push_back(std::move(cur));
    return lines;
}

std::vector<Line> logical_lines(const std::string& data, const std::string& name,
                                const std::vector<std::string>& raw) {
    // Pass 1: remove backslash-newline splices (and the \r of \r\n).
    std::string c;
    std::vector<int> ln, cl;
    c.reserve(data.size());
    ln.reserve(data.size());
    cl.reserve(data.size());
    int line = 1, col = 1;
    for (size_t i = 0; i < data.size(); ++i) {
        const char ch = data[i];
        if (ch == '\\' && i + 1 < data.size() &&
            (data[i + 1] == '\n' ||
             (data[i + 1] == '\r' && i + 2 < data.size() && data[i + 2] == '\n'))) {
            i += data[i + 1] == '\r' ? 2 : 1;
            ++line;
            col = 1;
            continue;
        }
        if (ch == '\r' && i + 1 < data.size() && data[i + 1] == '\n') continue;
        c += ch;
        ln.push_back(line);
        cl.push_back(col);
        if (ch == '\n') {
            ++line;
            col = 1;
        } else {
            ++col;
        }
    }

    // Pass 2: comments, string literals, newlines.
    std::vector<Line> lines;
    Line cur;
    bool open = false; // something read since the last newline
    auto put = [&](char ch, size_t at) {
        cur.text += ch;
        cur.line.push_back(ln[at]);
        cur.col.push_back(cl[at]);
    };
    size_t j = 0;
    while (j < c.size()) {
        if (!open) {
            cur = Line();
            cur.first = ln[j];
            open = true;
        }
        const char ch = c[j];
        if (ch == '\n') {
            cur.last = ln[j];
            lines.push_back(std::move(cur));
            open = false;
            ++j;
        } else if (ch == '"' || ch == '\'') {
            // A literal runs to its closing quote or the end of the line;
            // comment markers inside it are text.
            put(ch, j++);
            while (j < c.size() && c[j] != '\n') {
                const char d = c[j];
                put(d, j++);
                if (d == '\\' && j < c.size() && c[j] != '\n') {
                    put(c[j], j);
                    ++j;
                } else if (d == ch) {
                    break;
                }
            }
        } else if (ch == '/' && j + 1 < c.size() && c[j + 1] == '*') {
            const size_t end = c.find("*/", j + 2);
            if (end == std::string::npos) {
                const int l = ln[j];
                throw PreprocessError(name, l, cl[j], "unterminated comment",
                                      l - 1 < static_cast<int>(raw.size()) ? raw[l - 1]
                                                                           : "");
            }
            // One space; as many as the comment's characters when it is
            // within one line, so that the columns after it stay right.
            const bool one_line = ln[end + 1] == ln[j];
            for (size_t k = j; k < (one_line ? end + 2 : j + 1); ++k) put(' ', k);
            j = end + 2;
        } else if (ch == '/' && j + 1 < c.size() && c[j + 1] == '/') {
            put(' ', j);
            while (j < c.size() && c[j] != '\n') ++j;
        } else {
            put(ch, j++);
        }
    }
    if (open) {
        cur.last = ln.back();
        lines.push_back(std::move(cur));
    }
    return lines;
}

/// Multi-character punctuators, longest first: the same maximal munch as the
/// RSL lexer, so that tokens split here split there too.
constexpr std::string_view kPunctuators[] = {
    "...", "<<=", ">>=", "##", "&&", "||", "==", "!=", "<=", ">=", "<<", ">>",
    "+=",  "-=",  "*=",  "/=", "%=", "&=", "|=", "^=", "++", "--", "->"};

void tokenize(std::string_view text, size_t from, const int* line, const int* col,
              int at_line, int at_col, std::vector<Token>& out) {
    size_t i = from;
    while (i < text.size()) {
        Token t;
        t.line = line ? line[i] : at_line;
        t.col = col ? col[i] : at_col;
        const size_t start = i;
        const char ch = text[i];
        if (is_space(ch)) {
            t.kind = Tok::Space;
            while (i < text.size() && is_space(text[i])) ++i;
        } else if (is_ident_start(ch)) {
            t.kind = Tok::Ident;
            while (i < text.size() && is_ident_char(text[i])) ++i;
        } else if (is_digit(ch) ||
                   (ch == '.' && i + 1 < text.size() && is_digit(text[i + 1]))) {
            // A pp-number: digits, letters, '.', and signs after an exponent.
            t.kind = Tok::Number;
            ++i;
            while (i < text.size()) {
                const char d = text[i];
                if ((d == 'e' || d == 'E' || d == 'p' || d == 'P') &&
                    i + 1 < text.size() && (text[i + 1] == '+' || text[i + 1] == '-'))
                    i += 2;
                else if (is_ident_char(d) || d == '.')
                    ++i;
                else
                    break;
            }
        } else if (ch == '"' || ch == '\'') {
            // Unterminated literals end at the end of the line (the compiler
            // reports them).
            t.kind = ch == '"' ? Tok::String : Tok::Char;
            ++i;
            while (i < text.size() && text[i] != ch) i += text[i] == '\\' ? 2 : 1;
            i = std::min(i + 1, text.size());
        } else {
            t.kind = Tok::Punct;
            size_t n = 1;
            for (std::string_view p : kPunctuators)
                if (text.substr(i, p.size()) == p) {
                    n = p.size();
                    break;
                }
            i += n;
        }
        t.text.assign(text.substr(start, i - start));
        out.push_back(std::move(t));
    }
}

bool hidden(const HideSet& h, int id) {
    return std::binary_search(h.begin(), h.end(), id);
}

HideSet with(HideSet h, int id) {
    const auto it = std::lower_bound(h.begin(), h.end(), id);
    if (it == h.end() || *it != id) h.insert(it, id);
    return h;
}

bool would_merge(const Token& a, const Token& b) {
    if (a.text.empty() || b.text.empty()) return false;
    const char x = a.text.back(), y = b.text.front();
    if (is_ident_char(x) && is_ident_char(y)) return true;
    // Numbers absorb '.', digits after '.', and a sign after an exponent.
    if (a.kind == Tok::Number &&
        (y == '.' || ((x == 'e' || x == 'E') && (y == '+' || y == '-'))))
        return true;
    if (x == '.' && (is_digit(y) || y == '.')) return true;
    if (a.kind != Tok::Punct || b.kind != Tok::Punct) return false;
    static constexpr std::string_view kPairs[] = {
        "++", "--", "+=", "-=", "*=", "/=", "%=", "==", "!=", "<=", ">=", "&&",
        "||", "<<", ">>", "->", "//", "/*", "*/", "&=", "|=", "^=", "##"};
    const char pair[2] = {x, y};
    return std::find(std::begin(kPairs), std::end(kPairs), std::string_view(pair, 2)) !=
           std::end(kPairs);
}

std::string quote(std::string_view s) {
    std::string q = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') q += '\\';
        q += c;
    }
    return q + '"';
}

PreprocessResult Preprocessor::run(const std::string& text, const std::string& name) {
    // Predefined and command-line macros, reported as "<command line>".
    Context cmd;
    cmd.source = std::make_shared<Source>();
    cmd.display = "<command line>";
    m_ctx = &cmd;
    define_from_text("__SSS__ 1");
    define_from_text("RSL 1");
    for (const auto& [macro, value] : m_options.defines)
        define_from_text(macro + " " + value);
    for (const auto& macro : m_options.undefines) m_macros.erase(macro);

    Context main;
    main.source = load(text, name);
    main.display = name;
    main.file = file_index(name);
    process(main);
    return std::move(m_result);
}

void Preprocessor::fail(int line, int col, const std::string& message) const {
    const Context& c = *m_ctx;
    const auto& raw = c.source->raw_lines;
    throw PreprocessError(c.display, line + c.delta, col, message,
                          line >= 1 && line <= static_cast<int>(raw.size())
                              ? raw[line - 1]
                              : std::string());
}

void Preprocessor::fail(const Token& at, const std::string& message) const {
    fail(at.line, at.col, message);
}

int Preprocessor::file_index(const std::string& name) {
    const auto it = std::find(m_result.files.begin(), m_result.files.end(), name);
    if (it != m_result.files.end()) return static_cast<int>(it - m_result.files.begin());
    m_result.files.push_back(name);
    return static_cast<int>(m_result.files.size()) - 1;
}

void Preprocessor::emit(const std::string& text, int physical_line) {
    if (m_result.text.size() + text.size() + 1 > kMaxOutputChars)
        fail(physical_line, 1,
             "preprocessed output exceeds " + std::to_string(kMaxOutputChars) +
                 " characters (runaway macro expansion or include?)");
    m_result.text += text;
    m_result.text += '\n';
    m_result.lines.push_back({m_ctx->file, physical_line + m_ctx->delta});
}

void Preprocessor::emit_blank(int first, int last) {
    for (int l = first; l <= last; ++l) emit("", l);
}

std::shared_ptr<Source> Preprocessor::load(const std::string& text,
                                           const std::string& path) {
    auto s = std::make_shared<Source>();
    s->path = path;
    s->raw_lines = split_raw_lines(text);
    s->lines = logical_lines(text, path, s->raw_lines);
    return s;
}

void Preprocessor::process(Context& ctx) {
    Context* outer = m_ctx;
    m_ctx = &ctx;
    const auto& lines = ctx.source->lines;
    while (ctx.next < lines.size()) {
        const Line& l = lines[ctx.next++];
        size_t p = 0;
        while (p < l.text.size() && is_space(l.text[p])) ++p;
        const bool active = ctx.conds.empty() || ctx.conds.back().active;
        if (p < l.text.size() && l.text[p] == '#') {
            directive(ctx, l, p, active);
        } else if (!active) {
            emit_blank(l.first, l.last);
        } else {
            int last = l.last;
            const std::string text = expand_line(ctx, l, &last);
            emit(text, l.first);
            emit_blank(l.first + 1, last);
        }
    }
    if (!ctx.conds.empty()) {
        const Conditional& c = ctx.conds.back();
        fail(c.line, c.col, "unterminated #" + c.directive);
    }
    m_ctx = outer;
}

std::string Preprocessor::expand_line(Context& ctx, const Line& l, int* last) {
    std::vector<Token> tokens;
    tokenize(l.text, 0, l.line.data(), l.col.data(), 0, 0, tokens);
    // Invocations may continue on the next lines (not past a directive).
    const Fetch fetch = [&](std::deque<Token>& in, bool need_paren) {
        const auto& lines = ctx.source->lines;
        if (ctx.next >= lines.size()) return false;
        const Line& n = lines[ctx.next];
        size_t p = 0;
        while (p < n.text.size() && is_space(n.text[p])) ++p;
        if (p < n.text.size() && n.text[p] == '#') return false;
        if (need_paren && (p >= n.text.size() || n.text[p] != '(')) return false;
        ++ctx.next;
        *last = n.last;
        Token space;
        space.kind = Tok::Space;
        space.text = " ";
        space.line = n.first;
        space.col = 1;
        in.push_back(std::move(space));
        std::vector<Token> more;
        tokenize(n.text, 0, n.line.data(), n.col.data(), 0, 0, more);
        for (auto& t : more) in.push_back(std::move(t));
        return true;
    };
    std::deque<Token> in(std::make_move_iterator(tokens.begin()),
                         std::make_move_iterator(tokens.end()));
    return spell(expand(std::move(in), &fetch, 0));
}

std::string Preprocessor::spell(const std::vector<Token>& tokens, bool guard) {
    std::string s;
    const Token* prev = nullptr;
    for (const Token& t : tokens) {
        if (t.kind == Tok::Placemarker) continue;
        if (t.kind == Tok::Space) {
            s += t.text;
            prev = nullptr;
            continue;
        }
        if (guard && prev && (prev->from_macro || t.from_macro) && would_merge(*prev, t))
            s += ' ';
        s += t.text;
        prev = &t;
    }
    return s;
}

} // namespace sss::preprocess_detail

namespace sss {

namespace {

std::string read_file(const std::string& path) {
    detail::require_regular_file(path, " (the shader source)");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path, "cannot open the shader source");
    std::ostringstream data;
    data << in.rdbuf();
    if (in.bad()) throw IoError(path, "cannot read the shader source");
    return data.str();
}

} // namespace

PreprocessResult preprocess_file(const std::string& path,
                                 const PreprocessOptions& options) {
    return preprocess_detail::Preprocessor(options).run(read_file(path), path);
}

PreprocessResult preprocess_text(const std::string& text, const std::string& name,
                                 const PreprocessOptions& options) {
    return preprocess_detail::Preprocessor(options).run(text, name);
}

} // namespace sss
