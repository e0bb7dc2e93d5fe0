/// \file engine.cpp
/// The shading engine (engine.h): shader instances and their parameters,
/// frames (storage per symbol, constants, globals, parameter defaults), the
/// interpreter with its running mask and structured control flow, spaces,
/// and the batch entry point. Binding is in engine_bind.cpp, operators and
/// built-ins in the other engine_*.cpp files.
///
/// Control flow under a mask (shading.md 3.2): every point has a stop code
/// (0: running). `break n` / `continue n` / `return` set it for the running
/// points and clear them from the running mask; each construct, when it
/// ends, restores its entry mask minus the stopped points. A loop resets the
/// codes of its own continue after the body and of its own break after the
/// loop, a block those of its returns; a return outside any block stops the
/// point for the rest of the shader. Branches with no running point are
/// skipped, and so is everything after the last running point stops.

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

#include "texture_library.h"

namespace sss {

namespace detail {

const char* global_name(int g) {
    static const char* const kNames[G_count] = {
        "P",  "N",  "Ng", "I",      "E",    "dPdu",  "dPdv",    "Cs",   "Os",
        "u",  "v",  "du", "dv",     "s",    "t",     "Ci",      "Oi",   "L",
        "Cl", "Ol", "Ps", "ncomps", "time", "dtime", "dPdtime", "alpha"};
    return g >= 0 && g < G_count ? kNames[g] : "?";
}

std::string BoundProgram::where(int index) const {
    const Program& p = *program;
    if (index >= 0 && static_cast<std::size_t>(index) < p.ops.size()) {
        const SourceLocation& w = p.ops[index].where;
        std::string file =
            w.file >= 0 && static_cast<std::size_t>(w.file) < p.files.size()
                ? p.files[w.file]
                : p.source_path;
        if (file.empty()) file = "<" + p.name + ">";
        if (w.line > 0) return file + ":" + std::to_string(w.line);
        return file;
    }
    return p.source_path.empty() ? "<" + p.name + ">" : p.source_path;
}

std::string BoundProgram::describe(int index) const {
    return where(index) + ": shader '" + program->name + "'";
}

glm::vec3 xform_point(const glm::dmat4& m, const glm::vec3& p) {
    const glm::dvec4 q = m * glm::dvec4(glm::dvec3(p), 1.0);
    if (q.w != 1.0 && q.w != 0.0) return glm::vec3(glm::dvec3(q) / q.w);
    return glm::vec3(q);
}

glm::vec3 xform_vector(const glm::dmat4& m, const glm::vec3& v) {
    return glm::vec3(glm::dmat3(m) * glm::dvec3(v));
}

glm::vec3 xform_normal(const glm::dmat4& m, const glm::vec3& n) {
    return glm::vec3(glm::transpose(glm::inverse(glm::dmat3(m))) * glm::dvec3(n));
}

glm::vec3 xform_typed(ShadingType t, const glm::dmat4& m, const glm::vec3& v) {
    switch (t) {
    case ShadingType::Point:
        return xform_point(m, v);
    case ShadingType::Vector:
        return xform_vector(m, v);
    case ShadingType::Normal:
        return xform_normal(m, v);
    default:
        return v;
    }
}

uint64_t point_hash(uint64_t seed, std::size_t point, int op, uint32_t call) {
    uint64_t h = splitmix64(seed ^ 0x72736c72616e64ull);
    h = splitmix64(h ^ static_cast<uint64_t>(point));
    h = splitmix64(h ^ (static_cast<uint64_t>(static_cast<uint32_t>(op)) << 32 | call));
    return h;
}

// ---------------------------------------------------------------------------
// Frame

std::size_t Frame::first_active() const {
    if (active == n) return 0;
    for (std::size_t i = 0; i < n; ++i)
        if (mask[i]) return i;
    return n;
}

void Frame::recount() {
    std::size_t c = 0;
    for (std::size_t i = 0; i < n; ++i) c += mask[i] ? 1u : 0u;
    active = c;
}

std::vector<uint8_t>& Frame::push_mask() {
    if (static_cast<std::size_t>(mask_depth) >= mask_pool.size())
        mask_pool.emplace_back();
    std::vector<uint8_t>& m = mask_pool[mask_depth++];
    m.resize(n);
    return m;
}

void Frame::restore_mask(const std::vector<uint8_t>& entry) {
    std::size_t c = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const uint8_t on = entry[i] && stop[i] == 0;
        mask[i] = on;
        c += on;
    }
    active = c;
}

bool Frame::writes_varying(const BoundOp& b) const {
    const Op& op = *b.op;
    for (std::size_t k = 0; k < op.args.size() && k < 64; ++k)
        if (((op.writes >> k) & 1u) && slots[op.args[k]].varying) return true;
    return false;
}

void Frame::fail(const BoundOp& b, const std::string& what) const {
    throw ShaderRuntimeError(bound->describe(b.index) + ": " + what);
}

void Frame::warn_once(const BoundOp& b, const std::string& what) const {
    const std::string text = bound->describe(b.index) + ": " + what;
    if (ctx->resources.impl().first_time(text)) ctx->services.warning(text);
}

namespace {

enum Control : int {
    C_None = 0,
    C_If,
    C_Loop,
    C_Break,
    C_Continue,
    C_Block,
    C_Return,
    C_Illuminance,
    C_Illuminate,
    C_Solar,
    C_Gather
};

inline uint32_t stop_code(uint32_t kind, int depth) {
    return kind | (static_cast<uint32_t>(depth) << 2);
}

/// Restores `entry` minus the stopped points as the running mask.
void restore(Frame& f, const std::vector<uint8_t>& entry) {
    f.restore_mask(entry);
}

/// Points with stop code `code` run again.
void resume(Frame& f, uint32_t code) {
    for (std::size_t i = 0; i < f.n; ++i)
        if (f.stop[i] == code) f.stop[i] = 0;
}

/// Stops the running points with `code`.
void stop_running(Frame& f, uint32_t code) {
    for (std::size_t i = 0; i < f.n; ++i)
        if (f.mask[i]) {
            f.stop[i] = code;
            f.mask[i] = 0;
        }
    f.active = 0;
}

/// mask = parent && (cond != 0) (or == 0 when `invert`).
void cond_mask(const Slot& c, const std::vector<uint8_t>& parent, bool invert,
               std::size_t n, std::vector<uint8_t>& out) {
    for (std::size_t i = 0; i < n; ++i) {
        const bool t = (*c.at(i) != 0.0f) != invert;
        out[i] = parent[i] && t;
    }
}

} // namespace

// Declared in engine_lighting.cpp.
void run_illuminance(Frame& f, const BoundOp& b, int body_begin, int body_end);
void run_illuminate(Frame& f, const BoundOp& b, int body_begin, int body_end, bool solar);
// Declared in engine_raytrace.cpp.
void run_gather(Frame& f, const BoundOp& b, int hit_end, int miss_end);

void Frame::run(int begin, int end) {
    const std::vector<BoundOp>& ops = bound->ops;
    int i = begin;
    while (i < end) {
        if (active == 0) return;
        const BoundOp& b = ops[i];
        if (b.fn) {
            b.fn(*this, b);
            ++i;
            continue;
        }
        const Op& op = *b.op;
        switch (b.ia) {
        case C_If: {
            const Slot& c = slot(b, 0);
            std::vector<uint8_t>& entry = push_mask();
            entry = mask;
            if (!c.varying) {
                if (*c.p != 0.0f)
                    run(i + 1, op.jump[0]);
                else
                    run(op.jump[0], op.jump[1]);
            } else {
                std::vector<uint8_t>& other = push_mask();
                cond_mask(c, entry, true, n, other);
                cond_mask(c, entry, false, n, mask);
                recount();
                if (active > 0 && op.jump[0] > i + 1) run(i + 1, op.jump[0]);
                if (op.jump[1] > op.jump[0]) {
                    for (std::size_t k = 0; k < n; ++k)
                        mask[k] = other[k] && stop[k] == 0;
                    recount();
                    if (active > 0) run(op.jump[0], op.jump[1]);
                }
                pop_mask();
            }
            restore(*this, entry);
            pop_mask();
            i = op.jump[1];
            break;
        }
        case C_Loop: {
            std::vector<uint8_t>& entry = push_mask();
            entry = mask;
            std::vector<uint8_t>& body = push_mask();
            const int depth = ++loop_depth;
            run(i + 1, op.jump[0]);
            const Slot& c = slot(b, 0);
            long iterations = 0;
            while (active > 0) {
                run(op.jump[0], op.jump[1]);
                if (active == 0) break;
                if (!c.varying) {
                    if (*c.p == 0.0f) break;
                } else {
                    std::size_t cnt = 0;
                    for (std::size_t k = 0; k < n; ++k) {
                        const uint8_t on = mask[k] && *c.at(k) != 0.0f;
                        mask[k] = on;
                        cnt += on;
                    }
                    active = cnt;
                    if (active == 0) break;
                }
                if (++iterations > ShadingContext::kMaxLoopIterations)
                    fail(b, "loop does not end (more than " +
                                std::to_string(ShadingContext::kMaxLoopIterations) +
                                " iterations)");
                body = mask;
                run(op.jump[1], op.jump[2]);
                resume(*this, stop_code(StopContinue, depth));
                restore(*this, body);
                run(op.jump[2], op.jump[3]);
            }
            resume(*this, stop_code(StopBreak, depth));
            --loop_depth;
            restore(*this, entry);
            pop_mask();
            pop_mask();
            i = op.jump[3];
            break;
        }
        case C_Break:
        case C_Continue: {
            const int target = loop_depth - op.level + 1;
            stop_running(*this,
                         stop_code(b.ia == C_Break ? StopBreak : StopContinue, target));
            ++i;
            break;
        }
        case C_Block: {
            std::vector<uint8_t>& entry = push_mask();
            entry = mask;
            const int depth = ++block_depth;
            run(i + 1, op.jump[0]);
            resume(*this, stop_code(StopReturn, depth));
            --block_depth;
            restore(*this, entry);
            pop_mask();
            i = op.jump[0];
            break;
        }
        case C_Return:
            stop_running(*this, stop_code(StopReturn, block_depth));
            ++i;
            break;
        case C_Illuminance:
            run_illuminance(*this, b, i + 1, op.jump[0]);
            i = op.jump[0];
            break;
        case C_Illuminate:
        case C_Solar:
            run_illuminate(*this, b, i + 1, op.jump[0], b.ia == C_Solar);
            i = op.jump[0];
            break;
        case C_Gather:
            run_gather(*this, b, op.jump[0], op.jump[1]);
            i = op.jump[1];
            break;
        default:
            fail(b, "unbound op '" + op.name + "'");
        }
    }
}

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
        if (in.program.kind != ShaderKind::Surface &&
            in.program.kind != ShaderKind::Volume) {
            why = "illuminance is only for surface and volume shaders";
            return false;
        }
        return n == 4 && in.is_string(0) && in.is_ptype(1) && in.is_triple_(2) &&
               in.is_float(3);
    }
    if (name == "gather") {
        b.ia = C_Gather;
        if (in.program.kind != ShaderKind::Surface &&
            in.program.kind != ShaderKind::Light &&
            in.program.kind != ShaderKind::Displacement) {
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
        if (sym.type.array < 0 || sym.type.array > (1 << 20))
            fail(-1, "symbol '" + sym.name + "' has a bad array length");
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

const char* ray_kind_name(RayKind kind) {
    switch (kind) {
    case RayKind::Camera:
        return "camera";
    case RayKind::Diffuse:
        return "diffuse";
    case RayKind::Specular:
        return "specular";
    case RayKind::Transmission:
        return "transmission";
    }
    return "camera";
}

void ShadingServices::transmit(const ShadowRay* rays, std::size_t count, glm::vec3* out,
                               int depth) {
    (void)depth;
    const RayTracer* rt = occluders();
    if (!rt || count == 0) {
        std::fill(out, out + count, glm::vec3(1.0f));
        return;
    }
    std::vector<uint8_t> hit(count);
    rt->occluded(rays, count, hit.data());
    for (std::size_t r = 0; r < count; ++r) out[r] = glm::vec3(hit[r] ? 0.0f : 1.0f);
}

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
// ShadingResources

ShadingResources::Impl::Impl() {
    textures = std::make_unique<detail::TextureLibrary>();
}
ShadingResources::Impl::~Impl() = default;

bool ShadingResources::Impl::first_time(const std::string& text) const {
    std::lock_guard<std::mutex> lock(warned_mutex);
    return warned.insert(text).second;
}

ShadingResources::ShadingResources() : m_impl(std::make_unique<Impl>()) {}
ShadingResources::~ShadingResources() = default;

// ---------------------------------------------------------------------------
// ShadingContext

float ShadingContext::Impl::intern(const std::string& s) {
    auto it = string_index.find(s);
    if (it != string_index.end()) return static_cast<float>(it->second);
    if (strings.size() >= (1u << 24))
        throw ShaderRuntimeError("shading: too many strings in one batch");
    const int idx = static_cast<int>(strings.size());
    strings.push_back(s);
    string_index.emplace(s, idx);
    return static_cast<float>(idx);
}

void ShadingContext::Impl::reset_strings() {
    strings.clear();
    string_index.clear();
    intern("");
}

bool ShadingContext::Impl::space_to_current(const std::string& space,
                                            const detail::Frame& f, glm::dmat4& m) const {
    if (space == "current" || space == "camera") {
        m = glm::dmat4(1.0);
        return true;
    }
    if (space == "world") {
        m = world_to_camera;
        return true;
    }
    if (space == "object") {
        m = object_to_current;
        return true;
    }
    if (space == "shader") {
        m = f.shader_to_current;
        return true;
    }
    const Scene& scene = services.scene();
    if (space == "screen" || space == "raster" || space == "NDC") {
        const Camera& cam = scene.options.camera;
        // x and y as PRMan's screen/NDC/raster; depth as 1/z (perspective) or
        // z (orthographic): the depth-mapped z of Camera::world_to_ndc is
        // 1 - near/z, which a float cannot tell apart from 1 with the default
        // near clip, and the spaces must round-trip.
        glm::dmat4 proj(1.0);
        if (cam.perspective) {
            const double c = 1.0 / std::tan(cam.fov * 3.14159265358979323846 / 360.0);
            proj = glm::dmat4(0.0);
            proj[0][0] = c;
            proj[1][1] = c;
            proj[3][2] = 1.0;
            proj[2][3] = 1.0;
        }
        const auto window = cam.resolved_screen_window();
        glm::dmat4 window_to_ndc(1.0);
        window_to_ndc[0][0] = 1.0 / (window[1] - window[0]);
        window_to_ndc[3][0] = -window[0] / (window[1] - window[0]);
        window_to_ndc[1][1] = -1.0 / (window[3] - window[2]);
        window_to_ndc[3][1] = window[3] / (window[3] - window[2]);
        const glm::dmat4 camera_to_ndc = window_to_ndc * proj;
        glm::dmat4 to;
        if (space == "NDC") {
            to = camera_to_ndc;
        } else if (space == "raster") {
            glm::dmat4 s(1.0);
            s[0][0] = cam.xres;
            s[1][1] = cam.yres;
            to = s * camera_to_ndc;
        } else {
            const auto sw = cam.resolved_screen_window();
            glm::dmat4 screen_to_ndc(1.0);
            screen_to_ndc[0][0] = 1.0 / (sw[1] - sw[0]);
            screen_to_ndc[3][0] = -sw[0] / (sw[1] - sw[0]);
            screen_to_ndc[1][1] = -1.0 / (sw[3] - sw[2]);
            screen_to_ndc[3][1] = sw[3] / (sw[3] - sw[2]);
            to = glm::inverse(screen_to_ndc) * camera_to_ndc;
        }
        m = glm::inverse(to);
        return true;
    }
    auto it = scene.coordinate_systems.find(space);
    if (it != scene.coordinate_systems.end()) {
        m = world_to_camera * it->second;
        return true;
    }
    return false;
}

void ShadingContext::Impl::setup_frame(detail::Frame& f, const ShaderInstance& instance,
                                       std::size_t n) {
    using namespace detail;
    f.ctx = this;
    f.instance = &instance;
    f.bound = &instance.bound();
    f.program = &instance.program();
    f.n = n;
    const Program& p = *f.program;
    const std::size_t nsym = p.symbols.size();
    f.slots.resize(nsym);
    std::size_t total = 0;
    for (std::size_t s = 0; s < nsym; ++s) {
        const Symbol& sym = p.symbols[s];
        const int nf = sym.type.floats();
        total += static_cast<std::size_t>(nf) * (sym.varying ? n : 1);
    }
    f.arena.assign(total, 0.0f);
    std::size_t off = 0;
    for (std::size_t s = 0; s < nsym; ++s) {
        const Symbol& sym = p.symbols[s];
        Slot& sl = f.slots[s];
        sl.nf = sym.type.floats();
        sl.varying = sym.varying;
        sl.stride = sym.varying ? sl.nf : 0;
        sl.p = f.arena.data() + off;
        off += static_cast<std::size_t>(sl.nf) * (sym.varying ? n : 1);
        // Constants and constant defaults.
        if (sym.type.type == ShadingType::String) {
            if (!sym.strings.empty()) {
                for (std::size_t e = 0; e < sym.strings.size(); ++e) {
                    const float v = intern(sym.strings[e]);
                    const std::size_t reps = sym.varying ? n : 1;
                    for (std::size_t i = 0; i < reps; ++i) sl.at(i)[e] = v;
                }
            }
        } else if (!sym.numbers.empty()) {
            const std::size_t reps = sym.varying ? n : 1;
            for (std::size_t i = 0; i < reps; ++i)
                std::memcpy(sl.at(i), sym.numbers.data(), sizeof(float) * sl.nf);
        }
    }
    f.mask.assign(n, 1);
    f.active = n;
    f.stop.assign(n, 0);
    f.loop_depth = 0;
    f.block_depth = 0;
    f.mask_depth = 0;
    f.calls.assign(p.ops.size(), 0);
    f.shader_to_current = world_to_camera * instance.shader_to_world();
    f.lit.assign(n, 0);
    f.light_L.assign(n, glm::vec3(0.0f));
    f.in_illuminate = false;
    f.solar = false;
    f.current_light = -1;
}

namespace {

void fill3(const detail::Slot& sl, std::size_t n, const std::vector<glm::vec3>* src,
           const glm::vec3& fallback) {
    const std::size_t reps = sl.varying ? n : 1;
    const bool ok = src && src->size() >= n && n > 0;
    for (std::size_t i = 0; i < reps; ++i)
        detail::st3(sl.at(i), ok ? (*src)[i] : fallback);
}

void fill1(const detail::Slot& sl, std::size_t n, const std::vector<float>* src,
           float fallback) {
    const std::size_t reps = sl.varying ? n : 1;
    const bool ok = src && src->size() >= n && n > 0;
    for (std::size_t i = 0; i < reps; ++i) *sl.at(i) = ok ? (*src)[i] : fallback;
}

} // namespace

void ShadingContext::Impl::load_surface_globals(detail::Frame& f) {
    using namespace detail;
    const ShadingBatch& b = *batch;
    const std::size_t n = f.n;
    const int* g = f.bound->globals;
    auto sl = [&](int id) -> const Slot* {
        return g[id] >= 0 ? &f.slots[g[id]] : nullptr;
    };
    auto has = [&](const std::vector<glm::vec3>& v) { return v.size() >= n && n > 0; };
    const Attributes* attr = b.primitive ? &attributes_of(*b.primitive) : nullptr;
    const glm::vec3 cs = attr ? glm::vec3(attr->color) : glm::vec3(1.0f);
    const glm::vec3 os = attr ? glm::vec3(attr->opacity) : glm::vec3(1.0f);
    if (auto* s = sl(G_P)) fill3(*s, n, &b.P, glm::vec3(0.0f));
    if (auto* s = sl(G_N)) fill3(*s, n, has(b.N) ? &b.N : &b.Ng, glm::vec3(0.0f));
    if (auto* s = sl(G_Ng)) fill3(*s, n, has(b.Ng) ? &b.Ng : &b.N, glm::vec3(0.0f));
    if (auto* s = sl(G_I)) fill3(*s, n, has(b.I) ? &b.I : &b.P, glm::vec3(0.0f));
    if (auto* s = sl(G_E)) fill3(*s, n, nullptr, glm::vec3(0.0f));
    if (auto* s = sl(G_dPdu)) fill3(*s, n, &b.dPdu, glm::vec3(0.0f));
    if (auto* s = sl(G_dPdv)) fill3(*s, n, &b.dPdv, glm::vec3(0.0f));
    if (auto* s = sl(G_Cs)) fill3(*s, n, &b.Cs, cs);
    if (auto* s = sl(G_Os)) fill3(*s, n, &b.Os, os);
    if (auto* s = sl(G_Oi)) fill3(*s, n, &b.Os, os);
    if (auto* s = sl(G_u)) fill1(*s, n, &b.u, 0.0f);
    if (auto* s = sl(G_v)) fill1(*s, n, &b.v, 0.0f);
    if (auto* s = sl(G_du)) fill1(*s, n, &b.du, 0.0f);
    if (auto* s = sl(G_dv)) fill1(*s, n, &b.dv, 0.0f);
    if (auto* s = sl(G_s)) fill1(*s, n, b.s.size() >= n ? &b.s : &b.u, 0.0f);
    if (auto* s = sl(G_t)) fill1(*s, n, b.t.size() >= n ? &b.t : &b.v, 0.0f);
    if (auto* s = sl(G_ncomps)) fill1(*s, n, nullptr, 3.0f);
    if (auto* s = sl(G_time)) fill1(*s, n, nullptr, b.time);
    if (auto* s = sl(G_alpha)) fill1(*s, n, nullptr, 1.0f);
}

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
        const ShaderArgument* given = nullptr;
        for (const ShaderArgument& a : inst.arguments())
            if (a.name == sym.name) given = &a;
        if (given) {
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

void ShadingContext::Impl::run_body(detail::Frame& f) {
    f.run(f.program->body_begin, static_cast<int>(f.program->ops.size()));
}

ShadingContext::ShadingContext(const ShadingResources& resources,
                               ShadingServices& services)
    : m_impl(std::make_unique<Impl>(resources, services)) {}
ShadingContext::~ShadingContext() = default;

namespace {

/// Replaces non-finite values of the slot by 0; marks the points.
void clean_slot(const detail::Slot& sl, std::size_t n, std::vector<uint8_t>& bad) {
    const std::size_t reps = sl.varying ? n : 1;
    for (std::size_t i = 0; i < reps; ++i) {
        float* v = sl.at(i);
        bool b = false;
        for (int k = 0; k < sl.nf; ++k)
            if (!std::isfinite(v[k])) {
                v[k] = 0.0f;
                b = true;
            }
        if (b) {
            if (sl.varying)
                bad[i] = 1;
            else
                std::fill(bad.begin(), bad.end(), 1);
        }
    }
}

void read3(const detail::Slot& sl, std::size_t n, std::vector<glm::vec3>& out) {
    out.resize(n);
    for (std::size_t i = 0; i < n; ++i) out[i] = detail::ld3(sl.at(sl.varying ? i : 0));
}

} // namespace

void ShadingContext::execute(const ShaderInstance& shader, ShadingBatch& batch,
                             LightList lights) {
    using namespace detail;
    Impl& c = *m_impl;
    const std::size_t n = batch.size;
    if (batch.layout == BatchLayout::Grid &&
        static_cast<std::size_t>(batch.nu) * static_cast<std::size_t>(batch.nv) != n)
        throw ValueError("shading: grid batch of " + std::to_string(batch.nu) + " x " +
                         std::to_string(batch.nv) + " points has size " +
                         std::to_string(n));
    if (batch.layout == BatchLayout::Triplets && n % 3 != 0)
        throw ValueError("shading: a batch of triplets has " + std::to_string(n) +
                         " points");
    c.batch = &batch;
    c.lights = lights;
    c.depth = 0;
    c.reset_strings();
    c.extra_storage.clear();
    const Scene& scene = c.services.scene();
    c.world_to_camera = scene.options.camera.world_to_camera;
    c.camera_to_world = glm::inverse(c.world_to_camera);
    c.object_to_current =
        c.world_to_camera *
        (batch.primitive ? batch.primitive->object_to_world : Matrix4(1.0));
    c.light_states.clear();
    c.light_states.resize(lights.size());
    for (std::size_t k = 0; k < lights.size(); ++k)
        c.light_states[k].instance = lights[k];
    c.nonfinite = 0;
    c.last_shader = shader.program().name;
    c.last_program = shader.program_ptr();
    c.last_where = shader.where().empty() ? shader.bound().where(-1) : shader.where();

    Frame& f = c.main;
    c.setup_frame(f, shader, n);
    c.load_surface_globals(f);
    try {
        c.init_params(f, true);
        if (n > 0) c.run_body(f);
    } catch (const ShaderRuntimeError& e) {
        // Name the RIB call too: "scene.rib:12: Surface "x": file.sl:7: ..."
        if (shader.where().empty()) throw;
        throw ShaderRuntimeError(shader.where() + ": " + e.what());
    }

    // NaN / infinity: written as 0, counted.
    const Program& p = shader.program();
    const int* g = f.bound->globals;
    std::vector<uint8_t> bad(n, 0);
    for (int id : {G_Ci, G_Oi, G_P, G_N})
        if (g[id] >= 0) clean_slot(f.slots[g[id]], n, bad);
    for (int s : f.bound->params)
        if (p.symbols[s].kind == SymbolKind::OutputParam &&
            p.symbols[s].type.type != ShadingType::String)
            clean_slot(f.slots[s], n, bad);
    c.nonfinite = static_cast<std::size_t>(std::count(bad.begin(), bad.end(), 1));

    if (p.kind == ShaderKind::Displacement) {
        if (g[G_P] >= 0) read3(f.slots[g[G_P]], n, batch.P);
        if (g[G_N] >= 0) read3(f.slots[g[G_N]], n, batch.N);
    } else {
        if (g[G_Ci] >= 0)
            read3(f.slots[g[G_Ci]], n, batch.Ci);
        else
            batch.Ci.assign(n, glm::vec3(0.0f));
        if (g[G_Oi] >= 0) {
            read3(f.slots[g[G_Oi]], n, batch.Oi);
        } else {
            batch.Oi.resize(n);
            const glm::vec3 os = batch.primitive
                                     ? glm::vec3(attributes_of(*batch.primitive).opacity)
                                     : glm::vec3(1.0f);
            for (std::size_t i = 0; i < n; ++i)
                batch.Oi[i] = batch.Os.size() >= n ? batch.Os[i] : os;
        }
    }
    c.batch = nullptr;
}

std::size_t ShadingContext::nonfinite_points() const {
    return m_impl->nonfinite;
}

uint64_t ShadingContext::rays_traced() const {
    return m_impl->rays;
}

std::string ShadingContext::nonfinite_message() const {
    if (m_impl->nonfinite == 0) return "";
    return std::to_string(m_impl->nonfinite) + " points of shader '" +
           m_impl->last_shader + "' at " + m_impl->last_where +
           " gave NaN or infinity; written as 0";
}

bool ShadingContext::output(const std::string& name, TypeSpec& type,
                            std::vector<float>& values) const {
    const detail::Frame& f = m_impl->main;
    if (!f.program) return false;
    const int s = f.program->find(name);
    if (s < 0) return false;
    const Symbol& sym = f.program->symbols[s];
    if (sym.kind != SymbolKind::OutputParam && sym.kind != SymbolKind::Global &&
        sym.kind != SymbolKind::Param)
        return false;
    type = sym.type;
    const detail::Slot& sl = f.slots[s];
    values.resize(static_cast<std::size_t>(sl.nf) * f.n);
    for (std::size_t i = 0; i < f.n; ++i)
        std::memcpy(values.data() + i * sl.nf, sl.at(sl.varying ? i : 0),
                    sizeof(float) * sl.nf);
    return true;
}

} // namespace sss
