/* control_flow.sl: if/else under partial masks, while, for, break and
 * continue with levels, return from the shader under a mask, uniform stores
 * under partial masks. Batch: a plane grid of 8 x 4 points (u = (i+0.5)/8). */
#include "corpus.h"

surface control_flow(
    CHECK(if_else_chain); CHECK(nested_if_partial); CHECK(empty_branch);
    CHECK(while_varying_trips); CHECK(for_loop); CHECK(for_continue);
    CHECK(break_inner); CHECK(break_two); CHECK(continue_two);
    CHECK(loop_in_branch); CHECK(uniform_store_partial); CHECK(uniform_loop_varying_break);
    CHECK(ternary_masks); CHECK(shader_return);
    output uniform float w = 0;)
{
    float i = floor(u * 8); /* 0..7 per column */

    float r = 0;
    if (i < 2) r = 1;
    else if (i < 4) r = 2;
    else if (i == 4) r = 3;
    else r = 4;
    check_if_else_chain = near(r, i < 2 ? 1 : (i < 4 ? 2 : (i == 4 ? 3 : 4)), 0);

    float q = 0;
    if (i > 1) {
        q = 1;
        if (i > 3) {
            q = 2;
            if (i > 5) q = 3;
            else q += 10;
        } else
            q += 20;
    } else {
        q = -1;
    }
    float want_q = i <= 1 ? -1 : (i <= 3 ? 21 : (i <= 5 ? 12 : 3));
    check_nested_if_partial = near(q, want_q, 0);

    float e = 5;
    if (i > 100) e = 6; /* no point runs */
    if (i < 100) {} else e = 7;
    check_empty_branch = near(e, 5, 0);

    /* while: point i runs i + 1 times */
    float c = 0, n = 0;
    while (c <= i) { c += 1; n += 2; }
    check_while_varying_trips = near(c, i + 1, 0) + near(n, 2 * (i + 1), 0);

    /* for: sum of 0..i */
    float k, sum = 0;
    for (k = 0; k <= i; k += 1) sum += k;
    check_for_loop = near(sum, i * (i + 1) / 2, 0) + near(k, i + 1, 0);

    /* continue skips the odd k */
    float evens = 0;
    for (k = 0; k < 8; k += 1) {
        if (mod(k, 2) == 1) continue;
        evens += k;
    }
    check_for_continue = near(evens, 0 + 2 + 4 + 6, 0);

    /* break leaves the inner loop only */
    float j, count = 0;
    for (k = 0; k < 3; k += 1)
        for (j = 0; j < 10; j += 1) {
            if (j >= i) break;
            count += 1;
        }
    check_break_inner = near(count, 3 * min(i, 10), 0);

    /* break 2 leaves both loops at (k, j) = (1, i) */
    float hits = 0, bk = -1, bj = -1;
    for (k = 0; k < 4; k += 1) {
        for (j = 0; j < 8; j += 1) {
            if (k == 1 && j == i) {
                bk = k;
                bj = j;
                break 2;
            }
            hits += 1;
        }
    }
    check_break_two = near(hits, 8 + i, 0) + near(bk, 1, 0) + near(bj, i, 0) + near(k, 1, 0);

    /* continue 2 goes on with the outer loop's next iteration */
    float inner = 0;
    for (k = 0; k < 3; k += 1) {
        for (j = 0; j < 5; j += 1) {
            if (j > i) continue 2;
            inner += 1;
        }
    }
    check_continue_two = near(inner, 3 * min(i + 1, 5), 0);

    /* a loop inside a varying branch, with a varying trip count */
    float lb = 0;
    if (i >= 4) {
        float m;
        for (m = 0; m < i; m += 1) lb += 1;
    } else
        lb = -i;
    check_loop_in_branch = near(lb, i >= 4 ? i : -i, 0);

    /* a uniform target is written if any point runs */
    if (i == 3) w = 7;
    uniform float w2 = 1;
    if (i > 100) w2 = 2;
    check_uniform_store_partial = near(w, 7, 0) + near(w2, 1, 0);

    /* a uniform loop condition, varying break */
    uniform float it;
    float stop = -1;
    for (it = 0; it < 10; it += 1) {
        if (it == i) {
            stop = it;
            break;
        }
    }
    check_uniform_loop_varying_break = near(stop, i, 0);

    /* both arms of ?: under complementary masks */
    float tv = i < 4 ? sqrt(i) : -i;
    check_ternary_masks = near(tv, i < 4 ? sqrt(i) : -i, 1e-6);

    /* return ends the shader for the points that run it */
    check_shader_return = 0;
    if (i >= 6) return;
    check_shader_return = i >= 6 ? 1 : 0;
}
