/* Surface stage: the terrain colour T (hypsometric tint times Horn's
 * hillshade, or a tiled texture) where a pixel has terrain, and the road
 * colour S (procedural asphalt or a tiled texture) where it has road. */
#include "splatter.h"
#include "dem.h"

#include <math.h>

static uint32_t hash2(uint32_t x, uint32_t y)
{
    uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u;
    h ^= h >> 15; h *= 0x2c1b3c6dU;
    h ^= h >> 12; h *= 0x297a2d39U;
    h ^= h >> 15;
    return h;
}

static void hypsometric(double t, float rgb[3])
{
    static const double stops[6][4] = {
        { 0.00, 74, 112, 62 }, { 0.25, 104, 138, 72 }, { 0.50, 158, 156, 96 },
        { 0.70, 160, 132, 96 }, { 0.88, 150, 140, 132 }, { 1.00, 236, 236, 236 },
    };
    if (!(t > 0)) t = 0;
    if (t > 1) t = 1;
    int i = 0;
    while (i < 4 && t > stops[i + 1][0]) i++;
    double f = (t - stops[i][0]) / (stops[i + 1][0] - stops[i][0]);
    for (int c = 0; c < 3; c++) rgb[c] = (float)(stops[i][c + 1] + f * (stops[i + 1][c + 1] - stops[i][c + 1]));
}

/* Terrain colour of DEM sample row i, columns [c0, c1]: tint times a
 * hillshade by Horn's gradient, light from azimuth 315, altitude 45
 * (gdaldem's defaults and formula), normalised so flat ground keeps its
 * tint. */
static void terrain_row(const rs_splatter *s, uint32_t i, uint32_t c0, uint32_t c1, float *rgb)
{
    const rs_dem *d = s->dem;
    double zs = d->frame.z_scale;
    for (uint32_t j = c0; j <= c1; j++) {
        double dzdx, dzdy;
        rs__dem_horn(s->z, d->width, d->height, d->frame.cell_size, zs, i, j, &dzdx, &dzdy);
        double slope = atan(sqrt(dzdx * dzdx + dzdy * dzdy));
        double aspect = 0;
        if (dzdx != 0) {
            aspect = atan2(dzdy, -dzdx);
            if (aspect < 0) aspect += 2 * RS__PI;
        } else if (dzdy > 0) aspect = RS__PI / 2;
        else if (dzdy < 0) aspect = 1.5 * RS__PI;
        double hs = s->cos_zen * cos(slope) + s->sin_zen * sin(slope) * cos(s->sun_az - aspect);
        if (!(hs > 0)) hs = 0;
        double shade = 0.3 + 0.7 * hs / s->cos_zen;
        double zc = s->z[(size_t)i * d->width + j] * zs;
        double t = s->zrange > 0 ? (zc / zs - s->zmin) / s->zrange : 0.5;
        float tint[3];
        hypsometric(t, tint);
        float *out = rgb + 3 * (size_t)(j - c0);
        for (int ch = 0; ch < 3; ch++) {
            double v = tint[ch] * shade;
            out[ch] = (float)(v > 255 ? 255 : v);
        }
    }
}

static void texture_sample(const rs_image *img, double x, double y, double scale, float rgb[3])
{
    double u = x / scale, v = y / scale;
    u = (u - floor(u)) * img->width - 0.5;
    v = (v - floor(v)) * img->height - 0.5;
    double fu = floor(u), fv = floor(v);
    double au = u - fu, av = v - fv;
    int64_t x0 = (int64_t)fu, y0 = (int64_t)fv;
    int64_t W = img->width, H = img->height;
    int64_t xa = ((x0 % W) + W) % W, xb = (xa + 1) % W, ya = ((y0 % H) + H) % H, yb = (ya + 1) % H;
    const uint8_t *p00 = img->rgba + 4 * ((size_t)ya * W + xa), *p01 = img->rgba + 4 * ((size_t)ya * W + xb);
    const uint8_t *p10 = img->rgba + 4 * ((size_t)yb * W + xa), *p11 = img->rgba + 4 * ((size_t)yb * W + xb);
    for (int c = 0; c < 3; c++)
        rgb[c] = (float)((p00[c] * (1 - au) + p01[c] * au) * (1 - av) + (p10[c] * (1 - au) + p11[c] * au) * av);
}

/* Procedural asphalt: dark grey, fine grain per texel plus a soft mottle on
 * a 4-texel lattice; keyed to texel indices, so deterministic. */
static void asphalt(uint32_t px, uint32_t py, float rgb[3])
{
    double grain = (double)(hash2(px, py) & 0xFFFF) / 65535.0 - 0.5;
    uint32_t lx = px >> 2, ly = py >> 2;
    double fx = (px & 3) / 4.0, fy = (py & 3) / 4.0;
    double n00 = (hash2(lx, ly + 7919u) & 0xFF) / 255.0, n01 = (hash2(lx + 1, ly + 7919u) & 0xFF) / 255.0;
    double n10 = (hash2(lx, ly + 7920u) & 0xFF) / 255.0, n11 = (hash2(lx + 1, ly + 7920u) & 0xFF) / 255.0;
    double mottle = (n00 * (1 - fx) + n01 * fx) * (1 - fy) + (n10 * (1 - fx) + n11 * fx) * fy - 0.5;
    double v = 70 + 18 * grain + 10 * mottle;
    rgb[0] = (float)v;
    rgb[1] = (float)v;
    rgb[2] = (float)(v + 3);
}

void rs__surface(const rs_splatter *s, rs__piece *p)
{
    const uint32_t T = s->o.texels;
    const rs_surface_options *f = &s->o.surface;
    const size_t n = (size_t)p->rows * p->w;
    int need_terrain = 0;
    for (size_t i = 0; i < n && !need_terrain; i++) need_terrain = p->q[i] < 65535u;
    /* The two sample rows bounding the DEM row, over the piece's columns. */
    uint32_t c0 = p->x0 / T, c1 = (p->x0 + p->w - 1) / T + 1;
    if (need_terrain && !f->terrain_texture) {
        terrain_row(s, p->crow, c0, c1, p->trow[0]);
        terrain_row(s, p->crow + 1, c0, c1, p->trow[1]);
    }
    for (uint32_t r = 0; r < p->rows; r++) {
        uint32_t py = p->y0 + r, ty = py - p->crow * T;
        double fy = (ty + 0.5) / T;
        const uint16_t *q = p->q + (size_t)r * p->w;
        float *tc = p->tc + (size_t)r * p->w * 3, *sc = p->sc + (size_t)r * p->w * 3;
        for (uint32_t k = 0; k < p->w; k++) {
            uint32_t px = p->x0 + k;
            if (q[k] < 65535u) {
                if (f->terrain_texture) {
                    texture_sample(f->terrain_texture, (px + 0.5) * s->texel_m, (py + 0.5) * s->texel_m,
                                   f->texture_scale, tc + 3 * k);
                } else {
                    uint32_t ccol = px / T;
                    double fx = ((px - ccol * T) + 0.5) / T;
                    const float *a = p->trow[0] + 3 * (ccol - c0), *c = p->trow[1] + 3 * (ccol - c0);
                    for (int ch = 0; ch < 3; ch++)
                        tc[3 * k + ch] = (float)((a[ch] * (1 - fx) + a[ch + 3] * fx) * (1 - fy) +
                                                 (c[ch] * (1 - fx) + c[ch + 3] * fx) * fy);
                }
            }
            if (q[k] > 0) {
                if (f->road_texture)
                    texture_sample(f->road_texture, (px + 0.5) * s->texel_m, (py + 0.5) * s->texel_m,
                                   f->texture_scale, sc + 3 * k);
                else asphalt(px, py, sc + 3 * k);
            }
        }
    }
}
