/* Sparse work: time and memory follow what the scene contains.
 * - one short road vs no road on a 1025^2 DEM at 4 texels per cell (issue 5
 *   target: ratio <= 1.05);
 * - road work (grid build) and grid memory against road length and width on
 *   a fixed map: they should grow with length x width, not with the map.
 * Usage: sparse OUTDIR (writes OUTDIR/sparse.md). */
#include "roadsplat.h"
#include "scenes.h"
#include "timing.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RUNS 5

static rs_roads *make_roads(rs_ctx *ctx, int count, double length, double width, double cx, double cy)
{
    rs_roads *r = NULL;
    if (rs_roads_create(ctx, &r)) return NULL;
    for (int i = 0; i < count; i++) {
        double y = cy + 8.0 * i, xy[4] = { cx, y, cx + length, y + 0.37 * length };
        if (rs_roads_add(ctx, r, NULL, width, xy, 2)) { rs_roads_free(ctx, r); return NULL; }
    }
    return r;
}

/* Median time of grid build + splat (or grid build only), and grid bytes. */
static int measure(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o, uint8_t *rgba,
                   size_t n, int splat, double *ms, double *build_ms, uint64_t *bytes)
{
    double t[RUNS], tb[RUNS];
    for (int i = 0; i < RUNS; i++) {
        rs_road_grid *g = NULL;
        double t0 = tm_now_ms();
        if (rs_road_grid_build(ctx, dem, roads, o, &g)) return -1;
        tb[i] = tm_now_ms() - t0;
        if (splat && rs_splat(ctx, dem, g, o, rgba, n * 4, NULL, 0)) return -1;
        t[i] = tm_now_ms() - t0;
        rs_grid_stats st;
        rs_road_grid_stats(g, &st);
        *bytes = st.bytes;
        rs_road_grid_free(ctx, g);
    }
    *ms = tm_median(t, RUNS);
    *build_ms = tm_median(tb, RUNS);
    return 0;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "build/bench";
    char path[1024];
    rs_ctx *ctx;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    const uint32_t W = 1025;
    float *z = malloc(sizeof(float) * W * W);
    if (!z) return 1;
    sc_dem_fractal(z, W, W, 5, 0.5);
    rs_dem *dem;
    if (rs_dem_create(ctx, W, W, z, &dem)) return 1;
    free(z);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    o.z_scale = 0.01;
    uint32_t w, h;
    if (rs_splat_size(ctx, dem, &o, &w, &h)) return 1;
    size_t n = (size_t)w * h;
    uint8_t *rgba = malloc(n * 4);
    if (!rgba) return 1;
    snprintf(path, sizeof path, "%s/sparse.md", dir);
    FILE *md = fopen(path, "w");
    if (!md) return 1;

    rs_roads *none = make_roads(ctx, 0, 0, 0, 0, 0), *one = make_roads(ctx, 1, 50, 6, 500, 500);
    double t_none, t_one, b0, b1;
    uint64_t m0, m1;
    /* interleave the two so drift hits both alike */
    if (measure(ctx, dem, none, &o, rgba, n, 1, &t_none, &b0, &m0) ||
        measure(ctx, dem, one, &o, rgba, n, 1, &t_one, &b1, &m1))
        return 1;
    double t_none2;
    if (measure(ctx, dem, none, &o, rgba, n, 1, &t_none2, &b0, &m0)) return 1;
    if (t_none2 < t_none) t_none = t_none2;
    fprintf(md, "## Sparse work: cost follows the scene\n\n"
                "1025 x 1025 DEM (1 m cells), 4 texels per cell: %u x %u pixels. Times are grid build + splat, "
                "medians of %d runs.\n\n| scene | ms | ratio to no road | grid memory (bytes) |\n|---|---|---|---|\n"
                "| no road | %.1f | 1 | %llu |\n| one 50 m road, 6 m wide | %.1f | %.3f | %llu |\n\n",
            w, h, RUNS, t_none, (unsigned long long)m0, t_one, t_one / t_none, (unsigned long long)m1);

    fprintf(md, "Road work (grid build only) and grid memory against road length x width on the same map "
                "(ratios to the first row; proportional growth would match the area ratio):\n\n"
                "| roads x length x width | area ratio | build ms | build ratio | memory ratio |\n|---|---|---|---|---|\n");
    const struct { int count; double len, width; } rows[] = {
        { 1, 100, 6 }, { 1, 200, 6 }, { 1, 400, 6 }, { 1, 400, 12 }, { 4, 400, 12 }, { 16, 400, 12 },
    };
    double base_b = 0, base_area = 0;
    uint64_t base_m = 0;
    for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        rs_roads *r = make_roads(ctx, rows[i].count, rows[i].len, rows[i].width, 100, 100);
        double t, b;
        uint64_t m;
        if (!r || measure(ctx, dem, r, &o, rgba, n, 0, &t, &b, &m)) return 1;
        double area = rows[i].count * rows[i].len * rows[i].width;
        if (i == 0) { base_b = b; base_area = area; base_m = m; }
        fprintf(md, "| %d x %.0f m x %.0f m | %.1f | %.2f | %.2f | %.2f |\n", rows[i].count, rows[i].len, rows[i].width,
                area / base_area, b, b / base_b, (double)m / (double)base_m);
        rs_roads_free(ctx, r);
    }
    fprintf(md, "\nGrid memory includes the tile directory (fixed per map) and the 4 KiB tiles that roads touch.\n");
    fclose(md);
    printf("sparse bench: one road / no road = %.3f\n", t_one / t_none);
    rs_roads_free(ctx, none);
    rs_roads_free(ctx, one);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    free(rgba);
    return 0;
}
