// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* bake_radiance_gi: bake_radiance_t with global illumination, the
 * application note's suggested extension: the light arriving at each
 * micropolygon is ambient() + diffuse(N) + indirectdiffuse(P, N, samples)
 * (light bounced off the other objects, each shaded by its own surface
 * shader where the rays hit; rays that leave the scene see the optional
 * environment map), times Kdt, baked with its area for ptfilter
 * -ssdiffusion. The indirect part is also baked alone as "_indirect" when
 * displaychannels lists it. */
surface bake_radiance_gi(string filename = "", displaychannels = "_area,_radiance_t";
                         color Kdt = 1; float samples = 64; float maxdist = 0;
                         string envmap = "";)
{
    normal Nn = normalize(N);
    float a = area(P, "dicing");
    color indirect = 0;
    /* Rays that hit objects shade them, and those shaders may bake too:
     * bake only at the top of the ray tree (PRMan's idiom). */
    float depth = 0;
    rayinfo("depth", depth);
    if (maxdist > 0)
        indirect = indirectdiffuse(P, Nn, samples, "maxdist", maxdist,
                                   "environmentmap", envmap);
    else
        indirect = indirectdiffuse(P, Nn, samples, "environmentmap", envmap);
    color irrad = ambient() + diffuse(Nn) + indirect;
    color tr = Kdt * irrad;
    if (depth == 0)
        bake3d(filename, displaychannels, P, Nn, "interpolate", 1,
               "_area", a, "_radiance_t", tr, "_indirect", indirect);
    Oi = Os;
    Ci = Os * Cs * tr;
}
