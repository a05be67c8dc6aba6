/* Surface stage: tiled textures against a plain per-pixel reference.
 *
 * The textured surface path works two pixels at a time (four with AVX2,
 * where a group of four with a wrap takes its texels by gathers) and keeps
 * the texture's column coordinates for the whole window (lib/splat/surface.c); this
 * test recomputes the pixels one at a time from the documented sampler -
 * wrapped bilinear, doubles in the order below, rounded to float, blended
 * by the road weight, rounded to a byte -
 * over windows wider than a piece, at odd offsets and widths, with
 * textures of power-of-two and other sizes, magnified and minified. */
#include "harness.h"
#include "roadsplat.h"
#include "splatter.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;

/* Texel pair and weight of pixel p along one axis of an image of S texels
 * per repeat of `scale` metres. */
static void axis_ref(uint32_t p, double texel_m, double scale, uint32_t S, uint32_t *i0, uint32_t *i1, double *f)
{
    double u = (p + 0.5) * texel_m / scale;
    u = (u - floor(u)) * S - 0.5;
    double fu = floor(u);
    *f = u - fu;
    long long x = (long long)fu, n = S;
    x = ((x % n) + n) % n;
    *i0 = (uint32_t)x;
    *i1 = (uint32_t)((x + 1) % n);
}

static uint8_t to_byte(double v)
{
    return (uint8_t)(v >= 0 ? (v >= 255 ? 255 : v + 0.5) : 0);
}

/* Reference colour channel c of a tiled image at output pixel (px, py), as
 * the float the composite reads. */
static float texel_ref(const rs_image *img, double texel_m, double scale, uint32_t px, uint32_t py, int c)
{
    uint32_t x0, x1, y0, y1;
    double au, av;
    axis_ref(px, texel_m, scale, img->width, &x0, &x1, &au);
    axis_ref(py, texel_m, scale, img->height, &y0, &y1, &av);
    const double bu = 1 - au, bv = 1 - av;
    const uint8_t *t = img->rgba;
    const size_t W = img->width;
    return (float)((t[4 * (y0 * W + x0) + c] * bu + t[4 * (y0 * W + x1) + c] * au) * bv +
                   (t[4 * (y1 * W + x0) + c] * bu + t[4 * (y1 * W + x1) + c] * au) * av);
}

static void fill_texture(uint8_t *t, size_t n, uint32_t seed)
{
    uint32_t h = seed;
    for (size_t i = 0; i < n; i++) {
        h = h * 1664525u + 1013904223u;
        t[i] = (uint8_t)(h >> 24);
    }
}

/* One window [x0, x0 + w) x [y0, y0 + h) of a splat, checked pixel by pixel
 * where the reference knows the colour: pure terrain and pure road pixels
 * whose texture is set, and with both textures the blended ones, C = (1 -
 * R) T + R S (the composite's formula). Returns the number of channels that
 * differ and counts the pixels checked. */
static long check_window(const rs_splatter *s, const rs_splat_options *o, double texel_m, uint32_t x0,
                         uint32_t y0, uint32_t w, uint32_t h, long seen[3])
{
    const rs_image *ti = o->surface.terrain_texture, *ri = o->surface.road_texture;
    const double scale = o->surface.texture_scale;
    uint8_t *rgba = malloc((size_t)w * h * 4);
    uint16_t *wt = malloc((size_t)w * h * 2);
    long bad = -1;
    if (!rgba || !wt) goto done;
    if (rs_splat_window(ctx, s, x0, y0, w, h, rgba, (size_t)w * 4, wt, w, NULL) != RS_OK) goto done;
    bad = 0;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            const uint32_t q = wt[i];
            const int kind = q == 0 ? 0 : (q == 65535u ? 1 : 2);
            if (!(kind == 0 ? ti != NULL : (kind == 1 ? ri != NULL : ti && ri))) continue;
            seen[kind]++;
            for (int c = 0; c < 3; c++) {
                double v;
                if (kind == 0) v = texel_ref(ti, texel_m, scale, x0 + x, y0 + y, c);
                else if (kind == 1) v = texel_ref(ri, texel_m, scale, x0 + x, y0 + y, c);
                else {
                    double r = q / 65535.0;
                    v = (1 - r) * texel_ref(ti, texel_m, scale, x0 + x, y0 + y, c) +
                        r * texel_ref(ri, texel_m, scale, x0 + x, y0 + y, c);
                }
                if (rgba[4 * i + c] != to_byte(v)) bad++;
            }
            if (rgba[4 * i + 3] != 255) bad++;
        }
done:
    free(rgba);
    free(wt);
    return bad;
}

static void test_textures_reference(void)
{
    /* 300 x 7 samples, 2 m cells, 8 texels: 2392 x 48 pixels of 0.25 m, so
     * a whole row is two pieces */
    const uint32_t DW = 300, DH = 7, T = 8;
    const double cell = 2, texel_m = cell / T;
    float *z = malloc(sizeof(float) * DW * DH);
    for (uint32_t i = 0; i < DW * DH; i++) z[i] = (float)((i * 7919u) % 13);
    rs_dem *dem = NULL;
    rs_dem_frame fr = { cell, 1, 0, 0 };
    CHECK(rs_dem_create(ctx, DW, DH, z, &dem) == RS_OK && rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    free(z);
    /* a slanted road, 2.5 m wide, across the whole map */
    rs_roads *roads = NULL;
    double xy[4] = { -10, 3, 610, 9 };
    CHECK(rs_roads_create(ctx, &roads) == RS_OK && rs_roads_add(ctx, roads, "r", 2.5, xy, 2) == RS_OK);
    static uint8_t ta[37 * 23 * 4], tb[16 * 8 * 4], tc[1 * 5 * 4];
    fill_texture(ta, sizeof ta, 1);
    fill_texture(tb, sizeof tb, 2);
    fill_texture(tc, sizeof tc, 3);
    rs_image ia = { 37, 23, ta }, ib = { 16, 8, tb }, ic = { 1, 5, tc };
    const struct {
        const rs_image *terrain, *road;
        double scale;
    } cases[] = {
        { &ia, NULL, 1.3 },  /* minified: about 7 texels per pixel, wrapping every 5 pixels */
        { &ia, &ib, 40 },    /* magnified */
        { &ib, &ia, 3.7 },
        { NULL, &ib, 0.9 },  /* road texture only, procedural terrain */
        { &ic, &ib, 2.1 },   /* one texel wide: every pixel's texel pair wraps */
    };
    static const uint32_t win[][4] = { { 0, 0, 2392, 48 }, { 333, 5, 2049, 17 }, { 1, 9, 2391, 3 },
                                       { 2047, 40, 3, 8 }, { 2391, 0, 1, 48 } };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.texels = T;
        o.surface.terrain_texture = cases[c].terrain;
        o.surface.road_texture = cases[c].road;
        o.surface.texture_scale = cases[c].scale;
        rs_splatter *s = NULL;
        CHECK(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK);
        if (!s) continue;
        uint32_t w, h;
        rs_splatter_size(s, &w, &h);
        CHECK_EQ_INT(w, 2392);
        long seen[3] = { 0, 0, 0 };
        for (size_t k = 0; k < sizeof win / sizeof win[0]; k++) {
            long bad = check_window(s, &o, texel_m, win[k][0], win[k][1], win[k][2], win[k][3], seen);
            CHECKF(bad == 0, "case %zu window %zu: %ld channels differ from the reference", c, k, bad);
        }
        /* every kind of pixel was there to check */
        const rs_image *ti = o.surface.terrain_texture, *ri = o.surface.road_texture;
        CHECKF(!ti || seen[0] > 100000, "case %zu: %ld terrain pixels", c, seen[0]);
        CHECKF(!ri || seen[1] > 10000, "case %zu: %ld road pixels", c, seen[1]);
        CHECKF(!(ti && ri) || seen[2] > 5000, "case %zu: %ld blended pixels", c, seen[2]);
        rs_splatter_free(ctx, s);
    }
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
}

/* The composite's byte of a pure terrain or road pixel (lib/splat/composite.c
 * takes four in float with SSE2) against the scalar rule in double,
 * (uint8)(v + 0.5) clamped to 0..255 (NaN: 0), on the floats where a float
 * sum could round differently (0.49999997 + 0.5 rounds to 1 in float),
 * the clamps, NaN and infinities, and random values. */
static void test_composite_bytes(void)
{
    enum { W = 64 };
    float tc[3 * W], sc[3 * W];
    uint16_t q[W];
    double cov[W];
    uint8_t rgba[4 * W];
    const float special[] = { 0.0f, -0.0f, 0.49999997f, 0.5f, 0.50000006f, 1.4999999f, 1.5f, 2.4999998f, 127.49999f,
                              127.5f, 254.49998f, 254.5f, 254.50002f, 255.0f, 255.49998f, 255.5f, 256.0f, 1e30f,
                              -0.5f, -0.50000006f, -1e30f, (float)NAN, (float)INFINITY, -(float)INFINITY, 1e-30f,
                              -1e-30f, 0.99999994f, 3.5f };
    const size_t ns = sizeof special / sizeof special[0];
    uint32_t rng = 12345;
    int bad = 0;
    for (int round = 0; round < 200; round++) {
        for (size_t i = 0; i < 3 * W; i++) {
            rng = rng * 1664525u + 1013904223u;
            float v = round < 20 ? special[(i + (size_t)round) % ns] : (float)((rng >> 8) * (1.0 / 16777216.0) * 260.0 - 2.0);
            tc[i] = v;
            sc[i] = special[(i * 7 + (size_t)round) % ns];
        }
        for (size_t k = 0; k < W; k++) {
            q[k] = (k / 8) % 2 ? 65535u : 0;
            cov[k] = q[k] / 65535.0;
        }
        rs__piece p;
        memset(&p, 0, sizeof p);
        p.w = W;
        p.rows = 1;
        p.q = q;
        p.cov = cov;
        p.tc = tc;
        p.sc = sc;
        rs__composite(&p, rgba, sizeof rgba, NULL, 0);
        for (size_t k = 0; k < W; k++)
            for (int ch = 0; ch < 3; ch++) {
                double v = q[k] ? sc[ch * W + k] : tc[ch * W + k];
                uint8_t want = (uint8_t)(v >= 0 ? (v >= 255 ? 255 : v + 0.5) : 0);
                if (rgba[4 * k + ch] != want && bad++ < 5)
                    fprintf(stderr, "    composite of %.9g: %u, want %u\n", v, rgba[4 * k + ch], want);
            }
    }
    CHECK_EQ_INT(bad, 0);
}

int main(void)
{
    CHECK(rs_ctx_create(NULL, NULL, &ctx) == RS_OK);
    test_textures_reference();
    test_composite_bytes();
    rs_ctx_free(ctx);
    return th_finish("test_surface");
}
