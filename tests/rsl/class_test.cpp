// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file class_test.cpp
/// RSL 2.0 shader classes in the compiler (codegen_class.cpp,
/// codegen_coshader.cpp): the kind a class runs as, its methods and
/// pipelines, member variables, the parameters of pipeline methods bound to
/// globals, co-shader handles and method calls, and the errors.

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "rsl_test_util.h"
#include "sss/rsl/slo_info.h"

namespace {

using namespace sss;
using sss::test::compile_errors;
using sss::test::compile_one;
using sss::test::compile_raw;
using sss::test::count_ops;
using sss::test::has_error;

std::vector<std::string> method_names(const Program& p, const Pipeline* pl) {
    std::vector<std::string> out;
    if (pl)
        for (int m : pl->methods) out.push_back(p.methods[std::size_t(m)].name);
    return out;
}

const char* kStaged = R"(
class staged(float Kd = 1; color tint = 1; output varying color extra = 0;)
{
    varying color m_base;
    uniform float m_calls = 0;
    constant float m_once;
    float scale(float x) { return x * Kd; }
    public void construct() { m_once = 2; }
    public void begin() { m_calls += 1; }
    public void opacity(output color Oi) { Oi = Os; }
    public void prelighting(output color Ci, Oi) { m_base = tint * Cs; }
    public void lighting(output color Ci, Oi) {
        normal Nf = faceforward(normalize(N), I);
        Ci = m_base * scale(1) * diffuse(Nf);
    }
    public void postlighting(output color Ci, Oi) { Ci *= Oi; extra = m_base; }
    public float calls() { return m_calls; }
}
)";

TEST(RslClass, StagedSurfaceClass) {
    const Program p = compile_one(kStaged);
    EXPECT_EQ(p.name, "staged");
    EXPECT_EQ(p.kind, ShaderKind::Surface);
    EXPECT_TRUE(p.is_class());
    EXPECT_FALSE(p.runs_as(ShaderKind::Displacement));
    // The class parameters are the shader's.
    const std::vector<int> params = p.parameters();
    ASSERT_EQ(params.size(), 3u);
    EXPECT_EQ(p.symbols[params[0]].name, "Kd");
    EXPECT_EQ(p.symbols[params[2]].kind, SymbolKind::OutputParam);
    // Public methods, not the private helper (inlined where it is called).
    EXPECT_EQ(p.find_method("scale"), -1);
    EXPECT_GE(p.find_method("calls"), 0);
    EXPECT_EQ(p.methods.size(), 7u);
    EXPECT_EQ(method_names(p, p.pipeline(ShaderKind::Surface)),
              (std::vector<std::string>{"construct", "begin", "opacity", "prelighting",
                                        "lighting", "postlighting"}));
    // Member variables are symbols of the program; constant is uniform.
    const int base = p.find("m_base");
    ASSERT_GE(base, 0);
    EXPECT_TRUE(p.symbols[base].varying);
    EXPECT_FALSE(p.symbols[p.find("m_once")].varying);
    EXPECT_FALSE(p.symbols[p.find("m_calls")].varying);
    // A pipeline method's parameters are the globals they name.
    const Method& lighting = p.methods[std::size_t(p.find_method("lighting"))];
    ASSERT_EQ(lighting.params.size(), 2u);
    EXPECT_EQ(p.symbols[lighting.params[0]].name, "Ci");
    EXPECT_EQ(p.symbols[lighting.params[0]].kind, SymbolKind::Global);
    EXPECT_EQ(lighting.outputs, 3u);
    // Each method is a block among the ops, after the member initialisers.
    for (const Method& m : p.methods) {
        EXPECT_GE(m.begin, p.init_end) << m.name;
        EXPECT_EQ(p.ops[m.begin].name, "block") << m.name;
        EXPECT_EQ(p.ops[m.begin].jump[0], m.end) << m.name;
    }
    const Method& calls = p.methods[std::size_t(p.find_method("calls"))];
    ASSERT_GE(calls.result, 0);
    EXPECT_EQ(p.symbols[calls.result].type.type, ShadingType::Float);
}

TEST(RslClass, SurfaceMethodAloneAndKinds) {
    const Program s = compile_one(R"(
class plain(float Kd = 1;) {
    public void surface(output color Ci, Oi) { Oi = Os; Ci = Oi * Cs * Kd; }
}
)");
    EXPECT_EQ(s.kind, ShaderKind::Surface);
    EXPECT_EQ(method_names(s, s.pipeline(ShaderKind::Surface)),
              std::vector<std::string>{"surface"});

    // Displacement and surface: one shader that runs as either.
    const Program d = compile_one(R"(
class bumpy(float Km = 0.1;) {
    public void displacement(output point P; output normal N) {
        P += Km * normalize(N);
        N = calculatenormal(P);
    }
    public void surface(output color Ci, Oi) { Ci = Cs; }
}
)");
    EXPECT_EQ(d.kind, ShaderKind::Surface);
    EXPECT_TRUE(d.runs_as(ShaderKind::Displacement));
    EXPECT_TRUE(d.runs_as(ShaderKind::Surface));
    EXPECT_EQ(method_names(d, d.pipeline(ShaderKind::Displacement)),
              std::vector<std::string>{"displacement"});

    const Program donly = compile_one(R"(
class dent(float Km = 0.1;) {
    public void displacement(output point P; output normal N) { P -= Km * N; }
}
)");
    EXPECT_EQ(donly.kind, ShaderKind::Displacement);

    const Program l = compile_one(R"(
class lamp(float intensity = 1; point from = point "shader" (0, 0, 0);) {
    public void light(output vector L; output color Cl) {
        illuminate(from) { Cl = intensity / (L . L); }
    }
}
)");
    EXPECT_EQ(l.kind, ShaderKind::Light);
    EXPECT_EQ(method_names(l, l.pipeline(ShaderKind::Light)),
              std::vector<std::string>{"light"});

    const Program v = compile_one(R"(
class haze(color tint = 1;) {
    public void volume(output color Ci, Oi) { Ci = mix(Ci, tint, 0.5); }
}
)");
    EXPECT_EQ(v.kind, ShaderKind::Volume);

    // No pipeline method: a co-shader, bound with `Shader` only.
    const Program c = compile_one(R"(
class layer(color tint = 1;) {
    public color value(float x) { return tint * x; }
}
)");
    EXPECT_EQ(c.kind, ShaderKind::Shader);
    EXPECT_FALSE(c.runs_as(ShaderKind::Surface));
    EXPECT_STREQ(shader_kind_name(c.kind), "shader");
}

TEST(RslClass, MethodsSeeMembersParametersAndEachOther) {
    const Program p = compile_one(R"(
float outside(float x) { return x + 1; }
class c(float k = 2;) {
    float m_x = 3;
    float twice(float x) { return 2 * x * k; }
    public float both() { return twice(m_x) + outside(m_x); }
    public void surface(output color Ci, Oi) { Ci = both(); }
}
)");
    // both() is emitted on its own (a block, with twice() and outside()
    // inlined: 3) and inlined into surface() (4 with surface's own).
    EXPECT_GE(p.find_method("both"), 0);
    EXPECT_EQ(count_ops(p, "block"), 3 + 4);
}

TEST(RslClass, StagedMethodsWinOverSurfaceWithAWarning) {
    const CompileResult r = compile_raw(R"(
class both() {
    public void surface(output color Ci, Oi) { Ci = 1; }
    public void lighting(output color Ci, Oi) { Ci = 2; }
}
)");
    ASSERT_EQ(r.shaders.size(), 1u);
    const Program& p = r.shaders[0];
    EXPECT_EQ(method_names(p, p.pipeline(ShaderKind::Surface)),
              std::vector<std::string>{"lighting"});
    ASSERT_EQ(r.warnings.size(), 1u);
    EXPECT_NE(r.warnings[0].message.find("not surface()"), std::string::npos);
}

TEST(RslClass, Errors) {
    EXPECT_TRUE(has_error(compile_errors(R"(
class x() {
    public void light(output vector L; output color Cl) { Cl = 1; }
    public void surface(output color Ci, Oi) { Ci = 1; }
}
)"),
                          "light shader"));
    // A pipeline method's parameters name globals of the right type.
    EXPECT_TRUE(has_error(compile_errors(R"(
class x() { public void surface(output color C; output color Oi) { C = 1; } }
)"),
                          "must be a global variable"));
    EXPECT_TRUE(has_error(compile_errors(R"(
class x() { public void surface(output float Ci) { Ci = 1; } }
)"),
                          "the global 'Ci' is color"));
    EXPECT_TRUE(has_error(compile_errors(R"(
class x() { public void displacement(output point P; output color Ci) { } }
)"),
                          "'Ci' of the pipeline method 'displacement'"));
    // The displacement method follows a displacement shader's rules.
    EXPECT_TRUE(has_error(compile_errors(R"(
class x() {
    public void displacement(output point P; output normal N) { Ci = 1; }
    public void surface(output color Ci, Oi) { Ci = 1; }
}
)"),
                          "'Ci' is not available in a displacement shader"));
    EXPECT_TRUE(has_error(compile_errors(R"(
class x() { public float m; public void surface(output color Ci, Oi) { } }
)"),
                          "'public' is only for methods"));
    EXPECT_TRUE(has_error(compile_errors(R"(
class x() {
    public float f() { return 1; }
    public float f() { return 2; }
    public void surface(output color Ci, Oi) { }
}
)"),
                          "twice"));
    EXPECT_TRUE(has_error(compile_errors(R"(
class x(shader s = null;) { public void surface(output color Ci, Oi) { } }
)"),
                          "cannot be of type shader"));
    EXPECT_TRUE(has_error(compile_errors(R"(
class x() { public void surface(output color Ci, Oi) { Ci = 1 } }
)"),
                          "expected ';'"));
}

TEST(RslClass, ClassicShadersStillNameVariablesLikeTheNewWords) {
    // class, public, shader, constant and null are not reserved.
    const Program p = compile_one(R"(
surface s(float class = 1; float public = 2;) {
    float shader = class + public;
    float constant = shader, null = 1;
    Ci = shader + constant + null;
}
)");
    EXPECT_EQ(p.kind, ShaderKind::Surface);
    EXPECT_FALSE(p.is_class());
}

TEST(RslClass, CoshaderHandlesAndMethodCalls) {
    const Program p = compile_one(R"(
class main(string layer = "base"; string lightcat = "";) {
    shader m_layer;
    shader m_lights[];
    public void begin() {
        m_layer = getshader(layer);
        m_lights = getlights("category", lightcat);
    }
    public void surface(output color Ci, Oi) {
        shader all[] = getshaders();
        color c = 0;
        if (m_layer != null) c = m_layer->value(u);
        uniform float i, n = arraylength(m_lights);
        for (i = 0; i < n; i += 1) {
            vector L;
            color Cl;
            m_lights[i]->light(L, Cl);
            c += Cl * max(0, normalize(-L) . normalize(N));
        }
        float k = 0;
        if (getvar(m_layer, "gain", k) != 0) c *= k;
        if (hasmethod(m_layer, "touch")) m_layer->touch();
        Ci = c + arraylength(all);
    }
}
)");
    EXPECT_EQ(count_ops(p, "getshader"), 1);
    EXPECT_EQ(count_ops(p, "getlights"), 1);
    EXPECT_EQ(count_ops(p, "getshaders"), 1);
    EXPECT_EQ(count_ops(p, "getvar"), 1);
    EXPECT_EQ(count_ops(p, "hasmethod"), 1);
    EXPECT_EQ(count_ops(p, "callmethod"), 3);
    const int lights = p.find("m_lights");
    ASSERT_GE(lights, 0);
    EXPECT_EQ(p.symbols[lights].type, (TypeSpec{ShadingType::Shader, kResizableArray}));
    for (const Op& op : p.ops) {
        if (op.name != "callmethod") continue;
        // d handle "name" args...: the method name is a constant string.
        ASSERT_GE(op.args.size(), 3u);
        EXPECT_EQ(p.symbols[op.args[1]].type.type, ShadingType::Shader);
        const Symbol& name = p.symbols[op.args[2]];
        ASSERT_EQ(name.strings.size(), 1u);
        if (name.strings[0] == "value") {
            // The result takes the expected type; u (read-only) by value.
            EXPECT_EQ(p.symbols[op.args[0]].type.type, ShadingType::Color);
            EXPECT_EQ(op.writes, 1u);
        } else if (name.strings[0] == "light") {
            // Variables go by reference: the method may write them, so the
            // locals become varying.
            EXPECT_EQ(op.writes, (1u << 3) | (1u << 4));
            EXPECT_TRUE(p.symbols[op.args[3]].varying);
        } else {
            EXPECT_EQ(name.strings[0], "touch");
            EXPECT_EQ(op.writes, 0u); // a statement: the result is dropped
        }
    }
}

TEST(RslClass, CoshaderErrors) {
    EXPECT_TRUE(has_error(compile_errors(R"(
surface x() { float f = 1; Ci = f->value(); }
)"),
                          "'->' calls a method of a shader"));
    EXPECT_TRUE(has_error(compile_errors(R"(
surface x() { shader s = getshader("a"); Ci = s + 1; }
)"),
                          "shader handles only compare"));
    EXPECT_TRUE(has_error(compile_errors(R"(
surface x() { shader s[2] = getlights(); }
)"),
                          "resizable shader[]"));
    EXPECT_TRUE(has_error(compile_errors(R"(
surface x() { shader s = getshader(1); }
)"),
                          "getshader takes (string handle)"));
    EXPECT_TRUE(has_error(compile_errors(R"(
surface x() { shader s = getshader("a"); float v; getvar(s, "k", 2); }
)"),
                          "argument 3 of getvar is an output"));
}

TEST(RslClass, SloRoundTripAndInfo) {
    const Program p = compile_one(kStaged);
    std::ostringstream out;
    write_program(p, out);
    const std::string text = out.str();
    EXPECT_EQ(text.rfind("sss-slo 2\n", 0), 0u); // classes need version 2
    std::istringstream in(text);
    const Program q = read_program(in, "staged.slo");
    EXPECT_EQ(q.init_end, p.init_end);
    ASSERT_EQ(q.methods.size(), p.methods.size());
    for (std::size_t i = 0; i < p.methods.size(); ++i) {
        EXPECT_EQ(q.methods[i].name, p.methods[i].name);
        EXPECT_EQ(q.methods[i].begin, p.methods[i].begin);
        EXPECT_EQ(q.methods[i].end, p.methods[i].end);
        EXPECT_EQ(q.methods[i].result, p.methods[i].result);
        EXPECT_EQ(q.methods[i].params, p.methods[i].params);
        EXPECT_EQ(q.methods[i].outputs, p.methods[i].outputs);
    }
    ASSERT_EQ(q.pipelines.size(), p.pipelines.size());
    EXPECT_EQ(q.pipelines[0].methods, p.pipelines[0].methods);
    std::ostringstream again;
    write_program(q, again);
    EXPECT_EQ(again.str(), text);

    // A method range that is not a block is refused.
    std::string bad = text;
    const std::size_t at = bad.find("method \"opacity\" ");
    ASSERT_NE(at, std::string::npos);
    const std::size_t num = at + std::string("method \"opacity\" ").size();
    const std::size_t sp = bad.find(' ', num);
    bad.replace(num, sp - num, std::to_string(p.init_end > 0 ? p.init_end - 1 : 0));
    std::istringstream bin(bad);
    EXPECT_THROW(read_program(bin, "bad.slo"), ValueError);

    // sloinfo: the class parameters under the kind it runs as.
    const std::string info = describe_shader(p);
    EXPECT_EQ(info.rfind("surface \"staged\"\n", 0), 0u);
    EXPECT_NE(info.find("\"extra\" \"output parameter varying color\""),
              std::string::npos);
    EXPECT_EQ(info.find("m_base"), std::string::npos);
    const std::string json = describe_shader_json(p, "staged.slo");
    EXPECT_NE(json.find("\"methods\": [\"construct\", \"begin\", \"opacity\", "
                        "\"prelighting\", \"lighting\", \"postlighting\", \"calls\"]"),
              std::string::npos)
        << json;

    // Classic shaders keep version 1 and no methods in their JSON.
    const Program classic = compile_one("surface s() { Ci = 1; }");
    std::ostringstream c;
    write_program(classic, c);
    EXPECT_EQ(c.str().rfind("sss-slo 1\n", 0), 0u);
    EXPECT_EQ(describe_shader_json(classic, "s.slo").find("methods"), std::string::npos);
}

} // namespace
