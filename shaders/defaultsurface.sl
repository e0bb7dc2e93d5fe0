// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* defaultsurface: PRMan's surface for objects without a Surface: a
 * headlight, no light sources. */
surface defaultsurface(float Ka = .2, Kd = .8;
                       output varying color _diffuse = 0;)
{
    float d = (I . N) * (I . N) / ((I . I) * (N . N));
    Oi = Os;
    _diffuse = Os * Cs * (Ka + Kd * d);
    Ci = _diffuse;
}
