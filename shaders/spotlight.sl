// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* spotlight: a cone of light from `from` towards `to` with a soft edge and
 * a beam falloff (RISpec 3.2, appendix A). Extensions: shadowname
 * ("raytrace": samples and radius (spherical emitter) for soft shadows; a
 * shadow map: samples, blur, bias, width, light_shadows.h). */
#include "light_shadows.h"

light spotlight(float intensity = 1; color lightcolor = 1;
                point from = point "shader" (0, 0, 0);
                point to = point "shader" (0, 0, 1);
                float coneangle = radians(30), conedeltaangle = radians(5);
                float beamdistribution = 2;
                string shadowname = "";
                float samples = 1, radius = 0;
                float blur = 0, bias = -1, width = 1;)
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
             light_visibility(shadowname, Ps, samples, sphere_cone(radius, sqrt(d2))) *
             map_visibility(shadowname, Ps, samples, blur, bias, width);
    }
}
