// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file codegen_calls.cpp
/// Calls in the code generator: argument costs, overload resolution against
/// the built-in table (also by the expected result type) and against user
/// functions, built-in calls with their outputs, and inlining of user functions.

#include "codegen_internal.h"

namespace sss::detail::codegen {

// --- calls ------------------------------------------------------------

int Generator::arg_cost(const ArgInfo& a, ShadingType want, bool want_array,
                        bool output) {
    if (want == ShadingType::Void) return -1;
    if (a.literal) {
        if (want_array) return -1;
        if (a.expr->kind == ExprKind::Triple) return is_triple(want) ? 0 : -1;
        return want == ShadingType::Matrix ? 0 : -1;
    }
    if (!a.val.ok()) return 0; // already reported: do not add errors
    const TypeSpec t = type(a.val.sym);
    // A built-in's output array (textureinfo, attribute...) has a fixed length.
    if (want_array)
        return t.is_array() && t.type == want && !(output && t.is_resizable()) ? 0 : -1;
    if (t.is_array()) return -1;
    if (t.type == want) return 0;
    if (output) return -1;
    if (t.type == ShadingType::Float && (is_triple(want) || want == ShadingType::Matrix))
        return 1;
    if (is_point_like(t.type) && is_point_like(want)) return 1;
    return -1;
}

bool Generator::match(const Proto& p, const std::vector<ArgInfo>& args,
                      const TypeSpec* hint, Match& m) {
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
        if (m.slots[i].letter != 'x' || args[i].literal || !args[i].val.ok()) continue;
        const TypeSpec t = type(args[i].val.sym);
        if (is_point_like(t.type)) {
            m.x = t.type;
            bound = true;
        }
    }
    if (!bound) m.x = hint && is_point_like(hint->type) ? hint->type : ShadingType::Point;
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

int Generator::hint_rank(ShadingType result, const TypeSpec* hint) {
    if (!hint) return result == ShadingType::Float ? 0 : 1;
    if (result == hint->type) return 0;
    if (convertible({result, 0}, *hint)) return 1;
    return 2;
}

bool Generator::string_subscript(const Expr& e) {
    if (e.kind != ExprKind::Index) return false;
    const Var* v = lookup(e.text, e.loc, false);
    return v && type(v->sym) == TypeSpec{ShadingType::String, 0};
}

std::vector<ArgInfo> Generator::gather_args(const Expr& e, bool texture_like) {
    std::vector<ArgInfo> args;
    for (const ExprPtr& a : e.args) {
        ArgInfo info;
        info.expr = a.get();
        if (texture_like && args.empty() && !e.channel && string_subscript(*a)) {
            info.val = {lookup(a->text, a->loc)->sym};
        } else if (is_bare_tuple(*a)) {
            info.literal = true;
        } else if (a->kind == ExprKind::Ident && !(a->text == "PI" && !shadowed("PI")) &&
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

Val Generator::gen_call(const Expr& e, const TypeSpec* hint) {
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
    std::string length_why;
    for (std::size_t i = 0; i < users.size(); ++i) {
        int cost = 0;
        if (!match_user(*users[i].def, args, cost, &length_why)) continue;
        int rank = hint_rank(users[i].def->result, hint);
        if (best < 0 || cost < best_cost || (cost == best_cost && rank < best_rank)) {
            best = static_cast<int>(i);
            best_cost = cost;
            best_rank = rank;
        }
    }
    if (best >= 0) return inline_call(users[best], args, e);
    if (!length_why.empty()) {
        error(e.loc, length_why);
        return {};
    }
    if (is_array_function(name)) return array_call(e, args);
    if (is_coshader_function(name)) return coshader_call(e, args, -1);

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

bool Generator::written_token(const ArgInfo& name, const ArgInfo& value) {
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

bool Generator::ray_output_token(const std::string& fn, const ArgInfo& name) {
    if (fn != "occlusion" && fn != "indirectdiffuse") return false;
    if (!name.val.ok() || !is_const(name.val.sym) ||
        m_p.symbols[name.val.sym].strings.empty())
        return false;
    const std::string& t = m_p.symbols[name.val.sym].strings[0];
    return t == "environmentcolor" || t == "environmentdir" || t == "occlusion";
}

Val Generator::builtin_call(const Proto& p, const Match& m, std::vector<ArgInfo>& args,
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
                error(a.expr->loc, "argument " + std::to_string(i + 1) + " of '" + name +
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
    // PRMan lets message passing fill a uniform variable (a light's or
    // surface's parameter is one value for the batch, or taken at the
    // first running point).
    const bool message = name == "lightsource" || name == "surface" ||
                         name == "displacement" || name == "atmosphere";
    for (std::size_t i = 0; i < syms.size(); ++i) {
        if (out[i]) {
            writes |= uint64_t(1) << all.size();
            check_store(syms[i], call_varying && !message, args[i].expr->loc);
        }
        all.push_back(syms[i]);
    }
    emit(name, all, writes);
    return {result};
}

std::vector<Generator::UParam> Generator::user_params(const FuncDef& f) {
    std::vector<UParam> out;
    for (const VarDecl& g : f.params)
        for (const Declarator& d : g.names) out.push_back({&g, &d});
    return out;
}

bool Generator::match_user(const FuncDef& f, const std::vector<ArgInfo>& args, int& cost,
                           std::string* why) {
    const std::vector<UParam> ps = user_params(f);
    if (ps.size() != args.size()) return false;
    cost = 0;
    std::string length_why;
    for (std::size_t i = 0; i < ps.size(); ++i) {
        const VarDecl& g = *ps[i].group;
        const int length = ps[i].decl->array;
        if (length != 0) {
            // `name[]` takes any array of the type, `name[N]` N elements.
            if (args[i].literal) return false;
            if (!args[i].val.ok()) continue; // reported
            const TypeSpec t = type(args[i].val.sym);
            if (!t.is_array() || t.type != g.type) return false;
            if (length > 0 && t.array != length && length_why.empty())
                length_why = "argument " + std::to_string(i + 1) + " of '" + f.name +
                             "' is " + tname(t) +
                             (t.is_resizable() ? " (resizable)" : "") +
                             " but parameter '" + ps[i].decl->name + "' is " +
                             tname({g.type, length});
            continue;
        }
        int c = arg_cost(args[i], g.type, false, g.output);
        if (c < 0) return false;
        cost += c;
    }
    if (!length_why.empty()) {
        if (why) *why = length_why;
        return false;
    }
    return true;
}

Val Generator::inline_call(const FuncEntry& fe, std::vector<ArgInfo>& args,
                           const Expr& call) {
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
    const std::string suffix = std::string("@").append(std::to_string(inst));
    const std::string prefix = f.name + "::";
    // A class's methods see its member variables and parameters; other
    // functions only their own parameters (and what they declare extern).
    Scope* params = new_scope(fe.method ? fe.scope : nullptr);
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
            if (g.output && !check_writable(a.var, a.expr->text, a.expr->loc)) return {};
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
        ctx.result = add_symbol(unique_name(prefix + "result" + suffix), {f.result, 0},
                                false, SymbolKind::Temp);
        m_auto.insert(ctx.result);
    }
    m_inline.push_back(&f);
    const bool exit_varying = function_block(ctx, params);
    m_inline.pop_back();
    if (ctx.result < 0) return {Val::kVoid};
    m_p.symbols[ctx.result].varying = ctx.result_varying || exit_varying;
    return {ctx.result};
}

bool Generator::function_block(FuncCtx& ctx, Scope* params) {
    const FuncDef& f = *ctx.def;
    ctx.saved_loop_depth = m_loop_depth;
    ctx.entry_varying_cond = m_varying_cond;
    ctx.entry_region = m_regions.size();
    m_loop_depth = 0;
    m_funcs.push_back(ctx);
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
    ctx = m_funcs.back();
    m_funcs.pop_back();
    m_loop_depth = ctx.saved_loop_depth;
    return exit_varying;
}

} // namespace sss::detail::codegen
