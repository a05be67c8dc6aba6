/* Progress and cancel (issue 30 target 4). The road grid build of a
 * styled scene reports through the options' progress callback, done never
 * goes back and ends at total, a callback that asks to stop at its k-th
 * call makes the build return RS_ERR_CANCELLED ("cancelled", no grid,
 * nothing leaked: the sanitizer build checks that) at every stage, and a
 * callback changes nothing in the output. Then every other long call with
 * the context's callback (rs_ctx_set_progress): the splat window (several
 * pieces a band), the normal map, the splatter, rs_splat, the network,
 * the GPU scene, the virtual texture's creation and its tiles, and ROAM's
 * creation, refinements, frames and updates: the same rules, stopped at
 * each call point in turn (every few for the calls that build grids),
 * each leaving its objects usable (a ROAM mesh cancelled half way is
 * checked crack-free, and the call run again gives the same output). */
#include "roadsplat.h"
#include "atlas.h"
#include "internal.h"
#include "roam_check.h"
#include "scenes.h"
#include "harness.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct watch {
    uint64_t calls, last_done, last_total, stop_at;
    int went_back, over;
} watch;

static int on_progress(void *user, uint64_t done, uint64_t total)
{
    watch *w = user;
    w->calls++;
    if (w->calls > 1 && done < w->last_done) w->went_back = 1;
    if (done > total) w->over = 1;
    w->last_done = done;
    w->last_total = total;
    return w->stop_at && w->calls >= w->stop_at;
}

static uint64_t hash_rgba(const uint8_t *p, size_t n)
{
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

/* The grid of `roads` with `w` as its callback (NULL: none), splatted
 * whole; *hash: the image's hash. */
static rs_result build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, watch *w, uint64_t *hash)
{
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 2;
    o.progress = w ? on_progress : NULL;
    o.progress_user = w;
    rs_road_grid *g = NULL;
    rs_result r = rs_road_grid_build(ctx, dem, roads, &o, &g);
    if (r) {
        CHECK(g == NULL);
        return r;
    }
    o.progress = NULL;
    rs_splatter *s = NULL;
    if (hash && !rs_splatter_create(ctx, dem, NULL, g, &o, &s)) {
        uint32_t W, H;
        rs_splatter_size(s, &W, &H);
        uint8_t *px = malloc((size_t)W * H * 4);
        if (px && !rs_splat_window(ctx, s, 0, 0, W, H, px, (size_t)W * 4, NULL, 0, NULL))
            *hash = hash_rgba(px, (size_t)W * H * 4);
        free(px);
        rs_splatter_free(ctx, s);
    }
    rs_road_grid_free(ctx, g);
    return r;
}

/* ---- every long call with the context's callback ------------------------------ */

typedef struct fixture {
    rs_dem *dem;          /* the styled city's DEM */
    rs_roads *roads;
    rs_splatter *sp;      /* a 10-texel splatter on a small part: bands of two pieces */
    rs_dem *small;
    rs_vt *vt;
    rs_vt_workspace *vws;
    uint8_t *px;
    size_t px_bytes;
    rs_dem *fractal;      /* ROAM */
    const float *fz;
    uint32_t fw;
    rs_roam *roam;
    char *roads_text;     /* the city's roads as a road file */
    size_t roads_len;
    char *pgm[2];         /* a 600 x 600 DEM as P2 and as 16-bit P5 */
    size_t pgm_len[2];
} fixture;

enum {
    K_WINDOW, K_NORMALS, K_SPLATTER, K_SPLAT, K_NETWORK, K_GPU, K_VT_CREATE, K_VT_TILE, K_PARSE_ROADS,
    K_PARSE_P2, K_PARSE_P5, K_ATLAS, K_ROAM_CREATE,
    K_ROAM_ERROR, K_ROAM_COUNT, K_ROAM_FRAME, K_ROAM_UPDATE, K_ROAM_EXTRACT, K_COUNT
};
static const char *const kname[K_COUNT] = { "rs_splat_window", "rs_normal_window", "rs_splatter_create",
                                            "rs_splat", "rs_network_build", "rs_gpu_scene_create",
                                            "rs_vt_create", "rs_vt_make_tile", "rs_roads_parse",
                                            "rs_dem_parse_pgm (P2)", "rs_dem_parse_pgm (P5)", "rs_atlas_create",
                                            "rs_roam_create",
                                            "rs_roam_refine_error", "rs_roam_refine_count", "rs_roam_frame",
                                            "rs_roam_update", "rs_roam_extract" };

static int roam_call(int k) { return k >= K_ROAM_CREATE; }

static rs_roam_view roam_view(void)
{
    rs_roam_view v;
    memset(&v, 0, sizeof v);
    v.eye[0] = 20; v.eye[1] = 30; v.eye[2] = 150;
    v.dir[0] = 1; v.dir[1] = 0.7; v.dir[2] = -0.5;
    v.pixel_error = 0.7;
    return v;
}

/* The current ROAM mesh: its hash, and whether the independent checker
 * finds it crack-free and covering the map (*ok). */
static uint64_t roam_mesh(rs_ctx *ctx, const fixture *f, int *ok)
{
    size_t mv, mi, nv = 0, ni = 0;
    rs_roam_mesh_bound(f->roam, NULL, &mv, &mi);
    float *v = malloc(mv * 5 * sizeof *v);
    uint32_t *ix = malloc(mi * sizeof *ix);
    int32_t *gx = malloc(mv * sizeof *gx), *gy = malloc(mv * sizeof *gy);
    double *vz = malloc(mv * sizeof *vz);
    uint64_t h = 0;
    *ok = 0;
    /* on a context of its own: the extraction reports to its context's
     * callback, and the call under test is the one to stop */
    rs_ctx *quiet = NULL;
    (void)ctx;
    if (rs_ctx_create(NULL, NULL, &quiet) == RS_OK && v && ix && gx && gy && vz &&
        rs_roam_extract(quiet, f->roam, NULL, v, NULL, mv, ix, mi, &nv, &ni) == RS_OK) {
        h = hash_rgba((const uint8_t *)v, nv * 5 * sizeof *v) ^ hash_rgba((const uint8_t *)ix, ni * sizeof *ix);
        for (size_t k = 0; k < nv; k++) {
            gx[k] = (int32_t)v[5 * k];
            gy[k] = (int32_t)v[5 * k + 1];
            vz[k] = v[5 * k + 2];
        }
        rc_result res;
        *ok = rc_check(f->fw, f->fw, f->fz, 1.0, gx, gy, vz, nv, ix, ni / 3, &res) && res.ok_grid &&
              res.ok_winding && res.ok_area && res.ok_edges && res.ok_tjunction && res.ok_coverage;
    }
    free(v); free(ix); free(gx); free(gy); free(vz);
    rs_ctx_free(quiet);
    return h;
}

/* What the call needs, outside the measured part. */
static int prepare(rs_ctx *ctx, fixture *f, int k)
{
    if (k == K_ROAM_CREATE || !roam_call(k)) return 0;
    rs_roam_free(ctx, f->roam); /* a fresh landscape: a frame's target starts from the last tolerance */
    f->roam = NULL;
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    if (rs_roam_create(ctx, f->fractal, &o, &f->roam) != RS_OK) return 1;
    rs_roam_view v = roam_view();
    /* an extraction of a mesh of 2 10^5 triangles (several polls a pass) */
    if (k == K_ROAM_EXTRACT) return rs_roam_refine_count(ctx, f->roam, 200000) != RS_OK;
    /* an update goes on from the last one's mesh: measure the second */
    return k == K_ROAM_UPDATE && rs_roam_update(ctx, f->roam, &v, 0) != RS_OK;
}

/* Run call k; *hash: its output (0: none). Whatever it made is freed. */
static rs_result run_call(rs_ctx *ctx, fixture *f, int k, uint64_t *hash)
{
    rs_result r = RS_OK;
    uint32_t W, H;
    rs_splatter_size(f->sp, &W, &H);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 2;
    *hash = 0;
    memset(f->px, 0, f->px_bytes);
    switch (k) {
    case K_WINDOW:
        r = rs_splat_window(ctx, f->sp, 0, 0, W, H, f->px, (size_t)W * 4, NULL, 0, NULL);
        if (!r) *hash = hash_rgba(f->px, (size_t)W * H * 4);
        break;
    case K_NORMALS:
        r = rs_normal_window(ctx, f->sp, 0, 0, W, H, f->px, (size_t)W * 3, NULL);
        if (!r) *hash = hash_rgba(f->px, (size_t)W * H * 3);
        break;
    case K_SPLATTER: {
        rs_splatter *s = NULL;
        r = rs_splatter_create(ctx, f->dem, f->roads, NULL, &o, &s);
        if (!r) { /* (its image would be another call's progress) */
            rs_road_grid_stats st;
            rs_road_grid_get_stats(rs_splatter_grid(s), &st);
            *hash = hash_rgba((const uint8_t *)&st, sizeof st);
        }
        rs_splatter_free(ctx, s);
        break;
    }
    case K_SPLAT: {
        o.texels = 10;
        r = rs_splat(ctx, f->small, rs_splatter_grid(f->sp), &o, f->px, f->px_bytes, NULL, 0);
        if (!r) *hash = hash_rgba(f->px, (size_t)W * H * 4);
        break;
    }
    case K_NETWORK: {
        rs_network *n = NULL;
        r = rs_network_build(ctx, f->roads, NULL, &n);
        if (!r) *hash = rs_network_node_count(n) * 1000003u + rs_network_stroke_count(n);
        rs_network_free(ctx, n);
        break;
    }
    case K_GPU: {
        rs_gpu_scene *g = NULL;
        r = rs_gpu_scene_create(ctx, f->dem, f->roads, &o, NULL, &g);
        if (!r) {
            size_t ns = 0, nm = 0;
            const void *seg = rs_gpu_scene_array(g, RS_GPU_ARRAY_SEG, &ns);
            const void *mark = rs_gpu_scene_array(g, RS_GPU_ARRAY_MARK, &nm);
            *hash = hash_rgba((const uint8_t *)seg, ns * sizeof(float)) ^
                    hash_rgba((const uint8_t *)mark, nm * sizeof(float));
        }
        rs_gpu_scene_free(ctx, g);
        break;
    }
    case K_VT_CREATE:
    case K_VT_TILE: {
        rs_vt_options vo;
        memset(&vo, 0, sizeof vo);
        vo.roads = f->roads;
        vo.tile_size = 64;
        rs_vt *vt = f->vt;
        if (k == K_VT_CREATE) r = rs_vt_create(ctx, f->sp, &vo, &vt);
        rs_vt_info in;
        if (!r) rs_vt_get_info(vt, &in);
        /* the coarsest level (2 at 2 texels): averaged from the 1-texel image */
        if (!r && k == K_VT_TILE)
            r = rs_vt_make_tile(ctx, vt, f->vws, in.levels - 1, 0, 0, f->px, (size_t)in.tile_side * 4);
        if (!r) *hash = k == K_VT_TILE ? hash_rgba(f->px, (size_t)in.tile_side * in.tile_side * 4) : in.levels;
        if (k == K_VT_CREATE) rs_vt_free(ctx, vt);
        break;
    }
    case K_PARSE_ROADS: {
        rs_roads *R = NULL;
        r = rs_roads_parse(ctx, f->roads_text, f->roads_len, &R);
        if (!r) {
            *hash = rs_roads_count(R);
            for (size_t i = 0; i < rs_roads_count(R); i++) {
                const double *xy = NULL;
                size_t np = 0;
                rs_roads_get(R, i, NULL, NULL, &xy, &np);
                *hash ^= hash_rgba((const uint8_t *)xy, np * 2 * sizeof *xy) + i;
            }
        }
        rs_roads_free(ctx, R);
        break;
    }
    case K_PARSE_P2:
    case K_PARSE_P5: {
        rs_dem *d = NULL;
        int b = k == K_PARSE_P5;
        r = rs_dem_parse_pgm(ctx, f->pgm[b], f->pgm_len[b], &d);
        if (!r)
            *hash = hash_rgba((const uint8_t *)rs_dem_samples(d),
                              (size_t)rs_dem_width(d) * rs_dem_height(d) * sizeof(float));
        rs_dem_free(ctx, d);
        break;
    }
    case K_ATLAS: {
        /* one 2048 x 2048 sprite: 2048 rows of level 0, then its mip levels */
        const uint32_t side = 2048;
        uint8_t *px = malloc((size_t)side * side * 4);
        if (!px) return RS_ERR_NOMEM;
        for (size_t i = 0; i < (size_t)side * side * 4; i++) px[i] = (uint8_t)(i * 2654435761u >> 24);
        rs_image im = { side, side, px };
        const char *index = "big 0 0 2048 2048 2 2\n";
        rs_atlas *a = NULL;
        r = rs_atlas_create(ctx, &im, index, strlen(index), &a);
        for (uint32_t l = 0; !r && l < a->t[0].nlev; l++) /* every mip level's texels */
            *hash ^= hash_rgba((const uint8_t *)a->t[0].lev[l].px,
                               (size_t)a->t[0].lev[l].w * a->t[0].lev[l].h * 4 * sizeof(float)) + l;
        rs_atlas_free(ctx, a);
        free(px);
        break;
    }
    case K_ROAM_CREATE: {
        rs_roam *L = NULL;
        r = rs_roam_create(ctx, f->fractal, NULL, &L);
        rs_roam_stats st;
        if (!r) rs_roam_get_stats(L, &st);
        if (!r) *hash = st.base_nodes;
        rs_roam_free(ctx, L);
        break;
    }
    case K_ROAM_ERROR: r = rs_roam_refine_error(ctx, f->roam, 0.02); break;
    case K_ROAM_COUNT: r = rs_roam_refine_count(ctx, f->roam, 30000); break;
    case K_ROAM_FRAME: {
        rs_roam_view v = roam_view();
        v.target_triangles = 20000;
        r = rs_roam_frame(ctx, f->roam, &v);
        break;
    }
    case K_ROAM_UPDATE: {
        rs_roam_view v = roam_view(); /* (prepare made the first update's mesh) */
        v.eye[0] += 60;
        v.dir[1] = -0.2;
        v.pixel_error = 0.4;
        r = rs_roam_update(ctx, f->roam, &v, 0);
        break;
    }
    }
    if (k == K_ROAM_EXTRACT) {
        size_t mv, mi, nv = 0, ni = 0;
        rs_roam_mesh_options mo;
        memset(&mo, 0, sizeof mo);
        mo.normals = 1;
        rs_roam_mesh_bound(f->roam, &mo, &mv, &mi);
        float *v = malloc(mv * 5 * sizeof *v), *nr = malloc(mv * 3 * sizeof *nr);
        uint32_t *ix = malloc(mi * sizeof *ix);
        r = v && nr && ix ? rs_roam_extract(ctx, f->roam, &mo, v, nr, mv, ix, mi, &nv, &ni) : RS_ERR_NOMEM;
        if (!r)
            *hash = hash_rgba((const uint8_t *)v, nv * 5 * sizeof *v) ^ hash_rgba((const uint8_t *)nr, nv * 3 * sizeof *nr) ^
                    hash_rgba((const uint8_t *)ix, ni * sizeof *ix);
        free(v);
        free(nr);
        free(ix);
    }
    if (!r && roam_call(k) && k != K_ROAM_CREATE && k != K_ROAM_EXTRACT) {
        int ok;
        *hash = roam_mesh(ctx, f, &ok);
        CHECKF(ok, "%s: the mesh fails the checker", kname[k]);
    }
    return r;
}

static void test_call(rs_ctx *ctx, fixture *f, int k)
{
    watch w;
    uint64_t h0 = 0, h1 = 1;
    rs_ctx_set_progress(ctx, NULL, NULL);
    CHECK(prepare(ctx, f, k) == 0);
    CHECKF(run_call(ctx, f, k, &h0) == RS_OK, "%s: %s", kname[k], rs_ctx_message(ctx));
    memset(&w, 0, sizeof w);
    CHECK(prepare(ctx, f, k) == 0);
    rs_ctx_set_progress(ctx, on_progress, &w);
    CHECKF(run_call(ctx, f, k, &h1) == RS_OK, "%s: %s", kname[k], rs_ctx_message(ctx));
    CHECKF(h0 == h1, "%s: a progress callback changed the output", kname[k]);
    CHECKF(w.calls >= 2, "%s: %llu progress calls", kname[k], (unsigned long long)w.calls);
    CHECKF(!w.went_back && !w.over && w.last_total > 0 && w.last_done == w.last_total,
           "%s: back %d, over %d, last %llu of %llu", kname[k], w.went_back, w.over, (unsigned long long)w.last_done,
           (unsigned long long)w.last_total);
    /* stop at each call (every few for the calls that build grids) */
    uint64_t all = w.calls, stride = k == K_SPLATTER || k == K_VT_CREATE || k == K_GPU ? 7 : 1, stopped = 0;
    for (uint64_t at = 1; at <= all; at += at + stride > all && at != all ? all - at : stride) {
        watch c;
        memset(&c, 0, sizeof c);
        c.stop_at = at;
        rs_ctx_set_progress(ctx, NULL, NULL);
        CHECK(prepare(ctx, f, k) == 0);
        rs_ctx_set_progress(ctx, on_progress, &c);
        uint64_t h;
        rs_result r = run_call(ctx, f, k, &h);
        CHECKF(r == RS_ERR_CANCELLED, "%s: stop at call %llu of %llu: %s", kname[k], (unsigned long long)at,
               (unsigned long long)all, rs_strerror(r));
        CHECKF(c.calls == at, "%s: stop at call %llu: called on %llu times", kname[k], (unsigned long long)at,
               (unsigned long long)c.calls);
        CHECK(strcmp(rs_ctx_message(ctx), "cancelled") == 0);
        if (roam_call(k) && k != K_ROAM_CREATE) { /* the landscape's mesh is still valid */
            int ok;
            roam_mesh(ctx, f, &ok);
            CHECKF(ok, "%s: stopped at call %llu, the mesh fails the checker", kname[k], (unsigned long long)at);
        }
        stopped++;
    }
    /* the objects work on: the same call, uninterrupted, gives the same output */
    rs_ctx_set_progress(ctx, NULL, NULL);
    if (k == K_ROAM_ERROR || k == K_ROAM_COUNT || k == K_ROAM_UPDATE) {
        /* on the landscape the last stop left */
        CHECKF(run_call(ctx, f, k, &h1) == RS_OK, "%s after a cancel: %s", kname[k], rs_ctx_message(ctx));
        if (k != K_ROAM_UPDATE) CHECKF(h1 == h0, "%s after a cancel: another mesh", kname[k]);
    }
    CHECK(prepare(ctx, f, k) == 0);
    CHECK(run_call(ctx, f, k, &h1) == RS_OK && h1 == h0);
    printf("%s: %llu progress calls, cancelled at %llu of them\n", kname[k], (unsigned long long)all,
           (unsigned long long)stopped);
}

static void test_calls(rs_ctx *ctx, const sc_scene *sc, rs_dem *dem, rs_roads *roads)
{
    fixture f;
    memset(&f, 0, sizeof f);
    f.dem = dem;
    f.roads = roads;
    /* a strip of the city's DEM at 10 texels, wider than a piece (2048
     * columns): two pieces a band */
    uint32_t sw = 206, sh = 12;
    float *z = malloc((size_t)sw * sh * sizeof *z);
    rs_roads *sr = NULL;
    CHECK(z && rs_roads_create(ctx, &sr) == RS_OK);
    if (!z || !sr) return;
    for (uint32_t i = 0; i < sw * sh; i++) z[i] = sc->z[(i / sw) * sc->w + i % sw];
    CHECK(rs_dem_create(ctx, sw, sh, z, &f.small) == RS_OK);
    free(z);
    rs_dem_frame fr = { sc->cell_size, 0.01, 0, 0 };
    CHECK(f.small && rs_dem_set_frame(ctx, f.small, &fr) == RS_OK);
    double a[] = { 3, 20, 500, 35, 1000, 28 }, b[] = { 40, 2, 45, 60 };
    CHECK(rs_roads_add(ctx, sr, "a", 6, a, 3) == RS_OK && rs_roads_add(ctx, sr, "b", 4, b, 2) == RS_OK);
    CHECK(rs_roads_set_attr(ctx, sr, 0, "class", "primary") == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 10;
    CHECK(rs_splatter_create(ctx, f.small, sr, NULL, &o, &f.sp) == RS_OK);
    uint32_t W, H;
    rs_splatter_size(f.sp, &W, &H);
    CHECK(W > 2048);
    f.px_bytes = (size_t)W * H * 4;
    f.px = malloc(f.px_bytes);
    /* the city's roads as text, a 600 x 600 DEM as P2 and 16-bit P5 (both
     * beyond one poll's 65536 samples) */
    {
        size_t cap = 64, len = 0;
        for (size_t i = 0; i < sc->nroads; i++) cap += 64 + 48 * sc->roads[i].n;
        char *t = malloc(cap);
        for (size_t i = 0; t && i < sc->nroads; i++) {
            len += (size_t)snprintf(t + len, cap - len, "road r%zu width %.17g\n", i, sc->roads[i].width);
            for (size_t q = 0; q < sc->roads[i].n; q++)
                len += (size_t)snprintf(t + len, cap - len, "%.17g %.17g\n", sc->roads[i].xy[2 * q],
                                        sc->roads[i].xy[2 * q + 1]);
            len += (size_t)snprintf(t + len, cap - len, "end\n");
        }
        f.roads_text = t;
        f.roads_len = len;
        const uint32_t side = 600;
        size_t n = (size_t)side * side;
        f.pgm[0] = malloc(32 + 6 * n);
        f.pgm[1] = malloc(32 + 2 * n);
        if (f.pgm[0] && f.pgm[1]) {
            size_t pa = (size_t)sprintf(f.pgm[0], "P2\n%u %u\n4000\n", side, side);
            size_t pb = (size_t)sprintf(f.pgm[1], "P5\n%u %u\n4000\n", side, side);
            for (size_t i = 0; i < n; i++) {
                unsigned v = (unsigned)((i * 2654435761u) % 4001u);
                pa += (size_t)sprintf(f.pgm[0] + pa, "%u\n", v);
                f.pgm[1][pb++] = (char)(v >> 8);
                f.pgm[1][pb++] = (char)(v & 255);
            }
            f.pgm_len[0] = pa;
            f.pgm_len[1] = pb;
        }
        CHECK(t && f.pgm[0] && f.pgm[1]);
    }
    /* the virtual texture of the styled city at 2 texels (its tiles) */
    rs_splatter *city = NULL;
    o.texels = 2;
    CHECK(rs_splatter_create(ctx, dem, roads, NULL, &o, &city) == RS_OK);
    rs_vt_options vo;
    memset(&vo, 0, sizeof vo);
    vo.roads = roads;
    vo.tile_size = 64;
    CHECK(city && rs_vt_create(ctx, city, &vo, &f.vt) == RS_OK && rs_vt_workspace_create(ctx, f.vt, &f.vws) == RS_OK);
    /* ROAM: a 257^2 fractal */
    f.fw = 257;
    float *fz = malloc((size_t)f.fw * f.fw * sizeof *fz);
    CHECK(fz != NULL);
    if (!fz || !f.px || !f.vws) return;
    rc_dem_fractal(fz, f.fw, f.fw, 77, 128.0, 60.0, 0.5);
    f.fz = fz;
    CHECK(rs_dem_create(ctx, f.fw, f.fw, fz, &f.fractal) == RS_OK);
    for (int k = 0; k < K_COUNT; k++) {
        if (k == K_VT_CREATE) { /* its splatter is the city's */
            rs_splatter *t = f.sp;
            f.sp = city;
            test_call(ctx, &f, k);
            f.sp = t;
            continue;
        }
        test_call(ctx, &f, k);
    }
    rs_ctx_set_progress(ctx, NULL, NULL);
    rs_roam_free(ctx, f.roam);
    rs_dem_free(ctx, f.fractal);
    free(fz);
    rs_vt_workspace_free(ctx, f.vws);
    rs_vt_free(ctx, f.vt);
    rs_splatter_free(ctx, city);
    rs_splatter_free(ctx, f.sp);
    rs_roads_free(ctx, sr);
    rs_dem_free(ctx, f.small);
    free(f.px);
    free(f.roads_text);
    free(f.pgm[0]);
    free(f.pgm[1]);
}

/* rs__sort (lib/sort.c): stable, the same order as a reference insertion
 * sort, for small and large elements and many ties; a stop leaves the
 * array as it was; out of memory too. */
typedef struct sort_item {
    uint32_t key, at;
    unsigned char pad[32];
} sort_item;
static int sort_item_cmp(const void *a, const void *b)
{
    const sort_item *x = a, *y = b;
    return (x->key > y->key) - (x->key < y->key);
}
static int sort_u32_cmp(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a >> 8, y = *(const uint32_t *)b >> 8; /* low byte: the tie breaker */
    return (x > y) - (x < y);
}
static int stop_second(void *user, uint64_t done, uint64_t total)
{
    (void)done, (void)total;
    return ++*(int *)user >= 2;
}
static void *small_malloc(void *user, size_t size) { (void)user; return size > 4096 ? NULL : malloc(size); }
static void *small_realloc(void *user, void *p, size_t size) { (void)user; return size > 4096 ? NULL : realloc(p, size); }
static void small_free(void *user, void *p) { (void)user; free(p); }

static void test_sort(rs_ctx *ctx)
{
    static const size_t sizes[] = { 0, 1, 2, 15, 16, 17, 33, 100, 1000, 40000 };
    int bad = 0;
    uint32_t seed = 12345;
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; si++) {
        size_t n = sizes[si];
        for (uint32_t range = 1; range <= 1000000; range *= 100) {
            sort_item *v = calloc(n ? n : 1, sizeof *v);
            uint32_t *u = calloc(n ? n : 1, sizeof *u);
            for (size_t i = 0; i < n; i++) {
                seed = seed * 1103515245u + 12345u;
                v[i].key = (seed >> 8) % range;
                v[i].at = (uint32_t)i;
                v[i].pad[i % 32] = (unsigned char)i;
                u[i] = (v[i].key << 8) | (uint32_t)(i & 255);
            }
            /* the keyed sort (keys from a copy, in the elements' order) must give the same order */
            sort_item *w = malloc((n ? n : 1) * sizeof *w);
            uint64_t *key = malloc((n ? n : 1) * sizeof *key);
            memcpy(w, v, n * sizeof *v);
            for (size_t i = 0; i < n; i++) key[i] = (uint64_t)w[i].key << 31; /* (high bits too) */
            CHECK(rs__sort(ctx, v, n, sizeof *v, sort_item_cmp) == RS_OK);
            CHECK(rs__sort_keyed(ctx, w, n, sizeof *w, key) == RS_OK);
            bad += n && memcmp(v, w, n * sizeof *v) != 0;
            free(w);
            free(key);
            for (size_t i = 1; i < n; i++)
                bad += v[i - 1].key > v[i].key || (v[i - 1].key == v[i].key && v[i - 1].at >= v[i].at);
            for (size_t i = 0; i < n; i++) bad += v[i].pad[v[i].at % 32] != (unsigned char)v[i].at;
            /* 4-byte elements against an insertion sort by the high bits */
            uint32_t *ref = malloc((n ? n : 1) * sizeof *ref);
            memcpy(ref, u, n * sizeof *u);
            if (n <= 1000)
                for (size_t i = 1; i < n; i++)
                    for (size_t j = i; j > 0 && sort_u32_cmp(&ref[j - 1], &ref[j]) > 0; j--) {
                        uint32_t t = ref[j];
                        ref[j] = ref[j - 1];
                        ref[j - 1] = t;
                    }
            CHECK(rs__sort(ctx, u, n, sizeof *u, sort_u32_cmp) == RS_OK);
            if (n <= 1000) bad += n && memcmp(ref, u, n * sizeof *u) != 0;
            free(ref);
            free(v);
            free(u);
        }
    }
    CHECKF(bad == 0, "%d elements out of order or unstable", bad);

    /* a stop: RS_ERR_CANCELLED, the array untouched */
    size_t n = 200000;
    uint32_t *u = malloc(n * sizeof *u), *keep = malloc(n * sizeof *u);
    for (size_t i = 0; i < n; i++) u[i] = (uint32_t)((i * 2654435761u) >> 4);
    memcpy(keep, u, n * sizeof *u);
    rs_ctx *c2 = NULL;
    int calls = 0;
    CHECK(rs_ctx_create(NULL, NULL, &c2) == RS_OK);
    rs_ctx_set_progress(c2, stop_second, &calls);
    rs__progress pg;
    rs__progress_begin(c2, &pg, NULL, NULL, 1, 1);
    CHECK(rs__sort(c2, u, n, sizeof *u, sort_u32_cmp) == RS_ERR_CANCELLED);
    CHECK(rs__progress_end(c2, &pg, RS_ERR_CANCELLED) == RS_ERR_CANCELLED);
    CHECK(calls == 2 && memcmp(u, keep, n * sizeof *u) == 0);
    rs_ctx_free(c2);
    /* the keyed sort (a radix over (key, index) records) stopped the same way */
    uint64_t *key = malloc(n * sizeof *key);
    for (size_t i = 0; key && i < n; i++) key[i] = (uint64_t)u[i] * 0x9E3779B97F4A7C15ull;
    calls = 0;
    CHECK(key && rs_ctx_create(NULL, NULL, &c2) == RS_OK);
    rs_ctx_set_progress(c2, stop_second, &calls);
    rs__progress_begin(c2, &pg, NULL, NULL, 1, 1);
    CHECK(key && rs__sort_keyed(c2, u, n, sizeof *u, key) == RS_ERR_CANCELLED);
    CHECK(rs__progress_end(c2, &pg, RS_ERR_CANCELLED) == RS_ERR_CANCELLED);
    CHECK(calls == 2 && memcmp(u, keep, n * sizeof *u) == 0);
    rs_ctx_free(c2);
    /* records with keys over all 64 bits and many ties: by key, ties in
     * their order (against the merge sort's order of the same keys) */
    rs__keyed *rec = malloc(n * sizeof *rec);
    uint32_t *idx = malloc(n * sizeof *idx);
    int badr = 0;
    for (size_t i = 0; rec && idx && i < n; i++) {
        rec[i].h = key[i] >> (i % 3 ? 0 : 40); /* (a third share their high bytes' zeros) */
        rec[i].i = (uint32_t)i, rec[i].pos = 0;
        key[i] = rec[i].h;
        idx[i] = (uint32_t)i;
    }
    CHECK(rec && idx && rs__sort_recs(ctx, rec, n) == RS_OK && rs__sort_keyed(ctx, idx, n, sizeof *idx, key) == RS_OK);
    for (size_t i = 0; rec && idx && i < n; i++) {
        badr += rec[i].i != idx[i];
        if (i) badr += rec[i - 1].h > rec[i].h || (rec[i - 1].h == rec[i].h && rec[i - 1].i >= rec[i].i);
    }
    CHECKF(badr == 0, "rs__sort_recs: %d records out of order, unstable or not the keyed sort's", badr);
    free(rec);
    free(idx);
    free(key);
    /* no memory for the indices: RS_ERR_NOMEM, untouched */
    rs_allocator al = { small_malloc, small_realloc, small_free, NULL };
    CHECK(rs_ctx_create(&al, NULL, &c2) == RS_OK);
    CHECK(rs__sort(c2, u, n, sizeof *u, sort_u32_cmp) == RS_ERR_NOMEM);
    CHECK(memcmp(u, keep, n * sizeof *u) == 0);
    uint64_t *k2 = malloc(n * sizeof *k2);
    for (size_t i = 0; k2 && i < n; i++) k2[i] = n - i;
    CHECK(k2 && rs__sort_keyed(c2, u, n, sizeof *u, k2) == RS_ERR_NOMEM);
    CHECK(memcmp(u, keep, n * sizeof *u) == 0);
    free(k2);
    rs_ctx_free(c2);
    free(u);
    free(keep);
}

/* A splatter at 1 texel computes every sample's terrain colour
 * (rs__surface_colours, a poll a row): stopped at each of its callbacks it
 * returns RS_ERR_CANCELLED and makes nothing (the sanitizer build checks
 * that nothing leaks); run through, it splats the bytes of a run without
 * a callback. */
static void test_colour_table(void)
{
    rs_ctx *c2 = NULL;
    CHECK(rs_ctx_create(NULL, NULL, &c2) == RS_OK);
    enum { SIDE = 700 };
    float *z = malloc((size_t)SIDE * SIDE * sizeof *z);
    for (size_t i = 0; z && i < (size_t)SIDE * SIDE; i++) z[i] = (float)((i * 2654435761u) % 997u) * 0.1f;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    CHECK(z && rs_dem_create(c2, SIDE, SIDE, z, &dem) == RS_OK && rs_roads_create(c2, &roads) == RS_OK);
    static const double xy[4] = { 10, 10, 600, 500 };
    CHECK(roads && rs_roads_add(c2, roads, NULL, 8, xy, 2) == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 1;
    o.coverage.edges = RS_EDGES_ANALYTIC;
    watch w;
    memset(&w, 0, sizeof w);
    o.progress = on_progress;
    o.progress_user = &w;
    rs_splatter *s = NULL;
    uint64_t h0 = 0, h1 = 1;
    CHECK(dem && rs_splatter_create(c2, dem, roads, NULL, &o, &s) == RS_OK);
    uint64_t calls = w.calls;
    uint8_t *px = malloc((size_t)(SIDE - 1) * (SIDE - 1) * 4);
    if (s && px && !rs_splat_window(c2, s, 0, 0, SIDE - 1, SIDE - 1, px, (size_t)(SIDE - 1) * 4, NULL, 0, NULL))
        h0 = hash_rgba(px, (size_t)(SIDE - 1) * (SIDE - 1) * 4);
    rs_splatter_free(c2, s);
    /* the table's rows poll: more callbacks than the grid build's alone */
    CHECKF(calls >= 3, "%llu callbacks", (unsigned long long)calls);
    int bad = 0;
    for (uint64_t k = 1; k < calls; k++) {
        memset(&w, 0, sizeof w);
        w.stop_at = k;
        s = NULL;
        rs_result r = rs_splatter_create(c2, dem, roads, NULL, &o, &s);
        bad += r != RS_ERR_CANCELLED || s != NULL || w.calls != k;
        rs_splatter_free(c2, s);
    }
    CHECKF(bad == 0, "%d of %llu stops did not cancel cleanly", bad, (unsigned long long)(calls - 1));
    o.progress = NULL;
    s = NULL;
    if (rs_splatter_create(c2, dem, roads, NULL, &o, &s) == RS_OK && px &&
        !rs_splat_window(c2, s, 0, 0, SIDE - 1, SIDE - 1, px, (size_t)(SIDE - 1) * 4, NULL, 0, NULL))
        h1 = hash_rgba(px, (size_t)(SIDE - 1) * (SIDE - 1) * 4);
    CHECK(h0 == h1);
    rs_splatter_free(c2, s);
    free(px);
    rs_roads_free(c2, roads);
    rs_dem_free(c2, dem);
    free(z);
    rs_ctx_free(c2);
}

/* rs__grow / rs__resize: doubling keeps the elements; a block copied in
 * polled pieces (2 MB to 32 MB) can be stopped, leaving it as it was. */
static void test_grow(void)
{
    rs_ctx *c2 = NULL;
    CHECK(rs_ctx_create(NULL, NULL, &c2) == RS_OK);
    void *arr = NULL;
    size_t cap = 0, n = 0, bad = 0;
    for (; n < ((size_t)9 << 20) / sizeof(uint32_t); n++) {
        if (rs__grow(c2, &arr, n, &cap, sizeof(uint32_t), 16, SIZE_MAX) != RS_OK) break;
        ((uint32_t *)arr)[n] = (uint32_t)(n * 2654435761u);
    }
    CHECK(n == ((size_t)9 << 20) / sizeof(uint32_t) && cap >= n);
    for (size_t i = 0; i < n; i++) bad += ((uint32_t *)arr)[i] != (uint32_t)(i * 2654435761u);
    CHECKF(bad == 0, "%zu elements changed by growth", bad);
    /* the capacity is capped at max: RS_ERR_LIMIT past it, unchanged */
    size_t cap2 = 16;
    void *a2 = malloc(16 * sizeof(uint32_t));
    CHECK(rs__grow(c2, &a2, 16, &cap2, sizeof(uint32_t), 16, 16) == RS_ERR_LIMIT && cap2 == 16);
    CHECK(rs__grow(c2, &a2, 16, &cap2, sizeof(uint32_t), 16, 20) == RS_OK && cap2 == 20);
    free(a2);
    /* a stop during the piecewise copy of the full 16 MB block */
    int calls = 0;
    rs_ctx_set_progress(c2, stop_second, &calls);
    rs__progress pg;
    rs__progress_begin(c2, &pg, NULL, NULL, 1, 1);
    n = cap;
    void *before = arr;
    for (size_t i = ((size_t)9 << 20) / sizeof(uint32_t); i < n; i++) ((uint32_t *)arr)[i] = (uint32_t)(i * 2654435761u);
    size_t cap_before = cap;
    CHECK(rs__grow(c2, &arr, n, &cap, sizeof(uint32_t), 16, SIZE_MAX) == RS_ERR_CANCELLED);
    CHECK(rs__progress_end(c2, &pg, RS_ERR_CANCELLED) == RS_ERR_CANCELLED);
    CHECK(arr == before && cap == cap_before && calls == 2);
    bad = 0;
    for (size_t i = 0; i < n; i++) bad += ((uint32_t *)arr)[i] != (uint32_t)(i * 2654435761u);
    CHECKF(bad == 0, "%zu elements changed by a stopped growth", bad);
    free(arr);
    rs_ctx_free(c2);
    /* no memory: RS_ERR_NOMEM, the block kept */
    rs_allocator al = { small_malloc, small_realloc, small_free, NULL };
    CHECK(rs_ctx_create(&al, NULL, &c2) == RS_OK);
    arr = NULL, cap = 0;
    for (n = 0; n < 2048; n++) {
        rs_result r = rs__grow(c2, &arr, n, &cap, sizeof(uint32_t), 16, SIZE_MAX);
        if (r) {
            CHECK(r == RS_ERR_NOMEM && cap == 1024 && n == 1024);
            break;
        }
        ((uint32_t *)arr)[n] = (uint32_t)n;
    }
    bad = 0;
    for (size_t i = 0; i < n; i++) bad += ((uint32_t *)arr)[i] != (uint32_t)i;
    CHECK(bad == 0);
    small_free(NULL, arr);
    rs_ctx_free(c2);
}

int main(void)
{
    rs_ctx *ctx;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    sc_scene sc;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    /* a styled city: classes give lines, casings and automatic markings */
    CHECK(sc_city(&sc, 120, 100, 5.0, 300, 3) == 0);
    CHECK(rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) == RS_OK && rs_roads_create(ctx, &roads) == RS_OK);
    for (size_t i = 0; roads && i < sc.nroads; i++) {
        CHECK(rs_roads_add(ctx, roads, NULL, sc.roads[i].width, sc.roads[i].xy, sc.roads[i].n) == RS_OK);
        CHECK(rs_roads_set_attr(ctx, roads, i, "class", sc_city_class(sc.roads[i].width)) == RS_OK);
        CHECK(rs_roads_set_attr(ctx, roads, i, "lanes", "2") == RS_OK);
    }
    rs_dem_frame fc = { sc.cell_size, 0.01, 0, 0 };
    CHECK(rs_dem_set_frame(ctx, dem, &fc) == RS_OK);

    uint64_t h0 = 0, h1 = 1;
    watch w;
    memset(&w, 0, sizeof w);
    CHECK(build(ctx, dem, roads, NULL, &h0) == RS_OK);
    CHECK(build(ctx, dem, roads, &w, &h1) == RS_OK);
    CHECKF(h0 == h1, "a progress callback changed the image");
    /* 5b1f6e8's default build never called it */
    CHECKF(w.calls >= 5, "%llu progress calls", (unsigned long long)w.calls);
    CHECK(!w.went_back && !w.over && w.last_total > 0 && w.last_done == w.last_total);
    printf("grid build: %llu progress calls, total %llu\n", (unsigned long long)w.calls,
           (unsigned long long)w.last_total);

    /* stop at every call of the build: every stage cancels cleanly */
    uint64_t all = w.calls, cancelled = 0;
    for (uint64_t k = 1; k <= all; k++) {
        watch c;
        memset(&c, 0, sizeof c);
        c.stop_at = k;
        rs_result r = build(ctx, dem, roads, &c, NULL);
        CHECKF(r == RS_ERR_CANCELLED, "stop at call %llu of %llu: %s", (unsigned long long)k,
               (unsigned long long)all, rs_strerror(r));
        CHECKF(c.calls == k, "stop at call %llu: the build called on %llu times", (unsigned long long)k,
               (unsigned long long)c.calls);
        CHECK(strcmp(rs_ctx_message(ctx), "cancelled") == 0);
        cancelled += r == RS_ERR_CANCELLED;
    }
    printf("grid build: cancelled at %llu call points\n", (unsigned long long)cancelled);
    /* the context works on after a cancel */
    memset(&w, 0, sizeof w);
    h1 = 1;
    CHECK(build(ctx, dem, roads, &w, &h1) == RS_OK && h1 == h0);

    test_calls(ctx, &sc, dem, roads);
    test_sort(ctx);
    test_grow();
    test_colour_table();

    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
    return th_finish("test_progress");
}
