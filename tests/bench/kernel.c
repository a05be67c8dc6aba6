/* Splat kernel speed, one thread: rs_splat_window over the whole image on a
 * prepared splatter (the road grid or field is built once, outside the
 * timing), fastest of RUNS, against a plain RGBA fill of the same image in
 * the same run; the procedural and textured runs of a scene alternate. Scenes: the 1025^2 fractal of tests/bench/sparse.c (one
 * short road) and the city scene of tests/bench/splat.c, both at 4 texels,
 * procedural terrain and a tiled terrain texture. Stage times come from
 * rs_splat_profile.
 * Usage: kernel OUTDIR      (writes OUTDIR/kernel.md and kernel.csv)
 *        kernel OUTDIR once [CASE] (each case, or only case CASE 0..3, once,
 *                                   no files: for callgrind) */
#include "roadsplat.h"
#include "scene_splat.h"
#include "scenes.h"
#include "timing.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RUNS 7

typedef struct kcase {
    const char *name;
    int index;
    double ms, fill_ms, cov, surf, comp;
    uint32_t w, h;
} kcase;

static double clock_ms(void *user)
{
    (void)user;
    return tm_now_ms();
}

static int only_case = -1;

/* One whole-image window of splatter s into rgba, after a fill of the same
 * buffer; keeps the fastest of each in k. */
static int run_once(rs_ctx *ctx, const rs_splatter *s, uint8_t *rgba, int i, int profile, kcase *k)
{
    size_t n = (size_t)k->w * k->h;
    double t0 = tm_now_ms();
    uint32_t px = 0x11223344u + (uint32_t)i, *p32 = (uint32_t *)(void *)rgba;
    for (size_t j = 0; j < n; j++) p32[j] = px;
    double t = tm_now_ms() - t0;
    if (t < k->fill_ms) k->fill_ms = t;
    rs_splat_profile pf;
    memset(&pf, 0, sizeof pf);
    pf.clock_ms = clock_ms;
    t0 = tm_now_ms();
    if (rs_splat_window(ctx, s, 0, 0, k->w, k->h, rgba, (size_t)k->w * 4, NULL, 0, profile ? &pf : NULL)) return -1;
    t = tm_now_ms() - t0;
    if (t < k->ms) {
        k->ms = t;
        k->cov = pf.coverage_ms;
        k->surf = pf.surface_ms;
        k->comp = pf.composite_ms;
    }
    return 0;
}

/* Fastest of `runs` whole-image windows, and of the fill of the same buffer,
 * for the two option sets of one scene (procedural and textured terrain):
 * their runs alternate, so that a busy machine slows both alike and their
 * ratio holds. */
static int measure(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options o[2], int runs,
                   kcase k[2])
{
    rs_splatter *s[2] = { NULL, NULL };
    int use[2], rc = -1;
    uint8_t *rgba = NULL;
    for (int c = 0; c < 2; c++) {
        use[c] = only_case < 0 || only_case == k[c].index;
        k[c].ms = k[c].fill_ms = 1e300;
        if (use[c]) {
            if (rs_splatter_create(ctx, dem, roads, NULL, &o[c], &s[c])) goto done;
            rs_splatter_size(s[c], &k[c].w, &k[c].h);
        }
    }
    if (!use[0] && !use[1]) return 0;
    rgba = malloc((size_t)k[use[0] ? 0 : 1].w * k[use[0] ? 0 : 1].h * 4);
    if (!rgba) goto done;
    for (int i = 0; i < runs; i++)
        for (int c = 0; c < 2; c++)
            if (use[c] && run_once(ctx, s[c], rgba, i, runs > 1, &k[c])) goto done;
    rc = 0;
done:
    free(rgba);
    for (int c = 0; c < 2; c++) rs_splatter_free(ctx, s[c]);
    return rc;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "build/bench";
    int once = argc > 2 && !strcmp(argv[2], "once"), runs = once ? 1 : RUNS;
    int only = once && argc > 3 ? atoi(argv[3]) : -1;
    rs_ctx *ctx;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    const uint32_t TS = 256;
    uint8_t *tex = malloc((size_t)TS * TS * 4);
    if (!tex) return 1;
    for (size_t i = 0; i < (size_t)TS * TS * 4; i++) tex[i] = (uint8_t)(i * 2654435761u >> 24);
    rs_image img = { TS, TS, tex };
    kcase ks[4];
    memset(ks, 0, sizeof ks);
    only_case = only;
    for (int i = 0; i < 4; i++) ks[i].index = i;
    ks[0].name = "1025^2 fractal, procedural terrain";
    ks[1].name = "1025^2 fractal, terrain texture";
    ks[2].name = "city scene, procedural terrain";
    ks[3].name = "city scene, terrain texture";

    /* the fractal of tests/bench/sparse.c: one 50 m road, 6 m wide */
    rs_dem *dem;
    rs_roads *roads;
    if (ss_fractal_road(ctx, &dem, &roads)) return 1;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    rs_splat_options oo[2] = { o, o };
    oo[1].surface.terrain_texture = &img;
    if (measure(ctx, dem, roads, oo, runs, &ks[0])) return 1;
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);

    /* the city scene of tests/bench/splat.c */
    sc_scene sc;
    if (sc_city_default(&sc, 1) || rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) || rs_roads_create(ctx, &roads))
        return 1;
    for (size_t i = 0; i < sc.nroads; i++)
        if (rs_roads_add(ctx, roads, NULL, sc.roads[i].width, sc.roads[i].xy, sc.roads[i].n)) return 1;
    rs_dem_frame fc = { sc.cell_size, 0.01, 0, 0 };
    if (rs_dem_set_frame(ctx, dem, &fc)) return 1;
    if (measure(ctx, dem, roads, oo, runs, &ks[2])) return 1;
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    free(tex);
    rs_ctx_free(ctx);
    if (once) return 0;

    FILE *md, *csv;
    if (tm_open_section(dir, "kernel", &md, &csv)) return 1;
    fprintf(md, "## Splat kernel, one thread (tests/bench/kernel.c)\n\n"
                "`rs_splat_window` over the whole image on a prepared splatter (road grid built once, not timed), RGBA "
                "only, one thread; fastest of %d runs, the procedural and textured runs of a scene alternating. \"Ratio to fill\" = time of a plain RGBA fill of the same buffer "
                "(fastest of %d, interleaved) / splat time. Stage columns: coverage, surface and composite ms of the "
                "fastest run (rs_splat_profile). Scenes at 4 texels: the 1025^2 fractal of the sparse benchmark (one "
                "50 m road) and `sc_city_default(1)` (z-scale 0.01); the terrain texture is 256 x 256.\n\n"
                "| scene | pixels | ms | Mpixel/s | ratio to fill | coverage ms | surface ms | composite ms |\n"
                "|---|---|---|---|---|---|---|---|\n",
            RUNS, RUNS);
    fprintf(csv, "scene,pixels,ms,fill_ms,coverage_ms,surface_ms,composite_ms\n");
    for (int i = 0; i < 4; i++) {
        const kcase *k = &ks[i];
        double np = (double)k->w * k->h;
        fprintf(md, "| %s | %u x %u | %.1f | %.1f | %.4f | %.1f | %.1f | %.1f |\n", k->name, k->w, k->h, k->ms,
                np / (k->ms * 1e3), k->fill_ms / k->ms, k->cov, k->surf, k->comp);
        fprintf(csv, "\"%s\",%.0f,%.3f,%.3f,%.3f,%.3f,%.3f\n", k->name, np, k->ms, k->fill_ms, k->cov, k->surf, k->comp);
    }
    const double tf = ks[1].ms / ks[0].ms, tcity = ks[3].ms / ks[2].ms;
    fprintf(md, "\nTextured / procedural terrain time (same run): fractal %.2fx, city %.2fx.\n\n", tf, tcity);
    fprintf(md, "| target (issue 18, 3) | measured | |\n|---|---|---|\n"
                "| the textured terrain path within 1.3x of the procedural one | fractal %.2fx, city %.2fx | %s |\n",
            tf, tcity, tf <= 1.3 && tcity <= 1.3 ? "met" : "**missed**");
    fclose(md);
    fclose(csv);
    printf("kernel bench: fractal %.1f ms (%.4f of fill), city %.1f ms (%.4f of fill); textured/procedural %.2f, %.2f\n",
           ks[0].ms, ks[0].fill_ms / ks[0].ms, ks[2].ms, ks[2].fill_ms / ks[2].ms, ks[1].ms / ks[0].ms,
           ks[3].ms / ks[2].ms);
    return 0;
}
