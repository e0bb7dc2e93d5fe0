// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* shadowspot: PRMan's spotlight with a shadow map: the spotlight's cone and
 * beam, shadowed by the depth map `shadowname` (MakeShadow of a zfile
 * rendered from the light; "raytrace" traces rays instead). samples, blur,
 * bias (< 0: the scene's Option "shadow" "bias") and width filter the
 * lookup (light_shadows.h). */
#include "light_shadows.h"

light shadowspot(float intensity = 1; color lightcolor = 1;
                 point from = point "shader" (0, 0, 0);
                 point to = point "shader" (0, 0, 1);
                 float coneangle = radians(30), conedeltaangle = radians(5);
                 float beamdistribution = 2;
                 string shadowname = "";
                 float samples = 16, width = 1, blur = 0, bias = -1;)
{
    uniform vector A = normalize(to - from);
    illuminate(from, A, coneangle) {
        float d2 = L . L;
        float cosangle = (L . A) / sqrt(d2);
        float atten = 0;
        if (cosangle > 0)
            atten = pow(cosangle, beamdistribution) / d2 *
                    smoothstep(cos(coneangle), cos(coneangle - conedeltaangle), cosangle);
        Cl = atten * intensity * lightcolor *
             light_visibility(shadowname, Ps, samples, 0) *
             map_visibility(shadowname, Ps, samples, blur, bias, width);
    }
}
