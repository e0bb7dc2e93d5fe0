/* bake3d_texture3d.sl: bake3d records and texture3d lookups in a point cloud
 * and a brick map written by the library. corpus_test.cpp sets camera =
 * world + (0, 0, 1), so the plane grid (camera z = 1, N = (0, 0, -1)) lies
 * on world z = 0, and writes a cloud (and a brick map of it) over that
 * square with normals (0, 0, -1) and channels "v" = 0.25, "c" = (0.1, 0.2,
 * 0.3), "x" = the point's world x. */
#include "corpus.h"

surface bake3d_texture3d(
    CHECK(bake3d_returns_one); CHECK(texture3d_cloud); CHECK(texture3d_brickmap);
    CHECK(texture3d_linear_channel); CHECK(texture3d_miss);
    string cloud = ""; string bkm = ""; string out = "";)
{
    check_bake3d_returns_one = near(bake3d(out, "a, col", P, N, "a", u, "col", Cs, "radius", 0.05), 1, 0);
    float v = -1, x = -1;
    color c = -1;
    float found = texture3d(cloud, P, N, "v", v, "c", c);
    check_texture3d_cloud = near(found, 1, 0) + near(v, 0.25, 1e-3) + cnear(c, color(0.1, 0.2, 0.3), 1e-3);
    float vb = -1;
    float foundb = texture3d(bkm, P, N, "v", vb);
    check_texture3d_brickmap = near(foundb, 1, 0) + near(vb, 0.25, 1e-3);
    texture3d(cloud, P, N, "x", x);
    check_texture3d_linear_channel = near(x, xcomp(P), 0.02);
    /* documented: a miss returns 0 and leaves the outputs alone */
    float far = 9;
    float missed = texture3d(cloud, P + vector(0, 0, 50), N, "v", far);
    check_texture3d_miss = near(missed, 0, 0) + near(far, 9, 0);
    /* a file that cannot be read is a run-time error (corpus_test.cpp) */
}
