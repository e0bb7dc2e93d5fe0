// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file codegen_expr.cpp
/// Expressions in the code generator: names, tuples and casts, operators,
/// the ternary and assignments (calls are in codegen_calls.cpp).

#include "codegen_internal.h"

namespace sss::detail::codegen {

// --- expressions ----------------------------------------------------------

Val Generator::value(const Expr& e, const TypeSpec* hint) {
    Val v = gen(e, hint);
    if (v.sym == Val::kVoid) {
        error(e.loc, "a void function call has no value");
        return {};
    }
    return v;
}

Val Generator::condition(const Expr& e) {
    Val v = value(e);
    if (!v.ok()) return v;
    const TypeSpec t = type(v.sym);
    if (t.is_array() || t.type == ShadingType::String) {
        error(e.loc, "a " + tname(t) + " cannot be a condition");
        return {};
    }
    if (t.type == ShadingType::Float) return v;
    LocGuard lg(*this, e.loc);
    // A shader handle is true when it is not null.
    int zero =
        t.type == ShadingType::Shader ? knull() : convert({kfloat(0)}, t, e.loc).sym;
    int c = temp({ShadingType::Float, 0}, varying(v.sym));
    emit("ne", {c, v.sym, zero});
    return {c};
}

Val Generator::gen(const Expr& e, const TypeSpec* hint) {
    LocGuard lg(*this, e.loc);
    switch (e.kind) {
    case ExprKind::Number:
        return {kfloat(e.number)};
    case ExprKind::String:
        return {kstring(e.text)};
    case ExprKind::Ident: {
        if (e.text == "PI" && !shadowed("PI")) return {kfloat(kPi)};
        if (e.text == "null" && !shadowed("null")) return {knull()};
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
    case ExprKind::MethodCall:
        return gen_method_call(e, hint, false);
    }
    return {};
}

bool Generator::shadowed(const std::string& name) {
    for (Scope* s = m_scope; s; s = s->parent)
        if (s->vars.count(name)) return true;
    return false;
}

Val Generator::gen_index(const Expr& e) {
    const Var* v = lookup(e.text, e.loc);
    Val idx = value(*e.args[0]);
    if (!v || !idx.ok()) return {};
    const TypeSpec at = type(v->sym);
    const bool component = !at.is_array() && is_triple(at.type);
    if (!at.is_array() && !component) {
        error(e.loc, "'" + e.text + "' is not an array");
        return {};
    }
    if (type(idx.sym) != TypeSpec{ShadingType::Float, 0}) {
        error(e.args[0]->loc, "an array index must be a float");
        return {};
    }
    if (component) { // PRMan: c[i] is comp(c, i)
        int t = temp({ShadingType::Float, 0}, varying(v->sym) || varying(idx.sym));
        emit("comp", {t, v->sym, idx.sym});
        return {t};
    }
    int t = temp({at.type, 0}, varying(v->sym) || varying(idx.sym));
    emit("aref", {t, v->sym, idx.sym});
    return {t};
}

Val Generator::gen_tuple(const Expr& e, ShadingType t, int space) {
    const bool matrix = e.kind == ExprKind::Tuple16;
    if (matrix != (t == ShadingType::Matrix)) {
        error(e.loc, matrix
                         ? "a 16-tuple can only be a matrix"
                         : "a triple cannot be a " + std::string(shading_type_name(t)));
        return {};
    }
    const TypeSpec f{ShadingType::Float, 0};
    std::vector<int> parts;
    bool ok = true, all_const = true, any_varying = false;
    for (const ExprPtr& a : e.args) {
        Val v = value(*a, &f);
        if (v.ok() && type(v.sym) != f) {
            error(a->loc,
                  "the components of a tuple must be floats, not " + tname(type(v.sym)));
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

Val Generator::gen_cast(ShadingType t, bool has_space, const std::string& space_name,
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

Val Generator::gen_unary(const Expr& e, const TypeSpec* hint) {
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

Val Generator::arith(const std::string& op, Val a, Val b, SrcLoc at) {
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
            const float x = na[na.size() == 1 ? 0 : i], y = nb[nb.size() == 1 ? 0 : i];
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

Val Generator::gen_binary(const Expr& e, const TypeSpec* hint) {
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

Val Generator::gen_ternary(const Expr& e, const TypeSpec* hint) {
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

Val Generator::gen_assign(const Expr& e) {
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
        if (vt.is_array() && op == "=" && is_array_producer(rhs)) {
            if (!check_writable(v, lhs.text, lhs.loc)) return {};
            produce_array(v.sym, lhs.text, rhs);
            return {v.sym};
        }
        if (vt.is_array()) {
            error(lhs.loc, "cannot assign a whole array ('" + lhs.text + "')");
            return {};
        }
        Val r = value(rhs, &vt);
        if (op != "=") r = arith(op, {v.sym}, r, e.loc);
        if (!r.ok() || !check_writable(v, lhs.text, lhs.loc)) return {};
        if (!convertible(type(r.sym), vt)) {
            error(e.loc,
                  "cannot assign " + tname(type(r.sym)) + " to " + tname(vt) + " '" +
                      lhs.text + "'" +
                      (conversion_error(type(r.sym), vt).find("mix") != std::string::npos
                           ? " (points and colors do not mix)"
                           : ""));
            return {};
        }
        check_store(v.sym, varying(r.sym), e.loc);
        emit("assign", {v.sym, r.sym});
        return {v.sym};
    }
    // a[i] = ...
    const bool component = !vt.is_array() && is_triple(vt.type); // c[i] = x: setcomp
    if (!vt.is_array() && !component) {
        error(lhs.loc, "'" + lhs.text + "' is not an array");
        return {};
    }
    const TypeSpec et{component ? ShadingType::Float : vt.type, 0};
    Val idx = value(*lhs.args[0]);
    if (idx.ok() && type(idx.sym) != TypeSpec{ShadingType::Float, 0}) {
        error(lhs.args[0]->loc, "an array index must be a float");
        idx = {};
    }
    Val r = value(rhs, &et);
    if (!idx.ok() || !r.ok()) return {};
    if (op != "=") {
        int cur = temp(et, varying(v.sym) || varying(idx.sym));
        emit(component ? "comp" : "aref", {cur, v.sym, idx.sym});
        r = arith(op, {cur}, r, e.loc);
    }
    if (!r.ok() || !check_writable(v, lhs.text, lhs.loc)) return {};
    r = convert(r, et, e.loc);
    if (!r.ok()) return {};
    check_store(v.sym, varying(r.sym) || varying(idx.sym), e.loc);
    if (component)
        emit("setcomp", {v.sym, idx.sym, r.sym});
    else
        emit("aassign", {v.sym, idx.sym, r.sym});
    return r;
}

} // namespace sss::detail::codegen
