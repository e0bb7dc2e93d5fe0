// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* distantlight: parallel light along to - from (RISpec 3.2, appendix A).
 * Extensions: shadowname ("raytrace": samples and angle (degrees, the
 * angular diameter of the light's disk) for soft shadows; a shadow map:
 * samples, blur, bias, width, light_shadows.h). */
#include "light_shadows.h"

light distantlight(float intensity = 1; color lightcolor = 1;
                   point from = point "shader" (0, 0, 0);
                   point to = point "shader" (0, 0, 1);
                   string shadowname = "";
                   float samples = 1, angle = 0;
                   float blur = 0, bias = -1, width = 1;)
{
    solar(to - from, 0) {
        Cl = intensity * lightcolor *
             light_visibility(shadowname, Ps, samples, radians(angle)) *
             map_visibility(shadowname, Ps, samples, blur, bias, width);
    }
}
