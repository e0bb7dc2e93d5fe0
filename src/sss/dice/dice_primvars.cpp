// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file dice_primvars.cpp
/// Primitive variables of the parametric surfaces (dice_parametric.h): Cs, N
/// and the texture coordinates over one face, by storage class.

#include "dice_parametric.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>
#include <glm/vec4.hpp>

#include "sss/util/error.h"

namespace sss::detail {

// ---------------------------------------------------------------------------
// Primitive variables (Cs, N) over one face

PrimVar::PrimVar(const Primitive& prim, const char* name, const ClassCounts& counts,
                 int width) {
    param = prim.params.find(name);
    if (!param) return;
    if (param->type == ParamType::String || param->element_size() != width)
        fail(prim, std::string("\"") + name + "\" must have " + std::to_string(width) +
                       " numbers per value, not " +
                       std::to_string(param->element_size()));
    // Patches: facevarying values per patch corner (4 per patch),
    // facevertex values per patch control point (4 or 16 per patch).
    const std::size_t want = counts.of(param->storage);
    const auto w = static_cast<std::size_t>(width);
    if (param->numbers.size() != w * want)
        fail(prim, std::string("\"") + name + "\" has " +
                       std::to_string(param->numbers.size()) + " numbers, expected " +
                       std::to_string(w * want));
    values.resize(want);
    for (std::size_t k = 0; k < want; ++k) {
        dvec3 value(0.0);
        for (std::size_t c = 0; c < w; ++c) value[c] = param->numbers[w * k + c];
        values[k] = value;
        if (!finite(values[k]))
            fail(prim, std::string("\"") + name + "\" has a NaN or infinite value");
    }
}

PrimVar PrimVar::component(int c) const {
    PrimVar out;
    out.param = param;
    out.values.reserve(values.size());
    for (const dvec3& v : values) out.values.emplace_back(v[c], 0.0, 0.0);
    return out;
}

TexCoordVars::TexCoordVars(const Primitive& prim, const ClassCounts& counts) {
    const PrimVar st(prim, "st", counts, 2);
    if (st.param) {
        s = st.component(0);
        t = st.component(1);
        return;
    }
    s = PrimVar(prim, "s", counts, 1);
    t = PrimVar(prim, "t", counts, 1);
}

FaceValues PrimVar::face(const FaceIndex& at, const glm::dmat4& u_basis,
                         const glm::dmat4& v_basis) const {
    FaceValues fv;
    if (!param) return fv;
    switch (param->storage) {
    case ParamClass::Constant:
        fv.mode = FaceValues::Mode::Constant;
        fv.corners[0] = values[0];
        break;
    case ParamClass::Uniform:
        fv.mode = FaceValues::Mode::Constant;
        fv.corners[0] = values[at.uniform];
        break;
    case ParamClass::Varying:
        fv.mode = FaceValues::Mode::Bilinear;
        for (int k = 0; k < 4; ++k) fv.corners[k] = values[at.varying[k]];
        break;
    case ParamClass::FaceVarying:
        fv.mode = FaceValues::Mode::Bilinear;
        for (std::size_t k = 0; k < 4; ++k) fv.corners[k] = values[4 * at.uniform + k];
        break;
    case ParamClass::Vertex:
    case ParamClass::FaceVertex: {
        const bool per_face = param->storage == ParamClass::FaceVertex;
        const std::size_t n = at.bicubic ? 16 : 4;
        std::array<dvec3, 16> cp;
        for (std::size_t k = 0; k < n; ++k)
            cp[k] = values[per_face ? n * at.uniform + k : at.vertex[k]];
        if (at.bicubic) {
            fv.mode = FaceValues::Mode::Spline;
            fv.spline = std::make_shared<BicubicSurface>(cp, u_basis, v_basis);
        } else {
            fv.mode = FaceValues::Mode::Bilinear;
            std::copy(cp.begin(), cp.begin() + 4, fv.corners.begin());
        }
        break;
    }
    }
    return fv;
}
} // namespace sss::detail
