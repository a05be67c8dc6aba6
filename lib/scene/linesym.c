/* Line symbols: convex band pieces, a pixel-cell index, exact per-pixel
 * areas (lib/scene/linesym.h; docs/linesym.md). */
#include "linesym.h"
#include "network.h"
#include "lanes.h"
#include "roadfield.h"
#include "road_local.h"
#include "grid_edit.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define HALF_SQRT2 0.70710678118654752440
/* Offsets and widths beyond this are refused: a style is about a road. */
#define BAND_MAX_EXTENT 1e4
/* Index cells: CELL_PX columns x CELL_ROWS rows of pixels (both doubled
 * until there are at most MAX_CELLS): as tall as the splat's pieces of
 * rows (texels), so painting a piece reads only the entries it needs. */
#define CELL_PX 32u
#define CELL_ROWS 4u
#define MAX_CELLS ((uint64_t)1 << 22)
#define POLY_MAX 24
/* Half-planes per piece: 6 of its own, 3 per junction cut (two cuts). */
#define HP_MAX 12

enum { PIECE_SLAB = 0, PIECE_WEDGE = 1 };

/* One convex piece of one band, in its own frame: u along the segment
 * (unit vector (ux, uy)) from (ox, oy), v = left normal offset, so a
 * point's (u, v) = ((p-o).u, (p-o).(uy, -ux)). The piece is the set where
 * every half-plane c0 + cu u + cv v >= 0 holds; a wedge is further cut to
 * the annulus r0 <= |p-o| <= r1. A slab's first two half-planes are its
 * v limits (v >= a, v <= b). */
typedef struct ls_piece {
    /* what every visited pixel reads first */
    double ox, oy, ux, uy;
    uint32_t nhp;
    uint32_t kind;
    uint32_t band;
    uint32_t dashed;     /* slab: cut by the band's dash pattern along u */
    double a, b;         /* slab: v range */
    double uin0, uin1;   /* slab: centre u range where no half-plane but the v limits can cut a pixel (push_piece) */
    double su;           /* half the pixel's extent along u (and v) (push_piece) */
    double st_lo, st_e, st_q, st_h; /* slab: the strip's ramp (strip_below), in pixel areas (push_piece) */
    double s0;           /* slab: s at u = 0 */
    double r0, r1;       /* wedge radii */
    double wx0, wy0, wx1, wy1; /* wedge: box of the sector relative to (ox, oy), padded */
    double warea;              /* wedge: the sector's area in pixel areas */
    double sup[HP_MAX];  /* half the pixel square's extent along each half-plane's normal (push_piece) */
    double hp[HP_MAX][3];
    /* rows and columns to visit (push_piece) */
    double gx0, gx1, gy0, gy1; /* pixels to visit: their columns and rows */
    double ru0, ru1, rv0, rv1; /* slab: the piece's u and v ranges grown by su */
    /* build only */
    uint32_t nlim;       /* half-planes counted against HP_MAX (a dropped redundant one still counts) */
    double len;          /* slab: u range [0, len] of its box */
    double x0, y0, x1, y1; /* local box, grown by the pixel margin */
} ls_piece;

/* An index entry: a piece listed in a cell, with what the painter reads
 * before its pixels (its band, the rows and columns of its pixels), so a
 * cell's list is read in one sweep. */
typedef struct ls_pbox {
    double gx0, gx1, gy0, gy1;
    uint32_t id, band;
} ls_pbox;

/* A piece as the painter reads it (built from ls_piece): the fields a
 * pixel reads first come first; the half-planes live in one pool,
 * L->hpp[4 (hp0 + k) ..] = c0, cu, cv, sup of half-plane k. */
typedef struct ls_ppc {
    double ox, oy, ux, uy, a, b, su, uin0, uin1, st_lo, st_e, st_q, st_h, s0;
    double ru0, ru1, rv0, rv1;
    double iku, ikv, cbase; /* 1 / (ux pix), 1 / (uy pix) (0 when below 1e-12 / pix), ox / pix - 0.5 */
    double r0, r1, wx0, wy0, wx1, wy1, warea;
    uint32_t nhp, kind, band, dashed, hp0;
} ls_ppc;

#define HPP(L, P, k) ((L)->hpp + 4 * ((size_t)(P)->hp0 + (k)))

/* What the index build reads of a piece besides its ls_ppc (kept while
 * building only; a whole ls_piece per piece was ~700 bytes). */
typedef struct ls_pbuild {
    double len;                /* slab: u range [0, len] */
    double x0, y0, x1, y1;     /* local box, grown by the pixel margin */
    double gx0, gx1, gy0, gy1; /* pixels to visit */
} ls_pbuild;

typedef struct ls_band {
    float rgba[4];
    uint32_t dash0, ndash; /* into L->dash */
    double period, phase;
    double t;              /* the centre's lateral offset (rs__band) */
} ls_band;

/* A grid of index cells: gw x gh cells of cmx x cmy metres. */
typedef struct ls_grid {
    uint32_t gw, gh;
    double cmx, cmy;
} ls_grid;

struct ls_cutset;

struct rs__linesym {
    double pixel, margin;
    rs__band_aa aa;
    uint32_t out_w, out_h;
    uint32_t cpx, cpy;     /* pixels per index cell: columns, rows */
    ls_grid grid;          /* the same in metres */
    uint32_t gw, gh;
    uint32_t *start;       /* CSR: the pieces per cell in ent, ascending */
    ls_pbox *ent;
    ls_pbuild *pb;         /* while building */
    ls_ppc *pp;            /* painting: the pieces, their boxes, their half-planes */
    double *hpp;
    size_t npc, cap, nhpp, hcap; /* pieces (pp, pb) and half-planes (hpp) held and allocated */
    size_t cap0;           /* the first capacity: about the pieces the roads' bands make */
    uint64_t budget;       /* rs_limits.max_linesym_bytes: pieces, half-planes and index entries */
    int over_budget;       /* the build stopped at it */
    ls_band *band;
    uint32_t nband;
    double *dash;
    size_t bytes;
    /* while building: the cuts of each road (p->cuts[cut_ord[cut_start[r] ..
     * cut_start[r + 1])]) */
    const rs__line_cut *cuts;
    const uint32_t *cut_stroke; /* per road its stroke (NULL: every road its own) */
    struct ls_cutset *cs;       /* while building: the piece sets of push_trim [0] and push_cut [1] */
    uint32_t *cut_start, *cut_ord;
    int win_on;                 /* while building: only pieces meeting win are made (rs__linesym_params.window) */
    double win[4];
};

/* ------------------------------------------------------------------------
 * Geometry
 * ---------------------------------------------------------------------- */

/* Keep the part of polygon (x, y)[n] where c0 + cu x + cv y >= 0. */
static uint32_t clip_poly(const double *x, const double *y, uint32_t n, double c0, double cu, double cv, double *ox,
                          double *oy)
{
    uint32_t m = 0;
    if (n == 0) return 0;
    double px = x[n - 1], py = y[n - 1], pd = c0 + cu * px + cv * py;
    for (uint32_t i = 0; i < n; i++) {
        double cx = x[i], cy = y[i], cd = c0 + cu * cx + cv * cy;
        if ((pd >= 0) != (cd >= 0)) {
            double f = pd / (pd - cd);
            ox[m] = px + f * (cx - px);
            oy[m] = py + f * (cy - py);
            m++;
        }
        if (cd >= 0) {
            ox[m] = cx;
            oy[m] = cy;
            m++;
        }
        px = cx;
        py = cy;
        pd = cd;
    }
    return m;
}

static double poly_area(const double *x, const double *y, uint32_t n)
{
    double a = 0;
    for (uint32_t i = 0, j = n ? n - 1 : 0; i < n; j = i++) a += x[j] * y[i] - x[i] * y[j];
    return 0.5 * fabs(a);
}

/* Area of polygon (x, y)[n] (either orientation) where a <= y <= b: the
 * integral of x dy round its edges cut to the strip (Green's theorem; the
 * strip's own edges, dy = 0, add nothing), so nothing is clipped. */
static double strip_area(const double *x, const double *y, uint32_t n, double a, double b)
{
    double s = 0;
    for (uint32_t i = 0, j = n - 1; i < n; j = i++) {
        double y0 = y[j], y1 = y[i];
        double c0 = y0 < a ? a : (y0 > b ? b : y0), c1 = y1 < a ? a : (y1 > b ? b : y1);
        if (c0 == c1) continue;
        double t = (0.5 * (c0 + c1) - y0) / (y1 - y0);
        s += (c1 - c0) * (x[j] + t * (x[i] - x[j]));
    }
    return fabs(s);
}

/* Signed area of triangle (origin, p, q) inside the disc of radius r. */
static double tri_disc(double px, double py, double qx, double qy, double r)
{
    double dx = qx - px, dy = qy - py, A = dx * dx + dy * dy, B = px * dx + py * dy, C = px * px + py * py - r * r;
    double ts[4] = { 0, 0, 0, 1 };
    int nt = 1;
    if (A > 0) {
        double disc = B * B - A * C;
        if (disc > 0) {
            double sq = sqrt(disc), t1 = (-B - sq) / A, t2 = (-B + sq) / A;
            if (t1 > 0 && t1 < 1) ts[nt++] = t1;
            if (t2 > 0 && t2 < 1) ts[nt++] = t2;
        }
    }
    ts[nt++] = 1;
    double area = 0, ax = px, ay = py;
    for (int k = 1; k < nt; k++) {
        double bx = px + ts[k] * dx, by = py + ts[k] * dy;
        double mx = 0.5 * (ax + bx), my = 0.5 * (ay + by), cr = ax * by - ay * bx;
        if (mx * mx + my * my <= r * r) area += 0.5 * cr;
        else area += 0.5 * r * r * atan2(cr, ax * bx + ay * by);
        ax = bx;
        ay = by;
    }
    return area;
}

/* Area of the convex polygon inside the disc of radius r around the origin. */
static double poly_disc(const double *x, const double *y, uint32_t n, double r)
{
    if (!(r > 0) || n < 3) return 0;
    double a = 0;
    for (uint32_t i = 0, j = n - 1; i < n; j = i++) a += tri_disc(x[j], y[j], x[i], y[i], r);
    return fabs(a);
}

/* Dash pattern: is arc length s "on"? (pattern repeats both ways from phase) */
static int dash_on(const rs__linesym *L, const ls_band *B, double s)
{
    double x = s - B->phase, m = x - floor(x / B->period) * B->period;
    const double *d = L->dash + B->dash0;
    for (uint32_t j = 0; j < B->ndash; j += 2) {
        if (m < d[j]) return 1;
        m -= d[j];
        if (m < d[j + 1]) return 0;
        m -= d[j + 1];
    }
    return 0;
}

static double hermite(double x)
{
    x = x < 0 ? 0 : (x > 1 ? 1 : x);
    return x * x * (3 - 2 * x);
}

/* Fraction of the pixel square (centred at v = 0 of slab P's frame) where
 * v <= x: a ramp, a plateau and a ramp along the normal (constants from
 * push_piece). */
static inline double strip_below(const ls_ppc *P, double x)
{
    double e = P->st_e, t = x + e;
    if (t <= 0) return 0;
    if (t >= 2 * e) return 1;
    int flip = t > e;
    if (flip) t = 2 * e - t;
    double a = t <= P->st_lo ? t * t * P->st_q : (0.5 * P->st_lo + (t - P->st_lo)) * P->st_h;
    return flip ? 1 - a : a;
}

/* Keep the part of polygon (*sx, *sy)[n] inside the half-planes of P whose
 * bits are set in `cut`, swapping the buffers; returns the vertex count. */
static uint32_t clip_cut(const rs__linesym *L, const ls_ppc *P, uint32_t cut, double **sx, double **sy, double **tx,
                         double **ty, uint32_t n)
{
    for (uint32_t k = 0; cut && n; k++, cut >>= 1) {
        if (!(cut & 1u)) continue;
        const double *h = HPP(L, P, k), *x = *sx, *y = *sy;
        double d[POLY_MAX], *ox = *tx, *oy = *ty;
        uint32_t out = 0, m = 0;
        for (uint32_t i = 0; i < n; i++) {
            d[i] = h[0] + h[1] * x[i] + h[2] * y[i];
            out += d[i] < 0;
        }
        if (out == 0) continue; /* the plane misses the polygon */
        if (out == n) return 0;
        for (uint32_t i = 0, j = n - 1; i < n; j = i++) {
            if ((d[j] >= 0) != (d[i] >= 0)) {
                double f = d[j] / (d[j] - d[i]);
                ox[m] = x[j] + f * (x[i] - x[j]);
                oy[m] = y[j] + f * (y[i] - y[j]);
                m++;
            }
            if (d[i] >= 0) {
                ox[m] = x[i];
                oy[m] = y[i];
                m++;
            }
        }
        n = m;
        double *t;
        t = *sx; *sx = *tx; *tx = t;
        t = *sy; *sy = *ty; *ty = t;
    }
    return n;
}

/* Is s - phase (mod period) "on" over the whole of [m - eu, m + eu]?
 * 1 on, 0 off, -1 a dash end lies in it. */
static int dash_span(const rs__linesym *L, const ls_band *B, double x, double eu)
{
    const double *d = L->dash + B->dash0;
    double m = x - floor(x / B->period) * B->period, acc = 0;
    for (uint32_t j = 0; j < B->ndash; j++) {
        double hi = acc + d[j];
        if (m - eu >= acc && m + eu <= hi) return (j & 1) == 0;
        acc = hi;
    }
    return -1;
}

/* Area fraction of pixel (px, py) inside piece P (exact mode). */
static double piece_area(const rs__linesym *L, const ls_ppc *P, uint32_t px, uint32_t py)
{
    double pix = L->pixel, x0 = (double)px * pix - P->ox, y0 = (double)py * pix - P->oy, x1 = x0 + pix,
           y1 = y0 + pix;
    double ux = P->ux, uy = P->uy;
    /* which half-planes cut the pixel (its centre against each, by the
     * square's exact extent along the normal), before any corner */
    double xc = x0 + 0.5 * pix, yc = y0 + 0.5 * pix, cu = xc * ux + yc * uy, cv = xc * uy - yc * ux;
    uint32_t cut = 0, k0 = 0;
    if (P->kind == PIECE_SLAB) {
        /* the v limits; then, well inside the ends, nothing else */
        double d0 = cv - P->a, d1 = P->b - cv;
        if (d0 <= -P->su || d1 <= -P->su) return 0;
        cut = (uint32_t)(d0 < P->su) | (uint32_t)(d1 < P->su) << 1;
        k0 = cu >= P->uin0 && cu <= P->uin1 ? P->nhp : 2;
    }
    for (uint32_t k = k0; k < P->nhp; k++) {
        const double *h = HPP(L, P, k);
        double d = h[0] + h[1] * cu + h[2] * cv;
        if (d <= -h[3]) return 0;
        if (d < h[3]) cut |= 1u << k;
    }
    if (P->kind == PIECE_SLAB && !(cut & ~3u)) {
        /* the pixel crosses the band's edges only (half-planes 0, 1): the
         * strip's area in closed form (most line pixels), unless a dash
         * end is in it */
        int on = 1;
        if (P->dashed) {
            const ls_band *B = &L->band[P->band];
            on = dash_span(L, B, P->s0 + cu - B->phase, P->su);
        }
        if (on == 0) return 0;
        if (on > 0) return cut ? strip_below(P, P->b - cv) - strip_below(P, P->a - cv) : 1.0;
    }
    double hm = L->margin, far = 0;
    if (P->kind == PIECE_WEDGE) {
        /* outside the sector's box, or holding it all */
        if (x1 <= P->wx0 || x0 >= P->wx1 || y1 <= P->wy0 || y0 >= P->wy1) return 0;
        if (P->nhp == 2 && x0 <= P->wx0 && x1 >= P->wx1 && y0 <= P->wy0 && y1 >= P->wy1) return P->warea;
        far = sqrt(cu * cu + cv * cv);
        if (far - hm >= P->r1 || far + hm <= P->r0) return 0;
    }
    double bx[POLY_MAX], by[POLY_MAX], cx[POLY_MAX], cy[POLY_MAX];
    /* corners in (u, v) */
    const double X[4] = { x0, x1, x1, x0 }, Y[4] = { y0, y0, y1, y1 };
    for (int k = 0; k < 4; k++) {
        bx[k] = X[k] * ux + Y[k] * uy;
        by[k] = X[k] * uy - Y[k] * ux;
    }
    double *sx = bx, *sy = by, *tx = cx, *ty = cy;
    double pa = pix * pix;
    if (P->kind == PIECE_SLAB && !P->dashed) {
        /* the ends and cuts by clipping, the band's edges by the strip's
         * area in v */
        uint32_t n = clip_cut(L, P, cut & ~3u, &sx, &sy, &tx, &ty, 4);
        return n < 3 ? 0 : strip_area(sx, sy, n, P->a, P->b) / pa;
    }
    uint32_t n = clip_cut(L, P, cut, &sx, &sy, &tx, &ty, 4);
    if (n < 3) return 0;
    if (P->kind == PIECE_WEDGE) {
        double a1 = far + hm <= P->r1 ? poly_area(sx, sy, n) : poly_disc(sx, sy, n, P->r1);
        double a0 = P->r0 > 0 && far - hm < P->r0 ? poly_disc(sx, sy, n, P->r0) : 0;
        return (a1 - a0) / pa;
    }
    /* dashes: the on-intervals of s over the polygon's u range */
    const ls_band *B = &L->band[P->band];
    const double *d = L->dash + B->dash0;
    double umin = sx[0], umax = sx[0];
    for (uint32_t k = 1; k < n; k++) {
        umin = sx[k] < umin ? sx[k] : umin;
        umax = sx[k] > umax ? sx[k] : umax;
    }
    double s_lo = P->s0 + umin - B->phase, s_hi = P->s0 + umax - B->phase;
    double base = floor(s_lo / B->period) * B->period, area = 0;
    double whole = -1;
    for (; base <= s_hi; base += B->period) {
        double on0 = base;
        for (uint32_t j = 0; j < B->ndash; j += 2) {
            double on1 = on0 + d[j];
            if (on1 > s_lo && on0 < s_hi) {
                double lo = on0 + B->phase - P->s0, hi = on1 + B->phase - P->s0;
                if (lo <= umin && hi >= umax) {
                    if (whole < 0) whole = cut ? poly_area(sx, sy, n) : pa;
                    area += whole;
                } else {
                    area += strip_area(sy, sx, n, lo, hi); /* the part with u in [lo, hi] */
                }
            }
            on0 = on1 + d[j + 1];
        }
        if (base + B->period == base) break; /* s too large for the period: stop */
    }
    return area / pa;
}

/* Hermite mode: smoothstep of the pixel centre's distance to each edge. */
static double piece_hermite(const rs__linesym *L, const ls_ppc *P, uint32_t px, uint32_t py)
{
    double pix = L->pixel, x = ((double)px + 0.5) * pix - P->ox, y = ((double)py + 0.5) * pix - P->oy;
    double u = x * P->ux + y * P->uy, v = x * P->uy - y * P->ux;
    if (P->kind == PIECE_WEDGE) {
        /* the centre picks the piece; radial smoothing across the band */
        const double *h0 = HPP(L, P, 0), *h1 = HPP(L, P, 1);
        if (h0[1] * u + h0[2] * v < 0 || h1[1] * u + h1[2] * v < 0) return 0;
        double r = sqrt(u * u + v * v);
        double c = hermite(0.5 + (P->r1 - r) / pix) + (P->r0 > 0 ? hermite(0.5 + (r - P->r0) / pix) : 1.0) - 1.0;
        return c > 0 ? c : 0;
    }
    /* the other half-planes (ends, bisectors, junctions) by the centre */
    for (uint32_t k = 0; k < P->nhp; k++) {
        const double *h = HPP(L, P, k);
        if (k < 2) continue; /* the v limits: smoothed below */
        if (h[0] + h[1] * u + h[2] * v < 0) return 0;
    }
    double c = hermite(0.5 + (v - P->a) / pix) + hermite(0.5 + (P->b - v) / pix) - 1.0;
    if (!(c > 0)) return 0;
    if (P->dashed) {
        const ls_band *B = &L->band[P->band];
        const double *d = L->dash + B->dash0;
        double sx = P->s0 + u - B->phase, m = sx - floor(sx / B->period) * B->period, on0 = 0, best = 0;
        /* distance into the nearest on-interval, smoothed at both ends */
        for (uint32_t j = 0; j < B->ndash; j += 2) {
            for (int wrap = -1; wrap <= 1; wrap++) {
                double lo = on0 + wrap * B->period, hi = lo + d[j];
                double e = hermite(0.5 + (m - lo) / pix) + hermite(0.5 + (hi - m) / pix) - 1.0;
                if (e > best) best = e;
            }
            on0 += d[j] + d[j + 1];
        }
        c *= best;
    }
    return c;
}

/* ------------------------------------------------------------------------
 * Build
 * ---------------------------------------------------------------------- */

static uint32_t piece_poly(const ls_piece *P, double *x, double *y);

/* A piece's polygon (piece_poly), kept beside the piece while surfaces cut
 * it, so a surface that misses it costs no clipping. */
typedef struct ls_poly {
    uint32_t n;
    double x[POLY_MAX], y[POLY_MAX];
} ls_poly;

/* Local point (x, y) of piece coordinates (u, v): the inverse of (u, v) =
 * (d.u, d.(uy, -ux)) for d = (x - ox, y - oy). */
static inline void piece_point(const ls_piece *P, double u, double v, double *x, double *y)
{
    *x = P->ox + u * P->ux + v * P->uy;
    *y = P->oy + u * P->uy - v * P->ux;
}

static void piece_finish(const rs__linesym *L, const ls_piece *Q, const ls_poly *poly, ls_ppc *C, ls_pbuild *B,
                         double *hpp);

/* Append piece P, finished (piece_finish), as the painter's record (pp,
 * its half-planes in hpp) and the index build's (pb). */
/* Bytes of a piece while building (painter's record and index build's). */
#define PIECE_BYTES (sizeof(ls_ppc) + sizeof(ls_pbuild))
#define HP_BYTES (4 * sizeof(double))

/* Room for at most the budget: capacity `want`, cut to what the bytes left
 * after `other` hold of items of `item` bytes (at least `need`). */
static size_t budget_cap(const rs__linesym *L, size_t want, size_t need, uint64_t other, size_t item)
{
    if (!L->budget || other >= L->budget) return want;
    uint64_t fit = (L->budget - other) / item;
    if (fit < need) fit = need;
    return fit < want ? (size_t)fit : want;
}

/* poly: P's polygon (piece_poly's doubles) when the caller has it, else NULL. */
static rs_result push_piece(rs_ctx *ctx, rs__linesym *L, const ls_piece *P, const ls_poly *poly)
{
    /* all roads' pieces together (rs_limits.max_linesym_bytes) */
    if (L->budget &&
        (uint64_t)(L->npc + 1) * PIECE_BYTES + (uint64_t)(L->nhpp + HP_MAX) * HP_BYTES > L->budget) {
        L->over_budget = 1;
        return RS_ERR_LIMIT;
    }
    if (L->npc == L->cap) {
        size_t nc = budget_cap(L, L->cap ? 2 * L->cap : L->cap0, L->npc + 1, (uint64_t)L->hcap * HP_BYTES,
                               PIECE_BYTES), b1, b2;
        if (nc > UINT32_MAX || !rs__mul_size(nc, sizeof(ls_ppc), &b1) || !rs__mul_size(nc, sizeof(ls_pbuild), &b2))
            return RS_ERR_LIMIT;
        void *np = L->pp, *nb = L->pb;
        rs_result g = rs__resize(ctx, &np, L->cap * sizeof(ls_ppc), b1);
        L->pp = np;
        if (!g) g = rs__resize(ctx, &nb, L->cap * sizeof(ls_pbuild), b2);
        L->pb = nb;
        if (g) return g;
        L->cap = nc;
    }
    if (L->hcap - L->nhpp < HP_MAX) {
        size_t nc = budget_cap(L, L->hcap ? 2 * L->hcap : 4 * L->cap0, L->nhpp + HP_MAX, (uint64_t)L->cap * PIECE_BYTES,
                               HP_BYTES), bytes;
        if (nc > UINT32_MAX || !rs__mul_size(nc, 4 * sizeof(double), &bytes)) return RS_ERR_LIMIT;
        void *nh = L->hpp;
        rs_result g = rs__resize(ctx, &nh, L->hcap * 4 * sizeof(double), bytes);
        if (g) return g;
        L->hpp = nh;
        L->hcap = nc;
    }
    ls_ppc *C = &L->pp[L->npc];
    ls_pbuild *B = &L->pb[L->npc++];
    /* the piece's own values, then what piece_finish derives over them */
    C->ox = P->ox, C->oy = P->oy, C->ux = P->ux, C->uy = P->uy, C->a = P->a, C->b = P->b, C->su = P->su;
    C->uin0 = P->uin0, C->uin1 = P->uin1, C->st_lo = P->st_lo, C->st_e = P->st_e, C->st_q = P->st_q;
    C->st_h = P->st_h, C->s0 = P->s0, C->ru0 = P->ru0, C->ru1 = P->ru1, C->rv0 = P->rv0, C->rv1 = P->rv1;
    C->r0 = P->r0, C->r1 = P->r1, C->wx0 = P->wx0, C->wy0 = P->wy0, C->wx1 = P->wx1, C->wy1 = P->wy1;
    C->warea = P->warea, C->nhp = P->nhp, C->kind = P->kind, C->band = P->band, C->dashed = P->dashed;
    C->hp0 = (uint32_t)L->nhpp;
    double du = P->ux * L->pixel, dv = P->uy * L->pixel; /* 0 for a subnormal pixel */
    C->iku = fabs(P->ux) < 1e-12 || du == 0 ? 0 : 1 / du;
    C->ikv = fabs(P->uy) < 1e-12 || dv == 0 ? 0 : 1 / dv;
    C->cbase = P->ox / L->pixel - 0.5;
    B->len = P->len, B->x0 = P->x0, B->y0 = P->y0, B->x1 = P->x1, B->y1 = P->y1;
    B->gx0 = P->gx0, B->gx1 = P->gx1, B->gy0 = P->gy0, B->gy1 = P->gy1;
    piece_finish(L, P, poly, C, B, L->hpp + 4 * L->nhpp);
    L->nhpp += P->nhp;
    return RS_OK;
}

/* The painter's constants of a piece: half-plane extents, box, pixel
 * rows and columns, the slab's safe u range. poly: Q's polygon if known
 * (the cuts made it: the same clips in the same order as piece_poly). */
static void piece_finish(const rs__linesym *L, const ls_piece *Q, const ls_poly *poly, ls_ppc *C, ls_pbuild *B,
                         double *hpp)
{
    double pix = L->pixel, hp = 0.5 * pix, ax = fabs(Q->ux), ay = fabs(Q->uy);
    /* half-plane c0 + cu u + cv v in local (x, y): normal (cu ux + cv uy, cu uy - cv ux) */
    double sup[HP_MAX];
    for (uint32_t k = 0; k < Q->nhp; k++) {
        double cu = Q->hp[k][1], cv = Q->hp[k][2];
        sup[k] = hp * (fabs(cu * Q->ux + cv * Q->uy) + fabs(cu * Q->uy - cv * Q->ux));
        hpp[4 * k] = Q->hp[k][0];
        hpp[4 * k + 1] = cu;
        hpp[4 * k + 2] = cv;
        hpp[4 * k + 3] = sup[k];
    }
    const double su = hp * (ax + ay);
    C->su = su;
    /* the piece's polygon (a wedge's: its box cut by the two radii):
     * its box and ranges, a little wider against rounding */
    double qx[POLY_MAX], qy[POLY_MAX], bx0 = DBL_MAX, bx1 = -DBL_MAX, by0 = DBL_MAX, by1 = -DBL_MAX;
    const double *px = qx, *py = qy;
    double pu0 = DBL_MAX, pu1 = -DBL_MAX, pv0 = DBL_MAX, pv1 = -DBL_MAX;
    int herm = L->aa == RS__AA_HERMITE;
    uint32_t n;
    if (herm && Q->kind == PIECE_SLAB) {
        /* Hermite: the centres that pick the piece, with v half a pixel
         * beyond the band (its smoothing) */
        ls_piece G = *Q;
        G.hp[0][0] += hp;
        G.hp[1][0] += hp;
        n = piece_poly(&G, qx, qy);
    } else if (poly) {
        n = poly->n;
        px = poly->x;
        py = poly->y;
    } else {
        n = piece_poly(Q, qx, qy);
    }
    for (uint32_t k = 0; k < n; k++) {
        double x, y;
        piece_point(Q, px[k], py[k], &x, &y);
        bx0 = rs__fmin(bx0, x), bx1 = rs__fmax(bx1, x), by0 = rs__fmin(by0, y), by1 = rs__fmax(by1, y);
        pu0 = rs__fmin(pu0, px[k]), pu1 = rs__fmax(pu1, px[k]), pv0 = rs__fmin(pv0, py[k]), pv1 = rs__fmax(pv1, py[k]);
    }
    if (n < 3) { /* nothing left of it (the inner side of a sharp bend): never visited */
        B->gx0 = B->gy0 = 1;
        B->gx1 = B->gy1 = 0;
        C->ru0 = C->rv0 = 1;
        C->ru1 = C->rv1 = 0;
        return;
    }
    double eb = 1e-9 * (1 + rs__fmax(fabs(Q->ox), fabs(Q->oy)) + Q->len + fabs(Q->a) + fabs(Q->b) + Q->r1);
    if (Q->kind == PIECE_WEDGE && herm) {
        /* Hermite: the centre in the sector's angle, within half a pixel of its radii */
        bx0 = Q->ox + Q->wx0, bx1 = Q->ox + Q->wx1, by0 = Q->oy + Q->wy0, by1 = Q->oy + Q->wy1;
    } else if (Q->kind == PIECE_WEDGE) {
        bx0 = rs__fmax(bx0, Q->ox + Q->wx0), bx1 = rs__fmin(bx1, Q->ox + Q->wx1);
        by0 = rs__fmax(by0, Q->oy + Q->wy0), by1 = rs__fmin(by1, Q->oy + Q->wy1);
    }
    /* pixels that overlap the box */
    B->gx0 = ceil((bx0 - eb) / pix - 1);
    B->gx1 = floor((bx1 + eb) / pix);
    B->gy0 = ceil((by0 - eb) / pix - 1);
    B->gy1 = floor((by1 + eb) / pix);
    if (Q->kind == PIECE_SLAB) {
        double p1 = pix * ax, p2 = pix * ay, lo = p1 < p2 ? p1 : p2, hi = p1 < p2 ? p2 : p1;
        C->st_lo = lo;
        C->st_e = 0.5 * (lo + hi);
        /* a subnormal pixel (fuzzed options) may make hi or hi lo 0: e is
         * then 0 or the ramp below lo too thin to matter */
        C->st_h = hi > 0 ? 1 / hi : 0;
        C->st_q = hi * lo > 0 ? 0.5 / (hi * lo) : 0;
        C->ru0 = pu0 - su - eb;
        C->ru1 = pu1 + su + eb;
        C->rv0 = pv0 - su - eb;
        C->rv1 = pv1 + su + eb;
        /* A centre that passes the v limits has v in (a - su, b + su);
         * there half-plane k >= 2 holds with the square's extent to spare
         * where cu u >= sup - c0 - min over v of cv v (by a margin). */
        double ulo = -DBL_MAX, uhi = DBL_MAX, va = Q->a - su, vb = Q->b + su;
        for (uint32_t k = 2; k < Q->nhp; k++) {
            double c0 = Q->hp[k][0], cu = Q->hp[k][1], cv = Q->hp[k][2];
            double need = sup[k] - c0 - rs__fmin(cv * va, cv * vb) + eb * (1 + fabs(cu) + fabs(cv));
            if (cu > 0) ulo = rs__fmax(ulo, need / cu);
            else if (cu < 0) uhi = rs__fmin(uhi, need / cu);
            else if (need > 0) uhi = -DBL_MAX; /* never safe */
        }
        C->uin0 = ulo;
        C->uin1 = uhi;
    }
}

/* Local box of a piece's polygon outline, grown by the pixel margin. */
static void piece_box(const rs__linesym *L, ls_piece *P, double len, double a, double b)
{
    double m = L->margin;
    if (P->kind == PIECE_WEDGE) { /* the disc's (the junction cuts test against it; the painter uses the sector's) */
        P->x0 = P->ox - P->r1 - m;
        P->x1 = P->ox + P->r1 + m;
        P->y0 = P->oy - P->r1 - m;
        P->y1 = P->oy + P->r1 + m;
        return;
    }
    const double U[4] = { -m, len + m, len + m, -m }, V[4] = { a - m, a - m, b + m, b + m };
    P->x0 = P->y0 = DBL_MAX;
    P->x1 = P->y1 = -DBL_MAX;
    for (int k = 0; k < 4; k++) {
        double x, y;
        piece_point(P, U[k], V[k], &x, &y);
        P->x0 = rs__fmin(P->x0, x);
        P->x1 = rs__fmax(P->x1, x);
        P->y0 = rs__fmin(P->y0, y);
        P->y1 = rs__fmax(P->y1, y);
    }
}

typedef struct ls_vtx {
    double x, y;
} ls_vtx;
/* rs__road_local_walk writes them as an array of doubles, stride 2 */
typedef char ls_vtx_is_two_doubles[sizeof(ls_vtx) == 2 * sizeof(double) ? 1 : -1];

/* Segment i's direction d (unit) in the frame of segment j: (d.u_j, d.n_j). */
static void in_frame(double dx, double dy, double ux, double uy, double *fu, double *fv)
{
    *fu = dx * ux + dy * uy;
    *fv = dx * uy - dy * ux;
}

/* Cut the line (ox, oy) + u (ux, uy), u in [0, len], to the map grown by
 * ext: [*lo, *hi]; 0 when nothing is left. */
static int cut_to_map(double ox, double oy, double ux, double uy, double len, double ext, double wmap, double hmap,
                      double *lo, double *hi)
{
    const double d[2] = { ux, uy }, o[2] = { ox, oy }, b0[2] = { -ext, -ext }, b1[2] = { wmap + ext, hmap + ext };
    *lo = 0;
    *hi = len;
    for (int k = 0; k < 2; k++) {
        if (d[k] == 0) {
            if (o[k] < b0[k] || o[k] > b1[k]) return 0;
            continue;
        }
        double t0 = (b0[k] - o[k]) / d[k], t1 = (b1[k] - o[k]) / d[k];
        if (t0 > t1) { double t = t0; t0 = t1; t1 = t; }
        *lo = rs__fmax(*lo, t0);
        *hi = rs__fmin(*hi, t1);
    }
    return *lo <= *hi;
}

/* cut_to_map for the segment from (ox, oy) to (bx, by) (unit u, length
 * len), with the cut start's point (*cx, *cy), *rest (the cut start's
 * distance to B) and *span (hi - lo). An end past a million map sizes
 * carries rounding of metres (a road from 10^20 m): the cut is then
 * measured from the near end (rs__cut_far_end's reason), or from the
 * disc's centre when both are far, as the road field cuts the surface
 * (rs__clip_far), so the lines lie on it. *far_cut: one of those two ways
 * was taken (*cx, *cy, *rest and *span exact from the near end). */
static int cut_segment(double ox, double oy, double bx, double by, double ux, double uy, double len, double ext,
                       double wmap, double hmap, double *lo, double *hi, double *span, double *rest, double *cx,
                       double *cy, int *far_cut)
{
    double huge = 1e6 * (wmap + hmap + 2 * ext), mx = 0.5 * wmap, my = 0.5 * hmap;
    int a_near = fabs(ox - mx) <= huge && fabs(oy - my) <= huge, b_near = fabs(bx - mx) <= huge && fabs(by - my) <= huge;
    *far_cut = 0;
    if (a_near) {
        if (!cut_to_map(ox, oy, ux, uy, len, ext, wmap, hmap, lo, hi)) return 0;
        *rest = len - *lo;
        *span = *hi - *lo;
        *cx = *lo > 0 ? ox + *lo * ux : ox;
        *cy = *lo > 0 ? oy + *lo * uy : oy;
        return 1;
    }
    *far_cut = 1;
    double lb, hb;
    if (b_near) { /* from B backwards */
        if (!cut_to_map(bx, by, -ux, -uy, len, ext, wmap, hmap, &lb, &hb)) return 0;
        *lo = len - hb, *hi = len - lb, *rest = hb, *span = hb - lb;
        *cx = bx - hb * ux, *cy = by - hb * uy;
        return 1;
    }
    double ax2 = ox, ay2 = oy, bx2 = bx, by2 = by, along = 0;
    if (!rs__clip_far(&ax2, &ay2, &bx2, &by2, wmap, hmap, ext, huge, &along)) return 0;
    double l2 = rs__arc_len(ax2, ay2, bx2, by2);
    if (!cut_to_map(ax2, ay2, ux, uy, l2, ext, wmap, hmap, &lb, &hb)) return 0;
    *lo = along + lb, *hi = along + hb, *rest = len - *lo, *span = hb - lb;
    *cx = ax2 + lb * ux, *cy = ay2 + lb * uy;
    return 1;
}

/* ------------------------------------------------------------------------
 * Junctions: a road's lines stop at the edge of every other road's surface
 * (docs/linesym.md "Junctions").
 * ---------------------------------------------------------------------- */

/* One segment of a road surface: the rectangle u in [-r, len + r],
 * |v| <= r of its frame (square ends: a superset of the round caps and
 * joins). */
typedef struct ls_surf {
    double ax, ay, ux, uy, len, r;
    double u0, u1;        /* the rectangle along u: -r .. len + r, or shorter at a T (below) */
    uint32_t road;
    uint32_t cap;         /* bit 0: a free road end with a round cap at u = 0, bit 1: at u = len (the
                             rectangle's square end stands for the cap's half disc: cap_tangents) */
    uint32_t only, skip;  /* cuts only the stroke `only` / every stroke but `skip` (NO_STROKE: any) */
    uint32_t only2, skip2; /* and a second one (a through road of two strokes, rs__network_tees) */
    uint32_t skip3, skip4; /* the same for a one-segment record's other end at a T (junc_build) */
    int clip;             /* 1: only its part with cx x + cy y <= cc (a trimmed end at a T,
                             docs/network.md "Ends at a T": the surface stops at the far edge line) */
    double cx, cy, cc;
    int clip2;            /* 1: and only its part with cx2 x + cy2 y <= cc2 (the cut-back copy at a T
                             on the inner side of a bent street: one keep line per leg) */
    double cx2, cy2, cc2;
} ls_surf;

#define NO_STROKE RS__NO_STROKE
#define TEE_EDGE_ZONE 2.0 /* metres inside a through road's edge where its lines stop at a side road's mouth */
typedef rs__tee ls_tee;

/* Road end points and the unit directions pointing away from them along
 * the road (to tell a road that continues another from one that meets it). */
typedef struct ls_ends {
    double x[2], y[2], dx[2], dy[2];
    int valid;
} ls_ends;

typedef struct ls_junc {
    ls_grid grid;          /* its own cells, square */
    ls_surf *sf;
    size_t nsf;
    uint32_t *start, *ids; /* CSR per index cell, like the pieces */
    uint32_t *stamp;       /* per surface: last query that saw it */
    uint32_t query;
    const ls_ends *ends;
    uint64_t work, limit;  /* list entries visited by push_cut; rs_limits.max_field_work */
    const uint32_t *stroke_of; /* per road (NULL: every road its own stroke) */
    uint8_t *nocut;        /* per road: junction_cuts=no (its lines uncut, its surface cuts none) */
    uint8_t *car;          /* per road: not a path, footway or cycleway */
    const int *prio;       /* per road: rs__road_priority (NULL: all equal) */
    int *prio_own;         /* prio when worked out here */
    double *keep;          /* per road: its lines within this of its centre line run on over
                              the surface of a lower-ranked car road crossing it */
    uint32_t own_road;     /* push_cut's last road (UINT32_MAX: none) and the end of its */
    size_t own_end;        /* surfaces in sf: a road's pieces come one after another */
} ls_junc;

/* Roads r and q continue each other: they share an end point and leave it
 * in opposite directions (within 30 degrees of straight). */
static int continues(const ls_junc *J, uint32_t r, uint32_t q)
{
    const ls_ends *a = &J->ends[r], *b = &J->ends[q];
    if (!a->valid || !b->valid) return 0;
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++)
            if (a->x[i] == b->x[j] && a->y[i] == b->y[j] && a->dx[i] * b->dx[j] + a->dy[i] * b->dy[j] < -0.866)
                return 1;
    return 0;
}

/* Polygon of a piece (its box cut by its half-planes), in its frame. */
static uint32_t piece_poly(const ls_piece *P, double *x, double *y)
{
    double bx[POLY_MAX], by[POLY_MAX];
    const double X[4] = { P->x0, P->x1, P->x1, P->x0 }, Y[4] = { P->y0, P->y0, P->y1, P->y1 };
    for (int k = 0; k < 4; k++) {
        double dx = X[k] - P->ox, dy = Y[k] - P->oy;
        x[k] = dx * P->ux + dy * P->uy;
        y[k] = dx * P->uy - dy * P->ux;
    }
    uint32_t n = 4;
    for (uint32_t k = 0; k < P->nhp && n; k++) {
        n = clip_poly(x, y, n, P->hp[k][0], P->hp[k][1], P->hp[k][2], bx, by);
        memcpy(x, bx, n * sizeof *x);
        memcpy(y, by, n * sizeof *y);
    }
    return n;
}

/* Does the piece with polygon (x, y)[n] keep any area once clipped by
 * the nh further half-planes hp (in that order: the clips piece_poly would
 * make of them after its first ones, so the same doubles)? The clipped
 * polygon goes to g. */
static int nonempty_hp(const double *x, const double *y, uint32_t n, const double (*hp)[3], uint32_t nh, ls_poly *g)
{
    double bx[2][POLY_MAX], by[2][POLY_MAX];
    const double *sx = x, *sy = y;
    for (uint32_t k = 0; k < nh && n; k++) {
        double *dx = k + 1 == nh ? g->x : bx[k & 1], *dy = k + 1 == nh ? g->y : by[k & 1];
        n = clip_poly(sx, sy, n, hp[k][0], hp[k][1], hp[k][2], dx, dy);
        sx = dx;
        sy = dy;
    }
    g->n = n;
    return n >= 3 && poly_area(g->x, g->y, n) > 1e-12;
}

/* out = P with the nh half-planes hp appended (the caller checked that
 * P->nlim + nh <= HP_MAX); g: out's polygon. A slab's half-plane past its
 * v limits that holds every corner of g by `drop` or more is left out and
 * no longer counted: it cuts no pixel the piece touches (drop: the pixel's
 * diagonal; 0 keeps all). So the pieces of a line crossed by many roads in
 * a row keep only the cuts next to them, and every crossing can cut (the
 * far piece took one more half-plane per crossing and stayed whole from
 * about the sixth on until 6 December 2026). */
static void piece_with(ls_piece *out, const ls_piece *P, const double (*hp)[3], uint32_t nh, const ls_poly *g,
                       double drop)
{
    *out = *P;
    for (uint32_t k = 0; k < nh; k++) {
        out->hp[out->nhp][0] = hp[k][0];
        out->hp[out->nhp][1] = hp[k][1];
        out->hp[out->nhp][2] = hp[k][2];
        out->nhp++;
        out->nlim++;
    }
    if (!(drop > 0) || out->kind != PIECE_SLAB) return;
    uint32_t m = 2;
    for (uint32_t k = 2; k < out->nhp; k++) {
        const double *h = out->hp[k];
        uint32_t i = 0;
        while (i < g->n && h[0] + h[1] * g->x[i] + h[2] * g->y[i] >= drop) i++;
        if (i == g->n && g->n >= 3) {
            out->nlim--;
            continue;
        }
        if (m != k) out->hp[m][0] = h[0], out->hp[m][1] = h[1], out->hp[m][2] = h[2];
        m++;
    }
    out->nhp = m;
}

/* Round caps. Past a free road end the surface is a half disc, which the
 * rectangle's square end holds with its two corners: a line crossing a
 * corner stopped up to (sqrt 2 - 1) r short of the surface (0.6 m on
 * docs/examples/network_spike.txt, where the shader, cutting with the
 * capsules, drew it on). For the piece at hand the cap is the square's
 * part within a few tangents of the disc: starting from P's part past
 * the end (within the band), each tangent is taken at the angle of that
 * part's vertex farthest from the end point and clips it, until no
 * vertex is more than tol beyond the circle. So the cut holds the cap
 * and stands off it by at most tol where it meets the piece; a piece the
 * tangents do not settle within CAP_TAN_MAX also keeps the square end
 * (never more cut than by the square). */
#define CAP_TAN_MAX 4
/* the most parts of one cut: two beside, the end parts (tangents and
 * square ends), two beyond the clip lines */
#define CUT_PARTS (2 + 2 * (CAP_TAN_MAX + 1) + 2)

/* The tangents of the cap at end e (centre u = ce, outward sign se) for
 * the piece with (u, v) vertices qu, qv[n] in Q's frame, as (cos, sin) of
 * their angles from the outward direction into t; returns their count,
 * or CAP_TAN_MAX + 1 when the square end must be kept as well (not
 * settled). 0: nothing of P lies more than tol outside the cap. */
static uint32_t cap_tangents(const double *qu, const double *qv, uint32_t n, double ce, double se, double r, double tol,
                             double (*t)[2])
{
    double ax[POLY_MAX], ay[POLY_MAX], bx[POLY_MAX], by[POLY_MAX];
    int past = 0;
    for (uint32_t k = 0; k < n; k++) ax[k] = se * (qu[k] - ce), ay[k] = qv[k], past |= ax[k] > 0;
    if (!past) return 0; /* (most pieces a cap's rectangle cuts stop short of it) */
    uint32_t m = clip_poly(ax, ay, n, 0, 1, 0, bx, by); /* past the end */
    m = clip_poly(bx, by, m, r, 0, -1, ax, ay);          /* within the band */
    m = clip_poly(ax, ay, m, r, 0, 1, bx, by);
    const double far2 = (r + tol) * (r + tol);
    for (uint32_t k = 0; k < CAP_TAN_MAX; k++) {
        if (m < 3) return k;
        uint32_t f = 0;
        double best = -1;
        for (uint32_t i = 0; i < m; i++) {
            double d2 = bx[i] * bx[i] + by[i] * by[i];
            if (d2 > best) best = d2, f = i;
        }
        if (!(best > far2)) return k;
        double rho = sqrt(best);
        t[k][0] = bx[f] / rho;
        t[k][1] = by[f] / rho;
        m = clip_poly(bx, by, m, r, -t[k][0], -t[k][1], ax, ay);
        memcpy(bx, ax, m * sizeof *bx);
        memcpy(by, ay, m * sizeof *by);
    }
    for (uint32_t i = 0; m >= 3 && i < m; i++)
        if (bx[i] * bx[i] + by[i] * by[i] > far2) return CAP_TAN_MAX + 1;
    return CAP_TAN_MAX;
}

/* Q's frame and clip lines in P's frame: v' = cv0 + u fvu + v fvv and
 * u' = cu0 + u fuu + v fuv (Q's left normal and direction), and
 * n.(p - Q.a) = cn0 + u fnu + v fnv against cq for the clip line (dn0,
 * gnu, gnv against dq for the second). */
typedef struct ls_qframe {
    double cv0, fvu, fvv, cu0, fuu, fuv;
    double cn0, fnu, fnv, cq, dn0, gnu, gnv, dq;
} ls_qframe;

static void q_frame(const ls_piece *P, const ls_surf *Q, ls_qframe *F)
{
    double ox = P->ox - Q->ax, oy = P->oy - Q->ay;
    double nqx = Q->uy, nqy = -Q->ux; /* Q's left normal */
    double npx = P->uy, npy = -P->ux; /* P's left normal */
    F->cv0 = ox * nqx + oy * nqy, F->fvu = P->ux * nqx + P->uy * nqy, F->fvv = npx * nqx + npy * nqy;
    F->cu0 = ox * Q->ux + oy * Q->uy, F->fuu = P->ux * Q->ux + P->uy * Q->uy, F->fuv = npx * Q->ux + npy * Q->uy;
    F->cn0 = ox * Q->cx + oy * Q->cy, F->fnu = P->ux * Q->cx + P->uy * Q->cy, F->fnv = npx * Q->cx + npy * Q->cy;
    F->cq = Q->cc - (Q->ax * Q->cx + Q->ay * Q->cy);
    F->dn0 = ox * Q->cx2 + oy * Q->cy2, F->gnu = P->ux * Q->cx2 + P->uy * Q->cy2, F->gnv = npx * Q->cx2 + npy * Q->cy2;
    F->dq = Q->cc2 - (Q->ax * Q->cx2 + Q->ay * Q->cy2);
}

/* The part of P within the nh half-planes h, when it keeps area, as the
 * next piece of out (and its polygon). */
static void try_part(const ls_piece *P, const ls_poly *G, const double (*h)[3], uint32_t nh, ls_piece *out,
                     ls_poly *outg, int *m, double drop)
{
    if (nonempty_hp(G->x, G->y, G->n, h, nh, &outg[*m])) {
        piece_with(&out[*m], P, h, nh, &outg[*m], drop);
        (*m)++;
    }
}

/* The parts beyond Q's clip lines, within the k half-planes h[0 .. k)
 * (the rest of Q: its band and its ends) and, for the second line, within
 * the first. */
static void clip_parts(const ls_piece *P, const ls_poly *G, const ls_surf *Q, const ls_qframe *F, double (*h)[3],
                       uint32_t k, ls_piece *out, ls_poly *outg, int *m, double drop)
{
    if (Q->clip) { /* the rectangle's part beyond the clip line stays */
        h[k][0] = F->cn0 - F->cq, h[k][1] = F->fnu, h[k][2] = F->fnv;
        try_part(P, G, (const double(*)[3])h, k + 1, out, outg, m, drop);
    }
    if (Q->clip2) { /* and its part within the first clip line beyond the second */
        if (Q->clip) h[k][0] = F->cq - F->cn0, h[k][1] = -F->fnu, h[k][2] = -F->fnv, k++;
        h[k][0] = F->dn0 - F->dq, h[k][1] = F->gnu, h[k][2] = F->gnv;
        try_part(P, G, (const double(*)[3])h, k + 1, out, outg, m, drop);
    }
}

/* cut_piece where a round cap of Q meets P more than tol outside its
 * disc: the parts beside Q (one half-plane each), past each end (a cap's
 * tangents, in turn, or the square end), and past the clip lines, each
 * within the half-planes before it. -1 when no cap needs a tangent or a
 * part would pass HP_MAX (cut_piece then cuts with the square ends). */
static int cut_capped(const ls_piece *P, const ls_poly *G, const ls_surf *Q, const ls_qframe *F, const double *qu,
                      const double *qv, int in_v, ls_piece *out, ls_poly *outg, double drop, double tol)
{
    double r = Q->r;
    double tan_[2][CAP_TAN_MAX][2];
    uint32_t nt[2] = { 0, 0 }, any = 0;
    for (int e = 0; e < 2; e++)
        if (Q->cap >> e & 1) {
            nt[e] = cap_tangents(qu, qv, G->n, e ? Q->len : 0, e ? 1 : -1, r, tol, tan_[e]);
            any |= nt[e];
        }
    if (!any) return -1;
    /* each end's half-planes, the "inside" form (c0 + cu x + cv y >= 0 in P's frame) */
    double end[2][CAP_TAN_MAX + 1][3];
    uint32_t ne[2];
    for (int e = 0; e < 2; e++) {
        uint32_t k = 0;
        if (Q->cap >> e & 1) {
            double ce = e ? Q->len : 0, se = e ? 1 : -1;
            for (; k < nt[e] && k < CAP_TAN_MAX; k++) {
                /* r - se (u' - ce) cos - v' sin >= 0 */
                double cs = tan_[e][k][0], sn = tan_[e][k][1];
                double a0 = r + se * ce * cs, au = -se * cs, av = -sn;
                end[e][k][0] = a0 + au * F->cu0 + av * F->cv0;
                end[e][k][1] = au * F->fuu + av * F->fvu;
                end[e][k][2] = au * F->fuv + av * F->fvv;
            }
        }
        if (!(Q->cap >> e & 1) || nt[e] > CAP_TAN_MAX) { /* the rectangle's end */
            if (e) end[e][k][0] = Q->u1 - F->cu0, end[e][k][1] = -F->fuu, end[e][k][2] = -F->fuv;
            else end[e][k][0] = F->cu0 - Q->u0, end[e][k][1] = F->fuu, end[e][k][2] = F->fuv;
            k++;
        }
        ne[e] = k;
    }
    double h[HP_MAX][3];
    uint32_t nb = in_v ? 0 : 2, need = nb + ne[0] + ne[1] + (Q->clip ? 1u : 0u) + (Q->clip2 ? 1u : 0u);
    if (P->nlim + need > HP_MAX) return -1;
    int m = 0;
#define LS_SET(j, a0, a1, a2) (h[j][0] = (a0), h[j][1] = (a1), h[j][2] = (a2))
    if (!in_v) {
        LS_SET(0, F->cv0 - r, F->fvu, F->fvv); /* v' >= r */
        try_part(P, G, (const double(*)[3])h, 1, out, outg, &m, drop);
        LS_SET(0, -F->cv0 - r, -F->fvu, -F->fvv); /* v' <= -r */
        try_part(P, G, (const double(*)[3])h, 1, out, outg, &m, drop);
        LS_SET(0, F->cv0 + r, F->fvu, F->fvv);
        LS_SET(1, r - F->cv0, -F->fvu, -F->fvv);
    }
    /* past each end: beyond its k-th half-plane, within those before it */
    for (int e = 0; e < 2; e++)
        for (uint32_t k = 0; k < ne[e]; k++) {
            for (uint32_t j = 0; j < k; j++) LS_SET(nb + j, end[e][j][0], end[e][j][1], end[e][j][2]);
            LS_SET(nb + k, -end[e][k][0], -end[e][k][1], -end[e][k][2]);
            try_part(P, G, (const double(*)[3])h, nb + k + 1, out, outg, &m, drop);
        }
    uint32_t k = nb;
    for (int e = 0; e < 2; e++)
        for (uint32_t j = 0; j < ne[e]; j++, k++) LS_SET(k, end[e][j][0], end[e][j][1], end[e][j][2]);
#undef LS_SET
    clip_parts(P, G, Q, F, h, k, out, outg, &m, drop);
    return m;
}

/* P minus surface rectangle Q (cut by its clip lines, its square ends
 * taken in at round caps): up to CUT_PARTS disjoint pieces into out
 * (6 without caps); returns their count, -1 when Q misses P (P stays
 * whole), or -2 when a piece would need more half-planes than it holds (P
 * is then kept whole, its lines run on; cutset_cut may have it halved).
 * tol: the caps' (cap_tangents). */
static int cut_piece(const ls_piece *P, const ls_poly *G, const ls_surf *Q, ls_piece *out, ls_poly *outg, double drop,
                     double tol)
{
    ls_qframe F;
    q_frame(P, Q, &F);
    double r = Q->r, lo = Q->u0, hi = Q->u1;
    const double *x = G->x, *y = G->y;
    uint32_t n = G->n;
    if (n < 3) return -1;
    int out_v_hi = 1, out_v_lo = 1, out_u_lo = 1, out_u_hi = 1, out_clip = Q->clip, out_clip2 = Q->clip2;
    int in_v = 1, in_u = 1; /* P wholly within Q's sides / within its ends */
    double qu[POLY_MAX], qv[POLY_MAX]; /* P's polygon in Q's frame */
    for (uint32_t k = 0; k < n; k++) {
        double v = F.cv0 + x[k] * F.fvu + y[k] * F.fvv, u = F.cu0 + x[k] * F.fuu + y[k] * F.fuv;
        qu[k] = u, qv[k] = v;
        out_v_hi &= v >= r;
        out_v_lo &= v <= -r;
        out_u_lo &= u <= lo;
        out_u_hi &= u >= hi;
        in_v &= v > -r && v < r;
        in_u &= u > lo && u < hi;
        out_clip &= F.cn0 + x[k] * F.fnu + y[k] * F.fnv >= F.cq;
        out_clip2 &= F.dn0 + x[k] * F.gnu + y[k] * F.gnv >= F.dq;
    }
    if (out_v_hi || out_v_lo || out_u_lo || out_u_hi || out_clip || out_clip2) return -1;
    if (Q->cap && tol > 0) {
        int m = cut_capped(P, G, Q, &F, qu, qv, in_v, out, outg, drop, tol);
        if (m >= 0) return m;
    }
    /* the most half-planes a piece takes: 3 beside Q, 5 beyond its clip
     * line, 5 or 6 beyond the second (P stays whole when they pass HP_MAX) */
    uint32_t need = Q->clip2 ? 5u + (Q->clip ? 1u : 0u) : Q->clip ? 5u : 3u;
    /* P within Q's sides (a line under a road running along it, or crossing
     * it): its parts beyond Q's ends need one half-plane each, not three;
     * P within Q's ends: its parts beside Q need one each. So a line under
     * several surfaces in a row (a service road along a primary's edge, a
     * street crossing many) is cut by each, where the third cut overflowed
     * and left the line whole until 6 December 2026 */
    int slim = !Q->clip && !Q->clip2 && (in_v || in_u);
    if (slim) need = 1;
    if (P->nlim + need > HP_MAX) return -2; /* (Q would cut P: the caller may halve P) */
    int m = 0;
    double h[HP_MAX][3];
    /* each candidate piece's half-planes, clipped from P's polygon, kept when
     * it keeps area */
#define LS_HP(j, a0, a1, a2) (h[j][0] = (a0), h[j][1] = (a1), h[j][2] = (a2))
#define LS_TRY(nh) try_part(P, G, (const double(*)[3])h, (nh), out, outg, &m, drop)
    if (slim) {
        if (in_v) {
            LS_HP(0, lo - F.cu0, -F.fuu, -F.fuv); /* u' <= u0 */
            LS_TRY(1);
            LS_HP(0, F.cu0 - hi, F.fuu, F.fuv); /* u' >= u1 */
            LS_TRY(1);
        } else {
            LS_HP(0, F.cv0 - r, F.fvu, F.fvv); /* v' >= r */
            LS_TRY(1);
            LS_HP(0, -F.cv0 - r, -F.fvu, -F.fvv); /* v' <= -r */
            LS_TRY(1);
        }
        return m;
    }
    LS_HP(0, F.cv0 - r, F.fvu, F.fvv); /* v' >= r */
    LS_TRY(1);
    LS_HP(0, -F.cv0 - r, -F.fvu, -F.fvv); /* v' <= -r */
    LS_TRY(1);
    LS_HP(0, F.cv0 + r, F.fvu, F.fvv);
    LS_HP(1, r - F.cv0, -F.fvu, -F.fvv);
    LS_HP(2, lo - F.cu0, -F.fuu, -F.fuv); /* u' <= u0 */
    LS_TRY(3);
    LS_HP(2, F.cu0 - hi, F.fuu, F.fuv); /* u' >= u1 */
    LS_TRY(3);
    LS_HP(2, F.cu0 - lo, F.fuu, F.fuv);
    LS_HP(3, hi - F.cu0, -F.fuu, -F.fuv);
#undef LS_TRY
#undef LS_HP
    clip_parts(P, G, Q, &F, h, 4, out, outg, &m, drop);
    return m;
}

/* Does surface Q surely miss the box [x0, x1] x [y0, y1] (which holds
 * piece P's polygon: piece_poly starts from it)? The separating axes
 * cut_piece tests on the polygon, on the box, with a slack far above
 * the roundings of both: where this says so, cut_piece would find Q
 * missing every piece cut from P, so the piece's polygon need not be made
 * for it. */
static int surf_misses_box(const ls_surf *Q, double x0, double y0, double x1, double y1)
{
    double cx = 0.5 * (x0 + x1) - Q->ax, cy = 0.5 * (y0 + y1) - Q->ay, hx = 0.5 * (x1 - x0), hy = 0.5 * (y1 - y0);
    double mag = fabs(x0) + fabs(x1) + fabs(y0) + fabs(y1) + fabs(Q->ax) + fabs(Q->ay) + fabs(Q->u0) + fabs(Q->u1) +
                 Q->r;
    double slack = 1e-9 * (1 + mag);
    if (!(slack < 1e300)) return 0;
    double v = cx * Q->uy - cy * Q->ux, ev = hx * fabs(Q->uy) + hy * fabs(Q->ux);
    if (v - ev >= Q->r + slack || v + ev <= -Q->r - slack) return 1;
    double u = cx * Q->ux + cy * Q->uy, eu = hx * fabs(Q->ux) + hy * fabs(Q->uy);
    if (u + eu <= Q->u0 - slack || u - eu >= Q->u1 + slack) return 1;
    /* the clip lines: n.p >= cc on the whole box */
    if (Q->clip) {
        double n = (cx + Q->ax) * Q->cx + (cy + Q->ay) * Q->cy - hx * fabs(Q->cx) - hy * fabs(Q->cy);
        if (n >= Q->cc + slack * (1 + fabs(Q->cc))) return 1;
    }
    if (Q->clip2) {
        double n = (cx + Q->ax) * Q->cx2 + (cy + Q->ay) * Q->cy2 - hx * fabs(Q->cx2) - hy * fabs(Q->cy2);
        if (n >= Q->cc2 + slack * (1 + fabs(Q->cc2))) return 1;
    }
    return 0;
}

/* Work units of one cut_piece call in push_cut's budget (rs_limits.max_field_work):
 * measured against a list step, so that the budget bounds time. */
#define CUT_WORK 32

/* The pieces a piece is cut into, with their polygons (two buffers: the
 * pieces so far and those after the next cut). */
enum { QMAX = 16 };
typedef struct ls_cutset {
    uint32_t n, cur;
    int full; /* a cut was left out: it would have made more than QMAX pieces, or a piece more than HP_MAX half-planes */
    uint32_t nlim0; /* the first piece's half-planes */
    double drop; /* piece_with's */
    double tol;  /* cut_piece's at round caps: a sixteenth of a pixel */
    ls_piece p[2][QMAX + CUT_PARTS]; /* (room for one more cut's parts past QMAX) */
    ls_poly g[2][QMAX + CUT_PARTS];
} ls_cutset;

static void cutset_init(ls_cutset *S, const ls_piece *P, const rs__linesym *L)
{
    /* (exact edges only: the Hermite ramps reach past a half-plane) */
    S->drop = L->aa == RS__AA_EXACT ? 2 * L->margin * (1 + 1e-9) : 0;
    S->tol = L->pixel / 16;
    S->n = 1;
    S->cur = 0;
    S->full = 0;
    S->nlim0 = P->nlim;
    S->p[0][0] = *P;
    S->g[0][0].n = piece_poly(P, S->g[0][0].x, S->g[0][0].y);
}

/* Cut every piece so far by Q; a piece Q misses, or that cannot be cut,
 * stays. When the pieces would be more than QMAX, Q cuts nothing. work
 * (or NULL) counts CUT_WORK per piece tried. */
static void cutset_cut(ls_cutset *S, const ls_surf *Q, uint64_t *work)
{
    uint32_t c = S->cur, o = 1 - c, nn = 0;
    int full = 0, moved = 0; /* (pieces are copied to the other buffer once Q cuts one: mostly it cuts none) */
    for (uint32_t a = 0; a < S->n; a++) {
        if (work) *work += CUT_WORK; /* a polygon clip costs as much as ~32 list steps */
        /* the parts go straight to their place in the other buffer (nn <=
         * QMAX here, and it has room for CUT_PARTS more) */
        int m = cut_piece(&S->p[c][a], &S->g[c][a], Q, &S->p[o][nn], &S->g[o][nn], S->drop, S->tol);
        /* a cut left out for want of half-planes: the piece stays. Hermite
         * lines keep every cut's half-planes (drop 0), so a line crossed
         * by many roads in a row runs out of them after a few crossings:
         * when earlier cuts took two or more, its halves meet fewer of
         * them and may be cut. (Exact lines drop the far ones; there the
         * rare overflow is a crowded junction, which halving does not
         * help.) */
        if (m == -2 && S->drop == 0 && S->p[c][a].nlim >= S->nlim0 + 2) S->full = 1;
        if (m < 0) {
            if (!moved) {
                nn++;
            } else if (nn < QMAX) {
                S->p[o][nn] = S->p[c][a];
                S->g[o][nn++] = S->g[c][a];
            } else {
                full = 1;
            }
            continue;
        }
        if (!moved) {
            for (uint32_t b = 0; b < nn; b++) {
                S->p[o][b] = S->p[c][b];
                S->g[o][b] = S->g[c][b];
            }
            moved = 1;
        }
        nn += (uint32_t)m;
        if (nn > QMAX) { full = 1; break; }
    }
    S->full |= full;
    if (full || !moved) return; /* too many pieces: this surface does not cut; or it cut none */
    S->cur = o;
    S->n = nn;
}

/* First index in [lo, hi) of the ascending ids whose value is >= v. */
static uint32_t first_at_least(const uint32_t *ids, uint32_t lo, uint32_t hi, uint32_t v)
{
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (ids[mid] < v) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* Surfaces are stored road by road and listed in ascending order, so a
 * piece steps over its own road's run of a cell list in one binary search
 * (a road of 10^6 tiny segments would otherwise test each piece against
 * every surface of its own road in the cell). RS_ERR_LIMIT when the work
 * (list entries visited) passes J->limit. */
static int push_halves(rs_ctx *ctx, rs__linesym *L, ls_junc *J, const ls_piece *P, uint32_t road, uint32_t depth,
                       rs_result *res);

static rs_result push_cut(rs_ctx *ctx, rs__linesym *L, ls_junc *J, const ls_piece *P, uint32_t road, uint32_t depth)
{
    if (!J || !J->nsf || J->nocut[road]) return push_piece(ctx, L, P, NULL);
    /* the end of road's surfaces: the first with a larger road */
    if (J->own_road != road) {
        size_t lo = 0, hi_s = J->nsf;
        while (lo < hi_s) {
            size_t mid = lo + (hi_s - lo) / 2;
            if (J->sf[mid].road <= road) lo = mid + 1;
            else hi_s = mid;
        }
        J->own_road = road, J->own_end = lo;
    }
    const size_t own_end = J->own_end;
    /* candidate surfaces: those listed in the cells of P's box */
    const ls_grid *G = &J->grid;
    double fx0 = floor(P->x0 / G->cmx), fx1 = floor(P->x1 / G->cmx), fy0 = floor(P->y0 / G->cmy), fy1 = floor(P->y1 / G->cmy);
    ls_cutset *S = &L->cs[1];
    int cut = 0; /* S holds P's pieces: set up at the first surface that may cut it */
    if (!(fx1 < 0 || fy1 < 0 || fx0 >= G->gw || fy0 >= G->gh)) {
        uint32_t i0 = fx0 < 0 ? 0 : (uint32_t)fx0, i1 = fx1 >= G->gw ? G->gw - 1 : (uint32_t)fx1;
        uint32_t j0 = fy0 < 0 ? 0 : (uint32_t)fy0, j1 = fy1 >= G->gh ? G->gh - 1 : (uint32_t)fy1;
        J->query++;
        for (uint32_t j = j0; j <= j1; j++)
            for (uint32_t i = i0; i <= i1; i++) {
                size_t c = (size_t)j * G->gw + i;
                for (uint32_t e = J->start[c]; e < J->start[c + 1]; e++) {
                    uint32_t k = J->ids[e];
                    if (++J->work > J->limit) return RS_ERR_LIMIT;
                    if (J->sf[k].road == road) { /* skip the rest of the own road's run */
                        e = first_at_least(J->ids, e, J->start[c + 1], (uint32_t)own_end) - 1;
                        continue;
                    }
                    if (J->stamp[k] == J->query) continue;
                    J->stamp[k] = J->query;
                    const ls_surf *Q = &J->sf[k];
                    uint32_t sr = J->stroke_of ? J->stroke_of[road] : road;
                    if (Q->road == road || (J->stroke_of && J->stroke_of[Q->road] == sr) ||
                        (Q->only != NO_STROKE && Q->only != sr && Q->only2 != sr) || Q->skip == sr || Q->skip2 == sr ||
                        Q->skip3 == sr || Q->skip4 == sr)
                        continue;
                    /* roads on different levels (a bridge, layer=): the
                     * lower surface cuts none of the upper road's lines, the
                     * upper one all of the lower road's (they lie under its
                     * deck), whatever their classes (docs/network.md
                     * "Bridges and layers"); the rules below are for one level */
                    int lq = J->prio ? rs__rank_level(J->prio[Q->road]) : 0, lr = J->prio ? rs__rank_level(J->prio[road]) : 0;
                    if (lq < lr) continue;
                    /* a path, footway or cycleway crossing or meeting a car
                     * road cuts none of its lines (issue 27: the road's lines
                     * run on over a footway crossing, as over a zebra's) */
                    if (lq == lr && J->car[road] && !J->car[Q->road]) continue;
                    /* a car road of lower rank crossing this one (not a
                     * side road at a T: its cut-back copy does that) cuts
                     * only its lines near its edges, its mouths; the
                     * centre and lane lines run on (issue 27) */
                    if (lq == lr && J->prio && Q->only == NO_STROKE && J->car[road] && J->car[Q->road] &&
                        J->prio[Q->road] < J->prio[road] && fabs(L->band[P->band].t) <= J->keep[road])
                        continue;
                    /* (the box test before the end points': it passes over most surfaces) */
                    if (surf_misses_box(Q, P->x0, P->y0, P->x1, P->y1) || continues(J, road, Q->road)) continue;
                    if (!cut) cutset_init(S, P, L), cut = 1;
                    cutset_cut(S, Q, &J->work);
                }
            }
    }
    if (!cut) return push_piece(ctx, L, P, NULL);
    rs_result hr;
    if (S->full && push_halves(ctx, L, J, P, road, depth, &hr)) return hr;
    for (uint32_t a = 0; a < S->n; a++) {
        rs_result r = push_piece(ctx, L, &S->p[S->cur][a], &S->g[S->cur][a]);
        if (r) return r;
    }
    return RS_OK;
}

/* A line piece more roads cross than its pieces can be cut for (QMAX: a
 * long straight segment crossed by many streets, say a road given by its
 * two end points) kept its line over the crossings past that number: an
 * edge line drawn across a street's mouth. Such a slab is halved along its
 * length instead (one more half-plane each; the halves' areas sum to its
 * own) and each half is cut alone, meeting fewer roads, down to SPLIT_MAX
 * halvings or halves of SPLIT_MIN_PX pixels. Returns 0 (nothing pushed)
 * when P cannot be halved; else 1 with *res the result. */
#define SPLIT_MAX 12
#define SPLIT_MIN_PX 4

static int push_halves(rs_ctx *ctx, rs__linesym *L, ls_junc *J, const ls_piece *P, uint32_t road, uint32_t depth,
                       rs_result *res)
{
    if (depth >= SPLIT_MAX || P->kind != PIECE_SLAB || P->nlim + 1 > HP_MAX) return 0;
    ls_poly G;
    G.n = piece_poly(P, G.x, G.y);
    if (G.n < 3) return 0;
    double u0 = DBL_MAX, u1 = -DBL_MAX;
    for (uint32_t k = 0; k < G.n; k++) u0 = rs__fmin(u0, G.x[k]), u1 = rs__fmax(u1, G.x[k]);
    if (!(u1 - u0 >= 2 * SPLIT_MIN_PX * L->pixel)) return 0;
    const double m = 0.5 * (u0 + u1);
    const double h[2][1][3] = { { { m, -1, 0 } }, { { -m, 1, 0 } } }; /* u <= m, u >= m */
    *res = RS_OK;
    for (int e = 0; e < 2 && *res == RS_OK; e++) {
        ls_poly g;
        ls_piece H;
        if (!nonempty_hp(G.x, G.y, G.n, h[e], 1, &g)) continue;
        /* (every half-plane kept: the box below bounds the half's
         * polygon only with all of them) */
        piece_with(&H, P, h[e], 1, &g, 0);
        /* its box: its polygon's, grown by the pixel margin as piece_box
         * grows a slab's, within P's (so its polygon stays the same) */
        double x0 = DBL_MAX, x1 = -DBL_MAX, y0 = DBL_MAX, y1 = -DBL_MAX, mg = L->margin;
        for (uint32_t k = 0; k < g.n; k++) {
            double x, y;
            piece_point(P, g.x[k], g.y[k], &x, &y);
            x0 = rs__fmin(x0, x), x1 = rs__fmax(x1, x), y0 = rs__fmin(y0, y), y1 = rs__fmax(y1, y);
        }
        H.x0 = rs__fmax(P->x0, x0 - mg), H.x1 = rs__fmin(P->x1, x1 + mg);
        H.y0 = rs__fmax(P->y0, y0 - mg), H.y1 = rs__fmin(P->y1, y1 + mg);
        *res = push_cut(ctx, L, J, &H, road, depth + 1);
    }
    return 1;
}

/* Push P less the cuts of its road (lib/scene/lanes.h: its lane and centre
 * lines stop at a stop line, across a zebra), then cut at the junctions.
 * Like a junction cut, a cut that would split P into too many pieces
 * leaves it whole. */
static uint32_t cut_key(const rs__linesym *L, uint32_t road)
{
    return L->cut_stroke ? L->cut_stroke[road] : road;
}

static rs_result push_trim(rs_ctx *ctx, rs__linesym *L, ls_junc *J, const ls_piece *P, uint32_t road)
{
    /* a patch's grid: a piece wholly outside its window is not made (its
     * cuts lie within its box; a NaN box is kept) */
    if (L->win_on && (P->x1 < L->win[0] || P->x0 > L->win[2] || P->y1 < L->win[1] || P->y0 > L->win[3]))
        return RS_OK;
    uint32_t key = L->cut_start ? cut_key(L, road) : 0;
    if (!L->cut_start || L->cut_start[key] == L->cut_start[key + 1]) return push_cut(ctx, L, J, P, road, 0);
    ls_cutset *S = &L->cs[0];
    cutset_init(S, P, L);
    for (uint32_t e = L->cut_start[key]; e < L->cut_start[key + 1]; e++) {
        const rs__line_cut *c = &L->cuts[L->cut_ord[e]];
        ls_surf Q;
        memset(&Q, 0, sizeof Q);
        Q.ax = c->ax, Q.ay = c->ay, Q.ux = c->ux, Q.uy = c->uy, Q.u0 = c->u0, Q.u1 = c->u1, Q.r = c->r;
        cutset_cut(S, &Q, NULL);
    }
    for (uint32_t a = 0; a < S->n; a++) {
        rs_result r = push_cut(ctx, L, J, &S->p[S->cur][a], road, 0);
        if (r) return r;
    }
    return RS_OK;
}

/* Pieces of one band along one road or stroke. pts: n distinct
 * consecutive local points, s: arc length at each, seg_road: the record
 * of each segment (for the junction cuts). closed: the polyline is a
 * ring (pts[n - 1] == pts[0]): its first and last segments meet at the
 * seam as any two segments meet at a vertex (bisectors, a round join),
 * where until 6 December 2026 both ended square and left a wedge out of
 * the outer lines (0.9 m of a roundabout's edge line). */
static rs_result road_band_pieces(rs_ctx *ctx, rs__linesym *L, ls_junc *J, const uint32_t *seg_road,
                                  const ls_vtx *pts, const double *s, size_t n, const rs__band *bd, uint32_t band,
                                  double wmap, double hmap, int closed)
{
    closed = closed && n >= 4 && pts[0].x == pts[n - 1].x && pts[0].y == pts[n - 1].y;
    double a = bd->t - 0.5 * bd->w, b = bd->t + 0.5 * bd->w, ext = rs__fmax(fabs(a), fabs(b)) + L->margin;
    const ls_band *B = &L->band[band];
    for (size_t i = 0; i + 1 < n; i++) {
        /* a segment's junction cuts can take 0.1 ms (10^5 city roads): a
         * poll every 32, not every 256 ticks (issue 30 target 4: cancel
         * within 50 ms) */
        if ((i & 31) == 31 ? rs__poll(ctx) : rs__tick(ctx, 0)) return RS_ERR_CANCELLED;
        double dx = 0.5 * pts[i + 1].x - 0.5 * pts[i].x, dy = 0.5 * pts[i + 1].y - 0.5 * pts[i].y, lh = hypot(dx, dy);
        double ux = dx / lh, uy = dy / lh, len = 2 * lh;
        ls_piece P;
        memset(&P, 0, sizeof P);
        P.kind = PIECE_SLAB;
        P.band = band;
        P.ox = pts[i].x;
        P.oy = pts[i].y;
        P.ux = ux;
        P.uy = uy;
        P.s0 = s[i];
        P.a = a;
        P.b = b;
        P.dashed = B->ndash > 0;
        /* Far segments: cut the centreline to the map grown by the band's
         * reach, so the box and s stay finite and small. */
        double lo, hi, span, rest, cx, cy;
        int far_cut;
        if (!cut_segment(P.ox, P.oy, pts[i + 1].x, pts[i + 1].y, ux, uy, len, ext, wmap, hmap, &lo, &hi, &span, &rest,
                         &cx, &cy, &far_cut))
            continue;
        P.hp[P.nhp][0] = -a, P.hp[P.nhp][1] = 0, P.hp[P.nhp++][2] = 1;         /* v >= a */
        P.hp[P.nhp][0] = b, P.hp[P.nhp][1] = 0, P.hp[P.nhp++][2] = -1;         /* v <= b */
        /* Each end: the end perpendicular and the bisector with the
         * neighbouring segment. Over v in [a, b] one of the two lies wholly
         * beyond the other when the band is on one side of the centreline
         * (the perpendicular on the inner side of the bend, the bisector
         * on the outer): that one cuts nothing and is left out. */
        double bm[2][2];
        int has_bis[2] = { 0, 0 };
        if (i > 0 || closed) { /* bisector with the previous segment: m.(p - A) >= 0 */
            size_t ip = i > 0 ? i - 1 : n - 2, ia = i > 0 ? i : n - 1; /* (a ring's first: its last) */
            double pdx = 0.5 * pts[ia].x - 0.5 * pts[ip].x, pdy = 0.5 * pts[ia].y - 0.5 * pts[ip].y, pl = hypot(pdx, pdy);
            double mx = pdx / pl + ux, my = pdy / pl + uy, ml = hypot(mx, my);
            if (ml > 1e-9) {
                in_frame(mx / ml, my / ml, ux, uy, &bm[0][0], &bm[0][1]);
                has_bis[0] = 1;
            }
        }
        if (i + 2 < n || closed) { /* with the next: m.(p - B) <= 0 */
            size_t ib = i + 2 < n ? i + 1 : 0, in = i + 2 < n ? i + 2 : 1; /* (a ring's last: its first) */
            double ndx = 0.5 * pts[in].x - 0.5 * pts[ib].x, ndy = 0.5 * pts[in].y - 0.5 * pts[ib].y,
                   nl = hypot(ndx, ndy);
            double mx = ndx / nl + ux, my = ndy / nl + uy, ml = hypot(mx, my);
            if (ml > 1e-9) {
                in_frame(mx / ml, my / ml, ux, uy, &bm[1][0], &bm[1][1]);
                has_bis[1] = 1;
            }
        }
        for (int end = 0; end < 2; end++) {
            /* the start: mu u + mv v >= 0 (mu > 0) against u >= 0; the end:
             * mu (len - u) - mv v >= 0 against u <= len */
            int keep_perp = 1, keep_bis = has_bis[end];
            P.nlim += 1 + (uint32_t)has_bis[end];
            if (has_bis[end] && L->aa == RS__AA_EXACT) { /* (Hermite smooths beyond [a, b]: keep both) */
                double mv = end ? -bm[end][1] : bm[end][1];
                if (mv * a >= 0 && mv * b >= 0) keep_bis = 0;       /* the bisector holds wherever the perpendicular does */
                else if (mv * a <= 0 && mv * b <= 0) keep_perp = 0; /* and conversely */
            }
            if (keep_perp) {
                if (end == 0) P.hp[P.nhp][0] = 0, P.hp[P.nhp][1] = 1, P.hp[P.nhp++][2] = 0;  /* u >= 0 */
                else P.hp[P.nhp][0] = len, P.hp[P.nhp][1] = -1, P.hp[P.nhp++][2] = 0;       /* u <= len */
            }
            if (keep_bis) {
                double mu = bm[end][0], mv = bm[end][1];
                if (end == 0) P.hp[P.nhp][0] = 0, P.hp[P.nhp][1] = mu, P.hp[P.nhp++][2] = mv;
                else P.hp[P.nhp][0] = mu * len, P.hp[P.nhp][1] = -mu, P.hp[P.nhp++][2] = -mv;
            }
        }
        P.nlim += 2;
        if (far_cut) {
            /* (the same from the cut's own point: the end's limits at rest,
             * s on from B's, dashes run on across B as from a near A) */
            P.ox = cx;
            P.oy = cy;
            P.s0 = s[i + 1] - rest;
            for (uint32_t k = 0; k < P.nhp; k++)
                P.hp[k][0] = P.hp[k][1] < 0 ? -P.hp[k][1] * rest : P.hp[k][0] + P.hp[k][1] * lo;
        } else if (lo > 0) {
            /* Re-anchor at the cut start (only u shifts; the half-planes
             * keep the exact piece). The cut-off parts lie more than a
             * pixel margin outside the map, so the box may leave them out. */
            P.ox += lo * ux;
            P.oy += lo * uy;
            P.s0 += lo;
            for (uint32_t k = 0; k < P.nhp; k++) P.hp[k][0] += P.hp[k][1] * lo;
        }
        P.len = span;
        piece_box(L, &P, P.len, a, b);
        rs_result r = push_trim(ctx, L, J, &P, seg_road[i]);
        if (r) return r;
    }
    /* Round joins: the outer side of each interior vertex (a ring's seam
     * too, last: vertex n - 1, between segments n - 2 and 0). */
    for (size_t i = 1; i + 1 < n || (closed && i + 1 == n); i++) {
        size_t in = i + 1 < n ? i + 1 : 1; /* (the seam's next: the ring's second point) */
        double pdx = 0.5 * pts[i].x - 0.5 * pts[i - 1].x, pdy = 0.5 * pts[i].y - 0.5 * pts[i - 1].y, pl = hypot(pdx, pdy);
        double ndx = 0.5 * pts[in].x - 0.5 * pts[i].x, ndy = 0.5 * pts[in].y - 0.5 * pts[i].y, nl = hypot(ndx, ndy);
        double px = pdx / pl, py = pdy / pl, nx = ndx / nl, ny = ndy / nl;
        /* turn: next direction against the previous left normal (py, -px) */
        double turn = nx * py - ny * px;
        if (turn == 0) continue;
        double out = turn > 0 ? -1.0 : 1.0; /* left turn: outer side is the right (t < 0) */
        double r0 = out > 0 ? rs__fmax(a, 0) : rs__fmax(-b, 0), r1 = out > 0 ? b : -a;
        if (!(r1 > r0)) continue;
        /* (the seam: where the pattern is on at the ring's end and again at its start) */
        if (B->ndash && !(dash_on(L, B, s[i]) && (i + 1 < n || dash_on(L, B, s[0])))) continue;
        double vx = pts[i].x, vy = pts[i].y;
        if (vx < -r1 - L->margin || vx > wmap + r1 + L->margin || vy < -r1 - L->margin || vy > hmap + r1 + L->margin)
            continue;
        ls_piece P;
        memset(&P, 0, sizeof P);
        P.kind = PIECE_WEDGE;
        P.band = band;
        P.ox = vx;
        P.oy = vy;
        P.ux = nx;
        P.uy = ny;
        P.s0 = s[i];
        P.r0 = r0;
        P.r1 = r1;
        double mu, mv;
        in_frame(px, py, nx, ny, &mu, &mv);
        P.hp[0][0] = 0, P.hp[0][1] = mu, P.hp[0][2] = mv; /* (p - V).u_prev >= 0 */
        P.hp[1][0] = 0, P.hp[1][1] = -1, P.hp[1][2] = 0;  /* (p - V).u_next <= 0 */
        P.nhp = P.nlim = 2;
        /* the sector's box: its four corners and the axis directions
         * inside it at r1; padded against rounding */
        double c0x = out * py, c0y = -out * px, c1x = out * ny, c1y = -out * nx; /* outer normals */
        double bxs[8] = { r0 * c0x, r1 * c0x, r0 * c1x, r1 * c1x }, bys[8] = { r0 * c0y, r1 * c0y, r0 * c1y, r1 * c1y };
        int nb = 4;
        static const double AX[4] = { 1, -1, 0, 0 }, AY[4] = { 0, 0, 1, -1 };
        for (int q = 0; q < 4; q++)
            if (AX[q] * px + AY[q] * py > 0 && AX[q] * nx + AY[q] * ny < 0) bxs[nb] = r1 * AX[q], bys[nb++] = r1 * AY[q];
        P.wx0 = P.wx1 = bxs[0];
        P.wy0 = P.wy1 = bys[0];
        for (int q = 1; q < nb; q++) {
            P.wx0 = rs__fmin(P.wx0, bxs[q]), P.wx1 = rs__fmax(P.wx1, bxs[q]);
            P.wy0 = rs__fmin(P.wy0, bys[q]), P.wy1 = rs__fmax(P.wy1, bys[q]);
        }
        double pad = 1e-9 * (1 + r1);
        P.wx0 -= pad, P.wy0 -= pad, P.wx1 += pad, P.wy1 += pad;
        double pp = L->pixel * L->pixel; /* 0 only for a subnormal pixel: no shortcut then */
        P.warea = pp > 0 ? 0.5 * atan2(fabs(turn), px * nx + py * ny) * (r1 * r1 - r0 * r0) / pp : 0;
        piece_box(L, &P, 0, 0, 0);
        rs_result r = push_trim(ctx, L, J, &P, seg_road[i + 1 < n ? i : 0]);
        if (r) return r;
    }
    return RS_OK;
}

/* Cell spans kept between the index's counting and filling passes: span
 * m is cells [a[m], b[m]] of cell row j[m]; item k's spans are [first[k],
 * first[k + 1]). */
typedef struct ls_spans {
    uint32_t *j, *a, *b, *first;
    size_t n, cap;
    int failed; /* an allocation failed or the spans passed 2^32: the fill pass recomputes */
} ls_spans;

static void spans_init(rs_ctx *ctx, ls_spans *S, size_t items)
{
    memset(S, 0, sizeof *S);
    S->first = rs__alloc_array(ctx, items + 1, sizeof *S->first);
    S->failed = S->first == NULL;
}

/* Item k's spans start here (k = items: the end of the last one). */
static void spans_mark(ls_spans *S, size_t k)
{
    if (S->n >= UINT32_MAX) S->failed = 1;
    if (!S->failed) S->first[k] = (uint32_t)S->n;
}

static void spans_free(rs_ctx *ctx, ls_spans *S)
{
    rs__free(ctx, S->first);
    rs__free(ctx, S->j), rs__free(ctx, S->a), rs__free(ctx, S->b);
}

static void spans_push(rs_ctx *ctx, ls_spans *S, uint32_t j, uint32_t a, uint32_t b)
{
    if (S->failed) return;
    if (S->n == S->cap) {
        size_t nc = S->cap ? 2 * S->cap : 4096;
        void *nj = S->j, *na = S->a, *nb = S->b;
        if (rs__resize(ctx, &nj, S->cap * sizeof *S->j, nc * sizeof *S->j) ||
            (S->j = nj, rs__resize(ctx, &na, S->cap * sizeof *S->a, nc * sizeof *S->a)) ||
            (S->a = na, rs__resize(ctx, &nb, S->cap * sizeof *S->b, nc * sizeof *S->b))) {
            S->failed = 1;
            return;
        }
        S->b = nb;
        S->cap = nc;
    }
    S->j[S->n] = j, S->a[S->n] = a, S->b[S->n] = b, S->n++;
}

/* Index cells reached by the rectangle u in [u0, u1], v in [v0, v1] of the
 * frame (ox, oy, ux, uy) inside the local box [x0, x1] x [y0, y1] (per cell
 * row, the x extent of the rectangle cut to that row); fill 0 counts into
 * start[] (and keeps the spans in S when given), fill 1 fills the lists
 * from their ends: with *val in ent when ent is given, else with item k in
 * ids. */
static void rect_cells(const ls_grid *G, double ox, double oy, double ux, double uy, double u0, double u1,
                       double v0, double v1, double x0, double y0, double x1, double y1, uint32_t *start,
                       uint32_t *ids, uint32_t k, ls_pbox *ent, const ls_pbox *val, int fill, rs_ctx *ctx,
                       ls_spans *S)
{
    double cm = G->cmx, cmy = G->cmy;
    double fy0 = floor(y0 / cmy), fy1 = floor(y1 / cmy);
    if (!(fy1 >= 0) || !(fy0 < G->gh)) return;
    uint32_t j0 = fy0 < 0 ? 0 : (uint32_t)fy0, j1 = fy1 >= G->gh ? G->gh - 1 : (uint32_t)fy1;
    double fx0 = floor(x0 / cm), fx1 = floor(x1 / cm);
    if (!(fx1 >= 0) || !(fx0 < G->gw)) return;
    uint32_t i0 = fx0 < 0 ? 0 : (uint32_t)fx0, i1 = fx1 >= G->gw ? G->gw - 1 : (uint32_t)fx1;
    for (uint32_t j = j0; j <= j1; j++) {
        uint32_t a = i0, b = i1;
        if (i1 > i0) {
            double U[4] = { u0, u1, u1, u0 }, V[4] = { v0, v0, v1, v1 };
            double xs[POLY_MAX], ys[POLY_MAX], tx[POLY_MAX], ty[POLY_MAX];
            for (int q = 0; q < 4; q++) {
                xs[q] = ox + U[q] * ux + V[q] * uy;
                ys[q] = oy + U[q] * uy - V[q] * ux;
            }
            uint32_t nn = clip_poly(xs, ys, 4, -(double)j * cmy, 0, 1, tx, ty);
            nn = clip_poly(tx, ty, nn, (double)(j + 1) * cmy, 0, -1, xs, ys);
            if (nn == 0) continue;
            double lo = xs[0], hi = xs[0];
            for (uint32_t q = 1; q < nn; q++) {
                lo = rs__fmin(lo, xs[q]);
                hi = rs__fmax(hi, xs[q]);
            }
            double ga = floor(lo / cm), gb = floor(hi / cm);
            if (gb < (double)i0 || ga > (double)i1) continue;
            a = ga > (double)i0 ? (uint32_t)ga : i0;
            b = gb < (double)i1 ? (uint32_t)gb : i1;
        }
        if (S) spans_push(ctx, S, j, a, b);
        for (uint32_t i = a; i <= b; i++) {
            size_t c = (size_t)j * G->gw + i;
            if (!fill) start[c]++;
            else if (ent) ent[--start[c]] = *val;
            else ids[--start[c]] = k;
        }
    }
}

/* Counts piece k in the cells it covers (fill 0), or lists it there (fill
 * 1: its index entry, the painter's first read, written in place). */
static void piece_cells(rs__linesym *L, uint32_t k, int fill, rs_ctx *ctx, ls_spans *S)
{
    const ls_ppc *P = &L->pp[k];
    const ls_pbuild *B = &L->pb[k];
    double m = L->margin;
    ls_pbox v = { B->gx0, B->gx1, B->gy0, B->gy1, k, P->band };
    if (P->kind == PIECE_SLAB)
        rect_cells(&L->grid, P->ox, P->oy, P->ux, P->uy, -m, B->len + m, P->a - m, P->b + m, B->x0, B->y0, B->x1, B->y1,
                   L->start, NULL, k, L->ent, &v, fill, ctx, S);
    else /* the sector's box grown by the margin, as an axis-aligned rectangle */
        rect_cells(&L->grid, P->ox, P->oy, 1, 0, P->wx0 - m, P->wx1 + m, -P->wy1 - m, -P->wy0 + m, P->ox + P->wx0 - m,
                   P->oy + P->wy0 - m, P->ox + P->wx1 + m, P->oy + P->wy1 + m, L->start, NULL, k, L->ent, &v, fill,
                   ctx, S);
}

/* Counts to CSR end offsets (a list is then filled from its end). */
static int csr_close(uint32_t *start, size_t ncell, uint64_t lim, size_t *total)
{
    uint64_t run = 0;
    for (size_t c = 0; c < ncell; c++) {
        run += start[c];
        if (run > lim) return 0;
        start[c] = (uint32_t)run;
    }
    start[ncell] = (uint32_t)run;
    *total = (size_t)run;
    return 1;
}

/* The bands look the same drawn either way: each has its mirror image
 * (offset -t within 1e-9 m, all else equal) among them: a centre line
 * computed at 1e-15 m is at 0. */
static int bands_mirror(const rs__band *b, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++) {
        int found = 0;
        for (uint32_t j = 0; j < n && !found; j++)
            found = fabs(b[j].t + b[i].t) <= 1e-9 && b[j].w == b[i].w && !memcmp(b[j].rgba, b[i].rgba, sizeof b[i].rgba) &&
                    b[j].ndash == b[i].ndash && b[j].phase == b[i].phase &&
                    (b[i].ndash == 0 || !memcmp(b[j].dash, b[i].dash, b[i].ndash * sizeof *b[i].dash));
        if (!found) return 0;
    }
    return 1;
}

/* A run of a stroke's records drawn with the bands of record `rec`, from
 * polyline point `at`. */
typedef struct ls_run {
    uint32_t rec;
    size_t at;
} ls_run;

/* Two records' bands draw the same (band by band, offsets within 1e-9 m):
 * a stroke's records look alike until its lanes change along it. */
static int bands_equal(const rs__band *a, uint32_t na, const rs__band *b, uint32_t nb)
{
    if (na != nb) return 0;
    for (uint32_t i = 0; i < na; i++)
        if (!(fabs(a[i].t - b[i].t) <= 1e-9) || a[i].w != b[i].w || memcmp(a[i].rgba, b[i].rgba, sizeof a[i].rgba) ||
            a[i].ndash != b[i].ndash || a[i].phase != b[i].phase ||
            (a[i].ndash && memcmp(a[i].dash, b[i].dash, a[i].ndash * sizeof *a[i].dash)))
            return 0;
    return 1;
}

/* Append road ri's points to the *m_out points already in *pts (a stroke's
 * records one after the other: a point equal to the last is left out). */
static rs_result road_local_append(rs_ctx *ctx, const rs_roads *roads, size_t ri, int rev,
                                   const rs__linesym_params *p, double per_unit, ls_vtx **pts, double **sv,
                                   size_t *cap, size_t *m_out, int *gap)
{
    const double *xy = NULL;
    size_t n = 0, m0 = *m_out;
    rs_roads_get(roads, ri, NULL, NULL, &xy, &n);
    if (n > *cap - m0) {
        size_t b1, b2, want = m0 + n;
        if (want < 2 * *cap) want = 2 * *cap;
        if (!rs__mul_size(want, sizeof **pts, &b1) || !rs__mul_size(want, sizeof **sv, &b2)) return RS_ERR_LIMIT;
        ls_vtx *np = rs__realloc(ctx, *pts, b1);
        if (!np) return RS_ERR_NOMEM;
        *pts = np;
        double *ns = rs__realloc(ctx, *sv, b2);
        if (!ns) return RS_ERR_NOMEM;
        *sv = ns;
        *cap = want;
    }
    /* (a record drawn against its points: last to first) */
    rs__local_frame F = { p->origin_x, p->origin_y, per_unit };
    double *d = (double *)(void *)*pts; /* (x, y) pairs: ls_vtx is two doubles */
    if (gap) {
        /* the record does not start where the last one ended: a short
         * record between them was bridged (lib/scene/network.c bridge_short) */
        double fx = 0, fy = 0;
        if (n) rs__local_point(&F, xy, rev ? n - 1 : 0, &fx, &fy);
        *gap = m0 > 0 && n > 0 && !((*pts)[m0 - 1].x == fx && (*pts)[m0 - 1].y == fy);
    }
    rs__road_local_walk(roads, ri, rev, &F, d, d + 1, 2, *sv, m_out);
    return RS_OK;
}

/* A stroke's arc lengths at record q's points (appended at [m0, m), its
 * first point at m0 - 1 when it was the last one's end): the record's
 * base (rs__stroke_bases) plus its own
 * sums, so a part of a map's roads draws its dashes as the whole map does
 * (rs__network_subset), and the whole map alike from any record on. */
static void stroke_arcs(double base, const rs_roads *roads, uint32_t q, int rev, const rs__linesym_params *p,
                        double per_unit, ls_vtx *pts, double *sv, size_t m0, size_t m)
{
    const double *xy = NULL;
    size_t n = 0;
    rs_roads_get(roads, q, NULL, NULL, &xy, &n);
    if (!n) return;
    rs__local_frame F = { p->origin_x, p->origin_y, per_unit };
    double fx, fy;
    rs__local_point(&F, xy, rev ? n - 1 : 0, &fx, &fy);
    size_t j0 = m0 > 0 && pts[m0 - 1].x == fx && pts[m0 - 1].y == fy ? m0 - 1 : m0;
    if (j0 >= m) return;
    double acc = 0;
    sv[j0] = base;
    for (size_t i = j0 + 1; i < m; i++) {
        acc = rs__arc_add(acc, rs__arc_len(pts[i - 1].x, pts[i - 1].y, pts[i].x, pts[i].y));
        sv[i] = rs__arc_add(base, acc);
    }
}

/* Records split a road anywhere, also inside a straight stretch: the
 * joint point j of two records (points j-1, j, j+1 of the stroke) is left
 * out when it lies on the segment j-1 .. j+1 within eps (a few local
 * quanta), so the stroke has the unsplit road's points and arc lengths (a
 * collinear point would bend the mitres of a band on the inner side of a
 * nearby bend). Returns 1 when it was left out (points j.. move down). */
static int drop_straight_joint(ls_vtx *pts, double *sv, size_t j, size_t m, double eps)
{
    double ax = pts[j - 1].x, ay = pts[j - 1].y, dx = pts[j + 1].x - ax, dy = pts[j + 1].y - ay;
    double px = pts[j].x - ax, py = pts[j].y - ay, l2 = dx * dx + dy * dy, dot = px * dx + py * dy;
    if (!(l2 > 0) || !(dot > 0) || !(dot < l2) || !(fabs(px * dy - py * dx) <= eps * sqrt(l2))) return 0;
    for (size_t k = j; k + 1 < m; k++) {
        pts[k] = pts[k + 1];
        sv[k] = rs__arc_add(sv[k - 1], rs__arc_len(pts[k - 1].x, pts[k - 1].y, pts[k].x, pts[k].y));
    }
    return 1;
}

/* One road in local coordinates: distinct consecutive points and their arc
 * lengths (summed as lib/scene/roadfield.c sums them). */
static rs_result road_local(rs_ctx *ctx, const rs_roads *roads, size_t ri, const rs__linesym_params *p,
                            double per_unit, ls_vtx **pts, double **sv, size_t *cap, size_t *m_out)
{
    *m_out = 0;
    return road_local_append(ctx, roads, ri, 0, p, per_unit, pts, sv, cap, m_out, NULL);
}

static void unit_dir(double ax, double ay, double bx, double by, double *dx, double *dy)
{
    double hx = 0.5 * bx - 0.5 * ax, hy = 0.5 * by - 0.5 * ay, l = hypot(hx, hy);
    *dx = hx / l;
    *dy = hy / l;
}

static void junc_free(rs_ctx *ctx, ls_junc *J)
{
    rs__free(ctx, J->sf);
    rs__free(ctx, J->start);
    rs__free(ctx, J->ids);
    rs__free(ctx, J->stamp);
    rs__free(ctx, (void *)J->ends);
    rs__free(ctx, J->nocut);
    rs__free(ctx, J->car);
    rs__free(ctx, J->prio_own);
    rs__free(ctx, J->keep);
    memset(J, 0, sizeof *J);
}

/* The road ends that meet a through road with the right of way at a T
 * (per road two entries, start and end; stroke NO_STROKE: none): at a
 * junction node, the strokes that pass through it (a road through a shared
 * point or a T, or two records of one stroke) with the highest priority
 * there; every other road ending there is a side road of the one it meets
 * most squarely. NULL (and RS_OK) without a network. */
/* Major roads passing one node looked at (more: no T there) */
#define TEE_MAX_THROUGH 4

/* The direction of the street passing on leg a (and b, its second leg
 * there, or NULL) into *tx, *ty: the chord of both legs (rs__through_dir),
 * else a's own direction; 0 when both legs leave the same way. */
static int street_dir(const rs_network_leg *a, const rs_network_leg *b, double *tx, double *ty)
{
    *tx = cos(a->angle), *ty = sin(a->angle);
    return !b || rs__through_dir(a, b, tx, ty);
}

rs_result rs__network_tees(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, rs__tee **out)
{
    *out = NULL;
    size_t n = rs_roads_count(roads);
    if (!net || rs_network_road_count(net) != n) return RS_OK;
    ls_tee *T = rs__alloc_array(ctx, n ? 2 * n : 1, sizeof *T);
    if (!T) return RS_ERR_NOMEM;
    for (size_t i = 0; i < 2 * n; i++) T[i].stroke = T[i].stroke2 = NO_STROKE, T[i].off = 0;
    for (size_t nd = 0; nd < net->nnodes; nd++) {
        if ((nd & 4095) == 4095 && rs__poll(ctx)) { /* (10^5 roads: ~40 ms) */
            rs__free(ctx, T);
            return RS_ERR_CANCELLED;
        }
        const rs_network_leg *L = net->leg + net->leg_start[nd];
        uint32_t d = net->leg_start[nd + 1] - net->leg_start[nd], through = NO_STROKE, nthrough = 0;
        const rs_network_leg *tl = NULL, *tl2 = NULL, *tls[TEE_MAX_THROUGH], *tls2[TEE_MAX_THROUGH];
        if (d < 3) continue;
        for (uint32_t k = 0; k < d; k++) {
            uint32_t r = L[k].road, st = net->stroke_of[r];
            /* a road through the node, or a road end that its stroke continues */
            if (!rs__leg_passes(net, &L[k]) || !L[k].major) continue;
            uint32_t seen = TEE_MAX_THROUGH;
            for (uint32_t j = 0; j < nthrough && j < TEE_MAX_THROUGH; j++)
                if (net->stroke_of[tls[j]->road] == st) seen = j;
            if (seen < TEE_MAX_THROUGH) {
                if (!tls2[seen]) tls2[seen] = &L[k]; /* its second leg */
                continue;
            }
            if (nthrough < TEE_MAX_THROUGH) tls[nthrough] = &L[k], tls2[nthrough] = NULL;
            through = st, tl = &L[k];
            nthrough++;
        }
        /* none passing: two record ends going straight on, of the highest
         * priority there, that do not draw alike (a street whose lanes or
         * width change where a side road ends on it), as lib/scene/tee_ends.c */
        uint32_t through2 = NO_STROKE;
        double w = 0;
        if (nthrough == 0) {
            const rs_network_leg *pa = NULL, *pb = NULL;
            if (!rs__straight_pair(L, d, &pa, &pb) || !pa->major || !pb->major) continue;
            tl = pa, tl2 = pb;
            through = net->stroke_of[pa->road], through2 = net->stroke_of[pb->road];
            double w2 = 0;
            rs_roads_get(roads, pb->road, NULL, &w2, NULL, NULL);
            rs_roads_get(roads, pa->road, NULL, &w, NULL, NULL);
            if (w2 < w) w = w2;
        } else if (nthrough > TEE_MAX_THROUGH)
            continue;
        else if (nthrough == 1) {
            tl2 = tls2[0]; /* (tl is tls[0]) */
            rs_roads_get(roads, tl->road, NULL, &w, NULL, NULL);
        }
        for (uint32_t k = 0; k < d; k++) {
            uint32_t r = L[k].road;
            if (!rs__is_end_leg(&L[k]) || net->stroke_of[r] == through || net->stroke_of[r] == through2) continue;
            if (nthrough > 1) {
                /* several major roads pass (an X with a road ending on
                 * its shared point): the end's through road is the one it
                 * meets most squarely, the first of equals, as in
                 * lib/scene/tee_ends.c */
                int own = 0;
                double best = -1, wx = cos(L[k].angle), wy = sin(L[k].angle);
                for (uint32_t j = 0; j < nthrough; j++) {
                    /* the street's direction from its two legs, as the
                     * trim's (a bent street: one leg's angle could pick
                     * another street than the trim at a near-tie) */
                    double tx, ty, sn = street_dir(tls[j], tls2[j], &tx, &ty) ? rs__meet_sine(wx, wy, tx, ty) : -1;
                    own |= net->stroke_of[tls[j]->road] == net->stroke_of[r];
                    if (sn > best) best = sn, tl = tls[j], tl2 = tls2[j];
                }
                if (own) continue;
                through = net->stroke_of[tl->road];
                rs_roads_get(roads, tl->road, NULL, &w, NULL, NULL);
            }
            ls_tee *t = &T[rs__leg_end(&L[k])];
            t->stroke = through;
            t->stroke2 = through2;
            /* lines within 2 m of the through road's edges are edge lines:
             * they stop at the side road's mouth; the rest run on */
            t->keep = rs__fmax(0.5 * w - TEE_EDGE_ZONE, 0);
            /* a bent street: its direction from both legs, as the trim's */
            street_dir(tl, tl2, &t->dx, &t->dy);
            t->lx[0] = cos(tl->angle), t->ly[0] = sin(tl->angle);
            if (tl2) t->lx[1] = cos(tl2->angle), t->ly[1] = sin(tl2->angle);
            else t->lx[1] = -t->lx[0], t->ly[1] = -t->ly[0];
            /* an end inside the surface, short of the centre line or past it */
            double nx = -t->dy, ny = t->dx;
            if (nx * cos(L[k].angle) + ny * sin(L[k].angle) > 0) nx = -nx, ny = -ny;
            t->off = rs__tee_offset(roads, r, L[k].kind == RS_LEG_END, tl, nx, ny, net->tol);
        }
    }
    *out = T;
    return RS_OK;
}

/* The clip lines of a side road's cut-back copy at a T (T: the end's
 * tee, (wx, wy): the side road's direction from the node, (ex, ey): its
 * end point): the copy cuts the through road's lines only beyond `keep`
 * from its centre line, on the side road's side. The centre line passes
 * C = end + off n (n: the through road's normal towards the side road).
 * A straight street, or one bending away from the side road: one line
 * parallel to its direction from both legs (away from the side road the
 * legs only draw further from it); bending towards the side road: one line
 * per leg (the band of both legs there ends where the two meet). */
static void tee_keep_lines(const ls_tee *T, double wx, double wy, double ex, double ey, ls_surf *Qt)
{
    double nx = -T->dy, ny = T->dx;
    if (nx * wx + ny * wy < 0) nx = -nx, ny = -ny;
    double cx = ex + T->off * nx, cy = ey + T->off * ny;
    double bx = T->lx[0] + T->lx[1], by = T->ly[0] + T->ly[1];
    Qt->clip = 1;
    Qt->cx = -nx, Qt->cy = -ny, Qt->cc = -(nx * cx + ny * cy + T->keep);
    Qt->clip2 = 0;
    Qt->cx2 = Qt->cy2 = Qt->cc2 = 0;
    if (!(bx * wx + by * wy > 1e-6)) return;
    for (int k = 0; k < 2; k++) {
        double mx = -T->ly[k], my = T->lx[k];
        if (mx * wx + my * wy < 0) mx = -mx, my = -my;
        double c = -(mx * cx + my * cy + T->keep);
        if (k == 0) Qt->cx = -mx, Qt->cy = -my, Qt->cc = c;
        else Qt->clip2 = 1, Qt->cx2 = -mx, Qt->cy2 = -my, Qt->cc2 = c;
    }
}

/* Surfaces of every road with a width, their index, and the road ends. */
/* A record the network takes for a point (no longer than twice its
 * tolerance: the records on either side continue each other across it,
 * lib/scene/network.c bridge_short): its surface cuts no line and it draws
 * none (under its neighbours' surfaces it left a gap in their lines as
 * wide as itself, and its own lines stray bits of pattern). */
static int short_record(const rs_network *net, size_t nroads, size_t r)
{
    return net && rs_network_road_count(net) == nroads && net->length[r] <= 2 * net->tol;
}

/* A stroke of short records no longer than 2 tol in all: the road unsplit
 * would be one short record, which draws no lines (docs/network.md
 * "Degenerate records"). A run of more than 16 such records is a chain of
 * its own (lib/scene/network.c), so it reaches here as a stroke. */
static int short_stroke(const rs_network *net, size_t nroads, const uint32_t *recs, size_t nrec)
{
    double len = 0;
    for (size_t q = 0; q < nrec; q++) {
        if (!short_record(net, nroads, recs[q])) return 0;
        len += net->length[recs[q]];
    }
    return len <= 2 * net->tol;
}

/* How far a road's surface rectangle must run past a vertex of the road
 * for the round join there: hw tan(turn / 2), at most hw; (ax, ay), (bx,
 * by): the unit directions of travel into and out of the vertex. */
static double join_ext(double ax, double ay, double bx, double by, double hw)
{
    double c = ax * bx + ay * by, sn = fabs(ax * by - ay * bx);
    return 1 + c > sn ? hw * sn / (1 + c) : hw;
}

/* join_ext at a vertex of v: (ux, uy) the rectangle's segment's unit
 * direction, segment k (v[k] .. v[k + 1]) the one on the vertex's other side. */
static double join_reach(const ls_vtx *v, size_t k, double ux, double uy, double hw)
{
    double nx, ny;
    unit_dir(v[k].x, v[k].y, v[k + 1].x, v[k + 1].y, &nx, &ny);
    return join_ext(ux, uy, nx, ny, hw);
}

/* Where two records of a stroke meet at a bend (an OSM way split there,
 * a roundabout split at its arms), the union of their capsules has the
 * round join of one road: their end rectangles need run past the joint
 * only hw tan(turn / 2) each (join_ext), not the half width, when the
 * two are as wide and cut the same lines. end_rect: per record end, its
 * end rectangle in J->sf (SIZE_MAX: none, or a T's, left as it is). */
static void joints_reach(ls_junc *J, const ls_ends *ends, const rs_network *net, const size_t *end_rect,
                         size_t nroads)
{
    if (!net || rs_network_road_count(net) != nroads || !net->prev || !net->next) return;
    for (size_t ri = 0; ri < nroads; ri++)
        for (int e = 0; e < 2; e++) {
            size_t ka = end_rect[2 * ri + (size_t)e];
            if (ka == SIZE_MAX) continue;
            uint32_t cand[4] = { net->prev[ri], net->next[ri], UINT32_MAX, UINT32_MAX };
            uint32_t k = net->stroke_of[ri];
            if (net->closed && net->closed[k]) { /* the seam of a ring of records */
                cand[2] = net->stroke_roads[net->stroke_start[k]];
                cand[3] = net->stroke_roads[net->stroke_start[k + 1] - 1];
            }
            ls_surf *Q = &J->sf[ka];
            for (int c = 0; c < 4; c++) {
                uint32_t q = cand[c];
                if (q == UINT32_MAX || q == ri || q >= nroads || !ends[q].valid || J->nocut[q] != J->nocut[ri] ||
                    J->car[q] != J->car[ri] || (J->prio && J->prio[q] != J->prio[ri]))
                    continue;
                int f = ends[q].x[0] == ends[ri].x[e] && ends[q].y[0] == ends[ri].y[e] ? 0
                        : ends[q].x[1] == ends[ri].x[e] && ends[q].y[1] == ends[ri].y[e] ? 1 : -1;
                /* (the rectangles' half widths: the roads' widths) */
                if (f < 0 || end_rect[2 * (size_t)q + (size_t)f] == SIZE_MAX ||
                    J->sf[end_rect[2 * (size_t)q + (size_t)f]].r != Q->r)
                    continue;
                /* both directions point away from the joint: into it is the reverse of one */
                double ext = join_ext(-ends[ri].dx[e], -ends[ri].dy[e], ends[q].dx[f], ends[q].dy[f], Q->r);
                if (e) Q->u1 = rs__fmin(Q->u1, Q->len + ext);
                else Q->u0 = rs__fmax(Q->u0, -ext);
                Q->cap &= e ? ~2u : ~1u; /* a joint: the next record's surface goes on */
                break;
            }
        }
}

static rs_result junc_build(rs_ctx *ctx, rs__linesym *L, const rs_roads *roads, const rs__linesym_params *p,
                            ls_junc *J, ls_vtx **pts, double **sv, size_t *cap)
{
    size_t nroads = rs_roads_count(roads), ncap = 0;
    double per_unit = rs__local_quantum(p->cell_size);
    double wmap = (double)p->out_w * p->pixel, hmap = (double)p->out_h * p->pixel;
    ls_ends *ends = rs__calloc(ctx, nroads ? nroads : 1, sizeof *ends);
    J->ends = ends;
    J->nocut = rs__calloc(ctx, nroads ? nroads : 1, 1);
    J->car = rs__calloc(ctx, nroads ? nroads : 1, 1);
    if (!ends || !J->nocut || !J->car) return RS_ERR_NOMEM;
    J->keep = rs__alloc_array(ctx, nroads ? nroads : 1, sizeof *J->keep);
    if (!J->keep) return RS_ERR_NOMEM;
    if (p->prio_given) J->prio = p->prio;
    else {
        rs_result rp = rs__road_priorities(ctx, roads, &J->prio_own);
        if (rp) return rp;
        J->prio = J->prio_own;
    }
    for (size_t ri = 0; ri < nroads; ri++) {
        if (rs__tick(ctx, 0)) return RS_ERR_CANCELLED;
        const char *jc = rs_roads_get_attr(roads, ri, "junction_cuts");
        double w = 0;
        rs_roads_get(roads, ri, NULL, &w, NULL, NULL);
        J->nocut[ri] = jc && !strcmp(jc, "no");
        J->car[ri] = !rs__road_non_car(roads, ri);
        J->keep[ri] = rs__fmax(0.5 * w - TEE_EDGE_ZONE, 0);
    }
    ls_tee *tees = NULL;
    rs_result rt = rs__network_tees(ctx, roads, p->net, &tees);
    if (rt) return rt;
    /* trimmed ends (lib/scene/tee_ends.c): per road end the index of its T end */
    rs__tee_end *tend = NULL;
    size_t ntend = 0, *tend_of = NULL;
    if ((rt = rs__tee_ends_from(ctx, p->tees, roads, p->net, &tend, &ntend)) != RS_OK ||
        (ntend && !(tend_of = rs__alloc_array(ctx, 2 * nroads, sizeof *tend_of)))) {
        rs__free(ctx, tees);
        rs__free(ctx, tend);
        return rt ? rt : RS_ERR_NOMEM;
    }
    for (size_t i = 0; tend_of && i < 2 * nroads; i++) tend_of[i] = SIZE_MAX;
    /* per record end: its end segment's surface rectangle in J->sf, to run
     * on into a record continuing it (joints_reach, below) */
    size_t *end_rect = rs__alloc_array(ctx, 2 * (nroads ? nroads : 1), sizeof *end_rect);
    if (!end_rect) {
        rs__free(ctx, tees);
        rs__free(ctx, tend);
        rs__free(ctx, tend_of);
        return RS_ERR_NOMEM;
    }
    for (size_t i = 0; i < 2 * nroads; i++) end_rect[i] = SIZE_MAX;
    for (size_t i = 0; i < ntend; i++) tend_of[2 * (size_t)tend[i].road + (tend[i].end != 0)] = i;
    for (size_t ri = 0; ri < nroads; ri++) {
        double w = 0;
        size_t m = 0;
        rs_roads_get(roads, ri, NULL, &w, NULL, NULL);
        rs_result r = rs__tick(ctx, 0) ? RS_ERR_CANCELLED : road_local(ctx, roads, ri, p, per_unit, pts, sv, cap, &m);
        if (r) {
            rs__free(ctx, tees);
            rs__free(ctx, tend);
            rs__free(ctx, tend_of);
            rs__free(ctx, end_rect);
            return r;
        }
        if (m < 2 || short_record(p->net, nroads, ri)) continue;
        const ls_vtx *v = *pts;
        ends[ri].valid = 1;
        ends[ri].x[0] = v[0].x, ends[ri].y[0] = v[0].y;
        ends[ri].x[1] = v[m - 1].x, ends[ri].y[1] = v[m - 1].y;
        unit_dir(v[0].x, v[0].y, v[1].x, v[1].y, &ends[ri].dx[0], &ends[ri].dy[0]);
        unit_dir(v[m - 1].x, v[m - 1].y, v[m - 2].x, v[m - 2].y, &ends[ri].dx[1], &ends[ri].dy[1]);
        double hw = 0.5 * w;
        if (!(hw > 0) || !(hw <= BAND_MAX_EXTENT) || J->nocut[ri]) continue; /* no surface to stop at */
        const int closed = m >= 4 && v[0].x == v[m - 1].x && v[0].y == v[m - 1].y;
        for (size_t i = 0; i + 1 < m; i++) {
            ls_surf Q;
            unit_dir(v[i].x, v[i].y, v[i + 1].x, v[i + 1].y, &Q.ux, &Q.uy);
            double len = rs__arc_len(v[i].x, v[i].y, v[i + 1].x, v[i + 1].y), lo, hi, span, rest, cx, cy;
            int far_cut;
            if (!cut_segment(v[i].x, v[i].y, v[i + 1].x, v[i + 1].y, Q.ux, Q.uy, len, 2 * hw + L->margin, wmap, hmap,
                             &lo, &hi, &span, &rest, &cx, &cy, &far_cut))
                continue;
            Q.ax = far_cut ? cx : v[i].x + lo * Q.ux;
            Q.ay = far_cut ? cy : v[i].y + lo * Q.uy;
            Q.len = span;
            Q.r = hw;
            /* past an end, hw (a superset of the round cap); past a vertex
             * of the road (a closed record's seam too), only as far as the
             * round join needs: hw tan(turn / 2) covers its sector, so a
             * line meeting the outside of a gentle bend stops at most
             * hw (1 / cos(turn / 2) - 1) early (up to (sqrt 2 - 1) hw until
             * 6 December 2026, 0.46 m at an arm of a 24-point ring) */
            Q.u0 = (i > 0 || closed) && !(lo > 0) ? -join_reach(v, i > 0 ? i - 1 : m - 2, Q.ux, Q.uy, hw) : -hw;
            Q.u1 = Q.len + ((i + 2 < m || closed) && !(hi < len) ? join_reach(v, i + 2 < m ? i + 1 : 0, Q.ux, Q.uy, hw)
                                                                : hw);
            Q.road = (uint32_t)ri;
            /* a free end: its round cap (cut_capped) */
            Q.cap = (!closed && !far_cut && i == 0 && !(lo > 0) ? 1u : 0u) |
                    (!closed && !far_cut && i + 2 == m && !(hi < len) ? 2u : 0u);
            Q.only = Q.skip = Q.only2 = Q.skip2 = Q.skip3 = Q.skip4 = NO_STROKE;
            Q.clip = Q.clip2 = 0;
            Q.cx = Q.cy = Q.cc = Q.cx2 = Q.cy2 = Q.cc2 = 0;
            /* a trimmed end at a T: the rectangle reaches as far as the
             * strip does and is cut by the far edge line */
            for (int e = 0; tend_of && e < 2; e++) {
                int here = e ? i + 2 == m && hi == len : i == 0 && lo == 0;
                size_t ti = tend_of[2 * ri + (size_t)e];
                if (ti == SIZE_MAX) continue;
                const rs__tee_end *te = &tend[ti];
                if (!here) {
                    /* another segment of the record reaching past the line
                     * (its surface is clipped there too) */
                    double ex = e ? v[m - 1].x : v[0].x, ey = e ? v[m - 1].y : v[0].y;
                    double cc = te->nx * ex + te->ny * ey + te->far;
                    double fa = te->nx * Q.ax + te->ny * Q.ay, fb = fa + (Q.len + hw) * (te->nx * Q.ux + te->ny * Q.uy);
                    fa -= hw * (te->nx * Q.ux + te->ny * Q.uy);
                    if (!Q.clip && rs__fmax(fa, fb) + hw > cc) Q.clip = 1, Q.cx = te->nx, Q.cy = te->ny, Q.cc = cc;
                    continue;
                }
                double dx = e ? Q.ux : -Q.ux, dy = e ? Q.uy : -Q.uy; /* towards the end */
                double sn = te->nx * dx + te->ny * dy, cs = fabs(te->nx * dy - te->ny * dx);
                if (!(sn > 0.1)) continue;
                double ex = e ? v[m - 1].x : v[0].x, ey = e ? v[m - 1].y : v[0].y;
                double reach = rs__fmax((te->far + hw * cs) / sn, hw);
                if (e) Q.u1 = Q.len + reach;
                else Q.u0 = -reach;
                Q.cap &= e ? ~2u : ~1u; /* trimmed: no cap */
                Q.clip = 1;
                Q.cx = te->nx, Q.cy = te->ny, Q.cc = te->nx * ex + te->ny * ey + te->far;
            }
            /* an end segment at a T: the through stroke gets a copy that
             * stops `keep` short of its centre line (no extension); a
             * record of one segment may have a T at either end or both
             * (until 6 December 2026 only its end's was looked up, so a
             * two-point side road drawn from the T cut the through road's
             * far lines across its mouth) */
            int at_end = i + 2 == m && hi == len, at_start = i == 0 && lo == 0;
            ls_surf Qt[2];
            int tee = 0;
            for (int e = 1; tees && e >= 0; e--) { /* (the end's first: the order until then) */
                const ls_tee *T = &tees[2 * ri + (size_t)e];
                if (!(e ? at_end : at_start) || T->stroke == NO_STROKE) continue;
                double sn = fabs(Q.ux * T->dy - Q.uy * T->dx); /* sine of the angle between the roads */
                if (!(sn > 0.2)) continue;
                /* the copy keeps to the side road's side of the line
                 * `keep` from the through road's centre line, parallel
                 * to it (docs/network.md "The through road at a T"):
                 * until 3 December 2026 it stopped (keep + off) / sine
                 * back along the side road, square to it, so at an
                 * oblique T its acute corner cut the centre line */
                double wx = e ? -Q.ux : Q.ux, wy = e ? -Q.uy : Q.uy; /* the side road, from the node */
                double ex = e ? v[m - 1].x : v[0].x, ey = e ? v[m - 1].y : v[0].y;
                Qt[tee] = Q;
                Qt[tee].skip = Qt[tee].skip2 = Qt[tee].skip3 = Qt[tee].skip4 = NO_STROKE;
                tee_keep_lines(T, wx, wy, ex, ey, &Qt[tee]);
                Qt[tee].only = T->stroke;
                Qt[tee].only2 = T->stroke2;
                if (tee == 0) Q.skip = T->stroke, Q.skip2 = T->stroke2;
                else Q.skip3 = T->stroke, Q.skip4 = T->stroke2;
                tee++;
            }
            for (int c = 0; c <= tee; c++) {
                void *arr = J->sf;
                rs_result g = rs__grow(ctx, &arr, J->nsf, &ncap, sizeof *J->sf, 256, UINT32_MAX);
                if (g) {
                    rs__free(ctx, tees);
                    rs__free(ctx, tend);
                    rs__free(ctx, tend_of);
                    rs__free(ctx, end_rect);
                    return g;
                }
                J->sf = arr;
                J->sf[J->nsf++] = c ? Qt[c - 1] : Q;
            }
            /* a record end that is no T's: its rectangle may run on into
             * a record continuing it */
            if (!tee && !Q.clip && i == 0 && lo == 0) end_rect[2 * ri] = J->nsf - 1;
            if (!tee && !Q.clip && i + 2 == m && hi == len) end_rect[2 * ri + 1] = J->nsf - 1;
        }
    }
    joints_reach(J, ends, p->net, end_rect, nroads);
    rs__free(ctx, tees);
    rs__free(ctx, tend);
    rs__free(ctx, tend_of);
    rs__free(ctx, end_rect);
    /* surfaces in square cells of CELL_PX pixels (doubled until at most MAX_CELLS) */
    uint32_t jpx = CELL_PX;
    for (;;) {
        uint64_t gw = ((uint64_t)p->out_w + jpx - 1) / jpx, gh = ((uint64_t)p->out_h + jpx - 1) / jpx;
        if (gw * gh <= MAX_CELLS || jpx >= (1u << 30)) {
            J->grid.gw = (uint32_t)gw;
            J->grid.gh = (uint32_t)gh;
            break;
        }
        jpx *= 2;
    }
    J->grid.cmx = J->grid.cmy = (double)jpx * p->pixel;
    size_t ncell = (size_t)J->grid.gw * J->grid.gh, total = 0;
    J->start = rs__calloc(ctx, ncell + 1, sizeof *J->start);
    J->stamp = rs__calloc(ctx, J->nsf ? J->nsf : 1, sizeof *J->stamp);
    if (!J->start || !J->stamp) return RS_ERR_NOMEM;
    /* the cells of each surface counted and kept as spans, then listed
     * from them (as the pieces' index: no second clipping) */
    ls_spans S;
    spans_init(ctx, &S, J->nsf);
    rs_result res = RS_OK;
    for (int pass = 0; pass < 2 && !res; pass++) {
        if (pass == 1) {
            uint64_t lim = UINT32_MAX - 1u;
            if (ctx->limits.max_road_cells && ctx->limits.max_road_cells < lim) lim = ctx->limits.max_road_cells;
            spans_mark(&S, J->nsf);
            if (!csr_close(J->start, ncell, lim, &total)) { res = RS_ERR_LIMIT; break; }
            J->ids = rs__alloc_array(ctx, total ? total : 1, sizeof *J->ids);
            if (!J->ids) { res = RS_ERR_NOMEM; break; }
        }
        for (size_t k = pass ? J->nsf : 0; pass ? k-- > 0 : k < J->nsf; k += pass ? 0 : 1) {
            if (rs__tick(ctx, 0)) { res = RS_ERR_CANCELLED; break; }
            if (pass && !S.failed) {
                for (uint32_t m = S.first[k]; m < S.first[k + 1]; m++)
                    for (uint32_t i = S.a[m]; i <= S.b[m]; i++)
                        J->ids[--J->start[(size_t)S.j[m] * J->grid.gw + i]] = (uint32_t)k;
                continue;
            }
            const ls_surf *Q = &J->sf[k];
            double x0 = DBL_MAX, y0 = DBL_MAX, x1 = -DBL_MAX, y1 = -DBL_MAX;
            const double U[4] = { Q->u0, Q->u1, Q->u1, Q->u0 }, V[4] = { -Q->r, -Q->r, Q->r, Q->r };
            for (int c = 0; c < 4; c++) {
                double x = Q->ax + U[c] * Q->ux + V[c] * Q->uy, y = Q->ay + U[c] * Q->uy - V[c] * Q->ux;
                x0 = rs__fmin(x0, x), x1 = rs__fmax(x1, x), y0 = rs__fmin(y0, y), y1 = rs__fmax(y1, y);
            }
            if (!pass) spans_mark(&S, k);
            rect_cells(&J->grid, Q->ax, Q->ay, Q->ux, Q->uy, Q->u0, Q->u1, -Q->r, Q->r, x0, y0, x1, y1, J->start,
                       J->ids, (uint32_t)k, NULL, NULL, pass, ctx, pass ? NULL : &S);
        }
    }
    spans_free(ctx, &S);
    return res;
}

void rs__linesym_free(rs_ctx *ctx, rs__linesym *L)
{
    if (!L) return;
    rs__free(ctx, L->start);
    rs__free(ctx, L->pb);
    rs__free(ctx, L->pp);
    rs__free(ctx, L->ent);
    rs__free(ctx, L->hpp);
    rs__free(ctx, L->band);
    rs__free(ctx, L->dash);
    rs__free(ctx, L->cut_start);
    rs__free(ctx, L->cut_ord);
    rs__free(ctx, L->cs);
    rs__free(ctx, L);
}

size_t rs__linesym_bytes(const rs__linesym *L) { return L ? L->bytes : 0; }

size_t rs__linesym_piece_count(const rs__linesym *L) { return L ? L->npc : 0; }

void rs__linesym_piece_get(const rs__linesym *L, size_t k, rs__linesym_piece_view *out)
{
    const ls_ppc *P = &L->pp[k];
    const ls_band *B = &L->band[P->band];
    const double *hp = L->hpp + 4 * (size_t)P->hp0;
    int slab = P->kind == PIECE_SLAB;
    const double f[] = { P->ox, P->oy, P->ux, P->uy, P->a, P->b, P->s0, P->su, B->period, B->phase, B->t };
    uint64_t h = rs__fp_mix(rs__fp_mix(0x11e5, P->kind), P->dashed);
    for (size_t j = 0; j < sizeof f / sizeof f[0]; j++) h = rs__fp_mixd(h, f[j]);
    for (int c = 0; c < 4; c++) h = rs__fp_mixd(h, (double)B->rgba[c]);
    for (uint32_t j = 0; j < B->ndash; j++) h = rs__fp_mixd(h, L->dash[B->dash0 + j]);
    /* a slab's first two half-planes are its v limits; a wedge's all count */
    uint32_t own = slab && P->nhp >= 2 ? 2 : P->nhp;
    for (size_t j = 0; j < 4 * (size_t)own; j++) h = rs__fp_mixd(h, hp[j]);
    memset(out, 0, sizeof *out);
    out->slab = slab;
    out->ox = P->ox, out->oy = P->oy, out->ux = P->ux, out->uy = P->uy;
    if (slab) {
        out->ru0 = P->ru0, out->ru1 = P->ru1, out->rv0 = P->rv0, out->rv1 = P->rv1;
        out->hp = hp + 4 * (size_t)own;
        out->nhp = P->nhp - own;
    } else {
        const double w[] = { P->r0, P->r1, P->wx0, P->wy0, P->wx1, P->wy1, P->warea };
        for (size_t j = 0; j < sizeof w / sizeof w[0]; j++) h = rs__fp_mixd(h, w[j]);
        out->reg[0] = P->ox + P->wx0, out->reg[1] = P->oy + P->wy0, out->reg[2] = P->ox + P->wx1;
        out->reg[3] = P->oy + P->wy1, out->reg[4] = -1;
        if (!(P->wx0 <= P->wx1 && P->wy0 <= P->wy1)) out->reg[0] = 1, out->reg[2] = 0;
    }
    out->h = h;
}

rs_result rs__linesym_build(rs_ctx *ctx, const rs_roads *roads, const rs__linesym_params *p,
                            const uint32_t *band_start, const rs__band *bands, rs__linesym **out)
{
    *out = NULL;
    if (!roads || !p || !band_start || !(p->pixel > 0) || !isfinite(p->pixel) || !(p->cell_size > 0) ||
        !isfinite(p->origin_x) || !isfinite(p->origin_y) || p->out_w == 0 || p->out_h == 0)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "line symbols: bad parameters");
    size_t nroads = rs_roads_count(roads);
    uint32_t nband = band_start[nroads];
    size_t ndash = 0;
    for (uint32_t k = 0; k < nband; k++) {
        const rs__band *b = &bands[k];
        if (!(b->w > 0) || !(fabs(b->t) + 0.5 * b->w <= BAND_MAX_EXTENT) || (b->ndash & 1) || (b->ndash && !b->dash) ||
            !isfinite(b->phase) || fabs(b->phase) > 1e15)
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "line symbols: band %u: bad offset, width, dash or phase", k);
        double per = 0;
        for (uint32_t j = 0; j < b->ndash; j++) {
            if (!(b->dash[j] >= 0) || !(b->dash[j] <= 1e6))
                return rs__fail(ctx, RS_ERR_INVALID_ARG, "line symbols: band %u: bad dash length", k);
            per += b->dash[j];
        }
        /* a shorter period only makes grey: refuse it rather than loop per pixel over thousands of dashes */
        if (b->ndash && !(per >= 1e-3))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "line symbols: band %u: dash period below 1 mm", k);
        ndash += b->ndash;
    }
    rs__linesym *L = rs__calloc(ctx, 1, sizeof *L);
    if (!L) return rs__fail(ctx, RS_ERR_NOMEM, "line symbols: out of memory");
    rs_result res = RS_OK;
    L->pixel = p->pixel;
    L->budget = ctx->limits.max_linesym_bytes;
    L->win_on = p->window_on;
    memcpy(L->win, p->window, sizeof L->win);
    /* A slab per band and segment and a wedge per joint, about, as the
     * first capacity: growing by doubling from a small one wrote (and
     * faulted in) the arrays twice over and copied them (15 % of the styled
     * city's style build). At most 2^18 pieces at first: unwritten room
     * costs address space only, and the arrays shrink to what was made. */
    {
        uint64_t est = 0;
        for (size_t ri = 0; ri < nroads && est < (1u << 18); ri++) {
            size_t n = 0;
            rs_roads_get(roads, ri, NULL, NULL, NULL, &n);
            est += (uint64_t)(band_start[ri + 1] - band_start[ri]) * (2 * (uint64_t)n + 1);
        }
        L->cap0 = est < 256 ? 256 : est > (1u << 18) ? (1u << 18) : (size_t)est;
    }
    L->margin = p->pixel * HALF_SQRT2;
    L->aa = p->aa;
    L->out_w = p->out_w;
    L->out_h = p->out_h;
    L->cpx = CELL_PX;
    L->cpy = CELL_ROWS;
    for (;;) {
        uint64_t gw = ((uint64_t)p->out_w + L->cpx - 1) / L->cpx, gh = ((uint64_t)p->out_h + L->cpy - 1) / L->cpy;
        if (gw * gh <= MAX_CELLS || L->cpx >= (1u << 30)) {
            L->gw = (uint32_t)gw;
            L->gh = (uint32_t)gh;
            break;
        }
        L->cpx *= 2;
        L->cpy *= 2;
    }
    L->grid.gw = L->gw;
    L->grid.gh = L->gh;
    L->grid.cmx = (double)L->cpx * p->pixel;
    L->grid.cmy = (double)L->cpy * p->pixel;
    L->band = rs__alloc_array(ctx, nband ? nband : 1, sizeof *L->band);
    L->dash = rs__alloc_array(ctx, ndash ? ndash : 1, sizeof *L->dash);
    size_t ncell = (size_t)L->gw * L->gh;
    L->start = rs__calloc(ctx, ncell + 1, sizeof *L->start);
    ls_vtx *pts = NULL;
    double *sv = NULL, *own_bases = NULL;
    uint32_t *sr = NULL; /* the record of each segment of pts */
    size_t srcap = 0;
    ls_run *runs = NULL; /* a stroke's runs of records that look alike */
    size_t runcap = 0;
    ls_junc J;
    memset(&J, 0, sizeof J);
    J.own_road = UINT32_MAX;
    int over = 0; /* push_cut passed the work limit */
    if (!L->band || !L->dash || !L->start) { res = RS_ERR_NOMEM; goto fail; }
    L->nband = nband;
    for (uint32_t k = 0, d0 = 0; k < nband; k++) {
        ls_band *B = &L->band[k];
        memcpy(B->rgba, bands[k].rgba, sizeof B->rgba);
        B->dash0 = d0;
        B->ndash = bands[k].ndash;
        B->phase = bands[k].phase;
        B->t = bands[k].t;
        B->period = 0;
        for (uint32_t j = 0; j < B->ndash; j++) {
            L->dash[d0 + j] = bands[k].dash[j];
            B->period += bands[k].dash[j];
        }
        d0 += B->ndash;
    }
    double per_unit = rs__local_quantum(p->cell_size);
    double wmap = (double)p->out_w * p->pixel, hmap = (double)p->out_h * p->pixel;
    size_t cap = 0, total = 0;
    if (rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto fail; }
    if (nband && (res = junc_build(ctx, L, roads, p, &J, &pts, &sv, &cap)) != RS_OK) goto fail;
    J.limit = ctx->limits.max_field_work;
    if (nband && !(L->cs = rs__alloc_array(ctx, 2, sizeof *L->cs))) { res = RS_ERR_NOMEM; goto fail; }
    /* road by road, or stroke by stroke: the stroke's records as one polyline */
    const rs_network *net = p->net && rs_network_road_count(p->net) == nroads ? p->net : NULL;
    J.stroke_of = net ? net->stroke_of : NULL;
    /* the cuts by stroke (a counting sort): a stroke's polyline leaves out
     * the points where its records meet in a straight line, so a piece
     * cannot tell which record it lies on; the cuts are places, so every
     * cut of the stroke applies to each of its pieces */
    if (p->ncuts) {
        L->cuts = p->cuts;
        L->cut_stroke = J.stroke_of;
        L->cut_start = rs__calloc(ctx, nroads + 2, sizeof *L->cut_start);
        L->cut_ord = rs__alloc_array(ctx, p->ncuts, sizeof *L->cut_ord);
        if (!L->cut_start || !L->cut_ord) { res = RS_ERR_NOMEM; goto fail; }
        for (size_t k = 0; k < p->ncuts; k++)
            if (p->cuts[k].road < nroads) L->cut_start[cut_key(L, p->cuts[k].road) + 2]++;
        for (size_t r = 0; r < nroads; r++) L->cut_start[r + 2] += L->cut_start[r + 1];
        for (size_t k = 0; k < p->ncuts; k++)
            if (p->cuts[k].road < nroads) L->cut_ord[L->cut_start[cut_key(L, p->cuts[k].road) + 1]++] = (uint32_t)k;
    }
    /* each record's stroke arc length where it starts: the network's (a
     * part of a map) or summed here, record by record (stroke_arcs) */
    const double *bases = net ? net->s_base : NULL;
    if (net && !bases && net->nroads == nroads) {
        if (!(own_bases = rs__alloc_array(ctx, nroads ? nroads : 1, sizeof *own_bases))) {
            res = RS_ERR_NOMEM;
            goto fail;
        }
        if ((res = rs__stroke_bases(ctx, net, roads, p->origin_x, p->origin_y, p->cell_size, NULL, 0, own_bases)))
            goto fail;
        bases = own_bases;
    }
    size_t nstroke = net ? net->nstrokes : nroads;
    for (size_t k = 0; k < nstroke; k++) {
        uint32_t one = (uint32_t)k;
        const uint32_t *recs = net ? net->stroke_roads + net->stroke_start[k] : &one;
        size_t nrec = net ? net->stroke_start[k + 1] - net->stroke_start[k] : 1;
        uint32_t head = recs[0];
        if (rs__tick(ctx, nrec)) { res = RS_ERR_CANCELLED; goto fail; }
        if (band_start[head + 1] == band_start[head] || short_stroke(net, nroads, recs, nrec)) continue;
        /* records drawn both ways need lines that look the same both ways;
         * else each record is drawn alone */
        int alone = 0;
        for (size_t q = 1; net && q < nrec && !alone; q++)
            alone = net->rev[recs[q]] != net->rev[head] &&
                    (!bands_mirror(bands + band_start[head], band_start[head + 1] - band_start[head]) ||
                     !bands_mirror(bands + band_start[recs[q]], band_start[recs[q] + 1] - band_start[recs[q]]));
        for (size_t q0 = 0; q0 < nrec; q0 = alone ? q0 + 1 : nrec) {
            size_t m = 0, q1 = alone ? q0 + 1 : nrec;
            /* runs of records that look alike: where the lanes change along
             * the stroke the next run draws its own bands from the joint
             * on (the joint is kept), the arc length running on */
            size_t nrun = 0;
            for (size_t q = q0; q < q1; q++) {
                size_t m0 = m;
                int rev = net && !alone ? net->rev[recs[q]] : 0;
                uint32_t lead = nrun ? runs[nrun - 1].rec : recs[q];
                int starts = !nrun || !bands_equal(bands + band_start[lead], band_start[lead + 1] - band_start[lead],
                                                   bands + band_start[recs[q]],
                                                   band_start[recs[q] + 1] - band_start[recs[q]]);
                int gap = 0;
                if ((res = road_local_append(ctx, roads, recs[q], rev, p, per_unit, &pts, &sv, &cap, &m, &gap)) !=
                    RS_OK)
                    goto fail;
                if (bases && !alone) stroke_arcs(bases[recs[q]], roads, recs[q], rev, p, per_unit, pts, sv, m0, m);
                /* across a bridged short record both ends of the gap are
                 * joints: either left standing in a straight line would stop
                 * the mitre of a nearby bend (fuzz/split) */
                /* (not where the level changes, a bridge's record and the
                 * road it continues: a merged segment would be one record's,
                 * and the level of a piece's record decides which surfaces
                 * cut it; docs/network.md "Bridges and layers") */
                const int level_kept = q > q0 && rs__road_level(roads, recs[q]) != rs__road_level(roads, recs[q - 1]);
                if (!starts && !level_kept && gap && m0 >= 1 && m > m0 + 1 && drop_straight_joint(pts, sv, m0, m, 4 / per_unit))
                    m--;
                if (!starts && !level_kept && m0 >= 2 && m > m0 && drop_straight_joint(pts, sv, m0 - 1, m, 4 / per_unit))
                    m--, m0--;
                if (cap > srcap) {
                    uint32_t *ns = rs__realloc(ctx, sr, cap * sizeof *sr);
                    if (!ns) { res = RS_ERR_NOMEM; goto fail; }
                    sr = ns;
                    srcap = cap;
                }
                for (size_t i = m0 ? m0 - 1 : 0; i + 1 < m; i++) sr[i] = recs[q];
                if (starts) {
                    if (nrun == runcap) {
                        size_t nc = runcap ? 2 * runcap : 8;
                        ls_run *nr = rs__realloc(ctx, runs, nc * sizeof *runs);
                        if (!nr) { res = RS_ERR_NOMEM; goto fail; }
                        runs = nr;
                        runcap = nc;
                    }
                    runs[nrun].rec = recs[q];
                    runs[nrun].at = m0 ? m0 - 1 : 0;
                    nrun++;
                }
            }
            if (m < 2) continue;
            /* a ring drawn as one run: its seam joins (road_band_pieces) */
            const int ring = net && net->closed && net->closed[k] && !alone && nrun == 1;
            for (size_t u = 0; u < nrun; u++) {
                size_t i0 = runs[u].at, i1 = u + 1 < nrun ? runs[u + 1].at : m - 1;
                uint32_t first = runs[u].rec;
                if (i1 <= i0) continue;
                for (uint32_t b = band_start[first]; b < band_start[first + 1]; b++)
                    if ((res = road_band_pieces(ctx, L, &J, sr + i0, pts + i0, sv + i0, i1 - i0 + 1, &bands[b], b, wmap,
                                                hmap, ring)) != RS_OK)
                        goto fail;
            }
        }
    }
    rs__free(ctx, pts);
    rs__free(ctx, sv);
    rs__free(ctx, sr);
    rs__free(ctx, runs);
    rs__free(ctx, own_bases);
    own_bases = NULL;
    rs__free(ctx, L->cs);
    L->cs = NULL;
    sr = NULL;
    runs = NULL;
    junc_free(ctx, &J);
    pts = NULL;
    sv = NULL;
    /* the painter's records were made piece by piece: hand back the spare room */
    size_t nhpp = L->nhpp;
    if (L->npc && L->npc < L->cap) {
        ls_ppc *np = rs__realloc(ctx, L->pp, L->npc * sizeof *L->pp);
        if (np) L->pp = np;
    }
    if (nhpp && nhpp < L->hcap) {
        double *nh = rs__realloc(ctx, L->hpp, 4 * nhpp * sizeof *L->hpp);
        if (nh) L->hpp = nh;
    }
    /* the cells each piece covers, counted and kept as spans (the fill
     * pass below lists the pieces there without clipping again) */
    ls_spans S;
    spans_init(ctx, &S, L->npc);
    for (size_t k = 0; k < L->npc; k++) {
        if (rs__tick(ctx, 0)) { res = RS_ERR_CANCELLED; break; }
        spans_mark(&S, k);
        piece_cells(L, (uint32_t)k, 0, ctx, &S);
    }
    spans_mark(&S, L->npc);
    if (res) {
        spans_free(ctx, &S);
        goto fail;
    }
    uint64_t lim = UINT32_MAX - 1u;
    if (ctx->limits.max_road_cells && ctx->limits.max_road_cells < lim) lim = ctx->limits.max_road_cells;
    if (!csr_close(L->start, ncell, lim, &total)) res = RS_ERR_LIMIT;
    /* the index entries count too: a piece is listed in every cell it covers */
    if (!res && L->budget && (uint64_t)total * (sizeof(uint32_t) + sizeof *L->ent) >
                                 L->budget - ((uint64_t)L->npc * PIECE_BYTES + (uint64_t)nhpp * HP_BYTES)) {
        L->over_budget = 1;
        res = RS_ERR_LIMIT;
    }
    if (!res && !(L->ent = rs__alloc_array(ctx, total ? total : 1, sizeof *L->ent))) res = RS_ERR_NOMEM;
    for (size_t k = L->npc; !res && k-- > 0;) {
        if (rs__tick(ctx, 0)) { res = RS_ERR_CANCELLED; break; }
        if (S.failed) {
            piece_cells(L, (uint32_t)k, 1, ctx, NULL);
            continue;
        }
        const ls_pbuild *PB = &L->pb[k];
        ls_pbox v = { PB->gx0, PB->gx1, PB->gy0, PB->gy1, (uint32_t)k, L->pp[k].band };
        for (uint32_t m = S.first[k]; m < S.first[k + 1]; m++)
            for (uint32_t i = S.a[m]; i <= S.b[m]; i++) L->ent[--L->start[(size_t)S.j[m] * L->grid.gw + i]] = v;
    }
    spans_free(ctx, &S);
    if (res) goto fail;
    rs__free(ctx, L->pb); /* built */
    rs__free(ctx, L->cut_start);
    rs__free(ctx, L->cut_ord);
    L->pb = NULL;
    L->cut_start = L->cut_ord = NULL;
    L->cuts = NULL;
    L->cut_stroke = NULL;
    L->cap = 0;
    L->bytes = sizeof *L + (ncell + 1) * sizeof *L->start + total * sizeof *L->ent + L->npc * sizeof *L->pp +
               4 * nhpp * sizeof *L->hpp + nband * sizeof *L->band +
               ndash * sizeof *L->dash;
    *out = L;
    rs__ok(ctx);
    return RS_OK;
fail:
    over = J.limit && J.work > J.limit;
    int over_bytes = L->over_budget;
    rs__free(ctx, pts);
    rs__free(ctx, sv);
    rs__free(ctx, sr);
    rs__free(ctx, runs);
    rs__free(ctx, own_bases);
    junc_free(ctx, &J);
    rs__linesym_free(ctx, L);
    if (res == RS_ERR_NOMEM) return rs__fail(ctx, res, "line symbols: out of memory");
    if (res == RS_ERR_CANCELLED) return rs__fail(ctx, res, "cancelled");
    if (over_bytes)
        return rs__fail(ctx, res,
                        "line symbols: the pieces of the roads' lines and dashes and their index take more than "
                        "%llu bytes together (many styled lines, dashes or points; the budget is "
                        "rs_limits.max_linesym_bytes)", (unsigned long long)ctx->limits.max_linesym_bytes);
    if (over)
        return rs__fail(ctx, res,
                        "line symbols: cutting lines at the other roads' surfaces takes more than %llu steps "
                        "(too many roads in one place; the budget is rs_limits.max_field_work)",
                        (unsigned long long)ctx->limits.max_field_work);
    return rs__fail(ctx, res, "line symbols: too many pieces or index entries");
}

/* ------------------------------------------------------------------------
 * Painting
 * ---------------------------------------------------------------------- */

/* floor and ceil by a conversion (the painter's hot loops) */
static double fast_floor(double x)
{
    if (!(x > -1e15 && x < 1e15)) return floor(x);
    double t = (double)(long long)x;
    return t > x ? t - 1 : t;
}

static double fast_ceil(double x)
{
    if (!(x > -1e15 && x < 1e15)) return ceil(x);
    double t = (double)(long long)x;
    return t < x ? t + 1 : t;
}

/* Pixel columns [*lo, *hi] whose centres' u lies in [ua, ub] on the row
 * at yc (relative to P's origin; a superset by a little slack for
 * rounding). Narrows *lo, *hi. */
static inline void u_cols(const ls_ppc *P, double yc, double ua, double ub, double *lo, double *hi)
{
    /* u = xr ux + yc uy; xr = x - ox; pixel centres (x + 0.5) pix = xr + ox */
    double c = yc * P->uy;
    if (P->iku == 0) {
        if (c < ua - 1e-9 || c > ub + 1e-9) *hi = *lo - 1;
        return;
    }
    double t0 = (ua - c) * P->iku + P->cbase, t1 = (ub - c) * P->iku + P->cbase;
    if (t0 > t1) { double t = t0; t0 = t1; t1 = t; }
    double plo = fast_ceil(t0 - 1e-6), phi = fast_floor(t1 + 1e-6);
    if (plo > *lo) *lo = plo;
    if (phi < *hi) *hi = phi;
}

/* Pixel columns [*lo, *hi] of row y whose squares can touch slab P: their
 * centres lie in its u and v ranges grown by the square's extent along u
 * and v (a superset is harmless: its cover is 0). Narrows *lo, *hi. */
static void slab_row(const rs__linesym *L, const ls_ppc *P, uint32_t y, double *lo, double *hi)
{
    double yc = ((double)y + 0.5) * L->pixel - P->oy;
    /* v = xr uy - yc ux: the u formula in the frame turned by 90 degrees */
    double c = -yc * P->ux;
    if (P->ikv == 0) {
        if (c < P->rv0 - 1e-9 || c > P->rv1 + 1e-9) { *hi = *lo - 1; return; }
    } else {
        double t0 = (P->rv0 - c) * P->ikv + P->cbase, t1 = (P->rv1 - c) * P->ikv + P->cbase;
        if (t0 > t1) { double t = t0; t0 = t1; t1 = t; }
        double plo = fast_ceil(t0 - 1e-6), phi = fast_floor(t1 + 1e-6);
        if (plo > *lo) *lo = plo;
        if (phi < *hi) *hi = phi;
    }
    u_cols(P, yc, P->ru0, P->ru1, lo, hi);
}

/* Visit the block cell by cell; per cell, each run of pieces of one band:
 * sum their covers into scratch, then hand the run to `emit`. Each pixel
 * belongs to the one cell that holds it, whose list is in painting order,
 * so a pixel sees the same sums in the same order in every block. */
typedef void (*ls_emit)(const rs__linesym *L, uint32_t band, uint32_t x0, uint32_t y0, uint32_t y1, const uint32_t *rlo,
                        const uint32_t *rhi, const double *cov, size_t cstride, void *user);

/* A run's scratch rows: row y - y0 holds columns [x0, x1) (cs of them),
 * zeroed when first touched; [x0 + rlo, x0 + rhi) are the touched ones
 * (rhi 0: none). */
typedef struct ls_rows {
    uint32_t x0, x1, y0;
    size_t cs;
    double *scratch;
    uint32_t *rlo, *rhi;
} ls_rows;

/* Add piece P's cover of row y, columns [lo, hi] cut to the run's, into its scratch row. */
static void cover_cols(const rs__linesym *L, const ls_ppc *P, uint32_t y, double lo, double hi, const ls_rows *R)
{
    uint32_t x0 = R->x0, x1 = R->x1;
    uint32_t qa = lo > (double)x0 ? (lo < (double)x1 ? (uint32_t)lo : x1) : x0;
    uint32_t qb = hi + 1 < (double)x1 ? (hi + 1 > (double)qa ? (uint32_t)(hi + 1) : qa) : x1;
    if (qa >= qb) return;
    uint32_t r = y - R->y0;
    double *row = R->scratch + r * R->cs; /* column x at row[x - x0] */
    /* only the touched columns are zeroed (a thin line touches one or
     * two of the cell's 32 on a row) */
    if (R->rhi[r] == 0) {
        for (uint32_t x = qa - x0; x < qb - x0; x++) row[x] = 0;
        R->rlo[r] = qa - x0;
        R->rhi[r] = qb - x0;
    } else {
        if (qa - x0 < R->rlo[r]) {
            for (uint32_t x = qa - x0; x < R->rlo[r]; x++) row[x] = 0;
            R->rlo[r] = qa - x0;
        }
        if (qb - x0 > R->rhi[r]) {
            for (uint32_t x = R->rhi[r]; x < qb - x0; x++) row[x] = 0;
            R->rhi[r] = qb - x0;
        }
    }
    if (L->aa == RS__AA_HERMITE) {
        for (uint32_t x = qa; x < qb; x++) row[x - x0] += piece_hermite(L, P, x, y);
    } else if (P->kind == PIECE_SLAB && !P->dashed) {
        /* piece_area's first steps inline: outside the band, or crossing
         * only its edges well inside its ends (the same arithmetic) */
        double pix = L->pixel, yc = ((double)y * pix - P->oy) + 0.5 * pix, ux = P->ux, uy = P->uy, su = P->su;
        for (uint32_t x = qa; x < qb; x++) {
            double xc = ((double)x * pix - P->ox) + 0.5 * pix, cu = xc * ux + yc * uy, cv = xc * uy - yc * ux;
            double d0 = cv - P->a, d1 = P->b - cv;
            if (d0 <= -su || d1 <= -su) continue;
            if (cu >= P->uin0 && cu <= P->uin1)
                row[x - x0] += d0 < su || d1 < su ? strip_below(P, P->b - cv) - strip_below(P, P->a - cv) : 1.0;
            else
                row[x - x0] += piece_area(L, P, x, y);
        }
    } else if (P->kind == PIECE_SLAB) {
        /* the same for a dashed slab, with the dash test */
        const ls_band *B = &L->band[P->band];
        double pix = L->pixel, yc = ((double)y * pix - P->oy) + 0.5 * pix, ux = P->ux, uy = P->uy, su = P->su;
        for (uint32_t x = qa; x < qb; x++) {
            double xc = ((double)x * pix - P->ox) + 0.5 * pix, cu = xc * ux + yc * uy, cv = xc * uy - yc * ux;
            double d0 = cv - P->a, d1 = P->b - cv;
            if (d0 <= -su || d1 <= -su) continue;
            if (cu >= P->uin0 && cu <= P->uin1) {
                int on = dash_span(L, B, P->s0 + cu - B->phase, su);
                if (on == 0) continue;
                if (on > 0) {
                    row[x - x0] += d0 < su || d1 < su ? strip_below(P, P->b - cv) - strip_below(P, P->a - cv) : 1.0;
                    continue;
                }
            }
            row[x - x0] += piece_area(L, P, x, y);
        }
    } else {
        for (uint32_t x = qa; x < qb; x++) row[x - x0] += piece_area(L, P, x, y);
    }
}

/* Row y of dashed slab P over columns [lo, hi]: only the pixels that can
 * touch a dash (centre u within the square's extent of an on-interval), in
 * increasing column order, each once. */
static void dashed_row(const rs__linesym *L, const ls_ppc *P, uint32_t y, double lo, double hi, const ls_rows *R)
{
    const ls_band *B = &L->band[P->band];
    const double *d = L->dash + B->dash0;
    double pix = L->pixel, yc = ((double)y + 0.5) * pix - P->oy, m = P->su;
    /* the u range of the row's centres */
    double ua = (((lo + 0.5) * pix) - P->ox) * P->ux + yc * P->uy, ub = (((hi + 0.5) * pix) - P->ox) * P->ux + yc * P->uy;
    if (ua > ub) { double t = ua; ua = ub; ub = t; }
    double s_lo = P->s0 + ua - m - B->phase, s_hi = P->s0 + ub + m - B->phase;
    /* more periods than columns, or s too coarse for the period: every column */
    if (!((s_hi - s_lo) / B->period <= hi - lo + 1) || s_lo + B->period == s_lo) {
        cover_cols(L, P, y, lo, hi, R);
        return;
    }
    double done_lo = hi + 1, done_hi = lo - 1; /* columns covered so far (a run, growing at one end) */
    int asc = P->ux >= 0;
    for (double base = floor(s_lo / B->period) * B->period; base <= s_hi; base += B->period) {
        double on0 = base;
        for (uint32_t j = 0; j < B->ndash; j += 2) {
            double on1 = on0 + d[j];
            if (on1 + m >= s_lo && on0 - m <= s_hi && d[j] > 0) {
                double ca = lo, cb = hi, e = 1e-9 * (1 + fabs(on0) + fabs(P->s0));
                u_cols(P, yc, on0 + B->phase - P->s0 - m - e, on1 + B->phase - P->s0 + m + e, &ca, &cb);
                if (done_lo <= done_hi) { /* the pixels already visited lie before (asc) or after these */
                    if (asc && ca <= done_hi) ca = done_hi + 1;
                    if (!asc && cb >= done_lo) cb = done_lo - 1;
                }
                if (ca <= cb) {
                    cover_cols(L, P, y, ca, cb, R);
                    if (done_lo > done_hi) done_lo = ca, done_hi = cb;
                    else if (asc) done_hi = cb;
                    else done_lo = ca;
                }
            }
            on0 = on1 + d[j + 1];
        }
    }
}

static void visit(const rs__linesym *L, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h, double *scratch,
                  ls_emit emit, void *user, uint32_t only_band)
{
    if (!L || w == 0 || h == 0) return;
    uint32_t cx0 = px0 / L->cpx, cx1 = (px0 + w - 1) / L->cpx, cy0 = py0 / L->cpy, cy1 = (py0 + h - 1) / L->cpy;
    if (cx1 >= L->gw) cx1 = L->gw - 1;
    if (cy1 >= L->gh) cy1 = L->gh - 1;
    for (uint32_t cy = cy0; cy <= cy1 && cy < L->gh; cy++) {
        uint32_t ya0 = cy * L->cpy, yb0 = ya0 + L->cpy;
        if (ya0 < py0) ya0 = py0;
        if (yb0 > py0 + h) yb0 = py0 + h;
        /* (a cell larger than CELL_PX rows is walked CELL_PX rows at a time) */
        for (uint32_t ya = ya0; ya < yb0; ya += CELL_PX)
        for (uint32_t cx = cx0; cx <= cx1 && cx < L->gw; cx++) {
            uint32_t yb = yb0 - ya > CELL_PX ? ya + CELL_PX : yb0;
            uint32_t xa = cx * L->cpx, xb = xa + L->cpx;
            if (xa < px0) xa = px0;
            if (xb > px0 + w) xb = px0 + w;
            size_t c = (size_t)cy * L->gw + cx;
            uint32_t e0 = L->start[c], e1 = L->start[c + 1];
#if defined(__GNUC__)
            /* ask for the pieces this block of the cell will read, before reading them */
            for (uint32_t e = e0; e < e1; e++) {
                const ls_pbox *B = &L->ent[e];
                if (B->gy1 < (double)ya || B->gy0 >= (double)yb || B->gx1 < (double)xa || B->gx0 >= (double)xb) continue;
                const char *q = (const char *)&L->pp[B->id];
                __builtin_prefetch(q);
                __builtin_prefetch(q + 64);
                __builtin_prefetch(q + 128);
                __builtin_prefetch(q + sizeof(ls_ppc) - 1);
            }
#endif
            for (uint32_t e = e0; e < e1;) {
                const ls_pbox *PB = L->ent;
                uint32_t band = PB[e].band, f = e;
                while (f < e1 && PB[f].band == band) f++;
                if (only_band != UINT32_MAX && band != only_band) { e = f; continue; }
                /* the run's rows are the block's part of the cell: [xa, xb) x [ya, yb) */
                uint32_t rlo[CELL_PX], rhi[CELL_PX];
                ls_rows R = { xa, xb, ya, xb - xa, scratch, rlo, rhi };
                for (uint32_t r = 0; r < yb - ya; r++) rhi[r] = 0;
                for (uint32_t g = e; g < f; g++) {
                    const ls_pbox *Q = &PB[g];
                    if (Q->gy1 < (double)ya || Q->gy0 >= (double)yb || Q->gx1 < (double)xa || Q->gx0 >= (double)xb) continue;
                    uint32_t ry0 = Q->gy0 > (double)ya ? (uint32_t)Q->gy0 : ya;
                    uint32_t ry1 = Q->gy1 + 1 < (double)yb ? (uint32_t)(Q->gy1 + 1) : yb;
                    const ls_ppc *P = &L->pp[Q->id];
                    for (uint32_t y = ry0; y < ry1; y++) {
                        double lo = Q->gx0, hi = Q->gx1;
                        if (P->kind == PIECE_SLAB) {
                            slab_row(L, P, y, &lo, &hi);
                            if (lo > hi) continue;
                            if (P->dashed) {
                                /* cut to the block first: fewer dashes to walk */
                                if (lo < (double)xa) lo = (double)xa;
                                if (hi > (double)xb - 1) hi = (double)xb - 1;
                                if (lo <= hi) dashed_row(L, P, y, lo, hi, &R);
                                continue;
                            }
                        }
                        cover_cols(L, P, y, lo, hi, &R);
                    }
                }
                emit(L, band, xa, ya, yb, rlo, rhi, scratch, R.cs, user);
                e = f;
            }
        }
    }
}

typedef struct paint_ctx {
    uint32_t px0, py0, w;
    float *rgb;
    size_t stride;
} paint_ctx;

static void emit_paint(const rs__linesym *L, uint32_t band, uint32_t x0, uint32_t y0, uint32_t y1, const uint32_t *rlo,
                       const uint32_t *rhi, const double *cov, size_t cs, void *user)
{
    const paint_ctx *pc = user;
    const ls_band *B = &L->band[band];
    const float c0 = B->rgba[0], c1 = B->rgba[1], c2 = B->rgba[2];
    const double op = B->rgba[3];
    for (uint32_t y = y0; y < y1; y++) {
        if (rhi[y - y0] == 0) continue;
        /* the block's row and the run's, both from column x0 */
        float *r0 = pc->rgb + (size_t)(y - pc->py0) * pc->stride + (x0 - pc->px0), *r1 = r0 + pc->w, *r2 = r1 + pc->w;
        const double *cr = cov + (size_t)(y - y0) * cs;
        for (uint32_t i = rlo[y - y0]; i < rhi[y - y0]; i++) {
            double c = cr[i];
            if (!(c > 0)) continue;
            if (c > 1) c = 1;
            float a = (float)(c * op), k = 1.0f - a;
            r0[i] = r0[i] * k + c0 * a;
            r1[i] = r1[i] * k + c1 * a;
            r2[i] = r2[i] * k + c2 * a;
        }
    }
}

/* visit's runs are at most one cell block: at most CELL_PX rows of at most w columns */
size_t rs__linesym_scratch_len(uint32_t w)
{
    return (size_t)(w ? w : 1) * CELL_PX;
}

void rs__linesym_paint(const rs__linesym *L, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h, float *rgb,
                       size_t row_stride, double *scratch)
{
    paint_ctx pc = { px0, py0, w, rgb, row_stride };
    visit(L, px0, py0, w, h, scratch, emit_paint, &pc, UINT32_MAX);
}

typedef struct cov_ctx {
    uint32_t px0, py0;
    double *out;
    size_t stride;
} cov_ctx;

static void emit_cov(const rs__linesym *L, uint32_t band, uint32_t x0, uint32_t y0, uint32_t y1, const uint32_t *rlo,
                     const uint32_t *rhi, const double *cov, size_t cs, void *user)
{
    (void)L;
    (void)band;
    const cov_ctx *cc = user;
    for (uint32_t y = y0; y < y1; y++) {
        if (rhi[y - y0] == 0) continue;
        for (uint32_t x = x0 + rlo[y - y0]; x < x0 + rhi[y - y0]; x++) {
            double c = cov[(size_t)(y - y0) * cs + (x - x0)];
            cc->out[(size_t)(y - cc->py0) * cc->stride + (x - cc->px0)] = c > 1 ? 1 : c;
        }
    }
}

void rs__linesym_coverage(const rs__linesym *L, uint32_t band, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h,
                          double *out, size_t stride)
{
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) out[(size_t)y * stride + x] = 0;
    /* scratch: one cell at most */
    double scratch[CELL_PX * CELL_PX];
    if (!L || L->cpx > CELL_PX || L->cpy > CELL_PX) return;
    cov_ctx cc = { px0, py0, out, stride };
    visit(L, px0, py0, w, h, scratch, emit_cov, &cc, band);
}
