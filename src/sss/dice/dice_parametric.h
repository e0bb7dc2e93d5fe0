// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file dice_parametric.h
/// Internal: the REYES dicer of parametric surfaces (dice_parametric.cpp),
/// shared by the quadrics (dice_quadric.cpp) and the patches, patch meshes
/// and teapot (dice_patch.cpp): surfaces over the unit square, their
/// primitive variables, and the ParametricDicer that turns faces into
/// micropolygons.

#include <algorithm>
#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <glm/common.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "dice_common.h"
#include "sss/dice/dice.h"

namespace sss::detail {

using glm::dvec3;
using glm::dvec4;

/// Grows a scratch buffer to at least n elements; never shrinks it, so that
/// alternating sizes do not re-initialise elements over and over.
template <class T>
void ensure_size(std::vector<T>& v, std::size_t n) {
    if (v.size() < n) v.resize(n);
}

// ---------------------------------------------------------------------------
// Surfaces

/// A surface point in object space with its parametric derivatives.
struct SurfacePoint {
    dvec3 p;
    dvec3 dpdu;
    dvec3 dpdv;
};

/// A parametric surface over the unit square, in object space.
class Surface {
public:
    virtual ~Surface() = default;
    /// P, dPdu and dPdv at every (us[i], vs[j]), stored at out[j * us.size() + i].
    /// Tensor-product grids let each surface share work along rows and columns.
    virtual void evaluate(std::span<const double> us, std::span<const double> vs,
                          SurfacePoint* out) const = 0;
};

/// One bicubic patch: 16 control values in RI order (u fastest) and the
/// u and v bases. Also interpolates vertex-class colours and normals.
class BicubicSurface final : public Surface {
public:
    BicubicSurface(const std::array<dvec3, 16>& points, const glm::dmat4& u_basis,
                   const glm::dmat4& v_basis)
        : m_points(points), m_u_basis(u_basis), m_v_basis(v_basis) {}

    // Defined in dice_patch.cpp, out of the dicer's sight: inlined into the
    // dicer (a direct call guessed from the only surface in view), it would
    // be compiled with other fused multiply-adds and change the last bits of
    // the diced surfaces.
    void evaluate(std::span<const double> us, std::span<const double> vs,
                  SurfacePoint* out) const override;

private:
    std::array<dvec3, 16> m_points;
    glm::dmat4 m_u_basis;
    glm::dmat4 m_v_basis;
};

// ---------------------------------------------------------------------------
// Primitive variables (Cs, N) over one face

/// Cs or N over one face: absent, constant, bilinear over the four corners
/// (varying class) or interpolated like P (vertex class of bicubic patches
/// and NuPatches: a Surface over the values).
struct FaceValues {
    enum class Mode { None, Constant, Bilinear, Spline };
    Mode mode = Mode::None;
    std::array<dvec3, 4> corners{}; ///< Constant uses corners[0]
    std::shared_ptr<const Surface> spline;

    bool present() const { return mode != Mode::None; }

    /// Values at every (us[i], vs[j]), out[j * us.size() + i].
    void evaluate(std::span<const double> us, std::span<const double> vs,
                  dvec3* out) const {
        switch (mode) {
        case Mode::None:
            return;
        case Mode::Constant:
            std::fill(out, out + us.size() * vs.size(), corners[0]);
            return;
        case Mode::Bilinear:
            for (std::size_t j = 0; j < vs.size(); ++j)
                for (std::size_t i = 0; i < us.size(); ++i) {
                    const dvec3 bottom = glm::mix(corners[0], corners[1], us[i]);
                    const dvec3 top = glm::mix(corners[2], corners[3], us[i]);
                    out[j * us.size() + i] = glm::mix(bottom, top, vs[j]);
                }
            return;
        case Mode::Spline: {
            thread_local std::vector<SurfacePoint> tmp;
            const std::size_t n = us.size() * vs.size();
            ensure_size(tmp, n);
            spline->evaluate(us, vs, tmp.data());
            for (std::size_t k = 0; k < n; ++k) out[k] = tmp[k].p;
            return;
        }
        }
    }
};

/// Where one face finds its values among the primitive's.
struct FaceIndex {
    std::size_t uniform = 0; ///< also the patch number, for face* classes
    std::array<std::size_t, 4> varying{0, 1, 2, 3}; ///< RI corner order
    std::array<std::size_t, 16> vertex{0, 1, 2,
                                       3}; ///< control points (4 used if bilinear)
    bool bicubic = false;
};

/// A checked Cs or N parameter of a primitive.
struct PrimVar {
    const Param* param = nullptr;
    std::vector<dvec3> values;

    PrimVar() = default;
    /// Reads `name` (`width` numbers per value, 1 to 3, kept in the first
    /// components) and checks its count for its class.
    PrimVar(const Primitive& prim, const char* name, const ClassCounts& counts,
            int width = 3);

    /// Component c of every value, in the first component.
    PrimVar component(int c) const;

    /// The values over one face.
    FaceValues face(const FaceIndex& at, const glm::dmat4& u_basis,
                    const glm::dmat4& v_basis) const;
};

/// Texture coordinates of a primitive: "st" (two numbers per value), else
/// "s" and "t" (one each); absent ones are the face's u and v.
struct TexCoordVars {
    PrimVar s, t;
    TexCoordVars(const Primitive& prim, const ClassCounts& counts);
};

/// One parametric face to dice.
struct Face {
    const Surface* geometry = nullptr;
    FaceValues color;  ///< Cs
    FaceValues normal; ///< N, object space, used as given
    FaceValues s, t;   ///< texture coordinates (first component); absent: u, v
    /// The primitive's parametric coordinates of face point (u, v):
    /// (u_offset + u_scale * u, v_offset + v_scale * v) (patch meshes: the
    /// whole mesh spans [0, 1]^2).
    double u_offset = 0.0, u_scale = 1.0, v_offset = 0.0, v_scale = 1.0;
};

// ---------------------------------------------------------------------------
// The dicer

/// Dices the faces of one primitive into one DicedSurface: each face is
/// split in parameter space until its pieces make grids of at most 256
/// micropolygons of about the wanted size (dice_parametric.cpp).
class ParametricDicer {
public:
    /// Checks the transform and that `control` can size micropolygons for
    /// `prim` (ValueError naming it otherwise); faces are diced into `out`,
    /// or with `estimate` set only estimated into *estimate (from their
    /// measured samples, whose world points are range-checked either way).
    ParametricDicer(const Primitive& prim, const DiceControl& control, DicedSurface& out,
                    DiceEstimate* estimate = nullptr);
    ~ParametricDicer();
    ParametricDicer(const ParametricDicer&) = delete;
    ParametricDicer& operator=(const ParametricDicer&) = delete;

    /// Dices one face, appending its micropolygons and triangles to `out`.
    void dice(const Face& face);

private:
    // The dicer itself is local to dice_parametric.cpp (an anonymous class),
    // so the compiler optimises it as one unit, whoever calls it.
    struct State;
    std::unique_ptr<State> m_state;
};

} // namespace sss::detail
