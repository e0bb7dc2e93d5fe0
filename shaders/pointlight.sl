/* pointlight: light from a point, falling off with the squared distance
 * (RISpec 3.2, appendix A). Extensions: shadowname (ray traced), samples
 * and radius (a spherical emitter, shader space) for soft shadows. */
#include "light_shadows.h"

light pointlight(float intensity = 1; color lightcolor = 1;
                 point from = point "shader" (0, 0, 0);
                 string shadowname = "";
                 float samples = 1, radius = 0;)
{
    illuminate(from) {
        float d2 = L . L;
        Cl = intensity * lightcolor / d2 *
             light_visibility(shadowname, Ps, samples, sphere_cone(radius, sqrt(d2)));
    }
}
