/* A tests/scenes.h scene run through the library: its roads as rs_roads, and
 * the whole splat (DEM, road grid, RGBA and weights). Kept apart from
 * scenes.c, which must not depend on the library it is used to measure. */
#ifndef RS_TESTS_SCENE_SPLAT_H
#define RS_TESTS_SCENE_SPLAT_H
#include "roadsplat.h"
#include "scenes.h"

/* The scene's roads (unnamed), or NULL when the library refuses one. */
rs_roads *ss_roads(rs_ctx *ctx, const sc_scene *s);
/* The city (sc_city_default(sc, 1)) as a DEM (z-scale 0.01: its heights
 * are centimetres) and its roads: 0, or -1 when a step fails (the caller
 * frees what is not NULL, and sc with sc_scene_free). */
int ss_city(rs_ctx *ctx, sc_scene *sc, rs_dem **dem, rs_roads **roads);
/* The same for sc_city(sc, w, h, 5 m cells, n roads, seed), its roads
 * classed by width (sc_city_class) when `classes`: the edits' cities. */
int ss_city_of(rs_ctx *ctx, uint32_t w, uint32_t h, size_t n, uint64_t seed, int classes, sc_scene *sc, rs_dem **dem,
               rs_roads **roads);
/* One crowded road (sc_road_crowded): n points from (10, 16) over `length`
 * metres along x, 6 m wide, of class `cls` (NULL: unstyled); NULL when the
 * library refuses it. */
rs_roads *ss_crowded_road(rs_ctx *ctx, size_t n, double length, const char *cls);

/* The kernel benchmarks' scene (tests/bench/kernel.c, texels.c): the
 * 1025^2 fractal of tests/bench/sparse.c (sc_dem_fractal seed 5,
 * roughness 0.5, 1 m cells, z-scale 0.01) and one 50 m road, 6 m wide.
 * 0, or -1 when the library refuses it. */
int ss_fractal_road(rs_ctx *ctx, rs_dem **dem, rs_roads **roads);

/* A w x h DEM of sc_dem_fractal(seed, roughness 0.5) with cell size cs
 * and z-scale zs; NULL when a step fails. */
rs_dem *ss_fractal_dem(rs_ctx *ctx, uint32_t w, uint32_t h, uint64_t seed, double cs, double zs);

typedef struct ss_image {
    uint32_t w, h;
    uint8_t *rgba;  /* w*h*4, malloc'd */
    uint16_t *wt;   /* w*h road weights, malloc'd */
    double seam;    /* seam error of the road grid (when asked for) */
} ss_image;

/* Splat scene `s` with `opts` (cell_size taken from the scene); with `seam`,
 * also measure the grid's seam error. On failure *out is zeroed. */
rs_result ss_splat(rs_ctx *ctx, const sc_scene *s, const rs_splat_options *opts, int seam, ss_image *out);
/* The same with the DEM's z-scale (0 = 1). */
rs_result ss_splat_z(rs_ctx *ctx, const sc_scene *s, const rs_splat_options *opts, double z_scale, int seam,
                     ss_image *out);
void ss_image_free(ss_image *im);
/* The whole splat of `roads` over `dem` through a splatter (one window):
 * *rgba malloc'd, w x h pixels; on failure *rgba may be NULL or partial. */
rs_result ss_splat_window(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *opts,
                          uint32_t *w, uint32_t *h, uint8_t **rgba);
/* The whole splat (RGBA and weights) of a prepared grid through a
 * splatter (one window); on failure *out is zeroed. */
rs_result ss_grid_image(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *grid, const rs_splat_options *opts,
                        ss_image *out);
/* A whole grid built on a thread of its own (docs/embedding.md "Long
 * chains": a worker's build from a copy of the roads). Give dem, roads and
 * o; ss_build_run (a pthread start routine) makes g on a context of its
 * own (the caller's to free), ok 1 when it did, ms its thread's CPU time. */
typedef struct ss_build_job {
    const rs_dem *dem;
    const rs_roads *roads;
    const rs_splat_options *o;
    rs_road_grid *g;
    double ms;
    int ok;
} ss_build_job;
void *ss_build_run(void *job);
#endif
