// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* paintedplastic: plastic whose colour is multiplied by a texture map
 * (RISpec 3.2, appendix A); "" means no texture. */
surface paintedplastic(float Ka = 1, Kd = .5, Ks = .5, roughness = .1;
                       color specularcolor = 1;
                       string texturename = "";
                       output varying color _ambient = 0, _diffuse = 0, _specular = 0;)
{
    normal Nf = faceforward(normalize(N), I);
    vector V = -normalize(I);
    color Ct = Cs;
    if (texturename != "")
        Ct *= color texture(texturename);
    _ambient = Os * Ct * Ka * ambient();
    _diffuse = Os * Ct * Kd * diffuse(Nf);
    _specular = Os * specularcolor * Ks * specular(Nf, V, roughness);
    Oi = Os;
    Ci = _ambient + _diffuse + _specular;
}
