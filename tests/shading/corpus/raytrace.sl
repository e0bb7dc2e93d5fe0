/* raytrace.sl: gather with an else branch, rayinfo, and the ray-traced
 * calls under the default ShadingServices (every ray misses: gather's else
 * branch runs once per sample, trace() gives 0).
 * Batch: the plane grid z = 1, N = (0, 0, -1) facing the eye. */
#include "corpus.h"

surface raytrace(
    CHECK(gather_else_runs_per_sample); CHECK(gather_directions_in_cone);
    CHECK(gather_miss_length); CHECK(gather_surface_untouched_on_miss);
    CHECK(gather_break_is_the_loop_outside);)
{
    normal Nf = faceforward(normalize(N), I);
    float hits = 0, misses = 0, worst = 0;
    float len = 0;
    vector dir = 0;
    color hitc = color(5, 5, 5);
    gather("illuminance", P, Nf, PI / 4, 8, "surface:Ci", hitc, "ray:length", len,
           "ray:direction", dir, "maxdist", 3, "distribution", "cosine") {
        hits += 1;
    } else {
        misses += 1;
        worst = max(worst, acos(clamp(normalize(dir) . normalize(Nf), -1, 1)));
    }
    check_gather_else_runs_per_sample = near(hits, 0, 0) + near(misses, 8, 0);
    check_gather_directions_in_cone = worst <= PI / 4 + 1e-4 ? 0 : worst;
    check_gather_miss_length = near(len, 3, 0);
    check_gather_surface_untouched_on_miss = cnear(hitc, color(5, 5, 5), 0);

    /* break inside gather leaves the loop around it (gather is no loop level) */
    float i, passes = 0;
    for (i = 0; i < 3; i += 1) {
        gather("", P, Nf, PI / 2, 4) {
        } else {
            passes += 1;
            break;
        }
    }
    check_gather_break_is_the_loop_outside = near(passes, 1, 0) + near(i, 0, 0);
    Ci = 0;
}
