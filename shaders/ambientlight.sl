// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* ambientlight: light arriving from no direction (RISpec 3.2, appendix A). */
light ambientlight(float intensity = 1; color lightcolor = 1;)
{
    Cl = intensity * lightcolor;
}
