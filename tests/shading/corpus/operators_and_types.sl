/* operators_and_types.sl: every operator with its precedence, component-wise
 * colour arithmetic, promotions, casts, literals, arrays, uniform/varying.
 * Batch: a plane grid (any). */
#include "corpus.h"

surface operators_and_types(
    CHECK(precedence_arith); CHECK(left_assoc); CHECK(unary_minus);
    CHECK(dot_tighter_than_mul); CHECK(cross_between_add_and_mul);
    CHECK(cross_looser_than_mul); CHECK(dot_cross_values);
    CHECK(colour_componentwise); CHECK(colour_float_promotion);
    CHECK(point_arith); CHECK(point_minus_point); CHECK(matrix_arith);
    CHECK(matrix_float_promotion); CHECK(ternary); CHECK(ternary_nested);
    CHECK(compound_float); CHECK(compound_colour); CHECK(compound_point);
    CHECK(assign_is_expression); CHECK(relations); CHECK(logic);
    CHECK(triple_equality); CHECK(string_equality); CHECK(literals);
    CHECK(adjacent_strings); CHECK(pi); CHECK(casts_between_ptypes);
    CHECK(cast_hsv); CHECK(cast_matrix_space); CHECK(float_cast);
    CHECK(tuple_matrix); CHECK(arrays); CHECK(array_index_rounds_down);
    CHECK(array_param); CHECK(colour_array); CHECK(uniform_varying);
    CHECK(globals); CHECK(if_non_relation); CHECK(component_index);
    CHECK(shader_kinds_are_names);
    float tab[4] = {10, 20, 30, 40};
    uniform float two = 2;)
{
    check_precedence_arith = near(1 + 2 * 3 - 8 / 4, 5, 0) + near((1 + 2) * 3, 9, 0);
    check_left_assoc = near(8 / 4 / 2, 1, 0) + near(2 - 3 - 4, -5, 0);
    check_unary_minus = near(-2 * 3, -6, 0) + near(- -2, 2, 0) + near(2 - -3, 5, 0)
                        + pnear(-point(1, 2, 3), point(-1, -2, -3), 0);
    /* a * b . c is a * (b . c): a vector times a float, not (a*b).c, a float */
    check_dot_tighter_than_mul =
        pnear(vector(1, 2, 3) * vector(1, 1, 1) . vector(0, 0, 1), vector(1, 2, 3), 0);
    /* a ^ b + c is (a ^ b) + c */
    check_cross_between_add_and_mul =
        pnear(vector(1, 0, 0) ^ vector(0, 1, 0) + vector(0, 0, 1), vector(0, 0, 2), 0);
    /* a ^ b * c is a ^ (b * c) */
    check_cross_looser_than_mul =
        pnear(vector(1, 0, 0) ^ vector(0, 1, 0) * vector(1, 1, 2), vector(0, 0, 1), 0);
    check_dot_cross_values = near(vector(1, 2, 3) . vector(4, -5, 6), 12, 0)
        + pnear(vector(1, 2, 3) ^ vector(4, 5, 6), vector(-3, 6, -3), 0)
        + near(color(1, 2, 3) . color(1, 1, 1), 6, 0);

    check_colour_componentwise =
        cnear(color(1, 2, 3) * color(2, 3, 4), color(2, 6, 12), 0)
        + cnear(color(1, 2, 3) + color(1, 1, 1), color(2, 3, 4), 0)
        + cnear(color(2, 6, 12) / color(2, 3, 4), color(1, 2, 3), 0)
        + cnear(color(1, 2, 3) - color(3, 2, 1), color(-2, 0, 2), 0);
    color c1 = 0.5;
    check_colour_float_promotion = cnear(c1, color(0.5, 0.5, 0.5), 0)
        + cnear(2 * color(1, 2, 3), color(2, 4, 6), 0)
        + cnear(color(1, 2, 3) + 1, color(2, 3, 4), 0)
        + cnear(1 - color(0.25, 0.5, 1), color(0.75, 0.5, 0), 0);

    check_point_arith = pnear(point(1, 2, 3) + vector(1, 1, 1), point(2, 3, 4), 0)
        + pnear(point(1, 2, 3) * point(2, 2, 2), point(2, 4, 6), 0)
        + pnear(point(2, 4, 6) / 2, point(1, 2, 3), 0);
    vector pp = point(3, 3, 3) - point(1, 2, 3);
    check_point_minus_point = pnear(pp, vector(2, 1, 0), 0);

    matrix a = matrix(2, 0, 0, 0, 0, 3, 0, 0, 0, 0, 4, 0, 1, 2, 3, 1);
    matrix ident = 1;
    check_matrix_arith = mnear(a / a, ident, 1e-6) + mnear(a * ident, a, 0)
        + mnear(2 * ident, matrix(2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2), 0)
        /* row vectors: (1,1,1) * a = (2+1, 3+2, 4+3) */
        + pnear(transform(a, point(1, 1, 1)), point(3, 5, 7), 1e-6);
    matrix z = 0;
    check_matrix_float_promotion = mnear(ident, matrix(1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1), 0)
        + near(determinant(z), 0, 0) + near(determinant(a), 24, 1e-5);

    check_ternary = near(u < 2 ? 1 : 2, 1, 0) + near(u > 2 ? 1 : 2, 2, 0)
        + cnear(u < 2 ? color(1, 0, 0) : color(0, 1, 0), color(1, 0, 0), 0);
    /* right associative: a ? b : c ? d : e */
    float tn = u < 0.5 ? 1 : u < 0.75 ? 2 : 3;
    check_ternary_nested = near(tn, u < 0.5 ? 1 : (u < 0.75 ? 2 : 3), 0);

    float x = 10;
    x += 5; x -= 3; x *= 2; x /= 4;
    check_compound_float = near(x, 6, 0);
    color cc = color(1, 2, 3);
    cc += 1; cc *= color(1, 2, 3); cc -= color(1, 1, 1); cc /= 2;
    check_compound_colour = cnear(cc, color(0.5, 2.5, 5.5), 1e-6);
    point p3 = point(1, 1, 1);
    p3 += vector(1, 2, 3); p3 *= 2; p3 -= point(1, 1, 1); p3 /= point(1, 1, 7);
    check_compound_point = pnear(p3, point(3, 5, 1), 1e-6);

    float ea, eb;
    ea = eb = 3;
    float ec = (eb = 4) + 1;
    check_assign_is_expression = near(ea, 3, 0) + near(eb, 4, 0) + near(ec, 5, 0);

    check_relations = TRUTH(1 < 2) + TRUTH(2 <= 2) + TRUTH(3 > 2) + TRUTH(3 >= 3)
        + TRUTH(2 == 2) + TRUTH(2 != 3) + TRUTH(!(2 < 1));
    check_logic = TRUTH(1 < 2 && 2 < 3) + TRUTH(1 > 2 || 2 < 3) + TRUTH(!(1 > 2 && 2 < 3))
        + TRUTH(!(1 > 2 || 3 < 2));
    check_triple_equality = TRUTH(point(1, 2, 3) == point(1, 2, 3))
        + TRUTH(color(1, 2, 3) != color(1, 2, 4)) + TRUTH(vector 1 == vector(1, 1, 1))
        + TRUTH(color 0.5 == 0.5);
    string str = "abc";
    check_string_equality = TRUTH(str == "abc") + TRUTH(str != "abd") + TRUTH("" == "");
    check_literals = near(1., 1, 0) + near(.5, 0.5, 0) + near(1e2, 100, 0)
        + near(2.5e-1, 0.25, 0) + near(1.5f, 1.5, 0) + near(1E+1, 10, 0);
    check_adjacent_strings = TRUTH("ab" "cd" == "abcd");
    check_pi = near(PI, 3.14159265, 1e-6) + near(cos(PI), -1, 1e-6);

    normal nn = normal(vector(1, 2, 3));
    point pn = point(nn);
    vector vv = vector(point(4, 5, 6));
    check_casts_between_ptypes = pnear(pn, point(1, 2, 3), 0) + pnear(vv, vector(4, 5, 6), 0);
    check_cast_hsv = cnear(color "hsv" (0, 1, 1), color(1, 0, 0), 1e-6)
        + cnear(color "hsv" (1.0 / 3, 1, 0.5), color(0, 0.5, 0), 1e-6)
        + cnear(color "rgb" (0.1, 0.2, 0.3), color(0.1, 0.2, 0.3), 0);
    /* current = camera = world in this batch (no camera transform) */
    check_cast_matrix_space = mnear(matrix "world" 1, ident, 1e-6)
        + mnear(matrix "current" 2, 2 * ident, 1e-6);
    check_float_cast = near(float 2, 2, 0) + near(float(u) - u, 0, 0);
    matrix tup = (1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16);
    check_tuple_matrix = near(comp(tup, 0, 1), 2, 0) + near(comp(tup, 3, 0), 13, 0);

    float arr[3] = {1, 2, 3};
    arr[2] = arr[0] + arr[1] * 10;
    check_arrays = near(arr[2], 21, 0) + near(arr[0], 1, 0);
    /* the float index is rounded down: 1.9 -> 1, u*3 (u < 1) -> floor */
    check_array_index_rounds_down = near(arr[1.9], 2, 0) + near(arr[0.1], 1, 0)
        + near(tab[u * 4], 10 * (floor(u * 4) + 1), 0);
    check_array_param = near(tab[3], 40, 0) + near(tab[2.5] + tab[0], 40, 0);
    color carr[2] = {color(1, 0, 0), color(0, 1, 0)};
    carr[1] = carr[1] * 3;
    check_colour_array = cnear(carr[0] + carr[1], color(1, 3, 0), 0);

    /* uniform values promote into varying expressions */
    uniform float k = two * 3;
    varying float vk = u * k;
    uniform color uc = color(1, 2, 3);
    varying color vc = uc * u;
    check_uniform_varying = near(vk, 6 * u, 1e-6) + cnear(vc, color(u, 2 * u, 3 * u), 1e-6);

    check_globals = pnear(E, point(0, 0, 0), 0) + pnear(I, P - E, 1e-6)
        + near(ncomps, 3, 0) + TRUTH(du > 0 && dv > 0) + near(s, u, 0);
    /* a condition without a relation is "!= 0" */
    float nz = 0;
    if (u + 1) nz = 1;
    check_if_non_relation = near(nz, 1, 0);
    /* PRMan: c[i] is comp(c, i) on colours, points, vectors and normals */
    color ci = color(1, 2, 3);
    point pi3 = point(4, 5, 6);
    ci[1] = pi3[2] + u;
    ci[0] += 10;
    check_component_index = cnear(ci, color(11, 6 + u, 3), 1e-6) + near(pi3[0], 4, 0);
    /* shader kinds are keywords only where a shader is defined */
    color light = color(1, 0.5, 0);
    float volume = 2, imager = 3;
    check_shader_kinds_are_names = near(comp(light, 1) * volume * imager, 3, 0);
}
