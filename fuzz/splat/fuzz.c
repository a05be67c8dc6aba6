/* libFuzzer target: the whole splat pipeline on a small random scene, and
 * the windowed splatter: a random window must equal the crop of the whole
 * image (alpha-map or analytic edges, the latter through the road field).
 *
 * Input layout (short input reads as zero bytes):
 *   0,1   DEM width/height - 2, mod 23 (so 2..24 samples per side)
 *   2     flags: bits 0-1 texels-1 (1..4), bit 2 dilate buffer, bit 3 jitter,
 *         bit 4 weight output, bit 5 textures, bit 6 cancel via progress,
 *         bit 7 corrupt one option (byte 11 picks which)
 *   3     cell size/16 (0 = default)        4  z-scale: (b-128)/16 (0 = default)
 *   5     alpha_res mod 16 (0 = default 32, 1 invalid; small keeps execs fast)
 *   6     transition: (int8)b/8 px (0 = default, < 0 hard edge)
 *   7     road cell: 0 auto, else cell size / (b%16+1), tiny when b >= 240
 *   8     jitter amount b/255 and seed      9,10  origin (int8)*8 metres
 *   11    corrupted option (mod 12) / cancel point (mod 8); bit 4 short-buffer
 *         probe, bit 5 determinism check (second splat), bit 6 analytic
 *         edges, bit 7 window check (window from the 4 bytes after the roads)
 *   then  W*H height bytes (255 NaN, 254 +3e38, 253 -3e38), then roads:
 *         [points-1 mod 8][width/8][coordinate mode] then 2 bytes per point.
 * Cell size, z-scale and origin are the DEM's frame (rs_dem_set_frame).
 * Findings (abort): an unknown result code, success after an invalid option,
 * a window that differs from the crop of the whole image, layers of the
 * window (rs_splat_layers_window) that recompose to more than 1/255 from it
 * or whose coverage is not its weight,
 * a write outside the buffers sized by rs_splat_size, non-zero weight with no
 * roads, a non-deterministic second splat, an object returned on failure. */
#include "roadsplat.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define REQUIRE(c) do { if (!(c)) abort(); } while (0)
#define CANARY 0xA5
#define GUARD 64

typedef struct reader {
    const uint8_t *p;
    size_t n, i;
} reader;

static uint8_t next(reader *r) { return r->i < r->n ? r->p[r->i++] : 0; }

typedef struct cancel_state {
    unsigned calls, stop_at;
} cancel_state;

static int cancel_cb(void *user, uint64_t done, uint64_t total)
{
    cancel_state *c = user;
    REQUIRE(done <= total);
    return ++c->calls >= c->stop_at;
}

static int known_result(rs_result r) { return r >= RS_OK && r <= RS_ERR_CANCELLED; }

/* 1..4 x 1..4 RGBA image from the input. */
static uint8_t *make_texture(reader *r, rs_image *img)
{
    uint8_t b = next(r);
    img->width = 1 + (b & 3);
    img->height = 1 + ((b >> 2) & 3);
    uint8_t *px = malloc((size_t)img->width * img->height * 4);
    if (px)
        for (size_t k = 0; k < (size_t)img->width * img->height * 4; k++) px[k] = next(r);
    img->rgba = px;
    return px;
}

/* Coordinate for byte pair (a, b) in one of four ranges: on the map,
 * around it, far outside, absurdly far. */
static double coord(uint8_t a, uint8_t b, int mode, double extent)
{
    double u = ((double)a * 256 + b) / 65535.0; /* 0..1 */
    switch (mode & 3) {
    case 0: return u * extent;
    case 1: return (u * 3 - 1) * extent;
    case 2: return (u * 2 - 1) * 1e7;
    default: return (u * 2 - 1) * 1e300;
    }
}

/* Returns 1 when an option was corrupted, 2 when the frame was. */
static int corrupt(rs_splat_options *o, rs_dem_frame *f, uint8_t which)
{
    switch (which % 12) {
    case 0: f->cell_size = NAN; return 2;
    case 1: f->cell_size = -1; return 2;
    case 2: f->z_scale = INFINITY; return 2;
    case 3: o->texels = 2000; break;
    case 4: o->grid.buffer = (rs_buffer_mode)7; break;
    case 5: o->coverage.alpha_res = 1; break;
    case 6: o->coverage.alpha_res = 5000; break;
    case 7: f->origin_x = NAN; return 2;
    case 8: o->grid.road_cell = -1; break;
    case 9: o->coverage.jitter = 1; o->coverage.jitter_amount = 2; break;
    case 10: o->coverage.transition_px = INFINITY; break;
    default: o->surface.texture_scale = NAN; break;
    }
    return 1;
}

/* The window's layers recompose to the whole image's colour within 1/255
 * (include/roadsplat.h, rs_splat_layers), their coverage is the weight. */
static void check_layers(rs_ctx *ctx, const rs_splatter *sp, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                         const uint8_t *whole, const uint16_t *wwhole, uint32_t ow)
{
    const size_t n = (size_t)w * h;
    uint8_t *pl = malloc(n * 16);
    uint16_t *cv = malloc(n * sizeof *cv);
    rs_splat_layers L;
    memset(&L, 0, sizeof L);
    if (pl && cv) {
        L.terrain = pl;
        L.casing = pl + n * 4;
        L.surface = pl + n * 8;
        L.paint = pl + n * 12;
        L.terrain_stride = L.casing_stride = L.surface_stride = L.paint_stride = (size_t)w * 4;
        L.coverage = cv;
        L.coverage_stride = w;
        rs_result r = rs_splat_layers_window(ctx, sp, NULL, x0, y0, w, h, &L, NULL);
        REQUIRE(r == RS_OK || r == RS_ERR_NOMEM);
        for (size_t i = 0; r == RS_OK && i < n; i++) {
            size_t at = (y0 + i / w) * (size_t)ow + x0 + i % w;
            const uint8_t *out = whole + at * 4, *t = pl + 4 * i, *c = t + n * 4, *s = t + n * 8, *p = t + n * 12;
            if (wwhole) REQUIRE(cv[i] == wwhole[at]);
            double R = cv[i] / 65535.0;
            for (int ch = 0; ch < 3; ch++) {
                double g = t[ch] * (1 - c[3] / 255.0) + c[ch], road = s[ch] * (1 - p[3] / 255.0) + p[ch];
                double v = g * (1 - R) + road * R + 0.5;
                int b = v >= 255 ? 255 : (int)v;
                REQUIRE(b - out[ch] <= 1 && out[ch] - b <= 1);
            }
        }
    }
    free(pl);
    free(cv);
}

/* Window [x0,x0+w) x [y0,y0+h) rendered alone equals the crop of the whole. */
static void check_window(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *grid, const rs_splat_options *o,
                         reader *rd, const uint8_t *whole, const uint16_t *wwhole, uint32_t ow, uint32_t oh)
{
    rs_splatter *sp = NULL;
    rs_splat_options wo = *o;
    wo.progress = NULL; /* the whole image may have been cancelled on purpose; the window is not */
    rs_result r = rs_splatter_create(ctx, dem, NULL, grid, &wo, &sp);
    REQUIRE(r == RS_OK || r == RS_ERR_NOMEM);
    if (r) { REQUIRE(sp == NULL); return; }
    uint32_t x0 = next(rd) % ow, y0 = next(rd) % oh;
    uint32_t w = 1 + next(rd) % (ow - x0), h = 1 + next(rd) % (oh - y0);
    size_t stride = (size_t)w * 4 + 12; /* a padded stride must work too */
    uint8_t *px = malloc(stride * h);
    uint16_t *wt = malloc(((size_t)w + 3) * h * sizeof *wt);
    if (px && wt) {
        memset(px, CANARY, stride * h);
        r = rs_splat_window(ctx, sp, x0, y0, w, h, px, stride, wt, (size_t)w + 3, NULL);
        REQUIRE(r == RS_OK || r == RS_ERR_NOMEM);
        if (r == RS_OK)
            for (uint32_t y = 0; y < h; y++) {
                REQUIRE(memcmp(px + y * stride, whole + ((size_t)(y0 + y) * ow + x0) * 4, (size_t)w * 4) == 0);
                for (size_t k = (size_t)w * 4; k < stride; k++) REQUIRE(px[y * stride + k] == CANARY);
                if (wwhole)
                    REQUIRE(memcmp(wt + (size_t)y * (w + 3), wwhole + (size_t)(y0 + y) * ow + x0,
                                   (size_t)w * sizeof *wt) == 0);
            }
        if (r == RS_OK) check_layers(ctx, sp, x0, y0, w, h, whole, wwhole, ow);
        /* outside the image, empty: refused */
        REQUIRE(rs_splat_window(ctx, sp, x0, y0, w + (ow - x0), h, px, stride, NULL, 0, NULL) == RS_ERR_INVALID_ARG);
        REQUIRE(rs_splat_window(ctx, sp, x0, y0, 0, h, px, stride, NULL, 0, NULL) == RS_ERR_INVALID_ARG);
    }
    free(px);
    free(wt);
    rs_splatter_free(ctx, sp);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    reader rd = { data, size, 0 };
    const uint32_t W = 2 + next(&rd) % 23, H = 2 + next(&rd) % 23;
    const uint8_t flags = next(&rd);
    rs_splat_options o;
    rs_dem_frame fr;
    memset(&o, 0, sizeof o);
    memset(&fr, 0, sizeof fr);
    o.texels = 1 + (flags & 3);
    o.grid.buffer = flags & 4 ? RS_BUFFER_DILATE : RS_BUFFER_DISTANCE;
    fr.cell_size = next(&rd) / 16.0;
    uint8_t zb = next(&rd);
    fr.z_scale = zb ? (zb - 128) / 16.0 : 0;
    o.coverage.alpha_res = next(&rd) % 16;
    double tr = (int8_t)next(&rd) / 8.0;
    if (tr < 0) o.coverage.hard_edge = 1;
    else o.coverage.transition_px = tr;
    uint8_t rc_b = next(&rd);
    const double cs = fr.cell_size > 0 ? fr.cell_size : 1;
    o.grid.road_cell = rc_b == 0 ? 0 : rc_b >= 240 ? cs * 1e-6 * (rc_b - 239) : cs / (rc_b % 16 + 1);
    uint8_t jb = next(&rd);
    if (flags & 8) {
        o.coverage.jitter = 1;
        o.coverage.jitter_seed = 1u + jb;
        o.coverage.jitter_amount = jb / 255.0;
    }
    fr.origin_x = (int8_t)next(&rd) * 8.0;
    fr.origin_y = (int8_t)next(&rd) * 8.0;
    const uint8_t probe = next(&rd);
    o.coverage.edges = probe & 0x40 ? RS_EDGES_ANALYTIC : RS_EDGES_ALPHAMAP;
    /* Invalid by construction: alpha_res 1, a transition wider than half the
     * alpha-map (defaults: 32 and 2), or a corrupted field (below). */
    int invalid = o.coverage.alpha_res == 1 ||
                  (tr > 0 ? tr : 2) > (o.coverage.alpha_res ? o.coverage.alpha_res : 32) / 2.0;

    float *z = malloc((size_t)W * H * sizeof *z);
    if (!z) return 0;
    for (size_t k = 0; k < (size_t)W * H; k++) {
        uint8_t b = next(&rd);
        z[k] = b == 255 ? NAN : b == 254 ? 3e38f : b == 253 ? -3e38f : (float)b * 4.0f;
    }

    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_pixels = (uint64_t)1 << 16;
    lim.max_road_cells = (uint64_t)1 << 18;
    lim.max_points = 64;
    rs_ctx *ctx = NULL;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_road_grid *grid = NULL;
    uint8_t *tex_px[2] = { NULL, NULL }, *rgba = NULL, *rgba2 = NULL;
    uint16_t *weight = NULL;
    rs_image tex[2];
    if (rs_ctx_create(NULL, &lim, &ctx) != RS_OK) { free(z); return 0; }
    REQUIRE(rs_dem_create(ctx, W, H, z, &dem) == RS_OK); /* finite or NaN: valid */
    REQUIRE(rs_roads_create(ctx, &roads) == RS_OK);
    /* frame fields are corrupted here, option fields after the textures */
    rs_splat_options o_corrupt = o;
    int bad_frame = (flags & 0x80) && corrupt(&o_corrupt, &fr, probe) == 2;
    {
        rs_result fr_r = rs_dem_set_frame(ctx, dem, &fr);
        REQUIRE(bad_frame ? fr_r == RS_ERR_INVALID_ARG : fr_r == RS_OK);
        if (bad_frame) goto out;
    }

    if (flags & 0x20) {
        tex_px[0] = make_texture(&rd, &tex[0]);
        tex_px[1] = make_texture(&rd, &tex[1]);
        if (!tex_px[0] || !tex_px[1]) goto out;
        o.surface.terrain_texture = &tex[0];
        o.surface.road_texture = &tex[1];
        o.surface.texture_scale = 0.5 + (tex_px[0][0] & 15);
    }

    const double extent = (W > H ? W : H) * cs;
    for (int road = 0; road < 6 && rd.i < rd.n; road++) {
        size_t n = 1 + next(&rd) % 8;
        double width = next(&rd) / 8.0;
        int mode = next(&rd);
        double xy[16];
        for (size_t k = 0; k < 2 * n; k++) {
            uint8_t a = next(&rd), b = next(&rd);
            xy[k] = coord(a, b, mode, extent) + (k & 1 ? fr.origin_y : fr.origin_x);
        }
        if (mode & 4) xy[2 * n - 1] = mode & 8 ? NAN : INFINITY;
        int bad = n < 2 || !(width > 0) || (mode & 4);
        rs_result r = rs_roads_add(ctx, roads, "r", width, xy, n);
        REQUIRE(known_result(r));
        if (bad) REQUIRE(r != RS_OK);
        if (r == RS_OK) REQUIRE(!bad);
    }
    const size_t nroads = rs_roads_count(roads);

    if (flags & 0x80) invalid |= corrupt(&o, &fr, probe);
    cancel_state cancel = { 0, 1u + probe % 8 };
    if (flags & 0x40) { o.progress = cancel_cb; o.progress_user = &cancel; }

    rs_result r = rs_road_grid_build(ctx, dem, roads, &o, &grid);
    REQUIRE(known_result(r));
    REQUIRE(r == RS_OK || r == RS_ERR_INVALID_ARG || r == RS_ERR_LIMIT || r == RS_ERR_NOMEM ||
            r == RS_ERR_CANCELLED);
    if (r != RS_OK) { REQUIRE(grid == NULL); goto out; }
    rs_road_grid_stats gs;
    rs_road_grid_get_stats(grid, &gs);
    REQUIRE(gs.interior_cells + gs.boundary_cells == gs.road_cells);
    if (nroads == 0) REQUIRE(gs.road_cells == 0);
    /* the road field answers with a road it holds, or nothing */
    if (o.coverage.edges == RS_EDGES_ANALYTIC) {
        rs_road_point rp;
        if (rs_road_grid_query(grid, W * cs / 2, H * cs / 2, 1e3, &rp)) REQUIRE(rp.road < nroads && rp.distance >= 0);
    }

    uint32_t ow = 0, oh = 0;
    r = rs_splat_size(ctx, dem, &o, &ow, &oh);
    REQUIRE(r == RS_OK || r == RS_ERR_INVALID_ARG || r == RS_ERR_LIMIT);
    if (invalid) REQUIRE(r == RS_ERR_INVALID_ARG);
    if (r != RS_OK) {
        /* rs_splat must refuse the same options without touching memory. */
        uint8_t dummy[16];
        memset(dummy, CANARY, sizeof dummy);
        REQUIRE(rs_splat(ctx, dem, grid, &o, dummy, 4, NULL, 0) != RS_OK);
        for (size_t k = 0; k < sizeof dummy; k++) REQUIRE(dummy[k] == CANARY);
        goto out;
    }
    REQUIRE(ow == (W - 1) * o.texels && oh == (H - 1) * o.texels);
    const size_t npx = (size_t)ow * oh;
    rgba = malloc(npx * 4 + GUARD);
    rgba2 = malloc(npx * 4 + GUARD);
    weight = malloc((npx + GUARD) * sizeof *weight);
    if (!rgba || !rgba2 || !weight) goto out;
    memset(rgba, CANARY, npx * 4 + GUARD);
    memset(rgba2, CANARY, npx * 4 + GUARD);
    memset(weight, CANARY, (npx + GUARD) * sizeof *weight);
    uint16_t *wout = flags & 0x10 ? weight : NULL;

    /* A buffer one byte or one value short must be refused, untouched. */
    if (probe & 0x10) {
        r = rs_splat(ctx, dem, grid, &o, rgba, npx * 4 - 1, wout, npx);
        REQUIRE(r == RS_ERR_BUFFER_TOO_SMALL || r == RS_ERR_CANCELLED);
        if (wout) REQUIRE(rs_splat(ctx, dem, grid, &o, rgba, npx * 4, wout, npx - 1) != RS_OK);
        for (size_t k = 0; k < npx * 4 + GUARD; k++) REQUIRE(rgba[k] == CANARY);
    }

    cancel.calls = 0;
    r = rs_splat(ctx, dem, grid, &o, rgba, npx * 4, wout, npx);
    REQUIRE(r == RS_OK || r == RS_ERR_NOMEM || (r == RS_ERR_CANCELLED && (flags & 0x40)));
    for (size_t k = npx * 4; k < npx * 4 + GUARD; k++) REQUIRE(rgba[k] == CANARY);
    {
        const uint8_t *wb = (const uint8_t *)(weight + npx);
        for (size_t k = 0; k < GUARD * sizeof *weight; k++) REQUIRE(wb[k] == CANARY);
    }
    if (r != RS_OK) goto out;
    if (wout && nroads == 0)
        for (size_t k = 0; k < npx; k++) REQUIRE(weight[k] == 0);

    if (probe & 0x80) check_window(ctx, dem, grid, &o, &rd, rgba, wout, ow, oh);

    /* Same inputs, same bytes. */
    if ((probe & 0x20) && !(flags & 0x40)) {
        REQUIRE(rs_splat(ctx, dem, grid, &o, rgba2, npx * 4, NULL, 0) == RS_OK);
        REQUIRE(memcmp(rgba, rgba2, npx * 4) == 0);
    }

out:
    rs_road_grid_free(ctx, grid);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    free(z);
    free(tex_px[0]);
    free(tex_px[1]);
    free(rgba);
    free(rgba2);
    free(weight);
    return 0;
}
