/* Road edits with dirty rectangles (issue 30 target 3): on the 10k-road
 * city (sc_city 400 x 350 DEM of 5 m cells, 10,000 roads, classes by width:
 * casings, lines, automatic markings; T = 4, 1596 x 1396 pixels), edits of
 * one road (move it 15 m, add one, remove one, change its class):
 * rs_road_grid_update's time against a full rs_road_grid_build of the
 * edited roads (this thread's CPU time, medians of RUNS, the two
 * interleaved in the same run), and the dirty rectangles' area against the
 * pixels that really change (whole images before and after, colour or
 * weight; every changed pixel must lie in a rectangle).
 * Usage: edits OUTDIR   (writes OUTDIR/edits.md and .csv) */
#include "roadsplat.h"
#include "scene_splat.h"
#include "scenes.h"
#include "timing.h"
#include "roadgrid.h"
#include "grid_edit.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RUNS 3
#define PER_KIND 6
#define ROADS 10000
#define DRAG_STEPS 24
#define LONG 72     /* edits of the long chain */
#define FLAT_AT 24  /* patches at which a worker starts a whole build */
#define FLAT_JOIN 4 /* edits later the chain is rebased onto it */
#define SPREAD_STEP 50 /* every 50th road moved alone: the spread over roads */

enum { MOVE, ADD, REMOVE, RECLASS, KINDS };
static const char *const kind_name[KINDS] = { "move 15 m", "add", "remove", "reclass" };

static int apply(rs_ctx *ctx, rs_roads *roads, int kind, sc_rng *rng, double W, double H)
{
    size_t n = rs_roads_count(roads), i = (size_t)(sc_rng_unit(rng) * (double)n);
    static const char *const cls[] = { "primary", "secondary", "residential", "service" };
    if (kind == ADD) {
        double x = sc_rng_range(rng, 0.2 * W, 0.8 * W), y = sc_rng_range(rng, 0.2 * H, 0.8 * H);
        double a = sc_rng_range(rng, 0, 6.283185307179586), xy[6];
        for (int k = 0; k < 3; k++) xy[2 * k] = x + 40 * k * cos(a + 0.2 * k), xy[2 * k + 1] = y + 40 * k * sin(a + 0.2 * k);
        return rs_roads_add(ctx, roads, "new", 8, xy, 3) || rs_roads_set_attr(ctx, roads, n, "class", "residential");
    }
    if (kind == REMOVE) return rs_roads_remove(ctx, roads, i);
    if (kind == RECLASS) {
        const char *c = rs_roads_get_attr(roads, i, "class"), *to;
        do to = cls[(size_t)(sc_rng_unit(rng) * 4)];
        while (c && strcmp(c, to) == 0);
        return rs_roads_set_attr(ctx, roads, i, "class", to);
    }
    const double *p;
    size_t np;
    double w;
    rs_roads_get(roads, i, NULL, &w, &p, &np);
    double *q = malloc(2 * np * sizeof *q), a = sc_rng_range(rng, 0, 6.283185307179586);
    if (!q) return -1;
    for (size_t k = 0; k < np; k++) q[2 * k] = p[2 * k] + 15 * cos(a), q[2 * k + 1] = p[2 * k + 1] + 15 * sin(a);
    int r = rs_roads_replace(ctx, roads, i, NULL, w, q, np);
    free(q);
    return r;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The first road of median length among the first half by index: a
 * typical road to drag */
static size_t median_road(const rs_roads *roads)
{
    size_t n = rs_roads_count(roads), m = n / 2 ? n / 2 : n;
    double *len = malloc((m ? m : 1) * sizeof *len);
    if (!len) return 0;
    for (size_t i = 0; i < m; i++) {
        const double *p;
        size_t np;
        rs_roads_get(roads, i, NULL, NULL, &p, &np);
        len[i] = 0;
        for (size_t k = 0; k + 1 < np; k++) len[i] += hypot(p[2 * k + 2] - p[2 * k], p[2 * k + 3] - p[2 * k + 1]);
    }
    double *sorted = malloc((m ? m : 1) * sizeof *sorted);
    size_t pick = 0;
    if (sorted) {
        memcpy(sorted, len, m * sizeof *len);
        qsort(sorted, m, sizeof *sorted, cmp_double);
        while (pick + 1 < m && len[pick] != sorted[m / 2]) pick++;
    }
    free(sorted);
    free(len);
    return pick;
}

int main(int argc, char **argv)
{
    if (argc != 2) { fprintf(stderr, "usage: edits OUTDIR\n"); return 2; }
    rs_ctx *ctx, *cctx; /* cctx: the comparison off (rs_limits.max_dirty_compare 1): the pieces' candidates */
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_dirty_compare = 1;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    if (rs_ctx_create(NULL, &lim, &cctx)) return 1;
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    int bad = ss_city_of(ctx, 400, 350, ROADS, 1, 1, &sc, &dem, &roads) != 0;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    o.grid.edits = 1;
    rs_road_grid *g0 = NULL;
    ss_image a, b;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    if (!bad) bad = rs_road_grid_build(ctx, dem, roads, &o, &g0) || ss_grid_image(ctx, dem, g0, &o, &a);
    double upd[KINDS][PER_KIND * RUNS], full[KINDS][PER_KIND * RUNS], cand_ms[KINDS][PER_KIND], dirty[KINDS], changed[KINDS],
        cand[KINDS];
    long uncovered = 0, mismatch = 0; /* mismatch: pixels where the updated grid and a fresh build differ */
    size_t rects[KINDS];
    memset(dirty, 0, sizeof dirty);
    memset(changed, 0, sizeof changed);
    memset(cand, 0, sizeof cand);
    memset(rects, 0, sizeof rects);
    sc_rng rng;
    sc_rng_seed(&rng, 2026);
    double W = sc_extent_x(&sc), H = sc_extent_y(&sc);
    uint8_t *mask = NULL;
    for (int e = 0; !bad && e < KINDS * PER_KIND; e++) {
        int kind = e % KINDS, j = e / KINDS;
        if ((bad = apply(ctx, roads, kind, &rng, W, H) != 0)) break;
        rs_road_grid *g1 = NULL, *gf = NULL;
        for (int k = 0; k < RUNS && !bad; k++) {
            rs_road_grid *u = NULL, *f = NULL;
            double t0 = tm_thread_cpu_ms();
            bad = rs_road_grid_update(ctx, dem, roads, &o, g0, &u) != RS_OK;
            double t1 = tm_thread_cpu_ms();
            bad = bad || rs_road_grid_build(ctx, dem, roads, &o, &f) != RS_OK;
            double t2 = tm_thread_cpu_ms();
            upd[kind][j * RUNS + k] = t1 - t0;
            if (getenv("PERDIT")) fprintf(stderr, "E %d %d %d %.2f %zu\n", e, kind, k, t1 - t0, u->npatch);
            full[kind][j * RUNS + k] = t2 - t1;
            if (!gf) gf = f;
            else rs_road_grid_free(ctx, f);
            if (!g1) g1 = u;
            else rs_road_grid_free(ctx, u);
        }
        /* the candidates alone, once (and its time: the update less the comparison) */
        rs_road_grid *gc = NULL;
        double c0 = tm_thread_cpu_ms();
        bad = bad || rs_road_grid_update(cctx, dem, roads, &o, g0, &gc) != RS_OK;
        cand_ms[kind][j] = tm_thread_cpu_ms() - c0;
        size_t nc = bad ? 0 : rs_road_grid_dirty(gc, NULL, 0);
        rs_pixel_rect *CR = malloc((nc ? nc : 1) * sizeof *CR);
        if (!CR) bad = 1;
        if (!bad) rs_road_grid_dirty(gc, CR, nc);
        for (size_t k = 0; !bad && k < nc; k++) cand[kind] += (double)(CR[k].x1 - CR[k].x0) * (CR[k].y1 - CR[k].y0);
        free(CR);
        rs_road_grid_free(cctx, gc);
        ss_image_free(&b);
        /* the updated grid's image (b) against a fresh build's (c): the
         * same bytes; the change is measured on the fresh one */
        ss_image c;
        memset(&c, 0, sizeof c);
        if (bad || ss_grid_image(ctx, dem, g1, &o, &b) || ss_grid_image(ctx, dem, gf, &o, &c)) {
            bad = 1;
            rs_road_grid_free(ctx, g1);
            rs_road_grid_free(ctx, gf);
            ss_image_free(&c);
            break;
        }
        rs_road_grid_free(ctx, gf);
        for (size_t p = 0; p < (size_t)b.w * b.h; p++)
            mismatch += memcmp(b.rgba + 4 * p, c.rgba + 4 * p, 4) != 0 || b.wt[p] != c.wt[p];
        ss_image_free(&b);
        b = c;
        size_t np = (size_t)a.w * a.h, nr = rs_road_grid_dirty(g1, NULL, 0);
        rs_pixel_rect *R = malloc((nr ? nr : 1) * sizeof *R);
        if (!mask) mask = malloc(np);
        if (!R || !mask) {
            bad = 1;
            free(R);
            rs_road_grid_free(ctx, g1);
            break;
        }
        memset(mask, 0, np);
        rs_road_grid_dirty(g1, R, nr);
        for (size_t k = 0; k < nr; k++) {
            for (uint32_t y = R[k].y0; y < R[k].y1; y++) memset(mask + (size_t)y * a.w + R[k].x0, 1, R[k].x1 - R[k].x0);
            dirty[kind] += (double)(R[k].x1 - R[k].x0) * (R[k].y1 - R[k].y0);
        }
        rects[kind] += nr;
        for (size_t p = 0; p < np; p++)
            if (memcmp(a.rgba + 4 * p, b.rgba + 4 * p, 4) || a.wt[p] != b.wt[p]) {
                changed[kind]++;
                if (!mask[p]) uncovered++;
            }
        free(R);
        rs_road_grid_free(ctx, g0);
        g0 = g1;
        ss_image t = a;
        a = b;
        b = t;
    }
    /* what building the pieces adds to a grid build with opts.grid.edits:
     * again on a whole grid of the last roads, with the network it reads */
    double piece_ms[RUNS], piece_med = 0;
    rs_network *net = NULL;
    rs_road_grid *gw = NULL;
    if (!bad) bad = rs_network_build(ctx, roads, NULL, &net) != RS_OK || rs_road_grid_build(ctx, dem, roads, &o, &gw);
    for (int k = 0; !bad && k < RUNS; k++) {
        rs__grid_edit *keep = gw->edit;
        gw->edit = NULL;
        double t0 = tm_thread_cpu_ms();
        bad = rs__grid_edit_build(ctx, dem, roads, &o, net, NULL, NULL, gw) != RS_OK;
        piece_ms[k] = tm_thread_cpu_ms() - t0;
        rs__grid_edit_free(ctx, gw->edit);
        gw->edit = keep;
    }
    rs_road_grid_stats wst;
    memset(&wst, 0, sizeof wst);
    if (gw) rs_road_grid_get_stats(gw, &wst);
    size_t wpieces = gw && gw->edit ? gw->edit->n : 0;
    double wpiece_mb = gw && gw->edit ? gw->edit->bytes / 1e6 : 0;
    rs_road_grid_free(ctx, gw);
    rs_network_free(ctx, net);
    if (!bad) piece_med = tm_median(piece_ms, RUNS);
    /* a road dragged: DRAG_STEPS moves of one road by about a metre,
     * chained from a whole build, each timed RUNS times against a full
     * build; a patch that covers the last one's rectangle replaces it */
    double dupd[DRAG_STEPS * RUNS], dfull[DRAG_STEPS * RUNS];
    size_t dmost = 0;
    long dmismatch = 0;
    rs_road_grid *d0 = NULL;
    size_t pick = median_road(roads);
    if (!bad) bad = rs_road_grid_build(ctx, dem, roads, &o, &d0) != RS_OK;
    for (int step = 0; !bad && step < DRAG_STEPS; step++) {
        const double *p;
        size_t np;
        double w;
        rs_roads_get(roads, pick, NULL, &w, &p, &np);
        double *q = malloc(2 * np * sizeof *q);
        if (!q) { bad = 1; break; }
        for (size_t k = 0; k < np; k++) q[2 * k] = p[2 * k] + 1.0, q[2 * k + 1] = p[2 * k + 1] + 0.4;
        bad = rs_roads_replace(ctx, roads, pick, NULL, w, q, np) != RS_OK;
        free(q);
        rs_road_grid *d1 = NULL, *df = NULL;
        for (int k = 0; k < RUNS && !bad; k++) {
            rs_road_grid *u = NULL, *f = NULL;
            double t0 = tm_thread_cpu_ms();
            bad = rs_road_grid_update(ctx, dem, roads, &o, d0, &u) != RS_OK;
            double t1 = tm_thread_cpu_ms();
            bad = bad || rs_road_grid_build(ctx, dem, roads, &o, &f) != RS_OK;
            double t2 = tm_thread_cpu_ms();
            dupd[step * RUNS + k] = t1 - t0, dfull[step * RUNS + k] = t2 - t1;
            if (!df) df = f;
            else rs_road_grid_free(ctx, f);
            if (!d1) d1 = u;
            else rs_road_grid_free(ctx, u);
        }
        ss_image x, y;
        memset(&x, 0, sizeof x);
        memset(&y, 0, sizeof y);
        if (!bad && (ss_grid_image(ctx, dem, d1, &o, &x) || ss_grid_image(ctx, dem, df, &o, &y))) bad = 1;
        for (size_t px = 0; !bad && px < (size_t)x.w * x.h; px++)
            dmismatch += memcmp(x.rgba + 4 * px, y.rgba + 4 * px, 4) != 0 || x.wt[px] != y.wt[px];
        ss_image_free(&x);
        ss_image_free(&y);
        if (d1 && rs_road_grid_patch_count(d1) > dmost) dmost = rs_road_grid_patch_count(d1);
        rs_road_grid_free(ctx, df);
        rs_road_grid_free(ctx, d0);
        d0 = d1;
    }
    rs_road_grid_free(ctx, d0);
    double dsum = 0, dfsum = 0, dmax = 0;
    for (int i = 0; i < DRAG_STEPS * RUNS; i++) dsum += dupd[i], dfsum += dfull[i], dmax = dupd[i] > dmax ? dupd[i] : dmax;
    double dmed = bad ? 0 : tm_median(dupd, DRAG_STEPS * RUNS), dfmed = bad ? 1 : tm_median(dfull, DRAG_STEPS * RUNS);
    mismatch += dmismatch;
    /* a long chain with its whole builds on a worker (docs/embedding.md
     * "Long chains"): LONG edits of the four kinds in turn, chained, with
     * rs_limits.max_patches 64; at FLAT_AT patches the roads are copied
     * and a worker builds them whole, FLAT_JOIN edits later the chain is
     * rebased onto that grid. The caller's thread: each edit's calls
     * (update, and the copy or the rebase when they fall on it); the
     * worker's builds apart */
    double lmain[LONG], lwork = 0, lcopy = 0, lrebase = 0;
    size_t lmost = 0;
    int nflat = 0;
    double lbytes = 0, lsplat_p = 0, lsplat_w = 0;
    size_t lpatches = 0;
    long lmismatch = 0;
    {
        rs_limits ll;
        memset(&ll, 0, sizeof ll);
        ll.max_patches = 64;
        rs_ctx *lc = NULL;
        rs_road_grid *c0 = NULL, *since = NULL;
        rs_roads *snap = NULL;
        ss_build_job wk;
        memset(&wk, 0, sizeof wk);
        pthread_t th;
        int running = 0, started_at = 0;
        if (!bad) bad = rs_ctx_create(NULL, &ll, &lc) != RS_OK || rs_road_grid_build(lc, dem, roads, &o, &c0) != RS_OK;
        for (int e = 0; !bad && e < LONG; e++) {
            double t0 = tm_thread_cpu_ms(), extra = 0;
            if (running && e - started_at >= FLAT_JOIN) {
                pthread_join(th, NULL);
                running = 0;
                rs_road_grid *rb = NULL;
                double r0 = tm_thread_cpu_ms();
                bad = !wk.ok || rs_road_grid_rebase(lc, c0, since, wk.g, &rb) != RS_OK;
                lrebase += tm_thread_cpu_ms() - r0;
                lwork += wk.ms;
                rs_road_grid_free(lc, wk.g);
                rs_road_grid_free(lc, since);
                rs_roads_free(lc, snap);
                wk.g = NULL, since = NULL, snap = NULL;
                if (bad) break;
                rs_road_grid_free(lc, c0);
                c0 = rb;
                nflat++;
            }
            extra = tm_thread_cpu_ms() - t0;
            if ((bad = apply(lc, roads, e % KINDS, &rng, W, H) != 0)) break;
            rs_road_grid *c1 = NULL;
            double u0 = tm_thread_cpu_ms();
            bad = rs_road_grid_update(lc, dem, roads, &o, c0, &c1) != RS_OK;
            double u1 = tm_thread_cpu_ms();
            if (bad) break;
            if (rs_road_grid_patch_count(c1) > lmost) lmost = rs_road_grid_patch_count(c1);
            rs_road_grid_stats cs;
            rs_road_grid_get_stats(c1, &cs);
            if (cs.bytes / 1e6 > lbytes) lbytes = cs.bytes / 1e6;
            if (!running && rs_road_grid_patch_count(c1) >= FLAT_AT) {
                double k0 = tm_thread_cpu_ms();
                bad = rs_roads_copy(lc, roads, &snap) != RS_OK;
                lcopy += tm_thread_cpu_ms() - k0;
                extra += tm_thread_cpu_ms() - k0;
                since = c1; /* (kept until the rebase) */
                memset(&wk, 0, sizeof wk);
                wk.dem = dem, wk.roads = snap, wk.o = &o;
                if (!bad) bad = pthread_create(&th, NULL, ss_build_run, &wk) != 0;
                running = !bad, started_at = e;
            }
            lmain[e] = u1 - u0 + extra;
            if (c0 != since) rs_road_grid_free(lc, c0);
            c0 = c1;
        }
        if (running) {
            pthread_join(th, NULL);
            rs_road_grid_free(lc, wk.g);
        }
        /* the last grid against a fresh build */
        rs_road_grid *lf = NULL;
        ss_image x, y;
        memset(&x, 0, sizeof x);
        memset(&y, 0, sizeof y);
        if (!bad && (rs_road_grid_build(lc, dem, roads, &o, &lf) || ss_grid_image(lc, dem, c0, &o, &x) ||
                     ss_grid_image(lc, dem, lf, &o, &y)))
            bad = 1;
        for (size_t px = 0; !bad && px < (size_t)x.w * x.h; px++)
            lmismatch += memcmp(x.rgba + 4 * px, y.rgba + 4 * px, 4) != 0 || x.wt[px] != y.wt[px];
        /* what the patches cost a reader: the whole image's splat (splatter
         * and window) of the last grid and of the whole build, fastest of 3 */
        lpatches = c0 ? rs_road_grid_patch_count(c0) : 0;
        for (int k = 0; !bad && k < 3; k++) {
            ss_image_free(&x);
            ss_image_free(&y);
            double s0 = tm_thread_cpu_ms();
            bad = ss_grid_image(lc, dem, c0, &o, &x) != RS_OK;
            double s1 = tm_thread_cpu_ms();
            bad = bad || ss_grid_image(lc, dem, lf, &o, &y) != RS_OK;
            double s2 = tm_thread_cpu_ms();
            if (!k || s1 - s0 < lsplat_p) lsplat_p = s1 - s0;
            if (!k || s2 - s1 < lsplat_w) lsplat_w = s2 - s1;
        }
        ss_image_free(&x);
        ss_image_free(&y);
        rs_road_grid_free(lc, lf);
        if (since != c0) rs_road_grid_free(lc, since);
        rs_road_grid_free(lc, c0);
        rs_roads_free(lc, snap);
        rs_ctx_free(lc);
    }
    mismatch += lmismatch;
    /* the spread over roads: every SPREAD_STEP-th road moved 15 m alone
     * from a whole grid of the last roads (and put back), the faster of
     * two updates against the median full build above; long roads and
     * records of long strokes make the tail */
    size_t nspread = 0, swhole = 0, sover = 0;
    double *spread = NULL, ssum = 0;
    {
        rs_road_grid *gs = NULL;
        size_t n = rs_roads_count(roads);
        spread = malloc((n / SPREAD_STEP + 1) * sizeof *spread);
        if (!bad) bad = !spread || rs_road_grid_build(ctx, dem, roads, &o, &gs) != RS_OK;
        double fs[KINDS * PER_KIND * RUNS];
        for (int k = 0; k < KINDS; k++)
            for (int i = 0; i < PER_KIND * RUNS; i++) fs[k * PER_KIND * RUNS + i] = full[k][i];
        double fmed = bad ? 1 : tm_median(fs, KINDS * PER_KIND * RUNS);
        for (size_t i = 0; !bad && i < n; i += SPREAD_STEP) {
            const double *p;
            size_t np;
            double w;
            rs_roads_get(roads, i, NULL, &w, &p, &np);
            double *keep = malloc(2 * np * sizeof *keep), *q = malloc(2 * np * sizeof *q);
            if (!keep || !q) {
                free(keep);
                free(q);
                bad = 1;
                break;
            }
            memcpy(keep, p, 2 * np * sizeof *keep);
            for (size_t k = 0; k < np; k++) q[2 * k] = keep[2 * k] + 15 * 0.6, q[2 * k + 1] = keep[2 * k + 1] + 15 * 0.8;
            bad = rs_roads_replace(ctx, roads, i, NULL, w, q, np) != RS_OK;
            double fastest = INFINITY;
            for (int k = 0; !bad && k < 2; k++) {
                rs_road_grid *u = NULL;
                double t0 = tm_thread_cpu_ms();
                bad = rs_road_grid_update(ctx, dem, roads, &o, gs, &u) != RS_OK;
                double t = tm_thread_cpu_ms() - t0;
                fastest = t < fastest ? t : fastest;
                if (!bad && k == 0 && rs_road_grid_patch_count(u) == 0) swhole++;
                if (!bad && k == 1 && getenv("PERDIT")) { /* (what the tail's updates drew) */
                    unsigned long long area = 0;
                    size_t local = u->npatch ? u->patch[u->npatch - 1].n : 0;
                    for (size_t pk = 0; pk < u->npatch; pk++)
                        area += (unsigned long long)(u->patch[pk].rect.x1 - u->patch[pk].rect.x0) *
                                (u->patch[pk].rect.y1 - u->patch[pk].rect.y0);
                    fprintf(stderr, "S %zu %.3f np %zu rects %zu area %llu local %zu\n", i, fastest / fmed, np, u->npatch,
                            area, local);
                }
                rs_road_grid_free(ctx, u);
            }
            bad = bad || rs_roads_replace(ctx, roads, i, NULL, w, keep, np) != RS_OK;
            free(keep);
            free(q);
            if (bad) break;
            spread[nspread] = fastest / fmed;
            ssum += spread[nspread];
            sover += spread[nspread] > 0.05;
            nspread++;
        }
        rs_road_grid_free(ctx, gs);
    }
    if (bad) fprintf(stderr, "edits: %s\n", rs_ctx_message(ctx));
    FILE *md = NULL, *csv = NULL;
    if (!bad && !(bad = tm_open_section(argv[1], "edits", &md, &csv))) {
        rs_road_grid_stats st;
        rs_road_grid_get_stats(g0, &st);
        fprintf(md, "## Road edits with dirty rectangles (issue 30)\n\n"
                    "tests/bench/edits.c: the city with %zu roads (400 x 350 DEM of 5 m cells, classes by width:\n"
                    "casings, lines, automatic markings), T = 4 (1596 x 1396 pixels); %d edits of each kind, each\n"
                    "timed %d times; the edits chained (each update's grid the next one's old grid); this\n"
                    "thread's CPU time, medians, `rs_road_grid_update` and a full `rs_road_grid_build` of the\n"
                    "edited roads interleaved. Dirty: the rectangles' pixels; changed: pixels whose colour or\n"
                    "weight differ between the whole images before and after, each from a fresh build (%ld\n"
                    "changed pixels outside the rectangles; %ld pixels where an updated grid's image differs\n"
                    "from the fresh build's). A whole grid of the last roads holds %zu edit pieces, %.2f of its %.2f MB; making\n"
                    "them takes %.1f ms of a grid build that keeps them (opts.grid.edits; a plain build makes\n"
                    "none). The last updated grid holds %zu patches in %.2f MB with its base. Candidates: the\n"
                    "pixels of the pieces that differ (the rectangles of an update with\n"
                    "rs_limits.max_dirty_compare = 1, once per edit, beside its CPU time).\n\n"
                    "| edit | update ms | full build ms | update / build | candidates only ms | dirty px | changed px | dirty / changed | candidate px | candidates / changed | rectangles |\n"
                    "|---|---|---|---|---|---|---|---|---|---|---|\n",
                rs_roads_count(roads), PER_KIND, RUNS, uncovered, mismatch, wpieces, wpiece_mb, wst.bytes / 1e6, piece_med,
                rs_road_grid_patch_count(g0), st.bytes / 1e6);
        fprintf(csv, "edit,update_ms,build_ms,dirty_px,changed_px,rects\n");
        double worst_area = 0, worst_cost = 0;
        for (int k = 0; k < KINDS; k++) {
            double u = tm_median(upd[k], PER_KIND * RUNS), f = tm_median(full[k], PER_KIND * RUNS);
            double cm = tm_median(cand_ms[k], PER_KIND);
            double ra = changed[k] > 0 ? dirty[k] / changed[k] : (dirty[k] > 0 ? INFINITY : 1);
            worst_area = ra > worst_area ? ra : worst_area;
            worst_cost = u / f > worst_cost ? u / f : worst_cost;
            fprintf(md, "| %s | %.1f | %.1f | %.3f | %.1f | %.0f | %.0f | %.2f | %.0f | %.2f | %zu |\n", kind_name[k], u, f,
                    u / f, cm, dirty[k], changed[k], changed[k] > 0 ? dirty[k] / changed[k] : 0, cand[k],
                    changed[k] > 0 ? cand[k] / changed[k] : 0, rects[k]);
            fprintf(csv, "%s,%.3f,%.3f,%.0f,%.0f,%zu\n", kind_name[k], u, f, dirty[k], changed[k], rects[k]);
            printf("edits: %-10s update %.1f ms, build %.1f ms (%.3f); dirty / changed %.2f (%.0f / %.0f), candidates "
                   "%.2f\n",
                   kind_name[k], u, f, u / f, changed[k] > 0 ? dirty[k] / changed[k] : 0, dirty[k], changed[k],
                   changed[k] > 0 ? cand[k] / changed[k] : 0);
        }
        /* every update timed, flattening ones included (a whole build once the grid holds 16 patches) */
        double sum = 0, most = 0, fsum = 0;
        for (int k = 0; k < KINDS; k++)
            for (int i = 0; i < PER_KIND * RUNS; i++) {
                sum += upd[k][i];
                fsum += full[k][i];
                most = upd[k][i] > most ? upd[k][i] : most;
            }
        fprintf(md, "\nThe update (docs/embedding.md \"Patches\"): the roads' fingerprints find the edited ones, the\n"
                    "network updated in place (docs/network.md \"After an edit\") finds the records whose strokes\n"
                    "changed, the roads near them are built alone with the whole map's network and facts, and\n"
                    "the new grid shares the old one's structures and draws the new parts in patch rectangles;\n"
                    "the candidate pixels (the pieces that differ) rendered under both grids give the dirty\n"
                    "rectangles. An update that would leave more than rs_limits.max_patches (16) patches builds\n"
                    "the grid whole. Every update\n"
                    "timed (%d): mean %.1f ms = %.3f of the mean full build (%.1f ms), the whole builds\n"
                    "included; the slowest %.1f ms.\n\n",
                KINDS * PER_KIND * RUNS, sum / (KINDS * PER_KIND * RUNS), sum / fsum, fsum / (KINDS * PER_KIND * RUNS),
                most);
        fprintf(md, "A road dragged: %d moves of one road by 1.1 m, chained from a whole build, each timed %d\n"
                    "times against a full build (interleaved); the grid held at most %zu patch(es) (a patch that\n"
                    "covers the last one's rectangle replaces it), %ld pixels differ from fresh builds.\n\n"
                    "| edit | update ms | full build ms | update / build | mean update / mean build | slowest update ms |\n"
                    "|---|---|---|---|---|---|\n"
                    "| drag a road 1.1 m | %.1f | %.1f | %.3f | %.3f | %.1f |\n\n",
                DRAG_STEPS, RUNS, dmost, dmismatch, dmed, dfmed, dmed / dfmed, dsum / dfsum, dmax);
        fprintf(csv, "drag,%.3f,%.3f,0,0,0\n", dmed, dfmed);
        printf("edits: drag       update %.1f ms, build %.1f ms (%.3f); mean %.3f, at most %zu patch(es)\n", dmed, dfmed,
               dmed / dfmed, dsum / dfsum, dmost);
        double fall[KINDS * PER_KIND * RUNS];
        for (int k = 0; k < KINDS; k++)
            for (int i = 0; i < PER_KIND * RUNS; i++) fall[k * PER_KIND * RUNS + i] = full[k][i];
        double fm = tm_median(fall, KINDS * PER_KIND * RUNS), lsum = 0, lmax = 0, lsorted[LONG];
        for (int i = 0; i < LONG; i++) lsum += lmain[i], lmax = lmain[i] > lmax ? lmain[i] : lmax, lsorted[i] = lmain[i];
        double lmed = tm_median(lsorted, LONG);
        fprintf(md, "A long chain with its whole builds on a worker (docs/embedding.md \"Long chains\"): %d edits (the\n"
                    "four kinds in turn), chained, rs_limits.max_patches 64; when the grid holds %d patches the\n"
                    "roads are copied (rs_roads_copy) and a worker thread builds them whole, %d edits later the\n"
                    "chain is rebased onto that grid (rs_road_grid_rebase; %d times; here the edits come back to\n"
                    "back, so the join waits for the build). The caller's thread per edit: the\n"
                    "update, with the copy or the rebase when they fall on it (the copies %.1f ms, the rebases\n"
                    "%.2f ms in all); the worker's builds %.1f ms in all. Against the median full build of the\n"
                    "chain above (%.1f ms); at most %zu patches, %.1f MB with the base; the last grid differs\n"
                    "from a fresh build in %ld pixels; its %zu patches make the whole image's splat (splatter and\n"
                    "window, fastest of 3) %.1f ms against %.1f ms for the whole build's grid (%.2fx).\n\n"
                    "| long chain | caller's thread per edit, median | slowest | mean | mean with the worker's builds |\n"
                    "|---|---|---|---|---|\n"
                    "| %d edits | %.3f | %.3f | %.3f | %.3f |\n\n",
                LONG, FLAT_AT, FLAT_JOIN, nflat, lcopy, lrebase, lwork, fm, lmost, lbytes, lmismatch, lpatches, lsplat_p, lsplat_w,
                lsplat_w > 0 ? lsplat_p / lsplat_w : 0, LONG, lmed / fm,
                lmax / fm, lsum / LONG / fm, (lsum + lwork) / LONG / fm);
        printf("edits: long chain caller per edit median %.3f, slowest %.3f, mean %.3f; with the worker %.3f (%d rebases)\n",
               lmed / fm, lmax / fm, lsum / LONG / fm, (lsum + lwork) / LONG / fm, nflat);
        double sm = 0, s90 = 0, s99 = 0, smax = 0;
        if (nspread) {
            qsort(spread, nspread, sizeof *spread, cmp_double);
            sm = spread[nspread / 2], s90 = spread[nspread * 9 / 10], s99 = spread[nspread * 99 / 100];
            smax = spread[nspread - 1];
        }
        fprintf(md, "The spread over roads: every %dth road (%zu) moved 15 m alone from a whole grid of the last\n"
                    "roads and put back, the faster of two updates against the median full build above; %zu of\n"
                    "them built whole (the changed area passed a quarter of the image). Long roads and records of\n"
                    "long strokes (a stroke split or joined moves the dashes of all its records) make the tail.\n\n"
                    "| one road moved | median | 90th percentile | 99th percentile | slowest | mean | over 5 %% |\n"
                    "|---|---|---|---|---|---|---|\n"
                    "| %zu roads | %.3f | %.3f | %.3f | %.3f | %.3f | %zu (%.1f %%) |\n\n",
                SPREAD_STEP, nspread, swhole, nspread, sm, s90, s99, smax, nspread ? ssum / nspread : 0, sover,
                nspread ? 100.0 * sover / nspread : 0);
        printf("edits: spread of %zu one-road moves: median %.3f, p90 %.3f, p99 %.3f, slowest %.3f, %zu over 5 %%, %zu "
               "whole\n",
               nspread, sm, s90, s99, smax, sover, swhole);
        char met_kinds[128] = "";
        for (int k = 0; k < KINDS; k++) {
            double u = tm_median(upd[k], PER_KIND * RUNS), f = tm_median(full[k], PER_KIND * RUNS);
            if (u / f <= 0.05)
                snprintf(met_kinds + strlen(met_kinds), sizeof met_kinds - strlen(met_kinds), "%s%s",
                         met_kinds[0] ? ", " : "", kind_name[k]);
        }
        char verdict[192];
        if (worst_cost <= 0.05 && sum / fsum <= 0.05 && !sover) snprintf(verdict, sizeof verdict, "met");
        else snprintf(verdict, sizeof verdict, "**missed**%s%s%s", met_kinds[0] ? " (met by the medians of: " : "",
                      met_kinds, met_kinds[0] ? ")" : "");
        fprintf(md, "| target (issue 30, 3) | measured | |\n|---|---|---|\n"
                    "| an edit of one road costs <= 5 %% of a full rebuild | update / build up to %.3f (medians per "
                    "kind); %.3f mean of all, the whole build every 17th included; with it on a worker (long "
                    "chain) the caller's thread %.3f mean, %.3f slowest, %.3f with the worker's builds; one "
                    "road moved: %.1f %% of %zu roads over 5 %%, the slowest %.3f | %s |\n"
                    "| the dirty rectangles cover every changed pixel and <= 2x the changed area | %ld uncovered; "
                    "dirty / changed up to %.2f; updated grids = fresh builds but for %ld pixels | %s |\n",
                worst_cost, sum / fsum, lsum / LONG / fm, lmax / fm, (lsum + lwork) / LONG / fm,
                nspread ? 100.0 * sover / nspread : 0, nspread, smax, verdict, uncovered,
                worst_area, mismatch,
                !uncovered && !mismatch && worst_area <= 2 ? "met" : "**missed**");
        printf("edits: %ld changed pixels outside the rectangles, %ld where an updated grid differs from a fresh "
               "build; pieces %zu, %.2f MB, %.1f ms to make; mean update %.3f of a build, slowest %.1f ms\n",
               uncovered, mismatch, wpieces, wpiece_mb, piece_med, sum / fsum, most);
        bad = fclose(md) != 0;
        bad |= fclose(csv) != 0;
    }
    free(mask);
    free(spread);
    ss_image_free(&a);
    ss_image_free(&b);
    rs_road_grid_free(ctx, g0);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
    rs_ctx_free(cctx);
    return bad || uncovered || mismatch ? 1 : 0;
}
