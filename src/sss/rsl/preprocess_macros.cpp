// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file preprocess_macros.cpp
/// Macro expansion in the shader preprocessor (preprocess.cpp): Prosser's
/// hide-set algorithm, macro invocation with its arguments, substitution,
/// # and ##.

#include "preprocess_internal.h"

namespace sss::preprocess_detail {

int Preprocessor::macro_id(const std::string& name) {
    const auto [it, added] =
        m_macro_ids.emplace(name, static_cast<int>(m_macro_ids.size()));
    return it->second;
}

std::vector<Token> Preprocessor::expand(std::deque<Token> in, const Fetch* fetch,
                                        int depth) {
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

bool Preprocessor::invoke(const Macro& m, const Token& t, std::deque<Token>& in,
                          const Fetch* fetch, int depth) {
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
        // The invocations nested in the arguments, counted as they are read:
        // each level expanded copies the rest of the arguments, so 40000
        // nested calls must fail here, not after gigabytes of copies.
        std::vector<bool> invocation_opens;
        int invocations = 0;
        const Token* previous = nullptr;
        for (;;) {
            if (i >= in.size()) {
                if (fetch && (*fetch)(in, false)) continue;
                fail(t, "unterminated argument list invoking macro \"" + t.text + "\"");
            }
            const Token& a = in[i++];
            if (is_punct(a, "(")) {
                ++level;
                const bool call = previous && previous->kind == Tok::Ident &&
                                  m_macros.count(previous->text) > 0;
                invocation_opens.push_back(call);
                if (call && depth + ++invocations > kMaxArgumentDepth)
                    fail(a, "macro arguments nested too deeply");
            } else if (is_punct(a, ")")) {
                if (level == 0) {
                    close = &a;
                    break;
                }
                --level;
                if (invocation_opens.back()) --invocations;
                invocation_opens.pop_back();
            } else if (is_punct(a, ",") && level == 0 &&
                       !(m.variadic && args.size() == m.params.size())) {
                args.emplace_back();
                continue;
            }
            if (a.kind != Tok::Space) previous = &a;
            args.back().push_back(a);
        }
        // hide = (hide of the name & hide of the ')') + this macro.
        std::set_intersection(t.hide.begin(), t.hide.end(), close->hide.begin(),
                              close->hide.end(), std::back_inserter(hide));
        hide = with(std::move(hide), m.id);
        in.erase(in.begin(), in.begin() + static_cast<std::ptrdiff_t>(i));
        for (auto& a : args) {
            while (!a.empty() && a.back().kind == Tok::Space) a.pop_back();
            const auto first = std::find_if(
                a.begin(), a.end(), [](const Token& x) { return x.kind != Tok::Space; });
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

void Preprocessor::check_arguments(const Macro& m, const Token& t,
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

std::vector<Token> Preprocessor::substitute(const Macro& m,
                                            const std::vector<std::vector<Token>>& args,
                                            const HideSet& hide, const Token& site,
                                            int depth) {
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

Token Preprocessor::stringize(const std::vector<Token>& arg, const Token& site) {
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

std::vector<Token> Preprocessor::paste(std::vector<Token> r, const Token& site) {
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

} // namespace sss::preprocess_detail
