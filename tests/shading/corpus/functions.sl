/* functions.sl: user functions: results of every type, nesting, extern
 * variables (a local, a parameter, a global), output parameters, arrays as
 * parameters, overloading on argument and on return types, returns under a
 * mask, functions calling functions. Batch: a plane grid. */
#include "corpus.h"

float sq(float x) { return x * x; }
color tint(color c; float k) { return c * k; }
point mid(point a, b) { return (a + b) / 2; }
matrix twice(matrix m) { return m * 2; }
string greet(string who) { return concat("hi ", who); }

/* output parameters, several per group */
void split(float x; output float whole, frac) {
    whole = floor(x);
    frac = x - whole;
}
void bump3(output point p; vector d) { p += d; }

/* arrays as parameters */
float total(float a[]) {
    float t = 0, k;
    for (k = 0; k < 3; k += 1) t += a[k];
    return t;
}
void fill(output float a[]; float v) { a[0] = v; a[1] = v; a[2] = v; }

/* overloading on argument types and on the return type */
float kind(float x) { return 1; }
float kind(point x) { return 2; }
float kind(color x) { return 3; }
float pick() { return 1; }
color pick() { return color(1, 2, 3); }

/* an early return of a void function under a mask */
void clampup(output float a) {
    if (a > 0.5) return;
    a = a + 1;
}
/* the function's single return after varying work */
float piecewise(float x) {
    float y;
    if (x < 0.5) y = 2 * x;
    else y = 10;
    return y;
}
float sumsq(float a, b) { return sq(a) + sq(b); }

surface functions(
    CHECK(results); CHECK(output_params); CHECK(array_params); CHECK(overload_args);
    CHECK(overload_result); CHECK(void_return_mask); CHECK(single_return_mask);
    CHECK(calls_calls); CHECK(nested); CHECK(extern_local); CHECK(extern_param);
    CHECK(extern_global); CHECK(extern_write); CHECK(by_reference); CHECK(uniform_result_under_mask);
    float Kd = 0.25;)
{
    check_results = near(sq(3), 9, 0) + cnear(tint(color(1, 2, 3), 2), color(2, 4, 6), 0)
        + pnear(mid(point(0, 0, 0), point(2, 4, 6)), point(1, 2, 3), 0)
        + near(comp(twice(matrix 1), 1, 1), 2, 0) + TRUTH(greet("bob") == "hi bob");

    float wh, fr;
    split(u + 2, wh, fr);
    point bp = point(1, 1, 1);
    bump3(bp, vector(1, 2, 3));
    check_output_params = near(wh, 2, 0) + near(fr, u, 1e-6) + pnear(bp, point(2, 3, 4), 0);

    float arr[3] = {1, 2, 3};
    float t1 = total(arr);
    fill(arr, u);
    check_array_params = near(t1, 6, 0) + near(total(arr), 3 * u, 1e-6);

    check_overload_args = near(kind(1), 1, 0) + near(kind(point(1, 2, 3)), 2, 0)
        + near(kind(color(1, 2, 3)), 3, 0);
    check_overload_result = near(float pick(), 1, 0) + cnear(color pick(), color(1, 2, 3), 0);

    float a = u;
    clampup(a);
    check_void_return_mask = near(a, u > 0.5 ? u : u + 1, 1e-6);
    check_single_return_mask = near(piecewise(u), u < 0.5 ? 2 * u : 10, 1e-6);
    check_calls_calls = near(sumsq(3, u), 9 + u * u, 1e-5);

    /* a function declared inside the body, with its own nested helper */
    float outer(float x) {
        float inner(float y) { return y + 1; }
        return inner(x) * 2;
    }
    check_nested = near(outer(u), 2 * (u + 1), 1e-6);

    float base = 10;
    float addbase(float x) {
        extern float base;
        return x + base;
    }
    check_extern_local = near(addbase(u), u + 10, 1e-6);
    float withkd(float x) {
        extern float Kd;
        return x * Kd;
    }
    check_extern_param = near(withkd(4), 1, 0);
    float uplus() {
        extern varying float u;
        extern point P;
        return u + xcomp(P) * 0;
    }
    check_extern_global = near(uplus(), u, 0);
    float counter = 0;
    void incr() {
        extern float counter;
        counter += 1;
    }
    incr();
    incr();
    check_extern_write = near(counter, 2, 0);
    /* output parameters write the caller's variable itself */
    float same = 1;
    void twicep(output float a) { a *= 2; }
    twicep(same);
    twicep(same);
    check_by_reference = near(same, 4, 0);
    /* PRMan: a function may declare its result uniform, and a uniform result
       stays uniform when the call runs under a varying condition */
    uniform float calls = 0;
    uniform float next() {
        extern uniform float calls;
        calls += 1;
        return calls * 10;
    }
    float got = 0;
    if (u >= 0) {
        uniform float once = next();
        got = once;
    }
    check_uniform_result_under_mask = near(got, 10, 0) + near(calls, 1, 0);
}
