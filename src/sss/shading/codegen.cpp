/// \file codegen.cpp
/// Type checking and code generation in one walk over the syntax tree:
/// scopes, the globals of each shader kind (shading.md section 4), implicit
/// conversions, uniform/varying inference, overload resolution against the
/// built-in table (also by the expected result type), and inlining of user
/// functions (RSL has no recursion) into `block` ops.
///
/// Locals declared without `uniform`/`varying` start uniform; a pass that
/// finds one assigned a varying value, or assigned under a varying
/// condition, marks it and the shader is generated again (a fixed point:
/// marks only grow). Only the last pass's messages are kept.

#include "codegen.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "builtins.h"

namespace sss::detail {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr std::size_t kMaxOps = 500000;
constexpr std::size_t kMaxSymbols = 500000;
constexpr std::size_t kMaxInlineDepth = 64; ///< calls inside calls inside calls...
constexpr int kDemotionPasses = 8;          ///< then every undeclared local is varying

// --- globals (shading.md section 4) ------------------------------------------

constexpr unsigned kS = 1, kD = 2, kL = 4; // surface, displacement, light

struct GlobalDef {
    const char* name;
    ShadingType type;
    bool varying;
    unsigned read;
    unsigned write;
    unsigned in_loop; ///< kinds where it exists only inside illuminance / illuminate
};

constexpr ShadingType F = ShadingType::Float, C = ShadingType::Color,
                      Pt = ShadingType::Point, Ve = ShadingType::Vector,
                      No = ShadingType::Normal;

// clang-format off
constexpr GlobalDef kGlobals[] = {
    {"Cs", C, true, kS, kS, 0}, {"Os", C, true, kS, kS, 0},
    {"P", Pt, true, kS | kD | kL, kS | kD, 0},
    {"dPdu", Ve, true, kS | kD | kL, 0, 0}, {"dPdv", Ve, true, kS | kD | kL, 0, 0},
    {"N", No, true, kS | kD | kL, kS | kD | kL, 0}, {"Ng", No, true, kS | kD | kL, 0, 0},
    {"u", F, true, kS | kD | kL, 0, 0}, {"v", F, true, kS | kD | kL, 0, 0},
    {"du", F, true, kS | kD | kL, 0, 0}, {"dv", F, true, kS | kD | kL, 0, 0},
    {"s", F, true, kS | kD | kL, kS | kD | kL, 0}, {"t", F, true, kS | kD | kL, kS | kD | kL, 0},
    {"E", Pt, false, kS | kD | kL, 0, 0}, {"I", Ve, true, kS | kD, 0, 0},
    {"ncomps", F, false, kS | kD | kL, 0, 0}, {"time", F, false, kS | kD | kL, 0, 0},
    {"dtime", F, false, kS | kD | kL, 0, 0}, {"dPdtime", Ve, true, kS | kD, 0, 0},
    {"Ci", C, true, kS, kS, 0}, {"Oi", C, true, kS, kS, 0},
    {"L", Ve, true, kS | kL, 0, kS | kL},
    {"Cl", C, true, kS | kL, kL, kS}, {"Ol", C, true, kS | kL, kL, kS},
    {"Ps", Pt, true, kL, 0, 0},
};
// clang-format on

unsigned kind_bit(ShaderKind k) {
    switch (k) {
    case ShaderKind::Surface:
        return kS;
    case ShaderKind::Displacement:
        return kD;
    case ShaderKind::Light:
        return kL;
    default:
        return 0;
    }
}

const GlobalDef* find_global(const std::string& name) {
    for (const GlobalDef& g : kGlobals)
        if (name == g.name) return &g;
    return nullptr;
}

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

std::vector<Proto> parse_protos() {
    std::vector<Proto> out;
    for (const BuiltinSignature& sig : builtin_signatures()) {
        Proto p;
        p.sig = &sig;
        const std::string s = sig.proto;
        p.result = s.empty() ? 'o' : s[0];
        for (std::size_t i = 2; i < s.size(); ++i) {
            const char c = s[i];
            if (c == '!' || c == '@') {
                p.tokens = c;
            } else if (c == '*') {
                if (!p.fixed.empty()) {
                    p.has_rest = true;
                    p.rest = p.fixed.back();
                    p.fixed.pop_back();
                }
            } else if (c == '[' && i + 2 < s.size()) {
                PArg a;
                a.letter = static_cast<char>(std::tolower(s[i + 1]));
                a.output = std::isupper(static_cast<unsigned char>(s[i + 1])) != 0;
                a.array = true;
                p.fixed.push_back(a);
                i += 2;
            } else {
                PArg a;
                a.letter = static_cast<char>(std::tolower(c));
                a.output = std::isupper(static_cast<unsigned char>(c)) != 0;
                p.fixed.push_back(a);
            }
        }
        out.push_back(p);
    }
    return out;
}

const std::vector<Proto>& protos() {
    static const std::vector<Proto> table = parse_protos();
    return table;
}

ShadingType letter_type(char c, ShadingType x) {
    switch (c) {
    case 'f':
        return ShadingType::Float;
    case 'c':
        return ShadingType::Color;
    case 'p':
        return ShadingType::Point;
    case 'v':
        return ShadingType::Vector;
    case 'n':
        return ShadingType::Normal;
    case 'm':
        return ShadingType::Matrix;
    case 's':
        return ShadingType::String;
    case 'x':
        return x;
    default:
        return ShadingType::Void;
    }
}

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

bool is_bare_tuple(const Expr& e) {
    return e.kind == ExprKind::Triple || e.kind == ExprKind::Tuple16;
}

std::string tname(const TypeSpec& t) {
    return type_spec_name(t);
}

class Generator {
public:
    Generator(const SourceFile& file, const ShaderDef& shader, DiagnosticSink& diags,
              const std::set<std::string>& forced, std::set<std::string>& newly_forced,
              bool demote)
        : m_file(file), m_shader(shader), m_d(diags), m_forced(forced),
          m_newly(newly_forced), m_demote(demote) {}

    Program run() {
        m_p.kind = m_shader.kind;
        m_p.name = m_shader.name;
        m_p.files = m_d.source().files;
        if (m_p.files.empty()) m_p.files.push_back("<string>");
        m_p.source_path = m_p.files.front();
        m_kind_bit = kind_bit(m_shader.kind);

        Scope* params = new_scope(nullptr);
        for (const auto& f : m_file.functions)
            params->funcs[f->name].push_back({f.get(), params});
        m_scope = params;
        m_loc = m_shader.loc;
        for (const VarDecl& group : m_shader.params) parameter_group(group);
        m_p.body_begin = static_cast<int>(m_p.ops.size());

        m_regions.push_back({Region::Body, {}, false});
        m_scope = new_scope(params);
        for (const StmtPtr& s : m_shader.body->body) statement(*s);
        pop_region();
        return std::move(m_p);
    }

private:
    // --- symbols and ops --------------------------------------------------
    struct LocGuard {
        Generator& g;
        SrcLoc saved;
        LocGuard(Generator& gen, SrcLoc at) : g(gen), saved(gen.m_loc) { g.m_loc = at; }
        ~LocGuard() { g.m_loc = saved; }
    };

    void error(SrcLoc at, const std::string& msg) { m_d.error(at, msg); }

    Scope* new_scope(Scope* parent) {
        m_scopes.push_back(std::make_unique<Scope>());
        Scope* s = m_scopes.back().get();
        s->parent = parent;
        s->outer = parent;
        return s;
    }

    std::string unique_name(const std::string& base) {
        if (m_names.insert(base).second) return base;
        for (int k = 2;; ++k) {
            std::string n = base + "@" + std::to_string(k);
            if (m_names.insert(n).second) return n;
        }
    }

    int add_symbol(const std::string& name, TypeSpec type, bool varying,
                   SymbolKind kind) {
        if (m_p.symbols.size() >= kMaxSymbols) {
            error(m_loc, "shader too large (more than " + std::to_string(kMaxSymbols) +
                             " symbols)");
            throw CompileAbort{};
        }
        Symbol s;
        s.name = name;
        s.type = type;
        s.varying = varying;
        s.kind = kind;
        m_p.symbols.push_back(std::move(s));
        return static_cast<int>(m_p.symbols.size() - 1);
    }

    int temp(TypeSpec type, bool varying) {
        std::string name = "$t";
        name += std::to_string(m_ntemp++);
        return add_symbol(name, type, varying, SymbolKind::Temp);
    }

    int konst(TypeSpec type, std::vector<float> numbers,
              std::vector<std::string> strings) {
        std::string key = type_spec_name(type) + "|";
        for (float f : numbers) {
            char b[sizeof f];
            std::memcpy(b, &f, sizeof f);
            key.append(b, sizeof f);
        }
        for (const std::string& s : strings)
            key += "|" + std::to_string(s.size()) + ":" + s;
        auto it = m_consts.find(key);
        if (it != m_consts.end()) return it->second;
        std::string name = "$c";
        name += std::to_string(m_nconst++);
        int s = add_symbol(name, type, false, SymbolKind::Const);
        m_p.symbols[s].numbers = std::move(numbers);
        m_p.symbols[s].strings = std::move(strings);
        m_consts.emplace(key, s);
        return s;
    }
    int kfloat(double v) {
        return konst({ShadingType::Float, 0}, {static_cast<float>(v)}, {});
    }
    int kstring(const std::string& s) { return konst({ShadingType::String, 0}, {}, {s}); }
    int ktriple(ShadingType t, float x, float y, float z) {
        return konst({t, 0}, {x, y, z}, {});
    }

    int emit(const std::string& name, std::vector<int> args, uint64_t writes = 1) {
        if (m_p.ops.size() >= kMaxOps) {
            error(m_loc, "shader too large (more than " + std::to_string(kMaxOps) +
                             " operations after inlining)");
            throw CompileAbort{};
        }
        Op op;
        op.name = name;
        op.args = std::move(args);
        op.writes = writes;
        op.where = m_d.where(m_loc);
        m_p.ops.push_back(std::move(op));
        return static_cast<int>(m_p.ops.size() - 1);
    }
    int here() const { return static_cast<int>(m_p.ops.size()); }

    const TypeSpec& type(int s) const { return m_p.symbols[s].type; }
    bool varying(int s) const { return m_p.symbols[s].varying; }
    bool is_const(int s) const { return m_p.symbols[s].kind == SymbolKind::Const; }

    // --- variables ----------------------------------------------------------
    // A global of this shader kind, created on first use; null if there is none.
    const Var* global(const std::string& name, SrcLoc at) {
        const GlobalDef* g = find_global(name);
        if (!g || !(g->read & m_kind_bit)) return nullptr;
        if (g->in_loop & m_kind_bit) {
            const bool inside =
                m_kind_bit == kS ? m_in_illuminance > 0 : m_in_light_loop > 0;
            if (!inside) {
                error(at, "'" + name + "' exists only inside " +
                              (m_kind_bit == kS ? "an illuminance"
                                                : "an illuminate or solar") +
                              " statement");
                return nullptr;
            }
        }
        auto it = m_globals.find(name);
        if (it == m_globals.end()) {
            Var v;
            m_names.insert(name);
            v.sym = add_symbol(name, {g->type, 0}, g->varying, SymbolKind::Global);
            v.readonly = !(g->write & m_kind_bit);
            v.what = "global variable";
            it = m_globals.emplace(name, v).first;
        }
        return &it->second;
    }

    // Plain lookup: this function's scopes (or the body's), then globals.
    const Var* lookup(const std::string& name, SrcLoc at, bool report = true) {
        for (Scope* s = m_scope; s; s = s->parent) {
            auto it = s->vars.find(name);
            if (it != s->vars.end()) return &it->second;
        }
        if (find_global(name)) {
            if (const Var* g = global(name, at)) return g;
            if (find_global(name)->read & m_kind_bit) return nullptr; // reported
            if (report)
                error(at, "'" + name + "' is not available in a " +
                              shader_kind_name(m_shader.kind) + " shader");
            return nullptr;
        }
        if (report) error(at, "unknown variable '" + name + "'");
        return nullptr;
    }

    // extern: every enclosing scope, through function boundaries.
    const Var* lookup_extern(const std::string& name, SrcLoc at) {
        Scope* s = m_scope;
        while (s) {
            auto it = s->vars.find(name);
            if (it != s->vars.end() && s != m_scope) return &it->second;
            s = s->parent ? s->parent : s->outer;
        }
        if (find_global(name)) return global(name, at);
        return nullptr;
    }

    // --- uniform / varying ------------------------------------------------
    void force_varying(int sym) {
        if (!varying(sym)) m_newly.insert(m_p.symbols[sym].name);
    }

    // A store of a value (varying or not) into `target`.
    void check_store(int target, bool value_varying, SrcLoc at) {
        if (m_tentative.count(target)) {
            if (value_varying || masked()) force_varying(target);
            for (Region& r : m_regions) r.assigned.push_back(target);
            return;
        }
        if (m_auto.count(target)) return;
        if (value_varying && !varying(target))
            error(at, "cannot assign a varying value to uniform '" +
                          m_p.symbols[target].name + "'");
    }

    // Under a varying condition, or after a varying return in this function
    // (or the body): only some points run.
    bool masked() const {
        if (m_varying_cond > 0) return true;
        for (const Region& r : m_regions)
            if (r.kind != Region::Loop && r.varying_exit) return true;
        return false;
    }

    // A loop left by some points only runs its next iterations masked:
    // whatever it assigns is varying.
    void pop_region() {
        Region r = std::move(m_regions.back());
        m_regions.pop_back();
        if (r.kind == Region::Loop && r.varying_exit)
            for (int s : r.assigned) force_varying(s);
    }

    // --- conversions --------------------------------------------------------
    static bool convertible(const TypeSpec& from, const TypeSpec& to) {
        if (from == to) return true;
        if (from.is_array() || to.is_array()) return false;
        if (from.type == ShadingType::Float &&
            (is_triple(to.type) || to.type == ShadingType::Matrix))
            return true;
        return is_point_like(from.type) && is_point_like(to.type);
    }

    std::string conversion_error(const TypeSpec& from, const TypeSpec& to) {
        if ((from.type == ShadingType::Color && is_point_like(to.type)) ||
            (is_point_like(from.type) && to.type == ShadingType::Color))
            return "cannot convert " + tname(from) + " to " + tname(to) +
                   " (points and colors do not mix)";
        return "cannot convert " + tname(from) + " to " + tname(to);
    }

    // v as type `to`, converting (a temp) when needed; errors when impossible.
    Val convert(Val v, const TypeSpec& to, SrcLoc at) {
        if (!v.ok()) return v;
        const TypeSpec from = type(v.sym);
        if (from == to) return v;
        if (!convertible(from, to)) {
            error(at, conversion_error(from, to));
            return {};
        }
        if (is_const(v.sym)) {
            const std::vector<float>& n = m_p.symbols[v.sym].numbers;
            if (from.type == ShadingType::Float && !n.empty()) {
                if (to.type == ShadingType::Matrix) {
                    std::vector<float> m(16, 0.0f);
                    for (int i = 0; i < 4; ++i) m[i * 5] = n[0];
                    return {konst(to, m, {})};
                }
                return {konst(to, {n[0], n[0], n[0]}, {})};
            }
            return {konst(to, n, {})};
        }
        int t = temp(to, varying(v.sym));
        emit("assign", {t, v.sym});
        return {t};
    }

    // --- expressions ----------------------------------------------------------
    Val value(const Expr& e, const TypeSpec* hint = nullptr) {
        Val v = gen(e, hint);
        if (v.sym == Val::kVoid) {
            error(e.loc, "a void function call has no value");
            return {};
        }
        return v;
    }

    // A condition: a float (non-zero is true); triples compare against 0.
    Val condition(const Expr& e) {
        Val v = value(e);
        if (!v.ok()) return v;
        const TypeSpec t = type(v.sym);
        if (t.is_array() || t.type == ShadingType::String) {
            error(e.loc, "a " + tname(t) + " cannot be a condition");
            return {};
        }
        if (t.type == ShadingType::Float) return v;
        LocGuard lg(*this, e.loc);
        int zero = convert({kfloat(0)}, t, e.loc).sym;
        int c = temp({ShadingType::Float, 0}, varying(v.sym));
        emit("ne", {c, v.sym, zero});
        return {c};
    }

    Val gen(const Expr& e, const TypeSpec* hint) {
        LocGuard lg(*this, e.loc);
        switch (e.kind) {
        case ExprKind::Number:
            return {kfloat(e.number)};
        case ExprKind::String:
            return {kstring(e.text)};
        case ExprKind::Ident: {
            if (e.text == "PI" && !shadowed("PI")) return {kfloat(kPi)};
            const Var* v = lookup(e.text, e.loc);
            return v ? Val{v->sym} : Val{};
        }
        case ExprKind::Index:
            return gen_index(e);
        case ExprKind::Call:
            return gen_call(e, hint);
        case ExprKind::Triple: {
            ShadingType t = hint && !hint->is_array() && is_triple(hint->type)
                                ? hint->type
                                : ShadingType::Point;
            return gen_tuple(e, t, -1);
        }
        case ExprKind::Tuple16:
            return gen_tuple(e, ShadingType::Matrix, -1);
        case ExprKind::Cast:
            return gen_cast(e.cast_type, e.has_space, e.space, *e.args[0], e.loc);
        case ExprKind::Unary:
            return gen_unary(e, hint);
        case ExprKind::Binary:
            return gen_binary(e, hint);
        case ExprKind::Ternary:
            return gen_ternary(e, hint);
        case ExprKind::Assign:
            return gen_assign(e);
        }
        return {};
    }

    bool shadowed(const std::string& name) {
        for (Scope* s = m_scope; s; s = s->parent)
            if (s->vars.count(name)) return true;
        return false;
    }

    Val gen_index(const Expr& e) {
        const Var* v = lookup(e.text, e.loc);
        Val idx = value(*e.args[0]);
        if (!v || !idx.ok()) return {};
        const TypeSpec at = type(v->sym);
        if (!at.is_array()) {
            error(e.loc, "'" + e.text + "' is not an array");
            return {};
        }
        if (type(idx.sym) != TypeSpec{ShadingType::Float, 0}) {
            error(e.args[0]->loc, "an array index must be a float");
            return {};
        }
        int t = temp({at.type, 0}, varying(v->sym) || varying(idx.sym));
        emit("aref", {t, v->sym, idx.sym});
        return {t};
    }

    // (a,b,c) or the 16-tuple as `type`, with an optional space (string symbol).
    Val gen_tuple(const Expr& e, ShadingType t, int space) {
        const bool matrix = e.kind == ExprKind::Tuple16;
        if (matrix != (t == ShadingType::Matrix)) {
            error(e.loc,
                  matrix ? "a 16-tuple can only be a matrix"
                         : "a triple cannot be a " + std::string(shading_type_name(t)));
            return {};
        }
        const TypeSpec f{ShadingType::Float, 0};
        std::vector<int> parts;
        bool ok = true, all_const = true, any_varying = false;
        for (const ExprPtr& a : e.args) {
            Val v = value(*a, &f);
            if (v.ok() && type(v.sym) != f) {
                error(a->loc, "the components of a tuple must be floats, not " +
                                  tname(type(v.sym)));
                v = {};
            }
            if (!v.ok()) {
                ok = false;
                continue;
            }
            parts.push_back(v.sym);
            all_const = all_const && is_const(v.sym);
            any_varying = any_varying || varying(v.sym);
        }
        if (!ok) return {};
        if (all_const && space < 0) {
            std::vector<float> n;
            for (int p : parts) n.push_back(m_p.symbols[p].numbers.at(0));
            return {konst({t, 0}, n, {})};
        }
        std::vector<int> args;
        int d = temp({t, 0}, any_varying);
        args.push_back(d);
        if (space >= 0) args.push_back(space);
        args.insert(args.end(), parts.begin(), parts.end());
        emit("construct", args);
        return {d};
    }

    Val gen_cast(ShadingType t, bool has_space, const std::string& space_name,
                 const Expr& x, SrcLoc at) {
        const TypeSpec ts{t, 0};
        LocGuard lg(*this, at);
        if (t == ShadingType::Float || t == ShadingType::String) {
            Val v = value(x, &ts);
            if (v.ok() && type(v.sym) != ts) {
                error(at, "cannot cast " + tname(type(v.sym)) + " to " + tname(ts));
                return {};
            }
            return v;
        }
        const int space = has_space ? kstring(space_name) : -1;
        if (is_bare_tuple(x)) return gen_tuple(x, t, space);
        Val v = value(x, &ts);
        if (!v.ok()) return v;
        const TypeSpec from = type(v.sym);
        if (from.is_array()) {
            error(at, "cannot cast an array");
            return {};
        }
        if (space < 0) {
            if (from == ts) return v;
            if (!convertible(from, ts)) {
                error(at, "cannot cast: " + conversion_error(from, ts));
                return {};
            }
            return convert(v, ts, at);
        }
        int d = temp(ts, varying(v.sym));
        if (from.type == ShadingType::Float) {
            if (t == ShadingType::Matrix)
                emit("construct", {d, space, v.sym});
            else
                emit("construct", {d, space, v.sym, v.sym, v.sym});
            return {d};
        }
        const bool same_family =
            from.type == t || (is_point_like(from.type) && is_point_like(t));
        if (!same_family) {
            error(at, "cannot cast: " + conversion_error(from, ts));
            return {};
        }
        emit("cast", {d, space, v.sym});
        return {d};
    }

    Val gen_unary(const Expr& e, const TypeSpec* hint) {
        if (e.text == "!") {
            Val c = condition(*e.args[0]);
            if (!c.ok()) return c;
            int d = temp({ShadingType::Float, 0}, varying(c.sym));
            emit("not", {d, c.sym});
            return {d};
        }
        Val a = value(*e.args[0], hint);
        if (!a.ok()) return a;
        const TypeSpec t = type(a.sym);
        if (t.is_array() || t.type == ShadingType::String) {
            error(e.loc, "cannot negate a " + tname(t));
            return {};
        }
        if (is_const(a.sym) && t.type != ShadingType::Matrix) {
            std::vector<float> n = m_p.symbols[a.sym].numbers;
            for (float& f : n) f = -f;
            return {konst(t, n, {})};
        }
        int d = temp(t, varying(a.sym));
        emit("neg", {d, a.sym});
        return {d};
    }

    // The result type of a binary operator, or Void (with `why`) if illegal.
    ShadingType binary_type(const std::string& op, ShadingType a, ShadingType b,
                            std::string& why) {
        using T = ShadingType;
        const bool pa = is_point_like(a), pb = is_point_like(b);
        const bool mix_pc = (pa && b == T::Color) || (pb && a == T::Color);
        if (mix_pc) {
            why = "points and colors do not mix";
            return T::Void;
        }
        if (op == "&&" || op == "||")
            return a == T::Float && b == T::Float ? T::Float : T::Void;
        if (op == "==" || op == "!=") {
            if (a == b || (pa && pb) ||
                (a == T::Float && (is_triple(b) || b == T::Matrix)) ||
                (b == T::Float && (is_triple(a) || a == T::Matrix)))
                return T::Float;
            return T::Void;
        }
        if (op == "<" || op == "<=" || op == ">" || op == ">=") {
            if (a == T::Float && b == T::Float) return T::Float;
            why = "relational operators compare floats";
            return T::Void;
        }
        if (a == T::String || b == T::String) {
            why = "strings only compare with == and !=";
            return T::Void;
        }
        if (op == ".") {
            if ((pa && pb) || (a == T::Color && b == T::Color)) return T::Float;
            why = "'.' takes two vectors or two colors";
            return T::Void;
        }
        if (op == "^") {
            if (pa && pb) return T::Vector;
            why = "'^' takes two vectors";
            return T::Void;
        }
        // + - * /
        if (a == T::Matrix || b == T::Matrix) {
            if (a == T::Matrix && b == T::Matrix) return T::Matrix;
            if ((op == "*" && (a == T::Float || b == T::Float)) ||
                (op == "/" && b == T::Float))
                return T::Matrix;
            why = "a matrix combines only with a matrix (or is scaled by a float)";
            return T::Void;
        }
        if (a == T::Float) return b;
        if (b == T::Float) return a;
        if (a == b) {
            if (op == "-" && a == T::Point) return T::Vector;
            return a;
        }
        if (a == T::Color || b == T::Color) return T::Void;
        if (op == "+" || op == "-") {
            if (a == T::Point || b == T::Point) return T::Point;
        }
        return T::Vector;
    }

    static const char* op_name(const std::string& op) {
        static const std::map<std::string, const char*> names = {
            {"+", "add"},   {"-", "sub"}, {"*", "mul"},  {"/", "div"}, {".", "dot"},
            {"^", "cross"}, {"==", "eq"}, {"!=", "ne"},  {"<", "lt"},  {"<=", "le"},
            {">", "gt"},    {">=", "ge"}, {"&&", "and"}, {"||", "or"}};
        auto it = names.find(op);
        return it == names.end() ? "?" : it->second;
    }

    Val arith(const std::string& op, Val a, Val b, SrcLoc at) {
        if (!a.ok() || !b.ok()) return {};
        TypeSpec ta = type(a.sym), tb = type(b.sym);
        if (ta.is_array() || tb.is_array()) {
            error(at, "arrays cannot be used in expressions (index them)");
            return {};
        }
        std::string why;
        ShadingType rt = binary_type(op, ta.type, tb.type, why);
        if (rt == ShadingType::Void) {
            error(at, "operator '" + op + "' cannot combine " + tname(ta) + " and " +
                          tname(tb) + (why.empty() ? "" : " (" + why + ")"));
            return {};
        }
        if (op == "==" || op == "!=") {
            // Compare like with like: a float is replicated.
            if (ta.type == ShadingType::Float && tb.type != ShadingType::Float)
                a = convert(a, {tb.type, 0}, at);
            else if (tb.type == ShadingType::Float && ta.type != ShadingType::Float)
                b = convert(b, {ta.type, 0}, at);
            if (!a.ok() || !b.ok()) return {};
        }
        if ((op == "+" || op == "-" || op == "*" || op == "/") && is_const(a.sym) &&
            is_const(b.sym) && rt != ShadingType::Matrix) {
            const auto& na = m_p.symbols[a.sym].numbers;
            const auto& nb = m_p.symbols[b.sym].numbers;
            const std::size_t n = std::max(na.size(), nb.size());
            std::vector<float> r(n);
            bool fold = !na.empty() && !nb.empty();
            for (std::size_t i = 0; fold && i < n; ++i) {
                const float x = na[na.size() == 1 ? 0 : i],
                            y = nb[nb.size() == 1 ? 0 : i];
                if (op == "+")
                    r[i] = x + y;
                else if (op == "-")
                    r[i] = x - y;
                else if (op == "*")
                    r[i] = x * y;
                else if (y != 0.0f)
                    r[i] = x / y;
                else
                    fold = false;
            }
            if (fold) return {konst({rt, 0}, r, {})};
        }
        int d = temp({rt, 0}, varying(a.sym) || varying(b.sym));
        emit(op_name(op), {d, a.sym, b.sym});
        return {d};
    }

    Val gen_binary(const Expr& e, const TypeSpec* hint) {
        const std::string& op = e.text;
        if (op == "&&" || op == "||") {
            Val a = condition(*e.args[0]);
            Val b = condition(*e.args[1]);
            return arith(op, a, b, e.loc);
        }
        const Expr& l = *e.args[0];
        const Expr& r = *e.args[1];
        const bool arithmetic = op == "+" || op == "-" || op == "*" || op == "/";
        const TypeSpec* outer = arithmetic ? hint : nullptr;
        Val a, b;
        // A bare tuple takes the other operand's type (or the expected one).
        if (is_bare_tuple(l) && !is_bare_tuple(r)) {
            b = value(r, outer);
            TypeSpec h = b.ok() ? type(b.sym) : TypeSpec{};
            a = value(l, b.ok() && (is_triple(h.type) || h.type == ShadingType::Matrix)
                             ? &h
                             : outer);
        } else if (is_bare_tuple(r) && !is_bare_tuple(l)) {
            a = value(l, outer);
            TypeSpec h = a.ok() ? type(a.sym) : TypeSpec{};
            b = value(r, a.ok() && (is_triple(h.type) || h.type == ShadingType::Matrix)
                             ? &h
                             : outer);
        } else {
            a = value(l, outer);
            b = value(r, outer);
        }
        return arith(op, a, b, e.loc);
    }

    Val gen_ternary(const Expr& e, const TypeSpec* hint) {
        Val c = condition(*e.args[0]);
        if (!c.ok()) return c;
        const int op = emit("if", {c.sym}, 0);
        const bool vc = varying(c.sym);
        if (vc) ++m_varying_cond;
        Val a = value(*e.args[1], hint);
        TypeSpec rt = a.ok() ? type(a.sym) : TypeSpec{};
        if (hint && !hint->is_array() && rt.type == ShadingType::Float &&
            (is_triple(hint->type) || hint->type == ShadingType::Matrix))
            rt = *hint;
        if (rt.is_array()) {
            error(e.loc, "?: cannot choose between arrays");
            a = {};
        }
        const int r = temp(rt, false);
        m_auto.insert(r);
        bool any_varying = vc;
        a = convert(a, rt, e.args[1]->loc);
        if (a.ok()) {
            emit("assign", {r, a.sym});
            any_varying = any_varying || varying(a.sym);
        }
        m_p.ops[op].jump[0] = here();
        Val b = convert(value(*e.args[2], &rt), rt, e.args[2]->loc);
        if (b.ok()) {
            emit("assign", {r, b.sym});
            any_varying = any_varying || varying(b.sym);
        }
        m_p.ops[op].jump[1] = here();
        if (vc) --m_varying_cond;
        m_p.symbols[r].varying = any_varying;
        if (!a.ok() || !b.ok()) return {};
        return {r};
    }

    bool check_writable(const Var& v, const std::string& name, SrcLoc at) {
        if (!v.readonly) return true;
        std::string why;
        if (std::strcmp(v.what, "shader parameter") == 0)
            why = " (declare it output to write it)";
        else if (std::strcmp(v.what, "global variable") == 0)
            why = std::string(" in a ") + shader_kind_name(m_shader.kind) + " shader";
        else if (std::strcmp(v.what, "function parameter") == 0)
            why = " (declare it output to write it)";
        error(at, std::string("cannot assign to ") + v.what + " '" + name +
                      "': it is read-only" + why);
        return false;
    }

    Val gen_assign(const Expr& e) {
        const Expr& lhs = *e.args[0];
        const Expr& rhs = *e.args[1];
        const std::string op = e.text.substr(0, 1); // "+" for "+=", "=" for "="
        const Var* var = lookup(lhs.text, lhs.loc);
        if (!var) {
            value(rhs);
            return {};
        }
        const Var v = *var;
        const TypeSpec vt = type(v.sym);
        if (lhs.kind == ExprKind::Ident) {
            if (vt.is_array()) {
                error(lhs.loc, "cannot assign a whole array ('" + lhs.text + "')");
                return {};
            }
            Val r = value(rhs, &vt);
            if (op != "=") r = arith(op, {v.sym}, r, e.loc);
            if (!r.ok() || !check_writable(v, lhs.text, lhs.loc)) return {};
            if (!convertible(type(r.sym), vt)) {
                error(e.loc, "cannot assign " + tname(type(r.sym)) + " to " + tname(vt) +
                                 " '" + lhs.text + "'" +
                                 (conversion_error(type(r.sym), vt).find("mix") !=
                                          std::string::npos
                                      ? " (points and colors do not mix)"
                                      : ""));
                return {};
            }
            check_store(v.sym, varying(r.sym), e.loc);
            emit("assign", {v.sym, r.sym});
            return {v.sym};
        }
        // a[i] = ...
        if (!vt.is_array()) {
            error(lhs.loc, "'" + lhs.text + "' is not an array");
            return {};
        }
        const TypeSpec et{vt.type, 0};
        Val idx = value(*lhs.args[0]);
        if (idx.ok() && type(idx.sym) != TypeSpec{ShadingType::Float, 0}) {
            error(lhs.args[0]->loc, "an array index must be a float");
            idx = {};
        }
        Val r = value(rhs, &et);
        if (!idx.ok() || !r.ok()) return {};
        if (op != "=") {
            int cur = temp(et, varying(v.sym) || varying(idx.sym));
            emit("aref", {cur, v.sym, idx.sym});
            r = arith(op, {cur}, r, e.loc);
        }
        if (!r.ok() || !check_writable(v, lhs.text, lhs.loc)) return {};
        r = convert(r, et, e.loc);
        if (!r.ok()) return {};
        check_store(v.sym, varying(r.sym) || varying(idx.sym), e.loc);
        emit("aassign", {v.sym, idx.sym, r.sym});
        return r;
    }

    // --- calls ------------------------------------------------------------
    int arg_cost(const ArgInfo& a, ShadingType want, bool want_array, bool output) {
        if (want == ShadingType::Void) return -1;
        if (a.literal) {
            if (want_array) return -1;
            if (a.expr->kind == ExprKind::Triple) return is_triple(want) ? 0 : -1;
            return want == ShadingType::Matrix ? 0 : -1;
        }
        if (!a.val.ok()) return 0; // already reported: do not add errors
        const TypeSpec t = type(a.val.sym);
        if (want_array) return t.is_array() && t.type == want ? 0 : -1;
        if (t.is_array()) return -1;
        if (t.type == want) return 0;
        if (output) return -1;
        if (t.type == ShadingType::Float &&
            (is_triple(want) || want == ShadingType::Matrix))
            return 1;
        if (is_point_like(t.type) && is_point_like(want)) return 1;
        return -1;
    }

    struct Match {
        int cost = 0;
        ShadingType x = ShadingType::Point;
        std::vector<PArg> slots; ///< one per argument (token names/values as '.')
        std::vector<bool> token_value;
    };

    bool match(const Proto& p, const std::vector<ArgInfo>& args, const TypeSpec* hint,
               Match& m) {
        const std::size_t nfixed = p.fixed.size();
        if (args.size() < nfixed) return false;
        if (!p.has_rest && !p.tokens && args.size() != nfixed) return false;
        if (p.tokens && (args.size() - nfixed) % 2 != 0) return false;
        m.slots.clear();
        m.token_value.clear();
        for (std::size_t i = 0; i < args.size(); ++i) {
            bool tv = false;
            if (i < nfixed)
                m.slots.push_back(p.fixed[i]);
            else if (p.has_rest)
                m.slots.push_back(p.rest);
            else {
                PArg a;
                const bool is_name = (i - nfixed) % 2 == 0;
                a.letter = is_name ? 's' : '.';
                a.output = !is_name && p.tokens == '@';
                tv = !is_name;
                m.slots.push_back(a);
            }
            m.token_value.push_back(tv);
        }
        // x: the first point-like argument in an x slot, else the expected type.
        bool bound = false;
        for (std::size_t i = 0; i < args.size() && !bound; ++i) {
            if (m.slots[i].letter != 'x' || args[i].literal || !args[i].val.ok())
                continue;
            const TypeSpec t = type(args[i].val.sym);
            if (is_point_like(t.type)) {
                m.x = t.type;
                bound = true;
            }
        }
        if (!bound)
            m.x = hint && is_point_like(hint->type) ? hint->type : ShadingType::Point;
        m.cost = 0;
        for (std::size_t i = 0; i < args.size(); ++i) {
            const PArg& s = m.slots[i];
            int c;
            if (s.letter == '.') {
                c = (!args[i].literal && args[i].val.ok() && m.token_value[i] == false &&
                     type(args[i].val.sym).is_array())
                        ? -1
                        : 0;
                if (m.token_value[i]) c = 0;
            } else {
                c = arg_cost(args[i], letter_type(s.letter, m.x), s.array, s.output);
            }
            if (c < 0) return false;
            m.cost += c;
        }
        return true;
    }

    // 0: the result is what is expected, 1: it converts, 2: it does not.
    int hint_rank(ShadingType result, const TypeSpec* hint) {
        if (!hint) return result == ShadingType::Float ? 0 : 1;
        if (result == hint->type) return 0;
        if (convertible({result, 0}, *hint)) return 1;
        return 2;
    }

    // texture(name[i], ...) with `name` a string variable: i is the channel.
    bool string_subscript(const Expr& e) {
        if (e.kind != ExprKind::Index) return false;
        const Var* v = lookup(e.text, e.loc, false);
        return v && type(v->sym) == TypeSpec{ShadingType::String, 0};
    }

    std::vector<ArgInfo> gather_args(const Expr& e, bool texture_like) {
        std::vector<ArgInfo> args;
        for (const ExprPtr& a : e.args) {
            ArgInfo info;
            info.expr = a.get();
            if (texture_like && args.empty() && !e.channel && string_subscript(*a)) {
                info.val = {lookup(a->text, a->loc)->sym};
            } else if (is_bare_tuple(*a)) {
                info.literal = true;
            } else if (a->kind == ExprKind::Ident &&
                       !(a->text == "PI" && !shadowed("PI")) &&
                       lookup(a->text, a->loc, false)) {
                info.is_var = true;
                info.var = *lookup(a->text, a->loc);
                info.val = {info.var.sym};
            } else {
                info.val = gen(*a, nullptr);
                if (info.val.sym == Val::kVoid) {
                    error(a->loc, "a void function call has no value");
                    info.val = {};
                }
            }
            args.push_back(info);
        }
        return args;
    }

    Val gen_call(const Expr& e, const TypeSpec* hint) {
        const std::string& name = e.text;
        if (name == "bump") {
            error(e.loc, "bump is not supported (use calculatenormal)");
            return {};
        }
        const bool texture_like =
            name == "texture" || name == "environment" || name == "shadow";
        std::vector<ArgInfo> args = gather_args(e, texture_like);
        if (texture_like) {
            if (args.empty()) {
                error(e.loc, name + " needs a file name");
                return {};
            }
            ArgInfo chan;
            chan.expr = &e;
            if (e.channel) {
                chan.val = value(*e.channel);
            } else if (string_subscript(*e.args[0])) {
                chan.val = value(*e.args[0]->args[0]);
            } else {
                chan.val = {kfloat(0)};
            }
            args.insert(args.begin() + 1, chan);
        }

        // User functions, nearest scope first, shadow nothing: all overloads.
        std::vector<FuncEntry> users;
        for (Scope* s = m_scope; s; s = s->parent ? s->parent : s->outer) {
            auto it = s->funcs.find(name);
            if (it != s->funcs.end())
                users.insert(users.end(), it->second.begin(), it->second.end());
        }
        int best = -1, best_cost = 0, best_rank = 0;
        for (std::size_t i = 0; i < users.size(); ++i) {
            int cost = 0;
            if (!match_user(*users[i].def, args, cost)) continue;
            int rank = hint_rank(users[i].def->result, hint);
            if (best < 0 || cost < best_cost || (cost == best_cost && rank < best_rank)) {
                best = static_cast<int>(i);
                best_cost = cost;
                best_rank = rank;
            }
        }
        if (best >= 0) return inline_call(users[best], args, e);

        const Proto* bp = nullptr;
        Match bm;
        for (const Proto& p : protos()) {
            if (name != p.sig->name) continue;
            Match m;
            if (!match(p, args, hint, m)) continue;
            const int rank = hint_rank(letter_type(p.result, m.x), hint);
            if (!bp || m.cost < bm.cost ||
                (m.cost == bm.cost &&
                 rank < hint_rank(letter_type(bp->result, bm.x), hint))) {
                bp = &p;
                bm = m;
            }
        }
        if (!bp) {
            for (const ArgInfo& a : args)
                if (!a.literal && !a.val.ok() && a.expr != &e) return {}; // reported
            if (users.empty() && !is_builtin(name)) {
                error(e.loc, "unknown function '" + name + "'");
                return {};
            }
            std::string types;
            for (std::size_t i = 0; i < args.size(); ++i) {
                if (texture_like && i == 1) continue;
                if (!types.empty()) types += ", ";
                types +=
                    args[i].literal
                        ? (args[i].expr->kind == ExprKind::Triple ? "triple" : "16-tuple")
                        : tname(type(args[i].val.sym));
            }
            error(e.loc, "no version of '" + name + "' takes (" + types + ")" +
                             (!users.empty() ? " (user function or built-in)" : ""));
            return {};
        }
        return builtin_call(*bp, bm, args, e);
    }

    // In a '@' token-value list (texture3d), a value is written when it is a
    // writable variable, unless its name is one of the options that are read.
    bool written_token(const ArgInfo& name, const ArgInfo& value) {
        static const std::set<std::string> inputs = {
            "filterscale", "filterradius", "radius",       "coordsystem", "interpolate",
            "maxdepth",    "blur",         "lerp",         "width",       "maxdist",
            "samples",     "bias",         "cachelifetime"};
        if (!value.is_var || value.var.readonly) return false;
        if (name.val.ok() && is_const(name.val.sym) &&
            !m_p.symbols[name.val.sym].strings.empty() &&
            inputs.count(m_p.symbols[name.val.sym].strings[0]))
            return false;
        return true;
    }

    // occlusion() and indirectdiffuse(): the values of "environmentcolor",
    // "environmentdir" and "occlusion" are outputs (variables, written).
    bool ray_output_token(const std::string& fn, const ArgInfo& name) {
        if (fn != "occlusion" && fn != "indirectdiffuse") return false;
        if (!name.val.ok() || !is_const(name.val.sym) ||
            m_p.symbols[name.val.sym].strings.empty())
            return false;
        const std::string& t = m_p.symbols[name.val.sym].strings[0];
        return t == "environmentcolor" || t == "environmentdir" || t == "occlusion";
    }

    Val builtin_call(const Proto& p, const Match& m, std::vector<ArgInfo>& args,
                     const Expr& e) {
        const std::string& name = p.sig->name;
        std::vector<int> syms;
        std::vector<bool> out;
        bool call_varying = p.sig->always_varying;
        // rayinfo's "origin", "direction" and "length" differ per point
        // ("depth", "type", "label" are the batch's: uniform).
        if (name == "rayinfo" && !args.empty() && args[0].val.ok() &&
            is_const(args[0].val.sym) && !m_p.symbols[args[0].val.sym].strings.empty()) {
            const std::string& key = m_p.symbols[args[0].val.sym].strings[0];
            call_varying = key == "origin" || key == "direction" || key == "length";
        }
        for (std::size_t i = 0; i < args.size(); ++i) {
            const PArg& s = m.slots[i];
            ArgInfo& a = args[i];
            const TypeSpec want{letter_type(s.letter, m.x), 0};
            if (a.literal) {
                a.val = value(*a.expr, s.letter == '.' ? nullptr : &want);
                a.literal = false;
            }
            if (!a.val.ok()) return {};
            const bool ray_out = m.token_value[i] && ray_output_token(name, args[i - 1]);
            if (s.output && m.token_value[i] && !written_token(args[i - 1], a)) {
                // An option of a '@' list that is read, not a looked-up channel.
            } else if (s.output || ray_out) {
                if (!a.is_var) {
                    error(a.expr->loc, "argument " + std::to_string(i + 1) + " of '" +
                                           name +
                                           "' is an output: it must be a variable");
                    return {};
                }
                if (!check_writable(a.var, a.expr->text, a.expr->loc)) return {};
                syms.push_back(a.val.sym);
                out.push_back(true);
                continue;
            }
            Val v = a.val;
            if (s.letter != '.' && !s.array) v = convert(v, want, a.expr->loc);
            if (!v.ok()) return {};
            call_varying = call_varying || varying(v.sym);
            syms.push_back(v.sym);
            out.push_back(false);
        }
        if (syms.size() + 1 > 64) {
            error(e.loc, "too many arguments in the call of '" + name + "'");
            return {};
        }
        const ShadingType rt = letter_type(p.result, m.x);
        std::vector<int> all;
        uint64_t writes = 0;
        int result = Val::kVoid;
        if (rt != ShadingType::Void) {
            result = temp({rt, 0}, call_varying);
            all.push_back(result);
            writes |= 1;
        }
        for (std::size_t i = 0; i < syms.size(); ++i) {
            if (out[i]) {
                writes |= uint64_t(1) << all.size();
                check_store(syms[i], call_varying, args[i].expr->loc);
            }
            all.push_back(syms[i]);
        }
        emit(name, all, writes);
        return {result};
    }

    // Flattened parameters of a user function.
    struct UParam {
        const VarDecl* group;
        const Declarator* decl;
    };
    static std::vector<UParam> user_params(const FuncDef& f) {
        std::vector<UParam> out;
        for (const VarDecl& g : f.params)
            for (const Declarator& d : g.names) out.push_back({&g, &d});
        return out;
    }

    bool match_user(const FuncDef& f, const std::vector<ArgInfo>& args, int& cost) {
        const std::vector<UParam> ps = user_params(f);
        if (ps.size() != args.size()) return false;
        cost = 0;
        for (std::size_t i = 0; i < ps.size(); ++i) {
            int c = arg_cost(args[i], ps[i].group->type, ps[i].decl->array != 0,
                             ps[i].group->output);
            if (c < 0) return false;
            cost += c;
        }
        return true;
    }

    Val inline_call(const FuncEntry& fe, std::vector<ArgInfo>& args, const Expr& call) {
        const FuncDef& f = *fe.def;
        if (std::find(m_inline.begin(), m_inline.end(), &f) != m_inline.end()) {
            error(call.loc,
                  "recursive call of '" + f.name + "' (RSL functions cannot recurse)");
            return {};
        }
        if (m_inline.size() >= kMaxInlineDepth) {
            error(call.loc, "function calls nested more than " +
                                std::to_string(kMaxInlineDepth) + " deep");
            throw CompileAbort{};
        }
        const int inst = ++m_instances;
        const std::string suffix = "@" + std::to_string(inst);
        const std::string prefix = f.name + "::";
        Scope* params = new_scope(nullptr);
        params->outer = fe.scope;
        const std::vector<UParam> ps = user_params(f);
        for (std::size_t i = 0; i < ps.size(); ++i) {
            const VarDecl& g = *ps[i].group;
            const Declarator& d = *ps[i].decl;
            ArgInfo& a = args[i];
            const TypeSpec pt{g.type, 0};
            Var pv;
            pv.what = "function parameter";
            pv.readonly = !g.output;
            if (d.array != 0 || g.output) {
                if (!a.is_var) {
                    error(a.expr->loc, "argument " + std::to_string(i + 1) + " of '" +
                                           f.name +
                                           "' must be a variable (the parameter is " +
                                           (g.output ? "output" : "an array") + ")");
                    return {};
                }
                if (g.output && !check_writable(a.var, a.expr->text, a.expr->loc))
                    return {};
                if (g.storage == Storage::Uniform && varying(a.var.sym)) {
                    error(a.expr->loc,
                          "varying argument for uniform parameter '" + d.name + "'");
                    return {};
                }
                pv.sym = a.var.sym;
            } else if (a.is_var && type(a.var.sym) == pt &&
                       !(g.storage == Storage::Uniform && varying(a.var.sym))) {
                pv.sym = a.var.sym; // by reference
            } else {
                Val v = a.literal ? value(*a.expr, &pt) : a.val;
                v = convert(v, pt, a.expr->loc);
                if (!v.ok()) return {};
                if (g.storage == Storage::Uniform && varying(v.sym)) {
                    error(a.expr->loc,
                          "varying argument for uniform parameter '" + d.name + "'");
                    return {};
                }
                const bool pvary = g.storage == Storage::Varying ? true : varying(v.sym);
                pv.sym = add_symbol(unique_name(prefix + d.name + suffix), pt, pvary,
                                    SymbolKind::Local);
                emit("assign", {pv.sym, v.sym});
            }
            if (params->vars.count(d.name)) {
                error(d.loc, "parameter '" + d.name + "' is declared twice");
                return {};
            }
            params->vars[d.name] = pv;
        }
        FuncCtx ctx;
        ctx.def = &f;
        ctx.instance = inst;
        if (f.result != ShadingType::Void) {
            ctx.result = add_symbol(unique_name(prefix + "result" + suffix),
                                    {f.result, 0}, false, SymbolKind::Temp);
            m_auto.insert(ctx.result);
        }
        ctx.saved_loop_depth = m_loop_depth;
        m_loop_depth = 0;
        m_funcs.push_back(ctx);
        m_inline.push_back(&f);
        m_regions.push_back({Region::Function, {}, false});
        Scope* saved_scope = m_scope;
        m_scope = new_scope(params);
        const int block = emit("block", {}, 0);
        {
            LocGuard lg(*this, f.loc);
            for (const StmtPtr& s : f.body->body) statement(*s);
        }
        m_p.ops[block].jump[0] = here();
        m_scope = saved_scope;
        const bool exit_varying = m_regions.back().varying_exit;
        pop_region();
        m_inline.pop_back();
        ctx = m_funcs.back();
        m_funcs.pop_back();
        m_loop_depth = ctx.saved_loop_depth;
        if (ctx.result < 0) return {Val::kVoid};
        m_p.symbols[ctx.result].varying = ctx.result_varying || exit_varying;
        return {ctx.result};
    }

    // --- statements ---------------------------------------------------------
    void statement(const Stmt& s) {
        LocGuard lg(*this, s.loc);
        switch (s.kind) {
        case StmtKind::Empty:
            return;
        case StmtKind::Expr:
            gen(*s.expr, nullptr);
            return;
        case StmtKind::Block: {
            Scope* saved = m_scope;
            m_scope = new_scope(saved);
            for (const StmtPtr& b : s.body) statement(*b);
            m_scope = saved;
            return;
        }
        case StmtKind::Decl:
            declaration(*s.decl);
            return;
        case StmtKind::Func:
            m_scope->funcs[s.func->name].push_back({s.func.get(), m_scope});
            return;
        case StmtKind::Return:
            return_statement(s);
            return;
        case StmtKind::Break:
        case StmtKind::Continue:
            jump_statement(s);
            return;
        case StmtKind::If:
            if_statement(s);
            return;
        case StmtKind::While:
        case StmtKind::For:
            loop_statement(s);
            return;
        case StmtKind::Illuminance:
        case StmtKind::Illuminate:
        case StmtKind::Solar:
            light_statement(s);
            return;
        case StmtKind::Gather:
            gather_statement(s);
            return;
        }
    }

    void sub_statement(const Stmt& s) {
        Scope* saved = m_scope;
        m_scope = new_scope(saved);
        statement(s);
        m_scope = saved;
    }

    void declaration(const VarDecl& d) {
        for (const Declarator& n : d.names) {
            LocGuard lg(*this, n.loc);
            if (m_scope->vars.count(n.name)) {
                error(n.loc, "'" + n.name + "' is already declared in this scope");
                continue;
            }
            if (d.is_extern) {
                const Var* v = lookup_extern(n.name, n.loc);
                if (!v) {
                    error(n.loc, "extern '" + n.name +
                                     "' names no parameter, global or outer variable");
                    continue;
                }
                if (type(v->sym).type != d.type) {
                    error(n.loc, "extern '" + n.name + "' is declared " +
                                     shading_type_name(d.type) + " but is " +
                                     tname(type(v->sym)));
                    continue;
                }
                m_scope->vars[n.name] = *v;
                continue;
            }
            const TypeSpec t{d.type, std::max(n.array, 0)};
            std::string base = n.name;
            if (!m_funcs.empty())
                base = m_funcs.back().def->name + "::" + n.name + "@" +
                       std::to_string(m_funcs.back().instance);
            const std::string name = unique_name(base);
            bool vary = d.storage == Storage::Varying;
            const bool tentative =
                m_demote && d.storage == Storage::Default && !m_forced.count(name);
            if (d.storage == Storage::Default && !tentative) vary = true;
            Var v;
            v.sym = add_symbol(name, t, vary, SymbolKind::Local);
            if (tentative) m_tentative.insert(v.sym);
            initialise(v.sym, d, n);
            m_scope->vars[n.name] = v;
        }
    }

    // The initializer of a local or of a parameter: stores into `sym`.
    void initialise(int sym, const VarDecl& d, const Declarator& n) {
        const TypeSpec t = type(sym);
        if (n.has_list) {
            if (!t.is_array()) {
                error(n.loc, "{...} initialises arrays only");
                return;
            }
            if (static_cast<int>(n.list.size()) != t.array) {
                error(n.loc, "'" + n.name + "' has " + std::to_string(t.array) +
                                 " elements but " + std::to_string(n.list.size()) +
                                 " values are given");
                return;
            }
            const TypeSpec et{t.type, 0};
            for (std::size_t i = 0; i < n.list.size(); ++i) {
                Val v = elem_value(d, *n.list[i], et);
                if (!v.ok()) continue;
                check_store(sym, varying(v.sym), n.list[i]->loc);
                emit("aassign", {sym, kfloat(static_cast<double>(i)), v.sym});
            }
            return;
        }
        if (!n.init) return;
        if (t.is_array()) {
            error(n.loc, "an array is initialised with {...}");
            return;
        }
        Val v = elem_value(d, *n.init, t);
        if (!v.ok()) return;
        check_store(sym, varying(v.sym), n.init->loc);
        emit("assign", {sym, v.sym});
    }

    Val elem_value(const VarDecl& d, const Expr& e, const TypeSpec& et) {
        Val v = d.has_space ? gen_cast(d.type, true, d.space, e, e.loc) : value(e, &et);
        return convert(v, et, e.loc);
    }

    void parameter_group(const VarDecl& g) {
        for (const Declarator& n : g.names) {
            LocGuard lg(*this, n.loc);
            if (m_scope->vars.count(n.name)) {
                error(n.loc, "parameter '" + n.name + "' is declared twice");
                continue;
            }
            const TypeSpec t{g.type, std::max(n.array, 0)};
            m_names.insert(n.name);
            Var v;
            v.sym = add_symbol(n.name, t, g.storage == Storage::Varying,
                               g.output ? SymbolKind::OutputParam : SymbolKind::Param);
            v.readonly = !g.output;
            v.what = "shader parameter";
            const int begin = here();
            // Constant defaults are stored in the symbol; others become ops.
            std::vector<Val> vals;
            bool all_const = true;
            const TypeSpec et{t.type, 0};
            if (n.has_list) {
                if (!t.is_array())
                    error(n.loc, "{...} initialises arrays only");
                else if (static_cast<int>(n.list.size()) != t.array)
                    error(n.loc, "'" + n.name + "' has " + std::to_string(t.array) +
                                     " elements but " + std::to_string(n.list.size()) +
                                     " values are given");
                else
                    for (const ExprPtr& e : n.list) vals.push_back(elem_value(g, *e, et));
            } else if (n.init) {
                if (t.is_array())
                    error(n.loc, "an array parameter's default is written {...}");
                else
                    vals.push_back(elem_value(g, *n.init, et));
            }
            for (const Val& x : vals) all_const = all_const && x.ok() && is_const(x.sym);
            Symbol& sym = m_p.symbols[v.sym];
            if (all_const && here() == begin) {
                for (const Val& x : vals) {
                    const Symbol& c = m_p.symbols[x.sym];
                    sym.numbers.insert(sym.numbers.end(), c.numbers.begin(),
                                       c.numbers.end());
                    sym.strings.insert(sym.strings.end(), c.strings.begin(),
                                       c.strings.end());
                }
            } else {
                for (std::size_t i = 0; i < vals.size(); ++i) {
                    if (!vals[i].ok()) continue;
                    if (varying(vals[i].sym) && !varying(v.sym))
                        error(n.loc, "the default of uniform parameter '" + n.name +
                                         "' is varying");
                    if (t.is_array())
                        emit("aassign",
                             {v.sym, kfloat(static_cast<double>(i)), vals[i].sym});
                    else
                        emit("assign", {v.sym, vals[i].sym});
                }
                m_p.symbols[v.sym].init_begin = begin;
                m_p.symbols[v.sym].init_end = here();
            }
            m_scope->vars[n.name] = v;
        }
    }

    void return_statement(const Stmt& s) {
        if (m_funcs.empty()) {
            if (s.expr) error(s.loc, "a shader's body returns no value");
            if (masked())
                for (Region& r : m_regions) r.varying_exit = true;
            emit("return", {}, 0);
            return;
        }
        FuncCtx& ctx = m_funcs.back();
        if (ctx.def->result == ShadingType::Void) {
            if (s.expr)
                error(s.loc,
                      "void function '" + ctx.def->name + "' cannot return a value");
        } else if (!s.expr) {
            error(s.loc, "'" + ctx.def->name + "' must return a " +
                             shading_type_name(ctx.def->result));
        } else {
            const TypeSpec rt{ctx.def->result, 0};
            Val v = convert(value(*s.expr, &rt), rt, s.expr->loc);
            if (v.ok()) {
                if (varying(v.sym) || masked()) m_funcs.back().result_varying = true;
                emit("assign", {m_funcs.back().result, v.sym});
            }
        }
        if (masked())
            for (auto it = m_regions.rbegin(); it != m_regions.rend(); ++it) {
                it->varying_exit = true;
                if (it->kind == Region::Function) break;
            }
        emit("return", {}, 0);
    }

    void jump_statement(const Stmt& s) {
        const char* word = s.kind == StmtKind::Break ? "break" : "continue";
        if (m_loop_depth == 0) {
            error(s.loc, std::string(word) + " outside a loop");
            return;
        }
        if (s.level > m_loop_depth) {
            error(s.loc, std::string(word) + " " + std::to_string(s.level) + ": only " +
                             std::to_string(m_loop_depth) + " enclosing loop(s)");
            return;
        }
        if (masked()) {
            int n = s.level;
            for (auto it = m_regions.rbegin(); it != m_regions.rend() && n > 0; ++it) {
                if (it->kind != Region::Loop) break;
                it->varying_exit = true;
                --n;
            }
        }
        const int op = emit(word, {}, 0);
        m_p.ops[op].level = s.level;
    }

    void if_statement(const Stmt& s) {
        Val c = condition(*s.expr);
        if (!c.ok()) c = {kfloat(0)};
        const int op = emit("if", {c.sym}, 0);
        const bool vc = varying(c.sym);
        if (vc) ++m_varying_cond;
        sub_statement(*s.sub);
        m_p.ops[op].jump[0] = here();
        if (s.else_sub) sub_statement(*s.else_sub);
        m_p.ops[op].jump[1] = here();
        if (vc) --m_varying_cond;
    }

    void loop_statement(const Stmt& s) {
        const Expr* init = s.kind == StmtKind::For ? s.exprs[0].get() : nullptr;
        const Expr* cond = s.kind == StmtKind::For ? s.exprs[1].get() : s.expr.get();
        const Expr* step = s.kind == StmtKind::For ? s.exprs[2].get() : nullptr;
        const int op = emit("loop", {-1}, 0);
        if (init) gen(*init, nullptr);
        m_p.ops[op].jump[0] = here();
        m_regions.push_back({Region::Loop, {}, false});
        Val c = condition(*cond);
        if (!c.ok()) c = {kfloat(0)};
        m_p.ops[op].args[0] = c.sym;
        m_p.ops[op].jump[1] = here();
        const bool vc = varying(c.sym);
        if (vc) ++m_varying_cond;
        ++m_loop_depth;
        sub_statement(*s.sub);
        m_p.ops[op].jump[2] = here();
        if (step) gen(*step, nullptr);
        m_p.ops[op].jump[3] = here();
        --m_loop_depth;
        if (vc) --m_varying_cond;
        pop_region();
    }

    Val typed_arg(const Expr& e, ShadingType t) {
        const TypeSpec ts{t, 0};
        Val v = value(e, &ts);
        if (v.ok() && t == ShadingType::String && type(v.sym) != ts) {
            error(e.loc, "the light category must be a string");
            return {};
        }
        return convert(v, ts, e.loc);
    }

    void light_statement(const Stmt& s) {
        const std::size_t n = s.exprs.size();
        std::vector<int> args;
        bool ok = true;
        auto arg = [&](std::size_t i, ShadingType t) {
            Val v = typed_arg(*s.exprs[i], t);
            ok = ok && v.ok();
            args.push_back(v.ok() ? v.sym : 0);
        };
        const int no_axis = ktriple(ShadingType::Vector, 0, 0, 0);
        const char* name = "illuminance";
        if (s.kind == StmtKind::Illuminance) {
            if (m_shader.kind != ShaderKind::Surface) {
                error(s.loc, "illuminance is only allowed in surface shaders");
                return;
            }
            if (m_in_illuminance) {
                error(s.loc, "illuminance statements cannot be nested");
                return;
            }
            if (n < 1 || n > 4) return; // reported by the parser
            const std::size_t p = (n == 2 || n == 4) ? 1 : 0;
            if (p)
                arg(0, ShadingType::String);
            else
                args.push_back(kstring(""));
            arg(p, ShadingType::Point);
            if (n >= 3) {
                arg(p + 1, ShadingType::Vector);
                arg(p + 2, ShadingType::Float);
            } else {
                args.push_back(no_axis);
                args.push_back(kfloat(kPi));
            }
        } else {
            const bool solar = s.kind == StmtKind::Solar;
            name = solar ? "solar" : "illuminate";
            if (m_shader.kind != ShaderKind::Light) {
                error(s.loc, std::string(name) + " is only allowed in light shaders");
                return;
            }
            if (m_in_light_loop) {
                error(s.loc, "illuminate and solar statements cannot be nested");
                return;
            }
            if (solar ? (n != 0 && n != 2) : (n != 1 && n != 3)) return; // reported
            std::size_t i = 0;
            if (!solar) arg(i++, ShadingType::Point);
            if (n > i) {
                arg(i, ShadingType::Vector);
                arg(i + 1, ShadingType::Float);
            } else {
                args.push_back(no_axis);
                args.push_back(kfloat(-1));
            }
        }
        if (!ok) return;
        const int op = emit(name, args, 0);
        int& depth = s.kind == StmtKind::Illuminance ? m_in_illuminance : m_in_light_loop;
        ++depth;
        ++m_varying_cond;
        sub_statement(*s.sub);
        --m_varying_cond;
        --depth;
        m_p.ops[op].jump[0] = here();
    }

    // gather(category, P, dir, angle, samples, "name", value...) hit [else miss]:
    // op `gather` with the five fixed arguments (string, point, vector, float,
    // float) and the token-value pairs; values of output tokens ("surface:x",
    // "ray:...", "environment:...") are variables, written (varying).
    void gather_statement(const Stmt& s) {
        if (m_shader.kind != ShaderKind::Surface && m_shader.kind != ShaderKind::Light &&
            m_shader.kind != ShaderKind::Displacement) {
            error(s.loc,
                  "gather is only allowed in surface, light and displacement shaders");
            return;
        }
        const std::size_t n = s.exprs.size();
        if (n < 5 || (n - 5) % 2 != 0) {
            error(s.loc, "gather takes (category, P, dir, angle, samples [, \"name\", "
                         "value]...)");
            return;
        }
        std::vector<int> args;
        bool ok = true;
        auto arg = [&](std::size_t i, ShadingType t) {
            Val v = typed_arg(*s.exprs[i], t);
            ok = ok && v.ok();
            args.push_back(v.ok() ? v.sym : 0);
        };
        {
            Val c = value(*s.exprs[0]);
            if (c.ok() && type(c.sym) != TypeSpec{ShadingType::String, 0}) {
                error(s.exprs[0]->loc, "the gather category must be a string");
                ok = false;
            }
            args.push_back(c.ok() ? c.sym : 0);
            ok = ok && c.ok();
        }
        arg(1, ShadingType::Point);
        arg(2, ShadingType::Vector);
        arg(3, ShadingType::Float);
        arg(4, ShadingType::Float);
        uint64_t writes = 0;
        std::vector<std::pair<int, SrcLoc>> outputs;
        for (std::size_t i = 5; i + 1 < n; i += 2) {
            Val name = value(*s.exprs[i]);
            if (!name.ok() || type(name.sym) != TypeSpec{ShadingType::String, 0}) {
                if (name.ok())
                    error(s.exprs[i]->loc, "gather option names must be strings");
                ok = false;
                args.push_back(0);
                args.push_back(0);
                continue;
            }
            args.push_back(name.sym);
            std::string token;
            if (is_const(name.sym) && !m_p.symbols[name.sym].strings.empty())
                token = m_p.symbols[name.sym].strings[0];
            const Expr& ve = *s.exprs[i + 1];
            const auto colon = token.find(':');
            if (colon == std::string::npos) {
                Val v = value(ve);
                ok = ok && v.ok();
                args.push_back(v.ok() ? v.sym : 0);
                continue;
            }
            // An output: the variable itself.
            const std::string group = token.substr(0, colon),
                              key = token.substr(colon + 1);
            auto want = [&](bool fits, const char* what) {
                if (!fits) {
                    error(ve.loc, "gather output \"" + token + "\" needs " + what);
                    ok = false;
                }
            };
            const Var* var =
                ve.kind == ExprKind::Ident ? lookup(ve.text, ve.loc) : nullptr;
            if (group == "primitive") {
                error(ve.loc, "gather output \"" + token +
                                  "\": primitive variables of the hit are not supported "
                                  "(use \"surface:" +
                                  key + "\")");
                ok = false;
            } else if (group != "surface" && group != "ray" && group != "environment") {
                error(ve.loc, "unknown gather output \"" + token + "\"");
                ok = false;
            } else if (!var) {
                if (ve.kind != ExprKind::Ident)
                    error(ve.loc, "the value of gather output \"" + token +
                                      "\" must be a variable");
                ok = false;
            } else if (check_writable(*var, ve.text, ve.loc)) {
                const TypeSpec t = type(var->sym);
                if (group == "ray") {
                    if (key == "length")
                        want(t == TypeSpec{ShadingType::Float, 0}, "a float variable");
                    else if (key == "direction" || key == "origin")
                        want(!t.is_array() && is_point_like(t.type),
                             "a point, vector or normal variable");
                    else {
                        error(ve.loc, "unknown gather output \"" + token + "\"");
                        ok = false;
                    }
                } else if (group == "environment") {
                    if (key == "color")
                        want(t == TypeSpec{ShadingType::Color, 0}, "a color variable");
                    else if (key == "direction")
                        want(!t.is_array() && is_point_like(t.type),
                             "a point, vector or normal variable");
                    else {
                        error(ve.loc, "unknown gather output \"" + token + "\"");
                        ok = false;
                    }
                } else if (key.empty() || t.type == ShadingType::String) {
                    want(false, "a variable name and a non-string variable");
                }
                writes |= uint64_t(1) << std::min<std::size_t>(args.size(), 63);
                outputs.push_back({var->sym, ve.loc});
                args.push_back(var->sym);
                continue;
            } else {
                ok = false;
            }
            args.push_back(0);
        }
        if (args.size() > 64) {
            error(s.loc, "too many arguments to gather");
            return;
        }
        if (!ok) return;
        // Outputs vary per point (and are written under a varying mask).
        for (const auto& [sym, at] : outputs) check_store(sym, true, at);
        const int op = emit("gather", args, writes);
        ++m_varying_cond;
        sub_statement(*s.sub);
        m_p.ops[op].jump[0] = here();
        if (s.else_sub) sub_statement(*s.else_sub);
        m_p.ops[op].jump[1] = here();
        --m_varying_cond;
    }

    const SourceFile& m_file;
    const ShaderDef& m_shader;
    DiagnosticSink& m_d;
    const std::set<std::string>& m_forced;
    std::set<std::string>& m_newly;
    const bool m_demote;
    Program m_p;
    unsigned m_kind_bit = kS;
    SrcLoc m_loc;

    std::vector<std::unique_ptr<Scope>> m_scopes;
    Scope* m_scope = nullptr;
    std::unordered_map<std::string, Var> m_globals;
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
    int m_loop_depth = 0;
    int m_in_illuminance = 0;
    int m_in_light_loop = 0;
};

} // namespace

std::vector<Program> generate(const SourceFile& file, DiagnosticSink& diags) {
    std::vector<Program> out;
    for (const ShaderDef& shader : file.shaders) {
        std::set<std::string> forced;
        for (int pass = 0;; ++pass) {
            DiagnosticSink sink(diags.source());
            std::set<std::string> newly;
            Program program;
            bool aborted = false;
            // After a few passes, stop demoting: every undeclared local varying.
            const bool demote = pass < kDemotionPasses;
            try {
                program = Generator(file, shader, sink, forced, newly, demote).run();
            } catch (const CompileAbort&) {
                aborted = true;
            }
            std::size_t before = forced.size();
            forced.insert(newly.begin(), newly.end());
            // Marks only grow, so this ends; without demotion nothing is marked.
            if (aborted || forced.size() == before || !demote) {
                const int errors_before = diags.error_count();
                diags.absorb(sink);
                if (aborted) throw CompileAbort{};
                if (diags.error_count() == errors_before)
                    out.push_back(std::move(program));
                break;
            }
        }
    }
    return out;
}

} // namespace sss::detail
