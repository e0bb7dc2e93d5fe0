// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file codegen_class.cpp
/// RSL 2.0 shader classes in the code generator: `class name(params) {
/// members; methods }`. The parameters are the shader's; member variables
/// are symbols of the whole program, initialised by the ops
/// [body_begin, init_end); each public method (and each pipeline method:
/// construct, begin, displacement, opacity, surface, prelighting, lighting,
/// postlighting, light, volume) is emitted once as a Method, a `block` of
/// its own whose parameters are symbols (a pipeline method's parameters are
/// the globals they name: `surface(output color Ci, Oi)`). Calls between
/// methods of the class are inlined like functions, and see the members.
/// The pipelines list, per kind the class runs as, the methods the renderer
/// runs in order.

#include "codegen_internal.h"

namespace sss::detail::codegen {

namespace {

bool is_surface_stage(const std::string& n) {
    return n == "surface" || n == "opacity" || n == "prelighting" || n == "lighting" ||
           n == "postlighting";
}

bool is_pipeline_method(const std::string& n) {
    return is_surface_stage(n) || n == "displacement" || n == "light" || n == "volume" ||
           n == "construct" || n == "begin";
}

/// The kind a class runs as from the names of its methods (Shader: none of
/// the pipeline methods), or false with `why` for an impossible mix.
bool class_kind(const ShaderDef& c, ShaderKind& kind, std::string& why) {
    bool surface = false, displacement = false, light = false, volume = false;
    for (const auto& m : c.methods) {
        surface = surface || is_surface_stage(m->name);
        displacement = displacement || m->name == "displacement";
        light = light || m->name == "light";
        volume = volume || m->name == "volume";
    }
    if (light && (surface || displacement || volume)) {
        why = "a class with a light() method is a light shader: it cannot also have "
              "surface, displacement or volume methods";
        return false;
    }
    if (volume && (surface || displacement)) {
        why = "a class with a volume() method is a volume shader: it cannot also have "
              "surface or displacement methods";
        return false;
    }
    kind = light          ? ShaderKind::Light
           : volume       ? ShaderKind::Volume
           : surface      ? ShaderKind::Surface
           : displacement ? ShaderKind::Displacement
                          : ShaderKind::Shader;
    return true;
}

/// The kind whose rules (globals, statements) a method's body follows.
ShaderKind method_kind(const std::string& name, ShaderKind primary) {
    if (name == "displacement") return ShaderKind::Displacement;
    if (is_surface_stage(name)) return ShaderKind::Surface;
    // A co-shader's methods run on its caller's surface points.
    return primary == ShaderKind::Shader ? ShaderKind::Surface : primary;
}

} // namespace

Program Generator::run_class() {
    const ShaderDef& c = m_shader;
    m_p.name = c.name;
    m_p.files = m_d.source().files;
    if (m_p.files.empty()) m_p.files.push_back("<string>");
    m_p.source_path = m_p.files.front();
    m_loc = c.loc;
    std::string why;
    ShaderKind kind = ShaderKind::Shader;
    if (!class_kind(c, kind, why)) error(c.loc, "class '" + c.name + "': " + why);
    m_p.kind = kind;
    m_kind = method_kind("", kind);
    m_kind_bit = kind_bit(m_kind);

    Scope* params = new_scope(nullptr);
    for (const auto& f : m_file.functions)
        params->funcs[f->name].push_back({f.get(), params});
    m_scope = params;
    for (const VarDecl& group : c.params) parameter_group(group);
    m_p.body_begin = here();

    m_regions.push_back({Region::Body, {}, false});
    Scope* members = new_scope(params);
    for (const auto& m : c.methods)
        members->funcs[m->name].push_back({m.get(), members, true});
    m_scope = members;
    for (const VarDecl& d : c.members) declaration(d);
    m_p.init_end = here();

    std::set<std::string> emitted;
    for (const auto& m : c.methods) {
        const bool pipeline = is_pipeline_method(m->name);
        if (!m->is_public && !pipeline) continue; // inlined where it is called
        if (!emitted.insert(m->name).second) {
            error(m->loc, "class '" + c.name + "' defines the method '" + m->name +
                              "' twice (a public method has one definition)");
            continue;
        }
        standalone_method(*m, members, method_kind(m->name, kind), pipeline);
    }
    m_scope = members;
    pop_region();
    class_pipelines();
    return std::move(m_p);
}

void Generator::standalone_method(const FuncDef& f, Scope* members, ShaderKind kind,
                                  bool pipeline) {
    LocGuard lg(*this, f.loc);
    const ShaderKind saved_kind = m_kind;
    const unsigned saved_bit = m_kind_bit;
    m_kind = kind;
    m_kind_bit = kind_bit(kind);
    Method m;
    m.name = f.name;
    m.is_public = true;
    const int inst = ++m_instances;
    const std::string suffix = "@" + std::to_string(inst);
    const std::string prefix = f.name + "::";
    Scope* params = new_scope(members);
    bool ok = true;
    for (const UParam& up : user_params(f)) {
        const VarDecl& g = *up.group;
        const Declarator& d = *up.decl;
        if (params->vars.count(d.name)) {
            error(d.loc, "parameter '" + d.name + "' is declared twice");
            ok = false;
            continue;
        }
        if (m.params.size() >= 63) {
            error(d.loc, "method '" + f.name + "' has more than 63 parameters");
            ok = false;
            break;
        }
        const TypeSpec t{g.type, d.array};
        Var pv;
        if (pipeline) {
            // The renderer runs the pipeline methods: their parameters are
            // the globals they name (`surface(output color Ci, Oi)`).
            const Var* gv = find_global(d.name) ? global(d.name, d.loc) : nullptr;
            if (!gv) {
                error(d.loc, "parameter '" + d.name + "' of the pipeline method '" +
                                 f.name + "' must be a global variable of " +
                                 (kind == ShaderKind::Imager ? "an " : "a ") +
                                 shader_kind_name(kind) +
                                 " shader (as in surface(output "
                                 "color Ci, Oi))");
                ok = false;
                continue;
            }
            if (type(gv->sym) != t) {
                error(d.loc, "parameter '" + d.name + "' of '" + f.name + "' is " +
                                 tname(t) + " but the global '" + d.name + "' is " +
                                 tname(type(gv->sym)));
                ok = false;
                continue;
            }
            if (g.output && gv->readonly) {
                error(d.loc, "parameter '" + d.name + "' of '" + f.name +
                                 "' cannot be output: the global is read-only in a " +
                                 shader_kind_name(kind) + " shader");
                ok = false;
                continue;
            }
            pv = *gv;
            pv.readonly = gv->readonly || !g.output;
        } else {
            // Called by other shaders with values of their own: varying
            // unless declared uniform.
            pv.sym = add_symbol(unique_name(prefix + d.name + suffix), t,
                                g.storage != Storage::Uniform, SymbolKind::Local);
            pv.readonly = !g.output;
            pv.what = "function parameter";
        }
        params->vars[d.name] = pv;
        if (g.output) m.outputs |= uint64_t(1) << m.params.size();
        m.params.push_back(pv.sym);
    }
    FuncCtx ctx;
    ctx.def = &f;
    ctx.instance = inst;
    if (f.result != ShadingType::Void)
        ctx.result = add_symbol(unique_name(prefix + "result" + suffix), {f.result, 0},
                                true, SymbolKind::Temp);
    m.result = ctx.result;
    m.begin = here();
    m_inline.push_back(&f);
    function_block(ctx, params);
    m_inline.pop_back();
    m.end = here();
    if (ok) m_p.methods.push_back(std::move(m));
    m_kind = saved_kind;
    m_kind_bit = saved_bit;
}

void Generator::class_pipelines() {
    auto index = [&](const char* name) { return m_p.find_method(name); };
    std::vector<int> head;
    for (const char* n : {"construct", "begin"})
        if (index(n) >= 0) head.push_back(index(n));
    auto add = [&](ShaderKind k, std::initializer_list<const char*> names) {
        Pipeline p;
        p.kind = k;
        p.methods = head;
        bool any = false;
        for (const char* n : names)
            if (index(n) >= 0) {
                p.methods.push_back(index(n));
                any = true;
            }
        if (any) m_p.pipelines.push_back(std::move(p));
    };
    add(ShaderKind::Displacement, {"displacement"});
    add(ShaderKind::Light, {"light"});
    add(ShaderKind::Volume, {"volume"});
    // PRMan runs prelighting, lighting and postlighting when the class has
    // them (they are what re-lighting re-runs), else surface.
    const bool staged =
        index("prelighting") >= 0 || index("lighting") >= 0 || index("postlighting") >= 0;
    if (staged) {
        add(ShaderKind::Surface, {"opacity", "prelighting", "lighting", "postlighting"});
        if (index("surface") >= 0)
            m_d.warning(m_shader.loc,
                        "class '" + m_shader.name +
                            "' has lighting methods and surface(): the renderer runs "
                            "prelighting, lighting and postlighting, not surface()");
    } else {
        add(ShaderKind::Surface, {"opacity", "surface"});
    }
    if (m_p.kind == ShaderKind::Shader) {
        Pipeline p;
        p.kind = ShaderKind::Shader;
        p.methods = head;
        m_p.pipelines.push_back(std::move(p));
    }
}

} // namespace sss::detail::codegen
