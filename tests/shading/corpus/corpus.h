// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* corpus.h: conventions of the RSL acceptance corpus (docs/shading.md,
 * "Test corpus"). Every corpus shader declares one output parameter per
 * check with CHECK(name) and writes it once at the top level of its body:
 *   0          the check passed;
 *   non-zero   it failed: the value is the error |got - expected| (or 1 for
 *              a failed condition);
 *   -1         the default: the shader never wrote it (a failure too).
 * tests/shading/corpus_test.cpp runs each shader and asserts every check_*
 * parameter is 0 at every point, naming the file and the check. VALUE(name)
 * declares an output the C++ test aggregates itself (sums over a sphere...). */
#ifndef CORPUS_H
#define CORPUS_H

#define CHECK(name) output varying float check_##name = -1
#define VALUE(name) output varying float value_##name = 0
/* A condition as a check value. */
#define TRUTH(c) ((c) ? 0 : 1)

/* |got - want| when it exceeds tol, else 0. */
float near(float got; float want; float tol) {
    float e = abs(got - want);
    return e <= tol ? 0 : e;
}
/* Triples: the distance between got and want when it exceeds tol, else 0. */
float pnear(point got; point want; float tol) {
    float e = distance(got, want);
    return e <= tol ? 0 : e;
}
float cnear(color got; color want; float tol) {
    color d = got - want;
    float e = max(abs(comp(d, 0)), abs(comp(d, 1)), abs(comp(d, 2)));
    return e <= tol ? 0 : e;
}
/* Matrices: the largest element difference when it exceeds tol, else 0. */
float mnear(matrix got; matrix want; float tol) {
    float e = 0, r, c;
    for (r = 0; r < 4; r += 1)
        for (c = 0; c < 4; c += 1)
            e = max(e, abs(comp(got, r, c) - comp(want, r, c)));
    return e <= tol ? 0 : e;
}

#endif
