// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file parser.cpp
/// Recursive-descent parser for RSL (shading.md section 2): shader and
/// function definitions (nested too), declarations, statements and
/// expressions with the RISpec precedence table. Errors are collected; the
/// parser skips to the next `;` or `}` and goes on. Nesting deeper than
/// kMaxDepth is an error, so no input can exhaust the stack.

#include <algorithm>
#include <string_view>

#include "ast.h"

namespace sss::detail {

namespace {

constexpr int kMaxDepth = 256;

struct SyntaxError {};

bool is_type_word(std::string_view w) {
    return w == "float" || w == "color" || w == "point" || w == "vector" ||
           w == "normal" || w == "matrix" || w == "string" || w == "void";
}

ShadingType type_of(std::string_view w) {
    if (w == "color") return ShadingType::Color;
    if (w == "point") return ShadingType::Point;
    if (w == "vector") return ShadingType::Vector;
    if (w == "normal") return ShadingType::Normal;
    if (w == "matrix") return ShadingType::Matrix;
    if (w == "string") return ShadingType::String;
    if (w == "void") return ShadingType::Void;
    if (w == "shader") return ShadingType::Shader;
    return ShadingType::Float;
}

bool has_space_literal(ShadingType t) {
    return t == ShadingType::Color || is_point_like(t) || t == ShadingType::Matrix;
}

class Parser {
public:
    Parser(const std::vector<Token>& tokens, DiagnosticSink& diags)
        : m_toks(tokens), m_diags(diags) {}

    SourceFile file() {
        SourceFile out;
        while (!at_end()) {
            try {
                top_level(out);
            } catch (const SyntaxError&) {
                recover_top();
            }
        }
        return out;
    }

private:
    struct DepthGuard {
        Parser& p;
        explicit DepthGuard(Parser& parser) : p(parser) {
            if (++p.m_depth > kMaxDepth) {
                p.m_diags.error(p.peek().loc, "nesting too deep (more than " +
                                                  std::to_string(kMaxDepth) + " levels)");
                throw CompileAbort{};
            }
        }
        ~DepthGuard() { --p.m_depth; }
    };

    // --- tokens ---------------------------------------------------------
    const Token& peek(std::size_t ahead = 0) const {
        std::size_t i = std::min(m_pos + ahead, m_toks.size() - 1);
        return m_toks[i];
    }
    bool at_end() const { return peek().kind == TokKind::End; }
    bool is(std::string_view text, std::size_t ahead = 0) const {
        const Token& t = peek(ahead);
        return (t.kind == TokKind::Punct || t.kind == TokKind::Keyword) && t.text == text;
    }
    bool accept(std::string_view text) {
        if (!is(text)) return false;
        ++m_pos;
        return true;
    }
    const Token& take() {
        const Token& t = peek();
        if (m_pos + 1 < m_toks.size()) ++m_pos;
        return t;
    }
    [[noreturn]] void fail(const Token& at, const std::string& message) {
        m_diags.error(at.loc, message);
        throw SyntaxError{};
    }
    void expect(std::string_view text, const char* where = nullptr) {
        if (accept(text)) return;
        std::string msg = "expected '" + std::string(text) + "'";
        if (where) msg += std::string(" ") + where;
        fail(peek(), msg + ", got " + describe(peek()));
    }
    std::string ident(const char* what) {
        if (peek().kind != TokKind::Ident) {
            if (peek().kind == TokKind::Keyword)
                fail(peek(),
                     "'" + peek().text + "' is a keyword and cannot be used as " + what);
            fail(peek(), std::string("expected ") + what + ", got " + describe(peek()));
        }
        return take().text;
    }
    bool at_type() const {
        return (peek().kind == TokKind::Keyword && is_type_word(peek().text)) ||
               at_shader_type();
    }
    /// `shader name`: RSL 2.0's co-shader type, which is not reserved (old
    /// shaders name variables `shader`), so only a type before a name.
    bool at_shader_type(std::size_t ahead = 0) const {
        return peek(ahead).kind == TokKind::Ident && peek(ahead).text == "shader" &&
               peek(ahead + 1).kind == TokKind::Ident;
    }

    // Skips to just after the next `;` or to the next `}` of this level.
    void recover_stmt() {
        int depth = 0;
        while (!at_end()) {
            if (is("{")) {
                ++depth;
            } else if (is("}")) {
                if (depth == 0) return;
                --depth;
                if (depth == 0) {
                    ++m_pos;
                    return;
                }
            } else if (is(";") && depth == 0) {
                ++m_pos;
                return;
            }
            ++m_pos;
        }
    }
    void recover_top() {
        int depth = 0;
        while (!at_end()) {
            if (is("{")) {
                ++depth;
            } else if (is("}")) {
                ++m_pos;
                if (--depth <= 0) return;
                continue;
            } else if (is(";") && depth == 0) {
                ++m_pos;
                return;
            }
            ++m_pos;
        }
    }

    // --- top level ------------------------------------------------------
    void top_level(SourceFile& out) {
        const Token& t = peek();
        if (t.kind == TokKind::Ident && peek(1).kind == TokKind::Ident &&
            (t.text == "surface" || t.text == "displacement" || t.text == "light" ||
             t.text == "volume" || t.text == "imager" || t.text == "transformation")) {
            shader(out, t);
            return;
        }
        if (t.kind == TokKind::Ident && t.text == "class" &&
            peek(1).kind == TokKind::Ident && is("(", 2)) {
            class_def(out);
            return;
        }
        if (at_type() || at_storage_function() ||
            (t.kind == TokKind::Ident && is("(", 1))) {
            out.functions.push_back(function());
            return;
        }
        if (accept(";")) return;
        fail(t, "expected a shader or function definition, got " + describe(t));
    }

    void shader(SourceFile& out, const Token& kind_tok) {
        const std::string kind = take().text;
        ShaderDef def;
        def.loc = kind_tok.loc;
        def.name = ident("a shader name");
        if (kind == "surface")
            def.kind = ShaderKind::Surface;
        else if (kind == "displacement")
            def.kind = ShaderKind::Displacement;
        else if (kind == "light")
            def.kind = ShaderKind::Light;
        else if (kind == "imager")
            def.kind = ShaderKind::Imager;
        else
            def.kind = ShaderKind::Volume;
        expect("(", "after the shader name");
        while (accept(";")) {
        } // empty declarations, as macros leave them
        while (!is(")")) {
            def.params.push_back(var_decl(/*shader_param=*/true));
            if (!accept(";")) break;
            while (accept(";")) {
            }
        }
        expect(")", "after the shader parameters");
        def.body = block();
        if (kind == "transformation") {
            // RISpec 3.2 has them; PRMan never ran them and dropped the type.
            m_diags.error(kind_tok.loc,
                          "transformation shaders are not supported (PRMan does not run "
                          "them either); write a surface, displacement, light, volume "
                          "or imager shader");
            return;
        }
        out.shaders.push_back(std::move(def));
    }

    /// `class name(params) { members and methods }` (RSL 2.0 shader objects).
    void class_def(SourceFile& out) {
        ShaderDef def;
        def.loc = take().loc;
        def.is_class = true;
        def.name = ident("a class name");
        expect("(", "after the class name");
        while (accept(";")) {
        }
        while (!is(")")) {
            def.params.push_back(var_decl(/*shader_param=*/true));
            if (!accept(";")) break;
            while (accept(";")) {
            }
        }
        expect(")", "after the class parameters");
        expect("{", "to start the body of the class");
        while (!is("}")) {
            if (at_end()) fail(peek(), "missing '}' at the end of the class");
            try {
                class_member(def);
            } catch (const SyntaxError&) {
                recover_stmt();
            }
        }
        ++m_pos;
        out.shaders.push_back(std::move(def));
    }

    /// One member of a class: `[public] type name(...) {...}` (a method) or a
    /// member variable declaration (`constant` is PRMan 16's storage for
    /// values set once: here uniform).
    void class_member(ShaderDef& def) {
        if (accept(";")) return;
        const Token& start = peek();
        const bool is_public = start.kind == TokKind::Ident && start.text == "public";
        if (is_public) ++m_pos;
        if (at_function_def() || at_storage_function() ||
            (peek().kind == TokKind::Keyword && peek().text == "void")) {
            std::shared_ptr<FuncDef> f = function();
            f->is_public = is_public;
            def.methods.push_back(std::move(f));
            return;
        }
        if (is_public) fail(start, "'public' is only for methods");
        bool constant = false;
        if (peek().kind == TokKind::Ident && peek().text == "constant") {
            ++m_pos;
            constant = true;
        }
        VarDecl d = var_decl(/*shader_param=*/false);
        if (d.is_extern) fail(start, "a member variable cannot be extern");
        if (constant) {
            if (d.storage == Storage::Varying)
                fail(start, "a member variable cannot be both constant and varying");
            d.storage = Storage::Uniform;
        }
        expect(";", "after the member declaration");
        def.members.push_back(std::move(d));
    }

    /// At `uniform|varying type name (`: a function whose result has a
    /// storage class, which PRMan accepts (and which changes nothing here).
    bool at_storage_function() const {
        return (is("uniform") || is("varying")) && peek(1).kind == TokKind::Keyword &&
               is_type_word(peek(1).text) && peek(2).kind == TokKind::Ident && is("(", 3);
    }

    std::shared_ptr<FuncDef> function() {
        auto f = std::make_shared<FuncDef>();
        f->loc = peek().loc;
        if (at_storage_function()) ++m_pos;
        if (at_type()) f->result = type_of(take().text);
        f->name = ident("a function name");
        expect("(", "after the function name");
        while (!is(")")) {
            f->params.push_back(func_params());
            if (accept(";")) continue;
            // Also `float a, float b` (C style).
            if (is(",")) {
                ++m_pos;
                continue;
            }
            break;
        }
        expect(")", "after the function parameters");
        if (!is("{")) fail(peek(), "expected '{' to start the body of '" + f->name + "'");
        f->body = block();
        return f;
    }

    VarDecl func_params() {
        VarDecl d;
        d.loc = peek().loc;
        if (accept("output")) d.output = true;
        storage(d);
        if (!at_type())
            fail(peek(), "expected a parameter type, got " + describe(peek()));
        d.type = type_of(take().text);
        if (d.type == ShadingType::Void) fail(peek(), "a parameter cannot be void");
        for (;;) {
            Declarator n;
            n.loc = peek().loc;
            n.name = ident("a parameter name");
            // `name[]` takes an array of any length (fixed or resizable),
            // `name[16]` one of exactly that length.
            if (accept("[")) n.array = is("]") ? kResizableArray : array_length();
            if (n.array == kResizableArray) expect("]", "after '['");
            d.names.push_back(std::move(n));
            // `float a, b` continues the group; `float a, float b` starts another.
            if (!is(",") || peek(1).kind != TokKind::Ident) break;
            ++m_pos;
        }
        return d;
    }

    // `N]` after a '[': a fixed array length.
    int array_length() {
        if (peek().kind != TokKind::Number)
            fail(peek(), "expected the array length, got " + describe(peek()));
        const Token& len = take();
        if (len.number < 1 || len.number > kMaxArrayLength ||
            len.number != static_cast<int>(len.number))
            fail(len, "the array length must be a whole number from 1 to " +
                          std::to_string(kMaxArrayLength));
        expect("]", "after the array length");
        return static_cast<int>(len.number);
    }

    void storage(VarDecl& d) {
        if (accept("uniform"))
            d.storage = Storage::Uniform;
        else if (accept("varying"))
            d.storage = Storage::Varying;
    }

    // sgroup (shader parameters, defaults required) or a local vardecl.
    VarDecl var_decl(bool shader_param) {
        VarDecl d;
        d.loc = peek().loc;
        if (!shader_param && accept("extern")) d.is_extern = true;
        if (accept("output")) {
            if (!shader_param) fail(peek(), "'output' is only for parameters");
            d.output = true;
        }
        storage(d);
        if (!at_type()) fail(peek(), "expected a type, got " + describe(peek()));
        const Token& type_tok = take();
        d.type = type_of(type_tok.text);
        if (d.type == ShadingType::Void) fail(type_tok, "a variable cannot be void");
        if (peek().kind == TokKind::String && has_space_literal(d.type)) {
            d.has_space = true;
            d.space = take().text;
        }
        for (;;) {
            Declarator n;
            n.loc = peek().loc;
            n.name = ident(shader_param ? "a parameter name" : "a variable name");
            // A local `name[]` is resizable; a shader parameter needs a length.
            if (accept("[")) {
                if (!shader_param && accept("]"))
                    n.array = kResizableArray;
                else
                    n.array = array_length();
            }
            if (accept("=")) {
                if (is_extern_decl(d))
                    fail(peek(), "an extern declaration has no initializer");
                if (accept("{")) {
                    n.has_list = true;
                    if (!is("}")) {
                        do n.list.push_back(assignment());
                        while (accept(","));
                    }
                    expect("}", "after the array values");
                } else {
                    n.init = assignment();
                }
            } else if (shader_param) {
                fail(peek(), "shader parameter '" + n.name + "' needs a default value");
            }
            d.names.push_back(std::move(n));
            if (!accept(",")) break;
        }
        return d;
    }
    static bool is_extern_decl(const VarDecl& d) { return d.is_extern; }

    // --- statements -----------------------------------------------------
    StmtPtr block() {
        DepthGuard guard(*this);
        auto s = std::make_unique<Stmt>();
        s->kind = StmtKind::Block;
        s->loc = peek().loc;
        expect("{");
        while (!is("}")) {
            if (at_end()) fail(peek(), "missing '}' at the end of the file");
            try {
                s->body.push_back(statement());
            } catch (const SyntaxError&) {
                recover_stmt();
            }
        }
        ++m_pos;
        return s;
    }

    // True at `[type] name (...) {`: a function definition, not a call.
    bool at_function_def() const {
        std::size_t i = 0;
        if ((peek().kind == TokKind::Keyword && is_type_word(peek().text)) ||
            at_shader_type())
            i = 1;
        if (peek(i).kind != TokKind::Ident || !is("(", i + 1)) return false;
        if (i == 1) return true;
        int depth = 0;
        for (std::size_t k = m_pos + i + 1; k < m_toks.size(); ++k) {
            const Token& t = m_toks[k];
            if (t.kind == TokKind::End) return false;
            if (t.kind != TokKind::Punct) continue;
            if (t.text == "(")
                ++depth;
            else if (t.text == ")" && --depth == 0)
                return k + 1 < m_toks.size() && m_toks[k + 1].kind == TokKind::Punct &&
                       m_toks[k + 1].text == "{";
            else if (t.text == ";" || t.text == "{" || t.text == "}")
                return false;
        }
        return false;
    }

    /// `s` as the function definition the tokens start.
    StmtPtr function_statement(StmtPtr s) {
        s->kind = StmtKind::Func;
        s->func = function();
        return s;
    }

    /// `s` as the variable declaration the tokens start, up to its ';'.
    StmtPtr declaration_statement(StmtPtr s) {
        s->kind = StmtKind::Decl;
        s->decl = std::make_unique<VarDecl>(var_decl(false));
        expect(";", "after the declaration");
        return s;
    }

    StmtPtr statement() {
        DepthGuard guard(*this);
        auto s = std::make_unique<Stmt>();
        s->loc = peek().loc;
        const Token& t = peek();
        if (is("{")) return block();
        if (accept(";")) {
            s->kind = StmtKind::Empty;
            return s;
        }
        if (t.kind == TokKind::Keyword) {
            const std::string& w = t.text;
            if (w == "if") {
                ++m_pos;
                s->kind = StmtKind::If;
                expect("(", "after 'if'");
                s->expr = expression();
                expect(")", "after the condition");
                s->sub = statement();
                if (accept("else")) s->else_sub = statement();
                return s;
            }
            if (w == "while") {
                ++m_pos;
                s->kind = StmtKind::While;
                expect("(", "after 'while'");
                s->expr = expression();
                expect(")", "after the condition");
                s->sub = statement();
                return s;
            }
            if (w == "for") {
                ++m_pos;
                s->kind = StmtKind::For;
                expect("(", "after 'for'");
                s->exprs.push_back(is(";") ? nullptr : expression());
                expect(";", "after the loop's initialisation");
                if (is(";")) fail(peek(), "a for loop needs a condition");
                s->exprs.push_back(expression());
                expect(";", "after the loop's condition");
                s->exprs.push_back(is(")") ? nullptr : expression());
                expect(")", "after the loop's step");
                s->sub = statement();
                return s;
            }
            if (w == "break" || w == "continue") {
                ++m_pos;
                s->kind = w == "break" ? StmtKind::Break : StmtKind::Continue;
                if (peek().kind == TokKind::Number) {
                    const Token& n = take();
                    if (n.number < 1 || n.number > 1000 ||
                        n.number != static_cast<int>(n.number))
                        fail(n, "the " + w + " level must be a whole number >= 1");
                    s->level = static_cast<int>(n.number);
                }
                expect(";", ("after '" + w + "'").c_str());
                return s;
            }
            if (w == "return") {
                ++m_pos;
                s->kind = StmtKind::Return;
                if (!is(";")) s->expr = expression();
                expect(";", "after the return value");
                return s;
            }
            if (w == "illuminance" || w == "illuminate" || w == "solar") {
                ++m_pos;
                s->kind = w == "illuminance"  ? StmtKind::Illuminance
                          : w == "illuminate" ? StmtKind::Illuminate
                                              : StmtKind::Solar;
                expect("(", ("after '" + w + "'").c_str());
                if (!is(")")) {
                    do s->exprs.push_back(assignment());
                    while (accept(","));
                }
                expect(")", ("after the arguments of " + w).c_str());
                const std::size_t n = s->exprs.size();
                // illuminance's trailing "name", value options: codegen.
                const bool ok = w == "illuminance"  ? n >= 1
                                : w == "illuminate" ? (n == 1 || n == 3)
                                                    : (n == 0 || n == 2);
                if (!ok)
                    m_diags.error(s->loc,
                                  w + (w == "illuminance"
                                           ? " takes ([category,] P [, axis, angle] [, "
                                             "\"name\", value]...)"
                                       : w == "illuminate" ? " takes (P [, axis, angle])"
                                                           : " takes ([axis, angle])"));
                s->sub = statement();
                return s;
            }
            if (w == "gather") {
                ++m_pos;
                s->kind = StmtKind::Gather;
                expect("(", "after 'gather'");
                if (!is(")")) {
                    do s->exprs.push_back(assignment());
                    while (accept(","));
                }
                expect(")", "after the arguments of gather");
                s->sub = statement();
                if (accept("else")) s->else_sub = statement();
                return s;
            }
            if (w == "extern" || w == "uniform" || w == "varying" || w == "output" ||
                (is_type_word(w) &&
                 (peek(1).kind == TokKind::Ident || peek(1).kind == TokKind::String))) {
                if ((is_type_word(w) && at_function_def()) || at_storage_function())
                    return function_statement(std::move(s));
                return declaration_statement(std::move(s));
            }
            if (w == "void") return function_statement(std::move(s));
            if (w == "else") fail(t, "'else' without 'if'");
        }
        if (at_shader_type()) {
            if (at_function_def()) return function_statement(std::move(s));
            return declaration_statement(std::move(s));
        }
        if (t.kind == TokKind::Ident && at_function_def())
            return function_statement(std::move(s));
        s->kind = StmtKind::Expr;
        s->expr = expression();
        expect(";", "after the expression");
        return s;
    }

    // --- expressions ----------------------------------------------------
    ExprPtr make(ExprKind kind, SrcLoc loc) {
        auto e = std::make_unique<Expr>();
        e->kind = kind;
        e->loc = loc;
        return e;
    }

    ExprPtr expression() { return assignment(); }

    ExprPtr assignment() {
        DepthGuard guard(*this);
        ExprPtr lhs = ternary();
        const Token& t = peek();
        if (t.kind == TokKind::Punct &&
            (t.text == "=" || t.text == "+=" || t.text == "-=" || t.text == "*=" ||
             t.text == "/=")) {
            if (lhs->kind != ExprKind::Ident && lhs->kind != ExprKind::Index)
                fail(t, "the left side of '" + t.text +
                            "' must be a variable or an array element");
            ++m_pos;
            auto e = make(ExprKind::Assign, t.loc);
            e->text = t.text;
            e->args.push_back(std::move(lhs));
            e->args.push_back(assignment());
            return e;
        }
        return lhs;
    }

    ExprPtr ternary() {
        ExprPtr c = binary(0);
        if (!is("?")) return c;
        const Token& q = take();
        DepthGuard guard(*this);
        auto e = make(ExprKind::Ternary, q.loc);
        e->args.push_back(std::move(c));
        e->args.push_back(assignment());
        expect(":", "in the ?: expression");
        e->args.push_back(ternary());
        return e;
    }

    // Binary levels, lowest first.
    static int level_of(const Token& t) {
        if (t.kind != TokKind::Punct) return -1;
        const std::string& s = t.text;
        if (s == "||") return 0;
        if (s == "&&") return 1;
        if (s == "==" || s == "!=") return 2;
        if (s == "<" || s == "<=" || s == ">" || s == ">=") return 3;
        if (s == "+" || s == "-") return 4;
        if (s == "^") return 5;
        if (s == "*" || s == "/") return 6;
        if (s == ".") return 7;
        return -1;
    }

    ExprPtr binary(int level) {
        if (level > 7) return unary();
        ExprPtr lhs = binary(level + 1);
        // A chain a+b+c... nests to the left: every operator counts as a level.
        std::vector<std::unique_ptr<DepthGuard>> chain;
        while (level_of(peek()) == level) {
            const Token& op = take();
            chain.push_back(std::make_unique<DepthGuard>(*this));
            auto e = make(ExprKind::Binary, op.loc);
            e->text = op.text;
            e->args.push_back(std::move(lhs));
            e->args.push_back(binary(level + 1));
            lhs = std::move(e);
        }
        return lhs;
    }

    ExprPtr unary() {
        DepthGuard guard(*this);
        const Token& t = peek();
        if (is("-") || is("!")) {
            ++m_pos;
            auto e = make(ExprKind::Unary, t.loc);
            e->text = t.text;
            e->args.push_back(unary());
            return e;
        }
        if (is("+")) {
            ++m_pos;
            return unary();
        }
        if (is("++") || is("--"))
            fail(t, "'" + t.text + "' is not supported; write " +
                        (t.text == "++" ? "x += 1" : "x -= 1"));
        if (peek().kind == TokKind::Keyword && is_type_word(peek().text) &&
            peek().text != "void") {
            // Typecast: type ["space"] unary.
            const Token& type_tok = take();
            auto e = make(ExprKind::Cast, type_tok.loc);
            e->cast_type = type_of(type_tok.text);
            if (peek().kind == TokKind::String && has_space_literal(e->cast_type)) {
                e->has_space = true;
                e->space = take().text;
            }
            e->args.push_back(unary());
            return e;
        }
        return postfix();
    }

    ExprPtr postfix() {
        ExprPtr e = primary();
        // obj->method(args): a co-shader's method (RSL 2.0).
        std::vector<std::unique_ptr<DepthGuard>> chain;
        while (is("->")) {
            const Token& arrow = take();
            chain.push_back(std::make_unique<DepthGuard>(*this));
            auto m = make(ExprKind::MethodCall, arrow.loc);
            m->text = ident("a method name");
            m->args.push_back(std::move(e));
            expect("(", ("after the method name '" + m->text + "'").c_str());
            if (!is(")")) {
                do m->args.push_back(assignment());
                while (accept(","));
            }
            expect(")", ("to close the call of method " + m->text).c_str());
            e = std::move(m);
        }
        if (is("++") || is("--"))
            fail(peek(), "'" + peek().text + "' is not supported; write " +
                             (peek().text == "++" ? "x += 1" : "x -= 1"));
        return e;
    }

    static bool callable_keyword(std::string_view w) {
        return w == "texture" || w == "environment" || w == "shadow" || w == "bump" ||
               w == "surface" || w == "displacement" || w == "light" || w == "volume";
    }

    ExprPtr call(const Token& name_tok) {
        auto e = make(ExprKind::Call, name_tok.loc);
        e->text = name_tok.text;
        expect("(");
        const bool texture_like = e->text == "texture" || e->text == "environment" ||
                                  e->text == "shadow" || e->text == "bump";
        if (!is(")")) {
            do {
                e->args.push_back(assignment());
                // texture("file"[chan], ...): the subscript belongs to the name.
                if (texture_like && e->args.size() == 1 && is("[")) {
                    ++m_pos;
                    e->channel = expression();
                    expect("]", "after the channel");
                }
            } while (accept(","));
        }
        expect(")", ("to close the call of " + e->text).c_str());
        return e;
    }

    ExprPtr primary() {
        const Token& t = peek();
        switch (t.kind) {
        case TokKind::Number: {
            ++m_pos;
            auto e = make(ExprKind::Number, t.loc);
            e->number = t.number;
            return e;
        }
        case TokKind::String: {
            ++m_pos;
            auto e = make(ExprKind::String, t.loc);
            e->text = t.text;
            return e;
        }
        case TokKind::Ident: {
            ++m_pos;
            if (is("(")) return call(t);
            if (is("[")) {
                ++m_pos;
                auto e = make(ExprKind::Index, t.loc);
                e->text = t.text;
                e->args.push_back(expression());
                expect("]", "after the array index");
                return e;
            }
            auto e = make(ExprKind::Ident, t.loc);
            e->text = t.text;
            return e;
        }
        case TokKind::Keyword:
            if (callable_keyword(t.text) && is("(", 1)) {
                ++m_pos;
                return call(t);
            }
            fail(t, "unexpected " + describe(t) + " in an expression");
        case TokKind::Punct:
            if (t.text == "(") {
                ++m_pos;
                ExprPtr first = expression();
                if (accept(")")) return first;
                auto e = make(ExprKind::Triple, t.loc);
                e->args.push_back(std::move(first));
                while (accept(",")) e->args.push_back(expression());
                expect(")", "to close the tuple");
                if (e->args.size() == 16)
                    e->kind = ExprKind::Tuple16;
                else if (e->args.size() != 3)
                    fail(t, "a tuple has 3 values (a triple) or 16 (a matrix), not " +
                                std::to_string(e->args.size()));
                return e;
            }
            fail(t, "unexpected " + describe(t) + " in an expression");
        case TokKind::End:
            fail(t, "unexpected end of the file in an expression");
        }
        fail(t, "unexpected " + describe(t));
    }

    const std::vector<Token>& m_toks;
    DiagnosticSink& m_diags;
    std::size_t m_pos = 0;
    int m_depth = 0;
};

} // namespace

SourceFile parse(const std::vector<Token>& tokens, DiagnosticSink& diags) {
    return Parser(tokens, diags).file();
}

} // namespace sss::detail
