// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* pointlight: light from a point, falling off with the squared distance
 * (RISpec 3.2, appendix A). Extensions: shadowname ("raytrace": samples and
 * radius (a spherical emitter, shader space) for soft shadows; a shadow
 * map: samples, blur, bias, width, light_shadows.h). */
#include "light_shadows.h"

light pointlight(float intensity = 1; color lightcolor = 1;
                 point from = point "shader" (0, 0, 0);
                 string shadowname = "";
                 float samples = 1, radius = 0;
                 float blur = 0, bias = -1, width = 1;)
{
    illuminate(from) {
        float d2 = L . L;
        Cl = intensity * lightcolor / d2 *
             light_visibility(shadowname, Ps, samples, sphere_cone(radius, sqrt(d2))) *
             map_visibility(shadowname, Ps, samples, blur, bias, width);
    }
}
