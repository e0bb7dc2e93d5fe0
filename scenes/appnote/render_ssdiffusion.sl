/*
 * render_ssdiffusion: the render-pass shader of the subsurface scattering
 * application note. The light that diffused through the object was
 * computed by ptfilter -ssdiffusion from the baked direct light and made
 * into a brick map by brickmake; here texture3d looks it up at P and adds
 * it to the usual ambient and diffuse terms.
 *
 * Each term is also written to an output variable, so that a Display can
 * ask for it as an AOV: "_ambient", "_diffuse" and "_sss" (also known to
 * the renderer as ambient, diffuse and sss) and "_ssdiffusion", the value
 * read from the map as it is (negative where a blocker took more light
 * than diffused there).
 */
surface
render_ssdiffusion(string filename = "";
                   float Ka = 1, Kd = 1, Ksss = 1;
                   output varying color _ambient = 0;
                   output varying color _diffuse = 0;
                   output varying color _sss = 0;
                   output varying color _ssdiffusion = 0)
{
    normal Nn = normalize(N);
    normal Nf = faceforward(Nn, I);
    color ssd = 0;

    /* The map's normals are the baked surface's own (not faced forward). */
    if (filename != "")
        texture3d(filename, P, Nn, "_ssdiffusion", ssd);
    _ssdiffusion = ssd;

    _ambient = Os * Cs * Ka * ambient();
    _diffuse = Os * Cs * Kd * diffuse(Nf);
    /* A blocker can leave less than no light: show it as black. */
    _sss = Os * Cs * Ksss * max(ssd, color 0);

    Oi = Os;
    Ci = _ambient + _diffuse + _sss;
}
