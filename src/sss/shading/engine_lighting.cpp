// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_lighting.cpp
/// Lights and local illumination (RISpec 15.5, shading.md 4 and 5.5):
///
///  - Light shaders run lazily, once per batch per light (re-run when the
///    surface asks for points or positions the cache does not hold). Their
///    globals: Ps = the surface point, P = the origin of the light's shader
///    space in the current space, N = the surface's N at Ps (its N global,
///    else the batch's N; PRMan's convention, which envlight's
///    `illuminate(Ps + N)` relies on), E = 0; L, Cl, Ol start at 0. The
///    cache holds for the same Ps and N.
///  - `illuminate(P, axis, angle)` sets L = Ps - P (light to surface) and runs
///    its body where the angle between L and axis is at most angle (no axis:
///    everywhere); `solar(axis, angle)` sets L = axis (the direction the light
///    travels; no axis: L = 0) for every point. Points an illuminate or solar
///    body ran for are "lit"; a light shader with neither is an ambient
///    light: it contributes to ambient() only, and illuminance loops skip it.
///  - `illuminance(cat, P, axis, angle)`: a loop over the lights whose body runs, per
///  light, for the
///    points the light lit within the angle of the axis, with L = -L of the
///    light (towards the light), Cl and Ol. It is not a loop level for
///    break and continue (as the compiler counts them). Categories: the light's uniform
///    string parameter `__category` (comma separated); the loop's category
///    is a comma-separated list of names, each required (any of them) or,
///    with a leading '-', excluded.
///    Options ("name", value after the positional arguments): "lightcache"
///    "refresh" re-runs the lights (their cache is dropped first; "reuse"
///    is the default); "light:NAME", var receives the light's parameter
///    NAME each iteration (left alone for a light without one);
///    "send:light:NAME", value runs the lights with their parameter NAME set
///    to value (after the light's own parameters are bound; the lights are
///    re-run before and after the loop so that no other query sees them).
///  - Message passing: lightsource("NAME", var) inside illuminance reads
///    the current light's parameter NAME (0 outside, or when there is
///    none); surface("NAME", var) in a light shader reads the parameter of
///    the surface being lit, at the same point, as it is when the light runs.
///  - ambient(), diffuse(N), specular(N, V, roughness), phong(N, V, size) as
///    RISpec's definitions over illuminance(P, N, PI/2), with unit N and L,
///    roughness clamped to >= 1e-4 and N.H to >= 0 (the C++ shaders'
///    formulas). Lights whose `__nondiffuse` / `__nonspecular` parameter is
///    non-zero are skipped by diffuse / by specular and phong.
///  - Ray-traced shadows, transmission(), occlusion(), trace(),
///    indirectdiffuse() and gather are in engine_raytrace.cpp.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "engine_internal.h"
#include "sss/light/ray_tracer.h"
#include "sss/util/hash.h"
#include "sss/util/parse.h"

namespace sss {

using namespace detail;

bool detail::category_matches(const std::string& cat,
                              const std::vector<std::string>& light) {
    if (cat.empty()) return true;
    bool any_positive = false, positive_hit = false;
    for (const std::string& term : split_words(cat)) {
        const bool exclude = term[0] == '-';
        const std::string name = exclude ? term.substr(1) : term;
        const bool has = std::find(light.begin(), light.end(), name) != light.end();
        if (exclude) {
            if (has) return false;
        } else {
            any_positive = true;
            positive_hit = positive_hit || has;
        }
    }
    return !any_positive || positive_hit;
}

namespace {

void store3(const Slot* s, std::size_t i, const glm::vec3& v) {
    if (s) st3(s->at(i), v);
}

/// Whether a value of type `from` fits a variable of type `to` (messages).
bool message_fits(const TypeSpec& from, const TypeSpec& to) {
    if (from.is_array() || to.is_array()) return false;
    return from.type == to.type || (is_point_like(from.type) && is_point_like(to.type));
}

/// Sets light frame lf's parameter send.name to the sent value (per point
/// for a varying parameter, else the value at the first point of `mask`).
void apply_send(Frame& lf, const LightSend& send, const std::vector<uint8_t>& mask) {
    const int s = lf.program->find(send.name);
    if (s < 0) return;
    const Symbol& sym = lf.program->symbols[s];
    if ((sym.kind != SymbolKind::Param && sym.kind != SymbolKind::OutputParam) ||
        !message_fits({send.type, 0}, sym.type))
        return;
    Slot& to = lf.slots[s];
    const std::size_t first =
        std::find(mask.begin(), mask.end(), uint8_t(1)) - mask.begin();
    if (first >= lf.n) return;
    const std::size_t reps = to.varying ? lf.n : 1;
    for (std::size_t i = 0; i < reps; ++i)
        std::memcpy(to.at(i), send.value->at(to.varying ? i : first),
                    sizeof(float) * to.nf);
}

} // namespace

bool detail::copy_parameter(Frame& f, const BoundOp& b, int k, const Frame& from,
                            const std::string& name) {
    if (!from.program || from.n != f.n) return false;
    const int s = from.program->find(name);
    if (s < 0) return false;
    const Symbol& src = from.program->symbols[s];
    if (src.kind != SymbolKind::Param && src.kind != SymbolKind::OutputParam)
        return false;
    if (!message_fits(src.type, f.program->symbols[b.op->args[k]].type)) return false;
    const Slot& value = from.slots[s];
    Slot& to = f.slot(b, k);
    f.each(to.varying, [&](std::size_t i) {
        std::memcpy(to.at(i), value.at(i), sizeof(float) * to.nf);
    });
    return true;
}

LightState& ShadingContext::Impl::describe_light(int index) {
    LightState& ls = light_states[index];
    if (!ls.described) {
        const ShaderInstance& inst = *ls.instance;
        ls.described = true;
        ls.ambient = !inst.bound().has_illuminate;
        ls.categories = split_words(inst.string_parameter("__category").value_or(""));
        ls.nondiffuse = inst.float_parameter("__nondiffuse").value_or(0.0f) != 0.0f;
        ls.nonspecular = inst.float_parameter("__nonspecular").value_or(0.0f) != 0.0f;
        ls.frame = std::make_unique<Frame>();
    }
    return ls;
}

LightState& ShadingContext::Impl::light(int index, const float* P, int P_stride,
                                        const std::vector<uint8_t>& mask,
                                        std::size_t active, const float* axis,
                                        int axis_stride, float angle) {
    LightState& ls = describe_light(index);
    const std::size_t n = batch->size;
    const ShaderInstance& inst = *ls.instance;
    auto Pat = [&](std::size_t i) { return ld3(P + i * P_stride); };
    // The surface normal at Ps: the surface frame's N global, else the batch's.
    const int gN = main.bound ? main.bound->globals[G_N] : -1;
    const Slot* surfN = gN >= 0 && main.n == n ? &main.slots[gN] : nullptr;
    auto Nat = [&](std::size_t i) {
        if (surfN) return ld3(surfN->at(i));
        return batch && i < batch->N.size() ? batch->N[i] : glm::vec3(0.0f);
    };
    const bool all = axis == nullptr || angle >= 3.14159265f;
    auto Aat = [&](std::size_t i) {
        return all ? glm::vec3(0.0f) : ld3(axis + i * axis_stride);
    };
    if (ls.valid) {
        // Valid for points computed at the same P, under a cone that held
        // this request's (everything, or the same axis and angle).
        bool ok = ls.request_all || (!all && angle == ls.request_angle);
        for (std::size_t i = 0; i < n && ok; ++i)
            if (mask[i] && (!ls.computed[i] || ls.Ps[i] != Pat(i) || ls.N[i] != Nat(i) ||
                            (!ls.request_all && ls.request_axis[i] != Aat(i))))
                ok = false;
        if (ok) return ls;
    }
    if (depth > 4)
        throw ShaderRuntimeError(inst.bound().describe(-1) + ": lights nest too deep");
    ++depth;
    Frame& lf = *ls.frame;
    setup_frame(lf, inst, n);
    lf.is_light = true;
    const int* g = lf.bound->globals;
    auto sl = [&](int id) -> const Slot* {
        return g[id] >= 0 ? &lf.slots[id >= 0 ? g[id] : 0] : nullptr;
    };
    lf.light_Ps.resize(n);
    for (std::size_t i = 0; i < n; ++i) lf.light_Ps[i] = Pat(i);
    if (const Slot* s = sl(G_Ps))
        for (std::size_t i = 0; i < (s->varying ? n : 1); ++i) st3(s->at(i), Pat(i));
    if (const Slot* s = sl(G_N))
        for (std::size_t i = 0; i < (s->varying ? n : 1); ++i) st3(s->at(i), Nat(i));
    if (const Slot* s = sl(G_P)) {
        const glm::vec3 origin = xform_point(lf.shader_to_current, glm::vec3(0.0f));
        for (std::size_t i = 0; i < (s->varying ? n : 1); ++i) st3(s->at(i), origin);
    }
    if (const Slot* s = sl(G_ncomps)) *s->p = 3.0f;
    if (const Slot* s = sl(G_time))
        for (std::size_t i = 0; i < (s->varying ? n : 1); ++i) *s->at(i) = batch->time;
    init_params(lf, false);
    for (const LightSend& send : light_sends) apply_send(lf, send, mask);
    lf.mask = mask;
    lf.active = active;
    lf.request_axis = all ? nullptr : axis;
    lf.request_axis_stride = axis_stride;
    lf.request_angle = angle;
    if (active > 0) run_body(lf);
    ls.request_all = all;
    ls.request_angle = angle;
    ls.request_axis.resize(all ? 0 : n);
    if (!all)
        for (std::size_t i = 0; i < n; ++i)
            ls.request_axis[i] = mask[i] ? Aat(i) : glm::vec3(0.0f);

    ls.Ps.resize(n);
    for (std::size_t i = 0; i < n; ++i) ls.Ps[i] = mask[i] ? Pat(i) : glm::vec3(0.0f);
    ls.N.resize(n);
    for (std::size_t i = 0; i < n; ++i) ls.N[i] = mask[i] ? Nat(i) : glm::vec3(0.0f);
    ls.computed = mask;
    auto collect = [&](int id, std::vector<glm::vec3>& out) {
        out.assign(n, glm::vec3(0.0f));
        if (const Slot* s = sl(id))
            for (std::size_t i = 0; i < n; ++i) out[i] = ld3(s->at(i));
    };
    collect(G_Cl, ls.Cl);
    collect(G_Ol, ls.Ol);
    if (g[G_L] >= 0)
        collect(G_L, ls.L);
    else
        ls.L = lf.light_L;
    ls.lit = ls.ambient ? mask : lf.lit;
    ls.valid = true;
    --depth;
    return ls;
}

namespace detail {

namespace {
/// Whether direction L is within `angle` of `axis`, with a little slack so
/// that rounding never drops a light the surface's own test keeps.
bool in_request_cone(const glm::vec3& L, const glm::vec3& axis, float angle) {
    if (angle >= 3.14159265f) return true;
    const float la = glm::length(L) * glm::length(axis);
    if (!(la > 0.0f)) return true;
    return glm::dot(L, axis) / la >= std::cos(angle) - 1e-4f;
}
} // namespace

void run_illuminate(Frame& f, const BoundOp& b, int body_begin, int body_end,
                    bool solar) {
    const std::size_t n = f.n;
    const int* g = f.bound->globals;
    const Slot* Ls = g[G_L] >= 0 ? &f.slots[g[G_L]] : nullptr;
    const int axis_k = solar ? 0 : 1;
    const int angle_k = solar ? 1 : 2;
    std::vector<uint8_t>& entry = f.push_mask();
    entry = f.mask;
    std::size_t cnt = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!entry[i]) {
            f.mask[i] = 0;
            continue;
        }
        const float angle = *f.ptr(b, angle_k, i);
        const glm::vec3 axis = ld3(f.ptr(b, axis_k, i));
        glm::vec3 L;
        if (solar) {
            L = angle < 0.0f ? glm::vec3(0.0f) : axis;
        } else {
            L = f.light_Ps[i] - ld3(f.ptr(b, 0, i));
        }
        bool pass = true;
        if (!solar && angle >= 0.0f && angle < 3.14159265f) {
            const float la = glm::length(L) * glm::length(axis);
            if (la > 0.0f) pass = glm::dot(L, axis) / la >= std::cos(angle);
        }
        // The surface uses light from within its cone only: -L must lie in it.
        if (pass && f.request_axis &&
            !in_request_cone(-L, ld3(f.request_axis + i * f.request_axis_stride),
                             f.request_angle))
            pass = false;
        f.mask[i] = pass;
        if (pass) {
            f.light_L[i] = L;
            if (Ls && Ls->varying) st3(Ls->at(i), L);
            f.lit[i] = 1;
            ++cnt;
        }
    }
    f.active = cnt;
    if (Ls && !Ls->varying && cnt > 0) st3(Ls->p, f.light_L[f.first_active()]);
    (void)b;
    const bool was = f.in_illuminate;
    f.in_illuminate = true;
    f.solar = solar;
    if (cnt > 0) f.run(body_begin, body_end);
    f.in_illuminate = was;
    // restore
    f.restore_mask(entry);
    f.pop_mask();
}

namespace {

/// The surface P of a frame for lights: its global P, or the batch's.
struct PSource {
    const float* p = nullptr;
    int stride = 0;
    std::vector<float> own;
};

PSource surface_P(Frame& f) {
    PSource s;
    const int gp = f.bound->globals[G_P];
    if (gp >= 0) {
        s.p = f.slots[gp].p;
        s.stride = f.slots[gp].stride;
        return s;
    }
    const ShadingBatch& b = *f.ctx->batch;
    s.own.assign(f.n * 3, 0.0f);
    for (std::size_t i = 0; i < f.n && i < b.P.size(); ++i) st3(&s.own[i * 3], b.P[i]);
    s.p = s.own.data();
    s.stride = 3;
    return s;
}

/// Whether direction L is within `angle` of `axis` (axis 0 or angle >= PI:
/// everything).
inline bool in_cone(const glm::vec3& L, const glm::vec3& axis, float angle) {
    if (angle >= 3.14159265f) return true;
    const float la = glm::length(L) * glm::length(axis);
    if (!(la > 0.0f)) return true;
    return glm::dot(L, axis) / la >= std::cos(angle);
}

} // namespace

namespace {

/// The options of an illuminance op (see the file comment).
struct IlluminanceOptions {
    bool refresh = false;
    std::vector<std::pair<std::string, int>> receive; ///< light parameter, argument
    std::vector<LightSend> send;
};

IlluminanceOptions illuminance_options(Frame& f, const BoundOp& b) {
    IlluminanceOptions o;
    const std::size_t first = f.first_active();
    for_options(f, b, 4, [&](const std::string& name, int k) {
        if (name == "lightcache")
            o.refresh = f.str(b, k, first) == "refresh";
        else if (name.rfind("light:", 0) == 0)
            o.receive.push_back({name.substr(6), k});
        else if (name.rfind("send:light:", 0) == 0)
            o.send.push_back({name.substr(11), &f.slot(b, k),
                              f.program->symbols[b.op->args[k]].type.type});
    });
    return o;
}

void drop_light_caches(ShadingContext::Impl& ctx) {
    for (LightState& ls : ctx.light_states) ls.valid = false;
}

} // namespace

void run_illuminance(Frame& f, const BoundOp& b, int body_begin, int body_end) {
    ShadingContext::Impl& ctx = *f.ctx;
    const std::size_t n = f.n;
    IlluminanceOptions options;
    if (b.op->args.size() > 4) options = illuminance_options(f, b);
    if (options.refresh || !options.send.empty()) drop_light_caches(ctx);
    // The sends hold for this loop only (the lights run again after it).
    struct SendScope {
        ShadingContext::Impl& ctx;
        bool on;
        ~SendScope() {
            if (!on) return;
            ctx.light_sends.clear();
            drop_light_caches(ctx);
        }
    } send_scope{ctx, !options.send.empty()};
    if (send_scope.on) ctx.light_sends = options.send;
    const int* g = f.bound->globals;
    const Slot* Ls = g[G_L] >= 0 ? &f.slots[g[G_L]] : nullptr;
    const Slot* Cls = g[G_Cl] >= 0 ? &f.slots[g[G_Cl]] : nullptr;
    const Slot* Ols = g[G_Ol] >= 0 ? &f.slots[g[G_Ol]] : nullptr;
    const std::string cat = f.str(b, 0, f.first_active());
    const Slot& P = f.slot(b, 1);
    std::vector<uint8_t>& entry = f.push_mask();
    entry = f.mask;
    std::vector<uint8_t>& base = f.push_mask();
    for (std::size_t li = 0; li < ctx.lights.size(); ++li) {
        std::size_t cnt = 0;
        for (std::size_t i = 0; i < n; ++i) {
            base[i] = entry[i] && f.stop[i] == 0;
            cnt += base[i];
        }
        if (cnt == 0) break;
        const Slot& axis = f.slot(b, 2);
        const float angle = *f.ptr(b, 3, f.first_active());
        const bool uniform_cone = !f.slot(b, 3).varying;
        LightState& ls = ctx.light(static_cast<int>(li), P.p, P.stride, base, cnt,
                                   uniform_cone ? axis.p : nullptr, axis.stride,
                                   uniform_cone ? angle : 4.0f);
        if (ls.ambient || !category_matches(cat, ls.categories)) continue;
        std::size_t on = 0;
        for (std::size_t i = 0; i < n; ++i) {
            bool run = base[i] && ls.lit[i];
            if (run) run = in_cone(-ls.L[i], ld3(f.ptr(b, 2, i)), *f.ptr(b, 3, i));
            f.mask[i] = run;
            on += run;
        }
        f.active = on;
        if (on == 0) continue;
        f.each(true, [&](std::size_t i) {
            store3(Ls, i, -ls.L[i]);
            store3(Cls, i, ls.Cl[i]);
            store3(Ols, i, ls.Ol[i]);
        });
        for (const auto& [name, k] : options.receive)
            copy_parameter(f, b, k, *ls.frame, name);
        f.current_light = static_cast<int>(li);
        f.run(body_begin, body_end);
    }
    f.current_light = -1;
    f.restore_mask(entry);
    f.pop_mask();
    f.pop_mask();
}

namespace {

// --- ambient / diffuse / specular / phong ------------------------------------

enum Model { M_Ambient, M_Diffuse, M_Specular, M_Phong };

template <int M>
void op_lighting(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const std::size_t n = f.n;
    std::vector<glm::vec3> sum(n, glm::vec3(0.0f));
    ShadingContext::Impl& ctx = *f.ctx;
    if (!f.is_light && ctx.batch && f.active > 0) {
        PSource P = surface_P(f);
        // The light cache is filled for the running points.
        std::vector<uint8_t>& run = f.push_mask();
        run = f.mask;
        const std::size_t active = f.active;
        for (std::size_t li = 0; li < ctx.lights.size(); ++li) {
            // ambient() runs only the ambient lights; diffuse/specular/phong
            // only the others, for light from the hemisphere about N.
            const bool ambient_light = ctx.describe_light(static_cast<int>(li)).ambient;
            if ((M == M_Ambient) != ambient_light) continue;
            const Slot* axis = M == M_Ambient ? nullptr : &f.slot(b, 1);
            LightState& ls =
                axis ? ctx.light(static_cast<int>(li), P.p, P.stride, run, active,
                                 axis->p, axis->stride, 1.5707964f)
                     : ctx.light(static_cast<int>(li), P.p, P.stride, run, active);
            if (M == M_Ambient) {
                if (!ls.ambient) continue;
                for (std::size_t i = 0; i < n; ++i)
                    if (run[i]) sum[i] += ls.Cl[i];
                continue;
            }
            if (ls.ambient) continue;
            if (M == M_Diffuse && ls.nondiffuse) continue;
            if ((M == M_Specular || M == M_Phong) && ls.nonspecular) continue;
            for (std::size_t i = 0; i < n; ++i) {
                if (!run[i] || !ls.lit[i]) continue;
                const glm::vec3 N0 = ld3(f.ptr(b, 1, i));
                const float nl = glm::length(N0);
                const glm::vec3 N = nl > 0.0f ? N0 / nl : N0;
                const glm::vec3 L0 = -ls.L[i];
                const float ll = glm::length(L0);
                const glm::vec3 L = ll > 0.0f ? L0 / ll : L0;
                if (!in_cone(L, N, 1.5707964f)) continue;
                if (M == M_Diffuse) {
                    sum[i] += ls.Cl[i] * glm::dot(L, N);
                } else if (M == M_Specular) {
                    const glm::vec3 V = ld3(f.ptr(b, 2, i));
                    const float r = std::max(*f.ptr(b, 3, i), 1e-4f);
                    const glm::vec3 h = L + V;
                    const float hl = glm::length(h);
                    if (!(hl > 0.0f)) continue;
                    const float c = std::max(0.0f, glm::dot(N, h / hl));
                    sum[i] += ls.Cl[i] * std::pow(c, 1.0f / r);
                } else {
                    const glm::vec3 V0 = ld3(f.ptr(b, 2, i));
                    const float vl = glm::length(V0);
                    const glm::vec3 V = vl > 0.0f ? V0 / vl : V0;
                    const glm::vec3 R = -V - 2.0f * glm::dot(-V, N) * N;
                    const float c = std::max(0.0f, glm::dot(R, L));
                    sum[i] += ls.Cl[i] * std::pow(c, *f.ptr(b, 3, i));
                }
            }
        }
        f.pop_mask();
    }
    f.each(d.varying, [&](std::size_t i) { st3(d.at(i), sum[i]); });
}

// --- message passing ----------------------------------------------------------

void set_result(Frame& f, const BoundOp& b, bool found) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) { *d.at(i) = found ? 1.0f : 0.0f; });
}

/// lightsource("NAME", var): inside illuminance, the current light's parameter.
void op_lightsource(Frame& f, const BoundOp& b) {
    ShadingContext::Impl& ctx = *f.ctx;
    const int li = f.current_light;
    bool found = false;
    if (!f.is_light && li >= 0 &&
        static_cast<std::size_t>(li) < ctx.light_states.size()) {
        const LightState& ls = ctx.light_states[static_cast<std::size_t>(li)];
        if (ls.frame)
            found = copy_parameter(f, b, 2, *ls.frame, f.str(b, 1, f.first_active()));
    }
    set_result(f, b, found);
}

/// surface("NAME", var): in a light shader, the lit surface's parameter.
void op_surface_message(Frame& f, const BoundOp& b) {
    const Frame& surface = f.ctx->main;
    const bool found = f.is_light && surface.program &&
                       surface.kind == ShaderKind::Surface &&
                       copy_parameter(f, b, 2, surface, f.str(b, 1, f.first_active()));
    set_result(f, b, found);
}

bool bind_message(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_float(0) || !in.is_string(1) || in.is_array(2))
        return false;
    b.fn = in.op.name == "lightsource" ? op_lightsource : op_surface_message;
    return true;
}

bool bind_ambient(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 1 || !in.is_color(0)) return false;
    b.fn = op_lighting<M_Ambient>;
    return true;
}
bool bind_diffuse(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !in.is_color(0) || !in.is_ptype(1)) return false;
    b.fn = op_lighting<M_Diffuse>;
    return true;
}
bool bind_specular(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 4 || !in.is_color(0) || !in.is_ptype(1) || !in.is_ptype(2) ||
        !in.is_float(3))
        return false;
    b.fn = in.op.name == "phong" ? op_lighting<M_Phong> : op_lighting<M_Specular>;
    return true;
}

void op_specularbrdf(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        const glm::vec3 L0 = ld3(f.ptr(b, 1, i));
        const glm::vec3 N = ld3(f.ptr(b, 2, i));
        const glm::vec3 V = ld3(f.ptr(b, 3, i));
        const float r = std::max(*f.ptr(b, 4, i), 1e-4f);
        const float ll = glm::length(L0);
        const glm::vec3 h = (ll > 0.0f ? L0 / ll : L0) + V;
        const float hl = glm::length(h);
        const float c = hl > 0.0f ? std::max(0.0f, glm::dot(N, h / hl)) : 0.0f;
        st3(d.at(i), glm::vec3(std::pow(c, 1.0f / r)));
    });
}

bool bind_specularbrdf(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 5 || !in.is_color(0) || !in.is_ptype(1) || !in.is_ptype(2) ||
        !in.is_ptype(3) || !in.is_float(4))
        return false;
    b.fn = op_specularbrdf;
    return true;
}

} // namespace

void register_lighting(BinderTable& t) {
    t["ambient"] = bind_ambient;
    t["diffuse"] = bind_diffuse;
    t["specular"] = bind_specular;
    t["phong"] = bind_specular;
    t["specularbrdf"] = bind_specularbrdf;
    t["lightsource"] = bind_message;
    t["surface"] = bind_message;
}

} // namespace detail
} // namespace sss
