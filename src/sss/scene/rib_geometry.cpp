// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_geometry.cpp
/// The reader's geometry requests: topology and parameter checks of every
/// primitive, and the position parameter resolved from "P", "Pw" or "Pz".

#include "rib_reader.h"

#include <algorithm>
#include <limits>

#include "rib_args.h"
#include "sss/scene/blobby.h"
#include "sss/util/limits.h"

namespace sss::rib {

namespace {

/// The element counts a primitive's parameters must have, per storage class.
/// The reader counts facevertex values like facevarying ones (one per face
/// corner), so both get the same number.
ClassCounts counts(std::size_t uniform, std::size_t varying, std::size_t vertex,
                   std::size_t facevarying) {
    return {uniform, varying, vertex, facevarying, facevarying};
}

/// Every other parameter must have the number of values its class asks for.
void check_counts(const Statement& s, const ParamList& params, const ClassCounts& n) {
    for (const Param& p : params.items) {
        if (p.name == "P") continue;
        std::size_t want = n.of(p.storage);
        if (p.element_count() != want)
            fail(s, "parameter \"" + p.name + "\" (" + param_class_name(p.storage) + " " +
                        param_type_name(p.type) + ") has " +
                        std::to_string(p.element_count()) + " values, expected " +
                        std::to_string(want));
    }
}

/// The vertices a topology uses: its largest index + 1.
std::size_t vertex_count(const std::vector<int>& verts) {
    int m = -1;
    for (int v : verts) m = std::max(m, v);
    return static_cast<std::size_t>(m + 1);
}

/// Limit::PrimitiveVertices: a primitive's points and its face corners
/// (vertex indices) may not exceed it; LimitError naming the statement.
void check_vertices(const Statement& s, std::size_t count) {
    check_limit(Limit::PrimitiveVertices, count, where(s) + ": " + s.name);
}

/// The sum of counts (nvertices, nloops).
std::size_t sum(const std::vector<int>& v) {
    std::size_t total = 0;
    for (int k : v) total += static_cast<std::size_t>(k);
    return total;
}

/// The vertex indices must be as many as the vertex counts add up to.
void check_indices(const Statement& s, const std::vector<int>& verts,
                   std::size_t expected) {
    if (verts.size() != expected)
        fail(s, "vertices has " + std::to_string(verts.size()) +
                    " indices, the vertex counts add up to " + std::to_string(expected));
}

/// Patches and varying values along one direction of a patch mesh.
void patch_dir(const Statement& s, const char* dir, int n, bool wrap, bool bicubic,
               int step, std::size_t& patches, std::size_t& varying) {
    if (!bicubic) {
        if (n < 2) fail(s, std::string(dir) + " is too small for a bilinear mesh");
        patches = static_cast<std::size_t>(wrap ? n : n - 1);
        varying = static_cast<std::size_t>(n);
        return;
    }
    if (wrap) {
        if (n < step || n % step != 0)
            fail(s, std::string(dir) + " = " + std::to_string(n) +
                        " must be a positive multiple of the basis step " +
                        std::to_string(step) + " for a periodic mesh");
        patches = static_cast<std::size_t>(n / step);
        varying = patches;
    } else {
        if (n < 4 || (n - 4) % step != 0)
            fail(s, std::string(dir) + " = " + std::to_string(n) +
                        " must be 4 + a multiple of the basis step " +
                        std::to_string(step));
        patches = static_cast<std::size_t>((n - 4) / step + 1);
        varying = patches + 1;
    }
}

/// A PatchMesh wrap mode: "periodic" (true) or "nonperiodic" (false).
bool take_wrap(const Statement& s, std::size_t& i, const char* what) {
    std::string w = take_string(s, i, what);
    if (w == "periodic") return true;
    if (w == "nonperiodic") return false;
    fail(s, std::string(what) + " must be periodic or nonperiodic, got \"" + w + "\"");
}

} // namespace

void Reader::add_primitive(const Statement& s, Primitive p, const Matrix4& object_to_ctm,
                           const std::string& source) {
    if (!m_object && !m_in_world) fail(s, "geometry outside WorldBegin/WorldEnd");
    place(p, object_to_ctm);
    p.source = source;
    if (m_motion_capture) { // a time sample of a moving primitive (MotionEnd keeps it)
        m_motion_prims.back().push_back(std::move(p));
        return;
    }
    store_primitive(std::move(p));
}

void Reader::store_primitive(Primitive p) {
    if (m_object) {
        p.attributes.reset(); // objects take the attributes of each instance
        m_object->push_back(std::move(p));
    } else {
        p.attributes = snapshot();
        m_scene.primitives.push_back(std::move(p));
    }
}

void Reader::add_primitive(const Statement& s, Primitive p) {
    add_primitive(s, std::move(p), Matrix4(1.0), where(s));
}

void Reader::resolve_positions(const Statement& s, ParamList& params,
                               std::size_t n_points, int grid_nu, int grid_nv, bool uwrap,
                               bool vwrap) {
    auto remove = [&](std::string_view name) {
        std::erase_if(params.items, [&](const Param& p) { return p.name == name; });
    };
    const Param* P = params.find("P");
    const Param* Pw = params.find("Pw");
    const Param* Pz = params.find("Pz");
    if ((P != nullptr) + (Pw != nullptr) + (Pz != nullptr) > 1)
        fail(s, "give only one of \"P\", \"Pw\" and \"Pz\"");
    if (P) {
        if (P->type != ParamType::Point || P->array_size != 1)
            fail(s,
                 "\"P\" must be a point, not " + std::string(param_type_name(P->type)));
    } else if (Pw) {
        if (Pw->type != ParamType::HPoint || Pw->array_size != 1)
            fail(s, "\"Pw\" must be an hpoint");
        Param np;
        np.name = "P";
        np.type = ParamType::Point;
        np.storage = ParamClass::Vertex;
        bool uniform_w = true;
        const auto& h = Pw->numbers;
        for (std::size_t k = 0; k + 3 < h.size(); k += 4) {
            double w = h[k + 3];
            if (w == 0.0) fail(s, "\"Pw\" has a point with w = 0");
            if (w != h[3]) uniform_w = false;
            for (int c = 0; c < 3; ++c) np.numbers.push_back(h[k + c] / w);
        }
        if (!uniform_w && grid_nu > 0)
            warn_once("rational " + s.name, s,
                      s.name + ": rational patches are approximated by dividing by w");
        remove("Pw");
        params.items.push_back(std::move(np));
    } else if (Pz) {
        if (grid_nu <= 0) fail(s, "\"Pz\" is only for patches");
        if (Pz->type != ParamType::Float || Pz->array_size != 1)
            fail(s, "\"Pz\" must be a float");
        if (Pz->numbers.size() != n_points)
            fail(s, "\"Pz\" has " + std::to_string(Pz->numbers.size()) +
                        " values, expected " + std::to_string(n_points));
        // A height field over the unit square, u varying fastest.
        Param np;
        np.name = "P";
        np.type = ParamType::Point;
        np.storage = ParamClass::Vertex;
        double du = 1.0 / (uwrap ? grid_nu : grid_nu - 1);
        double dv = 1.0 / (vwrap ? grid_nv : grid_nv - 1);
        for (int v = 0; v < grid_nv; ++v)
            for (int u = 0; u < grid_nu; ++u) {
                np.numbers.push_back(u * du);
                np.numbers.push_back(v * dv);
                np.numbers.push_back(
                    Pz->numbers[static_cast<std::size_t>(v) * grid_nu + u]);
            }
        remove("Pz");
        params.items.push_back(std::move(np));
    } else {
        fail(s, "missing \"P\"");
    }
    const Param* p = params.find("P");
    if (p->element_count() != n_points)
        fail(s, "\"P\" has " + std::to_string(p->element_count()) + " points, expected " +
                    std::to_string(n_points));
}

void Reader::do_polygon(const Statement& s) {
    ParamList params = take_params(s, 0, false);
    const Param* P = params.find("P");
    const Param* Pw = params.find("Pw");
    std::size_t n = P ? P->element_count() : Pw ? Pw->element_count() : 0;
    if (n < 3)
        fail(s, "a polygon needs \"P\" with at least 3 points, got " + std::to_string(n));
    check_vertices(s, n);
    resolve_positions(s, params, n);
    check_counts(s, params, counts(1, n, n, n));
    Primitive p;
    p.kind = PrimitiveKind::Polygon;
    p.nverts = {static_cast<int>(n)};
    p.params = std::move(params);
    add_primitive(s, std::move(p));
}

void Reader::do_general_polygon(const Statement& s) {
    std::size_t i = 0;
    Primitive p;
    p.kind = PrimitiveKind::GeneralPolygon;
    p.nverts = take_ints(s, i, "nvertices", 3);
    if (p.nverts.empty()) fail(s, "no loops");
    p.params = take_params(s, i, false);
    std::size_t n = sum(p.nverts);
    check_vertices(s, n);
    resolve_positions(s, p.params, n);
    check_counts(s, p.params, counts(1, n, n, n));
    add_primitive(s, std::move(p));
}

void Reader::do_points_polygons(const Statement& s) {
    std::size_t i = 0;
    Primitive p;
    p.kind = PrimitiveKind::PointsPolygons;
    p.nverts = take_ints(s, i, "nvertices", 3);
    p.verts = take_ints(s, i, "vertices", 0);
    p.params = take_params(s, i, false);
    if (p.nverts.empty()) fail(s, "no polygons");
    check_vertices(s, p.verts.size());
    check_indices(s, p.verts, sum(p.nverts));
    std::size_t nv = vertex_count(p.verts);
    resolve_positions(s, p.params, nv);
    check_counts(s, p.params, counts(p.nverts.size(), nv, nv, p.verts.size()));
    add_primitive(s, std::move(p));
}

void Reader::do_points_general_polygons(const Statement& s) {
    std::size_t i = 0;
    Primitive p;
    p.kind = PrimitiveKind::PointsGeneralPolygons;
    p.nloops = take_ints(s, i, "nloops", 1);
    p.nverts = take_ints(s, i, "nvertices", 3);
    p.verts = take_ints(s, i, "vertices", 0);
    p.params = take_params(s, i, false);
    if (p.nloops.empty()) fail(s, "no polygons");
    if (p.nverts.size() != sum(p.nloops))
        fail(s, "nvertices has " + std::to_string(p.nverts.size()) +
                    " loops, nloops adds up to " + std::to_string(sum(p.nloops)));
    check_vertices(s, p.verts.size());
    check_indices(s, p.verts, sum(p.nverts));
    std::size_t nv = vertex_count(p.verts);
    resolve_positions(s, p.params, nv);
    check_counts(s, p.params, counts(p.nloops.size(), nv, nv, p.verts.size()));
    add_primitive(s, std::move(p));
}

void Reader::do_subdivision_mesh(const Statement& s) {
    // HierarchicalSubdivisionMesh: the same with 3 argument counts per tag
    // and string arguments (hierarchical edits).
    const bool hierarchical = s.name == "HierarchicalSubdivisionMesh";
    std::size_t i = 0;
    Primitive p;
    p.kind = PrimitiveKind::SubdivisionMesh;
    p.type = take_string(s, i, "scheme");
    p.nverts = take_ints(s, i, "nvertices", 3);
    p.verts = take_ints(s, i, "vertices", 0);
    std::vector<std::string> string_args;
    if (i < s.args.size() && s.args[i].is_array()) {
        p.tags = take_string_array(s, i, "tags");
        p.tag_nargs = take_ints(s, i, "nargs", 0);
        p.tag_intargs = take_ints(s, i, "intargs", std::numeric_limits<int>::min());
        p.tag_floatargs = take_float_array(s, i, "floatargs");
        if (hierarchical) string_args = take_string_array(s, i, "stringargs");
    }
    p.params = take_params(s, i, false);
    if (hierarchical) hierarchical_tags(s, p, string_args);
    check_subdivision_tags(s, p);
    if (p.nverts.empty()) fail(s, "no faces");
    check_vertices(s, p.verts.size());
    check_indices(s, p.verts, sum(p.nverts));
    std::size_t nv = vertex_count(p.verts);
    if (p.tag_nargs.size() != 2 * p.tags.size())
        fail(s, "nargs must have 2 numbers per tag: " + std::to_string(p.tags.size()) +
                    " tags, " + std::to_string(p.tag_nargs.size()) + " numbers");
    std::size_t ni = 0, nf = 0;
    for (std::size_t t = 0; t < p.tags.size(); ++t) {
        std::size_t ti = static_cast<std::size_t>(p.tag_nargs[2 * t]);
        std::size_t tf = static_cast<std::size_t>(p.tag_nargs[2 * t + 1]);
        if (ni + ti > p.tag_intargs.size() || nf + tf > p.tag_floatargs.size())
            fail(s, "tag \"" + p.tags[t] + "\" needs more arguments than given");
        const std::string& tag = p.tags[t];
        // Indices of the tags that name vertices or faces must exist.
        std::size_t limit = tag == "hole"                          ? p.nverts.size()
                            : (tag == "crease" || tag == "corner") ? nv
                                                                   : 0;
        if (limit)
            for (std::size_t k = ni; k < ni + ti; ++k)
                if (p.tag_intargs[k] < 0 ||
                    static_cast<std::size_t>(p.tag_intargs[k]) >= limit)
                    fail(s, "tag \"" + tag + "\": index " +
                                std::to_string(p.tag_intargs[k]) + " out of range");
        ni += ti;
        nf += tf;
    }
    if (ni != p.tag_intargs.size() || nf != p.tag_floatargs.size())
        fail(s, "tag argument counts do not match intargs/floatargs");
    resolve_positions(s, p.params, nv);
    check_counts(s, p.params, counts(p.nverts.size(), nv, nv, p.verts.size()));
    add_primitive(s, std::move(p));
}

void Reader::do_quadric(const Statement& s) {
    struct Q {
        std::string_view name;
        PrimitiveKind kind;
        std::size_t count;
    };
    static const Q table[] = {
        {"Sphere", PrimitiveKind::Sphere, 4},
        {"Cylinder", PrimitiveKind::Cylinder, 4},
        {"Cone", PrimitiveKind::Cone, 3},
        {"Disk", PrimitiveKind::Disk, 3},
        {"Torus", PrimitiveKind::Torus, 5},
        {"Hyperboloid", PrimitiveKind::Hyperboloid, 7},
        {"Paraboloid", PrimitiveKind::Paraboloid, 4},
    };
    const Q* q = nullptr;
    for (const Q& e : table)
        if (e.name == s.name) q = &e;
    std::size_t i = 0;
    Primitive p;
    p.kind = q->kind;
    p.args = take_numbers(s, i, q->count);
    p.params = take_params(s, i, false);
    if (p.params.has("P") || p.params.has("Pw") || p.params.has("Pz"))
        fail(s, "quadrics take no \"P\"");
    check_counts(s, p.params, counts(1, 4, 4, 4));
    add_primitive(s, std::move(p));
}

void Reader::do_patch(const Statement& s) {
    std::size_t i = 0;
    Primitive p;
    p.kind = PrimitiveKind::Patch;
    p.type = take_string(s, i, "patch type");
    p.params = take_params(s, i, false);
    int n;
    if (p.type == "bicubic")
        n = 4;
    else if (p.type == "bilinear")
        n = 2;
    else
        fail(s, "patch type must be bicubic or bilinear, got \"" + p.type + "\"");
    p.nu = p.nv = n;
    resolve_positions(s, p.params, static_cast<std::size_t>(n * n), n, n);
    check_counts(s, p.params, counts(1, 4, static_cast<std::size_t>(n * n), 4));
    add_primitive(s, std::move(p));
}

void Reader::do_patch_mesh(const Statement& s) {
    std::size_t i = 0;
    Primitive p;
    p.kind = PrimitiveKind::PatchMesh;
    p.type = take_string(s, i, "patch type");
    if (p.type != "bicubic" && p.type != "bilinear")
        fail(s, "patch type must be bicubic or bilinear, got \"" + p.type + "\"");
    p.nu = to_int(s, take_number(s, i), "nu");
    p.uwrap = take_wrap(s, i, "uwrap");
    p.nv = to_int(s, take_number(s, i), "nv");
    p.vwrap = take_wrap(s, i, "vwrap");
    p.params = take_params(s, i, false);
    bool bicubic = p.type == "bicubic";
    std::size_t pu, pv, vu, vv;
    patch_dir(s, "nu", p.nu, p.uwrap, bicubic, m_attr.attrs.u_basis.step, pu, vu);
    patch_dir(s, "nv", p.nv, p.vwrap, bicubic, m_attr.attrs.v_basis.step, pv, vv);
    std::size_t nvert = static_cast<std::size_t>(p.nu) * static_cast<std::size_t>(p.nv);
    check_vertices(s, nvert);
    resolve_positions(s, p.params, nvert, p.nu, p.nv, p.uwrap, p.vwrap);
    check_counts(s, p.params, counts(pu * pv, vu * vv, nvert, 4 * pu * pv));
    add_primitive(s, std::move(p));
}

namespace {

/// "width" is predeclared as a uniform shader parameter; on Points and
/// Curves it is the RI standard varying width, one per varying point.
void varying_width(ParamList& params, std::size_t varying) {
    for (Param& q : params.items)
        if (q.name == "width" && q.storage == ParamClass::Uniform &&
            q.element_count() == varying)
            q.storage = ParamClass::Varying;
}

} // namespace

void Reader::do_points(const Statement& s) {
    Primitive p;
    p.kind = PrimitiveKind::Points;
    p.params = take_params(s, 0, false);
    const Param* P = p.params.find("P");
    if (!P) P = p.params.find("Pw");
    const std::size_t n = P ? P->element_count() : 0;
    if (n == 0) fail(s, "no points (\"P\" is missing or empty)");
    check_vertices(s, n);
    resolve_positions(s, p.params, n);
    varying_width(p.params, n);
    check_counts(s, p.params, counts(1, n, n, n));
    add_primitive(s, std::move(p));
}

void Reader::do_curves(const Statement& s) {
    std::size_t i = 0;
    Primitive p;
    p.kind = PrimitiveKind::Curves;
    p.type = take_string(s, i, "curve type");
    if (p.type != "linear" && p.type != "cubic")
        fail(s, "curve type must be linear or cubic, got \"" + p.type + "\"");
    p.nverts = take_ints(s, i, "nvertices", 1);
    p.vwrap = take_wrap(s, i, "wrap");
    p.params = take_params(s, i, false);
    if (p.nverts.empty()) fail(s, "no curves");
    const bool cubic = p.type == "cubic";
    std::size_t varying = 0;
    for (int n : p.nverts) {
        std::size_t segments = 0, values = 0;
        patch_dir(s, "nvertices", n, p.vwrap, cubic, m_attr.attrs.v_basis.step, segments,
                  values);
        varying += values;
    }
    const std::size_t nvert = sum(p.nverts);
    check_vertices(s, nvert);
    resolve_positions(s, p.params, nvert);
    varying_width(p.params, varying);
    check_counts(s, p.params, counts(p.nverts.size(), varying, nvert, varying));
    add_primitive(s, std::move(p));
}

namespace {

/// A NuPatch or TrimCurve knot vector: n + order non-decreasing numbers,
/// with the range [min, max] inside the curve's domain
/// [knot[order - 1], knot[n]].
void check_knots(const Statement& s, const std::string& what, const double* knot, int n,
                 int order, double min, double max) {
    for (int k = 1; k < n + order; ++k)
        if (!(knot[k] >= knot[k - 1]))
            fail(s, what + " must not decrease (knot " + std::to_string(k) + ")");
    if (!(min < max) || min < knot[order - 1] || max > knot[n])
        fail(s, what + ": the range [" + fmt(min) + ", " + fmt(max) +
                    "] must be a non-empty part of [" + fmt(knot[order - 1]) + ", " +
                    fmt(knot[n]) + "]");
}

/// One direction of a NuPatch: n, order, knots, min, max.
void take_nurbs_dir(const Statement& s, std::size_t& i, const char* dir, int& n,
                    int& order, std::vector<double>& knot, double& min, double& max) {
    const std::string d = dir;
    n = to_int(s, take_number(s, i), "n" + d);
    order = to_int(s, take_number(s, i), d + "order");
    knot = take_float_array(s, i, (d + "knot").c_str());
    min = take_number(s, i);
    max = take_number(s, i);
    if (order < 1 || order > 16)
        fail(s, d + "order must be 1 to 16, not " + std::to_string(order));
    if (n < order)
        fail(s, "n" + d + " (" + std::to_string(n) + ") must be at least " + d +
                    "order (" + std::to_string(order) + ")");
    if (knot.size() != static_cast<std::size_t>(n) + static_cast<std::size_t>(order))
        fail(s, d + "knot has " + std::to_string(knot.size()) + " knots, expected n" + d +
                    " + " + d + "order = " + std::to_string(n + order));
    check_knots(s, d + "knot", knot.data(), n, order, min, max);
}

} // namespace

void Reader::do_nupatch(const Statement& s) {
    std::size_t i = 0;
    Primitive p;
    p.kind = PrimitiveKind::NuPatch;
    take_nurbs_dir(s, i, "u", p.nu, p.uorder, p.uknot, p.umin, p.umax);
    take_nurbs_dir(s, i, "v", p.nv, p.vorder, p.vknot, p.vmin, p.vmax);
    p.params = take_params(s, i, false);
    const std::size_t nvert =
        static_cast<std::size_t>(p.nu) * static_cast<std::size_t>(p.nv);
    check_vertices(s, nvert);
    // A rational patch keeps "Pw": its weights enter the basis.
    if (const Param* pw = p.params.find("Pw"); pw && !p.params.has("P")) {
        if (pw->type != ParamType::HPoint || pw->array_size != 1)
            fail(s, "\"Pw\" must be an hpoint");
        if (pw->element_count() != nvert)
            fail(s, "\"Pw\" has " + std::to_string(pw->element_count()) +
                        " points, expected " + std::to_string(nvert));
        for (std::size_t k = 3; k < pw->numbers.size(); k += 4)
            if (!(pw->numbers[k] > 0.0))
                fail(s, "\"Pw\" has a point with a weight w <= 0");
    } else {
        resolve_positions(s, p.params, nvert);
    }
    const std::size_t su = static_cast<std::size_t>(p.nu - p.uorder + 1);
    const std::size_t sv = static_cast<std::size_t>(p.nv - p.vorder + 1);
    check_counts(s, p.params,
                 counts(su * sv, (su + 1) * (sv + 1), nvert, (su + 1) * (sv + 1)));
    add_primitive(s, std::move(p));
}

void Reader::do_trim_curve(const Statement& s) {
    std::size_t i = 0;
    auto t = std::make_shared<TrimCurves>();
    t->ncurves = take_ints(s, i, "ncurves", 1);
    t->order = take_ints(s, i, "order", 2);
    t->knot = take_float_array(s, i, "knot");
    t->min = take_float_array(s, i, "min");
    t->max = take_float_array(s, i, "max");
    t->n = take_ints(s, i, "n", 2);
    t->u = take_float_array(s, i, "u");
    t->v = take_float_array(s, i, "v");
    t->w = take_float_array(s, i, "w");
    no_more_args(s, i);
    const std::size_t curves = sum(t->ncurves);
    for (const auto& [what, size] :
         {std::pair<const char*, std::size_t>{"order", t->order.size()},
          {"min", t->min.size()},
          {"max", t->max.size()},
          {"n", t->n.size()}})
        if (size != curves)
            fail(s, std::string(what) + " has " + std::to_string(size) +
                        " values, the loops have " + std::to_string(curves) + " curves");
    std::size_t knots = 0;
    std::size_t points = 0;
    for (std::size_t c = 0; c < curves; ++c) {
        if (t->n[c] < t->order[c])
            fail(s, "curve " + std::to_string(c) + ": n must be at least its order");
        const std::size_t k = static_cast<std::size_t>(t->n[c] + t->order[c]);
        if (knots + k > t->knot.size()) fail(s, "knot has too few knots for the curves");
        check_knots(s, "knot of curve " + std::to_string(c), &t->knot[knots], t->n[c],
                    t->order[c], t->min[c], t->max[c]);
        knots += k;
        points += static_cast<std::size_t>(t->n[c]);
    }
    if (knots != t->knot.size())
        fail(s, "knot has " + std::to_string(t->knot.size()) +
                    " knots, the curves need " + std::to_string(knots));
    if (t->u.size() != points || t->v.size() != points || t->w.size() != points)
        fail(s, "u, v and w need " + std::to_string(points) + " values each");
    for (double w : t->w)
        if (!(w > 0.0)) fail(s, "w must be > 0");
    check_vertices(s, points);
    attrs_mut().trim_curves = std::move(t);
}

void Reader::do_blobby(const Statement& s) {
    std::size_t i = 0;
    Primitive p;
    p.kind = PrimitiveKind::Blobby;
    p.nu = to_int(s, take_number(s, i), "nleaf");
    p.verts = take_ints(s, i, "code", 0);
    p.args = take_float_array(s, i, "floats");
    p.tags = take_string_array(s, i, "strings");
    p.params = take_params(s, i, false);
    if (p.nu < 1) fail(s, "nleaf must be at least 1, not " + std::to_string(p.nu));
    check_vertices(s, std::max(p.verts.size(), static_cast<std::size_t>(p.nu)));
    BlobbyProgram program;
    try {
        program = decode_blobby(p);
    } catch (const BlobbyOpcodeError& e) {
        not_implemented("blobby opcode " + std::to_string(e.opcode()), s,
                        "Blobby " + std::string(e.what()) +
                            " (not an opcode this toolchain knows)",
                        "the Blobby is skipped");
        return;
    } catch (const ValueError& e) {
        fail(s, e.what());
    }
    lenient_blobby_fields(s, p, program);
    if (p.params.has("P") || p.params.has("Pw") || p.params.has("Pz"))
        fail(s, "a Blobby takes no \"P\": its surface is where the field is 0.5");
    if (p.params.has("N")) {
        not_implemented("blobby N", s,
                        "\"N\" on a Blobby is not supported (its normals are the "
                        "field's gradient)",
                        "\"N\" is ignored");
        std::erase_if(p.params.items, [](const Param& q) { return q.name == "N"; });
    }
    const auto leaves = static_cast<std::size_t>(p.nu);
    check_counts(s, p.params, counts(1, leaves, leaves, leaves));
    add_primitive(s, std::move(p));
}

void Reader::lenient_blobby_fields(const Statement& s, Primitive& p,
                                   const BlobbyProgram& program) {
    bool rewrite = false;
    for (const BlobbyItem& item : program.items) {
        if (item.op == BlobbyOp::Plugin)
            not_implemented("blobby 1004", s,
                            "implicit field plugins of a Blobby (opcode 1004, code[" +
                                std::to_string(item.code_begin) + "]) are not supported",
                            "its field is 0");
        else
            continue;
        rewrite = true;
    }
    if (!rewrite) return;
    // Reading leniently: each such leaf becomes the constant 0, which keeps
    // the items, the leaves and the per-leaf values in place.
    std::vector<int> code;
    const auto zero = static_cast<int>(p.args.size());
    p.args.push_back(0.0);
    for (const BlobbyItem& item : program.items) {
        if (item.op == BlobbyOp::Plugin) {
            code.insert(code.end(), {1000, zero});
            continue;
        }
        code.insert(code.end(),
                    p.verts.begin() + static_cast<std::ptrdiff_t>(item.code_begin),
                    p.verts.begin() + static_cast<std::ptrdiff_t>(item.code_end));
    }
    p.verts = std::move(code);
}

void Reader::do_geometry(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "geometry name");
    if (name != "teapot") {
        not_implemented("geometry " + name, s,
                        "Geometry \"" + name + "\" is not supported", "skipped");
        return;
    }
    Primitive p;
    p.kind = PrimitiveKind::Teapot;
    p.params = take_params(s, i, false);
    for (const Param& q : p.params.items)
        if (q.storage != ParamClass::Constant && q.storage != ParamClass::Uniform)
            fail(s, "parameter \"" + q.name +
                        "\": only constant and uniform parameters "
                        "are allowed on the teapot");
    check_counts(s, p.params, counts(1, 1, 1, 1));
    add_primitive(s, std::move(p));
}

} // namespace sss::rib
