// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file compiler_test.cpp
/// The RSL front end (compiler.h): every construct of shading.md section 2
/// parses and type-checks into the Program IR (program.h); errors carry
/// file:line:column.

#include <gtest/gtest.h>

#include <string>

#include "rsl_test_util.h"

namespace {

using namespace sss;
using sss::test::compile_errors;
using sss::test::compile_one;
using sss::test::count_ops;
using sss::test::find_op;
using sss::test::has_error;

const Symbol& sym(const Program& p, const std::string& name) {
    const int i = p.find(name);
    EXPECT_GE(i, 0) << name;
    static const Symbol none;
    return i >= 0 ? p.symbols[i] : none;
}

TEST(RslCompiler, PlasticCompiles) {
    const Program p = compile_one(R"(
surface plastic(float Ka = 1, Kd = .5, Ks = .5, roughness = .1;
                color specularcolor = 1;)
{
    normal Nf = faceforward(normalize(N), I);
    vector V = -normalize(I);
    Oi = Os;
    Ci = Os * (Cs * (Ka * ambient() + Kd * diffuse(Nf)) +
               specularcolor * Ks * specular(Nf, V, roughness));
}
)");
    EXPECT_EQ(p.name, "plastic");
    EXPECT_EQ(p.kind, ShaderKind::Surface);
    const std::vector<int> params = p.parameters();
    ASSERT_EQ(params.size(), 5u);
    EXPECT_EQ(p.symbols[params[1]].name, "Kd");
    EXPECT_EQ(p.symbols[params[1]].numbers, std::vector<float>{0.5f});
    EXPECT_FALSE(p.symbols[params[1]].varying); // parameters default to uniform
    EXPECT_EQ(p.symbols[params[4]].type.type, ShadingType::Color);
    EXPECT_EQ(p.symbols[params[4]].numbers, (std::vector<float>{1, 1, 1}));
    EXPECT_EQ(p.body_begin, 0);
    EXPECT_EQ(sym(p, "Ci").kind, SymbolKind::Global);
    EXPECT_TRUE(sym(p, "Nf").varying);
    EXPECT_EQ(sym(p, "Nf").type.type, ShadingType::Normal);
    EXPECT_EQ(count_ops(p, "specular"), 1);
    for (const Op& op : p.ops) {
        EXPECT_EQ(op.where.file, 0);
        EXPECT_GT(op.where.line, 0);
    }
    const Op* spec = find_op(p, "specular");
    ASSERT_TRUE(spec);
    EXPECT_EQ(spec->args.size(), 4u);
    EXPECT_EQ(spec->writes, 1u);
    EXPECT_EQ(p.symbols[spec->args[0]].type.type, ShadingType::Color);
}

TEST(RslCompiler, LexerNumbersStringsAndOperators) {
    const Program p = compile_one(R"(
surface s(string tex = "a" "b\t\x41\101"; float a = 1.; float b = .5; float c = 1e2;
          float d = 2.5E-1f; float e = 3f)
{
    float x = 0;
    x += 1; x -= 2; x *= 3; x /= 4;
    Ci = x;
}
)");
    EXPECT_EQ(sym(p, "tex").strings, std::vector<std::string>{"ab\tAA"});
    EXPECT_EQ(sym(p, "a").numbers, std::vector<float>{1.0f});
    EXPECT_EQ(sym(p, "b").numbers, std::vector<float>{0.5f});
    EXPECT_EQ(sym(p, "c").numbers, std::vector<float>{100.0f});
    EXPECT_EQ(sym(p, "d").numbers, std::vector<float>{0.25f});
    EXPECT_EQ(sym(p, "e").numbers, std::vector<float>{3.0f});
    EXPECT_EQ(count_ops(p, "add"), 1);
    EXPECT_EQ(count_ops(p, "sub"), 1);
    EXPECT_EQ(count_ops(p, "mul"), 1);
    EXPECT_EQ(count_ops(p, "div"), 1);
}

TEST(RslCompiler, CommentsAreSkippedWithoutPreprocessor) {
    const Program p =
        compile_one("// line\nsurface /* c */ s() { Ci = 1; /* x\n y */ }\n");
    EXPECT_EQ(p.name, "s");
}

TEST(RslCompiler, PrecedenceDotTighterThanMul) {
    // a * b . c is a * (b . c): the dot of two vectors, then a float times it.
    const Program p = compile_one(R"(
surface s() {
    vector a = I, b = N, c = dPdu;
    float f = 2 * b . c;
    vector g = a + b ^ c * 2;
}
)");
    ASSERT_EQ(count_ops(p, "dot"), 1);
    const Op* dot = find_op(p, "dot");
    const Op* mul = find_op(p, "mul");
    ASSERT_TRUE(dot && mul);
    EXPECT_LT(dot - p.ops.data(), mul - p.ops.data()); // dot first
    EXPECT_EQ(mul->args[2], dot->args[0]);
    // a + (b ^ (c * 2)): mul, cross, add in that order.
    std::vector<std::string> order;
    for (const Op& op : p.ops)
        if (op.name == "cross" || op.name == "add" || op.name == "mul")
            order.push_back(op.name);
    EXPECT_EQ(order, (std::vector<std::string>{"mul", "mul", "cross", "add"}));
}

TEST(RslCompiler, UnaryAndCastBindTighterThanBinary) {
    const Program p = compile_one(R"(
surface s() {
    float f = float noise(P) * 2;
    float g = -f * 3;
    float h = !(f < g) ? 1 : 0;
}
)");
    const Op* noise = find_op(p, "noise");
    ASSERT_TRUE(noise);
    EXPECT_EQ(p.symbols[noise->args[0]].type.type, ShadingType::Float);
    EXPECT_EQ(count_ops(p, "neg"), 1);
    EXPECT_EQ(count_ops(p, "not"), 1);
    EXPECT_EQ(count_ops(p, "lt"), 1);
    EXPECT_EQ(count_ops(p, "if"), 1); // the ternary
}

TEST(RslCompiler, TypecastsAndTuples) {
    const Program p = compile_one(R"(
surface s() {
    color a = color "hsv" (0.5, 1, 1);
    point b = point "object" (0, 0, 0);
    vector c = vector "world" I;
    matrix m = matrix "world" (1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1);
    matrix n = matrix "shader" 1;
    color d = (1, 0, 0);
    point e = (u, v, 0);
    normal f = normal b;
    matrix g = 1;
    string str = string "x";
    float h = float 2;
    Ci = a + d;
}
)");
    int constructs = 0, casts = 0;
    for (const Op& op : p.ops) {
        if (op.name == "construct") {
            ++constructs;
            const Symbol& d = p.symbols[op.args[0]];
            if (d.type.type == ShadingType::Color) {
                EXPECT_EQ(op.args.size(), 5u);
                EXPECT_EQ(p.symbols[op.args[1]].strings, std::vector<std::string>{"hsv"});
            }
            if (d.type.type == ShadingType::Matrix) {
                EXPECT_TRUE(op.args.size() == 18u || op.args.size() == 3u);
            }
        }
        if (op.name == "cast") {
            ++casts;
            EXPECT_EQ(op.args.size(), 3u);
            EXPECT_EQ(p.symbols[op.args[1]].strings, std::vector<std::string>{"world"});
        }
    }
    EXPECT_EQ(constructs, 5); // hsv, object, 16-tuple world, shader 1, (u,v,0)
    EXPECT_EQ(casts, 1);
    // (1,0,0) as a color is a constant.
    EXPECT_EQ(p.symbols[find_op(p, "add")->args[2]].kind, SymbolKind::Local);
}

TEST(RslCompiler, ArraysParamsAndLocals) {
    const Program p = compile_one(R"(
surface s(float w[3] = {1, 2, 3}; string names[2] = {"a", "b"}) {
    float a[4] = {0, 1, 2, 3};
    float i = 1;
    a[i] = w[2];
    a[0] += 1;
    float x = a[i] + (a[2] = 5);
}
)");
    EXPECT_EQ(sym(p, "w").type, (TypeSpec{ShadingType::Float, 3}));
    EXPECT_EQ(sym(p, "w").numbers, (std::vector<float>{1, 2, 3}));
    EXPECT_EQ(sym(p, "names").strings, (std::vector<std::string>{"a", "b"}));
    EXPECT_EQ(count_ops(p, "aassign"), 4 + 3);
    EXPECT_GE(count_ops(p, "aref"), 3);
}

TEST(RslCompiler, ControlFlow) {
    const Program p = compile_one(R"(
surface s(float n = 4) {
    float i, sum = 0;
    for (i = 0; i < n; i += 1) {
        if (i == 2) continue;
        if (n > 10) break;
        sum += i;
    }
    while (sum > 0) {
        sum -= 1;
        float j;
        for (j = 0; j < 3; j += 1) {
            if (j > u) break 2;
            else continue 1;
        }
    }
    if (sum) Ci = 1; else Ci = 0;
    if (u > 0.5) return;
    Ci = 2;
}
)");
    ASSERT_EQ(count_ops(p, "loop"), 3);
    for (std::size_t i = 0; i < p.ops.size(); ++i) {
        const Op& op = p.ops[i];
        if (op.name == "loop") {
            EXPECT_LT(static_cast<int>(i), op.jump[0]);
            EXPECT_LE(op.jump[0], op.jump[1]);
            EXPECT_LE(op.jump[1], op.jump[2]);
            EXPECT_LE(op.jump[2], op.jump[3]);
            EXPECT_EQ(p.symbols[op.args[0]].type.type, ShadingType::Float);
        }
        if (op.name == "if") {
            EXPECT_LE(op.jump[0], op.jump[1]);
            EXPECT_GT(op.jump[0], static_cast<int>(i));
        }
    }
    bool saw_break2 = false;
    for (const Op& op : p.ops) saw_break2 |= op.name == "break" && op.level == 2;
    EXPECT_TRUE(saw_break2);
    EXPECT_EQ(count_ops(p, "continue"), 2);
    EXPECT_EQ(count_ops(p, "return"), 1);
    // The first loop is uniform: i and sum are uniform (n is a parameter).
    EXPECT_FALSE(sym(p, "i").varying);
    // sum is decremented in a loop that a varying break leaves: varying.
    EXPECT_TRUE(sym(p, "sum").varying);
    // `if (sum)`: a float condition as it is (non-zero is true).
    const Op* last_if = nullptr;
    for (const Op& op : p.ops)
        if (op.name == "if") last_if = &op;
    ASSERT_TRUE(last_if);
}

TEST(RslCompiler, UniformDemotion) {
    const Program p = compile_one(R"(
surface s(float Kd = 1) {
    float a = Kd * 2;     // uniform: only uniform assignments
    float b = a + s;      // varying
    float c = 1;
    if (u > 0.5) c = 2;   // assigned under a varying condition: varying
    float d = 1;
    if (Kd > 0.5) d = 2;  // uniform condition: stays uniform
    uniform float e = a;
    varying float f = 1;
    Ci = a + b + c + d + e + f;
}
)");
    EXPECT_FALSE(sym(p, "a").varying);
    EXPECT_TRUE(sym(p, "b").varying);
    EXPECT_TRUE(sym(p, "c").varying);
    EXPECT_FALSE(sym(p, "d").varying);
    EXPECT_FALSE(sym(p, "e").varying);
    EXPECT_TRUE(sym(p, "f").varying);
}

TEST(RslCompiler, ParameterDefaultsThatAreNotConstant) {
    const Program p = compile_one(R"(
light spot(float intensity = 1; point from = point "shader" (0,0,0);
           point to = point "shader" (0,0,1); float coneangle = radians(30);
           output varying float aov = 0;)
{
    uniform vector A = normalize(to - from);
    illuminate(from, A, coneangle) {
        Cl = intensity * pow(L . A / length(L), 2) / (L . L);
        aov = 1;
    }
}
)");
    EXPECT_EQ(p.kind, ShaderKind::Light);
    const Symbol& from = sym(p, "from");
    EXPECT_TRUE(from.numbers.empty());
    EXPECT_LT(from.init_begin, from.init_end);
    EXPECT_LE(from.init_end, p.body_begin);
    EXPECT_EQ(p.ops[from.init_begin].name, "construct");
    const Symbol& cone = sym(p, "coneangle");
    EXPECT_LT(cone.init_begin, cone.init_end);
    EXPECT_EQ(sym(p, "intensity").init_begin, -1);
    EXPECT_EQ(sym(p, "aov").kind, SymbolKind::OutputParam);
    EXPECT_TRUE(sym(p, "aov").varying);
    const Op* ill = find_op(p, "illuminate");
    ASSERT_TRUE(ill);
    EXPECT_EQ(ill->args.size(), 3u);
    EXPECT_GT(ill->jump[0], static_cast<int>(ill - p.ops.data()) + 1);
}

TEST(RslCompiler, IlluminanceForms) {
    const Program p = compile_one(R"(
surface s() {
    color c = 0;
    illuminance(P) { c += Cl; }
    illuminance(P, N, PI/2) { c += Cl * (normalize(L) . N); }
    illuminance("specular", P) { c += Ol; }
    illuminance("-diffuse", P, N, 1) { c += 1; }
    Ci = c;
}
)");
    int n = 0;
    for (const Op& op : p.ops) {
        if (op.name != "illuminance") continue;
        ++n;
        ASSERT_EQ(op.args.size(), 4u);
        EXPECT_EQ(p.symbols[op.args[0]].type.type, ShadingType::String);
        EXPECT_EQ(p.symbols[op.args[1]].type.type, ShadingType::Point);
        EXPECT_EQ(p.symbols[op.args[2]].type.type, ShadingType::Vector);
        EXPECT_EQ(p.symbols[op.args[3]].type.type, ShadingType::Float);
    }
    EXPECT_EQ(n, 4);
    EXPECT_TRUE(sym(p, "c").varying);
}

TEST(RslCompiler, SolarAndIlluminateForms) {
    const Program p = compile_one(R"(
light l(point from = (0,0,0)) {
    solar() { Cl = 1; }
    solar(vector (0,0,1), 0) { Cl = 1; }
    illuminate(from) { Cl = 1 / (L . L); }
    Ol = 1;
}
)");
    EXPECT_EQ(count_ops(p, "solar"), 2);
    const Op* solar = find_op(p, "solar");
    ASSERT_TRUE(solar);
    ASSERT_EQ(solar->args.size(), 2u);
    EXPECT_EQ(p.symbols[solar->args[1]].numbers, std::vector<float>{-1.0f});
    EXPECT_EQ(count_ops(p, "illuminate"), 1);
}

TEST(RslCompiler, DisplacementWritesPN) {
    const Program p = compile_one(R"(
displacement bumpy(float Km = 0.1) {
    P += Km * noise(P) * normalize(N);
    N = calculatenormal(P);
}
)");
    EXPECT_EQ(p.kind, ShaderKind::Displacement);
    EXPECT_EQ(count_ops(p, "calculatenormal"), 1);
}

TEST(RslCompiler, OverloadByReturnType) {
    const Program p = compile_one(R"(
surface s() {
    color c = noise(P);         // picks the color version
    float f = noise(P);
    vector v = vector noise(P);
    color d = color noise(s, t);
    float g = noise(P) * 2;     // float by default
    Ci = c + f + d + g;
}
)");
    std::vector<ShadingType> results;
    for (const Op& op : p.ops)
        if (op.name == "noise") results.push_back(p.symbols[op.args[0]].type.type);
    EXPECT_EQ(results, (std::vector<ShadingType>{ShadingType::Color, ShadingType::Float,
                                                 ShadingType::Vector, ShadingType::Color,
                                                 ShadingType::Float}));
}

TEST(RslCompiler, TextureChannelsAndTokenValues) {
    const Program p = compile_one(R"(
surface s(string map = "a.tx"; string names[2] = {"x", "y"}) {
    color c = texture(map[1], s, t, "blur", 0.1);
    float f = texture("f.tx");
    float g = float texture(names[1], s, t);
    float h = shadow("sm"[2], P, "bias", 0.01);
    color e = environment("env", vector (0,0,1));
    Ci = c * f * g * h * e;
}
)");
    std::vector<const Op*> tex;
    for (const Op& op : p.ops)
        if (op.name == "texture") tex.push_back(&op);
    ASSERT_EQ(tex.size(), 3u);
    // texture(map[1], s, t, "blur", 0.1): result, map, chan 1, s, t, "blur", 0.1
    ASSERT_EQ(tex[0]->args.size(), 7u);
    EXPECT_EQ(p.symbols[tex[0]->args[0]].type.type, ShadingType::Color);
    EXPECT_EQ(p.symbols[tex[0]->args[1]].name, "map");
    EXPECT_EQ(p.symbols[tex[0]->args[2]].numbers, std::vector<float>{1.0f});
    EXPECT_EQ(p.symbols[tex[0]->args[5]].strings, std::vector<std::string>{"blur"});
    // texture("f.tx"): channel 0 added.
    ASSERT_EQ(tex[1]->args.size(), 3u);
    EXPECT_EQ(p.symbols[tex[1]->args[2]].numbers, std::vector<float>{0.0f});
    // names[1] is an array element (names is an array): channel 0.
    EXPECT_EQ(p.symbols[tex[2]->args[2]].numbers, std::vector<float>{0.0f});
    const Op* sh = find_op(p, "shadow");
    ASSERT_TRUE(sh);
    EXPECT_EQ(p.symbols[sh->args[2]].numbers, std::vector<float>{2.0f});
    EXPECT_EQ(sh->args.size(), 6u);
    const Op* env = find_op(p, "environment");
    ASSERT_TRUE(env);
    EXPECT_EQ(env->args.size(), 4u);
}

TEST(RslCompiler, OutputArgumentsOfBuiltins) {
    const Program p = compile_one(R"(
surface s(float Kfs = 1) {
    float Kr, Kt;
    fresnel(normalize(I), normalize(N), 1.5, Kr, Kt);
    float res[2];
    float ok = textureinfo("a.tx", "resolution", res);
    point q = P;
    setxcomp(q, 1);
    float val = 0;
    float found = texture3d("c.ptc", P, N, "filterscale", Kfs, "_radiosity", val);
    Ci = Kr + Kt + ok + found + val;
}
)");
    const Op* fr = find_op(p, "fresnel");
    ASSERT_TRUE(fr);
    EXPECT_EQ(fr->args.size(), 5u); // void: no result
    EXPECT_EQ(fr->writes, (1u << 3) | (1u << 4));
    EXPECT_TRUE(sym(p, "Kr").varying);
    const Op* ti = find_op(p, "textureinfo");
    ASSERT_TRUE(ti);
    EXPECT_EQ(ti->writes, 1u | (1u << 3));
    const Op* sx = find_op(p, "setxcomp");
    ASSERT_TRUE(sx);
    EXPECT_EQ(sx->writes, 1u);
    const Op* t3 = find_op(p, "texture3d");
    ASSERT_TRUE(t3);
    EXPECT_EQ(t3->writes, 1u | (1u << 7)); // the channel value, not the filterscale
}

TEST(RslCompiler, FunctionsInlinedWithOutputAndExtern) {
    const Program p = compile_one(R"(
float twice(float x) { return 2 * x; }
void accumulate(output color acc; color c) { acc += c; }
surface s(float Kd = 1) {
    color total = 0;
    float scale(float y) {
        extern float Kd;
        extern color total;
        return y * Kd + comp(total, 0);
    }
    accumulate(total, Cs);
    float a = twice(u) + scale(3);
    float b = twice(2);
    Ci = total * a * b;
}
)");
    EXPECT_EQ(count_ops(p, "block"), 4);
    EXPECT_EQ(count_ops(p, "return"), 3); // void accumulate has none
    for (std::size_t i = 0; i < p.ops.size(); ++i) {
        const Op& op = p.ops[i];
        if (op.name != "block") continue;
        EXPECT_GT(op.jump[0], static_cast<int>(i));
    }
    // accumulate's acc aliases `total`: the add writes total directly.
    bool writes_total = false;
    for (const Op& op : p.ops)
        if (op.name == "assign" && p.symbols[op.args[0]].name == "total")
            writes_total = true;
    EXPECT_TRUE(writes_total);
    int twice_x = 0;
    for (const Symbol& s : p.symbols)
        if (s.name.rfind("twice::x@", 0) == 0) ++twice_x;
    EXPECT_EQ(twice_x, 1); // twice(u) aliases u; twice(2) copies 2 into a local
}

TEST(RslCompiler, NestedFunctionsAndUserOverloads) {
    const Program p = compile_one(R"(
float f(float x) { return x; }
color f(color x) { return x * 2; }
surface s() {
    void g(output float r) {
        float h(float z) { return z + 1; }
        r = h(r);
    }
    float a = 1;
    g(a);
    color c = f(Cs);
    Ci = c * f(a);
}
)");
    EXPECT_EQ(count_ops(p, "block"), 4);
}

TEST(RslCompiler, IfWithoutRelationIsNonZero) {
    const Program p =
        compile_one("surface s() { float x = u; if (x) Ci = 1; while (x) x -= 1; }");
    EXPECT_EQ(count_ops(p, "if"), 1);
    EXPECT_EQ(count_ops(p, "loop"), 1);
}

TEST(RslCompiler, SeveralShadersInOneFile) {
    auto r = sss::test::compile_raw("surface a() { Ci = 1; }\nlight b() { Cl = 1; }\n");
    ASSERT_EQ(r.shaders.size(), 2u);
    EXPECT_EQ(r.shaders[1].name, "b");
    EXPECT_EQ(r.shaders[1].kind, ShaderKind::Light);
}

// --- errors --------------------------------------------------------------

TEST(RslErrors, SyntaxErrorLineAndColumn) {
    auto ds = compile_errors("surface s() {\n  float x = 1\n  Ci = x;\n}\n");
    ASSERT_FALSE(ds.empty());
    EXPECT_EQ(ds[0].file, "test.sl");
    EXPECT_EQ(ds[0].line, 3);
    EXPECT_EQ(ds[0].column, 3);
    EXPECT_NE(ds[0].message.find("expected ';'"), std::string::npos) << ds[0].message;
    EXPECT_EQ(ds[0].source_line, "  Ci = x;");
    const std::string f = ds[0].format();
    EXPECT_EQ(f, "test.sl:3:3: error: expected ';' after the declaration, got 'Ci'\n"
                 "    Ci = x;\n"
                 "    ^");
}

TEST(RslErrors, SeveralErrorsInOneFile) {
    auto ds = compile_errors(
        "surface s() {\n  float x = ;\n  color c = (1,2);\n  Ci = 1 +;\n}\n");
    ASSERT_EQ(ds.size(), 3u) << sss::test::all_messages(ds);
    EXPECT_EQ(ds[0].line, 2);
    EXPECT_EQ(ds[1].line, 3);
    EXPECT_EQ(ds[2].line, 4);
    EXPECT_THROW(sss::test::compile_raw("surface s() { x = ; }"), ShaderCompileError);
}

TEST(RslErrors, SeveralTypeErrors) {
    auto ds = compile_errors(R"(surface s() {
    point p = Cs;
    color c = P;
    float f = P;
    Ci = P + Cs;
}
)");
    EXPECT_EQ(ds.size(), 4u) << sss::test::all_messages(ds);
    EXPECT_TRUE(has_error(ds, "points and colors do not mix"));
    EXPECT_EQ(ds[0].line, 2);
    EXPECT_EQ(ds[3].line, 5);
}

TEST(RslErrors, UnknownFunctionAndArgs) {
    auto ds = compile_errors("surface s() { float x = frobnicate(1); }");
    EXPECT_TRUE(has_error(ds, "unknown function 'frobnicate'"));
    ds = compile_errors("surface s() { float x = sin(1, 2); }");
    EXPECT_TRUE(has_error(ds, "no version of 'sin' takes (float, float)"));
    ds = compile_errors("surface s() { float x = sin(\"a\"); }");
    EXPECT_TRUE(has_error(ds, "no version of 'sin' takes (string)"));
    ds = compile_errors(
        "float f(float a) { return a; } surface s() { float x = f(1, 2); }");
    EXPECT_TRUE(has_error(ds, "no version of 'f'"));
    ds = compile_errors("surface s() { float x = y + 1; }");
    EXPECT_TRUE(has_error(ds, "unknown variable 'y'"));
}

TEST(RslErrors, Recursion) {
    auto ds =
        compile_errors("float f(float a) { return f(a); } surface s() { Ci = f(1); }");
    EXPECT_TRUE(has_error(ds, "recursive call of 'f'"));
    ds = compile_errors(R"(
float h(float a) { float k(float b) { return h(b); } return k(a); }
surface s() { Ci = h(1); }
)");
    EXPECT_TRUE(has_error(ds, "recursive call of 'h'"));
}

TEST(RslErrors, IndirectRecursion) {
    auto ds = compile_errors(R"(
float even(float n) { return n; }
surface t() {
    float odd(float n) {
        float even2(float m) { return odd(m); }
        return even2(n);
    }
    Ci = odd(1);
}
)");
    EXPECT_TRUE(has_error(ds, "recursive call of 'odd'"));
}

TEST(RslErrors, VaryingToUniform) {
    auto ds = compile_errors("surface s() { uniform float x = u; }");
    EXPECT_TRUE(has_error(ds, "cannot assign a varying value to uniform 'x'"));
    ds = compile_errors("surface s(output float k = 1) { k = s; }");
    EXPECT_TRUE(has_error(ds, "varying value to uniform 'k'"));
}

TEST(RslErrors, ReadOnly) {
    auto ds = compile_errors("surface s(float Kd = 1) { Kd = 2; }");
    EXPECT_TRUE(has_error(ds, "cannot assign to shader parameter 'Kd'"));
    // P and N are results of surface shaders too (RISpec 12.1); u is not.
    EXPECT_NO_THROW(compile_text("surface s() { P = P + 1; N = -N; }"));
    ds = compile_errors("surface s() { u = 1; }");
    EXPECT_TRUE(has_error(ds, "cannot assign to global variable 'u'"));
    ds = compile_errors("displacement d() { Ci = 1; }");
    EXPECT_TRUE(has_error(ds, "'Ci' is not available in a displacement shader"));
    ds = compile_errors("light l() { Ci = 1; }");
    EXPECT_TRUE(has_error(ds, "'Ci' is not available"));
    ds = compile_errors("surface s() { color c = Cl; }");
    EXPECT_TRUE(has_error(ds, "'Cl' exists only inside an illuminance"));
    ds = compile_errors("surface s() { illuminance(P) { Cl = 1; } }");
    EXPECT_TRUE(has_error(ds, "cannot assign to global variable 'Cl'"));
    ds = compile_errors("void f(float x) { x = 1; } surface s() { float y; f(y); }");
    EXPECT_TRUE(has_error(ds, "cannot assign to function parameter 'x'"));
    ds = compile_errors("void f(output float x) { x = 1; } surface s() { f(2); }");
    EXPECT_TRUE(has_error(ds, "must be a variable"));
    ds = compile_errors(
        "void f(output float x) { x = 1; } surface s() { color c; f(c); }");
    EXPECT_TRUE(has_error(ds, "no version of 'f'"));
}

TEST(RslErrors, MiscStatements) {
    auto ds = compile_errors("surface s() { break; }");
    EXPECT_TRUE(has_error(ds, "break outside a loop"));
    ds = compile_errors("surface s() { while (u > 0) { break 2; } }");
    EXPECT_TRUE(has_error(ds, "only 1 enclosing loop"));
    ds = compile_errors("transformation t() { P = P; }");
    EXPECT_TRUE(has_error(ds, "transformation shaders are not supported"));
    ds = compile_errors("surface s() { gather(\"\", P, N, 1) { Ci = 1; } }");
    EXPECT_TRUE(has_error(ds, "gather takes (category, P, dir, angle, samples"));
    ds = compile_errors(
        "surface s() { gather(\"\", P, N, 1, 4, \"surface:Ci\", 1) { Ci = 1; } }");
    EXPECT_TRUE(has_error(ds, "must be a variable"));
    ds = compile_errors(
        "surface s() { float x; gather(\"\", P, N, 1, 4, \"ray:length\", x, \"maxdist\") "
        "{ Ci = 1; } }");
    EXPECT_TRUE(has_error(ds, "gather takes"));
    ds = compile_errors(
        "surface s() { color c; gather(\"\", P, N, 1, 4, \"ray:length\", c) Ci = c; }");
    EXPECT_TRUE(has_error(ds, "needs a float variable"));
    ds = compile_errors(
        "surface s() { float x; gather(\"\", P, N, 1, 4, \"ray:nosuch\", x) Ci = x; }");
    EXPECT_TRUE(has_error(ds, "unknown gather output \"ray:nosuch\""));
    ds = compile_errors(
        "surface s(float k = 0) { gather(\"\", P, N, 1, 4, \"surface:Ci\", k) Ci = k; }");
    EXPECT_TRUE(has_error(ds, "read-only"));
    ds = compile_errors(
        "surface s() { uniform float x = 0; gather(\"\", P, N, 1, 4, \"ray:length\", x) "
        "Ci = x; }");
    EXPECT_TRUE(has_error(ds, "varying value to uniform"));
    {
        // 5 fixed arguments + 30 pairs = 65 > 64 (Op::writes is 64 bits).
        std::string many = "surface s() { float x = 0; gather(\"\", P, N, 1, 4";
        for (int i = 0; i < 30; ++i) many += ", \"ray:length\", x";
        many += ") Ci = x; }";
        ds = compile_errors(many);
        EXPECT_TRUE(has_error(ds, "too many arguments to gather"));
    }
    // occlusion()/indirectdiffuse() outputs must be variables.
    ds = compile_errors(
        "surface s() { Ci = occlusion(P, N, 16, \"environmentcolor\", color 1); }");
    EXPECT_TRUE(has_error(ds, "is an output: it must be a variable"));
    ds = compile_errors(
        "surface s() { Ci = indirectdiffuse(P, N, 16, \"occlusion\", 0.5); }");
    EXPECT_TRUE(has_error(ds, "is an output: it must be a variable"));
    ds = compile_errors("surface s(float k) { }");
    EXPECT_TRUE(has_error(ds, "needs a default value"));
    ds = compile_errors("light l() { illuminance(P) { } }");
    EXPECT_TRUE(
        has_error(ds, "illuminance is only allowed in surface and volume shaders"));
    ds = compile_errors("surface s() { illuminate(P) { } }");
    EXPECT_TRUE(has_error(ds, "only allowed in light shaders"));
    ds = compile_errors("surface s() { float x; float x; }");
    EXPECT_TRUE(has_error(ds, "already declared"));
    ds = compile_errors("surface s() { float a[2] = {1, 2, 3}; }");
    EXPECT_TRUE(has_error(ds, "2 elements but 3 values"));
    ds = compile_errors("surface s() { string x = \"a\"; float y = x < 1; }");
    EXPECT_FALSE(ds.empty());
    ds = compile_errors("surface s() { Ci = \"abc\n; }");
    EXPECT_TRUE(has_error(ds, "unterminated string"));
}

TEST(RslErrors, DeepNestingIsAnError) {
    std::string deep = "surface s() { Ci = ";
    for (int i = 0; i < 2000; ++i) deep += "(";
    deep += "1";
    for (int i = 0; i < 2000; ++i) deep += ")";
    deep += "; }";
    auto ds = compile_errors(deep);
    EXPECT_TRUE(has_error(ds, "nesting too deep"));
    std::string chain = "surface s() { Ci = 1";
    for (int i = 0; i < 5000; ++i) chain += "+1";
    chain += "; }";
    ds = compile_errors(chain);
    EXPECT_TRUE(has_error(ds, "nesting too deep"));
}

} // namespace

namespace {

TEST(RslErrors, InliningIsBounded) {
    // 100 functions each calling the previous one: too deep to inline.
    std::string deep = "float f0(float x) { return x; }\n";
    for (int i = 1; i < 100; ++i)
        deep += "float f" + std::to_string(i) + "(float x) { return f" +
                std::to_string(i - 1) + "(x); }\n";
    deep += "surface s() { Ci = f99(1); }\n";
    auto ds = sss::test::compile_errors(deep);
    EXPECT_TRUE(sss::test::has_error(ds, "nested more than 64 deep"));
    // Each calling the previous twice: 2^30 ops, stopped by the size limit.
    std::string wide = "float g0(float x) { return x + 1; }\n";
    for (int i = 1; i < 31; ++i)
        wide += "float g" + std::to_string(i) + "(float x) { return g" +
                std::to_string(i - 1) + "(x) + g" + std::to_string(i - 1) + "(x); }\n";
    wide += "surface s() { Ci = g30(u); }\n";
    ds = sss::test::compile_errors(wide);
    EXPECT_TRUE(sss::test::has_error(ds, "shader too large"));
}

} // namespace

namespace {

TEST(RslCompiler, CompileTextRunsThePreprocessor) {
    sss::PreprocessOptions options;
    options.defines.emplace_back("KD", "0.25");
    const sss::CompileResult r = sss::compile_text(
        "#define HALF(x) ((x) / 2)\n/* comment */\nsurface s(float Kd = KD) {\n"
        "#ifdef KD\n  Ci = HALF(Kd);\n#endif\n}\n",
        "m.sl", options);
    ASSERT_EQ(r.shaders.size(), 1u);
    const sss::Program& p = r.shaders[0];
    EXPECT_EQ(p.symbols[p.find("Kd")].numbers, std::vector<float>{0.25f});
    EXPECT_EQ(p.files.at(0), "m.sl");
    ASSERT_FALSE(p.ops.empty());
    EXPECT_EQ(p.ops.back().where.line, 5);
    try {
        sss::compile_text("surface s() {\n#line 40 \"other.sl\"\n  Ci = nope;\n}\n",
                          "m.sl");
        ADD_FAILURE() << "compiled";
    } catch (const sss::ShaderCompileError& e) {
        ASSERT_FALSE(e.diagnostics().empty());
        EXPECT_EQ(e.diagnostics()[0].file, "other.sl");
        EXPECT_EQ(e.diagnostics()[0].line, 40);
        EXPECT_EQ(e.diagnostics()[0].column, 8);
        EXPECT_EQ(std::string(e.what()), "other.sl:40:8: error: unknown variable 'nope'");
    }
}

} // namespace

TEST(RslCompile, GatherInLightAndDisplacementShadersAndItsVaryingOutputs) {
    for (const char* src :
         {"light l(output varying float n = 0) { gather(\"\", Ps, vector(0, 0, 1), 1, 4) "
          "n += 1; }",
          "displacement d() { float len = 0; gather(\"\", P, N, 1, 4, \"ray:length\", "
          "len) "
          "P += N * len; }"}) {
        SCOPED_TRACE(src);
        const sss::Program p = sss::test::compile_one(src);
        bool found = false;
        for (const sss::Op& op : p.ops)
            if (op.name == "gather") {
                found = true;
                for (std::size_t k = 0; k < op.args.size(); ++k)
                    if ((op.writes >> k) & 1u) {
                        EXPECT_TRUE(p.symbols[op.args[k]].varying);
                    }
            }
        EXPECT_TRUE(found);
    }
    // A local assigned inside the body only becomes varying (masked stores).
    const sss::Program p = sss::test::compile_one(
        "surface s() { float k = 0; gather(\"\", P, N, 1, 4) k = 1; Ci = k; }");
    EXPECT_TRUE(p.symbols[p.find("k")].varying);
}

TEST(RslCompile, RayinfoOfTheBatchIsUniformOfTheRayVarying) {
    // "depth", "type", "label" are the batch's: a uniform variable takes them.
    const sss::Program p = sss::test::compile_one(
        "surface s() { uniform float d = 0; float x = rayinfo(\"depth\", d); Ci = d; }");
    EXPECT_FALSE(p.symbols[p.find("d")].varying);
    // "origin", "direction", "length" differ per point.
    const sss::Program q = sss::test::compile_one(
        "surface s() { point o = 0; float x = rayinfo(\"origin\", o); Ci = xcomp(o); }");
    EXPECT_TRUE(q.symbols[q.find("o")].varying);
    auto ds = sss::test::compile_errors(
        "surface s() { uniform float l = 0; float x = rayinfo(\"length\", l); Ci = l; }");
    EXPECT_TRUE(sss::test::has_error(ds, "varying value to uniform"));
}

// What PRMan's compiler accepts from old shader libraries.
TEST(RslCompiler, PrmanLenienceOfOldLibraries) {
    // A storage class on a function's result; a uniform result stays uniform
    // inside illuminance (a varying loop).
    const CompileResult r = sss::test::compile_raw(R"(
uniform float next(uniform float x) { return x + 1; }
surface s(float seed = 3;) {
    uniform float count = 0;
    varying color light = 0;
    illuminance(P) {
        uniform float once = next(seed);
        extern vector L;
        count += once;
        light += Cl * normalize(L).N;
    }
    Ci = light * count;
}
)");
    ASSERT_EQ(r.shaders.size(), 1u);
    EXPECT_FALSE(sym(r.shaders[0], "count").varying);
    // extern L where L does not exist (the function's top), used where it
    // does; lightsource() filling a uniform variable; Ps in a surface shader
    // is P, with a warning.
    const CompileResult q = sss::test::compile_raw(R"(
color rim(normal Nn) {
    extern vector L;
    extern color Cl;
    color c = 0;
    uniform float flag = 0;
    illuminance(P, Nn, PI / 2) {
        if (lightsource("__rim", flag) == 0) flag = 0;
        c += flag * Cl * max(0, normalize(L).Nn);
    }
    return c;
}
surface s() { Ci = rim(normalize(N)) + color(length(Ps - P)); }
)");
    ASSERT_EQ(q.shaders.size(), 1u);
    ASSERT_EQ(q.warnings.size(), 1u);
    EXPECT_NE(q.warnings[0].message.find("'Ps' is a light shader variable"),
              std::string::npos);
    // Empty declarations in a parameter list, as macros of AOV lists leave.
    EXPECT_EQ(
        sss::test::compile_raw("surface s(; float a = 1;; float b = 2;;) { Ci = a + b; }")
            .shaders.size(),
        1u);
    // extern L used outside illuminance is still an error, where it is used.
    EXPECT_TRUE(has_error(compile_errors(R"(
surface s() {
    extern vector L;
    Ci = color(length(L));
}
)"),
                          "'L' exists only inside an illuminance statement"));
}

namespace {

using namespace sss;
using sss::test::compile_errors;
using sss::test::compile_one;
using sss::test::count_ops;
using sss::test::has_error;

// Volume shaders (RISpec 12.4): P, I, E, ncomps, time, dtime readable, Ci and
// Oi read and written, and lights through illuminance (L, Cl, Ol inside).
TEST(RslShaderTypes, VolumeGlobalsAndIlluminance) {
    const Program p = compile_one(R"(
volume murk(float density = 0.5; color tint = 1;)
{
    float d = length(I) + length(E) + time + dtime + ncomps + xcomp(P);
    color lit = 0;
    illuminance(P) {
        lit += Cl * (1 - Ol) * length(L);
    }
    Ci = mix(Ci, tint * lit, 1 - exp(-density * d));
    Oi = Oi * 0.5;
}
)");
    EXPECT_EQ(p.kind, ShaderKind::Volume);
    EXPECT_STREQ(shader_kind_name(p.kind), "volume");
    EXPECT_EQ(count_ops(p, "illuminance"), 1);
    for (const char* g :
         {"P", "I", "E", "Ci", "Oi", "time", "dtime", "ncomps", "L", "Cl", "Ol"}) {
        const int i = p.find(g);
        ASSERT_GE(i, 0) << g;
        EXPECT_EQ(p.symbols[i].kind, SymbolKind::Global) << g;
    }
    EXPECT_EQ(p.symbols[p.find("Ci")].type.type, ShadingType::Color);
    EXPECT_EQ(p.symbols[p.find("I")].type.type, ShadingType::Vector);
}

TEST(RslShaderTypes, VolumeErrors) {
    auto ds = compile_errors("volume v() { Ci = Cs; }");
    EXPECT_TRUE(has_error(ds, "'Cs' is not available in a volume shader"));
    ds = compile_errors("volume v() { Ci = N; }");
    EXPECT_TRUE(has_error(ds, "'N' is not available in a volume shader"));
    ds = compile_errors("volume v() { float x = s; }");
    EXPECT_TRUE(has_error(ds, "'s' is not available in a volume shader"));
    ds = compile_errors("volume v() { P = 0; }");
    EXPECT_TRUE(has_error(ds, "cannot assign to global variable 'P'"));
    ds = compile_errors("volume v() { I = 0; }");
    EXPECT_TRUE(has_error(ds, "cannot assign to global variable 'I'"));
    ds = compile_errors("volume v() { Ci = Cl; }");
    EXPECT_TRUE(has_error(ds, "'Cl' exists only inside an illuminance"));
    ds = compile_errors("volume v() { illuminance(P) { Cl = 1; } }");
    EXPECT_TRUE(has_error(ds, "cannot assign to global variable 'Cl'"));
    ds = compile_errors("volume v() { float a = alpha; }");
    EXPECT_TRUE(has_error(ds, "'alpha' is not available in a volume shader"));
    ds = compile_errors("volume v() { illuminate(P) { Cl = 1; } }");
    EXPECT_TRUE(has_error(ds, "illuminate is only allowed in light shaders"));
}

// Imager shaders (RISpec 12.5): Ci, Oi and alpha read and written, P (the
// pixel's raster position), ncomps, time, dtime readable; no lights.
TEST(RslShaderTypes, ImagerGlobals) {
    const Program p = compile_one(R"(
imager vignette(float strength = 0.5; float xres = 640, yres = 480;)
{
    float dx = xcomp(P) / xres - 0.5, dy = ycomp(P) / yres - 0.5;
    float fall = 1 - strength * (dx * dx + dy * dy) + 0 * (zcomp(P) + time + dtime + ncomps);
    Ci *= fall;
    Oi = alpha;
    alpha = clamp(alpha, 0, 1);
}
)");
    EXPECT_EQ(p.kind, ShaderKind::Imager);
    EXPECT_STREQ(shader_kind_name(p.kind), "imager");
    const int a = p.find("alpha");
    ASSERT_GE(a, 0);
    EXPECT_EQ(p.symbols[a].kind, SymbolKind::Global);
    EXPECT_EQ(p.symbols[a].type.type, ShadingType::Float);
    EXPECT_TRUE(p.symbols[a].varying);
    const int pp = p.find("P");
    ASSERT_GE(pp, 0);
    EXPECT_EQ(p.symbols[pp].type.type, ShadingType::Point);
}

TEST(RslShaderTypes, ImagerErrors) {
    auto ds = compile_errors("imager i() { Ci = Cs; }");
    EXPECT_TRUE(has_error(ds, "'Cs' is not available in an imager shader"));
    ds = compile_errors("imager i() { Ci = N; }");
    EXPECT_TRUE(has_error(ds, "'N' is not available"));
    ds = compile_errors("imager i() { vector v = I; }");
    EXPECT_TRUE(has_error(ds, "'I' is not available"));
    ds = compile_errors("imager i() { P = 0; }");
    EXPECT_TRUE(has_error(ds, "cannot assign to global variable 'P'"));
    ds = compile_errors("imager i() { illuminance(P) { Ci += Cl; } }");
    EXPECT_TRUE(
        has_error(ds, "illuminance is only allowed in surface and volume shaders"));
    ds = compile_errors("surface s() { alpha = 1; }");
    EXPECT_TRUE(has_error(ds, "'alpha' is not available in a surface shader"));
    // A local named alpha is still a local elsewhere.
    const Program s = compile_one("surface s() { float alpha = 0.5; Ci = alpha; }");
    EXPECT_EQ(s.symbols[s.find("alpha")].kind, SymbolKind::Local);
}

TEST(RslShaderTypes, TransformationShadersAreRefusedClearly) {
    const auto ds = compile_errors("transformation t() { P = P; }");
    ASSERT_FALSE(ds.empty());
    EXPECT_TRUE(has_error(ds, "transformation shaders are not supported (PRMan does not "
                              "run them either)"));
    EXPECT_EQ(ds[0].line, 1);
    EXPECT_EQ(ds[0].column, 1);
}

} // namespace
