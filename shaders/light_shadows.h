// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* Shared by the standard lights: the shadow term. shadowname "raytrace"
 * traces shadow rays: samples > 1 with a light of non-zero size gives soft
 * shadows over the cone the emitter subtends (half-angle cone). Any other
 * non-empty name is a shadow map (MakeShadow, Display "shadow"), looked up
 * with samples, blur, bias (< 0: the scene's Option "shadow" "bias") and
 * width (the filter footprint's multiplier). */
#ifndef SSS_LIGHT_SHADOWS_H
#define SSS_LIGHT_SHADOWS_H

/* The unshadowed fraction at Ps of a light seen under the cone (apex angle),
 * traced with shadowname "raytrace". */
float light_visibility(string shadowname; point Ps; float samples, cone) {
    float visible = 1;
    if (shadowname == "raytrace")
        visible = 1 - shadow("raytrace", Ps, "samples", samples, "samplecone", cone);
    return visible;
}

/* The unshadowed fraction at Ps in the shadow map shadowname (none: 1).
 * Called after light_visibility: the ray-traced shadow's samples stay as
 * they were before maps were read. */
float map_visibility(string shadowname; point Ps; float samples, blur, bias, width) {
    float visible = 1;
    if (shadowname != "" && shadowname != "raytrace")
        visible = 1 - shadow(shadowname, Ps, "samples", samples, "blur", blur,
                             "bias", bias, "width", width);
    return visible;
}

/* Apex angle of the cone a sphere of radius r (shader space) fills seen
 * from distance d (current space). */
float sphere_cone(float r, d) {
    float rc = r * length(vtransform("shader", "current", vector(1, 0, 0)));
    float cone = 0;
    if (rc > 0 && d > rc) cone = 2 * asin(rc / d);
    return cone;
}
#endif
