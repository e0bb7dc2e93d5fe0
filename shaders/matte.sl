// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* matte: the standard diffuse surface (RISpec 3.2, appendix A), with the
 * toolchain's ambient-occlusion extension (occlusion_samples > 0 scales the
 * ambient term by the unoccluded fraction). The components also go to the
 * output variables the renderer writes as AOVs. */
surface matte(float Ka = 1, Kd = 1;
              float occlusion_samples = 0, occlusion_maxdist = 0;
              output varying color _ambient = 0, _diffuse = 0;
              output varying float _occlusion = 1;)
{
    normal Nf = faceforward(normalize(N), I);
    if (occlusion_samples > 0)
        _occlusion = 1 - occlusion(P, Nf, occlusion_samples, "maxdist", occlusion_maxdist);
    _ambient = Os * Cs * (Ka * _occlusion) * ambient();
    _diffuse = Os * Cs * Kd * diffuse(Nf);
    Oi = Os;
    Ci = _ambient + _diffuse;
}
