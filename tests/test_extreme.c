/* Extreme DEMs (constant, spike, 0/65535 checkerboard, nodata, 2x2,
 * 8193x8193) and a seeded stress run of random scenes. Invariants: the
 * splat's weights are in range and zero away from roads, output is
 * deterministic, seams are exact (<= 1/255), ROAM meshes are valid, finite
 * and within their error bound; library memory stays within a stated bound
 * of the output size (counted through the allocator hook). */
#include "harness.h"
#include "fail_alloc.h"
#include "roadsplat.h"
#include "internal.h"
#include "roam_check.h"
#include "scene_splat.h"
#include "scenes.h"
#include "timing.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static size_alloc mem; /* (live and peak bytes through the ctx hook) */
static rs_ctx *ctx;

/* --- helpers ------------------------------------------------------------------ */

/* Distance from (x, y) to the road's centreline polyline. */
static double centreline_dist(const sc_road *r, double x, double y)
{
    double best = INFINITY;
    for (size_t q = 0; q < r->n; q++) {
        double ax = r->xy[2 * q], ay = r->xy[2 * q + 1];
        double bx = q + 1 < r->n ? r->xy[2 * q + 2] : ax, by = q + 1 < r->n ? r->xy[2 * q + 3] : ay;
        double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy;
        double t = l2 > 0 ? ((x - ax) * dx + (y - ay) * dy) / l2 : 0;
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
        double d = hypot(x - ax - t * dx, y - ay - t * dy);
        if (d < best) best = d;
    }
    return best;
}

/* Weights: opaque output, and zero wherever the texel is clearly away from
 * every road (farther than half the width plus a DEM cell plus a texel
 * diagonal: the road grid and transition band never reach that far). Also
 * some full-road weight when a road is wide enough to have an interior. */
static int check_weights(const sc_scene *s, const ss_image *o, uint32_t T, int dilate, size_t *stray)
{
    double px = s->cell_size / T;
    int ok = 1;
    *stray = 0;
    for (uint32_t y = 0; y < o->h; y++)
        for (uint32_t x = 0; x < o->w; x++) {
            size_t i = (size_t)y * o->w + x;
            if (o->rgba[4 * i + 3] != 255) ok = 0;
            if (!o->wt[i]) continue;
            double cx = (x + 0.5) * px, cy = (y + 0.5) * px, margin = s->cell_size + px;
            int near = 0;
            for (size_t k = 0; k < s->nroads && !near; k++) {
                /* dilate mode (the paper's square dilation) ends roads with
                 * square caps: their corners reach (sqrt 2 - 1) w/2 further */
                double cap = dilate ? (1.4142135623730951 - 1) * 0.5 * s->roads[k].width : 0;
                near = centreline_dist(&s->roads[k], cx, cy) <= 0.5 * s->roads[k].width + cap + margin;
            }
            if (!near) (*stray)++;
        }
    return ok && *stray == 0;
}

typedef struct mesh_check {
    int ok;            /* valid mesh (roam_check.h) with finite vertices */
    double tol;        /* float rounding of heights in metres: 2^-21 of the largest */
    double max_err;    /* measured */
    size_t triangles;
} mesh_check;

/* ROAM at `err` metres: build, extract, check against the DEM (nodata as
 * the library's fill, which the checker ignores). */
static rs_result roam_scene(const float *z, uint32_t W, uint32_t H, double cs, double zs, double err,
                            mesh_check *mc)
{
    memset(mc, 0, sizeof *mc);
    rs_dem *dem = NULL;
    rs_roam *roam = NULL;
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    rs_dem_frame fr = { cs, zs, 0, 0 };
    float *v = NULL;
    uint32_t *idx = NULL;
    rs_result r = rs_dem_create(ctx, W, H, z, &dem);
    if (!r) r = rs_dem_set_frame(ctx, dem, &fr);
    if (!r) r = rs_roam_create(ctx, dem, &o, &roam);
    if (!r) r = rs_roam_refine_error(ctx, roam, err);
    size_t nv = 0, ni = 0;
    if (!r) {
        size_t mv, mi;
        rs_roam_mesh_bound(roam, NULL, &mv, &mi);
        v = malloc((mv + 1) * 5 * sizeof *v);
        idx = malloc((mi + 1) * sizeof *idx);
        r = v && idx ? rs_roam_extract(ctx, roam, NULL, v, NULL, mv, idx, mi, &nv, &ni) : RS_ERR_NOMEM;
    }
    if (!r) {
        int32_t *gx = malloc((nv + 1) * sizeof *gx), *gy = malloc((nv + 1) * sizeof *gy);
        double *vz = malloc((nv + 1) * sizeof *vz);
        float *zf = malloc((size_t)W * H * sizeof *zf);
        int finite = 1;
        if (gx && gy && vz && zf) {
            for (size_t k = 0; k < nv; k++) {
                for (int c = 0; c < 5; c++) finite &= isfinite(v[5 * k + c]) != 0;
                gx[k] = (int32_t)lround(v[5 * k] / cs);
                gy[k] = (int32_t)lround(v[5 * k + 1] / cs);
                vz[k] = v[5 * k + 2];
            }
            double zmax = 0;
            for (size_t k = 0; k < (size_t)W * H; k++) {
                zf[k] = isnan(z[k]) ? z[k] : (float)((double)z[k] * zs);
                if (fabs(zf[k]) > zmax) zmax = fabs(zf[k]);
            }
            /* vertex and DEM heights in metres are floats: a plane of them is
             * planar only to float precision, so a bound of 0 is met to that */
            mc->tol = zmax / 2097152.0;
            rc_result res;
            memset(&res, 0, sizeof res);
            mc->ok = finite && rc_check(W, H, zf, 1.0, gx, gy, vz, nv, idx, ni / 3, &res) && rc_all_ok(&res);
            mc->max_err = res.max_err;
            mc->triangles = ni / 3;
        } else r = RS_ERR_NOMEM;
        free(gx); free(gy); free(vz); free(zf);
    }
    free(v);
    free(idx);
    rs_roam_free(ctx, roam);
    rs_dem_free(ctx, dem);
    return r;
}

/* --- extreme DEMs ------------------------------------------------------------------ */

enum { X_CONST, X_SPIKE, X_CHECKER, X_NODATA, X_ALLNODATA, X_TINY, X_COUNT };
static const char *x_name[X_COUNT] = { "constant", "spike", "checkerboard", "nodata", "all nodata", "2x2" };

static void test_extreme_dems(void)
{
    for (int kind = 0; kind < X_COUNT; kind++) {
        uint32_t W = kind == X_TINY ? 2 : 41, H = kind == X_TINY ? 2 : 33;
        sc_scene s;
        CHECK(sc_scene_init(&s, W, H, 1.0) == 0);
        switch (kind) {
        case X_CONST: sc_dem_constant(s.z, W, H, 65535.0f); break;
        case X_SPIKE: sc_dem_spike(s.z, W, H, 0.0f, 65535.0f, H / 2, W / 3); break;
        case X_CHECKER: sc_dem_checker(s.z, W, H, 1); break;
        case X_NODATA:
            sc_dem_fractal(s.z, W, H, 3, 0.5);
            for (uint32_t i = 0; i < H; i++)
                for (uint32_t j = 0; j < W; j++)
                    if ((i + 2 * j) % 7 == 0 || (j > 10 && j < 20)) s.z[(size_t)i * W + j] = NAN;
            break;
        case X_ALLNODATA: sc_dem_constant(s.z, W, H, NAN); break;
        default: s.z[0] = 0; s.z[1] = 65535; s.z[2] = 1; s.z[3] = 0.5f; break;
        }
        double X = sc_extent_x(&s), Y = sc_extent_y(&s);
        double a[4] = { -0.2 * X, 0.3 * Y, 1.1 * X, 0.7 * Y }, b[6] = { 0.5 * X, -1, 0.45 * X, 0.5 * Y, 0.9 * X, 1.2 * Y };
        CHECK(sc_add_road(&s, kind == X_TINY ? 0.3 : 3.0, a, 2) == 0);
        CHECK(sc_add_road(&s, kind == X_TINY ? 0.2 : 1.5, b, 3) == 0);
        for (int mode = 0; mode < 2; mode++) {
            rs_splat_options o;
            memset(&o, 0, sizeof o);
            o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
            o.grid.buffer = mode ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
            o.texels = 4;
            ss_image r1, r2;
            CHECK(ss_splat(ctx, &s, &o, 1, &r1) == RS_OK);
            CHECK(ss_splat(ctx, &s, &o, 0, &r2) == RS_OK);
            if (!r1.wt || !r2.wt) { ss_image_free(&r1); ss_image_free(&r2); continue; }
            size_t n = (size_t)r1.w * r1.h, stray;
            CHECKF(check_weights(&s, &r1, o.texels, mode, &stray), "%s: %zu stray weights", x_name[kind], stray);
            CHECKF(r1.seam <= 1.0 / 255, "%s: seam %g", x_name[kind], r1.seam);
            CHECK(memcmp(r1.rgba, r2.rgba, n * 4) == 0 && memcmp(r1.wt, r2.wt, n * 2) == 0);
            uint16_t wmax = 0;
            for (size_t i = 0; i < n; i++) if (r1.wt[i] > wmax) wmax = r1.wt[i];
            CHECKF(wmax > 0, "%s: no road drawn", x_name[kind]);
            ss_image_free(&r1);
            ss_image_free(&r2);
        }
        const double errs[3] = { 0.0, 1.0, 1000.0 };
        for (int e = 0; e < 3; e++) {
            mesh_check mc;
            CHECK(roam_scene(s.z, W, H, 1.0, 1.0, errs[e], &mc) == RS_OK);
            CHECKF(mc.ok && mc.max_err <= errs[e] + mc.tol, "%s ROAM at %g: valid %d, error %g", x_name[kind], errs[e], mc.ok,
                   mc.max_err);
        }
        sc_scene_free(&s);
    }
}

/* 8193 x 8193 samples at 1 texel per cell (8192^2 output pixels), two roads.
 * Library memory (allocator hook) beyond the DEM copy must stay a small
 * fraction of the caller's RGBA buffer: the road grid is sparse and the
 * splat works one cell row at a time. */
#if defined(__SANITIZE_ADDRESS__)
#define HUGE_SIDE 2049u /* ~20 s at 8193 under ASan: same test, a quarter the side */
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HUGE_SIDE 2049u
#endif
#endif
#ifndef HUGE_SIDE
#define HUGE_SIDE 8193u
#endif

static void test_huge_dem(void)
{
    const uint32_t N = HUGE_SIDE;
    sc_scene s;
    if (sc_scene_init(&s, N, N, 1.0)) { CHECK(0); return; }
    for (uint32_t i = 0; i < N; i++)
        for (uint32_t j = 0; j < N; j++) s.z[(size_t)i * N + j] = (float)((i * 3u + j * 5u) % 4096u);
    const double f = (N - 1) / 8192.0;
    double a[4] = { 10 * f, 20 * f, 8100 * f, 8000 * f }, b[4] = { 4000 * f, -50 * f, 4100 * f, 8300 * f };
    CHECK(sc_add_road(&s, 6, a, 2) == 0 && sc_add_road(&s, 12, b, 2) == 0);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
    o.texels = 1;
    /* 1x1 textures: no hillshade work, the test is about size and memory */
    static const uint8_t green[4] = { 90, 140, 70, 255 }, grey[4] = { 70, 70, 72, 255 };
    rs_image tt = { 1, 1, green }, rt = { 1, 1, grey };
    o.surface.terrain_texture = &tt;
    o.surface.road_texture = &rt;
    double t0 = (tm_now_ms() / 1000.0);
    size_t base = mem.live;
    mem.peak = mem.live;
    ss_image r;
    CHECK(ss_splat(ctx, &s, &o, 0, &r) == RS_OK);
    double secs = (tm_now_ms() / 1000.0) - t0;
    size_t dem_bytes = (size_t)N * N * sizeof(float), out_bytes = (size_t)(N - 1) * (N - 1) * 4;
    size_t extra = mem.peak - base - dem_bytes;
    printf("%u^2 splat:", N);
    printf(" %.2f s, library peak %.1f MB = DEM copy %.1f MB + %.2f MB (%.3f %% of the %.0f MB RGBA output)\n",
           secs, (mem.peak - base) / 1e6, dem_bytes / 1e6, extra / 1e6, 100.0 * extra / out_bytes, out_bytes / 1e6);
    /* per-row buffers grow with the width; the alpha-map tables (~1 MB) are
     * fixed, which matters for the smaller size used under ASan */
    CHECKF(extra <= out_bytes / 50 + ((size_t)2 << 20), "library memory beyond the DEM: %zu bytes", extra);
    CHECK(mem.live == base);
    if (r.wt) {
        size_t stray;
        CHECK(check_weights(&s, &r, 1, 0, &stray));
        CHECK(r.wt[(size_t)(4000 * f) * r.w + (size_t)(4050 * f)] == 65535); /* on road b's centreline */
    }
    ss_image_free(&r);
    /* ROAM: a 8193 x 5 strip of it always; the whole DEM (about 6 s and
     * 1.4 GB) only with RS_TEST_HUGE_ROAM=1. */
    int full = getenv("RS_TEST_HUGE_ROAM") && atoi(getenv("RS_TEST_HUGE_ROAM"));
    t0 = (tm_now_ms() / 1000.0);
    mem.peak = mem.live;
    mesh_check mc;
    CHECK(roam_scene(s.z, N, full ? N : 5, 1.0, 1.0, 2000.0, &mc) == RS_OK);
    printf("%ux%u ROAM at 2000:", N, full ? N : 5);
    printf(" %.2f s, %zu triangles, error %g, library peak %.1f MB\n", (tm_now_ms() / 1000.0) - t0,
           mc.triangles, mc.max_err, (mem.peak - base) / 1e6);
    CHECK(mc.ok && mc.max_err <= 2000.0);
    sc_scene_free(&s);
}

/* --- stress: random scenes ---------------------------------------------------------- */

static void random_roads(sc_scene *s, sc_rng *r)
{
    double X = sc_extent_x(s), Y = sc_extent_y(s), cs = s->cell_size;
    int nr = 1 + (int)(sc_rng_u64(r) % 7);
    for (int k = 0; k < nr; k++) {
        double w = sc_rng_range(r, 0.3, 12.0) * cs * (sc_rng_u64(r) % 4 == 0 ? 0.2 : 1.0);
        switch (sc_rng_u64(r) % 4) {
        case 0: sc_road_straight(s, sc_rng_range(r, 0, 2 * RS__PI), sc_rng_range(r, 0.1, 1.5) * (X + Y), w); break;
        case 1:
            sc_road_arc(s, sc_rng_range(r, 0, X), sc_rng_range(r, 0, Y), sc_rng_range(r, 1, 0.6 * (X + Y)),
                        sc_rng_range(r, 0, 6.3), sc_rng_range(r, 0, 6.3), w, 2 + (size_t)(sc_rng_u64(r) % 40));
            break;
        case 2: sc_road_leaving(s, sc_rng_range(r, 0, 2 * RS__PI), w, sc_rng_range(r, 0, 50) * cs); break;
        default: {
            double p[16];
            size_t n = 2 + (size_t)(sc_rng_u64(r) % 7);
            for (size_t q = 0; q < n; q++) {
                p[2 * q] = sc_rng_range(r, -0.2 * X, 1.2 * X);
                p[2 * q + 1] = sc_rng_range(r, -0.2 * Y, 1.2 * Y);
                if (q && sc_rng_u64(r) % 5 == 0) { p[2 * q] = p[2 * q - 2]; p[2 * q + 1] = p[2 * q - 1]; }
            }
            sc_add_road(s, w, p, n);
        }
        }
    }
}

static void test_stress(void)
{
    const int SCENES = 50;
    int bad_weights = 0, bad_seams = 0, nondet = 0, bad_mesh = 0;
    double worst_seam = 0, worst_mesh_ratio = 0;
    double t0 = (tm_now_ms() / 1000.0);
    for (int it = 0; it < SCENES; it++) {
        sc_rng r;
        sc_rng_seed(&r, 0x5EED0000u + (uint64_t)it);
        uint32_t W = 2 + (uint32_t)(sc_rng_u64(&r) % 70), H = 2 + (uint32_t)(sc_rng_u64(&r) % 70);
        static const double css[4] = { 0.25, 1, 2.5, 30 };
        sc_scene s;
        if (sc_scene_init(&s, W, H, css[sc_rng_u64(&r) % 4])) { CHECK(0); return; }
        switch (sc_rng_u64(&r) % 4) {
        case 0: sc_dem_fractal(s.z, W, H, (uint64_t)it, sc_rng_range(&r, 0.2, 0.9)); break;
        case 1: sc_dem_checker(s.z, W, H, 1 + (uint32_t)(sc_rng_u64(&r) % 3)); break;
        case 2: sc_dem_ridge(s.z, W, H, sc_rng_range(&r, 0, 3.2), sc_rng_range(&r, 0.5, 10), 65535.0f); break;
        default: sc_dem_terrain(s.z, W, H, s.cell_size, (uint64_t)it); break;
        }
        if (sc_rng_u64(&r) % 3 == 0) /* nodata holes */
            for (size_t i = 0; i < (size_t)W * H; i++) if (sc_rng_u64(&r) % 9 == 0) s.z[i] = NAN;
        random_roads(&s, &r);
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
        o.grid.buffer = sc_rng_u64(&r) % 2 ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
        o.texels = 1 + (uint32_t)(sc_rng_u64(&r) % 8);
        double zs = sc_rng_u64(&r) % 2 ? 0.01 : 1;
        if (sc_rng_u64(&r) % 3 == 0) o.grid.road_cell = s.cell_size / (1 + (double)(sc_rng_u64(&r) % 6));
        ss_image a, b;
        CHECK(ss_splat_z(ctx, &s, &o, zs, 1, &a) == RS_OK);
        CHECK(ss_splat_z(ctx, &s, &o, zs, 0, &b) == RS_OK);
        if (a.wt && b.wt) {
            size_t n = (size_t)a.w * a.h, stray;
            if (!check_weights(&s, &a, o.texels, o.grid.buffer == RS_BUFFER_DILATE, &stray)) bad_weights++;
            if (a.seam > 1.0 / 255) bad_seams++;
            if (a.seam > worst_seam) worst_seam = a.seam;
            if (memcmp(a.rgba, b.rgba, n * 4) || memcmp(a.wt, b.wt, n * 2)) nondet++;
            CHECKF(stray == 0, "stress scene %d: %zu stray weights (%s, T=%u, cs %g, road cell %g, W %u H %u)", it, stray,
                   o.grid.buffer ? "dilate" : "distance", o.texels, s.cell_size, o.grid.road_cell, W, H);
            if (stray && getenv("RS_DEBUG"))
                for (size_t k = 0; k < s.nroads; k++) {
                    fprintf(stderr, "  road w=%g:", s.roads[k].width);
                    for (size_t q = 0; q < s.roads[k].n; q++) fprintf(stderr, " (%g,%g)", s.roads[k].xy[2*q], s.roads[k].xy[2*q+1]);
                    fprintf(stderr, "\n");
                }
        }
        ss_image_free(&a);
        ss_image_free(&b);
        double err = (sc_rng_u64(&r) % 4 == 0) ? 0 : sc_rng_range(&r, 0, 5000) * zs;
        mesh_check mc;
        CHECK(roam_scene(s.z, W, H, s.cell_size, zs, err, &mc) == RS_OK);
        if (!mc.ok || mc.max_err > err + mc.tol) bad_mesh++;
        if (err > 0 && mc.max_err / err > worst_mesh_ratio) worst_mesh_ratio = mc.max_err / err;
        CHECKF(mc.ok && mc.max_err <= err + mc.tol, "stress scene %d: mesh valid %d, error %g > %g", it, mc.ok, mc.max_err, err);
        sc_scene_free(&s);
    }
    CHECK_EQ_INT(bad_weights, 0);
    CHECK_EQ_INT(bad_seams, 0);
    CHECK_EQ_INT(nondet, 0);
    CHECK_EQ_INT(bad_mesh, 0);
    printf("stress: %d scenes in %.2f s; worst seam %.4g, worst mesh error / bound %.3f\n", SCENES,
           (tm_now_ms() / 1000.0) - t0, worst_seam, worst_mesh_ratio);
}

/* The far-road tests' map: 16 x 12 flat samples of 5 m (75 x 55 m). */
static rs_dem *far_map(void)
{
    float z[16 * 12];
    memset(z, 0, sizeof z);
    rs_dem *dem = NULL;
    CHECK(rs_dem_create(ctx, 16, 12, z, &dem) == RS_OK);
    rs_dem_frame fr = { 5, 0.05, 0, 0 };
    CHECK(dem && rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    return dem;
}

/* The whole image of roads on dem with options o into *rgba and *wt
 * (malloc'd, the caller's; NULL on failure), *w x *h pixels. */
static void splat_whole(const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o, uint8_t **rgba,
                        uint16_t **wt, uint32_t *w, uint32_t *h)
{
    rs_splatter *sp = NULL;
    *w = *h = 0;
    *rgba = NULL;
    *wt = NULL;
    CHECK(dem && roads && rs_splatter_create(ctx, dem, roads, NULL, o, &sp) == RS_OK);
    if (!sp) return;
    rs_splatter_size(sp, w, h);
    *rgba = malloc((size_t)*w * *h * 4);
    *wt = malloc((size_t)*w * *h * 2);
    CHECK(*rgba && *wt && rs_splat_window(ctx, sp, 0, 0, *w, *h, *rgba, (size_t)*w * 4, *wt, *w, NULL) == RS_OK);
    rs_splatter_free(ctx, sp);
}

/* A road from 10^31 m away ending on the map: both edge modes draw it up
 * to its end point and no further (the cut to the map put the end at the
 * map's centre: its place along the line was the difference of two
 * numbers of 10^31, every digit lost; fuzz/edits, 5 December 2026). */
static void test_far_end(void)
{
    rs_dem *dem = far_map();
    rs_roads *roads = NULL;
    const double xy[4] = { 1.4444444444444444e31, 125.9, 52.6, 15.9 };
    CHECK(rs_roads_create(ctx, &roads) == RS_OK && rs_roads_add(ctx, roads, NULL, 6.2, xy, 2) == RS_OK);
    for (int mode = 0; dem && roads && mode < 2; mode++) {
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.texels = 3;
        o.coverage.edges = mode ? RS_EDGES_ALPHAMAP : RS_EDGES_ANALYTIC;
        uint8_t *rgba;
        uint16_t *wt;
        uint32_t w, h;
        splat_whole(dem, roads, &o, &rgba, &wt, &w, &h);
        /* (west of the end cap by more than a road cell and a pixel: no road;
         * on the road 10 m east of the end: road) */
        double pix = 5.0 / 3;
        size_t west = 0, on = 0;
        for (uint32_t y = 0; wt && y < h; y++)
            for (uint32_t x = 0; x < w; x++) {
                double cx = (x + 0.5) * pix, cy = (y + 0.5) * pix;
                if (cx < 52.6 - 3.1 - 2 * pix - 2.5) west += wt[(size_t)y * w + x] != 0;
                if (fabs(cx - 62.6) < pix && fabs(cy - 15.9) < pix) on += wt[(size_t)y * w + x] == 65535;
            }
        CHECKF(west == 0 && on > 0, "%s edges: %zu road pixels west of the end, %zu on the road",
               mode ? "alpha-map" : "analytic", west, on);
        free(rgba);
        free(wt);
    }
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
}

/* Distance from (x, y) to segment a-b. */
static double seg_dist2d(double x, double y, const double *a, const double *b)
{
    double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((x - a[0]) * dx + (y - a[1]) * dy) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(x - a[0] - t * dx, y - a[1] - t * dy);
}

/* A slanted road from 10^20 m away, bent on the map: its surface and edge
 * lines as the same road from 1 km away along the same line (the cut of a
 * far segment was built from the map's centre and missed the road's own
 * point by metres). The centre line's dashes are measured along a road
 * 10^20 m long and are left out of the comparison. */
static void test_far_slant(void)
{
    rs_dem *dem = far_map();
    const double B[2] = { 40, 20 }, C[2] = { 40, -50 };
    const double ux = 1e20 / hypot(1e20, 3e19), uy = 3e19 / hypot(1e20, 3e19);
    for (int mode = 0; dem && mode < 2; mode++) {
        uint8_t *rgba[2] = { NULL, NULL };
        uint16_t *wt[2] = { NULL, NULL };
        uint32_t w = 0, h = 0;
        for (int v = 0; v < 2; v++) {
            double d = v ? 1e3 : 1e20;
            const double xy[6] = { v ? B[0] + d * ux : 1e20, v ? B[1] + d * uy : 3e19, B[0], B[1], C[0], C[1] };
            rs_roads *roads = NULL;
            CHECK(rs_roads_create(ctx, &roads) == RS_OK && rs_roads_add(ctx, roads, NULL, 8, xy, 3) == RS_OK &&
                  rs_roads_set_attr(ctx, roads, 0, "class", "secondary") == RS_OK);
            rs_splat_options o;
            memset(&o, 0, sizeof o);
            o.texels = 16;
            o.coverage.edges = mode ? RS_EDGES_ALPHAMAP : RS_EDGES_ANALYTIC;
            splat_whole(dem, roads, &o, &rgba[v], &wt[v], &w, &h);
            rs_roads_free(ctx, roads);
        }
        double pix = 5.0 / 16, far[2] = { B[0] + 1e3 * ux, B[1] + 1e3 * uy };
        size_t road = 0, differ = 0, worst = 0;
        for (uint32_t y = 0; rgba[0] && rgba[1] && wt[0] && wt[1] && y < h; y++)
            for (uint32_t x = 0; x < w; x++) {
                double cx = (x + 0.5) * pix, cy = (y + 0.5) * pix;
                double dc = fmin(seg_dist2d(cx, cy, far, B), seg_dist2d(cx, cy, B, C));
                size_t p = (size_t)y * w + x;
                road += wt[1][p] != 0;
                if (dc < 1.0) continue; /* (the dashes) */
                int dw = abs((int)wt[0][p] - (int)wt[1][p]);
                for (int c = 0; c < 4; c++) {
                    int dd = abs((int)rgba[0][4 * p + c] - (int)rgba[1][4 * p + c]);
                    if (dd > dw) dw = dd;
                }
                differ += dw > 1;
                if ((size_t)dw > worst) worst = (size_t)dw;
            }
        CHECKF(road > 1000 && differ == 0, "%s edges: %zu of %zu road pixels off the centre line differ (by up to %zu)",
               mode ? "alpha-map" : "analytic", differ, road, worst);
        for (int v = 0; v < 2; v++) free(rgba[v]), free(wt[v]);
    }
    rs_dem_free(ctx, dem);
}

/* A zebra on a road from 10^33 m: its place along the road is an arc
 * length of 10^33 with no metres left, so it is not placed (it was painted
 * all along the road); on the same road the other way round its arc length
 * is 35 m and it is. */
static void test_far_zebra(void)
{
    rs_dem *dem = far_map();
    for (int rev = 0; dem && rev < 2; rev++) {
        uint8_t *rgba[2] = { NULL, NULL };
        uint16_t *wt[2] = { NULL, NULL };
        uint32_t w = 0, h = 0;
        for (int zebra = 0; zebra < 2; zebra++) {
            const double fwd[6] = { 1.1e33, 20, 40, 20, 75, 20 }, back[6] = { 75, 20, 40, 20, 1.1e33, 20 };
            rs_roads *roads = NULL;
            CHECK(rs_roads_create(ctx, &roads) == RS_OK &&
                  rs_roads_add(ctx, roads, NULL, 6, rev ? back : fwd, 3) == RS_OK);
            if (zebra) CHECK(rs_roads_set_point_attr(ctx, roads, 0, 1, "crossing", "zebra") == RS_OK);
            rs_splat_options o;
            memset(&o, 0, sizeof o);
            o.texels = 16;
            splat_whole(dem, roads, &o, &rgba[zebra], &wt[zebra], &w, &h);
            rs_roads_free(ctx, roads);
        }
        /* pixels the zebra changed, near its point and elsewhere */
        size_t near = 0, away = 0;
        for (uint32_t y = 0; rgba[0] && rgba[1] && y < h; y++)
            for (uint32_t x = 0; x < w; x++) {
                size_t p = (size_t)y * w + x;
                if (!memcmp(rgba[0] + 4 * p, rgba[1] + 4 * p, 4)) continue;
                double cx = (x + 0.5) * 5.0 / 16;
                if (fabs(cx - 40) < 3) near++;
                else away++;
            }
        CHECKF(away == 0 && (rev ? near > 100 : near == 0),
               "road %s: the zebra changed %zu pixels within 3 m of its point and %zu further off",
               rev ? "to the far point" : "from the far point", near, away);
        for (int v = 0; v < 2; v++) free(rgba[v]), free(wt[v]);
    }
    rs_dem_free(ctx, dem);
}

int main(void)
{
    rs_allocator al = size_alloc_hook(&mem);
    if (rs_ctx_create(&al, NULL, &ctx) != RS_OK) return 1;
    test_extreme_dems();
    test_stress();
    test_far_end();
    test_far_slant();
    test_far_zebra();
    if (!getenv("RS_DEBUG")) test_huge_dem();
    CHECK(mem.live > 0); /* the context itself */
    rs_ctx_free(ctx);
    CHECK_EQ_INT(mem.live, 0);
    return th_finish("test_extreme");
}
