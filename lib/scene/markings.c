/* Road markings (issue 14, docs/markings.md): sprites of the atlas placed
 * in road coordinates and drawn per pixel through a grid index over their
 * extents, after seed 001 (atlas + per-marking parametric record, one pass
 * for all markings, c = (1 - a) c1 + a c2) but with the marking bent along
 * its road instead of a rigid box, and the sprite's exact mean over the
 * pixel's footprint from a summed-area table (issue 25). */
#include "markings.h"
#include "lanes.h"
#include "splatter.h"
#include "network.h"
#include "roadfield.h"

#include <float.h>
#include <limits.h>
#include <stdio.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define MAX_INDEX_ENTRIES (1u << 26)
#define MAX_INDEX_CELLS (1u << 22)

static rs_result pre_build(rs_ctx *ctx, rs__markings *mk);

rs_result rs__placement_push(rs_ctx *ctx, rs__placement **pl, size_t *n, size_t *cap, const rs__placement *p)
{
    if (*n == *cap) {
        size_t nc = *cap ? 2 * *cap : 64;
        rs__placement *q = rs__realloc(ctx, *pl, nc * sizeof *q);
        if (!q) return RS_ERR_NOMEM;
        *pl = q;
        *cap = nc;
    }
    (*pl)[(*n)++] = *p;
    return RS_OK;
}

rs_result rs__markings_explicit(rs_ctx *ctx, const rs_roads *roads, const rs_atlas *atlas, rs__placement **pl,
                                size_t *npl, size_t *cap)
{
    size_t nexp = rs_roads_mark_count(roads);
    for (size_t i = 0; i < nexp; i++) {
        rs_mark m;
        rs_roads_get_mark(roads, i, &m);
        long ti = rs_atlas_find(atlas, m.type);
        if (ti < 0) {
            char where[48];
            if (m.line) snprintf(where, sizeof where, "line %llu: ", (unsigned long long)m.line);
            else snprintf(where, sizeof where, "mark %zu: ", i);
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "%smark: the atlas has no type '%s'", where, m.type);
        }
        rs__placement p;
        memset(&p, 0, sizeof p);
        p.type = (uint32_t)ti;
        p.road = m.road;
        p.s = m.s;
        p.t = m.t;
        p.length = m.length > 0 ? m.length : atlas->t[ti].length;
        p.width = m.width > 0 ? m.width : atlas->t[ti].width;
        p.flip = m.flip;
        p.line = m.line;
        if (rs__placement_push(ctx, pl, npl, cap, &p)) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
    }
    return RS_OK;
}

void rs__markings_free(rs_ctx *ctx, rs__markings *mk)
{
    if (!mk) return;
    for (size_t i = 0; mk->tex && i < mk->ntex; i++) {
        rs__free(ctx, mk->tex[i].sat);
        rs__free(ctx, mk->tex[i].isat);
    }
    rs__free(ctx, mk->tex);
    rs_atlas_free(ctx, mk->atlas_own);
    rs__free(ctx, mk->m);
    rs__free(ctx, mk->at);
    rs__free(ctx, mk->pts);
    rs__free(ctx, mk->parts);
    rs__free(ctx, mk->fps);
    rs__free(ctx, mk->pre);
    rs__free(ctx, mk->start);
    rs__free(ctx, mk->list);
    rs__free(ctx, mk->pl);
    rs__free(ctx, mk->lv);
    rs__free(ctx, mk->lv_stroke);
    rs__roadfield_free(ctx, mk->lv_own);
    rs__free(ctx, mk);
}

/* The paint-time table of a type (rs__mk_tex): its level-0 texels'
 * summed-area table, alpha only when every texel's colour is the same. */
static rs_result build_tex(rs_ctx *ctx, const rs__atlas_type *ty, rs__mk_tex *tx, size_t *bytes)
{
    const rs__atlas_level *L = &ty->lev[0];
    const uint32_t w = L->w, h = L->h;
    const size_t n = (size_t)w * h, w1 = (size_t)w + 1, h1 = (size_t)h + 1;
    /* one colour: every texel's premultiplied colour is that 8-bit colour
     * times its alpha, as lib/input/atlas.c computed it */
    int uniform = 1, have = 0;
    float col[3] = { 0, 0, 0 };
    tx->ax0 = tx->ay0 = INT32_MAX;
    tx->ax1 = tx->ay1 = INT32_MIN;
    for (size_t k = 0; k < n; k++) {
        const float *q = L->px + 4 * k;
        if (!(q[3] > 0)) continue;
        int32_t i = (int32_t)(k % w), j = (int32_t)(k / w);
        if (i < tx->ax0) tx->ax0 = i;
        if (i > tx->ax1) tx->ax1 = i;
        if (j < tx->ay0) tx->ay0 = j;
        if (j > tx->ay1) tx->ay1 = j;
        for (int c = 0; c < 3; c++) {
            if (!have) col[c] = (float)floor(q[c] / q[3] + 0.5);
            if (q[c] != col[c] * q[3]) uniform = 0;
        }
        have = 1;
    }
    tx->nch = uniform ? 1 : 4;
    memcpy(tx->col, col, sizeof col);
    /* alpha only: 255 a is a whole number (the image's 8 bits); the sums
     * stay below 2^31 for up to 8 M texels */
    if (uniform && n > ((size_t)1 << 23)) tx->nch = 4;
    double *S = rs__alloc_array(ctx, w1 * h1, sizeof *S);
    if (tx->nch == 1) tx->isat = rs__alloc_array(ctx, (w1 + 1) * (h1 + 1), sizeof(double));
    else tx->sat = rs__alloc_array(ctx, 4 * w1 * h1, 4 * sizeof(double));
    if (!S || (!tx->isat && !tx->sat)) {
        rs__free(ctx, S);
        return RS_ERR_NOMEM;
    }
    *bytes += tx->nch == 1 ? (w1 + 1) * (h1 + 1) * sizeof(double) : 4 * w1 * h1 * 4 * sizeof(double);
    for (uint32_t c = 0; c < tx->nch; c++) {
        const int ch = tx->nch == 1 ? 3 : (int)c;
        for (size_t i = 0; i < w1; i++) S[i] = 0;
        for (size_t j = 0; j < h; j++) {
            double row = 0;
            S[(j + 1) * w1] = 0;
            for (size_t i = 0; i < w; i++) {
                double x = L->px[(j * w + i) * 4 + (size_t)ch];
                row += tx->nch == 1 ? floor(x * 255 + 0.5) : x;
                S[(j + 1) * w1 + i + 1] = S[j * w1 + i + 1] + row;
            }
        }
        if (tx->nch == 1) {
            for (size_t j = 0; j <= h1; j++)
                for (size_t i = 0; i <= w1; i++)
                    tx->isat[j * (w1 + 1) + i] = S[(j < h1 ? j : h) * w1 + (i < w1 ? i : w)];
            continue;
        }
        for (size_t j = 0; j < h1; j++)
            for (size_t i = 0; i < w1; i++) {
                size_t i1 = i < w ? i + 1 : i, j1 = j < h ? j + 1 : j;
                double s00 = S[j * w1 + i], s01 = S[j * w1 + i1], s10 = S[j1 * w1 + i], s11 = S[j1 * w1 + i1];
                double e[4] = { s00, s01 - s00, s10 - s00, s11 - s10 - s01 + s00 };
                memcpy(tx->sat + (c * w1 * h1 + j * w1 + i) * 4, e, sizeof e);
            }
    }
    rs__free(ctx, S);
    tx->w = w;
    tx->h = h;
    return RS_OK;
}

/* Parts per parallelogram edge: enough that a sprite edge crossing one
 * part's slanted end costs at most FP_EPS of the pixel's coverage (the
 * triangle between the slant and the step, h^2 |slope| / 8 of area for a
 * part of height h), at most RS__MK_STEPS / 2 = 3 (issue 25 target 2:
 * 1.6 % and 2 parts left a mean error of 0.0229 at 1.25 m pixels, where
 * every pixel of a small sprite holds several of its edges; 1.25 % and 3
 * parts: 0.0151 over angles 0.7 degrees apart; docs/markings.md). */
#define FP_EPS 0.0125

/* The footprint of a pixel whose steps in x and y move the texel
 * coordinates by (e1u, e1v) and (e2u, e2v) (rs__mk_fp). */
static void footprint(double e1u, double e1v, double e2u, double e2v, rs__mk_fp *fp)
{
    double A = fabs(e1u * e2v - e1v * e2u);
    fp->n = 0;
    fp->ia = 0;
    if (!(A > 0)) return;
    /* both steps pointing to +V; the bottom vertex, then the left path to
     * the top one: along a then b (a, b: the two steps in some order) */
    if (e1v < 0) e1u = -e1u, e1v = -e1v;
    if (e2v < 0) e2u = -e2u, e2v = -e2v;
    /* via e1 first or e2 first: the one that starts further left (the
     * first edge's slope du/dv smaller); a horizontal step goes first */
    int e1_first = e1v == 0 || (e2v != 0 && e1u * e2v < e2u * e1v);
    double au = e1_first ? e1u : e2u, av = e1_first ? e1v : e2v;
    double bu = e1_first ? e2u : e1u, bv = e1_first ? e2v : e1v;
    if (av == 0) au = -fabs(au); /* along the bottom edge to its left end */
    double u = -0.5 * (au + bu), v = -0.5 * (av + bv);
    fp->pv[0][0] = v;
    double area = 0;
    for (int e = 0; e < 2; e++) {
        double eu = e ? bu : au, ev = e ? bv : av;
        if (ev > 0) {
            /* a part of height h = ev / n: h^2 |eu / ev| / 8 <= FP_EPS A */
            double need = sqrt(ev * fabs(eu) / (8 * FP_EPS * A));
            int n = need < 1 ? 1 : need >= RS__MK_STEPS / 2 ? RS__MK_STEPS / 2 : (int)ceil(need);
            for (int k = 0; k < n; k++) {
                double t1 = (double)(k + 1) / n, tm = (k + 0.5) / n;
                fp->pu[fp->n][0] = u + tm * eu;
                fp->pv[fp->n + 1][0] = k + 1 == n ? v + ev : v + t1 * ev;
                /* the band between this step and its mirror image */
                area += -2 * fp->pu[fp->n][0] * (fp->pv[fp->n + 1][0] - fp->pv[fp->n][0]);
                fp->n++;
            }
        }
        u += eu;
        v += ev;
    }
    fp->ia = area > 0 ? 1 / area : 0;
    for (int k = 0; k <= fp->n; k++) fp->pv[k][1] = -fp->pv[k][0];
    for (int k = 0; k < fp->n; k++) fp->pu[k][1] = -fp->pu[k][0];
    /* the staircase polygon's reach from the centre (both sides) */
    fp->hu = fp->hv = 0;
    for (int k = 0; k < fp->n; k++) {
        fp->hu = fmax(fp->hu, fabs(fp->pu[k][0]));
        fp->hv = fmax(fp->hv, fmax(fabs(fp->pv[k][0]), fabs(fp->pv[k + 1][0])));
    }
}

/* The road coordinates of local point (x, y) on a marking's stretch of
 * road (RS__MK_PT doubles per point): the nearest point of its segments
 * (the first and last extended beyond their ends, so that pixels past the
 * stretch never clamp onto it), s there and t = the signed distance (+ left
 * of travel), so a marking bends with the road as its buffer does. */
static void road_coords(const double *pts, size_t npt, double x, double y, double *s_out, double *t_out,
                        size_t *seg_out)
{
    /* the nearest segment by index (selects, not branches), then its s, t */
    double best = INFINITY;
    size_t bk = 0;
    for (size_t k = 0; k + 1 < npt; k++) {
        const double *a = pts + RS__MK_PT * k;
        double ux = a[3], uy = a[4];
        double px = x - a[0], py = y - a[1];
        double u = px * ux + py * uy;
        u = u < a[6] ? a[6] : u;
        u = u > a[7] ? a[7] : u;
        double ex = px - u * ux, ey = py - u * uy, d2 = ex * ex + ey * ey;
        d2 = a[5] > 0 ? d2 : INFINITY;
        bk = d2 < best ? k : bk;
        best = d2 < best ? d2 : best;
    }
    const double *a = pts + RS__MK_PT * bk;
    double ux = a[3], uy = a[4], px = x - a[0], py = y - a[1];
    double u = px * ux + py * uy;
    u = u < a[6] ? a[6] : u;
    u = u > a[7] ? a[7] : u;
    double ex = px - u * ux, ey = py - u * uy;
    double side = ex * uy - ey * ux; /* (p - q) . (dy, -dx) */
    *s_out = a[2] + u;
    *t_out = copysign(sqrt(best), side);
    *seg_out = bk;
}

/* Geometry of one placement: its levels, support, stretch of road,
 * bounding box. Returns 0 when it lies wholly off its road or its sprite
 * is transparent. */
static int place(const rs__placement *pl, const rs__road_local *r, const rs__atlas_type *ty, const rs__mk_tex *tx,
                 double pix, rs__mk *m, double **pts, size_t *npts, size_t *cap, rs_ctx *ctx, rs_result *err)
{
    memset(m, 0, sizeof *m);
    m->road = (uint32_t)pl->road;
    m->ty = ty;
    m->flip = pl->flip;
    m->s0 = pl->s;
    m->t0 = pl->t;
    m->hl = 0.5 * pl->length;
    m->hw = 0.5 * pl->width;
    m->kx = ty->lev[0].w / pl->width;
    m->ky = ty->lev[0].h / pl->length;
    m->tex = tx;
    if (tx->ax0 > tx->ax1) return 0;
    const double sgn = m->flip ? -1 : 1;
    m->cu = m->hw * m->kx;
    m->su = -sgn * m->kx;
    m->cv = m->hl * m->ky;
    m->sv = -sgn * m->ky;
    /* support: the footprint (reaching at most pix / sqrt 2 from the
     * centre; sharper on a one-segment stretch, below) meets a texel with
     * alpha > 0 */
    {
        double hu = 0.70711 * pix * m->kx, hv = 0.70711 * pix * m->ky;
        m->ulo = tx->ax0 - hu;
        m->uhi = tx->ax1 + 1 + hu;
        m->vlo = tx->ay0 - hv;
        m->vhi = tx->ay1 + 1 + hv;
    }
    {
        double d0 = (m->ulo - m->cu) / m->su, d1 = (m->uhi - m->cu) / m->su;
        double e0 = (m->vlo - m->cv) / m->sv, e1 = (m->vhi - m->cv) / m->sv;
        double dlo = d0 < d1 ? d0 : d1, dhi = d0 < d1 ? d1 : d0;
        double elo = e0 < e1 ? e0 : e1, ehi = e0 < e1 ? e1 : e0;
        /* a margin far above rounding: the box and row spans must hold
         * every pixel whose own test passes */
        double mt = 1e-6 + 1e-12 * fabs(m->t0), ms = 1e-6 + 1e-12 * fabs(m->s0);
        m->tlo = m->t0 + dlo - mt;
        m->thi = m->t0 + dhi + mt;
        m->slo = m->s0 + elo - ms;
        m->shi = m->s0 + ehi + ms;
    }
    if (r->n < 2) return 0;
    double total = r->s[r->n - 1];
    double lo = m->slo, hi = m->shi;
    if (hi < r->s[0] || lo > total) return 0; /* (s[0] < 0 on a stretch extended before the record) */
    if (!(fabs(lo) <= RS__ARC_MEASURED && fabs(hi) <= RS__ARC_MEASURED)) return 0;
    /* segments [a, b] overlapping [lo, hi] */
    size_t a = 0, b = r->n - 2;
    {
        size_t lw = 0, h = r->n - 1; /* last k with s[k] <= lo */
        while (lw + 1 < h) {
            size_t mid = (lw + h) / 2;
            if (r->s[mid] <= lo) lw = mid; else h = mid;
        }
        a = lw;
        lw = 0;
        h = r->n - 1; /* first k with s[k] >= hi */
        while (lw + 1 < h) {
            size_t mid = (lw + h) / 2;
            if (r->s[mid] >= hi) h = mid; else lw = mid;
        }
        b = h > 0 ? h - 1 : 0;
        if (b < a) b = a;
    }
    if (!(fabs(r->s[a]) <= RS__ARC_MEASURED)) return 0; /* (the stretch is measured from its first point) */
    size_t np = b - a + 2;
    /* the stretches of all marks together: a budget, as the points of all roads */
    if (np > ctx->limits.max_points - *npts) {
        *err = RS_ERR_LIMIT;
        return 0;
    }
    if (*npts + np > *cap) {
        size_t nc = *cap ? *cap : 256;
        while (nc < *npts + np) nc *= 2;
        double *q = rs__realloc(ctx, *pts, nc * RS__MK_PT * sizeof(double));
        if (!q) {
            *err = RS_ERR_NOMEM;
            return 0;
        }
        *pts = q;
        *cap = nc;
    }
    m->first = *npts;
    m->npt = np;
    double *c0 = *pts + RS__MK_PT * *npts;
    for (size_t k = 0; k < np; k++) {
        double *o = c0 + RS__MK_PT * k;
        o[0] = r->x[a + k];
        o[1] = r->y[a + k];
        o[2] = r->s[a + k];
        o[3] = o[4] = o[5] = 0;
        o[6] = k > 0 ? 0 : -INFINITY;
        o[7] = INFINITY;
        if (k > 0) {
            double *pv = o - RS__MK_PT, len = o[2] - pv[2];
            pv[5] = len;
            pv[3] = len > 0 ? (o[0] - pv[0]) / len : 1;
            pv[4] = len > 0 ? (o[1] - pv[1]) / len : 0;
            if (k + 1 < np) pv[7] = len;
            pv[8] = pv[3] != 0 ? 1 / (pv[3] * pix) : 0;
            pv[9] = pv[4] != 0 ? 1 / (pv[4] * pix) : 0;
        }
        o[8] = o[9] = 0;
    }
    if (np == 2) {
        /* one segment, extended both ways: s and t are affine in (x, y) */
        const double *A = c0;
        double ux = A[3], uy = A[4];
        m->bu = m->su * uy * pix;
        m->ibu = m->bu != 0 ? 1 / m->bu : 0;
        m->buy = -m->su * ux;
        m->au = m->cu + m->su * (A[1] * ux - A[0] * uy - m->t0);
        m->bv = m->sv * ux * pix;
        m->ibv = m->bv != 0 ? 1 / m->bv : 0;
        m->bvy = m->sv * uy;
        m->av = m->cv + m->sv * (A[2] - m->s0 - A[0] * ux - A[1] * uy);
        footprint(m->bu, m->bv, m->buy * pix, m->bvy * pix, &m->fp);
        double hu = m->fp.hu, hv = m->fp.hv;
        m->ulo = fmax(m->ulo, m->tex->ax0 - hu);
        m->uhi = fmin(m->uhi, m->tex->ax1 + 1 + hu);
        m->vlo = fmax(m->vlo, m->tex->ay0 - hv);
        m->vhi = fmin(m->vhi, m->tex->ay1 + 1 + hv);
        m->flat = m->bu == 0 || m->bv == 0;
        m->ua = m->ibu >= 0 ? m->ulo : m->uhi;
        m->ub = m->ibu >= 0 ? m->uhi : m->ulo;
        m->va = m->ibv >= 0 ? m->vlo : m->vhi;
        m->vb = m->ibv >= 0 ? m->vhi : m->vlo;
    }
    /* the box: the support's corners where [lo, hi] starts and ends (on
     * the end segments' lines, extended past the stretch as the lookup
     * extends them), and around every vertex inside [lo, hi] the square of
     * the farthest offset (an outer bend's arc stays in it) */
    double tin = m->tlo, tout = m->thi;
    double far = fabs(tin) > fabs(tout) ? fabs(tin) : fabs(tout);
    m->bx0 = m->by0 = INFINITY;
    m->bx1 = m->by1 = -INFINITY;
    for (int end = 0; end < 2; end++) {
        double sv = end ? hi : lo;
        /* the segment of the chain that holds sv (end segments extended) */
        size_t k = 0;
        while (k + 2 < np && c0[RS__MK_PT * (k + 1) + 2] <= sv) k++;
        const double *A = c0 + RS__MK_PT * k;
        double ux = A[3], uy = A[4];
        double px = A[0] + (sv - A[2]) * ux, py = A[1] + (sv - A[2]) * uy;
        for (int side = 0; side < 2; side++) {
            double tt = side ? tout : tin, x = px + tt * uy, y = py - tt * ux; /* left normal (dy, -dx) */
            if (x < m->bx0) m->bx0 = x;
            if (x > m->bx1) m->bx1 = x;
            if (y < m->by0) m->by0 = y;
            if (y > m->by1) m->by1 = y;
        }
    }
    for (size_t k = 1; k + 1 < np; k++) {
        const double *V = c0 + RS__MK_PT * k;
        if (!(V[2] > lo && V[2] < hi)) continue;
        if (V[0] - far < m->bx0) m->bx0 = V[0] - far;
        if (V[0] + far > m->bx1) m->bx1 = V[0] + far;
        if (V[1] - far < m->by0) m->by0 = V[1] - far;
        if (V[1] + far > m->by1) m->by1 = V[1] + far;
    }
    *npts += np;
    return 1;
}

/* Bounds on K (pixel column + 1/2) from lo <= q <= hi, where q = K pix cx +
 * (y - py) cy + c0 over the row centre y: into o[0..3] (lower a, b, upper
 * a, b) when cx != 0, else into the y range [*ylo, *yhi]. */
static void part_slab(double cx, double cy, double c0, double py, double lo, double hi, double pix, double *o,
                      double *ylo, double *yhi)
{
    if (cx != 0) {
        /* K = (q - c0 + py cy - y cy) / (pix cx) */
        double ib = 1 / (pix * cx), a = (lo - c0 + py * cy) * ib, c = (hi - c0 + py * cy) * ib, b = -cy * ib;
        if (ib < 0) {
            double t = a;
            a = c;
            c = t;
        }
        o[0] = a;
        o[1] = b;
        o[2] = c;
        o[3] = b;
        return;
    }
    o[0] = -INFINITY;
    o[1] = 0;
    o[2] = INFINITY;
    o[3] = 0;
    /* q = (y - py) cy + c0: y in [(lo - c0) / cy + py, (hi - c0) / cy + py] */
    double y0 = (lo - c0) / cy + py, y1 = (hi - c0) / cy + py;
    if (y0 > y1) {
        double t = y0;
        y0 = y1;
        y1 = t;
    }
    /* widened as the spans are: the per-pixel test decides */
    double e = 1e-6 * (1 + fabs(py));
    if (y0 - e > *ylo) *ylo = y0 - e;
    if (y1 + e < *yhi) *yhi = y1 + e;
}

/* The span parts of curved marking m: each segment's rectangle of the
 * support and the wedge at each vertex inside its s range. */
static rs_result build_parts(rs_ctx *ctx, rs__markings *mk, rs__mk *m, size_t *n, size_t *cap)
{
    const double *c0 = mk->pts + RS__MK_PT * m->first, pix = mk->pix;
    double far = fabs(m->tlo) > fabs(m->thi) ? fabs(m->tlo) : fabs(m->thi);
    m->part = *n;
    m->nparts = 0;
    for (size_t k = 0; k + 1 < m->npt; k++) {
        for (int wedge = 0; wedge < 2; wedge++) {
            const double *A = c0 + RS__MK_PT * k;
            double o[RS__MK_PART];
            o[8] = -INFINITY;
            o[9] = INFINITY;
            o[12] = -1;
            if (!wedge) {
                if (!(A[5] > 0)) continue;
                double ua = m->slo - A[2], ub = m->shi - A[2];
                ua = ua < A[6] ? A[6] : ua;
                ub = ub > A[7] ? A[7] : ub;
                if (!(ua <= ub)) continue;
                /* u = (x - ax) ux + (y - ay) uy, t = (x - ax) uy - (y - ay) ux, x = K pix */
                part_slab(A[3], A[4], -A[0] * A[3], A[1], ua, ub, pix, o, &o[8], &o[9]);
                part_slab(A[4], -A[3], -A[0] * A[4], A[1], m->tlo, m->thi, pix, o + 4, &o[8], &o[9]);
            } else {
                if (k == 0) continue;
                /* vertex k is the nearest point only past the end of segment
                 * k - 1 and before the start of segment k: the wedge between
                 * their normals (outer side of the bend), within the
                 * farthest offset */
                const double *B = A - RS__MK_PT;
                if (!(A[2] >= m->slo && A[2] <= m->shi)) continue;
                double *h1 = o, *h2 = o + 4;
                h1[0] = -INFINITY, h1[1] = 0, h1[2] = INFINITY, h1[3] = 0;
                h2[0] = -INFINITY, h2[1] = 0, h2[2] = INFINITY, h2[3] = 0;
                if (B[5] > 0) part_slab(B[3], B[4], -B[0] * B[3], B[1], B[5], INFINITY, pix, h1, &o[8], &o[9]);
                if (A[5] > 0) part_slab(A[3], A[4], -A[0] * A[3], A[1], -INFINITY, 0, pix, h2, &o[8], &o[9]);
                o[10] = A[0];
                o[11] = A[1];
                o[12] = far;
            }
            if (*n == *cap) {
                size_t nc = *cap ? 2 * *cap : 256;
                double *q = rs__realloc(ctx, mk->parts, nc * RS__MK_PART * sizeof(double));
                if (!q) return RS_ERR_NOMEM;
                mk->parts = q;
                *cap = nc;
            }
            memcpy(mk->parts + RS__MK_PART * *n, o, sizeof o);
            ++*n;
            m->nparts++;
        }
    }
    return RS_OK;
}

/* Index cell of coordinate v (metres): the map's cell less the index's
 * first (off), clamped to [0, n - 1]; the build and the paint use the same
 * function on the same (float) boxes, so a box beyond the index is listed
 * in, and found from, its nearest cells (the paint tests every box). */
static uint32_t cell_of(double v, double cell, uint32_t off, uint32_t n)
{
    double c = floor(v / cell) - off;
    if (!(c > 0)) return 0;
    return c >= n ? n - 1 : (uint32_t)c;
}

/* Cells [lo, hi] of the map's n along one axis that hold [a, b] (metres)
 * and one cell more each side */
static void window_cells(double a, double b, double cell, uint32_t n, uint32_t *lo, uint32_t *cnt)
{
    double c0 = floor(a / cell) - 1, c1 = floor(b / cell) + 1;
    c0 = c0 > 0 ? c0 : 0, c1 = c1 < (double)n - 1 ? c1 : (double)n - 1;
    if (!(c0 <= c1)) c0 = 0, c1 = (double)n - 1; /* (not a number, or outside: the map) */
    *lo = (uint32_t)c0;
    *cnt = (uint32_t)(c1 - c0) + 1;
}

static rs_result build_index(rs_ctx *ctx, rs__markings *mk, double map_w, double map_h, const double *window)
{
    double cell = 2.0;
    if (cell < 4 * mk->pix) cell = 4 * mk->pix;
    while ((map_w / cell + 1) * (map_h / cell + 1) > MAX_INDEX_CELLS) cell *= 2;
    mk->cell = cell;
    mk->ox = mk->oy = 0;
    mk->gw = (uint32_t)(map_w / cell) + 1;
    mk->gh = (uint32_t)(map_h / cell) + 1;
    if (window) { /* (a patch's grid: its rectangle's cells, the rest in the nearest) */
        window_cells(window[0], window[2], cell, mk->gw, &mk->ox, &mk->gw);
        window_cells(window[1], window[3], cell, mk->gh, &mk->oy, &mk->gh);
    }
    size_t ncell = (size_t)mk->gw * mk->gh;
    mk->start = rs__calloc(ctx, ncell + 1, sizeof *mk->start);
    if (!mk->start) return RS_ERR_NOMEM;
    uint64_t total = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t i = 0; i < mk->n; i++) {
            const rs__mk *m = &mk->m[i];
            rs__mk_ref e;
            e.x0 = nextafterf((float)m->bx0, -INFINITY);
            e.y0 = nextafterf((float)m->by0, -INFINITY);
            e.x1 = nextafterf((float)m->bx1, INFINITY);
            e.y1 = nextafterf((float)m->by1, INFINITY);
            e.i = m->rec;
            if (!(e.x1 >= 0 && e.y1 >= 0 && e.x0 < map_w + cell && e.y0 < map_h + cell)) continue;
            uint32_t x0 = cell_of(e.x0, cell, mk->ox, mk->gw), y0 = cell_of(e.y0, cell, mk->oy, mk->gh);
            uint32_t x1 = cell_of(e.x1, cell, mk->ox, mk->gw), y1 = cell_of(e.y1, cell, mk->oy, mk->gh);
            e.cx = x0;
            e.cy = y0;
            if (pass == 0) {
                total += (uint64_t)(x1 - x0 + 1) * (y1 - y0 + 1);
                if (total > MAX_INDEX_ENTRIES)
                    return rs__fail(ctx, RS_ERR_LIMIT, "markings cover more than %u index cells in all (too large?)",
                                    MAX_INDEX_ENTRIES);
                for (uint32_t y = y0; y <= y1; y++)
                    for (uint32_t x = x0; x <= x1; x++) mk->start[(size_t)y * mk->gw + x + 1]++;
            } else {
                for (uint32_t y = y0; y <= y1; y++)
                    for (uint32_t x = x0; x <= x1; x++) {
                        e.lx = x;
                        mk->list[mk->start[(size_t)y * mk->gw + x]++] = e;
                    }
            }
        }
        if (pass == 0) {
            for (size_t c = 0; c < ncell; c++) mk->start[c + 1] += mk->start[c];
            mk->list = rs__alloc_array(ctx, total ? (size_t)total : 1, sizeof *mk->list);
            if (!mk->list) return RS_ERR_NOMEM;
        } else {
            /* the fill advanced each start to the next cell's: shift back */
            for (size_t c = ncell; c > 0; c--) mk->start[c] = mk->start[c - 1];
            mk->start[0] = 0;
        }
    }
    mk->bytes += (ncell + 1) * sizeof *mk->start + (size_t)total * sizeof *mk->list;
    return RS_OK;
}

/* Stores the records by the top of their box (rs__markings.m), each
 * curved one's stretch points, span parts and footprints in the same
 * order, and makes mk->at. */
typedef struct mk_key {
    double y;
    uint32_t i;
} mk_key;

static int cmp_key(const void *pa, const void *pb)
{
    const mk_key *a = pa, *b = pb;
    if (a->y != b->y) return a->y < b->y ? -1 : 1;
    return (a->i > b->i) - (a->i < b->i);
}

static rs_result storage_order(rs_ctx *ctx, rs__markings *mk, size_t npart, size_t nfp)
{
    const size_t n = mk->n;
    size_t npt = 0;
    for (size_t i = 0; i < n; i++) npt += mk->m[i].npt;
    mk_key *key = rs__alloc_array(ctx, n, sizeof *key);
    rs__mk *m2 = rs__alloc_array(ctx, n, sizeof *m2);
    double *pts2 = rs__alloc_array(ctx, npt ? npt : 1, RS__MK_PT * sizeof(double));
    double *parts2 = npart ? rs__alloc_array(ctx, npart, RS__MK_PART * sizeof(double)) : NULL;
    rs__mk_fp *fps2 = nfp ? rs__alloc_array(ctx, nfp, sizeof *fps2) : NULL;
    uint32_t *at = rs__alloc_array(ctx, n, sizeof *at);
    rs_result r = !key || !m2 || !pts2 || (npart && !parts2) || (nfp && !fps2) || !at ? RS_ERR_NOMEM : RS_OK;
    if (!r) {
        for (size_t i = 0; i < n; i++) {
            key[i].y = isnan(mk->m[i].by0) ? INFINITY : mk->m[i].by0; /* a total order */
            key[i].i = (uint32_t)i;
        }
        r = rs__sort(ctx, key, n, sizeof *key, cmp_key);
    }
    if (r) goto fail;
    size_t pa = 0, qa = 0, fa = 0;
    for (size_t j = 0; j < n; j++) {
        if ((j & 1023) == 1023 && rs__poll(ctx)) { /* (the copies fault fresh pages in: ~30 ms per 8192) */
            r = RS_ERR_CANCELLED;
            goto fail;
        }
        const rs__mk *src = &mk->m[key[j].i];
        rs__mk *d = &m2[j];
        *d = *src;
        d->rec = key[j].i;
        at[key[j].i] = (uint32_t)j;
        memcpy(pts2 + RS__MK_PT * pa, mk->pts + RS__MK_PT * src->first, src->npt * RS__MK_PT * sizeof(double));
        d->first = pa;
        pa += src->npt;
        if (src->npt > 2) {
            memcpy(parts2 + RS__MK_PART * qa, mk->parts + RS__MK_PART * src->part,
                   src->nparts * RS__MK_PART * sizeof(double));
            d->part = qa;
            qa += src->nparts;
            memcpy(fps2 + fa, mk->fps + src->fpi, (src->npt - 1) * sizeof *fps2);
            d->fpi = fa;
            fa += src->npt - 1;
        }
    }
    rs__free(ctx, key);
    rs__free(ctx, mk->m);
    rs__free(ctx, mk->pts);
    rs__free(ctx, mk->parts);
    rs__free(ctx, mk->fps);
    mk->m = m2;
    mk->pts = pts2;
    mk->parts = parts2;
    mk->fps = fps2;
    mk->at = at;
    return RS_OK;
fail:
    rs__free(ctx, key);
    rs__free(ctx, m2);
    rs__free(ctx, pts2);
    rs__free(ctx, parts2);
    rs__free(ctx, fps2);
    rs__free(ctx, at);
    return r;
}

/* Road ri's local points extended past its ends along the records that go
 * on there (the network's links: the same street split into records), so
 * a placement reaching past a split follows the street's own line, also on
 * a bend: at least `before` metres before its first point (s < 0) and
 * `after` past its last, as far as the links go (16 records at most each
 * way). The joint points are shared; s runs on from the record's own. */
static rs_result road_local_extended(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, size_t ri,
                                     const rs_dem *dem, double before, double after, rs__road_local *out)
{
    rs_result r = rs__road_local_get(ctx, roads, ri, dem, out);
    if (r || out->n < 2) return r;
    for (int e = 0; e < 2; e++) {
        double need = e ? after : before, have = 0;
        size_t at = ri;
        int at_end = e; /* the end of `at` the chain leaves from */
        for (int hop = 0; hop < 16 && have < need; hop++) {
            uint32_t lk = net->link[2 * at + (size_t)at_end];
            if (lk == UINT32_MAX) break;
            size_t q = lk / 2;
            int qend = (int)(lk & 1); /* q meets us with its last point (1) or its first */
            rs__road_local ql;
            if ((r = rs__road_local_get(ctx, roads, q, dem, &ql)) != RS_OK) return r;
            if (ql.n < 2) {
                rs__road_local_free(ctx, &ql);
                break;
            }
            /* q's points away from the joint (the joint itself is ours) */
            size_t add = ql.n - 1, n0 = out->n;
            double *nx = rs__realloc(ctx, out->x, (n0 + add) * sizeof *nx);
            if (nx) out->x = nx;
            double *ny = nx ? rs__realloc(ctx, out->y, (n0 + add) * sizeof *ny) : NULL;
            if (ny) out->y = ny;
            double *ns = ny ? rs__realloc(ctx, out->s, (n0 + add) * sizeof *ns) : NULL;
            if (ns) out->s = ns;
            if (!ns) {
                rs__road_local_free(ctx, &ql);
                return RS_ERR_NOMEM;
            }
            if (!e) { /* before our first point: make room at the front */
                memmove(out->x + add, out->x, n0 * sizeof *out->x);
                memmove(out->y + add, out->y, n0 * sizeof *out->y);
                memmove(out->s + add, out->s, n0 * sizeof *out->s);
            }
            double len = ql.s[ql.n - 1];
            for (size_t k = 1; k <= add; k++) {
                /* the k-th point of q away from the joint, and its distance
                 * from the joint along q */
                size_t qi = qend ? ql.n - 1 - k : k;
                double d = qend ? len - ql.s[qi] : ql.s[qi];
                size_t o = e ? n0 + k - 1 : add - k;
                out->x[o] = ql.x[qi];
                out->y[o] = ql.y[qi];
                out->s[o] = e ? out->s[n0 - 1] + d : out->s[add] - d;
            }
            out->n = n0 + add;
            have += len;
            at = q;
            at_end = !qend; /* on along q: its other end */
            rs__road_local_free(ctx, &ql);
        }
    }
    return RS_OK;
}

rs_result rs__markings_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                             const rs_network *net_in, rs__markings **out)
{
    return rs__markings_build_planned(ctx, dem, roads, o, net_in, NULL, NULL, out);
}

rs_result rs__markings_build_planned(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads,
                                     const rs_splat_options *o, const rs_network *net_in, rs__auto_plan *plan,
                                     const double *window, rs__markings **out)
{
    *out = NULL;
    if (o->markings.disable) return RS_OK;
    size_t nexp = rs_roads_mark_count(roads);
    /* nothing to place: no atlas to load (the built-in one takes ms) */
    if (nexp == 0 && (o->markings.no_auto || !rs__markings_auto_possible(roads))) return RS_OK;
    rs__markings *mk = rs__calloc(ctx, 1, sizeof *mk);
    if (!mk) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
    rs_result r = RS_OK;
    const rs_atlas *atlas = o->markings.atlas;
    if (!atlas && plan && plan->atlas) {
        mk->atlas_own = plan->atlas; /* the plan's placements index it */
        plan->atlas = NULL;
    }
    if (!atlas && !mk->atlas_own) r = rs_atlas_default(ctx, &mk->atlas_own);
    if (!atlas) atlas = mk->atlas_own;
    rs__placement *pl = NULL;
    size_t npl = 0, cap = 0;
    if (!r) r = rs__markings_explicit(ctx, roads, atlas, &pl, &npl, &cap);
    size_t n_explicit = npl;
    if (!r && !o->markings.no_auto && plan) {
        for (size_t i = 0; i < plan->npl && !r; i++)
            if (rs__placement_push(ctx, &pl, &npl, &cap, &plan->pl[i])) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
    } else if (!r && !o->markings.no_auto) {
        r = rs__markings_auto(ctx, dem, roads, atlas, &o->style, net_in, &pl, &npl, &cap);
    }
    if (!r && npl > ctx->limits.max_points) /* ~0.5 KB each: a total, as for road points */
        r = rs__fail(ctx, RS_ERR_LIMIT, "markings: more than %llu markings (explicit and automatic; the budget is "
                     "rs_limits.max_points)", (unsigned long long)ctx->limits.max_points);
    if (!r && npl) {
        mk->pix = dem->frame.cell_size / o->texels;
        mk->m = rs__alloc_array(ctx, npl, sizeof *mk->m);
        mk->ntex = atlas->n;
        mk->tex = rs__calloc(ctx, atlas->n, sizeof *mk->tex);
        if (!mk->m || !mk->tex) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
        size_t tex_bytes = 0;
        size_t pcap = 0, npts = 0;
        rs__road_local rl;
        memset(&rl, 0, sizeof rl);
        size_t have_road = SIZE_MAX;
        /* the caller's network, else one built when a placement reaches past its record */
        rs_network *own = NULL;
        const rs_network *net = net_in && rs_network_road_count(net_in) == rs_roads_count(roads) ? net_in : NULL;
        int net_tried = net != NULL;
        /* placements road by road (a stable counting sort), so each road's
         * local points are made once however the marks alternate between
         * roads; kept[i]: placement i was placed into mk->m[i] */
        size_t nroads = rs_roads_count(roads), *order = rs__alloc_array(ctx, npl, sizeof *order);
        size_t *first = rs__calloc(ctx, nroads + 1, sizeof *first);
        uint8_t *kept = rs__calloc(ctx, npl, 1);
        if (!order || !first || !kept) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
        for (size_t i = 0; i < npl && !r; i++) first[pl[i].road + 1]++;
        for (size_t k = 0; k < nroads && !r; k++) first[k + 1] += first[k];
        for (size_t i = 0; i < npl && !r; i++) order[first[pl[i].road]++] = i;
        for (size_t q = 0; q < npl && !r; q++) {
            size_t i = order[q];
            if (pl[i].road != have_road) {
                if (rs__tick(ctx, 1)) {
                    r = RS_ERR_CANCELLED;
                    break;
                }
                rs__road_local_free(ctx, &rl);
                have_road = SIZE_MAX;
                if (rs__road_local_get(ctx, roads, pl[i].road, dem, &rl)) {
                    r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
                    break;
                }
                have_road = pl[i].road;
            }
            rs__mk_tex *tx = &mk->tex[pl[i].type];
            if (tx->w == 0 && build_tex(ctx, &atlas->t[pl[i].type], tx, &tex_bytes)) {
                r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
                break;
            }
            rs_result e = RS_OK;
            size_t npts0 = npts;
            kept[i] = (uint8_t)place(&pl[i], &rl, &atlas->t[pl[i].type], tx, mk->pix, &mk->m[i], &mk->pts, &npts,
                                     &pcap, ctx, &e);
            /* reaching past the record's end: along the records that go on
             * there (a street split anywhere draws as the unsplit one) */
            double total = rl.n >= 2 ? rl.s[rl.n - 1] : 0;
            if (!e && rl.n >= 2 && tx->ax0 <= tx->ax1 && (mk->m[i].slo < 0 || mk->m[i].shi > total)) {
                if (!net && !net_tried) {
                    net_tried = 1;
                    if ((e = rs_network_build(ctx, roads, NULL, &own)) == RS_OK) net = own;
                }
                rs__road_local xl;
                memset(&xl, 0, sizeof xl);
                if (net && !e)
                    e = road_local_extended(ctx, roads, net, pl[i].road, dem, -mk->m[i].slo, mk->m[i].shi - total, &xl);
                if (!e && xl.n > rl.n) {
                    npts = npts0;
                    kept[i] = (uint8_t)place(&pl[i], &xl, &atlas->t[pl[i].type], tx, mk->pix, &mk->m[i], &mk->pts,
                                             &npts, &pcap, ctx, &e);
                }
                rs__road_local_free(ctx, &xl);
            }
            if (e == RS_ERR_LIMIT)
                r = rs__fail(ctx, e, "markings: the marks' stretches of road hold more than %llu points together "
                             "(long marks on roads of many points; the budget is rs_limits.max_points)",
                             (unsigned long long)ctx->limits.max_points);
            else if (e)
                r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
        }
        for (size_t i = 0; i < npl && !r; i++) /* back to record order (storage_order then stores them by box) */
            if (kept[i]) {
                mk->m[mk->n++] = mk->m[i];
                if (i < n_explicit) mk->n_explicit++;
                else mk->n_auto++;
            }
        rs__free(ctx, order);
        rs__free(ctx, first);
        rs__free(ctx, kept);
        rs__road_local_free(ctx, &rl);
        rs_network_free(ctx, own);
        mk->bytes = sizeof *mk + npl * sizeof *mk->m + pcap * RS__MK_PT * sizeof(double) +
                    mk->ntex * sizeof *mk->tex + tex_bytes;
        size_t npart = 0, partcap = 0, nfp = 0;
        /* (the stages below take ~0.1 s at 10^5 roads: they poll, issue 30 target 4) */
        if (!r && rs__poll(ctx)) r = RS_ERR_CANCELLED;
        for (size_t i = 0; i < mk->n && !r; i++)
            if ((i & 4095) == 4095 && rs__poll(ctx)) r = RS_ERR_CANCELLED;
            else if (mk->m[i].npt > 2) {
                if (build_parts(ctx, mk, &mk->m[i], &npart, &partcap))
                    r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
                nfp += mk->m[i].npt - 1;
            }
        mk->bytes += partcap * RS__MK_PART * sizeof(double);
        /* curved stretches: the footprint of each segment's direction */
        if (!r && nfp) {
            mk->fps = rs__alloc_array(ctx, nfp, sizeof *mk->fps);
            if (!mk->fps) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
            mk->bytes += nfp * sizeof *mk->fps;
        }
        if (!r && rs__poll(ctx)) r = RS_ERR_CANCELLED;
        for (size_t i = 0, f = 0; i < mk->n && !r; i++) {
            rs__mk *m = &mk->m[i];
            if ((i & 4095) == 4095 && rs__poll(ctx)) r = RS_ERR_CANCELLED;
            if (m->npt <= 2) continue;
            m->fpi = f;
            for (size_t k = 0; k + 1 < m->npt; k++, f++) {
                const double *A = mk->pts + RS__MK_PT * (m->first + k);
                footprint(m->su * A[4] * mk->pix, m->sv * A[3] * mk->pix, -m->su * A[3] * mk->pix,
                          m->sv * A[4] * mk->pix, &mk->fps[f]);
            }
        }
        if (!r && rs__poll(ctx)) r = RS_ERR_CANCELLED;
        if (!r && mk->n) {
            rs_result e = storage_order(ctx, mk, npart, nfp);
            r = e == RS_ERR_NOMEM ? rs__fail(ctx, e, "out of memory for markings") : e;
        }
        if (!r && rs__poll(ctx)) r = RS_ERR_CANCELLED;
        if (!r && mk->n) {
            /* as stored: the records kept, the points, parts and footprints they use */
            size_t npt = 0;
            for (size_t i = 0; i < mk->n; i++) npt += mk->m[i].npt;
            mk->bytes = sizeof *mk + mk->n * (sizeof *mk->m + sizeof *mk->at) + npt * RS__MK_PT * sizeof(double) +
                        npart * RS__MK_PART * sizeof(double) + nfp * sizeof *mk->fps + mk->ntex * sizeof *mk->tex +
                        tex_bytes;
        }
        if (!r && mk->n) {
            double map_w = (double)(dem->width - 1) * dem->frame.cell_size;
            double map_h = (double)(dem->height - 1) * dem->frame.cell_size;
            r = build_index(ctx, mk, map_w, map_h, window);
            if (r == RS_ERR_NOMEM) rs__fail(ctx, r, "out of memory for the markings index");
        }
        if (!r && mk->n) {
            uint64_t iw = (uint64_t)(dem->width - 1) * o->texels, ih = (uint64_t)(dem->height - 1) * o->texels;
            mk->img_w = iw <= UINT32_MAX ? (uint32_t)iw : 0; /* 0: none kept */
            mk->img_h = ih <= UINT32_MAX ? (uint32_t)ih : 0;
            r = pre_build(ctx, mk);
        }
    }
    if (r || mk->n == 0) {
        rs__free(ctx, pl);
        rs__markings_free(ctx, mk);
        return r;
    }
    mk->pl = pl; /* kept for the GPU export */
    mk->npl = npl;
    mk->bytes += npl * sizeof *pl;
    *out = mk;
    return RS_OK;
}

/* Clamps one step of footprint fp (side: +1 left, -1 the right side,
 * the left turned by 180 degrees) at (U, V) to the sprite (w x h; no
 * alpha outside); 0 when it adds nothing (left of the sprite, or its V
 * range outside). */
static int fp_step(const rs__mk_fp *fp, int k, double sg, double U, double V, double w, double h, size_t w1,
                   size_t *ea, size_t *eb, double *fu, double *f0, double *f1)
{
    double u = U + sg * fp->pu[k][0], v0 = V + sg * fp->pv[k][0], v1 = V + sg * fp->pv[k + 1][0];
    u = u < w ? u : w;
    v0 = v0 > 0 ? v0 : 0;
    v0 = v0 < h ? v0 : h;
    v1 = v1 > 0 ? v1 : 0;
    v1 = v1 < h ? v1 : h;
    if (!(u > 0) || v0 == v1) return 0;
    size_t i = (size_t)u, j0 = (size_t)v0, j1 = (size_t)v1;
    *fu = u - (double)i;
    *f0 = v0 - (double)j0;
    *f1 = v1 - (double)j1;
    *ea = j0 * w1 + i;
    *eb = j1 * w1 + i;
    return 1;
}

#if defined(__SSE2__)
/* Both sides' levels v (clamped to [0, h]; lane 0 the left side, lane 1
 * the right): the table rows *pa, *pb and the fractions, each in both
 * lanes. */
static inline void level2(const double *t, size_t w2, __m128d v, const double **pa, const double **pb, __m128d *fa,
                          __m128d *fb)
{
    __m128i j = _mm_cvttpd_epi32(v);
    __m128d f = _mm_sub_pd(v, _mm_cvtepi32_pd(j));
    *pa = t + (size_t)(uint32_t)_mm_cvtsi128_si32(j) * w2;
    *pb = t + (size_t)(uint32_t)_mm_cvtsi128_si32(_mm_shuffle_epi32(j, 1)) * w2;
    *fa = _mm_unpacklo_pd(f, f);
    *fb = _mm_unpackhi_pd(f, f);
}

/* G(i, v1) - G(i, v0) and G(i + 1, v1) - G(i + 1, v0) (lanes 0 and 1) for
 * the table corners a (row of v0) and b (row of v1) of column i (rows of
 * w2 corners), the rows' fractions f0, f1 in both lanes: bilinear in
 * doubles from the whole numbers (exact inputs; the result is far below
 * 2^53). The column fraction is applied to both sides at once
 * (kern_integral). */
static inline __m128d step2(const double *a, const double *b, size_t w2, __m128d f0, __m128d f1)
{
    __m128d a0 = _mm_loadu_pd(a), a1 = _mm_loadu_pd(a + w2), b0 = _mm_loadu_pd(b), b1 = _mm_loadu_pd(b + w2);
    __m128d ra = _mm_add_pd(a0, _mm_mul_pd(f0, _mm_sub_pd(a1, a0)));
    __m128d rb = _mm_add_pd(b0, _mm_mul_pd(f1, _mm_sub_pd(b1, b0)));
    return _mm_sub_pd(rb, ra);
}
#else
/* G(u, v1) - G(u, v0) for the table corners a (row of v0) and b (row of
 * v1) of column i (rows of w2 corners), fu = u - i, f0, f1 the rows'
 * fractions: bilinear in doubles from the whole numbers (exact inputs;
 * the result is far below 2^53). */
static inline double step_int(const double *a, const double *b, size_t w2, double fu, double f0, double f1)
{
    double ra0 = a[0] + f0 * (a[w2] - a[0]), ra1 = a[1] + f0 * (a[w2 + 1] - a[1]);
    double rb0 = b[0] + f1 * (b[w2] - b[0]), rb1 = b[1] + f1 * (b[w2 + 1] - b[1]);
    double lo = rb0 - ra0, hi = rb1 - ra1;
    return lo + fu * (hi - lo);
}
#endif

#if !defined(__SSE2__)
/* The integral of the sprite's 255 x alpha (table t, rows of w2 = w + 2
 * corners, w x h texels) over footprint fp at (U, V): the line integral
 * of the summed-area table along the staircases, G(u, v1) - G(u, v0) per
 * step (both sides: the right side is the left one mirrored, V - dv, U -
 * du). The V levels are shared by consecutive steps; a step left of the
 * sprite adds nothing (G(0, v) = 0). kern_integral does the same with
 * SSE2, in the same order: the same bits. */
static double fp_integral_int(const double *t, size_t w2, double w, double h, const rs__mk_fp *fp, double U,
                              double V)
{
    double I = 0;
    const int n = fp->n;
    size_t row[2][RS__MK_STEPS + 1];
    double f[2][RS__MK_STEPS + 1];
    for (int k = 0; k <= n; k++)
        for (int side = 0; side < 2; side++) {
            double v = V + fp->pv[k][side];
            v = v > 0 ? v : 0;
            v = v < h ? v : h;
            size_t j = (size_t)v;
            row[side][k] = j * w2;
            f[side][k] = v - (double)j;
        }
    /* each side's steps in order, then the two sums added, as the SSE2
     * kernel sums them */
    double Is[2] = { 0, 0 };
    for (int k = 0; k < n; k++)
        for (int side = 0; side < 2; side++) {
            double u = U + fp->pu[k][side];
            u = u < w ? u : w;
            if (!(u > 0)) continue;
            size_t i = (size_t)u;
            Is[side] -= step_int(t + row[side][k] + i, t + row[side][k + 1] + i, w2, u - (double)i, f[side][k],
                                 f[side][k + 1]);
        }
    I = Is[0] + Is[1];
    return I;
}
#endif

/* The same for one plane of a table of doubles (several colours). */
static double fp_integral(const double *t, size_t w1, double w, double h, const rs__mk_fp *fp, double U, double V)
{
    double I = 0;
    for (int side = 0; side < 2; side++) {
        const double sg = side ? -1 : 1;
        for (int k = 0; k < fp->n; k++) {
            size_t ea, eb;
            double fu, f0, f1;
            if (!fp_step(fp, k, sg, U, V, w, h, w1, &ea, &eb, &fu, &f0, &f1)) continue;
            const double *a = t + 4 * ea, *b = t + 4 * eb;
            I -= (b[0] - a[0]) + fu * (b[1] - a[1]) + (f1 * b[2] - f0 * a[2]) + fu * (f1 * b[3] - f0 * a[3]);
        }
    }
    return I;
}

/* The sprite's mean premultiplied colour and alpha over footprint fp of
 * the pixel whose centre has level-0 texel coordinates (U, V), for a type
 * of several colours (four planes; alpha-only types: kern_put): the
 * exact integral over the staircase polygon from the summed-area table. */
static void sample4(const rs__mk *m, const rs__mk_fp *fp, double U, double V, float out[4])
{
    const rs__mk_tex *tx = m->tex;
    const size_t w1 = (size_t)tx->w + 1;
    const double w = tx->w, h = tx->h;
    const size_t plane = w1 * ((size_t)tx->h + 1) * 4;
    for (int c = 0; c < 4; c++) {
        double x = fp_integral(tx->sat + (size_t)c * plane, w1, w, h, fp, U, V) * fp->ia;
        double hi = c == 3 ? 1 : 255;
        x = x > 0 ? x : 0;
        out[c] = (float)(x < hi ? x : hi);
    }
}

/* What the paint reads per pixel of one marking and footprint, set up
 * once per marking (or per segment on a curved stretch). */
typedef struct mk_kern {
    const rs__mk *m;
    const rs__mk_fp *fp;
    const double *t;       /* alpha-only table, NULL: the four-plane sample */
    size_t w2;             /* its row length, w + 2 */
    double w, h, ia;       /* texels; 1 / the staircase polygon's area */
    double col[3];
} mk_kern;

static void kern_init(mk_kern *kn, const rs__mk *m, const rs__mk_fp *fp)
{
    const rs__mk_tex *tx = m->tex;
    kn->m = m;
    kn->fp = fp;
    kn->t = tx->nch == 1 ? tx->isat : NULL;
    kn->w2 = (size_t)tx->w + 2;
    kn->w = tx->w;
    kn->h = tx->h;
    kn->ia = fp->ia;
    for (int c = 0; c < 3; c++) kn->col[c] = tx->col[c];
}

#if defined(__SSE2__)
/* fp_integral_int with SSE2, both sides at once (lane 0 the left side,
 * lane 1 the right: the footprint's offset pairs; each side's sum in its
 * lane, the column fraction applied to both in one multiply): the same
 * operations in the same order, so the same bits. A step left of the sprite is clamped
 * onto column 0, where the table is 0, and adds exactly +0 (fu = 0): no
 * branch. */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline double kern_integral(const mk_kern *kn, double U, double V)
{
    const double *t = kn->t;
    const size_t w2 = kn->w2;
    const __m128d VV = _mm_set1_pd(V), UU = _mm_set1_pd(U), z = _mm_setzero_pd();
    const __m128d hh = _mm_set1_pd(kn->h), ww = _mm_set1_pd(kn->w);
    const double *pa, *pb;
    __m128d fa, fb, I2 = _mm_setzero_pd();
    const rs__mk_fp *fp = kn->fp;
    level2(t, w2, _mm_min_pd(_mm_max_pd(_mm_add_pd(VV, _mm_loadu_pd(fp->pv[0])), z), hh), &pa, &pb, &fa, &fb);
    for (int k = 0; k < fp->n; k++) {
        const double *pa1, *pb1;
        __m128d fa1, fb1;
        level2(t, w2, _mm_min_pd(_mm_max_pd(_mm_add_pd(VV, _mm_loadu_pd(fp->pv[k + 1])), z), hh), &pa1, &pb1, &fa1,
               &fb1);
        __m128d uz = _mm_max_pd(_mm_min_pd(_mm_add_pd(UU, _mm_loadu_pd(fp->pu[k])), ww), z);
        __m128i ii = _mm_cvttpd_epi32(uz);
        __m128d fu = _mm_sub_pd(uz, _mm_cvtepi32_pd(ii));
        size_t i0 = (size_t)(uint32_t)_mm_cvtsi128_si32(ii), i1 = (size_t)(uint32_t)_mm_cvtsi128_si32(_mm_shuffle_epi32(ii, 1));
        /* each side's step: columns i and i + 1, then the column fraction,
         * both sides in the lanes of one sum */
        __m128d da = step2(pa + i0, pa1 + i0, w2, fa, fa1), db = step2(pb + i1, pb1 + i1, w2, fb, fb1);
        __m128d lo = _mm_unpacklo_pd(da, db), hi = _mm_unpackhi_pd(da, db);
        I2 = _mm_sub_pd(I2, _mm_add_pd(lo, _mm_mul_pd(fu, _mm_sub_pd(hi, lo))));
        pa = pa1, pb = pb1, fa = fa1, fb = fb1;
    }
    return _mm_cvtsd_f64(I2) + _mm_cvtsd_f64(_mm_unpackhi_pd(I2, I2));
}
#endif

/* The sample at (U, V) (inside the support) as the paint blends it: c4
 * premultiplied; 0 when it blends nothing for sure. An alpha-only type
 * gives a transparent sample too, without a branch: keep 1, colour 0. */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline int kern_sample(const mk_kern *kn, double U, double V, float c4[4])
{
    if (kn->t) {
#if defined(__SSE2__)
        double a = kern_integral(kn, U, V) * kn->ia * (1.0 / 255);
#else
        double a = fp_integral_int(kn->t, kn->w2, kn->w, kn->h, kn->fp, U, V) * kn->ia * (1.0 / 255);
#endif
        a = a > 0 ? a : 0;
        a = a < 1 ? a : 1;
        c4[0] = (float)(kn->col[0] * a);
        c4[1] = (float)(kn->col[1] * a);
        c4[2] = (float)(kn->col[2] * a);
        c4[3] = (float)a;
        return 1;
    }
    sample4(kn->m, kn->fp, U, V, c4);
    return c4[3] > 0;
}

/* c4 blended over pixel o of a planar row (row length w). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void blend(const float c4[4], float *o, size_t w, uint64_t *painted)
{
    *painted += c4[3] > 0;
    float keep = 1.0f - c4[3];
    o[0] = o[0] * keep + c4[0];
    o[w] = o[w] * keep + c4[1];
    o[2 * w] = o[2 * w] * keep + c4[2];
}

/* What a marking's pixels go to: blended over the piece, or (rc) kept as
 * the marking's blends made in the build. */
typedef struct mk_rec {
    rs_ctx *ctx;
    rs__mk_pre *e;
    size_t n, cap, max;
    int full; /* out of memory or past max: the marking stays painted per piece */
} mk_rec;

static void rec_put(mk_rec *rc, const mk_kern *kn, double U, double V, long x, long y)
{
    float c4[4];
    if (!kern_sample(kn, U, V, c4)) return;
    /* o (1 - 0) + 0 = o: nothing to keep */
    if (!(c4[3] != 0 || c4[0] != 0 || c4[1] != 0 || c4[2] != 0)) return;
    if (rc->n == rc->cap) {
        size_t nc = rc->cap ? 2 * rc->cap : 4096, bytes;
        if (nc > rc->max) nc = rc->max;
        rs__mk_pre *ne = nc > rc->n && rs__mul_size(nc, sizeof *ne, &bytes) ? rs__realloc(rc->ctx, rc->e, bytes) : NULL;
        if (!ne) {
            rc->full = 1;
            return;
        }
        rc->e = ne;
        rc->cap = nc;
    }
    rs__mk_pre *e = &rc->e[rc->n++];
    e->x = (uint32_t)x;
    e->y = (uint32_t)y;
    memcpy(e->c, c4, sizeof e->c);
}

#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void kern_put(const mk_kern *kn, double U, double V, float *o, size_t w, uint64_t *painted)
{
    float c4[4];
    if (kern_sample(kn, U, V, c4)) blend(c4, o, w, painted);
}

/* Under a deck: a pixel centre (x, y) that a higher road of another
 * stroke holds (rs__markings_set_levels). */
static int held_above(const rs__markings *mk, const rs__mk *m, double x, double y)
{
    return rs__roadfield_held_above(mk->lv_field, x, y, mk->lv, mk->lv_stroke, mk->lv[m->road], mk->lv_stroke[m->road]);
}

/* Row spans are widened by this many pixels: far above the rounding of
 * the per-pixel test (about 1e-12 of a pixel), so every pixel it passes
 * is in the span, whichever piece holds it. */
#define SPAN_EPS 1e-4

/* ceil(e - SPAN_EPS) and floor(e + SPAN_EPS) for e clamped to [-2, w + 2]
 * (spans are clamped to [0, w) anyway): integer conversions, no libm. */
static long span_lo(double e, double w)
{
    e = e > -2 ? e : -2; /* NaN: -2 */
    e = e < w + 2 ? e : w + 2;
    e = e + 2 - SPAN_EPS;
    long t = (long)e;
    return t + ((double)t < e) - 2;
}

static long span_hi(double e, double w)
{
    e = e > -2 ? e : -2;
    e = e < w + 2 ? e : w + 2;
    return (long)(e + 2 + SPAN_EPS) - 2;
}

/* Narrows columns [*k0, *k1] (piece-relative) to those whose pixel centre
 * x = (gx + 1/2) pix, gx = gx0 + k, may satisfy lo <= a + b (gx + 1/2) <=
 * hi (ib = 1 / b). Returns 0 when none. */
static int slab(double a, double b, double ib, double lo, double hi, double gx0, double w, long *k0, long *k1)
{
    if (b == 0) return a >= lo && a <= hi;
    double e0 = (lo - a) * ib - 0.5 - gx0, e1 = (hi - a) * ib - 0.5 - gx0;
    long l0 = span_lo(e0 < e1 ? e0 : e1, w), l1 = span_hi(e0 < e1 ? e1 : e0, w);
    if (l0 > *k0) *k0 = l0;
    if (l1 < *k1) *k1 = l1;
    return *k0 <= *k1;
}

/* The span of row centre y on a marking with a curved stretch: the hull
 * of its parts (build_parts: each segment's rectangle of the support, the
 * wedge at each vertex where that vertex is the nearest point), from
 * bounds linear in y; selects rather than branches. */
static int curved_span(const rs__markings *mk, const rs__mk *m, double y, double gx0, double w, long *k0, long *k1)
{
    const double *P = mk->parts + RS__MK_PART * m->part, ipix = 1 / mk->pix;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t k = 0; k < m->nparts; k++, P += RS__MK_PART) {
        double l0 = P[0] + P[1] * y, l1 = P[4] + P[5] * y, h0 = P[2] + P[3] * y, h1 = P[6] + P[7] * y;
        double e0 = l0 > l1 ? l0 : l1, e1 = h0 < h1 ? h0 : h1;
        int ok = (y >= P[8]) & (y <= P[9]);
        if (P[12] >= 0) {
            double dy = y - P[11], r2 = P[12] * P[12] - dy * dy, h = sqrt(r2 > 0 ? r2 : 0);
            double d0 = (P[10] - h) * ipix, d1 = (P[10] + h) * ipix;
            e0 = e0 > d0 ? e0 : d0;
            e1 = e1 < d1 ? e1 : d1;
            ok &= r2 >= 0;
        }
        ok &= e0 <= e1 + 2 * SPAN_EPS;
        e0 = ok ? e0 : INFINITY;
        e1 = ok ? e1 : -INFINITY;
        lo = e0 < lo ? e0 : lo;
        hi = e1 > hi ? e1 : hi;
    }
    if (!(lo <= hi + 2 * SPAN_EPS)) return 0;
    /* K = gx0 + k + 1/2 */
    long l0 = span_lo(lo - 0.5 - gx0, w), l1 = span_hi(hi - 0.5 - gx0, w);
    if (l0 > *k0) *k0 = l0;
    if (l1 < *k1) *k1 = l1;
    return *k0 <= *k1;
}

/* The piece's rows [*r0, *r1] whose centres the box holds; 0: none. */
static int box_rows(const rs__mk *m, const rs__piece *p, double ipix, long *r0, long *r1)
{
    /* ipix = 1 / pix: its rounding is far below SPAN_EPS */
    *r0 = span_lo(m->by0 * ipix - 0.5 - (double)p->y0, (double)p->rows);
    *r1 = span_hi(m->by1 * ipix - 0.5 - (double)p->y0, (double)p->rows);
    if (*r0 < 0) *r0 = 0;
    if (*r1 > (long)p->rows - 1) *r1 = (long)p->rows - 1;
    return *r0 <= *r1;
}

/* A marking on a one-segment stretch: U, V affine in the pixel centre.
 * rc: its pixels kept (the piece is the whole image; no q, no sc). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void each_straight(const rs__markings *mk, const rs__mk *m, rs__piece *p, uint64_t *tests,
                                 uint64_t *painted, mk_rec *rc)
{
    const size_t w = p->w;
    const double pix = mk->pix, gx0 = (double)p->x0, wd = (double)w;
    const double ulo = m->ulo, uhi = m->uhi, vlo = m->vlo, vhi = m->vhi, bu = m->bu, bv = m->bv;
    long r0, r1;
    if (!box_rows(m, p, 1 / pix, &r0, &r1)) return;
    mk_kern kn;
    kern_init(&kn, m, &m->fp);
    for (long r = r0; r <= r1; r++) {
        double y = ((double)p->y0 + (double)r + 0.5) * pix;
        long k0 = 0, k1 = (long)w - 1;
        double ur = m->au + m->buy * y, vr = m->av + m->bvy * y;
        if (m->flat) {
            if (!slab(ur, bu, m->ibu, ulo, uhi, gx0, wd, &k0, &k1) || !slab(vr, bv, m->ibv, vlo, vhi, gx0, wd, &k0, &k1))
                continue;
        } else {
            /* both slabs, bounds ordered by the slopes' signs: no branch */
            double a0 = (m->ua - ur) * m->ibu, a1 = (m->ub - ur) * m->ibu;
            double b0 = (m->va - vr) * m->ibv, b1 = (m->vb - vr) * m->ibv;
            double e0 = a0 > b0 ? a0 : b0, e1 = a1 < b1 ? a1 : b1;
            long l0 = span_lo(e0 - 0.5 - gx0, wd), l1 = span_hi(e1 - 0.5 - gx0, wd);
            k0 = l0 > 0 ? l0 : 0;
            k1 = l1 < k1 ? l1 : k1;
            if (k0 > k1) continue;
        }
        float *sc = rc ? NULL : p->sc + (size_t)r * w * 3;
        const uint16_t *q = rc ? NULL : p->q + (size_t)r * w;
        for (long k = k0; k <= k1; k++) {
            if (!rc && q[k] == 0) continue;
            ++*tests;
            double gx = gx0 + (double)k + 0.5;
            double u = ur + bu * gx, v = vr + bv * gx;
            if (!(u >= ulo && u < uhi && v >= vlo && v < vhi)) continue;
            if (m->under && held_above(mk, m, gx * pix, y)) continue;
            if (rc) rec_put(rc, &kn, u, v, (long)p->x0 + k, (long)p->y0 + r);
            else kern_put(&kn, u, v, sc + k, w, painted);
        }
    }
}

static void paint_straight(const rs__markings *mk, const rs__mk *m, rs__piece *p, uint64_t *tests, uint64_t *painted)
{
    each_straight(mk, m, p, tests, painted, NULL);
}

#define MAX_ROW_SEG 8

/* A marking on a curved stretch: the nearest point per pixel (rc: as
 * each_straight). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void each_curved(const rs__markings *mk, const rs__mk *m, rs__piece *p, uint64_t *tests,
                               uint64_t *painted, mk_rec *rc)
{
    const size_t w = p->w;
    const double pix = mk->pix, gx0 = (double)p->x0, wd = (double)w;
    const double *pts = mk->pts + RS__MK_PT * m->first;
    const double ulo = m->ulo, uhi = m->uhi, vlo = m->vlo, vhi = m->vhi;
    /* at most MAX_ROW_SEG segments: per row, each segment's u and t
     * affine in the column */
    const size_t nseg = m->npt - 1;
    const int rowseg = nseg <= MAX_ROW_SEG;
    double su0[MAX_ROW_SEG], su1[MAX_ROW_SEG], st0[MAX_ROW_SEG], st1[MAX_ROW_SEG];
    /* the footprint of the nearest segment's direction (kept while the
     * nearest segment stays the same) */
    const rs__mk_fp *fps = mk->fps + m->fpi;
    const double ax0 = m->tex->ax0, ax1 = m->tex->ax1 + 1, ay0 = m->tex->ay0, ay1 = m->tex->ay1 + 1;
    mk_kern kn;
    size_t fp_seg = SIZE_MAX;
    long r0, r1;
    if (!box_rows(m, p, 1 / pix, &r0, &r1)) return;
    for (long r = r0; r <= r1; r++) {
        double y = ((double)p->y0 + (double)r + 0.5) * pix;
        long k0 = 0, k1 = (long)w - 1;
        if (!curved_span(mk, m, y, gx0, wd, &k0, &k1)) continue;
        for (size_t k = 0; rowseg && k < nseg; k++) {
            const double *A = pts + RS__MK_PT * k;
            double dy = y - A[1];
            su0[k] = dy * A[4] - A[0] * A[3];
            su1[k] = A[3] * pix;
            st0[k] = -A[0] * A[4] - dy * A[3];
            st1[k] = A[4] * pix;
        }
        float *sc = rc ? NULL : p->sc + (size_t)r * w * 3;
        const uint16_t *q = rc ? NULL : p->q + (size_t)r * w;
        for (long k = k0; k <= k1; k++) {
            if (!rc && q[k] == 0) continue;
            ++*tests;
            double gx = gx0 + (double)k + 0.5, u, v;
            size_t seg;
            if (nseg == 2) {
                /* the common bend: rowseg's loop unrolled, same arithmetic */
                const double *A = pts, *B = pts + RS__MK_PT;
                double uu0 = su0[0] + su1[0] * gx, tt0 = st0[0] + st1[0] * gx;
                double uu1 = su0[1] + su1[1] * gx, tt1 = st0[1] + st1[1] * gx;
                double uc0 = uu0 < A[6] ? A[6] : uu0, uc1 = uu1 < B[6] ? B[6] : uu1;
                uc0 = uc0 > A[7] ? A[7] : uc0;
                uc1 = uc1 > B[7] ? B[7] : uc1;
                double e0 = uu0 - uc0, e1 = uu1 - uc1;
                double d0 = e0 * e0 + tt0 * tt0, d1 = e1 * e1 + tt1 * tt1;
                d0 = A[5] > 0 ? d0 : INFINITY;
                d1 = B[5] > 0 ? d1 : INFINITY;
                int one = d1 < d0;
                seg = (size_t)one;
                double best = one ? d1 : d0, tt = one ? tt1 : tt0, sv = one ? B[2] + uc1 : A[2] + uc0;
                u = m->cu + m->su * (copysign(sqrt(best), tt) - m->t0);
                v = m->cv + m->sv * (sv - m->s0);
            } else if (rowseg) {
                /* road_coords with each segment's u, t from the row's
                 * coefficients: the distance to the clamped point is
                 * hypot(u - uc, t), its side the sign of t */
                double best = INFINITY;
                size_t bk = 0;
                for (size_t kk = 0; kk < nseg; kk++) {
                    const double *A = pts + RS__MK_PT * kk;
                    double uu = su0[kk] + su1[kk] * gx, tt = st0[kk] + st1[kk] * gx;
                    double uc = uu < A[6] ? A[6] : uu;
                    uc = uc > A[7] ? A[7] : uc;
                    double e = uu - uc, d2 = e * e + tt * tt;
                    d2 = A[5] > 0 ? d2 : INFINITY;
                    bk = d2 < best ? kk : bk;
                    best = d2 < best ? d2 : best;
                }
                seg = bk;
                const double *A = pts + RS__MK_PT * bk;
                double uu = su0[bk] + su1[bk] * gx, tt = st0[bk] + st1[bk] * gx;
                double uc = uu < A[6] ? A[6] : uu;
                uc = uc > A[7] ? A[7] : uc;
                u = m->cu + m->su * (copysign(sqrt(best), tt) - m->t0);
                v = m->cv + m->sv * (A[2] + uc - m->s0);
            } else {
                double s, t;
                road_coords(pts, m->npt, gx * pix, y, &s, &t, &seg);
                u = m->cu + m->su * (t - m->t0);
                v = m->cv + m->sv * (s - m->s0);
            }
            if (!(u >= ulo && u < uhi && v >= vlo && v < vhi)) continue;
            /* the support of this segment's footprint (ulo..vhi: of any
             * direction): outside it the sample is 0 */
            const rs__mk_fp *fp = fps + seg;
            if (!(u >= ax0 - fp->hu && u < ax1 + fp->hu && v >= ay0 - fp->hv && v < ay1 + fp->hv)) continue;
            if (m->under && held_above(mk, m, gx * pix, y)) continue;
            if (seg != fp_seg) {
                kern_init(&kn, m, fp);
                fp_seg = seg;
            }
            if (rc) rec_put(rc, &kn, u, v, (long)p->x0 + k, (long)p->y0 + r);
            else kern_put(&kn, u, v, sc + k, w, painted);
        }
    }
}

static void paint_curved(const rs__markings *mk, const rs__mk *m, rs__piece *p, uint64_t *tests, uint64_t *painted)
{
    each_curved(mk, m, p, tests, painted, NULL);
}

/* A marking's blends made in the build, over the piece's road pixels. */
static void paint_pre(const rs__markings *mk, const rs__mk *m, rs__piece *p, uint64_t *tests, uint64_t *painted)
{
    if (m->npre == 0) return; /* (mk->pre may be NULL) */
    const rs__mk_pre *e = mk->pre + m->pre0, *end = e + m->npre;
    const uint32_t y0 = p->y0, y1 = p->y0 + p->rows, x0 = p->x0;
    const size_t w = p->w;
    while (e < end && e->y < y0) e++;
    for (; e < end && e->y < y1; e++) {
        size_t k = (size_t)(uint32_t)(e->x - x0); /* left of the piece: wraps past w */
        if (k >= w) continue;
        size_t at = (size_t)(e->y - y0) * w;
        if (p->q[at + k] == 0) continue;
        ++*tests;
        blend(e->c, p->sc + 3 * at + k, w, painted);
    }
}

/* Small markings (a box of at most PRE_MAX_PX pixels) keep their blends
 * from the build, up to PRE_MAX entries in all (24 bytes each): the
 * sprite's integral is the paint's main cost at coarse pixels, where a
 * marking covers a few pixels, and a prepared splatter paints many
 * windows and tiles. The same function makes them as the paint does, so
 * the bytes are the same. */
#define PRE_MAX_PX 256.0
#define PRE_MAX ((size_t)1 << 20)

static rs_result pre_build(rs_ctx *ctx, rs__markings *mk)
{
    rs__piece P;
    memset(&P, 0, sizeof P);
    P.w = mk->img_w;
    P.rows = mk->img_h;
    mk_rec rc = { ctx, NULL, 0, 0, PRE_MAX, 0 };
    const double ipix = 1 / mk->pix;
    for (size_t i = 0; i < mk->n; i++) {
        rs__mk *m = &mk->m[i];
        m->pre0 = SIZE_MAX;
        m->npre = 0;
        if ((i & 1023) == 1023 && rs__poll(ctx)) { /* (the caller frees mk) */
            rs__free(ctx, rc.e);
            return RS_ERR_CANCELLED;
        }
        if (rc.full || P.w == 0 || P.rows == 0) continue;
        double area = ((m->by1 - m->by0) * ipix + 2) * ((m->bx1 - m->bx0) * ipix + 2);
        if (!(area <= PRE_MAX_PX) || (double)(rc.n) + area > (double)PRE_MAX) continue;
        size_t n0 = rc.n;
        uint64_t t = 0, pt = 0;
        if (m->npt == 2) each_straight(mk, m, &P, &t, &pt, &rc);
        else each_curved(mk, m, &P, &t, &pt, &rc);
        if (rc.full) {
            rc.n = n0;
            continue;
        }
        m->pre0 = n0;
        m->npre = rc.n - n0;
    }
    if (rc.n < rc.cap) {
        rs__mk_pre *ne = rs__realloc(ctx, rc.e, (rc.n ? rc.n : 1) * sizeof *ne);
        if (ne) rc.e = ne;
    }
    mk->pre = rc.e;
    mk->npre = rc.n;
    mk->bytes += rc.n * sizeof *rc.e;
    return RS_OK;
}

static void sort_u32(uint32_t *a, size_t n, uint32_t *tmp)
{
    if (n <= 32) {
        for (size_t i = 1; i < n; i++) {
            uint32_t v = a[i];
            size_t j = i;
            for (; j > 0 && a[j - 1] > v; j--) a[j] = a[j - 1];
            a[j] = v;
        }
        return;
    }
    /* LSD radix sort by 7-bit digits, skipping the digits all keys share
     * (marking indices below 2^14: two passes) */
    uint32_t all_or = 0, all_and = UINT32_MAX;
    for (size_t i = 0; i < n; i++) {
        all_or |= a[i];
        all_and &= a[i];
    }
    uint32_t *src = a, *dst = tmp;
    for (int sh = 0; sh < 32; sh += 7) {
        if (!(((all_or ^ all_and) >> sh) & 0x7Fu)) continue;
        size_t cnt[128] = { 0 };
        for (size_t i = 0; i < n; i++) cnt[(src[i] >> sh) & 0x7Fu]++;
        for (size_t b = 0, sum = 0; b < 128; b++) {
            size_t c = cnt[b];
            cnt[b] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++) dst[cnt[(src[i] >> sh) & 0x7Fu]++] = src[i];
        uint32_t *t = src;
        src = dst;
        dst = t;
    }
    if (src != a) memcpy(a, src, n * sizeof *a);
}

#define CAND_CAP 1024

/* The markings of a piece are scattered over mk->m: ask for the next ones'
 * records while painting one (a hint; nothing where the compiler has no
 * such builtin). */
#define PREFETCH_AHEAD 4
static void prefetch_mk(const rs__mk *m)
{
#if defined(__GNUC__)
    const char *c = (const char *)m;
    for (size_t o = 0; o < offsetof(rs__mk, ty); o += 64) __builtin_prefetch(c + o);
#else
    (void)m;
#endif
}

/* A curved marking's stretch points, span parts and footprints (read per
 * row and pixel; separate arrays, so not fetched with its record). */
static void prefetch_stretch(const rs__markings *mk, const rs__mk *m)
{
#if defined(__GNUC__)
    if (m->npt <= 2) return;
    const char *a = (const char *)(mk->pts + RS__MK_PT * m->first), *b = (const char *)(mk->parts + RS__MK_PART * m->part);
    const char *c = (const char *)(mk->fps + m->fpi);
    for (size_t o = 0; o < m->npt * RS__MK_PT * sizeof(double); o += 64) __builtin_prefetch(a + o);
    for (size_t o = 0; o < m->nparts * RS__MK_PART * sizeof(double); o += 64) __builtin_prefetch(b + o);
    for (size_t o = 0; o < (m->npt - 1) * sizeof *mk->fps; o += 64) __builtin_prefetch(c + o);
#else
    (void)mk;
    (void)m;
#endif
}

void rs__markings_paint(const rs__markings *mk, rs__piece *p)
{
    const double pix = mk->pix, cell = mk->cell;
    /* the piece's pixel centres */
    const double xa = ((double)p->x0 + 0.5) * pix, xb = ((double)p->x0 + (double)p->w - 0.5) * pix;
    const double ya = ((double)p->y0 + 0.5) * pix, yb = ((double)p->y0 + (double)p->rows - 0.5) * pix;
    /* a box meeting [xa, xb] has cell_of(x1) >= cell_of(xa), and so on
     * (division and floor are monotonic) */
    const uint32_t cx0 = cell_of(xa, cell, mk->ox, mk->gw), cx1 = cell_of(xb, cell, mk->ox, mk->gw);
    const uint32_t cy0 = cell_of(ya, cell, mk->oy, mk->gh), cy1 = cell_of(yb, cell, mk->oy, mk->gh);
    uint32_t cand[CAND_CAP], tmp[CAND_CAP];
    uint64_t tests = 0, painted = 0;
    /* the markings whose box meets the piece, each once (from the first of
     * its cells that the piece's cells hold), in ascending index; in
     * index ranges that hold at most CAND_CAP of them */
    uint32_t lo = 0, hi = UINT32_MAX;
    for (;;) {
        size_t n = 0;
        int over = 0;
        for (uint32_t cy = cy0; cy <= cy1 && !over; cy++) {
            /* the row's cells cx0..cx1 are one run of the list */
            size_t c0 = (size_t)cy * mk->gw;
            for (uint32_t k = mk->start[c0 + cx0], ke = mk->start[c0 + cx1 + 1]; k < ke; k++) {
                const rs__mk_ref *e = &mk->list[k];
                if (e->i < lo || e->i > hi) continue;
                if ((e->x1 < xa) | (e->x0 > xb) | (e->y1 < ya) | (e->y0 > yb)) continue;
                /* once: from the first of its cells that the piece's cells hold */
                if (((e->lx > cx0) & (e->cx < e->lx)) | ((cy > cy0) & (e->cy < cy))) continue;
                if (n == CAND_CAP) {
                    over = 1;
                    break;
                }
                cand[n++] = e->i;
            }
        }
        if (over) {
            hi = lo + (hi - lo) / 2;
            continue;
        }
        sort_u32(cand, n, tmp);
        for (size_t k = 0; k < n && k < PREFETCH_AHEAD; k++) prefetch_mk(&mk->m[mk->at[cand[k]]]);
        for (size_t k = 0; k < n; k++) {
            if (k + PREFETCH_AHEAD < n) prefetch_mk(&mk->m[mk->at[cand[k + PREFETCH_AHEAD]]]);
            if (k + 2 < n) prefetch_stretch(mk, &mk->m[mk->at[cand[k + 2]]]);
            const rs__mk *m = &mk->m[mk->at[cand[k]]];
            if (m->pre0 != SIZE_MAX) paint_pre(mk, m, p, &tests, &painted);
            else if (m->npt == 2) paint_straight(mk, m, p, &tests, &painted);
            else paint_curved(mk, m, p, &tests, &painted);
        }
        if (hi == UINT32_MAX) break;
        lo = hi + 1;
        hi = UINT32_MAX;
    }
    p->mark_tests += tests;
    p->mark_pixels += painted;
}

/* Road r's box in local metres (the road set's box of its points, kept
 * with its print), grown by its half width and a slack far above the
 * roundings (the T trims only take away); 0 when it has no finite one. */
static int road_box(const rs_roads *roads, size_t r, const rs__local_frame *F, double b[4])
{
    uint64_t print;
    double w;
    const double *wb;
    rs__roads_road_print(roads, r, &print, &w, &wb);
    /* (rs__local_coord is monotone: the corners' images bound the points') */
    b[0] = rs__local_coord(wb[0], F->ox, F->per_unit), b[1] = rs__local_coord(wb[1], F->oy, F->per_unit);
    b[2] = rs__local_coord(wb[2], F->ox, F->per_unit), b[3] = rs__local_coord(wb[3], F->oy, F->per_unit);
    double g = 0.5 * w;
    g += 1e-9 * (1 + g + fabs(b[0]) + fabs(b[1]) + fabs(b[2]) + fabs(b[3]));
    b[0] -= g, b[1] -= g, b[2] += g, b[3] += g;
    return b[0] <= b[2] && b[1] <= b[3] && isfinite(b[0]) && isfinite(b[1]) && isfinite(b[2]) && isfinite(b[3]);
}

/* Road q over a marking into its deck print: the road set's print of it
 * (width, points and attributes, so its level; not its index, which an
 * edit elsewhere may change). */
static uint64_t deck_mix(uint64_t h, const rs_roads *roads, size_t q)
{
    uint64_t print;
    double w;
    const double *wb;
    rs__roads_road_print(roads, q, &print, &w, &wb);
    return rs__fp_mix(h, print);
}

rs_result rs__markings_set_levels(rs_ctx *ctx, rs__markings *mk, const rs_dem *dem, const rs_roads *roads,
                                  const rs_network *net, const struct rs__roadfield *field, const rs__tees *tees,
                                  uint32_t texels)
{
    if (!mk || !mk->n) return RS_OK;
    size_t n = rs_roads_count(roads);
    if (!net || rs_network_road_count(net) != n) return RS_OK; /* (no strokes: a bridge record would hide its own road's) */
    rs_result res = RS_OK;
    int32_t lo = INT32_MAX, hi = INT32_MIN, *lv = rs__alloc_array(ctx, n ? n : 1, sizeof *lv);
    uint32_t *st = NULL;
    size_t *ri = NULL, nr = 0, nunder = 0;
    double *rb = NULL;
    if (!lv) goto nomem;
    for (size_t i = 0; i < n; i++) {
        if ((i & 4095) == 4095 && rs__poll(ctx)) {
            res = RS_ERR_CANCELLED;
            goto done;
        }
        lv[i] = rs__road_level(roads, i);
        lo = lv[i] < lo ? lv[i] : lo;
        hi = lv[i] > hi ? lv[i] : hi;
    }
    if (!(lo < hi)) goto done; /* one level: nothing lies under anything */
    /* the raised roads (above the lowest level) and their boxes */
    for (size_t i = 0; i < n; i++) nr += lv[i] > lo;
    st = rs__alloc_array(ctx, n, sizeof *st);
    ri = rs__alloc_array(ctx, nr ? nr : 1, sizeof *ri);
    rb = rs__alloc_array(ctx, nr ? nr : 1, 4 * sizeof *rb);
    if (!st || !ri || !rb) goto nomem;
    for (size_t i = 0; i < n; i++) st[i] = net->stroke_of[i];
    nr = 0;
    const rs__local_frame F = rs__local_frame_of(dem->frame.origin_x, dem->frame.origin_y, dem->frame.cell_size);
    for (size_t i = 0; i < n; i++)
        if (lv[i] > lo && road_box(roads, i, &F, rb + 4 * nr)) ri[nr++] = i;
    /* a marking is under a deck where a higher road of another stroke meets
     * its box; many of both: every marking below the top level is asked
     * per pixel (the same pixels, slower), and its print is of every raised
     * road. The print lets an edit of a road over a marking (moved, its
     * level changed, removed) change the marking's edit piece
     * (lib/scene/grid_edit.c): the marking's own print does not. */
    int all = (double)nr * (double)mk->n > 1e7;
    uint64_t all_print = 0x6b1d;
    for (size_t j = 0; all && j < nr; j++) all_print = deck_mix(all_print, roads, ri[j]);
    for (size_t k = 0; k < mk->n; k++) {
        if ((k & 1023) == 1023 && rs__poll(ctx)) {
            res = RS_ERR_CANCELLED;
            goto done;
        }
        rs__mk *m = &mk->m[k];
        const int32_t level = lv[m->road];
        const uint32_t stroke = st[m->road];
        m->under = 0;
        m->deck = 0;
        if (level >= hi) continue;
        if (all) {
            m->under = 1;
            m->deck = all_print;
        }
        for (size_t j = 0; j < nr && !all; j++) {
            size_t q = ri[j];
            if (!(lv[q] > level) || st[q] == stroke) continue;
            const double *b = rb + 4 * j;
            if (b[2] < m->bx0 || b[0] > m->bx1 || b[3] < m->by0 || b[1] > m->by1) continue;
            m->deck = deck_mix(m->under ? m->deck : 0x6b1d, roads, q);
            m->under = 1;
        }
        if (m->under) {
            m->pre0 = SIZE_MAX; /* (its blends from the build knew no decks: painted per piece) */
            m->npre = 0;
            nunder++;
        }
    }
    if (nunder && !field) {
        /* alpha-map edges: the grid has no road field; the same question
         * on a field of these roads with the build's T ends, as the
         * analytic grid's (only the surfaces and strips are asked, which
         * no index cell changes) */
        rs__roadfield_params fp = rs__roadfield_params_for_dem(dem, texels);
        if ((res = rs__roadfield_build(ctx, roads, &fp, &mk->lv_own)) == RS_OK && tees && tees->n)
            res = rs__roadfield_set_tees(ctx, mk->lv_own, roads, tees->t, tees->n);
        if (res != RS_OK) {
            rs__roadfield_free(ctx, mk->lv_own);
            mk->lv_own = NULL;
            goto done;
        }
        mk->bytes += rs__roadfield_bytes(mk->lv_own);
        field = mk->lv_own;
    }
    if (nunder) { /* kept for the paint */
        mk->lv_field = field;
        mk->lv = lv;
        mk->lv_stroke = st;
        mk->bytes += n * (sizeof *lv + sizeof *st);
        lv = NULL;
        st = NULL;
    }
    goto done;
nomem:
    res = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
done:
    rs__free(ctx, lv);
    rs__free(ctx, st);
    rs__free(ctx, ri);
    rs__free(ctx, rb);
    return res;
}
