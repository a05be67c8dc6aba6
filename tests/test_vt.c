/* The virtual texture (issue 30; include/roadsplat.h "Virtual texture"):
 * finest tiles are rs_splat's windows byte for byte (borders included),
 * direct coarser levels the splat at T/2^k, averaged levels the exact box
 * average of the splat at their texel count; the level at a ground point
 * never gets finer as the eye moves away; the resident set stays within the
 * budget over a flythrough and every tile the host is told about is
 * consistent (drops resident, makes new, slots unique); every visible point
 * is under a resident needed tile at least as fine as it asks for; the same
 * views give the same lists and the same bytes on two threads; updates and
 * made tiles allocate nothing. */
#include "roadsplat.h"
#include "fail_alloc.h"
#include "harness.h"
#include "scenes.h"
#include "scene_splat.h"

#include <limits.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* Allocator calls so far (fail_alloc counts its countdown down from LONG_MAX). */
static size_t calls(const fail_alloc *fa) { return (size_t)(LONG_MAX - fa->countdown); }

static const char scene_text[] =
    "style k\n casing 0.4 #707070\n line 0 0.15 #FFFFFF dash 3 6\n line -2.6 0.2 #FFFFFF\nend\n"
    "road a width 7 style=k\n0.5 11.3\n39.1 14.8\nend\n"
    "road b width 6 class=primary\n20.2 0.4\n23.9 39.5\nend\n"
    "road c width 4 class=residential\n3 35\n18 22\n36 38\nend\n"
    "mark arrow_left road=a s=12 t=-1.7\n";

#define DW 41
#define DH 37
#define TEX 12 /* levels 0..2 direct (12, 6, 3 texels), 3 and 4 averaged from 2 and 1 texels */

typedef struct scene {
    rs_dem *dem;
    rs_styles *styles;
    rs_roads *roads;
    rs_road_grid *grid;
    rs_splat_options o;
    rs_splatter *s;
    float z[DW * DH];
} scene;

static int scene_make(rs_ctx *ctx, scene *sc)
{
    memset(sc, 0, sizeof *sc);
    sc_dem_terrain(sc->z, DW, DH, 1.0, 7);
    float lo = sc->z[0];
    for (int i = 0; i < DW * DH; i++) lo = sc->z[i] < lo ? sc->z[i] : lo;
    for (int i = 0; i < DW * DH; i++) sc->z[i] = (sc->z[i] - lo) * 0.005f; /* 0 .. 3 m */
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    if (rs_dem_create(ctx, DW, DH, sc->z, &sc->dem) || rs_styles_create(ctx, &sc->styles)) return 1;
    po.styles = sc->styles;
    if (rs_roads_parse_ex(ctx, scene_text, strlen(scene_text), &po, &sc->roads)) return 1;
    memset(&sc->o, 0, sizeof sc->o);
    sc->o.texels = TEX;
    sc->o.style.styles = sc->styles;
    if (rs_road_grid_build(ctx, sc->dem, sc->roads, &sc->o, &sc->grid)) return 1;
    return rs_splatter_create(ctx, sc->dem, NULL, sc->grid, &sc->o, &sc->s) != RS_OK;
}

static void scene_free(rs_ctx *ctx, scene *sc)
{
    rs_splatter_free(ctx, sc->s);
    rs_road_grid_free(ctx, sc->grid);
    rs_roads_free(ctx, sc->roads);
    rs_styles_free(ctx, sc->styles);
    rs_dem_free(ctx, sc->dem);
}

/* The whole splat at t texels (w x h RGBA), malloc'd. */
static uint8_t *whole(rs_ctx *ctx, scene *sc, uint32_t t, uint32_t *w, uint32_t *h)
{
    rs_splat_options o = sc->o;
    o.texels = t;
    rs_splatter *s;
    /* a grid of its own (the scene is styled: its lines are laid out in the grid's pixels) */
    if (rs_splatter_create(ctx, sc->dem, t == TEX ? NULL : sc->roads, t == TEX ? sc->grid : NULL, &o, &s)) return NULL;
    rs_splatter_size(s, w, h);
    uint8_t *px = malloc((size_t)*w * *h * 4);
    if (px && rs_splat_window(ctx, s, 0, 0, *w, *h, px, (size_t)*w * 4, NULL, 0, NULL)) {
        free(px);
        px = NULL;
    }
    rs_splatter_free(ctx, s);
    return px;
}

/* The level-k image pixel (X, Y) as the documented rule computes it, in
 * plain doubles: the area average (alpha-weighted colour) of the splat at t
 * texels (w x h, `src`) over the pixel's square, transparent outside. */
static void reference_pixel(const uint8_t *src, uint32_t w, uint32_t h, uint32_t t, uint32_t k, long X, long Y,
                            uint8_t out[4])
{
    double p = (double)(1u << k) / TEX, q = 1.0 / t; /* cells */
    double acc[4] = { 0, 0, 0, 0 };
    for (long j = (long)floor(Y * p / q) - 1; j <= (long)ceil((Y + 1) * p / q) + 1; j++)
        for (long i = (long)floor(X * p / q) - 1; i <= (long)ceil((X + 1) * p / q) + 1; i++) {
            if (i < 0 || j < 0 || i >= (long)w || j >= (long)h) continue;
            double ox = fmin((i + 1) * q, (X + 1) * p) - fmax(i * q, X * p);
            double oy = fmin((j + 1) * q, (Y + 1) * p) - fmax(j * q, Y * p);
            if (ox <= 0 || oy <= 0) continue;
            const uint8_t *s = src + ((size_t)j * w + i) * 4;
            double wa = ox * oy * s[3];
            for (int c = 0; c < 3; c++) acc[c] += wa * s[c];
            acc[3] += wa;
        }
    memset(out, 0, 4);
    double a = acc[3] / (p * p);
    if (acc[3] <= 0 || floor(a + 0.5) < 1) return;
    for (int c = 0; c < 3; c++) out[c] = (uint8_t)floor(acc[c] / acc[3] + 0.5);
    out[3] = (uint8_t)floor(a + 0.5);
}

/* A virtual texture over the scene with S-pixel tiles, border and budget
 * as in rs_vt_options (0: defaults); NULL (a failed check) when refused. */
static rs_vt *vt_make(rs_ctx *ctx, const scene *sc, uint32_t S, int32_t border, uint64_t budget)
{
    rs_vt *vt = NULL;
    rs_vt_options vo;
    memset(&vo, 0, sizeof vo);
    vo.tile_size = S;
    vo.border = border;
    vo.budget_bytes = budget;
    vo.roads = sc->roads; /* the scene is styled: coarser levels build their own grids */
    CHECK(rs_vt_create(ctx, sc->s, &vo, &vt) == RS_OK && vt);
    return vt;
}

static void test_tiles(rs_ctx *ctx, scene *sc, fail_alloc *cnt)
{
    rs_vt *vt = vt_make(ctx, sc, 32, 3, 0);
    if (!vt) return;
    rs_vt_info in;
    rs_vt_get_info(vt, &in);
    CHECK_EQ_INT(in.levels, 5); /* 480 px: 32-px tiles until the level fits one tile (30 px) */
    CHECK_EQ_INT(in.tile_side, 38);
    rs_vt_workspace *ws = NULL;
    CHECK(rs_vt_workspace_create(ctx, vt, &ws) == RS_OK && ws);
    if (!ws) {
        rs_vt_free(ctx, vt);
        return;
    }
    const uint32_t n = in.tile_side, B = in.border, S = in.tile_size;
    uint8_t *tile = malloc((size_t)n * n * 4);
    size_t allocs = 0, tiles = 0;
    for (uint32_t k = 0; k < in.levels && tile; k++) {
        uint32_t t = (TEX % (1u << k)) == 0 ? (uint32_t)TEX >> k : ((uint32_t)TEX + (1u << k) - 1) >> k;
        if (t < 1) t = 1;
        uint32_t W, H, lw, lh;
        uint8_t *img = whole(ctx, sc, t, &W, &H);
        CHECK(img != NULL);
        CHECK(rs_vt_level_size(vt, k, &lw, &lh, NULL) == RS_OK);
        if (!img) continue;
        int direct = (TEX % (1u << k)) == 0;
        size_t same = 0, px = 0, off = 0;
        for (uint32_t ty = 0; ty * S < lh; ty++)
            for (uint32_t tx = 0; tx * S < lw; tx++) {
                size_t before = calls(cnt);
                rs_result r = rs_vt_make_tile(ctx, vt, ws, k, tx, ty, tile, (size_t)n * 4);
                allocs += calls(cnt) - before;
                tiles++;
                if (r != RS_OK) continue;
                for (uint32_t j = 0; j < n; j++)
                    for (uint32_t i = 0; i < n; i++) {
                        long X = (long)tx * S + i - B, Y = (long)ty * S + j - B;
                        uint8_t ref[4] = { 0, 0, 0, 0 };
                        if (direct) {
                            if (X >= 0 && Y >= 0 && X < (long)W && Y < (long)H)
                                memcpy(ref, img + ((size_t)Y * W + X) * 4, 4);
                        } else reference_pixel(img, W, H, t, k, X, Y, ref);
                        const uint8_t *got = tile + ((size_t)j * n + i) * 4;
                        px++;
                        if (!memcmp(got, ref, 4)) same++;
                        else if (!direct) {
                            int d = 0;
                            for (int c = 0; c < 4; c++) d = abs(got[c] - ref[c]) > d ? abs(got[c] - ref[c]) : d;
                            off += d > 1; /* the reference's doubles may round a half the other way */
                        }
                    }
            }
        if (direct)
            CHECKF(same == px, "level %u (%u texels): %zu of %zu tile pixels equal rs_splat's, borders included", k, t,
                   same, px);
        else
            CHECKF(off == 0 && same * 10 > px * 9,
                   "level %u: %zu of %zu pixels equal the box average of the %u-texel splat, %zu off by more than 1", k,
                   same, px, t, off);
        free(img);
    }
    CHECKF(allocs == 0, "%zu allocations making %zu tiles", allocs, tiles);
    /* misuse */
    CHECK(rs_vt_make_tile(ctx, vt, ws, in.levels, 0, 0, tile, (size_t)n * 4) == RS_ERR_INVALID_ARG);
    CHECK(rs_vt_make_tile(ctx, vt, ws, 0, 15, 0, tile, (size_t)n * 4) == RS_ERR_INVALID_ARG);
    CHECK(rs_vt_make_tile(ctx, vt, ws, 0, 0, 0, tile, (size_t)n * 4 - 1) == RS_ERR_INVALID_ARG);
    rs_vt *other = vt_make(ctx, sc, 32, 3, 0);
    CHECK(rs_vt_make_tile(ctx, other, ws, 0, 0, 0, tile, (size_t)n * 4) == RS_ERR_INVALID_ARG);
    rs_vt_free(ctx, other);
    free(tile);
    rs_vt_workspace_free(ctx, ws);
    rs_vt_free(ctx, vt);
}

static void test_options(rs_ctx *ctx, scene *sc)
{
    rs_vt *vt = NULL;
    rs_vt_options vo;
    memset(&vo, 0, sizeof vo);
    vo.tile_size = 4;
    CHECK(rs_vt_create(ctx, sc->s, &vo, &vt) == RS_ERR_INVALID_ARG && !vt);
    vo.tile_size = 32;
    vo.border = 17;
    CHECK(rs_vt_create(ctx, sc->s, &vo, &vt) == RS_ERR_INVALID_ARG && !vt);
    vo.border = -1;
    vo.levels = 6;
    CHECK(rs_vt_create(ctx, sc->s, &vo, &vt) == RS_ERR_INVALID_ARG && !vt);
    vo.levels = 2; /* the coarsest level then has 8 x 7 tiles of 4 KiB */
    vo.budget_bytes = 56 * 4096;
    /* a styled grid's coarser level needs the roads for a grid of its own */
    CHECK(rs_vt_create(ctx, sc->s, &vo, &vt) == RS_ERR_INVALID_ARG && !vt &&
          strstr(rs_ctx_message(ctx), "rs_vt_options.roads") != NULL);
    vo.roads = sc->roads;
    vo.budget_bytes = 55 * 4096;
    CHECK(rs_vt_create(ctx, sc->s, &vo, &vt) == RS_ERR_INVALID_ARG && !vt);
    vo.budget_bytes = 56 * 4096;
    CHECK(rs_vt_create(ctx, sc->s, &vo, &vt) == RS_OK && vt);
    rs_vt_info in;
    rs_vt_get_info(vt, &in);
    CHECK(in.border == 0 && in.tile_side == 32 && in.slots == 56 && in.levels == 2);
    rs_vt_free(ctx, vt);
    vt = NULL;
    /* alpha-map grids cannot be re-rendered at other texel counts */
    rs_splat_options o = sc->o;
    o.coverage.edges = RS_EDGES_ALPHAMAP;
    rs_splatter *s = NULL;
    CHECK(rs_splatter_create(ctx, sc->dem, sc->roads, NULL, &o, &s) == RS_OK);
    CHECK(rs_vt_create(ctx, s, NULL, &vt) == RS_ERR_UNSUPPORTED && !vt);
    rs_splatter_free(ctx, s);
    /* defaults (but the roads) */
    memset(&vo, 0, sizeof vo);
    vo.roads = sc->roads;
    CHECK(rs_vt_create(ctx, sc->s, &vo, &vt) == RS_OK);
    rs_vt_get_info(vt, &in);
    CHECK(in.tile_size == 256 && in.border == 4 && in.budget_bytes == (uint64_t)256 << 20 && in.levels == 2);
    rs_vt_view v;
    memset(&v, 0, sizeof v);
    v.eye[2] = 10;
    CHECK(rs_vt_update(ctx, vt, &v) == RS_ERR_INVALID_ARG); /* dir 0 */
    v.dir[0] = 1;
    v.fov_y = 180;
    CHECK(rs_vt_update(ctx, vt, &v) == RS_ERR_INVALID_ARG);
    v.fov_y = 0;
    v.anisotropy = 0.5;
    CHECK(rs_vt_update(ctx, vt, &v) == RS_ERR_INVALID_ARG);
    v.anisotropy = 0;
    CHECK(rs_vt_update(ctx, vt, &v) == RS_OK);
    rs_vt_free(ctx, vt);
}

/* Height of the terrain (bilinear between samples) at (x, y) metres. */
static double ground(const scene *sc, double x, double y)
{
    if (x < 0) x = 0;
    if (y < 0) y = 0;
    if (x > DW - 1) x = DW - 1;
    if (y > DH - 1) y = DH - 1;
    int i = (int)x < DW - 1 ? (int)x : DW - 2, j = (int)y < DH - 1 ? (int)y : DH - 2;
    double fx = x - i, fy = y - j;
    const float *z = sc->z + (size_t)j * DW + i;
    return (z[0] * (1 - fx) + z[1] * fx) * (1 - fy) + (z[DW] * (1 - fx) + z[DW + 1] * fx) * fy;
}

/* The needed tile whose core holds ground point (x, y), or NULL. */
static const rs_vt_tile *covering(const rs_vt_tile *need, size_t nn, double x, double y)
{
    for (size_t i = 0; i < nn; i++)
        if (x >= need[i].x0 && x < need[i].x1 && y >= need[i].y0 && y < need[i].y1) return &need[i];
    return NULL;
}

/* Level the rule asks for at distance d (anisotropy 1). */
static int point_level(double d, double fov, double hpx, double tp, int bias, int levels)
{
    double P = (1.0 / TEX) * hpx / (2 * tan(fov * 3.14159265358979323846 / 360)) / d;
    double L = floor(log2(tp / P)) + bias;
    return L < 0 ? 0 : L > levels - 1 ? levels - 1 : (int)L;
}

static void test_monotone(rs_ctx *ctx, scene *sc)
{
    rs_vt *vt = vt_make(ctx, sc, 16, 0, 0);
    if (!vt) return;
    rs_vt_info in;
    rs_vt_get_info(vt, &in);
    /* eyes receding from a ground point along rays, looking at it: the
     * level of the tile over it never gets finer */
    const double pts[3][2] = { { 20.5, 18.25 }, { 3.1, 33.7 }, { 38.9, 2.2 } };
    const double dirs[3][3] = { { 0.3, 0.2, 0.9 }, { -0.7, 0.1, 0.2 }, { 0.5, -0.6, 0.05 } };
    int bad = 0, checked = 0, levels_seen = 0, last_level = -1;
    for (int p = 0; p < 3; p++)
        for (int d = 0; d < 3; d++) {
            double gx = pts[p][0], gy = pts[p][1], gz = ground(sc, gx, gy);
            int prev = -1;
            for (int step = 0; step < 60; step++) {
                double t = 0.05 * pow(1.2, step);
                rs_vt_view v;
                memset(&v, 0, sizeof v);
                for (int i = 0; i < 3; i++) {
                    v.eye[i] = (i == 0 ? gx : i == 1 ? gy : gz) + t * dirs[d][i];
                    v.dir[i] = -dirs[d][i];
                }
                v.width = 640;
                v.height = 360;
                if (rs_vt_update(ctx, vt, &v) != RS_OK) {
                    bad++;
                    continue;
                }
                size_t nn;
                const rs_vt_tile *need = rs_vt_needed(vt, &nn);
                const rs_vt_tile *c = covering(need, nn, gx, gy);
                if (!c) {
                    bad++;
                    continue;
                }
                checked++;
                if ((int)c->level < prev) bad++;
                if ((int)c->level != last_level) levels_seen++;
                last_level = (int)c->level;
                prev = (int)c->level;
            }
        }
    CHECKF(bad == 0 && checked == 540, "%d of %d receding views chose a finer level (or none) over the point", bad,
           checked);
    CHECKF(levels_seen >= 9 * 3, "the receding views went through %d level changes", levels_seen);
    /* the rule itself: a needed tile's texel projects to at most texel_pixels
     * at its nearest distance; its parent's did not (unless at the top) */
    rs_vt_view v;
    memset(&v, 0, sizeof v);
    v.eye[0] = -5;
    v.eye[1] = 18;
    v.eye[2] = 4;
    v.dir[0] = 1;
    v.dir[2] = -0.15;
    v.height = 720;
    CHECK(rs_vt_update(ctx, vt, &v) == RS_OK);
    size_t nn;
    const rs_vt_tile *need = rs_vt_needed(vt, &nn);
    int rule = 0;
    for (size_t i = 0; i < nn; i++) {
        int want = point_level(need[i].dist, 60, 720, 1, 0, (int)in.levels);
        rule += (int)need[i].level > want;
    }
    CHECKF(nn > 4 && rule == 0, "%d of %zu needed tiles coarser than their nearest distance allows", rule, nn);
    /* the view angle: a grazing view needs no finer tiles for an isotropic
     * sampler (A = 1) than for a 16-fold anisotropic one, nor for that than
     * with the angle ignored (A = 0) */
    size_t count[3];
    double level_sum[3];
    const double an[3] = { 1, 16, 0 };
    v.eye[2] = 1.2;
    v.dir[2] = -0.05;
    for (int i = 0; i < 3; i++) {
        v.anisotropy = an[i];
        CHECK(rs_vt_update(ctx, vt, &v) == RS_OK);
        need = rs_vt_needed(vt, &count[i]);
        level_sum[i] = 0;
        for (size_t k = 0; k < count[i]; k++) level_sum[i] += need[k].level;
    }
    CHECKF(count[0] < count[1] && count[1] <= count[2] && level_sum[0] / count[0] > level_sum[2] / count[2],
           "grazing view: %zu tiles isotropic (mean level %.2f), %zu with 16x, %zu ignoring the angle (mean %.2f)",
           count[0], level_sum[0] / count[0], count[1], count[2], level_sum[2] / count[2]);
    rs_vt_free(ctx, vt);
}

typedef struct host_set {
    uint8_t *used;   /* per slot */
    uint64_t *key;   /* per slot */
    uint32_t count;
} host_set;

static uint64_t hkey(const rs_vt_tile *t) { return (uint64_t)t->level << 58 | (uint64_t)t->x << 29 | t->y; }

/* A flythrough: a low eye circling over the map, looking outwards and
 * down, with `budget` bytes; records every list into `log` (may be NULL)
 * and checks the host-side bookkeeping, the budget and the coverage. */
static void flythrough(rs_ctx *ctx, scene *sc, uint64_t budget, uint32_t max_make, uint64_t *log, size_t *nlog,
                       fail_alloc *cnt, int check_cover)
{
    rs_vt *vt = vt_make(ctx, sc, 16, 2, budget);
    if (!vt) return;
    rs_vt_info in;
    rs_vt_get_info(vt, &in);
    host_set hs;
    hs.used = calloc(in.slots, 1);
    hs.key = calloc(in.slots, sizeof *hs.key);
    hs.count = 0;
    int bad_drop = 0, bad_make = 0, over = 0, unresident = 0, uncovered = 0, too_coarse = 0, hits = 0, biased = 0;
    size_t allocs = 0, drops = 0;
    *nlog = 0;
    for (int f = 0; f < 120 && hs.used && hs.key; f++) {
        double a = f * 0.07;
        rs_vt_view v;
        memset(&v, 0, sizeof v);
        v.eye[0] = 20 + 14 * cos(a);
        v.eye[1] = 18 + 12 * sin(a);
        v.eye[2] = ground(sc, v.eye[0], v.eye[1]) + 1.5 + (f % 40) * 0.2;
        v.dir[0] = cos(a + 1.2);
        v.dir[1] = sin(a + 1.2);
        v.dir[2] = -0.25;
        v.width = 320;
        v.height = 180;
        v.max_make = max_make;
        size_t before = calls(cnt);
        if (rs_vt_update(ctx, vt, &v) != RS_OK) {
            over++;
            continue;
        }
        allocs += calls(cnt) - before;
        size_t nd, nm, nn;
        const rs_vt_tile *drop = rs_vt_to_drop(vt, &nd), *make = rs_vt_to_make(vt, &nm), *need = rs_vt_needed(vt, &nn);
        drops += nd;
        for (size_t i = 0; i < nd; i++) {
            if (drop[i].slot >= in.slots || !hs.used[drop[i].slot] || hs.key[drop[i].slot] != hkey(&drop[i])) bad_drop++;
            else {
                hs.used[drop[i].slot] = 0;
                hs.count--;
            }
            if (log) log[(*nlog)++] = hkey(&drop[i]) ^ ((uint64_t)drop[i].slot << 40) ^ 0x5555;
        }
        for (size_t i = 0; i < nm; i++) {
            if (make[i].slot >= in.slots || hs.used[make[i].slot]) bad_make++;
            else {
                hs.used[make[i].slot] = 1;
                hs.key[make[i].slot] = hkey(&make[i]);
                hs.count++;
            }
            if (log) log[(*nlog)++] = hkey(&make[i]) ^ ((uint64_t)make[i].slot << 40);
        }
        rs_vt_stats st;
        rs_vt_get_stats(vt, &st);
        if (st.resident != hs.count || st.resident_bytes > in.budget_bytes || hs.count > in.slots) over++;
        biased += st.bias > 0;
        if (max_make) continue;
        for (size_t i = 0; i < nn; i++)
            if (need[i].slot >= in.slots || !hs.used[need[i].slot] || hs.key[need[i].slot] != hkey(&need[i])) unresident++;
        if (!check_cover) continue;
        /* rays through a grid of screen pixels onto the terrain */
        double f3[3] = { v.dir[0], v.dir[1], v.dir[2] }, fl = sqrt(f3[0] * f3[0] + f3[1] * f3[1] + f3[2] * f3[2]);
        for (int i = 0; i < 3; i++) f3[i] /= fl;
        double hl = sqrt(f3[0] * f3[0] + f3[1] * f3[1]);
        double rt[3] = { f3[1] / hl, -f3[0] / hl, 0 };
        double up[3] = { rt[1] * f3[2] - rt[2] * f3[1], rt[2] * f3[0] - rt[0] * f3[2], rt[0] * f3[1] - rt[1] * f3[0] };
        double ty = tan(30 * 3.14159265358979323846 / 180), tx = ty * 320 / 180;
        for (int sy = 0; sy < 18; sy++)
            for (int sx = 0; sx < 32; sx++) {
                double u = ((sx + 0.5) / 32 * 2 - 1) * tx, w = (1 - (sy + 0.5) / 18 * 2) * ty;
                double r[3];
                for (int i = 0; i < 3; i++) r[i] = f3[i] + u * rt[i] + w * up[i];
                double rl = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
                for (int i = 0; i < 3; i++) r[i] /= rl;
                for (double t = 0.01; t < 200; t += 0.01 + t * 0.002) {
                    double p[3] = { v.eye[0] + t * r[0], v.eye[1] + t * r[1], v.eye[2] + t * r[2] };
                    if (p[0] < 0 || p[1] < 0 || p[0] >= DW - 1 || p[1] >= DH - 1) {
                        if (p[2] < -50) break;
                        continue;
                    }
                    if (p[2] > ground(sc, p[0], p[1])) continue;
                    hits++;
                    const rs_vt_tile *c = covering(need, nn, p[0], p[1]);
                    if (!c || c->slot >= in.slots || !hs.used[c->slot]) uncovered++;
                    else if ((int)c->level > point_level(t, 60, 180, 1, (int)st.bias, (int)in.levels)) too_coarse++;
                    break;
                }
            }
    }
    CHECKF(bad_drop == 0 && bad_make == 0, "budget %llu: %d drops of tiles not resident, %d makes into used slots",
           (unsigned long long)budget, bad_drop, bad_make);
    CHECKF(over == 0, "budget %llu: %d frames with the resident set over the budget or off the host's count",
           (unsigned long long)budget, over);
    CHECKF(allocs == 0, "%zu allocations in 120 updates", allocs);
    if (!max_make) CHECKF(unresident == 0, "%d needed tiles not resident after their update", unresident);
    if (check_cover)
        CHECKF(hits > 1000 && uncovered == 0 && too_coarse == 0,
               "budget %llu: %d of %d visible ground points under no resident needed tile, %d under a coarser one "
               "than they ask for (%d biased frames)",
               (unsigned long long)budget, uncovered, hits, too_coarse, biased);
    if (budget) CHECKF(drops > 0, "budget %llu: nothing dropped in 120 frames", (unsigned long long)budget);
    if (budget == 8 * 400 * 4) CHECKF(biased > 0, "the small budget never coarsened the cut");
    free(hs.used);
    free(hs.key);
    rs_vt_free(ctx, vt);
}

typedef struct make_job {
    const rs_vt *vt;
    uint32_t k, x, y, n;
    uint8_t *out;
    int bad;
} make_job;

static void *make_thread(void *arg)
{
    make_job *j = arg;
    rs_ctx *c = NULL;
    rs_vt_workspace *ws = NULL;
    j->bad = rs_ctx_create(NULL, NULL, &c) || rs_vt_workspace_create(c, j->vt, &ws);
    for (uint32_t i = 0; !j->bad && i < 3; i++)
        j->bad = rs_vt_make_tile(c, j->vt, ws, j->k, j->x, j->y, j->out, (size_t)j->n * 4) != RS_OK;
    rs_vt_workspace_free(c, ws);
    rs_ctx_free(c);
    return NULL;
}

static void test_determinism(rs_ctx *ctx, scene *sc, fail_alloc *cnt)
{
    size_t cap = 1 << 20, n1 = 0, n2 = 0;
    uint64_t *l1 = malloc(cap * sizeof *l1), *l2 = malloc(cap * sizeof *l2);
    if (!l1 || !l2) return;
    flythrough(ctx, sc, 20 * 400 * 4, 0, l1, &n1, cnt, 0);
    flythrough(ctx, sc, 20 * 400 * 4, 0, l2, &n2, cnt, 0);
    CHECKF(n1 > 100 && n1 == n2 && !memcmp(l1, l2, n1 * sizeof *l1), "two runs of the same views: %zu and %zu list "
                                                                          "entries, same: %d", n1, n2,
           n1 == n2 && !memcmp(l1, l2, n1 * sizeof *l1));
    free(l1);
    free(l2);
    /* the same tiles made on two threads at once and on this one */
    rs_vt *vt = vt_make(ctx, sc, 24, 0, 0);
    if (!vt) return;
    rs_vt_info in;
    rs_vt_get_info(vt, &in);
    const uint32_t tiles[3][3] = { { 0, 7, 5 }, { 2, 2, 1 }, { 3, 0, 1 } };
    int same = 0;
    for (int t = 0; t < 3; t++) {
        make_job j[2];
        pthread_t th[2];
        size_t sz = (size_t)in.tile_side * in.tile_side * 4;
        uint8_t *ref = malloc(sz);
        for (int i = 0; i < 2; i++) {
            j[i].vt = vt;
            j[i].k = tiles[t][0];
            j[i].x = tiles[t][1];
            j[i].y = tiles[t][2];
            j[i].n = in.tile_side;
            j[i].out = malloc(sz);
            pthread_create(&th[i], NULL, make_thread, &j[i]);
        }
        rs_vt_workspace *ws = NULL;
        int ok = ref && rs_vt_workspace_create(ctx, vt, &ws) == RS_OK &&
                 rs_vt_make_tile(ctx, vt, ws, tiles[t][0], tiles[t][1], tiles[t][2], ref, (size_t)in.tile_side * 4) ==
                     RS_OK;
        for (int i = 0; i < 2; i++) pthread_join(th[i], NULL);
        same += ok && !j[0].bad && !j[1].bad && j[0].out && j[1].out && !memcmp(ref, j[0].out, sz) &&
                !memcmp(ref, j[1].out, sz);
        rs_vt_workspace_free(ctx, ws);
        free(ref);
        free(j[0].out);
        free(j[1].out);
    }
    CHECKF(same == 3, "%d of 3 tiles made on two threads at once equal this thread's", same);
    rs_vt_free(ctx, vt);
}

/* Every allocation of create, workspace, update and make failing in turn:
 * RS_ERR_NOMEM and nothing left behind. */
static rs_result sweep_try(rs_ctx *c, void *user, int *wrong)
{
    const scene *sc = user;
    rs_vt *vt = NULL;
    rs_vt_workspace *ws = NULL;
    rs_vt_options vo;
    memset(&vo, 0, sizeof vo);
    vo.tile_size = 32;
    vo.roads = sc->roads;
    rs_result r = rs_vt_create(c, sc->s, &vo, &vt);
    if (r) {
        *wrong = vt != NULL;
        return r;
    }
    r = rs_vt_workspace_create(c, vt, &ws);
    *wrong = r && ws != NULL;
    rs_vt_view v;
    memset(&v, 0, sizeof v);
    v.eye[0] = 20;
    v.eye[1] = 18;
    v.eye[2] = 10;
    v.dir[2] = -1;
    if (!r) r = rs_vt_update(c, vt, &v);
    uint8_t tile[40 * 40 * 4];
    if (!r) r = rs_vt_make_tile(c, vt, ws, 4, 0, 0, tile, sizeof tile / 40);
    rs_vt_workspace_free(c, ws);
    rs_vt_free(c, vt);
    return r;
}

static void test_lookup_discard(rs_ctx *ctx, scene *sc)
{
    rs_vt *vt = vt_make(ctx, sc, 16, 0, 0);
    if (!vt) return;
    rs_vt_view v;
    memset(&v, 0, sizeof v);
    v.eye[0] = 20;
    v.eye[1] = 18;
    v.eye[2] = 12;
    v.dir[2] = -1; /* straight down */
    CHECK(rs_vt_update(ctx, vt, &v) == RS_OK);
    size_t nn, nm;
    const rs_vt_tile *need = rs_vt_needed(vt, &nn);
    rs_vt_to_make(vt, &nm);
    CHECK(nn > 0 && nm == nn);
    rs_vt_tile t = need[0], got;
    CHECK(rs_vt_lookup(vt, t.level, t.x, t.y, &got) == 1 && got.level == t.level && got.slot == t.slot);
    if (t.level > 0) CHECK(rs_vt_lookup(vt, t.level - 1, 2 * t.x, 2 * t.y, &got) == 1 && got.level == t.level);
    CHECK(rs_vt_discard(ctx, vt, t.level, t.x, t.y) == RS_OK);
    CHECK(rs_vt_discard(ctx, vt, t.level, t.x, t.y) == RS_ERR_INVALID_ARG);
    CHECK(rs_vt_update(ctx, vt, &v) == RS_OK);
    const rs_vt_tile *make = rs_vt_to_make(vt, &nm);
    CHECK(nm == 1 && make[0].level == t.level && make[0].x == t.x && make[0].y == t.y);
    rs_vt_free(ctx, vt);
}

/* A direct level's tile on the city (1000 roads) against a splatter built
 * from the roads at that level's texels: byte for byte. The level's
 * splatter shares the grid made for 100 texels; until its road field was
 * indexed anew for the coarser pixels (rs__roadfield_repixel), the cells-
 * around search gave 4 bytes of this tile a different rounding. */
static void test_city_direct_level(void)
{
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_pixels = (uint64_t)1 << 40;
    rs_ctx *ctx = NULL;
    sc_scene sc;
    if (!CHECK(rs_ctx_create(NULL, &lim, &ctx) == RS_OK)) return;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    CHECK(ss_city(ctx, &sc, &dem, &roads) == 0);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 100;
    rs_splatter *s = NULL, *f = NULL;
    rs_vt *vt = NULL;
    rs_vt_workspace *ws = NULL;
    rs_vt_options vo;
    memset(&vo, 0, sizeof vo);
    vo.tile_size = 256;
    int ok = CHECK(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK && rs_vt_create(ctx, s, &vo, &vt) == RS_OK &&
                   rs_vt_workspace_create(ctx, vt, &ws) == RS_OK);
    o.texels = 50;
    ok = ok && CHECK(rs_splatter_create(ctx, dem, roads, NULL, &o, &f) == RS_OK);
    uint8_t *tile = malloc(264 * 264 * 4), *ref = malloc(264 * 264 * 4);
    if (ok && tile && ref) {
        CHECK(rs_vt_make_tile(ctx, vt, ws, 1, 48, 38, tile, 264 * 4) == RS_OK);
        CHECK(rs_splat_window(ctx, f, 48 * 256 - 4, 38 * 256 - 4, 264, 264, ref, 264 * 4, NULL, 0, NULL) == RS_OK);
        size_t d = 0;
        for (size_t i = 0; i < 264 * 264 * 4; i++) d += tile[i] != ref[i];
        CHECKF(d == 0, "city level 1 tile (48, 38): %zu bytes differ from the 50-texel splatter's window", d);
    }
    free(tile);
    free(ref);
    rs_splatter_free(ctx, f);
    rs_vt_workspace_free(ctx, ws);
    rs_vt_free(ctx, vt);
    rs_splatter_free(ctx, s);
    rs_dem_free(ctx, dem);
    rs_roads_free(ctx, roads);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
}

int main(void)
{
    fail_alloc cnt = { LONG_MAX, 0 };
    rs_allocator al = fail_alloc_hook(&cnt);
    rs_ctx *ctx = NULL;
    scene sc;
    if (rs_ctx_create(&al, NULL, &ctx) || scene_make(ctx, &sc)) {
        fprintf(stderr, "test_vt: setup failed: %s\n", ctx ? rs_ctx_message(ctx) : "");
        return 1;
    }
    test_options(ctx, &sc);
    test_tiles(ctx, &sc, &cnt);
    test_monotone(ctx, &sc);
    size_t nlog;
    flythrough(ctx, &sc, 0, 0, NULL, &nlog, &cnt, 1);                 /* everything fits */
    flythrough(ctx, &sc, 40 * 400 * 4, 0, NULL, &nlog, &cnt, 1);      /* 40 tiles: LRU drops */
    flythrough(ctx, &sc, 8 * 400 * 4, 0, NULL, &nlog, &cnt, 1);       /* 8 tiles: the cut coarsened */
    flythrough(ctx, &sc, 40 * 400 * 4, 3, NULL, &nlog, &cnt, 0);      /* at most 3 made per frame */
    test_determinism(ctx, &sc, &cnt);
    test_lookup_discard(ctx, &sc);
    test_city_direct_level();
    fail_sweep fs = fail_alloc_sweep(6000, sweep_try, &sc);
    CHECK_SWEEP(fs, 10);
    scene_free(ctx, &sc);
    rs_ctx_free(ctx);
    return th_finish("test_vt");
}
