// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file codegen_types.cpp
/// Types in the code generator: the built-in prototype letters, implicit
/// conversions, the result types of operators, writability, and the
/// uniform/varying inference (stores under varying conditions and loops).

#include "codegen_internal.h"

namespace sss::detail::codegen {

namespace {

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

} // namespace

const std::vector<Proto>& protos() {
    static const std::vector<Proto> table = parse_protos();
    return table;
}

// --- uniform / varying ------------------------------------------------

void Generator::force_varying(int sym) {
    if (!varying(sym)) m_newly.insert(m_p.symbols[sym].name);
}

void Generator::check_store(int target, bool value_varying, SrcLoc at) {
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

bool Generator::masked() const {
    if (m_varying_cond > 0) return true;
    for (const Region& r : m_regions)
        if (r.kind != Region::Loop && r.varying_exit) return true;
    return false;
}

bool Generator::masked_in_function() const {
    const FuncCtx& ctx = m_funcs.back();
    if (m_varying_cond > ctx.entry_varying_cond) return true;
    for (std::size_t i = ctx.entry_region; i < m_regions.size(); ++i)
        if (m_regions[i].kind != Region::Loop && m_regions[i].varying_exit) return true;
    return false;
}

void Generator::pop_region() {
    Region r = std::move(m_regions.back());
    m_regions.pop_back();
    if (r.kind == Region::Loop && r.varying_exit)
        for (int s : r.assigned) force_varying(s);
}

// --- conversions --------------------------------------------------------

bool Generator::convertible(const TypeSpec& from, const TypeSpec& to) {
    if (from == to) return true;
    if (from.is_array() || to.is_array()) return false;
    if (from.type == ShadingType::Float &&
        (is_triple(to.type) || to.type == ShadingType::Matrix))
        return true;
    return is_point_like(from.type) && is_point_like(to.type);
}

std::string Generator::conversion_error(const TypeSpec& from, const TypeSpec& to) {
    if ((from.type == ShadingType::Color && is_point_like(to.type)) ||
        (is_point_like(from.type) && to.type == ShadingType::Color))
        return "cannot convert " + tname(from) + " to " + tname(to) +
               " (points and colors do not mix)";
    return "cannot convert " + tname(from) + " to " + tname(to);
}

Val Generator::convert(Val v, const TypeSpec& to, SrcLoc at) {
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

ShadingType Generator::binary_type(const std::string& op, ShadingType a, ShadingType b,
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
    if (a == T::Shader || b == T::Shader) {
        if ((op == "==" || op == "!=") && a == b) return T::Float;
        why = "shader handles only compare with == and != (with another shader or null)";
        return T::Void;
    }
    if (op == "==" || op == "!=") {
        if (a == b || (pa && pb) || (a == T::Float && (is_triple(b) || b == T::Matrix)) ||
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

const char* Generator::op_name(const std::string& op) {
    static const std::map<std::string, const char*> names = {
        {"+", "add"},   {"-", "sub"}, {"*", "mul"},  {"/", "div"}, {".", "dot"},
        {"^", "cross"}, {"==", "eq"}, {"!=", "ne"},  {"<", "lt"},  {"<=", "le"},
        {">", "gt"},    {">=", "ge"}, {"&&", "and"}, {"||", "or"}};
    auto it = names.find(op);
    return it == names.end() ? "?" : it->second;
}

bool Generator::check_writable(const Var& v, const std::string& name, SrcLoc at) {
    if (!v.readonly) return true;
    std::string why;
    if (std::strcmp(v.what, "shader parameter") == 0)
        why = " (declare it output to write it)";
    else if (std::strcmp(v.what, "global variable") == 0)
        why = std::string(" in a ") + shader_kind_name(m_kind) + " shader";
    else if (std::strcmp(v.what, "function parameter") == 0)
        why = " (declare it output to write it)";
    error(at, std::string("cannot assign to ") + v.what + " '" + name +
                  "': it is read-only" + why);
    return false;
}

} // namespace sss::detail::codegen
