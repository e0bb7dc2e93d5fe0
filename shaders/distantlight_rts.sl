// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* distantlight_rts: distantlight with ray-traced shadows always on (as in the RenderMan
 * application notes); the same parameters, shadowname defaults to
 * "raytrace". */
#include "light_shadows.h"

light distantlight_rts(float intensity = 1; color lightcolor = 1;
                   point from = point "shader" (0, 0, 0);
                   point to = point "shader" (0, 0, 1);
                   string shadowname = "raytrace";
                   float samples = 1, angle = 0;)
{
    solar(to - from, 0) {
        Cl = intensity * lightcolor *
             light_visibility(shadowname, Ps, samples, radians(angle)) *
             map_visibility(shadowname, Ps, samples, 0, -1, 1);
    }
}
