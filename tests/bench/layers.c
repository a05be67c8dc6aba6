/* Layers (issue 30), one thread, same run: 512 x 512 windows of the city
 * (default class styles: casings, lines, automatic markings; 16 texels a
 * 5 m cell, 0.31 m pixels) through a workspace:
 *  - rs_splat_window_ws (colour and weight): the plain window;
 *  - rs_splat_layers_window with terrain, casing, surface, coverage and
 *    paint (one pass);
 *  - the same with the normal plane too;
 *  - for comparison, the plain window plus rs_normal_window.
 * Times: this thread's CPU time, median of RUNS rounds over the same four
 * windows, the cases interleaved round by round.
 * Usage: layers [OUTDIR]   (writes OUTDIR/layers.md and layers.csv; build/bench by default) */
#include "roadsplat.h"
#include "scene_splat.h"
#include "scenes.h"
#include "timing.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RUNS 15
#define WIN 512u
#define NCASE 4

static const char *const case_name[NCASE] = {
    "plain window (colour + weight)",
    "layers: terrain, casing, surface, coverage, paint",
    "layers: the five + normal",
    "plain window + rs_normal_window",
};

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "build/bench";
    rs_ctx *ctx = NULL;
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_splatter *s = NULL;
    rs_splat_workspace *ws = NULL;
    int rc = 1;
    uint8_t *rgba = NULL, *t = NULL, *c = NULL, *sf = NULL, *p = NULL, *nm = NULL;
    uint16_t *wt = NULL, *cv = NULL;
    if (rs_ctx_create(NULL, NULL, &ctx) || ss_city(ctx, &sc, &dem, &roads)) goto done;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 16;
    if (rs_splatter_create(ctx, dem, roads, NULL, &o, &s) || rs_splat_workspace_create(ctx, s, WIN, &ws)) {
        fprintf(stderr, "layers: %s\n", rs_ctx_message(ctx));
        goto done;
    }
    uint32_t W, H;
    rs_splatter_size(s, &W, &H);
    const size_t n = (size_t)WIN * WIN;
    rgba = malloc(n * 4), t = malloc(n * 4), c = malloc(n * 4), sf = malloc(n * 4), p = malloc(n * 4);
    nm = malloc(n * 3);
    wt = malloc(n * 2), cv = malloc(n * 2);
    if (!rgba || !t || !c || !sf || !p || !nm || !wt || !cv) goto done;
    rs_splat_layers L;
    memset(&L, 0, sizeof L);
    L.terrain = t;
    L.terrain_stride = WIN * 4;
    L.casing = c;
    L.casing_stride = WIN * 4;
    L.surface = sf;
    L.surface_stride = WIN * 4;
    L.coverage = cv;
    L.coverage_stride = WIN;
    L.paint = p;
    L.paint_stride = WIN * 4;
    L.normal_stride = WIN * 3;
    /* four windows in the city's streets */
    const uint32_t wx[4] = { W / 2 - WIN, W / 2, W / 3, 2 * W / 3 - WIN }, wy[4] = { H / 2 - WIN, H / 2, H / 3, H / 4 };
    double ms[NCASE][RUNS];
    for (int run = 0; run < RUNS; run++)
        for (int k = 0; k < NCASE; k++) {
            double t0 = tm_thread_cpu_ms();
            for (int i = 0; i < 4; i++) {
                rs_result r;
                if (k == 0 || k == 3) {
                    r = rs_splat_window_ws(ctx, s, ws, wx[i], wy[i], WIN, WIN, rgba, WIN * 4, wt, WIN, NULL);
                    if (!r && k == 3) r = rs_normal_window(ctx, s, wx[i], wy[i], WIN, WIN, nm, WIN * 3, NULL);
                } else {
                    L.normal = k == 2 ? nm : NULL;
                    r = rs_splat_layers_window(ctx, s, ws, wx[i], wy[i], WIN, WIN, &L, NULL);
                }
                if (r) {
                    fprintf(stderr, "layers: %s\n", rs_ctx_message(ctx));
                    goto done;
                }
            }
            ms[k][run] = (tm_thread_cpu_ms() - t0) / 4;
        }
    FILE *md, *csv;
    if (tm_open_section(dir, "layers", &md, &csv)) goto done;
    double med[NCASE];
    for (int k = 0; k < NCASE; k++) med[k] = tm_median(ms[k], RUNS);
    fprintf(md, "## Layers (tests/bench/layers.c)\n\n");
    fprintf(md, "512 x 512 windows of the city (%u x %u px, 16 texels a 5 m cell, default class styles with "
                "automatic markings) through a workspace, one thread, CPU time per window (median of %d rounds "
                "of four windows, the cases interleaved):\n\n",
            W, H, RUNS);
    fprintf(md, "| case | ms per window | / plain window |\n|---|---|---|\n");
    fprintf(csv, "case,ms,ratio\n");
    for (int k = 0; k < NCASE; k++) {
        fprintf(md, "| %s | %.2f | %.2f |\n", case_name[k], med[k], med[k] / med[0]);
        fprintf(csv, "\"%s\",%.3f,%.3f\n", case_name[k], med[k], med[k] / med[0]);
    }
    fprintf(md, "\n");
    fclose(md);
    fclose(csv);
    for (int k = 0; k < NCASE; k++) printf("layers: %-50s %.2f ms  %.2fx\n", case_name[k], med[k], med[k] / med[0]);
    rc = 0;
done:
    free(rgba);
    free(t);
    free(c);
    free(sf);
    free(p);
    free(nm);
    free(wt);
    free(cv);
    rs_splat_workspace_free(ctx, ws);
    rs_splatter_free(ctx, s);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
    return rc;
}
