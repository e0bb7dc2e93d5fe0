// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file codegen_stmt.cpp
/// Statements in the code generator: declarations and parameters, return,
/// break/continue, if and loops, illuminance/illuminate/solar and gather.

#include "codegen_internal.h"

namespace sss::detail::codegen {

// --- statements ---------------------------------------------------------

void Generator::statement(const Stmt& s) {
    LocGuard lg(*this, s.loc);
    switch (s.kind) {
    case StmtKind::Empty:
        return;
    case StmtKind::Expr:
        // A method called for its effects: whatever it returns is dropped.
        if (s.expr->kind == ExprKind::MethodCall)
            gen_method_call(*s.expr, nullptr, true);
        else
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

void Generator::sub_statement(const Stmt& s) {
    Scope* saved = m_scope;
    m_scope = new_scope(saved);
    statement(s);
    m_scope = saved;
}

void Generator::declaration(const VarDecl& d) {
    for (const Declarator& n : d.names) {
        LocGuard lg(*this, n.loc);
        if (m_scope->vars.count(n.name)) {
            error(n.loc, "'" + n.name + "' is already declared in this scope");
            continue;
        }
        if (d.is_extern) {
            // A global that exists only inside illuminance (L, Cl...) may be
            // declared anywhere in a function and is checked where it is
            // used, as PRMan does: the name keeps resolving to the global.
            const GlobalDef* g = find_global(n.name);
            if (g && (g->in_loop & m_kind_bit) && !shadowed(n.name)) {
                if (g->type != d.type)
                    error(n.loc, "extern '" + n.name + "' is declared " +
                                     shading_type_name(d.type) + " but is " +
                                     shading_type_name(g->type));
                continue;
            }
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
        const TypeSpec t{d.type, n.array};
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

void Generator::initialise(int sym, const VarDecl& d, const Declarator& n) {
    const TypeSpec t = type(sym);
    if (t.is_array() && n.init && is_array_producer(*n.init)) {
        produce_array(sym, n.name, *n.init);
        return;
    }
    if (t.is_resizable() && !n.init) {
        // Each time the declaration runs, the array starts with the values
        // given (none: empty). The length is uniform; so is this store.
        check_store(sym, false, n.loc);
        emit("resize", {sym, kfloat(static_cast<double>(n.list.size()))});
    }
    if (n.has_list) {
        if (!t.is_array()) {
            error(n.loc, "{...} initialises arrays only");
            return;
        }
        if (!t.is_resizable() && static_cast<int>(n.list.size()) != t.array) {
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

Val Generator::elem_value(const VarDecl& d, const Expr& e, const TypeSpec& et) {
    Val v = d.has_space ? gen_cast(d.type, true, d.space, e, e.loc) : value(e, &et);
    return convert(v, et, e.loc);
}

void Generator::parameter_group(const VarDecl& g) {
    if (g.type == ShadingType::Shader) {
        error(g.loc, "a shader parameter cannot be of type shader: pass the co-shader's "
                     "handle as a string and call getshader()");
        return;
    }
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
                sym.numbers.insert(sym.numbers.end(), c.numbers.begin(), c.numbers.end());
                sym.strings.insert(sym.strings.end(), c.strings.begin(), c.strings.end());
            }
        } else {
            for (std::size_t i = 0; i < vals.size(); ++i) {
                if (!vals[i].ok()) continue;
                if (varying(vals[i].sym) && !varying(v.sym))
                    error(n.loc,
                          "the default of uniform parameter '" + n.name + "' is varying");
                if (t.is_array())
                    emit("aassign", {v.sym, kfloat(static_cast<double>(i)), vals[i].sym});
                else
                    emit("assign", {v.sym, vals[i].sym});
            }
            m_p.symbols[v.sym].init_begin = begin;
            m_p.symbols[v.sym].init_end = here();
        }
        m_scope->vars[n.name] = v;
    }
}

void Generator::return_statement(const Stmt& s) {
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
            error(s.loc, "void function '" + ctx.def->name + "' cannot return a value");
    } else if (!s.expr) {
        error(s.loc, "'" + ctx.def->name + "' must return a " +
                         shading_type_name(ctx.def->result));
    } else {
        const TypeSpec rt{ctx.def->result, 0};
        Val v = convert(value(*s.expr, &rt), rt, s.expr->loc);
        if (v.ok()) {
            if (varying(v.sym) || masked_in_function())
                m_funcs.back().result_varying = true;
            emit("assign", {m_funcs.back().result, v.sym});
        }
    }
    if (masked_in_function())
        for (auto it = m_regions.rbegin(); it != m_regions.rend(); ++it) {
            it->varying_exit = true;
            if (it->kind == Region::Function) break;
        }
    emit("return", {}, 0);
}

void Generator::jump_statement(const Stmt& s) {
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

void Generator::if_statement(const Stmt& s) {
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

void Generator::loop_statement(const Stmt& s) {
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

Val Generator::typed_arg(const Expr& e, ShadingType t) {
    const TypeSpec ts{t, 0};
    Val v = value(e, &ts);
    if (v.ok() && t == ShadingType::String && type(v.sym) != ts) {
        error(e.loc, "the light category must be a string");
        return {};
    }
    return convert(v, ts, e.loc);
}

void Generator::light_statement(const Stmt& s) {
    if (s.kind == StmtKind::Illuminance) {
        illuminance_statement(s);
        return;
    }
    const std::size_t n = s.exprs.size();
    std::vector<int> args;
    bool ok = true;
    auto arg = [&](std::size_t i, ShadingType t) {
        Val v = typed_arg(*s.exprs[i], t);
        ok = ok && v.ok();
        args.push_back(v.ok() ? v.sym : 0);
    };
    const int no_axis = ktriple(ShadingType::Vector, 0, 0, 0);
    const bool solar = s.kind == StmtKind::Solar;
    const char* name = solar ? "solar" : "illuminate";
    if (m_kind != ShaderKind::Light) {
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
    if (!ok) return;
    light_body(s, emit(name, args, 0));
}

void Generator::light_body(const Stmt& s, int op) {
    int& depth = s.kind == StmtKind::Illuminance ? m_in_illuminance : m_in_light_loop;
    ++depth;
    ++m_varying_cond;
    sub_statement(*s.sub);
    --m_varying_cond;
    --depth;
    m_p.ops[op].jump[0] = here();
}

void Generator::illuminance_statement(const Stmt& s) {
    if (m_kind != ShaderKind::Surface && m_kind != ShaderKind::Volume) {
        error(s.loc, "illuminance is only allowed in surface and volume shaders");
        return;
    }
    if (m_in_illuminance) {
        error(s.loc, "illuminance statements cannot be nested");
        return;
    }
    // The options start at the first string literal after the first argument
    // (the positional arguments after the category are a point, a vector and
    // a float).
    const std::size_t total = s.exprs.size();
    std::size_t n = 1;
    while (n < total && s.exprs[n]->kind != ExprKind::String) ++n;
    if (total < 1) return; // reported by the parser
    if (n > 4) {
        error(s.loc, "illuminance takes ([category,] P [, axis, angle] [, \"name\", "
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
        args.push_back(ktriple(ShadingType::Vector, 0, 0, 0));
        args.push_back(kfloat(kPi));
    }
    uint64_t writes = 0;
    ok = illuminance_options(s, n, args, writes) && ok;
    if (!ok) return;
    light_body(s, emit("illuminance", args, writes));
}

bool Generator::illuminance_options(const Stmt& s, std::size_t first,
                                    std::vector<int>& args, uint64_t& writes) {
    const std::size_t total = s.exprs.size();
    if ((total - first) % 2 != 0) {
        error(s.exprs.back()->loc,
              "illuminance options come in pairs: \"name\", value (the last has no "
              "value)");
        return false;
    }
    bool ok = true;
    for (std::size_t i = first; i + 1 < total; i += 2) {
        const Expr& ne = *s.exprs[i];
        const Expr& ve = *s.exprs[i + 1];
        if (ne.kind != ExprKind::String) {
            error(ne.loc, "illuminance option names must be string literals");
            ok = false;
            continue;
        }
        const std::string& token = ne.text;
        if (token == "lightcache") {
            Val v = value(ve);
            if (!v.ok()) {
                ok = false;
                continue;
            }
            if (type(v.sym) != TypeSpec{ShadingType::String, 0}) {
                error(ve.loc, "illuminance option \"lightcache\" takes a string "
                              "(\"refresh\" or \"reuse\")");
                ok = false;
                continue;
            }
            const std::vector<std::string>& str = m_p.symbols[v.sym].strings;
            if (is_const(v.sym) && !str.empty() && str[0] != "refresh" &&
                str[0] != "reuse")
                m_d.warning(ve.loc, "illuminance \"lightcache\" \"" + str[0] +
                                        "\" is neither \"refresh\" nor \"reuse\"; "
                                        "the cache is reused");
            args.push_back(kstring(token));
            args.push_back(v.sym);
            continue;
        }
        const bool receive = token.rfind("light:", 0) == 0 && token.size() > 6;
        const bool send = token.rfind("send:light:", 0) == 0 && token.size() > 11;
        if (send) {
            Val v = value(ve);
            if (!v.ok()) {
                ok = false;
                continue;
            }
            if (type(v.sym).is_array()) {
                error(ve.loc,
                      "illuminance option \"" + token + "\" cannot send an array");
                ok = false;
                continue;
            }
            args.push_back(kstring(token));
            args.push_back(v.sym);
            continue;
        }
        if (!receive) {
            m_d.warning(ne.loc,
                        "illuminance option \"" + token + "\" is not supported; ignored");
            continue;
        }
        // "light:NAME", var: the light's parameter NAME, each iteration.
        const Var* var = ve.kind == ExprKind::Ident ? lookup(ve.text, ve.loc) : nullptr;
        if (!var) {
            if (ve.kind != ExprKind::Ident)
                error(ve.loc, "the value of illuminance option \"" + token +
                                  "\" must be a variable");
            ok = false;
            continue;
        }
        if (!check_writable(*var, ve.text, ve.loc)) {
            ok = false;
            continue;
        }
        if (type(var->sym).is_array()) {
            error(ve.loc, "illuminance option \"" + token +
                              "\" needs a variable that "
                              "is not an array");
            ok = false;
            continue;
        }
        // Lights differ per point: the variable is written varying.
        check_store(var->sym, true, ve.loc);
        args.push_back(kstring(token));
        writes |= uint64_t(1) << std::min<std::size_t>(args.size(), 63);
        args.push_back(var->sym);
    }
    if (args.size() > 64) {
        error(s.loc, "too many arguments to illuminance");
        return false;
    }
    return ok;
}

void Generator::gather_statement(const Stmt& s) {
    if (m_kind != ShaderKind::Surface && m_kind != ShaderKind::Light &&
        m_kind != ShaderKind::Displacement) {
        error(s.loc, "gather is only allowed in surface, light and displacement shaders");
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
            if (name.ok()) error(s.exprs[i]->loc, "gather option names must be strings");
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
        const std::string group = token.substr(0, colon), key = token.substr(colon + 1);
        auto want = [&](bool fits, const char* what) {
            if (!fits) {
                error(ve.loc, "gather output \"" + token + "\" needs " + what);
                ok = false;
            }
        };
        const Var* var = ve.kind == ExprKind::Ident ? lookup(ve.text, ve.loc) : nullptr;
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
                error(ve.loc,
                      "the value of gather output \"" + token + "\" must be a variable");
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

} // namespace sss::detail::codegen
