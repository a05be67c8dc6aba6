/* The GPU export (issue 30, docs/embedding.md "The GPU side"), one thread,
 * same run: on the city unstyled and with classes (lines, casings,
 * automatic markings), the road grid's build, rs_gpu_scene_create from the
 * roads and rs_gpu_scene_from_grid from that grid (the same bytes), and
 * what the grid keeps for the export. Times: this thread's CPU time,
 * median of RUNS, the two exports interleaved run by run.
 * Usage: gpu_export OUTDIR   (writes OUTDIR/gpu_export.md and .csv) */
#include "roadsplat.h"
#include "scene_splat.h"
#include "timing.h"

#include <stdio.h>
#include <string.h>

#define RUNS 15

typedef struct row {
    const char *name;
    double grid_ms, create_ms, from_grid_ms;
    uint64_t grid_bytes;
    size_t scene_bytes, bands, marks;
} row;

static int measure(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, row *out)
{
    double g[RUNS], c[RUNS], f[RUNS];
    rs_road_grid *grid = NULL;
    for (int k = 0; k < RUNS; k++) {
        rs_road_grid *gr = NULL;
        rs_gpu_scene *a = NULL, *b = NULL;
        double t0 = tm_thread_cpu_ms();
        if (rs_road_grid_build(ctx, dem, roads, NULL, &gr)) return -1;
        g[k] = tm_thread_cpu_ms() - t0;
        if (!grid) grid = gr;
        t0 = tm_thread_cpu_ms();
        if (rs_gpu_scene_create(ctx, dem, roads, NULL, NULL, &a)) return -1;
        c[k] = tm_thread_cpu_ms() - t0;
        t0 = tm_thread_cpu_ms();
        if (rs_gpu_scene_from_grid(ctx, dem, roads, grid, NULL, &b)) return -1;
        f[k] = tm_thread_cpu_ms() - t0;
        rs_gpu_scene_info ia;
        rs_gpu_scene_get_info(a, &ia);
        out->scene_bytes = ia.bytes;
        out->bands = ia.nbands;
        out->marks = ia.nmarks;
        rs_gpu_scene_free(ctx, a);
        rs_gpu_scene_free(ctx, b);
        if (gr != grid) rs_road_grid_free(ctx, gr);
    }
    rs_road_grid_stats st;
    rs_road_grid_get_stats(grid, &st);
    out->grid_bytes = st.bytes;
    rs_road_grid_free(ctx, grid);
    out->grid_ms = tm_median(g, RUNS);
    out->create_ms = tm_median(c, RUNS);
    out->from_grid_ms = tm_median(f, RUNS);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc != 2) { fprintf(stderr, "usage: gpu_export OUTDIR\n"); return 2; }
    rs_ctx *ctx;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    sc_scene sc;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    row rows[2];
    memset(rows, 0, sizeof rows);
    rows[0].name = "city, unstyled";
    rows[1].name = "city, classes by width";
    int bad = ss_city(ctx, &sc, &dem, &roads) || measure(ctx, dem, roads, &rows[0]);
    for (size_t i = 0; !bad && i < sc.nroads; i++)
        bad = rs_roads_set_attr(ctx, roads, i, "class", sc_city_class(sc.roads[i].width)) != RS_OK;
    if (!bad) bad = measure(ctx, dem, roads, &rows[1]);
    if (bad) fprintf(stderr, "gpu_export: %s\n", rs_ctx_message(ctx));
    FILE *md = NULL, *csv = NULL;
    if (!bad && !(bad = tm_open_section(argv[1], "gpu_export", &md, &csv))) {
        fprintf(md, "## The GPU export from the roads and from the road grid (issue 30)\n\n"
                    "tests/bench/gpu_export.c: the city (%zu roads, 400 x 350 DEM of 5 m cells); this thread's CPU\n"
                    "time, median of %d runs, the two exports interleaved. `rs_gpu_scene_from_grid` reads the\n"
                    "styles, line cuts and markings the grid resolved (the same bytes as `rs_gpu_scene_create`).\n\n"
                    "| scene | grid build ms | grid MB | create ms | from grid ms | from grid / create | scene MB | lines | markings |\n"
                    "|---|---|---|---|---|---|---|---|---|\n",
                rs_roads_count(roads), RUNS);
        fprintf(csv, "scene,grid_ms,grid_bytes,create_ms,from_grid_ms,scene_bytes,bands,marks\n");
        for (int k = 0; k < 2; k++) {
            const row *r = &rows[k];
            fprintf(md, "| %s | %.1f | %.2f | %.1f | %.1f | %.2f | %.2f | %zu | %zu |\n", r->name, r->grid_ms,
                    r->grid_bytes / 1e6, r->create_ms, r->from_grid_ms, r->from_grid_ms / r->create_ms,
                    r->scene_bytes / 1e6, r->bands, r->marks);
            fprintf(csv, "%s,%.3f,%llu,%.3f,%.3f,%zu,%zu,%zu\n", r->name, r->grid_ms,
                    (unsigned long long)r->grid_bytes, r->create_ms, r->from_grid_ms, r->scene_bytes, r->bands,
                    r->marks);
        }
        bad = fclose(md) != 0;
        bad |= fclose(csv) != 0;
    }
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
    return bad ? 1 : 0;
}
