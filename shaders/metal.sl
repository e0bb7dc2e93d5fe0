// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* metal: the standard metal surface (RISpec 3.2, appendix A). */
surface metal(float Ka = 1, Ks = 1, roughness = .1;
              output varying color _ambient = 0, _specular = 0;)
{
    normal Nf = faceforward(normalize(N), I);
    vector V = -normalize(I);
    _ambient = Os * Cs * Ka * ambient();
    _specular = Os * Cs * Ks * specular(Nf, V, roughness);
    Oi = Os;
    Ci = _ambient + _specular;
}
