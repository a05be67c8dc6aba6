/* Number text for the OBJ writer (cli/numfmt.h).
 *
 * A fine OBJ is hundreds of MB of "%.9g" text, and glibc's printf spent
 * 1.8 of a 2.2 s mesh run on it (multi-precision digits for every value).
 * %.Pg rounds the exact binary value to P significant digits, ties to even,
 * picks the fixed style when the rounded exponent X is in -4 <= X < P (else
 * the exponent style) and drops trailing zeros. Here the value is m 2^e
 * (m < 2^53), and q = m 2^e 10^(P-1-X) is worked out exactly in 128-bit
 * integers, with the side of one half its remainder lies on; values where
 * that does not fit (far from 1: below about 1e-14 or above 1e38 at P = 9),
 * NaN and infinities go to snprintf. */
#include "numfmt.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

static size_t slow_g(char *out, double v, int prec)
{
    char buf[64];
    int k = snprintf(buf, sizeof buf, "%.*g", prec, v);
    if (k < 0) k = 0;
    if (k > CLI_FMT_G_MAX) k = CLI_FMT_G_MAX; /* (cannot happen for prec <= 17) */
    memcpy(out, buf, (size_t)k);
    return (size_t)k;
}

#ifdef __SIZEOF_INT128__
__extension__ typedef unsigned __int128 u128;

static const uint64_t p10[20] = { 1ull, 10ull, 100ull, 1000ull, 10000ull, 100000ull, 1000000ull, 10000000ull,
                                  100000000ull, 1000000000ull, 10000000000ull, 100000000000ull, 1000000000000ull,
                                  10000000000000ull, 100000000000000ull, 1000000000000000ull,
                                  10000000000000000ull, 100000000000000000ull, 1000000000000000000ull,
                                  10000000000000000000ull };

static u128 pow10_128(int j) { return j < 20 ? (u128)p10[j] : (u128)p10[j - 19] * p10[19]; }

static int bits128(u128 x)
{
    uint64_t h = (uint64_t)(x >> 64), l = (uint64_t)x;
    return h ? 128 - __builtin_clzll(h) : l ? 64 - __builtin_clzll(l) : 0;
}

/* q = floor(m 2^e 10^j), and *half = -1, 0 or 1 as the rest is below, at
 * or above one half; 0 when a number would not fit in 127 bits. */
static int scaled(uint64_t m, int e, int j, u128 *q, int *half)
{
    if (j >= 0) {
        if (j > 38) return 0;
        u128 t = pow10_128(j);
        if (bits128(t) + 53 > 127) return 0;
        u128 num = (u128)m * t;
        if (e >= 0) {
            if (bits128(num) + e > 127) return 0;
            *q = num << e;
            *half = -1;
            return 1;
        }
        int s = -e;
        if (s > 126) return 0;
        *q = num >> s;
        u128 r = num - (*q << s), h = (u128)1 << (s - 1);
        *half = r < h ? -1 : r > h ? 1 : 0;
        return 1;
    }
    int k = -j;
    if (k > 38) return 0;
    u128 den = pow10_128(k), num = m;
    if (e >= 0) {
        if (53 + e > 127) return 0;
        num <<= e;
    } else {
        if (bits128(den) + -e > 126) return 0;
        den <<= -e;
    }
    *q = num / den;
    u128 r2 = (num - *q * den) << 1; /* (den < 2^126: no overflow) */
    *half = r2 < den ? -1 : r2 > den ? 1 : 0;
    return 1;
}

size_t cli_fmt_g(char *out, double v, int prec)
{
    if (prec < 1 || prec > 17 || !isfinite(v)) return slow_g(out, v, prec);
    size_t n = 0;
    if (signbit(v)) out[n++] = '-';
    double a = fabs(v);
    if (a == 0) {
        out[n++] = '0';
        return n;
    }
    int ex;
    double f = frexp(a, &ex); /* a = f 2^ex, f in [0.5, 1): f 2^53 is an integer */
    uint64_t m = (uint64_t)ldexp(f, 53);
    int e = ex - 53;
    /* 2^(ex-1) <= a < 2^ex: floor(log10 a) is X or X + 1 ((ex - 1) log10 2
     * is never within the product's rounding of an integer) */
    int X = (int)floor((double)(ex - 1) * 0.30102999566398119521);
    const uint64_t lo = p10[prec - 1], hi = p10[prec];
    u128 q;
    int half;
    if (!scaled(m, e, prec - 1 - X, &q, &half)) return slow_g(out, v, prec);
    if (q >= hi) {
        X++;
        if (!scaled(m, e, prec - 1 - X, &q, &half)) return slow_g(out, v, prec);
    }
    if (q < lo || q >= hi) return slow_g(out, v, prec); /* (cannot happen: see above) */
    uint64_t d64 = (uint64_t)q;
    if (half > 0 || (half == 0 && (d64 & 1))) d64++;
    if (d64 == hi) d64 = lo, X++;
    char d[20];
    for (int i = prec - 1; i >= 0; i--) {
        d[i] = (char)('0' + d64 % 10);
        d64 /= 10;
    }
    int nd = prec; /* the digits that are not trailing zeros */
    while (nd > 1 && d[nd - 1] == '0') nd--;
    if (X < -4 || X >= prec) {
        out[n++] = d[0];
        if (nd > 1) {
            out[n++] = '.';
            memcpy(out + n, d + 1, (size_t)nd - 1);
            n += (size_t)nd - 1;
        }
        out[n++] = 'e';
        out[n++] = X < 0 ? '-' : '+';
        unsigned x = (unsigned)(X < 0 ? -X : X);
        if (x >= 100) {
            out[n++] = (char)('0' + x / 100);
            x %= 100;
        }
        out[n++] = (char)('0' + x / 10);
        out[n++] = (char)('0' + x % 10);
        return n;
    }
    if (X >= 0) {
        memcpy(out + n, d, (size_t)X + 1);
        n += (size_t)X + 1;
        if (nd > X + 1) {
            out[n++] = '.';
            memcpy(out + n, d + X + 1, (size_t)(nd - X - 1));
            n += (size_t)(nd - X - 1);
        }
        return n;
    }
    out[n++] = '0';
    out[n++] = '.';
    for (int i = 0; i < -X - 1; i++) out[n++] = '0';
    memcpy(out + n, d, (size_t)nd);
    return n + (size_t)nd;
}
#else
size_t cli_fmt_g(char *out, double v, int prec) { return slow_g(out, v, prec); }
#endif

size_t cli_fmt_u(char *out, unsigned long v)
{
    char t[24];
    size_t n = 0;
    do {
        t[n++] = (char)('0' + v % 10);
        v /= 10;
    } while (v);
    for (size_t i = 0; i < n; i++) out[i] = t[n - 1 - i];
    return n;
}
