/* cli/numfmt.c against the C library's printf: the same text for every
 * value tried (tests/cli_mesh_test.sh runs it). Values: chosen edges
 * (zeros, powers of 2 and 10 and their neighbours, ties at every digit
 * count, the limits, NaN and infinities) at every precision 1-17, random
 * bit patterns of doubles and floats, heights and coordinates as the OBJ
 * writer prints them (%.9g, %.10g, %.7g), and every 97th float of two
 * whole binades. Prints "N passed, N failed". */
#include "numfmt.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static unsigned long long passed, failed;

static void check(double v, int prec)
{
    char want[64], got[CLI_FMT_G_MAX + 1];
    snprintf(want, sizeof want, "%.*g", prec, v);
    size_t n = cli_fmt_g(got, v, prec);
    got[n] = 0;
    if (strcmp(want, got) == 0) {
        passed++;
        return;
    }
    uint64_t b;
    memcpy(&b, &v, sizeof b);
    if (failed++ < 20)
        printf("FAIL %%.%dg of %.17g (bits %016llx): printf '%s', cli_fmt_g '%s'\n", prec, v, (unsigned long long)b,
               want, got);
}

static void check_u(unsigned long v)
{
    char want[32], got[32];
    snprintf(want, sizeof want, "%lu", v);
    size_t n = cli_fmt_u(got, v);
    got[n] = 0;
    if (strcmp(want, got) == 0) passed++;
    else if (failed++ < 20) printf("FAIL %%lu of %lu: '%s'\n", v, got);
}

static uint64_t rng = 0x9E3779B97F4A7C15ull;
static uint64_t next(void) /* splitmix64 */
{
    uint64_t z = (rng += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static double of_bits(uint64_t b)
{
    double d;
    memcpy(&d, &b, sizeof d);
    return d;
}

static void all_prec(double v)
{
    for (int p = 1; p <= 17; p++) {
        check(v, p);
        check(-v, p);
    }
}

static double cpu_ns(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}

/* The OBJ writer's kinds of number (coordinates %.9g, heights %.10g,
 * texture coordinates %.9g, normals %.7g) for n vertices: ns per number,
 * cli_fmt_g against snprintf, and whether both wrote the same bytes. */
static int bench(size_t n)
{
    static char a[1 << 16], b[1 << 16];
    double best[2] = { 1e300, 1e300 };
    size_t count = 0, la = 0, lb = 0;
    uint64_t ha = 1469598103934665603ull, hb = ha;
    for (int run = 0; run < 5; run++)
        for (int way = 0; way < 2; way++) {
            rng = 0x9E3779B97F4A7C15ull;
            uint64_t h = 1469598103934665603ull;
            size_t len = 0;
            double t0 = cpu_ns();
            count = 0;
            for (size_t i = 0; i < n; i++) {
                double u = (double)(next() >> 11) * 0x1p-53, w = (double)(next() >> 11) * 0x1p-53;
                double v[8] = { (double)(float)(u * 1024.0), (double)(float)(u * 900.0 + 57.0) * 0.01,
                                (double)(float)(w * 1024.0), (double)(float)u, 1.0 - (double)(float)w,
                                (double)(float)(u - 0.5), (double)(float)(0.8 + 0.2 * w), (double)(float)(w - 0.5) };
                static const int prec[8] = { 9, 10, 9, 9, 9, 7, 7, 7 };
                char *o = way ? b : a;
                size_t k = 0;
                for (int j = 0; j < 8; j++) {
                    if (way) k += (size_t)snprintf(o + k, 64, "%.*g", prec[j], v[j]);
                    else k += cli_fmt_g(o + k, v[j], prec[j]);
                    o[k++] = ' ';
                }
                for (size_t q = 0; q < k; q++) h = (h ^ (unsigned char)o[q]) * 1099511628211ull;
                len += k;
                count += 8;
            }
            double t = cpu_ns() - t0;
            if (t < best[way]) best[way] = t;
            if (way) hb = h, lb = len;
            else ha = h, la = len;
        }
    printf("numbers %zu, cli_fmt_g %.1f ns, printf %.1f ns, ratio %.2f, same bytes %s (%zu)\n", count,
           best[0] / (double)count, best[1] / (double)count, best[1] / best[0], ha == hb && la == lb ? "yes" : "no", la);
    return ha == hb && la == lb ? 0 : 1;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "--bench") == 0) return bench(200000);
    static const double edges[] = { 0.0, 1.0, 0.5, 1.5, 2.5, 0.25, 0.125, 0.375, 1.25, 1.75, 9.5, 99.5, 0.95, 0.05,
                                    999999999.5, 9999999999.5, 0.0001, 0.00009999999995, 1e-5, 123456789.0,
                                    1234567890.0, 1e15, 1e16, 1e17, 9007199254740992.0, 9007199254740993.0,
                                    DBL_MAX, DBL_MIN, 4.9406564584124654e-324, FLT_MAX, FLT_MIN, 3.14159265358979,
                                    1.0 / 3, 2.0 / 3, 0.1, 0.2, 0.3, 1e-14, 1e-15, 1e38, 1e39, 65504.0 };
    for (size_t i = 0; i < sizeof edges / sizeof *edges; i++) all_prec(edges[i]);
    all_prec(NAN);
    all_prec(INFINITY);
    for (int k = -330; k <= 330; k++) { /* powers of 10 and their neighbours */
        double t = pow(10.0, k);
        all_prec(t);
        all_prec(nextafter(t, 0));
        all_prec(nextafter(t, INFINITY));
        all_prec(5 * t); /* (a tie at one digit fewer) */
    }
    for (int k = -1080; k <= 1030; k++) { /* powers of 2 */
        double t = ldexp(1.0, k);
        all_prec(t);
        all_prec(nextafter(t, 0));
        all_prec(nextafter(t, INFINITY));
        all_prec(3 * t);
    }
    /* exact ties: integers ending in 5 one to four digits past the
     * precision, and halves of odd integers */
    for (int p = 1; p <= 17; p++)
        for (int i = 0; i < 2000; i++) {
            uint64_t r = next();
            for (int extra = 1; extra <= 4 && p + extra <= 16; extra++) {
                uint64_t span = 1;
                for (int d = 0; d < p + extra - 1; d++) span *= 10;
                uint64_t k = span + r % (9 * span);
                k = k - k % 10 + 5;
                check((double)k, p);
                check(-(double)k, p);
                for (int s = 1; s <= 8; s++) check(ldexp((double)k, -s), p);
            }
            check((double)(2 * (r % 100000000) + 1) / 2, p);
        }
    /* random bit patterns of doubles (every exponent) and of floats */
    for (int i = 0; i < 300000; i++) {
        uint64_t b = next();
        double d = of_bits(b);
        int p = 1 + (int)(next() % 17);
        check(d, p);
        check(d, 9);
        float fl;
        uint32_t fb = (uint32_t)(b >> 32);
        memcpy(&fl, &fb, sizeof fl);
        check((double)fl, 9);
        check((double)fl, 7);
    }
    /* what the OBJ writer prints: float coordinates in metres, double
     * heights (a float sample times a double scale), texture coordinates */
    for (int i = 0; i < 400000; i++) {
        double u = (double)(next() >> 11) * 0x1p-53;
        float x = (float)(u * 20000.0), t = (float)u, nrm = (float)(2 * u - 1);
        double h = (double)(float)((u - 0.2) * 3000.0) * (i & 1 ? 1.0 : 0.01 + u);
        check((double)x, 9);
        check(h, 10);
        check((double)t, 9);
        check(1.0 - (double)t, 9);
        check((double)nrm, 7);
    }
    /* every 97th float of [1024, 2048) and [0.5, 1) */
    for (uint32_t b = 0x44800000u; b < 0x45000000u; b += 97) {
        float fl;
        memcpy(&fl, &b, sizeof fl);
        check((double)fl, 9);
    }
    for (uint32_t b = 0x3F000000u; b < 0x3F800000u; b += 97) {
        float fl;
        memcpy(&fl, &b, sizeof fl);
        check((double)fl, 9);
        check((double)fl, 7);
    }
    static const unsigned long us[] = { 0ul, 1ul, 9ul, 10ul, 99ul, 100ul, 4294967295ul, 4294967296ul,
                                        (unsigned long)-1 };
    for (size_t i = 0; i < sizeof us / sizeof *us; i++) check_u(us[i]);
    for (int i = 0; i < 100000; i++) check_u((unsigned long)(next() >> (next() % 64)));
    printf("%llu passed, %llu failed\n", passed, failed);
    return failed != 0;
}
