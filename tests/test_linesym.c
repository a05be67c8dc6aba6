/* Line symbols (lib/scene/linesym.c): band coverage against an independent
 * supersampled reference built from the SPEC's definition (nearest point of
 * the centreline, s and t), on straight roads at several angles, bends of
 * 30-170 degrees and a curve; dashed area along a curve; tiling and
 * translation invariance; painting; bad input and allocation failures.
 *
 * Reference resolution: the issue names a 16x16 supersampled reference, but
 * at 16x16 the reference is itself off by up to 1/32 where an edge runs
 * along the sample rows, more than the 2/255 it is asked to check. The
 * reference here uses REF_N x REF_N samples (off by at most 1/(2 REF_N) =
 * 1/192 on such an edge), so that a failure is an error of the library, not
 * of the reference. */
#include "harness.h"
#include "fail_alloc.h"
#include "bandref.h"
#include "linesym.h"
#include "network.h"
#include "roadfield.h"

#include <stdlib.h>

#define REF_N 96
#define RS_TEST_PI 3.14159265358979323846

static rs_ctx *ctx;

/* --- helpers -------------------------------------------------------------- */
static rs_roads *one_road(const double *x, const double *y, size_t n)
{
    rs_roads *r = NULL;
    if (rs_roads_create(ctx, &r) != RS_OK) return NULL;
    double xy[128];
    for (size_t k = 0; k < n; k++) xy[2 * k] = x[k], xy[2 * k + 1] = y[k];
    if (rs_roads_add(ctx, r, "r", 10, xy, n) != RS_OK) {
        rs_roads_free(ctx, r);
        return NULL;
    }
    return r;
}

static rs__linesym_params params(uint32_t w, uint32_t h, double pix, rs__band_aa aa)
{
    rs__linesym_params p;
    memset(&p, 0, sizeof p);
    p.cell_size = 1;
    p.out_w = w;
    p.out_h = h;
    p.pixel = pix;
    p.aa = aa;
    return p;
}

typedef struct err_stat {
    double sum_edge, max;
    size_t n_edge, n_px;
} err_stat;

/* Compare band `bi` of a one-road scene with the reference on every pixel
 * within reach of the band; accumulate into st. */
static void compare_scene(const double *x, const double *y, size_t n, const rs__band *bands, uint32_t nb, uint32_t W,
                          uint32_t H, double pix, err_stat *st, const char *what)
{
    rs_roads *roads = one_road(x, y, n);
    CHECK(roads != NULL);
    if (!roads) return;
    uint32_t bs[2] = { 0, nb };
    rs__linesym_params p = params(W, H, pix, RS__AA_EXACT);
    rs__linesym *L = NULL;
    CHECK_EQ_INT(rs__linesym_build(ctx, roads, &p, bs, bands, &L), RS_OK);
    bandref_line rl;
    bandref_init(&rl, x, y, n);
    double *cov = malloc(sizeof(double) * W * H);
    for (uint32_t bi = 0; bi < nb && L && cov; bi++) {
        rs__linesym_coverage(L, bi, 0, 0, W, H, cov, W);
        /* the band lies between these distances from the centreline */
        double reach = fabs(bands[bi].t) + 0.5 * bands[bi].w + pix,
               inner = fabs(bands[bi].t) - 0.5 * bands[bi].w - pix;
        err_stat one = { 0, 0, 0, 0 };
        for (uint32_t py = 0; py < H; py++)
            for (uint32_t px = 0; px < W; px++) {
                double c = cov[(size_t)py * W + px];
                double dc = bandref_dist(&rl, (px + 0.5) * pix, (py + 0.5) * pix);
                if (dc > reach || dc < inner) {
                    if (c != 0) one.max = fmax(one.max, fabs(c));
                    continue;
                }
                double g = bandref_cover(&rl, &bands[bi], pix, px, py, REF_N), e = fabs(c - g);
                one.n_px++;
                one.max = fmax(one.max, e);
                if ((c > 0 && c < 1) || (g > 0 && g < 1)) {
                    one.sum_edge += e;
                    one.n_edge++;
                }
            }
        CHECKF(one.max <= 2.0 / 255, "%s band %u: max error %.5f (x255: %.2f) over %zu pixels", what, bi, one.max,
               one.max * 255, one.n_px);
        /* (a band can lie wholly outside the window: on the inner side
         * of a sharp bend it ends where the bisector cuts it) */
        if (one.n_edge)
            CHECKF(one.sum_edge / one.n_edge <= 1.0 / 255, "%s band %u: mean edge error %.5f over %zu", what, bi,
                   one.sum_edge / one.n_edge, one.n_edge);
        st->sum_edge += one.sum_edge;
        st->n_edge += one.n_edge;
        st->max = fmax(st->max, one.max);
        st->n_px += one.n_px;
    }
    free(cov);
    rs__linesym_free(ctx, L);
    rs_roads_free(ctx, roads);
}

static const double dash_rms[2] = { 0.9, 1.3 };
static const double dash_short[4] = { 0.35, 0.2, 0.15, 0.45 };

/* --- straight roads at several angles ------------------------------------- */
static void test_straight(void)
{
    const double angles[] = { 7, 31, 58, 90, 103, 180 + 44 };
    err_stat st = { 0, 0, 0, 0 };
    for (size_t k = 0; k < sizeof angles / sizeof *angles; k++) {
        double a = angles[k] * 3.14159265358979323846 / 180, cx = 1.6, cy = 1.4;
        double x[2] = { cx - 4 * cos(a), cx + 4 * cos(a) }, y[2] = { cy - 4 * sin(a), cy + 4 * sin(a) };
        rs__band b[4] = {
            { 0, 0.15, { 1, 1, 1, 1 }, NULL, 0, 0 },
            { 0.8, 0.3, { 1, 1, 0, 1 }, NULL, 0, 0 },
            { -0.7, 0.12, { 1, 1, 1, 1 }, dash_rms, 2, 0.37 },
            { 0.2, 0.55, { 1, 1, 1, 1 }, dash_short, 4, -0.1 },
        };
        char what[64];
        snprintf(what, sizeof what, "straight %g deg", angles[k]);
        compare_scene(x, y, 2, b, 4, 32, 28, 0.1, &st, what);
    }
    /* coarse pixels: the thin line covers a tenth of a 1.25 m pixel */
    double x[2] = { -30, 60 }, y[2] = { 3, 21 };
    rs__band b[2] = { { 0, 0.15, { 1, 1, 1, 1 }, NULL, 0, 0 }, { 1.6, 0.12, { 1, 1, 1, 1 }, dash_rms, 2, 0 } };
    compare_scene(x, y, 2, b, 2, 24, 20, 1.25, &st, "straight, 1.25 m pixels");
    CHECKF(st.n_edge > 1500, "straight: only %zu edge pixels compared", st.n_edge);
    printf("straight: %zu pixels, mean edge error %.5f, max %.5f\n", st.n_px, st.sum_edge / st.n_edge, st.max);
}

/* --- bends ---------------------------------------------------------------- */
static void test_bends(void)
{
    const double turns[] = { 30, 90, 150, 170, -60, -135 };
    err_stat st = { 0, 0, 0, 0 };
    for (size_t k = 0; k < sizeof turns / sizeof *turns; k++) {
        double h0 = 0.4, h1 = h0 + turns[k] * 3.14159265358979323846 / 180, vx = 1.7, vy = 1.5;
        double x[3] = { vx - 3 * cos(h0), vx, vx + 3 * cos(h1) }, y[3] = { vy - 3 * sin(h0), vy, vy + 3 * sin(h1) };
        /* dashes straddle the vertex (s = 3 there) */
        rs__band b[5] = {
            { 0.6, 0.3, { 1, 1, 1, 1 }, NULL, 0, 0 },
            { -0.6, 0.3, { 1, 1, 1, 1 }, NULL, 0, 0 },
            { 0, 0.2, { 1, 1, 1, 1 }, dash_short, 4, 2.9 },
            { 0, 1.6, { 1, 1, 1, 1 }, NULL, 0, 0 },
            { 0.35, 0.25, { 1, 1, 1, 1 }, dash_rms, 2, 2.5 },
        };
        char what[64];
        snprintf(what, sizeof what, "bend %g deg", turns[k]);
        compare_scene(x, y, 3, b, 5, 34, 30, 0.1, &st, what);
    }
    CHECKF(st.n_edge > 2000, "bends: only %zu edge pixels compared", st.n_edge);
    printf("bends: %zu pixels, mean edge error %.5f, max %.5f\n", st.n_px, st.sum_edge / st.n_edge, st.max);
}

/* --- a curve: reference errors and the dashed area ------------------------- */
static void test_curve(void)
{
    enum { N = 41 };
    double x[N], y[N], R = 6;
    for (int k = 0; k < N; k++) {
        double a = 0.3 + 1.9 * k / (N - 1);
        x[k] = 7 + R * cos(a);
        y[k] = 0.5 + R * sin(a);
    }
    err_stat st = { 0, 0, 0, 0 };
    rs__band b[2] = { { 0.5, 0.3, { 1, 1, 1, 1 }, dash_rms, 2, 0.2 }, { -0.45, 0.2, { 1, 1, 1, 1 }, NULL, 0, 0 } };
    compare_scene(x, y, N, b, 2, 64, 48, 0.2, &st, "curve");
    printf("curve: %zu pixels, mean edge error %.5f, max %.5f\n", st.n_px, st.sum_edge / st.n_edge, st.max);

    /* dashed centre line along a curve of many segments: integrated
     * coverage = length x duty x width (1 %) */
    enum { M = 200 };
    double cx[M], cy[M], len = 0, R2 = 40;
    for (int k = 0; k < M; k++) {
        double a = 0.1 + 1.4 * k / (M - 1);
        cx[k] = 2 + R2 * cos(a);
        cy[k] = 2 + R2 * sin(a);
        if (k) len += hypot(cx[k] - cx[k - 1], cy[k] - cy[k - 1]);
    }
    rs_roads *rr = NULL;
    CHECK(rs_roads_create(ctx, &rr) == RS_OK);
    double xy[2 * M];
    for (int k = 0; k < M; k++) xy[2 * k] = cx[k], xy[2 * k + 1] = cy[k];
    CHECK(rs_roads_add(ctx, rr, "arc", 8, xy, M) == RS_OK);
    const double dash[2] = { 3, 6 };
    rs__band bd = { 0, 0.3, { 1, 1, 1, 1 }, dash, 2, 0.7 };
    uint32_t bs[2] = { 0, 1 };
    const double pix = 0.25;
    uint32_t W = 190, H = 190;
    rs__linesym_params p = params(W, H, pix, RS__AA_EXACT);
    rs__linesym *L = NULL;
    CHECK_EQ_INT(rs__linesym_build(ctx, rr, &p, bs, &bd, &L), RS_OK);
    double *cov = malloc(sizeof(double) * W * H), sum = 0;
    if (L && cov) {
        rs__linesym_coverage(L, 0, 0, 0, W, H, cov, W);
        for (size_t i = 0; i < (size_t)W * H; i++) sum += cov[i];
    }
    /* the dashes on [0, len]: count the on-length exactly */
    double on = 0;
    for (double s0 = 0.7 - 9 * ceil(0.7 / 9); s0 < len; s0 += 9) on += fmax(0, fmin(s0 + 3, len) - fmax(s0, 0));
    double expect = on * 0.3, got = sum * pix * pix;
    CHECKF(fabs(got - expect) <= 0.01 * expect, "dashed area %.4f m^2, expected %.4f (length %.2f)", got, expect, len);
    printf("curve dashes: area %.5f m^2 vs on-length x width %.5f (%.3f %%)\n", got, expect,
           100 * (got - expect) / expect);
    free(cov);
    rs__linesym_free(ctx, L);
    rs_roads_free(ctx, rr);
}

/* --- tiling, translation, painting ---------------------------------------- */
static void random_bands(uint32_t *seed, rs__band *b, uint32_t n)
{
    static const double d1[2] = { 0.9, 1.3 }, d2[4] = { 0.35, 0.2, 0.15, 0.45 };
    for (uint32_t k = 0; k < n; k++) {
        *seed = *seed * 1664525u + 1013904223u;
        uint32_t r = *seed >> 8;
        b[k].t = ((double)(r % 21) - 10) * 0.17;
        b[k].w = 0.1 + (r % 7) * 0.13;
        b[k].rgba[0] = (float)(r % 5) / 4.0f;
        b[k].rgba[1] = (float)(r % 3) / 2.0f;
        b[k].rgba[2] = 0.5f;
        b[k].rgba[3] = 0.9f;
        b[k].dash = (r & 1) ? d1 : ((r & 2) ? d2 : NULL);
        b[k].ndash = (r & 1) ? 2 : ((r & 2) ? 4 : 0);
        b[k].phase = (r % 13) * 0.31;
    }
}

static rs_roads *random_roads(uint32_t *seed, double W, double H, double ox, double oy, int nroads)
{
    rs_roads *r = NULL;
    if (rs_roads_create(ctx, &r) != RS_OK) return NULL;
    for (int i = 0; i < nroads; i++) {
        double xy[40];
        size_t n = 2 + i % 8;
        for (size_t k = 0; k < n; k++) {
            *seed = *seed * 1664525u + 1013904223u;
            xy[2 * k] = ox + floor((double)(*seed >> 8) / (1 << 24) * (W + 20) * 1000) / 1000 - 10;
            *seed = *seed * 1664525u + 1013904223u;
            xy[2 * k + 1] = oy + floor((double)(*seed >> 8) / (1 << 24) * (H + 20) * 1000) / 1000 - 10;
        }
        if (i == 0) { /* a road 1e6 m long across the map */
            xy[0] = ox - 5e5, xy[1] = oy + 0.3 * H, xy[2] = ox + 5e5, xy[3] = oy + 0.6 * H;
            n = 2;
        }
        if (rs_roads_add(ctx, r, "r", 6, xy, n) != RS_OK) break;
    }
    return r;
}

static float whole[2][2][150 * 3 * 130];

static void test_tiling_translation(void)
{
    uint32_t seed = 12345, W = 150, H = 130;
    double pix = 0.4;
    rs__band bands[3 * 12];
    uint32_t bs[13];
    for (int i = 0; i <= 12; i++) bs[i] = (uint32_t)(3 * i);
    random_bands(&seed, bands, 36);
    for (int aa = 0; aa < 2; aa++)
        for (int shift = 0; shift < 2; shift++) {
            uint32_t rs_seed = 99;
            double ox = shift ? 5e6 : 0, oy = shift ? -5e6 : 0;
            rs_roads *roads = random_roads(&rs_seed, W * pix, H * pix, ox, oy, 12);
            rs__linesym_params p = params(W, H, pix, aa ? RS__AA_HERMITE : RS__AA_EXACT);
            p.origin_x = ox;
            p.origin_y = oy;
            rs__linesym *L = NULL;
            CHECK_EQ_INT(rs__linesym_build(ctx, roads, &p, bs, bands, &L), RS_OK);
            float *img = whole[aa][shift], *tile = malloc(sizeof(float) * W * 3 * H);
            double *scratch = malloc(sizeof(double) * W * H);
            for (size_t i = 0; i < (size_t)W * 3 * H; i++) img[i] = (float)((i * 7) % 11) / 10.0f;
            rs__linesym_paint(L, 0, 0, W, H, img, (size_t)W * 3, scratch);
            /* windows of odd sizes and offsets; each window's planar rows hold its own width */
            int same = 1;
            for (uint32_t y0 = 0; y0 < H; y0 += 17)
                for (uint32_t x0 = 0; x0 < W; x0 += 23) {
                    uint32_t w = x0 + 23 <= W ? 23 : W - x0, h = y0 + 17 <= H ? 17 : H - y0;
                    for (uint32_t y = 0; y < h; y++)
                        for (uint32_t c = 0; c < 3; c++)
                            for (uint32_t x = 0; x < w; x++)
                                tile[(size_t)y * w * 3 + c * w + x] =
                                    (float)((((size_t)(y0 + y) * W * 3 + c * W + x0 + x) * 7) % 11) / 10.0f;
                    rs__linesym_paint(L, x0, y0, w, h, tile, (size_t)w * 3, scratch);
                    for (uint32_t y = 0; y < h; y++)
                        for (uint32_t c = 0; c < 3; c++)
                            if (memcmp(tile + (size_t)y * w * 3 + c * w, img + (size_t)(y0 + y) * W * 3 + c * W + x0,
                                       w * sizeof(float)))
                                same = 0;
                }
            CHECKF(same, "aa %d shift %d: windows differ from the whole image", aa, shift);
            /* something was painted */
            size_t changed = 0;
            for (size_t i = 0; i < (size_t)W * 3 * H; i++) changed += img[i] != (float)((i * 7) % 11) / 10.0f;
            CHECKF(changed > 1000, "aa %d: only %zu values painted", aa, changed);
            free(tile);
            free(scratch);
            rs__linesym_free(ctx, L);
            rs_roads_free(ctx, roads);
        }
    /* the same scene 5e6 m away paints the same bytes */
    for (int aa = 0; aa < 2; aa++) CHECKF(!memcmp(whole[aa][0], whole[aa][1], sizeof whole[aa][0]), "aa %d: translation", aa);
}

/* c = c (1 - a cov) + colour a cov, band after band */
static void test_paint_formula(void)
{
    double x[2] = { -1, 9 }, y[2] = { 2.2, 3.1 };
    rs_roads *roads = one_road(x, y, 2);
    rs__band b[2] = { { 0, 0.5, { 1, 0, 0, 0.8f }, NULL, 0, 0 }, { 0.2, 0.4, { 0, 0, 1, 1 }, NULL, 0, 0 } };
    uint32_t bs[2] = { 0, 2 }, W = 40, H = 24;
    rs__linesym_params p = params(W, H, 0.2, RS__AA_EXACT);
    rs__linesym *L = NULL;
    CHECK_EQ_INT(rs__linesym_build(ctx, roads, &p, bs, b, &L), RS_OK);
    float img[40 * 3 * 24];
    double c0[40 * 24], c1[40 * 24], scratch[40 * 24];
    for (size_t i = 0; i < sizeof img / sizeof *img; i++) img[i] = 0.5f;
    rs__linesym_paint(L, 0, 0, W, H, img, W * 3, scratch);
    rs__linesym_coverage(L, 0, 0, 0, W, H, c0, W);
    rs__linesym_coverage(L, 1, 0, 0, W, H, c1, W);
    double maxe = 0;
    for (uint32_t py = 0; py < H; py++)
        for (uint32_t px = 0; px < W; px++)
            for (int k = 0; k < 3; k++) {
                double v = 0.5, a0 = c0[py * W + px] * 0.8, a1 = c1[py * W + px];
                v = v * (1 - a0) + b[0].rgba[k] * a0;
                v = v * (1 - a1) + b[1].rgba[k] * a1;
                maxe = fmax(maxe, fabs(v - img[(size_t)py * W * 3 + (size_t)k * W + px]));
            }
    CHECKF(maxe < 1e-5, "paint vs formula: %g", maxe);
    rs__linesym_free(ctx, L);
    rs_roads_free(ctx, roads);
}

/* Junctions: lines stop at the other road's surface, taken as its
 * segments' rectangles with square ends (docs/linesym.md); roads that
 * continue each other keep their lines. Checked against the reference
 * with the other road's rectangles cut out. */
typedef struct jroad {
    double x[3], y[3];
    size_t n;
    double w;
} jroad;

static int in_surface(const jroad *r, double x, double y)
{
    for (size_t k = 0; k + 1 < r->n; k++) {
        double dx = r->x[k + 1] - r->x[k], dy = r->y[k + 1] - r->y[k], len = hypot(dx, dy), h = 0.5 * r->w;
        double u = ((x - r->x[k]) * dx + (y - r->y[k]) * dy) / len, v = ((x - r->x[k]) * dy - (y - r->y[k]) * dx) / len;
        if (u >= -h && u <= len + h && fabs(v) <= h) return 1;
    }
    return 0;
}

static void test_junctions(void)
{
    const double pix = 0.1;
    const uint32_t W = 120, H = 100;
    /* A: west-east through the middle; B: crosses it at 70 degrees; C ends on A (T-junction);
     * D continues A straight on from its east end */
    const jroad R[4] = {
        { { -2, 12.5, 0 }, { 5.1, 5.4, 0 }, 2, 4 },
        { { 3, 6.2, 0 }, { 0.5, 9.3, 0 }, 2, 3 },
        { { 9.3, 9.6, 0 }, { 9.7, 5.33, 0 }, 2, 2.5 },
        { { 12.5, 16, 0 }, { 5.4, 5.5, 0 }, 2, 4 },
    };
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    for (int i = 0; i < 4; i++) {
        double xy[6];
        for (size_t k = 0; k < R[i].n; k++) xy[2 * k] = R[i].x[k], xy[2 * k + 1] = R[i].y[k];
        CHECK(rs_roads_add(ctx, roads, "j", R[i].w, xy, R[i].n) == RS_OK);
    }
    rs__band b[6] = {
        { 0, 0.15, { 1, 1, 1, 1 }, NULL, 0, 0 },   { 1.8, 0.15, { 1, 1, 1, 1 }, NULL, 0, 0 },
        { -1.8, 0.15, { 1, 1, 1, 1 }, NULL, 0, 0 }, { 0, 0.12, { 1, 1, 0, 1 }, dash_rms, 2, 0 },
        { 0.9, 0.12, { 1, 1, 1, 1 }, NULL, 0, 0 },  { -0.9, 0.12, { 1, 1, 1, 1 }, NULL, 0, 0 },
    };
    uint32_t bs[5] = { 0, 3, 4, 6, 6 }; /* A: centre + edges; B: dashed centre; C: two lines; D: none */
    rs__linesym_params p = params(W, H, pix, RS__AA_EXACT);
    rs__linesym *L = NULL;
    CHECK_EQ_INT(rs__linesym_build(ctx, roads, &p, bs, b, &L), RS_OK);
    double *cov = malloc(sizeof(double) * W * H);
    double maxe = 0, sum = 0;
    size_t ne = 0, cut_px = 0;
    for (int ri = 0; ri < 3 && L && cov; ri++) {
        bandref_line rl;
        bandref_init(&rl, R[ri].x, R[ri].y, R[ri].n);
        for (uint32_t bi = bs[ri]; bi < bs[ri + 1]; bi++) {
            rs__linesym_coverage(L, bi, 0, 0, W, H, cov, W);
            double reach = fabs(b[bi].t) + 0.5 * b[bi].w + pix;
            for (uint32_t py = 0; py < H; py++)
                for (uint32_t px = 0; px < W; px++) {
                    double c = cov[(size_t)py * W + px];
                    if (bandref_dist(&rl, (px + 0.5) * pix, (py + 0.5) * pix) > reach) continue;
                    int in = 0, cut = 0;
                    const int N = 48;
                    for (int j = 0; j < N; j++)
                        for (int i = 0; i < N; i++) {
                            double x = (px + (i + 0.5) / N) * pix, y = (py + (j + 0.5) / N) * pix;
                            if (!bandref_in(&rl, &b[bi], x, y)) continue;
                            int other = 0;
                            for (int q = 0; q < 3; q++) /* D continues A: it cuts nothing of A */
                                if (q != ri && !(ri == 0 && q == 3) && in_surface(&R[q], x, y)) other = 1;
                            if (other) cut++;
                            else in++;
                        }
                    double g = (double)in / (N * N), e = fabs(c - g);
                    cut_px += cut > 0;
                    maxe = fmax(maxe, e);
                    if ((c > 0 && c < 1) || (g > 0 && g < 1)) sum += e, ne++;
                }
        }
    }
    /* the reference here has 48x48 samples: off by up to 1/96 on an edge along its rows */
    CHECKF(maxe <= 1.0 / 96 + 1e-9, "junctions: max error %.5f", maxe);
    CHECKF(ne > 0 && sum / ne <= 1.0 / 255, "junctions: mean edge error %.5f over %zu", ne ? sum / ne : -1, ne);
    CHECKF(cut_px > 200, "junctions: only %zu pixels where a line is cut", cut_px);
    printf("junctions: mean edge error %.5f, max %.5f, %zu pixels with a cut\n", ne ? sum / ne : -1, maxe, cut_px);
    free(cov);
    rs__linesym_free(ctx, L);
    rs_roads_free(ctx, roads);
}

static void test_bad_input(void)
{
    double x[2] = { 0, 5 }, y[2] = { 1, 1 };
    rs_roads *roads = one_road(x, y, 2);
    uint32_t bs[2] = { 0, 1 };
    rs__linesym_params p = params(10, 10, 0.5, RS__AA_EXACT);
    const double zero[2] = { 0, 0 }, tiny[2] = { 1e-4, 1e-4 }, neg[2] = { 1, -1 }, ok[2] = { 1, 1 };
    const rs__band bad[] = {
        { 0, 0, { 1, 1, 1, 1 }, NULL, 0, 0 },       /* width 0 */
        { 0, NAN, { 1, 1, 1, 1 }, NULL, 0, 0 },     /* NaN width */
        { 2e4, 1, { 1, 1, 1, 1 }, NULL, 0, 0 },     /* offset beyond 10 km */
        { 0, 1, { 1, 1, 1, 1 }, zero, 2, 0 },       /* period 0 */
        { 0, 1, { 1, 1, 1, 1 }, tiny, 2, 0 },       /* period below 1 mm */
        { 0, 1, { 1, 1, 1, 1 }, neg, 2, 0 },        /* negative length */
        { 0, 1, { 1, 1, 1, 1 }, ok, 1, 0 },         /* odd count */
        { 0, 1, { 1, 1, 1, 1 }, NULL, 2, 0 },       /* no array */
        { 0, 1, { 1, 1, 1, 1 }, ok, 2, INFINITY },  /* phase */
    };
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        rs__linesym *L = (rs__linesym *)1;
        rs_result r = rs__linesym_build(ctx, roads, &p, bs, &bad[k], &L);
        CHECKF(r == RS_ERR_INVALID_ARG && L == NULL, "bad band %zu: %d", k, (int)r);
    }
    rs__linesym_params q = p;
    q.pixel = 0;
    rs__linesym *L = NULL;
    CHECK_EQ_INT(rs__linesym_build(ctx, roads, &q, bs, &bad[0], &L), RS_ERR_INVALID_ARG);
    rs_roads_free(ctx, roads);
}

typedef struct alloc_case {
    const rs_roads *roads;
    const uint32_t *bs;
    const rs__band *bands;
} alloc_case;

static rs_result alloc_try(rs_ctx *c, void *user, int *wrong)
{
    const alloc_case *ac = user;
    rs__linesym_params p = params(100, 100, 0.4, RS__AA_EXACT);
    rs__linesym *L = NULL;
    rs_result r = rs__linesym_build(c, ac->roads, &p, ac->bs, ac->bands, &L);
    *wrong = r != RS_OK && L != NULL;
    rs__linesym_free(c, L);
    return r;
}

static void test_alloc_failures(void)
{
    uint32_t seed = 7;
    rs_roads *roads = random_roads(&seed, 40, 40, 0, 0, 30);
    rs__band bands[60];
    uint32_t bs[31];
    for (int i = 0; i <= 30; i++) bs[i] = (uint32_t)(2 * i);
    random_bands(&seed, bands, 60);
    CHECK(roads != NULL);
    if (!roads) return;
    alloc_case ac = { roads, bs, bands };
    fail_sweep fs = fail_alloc_sweep(1000, alloc_try, &ac);
    CHECK_SWEEP(fs, 4);
    rs_roads_free(ctx, roads);
}

/* Where several streets pass a node and a road ends there, the trim of
 * its end (rs__tee_ends) and its line rule (rs__network_tees) take the
 * street it meets most squarely. On a bent street the two measured that
 * differently (the direction from both legs, against one leg's angle), so
 * near a tie the surface stopped at one street's far edge while the lines
 * treated the other as the through road. Random nodes: two primaries
 * passing, each bent by up to 40 degrees, a third ending there (about
 * one in five a T end: where the flat strip's corner would stand off a
 * bent street, the end keeps its cap, tee_ends.c strip_on_street). */
static void test_tee_pick_agrees(void)
{
    uint64_t st = 0x9E3779B97F4A7C15ull;
    int compared = 0, differ = 0;
    for (int it = 0; it < 800; it++) {
        double ang[5];
        int ok = 1;
        for (int k = 0; k < 5; k++) {
            st = st * 6364136223846793005ull + 1442695040888963407ull;
            ang[k] = (double)(st >> 11) / 9007199254740992.0;
        }
        double a0 = 2 * RS_TEST_PI * ang[0], a1 = a0 + RS_TEST_PI + (ang[1] - 0.5) * 80 * RS_TEST_PI / 180;
        double b0 = 2 * RS_TEST_PI * ang[2], b1 = b0 + RS_TEST_PI + (ang[3] - 0.5) * 80 * RS_TEST_PI / 180;
        double c0 = 2 * RS_TEST_PI * ang[4], all[5] = { a0, a1, b0, b1, c0 };
        for (int i = 0; i < 5; i++)
            for (int j = i + 1; j < 5; j++) {
                double d = fmod(fabs(all[i] - all[j]), 2 * RS_TEST_PI);
                ok &= fmin(d, 2 * RS_TEST_PI - d) > 20 * RS_TEST_PI / 180;
            }
        if (!ok) continue;
        const double cx = 60, cy = 60, L = 40;
        double A[6] = { cx + L * cos(a0), cy + L * sin(a0), cx, cy, cx + L * cos(a1), cy + L * sin(a1) };
        double B[6] = { cx + L * cos(b0), cy + L * sin(b0), cx, cy, cx + L * cos(b1), cy + L * sin(b1) };
        double C[4] = { cx + L * cos(c0), cy + L * sin(c0), cx, cy };
        rs_roads *R = NULL;
        rs_network *net = NULL;
        rs__tee_end *te = NULL;
        rs__tee *lt = NULL;
        size_t nte = 0;
        CHECK(rs_roads_create(ctx, &R) == RS_OK);
        if (!R) return;
        CHECK(rs_roads_add(ctx, R, "A", 8, A, 3) == RS_OK && rs_roads_add(ctx, R, "B", 8, B, 3) == RS_OK &&
              rs_roads_add(ctx, R, "C", 8, C, 2) == RS_OK);
        for (size_t r = 0; r < 3; r++) CHECK(rs_roads_set_attr(ctx, R, r, "class", "primary") == RS_OK);
        CHECK(rs_network_build(ctx, R, NULL, &net) == RS_OK);
        CHECK(net && rs__tee_ends(ctx, R, net, &te, &nte) == RS_OK && rs__network_tees(ctx, R, net, &lt) == RS_OK);
        for (size_t i = 0; net && lt && i < nte; i++) {
            if (te[i].road != 2 || !te[i].end) continue;
            compared++;
            differ += lt[rs__leg_end(&(rs_network_leg){ .road = 2, .kind = RS_LEG_END })].stroke !=
                      net->stroke_of[te[i].through];
        }
        rs__free(ctx, te);
        rs__free(ctx, lt);
        rs_network_free(ctx, net);
        rs_roads_free(ctx, R);
    }
    printf("T ends at two bent streets: %d compared, %d with another through street for the lines\n", compared,
           differ);
    CHECKF(compared >= 100 && differ == 0, "%d of %d T ends at two streets: trim and lines pick different streets",
           differ, compared);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_straight();
    test_bends();
    test_curve();
    test_tiling_translation();
    test_paint_formula();
    test_junctions();
    test_tee_pick_agrees();
    test_bad_input();
    test_alloc_failures();
    rs_ctx_free(ctx);
    return th_finish("test_linesym");
}
