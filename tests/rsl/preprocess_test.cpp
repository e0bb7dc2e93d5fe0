// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file preprocess_test.cpp
/// The shader preprocessor (sss/rsl/preprocess.h): every directive,
/// macros, #if arithmetic, includes, the line map and error locations.

#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "sss/rsl/preprocess.h"
#include "test_util.h"

namespace sss {
namespace {

PreprocessResult pp(const std::string& text, const PreprocessOptions& options = {}) {
    return preprocess_text(text, "test.sl", options);
}

/// The output lines, trailing spaces removed.
std::vector<std::string> lines_of(const PreprocessResult& r) {
    std::vector<std::string> lines;
    std::string cur;
    for (char c : r.text) {
        if (c == '\n') {
            while (!cur.empty() && cur.back() == ' ') cur.pop_back();
            lines.push_back(cur);
            cur.clear();
        } else {
            cur += c;
        }
    }
    EXPECT_TRUE(cur.empty()) << "the text must end with a newline";
    EXPECT_EQ(lines.size(), r.lines.size());
    return lines;
}

/// The non-empty output lines joined by '|'.
std::string code(const std::string& text, const PreprocessOptions& options = {}) {
    std::string s;
    for (const auto& l : lines_of(pp(text, options))) {
        size_t b = l.find_first_not_of(" \t");
        if (b == std::string::npos) continue;
        if (!s.empty()) s += '|';
        s += l.substr(b);
    }
    return s;
}

/// The error of preprocessing `text`; fails the test if there is none.
PreprocessError error_of(const std::string& text, const PreprocessOptions& options = {}) {
    try {
        pp(text, options);
    } catch (const PreprocessError& e) {
        return e;
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return PreprocessError("", 0, 0, "", "");
}

void write(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
}

TEST(RslPreprocess, PlainTextPassesThroughLineForLine) {
    const std::string src = "surface s()\n{\n\tCi = color(1, 0, 0); /* red */\n}\n";
    const PreprocessResult r = pp(src);
    // A comment within a line becomes as many spaces: columns stay right.
    EXPECT_EQ(r.text,
              "surface s()\n{\n\tCi = color(1, 0, 0);" + std::string(10, ' ') + "\n}\n");
    ASSERT_EQ(r.lines.size(), 4u);
    for (int i = 0; i < 4; ++i) {
        EXPECT_EQ(r.lines[i].file, 0);
        EXPECT_EQ(r.lines[i].line, i + 1);
    }
    ASSERT_EQ(r.files.size(), 1u);
    EXPECT_EQ(r.files[0], "test.sl");
    // No newline at the end of the file, an empty file.
    EXPECT_EQ(pp("a\nb").text, "a\nb\n");
    EXPECT_EQ(pp("").text, "");
}

TEST(RslPreprocess, CommentsKeepTheLineCount) {
    const PreprocessResult r = pp("a /* one\ntwo\nthree */ b // tail\nc // x /* y\nd\n");
    const auto lines = lines_of(r);
    ASSERT_EQ(lines.size(), 5u);
    EXPECT_EQ(lines[0], "a   b");
    EXPECT_EQ(lines[1], "");
    EXPECT_EQ(lines[2], "");
    EXPECT_EQ(lines[3], "c");
    EXPECT_EQ(lines[4], "d");
    EXPECT_EQ(r.lines[3].line, 4);
    EXPECT_EQ(r.lines[4].line, 5);
    // Comment markers inside strings are text; quotes inside comments are not strings.
    EXPECT_EQ(code("s = \"a // b /* c\"; /* \" */ t = 1;"),
              "s = \"a // b /* c\";" + std::string(9, ' ') + "t = 1;");
}

TEST(RslPreprocess, LineSplices) {
    const PreprocessResult r = pp("#define TWO \\\n  2\nx = TWO;\nlong\\\nname\n");
    const auto lines = lines_of(r);
    ASSERT_EQ(lines.size(), 5u);
    EXPECT_EQ(lines[2], "x = 2;");
    EXPECT_EQ(r.lines[2].line, 3);
    EXPECT_EQ(lines[3], "longname");
    EXPECT_EQ(r.lines[4].line, 5);
    // A // comment continues over a splice.
    EXPECT_EQ(code("a // b \\\nc\nd"), "a|d");
}

TEST(RslPreprocess, ObjectAndFunctionMacros) {
    EXPECT_EQ(code("#define KD 0.5\nfloat k = KD;"), "float k = 0.5;");
    EXPECT_EQ(code("#define SQ(x) ((x)*(x))\ny = SQ(a+1);"), "y = ((a+1)*(a+1));");
    EXPECT_EQ(code("#define MIX(a, b, t) mix(a, b, t)\nc = MIX(f(1, 2), (g, h), 0.5);"),
              "c = mix(f(1, 2), (g, h), 0.5);");
    // Nested expansion, in arguments and in the result.
    EXPECT_EQ(code("#define A B\n#define B 3\n#define ID(x) x\nID(ID(A)) A"), "3 3");
    // A function-like name without arguments is left alone.
    EXPECT_EQ(code("#define f(x) x\nfloat f = 1; f;"), "float f = 1; f;");
    // No self-recursion, direct or indirect.
    EXPECT_EQ(code("#define x x + 1\nx"), "x + 1");
    EXPECT_EQ(code("#define a b\n#define b a\na b"), "a b");
    EXPECT_EQ(code("#define f(x) f(x + 1)\nf(f(0))"), "f(f(0 + 1) + 1)");
    // Arguments over several lines: the result stays on the first, the line
    // count is kept.
    const PreprocessResult r = pp("#define ADD(a, b) a + b\nx = ADD(1,\n  2);\ny;\n");
    const auto lines = lines_of(r);
    ASSERT_EQ(lines.size(), 4u);
    EXPECT_EQ(lines[1], "x = 1 + 2;");
    EXPECT_EQ(lines[2], "");
    EXPECT_EQ(lines[3], "y;");
    EXPECT_EQ(r.lines[3].line, 4);
    // The '(' may be on the next line.
    EXPECT_EQ(code("#define F(a) [a]\nF\n(1)"), "[1]");
    // Empty argument lists, empty arguments, variadic macros.
    EXPECT_EQ(code("#define Z() zero\nZ() Z( )"), "zero zero");
    EXPECT_EQ(code("#define P(a, b) <a|b>\nP(,) P(1,)"), "<|> <1|>");
    EXPECT_EQ(code("#define V(f, ...) f(__VA_ARGS__)\nV(g, 1, 2) V(h)"), "g(1, 2) h()");
}

TEST(RslPreprocess, MacrosAreNotExpandedInStrings) {
    EXPECT_EQ(code("#define name other\nprintf(\"name %f\", name);"),
              "printf(\"name %f\", other);");
}

TEST(RslPreprocess, StringizeAndPaste) {
    EXPECT_EQ(code("#define STR(x) #x\nSTR(a  +   b) STR( \"q\\n\" )"),
              "\"a + b\" \"\\\"q\\\\n\\\"\"");
    EXPECT_EQ(code("#define CAT(a, b) a ## b\nCAT(Kd, _tex) CAT(1, 2) CAT(, x) CAT(y, )"),
              "Kd_tex 12 x y");
    // The pasted name is rescanned; arguments of ## are not expanded first.
    EXPECT_EQ(code("#define AB done\n#define A nope\n#define CAT(a, b) a##b\nCAT(A, B)"),
              "done");
    // Stringize through a second level expands the argument.
    EXPECT_EQ(code("#define S(x) #x\n#define XS(x) S(x)\n#define V 42\nS(V) XS(V)"),
              "\"V\" \"42\"");
    // Tokens from macros never merge into other tokens.
    EXPECT_EQ(code("#define NEG -1\nx = -NEG;"), "x = - -1;");
    EXPECT_EQ(code("#define SL /\na SL/ b"), "a / / b");
}

TEST(RslPreprocess, UndefAndPredefined) {
    EXPECT_EQ(code("#define X 1\n#undef X\nX"), "X");
    EXPECT_EQ(code("__SSS__ RSL PI"), "1 1 PI");
    EXPECT_EQ(code("a __LINE__\nb __LINE__ __FILE__"), "a 1|b 2 \"test.sl\"");
}

TEST(RslPreprocess, CommandLineDefines) {
    PreprocessOptions o;
    o.defines = {{"QUALITY", "3"}, {"FAST", "1"}, {"TWICE(x)", "(2*(x))"}, {"RSL", "1"}};
    o.undefines = {"RSL"};
    EXPECT_EQ(code("QUALITY FAST TWICE(q) RSL", o), "3 1 (2*(q)) RSL");
    o.defines = {{"1BAD", "1"}};
    const PreprocessError e = error_of("x", o);
    EXPECT_EQ(e.file(), "<command line>");
    EXPECT_NE(std::string(e.what()).find("macro names must be identifiers"),
              std::string::npos);
}

TEST(RslPreprocess, Conditionals) {
    const std::string src =
        "#define A 2\n"
        "#ifdef A\nyes1\n#else\nno1\n#endif\n"
        "#ifndef A\nno2\n#elif A == 2\nyes2\n#else\nno3\n#endif\n"
        "#if defined(B) || defined A\nyes3\n#endif\n"
        "#if 0\n#if 1\nno4\n#endif\n#bogus directive\n#error no\n#else\nyes4\n#endif\n"
        "#if 0\nno5\n#elif 0\nno6\n#elif 1\nyes5\n#elif 1\nno7\n#endif\n";
    EXPECT_EQ(code(src), "yes1|yes2|yes3|yes4|yes5");
    // Skipped lines and directives become empty lines: the line map holds.
    const PreprocessResult r = pp(src);
    const auto lines = lines_of(r);
    for (size_t i = 0; i < lines.size(); ++i) {
        EXPECT_EQ(r.lines[i].line, static_cast<int>(i) + 1);
        if (lines[i] == "yes4") {
            EXPECT_EQ(i + 1, 24u);
        }
    }
}

TEST(RslPreprocess, IfArithmetic) {
    auto truth = [](const std::string& expr) {
        return code("#define TWO 2\n#define F(x) (x * 3)\n#if " + expr +
                    "\nT\n#else\nF\n#endif") == "T";
    };
    EXPECT_TRUE(truth("1 + 2 * 3 == 7"));
    EXPECT_TRUE(truth("(1 + 2) * 3 == 9"));
    EXPECT_TRUE(truth("10 / 3 == 3 && 10 % 3 == 1"));
    EXPECT_TRUE(truth("-7 / 2 == -3"));
    EXPECT_TRUE(truth("1 << 4 == 16 && 256 >> 2 == 64"));
    EXPECT_TRUE(truth("(5 & 3) == 1 && (5 | 3) == 7 && (5 ^ 3) == 6 && ~0 == -1"));
    EXPECT_TRUE(truth("!0 && !!5 && 3 > 2 && 2 >= 2 && 1 < 2 && 2 <= 2 && 1 != 2"));
    EXPECT_TRUE(truth("TWO == 2 && F(TWO) == 6"));
    EXPECT_TRUE(truth("UNDEFINED == 0 && !UNDEFINED"));
    EXPECT_TRUE(truth("0x10 == 16 && 010 == 8 && 10L == 10 && 'A' == 65"));
    EXPECT_TRUE(truth("(1 ? 5 : 6) == 5 && (0 ? 5 : 6) == 6"));
    EXPECT_TRUE(truth("defined TWO && defined(F) && !defined(G)"));
    // Short-circuit: the unevaluated division by zero is no error.
    EXPECT_TRUE(truth("1 || 1 / 0"));
    EXPECT_FALSE(truth("0 && 1 / 0"));
    EXPECT_TRUE(truth("1 ? 1 : 1 / 0"));
    EXPECT_FALSE(truth("3 - 3"));
}

TEST(RslPreprocess, LineDirective) {
    const PreprocessResult r =
        pp("a\n#line 100\nb\n#line 7 \"gen.sl\"\nc\n# 42 \"x.sl\"\nd\n");
    const auto lines = lines_of(r);
    for (size_t i = 0; i < lines.size(); ++i) {
        if (lines[i] == "b") {
            EXPECT_EQ(r.lines[i].line, 100);
        }
        if (lines[i] == "c") {
            EXPECT_EQ(r.lines[i].line, 7);
            EXPECT_EQ(r.files[r.lines[i].file], "gen.sl");
        }
        if (lines[i] == "d") {
            EXPECT_EQ(r.lines[i].line, 42);
            EXPECT_EQ(r.files[r.lines[i].file], "x.sl");
        }
    }
    // Errors after #line report the new name and number.
    const PreprocessError e = error_of("#line 50 \"orig.sl\"\n\n#error boom\n");
    EXPECT_STREQ(e.what(), "orig.sl:51:1: #error boom");
}

TEST(RslPreprocess, PragmaIgnoredErrorAndUnknownDirectives) {
    EXPECT_EQ(code("#pragma nolint\n#\nx"), "x");
    PreprocessError e = error_of("a\n  #error Kd must be set  \n");
    EXPECT_STREQ(e.what(), "test.sl:2:3: #error Kd must be set");
    EXPECT_EQ(e.source_line(), "  #error Kd must be set  ");
    e = error_of("\n\n #foo bar\n");
    EXPECT_STREQ(e.what(), "test.sl:3:3: unknown preprocessing directive \"#foo\"");
}

TEST(RslPreprocess, ErrorLocations) {
    auto what = [](const std::string& text) {
        return std::string(error_of(text).what());
    };
    EXPECT_EQ(what("#if 1\nx\n"), "test.sl:1:1: unterminated #if");
    EXPECT_EQ(what("x\n#ifdef A\n#else\n#else\n#endif\n"),
              "test.sl:4:1: #else after #else");
    EXPECT_EQ(what("#endif\n"), "test.sl:1:1: #endif without #if");
    EXPECT_EQ(what("#else\n"), "test.sl:1:1: #else without #if");
    EXPECT_EQ(what("#elif 1\n"), "test.sl:1:1: #elif without #if");
    EXPECT_EQ(what("a /* b\n c\n"), "test.sl:1:3: unterminated comment");
    EXPECT_EQ(what("#if 1 +\n#endif\n"), "test.sl:1:8: #if expression ends unexpectedly");
    EXPECT_EQ(what("#if 2 / 0\n#endif\n"),
              "test.sl:1:7: division by zero in #if expression");
    EXPECT_EQ(what("#if 1.5\n#endif\n"),
              "test.sl:1:5: floating-point number \"1.5\" in #if expression");
    EXPECT_EQ(what("#if (1\n#endif\n"), "test.sl:1:7: missing ')' in #if expression");
    EXPECT_EQ(what("#if 1 2\n#endif\n"),
              "test.sl:1:7: unexpected \"2\" in #if expression");
    EXPECT_EQ(what("#if\n#endif\n"), "test.sl:1:4: #if with no expression");
    EXPECT_EQ(what("#define F(a, b) a\n\n  y = F(1);\n"),
              "test.sl:3:7: macro \"F\" requires 2 arguments, 1 given");
    EXPECT_EQ(what("#define F(a) a\nF(1,\n2\n"),
              "test.sl:2:1: unterminated argument list invoking macro \"F\"");
    EXPECT_EQ(what("#define F(a) #b\n"),
              "test.sl:1:14: '#' is not followed by a macro parameter");
    EXPECT_EQ(what("#define F(a) ## a\n"),
              "test.sl:1:14: '##' cannot appear at either end of a macro");
    EXPECT_EQ(what("#define F(a, a) a\n"),
              "test.sl:1:14: duplicate macro parameter \"a\"");
    EXPECT_EQ(what("#define 3 x\n"), "test.sl:1:9: macro names must be identifiers");
    EXPECT_EQ(what("#define defined 1\n"),
              "test.sl:1:9: \"defined\" cannot be used as a macro name");
    EXPECT_EQ(what("#line x\n"),
              "test.sl:1:7: #line expects a line number (a positive integer)");
    EXPECT_EQ(what("#include\n"),
              "test.sl:1:9: #include expects \"FILENAME\" or <FILENAME>");
}

TEST(RslPreprocess, IncludesWithSearchPathAndLineMap) {
    test::TempDir dir("rsl_pp");
    std::filesystem::create_directories(dir.path() / "src");
    std::filesystem::create_directories(dir.path() / "inc1");
    std::filesystem::create_directories(dir.path() / "inc2");
    write(dir.file("src/local.h"), "/* local\n header */ float local_h;\n");
    write(dir.file("inc1/common.h"), "#ifndef COMMON_H\n#define COMMON_H\n#include "
                                     "\"nested.h\"\nfloat common1;\n#endif\n");
    write(dir.file("inc1/nested.h"), "float nested1;\n");
    write(dir.file("inc2/nested.h"), "float nested2;\n");
    write(dir.file("inc2/only2.h"), "float only2;\n");
    write(dir.file("inc2/common.h"), "float common2;\n");
    write(dir.file("src/main.sl"), "#include \"local.h\"\n"
                                   "#include <common.h>\n"
                                   "#include \"common.h\" // guarded: nothing\n"
                                   "#define HDR <only2.h>\n"
                                   "#include HDR\n"
                                   "float end;\n");
    PreprocessOptions o;
    o.include_dirs = {dir.file("inc1"), dir.file("inc2")};
    const PreprocessResult r = preprocess_file(dir.file("src/main.sl"), o);
    const auto lines = lines_of(r);
    struct Where {
        std::string file;
        int line;
    };
    std::vector<std::pair<std::string, Where>> expect = {
        {"float local_h;", {"src/local.h", 1}},
        {"float nested1;", {"inc1/nested.h", 1}},
        {"float common1;", {"inc1/common.h", 4}},
        {"float only2;", {"inc2/only2.h", 1}},
        {"float end;", {"src/main.sl", 6}}};
    std::vector<std::string> code_lines;
    for (size_t i = 0; i < lines.size(); ++i) {
        const size_t b = lines[i].find_first_not_of(' ');
        if (b == std::string::npos) continue;
        const std::string text = lines[i].substr(b);
        code_lines.push_back(text);
        for (const auto& [want, where] : expect)
            if (text == want) {
                const std::string& file = r.files[r.lines[i].file];
                EXPECT_EQ(file.substr(file.size() - where.file.size()), where.file)
                    << want;
                EXPECT_EQ(r.lines[i].line, where.line) << want;
            }
    }
    EXPECT_EQ(code_lines,
              (std::vector<std::string>{"float local_h;", "float nested1;",
                                        "float common1;", "float only2;", "float end;"}));
    EXPECT_EQ(r.files[0], dir.file("src/main.sl"));

    // Quotes search the including file's folder first: inc1/common.h's
    // "nested.h" is inc1's even with inc2 first on the path.
    o.include_dirs = {dir.file("inc2"), dir.file("inc1")};
    write(dir.file("src/b.sl"), "#include \"../inc1/common.h\"\n");
    EXPECT_NE(preprocess_file(dir.file("src/b.sl"), o).text.find("nested1"),
              std::string::npos);
}

TEST(RslPreprocess, IncludeErrors) {
    test::TempDir dir("rsl_pp_err");
    write(dir.file("bad.h"), "ok;\n#if\n");
    write(dir.file("cycle.h"), "#include \"cycle.h\"\n");
    write(dir.file("main.sl"), "x;\n  #include \"missing.h\"\n");
    try {
        preprocess_file(dir.file("main.sl"), {});
        ADD_FAILURE() << "no error";
    } catch (const PreprocessError& e) {
        EXPECT_EQ(e.file(), dir.file("main.sl"));
        EXPECT_EQ(e.line(), 2);
        EXPECT_EQ(e.column(), 12);
        EXPECT_NE(std::string(e.what()).find("cannot find include file \"missing.h\""),
                  std::string::npos);
    }
    write(dir.file("main.sl"), "x;\n#include \"bad.h\"\n");
    try {
        preprocess_file(dir.file("main.sl"), {});
        ADD_FAILURE() << "no error";
    } catch (const PreprocessError& e) {
        EXPECT_EQ(e.file(), dir.file("bad.h"));
        EXPECT_EQ(e.line(), 2);
        EXPECT_EQ(e.column(), 4);
    }
    write(dir.file("main.sl"), "#include \"cycle.h\"\n");
    try {
        preprocess_file(dir.file("main.sl"), {});
        ADD_FAILURE() << "no error";
    } catch (const PreprocessError& e) {
        EXPECT_NE(std::string(e.what()).find("nested more than 64 levels"),
                  std::string::npos);
    }
    EXPECT_THROW(preprocess_file(dir.file("nonexistent.sl"), {}), IoError);
}

TEST(RslPreprocess, PathologicalInputIsBounded) {
    // Exponential growth: each level doubles.
    std::string src = "#define L0 x\n";
    for (int i = 1; i <= 40; ++i)
        src += "#define L" + std::to_string(i) + " L" + std::to_string(i - 1) + " L" +
               std::to_string(i - 1) + "\n";
    src += "L40\n";
    const PreprocessError e = error_of(src);
    EXPECT_NE(std::string(e.what()).find("macro expansion"), std::string::npos)
        << e.what();
    // Deeply nested arguments.
    std::string nested = "#define F(x) x\n";
    for (int i = 0; i < 5000; ++i) nested += "F(";
    nested += "1";
    for (int i = 0; i < 5000; ++i) nested += ")";
    EXPECT_NE(std::string(error_of(nested).what()).find("nested too deeply"),
              std::string::npos);
    // Deep #if expressions.
    EXPECT_NE(
        std::string(error_of("#if " + std::string(10000, '(') + "1\n#endif\n").what())
            .find("nested too deeply"),
        std::string::npos);
    EXPECT_NE(
        std::string(error_of("#if " + std::string(10000, '!') + "1\n#endif\n").what())
            .find("nested too deeply"),
        std::string::npos);
}

} // namespace
} // namespace sss
