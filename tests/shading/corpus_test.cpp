// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file corpus_test.cpp
/// The RSL acceptance corpus (tests/shading/corpus/*.sl, docs/shading.md
/// "Test corpus"): every construct and built-in of the language, each
/// checked by the shader itself against a value computed by hand or in
/// closed form. Each corpus shader declares `output varying float
/// check_<name>` parameters (corpus.h): 0 passes; anything else (the error,
/// or -1 when the shader never wrote it) fails, and this file reports the
/// file, the check and the first failing point. Some checks need the whole
/// batch (area summed over a sphere): those shaders write `value_<name>`
/// outputs that the C++ test aggregates.
///
/// Also here: the coverage test (every built-in of builtins.cpp is called by
/// some corpus file), the table of shaders that must not compile (message
/// and file:line:column), and run-time failures (division by zero, NaN,
/// array index out of range).
///
/// Suite names start with "RslCorpus".

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "corpus_harness.h"
#include "engine_test_util.h"
#include "sss/rsl/builtins.h"
#include "test_util.h"

namespace {

using namespace sss;
using namespace sss::test;

constexpr double kPi = std::numbers::pi;

/// One float output per point.
std::vector<float> output_of(const ShadingContext& ctx, const std::string& name) {
    TypeSpec type;
    std::vector<float> values;
    EXPECT_TRUE(ctx.output(name, type, values)) << name;
    return values;
}

/// A sphere of radius r as a grid at cell centres (u around z, v pole to
/// pole), with exact N, dPdu, dPdv, s = u, t = v.
ShadingBatch sphere_grid(int nu, int nv, double r) {
    ShadingBatch b;
    b.layout = BatchLayout::Grid;
    b.nu = nu;
    b.nv = nv;
    b.size = static_cast<std::size_t>(nu) * nv;
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const double u = (i + 0.5) / nu, v = (j + 0.5) / nv;
            const double th = 2 * kPi * u, ph = -kPi / 2 + kPi * v;
            const glm::dvec3 n(std::cos(ph) * std::cos(th), std::cos(ph) * std::sin(th),
                               std::sin(ph));
            b.P.push_back(glm::vec3(r * n));
            b.N.push_back(glm::vec3(n));
            b.dPdu.push_back(glm::vec3(2 * kPi * r * std::cos(ph) *
                                       glm::dvec3(-std::sin(th), std::cos(th), 0)));
            b.dPdv.push_back(
                glm::vec3(kPi * r *
                          glm::dvec3(-std::sin(ph) * std::cos(th),
                                     -std::sin(ph) * std::sin(th), std::cos(ph))));
            b.u.push_back(static_cast<float>(u));
            b.v.push_back(static_cast<float>(v));
            b.du.push_back(1.0f / nu);
            b.dv.push_back(1.0f / nv);
        }
    b.Ng = b.N;
    b.s = b.u;
    b.t = b.v;
    b.I = b.P;
    return b;
}

TEST(RslCorpus, OperatorsAndTypes) {
    run_corpus("operators_and_types.sl", plane_grid(8, 4));
}

TEST(RslCorpus, ControlFlow) {
    run_corpus("control_flow.sl", plane_grid(8, 4));
}

TEST(RslCorpus, Functions) {
    run_corpus("functions.sl", plane_grid(8, 2));
}

TEST(RslCorpus, Math) {
    run_corpus("math.sl", plane_grid(8, 2));
}

TEST(RslCorpus, Noise) {
    run_corpus("noise.sl", plane_grid(16, 8));
}

TEST(RslCorpus, Geometry) {
    Engine e;
    e.services.scene_.options.camera.near_clip = 1;
    e.services.scene_.options.camera.far_clip = 11;
    run_corpus("geometry.sl", plane_grid(4, 2), {}, &e);
}

TEST(RslCorpus, Derivatives) {
    run_corpus("derivatives.sl", plane_grid(16, 8), {}, nullptr, {}, "derivatives");
}

TEST(RslCorpus, AreaSummedOverASphereIs4PiR2) {
    Engine e;
    const double r = 1.5;
    ShadingBatch b = sphere_grid(128, 128, r);
    run_corpus("derivatives.sl", b, {}, &e, {}, "sphere_area");
    double total = 0.0;
    for (float a : output_of(e.context, "value_area")) total += a;
    EXPECT_NEAR(total / (4 * kPi * r * r), 1.0, 1e-3);
}

TEST(RslCorpus, CalculatenormalOfADisplacedSphere) {
    Engine e;
    ShadingBatch b = sphere_grid(96, 96, 1.5);
    const std::vector<glm::vec3> before = b.P;
    run_corpus("derivatives.sl", b, {}, &e, {}, "bumpy");
    // The displacement's P and N are written back into the batch.
    EXPECT_NE(b.P[100], before[100]);
    EXPECT_NEAR(glm::length(b.N[100]), 1.0f, 1e-5f);
}

TEST(RslCorpus, Spaces) {
    Engine e;
    Camera& cam = e.services.scene_.options.camera;
    cam.world_to_camera = glm::translate(Matrix4(1.0), glm::dvec3(0, 0, 5));
    cam.perspective = true;
    cam.fov = 90;
    cam.xres = 200;
    cam.yres = 100;
    // Screen-space z is f/(f-n) - f n / ((f-n) z): finite clipping planes
    // keep it well conditioned in float for the round trips.
    cam.near_clip = 0.5;
    cam.far_clip = 100;
    e.services.scene_.coordinate_systems["lamp"] = glm::rotate(
        glm::translate(Matrix4(1.0), glm::dvec3(0, 0, 1)), kPi / 2, glm::dvec3(0, 0, 1));
    Primitive prim;
    prim.object_to_world = glm::scale(glm::translate(Matrix4(1.0), glm::dvec3(0, 3, 0)),
                                      glm::dvec3(2, 1, 1));
    ShadingBatch b = plane_grid(4, 2);
    b.primitive = &prim;
    run_corpus("spaces.sl", b, {}, &e, {}, "",
               glm::translate(Matrix4(1.0), glm::dvec3(1, 0, 0)));
}

TEST(RslCorpus, Color) {
    run_corpus("color.sl", plane_grid(4, 2));
}

TEST(RslCorpus, Matrix) {
    run_corpus("matrix.sl", plane_grid(4, 2));
}

TEST(RslCorpus, Strings) {
    Engine e;
    run_corpus("strings.sl", plane_grid(2, 1), {}, &e);
    // A varying printf prints once per running point.
    EXPECT_EQ(e.services.messages,
              (std::vector<std::string>{"skin 0.25\n", "skin 0.75\n"}));
}

TEST(RslCorpus, Lighting) {
    Engine e;
    const auto shaders = compile_corpus("lighting.sl");
    auto light = [&](const std::string& name, ParamList params) {
        for (auto& p : shaders)
            if (p->name == name) return ShaderInstance(p, params, Matrix4(1.0), name);
        ADD_FAILURE() << "no light " << name;
        return ShaderInstance(std::make_shared<Program>(), {}, Matrix4(1.0), name);
    };
    std::vector<ShaderInstance> lights;
    lights.push_back(light("keylight", [] {
        ParamList p;
        p.set(float_param("intensity", 2));
        return p;
    }()));
    lights.push_back(light("filllight", [] {
        ParamList p;
        p.set(float_param("intensity", 0.5));
        return p;
    }()));
    lights.push_back(light("amblight", [] {
        ParamList p;
        p.set(float_param("intensity", 0.25));
        return p;
    }()));
    lights.push_back(light("spotlight", {}));
    lights.push_back(light("skylight", [] {
        ParamList p;
        p.set(float_param("intensity", 0.1));
        return p;
    }()));
    std::vector<const ShaderInstance*> list;
    for (const ShaderInstance& l : lights) list.push_back(&l);
    run_corpus("lighting.sl", plane_grid(8, 8), {}, &e, list);
    // Nothing warned (trace(), indirectdiffuse() and shadow() no longer do).
    std::string all;
    for (const std::string& w : e.services.warnings) all += w + "\n";
    for (const char* name : {"trace()", "indirectdiffuse()", "shadow"})
        EXPECT_EQ(all.find(name), std::string::npos) << name << " in:\n" << all;
}

TEST(RslCorpus, Queries) {
    Engine e;
    Camera& cam = e.services.scene_.options.camera;
    cam.xres = 320;
    cam.yres = 240;
    cam.near_clip = 0.5;
    cam.far_clip = 100;
    e.services.scene_.options.hider = "raytrace";
    e.services.scene_.options.groups["render"].set(float_param("bucket", 16));
    auto attr = std::make_shared<Attributes>();
    attr->groups["identifier"].set(string_param("name", "ball"));
    attr->groups["user"].set(float_param("k", 4));
    attr->shading_rate = 2;
    attr->color = {1, 0.5, 0.25};
    Primitive prim;
    prim.attributes = attr;
    ShadingBatch b = plane_grid(2, 1);
    b.primitive = &prim;
    run_corpus("queries.sl", b, {}, &e);
}

TEST(RslCorpus, Raytrace) {
    run_corpus("raytrace.sl", plane_grid(4, 2));
}

TEST(RslCorpus, Preprocessor) {
    run_corpus("preprocessor.sl", plane_grid(4, 1));
}

// --- coverage ----------------------------------------------------------------------

/// Built-ins no corpus file needs to call. Empty: the functions this release
/// does not support (trace, indirectdiffuse, surface() in a surface shader,
/// displacement() and atmosphere() message passing, depth-map shadow) are
/// called anyway and their documented result (0, the variable untouched) is
/// checked (lighting.sl, queries.sl). Add a name here only with a comment saying
/// where its documented behaviour is tested instead.
const std::set<std::string> kNotInCorpus = {};

TEST(RslCorpus, EveryBuiltinIsExercised) {
    // Every corpus file, compiled: the ops of its shaders name the built-ins
    // it really calls (a name in a comment or a string does not count).
    std::set<std::string> called;
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(corpus_dir())) {
        if (entry.path().extension() != ".sl") continue;
        ++files;
        for (const auto& prog : compile_corpus(entry.path().filename().string()))
            for (const Op& op : prog->ops) called.insert(op.name);
    }
    EXPECT_GE(files, 16);
    std::set<std::string> missing;
    for (const detail::BuiltinSignature& sig : detail::builtin_signatures())
        if (!called.count(sig.name) && !kNotInCorpus.count(sig.name))
            missing.insert(sig.name);
    std::string list;
    for (const std::string& name : missing) list += " " + name;
    EXPECT_TRUE(missing.empty())
        << "built-ins no file of " << corpus_dir().string() << " calls:" << list;
    for (const std::string& name : kNotInCorpus)
        EXPECT_TRUE(detail::is_builtin(name))
            << name << " in the allow-list is no built-in";
}

// --- bad shaders --------------------------------------------------------------------

/// A shader that must not compile: the first error's message (a part of it)
/// and where it points.
struct BadShader {
    const char* what;
    const char* source;
    const char* message;
    int line, column;
};

const BadShader kBadShaders[] = {
    {"missing semicolon", "surface t() {\n    float x = 1\n    float y = 2;\n}\n",
     "expected ';' after the declaration, got 'float'", 3, 5},
    {"missing brace", "surface t() {\n    if (u > 0) {\n        Ci = 1;\n}\n",
     "missing '}' at the end of the file", 5, 1},
    {"incomplete expression", "surface t() {\n    float x = 1 / ;\n}\n",
     "unexpected ';' in an expression", 2, 19},
    {"unterminated string", "surface t() {\n    string s = \"abc;\n}\n",
     "unterminated string", 2, 16},
    {"triple to float", "surface t() {\n    float x = color(1, 2, 3);\n}\n",
     "cannot convert color to float", 2, 15},
    {"point to colour", "surface t() {\n    color c = point(1, 2, 3);\n}\n",
     "cannot convert point to color (points and colors do not mix)", 2, 15},
    {"colour plus point", "surface t() {\n    Ci = Cs + P;\n}\n",
     "operator '+' cannot combine color and point", 2, 13},
    {"point dot colour", "surface t() {\n    float x = P . Cs;\n}\n",
     "operator '.' cannot combine point and color", 2, 17},
    {"string arithmetic", "surface t() {\n    float x = \"a\" + 1;\n}\n",
     "operator '+' cannot combine string and float", 2, 19},
    {"unknown function", "surface t() {\n    float x = frobnicate(1);\n}\n",
     "unknown function 'frobnicate'", 2, 15},
    {"unknown variable", "surface t() {\n    Ci = nosuchvar;\n}\n",
     "unknown variable 'nosuchvar'", 2, 10},
    {"too many arguments", "surface t() {\n    float x = sin(1, 2);\n}\n",
     "no version of 'sin' takes (float, float)", 2, 15},
    {"too few arguments", "surface t() {\n    float x = sin();\n}\n",
     "no version of 'sin' takes ()", 2, 15},
    {"wrong argument type", "surface t() {\n    float x = sin(\"a\");\n}\n",
     "no version of 'sin' takes (string)", 2, 15},
    {"recursion",
     "float f(float x) {\n    return f(x) + 1;\n}\nsurface t() {\n    Ci = f(u);\n}\n",
     "recursive call of 'f' (RSL functions cannot recurse)", 2, 12},
    {"varying to uniform", "surface t() {\n    uniform float k = u;\n}\n",
     "cannot assign a varying value to uniform 'k'", 2, 23},
    {"read-only parameter", "surface t(float Kd = 1;) {\n    Kd = 2;\n}\n",
     "cannot assign to shader parameter 'Kd': it is read-only", 2, 5},
    {"read-only global", "surface t() {\n    u = 2;\n}\n",
     "cannot assign to global variable 'u': it is read-only in a surface shader", 2, 5},
    {"read-only global as an output argument",
     "surface t() {\n    float kr, kt;\n    fresnel(I, N, 1.5, u, kt);\n}\n",
     "cannot assign to global variable 'u'", 3, 24},
    {"read-only function parameter",
     "float f(float x) {\n    x = 1;\n    return x;\n}\nsurface t() {\n    Ci = "
     "f(u);\n}\n",
     "cannot assign to function parameter 'x'", 2, 5},
    {"constant to an output parameter",
     "void g(output float a) { a = 1; }\nsurface t() {\n    g(3);\n}\n",
     "argument 1 of 'g' must be a variable (the parameter is output)", 3, 7},
    {"L outside illuminance", "surface t() {\n    L = vector(1, 0, 0);\n}\n",
     "'L' exists only inside an illuminance statement", 2, 5},
    {"whole-array assignment",
     "surface t() {\n    float a[2] = {1, 2}, b[2] = {3, 4};\n    a = b;\n}\n",
     "cannot assign a whole array ('a')", 3, 5},
    {"array initialiser size", "surface t() {\n    float a[3] = {1, 2};\n}\n",
     "'a' has 3 elements but 2 values are given", 2, 11},
    {"redeclaration", "surface t() {\n    float x = 1;\n    float x = 2;\n}\n",
     "'x' is already declared in this scope", 3, 11},
    {"break outside a loop", "surface t() {\n    break;\n}\n", "break outside a loop", 2,
     5},
    {"gather output not a variable",
     "surface t() {\n    gather(\"\", P, N, 1, 4, \"surface:Ci\", Ci + 1) { Ci = 1; "
     "}\n}\n",
     "the value of gather output \"surface:Ci\" must be a variable", 2, 45},
    {"gather argument count", "surface t() {\n    gather(\"\", P, N, 1) { Ci = 1; }\n}\n",
     "gather takes (category, P, dir, angle, samples", 2, 5},
    {"gather primitive output",
     "surface t() {\n    color c;\n    gather(\"\", P, N, 1, 4, \"primitive:Cs\", c) Ci "
     "= c;\n}\n",
     "primitive variables of the hit are not supported", 3, 44},
};

TEST(RslCorpusErrors, BadShadersGiveClearMessages) {
    for (const BadShader& bad : kBadShaders) {
        SCOPED_TRACE(bad.what);
        try {
            compile_text(bad.source, "bad.sl");
            ADD_FAILURE() << "compiled:\n" << bad.source;
        } catch (const ShaderCompileError& e) {
            ASSERT_FALSE(e.diagnostics().empty());
            const Diagnostic& d = e.diagnostics()[0];
            EXPECT_EQ(d.severity, Diagnostic::Severity::Error);
            EXPECT_NE(d.message.find(bad.message), std::string::npos) << d.format();
            EXPECT_EQ(d.file, "bad.sl");
            EXPECT_EQ(d.line, bad.line) << d.format();
            EXPECT_EQ(d.column, bad.column) << d.format();
            // what() is the first error on one line, "file:line:column: ...".
            const std::string where = "bad.sl:" + std::to_string(bad.line) + ":" +
                                      std::to_string(bad.column) + ":";
            EXPECT_EQ(std::string(e.what()).rfind(where, 0), 0u) << e.what();
        }
    }
}

TEST(RslCorpusErrors, PreprocessorErrorsNameTheLine) {
    const struct {
        const char* source;
        const char* message;
        int line;
    } cases[] = {
        {"#include \"nosuchheader.h\"\nsurface t() {}\n", "cannot find include file", 1},
        {"\n#error stop here\nsurface t() {}\n", "stop here", 2},
        {"#if 1\nsurface t() {}\n", "unterminated #if", 1},
    };
    for (const auto& c : cases) {
        try {
            compile_text(c.source, "bad.sl", corpus_options());
            ADD_FAILURE() << "compiled:\n" << c.source;
        } catch (const PreprocessError& e) {
            EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos)
                << e.what();
            EXPECT_EQ(e.file(), "bad.sl");
            EXPECT_EQ(e.line(), c.line) << e.what();
        }
    }
}

/// Runs `source` over a 4 x 1 plane grid and returns the ShaderRuntimeError's
/// message ("" when it ran).
std::string runtime_error(const std::string& source) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    ShaderInstance inst(
        std::make_shared<Program>(compile_text(source, "bad.sl").shaders.at(0)), {},
        Matrix4(1.0), "scene.rib:7");
    try {
        e.context.execute(inst, b);
    } catch (const ShaderRuntimeError& err) {
        return err.what();
    }
    return "";
}

TEST(RslCorpusRuntime, ErrorsNameTheRibCallAndTheShaderLine) {
    const struct {
        const char* source;
        const char* message;
        int line;
    } cases[] = {
        {"surface t() {\n    float a[3] = {1, 2, 3};\n    Ci = a[u * 4];\n}\n",
         "array index 3.500000 out of range [0, 3)", 3},
        {"surface t() {\n    float a[3] = {1, 2, 3};\n    Ci = a[-0.5];\n}\n",
         "array index -0.500000 out of range [0, 3)", 3},
        {"surface t() {\n    float a[3] = {1, 2, 3};\n    a[3] = 1;\n}\n",
         "array index 3.000000 out of range [0, 3)", 3},
        {"surface t() {\n    Ci = comp(Cs, 3);\n}\n",
         "component index 3.000000 out of range", 2},
        {"surface t() {\n    matrix m = 1;\n    Ci = comp(m, 4, 0);\n}\n",
         "component index 4.000000 out of range [0, 4)", 3},
        {"surface t() {\n    Ci = color \"nosuchspace\" (1, 2, 3);\n}\n",
         "unknown colour space \"nosuchspace\"", 2},
        {"surface t() {\n    Ci = texture(\"nosuch.tx\");\n}\n", "nosuch.tx", 2},
        {"surface t() {\n    float x;\n    Oi = texture3d(\"nosuch.ptc\", P, N, \"v\", "
         "x);\n}\n",
         "nosuch.ptc", 3},
        {"surface t() {\n    Ci = spline(\"nosuchbasis\", u, 0, 1, 2, 3);\n}\n",
         "unknown basis \"nosuchbasis\"", 2},
        {"surface t() {\n    printf(\"%d %d\\n\", 1);\n}\n", "format \"%d %d", 2},
    };
    for (const auto& c : cases) {
        const std::string what = runtime_error(c.source);
        EXPECT_NE(what.find(c.message), std::string::npos) << c.source << "\n-> " << what;
        // The RIB call, then the shader's file:line.
        const std::string where = "scene.rib:7: bad.sl:" + std::to_string(c.line) + ":";
        EXPECT_EQ(what.rfind(where, 0), 0u) << what;
    }
}

// PRMan is lenient with an unknown coordinate system (the skin shader's
// vtransform("", dir) with an empty default space): it acts as "current",
// with one warning per call naming the RIB call and the shader line.
TEST(RslCorpusRuntime, UnknownSpaceIsCurrentWithOneWarningPerCall) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    const char* source = "surface t(string sp = \"\") {\n"
                         "    vector d = vtransform(sp, vector(1, 2, 3));\n"
                         "    point q = transform(\"nowhere\", point(4, 5, 6));\n"
                         "    Ci = color(xcomp(d), ycomp(d), zcomp(q));\n}\n";
    ShaderInstance inst(
        std::make_shared<Program>(compile_text(source, "lenient.sl").shaders.at(0)), {},
        Matrix4(1.0), "scene.rib:7");
    e.context.execute(inst, b);
    e.context.execute(inst, b);
    ASSERT_EQ(b.Ci.size(), 4u);
    for (const glm::vec3& c : b.Ci) EXPECT_EQ(c, glm::vec3(1.0f, 2.0f, 6.0f));
    std::vector<std::string> spaces;
    for (const std::string& w : e.services.warnings)
        if (w.find("unknown coordinate system") != std::string::npos) spaces.push_back(w);
    ASSERT_EQ(spaces.size(), 2u);
    EXPECT_NE(spaces[0].find("lenient.sl:2"), std::string::npos) << spaces[0];
    EXPECT_NE(spaces[0].find("\"\""), std::string::npos) << spaces[0];
    EXPECT_NE(spaces[1].find("lenient.sl:3"), std::string::npos) << spaces[1];
    EXPECT_NE(spaces[1].find("\"nowhere\""), std::string::npos) << spaces[1];
}

// Documented (engine.h, docs/shading.md): division by zero and NaN are IEEE
// inside a shader; results that are not finite are written as 0 and counted.
TEST(RslCorpusRuntime, DivisionByZeroAndNaNGiveFiniteResults) {
    Engine e;
    ShadingBatch b = plane_grid(4, 1);
    ShaderInstance inst(std::make_shared<Program>(compile_text(R"(
surface t(output varying float inf = 1; output varying float nan = 1;
          output varying color c = 1; output varying float fine = 0;
          output varying float guarded = 0;) {
    inf = 1 / (u - u);
    nan = sqrt(-u) + log(0) * 0;
    c = color(acos(2), 0 / (u - u), pow(0, -1));
    Ci = Cs / 0;
    Oi = 1;
    fine = u;
    /* a shader can test for NaN: it is not equal to itself */
    float x = 0 / (u - u);
    guarded = x != x ? 7 : x;
}
)",
                                                               "bad.sl")
                                                      .shaders.at(0)),
                        {}, Matrix4(1.0), "scene.rib:3");
    e.context.execute(inst, b);
    EXPECT_EQ(e.context.nonfinite_points(), 4u);
    EXPECT_NE(e.context.nonfinite_message().find("4 points"), std::string::npos)
        << e.context.nonfinite_message();
    for (const char* name : {"inf", "nan", "c"})
        for (float v : output_of(e.context, name)) EXPECT_EQ(v, 0.0f) << name;
    const std::vector<float> fine = output_of(e.context, "fine");
    const std::vector<float> guarded = output_of(e.context, "guarded");
    for (int i = 0; i < 4; ++i) {
        EXPECT_EQ(b.Ci[i], glm::vec3(0.0f));
        EXPECT_EQ(b.Oi[i], glm::vec3(1.0f));
        EXPECT_FLOAT_EQ(fine[i], b.u[i]);
        EXPECT_EQ(guarded[i], 7.0f);
    }
}

// --- bugs the corpus found (each fixed in src/sss/shading/) ----------------------

// ShadingContext::output() read the program through a raw pointer: after the
// ShaderInstance (the only owner of its Program) was destroyed it read freed
// memory. The context now keeps the last program alive.
TEST(RslCorpusFixes, OutputsOutliveTheShaderInstance) {
    Engine e;
    ShadingBatch b = plane_grid(3, 1);
    {
        ShaderInstance inst = e.instance(R"(
surface t(output varying float r = 0;) { r = u * 2; }
)");
        e.context.execute(inst, b);
    }
    const std::vector<float> r = output_of(e.context, "r");
    ASSERT_EQ(r.size(), 3u);
    for (int i = 0; i < 3; ++i) EXPECT_FLOAT_EQ(r[i], 2 * b.u[i]);
}

} // namespace
