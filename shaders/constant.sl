// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* constant: the surface colour, unlit (RISpec 3.2, appendix A). */
surface constant()
{
    Oi = Os;
    Ci = Os * Cs;
}
