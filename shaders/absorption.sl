// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* absorption: translucency without scattering, the absorption-only shader
 * of PRMan's subsurface scattering application note. Rays gathered into the
 * object (a cosine-weighted hemisphere about the inward normal) find where
 * they leave it; the light that arrives there (the baked _radiance_t,
 * looked up with texture3d in a brick map or point cloud) is attenuated by
 * exp(-absorption * distance) on the way through (absorption in 1/scene
 * unit, per colour channel). Plus ambient and direct diffuse light on the
 * surface. Only camera-ray hits gather: at ray hits (rayinfo depth > 0) the
 * shader gives its surface terms only, so the rays do not multiply. */
surface absorption(string filename = "";
                   string channel = "_radiance_t";
                   color absorption = color(0.6, 1.1, 2.0);
                   float samples = 16;
                   float Ka = 1, Kd = 0.1, Kt = 1;
                   output varying color _ambient = 0, _diffuse = 0, _sss = 0;)
{
    normal Nn = normalize(N);
    normal Nf = faceforward(Nn, I);
    float depth = 0;
    rayinfo("depth", depth);
    color through = 0;
    if (depth == 0 && filename != "") {
        point Phit = 0;
        normal Nhit = 0;
        float dist = 0;
        gather("illuminance", P, -Nf, PI / 2, samples, "distribution", "cosine",
               "surface:P", Phit, "surface:N", Nhit, "ray:length", dist) {
            color rad = 0;
            texture3d(filename, Phit, Nhit, channel, rad);
            through += max(rad, color 0) * color(exp(-comp(absorption, 0) * dist),
                                                 exp(-comp(absorption, 1) * dist),
                                                 exp(-comp(absorption, 2) * dist));
        }
        through /= max(samples, 1);
    }
    _ambient = Os * Cs * Ka * ambient();
    _diffuse = Os * Cs * Kd * diffuse(Nf);
    _sss = Os * Cs * Kt * through;
    Oi = Os;
    Ci = _ambient + _diffuse + _sss;
}
