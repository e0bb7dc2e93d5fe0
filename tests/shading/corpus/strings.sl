/* strings.sl: concat, format, printf and match (an invalid pattern is an error:
 * engine_budgets_test.cpp). corpus_test.cpp also checks
 * what printf sent. Batch: a plane grid of 2 x 1 points (u = 0.25, 0.75). */
#include "corpus.h"

surface strings(
    CHECK(concat); CHECK(format_numbers); CHECK(format_triples); CHECK(format_matrix);
    CHECK(format_strings); CHECK(match); CHECK(varying_format);
    string name = "skin";)
{
    check_concat = TRUTH(concat("a", "b") == "ab") + TRUTH(concat(name, "_", "ssd", ".bkm") == "skin_ssd.bkm")
        + TRUTH(concat("x") == "x");
    check_format_numbers = TRUTH(format("%f", 1.5) == "1.500000") + TRUTH(format("%.2f", PI) == "3.14")
        + TRUTH(format("%d", 3.7) == "3") + TRUTH(format("%g", 0.25) == "0.25")
        + TRUTH(format("%e", 1000) == "1.000000e+03") + TRUTH(format("%5.1f|", 2) == "  2.0|")
        + TRUTH(format("100%%") == "100%");
    check_format_triples = TRUTH(format("%p", point(1, 2, 3)) == "1.000000 2.000000 3.000000")
        + TRUTH(format("%.1c", color(0.5, 0.25, 1)) == "0.5 0.2 1.0")
        + TRUTH(format("%.0p", normal(1, 2, 3)) == "1 2 3");
    check_format_matrix = TRUTH(format("%.0m", matrix 1) == "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1");
    check_format_strings = TRUTH(format("%s-%s", name, "x") == "skin-x")
        + TRUTH(format("n=%d s=%s", 2, "a") == "n=2 s=a");
    check_match = TRUTH(match("^sk", name) == 1) + TRUTH(match("in$", name) == 1)
        + TRUTH(match("^x", name) == 0) + TRUTH(match("k.n", name) == 1)
        + TRUTH(match("[0-9]+", "frame12") == 1) + TRUTH(match("a|(b)", "xb") == 1);
    string f = format("%.2f", u);
    check_varying_format = TRUTH(f == (u < 0.5 ? "0.25" : "0.75"));
    printf("%s %.2f\n", name, u);
}
