// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file beam_diffusion.h
/// Photon beam diffusion (Habel, Christensen and Jarosz 2013) for a normally
/// incident beam, in units of the transport mean free path (sigma_t' = 1):
/// dipoles integrated along the refracted beam with d'Eon's boundary and
/// near-source correction, plus the exact single scattering.

#include <memory>

#include "radial_curve.h"

namespace sss::diffusion_detail {

/// Light that scattered more than once, per unit area at radius rho.
double beam_multiple(double alpha, double eta, double rho);
/// Light that scattered exactly once (exact for the reduced isotropic
/// medium), per unit area at radius rho.
double beam_single(double alpha, double eta, double rho);

/// The sampled curve rho (multiple + single), shared per (alpha, eta); every
/// value of a curve comes from `make` (so tabulated corrections can be
/// folded in): make(rho) = rho R(rho). alpha in (0, 1).
using CurveMaker = double (*)(double alpha, double eta, double rho);
std::shared_ptr<const RadialCurve> cached_curve(int family, CurveMaker make, double alpha,
                                                double eta);

/// f = rho R of photon beam diffusion.
double beam_curve_value(double alpha, double eta, double rho);

/// sigma_tr / sigma_t' of the Grosjean diffusion coefficient
/// D = (2 sigma_a + sigma_s') / (3 sigma_t'^2): the dmfp convention of the
/// better dipole, photon beam diffusion and the Monte-Carlo profile.
double grosjean_sigma_tr(double alpha);

} // namespace sss::diffusion_detail
