/*
 * test_common.h - a tiny check framework for the runtime's C tests.
 *
 * Every CHECK* macro prints file:line and the values involved on failure
 * and counts the failure; a test's main ends with TEST_END(), which returns
 * 1 if anything failed. References are computed in double in the tests.
 */
#ifndef TEST_COMMON_H
#define TEST_COMMON_H

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "gen_rt.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* TOL(d, f): a tolerance for the double build and one for the float build. */
#ifdef GEN_RT_REAL_FLOAT
#define TOL(d, f) (f)
#define TEST_IS_FLOAT 1
#else
#define TOL(d, f) (d)
#define TEST_IS_FLOAT 0
#endif

static int test_failures = 0;
static int test_checks = 0;

static inline void test_fail_hdr(const char *file, int line)
{
    ++test_failures;
    fprintf(stderr, "%s:%d: FAILED: ", file, line);
}

/* a condition */
#define CHECK(cond)                                                       \
    do {                                                                  \
        ++test_checks;                                                    \
        if (!(cond)) {                                                    \
            test_fail_hdr(__FILE__, __LINE__);                            \
            fprintf(stderr, "%s\n", #cond);                               \
        }                                                                 \
    } while (0)

/* two integers (status codes) equal */
#define CHECK_INT(got, want)                                              \
    do {                                                                  \
        long test_g_ = (long)(got), test_w_ = (long)(want);               \
        ++test_checks;                                                    \
        if (test_g_ != test_w_) {                                         \
            test_fail_hdr(__FILE__, __LINE__);                            \
            fprintf(stderr, "%s == %ld, expected %s == %ld\n", #got,       \
                    test_g_, #want, test_w_);                             \
        }                                                                 \
    } while (0)

/* |got - want| <= tol (fails on NaN) */
#define CHECK_NEAR(got, want, tol)                                        \
    do {                                                                  \
        double test_g_ = (double)(got), test_w_ = (double)(want);         \
        double test_t_ = (double)(tol);                                   \
        ++test_checks;                                                    \
        if (!(fabs(test_g_ - test_w_) <= test_t_)) {                      \
            test_fail_hdr(__FILE__, __LINE__);                            \
            fprintf(stderr,                                               \
                    "%s = %.17g, expected %s = %.17g, |diff| = %.3g > "   \
                    "tol %.3g\n",                                         \
                    #got, test_g_, #want, test_w_,                        \
                    fabs(test_g_ - test_w_), test_t_);                    \
        }                                                                 \
    } while (0)

/* a < b (fails on NaN) */
#define CHECK_LT(a, b)                                                    \
    do {                                                                  \
        double test_a_ = (double)(a), test_b_ = (double)(b);              \
        ++test_checks;                                                    \
        if (!(test_a_ < test_b_)) {                                       \
            test_fail_hdr(__FILE__, __LINE__);                            \
            fprintf(stderr, "%s = %.17g is not < %s = %.17g\n", #a,       \
                    test_a_, #b, test_b_);                                \
        }                                                                 \
    } while (0)

#define TEST_END()                                                        \
    do {                                                                  \
        printf("%s: %d checks, %d failed (%s)\n", __FILE__, test_checks,  \
               test_failures, TEST_IS_FLOAT ? "float" : "double");        \
        return test_failures ? 1 : 0;                                     \
    } while (0)

/* Reproducible pseudo-random numbers: a 32-bit LCG (Numerical Recipes). */
typedef struct { unsigned long s; } test_lcg;

static inline double test_lcg_uniform(test_lcg *g) /* in [-1, 1) */
{
    g->s = (1664525UL * g->s + 1013904223UL) & 0xFFFFFFFFUL;
    return (double)g->s / 2147483648.0 - 1.0;
}

#endif /* TEST_COMMON_H */
