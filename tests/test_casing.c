/* Casings in the splat (issue 13, docs/linesym.md "Casings"): the colour a
 * casing gives a pixel, against an independent supersampled reference of
 * the widened road, by both ways the splat blends it (one casing colour: in
 * the composite; several: the overlays stage), and windows against the
 * whole image. */
#include "roadsplat.h"
#include "harness.h"

#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;
static rs_edge_mode edges; /* of render() */

enum { DW = 26, DH = 22, TEX = 4 };
#define CELL 1.0
#define PIX (CELL / TEX)
#define RW 3.0    /* road A's width */
#define CW 0.5    /* casing width */
#define REF_N 128 /* point samples per pixel side */

static const double road_a[4] = { 2.3, 3.1, 21.7, 15.4 };
static const double road_b[4] = { 2.0, 19.5, 9.0, 20.2 };

static double seg_dist(const double *s, double x, double y)
{
    double dx = s[2] - s[0], dy = s[3] - s[1], wx = x - s[0], wy = y - s[1];
    double u = (wx * dx + wy * dy) / (dx * dx + dy * dy);
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    double ex = wx - u * dx, ey = wy - u * dy;
    return sqrt(ex * ex + ey * ey);
}

/* Fraction of pixel (px, py) within distance r of segment s. */
static double ref_cover(const double *s, double r, uint32_t px, uint32_t py)
{
    uint32_t in = 0;
    for (int j = 0; j < REF_N; j++)
        for (int i = 0; i < REF_N; i++) {
            double x = (px + (i + 0.5) / REF_N) * PIX, y = (py + (j + 0.5) / REF_N) * PIX;
            in += seg_dist(s, x, y) <= r;
        }
    return (double)in / (REF_N * REF_N);
}

typedef struct image {
    uint32_t w, h;
    uint8_t *rgba;
    uint16_t *wt;
} image;

/* Splat roads A and B, each with the given style ("" = none). */
static int render(const rs_dem *dem, const char *styles_text, const char *sa, const char *sb, image *im)
{
    rs_roads *roads = NULL;
    rs_styles *styles = NULL;
    rs_splatter *s = NULL;
    int ok = rs_roads_create(ctx, &roads) == RS_OK && rs_roads_add(ctx, roads, "a", RW, road_a, 2) == RS_OK &&
             rs_roads_add(ctx, roads, "b", 1.5, road_b, 2) == RS_OK;
    if (ok && *sa) ok = rs_roads_set_attr(ctx, roads, 0, "style", sa) == RS_OK;
    if (ok && *sb) ok = rs_roads_set_attr(ctx, roads, 1, "style", sb) == RS_OK;
    if (ok && styles_text) ok = rs_styles_parse(ctx, styles_text, strlen(styles_text), &styles) == RS_OK;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = TEX;
    o.style.styles = styles;
    o.coverage.edges = edges;
    if (ok) ok = rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK;
    if (ok) {
        rs_splatter_size(s, &im->w, &im->h);
        im->rgba = malloc((size_t)im->w * im->h * 4);
        im->wt = malloc((size_t)im->w * im->h * 2);
        ok = im->rgba && im->wt &&
             rs_splat_window(ctx, s, 0, 0, im->w, im->h, im->rgba, (size_t)im->w * 4, im->wt, im->w, NULL) == RS_OK;
        /* windows of odd sizes give the same bytes */
        size_t n = (size_t)im->w * im->h * 4;
        uint8_t *win = ok ? malloc(n) : NULL;
        int same = win != NULL;
        for (uint32_t y = 0; same && y < im->h; y += 13)
            for (uint32_t x = 0; x < im->w; x += 17) {
                uint32_t ww = im->w - x < 17 ? im->w - x : 17, hh = im->h - y < 13 ? im->h - y : 13;
                uint8_t *p = win + ((size_t)y * im->w + x) * 4;
                if (rs_splat_window(ctx, s, x, y, ww, hh, p, (size_t)im->w * 4, NULL, 0, NULL) != RS_OK) same = 0;
            }
        CHECKF(same && memcmp(win, im->rgba, n) == 0, "windows of 17 x 13 differ from the whole image");
        free(win);
    }
    rs_splatter_free(ctx, s);
    rs_styles_free(ctx, styles);
    rs_roads_free(ctx, roads);
    return ok;
}

/* A flat DW x DH DEM of CELL m cells (NULL after a failed check). */
static rs_dem *flat_dem(void)
{
    float z[DW * DH];
    for (int i = 0; i < DW * DH; i++) z[i] = 10.0f;
    rs_dem *dem = NULL;
    CHECK(rs_dem_create(ctx, DW, DH, z, &dem) == RS_OK);
    rs_dem_frame fr = { CELL, 1, 0, 0 };
    CHECK(dem && rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    return dem;
}

static void test_casing_colour(void)
{
    rs_dem *dem = flat_dem();
    static const char styles[] = "style red\n casing 0.5 #FF0000\nend\n"
                                 "style green\n casing 0.5 #00FF00\nend\n"
                                 "style plain\n fill #404040\nend\n";
    image plain = { 0 }, uni = { 0 }, multi = { 0 };
    /* plain: no casing anywhere; uni: both red (the composite blends it);
     * multi: A red, B green (the overlays stage blends per road) */
    CHECK(render(dem, styles, "plain", "plain", &plain));
    CHECK(render(dem, styles, "red", "red", &uni));
    CHECK(render(dem, styles, "red", "green", &multi));
    CHECK(plain.w == uni.w && plain.h == uni.h && multi.w == uni.w && multi.h == uni.h && uni.w > 90);
    size_t ring = 0, full = 0, bad_full = 0, far_b = 0, bad_multi = 0;
    double max_err = 0, sum_err = 0;
    for (uint32_t py = 0; py < uni.h && plain.rgba && uni.rgba && multi.rgba; py++)
        for (uint32_t px = 0; px < uni.w; px++) {
            size_t i = (size_t)py * uni.w + px;
            double cx = (px + 0.5) * PIX, cy = (py + 0.5) * PIX;
            const uint8_t *u = uni.rgba + 4 * i, *m = multi.rgba + 4 * i, *p0 = plain.rgba + 4 * i;
            /* away from road B both ways give the same colours (they round
             * in float and double: one unit) */
            if (seg_dist(road_b, cx, cy) > 2.0) {
                far_b++;
                for (int c = 0; c < 3; c++) bad_multi += abs((int)u[c] - (int)m[c]) > 1;
            }
            /* terrain pixels (R = 0) near road A: T + (K - T) C, C the
             * widened road's cover, T the plain image */
            double d = seg_dist(road_a, cx, cy);
            if (uni.wt[i] != 0 || d > RW / 2 + CW + PIX || d < RW / 2 - PIX) continue;
            double C = ref_cover(road_a, RW / 2 + CW, px, py);
            if (C == 0) continue;
            ring++;
            const double K[3] = { 255, 0, 0 };
            for (int c = 0; c < 3; c++) {
                double want = p0[c] + (K[c] - p0[c]) * C, e = fabs(u[c] - want);
                max_err = e > max_err ? e : max_err;
                sum_err += e / 3;
            }
            if (C == 1) {
                full++;
                bad_full += !(u[0] == 255 && u[1] == 0 && u[2] == 0);
            }
        }
    /* the reference's own error is up to 255/128 = 2 units on an edge */
    CHECKF(ring > 300 && max_err <= 3 && sum_err / (double)ring <= 1,
           "casing ring: %zu pixels, max error %.2f, mean %.3f (units of 1/255)", ring, max_err,
           ring ? sum_err / (double)ring : 0);
    CHECKF(full > 20 && bad_full == 0, "%zu of %zu pixels wholly in the casing are not the casing colour", bad_full, full);
    CHECKF(far_b > 1000 && bad_multi == 0, "one colour vs several: %zu channel values differ by more than 1", bad_multi);
    printf("casing ring: %zu pixels (%zu whole), max error %.2f, mean %.3f; one vs several colours: %zu differ\n", ring,
           full, max_err, ring ? sum_err / (double)ring : 0, bad_multi);
    free(plain.rgba);
    free(plain.wt);
    free(uni.rgba);
    free(uni.wt);
    free(multi.rgba);
    free(multi.wt);
    rs_dem_free(ctx, dem);
}

/* When every road has one fill colour the overlays stage paints it without
 * looking up the nearest road (docs/linesym.md "In the splat"): the same bytes as
 * the lookup. Roads A and B with fills that differ only in blue take the
 * lookup; red and green must then equal the one-colour render everywhere. */
static void test_fill_uniform(void)
{
    rs_dem *dem = flat_dem();
    static const char styles[] = "style f1\n fill #E03820\n line 0 0.1 #FFFFFF\nend\n"
                                 "style f2\n fill #E03821\n line 0 0.1 #FFFFFF\nend\n";
    image one = { 0 }, two = { 0 };
    CHECK(render(dem, styles, "f1", "f1", &one));
    CHECK(render(dem, styles, "f1", "f2", &two));
    CHECK(one.w == two.w && one.h == two.h && one.w > 90);
    size_t diff = 0, painted = 0;
    for (size_t i = 0; one.rgba && two.rgba && i < (size_t)one.w * one.h; i++) {
        diff += one.rgba[4 * i] != two.rgba[4 * i] || one.rgba[4 * i + 1] != two.rgba[4 * i + 1];
        painted += one.rgba[4 * i] > 150; /* the fill's red, not the grey terrain's */
    }
    CHECKF(diff == 0, "%zu pixels differ in red or green", diff);
    CHECKF(painted > 500, "only %zu pixels painted with the fill", painted);
    free(one.rgba);
    free(one.wt);
    free(two.rgba);
    free(two.wt);
    rs_dem_free(ctx, dem);
}

/* A casing on road b must not touch road a, which has none: every pixel
 * clear of b's casing is the same whether b has a casing or not, with
 * either edge mode. With alpha-map edges road a's edge pixels took casing
 * colour (up to 11/255; the casing field held a's analytic coverage, the
 * composite compared it with the alpha map's: found by fuzz/edits). */
static void test_uncased_untouched(void)
{
    rs_dem *dem = flat_dem();
    if (!dem) return;
    static const char sty[] = "style k\ncasing 0.5 #a0a0a0\nend\nstyle n\nfill #383838\nend\n";
    for (int e = 0; e < 2; e++) {
        image cased = { 0 }, bare = { 0 };
        edges = e ? RS_EDGES_ALPHAMAP : RS_EDGES_ANALYTIC;
        int ok = render(dem, sty, "", "k", &cased) && render(dem, sty, "", "n", &bare);
        CHECK(ok);
        long differ = 0, near_b = 0;
        for (uint32_t y = 0; ok && y < cased.h; y++)
            for (uint32_t x = 0; x < cased.w; x++) {
                size_t p = (size_t)y * cased.w + x;
                /* b's half width, its casing and a pixel's diagonal */
                if (seg_dist(road_b, (x + 0.5) * PIX, (y + 0.5) * PIX) < 0.75 + CW + PIX) {
                    near_b += memcmp(cased.rgba + 4 * p, bare.rgba + 4 * p, 3) != 0;
                    continue;
                }
                differ += memcmp(cased.rgba + 4 * p, bare.rgba + 4 * p, 3) != 0;
            }
        CHECKF(differ == 0, "%s edges: %ld pixels away from road b change when b gets a casing", e ? "alpha-map" : "analytic",
               differ);
        CHECKF(near_b > 0, "%s edges: the casing shows (%ld pixels)", e ? "alpha-map" : "analytic", near_b);
        free(cased.rgba);
        free(cased.wt);
        free(bare.rgba);
        free(bare.wt);
    }
    edges = RS_EDGES_ANALYTIC;
    rs_dem_free(ctx, dem);
}

/* Where a road without a casing ends on one with (a T), the mouth's edge
 * pixels keep the through road's casing whether or not a far road's
 * casing has another colour (one colour is blended over C - R; several
 * take the colour of the nearest road with a casing, until 3 December 2026
 * the nearest road of any kind: 0 instead of 78/255 of casing there,
 * found by fuzz/edits). */
static void test_casing_mixed_colours(void)
{
    static const char styles_one[] = "style thin\ncasing 0.15 #404040\nend\nstyle far\ncasing 0.5 #404040\nend\n";
    static const char styles_two[] = "style thin\ncasing 0.15 #404040\nend\nstyle far\ncasing 0.5 #a03030\nend\n";
    static const char roads_text[] = "road a width 6 style=far\n5 5\n70 50\nend\n"
                                     "road b width 4\n4 50\n70 5\nend\n"
                                     "road c width 12 style=thin\n-1.5 52\n4.5 57\nend\n";
    float z[16 * 12];
    for (int k = 0; k < 16 * 12; k++) z[k] = (float)(k % 7);
    rs_dem *dem = NULL;
    rs_dem_frame fr = { 5, 0.05, 0, 0 };
    CHECK(rs_dem_create(ctx, 16, 12, z, &dem) == RS_OK && rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    uint8_t plane[2][16 * 14 * 4];
    for (int v = 0; v < 2; v++) {
        rs_styles *S = NULL;
        rs_roads *R = NULL;
        rs_splatter *sp = NULL;
        const char *st = v ? styles_two : styles_one;
        CHECK(rs_styles_parse(ctx, st, strlen(st), &S) == RS_OK &&
              rs_roads_parse(ctx, roads_text, sizeof roads_text - 1, &R) == RS_OK);
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.texels = 4;
        o.style.styles = S;
        memset(plane[v], 0, sizeof plane[v]);
        rs_splat_layers L;
        memset(&L, 0, sizeof L);
        L.casing = plane[v];
        L.casing_stride = 16 * 4;
        /* the mouth: columns 0..15, rows 30..43 (road a is beyond column 40 there) */
        CHECK(rs_splatter_create(ctx, dem, R, NULL, &o, &sp) == RS_OK &&
              rs_splat_layers_window(ctx, sp, NULL, 0, 30, 16, 14, &L, NULL) == RS_OK);
        rs_splatter_free(ctx, sp);
        rs_roads_free(ctx, R);
        rs_styles_free(ctx, S);
    }
    int worst = 0, any = 0;
    for (size_t k = 0; k < sizeof plane[0]; k++) {
        int d = abs((int)plane[0][k] - (int)plane[1][k]);
        worst = d > worst ? d : worst;
        any |= (k & 3) == 3 && plane[0][k] > 40;
    }
    CHECK(any);                               /* the through road's casing is there */
    CHECKF(worst <= 1, "casing differs by %d/255 with a far road's other colour", worst);
    rs_dem_free(ctx, dem);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_casing_mixed_colours();
    test_casing_colour();
    test_fill_uniform();
    test_uncased_untouched();
    rs_ctx_free(ctx);
    return th_finish("test_casing");
}
