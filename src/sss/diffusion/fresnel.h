// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file fresnel.h
/// Fresnel terms of the diffusion boundary, for light inside a medium of
/// relative index eta (inside / outside).

namespace sss::diffusion_detail {

/// Reflectance at cosine mu inside (total internal reflection past the
/// critical angle).
double fresnel_internal(double mu, double eta);

struct FresnelMoments {
    double two_c1;   ///< 2 C1 = \int_0^1 2 F(mu) mu dmu
    double three_c2; ///< 3 C2 = \int_0^1 3 F(mu) mu^2 dmu
};

/// The hemispherical moments (exact quadrature, cached per eta).
FresnelMoments fresnel_moments(double eta);

} // namespace sss::diffusion_detail
