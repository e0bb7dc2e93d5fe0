/* spaces.sl: named spaces, typed casts with spaces, transform / vtransform /
 * ntransform in every form, matrix casts. corpus_test.cpp sets:
 *   world -> camera (= current): translate (0, 0, 5)
 *   object -> world: translate (0, 3, 0) * scale (2, 1, 1)
 *   shader -> world: translate (1, 0, 0)
 *   coordinate system "lamp" -> world: translate (0, 0, 1) * rotate 90 deg about z
 *   a perspective camera, fov 90, 200 x 100 pixels (screen window [-2,2]x[-1,1]).
 * Batch: a plane grid (P in camera space). */
#include "corpus.h"

surface spaces(
    CHECK(cast_point_spaces); CHECK(cast_vector_normal); CHECK(transform_to);
    CHECK(transform_from_to); CHECK(round_trips); CHECK(vtransform); CHECK(ntransform);
    CHECK(transform_matrix); CHECK(transform_from_matrix); CHECK(matrix_casts);
    CHECK(screen_ndc_raster); CHECK(shader_space_param);
    point from = point "shader" (0, 0, 0);)
{
    check_cast_point_spaces = pnear(point "object" (1, 0, 0), point(2, 3, 5), 1e-5)
        + pnear(point "world" (0, 0, 0), point(0, 0, 5), 1e-5)
        + pnear(point "camera" (1, 2, 3), point(1, 2, 3), 0)
        + pnear(point "current" (1, 2, 3), point(1, 2, 3), 0)
        + pnear(point "shader" (0, 0, 0), point(1, 0, 5), 1e-5)
        + pnear(point "lamp" (1, 0, 0), point(0, 1, 6), 1e-5);
    /* vectors drop the translation; normals take the inverse transpose */
    check_cast_vector_normal = pnear(vector "object" (1, 1, 0), vector(2, 1, 0), 1e-5)
        + pnear(normal "object" (1, 1, 0), normal(0.5, 1, 0), 1e-5)
        + pnear(vector "lamp" (1, 0, 0), vector(0, 1, 0), 1e-5);
    check_transform_to = pnear(transform("world", P), P - vector(0, 0, 5), 1e-5)
        + pnear(transform("object", point(2, 3, 5)), point(1, 0, 0), 1e-5)
        + pnear(transform("lamp", point(0, 1, 6)), point(1, 0, 0), 1e-5)
        + pnear(transform("shader", point(1, 0, 5)), point(0, 0, 0), 1e-5);
    check_transform_from_to = pnear(transform("object", "world", point(1, 0, 0)), point(2, 3, 0), 1e-5)
        + pnear(transform("world", "object", point(2, 3, 0)), point(1, 0, 0), 1e-5)
        + pnear(transform("lamp", "world", point(1, 0, 0)), point(0, 1, 1), 1e-5)
        + pnear(transform("shader", "lamp", point(-1, 0, 1)), point(0, 0, 0), 1e-5);
    point w = transform("object", "world", P);
    check_round_trips = pnear(transform("world", "object", w), P, 1e-5)
        + pnear(transform("world", "current", transform("world", P)), P, 1e-5)
        + pnear(transform("NDC", "current", transform("NDC", P)), P, 1e-4)
        + pnear(transform("raster", "screen", transform("raster", P)), transform("screen", P), 1e-4);
    check_vtransform = pnear(vtransform("object", "world", vector(1, 1, 0)), vector(2, 1, 0), 1e-5)
        + pnear(vtransform("world", vector(1, 2, 3)), vector(1, 2, 3), 1e-5)
        + pnear(vtransform("lamp", "world", vector(1, 0, 0)), vector(0, 1, 0), 1e-5)
        + pnear(vtransform(matrix 2, vector(1, 2, 3)), vector(2, 4, 6), 1e-5)
        + pnear(vtransform("world", translate(matrix 1, vector(9, 9, 9)), vector(1, 0, 0)),
                vector(1, 0, 0), 1e-5);
    check_ntransform = pnear(ntransform("object", "world", normal(1, 1, 0)), normal(0.5, 1, 0), 1e-5)
        + pnear(ntransform("world", normal(0, 0, 1)), normal(0, 0, 1), 1e-5)
        + pnear(ntransform(scale(matrix 1, point(2, 4, 1)), normal(1, 1, 1)), normal(0.5, 0.25, 1), 1e-5)
        + pnear(ntransform("object", scale(matrix 1, point(1, 2, 1)), normal(0, 1, 0)),
                normal(0, 0.5, 0), 1e-5);
    /* p' = p M with a 16-tuple */
    matrix m = (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 4, 5, 6, 1);
    check_transform_matrix = pnear(transform(m, point(1, 1, 1)), point(5, 6, 7), 1e-6)
        + pnear(vtransform(m, vector(1, 1, 1)), vector(1, 1, 1), 1e-6);
    /* (from, m, p): p taken from "from" space to current, then by m */
    check_transform_from_matrix = pnear(transform("world", m, point(0, 0, 0)), point(4, 5, 11), 1e-5);
    /* matrix "space" x: x given in that space, brought to current: current -> world first */
    check_matrix_casts = pnear(transform(matrix "world" 1, P), transform("world", P), 1e-5)
        + pnear(transform(matrix "shader" 1, P), transform("shader", P), 1e-5)
        + pnear(transform(matrix "world" (1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1, 1, 1, 1), point(0, 0, 5)),
                point(1, 1, 1), 1e-5);
    /* camera (1, 0.5, 2): screen (x/z, y/z) / tan(45 deg) = (0.5, 0.25);
     * NDC x (0.5 + 2) / 4 = 0.625, y (1 - 0.25) / 2 = 0.375; raster * (200, 100) */
    point sc = transform("screen", point(1, 0.5, 2));
    point nd = transform("NDC", point(1, 0.5, 2));
    point ra = transform("raster", point(1, 0.5, 2));
    check_screen_ndc_raster = near(xcomp(sc), 0.5, 1e-5) + near(ycomp(sc), 0.25, 1e-5)
        + near(xcomp(nd), 0.625, 1e-5) + near(ycomp(nd), 0.375, 1e-5)
        + near(xcomp(ra), 125, 1e-3) + near(ycomp(ra), 37.5, 1e-3);
    /* a parameter default in "shader" space arrives converted to current */
    check_shader_space_param = pnear(from, point(1, 0, 5), 1e-5);
}
