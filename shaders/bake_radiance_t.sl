// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* bake_radiance_t: the bake shader of PRMan's subsurface scattering
 * application note: the light arriving at each micropolygon (ambient plus
 * diffuse), times Kdt, baked with its area into a point cloud for
 * ptfilter -ssdiffusion. */
surface bake_radiance_t(string filename = "", displaychannels = "_area,_radiance_t";
                        color Kdt = 1;)
{
    normal Nn = normalize(N);
    float a = area(P, "dicing");
    color irrad = ambient() + diffuse(Nn);
    color tr = Kdt * irrad;
    bake3d(filename, displaychannels, P, Nn, "interpolate", 1,
           "_area", a, "_radiance_t", tr);
    Oi = Os;
    Ci = Os * Cs * tr;
}
