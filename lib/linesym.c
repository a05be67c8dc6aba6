/* Line symbols: convex band pieces, a pixel-cell index, exact per-pixel
 * areas (lib/linesym.h; docs/linesym.md). */
#include "linesym.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define HALF_SQRT2 0.70710678118654752440
/* Offsets and widths beyond this are refused: a style is about a road. */
#define BAND_MAX_EXTENT 1e4
/* Index cells: CELL_PX x CELL_PX pixels, grown until at most MAX_CELLS. */
#define CELL_PX 32u
#define MAX_CELLS ((uint64_t)1 << 22)
#define POLY_MAX 24
/* Half-planes per piece: 6 of its own, 3 per junction cut (two cuts). */
#define HP_MAX 12

enum { PIECE_SLAB = 0, PIECE_WEDGE = 1 };

/* One convex piece of one band, in its own frame: u along the segment
 * (unit vector (ux, uy)) from (ox, oy), v = left normal offset, so a
 * point's (u, v) = ((p-o).u, (p-o).(uy, -ux)). The piece is the set where
 * every half-plane c0 + cu u + cv v >= 0 holds; a wedge is further cut to
 * the annulus r0 <= |p-o| <= r1. */
typedef struct ls_piece {
    double ox, oy, ux, uy;
    double hp[HP_MAX][3];
    double hpm[HP_MAX];  /* pixel margin x |normal| of each half-plane (set by push_piece) */
    uint32_t nhp;
    uint32_t kind;
    uint32_t band;
    uint32_t dashed;     /* slab: cut by the band's dash pattern along u */
    double s0;           /* slab: s at u = 0 */
    double r0, r1;       /* wedge radii */
    double a, b;         /* slab: v range */
    double len;          /* slab: u range [0, len] of its box */
    double x0, y0, x1, y1; /* local box, grown by the pixel margin */
} ls_piece;

typedef struct ls_band {
    float rgba[4];
    uint32_t dash0, ndash; /* into L->dash */
    double period, phase;
} ls_band;

struct rs__linesym {
    double pixel, margin;
    rs__band_aa aa;
    uint32_t out_w, out_h;
    uint32_t cpx;          /* pixels per index cell side */
    uint32_t gw, gh;
    uint32_t *start, *ids; /* CSR: pieces per cell, ascending */
    ls_piece *pc;
    size_t npc, cap;
    ls_band *band;
    uint32_t nband;
    double *dash;
    size_t bytes;
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

/* Area of the pixel square (side pix, centred at v = 0 of slab P's frame)
 * where v <= x: a ramp, a plateau and a ramp along the normal. */
static double strip_below(const ls_piece *P, double pix, double x)
{
    double p1 = pix * fabs(P->ux), p2 = pix * fabs(P->uy), lo = fmin(p1, p2), hi = fmax(p1, p2);
    double e = 0.5 * (lo + hi), t = x + e, full = pix * pix;
    if (t <= 0) return 0;
    if (t >= 2 * e) return full;
    int flip = t > e;
    if (flip) t = 2 * e - t;
    double h = full / hi, a = t <= lo ? (lo > 0 ? 0.5 * t * t * h / lo : 0) : 0.5 * lo * h + (t - lo) * h;
    return flip ? full - a : a;
}

/* Area fraction of pixel (px, py) inside piece P (exact mode). */
static double piece_area(const rs__linesym *L, const ls_piece *P, uint32_t px, uint32_t py)
{
    double pix = L->pixel, x0 = (double)px * pix - P->ox, y0 = (double)py * pix - P->oy, x1 = x0 + pix,
           y1 = y0 + pix;
    double ux = P->ux, uy = P->uy;
    /* quick accept / reject on the centre, before any corner */
    double xc = x0 + 0.5 * pix, yc = y0 + 0.5 * pix, cu = xc * ux + yc * uy, cv = xc * uy - yc * ux;
    double hm = L->margin;
    int inside = 1, across = 1; /* across: only the v limits (slab half-planes 2, 3) cut the pixel */
    for (uint32_t k = 0; k < P->nhp; k++) {
        const double *h = P->hp[k];
        double d = h[0] + h[1] * cu + h[2] * cv;
        if (d < -P->hpm[k]) return 0;
        if (d < P->hpm[k]) {
            inside = 0;
            if (k != 2 && k != 3) across = 0;
        }
    }
    if (P->kind == PIECE_WEDGE && sqrt(cu * cu + cv * cv) - hm >= P->r1) return 0;
    if (P->kind == PIECE_SLAB && across) {
        /* the pixel crosses the band's edges only: the strip's area in
         * closed form (most line pixels), unless a dash end is in it */
        double on = 1;
        if (P->dashed) {
            const ls_band *B = &L->band[P->band];
            const double *d = L->dash + B->dash0;
            double eu = 0.5 * pix * (fabs(ux) + fabs(uy)), x = P->s0 + cu - B->phase;
            double m = x - floor(x / B->period) * B->period, acc = 0;
            on = -1;
            for (uint32_t j = 0; j < B->ndash; j++) {
                double lo = acc, hi = acc + d[j];
                if (m - eu >= lo && m + eu <= hi) { on = (j & 1) == 0; break; }
                acc = hi;
            }
        }
        if (on == 0) return 0;
        if (on > 0) return (strip_below(P, pix, P->b - cv) - strip_below(P, pix, P->a - cv)) / (pix * pix);
    }
    double bx[POLY_MAX], by[POLY_MAX], cx[POLY_MAX], cy[POLY_MAX];
    /* corners in (u, v) */
    const double X[4] = { x0, x1, x1, x0 }, Y[4] = { y0, y0, y1, y1 };
    for (int k = 0; k < 4; k++) {
        bx[k] = X[k] * ux + Y[k] * uy;
        by[k] = X[k] * uy - Y[k] * ux;
    }
    uint32_t n = 4;
    double *sx = bx, *sy = by, *tx = cx, *ty = cy;
    if (!inside) {
        for (uint32_t k = 0; k < P->nhp && n; k++) {
            n = clip_poly(sx, sy, n, P->hp[k][0], P->hp[k][1], P->hp[k][2], tx, ty);
            double *t;
            t = sx; sx = tx; tx = t;
            t = sy; sy = ty; ty = t;
        }
        if (n < 3) return 0;
    }
    double pa = pix * pix;
    if (P->kind == PIECE_WEDGE) {
        double far = sqrt(cu * cu + cv * cv);
        if (far - hm >= P->r1) return 0;
        double a1 = far + hm <= P->r1 ? poly_area(sx, sy, n) : poly_disc(sx, sy, n, P->r1);
        double a0 = P->r0 > 0 && far - hm < P->r0 ? (far + hm <= P->r0 ? poly_area(sx, sy, n) : poly_disc(sx, sy, n, P->r0))
                                                 : 0;
        return (a1 - a0) / pa;
    }
    if (!P->dashed) return inside ? 1.0 : poly_area(sx, sy, n) / pa;
    /* dashes: the on-intervals of s over the polygon's u range */
    const ls_band *B = &L->band[P->band];
    const double *d = L->dash + B->dash0;
    double umin = sx[0], umax = sx[0];
    for (uint32_t k = 1; k < n; k++) {
        umin = fmin(umin, sx[k]);
        umax = fmax(umax, sx[k]);
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
                    if (whole < 0) whole = inside ? pa : poly_area(sx, sy, n);
                    area += whole;
                } else {
                    double ex[POLY_MAX], ey[POLY_MAX], fx[POLY_MAX], fy[POLY_MAX];
                    uint32_t m = clip_poly(sx, sy, n, -lo, 1, 0, ex, ey);
                    m = clip_poly(ex, ey, m, hi, -1, 0, fx, fy);
                    if (m >= 3) area += poly_area(fx, fy, m);
                }
            }
            on0 = on1 + d[j + 1];
        }
        if (base + B->period == base) break; /* s too large for the period: stop */
    }
    return area / pa;
}

/* Hermite mode: smoothstep of the pixel centre's distance to each edge. */
static double piece_hermite(const rs__linesym *L, const ls_piece *P, uint32_t px, uint32_t py)
{
    double pix = L->pixel, x = ((double)px + 0.5) * pix - P->ox, y = ((double)py + 0.5) * pix - P->oy;
    double u = x * P->ux + y * P->uy, v = x * P->uy - y * P->ux;
    if (P->kind == PIECE_WEDGE) {
        /* the centre picks the piece; radial smoothing across the band */
        if (P->hp[0][1] * u + P->hp[0][2] * v < 0 || P->hp[1][1] * u + P->hp[1][2] * v < 0) return 0;
        double r = sqrt(u * u + v * v);
        double c = hermite(0.5 + (P->r1 - r) / pix) + (P->r0 > 0 ? hermite(0.5 + (r - P->r0) / pix) : 1.0) - 1.0;
        return c > 0 ? c : 0;
    }
    /* the other half-planes (ends, bisectors, junctions) by the centre */
    for (uint32_t k = 0; k < P->nhp; k++) {
        const double *h = P->hp[k];
        if (k == 2 || k == 3) continue; /* the v limits: smoothed below */
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

static rs_result push_piece(rs_ctx *ctx, rs__linesym *L, const ls_piece *P)
{
    if (L->npc == L->cap) {
        size_t nc = L->cap ? 2 * L->cap : 256, bytes;
        if (nc > UINT32_MAX || !rs__mul_size(nc, sizeof(ls_piece), &bytes)) return RS_ERR_LIMIT;
        ls_piece *np = rs__realloc(ctx, L->pc, bytes);
        if (!np) return RS_ERR_NOMEM;
        L->pc = np;
        L->cap = nc;
    }
    ls_piece *Q = &L->pc[L->npc++];
    *Q = *P;
    for (uint32_t k = 0; k < Q->nhp; k++) Q->hpm[k] = L->margin * sqrt(Q->hp[k][1] * Q->hp[k][1] + Q->hp[k][2] * Q->hp[k][2]);
    return RS_OK;
}

/* Local box of a piece's polygon outline, grown by the pixel margin. */
static void piece_box(const rs__linesym *L, ls_piece *P, double len, double a, double b)
{
    double m = L->margin;
    if (P->kind == PIECE_WEDGE) {
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
        /* inverse of (u, v) = (d.u, d.(uy, -ux)) */
        double x = P->ox + U[k] * P->ux + V[k] * P->uy, y = P->oy + U[k] * P->uy - V[k] * P->ux;
        P->x0 = fmin(P->x0, x);
        P->x1 = fmax(P->x1, x);
        P->y0 = fmin(P->y0, y);
        P->y1 = fmax(P->y1, y);
    }
}

typedef struct ls_vtx {
    double x, y;
} ls_vtx;

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
        *lo = fmax(*lo, t0);
        *hi = fmin(*hi, t1);
    }
    return *lo <= *hi;
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
    uint32_t road;
} ls_surf;

/* Road end points and the unit directions pointing away from them along
 * the road (to tell a road that continues another from one that meets it). */
typedef struct ls_ends {
    double x[2], y[2], dx[2], dy[2];
    int valid;
} ls_ends;

typedef struct ls_junc {
    ls_surf *sf;
    size_t nsf;
    uint32_t *start, *ids; /* CSR per index cell, like the pieces */
    uint32_t *stamp;       /* per surface: last query that saw it */
    uint32_t query;
    const ls_ends *ends;
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

/* Does piece P (its box cut by its half-planes) keep any area? */
static int piece_nonempty(const ls_piece *P)
{
    double x[POLY_MAX], y[POLY_MAX];
    uint32_t n = piece_poly(P, x, y);
    return n >= 3 && poly_area(x, y, n) > 1e-12;
}

static int add_hp(ls_piece *P, double c0, double cu, double cv)
{
    if (P->nhp >= HP_MAX) return 0;
    P->hp[P->nhp][0] = c0;
    P->hp[P->nhp][1] = cu;
    P->hp[P->nhp][2] = cv;
    P->nhp++;
    return 1;
}

/* P minus surface rectangle Q: up to 4 disjoint pieces into out; returns
 * their count, or -1 when Q misses P (P stays whole) or a piece would need
 * more half-planes than it holds (P is then kept whole: lines run on). */
static int cut_piece(const ls_piece *P, const ls_surf *Q, ls_piece *out)
{
    double ox = P->ox - Q->ax, oy = P->oy - Q->ay;
    double nqx = Q->uy, nqy = -Q->ux;      /* Q's left normal */
    double npx = P->uy, npy = -P->ux;      /* P's left normal */
    /* v' = cv0 + u fvu + v fvv, u' = cu0 + u fuu + v fuv in P's frame */
    double cv0 = ox * nqx + oy * nqy, fvu = P->ux * nqx + P->uy * nqy, fvv = npx * nqx + npy * nqy;
    double cu0 = ox * Q->ux + oy * Q->uy, fuu = P->ux * Q->ux + P->uy * Q->uy, fuv = npx * Q->ux + npy * Q->uy;
    double r = Q->r, hi = Q->len + r;
    double x[POLY_MAX], y[POLY_MAX];
    uint32_t n = piece_poly(P, x, y);
    if (n < 3) return -1;
    int out_v_hi = 1, out_v_lo = 1, out_u_lo = 1, out_u_hi = 1;
    for (uint32_t k = 0; k < n; k++) {
        double v = cv0 + x[k] * fvu + y[k] * fvv, u = cu0 + x[k] * fuu + y[k] * fuv;
        out_v_hi &= v >= r;
        out_v_lo &= v <= -r;
        out_u_lo &= u <= -r;
        out_u_hi &= u >= hi;
    }
    if (out_v_hi || out_v_lo || out_u_lo || out_u_hi) return -1;
    int m = 0;
    ls_piece A = *P;
    if (!add_hp(&A, cv0 - r, fvu, fvv)) return -1;                      /* v' >= r */
    if (piece_nonempty(&A)) out[m++] = A;
    A = *P;
    if (!add_hp(&A, -cv0 - r, -fvu, -fvv)) return -1;                   /* v' <= -r */
    if (piece_nonempty(&A)) out[m++] = A;
    for (int side = 0; side < 2; side++) {
        A = *P;
        if (!add_hp(&A, cv0 + r, fvu, fvv) || !add_hp(&A, r - cv0, -fvu, -fvv)) return -1;
        int ok = side == 0 ? add_hp(&A, -cu0 - r, -fuu, -fuv)            /* u' <= -r */
                           : add_hp(&A, cu0 - hi, fuu, fuv);             /* u' >= len + r */
        if (!ok) return -1;
        if (piece_nonempty(&A)) out[m++] = A;
    }
    return m;
}

static rs_result push_cut(rs_ctx *ctx, rs__linesym *L, ls_junc *J, const ls_piece *P, uint32_t road)
{
    if (!J || !J->nsf) return push_piece(ctx, L, P);
    /* candidate surfaces: those listed in the cells of P's box */
    double cm = (double)L->cpx * L->pixel;
    double fx0 = floor(P->x0 / cm), fx1 = floor(P->x1 / cm), fy0 = floor(P->y0 / cm), fy1 = floor(P->y1 / cm);
    enum { QMAX = 16 };
    ls_piece q[QMAX], tmp[4];
    uint32_t nq = 1;
    q[0] = *P;
    if (!(fx1 < 0 || fy1 < 0 || fx0 >= L->gw || fy0 >= L->gh)) {
        uint32_t i0 = fx0 < 0 ? 0 : (uint32_t)fx0, i1 = fx1 >= L->gw ? L->gw - 1 : (uint32_t)fx1;
        uint32_t j0 = fy0 < 0 ? 0 : (uint32_t)fy0, j1 = fy1 >= L->gh ? L->gh - 1 : (uint32_t)fy1;
        J->query++;
        for (uint32_t j = j0; j <= j1; j++)
            for (uint32_t i = i0; i <= i1; i++) {
                size_t c = (size_t)j * L->gw + i;
                for (uint32_t e = J->start[c]; e < J->start[c + 1]; e++) {
                    uint32_t k = J->ids[e];
                    if (J->stamp[k] == J->query) continue;
                    J->stamp[k] = J->query;
                    const ls_surf *Q = &J->sf[k];
                    if (Q->road == road || continues(J, road, Q->road)) continue;
                    /* cut every piece so far; a piece that cannot be cut stays */
                    uint32_t nn = 0;
                    ls_piece next[QMAX];
                    int full = 0;
                    for (uint32_t a = 0; a < nq; a++) {
                        int m = cut_piece(&q[a], Q, tmp);
                        if (m < 0) {
                            if (nn < QMAX) next[nn++] = q[a];
                            else full = 1;
                            continue;
                        }
                        if (nn + (uint32_t)m > QMAX) { full = 1; break; }
                        for (int b = 0; b < m; b++) next[nn++] = tmp[b];
                    }
                    if (full) continue; /* too many pieces: this surface does not cut */
                    memcpy(q, next, nn * sizeof *q);
                    nq = nn;
                }
            }
    }
    for (uint32_t a = 0; a < nq; a++) {
        rs_result r = push_piece(ctx, L, &q[a]);
        if (r) return r;
    }
    return RS_OK;
}

/* Pieces of one band along one road. pts: n distinct consecutive local
 * points, s: arc length at each. */
static rs_result road_band_pieces(rs_ctx *ctx, rs__linesym *L, ls_junc *J, uint32_t road, const ls_vtx *pts,
                                  const double *s, size_t n, const rs__band *bd, uint32_t band, double wmap,
                                  double hmap)
{
    double a = bd->t - 0.5 * bd->w, b = bd->t + 0.5 * bd->w, ext = fmax(fabs(a), fabs(b)) + L->margin;
    const ls_band *B = &L->band[band];
    for (size_t i = 0; i + 1 < n; i++) {
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
        double lo, hi;
        if (!cut_to_map(P.ox, P.oy, ux, uy, len, ext, wmap, hmap, &lo, &hi)) continue;
        P.hp[P.nhp][0] = 0, P.hp[P.nhp][1] = 1, P.hp[P.nhp++][2] = 0;          /* u >= 0 */
        P.hp[P.nhp][0] = len, P.hp[P.nhp][1] = -1, P.hp[P.nhp++][2] = 0;       /* u <= len */
        P.hp[P.nhp][0] = -a, P.hp[P.nhp][1] = 0, P.hp[P.nhp++][2] = 1;         /* v >= a */
        P.hp[P.nhp][0] = b, P.hp[P.nhp][1] = 0, P.hp[P.nhp++][2] = -1;         /* v <= b */
        if (i > 0) { /* bisector with the previous segment: m.(p - A) >= 0 */
            double pdx = 0.5 * pts[i].x - 0.5 * pts[i - 1].x, pdy = 0.5 * pts[i].y - 0.5 * pts[i - 1].y, pl = hypot(pdx, pdy);
            double mx = pdx / pl + ux, my = pdy / pl + uy, ml = hypot(mx, my);
            if (ml > 1e-9) {
                double mu, mv;
                in_frame(mx / ml, my / ml, ux, uy, &mu, &mv);
                P.hp[P.nhp][0] = 0, P.hp[P.nhp][1] = mu, P.hp[P.nhp++][2] = mv;
            }
        }
        if (i + 2 < n) { /* with the next: m.(p - B) <= 0 */
            double ndx = 0.5 * pts[i + 2].x - 0.5 * pts[i + 1].x, ndy = 0.5 * pts[i + 2].y - 0.5 * pts[i + 1].y,
                   nl = hypot(ndx, ndy);
            double mx = ndx / nl + ux, my = ndy / nl + uy, ml = hypot(mx, my);
            if (ml > 1e-9) {
                double mu, mv;
                in_frame(mx / ml, my / ml, ux, uy, &mu, &mv);
                P.hp[P.nhp][0] = mu * len, P.hp[P.nhp][1] = -mu, P.hp[P.nhp++][2] = -mv;
            }
        }
        if (lo > 0) {
            /* Re-anchor at the cut start (only u shifts; the half-planes
             * keep the exact piece). The cut-off parts lie more than a
             * pixel margin outside the map, so the box may leave them out. */
            P.ox += lo * ux;
            P.oy += lo * uy;
            P.s0 += lo;
            for (uint32_t k = 0; k < P.nhp; k++) P.hp[k][0] += P.hp[k][1] * lo;
        }
        P.len = hi - lo;
        piece_box(L, &P, P.len, a, b);
        rs_result r = push_cut(ctx, L, J, &P, road);
        if (r) return r;
    }
    /* Round joins: the outer side of each interior vertex. */
    for (size_t i = 1; i + 1 < n; i++) {
        double pdx = 0.5 * pts[i].x - 0.5 * pts[i - 1].x, pdy = 0.5 * pts[i].y - 0.5 * pts[i - 1].y, pl = hypot(pdx, pdy);
        double ndx = 0.5 * pts[i + 1].x - 0.5 * pts[i].x, ndy = 0.5 * pts[i + 1].y - 0.5 * pts[i].y, nl = hypot(ndx, ndy);
        double px = pdx / pl, py = pdy / pl, nx = ndx / nl, ny = ndy / nl;
        /* turn: next direction against the previous left normal (py, -px) */
        double turn = nx * py - ny * px;
        if (turn == 0) continue;
        double out = turn > 0 ? -1.0 : 1.0; /* left turn: outer side is the right (t < 0) */
        double r0 = out > 0 ? fmax(a, 0) : fmax(-b, 0), r1 = out > 0 ? b : -a;
        if (!(r1 > r0)) continue;
        if (B->ndash && !dash_on(L, B, s[i])) continue;
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
        P.nhp = 2;
        piece_box(L, &P, 0, 0, 0);
        rs_result r = push_cut(ctx, L, J, &P, road);
        if (r) return r;
    }
    return RS_OK;
}

/* Index cells reached by the rectangle u in [u0, u1], v in [v0, v1] of the
 * frame (ox, oy, ux, uy) inside the local box [x0, x1] x [y0, y1] (per cell
 * row, the x extent of the rectangle cut to that row); pass 0 counts into
 * start[], pass 1 fills ids[] from the ends, item k. */
static void rect_cells(const rs__linesym *L, double ox, double oy, double ux, double uy, double u0, double u1,
                       double v0, double v1, double x0, double y0, double x1, double y1, uint32_t *start,
                       uint32_t *ids, uint32_t k, int fill)
{
    double cm = (double)L->cpx * L->pixel;
    double fy0 = floor(y0 / cm), fy1 = floor(y1 / cm);
    if (!(fy1 >= 0) || !(fy0 < L->gh)) return;
    uint32_t j0 = fy0 < 0 ? 0 : (uint32_t)fy0, j1 = fy1 >= L->gh ? L->gh - 1 : (uint32_t)fy1;
    double fx0 = floor(x0 / cm), fx1 = floor(x1 / cm);
    if (!(fx1 >= 0) || !(fx0 < L->gw)) return;
    uint32_t i0 = fx0 < 0 ? 0 : (uint32_t)fx0, i1 = fx1 >= L->gw ? L->gw - 1 : (uint32_t)fx1;
    for (uint32_t j = j0; j <= j1; j++) {
        uint32_t a = i0, b = i1;
        if (i1 > i0) {
            double U[4] = { u0, u1, u1, u0 }, V[4] = { v0, v0, v1, v1 };
            double xs[POLY_MAX], ys[POLY_MAX], tx[POLY_MAX], ty[POLY_MAX];
            for (int q = 0; q < 4; q++) {
                xs[q] = ox + U[q] * ux + V[q] * uy;
                ys[q] = oy + U[q] * uy - V[q] * ux;
            }
            uint32_t nn = clip_poly(xs, ys, 4, -(double)j * cm, 0, 1, tx, ty);
            nn = clip_poly(tx, ty, nn, (double)(j + 1) * cm, 0, -1, xs, ys);
            if (nn == 0) continue;
            double lo = xs[0], hi = xs[0];
            for (uint32_t q = 1; q < nn; q++) {
                lo = fmin(lo, xs[q]);
                hi = fmax(hi, xs[q]);
            }
            double ga = floor(lo / cm), gb = floor(hi / cm);
            if (gb < (double)i0 || ga > (double)i1) continue;
            a = ga > (double)i0 ? (uint32_t)ga : i0;
            b = gb < (double)i1 ? (uint32_t)gb : i1;
        }
        for (uint32_t i = a; i <= b; i++) {
            size_t c = (size_t)j * L->gw + i;
            if (fill) ids[--start[c]] = k;
            else start[c]++;
        }
    }
}

static void piece_cells(rs__linesym *L, uint32_t k, int fill)
{
    const ls_piece *P = &L->pc[k];
    double m = L->margin;
    if (P->kind == PIECE_SLAB)
        rect_cells(L, P->ox, P->oy, P->ux, P->uy, -m, P->len + m, P->a - m, P->b + m, P->x0, P->y0, P->x1, P->y1,
                   L->start, L->ids, k, fill);
    else /* the sector's box, as an axis-aligned rectangle */
        rect_cells(L, P->ox, P->oy, 1, 0, P->x0 - P->ox, P->x1 - P->ox, P->oy - P->y1, P->oy - P->y0, P->x0, P->y0,
                   P->x1, P->y1, L->start, L->ids, k, fill);
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

/* One road in local coordinates: distinct consecutive points and their arc
 * lengths (summed as lib/roadfield.c sums them). */
static rs_result road_local(rs_ctx *ctx, const rs_roads *roads, size_t ri, const rs__linesym_params *p,
                            double per_unit, ls_vtx **pts, double **sv, size_t *cap, size_t *m_out)
{
    const double *xy = NULL;
    size_t n = 0;
    rs_roads_get(roads, ri, NULL, NULL, &xy, &n);
    if (n > *cap) {
        size_t b1, b2;
        if (!rs__mul_size(n, sizeof **pts, &b1) || !rs__mul_size(n, sizeof **sv, &b2)) return RS_ERR_LIMIT;
        ls_vtx *np = rs__realloc(ctx, *pts, b1);
        if (!np) return RS_ERR_NOMEM;
        *pts = np;
        double *ns = rs__realloc(ctx, *sv, b2);
        if (!ns) return RS_ERR_NOMEM;
        *sv = ns;
        *cap = n;
    }
    size_t m = 0;
    double s = 0;
    for (size_t k = 0; k < n; k++) {
        double x = rs__local_coord(xy[2 * k], p->origin_x, per_unit), y = rs__local_coord(xy[2 * k + 1], p->origin_y, per_unit);
        if (m > 0) {
            if (x == (*pts)[m - 1].x && y == (*pts)[m - 1].y) continue;
            s += 2 * hypot(0.5 * x - 0.5 * (*pts)[m - 1].x, 0.5 * y - 0.5 * (*pts)[m - 1].y);
            if (!(s <= DBL_MAX)) s = DBL_MAX;
        }
        (*pts)[m].x = x;
        (*pts)[m].y = y;
        (*sv)[m] = s;
        m++;
    }
    *m_out = m;
    return RS_OK;
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
    memset(J, 0, sizeof *J);
}

/* Surfaces of every road with a width, their index, and the road ends. */
static rs_result junc_build(rs_ctx *ctx, rs__linesym *L, const rs_roads *roads, const rs__linesym_params *p,
                            ls_junc *J, ls_vtx **pts, double **sv, size_t *cap)
{
    size_t nroads = rs_roads_count(roads), ncap = 0;
    double per_unit = rs__local_quantum(p->cell_size);
    double wmap = (double)p->out_w * p->pixel, hmap = (double)p->out_h * p->pixel;
    ls_ends *ends = rs__calloc(ctx, nroads ? nroads : 1, sizeof *ends);
    J->ends = ends;
    if (!ends) return RS_ERR_NOMEM;
    for (size_t ri = 0; ri < nroads; ri++) {
        double w = 0;
        size_t m = 0;
        rs_roads_get(roads, ri, NULL, &w, NULL, NULL);
        rs_result r = road_local(ctx, roads, ri, p, per_unit, pts, sv, cap, &m);
        if (r) return r;
        if (m < 2) continue;
        const ls_vtx *v = *pts;
        ends[ri].valid = 1;
        ends[ri].x[0] = v[0].x, ends[ri].y[0] = v[0].y;
        ends[ri].x[1] = v[m - 1].x, ends[ri].y[1] = v[m - 1].y;
        unit_dir(v[0].x, v[0].y, v[1].x, v[1].y, &ends[ri].dx[0], &ends[ri].dy[0]);
        unit_dir(v[m - 1].x, v[m - 1].y, v[m - 2].x, v[m - 2].y, &ends[ri].dx[1], &ends[ri].dy[1]);
        double hw = 0.5 * w;
        if (!(hw > 0) || !(hw <= BAND_MAX_EXTENT)) continue; /* no surface to stop at */
        for (size_t i = 0; i + 1 < m; i++) {
            ls_surf Q;
            unit_dir(v[i].x, v[i].y, v[i + 1].x, v[i + 1].y, &Q.ux, &Q.uy);
            double len = 2 * hypot(0.5 * v[i + 1].x - 0.5 * v[i].x, 0.5 * v[i + 1].y - 0.5 * v[i].y), lo, hi;
            if (!cut_to_map(v[i].x, v[i].y, Q.ux, Q.uy, len, 2 * hw + L->margin, wmap, hmap, &lo, &hi)) continue;
            Q.ax = v[i].x + lo * Q.ux;
            Q.ay = v[i].y + lo * Q.uy;
            Q.len = hi - lo;
            Q.r = hw;
            Q.road = (uint32_t)ri;
            if (J->nsf == ncap) {
                size_t nc = ncap ? 2 * ncap : 256, bytes;
                if (nc > UINT32_MAX || !rs__mul_size(nc, sizeof *J->sf, &bytes)) return RS_ERR_LIMIT;
                ls_surf *ns = rs__realloc(ctx, J->sf, bytes);
                if (!ns) return RS_ERR_NOMEM;
                J->sf = ns;
                ncap = nc;
            }
            J->sf[J->nsf++] = Q;
        }
    }
    size_t ncell = (size_t)L->gw * L->gh, total = 0;
    J->start = rs__calloc(ctx, ncell + 1, sizeof *J->start);
    J->stamp = rs__calloc(ctx, J->nsf ? J->nsf : 1, sizeof *J->stamp);
    if (!J->start || !J->stamp) return RS_ERR_NOMEM;
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 1) {
            uint64_t lim = UINT32_MAX - 1u;
            if (ctx->limits.max_road_cells && ctx->limits.max_road_cells < lim) lim = ctx->limits.max_road_cells;
            if (!csr_close(J->start, ncell, lim, &total)) return RS_ERR_LIMIT;
            J->ids = rs__alloc_array(ctx, total ? total : 1, sizeof *J->ids);
            if (!J->ids) return RS_ERR_NOMEM;
        }
        for (size_t k = pass ? J->nsf : 0; pass ? k-- > 0 : k < J->nsf; k += pass ? 0 : 1) {
            const ls_surf *Q = &J->sf[k];
            double x0 = DBL_MAX, y0 = DBL_MAX, x1 = -DBL_MAX, y1 = -DBL_MAX;
            const double U[4] = { -Q->r, Q->len + Q->r, Q->len + Q->r, -Q->r }, V[4] = { -Q->r, -Q->r, Q->r, Q->r };
            for (int c = 0; c < 4; c++) {
                double x = Q->ax + U[c] * Q->ux + V[c] * Q->uy, y = Q->ay + U[c] * Q->uy - V[c] * Q->ux;
                x0 = fmin(x0, x), x1 = fmax(x1, x), y0 = fmin(y0, y), y1 = fmax(y1, y);
            }
            rect_cells(L, Q->ax, Q->ay, Q->ux, Q->uy, -Q->r, Q->len + Q->r, -Q->r, Q->r, x0, y0, x1, y1, J->start,
                       J->ids, (uint32_t)k, pass);
        }
    }
    return RS_OK;
}

void rs__linesym_free(rs_ctx *ctx, rs__linesym *L)
{
    if (!L) return;
    rs__free(ctx, L->start);
    rs__free(ctx, L->ids);
    rs__free(ctx, L->pc);
    rs__free(ctx, L->band);
    rs__free(ctx, L->dash);
    rs__free(ctx, L);
}

size_t rs__linesym_bytes(const rs__linesym *L) { return L ? L->bytes : 0; }

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
    L->margin = p->pixel * HALF_SQRT2;
    L->aa = p->aa;
    L->out_w = p->out_w;
    L->out_h = p->out_h;
    L->cpx = CELL_PX;
    for (;;) {
        uint64_t gw = ((uint64_t)p->out_w + L->cpx - 1) / L->cpx, gh = ((uint64_t)p->out_h + L->cpx - 1) / L->cpx;
        if (gw * gh <= MAX_CELLS || L->cpx >= (1u << 30)) {
            L->gw = (uint32_t)gw;
            L->gh = (uint32_t)gh;
            break;
        }
        L->cpx *= 2;
    }
    L->band = rs__alloc_array(ctx, nband ? nband : 1, sizeof *L->band);
    L->dash = rs__alloc_array(ctx, ndash ? ndash : 1, sizeof *L->dash);
    size_t ncell = (size_t)L->gw * L->gh;
    L->start = rs__calloc(ctx, ncell + 1, sizeof *L->start);
    ls_vtx *pts = NULL;
    double *sv = NULL;
    ls_junc J;
    memset(&J, 0, sizeof J);
    if (!L->band || !L->dash || !L->start) { res = RS_ERR_NOMEM; goto fail; }
    L->nband = nband;
    for (uint32_t k = 0, d0 = 0; k < nband; k++) {
        ls_band *B = &L->band[k];
        memcpy(B->rgba, bands[k].rgba, sizeof B->rgba);
        B->dash0 = d0;
        B->ndash = bands[k].ndash;
        B->phase = bands[k].phase;
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
    if (nband && (res = junc_build(ctx, L, roads, p, &J, &pts, &sv, &cap)) != RS_OK) goto fail;
    for (size_t ri = 0; ri < nroads; ri++) {
        if (band_start[ri + 1] == band_start[ri]) continue;
        size_t m = 0;
        if ((res = road_local(ctx, roads, ri, p, per_unit, &pts, &sv, &cap, &m)) != RS_OK) goto fail;
        if (m < 2) continue;
        for (uint32_t k = band_start[ri]; k < band_start[ri + 1]; k++)
            if ((res = road_band_pieces(ctx, L, &J, (uint32_t)ri, pts, sv, m, &bands[k], k, wmap, hmap)) != RS_OK)
                goto fail;
    }
    rs__free(ctx, pts);
    rs__free(ctx, sv);
    junc_free(ctx, &J);
    pts = NULL;
    sv = NULL;
    for (size_t k = 0; k < L->npc; k++) piece_cells(L, (uint32_t)k, 0);
    uint64_t lim = UINT32_MAX - 1u;
    if (ctx->limits.max_road_cells && ctx->limits.max_road_cells < lim) lim = ctx->limits.max_road_cells;
    if (!csr_close(L->start, ncell, lim, &total)) { res = RS_ERR_LIMIT; goto fail; }
    L->ids = rs__alloc_array(ctx, total ? total : 1, sizeof *L->ids);
    if (!L->ids) { res = RS_ERR_NOMEM; goto fail; }
    for (size_t k = L->npc; k-- > 0;) piece_cells(L, (uint32_t)k, 1);
    L->bytes = sizeof *L + (ncell + 1) * sizeof *L->start + total * sizeof *L->ids + L->cap * sizeof *L->pc +
               nband * sizeof *L->band + ndash * sizeof *L->dash;
    *out = L;
    rs__ok(ctx);
    return RS_OK;
fail:
    rs__free(ctx, pts);
    rs__free(ctx, sv);
    junc_free(ctx, &J);
    rs__linesym_free(ctx, L);
    if (res == RS_ERR_NOMEM) return rs__fail(ctx, res, "line symbols: out of memory");
    return rs__fail(ctx, res, "line symbols: too many pieces or index entries");
}

/* ------------------------------------------------------------------------
 * Painting
 * ---------------------------------------------------------------------- */

static double piece_cover(const rs__linesym *L, const ls_piece *P, uint32_t px, uint32_t py)
{
    return L->aa == RS__AA_HERMITE ? piece_hermite(L, P, px, py) : piece_area(L, P, px, py);
}

/* Pixel columns [*lo, *hi] of row y whose centres lie in slab P's rectangle
 * grown by the pixel margin (every pixel that can touch P; a superset is
 * harmless, piece_cover gives 0 outside). Narrows *lo, *hi. */
static void slab_row(const rs__linesym *L, const ls_piece *P, uint32_t y, double *lo, double *hi)
{
    double pix = L->pixel, m = L->margin, yc = ((double)y + 0.5) * pix - P->oy;
    /* u = xr ux + yc uy in [-m, len + m]; v = xr uy - yc ux in [a - m, b + m]; xr = x - ox */
    double k[2] = { P->ux, P->uy }, c[2] = { yc * P->uy, -yc * P->ux };
    double l[2] = { -m, P->a - m }, h[2] = { P->len + m, P->b + m };
    double xlo = -DBL_MAX, xhi = DBL_MAX;
    for (int i = 0; i < 2; i++) {
        if (fabs(k[i]) < 1e-12) {
            if (c[i] < l[i] - 1e-9 || c[i] > h[i] + 1e-9) { *hi = *lo - 1; return; }
            continue;
        }
        double t0 = (l[i] - c[i]) / k[i], t1 = (h[i] - c[i]) / k[i];
        if (t0 > t1) { double t = t0; t0 = t1; t1 = t; }
        xlo = fmax(xlo, t0);
        xhi = fmin(xhi, t1);
    }
    /* pixel centres (x + 0.5) pix = xr + ox, with a little slack for rounding */
    double plo = ceil((xlo + P->ox) / pix - 0.5 - 1e-6), phi = floor((xhi + P->ox) / pix - 0.5 + 1e-6);
    if (plo > *lo) *lo = plo;
    if (phi < *hi) *hi = phi;
}

/* Visit the block cell by cell; per cell, each run of pieces of one band:
 * sum their covers into scratch, then hand the run to `emit`. Each pixel
 * belongs to the one cell that holds it, whose list is in painting order,
 * so a pixel sees the same sums in the same order in every block. */
typedef void (*ls_emit)(const rs__linesym *L, uint32_t band, uint32_t x0, uint32_t x1, uint32_t y0, uint32_t y1,
                        const double *cov, size_t cstride, void *user);

static void visit(const rs__linesym *L, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h, double *scratch,
                  ls_emit emit, void *user, uint32_t only_band)
{
    if (!L || w == 0 || h == 0) return;
    uint32_t cx0 = px0 / L->cpx, cx1 = (px0 + w - 1) / L->cpx, cy0 = py0 / L->cpx, cy1 = (py0 + h - 1) / L->cpx;
    if (cx1 >= L->gw) cx1 = L->gw - 1;
    if (cy1 >= L->gh) cy1 = L->gh - 1;
    for (uint32_t cy = cy0; cy <= cy1 && cy < L->gh; cy++) {
        uint32_t ya = cy * L->cpx, yb = ya + L->cpx;
        if (ya < py0) ya = py0;
        if (yb > py0 + h) yb = py0 + h;
        for (uint32_t cx = cx0; cx <= cx1 && cx < L->gw; cx++) {
            uint32_t xa = cx * L->cpx, xb = xa + L->cpx;
            if (xa < px0) xa = px0;
            if (xb > px0 + w) xb = px0 + w;
            size_t c = (size_t)cy * L->gw + cx;
            uint32_t e0 = L->start[c], e1 = L->start[c + 1];
            for (uint32_t e = e0; e < e1;) {
                uint32_t band = L->pc[L->ids[e]].band, f = e;
                while (f < e1 && L->pc[L->ids[f]].band == band) f++;
                if (only_band != UINT32_MAX && band != only_band) { e = f; continue; }
                /* the run's pixel box */
                double pix = L->pixel;
                double bx0 = DBL_MAX, bx1 = -DBL_MAX, by0 = DBL_MAX, by1 = -DBL_MAX;
                for (uint32_t g = e; g < f; g++) {
                    const ls_piece *P = &L->pc[L->ids[g]];
                    bx0 = fmin(bx0, P->x0), bx1 = fmax(bx1, P->x1), by0 = fmin(by0, P->y0), by1 = fmax(by1, P->y1);
                }
                /* pixels whose centre lies in the grown box (the margin already holds the half diagonal) */
                double fx0 = ceil(bx0 / pix - 0.5), fx1 = floor(bx1 / pix - 0.5), fy0 = ceil(by0 / pix - 0.5),
                       fy1 = floor(by1 / pix - 0.5);
                uint32_t x0 = fx0 > (double)xa ? (fx0 < (double)xb ? (uint32_t)fx0 : xb) : xa;
                uint32_t x1 = fx1 + 1 < (double)xb ? (fx1 + 1 > (double)x0 ? (uint32_t)(fx1 + 1) : x0) : xb;
                uint32_t y0 = fy0 > (double)ya ? (fy0 < (double)yb ? (uint32_t)fy0 : yb) : ya;
                uint32_t y1 = fy1 + 1 < (double)yb ? (fy1 + 1 > (double)y0 ? (uint32_t)(fy1 + 1) : y0) : yb;
                if (x0 >= x1 || y0 >= y1) { e = f; continue; }
                size_t cs = x1 - x0;
                for (size_t q = 0; q < cs * (y1 - y0); q++) scratch[q] = 0;
                for (uint32_t g = e; g < f; g++) {
                    const ls_piece *P = &L->pc[L->ids[g]];
                    double gx0 = ceil(P->x0 / pix - 0.5), gx1 = floor(P->x1 / pix - 0.5), gy0 = ceil(P->y0 / pix - 0.5),
                           gy1 = floor(P->y1 / pix - 0.5);
                    for (uint32_t y = y0; y < y1; y++) {
                        if ((double)y < gy0 || (double)y > gy1) continue;
                        double lo = gx0, hi = gx1;
                        if (P->kind == PIECE_SLAB) slab_row(L, P, y, &lo, &hi);
                        uint32_t qa = lo > (double)x0 ? (lo < (double)x1 ? (uint32_t)lo : x1) : x0;
                        uint32_t qb = hi + 1 < (double)x1 ? (hi + 1 > (double)qa ? (uint32_t)(hi + 1) : qa) : x1;
                        for (uint32_t x = qa; x < qb; x++) scratch[(y - y0) * cs + (x - x0)] += piece_cover(L, P, x, y);
                    }
                }
                emit(L, band, x0, x1, y0, y1, scratch, cs, user);
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

static void emit_paint(const rs__linesym *L, uint32_t band, uint32_t x0, uint32_t x1, uint32_t y0, uint32_t y1,
                       const double *cov, size_t cs, void *user)
{
    const paint_ctx *pc = user;
    const ls_band *B = &L->band[band];
    for (uint32_t y = y0; y < y1; y++) {
        float *row = pc->rgb + (size_t)(y - pc->py0) * pc->stride;
        for (uint32_t x = x0; x < x1; x++) {
            double c = cov[(size_t)(y - y0) * cs + (x - x0)];
            if (!(c > 0)) continue;
            if (c > 1) c = 1;
            float a = (float)(c * B->rgba[3]);
            size_t i = x - pc->px0;
            for (int k = 0; k < 3; k++) {
                float *v = row + (size_t)k * pc->w + i;
                *v = *v * (1.0f - a) + B->rgba[k] * a;
            }
        }
    }
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

static void emit_cov(const rs__linesym *L, uint32_t band, uint32_t x0, uint32_t x1, uint32_t y0, uint32_t y1,
                     const double *cov, size_t cs, void *user)
{
    (void)L;
    (void)band;
    const cov_ctx *cc = user;
    for (uint32_t y = y0; y < y1; y++)
        for (uint32_t x = x0; x < x1; x++) {
            double c = cov[(size_t)(y - y0) * cs + (x - x0)];
            cc->out[(size_t)(y - cc->py0) * cc->stride + (x - cc->px0)] = c > 1 ? 1 : c;
        }
}

void rs__linesym_coverage(const rs__linesym *L, uint32_t band, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h,
                          double *out, size_t stride)
{
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) out[(size_t)y * stride + x] = 0;
    /* scratch: one cell at most */
    double scratch[CELL_PX * CELL_PX];
    if (!L || L->cpx > CELL_PX) return;
    cov_ctx cc = { px0, py0, out, stride };
    visit(L, px0, py0, w, h, scratch, emit_cov, &cc, band);
}
