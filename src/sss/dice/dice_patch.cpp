// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_patch.cpp
/// Patch ("bilinear" and "bicubic" in any basis), PatchMesh (periodic or
/// not) and Geometry "teapot" (32 bicubic Bezier patches, teapot.cpp) as
/// faces for the REYES dicer, with their primitive variables per patch.

#include <algorithm>
#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "dice_parametric.h"
#include "sss/dice/dice.h"
#include "teapot_data.h"

namespace sss::detail {

namespace {

/// Spline weights of one parameter value: B * (t^3, t^2, t, 1) with the
/// basis matrix in our (column-vector) layout, and their derivatives.
inline void spline_weights(const glm::dmat4& basis, double t, dvec4& w, dvec4& dw) {
    w = basis * dvec4(t * t * t, t * t, t, 1.0);
    dw = basis * dvec4(3.0 * t * t, 2.0 * t, 1.0, 0.0);
}

/// A bilinear patch through four corners in RI order: (0,0) (1,0) (0,1) (1,1).
class BilinearSurface final : public Surface {
public:
    explicit BilinearSurface(const std::array<dvec3, 4>& corners) : m_c(corners) {}

    void evaluate(std::span<const double> us, std::span<const double> vs,
                  SurfacePoint* out) const override {
        for (std::size_t j = 0; j < vs.size(); ++j) {
            const double v = vs[j];
            const dvec3 bottom_du = m_c[1] - m_c[0];
            const dvec3 top_du = m_c[3] - m_c[2];
            SurfacePoint* row = out + j * us.size();
            for (std::size_t i = 0; i < us.size(); ++i) {
                const double u = us[i];
                const dvec3 bottom = m_c[0] + u * bottom_du;
                const dvec3 top = m_c[2] + u * top_du;
                row[i].p = bottom + v * (top - bottom);
                row[i].dpdu = bottom_du + v * (top_du - bottom_du);
                row[i].dpdv = top - bottom;
            }
        }
    }

private:
    std::array<dvec3, 4> m_c;
};

const glm::dmat4& bezier_matrix() {
    // RI Bezier basis; rows of the RIB matrix are the columns here.
    static const glm::dmat4 m(-1, 3, -3, 1, 3, -6, 3, 0, -3, 3, 0, 0, 1, 0, 0, 0);
    return m;
}

/// "P" (or "Pw" divided by w) with exactly `count` points.
std::vector<dvec3> read_points(const Primitive& prim, std::size_t count) {
    const Param* p = prim.params.find("P");
    const bool homogeneous = !p;
    if (homogeneous) p = prim.params.find("Pw");
    if (!p) fail(prim, "missing \"P\"");
    const std::string name = homogeneous ? "\"Pw\"" : "\"P\"";
    const int comps = homogeneous ? 4 : 3;
    if (p->element_size() != comps)
        fail(prim, name + " must have " + std::to_string(comps) +
                       " numbers per point, not " + std::to_string(p->element_size()));
    if (p->numbers.size() != static_cast<std::size_t>(comps) * count)
        fail(prim, name + " has " + std::to_string(p->numbers.size() / comps) +
                       " points, expected " + std::to_string(count));
    std::vector<dvec3> pts(count);
    for (std::size_t k = 0; k < count; ++k) {
        const double* v = &p->numbers[comps * k];
        pts[k] = dvec3(v[0], v[1], v[2]);
        if (homogeneous) {
            if (v[3] == 0.0) fail(prim, "\"Pw\" has a point with w = 0");
            pts[k] /= v[3];
        }
    }
    for (const dvec3& q : pts)
        if (!finite(q)) fail(prim, "\"P\" has a NaN or infinite coordinate");
    return pts;
}

bool is_bicubic(const Primitive& prim) {
    if (prim.type == "bicubic") return true;
    if (prim.type == "bilinear") return false;
    fail(prim, "type must be \"bilinear\" or \"bicubic\", not \"" + prim.type + "\"");
}

/// Patches along one direction of a patch mesh (RI rules), validating the count.
int patch_count(const Primitive& prim, int n, bool wrap, bool bicubic, int step,
                const char* dir) {
    const std::string d = dir;
    if (!bicubic) {
        if (n < 2) fail(prim, "n" + d + " must be at least 2");
        return wrap ? n : n - 1;
    }
    if (step < 1 || step > 4) fail(prim, d + " basis step must be in 1..4");
    if (wrap) {
        if (n < 1 || n % step != 0)
            fail(prim, "periodic n" + d + " (" + std::to_string(n) +
                           ") must be a positive multiple of the " + d + " step");
        return n / step;
    }
    if (n < 4 || (n - 4) % step != 0)
        fail(prim, "nonperiodic n" + d + " (" + std::to_string(n) +
                       ") must be 4 + a multiple of the " + d + " step");
    return (n - 4) / step + 1;
}

} // namespace

glm::dmat4 resolve_basis(const Basis& b) {
    // A default-constructed Basis has the identity matrix but the name "bezier".
    if (b.name == "bezier" && b.matrix == Matrix4(1.0)) return bezier_matrix();
    return b.matrix;
}

void BicubicSurface::evaluate(std::span<const double> us, std::span<const double> vs,
                              SurfacePoint* out) const {
    thread_local std::vector<dvec4> uw;
    ensure_size(uw, 2 * us.size());
    for (std::size_t i = 0; i < us.size(); ++i)
        spline_weights(m_u_basis, us[i], uw[2 * i], uw[2 * i + 1]);
    for (std::size_t j = 0; j < vs.size(); ++j) {
        dvec4 wv;
        dvec4 dwv;
        spline_weights(m_v_basis, vs[j], wv, dwv);
        // The four u-direction curves at this v, and their v derivatives.
        dvec3 q[4];
        dvec3 dq[4];
        for (int k = 0; k < 4; ++k) {
            q[k] = wv[0] * m_points[k] + wv[1] * m_points[4 + k] +
                   wv[2] * m_points[8 + k] + wv[3] * m_points[12 + k];
            dq[k] = dwv[0] * m_points[k] + dwv[1] * m_points[4 + k] +
                    dwv[2] * m_points[8 + k] + dwv[3] * m_points[12 + k];
        }
        SurfacePoint* row = out + j * us.size();
        for (std::size_t i = 0; i < us.size(); ++i) {
            const dvec4& w = uw[2 * i];
            const dvec4& dw = uw[2 * i + 1];
            row[i].p = w[0] * q[0] + w[1] * q[1] + w[2] * q[2] + w[3] * q[3];
            row[i].dpdu = dw[0] * q[0] + dw[1] * q[1] + dw[2] * q[2] + dw[3] * q[3];
            row[i].dpdv = w[0] * dq[0] + w[1] * dq[1] + w[2] * dq[2] + w[3] * dq[3];
        }
    }
}

DicedSurface dice_patch(const Primitive& prim, const DiceControl& control,
                        DiceEstimate* estimate) {
    const bool bicubic = is_bicubic(prim);
    const std::size_t count = bicubic ? 16 : 4;
    const std::vector<dvec3> pts = read_points(prim, count);
    const ClassCounts counts{1, 4, count, 4, count};
    const PrimVar cs(prim, "Cs", counts);
    const PrimVar n(prim, "N", counts);
    FaceIndex at;
    at.bicubic = bicubic;
    for (std::size_t k = 0; k < count; ++k) at.vertex[k] = k;
    const Attributes& attr = attributes_of(prim);
    const glm::dmat4 ub = resolve_basis(attr.u_basis);
    const glm::dmat4 vb = resolve_basis(attr.v_basis);
    std::optional<BicubicSurface> cubic;
    std::optional<BilinearSurface> linear;
    Face face;
    if (bicubic) {
        std::array<dvec3, 16> cp;
        std::copy(pts.begin(), pts.end(), cp.begin());
        face.geometry = &cubic.emplace(cp, ub, vb);
    } else {
        face.geometry =
            &linear.emplace(std::array<dvec3, 4>{pts[0], pts[1], pts[2], pts[3]});
    }
    face.color = cs.face(at, ub, vb);
    face.normal = n.face(at, ub, vb);
    const TexCoordVars st(prim, counts);
    face.s = st.s.face(at, ub, vb);
    face.t = st.t.face(at, ub, vb);
    DicedSurface out;
    ParametricDicer(prim, control, out, estimate).dice(face);
    return out;
}

DicedSurface dice_patch_mesh(const Primitive& prim, const DiceControl& control,
                             DiceEstimate* estimate) {
    const bool bicubic = is_bicubic(prim);
    const Attributes& attr = attributes_of(prim);
    const int nu = prim.nu;
    const int nv = prim.nv;
    const int ustep = bicubic ? attr.u_basis.step : 1;
    const int vstep = bicubic ? attr.v_basis.step : 1;
    const int pu = patch_count(prim, nu, prim.uwrap, bicubic, ustep, "u");
    const int pv = patch_count(prim, nv, prim.vwrap, bicubic, vstep, "v");
    const std::vector<dvec3> pts =
        read_points(prim, static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv));
    // Varying values sit at patch corners: one more than patches unless periodic.
    const int vary_u = prim.uwrap ? pu : pu + 1;
    const int vary_v = prim.vwrap ? pv : pv + 1;
    const std::size_t patches =
        static_cast<std::size_t>(pu) * static_cast<std::size_t>(pv);
    const ClassCounts counts{patches, static_cast<std::size_t>(vary_u) * vary_v,
                             static_cast<std::size_t>(nu) * nv, 4 * patches,
                             (bicubic ? 16 : 4) * patches};
    const PrimVar cs(prim, "Cs", counts);
    const PrimVar n(prim, "N", counts);
    const glm::dmat4 ub = resolve_basis(attr.u_basis);
    const glm::dmat4 vb = resolve_basis(attr.v_basis);
    const int order = bicubic ? 4 : 2;
    const TexCoordVars st(prim, counts);

    DicedSurface out;
    ParametricDicer dicer(prim, control, out, estimate);
    for (int j = 0; j < pv; ++j)
        for (int i = 0; i < pu; ++i) {
            FaceIndex at;
            at.bicubic = bicubic;
            at.uniform = static_cast<std::size_t>(j) * pu + i;
            for (int b = 0; b < 2; ++b)
                for (int a = 0; a < 2; ++a)
                    at.varying[2 * b + a] =
                        static_cast<std::size_t>((j + b) % vary_v) * vary_u +
                        (i + a) % vary_u;
            const int first_u = bicubic ? i * ustep : i;
            const int first_v = bicubic ? j * vstep : j;
            for (int r = 0; r < order; ++r)
                for (int c = 0; c < order; ++c)
                    at.vertex[r * order + c] =
                        static_cast<std::size_t>((first_v + r) % nv) * nu +
                        (first_u + c) % nu;
            std::optional<BicubicSurface> cubic;
            std::optional<BilinearSurface> linear;
            Face face;
            if (bicubic) {
                std::array<dvec3, 16> cp;
                for (int k = 0; k < 16; ++k) cp[k] = pts[at.vertex[k]];
                face.geometry = &cubic.emplace(cp, ub, vb);
            } else {
                face.geometry = &linear.emplace(
                    std::array<dvec3, 4>{pts[at.vertex[0]], pts[at.vertex[1]],
                                         pts[at.vertex[2]], pts[at.vertex[3]]});
            }
            face.color = cs.face(at, ub, vb);
            face.normal = n.face(at, ub, vb);
            face.s = st.s.face(at, ub, vb);
            face.t = st.t.face(at, ub, vb);
            // u and v span the whole mesh.
            face.u_offset = static_cast<double>(i) / pu;
            face.u_scale = 1.0 / pu;
            face.v_offset = static_cast<double>(j) / pv;
            face.v_scale = 1.0 / pv;
            dicer.dice(face);
        }
    return out;
}

DicedSurface dice_teapot(const Primitive& prim, const DiceControl& control,
                         DiceEstimate* estimate) {
    // Geometry "teapot" takes no per-patch data: only one Cs for all of it.
    const PrimVar cs(prim, "Cs", ClassCounts{1, 1, 1, 1, 1});
    DicedSurface out;
    ParametricDicer dicer(prim, control, out, estimate);
    for (const auto& cp : detail::teapot_patches()) {
        const BicubicSurface surface(cp, bezier_matrix(), bezier_matrix());
        Face face;
        face.geometry = &surface;
        if (cs.param) {
            face.color.mode = FaceValues::Mode::Constant;
            face.color.corners[0] = cs.values[0];
        }
        dicer.dice(face);
    }
    return out;
}

} // namespace sss::detail
