// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* background: the standard background imager (RISpec 3.2, appendix A, imager
 * shaders). Every pixel gets `bgcolor` behind what was rendered: the pixel's
 * premultiplied colour plus bgcolor times its uncovered part (1 - alpha).
 * The result is opaque: alpha = 1. Empty pixels become bgcolor; covered
 * pixels keep their colour. */
imager background(color bgcolor = 1;)
{
    Ci += (1 - alpha) * bgcolor;
    Oi = 1;
    alpha = 1;
}
