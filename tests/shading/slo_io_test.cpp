// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file slo_io_test.cpp
/// The .slo format (program.h write_program / read_program): a round trip
/// keeps every field; damaged files are ValueErrors naming file:line.

#include <gtest/gtest.h>

#include <sstream>
#include <string>

#include "rsl/rsl_test_util.h"
#include "sss/rsl/program.h"
#include "sss/shading/engine.h"
#include "sss/util/error.h"

namespace {

using namespace sss;

const char* kShader = R"(
float twice(float x) { return 2 * x; }
surface s(float Kd = .5; string tex = "a \"q\"\n.tx"; point from = point "shader" (0,0,0);
          float w[2] = {1, 2}; output varying color aov = 0) {
    color c = texture(tex[1], s, t, "blur", 0.1);
    float i;
    for (i = 0; i < 3; i += 1) { if (u > i) break; c += twice(i); }
    illuminance(P, N, PI / 2) { c += Cl; }
    aov = c;
    Ci = c * Kd;
}
)";

std::string to_text(const Program& p) {
    std::ostringstream out;
    write_program(p, out);
    return out.str();
}

Program from_text(const std::string& text) {
    std::istringstream in(text);
    return read_program(in, "x.slo");
}

TEST(RslSlo, RoundTrip) {
    const Program p = test::compile_one(kShader);
    const std::string text = to_text(p);
    EXPECT_EQ(text.rfind("sss-slo 1\n", 0), 0u);
    const Program q = from_text(text);
    EXPECT_EQ(q.name, p.name);
    EXPECT_EQ(q.kind, p.kind);
    EXPECT_EQ(q.body_begin, p.body_begin);
    EXPECT_EQ(q.files, p.files);
    EXPECT_EQ(q.source_path, p.source_path);
    ASSERT_EQ(q.symbols.size(), p.symbols.size());
    for (std::size_t i = 0; i < p.symbols.size(); ++i) {
        const Symbol &a = p.symbols[i], &b = q.symbols[i];
        EXPECT_EQ(a.name, b.name);
        EXPECT_EQ(a.type, b.type);
        EXPECT_EQ(a.varying, b.varying);
        EXPECT_EQ(a.kind, b.kind);
        EXPECT_EQ(a.numbers, b.numbers);
        EXPECT_EQ(a.strings, b.strings);
        EXPECT_EQ(a.init_begin, b.init_begin);
        EXPECT_EQ(a.init_end, b.init_end);
    }
    ASSERT_EQ(q.ops.size(), p.ops.size());
    for (std::size_t i = 0; i < p.ops.size(); ++i) {
        const Op &a = p.ops[i], &b = q.ops[i];
        EXPECT_EQ(a.name, b.name);
        EXPECT_EQ(a.args, b.args);
        EXPECT_EQ(a.jump, b.jump);
        EXPECT_EQ(a.level, b.level);
        EXPECT_EQ(a.writes, b.writes);
        EXPECT_EQ(a.where.file, b.where.file);
        EXPECT_EQ(a.where.line, b.where.line);
        EXPECT_EQ(a.where.column, b.where.column);
    }
    EXPECT_EQ(to_text(q), text);
}

TEST(RslSlo, TruncatedFilesAreRejected) {
    const std::string text = to_text(test::compile_one(kShader));
    std::size_t pos = 0;
    int lines = 0;
    while ((pos = text.find('\n', pos)) != std::string::npos) {
        ++pos;
        if (pos == text.size()) break;
        ++lines;
        EXPECT_THROW(from_text(text.substr(0, pos)), ValueError)
            << "cut after line " << lines;
    }
    EXPECT_GT(lines, 20);
}

// Replaces the first occurrence of `from` (after `after`) with `to`.
std::string damage(std::string text, const std::string& from, const std::string& to,
                   const std::string& after = "") {
    std::size_t start = after.empty() ? 0 : text.find(after);
    std::size_t at = text.find(from, start == std::string::npos ? 0 : start);
    if (at == std::string::npos) return text;
    return text.replace(at, from.size(), to);
}

void expect_rejected(const std::string& text, const std::string& part) {
    try {
        from_text(text);
        ADD_FAILURE() << "accepted a damaged file (expected '" << part << "')";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
        EXPECT_EQ(std::string(e.what()).rfind("x.slo:", 0), 0u) << e.what();
    }
}

TEST(RslSlo, DamagedFilesAreRejected) {
    const std::string text = to_text(test::compile_one(kShader));
    expect_rejected(damage(text, "sss-slo 1", "sss-slo 7"), "unsupported .slo version 7");
    expect_rejected(damage(text, "sss-slo", "xyz"), "expected 'sss-slo'");
    expect_rejected(damage(text, "shader surface", "shader bogus"),
                    "unknown shader kind");
    expect_rejected(damage(text, " float ", " flaot ", "sym "), "unknown type");
    expect_rejected(damage(text, "op \"if\" 1 ", "op \"if\" 1 99999 "), "out of range");
    expect_rejected(damage(text, "op \"loop\" 1 ", "op \"loop\" 2 "), "");
    expect_rejected(text + "junk\n", "");
    // A jump before the op itself.
    {
        const Program p = test::compile_one(kShader);
        Program q = p;
        for (Op& op : q.ops)
            if (op.name == "if") {
                op.jump[1] = op.jump[0] - 1;
                break;
            }
        expect_rejected(to_text(q), "jump target");
        q = p;
        for (Op& op : q.ops)
            if (op.name == "break") op.level = 3;
        expect_rejected(to_text(q), "level out of range");
        q = p;
        q.ops[q.body_begin].name = "frobnicate";
        expect_rejected(to_text(q), "unknown operation");
        q = p;
        for (Op& op : q.ops)
            if (op.name == "assign") {
                op.args[0] = q.find("$c0") >= 0 ? q.find("$c0") : op.args[0];
                break;
            }
        expect_rejected(to_text(q), "");
        q = p;
        q.symbols[q.find("Kd")].numbers = {1, 2};
        expect_rejected(to_text(q), "wrong number of values");
        q = p;
        q.symbols[q.find("from")].init_end = static_cast<int>(q.ops.size()) + 5;
        expect_rejected(to_text(q), "bad default range");
    }
}

TEST(RslSlo, EveryByteFlipIsHandled) {
    const std::string text = to_text(test::compile_one(kShader));
    // Damage every position (a cheap sweep): either a clean error or a program.
    for (std::size_t i = 0; i < text.size(); i += 3) {
        for (char c : {'9', '-', '"', ' ', '\n'}) {
            std::string t = text;
            t[i] = c;
            try {
                from_text(t);
            } catch (const ValueError&) {
            }
        }
    }
}

TEST(RslSlo, MissingFileIsIoError) {
    EXPECT_THROW(read_program_file("/nonexistent/x.slo"), IoError);
}

} // namespace

namespace {
const char* kGatherShader = R"(
surface g(output varying float n = 0) {
    color c = 0;
    float len = 0;
    vector d = 0;
    gather("illuminance", P, N, PI / 4, 8, "surface:Ci", c, "ray:length", len,
           "ray:direction", d, "distribution", "cosine", "maxdist", 10) {
        n += 1;
    } else {
        n += 100;
    }
    Ci = c + len + xcomp(d);
}
)";
} // namespace

TEST(RslSlo, GatherRoundTripsAndItsFlagsAreChecked) {
    const Program p = test::compile_one(kGatherShader);
    int gi = -1;
    for (std::size_t i = 0; i < p.ops.size(); ++i)
        if (p.ops[i].name == "gather") gi = static_cast<int>(i);
    ASSERT_GE(gi, 0);
    const Op& g = p.ops[gi];
    // cat P dir angle samples + 5 pairs; the three output values are written.
    ASSERT_EQ(g.args.size(), 15u);
    EXPECT_EQ(g.writes, (uint64_t(1) << 6) | (uint64_t(1) << 8) | (uint64_t(1) << 10));
    EXPECT_GT(g.jump[0], gi + 1);
    EXPECT_GT(g.jump[1], g.jump[0]); // the else body
    EXPECT_EQ(g.jump[2], -1);
    for (int k : {6, 8, 10}) EXPECT_TRUE(p.symbols[g.args[k]].varying) << k;
    const std::string text = to_text(p);
    const Program q = from_text(text);
    ASSERT_EQ(q.ops.size(), p.ops.size());
    EXPECT_EQ(q.ops[gi].args, g.args);
    EXPECT_EQ(q.ops[gi].jump, g.jump);
    EXPECT_EQ(q.ops[gi].writes, g.writes);
    EXPECT_EQ(to_text(q), text);
    // A written fixed argument or option name, or a bad range, is refused.
    for (uint64_t bad : {uint64_t(1), uint64_t(1) << 5, uint64_t(1) << 20}) {
        Program r = p;
        r.ops[gi].writes |= bad;
        EXPECT_THROW(from_text(to_text(r)), ValueError) << bad;
    }
    Program r = p;
    r.ops[gi].jump[1] = r.ops[gi].jump[0] - 1;
    EXPECT_THROW(from_text(to_text(r)), ValueError);
    // The engine binds it.
    EXPECT_NO_THROW(ShaderInstance(std::make_shared<Program>(q), {}, Matrix4(1.0), "x"));
}
