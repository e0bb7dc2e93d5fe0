// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* read_ssdiffusion: the final-render shader of PRMan's subsurface
 * scattering application note: the diffusion baked by ptfilter
 * (_ssdiffusion, looked up in a brick map or a point cloud with texture3d)
 * plus ambient and direct diffuse light. Defaults Ka = Kd = 1 as in the
 * note. Blockers bake negative light: where they outweigh the light that
 * diffuses past them the result is no light, not negative light. */
surface read_ssdiffusion(string filename = "";
                         string channel = "_ssdiffusion";
                         float Ka = 1, Kd = 1;
                         float filterscale = 1;
                         float occlusion_samples = 0, occlusion_maxdist = 0;
                         output varying color _ambient = 0, _diffuse = 0, _sss = 0;
                         output varying float _occlusion = 1;)
{
    normal Nn = normalize(N);
    normal Nf = faceforward(Nn, I);
    color ssd = 0;
    if (filename != "")
        texture3d(filename, P, Nn, "filterscale", filterscale, channel, ssd);
    if (occlusion_samples > 0)
        _occlusion = 1 - occlusion(P, Nf, occlusion_samples, "maxdist", occlusion_maxdist);
    _ambient = Os * Cs * (Ka * _occlusion) * ambient();
    _diffuse = Os * Cs * Kd * diffuse(Nf);
    _sss = Os * Cs * max(ssd, color 0);
    Oi = Os;
    Ci = _ambient + _diffuse + _sss;
}
