// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal to the shading module: the code generator shared by codegen.cpp
// (driver, symbols, variables), codegen_types.cpp (conversions, operator
// types, uniform/varying), codegen_expr.cpp (expressions), codegen_calls.cpp
// (overloads, built-in calls, inlining of user functions) and codegen_stmt.cpp
// (statements). One Generator walks one shader once per pass (codegen.h).

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "codegen.h"
#include "sss/rsl/builtins.h"
#include "sss/util/math.h"

namespace sss::detail::codegen {

using sss::kPi;
constexpr std::size_t kMaxOps = 500000;
constexpr std::size_t kMaxSymbols = 500000;
constexpr std::size_t kMaxInlineDepth = 64; ///< calls inside calls inside calls...
constexpr int kDemotionPasses = 8;          ///< then every undeclared local is varying

// --- globals (shading.md section 4) ------------------------------------------

// surface, displacement, light, volume, imager
constexpr unsigned kS = 1, kD = 2, kL = 4, kV = 8, kI = 16;

struct GlobalDef {
    const char* name;
    ShadingType type;
    bool varying;
    unsigned read;
    unsigned write;
    unsigned in_loop; ///< kinds where it exists only inside illuminance / illuminate
};

unsigned kind_bit(ShaderKind k);
const GlobalDef* find_global(const std::string& name);

// --- built-in prototypes (builtins.h) ----------------------------------------

struct PArg {
    char letter = 'f'; ///< f c p v n m s x .
    bool output = false;
    bool array = false;
};

struct Proto {
    const BuiltinSignature* sig = nullptr;
    char result = 'o';
    std::vector<PArg> fixed;
    bool has_rest = false;
    PArg rest;
    char tokens = 0; ///< 0, '!' or '@'
};

/// The built-in prototypes of builtins.h, parsed once.
const std::vector<Proto>& protos();

// --- the generator -----------------------------------------------------------

/// A value: a symbol index, kError after a reported error, kVoid for a void call.
struct Val {
    static constexpr int kError = -1;
    static constexpr int kVoid = -2;
    int sym = kError;
    bool ok() const { return sym >= 0; }
};

struct Var {
    int sym = -1;
    bool readonly = false;
    const char* what = "variable";
};

struct Scope;

struct FuncEntry {
    const FuncDef* def = nullptr;
    Scope* scope = nullptr; ///< where it was defined (externs, visible functions)
    bool method = false;    ///< a class's method: sees the members in `scope`
};

struct Scope {
    Scope* parent = nullptr; ///< variables (null at a function's parameters)
    Scope* outer = nullptr;  ///< functions and externs
    std::unordered_map<std::string, Var> vars;
    std::unordered_map<std::string, std::vector<FuncEntry>> funcs;
};

/// Loops, inlined functions and the body: where a varying exit (break,
/// continue, return under a varying condition) masks what follows.
struct Region {
    enum Kind { Body, Loop, Function } kind = Body;
    std::vector<int> assigned; ///< undeclared-storage locals assigned inside
    bool varying_exit = false;
};

struct FuncCtx {
    const FuncDef* def = nullptr;
    int result = -1;
    bool result_varying = false;
    int saved_loop_depth = 0;
    int instance = 0; ///< names this inlining's locals
    /// The varying conditions and regions around the call: a return is
    /// varying only under conditions of the function's own.
    int entry_varying_cond = 0;
    std::size_t entry_region = 0;
};

/// A call argument: generated, or a bare tuple generated once the callee's
/// parameter type is known.
struct ArgInfo {
    const Expr* expr = nullptr;
    Val val;
    bool literal = false; ///< a bare (a,b,c) or 16-tuple, not generated yet
    bool is_var = false;  ///< a plain variable (for output and by-reference params)
    Var var;
};

inline bool is_bare_tuple(const Expr& e) {
    return e.kind == ExprKind::Triple || e.kind == ExprKind::Tuple16;
}

inline std::string tname(const TypeSpec& t) {
    return type_spec_name(t);
}

class Generator {
public:
    Generator(const SourceFile& file, const ShaderDef& shader, DiagnosticSink& diags,
              const std::set<std::string>& forced, std::set<std::string>& newly_forced,
              bool demote)
        : m_file(file), m_shader(shader), m_d(diags), m_forced(forced),
          m_newly(newly_forced), m_demote(demote) {}

    Program run();

private:
    // --- symbols and ops --------------------------------------------------
    struct LocGuard {
        Generator& g;
        SrcLoc saved;
        LocGuard(Generator& gen, SrcLoc at) : g(gen), saved(gen.m_loc) { g.m_loc = at; }
        ~LocGuard() { g.m_loc = saved; }
    };

    void error(SrcLoc at, const std::string& msg) { m_d.error(at, msg); }

    Scope* new_scope(Scope* parent);
    std::string unique_name(const std::string& base);
    int add_symbol(const std::string& name, TypeSpec type, bool varying, SymbolKind kind);
    int temp(TypeSpec type, bool varying);
    int konst(TypeSpec type, std::vector<float> numbers,
              std::vector<std::string> strings);
    int kfloat(double v);
    int kstring(const std::string& s) { return konst({ShadingType::String, 0}, {}, {s}); }
    int ktriple(ShadingType t, float x, float y, float z);
    int emit(const std::string& name, std::vector<int> args, uint64_t writes = 1);
    int here() const { return static_cast<int>(m_p.ops.size()); }

    const TypeSpec& type(int s) const { return m_p.symbols[s].type; }
    bool varying(int s) const { return m_p.symbols[s].varying; }
    bool is_const(int s) const { return m_p.symbols[s].kind == SymbolKind::Const; }

    // --- variables ----------------------------------------------------------
    // A global of this shader kind, created on first use; null if there is none.
    const Var* global(const std::string& name, SrcLoc at);

    // Plain lookup: this function's scopes (or the body's), then globals.
    const Var* lookup(const std::string& name, SrcLoc at, bool report = true);

    // extern: every enclosing scope, through function boundaries.
    const Var* lookup_extern(const std::string& name, SrcLoc at);

    // --- uniform / varying ------------------------------------------------
    void force_varying(int sym);

    // A store of a value (varying or not) into `target`.
    void check_store(int target, bool value_varying, SrcLoc at);

    // Under a varying condition, or after a varying return in this function
    // (or the body): only some points run.
    bool masked() const;
    /// masked() counting only the conditions and exits inside the function
    /// being inlined: what makes its result or its exit varying.
    bool masked_in_function() const;

    // A loop left by some points only runs its next iterations masked:
    // whatever it assigns is varying.
    void pop_region();

    // --- conversions --------------------------------------------------------
    static bool convertible(const TypeSpec& from, const TypeSpec& to);
    std::string conversion_error(const TypeSpec& from, const TypeSpec& to);

    // v as type `to`, converting (a temp) when needed; errors when impossible.
    Val convert(Val v, const TypeSpec& to, SrcLoc at);

    // --- expressions ----------------------------------------------------------
    Val value(const Expr& e, const TypeSpec* hint = nullptr);

    // A condition: a float (non-zero is true); triples compare against 0.
    Val condition(const Expr& e);
    Val gen(const Expr& e, const TypeSpec* hint);
    bool shadowed(const std::string& name);
    Val gen_index(const Expr& e);

    // (a,b,c) or the 16-tuple as `type`, with an optional space (string symbol).
    Val gen_tuple(const Expr& e, ShadingType t, int space);
    Val gen_cast(ShadingType t, bool has_space, const std::string& space_name,
                 const Expr& x, SrcLoc at);

    Val gen_unary(const Expr& e, const TypeSpec* hint);

    // The result type of a binary operator, or Void (with `why`) if illegal.
    ShadingType binary_type(const std::string& op, ShadingType a, ShadingType b,
                            std::string& why);

    static const char* op_name(const std::string& op);
    Val arith(const std::string& op, Val a, Val b, SrcLoc at);
    Val gen_binary(const Expr& e, const TypeSpec* hint);
    Val gen_ternary(const Expr& e, const TypeSpec* hint);
    bool check_writable(const Var& v, const std::string& name, SrcLoc at);
    Val gen_assign(const Expr& e);

    // --- calls ------------------------------------------------------------
    int arg_cost(const ArgInfo& a, ShadingType want, bool want_array, bool output);

    struct Match {
        int cost = 0;
        ShadingType x = ShadingType::Point;
        std::vector<PArg> slots; ///< one per argument (token names/values as '.')
        std::vector<bool> token_value;
    };

    bool match(const Proto& p, const std::vector<ArgInfo>& args, const TypeSpec* hint,
               Match& m);

    // 0: the result is what is expected, 1: it converts, 2: it does not.
    int hint_rank(ShadingType result, const TypeSpec* hint);

    // texture(name[i], ...) with `name` a string variable: i is the channel.
    bool string_subscript(const Expr& e);
    std::vector<ArgInfo> gather_args(const Expr& e, bool texture_like);
    Val gen_call(const Expr& e, const TypeSpec* hint);

    // In a '@' token-value list (texture3d), a value is written when it is a
    // writable variable, unless its name is one of the options that are read.
    bool written_token(const ArgInfo& name, const ArgInfo& value);

    // occlusion() and indirectdiffuse(): the values of "environmentcolor",
    // "environmentdir" and "occlusion" are outputs (variables, written).
    bool ray_output_token(const std::string& fn, const ArgInfo& name);
    Val builtin_call(const Proto& p, const Match& m, std::vector<ArgInfo>& args,
                     const Expr& e);

    // Flattened parameters of a user function.
    struct UParam {
        const VarDecl* group;
        const Declarator* decl;
    };
    static std::vector<UParam> user_params(const FuncDef& f);
    /// Whether the arguments fit f's parameters (cost: conversions). An
    /// array of the wrong length for a fixed-length array parameter does not
    /// fit; `why` (when given) then says which.
    bool match_user(const FuncDef& f, const std::vector<ArgInfo>& args, int& cost,
                    std::string* why = nullptr);
    Val inline_call(const FuncEntry& fe, std::vector<ArgInfo>& args, const Expr& call);
    /// Emits ctx.def's body as a `block` op with `params` as its parameter
    /// scope; returns whether a return in it is varying.
    bool function_block(FuncCtx& ctx, Scope* params);

    // --- classes (codegen_class.cpp) -----------------------------------------
    /// A class shader (RSL 2.0): parameters, member variables, the methods
    /// other shaders and the renderer call, and the pipelines.
    Program run_class();
    /// Emits `f` as a Method of the program (its own parameter symbols; a
    /// pipeline method's parameters are the globals they name), with the
    /// rules of shader kind `kind`.
    void standalone_method(const FuncDef& f, Scope* members, ShaderKind kind,
                           bool pipeline);
    /// The pipelines of the class from the methods it defines (indices into
    /// m_p.methods by name); errors for impossible combinations.
    void class_pipelines();

    // --- co-shaders (codegen_coshader.cpp) -----------------------------------
    /// getshader, getshaders, getlight, getlights, getvar, hasmethod.
    static bool is_coshader_function(const std::string& name);
    /// A call of one of them; getshaders and getlights fill `target` (a
    /// resizable shader array) when it is >= 0, else a temporary.
    Val coshader_call(const Expr& e, std::vector<ArgInfo>& args, int target);
    /// Whether `e` is a call of getshaders or getlights (an array value).
    bool is_array_producer(const Expr& e);
    /// `array = getlights(...)`: the call writes the resizable array `target`.
    void produce_array(int target, const std::string& name, const Expr& call);
    /// `obj->method(args)`: its result takes the expected type (float without
    /// one); `discard` for a call whose value is not used (a statement).
    Val gen_method_call(const Expr& e, const TypeSpec* hint, bool discard);
    /// The null shader handle.
    int knull() { return konst({ShadingType::Shader, 0}, {0.0f}, {}); }

    // --- resizable arrays (codegen_arrays.cpp) ------------------------------
    /// arraylength, resize, push, pop, reserve.
    static bool is_array_function(const std::string& name);
    Val array_call(const Expr& e, std::vector<ArgInfo>& args);

    // --- statements ---------------------------------------------------------
    void statement(const Stmt& s);
    void sub_statement(const Stmt& s);
    void declaration(const VarDecl& d);

    // The initializer of a local or of a parameter: stores into `sym`.
    void initialise(int sym, const VarDecl& d, const Declarator& n);
    Val elem_value(const VarDecl& d, const Expr& e, const TypeSpec& et);
    void parameter_group(const VarDecl& g);
    void return_statement(const Stmt& s);
    void jump_statement(const Stmt& s);
    void if_statement(const Stmt& s);
    void loop_statement(const Stmt& s);
    Val typed_arg(const Expr& e, ShadingType t);
    void light_statement(const Stmt& s);

    // illuminance([category,] P [, axis, angle] [, "name", value]...): the op's
    // four fixed arguments, then the options it keeps.
    void illuminance_statement(const Stmt& s);
    // The "name", value options of illuminance from exprs[first]: appended to
    // args (outputs' bits in writes); unknown names warn and are dropped.
    bool illuminance_options(const Stmt& s, std::size_t first, std::vector<int>& args,
                             uint64_t& writes);
    // The body of a light statement after its op.
    void light_body(const Stmt& s, int op);

    // gather(category, P, dir, angle, samples, "name", value...) hit [else miss]:
    // op `gather` with the five fixed arguments (string, point, vector, float,
    // float) and the token-value pairs; values of output tokens ("surface:x",
    // "ray:...", "environment:...") are variables, written (varying).
    void gather_statement(const Stmt& s);

    const SourceFile& m_file;
    const ShaderDef& m_shader;
    DiagnosticSink& m_d;
    const std::set<std::string>& m_forced;
    std::set<std::string>& m_newly;
    const bool m_demote;
    Program m_p;
    /// The kind of the code being generated: the shader's, or for a class
    /// the kind of the method (displacement, surface...).
    ShaderKind m_kind = ShaderKind::Surface;
    unsigned m_kind_bit = kS;
    SrcLoc m_loc;

    std::vector<std::unique_ptr<Scope>> m_scopes;
    Scope* m_scope = nullptr;
    std::unordered_map<std::string, Var> m_globals; ///< by name and kind bit
    std::unordered_map<std::string, int> m_global_syms;
    std::unordered_set<std::string> m_names;
    std::unordered_map<std::string, int> m_consts;
    std::unordered_set<int>
        m_tentative;                ///< locals without a storage class, still uniform
    std::unordered_set<int> m_auto; ///< temps whose storage is settled afterwards
    std::vector<Region> m_regions;
    std::vector<FuncCtx> m_funcs;
    std::vector<const FuncDef*> m_inline;
    int m_ntemp = 0, m_nconst = 0, m_instances = 0;
    int m_varying_cond = 0;
    std::set<std::string> m_warned_names; ///< lenient names already warned about
    int m_loop_depth = 0;
    int m_in_illuminance = 0;
    int m_in_light_loop = 0;
};

} // namespace sss::detail::codegen
