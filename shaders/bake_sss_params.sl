// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* bake_sss_params: bake_radiance_t plus the material of each point
 * (_albedo, _diffusemeanfreepath in mm) for ptfilter -material fromfile.
 * The material is a preset (sss_materials.h) unless albedo and dmfp are
 * given; with noisefreq > 0 it blends towards albedo2/dmfp2 with 3-D noise
 * in shader space (frequency in cycles per shader unit). */
#include "sss_materials.h"

surface bake_sss_params(string filename = "";
                        string displaychannels =
                            "_area,_radiance_t,_albedo,_diffusemeanfreepath";
                        color Kdt = 1;
                        string material = "marble";
                        color albedo = -1, dmfp = -1, albedo2 = -1, dmfp2 = -1;
                        float noisefreq = 0;)
{
    color a1 = color(0.830191456, 0.790960197, 0.752609945);
    color d1 = color(8.50941186, 5.56618009, 3.95126596);
    if (sss_material(material, a1, d1) == 0)
        printf("bake_sss_params: unknown material \"%s\", using marble\n", material);
    if (albedo != color -1) a1 = albedo;
    if (dmfp != color -1) d1 = dmfp;
    color a2 = a1, d2 = d1;
    if (albedo2 != color -1) a2 = albedo2;
    if (dmfp2 != color -1) d2 = dmfp2;

    float t = 0;
    if (noisefreq > 0)
        t = float noise(noisefreq * transform("shader", P));
    color alb = mix(a1, a2, t);
    color mfp = mix(d1, d2, t);

    normal Nn = normalize(N);
    float a = area(P, "dicing");
    color tr = Kdt * (ambient() + diffuse(Nn));
    bake3d(filename, displaychannels, P, Nn, "interpolate", 1, "_area", a,
           "_radiance_t", tr, "_albedo", alb, "_diffusemeanfreepath", mfp);
    Oi = Os;
    Ci = Os * Cs * tr;
}
