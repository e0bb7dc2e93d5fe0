// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_bind_test.cpp
/// Every overload of the built-in table (builtins.cpp) binds in the engine:
/// programs calling each prototype are built by hand and bound.
///
/// Suite names start with "RslEngine".

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "sss/rsl/builtins.h"
#include "sss/shading/engine.h"

namespace {

using namespace sss;

// The compiler's type letters; '.' (any type) is tried as a float here.
ShadingType letter_type(char c, ShadingType x) {
    return c == '.' ? ShadingType::Float : detail::letter_type(c, x);
}

struct Arg {
    ShadingType type;
    bool output = false;
    bool array = false;
};

/// One program calling `name` with the prototype's arguments (x = `x`,
/// `rest` extra repetitions, a token-value pair when `pair`).
std::shared_ptr<Program> call_program(const detail::BuiltinSignature& sig, ShadingType x,
                                      int rest, bool pair) {
    const std::string proto = sig.proto;
    std::vector<Arg> args;
    Arg last{};
    bool tokens = false;
    for (std::size_t i = 2; i < proto.size(); ++i) {
        char c = proto[i];
        if (c == '!' || c == '@') {
            tokens = true;
            continue;
        }
        if (c == '*') { // the letter before '*' repeats zero or more times
            args.pop_back();
            for (int k = 0; k < rest; ++k) args.push_back(last);
            continue;
        }
        Arg a;
        if (c == '[') {
            a.array = true;
            c = proto[++i];
            ++i; // ']'
        }
        a.output = std::isupper(static_cast<unsigned char>(c)) != 0;
        a.type = letter_type(static_cast<char>(std::tolower(c)), x);
        args.push_back(a);
        last = a;
    }
    auto p = std::make_shared<Program>();
    p->name = std::string("call_") + sig.name;
    p->kind = ShaderKind::Surface;
    p->files = {"builtins.sl"};
    auto sym = [&](ShadingType t, bool array, bool varying) {
        Symbol s;
        s.name = "s" + std::to_string(p->symbols.size());
        s.type = {t, array ? 4 : 0};
        s.varying = varying && t != ShadingType::String;
        s.kind = SymbolKind::Local;
        p->symbols.push_back(s);
        return static_cast<int>(p->symbols.size() - 1);
    };
    Op op;
    op.name = sig.name;
    op.where = {0, 1, 1};
    const ShadingType rt = letter_type(proto[0], x);
    if (rt != ShadingType::Void) {
        op.args.push_back(sym(rt, false, true));
        op.writes |= 1;
    }
    for (const Arg& a : args) {
        if (a.output) op.writes |= uint64_t(1) << op.args.size();
        op.args.push_back(sym(a.type, a.array, true));
    }
    if (tokens && pair) {
        Symbol name;
        name.name = "tok";
        name.type = {ShadingType::String, 0};
        name.kind = SymbolKind::Const;
        name.strings = {"width"};
        p->symbols.push_back(name);
        op.args.push_back(static_cast<int>(p->symbols.size() - 1));
        op.args.push_back(sym(ShadingType::Float, false, false));
    }
    p->ops.push_back(op);
    return p;
}

TEST(RslEngineBind, EveryBuiltinOverloadBinds) {
    std::vector<std::string> failures;
    for (const detail::BuiltinSignature& sig : detail::builtin_signatures()) {
        const std::string proto = sig.proto;
        const bool has_x = proto.find('x') != std::string::npos;
        const bool has_rest = proto.find('*') != std::string::npos;
        const bool has_tokens = proto.find_first_of("!@") != std::string::npos;
        for (ShadingType x :
             {ShadingType::Point, ShadingType::Vector, ShadingType::Normal}) {
            for (int rest : {0, 2}) {
                for (bool pair : {false, true}) {
                    if ((!has_rest && rest) || (!has_tokens && pair)) continue;
                    auto prog = call_program(sig, x, rest, pair);
                    try {
                        ShaderInstance inst(prog, {}, Matrix4(1.0), "");
                    } catch (const ValueError& e) {
                        failures.push_back(std::string(sig.name) + " " + proto +
                                           " x=" + shading_type_name(x) + " rest=" +
                                           std::to_string(rest) + ": " + e.what());
                    }
                }
            }
            if (!has_x) break;
        }
    }
    std::string all;
    for (const std::string& f : failures) all += f + "\n";
    EXPECT_TRUE(failures.empty()) << all;
}

} // namespace
