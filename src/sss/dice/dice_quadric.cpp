// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_quadric.cpp
/// The RI quadrics (Sphere, Cylinder, Cone, Disk, Torus, Paraboloid,
/// Hyperboloid) as parametric surfaces for the REYES dicer, their argument
/// checks, and their reference areas (quadric_area).

#include <algorithm>
#include <array>
#include <cmath>
#include <span>
#include <string>
#include <vector>

#include "dice_parametric.h"
#include "sss/dice/dice.h"
#include "sss/util/error.h"
#include "sss/util/gauss_legendre.h"
#include "sss/util/math.h"

namespace sss {

namespace {

using detail::describe;
using detail::ensure_size;
using detail::fail;
using detail::Surface;
using detail::SurfacePoint;
using glm::dvec3;

constexpr double kDegToRad = kPi / 180.0;

/// sin and cos of an angle in degrees, exact at multiples of 90 degrees so
/// that poles, apexes and closed seams land exactly where they belong.
void sincos_deg(double deg, double& s, double& c) {
    const double quarter = deg / 90.0;
    if (quarter == std::floor(quarter) && std::abs(quarter) < 1e15) {
        static constexpr double kSin[4] = {0.0, 1.0, 0.0, -1.0};
        static constexpr double kCos[4] = {1.0, 0.0, -1.0, 0.0};
        const auto k = static_cast<int>(((static_cast<long long>(quarter) % 4) + 4) % 4);
        s = kSin[k];
        c = kCos[k];
        return;
    }
    const double r = deg * kDegToRad;
    s = std::sin(r);
    c = std::cos(r);
}

/// The RI quadrics: a profile curve swept about z by theta = u * thetamax.
class QuadricSurface final : public Surface {
public:
    enum class Profile { Sphere, Cylinder, Cone, Disk, Torus, Paraboloid, Hyperboloid };

    /// `args` are the RIB arguments, already validated (sphere z range clamped).
    QuadricSurface(Profile profile, const std::vector<double>& args)
        : m_profile(profile) {
        switch (profile) {
        case Profile::Sphere: {
            const double r = args[0];
            const double zmin = std::clamp(args[1], -r, r);
            const double zmax = std::clamp(args[2], -r, r);
            // Exactly +-90 at the poles so that they are single points.
            const double phimin = zmin <= -r ? -90.0 : std::asin(zmin / r) / kDegToRad;
            const double phimax = zmax >= r ? 90.0 : std::asin(zmax / r) / kDegToRad;
            m_a = {r, phimin, phimax - phimin};
            m_thetamax = args[3];
            break;
        }
        case Profile::Cylinder: // radius zmin zmax
            m_a = {args[0], args[1], args[2] - args[1]};
            m_thetamax = args[3];
            break;
        case Profile::Cone: // height radius
        case Profile::Disk: // height radius
            m_a = {args[0], args[1]};
            m_thetamax = args[2];
            break;
        case Profile::Torus: // major minor phimin phimax
            m_a = {args[0], args[1], args[2], args[3] - args[2]};
            m_thetamax = args[4];
            break;
        case Profile::Paraboloid: // rmax zmin zmax
            m_a = {args[0], args[1], args[2] - args[1], args[2]};
            m_thetamax = args[3];
            break;
        case Profile::Hyperboloid: // point1 point2
            m_a = {args[0],           args[1],           args[2],
                   args[3] - args[0], args[4] - args[1], args[5] - args[2]};
            m_thetamax = args[6];
            break;
        }
    }

    void evaluate(std::span<const double> us, std::span<const double> vs,
                  SurfacePoint* out) const override {
        thread_local std::vector<double> trig;
        ensure_size(trig, 2 * us.size());
        for (std::size_t i = 0; i < us.size(); ++i)
            sincos_deg(us[i] * m_thetamax, trig[2 * i], trig[2 * i + 1]);
        const double dtheta = m_thetamax * kDegToRad;
        for (std::size_t j = 0; j < vs.size(); ++j) {
            dvec3 q(0.0);
            dvec3 dq(0.0);
            profile(vs[j], q, dq);
            SurfacePoint* row = out + j * us.size();
            for (std::size_t i = 0; i < us.size(); ++i) {
                const double s = trig[2 * i];
                const double c = trig[2 * i + 1];
                SurfacePoint& sp = row[i];
                sp.p = dvec3(q.x * c - q.y * s, q.x * s + q.y * c, q.z);
                sp.dpdu = dvec3(-sp.p.y * dtheta, sp.p.x * dtheta, 0.0);
                sp.dpdv = dvec3(dq.x * c - dq.y * s, dq.x * s + dq.y * c, dq.z);
            }
        }
    }

private:
    /// The profile point at theta = 0 and its v derivative.
    void profile(double v, dvec3& q, dvec3& dq) const {
        const auto& a = m_a;
        switch (m_profile) {
        case Profile::Sphere: {
            double s;
            double c;
            sincos_deg(a[1] + v * a[2], s, c);
            const double dphi = a[2] * kDegToRad;
            q = dvec3(a[0] * c, 0.0, a[0] * s);
            dq = dvec3(-a[0] * s * dphi, 0.0, a[0] * c * dphi);
            return;
        }
        case Profile::Cylinder:
            q = dvec3(a[0], 0.0, a[1] + v * a[2]);
            dq = dvec3(0.0, 0.0, a[2]);
            return;
        case Profile::Cone:
            q = dvec3(a[1] * (1.0 - v), 0.0, v * a[0]);
            dq = dvec3(-a[1], 0.0, a[0]);
            return;
        case Profile::Disk:
            q = dvec3(a[1] * (1.0 - v), 0.0, a[0]);
            dq = dvec3(-a[1], 0.0, 0.0);
            return;
        case Profile::Torus: {
            double s;
            double c;
            sincos_deg(a[2] + v * a[3], s, c);
            const double dphi = a[3] * kDegToRad;
            q = dvec3(a[0] + a[1] * c, 0.0, a[1] * s);
            dq = dvec3(-a[1] * s * dphi, 0.0, a[1] * c * dphi);
            return;
        }
        case Profile::Paraboloid: {
            const double z = std::max(0.0, a[1] + v * a[2]);
            const double root = std::sqrt(z / a[3]);
            q = dvec3(a[0] * root, 0.0, z);
            // dr/dz is infinite at the apex; 0 there leaves a zero dPdu x dPdv
            // that the dicer treats as the degenerate point it is.
            dq = dvec3(z > 0.0 ? a[0] * a[2] / (2.0 * a[3] * root) : 0.0, 0.0, a[2]);
            return;
        }
        case Profile::Hyperboloid:
            q = dvec3(a[0] + v * a[3], a[1] + v * a[4], a[2] + v * a[5]);
            dq = dvec3(a[3], a[4], a[5]);
            return;
        }
    }

    Profile m_profile;
    std::array<double, 6> m_a{};
    double m_thetamax = 360.0;
};

// ---------------------------------------------------------------------------
// Arguments

void check_args(const Primitive& prim, std::size_t count) {
    if (prim.args.size() != count)
        fail(prim, "expects " + std::to_string(count) + " arguments, got " +
                       std::to_string(prim.args.size()));
    for (double a : prim.args)
        if (!std::isfinite(a)) fail(prim, "has a NaN or infinite argument");
}

/// What a quadric takes: its argument count, and which argument is the
/// radius that must be > 0 (none for the hyperboloid).
struct QuadricRule {
    PrimitiveKind kind;
    QuadricSurface::Profile profile;
    std::size_t args;
    int radius; ///< -1: none
    const char* radius_name;
};

constexpr QuadricRule kQuadricRules[] = {
    {PrimitiveKind::Sphere, QuadricSurface::Profile::Sphere, 4, 0, "radius"},
    {PrimitiveKind::Cylinder, QuadricSurface::Profile::Cylinder, 4, 0, "radius"},
    {PrimitiveKind::Cone, QuadricSurface::Profile::Cone, 3, 1, "radius"},
    {PrimitiveKind::Disk, QuadricSurface::Profile::Disk, 3, 1, "radius"},
    {PrimitiveKind::Torus, QuadricSurface::Profile::Torus, 5, 1, "minor radius"},
    {PrimitiveKind::Paraboloid, QuadricSurface::Profile::Paraboloid, 4, 0, "radius"},
    {PrimitiveKind::Hyperboloid, QuadricSurface::Profile::Hyperboloid, 7, -1, nullptr},
};

/// Checks a quadric's arguments; returns its profile.
QuadricSurface::Profile check_quadric(const Primitive& prim) {
    const auto& a = prim.args;
    for (const QuadricRule& rule : kQuadricRules) {
        if (rule.kind != prim.kind) continue;
        check_args(prim, rule.args);
        if (rule.radius >= 0 && !(a[rule.radius] > 0.0))
            fail(prim, std::string(rule.radius_name) + " must be > 0");
        if (rule.kind == PrimitiveKind::Paraboloid && (!(a[2] > 0.0) || a[1] < 0.0))
            fail(prim, "needs 0 <= zmin and zmax > 0");
        return rule.profile;
    }
    throw ValueError(describe(prim) + ": not a quadric");
}

// ---------------------------------------------------------------------------
// Reference areas

/// Adaptive 12-point Gauss-Legendre: halves an interval until the halves
/// agree with the whole to `tol`.
template <class F>
double adaptive_integral(const F& f, double a, double b, double tol, int depth = 0) {
    static const GaussRule rule(12);
    const double m = 0.5 * (a + b);
    const double whole = rule.integrate(f, a, b);
    const double left = rule.integrate(f, a, m);
    const double right = rule.integrate(f, m, b);
    if (std::abs(left + right - whole) <= tol || depth >= 40) return left + right;
    return adaptive_integral(f, a, m, 0.5 * tol, depth + 1) +
           adaptive_integral(f, m, b, 0.5 * tol, depth + 1);
}

/// Area of a surface of revolution swept by |thetamax| radians, given
/// g(v) = rho * sqrt(rho'^2 + z'^2) of its profile over v in [0, 1].
template <class F>
double revolution_area(double thetamax_rad, const F& g) {
    const double rough = GaussRule(12).integrate(g, 0.0, 1.0);
    const double tol = 1e-14 * std::max(std::abs(rough), 1e-300);
    return std::abs(thetamax_rad) * adaptive_integral(g, 0.0, 1.0, tol);
}

/// Integral of |R + r cos(phi)| over [a, b] (radians, a <= b), exactly:
/// split at the zeros of the integrand.
double torus_band(double major, double minor, double a, double b) {
    const auto antiderivative = [&](double phi) {
        return major * phi + minor * std::sin(phi);
    };
    std::vector<double> cuts{a, b};
    const double ratio = -major / minor;
    if (ratio > -1.0 && ratio < 1.0) {
        const double root = std::acos(ratio);
        for (double base : {root, -root}) {
            const double k0 = std::ceil((a - base) / (2.0 * kPi));
            for (double k = k0; base + 2.0 * kPi * k < b; k += 1.0)
                cuts.push_back(base + 2.0 * kPi * k);
        }
    }
    std::sort(cuts.begin(), cuts.end());
    double sum = 0.0;
    for (std::size_t k = 0; k + 1 < cuts.size(); ++k)
        sum += std::abs(antiderivative(cuts[k + 1]) - antiderivative(cuts[k]));
    return sum;
}

} // namespace

namespace detail {

DicedSurface dice_quadric(const Primitive& prim, const DiceControl& control,
                          DiceEstimate* estimate) {
    const QuadricSurface surface(check_quadric(prim), prim.args);
    const ClassCounts counts{1, 4, 4, 4, 4};
    const PrimVar cs(prim, "Cs", counts);
    const PrimVar n(prim, "N", counts);
    const FaceIndex at;
    Face face;
    face.geometry = &surface;
    face.color = cs.face(at, Matrix4(1.0), Matrix4(1.0));
    face.normal = n.face(at, Matrix4(1.0), Matrix4(1.0));
    const TexCoordVars st(prim, counts);
    face.s = st.s.face(at, Matrix4(1.0), Matrix4(1.0));
    face.t = st.t.face(at, Matrix4(1.0), Matrix4(1.0));
    DicedSurface out;
    ParametricDicer(prim, control, out, estimate).dice(face);
    return out;
}

} // namespace detail

double quadric_area(const Primitive& prim) {
    check_quadric(prim);
    const auto& a = prim.args;
    switch (prim.kind) {
    case PrimitiveKind::Sphere: {
        const double r = a[0];
        const double zmin = std::clamp(a[1], -r, r);
        const double zmax = std::clamp(a[2], -r, r);
        // Archimedes: a spherical zone's area is 2 pi r h.
        return r * std::abs(zmax - zmin) * std::abs(a[3]) * kDegToRad;
    }
    case PrimitiveKind::Cylinder:
        return a[0] * std::abs(a[2] - a[1]) * std::abs(a[3]) * kDegToRad;
    case PrimitiveKind::Cone:
        return 0.5 * a[1] * std::hypot(a[0], a[1]) * std::abs(a[2]) * kDegToRad;
    case PrimitiveKind::Disk:
        return 0.5 * a[1] * a[1] * std::abs(a[2]) * kDegToRad;
    case PrimitiveKind::Torus: {
        const double lo = std::min(a[2], a[3]) * kDegToRad;
        const double hi = std::max(a[2], a[3]) * kDegToRad;
        return std::abs(a[4]) * kDegToRad * a[1] * torus_band(a[0], a[1], lo, hi);
    }
    case PrimitiveKind::Paraboloid: {
        // rho^2 = rmax^2 z / zmax, so rho rho' = rmax^2 z' / (2 zmax): finite
        // at the apex even though rho' is not.
        const double rmax = a[0];
        const double zmin = a[1];
        const double dz = a[2] - a[1];
        const double zmax = a[2];
        const double rho_drho = rmax * rmax * dz / (2.0 * zmax);
        return revolution_area(a[3] * kDegToRad, [&](double v) {
            const double rho2 = rmax * rmax * std::max(0.0, zmin + v * dz) / zmax;
            return std::sqrt(rho_drho * rho_drho + rho2 * dz * dz);
        });
    }
    case PrimitiveKind::Hyperboloid: {
        // The line (x, y, z)(v) sweeps the same surface as its meridian
        // profile rho(v) = |(x, y)|: dA = rho sqrt(rho'^2 + z'^2) dtheta dv.
        const dvec3 p1(a[0], a[1], a[2]);
        const dvec3 d = dvec3(a[3], a[4], a[5]) - p1;
        return revolution_area(a[6] * kDegToRad, [&](double v) {
            const dvec3 q = p1 + v * d;
            const double rho_drho = q.x * d.x + q.y * d.y;
            const double rho2 = q.x * q.x + q.y * q.y;
            return std::sqrt(rho_drho * rho_drho + rho2 * d.z * d.z);
        });
    }
    default:
        break;
    }
    throw ValueError(describe(prim) + ": not a quadric");
}

} // namespace sss
