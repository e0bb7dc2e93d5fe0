// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* fog: the standard exponential fog (RISpec 3.2, appendix A, volume shaders).
 * Light from the far end of the ray (Ci, Oi as the surface left them) is
 * attenuated by exp(-length/distance) over the ray's length, and the fog's
 * own colour makes up the rest: the colour moves towards `background` and
 * the opacity towards 1 by the fraction 1 - exp(-length(I) / distance). Run
 * as an Atmosphere on camera rays (or as an Interior or Exterior). */
volume fog(float distance = 1; color background = 0;)
{
    float amount = 1 - exp(-length(I) / max(distance, 1e-30));
    Ci = mix(Ci, background, amount);
    Oi = mix(Oi, color(1), amount);
}
