/* queries.sl: attribute, option, rendererinfo, rayinfo, and the message
 * passing functions (not supported in this release: they return 0 and leave
 * the variable alone). corpus_test.cpp sets attributes identifier:name
 * "ball", ShadingRate 2, user:k 4, Color (1, 0.5, 0.25), the Format 320 x
 * 240, Clipping 0.5 100, a user option "render:bucket" 16. */
#include "corpus.h"

surface queries(
    CHECK(attribute); CHECK(attribute_unknown); CHECK(option); CHECK(rendererinfo);
    CHECK(rayinfo); CHECK(message_passing_unsupported);)
{
    string name = "";
    float rate = 0, k = 0, sides = 0;
    color col = 0;
    matrix xf = 0;
    float ok = attribute("identifier:name", name) + attribute("ShadingRate", rate)
        + attribute("user:k", k) + attribute("Ri:Color", col)
        + attribute("Ri:Transformation", xf) + attribute("Ri:Sides", sides);
    check_attribute = near(ok, 6, 0) + TRUTH(name == "ball") + near(rate, 2, 0) + near(k, 4, 0)
        + cnear(col, color(1, 0.5, 0.25), 0) + mnear(xf, matrix 1, 0) + near(sides, 2, 0);
    float none = 3;
    point pnone = point(1, 2, 3);
    vector vnone = vector(1, 1, 1);
    normal nnone = normal(1, 1, 1);
    float anone[2] = {7, 7};
    check_attribute_unknown = near(attribute("user:nope", none), 0, 0) + near(none, 3, 0)
        + near(attribute("nosuch", pnone) + attribute("nosuch", vnone) + attribute("nosuch", nnone)
               + attribute("nosuch", anone), 0, 0)
        + pnear(pnone, point(1, 2, 3), 0) + near(anone[1], 7, 0);
    float fmt[3] = {0, 0, 0}, clip[2] = {0, 0}, bucket = 0;
    string hider = "x";
    color oc = 0;
    point op = 0;
    matrix om = 0;
    float okopt = option("Format", fmt) + option("Clipping", clip) + option("render:bucket", bucket)
        + option("Hider", hider);
    check_option = near(okopt, 4, 0) + near(fmt[0], 320, 0) + near(fmt[1], 240, 0)
        + near(fmt[2], 1, 0) + near(clip[0], 0.5, 0) + near(clip[1], 100, 0) + near(bucket, 16, 0)
        + near(option("nosuch", oc) + option("nosuch", op) + option("nosuch", om), 0, 0);
    string rname = "";
    float rver[4] = {0, 0, 0, 0}, rnum = 0;
    check_rendererinfo = near(rendererinfo("renderer", rname), 1, 0) + TRUTH(rname == "sss")
        + near(rendererinfo("nosuch", rnum) + rendererinfo("nosuch", rver), 0, 0);
    float depth = -1;
    string label = "x";
    point org = 0;
    vector dir = 0;
    string rtype = "";
    float rlen = -1, dummy = 7;
    /* a camera batch: depth 0, type "camera", label ""; origin/direction/
       length of the ray from I (here I = P: the eye at the origin) */
    check_rayinfo = near(rayinfo("depth", depth), 1, 0) + near(depth, 0, 0)
        + near(rayinfo("label", label), 1, 0) + TRUTH(label == "")
        + near(rayinfo("type", rtype), 1, 0) + TRUTH(rtype == "camera")
        + near(rayinfo("origin", org), 1, 0) + near(length(org - (P - I)), 0, 1e-6)
        + near(rayinfo("direction", dir), 1, 0) + near(length(dir - normalize(I)), 0, 1e-6)
        + near(rayinfo("length", rlen), 1, 0) + near(rlen, length(I), 1e-5)
        + near(rayinfo("nosuch", dummy), 0, 0) + near(dummy, 7, 0)
        + near(raylevel(), 0, 0);
    /* documented: a surface shader cannot query surface(), its displacement
       shader's values or an atmosphere: 0, the variable untouched */
    float f = 1;
    color c = 2;
    point p = 3;
    vector v = 4;
    normal n = 5;
    string s = "s";
    matrix m = 6;
    float got = surface("Kd", f) + surface("Cs", c) + surface("P", p) + surface("v", v)
        + surface("n", n) + surface("s", s) + surface("m", m)
        + displacement("amp", f) + displacement("c", c) + displacement("p", p)
        + displacement("v", v) + displacement("n", n) + displacement("s", s)
        + displacement("m", m) + atmosphere("f", f) + atmosphere("c", c)
        + atmosphere("p", p) + atmosphere("s", s) + atmosphere("m", m);
    check_message_passing_unsupported = near(got, 0, 0) + near(f, 1, 0) + cnear(c, color 2, 0)
        + pnear(p, point 3, 0) + pnear(v, vector 4, 0) + pnear(n, normal 5, 0) + TRUTH(s == "s")
        + mnear(m, matrix 6, 0);
}
