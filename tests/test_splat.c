/* End to end through the library: road grid + splat on synthetic scenes. */
#include "harness.h"
#include "fail_alloc.h"
#include "roadsplat.h"
#include "mask.h"
#include "seams.h"
#include "scenes.h"
#include "groundtruth.h"
#include "scene_splat.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;

static rs_dem *flat_dem(uint32_t w, uint32_t h)
{
    float *z = malloc(sizeof(float) * w * h);
    for (uint32_t i = 0; i < w * h; i++) z[i] = (float)((i * 7919u) % 50);
    rs_dem *d = NULL;
    CHECK(rs_dem_create(ctx, w, h, z, &d) == RS_OK);
    free(z);
    return d;
}

typedef struct image {
    uint32_t w, h;
    uint8_t *rgba;
    uint16_t *wt;
} image;

static rs_result splat(rs_ctx *c, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o, image *im)
{
    rs_road_grid *g = NULL;
    memset(im, 0, sizeof *im);
    rs_result r = rs_splat_size(c, dem, o, &im->w, &im->h);
    if (r) return r;
    r = rs_road_grid_build(c, dem, roads, o, &g);
    if (r) return r;
    size_t n = (size_t)im->w * im->h;
    im->rgba = malloc(n * 4);
    im->wt = malloc(n * 2);
    r = rs_splat(c, dem, g, o, im->rgba, n * 4, im->wt, n);
    rs_road_grid_free(c, g);
    return r;
}

static void image_free(image *im)
{
    free(im->rgba);
    free(im->wt);
}

/* Drawn width (true width times drawn area over exact area) and edge error
 * of a straight road through (cx, cy) at angle th, inside the window
 * [m0, m1]^2 (metres) away from the map edge. Exact coverage by 16x16
 * supersampling on pixels near the edges. */
static void straight_error(const image *im, double px_m, double cx, double cy, double th, double width, double m0,
                           double m1, double *drawn_width, double *edge_err)
{
    double nx = -sin(th), ny = cos(th), area_r = 0, area_g = 0, err = 0;
    uint32_t p0 = (uint32_t)(m0 / px_m), p1 = (uint32_t)(m1 / px_m);
    for (uint32_t py = p0; py < p1; py++)
        for (uint32_t px = p0; px < p1; px++) {
            double dc = fabs(((px + 0.5) * px_m - cx) * nx + ((py + 0.5) * px_m - cy) * ny), g = 0;
            if (dc < width / 2 - 0.75 * px_m) g = 1;
            else if (dc <= width / 2 + 0.75 * px_m)
                for (int sy = 0; sy < 16; sy++)
                    for (int sx = 0; sx < 16; sx++) {
                        double x = (px + (sx + 0.5) / 16) * px_m, y = (py + (sy + 0.5) / 16) * px_m;
                        if (fabs((x - cx) * nx + (y - cy) * ny) <= width / 2) g += 1.0 / 256;
                    }
            double r = im->wt[(size_t)py * im->w + px] / 65535.0;
            area_r += r;
            area_g += g;
            err += fabs(r - g) * px_m * px_m;
        }
    /* outline length inside the window = twice the centreline length there */
    *drawn_width = width * area_r / area_g;
    *edge_err = err / (2 * area_g * px_m * px_m / width);
}

static rs_roads *one_road(double x0, double y0, double x1, double y1, double width)
{
    rs_roads *r = NULL;
    CHECK(rs_roads_create(ctx, &r) == RS_OK);
    double xy[4] = { x0, y0, x1, y1 };
    CHECK(rs_roads_add(ctx, r, "r", width, xy, 2) == RS_OK);
    return r;
}

/* Straight roads at many angles and lattice offsets: the drawn edge is
 * unbiased (mean drawn width = true width) and close (edge error). A road at
 * 45 degrees meets the lattice at one phase along its whole length, so the
 * bias is checked on the mean over offsets and the error on each. */
static void test_straight_roads(void)
{
    rs_dem *dem = flat_dem(41, 41);
    const double angles[] = { 0, 10, 22.5, 30, 45, 60, 77, 90, 135 };
    const double c = 0.25; /* road cell */
    for (int mode = 0; mode < 2; mode++)
        for (size_t a = 0; a < sizeof angles / sizeof angles[0]; a++) {
            double th = angles[a] * 3.14159265358979 / 180, width = 6, sum_w = 0, worst_e = 0;
            const int offsets = 8;
            /* shift along the normal over one period of the lattice phase */
            double l1 = fabs(cos(th)) + fabs(sin(th)), period = fabs(l1 - sqrt(2.0)) < 1e-9 ? c / sqrt(2.0) : c;
            for (int k = 0; k < offsets; k++) {
                double sh = period * (k + 0.5) / offsets, cx = 20.0 - sin(th) * sh, cy = 20.0 + cos(th) * sh;
                rs_roads *roads = one_road(cx - 60 * cos(th), cy - 60 * sin(th), cx + 60 * cos(th), cy + 60 * sin(th), width);
                rs_splat_options o;
                memset(&o, 0, sizeof o);
                o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
                o.texels = 4;
                o.grid.buffer = mode ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
                o.grid.road_cell = c;
                image im;
                CHECK(splat(ctx, dem, roads, &o, &im) == RS_OK);
                double dw, ee;
                straight_error(&im, 0.25, cx, cy, th, width, 8, 32, &dw, &ee);
                sum_w += dw;
                if (ee > worst_e) worst_e = ee;
                image_free(&im);
                rs_roads_free(ctx, roads);
            }
            /* distance: unbiased, each edge within c/2 of the truth (the
             * axis-aligned worst case). dilate: the band is a whole number k of
             * cells, so each side may be off by half a step, (|nx|+|ny|) c / 2. */
            double step = (fabs(cos(th)) + fabs(sin(th))) * c;
            double tol_w = mode ? step + 0.03 : 0.03, tol_e = mode ? 0.5 * step + 0.5 * c : 0.51 * c;
            CHECKF(fabs(sum_w / offsets - width) <= tol_w, "%s %.1f deg: mean drawn width %.4f m, true %.1f",
                   mode ? "dilate" : "distance", angles[a], sum_w / offsets, width);
            CHECKF(worst_e <= tol_e, "%s %.1f deg: edge error %.4f m", mode ? "dilate" : "distance", angles[a], worst_e);
        }
    rs_dem_free(ctx, dem);
}

static void test_determinism_and_sparsity(void)
{
    rs_dem *dem = flat_dem(33, 25);
    rs_roads *roads = NULL, *none = NULL;
    const char text[] =
        "road a width 5\n2 3\n20 14\n31 9\nend\n"
        "road b width 3.5\n-5 20\n12 20.3\n12 2\nend\n"
        "road loop width 2.5\n25 18\n29 18\n29 22\n25 22\n25 18\nend\n";
    CHECK(rs_roads_parse(ctx, text, sizeof text - 1, &roads) == RS_OK);
    CHECK(rs_roads_create(ctx, &none) == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
    o.texels = 6;
    image a, b, c;
    CHECK(splat(ctx, dem, roads, &o, &a) == RS_OK);
    CHECK(splat(ctx, dem, roads, &o, &b) == RS_OK);
    CHECK(splat(ctx, dem, none, &o, &c) == RS_OK);
    size_t n = (size_t)a.w * a.h;
    CHECK(a.w == 32 * 6 && a.h == 24 * 6);
    CHECK(memcmp(a.rgba, b.rgba, n * 4) == 0);
    CHECK(memcmp(a.wt, b.wt, n * 2) == 0);
    /* Where the weight is 0 the pixel is exactly the road-free terrain; no
     * pixel of the road-free splat carries road weight. */
    size_t differ = 0, full = 0, partial = 0, empty_w = 0;
    for (size_t i = 0; i < n; i++) {
        if (a.wt[i] == 0 && memcmp(a.rgba + 4 * i, c.rgba + 4 * i, 4)) differ++;
        if (a.wt[i] == 65535) full++;
        else if (a.wt[i]) partial++;
        if (c.wt[i]) empty_w++;
    }
    CHECK_EQ_INT(differ, 0);
    CHECK_EQ_INT(empty_w, 0);
    CHECK(full > 1000 && partial > 100);
    /* Fully covered pixels carry no terrain: they equal the asphalt whatever
     * the terrain beneath (a different DEM gives the same road pixels). */
    rs_dem *dem2 = NULL;
    float *z = malloc(sizeof(float) * 33 * 25);
    for (int i = 0; i < 33 * 25; i++) z[i] = (float)(1000 - i);
    CHECK(rs_dem_create(ctx, 33, 25, z, &dem2) == RS_OK);
    free(z);
    image d;
    CHECK(splat(ctx, dem2, roads, &o, &d) == RS_OK);
    size_t road_differ = 0;
    for (size_t i = 0; i < n; i++)
        if (a.wt[i] == 65535 && memcmp(a.rgba + 4 * i, d.rgba + 4 * i, 4)) road_differ++;
    CHECK_EQ_INT(road_differ, 0);
    image_free(&a);
    image_free(&b);
    image_free(&c);
    image_free(&d);
    rs_dem_free(ctx, dem2);
    rs_roads_free(ctx, roads);
    rs_roads_free(ctx, none);
    rs_dem_free(ctx, dem);
}

/* A road leaving the map: no border at the map edge, full weight there. */
static void test_road_leaving_map(void)
{
    rs_dem *dem = flat_dem(21, 21);
    rs_roads *roads = one_road(5, 10.3, 40, 10.3, 6);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
    o.texels = 4;
    image im;
    CHECK(splat(ctx, dem, roads, &o, &im) == RS_OK);
    /* right-most column: rows well inside the road are full road */
    int bad = 0;
    for (uint32_t py = (uint32_t)(8.0 * 4); py < (uint32_t)(12.5 * 4); py++)
        if (im.wt[(size_t)py * im.w + im.w - 1] != 65535) bad++;
    CHECK_EQ_INT(bad, 0);
    image_free(&im);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
}

static void test_scene_seams(void)
{
    rs_dem *dem = flat_dem(30, 30);
    rs_roads *roads = NULL;
    const char text[] =
        "road a width 4\n1 1\n28 27\nend\nroad b width 2.2\n3 25\n26 4\n20 20\nend\n"
        "road c width 7\n0 15\n29 14\nend\nroad d width 0.9\n10 2\n11 28\nend\n";
    CHECK(rs_roads_parse(ctx, text, sizeof text - 1, &roads) == RS_OK);
    for (int mode = 0; mode < 2; mode++) {
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
        o.texels = 2;
        o.grid.road_cell = 0.5;
        o.grid.buffer = mode ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
        rs_road_grid *g = NULL;
        CHECK(rs_road_grid_build(ctx, dem, roads, &o, &g) == RS_OK);
        rs_road_grid_stats st;
        rs_road_grid_get_stats(g, &st);
        CHECK(st.k == 2 && st.boundary_cells > 100 && st.by_type[RS_TILE_OUTER] > 0 && st.by_type[RS_TILE_INNER] > 0);
        CHECK_EQ_INT(st.road_cells, st.interior_cells + st.boundary_cells);
        double seam = rs_test_seam_error(g, 32);
        CHECKF(seam <= 1.0 / 255, "scene seam error %g", seam);
        rs_road_grid_free(ctx, g);
    }
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
}

/* Synthetic scenes from tests/scenes.c measured with the exact ruler
 * (tests/groundtruth.c): arcs, a junction grid, a road leaving the map, and a
 * straight road. Edges within half a road cell, seams exact, and on curved
 * and oblique roads at most half the error of a perfect hard raster. */
static void scene_vs_truth(const char *name, sc_scene *sc, unsigned T, double max_ratio)
{
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    CHECK(rs_dem_create(ctx, sc->w, sc->h, sc->z, &dem) == RS_OK);
    rs_dem_frame fr = { sc->cell_size, 0, 0, 0 };
    CHECK(rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    for (size_t i = 0; i < sc->nroads; i++)
        CHECK(rs_roads_add(ctx, roads, NULL, sc->roads[i].width, sc->roads[i].xy, sc->roads[i].n) == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
    o.texels = T;
    image im;
    CHECK(splat(ctx, dem, roads, &o, &im) == RS_OK);
    size_t n = (size_t)im.w * im.h;
    float *R = malloc(n * sizeof *R), *H = malloc(n * sizeof *H);
    for (size_t i = 0; i < n; i++) R[i] = im.wt[i] / 65535.0f;
    gt_result ours, hard;
    CHECK(gt_edge_error(sc, T, R, &ours) == 0);
    CHECK(gt_hard_raster(sc, T, H) == 0);
    CHECK(gt_edge_error(sc, T, H, &hard) == 0);
    if (max_ratio > 0)
        CHECKF(ours.edge_error <= max_ratio * hard.edge_error, "%s: edge error %.4f m vs hard raster %.4f m", name,
               ours.edge_error, hard.edge_error);
    rs_road_grid *g = NULL;
    CHECK(rs_road_grid_build(ctx, dem, roads, &o, &g) == RS_OK);
    rs_road_grid_stats st;
    rs_road_grid_get_stats(g, &st);
    /* every drawn edge lies within half a road cell of the true one */
    CHECKF(ours.edge_error <= 0.5 * st.road_cell, "%s: edge error %.4f m, road cell %.4f m", name, ours.edge_error,
           st.road_cell);
    double seam = rs_test_seam_error(g, 32);
    CHECKF(seam <= 1.0 / 255, "%s: seam error %g", name, seam);
    rs_road_grid_free(ctx, g);
    free(R);
    free(H);
    image_free(&im);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
}

static void test_scenes(void)
{
    sc_scene sc;
    CHECK(sc_scene_init(&sc, 61, 51, 2.0) == 0);
    sc_dem_fractal(sc.z, sc.w, sc.h, 3, 0.5);
    CHECK(sc_road_arc(&sc, 60, 50, 30, 0.2, 4.0, 5.0, 96) == 0);
    CHECK(sc_road_arc(&sc, 50, 45, 12, 0, 6.2831853, 3.0, 128) == 0);
    scene_vs_truth("arcs", &sc, 4, 0.5);
    sc_scene_free(&sc);

    CHECK(sc_scene_init(&sc, 61, 51, 2.0) == 0);
    CHECK(sc_road_grid(&sc, 4, 3, 6.0, 10) == 0);
    CHECK(sc_road_leaving(&sc, 0.7, 5.0, 30) == 0);
    /* axis-aligned streets: a hard raster's best case, so no ratio here */
    scene_vs_truth("junction grid", &sc, 4, 0);
    sc_scene_free(&sc);

    CHECK(sc_scene_init(&sc, 41, 41, 1.0) == 0);
    CHECK(sc_road_straight(&sc, 0.3, 200, 4.0) == 0);
    scene_vs_truth("straight", &sc, 8, 0.5);
    sc_scene_free(&sc);
}

/* User textures: a solid terrain texture gives exactly its colour where no
 * road is; a two-colour road texture tiles with the texture scale. */
static void test_textures(void)
{
    rs_dem *dem = flat_dem(17, 17);
    rs_roads *roads = one_road(-5, 8.2, 30, 8.2, 6);
    uint8_t solid[4 * 4 * 4];
    for (int i = 0; i < 16; i++) { solid[4 * i] = 10; solid[4 * i + 1] = 200; solid[4 * i + 2] = 30; solid[4 * i + 3] = 255; }
    uint8_t stripes[2 * 1 * 4] = { 255, 0, 0, 255, 0, 0, 255, 255 };
    rs_image ti = { 4, 4, solid }, ri = { 2, 1, stripes };
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
    o.texels = 4;
    o.surface.terrain_texture = &ti;
    o.surface.road_texture = &ri;
    o.surface.texture_scale = 4;
    image im;
    CHECK(splat(ctx, dem, roads, &o, &im) == RS_OK);
    size_t n = (size_t)im.w * im.h, terrain_ok = 1, road_px = 0, red = 0, blue = 0;
    for (size_t i = 0; i < n; i++) {
        const uint8_t *p = im.rgba + 4 * i;
        if (im.wt[i] == 0 && !(p[0] == 10 && p[1] == 200 && p[2] == 30 && p[3] == 255)) terrain_ok = 0;
        if (im.wt[i] == 65535) {
            road_px++;
            if (p[0] > 200 && p[2] < 60) red++;
            if (p[2] > 200 && p[0] < 60) blue++;
        }
    }
    CHECK(terrain_ok);
    CHECK(road_px > 100);
    /* wrap-around bilinear stripes, 2 m each: both colours present in bulk */
    CHECK(red > road_px / 5 && blue > road_px / 5);
    image_free(&im);
    rs_image empty = { 0, 0, NULL };
    o.surface.road_texture = &empty;
    uint32_t w, h;
    CHECK(rs_splat_size(ctx, dem, &o, &w, &h) == RS_ERR_INVALID_ARG);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
}

/* A tilted plane shades the same everywhere, map edges included: two cells
 * with the same corner heights get the same colour (regression: the first
 * row once read the last row as its northern neighbour). */
static void test_plane_shading(void)
{
    float z[12 * 9];
    for (int r = 0; r < 9; r++)
        for (int c = 0; c < 12; c++) z[r * 12 + c] = (float)(3 * c + 2 * r);
    rs_dem *dem = NULL;
    rs_roads *none = NULL;
    CHECK(rs_dem_create(ctx, 12, 9, z, &dem) == RS_OK);
    CHECK(rs_roads_create(ctx, &none) == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
    o.texels = 1;
    image im;
    CHECK(splat(ctx, dem, none, &o, &im) == RS_OK);
    /* cell (row r, col c) has corner heights 3c+2r + {0,3,2,5}: equal for
     * (r, c) and (r - 3k, c + 2k) */
    int differ = 0, pairs = 0;
    for (int r = 0; r < 8; r++)
        for (int c = 0; c < 11; c++)
            for (int k = 1; r - 3 * k >= 0 && c + 2 * k < 11; k++) {
                pairs++;
                if (memcmp(im.rgba + 4 * (r * 11 + c), im.rgba + 4 * ((r - 3 * k) * 11 + c + 2 * k), 3)) differ++;
            }
    CHECK(pairs > 20);
    CHECKF(differ == 0, "%d of %d equal-height cell pairs differ in colour", differ, pairs);
    image_free(&im);
    rs_roads_free(ctx, none);
    rs_dem_free(ctx, dem);
}

/* A scene translated to UTM-like coordinates (and to 10^7 m), written and
 * parsed as text like a user's file, with the origin set to match, gives
 * byte-identical output to the untranslated scene. */
static void test_translation(void)
{
    rs_dem *dem = flat_dem(33, 25);
    const double shifts[3][2] = { { 0, 0 }, { 500000, 5000000 }, { 1e7, 1e7 } };
    image ref;
    memset(&ref, 0, sizeof ref);
    for (int k = 0; k < 3; k++) {
        char text[4096];
        size_t len = 0;
        const double pts[] = { 1.125, 2.375, 13.001, 11.777, 31.9, 7.25, 3.3, 22.05, 29.123, 20.987 };
        len += (size_t)snprintf(text + len, sizeof text - len, "road a width 4.5\n");
        for (int i = 0; i < 3; i++)
            len += (size_t)snprintf(text + len, sizeof text - len, "%.3f %.3f\n", shifts[k][0] + pts[2 * i],
                                    shifts[k][1] + pts[2 * i + 1]);
        len += (size_t)snprintf(text + len, sizeof text - len, "end\nroad b width 2.75\n");
        for (int i = 3; i < 5; i++)
            len += (size_t)snprintf(text + len, sizeof text - len, "%.3f %.3f\n", shifts[k][0] + pts[2 * i],
                                    shifts[k][1] + pts[2 * i + 1]);
        len += (size_t)snprintf(text + len, sizeof text - len, "end\n");
        rs_roads *roads = NULL;
        CHECK(rs_roads_parse(ctx, text, len, &roads) == RS_OK);
        for (int mode = 0; mode < 2; mode++) {
            rs_splat_options o;
            memset(&o, 0, sizeof o);
            o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
            o.texels = 4;
            o.grid.buffer = mode ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
            rs_dem_frame fr = { 0, 0, shifts[k][0], shifts[k][1] };
            CHECK(rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
            image im;
            CHECK(splat(ctx, dem, roads, &o, &im) == RS_OK);
            if (k == 0 && mode == 0) {
                ref = im;
                continue;
            }
            if (mode == 0) {
                size_t n = (size_t)im.w * im.h;
                CHECKF(memcmp(im.rgba, ref.rgba, n * 4) == 0 && memcmp(im.wt, ref.wt, n * 2) == 0,
                       "translation by (%g, %g) changed the output", shifts[k][0], shifts[k][1]);
            }
            image_free(&im);
        }
        rs_roads_free(ctx, roads);
    }
    image_free(&ref);
    rs_dem_frame bad = { 0, 0, NAN, 0 };
    CHECK(rs_dem_set_frame(ctx, dem, &bad) == RS_ERR_INVALID_ARG);
    CHECK(strstr(rs_ctx_message(ctx), "origin") != NULL);
    rs_dem_free(ctx, dem);
}

/* --- two contexts in two threads ----------------------------------------------- */
typedef struct job {
    const char *text;
    image im;
    rs_result r;
} job;

static void *worker(void *arg)
{
    job *j = arg;
    rs_ctx *c = NULL;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    float z[17 * 13];
    for (int i = 0; i < 17 * 13; i++) z[i] = (float)(i % 17);
    j->r = rs_ctx_create(NULL, NULL, &c);
    if (!j->r) j->r = rs_dem_create(c, 17, 13, z, &dem);
    if (!j->r) j->r = rs_roads_parse(c, j->text, strlen(j->text), &roads);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
    if (!j->r) j->r = splat(c, dem, roads, &o, &j->im);
    rs_roads_free(c, roads);
    rs_dem_free(c, dem);
    rs_ctx_free(c);
    return NULL;
}

static void test_threads(void)
{
    const char *text = "road a width 3\n0 0\n16 12\nend\nroad b width 2\n0 12\n16 0\nend\n";
    job jobs[3] = { { text, { 0, 0, 0, 0 }, RS_OK }, { text, { 0, 0, 0, 0 }, RS_OK }, { text, { 0, 0, 0, 0 }, RS_OK } };
    pthread_t th[2];
    worker(&jobs[2]); /* serial reference */
    for (int i = 0; i < 2; i++) pthread_create(&th[i], NULL, worker, &jobs[i]);
    for (int i = 0; i < 2; i++) pthread_join(th[i], NULL);
    size_t n = (size_t)jobs[2].im.w * jobs[2].im.h * 4;
    for (int i = 0; i < 2; i++) {
        CHECK(jobs[i].r == RS_OK);
        CHECK(jobs[i].im.rgba && memcmp(jobs[i].im.rgba, jobs[2].im.rgba, n) == 0);
    }
    for (int i = 0; i < 3; i++) image_free(&jobs[i].im);
}

/* --- allocation failures ----------------------------------------------------------- */

static rs_result alloc_try(rs_ctx *c, void *user, int *wrong)
{
    static const char text[] = "road a width 3\n0 0\n16 12\nend\nroad b width 2\n0 12\n16 0\n3 3\nend\n";
    const float *z = user;
    (void)wrong;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_result r = rs_dem_create(c, 17, 13, z, &dem);
    if (!r) r = rs_roads_parse(c, text, sizeof text - 1, &roads);
    image im = { 0, 0, NULL, NULL };
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
    if (!r) r = splat(c, dem, roads, &o, &im);
    image_free(&im);
    rs_roads_free(c, roads);
    rs_dem_free(c, dem);
    return r;
}

static void test_alloc_failures(void)
{
    float z[17 * 13];
    for (int i = 0; i < 17 * 13; i++) z[i] = (float)(i % 5);
    fail_sweep fs = fail_alloc_sweep(10000, alloc_try, z);
    CHECK_SWEEP(fs, 5);
}

/* Absurd but finite input: far-away points, a huge width, a road that is
 * one repeated point. No crash, no undefined behaviour (the sanitizer suite
 * runs this), and sensible results. */
static void test_extreme_roads(void)
{
    rs_dem *dem = flat_dem(9, 9);
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    double far[4] = { -1e300, 4.1, 1e300, 4.1 }, wide[4] = { 1, 1, 2, 2 }, dot[4] = { 3, 3, 3, 3 };
    CHECK(rs_roads_add(ctx, roads, "far", 2, far, 2) == RS_OK);
    CHECK(rs_roads_add(ctx, roads, "dot", 1, dot, 2) == RS_OK);
    for (int mode = 0; mode < 2; mode++) {
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
        o.texels = 2;
        o.grid.buffer = mode ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
        image im;
        CHECK(splat(ctx, dem, roads, &o, &im) == RS_OK);
        /* the far road still crosses the map at y = 4.1 */
        CHECK(im.wt[(size_t)8 * im.w + 8] == 65535);
        image_free(&im);
    }
    CHECK(rs_roads_add(ctx, roads, "wide", 1e300, wide, 2) == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
    o.texels = 2;
    image im;
    CHECK(splat(ctx, dem, roads, &o, &im) == RS_OK);
    size_t full = 0;
    for (size_t i = 0; i < (size_t)im.w * im.h; i++) full += im.wt[i] == 65535;
    CHECK_EQ_INT(full, (size_t)im.w * im.h); /* covers everything */
    image_free(&im);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
}

static void test_bad_options(void)
{
    rs_dem *dem = flat_dem(9, 9);
    rs_roads *roads = one_road(0, 0, 8, 8, 2);
    rs_splat_options o;
    uint32_t w, h;
    memset(&o, 0, sizeof o);
    rs_dem_frame fr;
    memset(&fr, 0, sizeof fr);
    const double bad_cs[] = { -1, NAN, 1e-310, 5e-324, 1e308, INFINITY };
    for (size_t i = 0; i < sizeof bad_cs / sizeof bad_cs[0]; i++) {
        fr.cell_size = bad_cs[i];
        CHECK(rs_dem_set_frame(ctx, dem, &fr) == RS_ERR_INVALID_ARG);
        CHECK(strstr(rs_ctx_message(ctx), "cell size") != NULL);
    }
    fr.cell_size = 0;
    fr.z_scale = 1e300;
    CHECK(rs_dem_set_frame(ctx, dem, &fr) == RS_ERR_INVALID_ARG);
    CHECK(strstr(rs_ctx_message(ctx), "z-scale") != NULL);
    memset(&o, 0, sizeof o);
    o.surface.texture_scale = 1e-308;
    CHECK(rs_splat_size(ctx, dem, &o, &w, &h) == RS_ERR_INVALID_ARG);
    CHECK(strstr(rs_ctx_message(ctx), "texture scale") != NULL);
    memset(&o, 0, sizeof o);
    o.coverage.transition_px = -1;
    CHECK(rs_splat_size(ctx, dem, &o, &w, &h) == RS_ERR_INVALID_ARG);
    memset(&o, 0, sizeof o);
    o.coverage.edges = (rs_edge_mode)7;
    CHECK(rs_splat_size(ctx, dem, &o, &w, &h) == RS_ERR_INVALID_ARG);
    memset(&o, 0, sizeof o);
    o.coverage.transition_px = 100;
    CHECK(rs_splat_size(ctx, dem, &o, &w, &h) == RS_ERR_INVALID_ARG);
    memset(&o, 0, sizeof o);
    o.coverage.alpha_res = 1;
    rs_road_grid *g = NULL;
    CHECK(rs_road_grid_build(ctx, dem, roads, &o, &g) == RS_ERR_INVALID_ARG && g == NULL);
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP;
    o.grid.road_cell = 1e-9;
    CHECK(rs_road_grid_build(ctx, dem, roads, &o, &g) == RS_ERR_LIMIT && g == NULL);
    /* output limit */
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_pixels = 1000;
    rs_ctx *c2 = NULL;
    CHECK(rs_ctx_create(NULL, &lim, &c2) == RS_OK);
    memset(&o, 0, sizeof o);
    CHECK(rs_splat_size(c2, dem, &o, &w, &h) == RS_ERR_LIMIT);
    rs_ctx_free(c2);
    /* buffer too small */
    CHECK(rs_road_grid_build(ctx, dem, roads, NULL, &g) == RS_OK);
    uint8_t small[16];
    CHECK(rs_splat(ctx, dem, g, NULL, small, sizeof small, NULL, 0) == RS_ERR_BUFFER_TOO_SMALL);
    rs_road_grid_free(ctx, g);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
}

/* A grid built for finer pixels drawn at coarser ones (as the virtual
 * texture's levels do): the splatter indexes the grid's road field anew
 * for its pixel size (rs__roadfield_repixel) instead of searching the
 * cells around each pixel; the bytes are those of a grid built for the
 * coarse pixels, on the city (T ends, crossings, 1000 roads). */
static void test_grid_other_texels(void)
{
    sc_scene sc;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    CHECK(ss_city(ctx, &sc, &dem, &roads) == 0);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 8;
    rs_road_grid *fine = NULL;
    CHECK(rs_road_grid_build(ctx, dem, roads, &o, &fine) == RS_OK);
    for (uint32_t t = 1; t <= 2 && fine; t++) {
        o.texels = t;
        image want, got;
        CHECK(splat(ctx, dem, roads, &o, &want) == RS_OK);
        memset(&got, 0, sizeof got);
        got.w = want.w, got.h = want.h;
        size_t n = (size_t)got.w * got.h;
        got.rgba = malloc(n * 4);
        got.wt = malloc(n * 2);
        CHECK(got.rgba && got.wt && rs_splat(ctx, dem, fine, &o, got.rgba, n * 4, got.wt, n) == RS_OK);
        size_t diff = 0, road = 0;
        for (size_t i = 0; got.rgba && want.rgba && i < n; i++) {
            diff += memcmp(got.rgba + 4 * i, want.rgba + 4 * i, 4) != 0 || got.wt[i] != want.wt[i];
            road += want.wt[i] > 0;
        }
        CHECKF(diff == 0 && road > n / 20, "%u texels on a grid for 8: %zu of %zu pixels differ (%zu road pixels)", t,
               diff, n, road);
        image_free(&want);
        image_free(&got);
    }
    rs_road_grid_free(ctx, fine);
    /* with styles the grid's line symbols, casings and markings are laid out
     * in its pixels: another texel count is refused, not drawn wrong */
    size_t bad = 0;
    for (size_t i = 0; roads && i < rs_roads_count(roads); i++)
        bad += rs_roads_set_attr(ctx, roads, i, "class", sc_city_class(sc.roads[i].width)) != RS_OK;
    CHECK(bad == 0);
    o.texels = 8;
    fine = NULL;
    CHECK(rs_road_grid_build(ctx, dem, roads, &o, &fine) == RS_OK);
    o.texels = 2;
    rs_splatter *sp = NULL;
    CHECK(rs_splatter_create(ctx, dem, NULL, fine, &o, &sp) == RS_ERR_INVALID_ARG && !sp &&
          strstr(rs_ctx_message(ctx), "built for 8 texels, not 2") != NULL);
    o.texels = 8;
    CHECK(rs_splatter_create(ctx, dem, NULL, fine, &o, &sp) == RS_OK && sp);
    rs_splatter_free(ctx, sp);
    rs_road_grid_free(ctx, fine);
    rs_dem_free(ctx, dem);
    rs_roads_free(ctx, roads);
    sc_scene_free(&sc);
}

int main(void)
{
    CHECK(rs_ctx_create(NULL, NULL, &ctx) == RS_OK);
    test_grid_other_texels();
    test_straight_roads();
    test_determinism_and_sparsity();
    test_road_leaving_map();
    test_scene_seams();
    test_scenes();
    test_plane_shading();
    test_textures();
    test_threads();
    test_alloc_failures();
    test_extreme_roads();
    test_translation();
    test_bad_options();
    rs_ctx_free(ctx);
    return th_finish("test_splat");
}
