/* Ground truth and error measures: see groundtruth.h and docs/error-measures.md.
 *
 * Every road polyline is cut into capsules (segment + radius w/2); the road
 * area is their union. A uniform grid lists, per grid cell, every capsule
 * that comes within `margin` of the cell, so one lookup answers "which
 * capsules can touch this pixel". */
#include "groundtruth.h"
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct gt_seg {
    double ax, ay, bx, by; /* centreline end points */
    double ux, uy, len;    /* unit direction (0,0 for a single point) and length */
    double r;              /* half width */
} gt_seg;

struct gt_index {
    gt_seg *seg;
    size_t nseg;
    double gx0, gy0, g, margin; /* grid origin, cell size, list reach */
    uint32_t gw, gh;
    size_t *start; /* gw*gh+1 offsets into item */
    uint32_t *item;
    size_t maxlist;
};

static double gt_seg_dist(const gt_seg *s, double x, double y)
{
    double dx = x - s->ax, dy = y - s->ay, t = dx * s->ux + dy * s->uy;
    if (t < 0) t = 0;
    else if (t > s->len) t = s->len;
    dx -= t * s->ux;
    dy -= t * s->uy;
    return sqrt(dx * dx + dy * dy);
}

static void gt_seg_set(gt_seg *s, double ax, double ay, double bx, double by, double r)
{
    double dx = bx - ax, dy = by - ay, len = sqrt(dx * dx + dy * dy);
    s->ax = ax; s->ay = ay; s->bx = bx; s->by = by; s->r = r; s->len = len;
    s->ux = len > 0 ? dx / len : 0;
    s->uy = len > 0 ? dy / len : 0;
}

/* Grid cell of a point; 0 if outside the grid. */
static int gt_cell_of(const gt_index *ix, double x, double y, uint32_t *cx, uint32_t *cy)
{
    double fx = (x - ix->gx0) / ix->g, fy = (y - ix->gy0) / ix->g;
    if (!(fx >= 0 && fy >= 0 && fx < ix->gw && fy < ix->gh)) return 0;
    *cx = (uint32_t)fx;
    *cy = (uint32_t)fy;
    return 1;
}

void gt_index_free(gt_index *ix)
{
    if (!ix) return;
    free(ix->seg);
    free(ix->start);
    free(ix->item);
    free(ix);
}

/* Calls visit(ix, seg, cellidx) for every grid cell whose list gets `seg`. */
static size_t gt_insert(gt_index *ix, size_t si, int fill, size_t *pos)
{
    const gt_seg *s = &ix->seg[si];
    double reach = s->r + ix->margin, slack = ix->g * 0.70710678118654757 + 1e-9;
    double x0 = fmin(s->ax, s->bx) - reach, x1 = fmax(s->ax, s->bx) + reach;
    double y0 = fmin(s->ay, s->by) - reach, y1 = fmax(s->ay, s->by) + reach;
    double fx0 = floor((x0 - ix->gx0) / ix->g), fx1 = floor((x1 - ix->gx0) / ix->g);
    double fy0 = floor((y0 - ix->gy0) / ix->g), fy1 = floor((y1 - ix->gy0) / ix->g);
    long i, j, i0, i1, j0, j1;
    size_t count = 0;
    if (fx1 < 0 || fy1 < 0 || fx0 >= ix->gw || fy0 >= ix->gh) return 0;
    i0 = fx0 < 0 ? 0 : (long)fx0;
    j0 = fy0 < 0 ? 0 : (long)fy0;
    i1 = fx1 >= ix->gw ? (long)ix->gw - 1 : (long)fx1;
    j1 = fy1 >= ix->gh ? (long)ix->gh - 1 : (long)fy1;
    for (j = j0; j <= j1; j++)
        for (i = i0; i <= i1; i++) {
            double cx = ix->gx0 + (i + 0.5) * ix->g, cy = ix->gy0 + (j + 0.5) * ix->g;
            if (gt_seg_dist(s, cx, cy) > reach + slack) continue;
            count++;
            if (fill) {
                size_t c = (size_t)j * ix->gw + (size_t)i;
                ix->item[pos[c]++] = (uint32_t)si;
            } else
                pos[(size_t)j * ix->gw + (size_t)i]++;
        }
    return count;
}

gt_index *gt_index_new(const sc_scene *s, double margin)
{
    gt_index *ix = calloc(1, sizeof *ix);
    size_t i, k, n = 0, total = 0, ncell, *pos = NULL;
    double ex = sc_extent_x(s), ey = sc_extent_y(s), big = ex > ey ? ex : ey, pad;
    if (!ix) return NULL;
    for (i = 0; i < s->nroads; i++) n += s->roads[i].n;
    ix->seg = malloc((n ? n : 1) * sizeof *ix->seg);
    if (!ix->seg) goto fail;
    for (i = 0; i < s->nroads; i++) {
        const sc_road *r = &s->roads[i];
        size_t first = ix->nseg;
        for (k = 0; k + 1 < r->n; k++) {
            const double *p = r->xy + 2 * k;
            if (p[0] == p[2] && p[1] == p[3]) continue; /* repeated point: inside its neighbours */
            gt_seg_set(&ix->seg[ix->nseg++], p[0], p[1], p[2], p[3], r->width * 0.5);
        }
        if (ix->nseg == first && r->n > 0) /* a single point: a disc */
            gt_seg_set(&ix->seg[ix->nseg++], r->xy[0], r->xy[1], r->xy[0], r->xy[1], r->width * 0.5);
    }
    ix->margin = margin > 0 ? margin : 0;
    ix->g = big / 256;
    if (ix->g < 2) ix->g = 2;
    pad = 2 * ix->g;
    ix->gx0 = -pad;
    ix->gy0 = -pad;
    ix->gw = (uint32_t)ceil((ex + 2 * pad) / ix->g);
    ix->gh = (uint32_t)ceil((ey + 2 * pad) / ix->g);
    ncell = (size_t)ix->gw * ix->gh;
    ix->start = calloc(ncell + 1, sizeof *ix->start);
    pos = calloc(ncell + 1, sizeof *pos);
    if (!ix->start || !pos) goto fail;
    for (i = 0; i < ix->nseg; i++) total += gt_insert(ix, i, 0, pos);
    ix->item = malloc((total ? total : 1) * sizeof *ix->item);
    if (!ix->item) goto fail;
    for (k = 0, i = 0; k < ncell; k++) {
        size_t c = pos[k];
        ix->start[k] = i;
        pos[k] = i;
        i += c;
        if (c > ix->maxlist) ix->maxlist = c;
    }
    ix->start[ncell] = i;
    for (i = 0; i < ix->nseg; i++) gt_insert(ix, i, 1, pos);
    free(pos);
    return ix;
fail:
    free(pos);
    gt_index_free(ix);
    return NULL;
}

static double gt_brute_sd(const gt_index *ix, double x, double y)
{
    double best = HUGE_VAL;
    size_t i;
    for (i = 0; i < ix->nseg; i++) {
        double d = gt_seg_dist(&ix->seg[i], x, y) - ix->seg[i].r;
        if (d < best) best = d;
    }
    return best;
}

static double gt_scan_cell(const gt_index *ix, long cx, long cy, double x, double y, double best)
{
    size_t c = (size_t)cy * ix->gw + (size_t)cx, k;
    for (k = ix->start[c]; k < ix->start[c + 1]; k++) {
        const gt_seg *s = &ix->seg[ix->item[k]];
        double d = gt_seg_dist(s, x, y) - s->r;
        if (d < best) best = d;
    }
    return best;
}

double gt_signed_distance(const gt_index *ix, double x, double y)
{
    uint32_t ucx, ucy;
    long cx, cy, k, i;
    double best = HUGE_VAL;
    if (!gt_cell_of(ix, x, y, &ucx, &ucy)) return gt_brute_sd(ix, x, y);
    cx = ucx;
    cy = ucy;
    /* Rings of cells around the point. A capsule listed in none of the cells
     * of the square searched so far keeps > margin from all of it, so it is
     * farther than margin + (distance from the point to the square's border). */
    for (k = 0;; k++) {
        long x0 = cx - k, x1 = cx + k, y0 = cy - k, y1 = cy + k;
        double bx0, bx1, by0, by1, reach;
        if (k == 0)
            best = gt_scan_cell(ix, cx, cy, x, y, best);
        else {
            for (i = x0; i <= x1; i++) {
                if (i < 0 || i >= (long)ix->gw) continue;
                if (y0 >= 0) best = gt_scan_cell(ix, i, y0, x, y, best);
                if (y1 < (long)ix->gh) best = gt_scan_cell(ix, i, y1, x, y, best);
            }
            for (i = y0 + 1; i <= y1 - 1; i++) {
                if (i < 0 || i >= (long)ix->gh) continue;
                if (x0 >= 0) best = gt_scan_cell(ix, x0, i, x, y, best);
                if (x1 < (long)ix->gw) best = gt_scan_cell(ix, x1, i, x, y, best);
            }
        }
        if (x0 < 0) x0 = 0;
        if (y0 < 0) y0 = 0;
        if (x1 >= (long)ix->gw) x1 = (long)ix->gw - 1;
        if (y1 >= (long)ix->gh) y1 = (long)ix->gh - 1;
        bx0 = x - (ix->gx0 + x0 * ix->g);
        bx1 = ix->gx0 + (x1 + 1) * ix->g - x;
        by0 = y - (ix->gy0 + y0 * ix->g);
        by1 = ix->gy0 + (y1 + 1) * ix->g - y;
        reach = fmin(fmin(bx0, bx1), fmin(by0, by1));
        if (best <= ix->margin + reach) return best;
        if (x0 == 0 && y0 == 0 && x1 == (long)ix->gw - 1 && y1 == (long)ix->gh - 1) break;
    }
    /* capsules entirely off the grid */
    return fmin(best, gt_brute_sd(ix, x, y));
}

/* --- coverage ------------------------------------------------------------------ */

/* Capsule ∩ horizontal line y: one interval (the capsule is convex), the hull
 * of the end discs' and the swept rectangle's intervals. */
static int gt_row_interval(const gt_seg *s, double y, double *lo, double *hi)
{
    double l = HUGE_VAL, h = -HUGE_VAL, dy, r2 = s->r * s->r;
    dy = y - s->ay;
    if (dy * dy <= r2) {
        double q = sqrt(r2 - dy * dy);
        l = fmin(l, s->ax - q);
        h = fmax(h, s->ax + q);
    }
    dy = y - s->by;
    if (dy * dy <= r2) {
        double q = sqrt(r2 - dy * dy);
        l = fmin(l, s->bx - q);
        h = fmax(h, s->bx + q);
    }
    if (s->len > 0) {
        /* 0 <= (p-a).u <= len and -r <= (p-a).n <= r, n = (-uy, ux), p = (x, y) */
        double rl = -HUGE_VAL, rh = HUGE_VAL, k;
        int c;
        for (c = 0; c < 2; c++) {
            double a = c == 0 ? s->ux : -s->uy, c0 = c == 0 ? 0 : -s->r, c1 = c == 0 ? s->len : s->r;
            k = c == 0 ? -s->ax * s->ux + (y - s->ay) * s->uy : s->ax * s->uy + (y - s->ay) * s->ux;
            if (fabs(a) < 1e-15) {
                if (k < c0 || k > c1) { rl = 1; rh = 0; }
            } else {
                double t0 = (c0 - k) / a, t1 = (c1 - k) / a;
                if (t0 > t1) { double t = t0; t0 = t1; t1 = t; }
                rl = fmax(rl, t0);
                rh = fmin(rh, t1);
            }
        }
        if (rl <= rh) {
            l = fmin(l, rl);
            h = fmax(h, rh);
        }
    }
    *lo = l;
    *hi = h;
    return l <= h;
}

/* Length of the union of the capsules' row intervals inside [x0, x1]. */
static double gt_row_cover(const gt_seg *const *rel, size_t n, double y, double x0, double x1, double *buf)
{
    size_t i, m = 0, j;
    double total = 0, cl, ch;
    for (i = 0; i < n; i++) {
        double l, h;
        if (!gt_row_interval(rel[i], y, &l, &h)) continue;
        if (l < x0) l = x0;
        if (h > x1) h = x1;
        if (l >= h) continue;
        /* insertion by left end */
        for (j = m; j > 0 && buf[2 * (j - 1)] > l; j--) {
            buf[2 * j] = buf[2 * (j - 1)];
            buf[2 * j + 1] = buf[2 * (j - 1) + 1];
        }
        buf[2 * j] = l;
        buf[2 * j + 1] = h;
        m++;
    }
    if (m == 0) return 0;
    cl = buf[0];
    ch = buf[1];
    for (i = 1; i < m; i++) {
        if (buf[2 * i] > ch) {
            total += ch - cl;
            cl = buf[2 * i];
            ch = buf[2 * i + 1];
        } else if (buf[2 * i + 1] > ch)
            ch = buf[2 * i + 1];
    }
    return total + (ch - cl);
}

static void gt_push_y(double *ys, size_t *n, double y, double y0, double y1)
{
    if (y > y0 && y < y1) ys[(*n)++] = y;
}

static int gt_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Where two capsule outlines cross, the row cover has a kink: those y are
 * breakpoints too. Sides are segments p + t u, t in [0, len]. */
static void gt_side(const gt_seg *s, int side, double *px, double *py)
{
    *px = s->ax - side * s->uy * s->r;
    *py = s->ay + side * s->ux * s->r;
}

static void gt_push_xy(double *ys, size_t *n, double x, double y, double x0, double y0, double x1, double y1)
{
    if (x >= x0 && x <= x1) gt_push_y(ys, n, y, y0, y1);
}

static void gt_line_circle(double px, double py, double ux, double uy, double len, double cx, double cy, double r,
                           double *ys, size_t *n, double x0, double y0, double x1, double y1)
{
    double dx = px - cx, dy = py - cy, b = ux * dx + uy * dy, c = dx * dx + dy * dy - r * r, disc = b * b - c, q;
    int k;
    if (disc < 0) return;
    q = sqrt(disc);
    for (k = -1; k <= 1; k += 2) {
        double t = -b + k * q;
        if (t >= 0 && t <= len) gt_push_xy(ys, n, px + t * ux, py + t * uy, x0, y0, x1, y1);
    }
}

static void gt_pair_crossings(const gt_seg *a, const gt_seg *b, double *ys, size_t *n, double x0, double y0,
                              double x1, double y1)
{
    int sa, sb, ka, kb;
    double ra = a->r, rb = b->r;
    /* side x side */
    if (a->len > 0 && b->len > 0)
        for (sa = -1; sa <= 1; sa += 2)
            for (sb = -1; sb <= 1; sb += 2) {
                double px, py, qx, qy, den, wx, wy, t, u;
                gt_side(a, sa, &px, &py);
                gt_side(b, sb, &qx, &qy);
                den = a->ux * b->uy - a->uy * b->ux;
                if (fabs(den) < 1e-12) continue;
                wx = qx - px;
                wy = qy - py;
                t = (wx * b->uy - wy * b->ux) / den;
                u = (wx * a->uy - wy * a->ux) / den;
                if (t >= 0 && t <= a->len && u >= 0 && u <= b->len)
                    gt_push_xy(ys, n, px + t * a->ux, py + t * a->uy, x0, y0, x1, y1);
            }
    /* side x end circle, both ways */
    for (ka = 0; ka < 2; ka++) {
        const gt_seg *s = ka ? b : a, *o = ka ? a : b;
        if (s->len <= 0) continue;
        for (sa = -1; sa <= 1; sa += 2) {
            double px, py;
            gt_side(s, sa, &px, &py);
            gt_line_circle(px, py, s->ux, s->uy, s->len, o->ax, o->ay, o->r, ys, n, x0, y0, x1, y1);
            gt_line_circle(px, py, s->ux, s->uy, s->len, o->bx, o->by, o->r, ys, n, x0, y0, x1, y1);
        }
    }
    /* circle x circle */
    for (ka = 0; ka < 2; ka++)
        for (kb = 0; kb < 2; kb++) {
            double cx = ka ? a->bx : a->ax, cy = ka ? a->by : a->ay, ex = kb ? b->bx : b->ax, ey = kb ? b->by : b->ay;
            double dx = ex - cx, dy = ey - cy, d = sqrt(dx * dx + dy * dy), l, hh;
            if (d <= 0 || d > ra + rb || d < fabs(ra - rb)) continue;
            l = (ra * ra - rb * rb + d * d) / (2 * d);
            hh = ra * ra - l * l;
            hh = hh > 0 ? sqrt(hh) : 0;
            gt_push_xy(ys, n, cx + l * dx / d - hh * dy / d, cy + l * dy / d + hh * dx / d, x0, y0, x1, y1);
            gt_push_xy(ys, n, cx + l * dx / d + hh * dy / d, cy + l * dy / d - hh * dx / d, x0, y0, x1, y1);
        }
}

/* 8-point Gauss-Legendre on [-1, 1]. */
static const double gt_gl_x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
static const double gt_gl_w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};

/* Area of (union of capsules) ∩ [x0,x1]x[y0,y1]. The row cover f(y) is
 * smooth between the y where a disc starts or ends, a rectangle corner sits,
 * a capsule outline crosses x = x0 or x = x1, or two capsule outlines cross;
 * integrate each such piece with Gauss-Legendre. ys needs
 * 2 + 20n + 28 n(n-1)/2 doubles, buf 2n. */
static double gt_pixel_area(const gt_seg *const *rel, size_t n, double x0, double y0, double x1, double y1,
                            double *ys, double *buf)
{
    size_t i, m = 0, k;
    double area = 0;
    ys[m++] = y0;
    for (i = 0; i < n; i++) {
        const gt_seg *s = rel[i];
        double r = s->r, nx = -s->uy * r, ny = s->ux * r, xe;
        int e, side;
        gt_push_y(ys, &m, s->ay - r, y0, y1);
        gt_push_y(ys, &m, s->ay + r, y0, y1);
        gt_push_y(ys, &m, s->by - r, y0, y1);
        gt_push_y(ys, &m, s->by + r, y0, y1);
        if (s->len > 0) {
            gt_push_y(ys, &m, s->ay + ny, y0, y1);
            gt_push_y(ys, &m, s->ay - ny, y0, y1);
            gt_push_y(ys, &m, s->by + ny, y0, y1);
            gt_push_y(ys, &m, s->by - ny, y0, y1);
        }
        for (e = 0; e < 2; e++) {
            xe = e ? x1 : x0;
            for (k = 0; k < 2; k++) { /* end circles */
                double cx = k ? s->bx : s->ax, cy = k ? s->by : s->ay, dx = xe - cx;
                if (dx * dx <= r * r) {
                    double q = sqrt(r * r - dx * dx);
                    gt_push_y(ys, &m, cy - q, y0, y1);
                    gt_push_y(ys, &m, cy + q, y0, y1);
                }
            }
            if (s->len > 0 && fabs(s->ux) > 1e-15)
                for (side = -1; side <= 1; side += 2) { /* the two straight sides */
                    double px = s->ax + side * nx, py = s->ay + side * ny, t = (xe - px) / s->ux;
                    if (t >= 0 && t <= s->len) gt_push_y(ys, &m, py + t * s->uy, y0, y1);
                }
        }
    }
    for (i = 0; i < n; i++)
        for (k = i + 1; k < n; k++) gt_pair_crossings(rel[i], rel[k], ys, &m, x0, y0, x1, y1);
    ys[m++] = y1;
    qsort(ys + 1, m - 2, sizeof *ys, gt_cmp_double);
    for (k = 0; k + 1 < m; k++) {
        double a = ys[k], b = ys[k + 1], mid = 0.5 * (a + b), half = 0.5 * (b - a), sum = 0;
        int q;
        if (half <= 0) continue;
        for (q = 0; q < 4; q++) {
            sum += gt_gl_w[q] * gt_row_cover(rel, n, mid - half * gt_gl_x[q], x0, x1, buf);
            sum += gt_gl_w[q] * gt_row_cover(rel, n, mid + half * gt_gl_x[q], x0, x1, buf);
        }
        area += half * sum;
    }
    return area;
}

static int gt_image_size(const sc_scene *s, unsigned T, size_t *pw, size_t *ph)
{
    if (!s || T == 0 || s->w < 2 || s->h < 2 || !(s->cell_size > 0)) return -1;
    *pw = (size_t)(s->w - 1) * T;
    *ph = (size_t)(s->h - 1) * T;
    return 0;
}

/* Fills G (mode 0: coverage) or R (mode 1: hard raster of pixel centres). */
static int gt_raster(const sc_scene *s, unsigned T, float *out, int mode)
{
    size_t pw, ph, px, py, k;
    double p, hd;
    gt_index *ix;
    const gt_seg **rel = NULL;
    double *ys = NULL, *buf = NULL;
    if (gt_image_size(s, T, &pw, &ph)) return -1;
    p = s->cell_size / T;
    hd = p * 0.70710678118654757;
    ix = gt_index_new(s, hd * 1.000001);
    if (!ix) return -1;
    rel = malloc((ix->maxlist + 1) * sizeof *rel);
    ys = malloc((2 + 20 * (ix->maxlist + 1) + 14 * (ix->maxlist + 1) * ix->maxlist) * sizeof *ys);
    buf = malloc(2 * (ix->maxlist + 1) * sizeof *buf);
    if (!rel || !ys || !buf) {
        free(rel); free(ys); free(buf);
        gt_index_free(ix);
        return -1;
    }
    for (py = 0; py < ph; py++) {
        double cy = (py + 0.5) * p;
        for (px = 0; px < pw; px++) {
            double cx = (px + 0.5) * p, best = HUGE_VAL;
            uint32_t gx, gy;
            size_t c, n = 0;
            float v = 0;
            if (gt_cell_of(ix, cx, cy, &gx, &gy)) {
                c = (size_t)gy * ix->gw + gx;
                for (k = ix->start[c]; k < ix->start[c + 1]; k++) {
                    const gt_seg *sg = &ix->seg[ix->item[k]];
                    double d = gt_seg_dist(sg, cx, cy) - sg->r;
                    if (d < best) best = d;
                    if (d <= hd) rel[n++] = sg;
                }
            }
            if (mode == 1)
                v = best <= 0 ? 1.0f : 0.0f;
            else if (best < -hd)
                v = 1.0f;
            else if (n > 0) {
                double a = gt_pixel_area(rel, n, px * p, py * p, (px + 1) * p, (py + 1) * p, ys, buf) / (p * p);
                v = (float)(a < 0 ? 0 : a > 1 ? 1 : a);
            }
            out[py * pw + px] = v;
        }
    }
    free(rel);
    free(ys);
    free(buf);
    gt_index_free(ix);
    return 0;
}

int gt_coverage(const sc_scene *s, unsigned T, float *G) { return gt_raster(s, T, G, 0); }
int gt_hard_raster(const sc_scene *s, unsigned T, float *R) { return gt_raster(s, T, R, 1); }

int gt_cell_buffer(const sc_scene *s, unsigned T, float *R)
{
    size_t pw, ph, r, c, i, j;
    gt_index *ix;
    if (gt_image_size(s, T, &pw, &ph)) return -1;
    ix = gt_index_new(s, 0);
    if (!ix) return -1;
    for (r = 0; r + 1 < s->h; r++)
        for (c = 0; c + 1 < s->w; c++) {
            double x = (c + 0.5) * s->cell_size, y = (r + 0.5) * s->cell_size, best = HUGE_VAL;
            uint32_t gx, gy;
            float v;
            /* inside some capsule <=> listed in the point's own grid cell with d <= 0 */
            if (gt_cell_of(ix, x, y, &gx, &gy)) best = gt_scan_cell(ix, gx, gy, x, y, best);
            v = best <= 0 ? 1.0f : 0.0f;
            for (i = 0; i < T; i++)
                for (j = 0; j < T; j++) R[(r * T + i) * pw + c * T + j] = v;
        }
    gt_index_free(ix);
    return 0;
}

/* Pixel p's centre in cell-centre units (cell c's centre at c), clamped to
 * [0, n-1]: the two cells to blend and the weight of the second. */
static void gt_bilinear_span(size_t p, unsigned T, size_t n, size_t *a, size_t *b, double *t)
{
    double f = (p + 0.5) / T - 0.5;
    if (f < 0) f = 0;
    if (f > (double)(n - 1)) f = (double)(n - 1);
    *a = (size_t)f;
    *b = *a + 1 < n ? *a + 1 : *a;
    *t = f - (double)*a;
}

int gt_cell_buffer_bilinear(const sc_scene *s, unsigned T, float *R)
{
    size_t pw, ph, cw, ch, px, py;
    float *m;
    if (gt_image_size(s, T, &pw, &ph) || gt_cell_buffer(s, T, R)) return -1;
    cw = s->w - 1;
    ch = s->h - 1;
    m = malloc(cw * ch * sizeof *m);
    if (!m) return -1;
    for (py = 0; py < ch; py++)
        for (px = 0; px < cw; px++) m[py * cw + px] = R[py * T * pw + px * T];
    for (py = 0; py < ph; py++) {
        double ty;
        size_t y0, y1;
        gt_bilinear_span(py, T, ch, &y0, &y1, &ty);
        for (px = 0; px < pw; px++) {
            double tx;
            size_t x0, x1;
            gt_bilinear_span(px, T, cw, &x0, &x1, &tx);
            R[py * pw + px] = (float)((1 - ty) * ((1 - tx) * m[y0 * cw + x0] + tx * m[y0 * cw + x1]) +
                                      ty * ((1 - tx) * m[y1 * cw + x0] + tx * m[y1 * cw + x1]));
        }
    }
    free(m);
    return 0;
}

/* --- outline length ---------------------------------------------------------------- */
typedef struct gt_outline_ctx {
    const gt_index *ix;
    double ex, ey;
    size_t self;
} gt_outline_ctx;

/* A boundary point of capsule `self` counts when it is inside the image and
 * not strictly inside another capsule; where two outlines coincide exactly
 * (shared joints, duplicate roads) the lower index keeps it. */
static int gt_outline_keep(const gt_outline_ctx *oc, double x, double y)
{
    const gt_index *ix = oc->ix;
    uint32_t gx, gy;
    size_t c, k;
    if (!(x >= 0 && y >= 0 && x <= oc->ex && y <= oc->ey)) return 0;
    if (!gt_cell_of(ix, x, y, &gx, &gy)) return 0;
    c = (size_t)gy * ix->gw + gx;
    for (k = ix->start[c]; k < ix->start[c + 1]; k++) {
        size_t j = ix->item[k];
        const gt_seg *s;
        double d;
        if (j == oc->self) continue;
        s = &ix->seg[j];
        d = gt_seg_dist(s, x, y) - s->r;
        if (d < -1e-9 || (d <= 1e-9 && j < oc->self)) return 0;
    }
    return 1;
}

/* Boundary piece: a straight side (arc == 0: p(t) = (px,py) + t(ux,uy), t in
 * [0, len]) or an arc (centre (px,py), radius r, angle t in [a0, a0+len/r]). */
typedef struct gt_piece { int arc; double px, py, ux, uy, r, a0, len; } gt_piece;

static void gt_piece_at(const gt_piece *pc, double t, double *x, double *y)
{
    if (pc->arc) {
        double a = pc->a0 + t / pc->r;
        *x = pc->px + pc->r * cos(a);
        *y = pc->py + pc->r * sin(a);
    } else {
        *x = pc->px + t * pc->ux;
        *y = pc->py + t * pc->uy;
    }
}

static int gt_piece_keep(const gt_outline_ctx *oc, const gt_piece *pc, double t)
{
    double x, y;
    gt_piece_at(pc, t, &x, &y);
    return gt_outline_keep(oc, x, y);
}

/* Kept length of a piece: samples every <= ds, bisects each change of state. */
static double gt_piece_length(const gt_outline_ctx *oc, const gt_piece *pc, double ds)
{
    size_t n = (size_t)ceil(pc->len / ds), i;
    double total = 0, tprev = 0;
    int kprev;
    if (n < 1) n = 1;
    kprev = gt_piece_keep(oc, pc, 0);
    for (i = 1; i <= n; i++) {
        double t = pc->len * (double)i / (double)n;
        int k = gt_piece_keep(oc, pc, t);
        if (k == kprev) {
            if (k) total += t - tprev;
        } else {
            double lo = tprev, hi = t;
            int it;
            for (it = 0; it < 48; it++) {
                double mid = 0.5 * (lo + hi);
                if (gt_piece_keep(oc, pc, mid) == kprev) lo = mid;
                else hi = mid;
            }
            total += kprev ? (lo - tprev) : (t - hi);
        }
        tprev = t;
        kprev = k;
    }
    return total;
}

double gt_outline_length(const sc_scene *s, unsigned T)
{
    gt_outline_ctx oc;
    gt_index *ix;
    size_t i;
    double total = 0;
    (void)T;
    if (!s || s->w < 2 || s->h < 2) return -1;
    ix = gt_index_new(s, 0);
    if (!ix) return -1;
    oc.ix = ix;
    oc.ex = sc_extent_x(s);
    oc.ey = sc_extent_y(s);
    for (i = 0; i < ix->nseg; i++) {
        const gt_seg *sg = &ix->seg[i];
        double r = sg->r, ds = fmin(0.25, 0.25 * r);
        gt_piece pc;
        int side;
        if (!(r > 0)) continue;
        oc.self = i;
        pc.r = r;
        if (sg->len > 0) {
            double dir = atan2(sg->uy, sg->ux);
            pc.arc = 0;
            pc.ux = sg->ux;
            pc.uy = sg->uy;
            pc.len = sg->len;
            for (side = -1; side <= 1; side += 2) {
                pc.px = sg->ax - side * sg->uy * r;
                pc.py = sg->ay + side * sg->ux * r;
                total += gt_piece_length(&oc, &pc, ds);
            }
            pc.arc = 1;
            pc.len = 3.14159265358979323846 * r;
            pc.px = sg->bx; /* forward cap: dir - 90deg .. dir + 90deg */
            pc.py = sg->by;
            pc.a0 = dir - 1.5707963267948966;
            total += gt_piece_length(&oc, &pc, ds);
            pc.px = sg->ax; /* back cap */
            pc.py = sg->ay;
            pc.a0 = dir + 1.5707963267948966;
            total += gt_piece_length(&oc, &pc, ds);
        } else {
            pc.arc = 1;
            pc.px = sg->ax;
            pc.py = sg->ay;
            pc.a0 = 0;
            pc.len = 2 * 3.14159265358979323846 * r;
            total += gt_piece_length(&oc, &pc, ds);
        }
    }
    gt_index_free(ix);
    return total;
}

/* --- edge error -------------------------------------------------------------------- */
int gt_edge_error_g(const sc_scene *s, unsigned T, const float *G, double L, const float *R, gt_result *out)
{
    size_t pw, ph, px, py, i, npts = 0;
    double p, sum = 0, dmax = 0, dsum = 0;
    gt_index *ix;
    if (!out || !G || !R || gt_image_size(s, T, &pw, &ph)) return -1;
    memset(out, 0, sizeof *out);
    p = s->cell_size / T;
    for (i = 0; i < pw * ph; i++) {
        if (R[i] != R[i] || G[i] != G[i]) return -1;
        sum += fabs((double)R[i] - (double)G[i]);
    }
    if (L < 0) L = gt_outline_length(s, T);
    if (L < 0) return -1;
    ix = gt_index_new(s, p * 0.70710678118654757);
    if (!ix) return -1;
    /* the drawn edge: R = 0.5 between 4-adjacent pixel centres */
    for (py = 0; py < ph; py++)
        for (px = 0; px < pw; px++) {
            double a = R[py * pw + px];
            int dir;
            for (dir = 0; dir < 2; dir++) {
                double b, t, x, y, d;
                if (dir == 0 && px + 1 >= pw) continue;
                if (dir == 1 && py + 1 >= ph) continue;
                b = dir == 0 ? R[py * pw + px + 1] : R[(py + 1) * pw + px];
                if ((a >= 0.5) == (b >= 0.5)) continue;
                t = (0.5 - a) / (b - a);
                x = (px + 0.5 + (dir == 0 ? t : 0)) * p;
                y = (py + 0.5 + (dir == 1 ? t : 0)) * p;
                d = fabs(gt_signed_distance(ix, x, y));
                if (d > dmax) dmax = d;
                dsum += d;
                npts++;
            }
        }
    gt_index_free(ix);
    out->abs_area = sum * p * p;
    out->outline = L;
    out->edge_error = L > 0 ? out->abs_area / L : 0;
    out->max_disp = dmax;
    out->mean_disp = npts ? dsum / (double)npts : 0;
    out->contour_points = npts;
    return 0;
}

int gt_edge_error(const sc_scene *s, unsigned T, const float *R, gt_result *out)
{
    size_t pw, ph;
    float *G;
    int rc;
    if (gt_image_size(s, T, &pw, &ph)) return -1;
    G = malloc(pw * ph * sizeof *G);
    if (!G) return -1;
    rc = gt_coverage(s, T, G);
    if (rc == 0) rc = gt_edge_error_g(s, T, G, -1, R, out);
    free(G);
    return rc;
}
