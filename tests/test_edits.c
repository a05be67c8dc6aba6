/* Road edits and dirty rectangles (issue 30): rs_roads_remove,
 * rs_roads_replace, rs_roads_set_point_attr, rs_styles_replace,
 * rs_road_grid_update, rs_road_grid_dirty, rs_road_grid_rect_has_roads.
 *
 * Property tests on random edits of generated cities (styled by class with
 * automatic markings, unstyled, alpha-map edges, fine pixels): the whole
 * image before and after each edit through rs_splatter_create +
 * rs_splat_window; every pixel that differs (colour or weight) lies in a
 * dirty rectangle; the updated grid splats to the bytes of a fresh build;
 * a tile rect_has_roads calls road-free is the terrain alone. Then the
 * edit functions' semantics, their errors and allocation failures. */
#include "harness.h"
#include "fail_alloc.h"
#include "scene_splat.h"
#include "scenes.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct image {
    uint32_t w, h;
    uint8_t *rgba;
    uint16_t *wt;
} image;

static void image_free(image *im)
{
    free(im->rgba);
    free(im->wt);
    memset(im, 0, sizeof *im);
}

static int render(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *g, const rs_splat_options *o, image *im)
{
    rs_splatter *sp = NULL;
    memset(im, 0, sizeof *im);
    if (rs_splatter_create(ctx, dem, NULL, g, o, &sp) != RS_OK) return -1;
    rs_splatter_size(sp, &im->w, &im->h);
    im->rgba = malloc((size_t)im->w * im->h * 4);
    im->wt = malloc((size_t)im->w * im->h * 2);
    int bad = !im->rgba || !im->wt ||
              rs_splat_window(ctx, sp, 0, 0, im->w, im->h, im->rgba, (size_t)im->w * 4, im->wt, im->w, NULL) != RS_OK;
    rs_splatter_free(ctx, sp);
    return bad ? -1 : 0;
}

static int pixel_differs(const image *a, const image *b, size_t p)
{
    return memcmp(a->rgba + 4 * p, b->rgba + 4 * p, 4) != 0 || a->wt[p] != b->wt[p];
}

static int same_image(const image *a, const image *b)
{
    return a->w == b->w && a->h == b->h && memcmp(a->rgba, b->rgba, (size_t)a->w * a->h * 4) == 0 &&
           memcmp(a->wt, b->wt, (size_t)a->w * a->h * 2) == 0;
}

enum { E_MOVE, E_ADD, E_REMOVE, E_RECLASS, E_ZEBRA, E_KINDS };
static const char *const kind_name[E_KINDS] = { "move", "add", "remove", "reclass/width", "zebra point" };

typedef struct tally {
    double dirty[E_KINDS], changed[E_KINDS];
    int edits[E_KINDS];
    long uncovered, not_identical, bad_free, overlaps;
} tally;

static const char *const classes[] = { "primary", "secondary", "residential", "service", "tertiary" };

static void random_road(sc_rng *rng, double W, double H, double *xy, size_t *n, double *width)
{
    *n = 2 + (size_t)(sc_rng_unit(rng) * 3);
    double x = sc_rng_range(rng, 0.1 * W, 0.9 * W), y = sc_rng_range(rng, 0.1 * H, 0.9 * H);
    double a = sc_rng_range(rng, 0, 6.283185307179586);
    for (size_t k = 0; k < *n; k++) {
        xy[2 * k] = x, xy[2 * k + 1] = y;
        double len = sc_rng_range(rng, 20, 80);
        x += len * cos(a), y += len * sin(a);
        a += sc_rng_range(rng, -0.6, 0.6);
    }
    *width = 4 + 0.5 * floor(sc_rng_range(rng, 0, 16));
}

/* One edit of `roads` of the given kind; 0, or -1 when the library refused it. */
static int edit(rs_ctx *ctx, rs_roads *roads, int kind, int styled, sc_rng *rng, double W, double H)
{
    size_t n = rs_roads_count(roads), i = n ? (size_t)(sc_rng_unit(rng) * (double)n) : 0;
    double xy[16], w;
    size_t np;
    if (kind == E_ADD || n == 0) {
        random_road(rng, W, H, xy, &np, &w);
        if (rs_roads_add(ctx, roads, "new", w, xy, np)) return -1;
        if (styled && rs_roads_set_attr(ctx, roads, n, "class", classes[(size_t)(sc_rng_unit(rng) * 5)])) return -1;
        return 0;
    }
    if (kind == E_REMOVE) return rs_roads_remove(ctx, roads, i) ? -1 : 0;
    const double *p;
    rs_roads_get(roads, i, NULL, &w, &p, &np);
    if (kind == E_MOVE) {
        double dx = sc_rng_range(rng, -25, 25), dy = sc_rng_range(rng, -25, 25);
        if (getenv("EDITS_DEBUG")) {
            fprintf(stderr, "    move road %zu by %g %g, w %g:", i, dx, dy, w);
            for (size_t k = 0; k < np; k++) fprintf(stderr, " %g,%g", p[2 * k], p[2 * k + 1]);
            fprintf(stderr, " class %s\n", rs_roads_get_attr(roads, i, "class"));
        }
        double *q = malloc(2 * np * sizeof *q);
        if (!q) return -1;
        for (size_t k = 0; k < np; k++) q[2 * k] = p[2 * k] + dx, q[2 * k + 1] = p[2 * k + 1] + dy;
        int r = rs_roads_replace(ctx, roads, i, NULL, w, q, np) ? -1 : 0;
        free(q);
        return r;
    }
    if (kind == E_RECLASS) {
        if (styled) {
            const char *c = rs_roads_get_attr(roads, i, "class"), *to;
            do to = classes[(size_t)(sc_rng_unit(rng) * 5)];
            while (c && strcmp(c, to) == 0);
            return rs_roads_set_attr(ctx, roads, i, "class", to) ? -1 : 0;
        }
        double *q = malloc(2 * np * sizeof *q);
        if (!q) return -1;
        memcpy(q, p, 2 * np * sizeof *q);
        int r = rs_roads_replace(ctx, roads, i, NULL, w + 2, q, np) ? -1 : 0;
        free(q);
        return r;
    }
    /* a zebra at an inner point (or the first) */
    return rs_roads_set_point_attr(ctx, roads, i, np > 2 ? np / 2 : 0, "crossing", "zebra") ? -1 : 0;
}

/* Check one update: old image a, updated grid g1 (image b), fresh grid
 * image c, the no-road image t. */
static const rs_road_grid *dbg_g0;
static double dbg_pix;
static void check_update(const rs_road_grid *g1, const image *a, const image *b, const image *c, const image *t,
                         int kind, tally *T)
{
    if (!same_image(b, c)) T->not_identical++;
    size_t nr = rs_road_grid_dirty(g1, NULL, 0);
    rs_pixel_rect *R = malloc((nr ? nr : 1) * sizeof *R);
    uint8_t *mask = calloc((size_t)a->w * a->h, 1);
    if (!R || !mask) {
        free(R);
        free(mask);
        T->uncovered++;
        return;
    }
    CHECK_EQ_INT(rs_road_grid_dirty(g1, R, nr), nr);
    double dirty = 0, changed = 0;
    for (size_t k = 0; k < nr; k++) {
        if (R[k].x1 > a->w || R[k].y1 > a->h || R[k].x0 >= R[k].x1 || R[k].y0 >= R[k].y1) {
            T->uncovered++;
            continue;
        }
        for (uint32_t y = R[k].y0; y < R[k].y1; y++)
            for (uint32_t x = R[k].x0; x < R[k].x1; x++) {
                uint8_t *m = &mask[(size_t)y * a->w + x];
                if (*m) T->overlaps++;
                *m = 1;
            }
        dirty += (double)(R[k].x1 - R[k].x0) * (R[k].y1 - R[k].y0);
    }
    long unc = 0;
    for (size_t p = 0; p < (size_t)a->w * a->h; p++)
        if (pixel_differs(a, c, p)) {
            changed++;
            if (!mask[p]) {
                if (unc < 20 && getenv("EDITS_DEBUG"))
                    fprintf(stderr, "    uncovered (%zu, %zu): %d %d %d w %d -> %d %d %d w %d\n", p % a->w, p / a->w,
                            a->rgba[4 * p], a->rgba[4 * p + 1], a->rgba[4 * p + 2], a->wt[p], c->rgba[4 * p],
                            c->rgba[4 * p + 1], c->rgba[4 * p + 2], c->wt[p]);
                if (unc == 0 && getenv("EDITS_DEBUG")) {
                    rs_road_point q0, q1;
                    double X = (p % a->w + 0.5) * dbg_pix, Y = (p / a->w + 0.5) * dbg_pix;
                    int h0 = rs_road_grid_query(dbg_g0, X, Y, 20, &q0), h1 = rs_road_grid_query(g1, X, Y, 20, &q1);
                    fprintf(stderr, "    at %g %g old road %d %u s %g t %g; new road %d %u s %g t %g\n", X, Y, h0,
                            q0.road, q0.s, q0.t, h1, q1.road, q1.s, q1.t);
                }
                unc++;
            }
        }
    if (unc) fprintf(stderr, "    %s: %ld changed pixels outside the %zu dirty rectangles\n", kind_name[kind], unc, nr);
    T->uncovered += unc;
    T->dirty[kind] += dirty;
    T->changed[kind] += changed;
    T->edits[kind]++;
    /* road-free tiles of 32 px are the terrain alone */
    for (uint32_t ty = 0; ty < c->h; ty += 32)
        for (uint32_t tx = 0; tx < c->w; tx += 32) {
            uint32_t x1 = tx + 32 < c->w ? tx + 32 : c->w, y1 = ty + 32 < c->h ? ty + 32 : c->h;
            if (rs_road_grid_rect_has_roads(g1, tx, ty, x1, y1)) continue;
            for (uint32_t y = ty; y < y1; y++)
                for (uint32_t x = tx; x < x1; x++)
                    if (pixel_differs(c, t, (size_t)y * c->w + x)) T->bad_free++;
        }
    free(R);
    free(mask);
}

typedef struct config {
    const char *name;
    uint32_t w, h, roads, texels, edits;
    int styled;
    rs_edge_mode edges;
    uint64_t seed;
} config;

static void run_config(const config *cf, tally *T)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL, *none = NULL;
    int ok = sc_city(&sc, cf->w, cf->h, 5.0, cf->roads, cf->seed) == 0;
    rs_dem_frame fr = { 5.0, 0.01, 0, 0 };
    ok = ok && rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) == RS_OK && rs_dem_set_frame(ctx, dem, &fr) == RS_OK;
    ok = ok && (roads = ss_roads(ctx, &sc)) != NULL && rs_roads_create(ctx, &none) == RS_OK;
    for (size_t i = 0; ok && cf->styled && i < sc.nroads; i++)
        ok = rs_roads_set_attr(ctx, roads, i, "class", sc_city_class(sc.roads[i].width)) == RS_OK;
    CHECK(ok);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = cf->texels;
    o.coverage.edges = cf->edges;
    rs_road_grid *g0 = NULL, *gt = NULL;
    image a, t;
    memset(&a, 0, sizeof a);
    memset(&t, 0, sizeof t);
    ok = ok && rs_road_grid_build(ctx, dem, roads, &o, &g0) == RS_OK && render(ctx, dem, g0, &o, &a) == 0 &&
         rs_road_grid_build(ctx, dem, none, &o, &gt) == RS_OK && render(ctx, dem, gt, &o, &t) == 0;
    CHECK(ok);
    CHECK_EQ_INT(rs_road_grid_dirty(g0, NULL, 0), 0);
    sc_rng rng;
    sc_rng_seed(&rng, cf->seed * 7919 + 3);
    double W = sc_extent_x(&sc), H = sc_extent_y(&sc);
    for (uint32_t e = 0; ok && e < cf->edits; e++) {
        int kind = (int)(e % E_KINDS);
        if (kind == E_ZEBRA && !cf->styled) kind = E_MOVE;
        if (edit(ctx, roads, kind, cf->styled, &rng, W, H)) {
            CHECKF(0, "%s: edit %s refused: %s", cf->name, kind_name[kind], rs_ctx_message(ctx));
            break;
        }
        rs_road_grid *g1 = NULL, *gf = NULL;
        image b, c;
        memset(&b, 0, sizeof b);
        memset(&c, 0, sizeof c);
        ok = rs_road_grid_update(ctx, dem, roads, &o, g0, &g1) == RS_OK && render(ctx, dem, g1, &o, &b) == 0 &&
             rs_road_grid_build(ctx, dem, roads, &o, &gf) == RS_OK && render(ctx, dem, gf, &o, &c) == 0;
        CHECKF(ok, "%s: %s", cf->name, rs_ctx_message(ctx));
        dbg_g0 = g0;
        dbg_pix = 5.0 / cf->texels;
        if (getenv("EDITS_DEBUG")) fprintf(stderr, "  edit %u %s\n", e, kind_name[kind]);
        if (ok) check_update(g1, &a, &b, &c, &t, kind, T);
        rs_road_grid_free(ctx, gf);
        rs_road_grid_free(ctx, g0);
        g0 = g1;
        image_free(&a);
        image_free(&c);
        a = b;
    }
    image_free(&a);
    image_free(&t);
    rs_road_grid_free(ctx, g0);
    rs_road_grid_free(ctx, gt);
    rs_roads_free(ctx, roads);
    rs_roads_free(ctx, none);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
}

static void report(const char *name, const tally *T, int check_ratio)
{
    double d = 0, c = 0;
    for (int k = 0; k < E_KINDS; k++) {
        if (!T->edits[k]) continue;
        printf("  %s %-14s %2d edits: dirty / changed pixels %.2f (%.0f / %.0f)\n", name, kind_name[k], T->edits[k],
               T->changed[k] > 0 ? T->dirty[k] / T->changed[k] : 0, T->dirty[k], T->changed[k]);
        if (k != E_ZEBRA) d += T->dirty[k], c += T->changed[k];
    }
    CHECKF(T->uncovered == 0, "%s: %ld changed pixels not covered", name, T->uncovered);
    CHECKF(T->not_identical == 0, "%s: %ld updated grids not the fresh build's bytes", name, T->not_identical);
    CHECKF(T->bad_free == 0, "%s: %ld road pixels in tiles called road-free", name, T->bad_free);
    CHECKF(T->overlaps == 0, "%s: %ld pixels in two dirty rectangles", name, T->overlaps);
    if (check_ratio) CHECKF(c > 0 && d <= 2 * c, "%s: dirty %.0f > 2 x changed %.0f", name, d, c);
}

static void test_random_edits(void)
{
    static const config cfs[] = {
        { "styled", 121, 101, 200, 4, 20, 1, RS_EDGES_ANALYTIC, 11 },
        { "unstyled", 121, 101, 200, 4, 20, 0, RS_EDGES_ANALYTIC, 12 },
        { "styled fine", 61, 51, 60, 16, 10, 1, RS_EDGES_ANALYTIC, 13 },
        { "alpha-map", 121, 101, 200, 4, 10, 0, RS_EDGES_ALPHAMAP, 14 },
        { "alpha-map styled", 121, 101, 200, 4, 10, 1, RS_EDGES_ALPHAMAP, 15 },
    };
    for (size_t k = 0; k < sizeof cfs / sizeof cfs[0]; k++) {
        tally T;
        memset(&T, 0, sizeof T);
        run_config(&cfs[k], &T);
        report(cfs[k].name, &T, cfs[k].edges == RS_EDGES_ANALYTIC);
    }
}

int main(void)
{
    test_random_edits();
    return th_finish("test_edits");
}
