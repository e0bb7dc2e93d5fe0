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

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <optional>
#include <sstream>
#include <unordered_map>

#include <sys/stat.h>

#include "sss/shading/preprocess.h"
#include "sss/util/byte_io.h"

namespace sss {

PreprocessError::PreprocessError(std::string file, int line, int column,
                                 const std::string& message,
                                 const std::string& source_line)
    : ValueError(file + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " +
                 message),
      m_file(std::move(file)), m_line(line), m_column(column),
      m_source_line(source_line) {}

namespace {

constexpr int kMaxIncludeDepth = 64;
constexpr size_t kMaxOutputChars = 10'000'000;
constexpr int64_t kMaxExpansions = 1'000'000;
/// Tokens waiting for rescanning or produced by one expansion.
constexpr size_t kMaxTokens = 1'000'000;
/// Macro calls inside macro arguments inside ... (each level recurses).
constexpr int kMaxArgumentDepth = 200;
constexpr int kMaxExpressionDepth = 200;

enum class Tok : uint8_t {
    Ident,
    Number,
    String,
    Char,
    Punct,
    Space,
    // Only in macro bodies and during substitution:
    Param,       ///< a parameter (index in `param`)
    Stringize,   ///< `#param`
    Paste,       ///< the `##` operator
    Placemarker, ///< an empty argument next to `##`
};

/// Macro ids of the macros a token came out of, sorted.
using HideSet = std::vector<int>;

struct Token {
    Tok kind = Tok::Punct;
    bool from_macro = false; ///< produced by an expansion (for output spacing)
    int param = -1;
    int line = 0; ///< physical line in the current file
    int col = 0;
    std::string text;
    HideSet hide;
};

bool is_ident_start(char c) {
    return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
}
bool is_ident_char(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
}
bool is_digit(char c) {
    return c >= '0' && c <= '9';
}
bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\f' || c == '\v' || c == '\r';
}

bool is_punct(const Token& t, std::string_view s) {
    return t.kind == Tok::Punct && t.text == s;
}

/// A logical line: splices removed, comments replaced by a space; each
/// character keeps its physical line and column.
struct Line {
    std::string text;
    std::vector<int> line, col;
    int first = 0, last = 0; ///< physical lines spanned
};

/// A file (or the command line) being read.
struct Source {
    std::string path;                   ///< as opened; its folder is searched first
    std::vector<std::string> raw_lines; ///< for error messages
    std::vector<Line> lines;
};

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

/// Cuts `data` into logical lines. Throws on an unterminated comment.
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

/// Tokenizes text[from, to); `line`/`col` give the positions (null: all at
/// `at_line`/`at_col`).
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

/// Whether two adjacent tokens, written without a space, would read back as
/// other tokens (`-` `-` as `--`, `/` `/` as a comment, `x` `1` as `x1`).
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

struct Macro {
    int id = 0;
    bool function_like = false;
    bool variadic = false; ///< the last parameter is __VA_ARGS__
    bool has_paste = false;
    std::vector<std::string> params;
    std::vector<Token> body; ///< spaces collapsed; Param/Stringize/Paste resolved
};

/// One #if / #ifdef / #ifndef group.
struct Conditional {
    bool parent_active = true;
    bool taken = false; ///< a branch of the group was taken
    bool active = false;
    bool seen_else = false;
    int line = 0, col = 0;
    std::string directive;
};

/// The state of one file being read.
struct Context {
    std::shared_ptr<Source> source;
    std::string display; ///< the name in messages (#line may change it)
    int file = 0;        ///< index in PreprocessResult::files
    int delta = 0;       ///< reported line = physical line + delta (#line)
    size_t next = 0;     ///< next logical line
    int depth = 0;       ///< include depth
    std::vector<Conditional> conds;
};

std::string quote(std::string_view s) {
    std::string q = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') q += '\\';
        q += c;
    }
    return q + '"';
}

class Preprocessor {
public:
    explicit Preprocessor(const PreprocessOptions& options) : m_options(options) {}

    PreprocessResult run(const std::string& text, const std::string& name) {
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

private:
    const PreprocessOptions& m_options;
    PreprocessResult m_result;
    Context* m_ctx = nullptr;
    std::unordered_map<std::string, Macro> m_macros;
    std::unordered_map<std::string, int> m_macro_ids;
    int64_t m_expansions = 0;

    using Fetch = std::function<bool(std::deque<Token>&, bool need_paren)>;

    // --- errors and output --------------------------------------------------

    [[noreturn]] void fail(int line, int col, const std::string& message) const {
        const Context& c = *m_ctx;
        const auto& raw = c.source->raw_lines;
        throw PreprocessError(c.display, line + c.delta, col, message,
                              line >= 1 && line <= static_cast<int>(raw.size())
                                  ? raw[line - 1]
                                  : std::string());
    }
    [[noreturn]] void fail(const Token& at, const std::string& message) const {
        fail(at.line, at.col, message);
    }

    int file_index(const std::string& name) {
        const auto it = std::find(m_result.files.begin(), m_result.files.end(), name);
        if (it != m_result.files.end())
            return static_cast<int>(it - m_result.files.begin());
        m_result.files.push_back(name);
        return static_cast<int>(m_result.files.size()) - 1;
    }

    void emit(const std::string& text, int physical_line) {
        if (m_result.text.size() + text.size() + 1 > kMaxOutputChars)
            fail(physical_line, 1,
                 "preprocessed output exceeds " + std::to_string(kMaxOutputChars) +
                     " characters (runaway macro expansion or include?)");
        m_result.text += text;
        m_result.text += '\n';
        m_result.lines.push_back({m_ctx->file, physical_line + m_ctx->delta});
    }
    void emit_blank(int first, int last) {
        for (int l = first; l <= last; ++l) emit("", l);
    }

    // --- files ----------------------------------------------------------------

    std::shared_ptr<Source> load(const std::string& text, const std::string& path) {
        auto s = std::make_shared<Source>();
        s->path = path;
        s->raw_lines = split_raw_lines(text);
        s->lines = logical_lines(text, path, s->raw_lines);
        return s;
    }

    void process(Context& ctx) {
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

    std::string expand_line(Context& ctx, const Line& l, int* last) {
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

    /// The tokens as text, with a space where two tokens of which one came
    /// out of a macro would otherwise read back as different tokens.
    static std::string spell(const std::vector<Token>& tokens, bool guard = true) {
        std::string s;
        const Token* prev = nullptr;
        for (const Token& t : tokens) {
            if (t.kind == Tok::Placemarker) continue;
            if (t.kind == Tok::Space) {
                s += t.text;
                prev = nullptr;
                continue;
            }
            if (guard && prev && (prev->from_macro || t.from_macro) &&
                would_merge(*prev, t))
                s += ' ';
            s += t.text;
            prev = &t;
        }
        return s;
    }

    // --- macro expansion --------------------------------------------------

    int macro_id(const std::string& name) {
        const auto [it, added] =
            m_macro_ids.emplace(name, static_cast<int>(m_macro_ids.size()));
        return it->second;
    }

    /// Fully expands `in`. `fetch` (top level only) reads further source
    /// lines when the input ends inside an invocation.
    std::vector<Token> expand(std::deque<Token> in, const Fetch* fetch, int depth) {
        if (depth > kMaxArgumentDepth)
            fail(in.empty() ? 0 : in.front().line, in.empty() ? 0 : in.front().col,
                 "macro arguments nested too deeply");
        std::vector<Token> out;
        size_t out_chars = 0;
        while (!in.empty()) {
            Token t = std::move(in.front());
            in.pop_front();
            if (t.kind == Tok::Ident) {
                if (t.text == "__LINE__" || t.text == "__FILE__") {
                    const bool is_line = t.text[2] == 'L';
                    t.kind = is_line ? Tok::Number : Tok::String;
                    t.text = is_line ? std::to_string(t.line + m_ctx->delta)
                                     : quote(m_ctx->display);
                    t.from_macro = true;
                } else if (const auto it = m_macros.find(t.text);
                           it != m_macros.end() && !hidden(t.hide, it->second.id)) {
                    if (invoke(it->second, t, in, fetch, depth)) continue;
                }
            }
            out_chars += t.text.size();
            if (out.size() >= kMaxTokens || out_chars > kMaxOutputChars)
                fail(t, "macro expansion too large (more than " +
                            std::to_string(kMaxOutputChars) + " characters)");
            out.push_back(std::move(t));
        }
        return out;
    }

    /// Expands the macro named by `t` if it is invoked (object-like, or
    /// followed by an argument list): the replacement goes back in front of
    /// `in` for rescanning. False when a function-like macro has no '('.
    bool invoke(const Macro& m, const Token& t, std::deque<Token>& in, const Fetch* fetch,
                int depth) {
        std::vector<std::vector<Token>> args;
        HideSet hide;
        if (!m.function_like) {
            hide = with(t.hide, m.id);
        } else {
            size_t k = 0;
            for (;;) {
                while (k < in.size() && in[k].kind == Tok::Space) ++k;
                if (k < in.size() || !fetch || !(*fetch)(in, true)) break;
            }
            if (k >= in.size() || !is_punct(in[k], "(")) return false;
            in.erase(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(k + 1));

            args.emplace_back();
            int level = 0;
            size_t i = 0;
            const Token* close = nullptr;
            for (;;) {
                if (i >= in.size()) {
                    if (fetch && (*fetch)(in, false)) continue;
                    fail(t,
                         "unterminated argument list invoking macro \"" + t.text + "\"");
                }
                const Token& a = in[i++];
                if (is_punct(a, "(")) {
                    ++level;
                } else if (is_punct(a, ")")) {
                    if (level == 0) {
                        close = &a;
                        break;
                    }
                    --level;
                } else if (is_punct(a, ",") && level == 0 &&
                           !(m.variadic && args.size() == m.params.size())) {
                    args.emplace_back();
                    continue;
                }
                args.back().push_back(a);
            }
            // hide = (hide of the name & hide of the ')') + this macro.
            std::set_intersection(t.hide.begin(), t.hide.end(), close->hide.begin(),
                                  close->hide.end(), std::back_inserter(hide));
            hide = with(std::move(hide), m.id);
            in.erase(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(i));
            for (auto& a : args) {
                while (!a.empty() && a.back().kind == Tok::Space) a.pop_back();
                const auto first = std::find_if(a.begin(), a.end(), [](const Token& x) {
                    return x.kind != Tok::Space;
                });
                a.erase(a.begin(), first);
            }
            check_arguments(m, t, args);
        }
        if (++m_expansions > kMaxExpansions)
            fail(t, "more than " + std::to_string(kMaxExpansions) +
                        " macro expansions (runaway recursion?)");
        std::vector<Token> body = substitute(m, args, hide, t, depth);
        if (in.size() + body.size() > kMaxTokens)
            fail(t, "macro expansion too large (more than " + std::to_string(kMaxTokens) +
                        " tokens)");
        in.insert(in.begin(), std::make_move_iterator(body.begin()),
                  std::make_move_iterator(body.end()));
        return true;
    }

    void check_arguments(const Macro& m, const Token& t,
                         std::vector<std::vector<Token>>& args) const {
        const size_t n = m.params.size();
        if (n == 0) {
            if (args.size() == 1 && args[0].empty()) {
                args.clear();
                return;
            }
            fail(t, "macro \"" + t.text + "\" takes no arguments, " +
                        std::to_string(args.size()) + " given");
        }
        if (m.variadic && args.size() == n - 1) args.emplace_back(); // no variadic part
        if (args.size() != n)
            fail(t, "macro \"" + t.text + "\" requires " + std::to_string(n) +
                        (n == 1 ? " argument, " : " arguments, ") +
                        std::to_string(args.size()) + " given");
    }

    /// The replacement of `m` with `args`: parameters replaced (expanded,
    /// or raw next to ## and after #), pastes done, every token given
    /// `hide` and the invocation's position.
    std::vector<Token> substitute(const Macro& m,
                                  const std::vector<std::vector<Token>>& args,
                                  const HideSet& hide, const Token& site, int depth) {
        std::vector<Token> r;
        std::vector<std::optional<std::vector<Token>>> expanded(args.size());
        const auto& body = m.body;
        for (size_t i = 0; i < body.size(); ++i) {
            const Token& b = body[i];
            if (b.kind == Tok::Stringize) {
                r.push_back(stringize(args[b.param], site));
            } else if (b.kind == Tok::Param) {
                const bool raw = (i > 0 && body[i - 1].kind == Tok::Paste) ||
                                 (i + 1 < body.size() && body[i + 1].kind == Tok::Paste);
                const std::vector<Token>* a = &args[b.param];
                if (!raw) {
                    auto& e = expanded[b.param];
                    if (!e)
                        e = expand(std::deque<Token>(a->begin(), a->end()), nullptr,
                                   depth + 1);
                    a = &*e;
                }
                if (a->empty() && raw) {
                    Token p;
                    p.kind = Tok::Placemarker;
                    r.push_back(std::move(p));
                }
                if (r.size() + a->size() > kMaxTokens)
                    fail(site, "macro expansion too large (more than " +
                                   std::to_string(kMaxTokens) + " tokens)");
                r.insert(r.end(), a->begin(), a->end());
            } else {
                r.push_back(b);
            }
        }
        if (m.has_paste) r = paste(std::move(r), site);
        std::vector<Token> out;
        out.reserve(r.size());
        for (Token& t : r) {
            if (t.kind == Tok::Placemarker) continue;
            if (t.hide.empty()) {
                t.hide = hide;
            } else {
                HideSet u;
                std::set_union(t.hide.begin(), t.hide.end(), hide.begin(), hide.end(),
                               std::back_inserter(u));
                t.hide = std::move(u);
            }
            t.line = site.line;
            t.col = site.col;
            t.from_macro = true;
            out.push_back(std::move(t));
        }
        return out;
    }

    /// `#param`: the argument's spelling, spaces collapsed, quoted.
    static Token stringize(const std::vector<Token>& arg, const Token& site) {
        std::string s = "\"";
        bool space = false;
        for (const Token& t : arg) {
            if (t.kind == Tok::Space) {
                space = true;
                continue;
            }
            if (space && s.size() > 1) s += ' ';
            space = false;
            if (t.kind == Tok::String || t.kind == Tok::Char) {
                for (char c : t.text) {
                    if (c == '"' || c == '\\') s += '\\';
                    s += c;
                }
            } else {
                s += t.text;
            }
        }
        Token t;
        t.kind = Tok::String;
        t.text = s + '"';
        t.line = site.line;
        t.col = site.col;
        return t;
    }

    /// Performs the `##` operators of a substituted body. The operands are
    /// the tokens either side (an empty argument is a placemarker); the
    /// joined text is tokenized again.
    static std::vector<Token> paste(std::vector<Token> r, const Token& site) {
        std::vector<Token> o;
        for (size_t i = 0; i < r.size(); ++i) {
            if (r[i].kind != Tok::Paste || o.empty() || i + 1 >= r.size()) {
                o.push_back(std::move(r[i]));
                continue;
            }
            Token rhs = std::move(r[++i]);
            if (rhs.kind == Tok::Paste) {
                rhs.kind = Tok::Punct;
                rhs.text = "##";
            }
            Token& lhs = o.back();
            if (rhs.kind == Tok::Placemarker) continue;
            if (lhs.kind == Tok::Placemarker) {
                lhs = std::move(rhs);
                continue;
            }
            const std::string joined = lhs.text + rhs.text;
            HideSet hide = lhs.hide;
            o.pop_back();
            std::vector<Token> t;
            tokenize(joined, 0, nullptr, nullptr, site.line, site.col, t);
            for (Token& x : t) {
                x.hide = hide;
                o.push_back(std::move(x));
            }
        }
        return o;
    }

    // --- directives ---------------------------------------------------------

    /// The tokens of a directive after its name, spaces at both ends dropped.
    static std::vector<Token> rest(std::vector<Token> tokens, size_t from) {
        tokens.erase(tokens.begin(), tokens.begin() + static_cast<std::ptrdiff_t>(from));
        while (!tokens.empty() && tokens.front().kind == Tok::Space)
            tokens.erase(tokens.begin());
        while (!tokens.empty() && tokens.back().kind == Tok::Space) tokens.pop_back();
        return tokens;
    }

    /// Where errors about "the end of the line" point.
    static Token end_of(const Line& l) {
        Token t;
        t.line = l.text.empty() ? l.first : l.line.back();
        t.col = l.text.empty() ? 1 : l.col.back() + 1;
        return t;
    }

    void directive(Context& ctx, const Line& l, size_t hash, bool active) {
        std::vector<Token> tokens;
        tokenize(l.text, hash + 1, l.line.data(), l.col.data(), 0, 0, tokens);
        size_t k = 0;
        while (k < tokens.size() && tokens[k].kind == Tok::Space) ++k;
        const Token at_hash = [&] {
            Token t;
            t.line = l.line[hash];
            t.col = l.col[hash];
            return t;
        }();
        if (k >= tokens.size()) { // the null directive
            emit_blank(l.first, l.last);
            return;
        }
        const Token& name_tok = tokens[k];
        const std::string name = name_tok.kind == Tok::Number ? "line" : name_tok.text;
        std::vector<Token> args = rest(tokens, name_tok.kind == Tok::Number ? k : k + 1);

        if (name == "if" || name == "ifdef" || name == "ifndef") {
            Conditional c;
            c.parent_active = active;
            c.directive = name;
            c.line = at_hash.line;
            c.col = at_hash.col;
            if (active) {
                if (name == "if")
                    c.active = evaluate(args, name_tok, l);
                else
                    c.active = is_defined(args, name_tok, name) == (name == "ifdef");
                c.taken = c.active;
            }
            ctx.conds.push_back(c);
        } else if (name == "elif" || name == "else") {
            if (ctx.conds.empty()) fail(at_hash, "#" + name + " without #if");
            Conditional& c = ctx.conds.back();
            if (c.seen_else) fail(at_hash, "#" + name + " after #else");
            if (name == "else") {
                c.seen_else = true;
                c.active = c.parent_active && !c.taken;
            } else {
                // Not evaluated once a branch was taken (it may be invalid then).
                c.active = c.parent_active && !c.taken && evaluate(args, name_tok, l);
            }
            c.taken = c.taken || c.active;
        } else if (name == "endif") {
            if (ctx.conds.empty()) fail(at_hash, "#endif without #if");
            ctx.conds.pop_back();
        } else if (!active) {
            // Other directives in skipped groups are not even checked.
        } else if (name == "include") {
            include(ctx, l, std::move(args));
            return; // the included lines replace this one
        } else if (name == "define") {
            define(args, end_of(l));
        } else if (name == "undef") {
            if (args.empty() || args[0].kind != Tok::Ident)
                fail(args.empty() ? end_of(l) : args[0], "#undef expects a macro name");
            if (args[0].text == "__LINE__" || args[0].text == "__FILE__")
                fail(args[0], "\"" + args[0].text + "\" cannot be undefined");
            m_macros.erase(args[0].text);
        } else if (name == "line") {
            line_directive(ctx, l, args);
        } else if (name == "error") {
            std::string message;
            if (!args.empty()) {
                // The message as written, from the first token to the line's end.
                const size_t start = index_of(l, args.front());
                message = l.text.substr(start);
                while (!message.empty() && is_space(message.back())) message.pop_back();
            }
            fail(at_hash, "#error " + message);
        } else if (name == "pragma") {
            // Ignored, like aqsl and sdrc do.
        } else {
            fail(name_tok, "unknown preprocessing directive \"#" + name_tok.text + "\"");
        }
        emit_blank(l.first, l.last);
    }

    /// The index in l.text of a token tokenized from l.
    static size_t index_of(const Line& l, const Token& t) {
        for (size_t i = 0; i < l.text.size(); ++i)
            if (l.line[i] == t.line && l.col[i] == t.col) return i;
        return l.text.size();
    }

    bool is_defined(const std::vector<Token>& args, const Token& name_tok,
                    const std::string& name) const {
        if (args.empty() || args[0].kind != Tok::Ident)
            fail(args.empty() ? name_tok : args[0], "#" + name + " expects a macro name");
        return m_macros.count(args[0].text) > 0 || args[0].text == "__LINE__" ||
               args[0].text == "__FILE__";
    }

    void define_from_text(const std::string& text) {
        std::vector<Token> tokens;
        // Positions: column i+1 of the one-line "command line".
        std::vector<int> line(text.size(), 1), col(text.size());
        for (size_t i = 0; i < text.size(); ++i) col[i] = static_cast<int>(i) + 1;
        tokenize(text, 0, line.data(), col.data(), 1, 1, tokens);
        m_ctx->source->raw_lines = {text};
        Token end;
        end.line = 1;
        end.col = static_cast<int>(text.size()) + 1;
        define(rest(std::move(tokens), 0), end);
    }

    void define(const std::vector<Token>& args, const Token& end) {
        if (args.empty() || args[0].kind != Tok::Ident)
            fail(args.empty() ? end : args[0], "macro names must be identifiers");
        const std::string& name = args[0].text;
        if (name == "defined" || name == "__LINE__" || name == "__FILE__")
            fail(args[0], "\"" + name + "\" cannot be used as a macro name");
        Macro m;
        m.id = macro_id(name);
        size_t i = 1;
        if (i < args.size() && is_punct(args[i], "(")) {
            m.function_like = true;
            ++i;
            auto skip = [&] {
                while (i < args.size() && args[i].kind == Tok::Space) ++i;
            };
            skip();
            if (i < args.size() && is_punct(args[i], ")")) {
                ++i;
            } else {
                for (;;) {
                    skip();
                    if (i >= args.size())
                        fail(end, "missing ')' in macro parameter list");
                    const Token& p = args[i++];
                    if (is_punct(p, "...")) {
                        m.variadic = true;
                        m.params.push_back("__VA_ARGS__");
                    } else if (p.kind == Tok::Ident) {
                        if (std::find(m.params.begin(), m.params.end(), p.text) !=
                            m.params.end())
                            fail(p, "duplicate macro parameter \"" + p.text + "\"");
                        m.params.push_back(p.text);
                    } else {
                        fail(p, "expected a parameter name, found \"" + p.text + "\"");
                    }
                    skip();
                    if (i >= args.size())
                        fail(end, "missing ')' in macro parameter list");
                    const Token& sep = args[i++];
                    if (is_punct(sep, ")")) break;
                    if (!is_punct(sep, ",") || m.variadic)
                        fail(sep, m.variadic
                                      ? "expected ')' after \"...\""
                                      : "expected ',' or ')' in macro parameter list");
                }
            }
        }
        // The body: spaces collapsed, parameters, # and ## resolved.
        std::vector<Token>& body = m.body;
        while (i < args.size() && args[i].kind == Tok::Space) ++i;
        for (; i < args.size(); ++i) {
            Token t = args[i];
            if (t.kind == Tok::Space) {
                t.text = " ";
                if (!body.empty() && body.back().kind != Tok::Space) body.push_back(t);
                continue;
            }
            auto param_index = [&](const Token& x) {
                if (x.kind != Tok::Ident) return -1;
                const auto it = std::find(m.params.begin(), m.params.end(), x.text);
                return it == m.params.end() ? -1
                                            : static_cast<int>(it - m.params.begin());
            };
            if (m.function_like && is_punct(t, "#")) {
                size_t j = i + 1;
                while (j < args.size() && args[j].kind == Tok::Space) ++j;
                const int p = j < args.size() ? param_index(args[j]) : -1;
                if (p < 0) fail(t, "'#' is not followed by a macro parameter");
                t.kind = Tok::Stringize;
                t.param = p;
                i = j;
            } else if (is_punct(t, "##")) {
                if (!body.empty() && body.back().kind == Tok::Space) body.pop_back();
                if (body.empty()) fail(t, "'##' cannot appear at either end of a macro");
                t.kind = Tok::Paste;
                m.has_paste = true;
                body.push_back(std::move(t));
                while (i + 1 < args.size() && args[i + 1].kind == Tok::Space) ++i;
                if (i + 1 >= args.size())
                    fail(body.back(), "'##' cannot appear at either end of a macro");
                continue;
            } else if (const int p = m.function_like ? param_index(t) : -1; p >= 0) {
                t.kind = Tok::Param;
                t.param = p;
            }
            body.push_back(std::move(t));
        }
        while (!body.empty() && body.back().kind == Tok::Space) body.pop_back();
        for (Token& t : body) t.hide.clear();
        m_macros[name] = std::move(m);
    }

    void include(Context& ctx, const Line& l, std::vector<Token> args) {
        if (args.empty()) fail(end_of(l), "#include expects \"FILENAME\" or <FILENAME>");
        const Token where = args.front();
        std::string spelled;
        if (args.front().kind == Tok::String || is_punct(args.front(), "<")) {
            // Take the name as written: no escapes, and <a/b.h> is not tokens.
            const size_t start = index_of(l, args.front());
            spelled = l.text.substr(start);
        } else {
            // #include MACRO: expanded, then read as one of the two forms.
            spelled = spell(
                expand(std::deque<Token>(args.begin(), args.end()), nullptr, 0), false);
        }
        while (!spelled.empty() && is_space(spelled.back())) spelled.pop_back();
        const char open = spelled.empty() ? 0 : spelled[0];
        const char close = open == '"' ? '"' : '>';
        const size_t end = spelled.find(close, 1);
        if ((open != '"' && open != '<') || end == std::string::npos)
            fail(where, "#include expects \"FILENAME\" or <FILENAME>");
        const std::string file = spelled.substr(1, end - 1);
        if (file.empty()) fail(where, "empty file name in #include");
        if (ctx.depth + 1 > kMaxIncludeDepth)
            fail(where, "#include nested more than " + std::to_string(kMaxIncludeDepth) +
                            " levels deep (an include cycle?)");

        namespace fs = std::filesystem;
        std::vector<fs::path> dirs;
        if (open == '"') {
            const fs::path parent = fs::path(ctx.source->path).parent_path();
            dirs.push_back(parent.empty() ? fs::path(".") : parent);
        }
        for (const auto& d : m_options.include_dirs) dirs.emplace_back(d);
        std::string found;
        std::error_code ec;
        if (fs::path(file).is_absolute()) {
            if (fs::is_regular_file(file, ec)) found = file;
        } else {
            for (const auto& d : dirs) {
                const fs::path p = d / file;
                if (fs::is_regular_file(p, ec)) {
                    found = (d == "." ? fs::path(file) : p).lexically_normal().string();
                    break;
                }
            }
        }
        if (found.empty()) {
            std::string searched;
            for (const auto& d : dirs)
                searched += (searched.empty() ? "" : ", ") + d.string();
            fail(where, "cannot find include file \"" + file + "\"" +
                            (searched.empty() ? std::string(" (no folders to search)")
                                              : " (searched " + searched + ")"));
        }
        struct stat st {};
        if (::stat(found.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
            fail(where, "include file \"" + found + "\" is not a regular file");
        std::ifstream in(found, std::ios::binary);
        std::ostringstream data;
        data << in.rdbuf();
        if (!in && !in.eof()) fail(where, "cannot read include file \"" + found + "\"");

        Context child;
        child.source = load(data.str(), found);
        child.display = found;
        child.file = file_index(found);
        child.depth = ctx.depth + 1;
        process(child);
    }

    void line_directive(Context& ctx, const Line& l, const std::vector<Token>& args) {
        std::vector<Token> e =
            expand(std::deque<Token>(args.begin(), args.end()), nullptr, 0);
        e.erase(std::remove_if(e.begin(), e.end(),
                               [](const Token& t) { return t.kind == Tok::Space; }),
                e.end());
        const Token& at = e.empty() ? end_of(l) : e[0];
        if (e.empty() || e[0].kind != Tok::Number ||
            !std::all_of(e[0].text.begin(), e[0].text.end(), is_digit) ||
            e[0].text.size() > 9 || std::stol(e[0].text) < 1)
            fail(at, "#line expects a line number (a positive integer)");
        std::string file;
        if (e.size() > 1) {
            if (e[1].kind != Tok::String || e[1].text.size() < 2 ||
                e[1].text.back() != '"')
                fail(e[1], "#line expects a file name in quotes after the number");
            const std::string& q = e[1].text;
            for (size_t i = 1; i + 1 < q.size(); ++i) {
                if (q[i] == '\\' && i + 2 < q.size()) ++i;
                file += q[i];
            }
        }
        // The next physical line gets the given number.
        ctx.delta = static_cast<int>(std::stol(e[0].text)) - (l.last + 1);
        if (!file.empty() || e.size() > 1) {
            ctx.display = file;
            ctx.file = file_index(file);
        }
    }

    // --- #if expressions ------------------------------------------------------

    bool evaluate(const std::vector<Token>& args, const Token& name_tok, const Line& l) {
        if (args.empty()) fail(end_of(l), "#" + name_tok.text + " with no expression");
        // `defined` is resolved before expansion.
        std::deque<Token> in;
        for (size_t i = 0; i < args.size(); ++i) {
            if (args[i].kind != Tok::Ident || args[i].text != "defined") {
                in.push_back(args[i]);
                continue;
            }
            Token t = args[i];
            auto skip = [&] {
                while (i + 1 < args.size() && args[i + 1].kind == Tok::Space) ++i;
            };
            skip();
            bool paren = false;
            if (i + 1 < args.size() && is_punct(args[i + 1], "(")) {
                paren = true;
                ++i;
                skip();
            }
            if (i + 1 >= args.size() || args[i + 1].kind != Tok::Ident)
                fail(t, "operator \"defined\" requires a macro name");
            const std::string& macro = args[++i].text;
            if (paren) {
                skip();
                if (i + 1 >= args.size() || !is_punct(args[i + 1], ")"))
                    fail(t, "missing ')' after \"defined\"");
                ++i;
            }
            t.kind = Tok::Number;
            t.text = m_macros.count(macro) || macro == "__LINE__" || macro == "__FILE__"
                         ? "1"
                         : "0";
            in.push_back(std::move(t));
        }
        std::vector<Token> e = expand(std::move(in), nullptr, 0);
        e.erase(std::remove_if(e.begin(), e.end(),
                               [](const Token& t) { return t.kind == Tok::Space; }),
                e.end());
        Expression x{*this, e, end_of(l)};
        const int64_t v = x.conditional(true, 0);
        if (x.pos < e.size()) x.unexpected();
        return v != 0;
    }

    /// Recursive descent over the expanded tokens of a #if, in int64 with
    /// wrapping arithmetic. `eval` false: parse only (the unevaluated side of
    /// && || ?:, where 1/0 is allowed).
    struct Expression {
        const Preprocessor& pp;
        const std::vector<Token>& t;
        Token end;
        size_t pos = 0;

        const Token& here() const { return pos < t.size() ? t[pos] : end; }
        bool at(std::string_view op) const {
            return pos < t.size() && is_punct(t[pos], op);
        }
        [[noreturn]] void unexpected() const {
            if (pos >= t.size()) pp.fail(end, "#if expression ends unexpectedly");
            pp.fail(t[pos], "unexpected \"" + t[pos].text + "\" in #if expression");
        }

        static int64_t wrap(uint64_t v) { return static_cast<int64_t>(v); }

        int64_t conditional(bool eval, int depth) {
            if (depth > kMaxExpressionDepth)
                pp.fail(here(), "#if expression nested too deeply");
            const int64_t c = binary(0, eval, depth);
            if (!at("?")) return c;
            ++pos;
            const int64_t a = conditional(eval && c != 0, depth + 1);
            if (!at(":")) pp.fail(here(), "expected ':' in #if expression");
            ++pos;
            const int64_t b = conditional(eval && c == 0, depth + 1);
            return c != 0 ? a : b;
        }

        /// Binary operators by precedence level, lowest first.
        int64_t binary(int level, bool eval, int depth) {
            static const std::vector<std::vector<std::string_view>> kLevels = {
                {"||"},
                {"&&"},
                {"|"},
                {"^"},
                {"&"},
                {"==", "!="},
                {"<", ">", "<=", ">="},
                {"<<", ">>"},
                {"+", "-"},
                {"*", "/", "%"}};
            if (level == static_cast<int>(kLevels.size())) return unary(eval, depth);
            int64_t a = binary(level + 1, eval, depth);
            for (;;) {
                std::string_view op;
                for (std::string_view o : kLevels[level])
                    if (at(o)) op = o;
                if (op.empty()) return a;
                const Token& op_tok = t[pos++];
                const bool rhs_eval =
                    eval && !(op == "||" && a != 0) && !(op == "&&" && a == 0);
                const int64_t b = binary(level + 1, rhs_eval, depth);
                const auto ua = static_cast<uint64_t>(a), ub = static_cast<uint64_t>(b);
                if (op == "||")
                    a = (a != 0 || b != 0);
                else if (op == "&&")
                    a = (a != 0 && b != 0);
                else if (op == "|")
                    a = wrap(ua | ub);
                else if (op == "^")
                    a = wrap(ua ^ ub);
                else if (op == "&")
                    a = wrap(ua & ub);
                else if (op == "==")
                    a = a == b;
                else if (op == "!=")
                    a = a != b;
                else if (op == "<")
                    a = a < b;
                else if (op == ">")
                    a = a > b;
                else if (op == "<=")
                    a = a <= b;
                else if (op == ">=")
                    a = a >= b;
                else if (op == "<<")
                    a = b < 0 || b > 63 ? 0 : wrap(ua << b);
                else if (op == ">>")
                    a = b < 0 || b > 63 ? (a < 0 ? -1 : 0) : a >> b;
                else if (op == "+")
                    a = wrap(ua + ub);
                else if (op == "-")
                    a = wrap(ua - ub);
                else if (op == "*")
                    a = wrap(ua * ub);
                else if (!eval)
                    a = 0;
                else if (b == 0)
                    pp.fail(op_tok, "division by zero in #if expression");
                else if (b == -1)
                    a = op == "/" ? wrap(0 - ua) : 0; // no INT64_MIN / -1 trap
                else
                    a = op == "/" ? a / b : a % b;
            }
        }

        int64_t unary(bool eval, int depth) {
            if (depth > kMaxExpressionDepth)
                pp.fail(here(), "#if expression nested too deeply");
            if (at("+") || at("-") || at("!") || at("~")) {
                const char op = t[pos++].text[0];
                const int64_t v = unary(eval, depth + 1);
                const auto u = static_cast<uint64_t>(v);
                return op == '+'   ? v
                       : op == '-' ? wrap(0 - u)
                       : op == '!' ? v == 0
                                   : wrap(~u);
            }
            if (at("(")) {
                ++pos;
                const int64_t v = conditional(eval, depth + 1);
                if (!at(")")) pp.fail(here(), "missing ')' in #if expression");
                ++pos;
                return v;
            }
            if (pos >= t.size()) unexpected();
            const Token& x = t[pos++];
            switch (x.kind) {
            case Tok::Ident:
                return 0; // identifiers left after expansion are 0
            case Tok::Number:
                return number(x);
            case Tok::Char:
                return character(x);
            default:
                --pos;
                unexpected();
            }
        }

        int64_t number(const Token& x) const {
            std::string s = x.text;
            while (!s.empty() && (s.back() == 'u' || s.back() == 'U' || s.back() == 'l' ||
                                  s.back() == 'L'))
                s.pop_back();
            int base = 10;
            size_t i = 0;
            if (s.size() > 1 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
                base = 16;
                i = 2;
            } else if (s.size() > 1 && s[0] == '0') {
                base = 8;
                i = 1;
            }
            if (s.find_first_of(".") != std::string::npos ||
                (base == 10 && s.find_first_of("eE") != std::string::npos))
                pp.fail(x, "floating-point number \"" + x.text + "\" in #if expression");
            if (i >= s.size() && base == 16)
                pp.fail(x, "invalid number \"" + x.text + "\"");
            uint64_t v = 0;
            for (; i < s.size(); ++i) {
                const char c =
                    static_cast<char>(std::tolower(static_cast<unsigned char>(s[i])));
                const int d = is_digit(c)              ? c - '0'
                              : (c >= 'a' && c <= 'f') ? c - 'a' + 10
                                                       : 99;
                if (d >= base)
                    pp.fail(x, "invalid number \"" + x.text + "\" in #if expression");
                v = v * static_cast<uint64_t>(base) + static_cast<uint64_t>(d);
            }
            return wrap(v);
        }

        int64_t character(const Token& x) const {
            const std::string& s = x.text;
            if (s.size() == 3 && s[2] == '\'') return static_cast<unsigned char>(s[1]);
            if (s.size() == 4 && s[1] == '\\' && s[3] == '\'') {
                switch (s[2]) {
                case 'n':
                    return '\n';
                case 't':
                    return '\t';
                case 'r':
                    return '\r';
                case '0':
                    return 0;
                default:
                    return static_cast<unsigned char>(s[2]);
                }
            }
            pp.fail(x, "invalid character constant " + s + " in #if expression");
        }
    };
};

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
    return Preprocessor(options).run(read_file(path), path);
}

PreprocessResult preprocess_text(const std::string& text, const std::string& name,
                                 const PreprocessOptions& options) {
    return Preprocessor(options).run(text, name);
}

} // namespace sss
