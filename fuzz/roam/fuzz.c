/* Fuzz target for the ROAM mesher. Input (tests/roam_fuzz_input.h): a
 * small DEM, the pool size, error threshold and mode from the last bytes,
 * and with bit 3 of the last byte six rs_roam_update calls (views,
 * budgets, tolerance or triangle target from the body's bytes). Checks
 * invariants after each mesh and traps on a violation (no NaN vertex,
 * indices in range, count == stats, the triangles tile the map, no
 * T-junction, the patches' triangles add up to the mesh's and the upload
 * units' are exactly its (unit_size from the top bits of the pool's high
 * byte); after an update at a tolerance, every vertex of a rebuild at that
 * view). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "roadsplat.h"
#include "../../tests/roam_check.h"
#include "../../tests/roam_fuzz_input.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define REQUIRE(c) do { if (!(c)) __builtin_trap(); } while (0)


/* Extract r's mesh (whole, per patch and per upload unit) and check it. */
static void check_mesh(rs_ctx *ctx, rs_roam *r, uint32_t W, uint32_t H, double cs, uint8_t opt)
{
    rs_roam_stats st;
    rs_roam_get_stats(r, &st);
    REQUIRE(st.pool_used <= st.pool_nodes);
    rs_roam_mesh_options mo = { 0, opt & 1, (opt & 2) ? 3.0 : 0.0, NULL };
    size_t mv, mi, nv, ni;
    rs_roam_mesh_bound(r, &mo, &mv, &mi);
    float *v = malloc((mv + 1) * 5 * sizeof *v), *n = malloc((mv + 1) * 3 * sizeof *n);
    uint32_t *idx = malloc((mi + 1) * sizeof *idx);
    if (v && n && idx) {
        REQUIRE(rs_roam_extract(ctx, r, &mo, v, n, mv, idx, mi, &nv, &ni) == RS_OK);
        REQUIRE(ni >= 3 * (size_t)st.triangles);
        for (size_t k = 0; k < nv * 5; k++) REQUIRE(isfinite(v[k]));
        for (size_t k = 0; k < ni; k++) REQUIRE(idx[k] < nv);
        double area = 0;
        for (size_t t = 0; t < 3 * (size_t)st.triangles; t += 3) {
            const float *a = v + 5 * idx[t], *b = v + 5 * idx[t + 1], *c = v + 5 * idx[t + 2];
            area += -((double)(b[0] - a[0]) * (c[1] - a[1]) - (double)(c[0] - a[0]) * (b[1] - a[1])) / 2;
        }
        double want = (W - 1) * (H - 1) * cs * cs;
        REQUIRE(fabs(area - want) <= 1e-6 * want);
        /* conforming: no vertex strictly inside a triangle edge (a crack) */
        unsigned char *isv = calloc((size_t)W * H, 1);
        if (isv) {
            for (size_t k = 0; k < nv; k++) {
                long gx = lround(v[5 * k] / cs), gy = lround(v[5 * k + 1] / cs);
                REQUIRE(gx >= 0 && gy >= 0 && gx < (long)W && gy < (long)H);
                isv[(size_t)gy * W + (size_t)gx] = 1;
            }
            for (size_t t = 0; t < 3 * (size_t)st.triangles; t++) {
                const float *a = v + 5 * idx[t], *b = v + 5 * idx[t % 3 == 2 ? t - 2 : t + 1];
                long ax = lround(a[0] / cs), ay = lround(a[1] / cs);
                long ex = lround(b[0] / cs) - ax, ey = lround(b[1] / cs) - ay;
                long g = labs(ex) > labs(ey) ? labs(ex) : labs(ey); /* bintree edges: axis or diagonal */
                for (long s = 1; s < g; s++) REQUIRE(!isv[(size_t)(ay + ey / g * s) * W + (size_t)(ax + ex / g * s)]);
            }
            free(isv);
        }
        /* the patches' triangles add up to the mesh's */
        size_t sum = 0;
        for (uint32_t p = 0; p < st.patches_x * st.patches_y; p++) {
            size_t pv, pi;
            REQUIRE(rs_roam_extract_patch(ctx, r, p, NULL, v, NULL, mv, idx, mi, &pv, &pi) == RS_OK);
            for (size_t k = 0; k < pi; k++) REQUIRE(idx[k] < pv);
            sum += pi / 3;
        }
        REQUIRE(sum == st.triangles);
        /* the upload units' triangles are exactly the mesh's */
        REQUIRE(rs_roam_extract(ctx, r, NULL, v, NULL, mv, idx, mi, &nv, &ni) == RS_OK);
        uint64_t *all = rc_tri_keys(v, idx, ni / 3, W, cs), *cat = malloc((ni / 3 + 1) * sizeof *cat);
        size_t nu = 0;
        for (uint32_t u = 0; all && cat && u < st.units; u++) {
            size_t uv, ui;
            REQUIRE(rs_roam_extract_unit(ctx, r, u, NULL, v, NULL, mv, idx, mi, &uv, &ui) == RS_OK);
            for (size_t k = 0; k < ui; k++) REQUIRE(idx[k] < uv);
            REQUIRE(nu + ui / 3 <= ni / 3);
            uint64_t *k = rc_tri_keys(v, idx, ui / 3, W, cs);
            if (k) memcpy(cat + nu, k, ui / 3 * sizeof *k);
            nu += ui / 3;
            free(k);
        }
        if (all && cat) {
            REQUIRE(nu == ni / 3);
            qsort(cat, nu, sizeof *cat, rc_cmp_u64);
            REQUIRE(memcmp(cat, all, nu * sizeof *cat) == 0);
        }
        REQUIRE(rs_roam_unit_generation(r, st.units) == 0);
        free(all); free(cat);
    }
    free(v); free(n); free(idx);
}

/* The samples that are vertices of r's mesh (W x H flags; NULL when
 * memory runs out). */
static unsigned char *vertex_set(rs_ctx *ctx, rs_roam *r, uint32_t W, uint32_t H, double cs)
{
    size_t mv, mi, nv, ni;
    rs_roam_mesh_bound(r, NULL, &mv, &mi);
    float *v = malloc((mv + 1) * 5 * sizeof *v);
    uint32_t *idx = malloc((mi + 1) * sizeof *idx);
    unsigned char *set = calloc((size_t)W * H, 1);
    if (v && idx && set) {
        REQUIRE(rs_roam_extract(ctx, r, NULL, v, NULL, mv, idx, mi, &nv, &ni) == RS_OK);
        for (size_t k = 0; k < nv; k++)
            set[(size_t)lround(v[5 * k + 1] / cs) * W + (size_t)lround(v[5 * k] / cs)] = 1;
    } else {
        free(set);
        set = NULL;
    }
    free(v); free(idx);
    return set;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rf_input in;
    if (!rf_read(data, size, &in)) return 0;
    const uint32_t W = in.W, H = in.H;
    const double cs = in.cs;
    float *z = rf_samples(&in);
    if (!z) return 0;
    rs_ctx *ctx = NULL;
    rs_dem *dem = NULL;
    rs_roam *r = NULL, *rb = NULL;
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) { free(z); return 0; }
    if (rs_dem_create(ctx, W, H, z, &dem) != RS_OK) goto out;
    rs_dem_frame fr = { cs, 0, 0, 0 };
    REQUIRE(rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    rs_roam_options o = in.o;
    if (rs_roam_create(ctx, dem, &o, &r) != RS_OK) goto out;
    rs_result rr = rf_first_mesh(ctx, r, &in);
    REQUIRE(rr == RS_OK || rr == RS_ERR_POOL_EXHAUSTED || rr == RS_ERR_LIMIT);
    check_mesh(ctx, r, W, H, cs, in.tail[2]);
    if (in.updates) {
        /* an update sequence from the current mesh */
        for (int k = 0; k < 6; k++) {
            rs_roam_view v;
            uint32_t budget;
            uint8_t opt;
            rf_update_view(&in, k, &v, &budget, &opt);
            rs_result ru = rs_roam_update(ctx, r, &v, budget);
            REQUIRE(ru == RS_OK || ru == RS_ERR_POOL_EXHAUSTED);
            check_mesh(ctx, r, W, H, cs, opt);
            /* a completed update at a tolerance leaves no leaf above it:
             * its mesh refines the rebuild's (the coarsest such mesh),
             * so every rebuild vertex is one of its vertices */
            if (ru == RS_OK && !budget && !v.target_triangles && (rb || rs_roam_create(ctx, dem, &o, &rb) == RS_OK)
                && rs_roam_frame(ctx, rb, &v) == RS_OK) {
                unsigned char *a = vertex_set(ctx, r, W, H, cs), *b = vertex_set(ctx, rb, W, H, cs);
                if (a && b)
                    for (size_t s = 0; s < (size_t)W * H; s++) REQUIRE(a[s] || !b[s]);
                free(a); free(b);
            }
        }
    }
out:
    rs_roam_free(ctx, r);
    rs_roam_free(ctx, rb);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    free(z);
    return 0;
}
