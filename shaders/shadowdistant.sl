// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* shadowdistant: PRMan's distantlight with a shadow map `shadowname`
 * (rendered with an orthographic camera looking along to - from; "raytrace"
 * traces rays instead), filtered by samples, blur, bias (< 0: the scene's
 * Option "shadow" "bias") and width (light_shadows.h). */
#include "light_shadows.h"

light shadowdistant(float intensity = 1; color lightcolor = 1;
                    point from = point "shader" (0, 0, 0);
                    point to = point "shader" (0, 0, 1);
                    string shadowname = "";
                    float samples = 16, width = 1, blur = 0, bias = -1;)
{
    solar(to - from, 0) {
        Cl = intensity * lightcolor *
             light_visibility(shadowname, Ps, samples, 0) *
             map_visibility(shadowname, Ps, samples, blur, bias, width);
    }
}
