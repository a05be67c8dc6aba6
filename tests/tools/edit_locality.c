/* edit_locality [D [MODE]]: how local is a grid's picture? (issue 30
 * target 3, docs/embedding.md "Toward an update in proportion to the
 * edit"). On the 10k-road city of tests/bench/edits.c (classes by width:
 * casings, lines, dashes, automatic markings; T = 4), for three boxes of
 * the map: builds a grid from only the roads within D metres of the box
 * (default 30) and, with MODE 1, also every road of a stroke that one
 * of them is in (docs/network.md) and the roads within 30 m of those
 * roads' end points; with MODE 2, the roads within D alone with the whole
 * map's network (rs__road_grid_build_subset: the strokes' arc lengths and
 * order). Splats the box's pixels from it and from the grid of all roads,
 * and counts the pixels that differ. Also the two builds' thread CPU
 * time. */
#include "roadsplat.h"
#include "internal.h"
#include "network.h"
#include "scene_splat.h"
#include "scenes.h"
#include "timing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Distance from the box to segment a-b, from points 0.25 m apart on it
 * (enough for a test of metres; a segment crossing the box has one inside). */
static double seg_box_dist(double ax, double ay, double bx, double by, double x0, double y0, double x1, double y1)
{
    double len = hypot(bx - ax, by - ay), best = INFINITY;
    int n = (int)(len / 0.25) + 1;
    for (int i = 0; i <= n; i++) {
        double t = (double)i / n, x = ax + t * (bx - ax), y = ay + t * (by - ay);
        double dx = x < x0 ? x0 - x : x > x1 ? x - x1 : 0, dy = y < y0 ? y0 - y : y > y1 ? y - y1 : 0;
        double d = sqrt(dx * dx + dy * dy);
        if (d < best) best = d;
    }
    return best;
}

/* Distance from the box to the polyline of n points. */
static double road_box_dist(const double *xy, size_t n, double x0, double y0, double x1, double y1)
{
    double best = n == 1 ? seg_box_dist(xy[0], xy[1], xy[0], xy[1], x0, y0, x1, y1) : INFINITY;
    for (size_t k = 0; k + 1 < n; k++) {
        double d = seg_box_dist(xy[2 * k], xy[2 * k + 1], xy[2 * k + 2], xy[2 * k + 3], x0, y0, x1, y1);
        if (d < best) best = d;
    }
    return best;
}

int main(int argc, char **argv)
{
    double D = argc > 1 ? atof(argv[1]) : 30;
    int mode = argc > 2 ? atoi(argv[2]) : 0, strokes = mode == 1, whole_net = mode == 2;
    rs_ctx *ctx = NULL;
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    if (rs_ctx_create(NULL, NULL, &ctx) || ss_city_of(ctx, 400, 350, 10000, 1, 1, &sc, &dem, &roads)) return 1;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    rs_road_grid *g = NULL;
    rs_splatter *s = NULL;
    rs_network *net = NULL;
    double t0 = tm_thread_cpu_ms();
    if (rs_road_grid_build(ctx, dem, roads, &o, &g)) goto fail;
    double full_ms = tm_thread_cpu_ms() - t0;
    if (rs_splatter_create(ctx, dem, NULL, g, &o, &s) || rs_network_build(ctx, roads, NULL, &net)) goto fail;
    rs__grid_facts facts;
    rs__grid_facts_of(g, &facts);
    /* (the strokes' bases once, as an update's network has them: not in each box's build time) */
    if (!(net->s_base = malloc(sc.nroads * sizeof *net->s_base))) return 1;
    rs__stroke_bases(net, roads, dem->frame.origin_x, dem->frame.origin_y, dem->frame.cell_size, NULL, 0,
                     net->s_base);
    unsigned char *in = calloc(sc.nroads, 1);
    if (!in) return 1;
    const double pix = 5.0 / 4, boxes[][4] = { { 800, 700, 1000, 900 }, { 300, 300, 400, 420 }, { 1500, 1000, 1700, 1300 } };
    printf("roads within %.0f m of the box%s; full grid build %.1f ms\n", D,
           strokes ? ", their strokes and the roads near those roads' ends" : "", full_ms);
    for (int b = 0; b < 3; b++) {
        const double *B = boxes[b];
        memset(in, 0, sc.nroads);
        for (size_t i = 0; i < sc.nroads; i++) {
            const double *xy;
            size_t n;
            rs_roads_get(roads, i, NULL, NULL, &xy, &n);
            if (road_box_dist(xy, n, B[0], B[1], B[2], B[3]) <= D) in[i] = 1;
        }
        for (size_t i = 0; strokes && i < sc.nroads; i++)
            if (in[i] == 1)
                for (uint32_t e = net->stroke_start[net->stroke_of[i]]; e < net->stroke_start[net->stroke_of[i] + 1]; e++)
                    if (!in[net->stroke_roads[e]]) in[net->stroke_roads[e]] = 2;
        for (size_t i = 0; strokes && i < sc.nroads; i++) {
            if (in[i] != 2) continue;
            const double *xy;
            size_t n;
            rs_roads_get(roads, i, NULL, NULL, &xy, &n);
            for (int q = 0; q < 2; q++) {
                double ex = xy[q ? 2 * n - 2 : 0], ey = xy[q ? 2 * n - 1 : 1];
                for (size_t j = 0; j < sc.nroads; j++) {
                    const double *xj;
                    size_t nj;
                    rs_roads_get(roads, j, NULL, NULL, &xj, &nj);
                    if (!in[j] && road_box_dist(xj, nj, ex - 30, ey - 30, ex + 30, ey + 30) == 0) in[j] = 3;
                }
            }
        }
        rs_roads *sub = NULL;
        rs_road_grid *gs = NULL;
        rs_splatter *ss = NULL;
        uint32_t *ids = malloc(sc.nroads * sizeof *ids);
        size_t nsub = 0;
        if (!ids) return 1;
        for (size_t i = 0; i < sc.nroads; i++)
            if (in[i]) ids[nsub++] = (uint32_t)i;
        if (rs__roads_subset(ctx, roads, ids, nsub, &sub)) goto fail;
        t0 = tm_thread_cpu_ms();
        if (whole_net ? rs__road_grid_build_subset(ctx, dem, roads, &o, net, &facts, ids, nsub, &gs)
                      : rs_road_grid_build(ctx, dem, sub, &o, &gs))
            goto fail;
        free(ids);
        double sub_ms = tm_thread_cpu_ms() - t0;
        if (rs_splatter_create(ctx, dem, NULL, gs, &o, &ss)) goto fail;
        uint32_t x0 = (uint32_t)(B[0] / pix), y0 = (uint32_t)(B[1] / pix), w = (uint32_t)((B[2] - B[0]) / pix),
                 h = (uint32_t)((B[3] - B[1]) / pix);
        uint8_t *a = malloc((size_t)w * h * 4), *c = malloc((size_t)w * h * 4);
        if (!a || !c || rs_splat_window(ctx, s, x0, y0, w, h, a, (size_t)w * 4, NULL, 0, NULL) ||
            rs_splat_window(ctx, ss, x0, y0, w, h, c, (size_t)w * 4, NULL, 0, NULL))
            goto fail;
        size_t diff = 0;
        int maxd = 0;
        for (size_t i = 0; i < (size_t)w * h; i++) {
            int d = 0;
            for (int ch = 0; ch < 4; ch++) {
                int e = abs(a[4 * i + ch] - c[4 * i + ch]);
                d = e > d ? e : d;
            }
            diff += d != 0;
            maxd = d > maxd ? d : maxd;
        }
        printf("box %d (%.0f x %.0f m): %zu of %zu roads, grid built in %.1f ms (%.1f %% of the full build); "
               "%zu of %u pixels differ (by up to %d)\n",
               b, B[2] - B[0], B[3] - B[1], nsub, sc.nroads, sub_ms, 100 * sub_ms / full_ms, diff, w * h, maxd);
        free(a);
        free(c);
        rs_splatter_free(ctx, ss);
        rs_road_grid_free(ctx, gs);
        rs_roads_free(ctx, sub);
    }
    free(in);
    rs_network_free(ctx, net);
    rs_splatter_free(ctx, s);
    rs_road_grid_free(ctx, g);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
    return 0;
fail:
    fprintf(stderr, "edit_locality: %s\n", rs_ctx_message(ctx));
    return 1;
}
