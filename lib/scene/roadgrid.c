/* Road grid: which road cells are road, and their 8-neighbour class.
 *
 * Both marking modes aim the drawn road edge (which runs through the
 * centres of the outermost road cells, seed 000 section 2.2) at the road's
 * true half-width; docs/design.md derives the offsets used here. */
#include "roadgrid.h"
#include "lanes.h"
#include "mask.h"
#include "roadfield.h"
#include "road_local.h"
#include "styling.h"
#include "markings.h"
#include "grid_edit.h"
#include "network.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct marker {
    rs_ctx *ctx;
    rs_road_grid *g;
} marker;

static rs_result mark_span(marker *m, int64_t gy, int64_t x0, int64_t x1)
{
    rs_road_grid *g = m->g;
    if (gy < 0 || gy >= (int64_t)g->gh) return RS_OK;
    if (x0 < 0) x0 = 0;
    if (x1 >= (int64_t)g->gw) x1 = (int64_t)g->gw - 1;
    uint32_t ty = (uint32_t)gy >> RS__TILE_SHIFT, ry = (uint32_t)gy & (RS__TILE - 1);
    while (x0 <= x1) {
        uint32_t tx = (uint32_t)x0 >> RS__TILE_SHIFT;
        uint32_t rx0 = (uint32_t)x0 & (RS__TILE - 1);
        int64_t tile_end = ((int64_t)tx + 1) * RS__TILE - 1;
        int64_t e = x1 < tile_end ? x1 : tile_end;
        uint8_t **slot = &g->tiles[(size_t)ty * g->tw + tx];
        if (!*slot) {
            *slot = rs__calloc(m->ctx, RS__TILE * RS__TILE, 1);
            if (!*slot) return rs__fail(m->ctx, RS_ERR_NOMEM, "out of memory for road grid tiles");
            g->stats.tiles_allocated++;
        }
        memset(*slot + (size_t)ry * RS__TILE + rx0, RS__CELL_ROAD, (size_t)(e - x0 + 1));
        x0 = e + 1;
    }
    return RS_OK;
}

/* Intersect [*lo,*hi] with {x : lo_v <= a*x + b <= hi_v}. */
static void clip_linear(double a, double b, double lo_v, double hi_v, double *lo, double *hi)
{
    if (a == 0) {
        if (b < lo_v || b > hi_v) { *lo = 1; *hi = 0; }
        return;
    }
    double x0 = (lo_v - b) / a, x1 = (hi_v - b) / a;
    if (a < 0) { double t = x0; x0 = x1; x1 = t; }
    if (x0 > *lo) *lo = x0;
    if (x1 < *hi) *hi = x1;
}

/* Rows whose centre lies in [y0,y1] (cell units), clamped to the grid. */
static void row_range(const rs_road_grid *g, double y0, double y1, int64_t *i0, int64_t *i1)
{
    double a = ceil(y0 - 0.5), b = floor(y1 - 0.5);
    if (a < 0) a = 0;
    if (b > (double)g->gh - 1) b = (double)g->gh - 1;
    *i0 = (int64_t)a;
    *i1 = (int64_t)b;
}

/* ---- marking: spans per row ---------------------------------------------------
 *
 * A road is a set of primitives: in distance mode a round cap at every
 * vertex and a band along every segment, in dilate mode a dilated
 * centreline raster per segment. Each primitive gives at most two
 * intervals of cells on each grid row it touches, in O(1) (caps: a binary
 * search on the exact per-cell test), so the primitives of a road are swept
 * row by row: the row's intervals are sorted, merged and marked once. Work
 * is bounded by the rows each primitive spans plus the cells covered, not
 * by the sum of the primitives' areas (a 1e9 m wide road of 1,000 vertices
 * used to mark the whole map 2,000 times). Roads with more primitives than
 * PRIM_BATCH are swept in batches. Every cell marked is one the per-cell
 * tests of docs/design.md accept, as before (byte-identical grids). */

#define PRIM_BATCH 8192
#define CANCEL_ROWS 256 /* rows between progress calls within a road */
#define PROGRESS_STEP 64 /* roads between progress calls of the analytic build's stages */

enum { PRIM_CAP, PRIM_BAND, PRIM_DILATE };

typedef struct prim {
    int64_t i0, i1;   /* rows touched (clamped to the grid) */
    int kind;
    double a, b, c, d; /* cap: px, py; band: clipped A (a, b), B (c, d), cell units */
    double h;          /* cap: half-width (cell units); band: the band radius r */
    int64_t x0, y0, x1, y1, k; /* dilate: end cells, square half-size */
} prim;

typedef struct span { int64_t lo, hi; } span;

typedef struct sweep {
    marker *m;
    prim *p;
    size_t np;
    size_t *active;
    span *iv;
    const rs_splat_options *o; /* progress */
    uint64_t done, total;      /* progress: roads */
    uint64_t rows;             /* rows swept since the last progress call */
} sweep;

/* Exact per-cell test of a round cap (the cell centre at offset d from the
 * point is road when |d| <= h + (|dx| + |dy|) / (2|d|), the radial form of
 * the band offset, cell units). */
static int cap_in(double px, double dy, double h, int64_t j)
{
    double dx = (double)j + 0.5 - px, d = sqrt(dx * dx + dy * dy);
    return d == 0 || d <= h + (fabs(dx) + fabs(dy)) / (2 * d);
}

/* Cells of a cap on row i: up to two intervals appended to out. The test
 * as a function of |dx| rises while |dx| < |dy|, then falls (its derivative
 * is |dy|(|dy|-|dx|)/(2 d^3) - |dx|/d, one sign change): on rows with
 * |dy| <= h + 1/2 the cells in are one run around the point, found by
 * binary search; on the outermost rows (|dy| near or past h + 1/2, where
 * the run can split in two) the O(sqrt(h)) candidates are tested one by one. */
static size_t cap_row(const rs_road_grid *g, const prim *p, int64_t i, span *out)
{
    double px = p->a, py = p->b, h = p->h, rmax = h + 0.7072;
    double dy = (double)i + 0.5 - py;
    double jlo = floor(px - rmax), jhi = ceil(px + rmax);
    if (jlo < 0) jlo = 0;
    if (jhi > (double)g->gw - 1) jhi = (double)g->gw - 1;
    if (jlo > jhi) return 0;
    int64_t j0 = (int64_t)jlo, j1 = (int64_t)jhi;
    size_t n = 0;
    if (fabs(dy) > h + 0.5 - (1e-6 + 1e-12 * h)) {
        /* every cell in has d <= h + 1/sqrt(2) < rmax: |dx| <= sqrt(rmax^2 - dy^2) */
        double w = rmax * rmax - dy * dy;
        w = w > 0 ? sqrt(w) + 1.0 : 1.0;
        double a = floor(px - w), b = ceil(px + w);
        if (a > (double)j0) j0 = (int64_t)a;
        if (b < (double)j1) j1 = (int64_t)b;
        int64_t run = -1;
        for (int64_t j = j0; j <= j1 + 1; j++) {
            int in = j <= j1 && cap_in(px, dy, h, j);
            if (in && run < 0) run = j;
            if (!in && run >= 0) {
                out[n].lo = run;
                out[n].hi = j - 1;
                n++;
                run = -1;
            }
        }
        return n;
    }
    /* one run: the cell nearest the point, then both ends */
    double jn_d = floor(px);
    int64_t jn = jn_d < (double)j0 ? j0 : jn_d > (double)j1 ? j1 : (int64_t)jn_d;
    if (!cap_in(px, dy, h, jn)) return 0;
    int64_t lo = j0, hi = jn; /* smallest j in [j0, jn] that is in */
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (cap_in(px, dy, h, mid)) hi = mid; else lo = mid + 1;
    }
    out[0].lo = lo;
    lo = jn; hi = j1; /* largest j in [jn, j1] that is in */
    while (lo < hi) {
        int64_t mid = hi - (hi - lo) / 2;
        if (cap_in(px, dy, h, mid)) lo = mid; else hi = mid - 1;
    }
    out[0].hi = lo;
    return 1;
}

/* Cells of a distance-mode band on row i: the centres within r of the
 * segment's line and between its ends. */
static size_t band_row(const rs_road_grid *g, const prim *p, int64_t i, span *out)
{
    double ax = p->a, ay = p->b, bx = p->c, by = p->d, r = p->h;
    double dx = bx - ax, dy = by - ay, len = hypot(dx, dy);
    double tx = dx / len, ty = dy / len;
    double yc = (double)i + 0.5 - ay;
    double lo = -1e300, hi = 1e300;
    /* along: 0 <= (x-ax)*tx + yc*ty <= len; across: |-(x-ax)*ty + yc*tx| <= r */
    clip_linear(tx, -ax * tx + yc * ty, 0, len, &lo, &hi);
    clip_linear(-ty, ax * ty + yc * tx, -r, r, &lo, &hi);
    /* cells whose centre x (centre at j + 0.5) lies in [lo, hi] */
    if (!(lo <= hi)) return 0;
    double j0 = ceil(lo - 0.5), j1 = floor(hi - 0.5);
    if (j1 < 0 || j0 >= (double)g->gw || j0 > j1) return 0;
    if (j0 < 0) j0 = 0;
    if (j1 > (double)g->gw - 1) j1 = (double)g->gw - 1;
    out[0].lo = (int64_t)j0;
    out[0].hi = (int64_t)j1;
    return 1;
}

/* Dilate mode: the centreline raster of a segment between the cells
 * holding its ends. One cell per step along the major axis, the minor
 * coordinate rounded to nearest; where the line passes exactly between two
 * cells both are taken (the raster is the same whichever end it starts
 * from and under every 90-degree turn or mirroring). In closed form, step
 * s in 0..dmaj takes minor offsets t with |s*dmin/dmaj - t| <= 1/2. */
typedef struct raster {
    int xmajor;
    int64_t p0, q0, sp, sq, dmaj, dmin;
} raster;

static void raster_init(const prim *p, raster *r)
{
    int64_t ddx = p->x1 > p->x0 ? p->x1 - p->x0 : p->x0 - p->x1, ddy = p->y1 > p->y0 ? p->y1 - p->y0 : p->y0 - p->y1;
    r->xmajor = ddx >= ddy;
    r->p0 = r->xmajor ? p->x0 : p->y0;
    r->q0 = r->xmajor ? p->y0 : p->x0;
    r->sp = (r->xmajor ? p->x1 > p->x0 : p->y1 > p->y0) ? 1 : -1;
    r->sq = (r->xmajor ? p->y1 > p->y0 : p->x1 > p->x0) ? 1 : -1;
    r->dmaj = r->xmajor ? ddx : ddy;
    r->dmin = r->xmajor ? ddy : ddx;
}

/* Columns of the raster on grid row y (y within the segment's rows): a run. */
static void raster_row(const raster *r, int64_t y, int64_t *c0, int64_t *c1)
{
    if (!r->xmajor) { /* rows are steps: s = (y - p0) * sp */
        int64_t s = (y - r->p0) * r->sp, lo_t, hi_t;
        if (r->dmaj == 0) lo_t = hi_t = 0;
        else {
            int64_t q = s * r->dmin / r->dmaj, rem = 2 * (s * r->dmin - q * r->dmaj);
            lo_t = rem > r->dmaj ? q + 1 : q;
            hi_t = rem >= r->dmaj ? q + 1 : q;
        }
        int64_t a = r->q0 + r->sq * lo_t, b = r->q0 + r->sq * hi_t;
        *c0 = a < b ? a : b;
        *c1 = a < b ? b : a;
        return;
    }
    /* rows are minor offsets t; steps s with (2t-1) dmaj <= 2 s dmin <= (2t+1) dmaj */
    int64_t t = (y - r->q0) * r->sq, s0, s1;
    if (r->dmin == 0) { s0 = 0; s1 = r->dmaj; }
    else {
        int64_t lo_n = (2 * t - 1) * r->dmaj, hi_n = (2 * t + 1) * r->dmaj, den = 2 * r->dmin;
        s0 = lo_n <= 0 ? 0 : (lo_n + den - 1) / den;
        s1 = hi_n / den;
        if (s1 > r->dmaj) s1 = r->dmaj;
    }
    int64_t a = r->p0 + r->sp * s0, b = r->p0 + r->sp * s1;
    *c0 = a < b ? a : b;
    *c1 = a < b ? b : a;
}

/* Cells of a dilated segment on row i: the raster's cells on rows i-k..i+k
 * form one run (the raster is monotone and 8-connected), widened by k. */
static size_t dilate_row(const prim *p, int64_t i, span *out)
{
    raster r;
    raster_init(p, &r);
    int64_t ylo = p->y0 < p->y1 ? p->y0 : p->y1, yhi = p->y0 < p->y1 ? p->y1 : p->y0;
    int64_t ya = i - p->k > ylo ? i - p->k : ylo, yb = i + p->k < yhi ? i + p->k : yhi;
    if (ya > yb) return 0;
    int64_t a0, a1, b0, b1;
    raster_row(&r, ya, &a0, &a1);
    raster_row(&r, yb, &b0, &b1);
    out[0].lo = (a0 < b0 ? a0 : b0) - p->k;
    out[0].hi = (a1 > b1 ? a1 : b1) + p->k;
    return 1;
}

static int cmp_prim(const void *x, const void *y)
{
    const prim *a = x, *b = y;
    return a->i0 < b->i0 ? -1 : a->i0 > b->i0;
}

static int cmp_span(const void *x, const void *y)
{
    const span *a = x, *b = y;
    return a->lo < b->lo ? -1 : a->lo > b->lo;
}

/* Sweep the batch's primitives row by row: each row's intervals merged,
 * each cell marked once. */
static rs_result sweep_batch(sweep *sw)
{
    if (!sw->np) return RS_OK;
    marker *m = sw->m;
    if (sw->np > 1) qsort(sw->p, sw->np, sizeof *sw->p, cmp_prim);
    size_t next = 0, na = 0;
    int64_t row = sw->p[0].i0;
    while (next < sw->np || na) {
        if (!na && row < sw->p[next].i0) row = sw->p[next].i0;
        while (next < sw->np && sw->p[next].i0 <= row) sw->active[na++] = next++;
        size_t ni = 0;
        for (size_t a = 0; a < na; a++) {
            const prim *p = &sw->p[sw->active[a]];
            span *o = sw->iv + ni;
            ni += p->kind == PRIM_CAP ? cap_row(m->g, p, row, o)
                  : p->kind == PRIM_BAND ? band_row(m->g, p, row, o) : dilate_row(p, row, o);
        }
        if (ni > 1) qsort(sw->iv, ni, sizeof *sw->iv, cmp_span);
        for (size_t a = 0; a < ni;) {
            int64_t lo = sw->iv[a].lo, hi = sw->iv[a].hi;
            for (a++; a < ni && sw->iv[a].lo <= hi + 1; a++)
                if (sw->iv[a].hi > hi) hi = sw->iv[a].hi;
            rs_result r = mark_span(m, row, lo, hi);
            if (r) return r;
        }
        row++;
        size_t keep = 0;
        for (size_t a = 0; a < na; a++)
            if (sw->p[sw->active[a]].i1 >= row) sw->active[keep++] = sw->active[a];
        na = keep;
        /* cancellation within a road, not only between roads */
        if (++sw->rows >= CANCEL_ROWS) {
            sw->rows = 0;
            if (sw->o->progress && sw->o->progress(sw->o->progress_user, sw->done, sw->total))
                return rs__fail(m->ctx, RS_ERR_CANCELLED, "cancelled");
        }
    }
    sw->np = 0;
    return RS_OK;
}

static rs_result add_prim(sweep *sw, const prim *p)
{
    if (p->i0 > p->i1) return RS_OK;
    sw->p[sw->np++] = *p;
    return sw->np == PRIM_BATCH ? sweep_batch(sw) : RS_OK;
}

/* Distance mode, one segment (cell units): the band of cell centres within
 * h + (|nx|+|ny|)/2 of the segment, n its unit normal. */
static rs_result add_band(sweep *sw, double ax, double ay, double bx, double by, double h)
{
    double dx = bx - ax, dy = by - ay, len = hypot(dx, dy);
    if (!(len > 0)) return RS_OK;
    double tx = dx / len, ty = dy / len;
    prim p;
    memset(&p, 0, sizeof p);
    p.kind = PRIM_BAND;
    p.a = ax; p.b = ay; p.c = bx; p.d = by;
    p.h = h + 0.5 * (fabs(tx) + fabs(ty));
    row_range(sw->m->g, fmin(ay, by) - p.h, fmax(ay, by) + p.h, &p.i0, &p.i1);
    return add_prim(sw, &p);
}

static rs_result add_cap(sweep *sw, double px, double py, double h)
{
    prim p;
    memset(&p, 0, sizeof p);
    p.kind = PRIM_CAP;
    p.a = px; p.b = py; p.h = h;
    double rmax = h + 0.7072;
    row_range(sw->m->g, py - rmax, py + rmax, &p.i0, &p.i1);
    return add_prim(sw, &p);
}

/* Clip segment A-B to a disc around the grid grown by `pad` cells, so that
 * far-away or huge coordinates never reach an integer conversion and lose
 * no precision across the line. Segments already inside are left exactly as
 * they are. Returns 0 when nothing is left. */
static int clip_segment(const rs_road_grid *g, double pad, double *ax, double *ay, double *bx, double *by)
{
    double lo_x = -pad, lo_y = -pad, hi_x = (double)g->gw + pad, hi_y = (double)g->gh + pad;
    if (*ax >= lo_x && *ax <= hi_x && *bx >= lo_x && *bx <= hi_x && *ay >= lo_y && *ay <= hi_y && *by >= lo_y &&
        *by <= hi_y)
        return 1;
    double dx = *bx - *ax, dy = *by - *ay, len = hypot(dx, dy);
    if (!(len > 0) || !isfinite(len)) return 0;
    double tx = dx / len, ty = dy / len, cx = 0.5 * g->gw, cy = 0.5 * g->gh;
    double rad = 0.5 * hypot((double)g->gw, (double)g->gh) + pad, huge = 1e6 * ((double)g->gw + g->gh + 2 * pad);
    /* one end on the grid, the other past a million grid sizes: cut from
     * the near end, as the road field does (rs__clip_far) */
    int a_in = *ax >= lo_x && *ax <= hi_x && *ay >= lo_y && *ay <= hi_y;
    int b_in = *bx >= lo_x && *bx <= hi_x && *by >= lo_y && *by <= hi_y;
    if (a_in != b_in && !(fabs(a_in ? *bx - cx : *ax - cx) <= huge && fabs(a_in ? *by - cy : *ay - cy) <= huge)) {
        double along;
        return rs__cut_far_end(ax, ay, bx, by, a_in, tx, ty, len, cx, cy, rad, &along);
    }
    double ex = cx - *ax, ey = cy - *ay;
    double dist = -ty * ex + tx * ey; /* signed distance of the centre from the line */
    if (fabs(dist) > rad) return 0;   /* the line misses the disc */
    /* Foot of the perpendicular from the centre: built from the centre, so it
     * keeps full precision however far away A and B are. */
    double px = cx + ty * dist, py = cy - tx * dist;
    /* each end's place along the line from its own coordinates: len - sc
     * lost every digit when A was far and B near (a road from 10^31 m
     * ended at the map's centre: fuzz/edits) */
    double sc = ex * tx + ey * ty, s0 = -sc, s1 = (*bx - cx) * tx + (*by - cy) * ty;
    if (s0 < -rad) s0 = -rad;
    if (s1 > rad) s1 = rad;
    if (s0 > s1) return 0;
    *ax = px + s0 * tx;
    *ay = py + s0 * ty;
    *bx = px + s1 * tx;
    *by = py + s1 * ty;
    return 1;
}

/* Dilate mode, the raster walked step by step, each cell dilated by a k x k
 * square: only for segments too long for the closed form's 64-bit products
 * (grids beyond the default limits). */
static rs_result dilate_walk(marker *m, const prim *pr)
{
    raster r;
    raster_init(pr, &r);
    int64_t q = 0, rem = 0, k = pr->k;
    for (int64_t s = 0; s <= r.dmaj; s++) {
        int64_t lo = rem > r.dmaj ? q + 1 : q, hi = rem >= r.dmaj && r.dmaj > 0 ? q + 1 : q;
        for (int64_t t = lo; t <= hi; t++) {
            int64_t p = r.p0 + r.sp * s, c = r.q0 + r.sq * t;
            int64_t x = r.xmajor ? p : c, y = r.xmajor ? c : p;
            if (x + k < 0 || x - k >= (int64_t)m->g->gw) continue;
            for (int64_t yy = y - k; yy <= y + k; yy++) {
                rs_result res = mark_span(m, yy, x - k, x + k);
                if (res) return res;
            }
        }
        rem += 2 * r.dmin;
        if (rem >= 2 * r.dmaj && r.dmaj > 0) { rem -= 2 * r.dmaj; q++; }
    }
    return RS_OK;
}

/* Dilate mode, one segment: the 8-connected centreline raster between the
 * cells holding the end points, each cell dilated by a k x k square. */
static rs_result add_dilate(sweep *sw, double ax, double ay, double bx, double by, double h)
{
    marker *m = sw->m;
    double dx = bx - ax, dy = by - ay, len = hypot(dx, dy);
    double nx = len > 0 ? fabs(dy / len) : 0, ny = len > 0 ? fabs(dx / len) : 1;
    /* The dilated band's edge lands at k(|nx|+|ny|) - min(|nx|,|ny|)/2 cells. */
    double kf = (h + 0.5 * fmin(nx, ny)) / (nx + ny);
    /* A band wider than the grid covers it all; keeps the casts defined. */
    double kmax = (double)m->g->gw + (double)m->g->gh + 2;
    if (!(kf <= kmax)) kf = kmax;
    int64_t k = (int64_t)floor(kf + 0.5);
    if (k < 0) k = 0;
    if (!clip_segment(m->g, (double)k + 2, &ax, &ay, &bx, &by)) return RS_OK;
    prim p;
    memset(&p, 0, sizeof p);
    p.kind = PRIM_DILATE;
    p.x0 = (int64_t)floor(ax); p.y0 = (int64_t)floor(ay); p.x1 = (int64_t)floor(bx); p.y1 = (int64_t)floor(by);
    p.k = k;
    int64_t ddx = p.x1 > p.x0 ? p.x1 - p.x0 : p.x0 - p.x1, ddy = p.y1 > p.y0 ? p.y1 - p.y0 : p.y0 - p.y1;
    if (ddx > ((int64_t)1 << 30) || ddy > ((int64_t)1 << 30)) return dilate_walk(m, &p);
    int64_t ylo = p.y0 < p.y1 ? p.y0 : p.y1, yhi = p.y0 < p.y1 ? p.y1 : p.y0;
    p.i0 = ylo - k > 0 ? ylo - k : 0;
    p.i1 = yhi + k < (int64_t)m->g->gh - 1 ? yhi + k : (int64_t)m->g->gh - 1;
    return add_prim(sw, &p);
}

static int inside_box(const rs_road_grid *g, double x0, double y0, double x1, double y1, double pad)
{
    return !(fmax(x0, x1) + pad < 0 || fmin(x0, x1) - pad > (double)g->gw ||
             fmax(y0, y1) + pad < 0 || fmin(y0, y1) - pad > (double)g->gh);
}

static rs_result mark_road(sweep *sw, const double *pts, size_t n, double width, rs_buffer_mode mode,
                           double ox, double oy, double *scratch)
{
    const rs_road_grid *g = sw->m->g;
    rs__local_frame F = rs__local_frame_of(ox, oy, g->frame.cell_size);
    for (size_t i = 0; i < n; i++) rs__local_point(&F, pts, i, &scratch[2 * i], &scratch[2 * i + 1]);
    const double *xy = scratch;
    double inv = 1.0 / g->c, h = 0.5 * width * inv;
    double hmax = (double)g->gw + (double)g->gh + 2; /* wider covers the whole grid anyway */
    if (h > hmax) h = hmax;
    double pad = h + 2.0;
    int moving = 0; /* some segment has non-zero length */
    for (size_t i = 0; i + 1 < n && !moving; i++)
        moving = xy[2 * i] != xy[2 * i + 2] || xy[2 * i + 1] != xy[2 * i + 3];
    rs_result r = RS_OK;
    for (size_t i = 0; i < n && !r; i++) {
        double ax = xy[2 * i] * inv, ay = xy[2 * i + 1] * inv;
        if (mode == RS_BUFFER_DISTANCE) {
            if (inside_box(g, ax, ay, ax, ay, pad)) r = add_cap(sw, ax, ay, h);
            if (!r && i + 1 < n) {
                double bx = xy[2 * i + 2] * inv, by = xy[2 * i + 3] * inv, cx = ax, cy = ay;
                /* clip first: the band's direction is kept, far parts can't matter */
                if (inside_box(g, ax, ay, bx, by, pad) && clip_segment(g, pad, &cx, &cy, &bx, &by))
                    r = add_band(sw, cx, cy, bx, by, h);
            }
        } else if (i + 1 < n || n == 1) {
            double bx = i + 1 < n ? xy[2 * i + 2] * inv : ax, by = i + 1 < n ? xy[2 * i + 3] * inv : ay;
            /* A repeated point is no segment: it would get the square of an
             * axis-aligned road, wider than a diagonal road's band. Only a
             * road that is one point throughout is drawn as that square. */
            int dot = bx == ax && by == ay;
            if ((!dot || (!moving && i == 0)) && inside_box(g, ax, ay, bx, by, pad))
                r = add_dilate(sw, ax, ay, bx, by, h);
        }
    }
    if (!r) r = sweep_batch(sw);
    sw->np = 0;
    return r;
}

/* Road bit of cell (x, y), clamped to the grid: outside, a neighbour copies
 * the nearest inside cell, so roads leaving the map get no border there. */
static unsigned road_at(const rs_road_grid *g, int64_t x, int64_t y)
{
    if (x < 0) x = 0;
    if (y < 0) y = 0;
    if (x >= (int64_t)g->gw) x = (int64_t)g->gw - 1;
    if (y >= (int64_t)g->gh) y = (int64_t)g->gh - 1;
    const uint8_t *t = rs__grid_tile(g, (uint32_t)x >> RS__TILE_SHIFT, (uint32_t)y >> RS__TILE_SHIFT);
    if (!t) return 0;
    return t[((uint32_t)y & (RS__TILE - 1)) * RS__TILE + ((uint32_t)x & (RS__TILE - 1))] & RS__CELL_ROAD;
}

static void classify_tile(rs_road_grid *g, const rs__mask_table *mt, uint32_t tx, uint32_t ty)
{
    /* Road bits (0/1) of the tile plus a one-cell ring from its neighbours. */
    enum { W = RS__TILE + 2 };
    uint8_t win[W * W], h3[W * W];
    uint8_t *t = g->tiles[(size_t)ty * g->tw + tx];
    int64_t bx = (int64_t)tx * RS__TILE, by = (int64_t)ty * RS__TILE;
    for (uint32_t y = 0; y < RS__TILE; y++)
        for (uint32_t x = 0; x < RS__TILE; x++) win[(y + 1) * W + x + 1] = t[y * RS__TILE + x] >> 7;
    for (uint32_t k = 0; k < W; k++) {
        win[k] = (uint8_t)(road_at(g, bx + k - 1, by - 1) >> 7);
        win[(W - 1) * W + k] = (uint8_t)(road_at(g, bx + k - 1, by + RS__TILE) >> 7);
        win[k * W] = (uint8_t)(road_at(g, bx - 1, by + k - 1) >> 7);
        win[k * W + W - 1] = (uint8_t)(road_at(g, bx + RS__TILE, by + k - 1) >> 7);
    }
    /* Cells past the grid's right/bottom edge copy the nearest inside cell. */
    uint32_t xe = g->gw - (uint32_t)bx < RS__TILE ? g->gw - (uint32_t)bx : RS__TILE;
    uint32_t ye = g->gh - (uint32_t)by < RS__TILE ? g->gh - (uint32_t)by : RS__TILE;
    if (xe < RS__TILE)
        for (uint32_t y = 0; y < W; y++)
            for (uint32_t x = xe + 1; x < W; x++) win[y * W + x] = win[y * W + xe];
    if (ye < RS__TILE)
        for (uint32_t y = ye + 1; y < W; y++) memcpy(win + y * W, win + ye * W, W);
    /* h3 = AND of three horizontal neighbours: interior iff three rows agree. */
    for (uint32_t y = 0; y < W; y++)
        for (uint32_t x = 1; x + 1 < W; x++)
            h3[y * W + x] = win[y * W + x - 1] & win[y * W + x] & win[y * W + x + 1];
    static const int ox[8] = { 0, 1, 1, 1, 0, -1, -1, -1 }, oy[8] = { -1, -1, 0, 1, 1, 1, 0, -1 };
    for (uint32_t y = 0; y < ye; y++) {
        for (uint32_t x = 0; x < xe; x++) {
            uint8_t *cell = &t[y * RS__TILE + x];
            if (!(*cell & RS__CELL_ROAD)) continue;
            size_t c = (size_t)(y + 1) * W + x + 1;
            g->stats.road_cells++;
            if (h3[c - W] & h3[c] & h3[c + W]) {
                *cell = RS__CELL_ROAD; /* pattern 0: interior */
                g->stats.interior_cells++;
                continue;
            }
            unsigned mask = 0;
            for (int b = 0; b < 8; b++)
                if (win[c + oy[b] * W + ox[b]]) mask |= 1u << b;
            unsigned p = mt->corners[mask];
            *cell = (uint8_t)(RS__CELL_ROAD | p);
            g->stats.boundary_cells++;
            g->stats.by_type[mt->type[p]]++;
        }
    }
}

/* Road cells per DEM cell side. Automatic: the narrowest road spans at least
 * 4 road cells and a road cell is at most half a texel, so the drawn edge is
 * finer than the output; capped at 64 and by the road-cell limit. */
static rs_result choose_k(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, double cs, uint32_t texels,
                          double road_cell, uint32_t *k_out)
{
    uint64_t cw = dem->width - 1, ch = dem->height - 1, cells;
    uint64_t k;
    if (road_cell > 0) {
        double kf = floor(cs / road_cell + 0.5);
        if (kf < 1) kf = 1;
        if (kf > 65536) return rs__fail(ctx, RS_ERR_LIMIT, "road cell %g m is too small for cell size %g m", road_cell, cs);
        k = (uint64_t)kf;
        if (!rs__mul_u64(cw * k, ch * k, &cells) || cells > ctx->limits.max_road_cells || cw * k > UINT32_MAX ||
            ch * k > UINT32_MAX)
            return rs__fail(ctx, RS_ERR_LIMIT, "road cell %g m gives more than %llu road cells", road_cell,
                            (unsigned long long)ctx->limits.max_road_cells);
        *k_out = (uint32_t)k;
        return RS_OK;
    }
    double wmin = INFINITY;
    for (size_t i = 0; i < rs_roads_count(roads); i++) {
        double w;
        if (rs_roads_get(roads, i, NULL, &w, NULL, NULL) == RS_OK && w < wmin) wmin = w;
    }
    double target = 0.5 * cs / texels;
    if (wmin / 4 < target) target = wmin / 4;
    /* a subnormal road width makes target 0: as narrow as it gets, k = 64 */
    double kf = target > 0 ? ceil(cs / target - 1e-9) : 64;
    k = kf < 1 ? 1 : (kf > 64 ? 64 : (uint64_t)kf);
    while (k > 1 && (!rs__mul_u64(cw * k, ch * k, &cells) || cells > ctx->limits.max_road_cells)) k--;
    *k_out = (uint32_t)k;
    return RS_OK;
}

void rs__grid_hold(rs_road_grid *g) { rs__refs_add(&g->refs, 1); }

const rs_road_grid *rs__grid_at(const rs_road_grid *g, uint32_t x, uint32_t y, const rs__grid_patch **patch)
{
    for (size_t k = g->npatch; k-- > 0;) {
        const rs__grid_patch *p = &g->patch[k];
        if (x >= p->rect.x0 && x < p->rect.x1 && y >= p->rect.y0 && y < p->rect.y1) {
            if (patch) *patch = p;
            return p->grid;
        }
    }
    if (patch) *patch = NULL;
    return g;
}

void rs_road_grid_free(rs_ctx *ctx, rs_road_grid *grid)
{
    if (!ctx || !grid) return;
    if (rs__refs_add(&grid->refs, -1) > 0) return; /* (a patched grid still draws with it) */
    rs__grid_track_free(ctx, grid->track);
    if (grid->base) { /* a patched grid: its own parts only */
        for (size_t k = 0; k < grid->npatch; k++) {
            rs_road_grid_free(ctx, grid->patch[k].grid);
            rs__free(ctx, grid->patch[k].ids);
        }
        rs__free(ctx, grid->patch);
        rs__free(ctx, grid->dirty);
        rs_road_grid_free(ctx, grid->base);
        rs__free(ctx, grid);
        return;
    }
    rs__roadfield_free(ctx, grid->field);
    rs__styling_free(ctx, grid->styling);
    rs__markings_free(ctx, grid->markings);
    rs__grid_edit_free(ctx, grid->edit);
    rs_road_grid_free(ctx, grid->atlas_hold); /* (after the markings that point into its atlas) */
    if (grid->tiles) {
        for (size_t i = 0; i < (size_t)grid->tw * grid->th; i++) rs__free(ctx, grid->tiles[i]);
        rs__free(ctx, grid->tiles);
    }
    rs__free(ctx, grid);
}

void rs_road_grid_get_stats(const rs_road_grid *grid, rs_road_grid_stats *out)
{
    if (grid && out) *out = grid->stats;
}

void rs__grid_size(const rs_road_grid *g, uint32_t *gw, uint32_t *gh)
{
    *gw = g->tiles ? g->gw : 0;
    *gh = g->tiles ? g->gh : 0;
}

int rs__grid_cell(const rs_road_grid *g, uint32_t x, uint32_t y, unsigned *pattern)
{
    if (!g->tiles || x >= g->gw || y >= g->gh) return 0;
    const uint8_t *t = rs__grid_tile(g, x >> RS__TILE_SHIFT, y >> RS__TILE_SHIFT);
    unsigned c = t ? t[(y & (RS__TILE - 1)) * RS__TILE + (x & (RS__TILE - 1))] : 0;
    if (!(c & RS__CELL_ROAD)) return 0;
    *pattern = c & RS__CELL_PATTERN;
    return 1;
}

int rs_road_grid_query(const rs_road_grid *grid, double x, double y, double reach, rs_road_point *out)
{
    rs__road_point p;
    const rs__grid_patch *patch = NULL;
    if (grid && grid->npatch) {
        /* the grid that draws the point's pixel */
        double px = (x - grid->frame.origin_x) / (grid->frame.cell_size / grid->texels);
        double py = (y - grid->frame.origin_y) / (grid->frame.cell_size / grid->texels);
        if (px >= 0 && py >= 0 && px < 4294967295.0 && py < 4294967295.0)
            grid = rs__grid_at(grid, (uint32_t)px, (uint32_t)py, &patch);
    }
    if (!grid || !grid->field || !out || !(reach >= 0) || !rs__roadfield_nearest(grid->field, x, y, reach, &p))
        return 0;
    if (patch && (p.road >= patch->n || patch->ids[p.road] == UINT32_MAX)) return 0;
    out->road = patch ? patch->ids[p.road] : p.road;
    out->segment = p.seg;
    out->s = p.s;
    out->t = p.t;
    out->distance = p.dist;
    return 1;
}

/* Analytic edges: the road field over the map. */
static rs_result build_field(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, uint32_t texels,
                             const rs__grid_facts *facts, rs_road_grid *g)
{
    rs__roadfield_params p = rs__roadfield_params_for_dem(dem, texels);
    if (facts) { /* (a part of a map: the whole map's cells, and the part's window) */
        p.index_cell = facts->index_cell;
        p.window_on = facts->window_on;
        memcpy(p.window, facts->window, sizeof p.window);
        p.window_reach = facts->window_reach;
    }
    rs_result r = rs__roadfield_build(ctx, roads, &p, &g->field);
    if (r == RS_OK) {
        for (size_t i = 0; i < rs_roads_count(roads); i++) {
            size_t np = 0;
            rs_roads_get(roads, i, NULL, NULL, NULL, &np);
            g->stats.segments += np > 1 ? np - 1 : 1;
        }
        g->stats.bytes += rs__roadfield_bytes(g->field);
    }
    return r;
}

/* rs_road_grid_build, with the network `given` (NULL: built here from
 * roads) and the whole map's facts when roads are a part of it (NULL: these
 * roads are the map) */
static rs_result grid_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *opts,
                            const rs_network *given, const rs__grid_facts *facts, rs_road_grid **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_road_grid_build");
    *out = NULL;
    if (!dem || !roads) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_road_grid_build");
    rs_splat_options o;
    rs_result r = rs__splat_defaults(ctx, opts, &o);
    if (r) return r;
    rs_road_grid *g = rs__calloc(ctx, 1, sizeof *g);
    if (!g) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the road grid");
    g->refs = 1;
    g->dem_w = dem->width;
    g->dem_h = dem->height;
    g->frame = dem->frame;
    g->texels = o.texels;
    g->opts = o.grid;
    g->edges = o.coverage.edges;
    g->style = o.style;
    g->style.styles = NULL; /* borrowed only while building */
    g->marks = o.markings;
    g->stats.bytes = sizeof *g;
    /* progress of the analytic build's stages, a road per unit each: the
     * field, the network, the line symbols, the automatic markings' line
     * cuts and placements (rs__tick in their loops; more than total when
     * a stage runs twice, fewer when styles are off: the last call says
     * total) */
    size_t nroads = rs_roads_count(roads);
    rs__progress pg;
    memset(&pg, 0, sizeof pg);
    pg.nested = 1; /* alpha-map edges: their sweep below reports itself (the options' callback) */
    if (o.coverage.edges == RS_EDGES_ANALYTIC) {
        rs__progress_begin(ctx, &pg, o.progress, o.progress_user, 5 * (uint64_t)nroads + 1, PROGRESS_STEP);
        r = build_field(ctx, dem, roads, o.texels, facts, g);
    }
    /* the styles look pixels' roads up in the grid's field when it has one */
    /* the network (docs/network.md): strokes carry dashes and surface
     * images across the records a road is split into; read while building
     * the styles and the markings only */
    rs_network *own = NULL;
    const rs_network *net = NULL;
    if (!r && !o.style.disable && nroads > 0) {
        if (given) net = given;
        else if (!(r = rs_network_build(ctx, roads, NULL, &own))) net = own;
    }
    if (!r && rs__tick(ctx, nroads)) r = RS_ERR_CANCELLED;
    /* record ends at a T lose their round caps (docs/network.md "Ends at a T");
     * worked out once, the styles, the edit pieces and the track read them */
    rs__tee_end *tees = NULL;
    size_t ntees = 0;
    if (!r && net) r = rs__tee_ends(ctx, roads, net, &tees, &ntees);
    const rs__tees T = { tees, ntees }, *Tp = net ? &T : NULL;
    if (!r && net && g->field) r = rs__roadfield_set_tees(ctx, g->field, roads, tees, ntees);
    /* the automatic markings, placed once: the styles' lines stop at them */
    rs__auto_plan plan;
    memset(&plan, 0, sizeof plan);
    /* (a patch: the pixels it draws, which its markings index and edit pieces serve) */
    const double *window = facts && facts->window_on ? facts->window : NULL;
    if (!r) r = rs__auto_plan_make(ctx, dem, roads, &o, net, &plan);
    if (!r) r = rs__styling_build(ctx, dem, roads, &o, g->field, net, Tp, plan.cuts, plan.ncuts, facts, &g->styling);
    if (!r) r = rs__markings_build_planned(ctx, dem, roads, &o, net, &plan, window, &g->markings);
    /* a lower road's markings under a bridge's deck (docs/network.md "Bridges and layers") */
    /* (alpha-map edges: the styles' field of the roads when they keep one) */
    if (!r && g->markings)
        r = rs__markings_set_levels(ctx, g->markings, dem, roads, net,
                                    g->field ? g->field : g->styling ? g->styling->near : NULL, Tp, o.texels);
    if (!r && o.grid.edits) r = rs__grid_edit_build(ctx, dem, roads, &o, net, Tp, window, g);
    rs__auto_plan_free(ctx, &plan);
    /* a whole grid kept for edits keeps what a proportional update reads (its network too) */
    if (!r && o.grid.edits && !facts && o.coverage.edges == RS_EDGES_ANALYTIC) {
        r = rs__grid_track_build(ctx, roads, &o, own, own == net ? Tp : NULL, g);
        own = NULL;
    }
    rs__free(ctx, tees);
    rs_network_free(ctx, own);
    r = rs__progress_end(ctx, &pg, r);
    if (r) {
        rs_road_grid_free(ctx, g);
        return r;
    }
    if (g->styling) g->stats.bytes += g->styling->bytes;
    if (g->edit) g->stats.bytes += g->edit->bytes;
    if (g->track) g->stats.bytes += g->track->bytes;
    if (g->markings) {
        g->stats.bytes += g->markings->bytes;
        g->stats.marks_explicit = g->markings->n_explicit;
        g->stats.marks_auto = g->markings->n_auto;
    }
    if (o.coverage.edges == RS_EDGES_ANALYTIC) {
        *out = g;
        rs__ok(ctx);
        return RS_OK;
    }
    uint32_t k = 1;
    r = choose_k(ctx, dem, roads, dem->frame.cell_size, o.texels, o.grid.road_cell, &k);
    if (r) {
        rs_road_grid_free(ctx, g);
        return r;
    }
    g->k = k;
    g->c = g->frame.cell_size / k;
    g->gw = (dem->width - 1) * k;
    g->gh = (dem->height - 1) * k;
    g->tw = (g->gw + RS__TILE - 1) / RS__TILE;
    g->th = (g->gh + RS__TILE - 1) / RS__TILE;
    g->stats.k = k;
    g->stats.road_cell = g->c;
    g->tiles = rs__calloc(ctx, (size_t)g->tw * g->th, sizeof *g->tiles);
    if (!g->tiles) {
        rs_road_grid_free(ctx, g);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the road grid directory");
    }
    marker m = { ctx, g };
    size_t n = rs_roads_count(roads), most = 0;
    sweep sw;
    memset(&sw, 0, sizeof sw);
    sw.m = &m;
    sw.o = &o;
    sw.total = n;
    sw.p = rs__alloc_array(ctx, PRIM_BATCH, sizeof *sw.p);
    sw.active = rs__alloc_array(ctx, PRIM_BATCH, sizeof *sw.active);
    sw.iv = rs__alloc_array(ctx, 2 * PRIM_BATCH, sizeof *sw.iv);
    for (size_t i = 0; i < n; i++) {
        size_t np;
        rs_roads_get(roads, i, NULL, NULL, NULL, &np);
        if (np > most) most = np;
    }
    double *scratch = rs__alloc_array(ctx, most ? 2 * most : 2, sizeof *scratch);
    if (!scratch || !sw.p || !sw.active || !sw.iv) {
        rs__free(ctx, scratch);
        rs__free(ctx, sw.p);
        rs__free(ctx, sw.active);
        rs__free(ctx, sw.iv);
        rs_road_grid_free(ctx, g);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for road points");
    }
    for (size_t i = 0; i < n && !r; i++) {
        const double *xy;
        size_t np;
        double w;
        rs_roads_get(roads, i, NULL, &w, &xy, &np);
        sw.done = i;
        r = mark_road(&sw, xy, np, w, o.grid.buffer, dem->frame.origin_x, dem->frame.origin_y, scratch);
        if (!r && o.progress && o.progress(o.progress_user, i + 1, n)) r = rs__fail(ctx, RS_ERR_CANCELLED, "cancelled");
    }
    rs__free(ctx, scratch);
    rs__free(ctx, sw.p);
    rs__free(ctx, sw.active);
    rs__free(ctx, sw.iv);
    rs__mask_table mt;
    rs__mask_table_build(&mt);
    if (!r)
        for (uint32_t ty = 0; ty < g->th; ty++)
            for (uint32_t tx = 0; tx < g->tw; tx++)
                if (g->tiles[(size_t)ty * g->tw + tx]) classify_tile(g, &mt, tx, ty);
    if (r) {
        rs_road_grid_free(ctx, g);
        return r;
    }
    /* (on top of the styles, markings and edit pieces counted above) */
    g->stats.bytes += (uint64_t)g->tw * g->th * sizeof *g->tiles + g->stats.tiles_allocated * RS__TILE * RS__TILE;
    *out = g;
    rs__ok(ctx);
    return RS_OK;
}

rs_result rs_road_grid_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *opts,
                             rs_road_grid **out)
{
    return grid_build(ctx, dem, roads, opts, NULL, NULL, out);
}

void rs__grid_facts_of(const rs_road_grid *g, rs__grid_facts *out)
{
    const rs__styling *st = g->styling;
    memset(out, 0, sizeof *out);
    out->index_cell = rs__roadfield_cell(g->field);
    if (!st) return;
    out->styled = 1;
    out->any_surface = st->any_surface;
    out->fill_uniform = st->fill_uniform;
    memcpy(out->fill_rgba, st->fill_rgba, sizeof out->fill_rgba);
    out->casing_uniform = st->casing_uniform;
    memcpy(out->casing_rgba, st->casing_rgba, sizeof out->casing_rgba);
    out->widest_casing = st->widest_casing;
    out->ranked = st->prio != NULL;
}

rs_result rs__road_grid_build_subset(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads,
                                     const rs_splat_options *opts, const rs_network *net,
                                     const rs__grid_facts *facts, const uint32_t *ids, size_t n, rs_road_grid **out)
{
    rs_roads *sub = NULL;
    rs_network *part = NULL;
    *out = NULL;
    if (!net) { /* (styles off: no network is built) */
        rs_result r = rs__roads_subset(ctx, roads, ids, n, &sub);
        if (!r) r = grid_build(ctx, dem, sub, opts, NULL, facts, out);
        rs_roads_free(ctx, sub);
        return r;
    }
    if (net->nroads != rs_roads_count(roads))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "subset build: a network of %zu records for %zu roads", net->nroads,
                        rs_roads_count(roads));
    /* the strokes' arc lengths record by record, as the whole map's line symbols sum them */
    double *bases = net->s_base ? NULL : rs__alloc_array(ctx, net->nroads ? net->nroads : 1, sizeof *bases);
    if (!net->s_base && !bases) return rs__fail(ctx, RS_ERR_NOMEM, "subset build: out of memory");
    rs_result r = bases ? rs__stroke_bases(ctx, net, roads, dem->frame.origin_x, dem->frame.origin_y,
                                           dem->frame.cell_size, ids, n, bases)
                        : RS_OK;
    if (!r) r = rs__roads_subset(ctx, roads, ids, n, &sub);
    if (!r) r = rs__network_subset(ctx, net, bases, ids, n, &part);
    rs__free(ctx, bases);
    if (!r) r = grid_build(ctx, dem, sub, opts, part, facts, out);
    rs_network_free(ctx, part);
    rs_roads_free(ctx, sub);
    return r;
}
