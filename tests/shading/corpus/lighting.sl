/* lighting.sl: light shaders (illuminate with and without a cone, solar with
 * and without an axis, an ambient light, categories, __nondiffuse) and the
 * surface side: illuminance with and without category / axis / angle,
 * ambient, diffuse, specular, specularbrdf, phong, and the ray-traced calls
 * without occluders (the default services: every ray misses). Each light checks its own side (L = Ps - from, E) and
 * gives Cl = 0 when that fails, which the surface's checks then see.
 *
 * corpus_test.cpp binds, with camera = world = shader space:
 *   key:  keylight at the eye (0, 0, 0), intensity 2, __category "key"
 *   fill: filllight, solar along (0, 0, 1), intensity 0.5, __category "fill"
 *   amb:  amblight, intensity 0.25
 *   spot: spotlight at the eye towards +z, cone 20 degrees, intensity 1
 *   sky:  skylight, solar() everywhere, intensity 0.1, __nondiffuse 1,
 *         __nonspecular 1, __category "sky"
 * Batch: the plane grid z = 1, N = (0, 0, -1) facing the eye. */
#include "corpus.h"

light keylight(float intensity = 1; point from = point "shader" (0, 0, 0);
               string __category = "key";)
{
    illuminate(from) {
        /* in a light, L goes from the light to the surface point Ps */
        float ok = abs(length(L - (Ps - from))) < 1e-5 && length(E) == 0 ? 1 : 0;
        Cl = ok * intensity / (L . L);
    }
}

light filllight(float intensity = 1; vector dir = vector(0, 0, 1);
                string __category = "fill";)
{
    solar(dir, 0) {
        float ok = length(L - dir) < 1e-6 ? 1 : 0;
        Cl = ok * intensity;
    }
}

light amblight(float intensity = 1;) { Cl = intensity; }

light spotlight(float intensity = 1; point from = point "shader" (0, 0, 0);
                point to = point "shader" (0, 0, 1); float coneangle = radians(20);
                string __category = "spot";)
{
    uniform vector A = normalize(to - from);
    illuminate(from, A, coneangle) {
        Cl = intensity / length(L);
    }
}

light skylight(float intensity = 1; float __nondiffuse = 1; float __nonspecular = 1;
               string __category = "sky";)
{
    solar() { Cl = intensity; }
}

surface lighting(
    CHECK(ambient); CHECK(diffuse); CHECK(illuminance_all); CHECK(illuminance_category);
    CHECK(illuminance_excluded); CHECK(illuminance_axis_angle); CHECK(illuminance_hemisphere);
    CHECK(specular_vs_brdf); CHECK(specular_closed_form); CHECK(phong);
    CHECK(lightsource); CHECK(illuminance_light_option); CHECK(raytraced_without_occluders);
    CHECK(empty_shadow_map_name); CHECK(trace_all_miss);
    float rough = 0.2; float size = 10;)
{
    normal Nf = faceforward(normalize(N), I);
    vector V = -normalize(I);
    float d = length(P);
    float cosang = 1 / d; /* P.z = 1: the angle to the +z axis */
    float inspot = cosang >= cos(radians(20)) ? 1 : 0;

    check_ambient = cnear(ambient(), color 0.25, 1e-6);

    /* N.L = 1/d: key 2/d^2 * 1/d; fill 0.5; spot 1/d * 1/d inside its cone;
     * sky is __nondiffuse; the ambient light is not in diffuse() */
    check_diffuse = cnear(diffuse(Nf), color(2 / (d * d * d) + 0.5 + inspot / (d * d)), 1e-5);

    /* no category, no axis: every non-ambient light that lit the point */
    float count = 0;
    color sumcl = 0;
    illuminance(P) {
        count += 1;
        sumcl += Cl;
    }
    check_illuminance_all = near(count, 3 + inspot, 0)
        + cnear(sumcl, color(2 / (d * d) + 0.5 + inspot / d + 0.1), 1e-5);

    /* one category: L points from the surface towards the light */
    float nkey = 0;
    vector lkey = 0;
    color clkey = 0;
    illuminance("key", P) {
        nkey += 1;
        lkey = L;
        clkey = Cl;
    }
    check_illuminance_category = near(nkey, 1, 0) + pnear(lkey, -P, 1e-5)
        + cnear(clkey, color(2 / (d * d)), 1e-5);

    /* a leading '-' excludes; a list requires any of its names */
    float nrest = 0, nlist = 0;
    illuminance("-sky", P) { nrest += 1; }
    illuminance("fill,spot", P) { nlist += 1; }
    check_illuminance_excluded = near(nrest, 2 + inspot, 0) + near(nlist, 1 + inspot, 0);

    /* within 10 degrees of -z (towards the eye): fill always, key and spot
     * when the point is within 10 degrees of the view axis */
    float naxis = 0;
    float near10 = cosang >= cos(radians(10)) ? 1 : 0;
    illuminance("-sky", P, vector(0, 0, -1), radians(10)) { naxis += 1; }
    check_illuminance_axis_angle = near(naxis, 1 + near10 + near10 * inspot, 0);

    /* the hemisphere around Nf: every light is in front here; around -Nf none */
    float nfront = 0, nback = 0;
    illuminance("-sky", P, Nf, PI / 2) { nfront += 1; }
    illuminance("-sky", P, -Nf, PI / 2 - 0.01) { nback += 1; }
    check_illuminance_hemisphere = near(nfront, 2 + inspot, 0) + near(nback, 0, 0);

    /* specular() is the sum of Cl * specularbrdf over the lights in the
     * hemisphere, __nonspecular lights skipped */
    color brdfsum = 0;
    illuminance("-sky", P, Nf, PI / 2) {
        brdfsum += Cl * specularbrdf(normalize(L), Nf, V, rough);
    }
    color spec = specular(Nf, V, rough);
    check_specular_vs_brdf = cnear(spec, brdfsum, 1e-5);
    /* closed form: H = normalize(L + V), (N.H)^(1/roughness); for the key
     * light L = V, so N.H = N.V = 1/d */
    check_specular_closed_form =
        near(comp(specularbrdf(V, Nf, V, rough), 0), pow(cosang, 1 / rough), 1e-5)
        + near(comp(specularbrdf(vector(0, 0, -1), normal(0, 0, -1), vector(0, 0, -1), 0.5), 1), 1, 1e-6);
    /* phong: R = reflect(-V, N); sum of Cl * max(0, R.L)^size */
    vector R = reflect(-V, Nf);
    color phongsum = 0;
    illuminance("-sky", P, Nf, PI / 2) {
        phongsum += Cl * pow(max(0, R . normalize(L)), size);
    }
    check_phong = cnear(phong(Nf, V, size), phongsum, 1e-5);

    /* message passing: lightsource() inside illuminance reads the current
       light's parameter (the key light's intensity 2); outside, or for a
       parameter the light does not have, 0 and the variable untouched */
    float got = -3, ret = 7, none = -4, ret_none = 7;
    illuminance("key", P) {
        ret = lightsource("intensity", got);
        ret_none = lightsource("nosuch", none);
    }
    float outside = -5;
    float ret_outside = lightsource("intensity", outside);
    check_lightsource = near(ret, 1, 0) + near(got, 2, 0) + near(ret_none, 0, 0)
        + near(none, -4, 0) + near(ret_outside, 0, 0) + near(outside, -5, 0);
    /* illuminance's "light:NAME" option receives it each iteration */
    float recv = -1;
    illuminance("key", P, "light:intensity", recv, "lightcache", "reuse") { }
    check_illuminance_light_option = near(recv, 2, 0);

    /* no occluders bound: nothing is shadowed or occluded */
    check_raytraced_without_occluders = near(shadow("raytrace", P), 0, 0)
        + cnear(color shadow("raytrace", P), color 0, 0)
        + cnear(transmission(P, point(0, 0, 0)), color 1, 0)
        + near(occlusion(P, Nf, 16), 0, 0)
        + near(occlusion(P, Nf, 16, "maxdist", 10, "coneangle", PI / 4), 0, 0);
    /* an empty map name is 0, quietly (depth maps: tests/binding) */
    check_empty_shadow_map_name = near(shadow("", P), 0, 0)
        + cnear(color shadow(""[0], P, "bias", 0.1), color 0, 0);
    /* the default ShadingServices::trace misses every ray: trace() and
       indirectdiffuse() (no environment map) give 0, and
       environment("raytrace") too */
    check_trace_all_miss = cnear(trace(P, reflect(I, Nf)), color 0, 0)
        + cnear(indirectdiffuse(P, Nf, 16), color 0, 0)
        + cnear(color environment("raytrace", reflect(I, Nf)), color 0, 0);
}
