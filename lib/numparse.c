/* Locale-independent decimal parsing for the PGM and road-file readers.
 *
 * strtod() follows the process locale (a host that set de_DE reads "2.5"
 * as 2), so the library parses numbers itself. The grammar is
 *     [+-] digits [. digits] [(e|E) [+-] digits]      (".5" and "5." too)
 * and nothing else: no hex, no inf/nan, no decimal comma.
 *
 * Results are correctly rounded (round-half-even), hence deterministic:
 * - fast path: at most 19 significant digits whose integer fits in 2^53
 *   and a power of ten that is exact in a double -> one IEEE operation;
 * - otherwise an estimate from the leading digits is corrected one ulp at
 *   a time by comparing the exact decimal value with the midpoints between
 *   neighbouring doubles in big-integer arithmetic. */
#include "internal.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* Significant digits kept. A double's midpoint needs at most 767 of them,
 * so dropping the rest and appending a single '1' when any dropped digit
 * was non-zero keeps every comparison on the correct side. */
#define RS__MAX_DIGITS 800

/* Big integers large enough for M * 2^1076 with an 801-digit M, and for
 * 2^54 * 10^1125 (the extremes the range checks below allow). */
#define RS__BIG_WORDS 136

typedef struct rs_big {
    uint32_t w[RS__BIG_WORDS]; /* little-endian words */
    int n;                     /* words in use; w[n-1] != 0 unless n == 0 */
    int overflow;              /* set if an operation did not fit (never expected) */
} rs_big;

static const double rs_pow10_exact[23] = {
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22
};

static void big_set_u64(rs_big *b, uint64_t v)
{
    b->n = 0;
    b->overflow = 0;
    while (v) {
        b->w[b->n++] = (uint32_t)v;
        v >>= 32;
    }
}

static void big_mul_add(rs_big *b, uint32_t mul, uint32_t add)
{
    uint64_t carry = add;
    for (int i = 0; i < b->n; i++) {
        uint64_t t = (uint64_t)b->w[i] * mul + carry;
        b->w[i] = (uint32_t)t;
        carry = t >> 32;
    }
    if (carry) {
        if (b->n == RS__BIG_WORDS) { b->overflow = 1; return; }
        b->w[b->n++] = (uint32_t)carry;
    }
}

static void big_mul_pow10(rs_big *b, int k)
{
    while (k >= 9) { big_mul_add(b, 1000000000u, 0); k -= 9; }
    static const uint32_t small[9] = { 1, 10, 100, 1000, 10000, 100000, 1000000, 10000000, 100000000 };
    if (k > 0) big_mul_add(b, small[k], 0);
}

static void big_shl(rs_big *b, int bits)
{
    if (b->n == 0 || bits <= 0) return;
    int words = bits / 32, rem = bits % 32;
    int nn = b->n + words + 1;
    if (nn > RS__BIG_WORDS) { b->overflow = 1; return; }
    b->w[nn - 1] = 0;
    for (int i = b->n - 1; i >= 0; i--) {
        uint32_t v = b->w[i];
        if (rem) {
            b->w[i + words + 1] |= v >> (32 - rem);
            b->w[i + words] = v << rem;
        } else {
            b->w[i + words] = v;
        }
    }
    for (int i = 0; i < words; i++) b->w[i] = 0;
    b->n = nn;
    while (b->n > 0 && b->w[b->n - 1] == 0) b->n--;
}

static int big_cmp(const rs_big *a, const rs_big *b)
{
    if (a->n != b->n) return a->n < b->n ? -1 : 1;
    for (int i = a->n - 1; i >= 0; i--)
        if (a->w[i] != b->w[i]) return a->w[i] < b->w[i] ? -1 : 1;
    return 0;
}

/* The exact decimal value digits[0..nd) * 10^e10, as a big integer. */
typedef struct rs_decimal {
    const char *digits;
    int nd;
    int e10;
} rs_decimal;

/* Compare the decimal value with a * 2^e2. Returns -1, 0, 1, or 2 when the
 * big integers would not fit (callers then give up). */
static int decimal_cmp(const rs_decimal *d, uint64_t a, int e2)
{
    rs_big lhs, rhs;
    big_set_u64(&lhs, 0);
    for (int i = 0; i < d->nd; i++) big_mul_add(&lhs, 10, (uint32_t)(d->digits[i] - '0'));
    big_set_u64(&rhs, a);
    if (d->e10 >= 0) big_mul_pow10(&lhs, d->e10);
    else big_mul_pow10(&rhs, -d->e10);
    if (e2 >= 0) big_shl(&rhs, e2);
    else big_shl(&lhs, -e2);
    if (lhs.overflow || rhs.overflow) return 2;
    return big_cmp(&lhs, &rhs);
}

/* Split a positive finite double into m * 2^e with m an integer. */
static void split_double(double z, uint64_t *m, int *e)
{
    int ex;
    double f = frexp(z, &ex); /* z = f * 2^ex, f in [0.5, 1) */
    if (ex - 53 < -1074) {
        *m = (uint64_t)ldexp(z, 1074);
        *e = -1074;
    } else {
        *m = (uint64_t)ldexp(f, 53);
        *e = ex - 53;
    }
}

/* Correctly rounded value of the decimal, starting from an estimate `z`.
 * Returns 0 if the value rounds to infinity. */
static int refine(const rs_decimal *d, double z, double *out)
{
    if (z == 0.0) z = ldexp(1.0, -1074);
    if (isinf(z)) z = DBL_MAX;
    for (int guard = 0; guard < 4096; guard++) {
        uint64_t m;
        int e;
        split_double(z, &m, &e);
        int c = decimal_cmp(d, 2 * m + 1, e - 1);
        if (c == 2) return 0;
        if (c > 0 || (c == 0 && (m & 1))) {
            double up = nextafter(z, HUGE_VAL);
            if (isinf(up)) return 0;
            if (c == 0) { *out = up; return 1; }
            z = up;
            continue;
        }
        if (c == 0) { *out = z; return 1; }
        /* Below the upper midpoint: check the lower one. Just above a power
         * of two the gap below is half the gap above. */
        int lc = (m == ((uint64_t)1 << 52) && e > -1074) ? decimal_cmp(d, 4 * m - 1, e - 2)
                                                        : decimal_cmp(d, 2 * m - 1, e - 1);
        if (lc == 2) return 0;
        if (lc < 0 || (lc == 0 && (m & 1))) {
            double down = nextafter(z, 0.0);
            if (lc == 0 || down == 0.0) { *out = down; return 1; }
            z = down;
            continue;
        }
        *out = z;
        return 1;
    }
    return 0; /* not reached for estimates within a few thousand ulps */
}

static int is_digit(char c) { return c >= '0' && c <= '9'; }

int rs__parse_double(const char *s, const char *end, double *out, const char **stop)
{
    const char *p = s;
    char digits[RS__MAX_DIGITS + 1];
    int nd = 0, any = 0, sticky = 0, neg = 0;
    long dp = 0; /* value = 0.digits * 10^dp */

    if (stop) *stop = s;
    if (p < end && (*p == '+' || *p == '-')) { neg = *p == '-'; p++; }
    for (; p < end && is_digit(*p); p++) {
        any = 1;
        if (nd == 0 && *p == '0') continue;
        if (nd < RS__MAX_DIGITS) digits[nd++] = *p;
        else if (*p != '0') sticky = 1;
        if (dp < 1000000) dp++;
    }
    if (p < end && *p == '.') {
        const char *q = p + 1;
        int frac = 0;
        for (; q < end && is_digit(*q); q++) {
            frac = 1;
            if (nd == 0 && *q == '0') { if (dp > -1000000) dp--; continue; }
            if (nd < RS__MAX_DIGITS) digits[nd++] = *q;
            else if (*q != '0') sticky = 1;
        }
        if (!any && !frac) return 0; /* "." or "-." */
        any = 1;
        p = q;
    }
    if (!any) return 0;
    if (p < end && (*p == 'e' || *p == 'E')) {
        const char *q = p + 1;
        int eneg = 0;
        long ev = 0;
        if (q < end && (*q == '+' || *q == '-')) { eneg = *q == '-'; q++; }
        if (q < end && is_digit(*q)) {
            for (; q < end && is_digit(*q); q++)
                if (ev < 1000000) ev = ev * 10 + (*q - '0');
            dp += eneg ? -ev : ev;
            p = q;
        } /* else "1e" / "1e+": the number ends before the 'e' */
    }
    if (stop) *stop = p;

    if (sticky) digits[nd++] = '1'; /* nd was RS__MAX_DIGITS */
    else while (nd > 0 && digits[nd - 1] == '0') nd--;
    if (nd == 0) { *out = neg ? -0.0 : 0.0; return 1; }
    if (dp > 310) return 0;                             /* >= 10^309 > DBL_MAX */
    if (dp < -324) { *out = neg ? -0.0 : 0.0; return 1; } /* < 10^-324: rounds to 0 */

    int e10 = (int)dp - nd; /* value = digits * 10^e10 */
    double v;
#if defined(FLT_EVAL_METHOD) && (FLT_EVAL_METHOD == 0 || FLT_EVAL_METHOD == 1)
    if (nd <= 19) {
        uint64_t m = 0;
        for (int i = 0; i < nd; i++) m = m * 10 + (uint64_t)(digits[i] - '0');
        if (m <= ((uint64_t)1 << 53)) {
            if (e10 >= 0 && e10 <= 22) {
                *out = neg ? -((double)m * rs_pow10_exact[e10]) : (double)m * rs_pow10_exact[e10];
                return 1;
            }
            if (e10 < 0 && e10 >= -22) {
                *out = neg ? -((double)m / rs_pow10_exact[-e10]) : (double)m / rs_pow10_exact[-e10];
                return 1;
            }
            /* 123e30 = (123 * 10^8) * 10^22 while the first factor stays exact */
            if (e10 > 22 && e10 <= 22 + 15) {
                uint64_t mm = m;
                int k = e10 - 22, ok = 1;
                for (int i = 0; i < k && ok; i++) {
                    if (mm > ((uint64_t)1 << 53) / 10) ok = 0;
                    else mm *= 10;
                }
                if (ok) {
                    v = (double)mm * 1e22;
                    *out = neg ? -v : v;
                    return 1;
                }
            }
        }
    }
#endif
    /* Estimate from the leading 19 digits, scaled through 2^600 so that
     * no intermediate leaves the normal range, then refine exactly. */
    {
        int k = nd < 19 ? nd : 19;
        uint64_t m = 0;
        for (int i = 0; i < k; i++) m = m * 10 + (uint64_t)(digits[i] - '0');
        int pe = (int)dp - k;
        double z = (double)m;
        if (pe >= 0) {
            while (pe >= 22) { z *= 1e22; pe -= 22; }
            z *= rs_pow10_exact[pe];
        } else {
            z = ldexp(z, 600);
            pe = -pe;
            while (pe >= 22) { z /= 1e22; pe -= 22; }
            z /= rs_pow10_exact[pe];
            z = ldexp(z, -600);
        }
        rs_decimal d;
        d.digits = digits;
        d.nd = nd;
        d.e10 = e10;
        if (!refine(&d, z, &v)) return 0;
    }
    *out = neg ? -v : v;
    return 1;
}
