// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file codegen_coshader.cpp
/// RSL 2.0 co-shaders in the code generator: `shader` handles from
/// getshader("handle"), getlight("handle"), getshaders() and getlights()
/// (resizable `shader[]` arrays, with an optional "category" option),
/// getvar(s, "name"[, var]), hasmethod(s, "name") and method calls
/// `s->method(args)`.
///
/// Which method a call reaches is known only when it runs, so a call is the
/// op `callmethod d handle "name" args...`: every argument that is a
/// writable variable is passed by reference (its bit in `writes`: the
/// method's outputs are copied back to it), others by value; d receives
/// the result (bit 0; clear when the value is not used). The result's type
/// is the one the context expects (`color c = s->f()`, `Ci += s->f()`),
/// float without one. The engine checks the arguments against the method
/// (engine_coshader.cpp).

#include "codegen_internal.h"

namespace sss::detail::codegen {

bool Generator::is_coshader_function(const std::string& name) {
    return name == "getshader" || name == "getshaders" || name == "getlight" ||
           name == "getlights" || name == "getvar" || name == "hasmethod";
}

bool Generator::is_array_producer(const Expr& e) {
    return e.kind == ExprKind::Call && (e.text == "getshaders" || e.text == "getlights");
}

void Generator::produce_array(int target, const std::string& name, const Expr& call) {
    const TypeSpec t = type(target);
    if (t != TypeSpec{ShadingType::Shader, kResizableArray}) {
        error(
            call.loc,
            call.text + "() gives a resizable shader[]: '" + name + "' is a " + tname(t) +
                (t.type == ShadingType::Shader ? " (declare it '" + name + "[]')" : ""));
        return;
    }
    std::vector<ArgInfo> args = gather_args(call, false);
    coshader_call(call, args, target);
}

Val Generator::coshader_call(const Expr& e, std::vector<ArgInfo>& args, int target) {
    const std::string& name = e.text;
    for (const ArgInfo& a : args)
        if (!a.literal && !a.val.ok()) return {}; // reported
    auto is_type = [&](const ArgInfo& a, ShadingType t) {
        return !a.literal && type(a.val.sym) == TypeSpec{t, 0};
    };
    const TypeSpec shader{ShadingType::Shader, 0};
    if (name == "getshader" || name == "getlight") {
        if (args.size() != 1 || !is_type(args[0], ShadingType::String)) {
            error(e.loc, name + " takes (string handle)");
            return {};
        }
        const int d = temp(shader, varying(args[0].val.sym));
        emit(name, {d, args[0].val.sym});
        return {d};
    }
    if (name == "getshaders" || name == "getlights") {
        std::vector<int> ops;
        for (std::size_t k = 0; k < args.size(); ++k)
            if (!is_type(args[k], ShadingType::String) || varying(args[k].val.sym)) {
                error(e.loc, name + " takes (\"category\", uniform string category)");
                return {};
            }
        if (args.size() % 2 != 0) {
            error(e.loc, name + " takes (\"category\", uniform string category)");
            return {};
        }
        if (target < 0) target = temp({ShadingType::Shader, kResizableArray}, false);
        check_store(target, false, e.loc);
        std::vector<int> all{target};
        for (const ArgInfo& a : args) all.push_back(a.val.sym);
        emit(name, all, 1);
        return {target};
    }
    if (name == "hasmethod") {
        if (args.size() != 2 || !is_type(args[0], ShadingType::Shader) ||
            !is_type(args[1], ShadingType::String)) {
            error(e.loc, "hasmethod takes (shader, string name)");
            return {};
        }
        const int d = temp({ShadingType::Float, 0},
                           varying(args[0].val.sym) || varying(args[1].val.sym));
        emit(name, {d, args[0].val.sym, args[1].val.sym});
        return {d};
    }
    // getvar(shader, "name"[, output var]): 1 when the shader has it.
    if (args.size() < 2 || args.size() > 3 || !is_type(args[0], ShadingType::Shader) ||
        !is_type(args[1], ShadingType::String)) {
        error(e.loc, "getvar takes (shader, string name[, output variable])");
        return {};
    }
    const int d = temp({ShadingType::Float, 0}, varying(args[0].val.sym));
    std::vector<int> all{d, args[0].val.sym, args[1].val.sym};
    uint64_t writes = 1;
    if (args.size() == 3) {
        const ArgInfo& out = args[2];
        if (!out.is_var) {
            error(out.expr->loc,
                  "argument 3 of getvar is an output: it must be a variable");
            return {};
        }
        if (!check_writable(out.var, out.expr->text, out.expr->loc)) return {};
        check_store(out.var.sym, m_tentative.count(out.var.sym) > 0, out.expr->loc);
        all.push_back(out.var.sym);
        writes |= 8;
    }
    emit("getvar", all, writes);
    return {d};
}

Val Generator::gen_method_call(const Expr& e, const TypeSpec* hint, bool discard) {
    LocGuard lg(*this, e.loc);
    Val h = value(*e.args[0]);
    if (!h.ok()) return {};
    if (type(h.sym) != TypeSpec{ShadingType::Shader, 0}) {
        error(e.args[0]->loc, "'->' calls a method of a shader (from getshader(), "
                              "getlights()...), not of a " +
                                  tname(type(h.sym)));
        return {};
    }
    if (e.args.size() + 2 > 64) {
        error(e.loc, "too many arguments in the call of method '" + e.text + "'");
        return {};
    }
    std::vector<int> all{-1, h.sym, kstring(e.text)};
    uint64_t writes = 0;
    bool ok = true;
    for (std::size_t k = 1; k < e.args.size(); ++k) {
        const Expr& a = *e.args[k];
        // A writable variable goes by reference: the method may write it.
        const Var* v = a.kind == ExprKind::Ident &&
                               !(a.text == "PI" && !shadowed("PI")) &&
                               !(a.text == "null" && !shadowed("null"))
                           ? lookup(a.text, a.loc, false)
                           : nullptr;
        if (v && !v->readonly) {
            writes |= uint64_t(1) << all.size();
            // What the method writes may vary per point.
            check_store(v->sym, m_tentative.count(v->sym) > 0, a.loc);
            all.push_back(v->sym);
            continue;
        }
        Val x = v ? Val{v->sym} : value(a);
        if (!x.ok()) {
            ok = false;
            continue;
        }
        all.push_back(x.sym);
    }
    if (!ok) return {};
    TypeSpec rt{ShadingType::Float, 0};
    if (hint && !hint->is_array() && hint->type != ShadingType::Void) rt = *hint;
    all[0] = temp(rt, true);
    if (!discard) writes |= 1;
    emit("callmethod", all, writes);
    if (discard) return {Val::kVoid};
    return {all[0]};
}

} // namespace sss::detail::codegen
