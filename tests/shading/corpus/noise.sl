/* noise.sl: noise, pnoise and cellnoise in every form: range, 0.5 at the
 * integer lattice, continuity (a Lipschitz bound between close points),
 * periodicity, cells, and decorrelated components of the triple forms.
 * Batch: a plane grid; each point samples a stretch of noise along a line
 * through its own (u, v). */
#include "corpus.h"

surface noise(
    CHECK(range_1d); CHECK(range_2d); CHECK(range_3d); CHECK(range_4d);
    CHECK(lattice_half); CHECK(continuity); CHECK(not_constant);
    CHECK(triple_forms); CHECK(triple_components_differ); CHECK(vector_normal_args);
    CHECK(pnoise_period); CHECK(pnoise_forms); CHECK(cellnoise_cells);
    CHECK(cellnoise_forms);)
{
    float k, lo = 1, hi = 0, lo2 = 1, hi2 = 0, lo3 = 1, hi3 = 0, lo4 = 1, hi4 = 0;
    float jump = 0, spread = 0, lattice = 0;
    point base = point(u * 13.7, v * 7.3, u * v * 3.1);
    for (k = 0; k < 64; k += 1) {
        float x = u * 40 + k * 0.37 - 20;
        float n1 = noise(x);
        float n2 = noise(x, v * 9 - k * 0.21);
        float n3 = noise(base + vector(k * 0.31, -k * 0.17, k * 0.11));
        float n4 = noise(base * 2 - k * 0.13, x);
        lo = min(lo, n1); hi = max(hi, n1);
        lo2 = min(lo2, n2); hi2 = max(hi2, n2);
        lo3 = min(lo3, n3); hi3 = max(hi3, n3);
        lo4 = min(lo4, n4); hi4 = max(hi4, n4);
        /* Lipschitz: a step of 1e-3 moves noise by far less than 0.01 */
        jump = max(jump, abs(noise(x + 1e-3) - n1),
                   abs(noise(base + vector(k * 0.31 + 1e-3, -k * 0.17, k * 0.11)) - n3));
        spread = max(spread, abs(n1 - noise(x + 0.5)));
        lattice = max(lattice, abs(noise(k - 32) - 0.5), abs(noise(k, -k) - 0.5),
                       abs(noise(point(k, k - 3, 5 - k)) - 0.5),
                       abs(noise(point(k, 1, 2), k) - 0.5));
    }
    check_range_1d = TRUTH(lo >= 0 && hi <= 1);
    check_range_2d = TRUTH(lo2 >= 0 && hi2 <= 1);
    check_range_3d = TRUTH(lo3 >= 0 && hi3 <= 1);
    check_range_4d = TRUTH(lo4 >= 0 && hi4 <= 1);
    check_lattice_half = near(lattice, 0, 1e-6);
    check_continuity = near(jump, 0, 0.01);
    check_not_constant = TRUTH(spread > 0.01 && hi - lo > 0.1);

    color nc = noise(base);
    vector nv = noise(base);
    point np = noise(u * 7);
    color nc2 = noise(u * 7, v * 3);
    vector nv4 = noise(base, 2.5);
    check_triple_forms =
        TRUTH(comp(nc, 0) >= 0 && comp(nc, 1) <= 1 && xcomp(nv) >= 0 && zcomp(np) <= 1
              && comp(nc2, 2) >= 0 && ycomp(nv4) <= 1)
        + cnear(color noise(point(1, 2, 3)), color 0.5, 1e-6);
    check_triple_components_differ =
        TRUTH(comp(nc, 0) != comp(nc, 1) && comp(nc, 1) != comp(nc, 2)
              && xcomp(nv) != ycomp(nv));
    /* vector and normal arguments are taken as points */
    check_vector_normal_args = near(noise(vector(base)), noise(base), 0)
        + near(noise(normal(base)), noise(base), 0)
        + cnear(color noise(vector(base)), nc, 0)
        + pnear(vector noise(normal(base)), nv, 0);

    /* pnoise repeats with the (integer) period */
    float px = u * 10 - 3, py = v * 6;
    point pq = point(u * 5, v * 5, 1.3);
    check_pnoise_period = near(pnoise(px + 4, 4), pnoise(px, 4), 1e-5)
        + near(pnoise(px + 3, py - 5, 3, 5), pnoise(px, py, 3, 5), 1e-5)
        + near(pnoise(pq + vector(2, 3, 4), point(2, 3, 4)), pnoise(pq, point(2, 3, 4)), 1e-5)
        + near(pnoise(pq + vector(2, 0, 0), 1.5 + 6, point(2, 3, 4), 6),
               pnoise(pq, 1.5, point(2, 3, 4), 6), 1e-5);
    color pc = pnoise(px, 4);
    color pc2 = pnoise(px, py, 3, 5);
    point pp = pnoise(pq, point(2, 3, 4));
    vector pv = pnoise(pq, 1.5, point(2, 3, 4), 6);
    check_pnoise_forms = cnear(color pnoise(px + 4, 4), pc, 1e-5)
        + cnear(color pnoise(px, py + 5, 3, 5), pc2, 1e-5)
        + pnear(point pnoise(pq + vector(0, 3, 0), point(2, 3, 4)), pp, 1e-5)
        + pnear(vector pnoise(pq, 7.5, point(2, 3, 4), 6), pv, 1e-5)
        + TRUTH(pnoise(px, 4) >= 0 && pnoise(px, 4) <= 1 && comp(pc, 0) != comp(pc, 1));

    /* cellnoise: constant on each integer cell, in [0, 1) */
    float cx = floor(u * 8) + 0.1;
    check_cellnoise_cells = near(cellnoise(cx), cellnoise(cx + 0.8), 0)
        + near(cellnoise(cx, 2.2), cellnoise(cx + 0.5, 2.9), 0)
        + near(cellnoise(point(cx, 1.5, -0.5)), cellnoise(point(cx + 0.3, 1.1, -0.9)), 0)
        + near(cellnoise(point(cx, 1.5, 2.5), 3.5), cellnoise(point(cx, 1.2, 2.2), 3.2), 0)
        + TRUTH(cellnoise(cx) >= 0 && cellnoise(cx) < 1 && cellnoise(cx) != cellnoise(cx + 1));
    color cc = cellnoise(cx);
    vector cv = cellnoise(cx, 2.2);
    point cp = cellnoise(point(cx, 1.5, -0.5));
    color cc4 = cellnoise(point(cx, 1.5, 2.5), 3.5);
    check_cellnoise_forms = cnear(color cellnoise(cx + 0.5), cc, 0)
        + pnear(vector cellnoise(cx + 0.5, 2.7), cv, 0)
        + pnear(point cellnoise(point(cx + 0.5, 1.7, -0.7)), cp, 0)
        + cnear(color cellnoise(point(cx + 0.5, 1.7, 2.7), 3.7), cc4, 0)
        + TRUTH(comp(cc, 0) != comp(cc, 1) && comp(cc, 0) >= 0 && comp(cc, 2) < 1);
}
