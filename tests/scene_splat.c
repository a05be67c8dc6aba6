#include "scene_splat.h"
#include "seams.h"
#include "timing.h"

#include <stdlib.h>
#include <string.h>

rs_roads *ss_roads(rs_ctx *ctx, const sc_scene *s)
{
    rs_roads *roads = NULL;
    if (rs_roads_create(ctx, &roads) != RS_OK) return NULL;
    for (size_t i = 0; i < s->nroads; i++)
        if (rs_roads_add(ctx, roads, NULL, s->roads[i].width, s->roads[i].xy, s->roads[i].n) != RS_OK) {
            rs_roads_free(ctx, roads);
            return NULL;
        }
    return roads;
}

/* sc (made) as a DEM of z-scale 0.01 and its roads, classed when asked */
static int city_rs(rs_ctx *ctx, const sc_scene *sc, int classes, rs_dem **dem, rs_roads **roads)
{
    rs_dem_frame fr = { sc->cell_size, 0.01, 0, 0 };
    *roads = ss_roads(ctx, sc);
    if (!*roads || rs_dem_create(ctx, sc->w, sc->h, sc->z, dem) || rs_dem_set_frame(ctx, *dem, &fr)) return -1;
    for (size_t i = 0; classes && i < sc->nroads; i++)
        if (rs_roads_set_attr(ctx, *roads, i, "class", sc_city_class(sc->roads[i].width))) return -1;
    return 0;
}

int ss_city(rs_ctx *ctx, sc_scene *sc, rs_dem **dem, rs_roads **roads)
{
    *dem = NULL;
    *roads = NULL;
    return sc_city_default(sc, 1) ? -1 : city_rs(ctx, sc, 0, dem, roads);
}

int ss_city_of(rs_ctx *ctx, uint32_t w, uint32_t h, size_t n, uint64_t seed, int classes, sc_scene *sc, rs_dem **dem,
               rs_roads **roads)
{
    *dem = NULL;
    *roads = NULL;
    return sc_city(sc, w, h, 5.0, n, seed) ? -1 : city_rs(ctx, sc, classes, dem, roads);
}

rs_roads *ss_crowded_road(rs_ctx *ctx, size_t n, double length, const char *cls)
{
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_roads *R = sc_road_crowded(&sc, 10, 16, length, n, 6) ? NULL : ss_roads(ctx, &sc);
    sc_scene_free(&sc);
    if (R && cls && rs_roads_set_attr(ctx, R, 0, "class", cls)) {
        rs_roads_free(ctx, R);
        R = NULL;
    }
    return R;
}

int ss_fractal_road(rs_ctx *ctx, rs_dem **dem, rs_roads **roads)
{
    const uint32_t W = 1025;
    float *z = malloc(sizeof(float) * W * W);
    if (!z) return -1;
    sc_dem_fractal(z, W, W, 5, 0.5);
    double xy[4] = { 500, 500, 550, 518.5 };
    rs_dem_frame fr = { 0, 0.01, 0, 0 };
    *dem = NULL;
    *roads = NULL;
    int bad = rs_dem_create(ctx, W, W, z, dem) || rs_dem_set_frame(ctx, *dem, &fr) || rs_roads_create(ctx, roads) ||
              rs_roads_add(ctx, *roads, NULL, 6, xy, 2);
    free(z);
    return bad ? -1 : 0;
}

void ss_image_free(ss_image *im)
{
    free(im->rgba);
    free(im->wt);
    memset(im, 0, sizeof *im);
}

rs_result ss_splat(rs_ctx *ctx, const sc_scene *s, const rs_splat_options *opts, int seam, ss_image *out)
{
    return ss_splat_z(ctx, s, opts, 0, seam, out);
}

rs_result ss_splat_z(rs_ctx *ctx, const sc_scene *s, const rs_splat_options *opts, double z_scale, int seam,
                     ss_image *out)
{
    memset(out, 0, sizeof *out);
    rs_splat_options o = *opts;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_road_grid *g = NULL;
    rs_dem_frame fr = { s->cell_size, z_scale, 0, 0 };
    rs_result r = rs_dem_create(ctx, s->w, s->h, s->z, &dem);
    if (!r) r = rs_dem_set_frame(ctx, dem, &fr);
    if (!r) r = (roads = ss_roads(ctx, s)) ? RS_OK : RS_ERR_NOMEM;
    if (!r) r = rs_splat_size(ctx, dem, &o, &out->w, &out->h);
    if (!r) r = rs_road_grid_build(ctx, dem, roads, &o, &g);
    if (!r && seam) out->seam = rs_test_seam_error(g, 32);
    if (!r) {
        size_t n = (size_t)out->w * out->h;
        out->rgba = malloc(n * 4);
        out->wt = malloc(n * sizeof *out->wt);
        r = out->rgba && out->wt ? rs_splat(ctx, dem, g, &o, out->rgba, n * 4, out->wt, n) : RS_ERR_NOMEM;
    }
    rs_road_grid_free(ctx, g);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    if (r) ss_image_free(out);
    return r;
}

rs_result ss_splat_window(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *opts,
                          uint32_t *w, uint32_t *h, uint8_t **rgba)
{
    rs_splatter *s = NULL;
    *rgba = NULL;
    *w = *h = 0;
    rs_result r = rs_splatter_create(ctx, dem, roads, NULL, opts, &s);
    if (!r) {
        rs_splatter_size(s, w, h);
        *rgba = malloc((size_t)*w * *h * 4);
        r = *rgba ? rs_splat_window(ctx, s, 0, 0, *w, *h, *rgba, (size_t)*w * 4, NULL, 0, NULL) : RS_ERR_NOMEM;
    }
    rs_splatter_free(ctx, s);
    return r;
}

rs_result ss_grid_image(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *grid, const rs_splat_options *opts,
                        ss_image *out)
{
    rs_splatter *s = NULL;
    memset(out, 0, sizeof *out);
    rs_result r = rs_splatter_create(ctx, dem, NULL, grid, opts, &s);
    if (!r) {
        rs_splatter_size(s, &out->w, &out->h);
        out->rgba = malloc((size_t)out->w * out->h * 4);
        out->wt = malloc((size_t)out->w * out->h * 2);
        r = out->rgba && out->wt ? rs_splat_window(ctx, s, 0, 0, out->w, out->h, out->rgba, (size_t)out->w * 4,
                                                   out->wt, out->w, NULL)
                                 : RS_ERR_NOMEM;
    }
    rs_splatter_free(ctx, s);
    if (r) ss_image_free(out);
    return r;
}

rs_dem *ss_fractal_dem(rs_ctx *ctx, uint32_t w, uint32_t h, uint64_t seed, double cs, double zs)
{
    float *z = malloc(sizeof(float) * w * h);
    rs_dem *dem = NULL;
    rs_dem_frame fr = { cs, zs, 0, 0 };
    if (z) sc_dem_fractal(z, w, h, seed, 0.5);
    if (!z || rs_dem_create(ctx, w, h, z, &dem) || rs_dem_set_frame(ctx, dem, &fr)) {
        rs_dem_free(ctx, dem);
        dem = NULL;
    }
    free(z);
    return dem;
}

void *ss_build_run(void *job)
{
    ss_build_job *j = job;
    rs_ctx *c = NULL;
    double t0 = tm_thread_cpu_ms();
    j->ok = rs_ctx_create(NULL, NULL, &c) == RS_OK && rs_road_grid_build(c, j->dem, j->roads, j->o, &j->g) == RS_OK;
    j->ms = tm_thread_cpu_ms() - t0;
    rs_ctx_free(c);
    return NULL;
}
