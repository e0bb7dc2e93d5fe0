// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file arrays_test.cpp
/// The compiler's PRMan 13.5+ additions: fixed-length array parameters of
/// functions (`float mx[16]`), resizable arrays (`float a[]`, arraylength,
/// resize, push, pop, reserve) and illuminance's "name", value options.
/// What the compiled programs compute is checked in
/// tests/shading/engine_arrays_test.cpp and engine_messages_test.cpp.

#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "rsl_test_util.h"

namespace {

using namespace sss;
using sss::test::all_messages;
using sss::test::compile_errors;
using sss::test::compile_one;
using sss::test::compile_raw;
using sss::test::count_ops;
using sss::test::find_op;
using sss::test::has_error;

const Diagnostic* first_error(const std::vector<Diagnostic>& ds) {
    for (const Diagnostic& d : ds)
        if (d.severity == Diagnostic::Severity::Error) return &d;
    return nullptr;
}

TEST(RslCompilerArrays, FixedLengthParameterTakesItsLength) {
    const Program p = compile_one(R"(
matrix array_to_mx(float mx[16]) {
    return matrix (mx[0], mx[1], mx[2], mx[3], mx[4], mx[5], mx[6], mx[7],
                   mx[8], mx[9], mx[10], mx[11], mx[12], mx[13], mx[14], mx[15]);
}
surface s() {
    float m[16] = {1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1};
    matrix x = array_to_mx(m);
    Ci = comp(x, 0, 0);
}
)");
    // Inlined: the parameter is the caller's array, read 16 times.
    EXPECT_EQ(count_ops(p, "aref"), 16);
}

TEST(RslCompilerArrays, FixedLengthParameterRefusesAnotherLength) {
    const auto ds = compile_errors("float first(float v[3]) { return v[0]; }\n"
                                   "surface s() {\n"
                                   "    float a[4] = {1, 2, 3, 4};\n"
                                   "    Ci = first(a);\n"
                                   "}\n");
    const Diagnostic* d = first_error(ds);
    ASSERT_NE(d, nullptr);
    EXPECT_EQ(d->message,
              "argument 1 of 'first' is float[4] but parameter 'v' is float[3]")
        << all_messages(ds);
    EXPECT_EQ(d->file, "test.sl");
    EXPECT_EQ(d->line, 4);
    EXPECT_EQ(d->column, 10);
}

TEST(RslCompilerArrays, FixedLengthParameterRefusesAResizableArray) {
    const auto ds = compile_errors("float first(float v[3]) { return v[0]; }\n"
                                   "surface s() {\n"
                                   "    float a[] = {1, 2, 3};\n"
                                   "    Ci = first(a);\n"
                                   "}\n");
    EXPECT_TRUE(has_error(ds, "is float[] (resizable) but parameter 'v' is float[3]"))
        << all_messages(ds);
}

TEST(RslCompilerArrays, OverloadsByArrayLength) {
    const Program p = compile_one(R"(
float pick(float v[2]) { return 2; }
float pick(float v[3]) { return 3; }
surface s() {
    float a[3] = {1, 2, 3};
    Ci = pick(a);
}
)");
    // The 3-element overload: its result is the constant 3.
    bool three = false;
    for (const Op& op : p.ops)
        if (op.name == "assign" && p.symbols[op.args[1]].kind == SymbolKind::Const &&
            p.symbols[op.args[1]].numbers == std::vector<float>{3.0f})
            three = true;
    EXPECT_TRUE(three);
}

TEST(RslCompilerArrays, FixedLengthParameterLengthIsChecked) {
    auto ds = compile_errors("float f(float v[0]) { return 1; }\nsurface s() {}\n");
    EXPECT_TRUE(
        has_error(ds, "the array length must be a whole number from 1 to 1000000"))
        << all_messages(ds);
}

TEST(RslCompilerArrays, ResizableLocalsAndTheirFunctions) {
    const Program p = compile_one(R"(
surface s() {
    float a[];
    color c[] = {1, color(0, 1, 0)};
    reserve(a, 8);
    push(a, 1);
    push(a, u);
    resize(a, 4);
    float last = pop(a);
    Ci = arraylength(a) + last + arraylength(c) + comp(c[1], 1);
}
)");
    const int a = p.find("a");
    ASSERT_GE(a, 0);
    EXPECT_EQ(p.symbols[a].type, (TypeSpec{ShadingType::Float, kResizableArray}));
    EXPECT_TRUE(p.symbols[a].varying); // push(a, u)
    const int c = p.find("c");
    ASSERT_GE(c, 0);
    EXPECT_FALSE(p.symbols[c].varying);
    EXPECT_EQ(count_ops(p, "resize"), 3); // the two declarations and resize()
    EXPECT_EQ(count_ops(p, "reserve"), 1);
    EXPECT_EQ(count_ops(p, "push"), 2);
    EXPECT_EQ(count_ops(p, "arraylength"), 2);
    const Op* pop = find_op(p, "pop");
    ASSERT_NE(pop, nullptr);
    EXPECT_EQ(pop->writes, 3u);
    EXPECT_EQ(pop->args[1], a);
}

TEST(RslCompilerArrays, ArraylengthOfAFixedArrayIsAConstant) {
    const Program p = compile_one(R"(
float count(float v[]) { return arraylength(v); }
surface s() {
    float a[5];
    Ci = count(a) + arraylength(a);
}
)");
    EXPECT_EQ(count_ops(p, "arraylength"), 0);
}

TEST(RslCompilerArrays, OutputArrayParametersTakeResizableArrays) {
    const Program p = compile_one(R"(
void add_two(output float v[]; float x) { push(v, x); push(v, x + 1); }
surface s() {
    float a[];
    add_two(a, 1);
    Ci = arraylength(a);
}
)");
    const int a = p.find("a");
    ASSERT_GE(a, 0);
    int pushes_into_a = 0;
    for (const Op& op : p.ops) pushes_into_a += op.name == "push" && op.args[0] == a;
    EXPECT_EQ(pushes_into_a, 2);
}

TEST(RslCompilerArrays, ResizableArrayMistakes) {
    struct Case {
        const char* body;
        const char* message;
    };
    const Case cases[] = {
        {"float a[3]; push(a, 1);", "push: 'a' has the fixed length 3"},
        {"float a[]; resize(a, u);", "resize: the length must be uniform"},
        {"float x = 1; Ci = arraylength(x);", "must be an array, not a float"},
        {"float a[]; push(a);", "push takes (array, value)"},
        {"float a[]; push(a, color 1);", "cannot convert color to float"},
        {"float a[] = 3;", "an array is initialised with {...}"},
        {"float a[]; a = 1;", "cannot assign a whole array"},
        {"float a[]; float y; textureinfo(\"x.tx\", \"resolution\", a);",
         "no version of 'textureinfo'"},
    };
    for (const Case& c : cases) {
        const auto ds =
            compile_errors(std::string("surface s() {\n    ") + c.body + "\n}\n");
        EXPECT_TRUE(has_error(ds, c.message)) << c.body << "\n" << all_messages(ds);
        const Diagnostic* d = first_error(ds);
        ASSERT_NE(d, nullptr) << c.body;
        EXPECT_EQ(d->line, 2) << c.body;
    }
}

TEST(RslCompilerArrays, ReadOnlyArrayParameterCannotGrow) {
    const auto ds = compile_errors("void f(float v[]) { push(v, 1); }\n"
                                   "surface s() { float a[]; f(a); }\n");
    EXPECT_TRUE(has_error(ds, "cannot assign to function parameter 'v'"))
        << all_messages(ds);
}

TEST(RslCompilerArrays, ShaderParametersStillNeedALength) {
    const auto ds = compile_errors("surface s(float a[] = {1};) {}\n");
    EXPECT_TRUE(has_error(ds, "expected the array length")) << all_messages(ds);
}

TEST(RslCompilerArrays, IlluminanceOptions) {
    CompileResult r = compile_raw(R"(surface s(output varying float got = 0;) {
    float k = 0;
    illuminance("key", P, N, PI / 2, "lightcache", "refresh", "light:intensity", k,
                "send:light:scale", 2, "nosuch", 1) {
        got += k;
    }
    illuminance(P, "lightcache", "reuse") { Ci += Cl; }
}
)");
    ASSERT_EQ(r.shaders.size(), 1u);
    const Program& p = r.shaders[0];
    const Op* op = find_op(p, "illuminance");
    ASSERT_NE(op, nullptr);
    // cat P axis angle + lightcache, light:intensity, send:light:scale (nosuch dropped).
    ASSERT_EQ(op->args.size(), 10u);
    EXPECT_EQ(p.symbols[op->args[4]].strings, std::vector<std::string>{"lightcache"});
    EXPECT_EQ(p.symbols[op->args[6]].strings,
              std::vector<std::string>{"light:intensity"});
    EXPECT_EQ(op->args[7], p.find("k"));
    EXPECT_EQ(op->writes, uint64_t(1) << 7);
    EXPECT_TRUE(p.symbols[p.find("k")].varying);
    // The unknown option: a warning naming it, where it is.
    ASSERT_EQ(r.warnings.size(), 1u);
    EXPECT_NE(r.warnings[0].message.find("\"nosuch\" is not supported; ignored"),
              std::string::npos);
    EXPECT_EQ(r.warnings[0].line, 4);
}

TEST(RslCompilerArrays, IlluminanceOptionMistakes) {
    struct Case {
        const char* stmt;
        const char* message;
    };
    const Case cases[] = {
        {"illuminance(P, \"light:intensity\") {}", "come in pairs"},
        {"illuminance(P, \"light:intensity\", 1) {}", "must be a variable"},
        {"illuminance(P, \"light:intensity\", Ng) {}", "cannot assign to global"},
        {"illuminance(P, \"lightcache\", 1) {}", "takes a string"},
        {"illuminance(P, N, PI, 1, 2) {}", "illuminance takes"},
        {"string o = \"lightcache\"; illuminance(P, \"lightcache\", \"reuse\", o, 1) {}",
         "option names must be string literals"},
    };
    for (const Case& c : cases) {
        const auto ds =
            compile_errors(std::string("surface s() {\n    ") + c.stmt + "\n}\n");
        EXPECT_TRUE(has_error(ds, c.message)) << c.stmt << "\n" << all_messages(ds);
    }
}

TEST(RslCompilerArrays, SloRoundTrip) {
    const Program p = compile_one(R"(surface s(output varying float got = 0;) {
    float a[] = {1, 2};
    push(a, 3);
    float k = 0;
    illuminance(P, "light:intensity", k) { got += k; }
    Ci = pop(a) + arraylength(a) + k;
}
)");
    std::stringstream text;
    write_program(p, text);
    const Program back = read_program(text, "s.slo");
    ASSERT_EQ(back.symbols.size(), p.symbols.size());
    EXPECT_EQ(back.symbols[back.find("a")].type, p.symbols[p.find("a")].type);
    ASSERT_EQ(back.ops.size(), p.ops.size());
    for (std::size_t i = 0; i < p.ops.size(); ++i) {
        EXPECT_EQ(back.ops[i].name, p.ops[i].name);
        EXPECT_EQ(back.ops[i].writes, p.ops[i].writes);
    }
}

} // namespace
