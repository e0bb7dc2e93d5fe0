// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* bake_constant: bakes the surface colour Cs (per vertex when the object
 * gives one; negative values allowed) with each point's area: blockers
 * inside objects for ptfilter. `channel` names the colour channel. */
surface bake_constant(string filename = "", channel = "_radiance_t";)
{
    normal Nn = normalize(N);
    float a = area(P, "dicing");
    bake3d(filename, concat("_area,", channel), P, Nn, "interpolate", 1,
           "_area", a, channel, Cs);
    Oi = Os;
    Ci = Os * Cs;
}
