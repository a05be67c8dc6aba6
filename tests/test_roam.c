/* ROAM mesher: crack-freedom and coverage for every pool size, the error
 * bound, height scaling, determinism, budgets, view-dependent feedback,
 * nodata, extraction options and error paths. Meshes are checked by the
 * independent checker in roam_check.h. */
#include "harness.h"
#include "roadsplat.h"
#include "roam_check.h"
#include "roam_fuzz_input.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct mesh {
    float *v, *n;
    uint32_t *i;
    size_t nv, ni;
} mesh;

static void mesh_free(mesh *m)
{
    free(m->v); free(m->n); free(m->i);
    memset(m, 0, sizeof *m);
}

static rs_result extract(rs_ctx *ctx, rs_roam *r, const rs_roam_mesh_options *o, mesh *m)
{
    size_t mv, mi;
    memset(m, 0, sizeof *m);
    rs_roam_mesh_bound(r, o, &mv, &mi);
    m->v = malloc((mv ? mv : 1) * 5 * sizeof(float));
    m->n = malloc((mv ? mv : 1) * 3 * sizeof(float));
    m->i = malloc((mi ? mi : 1) * sizeof(uint32_t));
    if (!m->v || !m->n || !m->i) return RS_ERR_NOMEM;
    return rs_roam_extract(ctx, r, o, m->v, (o && o->normals) ? m->n : NULL, mv, m->i, mi, &m->nv, &m->ni);
}

/* Check the top surface (the first `ntri` triangles) with the checker. */
static int check(const float *z, uint32_t W, uint32_t H, double cs, double zs, const mesh *m, size_t ntri,
                 rc_result *res)
{
    int32_t *gx = malloc((m->nv + 1) * sizeof *gx), *gy = malloc((m->nv + 1) * sizeof *gy);
    double *vz = malloc((m->nv + 1) * sizeof *vz);
    int ok = gx && gy && vz;
    for (size_t k = 0; ok && k < m->nv; k++) {
        gx[k] = (int32_t)lround(m->v[5 * k] / cs);
        gy[k] = (int32_t)lround(m->v[5 * k + 1] / cs);
        vz[k] = m->v[5 * k + 2];
        if (fabs(gx[k] * cs - m->v[5 * k]) > 1e-3 * cs) gx[k] = -1;
    }
    /* vertex heights are floats: compare the DEM at float precision too */
    float *zf = malloc((size_t)W * H * sizeof *zf);
    ok = ok && zf;
    for (size_t k = 0; ok && k < (size_t)W * H; k++) zf[k] = isnan(z[k]) ? z[k] : (float)((double)z[k] * zs);
    size_t nv = 0; /* skirt vertices follow the top surface's */
    for (size_t k = 0; k < 3 * ntri; k++) if (m->i[k] + (size_t)1 > nv) nv = m->i[k] + (size_t)1;
    ok = ok && rc_check(W, H, zf, 1.0, gx, gy, vz, nv, m->i, ntri, res);
    free(gx); free(gy); free(vz); free(zf);
    return ok;
}

/* A landscape on a new DEM with cell size cs and z-scale zs (0: 1). */
static rs_roam *make_f(rs_ctx *ctx, const float *z, uint32_t W, uint32_t H, double cs, double zs,
                       const rs_roam_options *o, rs_dem **dem)
{
    rs_roam *r = NULL;
    rs_dem_frame fr = { cs, zs, 0, 0 };
    if (rs_dem_create(ctx, W, H, z, dem) != RS_OK) return NULL;
    if (rs_dem_set_frame(ctx, *dem, &fr) != RS_OK) { rs_dem_free(ctx, *dem); *dem = NULL; return NULL; }
    if (rs_roam_create(ctx, *dem, o, &r) != RS_OK) { rs_dem_free(ctx, *dem); *dem = NULL; return NULL; }
    return r;
}

static rs_roam *make(rs_ctx *ctx, const float *z, uint32_t W, uint32_t H, const rs_roam_options *o,
                     rs_dem **dem)
{
    return make_f(ctx, z, W, H, 0, 0, o, dem);
}

enum { DEM_CONST, DEM_SPIKE, DEM_CHECKER, DEM_RIDGE, DEM_FRACTAL, DEM_NODATA, DEM_COUNT };
static const char *dem_name[DEM_COUNT] = { "constant", "spike", "checkerboard", "ridge", "fractal", "nodata" };

static float *gen(int kind, uint32_t W, uint32_t H)
{
    float *z = malloc((size_t)W * H * sizeof *z);
    if (!z) return NULL;
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            float v = 0;
            switch (kind) {
            case DEM_CONST: v = 123.5f; break;
            case DEM_SPIKE: v = (x == W / 3 && y == H / 2) ? 900.0f : 10.0f; break;
            case DEM_CHECKER: v = ((x + y) & 1) ? 65535.0f : 0.0f; break;
            case DEM_RIDGE: v = (float)(200.0 - 7.0 * fabs((double)x - 0.6 * y - 3.0)); break;
            default: break;
            }
            z[(size_t)y * W + x] = v;
        }
    if (kind == DEM_FRACTAL || kind == DEM_NODATA) rc_dem_fractal(z, W, H, 7, 16.0, 50.0, 0.55);
    if (kind == DEM_NODATA)
        for (uint32_t y = 0; y < H; y++)
            for (uint32_t x = 0; x < W; x++)
                if ((x > W / 4 && x < W / 2 && y > 1 && y < H - 3) || (x == W - 1 && y == 0)) z[(size_t)y * W + x] = NAN;
    return z;
}

/* Vertex set of a mesh as a W*H bitmap. */
static unsigned char *vertex_set(const mesh *m, uint32_t W, uint32_t H, double cs)
{
    unsigned char *s = calloc((size_t)W * H, 1);
    if (!s) return NULL;
    for (size_t k = 0; k < m->nv; k++) {
        long x = lround(m->v[5 * k] / cs), y = lround(m->v[5 * k + 1] / cs);
        if (x >= 0 && y >= 0 && x < (long)W && y < (long)H) s[(size_t)y * W + (size_t)x] = 1;
    }
    return s;
}

/* Every pool size from 1 node to what the finest mesh needs: always a valid
 * complete mesh, never coarser than with a smaller pool. */
static void test_pool_sweep(rs_ctx *ctx, int kind, uint32_t W, uint32_t H)
{
    float *z = gen(kind, W, H);
    rs_dem *dem = NULL;
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    rs_roam *full = make(ctx, z, W, H, &o, &dem);
    CHECK(full != NULL);
    if (!full) { free(z); return; }
    CHECK_EQ_INT(rs_roam_refine_error(ctx, full, 0.0), RS_OK);
    rs_roam_stats st;
    rs_roam_get_stats(full, &st);
    uint32_t need = st.pool_used, full_tris = st.triangles;
    rs_roam_free(ctx, full);
    int all_valid = 1, monotone = 1, exhausted_flag_ok = 1, status_ok = 1;
    unsigned char *prev = NULL;
    uint32_t prev_tris = 0;
    for (uint32_t pool = 1; pool <= need + 2; pool++) {
        o.pool_nodes = pool;
        rs_roam *r = NULL;
        if (rs_roam_create(ctx, dem, &o, &r) != RS_OK) { all_valid = 0; break; }
        rs_result rr = rs_roam_refine_error(ctx, r, 0.0);
        rs_roam_get_stats(r, &st);
        if ((rr == RS_ERR_POOL_EXHAUSTED) != (st.pool_exhausted != 0)) exhausted_flag_ok = 0;
        if (pool >= need && rr != RS_OK) status_ok = 0;
        if (pool < need && rr != RS_ERR_POOL_EXHAUSTED) status_ok = 0;
        if (st.pool_used > pool) all_valid = 0;
        mesh m;
        rc_result res;
        if (extract(ctx, r, NULL, &m) != RS_OK || !check(z, W, H, 1.0, 1.0, &m, m.ni / 3, &res) || !rc_all_ok(&res)) {
            if (all_valid) fprintf(stderr, "    %s %ux%u pool %u: invalid mesh\n", dem_name[kind], W, H, pool);
            all_valid = 0;
        }
        unsigned char *cur = vertex_set(&m, W, H, 1.0);
        if (prev && cur) {
            for (size_t k = 0; k < (size_t)W * H; k++)
                if (prev[k] && !cur[k]) monotone = 0;
            if (st.triangles < prev_tris) monotone = 0;
        }
        free(prev);
        prev = cur;
        prev_tris = st.triangles;
        mesh_free(&m);
        rs_roam_free(ctx, r);
    }
    free(prev);
    CHECKF(all_valid, "%s %ux%u: every pool size gives a crack-free complete mesh", dem_name[kind], W, H);
    CHECKF(monotone, "%s %ux%u: a larger pool never gives a coarser mesh", dem_name[kind], W, H);
    CHECKF(exhausted_flag_ok && status_ok, "%s %ux%u: exhaustion reported exactly when the pool is short (need %u)",
           dem_name[kind], W, H, need);
    CHECKF(prev_tris == full_tris, "%s %ux%u: the largest pool reaches the finest mesh", dem_name[kind], W, H);
    rs_dem_free(ctx, dem);
    free(z);
}

/* Measured max error <= E over a sweep; coarser with larger E; and the mesh
 * is minimal: merging any split diamond would break the bound is not
 * checked here, but no triangle exceeds E while the count falls with E. */
static void test_error_sweep(rs_ctx *ctx, int kind, uint32_t W, uint32_t H, double cs, double zs)
{
    float *z = gen(kind, W, H);
    rs_dem *dem = NULL;
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    rs_roam *r = make_f(ctx, z, W, H, cs, zs, &o, &dem);
    CHECK(r != NULL);
    if (!r) { free(z); return; }
    static const double Es[] = { 0.0, 0.01, 0.1, 0.5, 1.0, 2.5, 5.0, 10.0, 40.0, 1e9 };
    int bound_ok = 1, valid = 1, mono = 1, tight = 1;
    uint32_t prev = UINT32_MAX;
    double worst = 0, zmax = 0, loose = 0;
    for (size_t k = 0; k < (size_t)W * H; k++)
        if (!isnan(z[k]) && fabs((double)z[k]) > zmax) zmax = fabs((double)z[k]);
    for (size_t e = 0; e < sizeof Es / sizeof Es[0]; e++) {
        if (rs_roam_refine_error(ctx, r, Es[e]) != RS_OK) { valid = 0; continue; }
        mesh m;
        rc_result res;
        if (extract(ctx, r, NULL, &m) != RS_OK || !check(z, W, H, cs, zs, &m, m.ni / 3, &res) || !rc_all_ok(&res))
            valid = 0;
        /* float vertex heights: allow their rounding, nothing more */
        if (res.max_err > Es[e] + 1e-6 * 70000.0 * zs) { bound_ok = 0; worst = res.max_err; }
        rs_roam_stats st;
        rs_roam_get_stats(r, &st);
        if (st.triangles > prev) mono = 0;
        if (st.max_error_bound > Es[e]) bound_ok = 0;
        /* the bound is exact, not loose: it equals the measured max error up
         * to the float rounding of vertex heights and of the stored bound */
        if (kind != DEM_NODATA && fabs(st.max_error_bound - res.max_err) > 4e-7 * zmax * zs + 1e-12) {
            tight = 0;
            loose = st.max_error_bound - res.max_err;
        }
        prev = st.triangles;
        mesh_free(&m);
    }
    CHECKF(valid, "%s %ux%u: meshes over the E sweep are crack-free and complete", dem_name[kind], W, H);
    CHECKF(bound_ok, "%s %ux%u: measured max error <= E (worst %g)", dem_name[kind], W, H, worst);
    CHECKF(mono, "%s %ux%u: triangle count never rises with E", dem_name[kind], W, H);
    CHECKF(tight, "%s %ux%u: reported bound == measured max error (off by %g)", dem_name[kind], W, H, loose);
    rs_roam_free(ctx, r);
    rs_dem_free(ctx, dem);
    free(z);
}

static int same_indices(const mesh *a, const mesh *b)
{
    return a->ni == b->ni && a->nv == b->nv && memcmp(a->i, b->i, a->ni * sizeof(uint32_t)) == 0;
}

static void test_scaling_and_determinism(rs_ctx *ctx)
{
    const uint32_t W = 97, H = 65;
    float *z = gen(DEM_FRACTAL, W, H), *zk = malloc((size_t)W * H * sizeof(float));
    for (size_t k = 0; k < (size_t)W * H; k++) zk[k] = z[k] * 4.0f;
    rs_dem *d1 = NULL, *d2 = NULL;
    rs_roam *r1 = make(ctx, z, W, H, NULL, &d1), *r2 = make(ctx, zk, W, H, NULL, &d2);
    rs_dem *dz3 = NULL;
    rs_roam *r3 = make_f(ctx, z, W, H, 0, 3.0, NULL, &dz3);
    CHECK(r1 && r2 && d1 && r3);
    int same = 1, same3 = 1;
    static const double Es[] = { 0.05, 0.3, 1.0, 3.0, 9.0 };
    for (size_t e = 0; r1 && r2 && r3 && e < 5; e++) {
        mesh a, b, c;
        rs_roam_refine_error(ctx, r1, Es[e]);
        rs_roam_refine_error(ctx, r2, 4.0 * Es[e]);
        rs_roam_refine_error(ctx, r3, 3.0 * Es[e]);
        extract(ctx, r1, NULL, &a); extract(ctx, r2, NULL, &b); extract(ctx, r3, NULL, &c);
        if (!same_indices(&a, &b)) same = 0;
        if (!same_indices(&a, &c)) same3 = 0;
        mesh_free(&a); mesh_free(&b); mesh_free(&c);
    }
    CHECK(same);   /* heights x4 at 4E: same mesh */
    CHECK(same3);  /* z_scale 3 at 3E: same mesh */
    rs_roam_free(ctx, r3);
    rs_dem_free(ctx, dz3);
    /* determinism: a second context, a second build, identical bytes */
    rs_ctx *ctx2 = NULL;
    rs_ctx_create(NULL, NULL, &ctx2);
    rs_dem *d3 = NULL;
    rs_roam *r4 = ctx2 ? make(ctx2, z, W, H, NULL, &d3) : NULL;
    CHECK(r4 != NULL);
    if (r4 && r1) {
        rs_roam_mesh_options mo = { sizeof(rs_roam_mesh_options), 1, 5.0, NULL };
        mesh a, b;
        rs_roam_refine_error(ctx, r1, 0.7);
        rs_roam_refine_error(ctx2, r4, 0.7);
        extract(ctx, r1, &mo, &a);
        extract(ctx2, r4, &mo, &b);
        CHECK(same_indices(&a, &b) && memcmp(a.v, b.v, a.nv * 5 * sizeof(float)) == 0
              && memcmp(a.n, b.n, a.nv * 3 * sizeof(float)) == 0);
        /* extracting twice gives the same bytes too (scratch maps are restored) */
        mesh c;
        extract(ctx, r1, &mo, &c);
        CHECK(same_indices(&a, &c) && memcmp(a.v, c.v, a.nv * 5 * sizeof(float)) == 0);
        mesh_free(&a); mesh_free(&b); mesh_free(&c);
    }
    rs_roam_free(ctx2, r4);
    rs_dem_free(ctx2, d3);
    rs_ctx_free(ctx2);
    rs_roam_free(ctx, r1); rs_roam_free(ctx, r2);
    rs_dem_free(ctx, d1); rs_dem_free(ctx, d2);
    free(z); free(zk);
}

static void test_budget(rs_ctx *ctx)
{
    const uint32_t W = 129, H = 129;
    float *z = gen(DEM_FRACTAL, W, H);
    rs_dem *d = NULL;
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    o.patch_size = 128; /* one patch: a base mesh of 2 triangles (the automatic size gives 4 patches) */
    rs_roam *r = make(ctx, z, W, H, &o, &d);
    CHECK(r != NULL);
    static const uint32_t Ns[] = { 2, 50, 1000, 5000 };
    for (size_t k = 0; r && k < 4; k++) {
        CHECK_EQ_INT(rs_roam_refine_count(ctx, r, Ns[k]), RS_OK);
        rs_roam_stats st;
        rs_roam_get_stats(r, &st);
        CHECKF(st.triangles <= Ns[k], "budget %u: got %u", Ns[k], st.triangles);
        /* finest: the next smaller error (one float step down) would not fit */
        if (st.threshold > 0) {
            float t = nextafterf((float)st.threshold, 0.0f);
            rs_roam_refine_error(ctx, r, t);
            rs_roam_stats s2;
            rs_roam_get_stats(r, &s2);
            CHECKF(s2.triangles > Ns[k] || s2.triangles == st.triangles, "budget %u: finer mesh %u also fits",
                   Ns[k], s2.triangles);
        }
        mesh m;
        rc_result res;
        rs_roam_refine_count(ctx, r, Ns[k]);
        CHECK(extract(ctx, r, NULL, &m) == RS_OK && check(z, W, H, 1, 1, &m, m.ni / 3, &res) && rc_all_ok(&res)
              && res.max_err <= st.threshold + 1e-3);
        mesh_free(&m);
    }
    rs_roam_free(ctx, r);
    rs_dem_free(ctx, d);
    free(z);
}

/* The fractal the view-mode tests fly over (80 m relief at 10 m cells). */
static float *view_dem(uint32_t W, uint32_t H)
{
    float *z = malloc((size_t)W * H * sizeof *z);
    if (z) rc_dem_fractal(z, W, H, 11, 64.0, 80.0, 0.55);
    return z;
}

/* A landscape on view_dem with VIEW_CS-metre cells, options *o (patch and
 * unit size); *z and *d for the caller to free. */
#define VIEW_CS 10.0
static rs_roam *make_view_roam(rs_ctx *ctx, uint32_t W, uint32_t H, uint32_t patch, uint32_t unit, float **z,
                               rs_dem **d, rs_roam_options *o)
{
    memset(o, 0, sizeof *o);
    o->patch_size = patch;
    o->unit_size = unit;
    *z = view_dem(W, H);
    return *z ? make_f(ctx, *z, W, H, VIEW_CS, 0, o, d) : NULL;
}

static void test_view(rs_ctx *ctx)
{
    const uint32_t W = 257, H = 257;
    float *z = view_dem(W, H);
    rs_dem *d = NULL;
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    o.patch_size = 64;
    rs_roam *r = make_f(ctx, z, W, H, 10.0, 0, &o, &d);
    CHECK(r != NULL);
    if (!r) { free(z); return; }
    rs_roam_view v;
    memset(&v, 0, sizeof v);
    v.target_triangles = 6000;
    v.fov_y = 60;
    v.width = 1024; v.height = 768;
    int within = 1, valid = 1;
    uint32_t maxpasses = 0;
    for (int f = 0; f < 40; f++) {
        double t = f / 40.0 * 6.2831853;
        /* fly a circle, looking towards the centre and down a little, then out */
        double rad = f < 30 ? 900.0 : 900.0 + (f - 30) * 300.0;
        v.eye[0] = 1280 + rad * cos(t); v.eye[1] = 1280 + rad * sin(t); v.eye[2] = 250 + 10 * f;
        v.dir[0] = 1280 - v.eye[0]; v.dir[1] = 1280 - v.eye[1]; v.dir[2] = -300;
        rs_result rr = rs_roam_frame(ctx, r, &v);
        rs_roam_stats st;
        rs_roam_get_stats(r, &st);
        double dev = fabs((double)st.triangles - v.target_triangles) / v.target_triangles;
        if (rr != RS_OK || dev > 0.05) {
            within = 0;
            fprintf(stderr, "    frame %d: %u triangles (%.1f%% off), %u passes, rc %d\n", f, st.triangles,
                    100 * dev, st.frame_passes, rr);
        }
        if (st.frame_passes > maxpasses) maxpasses = st.frame_passes;
        if (f % 10 == 3) {
            mesh m;
            rc_result res;
            if (extract(ctx, r, NULL, &m) != RS_OK || !check(z, W, H, 10.0, 1.0, &m, m.ni / 3, &res) || !rc_all_ok(&res))
                valid = 0;
            mesh_free(&m);
        }
    }
    CHECKF(within, "view-dependent count within +-5%% of the target on every frame");
    CHECK(valid);
    printf("view: at most %u tessellation passes per frame\n", maxpasses);
    /* frustum culling: looking away from the map leaves it at the base mesh */
    memset(&v, 0, sizeof v);
    v.eye[0] = -100; v.eye[1] = 1280; v.eye[2] = 300;
    v.dir[0] = -1; v.dir[1] = 0; v.dir[2] = 0;
    v.pixel_error = 3.0;
    CHECK_EQ_INT(rs_roam_frame(ctx, r, &v), RS_OK);
    rs_roam_stats st;
    rs_roam_get_stats(r, &st);
    CHECK_EQ_INT(st.patches_culled, 16);
    CHECK_EQ_INT(st.triangles, 32);
    /* looking at it: closer parts finer than far ones */
    v.dir[0] = 1; v.dir[2] = -0.3;
    CHECK_EQ_INT(rs_roam_frame(ctx, r, &v), RS_OK);
    rs_roam_get_stats(r, &st);
    CHECK(st.triangles > 32 && st.patches_culled < 16);
    mesh m;
    rc_result res;
    CHECK(extract(ctx, r, NULL, &m) == RS_OK && check(z, W, H, 10.0, 1.0, &m, m.ni / 3, &res) && rc_all_ok(&res));
    size_t nearv = 0, farv = 0;
    for (size_t k = 0; k < m.nv; k++) {
        if (m.v[5 * k] < 640) nearv++;
        else if (m.v[5 * k] > 1920) farv++;
    }
    CHECKF(nearv > 2 * farv, "near quarter %zu vertices, far quarter %zu", nearv, farv);
    mesh_free(&m);
    /* bad views */
    v.dir[0] = v.dir[1] = v.dir[2] = 0;
    CHECK_EQ_INT(rs_roam_frame(ctx, r, &v), RS_ERR_INVALID_ARG);
    v.dir[0] = 1; v.fov_y = 200;
    CHECK_EQ_INT(rs_roam_frame(ctx, r, &v), RS_ERR_INVALID_ARG);
    rs_roam_free(ctx, r);
    rs_dem_free(ctx, d);
    free(z);
}

/* The mesh of r: valid and crack-free (rc_check), and within the view
 * tolerance on every triangle in the frustum (rc_view_worst; 29 degrees
 * is inside a 60 degree vertical field of view at any aspect >= 1). */
static int view_mesh_ok(rs_ctx *ctx, rs_roam *r, const float *z, uint32_t W, uint32_t H, double cs,
                        const rs_roam_view *v, double tol, double *worst)
{
    mesh m;
    rc_result res;
    int ok = extract(ctx, r, NULL, &m) == RS_OK && check(z, W, H, cs, 1.0, &m, m.ni / 3, &res) && rc_all_ok(&res);
    if (ok && worst) {
        int32_t *gx = malloc((m.nv + 1) * sizeof *gx), *gy = malloc((m.nv + 1) * sizeof *gy);
        for (size_t k = 0; k < m.nv; k++) {
            gx[k] = (int32_t)lround(m.v[5 * k] / cs);
            gy[k] = (int32_t)lround(m.v[5 * k + 1] / cs);
        }
        double k = v->height / (2.0 * tan(30.0 * 3.14159265358979323846 / 180.0));
        *worst = rc_view_worst(W, H, z, 1.0, cs, gx, gy, m.i, m.ni / 3, v->eye, v->dir,
                               29.0 * 3.14159265358979323846 / 180.0, k, tol, 1e-3 * cs, NULL);
        free(gx); free(gy);
    }
    mesh_free(&m);
    return ok;
}

/* Frame f of a low flight over a W x H map of cs-metre cells, turning. */
static void flight_view(int f, uint32_t W, double cs, rs_roam_view *v)
{
    double c = 0.5 * (W - 1) * cs, t = f / 60.0 * 3.0;
    memset(v, 0, sizeof *v);
    v->eye[0] = c + 0.35 * c * cos(t) + 2.0 * f; v->eye[1] = c + 0.35 * c * sin(t); v->eye[2] = 90 + f % 7;
    v->dir[0] = -sin(t); v->dir[1] = cos(t); v->dir[2] = -0.25;
    v->fov_y = 60; v->width = 1024; v->height = 768;
}

/* 1 when every vertex of mesh a is a vertex of mesh b (both extracted with
 * the same frame: equal samples give equal floats). */
static int vertices_within(const mesh *a, const mesh *b)
{
    size_t j = 0;
    /* both are numbered in row-major sample order: one merge pass */
    for (size_t k = 0; k < a->nv; k++) {
        float ax = a->v[5 * k], ay = a->v[5 * k + 1];
        while (j < b->nv && (b->v[5 * j + 1] < ay || (b->v[5 * j + 1] == ay && b->v[5 * j] < ax))) j++;
        if (j == b->nv || b->v[5 * j] != ax || b->v[5 * j + 1] != ay) return 0;
    }
    return 1;
}

/* Frame f of test_update_turning's flight: the camera turns in place, then
 * sweeps sideways while turning. */
static void turning_view(int f, uint32_t W, double cs, rs_roam_view *v)
{
    double a = f * 0.021, c = 0.5 * (W - 1) * cs;
    double side = f < 75 ? 0.0 : (f - 75) * 1.3;
    memset(v, 0, sizeof *v);
    v->eye[0] = c + side * cos(a); v->eye[1] = c + 200.0 + side * sin(a); v->eye[2] = 60.0;
    v->dir[0] = cos(a); v->dir[1] = sin(a); v->dir[2] = -0.2;
    v->fov_y = 50; v->width = 1280; v->height = 720; v->pixel_error = 1.0;
}

/* Frame f of a shuttle: 31 m per frame back and forth along a 600 m line
 * (150 frames, 4.6 km of travel: the scan records' odometer readings are
 * floats from a base that moves every 4 km), looking along the line, with a
 * slow turn so nodes partly in view come due by their turn readings too. */
static void shuttle_view(int f, uint32_t W, double cs, rs_roam_view *v)
{
    double c = 0.5 * (W - 1) * cs, s = fmod(f * 31.0, 1200.0);
    double x = s < 600.0 ? s : 1200.0 - s, dirx = s < 600.0 ? 1.0 : -1.0, a = f * 0.004;
    memset(v, 0, sizeof *v);
    v->eye[0] = c - 300.0 + x; v->eye[1] = c + 40.0 * sin(a); v->eye[2] = 45.0;
    v->dir[0] = dirx * cos(a); v->dir[1] = sin(a); v->dir[2] = -0.2;
    v->fov_y = 50; v->width = 1280; v->height = 720; v->pixel_error = 1.0;
}

/* Frame f of a strafe: the view direction fixed, the eye sliding sideways
 * 9 m per frame and back, so whole subtrees cross the side planes by
 * travel alone (the readings of a node's class). */
static void strafe_view(int f, uint32_t W, double cs, rs_roam_view *v)
{
    double c = 0.5 * (W - 1) * cs, s = fmod(f * 9.0, 1200.0);
    double y = s < 600.0 ? s : 1200.0 - s;
    memset(v, 0, sizeof *v);
    v->eye[0] = c - 500.0; v->eye[1] = c - 300.0 + y; v->eye[2] = 50.0;
    v->dir[0] = 1.0; v->dir[1] = 0.35; v->dir[2] = -0.15;
    v->fov_y = 40; v->width = 1280; v->height = 720; v->pixel_error = 1.0;
}

/* Updates along a flight (150 frames of `view`): after every update no
 * leaf may be above the tolerance, which holds exactly when the mesh
 * refines the rebuild's (the coarsest such mesh): the rebuild's vertices
 * are all in the update's, over the whole frustum (the view check of
 * test_update only looks inside a cone). */
static void update_refines_flight(rs_ctx *ctx, uint32_t patch, const char *name,
                                  void (*view)(int, uint32_t, double, rs_roam_view *))
{
    const uint32_t W = 257, H = 257;
    const double cs = VIEW_CS;
    float *z = NULL;
    rs_dem *d = NULL;
    rs_roam_options o;
    rs_roam *up = make_view_roam(ctx, W, H, patch, 0, &z, &d, &o), *reb = NULL;
    CHECK(up && rs_roam_create(ctx, d, &o, &reb) == RS_OK);
    if (!up || !reb) goto out;
    int refines = 1, ok = 1;
    uint32_t skipped_frames = 0;
    for (int f = 0; f < 150; f++) {
        rs_roam_view v;
        view(f, W, cs, &v);
        if (rs_roam_update(ctx, up, &v, 0) != RS_OK || rs_roam_frame(ctx, reb, &v) != RS_OK) { ok = 0; break; }
        mesh mu, mr;
        if (extract(ctx, up, NULL, &mu) != RS_OK) { ok = 0; break; }
        if (extract(ctx, reb, NULL, &mr) != RS_OK) { mesh_free(&mu); ok = 0; break; }
        if (!vertices_within(&mr, &mu)) refines = 0;
        rs_roam_stats st;
        rs_roam_get_stats(up, &st);
        if (st.update_ops == 0) skipped_frames++;
        mesh_free(&mu);
        mesh_free(&mr);
    }
    CHECK(ok);
    CHECKF(refines, "update (patch %u), %s: the mesh refines the rebuild's on every frame", patch, name);
    printf("update %s (patch %u): %u of 150 updates changed nothing\n", name, patch, skipped_frames);
out:
    rs_roam_free(ctx, up);
    rs_roam_free(ctx, reb);
    rs_dem_free(ctx, d);
    free(z);
}

/* Items near the frustum's sides come into view and leave it, and the
 * update skips subtrees by a bound on how far the frustum moved. */
static void test_update_turning(rs_ctx *ctx, uint32_t patch)
{
    update_refines_flight(ctx, patch, "turning", turning_view);
}

/* Sideways travel without a turn. */
static void test_update_strafe(rs_ctx *ctx, uint32_t patch)
{
    update_refines_flight(ctx, patch, "strafe", strafe_view);
}

/* Kilometres of travel: the readings' base moves (and the scan is full)
 * on the way. */
static void test_update_shuttle(rs_ctx *ctx, uint32_t patch)
{
    update_refines_flight(ctx, patch, "shuttle", shuttle_view);
}

/* rs_roam_update over a flight: crack-free and within the tolerance after
 * every update, never fewer triangles than a rebuild at the same view
 * (the rebuild's mesh is the coarsest that meets the tolerance) and at
 * most 5 % more; with a small work budget still crack-free at every step
 * and within the tolerance once an update completes; a triangle target
 * within 2 % in one update per frame. */
static void test_update(rs_ctx *ctx, uint32_t patch)
{
    const uint32_t W = 257, H = 257;
    const double cs = 10.0, tol = 1.5;
    float *z = view_dem(W, H);
    rs_dem *d = NULL;
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    o.patch_size = patch;
    rs_roam *up = make_f(ctx, z, W, H, cs, 0, &o, &d), *reb = NULL, *bud = NULL, *tgt = NULL;
    CHECK(up && rs_roam_create(ctx, d, &o, &reb) == RS_OK && rs_roam_create(ctx, d, &o, &bud) == RS_OK
          && rs_roam_create(ctx, d, &o, &tgt) == RS_OK);
    if (!up || !reb || !bud || !tgt) goto out;
    int valid = 1, bound = 1, counts = 1, bvalid = 1, bbound = 1, within = 1, rc_ok = 1;
    double worst = 0, bworst = 0, most = 0, tdev = 0;
    uint32_t ops = 0, frames = 0;
    for (int f = 0; f < 60; f++) {
        rs_roam_view v;
        flight_view(f, W, cs, &v);
        v.pixel_error = tol;
        if (rs_roam_update(ctx, up, &v, 0) != RS_OK || rs_roam_frame(ctx, reb, &v) != RS_OK) rc_ok = 0;
        rs_roam_stats a, b, c;
        rs_roam_get_stats(up, &a);
        rs_roam_get_stats(reb, &b);
        double w = 0;
        if (!view_mesh_ok(ctx, up, z, W, H, cs, &v, tol, &w)) valid = 0;
        if (w > worst) worst = w;
        if (!a.update_done || w > 1.0) bound = 0;
        double ratio = (double)a.triangles / b.triangles;
        if (ratio > most) most = ratio;
        if (a.triangles < b.triangles || ratio > 1.05) counts = 0;
        ops += a.update_ops;
        /* 7 operations per update: valid at every step, within the
         * tolerance when an update completes */
        if (rs_roam_update(ctx, bud, &v, 7) != RS_OK) rc_ok = 0;
        rs_roam_get_stats(bud, &c);
        if (!view_mesh_ok(ctx, bud, z, W, H, cs, &v, tol, c.update_done ? &w : NULL)) bvalid = 0;
        if (c.update_done && w > bworst) bworst = w;
        if (c.update_done && w > 1.0) bbound = 0;
        frames += (uint32_t)c.update_done;
        v.target_triangles = 3000;
        if (rs_roam_update(ctx, tgt, &v, 0) != RS_OK) rc_ok = 0;
        rs_roam_get_stats(tgt, &c);
        double dev = fabs((double)c.triangles - 3000.0) / 3000.0;
        if (dev > tdev) tdev = dev;
        if (dev > 0.02 || c.frame_passes != 1) within = 0;
        if (f % 6 == 0 && !view_mesh_ok(ctx, tgt, z, W, H, cs, &v, tol, NULL)) within = 0;
    }
    CHECK(rc_ok);
    CHECKF(valid, "update (patch %u): every mesh valid and crack-free", patch);
    CHECKF(bound, "update (patch %u): within the tolerance after every update (worst %.4f of it)", patch, worst);
    CHECKF(counts, "update (patch %u): rebuild <= update <= 1.05 x rebuild triangles (worst %.4f)", patch, most);
    CHECKF(bvalid, "update (patch %u) with a budget of 7: crack-free after every step", patch);
    CHECKF(bbound, "update (patch %u) with a budget: within the tolerance when complete (%u of 60, worst %.4f)",
           patch, frames, bworst);
    CHECKF(within, "update (patch %u): triangle target within 2 %% in one update per frame (worst %.2f %%)", patch,
           100 * tdev);
    printf("update (patch %u): %u split/merge operations over 60 frames, worst tris ratio %.4f\n", patch, ops, most);
    /* the budgeted landscape catches up at the last view */
    {
        rs_roam_view v;
        flight_view(59, W, cs, &v);
        v.pixel_error = tol;
        rs_roam_stats c;
        int n = 0;
        do {
            rs_roam_update(ctx, bud, &v, 7);
            rs_roam_get_stats(bud, &c);
        } while (!c.update_done && ++n < 100000);
        double w = 0;
        CHECK(c.update_done && view_mesh_ok(ctx, bud, z, W, H, cs, &v, tol, &w) && w <= 1.0);
        /* other modes and updates mix: a rebuild, then updates from it */
        CHECK_EQ_INT(rs_roam_refine_error(ctx, bud, 2.0), RS_OK);
        CHECK_EQ_INT(rs_roam_update(ctx, bud, &v, 0), RS_OK);
        rs_roam_stats a, b;
        rs_roam_get_stats(bud, &a);
        CHECK_EQ_INT(rs_roam_frame(ctx, reb, &v), RS_OK);
        rs_roam_get_stats(reb, &b);
        /* a mesh another mode left finer keeps what lies between the merge
         * and split thresholds (tol / 1.25 .. tol): up to 7 % more here
         * (4 % with a hysteresis of 1.1); on a drive 0.8 % (target 3) */
        CHECK(view_mesh_ok(ctx, bud, z, W, H, cs, &v, tol, &w) && w <= 1.0 && a.triangles >= b.triangles
              && a.triangles <= b.triangles * 1.10);
    }
    /* bad arguments */
    CHECK_EQ_INT(rs_roam_update(ctx, NULL, NULL, 0), RS_ERR_INVALID_ARG);
    {
        rs_roam_view v;
        memset(&v, 0, sizeof v);
        CHECK_EQ_INT(rs_roam_update(ctx, up, &v, 0), RS_ERR_INVALID_ARG); /* dir 0 */
        v.dir[0] = 1;
        v.merge_hysteresis = 0.5;
        CHECK_EQ_INT(rs_roam_update(ctx, up, &v, 0), RS_ERR_INVALID_ARG);
    }
out:
    rs_roam_free(ctx, up); rs_roam_free(ctx, reb); rs_roam_free(ctx, bud); rs_roam_free(ctx, tgt);
    rs_dem_free(ctx, d);
    free(z);
}

/* Triangles of patch p, or with `unit` of upload unit p (or of the whole
 * mesh, p = UINT32_MAX) as sorted keys of their corner samples (rotated to
 * start at the smallest, so the winding is kept); NULL on failure. *nvert:
 * the vertices written. */
static uint64_t *part_keys(rs_ctx *ctx, rs_roam *r, int unit, uint32_t p, uint32_t W, double cs, size_t *n,
                           size_t *nvert)
{
    size_t mv, mi, nv = 0, ni = 0;
    rs_roam_mesh_bound(r, NULL, &mv, &mi);
    float *v = malloc((mv + 1) * 5 * sizeof *v);
    uint32_t *ix = malloc((mi + 1) * sizeof *ix);
    rs_result rr = p == UINT32_MAX ? rs_roam_extract(ctx, r, NULL, v, NULL, mv, ix, mi, &nv, &ni)
                   : unit ? rs_roam_extract_unit(ctx, r, p, NULL, v, NULL, mv, ix, mi, &nv, &ni)
                          : rs_roam_extract_patch(ctx, r, p, NULL, v, NULL, mv, ix, mi, &nv, &ni);
    *nvert = nv;
    for (size_t t = 0; rr == RS_OK && t < ni; t++)
        if (ix[t] >= nv) rr = RS_ERR_INVALID_ARG; /* an index past the part's vertices */
    uint64_t *k = rr == RS_OK ? rc_tri_keys(v, ix, ni / 3, W, cs) : NULL;
    *n = ni / 3;
    free(v); free(ix);
    return k;
}

static uint64_t *tri_keys(rs_ctx *ctx, rs_roam *r, uint32_t p, uint32_t W, double cs, size_t *n)
{
    size_t nv;
    return part_keys(ctx, r, 0, p, W, cs, n, &nv);
}

/* Sorted triangle keys (part_keys) of a W x H map: conforming (no corner
 * strictly inside another triangle's edge) and covering the map (the
 * areas add up to it, every triangle counter-clockwise). */
static int keys_conform(const uint64_t *k, size_t n, uint32_t W, uint32_t H)
{
    unsigned char *isv = calloc((size_t)W * H, 1);
    if (!isv) return 0;
    const uint64_t m21 = (1u << 21) - 1u;
    for (size_t t = 0; t < n; t++)
        for (int c = 0; c < 3; c++) isv[(k[t] >> (21 * c)) & m21] = 1;
    int ok = 1;
    double area2 = 0;
    for (size_t t = 0; t < n && ok; t++) {
        long x[3], y[3];
        for (int c = 0; c < 3; c++) {
            uint64_t s = (k[t] >> (42 - 21 * c)) & m21;
            x[c] = (long)(s % W); y[c] = (long)(s / W);
        }
        area2 += (double)((x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]));
        for (int c = 0; c < 3 && ok; c++) {
            long ex = x[(c + 1) % 3] - x[c], ey = y[(c + 1) % 3] - y[c];
            long g = labs(ex) > labs(ey) ? labs(ex) : labs(ey);
            for (long s = 1; s < g && ok; s++)
                if (isv[(size_t)(y[c] + ey / g * s) * W + (size_t)(x[c] + ex / g * s)]) ok = 0;
        }
    }
    free(isv);
    return ok && fabs(fabs(area2) - 2.0 * (W - 1) * (H - 1)) < 0.5;
}

/* Upload units over a flight (issue 31, target 4): the units' triangles
 * together are exactly the mesh's (and so conform and cover the map), an
 * unchanged unit generation means unchanged triangles, a changed one is
 * reported for fewer vertices than the patches' generations report, and a
 * rebuild changes every unit's generation. */
static void test_units(rs_ctx *ctx, uint32_t W, uint32_t H, uint32_t patch, uint32_t unit, uint32_t want_size)
{
    const double cs = VIEW_CS;
    float *z = NULL;
    rs_dem *d = NULL;
    rs_roam_options o;
    rs_roam *r = make_view_roam(ctx, W, H, patch, unit, &z, &d, &o);
    CHECK(r != NULL);
    if (!r) { free(z); return; }
    rs_roam_stats st;
    rs_roam_get_stats(r, &st);
    uint32_t np = st.patches_x * st.patches_y, nu = st.units, upp = nu / np;
    CHECKF(st.unit_size == want_size && upp == 2 * (st.patch_size / want_size) * (st.patch_size / want_size)
           && nu == np * upp, "units: patch %u unit_size %u -> %u (%u per patch)", st.patch_size, unit, st.unit_size, upp);
    uint64_t **prev = calloc(nu, sizeof *prev);
    size_t *nprev = calloc(nu, sizeof *nprev), *vcount = calloc(nu, sizeof *vcount);
    uint32_t *gen = calloc(nu, sizeof *gen), *pgen = calloc(np, sizeof *pgen);
    int union_ok = 1, kept_ok = 1, conform_ok = 1, kept = 0, changed = 0;
    double unit_up = 0, patch_up = 0;
    for (int f = 0; prev && f < 30; f++) {
        rs_roam_view v;
        flight_view(f, W, cs, &v);
        v.pixel_error = 1.5;
        CHECK_EQ_INT(rs_roam_update(ctx, r, &v, 0), RS_OK);
        size_t nall, sum = 0, vall = 0, vchanged = 0, vpatch = 0;
        uint64_t *all = tri_keys(ctx, r, UINT32_MAX, W, cs, &nall), *cat = malloc((nall + 1) * sizeof *cat);
        for (uint32_t u = 0; u < nu; u++) {
            size_t n = 0, nv = 0;
            uint64_t *k = part_keys(ctx, r, 1, u, W, cs, &n, &nv);
            if (!k) { union_ok = 0; continue; }
            if (sum + n <= nall) memcpy(cat + sum, k, n * sizeof *k);
            sum += n;
            vall += nv;
            uint32_t g = rs_roam_unit_generation(r, u);
            if (f > 0 && g == gen[u]) {
                kept++;
                if (n != nprev[u] || memcmp(k, prev[u], n * sizeof *k) != 0) kept_ok = 0;
            } else if (f > 0) { changed++; vchanged += nv; }
            if (f > 0 && rs_roam_patch_generation(r, u / upp) != pgen[u / upp]) vpatch += nv;
            free(prev[u]);
            prev[u] = k; nprev[u] = n; gen[u] = g; vcount[u] = nv;
        }
        for (uint32_t p = 0; p < np; p++) pgen[p] = rs_roam_patch_generation(r, p);
        if (f > 0 && vall) { unit_up += (double)vchanged / vall; patch_up += (double)vpatch / vall; }
        if (sum != nall || !all) union_ok = 0;
        else {
            qsort(cat, sum, sizeof *cat, rc_cmp_u64);
            if (memcmp(cat, all, sum * sizeof *cat) != 0) union_ok = 0;
            else if (!keys_conform(cat, sum, W, H)) conform_ok = 0;
        }
        free(all); free(cat);
    }
    CHECKF(union_ok, "units (patch %u, unit %u): their triangles together are exactly the mesh's", st.patch_size, st.unit_size);
    CHECKF(conform_ok, "units (patch %u, unit %u): together crack-free and covering the map", st.patch_size, st.unit_size);
    CHECKF(kept_ok, "units (patch %u, unit %u): an unchanged generation means unchanged triangles", st.patch_size, st.unit_size);
    /* (patches of 1 or 2 cells use no pool node: every update rebuilds from
     * the base mesh, and every generation changes) */
    CHECKF(changed > 0 && (kept > 0 || st.patch_size <= 2), "units: %d kept and %d changed over the flight", kept, changed);
    if (st.unit_size < st.patch_size)
        CHECKF(unit_up < patch_up, "units (patch %u, unit %u): re-upload %.3f below the patches' %.3f", st.patch_size,
               st.unit_size, unit_up / 29, patch_up / 29);
    /* out of range */
    CHECK_EQ_INT(rs_roam_unit_generation(r, nu), 0);
    CHECK_EQ_INT(rs_roam_unit_generation(NULL, 0), 0);
    {
        size_t nv = 7, ni = 7;
        float vb[5];
        uint32_t ib[3];
        CHECK_EQ_INT(rs_roam_extract_unit(ctx, r, nu, NULL, vb, NULL, 1, ib, 3, &nv, &ni), RS_ERR_INVALID_ARG);
        CHECK(nv == 0 && ni == 0);
        CHECK_EQ_INT(rs_roam_extract_unit(ctx, NULL, 0, NULL, vb, NULL, 1, ib, 3, &nv, &ni), RS_ERR_INVALID_ARG);
    }
    /* a rebuild changes every unit's generation */
    int all_changed = 1;
    rs_roam_refine_error(ctx, r, 1.0);
    for (uint32_t u = 0; u < nu; u++) all_changed &= rs_roam_unit_generation(r, u) != gen[u];
    CHECKF(all_changed, "units: a rebuild changes every unit's generation");
    /* unit_size must be a power of two */
    o.unit_size = 12;
    rs_roam *bad = NULL;
    CHECK_EQ_INT(rs_roam_create(ctx, d, &o, &bad), RS_ERR_INVALID_ARG);
    for (uint32_t u = 0; prev && u < nu; u++) free(prev[u]);
    free(prev); free(nprev); free(vcount); free(gen); free(pgen);
    rs_roam_free(ctx, r);
    rs_dem_free(ctx, d);
    free(z);
}

/* Per-patch output over a flight: the patches' triangles together are the
 * mesh's, and a patch whose generation did not change since the last
 * update has the same triangles as then. */
static void test_patches(rs_ctx *ctx)
{
    const uint32_t W = 257, H = 257, np = 16; /* automatic size: 64-cell patches */
    const double cs = 10.0;
    float *z = view_dem(W, H);
    rs_dem *d = NULL;
    rs_roam *r = make_f(ctx, z, W, H, cs, 0, NULL, &d);
    CHECK(r != NULL);
    rs_roam_stats st;
    rs_roam_get_stats(r, &st);
    CHECK_EQ_INT(st.patches_x * st.patches_y, np);
    uint64_t *prev[16] = { NULL };
    size_t nprev[16] = { 0 };
    uint32_t gen[16] = { 0 };
    int union_ok = 1, kept_ok = 1, kept = 0, changed = 0;
    for (int f = 0; r && f < 30; f++) {
        rs_roam_view v;
        flight_view(f, W, cs, &v);
        v.pixel_error = 1.5;
        CHECK_EQ_INT(rs_roam_update(ctx, r, &v, 0), RS_OK);
        size_t nall, sum = 0;
        uint64_t *all = tri_keys(ctx, r, UINT32_MAX, W, cs, &nall), *cat = malloc((nall + 1) * sizeof *cat);
        for (uint32_t p = 0; p < np; p++) {
            size_t n = 0;
            uint64_t *k = tri_keys(ctx, r, p, W, cs, &n);
            if (!k) { union_ok = 0; continue; }
            if (sum + n <= nall) memcpy(cat + sum, k, n * sizeof *k);
            sum += n;
            uint32_t g = rs_roam_patch_generation(r, p);
            if (f > 0 && g == gen[p]) {
                kept++;
                if (n != nprev[p] || memcmp(k, prev[p], n * sizeof *k) != 0) kept_ok = 0;
            } else if (f > 0) changed++;
            free(prev[p]);
            prev[p] = k; nprev[p] = n; gen[p] = g;
        }
        if (sum != nall) union_ok = 0;
        else {
            qsort(cat, sum, sizeof *cat, rc_cmp_u64);
            if (!all || memcmp(cat, all, sum * sizeof *cat) != 0) union_ok = 0;
        }
        free(all); free(cat);
    }
    CHECKF(union_ok, "patches: their triangles together are the mesh's");
    CHECKF(kept_ok, "patches: an unchanged generation means unchanged triangles");
    CHECKF(kept > 0 && changed > 0, "patches: %d kept and %d changed over the flight", kept, changed);
    CHECK_EQ_INT(rs_roam_patch_generation(r, np), 0);
    {
        size_t nv, ni;
        float vb[5];
        uint32_t ib[3];
        CHECK_EQ_INT(rs_roam_extract_patch(ctx, r, np, NULL, vb, NULL, 1, ib, 3, &nv, &ni), RS_ERR_INVALID_ARG);
    }
    /* a rebuild changes every patch's generation */
    uint32_t g0 = rs_roam_patch_generation(r, 0);
    rs_roam_refine_error(ctx, r, 1.0);
    CHECK(rs_roam_patch_generation(r, 0) != g0);
    for (uint32_t p = 0; p < np; p++) free(prev[p]);
    rs_roam_free(ctx, r);
    rs_dem_free(ctx, d);
    free(z);
}

/* Seams: two landscapes on the halves of one DEM (sharing the middle
 * column, or the middle row), updated with the same camera, then
 * stitched: together they must be one crack-free mesh of the whole DEM
 * (rc_check: every interior edge paired, no T-junction across the seam);
 * without the stitch they are not. */
static void test_seams(rs_ctx *ctx, int vertical_seam)
{
    const uint32_t S = 129, N = 2 * S - 1; /* the whole map: N x S or S x N */
    const uint32_t WW = vertical_seam ? N : S, HH = vertical_seam ? S : N;
    const double cs = 10.0;
    float *z = malloc((size_t)WW * HH * sizeof *z), *h[2];
    rc_dem_fractal(z, WW, HH, 21, 48.0, 60.0, 0.55);
    rs_dem *d[2] = { NULL, NULL };
    rs_roam *r[2] = { NULL, NULL };
    for (int k = 0; k < 2; k++) {
        h[k] = malloc((size_t)S * S * sizeof *h[k]);
        for (uint32_t y = 0; y < S; y++)
            for (uint32_t x = 0; x < S; x++)
                h[k][(size_t)y * S + x] = vertical_seam ? z[(size_t)y * WW + x + (uint32_t)k * (S - 1)]
                                                        : z[(size_t)(y + (uint32_t)k * (S - 1)) * WW + x];
        r[k] = make_f(ctx, h[k], S, S, cs, 0, NULL, &d[k]);
    }
    CHECK(r[0] && r[1]);
    int open_before = 0, closed = 1, valid = 1;
    for (int f = 0; r[0] && r[1] && f < 12; f++) {
        rs_roam_view v;
        flight_view(f, WW, cs, &v);
        v.eye[1] = 0.5 * (HH - 1) * cs + 0.2 * (HH - 1) * cs * sin(f / 4.0);
        v.pixel_error = 1.0;
        for (int k = 0; k < 2; k++) {
            rs_roam_view w = v; /* the same camera in each tile's frame */
            if (vertical_seam) w.eye[0] -= k * (S - 1) * cs; else w.eye[1] -= k * (S - 1) * cs;
            CHECK_EQ_INT(rs_roam_update(ctx, r[k], &w, 0), RS_OK);
        }
        for (int pass = 0; pass < 2; pass++) {
            if (pass == 1)
                CHECK_EQ_INT(rs_roam_stitch(ctx, r[0], vertical_seam ? RS_ROAM_EDGE_RIGHT : RS_ROAM_EDGE_BOTTOM, r[1],
                                            vertical_seam ? RS_ROAM_EDGE_LEFT : RS_ROAM_EDGE_TOP), RS_OK);
            /* both meshes in the whole map's grid */
            mesh m[2];
            extract(ctx, r[0], NULL, &m[0]);
            extract(ctx, r[1], NULL, &m[1]);
            size_t nv = m[0].nv + m[1].nv, ni = m[0].ni + m[1].ni;
            int32_t *gx = malloc((nv + 1) * sizeof *gx), *gy = malloc((nv + 1) * sizeof *gy);
            double *vz = malloc((nv + 1) * sizeof *vz);
            uint32_t *ix = malloc((ni + 1) * sizeof *ix);
            for (int k = 0; k < 2; k++) {
                size_t v0 = k ? m[0].nv : 0, i0 = k ? m[0].ni : 0;
                for (size_t q = 0; q < m[k].nv; q++) {
                    gx[v0 + q] = (int32_t)lround(m[k].v[5 * q] / cs) + (vertical_seam ? k * (int32_t)(S - 1) : 0);
                    gy[v0 + q] = (int32_t)lround(m[k].v[5 * q + 1] / cs) + (vertical_seam ? 0 : k * (int32_t)(S - 1));
                    vz[v0 + q] = m[k].v[5 * q + 2];
                }
                for (size_t q = 0; q < m[k].ni; q++) ix[i0 + q] = m[k].i[q] + (uint32_t)v0;
            }
            float *zf = malloc((size_t)WW * HH * sizeof *zf);
            for (size_t q = 0; q < (size_t)WW * HH; q++) zf[q] = (float)z[q];
            rc_result res;
            int ok = rc_check(WW, HH, zf, 1.0, gx, gy, vz, nv, ix, ni / 3, &res);
            if (!ok || !res.ok_grid || !res.ok_heights || !res.ok_winding || !res.ok_area || !res.ok_coverage) valid = 0;
            int seamless = ok && res.ok_edges && res.ok_tjunction;
            if (pass == 0 && !seamless) open_before++;
            if (pass == 1 && !seamless) closed = 0;
            free(gx); free(gy); free(vz); free(ix); free(zf);
            mesh_free(&m[0]); mesh_free(&m[1]);
        }
    }
    CHECKF(valid, "seams (%s): both tiles' meshes valid", vertical_seam ? "columns" : "rows");
    CHECKF(closed, "seams (%s): stitched tiles form one crack-free mesh on every frame", vertical_seam ? "columns" : "rows");
    CHECKF(open_before > 0, "seams (%s): unstitched tiles had T-junctions on %d of 12 frames", vertical_seam ? "columns" : "rows",
           open_before);
    printf("seams (%s): open before stitching on %d of 12 frames\n", vertical_seam ? "columns" : "rows", open_before);
    /* refused: mismatched edges */
    if (r[0] && r[1]) {
        CHECK_EQ_INT(rs_roam_stitch(ctx, r[0], 7, r[1], RS_ROAM_EDGE_LEFT), RS_ERR_INVALID_ARG);
        CHECK_EQ_INT(rs_roam_stitch(ctx, r[0], RS_ROAM_EDGE_LEFT, r[0], RS_ROAM_EDGE_RIGHT), RS_ERR_INVALID_ARG);
    }
    for (int k = 0; k < 2; k++) {
        rs_roam_free(ctx, r[k]);
        rs_dem_free(ctx, d[k]);
        free(h[k]);
    }
    free(z);
}

static void test_extract_options(rs_ctx *ctx)
{
    const uint32_t W = 45, H = 30; /* not 2^n+1: border splits */
    float *z = gen(DEM_NODATA, W, H);
    rs_dem *d = NULL;
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    rs_roam *r = make_f(ctx, z, W, H, 2.0, 0.5, &o, &d);
    CHECK(r != NULL);
    if (!r) { free(z); return; }
    CHECK_EQ_INT(rs_roam_refine_error(ctx, r, 0.5), RS_OK);
    rs_roam_stats st;
    rs_roam_get_stats(r, &st);
    rs_roam_mesh_options mo = { sizeof(rs_roam_mesh_options), 1, 7.5, NULL };
    mesh m;
    CHECK_EQ_INT(extract(ctx, r, &mo, &m), RS_OK);
    int finite = 1, unit = 1, uv = 1;
    for (size_t k = 0; k < m.nv; k++) {
        for (int c = 0; c < 5; c++) if (!isfinite(m.v[5 * k + c])) finite = 0;
        double l = sqrt(m.n[3 * k] * m.n[3 * k] + m.n[3 * k + 1] * m.n[3 * k + 1] + m.n[3 * k + 2] * m.n[3 * k + 2]);
        if (fabs(l - 1) > 1e-5 || !(m.n[3 * k + 2] > 0)) unit = 0;
        if (fabs(m.v[5 * k + 3] - m.v[5 * k] / (2.0 * (W - 1))) > 1e-6 || fabs(m.v[5 * k + 4] - m.v[5 * k + 1] / (2.0 * (H - 1))) > 1e-6)
            uv = 0;
    }
    CHECK(finite);  /* nodata never yields a NaN vertex */
    CHECK(unit);
    CHECK(uv);
    size_t top = (size_t)st.triangles * 3;
    CHECK(m.ni > top);
    rc_result res;
    CHECKF(check(z, W, H, 2.0, 0.5, &m, st.triangles, &res) && rc_all_ok(&res), "grid %d h %d wind %d area %d edges %d tj %d cov %d",
           res.ok_grid, res.ok_heights, res.ok_winding, res.ok_area, res.ok_edges, res.ok_tjunction, res.ok_coverage);
    CHECKF(res.max_err <= 0.5 + 1e-4, "nodata DEM: max error %g over valid samples", res.max_err);
    /* skirt: walls hang below their top vertices, facing outwards */
    int skirt_ok = 1;
    for (size_t t = top; t < m.ni; t += 3) {
        const float *a = m.v + 5 * m.i[t], *b = m.v + 5 * m.i[t + 1], *c = m.v + 5 * m.i[t + 2];
        /* wall normal (library frame) must point away from the map centre */
        double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
        double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
        double nx = uy * vz - uz * vy, ny = uz * vx - ux * vz;
        /* the library frame is left-handed (y down): flip to get the outward side */
        double cx = (a[0] + b[0] + c[0]) / 3 - (W - 1), cy = (a[1] + b[1] + c[1]) / 3 - (H - 1);
        if (-(nx * cx + ny * cy) <= 0) skirt_ok = 0;
        if (fabs(a[2] - b[2]) < 1e-6 && fabs(a[2] - c[2]) < 1e-6) skirt_ok = 0;
    }
    CHECK(skirt_ok);
    size_t border = 0;
    for (size_t t = 0; t < top; t += 3)
        for (int e = 0; e < 3; e++) {
            const float *p = m.v + 5 * m.i[t + (size_t)e], *q = m.v + 5 * m.i[t + (size_t)(e + 1) % 3];
            if ((p[0] == q[0] && (p[0] == 0 || p[0] == 2.0f * (W - 1))) || (p[1] == q[1] && (p[1] == 0 || p[1] == 2.0f * (H - 1))))
                border++;
        }
    CHECK_EQ_INT(m.ni - top, 6 * border);
    /* buffers one short fail cleanly */
    size_t mv, mi, nv, ni;
    rs_roam_mesh_bound(r, &mo, &mv, &mi);
    CHECK(m.nv <= mv && m.ni <= mi);
    CHECK_EQ_INT(rs_roam_extract(ctx, r, &mo, m.v, m.n, m.nv - 1, m.i, mi, &nv, &ni), RS_ERR_BUFFER_TOO_SMALL);
    CHECK_EQ_INT(rs_roam_extract(ctx, r, &mo, m.v, m.n, mv, m.i, m.ni - 1, &nv, &ni), RS_ERR_BUFFER_TOO_SMALL);
    CHECK(strlen(rs_ctx_message(ctx)) > 0);
    CHECK_EQ_INT(rs_roam_extract(ctx, r, &mo, m.v, NULL, mv, m.i, mi, &nv, &ni), RS_ERR_INVALID_ARG);
    /* and still work afterwards, identically */
    mesh m2;
    CHECK_EQ_INT(extract(ctx, r, &mo, &m2), RS_OK);
    CHECK(same_indices(&m, &m2));
    mesh_free(&m2);
    mesh_free(&m);
    rs_roam_free(ctx, r);
    rs_dem_free(ctx, d);
    /* all nodata: a flat mesh at 0 */
    for (size_t k = 0; k < (size_t)W * H; k++) z[k] = NAN;
    r = make(ctx, z, W, H, NULL, &d);
    CHECK(r != NULL);
    if (r) {
        CHECK_EQ_INT(rs_roam_refine_error(ctx, r, 0.0), RS_OK);
        CHECK_EQ_INT(extract(ctx, r, NULL, &m), RS_OK);
        int zero = 1;
        for (size_t k = 0; k < m.nv; k++) if (m.v[5 * k + 2] != 0.0f) zero = 0;
        CHECK(zero);
        mesh_free(&m);
        rs_roam_free(ctx, r);
        rs_dem_free(ctx, d);
    }
    free(z);
}

typedef struct fail_alloc { int left; int live; } fail_alloc;
static void *fa_malloc(void *u, size_t n)
{
    fail_alloc *f = u;
    if (f->left-- <= 0) return NULL;
    f->live++;
    return malloc(n);
}
static void *fa_realloc(void *u, void *p, size_t n)
{
    fail_alloc *f = u;
    if (f->left-- <= 0) return NULL;
    if (!p) f->live++;
    return realloc(p, n);
}
static void fa_free(void *u, void *p) { fail_alloc *f = u; f->live--; free(p); }

static void test_errors(rs_ctx *ctx)
{
    float z[12] = { 0 };
    rs_dem *d = NULL, *thin = NULL;
    rs_roam *r = NULL;
    CHECK_EQ_INT(rs_dem_create(ctx, 4, 3, z, &d), RS_OK);
    CHECK_EQ_INT(rs_roam_create(ctx, NULL, NULL, &r), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_roam_create(ctx, d, NULL, NULL), RS_ERR_INVALID_ARG);
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    rs_dem_frame fr = { -1, 0, 0, 0 };
    CHECK_EQ_INT(rs_dem_set_frame(ctx, d, &fr), RS_ERR_INVALID_ARG);
    CHECK(strstr(rs_ctx_message(ctx), "cell size") != NULL);
    fr.cell_size = 1; fr.z_scale = NAN;
    CHECK_EQ_INT(rs_dem_set_frame(ctx, d, &fr), RS_ERR_INVALID_ARG);
    fr.z_scale = -2;
    CHECK_EQ_INT(rs_dem_set_frame(ctx, d, &fr), RS_OK);
    CHECK_EQ_INT(rs_roam_create(ctx, d, &o, &r), RS_ERR_INVALID_ARG);
    CHECK(strstr(rs_ctx_message(ctx), "z-scale") != NULL);
    fr.z_scale = 1;
    CHECK_EQ_INT(rs_dem_set_frame(ctx, d, &fr), RS_OK);
    o.patch_size = 3;
    CHECK_EQ_INT(rs_roam_create(ctx, d, &o, &r), RS_ERR_INVALID_ARG);
    o.patch_size = 0; o.pool_nodes = 0xFFFFFFFFu;
    CHECK_EQ_INT(rs_roam_create(ctx, d, &o, &r), RS_ERR_LIMIT);
    o.pool_nodes = 0;
    CHECK_EQ_INT(rs_roam_create(ctx, d, &o, &r), RS_OK);
    CHECK_EQ_INT(rs_roam_refine_error(ctx, r, NAN), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_roam_refine_error(ctx, r, -1), RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_roam_refine_count(ctx, r, 0), RS_ERR_LIMIT);
    CHECK_EQ_INT(rs_roam_refine_error(ctx, NULL, 1), RS_ERR_INVALID_ARG);
    rs_roam_free(ctx, r);
    rs_roam_free(ctx, NULL);
    float z2[2] = { 1, 2 };
    if (rs_dem_create(ctx, 2, 1, z2, &thin) == RS_OK) {
        CHECK_EQ_INT(rs_roam_create(ctx, thin, NULL, &r), RS_ERR_INVALID_ARG);
        rs_dem_free(ctx, thin);
    }
    rs_dem_free(ctx, d);
    /* every allocation failing in turn: clean failure, nothing leaked */
    const uint32_t W = 37, H = 21;
    float *zz = gen(DEM_NODATA, W, H);
    int clean = 1, reached_ok = 0;
    for (int k = 0; k < 40 && !reached_ok; k++) {
        fail_alloc fa = { 1000, 0 };
        rs_allocator al = { fa_malloc, fa_realloc, fa_free, &fa };
        rs_ctx *c2 = NULL;
        if (rs_ctx_create(&al, NULL, &c2) != RS_OK) { clean = 0; break; }
        rs_dem *dd = NULL;
        if (rs_dem_create(c2, W, H, zz, &dd) != RS_OK) { clean = 0; rs_ctx_free(c2); break; }
        int live0 = fa.live;
        fa.left = k;
        rs_roam *rr = NULL;
        rs_result res = rs_roam_create(c2, dd, NULL, &rr);
        fa.left = 1000;
        if (res == RS_OK) { reached_ok = 1; rs_roam_free(c2, rr); }
        else if (res != RS_ERR_NOMEM || rr != NULL) clean = 0;
        if (fa.live != live0) clean = 0;
        rs_dem_free(c2, dd);
        rs_ctx_free(c2);
    }
    CHECK(clean);
    CHECK(reached_ok);
    free(zz);
}

static int same_mesh(const mesh *a, const mesh *b)
{
    return same_indices(a, b) && memcmp(a->v, b->v, a->nv * 5 * sizeof(float)) == 0;
}

/* rs_roam_set_dem: a landscape moved through several DEMs of one size gives
 * byte-identical meshes to fresh landscapes on each, in every mode; a size
 * mismatch or an allocation failure leaves it on its previous DEM. */
static void test_set_dem(rs_ctx *ctx)
{
    const uint32_t W = 45, H = 29;
    const int kinds[] = { DEM_FRACTAL, DEM_NODATA, DEM_SPIKE, DEM_NODATA, DEM_CHECKER, DEM_FRACTAL };
    rs_dem *d0 = NULL;
    float *z0 = gen(DEM_RIDGE, W, H);
    rs_roam *moved = make(ctx, z0, W, H, NULL, &d0);
    CHECK(moved != NULL);
    if (!moved) { free(z0); return; }
    int same_err = 1, same_count = 0, same_view = 1;
    for (size_t t = 0; t < sizeof kinds / sizeof kinds[0]; t++) {
        float *z = gen(kinds[t], W, H);
        rs_dem *d = NULL, *df = NULL;
        if (rs_dem_create(ctx, W, H, z, &d) != RS_OK) { free(z); same_err = 0; continue; }
        rs_roam *fresh = make(ctx, z, W, H, NULL, &df);
        CHECK_EQ_INT(rs_roam_set_dem(ctx, moved, d), RS_OK);
        mesh a, b;
        double Es[] = { 0.0, 0.5, 40.0 };
        for (int e = 0; e < 3 && fresh; e++) {
            rs_roam_refine_error(ctx, moved, Es[e]);
            rs_roam_refine_error(ctx, fresh, Es[e]);
            extract(ctx, moved, NULL, &a);
            extract(ctx, fresh, NULL, &b);
            if (!same_mesh(&a, &b)) same_err = 0;
            mesh_free(&a); mesh_free(&b);
        }
        if (fresh) {
            rs_roam_refine_count(ctx, moved, 300);
            rs_roam_refine_count(ctx, fresh, 300);
            extract(ctx, moved, NULL, &a);
            extract(ctx, fresh, NULL, &b);
            same_count += same_mesh(&a, &b);
            mesh_free(&a); mesh_free(&b);
            rs_roam_view v;
            memset(&v, 0, sizeof v);
            v.eye[0] = 10; v.eye[1] = -15; v.eye[2] = 50000;
            v.dir[0] = 0.3; v.dir[1] = 1; v.dir[2] = -0.4;
            v.pixel_error = 2; v.target_triangles = 400;
            rs_roam_frame(ctx, moved, &v);
            rs_roam_frame(ctx, fresh, &v);
            extract(ctx, moved, NULL, &a);
            extract(ctx, fresh, NULL, &b);
            if (!same_mesh(&a, &b)) same_view = 0;
            mesh_free(&a); mesh_free(&b);
        } else same_err = 0;
        rs_roam_free(ctx, fresh);
        rs_dem_free(ctx, df);
        /* keep d alive: the landscape references it */
        rs_dem_free(ctx, d0);
        d0 = d;
        free(z);
    }
    CHECKF(same_err, "set_dem: error-bounded meshes identical to fresh landscapes (%zu DEMs)",
           sizeof kinds / sizeof kinds[0]);
    CHECK_EQ_INT(same_count, (int)(sizeof kinds / sizeof kinds[0]));
    CHECKF(same_view, "set_dem: view-dependent meshes identical to fresh landscapes");

    /* wrong size: refused, the landscape still meshes its current DEM */
    mesh before, after;
    rs_roam_refine_error(ctx, moved, 1.0);
    extract(ctx, moved, NULL, &before);
    float zs[6] = { 0, 1, 2, 3, 4, 5 };
    rs_dem *small = NULL;
    if (rs_dem_create(ctx, 3, 2, zs, &small) == RS_OK) {
        CHECK_EQ_INT(rs_roam_set_dem(ctx, moved, small), RS_ERR_INVALID_ARG);
        CHECK(strstr(rs_ctx_message(ctx), "3x2") != NULL);
        rs_dem_free(ctx, small);
    }
    CHECK_EQ_INT(rs_roam_set_dem(ctx, moved, NULL), RS_ERR_INVALID_ARG);
    rs_roam_refine_error(ctx, moved, 1.0);
    extract(ctx, moved, NULL, &after);
    CHECK(same_mesh(&before, &after));
    mesh_free(&before); mesh_free(&after);
    rs_roam_free(ctx, moved);
    rs_dem_free(ctx, d0);
    free(z0);

    /* out of memory while filling a nodata DEM: RS_ERR_NOMEM, previous DEM kept, no leak */
    float *za = gen(DEM_FRACTAL, W, H), *zb = gen(DEM_NODATA, W, H);
    fail_alloc fa = { 1000, 0 };
    rs_allocator al = { fa_malloc, fa_realloc, fa_free, &fa };
    rs_ctx *c2 = NULL;
    int nomem_ok = 0, kept = 0, leak_free = 0;
    if (rs_ctx_create(&al, NULL, &c2) == RS_OK) {
        rs_dem *da = NULL, *db = NULL;
        rs_roam *r = make(c2, za, W, H, NULL, &da);
        if (r && rs_dem_create(c2, W, H, zb, &db) == RS_OK) {
            rs_roam_refine_error(c2, r, 0.5);
            extract(c2, r, NULL, &before);
            int live0 = fa.live;
            fa.left = 0;
            nomem_ok = rs_roam_set_dem(c2, r, db) == RS_ERR_NOMEM;
            fa.left = 1000;
            leak_free = fa.live == live0;
            rs_roam_refine_error(c2, r, 0.5);
            extract(c2, r, NULL, &after);
            kept = same_mesh(&before, &after);
            mesh_free(&before); mesh_free(&after);
            rs_dem_free(c2, db);
        }
        rs_roam_free(c2, r);
        rs_dem_free(c2, da);
        rs_ctx_free(c2);
        leak_free = leak_free && fa.live == 0;
    }
    CHECK(nomem_ok);
    CHECK(kept);
    CHECK(leak_free);
    free(za); free(zb);
}

/* ---- an all-explicit reference ----------------------------------------- */
/* The mesher keeps its finest levels implicit, finds diamond partners from
 * tables and computes bounds from closed forms. This reference has none of
 * that: every triangle is a node, force-splits follow the links as in the
 * seed, and a bound is the maximum over the lattice points of the triangle,
 * found by brute force. In error mode both must give the same unique
 * coarsest conforming mesh. DEMs are quantised to quarters, so every plane
 * value is exact in double and no bound can differ by rounding. */
typedef struct ref_node { int ax, ay, bx, by, cx, cy; int32_t lc, base, left, right; } ref_node;

static double ref_err(const float *z, uint32_t W, const ref_node *t)
{
    int px = t->bx - t->ax, py = t->by - t->ay, qx = t->cx - t->ax, qy = t->cy - t->ay;
    double l2 = (double)(px * px + py * py), za = z[(size_t)t->ay * W + (size_t)t->ax];
    double db = z[(size_t)t->by * W + (size_t)t->bx] - za, dc = z[(size_t)t->cy * W + (size_t)t->cx] - za;
    int x0 = t->ax < t->bx ? t->ax : t->bx, x1 = t->ax > t->bx ? t->ax : t->bx;
    int y0 = t->ay < t->by ? t->ay : t->by, y1 = t->ay > t->by ? t->ay : t->by;
    x0 = t->cx < x0 ? t->cx : x0;
    x1 = t->cx > x1 ? t->cx : x1;
    y0 = t->cy < y0 ? t->cy : y0;
    y1 = t->cy > y1 ? t->cy : y1;
    double m = 0.0;
    for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) {
            int dx = x - t->ax, dy = y - t->ay;
            int s = dx * px + dy * py, u = dx * qx + dy * qy; /* along the legs, times l2 */
            if (s < 0 || u < 0 || s + u > (int)l2) continue;
            double d = fabs(z[(size_t)y * W + (size_t)x] - (za + s / l2 * db + u / l2 * dc));
            if (d > m) m = d;
        }
    return m;
}

/* A triangle's sample keys (apex, right, left) rotated to start at the
 * smallest, the orientation kept: the same triangle gives the same triple. */
static void canon_tri(const uint64_t k[3], uint64_t *out)
{
    int m = k[1] < k[0] ? (k[2] < k[1] ? 2 : 1) : (k[2] < k[0] ? 2 : 0);
    out[0] = k[m]; out[1] = k[(m + 1) % 3]; out[2] = k[(m + 2) % 3];
}

static void ref_relink(ref_node *n, int32_t nb, int32_t old, int32_t now)
{
    if (nb < 0) return;
    if (n[nb].base == old) n[nb].base = now;
    else if (n[nb].left == old) n[nb].left = now;
    else if (n[nb].right == old) n[nb].right = now;
}

static void ref_split(ref_node *n, size_t *count, int32_t t)
{
    if (n[t].lc >= 0) return;
    if (n[t].base >= 0 && n[n[t].base].base != t) ref_split(n, count, n[t].base);
    int32_t lc = (int32_t)(*count)++, rc = (int32_t)(*count)++;
    ref_node T = n[t];
    int mx = (T.bx + T.cx) / 2, my = (T.by + T.cy) / 2;
    ref_node a = { mx, my, T.ax, T.ay, T.bx, T.by, -1, T.left, rc, -1 };
    ref_node b = { mx, my, T.cx, T.cy, T.ax, T.ay, -1, T.right, -1, lc };
    n[lc] = a; n[rc] = b;
    n[t].lc = lc;
    ref_relink(n, T.left, t, lc);
    ref_relink(n, T.right, t, rc);
    if (T.base >= 0) {
        if (n[T.base].lc >= 0) {
            int32_t blc = n[T.base].lc, brc = blc + 1;
            n[blc].right = rc; n[brc].left = lc;
            n[lc].right = brc; n[rc].left = blc;
        } else ref_split(n, count, T.base);
    }
}

/* Leaves of the reference for max error E, as canonical triangles. */
static size_t ref_mesh(const float *z, uint32_t W, uint32_t H, uint32_t P, double E, uint64_t **out)
{
    uint32_t npx = (W - 1) / P, npy = (H - 1) / P;
    size_t cap = 8 * (size_t)W * H + 16, count = 0;
    ref_node *n = malloc(cap * sizeof *n);
    if (!n) return 0;
    for (uint32_t py = 0; py < npy; py++)
        for (uint32_t px = 0; px < npx; px++) {
            int32_t p = (int32_t)(py * npx + px);
            int x0 = (int)(px * P), y0 = (int)(py * P), s = (int)P;
            ref_node r0 = { x0, y0, x0 + s, y0, x0, y0 + s, -1, 2 * p + 1,
                            py > 0 ? 2 * (p - (int32_t)npx) + 1 : -1, px > 0 ? 2 * (p - 1) + 1 : -1 };
            ref_node r1 = { x0 + s, y0 + s, x0, y0 + s, x0 + s, y0, -1, 2 * p,
                            py + 1 < npy ? 2 * (p + (int32_t)npx) : -1, px + 1 < npx ? 2 * (p + 1) : -1 };
            n[count++] = r0; n[count++] = r1;
        }
    for (int changed = 1; changed;) {
        changed = 0;
        for (size_t i = 0; i < count; i++)
            if (n[i].lc < 0 && ref_err(z, W, &n[i]) > E) { ref_split(n, &count, (int32_t)i); changed = 1; }
    }
    uint64_t *t = malloc((count + 1) * sizeof *t * 3);
    size_t nt = 0;
    for (size_t i = 0; t && i < count; i++) {
        if (n[i].lc >= 0) continue;
        uint64_t k[3] = { (uint64_t)n[i].ay * W + (uint64_t)n[i].ax, (uint64_t)n[i].cy * W + (uint64_t)n[i].cx,
                          (uint64_t)n[i].by * W + (uint64_t)n[i].bx };
        canon_tri(k, t + 3 * nt++);
    }
    free(n);
    *out = t;
    return t ? nt : 0;
}

static int cmp_tri3(const void *a, const void *b)
{
    const uint64_t *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x[k] != y[k]) return x[k] < y[k] ? -1 : 1;
    return 0;
}

/* The mesher's triangles, canonical too. */
static size_t lib_tris(const mesh *m, uint32_t W, uint64_t **out)
{
    size_t nt = m->ni / 3;
    uint64_t *t = malloc((nt + 1) * 3 * sizeof *t);
    for (size_t i = 0; t && i < nt; i++) {
        uint64_t k[3];
        for (int c = 0; c < 3; c++) {
            const float *v = m->v + 5 * m->i[3 * i + (size_t)c];
            k[c] = (uint64_t)lround(v[1]) * W + (uint64_t)lround(v[0]);
        }
        canon_tri(k, t + 3 * i);
    }
    *out = t;
    return t ? nt : 0;
}

static void test_reference(rs_ctx *ctx)
{
    static const uint32_t cfg[][3] = { { 33, 33, 8 }, { 33, 17, 16 }, { 17, 17, 4 }, { 17, 33, 2 },
                                       { 65, 65, 64 }, { 65, 33, 16 }, { 9, 9, 1 } };
    static const double errs[] = { 0.3, 1.1, 3.7, 20.3 };
    static const int kinds[] = { DEM_SPIKE, DEM_CHECKER, DEM_RIDGE, DEM_FRACTAL, DEM_COUNT /* noise */ };
    int same = 1, cases = 0;
    for (size_t c = 0; c < sizeof cfg / sizeof cfg[0]; c++)
        for (size_t k = 0; k < sizeof kinds / sizeof kinds[0]; k++) {
            uint32_t W = cfg[c][0], H = cfg[c][1];
            float *z = gen(kinds[k] == DEM_COUNT ? DEM_CONST : kinds[k], W, H);
            if (!z) { same = 0; continue; }
            for (size_t i = 0; i < (size_t)W * H; i++) {
                /* white noise: every sample of every closed form can be the maximum */
                if (kinds[k] == DEM_COUNT) z[i] = (float)(rc_hash(i * 7919u + W) % 97u) * 0.5f;
                z[i] = roundf(z[i] * 4.0f) / 4.0f;
            }
            rs_dem *dem = NULL;
            rs_roam_options o;
            memset(&o, 0, sizeof o);
            o.patch_size = cfg[c][2];
            rs_roam *r = make(ctx, z, W, H, &o, &dem);
            for (size_t e = 0; r && e < sizeof errs / sizeof errs[0]; e++) {
                mesh m;
                uint64_t *a = NULL, *b = NULL;
                size_t na = 0, nb = ref_mesh(z, W, H, cfg[c][2], errs[e], &b);
                if (rs_roam_refine_error(ctx, r, errs[e]) == RS_OK && extract(ctx, r, NULL, &m) == RS_OK)
                    na = lib_tris(&m, W, &a);
                else memset(&m, 0, sizeof m);
                int ok = a && b && na == nb && na > 0;
                if (ok) {
                    qsort(a, na, 3 * sizeof *a, cmp_tri3);
                    qsort(b, nb, 3 * sizeof *b, cmp_tri3);
                    ok = memcmp(a, b, na * 3 * sizeof *a) == 0;
                }
                if (!ok && same)
                    fprintf(stderr, "    reference: %s %ux%u patch %u E %g: %zu vs %zu triangles\n",
                            kinds[k] == DEM_COUNT ? "noise" : dem_name[kinds[k]],
                            W, H, cfg[c][2], errs[e], na, nb);
                same = same && ok;
                cases++;
                free(a); free(b);
                mesh_free(&m);
            }
            if (!r) same = 0;
            rs_roam_free(ctx, r);
            rs_dem_free(ctx, dem);
            free(z);
        }
    CHECKF(same, "error mode equals an all-explicit reference ROAM with brute-force bounds (%d cases)", cases);
}

/* The roam fuzz target's setup and update sequence on one input
 * (tests/roam_fuzz_input.h, without the target's mesh checks): the largest
 * operation count of its updates, whether each was done, and the last
 * update with a triangle target's count and target. */
static void fuzz_updates(rs_ctx *ctx, const uint8_t *data, size_t size, uint32_t *max_ops, int *all_done,
                         uint32_t *tris, uint32_t *target)
{
    *max_ops = 0, *all_done = 0, *tris = *target = 0;
    rf_input in;
    float *z = rf_read(data, size, &in) ? rf_samples(&in) : NULL;
    rs_dem *d = NULL;
    rs_roam *r = z ? make_f(ctx, z, in.W, in.H, in.cs, 0, &in.o, &d) : NULL;
    if (!r) {
        free(z);
        return;
    }
    *all_done = 1;
    rf_first_mesh(ctx, r, &in);
    for (int k = 0; k < 6 && in.updates; k++) {
        rs_roam_view v;
        uint32_t budget;
        uint8_t opt;
        rf_update_view(&in, k, &v, &budget, &opt);
        rs_result ru = rs_roam_update(ctx, r, &v, budget);
        rs_roam_stats st;
        rs_roam_get_stats(r, &st);
        if (st.update_ops > *max_ops) *max_ops = st.update_ops;
        if (!budget && (ru != RS_OK || !st.update_done)) *all_done = 0;
        if (v.target_triangles) *tris = st.triangles, *target = v.target_triangles;
    }
    rs_roam_free(ctx, r);
    rs_dem_free(ctx, d);
    free(z);
}

/* Triangle targets on tiny meshes, found by the roam fuzzer
 * (tests/crashers/roam/target_*.bin): each update ran to the op limit of
 * its pool (over 520,000 split and merge operations, 0.4 s, update_done
 * 0). band: a target of 96 whose 1 % band holds 96 alone, the steps
 * going 95 <-> 97; cycle: a target of 100 whose trades cycled through
 * forced splits (99 -> 105 -> 103 -> 102 -> 100 -> ...). Now each update
 * is done within about TARGET_FINE_OPS operations past the target, at a
 * count within the band or beside it. */
static void test_update_target_cycles(rs_ctx *ctx)
{
    static const uint8_t band[] = { 0xef, 0xdc, 0x00, 0x00, 0xff, 0xd5, 0x5c, 0x14, 0xff, 0xff, 0x28 };
    static const uint8_t head[8] = { 0x28, 0xa4, 0xff, 0x01, 0x01, 0x00, 0x1d, 0x01 };
    static const uint8_t end[6] = { 0xa4, 0x1a, 0x1f, 0xff, 0x87, 0x1a };
    uint8_t cycle[134];
    memset(cycle, 0x60, sizeof cycle);
    memcpy(cycle, head, sizeof head);
    memcpy(cycle + sizeof cycle - sizeof end, end, sizeof end);
    cycle[0x4c] = 0x70;
    uint32_t ops, tris, target;
    int done;
    fuzz_updates(ctx, band, sizeof band, &ops, &done, &tris, &target);
    CHECKF(done && ops < 200 && target == 96 && (tris == 95 || tris == 97),
           "a target band narrower than one step: done %d, %u operations, %u triangles (target %u)", done, ops, tris,
           target);
    fuzz_updates(ctx, cycle, sizeof cycle, &ops, &done, &tris, &target);
    CHECKF(done && ops <= 2200 && target == 100 && tris >= 99 && tris <= 101,
           "trades cycling through forced splits: done %d, %u operations, %u triangles (target %u)", done, ops, tris,
           target);
}

int main(void)
{
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    for (int k = 0; k < DEM_COUNT; k++) {
        test_pool_sweep(ctx, k, 17, 17);
        test_pool_sweep(ctx, k, 13, 10);
    }
    test_pool_sweep(ctx, DEM_FRACTAL, 2, 2);
    test_pool_sweep(ctx, DEM_FRACTAL, 33, 5);
    for (int k = 0; k < DEM_COUNT; k++) {
        test_error_sweep(ctx, k, 65, 65, 1.0, 1.0);
        test_error_sweep(ctx, k, 50, 37, 2.5, 0.1);
    }
    test_scaling_and_determinism(ctx);
    test_budget(ctx);
    test_view(ctx);
    test_update(ctx, 0);
    test_update(ctx, 16);
    test_update(ctx, 256);
    test_update_turning(ctx, 0);
    test_update_turning(ctx, 16);
    test_update_shuttle(ctx, 0);
    test_update_shuttle(ctx, 16);
    test_update_strafe(ctx, 0);
    test_update_strafe(ctx, 16);
    test_update_target_cycles(ctx);
    test_patches(ctx);
    test_units(ctx, 257, 201, 0, 0, 8);    /* automatic 64-cell patches, the default units */
    test_units(ctx, 257, 201, 64, 16, 16);
    test_units(ctx, 257, 201, 64, 4, 4);   /* the smallest: one block */
    test_units(ctx, 200, 257, 32, 8, 8);
    test_units(ctx, 257, 201, 16, 64, 16); /* larger than the patch: the patch */
    test_units(ctx, 41, 37, 2, 0, 2);      /* blocks are the roots */
    test_units(ctx, 21, 17, 1, 0, 1);
    test_seams(ctx, 1);
    test_seams(ctx, 0);
    test_extract_options(ctx);
    test_errors(ctx);
    test_set_dem(ctx);
    test_reference(ctx);
    rs_ctx_free(ctx);
    return th_finish("test_roam");
}
