// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file codegen_arrays.cpp
/// The array functions of PRMan 13.5's RSL in the code generator:
/// `arraylength(a)` (a constant for a fixed-length array), and for resizable
/// arrays (`float a[]`) `resize(a, n)`, `push(a, value)`, `pop(a)` and
/// `reserve(a, n)`. A resizable array has one length for the whole batch:
/// the lengths given to resize and reserve must be uniform; its elements may
/// vary. The ops are described in program.h.

#include "codegen_internal.h"

namespace sss::detail::codegen {

bool Generator::is_array_function(const std::string& name) {
    return name == "arraylength" || name == "resize" || name == "push" || name == "pop" ||
           name == "reserve";
}

Val Generator::array_call(const Expr& e, std::vector<ArgInfo>& args) {
    const std::string& name = e.text;
    const bool one = name == "arraylength" || name == "pop";
    if (args.size() != (one ? 1u : 2u)) {
        error(e.loc, name + " takes " +
                         (one              ? std::string("(array)")
                          : name == "push" ? std::string("(array, value)")
                                           : std::string("(array, length)")));
        return {};
    }
    ArgInfo& a = args[0];
    if (!a.literal && !a.val.ok()) return {}; // reported
    const TypeSpec at = a.literal ? TypeSpec{} : type(a.val.sym);
    if (a.literal || !at.is_array()) {
        error(a.expr->loc, "the first argument of " + name + " must be an array, not " +
                               (a.literal ? std::string("a tuple") : "a " + tname(at)));
        return {};
    }
    const int array = a.val.sym;
    if (name == "arraylength") {
        if (!at.is_resizable()) return {kfloat(at.array)};
        const int d = temp({ShadingType::Float, 0}, false);
        emit("arraylength", {d, array});
        return {d};
    }
    if (!at.is_resizable()) {
        error(a.expr->loc, name + ": '" + a.expr->text + "' has the fixed length " +
                               std::to_string(at.array) +
                               " (only arrays declared with [] can change length)");
        return {};
    }
    if (!a.is_var || !check_writable(a.var, a.expr->text, a.expr->loc)) return {};
    const TypeSpec et{at.type, 0};
    if (name == "pop") {
        const int d = temp(et, varying(array));
        check_store(array, false, e.loc);
        emit("pop", {d, array}, 3);
        return {d};
    }
    ArgInfo& x = args[1];
    if (name == "push") {
        Val v = x.literal ? value(*x.expr, &et) : x.val;
        v = convert(v, et, x.expr->loc);
        if (!v.ok()) return {};
        check_store(array, varying(v.sym), e.loc);
        emit("push", {array, v.sym});
        return {Val::kVoid};
    }
    // resize, reserve: a uniform float length.
    const TypeSpec ft{ShadingType::Float, 0};
    Val n = x.literal ? Val{} : x.val;
    if (x.literal || (n.ok() && type(n.sym) != ft)) {
        error(x.expr->loc, name + ": the length must be a float");
        return {};
    }
    if (!n.ok()) return {};
    if (varying(n.sym)) {
        error(x.expr->loc, name + ": the length must be uniform (a resizable array has "
                                  "one length for every point)");
        return {};
    }
    if (name == "resize") check_store(array, false, e.loc);
    emit(name, {array, n.sym});
    return {Val::kVoid};
}

} // namespace sss::detail::codegen
