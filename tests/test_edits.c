/* Road edits and dirty rectangles (issue 30): rs_roads_remove,
 * rs_roads_replace, rs_roads_set_point_attr, rs_styles_replace,
 * rs_road_grid_update, rs_road_grid_dirty, rs_road_grid_rect_has_roads.
 *
 * test_random_edits: random edits (moves by up to 25 m, new roads,
 * removals, class or width changes, zebra points, named fill styles) of
 * generated cities in seven configurations (styled by class with automatic
 * markings, unstyled, 0.31 m pixels, alpha-map edges unstyled and styled,
 * fills and gradients, Hermite lines), chained (each update's grid is the
 * next one's old grid). For every edit: the whole image before and after
 * through rs_splatter_create + rs_splat_window; every pixel whose colour
 * or weight differs lies in a dirty rectangle; the rectangles lie in the
 * image and never overlap; the updated grid splats to the bytes of a fresh
 * build; a 32-pixel tile rect_has_roads calls road-free equals the splat
 * without roads; moves, additions and removals dirty at most 2.5x the
 * changed pixels (printed per kind). Then the edit functions' semantics
 * (renumbering, markings and point attributes dropped or kept), a named
 * style redefined (only its roads dirty), no edit (nothing dirty), a
 * removal (the renumbered roads dirty nothing), errors naming the value,
 * and allocation failures (every allocation failed in turn: no leak, no
 * object on failure) of the update, the three road edits and the local
 * build. test_subset_build: the local build a proportional update needs
 * (rs__road_grid_build_subset) splats a region as the whole grid does.
 * EDITS_DEBUG=1 prints the first pixels a rectangle misses. */
#include "harness.h"
#include "fail_alloc.h"
#include "scene_splat.h"
#include "scenes.h"
#include "internal.h"
#include "network.h"
#include "grid_edit.h"
#include "roadgrid.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef ss_image image;
#define image_free ss_image_free

static int render(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *g, const rs_splat_options *o, image *im)
{
    return ss_grid_image(ctx, dem, g, o, im) == RS_OK ? 0 : -1;
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
    long uncovered, not_identical, bad_free, overlaps, outputs_differ, net_differ;
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
/* Road i moved by (dx, dy); 0, or -1 when that failed */
static int move_road(rs_ctx *ctx, rs_roads *roads, size_t i, double dx, double dy)
{
    const double *p;
    size_t np;
    double w;
    if (rs_roads_get(roads, i, NULL, &w, &p, &np)) return -1;
    double *q = malloc(2 * np * sizeof *q);
    if (!q) return -1;
    for (size_t k = 0; k < np; k++) q[2 * k] = p[2 * k] + dx, q[2 * k + 1] = p[2 * k + 1] + dy;
    int r = rs_roads_replace(ctx, roads, i, NULL, w, q, np) == RS_OK ? 0 : -1;
    free(q);
    return r;
}


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
        return move_road(ctx, roads, i, dx, dy);
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

/* Grids a and b draw alike in every output, not only the colour: the
 * layers (rs_splat_layers_window, all planes with normals), the normal map
 * (rs_normal_window) and the lit colour; on splatters of their own, whole
 * image. 1: the same bytes. */
static int same_outputs(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *a, const rs_road_grid *b,
                        const rs_splat_options *o)
{
    const rs_road_grid *g[2] = { a, b };
    rs_splat_options lit = *o;
    lit.lighting.enable = 1;
    rs_splatter *s[2] = { NULL, NULL }, *sl[2] = { NULL, NULL };
    uint32_t W = 0, H = 0;
    int same = rs_splat_size(ctx, dem, o, &W, &H) == RS_OK;
    size_t n = (size_t)W * H, per = 4 + 4 + 4 + 4 + 3 + 2 + 3 + 4; /* layers, normal map, lit colour */
    uint8_t *buf[2] = { calloc(n, per), calloc(n, per) };
    same = same && buf[0] && buf[1];
    for (int i = 0; i < 2 && same; i++) {
        uint8_t *q = buf[i];
        rs_splat_layers L;
        memset(&L, 0, sizeof L);
        L.terrain = q, L.terrain_stride = 4 * (size_t)W, q += 4 * n;
        L.casing = q, L.casing_stride = 4 * (size_t)W, q += 4 * n;
        L.surface = q, L.surface_stride = 4 * (size_t)W, q += 4 * n;
        L.paint = q, L.paint_stride = 4 * (size_t)W, q += 4 * n;
        L.normal = q, L.normal_stride = 3 * (size_t)W, q += 3 * n;
        L.coverage = (uint16_t *)(void *)q, L.coverage_stride = W, q += 2 * n;
        uint8_t *nm = q, *rgba = q + 3 * n;
        same = rs_splatter_create(ctx, dem, NULL, g[i], o, &s[i]) == RS_OK &&
               rs_splatter_create(ctx, dem, NULL, g[i], &lit, &sl[i]) == RS_OK &&
               rs_splat_layers_window(ctx, s[i], NULL, 0, 0, W, H, &L, NULL) == RS_OK &&
               rs_normal_window(ctx, s[i], 0, 0, W, H, nm, 3 * (size_t)W, NULL) == RS_OK &&
               rs_splat_window(ctx, sl[i], 0, 0, W, H, rgba, 4 * (size_t)W, NULL, 0, NULL) == RS_OK;
    }
    same = same && memcmp(buf[0], buf[1], n * per) == 0;
    for (int i = 0; i < 2; i++) {
        rs_splatter_free(ctx, s[i]);
        rs_splatter_free(ctx, sl[i]);
        free(buf[i]);
    }
    return same;
}

typedef struct config {
    const char *name;
    uint32_t w, h, roads, texels, edits;
    int styled;
    rs_edge_mode edges;
    uint64_t seed;
    int fills;   /* every third road a named style with a fill or a gradient (priorities show) */
    int hermite; /* the seed's Hermite line anti-aliasing */
} config;

/* Splat options at `texels` that keep the edit pieces (all else default). */
static rs_splat_options edit_opts(uint32_t texels)
{
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = texels;
    o.grid.edits = 1;
    return o;
}

static const char fill_styles[] = "style red\nfill #b04030\ncasing 0.4 #303030\nline 0 0.2 #ffffff dash 3 3\nend\n"
                                  "style grad\ngradient #202020 #707070\nend\n";
static const char *const fill_names[] = { "red", "grad" };

/* A context whose allocator keeps a guard after every block (tests/
 * fail_alloc.h), so that a write past a block's end fails these tests in
 * a plain build too; guarded_free checks the guards. g must outlive the
 * context. A block may be freed through another guarded context (a
 * patched grid made on one drops its share of a base made on the other):
 * the layout is the same, only the live counts move between them. */
static rs_ctx *guarded_ctx(guard_alloc *g, const rs_limits *lim)
{
    g->live = g->broken = 0;
    rs_allocator al = guard_alloc_hook(g);
    rs_ctx *c = NULL;
    return rs_ctx_create(&al, lim, &c) == RS_OK ? c : NULL;
}

static void guarded_free(rs_ctx *c, guard_alloc *g, const char *what)
{
    rs_ctx_free(c);
    CHECKF(g->broken == 0, "%s: %ld blocks written past their end", what, g->broken);
}

/* T: the updates as a host gets them (the candidate pixels compared: the
 * changed ones exactly); Tc: the same updates with the comparison off
 * (rs_limits.max_dirty_compare 1), the pieces' candidates alone. */
static void run_config(const config *cf, tally *T, tally *Tc)
{
    guard_alloc guard, guard_c;
    rs_ctx *ctx = guarded_ctx(&guard, NULL), *cctx;
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_dirty_compare = 1;
    cctx = guarded_ctx(&guard_c, &lim);
    CHECK(ctx && cctx);
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL, *none = NULL;
    int ok = ss_city_of(ctx, cf->w, cf->h, cf->roads, cf->seed, cf->styled, &sc, &dem, &roads) == 0 &&
             rs_roads_create(ctx, &none) == RS_OK;
    rs_styles *S = NULL;
    if (ok && cf->fills) ok = rs_styles_parse(ctx, fill_styles, sizeof fill_styles - 1, &S) == RS_OK;
    for (size_t i = 0; ok && cf->fills && i < sc.nroads; i += 3)
        ok = rs_roads_set_attr(ctx, roads, i, "style", fill_names[(i / 3) % 2]) == RS_OK;
    CHECK(ok);
    rs_splat_options o = edit_opts(cf->texels);
    o.coverage.edges = cf->edges;
    o.style.styles = S;
    if (cf->hermite) o.style.aa = RS_LINE_AA_HERMITE;
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
        int refused = kind == E_RECLASS && cf->fills && e % 2
                          ? rs_roads_set_attr(ctx, roads, (size_t)(sc_rng_unit(&rng) * (double)rs_roads_count(roads)),
                                              "style", fill_names[e % 4 == 1]) != RS_OK
                          : edit(ctx, roads, kind, cf->styled, &rng, W, H) != 0;
        if (refused) {
            CHECKF(0, "%s: edit %s refused: %s", cf->name, kind_name[kind], rs_ctx_message(ctx));
            break;
        }
        rs_road_grid *g1 = NULL, *gf = NULL, *gc = NULL;
        image b, c;
        memset(&b, 0, sizeof b);
        memset(&c, 0, sizeof c);
        ok = rs_road_grid_update(ctx, dem, roads, &o, g0, &g1) == RS_OK && render(ctx, dem, g1, &o, &b) == 0 &&
             rs_road_grid_build(ctx, dem, roads, &o, &gf) == RS_OK && render(ctx, dem, gf, &o, &c) == 0 &&
             rs_road_grid_update(cctx, dem, roads, &o, g0, &gc) == RS_OK;
        CHECKF(ok, "%s: %s", cf->name, rs_ctx_message(ctx));
        dbg_g0 = g0;
        dbg_pix = 5.0 / cf->texels;
        if (getenv("EDITS_DEBUG")) fprintf(stderr, "  edit %u %s\n", e, kind_name[kind]);
        if (ok) check_update(g1, &a, &b, &c, &t, kind, T);
        /* (the network it keeps for the next update, updated in place: a whole build's) */
        if (ok) T->net_differ += rs__grid_track_net_check(ctx, g1, roads) != 1;
        /* (class styles and fills: every output of the updated grid, lit and layered too) */
        if (ok && (strcmp(cf->name, "styled") == 0 || strcmp(cf->name, "fills") == 0))
            T->outputs_differ += !same_outputs(ctx, dem, g1, gf, &o);
        if (ok) check_update(gc, &a, &b, &c, &t, kind, Tc);
        rs_road_grid_free(cctx, gc);
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
    rs_styles_free(ctx, S);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    guarded_free(ctx, &guard, cf->name);
    guarded_free(cctx, &guard_c, cf->name);
}

/* check_ratio 1: moves, additions, removals within 2.5x; 2: every kind
 * exactly the changed pixels */
static void report(const char *name, const tally *T, int check_ratio)
{
    double d = 0, c = 0;
    for (int k = 0; k < E_KINDS; k++) {
        if (!T->edits[k]) continue;
        printf("  %s %-14s %2d edits: dirty / changed pixels %.2f (%.0f / %.0f)\n", name, kind_name[k], T->edits[k],
               T->changed[k] > 0 ? T->dirty[k] / T->changed[k] : 0, T->dirty[k], T->changed[k]);
        if (k == E_MOVE || k == E_ADD || k == E_REMOVE) d += T->dirty[k], c += T->changed[k];
    }
    CHECKF(T->uncovered == 0, "%s: %ld changed pixels not covered", name, T->uncovered);
    CHECKF(T->not_identical == 0, "%s: %ld updated grids not the fresh build's bytes", name, T->not_identical);
    CHECKF(T->outputs_differ == 0, "%s: %ld updated grids whose layers, normals or lit colour differ from a fresh "
           "build's", name, T->outputs_differ);
    CHECKF(T->bad_free == 0, "%s: %ld road pixels in tiles called road-free", name, T->bad_free);
    CHECKF(T->net_differ == 0, "%s: %ld updated grids whose kept network differs from a whole build's", name,
           T->net_differ);
    CHECKF(T->overlaps == 0, "%s: %ld pixels in two dirty rectangles", name, T->overlaps);
    /* moves, additions and removals: the dirty area within 2.5x of the
     * pixels that change (at 1.25 m pixels a road's edge pixels weigh
     * more; the bench measures the 10k-road city) */
    if (check_ratio == 1) CHECKF(c > 0 && d <= 2.5 * c, "%s: dirty %.0f > 2.5 x changed %.0f", name, d, c);
    for (int k = 0; check_ratio == 2 && k < E_KINDS; k++)
        CHECKF(T->dirty[k] == T->changed[k], "%s %s: dirty %.0f, changed %.0f", name, kind_name[k], T->dirty[k],
               T->changed[k]);
}

static void test_random_edits(void)
{
    static const config cfs[] = {
        { "styled", 121, 101, 200, 4, 20, 1, RS_EDGES_ANALYTIC, 11, 0, 0 },
        { "unstyled", 121, 101, 200, 4, 20, 0, RS_EDGES_ANALYTIC, 12, 0, 0 },
        { "styled fine", 61, 51, 60, 16, 10, 1, RS_EDGES_ANALYTIC, 13, 0, 0 },
        { "alpha-map", 121, 101, 200, 4, 10, 0, RS_EDGES_ALPHAMAP, 14, 0, 0 },
        { "alpha-map styled", 121, 101, 200, 4, 10, 1, RS_EDGES_ALPHAMAP, 15, 0, 0 },
        { "fills", 121, 101, 200, 4, 15, 1, RS_EDGES_ANALYTIC, 16, 1, 0 },
        { "styled hermite", 81, 61, 80, 8, 10, 1, RS_EDGES_ANALYTIC, 17, 0, 1 },
    };
    for (size_t k = 0; k < sizeof cfs / sizeof cfs[0]; k++) {
        tally T, Tc;
        memset(&T, 0, sizeof T);
        memset(&Tc, 0, sizeof Tc);
        run_config(&cfs[k], &T, &Tc);
        char cname[64];
        snprintf(cname, sizeof cname, "%s candidates", cfs[k].name);
        report(cname, &Tc, cfs[k].edges == RS_EDGES_ANALYTIC);
        report(cfs[k].name, &T, 2);
    }
}

/* ---- the edit functions ---------------------------------------------------- */

static const char two_roads[] =
    "road a width 6 class=residential\n0 0\n50 0 crossing=zebra\n100 0\nend\n"
    "road b width 8\n50 -40\n50 40\nend\n"
    "road c width 4\n0 20\n100 20 crossing=zebra\nend\n"
    "mark arrow_straight road=a s=20 t=-1.5\n"
    "mark arrow_straight road=c s=30 t=0\n";

static int has_msg(rs_ctx *ctx, const char *what)
{
    const char *m = rs_ctx_message(ctx);
    int ok = m && strstr(m, what) != NULL;
    if (!ok) fprintf(stderr, "    message \"%s\" lacks \"%s\"\n", m ? m : "(null)", what);
    return ok;
}

static void test_remove(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    rs_roads *R = NULL;
    CHECK(rs_roads_parse(ctx, two_roads, sizeof two_roads - 1, &R) == RS_OK);
    CHECK_EQ_INT(rs_roads_count(R), 3);
    CHECK_EQ_INT(rs_roads_mark_count(R), 2);
    CHECK_EQ_INT(rs_roads_point_attr_count(R), 2);
    CHECK(rs_roads_remove(ctx, R, 0) == RS_OK);
    CHECK_EQ_INT(rs_roads_count(R), 2);
    const char *name;
    const double *xy;
    size_t n;
    double w;
    CHECK(rs_roads_get(R, 0, &name, &w, &xy, &n) == RS_OK && strcmp(name, "b") == 0 && w == 8 && n == 2 &&
          xy[0] == 50 && xy[3] == 40);
    CHECK(rs_roads_get(R, 1, &name, &w, &xy, &n) == RS_OK && strcmp(name, "c") == 0 && n == 2 && xy[1] == 20);
    /* road a's marking and point attribute went; c's moved down to 1 */
    CHECK_EQ_INT(rs_roads_mark_count(R), 1);
    rs_mark m;
    CHECK(rs_roads_get_mark(R, 0, &m) == RS_OK && m.road == 1 && m.s == 30);
    CHECK_EQ_INT(rs_roads_point_attr_count(R), 1);
    size_t road, point;
    const char *k, *v;
    CHECK(rs_roads_point_attr_at(R, 0, &road, &point, &k, &v) == RS_OK && road == 1 && point == 1 &&
          strcmp(k, "crossing") == 0);
    CHECK(rs_roads_get_attr(R, 0, "class") == NULL);
    /* errors name the value */
    CHECK(rs_roads_remove(ctx, R, 7) == RS_ERR_INVALID_ARG && has_msg(ctx, "road 7"));
    CHECK(rs_roads_remove(ctx, NULL, 0) == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_remove(NULL, R, 0) == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_remove(ctx, R, 1) == RS_OK && rs_roads_remove(ctx, R, 0) == RS_OK);
    CHECK_EQ_INT(rs_roads_count(R), 0);
    CHECK_EQ_INT(rs_roads_mark_count(R), 0);
    CHECK_EQ_INT(rs_roads_point_attr_count(R), 0);
    rs_roads_free(ctx, R);
    guarded_free(ctx, &guard, "remove");
}

/* The road set keeps each road's print and box as its edits make them
 * (rs__roads_road_print: an update reads them instead of hashing every
 * road). The same road gives the same print however it came there
 * (parsed, added and given its attributes, copied, replaced back, moved
 * up by a removal, its y negated twice), and a change of its name, width,
 * a point or an attribute changes it. */
static int same_print(const rs_roads *a, size_t i, const rs_roads *b, size_t j)
{
    uint64_t pa, pb;
    double wa, wb;
    const double *ba, *bb;
    rs__roads_road_print(a, i, &pa, &wa, &ba);
    rs__roads_road_print(b, j, &pb, &wb, &bb);
    return pa == pb && wa == wb && memcmp(ba, bb, 4 * sizeof *ba) == 0;
}

static void test_road_prints(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    const char text[] = "road a width 6 class=residential lanes=2\n0 0\n40 3\n80 -2\nend\n"
                        "road b width 4\n10 -20\n10 30\nend\n";
    rs_roads *P = NULL, *A = NULL, *C = NULL;
    CHECK(rs_roads_parse(ctx, text, sizeof text - 1, &P) == RS_OK);
    const double a_xy[] = { 0, 0, 40, 3, 80, -2 }, b_xy[] = { 10, -20, 10, 30 };
    CHECK(rs_roads_create(ctx, &A) == RS_OK && rs_roads_add(ctx, A, "a", 6, a_xy, 3) == RS_OK &&
          rs_roads_set_attr(ctx, A, 0, "class", "residential") == RS_OK &&
          rs_roads_set_attr(ctx, A, 0, "lanes", "2") == RS_OK && rs_roads_add(ctx, A, "b", 4, b_xy, 2) == RS_OK);
    CHECK(same_print(P, 0, A, 0) && same_print(P, 1, A, 1));
    const double *box;
    uint64_t h;
    double w;
    rs__roads_road_print(P, 0, &h, &w, &box);
    CHECK(w == 6 && box[0] == 0 && box[1] == -2 && box[2] == 80 && box[3] == 3);
    CHECK(rs_roads_copy(ctx, P, &C) == RS_OK && same_print(P, 0, C, 0) && same_print(P, 1, C, 1));
    /* each change changes the print; putting it back restores it */
    const double moved[] = { 0, 0, 40, 3.5, 80, -2 };
    CHECK(rs_roads_replace(ctx, C, 0, NULL, 6, moved, 3) == RS_OK && !same_print(P, 0, C, 0));
    CHECK(rs_roads_replace(ctx, C, 0, NULL, 6, a_xy, 3) == RS_OK && same_print(P, 0, C, 0));
    CHECK(rs_roads_replace(ctx, C, 0, NULL, 6.5, a_xy, 3) == RS_OK && !same_print(P, 0, C, 0));
    CHECK(rs_roads_replace(ctx, C, 0, NULL, 6, a_xy, 3) == RS_OK && same_print(P, 0, C, 0));
    CHECK(rs_roads_replace(ctx, C, 0, "z", 6, a_xy, 3) == RS_OK && !same_print(P, 0, C, 0));
    CHECK(rs_roads_replace(ctx, C, 0, "a", 6, a_xy, 3) == RS_OK && same_print(P, 0, C, 0));
    CHECK(rs_roads_set_attr(ctx, C, 0, "class", "primary") == RS_OK && !same_print(P, 0, C, 0));
    CHECK(rs_roads_set_attr(ctx, C, 0, "class", "residential") == RS_OK && same_print(P, 0, C, 0));
    CHECK(rs_roads_negate_y(ctx, C) == RS_OK && !same_print(P, 1, C, 1));
    CHECK(rs_roads_negate_y(ctx, C) == RS_OK && same_print(P, 1, C, 1) && same_print(P, 0, C, 0));
    CHECK(rs_roads_remove(ctx, C, 0) == RS_OK && same_print(P, 1, C, 0));
    rs_roads_free(ctx, P);
    rs_roads_free(ctx, A);
    rs_roads_free(ctx, C);
    guarded_free(ctx, &guard, "road_prints");
}

static void test_replace(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    rs_roads *R = NULL;
    CHECK(rs_roads_parse(ctx, two_roads, sizeof two_roads - 1, &R) == RS_OK);
    const double pts[] = { 0, 5, 30, 5, 60, 10, 90, 5 };
    CHECK(rs_roads_replace(ctx, R, 0, NULL, 7, pts, 4) == RS_OK);
    const char *name;
    const double *xy;
    size_t n;
    double w;
    CHECK(rs_roads_get(R, 0, &name, &w, &xy, &n) == RS_OK && strcmp(name, "a") == 0 && w == 7 && n == 4 &&
          xy[5] == 10);
    CHECK(rs_roads_get(R, 1, &name, &w, &xy, &n) == RS_OK && strcmp(name, "b") == 0 && n == 2 && xy[3] == 40);
    CHECK(rs_roads_get_attr(R, 0, "class") && strcmp(rs_roads_get_attr(R, 0, "class"), "residential") == 0);
    rs_road_info info;
    CHECK(rs_roads_get_info(R, 0, &info) == RS_OK && info.width_given == 1);
    /* shorter: the point attribute on point 1 stays, a name is set */
    CHECK(rs_roads_replace(ctx, R, 2, "cc", 5, pts, 2) == RS_OK);
    CHECK(rs_roads_get(R, 2, &name, &w, &xy, &n) == RS_OK && strcmp(name, "cc") == 0 && n == 2);
    CHECK_EQ_INT(rs_roads_point_attr_count(R), 2);
    CHECK(rs_roads_replace(ctx, R, 2, NULL, 5, pts + 2, 1) == RS_ERR_INVALID_ARG && has_msg(ctx, "1 points"));
    CHECK_EQ_INT(rs_roads_point_attr_count(R), 2);
    /* a road's own points as the source */
    CHECK(rs_roads_get(R, 1, NULL, NULL, &xy, &n) == RS_OK);
    CHECK(rs_roads_replace(ctx, R, 0, NULL, 3, xy, n) == RS_OK);
    CHECK(rs_roads_get(R, 0, NULL, &w, &xy, &n) == RS_OK && n == 2 && xy[0] == 50 && xy[1] == -40 && w == 3);
    /* the first point's attribute (point 1 of road 0) went with the shorter road? no: n = 2 keeps point 1 */
    CHECK_EQ_INT(rs_roads_point_attr_count(R), 2);
    CHECK(rs_roads_replace(ctx, R, 9, NULL, 3, pts, 2) == RS_ERR_INVALID_ARG && has_msg(ctx, "road 9"));
    CHECK(rs_roads_replace(ctx, R, 0, NULL, -2, pts, 2) == RS_ERR_INVALID_ARG && has_msg(ctx, "width -2"));
    CHECK(rs_roads_replace(ctx, R, 0, NULL, 2, NULL, 2) == RS_ERR_INVALID_ARG);
    const double bad[] = { 0, 0, NAN, 1 };
    CHECK(rs_roads_replace(ctx, R, 0, NULL, 2, bad, 2) == RS_ERR_INVALID_ARG && has_msg(ctx, "point 1"));
    rs_roads_free(ctx, R);
    guarded_free(ctx, &guard, "replace");
}

static void test_point_attr(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    rs_roads *R = NULL;
    CHECK(rs_roads_parse(ctx, two_roads, sizeof two_roads - 1, &R) == RS_OK);
    CHECK(rs_roads_set_point_attr(ctx, R, 1, 1, "crossing", "zebra") == RS_OK);
    CHECK_EQ_INT(rs_roads_point_attr_count(R), 3);
    size_t road, point;
    const char *k, *v;
    CHECK(rs_roads_point_attr_at(R, 2, &road, &point, &k, &v) == RS_OK && road == 1 && point == 1 &&
          strcmp(v, "zebra") == 0);
    /* replace in place, then remove */
    CHECK(rs_roads_set_point_attr(ctx, R, 0, 1, "crossing", "traffic_signals") == RS_OK);
    CHECK_EQ_INT(rs_roads_point_attr_count(R), 3);
    CHECK(rs_roads_point_attr_at(R, 0, &road, &point, &k, &v) == RS_OK && strcmp(v, "traffic_signals") == 0);
    CHECK(rs_roads_set_point_attr(ctx, R, 0, 1, "crossing", NULL) == RS_OK);
    CHECK_EQ_INT(rs_roads_point_attr_count(R), 2);
    CHECK(rs_roads_set_point_attr(ctx, R, 0, 1, "crossing", NULL) == RS_OK);
    /* the parser's checks, each naming the value */
    CHECK(rs_roads_set_point_attr(ctx, R, 5, 0, "crossing", "zebra") == RS_ERR_INVALID_ARG && has_msg(ctx, "road 5"));
    CHECK(rs_roads_set_point_attr(ctx, R, 0, 3, "crossing", "zebra") == RS_ERR_INVALID_ARG && has_msg(ctx, "point 3"));
    CHECK(rs_roads_set_point_attr(ctx, R, 0, 0, "bad key", "zebra") == RS_ERR_INVALID_ARG && has_msg(ctx, "bad key"));
    CHECK(rs_roads_set_point_attr(ctx, R, 0, 0, "", "zebra") == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_set_point_attr(ctx, R, 0, 0, "crossing", "") == RS_ERR_INVALID_ARG && has_msg(ctx, "crossing"));
    CHECK(rs_roads_set_point_attr(ctx, R, 0, 0, "crossing", "a\x01") == RS_ERR_INVALID_ARG && has_msg(ctx, "0x01"));
    CHECK(rs_roads_set_point_attr(ctx, R, 0, 0, "crossing", "\xff") == RS_ERR_INVALID_ARG && has_msg(ctx, "UTF-8"));
    CHECK(rs_roads_set_point_attr(ctx, R, 0, 0, NULL, "zebra") == RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_roads_point_attr_count(R), 2);
    rs_roads_free(ctx, R);
    guarded_free(ctx, &guard, "point_attr");
}

static void test_styles_replace(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    rs_styles *S = NULL;
    static const char text[] = "style red\nfill #ff0000\nend\nstyle blue\nfill #0000ff\nend\n";
    CHECK(rs_styles_parse(ctx, text, sizeof text - 1, &S) == RS_OK);
    rs_style st = *rs_styles_find(S, "red");
    CHECK(rs_styles_add(ctx, S, &st) == RS_ERR_INVALID_ARG); /* unchanged: a name in the set is an error */
    st.fill.g = 200;
    CHECK(rs_styles_replace(ctx, S, &st) == RS_OK);
    CHECK_EQ_INT(rs_styles_count(S), 2);
    CHECK(rs_styles_get(S, 0)->fill.g == 200 && strcmp(rs_styles_get(S, 0)->name, "red") == 0);
    CHECK(rs_styles_find(S, "blue") == rs_styles_get(S, 1));
    rs_style nw = st;
    strcpy(nw.name, "green");
    CHECK(rs_styles_replace(ctx, S, &nw) == RS_OK);
    CHECK_EQ_INT(rs_styles_count(S), 3);
    CHECK(rs_styles_find(S, "green") == rs_styles_get(S, 2));
    nw.casing_width = -1;
    CHECK(rs_styles_replace(ctx, S, &nw) == RS_ERR_INVALID_ARG && has_msg(ctx, "casing"));
    CHECK(rs_styles_find(S, "green")->casing_width == st.casing_width);
    CHECK(rs_styles_replace(ctx, NULL, &nw) == RS_ERR_INVALID_ARG);
    rs_styles_free(ctx, S);
    guarded_free(ctx, &guard, "styles_replace");
}

static rs_dem *flat_dem(rs_ctx *ctx, uint32_t w, uint32_t h, double cs)
{
    float *z = calloc((size_t)w * h, sizeof *z);
    rs_dem *dem = NULL;
    rs_dem_frame fr = { cs, 1, 0, 0 };
    if (z && (rs_dem_create(ctx, w, h, z, &dem) || rs_dem_set_frame(ctx, dem, &fr))) {
        rs_dem_free(ctx, dem);
        dem = NULL;
    }
    free(z);
    return dem;
}

/* A named style redefined: the roads naming it change, the others not. */
static void test_style_edit_grid(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    rs_dem *dem = flat_dem(ctx, 41, 31, 2);
    rs_styles *S = NULL;
    static const char text[] = "style red\nfill #ff0000\ncasing 0.5 #202020\nend\n"
                               "road a width 6 style=red\n5 10\n75 12\nend\n"
                               "road b width 6 class=residential\n10 40\n70 50\nend\n";
    rs_roads *R = NULL;
    CHECK(rs_styles_create(ctx, &S) == RS_OK);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = S;
    CHECK(rs_roads_parse_ex(ctx, text, sizeof text - 1, &po, &R) == RS_OK);
    rs_splat_options o = edit_opts(8);
    o.style.styles = S;
    rs_road_grid *g0 = NULL, *g1 = NULL, *gf = NULL;
    image a, b, c;
    CHECK(rs_road_grid_build(ctx, dem, R, &o, &g0) == RS_OK && render(ctx, dem, g0, &o, &a) == 0);
    rs_style st = *rs_styles_find(S, "red");
    st.fill.r = 0, st.fill.g = 160;
    CHECK(rs_styles_replace(ctx, S, &st) == RS_OK);
    CHECK(rs_road_grid_update(ctx, dem, R, &o, g0, &g1) == RS_OK && render(ctx, dem, g1, &o, &b) == 0);
    CHECK(rs_road_grid_build(ctx, dem, R, &o, &gf) == RS_OK && render(ctx, dem, gf, &o, &c) == 0);
    CHECK(same_image(&b, &c));
    size_t nr = rs_road_grid_dirty(g1, NULL, 0);
    rs_pixel_rect rr[4096];
    CHECK(nr > 0 && nr <= 4096);
    rs_road_grid_dirty(g1, rr, 4096);
    /* every changed pixel inside, and road b's pixels (rows below 30 m) clean */
    long out = 0, low = 0;
    for (uint32_t y = 0; y < a.h; y++)
        for (uint32_t x = 0; x < a.w; x++) {
            int in = 0;
            for (size_t k = 0; k < nr && k < 4096; k++)
                in |= x >= rr[k].x0 && x < rr[k].x1 && y >= rr[k].y0 && y < rr[k].y1;
            if (pixel_differs(&a, &c, (size_t)y * a.w + x) && !in) out++;
            if (in && y * 0.25 > 30) low++;
        }
    CHECK_EQ_INT(out, 0);
    CHECK_EQ_INT(low, 0);
    /* a count smaller than the rectangles: the first cap of them */
    rs_pixel_rect one;
    CHECK(rs_road_grid_dirty(g1, &one, 1) == nr && one.x0 == rr[0].x0 && one.y1 == rr[0].y1);
    image_free(&a);
    image_free(&b);
    image_free(&c);
    rs_road_grid_free(ctx, g0);
    rs_road_grid_free(ctx, g1);
    rs_road_grid_free(ctx, gf);
    rs_roads_free(ctx, R);
    rs_styles_free(ctx, S);
    rs_dem_free(ctx, dem);
    guarded_free(ctx, &guard, "style_edit_grid");
}

static void test_update_errors(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    rs_dem *dem = flat_dem(ctx, 21, 21, 2), *other = flat_dem(ctx, 23, 21, 2);
    rs_roads *R = NULL;
    CHECK(rs_roads_parse(ctx, two_roads, sizeof two_roads - 1, &R) == RS_OK);
    rs_splat_options o = edit_opts(4);
    rs_road_grid *g0 = NULL, *g1 = (rs_road_grid *)1;
    CHECK(rs_road_grid_build(ctx, dem, R, &o, &g0) == RS_OK);
    CHECK(rs_road_grid_update(ctx, dem, R, &o, NULL, &g1) == RS_ERR_INVALID_ARG && g1 == NULL && has_msg(ctx, "old"));
    CHECK(rs_road_grid_update(ctx, dem, NULL, &o, g0, &g1) == RS_ERR_INVALID_ARG && has_msg(ctx, "roads"));
    CHECK(rs_road_grid_update(ctx, NULL, R, &o, g0, &g1) == RS_ERR_INVALID_ARG && has_msg(ctx, "dem"));
    CHECK(rs_road_grid_update(ctx, dem, R, &o, g0, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_road_grid_update(NULL, dem, R, &o, g0, &g1) == RS_ERR_INVALID_ARG);
    CHECK(rs_road_grid_update(ctx, other, R, &o, g0, &g1) == RS_ERR_INVALID_ARG && has_msg(ctx, "23 x 21"));
    o.texels = 8;
    CHECK(rs_road_grid_update(ctx, dem, R, &o, g0, &g1) == RS_ERR_INVALID_ARG && has_msg(ctx, "8"));
    o.texels = 4;
    o.coverage.edges = RS_EDGES_ALPHAMAP;
    CHECK(rs_road_grid_update(ctx, dem, R, &o, g0, &g1) == RS_ERR_INVALID_ARG && has_msg(ctx, "edges"));
    o.coverage.edges = RS_EDGES_ANALYTIC;
    /* a grid built without opts->grid.edits keeps no pieces: the update
     * refuses it, rect_has_roads says "may" everywhere, its bytes are the
     * same, and its splat too */
    {
        rs_splat_options p = o;
        p.grid.edits = 0;
        rs_road_grid *gp = NULL;
        CHECK(rs_road_grid_build(ctx, dem, R, &p, &gp) == RS_OK);
        CHECK(rs_road_grid_update(ctx, dem, R, &o, gp, &g1) == RS_ERR_INVALID_ARG && g1 == NULL &&
              has_msg(ctx, "grid.edits"));
        CHECK(rs_road_grid_rect_has_roads(gp, 70, 70, 80, 80) == 1);
        CHECK(rs_road_grid_dirty(gp, NULL, 0) == 0);
        rs_road_grid_stats sp, s0b;
        rs_road_grid_get_stats(gp, &sp);
        rs_road_grid_get_stats(g0, &s0b);
        CHECK(sp.bytes < s0b.bytes);
        ss_image a, b;
        CHECK(ss_grid_image(ctx, dem, gp, &p, &a) == 0 && ss_grid_image(ctx, dem, g0, &o, &b) == 0 &&
              a.w == b.w && a.h == b.h && memcmp(a.rgba, b.rgba, (size_t)a.w * a.h * 4) == 0);
        ss_image_free(&a);
        ss_image_free(&b);
        /* the update's grid keeps pieces even when the options say 0 */
        CHECK(rs_road_grid_update(ctx, dem, R, &p, g0, &g1) == RS_OK);
        CHECK(rs_road_grid_rect_has_roads(g1, 70, 70, 80, 80) == 0);
        rs_road_grid_free(ctx, g1);
        rs_road_grid_free(ctx, gp);
    }
    /* no edit: nothing dirty */
    CHECK(rs_road_grid_update(ctx, dem, R, &o, g0, &g1) == RS_OK);
    CHECK_EQ_INT(rs_road_grid_dirty(g1, NULL, 0), 0);
    rs_road_grid_stats s0, s1;
    rs_road_grid_get_stats(g0, &s0);
    rs_road_grid_get_stats(g1, &s1);
    CHECK(s0.bytes == s1.bytes);
    /* rect_has_roads: empty, far from the roads, on them */
    CHECK(rs_road_grid_rect_has_roads(g1, 5, 5, 5, 9) == 0);
    CHECK(rs_road_grid_rect_has_roads(NULL, 0, 0, 9, 9) == 0);
    CHECK(rs_road_grid_rect_has_roads(g1, 0, 0, 80, 80) == 1);
    rs_road_grid_free(ctx, g1);
    /* a road removed: renumbered roads dirty nothing of their own */
    CHECK(rs_roads_remove(ctx, R, 0) == RS_OK);
    CHECK(rs_road_grid_update(ctx, dem, R, &o, g0, &g1) == RS_OK);
    size_t nr = rs_road_grid_dirty(g1, NULL, 0);
    rs_pixel_rect rr[512];
    CHECK(nr > 0 && nr <= 512);
    rs_road_grid_dirty(g1, rr, 512);
    int beyond = 0; /* road a ran along y = 0 (rows 0..~4 at 0.5 m, up to its reach) */
    for (size_t k = 0; k < nr && k < 512; k++) {
        if (rr[k].y1 > 12) fprintf(stderr, "    rect %u %u %u %u\n", rr[k].x0, rr[k].y0, rr[k].x1, rr[k].y1);
        beyond |= rr[k].y1 > 12;
    }
    CHECK(!beyond);
    rs_road_grid_free(ctx, g1);
    rs_road_grid_free(ctx, g0);
    rs_roads_free(ctx, R);
    rs_dem_free(ctx, dem);
    rs_dem_free(ctx, other);
    guarded_free(ctx, &guard, "update_errors");
}

typedef struct sweep_in {
    const rs_dem *dem;
    const char *text;
    int what; /* 0: update, 1: remove, 2: replace, 3: point attribute, 4: subset build */
} sweep_in;

static rs_result try_edit(rs_ctx *c, void *user, int *wrong)
{
    const sweep_in *in = user;
    rs_roads *R = NULL;
    rs_result r = rs_roads_parse(c, in->text, strlen(in->text), &R);
    if (r) return r;
    const double pts[] = { 0, 3, 40, 8, 80, 3, 100, 9, 110, 20 };
    if (in->what == 0) {
        rs_splat_options o = edit_opts(4);
        rs_road_grid *g0 = NULL, *g1 = (rs_road_grid *)1;
        r = rs_road_grid_build(c, in->dem, R, &o, &g0);
        if (!r) r = rs_roads_replace(c, R, 1, NULL, 5, pts, 3);
        if (!r) {
            r = rs_road_grid_update(c, in->dem, R, &o, g0, &g1);
            if (r != RS_OK && g1 != NULL) *wrong = 1;
            if (r == RS_OK) rs_road_grid_free(c, g1);
        }
        rs_road_grid_free(c, g0);
    } else if (in->what == 1) {
        r = rs_roads_remove(c, R, 1);
    } else if (in->what == 2) {
        size_t before = rs_roads_point_attr_count(R);
        r = rs_roads_replace(c, R, 0, "longer name for the pool", 5, pts, 5);
        if (r && rs_roads_point_attr_count(R) != before) *wrong = 1;
    } else if (in->what == 3) {
        for (int k = 0; k < 40 && !r; k++) r = rs_roads_set_point_attr(c, R, 0, (size_t)(k % 3), k & 1 ? "x" : "y", "v");
    } else if (in->what == 6) {
        /* a chain moved onto a grid of a copy of its roads */
        rs_splat_options o = edit_opts(4);
        rs_road_grid *g0 = NULL, *g1 = NULL, *f = NULL, *b = (rs_road_grid *)1;
        rs_roads *C = NULL;
        r = rs_road_grid_build(c, in->dem, R, &o, &g0);
        if (!r) r = rs_roads_copy(c, R, &C);
        if (!r) r = rs_roads_replace(c, R, 1, NULL, 5, pts, 3);
        if (!r) r = rs_road_grid_update(c, in->dem, R, &o, g0, &g1);
        if (!r) r = rs_road_grid_build(c, in->dem, C, &o, &f);
        if (!r) {
            r = rs_road_grid_rebase(c, g1, g0, f, &b);
            if (r != RS_OK && b != NULL) *wrong = 1;
            if (r == RS_OK) rs_road_grid_free(c, b);
        }
        rs_road_grid_free(c, g0);
        rs_road_grid_free(c, g1);
        rs_road_grid_free(c, f);
        rs_roads_free(c, C);
    } else if (in->what == 5) {
        rs_roads *C = (rs_roads *)1;
        r = rs_roads_copy(c, R, &C);
        if (r != RS_OK && C != NULL) *wrong = 1;
        if (r == RS_OK) rs_roads_free(c, C);
    } else {
        /* the local build of roads a and c (their markings and zebra
         * points renumbered) with the network of all three */
        rs_splat_options o = edit_opts(4);
        rs_network *net = NULL;
        rs_road_grid *g = (rs_road_grid *)1;
        const uint32_t ac[2] = { 0, 2 };
        r = rs_network_build(c, R, NULL, &net);
        if (!r) {
            r = rs__road_grid_build_subset(c, in->dem, R, &o, net, NULL, ac, 2, &g);
            if (r != RS_OK && g != NULL) *wrong = 1;
            if (r == RS_OK) rs_road_grid_free(c, g);
        }
        rs_network_free(c, net);
    }
    rs_roads_free(c, R);
    return r;
}

static void test_alloc_failures(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_dem *dem = flat_dem(ctx, 31, 21, 4);
    for (int what = 0; what < 7; what++) {
        sweep_in in = { dem, two_roads, what };
        fail_sweep fs = fail_alloc_sweep(20000, try_edit, &in);
        CHECKF(fs.succeeded && fs.wrong == 0 && fs.leaks == 0, "sweep %d: tries %ld wrong %ld leaks %ld", what,
               fs.tries, fs.wrong, fs.leaks);
    }
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
}

/* Cancel at every progress call of an update, the comparison's last ones
 * included: RS_ERR_CANCELLED and no grid, or (past the last) the grid and
 * its exact rectangles. */
typedef struct cancel_at {
    long calls, at;
} cancel_at;

static int cancel_cb(void *user, uint64_t done, uint64_t total)
{
    cancel_at *c = user;
    (void)done, (void)total;
    return ++c->calls == c->at;
}

static void test_update_cancel(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    rs_dem *dem = flat_dem(ctx, 31, 21, 4);
    rs_roads *R = NULL;
    CHECK(rs_roads_parse(ctx, two_roads, sizeof two_roads - 1, &R) == RS_OK);
    rs_splat_options o = edit_opts(4);
    rs_road_grid *g0 = NULL;
    CHECK(rs_road_grid_build(ctx, dem, R, &o, &g0) == RS_OK);
    const double pts[] = { 0, 3, 40, 8, 80, 3 };
    CHECK(rs_roads_replace(ctx, R, 1, NULL, 5, pts, 3) == RS_OK);
    cancel_at c = { 0, 0 };
    rs_ctx_set_progress(ctx, cancel_cb, &c);
    rs_road_grid *g1 = NULL;
    CHECK(rs_road_grid_update(ctx, dem, R, &o, g0, &g1) == RS_OK && g1);
    size_t nr = g1 ? rs_road_grid_dirty(g1, NULL, 0) : 0;
    rs_road_grid_free(ctx, g1);
    long total = c.calls;
    CHECK(total > 2 && nr > 0);
    for (long at = 1; at <= total + 1; at++) {
        c.calls = 0, c.at = at;
        g1 = (rs_road_grid *)1;
        rs_result r = rs_road_grid_update(ctx, dem, R, &o, g0, &g1);
        if (at <= total)
            CHECKF(r == RS_ERR_CANCELLED && g1 == NULL, "cancel at call %ld of %ld: %s", at, total, rs_strerror(r));
        else
            CHECKF(r == RS_OK && g1 && rs_road_grid_dirty(g1, NULL, 0) == nr, "no cancel: %s", rs_strerror(r));
        if (r == RS_OK) rs_road_grid_free(ctx, g1);
    }
    rs_ctx_set_progress(ctx, NULL, NULL);
    rs_road_grid_free(ctx, g0);
    rs_roads_free(ctx, R);
    rs_dem_free(ctx, dem);
    guarded_free(ctx, &guard, "update_cancel");
}

/* Distance from the box [x0, x1] x [y0, y1] to road i's polyline, from
 * points 0.25 m apart on each segment (a test of tens of metres). */
static double road_box_dist(const rs_roads *roads, size_t i, double x0, double y0, double x1, double y1)
{
    const double *xy;
    size_t n;
    double best = INFINITY;
    rs_roads_get(roads, i, NULL, NULL, &xy, &n);
    for (size_t k = 0; k < n; k++) {
        const double *a = xy + 2 * k, *b = xy + 2 * (k + 1 < n ? k + 1 : k);
        int steps = (int)(hypot(b[0] - a[0], b[1] - a[1]) / 0.25) + 1;
        for (int j = 0; j <= steps; j++) {
            double t = (double)j / steps, x = a[0] + t * (b[0] - a[0]), y = a[1] + t * (b[1] - a[1]);
            double dx = x < x0 ? x0 - x : x > x1 ? x - x1 : 0, dy = y < y0 ? y0 - y : y > y1 ? y - y1 : 0;
            best = fmin(best, sqrt(dx * dx + dy * dy));
        }
    }
    return best;
}

/* Styles for the local builds' second city: casings of two colours on some
 * roads only, a fill and a gradient, dashed lines. */
static const char subset_styles[] = "style red\nfill #b04030\ncasing 0.4 #303030\nline 0 0.2 #ffffff dash 3 3\nend\n"
                                    "style grad\ngradient #202020 #707070\ncasing 0.6 #a0a0a0\nend\n"
                                    "style kerb\ncasing 0.3 #303030\nline 1 0.15 #ffff00\nend\n";

/* One city for test_subset_build: `styled` 1 by class, 2 by the styles
 * above on a third of the roads (in runs of 40, so that boxes see some
 * and not others). Returns the pixels compared; *differ counts those that
 * differ, *kept the roads the boxes took. */
static size_t subset_case(int styled, int use_net, size_t *differ, size_t *kept)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_network *net = NULL;
    rs_styles *S = NULL;
    size_t pixels = 0;
    *differ = *kept = 0;
    int ok = ss_city_of(ctx, 161, 141, 1000, 5, styled == 1, &sc, &dem, &roads) == 0;
    static const char *const names[] = { "red", "grad", "kerb" };
    for (size_t i = 0; ok && styled == 2 && i < sc.nroads; i++)
        if ((i / 40) % 3 == 0) ok = rs_roads_set_attr(ctx, roads, i, "style", names[(i / 120) % 3]) == RS_OK;
    if (ok && styled == 2) ok = rs_styles_parse(ctx, subset_styles, sizeof subset_styles - 1, &S) == RS_OK;
    rs_splat_options o = edit_opts(4);
    o.style.styles = S;
    rs_road_grid *g = NULL, *gs = NULL;
    image a, b;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    ok = ok && rs_road_grid_build(ctx, dem, roads, &o, &g) == RS_OK && render(ctx, dem, g, &o, &a) == 0 &&
         rs_network_build(ctx, roads, NULL, &net) == RS_OK;
    CHECKF(ok, "city %d: %s", styled, rs_ctx_message(ctx));
    size_t n = rs_roads_count(roads);
    uint32_t *ids = malloc((n ? n : 1) * sizeof *ids);
    CHECK(ids != NULL);
    rs__grid_facts facts;
    if (ok && ids) rs__grid_facts_of(g, &facts);
    if (ok && ids && styled == 1 && use_net) {
        for (size_t i = 0; i < n; i++) ids[i] = (uint32_t)i;
        ok = rs__road_grid_build_subset(ctx, dem, roads, &o, net, &facts, ids, n, &gs) == RS_OK &&
             render(ctx, dem, gs, &o, &b) == 0;
        CHECKF(ok && same_image(&a, &b), "every road: not the whole build's image");
        image_free(&b);
        rs_road_grid_free(ctx, gs);
        gs = NULL;
        ids[0] = 1, ids[1] = 0;
        CHECK_EQ_INT(rs__road_grid_build_subset(ctx, dem, roads, &o, net, &facts, ids, 2, &gs), RS_ERR_INVALID_ARG);
        CHECK(gs == NULL);
    }
    sc_rng rng;
    sc_rng_seed(&rng, 77);
    double W = sc_extent_x(&sc), H = sc_extent_y(&sc), pix = 5.0 / 4;
    for (int box = 0; box < 20 && ok && ids; box++) {
        double bw = 60 + 140 * sc_rng_unit(&rng), bh = 60 + 140 * sc_rng_unit(&rng);
        double x0 = sc_rng_unit(&rng) * (W - bw), y0 = sc_rng_unit(&rng) * (H - bh);
        size_t m = 0;
        for (size_t i = 0; i < n; i++)
            if (road_box_dist(roads, i, x0, y0, x0 + bw, y0 + bh) <= 60) ids[m++] = (uint32_t)i;
        *kept += m;
        rs_roads *part = NULL;
        if (use_net) ok = rs__road_grid_build_subset(ctx, dem, roads, &o, net, &facts, ids, m, &gs) == RS_OK;
        else /* (the part's roads alone, with a network of their own) */
            ok = rs__roads_subset(ctx, roads, ids, m, &part) == RS_OK &&
                 rs_road_grid_build(ctx, dem, part, &o, &gs) == RS_OK;
        rs_roads_free(ctx, part);
        ok = ok && render(ctx, dem, gs, &o, &b) == 0;
        CHECKF(ok, "box %d: %s", box, rs_ctx_message(ctx));
        for (uint32_t y = (uint32_t)(y0 / pix); ok && y < (uint32_t)((y0 + bh) / pix) && y < a.h; y++)
            for (uint32_t x = (uint32_t)(x0 / pix); x < (uint32_t)((x0 + bw) / pix) && x < a.w; x++) {
                *differ += pixel_differs(&a, &b, (size_t)y * a.w + x);
                pixels++;
            }
        image_free(&b);
        rs_road_grid_free(ctx, gs);
        gs = NULL;
    }
    free(ids);
    image_free(&a);
    rs_road_grid_free(ctx, g);
    rs_network_free(ctx, net);
    rs_roads_free(ctx, roads);
    rs_styles_free(ctx, S);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    guarded_free(ctx, &guard, "subset");
    return pixels;
}

/* The local build a proportional update needs (docs/embedding.md "Toward
 * an update in proportion to the edit"): rs__road_grid_build_subset of the
 * roads within 60 m of each of twenty boxes, with the whole map's network (its
 * strokes' arc lengths, so the dashes keep their phase) and facts (the
 * styles' switches, the index cell), splats the boxes' pixels as the grid
 * of all roads does. On two cities of 1000 roads at 1.25 m pixels:
 * class-styled (casings, edge and dashed centre lines, automatic
 * markings), and named styles on some roads (casings of two colours, a
 * fill, a gradient, dashed lines). With every road it is the whole build's
 * image; with a network of the part's roads alone pixels differ. Ids out of order are
 * refused; rs__roads_subset renumbers markings and point attributes. */
static void test_subset_build(void)
{
    size_t differ, kept;
    for (int styled = 1; styled <= 2; styled++) {
        size_t px = subset_case(styled, 1, &differ, &kept);
        printf("  subset builds, city %d: %zu of %zu box pixels differ (%zu roads kept of 20 x 1000)\n", styled,
               differ, px, kept);
        CHECK(px > 160000);
        CHECK(kept < 20 * 1000 / 2);
        CHECKF(differ == 0, "city %d: %zu pixels differ", styled, differ);
    }
    size_t px = subset_case(1, 0, &differ, &kept);
    printf("  the same roads with a network of their own: %zu of %zu differ\n", differ, px);
    CHECK(differ > 0);
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    /* roads a and c of three: their markings and zebra points follow them */
    rs_roads *R = NULL, *sub = NULL;
    const uint32_t ac[2] = { 0, 2 };
    CHECK(rs_roads_parse(ctx, two_roads, strlen(two_roads), &R) == RS_OK &&
          rs__roads_subset(ctx, R, ac, 2, &sub) == RS_OK);
    if (sub) {
        const char *name = NULL;
        rs_mark mk;
        size_t road = 9, point = 9;
        CHECK_EQ_INT((int)rs_roads_count(sub), 2);
        CHECK(rs_roads_get(sub, 1, &name, NULL, NULL, NULL) == RS_OK && strcmp(name, "c") == 0);
        CHECK(rs_roads_get_attr(sub, 0, "class") && strcmp(rs_roads_get_attr(sub, 0, "class"), "residential") == 0);
        CHECK_EQ_INT((int)rs_roads_mark_count(sub), 2);
        CHECK(rs_roads_get_mark(sub, 1, &mk) == RS_OK && mk.road == 1 && mk.s == 30);
        CHECK_EQ_INT((int)rs_roads_point_attr_count(sub), 2);
        CHECK(rs_roads_point_attr_at(sub, 1, &road, &point, NULL, NULL) == RS_OK && road == 1 && point == 1);
    }
    rs_roads_free(ctx, sub);
    rs_roads_free(ctx, R);
    guarded_free(ctx, &guard, "subset_build");
}

/* Shared structures between threads (docs/embedding.md "Patches"): a
 * patched grid renders in one thread while the grid it was updated from,
 * whose structures it shares, is freed in another; its image is the fresh
 * build's. Then the patched grid itself is freed (the base goes with it:
 * ASan's leak check in make sanitize-test). */
typedef struct render_job {
    const rs_dem *dem;
    const rs_road_grid *g;
    const rs_splat_options *o;
    image im;
    int ok;
} render_job;

static void *render_thread(void *arg)
{
    render_job *j = arg;
    rs_ctx *c = NULL;
    j->ok = rs_ctx_create(NULL, NULL, &c) == RS_OK && render(c, j->dem, j->g, j->o, &j->im) == 0;
    rs_ctx_free(c);
    return NULL;
}

static void test_shared_free(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    int ok = ss_city_of(ctx, 121, 101, 200, 21, 1, &sc, &dem, &roads) == 0;
    rs_splat_options o = edit_opts(4);
    rs_road_grid *g0 = NULL, *g1 = NULL, *gf = NULL;
    const double xy[] = { 200, 200, 260, 230, 300, 290 };
    ok = ok && rs_road_grid_build(ctx, dem, roads, &o, &g0) == RS_OK &&
         rs_roads_add(ctx, roads, "new", 7, xy, 3) == RS_OK && rs_road_grid_update(ctx, dem, roads, &o, g0, &g1) == RS_OK &&
         rs_road_grid_build(ctx, dem, roads, &o, &gf) == RS_OK;
    CHECK(ok);
    if (ok) {
        rs_road_grid_stats a, b;
        rs_road_grid_get_stats(g1, &a);
        rs_road_grid_get_stats(gf, &b);
        CHECKF(a.bytes > b.bytes, "a patched grid counts its base and patch: %llu bytes, a whole one %llu",
               (unsigned long long)a.bytes, (unsigned long long)b.bytes);
        render_job j = { dem, g1, &o, { 0 }, 0 };
        pthread_t th;
        CHECK(pthread_create(&th, NULL, render_thread, &j) == 0);
        rs_road_grid_free(ctx, g0); /* (while g1 renders) */
        g0 = NULL;
        pthread_join(th, NULL);
        image c;
        memset(&c, 0, sizeof c);
        CHECK(j.ok && render(ctx, dem, gf, &o, &c) == 0 && same_image(&j.im, &c));
        image_free(&j.im);
        image_free(&c);
        /* queries: the same road, point and distance (inside the patch too) */
        sc_rng rng;
        sc_rng_seed(&rng, 5);
        int same = 1, hits = 0;
        for (int k = 0; k < 400; k++) {
            double x = k < 200 ? sc_rng_range(&rng, 150, 350) : sc_rng_range(&rng, 0, sc_extent_x(&sc));
            double y = k < 200 ? sc_rng_range(&rng, 150, 340) : sc_rng_range(&rng, 0, sc_extent_y(&sc));
            rs_road_point p1, pf;
            int h1 = rs_road_grid_query(g1, x, y, 15, &p1), hf = rs_road_grid_query(gf, x, y, 15, &pf);
            hits += hf;
            same &= h1 == hf && (!hf || (p1.road == pf.road && p1.segment == pf.segment && p1.s == pf.s &&
                                         p1.t == pf.t && p1.distance == pf.distance));
        }
        CHECKF(same && hits > 100, "queries of the patched grid: same %d, %d hits", same, hits);
    }
    rs_road_grid_free(ctx, g0);
    rs_road_grid_free(ctx, g1);
    rs_road_grid_free(ctx, gf);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    guarded_free(ctx, &guard, "shared_free");
}


/* A road dragged: forty moves of one road by about a metre, chained. Each
 * patch covers the last one's rectangle, which then goes, until that would
 * more than double the new rectangle (docs/embedding.md "Patches"): the
 * grid holds 1 to 3 patches (16 without), so a drag comes nowhere near the
 * whole build at the 17th patch; every step splats to a fresh build's
 * bytes and its rectangles cover every changed pixel. */
static void test_drag(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    int ok = ss_city_of(ctx, 241, 201, 800, 21, 1, &sc, &dem, &roads) == 0;
    CHECK(ok);
    rs_splat_options o = edit_opts(4);
    rs_road_grid *g0 = NULL;
    image a;
    memset(&a, 0, sizeof a);
    ok = ok && rs_road_grid_build(ctx, dem, roads, &o, &g0) == RS_OK && render(ctx, dem, g0, &o, &a) == 0;
    CHECK(ok);
    /* the road nearest the map's middle */
    double W = sc_extent_x(&sc), H = sc_extent_y(&sc), best = INFINITY;
    size_t pick = 0;
    for (size_t i = 0; ok && i < rs_roads_count(roads); i++) {
        const double *xy;
        size_t np;
        rs_roads_get(roads, i, NULL, NULL, &xy, &np);
        double d = hypot(xy[0] - 0.5 * W, xy[1] - 0.5 * H);
        if (d < best) best = d, pick = i;
    }
    size_t most = 0;
    long uncovered = 0, differ = 0;
    for (int step = 0; ok && step < 40; step++) {
        ok = move_road(ctx, roads, pick, 1.0, 0.4) == 0;
        rs_road_grid *g1 = NULL, *gf = NULL;
        image b, c;
        memset(&b, 0, sizeof b);
        memset(&c, 0, sizeof c);
        ok = ok && rs_road_grid_update(ctx, dem, roads, &o, g0, &g1) == RS_OK && render(ctx, dem, g1, &o, &b) == 0 &&
             rs_road_grid_build(ctx, dem, roads, &o, &gf) == RS_OK && render(ctx, dem, gf, &o, &c) == 0;
        CHECKF(ok, "drag step %d: %s", step, rs_ctx_message(ctx));
        if (ok) {
            most = g1->npatch > most ? g1->npatch : most;
            differ += !same_image(&b, &c);
            size_t nr = rs_road_grid_dirty(g1, NULL, 0);
            rs_pixel_rect *R = malloc((nr ? nr : 1) * sizeof *R);
            ok = R != NULL;
            if (ok) rs_road_grid_dirty(g1, R, nr);
            for (size_t px = 0; ok && px < (size_t)a.w * a.h; px++) {
                if (!pixel_differs(&a, &b, px)) continue;
                uint32_t x = (uint32_t)(px % a.w), y = (uint32_t)(px / a.w);
                int in = 0;
                for (size_t k = 0; k < nr && !in; k++) in = x >= R[k].x0 && x < R[k].x1 && y >= R[k].y0 && y < R[k].y1;
                uncovered += !in;
            }
            free(R);
        }
        rs_road_grid_free(ctx, gf);
        rs_road_grid_free(ctx, g0);
        g0 = g1;
        image_free(&a);
        image_free(&c);
        a = b;
    }
    CHECKF(most >= 1 && most <= 3, "drag: the grid held up to %zu patches (1 to 3 expected)", most);
    CHECKF(differ == 0, "drag: %ld steps not a fresh build's bytes", differ);
    CHECKF(uncovered == 0, "drag: %ld changed pixels outside the rectangles", uncovered);
    image_free(&a);
    rs_road_grid_free(ctx, g0);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    guarded_free(ctx, &guard, "drag");
}

/* rs_roads_copy: the same roads, names, attributes, markings, point
 * attributes and frame as the original; an edit of either leaves the other
 * as it was; NULL is refused. */
static void test_roads_copy(void)
{
    guard_alloc guard;
    rs_ctx *ctx = guarded_ctx(&guard, NULL);
    rs_roads *R = NULL, *C = NULL;
    CHECK_EQ_INT(rs_roads_parse(ctx, two_roads, strlen(two_roads), &R), RS_OK);
    CHECK_EQ_INT(rs_roads_copy(ctx, R, &C), RS_OK);
    int same = R && C && rs_roads_count(R) == rs_roads_count(C) && rs_roads_mark_count(R) == rs_roads_mark_count(C) &&
               rs_roads_point_attr_count(R) == rs_roads_point_attr_count(C) && rs_roads_frame(R, NULL) == rs_roads_frame(C, NULL);
    for (size_t i = 0; same && i < rs_roads_count(R); i++) {
        const char *na, *nb;
        double wa, wb;
        const double *pa, *pb;
        size_t ca, cb;
        rs_roads_get(R, i, &na, &wa, &pa, &ca);
        rs_roads_get(C, i, &nb, &wb, &pb, &cb);
        same = strcmp(na, nb) == 0 && wa == wb && ca == cb && memcmp(pa, pb, 2 * ca * sizeof *pa) == 0 &&
               rs_roads_attr_count(R, i) == rs_roads_attr_count(C, i);
        for (size_t k = 0; same && k < rs_roads_attr_count(R, i); k++) {
            const char *ka, *va, *kb, *vb;
            rs_roads_attr_at(R, i, k, &ka, &va);
            rs_roads_attr_at(C, i, k, &kb, &vb);
            same = strcmp(ka, kb) == 0 && strcmp(va, vb) == 0;
        }
    }
    CHECK(same);
    CHECK(R && rs_roads_mark_count(R) > 0 && rs_roads_point_attr_count(R) > 0); /* (the copy had them to copy) */
    /* edits of the copy leave the original, and the other way round */
    const double pts[] = { 1, 2, 3, 4 };
    size_t n0 = rs_roads_count(R);
    CHECK_EQ_INT(rs_roads_remove(ctx, C, 0), RS_OK);
    CHECK_EQ_INT(rs_roads_add(ctx, C, "new", 3, pts, 2), RS_OK);
    CHECK_EQ_INT(rs_roads_count(R), n0);
    CHECK_EQ_INT(rs_roads_replace(ctx, R, 0, "renamed", 2, pts, 2), RS_OK);
    const char *name = NULL;
    rs_roads_get(C, rs_roads_count(C) - 1, &name, NULL, NULL, NULL);
    CHECK(name && strcmp(name, "new") == 0);
    rs_roads *N = (rs_roads *)1;
    CHECK_EQ_INT(rs_roads_copy(ctx, NULL, &N), RS_ERR_INVALID_ARG);
    CHECK(N == NULL);
    CHECK(has_msg(ctx, "rs_roads_copy"));
    CHECK_EQ_INT(rs_roads_copy(ctx, R, NULL), RS_ERR_INVALID_ARG);
    rs_roads_free(ctx, R);
    rs_roads_free(ctx, C);
    guarded_free(ctx, &guard, "roads_copy");
}

/* A long chain (docs/embedding.md "Long chains"): rs_limits.max_patches
 * 40, thirty-six moves of roads spread over the map, chained; every grid
 * splats to a fresh build's bytes (more than 16 patches: the windows cut
 * at every patch's edges) and holds at most 40 patches. At the 20th edit
 * a worker thread builds the grid whole from a copy of the roads
 * (rs_roads_copy) while the edits go on; rs_road_grid_rebase then moves the
 * chain onto it: the same bytes, no dirty rectangle, only the patches made
 * after the copy, and four more edits from it splat as fresh builds do.
 * Rebase refuses a flat grid of other roads, a patched one, NULL. Then
 * with max_patches 3 the update past it builds whole, and a rebase across
 * that build keeps the current grid's pixels. */
static void test_long_chain(void)
{
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_patches = 40;
    rs_ctx *ctx;
    rs_ctx_create(NULL, &lim, &ctx);
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL, *snap = NULL;
    int ok = ss_city_of(ctx, 241, 201, 800, 23, 1, &sc, &dem, &roads) == 0;
    CHECK(ok);
    rs_splat_options o = edit_opts(4);
    rs_road_grid *g0 = NULL;
    ok = ok && rs_road_grid_build(ctx, dem, roads, &o, &g0) == RS_OK;
    sc_rng rng;
    sc_rng_seed(&rng, 4242);
    size_t most = 0;
    long differ = 0;
    ss_build_job job;
    memset(&job, 0, sizeof job);
    pthread_t th;
    int started = 0;
    rs_road_grid *since = NULL;
    for (int e = 0; ok && e < 36; e++) {
        if (e == 20) {
            since = g0; /* (kept: the grid the copy was taken at) */
            ok = rs_roads_copy(ctx, roads, &snap) == RS_OK;
            job.dem = dem, job.roads = snap, job.o = &o;
            started = ok && pthread_create(&th, NULL, ss_build_run, &job) == 0;
            CHECK(started);
        }
        size_t i = (size_t)(sc_rng_unit(&rng) * (double)rs_roads_count(roads));
        ok = move_road(ctx, roads, i, 3.0, -2.0) == 0;
        rs_road_grid *g1 = NULL, *gf = NULL;
        image b, c;
        memset(&b, 0, sizeof b);
        memset(&c, 0, sizeof c);
        ok = ok && rs_road_grid_update(ctx, dem, roads, &o, g0, &g1) == RS_OK && render(ctx, dem, g1, &o, &b) == 0 &&
             rs_road_grid_build(ctx, dem, roads, &o, &gf) == RS_OK && render(ctx, dem, gf, &o, &c) == 0;
        CHECKF(ok, "long chain edit %d: %s", e, rs_ctx_message(ctx));
        if (ok) {
            size_t np2 = rs_road_grid_patch_count(g1);
            most = np2 > most ? np2 : most;
            differ += !same_image(&b, &c);
        }
        image_free(&b);
        image_free(&c);
        rs_road_grid_free(ctx, gf);
        if (g0 != since) rs_road_grid_free(ctx, g0);
        g0 = g1;
    }
    CHECKF(most > 16 && most <= 40, "long chain: the grid held up to %zu patches (17 to 40 expected)", most);
    CHECKF(differ == 0, "long chain: %ld grids not a fresh build's bytes", differ);
    /* the worker's whole grid, with the patches made since the copy */
    if (started) pthread_join(th, NULL);
    CHECK(job.ok);
    if (ok && job.ok) {
        rs_road_grid *rb = NULL, *bad = (rs_road_grid *)1, *other = NULL;
        ok = rs_road_grid_rebase(ctx, g0, since, job.g, &rb) == RS_OK;
        CHECKF(ok, "rebase: %s", rs_ctx_message(ctx));
        size_t before = rs_road_grid_patch_count(g0), after = rb ? rs_road_grid_patch_count(rb) : 0;
        CHECKF(ok && after <= 16 && after < before && rs_road_grid_dirty(rb, NULL, 0) == 0,
               "rebase: %zu patches (had %zu, 16 edits since the copy), %zu dirty", after, before,
               rb ? rs_road_grid_dirty(rb, NULL, 0) : 0);
        /* the chain goes on from it */
        for (int e = 0; ok && e < 5; e++) {
            rs_road_grid *g1 = NULL, *gf = NULL;
            image b, c;
            memset(&b, 0, sizeof b);
            memset(&c, 0, sizeof c);
            if (e) {
                size_t i = (size_t)(sc_rng_unit(&rng) * (double)rs_roads_count(roads));
                ok = move_road(ctx, roads, i, -2.5, 1.0) == 0 && rs_road_grid_update(ctx, dem, roads, &o, rb, &g1) == RS_OK;
            }
            const rs_road_grid *show = e ? g1 : rb;
            ok = ok && render(ctx, dem, show, &o, &b) == 0 && rs_road_grid_build(ctx, dem, roads, &o, &gf) == RS_OK &&
                 render(ctx, dem, gf, &o, &c) == 0;
            CHECKF(ok && same_image(&b, &c), "rebased chain, edit %d: not a fresh build's bytes", e);
            image_free(&b);
            image_free(&c);
            rs_road_grid_free(ctx, gf);
            if (g1) {
                rs_road_grid_free(ctx, rb);
                rb = g1;
            }
        }
        /* what it refuses */
        CHECK_EQ_INT(rs_road_grid_rebase(ctx, g0, since, g0, &bad), RS_ERR_INVALID_ARG);
        CHECK(bad == NULL && has_msg(ctx, "flat is not a whole grid"));
        ok = rs_road_grid_build(ctx, dem, roads, &o, &other) == RS_OK; /* (the roads now, not the copy's) */
        CHECK_EQ_INT(rs_road_grid_rebase(ctx, g0, since, other, &bad), RS_ERR_INVALID_ARG);
        CHECK(has_msg(ctx, "flat was not built from the roads"));
        CHECK_EQ_INT(rs_road_grid_rebase(ctx, g0, NULL, job.g, &bad), RS_ERR_INVALID_ARG);
        rs_road_grid_free(ctx, other);
        rs_road_grid_free(ctx, rb);
    }
    rs_road_grid_free(ctx, since);
    rs_road_grid_free(ctx, job.g);
    /* max_patches 3: the update that would hold a fourth builds whole */
    rs_limits l3;
    memset(&l3, 0, sizeof l3);
    l3.max_patches = 3;
    rs_ctx *c3;
    rs_ctx_create(NULL, &l3, &c3);
    rs_road_grid *h = NULL;
    ok = ok && rs_road_grid_build(c3, dem, roads, &o, &h) == RS_OK;
    size_t seen[6] = { 0 };
    rs_road_grid *h0 = NULL, *f0 = NULL; /* the first grid, and a whole build of its roads */
    for (int e = 0; ok && e < 6; e++) {
        if (e == 0) {
            h0 = h;
            ok = rs_road_grid_build(c3, dem, roads, &o, &f0) == RS_OK;
        }
        ok = move_road(c3, roads, (size_t)e * 131 % rs_roads_count(roads), -2.0, 1.0) == 0;
        rs_road_grid *h1 = NULL;
        ok = ok && rs_road_grid_update(c3, dem, roads, &o, h, &h1) == RS_OK;
        if (ok) seen[e] = rs_road_grid_patch_count(h1);
        if (h != h0) rs_road_grid_free(c3, h);
        h = h1;
    }
    int capped = 1, reset = 0;
    for (int e = 0; e < 6; e++) capped &= seen[e] <= 3, reset |= e > 0 && seen[e] == 0 && seen[e - 1] == 3;
    CHECKF(capped && reset, "max_patches 3: patches %zu %zu %zu %zu %zu %zu", seen[0], seen[1], seen[2], seen[3], seen[4],
           seen[5]);
    /* across that whole build: current's pixels on current's base */
    if (ok && h0) {
        rs_road_grid *rb = NULL, *gf = NULL;
        image b, c;
        memset(&b, 0, sizeof b);
        memset(&c, 0, sizeof c);
        ok = rs_road_grid_rebase(c3, h, h0, f0, &rb) == RS_OK && render(c3, dem, rb, &o, &b) == 0 &&
             rs_road_grid_build(c3, dem, roads, &o, &gf) == RS_OK && render(c3, dem, gf, &o, &c) == 0;
        CHECKF(ok && same_image(&b, &c) && rs_road_grid_patch_count(rb) == rs_road_grid_patch_count(h),
               "rebase across a whole build: %s", rs_ctx_message(c3));
        image_free(&b);
        image_free(&c);
        rs_road_grid_free(c3, gf);
        rs_road_grid_free(c3, rb);
    }
    rs_road_grid_free(c3, h0);
    rs_road_grid_free(c3, f0);
    rs_road_grid_free(c3, h);
    rs_ctx_free(c3);
    rs_road_grid_free(ctx, g0);
    rs_roads_free(ctx, roads);
    rs_roads_free(ctx, snap);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
}

/* One update checked against a fresh build: the roads (a city, or the
 * test's own), the grid before and its image (a), the updated grid and its
 * image (b), a fresh build and its image (c). */
typedef struct one_edit {
    guard_alloc ga; /* E's context's allocator's (guarded_ctx) */
    rs_ctx *ctx;
    sc_scene sc;
    rs_dem *dem;
    rs_roads *roads;
    rs_splat_options o;
    rs_road_grid *g0, *g1, *gf;
    image a, b, c;
    int ok;
} one_edit;

/* E's context and, with n roads, the 241 x 201 city of n roads (seed). */
static void edit_begin(one_edit *E, size_t n, uint64_t seed)
{
    memset(E, 0, sizeof *E);
    E->ok = (E->ctx = guarded_ctx(&E->ga, NULL)) != NULL;
    if (n) E->ok = E->ok && ss_city_of(E->ctx, 241, 201, n, seed, 1, &E->sc, &E->dem, &E->roads) == 0;
}

/* The whole grid of E's roads and its image (a), with named styles
 * (NULL: none; the caller's, outliving E's grids). */
static void edit_base_styled(one_edit *E, uint32_t texels, const rs_styles *styles)
{
    E->o = edit_opts(texels);
    E->o.style.styles = styles;
    E->ok = E->ok && rs_road_grid_build(E->ctx, E->dem, E->roads, &E->o, &E->g0) == RS_OK &&
            render(E->ctx, E->dem, E->g0, &E->o, &E->a) == 0;
}

static void edit_base(one_edit *E, uint32_t texels)
{
    edit_base_styled(E, texels, NULL);
}

/* The update of E's roads since the base, a fresh build, their images. */
static void edit_update(one_edit *E, const char *what)
{
    E->ok = E->ok && rs_road_grid_update(E->ctx, E->dem, E->roads, &E->o, E->g0, &E->g1) == RS_OK &&
            render(E->ctx, E->dem, E->g1, &E->o, &E->b) == 0 &&
            rs_road_grid_build(E->ctx, E->dem, E->roads, &E->o, &E->gf) == RS_OK &&
            render(E->ctx, E->dem, E->gf, &E->o, &E->c) == 0;
    CHECKF(E->ok, "%s: %s", what, rs_ctx_message(E->ctx));
}

static void edit_end(one_edit *E)
{
    image_free(&E->a);
    image_free(&E->b);
    image_free(&E->c);
    rs_road_grid_free(E->ctx, E->g0);
    rs_road_grid_free(E->ctx, E->g1);
    rs_road_grid_free(E->ctx, E->gf);
    rs_roads_free(E->ctx, E->roads);
    rs_dem_free(E->ctx, E->dem);
    sc_scene_free(&E->sc);
    guarded_free(E->ctx, &E->ga, "one edit");
}

/* An update's grid g1 against the images before (a), from g1 (b) and
 * from a fresh build (c): the same bytes as the fresh build, every changed
 * pixel in a dirty rectangle, none in two, in rows then columns; g1's
 * patch rectangles do not overlap. */
static void check_rects(const char *what, const rs_road_grid *g1, const image *a, const image *b, const image *c)
{
    CHECKF(same_image(b, c), "%s: the updated grid draws otherwise than a fresh build", what);
    size_t nr = rs_road_grid_dirty(g1, NULL, 0);
    rs_pixel_rect *R = malloc((nr ? nr : 1) * sizeof *R);
    CHECK(R != NULL);
    if (R) rs_road_grid_dirty(g1, R, nr);
    long uncovered = 0, twice = 0, order = 0, changed = 0, overlap = 0;
    for (size_t k = 0; R && k + 1 < nr; k++)
        order += R[k].y0 > R[k + 1].y0 || (R[k].y0 == R[k + 1].y0 && R[k].x0 >= R[k + 1].x0);
    for (size_t px = 0; R && px < (size_t)a->w * a->h; px++) {
        uint32_t x = (uint32_t)(px % a->w), y = (uint32_t)(px / a->w);
        int in = 0, inp = 0;
        for (size_t k = 0; k < nr; k++) in += x >= R[k].x0 && x < R[k].x1 && y >= R[k].y0 && y < R[k].y1;
        for (size_t k = 0; k < g1->npatch; k++) {
            const rs_pixel_rect *P = &g1->patch[k].rect;
            inp += x >= P->x0 && x < P->x1 && y >= P->y0 && y < P->y1 && g1->patch[k].grid == g1->patch[g1->npatch - 1].grid;
        }
        twice += in > 1;
        overlap += inp > 1;
        if (pixel_differs(a, b, px)) changed++, uncovered += !in;
    }
    CHECKF(changed > 0 && uncovered == 0 && twice == 0 && order == 0 && overlap == 0,
           "%s: %ld changed, %ld uncovered, %ld in two rectangles, %ld out of order, %ld in two of the last "
           "update's patch rectangles",
           what, changed, uncovered, twice, order, overlap);
    free(R);
}

/* Two roads moved in one update, at opposite corners of the map: one
 * patch (a local build) drawing in two rectangles, one at each (not one
 * rectangle over the map between them); the grid splats to a fresh build's bytes, every changed pixel lies in a
 * rectangle, the rectangles do not overlap and come in rows, then
 * columns. */
static void test_two_places(void)
{
    one_edit E;
    edit_begin(&E, 800, 31);
    edit_base(&E, 4);
    double W = sc_extent_x(&E.sc), H = sc_extent_y(&E.sc);
    for (int corner = 0; E.ok && corner < 2; corner++) {
        double tx = corner ? 0.85 * W : 0.15 * W, ty = corner ? 0.85 * H : 0.15 * H, best = INFINITY;
        size_t pick = 0;
        for (size_t i = 0; i < rs_roads_count(E.roads); i++) {
            const double *xy;
            size_t np;
            double len = 0;
            rs_roads_get(E.roads, i, NULL, NULL, &xy, &np);
            for (size_t k = 0; k + 1 < np; k++) len += hypot(xy[2 * k + 2] - xy[2 * k], xy[2 * k + 3] - xy[2 * k + 1]);
            double d = hypot(xy[0] - tx, xy[1] - ty);
            if (len < 60 && d < best) best = d, pick = i; /* (a short road: it stays in its corner) */
        }
        E.ok = move_road(E.ctx, E.roads, pick, 2.0, 1.5) == 0;
    }
    edit_update(&E, "two places");
    if (E.ok) {
        /* (one local build draws in every rectangle; none spans the map
         * between the corners) */
        const rs_road_grid *g1 = E.g1;
        int small = g1->npatch >= 2;
        for (size_t k = 0; k < g1->npatch; k++)
            small &= g1->patch[k].grid == g1->patch[0].grid &&
                     8 * (uint64_t)(g1->patch[k].rect.x1 - g1->patch[k].rect.x0) * (g1->patch[k].rect.y1 - g1->patch[k].rect.y0) <
                         (uint64_t)E.a.w * E.a.h;
        CHECKF(rs_road_grid_patch_count(g1) == 1 && small,
               "two places: %zu patches in %zu rectangles (1 in small ones expected)", rs_road_grid_patch_count(g1),
               g1->npatch);
        check_rects("two places", g1, &E.a, &E.b, &E.c);
    }
    edit_end(&E);
}

/* A long diagonal road moved: its changed area is the strip along it (boxes
 * along the road, their union in disjoint rectangles), not its bounding
 * box: the patch's rectangles cover well under the box, one local build
 * draws in all of them, and the grid is a fresh build's bytes with every
 * changed pixel in a dirty rectangle. */
static void test_long_road(void)
{
    one_edit E;
    edit_begin(&E, 800, 31);
    edit_base(&E, 4);
    /* the road whose box is widest both ways */
    size_t pick = 0;
    double best = -1, box[4] = { 0, 0, 0, 0 };
    for (size_t i = 0; E.ok && i < rs_roads_count(E.roads); i++) {
        const double *xy;
        size_t np;
        rs_roads_get(E.roads, i, NULL, NULL, &xy, &np);
        double b4[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
        for (size_t k = 0; k < np; k++) {
            b4[0] = fmin(b4[0], xy[2 * k]), b4[1] = fmin(b4[1], xy[2 * k + 1]);
            b4[2] = fmax(b4[2], xy[2 * k]), b4[3] = fmax(b4[3], xy[2 * k + 1]);
        }
        double m = fmin(b4[2] - b4[0], b4[3] - b4[1]);
        if (m > best) best = m, pick = i, memcpy(box, b4, sizeof box);
    }
    E.ok = E.ok && move_road(E.ctx, E.roads, pick, 2.0, 1.5) == 0;
    edit_update(&E, "long road");
    if (E.ok) {
        /* (the rectangles against their bounding box: one rectangle over
         * the changed boxes took that) */
        const rs_road_grid *g1 = E.g1;
        double area = 0;
        rs_pixel_rect hull = g1->patch[0].rect;
        for (size_t k = 0; k < g1->npatch; k++) {
            const rs_pixel_rect *P = &g1->patch[k].rect;
            area += (double)(P->x1 - P->x0) * (P->y1 - P->y0);
            hull.x0 = P->x0 < hull.x0 ? P->x0 : hull.x0, hull.y0 = P->y0 < hull.y0 ? P->y0 : hull.y0;
            hull.x1 = P->x1 > hull.x1 ? P->x1 : hull.x1, hull.y1 = P->y1 > hull.y1 ? P->y1 : hull.y1;
        }
        double hull_px = (double)(hull.x1 - hull.x0) * (hull.y1 - hull.y0);
        CHECKF(rs_road_grid_patch_count(g1) == 1 && g1->npatch > 1 && area < 0.75 * hull_px,
               "long road (%.0f x %.0f m): %zu patches in %zu rectangles of %.0f px, their bounding box %.0f",
               box[2] - box[0], box[3] - box[1], rs_road_grid_patch_count(g1), g1->npatch, area, hull_px);
        check_rects("long road", g1, &E.a, &E.b, &E.c);
    }
    edit_end(&E);
}

/* E on the edits fuzz target's 64 x 48 map of 5 m cells (its heights),
 * with no roads yet. */
static void edit_fuzz_map(one_edit *E)
{
    static float z[64 * 48];
    edit_begin(E, 0, 0);
    for (int k = 0; k < 64 * 48; k++) z[k] = (float)((k * 37 % 23) + (k / 64) * 2);
    rs_dem_frame fr = { 5, 0.05, 0, 0 };
    E->ok = E->ok && rs_dem_create(E->ctx, 64, 48, z, &E->dem) == RS_OK && rs_dem_set_frame(E->ctx, E->dem, &fr) == RS_OK &&
            rs_roads_create(E->ctx, &E->roads) == RS_OK;
}

/* The fuzz map and named styles parsed in a context of their own (*sc),
 * which outlive E's grids (edit_end_styled frees them). */
static rs_styles *edit_fuzz_map_styled(one_edit *E, const char *text, size_t len, rs_ctx **sc)
{
    rs_styles *st = NULL;
    edit_fuzz_map(E);
    *sc = NULL;
    E->ok = E->ok && rs_ctx_create(NULL, NULL, sc) == RS_OK && rs_styles_parse(*sc, text, len, &st) == RS_OK;
    return st;
}

static void edit_end_styled(one_edit *E, rs_ctx *sc, rs_styles *st)
{
    edit_end(E);
    rs_styles_free(sc, st);
    rs_ctx_free(sc);
}

/* A road of a fuzz input: width, point count, points. */
typedef struct fuzz_road {
    double w;
    size_t n;
    double xy[6];
} fuzz_road;

static void add_fuzz_roads(one_edit *E, const fuzz_road *r, size_t n)
{
    for (size_t k = 0; k < n; k++) E->ok = E->ok && rs_roads_add(E->ctx, E->roads, NULL, r[k].w, r[k].xy, r[k].n) == RS_OK;
}

/* A long road moved before another long one (fuzz/edits, 6 December
 * 2026): the update copies the kept roads' boxes along them (chunks) a
 * run at a time into room made once for all the kept ones, while a moved
 * road's boxes, made anew from its points, go in between; with more than
 * the slack of them the next run's copy wrote past the room (a heap
 * overflow AddressSanitizer found in the fuzz target). A guarded
 * allocator sees such a write in a plain build; the updated grid must
 * also draw as a fresh build. */
static void test_chunk_room(void)
{
    guard_alloc ga = { 0, 0 };
    rs_allocator al = guard_alloc_hook(&ga);
    rs_ctx *ctx = NULL;
    static float z[64 * 48];
    for (int k = 0; k < 64 * 48; k++) z[k] = (float)((k * 37 % 23) + (k / 64) * 2);
    rs_dem_frame fr = { 5, 0.05, 0, 0 };
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    int ok = rs_ctx_create(&al, NULL, &ctx) == RS_OK && rs_dem_create(ctx, 64, 48, z, &dem) == RS_OK &&
             rs_dem_set_frame(ctx, dem, &fr) == RS_OK && rs_roads_create(ctx, &roads) == RS_OK;
    /* a road of two legs (about 20 boxes of CHUNK_M, 32 m, along it: a
     * few more than the room's slack of 16, so that the overflow stays
     * within the allocator's guard) and a zigzag of 2.6 km after it (some
     * 80 boxes) */
    double xy[2][20];
    for (int k = 0; k < 10; k++) xy[0][2 * k] = k % 2 ? 300 : 10, xy[0][2 * k + 1] = 15 + 22 * k + 10;
    xy[1][0] = 10, xy[1][1] = 15, xy[1][2] = 300, xy[1][3] = 15, xy[1][4] = 40, xy[1][5] = 40;
    ok = ok && rs_roads_add(ctx, roads, NULL, 4, xy[1], 3) == RS_OK && rs_roads_add(ctx, roads, NULL, 4, xy[0], 10) == RS_OK;
    rs_splat_options o = edit_opts(1);
    rs_road_grid *g0 = NULL, *g1 = NULL, *gf = NULL;
    image a, b;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    ok = ok && rs_road_grid_build(ctx, dem, roads, &o, &g0) == RS_OK;
    /* road 0 moved 1 m east: its boxes made anew, road 1's copied after them */
    for (int k = 0; k < 3; k++) xy[1][2 * k] += 1;
    ok = ok && rs_roads_replace(ctx, roads, 0, NULL, 4, xy[1], 3) == RS_OK &&
         rs_road_grid_update(ctx, dem, roads, &o, g0, &g1) == RS_OK && rs_road_grid_build(ctx, dem, roads, &o, &gf) == RS_OK &&
         render(ctx, dem, g1, &o, &a) == 0 && render(ctx, dem, gf, &o, &b) == 0;
    CHECKF(ok, "chunk room: %s", ctx ? rs_ctx_message(ctx) : "no context");
    if (ok) {
        CHECK(same_image(&a, &b));
        CHECK_EQ_INT(rs__grid_track_net_check(ctx, g1, roads), 1);
    }
    image_free(&a);
    image_free(&b);
    rs_road_grid_free(ctx, g0);
    rs_road_grid_free(ctx, g1);
    rs_road_grid_free(ctx, gf);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    CHECKF(ga.broken == 0, "chunk room: %ld blocks written past their end", ga.broken);
    CHECK_EQ_INT(ga.live, 0);
}

/* A large ring of six records (a ring road, a roundabout split in OSM)
 * with a short road near its seam moved: the local build takes only the
 * ring's nearby records unless it takes the ring whole, and its lines join
 * at the seam only when the whole ring is there (a ring's seam draws as
 * any vertex since 6 December 2026: tests/test_lanes.c test_ring_seam).
 * The updated grid must draw as a fresh build. */
static void test_ring_edit(void)
{
    one_edit E;
    edit_begin(&E, 0, 0);
    static float z[81 * 81];
    rs_dem_frame fr = { 5, 0.01, 0, 0 };
    E.ok = E.ok && rs_dem_create(E.ctx, 81, 81, z, &E.dem) == RS_OK && rs_dem_set_frame(E.ctx, E.dem, &fr) == RS_OK &&
           rs_roads_create(E.ctx, &E.roads) == RS_OK;
    /* a 24-gon of 130 m round (200, 200), records of four segments from the seam at (330, 200) */
    for (int q = 0; q < 6 && E.ok; q++) {
        double xy[10];
        for (int k = 0; k < 5; k++) {
            double a = 2 * 3.14159265358979323846 * ((q * 4 + k) % 24) / 24;
            xy[2 * k] = 200 + 130 * cos(a), xy[2 * k + 1] = 200 + 130 * sin(a);
        }
        E.ok = rs_roads_add(E.ctx, E.roads, NULL, 7, xy, 5) == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, (size_t)q, "class", "secondary") == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, (size_t)q, "area", "rural") == RS_OK;
    }
    const double side[4] = { 340, 212, 372, 218 };
    E.ok = E.ok && rs_roads_add(E.ctx, E.roads, NULL, 5, side, 2) == RS_OK &&
           rs_roads_set_attr(E.ctx, E.roads, 6, "class", "residential") == RS_OK;
    edit_base(&E, 5); /* (1 m pixels) */
    E.ok = E.ok && move_road(E.ctx, E.roads, 6, 0, 3) == 0;
    edit_update(&E, "ring edit");
    if (E.ok) {
        check_rects("ring edit", E.g1, &E.a, &E.b, &E.c);
        /* the seam's outer edge line, (333.4, 200) m, is drawn by the
         * update's patch (the case the test is for), and the ring's far
         * side, 260 m away, lies outside the local build's reach */
        size_t in = 0;
        for (size_t k = 0; k < E.g1->npatch; k++) {
            const rs_pixel_rect *P = &E.g1->patch[k].rect;
            in += P->x0 <= 333 && P->x1 > 333 && P->y0 <= 200 && P->y1 > 200;
        }
        CHECKF(in == 1, "ring edit: the seam lies in %zu of %zu patch rectangles", in, E.g1->npatch);
    }
    edit_end(&E);
}

/* A road's level edited (layer= set, then bridge=no over a layer): the
 * primary's lines under the secondary, the secondary's over it and the
 * street ending under it (a T with it on one level, none with the bridge)
 * change, and so do the primary's two words under the secondary's deck
 * (left out there on another level); each update draws as a fresh build
 * and its rectangles hold every changed pixel (docs/network.md "Bridges
 * and layers"). */
static void test_level_edit(void)
{
    static const char *const step[3][2] = { { "layer", "1" }, { "layer", "-1" }, { "layer", "0" } };
    static float z[51 * 31];
    rs_dem_frame fr = { 2, 0.01, 0, 0 };
    const double p[4] = { 2, 30, 98, 30 }, b[4] = { 50, 2, 50, 58 }, u[4] = { 75, 45, 52, 45 };
    for (int k = 0; k < 3; k++) {
        one_edit E;
        edit_begin(&E, 0, 0);
        E.ok = E.ok && rs_dem_create(E.ctx, 51, 31, z, &E.dem) == RS_OK && rs_dem_set_frame(E.ctx, E.dem, &fr) == RS_OK &&
               rs_roads_create(E.ctx, &E.roads) == RS_OK && rs_roads_add(E.ctx, E.roads, NULL, 9, p, 2) == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, 0, "class", "primary") == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, 0, "area", "rural") == RS_OK &&
               rs_roads_add(E.ctx, E.roads, NULL, 7, b, 2) == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, 1, "class", "secondary") == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, 1, "area", "rural") == RS_OK &&
               rs_roads_add(E.ctx, E.roads, NULL, 6, u, 2) == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, 2, "class", "residential") == RS_OK;
        rs_mark mk1 = { "word_bus", 0, 48, -2.2, 6, 2, 0, 0 }, mk2 = { "word_slow", 0, 43, 2.2, 6, 2, 1, 0 };
        E.ok = E.ok && rs_roads_add_mark(E.ctx, E.roads, &mk1) == RS_OK && rs_roads_add_mark(E.ctx, E.roads, &mk2) == RS_OK;
        /* the base on the step before (none for the first) */
        for (int j = 0; j < k && E.ok; j++) E.ok = rs_roads_set_attr(E.ctx, E.roads, 1, step[j][0], step[j][1]) == RS_OK;
        edit_base(&E, 5);
        E.ok = E.ok && rs_roads_set_attr(E.ctx, E.roads, 1, step[k][0], step[k][1]) == RS_OK;
        char what[64];
        snprintf(what, sizeof what, "level edit %s=%s", step[k][0], step[k][1]);
        edit_update(&E, what);
        if (E.ok) {
            check_rects(what, E.g1, &E.a, &E.b, &E.c);
            CHECKF(!same_image(&E.a, &E.b), "%s: nothing changed", what);
        }
        edit_end(&E);
    }
}

/* A street moved beside a rural primary of one 308 m segment that thirty
 * streets cross: the primary's edge-line pieces are more than a cutset
 * holds and are halved along their length (docs/linesym.md "Junctions"),
 * in the whole build and in the update's local build, which sees only the
 * streets near the edit. The update draws as a fresh build. */
static void test_crossings_edit(void)
{
    static float z[156 * 31];
    rs_dem_frame fr = { 2, 0.01, 0, 0 };
    const int moved[3] = { 2, 15, 27 };
    for (int t = 0; t < 3; t++) {
        one_edit E;
        edit_begin(&E, 0, 0);
        const double p[4] = { 1, 30, 309, 30 };
        E.ok = E.ok && rs_dem_create(E.ctx, 156, 31, z, &E.dem) == RS_OK && rs_dem_set_frame(E.ctx, E.dem, &fr) == RS_OK &&
               rs_roads_create(E.ctx, &E.roads) == RS_OK && rs_roads_add(E.ctx, E.roads, NULL, 8, p, 2) == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, 0, "class", "primary") == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, 0, "area", "rural") == RS_OK;
        for (int k = 0; k < 30 && E.ok; k++) {
            const double q[4] = { 10 + 10 * k, 2, 10 + 10 * k, 58 };
            E.ok = rs_roads_add(E.ctx, E.roads, NULL, 6, q, 2) == RS_OK &&
                   rs_roads_set_attr(E.ctx, E.roads, (size_t)k + 1, "class", "secondary") == RS_OK;
        }
        edit_base(&E, 4);
        const double q[4] = { 12 + 10 * moved[t], 2, 12 + 10 * moved[t], 58 };
        E.ok = E.ok && rs_roads_replace(E.ctx, E.roads, (size_t)moved[t] + 1, NULL, 6, q, 2) == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, (size_t)moved[t] + 1, "class", "secondary") == RS_OK;
        char what[64];
        snprintf(what, sizeof what, "thirty crossings, street %d moved", moved[t]);
        edit_update(&E, what);
        if (E.ok) check_rects(what, E.g1, &E.a, &E.b, &E.c);
        edit_end(&E);
    }
}

/* A road given a second time (the same points, width and attributes):
 * its pieces have the same fingerprints, but its lines are painted twice,
 * so their partly covered pixels change; the dirty rectangles hold them
 * (a patch's candidates compared which pieces each grid has, not how many
 * times: fuzz/edits, 5 December 2026). */
static void test_duplicate_road(void)
{
    one_edit E;
    edit_fuzz_map(&E);
    /* (the fuzz input's roads: a service road, a secondary road given
     * twice, a 1 m road without a class) */
    const double A[6] = { 28.5, 21, 22.5, 21, 11.5, 30 }, B[6] = { 17.5, 9, 14.5, 9, -2.5, 3 }, C[4] = { -2.5, 0, 68.5, 9 };
    rs_roads *R = E.roads;
    E.ok = E.ok && rs_roads_add(E.ctx, R, NULL, 4, A, 3) == RS_OK && rs_roads_set_attr(E.ctx, R, 0, "class", "service") == RS_OK &&
           rs_roads_add(E.ctx, R, NULL, 8, B, 3) == RS_OK && rs_roads_set_attr(E.ctx, R, 1, "class", "secondary") == RS_OK &&
           rs_roads_add(E.ctx, R, NULL, 1, C, 2) == RS_OK && rs_roads_add(E.ctx, R, NULL, 8, B, 3) == RS_OK &&
           rs_roads_set_attr(E.ctx, R, 3, "class", "secondary") == RS_OK;
    edit_base(&E, 2);
    E.ok = E.ok && rs_roads_add(E.ctx, R, NULL, 1, C, 2) == RS_OK; /* (road 2 again) */
    edit_update(&E, "duplicate road");
    if (E.ok) {
        CHECK(rs_road_grid_patch_count(E.g1) == 1);
        check_rects("duplicate road", E.g1, &E.a, &E.b, &E.c);
    }
    edit_end(&E);
}

/* A removed road's T strip (fuzz/edits seed 2f282ac0): a 3 m record of
 * an 11 m road ended on another record's surface at a slant, and the T
 * strip of that end (its end segment run on to the clip line) reached
 * 30 m past the road's own boxes. Removing it must clear the strip's
 * pixels: the update takes the strip where it was from the grid's track. */
static void test_removed_tee_strip(void)
{
    one_edit E;
    edit_fuzz_map(&E);
    static const fuzz_road roads[4] = { { 11, 3, { 30.5, 22, 27.5, 21, 27.5, 21 } },
                                        { 11, 3, { 27.5, 59, 75.5, 57, 27.5, 59 } },
                                        { 11, 3, { 27.5, 21, 27.5, 21, 37.5, 22 } },
                                        { 1, 2, { 27.5, 11, -2.5, 0 } } };
    add_fuzz_roads(&E, roads, 4);
    edit_base(&E, 2);
    E.ok = E.ok && rs_roads_remove(E.ctx, E.roads, 0) == RS_OK;
    edit_update(&E, "removed T strip");
    if (E.ok) {
        long changed = 0;
        for (size_t p = 0; p < (size_t)E.a.w * E.a.h; p++) changed += E.a.wt[p] != E.c.wt[p];
        CHECKF(changed > 0, "removed T strip: the removal changes %ld pixels", changed);
        CHECK(rs_road_grid_patch_count(E.g1) >= 1);
        check_rects("removed T strip", E.g1, &E.a, &E.b, &E.c);
    }
    edit_end(&E);
}

/* A T that clips a record's far end strip and all (fuzz/edits seed
 * b0e8f047): a hairpin (4.5, 46) -> (63.5, 0) -> (21.5, 52) whose last
 * point is a T on a narrow straight road, its slanted strip running 30 m
 * along it to the south-west. A new road across its start (running on 39
 * m west of it, so that the start's strip stays on it: tee_ends.c
 * strip_on_street) makes that start a T whose line takes the hairpin's
 * whole second leg, strip included: the change area and the dirty
 * rectangles must reach the strip's far end, 25 m from the new T. */
static void test_far_strip_clipped(void)
{
    one_edit E;
    edit_fuzz_map(&E);
    static const fuzz_road roads[4] = { { 3.875, 3, { -12.6, 77.8, 11.75, 60.25, 75.75, 14.25 } },
                                        { 12, 3, { 63.5, 0, 29.5, 48, 63.5, 0 } },
                                        { 11, 3, { 4.5, 46, 63.5, 0, 21.5, 52 } },
                                        { 11, 3, { -34.5, 44, 16.5, 47, 63.5, 0 } } };
    add_fuzz_roads(&E, roads, 3);
    edit_base(&E, 2);
    add_fuzz_roads(&E, roads + 3, 1);
    edit_update(&E, "far strip clipped");
    if (E.ok) {
        /* (the strip's far pixels, over 20 m from the new road's T, change) */
        long far = 0;
        for (uint32_t y = 23; y < 29 && y < E.a.h; y++)
            for (uint32_t x = 0; x < 7 && x < E.a.w; x++) far += E.a.wt[(size_t)y * E.a.w + x] != E.c.wt[(size_t)y * E.a.w + x];
        CHECKF(far > 0, "far strip clipped: %ld pixels of the strip change", far);
        check_rects("far strip clipped", E.g1, &E.a, &E.b, &E.c);
    }
    edit_end(&E);
}

/* Twelve short residential streets along the fuzz map's far side: most of
 * the map is not near an edit at y = 100, so an update patches. */
/* E's update patched the grid, its dirty rectangles hold every changed
 * pixel, and the T lines and strips it keeps for the next update are a
 * build's. */
static void check_patched_tees(one_edit *E, const char *what)
{
    if (!E->ok) return;
    CHECK(rs_road_grid_patch_count(E->g1) >= 1);
    check_rects(what, E->g1, &E->a, &E->b, &E->c);
    CHECKF(rs__grid_track_net_check(E->ctx, E->g1, E->roads) == 1, "%s: the T lines kept are not a build's", what);
}

static void add_far_streets(one_edit *E)
{
    for (int k = 0; k < 12; k++) {
        const double xy[4] = { 10 + 25 * k, 200, 25 + 25 * k, 215 };
        size_t n = rs_roads_count(E->roads);
        E->ok = E->ok && rs_roads_add(E->ctx, E->roads, NULL, 4, xy, 2) == RS_OK &&
                rs_roads_set_attr(E->ctx, E->roads, n, "class", "residential") == RS_OK;
    }
}

/* A T that goes with no changed road at its node (fuzz/edits, 6 December
 * 2026): an 11 m primary ends at a slant inside a 4 m residential
 * street's surface, a free end that meets the street in a T, its flat
 * strip running 29 m along it (the primary's fill over the street's).
 * A new road starting at that end point makes the end no longer free: the
 * T and its strip go. The new road's node in the new network is not the
 * old node, where no changed road has a leg; the update takes the old
 * node's T ends too (grid_patch.c mark_across), so the strip's far end,
 * beyond the new road's own change area, is in the patch. */
static void test_tee_gone_at_node(void)
{
    one_edit E;
    edit_fuzz_map(&E);
    double street[60]; /* (points 10 m apart: a T changes how the segments beside it are drawn) */
    for (int k = 0; k < 30; k++) street[2 * k] = 10 + 10 * k, street[2 * k + 1] = 100;
    const double side[4] = { 91.9, 84.5, 150, 99.5 }, spur[4] = { 150, 99.5, 120, 140 };
    E.ok = E.ok && rs_roads_add(E.ctx, E.roads, NULL, 4, street, 30) == RS_OK &&
           rs_roads_set_attr(E.ctx, E.roads, 0, "class", "residential") == RS_OK &&
           rs_roads_add(E.ctx, E.roads, NULL, 11, side, 2) == RS_OK &&
           rs_roads_set_attr(E.ctx, E.roads, 1, "class", "primary") == RS_OK;
    add_far_streets(&E);
    edit_base(&E, 2);
    E.ok = E.ok && rs_roads_add(E.ctx, E.roads, NULL, 4, spur, 2) == RS_OK &&
           rs_roads_set_attr(E.ctx, E.roads, 14, "class", "residential") == RS_OK;
    edit_update(&E, "T gone at its node");
    if (E.ok) {
        /* (pixels more than 20 m east of the end change: the strip's) */
        long far = 0;
        for (uint32_t y = 0; y < E.a.h; y++)
            for (uint32_t x = (uint32_t)((150 + 20) / 2.5); x < E.a.w; x++) {
                size_t p = (size_t)y * E.a.w + x;
                far += memcmp(E.a.rgba + 4 * p, E.c.rgba + 4 * p, 4) != 0;
            }
        CHECKF(far > 0, "T gone at its node: %ld pixels beyond 20 m change", far);
        CHECK(rs_road_grid_patch_count(E.g1) >= 1);
        check_rects("T gone at its node", E.g1, &E.a, &E.b, &E.c);
    }
    edit_end(&E);
}

/* A T that goes where its street stops short (tee_ends.c strip_on_street):
 * an 11 m primary ends at a slant on a street of three records, its flat
 * strip running 29 m east along the first two. Removing the third record,
 * 20 m east of the T, leaves the street too short for the strip: the end
 * keeps its cap. No record at the T's node changed (the street's first
 * record keeps its neighbours and arc lengths; only its stroke's length
 * changed): the update finds the T gone there (grid_patch.c run_flips),
 * and the T lines it keeps for the next update are a build's. */
static void test_tee_street_shortened(void)
{
    one_edit E;
    edit_fuzz_map(&E);
    double a[32], c[10];
    for (int k = 0; k < 15; k++) a[2 * k] = 10 + 10 * k, a[2 * k + 1] = 100;
    a[30] = 150, a[31] = 100; /* (its last point repeated, as OSM exports have) */
    for (int k = 0; k < 5; k++) c[2 * k] = 160 + 10 * k, c[2 * k + 1] = 100;
    const double b[4] = { 150, 100, 160, 100 }, side[4] = { 81.9, 84.5, 140, 99.5 };
    E.ok = E.ok && rs_roads_add(E.ctx, E.roads, NULL, 4, a, 16) == RS_OK &&
           rs_roads_add(E.ctx, E.roads, NULL, 4, b, 2) == RS_OK && rs_roads_add(E.ctx, E.roads, NULL, 4, c, 5) == RS_OK &&
           rs_roads_add(E.ctx, E.roads, NULL, 11, side, 2) == RS_OK;
    for (size_t k = 0; k < 4; k++)
        E.ok = E.ok && rs_roads_set_attr(E.ctx, E.roads, k, "class", k == 3 ? "primary" : "residential") == RS_OK;
    add_far_streets(&E);
    edit_base(&E, 2);
    E.ok = E.ok && rs_roads_remove(E.ctx, E.roads, 2) == RS_OK;
    edit_update(&E, "street shortened past a T");
    check_patched_tees(&E, "street shortened past a T");
    edit_end(&E);
}

/* A T inside a street's surface whose street gets a record joined to its
 * stroke (fuzz/edits, 6 December 2026): an 11 m road starts 1 m before
 * the end of an 11 m hairpin, inside its surface, a T end with the
 * hairpin's two legs at its node. A road added at the hairpin's end point
 * joins its stroke, and the start is no T any more: the new network holds
 * it alone, where no road passes, so only the old node, where the
 * hairpin passed, shows that the street's run changed there. */
static void test_tee_surface_street_joined(void)
{
    static const fuzz_road roads[2] = { { 11, 3, { 63.5, 0, 68.5, 0, 63.5, 0 } },
                                        { 11, 3, { 62.5, 0, 59.5, 49, -2.5, 46 } } };
    const double xy[6] = { 63.5, 0, 63.5, 0, 74.5, 50 };
    one_edit E;
    edit_fuzz_map(&E);
    add_fuzz_roads(&E, roads, 2);
    add_far_streets(&E);
    edit_base(&E, 2);
    E.ok = E.ok && rs_roads_add(E.ctx, E.roads, NULL, 11, xy, 3) == RS_OK;
    edit_update(&E, "a street's stroke joined past a T inside it");
    check_patched_tees(&E, "a street's stroke joined past a T inside it");
    edit_end(&E);
}

/* Fills where roads of equal priority overlap (fuzz/edits seed 224dbe0b):
 * while every road ranks alike a pixel takes the nearest centre line;
 * once the priorities differ anywhere on the map, a surface that holds
 * the pixel wins over a nearer centre line (issue 27). A road of a higher
 * class added far away flips that for the whole map, so the update builds
 * whole; and a patch among roads that rank alike, on a map where they do
 * not, looks its fills up as the whole map does. */
static void test_ranked_fills(void)
{
    static const char sty[] = "style s\nfill #a04030\nend\n";
    static const fuzz_road roads[3] = { { 6, 2, { 5, 5, 70, 50 } },
                                        { 5, 3, { -2.5, 52, 9.5, 2, 9.5, 2 } },
                                        { 4, 3, { 9.5, 10, 21.5, 1, -2.5, 0 } } };
    const double far[4] = { 250, 200, 262, 205 };
    for (int flip = 0; flip < 2; flip++) {
        one_edit E;
        rs_ctx *sc;
        rs_styles *styles = edit_fuzz_map_styled(&E, sty, sizeof sty - 1, &sc);
        add_fuzz_roads(&E, roads, 3);
        E.ok = E.ok && rs_roads_set_attr(E.ctx, E.roads, 0, "style", "s") == RS_OK;
        if (!flip) /* (the map ranks its roads: a secondary road far away) */
            E.ok = E.ok && rs_roads_add(E.ctx, E.roads, NULL, 8, far, 2) == RS_OK &&
                   rs_roads_set_attr(E.ctx, E.roads, 3, "class", "secondary") == RS_OK;
        edit_base_styled(&E, 3, styles);
        if (flip) /* the secondary road added: the whole map ranks */
            E.ok = E.ok && rs_roads_add(E.ctx, E.roads, NULL, 8, far, 2) == RS_OK &&
                   rs_roads_set_attr(E.ctx, E.roads, 3, "class", "secondary") == RS_OK;
        else { /* road 2 moved a metre: a patch among roads that rank alike */
            double q[6];
            for (int k = 0; k < 6; k++) q[k] = roads[2].xy[k] + (k % 2 ? 0 : 1);
            E.ok = E.ok && rs_roads_replace(E.ctx, E.roads, 2, NULL, 4, q, 3) == RS_OK;
        }
        edit_update(&E, flip ? "ranked fills: a class added" : "ranked fills: a patch");
        if (E.ok) {
            if (!flip) CHECK(rs_road_grid_patch_count(E.g1) == 1);
            check_rects(flip ? "ranked fills: a class added" : "ranked fills: a patch", E.g1, &E.a, &E.b, &E.c);
        }
        edit_end_styled(&E, sc, styles);
    }
}

/* A record that only moved along its stroke (docs/embedding.md "Records
 * moved along their stroke"): a residential street of five 50 m records
 * on the fuzz map, a service road giving way on its last record. Moving
 * the second record up splits the street: the last two records keep
 * their neighbours, only their arc lengths change, and they draw no
 * lines, so the patch stays near the split and the far records' give-way
 * line is not rebuilt; the bytes are a fresh build's. With lines on the
 * street (dashes laid along it) the far records are changed whole. */
static void test_moved_along_stroke(void)
{
    static const char sty[] = "style dashed\nfill #505050\nline 0 0.15 #ffffff dash 3 3\nend\n";
    for (int lines = 0; lines < 2; lines++) {
        one_edit E;
        rs_ctx *sc;
        rs_styles *styles = edit_fuzz_map_styled(&E, sty, sizeof sty - 1, &sc);
        for (int k = 0; k < 5; k++) {
            const double xy[4] = { 20 + 50 * k, 100, 70 + 50 * k, 100 };
            E.ok = E.ok && rs_roads_add(E.ctx, E.roads, NULL, 6, xy, 2) == RS_OK &&
                   rs_roads_set_attr(E.ctx, E.roads, (size_t)k, "class", "residential") == RS_OK &&
                   (!lines || rs_roads_set_attr(E.ctx, E.roads, (size_t)k, "style", "dashed") == RS_OK);
        }
        const double side[4] = { 245, 130, 245, 100 };
        E.ok = E.ok && rs_roads_add(E.ctx, E.roads, NULL, 4, side, 2) == RS_OK &&
               rs_roads_set_attr(E.ctx, E.roads, 5, "class", "service") == RS_OK;
        edit_base_styled(&E, 2, styles);
        const double up[4] = { 70, 115, 120, 115 };
        E.ok = E.ok && rs_roads_replace(E.ctx, E.roads, 1, NULL, 6, up, 2) == RS_OK;
        edit_update(&E, lines ? "moved along its stroke, lines" : "moved along its stroke");
        if (E.ok) {
            /* the patch's reach along the street (2.5 m pixels): the third
             * record, a neighbour at a changed node, is drawn again all
             * along (its capsule's ends changed); the last one's end
             * (x 270 m) only with lines (else the whole build) */
            uint32_t x1 = 0;
            for (size_t k = 0; k < E.g1->npatch; k++) x1 = E.g1->patch[k].rect.x1 > x1 ? E.g1->patch[k].rect.x1 : x1;
            if (lines) CHECKF(!E.g1->npatch || x1 >= 270 / 2.5, "moved along its stroke, lines: the patch reaches x = %u px", x1);
            else CHECKF(E.g1->npatch && x1 < 270 / 2.5, "moved along its stroke: %zu patches reaching x = %u px",
                        E.g1->npatch, x1);
            check_rects(lines ? "moved along its stroke, lines" : "moved along its stroke", E.g1, &E.a, &E.b, &E.c);
        }
        edit_end_styled(&E, sc, styles);
    }
}

int main(void)
{
    test_shared_free();
    test_subset_build();
    test_remove();
    test_road_prints();
    test_replace();
    test_point_attr();
    test_styles_replace();
    test_style_edit_grid();
    test_update_errors();
    test_alloc_failures();
    test_update_cancel();
    test_random_edits();
    test_drag();
    test_roads_copy();
    test_long_chain();
    test_two_places();
    test_long_road();
    test_chunk_room();
    test_ring_edit();
    test_level_edit();
    test_crossings_edit();
    test_duplicate_road();
    test_removed_tee_strip();
    test_far_strip_clipped();
    test_tee_gone_at_node();
    test_tee_street_shortened();
    test_tee_surface_street_joined();
    test_ranked_fills();
    test_moved_along_stroke();
    return th_finish("test_edits");
}
