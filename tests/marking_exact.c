/* Issue 25: a hard-edged marking against the exact coverage of its
 * rotated rectangle (marking_exact.h). */
#include "marking_exact.h"
#include "markings.h"
#include "splatter.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Clip polygon (n points in xy) to a.x + b.y <= c; returns the new count. */
static int clip(double *xy, int n, double a, double b, double c, double *out)
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        const double *p = xy + 2 * i, *q = xy + 2 * ((i + 1) % n);
        double fp = a * p[0] + b * p[1] - c, fq = a * q[0] + b * q[1] - c;
        if (fp <= 0) {
            out[2 * m] = p[0];
            out[2 * m + 1] = p[1];
            m++;
        }
        if ((fp < 0 && fq > 0) || (fp > 0 && fq < 0)) {
            double t = fp / (fp - fq);
            out[2 * m] = p[0] + t * (q[0] - p[0]);
            out[2 * m + 1] = p[1] + t * (q[1] - p[1]);
            m++;
        }
    }
    return m;
}

double me_pixel_area(double x0, double y0, double p, double cx, double cy, double dx, double dy, double hl,
                     double hw)
{
    double a[32], b[32];
    double sq[8] = { x0, y0, x0 + p, y0, x0 + p, y0 + p, x0, y0 + p };
    memcpy(a, sq, sizeof sq);
    int n = 4;
    /* |(x - c) . d| <= hl, |(x - c) . (dy, -dx)| <= hw */
    n = clip(a, n, dx, dy, hl + dx * cx + dy * cy, b);
    n = clip(b, n, -dx, -dy, hl - dx * cx - dy * cy, a);
    n = clip(a, n, dy, -dx, hw + dy * cx - dx * cy, b);
    n = clip(b, n, -dy, dx, hw - dy * cx + dx * cy, a);
    double s = 0;
    for (int i = 0; i < n; i++) {
        const double *u = a + 2 * i, *v = a + 2 * ((i + 1) % n);
        s += u[0] * v[1] - v[0] * u[1];
    }
    return fabs(0.5 * s);
}

int me_opaque(int shape, uint32_t tw, uint32_t th, uint32_t i, uint32_t j)
{
    if (shape == 0) return 1;
    double x = fabs(i + 0.5 - 0.5 * tw), head = 0.4 * th;
    if (j + 0.5 < head) return x <= 0.5 * tw * (j + 0.5) / head;
    return x < 0.25 * tw;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int me_measure(rs_ctx *ctx, const me_case *c, me_stats *out)
{
    memset(out, 0, sizeof *out);
    /* a flat map of about 24 m, 10 pixels per DEM cell */
    const uint32_t T = 10;
    const double pix = c->pix, cell = pix * T, span = 24;
    const uint32_t n = (uint32_t)ceil(span / cell) + 1;
    const double PI = 3.14159265358979323846;
    int rc = -1;
    float *z = calloc((size_t)n * n, sizeof *z);
    uint8_t *img = malloc((size_t)c->tw * c->th * 4);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_atlas *atlas = NULL;
    rs__markings *mk = NULL;
    double *a = NULL, *err = NULL;
    rs__piece p;
    memset(&p, 0, sizeof p);
    if (!z || !img) goto done;
    memset(img, 255, (size_t)c->tw * c->th * 4);
    size_t nop = 0;
    for (uint32_t j = 0; j < c->th; j++)
        for (uint32_t i = 0; i < c->tw; i++) {
            int on = me_opaque(c->shape, c->tw, c->th, i, j);
            img[((size_t)j * c->tw + i) * 4 + 3] = on ? 255 : 0;
            nop += (size_t)on;
        }
    rs_image im = { c->tw, c->th, img };
    char idx[128];
    snprintf(idx, sizeof idx, "box 0 0 %u %u %.17g %.17g\n", (unsigned)c->tw, (unsigned)c->th, c->length, c->width);
    rs_dem_frame fr = { cell, 1, 0, 0 };
    if (rs_dem_create(ctx, n, n, z, &dem) || rs_dem_set_frame(ctx, dem, &fr) ||
        rs_atlas_create(ctx, &im, idx, strlen(idx), &atlas) || rs_roads_create(ctx, &roads))
        goto done;
    double th = c->angle * PI / 180, dx = cos(th), dy = sin(th), half = 10;
    double mx = 0.5 * (n - 1) * cell + 0.137 + c->ox * pix, my = 0.5 * (n - 1) * cell - 0.211 + c->oy * pix;
    double xy[4] = { mx - half * dx, my - half * dy, mx + half * dx, my + half * dy };
    double s0 = half + 0.31, t0 = 0.23;
    if (rs_roads_add(ctx, roads, "r", 8, xy, 2)) goto done;
    rs_mark m = { "box", 0, s0, t0, 0, 0, 0, 0 };
    if (rs_roads_add_mark(ctx, roads, &m)) goto done;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = T;
    o.markings.atlas = atlas;
    o.markings.no_auto = 1;
    if (rs__markings_build(ctx, dem, roads, &o, NULL, &mk) || !mk) goto done;
    const uint32_t W = (n - 1) * T, H = (n - 1) * T;
    a = calloc((size_t)W * H, sizeof *a);
    err = malloc((size_t)W * H * sizeof *err);
    p.w = W;
    p.rows = 1;
    p.q = malloc(W * sizeof *p.q);
    p.sc = malloc((size_t)W * 3 * sizeof *p.sc);
    if (!a || !err || !p.q || !p.sc) goto done;
    for (uint32_t k = 0; k < W; k++) p.q[k] = 65535;
    for (uint32_t y = 0; y < H; y++) {
        p.y0 = y;
        memset(p.sc, 0, (size_t)W * 3 * sizeof *p.sc);
        rs__markings_paint(mk, &p);
        for (uint32_t k = 0; k < W; k++) a[(size_t)y * W + k] = p.sc[k] / 255.0;
    }
    /* the rectangle: centre P0 + s0 d + t0 n, n = (dy, -dx) (left of travel) */
    double cx = xy[0] + s0 * dx + t0 * dy, cy = xy[1] + s0 * dy - t0 * dx;
    double hl = 0.5 * c->length, hw = 0.5 * c->width, r = hypot(hl, hw) + 2 * pix;
    double sum = 0, sx = 0, sy = 0, esum = 0, ex = 0, ey = 0;
    long ne = 0;
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            double px = x * pix, py = y * pix, v = a[(size_t)y * W + x], e = 0;
            int near = fabs(px + 0.5 * pix - cx) <= r && fabs(py + 0.5 * pix - cy) <= r;
            if (near && c->shape == 0) e = me_pixel_area(px, py, pix, cx, cy, dx, dy, hl, hw) / (pix * pix);
            else if (near) {
                /* each opaque texel's square: its centre at t = t0 + W/2 - (i + 1/2) W/tw, s = s0 + L/2 - (j
                 * + 1/2) L/th */
                double kw = c->width / c->tw, kl = c->length / c->th, reach = 0.75 * pix + kw + kl;
                for (uint32_t j = 0; j < c->th; j++)
                    for (uint32_t i = 0; i < c->tw; i++) {
                        double tt = t0 + hw - (i + 0.5) * kw, ss = s0 + hl - (j + 0.5) * kl;
                        double qx = xy[0] + ss * dx + tt * dy, qy = xy[1] + ss * dy - tt * dx;
                        if (fabs(qx - px - 0.5 * pix) > reach || fabs(qy - py - 0.5 * pix) > reach) continue;
                        if (!me_opaque(c->shape, c->tw, c->th, i, j)) continue;
                        e += me_pixel_area(px, py, pix, qx, qy, dx, dy, 0.5 * kl, 0.5 * kw);
                    }
                e /= pix * pix;
            }
            if (v == 0 && e == 0) continue;
            err[ne++] = fabs(v - e);
            sum += v;
            sx += v * (px + 0.5 * pix);
            sy += v * (py + 0.5 * pix);
            esum += e;
            ex += e * (px + 0.5 * pix);
            ey += e * (py + 0.5 * pix);
        }
    if (ne == 0 || sum == 0 || esum == 0) goto done;
    double tot = 0;
    for (long k = 0; k < ne; k++) tot += err[k];
    qsort(err, (size_t)ne, sizeof *err, cmp_double);
    out->mean = tot / ne;
    out->p99 = err[(size_t)floor(0.99 * (double)(ne - 1))];
    out->area = sum * pix * pix / (c->length * c->width * (double)nop / ((double)c->tw * c->th)) - 1;
    out->centroid = hypot(sx / sum - ex / esum, sy / sum - ey / esum) / pix;
    out->pixels = ne;
    rc = 0;
done:
    free(p.q);
    free(p.sc);
    free(a);
    free(err);
    rs__markings_free(ctx, mk);
    rs_atlas_free(ctx, atlas);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    free(img);
    free(z);
    return rc;
}
