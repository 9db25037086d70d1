/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/check.h -- the smallest test harness that does the job.
 *
 * A test file defines `static void test_x(void)` functions and a main() that
 * calls RUN(test_x) for each, then returns check_summary(). A failed CHECK
 * prints file:line and the expression (with values for the _EQ forms) and
 * marks the test failed; the test goes on so one run shows every failure.
 * Each test file is one ctest test.
 */
#ifndef CANOLA_TEST_CHECK_H
#define CANOLA_TEST_CHECK_H

#include <inttypes.h>
#include <stdio.h>
#include <string.h>

static int check_failures_total;
static int check_failures_here;
static int check_tests_run;
static int check_tests_failed;

#define CHECK(cond)                                                                                \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            printf("  %s:%d: CHECK(%s) failed\n", __FILE__, __LINE__, #cond);                      \
            check_failures_here++;                                                                 \
        }                                                                                          \
    } while (0)

#define CHECK_EQ(a, b)                                                                             \
    do {                                                                                           \
        unsigned long long check_a_ = (unsigned long long)(a);                                     \
        unsigned long long check_b_ = (unsigned long long)(b);                                     \
        if (check_a_ != check_b_) {                                                                \
            printf("  %s:%d: %s == %s failed: 0x%llx != 0x%llx\n", __FILE__, __LINE__, #a, #b,     \
                   check_a_, check_b_);                                                            \
            check_failures_here++;                                                                 \
        }                                                                                          \
    } while (0)

#define CHECK_STR(a, b)                                                                            \
    do {                                                                                           \
        const char *check_a_ = (a);                                                                \
        const char *check_b_ = (b);                                                                \
        if (strcmp(check_a_, check_b_) != 0) {                                                     \
            printf("  %s:%d: %s == %s failed:\n    got      \"%s\"\n    expected \"%s\"\n",        \
                   __FILE__, __LINE__, #a, #b, check_a_, check_b_);                                \
            check_failures_here++;                                                                 \
        }                                                                                          \
    } while (0)

#define RUN(test)                                                                                  \
    do {                                                                                           \
        check_failures_here = 0;                                                                   \
        test();                                                                                    \
        check_tests_run++;                                                                         \
        if (check_failures_here) {                                                                 \
            check_tests_failed++;                                                                  \
            check_failures_total += check_failures_here;                                           \
            printf("FAIL %s\n", #test);                                                            \
        } else {                                                                                   \
            printf("ok   %s\n", #test);                                                            \
        }                                                                                          \
    } while (0)

static inline int check_summary(void)
{
    printf("%d passed, %d failed\n", check_tests_run - check_tests_failed, check_tests_failed);
    return check_tests_failed ? 1 : 0;
}

#endif /* CANOLA_TEST_CHECK_H */
