/* stripgen: writes the bundled road-surface strip image (docs/surface.md,
 * docs/examples/asphalt-strip.png), a line-scan-like picture of a two-lane
 * asphalt road: across the image = across the road (left edge = the left
 * road edge), down the image = along the road. Everything is a function of
 * the pixel's column and its row modulo the height, so the strip repeats
 * seamlessly along the road.
 *
 *   stripgen OUT.png [WIDTH HEIGHT]      (default 128 x 512)
 *
 * Contents: asphalt grain (hashed per pixel) and a soft mottle (smooth
 * periodic noise), darker polished wheel paths (two per lane), a worn
 * lighter band along the centre, a longitudinal crack that wanders
 * periodically, and one darker repair patch. PNG through zlib. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

static uint32_t mix(uint32_t x, uint32_t y)
{
    uint32_t h = x * 0x9e3779b1u ^ (y + 0x7f4a7c15u) * 0x85ebca77u;
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}

static double unit(uint32_t h) { return (h & 0xFFFFFF) / 16777215.0; }

/* Smooth noise on a lattice of `cell` pixels, periodic in y with period
 * `ph` pixels (ph a multiple of cell). */
static double smooth(double x, double y, int cell, int ph, uint32_t seed)
{
    int gy = ph / cell;
    double fx = x / cell, fy = y / cell;
    int ix = (int)floor(fx), iy = (int)floor(fy);
    double ax = fx - ix, ay = fy - iy;
    ax = ax * ax * (3 - 2 * ax);
    ay = ay * ay * (3 - 2 * ay);
    int y0 = ((iy % gy) + gy) % gy, y1 = (y0 + 1) % gy;
    double n00 = unit(mix((uint32_t)ix + seed, (uint32_t)y0)), n01 = unit(mix((uint32_t)ix + 1 + seed, (uint32_t)y0));
    double n10 = unit(mix((uint32_t)ix + seed, (uint32_t)y1)), n11 = unit(mix((uint32_t)ix + 1 + seed, (uint32_t)y1));
    return (n00 * (1 - ax) + n01 * ax) * (1 - ay) + (n10 * (1 - ax) + n11 * ax) * ay;
}

static double band(double u, double centre, double half)
{
    double d = fabs(u - centre) / half;
    return d >= 1 ? 0 : 0.5 + 0.5 * cos(d * 3.14159265358979);
}

static int put_chunk(FILE *f, const char *type, const uint8_t *data, uint32_t n)
{
    uint8_t len[4] = { (uint8_t)(n >> 24), (uint8_t)(n >> 16), (uint8_t)(n >> 8), (uint8_t)n };
    uLong crc = crc32(0, (const Bytef *)type, 4);
    if (n) crc = crc32(crc, data, n);
    uint8_t c[4] = { (uint8_t)(crc >> 24), (uint8_t)(crc >> 16), (uint8_t)(crc >> 8), (uint8_t)crc };
    return fwrite(len, 1, 4, f) != 4 || fwrite(type, 1, 4, f) != 4 || (n && fwrite(data, 1, n, f) != n) ||
           fwrite(c, 1, 4, f) != 4;
}

int main(int argc, char **argv)
{
    if (argc != 2 && argc != 4) {
        fprintf(stderr, "usage: stripgen OUT.png [WIDTH HEIGHT]\n");
        return 2;
    }
    int W = argc == 4 ? atoi(argv[2]) : 128, H = argc == 4 ? atoi(argv[3]) : 512;
    if (W < 16 || H < 64 || W > 4096 || H > 16384 || H % 32) {
        fprintf(stderr, "stripgen: WIDTH 16..4096, HEIGHT 64..16384 and a multiple of 32\n");
        return 2;
    }
    size_t rowb = (size_t)W * 3 + 1, raw_n = rowb * H;
    uint8_t *raw = malloc(raw_n);
    uLongf zn = compressBound((uLong)raw_n);
    uint8_t *z = malloc(zn);
    if (!raw || !z) return 1;
    for (int y = 0; y < H; y++) {
        uint8_t *row = raw + rowb * y;
        row[0] = 0; /* filter: none */
        for (int x = 0; x < W; x++) {
            double u = (x + 0.5) / W, v = (y + 0.5) / H; /* across, along (one period) */
            double grain = unit(mix((uint32_t)x, (uint32_t)y)) - 0.5;
            double mottle = smooth(x, y, 8, H, 11u) - 0.5 + 0.5 * (smooth(x, y, 32, H, 23u) - 0.5);
            /* wheel paths: lane centres at u = 0.25 and 0.75, wheels 0.9 m
             * either side of a 3.5 m lane (road 7 m: 0.129 of the width) */
            double wheel = 0;
            for (int l = 0; l < 2; l++)
                for (int sgn = -1; sgn <= 1; sgn += 2) wheel += band(u, 0.25 + 0.5 * l + sgn * 0.129, 0.05);
            double centre = band(u, 0.5, 0.04);
            /* a crack wandering around u = 0.62 with one period per strip */
            double cu = 0.62 + 0.03 * sin(2 * 3.14159265358979 * v) + 0.01 * sin(6 * 3.14159265358979 * v + 1.0);
            double crack = band(u, cu, 1.2 / W) * (0.6 + 0.4 * smooth(0, y, 16, H, 5u));
            /* a repair patch: u 0.08..0.36, v 0.55..0.70 */
            double patch = u > 0.08 && u < 0.36 && v > 0.55 && v < 0.70 ? 1 : 0;
            double g = 92 + 26 * grain + 16 * mottle - 12 * wheel + 8 * centre - 45 * crack - 14 * patch;
            double rgb[3] = { g, g, g + 4 - 3 * patch };
            for (int c = 0; c < 3; c++) {
                double val = rgb[c] + 0.5;
                row[1 + 3 * x + c] = (uint8_t)(val < 0 ? 0 : (val > 255 ? 255 : val));
            }
        }
    }
    if (compress2(z, &zn, raw, (uLong)raw_n, 9) != Z_OK) return 1;
    FILE *f = fopen(argv[1], "wb");
    if (!f) {
        fprintf(stderr, "stripgen: cannot write %s\n", argv[1]);
        return 1;
    }
    static const uint8_t sig[8] = { 0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A };
    uint8_t ihdr[13] = { (uint8_t)(W >> 24), (uint8_t)(W >> 16), (uint8_t)(W >> 8), (uint8_t)W,
                         (uint8_t)(H >> 24), (uint8_t)(H >> 16), (uint8_t)(H >> 8), (uint8_t)H,
                         8, 2, 0, 0, 0 }; /* 8-bit RGB */
    int bad = fwrite(sig, 1, 8, f) != 8 || put_chunk(f, "IHDR", ihdr, 13) || put_chunk(f, "IDAT", z, (uint32_t)zn) ||
              put_chunk(f, "IEND", NULL, 0);
    bad |= fclose(f) != 0;
    free(raw);
    free(z);
    if (bad) {
        fprintf(stderr, "stripgen: write failed: %s\n", argv[1]);
        return 1;
    }
    return 0;
}
