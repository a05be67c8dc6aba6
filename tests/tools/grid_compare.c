/* Before/after comparison of road grids (issue 19: the row-sweep marker of
 * lib/scene/roadgrid.c must give byte-identical grids). Prints, per grid, the
 * build result, k, road-cell count and an FNV-1a hash of every classified
 * tile and the stats, over the tests/scenes.c cities (both buffer modes,
 * automatic and explicit road cells) and 150 random scenes (thin to wide
 * roads, arcs, roads leaving the map, repeated points, short wiggles).
 * Not run by `make test` (tests/test_*.c compare the images too), only
 * built there so it keeps compiling; `make build/tools/grid_compare` in two
 * trees, run both and diff the outputs. */
#include "roadsplat.h"
#include "roadgrid.h"
#include "scenes.h"
#include <stdio.h>
#include <string.h>
#include <math.h>
#include <time.h>

static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const unsigned char *c = p;
    for (size_t i = 0; i < n; i++) { h ^= c[i]; h *= 1099511628211ull; }
    return h;
}

static rs_ctx *ctx;
static int nscenes;
static double total_ms;

static void run(const char *name, sc_scene *s, int mode, uint32_t texels, double road_cell)
{
    rs_dem *dem; rs_roads *roads;
    rs_dem_frame fr = { s->cell_size, 1, 0, 0 };
    if (rs_dem_create(ctx, s->w, s->h, s->z, &dem)) { printf("%s dem fail\n", name); return; }
    if (rs_dem_set_frame(ctx, dem, &fr)) { printf("%s frame fail\n", name); rs_dem_free(ctx, dem); return; }
    rs_roads_create(ctx, &roads);
    for (size_t i = 0; i < s->nroads; i++) rs_roads_add(ctx, roads, NULL, s->roads[i].width, s->roads[i].xy, s->roads[i].n);
    rs_splat_options o; memset(&o, 0, sizeof o);
    o.grid.buffer = (rs_buffer_mode)mode; o.texels = texels; o.grid.road_cell = road_cell;
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* the cell grid is built for alpha-map edges only */
    rs_road_grid *g = NULL;
    struct timespec t0, t1; clock_gettime(CLOCK_MONOTONIC, &t0);
    rs_result r = rs_road_grid_build(ctx, dem, roads, &o, &g);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    total_ms += (t1.tv_sec - t0.tv_sec) * 1e3 + (t1.tv_nsec - t0.tv_nsec) / 1e6;
    uint64_t h = 1469598103934665603ull;
    if (!r) {
        for (size_t i = 0; i < (size_t)g->tw * g->th; i++) {
            h = fnv(h, &i, sizeof i);
            if (g->tiles[i]) h = fnv(h, g->tiles[i], RS__TILE * RS__TILE);
        }
        h = fnv(h, &g->stats, sizeof g->stats);
    }
    printf("%s mode %d T %u rc %g: r=%d k=%u cells=%llu hash=%016llx\n", name, mode, texels, road_cell, r,
           g ? g->k : 0, g ? (unsigned long long)g->stats.road_cells : 0ull, (unsigned long long)h);
    nscenes++;
    rs_road_grid_free(ctx, g); rs_roads_free(ctx, roads); rs_dem_free(ctx, dem);
}

static void all_modes(const char *name, sc_scene *s)
{
    const uint32_t T[3] = { 1, 4, 8 };
    for (int m = 0; m < 2; m++) {
        for (int t = 0; t < 3; t++) run(name, s, m, T[t], 0);
        run(name, s, m, 4, s->cell_size / 3.0);
        run(name, s, m, 4, s->cell_size / 17.0);
    }
}

int main(void)
{
    rs_ctx_create(NULL, NULL, &ctx);
    char name[64];
    for (uint64_t seed = 1; seed <= 3; seed++) {
        sc_scene s;
        sc_city(&s, 120, 100, 5.0, 150, seed);
        snprintf(name, sizeof name, "city%llu", (unsigned long long)seed);
        all_modes(name, &s);
        sc_scene_free(&s);
    }
    {
        sc_scene s; sc_city_default(&s, 7); run("citydefault", &s, 0, 8, 0); run("citydefault", &s, 1, 8, 0); sc_scene_free(&s);
    }
    sc_rng rng; sc_rng_seed(&rng, 12345);
    for (int it = 0; it < 150; it++) {
        uint32_t W = 2 + (uint32_t)(sc_rng_u64(&rng) % 60), H = 2 + (uint32_t)(sc_rng_u64(&rng) % 60);
        double cs = pow(10.0, sc_rng_range(&rng, -2, 2));
        sc_scene s; sc_scene_init(&s, W, H, cs);
        sc_dem_fractal(s.z, W, H, it, 0.5);
        double X = sc_extent_x(&s), Y = sc_extent_y(&s);
        int nr = 1 + (int)(sc_rng_u64(&rng) % 5);
        for (int q = 0; q < nr; q++) {
            int kind = (int)(sc_rng_u64(&rng) % 5);
            double w = cs * pow(10.0, sc_rng_range(&rng, -1.5, 1.3));
            if (kind == 0) sc_road_straight(&s, sc_rng_range(&rng, 0, 6.3), sc_rng_range(&rng, 0.1, 3) * (X + Y), w);
            else if (kind == 1) sc_road_arc(&s, X * sc_rng_unit(&rng), Y * sc_rng_unit(&rng), (X + Y) * sc_rng_range(&rng, 0.05, 0.5), 0, sc_rng_range(&rng, 0.5, 7), w, 2 + sc_rng_u64(&rng) % 40);
            else if (kind == 2) sc_road_leaving(&s, sc_rng_range(&rng, 0, 6.3), w, sc_rng_range(&rng, 0, X));
            else {
                double xy[40]; size_t n = 1 + sc_rng_u64(&rng) % 20;
                for (size_t k = 0; k < n; k++) {
                    xy[2 * k] = sc_rng_range(&rng, -0.3, 1.3) * X; xy[2 * k + 1] = sc_rng_range(&rng, -0.3, 1.3) * Y;
                    if (kind == 4 && k) { xy[2 * k] = xy[2 * k - 2] + sc_rng_range(&rng, -2, 2) * cs; xy[2 * k + 1] = xy[2 * k - 1] + sc_rng_range(&rng, -2, 2) * cs; }
                    if (sc_rng_u64(&rng) % 7 == 0 && k) { xy[2 * k] = xy[2 * k - 2]; xy[2 * k + 1] = xy[2 * k - 1]; }
                }
                if (n == 1) { xy[2] = xy[0]; xy[3] = xy[1]; n = 2; }
                sc_add_road(&s, w, xy, n);
            }
        }
        snprintf(name, sizeof name, "rand%d", it);
        for (int m = 0; m < 2; m++) {
            uint32_t T = 1 + (uint32_t)(sc_rng_u64(&rng) % 8);
            run(name, &s, m, T, 0);
            run(name, &s, m, T, cs / (1 + (double)(sc_rng_u64(&rng) % 40)));
        }
        sc_scene_free(&s);
    }
    fprintf(stderr, "%d grids, %.1f ms building\n", nscenes, total_ms);
    rs_ctx_free(ctx);
    return 0;
}
