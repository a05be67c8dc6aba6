/* Issue 19 (library side): extreme scales and bounded work; issue 26
 * row 14 (NULL pointers with counts, at the end).
 * - ROAM: every extracted value fits a float; values that would not are
 *   refused up front (cell size, heights x z-scale, skirt depth); the
 *   coarsest mesh stays the coarsest at the largest accepted heights;
 *   rs_roam_create without a context still clears *out; a subnormal fov_y
 *   is refused; the per-vertex sample index matches the vertices.
 * - Road grid: a subnormal cell size is refused (was NaN -> int64 and a
 *   division by zero); work follows the covered area (one 1e9 m wide road of
 *   1,001 vertices, a dilated road on a 10^4 x 10^4 road grid); cancellation
 *   is checked within a road. */
#include "roadsplat_experimental.h"
#include "harness.h"
#include "timing.h"

#include <float.h>
#include <stdlib.h>

static rs_ctx *ctx;

static rs_dem *dem_of(uint32_t W, uint32_t H, float z0, float z1)
{
    float *z = malloc((size_t)W * H * sizeof *z);
    for (size_t k = 0; k < (size_t)W * H; k++) z[k] = (k * 7919u) % 3 ? z0 : z1;
    rs_dem *d = NULL;
    rs_result r = rs_dem_create(ctx, W, H, z, &d);
    free(z);
    return r ? NULL : d;
}

/* The frame is the DEM's: a cell size or z-scale out of range is refused
 * by rs_dem_set_frame, the rest by rs_roam_create. */
static rs_roam *roam_of(rs_dem *d, double cs, double zs, rs_result *r)
{
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    rs_dem_frame fr = { cs, zs, 0, 0 };
    rs_roam *L = (rs_roam *)(uintptr_t)1; /* must be cleared on failure */
    *r = rs_dem_set_frame(ctx, d, &fr);
    if (*r) return NULL;
    *r = rs_roam_create(ctx, d, &o, &L);
    if (*r) CHECK(L == NULL);
    return *r ? NULL : L;
}

/* Extract with normals and skirt; every float finite; samples consistent. */
static int extract_finite(rs_roam *L, double cs, uint32_t W, double skirt, rs_result *res)
{
    rs_roam_mesh_options mo;
    memset(&mo, 0, sizeof mo);
    mo.normals = 1;
    mo.skirt_depth = skirt;
    size_t mv, mi, nv = 0, ni = 0;
    rs_roam_mesh_bound(L, &mo, &mv, &mi);
    float *v = malloc(mv * 5 * sizeof *v), *n = malloc(mv * 3 * sizeof *n);
    uint32_t *idx = malloc(mi * sizeof *idx), *smp = malloc(mv * sizeof *smp);
    mo.samples = smp;
    *res = rs_roam_extract(ctx, L, &mo, v, n, mv, idx, mi, &nv, &ni);
    int ok = 1;
    for (size_t k = 0; *res == RS_OK && k < nv; k++) {
        for (int c = 0; c < 5; c++) ok &= isfinite(v[5 * k + c]) != 0;
        for (int c = 0; c < 3; c++) ok &= isfinite(n[3 * k + c]) != 0;
        uint32_t j = smp[k] % W, i = smp[k] / W;
        ok &= v[5 * k] == (float)(j * cs) && v[5 * k + 1] == (float)(i * cs);
    }
    free(v); free(n); free(idx); free(smp);
    return ok;
}

static void test_roam_float_range(void)
{
    rs_dem *d = dem_of(12, 12, 0.0f, 50.0f);
    rs_result r;
    /* NULL context: *out is cleared like every other failure */
    rs_roam *L = (rs_roam *)(uintptr_t)1;
    CHECK_EQ_INT(rs_roam_create(NULL, d, NULL, &L), RS_ERR_INVALID_ARG);
    CHECK(L == NULL);
    /* cell sizes whose vertices underflow or overflow a float */
    CHECK(roam_of(d, 1e-46, 1, &r) == NULL && r == RS_ERR_INVALID_ARG);
    CHECK(roam_of(d, 1e-39, 1, &r) == NULL && r == RS_ERR_INVALID_ARG);
    CHECK(roam_of(d, 1e39, 1, &r) == NULL && r == RS_ERR_INVALID_ARG);
    CHECK(roam_of(d, 5e-324, 1, &r) == NULL && r == RS_ERR_INVALID_ARG);
    CHECK(roam_of(d, 1e-310, 1, &r) == NULL && r == RS_ERR_INVALID_ARG);
    CHECK(roam_of(d, 3.4e38 / 11 * 1.01, 1, &r) == NULL && r == RS_ERR_INVALID_ARG);
    /* z-scale: 50 * 1e40 is no float */
    CHECK(roam_of(d, 1, 1e40, &r) == NULL && r == RS_ERR_INVALID_ARG);
    /* the extremes still accepted give finite output, samples match */
    const double cs_ok[3] = { 1e-9, 1.0, 1e9 }; /* the frame's range */
    for (int c = 0; c < 3; c++) {
        L = roam_of(d, cs_ok[c], 1, &r);
        CHECKF(L != NULL, "cell size %g refused", cs_ok[c]);
        if (!L) continue;
        CHECK_EQ_INT(rs_roam_refine_error(ctx, L, 0), RS_OK);
        rs_result er;
        CHECKF(extract_finite(L, cs_ok[c], 12, 1.0, &er) && er == RS_OK, "cell size %g: non-finite output", cs_ok[c]);
        /* a skirt reaching below -FLT_MAX is refused, not written as -inf */
        CHECK(extract_finite(L, cs_ok[c], 12, 1e39, &er) && er == RS_ERR_INVALID_ARG);
        CHECK(extract_finite(L, cs_ok[c], 12, FLT_MAX, &er) && er == RS_OK); /* heights >= 0 here: -FLT_MAX fits */
        rs_roam_free(ctx, L);
    }
    rs_dem_free(ctx, d);

    /* +-3.4e38 heights: refused (their error bounds are no floats) ... */
    d = dem_of(12, 12, -3.4e38f, 3.4e38f);
    CHECK(roam_of(d, 1, 1, &r) == NULL && r == RS_ERR_INVALID_ARG);
    rs_dem_free(ctx, d);
    /* ... and at the largest accepted heights the coarsest mesh is the
     * base mesh (a flat DEM's), as for any DEM */
    rs_dem *flat = dem_of(33, 17, 0.0f, 0.0f);
    d = dem_of(33, 17, -8.5e37f, 8.5e37f);
    rs_roam *Lf = roam_of(flat, 1, 1, &r), *Lh = roam_of(d, 1, 1, &r);
    CHECK(Lf && Lh);
    if (Lf && Lh) {
        rs_roam_stats sf, sh;
        CHECK_EQ_INT(rs_roam_refine_error(ctx, Lf, 0), RS_OK);
        CHECK_EQ_INT(rs_roam_refine_error(ctx, Lh, 1e300), RS_OK);
        rs_roam_get_stats(Lf, &sf);
        rs_roam_get_stats(Lh, &sh);
        CHECK_EQ_INT(sh.triangles, sf.triangles);
        CHECK(isfinite(sh.max_error_bound));
        rs_result er;
        CHECK(extract_finite(Lh, 1, 33, 0, &er) && er == RS_OK);
        /* a subnormal field of view has no finite projection */
        rs_roam_view vw;
        memset(&vw, 0, sizeof vw);
        vw.eye[0] = 16; vw.eye[1] = 40; vw.eye[2] = 30;
        vw.dir[1] = -1; vw.dir[2] = -0.5;
        vw.fov_y = 1e-320;
        CHECK_EQ_INT(rs_roam_frame(ctx, Lh, &vw), RS_ERR_INVALID_ARG);
        vw.fov_y = 5e-324;
        CHECK_EQ_INT(rs_roam_frame(ctx, Lh, &vw), RS_ERR_INVALID_ARG);
    }
    rs_roam_free(ctx, Lf);
    rs_roam_free(ctx, Lh);
    rs_dem_free(ctx, flat);
    rs_dem_free(ctx, d);
}

/* ---- road grid --------------------------------------------------------------- */

typedef struct cancel_probe { int calls; uint64_t first_done; int cancel_at; } cancel_probe;

static int probe_cb(void *user, uint64_t done, uint64_t total)
{
    cancel_probe *p = user;
    (void)total;
    if (p->calls++ == 0) p->first_done = done;
    return p->cancel_at && p->calls >= p->cancel_at;
}

static rs_roads *wide_road(size_t n, double width)
{
    rs_roads *roads = NULL;
    rs_roads_create(ctx, &roads);
    double *xy = malloc(2 * n * sizeof *xy);
    for (size_t i = 0; i < n; i++) {
        xy[2 * i] = 100 + 0.01 * (double)i;
        xy[2 * i + 1] = 75 + 0.013 * (double)(i % 7);
    }
    rs_roads_add(ctx, roads, "wide", width, xy, n);
    free(xy);
    return roads;
}

static void test_grid(void)
{
    rs_dem *d = dem_of(201, 151, 0.0f, 3.0f);
    rs_roads *roads = wide_road(1001, 1e9);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
    rs_road_grid *g = NULL;
    /* subnormal cell sizes: an error, no NaN -> int64 or division by zero */
    const double tiny[3] = { 1e-310, 5e-324, 1e-250 };
    for (int t = 0; t < 3; t++) {
        rs_dem_frame fr = { tiny[t], 0, 0, 0 };
        CHECKF(rs_dem_set_frame(ctx, d, &fr) == RS_ERR_INVALID_ARG, "cell size %g", tiny[t]);
    }
    /* 1,001 vertices of a road 1e9 m wide: each vertex's round cap and each
     * segment's band covers the whole 3200 x 2400 road grid (28 s before:
     * every cap cost the clipped area; now each cell is marked once) */
    double t0 = tm_now_ms();
    CHECK_EQ_INT(rs_road_grid_build(ctx, d, roads, &o, &g), RS_OK);
    double ms = tm_now_ms() - t0;
    rs_road_grid_stats st;
    if (g) {
        rs_road_grid_get_stats(g, &st);
        CHECK_EQ_INT(st.road_cells, (uint64_t)200 * st.k * 150 * st.k);
    }
    printf("wide road, 1001 vertices, distance: %.0f ms\n", ms);
    rs_road_grid_free(ctx, g);
    o.grid.buffer = RS_BUFFER_DILATE;
    t0 = tm_now_ms();
    CHECK_EQ_INT(rs_road_grid_build(ctx, d, roads, &o, &g), RS_OK);
    ms = tm_now_ms() - t0;
    printf("wide road, 1001 vertices, dilate: %.0f ms\n", ms);
    rs_road_grid_free(ctx, g);
    /* cancellation within the road: the first progress call comes before
     * the road is done (done == 0), and cancelling there stops the build */
    cancel_probe p = { 0, 99, 1 };
    o.grid.buffer = RS_BUFFER_DISTANCE;
    o.progress = probe_cb;
    o.progress_user = &p;
    CHECK_EQ_INT(rs_road_grid_build(ctx, d, roads, &o, &g), RS_ERR_CANCELLED);
    CHECK(g == NULL);
    CHECK_EQ_INT(p.first_done, 0);
    o.progress = NULL;
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, d);

    /* dilate on a 2 x 2 DEM with a 1e-4 m road cell: a 10^4 x 10^4 grid
     * (54 s before: a (2k+1)^2 square per centreline step) */
    d = dem_of(2, 2, 0.0f, 1.0f);
    roads = NULL;
    rs_roads_create(ctx, &roads);
    const double xy[4] = { 0.1, 0.1, 0.9, 0.8 };
    rs_roads_add(ctx, roads, "a", 0.6, xy, 2);
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP;
    o.grid.buffer = RS_BUFFER_DILATE;
    o.grid.road_cell = 1e-4;
    o.texels = 1;
    t0 = tm_now_ms();
    CHECK_EQ_INT(rs_road_grid_build(ctx, d, roads, &o, &g), RS_OK);
    ms = tm_now_ms() - t0;
    printf("dilate, 10^4 x 10^4 road grid: %.0f ms\n", ms);
    if (g) {
        rs_road_grid_get_stats(g, &st);
        CHECK_EQ_INT(st.k, 10000);
        CHECK(st.road_cells > 10000000 && st.road_cells < 100000000);
    }
    rs_road_grid_free(ctx, g);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, d);
}

/* Issue 26 row 14: every public (pointer, count) pair refuses a NULL
 * pointer with a count above zero (RS_ERR_INVALID_ARG, never a
 * dereference), and takes NULL with a count of zero where empty input is
 * valid. The pairs of include/roadsplat.h: PGM bytes, DEM samples, road
 * and style text, road points, the atlas image and index, the surface
 * image table (row 14: it was dereferenced) and each entry's pixels and
 * name, textures, the splat / window / normal-map / alpha-map outputs and
 * the mesh buffers. */
static void test_null_counts(void)
{
    rs_dem *d = dem_of(9, 9, 0.0f, 1.0f), *d2 = NULL;
    rs_roads *R = NULL, *R2 = NULL;
    rs_styles *st = NULL, *st2 = NULL;
    rs_atlas *a = NULL;
    CHECK(rs_roads_create(ctx, &R) == RS_OK && rs_styles_create(ctx, &st) == RS_OK);
    const double xy[4] = { 1, 4, 7, 4 };
    CHECK(rs_roads_add(ctx, R, "a", 2, xy, 2) == RS_OK);
    CHECK_EQ_INT(rs_dem_parse_pgm(ctx, NULL, 10, &d2), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_dem_create(ctx, 4, 4, NULL, &d2), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_roads_parse(ctx, NULL, 10, &R2), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_roads_parse_ex(ctx, NULL, 10, NULL, &R2), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_styles_parse(ctx, NULL, 10, &st2), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_styles_add_text(ctx, st, NULL, 10), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_roads_add(ctx, R, "b", 2, NULL, 2), RS_ERR_INVALID_ARG);
    /* NULL with a count of zero: empty text is valid */
    CHECK_EQ_INT(rs_roads_parse(ctx, NULL, 0, &R2), RS_OK);
    rs_roads_free(ctx, R2);
    CHECK_EQ_INT(rs_styles_add_text(ctx, st, NULL, 0), RS_OK);
    uint8_t px[4 * 4 * 4];
    memset(px, 255, sizeof px);
    rs_image none = { 4, 4, NULL }, img = { 4, 4, px };
    CHECK_EQ_INT(rs_atlas_create(ctx, &none, "x 0 0 2 2 1 1", 13, &a), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_atlas_create(ctx, &img, NULL, 13, &a), RS_ERR_INVALID_ARG);
    CHECK(a == NULL);

    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 2;
    rs_road_grid *g = NULL, *g2 = NULL;
    rs_splatter *sp = NULL, *sp2 = NULL;
    CHECK(rs_road_grid_build(ctx, d, R, &o, &g) == RS_OK && rs_splatter_create(ctx, d, NULL, g, &o, &sp) == RS_OK);
    /* the surface-image table (row 14), whether a style uses it or not */
    rs_splat_options ob = o;
    ob.style.surface_images = NULL;
    ob.style.surface_image_count = 2;
    CHECK_EQ_INT(rs_road_grid_build(ctx, d, R, &ob, &g2), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_splatter_create(ctx, d, R, NULL, &ob, &sp2), RS_ERR_INVALID_ARG);
    CHECK(g2 == NULL && sp2 == NULL);
    rs_surface_image si = { "x", { 4, 4, NULL } };
    ob.style.surface_images = &si;
    ob.style.surface_image_count = 1;
    CHECK_EQ_INT(rs_road_grid_build(ctx, d, R, &ob, &g2), RS_ERR_INVALID_ARG);
    si.image.rgba = px;
    si.name = NULL;
    CHECK_EQ_INT(rs_road_grid_build(ctx, d, R, &ob, &g2), RS_ERR_INVALID_ARG);
    ob.style.surface_images = NULL;
    ob.style.surface_image_count = 0;
    ob.surface.terrain_texture = &none;
    CHECK_EQ_INT(rs_road_grid_build(ctx, d, R, &ob, &g2), RS_ERR_INVALID_ARG);
    ob.surface.terrain_texture = NULL;
    ob.surface.road_texture = &none;
    CHECK_EQ_INT(rs_splatter_create(ctx, d, NULL, g, &ob, &sp2), RS_ERR_INVALID_ARG);
    CHECK(g2 == NULL && sp2 == NULL);
    /* a style that uses an image with the table NULL (dereferenced before) */
    static const char text[] = "style s\n surface img.png\nend\nroad r width 2 style=s\n1 4\n7 4\nend\n";
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = st;
    CHECK(rs_roads_parse_ex(ctx, text, sizeof text - 1, &po, &R2) == RS_OK);
    ob = o;
    ob.style.styles = st;
    ob.style.surface_image_count = 2;
    CHECK_EQ_INT(rs_road_grid_build(ctx, d, R2, &ob, &g2), RS_ERR_INVALID_ARG);
    rs_roads_free(ctx, R2);

    /* outputs */
    uint32_t w = 0, h = 0;
    CHECK(rs_splat_size(ctx, d, &o, &w, &h) == RS_OK);
    CHECK_EQ_INT(rs_splat(ctx, d, g, &o, NULL, (size_t)w * h * 4, NULL, 0), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_splat_window(ctx, sp, 0, 0, 2, 2, NULL, 8, NULL, 0, NULL), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_normal_window(ctx, sp, 0, 0, 2, 2, NULL, 6, NULL), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_alpha_map(RS_TILE_EDGE, 4, 0, 0, 0, NULL, 25), RS_ERR_INVALID_ARG);
    rs_roam *L = NULL;
    rs_roam_options ro;
    memset(&ro, 0, sizeof ro);
    CHECK(rs_roam_create(ctx, d, &ro, &L) == RS_OK && rs_roam_refine_error(ctx, L, 0) == RS_OK);
    if (L) {
        rs_roam_mesh_options mo;
        memset(&mo, 0, sizeof mo);
        mo.normals = 1;
        size_t mv = 0, mi = 0, nv = 0, ni = 0;
        rs_roam_mesh_bound(L, &mo, &mv, &mi);
        float *v = malloc(mv * 5 * sizeof *v), *nrm = malloc(mv * 3 * sizeof *nrm);
        uint32_t *idx = malloc(mi * sizeof *idx);
        CHECK_EQ_INT(rs_roam_extract(ctx, L, &mo, NULL, nrm, mv, idx, mi, &nv, &ni), RS_ERR_INVALID_ARG);
        CHECK_EQ_INT(rs_roam_extract(ctx, L, &mo, v, NULL, mv, idx, mi, &nv, &ni), RS_ERR_INVALID_ARG);
        CHECK_EQ_INT(rs_roam_extract(ctx, L, &mo, v, nrm, mv, NULL, mi, &nv, &ni), RS_ERR_INVALID_ARG);
        CHECK_EQ_INT(rs_roam_extract(ctx, L, &mo, v, nrm, mv, idx, mi, &nv, &ni), RS_OK);
        free(v);
        free(nrm);
        free(idx);
    }
    rs_roam_free(ctx, L);
    rs_splatter_free(ctx, sp);
    rs_road_grid_free(ctx, g);
    rs_styles_free(ctx, st);
    rs_roads_free(ctx, R);
    rs_dem_free(ctx, d);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_roam_float_range();
    test_grid();
    test_null_counts();
    rs_ctx_free(ctx);
    return th_finish("test_harden");
}
