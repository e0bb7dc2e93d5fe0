/* preprocessor.sl: the C preprocessor before the compiler: #include from
 * the -I folders, object-like and function-like macros (#, ##, variadic),
 * #undef, #if / #elif / #else with defined() and arithmetic, #ifdef,
 * #ifndef, __LINE__, __FILE__, predefined macros, -D from the command line
 * (corpus_test.cpp defines CORPUS_LEVEL=3), comments and line splices. */
#include "corpus.h"
#include <corpus_pp.h>
#include "corpus_pp.h" /* a second include: the guard keeps it once */

#define SCALE 2.5
#define TWICE(x) (2 * (x))
#define LONG_SUM(a, b, \
                 c) ((a) + (b) + (c))
#define GONE 1
#undef GONE

float pp_count(float a, b) { return 2; }

#if defined(CORPUS_LEVEL) && CORPUS_LEVEL >= 3 && !defined(GONE)
#define LEVEL_BRANCH 1
#elif defined(CORPUS_LEVEL)
#define LEVEL_BRANCH 2
#else
#define LEVEL_BRANCH 3
#endif

#ifdef GONE
#error "#undef did not remove GONE"
#endif

#ifndef __SSS__
#error "__SSS__ is predefined"
#endif

#if (1 + 2) * 3 == 9 && (7 % 4) == 3 && (1 << 3) == 8 && -1 < 0
#define ARITH 1
#else
#define ARITH 0
#endif

#if 0
this is not RSL and must be skipped: }}} ###
#endif

surface preprocessor(
    CHECK(include_by_I); CHECK(object_macro); CHECK(function_macros); CHECK(paste_and_stringize);
    CHECK(variadic); CHECK(conditionals); CHECK(arithmetic); CHECK(line_and_file);
    CHECK(command_line_define); CHECK(splices_and_comments); CHECK(predefined);)
{
    check_include_by_I = near(PP_FROM_HEADER, 42, 0) + near(pp_header_function(1), 43, 0);
    check_object_macro = near(SCALE * 2, 5, 0);
    /* arguments are parenthesised by the macro: TWICE(1 + 2) = 6 */
    check_function_macros = near(TWICE(1 + 2), 6, 0) + near(SQUARE(u + 1), (u + 1) * (u + 1), 1e-6)
        + near(MAX2(3, 7), 7, 0) + near(LERP(2, 4, 0.5), 3, 0) + near(TWICE(SQUARE(3)), 18, 0);
    float CAT(pas, ted) = 5;
    check_paste_and_stringize = near(pasted, 5, 0) + TRUTH(STR(abc) == "abc");
    check_variadic = near(FIRST(4, 5, 6), 4, 0) + near(COUNT_REST(1, 2, 3), 2, 0);
    check_conditionals = near(LEVEL_BRANCH, 1, 0);
    check_arithmetic = near(ARITH, 1, 0);
    /* __LINE__ is this line's number in this file */
    check_line_and_file = near(__LINE__, 61, 0) + TRUTH(match("preprocessor[.]sl$", __FILE__) == 1);
    check_command_line_define = near(CORPUS_LEVEL, 3, 0);
    float spliced = LONG_SUM(1, /* a comment
    over two lines */ 2,
                             3); // and a line comment
    check_splices_and_comments = near(spliced, 6, 0);
    check_predefined = near(__SSS__, 1, 0) + near(RSL, 1, 0);
}
