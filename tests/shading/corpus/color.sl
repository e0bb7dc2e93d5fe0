/* color.sl: colour components, colour spaces (casts and ctransform), mix and
 * comparisons. Batch: a plane grid. */
#include "corpus.h"

surface colors(
    CHECK(comp); CHECK(setcomp); CHECK(cast_spaces); CHECK(ctransform_to);
    CHECK(ctransform_from_to); CHECK(round_trips); CHECK(mix); CHECK(comparisons);)
{
    color c = color(0.1, 0.2, 0.3);
    check_comp = near(comp(c, 0), 0.1, 1e-7) + near(comp(c, 1), 0.2, 1e-7)
        + near(comp(c, 2), 0.3, 1e-7) + near(comp(color(u, 0, 0), 0), u, 0);
    setcomp(c, 1, 0.9);
    setcomp(c, 2, u);
    check_setcomp = cnear(c, color(0.1, 0.9, u), 1e-7);
    /* casts read the triple in the space and give rgb */
    check_cast_spaces = cnear(color "hsv" (0, 1, 1), color(1, 0, 0), 1e-6)
        + cnear(color "hsv" (2.0 / 3, 0.5, 1), color(0.5, 0.5, 1), 1e-6)
        + cnear(color "hsl" (1.0 / 3, 1, 0.25), color(0, 0.5, 0), 1e-6)
        + cnear(color "hsl" (0, 0, 0.7), color(0.7, 0.7, 0.7), 1e-6)
        + cnear(color "YIQ" (1, 0, 0), color(1, 1, 1), 1e-3)
        + cnear(color "XYZ" (0.9505, 1, 1.089), color(1, 1, 1), 2e-3)
        + cnear(color "xyz" (0.4124, 0.2126, 0.0193), color(1, 0, 0), 2e-3);
    check_ctransform_to = cnear(ctransform("hsv", color(1, 0, 0)), color(0, 1, 1), 1e-6)
        + cnear(ctransform("hsv", color(0, 0.5, 0)), color(1.0 / 3, 1, 0.5), 1e-6)
        + cnear(ctransform("hsl", color(0, 0.5, 0)), color(1.0 / 3, 1, 0.25), 1e-6)
        /* luminance (Y) of rec. 709 red and the YIQ luma of red */
        + near(comp(ctransform("xyz", color(1, 0, 0)), 1), 0.2126, 1e-3)
        + near(comp(ctransform("yiq", color(1, 0, 0)), 0), 0.299, 1e-3)
        + cnear(ctransform("rgb", color(0.1, 0.2, 0.3)), color(0.1, 0.2, 0.3), 0);
    check_ctransform_from_to = cnear(ctransform("hsv", "rgb", color(0, 1, 1)), color(1, 0, 0), 1e-6)
        + cnear(ctransform("hsv", "hsl", color(0, 1, 1)), color(0, 1, 0.5), 1e-6)
        + cnear(ctransform("rgb", "hsv", color(0, 0, 1)), color(2.0 / 3, 1, 1), 1e-6);
    color x = color(u, 0.3, 1 - u);
    check_round_trips = cnear(ctransform("hsv", "rgb", ctransform("hsv", x)), x, 1e-5)
        + cnear(ctransform("hsl", "rgb", ctransform("hsl", x)), x, 1e-5)
        + cnear(ctransform("xyz", "rgb", ctransform("xyz", x)), x, 1e-4)
        + cnear(ctransform("YIQ", "rgb", ctransform("YIQ", x)), x, 1e-4);
    check_mix = cnear(mix(color(1, 0, 0), color(0, 0, 1), 0.25), color(0.75, 0, 0.25), 1e-6)
        + cnear(mix(color 0, color 1, color(0, 0.5, 1)), color(0, 0.5, 1), 1e-6);
    check_comparisons = TRUTH(color(1, 2, 3) == color(1, 2, 3))
        + TRUTH(color(1, 2, 3) != color(1, 2, 3.5)) + TRUTH(!(color 1 != color(1, 1, 1)));
}
