/* Road ends at a T (issue 27 problem 3, docs/network.md "Ends at a T"): a
 * record ending on a road that passes through its end point has no round
 * cap; its surface and casing run as a flat strip to the through road's far
 * edge line and stop there. Rendered at 0.1 m pixels: no road weight and
 * no change beyond the far edge, the side road's full width up to the
 * through road, any split of either road alike, dead ends keep their caps. */
#include "harness.h"
#include "roadsplat.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { DW = 61, DH = 41, TEX = 10 }; /* 1 m cells: 600 x 400 pixels of 0.1 m */
#define PIX (1.0 / TEX)
#define DEG (3.14159265358979323846 / 180)

static rs_ctx *ctx;
static const char *styles_text; /* NULL: the built-in styles; else named by class (style=CLASS) */

typedef struct image {
    uint32_t w, h;
    uint8_t *rgba;
    uint16_t *wt;
} image;

static int render(const rs_roads *roads, image *im)
{
    static float z[DW * DH];
    rs_dem *dem = NULL;
    rs_splatter *s = NULL;
    rs_styles *styles = NULL;
    memset(im, 0, sizeof *im);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = TEX;
    if (styles_text && rs_styles_parse(ctx, styles_text, strlen(styles_text), &styles) != RS_OK) return 0;
    o.style.styles = styles;
    /* (automatic give-way lines still depend on where the ways are split:
     * issue 27 problem 5; the caps are what this test is about) */
    o.markings.disable = 1;
    int ok = rs_dem_create(ctx, DW, DH, z, &dem) == RS_OK && rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK;
    if (ok) {
        rs_splatter_size(s, &im->w, &im->h);
        im->rgba = malloc((size_t)im->w * im->h * 4);
        im->wt = malloc((size_t)im->w * im->h * sizeof *im->wt);
        ok = im->rgba && im->wt &&
             rs_splat_window(ctx, s, 0, 0, im->w, im->h, im->rgba, (size_t)im->w * 4, im->wt, im->w, NULL) == RS_OK;
    }
    rs_splatter_free(ctx, s);
    rs_dem_free(ctx, dem);
    rs_styles_free(ctx, styles);
    return ok;
}

static void image_free(image *im)
{
    free(im->rgba);
    free(im->wt);
}

/* The scenes turn by rot (radians) about (30, 20): clip lines at any angle. */
static double rot;

static void turn(double *x, double *y, double a)
{
    double dx = *x - 30, dy = *y - 20;
    *x = 30 + dx * cos(a) - dy * sin(a);
    *y = 20 + dx * sin(a) + dy * cos(a);
}

static void add(rs_roads *roads, double w, const char *cls, double x0, double y0, double x1, double y1)
{
    turn(&x0, &y0, rot);
    turn(&x1, &y1, rot);
    double xy[4] = { x0, y0, x1, y1 };
    CHECK(rs_roads_add(ctx, roads, "r", w, xy, 2) == RS_OK);
    CHECK(rs_roads_set_attr(ctx, roads, rs_roads_count(roads) - 1, "class", cls) == RS_OK);
    if (styles_text) CHECK(rs_roads_set_attr(ctx, roads, rs_roads_count(roads) - 1, "style", cls) == RS_OK);
}

static int rgb_diff(const image *a, const image *b, size_t i)
{
    int d = 0;
    for (int c = 0; c < 3; c++) {
        int v = abs((int)a->rgba[4 * i + c] - (int)b->rgba[4 * i + c]);
        d = v > d ? v : d;
    }
    return d;
}

/* The through road: 3 m (residential) along y = 20 from x = 2 to 58. */
#define TY 20.0
#define TR 1.5
/* The side road: 15 m (primary) ending at (30, 20), coming from below at
 * `deg` degrees to the through road. */
#define SR 7.5

static void side_end(double deg, double len, double *x0, double *y0)
{
    *x0 = 30 - len * cos(deg * DEG);
    *y0 = TY - len * sin(deg * DEG);
}

/* Scene: the through road in `tsplit` records (split at the T when 2), the
 * side road at `deg` degrees in `ssplit` records. */
/* 1: a 2 m footway along the far side too, 0.5 m from the street's edge
 * (its lines must not be cut where the side road's surface no longer is) */
static int with_walk;

static void add_walk(rs_roads *roads)
{
    if (with_walk) add(roads, 2, "footway", 2, TY + TR + 1.5, 58, TY + TR + 1.5);
}

/* How far past (30, TY) along its direction the side road ends (negative:
 * short of the through road's centre line): an end inside the through
 * road's surface is a T too (docs/network.md "Ends inside a surface") */
static double end_shift;

static rs_roads *tee_scene(double deg, int tsplit, int ssplit)
{
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    add_walk(roads);
    if (tsplit == 2) {
        add(roads, 2 * TR, "residential", 2, TY, 30, TY);
        add(roads, 2 * TR, "residential", 30, TY, 58, TY);
    } else
        add(roads, 2 * TR, "residential", 2, TY, 58, TY);
    double x0, y0, ex = 30 + end_shift * cos(deg * DEG), ey = TY + end_shift * sin(deg * DEG);
    side_end(deg, 18 / sin(deg * DEG), &x0, &y0);
    if (ssplit == 2) {
        double xm = x0 + 0.37 * (30 - x0), ym = y0 + 0.37 * (TY - y0);
        add(roads, 2 * SR, "primary", x0, y0, xm, ym);
        add(roads, 2 * SR, "primary", xm, ym, ex, ey);
    } else
        add(roads, 2 * SR, "primary", x0, y0, ex, ey);
    return roads;
}

/* > 0: another road's edge lies inside a T's box (its pixels there come
 * from 16 sub-rows too): the weight difference allowed, of 65535 */
static int sub_rows;

/* Beyond the far edge (y > TY + TR + half a pixel, near the T): the
 * weight (0 without a footway) and the colour of the through road alone.
 * Returns the worst colour difference; *wt the count of pixels whose
 * weight differs. */
static int beyond_far_edge(const image *tee, const image *alone, size_t *wt)
{
    int worst = 0;
    *wt = 0;
    for (uint32_t py = 0; py < tee->h; py++)
        for (uint32_t px = 0; px < tee->w; px++) {
            double x = (px + 0.5) * PIX, y = (py + 0.5) * PIX;
            turn(&x, &y, -rot);
            /* (a turned edge: half a pixel diagonal) */
            if (!(y > TY + TR + (rot != 0 ? 0.70710678 : 0.5) * PIX) || fabs(x - 30) > 25) continue;
            size_t i = (size_t)py * tee->w + px;
            /* turned: slanted edges inside a T's box come from 16 sub-rows
             * (roadfield.c tee_pixel), within 0.002 of exact */
            *wt += abs((int)tee->wt[i] - (int)alone->wt[i]) > (rot != 0 ? 160 : sub_rows ? sub_rows : 0);
            int d = rgb_diff(tee, alone, i);
            worst = d > worst ? d : worst;
        }
    return worst;
}

/* The side road's strip (|t| <= SR) from 12 m back up to the through
 * road's far edge line: pixels whose square lies inside by half a pixel
 * diagonal are all road (weight 65535). Returns the count that are not. */
static size_t strip_gaps(const image *im, double deg)
{
    double ux = cos(deg * DEG), uy = sin(deg * DEG), e = PIX * 0.70710678;
    size_t gaps = 0;
    for (uint32_t py = 0; py < im->h; py++)
        for (uint32_t px = 0; px < im->w; px++) {
            double x = (px + 0.5) * PIX, y = (py + 0.5) * PIX;
            turn(&x, &y, -rot);
            x -= 30, y -= TY;
            double u = x * ux + y * uy, t = x * uy - y * ux; /* along the side road (towards the T), across */
            if (fabs(t) > SR - e || u < -12 || y > TR - e) continue;
            gaps += im->wt[(size_t)py * im->w + px] != 65535;
        }
    return gaps;
}

static void test_tee_caps(const char *what)
{
    static const double degs[3] = { 90, 60, 40 };
    rs_roads *alone = NULL;
    CHECK(rs_roads_create(ctx, &alone) == RS_OK);
    add_walk(alone);
    add(alone, 2 * TR, "residential", 2, TY, 58, TY);
    image A;
    CHECK(render(alone, &A));
    for (int k = 0; k < 3; k++) {
        image ref = { 0 };
        for (int v = 0; v < 4; v++) {
            /* 0: one record each; 1: the through road split at the T; 2: the
             * side road split; 3: both */
            rs_roads *roads = tee_scene(degs[k], v & 1 ? 2 : 1, v & 2 ? 2 : 1);
            image B;
            CHECK(render(roads, &B));
            if (!B.rgba || !A.rgba) {
                image_free(&B);
                rs_roads_free(ctx, roads);
                continue;
            }
            size_t wt, gaps = strip_gaps(&B, degs[k]);
            int worst = beyond_far_edge(&B, &A, &wt);
            if (v == 0) printf("%s, T at %.0f deg: beyond the far edge %zu pixels of other weight, worst colour %d/255; %zu gaps in the strip\n",
                               what, degs[k], wt, worst, gaps);
            CHECKF(wt == 0, "T at %.0f deg (split %d): %zu pixels beyond the far edge have other road weight than the street alone",
                   degs[k], v, wt);
            /* turned: the through road's casing edge inside a T's box comes
             * from 16 sub-rows (roadfield.c tee_pixel), within 0.002 of exact */
            CHECKF(worst <= (rot != 0 ? 1 : 0),
                   "T at %.0f deg (split %d): beyond the far edge the colour differs by %d/255 from the through road alone",
                   degs[k], v, worst);
            CHECKF(gaps == 0, "T at %.0f deg (split %d): %zu pixels of the side road's strip are not whole road", degs[k], v, gaps);
            if (v == 0) ref = B;
            else {
                int d = 0;
                for (size_t i = 0; i < (size_t)B.w * B.h; i++) {
                    int q = rgb_diff(&B, &ref, i);
                    d = q > d ? q : d;
                }
                size_t wi = 0;
                for (size_t i = 0; i < (size_t)B.w * B.h; i++)
                    if (rgb_diff(&B, &ref, i) == d) { wi = i; break; }
                CHECKF(d <= 1, "T at %.0f deg: split %d draws %d/255 off the unsplit roads (at %.2f, %.2f)", degs[k], v, d,
                       (wi % B.w + 0.5) * PIX, (wi / B.w + 0.5) * PIX);
                image_free(&B);
            }
            rs_roads_free(ctx, roads);
        }
        image_free(&ref);
    }
    image_free(&A);
    rs_roads_free(ctx, alone);
}

/* A side road whose last segment is short (2 m, after a 10 degree bend):
 * the segment before it reaches past the far edge line too and is clipped
 * by it (its joint disc would bulge out 4 m). */
static void test_short_end_segment(void)
{
    rs_roads *alone = NULL;
    CHECK(rs_roads_create(ctx, &alone) == RS_OK);
    add(alone, 2 * TR, "residential", 2, TY, 58, TY);
    image A;
    CHECK(render(alone, &A));
    for (int k = 0; k < 2; k++) {
        double deg = k ? 60 : 90, ux = cos(deg * DEG), uy = sin(deg * DEG), b = (deg - 10) * DEG;
        double vx = 30 - 2 * ux, vy = TY - 2 * uy, sx = vx - 16 * cos(b), sy = vy - 16 * sin(b);
        rs_roads *roads = NULL;
        CHECK(rs_roads_create(ctx, &roads) == RS_OK);
        add(roads, 2 * TR, "residential", 2, TY, 58, TY);
        double xy[6] = { sx, sy, vx, vy, 30, TY };
        for (int j = 0; j < 3; j++) turn(&xy[2 * j], &xy[2 * j + 1], rot);
        CHECK(rs_roads_add(ctx, roads, "s", 2 * SR, xy, 3) == RS_OK);
        CHECK(rs_roads_set_attr(ctx, roads, 1, "class", "primary") == RS_OK);
        image B;
        CHECK(render(roads, &B));
        size_t wt = 0;
        int worst = B.rgba && A.rgba ? beyond_far_edge(&B, &A, &wt) : 255;
        printf("short end segment, T at %.0f deg: beyond the far edge %zu pixels of other weight, worst colour %d/255\n",
               deg, wt, worst);
        CHECKF(wt == 0 && worst == 0, "short end segment at %.0f deg: %zu pixels of road weight, colour %d/255 beyond the far edge",
               deg, wt, worst);
        image_free(&B);
        rs_roads_free(ctx, roads);
    }
    image_free(&A);
    rs_roads_free(ctx, alone);
}

/* A dead end (the side road stops 5 m short of the through road) keeps its
 * round cap: the disc beyond its end point is road. */
static void test_dead_end_keeps_cap(void)
{
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    add(roads, 2 * TR, "residential", 2, TY + 12, 58, TY + 12);
    add(roads, 2 * SR, "primary", 30, 2, 30, TY);
    image B;
    CHECK(render(roads, &B));
    size_t miss = 0, in = 0;
    for (uint32_t py = 0; B.wt && py < B.h; py++)
        for (uint32_t px = 0; px < B.w; px++) {
            double x = (px + 0.5) * PIX - 30, y = (py + 0.5) * PIX - TY;
            if (!(y > 0.2 && hypot(x, y) < SR - 0.2)) continue;
            in++;
            miss += B.wt[(size_t)py * B.w + px] != 65535;
        }
    CHECKF(in > 1000 && miss == 0, "a dead end lost %zu of %zu pixels of its round cap", miss, in);
    image_free(&B);
    rs_roads_free(ctx, roads);
}

/* A street whose two records at the T do not draw alike (3 m west of it,
 * 4 m east: no stroke passes there) is still the through road: two record
 * ends going straight on. The side road's strip stops at the narrower
 * one's far edge (the wider one's surface fills the rest); before, its
 * round cap bulged 6 m past both. */
static void test_through_of_two_looks(void)
{
    rs_roads *alone = NULL, *roads = NULL;
    CHECK(rs_roads_create(ctx, &alone) == RS_OK && rs_roads_create(ctx, &roads) == RS_OK);
    for (int k = 0; k < 2; k++) {
        rs_roads *r = k ? roads : alone;
        add(r, 2 * TR, "residential", 2, TY, 30, TY);
        add(r, 2 * TR + 1, "residential", 30, TY, 58, TY);
    }
    add(roads, 2 * SR, "primary", 30, 2, 30, TY);
    image A, B;
    CHECK(render(alone, &A) && render(roads, &B));
    size_t wt = 0;
    /* (the wider record's start disc in the T's box: its edge, nearly
     * level there, from 16 sub-rows: up to 1/32 of a pixel; 0.0083 at
     * (29.95, 21.95)) */
    sub_rows = 2048;
    int worst = A.rgba && B.rgba ? beyond_far_edge(&B, &A, &wt) : 255;
    sub_rows = 0;
    size_t gaps = B.wt ? strip_gaps(&B, 90) : 1;
    printf("through road of two looks: beyond the far edge %zu pixels of other weight, worst colour %d/255; %zu gaps\n",
           wt, worst, gaps);
    CHECKF(wt == 0 && worst <= 1, "a T on a street of two looks: %zu pixels beyond the far edge differ (worst %d/255)", wt,
           worst);
    CHECKF(gaps == 0, "a T on a street of two looks: %zu pixels of the side road's strip are not whole road", gaps);
    image_free(&A);
    image_free(&B);
    rs_roads_free(ctx, alone);
    rs_roads_free(ctx, roads);
}

/* Two roads of width w and class cls crossing at (30, TY) through a shared
 * point: A along y = TY from x = 2 to 58, B along x = 30 from y = b0 to 38. */
static void add_cross(rs_roads *r, double w, const char *cls, double b0)
{
    const double a[6] = { 2, TY, 30, TY, 58, TY }, b[6] = { 30, b0, 30, TY, 30, 38 };
    size_t n0 = rs_roads_count(r);
    CHECK(rs_roads_add(ctx, r, "A", w, a, 3) == RS_OK && rs_roads_add(ctx, r, "B", w, b, 3) == RS_OK);
    CHECK(rs_roads_set_attr(ctx, r, n0, "class", cls) == RS_OK && rs_roads_set_attr(ctx, r, n0 + 1, "class", cls) == RS_OK);
}

/* A side road ending where two streets cross (an X through a shared
 * point, both streets passing): its strip runs flat to the far edge line
 * of the street it meets most squarely (the first of two at 45 degrees)
 * and stops there. Before, a node with two through roads kept the round
 * cap: the 15 m primary bulged 6 m past the far edge. */
static void test_x_node(double deg)
{
    rs_roads *alone = NULL, *roads = NULL;
    CHECK(rs_roads_create(ctx, &alone) == RS_OK && rs_roads_create(ctx, &roads) == RS_OK);
    for (int k = 0; k < 2; k++) add_cross(k ? roads : alone, 2 * TR, "residential", 2);
    double x0, y0;
    side_end(deg, 18 / sin(deg * DEG), &x0, &y0);
    add(roads, 2 * SR, "primary", x0, y0, 30, TY);
    image A, B;
    CHECK(render(alone, &A) && render(roads, &B));
    size_t wt = 0;
    int worst = A.rgba && B.rgba ? beyond_far_edge(&B, &A, &wt) : 255;
    size_t gaps = B.wt ? strip_gaps(&B, deg) : 1;
    printf("side road at %.0f degrees ending on an X: beyond the far edge %zu pixels of other weight, worst colour "
           "%d/255; %zu gaps\n",
           deg, wt, worst, gaps);
    CHECKF(wt == 0 && worst <= 1, "a T at an X (%.0f degrees): %zu pixels beyond the far edge differ (worst %d/255)", deg,
           wt, worst);
    CHECKF(gaps == 0, "a T at an X (%.0f degrees): %zu pixels of the side road's strip are not whole road", deg, gaps);
    image_free(&A);
    image_free(&B);
    rs_roads_free(ctx, alone);
    rs_roads_free(ctx, roads);
}

/* The lines at an X with a road ending on its shared point: the road the
 * end meets most squarely keeps its centre line through the end's mouth,
 * as a through road does at a T (lib/scene/linesym.c rs__network_tees).
 * Three 8 m primaries: A and B cross, C ends there at 30 degrees to A (60
 * to B; B starts 24 m before A, so a dash of its 6/12 m centre line
 * reaches A's near edge). B's centre line before A equals B's in the X
 * without C but for 2 pixels of its end (36/255); before, a node with two
 * through roads had no T and C's surface cut the line's last 0.6 m (12
 * pixels, up to 107/255). */
static void test_x_lines(void)
{
    rs_roads *alone = NULL, *roads = NULL;
    CHECK(rs_roads_create(ctx, &alone) == RS_OK && rs_roads_create(ctx, &roads) == RS_OK);
    for (int k = 0; k < 2; k++) add_cross(k ? roads : alone, 8, "primary", TY - 24);
    double x0, y0;
    side_end(30, 30, &x0, &y0);
    add(roads, 8, "primary", x0, y0, 30, TY);
    image A, B;
    CHECK(render(alone, &A) && render(roads, &B));
    size_t diff = 0, n = 0;
    int worst = 0;
    for (uint32_t py = 0; A.rgba && B.rgba && py < B.h; py++)
        for (uint32_t px = 0; px < B.w; px++) {
            double x = (px + 0.5) * PIX, y = (py + 0.5) * PIX;
            if (fabs(x - 30) > 0.3 || y < TY - 12 || y > TY - 4 - 0.1) continue;
            n++;
            int d = rgb_diff(&A, &B, (size_t)py * B.w + px);
            diff += d != 0;
            worst = d > worst ? d : worst;
        }
    printf("X with a road ending: %zu of %zu centre line pixels differ from the X alone, worst %d/255\n", diff, n, worst);
    /* (the mouth's slanted cut of the edge zone, 2 m from the centre
     * line, crosses the line's last half pixel column: 2 pixels, 36/255) */
    CHECKF(n > 400 && diff <= 2 && worst <= 40,
           "at an X, %zu of %zu pixels of the centre line the side road meets most squarely differ from the X alone "
           "(worst %d/255): the line is cut", diff, n, worst);
    image_free(&A);
    image_free(&B);
    rs_roads_free(ctx, alone);
    rs_roads_free(ctx, roads);
}

/* A record whose start is a T on a street and which crosses that street
 * again further on keeps the crossing: only the segments from its T end on
 * up to the first that does not reach the far edge line are clipped.
 * (Every segment of the record reaching past the line was clipped: the
 * loop lost all of itself beyond the street at its second crossing; found
 * by fuzz/edits.) */
static void test_loop_crosses_again(void)
{
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    add(roads, 2 * TR, "residential", 2, TY, 58, TY); /* the street, y = TY */
    /* the loop: starts on the street at x = 10, runs 12 m south, east, and
     * back north across the street at x = 45, up to 12 m beyond it */
    const double xy[10] = { 10, TY, 10, TY - 12, 45, TY - 12, 45, TY + 12, 45, TY + 12.5 };
    CHECK(rs_roads_add(ctx, roads, "loop", 3, xy, 5) == RS_OK);
    CHECK(rs_roads_set_attr(ctx, roads, 1, "class", "residential") == RS_OK);
    image B;
    CHECK(render(roads, &B));
    size_t miss = 0, in = 0, beyond = 0;
    for (uint32_t py = 0; B.wt && py < B.h; py++)
        for (uint32_t px = 0; px < B.w; px++) {
            double x = (px + 0.5) * PIX, y = (py + 0.5) * PIX;
            uint16_t w = B.wt[(size_t)py * B.w + px];
            /* the loop's leg beyond the street's far side (y > TY + TR) */
            if (fabs(x - 45) < 1.3 && y > TY + TR + 0.3 && y < TY + 12) in++, miss += w != 65535;
            /* the T end itself: nothing beyond the far edge line there */
            if (fabs(x - 10) < 1.3 && y > TY + TR + 0.2) beyond += w != 0;
        }
    CHECKF(in > 2000 && miss == 0, "the loop's second crossing lost %zu of %zu pixels beyond the street", miss, in);
    CHECKF(beyond == 0, "%zu road pixels beyond the far edge at the loop's T end", beyond);
    image_free(&B);
    rs_roads_free(ctx, roads);
}

/* Windows of 37 x 23 pixels give the bytes of the whole image (the
 * trimmed pixels depend on their own coordinates only). */
static void test_windows(void)
{
    static float z[DW * DH];
    rs_roads *roads = tee_scene(40, 2, 2);
    rs_dem *dem = NULL;
    rs_splatter *s = NULL;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = TEX;
    CHECK(rs_dem_create(ctx, DW, DH, z, &dem) == RS_OK && rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK);
    image A = { 0 };
    if (s) {
        rs_splatter_size(s, &A.w, &A.h);
        A.rgba = malloc((size_t)A.w * A.h * 4);
        A.wt = malloc((size_t)A.w * A.h * sizeof *A.wt);
        CHECK(A.rgba && A.wt && rs_splat_window(ctx, s, 0, 0, A.w, A.h, A.rgba, (size_t)A.w * 4, A.wt, A.w, NULL) == RS_OK);
    }
    uint8_t win[37 * 23 * 4];
    uint16_t wwt[37 * 23];
    size_t bad = 0;
    for (uint32_t y0 = 0; s && A.rgba && y0 < A.h; y0 += 23)
        for (uint32_t x0 = 0; x0 < A.w; x0 += 37) {
            uint32_t w = A.w - x0 < 37 ? A.w - x0 : 37, h = A.h - y0 < 23 ? A.h - y0 : 23;
            CHECK(rs_splat_window(ctx, s, x0, y0, w, h, win, 37 * 4, wwt, 37, NULL) == RS_OK);
            for (uint32_t y = 0; y < h; y++) {
                size_t i = (size_t)(y0 + y) * A.w + x0;
                bad += memcmp(win + 37 * 4 * y, A.rgba + 4 * i, 4 * w) != 0 ||
                       memcmp(wwt + 37 * y, A.wt + i, w * sizeof *wwt) != 0;
            }
        }
    CHECKF(bad == 0, "%zu window rows differ from the whole image at a trimmed T", bad);
    image_free(&A);
    rs_splatter_free(ctx, s);
    rs_dem_free(ctx, dem);
    rs_roads_free(ctx, roads);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_loop_crosses_again();
    test_x_node(45);
    test_x_node(60);
    test_x_lines();
    test_tee_caps("built-in styles");
    /* casings: the side road's (1 m) stops at the through road's casing's
     * far edge (0.3 m beyond its surface) */
    styles_text = "style residential\n  casing 0.3 #C8C8C8\n  fill #505050\nend\n"
                  "style primary\n  casing 1.0 #E0A040\n  fill #404040\n  line 0 0.15 #FFFFFF dash 3 6\nend\n";
    test_tee_caps("casings");
    styles_text = NULL;
    /* a footway beyond the far edge keeps its dashes (the side road's
     * surface cuts lines only up to the far edge line, lib/scene/linesym.c) */
    styles_text = "style residential\n  fill #505050\n  line 1.35 0.12 #FFFFFF\n  line -1.35 0.12 #FFFFFF\nend\n"
                  "style primary\n  fill #404040\n  line 0 0.15 #FFFFFF dash 3 6\nend\n"
                  "style footway\n  fill #9A9A90\n  line 0 0.3 #FFFFFF dash 1 1\nend\n";
    with_walk = 1;
    test_tee_caps("a footway beyond the far edge");
    rot = 30 * DEG;
    test_tee_caps("a footway beyond the far edge, turned 30 degrees");
    with_walk = 0;
    styles_text = NULL;
    rot = 25 * DEG;
    test_tee_caps("built-in styles, turned 25 degrees");
    rot = -110 * DEG;
    test_tee_caps("built-in styles, turned -110 degrees");
    rot = 0;
    /* ends inside the 3 m street, 1 m short of its centre line or 0.9 m
     * past it (before, their 7.5 m round caps bulged up to 7 m past the
     * far edge) */
    end_shift = -1.0;
    test_tee_caps("built-in styles, the side road ending 1 m short of the centre line");
    end_shift = 0.9;
    test_tee_caps("built-in styles, the side road ending 0.9 m past the centre line");
    styles_text = "style residential\n  casing 0.3 #C8C8C8\n  fill #505050\nend\n"
                  "style primary\n  casing 1.0 #E0A040\n  fill #404040\n  line 0 0.15 #FFFFFF dash 3 6\nend\n";
    end_shift = -1.0;
    test_tee_caps("casings, the side road ending 1 m short of the centre line");
    styles_text = NULL;
    end_shift = 0;
    test_dead_end_keeps_cap();
    test_through_of_two_looks();
    test_short_end_segment();
    test_windows();
    rs_ctx_free(ctx);
    return th_finish("test_tee_caps");
}
