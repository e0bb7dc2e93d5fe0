// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_coshader.cpp
/// RSL 2.0 shader objects in the shading engine: `shader` handles and the
/// calls through them.
///
///  - Handles: a `shader` value is an index into the context's table of
///    shader objects for the batch (ShaderObject, engine_internal.h), 0
///    being null. getshader("h") and getshaders() hand out the batch's
///    co-shaders (`Shader "name" "h"` in effect for the primitive),
///    getlight("h") and getlights() its lights; getshaders and getlights
///    take a "category" option (the shaders' `__category`, as illuminance
///    selects lights).
///  - A co-shader's frame is set up the first time a method or getvar needs
///    it: its parameters (and primitive variables), the batch's globals,
///    its member variables' initialisers, construct() and begin(); it lives
///    for the batch, so member variables keep their values between calls.
///  - `s->m(args)` (op callmethod) runs method m of the object at the
///    caller's running points: arguments are copied into the method's
///    parameters (a float into a triple is replicated; point, vector and
///    normal fit each other; arrays of one element type and length),
///    outputs and the result copied back. A uniform destination takes the
///    value at the first running point. A light's `light(L, Cl[, Ol])` is
///    the light evaluated (cached) at the caller's P: L from the light to
///    the point, as illuminate sets it; its other methods run in the
///    light's frame once evaluated. A call on null, or of a method the
///    shader does not have, does nothing (warned once); a wrong number or
///    type of arguments is an error, and so is a shader calling itself.
///  - A classic shader (not a class) called by the name of its type runs
///    its body: `s->surface(Ci, Oi)`, `s->displacement(P, N)`,
///    `s->volume(Ci, Oi)` (`light(L, Cl)` as above), the arguments in and out
///    of those globals.
///  - getvar(s, "name"[, var]): whether the object has a parameter or
///    member variable `name` (of var's type), and its value;
///    hasmethod(s, "name"): whether a call of `name` would run something.

#include <algorithm>
#include <cstring>

#include "engine_internal.h"
#include "sss/util/parse.h"

namespace sss::detail {

namespace {

using Impl = ShadingContext::Impl;

constexpr int kMaxCallDepth = 16;

/// The handle of `inst` (a light when light >= 0): its index in the
/// object table plus one, added on first use.
float object_handle(Impl& ctx, const ShaderInstance* inst, int light) {
    for (std::size_t k = 0; k < ctx.objects.size(); ++k)
        if (ctx.objects[k].instance == inst && ctx.objects[k].light == light)
            return static_cast<float>(k + 1);
    ShaderObject obj;
    obj.instance = inst;
    obj.light = light;
    ctx.objects.push_back(std::move(obj));
    return static_cast<float>(ctx.objects.size());
}

/// busy flag and call depth for the time of one call.
struct CallGuard {
    Impl& ctx;
    ShaderObject& obj;
    CallGuard(Frame& caller, const BoundOp& b, ShaderObject& o)
        : ctx(*caller.ctx), obj(o) {
        if (obj.busy)
            caller.fail(b, "shader '" + obj.instance->program().name +
                               "' calls itself (through a co-shader handle)");
        if (ctx.depth >= kMaxCallDepth)
            caller.fail(b, "co-shader calls nest more than " +
                               std::to_string(kMaxCallDepth) + " deep");
        obj.busy = true;
        ++ctx.depth;
    }
    ~CallGuard() {
        obj.busy = false;
        --ctx.depth;
    }
};

/// A co-shader's frame, set up on first use (see the file comment).
Frame& coshader_frame(Frame& caller, const BoundOp& b, ShaderObject& obj) {
    if (obj.frame) return *obj.frame;
    Impl& ctx = *caller.ctx;
    obj.frame = std::make_unique<Frame>();
    Frame& cf = *obj.frame;
    ctx.setup_frame(cf, *obj.instance, caller.n);
    ctx.load_surface_globals(cf);
    CallGuard guard(caller, b, obj);
    ctx.init_params(cf, true);
    const Program& p = *cf.program;
    if (p.is_class() && cf.n > 0) {
        cf.run(p.body_begin, p.init_end);
        for (const char* name : {"construct", "begin"}) {
            const int m = p.find_method(name);
            if (m < 0) continue;
            std::fill(cf.mask.begin(), cf.mask.end(), 1);
            cf.active = cf.n;
            cf.run(p.methods[std::size_t(m)].begin, p.methods[std::size_t(m)].end);
        }
    }
    return cf;
}

/// The surface positions lights are evaluated at for a call from `f`: its
/// P global, else the batch's.
struct Positions {
    const float* p = nullptr;
    int stride = 0;
    std::vector<float> own;
};

Positions positions(Frame& f) {
    Positions s;
    const int gp = f.bound->globals[G_P];
    if (gp >= 0 && !f.is_light) {
        s.p = f.slots[gp].p;
        s.stride = f.slots[gp].stride;
        return s;
    }
    const ShadingBatch& batch = *f.ctx->batch;
    s.own.assign(f.n * 3, 0.0f);
    for (std::size_t i = 0; i < f.n && i < batch.P.size(); ++i)
        st3(&s.own[i * 3], batch.P[i]);
    s.p = s.own.data();
    s.stride = 3;
    return s;
}

/// Light `obj` evaluated at the points of `group` (cached for the batch).
LightState& evaluate_light(Frame& caller, const ShaderObject& obj,
                           const std::vector<uint8_t>& group, std::size_t count) {
    Positions P = positions(caller);
    return caller.ctx->light(obj.light, P.p, P.stride, group, count);
}

/// The object behind handle value v, or null for null; fails for a value
/// that is no handle.
ShaderObject* object_of(Frame& f, const BoundOp& b, float v) {
    if (v == 0.0f) return nullptr;
    const std::size_t k = v >= 1.0f ? static_cast<std::size_t>(v) : 0;
    if (k == 0 || k > f.ctx->objects.size() || static_cast<float>(k) != v)
        f.fail(b, "not a shader handle (" + std::to_string(v) + ")");
    return &f.ctx->objects[k - 1];
}

// --- copying values between frames -------------------------------------------

enum class Fit { No, Copy, Splat };

Fit fit(const TypeSpec& from, const TypeSpec& to) {
    if (from.is_array() != to.is_array()) return Fit::No;
    const bool same =
        from.type == to.type || (is_point_like(from.type) && is_point_like(to.type));
    if (same) return Fit::Copy;
    if (!from.is_array() && from.type == ShadingType::Float && is_triple(to.type))
        return Fit::Splat;
    return Fit::No;
}

/// The number of elements of an array value (a resizable one's length).
int elements(const Frame& f, const Slot& s, const TypeSpec& t) {
    if (!t.is_array()) return 1;
    return s.resizable >= 0 ? resizable_length(f, s) : t.array;
}

/// Copies the value of symbol `from` of frame fs into symbol `to` of frame
/// fd at the points of `mask` (a uniform destination once, from `first`).
/// Errors name op b of frame `err`; false when the types do not fit.
bool copy_value(Frame& fs, int from, Frame& fd, int to, const std::vector<uint8_t>& mask,
                std::size_t first, Frame& err, const BoundOp& b) {
    const TypeSpec& ts = fs.program->symbols[std::size_t(from)].type;
    const TypeSpec& td = fd.program->symbols[std::size_t(to)].type;
    const Fit how = fit(ts, td);
    if (how == Fit::No) return false;
    const Slot& src = fs.slots[std::size_t(from)];
    Slot& dst = fd.slots[std::size_t(to)];
    const int ef = shading_type_floats(td.type);
    const int count = elements(fs, src, ts);
    if (td.is_array()) {
        if (dst.resizable >= 0)
            resize_array(fd, b, dst, ef, count, "a method's array argument");
        else if (count != td.array)
            err.fail(b, "an array of " + std::to_string(count) + " elements for " +
                            type_spec_name(td));
    }
    const std::size_t nf = static_cast<std::size_t>(count) * ef;
    if (nf == 0) return true; // an empty array: nothing to copy
    auto one = [&](std::size_t i) {
        const float* s = src.at(src.varying ? i : first);
        float* d = dst.at(i);
        if (how == Fit::Splat)
            std::fill(d, d + ef, *s);
        else
            std::memcpy(d, s, sizeof(float) * nf);
    };
    if (!dst.varying) {
        if (first < fd.n) one(first);
        return true;
    }
    for (std::size_t i = 0; i < fd.n; ++i)
        if (mask[i]) one(i);
    return true;
}

/// Writes `v` into symbol `to` of frame f at the points of `mask`.
void fill_value(Frame& f, int to, const std::vector<uint8_t>& mask, std::size_t first,
                float v) {
    Slot& d = f.slots[std::size_t(to)];
    if (d.resizable >= 0) return;
    for (std::size_t i = 0; i < f.n; ++i) {
        if (d.varying ? !mask[i] : i != first) continue;
        std::fill(d.at(i), d.at(i) + d.nf, v);
    }
}

std::size_t first_of(const std::vector<uint8_t>& mask) {
    return static_cast<std::size_t>(std::find(mask.begin(), mask.end(), uint8_t(1)) -
                                    mask.begin());
}

// --- getshader, getlight, getshaders, getlights ------------------------------

std::vector<std::string> categories_of(const ShaderInstance& inst) {
    return split_words(inst.string_parameter("__category").value_or(""));
}

void op_getshader(Frame& f, const BoundOp& b) {
    Impl& ctx = *f.ctx;
    const bool light = b.op->name == "getlight";
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        const std::string& handle = f.str(b, 1, i);
        float v = 0.0f;
        if (light) {
            for (std::size_t l = 0; l < ctx.lights.size() && v == 0.0f; ++l)
                if (ctx.lights[l]->handle() == handle)
                    v = object_handle(ctx, ctx.lights[l], static_cast<int>(l));
        } else {
            for (const ShaderInstance* s : ctx.coshaders)
                if (s->handle() == handle) {
                    v = object_handle(ctx, s, -1);
                    break;
                }
        }
        *d.at(i) = v;
    });
}

void op_getshaders(Frame& f, const BoundOp& b) {
    Impl& ctx = *f.ctx;
    const bool lights = b.op->name == "getlights";
    const std::size_t first = f.first_active();
    std::string category;
    for_options(f, b, 1, [&](const std::string& name, int k) {
        if (name == "category")
            category = f.str(b, k, first);
        else
            f.warn_once(b, b.op->name + ": unknown option \"" + name + "\" ignored");
    });
    std::vector<float> handles;
    if (lights) {
        for (std::size_t l = 0; l < ctx.lights.size(); ++l)
            if (category_matches(category, categories_of(*ctx.lights[l])))
                handles.push_back(object_handle(ctx, ctx.lights[l], static_cast<int>(l)));
    } else {
        for (const ShaderInstance* s : ctx.coshaders)
            if (category_matches(category, categories_of(*s)))
                handles.push_back(object_handle(ctx, s, -1));
    }
    Slot& a = f.slot(b, 0);
    resize_array(f, b, a, 1, static_cast<double>(handles.size()), b.op->name.c_str());
    if (handles.empty()) return;
    for (std::size_t i = 0; i < (a.varying ? f.n : 1); ++i)
        std::copy(handles.begin(), handles.end(), a.at(i));
}

// --- getvar -------------------------------------------------------------------

/// The symbol of a parameter or member variable `name` of frame f, or -1.
int variable_of(const Frame& f, const std::string& name) {
    const int s = f.program->find(name);
    if (s < 0) return -1;
    const SymbolKind k = f.program->symbols[std::size_t(s)].kind;
    return k == SymbolKind::Param || k == SymbolKind::OutputParam ||
                   k == SymbolKind::Local
               ? s
               : -1;
}

void op_getvar(Frame& f, const BoundOp& b) {
    const std::size_t first = f.first_active();
    ShaderObject* obj = object_of(f, b, *f.ptr(b, 1, first));
    bool found = false;
    if (obj) {
        Frame* of = nullptr;
        if (obj->light >= 0)
            of = evaluate_light(f, *obj, f.mask, f.active).frame.get();
        else
            of = &coshader_frame(f, b, *obj);
        const int s = variable_of(*of, f.str(b, 2, first));
        if (s >= 0) {
            found = true;
            if (b.op->args.size() > 3)
                found = copy_value(*of, s, f, b.op->args[3], f.mask, first, f, b);
        }
    }
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) { *d.at(i) = found ? 1.0f : 0.0f; });
}

// --- method calls ---------------------------------------------------------------

constexpr int kFirstArg = 3; ///< callmethod d handle "name" args...

std::string method_text(const ShaderObject& obj, const std::string& name) {
    return "method '" + name + "' of shader '" + obj.instance->program().name + "'";
}

/// The globals a classic shader takes when called by the name of its type
/// (`s->surface(Ci, Oi)`), or null when `name` is not that.
const std::vector<std::string>* classic_method(const Program& p,
                                               const std::string& name) {
    static const std::vector<std::string> colour{"Ci", "Oi"}, moved{"P", "N"},
        lit{"L", "Cl"};
    if (p.is_class() || name != shader_kind_name(p.kind)) return nullptr;
    switch (p.kind) {
    case ShaderKind::Surface:
    case ShaderKind::Volume:
        return &colour;
    case ShaderKind::Displacement:
        return &moved;
    case ShaderKind::Light:
        return &lit;
    default:
        return nullptr;
    }
}

bool has_method(const Program& p, const std::string& name) {
    return p.find_method(name) >= 0 || classic_method(p, name) != nullptr;
}

/// A classic shader's body run for `s->surface(Ci, Oi)` and the like.
void run_classic(Frame& f, const BoundOp& b, ShaderObject& obj, Frame& cf,
                 const std::vector<std::string>& globals,
                 const std::vector<uint8_t>& group, std::size_t count,
                 std::size_t first) {
    const Program& p = *cf.program;
    const std::string name = f.str(b, 2); // a copy: running shaders add strings
    const std::size_t nargs = b.op->args.size() - kFirstArg;
    if (nargs != globals.size())
        f.fail(b, method_text(obj, name) + " takes (" + globals[0] + ", " + globals[1] +
                      ")");
    CallGuard guard(f, b, obj);
    std::vector<int> syms(nargs, -1);
    for (std::size_t k = 0; k < nargs; ++k) {
        const int s = p.find(globals[k]);
        if (s < 0 || p.symbols[std::size_t(s)].kind != SymbolKind::Global) continue;
        syms[k] = s;
        if (!copy_value(f, b.op->args[kFirstArg + k], cf, s, group, first, f, b))
            f.fail(b, "argument " + std::to_string(k + 1) + " of " +
                          method_text(obj, name) + " does not fit " + globals[k]);
    }
    cf.mask = group;
    cf.active = count;
    std::fill(cf.stop.begin(), cf.stop.end(), 0u);
    cf.run(p.body_begin, static_cast<int>(p.ops.size()));
    for (std::size_t k = 0; k < nargs; ++k) {
        const std::size_t a = kFirstArg + k;
        if (syms[k] < 0 || !((b.op->writes >> a) & 1u)) continue;
        if (!copy_value(cf, syms[k], f, b.op->args[a], group, first, f, b))
            f.fail(b, globals[k] + " of " + method_text(obj, name) +
                          " does not fit the variable given");
    }
    if (b.op->writes & 1u) fill_value(f, b.op->args[0], group, first, 0.0f);
}

/// light(L, Cl[, Ol]) of a light: the light evaluated at the caller's points.
void call_light(Frame& f, const BoundOp& b, ShaderObject& obj,
                const std::vector<uint8_t>& group, std::size_t count, std::size_t first) {
    const int nargs = static_cast<int>(b.op->args.size()) - kFirstArg;
    if (nargs < 2 || nargs > 3)
        f.fail(b, method_text(obj, "light") + " takes (L, Cl) or (L, Cl, Ol)");
    LightState& ls = evaluate_light(f, obj, group, count);
    const std::vector<glm::vec3>* values[3] = {&ls.L, &ls.Cl, &ls.Ol};
    for (int k = 0; k < nargs; ++k) {
        const int a = kFirstArg + k;
        if (!((b.op->writes >> a) & 1u)) continue;
        const Symbol& sym = f.program->symbols[std::size_t(b.op->args[std::size_t(a)])];
        if (sym.type.is_array() || !is_triple(sym.type.type))
            f.fail(b, "argument " + std::to_string(k + 1) + " of " +
                          method_text(obj, "light") + " must be a " +
                          (k == 0 ? "vector" : "color"));
        Slot& d = f.slot(b, a);
        for (std::size_t i = 0; i < f.n; ++i)
            if (d.varying ? group[i] != 0 : i == first) st3(d.at(i), (*values[k])[i]);
    }
    if (b.op->writes & 1u) fill_value(f, b.op->args[0], group, first, 0.0f);
}

/// Runs method `mi` of frame cf for the points of `group`, arguments in and out.
void run_method(Frame& f, const BoundOp& b, ShaderObject& obj, Frame& cf, int mi,
                const std::vector<uint8_t>& group, std::size_t count, std::size_t first) {
    const Method& m = cf.program->methods[std::size_t(mi)];
    const std::size_t nargs = b.op->args.size() - kFirstArg;
    if (nargs != m.params.size())
        f.fail(b, method_text(obj, m.name) + " takes " + std::to_string(m.params.size()) +
                      " arguments, not " + std::to_string(nargs));
    CallGuard guard(f, b, obj);
    for (std::size_t k = 0; k < nargs; ++k) {
        const int arg = b.op->args[kFirstArg + k];
        if (!copy_value(f, arg, cf, m.params[k], group, first, f, b))
            f.fail(b, "argument " + std::to_string(k + 1) + " of " +
                          method_text(obj, m.name) + " is a " +
                          type_spec_name(f.program->symbols[std::size_t(arg)].type) +
                          "; the method takes a " +
                          type_spec_name(cf.program->symbols[m.params[k]].type));
    }
    cf.mask = group;
    cf.active = count;
    std::fill(cf.stop.begin(), cf.stop.end(), 0u);
    cf.run(m.begin, m.end);
    for (std::size_t k = 0; k < nargs; ++k) {
        if (!((m.outputs >> k) & 1u)) continue;
        const std::size_t a = kFirstArg + k;
        if (!((b.op->writes >> a) & 1u)) {
            f.warn_once(b, "argument " + std::to_string(k + 1) + " of " +
                               method_text(obj, m.name) +
                               " is an output, but the call passes a value: the "
                               "output is dropped");
            continue;
        }
        if (!copy_value(cf, m.params[k], f, b.op->args[a], group, first, f, b))
            f.fail(b, "output " + std::to_string(k + 1) + " of " +
                          method_text(obj, m.name) + " does not fit the variable given");
    }
    if (!(b.op->writes & 1u)) return;
    if (m.result < 0) {
        fill_value(f, b.op->args[0], group, first, 0.0f);
    } else if (!copy_value(cf, m.result, f, b.op->args[0], group, first, f, b)) {
        f.fail(b,
               method_text(obj, m.name) + " returns a " +
                   type_spec_name(cf.program->symbols[std::size_t(m.result)].type) +
                   ", used as a " +
                   type_spec_name(f.program->symbols[std::size_t(b.op->args[0])].type));
    }
}

/// The call for the points of `group`, whose handle is `v`.
void call_one(Frame& f, const BoundOp& b, float v, const std::vector<uint8_t>& group,
              std::size_t count) {
    const std::string name = f.str(b, 2); // a copy: running shaders add strings
    const std::size_t first = first_of(group);
    ShaderObject* obj = object_of(f, b, v);
    if (!obj) {
        f.warn_once(b, "method '" + name + "' called on a null shader: nothing runs");
        if (b.op->writes & 1u) fill_value(f, b.op->args[0], group, first, 0.0f);
        return;
    }
    if (obj->light >= 0 && name == "light") {
        call_light(f, b, *obj, group, count, first);
        return;
    }
    Frame& cf = obj->light >= 0 ? *evaluate_light(f, *obj, group, count).frame
                                : coshader_frame(f, b, *obj);
    const int mi = cf.program->find_method(name);
    if (const std::vector<std::string>* globals = classic_method(*cf.program, name)) {
        run_classic(f, b, *obj, cf, *globals, group, count, first);
        return;
    }
    if (mi < 0) {
        f.warn_once(b, "shader '" + cf.program->name + "' has no method '" + name +
                           "': the call does nothing");
        if (b.op->writes & 1u) fill_value(f, b.op->args[0], group, first, 0.0f);
        return;
    }
    run_method(f, b, *obj, cf, mi, group, count, first);
}

void op_callmethod(Frame& f, const BoundOp& b) {
    const Slot& h = f.slot(b, 1);
    if (!h.varying) {
        call_one(f, b, *h.p, f.mask, f.active);
        return;
    }
    // A varying handle: one call per distinct shader, for its points.
    std::vector<uint8_t>& done = f.push_mask();
    std::fill(done.begin(), done.end(), 0);
    std::vector<uint8_t>& group = f.push_mask();
    for (std::size_t i = 0; i < f.n; ++i) {
        if (!f.mask[i] || done[i]) continue;
        const float v = *h.at(i);
        std::size_t count = 0;
        for (std::size_t k = 0; k < f.n; ++k) {
            const bool on = f.mask[k] && !done[k] && *h.at(k) == v;
            group[k] = on;
            done[k] = done[k] || on;
            count += on;
        }
        call_one(f, b, v, group, count);
    }
    f.pop_mask();
    f.pop_mask();
}

void op_hasmethod(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) {
        const ShaderObject* obj = object_of(f, b, *f.ptr(b, 1, i));
        *d.at(i) =
            obj && has_method(obj->instance->program(), f.str(b, 2, i)) ? 1.0f : 0.0f;
    });
}

// --- binders ------------------------------------------------------------------

bool is_shader(const BindInfo& in, int k) {
    return in.is(k, ShadingType::Shader);
}

bool bind_getshader(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 2 || !is_shader(in, 0) || !in.is_string(1)) return false;
    b.fn = op_getshader;
    return true;
}

bool bind_getshaders(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() < 1 || (in.nargs() - 1) % 2 != 0 || !in.sym(0).type.is_resizable() ||
        in.type(0) != ShadingType::Shader || in.op.writes != 1)
        return false;
    for (int k = 1; k < in.nargs(); k += 2)
        if (!in.is_string(k) || !in.is_string(k + 1)) return false;
    b.fn = op_getshaders;
    return true;
}

bool bind_getvar(const BindInfo& in, BoundOp& b, std::string&) {
    if ((in.nargs() != 3 && in.nargs() != 4) || !in.is_float(0) || !is_shader(in, 1) ||
        !in.is_string(2) || in.op.writes != (in.nargs() == 4 ? 9u : 1u))
        return false;
    b.fn = op_getvar;
    return true;
}

bool bind_hasmethod(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_float(0) || !is_shader(in, 1) || !in.is_string(2))
        return false;
    b.fn = op_hasmethod;
    return true;
}

bool bind_callmethod(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() < kFirstArg || in.is_array(0) || !is_shader(in, 1) ||
        !in.is_string(2) || in.writes(1) || in.writes(2))
        return false;
    b.fn = op_callmethod;
    return true;
}

} // namespace

void register_coshader(BinderTable& t) {
    t["getshader"] = bind_getshader;
    t["getlight"] = bind_getshader;
    t["getshaders"] = bind_getshaders;
    t["getlights"] = bind_getshaders;
    t["getvar"] = bind_getvar;
    t["hasmethod"] = bind_hasmethod;
    t["callmethod"] = bind_callmethod;
}

} // namespace sss::detail
