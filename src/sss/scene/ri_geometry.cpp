// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file ri_geometry.cpp
/// The Ri C binding's geometry and procedurals: each primitive's positional
/// arguments as its RIB request takes them, and the number of values each
/// storage class holds on it (RISpec 3.2's table), from which the length of
/// every parameter's values follows.

#include <algorithm>
#include <cstdarg>
#include <cstdlib>
#include <cstring>
#include <numeric>

#include "ri_call.h"
#include "rib_reader.h"

namespace sss::rib {

void ri_geometry_anchor() {}

} // namespace sss::rib

using sss::rib::ClassCounts;
using sss::rib::ri_guarded;
using sss::rib::ri_guarded_raw;
using sss::rib::RiCall;

namespace {

// Sum of n counts, each checked to be >= min_each.
std::size_t sum_of(RiCall& c, const RtInt* v, RtInt n, const char* what, RtInt min_each) {
    if (n < 0) c.fail(std::string("a negative number of ") + what);
    if (n > 0 && !v) c.fail(std::string("no ") + what + " (a null pointer)");
    std::size_t sum = 0;
    for (RtInt i = 0; i < n; ++i) {
        if (v[i] < min_each)
            c.fail(std::string(what) + "[" + std::to_string(i) + "] is " +
                   std::to_string(v[i]) + ", less than " + std::to_string(min_each));
        sum += std::size_t(v[i]);
    }
    return sum;
}

// 1 + the largest vertex index (0 without any).
std::size_t vertex_count(RiCall& c, const RtInt* verts, std::size_t n) {
    if (n > 0 && !verts) c.fail("no vertex indices (a null pointer)");
    std::size_t count = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (verts[i] < 0)
            c.fail("vertex index " + std::to_string(verts[i]) + " is negative");
        count = std::max(count, std::size_t(verts[i]) + 1);
    }
    return count;
}

ClassCounts counts(std::size_t uniform, std::size_t varying, std::size_t vertex,
                   std::size_t facevarying) {
    ClassCounts c;
    c.uniform = uniform;
    c.varying = varying;
    c.vertex = vertex;
    c.facevarying = facevarying;
    return c;
}

constexpr ClassCounts kQuadric{1, 4, 4, 4};

bool is(const char* token, const char* word) {
    return token && std::strcmp(token, word) == 0;
}

// Segments of a spline of n vertices along one direction.
std::size_t segments(RiCall& c, bool cubic, bool periodic, RtInt n, int step) {
    if (n < 1) c.fail("no vertices along a direction");
    if (!cubic) return periodic ? std::size_t(n) : std::size_t(n - 1);
    if (step < 1) c.fail("a basis step below 1");
    if (periodic) return std::size_t(n / step);
    if (n < 4) c.fail("a cubic direction needs at least 4 vertices");
    return std::size_t((n - 4) / step + 1);
}

void quadric(const char* request, std::initializer_list<double> args, RtInt n,
             RtToken tokens[], RtPointer values[]) {
    ri_guarded(request, [&](RiCall& c) {
        for (double a : args) c.number(a);
        c.params(n, tokens, values, kQuadric);
    });
}

} // namespace

extern "C" {

// --- polygons and meshes ------------------------------------------------------------

RtVoid RiPolygonV(RtInt nvertices, RtInt n, RtToken tokens[], RtPointer values[]) {
    ri_guarded("Polygon", [&](RiCall& c) {
        if (nvertices < 3) c.fail("a polygon needs at least 3 vertices");
        const std::size_t v = std::size_t(nvertices);
        c.params(n, tokens, values, counts(1, v, v, v));
    });
}
RtVoid RiPolygon(RtInt nvertices, ...) {
    SSS_RI_VARARGS(pv, nvertices);
    RiPolygonV(nvertices, pv.count(), pv.tokens.data(), pv.values.data());
}

RtVoid RiGeneralPolygonV(RtInt nloops, RtInt nverts[], RtInt n, RtToken tokens[],
                         RtPointer values[]) {
    ri_guarded("GeneralPolygon", [&](RiCall& c) {
        const std::size_t v = sum_of(c, nverts, nloops, "nverts", 3);
        c.ints(nverts, std::size_t(nloops), "nverts");
        c.params(n, tokens, values, counts(1, v, v, v));
    });
}
RtVoid RiGeneralPolygon(RtInt nloops, RtInt nverts[], ...) {
    SSS_RI_VARARGS(pv, nverts);
    RiGeneralPolygonV(nloops, nverts, pv.count(), pv.tokens.data(), pv.values.data());
}

RtVoid RiPointsPolygonsV(RtInt npolys, RtInt nverts[], RtInt verts[], RtInt n,
                         RtToken tokens[], RtPointer values[]) {
    ri_guarded("PointsPolygons", [&](RiCall& c) {
        const std::size_t corners = sum_of(c, nverts, npolys, "nverts", 3);
        const std::size_t v = vertex_count(c, verts, corners);
        c.ints(nverts, std::size_t(npolys), "nverts").ints(verts, corners, "verts");
        c.params(n, tokens, values, counts(std::size_t(npolys), v, v, corners));
    });
}
RtVoid RiPointsPolygons(RtInt npolys, RtInt nverts[], RtInt verts[], ...) {
    SSS_RI_VARARGS(pv, verts);
    RiPointsPolygonsV(npolys, nverts, verts, pv.count(), pv.tokens.data(),
                      pv.values.data());
}

RtVoid RiPointsGeneralPolygonsV(RtInt npolys, RtInt nloops[], RtInt nverts[],
                                RtInt verts[], RtInt n, RtToken tokens[],
                                RtPointer values[]) {
    ri_guarded("PointsGeneralPolygons", [&](RiCall& c) {
        const std::size_t loops = sum_of(c, nloops, npolys, "nloops", 1);
        if (loops > std::size_t(1) << 30) c.fail("too many loops");
        const std::size_t corners = sum_of(c, nverts, RtInt(loops), "nverts", 3);
        const std::size_t v = vertex_count(c, verts, corners);
        c.ints(nloops, std::size_t(npolys), "nloops").ints(nverts, loops, "nverts");
        c.ints(verts, corners, "verts");
        c.params(n, tokens, values, counts(std::size_t(npolys), v, v, corners));
    });
}
RtVoid RiPointsGeneralPolygons(RtInt npolys, RtInt nloops[], RtInt nverts[],
                               RtInt verts[], ...) {
    SSS_RI_VARARGS(pv, verts);
    RiPointsGeneralPolygonsV(npolys, nloops, nverts, verts, pv.count(), pv.tokens.data(),
                             pv.values.data());
}

RtVoid RiSubdivisionMeshV(RtToken scheme, RtInt nfaces, RtInt nvertices[],
                          RtInt vertices[], RtInt ntags, RtToken tags[], RtInt nargs[],
                          RtInt intargs[], RtFloat floatargs[], RtInt n, RtToken tokens[],
                          RtPointer values[]) {
    ri_guarded("SubdivisionMesh", [&](RiCall& c) {
        const std::size_t corners = sum_of(c, nvertices, nfaces, "nvertices", 3);
        const std::size_t v = vertex_count(c, vertices, corners);
        if (ntags < 0 || ntags > (1 << 28)) c.fail("a bad number of tags");
        std::size_t ni = 0, nf = 0;
        if (ntags > 0) {
            sum_of(c, nargs, 2 * ntags, "nargs", 0);
            for (RtInt t = 0; t < ntags; ++t) {
                ni += std::size_t(nargs[2 * t]);
                nf += std::size_t(nargs[2 * t + 1]);
            }
        }
        c.string(scheme, "scheme").ints(nvertices, std::size_t(nfaces), "nvertices");
        c.ints(vertices, corners, "vertices").strings(tags, std::size_t(ntags), "tags");
        c.ints(nargs, 2 * std::size_t(ntags), "nargs").ints(intargs, ni, "intargs");
        c.floats(floatargs, nf, "floatargs");
        c.params(n, tokens, values, counts(std::size_t(nfaces), v, v, corners));
    });
}
RtVoid RiSubdivisionMesh(RtToken scheme, RtInt nfaces, RtInt nvertices[],
                         RtInt vertices[], RtInt ntags, RtToken tags[], RtInt nargs[],
                         RtInt intargs[], RtFloat floatargs[], ...) {
    SSS_RI_VARARGS(pv, floatargs);
    RiSubdivisionMeshV(scheme, nfaces, nvertices, vertices, ntags, tags, nargs, intargs,
                       floatargs, pv.count(), pv.tokens.data(), pv.values.data());
}

// --- patches --------------------------------------------------------------------------

RtVoid RiPatchV(RtToken type, RtInt n, RtToken tokens[], RtPointer values[]) {
    ri_guarded("Patch", [&](RiCall& c) {
        if (!is(type, "bilinear") && !is(type, "bicubic"))
            c.fail("the type must be \"bilinear\" or \"bicubic\"");
        const std::size_t vertex = is(type, "bicubic") ? 16 : 4;
        c.string(type, "type").params(n, tokens, values, counts(1, 4, vertex, 4));
    });
}
RtVoid RiPatch(RtToken type, ...) {
    SSS_RI_VARARGS(pv, type);
    RiPatchV(type, pv.count(), pv.tokens.data(), pv.values.data());
}

RtVoid RiPatchMeshV(RtToken type, RtInt nu, RtToken uwrap, RtInt nv, RtToken vwrap,
                    RtInt n, RtToken tokens[], RtPointer values[]) {
    ri_guarded("PatchMesh", [&](RiCall& c) {
        if (!is(type, "bilinear") && !is(type, "bicubic"))
            c.fail("the type must be \"bilinear\" or \"bicubic\"");
        const bool cubic = is(type, "bicubic");
        const bool up = is(uwrap, "periodic"), vp = is(vwrap, "periodic");
        const sss::rib::Reader& r = *c.context().reader;
        const std::size_t su = segments(c, cubic, up, nu, r.basis_step(false));
        const std::size_t sv = segments(c, cubic, vp, nv, r.basis_step(true));
        const std::size_t varying = (up ? su : su + 1) * (vp ? sv : sv + 1);
        c.string(type, "type").number(nu).string(uwrap, "uwrap").number(nv);
        c.string(vwrap, "vwrap");
        c.params(n, tokens, values,
                 counts(su * sv, varying, std::size_t(nu) * std::size_t(nv), varying));
    });
}
RtVoid RiPatchMesh(RtToken type, RtInt nu, RtToken uwrap, RtInt nv, RtToken vwrap, ...) {
    SSS_RI_VARARGS(pv, vwrap);
    RiPatchMeshV(type, nu, uwrap, nv, vwrap, pv.count(), pv.tokens.data(),
                 pv.values.data());
}

RtVoid RiNuPatchV(RtInt nu, RtInt uorder, RtFloat uknot[], RtFloat umin, RtFloat umax,
                  RtInt nv, RtInt vorder, RtFloat vknot[], RtFloat vmin, RtFloat vmax,
                  RtInt n, RtToken tokens[], RtPointer values[]) {
    ri_guarded("NuPatch", [&](RiCall& c) {
        if (uorder < 1 || vorder < 1 || nu < uorder || nv < vorder || nu > (1 << 24) ||
            nv > (1 << 24))
            c.fail(
                "orders must be >= 1 and no more than the vertices along each direction");
        c.number(nu).number(uorder).floats(uknot, std::size_t(nu + uorder), "uknot");
        c.number(umin).number(umax);
        c.number(nv).number(vorder).floats(vknot, std::size_t(nv + vorder), "vknot");
        c.number(vmin).number(vmax);
        const std::size_t varying =
            std::size_t(nu - uorder + 2) * std::size_t(nv - vorder + 2);
        c.params(n, tokens, values,
                 counts(std::size_t(nu - uorder + 1) * std::size_t(nv - vorder + 1),
                        varying, std::size_t(nu) * std::size_t(nv), varying));
    });
}
RtVoid RiNuPatch(RtInt nu, RtInt uorder, RtFloat uknot[], RtFloat umin, RtFloat umax,
                 RtInt nv, RtInt vorder, RtFloat vknot[], RtFloat vmin, RtFloat vmax,
                 ...) {
    SSS_RI_VARARGS(pv, vmax);
    RiNuPatchV(nu, uorder, uknot, umin, umax, nv, vorder, vknot, vmin, vmax, pv.count(),
               pv.tokens.data(), pv.values.data());
}

RtVoid RiTrimCurve(RtInt nloops, RtInt ncurves[], RtInt order[], RtFloat knot[],
                   RtFloat min[], RtFloat max[], RtInt n[], RtFloat u[], RtFloat v[],
                   RtFloat w[]) {
    ri_guarded("TrimCurve", [&](RiCall& c) {
        const std::size_t curves = sum_of(c, ncurves, nloops, "ncurves", 1);
        if (curves > std::size_t(1) << 28) c.fail("too many curves");
        const std::size_t orders = sum_of(c, order, RtInt(curves), "order", 1);
        const std::size_t points = sum_of(c, n, RtInt(curves), "n", 1);
        c.ints(ncurves, std::size_t(nloops), "ncurves").ints(order, curves, "order");
        c.floats(knot, orders + points, "knot").floats(min, curves, "min");
        c.floats(max, curves, "max").ints(n, curves, "n").floats(u, points, "u");
        c.floats(v, points, "v").floats(w, points, "w");
    });
}

// --- quadrics -----------------------------------------------------------------------

RtVoid RiSphereV(RtFloat radius, RtFloat zmin, RtFloat zmax, RtFloat tmax, RtInt n,
                 RtToken tokens[], RtPointer values[]) {
    quadric("Sphere", {radius, zmin, zmax, tmax}, n, tokens, values);
}
RtVoid RiSphere(RtFloat radius, RtFloat zmin, RtFloat zmax, RtFloat tmax, ...) {
    SSS_RI_VARARGS(pv, tmax);
    RiSphereV(radius, zmin, zmax, tmax, pv.count(), pv.tokens.data(), pv.values.data());
}
RtVoid RiConeV(RtFloat height, RtFloat radius, RtFloat tmax, RtInt n, RtToken tokens[],
               RtPointer values[]) {
    quadric("Cone", {height, radius, tmax}, n, tokens, values);
}
RtVoid RiCone(RtFloat height, RtFloat radius, RtFloat tmax, ...) {
    SSS_RI_VARARGS(pv, tmax);
    RiConeV(height, radius, tmax, pv.count(), pv.tokens.data(), pv.values.data());
}
RtVoid RiCylinderV(RtFloat radius, RtFloat zmin, RtFloat zmax, RtFloat tmax, RtInt n,
                   RtToken tokens[], RtPointer values[]) {
    quadric("Cylinder", {radius, zmin, zmax, tmax}, n, tokens, values);
}
RtVoid RiCylinder(RtFloat radius, RtFloat zmin, RtFloat zmax, RtFloat tmax, ...) {
    SSS_RI_VARARGS(pv, tmax);
    RiCylinderV(radius, zmin, zmax, tmax, pv.count(), pv.tokens.data(), pv.values.data());
}
RtVoid RiHyperboloidV(RtPoint p1, RtPoint p2, RtFloat tmax, RtInt n, RtToken tokens[],
                      RtPointer values[]) {
    ri_guarded("Hyperboloid", [&](RiCall& c) {
        if (!p1 || !p2) c.fail("no points (a null pointer)");
        for (const RtFloat* p : {p1, p2}) c.number(p[0]).number(p[1]).number(p[2]);
        c.number(tmax).params(n, tokens, values, kQuadric);
    });
}
RtVoid RiHyperboloid(RtPoint p1, RtPoint p2, RtFloat tmax, ...) {
    SSS_RI_VARARGS(pv, tmax);
    RiHyperboloidV(p1, p2, tmax, pv.count(), pv.tokens.data(), pv.values.data());
}
RtVoid RiParaboloidV(RtFloat rmax, RtFloat zmin, RtFloat zmax, RtFloat tmax, RtInt n,
                     RtToken tokens[], RtPointer values[]) {
    quadric("Paraboloid", {rmax, zmin, zmax, tmax}, n, tokens, values);
}
RtVoid RiParaboloid(RtFloat rmax, RtFloat zmin, RtFloat zmax, RtFloat tmax, ...) {
    SSS_RI_VARARGS(pv, tmax);
    RiParaboloidV(rmax, zmin, zmax, tmax, pv.count(), pv.tokens.data(), pv.values.data());
}
RtVoid RiDiskV(RtFloat height, RtFloat radius, RtFloat tmax, RtInt n, RtToken tokens[],
               RtPointer values[]) {
    quadric("Disk", {height, radius, tmax}, n, tokens, values);
}
RtVoid RiDisk(RtFloat height, RtFloat radius, RtFloat tmax, ...) {
    SSS_RI_VARARGS(pv, tmax);
    RiDiskV(height, radius, tmax, pv.count(), pv.tokens.data(), pv.values.data());
}
RtVoid RiTorusV(RtFloat major, RtFloat minor, RtFloat phimin, RtFloat phimax,
                RtFloat tmax, RtInt n, RtToken tokens[], RtPointer values[]) {
    quadric("Torus", {major, minor, phimin, phimax, tmax}, n, tokens, values);
}
RtVoid RiTorus(RtFloat major, RtFloat minor, RtFloat phimin, RtFloat phimax, RtFloat tmax,
               ...) {
    SSS_RI_VARARGS(pv, tmax);
    RiTorusV(major, minor, phimin, phimax, tmax, pv.count(), pv.tokens.data(),
             pv.values.data());
}

// --- points, curves, blobs ------------------------------------------------------------

RtVoid RiPointsV(RtInt npoints, RtInt n, RtToken tokens[], RtPointer values[]) {
    ri_guarded("Points", [&](RiCall& c) {
        if (npoints < 1) c.fail("no points");
        const std::size_t v = std::size_t(npoints);
        ClassCounts cc = counts(1, v, v, v);
        cc.varying_width = true;
        c.params(n, tokens, values, cc);
    });
}
RtVoid RiPoints(RtInt npoints, ...) {
    SSS_RI_VARARGS(pv, npoints);
    RiPointsV(npoints, pv.count(), pv.tokens.data(), pv.values.data());
}

RtVoid RiCurvesV(RtToken type, RtInt ncurves, RtInt nvertices[], RtToken wrap, RtInt n,
                 RtToken tokens[], RtPointer values[]) {
    ri_guarded("Curves", [&](RiCall& c) {
        if (!is(type, "linear") && !is(type, "cubic"))
            c.fail("the type must be \"linear\" or \"cubic\"");
        const bool cubic = is(type, "cubic"), periodic = is(wrap, "periodic");
        const std::size_t vertex = sum_of(c, nvertices, ncurves, "nvertices", 1);
        const int step = c.context().reader->basis_step(true);
        std::size_t varying = 0;
        for (RtInt i = 0; i < ncurves; ++i) {
            const std::size_t segs = segments(c, cubic, periodic, nvertices[i], step);
            varying += periodic ? segs : segs + 1;
        }
        c.string(type, "type").ints(nvertices, std::size_t(ncurves), "nvertices");
        c.string(wrap, "wrap");
        ClassCounts cc = counts(std::size_t(ncurves), varying, vertex, varying);
        cc.varying_width = true;
        c.params(n, tokens, values, cc);
    });
}
RtVoid RiCurves(RtToken type, RtInt ncurves, RtInt nvertices[], RtToken wrap, ...) {
    SSS_RI_VARARGS(pv, wrap);
    RiCurvesV(type, ncurves, nvertices, wrap, pv.count(), pv.tokens.data(),
              pv.values.data());
}

RtVoid RiBlobbyV(RtInt nleaf, RtInt ncode, RtInt code[], RtInt nflt, RtFloat flt[],
                 RtInt nstr, RtToken str[], RtInt n, RtToken tokens[],
                 RtPointer values[]) {
    ri_guarded("Blobby", [&](RiCall& c) {
        if (nleaf < 1 || ncode < 0 || nflt < 0 || nstr < 0)
            c.fail("negative counts, or no leaves");
        c.number(nleaf).ints(code, std::size_t(ncode), "code");
        c.floats(flt, std::size_t(nflt), "floats")
            .strings(str, std::size_t(nstr), "strings");
        const std::size_t v = std::size_t(nleaf);
        c.params(n, tokens, values, counts(1, v, v, v));
    });
}
RtVoid RiBlobby(RtInt nleaf, RtInt ncode, RtInt code[], RtInt nflt, RtFloat flt[],
                RtInt nstr, RtToken str[], ...) {
    SSS_RI_VARARGS(pv, str);
    RiBlobbyV(nleaf, ncode, code, nflt, flt, nstr, str, pv.count(), pv.tokens.data(),
              pv.values.data());
}

// --- procedurals ----------------------------------------------------------------------

namespace {

// RiProcedural's standard subdivide functions are their RIB forms; the
// strings each one's data holds.
const char* standard_procedural(RtProcSubdivFunc f, std::size_t& strings) {
    strings = 2;
    if (f == RiProcDelayedReadArchive) {
        strings = 1;
        return "DelayedReadArchive";
    }
    if (f == RiProcRunProgram) return "RunProgram";
    if (f == RiProcDynamicLoad) return "DynamicLoad";
    return nullptr;
}

// Calls the DSO's free function once, however the request ended.
struct FreeAfter {
    RtProcFreeFunc free_data;
    RtPointer data;
    ~FreeAfter() {
        if (free_data) free_data(data);
    }
};

void standard_request(const char* kind, std::size_t strings, RtPointer data,
                      RtBound bound) {
    ri_guarded("Procedural", [&](RiCall& c) {
        c.string(kind, "procedural")
            .strings(static_cast<RtToken const*>(data), strings, "procedural arguments");
        if (bound) {
            c.floats(bound, 6, "bound");
        } else {
            const RtFloat everything[6] = {-1e30f, 1e30f, -1e30f, 1e30f, -1e30f, 1e30f};
            c.floats(everything, 6, "bound");
        }
    });
}

} // namespace

RtVoid RiProcedural(RtPointer data, RtBound bound, RtProcSubdivFunc subdivfunc,
                    RtProcFreeFunc freefunc) {
    FreeAfter release{freefunc, data};
    std::size_t strings = 0;
    if (const char* kind = standard_procedural(subdivfunc, strings)) {
        if (!bound) {
            ri_guarded_raw("Procedural",
                           [](RiCall& c) { c.fail("no bound (a null pointer)"); });
            return;
        }
        standard_request(kind, strings, data, bound);
        return;
    }
    sss::rib::ri_guarded_raw("Procedural", [&](RiCall& c) {
        if (!bound) c.fail("no bound (a null pointer)");
        if (!subdivfunc) c.fail("no subdivide function (a null pointer)");
        const double b[6] = {bound[0], bound[1], bound[2], bound[3], bound[4], bound[5]};
        // The DSO frees its data itself once its subdivision has run.
        release.free_data = nullptr;
        c.context().reader->ri_procedural(c.statement(), data, b, subdivfunc, freefunc);
    });
}

// Called directly, the standard procedurals do their work at once.
RtVoid RiProcDelayedReadArchive(RtPointer data, RtFloat) {
    ri_guarded("ReadArchive", [&](RiCall& c) {
        if (!data) c.fail("no archive name (a null pointer)");
        c.string(static_cast<RtToken const*>(data)[0], "archive name");
    });
}
RtVoid RiProcRunProgram(RtPointer data, RtFloat) {
    standard_request("RunProgram", 2, data, nullptr);
}
RtVoid RiProcDynamicLoad(RtPointer data, RtFloat) {
    standard_request("DynamicLoad", 2, data, nullptr);
}
RtVoid RiProcFree(RtPointer data) {
    std::free(data);
}

} // extern "C"
