// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* pointlight_rts: pointlight with ray-traced shadows always on (as in the RenderMan
 * application notes); the same parameters, shadowname defaults to
 * "raytrace". */
#include "light_shadows.h"

light pointlight_rts(float intensity = 1; color lightcolor = 1;
                 point from = point "shader" (0, 0, 0);
                 string shadowname = "raytrace";
                 float samples = 1, radius = 0;)
{
    illuminate(from) {
        float d2 = L . L;
        Cl = intensity * lightcolor / d2 *
             light_visibility(shadowname, Ps, samples, sphere_cone(radius, sqrt(d2))) *
             map_visibility(shadowname, Ps, samples, 0, -1, 1);
    }
}
