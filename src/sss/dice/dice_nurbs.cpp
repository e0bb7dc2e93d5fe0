// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_nurbs.cpp
/// NuPatch: non-uniform rational B-spline patches of any order, one face of
/// the REYES dicer per non-empty knot span within the patch's parameter
/// range, with their primitive variables by storage class, and the current
/// TrimCurve: micropolygons and triangles whose parameters fall in the
/// trimmed-away region are dropped.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec2.hpp>

#include "dice_parametric.h"

namespace sss::detail {

namespace {

constexpr int kMaxOrder = 16;

/// The B-spline basis of one direction (or of a trim curve).
struct KnotVector {
    const double* knot = nullptr;
    int n = 0;
    int order = 0;

    /// Values and derivatives of the `order` basis functions nonzero on the
    /// span knot[span] <= x <= knot[span + 1] (functions span - order + 1 ..
    /// span), by the triangular recurrence; the derivatives from the
    /// functions of one order less.
    void basis(int span, double x, double* value, double* derivative) const {
        const double* t = knot;
        const int k = order;
        double left[kMaxOrder];
        double right[kMaxOrder];
        double lower[kMaxOrder] = {1.0};
        value[0] = 1.0;
        for (int j = 1; j < k; ++j) {
            left[j] = x - t[span + 1 - j];
            right[j] = t[span + j] - x;
            if (j == k - 1) std::copy(value, value + j, lower);
            double saved = 0.0;
            for (int r = 0; r < j; ++r) {
                const double den = right[r + 1] + left[j - r];
                const double tmp = den != 0.0 ? value[r] / den : 0.0;
                value[r] = saved + right[r + 1] * tmp;
                saved = left[j - r] * tmp;
            }
            value[j] = saved;
        }
        for (int r = 0; r < k; ++r) {
            const int f = span - k + 1 + r;
            double d = 0.0;
            if (r >= 1 && t[f + k - 1] > t[f]) d += lower[r - 1] / (t[f + k - 1] - t[f]);
            if (r <= k - 2 && t[f + k] > t[f + 1]) d -= lower[r] / (t[f + k] - t[f + 1]);
            derivative[r] = (k - 1) * d;
        }
    }
};

/// One knot span of a NuPatch as a surface over the unit square: face
/// (s, t) is the patch's (u0 + s (u1 - u0), v0 + t (v1 - v0)). The control
/// points are homogeneous (x w, y w, z w, w), u fastest; over values
/// instead of positions it interpolates vertex-class variables the same way.
class NurbsSpan final : public Surface {
public:
    NurbsSpan(const KnotVector& u, const KnotVector& v, int su, int sv,
              std::array<double, 4> range, const std::vector<dvec4>& control)
        : m_u(u), m_v(v), m_su(su), m_sv(sv), m_range(range), m_cp(control) {}

    void evaluate(std::span<const double> us, std::span<const double> vs,
                  SurfacePoint* out) const override {
        const int ku = m_u.order;
        const int kv = m_v.order;
        thread_local std::vector<double> ub;
        ensure_size(ub, 2 * kMaxOrder * us.size());
        const double du = m_range[1] - m_range[0];
        const double dv = m_range[3] - m_range[2];
        for (std::size_t i = 0; i < us.size(); ++i)
            m_u.basis(m_su, m_range[0] + us[i] * du, &ub[2 * kMaxOrder * i],
                      &ub[2 * kMaxOrder * i + kMaxOrder]);
        const int first_u = m_su - ku + 1;
        const int first_v = m_sv - kv + 1;
        for (std::size_t j = 0; j < vs.size(); ++j) {
            double bv[kMaxOrder];
            double dbv[kMaxOrder];
            m_v.basis(m_sv, m_range[2] + vs[j] * dv, bv, dbv);
            // The u-direction control curve at this v, and its v derivative.
            std::array<dvec4, kMaxOrder> q{};
            std::array<dvec4, kMaxOrder> dq{};
            for (int a = 0; a < ku; ++a)
                for (int b = 0; b < kv; ++b) {
                    const dvec4& c = m_cp[static_cast<std::size_t>(first_v + b) * m_u.n +
                                          static_cast<std::size_t>(first_u + a)];
                    q[a] += bv[b] * c;
                    dq[a] += dbv[b] * c;
                }
            for (std::size_t i = 0; i < us.size(); ++i) {
                const double* bu = &ub[2 * kMaxOrder * i];
                const double* dbu = bu + kMaxOrder;
                dvec4 h(0.0);
                dvec4 hu(0.0);
                dvec4 hv(0.0);
                for (int a = 0; a < ku; ++a) {
                    h += bu[a] * q[a];
                    hu += dbu[a] * q[a];
                    hv += bu[a] * dq[a];
                }
                SurfacePoint& sp = out[j * us.size() + i];
                const double w = h.w != 0.0 ? h.w : 1.0;
                sp.p = dvec3(h) / w;
                sp.dpdu = (dvec3(hu) - sp.p * hu.w) / w * du;
                sp.dpdv = (dvec3(hv) - sp.p * hv.w) / w * dv;
            }
        }
    }

private:
    KnotVector m_u, m_v;
    int m_su, m_sv;
    std::array<double, 4> m_range; ///< u0 u1 v0 v1
    const std::vector<dvec4>& m_cp;
};

/// The homogeneous control points of "Pw", or of "P" with weight 1.
std::vector<dvec4> control_points(const Primitive& prim) {
    const std::size_t count = static_cast<std::size_t>(prim.nu) * prim.nv;
    const Param* pw = prim.params.find("Pw");
    const Param* p = prim.params.find("P");
    const Param* q = p ? p : pw;
    if (!q) fail(prim, "missing \"P\"");
    const std::size_t comps = p ? 3 : 4;
    if (q->numbers.size() != comps * count)
        fail(prim, "\"" + q->name + "\" has " +
                       std::to_string(q->numbers.size() / comps) + " points, expected " +
                       std::to_string(count));
    std::vector<dvec4> cp(count);
    for (std::size_t k = 0; k < count; ++k) {
        const double* v = &q->numbers[comps * k];
        cp[k] = p ? dvec4(v[0], v[1], v[2], 1.0) : dvec4(v[0], v[1], v[2], v[3]);
        if (!finite(dvec3(cp[k])) || !std::isfinite(cp[k].w) || !(cp[k].w > 0.0))
            fail(prim,
                 "\"" + q->name + "\" has a point that is not finite or has w <= 0");
    }
    return cp;
}

/// A knot span of the patch within its parameter range.
struct Span {
    int su = 0, sv = 0; ///< span (knot index) in u and v
    int iu = 0, iv = 0; ///< its number among the patch's segments
    std::array<double, 4> range{};
};

/// The non-empty knot spans of one direction within [min, max]: knot index
/// and the part of the span inside the range.
std::vector<std::pair<int, std::array<double, 2>>>
spans(const std::vector<double>& knot, int n, int order, double min, double max) {
    std::vector<std::pair<int, std::array<double, 2>>> out;
    for (int s = order - 1; s < n; ++s) {
        const double a = std::max(knot[s], min);
        const double b = std::min(knot[s + 1], max);
        if (a < b) out.push_back({s, {a, b}});
    }
    return out;
}

/// The values of a Cs, N, s or t variable over one span.
class SpanValues {
public:
    SpanValues(const Primitive& prim, const PrimVar& var, const std::vector<dvec4>& cp)
        : m_prim(prim), m_var(var) {
        if (!var.param) return;
        const ParamClass c = var.param->storage;
        if (c == ParamClass::Vertex || c == ParamClass::FaceVertex) {
            // Rational interpolation with the patch's weights.
            m_control.resize(cp.size());
            for (std::size_t k = 0; k < cp.size(); ++k)
                m_control[k] = dvec4(var.values[k] * cp[k].w, cp[k].w);
        }
    }

    FaceValues face(const Span& s, const KnotVector& u, const KnotVector& v) const {
        FaceValues fv;
        if (!m_var.param) return fv;
        const std::size_t segments_u =
            static_cast<std::size_t>(m_prim.nu - m_prim.uorder + 1);
        const std::size_t iu = static_cast<std::size_t>(s.iu);
        const std::size_t iv = static_cast<std::size_t>(s.iv);
        switch (m_var.param->storage) {
        case ParamClass::Constant:
            fv.mode = FaceValues::Mode::Constant;
            fv.corners[0] = m_var.values[0];
            break;
        case ParamClass::Uniform:
            fv.mode = FaceValues::Mode::Constant;
            fv.corners[0] = m_var.values[iv * segments_u + iu];
            break;
        case ParamClass::Varying:
        case ParamClass::FaceVarying:
            // One value per segment corner, (segments + 1) per row.
            fv.mode = FaceValues::Mode::Bilinear;
            for (std::size_t b = 0; b < 2; ++b)
                for (std::size_t a = 0; a < 2; ++a)
                    fv.corners[2 * b + a] =
                        m_var.values[(iv + b) * (segments_u + 1) + iu + a];
            break;
        case ParamClass::Vertex:
        case ParamClass::FaceVertex:
            fv.mode = FaceValues::Mode::Spline;
            fv.spline = std::make_shared<NurbsSpan>(u, v, s.su, s.sv, s.range, m_control);
            break;
        }
        return fv;
    }

private:
    const Primitive& m_prim;
    const PrimVar& m_var;
    std::vector<dvec4> m_control;
};

// --- Trimming ---------------------------------------------------------------

/// The region a TrimCurve keeps: its loops as polylines in (u, v), a point
/// kept or not by the odd winding rule and the "trimcurve" "sense"
/// attribute ("inside", the default, discards what lies inside the loops).
class TrimRegion {
public:
    TrimRegion(const TrimCurves& t, bool keep_inside) : m_keep_inside(keep_inside) {
        std::size_t curve = 0, knot = 0, point = 0;
        for (int loop_curves : t.ncurves) {
            std::vector<glm::dvec2> loop;
            for (int c = 0; c < loop_curves; ++c, ++curve) {
                const KnotVector kv{&t.knot[knot], t.n[curve], t.order[curve]};
                sample(kv, t, point, t.min[curve], t.max[curve], loop);
                knot += static_cast<std::size_t>(t.n[curve] + t.order[curve]);
                point += static_cast<std::size_t>(t.n[curve]);
            }
            for (std::size_t k = 0; k < loop.size(); ++k)
                m_edges.push_back({loop[k], loop[(k + 1) % loop.size()]});
        }
    }

    /// Whether parameter point (u, v) stays.
    bool keeps(double u, double v) const {
        bool inside = false;
        for (const auto& [a, b] : m_edges) {
            if ((a.y > v) == (b.y > v)) continue;
            const double x = a.x + (v - a.y) / (b.y - a.y) * (b.x - a.x);
            if (x > u) inside = !inside;
        }
        return inside == m_keep_inside;
    }

private:
    /// Points along one rational trim curve, 16 per knot span.
    static void sample(const KnotVector& kv, const TrimCurves& t, std::size_t point,
                       double min, double max, std::vector<glm::dvec2>& out) {
        constexpr int kSteps = 16;
        const std::vector<double> knots(kv.knot, kv.knot + kv.n + kv.order);
        for (const auto& [s, r] : spans(knots, kv.n, kv.order, min, max))
            for (int k = 0; k <= kSteps; ++k) {
                double value[kMaxOrder];
                double derivative[kMaxOrder];
                kv.basis(s, r[0] + (r[1] - r[0]) * k / kSteps, value, derivative);
                glm::dvec3 h(0.0);
                for (int a = 0; a < kv.order; ++a) {
                    const std::size_t i =
                        point + static_cast<std::size_t>(s - kv.order + 1 + a);
                    h += value[a] * glm::dvec3(t.u[i], t.v[i], t.w[i]);
                }
                out.emplace_back(h.x / h.z, h.y / h.z);
            }
    }

    bool m_keep_inside;
    std::vector<std::pair<glm::dvec2, glm::dvec2>> m_edges;
};

/// Drops the micropolygons (by their centre's u, v) and triangles (by their
/// vertices' mean u, v) that the region does not keep, and the grids that
/// lost a cell; without `keep_parametric`, then drops the parametric data
/// too (it was made only for this).
void trim(DicedSurface& d, const TrimRegion& region, bool keep_parametric) {
    const std::size_t n = d.size();
    std::vector<std::size_t> index(n, n);
    std::size_t kept = 0;
    for (std::size_t k = 0; k < n; ++k)
        if (region.keeps(d.u[k], d.v[k])) index[k] = kept++;
    const auto compact = [&](auto& a) {
        if (a.size() != n) return;
        for (std::size_t k = 0; k < n; ++k)
            if (index[k] < n) a[index[k]] = a[k];
        a.resize(kept);
    };
    compact(d.centers);
    compact(d.normals);
    compact(d.areas);
    compact(d.radii);
    compact(d.colors);
    for (auto* a : {&d.u, &d.v, &d.du, &d.dv, &d.s, &d.t}) compact(*a);
    compact(d.dPdu);
    compact(d.dPdv);
    std::vector<DicedGrid> grids;
    for (const DicedGrid& g : d.grids) {
        bool whole = true;
        for (std::size_t k = g.first; k < g.first + g.size(); ++k)
            whole = whole && index[k] < n;
        if (whole) grids.push_back(DicedGrid{index[g.first], g.nu, g.nv});
    }
    d.grids = std::move(grids);
    std::size_t t = 0;
    for (std::size_t k = 0; k + 2 < d.triangles.size(); k += 3) {
        glm::dvec2 mean(0.0);
        for (int c = 0; c < 3; ++c)
            mean += glm::dvec2(d.vertex_uvst[d.triangles[k + c]]) / 3.0;
        if (!region.keeps(mean.x, mean.y)) continue;
        for (int c = 0; c < 3; ++c) d.triangles[t++] = d.triangles[k + c];
    }
    d.triangles.resize(t);
    if (keep_parametric) return;
    for (auto* a : {&d.u, &d.v, &d.du, &d.dv, &d.s, &d.t}) a->clear();
    d.dPdu.clear();
    d.dPdv.clear();
    d.vertex_uvst.clear();
    d.grids.clear();
}

/// Whether the "trimcurve" "sense" attribute keeps what is inside the loops.
bool keeps_inside(const Primitive& prim) {
    const auto& groups = attributes_of(prim).groups;
    const auto it = groups.find("trimcurve");
    if (it == groups.end()) return false;
    const std::string sense = it->second.get_string("sense", "inside");
    if (sense == "inside") return false;
    if (sense == "outside") return true;
    fail(prim,
         "Attribute \"trimcurve\" \"sense\" must be \"inside\" or \"outside\", not \"" +
             sense + "\"");
}

} // namespace

DicedSurface dice_nupatch(const Primitive& prim, const DiceControl& control,
                          DiceEstimate* estimate) {
    if (prim.uorder < 1 || prim.vorder < 1 || prim.uorder > kMaxOrder ||
        prim.vorder > kMaxOrder || prim.nu < prim.uorder || prim.nv < prim.vorder ||
        prim.uknot.size() != static_cast<std::size_t>(prim.nu + prim.uorder) ||
        prim.vknot.size() != static_cast<std::size_t>(prim.nv + prim.vorder))
        fail(prim, "inconsistent orders, counts and knots");
    const std::vector<dvec4> cp = control_points(prim);
    const KnotVector u{prim.uknot.data(), prim.nu, prim.uorder};
    const KnotVector v{prim.vknot.data(), prim.nv, prim.vorder};
    const std::size_t seg_u = static_cast<std::size_t>(prim.nu - prim.uorder + 1);
    const std::size_t seg_v = static_cast<std::size_t>(prim.nv - prim.vorder + 1);
    const std::size_t nvert = cp.size();
    const ClassCounts counts{seg_u * seg_v, (seg_u + 1) * (seg_v + 1), nvert,
                             (seg_u + 1) * (seg_v + 1), nvert};
    const PrimVar cs(prim, "Cs", counts);
    const PrimVar n(prim, "N", counts);
    const TexCoordVars st(prim, counts);
    const SpanValues cs_values(prim, cs, cp), n_values(prim, n, cp);
    const SpanValues s_values(prim, st.s, cp), t_values(prim, st.t, cp);

    const std::shared_ptr<const TrimCurves>& trim_curves =
        attributes_of(prim).trim_curves;
    const bool trimmed = trim_curves && !estimate;
    DiceControl with_grids = control;
    with_grids.grids = true; // the trim needs every centre's u and v
    // Trim edges follow the triangles: at full density, not coarsened.
    with_grids.coarsening = 1.0;
    DicedSurface out;
    {
        ParametricDicer dicer(prim, trimmed ? with_grids : control, out, estimate);
        const auto us = spans(prim.uknot, prim.nu, prim.uorder, prim.umin, prim.umax);
        const auto vs = spans(prim.vknot, prim.nv, prim.vorder, prim.vmin, prim.vmax);
        for (const auto& [sv, rv] : vs)
            for (const auto& [su, ru] : us) {
                Span s;
                s.su = su;
                s.sv = sv;
                s.iu = su - (prim.uorder - 1);
                s.iv = sv - (prim.vorder - 1);
                s.range = {ru[0], ru[1], rv[0], rv[1]};
                const NurbsSpan geometry(u, v, su, sv, s.range, cp);
                Face face;
                face.geometry = &geometry;
                face.color = cs_values.face(s, u, v);
                face.normal = n_values.face(s, u, v);
                face.s = s_values.face(s, u, v);
                face.t = t_values.face(s, u, v);
                // The primitive's u and v are the knot parameters.
                face.u_offset = ru[0];
                face.u_scale = ru[1] - ru[0];
                face.v_offset = rv[0];
                face.v_scale = rv[1] - rv[0];
                dicer.dice(face);
            }
    }
    if (trimmed) trim(out, TrimRegion(*trim_curves, keeps_inside(prim)), control.grids);
    return out;
}

} // namespace sss::detail
