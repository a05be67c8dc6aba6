/* The ABI rule of the option structs (issue 30; include/roadsplat.h "ABI"):
 * a struct with the size of an older header (a prefix) has its tail taken
 * as defaults whatever bytes lie beyond it; a larger struct (a newer
 * header) is accepted when its extra bytes are zero and refused with
 * RS_ERR_UNSUPPORTED naming the struct otherwise; size 0 and sizeof give
 * the same result; a getter writes only the bytes the host's size holds. */
#include "roadsplat.h"
#include "harness.h"

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static uint64_t hash_bytes(const uint8_t *p, size_t n)
{
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

/* The image of the roads over the DEM with `o` (its hash), or the result. */
static rs_result splat_hash(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                            uint64_t *hash)
{
    rs_splatter *s = NULL;
    rs_result r = rs_splatter_create(ctx, dem, roads, NULL, o, &s);
    if (r) return r;
    uint32_t W, H;
    rs_splatter_size(s, &W, &H);
    uint8_t *px = malloc((size_t)W * H * 4);
    r = px ? rs_splat_window(ctx, s, 0, 0, W, H, px, (size_t)W * 4, NULL, 0, NULL) : RS_ERR_NOMEM;
    if (!r) *hash = hash_bytes(px, (size_t)W * H * 4);
    free(px);
    rs_splatter_free(ctx, s);
    return r;
}

/* `opts` (`size` bytes) as a host built against a newer header passes it:
 * 16 bytes more, zero but for byte `set` of them (-1: none), its size
 * field saying so. free() it. */
static void *newer(const void *opts, size_t size, int set)
{
    unsigned char *p = calloc(1, size + 16);
    size_t n = size + 16;
    if (!p) return NULL;
    memcpy(p, opts, size);
    memcpy(p, &n, sizeof n);
    if (set >= 0) p[size + (size_t)set] = 1;
    return p;
}

static void test_roam_view(rs_ctx *ctx)
{
    float z[17 * 17];
    for (int i = 0; i < 17 * 17; i++) z[i] = (float)((i * 7919) % 13);
    rs_dem *dem = NULL;
    rs_roam *roam = NULL;
    CHECK(rs_dem_create(ctx, 17, 17, z, &dem) == RS_OK);
    CHECK(dem && rs_roam_create(ctx, dem, NULL, &roam) == RS_OK);
    if (!roam) return;
    rs_roam_view v;
    memset(&v, 0, sizeof v);
    v.eye[0] = 8; v.eye[1] = 8; v.eye[2] = 40;
    v.dir[0] = 0.2; v.dir[2] = -1;
    rs_roam_stats st;
    CHECK_EQ_INT(rs_roam_frame(ctx, roam, &v), RS_OK);
    rs_roam_get_stats(roam, &st);
    uint32_t tris = st.triangles;
    /* size 0 and sizeof: the same */
    v.size = sizeof v;
    CHECK_EQ_INT(rs_roam_frame(ctx, roam, &v), RS_OK);
    rs_roam_get_stats(roam, &st);
    CHECK_EQ_INT(st.triangles, tris);
    /* an older header without far_dist and what follows: the bytes there
     * (an invalid far plane, a hysteresis below 1) are not read */
    v.size = offsetof(rs_roam_view, far_dist);
    v.far_dist = -5;
    v.merge_hysteresis = 0.5;
    CHECK_EQ_INT(rs_roam_frame(ctx, roam, &v), RS_OK);
    rs_roam_get_stats(roam, &st);
    CHECK_EQ_INT(st.triangles, tris);
    CHECK_EQ_INT(rs_roam_update(ctx, roam, &v, 0), RS_OK);
    v.size = 0; /* the whole struct: the bad fields are read now */
    CHECK_EQ_INT(rs_roam_frame(ctx, roam, &v), RS_ERR_INVALID_ARG);
    v.far_dist = 0;
    v.merge_hysteresis = 0;
    /* a newer header: zero extra bytes accepted, set ones refused */
    rs_roam_view *nv = newer(&v, sizeof v, -1), *nv1 = newer(&v, sizeof v, 7);
    CHECK(nv && nv1);
    if (nv && nv1) {
        CHECK_EQ_INT(rs_roam_frame(ctx, roam, nv), RS_OK);
        rs_roam_get_stats(roam, &st);
        CHECK_EQ_INT(st.triangles, tris);
        CHECK_EQ_INT(rs_roam_frame(ctx, roam, nv1), RS_ERR_UNSUPPORTED);
        CHECKF(strstr(rs_ctx_message(ctx), "rs_roam_view.size") != NULL, "%s", rs_ctx_message(ctx));
        CHECK_EQ_INT(rs_roam_update(ctx, roam, nv1, 0), RS_ERR_UNSUPPORTED);
    }
    free(nv);
    free(nv1);
    /* a size that cannot even hold itself */
    v.size = 3;
    CHECK_EQ_INT(rs_roam_frame(ctx, roam, &v), RS_ERR_INVALID_ARG);
    CHECKF(strstr(rs_ctx_message(ctx), "rs_roam_view.size 3") != NULL, "%s", rs_ctx_message(ctx));
    /* the mesh options: refused for extraction, bounded as with a skirt */
    rs_roam_mesh_options mo[2];
    memset(mo, 0, sizeof mo);
    mo[0].size = sizeof mo;
    mo[1].normals = 1;
    size_t mv0, mi0, mv1, mi1, nv0 = 0, ni0 = 0;
    rs_roam_mesh_bound(roam, NULL, &mv0, &mi0);
    rs_roam_mesh_bound(roam, &mo[0], &mv1, &mi1);
    CHECK(mv1 > mv0 && mi1 > mi0);
    float *vb = malloc(mv1 * 5 * sizeof *vb);
    uint32_t *ib = malloc(mi1 * sizeof *ib);
    CHECK_EQ_INT(rs_roam_extract(ctx, roam, &mo[0], vb, NULL, mv1, ib, mi1, &nv0, &ni0), RS_ERR_UNSUPPORTED);
    mo[0].size = sizeof mo[0];
    CHECK_EQ_INT(rs_roam_extract(ctx, roam, &mo[0], vb, NULL, mv1, ib, mi1, &nv0, &ni0), RS_OK);
    free(vb);
    free(ib);
    rs_roam_free(ctx, roam);
    rs_dem_free(ctx, dem);
}

static void test_splat(rs_ctx *ctx)
{
    enum { W = 24, H = 20 };
    float z[W * H];
    for (int i = 0; i < W * H; i++) z[i] = (float)(i % W) * 0.5f + (float)(i / W);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    const double a[] = { 1, 2, 22, 17 }, b[] = { 3, 18, 20, 3, 12, 1 };
    CHECK(rs_dem_create(ctx, W, H, z, &dem) == RS_OK && rs_roads_create(ctx, &roads) == RS_OK);
    CHECK(rs_roads_add(ctx, roads, "a", 2.5, a, 2) == RS_OK && rs_roads_add(ctx, roads, "b", 1.5, b, 3) == RS_OK);
    CHECK(rs_roads_set_attr(ctx, roads, 0, "class", "residential") == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    uint64_t h0 = 0, h1 = 1, hl = 2;
    CHECK_EQ_INT(splat_hash(ctx, dem, roads, &o, &h0), RS_OK);
    o.size = sizeof o;
    CHECK_EQ_INT(splat_hash(ctx, dem, roads, &o, &h1), RS_OK);
    CHECK(h0 == h1);
    /* lit: another image */
    o.lighting.enable = 1;
    CHECK_EQ_INT(splat_hash(ctx, dem, roads, &o, &hl), RS_OK);
    CHECK(hl != h0);
    /* an older header that ended before `lighting`: the lighting bytes
     * (set) are not read, the image is the unlit one */
    o.size = offsetof(rs_splat_options, lighting);
    h1 = 1;
    CHECK_EQ_INT(splat_hash(ctx, dem, roads, &o, &h1), RS_OK);
    CHECK(h1 == h0);
    /* the nested structs' own size fields mean nothing inside */
    o.size = 0;
    o.lighting.enable = 0;
    o.style.size = 7;
    o.lighting.normal.size = 1000;
    h1 = 1;
    CHECK_EQ_INT(splat_hash(ctx, dem, roads, &o, &h1), RS_OK);
    CHECK(h1 == h0);
    o.style.size = o.lighting.normal.size = 0;
    /* a newer header */
    rs_splat_options *ns = newer(&o, sizeof o, -1), *ns1 = newer(&o, sizeof o, 10);
    CHECK(ns && ns1);
    if (ns && ns1) {
        h1 = 1;
        CHECK_EQ_INT(splat_hash(ctx, dem, roads, ns, &h1), RS_OK);
        CHECK(h1 == h0);
        rs_road_grid *g = NULL;
        CHECK_EQ_INT(rs_road_grid_build(ctx, dem, roads, ns1, &g), RS_ERR_UNSUPPORTED);
        CHECK(g == NULL);
        CHECKF(strstr(rs_ctx_message(ctx), "rs_splat_options.size") != NULL, "%s", rs_ctx_message(ctx));
        rs_gpu_scene *gs = NULL;
        CHECK_EQ_INT(rs_gpu_scene_create(ctx, dem, roads, ns1, NULL, &gs), RS_ERR_UNSUPPORTED);
        CHECK(gs == NULL);
        uint32_t sw, sh;
        CHECK_EQ_INT(rs_splat_size(ctx, dem, ns1, &sw, &sh), RS_ERR_UNSUPPORTED);
    }
    free(ns);
    free(ns1);
    /* the layers' plane set: a newer header's struct with its extra bytes
     * zero draws, with one of them set it is refused */
    {
        rs_splatter *sp = NULL;
        CHECK_EQ_INT(rs_splatter_create(ctx, dem, roads, NULL, &o, &sp), RS_OK);
        uint8_t t0[8 * 4 * 4], t1[8 * 4 * 4];
        rs_splat_layers L;
        memset(&L, 0, sizeof L);
        L.terrain = t0;
        L.terrain_stride = 8 * 4;
        CHECK_EQ_INT(rs_splat_layers_window(ctx, sp, NULL, 3, 5, 8, 4, &L, NULL), RS_OK);
        L.terrain = t1;
        rs_splat_layers *nl = newer(&L, sizeof L, -1), *nl1 = newer(&L, sizeof L, 3);
        CHECK(nl && nl1);
        if (nl && nl1) {
            memset(t1, 0, sizeof t1);
            CHECK_EQ_INT(rs_splat_layers_window(ctx, sp, NULL, 3, 5, 8, 4, nl, NULL), RS_OK);
            CHECK(memcmp(t0, t1, sizeof t0) == 0);
            CHECK_EQ_INT(rs_splat_layers_window(ctx, sp, NULL, 3, 5, 8, 4, nl1, NULL), RS_ERR_UNSUPPORTED);
            CHECKF(strstr(rs_ctx_message(ctx), "rs_splat_layers.size") != NULL, "%s", rs_ctx_message(ctx));
        }
        free(nl);
        free(nl1);
        rs_splatter_free(ctx, sp);
    }
    /* the standalone style options, a struct without a context */
    rs_style_options so[2];
    memset(so, 0, sizeof so);
    rs_style st0, st1;
    CHECK_EQ_INT(rs_road_style_ex(ctx, roads, 0, &so[0], &st0), RS_OK);
    so[0].size = sizeof so;
    so[1].profile = RS_PROFILE_MUTCD;
    CHECK_EQ_INT(rs_road_style_ex(ctx, roads, 0, &so[0], &st1), RS_ERR_UNSUPPORTED);
    rs_road_lanes ln;
    CHECK_EQ_INT(rs_road_lanes_get(roads, 0, &so[0], &ln), RS_ERR_UNSUPPORTED);
    so[0].size = sizeof so[0];
    CHECK_EQ_INT(rs_road_style_ex(ctx, roads, 0, &so[0], &st1), RS_OK);
    CHECK(memcmp(&st0, &st1, sizeof st0) == 0);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
}

static void test_limits(void)
{
    /* an older rs_limits without max_linesym_bytes: 1 there is not read */
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.size = offsetof(rs_limits, max_linesym_bytes);
    lim.max_linesym_bytes = 1;
    lim.max_dem_side = 100;
    rs_ctx *ctx = NULL;
    CHECK_EQ_INT(rs_ctx_create(NULL, &lim, &ctx), RS_OK);
    rs_limits got;
    memset(&got, 0, sizeof got);
    if (ctx) rs_ctx_limits(ctx, &got);
    CHECK_EQ_INT(got.size, sizeof got);
    CHECK_EQ_INT(got.max_dem_side, 100);
    CHECK(got.max_linesym_bytes == (uint64_t)1 << 32);
    CHECK(got.max_dirty_compare == (uint64_t)1 << 20);
    CHECK_EQ_INT(got.max_patches, 16);
    /* the getter writes only what an older host's struct holds */
    memset(&got, 0xAB, sizeof got);
    got.size = offsetof(rs_limits, max_atlas_bytes);
    if (ctx) rs_ctx_limits(ctx, &got);
    CHECK_EQ_INT(got.size, offsetof(rs_limits, max_atlas_bytes));
    CHECK_EQ_INT(got.max_dem_side, 100);
    CHECK(got.max_atlas_bytes == 0xABABABABABABABABull && got.max_linesym_bytes == 0xABABABABABABABABull);
    rs_ctx_free(ctx);
    /* newer: refused when the extra bytes are set (no context yet: no message) */
    memset(&lim, 0, sizeof lim);
    rs_limits *nl = newer(&lim, sizeof lim, -1), *nl1 = newer(&lim, sizeof lim, 3);
    ctx = NULL;
    CHECK(nl && nl1 && rs_ctx_create(NULL, nl, &ctx) == RS_OK);
    rs_ctx_free(ctx);
    ctx = NULL;
    CHECK(nl1 && rs_ctx_create(NULL, nl1, &ctx) == RS_ERR_UNSUPPORTED);
    CHECK(ctx == NULL);
    free(nl);
    free(nl1);
    /* rs_style_request: no context either */
    rs_style_request q;
    memset(&q, 0, sizeof q);
    q.road_class = RS_CLASS_PRIMARY;
    rs_style_request *nq = newer(&q, sizeof q, -1), *nq1 = newer(&q, sizeof q, 0);
    double w0 = 0, w1 = 0;
    rs_style st;
    CHECK(nq && nq1 && rs_style_default_width(nq, &w0) == RS_OK);
    CHECK(nq1 && rs_style_default_width(nq1, &w1) == RS_ERR_UNSUPPORTED);
    CHECK(nq1 && rs_style_default(nq1, &st) == RS_ERR_UNSUPPORTED);
    free(nq);
    free(nq1);
    /* an older request without the per-direction lanes and the side */
    q.size = offsetof(rs_style_request, lanes_forward);
    q.lanes_forward = 99; /* out of range if read */
    CHECK_EQ_INT(rs_style_default_width(&q, &w1), RS_OK);
    CHECK(w1 == w0);
}

static void test_others(rs_ctx *ctx)
{
    rs_roads *roads = NULL;
    const double a[] = { 0, 0, 10, 0 };
    CHECK(rs_roads_create(ctx, &roads) == RS_OK && rs_roads_add(ctx, roads, "a", 2, a, 2) == RS_OK);
    rs_network_options no;
    memset(&no, 0, sizeof no);
    rs_network_options *nn = newer(&no, sizeof no, -1), *nn1 = newer(&no, sizeof no, 15);
    rs_network *net = NULL;
    CHECK(nn && nn1 && rs_network_build(ctx, roads, nn, &net) == RS_OK);
    rs_network_free(ctx, net);
    net = NULL;
    CHECK(nn1 && rs_network_build(ctx, roads, nn1, &net) == RS_ERR_UNSUPPORTED);
    CHECK(net == NULL);
    free(nn);
    free(nn1);
    /* an older network options struct with only its size */
    no.size = sizeof(size_t);
    no.tolerance = -1; /* invalid if read */
    CHECK_EQ_INT(rs_network_build(ctx, roads, &no, &net), RS_OK);
    rs_network_free(ctx, net);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    rs_road_parse_options *np = newer(&po, sizeof po, 1);
    rs_roads *r2 = NULL;
    CHECK(np && rs_roads_parse_ex(ctx, "road a width 2\n0 0\n1 1\n", 24, np, &r2) == RS_ERR_UNSUPPORTED);
    CHECK(r2 == NULL);
    free(np);
    rs_roads_free(ctx, roads);
}

int main(void)
{
    rs_ctx *ctx;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    test_roam_view(ctx);
    test_splat(ctx);
    test_limits();
    test_others(ctx);
    rs_ctx_free(ctx);
    return th_finish("test_abi");
}
