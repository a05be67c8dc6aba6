/* Paint stays on the road (issue 25): with casings, lines, surfaces and
 * markings together, every pixel farther from every road than its half
 * width plus its casing equals the road-free render, and windows of any
 * offset and size (1-px rows, the last partial row) and any thread count
 * give the bytes of the whole image. On b8396fd the line symbols used the
 * one-colour casing's coverage buffer as scratch, so the composite blended
 * kerb grey onto bare terrain on the first rows of each DEM-cell row and
 * windows differed from crops. */
#include "roadsplat.h"
#include "harness.h"
#include "band_threads.h"
#include "scenes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;

enum { DW = 31, DH = 31, TEX = 8 };
#define CELL 2.0
#define PIX (CELL / TEX)

/* Each scene: road text (with styles and marks), and per road the reach of
 * its paint from the centreline: half width + casing width. */
typedef struct scene {
    const char *name;
    const char *text;
} scene;

/* Default class styles: kerb casings of one colour, RMS lines, automatic
 * and explicit markings. */
static const char class_text[] =
    "road main_w width 10 class=primary turn:lanes=left|through;right\n"
    "0 30.3\n25 31.1 crossing=zebra\n37.7 30\nend\n"
    "road main_e width 10 class=primary\n60 29.2\n37.7 30\nend\n"
    "road north width 7 class=residential\n30.4 0\n37.7 30\nend\n"
    "road south width 7 class=residential control=stop turn:lanes=through;left|right\n31 60\n37.7 30\nend\n"
    "road lane width 4 class=service\n2.1 3.3\n14.9 9.7\n6.2 22.5\nend\n"
    "mark word_bus road=main_w s=8 t=-2.5 length=3 width=2\n"
    "mark cycle road=north s=6 t=-1.75\n";

/* Styles of their own: one casing colour with dashed lines, and two
 * casing colours (the overlays stage's per-pixel path) with a gradient. */
static const char one_casing_text[] =
    "style k\n casing 0.5 #606060\n line 0 0.15 #FFFFFF dash 3 6 phase 1\n line 2.2 0.2 #F0F000\nend\n"
    "road a width 6 style=k\n1.3 7.7\n58.1 13.4\nend\n"
    "road b width 5 style=k\n9.9 58.6\n30.2 10.4\n52.3 55.5\nend\n"
    "road c width 3 style=k\n44.4 2.2\n48.8 30.6\nend\n"
    "mark arrow_left road=a s=20 t=-1.5\n";

static const char two_casings_text[] =
    "style k\n casing 0.5 #606060\n line 0 0.15 #FFFFFF dash 3 6\nend\n"
    "style m\n gradient #202020 #505050\n casing 0.8 #B04020\n line -1.2 0.12 #FFFFFF\n line 1.2 0.12 #FFFFFF dash 1 1\nend\n"
    "road a width 6 style=k\n1.3 7.7\n58.1 13.4\nend\n"
    "road b width 5 style=m\n9.9 58.6\n30.2 10.4\n52.3 55.5\nend\n"
    "road c width 3 style=m\n44.4 2.2\n48.8 30.6\nend\n";

static const scene scenes[] = {
    { "class styles", class_text },
    { "one casing colour", one_casing_text },
    { "two casing colours", two_casings_text },
};

static rs_dem *make_dem(void)
{
    float *z = malloc(sizeof(float) * DW * DH);
    if (!z) return NULL;
    sc_dem_terrain(z, DW, DH, CELL, 7);
    rs_dem *dem = NULL;
    rs_dem_frame fr = { CELL, 0.01, 0, 0 };
    if (rs_dem_create(ctx, DW, DH, z, &dem) != RS_OK) dem = NULL;
    else if (rs_dem_set_frame(ctx, dem, &fr) != RS_OK) {
        rs_dem_free(ctx, dem);
        dem = NULL;
    }
    free(z);
    return dem;
}

static double seg_dist(const double *a, const double *b, double x, double y)
{
    double dx = b[0] - a[0], dy = b[1] - a[1], wx = x - a[0], wy = y - a[1];
    double l2 = dx * dx + dy * dy, u = l2 > 0 ? (wx * dx + wy * dy) / l2 : 0;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    double ex = wx - u * dx, ey = wy - u * dy;
    return sqrt(ex * ex + ey * ey);
}

/* Distance from (x, y) to the nearest paint reach of any road: the
 * centreline distance less the half width and the casing width. */
static double off_road(const rs_roads *roads, const rs_styles *styles, double x, double y)
{
    double best = INFINITY;
    for (size_t i = 0; i < rs_roads_count(roads); i++) {
        const double *xy;
        size_t n;
        double w;
        rs_road_info info;
        if (rs_roads_get(roads, i, NULL, &w, &xy, &n) != RS_OK || rs_roads_get_info(roads, i, &info) != RS_OK)
            continue;
        double reach = w / 2;
        const rs_style *st = info.style && styles ? rs_styles_find(styles, info.style) : NULL;
        /* the default class styles' kerbs are at most 0.3 m; be generous */
        reach += st ? st->casing_width : 0.5;
        for (size_t k = 0; k + 1 < n; k++) {
            double d = seg_dist(xy + 2 * k, xy + 2 * k + 2, x, y) - reach;
            if (d < best) best = d;
        }
        if (n == 1) {
            double d = hypot(x - xy[0], y - xy[1]) - reach;
            if (d < best) best = d;
        }
    }
    return best;
}

typedef struct render {
    rs_splatter *s;
    uint32_t w, h;
    uint8_t *rgba;
    uint16_t *wt;
} render;

static int render_whole(const rs_dem *dem, const rs_roads *roads, const rs_styles *styles, render *r)
{
    memset(r, 0, sizeof *r);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = TEX;
    o.style.styles = styles;
    if (rs_splatter_create(ctx, dem, roads, NULL, &o, &r->s) != RS_OK) return 0;
    rs_splatter_size(r->s, &r->w, &r->h);
    r->rgba = malloc((size_t)r->w * r->h * 4);
    r->wt = malloc((size_t)r->w * r->h * 2);
    return r->rgba && r->wt &&
           rs_splat_window(ctx, r->s, 0, 0, r->w, r->h, r->rgba, (size_t)r->w * 4, r->wt, r->w, NULL) == RS_OK;
}

static void render_free(render *r)
{
    rs_splatter_free(ctx, r->s);
    free(r->rgba);
    free(r->wt);
}

/* Window (x, y, w, h) against the crop of the whole image. */
static int window_equal(const render *r, uint32_t x, uint32_t y, uint32_t w, uint32_t h)
{
    uint8_t *win = malloc((size_t)w * h * 4);
    uint16_t *wt = malloc((size_t)w * h * 2);
    int ok = win && wt && rs_splat_window(ctx, r->s, x, y, w, h, win, (size_t)w * 4, wt, w, NULL) == RS_OK;
    for (uint32_t j = 0; ok && j < h; j++)
        ok = memcmp(win + (size_t)j * w * 4, r->rgba + ((size_t)(y + j) * r->w + x) * 4, (size_t)w * 4) == 0 &&
             memcmp(wt + (size_t)j * w, r->wt + (size_t)(y + j) * r->w + x, (size_t)w * 2) == 0;
    free(win);
    free(wt);
    return ok;
}

static void test_scene(const rs_dem *dem, const scene *sc)
{
    rs_styles *styles = NULL;
    rs_roads *roads = NULL, *none = NULL;
    CHECK(rs_styles_create(ctx, &styles) == RS_OK);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = styles;
    CHECK(rs_roads_parse_ex(ctx, sc->text, strlen(sc->text), &po, &roads) == RS_OK);
    CHECK(rs_roads_create(ctx, &none) == RS_OK);
    if (!roads || !none || !styles) goto out;
    render whole, bare;
    int ok = render_whole(dem, roads, styles, &whole);
    int ok_bare = render_whole(dem, none, styles, &bare);
    CHECKF(ok && ok_bare, "%s: renders", sc->name);
    if (ok && ok_bare && whole.w == bare.w && whole.h == bare.h) {
        /* no paint off the road */
        size_t far = 0, differ = 0, weighted = 0;
        int worst = 0;
        for (uint32_t y = 0; y < whole.h; y++)
            for (uint32_t x = 0; x < whole.w; x++) {
                double d = off_road(roads, styles, (x + 0.5) * PIX, (y + 0.5) * PIX);
                if (!(d > PIX * 0.7072 + 1e-6)) continue;
                far++;
                size_t i = (size_t)y * whole.w + x;
                weighted += whole.wt[i] != 0;
                int diff = 0;
                for (int c = 0; c < 4; c++) {
                    int e = abs((int)whole.rgba[4 * i + c] - (int)bare.rgba[4 * i + c]);
                    if (e > diff) diff = e;
                }
                if (diff) differ++;
                if (diff > worst) worst = diff;
            }
        CHECKF(far > (size_t)whole.w * whole.h / 4, "%s: most pixels are off the road (%zu)", sc->name, far);
        CHECKF(differ == 0 && weighted == 0, "%s: %zu off-road pixels differ from the road-free render (max %d), "
                  "%zu have road weight", sc->name, differ, worst, weighted);
        /* windows: 1-px rows, 1-px columns, odd offsets, the last partial row */
        int wins = 1;
        for (uint32_t y = 0; wins && y < whole.h; y += 37) wins = window_equal(&whole, 0, y, whole.w, 1);
        for (uint32_t x = 3; wins && x < whole.w; x += 41) wins = window_equal(&whole, x, 0, 1, whole.h);
        sc_rng rng;
        sc_rng_seed(&rng, 25);
        for (int k = 0; wins && k < 40; k++) {
            uint32_t x = (uint32_t)(sc_rng_unit(&rng) * whole.w), y = (uint32_t)(sc_rng_unit(&rng) * whole.h);
            uint32_t w = 1 + (uint32_t)(sc_rng_unit(&rng) * (whole.w - x));
            uint32_t h = 1 + (uint32_t)(sc_rng_unit(&rng) * (whole.h - y));
            if (w > whole.w - x) w = whole.w - x;
            if (h > whole.h - y) h = whole.h - y;
            wins = window_equal(&whole, x, y, w, h);
            if (!wins) fprintf(stderr, "  window %u,%u %ux%u differs\n", x, y, w, h);
        }
        /* the last partial band of rows and columns */
        if (wins) wins = window_equal(&whole, whole.w - 5, whole.h - 3, 5, 3);
        CHECKF(wins, "%s: windows equal crops of the whole image", sc->name);
        /* threads, in row bands of odd heights */
        CHECKF(bt_threads_equal(whole.s, NULL, whole.rgba, whole.w, whole.h, 7, 3),
                  "%s: 3 threads in 7-row bands give the same bytes", sc->name);
        CHECKF(bt_threads_equal(whole.s, NULL, whole.rgba, whole.w, whole.h, 1, 2),
                  "%s: 2 threads in 1-row bands give the same bytes", sc->name);
    }
    render_free(&whole);
    render_free(&bare);
out:
    rs_roads_free(ctx, roads);
    rs_roads_free(ctx, none);
    rs_styles_free(ctx, styles);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    rs_dem *dem = make_dem();
    CHECK(dem != NULL);
    if (dem)
        for (size_t i = 0; i < sizeof scenes / sizeof *scenes; i++) test_scene(dem, &scenes[i]);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    return th_finish("test_paint_bounds");
}
