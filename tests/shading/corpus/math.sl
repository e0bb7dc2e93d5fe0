/* math.sl: the math built-ins of RISpec 15.1 against closed forms, every
 * overload (float, color, point/vector/normal). Batch: a plane grid. */
#include "corpus.h"

surface math(
    CHECK(radians_degrees); CHECK(trig); CHECK(inverse_trig); CHECK(atan2);
    CHECK(pow_exp_log); CHECK(pow_colour); CHECK(sqrt_inversesqrt); CHECK(mod);
    CHECK(abs); CHECK(sign); CHECK(floor_ceil_round); CHECK(floor_ceil_round_triples);
    CHECK(min_max); CHECK(min_max_triples); CHECK(clamp); CHECK(mix); CHECK(step);
    CHECK(smoothstep); CHECK(erf); CHECK(spline_catmull_rom); CHECK(spline_many_knots);
    CHECK(spline_bases); CHECK(spline_triples); CHECK(spline_arrays);
    CHECK(random_range); CHECK(random_triples);)
{
    check_radians_degrees = near(radians(180), PI, 1e-6) + near(degrees(PI / 2), 90, 1e-4);
    check_trig = near(sin(PI / 6), 0.5, 1e-6) + near(cos(PI / 3), 0.5, 1e-6)
        + near(tan(PI / 4), 1, 1e-6) + near(sin(u) * sin(u) + cos(u) * cos(u), 1, 1e-6);
    check_inverse_trig = near(asin(1), PI / 2, 1e-6) + near(acos(-1), PI, 1e-6)
        + near(acos(0.5), PI / 3, 1e-6) + near(atan(1), PI / 4, 1e-6)
        + near(asin(sin(u)), u, 1e-6);
    check_atan2 = near(atan(1, -1), 3 * PI / 4, 1e-6) + near(atan(-1, -1), -3 * PI / 4, 1e-6)
        + near(atan(0, 1), 0, 0) + near(atan(1, 0), PI / 2, 1e-6);
    check_pow_exp_log = near(pow(2, 10), 1024, 0) + near(pow(9, 0.5), 3, 1e-6)
        + near(exp(1), 2.718281828, 1e-6) + near(log(exp(2.5)), 2.5, 1e-6)
        + near(log(8, 2), 3, 1e-6) + near(log(1000, 10), 3, 1e-5);
    check_pow_colour = cnear(pow(color(1, 2, 3), 2), color(1, 4, 9), 1e-6);
    check_sqrt_inversesqrt = near(sqrt(16), 4, 0) + near(inversesqrt(4), 0.5, 1e-7)
        + near(sqrt(u) * sqrt(u), u, 1e-6);
    /* mod is in [0, b): a - b * floor(a / b) */
    check_mod = near(mod(7, 3), 1, 0) + near(mod(-1, 3), 2, 0) + near(mod(-7, 3), 2, 0)
        + near(mod(5.5, 2), 1.5, 0) + near(mod(6, 3), 0, 0);
    check_abs = near(abs(-2), 2, 0) + cnear(abs(color(-1, 2, -3)), color(1, 2, 3), 0)
        + pnear(abs(vector(-1, -2, 3)), vector(1, 2, 3), 0)
        + pnear(abs(point(-4, 0, -5)), point(4, 0, 5), 0);
    check_sign = near(sign(-3), -1, 0) + near(sign(0), 0, 0) + near(sign(2), 1, 0);
    check_floor_ceil_round = near(floor(-1.5), -2, 0) + near(ceil(-1.5), -1, 0)
        + near(floor(2.7), 2, 0) + near(ceil(2.2), 3, 0) + near(round(2.4), 2, 0)
        + near(round(2.6), 3, 0) + near(round(-2.6), -3, 0)
        /* halves away from zero */
        + near(round(2.5), 3, 0) + near(round(-2.5), -3, 0);
    check_floor_ceil_round_triples =
        cnear(floor(color(1.5, -1.5, 2)), color(1, -2, 2), 0)
        + cnear(ceil(color(1.5, -1.5, 2)), color(2, -1, 2), 0)
        + cnear(round(color(1.4, -1.6, 2)), color(1, -2, 2), 0)
        + pnear(floor(point(1.5, -1.5, 2)), point(1, -2, 2), 0)
        + pnear(ceil(vector(1.5, -1.5, 2)), vector(2, -1, 2), 0)
        + pnear(round(normal(1.4, -1.6, 2)), normal(1, -2, 2), 0);
    check_min_max = near(min(3, 1, 2), 1, 0) + near(max(3, 1, 7), 7, 0)
        + near(min(2, u), u, 0) + near(max(u, -1), u, 0) + near(min(4, 5, 6, 3, 9), 3, 0);
    check_min_max_triples = cnear(min(color(1, 5, 3), color(2, 4, 6)), color(1, 4, 3), 0)
        + cnear(max(color(1, 5, 3), color(2, 4, 6), color(0, 0, 7)), color(2, 5, 7), 0)
        + pnear(min(point(1, 5, 3), point(2, 4, 6)), point(1, 4, 3), 0)
        + pnear(max(vector(1, 5, 3), vector(2, 4, 6)), vector(2, 5, 6), 0);
    check_clamp = near(clamp(5, 0, 3), 3, 0) + near(clamp(-1, 0, 3), 0, 0)
        + near(clamp(u, 0, 1), u, 0)
        + cnear(clamp(color(-1, 0.5, 2), color(0, 0, 0), color(1, 1, 1)), color(0, 0.5, 1), 0)
        + pnear(clamp(point(-1, 0.5, 2), point(0, 0, 0), point(1, 1, 1)), point(0, 0.5, 1), 0);
    check_mix = near(mix(2, 4, 0.25), 2.5, 0)
        + cnear(mix(color(0, 0, 0), color(4, 8, 12), 0.25), color(1, 2, 3), 1e-6)
        + pnear(mix(point(0, 0, 0), point(4, 8, 12), 0.5), point(2, 4, 6), 1e-6)
        + cnear(mix(color(0, 0, 0), color(4, 4, 4), color(0, 0.5, 1)), color(0, 2, 4), 1e-6);
    check_step = near(step(1, 0.5), 0, 0) + near(step(1, 1), 1, 0) + near(step(1, 2), 1, 0);
    /* 3t^2 - 2t^3 at t = 0.25 */
    check_smoothstep = near(smoothstep(0, 2, 0.5), 0.15625, 1e-7)
        + near(smoothstep(0, 2, -1), 0, 0) + near(smoothstep(0, 2, 3), 1, 0)
        + near(smoothstep(0, 1, u), u * u * (3 - 2 * u), 1e-6);
    check_erf = near(erf(0.5), 0.5204998778, 1e-6) + near(erfc(0.5), 0.4795001222, 1e-6)
        + near(erf(0), 0, 0) + near(erf(u) + erfc(u), 1, 1e-6);
    /* catmull-rom through v1, v2 between t = 0 and 1 */
    check_spline_catmull_rom = near(spline(0.5, 0, 0, 1, 1), 0.5, 1e-6)
        + near(spline(0, 5, 1, 2, 9), 1, 1e-6) + near(spline(1, 5, 1, 2, 9), 2, 1e-6)
        + near(spline(0.25, 0, 1, 2, 3), 1.25, 1e-6)
        + near(spline("catmull-rom", 0.25, 0, 1, 2, 3), 1.25, 1e-6);
    /* 8 knots on a line: 5 segments; t = 0.5 is halfway through the third */
    check_spline_many_knots = near(spline(0.5, 0, 1, 2, 3, 4, 5, 6, 7), 3.5, 1e-5)
        + near(spline(u, 0, 1, 2, 3, 4, 5, 6, 7), 1 + 5 * u, 1e-5);
    check_spline_bases = near(spline("linear", 0.25, 0, 1, 3, 9), 1.5, 1e-6)
        /* bezier: 3(1-t)^2 t + 3(1-t) t^2 at t = 0.5 */
        + near(spline("bezier", 0.5, 0, 1, 1, 0), 0.75, 1e-6)
        /* uniform b-spline at t = 0: (v0 + 4 v1 + v2) / 6 */
        + near(spline("bspline", 0, 0, 6, 0, 0), 4, 1e-6)
        + near(spline("b-spline", 1, 0, 6, 0, 0), 1, 1e-6)
        /* hermite (P0, T0, P1, T1) at 0.5: P0/2 + T0/8 + P1/2 - T1/8 */
        + near(spline("hermite", 0.5, 0, 4, 1, 0), 1, 1e-6)
        /* power: v0 t^3 + v1 t^2 + v2 t + v3 */
        + near(spline("power", 0.5, 8, 4, 2, 1), 1 + 1 + 1 + 1, 1e-6);
    check_spline_triples =
        cnear(spline(0.25, color(0, 0, 0), color(1, 2, 3), color(2, 4, 6), color(3, 6, 9)),
              color(1.25, 2.5, 3.75), 1e-5)
        + pnear(spline(0.5, point(0, 0, 0), point(0, 0, 0), point(2, 2, 2), point(2, 2, 2)),
                point(1, 1, 1), 1e-5)
        + pnear(spline("linear", 0.5, vector(0, 0, 0), vector(0, 0, 0), vector(2, 4, 6),
                       vector(0, 0, 0)), vector(1, 2, 3), 1e-5)
        + cnear(spline("bezier", 0.5, color 0, color 1, color 1, color 0), color 0.75, 1e-6);
    float fa[4] = {0, 1, 2, 3};
    color ca[4] = {color 0, color 1, color 2, color 3};
    point pa[4] = {point 0, point 1, point 2, point 3};
    check_spline_arrays = near(spline(0.25, fa), 1.25, 1e-6)
        + near(spline("linear", 0.75, fa), 1.75, 1e-6)
        + cnear(spline(0.5, ca), color 1.5, 1e-6) + pnear(spline(0.5, pa), point 1.5, 1e-6)
        + cnear(spline("catmull-rom", 0.5, ca), color 1.5, 1e-6)
        + pnear(spline("bspline", 0.5, pa), point 1.5, 1e-6);
    float r1 = random(), r2 = random();
    check_random_range = TRUTH(r1 >= 0 && r1 < 1 && r2 >= 0 && r2 < 1 && r1 != r2);
    color rc = random();
    point rp = random();
    check_random_triples = TRUTH(comp(rc, 0) >= 0 && comp(rc, 2) < 1 && comp(rc, 0) != comp(rc, 1)
                                 && xcomp(rp) >= 0 && zcomp(rp) < 1 && xcomp(rp) != ycomp(rp));
}
