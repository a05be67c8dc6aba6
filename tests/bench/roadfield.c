/* Road field benchmark: analytic coverage (lib/scene/roadfield.c) of the city
 * scene at T = 4 against the exact ground truth: edge error (SPEC), max
 * pixel error, build time, coverage time as one whole-image call and as
 * the splatter calls it (pieces of one DEM row: T rows x the full width,
 * which must give the same doubles); optionally Cairo
 * (python3-cairo) filling the same stroked roads, timed in the same run.
 * Usage: roadfield OUTDIR   (writes OUTDIR/roadfield.md, and
 * OUTDIR/roadfield_roads.txt for tests/bench/roadfield_cairo.py);
 * roadfield --profile [N [FILE [whole|pieces]]] (see profile()). */
#include "groundtruth.h"
#include "roadfield.h"
#include "roadsplat.h"
#include "scenes.h"
#include "timing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Timing on a shared machine: every time is the minimum (fastest) of its
 * runs, the least disturbed one (medians swing 2x with load). The auto-cell
 * coverage and Cairo alternate in ROUNDS rounds (RUNS coverage runs, then
 * CAIRO_FILLS Cairo fills per round), so both see the same load. */
#define RUNS 7
#define ROUNDS 4
#define CAIRO_FILLS 5

/* Fastest ms of CAIRO_FILLS Cairo fills (the script prints it), or < 0 when unavailable. */
static double cairo_ms(const char *roads_path)
{
    char args[2048];
    snprintf(args, sizeof args, "tests/bench/roadfield_cairo.py '%s' 4 - %d", roads_path, CAIRO_FILLS);
    return tm_python_ms(args);
}

/* Cairo's own coverage image of the same roads (one fill, written as float32
 * by the script) into R; 0, or -1 when unavailable. */
static int cairo_image(const char *roads_path, const char *out_path, float *R, size_t n)
{
    const char *py[2] = { "python3", "/usr/bin/python3" };
    for (int i = 0; i < 2; i++) {
        char cmd[3072];
        snprintf(cmd, sizeof cmd, "%s tests/bench/roadfield_cairo.py '%s' 4 '%s' 1 >/dev/null 2>&1", py[i], roads_path,
                 out_path);
        if (system(cmd) != 0) continue;
        FILE *f = fopen(out_path, "rb");
        if (!f) continue;
        size_t got = fread(R, sizeof *R, n, f);
        fclose(f);
        if (got == n) return 0;
    }
    return -1;
}

static double tm_min(const double *v, int n)
{
    double m = v[0];
    for (int i = 1; i < n; i++)
        if (v[i] < m) m = v[i];
    return m;
}

typedef struct run_result {
    double build_ms, cover_ms, rows_ms, edge, maxd, maxpix;
    size_t bytes;
    rs__roadfield_stats st;
} run_result;

static int measure(rs_ctx *ctx, const rs_roads *roads, const sc_scene *sc, unsigned T, double index_cell,
                   const float *G, double L, double *cov, double *rowcov, float *R, run_result *rr)
{
    uint32_t w = (sc->w - 1) * T, h = (sc->h - 1) * T;
    double pix = sc->cell_size / T, tb[RUNS], tc[RUNS], tr[RUNS];
    rs__roadfield_params p;
    memset(&p, 0, sizeof p);
    p.cell_size = sc->cell_size;
    p.width_m = sc_extent_x(sc);
    p.height_m = sc_extent_y(sc);
    p.index_cell = index_cell;
    p.pixel = pix;
    rs__roadfield *f = NULL;
    for (int i = 0; i < RUNS; i++) {
        double t0 = tm_now_ms();
        if (rs__roadfield_build(ctx, roads, &p, &f)) return -1;
        tb[i] = tm_now_ms() - t0;
        t0 = tm_now_ms();
        rs__roadfield_coverage(f, 0, 0, w, h, pix, cov, w);
        tc[i] = tm_now_ms() - t0;
        /* the splatter's pieces: one DEM row (T pixel rows) at a time */
        t0 = tm_now_ms();
        for (uint32_t y = 0; y < h; y += T)
            rs__roadfield_coverage(f, 0, y, w, h - y < T ? h - y : T, pix, rowcov + (size_t)y * w, w);
        tr[i] = tm_now_ms() - t0;
        if (memcmp(rowcov, cov, (size_t)w * h * sizeof *cov) != 0) {
            fprintf(stderr, "roadfield bench: row pieces differ from the whole-image call\n");
            return -1;
        }
        if (i + 1 < RUNS) rs__roadfield_free(ctx, f);
    }
    rr->build_ms = tm_min(tb, RUNS);
    rr->cover_ms = tm_min(tc, RUNS);
    rr->rows_ms = tm_min(tr, RUNS);
    rr->bytes = rs__roadfield_bytes(f);
    rs__roadfield_get_stats(f, &rr->st);
    rs__roadfield_free(ctx, f);
    rr->maxpix = 0;
    for (size_t i = 0; i < (size_t)w * h; i++) {
        R[i] = (float)cov[i];
        double d = fabs(cov[i] - G[i]);
        if (d > rr->maxpix) rr->maxpix = d;
    }
    gt_result gr;
    if (gt_edge_error_g(sc, T, G, L, R, &gr)) return -1;
    rr->edge = gr.edge_error;
    rr->maxd = gr.max_disp;
    return 0;
}

static double cpu_ms(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts)) return 0;
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* `roadfield --profile [N [FILE [whole|pieces]]]`: only the auto-cell
 * build and N (default 1) whole-image coverage calls plus N passes of row
 * pieces (or only one of the two), for callgrind
 * (--toggle-collect=rs__roadfield_coverage); prints a checksum and the
 * fastest call of each kind, and writes the doubles to FILE ("-": none;
 * to compare builds with cmp). */
static int profile(rs_ctx *ctx, const rs_roads *roads, const sc_scene *sc, unsigned T, int n, const char *file,
                   const char *only)
{
    uint32_t w = (sc->w - 1) * T, h = (sc->h - 1) * T;
    double pix = sc->cell_size / T, sum = 0;
    rs__roadfield_params p;
    memset(&p, 0, sizeof p);
    p.cell_size = sc->cell_size;
    p.width_m = sc_extent_x(sc);
    p.height_m = sc_extent_y(sc);
    p.pixel = pix;
    rs__roadfield *f = NULL;
    double *cov = malloc((size_t)w * h * sizeof *cov), *rowcov = malloc((size_t)w * h * sizeof *rowcov);
    if (!cov || !rowcov || rs__roadfield_build(ctx, roads, &p, &f)) return 1;
    /* wall clock and this thread's CPU time (less disturbed by other
     * processes taking turns on the cores) */
    double tw = 1e300, tp = 1e300, cw = 1e300, cp = 1e300;
    for (int i = 0; i < n; i++) {
        double t0 = tm_now_ms(), c0 = cpu_ms();
        if (!only || strcmp(only, "pieces") != 0) rs__roadfield_coverage(f, 0, 0, w, h, pix, cov, w);
        double t1 = tm_now_ms(), c1 = cpu_ms();
        for (uint32_t y = 0; y < h && (!only || strcmp(only, "whole") != 0); y += T)
            rs__roadfield_coverage(f, 0, y, w, h - y < T ? h - y : T, pix, rowcov + (size_t)y * w, w);
        double t2 = tm_now_ms(), c2 = cpu_ms();
        tw = fmin(tw, t1 - t0);
        tp = fmin(tp, t2 - t1);
        cw = fmin(cw, c1 - c0);
        cp = fmin(cp, c2 - c1);
    }
    int same = only || memcmp(rowcov, cov, (size_t)w * h * sizeof *cov) == 0;
    if (only && strcmp(only, "pieces") == 0) memcpy(cov, rowcov, (size_t)w * h * sizeof *cov);
    for (size_t i = 0; i < (size_t)w * h; i++) sum += cov[i];
    printf("roadfield profile: sum %.17g, pieces %s; fastest whole %.2f ms, pieces %.2f ms (thread CPU time "
           "%.2f, %.2f ms)\n", sum, same ? "identical" : "DIFFER", tw, tp, cw, cp);
    if (file && strcmp(file, "-") != 0) {
        FILE *fo = fopen(file, "wb");
        if (!fo || fwrite(cov, sizeof *cov, (size_t)w * h, fo) != (size_t)w * h || fclose(fo)) return 1;
    }
    rs__roadfield_free(ctx, f);
    free(cov);
    free(rowcov);
    return !same;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "build/bench";
    char path[1024];
    sc_scene sc;
    rs_ctx *ctx = NULL;
    rs_roads *roads = NULL;
    const unsigned T = 4;
    if (rs_ctx_create(NULL, NULL, &ctx) || sc_city_default(&sc, 1) || rs_roads_create(ctx, &roads)) return 1;
    for (size_t i = 0; i < sc.nroads; i++)
        if (rs_roads_add(ctx, roads, NULL, sc.roads[i].width, sc.roads[i].xy, sc.roads[i].n)) return 1;
    if (argc > 1 && strcmp(argv[1], "--profile") == 0)
        return profile(ctx, roads, &sc, T, argc > 2 ? atoi(argv[2]) : 1, argc > 3 ? argv[3] : NULL,
                       argc > 4 ? argv[4] : NULL);
    uint32_t w = (sc.w - 1) * T, h = (sc.h - 1) * T;
    size_t n = (size_t)w * h;
    float *G = malloc(n * sizeof *G), *R = malloc(n * sizeof *R);
    double *cov = malloc(n * sizeof *cov), *rowcov = malloc(n * sizeof *rowcov);
    if (!G || !R || !cov || !rowcov || gt_coverage(&sc, T, G)) return 1;
    double L = gt_outline_length(&sc, T);
    double cells[] = { 0, 2.5, 10 };
    run_result rr[3];
    for (int i = 1; i < 3; i++)
        if (measure(ctx, roads, &sc, T, cells[i], G, L, cov, rowcov, R, &rr[i])) return 1;
    snprintf(path, sizeof path, "%s/roadfield_roads.txt", dir);
    int have_roads = sc_write_plain(path, &sc) == 0;
    double cairo = -1;
    for (int round = 0; round < ROUNDS; round++) {
        run_result r0;
        if (measure(ctx, roads, &sc, T, cells[0], G, L, cov, rowcov, R, &r0)) return 1;
        if (round == 0) rr[0] = r0;
        rr[0].build_ms = fmin(rr[0].build_ms, r0.build_ms);
        rr[0].cover_ms = fmin(rr[0].cover_ms, r0.cover_ms);
        rr[0].rows_ms = fmin(rr[0].rows_ms, r0.rows_ms);
        double c = have_roads ? cairo_ms(path) : -1;
        if (c >= 0 && (cairo < 0 || c < cairo)) cairo = c;
    }

    /* Cairo's accuracy on the same ruler: its A8 coverage as the road weight */
    gt_result cres;
    int have_cerr = 0;
    if (have_roads && cairo >= 0) {
        char img[1100];
        snprintf(img, sizeof img, "%s/roadfield_cairo.f32", dir);
        have_cerr = cairo_image(path, img, R, (size_t)w * h) == 0 && gt_edge_error_g(&sc, T, G, L, R, &cres) == 0;
    }
    snprintf(path, sizeof path, "%s/roadfield.md", dir);
    FILE *md = fopen(path, "w");
    if (!md) return 1;
    fprintf(md, "## Road field: analytic coverage (tests/bench/roadfield.c)\n\n");
    fprintf(md, "City scene (`sc_city_default(1)`: %zu roads, %ux%u samples, %g m cells) at T = %u: %ux%u pixels of "
                "%g m. Coverage = area fraction of each pixel inside the union of the roads "
                "(lib/scene/roadfield.c, one thread); error against the exact ground truth (tests/groundtruth.c). "
                "Coverage is timed as one whole-image call and as the splatter calls it: pieces of one "
                "DEM row (%u pixel rows x the full width; same doubles). Times are minima (the fastest run) of %d runs "
                "(auto cell: %d rounds of %d, alternating with Cairo), not medians: on a shared machine the "
                "fastest run is the least disturbed one, medians swing 2x with load.\n\n",
            sc.nroads, sc.w, sc.h, sc.cell_size, T, w, h, sc.cell_size / T, T, RUNS, ROUNDS, RUNS);
    fprintf(md, "| index cell (m) | cells | entries | full cells | max list | bytes | build ms | coverage ms | "
                "row pieces ms | edge error (m) | max edge disp (m) | max pixel error |\n");
    fprintf(md, "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
    for (int i = 0; i < 3; i++)
        fprintf(md, "| %g%s | %ux%u | %zu | %zu | %zu | %zu | %.2f | %.2f | %.2f | %.5f | %.4f | %.4f |\n",
                rr[i].st.index_cell, cells[i] == 0 ? " (auto)" : "", rr[i].st.gw, rr[i].st.gh, rr[i].st.entries,
                rr[i].st.full_cells, rr[i].st.max_list, rr[i].bytes, rr[i].build_ms, rr[i].cover_ms, rr[i].rows_ms,
                rr[i].edge, rr[i].maxd, rr[i].maxpix);
    if (cairo >= 0)
        fprintf(md, "\nCairo (python3-cairo, tests/bench/roadfield_cairo.py) filling the same roads stroked with "
                    "round caps and joins into an A8 surface of the same size, antialias default: %.2f ms "
                    "(fastest of %d fills, fill only, %d fills after each round of coverage runs). "
                    "Coverage (auto cell) / Cairo, fastest against fastest: whole image %.2f, row pieces %.2f.\n",
                cairo, ROUNDS * CAIRO_FILLS, CAIRO_FILLS, rr[0].cover_ms / cairo, rr[0].rows_ms / cairo);
    if (cairo >= 0) {
        /* issue 29 target 2: the index is part of the work Cairo does in its fill */
        double tot = rr[0].build_ms + rr[0].cover_ms;
        fprintf(md, "\n| target (issue 29, 2) | measured | |\n|---|---|---|\n"
                    "| plain coverage including the index build <= 1.0x Cairo | (%.2f + %.2f ms) / %.2f ms = %.2fx | "
                    "%s |\n",
                rr[0].build_ms, rr[0].cover_ms, cairo, tot / cairo, tot <= cairo ? "met" : "**missed**");
    } else
        fprintf(md, "\nCairo comparison skipped (python3-cairo not available).\n");
    if (have_cerr)
        fprintf(md, "\nAccuracy on the same ruler (SPEC edge error against the exact ground truth): Cairo's antialiased "
                    "stroke (A8, 8-bit coverage) %.5f m (max edge displacement %.4f m); roadsplat's analytic coverage "
                    "%.5f m, %.3fx Cairo's error. Target (issue 12): <= 0.025 m and better than Cairo.\n",
                cres.edge_error, cres.max_disp, rr[0].edge, rr[0].edge / cres.edge_error);
    fclose(md);
    printf("roadfield: auto cell %.3g m: build %.2f ms, coverage %.2f ms (row pieces %.2f ms), edge %.5f m, "
           "max pixel err %.4f; cairo %.2f ms",
           rr[0].st.index_cell, rr[0].build_ms, rr[0].cover_ms, rr[0].rows_ms, rr[0].edge, rr[0].maxpix, cairo);
    if (cairo > 0)
        printf(" (ratio whole %.2f, rows %.2f; build + whole %.2f)", rr[0].cover_ms / cairo, rr[0].rows_ms / cairo,
               (rr[0].build_ms + rr[0].cover_ms) / cairo);
    printf("\n");
    for (int i = 1; i < 3; i++)
        printf("  cell %g: build %.2f ms, coverage %.2f ms (row pieces %.2f ms), edge %.5f\n", rr[i].st.index_cell,
               rr[i].build_ms, rr[i].cover_ms, rr[i].rows_ms, rr[i].edge);
    free(G); free(R); free(cov); free(rowcov);
    rs_roads_free(ctx, roads);
    rs_ctx_free(ctx);
    sc_scene_free(&sc);
    return 0;
}
