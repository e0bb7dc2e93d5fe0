/* matrix.sl: matrices: 16-tuples (row-major), comp/setcomp, determinant,
 * products and quotients, translate/rotate/scale (appended as RiTranslate...
 * append to the CTM: applied to points first), float promotion.
 * Batch: a plane grid. */
#include "corpus.h"

surface matrices(
    CHECK(tuple_row_major); CHECK(comp_setcomp); CHECK(determinant); CHECK(product);
    CHECK(quotient); CHECK(translate); CHECK(rotate); CHECK(scale); CHECK(append_order);
    CHECK(float_times_matrix); CHECK(comparisons); CHECK(varying_matrix);)
{
    matrix m = matrix(1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16);
    check_tuple_row_major = near(comp(m, 0, 3), 4, 0) + near(comp(m, 3, 0), 13, 0)
        + near(comp(m, 2, 1), 10, 0);
    setcomp(m, 1, 2, -7);
    setcomp(m, 3, 3, u);
    check_comp_setcomp = near(comp(m, 1, 2), -7, 0) + near(comp(m, 3, 3), u, 0)
        + near(comp(m, 1, 1), 6, 0);
    matrix t = matrix(2, 0, 0, 0, 1, 3, 0, 0, 4, 5, 4, 0, 7, 8, 9, 0.5);
    check_determinant = near(determinant(t), 2 * 3 * 4 * 0.5, 1e-5)
        + near(determinant(matrix 1), 1, 0)
        + near(determinant(matrix(1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16)), 0, 1e-3);
    /* row vectors: p (A B) = (p A) B */
    matrix A = translate(matrix 1, vector(1, 2, 3));
    matrix B = scale(matrix 1, point(2, 3, 4));
    check_product = pnear(transform(A * B, point(1, 1, 1)), point(4, 9, 16), 1e-5)
        + pnear(transform(B * A, point(1, 1, 1)), point(3, 5, 7), 1e-5);
    check_quotient = mnear(t / t, matrix 1, 1e-5) + mnear((A * B) / B, A, 1e-5);
    check_translate = pnear(transform(A, point(0, 0, 0)), point(1, 2, 3), 1e-6)
        + pnear(vtransform(A, vector(1, 0, 0)), vector(1, 0, 0), 1e-6);
    matrix R = rotate(matrix 1, PI / 2, vector(0, 0, 1));
    check_rotate = pnear(transform(R, point(1, 0, 0)), point(0, 1, 0), 1e-6)
        + pnear(transform(rotate(matrix 1, PI, vector(1, 0, 0)), point(0, 1, 0)), point(0, -1, 0), 1e-6);
    check_scale = pnear(transform(B, point(1, 1, 1)), point(2, 3, 4), 1e-6);
    /* translate(scale(1, 2), t): t is applied first, then the scale */
    check_append_order =
        pnear(transform(translate(scale(matrix 1, point(2, 2, 2)), vector(1, 0, 0)), point(1, 0, 0)),
              point(4, 0, 0), 1e-6)
        + pnear(transform(scale(translate(matrix 1, vector(1, 0, 0)), point(2, 2, 2)), point(1, 0, 0)),
                point(3, 0, 0), 1e-6);
    check_float_times_matrix = mnear(3 * matrix 1, matrix 3, 0)
        + near(comp(matrix 2 * 0.5, 2, 2), 1, 0) + near(comp(matrix 2, 0, 1), 0, 0);
    check_comparisons = TRUTH(A == A) + TRUTH(A != B);
    matrix V = translate(matrix 1, vector(u, 0, 0));
    check_varying_matrix = pnear(transform(V, point(0, 0, 0)), point(u, 0, 0), 1e-6);
}
