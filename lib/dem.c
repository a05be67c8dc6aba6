/* The DEM: samples, frame (cell size, z-scale, origin), height range, the
 * one nodata policy and the one Horn gradient shared by splat, mesh and
 * render. */
#include "dem.h"

#include <float.h>
#include <math.h>
#include <string.h>

rs_result rs__dem_alloc(rs_ctx *ctx, uint32_t w, uint32_t h, rs_dem **out)
{
    size_t n, bytes;
    if (!rs__mul_size(w, h, &n) || !rs__mul_size(n, sizeof(float), &bytes))
        return rs__fail(ctx, RS_ERR_LIMIT, "DEM %ux%u is too large for this machine", w, h);
    rs_dem *dem = rs__malloc(ctx, sizeof *dem);
    if (!dem) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for a %ux%u DEM", w, h);
    memset(dem, 0, sizeof *dem);
    dem->width = w;
    dem->height = h;
    dem->frame.cell_size = 1;
    dem->frame.z_scale = 1;
    dem->z = rs__malloc(ctx, bytes);
    if (!dem->z) {
        rs__free(ctx, dem);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for a %ux%u DEM", w, h);
    }
    *out = dem;
    return RS_OK;
}

rs_result rs_dem_create(rs_ctx *ctx, uint32_t width, uint32_t height, const float *samples, rs_dem **out)
{
    if (!out) return ctx ? rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_dem_create: out is NULL") : RS_ERR_INVALID_ARG;
    *out = NULL;
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!samples) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_dem_create: samples is NULL");
    if (width < 2 || height < 2)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_dem_create: DEM is %ux%u; width and height must be >= 2",
                        width, height);
    if (width > ctx->limits.max_dem_side || height > ctx->limits.max_dem_side)
        return rs__fail(ctx, RS_ERR_LIMIT, "rs_dem_create: DEM is %ux%u; the limit is %u samples per side", width,
                        height, ctx->limits.max_dem_side);
    size_t n;
    if (!rs__mul_size(width, height, &n))
        return rs__fail(ctx, RS_ERR_LIMIT, "rs_dem_create: %ux%u is too large", width, height);
    /* (the height range in the same pass: a NaN compares false, the bounds stay) */
    float lo = INFINITY, hi = -INFINITY;
    int nodata = 0;
    for (size_t i = 0; i < n; i++) {
        float z = samples[i];
        if (isinf(z))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_dem_create: sample %zu (row %zu, column %zu) is infinite",
                            i, i / width, i % width);
        nodata |= z != z;
        lo = z < lo ? z : lo;
        hi = z > hi ? z : hi;
    }
    rs_dem *dem;
    rs_result rc = rs__dem_alloc(ctx, width, height, &dem);
    if (rc != RS_OK) return rc;
    memcpy(dem->z, samples, n * sizeof(float));
    rs__dem_seal_range(dem, lo, hi, nodata);
    *out = dem;
    rs__ok(ctx);
    return RS_OK;
}

void rs_dem_free(rs_ctx *ctx, rs_dem *dem)
{
    if (!ctx || !dem) return;
    rs__free(ctx, dem->z);
    rs__free(ctx, dem);
}

uint32_t rs_dem_width(const rs_dem *dem) { return dem ? dem->width : 0; }
uint32_t rs_dem_height(const rs_dem *dem) { return dem ? dem->height : 0; }
const float *rs_dem_samples(const rs_dem *dem) { return dem ? dem->z : NULL; }

/* Ranges keep every derived quantity - extent, texel size, heights in
 * metres, their products in gradients - finite and normal in double and
 * representable in float outputs, so no later stage needs its own check. */
rs_result rs_dem_set_frame(rs_ctx *ctx, rs_dem *dem, const rs_dem_frame *frame)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!dem) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_dem_set_frame: dem is NULL");
    rs_dem_frame f;
    if (frame) f = *frame;
    else memset(&f, 0, sizeof f);
    if (f.cell_size == 0) f.cell_size = 1;
    if (f.z_scale == 0) f.z_scale = 1;
    if (!(f.cell_size >= 1e-9 && f.cell_size <= 1e9))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "cell size %g must be in [1e-9, 1e9] metres", f.cell_size);
    if (!(fabs(f.z_scale) >= 1e-12 && fabs(f.z_scale) <= 1e12))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "z-scale %g must be in [1e-12, 1e12] in magnitude", f.z_scale);
    if (!(fabs(f.origin_x) <= 1e12 && fabs(f.origin_y) <= 1e12))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "origin (%g, %g) must be finite and within 1e12 m", f.origin_x,
                        f.origin_y);
    double extent = (double)(dem->width > dem->height ? dem->width : dem->height) * f.cell_size;
    if (!(extent <= 1e12))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "cell size %g m makes the map %g m wide (limit 1e12 m)",
                        f.cell_size, extent);
    dem->frame = f;
    rs__ok(ctx);
    return RS_OK;
}

void rs_dem_get_frame(const rs_dem *dem, rs_dem_frame *out)
{
    if (!out) return;
    if (dem) *out = dem->frame;
    else {
        memset(out, 0, sizeof *out);
        out->cell_size = 1;
        out->z_scale = 1;
    }
}

void rs_dem_height_range(const rs_dem *dem, double *zmin, double *zmax, int *has_nodata)
{
    /* (kept when the samples went in: rs__dem_seal_range) */
    if (zmin) *zmin = dem ? dem->zlo : 0;
    if (zmax) *zmax = dem ? dem->zhi : 0;
    if (has_nodata) *has_nodata = dem ? dem->nodata : 0;
}

void rs__dem_seal_range(rs_dem *dem, float lo, float hi, int nodata)
{
    if (!(lo <= hi)) lo = hi = 0; /* (no valid sample) */
    dem->zlo = lo, dem->zhi = hi, dem->nodata = nodata;
}

#define NIL 0xFFFFFFFFu

rs_result rs__dem_fill_nodata(rs_ctx *ctx, const rs_dem *dem, float **out)
{
    uint32_t W = dem->width, H = dem->height;
    size_t n = (size_t)W * H;
    float *z = rs__alloc_array(ctx, n, sizeof *z);
    uint32_t *q = rs__alloc_array(ctx, n, sizeof *q);
    uint32_t *layer = rs__alloc_array(ctx, n, sizeof *layer);
    if (!z || !q || !layer) {
        rs__free(ctx, z); rs__free(ctx, q); rs__free(ctx, layer);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory filling nodata (%zu samples)", n);
    }
    const float *src = dem->z;
    size_t qn = 0, valid = 0;
    for (size_t i = 0; i < n; i++) {
        z[i] = isfinite(src[i]) ? src[i] : NAN;
        layer[i] = isnan(z[i]) ? NIL : 0;
        if (!isnan(z[i])) valid++;
    }
    if (valid == 0) {
        for (size_t i = 0; i < n; i++) z[i] = 0.0f;
    } else {
        /* seed layer 1: nodata samples touching valid ones */
        for (uint32_t i = 0; i < H; i++)
            for (uint32_t j = 0; j < W; j++) {
                size_t id = (size_t)i * W + j;
                if (layer[id] != NIL) continue;
                int touch = 0;
                for (int di = -1; di <= 1 && !touch; di++)
                    for (int dj = -1; dj <= 1; dj++) {
                        int64_t ii = (int64_t)i + di, jj = (int64_t)j + dj;
                        if (ii < 0 || jj < 0 || ii >= H || jj >= W) continue;
                        if (layer[(size_t)ii * W + (size_t)jj] == 0) { touch = 1; break; }
                    }
                if (touch) { layer[id] = 1; q[qn++] = (uint32_t)id; }
            }
        size_t head = 0;
        while (head < qn) {
            uint32_t cur = layer[q[head]];
            size_t end = qn;
            for (size_t k = head; k < end; k++) { /* values of this layer */
                size_t id = q[k];
                int64_t i = (int64_t)(id / W), j = (int64_t)(id % W);
                float best = INFINITY;
                for (int di = -1; di <= 1; di++)
                    for (int dj = -1; dj <= 1; dj++) {
                        int64_t ii = i + di, jj = j + dj;
                        if (ii < 0 || jj < 0 || ii >= H || jj >= W) continue;
                        size_t nb = (size_t)ii * W + (size_t)jj;
                        if (layer[nb] < cur && z[nb] < best) best = z[nb];
                    }
                z[id] = best;
            }
            for (size_t k = head; k < end; k++) { /* next layer */
                size_t id = q[k];
                int64_t i = (int64_t)(id / W), j = (int64_t)(id % W);
                for (int di = -1; di <= 1; di++)
                    for (int dj = -1; dj <= 1; dj++) {
                        int64_t ii = i + di, jj = j + dj;
                        if (ii < 0 || jj < 0 || ii >= H || jj >= W) continue;
                        size_t nb = (size_t)ii * W + (size_t)jj;
                        if (layer[nb] == NIL) { layer[nb] = cur + 1; q[qn++] = (uint32_t)nb; }
                    }
            }
            head = end;
        }
    }
    rs__free(ctx, q);
    rs__free(ctx, layer);
    *out = z;
    return RS_OK;
}

/* Height at (i, j) in metres; outside the map the surface continues
 * linearly from the two nearest samples, so a plane has the same gradient
 * up to its edges. */
static double sample_ext(const float *z, int64_t W, int64_t H, double zs, int64_t i, int64_t j)
{
    int64_t i0 = i < 0 ? 0 : (i >= H ? H - 1 : i), j0 = j < 0 ? 0 : (j >= W ? W - 1 : j);
    double z00 = z[(size_t)i0 * (size_t)W + (size_t)j0] * zs;
    if (i0 == i && j0 == j) return z00;
    int64_t i1 = i < 0 ? 1 : (i >= H ? H - 2 : i0), j1 = j < 0 ? 1 : (j >= W ? W - 2 : j0);
    double zi = i1 != i0 ? z00 - z[(size_t)i1 * (size_t)W + (size_t)j0] * zs : 0;
    double zj = j1 != j0 ? z00 - z[(size_t)i0 * (size_t)W + (size_t)j1] * zs : 0;
    return z00 + zi + zj;
}

void rs__dem_horn_border(const float *z, uint32_t width, uint32_t height, double cell_size, double z_scale,
                         uint32_t i, uint32_t j, double *dzdx, double *dzdy)
{
    int64_t W = width, H = height, r = i, q = j;
    double zs = z_scale;
    double a = sample_ext(z, W, H, zs, r - 1, q - 1), b = sample_ext(z, W, H, zs, r - 1, q),
           c = sample_ext(z, W, H, zs, r - 1, q + 1);
    double d = sample_ext(z, W, H, zs, r, q - 1), f = sample_ext(z, W, H, zs, r, q + 1);
    double g = sample_ext(z, W, H, zs, r + 1, q - 1), h = sample_ext(z, W, H, zs, r + 1, q),
           k = sample_ext(z, W, H, zs, r + 1, q + 1);
    *dzdx = ((c + 2 * f + k) - (a + 2 * d + g)) / (8 * cell_size);
    *dzdy = ((g + 2 * h + k) - (a + 2 * b + c)) / (8 * cell_size);
}
