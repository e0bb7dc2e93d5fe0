/* derivatives.sl: Du, Dv, Deriv (every overload), area, calculatenormal and
 * filterstep on grids, against closed forms.
 *  - derivatives: a plane grid (P = (u - 0.5, v - 0.5, 1), s = u, t = v);
 *    centred differences inside and second-order one-sided differences at
 *    the edges are exact for quadratics.
 *  - sphere_area: a sphere of radius 1.5 as a 128 x 128 grid; corpus_test.cpp
 *    sums value_area against 4 pi r^2.
 *  - bumpy: a displacement of that sphere along a meridian profile
 *    R(phi) = r + a sin(2 phi), whose normal is known in closed form:
 *    normalize(R e_r - R' e_phi). */
#include "corpus.h"

surface derivatives(
    CHECK(du_dv_float); CHECK(du_dv_colour); CHECK(du_dv_point); CHECK(du_dv_vector);
    CHECK(deriv_float); CHECK(deriv_colour); CHECK(deriv_vector); CHECK(area_plane);
    CHECK(area_kinds); CHECK(calculatenormal_plane); CHECK(filterstep);
    CHECK(filterstep_width); CHECK(filterstep_interval);
    uniform float nu = 16; uniform float nv = 8;)
{
    check_du_dv_float = near(Du(s), 1, 1e-4) + near(Dv(s), 0, 1e-4)
        + near(Dv(t * t), 2 * t, 1e-4) + near(Du(u * u + 3 * v), 2 * u, 1e-4)
        + near(Du(5), 0, 0);
    check_du_dv_colour = cnear(Du(color(u * u, 2 * u, v)), color(2 * u, 2, 0), 1e-4)
        + cnear(Dv(color(u * v, 1, v * v)), color(u, 0, 2 * v), 1e-4);
    /* Du(P) is in units of u: the grid spans 1 in u, so (1, 0, 0) */
    check_du_dv_point = pnear(Du(P), vector(1, 0, 0), 1e-4) + pnear(Dv(P), vector(0, 1, 0), 1e-4)
        + pnear(Du(point(u * u, 0, v)), vector(2 * u, 0, 0), 1e-4);
    check_du_dv_vector = pnear(Du(vector(u, u * v, 0)), vector(1, v, 0), 1e-4)
        + pnear(Dv(normal(0, u * v, v * v)), vector(0, u, 2 * v), 1e-4);
    /* Deriv(num, den) = d num / d den: exact for num quadratic in den = u */
    check_deriv_float = near(Deriv(u * u, u), 2 * u, 1e-4) + near(Deriv(t * t, t), 2 * t, 1e-4)
        + near(Deriv(s * s * s, s), 3 * s * s, 0.01);
    check_deriv_colour = cnear(Deriv(color(u * u, u, 1), u), color(2 * u, 1, 0), 1e-4);
    check_deriv_vector = pnear(Deriv(vector(u * u, 0, 3 * u), u), vector(2 * u, 0, 3), 1e-4)
        + pnear(Deriv(P, u), vector(1, 0, 0), 1e-4);
    /* one micropolygon: du * dv of a unit square */
    check_area_plane = near(area(P), du * dv, 1e-6) + near(area(P), 1 / (nu * nv), 1e-6);
    /* "shading" is area(P); "dicing" without the dicer's areas too */
    check_area_kinds = near(area(P, "shading"), area(P), 0) + near(area(P, "dicing"), area(P), 0);
    /* Du(P) ^ Dv(P), normalised: x ^ y = z on the plane; with z = 1 - u^2
     * (N is -z), (1, 0, -2u) ^ (0, 1, 0) = (2u, 0, 1) */
    check_calculatenormal_plane = pnear(calculatenormal(P), normal(0, 0, 1), 1e-5)
        + pnear(calculatenormal(P + N * u * u), normalize(normal(2 * u, 0, 1)), 1e-4);
    /* the step box-filtered over s +- half the width |Du(s) du| + |Dv(s) dv| = 1/nu */
    float w = 1 / nu;
    check_filterstep = near(filterstep(0.5, s), clamp((s + w / 2 - 0.5) / w, 0, 1), 1e-5)
        + near(filterstep(0.3, s), clamp((s + w / 2 - 0.3) / w, 0, 1), 1e-5);
    check_filterstep_width =
        near(filterstep(0.5, s, "width", 4), clamp((s + 2 * w - 0.5) / (4 * w), 0, 1), 1e-5);
    /* the two-value form filters over [s1, s2] */
    check_filterstep_interval = near(filterstep(0.5, 0.25, 1.25), 0.75, 1e-6)
        + near(filterstep(0.5, s - 0.1, s + 0.1), clamp((s + 0.1 - 0.5) / 0.2, 0, 1), 1e-5)
        + near(filterstep(0.5, 0, 1, "width", 1), 0.5, 1e-6);
}

surface sphere_area(VALUE(area); CHECK(area_positive);) {
    value_area = area(P);
    check_area_positive = TRUTH(value_area > 0);
}

displacement bumpy(
    CHECK(normal_closed_form); CHECK(normal_unit); CHECK(radius);
    float r = 1.5; float a = 0.1;)
{
    float theta = 2 * PI * u, phi = -PI / 2 + PI * v;
    float R = r + a * sin(2 * phi), dR = 2 * a * cos(2 * phi);
    P += normalize(N) * a * sin(2 * phi);
    N = calculatenormal(P);
    vector er = vector(cos(phi) * cos(theta), cos(phi) * sin(theta), sin(phi));
    vector ephi = vector(-sin(phi) * cos(theta), -sin(phi) * sin(theta), cos(phi));
    check_normal_closed_form = pnear(N, normalize(R * er - dR * ephi), 2e-3);
    check_normal_unit = near(length(N), 1, 1e-5);
    check_radius = near(length(P), R, 1e-5);
}
