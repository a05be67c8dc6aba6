/* Splatting: road weight per texel from the classified road grid, then
 * C = alpha*T + (1-alpha)*S (seed 000, formula 4).
 *
 * Work is done one DEM-cell row at a time (T texel rows): the road weight of
 * the band is accumulated from the road cells of that row only, as the exact
 * integral of each cell's alpha-map over its overlap with each texel (a box
 * filter, via summed-area tables of the bilinear alpha-map). Texels no road
 * cell touches get the terrain colour with no blending work; texels fully
 * inside interior cells get the road colour alone. */
#include "internal.h"
#include "mask.h"
#include "roadgrid.h"

#include <math.h>
#include <string.h>

rs_result rs__splat_defaults(rs_ctx *ctx, const rs_splat_options *in, rs_splat_options *out)
{
    rs_splat_options o;
    if (in) o = *in;
    else memset(&o, 0, sizeof o);
    if (o.cell_size == 0) o.cell_size = 1;
    if (o.z_scale == 0) o.z_scale = 1;
    if (o.texels == 0) o.texels = 8;
    if (o.alpha_res == 0) o.alpha_res = 32;
    if (o.transition == 0) o.transition = 2;
    if (o.texture_scale == 0) o.texture_scale = 10;
    if (o.jitter && o.jitter_amount == 0) o.jitter_amount = 0.5;
    if (!(o.cell_size > 0) || !isfinite(o.cell_size))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "cell size %g must be a finite number > 0", o.cell_size);
    if (!isfinite(o.z_scale)) return rs__fail(ctx, RS_ERR_INVALID_ARG, "z-scale %g must be finite", o.z_scale);
    if (o.texels > 1024) return rs__fail(ctx, RS_ERR_INVALID_ARG, "texels %u must be 1..1024", o.texels);
    if (o.buffer != RS_BUFFER_DISTANCE && o.buffer != RS_BUFFER_DILATE)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "unknown buffer mode %d", (int)o.buffer);
    if (o.alpha_res < 2 || o.alpha_res > RS__MAX_ALPHA_RES)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "alpha-map resolution %u must be 2..%u", o.alpha_res, RS__MAX_ALPHA_RES);
    if (o.transition != o.transition || o.transition > o.alpha_res / 2.0)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "transition %g px must be at most half the alpha-map (%u px)",
                        o.transition, o.alpha_res / 2);
    if (!isfinite(o.origin_x) || !isfinite(o.origin_y))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "origin (%g, %g) must be finite", o.origin_x, o.origin_y);
    if (!(o.road_cell >= 0) || !isfinite(o.road_cell))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "road cell %g must be a finite number >= 0", o.road_cell);
    if (!(o.jitter_amount >= 0 && o.jitter_amount <= 1))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "jitter amount %g must be in [0,1]", o.jitter_amount);
    if (!(o.texture_scale > 0) || !isfinite(o.texture_scale))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "texture scale %g must be a finite number > 0", o.texture_scale);
    const rs_image *tex[2] = { o.terrain_texture, o.road_texture };
    for (int i = 0; i < 2; i++)
        if (tex[i] && (!tex[i]->rgba || tex[i]->width == 0 || tex[i]->height == 0))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s texture is empty", i ? "road" : "terrain");
    *out = o;
    return RS_OK;
}

/* Output size for options already checked by rs__splat_defaults. */
static rs_result output_size(rs_ctx *ctx, const rs_dem *dem, const rs_splat_options *o, uint32_t *width,
                             uint32_t *height)
{
    uint64_t w = (uint64_t)(dem->width - 1) * o->texels, h = (uint64_t)(dem->height - 1) * o->texels, px;
    if (!rs__mul_u64(w, h, &px) || px > ctx->limits.max_pixels || w > UINT32_MAX || h > UINT32_MAX)
        return rs__fail(ctx, RS_ERR_LIMIT, "output of %llu x %llu pixels exceeds the limit of %llu pixels",
                        (unsigned long long)w, (unsigned long long)h, (unsigned long long)ctx->limits.max_pixels);
    *width = (uint32_t)w;
    *height = (uint32_t)h;
    return RS_OK;
}

rs_result rs_splat_size(rs_ctx *ctx, const rs_dem *dem, const rs_splat_options *opts, uint32_t *width,
                        uint32_t *height)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!dem || !width || !height) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_splat_size");
    rs_splat_options o;
    rs_result r = rs__splat_defaults(ctx, opts, &o);
    if (!r) r = output_size(ctx, dem, &o, width, height);
    if (!r) rs__ok(ctx);
    return r;
}

/* --- integral tables of one alpha-map --------------------------------------- */

typedef struct alpha_table {
    uint32_t n;    /* res + 1 samples per side */
    double h2;     /* area of one alpha-map pixel in cell units */
    float *f;      /* samples */
    double *s;     /* S[i][j]: integral over [0,j]x[0,i] (pixel units) */
    double *col;   /* integral of f(j, .) over [0,i] */
    double *row;   /* integral of f(., i) over [0,j] */
} alpha_table;

static void table_build(alpha_table *t)
{
    uint32_t n = t->n;
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = 0; j < n; j++) {
            size_t k = (size_t)i * n + j;
            double fv = t->f[k];
            t->col[k] = i ? t->col[k - n] + 0.5 * (t->f[k - n] + fv) : 0;
            t->row[k] = j ? t->row[k - 1] + 0.5 * (t->f[k - 1] + fv) : 0;
            if (!i || !j) t->s[k] = 0;
            else
                t->s[k] = t->s[k - n] + t->s[k - 1] - t->s[k - n - 1] +
                          0.25 * (t->f[k - n - 1] + t->f[k - n] + t->f[k - 1] + fv);
        }
}

/* Integral of the bilinear alpha-map over [0,x] x [0,y] (pixel units). */
static double table_F(const alpha_table *t, double x, double y)
{
    uint32_t last = t->n - 1;
    double xf = floor(x), yf = floor(y);
    uint32_t X = xf >= last ? last - 1 : (uint32_t)xf, Y = yf >= last ? last - 1 : (uint32_t)yf;
    double fx = x - X, fy = y - Y;
    size_t k = (size_t)Y * t->n + X;
    double r = t->s[k];
    r += fx * t->col[k] + 0.5 * fx * fx * (t->col[k + 1] - t->col[k]);
    r += fy * t->row[k] + 0.5 * fy * fy * (t->row[k + t->n] - t->row[k]);
    double A = fx - 0.5 * fx * fx, B = 0.5 * fx * fx, C = fy - 0.5 * fy * fy, D = 0.5 * fy * fy;
    r += t->f[k] * A * C + t->f[k + 1] * B * C + t->f[k + t->n] * A * D + t->f[k + t->n + 1] * B * D;
    return r;
}

/* Integral of the canonical tile over [u0,u1]x[v0,v1] (cell-local). */
static double table_rect(const alpha_table *t, double u0, double v0, double u1, double v1)
{
    double s = (double)(t->n - 1);
    u0 *= s; u1 *= s; v0 *= s; v1 *= s;
    return (table_F(t, u1, v1) - table_F(t, u0, v1) - table_F(t, u1, v0) + table_F(t, u0, v0)) * t->h2;
}

/* Integral of the canonical tile turned `rot` quarter turns clockwise. */
static double table_rect_rot(const alpha_table *t, int rot, double u0, double v0, double u1, double v1)
{
    switch (rot & 3) {
    case 1: return table_rect(t, v0, 1 - u1, v1, 1 - u0);
    case 2: return table_rect(t, 1 - u1, 1 - v1, 1 - u0, 1 - v0);
    case 3: return table_rect(t, 1 - v1, u0, 1 - v0, u1);
    default: return table_rect(t, u0, v0, u1, v1);
    }
}

/* --- colours ------------------------------------------------------------------ */

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

typedef struct splat_state {
    const rs_dem *dem;
    const rs_splat_options *o;
    double zmin, zrange;
    double sun_zen, sun_az; /* radians; az in the math convention */
    double cos_zen, sin_zen;
} splat_state;

static double sample_raw(const splat_state *s, int64_t i, int64_t j, double fallback)
{
    const rs_dem *d = s->dem;
    double z = d->z[(size_t)i * d->width + (size_t)j];
    return z == z ? z * s->o->z_scale : fallback;
}

/* Height in metres at (i, j); outside the map the surface is extended
 * linearly from the two nearest samples, so a plane shades the same up to
 * its edges. NaN (nodata) reads as `fallback`. */
static double sample_m(const splat_state *s, int64_t i, int64_t j, double fallback)
{
    const int64_t H = s->dem->height, W = s->dem->width;
    int64_t i0 = i < 0 ? 0 : (i >= H ? H - 1 : i), j0 = j < 0 ? 0 : (j >= W ? W - 1 : j);
    int64_t i1 = i < 0 ? 1 : (i >= H ? H - 2 : i0), j1 = j < 0 ? 1 : (j >= W ? W - 2 : j0);
    double z00 = sample_raw(s, i0, j0, fallback);
    if (i0 == i && j0 == j) return z00;
    /* z(i,j) ~ z00 + (z00 - z(i1,j0)) + (z00 - z(i0,j1)) for one step out */
    double zi = i1 != i0 ? z00 - sample_raw(s, i1, j0, z00) : 0;
    double zj = j1 != j0 ? z00 - sample_raw(s, i0, j1, z00) : 0;
    return z00 + zi + zj;
}

/* Terrain colour of DEM sample row i: hypsometric tint times a hillshade by
 * Horn's method, light from azimuth 315, altitude 45 (gdaldem's defaults and
 * formula), normalised so flat ground keeps its tint. */
static void terrain_row(const splat_state *s, uint32_t i, float *rgb)
{
    const rs_dem *d = s->dem;
    double cs = s->o->cell_size;
    for (uint32_t j = 0; j < d->width; j++) {
        double zc = sample_m(s, i, j, s->zmin * s->o->z_scale);
        int64_t r = i, q = j; /* signed: the window reaches row/column -1 */
        double a = sample_m(s, r - 1, q - 1, zc), b = sample_m(s, r - 1, q, zc), c = sample_m(s, r - 1, q + 1, zc);
        double dd = sample_m(s, r, q - 1, zc), f = sample_m(s, r, q + 1, zc);
        double g = sample_m(s, r + 1, q - 1, zc), hh = sample_m(s, r + 1, q, zc), k = sample_m(s, r + 1, q + 1, zc);
        double dzdx = ((c + 2 * f + k) - (a + 2 * dd + g)) / (8 * cs);
        double dzdy = ((g + 2 * hh + k) - (a + 2 * b + c)) / (8 * cs);
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
        double t = s->zrange > 0 ? (zc / s->o->z_scale - s->zmin) / s->zrange : 0.5;
        float tint[3];
        hypsometric(t, tint);
        for (int ch = 0; ch < 3; ch++) {
            double v = tint[ch] * shade;
            rgb[3 * j + ch] = (float)(v > 255 ? 255 : v);
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

static uint8_t to_byte(double v)
{
    return (uint8_t)(v <= 0 ? 0 : (v >= 255 ? 255 : v + 0.5));
}

/* --- the splat ---------------------------------------------------------------- */

typedef struct splat_buffers {
    alpha_table tab[3]; /* EDGE, INNER, OUTER */
    double *band;       /* road weight of one band: T rows x out_w */
    float *rows[2];     /* terrain colours of the band's two sample rows */
} splat_buffers;

static void free_buffers(rs_ctx *ctx, splat_buffers *b)
{
    for (int i = 0; i < 3; i++) {
        rs__free(ctx, b->tab[i].f);
        rs__free(ctx, b->tab[i].s);
        rs__free(ctx, b->tab[i].col);
        rs__free(ctx, b->tab[i].row);
    }
    rs__free(ctx, b->band);
    rs__free(ctx, b->rows[0]);
    rs__free(ctx, b->rows[1]);
}

/* Add the road weight of a run of cells [gx, gx_end) of one row to the band:
 * one boundary cell of `type`, or a run of interior cells (all road, so only
 * overlap areas). Coordinates are integers in units of 1/(K*T) DEM cell. */
static void add_cells(const splat_buffers *b, double *band, uint32_t out_w, uint32_t T, uint32_t K, uint32_t gx,
                      uint32_t gx_end, uint32_t ly, rs_tile_type type, int rot)
{
    uint64_t cx0 = (uint64_t)gx * T, cx1 = (uint64_t)gx_end * T, cy0 = (uint64_t)ly * T, cy1 = cy0 + T;
    uint32_t px0 = (uint32_t)(cx0 / K), px1 = (uint32_t)((cx1 - 1) / K);
    uint32_t py0 = (uint32_t)(cy0 / K), py1 = (uint32_t)((cy1 - 1) / K);
    double inv_t = 1.0 / T, scale = (double)T * T / ((double)K * K);
    for (uint32_t py = py0; py <= py1; py++) {
        uint64_t ty0 = (uint64_t)py * K, ty1 = ty0 + K;
        uint64_t oy0 = ty0 > cy0 ? ty0 : cy0, oy1 = ty1 < cy1 ? ty1 : cy1;
        double v0 = (double)(oy0 - cy0) * inv_t, v1 = (double)(oy1 - cy0) * inv_t;
        double *row = band + (size_t)py * out_w;
        for (uint32_t px = px0; px <= px1 && px < out_w; px++) {
            uint64_t tx0 = (uint64_t)px * K, tx1 = tx0 + K;
            uint64_t ox0 = tx0 > cx0 ? tx0 : cx0, ox1 = tx1 < cx1 ? tx1 : cx1;
            double u0 = (double)(ox0 - cx0) * inv_t, u1 = (double)(ox1 - cx0) * inv_t;
            double area = (u1 - u0) * (v1 - v0), alpha = 0;
            if (type == RS_TILE_INTERIOR) {
                row[px] += (double)(ox1 - ox0) * (double)(oy1 - oy0) / ((double)K * K);
                continue;
            }
            switch (type) {
            case RS_TILE_EDGE: alpha = table_rect_rot(&b->tab[0], rot, u0, v0, u1, v1); break;
            case RS_TILE_INNER: alpha = table_rect_rot(&b->tab[1], rot, u0, v0, u1, v1); break;
            case RS_TILE_OUTER: alpha = table_rect_rot(&b->tab[2], rot, u0, v0, u1, v1); break;
            case RS_TILE_SADDLE:
                alpha = table_rect_rot(&b->tab[1], rot, u0, v0, u1, v1) +
                        table_rect_rot(&b->tab[1], rot + 2, u0, v0, u1, v1);
                break;
            default: break;
            }
            row[px] += (area - alpha) * scale;
        }
    }
}

rs_result rs_splat(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *grid, const rs_splat_options *opts,
                   uint8_t *rgba, size_t rgba_size, uint16_t *weight, size_t weight_count)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!dem || !grid || !rgba) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_splat");
    rs_splat_options o;
    rs_result r = rs__splat_defaults(ctx, opts, &o);
    if (r) return r;
    uint32_t out_w, out_h;
    r = output_size(ctx, dem, &o, &out_w, &out_h);
    if (r) return r;
    if (grid->dem_w != dem->width || grid->dem_h != dem->height || grid->cell_size != o.cell_size)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "road grid was built for another DEM or cell size");
    size_t npx = (size_t)out_w * out_h;
    if (rgba_size / 4 < npx)
        return rs__fail(ctx, RS_ERR_BUFFER_TOO_SMALL, "RGBA buffer of %zu bytes, need %zu", rgba_size, npx * 4);
    if (weight && weight_count < npx)
        return rs__fail(ctx, RS_ERR_BUFFER_TOO_SMALL, "weight buffer of %zu values, need %zu", weight_count, npx);

    const uint32_t T = o.texels, K = grid->k, R = o.alpha_res;
    rs__mask_table mt;
    rs__mask_table_build(&mt);
    splat_buffers b;
    memset(&b, 0, sizeof b);
    size_t n = (size_t)(R + 1) * (R + 1);
    static const rs_tile_type types[3] = { RS_TILE_EDGE, RS_TILE_INNER, RS_TILE_OUTER };
    int ok = 1;
    for (int i = 0; i < 3 && ok; i++) {
        alpha_table *t = &b.tab[i];
        t->n = R + 1;
        t->h2 = 1.0 / ((double)R * R);
        t->f = rs__alloc_array(ctx, n, sizeof *t->f);
        t->s = rs__alloc_array(ctx, n, sizeof *t->s);
        t->col = rs__alloc_array(ctx, n, sizeof *t->col);
        t->row = rs__alloc_array(ctx, n, sizeof *t->row);
        ok = t->f && t->s && t->col && t->row;
        if (ok) {
            rs__alpha_map_float(types[i], R, o.transition, o.jitter, o.jitter_amount, t->f);
            table_build(t);
        }
    }
    if (ok) {
        b.band = rs__alloc_array(ctx, (size_t)T * out_w, sizeof *b.band);
        b.rows[0] = rs__alloc_array(ctx, (size_t)dem->width * 3, sizeof(float));
        b.rows[1] = rs__alloc_array(ctx, (size_t)dem->width * 3, sizeof(float));
        ok = b.band && b.rows[0] && b.rows[1];
    }
    if (!ok) {
        free_buffers(ctx, &b);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for splat buffers");
    }

    splat_state st;
    st.dem = dem;
    st.o = &o;
    st.zmin = INFINITY;
    double zmax = -INFINITY;
    for (size_t i = 0; i < (size_t)dem->width * dem->height; i++) {
        double z = dem->z[i];
        if (z == z) {
            if (z < st.zmin) st.zmin = z;
            if (z > zmax) zmax = z;
        }
    }
    if (!(st.zmin <= zmax)) { st.zmin = 0; zmax = 0; }
    st.zrange = zmax - st.zmin;
    st.sun_zen = (90.0 - 45.0) * RS__PI / 180.0;
    st.sun_az = fmod(360.0 - 315.0 + 90.0, 360.0) * RS__PI / 180.0;
    st.cos_zen = cos(st.sun_zen);
    st.sin_zen = sin(st.sun_zen);

    const double texel_m = o.cell_size / T;
    for (uint32_t crow = 0; crow + 1 < dem->height; crow++) {
        /* Road weight of this band, from the road cells of this DEM row. */
        memset(b.band, 0, (size_t)T * out_w * sizeof *b.band);
        for (uint32_t ly = 0; ly < K; ly++) {
            uint32_t gy = crow * K + ly;
            uint32_t ty = gy >> RS__TILE_SHIFT;
            for (uint32_t tx = 0; tx < grid->tw; tx++) {
                const uint8_t *tile = rs__grid_tile(grid, tx, ty);
                if (!tile) continue;
                const uint8_t *trow_base = tile + (size_t)(gy & (RS__TILE - 1)) * RS__TILE;
                uint32_t gx0 = tx * RS__TILE, xe = grid->gw - gx0 < RS__TILE ? grid->gw - gx0 : RS__TILE;
                for (uint32_t x = 0; x < xe;) {
                    uint8_t cell = trow_base[x];
                    if (!(cell & RS__CELL_ROAD)) { x++; continue; }
                    unsigned p = cell & RS__CELL_PATTERN;
                    rs_tile_type type = (rs_tile_type)mt.type[p];
                    uint32_t x1 = x + 1;
                    if (type == RS_TILE_INTERIOR)
                        while (x1 < xe && trow_base[x1] == cell) x1++;
                    if (type != RS_TILE_TERRAIN) add_cells(&b, b.band, out_w, T, K, gx0 + x, gx0 + x1, ly, type, mt.rot[p]);
                    x = x1;
                }
            }
        }
        /* Terrain colours of the two sample rows bounding the band. */
        if (!o.terrain_texture) {
            if (crow == 0) terrain_row(&st, 0, b.rows[0]);
            else { float *t = b.rows[0]; b.rows[0] = b.rows[1]; b.rows[1] = t; }
            terrain_row(&st, crow + 1, b.rows[1]);
        }
        for (uint32_t ty = 0; ty < T; ty++) {
            uint32_t py = crow * T + ty;
            double fy = (ty + 0.5) / T;
            uint8_t *out = rgba + (size_t)py * out_w * 4;
            const double *wrow = b.band + (size_t)ty * out_w;
            for (uint32_t px = 0; px < out_w; px++) {
                double rw = wrow[px];
                uint32_t q = rw <= 0 ? 0 : (rw >= 1 ? 65535u : (uint32_t)(rw * 65535.0 + 0.5));
                if (weight) weight[(size_t)py * out_w + px] = (uint16_t)q;
                float tc[3] = { 0, 0, 0 }, sc[3] = { 0, 0, 0 };
                if (q < 65535u) {
                    if (o.terrain_texture) {
                        texture_sample(o.terrain_texture, (px + 0.5) * texel_m, (py + 0.5) * texel_m, o.texture_scale, tc);
                    } else {
                        uint32_t ccol = px / T;
                        double fx = ((px - ccol * T) + 0.5) / T;
                        const float *a = b.rows[0] + 3 * ccol, *c = b.rows[1] + 3 * ccol;
                        for (int ch = 0; ch < 3; ch++)
                            tc[ch] = (float)((a[ch] * (1 - fx) + a[ch + 3] * fx) * (1 - fy) +
                                             (c[ch] * (1 - fx) + c[ch + 3] * fx) * fy);
                    }
                }
                if (q > 0) {
                    if (o.road_texture)
                        texture_sample(o.road_texture, (px + 0.5) * texel_m, (py + 0.5) * texel_m, o.texture_scale, sc);
                    else asphalt(px, py, sc);
                }
                double rr = q / 65535.0;
                for (int ch = 0; ch < 3; ch++) {
                    double v = q == 0 ? tc[ch] : (q == 65535u ? sc[ch] : (1 - rr) * tc[ch] + rr * sc[ch]);
                    out[4 * px + ch] = to_byte(v);
                }
                out[4 * px + 3] = 255;
            }
        }
        if (o.progress && o.progress(o.progress_user, crow + 1, dem->height - 1)) {
            free_buffers(ctx, &b);
            return rs__fail(ctx, RS_ERR_CANCELLED, "cancelled");
        }
    }
    free_buffers(ctx, &b);
    rs__ok(ctx);
    return RS_OK;
}
