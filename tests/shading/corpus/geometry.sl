/* geometry.sl: the geometric built-ins of RISpec 15.2 against hand-computed
 * values. Batch: the plane grid of corpus_test.cpp (z = 1, N = Ng = (0,0,-1)
 * facing the eye), camera clipping planes 1 and 11. */
#include "corpus.h"

surface geometry(
    CHECK(components); CHECK(set_components); CHECK(length_distance);
    CHECK(normalize); CHECK(normalize_zero); CHECK(ptlined); CHECK(rotate_point);
    CHECK(faceforward); CHECK(faceforward_ng); CHECK(reflect); CHECK(refract);
    CHECK(refract_tir); CHECK(fresnel); CHECK(fresnel_directions); CHECK(depth);)
{
    point p = point(1, 2, 3);
    vector vv = vector(4, 5, 6);
    normal nn = normal(7, 8, 9);
    check_components = near(xcomp(p), 1, 0) + near(ycomp(p), 2, 0) + near(zcomp(p), 3, 0)
        + near(xcomp(vv) + ycomp(nn) + zcomp(vv), 4 + 8 + 6, 0) + near(zcomp(P), 1, 0);
    setxcomp(p, 10);
    setycomp(vv, 20);
    setzcomp(nn, 30);
    setzcomp(p, u);
    check_set_components = pnear(p, point(10, 2, u), 0) + pnear(vv, vector(4, 20, 6), 0)
        + pnear(nn, normal(7, 8, 30), 0);
    check_length_distance = near(length(vector(3, 4, 12)), 13, 1e-6)
        + near(length(normal(0, 0, -2)), 2, 0)
        + near(distance(point(1, 1, 1), point(4, 5, 1)), 5, 1e-6)
        + near(length(point(0, 3, 4)), 5, 1e-6);
    check_normalize = pnear(normalize(vector(0, 3, 4)), vector(0, 0.6, 0.8), 1e-7)
        + pnear(normalize(normal(2, 0, 0)), normal(1, 0, 0), 0)
        + pnear(normalize(point(0, 0, -5)), vector(0, 0, -1), 0)
        + near(length(normalize(P)), 1, 1e-6);
    /* documented: normalize of a zero vector is 0, not NaN */
    check_normalize_zero = pnear(normalize(vector 0), vector 0, 0)
        + pnear(normalize(normal 0), normal 0, 0);
    /* ptlined(P0, P1, Q) (RISpec's order): the distance from Q to the segment,
     * perpendicular inside, to an end beyond it */
    check_ptlined = near(ptlined(point(0, 0, 0), point(1, 0, 0), point(0.5, 2, 0)), 2, 1e-6)
        + near(ptlined(point(0, 0, 0), point(1, 0, 0), point(4, 4, 0)), 5, 1e-6)
        + near(ptlined(point(0, 0, 0), point(1, 0, 0), point(-3, 0, 4)), 5, 1e-6);
    /* right-hand rule about the axis from P0 to P1 */
    check_rotate_point =
        pnear(rotate(point(1, 0, 0), PI / 2, point(0, 0, 0), point(0, 0, 1)), point(0, 1, 0), 1e-6)
        + pnear(rotate(point(2, 0, 0), PI, point(1, 0, 0), point(1, 0, 5)), point(0, 0, 0), 1e-6)
        + pnear(rotate(vector(0, 1, 0), PI / 2, point(0, 0, 0), point(1, 0, 0)), vector(0, 0, 1), 1e-6)
        + pnear(rotate(normal(0, 0, 1), u, point(0, 0, 0), point(0, 0, 1)), normal(0, 0, 1), 1e-6);
    /* faceforward(N, I, Nref): N turned so that it faces against I */
    check_faceforward =
        pnear(faceforward(vector(0, 0, 1), vector(0, 0, 1), vector(0, 0, 1)), vector(0, 0, -1), 0)
        + pnear(faceforward(vector(0, 0, 1), vector(0, 0, -1), vector(0, 0, 1)), vector(0, 0, 1), 0)
        + pnear(faceforward(normal(0, 0, 2), vector(0, 0, 1), normal(0, 0, -1)), normal(0, 0, 2), 0);
    /* without Nref, Ng = (0, 0, -1) decides: I = P has z = 1 */
    check_faceforward_ng = pnear(faceforward(normal(0, 0, 5), I), normal(0, 0, 5), 0)
        + pnear(faceforward(normal(0, 0, 5), -I), normal(0, 0, -5), 0)
        + pnear(faceforward(N, I), N, 0);
    check_reflect = pnear(reflect(vector(1, 0, -1), normal(0, 0, 1)), vector(1, 0, 1), 0)
        + pnear(reflect(vector(1, -2, 3), normal(0, 1, 0)), vector(1, 2, 3), 0);
    /* Snell at 45 degrees into glass (eta = 1/1.5): T = eta I + (eta cos - cos_t) N */
    vector i45 = normalize(vector(1, 0, -1));
    check_refract = pnear(refract(i45, normal(0, 0, 1), 1 / 1.5),
                          vector(0.4714045208, 0, -0.8819171037), 1e-6)
        + pnear(refract(vector(0, 0, -1), normal(0, 0, 1), 1.3), vector(0, 0, -1), 1e-6);
    /* from glass to air beyond the critical angle: 0 */
    check_refract_tir = pnear(refract(normalize(vector(1, 0, -0.2)), normal(0, 0, 1), 1.5), vector 0, 0);
    float kr, kt, kr0, kt0;
    fresnel(i45, normal(0, 0, 1), 1 / 1.5, kr, kt);
    fresnel(vector(0, 0, -1), normal(0, 0, 1), 1 / 1.5, kr0, kt0);
    /* (Rs + Rp) / 2 at 45 degrees, ((n1 - n2) / (n1 + n2))^2 at normal incidence */
    check_fresnel = near(kr, 0.0502399110, 1e-6) + near(kt, 1 - 0.0502399110, 1e-6)
        + near(kr0, 0.04, 1e-6) + near(kt0, 0.96, 1e-6);
    vector R, T;
    float kr2, kt2;
    fresnel(i45, normal(0, 0, 1), 1 / 1.5, kr2, kt2, R, T);
    check_fresnel_directions = near(kr2, kr, 0) + pnear(R, normalize(vector(1, 0, 1)), 1e-6)
        + pnear(T, vector(0.4714045208, 0, -0.8819171037), 1e-6);
    /* camera z mapped to 0 at the near plane (1), 1 at the far one (11) */
    check_depth = near(depth(point(0, 0, 6)), 0.5, 1e-6) + near(depth(P), 0, 1e-6)
        + near(depth(point(3, 4, 11)), 1, 1e-6);
}
