/* textures.sl: texture (every form: implicit s/t, one pair, four pairs;
 * channels, float and colour results, options), environment, textureinfo.
 * corpus_test.cpp writes with OpenImageIO:
 *   map: 4 x 2 pixels, RGB float: R = (x + 0.5) / 4, G = (y + 0.5) / 2,
 *        B = 0.25 + 0.1 x (y = 0 the top row, at t = 0);
 *   env: a lat-long environment, every pixel (0.2, 0.4, 0.6).
 * A map that cannot be read stops the shader (ShaderRuntimeError), see
 * RslCorpusRuntime in corpus_test.cpp.
 * Batch: a plane grid of 4 x 2 points, s = u and t = v at the pixel centres. */
#include "corpus.h"

surface textures(
    CHECK(pixels_colour); CHECK(pixels_channels); CHECK(implicit_st); CHECK(filtered_gradient);
    CHECK(four_points); CHECK(fill); CHECK(blur_whole_map); CHECK(environment);
    CHECK(textureinfo);
    string map = ""; string env = "";)
{
    float col = floor(s * 4);
    color want = color(s, t, 0.25 + 0.1 * col);
    /* "width" 0: no filtering, the pixel itself */
    check_pixels_colour = cnear(color texture(map, s, t, "width", 0), want, 1e-5);
    check_pixels_channels = near(float texture(map[1], s, t, "width", 0), t, 1e-5)
        + near(float texture(map[2], s, t, "swidth", 0, "twidth", 0), comp(want, 2), 1e-5)
        + near(texture(map, s, t, "width", 0), s, 1e-5);
    check_implicit_st = cnear(color texture(map, "width", 0), want, 1e-5)
        + near(float texture(map[1], "width", 0), t, 1e-5);
    /* filtered over the point's own footprint (Du(s) du: one pixel across,
     * nothing down as the t argument does not vary): the linear ramp of R
     * keeps its value at the centre of the inner columns (the outer ones
     * blend with the black beyond the edge) */
    float inner = col == 1 || col == 2 ? 1 : 0;
    check_filtered_gradient = inner * near(float texture(map, s, 0.25 + 0 * t), s, 0.02);
    /* the quad around the pixel centre */
    float h = 0.05;
    check_four_points = near(float texture(map[1], s - h, t - h, s + h, t - h, s + h, t + h,
                                           s - h, t + h), t, 0.02);
    /* channels past the image's last take "fill" */
    check_fill = cnear(color texture(map[2], s, t, "width", 0, "fill", 0.7),
                       color(comp(want, 2), 0.7, 0.7), 1e-5);
    /* a blur of the whole map averages it: R averages to 0.5 */
    check_blur_whole_map = near(float texture(map, 0.5, 0.5, "blur", 1), 0.5, 0.1);
    check_environment = cnear(color environment(env, vector(0, 0, 1)), color(0.2, 0.4, 0.6), 1e-4)
        + cnear(color environment(env, N), color(0.2, 0.4, 0.6), 1e-4)
        + near(float environment(env[1], vector(1, 0, 0)), 0.4, 1e-4);
    float res[2] = {0, 0}, nch = 0;
    string kind = "";
    float ok = textureinfo(map, "resolution", res) + textureinfo(map, "channels", nch)
        + textureinfo(map, "type", kind);
    float none = textureinfo(map, "nosuchkey", nch) + textureinfo("nosuch.tx", "channels", nch);
    check_textureinfo = near(ok, 3, 0) + near(res[0], 4, 0) + near(res[1], 2, 0)
        + near(nch, 3, 0) + TRUTH(kind == "texture") + near(none, 0, 0);
    /* a map that cannot be read is a run-time error (corpus_test.cpp) */
}
