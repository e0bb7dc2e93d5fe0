// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* plastic: the standard plastic surface (RISpec 3.2, appendix A), with the
 * toolchain's ambient-occlusion extension and AOV outputs. */
surface plastic(float Ka = 1, Kd = .5, Ks = .5, roughness = .1;
                color specularcolor = 1;
                float occlusion_samples = 0, occlusion_maxdist = 0;
                output varying color _ambient = 0, _diffuse = 0, _specular = 0;
                output varying float _occlusion = 1;)
{
    normal Nf = faceforward(normalize(N), I);
    vector V = -normalize(I);
    if (occlusion_samples > 0)
        _occlusion = 1 - occlusion(P, Nf, occlusion_samples, "maxdist", occlusion_maxdist);
    _ambient = Os * Cs * (Ka * _occlusion) * ambient();
    _diffuse = Os * Cs * Kd * diffuse(Nf);
    _specular = Os * specularcolor * Ks * specular(Nf, V, roughness);
    Oi = Os;
    Ci = _ambient + _diffuse + _specular;
}
