/* Scaling benchmark: how splat time grows with map size (constant road
 * density), road length, road count and texels per cell, with least-squares
 * slopes on log-log axes (slope 1 = linear).
 * Usage: scaling OUTDIR -> OUTDIR/scaling.md, scaling.csv and scaling_fit.gp
 * (the fitted lines, loaded by tests/bench/scaling.gp for the plot). */
#include "roadsplat.h"
#include "scene_splat.h"
#include "scenes.h"
#include "timing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RUNS 3
#define MAXP 8

typedef struct sample {
    double x, pixels, build_ms, total_ms;
} sample;

typedef struct series {
    const char *name, *xname, *what;
    sample s[MAXP];
    int n;
} series;

/* Median grid build time and median build + splat (RGBA only) time. */
static int measure(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o, sample *out)
{
    double tb[RUNS], tt[RUNS];
    uint32_t w, h;
    if (rs_splat_size(ctx, dem, o, &w, &h)) return -1;
    size_t n = (size_t)w * h;
    uint8_t *rgba = malloc(n * 4);
    if (!rgba) return -1;
    for (int i = 0; i < RUNS; i++) {
        rs_road_grid *g = NULL;
        double t0 = tm_now_ms();
        if (rs_road_grid_build(ctx, dem, roads, o, &g)) { free(rgba); return -1; }
        tb[i] = tm_now_ms() - t0;
        rs_result r = rs_splat(ctx, dem, g, o, rgba, n * 4, NULL, 0);
        tt[i] = tm_now_ms() - t0;
        rs_road_grid_free(ctx, g);
        if (r) { free(rgba); return -1; }
    }
    free(rgba);
    out->pixels = (double)n;
    out->build_ms = tm_median(tb, RUNS);
    out->total_ms = tm_median(tt, RUNS);
    return 0;
}

/* Least squares of log y on log x: y = exp(b) x^a. */
static void fit(const series *se, int total, double *a, double *b)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int n = se->n;
    for (int i = 0; i < n; i++) {
        double lx = log(se->s[i].x), ly = log(total ? se->s[i].total_ms : se->s[i].build_ms);
        sx += lx; sy += ly; sxx += lx * lx; sxy += lx * ly;
    }
    double d = n * sxx - sx * sx;
    *a = d != 0 ? (n * sxy - sx * sy) / d : 0;
    *b = (sy - *a * sx) / n;
}

static rs_dem *fractal_dem(rs_ctx *ctx, uint32_t W)
{
    float *z = malloc(sizeof(float) * W * W);
    rs_dem *dem = NULL;
    if (!z) return NULL;
    sc_dem_fractal(z, W, W, 5, 0.5);
    if (rs_dem_create(ctx, W, W, z, &dem)) dem = NULL;
    free(z);
    return dem;
}

/* One 6 m road of total length `len` metres, meandering in 400 m rows 20 m
 * apart inside a 512 m map, so any length fits without touching the border. */
static rs_roads *meander(rs_ctx *ctx, double len)
{
    double xy[2 * 64];
    size_t n = 0;
    double x = 50, y = 50, left = len;
    int dir = 1;
    xy[n++] = x; xy[n++] = y;
    while (left > 0 && n + 4 <= sizeof xy / sizeof xy[0]) {
        double run = left < 400 ? left : 400;
        x += dir * run;
        left -= run;
        xy[n++] = x; xy[n++] = y;
        if (left <= 0) break;
        run = left < 20 ? left : 20;
        y += run;
        left -= run;
        xy[n++] = x; xy[n++] = y;
        dir = -dir;
    }
    rs_roads *r = NULL;
    if (rs_roads_create(ctx, &r)) return NULL;
    if (rs_roads_add(ctx, r, NULL, 6, xy, n / 2)) { rs_roads_free(ctx, r); return NULL; }
    return r;
}

/* `count` straight 60 m x 6 m roads at seeded random places and angles. */
static rs_roads *scattered(rs_ctx *ctx, int count, double extent)
{
    sc_rng g;
    rs_roads *r = NULL;
    sc_rng_seed(&g, 42);
    if (rs_roads_create(ctx, &r)) return NULL;
    for (int i = 0; i < count; i++) {
        double x = sc_rng_range(&g, 40, extent - 40), y = sc_rng_range(&g, 40, extent - 40);
        double a = sc_rng_range(&g, 0, 6.283185307179586), xy[4] = { x - 30 * cos(a), y - 30 * sin(a), x + 30 * cos(a), y + 30 * sin(a) };
        if (rs_roads_add(ctx, r, NULL, 6, xy, 2)) { rs_roads_free(ctx, r); return NULL; }
    }
    return r;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "build/bench";
    char path[1024];
    rs_ctx *ctx;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    const rs_dem_frame fr5 = { 5, 0.01, 0, 0 }, fr1 = { 1, 0.01, 0, 0 };
    static series S[4];
    const char *names[4][3] = {
        { "map", "DEM side (samples)", "city scene, 5 m cells, ~1000 roads per 400 x 350 cells, T = 4" },
        { "length", "road length (m)", "one 6 m road meandering on a 513^2 fractal DEM, 1 m cells, T = 4" },
        { "count", "road count", "60 m x 6 m roads scattered on a 513^2 fractal DEM, 1 m cells, T = 4" },
        { "texels", "texels per cell", "city scene sc_city_default (400 x 350, 5 m cells, 1000 roads)" },
    };
    for (int k = 0; k < 4; k++) { S[k].name = names[k][0]; S[k].xname = names[k][1]; S[k].what = names[k][2]; }

    /* 1. map size at constant road density */
    const uint32_t sides[] = { 101, 201, 401, 801 };
    for (int i = 0; i < 4; i++) {
        sc_scene sc;
        size_t target = (size_t)(1000.0 * (sides[i] - 1) * (sides[i] - 1) / (399.0 * 349.0) + 0.5);
        if (sc_city(&sc, sides[i], sides[i], 5.0, target, 1)) return 1;
        rs_dem *dem = NULL;
        rs_roads *r = ss_roads(ctx, &sc);
        rs_splat_options q = o;
        sample *s = &S[0].s[S[0].n++];
        s->x = sides[i];
        if (!r || rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) || rs_dem_set_frame(ctx, dem, &fr5) ||
            measure(ctx, dem, r, &q, s))
            return 1;
        rs_roads_free(ctx, r);
        rs_dem_free(ctx, dem);
        sc_scene_free(&sc);
    }
    /* 2 and 3. road length and road count on one map */
    rs_dem *dem = fractal_dem(ctx, 513);
    if (!dem || rs_dem_set_frame(ctx, dem, &fr1)) return 1;
    const double lens[] = { 100, 200, 400, 800, 1600, 3200 };
    for (int i = 0; i < 6; i++) {
        rs_roads *r = meander(ctx, lens[i]);
        sample *s = &S[1].s[S[1].n++];
        s->x = lens[i];
        if (!r || measure(ctx, dem, r, &o, s)) return 1;
        rs_roads_free(ctx, r);
    }
    const int counts[] = { 1, 4, 16, 64, 256 };
    for (int i = 0; i < 5; i++) {
        rs_roads *r = scattered(ctx, counts[i], 512);
        sample *s = &S[2].s[S[2].n++];
        s->x = counts[i];
        if (!r || measure(ctx, dem, r, &o, s)) return 1;
        rs_roads_free(ctx, r);
    }
    rs_dem_free(ctx, dem);
    /* 4. texels per cell */
    {
        sc_scene sc;
        if (sc_city_default(&sc, 1)) return 1;
        rs_roads *r = ss_roads(ctx, &sc);
        if (!r || rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) || rs_dem_set_frame(ctx, dem, &fr5)) return 1;
        const unsigned ts[] = { 1, 2, 4, 8 };
        for (int i = 0; i < 4; i++) {
            rs_splat_options q = o;
            q.texels = ts[i];
            sample *s = &S[3].s[S[3].n++];
            s->x = ts[i];
            if (measure(ctx, dem, r, &q, s)) return 1;
        }
        rs_roads_free(ctx, r);
        rs_dem_free(ctx, dem);
        sc_scene_free(&sc);
    }

    snprintf(path, sizeof path, "%s/scaling.csv", dir);
    FILE *csv = fopen(path, "w");
    snprintf(path, sizeof path, "%s/scaling_fit.gp", dir);
    FILE *gp = fopen(path, "w");
    snprintf(path, sizeof path, "%s/scaling.md", dir);
    FILE *md = fopen(path, "w");
    if (!csv || !gp || !md) return 1;
    fprintf(csv, "series,x,pixels,build_ms,total_ms\n");
    fprintf(gp, "# written by tests/bench/scaling.c: time = exp(b) * x^a, least squares on log-log\n");
    fprintf(md, "## Scaling (tests/bench/scaling.c)\n\n"
                "Time of road grid build (\"road work\") and of grid build + splat to RGBA (\"total\"), medians of %d "
                "runs, against one scene parameter at a time. Slopes are least-squares fits of log time on log x "
                "(1 = linear, 2 = quadratic, 0 = flat); the texel series is expected near 2 (pixels grow as T^2) "
                "and map size near 2 in the DEM side (pixels and roads grow with the area).\n\n"
                "![scaling](bench/scaling.png)\n\n"
                "| series | scene | x | slope, road work | slope, total | total ms: last / first row |\n|---|---|---|---|---|---|\n",
            RUNS);
    double slope_total[4], slope_build[4];
    for (int k = 0; k < 4; k++) {
        double ab, bb, at, bt;
        fit(&S[k], 0, &ab, &bb);
        fit(&S[k], 1, &at, &bt);
        slope_build[k] = ab;
        slope_total[k] = at;
        fprintf(gp, "a_%s_build = %.6f\nb_%s_build = %.6f\na_%s_total = %.6f\nb_%s_total = %.6f\n", S[k].name, ab,
                S[k].name, bb, S[k].name, at, S[k].name, bt);
        for (int i = 0; i < S[k].n; i++)
            fprintf(csv, "%s,%g,%.0f,%.4f,%.4f\n", S[k].name, S[k].s[i].x, S[k].s[i].pixels, S[k].s[i].build_ms,
                    S[k].s[i].total_ms);
        fprintf(md, "| %s | %s | %s %g..%g | %.2f | %.2f | %.2f (x grows %.0fx) |\n", S[k].name, S[k].what, S[k].xname,
                S[k].s[0].x, S[k].s[S[k].n - 1].x, ab, at, S[k].s[S[k].n - 1].total_ms / S[k].s[0].total_ms,
                S[k].s[S[k].n - 1].x / S[k].s[0].x);
    }
    fprintf(md, "\nMeasured rows (ratios to the first row of each series):\n\n"
                "| series | x | pixels | road work ms | ratio | total ms | ratio |\n|---|---|---|---|---|---|---|\n");
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < S[k].n; i++) {
            const sample *s = &S[k].s[i];
            fprintf(md, "| %s | %g | %.0f | %.2f | %.2f | %.1f | %.2f |\n", S[k].name, s->x, s->pixels, s->build_ms,
                    s->build_ms / S[k].s[0].build_ms, s->total_ms, s->total_ms / S[k].s[0].total_ms);
        }
    const series *tx = &S[3];
    double local = log(tx->s[tx->n - 1].total_ms / tx->s[tx->n - 2].total_ms) / log(tx->s[tx->n - 1].x / tx->s[tx->n - 2].x);
    fprintf(md, "\nConclusions (ratios and slopes from this run):\n\n"
                "- Total time follows the output pixels: map-size slope %.2f in the DEM side, i.e. %.2f in pixels "
                "(1 = proportional). Over texels 1..8 the slope is %.2f because per-scene costs (road grid, "
                "alpha-maps) dominate at T = 1-2; between the last two rows (T %g -> %g) it is %.2f (2 = proportional "
                "to pixels).\n"
                "- Road work grows with road length (slope %.2f) and road count (slope %.2f), i.e. with the road "
                "area, while the total on the same map barely moves (slopes %.2f and %.2f; %gx longer road: total "
                "x%.2f): terrain pixels, not roads, dominate the total on these maps.\n",
            slope_total[0], slope_total[0] / 2, slope_total[3], tx->s[tx->n - 2].x, tx->s[tx->n - 1].x, local,
            slope_build[1], slope_build[2], slope_total[1], slope_total[2], S[1].s[S[1].n - 1].x / S[1].s[0].x,
            S[1].s[S[1].n - 1].total_ms / S[1].s[0].total_ms);
    fclose(csv);
    fclose(gp);
    fclose(md);
    rs_ctx_free(ctx);
    printf("scaling bench: slopes total map %.2f, texels %.2f; road work length %.2f, count %.2f\n", slope_total[0],
           slope_total[3], slope_build[1], slope_build[2]);
    return 0;
}
