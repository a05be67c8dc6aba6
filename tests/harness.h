/* Tiny assert harness: each CHECK counts one pass or one failure; the test
 * binary prints "N passed, N failed" and exits non-zero on any failure. */
#ifndef RS_TEST_HARNESS_H
#define RS_TEST_HARNESS_H
#include <stdio.h>
#include <string.h>
#include <math.h>

static int th_passed, th_failed;

#define CHECK(cond) th_check((cond) != 0, __FILE__, __LINE__, #cond)
#define CHECKF(cond, ...) do { if (!th_check((cond) != 0, __FILE__, __LINE__, #cond)) { \
    fprintf(stderr, "    "); fprintf(stderr, __VA_ARGS__); fprintf(stderr, "\n"); } } while (0)
#define CHECK_EQ_INT(a, b) do { long long th_a = (long long)(a), th_b = (long long)(b); \
    if (!th_check(th_a == th_b, __FILE__, __LINE__, #a " == " #b)) \
        fprintf(stderr, "    got %lld, expected %lld\n", th_a, th_b); } while (0)
#define CHECK_NEAR(a, b, tol) do { double th_a = (double)(a), th_b = (double)(b); \
    if (!th_check(fabs(th_a - th_b) <= (tol), __FILE__, __LINE__, #a " ~ " #b)) \
        fprintf(stderr, "    got %.9g, expected %.9g (tol %g)\n", th_a, th_b, (double)(tol)); } while (0)

static int th_check(int ok, const char *file, int line, const char *what)
{
    if (ok) { th_passed++; return 1; }
    th_failed++;
    fprintf(stderr, "FAIL %s:%d: %s\n", file, line, what);
    return 0;
}

static int th_finish(const char *name)
{
    printf("%s: %d passed, %d failed\n", name, th_passed, th_failed);
    return th_failed ? 1 : 0;
}
#endif
