// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* skin: subsurface diffusion from a brick map or point cloud (as
 * read_ssdiffusion) under a thin oily layer: a specular lobe whose weight
 * goes from Ksfacing (looking straight at the surface) to Ksglancing (at
 * grazing angles), and diffuse light scaled by ambient occlusion. */
surface skin(string filename = "";
             string channel = "_ssdiffusion";
             float Ka = 0, Kd = .3;
             float Ksfacing = .05, Ksglancing = .3, roughness = .2;
             color specularcolor = 1;
             float sss_weight = 1;
             color sss_color = 1;
             float filterscale = 1;
             float occlusion_samples = 0, occlusion_maxdist = 0;
             output varying color _ambient = 0, _diffuse = 0, _specular = 0, _sss = 0;
             output varying float _occlusion = 1;)
{
    normal Nn = normalize(N);
    normal Nf = faceforward(Nn, I);
    vector V = -normalize(I);
    color ssd = 0;
    if (filename != "")
        texture3d(filename, P, Nn, "filterscale", filterscale, channel, ssd);
    if (occlusion_samples > 0)
        _occlusion = 1 - occlusion(P, Nf, occlusion_samples, "maxdist", occlusion_maxdist);
    float facing = max(0, Nf . V);
    float ks = Ksglancing + (Ksfacing - Ksglancing) * facing;
    _ambient = Os * Cs * (Ka * _occlusion) * ambient();
    _diffuse = Os * Cs * (Kd * _occlusion) * diffuse(Nf);
    _specular = Os * specularcolor * ks * specular(Nf, V, roughness);
    _sss = Os * sss_weight * sss_color * max(ssd, color 0);
    Oi = Os;
    Ci = _ambient + _diffuse + _specular + _sss;
}
