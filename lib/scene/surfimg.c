/* Road-aligned surface images: the mip chain and the trilinear sampler
 * (lib/scene/surfimg.h, docs/surface.md). */
#include "surfimg.h"

#include <math.h>
#include <string.h>

void rs__surfimg_free(rs_ctx *ctx, rs__surfimg *m)
{
    if (!m) return;
    for (uint32_t k = 0; k < m->levels; k++) rs__free(ctx, m->px[k]);
    rs__free(ctx, m);
}

static uint8_t byte_of(double v)
{
    v += 0.5;
    return (uint8_t)(v >= 255 ? 255 : (v > 0 ? v : 0));
}

/* One row of n premultiplied RGBA8 texels, area-resampled to m texels
 * (m <= n): texel i covers [i n, (i + 1) n) in units of 1/m input texel.
 * Sums of the overlaps (integers) times the values, not divided. */
static void resample_row(const uint8_t *in, uint32_t n, uint32_t m, double *out)
{
    for (uint32_t i = 0; i < m; i++) {
        uint64_t lo = (uint64_t)i * n, hi = lo + n;
        uint32_t j0 = (uint32_t)(lo / m), j1 = (uint32_t)((hi - 1) / m);
        double a[4] = { 0, 0, 0, 0 };
        for (uint32_t j = j0; j <= j1; j++) {
            uint64_t jl = (uint64_t)j * m, jh = jl + m;
            double ov = (double)((hi < jh ? hi : jh) - (lo > jl ? lo : jl));
            for (int c = 0; c < 4; c++) a[c] += ov * in[4 * (size_t)j + c];
        }
        for (int c = 0; c < 4; c++) out[4 * (size_t)i + c] = a[c];
    }
}

rs_result rs__surfimg_build(rs_ctx *ctx, const rs_image *img, const char *what, rs__surfimg **out)
{
    *out = NULL;
    if (!img->rgba || img->width == 0 || img->height == 0)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "surface image %s is empty", what);
    if (img->width > RS__SURFIMG_MAX_SIDE || img->height > RS__SURFIMG_MAX_SIDE ||
        (uint64_t)img->width * img->height > ctx->limits.max_texture_pixels)
        return rs__fail(ctx, RS_ERR_LIMIT,
                        "surface image %s of %u x %u pixels exceeds the limits (%u a side, %llu pixels)", what,
                        img->width, img->height, RS__SURFIMG_MAX_SIDE,
                        (unsigned long long)ctx->limits.max_texture_pixels);
    rs__surfimg *m = rs__calloc(ctx, 1, sizeof *m);
    double *row = NULL, *acc = NULL;
    if (!m) goto nomem;
    uint32_t W = img->width, H = img->height;
    m->w[0] = W, m->h[0] = H;
    m->px[0] = rs__alloc_array(ctx, (size_t)W * H, 4);
    if (!m->px[0]) goto nomem;
    m->levels = 1;
    m->bytes = sizeof *m + (size_t)W * H * 4;
    /* premultiplied alpha: transparent texels add no colour when filtered */
    for (size_t i = 0; i < (size_t)W * H; i++) {
        const uint8_t *s = img->rgba + 4 * i;
        uint8_t *d = m->px[0] + 4 * i;
        for (int c = 0; c < 3; c++) d[c] = byte_of(s[c] * (double)s[3] / 255.0);
        d[3] = s[3];
    }
    row = rs__alloc_array(ctx, (size_t)(W > 1 ? W / 2 : 1), 4 * sizeof *row);
    acc = rs__alloc_array(ctx, (size_t)(W > 1 ? W / 2 : 1), 4 * sizeof *acc);
    if (!row || !acc) goto nomem;
    while (m->levels < RS__SURFIMG_LEVELS && (m->w[m->levels - 1] > 1 || m->h[m->levels - 1] > 1)) {
        uint32_t k = m->levels, n = m->w[k - 1], nh = m->h[k - 1];
        uint32_t w2 = n > 1 ? n / 2 : 1, h2 = nh > 1 ? nh / 2 : 1;
        uint8_t *dst = rs__alloc_array(ctx, (size_t)w2 * h2, 4);
        if (!dst) goto nomem;
        m->px[k] = dst, m->w[k] = w2, m->h[k] = h2;
        m->levels++;
        m->bytes += (size_t)w2 * h2 * 4;
        const uint8_t *src = m->px[k - 1];
        /* output row i covers input rows [i nh, (i + 1) nh) in units of 1/h2;
         * the whole period is covered exactly, so the rows repeat seamlessly */
        for (uint32_t i = 0; i < h2; i++) {
            uint64_t lo = (uint64_t)i * nh, hi = lo + nh;
            uint32_t j0 = (uint32_t)(lo / h2), j1 = (uint32_t)((hi - 1) / h2);
            memset(acc, 0, (size_t)w2 * 4 * sizeof *acc);
            for (uint32_t j = j0; j <= j1; j++) {
                uint64_t jl = (uint64_t)j * h2, jh = jl + h2;
                double ov = (double)((hi < jh ? hi : jh) - (lo > jl ? lo : jl));
                resample_row(src + (size_t)j * n * 4, n, w2, row);
                for (size_t c = 0; c < (size_t)w2 * 4; c++) acc[c] += ov * row[c];
            }
            double area = (double)n * (double)nh;
            for (size_t c = 0; c < (size_t)w2 * 4; c++) dst[(size_t)i * w2 * 4 + c] = byte_of(acc[c] / area);
        }
    }
    rs__free(ctx, row);
    rs__free(ctx, acc);
    *out = m;
    return RS_OK;
nomem:
    rs__free(ctx, row);
    rs__free(ctx, acc);
    rs__surfimg_free(ctx, m);
    return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for surface image %s", what);
}

void rs__surfimg_lod(const rs__surfimg *m, double texels, uint32_t *lev, double *f)
{
    double l = texels > 0 ? log2(texels) : 0;
    double top = (double)(m->levels - 1);
    if (!(l > 0)) *lev = 0, *f = 0;
    else if (l >= top) *lev = m->levels - 1, *f = 0;
    else {
        double fl = floor(l);
        *lev = (uint32_t)fl;
        *f = l - fl;
    }
}

/* Bilinear sample of level k, weight wgt added into a. */
static void level_sample(const rs__surfimg *m, uint32_t k, double u, double v, double wgt, double a[4])
{
    const uint32_t W = m->w[k], H = m->h[k];
    double x = u * W - 0.5;
    if (!(x > 0)) x = 0;
    if (x > W - 1) x = W - 1;
    uint32_t x0 = (uint32_t)x, x1 = x0 + 1 < W ? x0 + 1 : x0;
    double fx = x - x0;
    double y = v * H - 0.5, fly = floor(y), fy = y - fly;
    int64_t yi = (int64_t)fly;
    uint32_t y0 = yi < 0 ? H - 1 : (yi >= H ? (uint32_t)(yi % H) : (uint32_t)yi);
    uint32_t y1 = y0 + 1 == H ? 0 : y0 + 1;
    const uint8_t *r0 = m->px[k] + (size_t)y0 * W * 4, *r1 = m->px[k] + (size_t)y1 * W * 4;
    for (int c = 0; c < 4; c++) {
        double t0 = r0[4 * (size_t)x0 + c] * (1 - fx) + r0[4 * (size_t)x1 + c] * fx;
        double t1 = r1[4 * (size_t)x0 + c] * (1 - fx) + r1[4 * (size_t)x1 + c] * fx;
        a[c] += wgt * (t0 * (1 - fy) + t1 * fy);
    }
}

void rs__surfimg_sample(const rs__surfimg *m, double u, double v, uint32_t lev, double f, double out[4])
{
    double a[4] = { 0, 0, 0, 0 };
    if (!(u > 0)) u = 0;
    if (u > 1) u = 1;
    v -= floor(v);
    if (!(v >= 0 && v < 1)) v = 0; /* NaN, or 1 by rounding */
    level_sample(m, lev, u, v, 1 - f, a);
    if (f > 0 && lev + 1 < m->levels) level_sample(m, lev + 1, u, v, f, a);
    out[0] = a[0], out[1] = a[1], out[2] = a[2];
    out[3] = a[3] / 255.0;
}
