// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* depthcue: the standard depth cue (RISpec 3.2, appendix A, volume shaders).
 * The colour moves linearly towards `background` (and the opacity towards 1)
 * with the point's depth: not at all at normalised depth `mindistance` or
 * nearer, entirely at `maxdistance` or farther. Depths are depth(P): 0 at the
 * near clipping plane, 1 at the far one (Clipping). */
volume depthcue(float mindistance = 0, maxdistance = 1; color background = 0;)
{
    float span = maxdistance - mindistance;
    float amount = span > 0 ? clamp((depth(P) - mindistance) / span, 0, 1)
                            : (depth(P) >= maxdistance ? 1 : 0);
    Ci = mix(Ci, background, amount);
    Oi = mix(Oi, color(1), amount);
}
