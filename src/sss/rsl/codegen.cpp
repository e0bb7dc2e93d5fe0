// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
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
///
/// This file: the passes, symbols and ops, variables. The Generator class is
/// in codegen_internal.h; its other phases are in codegen_types.cpp,
/// codegen_expr.cpp, codegen_calls.cpp and codegen_stmt.cpp.

#include "codegen_internal.h"

namespace sss::detail::codegen {

namespace {

constexpr ShadingType F = ShadingType::Float, C = ShadingType::Color,
                      Pt = ShadingType::Point, Ve = ShadingType::Vector,
                      No = ShadingType::Normal;

// clang-format off
// Volume shaders (RISpec 12.4): P, I, E, Ci, Oi (and the lights' L, Cl, Ol in
// illuminance). Imager shaders (12.5): Ci, Oi, alpha, and P the pixel's
// raster position.
constexpr GlobalDef kGlobals[] = {
    {"Cs", C, true, kS, kS, 0}, {"Os", C, true, kS, kS, 0},
    {"P", Pt, true, kS | kD | kL | kV | kI, kS | kD, 0},
    {"dPdu", Ve, true, kS | kD | kL, 0, 0}, {"dPdv", Ve, true, kS | kD | kL, 0, 0},
    {"N", No, true, kS | kD | kL, kS | kD | kL, 0}, {"Ng", No, true, kS | kD | kL, 0, 0},
    {"u", F, true, kS | kD | kL, 0, 0}, {"v", F, true, kS | kD | kL, 0, 0},
    {"du", F, true, kS | kD | kL, 0, 0}, {"dv", F, true, kS | kD | kL, 0, 0},
    {"s", F, true, kS | kD | kL, kS | kD | kL, 0}, {"t", F, true, kS | kD | kL, kS | kD | kL, 0},
    {"E", Pt, false, kS | kD | kL | kV, 0, 0}, {"I", Ve, true, kS | kD | kV, 0, 0},
    {"ncomps", F, false, kS | kD | kL | kV | kI, 0, 0},
    {"time", F, false, kS | kD | kL | kV | kI, 0, 0},
    {"dtime", F, false, kS | kD | kL | kV | kI, 0, 0}, {"dPdtime", Ve, true, kS | kD, 0, 0},
    {"Ci", C, true, kS | kV | kI, kS | kV | kI, 0},
    {"Oi", C, true, kS | kV | kI, kS | kV | kI, 0},
    {"alpha", F, true, kI, kI, 0},
    {"L", Ve, true, kS | kL | kV, kL, kS | kV},
    {"Cl", C, true, kS | kL | kV, kL, kS | kV}, {"Ol", C, true, kS | kL | kV, kL, kS | kV},
    {"Ps", Pt, true, kL, 0, 0},
};
// clang-format on

} // namespace

unsigned kind_bit(ShaderKind k) {
    switch (k) {
    case ShaderKind::Surface:
        return kS;
    case ShaderKind::Displacement:
        return kD;
    case ShaderKind::Light:
        return kL;
    case ShaderKind::Volume:
        return kV;
    case ShaderKind::Imager:
        return kI;
    case ShaderKind::Shader: // a co-shader runs on its caller's surface points
        return kS;
    }
    return 0;
}

const GlobalDef* find_global(const std::string& name) {
    for (const GlobalDef& g : kGlobals)
        if (name == g.name) return &g;
    return nullptr;
}

Program Generator::run() {
    if (m_shader.is_class) return run_class();
    m_p.kind = m_shader.kind;
    m_kind = m_shader.kind;
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

Scope* Generator::new_scope(Scope* parent) {
    m_scopes.push_back(std::make_unique<Scope>());
    Scope* s = m_scopes.back().get();
    s->parent = parent;
    s->outer = parent;
    return s;
}

std::string Generator::unique_name(const std::string& base) {
    if (m_names.insert(base).second) return base;
    for (int k = 2;; ++k) {
        std::string n = base + "@" + std::to_string(k);
        if (m_names.insert(n).second) return n;
    }
}

int Generator::add_symbol(const std::string& name, TypeSpec type, bool varying,
                          SymbolKind kind) {
    if (m_p.symbols.size() >= kMaxSymbols) {
        error(m_loc,
              "shader too large (more than " + std::to_string(kMaxSymbols) + " symbols)");
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

int Generator::temp(TypeSpec type, bool varying) {
    std::string name = "$t";
    name += std::to_string(m_ntemp++);
    return add_symbol(name, type, varying, SymbolKind::Temp);
}

int Generator::konst(TypeSpec type, std::vector<float> numbers,
                     std::vector<std::string> strings) {
    std::string key = type_spec_name(type) + "|";
    for (float f : numbers) {
        char b[sizeof f];
        std::memcpy(b, &f, sizeof f);
        key.append(b, sizeof f);
    }
    for (const std::string& s : strings)
        key.append("|").append(std::to_string(s.size())).append(":").append(s);
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

int Generator::kfloat(double v) {
    return konst({ShadingType::Float, 0}, {static_cast<float>(v)}, {});
}

int Generator::ktriple(ShadingType t, float x, float y, float z) {
    return konst({t, 0}, {x, y, z}, {});
}

int Generator::emit(const std::string& name, std::vector<int> args, uint64_t writes) {
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

// --- variables ----------------------------------------------------------

const Var* Generator::global(const std::string& name, SrcLoc at) {
    const GlobalDef* g = find_global(name);
    if (!g || !(g->read & m_kind_bit)) return nullptr;
    if (g->in_loop & m_kind_bit) {
        const bool illuminance = m_kind_bit != kL;
        const bool inside = illuminance ? m_in_illuminance > 0 : m_in_light_loop > 0;
        if (!inside) {
            error(at, "'" + name + "' exists only inside " +
                          (illuminance ? "an illuminance" : "an illuminate or solar") +
                          " statement");
            return nullptr;
        }
    }
    // One symbol per global; whether it is writable depends on the kind of
    // the code using it (a class's displacement and surface methods differ).
    const std::string key = name + "#" + std::to_string(m_kind_bit);
    auto it = m_globals.find(key);
    if (it == m_globals.end()) {
        Var v;
        auto sym = m_global_syms.find(name);
        if (sym != m_global_syms.end()) {
            v.sym = sym->second;
        } else {
            m_names.insert(name);
            v.sym = add_symbol(name, {g->type, 0}, g->varying, SymbolKind::Global);
            m_global_syms.emplace(name, v.sym);
        }
        v.readonly = !(g->write & m_kind_bit);
        v.what = "global variable";
        it = m_globals.emplace(key, v).first;
    }
    return &it->second;
}

const Var* Generator::lookup(const std::string& name, SrcLoc at, bool report) {
    for (Scope* s = m_scope; s; s = s->parent) {
        auto it = s->vars.find(name);
        if (it != s->vars.end()) return &it->second;
    }
    // PRMan's Ns in a light shader is the normal of the surface being lit,
    // which is what N holds there.
    if (name == "Ns" && m_kind_bit == kL) return lookup("N", at, report);
    // Old shaders (The RenderMan Companion's) read Ps, the light shaders'
    // surface point, in surface shaders: there it is P.
    if (name == "Ps" && m_kind_bit == kS && !shadowed(name)) {
        if (m_warned_names.insert(name).second)
            m_d.warning(at,
                        "'Ps' is a light shader variable; P is used in a surface shader");
        return lookup("P", at, report);
    }
    if (find_global(name)) {
        if (const Var* g = global(name, at)) return g;
        if (find_global(name)->read & m_kind_bit) return nullptr; // reported
        if (report)
            error(at, "'" + name + "' is not available in " +
                          (m_kind == ShaderKind::Imager ? "an " : "a ") +
                          shader_kind_name(m_kind) + " shader");
        return nullptr;
    }
    if (report) error(at, "unknown variable '" + name + "'");
    return nullptr;
}

const Var* Generator::lookup_extern(const std::string& name, SrcLoc at) {
    Scope* s = m_scope;
    while (s) {
        auto it = s->vars.find(name);
        if (it != s->vars.end() && s != m_scope) return &it->second;
        s = s->parent ? s->parent : s->outer;
    }
    if (find_global(name)) return global(name, at);
    return nullptr;
}

} // namespace sss::detail::codegen

namespace sss::detail {

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
            const bool demote = pass < codegen::kDemotionPasses;
            try {
                program =
                    codegen::Generator(file, shader, sink, forced, newly, demote).run();
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
