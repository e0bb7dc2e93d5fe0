// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* corpus_pp.h: a header found only through -I (tests/shading/corpus/include),
 * included by preprocessor.sl. */
#ifndef CORPUS_PP_H
#define CORPUS_PP_H

#define PP_FROM_HEADER 42
#define SQUARE(x) ((x) * (x))
#define MAX2(a, b) ((a) > (b) ? (a) : (b))
#define LERP(a, b, t) ((a) + ((b) - (a)) * (t))
#define CAT(a, b) a##b
#define STR(x) #x
#define FIRST(a, ...) (a)
#define COUNT_REST(a, ...) pp_count(__VA_ARGS__)

float pp_header_function(float x) { return x + PP_FROM_HEADER; }

#endif
