// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the shading module: the C preprocessor for shaders shared by
// preprocess.cpp (logical lines, tokens, files, the driver),
// preprocess_macros.cpp (macro expansion), preprocess_directives.cpp
// (directives) and preprocess_expr.cpp (#if expressions).

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

#include "sss/rsl/preprocess.h"
#include "sss/util/byte_io.h"

namespace sss::preprocess_detail {

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

inline bool is_ident_start(char c) {
    return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
}

inline bool is_ident_char(char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
}

inline bool is_digit(char c) {
    return c >= '0' && c <= '9';
}

inline bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\f' || c == '\v' || c == '\r';
}

inline bool is_punct(const Token& t, std::string_view s) {
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

std::vector<std::string> split_raw_lines(const std::string& data);

/// Cuts `data` into logical lines. Throws on an unterminated comment.
std::vector<Line> logical_lines(const std::string& data, const std::string& name,
                                const std::vector<std::string>& raw);

/// Tokenizes text[from, to); `line`/`col` give the positions (null: all at
/// `at_line`/`at_col`).
void tokenize(std::string_view text, size_t from, const int* line, const int* col,
              int at_line, int at_col, std::vector<Token>& out);

bool hidden(const HideSet& h, int id);

HideSet with(HideSet h, int id);

/// Whether two adjacent tokens, written without a space, would read back as
/// other tokens (`-` `-` as `--`, `/` `/` as a comment, `x` `1` as `x1`).
bool would_merge(const Token& a, const Token& b);

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

std::string quote(std::string_view s);

class Preprocessor {
public:
    explicit Preprocessor(const PreprocessOptions& options) : m_options(options) {}
    PreprocessResult run(const std::string& text, const std::string& name);

private:
    const PreprocessOptions& m_options;
    PreprocessResult m_result;
    Context* m_ctx = nullptr;
    std::unordered_map<std::string, Macro> m_macros;
    std::unordered_map<std::string, int> m_macro_ids;
    int64_t m_expansions = 0;
    using Fetch = std::function<bool(std::deque<Token>&, bool need_paren)>;
    [[noreturn]] void fail(int line, int col, const std::string& message) const;
    [[noreturn]] void fail(const Token& at, const std::string& message) const;
    int file_index(const std::string& name);
    void emit(const std::string& text, int physical_line);
    void emit_blank(int first, int last);
    std::shared_ptr<Source> load(const std::string& text, const std::string& path);
    void process(Context& ctx);
    std::string expand_line(Context& ctx, const Line& l, int* last);
    /// The tokens as text, with a space where two tokens of which one came
    /// out of a macro would otherwise read back as different tokens.
    static std::string spell(const std::vector<Token>& tokens, bool guard = true);
    int macro_id(const std::string& name);
    /// Fully expands `in`. `fetch` (top level only) reads further source
    /// lines when the input ends inside an invocation.
    std::vector<Token> expand(std::deque<Token> in, const Fetch* fetch, int depth);
    /// Expands the macro named by `t` if it is invoked (object-like, or
    /// followed by an argument list): the replacement goes back in front of
    /// `in` for rescanning. False when a function-like macro has no '('.
    bool invoke(const Macro& m, const Token& t, std::deque<Token>& in, const Fetch* fetch,
                int depth);
    void check_arguments(const Macro& m, const Token& t,
                         std::vector<std::vector<Token>>& args) const;
    /// The replacement of `m` with `args`: parameters replaced (expanded,
    /// or raw next to ## and after #), pastes done, every token given
    /// `hide` and the invocation's position.
    std::vector<Token> substitute(const Macro& m,
                                  const std::vector<std::vector<Token>>& args,
                                  const HideSet& hide, const Token& site, int depth);
    /// `#param`: the argument's spelling, spaces collapsed, quoted.
    static Token stringize(const std::vector<Token>& arg, const Token& site);
    /// Performs the `##` operators of a substituted body. The operands are
    /// the tokens either side (an empty argument is a placemarker); the
    /// joined text is tokenized again.
    static std::vector<Token> paste(std::vector<Token> r, const Token& site);
    /// The tokens of a directive after its name, spaces at both ends dropped.
    static std::vector<Token> rest(std::vector<Token> tokens, size_t from);
    /// Where errors about "the end of the line" point.
    static Token end_of(const Line& l);
    void directive(Context& ctx, const Line& l, size_t hash, bool active);
    /// The index in l.text of a token tokenized from l.
    static size_t index_of(const Line& l, const Token& t);
    bool is_defined(const std::vector<Token>& args, const Token& name_tok,
                    const std::string& name) const;
    void define_from_text(const std::string& text);
    void define(const std::vector<Token>& args, const Token& end);
    void include(Context& ctx, const Line& l, std::vector<Token> args);
    void line_directive(Context& ctx, const Line& l, const std::vector<Token>& args);
    bool evaluate(const std::vector<Token>& args, const Token& name_tok, const Line& l);
    /// Recursive descent over the expanded tokens of a #if, in int64 with
    /// wrapping arithmetic. `eval` false: parse only (the unevaluated side of
    /// && || ?:, where 1/0 is allowed).
    struct Expression;
};

} // namespace sss::preprocess_detail
