// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file slo_io.cpp
/// The .slo text format (write_program / read_program, program.h):
///
///     sss-slo 1
///     shader <kind> "<name>"
///     source "<path>"
///     files <n>            then n lines: file "<path>"
///     symbols <n>          then n lines:
///       sym "<name>" <type> <array> <u|v> <kind> <init_begin> <init_end>
///           <count> <float>... <count> "<string>"...
///     ops <n>              then n lines:
///       op "<name>" <nargs> <arg>... <jump0> <jump1> <jump2> <jump3> <level>
///          <writes> <file> <line> <column>
///     body <body_begin>
///     end
///
/// Version 2 (written for RSL 2.0 class shaders only; version 1 otherwise)
/// has between `body` and `end`:
///
///     class <init_end>
///     methods <n>          then n lines:
///       method "<name>" <begin> <end> <result> <outputs> <nparams> <sym>...
///     pipelines <n>        then n lines:
///       pipeline <kind> <n> <method>...
///
/// Strings are quoted with C escapes. The reader checks everything the
/// engine relies on (indices, jump ranges and their nesting, argument counts
/// and types of the core ops, known op names), so a damaged file is a
/// ValueError "path:line: ...", never a crash later.

#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "sss/rsl/builtins.h"
#include "sss/rsl/program.h"
#include "sss/util/atomic_output.h"
#include "sss/util/byte_io.h"
#include "sss/util/error.h"

namespace sss {

namespace {

constexpr const char* kMagic = "sss-slo";
constexpr int kVersion = 1;      ///< classic shaders
constexpr int kClassVersion = 2; ///< class shaders (RSL 2.0)
constexpr long kMaxCount = 50000000;

std::string quote(const std::string& s) {
    static const char* hex = "0123456789abcdef";
    std::string out = "\"";
    for (char c : s) {
        const unsigned char u = static_cast<unsigned char>(c);
        if (c == '"' || c == '\\') {
            out += '\\';
            out += c;
        } else if (c == '\n') {
            out += "\\n";
        } else if (c == '\t') {
            out += "\\t";
        } else if (u < 32 || u == 127) {
            out += "\\x";
            out += hex[u >> 4];
            out += hex[u & 15];
        } else {
            out += c;
        }
    }
    return out + "\"";
}

std::string number(float f) {
    if (std::isnan(f)) return "nan";
    if (std::isinf(f)) return f > 0 ? "inf" : "-inf";
    char buf[64];
    auto r = std::to_chars(buf, buf + sizeof buf, f);
    return std::string(buf, r.ptr);
}

const char* kind_word(SymbolKind k) {
    switch (k) {
    case SymbolKind::Param:
        return "param";
    case SymbolKind::OutputParam:
        return "output";
    case SymbolKind::Global:
        return "global";
    case SymbolKind::Local:
        return "local";
    case SymbolKind::Temp:
        return "temp";
    case SymbolKind::Const:
        return "const";
    }
    return "?";
}

// --- reading ----------------------------------------------------------------

class Reader {
public:
    Reader(std::istream& in, const std::string& path) : m_in(in), m_path(path) {}

    [[noreturn]] void fail(const std::string& what) const {
        throw ValueError(m_path + ":" + std::to_string(m_line) + ": " + what);
    }

    // Reads the next line into words; false at the end of the input.
    bool next_line() {
        std::string line;
        if (!std::getline(m_in, line)) return false;
        ++m_line;
        if (line.size() > 100000000) fail("line too long");
        m_words.clear();
        m_pos = 0;
        std::size_t i = 0;
        while (i < line.size()) {
            if (line[i] == ' ' || line[i] == '\t' || line[i] == '\r') {
                ++i;
                continue;
            }
            std::string w;
            if (line[i] == '"') {
                ++i;
                bool closed = false;
                while (i < line.size()) {
                    char c = line[i++];
                    if (c == '"') {
                        closed = true;
                        break;
                    }
                    if (c != '\\') {
                        w += c;
                        continue;
                    }
                    if (i >= line.size()) break;
                    char e = line[i++];
                    if (e == 'n')
                        w += '\n';
                    else if (e == 't')
                        w += '\t';
                    else if (e == 'x') {
                        if (i + 2 > line.size()) fail("bad escape in a string");
                        int v = 0;
                        for (int k = 0; k < 2; ++k) {
                            char h = line[i++];
                            int d = h >= '0' && h <= '9'   ? h - '0'
                                    : h >= 'a' && h <= 'f' ? h - 'a' + 10
                                                           : -1;
                            if (d < 0) fail("bad escape in a string");
                            v = v * 16 + d;
                        }
                        w += static_cast<char>(v);
                    } else
                        w += e;
                }
                if (!closed) fail("unterminated string");
                m_words.push_back({w, true});
            } else {
                while (i < line.size() && line[i] != ' ' && line[i] != '\t' &&
                       line[i] != '\r')
                    w += line[i++];
                m_words.push_back({w, false});
            }
        }
        return true;
    }

    void line(const char* keyword) {
        if (!next_line()) fail(std::string("truncated file: expected '") + keyword + "'");
        if (m_words.empty() || m_words[0].quoted || m_words[0].text != keyword)
            fail(std::string("expected '") + keyword + "'");
        m_pos = 1;
    }

    std::string word() {
        if (m_pos >= m_words.size()) fail("missing value");
        if (m_words[m_pos].quoted) fail("unexpected string");
        return m_words[m_pos++].text;
    }
    std::string string() {
        if (m_pos >= m_words.size()) fail("missing string");
        if (!m_words[m_pos].quoted) fail("expected a quoted string");
        return m_words[m_pos++].text;
    }
    long integer(long lo, long hi) {
        const std::string w = word();
        long v = 0;
        auto r = std::from_chars(w.data(), w.data() + w.size(), v);
        if (r.ec != std::errc() || r.ptr != w.data() + w.size())
            fail("bad integer '" + w + "'");
        if (v < lo || v > hi)
            fail("value " + w + " out of range [" + std::to_string(lo) + ", " +
                 std::to_string(hi) + "]");
        return v;
    }
    uint64_t bits() {
        const std::string w = word();
        uint64_t v = 0;
        auto r = std::from_chars(w.data(), w.data() + w.size(), v);
        if (r.ec != std::errc() || r.ptr != w.data() + w.size())
            fail("bad integer '" + w + "'");
        return v;
    }
    float real() {
        const std::string w = word();
        if (w == "nan") return std::numeric_limits<float>::quiet_NaN();
        if (w == "inf") return std::numeric_limits<float>::infinity();
        if (w == "-inf") return -std::numeric_limits<float>::infinity();
        float v = 0;
        auto r = std::from_chars(w.data(), w.data() + w.size(), v);
        if (r.ec != std::errc() || r.ptr != w.data() + w.size())
            fail("bad number '" + w + "'");
        return v;
    }
    void end_of_line() {
        if (m_pos != m_words.size()) fail("unexpected extra values");
    }
    bool blank() const { return m_words.empty(); }
    int line_number() const { return m_line; }
    void set_line(int line) { m_line = line; }

private:
    struct Word {
        std::string text;
        bool quoted;
    };
    std::istream& m_in;
    const std::string& m_path;
    int m_line = 0;
    std::vector<Word> m_words;
    std::size_t m_pos = 0;
};

ShadingType parse_type(Reader& r, const std::string& w) {
    for (ShadingType t : {ShadingType::Float, ShadingType::Color, ShadingType::Point,
                          ShadingType::Vector, ShadingType::Normal, ShadingType::Matrix,
                          ShadingType::String, ShadingType::Shader})
        if (w == shading_type_name(t)) return t;
    r.fail("unknown type '" + w + "'");
}

ShaderKind parse_shader_kind(Reader& r, const std::string& w) {
    for (ShaderKind k : {ShaderKind::Surface, ShaderKind::Displacement, ShaderKind::Light,
                         ShaderKind::Volume, ShaderKind::Imager, ShaderKind::Shader})
        if (w == shader_kind_name(k)) return k;
    r.fail("unknown shader kind '" + w + "'");
}

/// The class part of a version 2 file: member initialisers' end, methods
/// (each a `block` of its own among the body's ops) and pipelines.
void read_class(Reader& r, Program& p) {
    const long nops = static_cast<long>(p.ops.size());
    const long nsyms = static_cast<long>(p.symbols.size());
    r.line("class");
    p.init_end = static_cast<int>(r.integer(p.body_begin, nops));
    r.end_of_line();
    r.line("methods");
    const long nmethods = r.integer(0, kMaxCount);
    r.end_of_line();
    for (long i = 0; i < nmethods; ++i) {
        r.line("method");
        Method m;
        m.name = r.string();
        m.begin = static_cast<int>(r.integer(p.init_end, nops - 1));
        m.end = static_cast<int>(r.integer(m.begin + 1, nops));
        if (p.ops[m.begin].name != "block" || p.ops[m.begin].jump[0] != m.end)
            r.fail("method '" + m.name + "' is not a block of the program");
        m.result = static_cast<int>(r.integer(-1, nsyms - 1));
        m.outputs = r.bits();
        const long nparams = r.integer(0, 63);
        if ((m.outputs >> nparams) != 0) r.fail("output flag for a missing parameter");
        for (long k = 0; k < nparams; ++k)
            m.params.push_back(static_cast<int>(r.integer(0, nsyms - 1)));
        r.end_of_line();
        m.params.shrink_to_fit();
        for (int s : m.params)
            if (p.symbols[s].kind == SymbolKind::Const)
                r.fail("a parameter of method '" + m.name + "' is a constant");
        if (m.result >= 0 && p.symbols[m.result].kind == SymbolKind::Const)
            r.fail("the result of method '" + m.name + "' is a constant");
        p.methods.push_back(std::move(m));
    }
    r.line("pipelines");
    const long npipelines = r.integer(0, 6);
    r.end_of_line();
    for (long i = 0; i < npipelines; ++i) {
        r.line("pipeline");
        Pipeline pl;
        pl.kind = parse_shader_kind(r, r.word());
        if (p.pipeline(pl.kind)) r.fail("two pipelines of one kind");
        const long n = r.integer(0, kMaxCount);
        for (long k = 0; k < n; ++k)
            pl.methods.push_back(static_cast<int>(r.integer(0, nmethods - 1)));
        r.end_of_line();
        p.pipelines.push_back(std::move(pl));
    }
}

SymbolKind parse_kind(Reader& r, const std::string& w) {
    for (SymbolKind k : {SymbolKind::Param, SymbolKind::OutputParam, SymbolKind::Global,
                         SymbolKind::Local, SymbolKind::Temp, SymbolKind::Const})
        if (w == kind_word(k)) return k;
    r.fail("unknown symbol kind '" + w + "'");
}

// Checks ops [begin, end): control ops' parts lie inside and nest.
class Validator {
public:
    Validator(const Program& p, Reader& r, const std::vector<int>& lines)
        : m_p(p), m_r(r), m_lines(lines) {}

    void range(int begin, int end, int loops) {
        int i = begin;
        while (i < end) i = op(i, end, loops);
    }

private:
    [[noreturn]] void fail(int i, const std::string& what) {
        m_r.set_line(m_lines[i]);
        m_r.fail(what);
    }
    const TypeSpec& type(int s) const { return m_p.symbols[s].type; }
    bool is(int s, ShadingType t) const { return type(s) == TypeSpec{t, 0}; }

    void nargs(int i, std::size_t lo, std::size_t hi) {
        const std::size_t n = m_p.ops[i].args.size();
        if (n < lo || n > hi)
            fail(i, "wrong number of arguments for '" + m_p.ops[i].name + "'");
    }
    void writes_only_result(int i) {
        if (m_p.ops[i].writes != 1)
            fail(i, "bad write flags for '" + m_p.ops[i].name + "'");
    }
    void no_writes(int i) {
        if (m_p.ops[i].writes != 0)
            fail(i, "bad write flags for '" + m_p.ops[i].name + "'");
    }
    void jumps(int i, int parts, int end) {
        const Op& op = m_p.ops[i];
        int prev = i + 1;
        for (int k = 0; k < 4; ++k) {
            if (k >= parts) {
                if (op.jump[k] != -1) fail(i, "unexpected jump target");
                continue;
            }
            if (op.jump[k] < prev || op.jump[k] > end)
                fail(i, "jump target out of range in '" + op.name + "'");
            prev = op.jump[k];
        }
    }

    // gather cat P dir angle samples ("name" value)...: hit body [i+1, jump0),
    // else body [jump0, jump1); only token values written.
    int gather_op(int i, int end, int loops) {
        const Op& op = m_p.ops[i];
        const std::size_t na = op.args.size();
        if (na < 5 || (na - 5) % 2 != 0)
            fail(i, "wrong number of arguments for 'gather'");
        if (!is(op.args[0], ShadingType::String) ||
            !is_point_like(type(op.args[1]).type) || type(op.args[1]).is_array() ||
            !is_point_like(type(op.args[2]).type) || type(op.args[2]).is_array() ||
            !is(op.args[3], ShadingType::Float) || !is(op.args[4], ShadingType::Float))
            fail(i, "bad argument types for 'gather'");
        for (std::size_t k = 5; k < na; k += 2)
            if (!is(op.args[k], ShadingType::String))
                fail(i, "gather option names must be strings");
        for (std::size_t k = 0; k < na && k < 64; ++k)
            if (((op.writes >> k) & 1u) && (k < 5 || (k - 5) % 2 == 0))
                fail(i, "bad write flags for 'gather'");
        if (na < 64 && (op.writes >> na) != 0) fail(i, "bad write flags for 'gather'");
        jumps(i, 2, end);
        range(i + 1, op.jump[0], loops);
        range(op.jump[0], op.jump[1], loops);
        return op.jump[1];
    }

    // Validates op i (and its parts); returns the index after it.
    int op(int i, int end, int loops) {
        const Op& op = m_p.ops[i];
        const std::string& n = op.name;
        if (n == "if") {
            nargs(i, 1, 1);
            no_writes(i);
            if (!is(op.args[0], ShadingType::Float))
                fail(i, "'if' needs a float condition");
            jumps(i, 2, end);
            range(i + 1, op.jump[0], loops);
            range(op.jump[0], op.jump[1], loops);
            return op.jump[1];
        }
        if (n == "loop") {
            nargs(i, 1, 1);
            no_writes(i);
            if (!is(op.args[0], ShadingType::Float))
                fail(i, "'loop' needs a float condition");
            jumps(i, 4, end);
            range(i + 1, op.jump[0], loops);
            range(op.jump[0], op.jump[1], loops);
            range(op.jump[1], op.jump[2], loops + 1);
            range(op.jump[2], op.jump[3], loops);
            return op.jump[3];
        }
        if (n == "gather") return gather_op(i, end, loops);
        if (n == "block" || n == "illuminance" || n == "illuminate" || n == "solar") {
            const std::size_t want = n == "block"         ? 0
                                     : n == "illuminance" ? 4
                                     : n == "illuminate"  ? 3
                                                          : 2;
            if (n == "illuminance") {
                // "name", value options follow; "light:..." values are written.
                nargs(i, want, 64);
                if ((op.args.size() - want) % 2 != 0)
                    fail(i, "illuminance options come in pairs");
                for (std::size_t k = want; k < op.args.size(); k += 2)
                    if (!is(op.args[k], ShadingType::String) ||
                        type(op.args[k + 1]).is_array())
                        fail(i, "bad illuminance option");
                for (std::size_t k = 0; k < op.args.size() && k < 64; ++k)
                    if (((op.writes >> k) & 1u) && (k < want || (k - want) % 2 == 0))
                        fail(i, "bad write flags for 'illuminance'");
            } else {
                nargs(i, want, want);
                no_writes(i);
            }
            std::size_t a = 0;
            if (n == "illuminance" && !is(op.args[a++], ShadingType::String))
                fail(i, "illuminance category must be a string");
            if ((n == "illuminance" || n == "illuminate") &&
                !is(op.args[a++], ShadingType::Point))
                fail(i, n + " position must be a point");
            if (n != "block" && (!is(op.args[a], ShadingType::Vector) ||
                                 !is(op.args[a + 1], ShadingType::Float)))
                fail(i, n + " needs a vector axis and a float angle");
            jumps(i, 1, end);
            // A block is a function body: its loops are its own.
            range(i + 1, op.jump[0], n == "block" ? 0 : loops);
            return op.jump[0];
        }
        jumps(i, 0, end);
        if (n == "break" || n == "continue") {
            nargs(i, 0, 0);
            no_writes(i);
            if (op.level < 1 || op.level > loops)
                fail(i, "'" + n + "' level out of range");
            return i + 1;
        }
        if (op.level != 0) fail(i, "unexpected level");
        if (n == "return") {
            nargs(i, 0, 0);
            no_writes(i);
            return i + 1;
        }
        if (n == "assign" || n == "neg" || n == "not") {
            nargs(i, 2, 2);
            writes_only_result(i);
            if (type(op.args[0]).is_array() || type(op.args[1]).is_array())
                fail(i, "'" + n + "' of an array");
            return i + 1;
        }
        static const char* binary[] = {"add", "sub", "mul", "div", "dot", "cross", "eq",
                                       "ne",  "lt",  "le",  "gt",  "ge",  "and",   "or"};
        for (const char* b : binary)
            if (n == b) {
                nargs(i, 3, 3);
                writes_only_result(i);
                for (int a : op.args)
                    if (type(a).is_array()) fail(i, "'" + n + "' of an array");
                return i + 1;
            }
        if (n == "aref" || n == "aassign") {
            nargs(i, 3, 3);
            writes_only_result(i);
            const int array = n == "aref" ? op.args[1] : op.args[0];
            const int value = n == "aref" ? op.args[0] : op.args[2];
            if (!type(array).is_array() ||
                !is(op.args[n == "aref" ? 2 : 1], ShadingType::Float) ||
                type(value) != TypeSpec{type(array).type, 0})
                fail(i, "bad argument types for '" + n + "'");
            return i + 1;
        }
        if (n == "arraylength" || n == "resize" || n == "reserve" || n == "push" ||
            n == "pop") {
            // arraylength d a, resize a n, reserve a n, push a v, pop d a.
            nargs(i, 2, 2);
            const bool result = n == "arraylength" || n == "pop";
            const int array = op.args[result ? 1 : 0];
            const bool resizable = type(array).is_resizable();
            if (op.writes != (n == "pop" ? 3u : 1u) ||
                !(resizable || (n == "arraylength" && type(array).is_array())))
                fail(i, "bad arguments for '" + n + "'");
            return i + 1;
        }
        if (n == "construct" || n == "cast") {
            nargs(i, 3, 18);
            writes_only_result(i);
            for (int a : op.args)
                if (type(a).is_array()) fail(i, "'" + n + "' of an array");
            return i + 1;
        }
        if (n == "getshader" || n == "getlight" || n == "getshaders" ||
            n == "getlights" || n == "getvar" || n == "hasmethod" || n == "callmethod")
            return coshader_op(i);
        if (!detail::is_builtin(n)) fail(i, "unknown operation '" + n + "'");
        return i + 1;
    }

    // The RSL 2.0 co-shader ops (program.h): argument types and write flags.
    int coshader_op(int i) {
        const Op& op = m_p.ops[i];
        const std::string& n = op.name;
        const std::size_t na = op.args.size();
        const TypeSpec shader{ShadingType::Shader, 0};
        bool ok = true;
        if (n == "getshader" || n == "getlight") {
            ok = na == 2 && type(op.args[0]) == shader &&
                 is(op.args[1], ShadingType::String) && op.writes == 1;
        } else if (n == "getshaders" || n == "getlights") {
            ok = na >= 1 && na % 2 == 1 &&
                 type(op.args[0]) == TypeSpec{ShadingType::Shader, kResizableArray} &&
                 op.writes == 1;
            for (std::size_t k = 1; k < na && ok; ++k)
                ok = is(op.args[k], ShadingType::String);
        } else if (n == "hasmethod") {
            ok = na == 3 && is(op.args[0], ShadingType::Float) &&
                 type(op.args[1]) == shader && is(op.args[2], ShadingType::String) &&
                 op.writes == 1;
        } else if (n == "getvar") {
            ok = (na == 3 || na == 4) && is(op.args[0], ShadingType::Float) &&
                 type(op.args[1]) == shader && is(op.args[2], ShadingType::String) &&
                 op.writes == (na == 4 ? 9u : 1u);
        } else { // callmethod d handle "name" args...
            ok = na >= 3 && !type(op.args[0]).is_array() && type(op.args[1]) == shader &&
                 is(op.args[2], ShadingType::String) && (op.writes & 6u) == 0;
        }
        if (!ok) fail(i, "bad arguments for '" + n + "'");
        return i + 1;
    }

    const Program& m_p;
    Reader& m_r;
    const std::vector<int>& m_lines;
};

} // namespace

void write_program(const Program& p, std::ostream& out) {
    out << kMagic << " " << (p.is_class() ? kClassVersion : kVersion) << "\n";
    out << "shader " << shader_kind_name(p.kind) << " " << quote(p.name) << "\n";
    out << "source " << quote(p.source_path) << "\n";
    out << "files " << p.files.size() << "\n";
    for (const std::string& f : p.files) out << "file " << quote(f) << "\n";
    out << "symbols " << p.symbols.size() << "\n";
    for (const Symbol& s : p.symbols) {
        out << "sym " << quote(s.name) << " " << shading_type_name(s.type.type) << " "
            << s.type.array << " " << (s.varying ? "v" : "u") << " " << kind_word(s.kind)
            << " " << s.init_begin << " " << s.init_end << " " << s.numbers.size();
        for (float f : s.numbers) out << " " << number(f);
        out << " " << s.strings.size();
        for (const std::string& str : s.strings) out << " " << quote(str);
        out << "\n";
    }
    out << "ops " << p.ops.size() << "\n";
    for (const Op& op : p.ops) {
        out << "op " << quote(op.name) << " " << op.args.size();
        for (int a : op.args) out << " " << a;
        for (int j : op.jump) out << " " << j;
        out << " " << op.level << " " << op.writes << " " << op.where.file << " "
            << op.where.line << " " << op.where.column << "\n";
    }
    out << "body " << p.body_begin << "\n";
    if (p.is_class()) {
        out << "class " << p.init_end << "\n";
        out << "methods " << p.methods.size() << "\n";
        for (const Method& m : p.methods) {
            out << "method " << quote(m.name) << " " << m.begin << " " << m.end << " "
                << m.result << " " << m.outputs << " " << m.params.size();
            for (int s : m.params) out << " " << s;
            out << "\n";
        }
        out << "pipelines " << p.pipelines.size() << "\n";
        for (const Pipeline& pl : p.pipelines) {
            out << "pipeline " << shader_kind_name(pl.kind) << " " << pl.methods.size();
            for (int m : pl.methods) out << " " << m;
            out << "\n";
        }
    }
    out << "end\n";
}

Program read_program(std::istream& in, const std::string& path) {
    Reader r(in, path);
    Program p;
    r.line(kMagic);
    long version = 0;
    {
        version = r.integer(0, 1000000);
        if (version != kVersion && version != kClassVersion)
            r.fail("unsupported .slo version " + std::to_string(version) +
                   " (this build reads " + std::to_string(kVersion) + " and " +
                   std::to_string(kClassVersion) + ")");
        r.end_of_line();
    }
    r.line("shader");
    {
        p.kind = parse_shader_kind(r, r.word());
        p.name = r.string();
        r.end_of_line();
    }
    r.line("source");
    p.source_path = r.string();
    r.end_of_line();
    r.line("files");
    const long nfiles = r.integer(0, kMaxCount);
    r.end_of_line();
    for (long i = 0; i < nfiles; ++i) {
        r.line("file");
        p.files.push_back(r.string());
        r.end_of_line();
    }
    r.line("symbols");
    const long nsyms = r.integer(0, kMaxCount);
    r.end_of_line();
    std::vector<int> sym_lines;
    for (long i = 0; i < nsyms; ++i) {
        r.line("sym");
        sym_lines.push_back(r.line_number());
        Symbol s;
        s.name = r.string();
        s.type.type = parse_type(r, r.word());
        s.type.array = static_cast<int>(r.integer(kResizableArray, kMaxArrayLength));
        const std::string storage = r.word();
        if (storage != "u" && storage != "v") r.fail("storage must be u or v");
        s.varying = storage == "v";
        s.kind = parse_kind(r, r.word());
        s.init_begin = static_cast<int>(r.integer(-1, kMaxCount));
        s.init_end = static_cast<int>(r.integer(-1, kMaxCount));
        const long nnum = r.integer(0, kMaxCount);
        for (long k = 0; k < nnum; ++k) s.numbers.push_back(r.real());
        const long nstr = r.integer(0, kMaxCount);
        for (long k = 0; k < nstr; ++k) s.strings.push_back(r.string());
        r.end_of_line();
        const std::size_t elems = static_cast<std::size_t>(std::max(s.type.array, 1));
        const bool is_string = s.type.type == ShadingType::String;
        const std::size_t want =
            is_string ? elems : static_cast<std::size_t>(s.type.floats());
        const std::size_t have = is_string ? s.strings.size() : s.numbers.size();
        if ((is_string ? !s.numbers.empty() : !s.strings.empty()) ||
            (have != 0 && have != want))
            r.fail("symbol '" + s.name + "' has the wrong number of values");
        if (s.kind == SymbolKind::Const && have == 0) r.fail("constant without a value");
        if (s.kind == SymbolKind::Const && s.varying)
            r.fail("a constant cannot be varying");
        if (s.type.type == ShadingType::Shader &&
            (s.kind == SymbolKind::Param || s.kind == SymbolKind::OutputParam ||
             s.kind == SymbolKind::Global))
            r.fail("a parameter or global cannot be a shader handle");
        if (s.type.is_resizable() &&
            (s.kind != SymbolKind::Local && s.kind != SymbolKind::Temp))
            r.fail("only locals can be resizable arrays");
        p.symbols.push_back(std::move(s));
    }
    r.line("ops");
    const long nops = r.integer(0, kMaxCount);
    r.end_of_line();
    std::vector<int> op_lines;
    for (long i = 0; i < nops; ++i) {
        r.line("op");
        op_lines.push_back(r.line_number());
        Op op;
        op.name = r.string();
        const long nargs = r.integer(0, 64);
        for (long k = 0; k < nargs; ++k)
            op.args.push_back(static_cast<int>(r.integer(0, nsyms - 1)));
        for (int& j : op.jump) j = static_cast<int>(r.integer(-1, nops));
        op.level = static_cast<int>(r.integer(0, 1000000));
        op.writes = r.bits();
        if (nargs < 64 && (op.writes >> nargs) != 0)
            r.fail("write flag for a missing argument");
        for (std::size_t k = 0; k < op.args.size(); ++k)
            if ((op.writes >> k) & 1) {
                const SymbolKind kind = p.symbols[op.args[k]].kind;
                if (kind == SymbolKind::Const) r.fail("an operation writes a constant");
            }
        op.where.file = static_cast<int>(r.integer(-1, nfiles - 1));
        op.where.line = static_cast<int>(r.integer(0, std::numeric_limits<int>::max()));
        op.where.column = static_cast<int>(r.integer(0, std::numeric_limits<int>::max()));
        r.end_of_line();
        p.ops.push_back(std::move(op));
    }
    r.line("body");
    p.body_begin = static_cast<int>(r.integer(0, nops));
    r.end_of_line();
    if (version == kClassVersion) read_class(r, p);
    r.line("end");
    r.end_of_line();
    while (r.next_line())
        if (!r.blank()) r.fail("unexpected data after 'end'");

    // Parameters: a value, or an init range inside the defaults.
    for (std::size_t i = 0; i < p.symbols.size(); ++i) {
        const Symbol& s = p.symbols[i];
        const bool ranged = s.init_begin != -1 || s.init_end != -1;
        if (ranged && (s.init_begin < 0 || s.init_begin > s.init_end ||
                       s.init_end > p.body_begin)) {
            r.set_line(sym_lines[i]);
            r.fail("bad default range of '" + s.name + "'");
        }
        if (ranged && s.kind != SymbolKind::Param && s.kind != SymbolKind::OutputParam) {
            r.set_line(sym_lines[i]);
            r.fail("only parameters have a default range");
        }
    }
    Validator v(p, r, op_lines);
    v.range(0, p.body_begin, 0);
    v.range(p.body_begin, static_cast<int>(p.ops.size()), 0);
    for (std::size_t i = 0; i < p.symbols.size(); ++i) {
        const Symbol& s = p.symbols[i];
        if (s.init_begin >= 0 && s.init_begin < s.init_end)
            v.range(s.init_begin, s.init_end, 0);
    }
    return p;
}

Program read_program_file(const std::string& path) {
    detail::require_regular_file(path);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path, "cannot open");
    return read_program(in, path);
}

void write_program_file(const Program& program, const std::string& path) {
    AtomicOutput out(path);
    {
        std::ofstream f(out.temp_path(), std::ios::binary | std::ios::trunc);
        if (!f) throw IoError(path, "cannot create");
        write_program(program, f);
        f.flush();
        if (!f) throw IoError(path, "cannot write");
    }
    out.commit();
}

} // namespace sss
