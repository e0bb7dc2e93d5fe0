// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the shading module: the syntax tree the parser builds
// (shading.md section 2) and the code generator walks.

#include <memory>
#include <string>
#include <vector>

#include "diagnostics.h"
#include "lexer.h"
#include "sss/rsl/program.h"

namespace sss::detail {

enum class ExprKind {
    Number,  ///< number
    String,  ///< text
    Ident,   ///< text = name
    Index,   ///< text = array name, args[0] = index
    Call,    ///< text = function, args; channel = texture channel of args[0]
    Triple,  ///< (a, b, c): args
    Tuple16, ///< 16-tuple: args
    Cast,    ///< cast_type [space] args[0]
    Unary,   ///< text = "-" or "!", args[0]
    Binary,  ///< text = operator, args[0], args[1]
    Ternary, ///< args[0] ? args[1] : args[2]
    Assign,  ///< args[0] (Ident or Index) text= args[1]; text "=", "+=", ...
    /// RSL 2.0 co-shader call `obj->method(a, b)`: text = method, args[0] =
    /// obj (a shader value), args[1...] = the arguments.
    MethodCall
};

struct Expr;
using ExprPtr = std::unique_ptr<Expr>;

struct Expr {
    ExprKind kind = ExprKind::Number;
    SrcLoc loc;
    double number = 0.0;
    std::string text;
    ShadingType cast_type = ShadingType::Float;
    bool has_space = false;
    std::string space;
    std::vector<ExprPtr> args;
    ExprPtr channel;
};

enum class Storage { Default, Uniform, Varying };

/// One declared name: `x`, `a[3] = {1, 2, 3}`, `f[]` (a function parameter
/// taking any length, or a resizable local).
struct Declarator {
    std::string name;
    SrcLoc loc;
    int array = 0;             ///< > 0 fixed length, kResizableArray "[]"
    ExprPtr init;              ///< = expr
    std::vector<ExprPtr> list; ///< = { ... }
    bool has_list = false;
};

/// A declaration group: `[extern] [output] [uniform|varying] type ["space"] d, d...`.
struct VarDecl {
    SrcLoc loc;
    bool is_extern = false;
    bool output = false;
    Storage storage = Storage::Default;
    ShadingType type = ShadingType::Float;
    bool has_space = false;
    std::string space;
    std::vector<Declarator> names;
};

struct Stmt;
using StmtPtr = std::unique_ptr<Stmt>;

struct FuncDef {
    SrcLoc loc;
    std::string name;
    bool is_public = false; ///< a class's `public` method
    ShadingType result = ShadingType::Void;
    std::vector<VarDecl> params; ///< one entry per parameter group
    StmtPtr body;                ///< a Block
};

enum class StmtKind {
    Expr,
    Decl,
    Func,
    Return,
    Block,
    Empty,
    Break,
    Continue,
    If,
    While,
    For,
    Illuminance,
    Illuminate,
    Solar,
    Gather
};

struct Stmt {
    StmtKind kind = StmtKind::Empty;
    SrcLoc loc;
    ExprPtr expr; ///< Expr, Return (may be null), If / While condition
    /// For: init, cond, step (any may be null); light loops: args (for
    /// illuminance, "name", value options after the positional ones).
    std::vector<ExprPtr> exprs;
    std::vector<StmtPtr> body; ///< Block
    StmtPtr sub;               ///< If: then; loops: body
    StmtPtr else_sub;          ///< If / Gather: else
    int level = 1;             ///< Break / Continue
    std::unique_ptr<VarDecl> decl;
    std::shared_ptr<FuncDef> func;
};

struct ShaderDef {
    SrcLoc loc;
    ShaderKind kind = ShaderKind::Surface;
    std::string name;
    std::vector<VarDecl> params;
    StmtPtr body; ///< null for a class
    /// RSL 2.0 `class name(params) { members and methods }`: the kind is
    /// decided by the methods it defines (codegen_class.cpp).
    bool is_class = false;
    std::vector<VarDecl> members;
    std::vector<std::shared_ptr<FuncDef>> methods;
};

/// A parsed file: its shaders and top-level functions, in order.
struct SourceFile {
    std::vector<ShaderDef> shaders;
    std::vector<std::shared_ptr<FuncDef>> functions;
};

/// Parses `tokens` (from tokenize). Syntax errors go to `diags`; the parser
/// recovers at the next `;` or `}` and keeps going.
SourceFile parse(const std::vector<Token>& tokens, DiagnosticSink& diags);

} // namespace sss::detail
