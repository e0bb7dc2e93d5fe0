/*
 * calcite_sss: the render-pass shader of the calcite study. The light that
 * diffused through the crystal (the _ssdiffusion of ptfilter, looked up in
 * the brick map with texture3d), a sharp specular reflection of the lights
 * on the polished faces, and a little ambient light scaled by ambient
 * occlusion.
 *
 * Two terms are AOVs for the compositor: _occlusion, the unoccluded
 * fraction from occlusion() (1 = open sky, grey), and _sss, the
 * diffusion. _ambient, _diffuse and _specular are the other terms of the
 * beauty.
 */
surface
calcite_sss(string filename = "";
            float Ka = 1, Kd = 0.05, Ks = 0.6, roughness = 0.04;
            float occlusion_samples = 32, occlusion_maxdist = 6;
            output varying color _occlusion = 1;
            output varying color _sss = 0;
            output varying color _ambient = 0;
            output varying color _diffuse = 0;
            output varying color _specular = 0)
{
    normal Nn = normalize(N);
    normal Nf = faceforward(Nn, I);
    vector V = -normalize(I);

    color ssd = 0;
    if (filename != "")
        texture3d(filename, P, Nn, "_ssdiffusion", ssd);
    if (occlusion_samples > 0)
        _occlusion = color(1 - occlusion(P, Nf, occlusion_samples,
                                         "maxdist", occlusion_maxdist));

    _ambient = Os * Cs * Ka * _occlusion * ambient();
    _diffuse = Os * Cs * Kd * diffuse(Nf);
    _specular = Os * Ks * specular(Nf, V, roughness);
    _sss = Os * Cs * max(ssd, color 0);
    Oi = Os;
    Ci = _ambient + _diffuse + _specular + _sss;
}
