// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file preprocess_directives.cpp
/// Directives in the shader preprocessor (preprocess.cpp): conditionals,
/// #define and #undef, #include, #line, #error and #pragma.

#include "preprocess_internal.h"

namespace sss::preprocess_detail {

std::vector<Token> Preprocessor::rest(std::vector<Token> tokens, size_t from) {
    tokens.erase(tokens.begin(), tokens.begin() + static_cast<std::ptrdiff_t>(from));
    while (!tokens.empty() && tokens.front().kind == Tok::Space)
        tokens.erase(tokens.begin());
    while (!tokens.empty() && tokens.back().kind == Tok::Space) tokens.pop_back();
    return tokens;
}

Token Preprocessor::end_of(const Line& l) {
    Token t;
    t.line = l.text.empty() ? l.first : l.line.back();
    t.col = l.text.empty() ? 1 : l.col.back() + 1;
    return t;
}

void Preprocessor::directive(Context& ctx, const Line& l, size_t hash, bool active) {
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

size_t Preprocessor::index_of(const Line& l, const Token& t) {
    for (size_t i = 0; i < l.text.size(); ++i)
        if (l.line[i] == t.line && l.col[i] == t.col) return i;
    return l.text.size();
}

bool Preprocessor::is_defined(const std::vector<Token>& args, const Token& name_tok,
                              const std::string& name) const {
    if (args.empty() || args[0].kind != Tok::Ident)
        fail(args.empty() ? name_tok : args[0], "#" + name + " expects a macro name");
    return m_macros.count(args[0].text) > 0 || args[0].text == "__LINE__" ||
           args[0].text == "__FILE__";
}

void Preprocessor::define_from_text(const std::string& text) {
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

void Preprocessor::define(const std::vector<Token>& args, const Token& end) {
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
                if (i >= args.size()) fail(end, "missing ')' in macro parameter list");
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
                if (i >= args.size()) fail(end, "missing ')' in macro parameter list");
                const Token& sep = args[i++];
                if (is_punct(sep, ")")) break;
                if (!is_punct(sep, ",") || m.variadic)
                    fail(sep, m.variadic ? "expected ')' after \"...\""
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
            return it == m.params.end() ? -1 : static_cast<int>(it - m.params.begin());
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

void Preprocessor::include(Context& ctx, const Line& l, std::vector<Token> args) {
    if (args.empty()) fail(end_of(l), "#include expects \"FILENAME\" or <FILENAME>");
    const Token where = args.front();
    std::string spelled;
    if (args.front().kind == Tok::String || is_punct(args.front(), "<")) {
        // Take the name as written: no escapes, and <a/b.h> is not tokens.
        const size_t start = index_of(l, args.front());
        spelled = l.text.substr(start);
    } else {
        // #include MACRO: expanded, then read as one of the two forms.
        spelled =
            spell(expand(std::deque<Token>(args.begin(), args.end()), nullptr, 0), false);
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

void Preprocessor::line_directive(Context& ctx, const Line& l,
                                  const std::vector<Token>& args) {
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
        if (e[1].kind != Tok::String || e[1].text.size() < 2 || e[1].text.back() != '"')
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

} // namespace sss::preprocess_detail
