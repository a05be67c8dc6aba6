/* The staged, windowed splatter: any tiling of the image into windows, and
 * any number of threads, gives the bytes of the whole image; argument and
 * grid checks; allocation failure. */
#include "harness.h"
#include "fail_alloc.h"
#include "roadsplat.h"
#include "scenes.h"
#include "scene_splat.h"
#include "band_threads.h"

#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;

typedef struct fixture {
    sc_scene sc;
    rs_dem *dem;
    rs_roads *roads;
    rs_roads *sroads;   /* the same roads with class= and style= attributes */
    rs_styles *styles;
    rs_image tex[2];
    uint8_t tex_px[2][5 * 3 * 4];
} fixture;

/* A small scene with a bend, a crossing, a dead end and nodata. */
static void fixture_init(fixture *f, double origin)
{
    memset(f, 0, sizeof *f);
    CHECK(sc_scene_init(&f->sc, 37, 29, 2.5) == 0);
    sc_dem_terrain(f->sc.z, 37, 29, 2.5, 5);
    f->sc.z[11 * 37 + 7] = NAN;
    const double a[] = { 3, 4, 40, 30, 85, 8 }, b[] = { 10, 60, 60, 20 }, c[] = { 70, 50, 71, 52 };
    double t[6];
    CHECK(rs_dem_create(ctx, 37, 29, f->sc.z, &f->dem) == RS_OK);
    rs_dem_frame fr = { 2.5, 0.5, origin, -origin };
    CHECK(rs_dem_set_frame(ctx, f->dem, &fr) == RS_OK);
    CHECK(rs_roads_create(ctx, &f->roads) == RS_OK);
    for (int i = 0; i < 6; i++) t[i] = a[i] + (i & 1 ? -origin : origin);
    CHECK(rs_roads_add(ctx, f->roads, "a", 6.5, t, 3) == RS_OK);
    for (int i = 0; i < 4; i++) t[i] = b[i] + (i & 1 ? -origin : origin);
    CHECK(rs_roads_add(ctx, f->roads, "b", 3.0, t, 2) == RS_OK);
    for (int i = 0; i < 4; i++) t[i] = c[i] + (i & 1 ? -origin : origin);
    CHECK(rs_roads_add(ctx, f->roads, "c", 1.2, t, 2) == RS_OK);
    /* styled copy: a primary road with lines, a gradient with a casing and
     * dashes, a residential street with a kerb */
    static const char style_text[] = "style gradkerb\n"
                                     "  gradient #505050 #909090\n"
                                     "  casing 0.8 #C0C0C0\n"
                                     "  line 0 0.3 #FFFFFF dash 1.5 1 phase 0.4\n"
                                     "  line 1.2 0.15 #FFFF00C0\n"
                                     "end\n";
    CHECK(rs_styles_parse(ctx, style_text, sizeof style_text - 1, &f->styles) == RS_OK);
    CHECK(rs_roads_create(ctx, &f->sroads) == RS_OK);
    static const char *const attr[3][2] = { { "class", "primary" }, { "style", "gradkerb" }, { "class", "residential" } };
    for (size_t i = 0; i < 3; i++) {
        const char *name;
        double w;
        const double *xy;
        size_t n;
        CHECK(rs_roads_get(f->roads, i, &name, &w, &xy, &n) == RS_OK);
        CHECK(rs_roads_add(ctx, f->sroads, name, w, xy, n) == RS_OK);
        CHECK(rs_roads_set_attr(ctx, f->sroads, i, attr[i][0], attr[i][1]) == RS_OK);
    }
    /* markings (issue 14) on the styled copy: one over the bend of road a,
     * one flipped, one across road b */
    static const rs_mark marks[] = { { "arrow_straight", 0, 20, -1.5, 0, 0, 0, 0 },
                                     { "word_slow", 0, 44, 1.5, 12, 2.5, 1, 0 },
                                     { "zebra", 1, 20, 0, 0, 3.0, 0, 0 },
                                     { "stop_line", 0, 60, -1.6, 0, 3.2, 0, 0 } };
    for (size_t i = 0; i < sizeof marks / sizeof marks[0]; i++) CHECK(rs_roads_add_mark(ctx, f->sroads, &marks[i]) == RS_OK);
    for (int k = 0; k < 2; k++) {
        for (size_t i = 0; i < sizeof f->tex_px[k]; i++) f->tex_px[k][i] = (uint8_t)(i * 37 + k * 101);
        f->tex[k].width = 5;
        f->tex[k].height = 3;
        f->tex[k].rgba = f->tex_px[k];
    }
}

static void fixture_free(fixture *f)
{
    rs_roads_free(ctx, f->roads);
    rs_roads_free(ctx, f->sroads);
    rs_styles_free(ctx, f->styles);
    rs_dem_free(ctx, f->dem);
    sc_scene_free(&f->sc);
}

typedef struct whole {
    uint32_t w, h;
    uint8_t *rgba;
    uint16_t *wt;
} whole;

static rs_result render_whole(const rs_splatter *s, whole *im)
{
    rs_splatter_size(s, &im->w, &im->h);
    size_t n = (size_t)im->w * im->h;
    im->rgba = malloc(n * 4);
    im->wt = malloc(n * 2);
    return rs_splat_window(ctx, s, 0, 0, im->w, im->h, im->rgba, (size_t)im->w * 4, im->wt, im->w, NULL);
}

/* Cut the image into a grid of windows with the given (odd) sizes and an
 * offset first row/column, render each into a padded buffer, compare. */
static int tiled_equal(const rs_splatter *s, const whole *ref, uint32_t tw, uint32_t th, uint32_t off)
{
    size_t stride = (size_t)ref->w * 4 + 20, wstride = ref->w + 7;
    uint8_t *px = malloc(stride * ref->h);
    uint16_t *wt = malloc(wstride * ref->h * 2);
    int ok = px && wt;
    memset(px, 0xA5, stride * ref->h);
    for (uint32_t y = 0; ok && y < ref->h;) {
        uint32_t hh = y == 0 && off ? off : th;
        if (hh > ref->h - y) hh = ref->h - y;
        for (uint32_t x = 0; ok && x < ref->w;) {
            uint32_t ww = x == 0 && off ? off : tw;
            if (ww > ref->w - x) ww = ref->w - x;
            ok = rs_splat_window(ctx, s, x, y, ww, hh, px + y * stride + (size_t)x * 4, stride, wt + y * wstride + x,
                                 wstride, NULL) == RS_OK;
            x += ww;
        }
        y += hh;
    }
    for (uint32_t y = 0; ok && y < ref->h; y++) {
        ok = memcmp(px + y * stride, ref->rgba + (size_t)y * ref->w * 4, (size_t)ref->w * 4) == 0 &&
             memcmp(wt + y * wstride, ref->wt + (size_t)y * ref->w, (size_t)ref->w * 2) == 0;
        for (size_t k = (size_t)ref->w * 4; ok && k < stride; k++) ok = px[y * stride + k] == 0xA5;
    }
    free(px);
    free(wt);
    return ok;
}

static void settings(int i, rs_splat_options *o, fixture *f, const char **name)
{
    memset(o, 0, sizeof *o);
    o->texels = 3;
    o->coverage.edges = RS_EDGES_ALPHAMAP;
    switch (i) {
    case 0: *name = "alpha-map defaults, 3 texels"; break;
    case 1: *name = "dilate, 5 texels"; o->texels = 5; o->grid.buffer = RS_BUFFER_DILATE; break;
    case 2: *name = "hard edge, road cell"; o->coverage.hard_edge = 1; o->grid.road_cell = 0.9; break;
    case 3: *name = "jitter seed 0, alpha-res 8";
        o->coverage.jitter = 1; o->coverage.alpha_res = 8; o->coverage.transition_px = 3; break;
    case 4: *name = "textures"; o->surface.terrain_texture = &f->tex[0]; o->surface.road_texture = &f->tex[1];
        o->surface.texture_scale = 3.7; break;
    case 5: *name = "1 texel"; o->texels = 1; break;
    case 6: *name = "defaults (analytic edges), 4 texels"; memset(o, 0, sizeof *o); o->texels = 4; break;
    case 7: *name = "analytic, textures, 7 texels"; o->coverage.edges = RS_EDGES_ANALYTIC; o->texels = 7;
        o->surface.terrain_texture = &f->tex[0]; break;
    case 8: *name = "styles and markings (analytic), 4 texels"; memset(o, 0, sizeof *o); o->texels = 4; o->style.styles = f->styles;
        break;
    default: *name = "styles and markings, alpha-map, Hermite lines, US profile, 5 texels"; o->texels = 5;
        o->style.styles = f->styles; o->style.aa = RS_LINE_AA_HERMITE; o->style.profile = RS_PROFILE_MUTCD; break;
    }
}

#define NSETTINGS 10

/* The roads of setting i: the styled copy for the style settings. */
static const rs_roads *roads_for(int i, const fixture *f)
{
    return i >= 8 ? f->sroads : f->roads;
}

static void test_tiling(void)
{
    fixture f;
    fixture_init(&f, 0);
    static const uint32_t cuts[][3] = { { 1, 1, 0 }, { 7, 5, 3 }, { 13, 64, 1 }, { 31, 2, 0 }, { 200, 9, 11 },
                                        { 3, 300, 2 } };
    for (int i = 0; i < NSETTINGS; i++) {
        rs_splat_options o;
        const char *name;
        settings(i, &o, &f, &name);
        rs_splatter *s = NULL;
        rs_result r = rs_splatter_create(ctx, f.dem, roads_for(i, &f), NULL, &o, &s);
        CHECKF(r == RS_OK, "%s: %s", name, rs_ctx_message(ctx));
        if (r) continue;
        whole ref;
        CHECK(render_whole(s, &ref) == RS_OK);
        uint64_t road = 0;
        for (size_t k = 0; k < (size_t)ref.w * ref.h; k++) road += ref.wt[k] != 0;
        CHECKF(road > 0, "%s: no road drawn", name);
        for (size_t c = 0; c < sizeof cuts / sizeof cuts[0]; c++)
            CHECKF(tiled_equal(s, &ref, cuts[c][0], cuts[c][1], cuts[c][2]), "%s: windows %ux%u (first %u) differ",
                   name, cuts[c][0], cuts[c][1], cuts[c][2]);
        /* rs_splat on the same grid gives the same bytes too */
        uint8_t *px = malloc((size_t)ref.w * ref.h * 4);
        CHECK(rs_splat(ctx, f.dem, rs_splatter_grid(s), &o, px, (size_t)ref.w * ref.h * 4, NULL, 0) == RS_OK);
        CHECKF(memcmp(px, ref.rgba, (size_t)ref.w * ref.h * 4) == 0, "%s: rs_splat differs", name);
        free(px);
        free(ref.rgba);
        free(ref.wt);
        rs_splatter_free(ctx, s);
    }
    fixture_free(&f);
}

/* The style settings draw something: setting 8 is setting 6 plus styles. */
static void test_styles_drawn(void)
{
    fixture f;
    fixture_init(&f, 0);
    whole im[2] = { { 0, 0, NULL, NULL }, { 0, 0, NULL, NULL } };
    const int which[2] = { 6, 8 };
    for (int k = 0; k < 2; k++) {
        rs_splat_options o;
        const char *name;
        settings(which[k], &o, &f, &name);
        rs_splatter *s = NULL;
        CHECK(rs_splatter_create(ctx, f.dem, roads_for(which[k], &f), NULL, &o, &s) == RS_OK);
        if (s) CHECK(render_whole(s, &im[k]) == RS_OK);
        rs_splatter_free(ctx, s);
    }
    size_t differ = 0, n = (size_t)im[0].w * im[0].h;
    for (size_t i = 0; im[0].rgba && im[1].rgba && i < n; i++) differ += memcmp(im[0].rgba + 4 * i, im[1].rgba + 4 * i, 4) != 0;
    CHECKF(differ > n / 20, "styles changed only %zu of %zu pixels", differ, n);
    /* the road weight is the road's, styles or not */
    CHECK(im[0].wt && im[1].wt && memcmp(im[0].wt, im[1].wt, n * 2) == 0);
    for (int k = 0; k < 2; k++) free(im[k].rgba), free(im[k].wt);
    fixture_free(&f);
}

/* A scene translated by 5e6 m (roads and origin together): same bytes. */
static void test_translation(void)
{
    fixture a, b;
    fixture_init(&a, 0);
    fixture_init(&b, 5e6);
    for (int i = 0; i < NSETTINGS; i++) {
        rs_splat_options o;
        const char *name;
        settings(i, &o, &a, &name);
        settings(i, &o, &b, &name);
        rs_splatter *sa = NULL, *sb = NULL;
        o.style.styles = a.styles; /* the two fixtures' style sets are the same */
        CHECK(rs_splatter_create(ctx, a.dem, roads_for(i, &a), NULL, &o, &sa) == RS_OK);
        CHECK(rs_splatter_create(ctx, b.dem, roads_for(i, &b), NULL, &o, &sb) == RS_OK);
        whole ia = { 0, 0, NULL, NULL }, ib = { 0, 0, NULL, NULL };
        if (sa && sb && render_whole(sa, &ia) == RS_OK && render_whole(sb, &ib) == RS_OK)
            CHECKF(memcmp(ia.rgba, ib.rgba, (size_t)ia.w * ia.h * 4) == 0, "%s: translation by 5e6 m changed bytes",
                   name);
        free(ia.rgba); free(ia.wt); free(ib.rgba); free(ib.wt);
        rs_splatter_free(ctx, sa);
        rs_splatter_free(ctx, sb);
    }
    fixture_free(&a);
    fixture_free(&b);
}

/* Threads: one splatter, N threads with their own contexts rendering
 * interleaved row bands at once, for N = 1..4; every result the same. */
static void test_threads(void)
{
    fixture f;
    fixture_init(&f, 0);
    for (int i = 0; i < NSETTINGS; i += 3) {
        rs_splat_options o;
        const char *name;
        settings(i, &o, &f, &name);
        rs_splatter *s = NULL;
        CHECK(rs_splatter_create(ctx, f.dem, roads_for(i, &f), NULL, &o, &s) == RS_OK);
        if (!s) continue;
        whole ref;
        CHECK(render_whole(s, &ref) == RS_OK);
        for (uint32_t n = 1; n <= 4; n++)
            CHECKF(bt_threads_equal(s, NULL, ref.rgba, ref.w, ref.h, 5, n), "%s: %u threads differ", name, n);
        free(ref.rgba);
        free(ref.wt);
        rs_splatter_free(ctx, s);
    }
    fixture_free(&f);
}

static void test_arguments(void)
{
    fixture f;
    fixture_init(&f, 0);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 2;
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* grid options only bind alpha-map grids */
    rs_splatter *s = (rs_splatter *)&o;
    CHECK(rs_splatter_create(ctx, f.dem, NULL, NULL, &o, &s) == RS_ERR_INVALID_ARG && s == NULL);
    rs_road_grid *g = NULL;
    CHECK(rs_road_grid_build(ctx, f.dem, f.roads, &o, &g) == RS_OK);
    s = (rs_splatter *)&o;
    CHECK(rs_splatter_create(ctx, f.dem, f.roads, g, &o, &s) == RS_ERR_INVALID_ARG && s == NULL);
    /* a grid built for other options, another frame or another DEM */
    rs_splat_options o2 = o;
    o2.texels = 3;
    CHECK(rs_splatter_create(ctx, f.dem, NULL, g, &o2, &s) == RS_ERR_INVALID_ARG);
    CHECK(strstr(rs_ctx_message(ctx), "texels") != NULL);
    o2 = o;
    o2.grid.buffer = RS_BUFFER_DILATE;
    CHECK(rs_splatter_create(ctx, f.dem, NULL, g, &o2, &s) == RS_ERR_INVALID_ARG);
    o2 = o;
    o2.coverage.edges = RS_EDGES_ANALYTIC;
    CHECK(rs_splatter_create(ctx, f.dem, NULL, g, &o2, &s) == RS_ERR_INVALID_ARG);
    CHECK(rs_splat(ctx, f.dem, g, &o2, (uint8_t *)&o2, 4, NULL, 0) == RS_ERR_INVALID_ARG);
    rs_dem_frame fr = { 2.5, 0.5, 10, 0 };
    CHECK(rs_dem_set_frame(ctx, f.dem, &fr) == RS_OK);
    CHECK(rs_splatter_create(ctx, f.dem, NULL, g, &o, &s) == RS_ERR_INVALID_ARG);
    CHECK(strstr(rs_ctx_message(ctx), "origin") != NULL);
    fr.origin_x = 0;
    CHECK(rs_dem_set_frame(ctx, f.dem, &fr) == RS_OK);
    CHECK(rs_splatter_create(ctx, f.dem, NULL, g, &o, &s) == RS_OK);
    uint32_t w, h;
    rs_splatter_size(s, &w, &h);
    CHECK(w == 36 * 2 && h == 28 * 2);
    uint8_t px[16 * 4];
    uint16_t wt[16];
    CHECK(rs_splat_window(ctx, s, 0, 0, 0, 1, px, 64, NULL, 0, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_splat_window(ctx, s, w - 3, 0, 4, 1, px, 64, NULL, 0, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_splat_window(ctx, s, 0, h, 1, 1, px, 64, NULL, 0, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_splat_window(ctx, s, 0, 0, 16, 1, px, 63, NULL, 0, NULL) == RS_ERR_BUFFER_TOO_SMALL);
    CHECK(rs_splat_window(ctx, s, 0, 0, 16, 1, px, 64, wt, 15, NULL) == RS_ERR_BUFFER_TOO_SMALL);
    CHECK(rs_splat_window(ctx, s, 0, 0, 16, 1, NULL, 64, NULL, 0, NULL) == RS_ERR_INVALID_ARG);
    /* the profile adds up pixels and calls the caller's clock */
    rs_splat_profile pf;
    memset(&pf, 0, sizeof pf);
    CHECK(rs_splat_window(ctx, s, 0, 0, 16, 1, px, 64, wt, 16, &pf) == RS_OK);
    CHECK(rs_splat_window(ctx, s, 0, 1, 16, 1, px, 64, wt, 16, &pf) == RS_OK);
    CHECK_EQ_INT(pf.pixels, 32);
    rs_splatter_free(ctx, s);
    rs_road_grid_free(ctx, g);
    /* a texture over the context's max_texture_pixels is refused */
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_texture_pixels = 14;
    rs_ctx *c2 = NULL;
    CHECK(rs_ctx_create(NULL, &lim, &c2) == RS_OK);
    o.surface.terrain_texture = &f.tex[0]; /* 5 x 3 */
    CHECK(rs_splatter_create(c2, f.dem, f.roads, NULL, &o, &s) == RS_ERR_LIMIT && s == NULL);
    CHECK(strstr(rs_ctx_message(c2), "texture") != NULL);
    lim.max_texture_pixels = 15;
    rs_ctx_free(c2);
    CHECK(rs_ctx_create(NULL, &lim, &c2) == RS_OK);
    CHECK(rs_splatter_create(c2, f.dem, f.roads, NULL, &o, &s) == RS_OK);
    rs_splatter_free(c2, s);
    rs_ctx_free(c2);
    fixture_free(&f);
}

/* Every allocation of create + window failing in turn: RS_ERR_NOMEM, no leak. */

/* Modes 0, 1: alpha-map and analytic edges; 2, 3: the same on the styled roads. */
typedef struct alloc_case {
    const fixture *f;
    int mode;
} alloc_case;

static rs_result alloc_try(rs_ctx *c, void *user, int *wrong)
{
    const alloc_case *ac = user;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 2;
    o.coverage.edges = ac->mode & 1 ? RS_EDGES_ANALYTIC : RS_EDGES_ALPHAMAP;
    if (ac->mode >= 2) o.style.styles = ac->f->styles;
    rs_splatter *s = NULL;
    uint8_t px[9 * 7 * 4];
    rs_result r = rs_splatter_create(c, ac->f->dem, ac->mode >= 2 ? ac->f->sroads : ac->f->roads, NULL, &o, &s);
    if (!r) r = rs_splat_window(c, s, 3, 4, 9, 7, px, 9 * 4, NULL, 0, NULL);
    (void)wrong;
    rs_splatter_free(c, s);
    return r;
}

static void test_alloc_failures(void)
{
    fixture f;
    fixture_init(&f, 0);
    for (int mode = 0; mode < 4; mode++) {
        alloc_case ac = { &f, mode };
        fail_sweep fs = fail_alloc_sweep(5000, alloc_try, &ac);
        CHECK_SWEEP(fs, 3);
    }
    fixture_free(&f);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_tiling();
    test_styles_drawn();
    test_translation();
    test_threads();
    test_arguments();
    test_alloc_failures();
    rs_ctx_free(ctx);
    return th_finish("test_window");
}
