// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_bind.cpp
/// Binding in the shading engine (engine.h): a Program's ops resolved against
/// the operator tables into a BoundProgram, a shader instance's RIB parameters
/// matched against the shader's parameters, and the parameter values (defaults,
/// instance arguments, primitive variables) written into a frame's storage.

#include "sss/shading/engine.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include "engine_internal.h"
#include "sss/util/hash.h"

namespace sss {

namespace detail {

// ---------------------------------------------------------------------------
// Binding

namespace {

const BinderTable& binders() {
    static const BinderTable table = [] {
        BinderTable t;
        register_core_ops(t);
        register_math(t);
        register_geometry(t);
        register_lighting(t);
        register_texture(t);
        register_raytrace(t);
        register_arrays(t);
        register_coshader(t);
        return t;
    }();
    return table;
}

std::string signature_of(const Program& p, const Op& op) {
    std::string s = op.name + "(";
    for (std::size_t k = 0; k < op.args.size(); ++k) {
        if (k) s += ", ";
        const Symbol& sym = p.symbols[op.args[k]];
        s += (sym.varying ? "varying " : "uniform ") + type_spec_name(sym.type);
    }
    return s + ")";
}

struct Validator {
    const Program& p;
    const BoundProgram& bp;
    [[noreturn]] void fail(int i, const std::string& what) const {
        throw ValueError(bp.describe(i) + ": " + what);
    }
    void range(int i, int b, int e, int limit) const {
        if (b < i + 1 || e < b || e > limit)
            fail(i, "'" + p.ops[i].name + "' has a bad jump range [" + std::to_string(b) +
                        ", " + std::to_string(e) + ")");
    }
    /// Checks the structure of ops [begin, end).
    void walk(int begin, int end, int loops, int blocks, bool in_illuminance) const {
        int i = begin;
        while (i < end) {
            const Op& op = p.ops[i];
            const auto& j = op.jump;
            if (op.name == "if") {
                range(i, i + 1, j[0], end);
                range(i, j[0], j[1], end);
                walk(i + 1, j[0], loops, blocks, in_illuminance);
                walk(j[0], j[1], loops, blocks, in_illuminance);
                i = j[1];
            } else if (op.name == "loop") {
                range(i, i + 1, j[0], end);
                range(i, j[0], j[1], end);
                range(i, j[1], j[2], end);
                range(i, j[2], j[3], end);
                walk(i + 1, j[0], loops, blocks, in_illuminance);
                walk(j[0], j[1], loops, blocks, in_illuminance);
                walk(j[1], j[2], loops + 1, blocks, in_illuminance);
                walk(j[2], j[3], loops, blocks, in_illuminance);
                i = j[3];
            } else if (op.name == "gather") {
                // Not a loop level: break/continue inside count the loops outside.
                range(i, i + 1, j[0], end);
                range(i, j[0], j[1], end);
                walk(i + 1, j[0], loops, blocks, in_illuminance);
                walk(j[0], j[1], loops, blocks, in_illuminance);
                i = j[1];
            } else if (op.name == "block") {
                range(i, i + 1, j[0], end);
                walk(i + 1, j[0], loops, blocks + 1, in_illuminance);
                i = j[0];
            } else if (op.name == "illuminance" || op.name == "illuminate" ||
                       op.name == "solar") {
                range(i, i + 1, j[0], end);
                walk(i + 1, j[0], loops, blocks,
                     in_illuminance || op.name == "illuminance");
                i = j[0];
            } else {
                if ((op.name == "break" || op.name == "continue") &&
                    (op.level < 1 || op.level > loops))
                    fail(i, "'" + op.name + " " + std::to_string(op.level) +
                                "' outside " + std::to_string(op.level) + " loops");
                ++i;
            }
        }
    }
};

/// A class shader's methods are blocks among its ops, their parameters and
/// results symbols, its pipelines lists of them.
void validate_class(const Program& p, const Validator& val) {
    const int nops = static_cast<int>(p.ops.size());
    const int nsym = static_cast<int>(p.symbols.size());
    if (p.init_end < p.body_begin || p.init_end > nops) val.fail(-1, "bad class layout");
    for (const Method& m : p.methods) {
        if (m.begin < p.init_end || m.begin >= nops || p.ops[m.begin].name != "block" ||
            p.ops[m.begin].jump[0] != m.end)
            val.fail(-1, "method '" + m.name + "' is not a block of the program");
        if (m.result < -1 || m.result >= nsym || m.params.size() > 63 ||
            (m.outputs >> m.params.size()) != 0)
            val.fail(-1, "method '" + m.name + "' has a bad result or parameters");
        for (int s : m.params)
            if (s < 0 || s >= nsym || p.symbols[s].type.type == ShadingType::Void ||
                p.symbols[s].kind == SymbolKind::Const)
                val.fail(-1, "method '" + m.name + "' has a bad parameter");
        if (m.result >= 0 && p.symbols[m.result].kind == SymbolKind::Const)
            val.fail(-1, "method '" + m.name + "' returns into a constant");
    }
    for (const Pipeline& pl : p.pipelines)
        for (int m : pl.methods)
            if (m < 0 || static_cast<std::size_t>(m) >= p.methods.size())
                val.fail(-1, "a pipeline names a method the shader does not have");
}

bool bind_control(const BindInfo& in, BoundOp& b, std::string& why) {
    const std::string& name = in.op.name;
    const int n = in.nargs();
    if (name == "if" || name == "loop") {
        b.ia = name == "if" ? C_If : C_Loop;
        return n == 1 && in.is_float(0);
    }
    if (name == "break" || name == "continue") {
        b.ia = name == "break" ? C_Break : C_Continue;
        return n == 0;
    }
    if (name == "block") {
        b.ia = C_Block;
        return n == 0;
    }
    if (name == "return") {
        b.ia = C_Return;
        return n == 0;
    }
    if (name == "illuminance") {
        b.ia = C_Illuminance;
        // A co-shader's methods run on the points of the surface calling them.
        if (in.program.kind != ShaderKind::Surface &&
            in.program.kind != ShaderKind::Volume &&
            in.program.kind != ShaderKind::Shader) {
            why = "illuminance is only for surface and volume shaders";
            return false;
        }
        if (n < 4 || (n - 4) % 2 != 0 || !in.is_string(0) || !in.is_ptype(1) ||
            !in.is_triple_(2) || !in.is_float(3))
            return false;
        // Options: "name", value pairs; only "light:..." values are written.
        for (int k = 4; k < n; k += 2) {
            if (!in.is_string(k) || in.writes(k) || in.is_array(k + 1)) return false;
            if (in.writes(k + 1) !=
                (in.program.symbols[in.op.args[k]].strings.size() == 1 &&
                 in.program.symbols[in.op.args[k]].strings[0].rfind("light:", 0) == 0)) {
                why = "illuminance writes an option that is not \"light:...\"";
                return false;
            }
        }
        return !in.writes(0) && !in.writes(1) && !in.writes(2) && !in.writes(3);
    }
    if (name == "gather") {
        b.ia = C_Gather;
        if (in.program.kind != ShaderKind::Surface &&
            in.program.kind != ShaderKind::Light &&
            in.program.kind != ShaderKind::Displacement &&
            in.program.kind != ShaderKind::Shader) {
            why = "gather is only for surface, light and displacement shaders";
            return false;
        }
        if (n < 5 || (n - 5) % 2 != 0 || !in.is_string(0) || !in.is_ptype(1) ||
            !in.is_ptype(2) || !in.is_float(3) || !in.is_float(4))
            return false;
        for (int k = 5; k < n; k += 2)
            if (!in.is_string(k)) return false;
        for (int k = 0; k < n; ++k)
            if (in.writes(k) && (k < 5 || (k - 5) % 2 == 0)) {
                why = "gather writes one of its fixed arguments or option names";
                return false;
            }
        return true;
    }
    if (name == "illuminate" || name == "solar") {
        b.ia = name == "solar" ? C_Solar : C_Illuminate;
        if (in.program.kind != ShaderKind::Light) {
            why = name + " is only for light shaders";
            return false;
        }
        if (name == "illuminate")
            return n == 3 && in.is_ptype(0) && in.is_triple_(1) && in.is_float(2);
        return n == 2 && in.is_triple_(0) && in.is_float(1);
    }
    return false;
}

bool is_control(const std::string& name) {
    return name == "if" || name == "loop" || name == "break" || name == "continue" ||
           name == "block" || name == "return" || name == "illuminance" ||
           name == "illuminate" || name == "solar" || name == "gather";
}

} // namespace

std::shared_ptr<const BoundProgram> bind_program(std::shared_ptr<const Program> program) {
    if (!program) throw ValueError("shading: no program to bind");
    auto bp = std::make_shared<BoundProgram>();
    bp->program = program;
    const Program& p = *program;
    const int nsym = static_cast<int>(p.symbols.size());
    const int nops = static_cast<int>(p.ops.size());
    Validator val{p, *bp};
    auto fail = [&](int i, const std::string& what) { val.fail(i, what); };

    for (int g = 0; g < G_count; ++g) bp->globals[g] = -1;
    for (int s = 0; s < nsym; ++s) {
        const Symbol& sym = p.symbols[s];
        if (sym.type.array < kResizableArray || sym.type.array > kMaxArrayLength)
            fail(-1, "symbol '" + sym.name + "' has a bad array length");
        if (sym.type.is_resizable() &&
            (sym.kind != SymbolKind::Local && sym.kind != SymbolKind::Temp))
            fail(-1, "symbol '" + sym.name + "' is a resizable array but not a local");
        if (sym.type.type == ShadingType::Void && sym.kind != SymbolKind::Temp)
            fail(-1, "symbol '" + sym.name + "' is void");
        const int elements = sym.type.array > 0 ? sym.type.array : 1;
        if (sym.type.type == ShadingType::String) {
            if (!sym.strings.empty() && static_cast<int>(sym.strings.size()) != elements)
                fail(-1, "symbol '" + sym.name + "' has " +
                             std::to_string(sym.strings.size()) + " strings for " +
                             std::to_string(elements) + " elements");
        } else if (!sym.numbers.empty() &&
                   static_cast<int>(sym.numbers.size()) != sym.type.floats()) {
            fail(-1, "symbol '" + sym.name + "' has " +
                         std::to_string(sym.numbers.size()) + " numbers for a " +
                         type_spec_name(sym.type));
        }
        if (sym.kind == SymbolKind::Param || sym.kind == SymbolKind::OutputParam) {
            bp->params.push_back(s);
            const bool has_init = sym.init_begin >= 0 || sym.init_end >= 0;
            if (has_init && (sym.init_begin < 0 || sym.init_end < sym.init_begin ||
                             sym.init_end > p.body_begin))
                fail(-1, "parameter '" + sym.name + "' has a bad default range");
        }
        if (sym.kind == SymbolKind::Global) {
            for (int g = 0; g < G_count; ++g)
                if (sym.name == global_name(g)) {
                    const int want = (g == G_ncomps || g == G_time || g == G_dtime ||
                                      g == G_u || g == G_v || g == G_du || g == G_dv ||
                                      g == G_s || g == G_t || g == G_alpha)
                                         ? 1
                                         : 3;
                    if (sym.type.is_array() || sym.type.floats() != want)
                        fail(-1, "global '" + sym.name + "' has type " +
                                     type_spec_name(sym.type));
                    bp->globals[g] = s;
                }
        }
    }
    if (p.body_begin < 0 || p.body_begin > nops) fail(-1, "bad body start");

    for (int i = 0; i < nops; ++i) {
        const Op& op = p.ops[i];
        for (int a : op.args)
            if (a < 0 || a >= nsym)
                fail(i, "'" + op.name + "' has a bad symbol index " + std::to_string(a));
        if (op.args.size() > 64) fail(i, "'" + op.name + "' has too many arguments");
    }
    // Structure: every parameter default range, then the body.
    for (int s : bp->params) {
        const Symbol& sym = p.symbols[s];
        if (sym.init_begin >= 0) val.walk(sym.init_begin, sym.init_end, 0, 0, false);
    }
    val.walk(p.body_begin, nops, 0, 0, false);
    if (p.is_class()) validate_class(p, val);

    bp->ops.resize(nops);
    const BinderTable& table = binders();
    for (int i = 0; i < nops; ++i) {
        const Op& op = p.ops[i];
        BoundOp& b = bp->ops[i];
        b.op = &op;
        b.index = i;
        BindInfo info{p, op};
        std::string why;
        if (is_control(op.name)) {
            if (!bind_control(info, b, why))
                fail(i, why.empty() ? "bad arguments to '" + signature_of(p, op) + "'"
                                    : why);
            b.fn = nullptr;
            if (op.name == "illuminate" || op.name == "solar") bp->has_illuminate = true;
            continue;
        }
        auto it = table.find(op.name);
        if (it == table.end())
            fail(i, "the engine does not implement the function '" + op.name + "'");
        if (!it->second(info, b, why) || !b.fn)
            fail(i, why.empty() ? "no implementation of '" + signature_of(p, op) + "'"
                                : "'" + op.name + "': " + why);
    }
    return bp;
}

} // namespace detail

// ---------------------------------------------------------------------------
// ShaderInstance

namespace {

ShadingType rib_shading_type(ParamType t) {
    switch (t) {
    case ParamType::Float:
    case ParamType::Integer:
        return ShadingType::Float;
    case ParamType::String:
        return ShadingType::String;
    case ParamType::Color:
        return ShadingType::Color;
    case ParamType::Point:
    case ParamType::HPoint:
        return ShadingType::Point;
    case ParamType::Vector:
        return ShadingType::Vector;
    case ParamType::Normal:
        return ShadingType::Normal;
    case ParamType::Matrix:
        return ShadingType::Matrix;
    }
    return ShadingType::Float;
}

bool same_class(ShadingType a, ShadingType b) {
    return a == b || (is_point_like(a) && is_point_like(b));
}

} // namespace

ShaderInstance::ShaderInstance(std::shared_ptr<const Program> program,
                               const ParamList& params, const Matrix4& shader_to_world,
                               std::string where, std::vector<std::string>* warnings)
    : m_program(std::move(program)), m_shader_to_world(shader_to_world),
      m_where(std::move(where)) {
    if (!m_program) throw ValueError(m_where + ": no shader program");
    const Program& p = *m_program;
    const std::string prefix =
        (m_where.empty() ? "" : m_where + ": ") + "shader '" + p.name + "'";
    m_bound = detail::bind_program(m_program);
    m_argument_of.assign(p.symbols.size(), -1);

    for (const Param& param : params.items) {
        const int s = p.find(param.name);
        if (s < 0 || (p.symbols[s].kind != SymbolKind::Param &&
                      p.symbols[s].kind != SymbolKind::OutputParam)) {
            if (warnings)
                warnings->push_back(prefix + " has no parameter '" + param.name +
                                    "'; ignored");
            continue;
        }
        const Symbol& sym = p.symbols[s];
        const int elements = sym.type.array > 0 ? sym.type.array : 1;
        ShaderArgument arg;
        arg.name = param.name;
        arg.type = TypeSpec{rib_shading_type(param.type),
                            param.array_size > 1 ? param.array_size : 0};
        const std::string got =
            std::string(param_type_name(param.type)) +
            (param.array_size > 1 ? "[" + std::to_string(param.array_size) + "]" : "") +
            " with " +
            std::to_string(param.type == ParamType::String ? param.strings.size()
                                                           : param.numbers.size()) +
            (param.type == ParamType::String ? " strings" : " numbers");
        auto mismatch = [&] {
            throw ValueError(prefix + ": parameter '" + param.name + "' is a " +
                             type_spec_name(sym.type) + ", given a " + got);
        };
        if (sym.type.type == ShadingType::String) {
            if (param.type != ParamType::String ||
                static_cast<int>(param.strings.size()) != elements)
                mismatch();
            arg.strings = param.strings;
        } else {
            if (param.type == ParamType::String) mismatch();
            std::vector<float> numbers;
            if (param.type == ParamType::HPoint) {
                if (param.numbers.size() % 4 != 0) mismatch();
                for (std::size_t k = 0; k + 3 < param.numbers.size(); k += 4) {
                    const double w =
                        param.numbers[k + 3] != 0.0 ? param.numbers[k + 3] : 1.0;
                    for (int c = 0; c < 3; ++c)
                        numbers.push_back(static_cast<float>(param.numbers[k + c] / w));
                }
            } else {
                for (double d : param.numbers) numbers.push_back(static_cast<float>(d));
            }
            const ShadingType given = rib_shading_type(param.type);
            const bool loose_floats = given == ShadingType::Float;
            // One float for a colour, point, vector or normal is replicated,
            // so RIBs written for shaders that took a float ("Kdt" [1])
            // still bind (documented in docs/shading.md).
            if (loose_floats && numbers.size() == 1 && !sym.type.is_array() &&
                is_triple(sym.type.type))
                numbers.assign(3, numbers[0]);
            if (static_cast<int>(numbers.size()) != sym.type.floats()) mismatch();
            if (!loose_floats && !same_class(given, sym.type.type)) mismatch();
            arg.numbers = std::move(numbers);
        }
        m_arguments.push_back(std::move(arg));
        // A parameter given twice takes its last value.
        m_argument_of[std::size_t(s)] = static_cast<int>(m_arguments.size()) - 1;
    }
}

std::optional<std::string>
ShaderInstance::string_parameter(const std::string& name) const {
    for (const ShaderArgument& a : m_arguments)
        if (a.name == name && !a.strings.empty()) return a.strings[0];
    const int s = m_program->find(name);
    if (s < 0) return std::nullopt;
    const Symbol& sym = m_program->symbols[s];
    if ((sym.kind != SymbolKind::Param && sym.kind != SymbolKind::OutputParam) ||
        sym.type.type != ShadingType::String || sym.init_begin != sym.init_end)
        return std::nullopt;
    if (sym.strings.empty()) return std::string();
    return sym.strings[0];
}

std::optional<float> ShaderInstance::float_parameter(const std::string& name) const {
    for (const ShaderArgument& a : m_arguments)
        if (a.name == name && a.numbers.size() == 1) return a.numbers[0];
    const int s = m_program->find(name);
    if (s < 0) return std::nullopt;
    const Symbol& sym = m_program->symbols[s];
    if ((sym.kind != SymbolKind::Param && sym.kind != SymbolKind::OutputParam) ||
        sym.type.type != ShadingType::Float || sym.type.is_array() ||
        sym.init_begin != sym.init_end)
        return std::nullopt;
    if (sym.numbers.empty()) return 0.0f;
    return sym.numbers[0];
}

// ---------------------------------------------------------------------------
// Parameter values

namespace {

/// Writes a ShaderArgument's values into a parameter's slot (converting
/// points, vectors and normals by `m`).
void write_argument(ShadingContext::Impl& ctx, const detail::Slot& sl, const Symbol& sym,
                    const ShaderArgument& a, std::size_t n, const glm::dmat4& m,
                    bool convert) {
    using namespace detail;
    const int nf = sl.nf;
    const bool arg_varying = a.varying;
    const std::size_t reps = sl.varying ? n : 1;
    if (sym.type.type == ShadingType::String) {
        for (std::size_t i = 0; i < reps; ++i)
            for (int e = 0; e < nf; ++e) {
                const std::size_t k = arg_varying ? i * nf + e : e;
                sl.at(i)[e] = k < a.strings.size() ? ctx.intern(a.strings[k]) : 0.0f;
            }
        return;
    }
    for (std::size_t i = 0; i < reps; ++i) {
        float* dst = sl.at(i);
        const std::size_t base = arg_varying ? i * nf : 0;
        if (base + nf > a.numbers.size()) continue;
        std::memcpy(dst, a.numbers.data() + base, sizeof(float) * nf);
        if (convert && is_point_like(sym.type.type))
            for (int e = 0; e + 2 < nf; e += 3)
                st3(dst + e, xform_typed(sym.type.type, m, ld3(dst + e)));
    }
}

/// Whether a primitive variable fits a parameter (count per point).
bool primvar_fits(const Symbol& sym, const ShaderArgument& a, std::size_t n) {
    const int nf = sym.type.floats();
    const std::size_t values = a.varying ? n : 1;
    if (sym.type.type == ShadingType::String)
        return a.type.type == ShadingType::String && a.strings.size() == values * nf;
    if (a.type.type == ShadingType::String) return false;
    if (a.numbers.size() != values * nf) return false;
    return a.type.type == ShadingType::Float || same_class(a.type.type, sym.type.type);
}

} // namespace

void ShadingContext::Impl::init_params(detail::Frame& f, bool primvars) {
    using namespace detail;
    const Program& p = *f.program;
    const ShaderInstance& inst = *f.instance;
    for (int s : f.bound->params) {
        const Symbol& sym = p.symbols[s];
        if (const ShaderArgument* given = inst.argument_of(s)) {
            write_argument(*this, f.slots[s], sym, *given, f.n, f.shader_to_current,
                           true);
        } else if (sym.init_begin >= 0 && sym.init_end > sym.init_begin) {
            std::fill(f.mask.begin(), f.mask.end(), 1);
            f.active = f.n;
            f.run(sym.init_begin, sym.init_end);
        }
    }
    if (primvars && batch) {
        for (const ShaderArgument& a : batch->primvars) {
            const int s = p.find(a.name);
            if (s < 0) continue;
            const Symbol& sym = p.symbols[s];
            if (sym.kind != SymbolKind::Param && sym.kind != SymbolKind::OutputParam)
                continue;
            if (!primvar_fits(sym, a, f.n)) {
                const std::string text = f.bound->describe(-1) +
                                         ": primitive variable '" + a.name +
                                         "' does not fit the parameter (a " +
                                         type_spec_name(sym.type) + "); ignored";
                if (resources.impl().first_time(text)) services.warning(text);
                continue;
            }
            Slot& sl = f.slots[s];
            if (a.varying && !sl.varying) {
                // A varying primitive variable makes the parameter varying.
                const std::size_t need = static_cast<std::size_t>(sl.nf) * f.n;
                extra_storage.emplace_back(need, 0.0f);
                sl.p = extra_storage.back().data();
                sl.varying = true;
                sl.stride = sl.nf;
            }
            write_argument(*this, sl, sym, a, f.n, object_to_current, true);
        }
    }
    std::fill(f.mask.begin(), f.mask.end(), 1);
    f.active = f.n;
    std::fill(f.stop.begin(), f.stop.end(), 0);
}

} // namespace sss
