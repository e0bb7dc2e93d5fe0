/*
 * skin_pass: the beauty pass of the skin study. Subsurface diffusion from
 * the brick map ptfilter and brickmake made of the bake pass, under a thin
 * oily layer (a specular lobe), plus a little ambient (scaled by ambient
 * occlusion) and diffuse light, on a surface bumped by a displacement
 * texture (pores and fine wrinkles).
 *
 * Every term goes to an output variable, so that the pipeline can write
 * each to a file of its own for the compositor: _ambient, _diffuse,
 * _specular, _sss (their sum is the beauty), and _occlusion (1 = open),
 * _bump (the height read from the map) and _albedo (the skin colour).
 */

/* Displace: the point P moved by amp along the direction dir, amp being
 * measured in the units of the coordinate system `space` (a scaled object
 * space makes the bump scale with the object). An empty space name is
 * "current": amp is then in the current units. */
point Displace(vector dir; string space; float amp)
{
    extern point P;
    float spacescale = length(vtransform(space, dir));
    return P + dir * (amp / max(spacescale, 1e-6));
}

surface
skin_pass(string filename = "";              /* brick map of _ssdiffusion */
          string bumpmap = "";               /* displacement texture, 0.5 = no bump */
          float bumpfreq = 1;                /* repeats of the map per shader unit */
          float Km = 0.01;                   /* bump height, in dispSPACE units */
          string dispSPACE = "";
          float Ka = 1, Kd = 0.1;
          float Ks = 0.25, roughness = 0.15;
          color specularcolor = 1;
          float sss_weight = 1;
          float occlusion_samples = 16, occlusion_maxdist = 3;
          output varying color _ambient = 0;
          output varying color _diffuse = 0;
          output varying color _specular = 0;
          output varying color _sss = 0;
          output varying float _occlusion = 1;
          output varying float _bump = 0;
          output varying color _albedo = 0)
{
    /* The bump: the map projected along the shader's z axis, tiled. */
    point Psh = transform("shader", P);
    float h = 0;
    if (bumpmap != "")
        h = float texture(bumpmap, bumpfreq * xcomp(Psh), bumpfreq * ycomp(Psh)) - 0.5;
    _bump = h;

    normal Nn = normalize(N);
    point Pb = Displace(vector Nn, dispSPACE, Km * h);
    /* The bumped normal lights the surface. The ear is a closed surface
     * whose normals face out, towards the lights: no faceforward. */
    normal Nb = normalize(calculatenormal(Pb));
    vector V = -normalize(I);

    /* The diffusion was baked on the smooth surface: look it up there,
     * with the smooth surface's own normal. */
    color ssd = 0;
    if (filename != "")
        texture3d(filename, P, Nn, "_ssdiffusion", ssd);
    if (occlusion_samples > 0)
        _occlusion = 1 - occlusion(P, Nn, occlusion_samples,
                                   "maxdist", occlusion_maxdist);

    _albedo = Os * Cs;
    _ambient = Os * Cs * Ka * _occlusion * ambient();
    _diffuse = Os * Cs * Kd * diffuse(Nb);
    _specular = Os * specularcolor * Ks * specular(Nb, V, roughness);
    _sss = Os * sss_weight * max(ssd, color 0);
    Oi = Os;
    Ci = _ambient + _diffuse + _specular + _sss;
}
