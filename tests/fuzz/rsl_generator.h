#pragma once
// A deterministic generator of well-typed RSL surface shaders driven by the
// fuzzer's bytes (fuzz_engine.cpp, docs/fuzzing.md): variables of float,
// color, point and string type, fixed and resizable float arrays,
// arithmetic, if/else, for and while loops, user functions (one of them
// recursive in some inputs), texture/environment/textureinfo on files that
// exist in the scratch folder and names that do not, bake3d and texture3d on
// a cloud in the scratch folder, illuminance, concat/format/printf.
//
// Every loop is bounded (at most kMaxTrips trips, nested at most two deep)
// unless `runaway` is set: then about one loop in 256 has a condition that
// may never become false, which the engine's budgets must end (the target
// sets them low; SSS_FUZZ_RUNAWAY=0 leaves such loops out).
//
// Arithmetic that can leave the reals (division, sqrt, log, pow, overflow in
// loops) is allowed: the shader ends with Ci, Oi and its output passed
// through fz_finite(), which maps NaN and infinities to 0, so that the image
// must be finite whatever the body computed.

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace sss::fuzz {

/// Reads choices from the fuzzer's bytes; 0 once they are used up, so every
/// input, however short, gives a complete shader.
class ByteChoices {
public:
    ByteChoices(const uint8_t* data, std::size_t size) : m_data(data), m_size(size) {}
    /// A number in [0, n).
    unsigned pick(unsigned n) {
        if (n <= 1) return 0;
        unsigned v = next();
        if (n > 256) v = v << 8 | next();
        return v % n;
    }
    /// True with probability about num/den.
    bool chance(unsigned num, unsigned den) { return pick(den) < num; }
    bool exhausted() const { return m_pos >= m_size; }

private:
    unsigned next() { return m_pos < m_size ? m_data[m_pos++] : 0u; }
    const uint8_t* m_data;
    std::size_t m_size;
    std::size_t m_pos = 0;
};

/// The files a generated shader names (in the scratch folder, or not at all).
struct GeneratorFiles {
    std::vector<std::string> textures;     ///< exist: 2-D textures
    std::vector<std::string> environments; ///< exist: lat-long maps
    std::string missing = "missing.tx";    ///< does not exist
    std::string cloud = "bake.ptc";        ///< bake3d writes it, texture3d reads it
};

class RslGenerator {
public:
    static constexpr int kMaxTrips = 12;
    static constexpr int kVarsPerType = 3;

    RslGenerator(ByteChoices& in, GeneratorFiles files, bool runaway)
        : m_in(in), m_files(std::move(files)), m_runaway(runaway) {}

    /// The shader's source; its name is `name`.
    std::string shader(const std::string& name) {
        m_missing = m_in.chance(1, 8);
        std::string out = finite_function();
        const int functions = 1 + static_cast<int>(m_in.pick(3));
        for (int i = 0; i < functions; ++i) out += user_function(i);
        m_functions = functions;
        if (m_in.chance(1, 6)) {
            out += recursive_function();
            m_recursive = true;
        }
        out += "surface " + name + "(float Kd = 0.5; string texname = \"" +
               pick_texture() + "\"; output varying color aov = 0;)\n{\n";
        out += declarations();
        const int statements = 2 + static_cast<int>(m_in.pick(10));
        for (int i = 0; i < statements && !m_in.exhausted(); ++i) out += statement(1);
        out += "    Oi = Os;\n";
        out += "    Ci = fz_finite(Oi * (" + color_expr(0) + "));\n";
        out += "    aov = fz_finite(c0);\n}\n";
        return out;
    }

private:
    static std::string indent(int depth) { return std::string(4 * depth, ' '); }

    std::string var(char type) {
        return std::string(1, type) + std::to_string(m_in.pick(kVarsPerType));
    }

    // A missing file stops the render with an error: only some shaders
    // name one, so that most get as far as their output.
    std::string pick_texture() {
        if ((m_missing && m_in.chance(1, 4)) || m_files.textures.empty())
            return m_files.missing;
        return m_files.textures[m_in.pick(unsigned(m_files.textures.size()))];
    }
    std::string pick_environment() {
        if ((m_missing && m_in.chance(1, 4)) || m_files.environments.empty())
            return m_files.missing;
        return m_files.environments[m_in.pick(unsigned(m_files.environments.size()))];
    }

    static std::string finite_function() {
        // abs(NaN) < 1e30 is false, as is abs(inf) < 1e30.
        return "color fz_finite(color c) {\n"
               "    float r = comp(c, 0), g = comp(c, 1), b = comp(c, 2);\n"
               "    return color(abs(r) < 1e30 ? r : 0, abs(g) < 1e30 ? g : 0,\n"
               "                 abs(b) < 1e30 ? b : 0);\n"
               "}\n";
    }

    /// Arithmetic on a function's parameters x and c only (the shader's
    /// variables are not in its scope).
    std::string parameter_expr(int depth) {
        switch (m_in.pick(depth >= 2 ? 3 : 6)) {
        case 0:
            return "x";
        case 1:
            return literal();
        case 2:
            return "comp(c, " + std::to_string(m_in.pick(3)) + ")";
        case 3:
            return "sqrt(" + parameter_expr(depth + 1) + ")";
        default: {
            static const char kOps[] = "+-*/";
            return "(" + parameter_expr(depth + 1) + " " + kOps[m_in.pick(4)] + " " +
                   parameter_expr(depth + 1) + ")";
        }
        }
    }

    std::string user_function(int i) {
        std::string body = "float fn" + std::to_string(i) + "(float x; color c) {\n";
        body += "    float y = " + parameter_expr(0) + ";\n";
        if (m_in.chance(1, 2))
            body += "    y += comp(c, " + std::to_string(m_in.pick(3)) + ");\n";
        body += "    return y * " + literal() + ";\n}\n";
        return body;
    }

    static std::string recursive_function() {
        // The compiler inlines calls (at most 64 deep): expect its error.
        return "float rec(float x; float d) {\n"
               "    if (d <= 0) return x;\n"
               "    return rec(x * 0.5, d - 1) + 1;\n"
               "}\n";
    }

    std::string declarations() {
        std::string out;
        for (int i = 0; i < kVarsPerType; ++i) {
            const std::string n = std::to_string(i);
            out += "    float f" + n + " = " + literal() + ";\n";
            out += "    color c" + n + " = color(" + literal() + ", " + literal() + ", " +
                   literal() + ");\n";
            out += "    point p" + n + " = P;\n";
            out += "    string s" + n + " = \"" + (i == 0 ? pick_texture() : "s" + n) +
                   "\";\n";
        }
        out += "    float i0 = 0, i1 = 0, i2 = 0, w0 = 0, w1 = 0, w2 = 0;\n";
        out += "    float a0[4] = {1, 2, 3, 4};\n";
        out += "    float r0[] = {0};\n";
        return out;
    }

    std::string literal() {
        static const char* const kValues[] = {"0",    "1",     "0.5",  "2",
                                              "-1",   "3.5",   "0.01", "100",
                                              "1e-6", "-0.25", "7",    "1e6"};
        return kValues[m_in.pick(sizeof kValues / sizeof kValues[0])];
    }

    std::string float_expr(int depth) {
        const unsigned n = depth >= 3 ? 6 : 19;
        switch (m_in.pick(n)) {
        case 0:
            return literal();
        case 1:
            return var('f');
        case 2:
            return m_in.chance(1, 2) ? "s" : "t";
        case 3:
            return m_in.chance(1, 2) ? "u" : "v";
        case 4:
            return "comp(" + var('c') + ", " + std::to_string(m_in.pick(3)) + ")";
        case 5:
            return "a0[" + std::to_string(m_in.pick(4)) + "]";
        case 6:
            return "area(P)";
        case 7:
        case 8: {
            static const char kOps[] = "+-*/";
            return "(" + float_expr(depth + 1) + " " + kOps[m_in.pick(4)] + " " +
                   float_expr(depth + 1) + ")";
        }
        case 9: {
            static const char* const kOne[] = {"sin",   "cos", "sqrt", "abs",
                                               "floor", "log", "exp",  "sign"};
            return std::string(kOne[m_in.pick(8)]) + "(" + float_expr(depth + 1) + ")";
        }
        case 10:
            return std::string(m_in.chance(1, 2) ? "pow" : "mod") + "(" +
                   float_expr(depth + 1) + ", " + float_expr(depth + 1) + ")";
        case 11:
            return "length(" + var('p') + " - P)";
        case 12:
            return std::string("float texture(") +
                   (m_in.chance(1, 2) ? "s0" : "texname") + "[" +
                   std::to_string(m_in.pick(4)) + "], s, t, \"blur\", " + literal() + ")";
        case 13:
            return m_functions > 0
                       ? "fn" + std::to_string(m_in.pick(unsigned(m_functions))) + "(" +
                             float_expr(depth + 1) + ", " + color_expr(depth + 1) + ")"
                       : literal();
        case 14:
            return m_recursive ? "rec(" + float_expr(depth + 1) + ", " + literal() + ")"
                               : var('f');
        case 15:
            // Now and then possibly out of range: the engine's checks.
            if (m_in.chance(1, 4)) return "a0[floor(" + float_expr(depth + 1) + ")]";
            return "a0[clamp(floor(" + float_expr(depth + 1) + "), 0, 3)]";
        case 16:
            return "arraylength(r0)";
        case 17:
            return "clamp(" + float_expr(depth + 1) + ", 0, " + literal() + ")";
        default:
            return "float noise(" + var('p') + ")";
        }
    }

    std::string color_expr(int depth) {
        switch (m_in.pick(depth >= 3 ? 3 : 12)) {
        case 0:
            return var('c');
        case 1:
            return "Cs";
        case 2:
            return "color(" + literal() + ", " + literal() + ", " + literal() + ")";
        case 3:
            return "(" + color_expr(depth + 1) + (m_in.chance(1, 2) ? " + " : " * ") +
                   color_expr(depth + 1) + ")";
        case 4:
            return "(" + color_expr(depth + 1) + " * " + float_expr(depth + 1) + ")";
        case 5:
            return "color texture(" + texture_name() + ", s, t, \"width\", " + literal() +
                   ", \"filter\", \"" + (m_in.chance(1, 2) ? "gaussian" : "box") + "\")";
        case 6:
            return "color environment(\"" + pick_environment() + "\", normalize(" +
                   var('p') + " - point(0, 0, 0)))";
        case 7:
            return "ambient() + diffuse(normalize(N))";
        case 8:
            return "mix(" + color_expr(depth + 1) + ", " + color_expr(depth + 1) + ", " +
                   float_expr(depth + 1) + ")";
        case 9:
            return "color(" + float_expr(depth + 1) + ", " + float_expr(depth + 1) +
                   ", " + float_expr(depth + 1) + ")";
        case 10:
            return "color noise(" + var('p') + ")";
        default:
            return "specular(normalize(N), normalize(-I), " + literal() + ")";
        }
    }

    std::string point_expr(int depth) {
        switch (m_in.pick(depth >= 3 ? 2 : 5)) {
        case 0:
            return var('p');
        case 1:
            return "P";
        case 2:
            return "(" + point_expr(depth + 1) + " + vector(" + float_expr(depth + 1) +
                   ", " + literal() + ", " + literal() + "))";
        case 3:
            return "transform(\"object\", " + point_expr(depth + 1) + ")";
        default:
            return "point(" + float_expr(depth + 1) + ", " + float_expr(depth + 1) +
                   ", " + literal() + ")";
        }
    }

    /// A texture's name: a file (s0 holds only names of files).
    std::string texture_name() {
        switch (m_in.pick(3)) {
        case 0:
            return "s0";
        case 1:
            return "texname";
        default:
            return "\"" + pick_texture() + "\"";
        }
    }

    std::string string_expr(int depth) {
        switch (m_in.pick(depth >= 3 ? 3 : 6)) {
        case 0:
            return var('s');
        case 1:
            return "\"" + pick_texture() + "\"";
        case 2:
            return texture_name();
        case 3:
            // One side a literal: in a loop, strings grow linearly, not doubling.
            return "concat(" + string_expr(depth + 1) + ", \"" + pick_texture() + "\")";
        case 4:
            return "format(\"%s%.0f\", " + string_expr(depth + 1) + ", " +
                   float_expr(depth + 1) + ")";
        default:
            return "concat(\"s\", \"" + pick_texture() + "\")";
        }
    }

    std::string assignment(int depth) {
        const std::string in = indent(depth);
        switch (m_in.pick(8)) {
        case 0:
            return in + var('f') + " = " + float_expr(0) + ";\n";
        case 1:
            return in + var('f') + (m_in.chance(1, 2) ? " += " : " *= ") + float_expr(1) +
                   ";\n";
        case 2:
            return in + var('c') + " = " + color_expr(0) + ";\n";
        case 3:
            return in + var('c') + " += " + color_expr(1) + ";\n";
        case 4:
            return in + var('p') + " = " + point_expr(0) + ";\n";
        case 5:
            if (m_in.chance(1, 2)) return in + "s0 = " + texture_name() + ";\n";
            return in + "s" + std::to_string(1 + m_in.pick(2)) + " = " + string_expr(0) +
                   ";\n";
        case 6:
            return in + "a0[" + std::to_string(m_in.pick(4)) + "] = " + float_expr(1) +
                   ";\n";
        default:
            return in + "push(r0, " + float_expr(1) + ");\n";
        }
    }

    std::string loop(int depth) {
        const std::string in = indent(depth);
        const std::string i = std::to_string(depth - 1); // own counter per level
        const std::string trips = std::to_string(m_in.pick(kMaxTrips + 1));
        std::string head, step;
        const unsigned kind = m_in.pick(4);
        if (m_runaway && m_in.pick(256) == 0) {
            // May never end: the step can be 0 or carry w away from the bound.
            head = in + "while (w" + i + " < " + trips + ") {\n";
            step = indent(depth + 1) + "w" + i + " += " + float_expr(2) + ";\n";
        } else if (kind == 0) {
            head = in + "for (i" + i + " = 0; i" + i + " < " + trips + "; i" + i +
                   " += 1) {\n";
        } else if (kind == 1) {
            head =
                in + "w" + i + " = 0;\n" + in + "while (w" + i + " < " + trips + ") {\n";
            step = indent(depth + 1) + "w" + i + " += 1;\n";
        } else {
            // Looks unbounded; the counter's break ends it.
            head = in + "w" + i + " = 0;\n" + in + "while (1) {\n";
            step = indent(depth + 1) + "w" + i + " += 1;\n" + indent(depth + 1) +
                   "if (w" + i + " > " + trips + ") break;\n";
        }
        std::string body = head + step;
        const int n = 1 + static_cast<int>(m_in.pick(3));
        for (int k = 0; k < n; ++k) body += statement(depth + 1);
        if (m_in.chance(1, 4))
            body += indent(depth + 1) + "if (" + float_expr(2) + " > " + literal() +
                    ") " + (m_in.chance(1, 2) ? "break" : "continue") + ";\n";
        return body + in + "}\n";
    }

    std::string statement(int depth) {
        const std::string in = indent(depth);
        const unsigned n = depth >= 3 ? 1 : 11;
        switch (m_in.pick(n)) {
        case 0:
            return assignment(depth);
        case 1:
            return assignment(depth);
        case 2:
        case 3:
            return loop(depth);
        case 4: {
            std::string out = in + "if (" + float_expr(1) + " < " + float_expr(1) +
                              ") {\n" + statement(depth + 1) + in + "}";
            if (m_in.chance(1, 2)) out += " else {\n" + statement(depth + 1) + in + "}";
            return out + "\n";
        }
        case 5:
            return in + "illuminance(P, normalize(N), PI / 2) {\n" + indent(depth + 1) +
                   var('c') + " += Cl * max(0, normalize(L) . normalize(N));\n" + in +
                   "}\n";
        case 6:
            return in + "bake3d(\"" + m_files.cloud + "\", \"_f,_c\", P, normalize(N), " +
                   "\"interpolate\", 1, \"_f\", " + float_expr(1) + ", \"_c\", " +
                   color_expr(1) + ");\n";
        case 7:
            return in + "texture3d(\"" + m_files.cloud + "\", P, normalize(N), \"_f\", " +
                   var('f') + ", \"_c\", " + var('c') + ");\n";
        case 8:
            return in + "printf(\"%f %c %s\\n\", " + float_expr(1) + ", " +
                   color_expr(1) + ", " + string_expr(1) + ");\n";
        case 9:
            return in + "textureinfo(" + texture_name() + ", \"channels\", " + var('f') +
                   ");\n";
        default:
            return in + var('c') + " += color texture(" + texture_name() +
                   ", s, t, s + 0.1, t, s, t + 0.1, s + 0.1, t + 0.1);\n";
        }
    }

    ByteChoices& m_in;
    GeneratorFiles m_files;
    bool m_runaway;
    int m_functions = 0;
    bool m_missing = false; // may name a texture that does not exist
    bool m_recursive = false;
};

} // namespace sss::fuzz
