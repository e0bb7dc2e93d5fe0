// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file preprocess_expr.cpp
/// #if expressions in the shader preprocessor (preprocess.cpp): `defined`,
/// macro expansion, then recursive descent in int64 with wrapping arithmetic.

#include "preprocess_internal.h"

namespace sss::preprocess_detail {

struct Preprocessor::Expression {
    const Preprocessor& pp;
    const std::vector<Token>& t;
    Token end;
    size_t pos = 0;

    const Token& here() const { return pos < t.size() ? t[pos] : end; }
    bool at(std::string_view op) const { return pos < t.size() && is_punct(t[pos], op); }
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

    /// `a op b` for a binary operator. Out of line, so that the recursion
    /// through the precedence levels keeps small frames (the sanitizer build
    /// gives each std::string of an error message a large one).
    [[gnu::noinline]] int64_t apply(std::string_view op, const Token& op_tok, int64_t a,
                                    int64_t b, bool eval) const {
        int64_t r = a;
        const auto ua = static_cast<uint64_t>(a), ub = static_cast<uint64_t>(b);
        if (op == "||")
            r = (a != 0 || b != 0);
        else if (op == "&&")
            r = (a != 0 && b != 0);
        else if (op == "|")
            r = wrap(ua | ub);
        else if (op == "^")
            r = wrap(ua ^ ub);
        else if (op == "&")
            r = wrap(ua & ub);
        else if (op == "==")
            r = a == b;
        else if (op == "!=")
            r = a != b;
        else if (op == "<")
            r = a < b;
        else if (op == ">")
            r = a > b;
        else if (op == "<=")
            r = a <= b;
        else if (op == ">=")
            r = a >= b;
        else if (op == "<<")
            r = b < 0 || b > 63 ? 0 : wrap(ua << b);
        else if (op == ">>")
            r = b < 0 || b > 63 ? (a < 0 ? -1 : 0) : a >> b;
        else if (op == "+")
            r = wrap(ua + ub);
        else if (op == "-")
            r = wrap(ua - ub);
        else if (op == "*")
            r = wrap(ua * ub);
        else if (!eval)
            r = 0;
        else if (b == 0)
            pp.fail(op_tok, "division by zero in #if expression");
        else if (b == -1)
            r = op == "/" ? wrap(0 - ua) : 0; // no INT64_MIN / -1 trap
        else
            r = op == "/" ? a / b : a % b;
        return r;
    }

    /// Binary operators by precedence level, lowest first. Out of line: the
    /// table's initializer would take room in every frame of binary().
    [[gnu::noinline]] static const std::vector<std::vector<std::string_view>>&
    binary_levels() {
        static const std::vector<std::vector<std::string_view>> levels = {
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
        return levels;
    }

    /// Binary operators by precedence level, lowest first.
    int64_t binary(int level, bool eval, int depth) {
        const std::vector<std::vector<std::string_view>>& kLevels = binary_levels();
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
            a = apply(op, op_tok, a, b, eval);
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
        while (!s.empty() &&
               (s.back() == 'u' || s.back() == 'U' || s.back() == 'l' || s.back() == 'L'))
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
        if (i >= s.size() && base == 16) pp.fail(x, "invalid number \"" + x.text + "\"");
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

bool Preprocessor::evaluate(const std::vector<Token>& args, const Token& name_tok,
                            const Line& l) {
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

} // namespace sss::preprocess_detail
