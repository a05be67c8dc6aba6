/* Pictures for the docs (docs/images/): the 16 corner-pattern tiles and a
 * side-by-side of a plain per-cell road buffer against the alpha-map splat
 * on a crop of the city scene. Writes uncompressed PNGs itself so that the
 * benchmarks need no image library.  Usage: pictures OUTDIR [IMAGEDIR] */
#include "groundtruth.h"
#include "roadsplat_experimental.h"
#include "scene_splat.h"
#include "scenes.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static uint32_t crc_table[256];

static void crc_init(void)
{
    for (uint32_t n = 0; n < 256; n++) {
        uint32_t c = n;
        for (int k = 0; k < 8; k++) c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        crc_table[n] = c;
    }
}

static uint32_t crc(uint32_t c, const uint8_t *p, size_t n)
{
    for (size_t i = 0; i < n; i++) c = crc_table[(c ^ p[i]) & 0xFF] ^ (c >> 8);
    return c;
}

static void be32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24); p[1] = (uint8_t)(v >> 16); p[2] = (uint8_t)(v >> 8); p[3] = (uint8_t)v;
}

static void chunk(FILE *f, const char *type, const uint8_t *data, uint32_t n)
{
    uint8_t h[8];
    be32(h, n);
    memcpy(h + 4, type, 4);
    fwrite(h, 1, 8, f);
    if (n) fwrite(data, 1, n, f);
    uint32_t c = crc(0xFFFFFFFFu, (const uint8_t *)type, 4);
    c = crc(c, data, n) ^ 0xFFFFFFFFu;
    be32(h, c);
    fwrite(h, 1, 4, f);
}

/* RGB8 PNG with zlib "stored" blocks. */
static int write_png(const char *path, uint32_t w, uint32_t h, const uint8_t *rgb)
{
    size_t raw_n = (size_t)h * (3 * w + 1);
    uint8_t *raw = malloc(raw_n);
    size_t nblocks = raw_n / 65535 + 1, z_n = 2 + raw_n + 5 * nblocks + 4;
    uint8_t *z = malloc(z_n);
    if (!raw || !z) { free(raw); free(z); return -1; }
    for (uint32_t y = 0; y < h; y++) {
        raw[y * (3 * w + 1)] = 0;
        memcpy(raw + y * (3 * w + 1) + 1, rgb + (size_t)y * 3 * w, 3 * w);
    }
    size_t o = 0, i = 0;
    z[o++] = 0x78; z[o++] = 0x01;
    uint32_t a = 1, b = 0;
    for (size_t k = 0; k < raw_n; k++) { a = (a + raw[k]) % 65521; b = (b + a) % 65521; }
    while (i < raw_n || i == 0) {
        size_t len = raw_n - i > 65535 ? 65535 : raw_n - i;
        z[o++] = i + len == raw_n ? 1 : 0;
        z[o++] = (uint8_t)len; z[o++] = (uint8_t)(len >> 8);
        z[o++] = (uint8_t)~len; z[o++] = (uint8_t)(~len >> 8);
        memcpy(z + o, raw + i, len);
        o += len; i += len;
        if (raw_n == 0) break;
    }
    be32(z + o, (b << 16) | a);
    o += 4;
    FILE *f = fopen(path, "wb");
    if (!f) { free(raw); free(z); return -1; }
    static const uint8_t sig[8] = { 137, 80, 78, 71, 13, 10, 26, 10 };
    uint8_t ihdr[13];
    be32(ihdr, w); be32(ihdr + 4, h);
    ihdr[8] = 8; ihdr[9] = 2; ihdr[10] = 0; ihdr[11] = 0; ihdr[12] = 0;
    fwrite(sig, 1, 8, f);
    chunk(f, "IHDR", ihdr, 13);
    chunk(f, "IDAT", z, (uint32_t)o);
    chunk(f, "IEND", NULL, 0);
    int ok = fclose(f) == 0;
    free(raw);
    free(z);
    return ok ? 0 : -1;
}

/* One representative mask per corner pattern (bit0 NE, SE, SW, NW). */
static uint8_t mask_for_pattern(unsigned p)
{
    for (unsigned m = 255;; m--) {
        unsigned q = 0;
        if ((m & 0x07) != 0x07) q |= 1;
        if ((m & 0x1C) != 0x1C) q |= 2;
        if ((m & 0x70) != 0x70) q |= 4;
        if ((m & 0xC1) != 0xC1) q |= 8;
        if (q == p) return (uint8_t)m;
        if (m == 0) return 0;
    }
}

static int tiles_picture(const char *path)
{
    const int S = 96, G = 8, cols = 8, rows = 2;
    uint32_t w = cols * (S + G) + G, h = rows * (S + G) + G;
    uint8_t *img = malloc((size_t)w * h * 3);
    if (!img) return -1;
    memset(img, 255, (size_t)w * h * 3);
    for (unsigned p = 0; p < 16; p++) {
        uint8_t m = mask_for_pattern(p);
        int ox = G + (int)(p % cols) * (S + G), oy = G + (int)(p / cols) * (S + G);
        for (int y = 0; y < S; y++)
            for (int x = 0; x < S; x++) {
                double a = rs_tile_alpha(m, (x + 0.5) / S, (y + 0.5) / S, 2.0 / 32);
                uint8_t *px = img + 3 * ((size_t)(oy + y) * w + ox + x);
                px[0] = (uint8_t)(60 + a * (120 - 60) + 0.5);
                px[1] = (uint8_t)(60 + a * (170 - 60) + 0.5);
                px[2] = (uint8_t)(64 + a * (90 - 64) + 0.5);
            }
    }
    int r = write_png(path, w, h, img);
    free(img);
    return r;
}

/* Left: road buffer on the DEM cells (hard). Right: the alpha-map splat. */
static int compare_picture(const char *path)
{
    sc_scene sc;
    rs_ctx *ctx;
    if (sc_city_default(&sc, 1) || rs_ctx_create(NULL, NULL, &ctx)) return -1;
    rs_dem *dem;
    rs_roads *roads, *none;
    if (rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) || !(roads = ss_roads(ctx, &sc)) || rs_roads_create(ctx, &none))
        return -1;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 8;
    rs_dem_frame fr = { sc.cell_size, 0.01, 0, 0 };
    if (rs_dem_set_frame(ctx, dem, &fr)) return -1;
    uint32_t W, H;
    rs_splat_size(ctx, dem, &o, &W, &H);
    size_t n = (size_t)W * H;
    uint8_t *a = malloc(n * 4), *t = malloc(n * 4);
    uint16_t *wt = malloc(n * 2);
    float *cb = malloc(n * sizeof *cb);
    rs_road_grid *g, *g0;
    if (!a || !t || !wt || !cb || rs_road_grid_build(ctx, dem, roads, &o, &g) || rs_road_grid_build(ctx, dem, none, &o, &g0))
        return -1;
    rs_splat(ctx, dem, g, &o, a, n * 4, wt, n);
    rs_splat(ctx, dem, g0, &o, t, n * 4, NULL, 0);
    gt_cell_buffer(&sc, o.texels, cb);
    /* a 60 x 45 m... crop: 480 x 360 pixels from the map centre */
    const uint32_t cw = 360, ch = 300, x0 = W / 2 - 200, y0 = H / 2 - 150, gap = 8;
    uint32_t ow = 2 * cw + gap;
    uint8_t *img = malloc((size_t)ow * ch * 3);
    if (!img) return -1;
    memset(img, 255, (size_t)ow * ch * 3);
    for (uint32_t y = 0; y < ch; y++)
        for (uint32_t x = 0; x < cw; x++) {
            size_t s = (size_t)(y0 + y) * W + x0 + x;
            /* road colour: the splat's own, where it is full road nearby */
            uint8_t *l = img + 3 * ((size_t)y * ow + x), *r = img + 3 * ((size_t)y * ow + cw + gap + x);
            for (int c = 0; c < 3; c++) {
                double road = 72;
                l[c] = (uint8_t)(cb[s] > 0.5f ? road : t[4 * s + c]);
                r[c] = a[4 * s + c];
            }
        }
    int rc = write_png(path, ow, ch, img);
    free(img); free(a); free(t); free(wt); free(cb);
    rs_road_grid_free(ctx, g);
    rs_road_grid_free(ctx, g0);
    rs_roads_free(ctx, roads);
    rs_roads_free(ctx, none);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    sc_scene_free(&sc);
    return rc;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 2 ? argv[2] : "docs/images";
    char path[1024];
    crc_init();
    snprintf(path, sizeof path, "%s/tiles.png", dir);
    if (tiles_picture(path)) { fprintf(stderr, "pictures: cannot write %s\n", path); return 1; }
    snprintf(path, sizeof path, "%s/compare.png", dir);
    if (compare_picture(path)) { fprintf(stderr, "pictures: cannot write %s\n", path); return 1; }
    if (argc > 1) {
        snprintf(path, sizeof path, "%s/pictures.md", argv[1]);
        FILE *f = fopen(path, "w");
        if (f) {
            fprintf(f, "## Pictures\n\n`docs/images/tiles.png` (the 16 corner-pattern tiles) and "
                       "`docs/images/compare.png` (road buffer on the DEM cells vs the alpha-map splat) were "
                       "regenerated by this run.\n");
            fclose(f);
        }
    }
    printf("pictures: wrote %s/tiles.png and %s/compare.png\n", dir, dir);
    return 0;
}
