// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file engine_texture.cpp
/// Texture built-ins through the TextureLibrary (texture, environment,
/// textureinfo, texture3d), bake3d records (ShadingServices::bake3d), and
/// the queries attribute, option, rendererinfo, rayinfo and the message
/// passing functions displacement/atmosphere (which return 0; surface and
/// lightsource are in engine_lighting.cpp).
///
///  - texture(file[ch], [s, t | s1,t1..s4,t4], options): without
///    coordinates the globals s, t; the filter footprint is the differences
///    of s and t to the neighbour points (Du(s) du...). A file that cannot
///    be read is a ShaderRuntimeError (texture3d too).
///  - environment(file[ch], dir): dir converted to world space; the name
///    "raytrace" traces rays instead (environment_raytrace,
///    engine_raytrace.cpp).
///  - shadow(map[ch], P | P1..P4, options) on a depth map: P (or the quad's
///    centre) in world space, its footprint the differences of P to the
///    neighbour points (or the quad's edges), the bias the call's, else
///    the scene's (scene_shadow_bias); the fraction in shadow per point,
///    every channel of a colour result alike (TextureServices::shadow).
///  - rayinfo: "depth", "type", "label" (ShadingBatch::ray), "origin",
///    "direction", "length" (from I).
///  - texture3d(file, P, N, "channel", out...): P and N converted to the
///    option "coordsystem" (default world); outputs written only where the
///    lookup finds data (returns 1 there, 0 elsewhere).
///  - bake3d(file, channels, P, N, "channel", value...): a Bake3dRecord of
///    the running points, P and N in "coordsystem" (default world), radius
///    from "radius" (times "radiusscale") or ShadingBatch::radius or
///    sqrt(area / pi) of the micropolygon; channels from the comma/space
///    separated list, each matched to its token-value pair (a listed
///    channel without a value warns once and is left out). Returns 1 for the
///    points written.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "engine_internal.h"
#include "sss/light/shadow_map.h"
#include "sss/shading/texture_services.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"
#include "sss/util/parse.h"
#include "sss/util/version.h"
#include "texture_options.h"

namespace sss::detail {

namespace {

/// The job's texture services (null: every lookup fails, "no texture services").
TextureServices* library(Frame& f) {
    return f.ctx->services.textures();
}

/// Running points as a byte mask (the frame's running mask).
const uint8_t* run_mask(Frame& f) {
    return f.mask.data();
}

/// Number of leading float arguments from `first` (up to a string).
int count_floats(const BindInfo& in, int first) {
    int k = first;
    while (k < in.nargs() && in.is_float(k)) ++k;
    return k - first;
}

bool options_ok(const BindInfo& in, int first) {
    if ((in.nargs() - first) % 2 != 0) return false;
    for (int k = first; k < in.nargs(); k += 2)
        if (!in.is_string(k)) return false;
    return true;
}

/// Values of argument k for every point (n x comps floats).
std::vector<float> gather(Frame& f, const Slot& s, int comps) {
    std::vector<float> out(f.n * comps);
    for (std::size_t i = 0; i < f.n; ++i)
        std::memcpy(&out[i * comps], s.at(i), sizeof(float) * comps);
    return out;
}

/// Differences along u and v (derivative times du / dv).
void differences(Frame& f, const Slot& s, int comps, const std::string& name,
                 std::vector<float>& du, std::vector<float>& dv) {
    du.assign(f.n * comps, 0.0f);
    dv.assign(f.n * comps, 0.0f);
    derivative(f, s, comps, 0, name, du.data());
    derivative(f, s, comps, 1, name, dv.data());
    const ShadingBatch* b = f.ctx->batch;
    for (std::size_t i = 0; i < f.n; ++i) {
        const float a = b && b->du.size() > i ? b->du[i] : 0.0f;
        const float c = b && b->dv.size() > i ? b->dv[i] : 0.0f;
        for (int k = 0; k < comps; ++k) {
            du[i * comps + k] *= a;
            dv[i * comps + k] *= c;
        }
    }
}

void read_texture_options(Frame& f, const BoundOp& b, int first, TextureOptions& o) {
    const std::size_t i0 = f.first_active();
    for_options(f, b, first, [&](const std::string& name, int k) {
        const Slot& s = f.slot(b, k);
        const bool str =
            f.program->symbols[b.op->args[k]].type.type == ShadingType::String;
        const std::string* text = str ? &f.str(b, k, i0) : nullptr;
        if (!set_texture_option(o, name, str ? nullptr : s.at(i0), str ? 0 : s.nf, text))
            f.warn_once(b, "unknown texture option \"" + name + "\"; ignored");
    });
}

void write_result(Frame& f, Slot& d, const std::vector<float>& out, int nc) {
    f.each(d.varying, [&](std::size_t i) {
        float* o = d.at(i);
        if (d.nf == nc)
            std::memcpy(o, &out[i * nc], sizeof(float) * nc);
        else
            for (int k = 0; k < d.nf; ++k) o[k] = out[i * nc + std::min(k, nc - 1)];
    });
}

// --- texture ------------------------------------------------------------------

void op_texture(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const int nc = d.nf;
    const std::size_t n = f.n;
    const std::size_t i0 = f.first_active();
    const std::string& file = f.str(b, 1, i0);
    // texture("") is 0, quietly, as in PRMan: library shaders call it
    // unguarded with an empty default map name. A named map that cannot be
    // read stays an error (below).
    if (file.empty()) {
        write_result(f, d, std::vector<float>(n * std::size_t(nc), 0.0f), nc);
        return;
    }
    const int channel = static_cast<int>(*f.ptr(b, 2, i0));
    const int coords = b.ia; // 0, 2 or 8
    TextureOptions o;
    read_texture_options(f, b, 3 + coords, o);
    std::vector<float> out(n * nc, 0.0f);
    TextureServices* lib = library(f);
    std::string error;
    bool ok = false;
    if (!lib) {
        error = "no texture services";
    } else if (coords == 8) {
        std::vector<std::vector<float>> st(8);
        const float* ptrs[8];
        for (int k = 0; k < 8; ++k) {
            st[k] = gather(f, f.slot(b, 3 + k), 1);
            ptrs[k] = st[k].data();
        }
        ok = lib->texture_quad(file, channel, nc, o, n, ptrs, run_mask(f), out.data(),
                               &error);
    } else {
        const Slot* ss;
        const Slot* ts;
        std::string sname = "s", tname = "t";
        std::vector<float> fallback_s, fallback_t;
        Slot fs, ft;
        if (coords == 2) {
            ss = &f.slot(b, 3);
            ts = &f.slot(b, 4);
            sname = f.program->symbols[b.op->args[3]].name;
            tname = f.program->symbols[b.op->args[4]].name;
        } else {
            const int* g = f.bound->globals;
            const ShadingBatch* batch = f.ctx->batch;
            auto global_slot = [&](int id, const std::vector<float>& a,
                                   const std::vector<float>& alt, std::vector<float>& own,
                                   Slot& tmp) -> const Slot* {
                if (g[id] >= 0) return &f.slots[g[id]];
                own.assign(n, 0.0f);
                const std::vector<float>& src = a.size() >= n ? a : alt;
                for (std::size_t i = 0; i < n && i < src.size(); ++i) own[i] = src[i];
                tmp.p = own.data();
                tmp.nf = 1;
                tmp.stride = 1;
                tmp.varying = true;
                return &tmp;
            };
            static const std::vector<float> none;
            ss = global_slot(G_s, batch ? batch->s : none, batch ? batch->u : none,
                             fallback_s, fs);
            ts = global_slot(G_t, batch ? batch->t : none, batch ? batch->v : none,
                             fallback_t, ft);
        }
        const std::vector<float> s = gather(f, *ss, 1), t = gather(f, *ts, 1);
        std::vector<float> dsdu, dsdv, dtdu, dtdv;
        differences(f, *ss, 1, sname, dsdu, dsdv);
        differences(f, *ts, 1, tname, dtdu, dtdv);
        ok = lib->texture(file, channel, nc, o, n, s.data(), t.data(), dsdu.data(),
                          dtdu.data(), dsdv.data(), dtdv.data(), run_mask(f), out.data(),
                          &error);
    }
    if (!ok) {
        // A map that cannot be read stops the job: a frame rendered without
        // its textures must not pass for a finished one.
        f.fail(b, "texture \"" + file + "\": " + error);
    }
    write_result(f, d, out, nc);
}

bool bind_texture(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() < 3 || !(in.is_float(0) || in.is_color(0)) || !in.is_string(1) ||
        !in.is_float(2))
        return false;
    const int coords = count_floats(in, 3);
    if (coords != 0 && coords != 2 && coords != 8) return false;
    if (!options_ok(in, 3 + coords)) return false;
    b.ia = coords;
    b.fn = op_texture;
    return true;
}

void op_environment(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const int nc = d.nf;
    const std::size_t n = f.n;
    const std::size_t i0 = f.first_active();
    const std::string& file = f.str(b, 1, i0);
    if (file.empty()) { // as texture("")
        write_result(f, d, std::vector<float>(n * std::size_t(nc), 0.0f), nc);
        return;
    }
    if (file == "raytrace") {
        environment_raytrace(f, b);
        return;
    }
    const int channel = static_cast<int>(*f.ptr(b, 2, i0));
    TextureOptions o;
    read_texture_options(f, b, 4, o);
    const Slot& ds = f.slot(b, 3);
    std::vector<float> du, dv;
    differences(f, ds, 3, f.program->symbols[b.op->args[3]].name, du, dv);
    const glm::dmat4& m = f.ctx->camera_to_world;
    std::vector<glm::vec3> dir(n), ddu(n), ddv(n);
    for (std::size_t i = 0; i < n; ++i) {
        dir[i] = xform_vector(m, ld3(ds.at(i)));
        ddu[i] = xform_vector(m, ld3(&du[i * 3]));
        ddv[i] = xform_vector(m, ld3(&dv[i * 3]));
    }
    std::vector<float> out(n * nc, 0.0f);
    std::string error;
    TextureServices* lib = library(f);
    const bool ok =
        lib && lib->environment(file, channel, nc, o, n, dir.data(), ddu.data(),
                                ddv.data(), run_mask(f), out.data(), &error);
    if (!ok) {
        f.fail(b,
               "environment \"" + file + "\": " + (lib ? error : "no texture services"));
    }
    write_result(f, d, out, nc);
}

bool bind_environment(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() < 4 || !(in.is_float(0) || in.is_color(0)) || !in.is_string(1) ||
        !in.is_float(2) || !in.is_ptype(3) || !options_ok(in, 4))
        return false;
    b.fn = op_environment;
    return true;
}

// --- shadow maps -------------------------------------------------------------------

} // namespace

void shadow_map_lookup(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const std::size_t n = f.n;
    const std::size_t i0 = f.first_active();
    const std::string& file = f.str(b, 1, i0);
    const int points = b.ia == 4 ? 4 : 1;
    TextureOptions o;
    read_texture_options(f, b, 3 + points, o);
    // Without "bias": the scene's Option "shadow" "bias", else PRMan's default.
    if (!(o.bias >= 0.0f)) o.bias = scene_shadow_bias(f.ctx->services.scene());
    const glm::dmat4& m = f.ctx->camera_to_world;
    std::vector<glm::vec3> P(n), du(n), dv(n);
    if (points == 4) {
        // The quad's corners as texture()'s: 1 at (0,0), 2 at (1,0), 3 at
        // (0,1), 4 at (1,1); the lookup at their mean, its footprint the
        // mean edges.
        for (std::size_t i = 0; i < n; ++i) {
            glm::vec3 c[4];
            for (int k = 0; k < 4; ++k) c[k] = xform_point(m, ld3(f.ptr(b, 3 + k, i)));
            P[i] = 0.25f * (c[0] + c[1] + c[2] + c[3]);
            du[i] = 0.5f * ((c[1] - c[0]) + (c[3] - c[2]));
            dv[i] = 0.5f * ((c[2] - c[0]) + (c[3] - c[1]));
        }
    } else {
        const Slot& ps = f.slot(b, 3);
        std::vector<float> eu, ev;
        differences(f, ps, 3, f.program->symbols[b.op->args[3]].name, eu, ev);
        for (std::size_t i = 0; i < n; ++i) {
            P[i] = xform_point(m, ld3(ps.at(i)));
            du[i] = xform_vector(m, ld3(&eu[i * 3]));
            dv[i] = xform_vector(m, ld3(&ev[i * 3]));
        }
    }
    std::vector<float> out(n, 0.0f);
    std::string error;
    TextureServices* lib = library(f);
    const bool ok = lib && lib->shadow(file, o, n, P.data(), du.data(), dv.data(),
                                       run_mask(f), out.data(), &error);
    // A named map that cannot be read stops the job, as texture()'s.
    if (!ok)
        f.fail(b, "shadow \"" + file + "\": " + (lib ? error : "no texture services"));
    f.each(d.varying, [&](std::size_t i) {
        const float v = std::isfinite(out[i]) ? out[i] : 0.0f;
        std::fill(d.at(i), d.at(i) + d.nf, v);
    });
}

namespace {

// --- textureinfo, attribute, option ------------------------------------------------

/// Writes `numbers` / `text` to the output argument k if its type fits.
struct QueryValue {
    std::vector<float> numbers;
    std::string text;
    bool is_string = false;
    bool matrix = false; ///< numbers hold a matrix
};

bool write_query(Frame& f, const BoundOp& b, int k, const QueryValue& v) {
    const Symbol& sym = f.program->symbols[b.op->args[k]];
    Slot& s = f.slot(b, k);
    if (sym.type.type == ShadingType::String) {
        if (!v.is_string || sym.type.is_array()) return false;
        const float idx = f.ctx->intern(v.text);
        f.each(s.varying, [&](std::size_t i) { *s.at(i) = idx; });
        return true;
    }
    if (v.is_string || static_cast<int>(v.numbers.size()) != s.nf) return false;
    if (v.matrix != (sym.type.type == ShadingType::Matrix && !sym.type.is_array()))
        return false;
    f.each(s.varying, [&](std::size_t i) {
        std::memcpy(s.at(i), v.numbers.data(), sizeof(float) * s.nf);
    });
    return true;
}

void set_result(Frame& f, const BoundOp& b, float r) {
    Slot& d = f.slot(b, 0);
    f.each(d.varying, [&](std::size_t i) { *d.at(i) = r; });
}

void op_textureinfo(Frame& f, const BoundOp& b) {
    const std::size_t i0 = f.first_active();
    const std::string& file = f.str(b, 1, i0);
    const std::string& key = f.str(b, 2, i0);
    // A file this job writes is never read, not even its header.
    if (std::string conflict = JobFiles::opened(file, "a textureinfo lookup");
        !conflict.empty())
        f.fail(b, "textureinfo \"" + file + "\": " + conflict);
    const Symbol& sym = f.program->symbols[b.op->args[3]];
    const bool str = sym.type.type == ShadingType::String;
    QueryValue v;
    v.is_string = str;
    v.matrix = sym.type.type == ShadingType::Matrix;
    const int expected = str ? 0 : sym.type.floats();
    v.numbers.assign(expected, 0.0f);
    TextureServices* lib = library(f);
    bool ok = lib && lib->texture_info(file, key, expected, v.numbers.data(), &v.text);
    if (ok) ok = write_query(f, b, 3, v);
    set_result(f, b, ok ? 1.0f : 0.0f);
}

bool bind_textureinfo(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 4 || !in.is_float(0) || !in.is_string(1) || !in.is_string(2))
        return false;
    b.fn = op_textureinfo;
    return true;
}

const Attributes* attributes_for(Frame& f) {
    const ShadingBatch* batch = f.ctx->batch;
    return batch && batch->primitive ? &attributes_of(*batch->primitive) : nullptr;
}

QueryValue from_param(const Param& p) {
    QueryValue v;
    if (p.type == ParamType::String) {
        v.is_string = true;
        v.text = p.strings.empty() ? "" : p.strings[0];
        return v;
    }
    for (double d : p.numbers) v.numbers.push_back(static_cast<float>(d));
    v.matrix = p.type == ParamType::Matrix;
    return v;
}

QueryValue number(double x) {
    QueryValue v;
    v.numbers = {static_cast<float>(x)};
    return v;
}
QueryValue triple(const glm::dvec3& c) {
    QueryValue v;
    v.numbers = {static_cast<float>(c.x), static_cast<float>(c.y),
                 static_cast<float>(c.z)};
    return v;
}
QueryValue text(const std::string& s) {
    QueryValue v;
    v.is_string = true;
    v.text = s;
    return v;
}

/// A "group:name" lookup in a map of parameter lists.
bool user_value(const std::map<std::string, ParamList>& groups, const std::string& name,
                QueryValue& v) {
    const auto colon = name.find(':');
    if (colon == std::string::npos) return false;
    auto it = groups.find(name.substr(0, colon));
    if (it == groups.end()) return false;
    const Param* p = it->second.find(name.substr(colon + 1));
    if (!p) return false;
    v = from_param(*p);
    return true;
}

void op_attribute(Frame& f, const BoundOp& b) {
    const std::string& name = f.str(b, 1, f.first_active());
    const Attributes* a = attributes_for(f);
    static const Attributes kDefault;
    if (!a) a = &kDefault;
    const ShadingBatch* batch = f.ctx->batch;
    const bool out_string =
        f.program->symbols[b.op->args[2]].type.type == ShadingType::String;
    QueryValue v;
    bool known = true;
    if (name == "identifier:name")
        v = text(a->name());
    else if (name == "ShadingRate" || name == "Ri:ShadingRate")
        v = number(a->shading_rate);
    else if (name == "Ri:Sides" || name == "Sides")
        v = number(a->sides);
    else if (name == "Ri:Orientation" || name == "Orientation")
        v = out_string ? text(a->orientation_inside ? "inside" : "outside")
                       : number(a->orientation_inside ? 1.0 : 0.0);
    else if (name == "Ri:Color" || name == "Color")
        v = triple(a->color);
    else if (name == "Ri:Opacity" || name == "Opacity")
        v = triple(a->opacity);
    else if (name == "Ri:ShadingInterpolation")
        v = text(a->shading_interpolation);
    else if (name == "Ri:Transformation") {
        v.matrix = true;
        v.numbers.assign(16, 0.0f);
        stm(v.numbers.data(),
            batch && batch->primitive ? batch->primitive->object_to_world : Matrix4(1.0));
    } else
        known = user_value(a->groups, name, v);
    set_result(f, b, known && write_query(f, b, 2, v) ? 1.0f : 0.0f);
}

void op_option(Frame& f, const BoundOp& b) {
    const std::string& name = f.str(b, 1, f.first_active());
    const RenderOptions& o = f.ctx->services.scene().options;
    const Camera& cam = o.camera;
    QueryValue v;
    bool known = true;
    if (name == "Format" || name == "Ri:Format") {
        v.numbers = {static_cast<float>(cam.xres), static_cast<float>(cam.yres),
                     static_cast<float>(cam.pixel_aspect)};
    } else if (name == "Frame" || name == "Ri:Frame") {
        const std::optional<int> frame =
            f.ctx->services.frame() ? f.ctx->services.frame() : o.frame;
        known = frame.has_value();
        if (known) v = number(*frame);
    } else if (name == "FrameAspectRatio" || name == "Ri:FrameAspectRatio") {
        v = number(static_cast<double>(cam.xres) * cam.pixel_aspect / cam.yres);
    } else if (name == "Clipping" || name == "Ri:Clipping") {
        v.numbers = {static_cast<float>(cam.near_clip), static_cast<float>(cam.far_clip)};
    } else if (name == "PixelSamples" || name == "Ri:PixelSamples") {
        v.numbers = {static_cast<float>(o.pixel_samples[0]),
                     static_cast<float>(o.pixel_samples[1])};
    } else if (name == "Hider" || name == "Ri:Hider") {
        v = text(o.hider);
    } else {
        known = user_value(o.groups, name, v);
    }
    set_result(f, b, known && write_query(f, b, 2, v) ? 1.0f : 0.0f);
}

void op_rendererinfo(Frame& f, const BoundOp& b) {
    const std::string& name = f.str(b, 1, f.first_active());
    QueryValue v;
    bool known = true;
    if (name == "renderer")
        v = text("sss");
    else if (name == "versionstring")
        v = text(version_string());
    else
        known = false;
    set_result(f, b, known && write_query(f, b, 2, v) ? 1.0f : 0.0f);
}

/// rayinfo(key, out v): "depth", "type", "label" of how the batch was
/// reached (ShadingBatch::ray); "origin", "direction", "length" of the ray
/// to each point, from I (origin = P - I, direction = normalize(I), length
/// = |I|, current space). Unknown keys (or a variable of the wrong type)
/// return 0 and leave v alone.
void op_rayinfo(Frame& f, const BoundOp& b) {
    const std::string& name = f.str(b, 1, f.first_active());
    const ShadingBatch* batch = f.ctx->batch;
    static const RayContext kCamera;
    const RayContext& ray = batch ? batch->ray : kCamera;
    QueryValue v;
    bool known = true;
    if (name == "depth") {
        v = number(ray.depth);
    } else if (name == "type") {
        v = text(ray_kind_name(ray.kind));
    } else if (name == "label") {
        v = text(ray.label);
    } else if (name == "origin" || name == "direction" || name == "length") {
        const Symbol& sym = f.program->symbols[b.op->args[2]];
        const bool want_float = name == "length";
        const bool fits =
            !sym.type.is_array() && (want_float ? sym.type.type == ShadingType::Float
                                                : is_point_like(sym.type.type));
        if (!fits) {
            set_result(f, b, 0.0f);
            return;
        }
        const int* g = f.bound->globals;
        const Slot* Is = g[G_I] >= 0 ? &f.slots[g[G_I]] : nullptr;
        const Slot* Ps = g[G_P] >= 0 ? &f.slots[g[G_P]] : nullptr;
        Slot& out = f.slot(b, 2);
        f.each(out.varying, [&](std::size_t i) {
            glm::vec3 I(0.0f), P(0.0f);
            if (Is)
                I = ld3(Is->at(i));
            else if (batch && batch->I.size() > i)
                I = batch->I[i];
            if (Ps)
                P = ld3(Ps->at(i));
            else if (batch && batch->P.size() > i)
                P = batch->P[i];
            const float len = glm::length(I);
            if (name == "length")
                *out.at(i) = std::isfinite(len) ? len : 0.0f;
            else if (name == "origin")
                st3(out.at(i), P - I);
            else
                st3(out.at(i),
                    len > 0.0f && std::isfinite(len) ? I / len : glm::vec3(0.0f));
        });
        set_result(f, b, 1.0f);
        return;
    } else {
        known = false;
    }
    set_result(f, b, known && write_query(f, b, 2, v) ? 1.0f : 0.0f);
}

/// displacement() and atmosphere(): a surface shader cannot reach its
/// displacement shader's values (displacement runs when the dicer makes the
/// grids), and there are no volume shaders: returns 0 and leaves the variable
/// alone. (surface() and lightsource() are in engine_lighting.cpp.)
void op_message(Frame& f, const BoundOp& b) {
    set_result(f, b, 0.0f);
}

/// raylevel(): PRMan's depth of the ray that reached the batch (0: camera).
void op_raylevel(Frame& f, const BoundOp& b) {
    const ShadingBatch* batch = f.ctx->batch;
    set_result(f, b, batch ? static_cast<float>(batch->ray.depth) : 0.0f);
}

bool bind_raylevel(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 1 || !in.is_float(0)) return false;
    b.fn = op_raylevel;
    return true;
}

bool bind_query(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() != 3 || !in.is_float(0) || !in.is_string(1)) return false;
    const std::string& n = in.op.name;
    b.fn = n == "attribute"      ? op_attribute
           : n == "option"       ? op_option
           : n == "rendererinfo" ? op_rendererinfo
           : n == "rayinfo"      ? op_rayinfo
                                 : op_message;
    return true;
}

// --- texture3d and bake3d ----------------------------------------------------------

glm::dmat4 current_to(Frame& f, const BoundOp& b, const std::string& space) {
    return glm::inverse(named_space_to_current(f, b, space));
}

void op_texture3d(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const std::size_t n = f.n;
    const std::size_t i0 = f.first_active();
    const std::string& file = f.str(b, 1, i0);
    Texture3dOptions o;
    std::vector<std::string> channels;
    std::vector<int> outs;
    for_options(f, b, 4, [&](const std::string& name, int k) {
        const Slot& s = f.slot(b, k);
        const bool str =
            f.program->symbols[b.op->args[k]].type.type == ShadingType::String;
        if (set_texture3d_option(o, name, str ? nullptr : s.at(i0), str ? 0 : s.nf,
                                 str ? &f.str(b, k, i0) : nullptr))
            return;
        channels.push_back(name);
        outs.push_back(k);
    });
    const glm::dmat4 m = current_to(f, b, o.coordsystem);
    std::vector<glm::vec3> P(n), N(n);
    // Without "filterradius", the shading point's own filter radius (the
    // renderer's pixel footprint, the baker's micropolygon), else 0.
    const ShadingBatch* shading = f.ctx->batch;
    const bool own_radius = o.filterradius < 0.0f;
    std::vector<float> radius(n, std::max(o.filterradius, 0.0f) * o.filterscale);
    for (std::size_t i = 0; i < n; ++i) {
        if (own_radius && shading && shading->radius.size() >= n)
            radius[i] = shading->radius[i] * o.filterscale;
        P[i] = xform_point(m, ld3(f.ptr(b, 2, i)));
        N[i] = xform_normal(m, ld3(f.ptr(b, 3, i)));
    }
    std::vector<uint8_t> found(n, 0);
    std::vector<int> floats;
    std::vector<float> out;
    std::string error;
    TextureServices* lib = library(f);
    bool ok = false;
    if (lib && !channels.empty()) {
        // Stride at most the sum of the outputs' sizes.
        int stride = 0;
        for (int k : outs) stride += f.slot(b, k).nf;
        out.assign(n * static_cast<std::size_t>(std::max(stride, 1)), 0.0f);
        ok = lib->texture3d(file, channels, n, P.data(), N.data(), radius.data(),
                            run_mask(f), floats, out.data(), found.data(), &error);
    }
    if (!ok) {
        if (!lib) f.fail(b, "texture3d \"" + file + "\": no texture services");
        if (!channels.empty()) f.fail(b, "texture3d: " + error);
        set_result(f, b, 0.0f);
        return;
    }
    if (!error.empty()) f.fail(b, "texture3d: " + error);
    int stride = 0;
    for (int c : floats) stride += c;
    f.each(d.varying, [&](std::size_t i) {
        if (!found[i]) {
            *d.at(i) = 0.0f;
            return;
        }
        *d.at(i) = 1.0f;
        int off = 0;
        for (std::size_t c = 0; c < channels.size(); ++c) {
            const int cf = floats[c];
            Slot& s = f.slot(b, outs[c]);
            if (cf > 0 && cf == s.nf)
                std::memcpy(s.at(i), &out[i * stride + off], sizeof(float) * cf);
            off += cf;
        }
    });
}

bool bind_texture3d(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() < 4 || !in.is_float(0) || !in.is_string(1) || !in.is_ptype(2) ||
        !in.is_ptype(3) || !options_ok(in, 4))
        return false;
    b.fn = op_texture3d;
    return true;
}

/// Counts `rec` against the job's bake3d budget: its file among the job's
/// files (BAKE3D_FILES), its points (BAKE3D_POINTS) and, every
/// kShaderMemoryStep of records, the memory budget.
void count_bake3d(Frame& f, const BoundOp& b, const Bake3dRecord& rec) {
    ShadingResources::Impl& r = f.ctx->resources.impl();
    const uint64_t points = rec.P.size();
    const uint64_t bytes = sizeof(Bake3dRecord) + rec.file.size() +
                           points * (2 * sizeof(glm::vec3) + 2 * sizeof(float)) +
                           rec.values.size() * sizeof(float);
    const uint64_t max_files = limit(Limit::Bake3dFiles);
    const uint64_t max_points = limit(Limit::Bake3dPoints);
    bool new_file = false, too_many_files = false, too_many_points = false;
    uint64_t check_bytes = 0;
    {
        std::lock_guard<std::mutex> lock(r.bake3d_mutex);
        if (!r.bake3d_files.count(rec.file)) {
            new_file = true;
            too_many_files = r.bake3d_files.size() >= max_files;
            if (!too_many_files) r.bake3d_files.insert(rec.file);
        }
        r.bake3d_points += points;
        too_many_points = r.bake3d_points > max_points;
        r.bake3d_bytes += bytes;
        if (r.bake3d_bytes >= r.bake3d_checked_bytes + kShaderMemoryStep) {
            r.bake3d_checked_bytes = r.bake3d_bytes;
            check_bytes = r.bake3d_bytes;
        }
    }
    const std::string call = "bake3d \"" + rec.file + "\": ";
    if (new_file && too_many_files)
        f.fail(b, call + "a new file after " + std::to_string(max_files) +
                      ": the files of one job " + limit_exceeded(Limit::Bake3dFiles));
    if (too_many_points)
        f.fail(b, call + "the points baked in one job exceed the limit of " +
                      std::to_string(max_points) + " (set " +
                      limit_variable(Limit::Bake3dPoints) + " to raise it)");
    if (check_bytes)
        f.check_memory_for(b, kShaderMemoryStep,
                           call + "the job's bake3d points (" +
                               format_bytes(check_bytes) + ")");
}

void op_bake3d(Frame& f, const BoundOp& b) {
    Slot& d = f.slot(b, 0);
    const std::size_t n = f.n;
    const std::size_t i0 = f.first_active();
    Bake3dRecord rec;
    rec.file = f.str(b, 1, i0);
    // The system would cut the name at the NUL: "x\0y.ptc" would write "x".
    if (rec.file.find('\0') != std::string::npos)
        f.fail(b, "bake3d " + sss::quoted(rec.file) +
                      ": a file name cannot hold a NUL byte");
    Bake3dOptions o;
    std::vector<std::pair<std::string, int>> values;
    for_options(f, b, 5, [&](const std::string& name, int k) {
        const Slot& s = f.slot(b, k);
        const bool str =
            f.program->symbols[b.op->args[k]].type.type == ShadingType::String;
        if (name == "radius" || name == "radiusscale" || name == "coordsystem" ||
            name == "interpolate") {
            if (!set_bake3d_option(o, name, str ? nullptr : s.at(i0), str ? 0 : s.nf,
                                   str ? &f.str(b, k, i0) : nullptr))
                f.warn_once(b, "bad bake3d option " + sss::quoted(name));
            return;
        }
        values.emplace_back(name, k);
    });
    std::vector<int> chan_args;
    for (const std::string& c : split_words(f.str(b, 2, i0))) {
        int arg = -1;
        for (const auto& [name, k] : values)
            if (name == c) arg = k;
        if (arg < 0) {
            f.fail(b, "bake3d " + sss::quoted(rec.file) + ": channel " + sss::quoted(c) +
                          " is listed but the call gives it no value");
        }
        if (f.program->symbols[b.op->args[arg]].type.type == ShadingType::String) {
            f.warn_once(b,
                        "bake3d: channel " + sss::quoted(c) + " is a string; not baked");
            continue;
        }
        rec.channels.push_back(c);
        rec.channel_floats.push_back(f.slot(b, arg).nf);
        chan_args.push_back(arg);
    }
    const glm::dmat4 m = current_to(f, b, o.coordsystem);
    // Radii: the option, the batch's, or the micropolygon's.
    std::vector<float> area;
    const ShadingBatch* batch = f.ctx->batch;
    const bool need_area = o.radius < 0.0f && !(batch && batch->radius.size() >= n) &&
                           !(batch && batch->dicing_area.size() >= n);
    if (need_area) {
        std::vector<float> eu(n * 3), ev(n * 3);
        const Slot& p = f.slot(b, 3);
        const std::string& pname = f.program->symbols[b.op->args[3]].name;
        differences(f, p, 3, pname, eu, ev);
        area.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            area[i] = glm::length(glm::cross(ld3(&eu[i * 3]), ld3(&ev[i * 3])));
    }
    const double scale = std::cbrt(std::abs(glm::determinant(glm::dmat3(m))));
    int stride = 0;
    for (int c : rec.channel_floats) stride += c;
    f.each(true, [&](std::size_t i) {
        rec.P.push_back(xform_point(m, ld3(f.ptr(b, 3, i))));
        rec.N.push_back(xform_normal(m, ld3(f.ptr(b, 4, i))));
        float r;
        if (o.radius >= 0.0f)
            r = o.radius;
        else if (batch && batch->radius.size() >= n)
            r = batch->radius[i];
        else {
            const float a = need_area ? area[i] : batch->dicing_area[i];
            // The micropolygon's area, in current units -> the file's space.
            r = static_cast<float>(std::sqrt(std::max(a, 0.0f) / 3.14159265358979) *
                                   scale);
        }
        rec.radius.push_back(r * o.radiusscale);
        rec.area.push_back(batch && batch->dicing_area.size() >= n ? batch->dicing_area[i]
                           : need_area                             ? area[i]
                                                                   : 0.0f);
        for (std::size_t c = 0; c < chan_args.size(); ++c) {
            const float* v = f.ptr(b, chan_args[c], i);
            // A cloud holds finite numbers only: the shader's line, not the
            // writer at the end of the job, says which value is not.
            for (int k = 0; k < rec.channel_floats[c]; ++k)
                if (!std::isfinite(v[k]))
                    f.fail(b, "bake3d " + sss::quoted(rec.file) + ": channel " +
                                  sss::quoted(rec.channels[c]) + " is " +
                                  (std::isnan(v[k]) ? "NaN" : "infinite") +
                                  " at a shaded point");
            rec.values.insert(rec.values.end(), v, v + rec.channel_floats[c]);
        }
        const glm::dvec3 p = rec.P.back(), nn = rec.N.back();
        if (!std::isfinite(p.x + p.y + p.z) || !std::isfinite(nn.x + nn.y + nn.z) ||
            !std::isfinite(rec.radius.back()))
            f.fail(b, "bake3d " + sss::quoted(rec.file) +
                          ": a position, normal or radius that is not a finite number");
    });
    (void)stride;
    if (!rec.P.empty()) {
        count_bake3d(f, b, rec);
        f.ctx->services.bake3d(std::move(rec));
    }
    f.each(d.varying, [&](std::size_t i) { *d.at(i) = 1.0f; });
}

bool bind_bake3d(const BindInfo& in, BoundOp& b, std::string&) {
    if (in.nargs() < 5 || !in.is_float(0) || !in.is_string(1) || !in.is_string(2) ||
        !in.is_ptype(3) || !in.is_ptype(4) || !options_ok(in, 5))
        return false;
    for (int k = 6; k < in.nargs(); k += 2)
        if (in.is_array(k)) return false;
    b.fn = op_bake3d;
    return true;
}

} // namespace

void register_texture(BinderTable& t) {
    t["texture"] = bind_texture;
    t["environment"] = bind_environment;
    t["textureinfo"] = bind_textureinfo;
    t["texture3d"] = bind_texture3d;
    t["bake3d"] = bind_bake3d;
    t["attribute"] = bind_query;
    t["option"] = bind_query;
    t["rendererinfo"] = bind_query;
    t["rayinfo"] = bind_query;
    t["raylevel"] = bind_raylevel;
    t["displacement"] = bind_query;
    t["atmosphere"] = bind_query;
}

} // namespace sss::detail
