/*
 * subsurf_noscatter: translucency without scattering, the absorption-only
 * shader of the subsurface scattering application note. Light goes
 * straight through the object and is only absorbed on the way.
 *
 * The camera sees a point: the shader gathers rays into the object (a
 * cosine-weighted hemisphere about the inward normal), labelled "subsurf".
 * Each ray hits the object again from inside, where it leaves it; there
 * the same shader runs for the hit, sees the label and returns the direct
 * light baked at that exit point (_radiance_t of bake_radiance_t, read with
 * texture3d from the point cloud or its brick map). The light is
 * attenuated by exp(-extcoeff * distance) on its way through, per colour
 * channel (extcoeff in 1 / scene unit).
 *
 * Rays that find no exit (an open object) count in the _missed output.
 */
surface
subsurf_noscatter(string filename = "";
                  color extcoeff = color(1.2, 2.2, 4);
                  float samples = 16;
                  float Ka = 1, Kd = 0.1, Kt = 1;
                  output varying color _ambient = 0;
                  output varying color _diffuse = 0;
                  output varying color _sss = 0;
                  output varying float _missed = 0)
{
    normal Nn = normalize(N);
    uniform string raylabel = "";
    rayinfo("label", raylabel);

    if (raylabel == "subsurf") {
        /* Hit by one of our rays from inside: the baked light here. */
        color rad_t = 0;
        if (filename != "")
            texture3d(filename, P, Nn, "_radiance_t", rad_t);
        Ci = max(rad_t, color 0);
        Oi = 1;
    } else {
        normal Nf = faceforward(Nn, I);
        color sum = 0, rad = 0;
        float dist = 0, missed = 0;
        gather("illuminance", P, -Nf, PI / 2, samples,
               "distribution", "cosine", "label", "subsurf",
               "surface:Ci", rad, "ray:length", dist) {
            sum += rad * color(exp(-comp(extcoeff, 0) * dist),
                               exp(-comp(extcoeff, 1) * dist),
                               exp(-comp(extcoeff, 2) * dist));
        } else {
            missed += 1;
        }
        _missed = missed / max(samples, 1);

        _ambient = Os * Cs * Ka * ambient();
        _diffuse = Os * Cs * Kd * diffuse(Nf);
        _sss = Os * Cs * Kt * sum / max(samples, 1);
        Oi = Os;
        Ci = _ambient + _diffuse + _sss;
    }
}
