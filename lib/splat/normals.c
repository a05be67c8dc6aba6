/* Normal maps (issue 16; docs/normals.md): a tangent-space normal per
 * output pixel, on the colour output's pixel grid.
 *
 * Per pixel: the terrain gradient (Horn's, lib/dem.h) at the four DEM
 * samples around it, interpolated bilinearly as the surface stage
 * interpolates the terrain colour; plus, weighted by the road weight R,
 * the road's own relief: the Sobel gradient of the road texture's
 * luminance (height = luminance, `strength` per pixel) and of the paint
 * coverage of lines and markings (`paint_height` metres). Every value is a
 * function of the pixel's coordinates only (a neighbour outside the image
 * is the edge pixel repeated), so any window gives the bytes of the same
 * pixels of the whole image. */
#include "splatter.h"
#include "dem.h"
#include "linesym.h"
#include "markings.h"
#include "styling.h"
#include "roadfield.h"

#include <math.h>
#include <string.h>

#define NM_COLS 1024u      /* columns of one piece */
#define NM_PAINT 0.003     /* default paint height, metres */
#define NM_FXT 64          /* column weights kept in a table: texels up to this */

typedef rs__nm_scratch nm_scratch;

void rs__nm_scratch_free(rs_ctx *ctx, rs__nm_scratch *b)
{
    rs__free(ctx, b->cov);
    rs__free(ctx, b->ov);
    rs__free(ctx, b->paint);
    rs__free(ctx, b->lum);
    rs__free(ctx, b->q);
    rs__free(ctx, b->sc);
    rs__free(ctx, b->g);
    memset(b, 0, sizeof *b);
}

/* The scratch of a piece of the normals of a window `cols` wide (at most
 * NM_COLS used) and rows high: the halo region's pixels and the gradient
 * columns. */
static void nm_size(uint32_t cols, uint32_t rows, uint32_t T, size_t *npx, size_t *ncol)
{
    if (cols > NM_COLS) cols = NM_COLS;
    *npx = ((size_t)cols + 2) * ((size_t)rows + 2);
    *ncol = (size_t)cols / T + 3;
}

/* Allocate b (empty) for npx pixels and ncol columns; `paint`, `relief`:
 * those planes too. */
static rs_result nm_alloc(rs_ctx *ctx, nm_scratch *b, size_t npx, size_t ncol, int paint, int relief)
{
    b->cov = rs__alloc_array(ctx, npx, sizeof *b->cov);
    b->ov = rs__alloc_array(ctx, npx, sizeof *b->ov);
    b->q = rs__alloc_array(ctx, npx, sizeof *b->q);
    b->sc = rs__alloc_array(ctx, npx * 3, sizeof *b->sc);
    b->paint = paint ? rs__alloc_array(ctx, npx, sizeof *b->paint) : NULL;
    b->lum = relief ? rs__alloc_array(ctx, npx, sizeof *b->lum) : NULL;
    b->g = rs__alloc_array(ctx, ncol * 4, sizeof *b->g);
    b->npx = npx;
    b->ncol = ncol;
    if (!b->cov || !b->ov || !b->q || !b->sc || (paint && !b->paint) || (relief && !b->lum) || !b->g) {
        rs__nm_scratch_free(ctx, b);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for normal-map scratch (%zu pixels)", npx);
    }
    return RS_OK;
}

rs_result rs__nm_scratch_reserve(rs_ctx *ctx, const rs_splatter *s, uint32_t max_w, rs__nm_scratch *b)
{
    size_t npx, ncol;
    nm_size(max_w, s->o.texels, s->o.texels, &npx, &ncol);
    if (b->npx >= npx && b->ncol >= ncol) return RS_OK;
    rs__nm_scratch_free(ctx, b);
    return nm_alloc(ctx, b, npx, ncol, 1, 1);
}

/* Options with the defaults filled in, or RS_ERR_INVALID_ARG. */
static rs_result nm_defaults(rs_ctx *ctx, const rs_normal_options *in, rs_normal_options *o)
{
    rs_result r = RS__OPTS_IN(ctx, in, o, rs_normal_options);
    if (r) return r;
    if (o->strength == 0) o->strength = 1;
    if (o->paint_height == 0) o->paint_height = NM_PAINT;
    if (!(o->strength > 0 && o->strength <= 1e6))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "normal map: strength %g must be in (0, 1e6]", o->strength);
    if (!(o->paint_height > 0 && o->paint_height <= 1))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "normal map: paint_height %g must be in (0, 1] metres",
                        o->paint_height);
    return RS_OK;
}

/* Luminance (0..1, Rec. 709 weights on the stored bytes) of the bilinear
 * sample of the road texture at the centre of pixel (px, py); the texture
 * coordinates of the surface stage (lib/splat/surface.c texture_axis). Pixel
 * coordinates may be -1 (beyond the image): the texture repeats. */
static void tex_axis(int64_t p, double texel_m, double scale, uint32_t size, uint32_t *i0, uint32_t *i1, double *f)
{
    const int64_t S = size;
    double u = ((double)p + 0.5) * texel_m / scale;
    u = (u - floor(u)) * (double)S - 0.5;
    double fu = floor(u);
    int64_t x0 = (int64_t)fu;
    int64_t a = x0 >= 0 && x0 < S ? x0 : ((x0 % S) + S) % S;
    *i0 = (uint32_t)a;
    *i1 = (uint32_t)(a + 1 == S ? 0 : a + 1);
    *f = u - fu;
}

static double luminance(const rs_splatter *s, const rs_image *img, int64_t px, int64_t py)
{
    uint32_t x0, x1, y0, y1;
    double fx, fy;
    double scale = s->o.surface.texture_scale;
    /* on the map's pixel grid, as the colour (rs_surface_options.texel_offset_x/y) */
    tex_axis(px + s->o.surface.texel_offset_x, s->texel_m, scale, img->width, &x0, &x1, &fx);
    tex_axis(py + s->o.surface.texel_offset_y, s->texel_m, scale, img->height, &y0, &y1, &fy);
    const size_t W4 = 4 * (size_t)img->width;
    const uint8_t *p00 = img->rgba + y0 * W4 + 4 * (size_t)x0, *p01 = img->rgba + y0 * W4 + 4 * (size_t)x1;
    const uint8_t *p10 = img->rgba + y1 * W4 + 4 * (size_t)x0, *p11 = img->rgba + y1 * W4 + 4 * (size_t)x1;
    static const double wt[3] = { 0.2126, 0.7152, 0.0722 };
    double l = 0;
    for (int c = 0; c < 3; c++)
        l += wt[c] * ((p00[c] * (1 - fx) + p01[c] * fx) * (1 - fy) + (p10[c] * (1 - fx) + p11[c] * fx) * fy);
    return l / 255.0;
}

/* The surface image's share of the luminance at the centre of pixel (px,
 * py) over the base luminance `base`: the nearest road within two pixels
 * (so the 3 x 3 neighbours of a road pixel see the image clamped across,
 * not a step at the road edge), when its style has a surface image. */
static double image_luminance(const rs__styling *st, double pix, int64_t px, int64_t py, double base)
{
    rs__road_point rp;
    double x = ((double)px + 0.5) * pix, y = ((double)py + 0.5) * pix, im[4];
    if (!st->near || !rs__roadfield_nearest_ranked(st->near, x, y, 2 * pix, st->prio, &rp)) return base;
    if (!rs__styling_image(st, rp.road, rp.s, rp.t, im)) return base;
    return (0.2126 * im[0] + 0.7152 * im[1] + 0.0722 * im[2]) / 255.0 + (1 - im[3]) * base;
}

/* Road weight (cov, q) and, when `paint`, the paint coverage of lines and
 * markings over the region [hx0, hx0 + hw) x [hy0, hy0 + hh), cut into
 * pieces inside one DEM-cell row each (the coverage stages need that).
 * Paint coverage: the overlays' lines and markings blend c' = c (1 - a) +
 * colour a, layer by layer, which is affine in the base colour c; painting
 * once over 0 and once over 1 gives the transmittance as the difference. */
static void region_fields(const rs_splatter *s, const nm_scratch *b, uint32_t hx0, uint32_t hy0, uint32_t hw,
                          uint32_t hh, int paint)
{
    const uint32_t T = s->o.texels;
    const rs__styling *st = s->grid->styling;
    const int analytic = s->o.coverage.edges == RS_EDGES_ANALYTIC;
    for (uint32_t y = hy0; y < hy0 + hh;) {
        rs__piece p;
        memset(&p, 0, sizeof p);
        p.crow = y / T;
        uint32_t end = (p.crow + 1) * T;
        if (end > hy0 + hh) end = hy0 + hh;
        size_t at = (size_t)(y - hy0) * hw;
        p.x0 = hx0;
        p.w = hw;
        p.y0 = y;
        p.rows = end - y;
        p.cov = b->cov + at;
        p.q = b->q + at;
        p.ov = b->ov + at;
        p.sc = b->sc + 3 * at;
        if (analytic) rs__coverage_analytic(s, &p);
        else rs__coverage_alphamap(s, &p);
        rs__coverage_quantise(&p);
        if (paint && p.road_pixels) {
            const size_t n = (size_t)p.rows * hw;
            double *pt = b->paint + at;
            for (int pass = 0; pass < 2; pass++) {
                float base = (float)pass;
                for (size_t i = 0; i < 3 * n; i++) p.sc[i] = base;
                if (st && st->lines)
                    rs__linesym_paint(st->lines, p.x0, p.y0, p.w, p.rows, p.sc, (size_t)p.w * 3, p.ov);
                if (s->grid->markings) rs__markings_paint(s->grid->markings, &p);
                for (uint32_t r = 0; r < p.rows; r++)
                    for (uint32_t k = 0; k < hw; k++) {
                        double v = p.sc[(size_t)r * hw * 3 + k];
                        if (pass == 0) pt[(size_t)r * hw + k] = v;
                        else {
                            double a = 1 - (v - pt[(size_t)r * hw + k]);
                            pt[(size_t)r * hw + k] = a < 0 ? 0 : (a > 1 ? 1 : a);
                        }
                    }
            }
        } else if (paint) {
            memset(b->paint + at, 0, (size_t)p.rows * hw * sizeof *b->paint);
        }
        y = end;
    }
}

/* Sobel gradient (per pixel, x right, y down) of the region plane f at
 * (r, k), neighbours clamped to the region (which is the image's edge
 * wherever the region stops short of the halo). */
static void sobel(const double *f, size_t hw, uint32_t hh, uint32_t r, uint32_t k, double *gx, double *gy)
{
    size_t ku = k > 0 ? k - 1 : k, kd = k + 1 < hw ? k + 1 : k;
    uint32_t ru = r > 0 ? r - 1 : r, rd = r + 1 < hh ? r + 1 : r;
    const double *a = f + (size_t)ru * hw, *m = f + (size_t)r * hw, *c = f + (size_t)rd * hw;
    *gx = ((a[kd] + 2 * m[kd] + c[kd]) - (a[ku] + 2 * m[ku] + c[ku])) / 8;
    *gy = ((c[ku] + 2 * c[k] + c[kd]) - (a[ku] + 2 * a[k] + a[kd])) / 8;
}

static uint8_t enc(double n)
{
    double v = (n * 0.5 + 0.5) * 255 + 0.5;
    return (uint8_t)(v >= 0 ? (v >= 255 ? 255 : v) : 0);
}

rs_result rs_normal_window(rs_ctx *ctx, const rs_splatter *s, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                           uint8_t *rgb, size_t rgb_stride, const rs_normal_options *opts)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!s || !rgb) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_normal_window");
    rs_normal_options o;
    rs_result res = nm_defaults(ctx, opts, &o);
    if (res) return res;
    if (w == 0 || h == 0 || x0 >= s->out_w || y0 >= s->out_h || w > s->out_w - x0 || h > s->out_h - y0)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "window %u,%u %ux%u is empty or outside the %ux%u image", x0, y0, w,
                        h, s->out_w, s->out_h);
    if (rgb_stride / 3 < w)
        return rs__fail(ctx, RS_ERR_BUFFER_TOO_SMALL, "RGB row stride %zu bytes, need %zu", rgb_stride,
                        (size_t)w * 3);
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, h, 1);
    res = rs__progress_end(ctx, &pg, rs__normals_window(ctx, s, x0, y0, w, h, &o, rgb, rgb_stride));
    if (!res) rs__ok(ctx);
    return res;
}

rs_result rs__normal_check(rs_ctx *ctx, const rs_normal_options *o)
{
    rs_normal_options d;
    return nm_defaults(ctx, o, &d);
}

rs_result rs__lighting_check(rs_ctx *ctx, const rs_lighting_options *l)
{
    rs_normal_options o;
    rs_result r = nm_defaults(ctx, &l->normal, &o);
    if (r) return r;
    if (l->sun_given && !(l->sun_azimuth >= -1e6 && l->sun_azimuth <= 1e6))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "lighting: sun azimuth %g must be finite (degrees)", l->sun_azimuth);
    /* (an altitude so small that its sine rounds to 0 is the horizon: the
     * shading divides by that sine) */
    if (l->sun_given && !(l->sun_altitude > 0 && l->sun_altitude <= 90 && sin(l->sun_altitude * RS__PI / 180.0) > 0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "lighting: sun altitude %g must be in (0, 90] degrees",
                        l->sun_altitude);
    if (!(l->ambient >= 0 && l->ambient <= 1))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "lighting: ambient %g must be in (0, 1] (0 = 0.3)", l->ambient);
    if (!(l->specular >= 0 && l->specular <= 1))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "lighting: specular %g must be in [0, 1]", l->specular);
    return RS_OK;
}

/* The colour of one pixel (rgba) lit with unit normal n (tangent space)
 * and road weight R (docs/surface.md). */
static void light_pixel(const rs_splatter *s, const double n[3], double R, uint8_t *px)
{
    const double *L = s->light, *Hv = s->half;
    double d = n[0] * L[0] + n[1] * L[1] + n[2] * L[2];
    if (!(d > 0)) d = 0;
    double f = s->ambient + (1 - s->ambient) * d / L[2];
    double sp = 0;
    if (s->specular > 0 && R > 0) {
        double hd = n[0] * Hv[0] + n[1] * Hv[1] + n[2] * Hv[2];
        if (hd > 0) {
            double h2 = hd * hd, h4 = h2 * h2, h8 = h4 * h4, h32 = h8 * h8 * h8 * h8;
            sp = 255 * s->specular * (R > 1 ? 1 : R) * h32 * h8; /* hd^40 */
        }
    }
    for (int c = 0; c < 3; c++) {
        double v = px[c] * f + sp + 0.5;
        px[c] = (uint8_t)(v >= 255 ? 255 : (v > 0 ? v : 0));
    }
}

rs_result rs__normals_run(rs_ctx *ctx, const rs_splatter *s, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                          const rs_normal_options *opts, uint8_t *rgb, size_t rgb_stride, uint8_t *rgba,
                          size_t rgba_stride, rs__nm_scratch *keep)
{
    rs_normal_options o;
    rs_result res = nm_defaults(ctx, opts, &o);
    if (res) return res;
    const uint32_t T = s->o.texels;
    const rs_dem *d = s->dem;
    const rs_image *tex = s->o.surface.road_texture;
    const rs__styling *st = s->grid->styling;
    const int paint = !o.no_paint && ((st && st->lines) || s->grid->markings);
    const int images = st && st->img_of;
    const int relief = tex || images;
    const double pix = s->texel_m;
    uint32_t cols = w < NM_COLS ? w : NM_COLS;
    uint32_t max_rows = T < h ? T : h;
    size_t npx, ncol;
    nm_size(cols, max_rows, T, &npx, &ncol);
    nm_scratch b;
    memset(&b, 0, sizeof b);
    if (keep && keep->npx >= npx && keep->ncol >= ncol) {
        /* a workspace's (rs__nm_scratch_reserve: every plane) */
        b = *keep;
        ncol = b.ncol;
    } else {
        keep = NULL;
        if ((res = nm_alloc(ctx, &b, npx, ncol, paint, relief)) != RS_OK) return res;
    }
    double fxt[NM_FXT];
    for (uint32_t t = 0; t < NM_FXT && t < T; t++) fxt[t] = (t + 0.5) / T;
    /* progress (rs__progress_begin: rs_normal_window's, or the splat
     * window's when lighting it): a poll every few pieces, rows at the end
     * of a band (the splat window counts its own) */
    uint32_t pieces = 0;
    for (uint32_t y = y0; y < y0 + h && !res;) {
        uint32_t crow = y / T, end = (crow + 1) * T;
        if (end > y0 + h) end = y0 + h;
        uint32_t rows = end - y;
        for (uint32_t x = x0; x < x0 + w; x += cols) {
            if ((++pieces & 7) == 0 && rs__poll(ctx)) {
                res = RS_ERR_CANCELLED;
                break;
            }
            uint32_t pw = x0 + w - x < cols ? x0 + w - x : cols;
            /* Horn's gradient at the samples around the piece */
            uint32_t c0 = x / T, c1 = (x + pw - 1) / T + 1;
            double *gx0 = b.g, *gy0 = b.g + ncol, *gx1 = b.g + 2 * ncol, *gy1 = b.g + 3 * ncol;
            for (uint32_t c = c0; c <= c1; c++) {
                rs__dem_horn(s->z, d->width, d->height, d->frame.cell_size, d->frame.z_scale, crow, c, &gx0[c - c0],
                             &gy0[c - c0]);
                rs__dem_horn(s->z, d->width, d->height, d->frame.cell_size, d->frame.z_scale, crow + 1, c,
                             &gx1[c - c0], &gy1[c - c0]);
            }
            /* the halo region: one pixel more on each side inside the image */
            uint32_t hx0 = x > 0 ? x - 1 : x, hy0 = y > 0 ? y - 1 : y;
            uint32_t hx1 = x + pw < s->out_w ? x + pw + 1 : x + pw, hy1 = y + rows < s->out_h ? y + rows + 1 : y + rows;
            uint32_t rw = hx1 - hx0, rh = hy1 - hy0, ox = x - hx0, oy = y - hy0;
            region_fields(s, &b, hx0, hy0, rw, rh, paint);
            int road = 0;
            for (uint32_t r = 0; r < rows && !road; r++)
                for (uint32_t k = 0; k < pw && !road; k++) road = b.q[(size_t)(r + oy) * rw + k + ox] != 0;
            if (road && relief)
                for (uint32_t r = 0; r < rh; r++)
                    for (uint32_t k = 0; k < rw; k++) {
                        int64_t px = (int64_t)hx0 + k, py = (int64_t)hy0 + r;
                        double l = tex ? luminance(s, tex, px, py) : 0;
                        b.lum[(size_t)r * rw + k] = images ? image_luminance(st, pix, px, py, l) : l;
                    }
            for (uint32_t r = 0; r < rows; r++) {
                uint32_t py = y + r;
                double fy = ((py - crow * T) + 0.5) / T, gy_ = 1 - fy;
                uint8_t *out = rgba ? rgba + (size_t)(py - y0) * rgba_stride + (size_t)(x - x0) * 4
                                    : rgb + (size_t)(py - y0) * rgb_stride + (size_t)(x - x0) * 3;
                /* the column's cell and offset in it counted along (no
                 * division per pixel), its weight from the table: the same
                 * doubles as ((px mod T) + 0.5) / T */
                uint32_t cc = x / T - c0, off = x % T;
                for (uint32_t k = 0; k < pw; k++, off++) {
                    if (off == T) {
                        off = 0;
                        cc++;
                    }
                    double fx = off < NM_FXT ? fxt[off] : (off + 0.5) / T, gx_ = 1 - fx;
                    double gx = (gx0[cc] * gx_ + gx0[cc + 1] * fx) * gy_ + (gx1[cc] * gx_ + gx1[cc + 1] * fx) * fy;
                    double gy = (gy0[cc] * gx_ + gy0[cc + 1] * fx) * gy_ + (gy1[cc] * gx_ + gy1[cc + 1] * fx) * fy;
                    size_t at = (size_t)(r + oy) * rw + k + ox;
                    double R = b.cov[at];
                    if (R > 0 && (relief || paint)) {
                        double dx = 0, dy = 0, ax, ay;
                        if (relief) {
                            sobel(b.lum, rw, rh, r + oy, k + ox, &ax, &ay);
                            dx += o.strength * ax;
                            dy += o.strength * ay;
                        }
                        if (paint) {
                            sobel(b.paint, rw, rh, r + oy, k + ox, &ax, &ay);
                            dx += o.paint_height / pix * ax;
                            dy += o.paint_height / pix * ay;
                        }
                        R = R > 1 ? 1 : R;
                        gx += R * dx;
                        gy += R * dy;
                    }
                    /* tangent space: X east, Y north (-y), Z up; a
                     * height field's normal is (-dz/dx, -dz/dy, 1) in
                     * the map frame, so Y = +dz/dy (y down) */
                    double m = fabs(gx) > fabs(gy) ? fabs(gx) : fabs(gy);
                    /* (x / 1 is x: no division for the slopes up to 45 degrees) */
                    double nx = -gx, ny = gy, nz = 1;
                    if (m > 1) nx = -gx / m, ny = gy / m, nz = 1 / m;
                    double len = sqrt(nx * nx + ny * ny + nz * nz);
                    if (!(len > 0 && len < HUGE_VAL)) nx = 0, ny = 0, nz = len = 1;
                    if (rgba) {
                        const double n[3] = { nx / len, ny / len, nz / len };
                        light_pixel(s, n, b.cov[at], out + 4 * (size_t)k);
                        continue;
                    }
                    if (o.directx) ny = -ny;
                    out[3 * k] = enc(nx / len);
                    out[3 * k + 1] = enc(ny / len);
                    out[3 * k + 2] = enc(nz / len);
                }
            }
        }
        y = end;
        if (!res && rgb && rs__tick(ctx, rows)) res = RS_ERR_CANCELLED;
    }
    if (!keep) rs__nm_scratch_free(ctx, &b);
    return res;
}
