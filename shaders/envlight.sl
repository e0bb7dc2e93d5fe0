// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* envlight: image-based light (the classic PRMan environment light). It
 * runs at the surface point (illuminate(Ps + N): light arrives along the
 * surface normal, which the engine gives light shaders as N) and returns
 * the surface's cosine-weighted view of the environment with occlusion by
 * the scene: occlusion() over `samples` cosine-distributed rays in the cone
 * about N, maxdist (0 = infinite); with an environment map, envcol is the
 * average of the map (looked up in envspace) over the unoccluded rays, so a
 * constant white map on an unoccluded point gives 1. Then
 *     diffuse(N) = intensity * lightcolor * envcol
 *               ~ intensity * lightcolor * (1/pi) * integral of map * cos,
 * the cosine-weighted irradiance / pi; without a map, 1 - occlusion (white
 * sky). __nonspecular = 1: specular() ignores it. docs/lighting.md. */

light envlight(float intensity = 1;
               color lightcolor = 1;
               string envmap = "";
               string envspace = "world";
               float samples = 64;
               float maxdist = 0;
               float coneangle = PI / 2;
               float bias = -1;
               string __category = "";
               float __nonspecular = 1;)
{
    normal Nn = normalize(N);
    illuminate(Ps + Nn) {
        color envcol = 0;
        float occ = occlusion(Ps, Nn, samples, "maxdist", maxdist, "coneangle", coneangle,
                              "bias", bias, "environmentmap", envmap,
                              "environmentspace", envspace, "environmentcolor", envcol);
        if (envmap != "")
            Cl = intensity * lightcolor * envcol;
        else
            Cl = intensity * lightcolor * (1 - occ);
    }
}
