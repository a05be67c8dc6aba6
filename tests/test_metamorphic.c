/* Metamorphic tests: change the input in a way whose effect on the output is
 * known, and check the output changed exactly that way (docs/stability.md).
 *  - D4: rotating/mirroring DEM and roads rotates/mirrors the road weight;
 *  - reversing, duplicating points of, or splitting a road changes nothing;
 *  - scaling heights by k keeps the weight and scales ROAM errors by k;
 *  - scaling cell size and roads together keeps the weight image. */
#include "harness.h"
#include "roadsplat.h"
#include "roam_check.h"
#include "scene_splat.h"
#include "scenes.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;

/* --- weight images ------------------------------------------------------------ */

static size_t wdiff(const uint16_t *a, const uint16_t *b, size_t n, int *maxd)
{
    size_t c = 0;
    *maxd = 0;
    for (size_t i = 0; i < n; i++) {
        int d = abs((int)a[i] - (int)b[i]);
        if (d) c++;
        if (d > *maxd) *maxd = d;
    }
    return c;
}

/* --- D4 transforms ---------------------------------------------------------------
 * g & 4: mirror left-right first; g & 3: then that many 90-degree clockwise
 * turns. A point (x, y) in a frame of extent X by Y goes to (X - x, y) when
 * mirrored and to (Y - y, x) on a turn (the extents swap). */
static void xf_point(int g, double X, double Y, double *x, double *y)
{
    if (g & 4) *x = X - *x;
    for (int r = 0; r < (g & 3); r++) {
        double nx = Y - *y, ny = *x, t = X;
        *x = nx;
        *y = ny;
        X = Y;
        Y = t;
    }
}

static int xf_scene(const sc_scene *in, int g, sc_scene *out)
{
    uint32_t W = (g & 1) ? in->h : in->w, H = (g & 1) ? in->w : in->h;
    if (sc_scene_init(out, W, H, in->cell_size)) return -1;
    for (uint32_t i = 0; i < in->h; i++)
        for (uint32_t j = 0; j < in->w; j++) {
            double x = j, y = i;
            xf_point(g, in->w - 1, in->h - 1, &x, &y);
            out->z[(size_t)y * W + (size_t)x] = in->z[(size_t)i * in->w + j];
        }
    for (size_t k = 0; k < in->nroads; k++) {
        const sc_road *rd = &in->roads[k];
        double *p = malloc(rd->n * 2 * sizeof *p);
        if (!p) return -1;
        for (size_t q = 0; q < rd->n; q++) {
            p[2 * q] = rd->xy[2 * q];
            p[2 * q + 1] = rd->xy[2 * q + 1];
            xf_point(g, sc_extent_x(in), sc_extent_y(in), &p[2 * q], &p[2 * q + 1]);
        }
        int e = sc_add_road(out, rd->width, p, rd->n);
        free(p);
        if (e) return -1;
    }
    return 0;
}

/* The weight image `in` (w x h) transformed by g. */
static uint16_t *xf_image(const uint16_t *in, uint32_t w, uint32_t h, int g)
{
    uint32_t W = (g & 1) ? h : w;
    uint16_t *out = malloc((size_t)w * h * sizeof *out);
    if (!out) return NULL;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            double px = x, py = y;
            xf_point(g, w - 1, h - 1, &px, &py);
            out[(size_t)py * W + (size_t)px] = in[(size_t)y * w + x];
        }
    return out;
}

/* Random coordinates on a 2^-16 m lattice so that X - x and the turns are
 * exact in double: the transformed scene is exactly the turned scene. */
static double lattice(sc_rng *r, double lo, double hi)
{
    return floor(sc_rng_range(r, lo, hi) * 65536.0) / 65536.0;
}

/* W x H fractal DEM (cell size cs) with `nroads` random polylines of 2..5
 * points, some crossing, one leaving the map. */
static int random_scene(sc_scene *s, uint32_t W, uint32_t H, double cs, uint64_t seed, int nroads, int dyadic)
{
    if (sc_scene_init(s, W, H, cs)) return -1;
    sc_dem_fractal(s->z, W, H, seed, 0.5);
    sc_rng r;
    sc_rng_seed(&r, seed * 7919 + 1);
    double X = sc_extent_x(s), Y = sc_extent_y(s);
    for (int k = 0; k < nroads; k++) {
        double p[10];
        size_t n = 2 + (size_t)(sc_rng_u64(&r) % 4);
        for (size_t q = 0; q < n; q++) {
            double lo = k == 0 ? -0.3 : 0.05;
            p[2 * q] = dyadic ? lattice(&r, lo * X, 0.95 * X) : floor(sc_rng_range(&r, lo * X, 0.95 * X) * 1000) / 1000;
            p[2 * q + 1] = dyadic ? lattice(&r, lo * Y, 0.95 * Y) : floor(sc_rng_range(&r, lo * Y, 0.95 * Y) * 1000) / 1000;
        }
        double wd = floor(sc_rng_range(&r, 0.7, 6.0) * 64) / 64 * cs;
        if (sc_add_road(s, wd, p, n)) return -1;
    }
    return 0;
}

/* --- D4 ----------------------------------------------------------------------- */

static void test_d4(void)
{
    int worst = 0;
    size_t worst_px = 0;
    for (uint64_t seed = 1; seed <= 4; seed++) {
        sc_scene s;
        CHECK(random_scene(&s, 23 + (uint32_t)seed, 17, 1.0, seed, 5, 1) == 0);
        for (int mode = 0; mode < 2; mode++)
            for (int ti = 0; ti < 2; ti++) {
                rs_splat_options o;
                memset(&o, 0, sizeof o);
                o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
                o.grid.buffer = mode ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
                o.texels = ti ? 3 : 4;
                ss_image ref;
                CHECK(ss_splat(ctx, &s, &o, 0, &ref) == RS_OK);
                if (!ref.wt) continue;
                size_t n = (size_t)ref.w * ref.h;
                for (int g = 1; g < 8; g++) {
                    sc_scene t;
                    ss_image im;
                    CHECK(xf_scene(&s, g, &t) == 0);
                    CHECK(ss_splat(ctx, &t, &o, 0, &im) == RS_OK);
                    uint16_t *want = xf_image(ref.wt, ref.w, ref.h, g);
                    if (im.wt && want) {
                        int md;
                        size_t c = wdiff(want, im.wt, n, &md);
                        CHECKF(c == 0, "seed %llu %s T=%u g=%d: %zu pixels differ, max %d/65535",
                               (unsigned long long)seed, mode ? "dilate" : "distance", o.texels, g, c, md);
                        if (md > worst) worst = md;
                        worst_px += c;
                    }
                    free(want);
                    ss_image_free(&im);
                    sc_scene_free(&t);
                }
                ss_image_free(&ref);
            }
        sc_scene_free(&s);
    }
    printf("d4: %zu differing pixels, max difference %d/65535\n", worst_px, worst);
}

/* --- road edits that change nothing ----------------------------------------------- */

/* EDIT_SPLIT splits a road at a vertex it has; EDIT_SPLIT_NEW at the
 * midpoint of its first segment, a point the road did not have. */
enum { EDIT_REVERSE, EDIT_DUPLICATE, EDIT_SPLIT, EDIT_SPLIT_NEW, EDIT_COUNT };
static const char *edit_name[EDIT_COUNT] = { "reverse", "duplicate points", "split at a vertex",
                                             "split at a new point" };

static int edit_scene(const sc_scene *in, int edit, sc_scene *out)
{
    if (sc_scene_init(out, in->w, in->h, in->cell_size)) return -1;
    memcpy(out->z, in->z, (size_t)in->w * in->h * sizeof *in->z);
    for (size_t k = 0; k < in->nroads; k++) {
        const sc_road *rd = &in->roads[k];
        double *p = malloc(rd->n * 4 * sizeof *p);
        if (!p) return -1;
        int e = 0;
        size_t n = rd->n;
        if (edit == EDIT_REVERSE) {
            for (size_t q = 0; q < n; q++) {
                p[2 * q] = rd->xy[2 * (n - 1 - q)];
                p[2 * q + 1] = rd->xy[2 * (n - 1 - q) + 1];
            }
            e = sc_add_road(out, rd->width, p, n);
        } else if (edit == EDIT_DUPLICATE) {
            for (size_t q = 0; q < n; q++) /* every point twice */
                for (int c = 0; c < 2; c++) {
                    p[4 * q + 2 * c] = rd->xy[2 * q];
                    p[4 * q + 2 * c + 1] = rd->xy[2 * q + 1];
                }
            e = sc_add_road(out, rd->width, p, 2 * n);
        } else if (edit == EDIT_SPLIT) {
            size_t mid = n / 2; /* two points: nothing to split at, left as is */
            e = sc_add_road(out, rd->width, rd->xy, n >= 3 ? mid + 1 : n);
            if (!e && n >= 3) e = sc_add_road(out, rd->width, rd->xy + 2 * mid, n - mid);
        } else {
            /* dyadic coordinates: the midpoint is exact */
            double a[4] = { rd->xy[0], rd->xy[1], 0.5 * (rd->xy[0] + rd->xy[2]), 0.5 * (rd->xy[1] + rd->xy[3]) };
            e = sc_add_road(out, rd->width, a, 2);
            memcpy(p, a + 2, 2 * sizeof *p);
            memcpy(p + 2, rd->xy + 2, 2 * (n - 1) * sizeof *p);
            if (!e) e = sc_add_road(out, rd->width, p, n);
        }
        free(p);
        if (e) return -1;
    }
    return 0;
}

/* Total road length of a scene, metres. */
static double scene_length(const sc_scene *s)
{
    double L = 0;
    for (size_t k = 0; k < s->nroads; k++)
        for (size_t q = 0; q + 1 < s->roads[k].n; q++)
            L += hypot(s->roads[k].xy[2 * q + 2] - s->roads[k].xy[2 * q],
                       s->roads[k].xy[2 * q + 3] - s->roads[k].xy[2 * q + 1]);
    return L;
}

static void test_edits(void)
{
    for (int edit = 0; edit < EDIT_COUNT; edit++) {
        size_t total = 0;
        int worst = 0;
        double worst_strip = 0;
        for (uint64_t seed = 11; seed <= 16; seed++) {
            sc_scene s, t;
            CHECK(random_scene(&s, 29, 21, 1.0, seed, 6, 1) == 0);
            CHECK(edit_scene(&s, edit, &t) == 0);
            for (int mode = 0; mode < 2; mode++) {
                rs_splat_options o;
                memset(&o, 0, sizeof o);
                o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
                o.grid.buffer = mode ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
                o.texels = 4;
                ss_image a, b;
                CHECK(ss_splat(ctx, &s, &o, 0, &a) == RS_OK);
                CHECK(ss_splat(ctx, &t, &o, 0, &b) == RS_OK);
                if (!a.wt || !b.wt) { ss_image_free(&a); ss_image_free(&b); continue; }
                int md;
                size_t n = (size_t)a.w * a.h, c = wdiff(a.wt, b.wt, n, &md);
                if (edit == EDIT_SPLIT_NEW && mode == 1) {
                    /* Dilate mode rasterises the centreline between the cells
                     * holding the points (seed 000), so a new point can move
                     * the raster by one road cell near it: the changed area
                     * is a thin strip along the road (docs/stability.md). */
                    double area = 0, px = s.cell_size / o.texels;
                    for (size_t i = 0; i < n; i++) area += fabs((double)a.wt[i] - b.wt[i]) / 65535.0 * px * px;
                    double strip = area / scene_length(&s); /* metres */
                    if (strip > worst_strip) worst_strip = strip;
                    CHECKF(strip <= 0.02 * s.cell_size, "split at a new point, seed %llu: changed strip %g m wide",
                           (unsigned long long)seed, strip);
                } else {
                    CHECKF(c == 0 && memcmp(a.rgba, b.rgba, n * 4) == 0,
                           "%s, seed %llu, %s: %zu weights differ, max %d/65535", edit_name[edit],
                           (unsigned long long)seed, mode ? "dilate" : "distance", c, md);
                }
                total += c;
                if (md > worst) worst = md;
                ss_image_free(&a);
                ss_image_free(&b);
            }
            sc_scene_free(&s);
            sc_scene_free(&t);
        }
        printf("%s: %zu differing pixels, max difference %d/65535", edit_name[edit], total, worst);
        if (edit == EDIT_SPLIT_NEW) printf(" (dilate mode only; widest changed strip %.4g m)", worst_strip);
        printf("\n");
    }
}

/* --- heights scaled: weight unchanged ---------------------------------------------- */

static void test_height_scale_splat(void)
{
    static const double ks[3] = { 2, 0.5, 1000 };
    sc_scene s;
    CHECK(random_scene(&s, 31, 27, 1.0, 21, 6, 1) == 0);
    for (int mode = 0; mode < 2; mode++) {
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
        o.grid.buffer = mode ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
        ss_image ref;
        CHECK(ss_splat(ctx, &s, &o, 0, &ref) == RS_OK);
        for (int i = 0; i < 3 && ref.wt; i++) {
            sc_scene t;
            CHECK(sc_scene_init(&t, s.w, s.h, s.cell_size) == 0);
            for (size_t q = 0; q < (size_t)s.w * s.h; q++) t.z[q] = (float)(s.z[q] * ks[i]);
            for (size_t q = 0; q < s.nroads; q++) CHECK(sc_add_road(&t, s.roads[q].width, s.roads[q].xy, s.roads[q].n) == 0);
            ss_image a, b;
            CHECK(ss_splat(ctx, &t, &o, 0, &a) == RS_OK); /* samples times k */
            CHECK(ss_splat_z(ctx, &s, &o, ks[i], 0, &b) == RS_OK); /* z-scale k */
            if (a.wt && b.wt) {
                size_t n = (size_t)a.w * a.h;
                CHECKF(memcmp(a.wt, ref.wt, n * 2) == 0, "heights x%g changed the weight", ks[i]);
                CHECKF(memcmp(b.wt, ref.wt, n * 2) == 0, "z-scale %g changed the weight", ks[i]);
            }
            ss_image_free(&a);
            ss_image_free(&b);
            sc_scene_free(&t);
        }
        ss_image_free(&ref);
    }
    sc_scene_free(&s);
}

/* --- cell size and roads scaled together ------------------------------------------- */

static void test_cell_scale(void)
{
    static const double scales[2] = { 1e-3, 1e4 };
    for (int dy = 0; dy < 2; dy++)
        for (uint64_t seed = 31; seed <= 33; seed++) {
            sc_scene s;
            CHECK(random_scene(&s, 27, 23, 1.0, seed, 6, dy) == 0);
            for (int mode = 0; mode < 2; mode++) {
                rs_splat_options o;
                memset(&o, 0, sizeof o);
                o.coverage.edges = RS_EDGES_ALPHAMAP; /* this file tests the alpha-map table */
                o.grid.buffer = mode ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
                o.texels = 4;
                ss_image ref;
                CHECK(ss_splat(ctx, &s, &o, 0, &ref) == RS_OK);
                for (int i = 0; i < 2 && ref.wt; i++) {
                    sc_scene t;
                    CHECK(sc_scene_init(&t, s.w, s.h, scales[i]) == 0);
                    memcpy(t.z, s.z, (size_t)s.w * s.h * sizeof *s.z);
                    for (size_t q = 0; q < s.nroads; q++) {
                        double p[10];
                        for (size_t c = 0; c < 2 * s.roads[q].n; c++) p[c] = s.roads[q].xy[c] * scales[i];
                        CHECK(sc_add_road(&t, s.roads[q].width * scales[i], p, s.roads[q].n) == 0);
                    }
                    ss_image im;
                    CHECK(ss_splat(ctx, &t, &o, 0, &im) == RS_OK);
                    if (im.wt) {
                        int md;
                        size_t c = wdiff(im.wt, ref.wt, (size_t)im.w * im.h, &md);
                        CHECKF(c == 0, "cell size %g (%s coordinates, seed %llu, %s): %zu pixels differ, max %d/65535",
                               scales[i], dy ? "dyadic" : "mm", (unsigned long long)seed, mode ? "dilate" : "distance",
                               c, md);
                    }
                    ss_image_free(&im);
                    sc_scene_free(&t);
                }
                ss_image_free(&ref);
            }
            sc_scene_free(&s);
        }
}

/* --- ROAM: heights scaled by k ------------------------------------------------------ */

typedef struct mesh {
    float *v;
    uint32_t *i;
    size_t nv, ni;
} mesh;

static rs_result mesh_at(const float *z, uint32_t W, uint32_t H, double zs, double err, mesh *m)
{
    memset(m, 0, sizeof *m);
    rs_dem *dem = NULL;
    rs_roam *roam = NULL;
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    rs_dem_frame fr = { 0, zs, 0, 0 };
    rs_result r = rs_dem_create(ctx, W, H, z, &dem);
    if (!r) r = rs_dem_set_frame(ctx, dem, &fr);
    if (!r) r = rs_roam_create(ctx, dem, &o, &roam);
    if (!r) r = rs_roam_refine_error(ctx, roam, err);
    if (!r) {
        size_t mv, mi;
        rs_roam_mesh_bound(roam, NULL, &mv, &mi);
        m->v = malloc((mv + 1) * 5 * sizeof *m->v);
        m->i = malloc((mi + 1) * sizeof *m->i);
        r = m->v && m->i ? rs_roam_extract(ctx, roam, NULL, m->v, NULL, mv, m->i, mi, &m->nv, &m->ni) : RS_ERR_NOMEM;
    }
    rs_roam_free(ctx, roam);
    rs_dem_free(ctx, dem);
    return r;
}

/* Max error of the mesh against the DEM (z * zs), by the independent checker. */
static double mesh_error(const mesh *m, const float *z, uint32_t W, uint32_t H, double zs, int *valid)
{
    int32_t *gx = malloc((m->nv + 1) * sizeof *gx), *gy = malloc((m->nv + 1) * sizeof *gy);
    double *vz = malloc((m->nv + 1) * sizeof *vz);
    float *zf = malloc((size_t)W * H * sizeof *zf);
    rc_result res;
    memset(&res, 0, sizeof res);
    *valid = 0;
    if (gx && gy && vz && zf) {
        for (size_t k = 0; k < m->nv; k++) {
            gx[k] = (int32_t)lround(m->v[5 * k]);
            gy[k] = (int32_t)lround(m->v[5 * k + 1]);
            vz[k] = m->v[5 * k + 2];
        }
        for (size_t k = 0; k < (size_t)W * H; k++) zf[k] = (float)((double)z[k] * zs);
        *valid = rc_check(W, H, zf, 1.0, gx, gy, vz, m->nv, m->i, m->ni / 3, &res) && rc_all_ok(&res);
    }
    free(gx); free(gy); free(vz); free(zf);
    return res.max_err;
}

static void test_height_scale_roam(void)
{
    static const double ks[3] = { 2, 0.5, 1000 };
    const uint32_t W = 65, H = 49;
    float *z = malloc((size_t)W * H * sizeof *z), *zk = malloc((size_t)W * H * sizeof *zk);
    if (!z || !zk) { CHECK(0); free(z); free(zk); return; }
    rc_dem_fractal(z, W, H, 5, 32.0, 80.0, 0.55);
    const double E[3] = { 0.5, 3.0, 12.0 };
    for (int e = 0; e < 3; e++) {
        mesh base;
        int valid;
        CHECK(mesh_at(z, W, H, 1.0, E[e], &base) == RS_OK);
        double err1 = mesh_error(&base, z, W, H, 1.0, &valid);
        CHECK(valid && err1 <= E[e]);
        for (int i = 0; i < 3; i++) {
            double k = ks[i];
            int pow2 = k == 2 || k == 0.5;
            for (int via = 0; via < 2; via++) {
                /* via 0: z-scale k; via 1: samples times k (exact for powers of two only) */
                if (via == 1 && !pow2) continue;
                for (size_t q = 0; q < (size_t)W * H; q++) zk[q] = via ? (float)(z[q] * k) : z[q];
                mesh m;
                CHECK(mesh_at(zk, W, H, via ? 1.0 : k, k * E[e], &m) == RS_OK);
                int same = m.ni == base.ni && m.nv == base.nv && memcmp(m.i, base.i, m.ni * sizeof *m.i) == 0;
                double zdev = 0;
                for (size_t v = 0; same && v < m.nv; v++) {
                    same = m.v[5 * v] == base.v[5 * v] && m.v[5 * v + 1] == base.v[5 * v + 1];
                    double d = fabs(m.v[5 * v + 2] - k * base.v[5 * v + 2]);
                    if (d > zdev) zdev = d;
                }
                CHECKF(same, "heights x%g (%s), error %g: a different mesh (%zu vs %zu triangles)", k,
                       via ? "samples" : "z-scale", k * E[e], m.ni / 3, base.ni / 3);
                double errk = mesh_error(&m, zk, W, H, via ? 1.0 : k, &valid);
                CHECK(valid);
                if (pow2) {
                    CHECKF(zdev == 0 && errk == k * err1, "x%g: z off by %g, error %.17g vs %.17g", k, zdev, errk,
                           k * err1);
                } else {
                    /* float heights: z*k rounds once in float (2^-24 relative) */
                    CHECKF(zdev <= 1e-6 * k * 65536 && fabs(errk - k * err1) <= 1e-6 * k * (err1 + 1),
                           "x%g: z off by %g, error %.17g vs %.17g", k, zdev, errk, k * err1);
                }
                CHECKF(errk <= k * E[e] * (1 + 1e-6), "x%g: error %g over the bound %g", k, errk, k * E[e]);
                free(m.v);
                free(m.i);
            }
        }
        free(base.v);
        free(base.i);
    }
    free(z);
    free(zk);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_d4();
    test_edits();
    test_height_scale_splat();
    test_cell_scale();
    test_height_scale_roam();
    rs_ctx_free(ctx);
    return th_finish("test_metamorphic");
}
