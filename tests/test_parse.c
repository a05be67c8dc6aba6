/* Parsers: numbers (locale-independent, correctly rounded), PGM P2/P5 and
 * the road text format. Every bad input must give a clean rs_result and a
 * message naming the problem; allocation failures at every point must leak
 * nothing. */
#include "harness.h"
#include "internal.h"
#include "roadsplat.h"

#include <locale.h>
#include <stdint.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>

/* ---- counting, failure-injecting allocator ------------------------------ */
typedef struct test_alloc {
    long live;      /* blocks currently allocated */
    long calls;     /* malloc + realloc calls so far */
    long fail_at;   /* fail the call with this number (1-based); 0 = never */
    size_t largest; /* largest request seen */
} test_alloc;

static void *ta_malloc(void *u, size_t n)
{
    test_alloc *a = u;
    a->calls++;
    if (n > a->largest) a->largest = n;
    if (a->fail_at && a->calls == a->fail_at) return NULL;
    void *p = malloc(n);
    if (p) a->live++;
    return p;
}

static void *ta_realloc(void *u, void *p, size_t n)
{
    test_alloc *a = u;
    a->calls++;
    if (n > a->largest) a->largest = n;
    if (a->fail_at && a->calls == a->fail_at) return NULL;
    void *q = realloc(p, n);
    if (q && !p) a->live++;
    return q;
}

static void ta_free(void *u, void *p)
{
    test_alloc *a = u;
    a->live--;
    free(p);
}

static rs_ctx *make_ctx(test_alloc *a, const rs_limits *lim)
{
    memset(a, 0, sizeof *a);
    rs_allocator al = { ta_malloc, ta_realloc, ta_free, a };
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(&al, lim, &ctx) != RS_OK) return NULL;
    return ctx;
}

static int contains(const char *hay, const char *needle) { return strstr(hay, needle) != NULL; }

/* ---- numbers ------------------------------------------------------------- */
static int num(const char *s, double *v, size_t *used)
{
    const char *stop;
    int ok = rs__parse_double(s, s + strlen(s), v, &stop);
    *used = (size_t)(stop - s);
    return ok;
}

static void test_numbers(void)
{
    double v;
    size_t used;
    CHECK(num("2.5", &v, &used) && v == 2.5 && used == 3);
    CHECK(num("-1e3", &v, &used) && v == -1000.0 && used == 4);
    CHECK(num("+.5", &v, &used) && v == 0.5);
    CHECK(num("5.", &v, &used) && v == 5.0 && used == 2);
    CHECK(num("0.1", &v, &used) && v == 0.1);
    CHECK(num("1e-400", &v, &used) && v == 0.0);
    CHECK(num("-0", &v, &used) && v == 0.0 && signbit(v));
    CHECK(num("4.9406564584124654e-324", &v, &used) && v > 0 && v == nextafter(0.0, 1.0));
    CHECK(num("1.7976931348623157e308", &v, &used) && v == 1.7976931348623157e308);
    CHECK(!num("1e999", &v, &used));
    CHECK(!num("1.7976931348623159e308", &v, &used)); /* rounds to infinity */
    CHECK(!num("inf", &v, &used) && used == 0);
    CHECK(!num("nan", &v, &used) && used == 0);
    CHECK(!num(".", &v, &used) && used == 0);
    CHECK(!num("-", &v, &used));
    CHECK(!num("", &v, &used));
    CHECK(num("2,5", &v, &used) && v == 2.0 && used == 1); /* stops at the comma */
    CHECK(num("0x10", &v, &used) && v == 0.0 && used == 1); /* no hex */
    CHECK(num("1e", &v, &used) && v == 1.0 && used == 1);   /* dangling exponent not consumed */
    /* halfway cases round to even */
    CHECK(num("9007199254740993", &v, &used) && v == 9007199254740992.0);
    CHECK(num("9007199254740995", &v, &used) && v == 9007199254740996.0);
    CHECK(num("9007199254740993.0000000000000000000000000000001", &v, &used) && v == 9007199254740994.0);
    /* the end pointer bounds the scan: "12345" read as "12" */
    { const char *s = "12345", *stop; CHECK(rs__parse_double(s, s + 2, &v, &stop) && v == 12.0 && stop == s + 2); }

    /* Property: agrees bit for bit with the C library's correctly rounded
     * strtod (we are in the "C" locale here) on random decimal strings. */
    uint64_t st = 0x9E3779B97F4A7C15ull;
    int bad = 0;
    char buf[128];
    for (int it = 0; it < 20000; it++) {
        st ^= st << 13; st ^= st >> 7; st ^= st << 17;
        uint64_t bits = st >> 1;
        double d;
        memcpy(&d, &bits, sizeof d);
        if (!isfinite(d)) continue;
        snprintf(buf, sizeof buf, "%.*g", (int)(1 + st % 20), d);
        double ours, ref = strtod(buf, NULL);
        if (!num(buf, &ours, &used) || memcmp(&ours, &ref, sizeof ours) != 0) bad++;
    }
    CHECK_EQ_INT(bad, 0);
}

/* A host program that switched to a decimal-comma locale must still read
 * "2.5". tests/run.sh builds de_DE.UTF-8 (LOCPATH) when the machine has
 * none; without any, this prints a SKIP line and counts nothing. */
static void test_locale(void)
{
    const char *names[] = { "de_DE.UTF-8", "de_DE.utf8", "de_DE", "fr_FR.UTF-8", NULL };
    const char *got = NULL;
    for (int i = 0; names[i] && !got; i++) got = setlocale(LC_ALL, names[i]);
    if (!got || strcmp(localeconv()->decimal_point, ",") != 0) {
        printf("SKIP test_locale: no decimal-comma locale loads (run via tests/run.sh, which builds de_DE.UTF-8 "
               "with localedef, or install one)\n");
    } else {
        double v;
        size_t used;
        /* the locale really bites: the C library now stops at the '.' */
        CHECK(strtod("2.5", NULL) == 2.0);
        CHECK(num("2.5", &v, &used) && v == 2.5 && used == 3);
        CHECK(!num("2,5", &v, &used) || used != 3);
        rs_ctx *ctx;
        rs_ctx_create(NULL, NULL, &ctx);
        const char *txt = "road a width 2.5\n0.5 1.25\n3 4\nend\n";
        rs_roads *r = NULL;
        CHECK(rs_roads_parse(ctx, txt, strlen(txt), &r) == RS_OK);
        double w = 0;
        const double *xy = NULL;
        if (r) rs_roads_get(r, 0, NULL, &w, &xy, NULL);
        CHECK(w == 2.5 && xy && xy[0] == 0.5 && xy[1] == 1.25);
        rs_roads_free(ctx, r);
        /* ...and the locale does not widen the grammar either */
        const char *comma = "road a width 2,5\n0 0\n3 4\nend\n";
        r = (rs_roads *)1;
        CHECK(rs_roads_parse(ctx, comma, strlen(comma), &r) == RS_ERR_PARSE && r == NULL);
        rs_ctx_free(ctx);
    }
    setlocale(LC_ALL, "C");
}

/* ---- PGM ----------------------------------------------------------------- */
static rs_result pgm(rs_ctx *ctx, const void *data, size_t n, rs_dem **out)
{
    return rs_dem_parse_pgm(ctx, data, n, out);
}

static rs_result pgm_s(rs_ctx *ctx, const char *s, rs_dem **out) { return pgm(ctx, s, strlen(s), out); }

static void pgm_bad(rs_ctx *ctx, const void *data, size_t n, rs_result want, const char *a, const char *b)
{
    rs_dem *d = (rs_dem *)1;
    rs_result rc = pgm(ctx, data, n, &d);
    const char *m = rs_ctx_message(ctx);
    CHECKF(rc == want && d == NULL, "got %d want %d (%s)", rc, want, m);
    CHECKF(m[0] != '\0' && (!a || contains(m, a)) && (!b || contains(m, b)), "message '%s' lacks '%s' / '%s'", m,
           a ? a : "", b ? b : "");
}

static void pgm_bad_s(rs_ctx *ctx, const char *s, rs_result want, const char *a, const char *b)
{
    pgm_bad(ctx, s, strlen(s), want, a, b);
}

#define PGM_BAD_LIT(ctx, lit, want, a, b) pgm_bad(ctx, lit, sizeof lit - 1, want, a, b)

static void test_pgm(void)
{
    test_alloc ta;
    rs_ctx *ctx = make_ctx(&ta, NULL);
    rs_dem *d = NULL;

    /* P2 with comments in every place whitespace may go */
    const char *p2 = "P2# after magic\n# full line\n3 # w\n2\n# before maxval\n 9# after maxval\n"
                     "1 2 3 # row 0\n# between rows\n4\t5\r\n6# last\n\n";
    CHECK(pgm_s(ctx, p2, &d) == RS_OK);
    if (d) {
        CHECK(rs_dem_width(d) == 3 && rs_dem_height(d) == 2);
        const float *z = rs_dem_samples(d);
        int ok = 1;
        for (int i = 0; i < 6; i++) ok &= z[i] == (float)(i + 1);
        CHECK(ok);
        /* the range the parser keeps (rs__dem_seal_range) */
        double lo = -1, hi = -1;
        int nd = -1;
        rs_dem_height_range(d, &lo, &hi, &nd);
        CHECKF(lo == 1 && hi == 6 && nd == 0, "P2 range %g %g %d", lo, hi, nd);
        rs_dem_free(ctx, d);
    }
    CHECK(rs_ctx_message(ctx)[0] == '\0');
    /* P5, 16 bits: the range from the samples as they come; and a DEM
     * made from floats keeps its range and nodata (NaN) */
    {
        const unsigned char p5[] = { 'P', '5', ' ', '2', ' ', '2', ' ', '6', '5', '5', '3', '5', '\n',
                                     0x01, 0x02, 0xff, 0x00, 0x00, 0x07, 0x12, 0x34 };
        CHECK(pgm(ctx, p5, sizeof p5, &d) == RS_OK);
        if (d) {
            double lo = -1, hi = -1;
            int nd = -1;
            rs_dem_height_range(d, &lo, &hi, &nd);
            CHECKF(lo == 7 && hi == 0xff00 && nd == 0, "P5 range %g %g %d", lo, hi, nd);
            rs_dem_free(ctx, d);
        }
        const float zf[] = { 3.5f, NAN, -2.25f, 8 };
        CHECK(rs_dem_create(ctx, 2, 2, zf, &d) == RS_OK);
        if (d) {
            double lo = -1, hi = -1;
            int nd = -1;
            rs_dem_height_range(d, &lo, &hi, &nd);
            CHECKF(lo == -2.25 && hi == 8 && nd == 1, "float range %g %g %d", lo, hi, nd);
            rs_dem_free(ctx, d);
        }
    }

    /* P5 8-bit, and a comment right after maxval ending the header */
    {
        const unsigned char b[] = "P5 2 2 255#c\n\x00\x7f\x80\xff";
        CHECK(pgm(ctx, b, sizeof b - 1, &d) == RS_OK);
        if (d) {
            const float *z = rs_dem_samples(d);
            CHECK(z[0] == 0 && z[1] == 127 && z[2] == 128 && z[3] == 255);
            rs_dem_free(ctx, d);
        }
    }
    /* P5 16-bit big-endian */
    {
        const unsigned char b[] = "P5\n2 2\n65535\n\x01\x02\xff\xfe\x00\x01\x80\x00";
        CHECK(pgm(ctx, b, sizeof b - 1, &d) == RS_OK);
        if (d) {
            const float *z = rs_dem_samples(d);
            CHECK_EQ_INT(z[0], 258);
            CHECK_EQ_INT(z[1], 65534);
            CHECK_EQ_INT(z[2], 1);
            CHECK_EQ_INT(z[3], 32768);
            rs_dem_free(ctx, d);
        }
    }
    /* 16-bit with maxval 1000 (still 2 bytes), trailing newline accepted */
    {
        const unsigned char b[] = "P5 2 2 1000\n\x03\xe8\x00\x00\x01\x00\x00\x10\n";
        CHECK(pgm(ctx, b, sizeof b - 1, &d) == RS_OK);
        if (d) { CHECK(rs_dem_samples(d)[0] == 1000 && rs_dem_samples(d)[2] == 256); rs_dem_free(ctx, d); }
    }
    /* maxval 1 (bit images are PGM too) and P2 without a final newline */
    CHECK(pgm_s(ctx, "P2 2 2 1 0 1 1 0", &d) == RS_OK);
    rs_dem_free(ctx, d);

    /* bad headers */
    pgm_bad_s(ctx, "", RS_ERR_PARSE, "PGM", NULL);
    pgm_bad_s(ctx, "P", RS_ERR_PARSE, "P2", NULL);
    pgm_bad_s(ctx, "P6 2 2 255\n", RS_ERR_PARSE, "P5", NULL);
    pgm_bad_s(ctx, "P2 2 2 0\n0 0 0 0\n", RS_ERR_PARSE, "maxval 0", NULL);
    pgm_bad_s(ctx, "P2 2 2 65536\n0 0 0 0\n", RS_ERR_PARSE, "maxval 65536", NULL);
    pgm_bad_s(ctx, "P2 1 5 9\n0 0 0 0 0\n", RS_ERR_PARSE, "1x5", ">= 2");
    pgm_bad_s(ctx, "P2\n2\n2\n0\n0 0 0 0\n", RS_ERR_PARSE, "line 4", "maxval 0");
    pgm_bad_s(ctx, "P2\n# c\n1 5 9\n0 0 0 0 0\n", RS_ERR_PARSE, "line 3", "1x5");
    pgm_bad_s(ctx, "P2 0 0 9\n", RS_ERR_PARSE, ">= 2", NULL);
    pgm_bad_s(ctx, "P2 99999999999999999999999 2 9\n", RS_ERR_PARSE, "width", "too large");
    pgm_bad_s(ctx, "P5 4294967296 4294967296 255\n", RS_ERR_LIMIT, "limit", NULL);
    pgm_bad_s(ctx, "P5 16385 2 255\n", RS_ERR_LIMIT, "16385", NULL);
    pgm_bad_s(ctx, "P2 2 -2 9\n", RS_ERR_PARSE, "height", "'-'");
    pgm_bad_s(ctx, "P2 2 2.5 9\n", RS_ERR_PARSE, "'.'", "height");
    pgm_bad_s(ctx, "P2 2 2", RS_ERR_PARSE, "maxval", "missing");
    pgm_bad_s(ctx, "P22 2 9\n", RS_ERR_PARSE, "whitespace", NULL);
    /* truncated data, caught before allocating the raster */
    ta.largest = 0;
    pgm_bad_s(ctx, "P5 16384 16384 255\n\x01\x02", RS_ERR_PARSE, "truncated", NULL);
    pgm_bad_s(ctx, "P2 16384 16384 65535\n1 2 3\n", RS_ERR_PARSE, "truncated", NULL);
    CHECKF(ta.largest < 4096, "largest allocation %zu", ta.largest);
    PGM_BAD_LIT(ctx, "P5 2 2 65535\n\x00\x01\x00\x02\x00\x03\x00", RS_ERR_PARSE, "truncated", "sample 3");
    pgm_bad_s(ctx, "P5 2 2 255\n", RS_ERR_PARSE, "truncated", NULL);
    pgm_bad_s(ctx, "P2 2 2 9\n1 2 3", RS_ERR_PARSE, "truncated", "3 of 4");
    /* samples above maxval, garbage, trailing data */
    pgm_bad_s(ctx, "P2 2 2 10\n1 2\n11 3\n", RS_ERR_PARSE, "sample 2 (row 1, column 0) is 11", "line 3");
    pgm_bad_s(ctx, "P2 2 2 10\n1 2 3 99999999999999999999999\n", RS_ERR_PARSE, "sample 3", "above maxval");
    pgm_bad_s(ctx, "P5 2 2 100\n\x01\x02\x65\x03", RS_ERR_PARSE, "sample 2", "101");
    PGM_BAD_LIT(ctx, "P5 2 2 300\n\x00\x01\x01\x2d\x00\x00\x00\x00", RS_ERR_PARSE, "sample 1", "301");
    pgm_bad_s(ctx, "P2 2 2 10\n1 2\nx 3\n", RS_ERR_PARSE, "line 3", "'x'");
    pgm_bad_s(ctx, "P2 2 2 10\n1 2 3.5 4\n", RS_ERR_PARSE, "sample 2", "'.'");
    pgm_bad_s(ctx, "P2 2 2 10\n1 2 3 4 5\n", RS_ERR_PARSE, "'5'", "after the last");
    pgm_bad_s(ctx, "P5 2 2 255\n\x01\x02\x03\x04junk", RS_ERR_PARSE, "after the last sample", NULL);
    pgm_bad_s(ctx, "P2 2 2 10\n1 2 3 -4\n", RS_ERR_PARSE, "'-'", NULL);
    {
        const char nul[] = "P2 2 2 10\n1 2\0 3 4\n";
        pgm_bad(ctx, nul, sizeof nul - 1, RS_ERR_PARSE, "0x00", NULL);
    }
    /* tighter limits */
    {
        rs_limits lim;
        memset(&lim, 0, sizeof lim);
        lim.max_dem_side = 4;
        rs_ctx *c2;
        rs_ctx_create(NULL, &lim, &c2);
        pgm_bad_s(c2, "P2 5 2 9\n0 0 0 0 0 0 0 0 0 0\n", RS_ERR_LIMIT, "5x2", "4");
        CHECK(pgm_s(c2, "P2 4 2 9\n0 0 0 0 0 0 0 0\n", &d) == RS_OK);
        rs_dem_free(c2, d);
        rs_ctx_free(c2);
    }
    /* argument checks */
    CHECK(rs_dem_parse_pgm(ctx, "P2", 2, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_dem_parse_pgm(NULL, "P2", 2, &d) == RS_ERR_INVALID_ARG && d == NULL);

    /* rs_dem_create: NaN kept as nodata, infinities rejected */
    {
        float z[6] = { 1, 2, 3, 4, 5, 6 };
        z[4] = NAN;
        CHECK(rs_dem_create(ctx, 3, 2, z, &d) == RS_OK);
        if (d) { CHECK(isnan(rs_dem_samples(d)[4]) && rs_dem_samples(d)[5] == 6); rs_dem_free(ctx, d); }
        z[1] = INFINITY;
        CHECK(rs_dem_create(ctx, 3, 2, z, &d) == RS_ERR_INVALID_ARG && d == NULL);
        CHECK(contains(rs_ctx_message(ctx), "sample 1"));
        z[1] = -INFINITY;
        CHECK(rs_dem_create(ctx, 3, 2, z, &d) == RS_ERR_INVALID_ARG);
        CHECK(rs_dem_create(ctx, 1, 6, z, &d) == RS_ERR_INVALID_ARG);
        CHECK(rs_dem_create(ctx, 3, 2, NULL, &d) == RS_ERR_INVALID_ARG);
        CHECK(rs_dem_create(ctx, 20000, 2, z, &d) == RS_ERR_LIMIT);
    }
    /* Property: P2 and P5 of the same random raster give the same DEM */
    {
        uint64_t st = 12345;
        int same = 1;
        for (int t = 0; t < 20; t++) {
            unsigned w = 2 + t % 7, h = 2 + (t * 3) % 5, maxval = t % 2 ? 65535 : 200 + t;
            char txt[4096];
            unsigned char bin[1024];
            int o = snprintf(txt, sizeof txt, "P2\n%u %u\n%u\n", w, h, maxval);
            int bo = snprintf((char *)bin, sizeof bin, "P5 %u %u %u\n", w, h, maxval);
            for (unsigned i = 0; i < w * h; i++) {
                st ^= st << 13; st ^= st >> 7; st ^= st << 17;
                unsigned v = (unsigned)(st % (maxval + 1u));
                o += snprintf(txt + o, sizeof txt - (size_t)o, "%u%s", v, (i + 1) % w ? " " : "\n");
                if (maxval > 255) bin[bo++] = (unsigned char)(v >> 8);
                bin[bo++] = (unsigned char)v;
            }
            rs_dem *a = NULL, *b = NULL;
            if (pgm(ctx, txt, (size_t)o, &a) != RS_OK || pgm(ctx, bin, (size_t)bo, &b) != RS_OK) same = 0;
            else same &= memcmp(rs_dem_samples(a), rs_dem_samples(b), w * h * sizeof(float)) == 0;
            rs_dem_free(ctx, a);
            rs_dem_free(ctx, b);
        }
        CHECK(same);
    }
    CHECK_EQ_INT(ta.live, 1); /* only the context itself */
    rs_ctx_free(ctx);
    CHECK_EQ_INT(ta.live, 0);
}

/* ---- roads --------------------------------------------------------------- */
static rs_result roads_s(rs_ctx *ctx, const char *s, rs_roads **out) { return rs_roads_parse(ctx, s, strlen(s), out); }

static void roads_bad_n(rs_ctx *ctx, const char *s, size_t n, rs_result want, const char *a, const char *b)
{
    rs_roads *r = (rs_roads *)1;
    rs_result rc = rs_roads_parse(ctx, s, n, &r);
    const char *m = rs_ctx_message(ctx);
    CHECKF(rc == want && r == NULL, "got %d want %d (%s)", rc, want, m);
    CHECKF(strncmp(m, "line ", 5) == 0 && (!a || contains(m, a)) && (!b || contains(m, b)),
           "message '%s' lacks 'line' / '%s' / '%s'", m, a ? a : "", b ? b : "");
}

static void roads_bad(rs_ctx *ctx, const char *s, rs_result want, const char *a, const char *b)
{
    roads_bad_n(ctx, s, strlen(s), want, a, b);
}

static void test_roads(void)
{
    test_alloc ta;
    rs_ctx *ctx = make_ctx(&ta, NULL);
    rs_roads *r = NULL;
    const char *name;
    double w;
    const double *xy;
    size_t n;

    const char *good = "\xEF\xBB\xBF# two roads\r\n"
                       "\r\n"
                       "  road Main_St width 7.5   # comment\r\n"
                       "\t0 0\r\n"
                       "10.25 -3e1 # x y\r\n"
                       "10.25 -3e1\r\n" /* duplicate point: valid */
                       "0 0\r\n"        /* 180-degree reversal: valid */
                       "end\r\n"
                       "road Stra\xC3\x9F" "e width 4\n"
                       "0.1 0.2\n1 1\n2 0\n0.1 0.2\n" /* closed loop */
                       "end"; /* no final newline */
    CHECK(roads_s(ctx, good, &r) == RS_OK);
    CHECK_EQ_INT(rs_roads_count(r), 2);
    if (r && rs_roads_count(r) == 2) {
        rs_roads_get(r, 0, &name, &w, &xy, &n);
        CHECK(strcmp(name, "Main_St") == 0 && w == 7.5 && n == 4);
        CHECK(xy[0] == 0 && xy[1] == 0 && xy[2] == 10.25 && xy[3] == -30 && xy[4] == 10.25 && xy[6] == 0);
        rs_roads_get(r, 1, &name, &w, &xy, &n);
        CHECK(strcmp(name, "Stra\xC3\x9F" "e") == 0 && w == 4 && n == 4);
        CHECK(xy[0] == 0.1 && xy[1] == 0.2 && xy[6] == 0.1);
        CHECK(rs_roads_get(r, 2, &name, &w, &xy, &n) == RS_ERR_INVALID_ARG);
    }
    rs_roads_free(ctx, r);

    /* empty and comment-only files are valid, with no roads */
    CHECK(rs_roads_parse(ctx, NULL, 0, &r) == RS_OK && rs_roads_count(r) == 0);
    rs_roads_free(ctx, r);
    CHECK(roads_s(ctx, "# nothing\n\n   \n", &r) == RS_OK && rs_roads_count(r) == 0);
    rs_roads_free(ctx, r);
    CHECK(roads_s(ctx, "road a width 1#c\n0 0#c\n1 1\nend#c", &r) == RS_OK && rs_roads_count(r) == 1);
    rs_roads_free(ctx, r);

    roads_bad(ctx, "foo 1 2\n", RS_ERR_PARSE, "line 1", "'foo'");
    roads_bad(ctx, "\n\n1 2\n", RS_ERR_PARSE, "line 3", "outside a road");
    roads_bad(ctx, "road a width 2\n0 0\n1 1\nroad b width 3\n", RS_ERR_PARSE, "line 4", "'a' (line 1)");
    roads_bad(ctx, "road a width 2\n0 0\n1 1\n", RS_ERR_PARSE, "line 3", "'a' (started on line 1) has no 'end'");
    roads_bad(ctx, "road a width 2\r\n0 0\r\n1 1", RS_ERR_PARSE, "no 'end'", NULL);
    roads_bad(ctx, "road\n", RS_ERR_PARSE, "line 1", "name");
    roads_bad(ctx, "road a\n", RS_ERR_PARSE, "'a'", "width");
    roads_bad(ctx, "road a width\n", RS_ERR_PARSE, "'a'", "width value is missing");
    roads_bad(ctx, "road a Width 2\n", RS_ERR_PARSE, "expected 'width'", "'Width'");
    roads_bad(ctx, "road a width 0\n", RS_ERR_PARSE, "'0'", "> 0");
    roads_bad(ctx, "road a width -3\n", RS_ERR_PARSE, "'-3'", "> 0");
    roads_bad(ctx, "road a width -0\n", RS_ERR_PARSE, "'-0'", "> 0");
    roads_bad(ctx, "road a width nan\n", RS_ERR_PARSE, "'nan'", "not a number");
    roads_bad(ctx, "road a width NaN\n", RS_ERR_PARSE, "'NaN'", "not a number");
    roads_bad(ctx, "road a width inf\n", RS_ERR_PARSE, "'inf'", "not a number");
    roads_bad(ctx, "road a width -infinity\n", RS_ERR_PARSE, "'-infinity'", NULL);
    roads_bad(ctx, "road a width 1e999\n", RS_ERR_PARSE, "'1e999'", "out of range");
    roads_bad(ctx, "road a width 2,5\n", RS_ERR_PARSE, "'2,5'", "decimal point");
    roads_bad(ctx, "road a width 0x10\n", RS_ERR_PARSE, "'0x10'", NULL);
    roads_bad(ctx, "road a width 2 lanes\n", RS_ERR_PARSE, "extra token", "'lanes'");
    roads_bad(ctx, "road a width 2\n0 0\nend\n", RS_ERR_PARSE, "line 3", "'a' (line 1) has 1 point;");
    roads_bad(ctx, "road a width 2\nend\n", RS_ERR_PARSE, "'a'", "0 points");
    roads_bad(ctx, "road a width 2\n0 abc\nend\n", RS_ERR_PARSE, "line 2", "'abc'");
    roads_bad(ctx, "road a width 2\n0 0\nnan 5\nend\n", RS_ERR_PARSE, "line 3", "x 'nan' is not a number");
    roads_bad(ctx, "road a width 2\n0 0\n1 inf\nend\n", RS_ERR_PARSE, "line 3", "y 'inf' is not a number");
    roads_bad(ctx, "road a\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9"
                   "\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9\xC3\xA9x width 2\n0 0\n",
              RS_ERR_PARSE, "\xC3\xA9\xC3\xA9...'", "no 'end'");
    roads_bad(ctx, "road a width 2\n0\nend\n", RS_ERR_PARSE, "line 2", "'X Y'");
    roads_bad(ctx, "road a width 2\n1 2 3\nend\n", RS_ERR_PARSE, "line 2", "extra token '3'");
    roads_bad(ctx, "road a width 2\n1,5 2\nend\n", RS_ERR_PARSE, "'1,5'", "decimal point");
    roads_bad(ctx, "road a width 2\n1e999 2\nend\n", RS_ERR_PARSE, "'1e999'", "out of range");
    roads_bad(ctx, "road a width 2\n1 -1e400x\nend\n", RS_ERR_PARSE, "'-1e400x'", NULL);
    roads_bad(ctx, "road a width 2\n0 0\n1 1\nend now\n", RS_ERR_PARSE, "line 4", "'now'");
    roads_bad(ctx, "end\n", RS_ERR_PARSE, "line 1", "without");
    roads_bad(ctx, "road a width 2\n0 0\n1 1\nEND\n", RS_ERR_PARSE, "'END'", "unknown keyword");
    {
        const char nul[] = "road a width 2\n0 \0 0\nend\n";
        roads_bad_n(ctx, nul, sizeof nul - 1, RS_ERR_PARSE, "line 2", "NUL");
    }
    roads_bad(ctx, "road a width 2\n\x01\x02\x03\n", RS_ERR_PARSE, "line 2", "control character 0x01");
    roads_bad(ctx, "# ok\n\xff\xfe\x89PNG\n", RS_ERR_PARSE, "line 2", "UTF-8");
    roads_bad(ctx, "road a\rwidth 2\n", RS_ERR_PARSE, "line 1", "0x0d");
    /* limits */
    {
        rs_limits lim;
        memset(&lim, 0, sizeof lim);
        lim.max_line_length = 16;
        lim.max_points = 3;
        rs_ctx *c2;
        rs_ctx_create(NULL, &lim, &c2);
        roads_bad(c2, "road a width 2\n0 0\n1 1 # a comment that is long\nend\n", RS_ERR_LIMIT, "line 3", "16 bytes");
        roads_bad(c2, "road a width 2\n0 0\n1 1\nend\nroad b width 2\n0 0\n1 1\nend\n", RS_ERR_LIMIT, "line 7",
                  "3 road points");
        CHECK(roads_s(c2, "road a width 2\n0 0\n1 1\n2 2\nend\n", &r) == RS_OK);
        rs_roads_free(c2, r);
        rs_ctx_free(c2);
    }
    CHECK(rs_roads_parse(ctx, "x", 1, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_parse(NULL, "x", 1, &r) == RS_ERR_INVALID_ARG);

    /* rs_roads_add */
    CHECK(rs_roads_create(ctx, &r) == RS_OK);
    {
        double pts[6] = { 0, 0, 5, 5, 10, 0 };
        CHECK(rs_roads_add(ctx, r, "x", 3, pts, 3) == RS_OK);
        CHECK(rs_roads_add(ctx, r, NULL, 2, pts, 2) == RS_OK);
        CHECK(rs_roads_add(ctx, r, "bad", 0, pts, 3) == RS_ERR_INVALID_ARG);
        CHECK(rs_roads_add(ctx, r, "bad", NAN, pts, 3) == RS_ERR_INVALID_ARG);
        CHECK(rs_roads_add(ctx, r, "bad", INFINITY, pts, 3) == RS_ERR_INVALID_ARG);
        CHECK(rs_roads_add(ctx, r, "bad", 1, pts, 1) == RS_ERR_INVALID_ARG);
        pts[3] = NAN;
        CHECK(rs_roads_add(ctx, r, "bad", 1, pts, 3) == RS_ERR_INVALID_ARG);
        CHECK(contains(rs_ctx_message(ctx), "point 1"));
        CHECK_EQ_INT(rs_roads_count(r), 2);
        rs_roads_get(r, 1, &name, &w, &xy, &n);
        CHECK(strcmp(name, "") == 0 && w == 2 && n == 2 && xy[2] == 5);
        rs_roads_get(r, 0, &name, &w, &xy, &n);
        CHECK(strcmp(name, "x") == 0 && n == 3 && xy[5] == 0);
        /* copying a road out of the same set: its pointers must survive growth */
        for (int k = 0; k < 40; k++) {
            rs_roads_get(r, rs_roads_count(r) - 1, &name, &w, &xy, &n);
            if (rs_roads_add(ctx, r, name, w, xy, n) != RS_OK) break;
        }
        CHECK_EQ_INT(rs_roads_count(r), 42);
        rs_roads_get(r, 41, &name, &w, &xy, &n);
        CHECK(strcmp(name, "") == 0 && n == 2 && xy[0] == 0 && xy[2] == 5 && xy[3] == 5);
        rs_roads_get(r, 0, &name, &w, &xy, &n);
        for (int k = 0; k < 40; k++) {
            rs_roads_add(ctx, r, name, w, xy, n);
            rs_roads_get(r, rs_roads_count(r) - 1, &name, &w, &xy, &n);
        }
        rs_roads_get(r, rs_roads_count(r) - 1, &name, &w, &xy, &n);
        CHECK(strcmp(name, "x") == 0 && w == 3 && n == 3 && xy[2] == 5 && xy[4] == 10);
    }
    rs_roads_free(ctx, r);

    /* Property: print random roads with %.17g, parse back, get the same
     * doubles; and every mutated input either parses or fails with a
     * "line N:" message. */
    {
        uint64_t st = 777;
        char *buf = malloc(1 << 16);
        double *pts = malloc(2 * 64 * sizeof(double));
        int round_ok = 1, msg_ok = 1;
        for (int t = 0; t < 200 && buf && pts; t++) {
            size_t o = 0, np = 2 + (size_t)(t % 30);
            double width = 0.5 + t * 0.37;
            o += (size_t)snprintf(buf + o, 100, "road r%d width %.17g\n", t, width);
            for (size_t i = 0; i < 2 * np; i++) {
                st ^= st << 13; st ^= st >> 7; st ^= st << 17;
                pts[i] = ((double)(int64_t)(st >> 11) - 4.5e15) / (double)(1 + (st & 0xffff));
                o += (size_t)snprintf(buf + o, 100, "%.17g%s", pts[i], (i & 1) ? "\n" : " ");
            }
            o += (size_t)snprintf(buf + o, 100, "end\n");
            if (roads_s(ctx, buf, &r) != RS_OK) { round_ok = 0; continue; }
            rs_roads_get(r, 0, &name, &w, &xy, &n);
            round_ok &= n == np && w == width && memcmp(xy, pts, 2 * np * sizeof(double)) == 0;
            rs_roads_free(ctx, r);
            for (int k = 0; k < 20; k++) {
                char m[4096];
                size_t len = o < sizeof m ? o : sizeof m;
                memcpy(m, buf, len);
                st ^= st << 13; st ^= st >> 7; st ^= st << 17;
                for (int e = 0; e < 1 + (int)(st % 3); e++) {
                    st ^= st << 13; st ^= st >> 7; st ^= st << 17;
                    m[(st >> 8) % len] = "x ,.#\n\r\0-e9\xff"[st % 12];
                }
                rs_result rc = rs_roads_parse(ctx, m, len, &r);
                if (rc == RS_OK) rs_roads_free(ctx, r);
                else msg_ok &= (rc == RS_ERR_PARSE || rc == RS_ERR_LIMIT) && strncmp(rs_ctx_message(ctx), "line ", 5) == 0;
            }
        }
        free(buf);
        free(pts);
        CHECK(round_ok);
        CHECK(msg_ok);
    }
    CHECK_EQ_INT(ta.live, 1);
    rs_ctx_free(ctx);
    CHECK_EQ_INT(ta.live, 0);
}

/* ---- allocation failure at every allocation ------------------------------ */
typedef rs_result (*alloc_case)(rs_ctx *ctx, const char *input, size_t n);

static rs_result case_roads(rs_ctx *ctx, const char *input, size_t n)
{
    rs_roads *r = NULL;
    rs_result rc = rs_roads_parse(ctx, input, n, &r);
    if (rc == RS_OK) {
        double pts[4] = { 1, 2, 3, 4 };
        rc = rs_roads_add(ctx, r, "added", 1, pts, 2);
    }
    rs_roads_free(ctx, r);
    return rc;
}

static rs_result case_pgm(rs_ctx *ctx, const char *input, size_t n)
{
    rs_dem *d = NULL;
    rs_result rc = rs_dem_parse_pgm(ctx, input, n, &d);
    if (rc == RS_OK) {
        rs_dem *e = NULL;
        rc = rs_dem_create(ctx, rs_dem_width(d), rs_dem_height(d), rs_dem_samples(d), &e);
        rs_dem_free(ctx, e);
    }
    rs_dem_free(ctx, d);
    return rc;
}

static void alloc_failures(const char *label, alloc_case fn, const char *input, size_t n)
{
    test_alloc ta;
    rs_ctx *ctx = make_ctx(&ta, NULL);
    long base_calls = ta.calls;
    int all_nomem = 1, no_leak = 1, finished = 0;
    long N;
    for (N = 1; N < 100000; N++) {
        ta.fail_at = base_calls + N;
        rs_result rc = fn(ctx, input, n);
        long made = ta.calls - base_calls;
        ta.calls = base_calls;
        if (ta.live != 1) no_leak = 0;
        if (made < N) { /* no failure injected: must have succeeded */
            CHECKF(rc == RS_OK, "%s: rc %d without an injected failure", label, rc);
            finished = 1;
            break;
        }
        if (rc != RS_ERR_NOMEM) all_nomem = 0;
    }
    CHECKF(finished && N > 3, "%s: N=%ld", label, N);
    CHECKF(all_nomem, "%s: some injected failure did not give RS_ERR_NOMEM", label);
    CHECKF(no_leak, "%s: leak after an injected failure", label);
    ta.fail_at = 0;
    rs_ctx_free(ctx);
    CHECK_EQ_INT(ta.live, 0);
}

static void test_alloc_failures(void)
{
    char *buf = malloc(1 << 16);
    if (!buf) { CHECK(0); return; }
    size_t o = 0;
    for (int rd = 0; rd < 40; rd++) {
        o += (size_t)snprintf(buf + o, 200, "road road_number_%d width %d.5\n", rd, 1 + rd % 9);
        for (int i = 0; i < 2 + rd % 7; i++) o += (size_t)snprintf(buf + o, 200, "%d.25 %d\n", i * 3, rd);
        o += (size_t)snprintf(buf + o, 200, "end\n");
    }
    alloc_failures("roads", case_roads, buf, o);
    {
        const char *p2 = "P2 3 3 9\n1 2 3\n4 5 6\n7 8 9\n";
        alloc_failures("pgm", case_pgm, p2, strlen(p2));
    }
    free(buf);
}

/* The `frame` header line (issue 17) and rs_roads_negate_y. */
static void test_frame(void)
{
    test_alloc ta;
    rs_ctx *ctx = make_ctx(&ta, NULL);
    rs_roads *r = NULL;
    const char *crs = "x";
    const double *xy;
    if (!ctx) { CHECK(0); return; }
    static const char none[] = "road a width 2\n1 2\n3 4\nend\n";
    CHECK(rs_roads_parse(ctx, none, strlen(none), &r) == RS_OK);
    CHECK(rs_roads_frame(r, &crs) == RS_FRAME_NONE && crs == NULL);
    rs_roads_free(ctx, r);
    static const char local[] = "# c\n\nframe local # a comment\nroad a width 2\n1 2\n3 4\nend\n";
    CHECK(rs_roads_parse(ctx, local, strlen(local), &r) == RS_OK);
    CHECK(rs_roads_frame(r, &crs) == RS_FRAME_LOCAL && crs == NULL);
    rs_roads_free(ctx, r);
    static const char world[] = "frame world EPSG:32632\nroad a width 2\n500001 5000079\n3 -4\nend\n";
    CHECK(rs_roads_parse(ctx, world, strlen(world), &r) == RS_OK);
    CHECK(rs_roads_frame(r, &crs) == RS_FRAME_WORLD && crs && !strcmp(crs, "EPSG:32632"));
    CHECK(rs_roads_negate_y(ctx, r) == RS_OK);
    CHECK(rs_roads_get(r, 0, NULL, NULL, &xy, NULL) == RS_OK && xy[0] == 500001 && xy[1] == -5000079 &&
          xy[2] == 3 && xy[3] == 4);
    CHECK(rs_roads_negate_y(ctx, NULL) == RS_ERR_INVALID_ARG);
    rs_roads_free(ctx, r);
    static const char quoted[] = "frame world \"PROJCS[\\\"x y\\\"]\"\n";
    CHECK(rs_roads_parse(ctx, quoted, strlen(quoted), &r) == RS_OK);
    CHECK(rs_roads_frame(r, &crs) == RS_FRAME_WORLD && crs && !strcmp(crs, "PROJCS[\"x y\"]"));
    rs_roads_free(ctx, r);
    static const char bare[] = "frame world\n";
    CHECK(rs_roads_parse(ctx, bare, strlen(bare), &r) == RS_OK);
    CHECK(rs_roads_frame(r, &crs) == RS_FRAME_WORLD && crs == NULL);
    rs_roads_free(ctx, r);
    CHECK(rs_roads_frame(NULL, &crs) == RS_FRAME_NONE && crs == NULL);
    roads_bad(ctx, "frame local\nframe local\n", RS_ERR_PARSE, "line 2: 'frame' given twice (first on line 1)", NULL);
    roads_bad(ctx, "road a width 2\n1 2\n3 4\nend\nframe local\n", RS_ERR_PARSE,
              "line 5: 'frame' must come before the first road, style or mark", NULL);
    roads_bad(ctx, "style s\nfill #000000\nend\nframe world\n", RS_ERR_PARSE, "line 4: 'frame' must come before", NULL);
    roads_bad(ctx, "frame utm\n", RS_ERR_PARSE, "line 1: frame 'utm' must be 'local' or 'world [CRS]'", NULL);
    roads_bad(ctx, "frame\n", RS_ERR_PARSE, "line 1: frame '' must be", NULL);
    roads_bad(ctx, "frame local EPSG:1\n", RS_ERR_PARSE, "line 1: extra token 'EPSG:1' after 'frame local'", NULL);
    roads_bad(ctx, "frame world EPSG:1 x\n", RS_ERR_PARSE, "line 1: extra token 'x' after the CRS", NULL);
    roads_bad(ctx, "frame world \"EPSG\n", RS_ERR_PARSE, "line 1: the quote at column 13 is not closed", NULL);
    roads_bad(ctx, "frame world \"\"\n", RS_ERR_PARSE, "line 1: the CRS is empty", NULL);
    rs_ctx_free(ctx);
    CHECK_EQ_INT(ta.live, 0);
}

int main(void)
{
    test_numbers();
    test_locale();
    test_pgm();
    test_roads();
    test_frame();
    test_alloc_failures();
    return th_finish("test_parse");
}
