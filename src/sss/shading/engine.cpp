// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine.cpp
/// The shading engine (engine.h): frames (storage per symbol, constants,
/// globals), the interpreter with its running mask and structured control
/// flow, spaces, and the batch entry point. Binding (ops, shader instances'
/// parameters, parameter values) is in engine_bind.cpp, operators and
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
#include "sss/util/limits.h"

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

void Frame::check_string_length(const BoundOp& b, uint64_t length) const {
    if (length > ctx->string_limit)
        fail(b, "a string of " + std::to_string(length) + " bytes " +
                    limit_exceeded(Limit::ShaderStringLength));
}

void Frame::check_memory_for(const BoundOp& b, uint64_t bytes,
                             const std::string& what) const {
    try {
        check_memory(bytes, what, "");
    } catch (const OutOfMemoryError& e) {
        throw OutOfMemoryError(bound->describe(b.index) + ": " + e.what());
    }
}

float Frame::intern(const BoundOp& b, const std::string& s) {
    check_string_length(b, s.size());
    ShadingContext::Impl& c = *ctx;
    const float idx = c.intern(s);
    if (c.string_bytes >= c.string_checked_bytes + kShaderMemoryStep) {
        c.string_checked_bytes = c.string_bytes;
        check_memory_for(b, kShaderMemoryStep,
                         "the shader's strings (" + format_bytes(c.string_bytes) +
                             " in this batch)");
    }
    return idx;
}

namespace {

[[noreturn]] void fail_operations(const Frame& f, const BoundOp& b) {
    f.fail(b, "more operations in one shading batch than the limit of " +
                  std::to_string(f.ctx->ops_limit) +
                  " (a loop or recursion that does not end?); set " +
                  limit_variable(Limit::ShaderOperations) + " to raise it");
}

} // namespace

void Frame::warn_once(const BoundOp& b, const std::string& what) const {
    const std::string text = bound->describe(b.index) + ": " + what;
    if (ctx->resources.impl().first_time(text)) ctx->services.warning(text);
}

namespace {

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
        if (++ctx->ops > ctx->ops_limit) [[unlikely]]
            fail_operations(*this, b);
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
                // An iteration counts as an op: a loop may have none.
                if (++ctx->ops > ctx->ops_limit) [[unlikely]]
                    fail_operations(*this, b);
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
// ShadingResources

ShadingResources::Impl::Impl() = default;
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
    string_bytes += s.size() + sizeof(std::string) * 2;
    strings.push_back(s);
    string_index.emplace(s, idx);
    return static_cast<float>(idx);
}

void ShadingContext::Impl::reset_strings() {
    strings.clear();
    string_index.clear();
    string_bytes = string_checked_bytes = 0;
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
    f.kind = f.program->kind;
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
    int resizable = 0;
    for (std::size_t s = 0; s < nsym; ++s) {
        const Symbol& sym = p.symbols[s];
        Slot& sl = f.slots[s];
        sl.nf = sym.type.floats();
        sl.varying = sym.varying;
        sl.stride = sym.varying ? sl.nf : 0;
        sl.p = f.arena.data() + off;
        // A resizable array starts empty, its storage apart (engine_arrays.cpp).
        sl.resizable = sym.type.is_resizable() ? resizable++ : -1;
        if (sl.resizable >= 0) sl.p = nullptr;
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
    f.resizable.resize(static_cast<std::size_t>(resizable));
    if (resizable > 0) detail::reset_resizable(f);
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
    // Volume and imager shaders start from the Ci and Oi they are given.
    const bool given = f.kind == ShaderKind::Volume || f.kind == ShaderKind::Imager;
    if (auto* s = sl(G_Oi)) fill3(*s, n, given && has(b.Oi) ? &b.Oi : &b.Os, os);
    if (given)
        if (auto* s = sl(G_Ci)) fill3(*s, n, &b.Ci, glm::vec3(0.0f));
    if (auto* s = sl(G_u)) fill1(*s, n, &b.u, 0.0f);
    if (auto* s = sl(G_v)) fill1(*s, n, &b.v, 0.0f);
    if (auto* s = sl(G_du)) fill1(*s, n, &b.du, 0.0f);
    if (auto* s = sl(G_dv)) fill1(*s, n, &b.dv, 0.0f);
    if (auto* s = sl(G_s)) fill1(*s, n, b.s.size() >= n ? &b.s : &b.u, 0.0f);
    if (auto* s = sl(G_t)) fill1(*s, n, b.t.size() >= n ? &b.t : &b.v, 0.0f);
    if (auto* s = sl(G_ncomps)) fill1(*s, n, nullptr, 3.0f);
    if (auto* s = sl(G_time)) fill1(*s, n, nullptr, b.time);
    if (auto* s = sl(G_alpha)) fill1(*s, n, &b.alpha, 1.0f);
}

void ShadingContext::Impl::run_body(detail::Frame& f) {
    const Program& p = *f.program;
    if (!p.is_class()) {
        f.run(p.body_begin, static_cast<int>(p.ops.size()));
        return;
    }
    f.run(p.body_begin, p.init_end);
    if (const Pipeline* pipeline = p.pipeline(f.kind))
        for (int m : pipeline->methods)
            f.run(p.methods[std::size_t(m)].begin, p.methods[std::size_t(m)].end);
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
                             LightList lights, CoshaderList coshaders) {
    execute_as(shader.program().kind, shader, batch, lights, coshaders);
}

void ShadingContext::execute_as(ShaderKind kind, const ShaderInstance& shader,
                                ShadingBatch& batch, LightList lights,
                                CoshaderList coshaders) {
    using namespace detail;
    Impl& c = *m_impl;
    if (!shader.program().runs_as(kind))
        throw ValueError((shader.where().empty() ? "" : shader.where() + ": ") +
                         "shader '" + shader.program().name + "' is a " +
                         shader_kind_name(shader.program().kind) + " shader and has no " +
                         shader_kind_name(kind) + " method");
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
    c.coshaders = coshaders;
    c.objects.clear();
    c.depth = 0;
    c.reset_strings();
    c.ops = 0;
    c.ops_limit = limit(Limit::ShaderOperations);
    c.string_limit = limit(Limit::ShaderStringLength);
    c.array_limit = limit(Limit::ShaderArrayLength);
    c.extra_storage.clear();
    const Scene& scene = c.services.scene();
    c.world_to_camera = scene.options.camera.world_to_camera;
    c.camera_to_world = glm::inverse(c.world_to_camera);
    c.object_to_current =
        c.world_to_camera *
        (batch.primitive ? batch.primitive->object_to_world : Matrix4(1.0));
    c.light_states.clear();
    c.light_states.resize(lights.size());
    c.light_sends.clear();
    for (std::size_t k = 0; k < lights.size(); ++k)
        c.light_states[k].instance = lights[k];
    c.nonfinite = 0;
    c.last_shader = shader.program().name;
    c.last_program = shader.program_ptr();
    c.last_where = shader.where().empty() ? shader.bound().where(-1) : shader.where();

    Frame& f = c.main;
    c.setup_frame(f, shader, n);
    f.kind = kind;
    c.load_surface_globals(f);
    try {
        c.init_params(f, true);
        if (n > 0) c.run_body(f);
    } catch (const ShaderRuntimeError& e) {
        // Name the RIB call too: "scene.rib:12: Surface "x": file.sl:7: ..."
        if (shader.where().empty()) throw;
        throw ShaderRuntimeError(shader.where() + ": " + e.what());
    } catch (const OutOfMemoryError& e) {
        if (shader.where().empty()) throw;
        throw OutOfMemoryError(shader.where() + ": " + e.what());
    }

    // NaN / infinity: written as 0, counted.
    const Program& p = shader.program();
    const int* g = f.bound->globals;
    std::vector<uint8_t> bad(n, 0);
    for (int id : {G_Ci, G_Oi, G_P, G_N, G_alpha})
        if (g[id] >= 0) clean_slot(f.slots[g[id]], n, bad);
    for (int s : f.bound->params)
        if (p.symbols[s].kind == SymbolKind::OutputParam &&
            p.symbols[s].type.type != ShadingType::String)
            clean_slot(f.slots[s], n, bad);
    c.nonfinite = static_cast<std::size_t>(std::count(bad.begin(), bad.end(), 1));

    if (kind == ShaderKind::Displacement) {
        if (g[G_P] >= 0) read3(f.slots[g[G_P]], n, batch.P);
        if (g[G_N] >= 0) read3(f.slots[g[G_N]], n, batch.N);
    } else if (kind == ShaderKind::Volume || kind == ShaderKind::Imager) {
        // What the shader does not mention stays as it was given.
        if (g[G_Ci] >= 0) read3(f.slots[g[G_Ci]], n, batch.Ci);
        if (g[G_Oi] >= 0) read3(f.slots[g[G_Oi]], n, batch.Oi);
        if (g[G_alpha] >= 0) {
            const Slot& a = f.slots[g[G_alpha]];
            batch.alpha.resize(n);
            for (std::size_t i = 0; i < n; ++i) batch.alpha[i] = *a.at(a.varying ? i : 0);
        }
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
