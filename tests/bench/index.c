/* Road index build against the road count on a fixed map (issue 29 target
 * 3): the city generator (tests/scenes.c sc_city) on the 400 x 350 DEM of
 * 5 m cells with 100, 1,000, 10,000 and 100,000 roads, T = 4 (1596 x 1396
 * pixels, 2.2 Mpx). Times the road field alone (rs__roadfield_build, the
 * analytic edges' index) and the whole unstyled road grid build
 * (rs_road_grid_build, which contains it), thread CPU time, fastest of
 * RUNS, the builds of a count interleaved.
 * Usage: index [OUTDIR] (writes OUTDIR/index.md; OUTDIR build/bench by default);
 *        index --one N [REPS [grid|CELL]] (N roads, REPS road-field builds
 *        (index cell CELL m, default automatic), or whole grid builds: for
 *        profilers; INDEX_ALLOC=kept or fresh runs them on that allocator);
 *        index --dump N FILE [CELL] (N roads, index cell CELL m (0: automatic): the road field's stats, whole-image
 *        coverage doubles and a nearest query per 7th pixel into FILE, to
 *        compare two builds byte for byte with cmp).
 * The 10^4 and 10^5 road fields and grids are also built under two host allocators
 * that put both counts in the same memory state: "fresh pages" maps every
 * block of 64 KiB or more anew and unmaps it when freed (each build
 * faults all its memory in, as a one-shot run does), "kept pages" never
 * gives memory back and hands a freed block out again (each build after
 * the first writes into pages already there, as a host with a pool does).
 * glibc's malloc does neither: it keeps freed blocks below its 32 MiB
 * mapping cap in the heap and maps larger ones anew, so with it the 10^4
 * case runs in kept pages and the 10^5 case's big arrays in fresh ones. */
#define _DEFAULT_SOURCE /* MAP_ANONYMOUS */
#include "roadfield.h"
#include "roadsplat.h"
#include "scene_splat.h"
#include "scenes.h"
#include "timing.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

#define RUNS 5
#define DEM_W 400
#define DEM_H 350
#define CELL 5.0
#define T 4

static double one_cell; /* index --one N REPS CELL: the index cell (0: automatic) */

static rs__roadfield_params field_params(void)
{
    rs__roadfield_params p;
    memset(&p, 0, sizeof p);
    p.index_cell = one_cell;
    p.cell_size = CELL;
    p.width_m = (DEM_W - 1) * CELL;
    p.height_m = (DEM_H - 1) * CELL;
    p.pixel = CELL / T;
    return p;
}

/* One road-field build, ms (< 0: failed); its stats into *st. */
static double field_once(rs_ctx *ctx, const rs_roads *R, rs__roadfield_stats *st)
{
    rs__roadfield_params p = field_params();
    rs__roadfield *f = NULL;
    double t0 = tm_thread_cpu_ms();
    rs_result r = rs__roadfield_build(ctx, R, &p, &f);
    double ms = tm_thread_cpu_ms() - t0;
    if (r == RS_OK && st) rs__roadfield_get_stats(f, st);
    rs__roadfield_free(ctx, f);
    return r ? -1 : ms;
}

/* ---- the two host allocators: a 16-byte header holds the capacity and whether the block is mapped ---- */
#define HDR 16
#define MAP_MIN ((size_t)64 << 10)

static void *hdr_set(void *raw, size_t cap, size_t mapped)
{
    size_t *h = raw;
    h[0] = cap, h[1] = mapped;
    return (char *)raw + HDR;
}

static size_t hdr_cap(void *p) { return ((size_t *)((char *)p - HDR))[0]; }
static size_t hdr_mapped(void *p) { return ((size_t *)((char *)p - HDR))[1]; }

static void *fresh_malloc(void *u, size_t n)
{
    (void)u;
#ifdef MAP_ANONYMOUS
    if (n >= MAP_MIN && n < ((size_t)1 << 40)) {
        void *raw = mmap(NULL, n + HDR, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        return raw == MAP_FAILED ? NULL : hdr_set(raw, n, 1);
    }
#endif
    void *raw = malloc(n + HDR);
    return raw ? hdr_set(raw, n, 0) : NULL;
}

static void fresh_free(void *u, void *p)
{
    (void)u;
    if (!p) return;
#ifdef MAP_ANONYMOUS
    if (hdr_mapped(p)) {
        munmap((char *)p - HDR, hdr_cap(p) + HDR);
        return;
    }
#endif
    free((char *)p - HDR);
}

static void *fresh_realloc(void *u, void *p, size_t n)
{
    if (!p) return fresh_malloc(u, n);
    void *q = fresh_malloc(u, n);
    if (!q) return NULL;
    size_t c = hdr_cap(p);
    memcpy(q, p, c < n ? c : n);
    fresh_free(u, p);
    return q;
}

/* kept pages: freed blocks on a list, the smallest that fits handed out again */
typedef struct kept_pool {
    void **blk;
    size_t n, cap;
} kept_pool;

static void *kept_malloc(void *u, size_t n)
{
    kept_pool *P = u;
    size_t best = P->n;
    for (size_t i = 0; i < P->n; i++)
        if (hdr_cap(P->blk[i]) >= n && (best == P->n || hdr_cap(P->blk[i]) < hdr_cap(P->blk[best]))) best = i;
    if (best < P->n) {
        void *p = P->blk[best];
        P->blk[best] = P->blk[--P->n];
        return p;
    }
    void *raw = malloc(n + HDR);
    return raw ? hdr_set(raw, n, 0) : NULL;
}

static void kept_free(void *u, void *p)
{
    kept_pool *P = u;
    if (!p) return;
    if (P->n == P->cap) {
        size_t nc = P->cap ? 2 * P->cap : 256;
        void **nb = realloc(P->blk, nc * sizeof *nb);
        if (!nb) { /* (no room to keep it: give it back) */
            free((char *)p - HDR);
            return;
        }
        P->blk = nb, P->cap = nc;
    }
    P->blk[P->n++] = p;
}

static void *kept_realloc(void *u, void *p, size_t n)
{
    if (!p) return kept_malloc(u, n);
    if (hdr_cap(p) >= n) return p;
    void *q = kept_malloc(u, n);
    if (!q) return NULL;
    memcpy(q, p, hdr_cap(p));
    kept_free(u, p);
    return q;
}

static void kept_release(kept_pool *P)
{
    for (size_t i = 0; i < P->n; i++) free((char *)P->blk[i] - HDR);
    free(P->blk);
    memset(P, 0, sizeof *P);
}

/* One whole road grid build of R: thread CPU ms (< 0: failed). */
static double grid_once(rs_ctx *ctx, const rs_dem *d, const rs_roads *R, const rs_splat_options *o)
{
    rs_road_grid *g = NULL;
    double t0 = tm_thread_cpu_ms();
    rs_result r = rs_road_grid_build(ctx, d, R, o, &g);
    double ms = tm_thread_cpu_ms() - t0;
    rs_road_grid_free(ctx, g);
    return r ? -1 : ms;
}

/* The fastest of RUNS road-field builds (d NULL) or whole grid builds in a
 * context of their own on allocator a, ms (< 0: failed). */
static double build_best(const rs_allocator *a, const rs_roads *R, const rs_dem *d, const rs_splat_options *o)
{
    rs_ctx *c = NULL;
    if (rs_ctx_create(a, NULL, &c)) return -1;
    double best = -1;
    for (int k = 0; k < RUNS; k++) {
        double ms = d ? grid_once(c, d, R, o) : field_once(c, R, NULL);
        if (ms < 0) {
            best = -1;
            break;
        }
        if (best < 0 || ms < best) best = ms;
    }
    rs_ctx_free(c);
    return best;
}

int main(int argc, char **argv)
{
    rs_ctx *ctx = NULL;
    /* (--one on a chosen allocator: INDEX_ALLOC=kept or fresh, as in the table's columns) */
    static kept_pool one_pool;
    const char *one_alloc = getenv("INDEX_ALLOC");
    rs_allocator kept_a = { kept_malloc, kept_realloc, kept_free, &one_pool };
    rs_allocator fresh_a = { fresh_malloc, fresh_realloc, fresh_free, NULL };
    const rs_allocator *one_a = !one_alloc ? NULL : !strcmp(one_alloc, "kept") ? &kept_a : !strcmp(one_alloc, "fresh") ? &fresh_a : NULL;
    if (rs_ctx_create(argc > 2 && strcmp(argv[1], "--one") == 0 ? one_a : NULL, NULL, &ctx)) return 1;
    if (argc > 2 && strcmp(argv[1], "--one") == 0) {
        sc_scene s;
        if (sc_city(&s, DEM_W, DEM_H, CELL, (size_t)atol(argv[2]), 1)) return 1;
        rs_roads *R = ss_roads(ctx, &s);
        int reps = argc > 3 ? atoi(argv[3]) : 1;
        double best = -1;
        rs__roadfield_stats st;
        memset(&st, 0, sizeof st);
        rs_dem *d = NULL;
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.texels = T;
        int grid = argc > 4 && strcmp(argv[4], "grid") == 0;
        if (argc > 4 && !grid) one_cell = atof(argv[4]);
        if (grid) {
            rs_dem_frame fr = { CELL, 1, 0, 0 };
            if (rs_dem_create(ctx, s.w, s.h, s.z, &d) || rs_dem_set_frame(ctx, d, &fr)) return 1;
        }
        for (int i = 0; i < reps && R; i++) {
            double ms = grid ? grid_once(ctx, d, R, &o) : field_once(ctx, R, &st);
            if (ms < 0) return 1;
            if (best < 0 || ms < best) best = ms;
        }
        printf("index: %zu roads, %zu segments, %zu entries, max list %zu, relation work %.1f per segment, "
               "%zu redundant: road field %.2f ms (fastest of %d)\n",
               s.nroads, st.segments, st.entries, st.max_list,
               st.segments ? (double)st.relation_work / (double)st.segments : 0, st.redundant, best, reps);
        if (grid) printf("  (whole road grid builds)\n");
        rs_dem_free(ctx, d);
        rs_roads_free(ctx, R);
        sc_scene_free(&s);
        rs_ctx_free(ctx);
        kept_release(&one_pool);
        return 0;
    }
    if (argc > 3 && strcmp(argv[1], "--dump") == 0) {
        sc_scene s;
        if (sc_city(&s, DEM_W, DEM_H, CELL, (size_t)atol(argv[2]), 1)) return 1;
        rs_roads *R = ss_roads(ctx, &s);
        rs__roadfield_params p = field_params();
        if (argc > 4) p.index_cell = atof(argv[4]);
        rs__roadfield *f = NULL;
        FILE *fo = fopen(argv[3], "wb");
        if (!R || !fo || rs__roadfield_build(ctx, R, &p, &f)) return 1;
        rs__roadfield_stats st;
        rs__roadfield_get_stats(f, &st);
        fprintf(fo, "%zu %zu %zu %zu %zu %zu %llu\n", st.segments, st.entries, st.nonempty_cells, st.full_cells,
                st.max_list, st.redundant, (unsigned long long)st.relation_work);
        uint32_t w = (DEM_W - 1) * T, h = (DEM_H - 1) * T;
        double *cov = malloc((size_t)w * h * sizeof *cov);
        if (!cov) return 1;
        rs__roadfield_coverage(f, 0, 0, w, h, p.pixel, cov, w);
        fwrite(cov, sizeof *cov, (size_t)w * h, fo);
        for (size_t i = 0; i < (size_t)w * h; i += 7) {
            rs__road_point rp;
            memset(&rp, 0, sizeof rp);
            double x = ((double)(i % w) + 0.5) * p.pixel, y = ((double)(i / w) + 0.5) * p.pixel;
            int got = rs__roadfield_nearest(f, x, y, i % 3 ? 0.5 : 6, &rp);
            fprintf(fo, "%d %u %u %.17g %.17g\n", got, rp.road, rp.seg, rp.s, rp.t);
        }
        free(cov);
        fclose(fo);
        rs__roadfield_free(ctx, f);
        rs_roads_free(ctx, R);
        sc_scene_free(&s);
        rs_ctx_free(ctx);
        return 0;
    }
    const char *dir = argc > 1 ? argv[1] : "build/bench";
    char path[4096];
    snprintf(path, sizeof path, "%s/index.md", dir);
    FILE *md = fopen(path, "w");
    if (!md) return 1;
    size_t want[4] = { 100, 1000, 10000, 100000 };
    size_t nroads[4], nseg[4], nent[4], maxl[4];
    double fms[4], gms[4], fresh[4] = { -1, -1, -1, -1 }, kept[4] = { -1, -1, -1, -1 };
    double gfresh[4] = { -1, -1, -1, -1 }, gkept[4] = { -1, -1, -1, -1 };
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = T;
    for (int i = 0; i < 4; i++) {
        sc_scene s;
        if (sc_city(&s, DEM_W, DEM_H, CELL, want[i], 1)) return 1;
        rs_roads *R = ss_roads(ctx, &s);
        rs_dem *d = NULL;
        if (!R || rs_dem_create(ctx, s.w, s.h, s.z, &d)) return 1;
        rs_dem_frame fr;
        rs_dem_get_frame(d, &fr);
        fr.cell_size = CELL;
        if (rs_dem_set_frame(ctx, d, &fr)) return 1;
        rs__roadfield_stats st;
        memset(&st, 0, sizeof st);
        fms[i] = gms[i] = -1;
        for (int k = 0; k < RUNS; k++) {
            double a = field_once(ctx, R, &st), b = grid_once(ctx, d, R, &o);
            if (a < 0 || b < 0) {
                fprintf(stderr, "index: %s\n", rs_ctx_message(ctx));
                return 1;
            }
            if (fms[i] < 0 || a < fms[i]) fms[i] = a;
            if (gms[i] < 0 || b < gms[i]) gms[i] = b;
        }
        if (i >= 2) {
            /* the same counts in one memory state (the allocators above) */
            kept_pool pool;
            memset(&pool, 0, sizeof pool);
            rs_allocator fa = { fresh_malloc, fresh_realloc, fresh_free, NULL };
            rs_allocator ka = { kept_malloc, kept_realloc, kept_free, &pool };
            fresh[i] = build_best(&fa, R, NULL, NULL);
            kept[i] = build_best(&ka, R, NULL, NULL);
            gfresh[i] = build_best(&fa, R, d, &o);
            gkept[i] = build_best(&ka, R, d, &o);
            kept_release(&pool);
            printf("index: %zu roads: road field in fresh pages %.2f ms, in kept pages %.2f ms; road grid %.2f, %.2f ms\n",
                   s.nroads, fresh[i], kept[i], gfresh[i], gkept[i]);
        }
        nroads[i] = s.nroads;
        nseg[i] = st.segments;
        nent[i] = st.entries;
        maxl[i] = st.max_list;
        printf("index: %zu roads: road field %.2f ms, road grid %.2f ms\n", s.nroads, fms[i], gms[i]);
        rs_dem_free(ctx, d);
        rs_roads_free(ctx, R);
        sc_scene_free(&s);
    }
    fprintf(md, "## Road index build against the road count (tests/bench/index.c; issue 29 target 3)\n\n");
    fprintf(md, "City generator (`sc_city`, tests/scenes.c) on one %u x %u DEM of %g m cells with 100 to 100,000 "
                "roads, T = %d (%u x %u pixels of %g m); thread CPU time, fastest of %d, the two builds of a count "
                "alternating. Road field = `rs__roadfield_build` (the analytic edges' index); road grid = the "
                "whole unstyled `rs_road_grid_build` that contains it.\n\n",
            DEM_W, DEM_H, CELL, T, (DEM_W - 1) * T, (DEM_H - 1) * T, CELL / T, RUNS);
    fprintf(md, "| roads | segments | index entries | longest cell list | road field ms | ratio | road grid ms | ratio |\n");
    fprintf(md, "|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < 4; i++)
        fprintf(md, "| %zu | %zu | %zu | %zu | %.2f | %s%.1f | %.2f | %s%.1f |\n", nroads[i], nseg[i], nent[i], maxl[i],
                fms[i], i ? "x" : "", i ? fms[i] / fms[i - 1] : 1.0, gms[i], i ? "x" : "",
                i ? gms[i] / gms[i - 1] : 1.0);
    double rf = fms[3] / fms[2], rg = gms[3] / gms[2];
    double rfr = fresh[2] > 0 ? fresh[3] / fresh[2] : -1, rkp = kept[2] > 0 ? kept[3] / kept[2] : -1;
    double gfr = gfresh[2] > 0 ? gfresh[3] / gfresh[2] : -1, gkp = gkept[2] > 0 ? gkept[3] / gkept[2] : -1;
    fprintf(md, "\nThe road field and the road grid of 10^4 and 10^5 roads with both counts in one memory state (host allocators in "
                "tests/bench/index.c, fastest of %d in a context of their own): **fresh pages** maps every block of 64 "
                "KiB or more anew and unmaps it when freed, so each build faults all its memory in, as a one-shot run "
                "does; **kept pages** never gives memory back, so each build after the first writes into pages "
                "already there, as a host with a pool does. glibc's malloc (the columns above) keeps freed blocks "
                "below its 32 MiB mapping cap and maps larger ones anew: the 10^4 case runs in kept pages, the 10^5 "
                "case's big arrays (segments, lists, record) in fresh ones, and its ratio adds their page faults.\n\n",
            RUNS);
    fprintf(md, "| memory | road field 10^4 ms | 10^5 ms | ratio | road grid 10^4 ms | 10^5 ms | ratio |\n"
                "|---|---:|---:|---:|---:|---:|---:|\n");
    fprintf(md, "| glibc malloc (above) | %.2f | %.2f | %.1fx | %.2f | %.2f | %.1fx |\n", fms[2], fms[3], rf, gms[2], gms[3],
            rg);
    fprintf(md, "| fresh pages at both counts | %.2f | %.2f | %.1fx | %.2f | %.2f | %.1fx |\n", fresh[2], fresh[3], rfr,
            gfresh[2], gfresh[3], gfr);
    fprintf(md, "| kept pages at both counts | %.2f | %.2f | %.1fx | %.2f | %.2f | %.1fx |\n", kept[2], kept[3], rkp,
            gkept[2], gkept[3], gkp);
    fprintf(md, "\n| target (issue 29, 3) | measured | |\n|---|---|---|\n");
    fprintf(md, "| road index build, 100k roads <= 12x the 10k case | road field %.1fx, road grid %.1fx (glibc malloc); "
                "road field %.1fx in fresh pages, %.1fx in kept pages; road grid %.1fx in fresh pages, %.1fx in kept "
                "pages | %s |\n",
            rf, rg, rfr, rkp, gfr, gkp, rf <= 12 && rg <= 12 && gfr <= 12 && gkp <= 12 ? "met" : "**missed**");
    fclose(md);
    rs_ctx_free(ctx);
    printf("index: wrote %s\n", path);
    return 0;
}
