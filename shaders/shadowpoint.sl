// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* shadowpoint: PRMan's pointlight with six shadow maps, one per world axis
 * (sfpx sfnx sfpy sfny sfpz sfnz: 90-degree views from `from` along +x, -x,
 * +y, -y, +z, -z). Each point is looked up in the map of the axis its
 * direction from the light is nearest to; an empty name there means no
 * shadow. samples, blur, bias (< 0: the scene's Option "shadow" "bias") and
 * width filter the lookup (light_shadows.h). */
#include "light_shadows.h"

light shadowpoint(float intensity = 1; color lightcolor = 1;
                  point from = point "shader" (0, 0, 0);
                  string sfpx = "", sfnx = "", sfpy = "", sfny = "", sfpz = "",
                         sfnz = "";
                  float samples = 16, width = 1, blur = 0, bias = -1;)
{
    illuminate(from) {
        float d2 = L . L;
        vector Lw = vtransform("world", L);
        float ax = abs(xcomp(Lw)), ay = abs(ycomp(Lw)), az = abs(zcomp(Lw));
        /* One lookup per map, each under its own condition: a map name
           is the same for every point of a call. */
        float visible = 1;
        if (ax >= ay && ax >= az) {
            if (xcomp(Lw) > 0)
                visible = light_visibility(sfpx, Ps, samples, 0) *
                          map_visibility(sfpx, Ps, samples, blur, bias, width);
            else
                visible = light_visibility(sfnx, Ps, samples, 0) *
                          map_visibility(sfnx, Ps, samples, blur, bias, width);
        } else if (ay >= az) {
            if (ycomp(Lw) > 0)
                visible = light_visibility(sfpy, Ps, samples, 0) *
                          map_visibility(sfpy, Ps, samples, blur, bias, width);
            else
                visible = light_visibility(sfny, Ps, samples, 0) *
                          map_visibility(sfny, Ps, samples, blur, bias, width);
        } else {
            if (zcomp(Lw) > 0)
                visible = light_visibility(sfpz, Ps, samples, 0) *
                          map_visibility(sfpz, Ps, samples, blur, bias, width);
            else
                visible = light_visibility(sfnz, Ps, samples, 0) *
                          map_visibility(sfnz, Ps, samples, blur, bias, width);
        }
        Cl = intensity * lightcolor / d2 * visible;
    }
}
