/*
 * test_util.h — the tiny assertion kit every test uses.
 *
 * CHECK(cond, fmt, ...) records a failure with file:line and continues; TEST_MAIN_END returns
 * non-zero if anything failed, and prints "N passed, N failed" for the checks of this program.
 */
#ifndef IC_TEST_UTIL_H
#define IC_TEST_UTIL_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int ic_test_passed, ic_test_failed;

#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (cond) {                                                                                \
            ++ic_test_passed;                                                                      \
        } else {                                                                                   \
            ++ic_test_failed;                                                                      \
            fprintf(stderr, "%s:%d: CHECK failed: %s: ", __FILE__, __LINE__, #cond);               \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
        }                                                                                          \
    } while (0)

#define CHECK_NEAR(a, b, tol, what)                                                                \
    CHECK(fabs((double)(a) - (double)(b)) <= (double)(tol), "%s: %.9g vs %.9g (tol %.3g)", what,    \
          (double)(a), (double)(b), (double)(tol))

/* Work counts of exhaustive comparisons: sanitizer builds (IC_TEST_SANITIZED, set by tests/CMakeLists.txt)
 * look for memory and undefined-behaviour errors, which a quarter of the queries reaches as well; the
 * release build runs the full counts. */
#ifdef IC_TEST_SANITIZED
#define IC_TEST_WORK(n) ((n) / 4)
#else
#define IC_TEST_WORK(n) (n)
#endif

#define TEST_MAIN_END()                                                                            \
    do {                                                                                           \
        printf("%d passed, %d failed\n", ic_test_passed, ic_test_failed);                          \
        return ic_test_failed ? 1 : 0;                                                             \
    } while (0)

#endif
