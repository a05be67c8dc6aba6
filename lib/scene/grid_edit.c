/* Edits with dirty rectangles (issue 30; docs/embedding.md "Edits and dirty
 * rectangles"): rs_road_grid_update, rs_road_grid_dirty,
 * rs_road_grid_rect_has_roads.
 *
 * A grid built with opts->grid.edits keeps its pieces (lib/scene/grid_edit.h): each road cut into
 * chunks of about 10 m, each chunk as a core (pixels wholly road whatever
 * the width and casing) and two rims; discs at the road's ends and bends;
 * the strip of a trimmed end at a T; the line symbols' convex pieces
 * (straight ones in stretches along their segment, with the cuts that
 * reach each stretch); the markings. A piece has a fingerprint of what
 * the build made that decides how it is drawn (never a road index: a
 * removal's renumbering changes nothing) and a region holding every pixel
 * its paint reaches. A pixel's colour is made from the pieces whose
 * regions hold it, so the pixels an edit can change lie in the regions of
 * the pieces found in only one of the two grids: the fingerprints are
 * compared as multisets, the regions of the unmatched ones rasterised
 * row by row (less the cores of unchanged roads where no fill shows which
 * road is on top), and the runs stacked into rectangles. */
#include "grid_edit.h"
#include "roadgrid.h"
#include "styling.h"
#include "linesym.h"
#include "markings.h"
#include "network.h"
#include "roadfield.h"
#include "lanes.h"
#include "road_local.h"
#include "dem.h"
#include "splatter.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CHUNK_M 10.0   /* metres of road per chunk ... */
#define CHUNK_PX 16.0  /* ... and at least this many pixels */
#define MAX_BIN_ENTRIES (1u << 26)
#define MAX_BINS (1u << 22)
#define MAX_SPLIT 4096          /* pieces of one long segment */
#define MAX_PIECES (1u << 21)   /* pieces of a grid: beyond, it keeps none (every edit dirties the whole
                                   image, every rectangle may have roads) */
#define MAX_SPANS (1u << 22)    /* pixel runs of an update: beyond, the whole image is dirty */

/* ---- fingerprints ---------------------------------------------------------- */

#define mix rs__fp_mix
#define mixd rs__fp_mixd

#define mixs rs__fp_mixs

/* A through road as a T end sees it: width, first and last points (its
 * attributes act through what they resolve to: the T's edge lines). */
static uint64_t road_sig(const rs_roads *roads, size_t q)
{
    const double *xy;
    size_t n = 0;
    double w = 0;
    rs_roads_get(roads, q, NULL, &w, &xy, &n);
    uint64_t h = mixd(0x5167, w);
    if (n >= 2) {
        const size_t at[4] = { 0, 1, n - 2, n - 1 };
        for (int k = 0; k < 4; k++) h = mixd(mixd(h, xy[2 * at[k]]), xy[2 * at[k] + 1]);
    }
    return h;
}

/* Per road end: the T it ends at, for the T's own pieces (the road the
 * end continues into changes no pixel of the surface: the fields join
 * capsules by geometry alone; its lines are pieces of their own). */
typedef struct road_ends {
    uint64_t h[2];
    double tee[2]; /* a trimmed end at a T: how far past the end point the through road's far edge lies
                      across it (0: no T), and the through road's normal */
    double tnx[2], tny[2];
    double thw[2]; /* rs__tee_end.far: the far edge line lies this far past the end point along n */
} road_ends;

/* What a road's surface draws (not its lines and markings, which are
 * pieces of their own, nor its attributes, which act through what they
 * resolve to), in two parts: the core, pixels within rc of the centre line
 * (wholly road whatever the width and casing: the fill, gradient, surface
 * image and priority decide them), and the rim out to the paint reach
 * (width, casing and everything of the core). */
typedef struct road_fp {
    uint64_t core, rim;
    double hw, reach, rc; /* rc < 0: no core */
    int s_matters;
    road_ends E;
    size_t clip0, clip1; /* segments [0, clip0) and [clip1, n - 1) may be clipped at a T (tee_run) */
} road_fp;

static void road_prints(const rs_roads *roads, size_t i, const rs__styling *st, const rs_network *net,
                        double core_in, road_fp *F)
{
    double w = 0;
    rs_roads_get(roads, i, NULL, &w, NULL, NULL);
    uint64_t c = 0xc0e, m = mixd(0x5a4f, w);
    double hw = 0.5 * w, r = hw;
    int image = 0, shade = 0;
    /* only what differs from an unstyled road: a road draws alike in a
     * grid with styles and in one without */
    if (st && i < st->nroads) {
        /* how the casings are drawn: the grid's field widened or a field
         * of their own (wider than an index cell), and one colour for all
         * (C - R blended) or each pixel the colour of its nearest road's
         * casing, none when that road has none. The ways differ at a
         * side road's edge in a T mouth, and an edit of any road's casing
         * may switch them (fuzz/edits: a far road's new casing colour took
         * the casing off a pixel where a road without one meets one with) */
        if (st->casing) m = mix(mix(m, st->casing_merged ? 0xca51 : 0xca52), st->casing_uniform ? 0xca53 : 0xca54);
        uint64_t sf = st->surface ? st->surface[i] : 0;
        shade = sf == RS_SURFACE_GRADIENT;
        if (sf != RS_SURFACE_DEFAULT && st->colour) {
            c = mix(c, sf);
            for (int k = 0; k < 12; k++) c = mixd(c, (double)st->colour[16 * i + (size_t)k]); /* fill, gradient */
        }
        if (st->half_width && st->half_width[i] != hw) m = mixd(m, st->half_width[i]);
        if (st->casing_width && st->casing_width[i] > 0) {
            m = mixd(m, st->casing_width[i]);
            if (st->colour)
                for (int k = 12; k < 16; k++) m = mixd(m, (double)st->colour[16 * i + (size_t)k]); /* casing */
            if (hw + st->casing_width[i] > r) r = hw + st->casing_width[i];
        }
        /* the priority picks the fill where surfaces overlap; with no
         * fill, gradient or image anywhere it draws nothing (line cuts by
         * priority are in the line pieces) */
        if (st->prio && st->any_surface) c = mix(mix(c, 0x9e10), (uint64_t)(int64_t)st->prio[i]);
        if (st->img_of && st->img_of[i] >= 0) {
            image = 1;
            c = mix(c, (uint64_t)(int64_t)st->img_of[i]);
            c = mixd(mixd(c, st->img_len[i]), st->img_f[i]);
            c = mix(c, st->img_lev[i]);
            if (st->img_s0) c = mixd(c, st->img_s0[i]);
            if (st->img_rev) c = mix(c, st->img_rev[i]);
        }
    }
    /* a road's level decides where a bridge's casing lies over it (its
     * surface, core and rim) and where its own casing lies over the roads
     * below (lib/splat/overlays.c decks); level 0 leaves the prints as
     * they were */
    const int level = rs__road_level(roads, i);
    if (level) c = mix(mix(c, 0x1e7e), (uint64_t)(int64_t)level), m = mix(mix(m, 0x1e7e), (uint64_t)(int64_t)level);
    if (image && net && i < net->nroads) c = mix(mixd(c, net->s_off[i]), net->rev[i]);
    if (image || shade) c = mixd(c, hw); /* mapped across the width */
    F->hw = hw;
    F->reach = r;
    F->rc = hw - core_in;
    if (!(F->rc > 0)) F->rc = -1;
    F->core = mixd(c, F->rc);
    F->rim = mix(m, c);
    F->s_matters = image;
}

/* ---- the pieces ------------------------------------------------------------ */

typedef struct builder {
    rs_ctx *ctx;
    rs__grid_edit *e;
    double pix, chunk, devmax;
    double mx0, my0, mx1, my1; /* the map, grown by what any pad can add */
    double cell;               /* the largest index cell of the fields that trim ends at T's */
    uint32_t kind;             /* RS__EI_* of the pieces pushed */
    int win_on;                /* 1: only pieces whose box meets win are kept (a patch's) */
    double win[4];
} builder;

static void item_box(const rs__edit_item *it, double pad, double *x0, double *y0, double *x1, double *y1);

static rs_result push(builder *b, uint64_t h, double ax, double ay, double bx, double by, double r)
{
    rs__grid_edit *e = b->e;
    if (b->win_on) { /* (NaN: kept) */
        rs__edit_item q;
        double x0, y0, x1, y1;
        q.ax = ax, q.ay = ay, q.bx = bx, q.by = by, q.r = r;
        item_box(&q, 0, &x0, &y0, &x1, &y1);
        if (x1 < b->win[0] || x0 > b->win[2] || y1 < b->win[1] || y0 > b->win[3]) return RS_OK;
    }
    if (e->n >= MAX_PIECES) {
        e->over = 1;
        return RS_OK;
    }
    if (e->n == e->cap) {
        size_t nc = e->cap ? 2 * e->cap : 256, bytes;
        if (nc < e->cap || !rs__mul_size(nc, sizeof *e->it, &bytes))
            return rs__fail(b->ctx, RS_ERR_NOMEM, "out of memory for the grid's edit pieces");
        rs__edit_item *it = rs__realloc(b->ctx, e->it, bytes);
        if (!it) return rs__fail(b->ctx, RS_ERR_NOMEM, "out of memory for the grid's edit pieces");
        e->it = it;
        e->cap = nc;
    }
    rs__edit_item *it = &e->it[e->n++];
    it->h = rs__fp_final(h);
    it->ax = ax, it->ay = ay, it->bx = bx, it->by = by, it->r = r;
    it->dev = 0;
    it->kind = b->kind;
    return RS_OK;
}

static void end_info(const rs_roads *roads, size_t i, const rs__tee_end *tees, const size_t *tee_of, road_ends *E)
{
    memset(E, 0, sizeof *E);
    for (int e = 0; e < 2; e++) {
        uint64_t h = mix(0xe0d, (uint64_t)e);
        if (tee_of && tee_of[2 * i + (size_t)e] != SIZE_MAX) {
            const rs__tee_end *t = &tees[tee_of[2 * i + (size_t)e]];
            h = mixd(mixd(mixd(mixd(h, t->nx), t->ny), t->far), t->grow);
            h = mix(h, road_sig(roads, t->through));
            E->tee[e] = t->far + t->grow + 2 * RS__NETWORK_TOL;
            E->tnx[e] = t->nx, E->tny[e] = t->ny;
            E->thw[e] = t->far;
        }
        E->h[e] = h;
    }
}

/* Cut segment (ax, ay)-(bx, by) to the box: fractions [*t0, *t1]; 0 when
 * it misses. */
static int clip_box(const builder *b, double ax, double ay, double bx, double by, double grow, double *t0, double *t1)
{
    double p[4] = { -(bx - ax), bx - ax, -(by - ay), by - ay };
    double q[4] = { ax - (b->mx0 - grow), (b->mx1 + grow) - ax, ay - (b->my0 - grow), (b->my1 + grow) - ay };
    double lo = 0, hi = 1;
    for (int k = 0; k < 4; k++) {
        if (p[k] == 0) {
            if (q[k] < 0) return 0;
            continue;
        }
        double t = q[k] / p[k];
        if (p[k] < 0) {
            if (t > lo) lo = t;
        } else if (t < hi) hi = t;
    }
    *t0 = lo, *t1 = hi;
    return lo <= hi;
}

/* Segment (ax, ay)-(bx, by) cut to the map grown by `grow`, measured from
 * its end nearer the origin (a point at 1e52 m would otherwise swamp the
 * cut's position: ua near 1 rounds to it): o = that end, d = the other
 * minus it, [*t0, *t1] the part kept; 0 when it misses. */
static int clip_near(const builder *b, double ax, double ay, double bx, double by, double grow, double o[2], double d[2],
                     double *t0, double *t1)
{
    if (fabs(ax) + fabs(ay) > fabs(bx) + fabs(by)) {
        double tx = ax, ty = ay;
        ax = bx, ay = by, bx = tx, by = ty;
    }
    o[0] = ax, o[1] = ay, d[0] = bx - ax, d[1] = by - ay;
    return clip_box(b, ax, ay, bx, by, grow, t0, t1);
}

/* A stretch of road from a to b (straight within dev, its directions
 * within angle th of the chord): the core capsule and the rims on both
 * sides as capsules of the chord moved sideways. hc, hr: the stretch's
 * core and rim fingerprints. tee: the stretch ends at a trimmed end at a T,
 * past which its core capsule may reach off the road (it is then no core
 * for the updates' subtraction). */
static rs_result stretch(builder *b, const road_fp *F, uint64_t hc, uint64_t hr, double ax, double ay, double bx,
                         double by, double dev, double th, int tee)
{
    rs_result r = RS_OK;
    if (F->rc > 0) {
        b->kind = tee ? RS__EI_SURFACE : RS__EI_CORE;
        size_t n0 = b->e->n;
        r = push(b, hc, ax, ay, bx, by, F->rc + dev);
        if (!r && b->e->n > n0) b->e->it[b->e->n - 1].dev = nextafterf((float)dev, INFINITY);
        b->kind = RS__EI_SURFACE;
    }
    double lo = F->rc > 0 ? F->rc : 0, mid = 0.5 * (lo + F->reach), half = 0.5 * (F->reach - lo);
    double dx = bx - ax, dy = by - ay, l = hypot(dx, dy);
    if (!(l > 0) || !(F->rc > 0)) return r ? r : push(b, hr, ax, ay, bx, by, F->reach + dev);
    double nx = dy / l * mid, ny = -dx / l * mid, rr = half + dev + F->reach * th;
    for (int side = -1; side <= 1 && !r; side += 2)
        r = push(b, mix(hr, (uint64_t)(side + 1)), ax + side * nx, ay + side * ny, bx + side * nx, by + side * ny, rr);
    return r;
}

/* The chunk of points k0..k1 (arc: its length along the road). */
static rs_result flush(builder *b, const rs__road_local *rl, size_t k0, size_t k1, double arc, const road_fp *F)
{
    const double *x = rl->x, *y = rl->y, *s = rl->s;
    double cx = x[k1] - x[k0], cy = y[k1] - y[k0], ch = hypot(cx, cy);
    double dev = 0.5 * sqrt(fmax(0, arc * arc - ch * ch)), th = 0;
    uint64_t h = 0xc4c;
    for (size_t j = k0; j <= k1; j++) {
        h = mixd(mixd(h, x[j]), y[j]);
        if (F->s_matters) h = mixd(h, s[j]);
        if (j > k0 && ch > 0) { /* the segment's angle to the chord */
            double ux = x[j] - x[j - 1], uy = y[j] - y[j - 1], lu = hypot(ux, uy);
            if (lu > 0) {
                double c = (ux * cx + uy * cy) / (lu * ch);
                th = fmax(th, c <= 0 ? 2 : fabs(ux * cy - uy * cx) / (lu * ch) * 1.5708);
            }
        }
    }
    /* a segment of it may be clipped at a T: no core (diff matches a core
     * only with a core). What the T changes lies in its own pieces (strip,
     * box, the segments it may clip: road_pieces), so the chunk's print
     * leaves it out, and a T made or lost by an edit elsewhere (a class
     * change of the through road) dirties the T, not the chunk. */
    int tee = k0 < F->clip0 || k1 > F->clip1;
    return stretch(b, F, mix(F->core, h), mix(F->rim, h), x[k0], y[k0], x[k1], y[k1], dev, th, tee);
}

/* A segment longer than a chunk, cut to the map and split evenly. */
static rs_result split_long(builder *b, const rs__road_local *rl, size_t k, const road_fp *F)
{
    const double *x = rl->x, *y = rl->y;
    double len = rl->s[k + 1] - rl->s[k], t0, t1, o[2], d[2];
    if (!clip_near(b, x[k], y[k], x[k + 1], y[k + 1], F->reach, o, d, &t0, &t1)) return RS_OK;
    /* pieces of a chunk, or of the road's reach when that is wider (its
     * region is then mostly reach), at most MAX_SPLIT */
    double m = ceil((t1 - t0) * len / fmax(b->chunk, F->reach));
    if (!(m >= 1)) m = 1;
    if (m > MAX_SPLIT) m = MAX_SPLIT;
    rs_result r = RS_OK;
    for (double j = 0; j < m && !r; j++) {
        double ua = t0 + (t1 - t0) * j / m, ub = j + 1 == m ? t1 : t0 + (t1 - t0) * (j + 1) / m;
        uint64_t h = 0x5e9;
        h = mixd(mixd(mixd(mixd(h, x[k]), y[k]), x[k + 1]), y[k + 1]);
        h = mixd(mixd(h, ua), ub);
        if (F->s_matters) h = mixd(h, rl->s[k]);
        r = stretch(b, F, mix(F->core, h), mix(F->rim, h), o[0] + ua * d[0], o[1] + ua * d[1], o[0] + ub * d[0],
                    o[1] + ub * d[1], 0, 0, k < F->clip0 || k >= F->clip1);
    }
    return r;
}

/* A disc of the rim around point k (a road end's cap, a bend's join). */
static rs_result joint(builder *b, const rs__road_local *rl, size_t k, const road_fp *F)
{
    uint64_t h = mix(F->rim, 0x7015);
    for (size_t j = k ? k - 1 : k; j <= k + 1 && j < rl->n; j++) h = mixd(mixd(h, rl->x[j]), rl->y[j]);
    return push(b, h, rl->x[k], rl->y[k], rl->x[k], rl->y[k], F->reach);
}

/* Whether a chunk boundary at point k needs a joint: the outer side of the
 * bend opens further than the rims' round ends reach. */
static int bends(const rs__road_local *rl, size_t k, const road_fp *F)
{
    const double *x = rl->x, *y = rl->y;
    double ux = x[k] - x[k - 1], uy = y[k] - y[k - 1], vx = x[k + 1] - x[k], vy = y[k + 1] - y[k];
    double lu = hypot(ux, uy), lv = hypot(vx, vy);
    if (!(lu > 0 && lv > 0)) return 1;
    double c = (ux * vx + uy * vy) / (lu * lv), sn = fabs(ux * vy - uy * vx) / (lu * lv);
    double lo = F->rc > 0 ? F->rc : 0;
    return c <= 0 || F->reach * sn > 0.25 * (F->reach - lo);
}

/* How many segments from end e on the fields may clip at its T
 * (rs__roadfield_set_tees: the end segment, then along the record while
 * a segment's capsule reaches past the through road's far edge line; the
 * test here looser: reach >= a segment's half width, cell >= a field's
 * index cell). A slanting leg loses one edge over many metres: found by
 * fuzz/edits, a T's removal dirtied the end alone. 0: no T there. */
static size_t tee_run(const rs__road_local *rl, const road_fp *F, double cell, int e)
{
    size_t n = rl->n, run = 0;
    if (n < 2 || !(F->E.tee[e] > 0)) return 0;
    const double *x = rl->x, *y = rl->y, nx = F->E.tnx[e], ny = F->E.tny[e];
    size_t k = e ? n - 1 : 0;
    double cE = nx * x[k] + ny * y[k];
    double lim = cE + F->E.thw[e] - 1e-6 * (1 + fabs(cE)), rad = F->reach + cell;
    for (size_t j = k; e ? j > 0 : j + 1 < n; j = e ? j - 1 : j + 1, run++) {
        size_t i2 = e ? j - 1 : j + 1;
        if (j != k && !(fmax(nx * x[j] + ny * y[j], nx * x[i2] + ny * y[i2]) + rad > lim)) break;
    }
    return run;
}

/* The strip of end e when it is a trimmed end at a T: the unit direction
 * (*dx, *dy) of its end segment towards the end, *sn = its sine against
 * the T line (at least 0.2) and how far the strip runs on past the end
 * point, the widest shape's (a casing strip's corner reaches further
 * along). 0: no T there, or a zero-length end segment. */
static int tee_strip(const rs__road_local *rl, const road_fp *F, int e, double *dx, double *dy, double *sn, double *far)
{
    size_t n = rl->n, k = e ? n - 1 : 0, q = e ? n - 2 : 1;
    if (n < 2 || !(F->E.tee[e] > 0)) return 0;
    double ux = rl->x[k] - rl->x[q], uy = rl->y[k] - rl->y[q], l = hypot(ux, uy);
    if (!(l > 0)) return 0;
    *dx = ux / l, *dy = uy / l;
    *sn = fmax(0.2, fabs(*dx * F->E.tnx[e] + *dy * F->E.tny[e]));
    *far = (F->E.tee[e] + F->reach * sqrt(fmax(0, 1 - *sn * *sn))) / *sn;
    return 1;
}

/* The box of end e's T (its strip's direction dx, dy and sine sn, from
 * tee_strip) that the road field computes again whatever road its pixels
 * lie on (lib/scene/roadfield.c tee_box, tee_pass): a neighbour's edge
 * there comes from 16 sub-rows and may round otherwise (found by
 * fuzz/edits: a through road's edge pixel 5 m from a new T end, 3/65535 in
 * weight). The box: the flat strip's corners (u from where the clip line
 * crosses the far side to where it crosses the near side, t = +-reach)
 * and the end disc, grown by the field's margin of half a pixel diagonal. */
static rs_result tee_box_piece(builder *b, const rs__road_local *rl, const road_fp *F, int e, double dx, double dy,
                               double sn, uint64_t h)
{
    size_t k = e ? rl->n - 1 : 0;
    const double *x = rl->x, *y = rl->y;
    double cs = fabs(F->E.tnx[e] * dy - F->E.tny[e] * dx), R = F->reach;
    double ua = fmin((F->E.tee[e] - R * cs) / sn, 0), ub = fmax((F->E.tee[e] + R * cs) / sn, 0);
    double bx0 = x[k] - R, bx1 = x[k] + R, by0 = y[k] - R, by1 = y[k] + R;
    for (int c = 0; c < 4; c++) {
        double u = c & 1 ? ub : ua, t = c & 2 ? R : -R;
        double px = x[k] + u * dx + t * dy, py = y[k] + u * dy - t * dx;
        bx0 = fmin(bx0, px), bx1 = fmax(bx1, px), by0 = fmin(by0, py), by1 = fmax(by1, py);
    }
    double mg = 0.7072 * b->pix + 1e-9 * (1 + fabs(x[k]) + fabs(y[k]) + R + ub - ua);
    return push(b, h, bx0 - mg, by0 - mg, bx1 + mg, by1 + mg, -1);
}

static rs_result road_pieces(builder *b, const rs__road_local *rl, const road_fp *F)
{
    size_t n = rl->n;
    const double *x = rl->x, *y = rl->y, *s = rl->s;
    rs_result r = RS_OK;
    if (n == 0) return RS_OK;
    road_fp G = *F;
    G.clip0 = tee_run(rl, F, b->cell, 0);
    G.clip1 = n - 1 - tee_run(rl, F, b->cell, 1);
    F = &G;
    r = joint(b, rl, 0, F);
    if (n == 1) return r;
    if (!r) r = joint(b, rl, n - 1, F);
    /* a trimmed end at a T: the strip runs on to the through road's far
     * edge line (its corners included) */
    for (int e = 0; e < 2 && !r; e++) {
        size_t k = e ? n - 1 : 0, q = e ? n - 2 : 1;
        double dx, dy, sn, far;
        if (!tee_strip(rl, F, e, &dx, &dy, &sn, &far)) continue;
        uint64_t h = mix(mix(mix(F->rim, 0x7ee), F->E.h[e]), (uint64_t)e);
        h = mixd(mixd(mixd(mixd(h, x[k]), y[k]), x[q]), y[q]);
        r = push(b, h, x[k], y[k], x[k] + far * dx, y[k] + far * dy, F->reach);
        /* the road field computes the pixels of the T's box again (tee_box_piece) */
        if (!r) r = tee_box_piece(b, rl, F, e, dx, dy, sn, mix(h, 0xb0c5));
        /* and the segments a field may clip (tee_run, counted above): of
         * each, the part whose capsule may reach the end's normal line
         * (centre line at n.p >= n.E - reach, a pixel diagonal and rounding
         * less). A field's trimmed shape differs from the capsule only past
         * its clip line, which lies beyond E, and past E along the end
         * segment (lib/scene/roadfield.c tee_box); the rest of the segment
         * draws alike with or without the T, so a T made or lost by an
         * edit elsewhere dirties only the mouth. */
        size_t run = e ? n - 1 - F->clip1 : F->clip0;
        double tn = F->E.tnx[e], tm = F->E.tny[e], cE = tn * x[k] + tm * y[k];
        double L = cE - F->reach - 0.7072 * b->pix - 1e-6 * (1 + fabs(cE) + F->reach);
        for (size_t i = 0; i < run && !r; i++) {
            size_t j = e ? n - 1 - i : i, i2 = e ? j - 1 : j + 1;
            double o[2], d[2], t0, t1;
            if (!clip_near(b, x[j], y[j], x[i2], y[i2], F->reach, o, d, &t0, &t1)) continue;
            double no = tn * o[0] + tm * o[1], nd = tn * d[0] + tm * d[1];
            if (nd > 0) t0 = fmax(t0, (L - no) / nd);
            else if (nd < 0) t1 = fmin(t1, (L - no) / nd);
            else if (no < L) t0 = 2; /* (none of it) */
            uint64_t hi = mix(h, 0xbac + (uint64_t)i);
            if (t0 <= t1) {
                r = push(b, hi, o[0] + t0 * d[0], o[1] + t0 * d[1], o[0] + t1 * d[0], o[1] + t1 * d[1], F->reach);
                continue;
            }
            /* (not reaching the line: a field still takes the box around its
             * point nearest the line, r and a margin a side, as a T box) */
            size_t po = o[0] == x[j] && o[1] == y[j] ? j : i2, pf = nd >= 0 ? j + i2 - po : po;
            double px = x[pf], py = y[pf];
            double R = F->reach + 0.7072 * b->pix + 1e-9 * (1 + fabs(px) + fabs(py) + F->reach);
            r = push(b, mix(hi, 0xb0c5), px - R, py - R, px + R, py + R, -1);
        }
        /* a run over the whole record reaches the other end's segment,
         * whose trimmed shape, at a T there, runs on in its strip: the
         * clip may take the strip too, however far along it reaches
         * (fuzz/edits b0e8f047: a hairpin's start became a T whose line
         * took its far end's strip, 28 m long). That strip's region again,
         * as a piece of this T's. */
        int oe = !e;
        double ox, oy, osn, ofar;
        if (!r && run >= n - 1 && tee_strip(rl, F, oe, &ox, &oy, &osn, &ofar)) {
            size_t ko = oe ? n - 1 : 0;
            uint64_t ho = mix(mix(h, F->E.h[oe]), 0x0e5);
            r = push(b, ho, x[ko], y[ko], x[ko] + ofar * ox, y[ko] + ofar * oy, F->reach);
            /* and its box, which the road field computes again (the strip's
             * far corners and a pixel's margin: fuzz/edits, 6 December
             * 2026: a road starting inside one street and ending inside it
             * had its start's T moved to a road added there; the pixels at
             * the tip of its end's 23 m strip changed, outside the capsule) */
            if (!r) r = tee_box_piece(b, rl, F, oe, ox, oy, osn, mix(ho, 0xb0c5));
        }
    }
    /* chunks: runs of short segments up to a chunk of arc staying near
     * their chord; long segments cut to the map and split; a joint where
     * a chunk ends at a bend */
    size_t k0 = 0;
    double arc = 0;
    for (size_t k = 0; k + 1 < n && !r; k++) {
        double len = s[k + 1] - s[k];
        if (len > b->chunk) {
            if (k > k0) r = flush(b, rl, k0, k, arc, F);
            if (!r && k > 0 && bends(rl, k, F)) r = joint(b, rl, k, F);
            if (!r) r = split_long(b, rl, k, F);
            if (!r && k + 2 < n && bends(rl, k + 1, F)) r = joint(b, rl, k + 1, F);
            k0 = k + 1;
            arc = 0;
            continue;
        }
        double na = arc + len, ch = hypot(x[k + 1] - x[k0], y[k + 1] - y[k0]);
        double dev = 0.5 * sqrt(fmax(0, na * na - ch * ch)), th = 0;
        if (k > k0 && ch > 0) {
            double ux = x[k + 1] - x[k], uy = y[k + 1] - y[k], cx = x[k + 1] - x[k0], cy = y[k + 1] - y[k0];
            th = fabs(ux * cy - uy * cx) / (hypot(ux, uy) * ch);
            if (ux * cx + uy * cy <= 0) th = 1;
        }
        if (k > k0 && (na > b->chunk || dev > b->devmax || th > 0.1 || k - k0 >= 64)) {
            r = flush(b, rl, k0, k, arc, F);
            if (!r && bends(rl, k, F)) r = joint(b, rl, k, F);
            k0 = k;
            na = len;
        }
        arc = na;
    }
    if (!r && k0 + 1 < n) r = flush(b, rl, k0, n - 1, arc, F);
    return r;
}

/* A slab of the line symbols in stretches of a chunk along u, anchored at
 * its frame's origin (the same stretches whatever cuts its ends): each
 * with the slab's fingerprint, its part of the u range and the
 * half-planes that cut a pixel centre in it (all of them with Hermite
 * smoothing, which reads further), so that a cut far along the road
 * leaves the stretches away from it unchanged. */
static rs_result slab_pieces(builder *b, const rs__linesym_piece_view *V, int all)
{
    if (!(V->ru0 <= V->ru1 && V->rv0 <= V->rv1)) return RS_OK;
    double len = fmax(b->chunk, (V->ru1 - V->ru0) / MAX_SPLIT);
    double j0 = floor(V->ru0 / len), j1 = floor(V->ru1 / len);
    double vm = 0.5 * (V->rv0 + V->rv1), nx = V->uy, ny = -V->ux, rad = 0.5 * (V->rv1 - V->rv0);
    rs_result r = RS_OK;
    for (double j = j0; j <= j1 && !r; j++) {
        double ua = fmax(V->ru0, j * len), ub = fmin(V->ru1, (j + 1) * len);
        if (ua > ub) continue;
        uint64_t h = mixd(mixd(mix(V->h, 0x51ab), ua), ub);
        for (uint32_t q = 0; q < V->nhp; q++) {
            const double *hp = V->hp + 4 * (size_t)q;
            double lo = hp[0] + fmin(hp[1] * ua, hp[1] * ub) + fmin(hp[2] * V->rv0, hp[2] * V->rv1);
            double eps = 1e-9 * (1 + fabs(hp[0]) + fabs(hp[1]) * fmax(fabs(ua), fabs(ub)) +
                                 fabs(hp[2]) * fmax(fabs(V->rv0), fabs(V->rv1)) + hp[3]);
            if (!all && lo >= hp[3] + eps) continue; /* cuts no pixel centre here */
            h = mixd(mixd(mixd(mixd(h, hp[0]), hp[1]), hp[2]), hp[3]);
        }
        b->kind = RS__EI_PAINT_AT;
        r = push(b, h, V->ox + ua * V->ux + vm * nx, V->oy + ua * V->uy + vm * ny, V->ox + ub * V->ux + vm * nx,
                 V->oy + ub * V->uy + vm * ny, rad);
        b->kind = RS__EI_PAINT;
    }
    return r;
}

static rs_result line_and_mark_pieces(builder *b, const rs_road_grid *g)
{
    rs_result r = RS_OK;
    b->kind = RS__EI_PAINT;
    const rs__linesym *L = g->styling ? g->styling->lines : NULL;
    size_t np = rs__linesym_piece_count(L);
    for (size_t k = 0; k < np && !r; k++) {
        if (rs__tick(b->ctx, 0)) {
            r = RS_ERR_CANCELLED;
            break;
        }
        rs__linesym_piece_view V;
        rs__linesym_piece_get(L, k, &V);
        if (!V.slab) {
            if (V.reg[0] <= V.reg[2]) r = push(b, V.h, V.reg[0], V.reg[1], V.reg[2], V.reg[3], V.reg[4]);
            continue;
        }
        r = slab_pieces(b, &V, g->style.aa == RS_LINE_AA_HERMITE);
    }
    const rs__markings *mk = g->markings;
    for (size_t k = 0; mk && k < mk->n && !r; k++) {
        const rs__mk *m = &mk->m[k];
        uint64_t h = mixs(0x3a2c, m->ty ? m->ty->name : "");
        const double f[] = { m->s0, m->t0, m->hl, m->hw, m->kx, m->ky, m->ulo, m->uhi, m->vlo, m->vhi,
                             m->slo, m->shi, m->tlo, m->thi, m->bx0, m->by0, m->bx1, m->by1 };
        for (size_t j = 0; j < sizeof f / sizeof f[0]; j++) h = mixd(h, f[j]);
        h = mix(h, (uint64_t)m->flip);
        /* under a bridge's deck: the roads over it leave out its pixels there */
        if (m->under) h = mix(mix(h, 0x7d3e), m->deck);
        for (size_t j = 0; j < m->npt * RS__MK_PT; j++) h = mixd(h, mk->pts[RS__MK_PT * m->first + j]);
        if (m->npt == 2) { /* one segment: the support is a rectangle in (s, t); its capsule along its longer side */
            const double *A = mk->pts + RS__MK_PT * m->first;
            double sl = m->shi - m->slo, tl = m->thi - m->tlo, sm = 0.5 * (m->slo + m->shi), tm = 0.5 * (m->tlo + m->thi);
            double s0 = sl >= tl ? m->slo : sm, s1 = sl >= tl ? m->shi : sm, t0 = sl >= tl ? tm : m->tlo,
                   t1 = sl >= tl ? tm : m->thi;
            double px0 = A[0] + (s0 - A[2]) * A[3] + t0 * A[4], py0 = A[1] + (s0 - A[2]) * A[4] - t0 * A[3];
            double px1 = A[0] + (s1 - A[2]) * A[3] + t1 * A[4], py1 = A[1] + (s1 - A[2]) * A[4] - t1 * A[3];
            double rad = 0.5 * (sl >= tl ? tl : sl) + 1e-9 * (1 + fabs(px0) + fabs(py0) + sl + tl);
            double area = (fabs(px1 - px0) + 2 * rad) * (fabs(py1 - py0) + 2 * rad);
            if (area < (m->bx1 - m->bx0) * (m->by1 - m->by0)) {
                r = push(b, h, px0, py0, px1, py1, rad);
                continue;
            }
        }
        r = push(b, h, m->bx0, m->by0, m->bx1, m->by1, -1);
    }
    return r;
}

/* An item's box, grown by pad. */
static void item_box(const rs__edit_item *it, double pad, double *x0, double *y0, double *x1, double *y1)
{
    double r = (it->r < 0 ? 0 : it->r) + pad;
    *x0 = fmin(it->ax, it->bx) - r;
    *x1 = fmax(it->ax, it->bx) + r;
    *y0 = fmin(it->ay, it->by) - r;
    *y1 = fmax(it->ay, it->by) + r;
}

static uint32_t bin_of(double v, double bin, uint32_t nb)
{
    double q = floor(v / bin);
    if (!(q > 0)) return 0;
    if (q >= nb) return nb - 1;
    return (uint32_t)q;
}

static rs_result build_bins(rs_ctx *ctx, rs__grid_edit *e, double wm, double hm, double chunk)
{
    double bin = sqrt(wm * hm / (double)(e->n + 1));
    if (!(bin >= 2 * chunk)) bin = 2 * chunk;
    for (;;) {
        double bw = ceil(wm / bin), bh = ceil(hm / bin);
        if (bw < 1) bw = 1;
        if (bh < 1) bh = 1;
        if (bw * bh > MAX_BINS) {
            bin *= 2;
            continue;
        }
        e->bin = bin;
        e->bw = (uint32_t)bw;
        e->bh = (uint32_t)bh;
        uint64_t total = 0;
        for (size_t i = 0; i < e->n; i++) {
            double x0, y0, x1, y1;
            item_box(&e->it[i], 0, &x0, &y0, &x1, &y1);
            total += (uint64_t)(bin_of(x1, bin, e->bw) - bin_of(x0, bin, e->bw) + 1) *
                     (bin_of(y1, bin, e->bh) - bin_of(y0, bin, e->bh) + 1);
        }
        if (total > MAX_BIN_ENTRIES) {
            bin *= 2;
            continue;
        }
        size_t nb = (size_t)e->bw * e->bh;
        e->bstart = rs__calloc(ctx, nb + 1, sizeof *e->bstart);
        e->bitem = rs__alloc_array(ctx, total ? (size_t)total : 1, sizeof *e->bitem);
        if (!e->bstart || !e->bitem) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the grid's edit index");
        for (int pass = 0; pass < 2; pass++) {
            for (size_t i = 0; i < e->n; i++) {
                double x0, y0, x1, y1;
                item_box(&e->it[i], 0, &x0, &y0, &x1, &y1);
                uint32_t i0 = bin_of(x0, bin, e->bw), i1 = bin_of(x1, bin, e->bw);
                uint32_t j0 = bin_of(y0, bin, e->bh), j1 = bin_of(y1, bin, e->bh);
                for (uint32_t j = j0; j <= j1; j++)
                    for (uint32_t k = i0; k <= i1; k++) {
                        size_t c = (size_t)j * e->bw + k;
                        if (pass == 0) e->bstart[c + 1]++;
                        else e->bitem[e->bstart[c]++] = (uint32_t)i;
                    }
            }
            if (pass == 0)
                for (size_t c = 0; c < nb; c++) e->bstart[c + 1] += e->bstart[c];
            else {
                for (size_t c = nb; c > 0; c--) e->bstart[c] = e->bstart[c - 1];
                e->bstart[0] = 0;
            }
        }
        e->bytes += (nb + 1) * sizeof *e->bstart + (size_t)total * sizeof *e->bitem;
        return RS_OK;
    }
}

void rs__grid_edit_free(rs_ctx *ctx, rs__grid_edit *e)
{
    if (!e) return;
    rs__free(ctx, e->it);
    rs__free(ctx, e->bstart);
    rs__free(ctx, e->bitem);
    rs__free(ctx, e->dirty);
    rs__free(ctx, e);
}

static double grid_pad(const rs_road_grid *g);

/* Does every piece of road i lie outside b's window? Its pieces lie
 * within its points' box grown by: a chunk's capsule (the reach, its
 * deviation, a stretch's reach again), a T end's strip and box (the far
 * edge past the end and the reach, over a sine of at least 0.2), a pixel,
 * and a metre for the local frame's rounding. NaN or infinite: no. */
static int far_from(const builder *b, const rs_roads *roads, size_t i, const road_fp *F, const rs_dem *dem)
{
    const double *xy;
    size_t np;
    rs_roads_get(roads, i, NULL, NULL, &xy, &np);
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    for (size_t k = 0; k < np; k++) {
        x0 = fmin(x0, xy[2 * k]), x1 = fmax(x1, xy[2 * k]);
        y0 = fmin(y0, xy[2 * k + 1]), y1 = fmax(y1, xy[2 * k + 1]);
    }
    double tee = fmax(fmax(F->E.tee[0], F->E.tee[1]), 0);
    double g = 3 * F->reach + b->devmax + 5 * (tee + F->reach) + 2 * b->pix + 1;
    double ox = dem->frame.origin_x, oy = dem->frame.origin_y;
    if (!(g < 1e300) || !(x0 <= x1 && y0 <= y1)) return 0;
    return x0 - ox - g > b->win[2] || x1 - ox + g < b->win[0] || y0 - oy - g > b->win[3] || y1 - oy + g < b->win[1];
}

rs_result rs__grid_edit_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                              const rs_network *net, const rs__tees *T, const double *window, rs_road_grid *g)
{
    size_t nr = rs_roads_count(roads);
    const rs__styling *st = g->styling;
    double cs = dem->frame.cell_size, pix = cs / o->texels;
    double wm = (double)(dem->width - 1) * cs, hm = (double)(dem->height - 1) * cs;
    rs__grid_edit *e = rs__calloc(ctx, 1, sizeof *e);
    size_t *tee_of = NULL;
    rs__tee_end *tees = NULL;
    size_t ntees = 0;
    rs_result r = RS_OK;
    if (!e) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the grid's edit pieces");
    if (!r && net && nr) {
        r = rs__tee_ends_from(ctx, T, roads, net, &tees, &ntees);
        if (!r && ntees) {
            tee_of = rs__alloc_array(ctx, 2 * nr, sizeof *tee_of);
            if (!tee_of) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the grid's edit pieces");
            for (size_t k = 0; !r && k < 2 * nr; k++) tee_of[k] = SIZE_MAX;
            for (size_t k = 0; !r && k < ntees; k++)
                if (tees[k].road < nr) tee_of[2 * (size_t)tees[k].road + (tees[k].end ? 1 : 0)] = k;
            /* a casing strip stops at the through road's casing edge
             * (lib/scene/styling.c): its corners reach that much further */
            for (size_t k = 0; !r && st && st->casing_width && k < ntees; k++)
                if (tees[k].through < st->nroads && st->casing_width[tees[k].through] > 0)
                    tees[k].grow = st->casing_width[tees[k].through];
        }
    }
    /* the core: pixels whose centre lies half a pixel diagonal inside the
     * surface, which the road field's coverage takes as wholly road at
     * once (docs/roadfield.md "Coverage"; with alpha-map edges, also the
     * road cells around them: at most 2 road cells of the automatic K a
     * texel, 2 forced road cells) */
    double core_in = 0.7072 * pix + 1e-6 * (1 + fmax(wm, hm));
    if (o->coverage.edges == RS_EDGES_ALPHAMAP) core_in += 4 * (o->grid.road_cell > 0 ? 2 * o->grid.road_cell : 0.5 * pix);
    builder b;
    memset(&b, 0, sizeof b);
    b.ctx = ctx;
    b.e = e;
    b.pix = pix;
    b.chunk = fmax(CHUNK_M, CHUNK_PX * pix);
    b.devmax = fmax(0.25, 0.5 * pix);
    b.kind = RS__EI_SURFACE;
    if (g->field) b.cell = rs__roadfield_cell(g->field);
    if (st && st->casing) b.cell = fmax(b.cell, rs__roadfield_cell(st->casing));
    /* (a bridge's casing over the roads below shows which is on top too) */
    if (e) e->fills = st && (st->any_surface || st->img_of || st->ndeck);
    /* long segments are cut to the map grown by the largest pad (an
     * alpha-map road cell is at most a DEM cell) */
    double grow = 4 * cs + 4 * pix + 1;
    b.mx0 = -grow, b.my0 = -grow, b.mx1 = wm + grow, b.my1 = hm + grow;
    if (window) {
        /* a patch's pieces: those an update reads (rs__patch_candidates:
         * the pieces meeting the patch's rectangle grown by a grid's pad;
         * an equal piece of another grid lies there too), with room */
        double wp = grid_pad(g) + 4 * pix + 4;
        b.win_on = 1;
        b.win[0] = window[0] - wp, b.win[1] = window[1] - wp, b.win[2] = window[2] + wp, b.win[3] = window[3] + wp;
    }
    for (size_t i = 0; !r && i < nr; i++) {
        if (rs__tick(ctx, 0)) { /* a poll every RS__TICK_POLLS roads: the build's cancel */
            r = RS_ERR_CANCELLED;
            break;
        }
        road_fp F;
        road_prints(roads, i, st, net, core_in, &F);
        end_info(roads, i, tees, tee_of, &F.E);
        if (b.win_on && far_from(&b, roads, i, &F, dem)) continue; /* (a patch's: none of its pieces is kept) */
        rs__road_local rl;
        memset(&rl, 0, sizeof rl);
        if (rs__road_local_get(ctx, roads, i, dem, &rl)) {
            r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the grid's edit pieces");
            break;
        }
        r = road_pieces(&b, &rl, &F);
        rs__road_local_free(ctx, &rl);
    }
    if (!r) r = line_and_mark_pieces(&b, g);
    if (!r && e->over) {
        rs__free(ctx, e->it);
        e->it = NULL;
        e->n = e->cap = 0;
    }
    if (!r && e->n && e->n < e->cap) { /* to size: the grid keeps them */
        rs__edit_item *it = rs__realloc(ctx, e->it, e->n * sizeof *e->it);
        if (it) e->it = it, e->cap = e->n;
    }
    if (!r) r = build_bins(ctx, e, wm, hm, b.chunk);
    rs__free(ctx, tee_of);
    rs__free(ctx, tees);
    if (r) {
        rs__grid_edit_free(ctx, e);
        return r;
    }
    e->bytes += sizeof *e + e->cap * sizeof *e->it;
    g->edit = e;
    return RS_OK;
}

/* ---- regions in pixels ------------------------------------------------------------ */

/* What the grid adds to every region (whose pixels are those whose square
 * meets it): the road field's coverage treats a capsule whose boundary
 * comes within half a pixel diagonal of a pixel centre as near, which may
 * change the pixel's rounding (docs/roadfield.md "Coverage"), a little
 * beyond the pixels the capsule meets; with alpha-map edges the road
 * cells' marking offset and the neighbour they are classified by
 * (docs/design.md). */
static double grid_pad(const rs_road_grid *g)
{
    double pix = g->frame.cell_size / g->texels;
    return 0.2072 * pix + 0.01 + (g->tiles ? 4 * g->c : 0);
}

/* x extent of the capsule (a)-(b), radius r, on the line y = c. */
static int capsule_slice(double ax, double ay, double bx, double by, double r, double c, double *lo, double *hi)
{
    double l = INFINITY, h = -INFINITY;
    const double px[2] = { ax, bx }, py[2] = { ay, by };
    for (int k = 0; k < 2; k++) {
        double dy = c - py[k];
        if (fabs(dy) <= r) {
            double w = sqrt(r * r - dy * dy);
            l = fmin(l, px[k] - w);
            h = fmax(h, px[k] + w);
        }
    }
    double dx = bx - ax, dy = by - ay, len = hypot(dx, dy);
    if (len > 0) {
        double nx = -dy / len * r, ny = dx / len * r;
        const double cx[4] = { ax + nx, bx + nx, bx - nx, ax - nx }, cy[4] = { ay + ny, by + ny, by - ny, ay - ny };
        for (int k = 0; k < 4; k++) {
            double x0 = cx[k], y0 = cy[k], x1 = cx[(k + 1) & 3], y1 = cy[(k + 1) & 3];
            if ((y0 - c) * (y1 - c) > 0) continue;
            if (y0 == y1) {
                l = fmin(l, fmin(x0, x1));
                h = fmax(h, fmax(x0, x1));
            } else {
                double x = x0 + (c - y0) * (x1 - x0) / (y1 - y0);
                l = fmin(l, x);
                h = fmax(h, x);
            }
        }
    }
    *lo = l, *hi = h;
    return l <= h;
}

/* x extent of the region of `it` grown by pad over rows y in [ya, yb]. */
static int item_xrange(const rs__edit_item *it, double pad, double ya, double yb, double *lo, double *hi)
{
    double x0, y0, x1, y1;
    item_box(it, pad, &x0, &y0, &x1, &y1);
    if (yb < y0 || ya > y1) return 0;
    if (it->r < 0) {
        *lo = x0, *hi = x1;
        return 1;
    }
    if (ya < y0) ya = y0;
    if (yb > y1) yb = y1;
    double r = it->r + pad, l = INFINITY, h = -INFINITY, a, c;
    if (capsule_slice(it->ax, it->ay, it->bx, it->by, r, ya, &a, &c)) l = fmin(l, a), h = fmax(h, c);
    if (capsule_slice(it->ax, it->ay, it->bx, it->by, r, yb, &a, &c)) l = fmin(l, a), h = fmax(h, c);
    /* the leftmost and rightmost points of the capsule, when in the rows */
    double ylo = fmin(it->ay, it->by), yhi = fmax(it->ay, it->by);
    if (it->ax == it->bx) {
        if (!(yhi < ya || ylo > yb)) l = fmin(l, it->ax - r), h = fmax(h, it->ax + r);
    } else {
        double yl = it->ax < it->bx ? it->ay : it->by, yr = it->ax < it->bx ? it->by : it->ay;
        if (yl >= ya && yl <= yb) l = fmin(l, fmin(it->ax, it->bx) - r);
        if (yr >= ya && yr <= yb) h = fmax(h, fmax(it->ax, it->bx) + r);
    }
    *lo = l, *hi = h;
    return l <= h;
}

typedef struct span3 {
    uint32_t y, x0, x1;
} span3;

typedef struct spans {
    span3 *v;
    size_t n, cap;
    int over; /* MAX_SPANS reached: the runs are incomplete */
} spans;

static int span_push(rs_ctx *ctx, spans *S, uint32_t y, uint32_t x0, uint32_t x1)
{
    if (S->n >= MAX_SPANS) {
        S->over = 1;
        return 1;
    }
    if (S->n == S->cap) {
        size_t nc = S->cap ? 2 * S->cap : 1024, bytes;
        if (nc < S->cap || !rs__mul_size(nc, sizeof *S->v, &bytes)) return 0;
        span3 *v = rs__realloc(ctx, S->v, bytes);
        if (!v) return 0;
        S->v = v;
        S->cap = nc;
    }
    S->v[S->n].y = y, S->v[S->n].x0 = x0, S->v[S->n].x1 = x1;
    S->n++;
    return 1;
}

static uint32_t to_px(double v, uint32_t lim)
{
    if (!(v > 0)) return 0;
    if (v >= (double)lim) return lim;
    return (uint32_t)v;
}

/* The rows of item it's region (grown by pad) in a W x H image of pix metres. */
static int item_spans(rs_ctx *ctx, spans *S, const rs__edit_item *it, double pad, double pix, uint32_t W, uint32_t H)
{
    double x0, y0, x1, y1;
    item_box(it, pad, &x0, &y0, &x1, &y1);
    uint32_t r0 = to_px(floor(y0 / pix), H), r1 = to_px(floor(y1 / pix) + 1, H);
    for (uint32_t y = r0; y < r1; y++) {
        double lo, hi;
        if (!item_xrange(it, pad, y * pix, (y + 1) * pix, &lo, &hi)) continue;
        uint32_t a = to_px(floor(lo / pix), W), b = to_px(floor(hi / pix) + 1, W);
        if (a < b && !span_push(ctx, S, y, a, b)) return 0;
    }
    return 1;
}

static int cmp_span(const void *pa, const void *pb)
{
    const span3 *a = pa, *b = pb;
    if (a->y != b->y) return a->y < b->y ? -1 : 1;
    if (a->x0 != b->x0) return a->x0 < b->x0 ? -1 : 1;
    return (a->x1 > b->x1) - (a->x1 < b->x1);
}

/* Sorted by rows, a row's overlapping or touching spans merged. */
static void spans_norm(spans *S)
{
    if (S->n > 1) qsort(S->v, S->n, sizeof *S->v, cmp_span); /* (none: S->v may be NULL) */
    size_t m = 0;
    for (size_t k = 0; k < S->n; k++) {
        if (m && S->v[m - 1].y == S->v[k].y && S->v[k].x0 <= S->v[m - 1].x1) {
            if (S->v[k].x1 > S->v[m - 1].x1) S->v[m - 1].x1 = S->v[k].x1;
        } else S->v[m++] = S->v[k];
    }
    S->n = m;
}

/* Append to out the spans of A (normalised) less those of C (normalised). */
static int spans_minus(rs_ctx *ctx, const spans *A, const spans *C, spans *out)
{
    size_t c = 0;
    for (size_t k = 0; k < A->n; k++) {
        span3 a = A->v[k];
        while (c < C->n && (C->v[c].y < a.y || (C->v[c].y == a.y && C->v[c].x1 <= a.x0))) c++;
        uint32_t x = a.x0;
        for (size_t d = c; d < C->n && C->v[d].y == a.y && C->v[d].x0 < a.x1; d++) {
            if (C->v[d].x0 > x && !span_push(ctx, out, a.y, x, C->v[d].x0)) return 0;
            if (C->v[d].x1 > x) x = C->v[d].x1;
        }
        if (x < a.x1 && !span_push(ctx, out, a.y, x, a.x1)) return 0;
    }
    return 1;
}

/* The pixels whose centre is certainly in core item `it` (within its
 * radius less its centre line's stray of the segment). */
static int core_spans(rs_ctx *ctx, spans *S, const rs__edit_item *it, double pix, uint32_t W, uint32_t H)
{
    double rin = it->r - 2 * (double)it->dev;
    rin -= 1e-9 * (1 + fabs(it->ax) + fabs(it->ay) + rin);
    if (!(rin > 0)) return 1;
    double y0 = fmin(it->ay, it->by) - rin, y1 = fmax(it->ay, it->by) + rin;
    uint32_t r0 = to_px(ceil(y0 / pix - 0.5), H), r1 = to_px(floor(y1 / pix - 0.5) + 1, H);
    for (uint32_t y = r0; y < r1; y++) {
        double lo, hi;
        if (!capsule_slice(it->ax, it->ay, it->bx, it->by, rin, (y + 0.5) * pix, &lo, &hi)) continue;
        uint32_t a = to_px(ceil(lo / pix - 0.5), W), b = to_px(floor(hi / pix - 0.5) + 1, W);
        if (a < b && !span_push(ctx, S, y, a, b)) return 0;
    }
    return 1;
}

/* The pixels whose centre lies in item `it`'s region grown by pad (an
 * RS__EI_PAINT_AT piece). */
static int centre_spans(rs_ctx *ctx, spans *S, const rs__edit_item *it, double pad, double pix, uint32_t W, uint32_t H)
{
    double x0, y0, x1, y1;
    item_box(it, pad, &x0, &y0, &x1, &y1);
    uint32_t r0 = to_px(ceil(y0 / pix - 0.5), H), r1 = to_px(floor(y1 / pix - 0.5) + 1, H);
    for (uint32_t y = r0; y < r1; y++) {
        double lo = x0, hi = x1;
        if (it->r >= 0 && !capsule_slice(it->ax, it->ay, it->bx, it->by, it->r + pad, (y + 0.5) * pix, &lo, &hi)) continue;
        uint32_t a = to_px(ceil(lo / pix - 0.5), W), b = to_px(floor(hi / pix - 0.5) + 1, W);
        if (a < b && !span_push(ctx, S, y, a, b)) return 0;
    }
    return 1;
}

/* The runs of piece q that changed: a line's paint (PAINT_AT) by the pixel
 * centres it reaches into S (the road field's pad is not its business),
 * other paint by its region grown by pad into S, surfaces into Ssf. 0: no
 * memory. */
static int piece_spans(rs_ctx *ctx, spans *S, spans *Ssf, const rs__edit_item *q, double pad, double pix, uint32_t W,
                       uint32_t H)
{
    if (q->kind == RS__EI_PAINT_AT)
        return centre_spans(ctx, S, q, 1e-3 * pix + 1e-9 * (1 + fabs(q->ax) + fabs(q->ay) + fabs(q->bx) + fabs(q->by)),
                            pix, W, H);
    return item_spans(ctx, q->kind == RS__EI_PAINT ? S : Ssf, q, pad, pix, W, H);
}

/* Spans to rectangles: a row's overlapping or touching spans merged, a
 * rectangle grown down while the next row has the same span. */
static rs_result spans_to_rects(rs_ctx *ctx, spans *S, rs_pixel_rect **out, size_t *nout)
{
    *out = NULL;
    *nout = 0;
    if (!S->n) return RS_OK;
    spans_norm(S);
    size_t m = S->n;
    rs_pixel_rect *R = rs__alloc_array(ctx, m, sizeof *R);
    size_t *open = rs__alloc_array(ctx, m, sizeof *open); /* rectangles ending at the previous row, by x0 */
    size_t *next = rs__alloc_array(ctx, m, sizeof *next);
    if (!R || !open || !next) {
        rs__free(ctx, R);
        rs__free(ctx, open);
        rs__free(ctx, next);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the dirty rectangles");
    }
    size_t nr = 0, nopen = 0;
    for (size_t k = 0; k < m;) {
        uint32_t y = S->v[k].y;
        size_t nn = 0, o = 0;
        for (; k < m && S->v[k].y == y; k++) {
            const span3 *sp = &S->v[k];
            while (o < nopen && R[open[o]].x0 < sp->x0) o++;
            if (o < nopen && R[open[o]].y1 == y && R[open[o]].x0 == sp->x0 && R[open[o]].x1 == sp->x1) {
                R[open[o]].y1 = y + 1;
                next[nn++] = open[o++];
            } else {
                R[nr].x0 = sp->x0, R[nr].x1 = sp->x1, R[nr].y0 = y, R[nr].y1 = y + 1;
                next[nn++] = nr++;
            }
        }
        memcpy(open, next, nn * sizeof *open);
        nopen = nn;
    }
    rs__free(ctx, open);
    rs__free(ctx, next);
    *out = R;
    *nout = nr;
    return RS_OK;
}

/* ---- the public calls ------------------------------------------------------------ */

typedef rs__keyed keyed;

/* e's pieces' fingerprints and indices, sorted (fingerprint, then index)
 * into *out (the caller's: rs__free). */
static rs_result sorted_keys(rs_ctx *ctx, const rs__grid_edit *e, keyed **out)
{
    keyed *k = rs__alloc_array(ctx, e->n ? e->n : 1, sizeof *k);
    *out = NULL;
    if (!k) return RS_ERR_NOMEM;
    for (size_t i = 0; i < e->n; i++) k[i].h = e->it[i].h, k[i].i = k[i].pos = (uint32_t)i;
    rs_result r = rs__sort_recs(ctx, k, e->n);
    if (r) rs__free(ctx, k);
    else *out = k;
    return r;
}

/* The first of the sorted keys whose fingerprint is at least h (binary search). */
static size_t first_key(const keyed *k, size_t n, uint64_t h)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (k[mid].h < h) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* Sorted keys with a directory by their top bits (a key of fingerprint h
 * lies at or after start[h >> shift]): the fingerprints are uniform, so a
 * lookup reads a bucket of about one key, where first_key's binary search
 * missed the cache at every step (a patch's candidates look up every piece
 * near its rectangle). */
typedef struct keydir {
    const keyed *k;
    size_t n;
    uint32_t *start; /* 2^bits + 1 */
    unsigned shift;
} keydir;

static int keydir_make(rs_ctx *ctx, keydir *d, const keyed *k, size_t n)
{
    unsigned bits = 1;
    while (bits < 20 && ((size_t)1 << bits) < n) bits++;
    d->k = k, d->n = n, d->shift = 64 - bits;
    size_t nb = (size_t)1 << bits;
    if (!(d->start = rs__alloc_array(ctx, nb + 1, sizeof *d->start))) return 0;
    for (size_t b = 0, i = 0; b <= nb; b++) {
        while (i < n && (b == nb || (k[i].h >> d->shift) < b)) i++;
        d->start[b] = (uint32_t)i;
    }
    return 1;
}

/* first_key through the directory: the same index. */
static size_t dir_first(const keydir *d, uint64_t h)
{
    size_t b = (size_t)(h >> d->shift), lo = d->start[b], hi = d->start[b + 1];
    while (lo < hi && d->k[lo].h < h) lo++;
    return lo;
}

/* Whether fingerprint h is missing from the sorted keys. */
static int item_changed(const keyed *k, size_t n, uint64_t h)
{
    size_t lo = first_key(k, n, h);
    return !(lo < n && k[lo].h == h);
}

static rs_result whole_image(rs_ctx *ctx, uint32_t W, uint32_t H, rs_pixel_rect **out, size_t *nout)
{
    rs_pixel_rect *R = rs__alloc_array(ctx, 1, sizeof *R);
    if (!R) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the dirty rectangles");
    R->x0 = 0, R->y0 = 0, R->x1 = W, R->y1 = H;
    *out = R;
    *nout = 1;
    return RS_OK;
}

/* The dirty rectangles between grids a (old) and b (new). */
/* (clip: pieces outside these pixels are passed over; NULL: none) */
static int outside(const rs__edit_item *q, double pad, const rs_pixel_rect *clip, double pix)
{
    if (!clip) return 0;
    double x0, y0, x1, y1;
    item_box(q, pad, &x0, &y0, &x1, &y1);
    return x1 < clip->x0 * pix || x0 > clip->x1 * pix || y1 < clip->y0 * pix || y0 > clip->y1 * pix;
}

static rs_result diff(rs_ctx *ctx, const rs_road_grid *a, const rs_road_grid *b, const rs_pixel_rect *clip,
                      rs_pixel_rect **out, size_t *nout)
{
    double pix = b->frame.cell_size / b->texels;
    uint64_t W64 = (uint64_t)(b->dem_w - 1) * b->texels, H64 = (uint64_t)(b->dem_h - 1) * b->texels;
    uint32_t W = W64 > UINT32_MAX ? UINT32_MAX : (uint32_t)W64, H = H64 > UINT32_MAX ? UINT32_MAX : (uint32_t)H64;
    *out = NULL;
    *nout = 0;
    if (!W || !H) return RS_OK;
    if (!a->edit || !b->edit || a->edit->over || b->edit->over || a->k != b->k || a->c != b->c)
        return whole_image(ctx, W, H, out, nout);
    const rs__grid_edit *ea = a->edit, *eb = b->edit;
    keyed *ka = NULL, *kb = NULL;
    rs_result r = sorted_keys(ctx, ea, &ka);
    if (!r) r = sorted_keys(ctx, eb, &kb);
    uint8_t *kept = rs__calloc(ctx, eb->n ? eb->n : 1, 1); /* b's pieces found in a too (1), and seen (2) */
    spans S, Ssf, C;
    memset(&S, 0, sizeof S);
    memset(&Ssf, 0, sizeof Ssf);
    memset(&C, 0, sizeof C);
    if (!r && !kept) r = RS_ERR_NOMEM;
    if (r == RS_ERR_NOMEM) r = rs__fail(ctx, r, "out of memory for the dirty rectangles");
    double pa = grid_pad(a), pb = grid_pad(b);
    int ok = 1;
    size_t i = 0, j = 0;
    while (!r && ok && (i < ea->n || j < eb->n)) {
        if (i < ea->n && j < eb->n && ka[i].h == kb[j].h) {
            /* (a core only where it was one: a chunk clipped at a T in one grid is the same piece
             * but not wholly road there) */
            kept[kb[j].i] = ea->it[ka[i].i].kind == eb->it[kb[j].i].kind ? 1 : 3;
            i++, j++;
            continue;
        }
        const rs__edit_item *q;
        double pad;
        if (j >= eb->n || (i < ea->n && ka[i].h < kb[j].h)) q = &ea->it[ka[i++].i], pad = pa;
        else q = &eb->it[kb[j++].i], pad = pb;
        if (outside(q, pad, clip, pix)) continue;
        ok = piece_spans(ctx, &S, &Ssf, q, pad, pix, W, H);
    }
    /* where an unchanged road's core lies under a changed surface, the
     * pixels stay wholly road of the same colour (no fills: which road is
     * on top does not show): those pixels are not dirty */
    if (!r && ok && Ssf.n && !ea->fills && !eb->fills) {
        for (size_t k = 0; ok && k < ea->n + eb->n; k++) {
            const rs__edit_item *q = k < ea->n ? &ea->it[k] : &eb->it[k - ea->n];
            if (q->kind >= RS__EI_PAINT || (k >= ea->n && kept[k - ea->n])) continue;
            if (outside(q, k < ea->n ? pa : pb, clip, pix)) continue;
            if (k < ea->n && !item_changed(kb, eb->n, q->h)) continue;
            double x0, y0, x1, y1;
            item_box(q, k < ea->n ? pa : pb, &x0, &y0, &x1, &y1);
            uint32_t i0 = bin_of(x0, eb->bin, eb->bw), i1 = bin_of(x1, eb->bin, eb->bw);
            uint32_t j0 = bin_of(y0, eb->bin, eb->bh), j1 = bin_of(y1, eb->bin, eb->bh);
            for (uint32_t by = j0; ok && by <= j1; by++)
                for (uint32_t bx = i0; ok && bx <= i1; bx++) {
                    size_t c = (size_t)by * eb->bw + bx;
                    for (uint32_t e = eb->bstart[c]; ok && e < eb->bstart[c + 1]; e++) {
                        uint32_t t = eb->bitem[e];
                        if (kept[t] != 1 || eb->it[t].kind != RS__EI_CORE) continue;
                        kept[t] = 2;
                        ok = core_spans(ctx, &C, &eb->it[t], pix, W, H);
                    }
                }
        }
        if (ok) {
            spans_norm(&Ssf);
            spans_norm(&C);
            ok = spans_minus(ctx, &Ssf, &C, &S);
        }
    } else if (ok) {
        for (size_t k = 0; ok && k < Ssf.n; k++) ok = span_push(ctx, &S, Ssf.v[k].y, Ssf.v[k].x0, Ssf.v[k].x1);
    }
    if (!r && !ok) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the dirty rectangles");
    rs__free(ctx, ka);
    rs__free(ctx, kb);
    rs__free(ctx, kept);
    if (!r) r = S.over || Ssf.over ? whole_image(ctx, W, H, out, nout) : spans_to_rects(ctx, &S, out, nout);
    rs__free(ctx, S.v);
    rs__free(ctx, Ssf.v);
    rs__free(ctx, C.v);
    return r;
}

/* Candidate rectangles (diff's, or a patch's) narrowed to the pixels that change:
 * each rendered under both grids (unlit: the colour and weight the
 * rectangles promise, docs/embedding.md) and compared byte for byte. The
 * pieces find where a pixel may change, not whether it does: at 1.25 m
 * pixels a new casing 0.15 m wider changes one pixel of the three its rim
 * meets. Up to rs_limits.max_dirty_compare candidate pixels (2^20: ~0.25 s
 * on the styled city); beyond, and when a splatter cannot be made on a grid (another
 * DEM or options given), the candidates stand. */
#define EXACT_WINDOW 16384u /* pixels of one window */

/* Whether pixel k differs in colour or weight between renders a and b. */
static int px_differs(const uint8_t *ca, const uint16_t *wa, const uint8_t *cb, const uint16_t *wb, size_t k)
{
    return memcmp(ca + 4 * k, cb + 4 * k, 4) != 0 || wa[k] != wb[k];
}

rs_result rs__dirty_render(rs_ctx *ctx, const rs_dem *dem, const rs_splat_options *opts, const rs_road_grid *a,
                           const rs_road_grid *b, rs_pixel_rect **rects, size_t *nrects)
{
    const rs_pixel_rect *cand = *rects;
    const size_t ncand = *nrects;
    uint64_t total = 0;
    for (size_t k = 0; k < ncand; k++) total += (uint64_t)(cand[k].x1 - cand[k].x0) * (cand[k].y1 - cand[k].y0);
    if (!total || total > ctx->limits.max_dirty_compare) return RS_OK;
    rs_splat_options o = *opts;
    o.lighting.enable = 0;
    o.progress = NULL; /* (the context's, as the build's; reported as 2 units a pixel) */
    o.progress_user = NULL;
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, 2 * total, 4096);
    rs_splatter *sa = NULL, *sb = NULL;
    uint8_t *ca = rs__alloc_array(ctx, EXACT_WINDOW, 8), *cb = ca ? ca + 4 * (size_t)EXACT_WINDOW : NULL;
    uint16_t *wa = rs__alloc_array(ctx, EXACT_WINDOW, 2 * sizeof *wa), *wb = wa ? wa + EXACT_WINDOW : NULL;
    spans S;
    memset(&S, 0, sizeof S);
    rs_result r = ca && wa ? RS_OK : RS_ERR_NOMEM;
    if (!r) r = rs__splatter_create_lean(ctx, dem, a, &o, &sa);
    if (!r) r = rs__splatter_create_lean(ctx, dem, b, &o, &sb);
    int ok = 1;
    for (size_t k = 0; !r && ok && k < ncand; k++) {
        const rs_pixel_rect R = cand[k];
        for (uint32_t x = R.x0; !r && ok && x < R.x1;) {
            uint32_t cw = R.x1 - x < EXACT_WINDOW ? R.x1 - x : EXACT_WINDOW, rows = EXACT_WINDOW / cw;
            for (uint32_t y = R.y0; !r && ok && y < R.y1; y += rows) {
                uint32_t h = R.y1 - y < rows ? R.y1 - y : rows;
                r = rs_splat_window(ctx, sa, x, y, cw, h, ca, 4 * (size_t)cw, wa, cw, NULL);
                if (!r) r = rs_splat_window(ctx, sb, x, y, cw, h, cb, 4 * (size_t)cw, wb, cw, NULL);
                for (uint32_t j = 0; !r && ok && j < h; j++) {
                    const size_t row = (size_t)j * cw;
                    for (uint32_t i = 0; ok && i < cw;) {
                        while (i < cw && !px_differs(ca, wa, cb, wb, row + i)) i++;
                        uint32_t i0 = i;
                        while (i < cw && px_differs(ca, wa, cb, wb, row + i)) i++;
                        if (i > i0) ok = span_push(ctx, &S, y + j, x + i0, x + i);
                    }
                }
                if (!r && rs__tick(ctx, 2 * (uint64_t)cw * h)) r = RS_ERR_CANCELLED;
            }
            x += cw;
        }
    }
    rs_splatter_free(ctx, sa);
    rs_splatter_free(ctx, sb);
    rs__free(ctx, ca);
    rs__free(ctx, wa);
    if (!r && !ok) r = RS_ERR_NOMEM;
    if (!r && !S.over) {
        rs_pixel_rect *nr = NULL;
        size_t nn = 0;
        r = spans_to_rects(ctx, &S, &nr, &nn);
        if (!r) {
            rs__free(ctx, *rects);
            *rects = nr;
            *nrects = nn;
        }
    }
    rs__free(ctx, S.v);
    /* (anything but a cancel leaves the candidates: a superset) */
    if (r && r != RS_ERR_CANCELLED) r = RS_OK;
    return rs__progress_end(ctx, &pg, r);
}

/* The kind of e's pieces of fingerprint h (keys k[0..n): some of e's,
 * sorted; RS__EI_SURFACE when their kinds differ), or -1 when none of them
 * has it; *count: how many have it. */
static int kind_of(const keydir *d, const rs__grid_edit *e, uint64_t h, size_t *count)
{
    const keyed *k = d->k;
    const size_t n = d->n;
    size_t lo = dir_first(d, h), c = 0;
    int kind = -1;
    for (; lo + c < n && k[lo + c].h == h; c++) {
        int q = (int)e->it[k[lo + c].i].kind;
        kind = c == 0 || q == kind ? q : RS__EI_SURFACE; /* (mixed: no core) */
    }
    *count = c;
    return kind;
}

/* How many of the sorted keys are fingerprint h. */
static size_t count_of(const keydir *d, uint64_t h)
{
    const keyed *k = d->k;
    const size_t n = d->n;
    size_t lo = dir_first(d, h), c = 0;
    while (lo + c < n && k[lo + c].h == h) c++;
    return c;
}

/* Per key of the sorted keys, at its place before the sort (pos): how many
 * keys have its fingerprint. A piece drawn twice (a road given twice: its
 * partly covered line pixels take the paint twice) draws otherwise than
 * once. NULL on no memory. */
static uint32_t *run_counts(rs_ctx *ctx, const keyed *k, size_t n)
{
    uint32_t *c = rs__alloc_array(ctx, n ? n : 1, sizeof *c);
    if (!c) return NULL;
    for (size_t a = 0, b; a < n; a = b) {
        for (b = a + 1; b < n && k[b].h == k[a].h; b++) {}
        for (size_t j = a; j < b; j++) c[k[j].pos] = (uint32_t)(b - a);
    }
    return c;
}

/* The pieces of e whose regions (no pad) meet box [x0, x1] x [y0, y1]
 * (metres), ascending, from its bins: *ids_out (the caller's: rs__free),
 * *n; their keys sorted in *keys (also the caller's). */
static rs_result near_items(rs_ctx *ctx, const rs__grid_edit *e, double x0, double y0, double x1, double y1,
                            uint32_t **ids_out, size_t *n, keyed **keys)
{
    size_t m = 0;
    uint32_t *ids = NULL;
    int all = !e->bstart || (bin_of(x0, e->bin, e->bw) == 0 && bin_of(y0, e->bin, e->bh) == 0 &&
                             bin_of(x1, e->bin, e->bw) == e->bw - 1 && bin_of(y1, e->bin, e->bh) == e->bh - 1);
    if (all) {
        if (!(ids = rs__alloc_array(ctx, e->n ? e->n : 1, sizeof *ids))) return RS_ERR_NOMEM;
        for (size_t i = 0; i < e->n; i++) ids[i] = (uint32_t)i;
        m = e->n;
    } else {
        uint32_t i0 = bin_of(x0, e->bin, e->bw), i1 = bin_of(x1, e->bin, e->bw);
        uint32_t j0 = bin_of(y0, e->bin, e->bh), j1 = bin_of(y1, e->bin, e->bh);
        size_t total = 0;
        for (uint32_t j = j0; j <= j1; j++) total += e->bstart[(size_t)j * e->bw + i1 + 1] - e->bstart[(size_t)j * e->bw + i0];
        /* (each piece once, ascending: a bit per piece, not a sort) */
        uint64_t *seen = rs__calloc(ctx, e->n / 64 + 1, sizeof *seen);
        if (!seen || !(ids = rs__alloc_array(ctx, total ? total : 1, sizeof *ids))) {
            rs__free(ctx, seen);
            return RS_ERR_NOMEM;
        }
        for (uint32_t j = j0; j <= j1; j++)
            for (uint32_t b = e->bstart[(size_t)j * e->bw + i0]; b < e->bstart[(size_t)j * e->bw + i1 + 1]; b++)
                seen[e->bitem[b] / 64] |= (uint64_t)1 << (e->bitem[b] % 64);
        for (size_t w = 0; w <= e->n / 64; w++)
            for (uint64_t bits = seen[w]; bits; bits &= bits - 1) {
                uint32_t i = (uint32_t)(64 * w), v = 0;
                while (!((bits >> v) & 1)) v++;
                i += v;
                double a0, b0, a1, b1;
                item_box(&e->it[i], 0, &a0, &b0, &a1, &b1);
                if (a1 < x0 || a0 > x1 || b1 < y0 || b0 > y1) continue;
                ids[m++] = i;
            }
        rs__free(ctx, seen);
    }
    keyed *k = rs__alloc_array(ctx, m ? m : 1, sizeof *k);
    if (!k) {
        rs__free(ctx, ids);
        return RS_ERR_NOMEM;
    }
    for (size_t i = 0; i < m; i++) k[i].h = e->it[ids[i]].h, k[i].i = ids[i], k[i].pos = (uint32_t)i;
    rs_result r = rs__sort_recs(ctx, k, m); /* (ids ascending: the ties in index order) */
    if (r) {
        rs__free(ctx, k);
        rs__free(ctx, ids);
        return r;
    }
    *ids_out = ids;
    *n = m;
    *keys = k;
    return RS_OK;
}

/* Whether what source k of a patched grid draws of piece q (its region
 * grown by pad, within rectangle R and the source's rectangle A, pixels)
 * lies wholly inside one later patch's rectangle (patches[k ..), the
 * sources after k): a later patch draws it instead. */
static int hidden(const rs__edit_item *q, double pad, const rs_pixel_rect *R, const rs_pixel_rect *A,
                  const rs__grid_patch *later, size_t n, double pix)
{
    double x0, y0, x1, y1;
    item_box(q, pad, &x0, &y0, &x1, &y1);
    x0 = fmax(x0, fmax(R->x0, A->x0) * pix), y0 = fmax(y0, fmax(R->y0, A->y0) * pix);
    x1 = fmin(x1, fmin(R->x1, A->x1) * pix), y1 = fmin(y1, fmin(R->y1, A->y1) * pix);
    for (size_t j = 0; j < n; j++) {
        const rs_pixel_rect *L = &later[j].rect;
        if (L->x0 * pix <= x0 && x1 <= L->x1 * pix && L->y0 * pix <= y0 && y1 <= L->y1 * pix) return 1;
    }
    return 0;
}

/* A piece's region meets rectangle R (pixels)? */
static int meets(const rs__edit_item *q, double pad, const rs_pixel_rect *R, double pix)
{
    double x0, y0, x1, y1;
    item_box(q, pad, &x0, &y0, &x1, &y1);
    return !(x1 < R->x0 * pix || x0 > R->x1 * pix || y1 < R->y0 * pix || y0 > R->y1 * pix);
}

rs_result rs__patch_candidates(rs_ctx *ctx, const rs_road_grid *old, const rs_road_grid *local, rs_pixel_rect rect,
                               rs_pixel_rect **out, size_t *nout)
{
    /* What old drew: its base, and inside each patch's rectangle that
     * patch's grid (later over earlier). A piece of local is new unless
     * every grid of old that draws some of it (not hidden there by one
     * later patch's rectangle) has it; a piece of such a grid is gone when
     * local lacks it, unless one later patch's rectangle hides what that
     * grid draws of it (a patch's edit left the pixels outside its
     * rectangle as they were: the base's stale pieces there draw them
     * still). */
    const size_t ns = old->npatch + 1;
    const rs_road_grid **src = rs__alloc_array(ctx, ns, sizeof *src);
    keyed **ks = rs__calloc(ctx, ns, sizeof *ks);
    uint32_t **near = rs__calloc(ctx, ns, sizeof *near);
    size_t *nk = rs__calloc(ctx, ns, sizeof *nk);
    const rs__grid_edit *el = local->edit;
    keyed *kl = NULL;
    rs_result r = el ? sorted_keys(ctx, el, &kl) : RS_ERR_NOMEM;
    uint32_t *cl = kl ? run_counts(ctx, kl, el->n) : NULL, **cs = rs__calloc(ctx, ns, sizeof *cs);
    spans S, Ssf, C;
    memset(&S, 0, sizeof S);
    memset(&Ssf, 0, sizeof Ssf);
    memset(&C, 0, sizeof C);
    if (!r && !(src && ks && near && nk && cl && cs)) r = RS_ERR_NOMEM;
    int fills = 0;
    *out = NULL;
    *nout = 0;
    const double pix = local->frame.cell_size / local->texels;
    const uint32_t W = (local->dem_w - 1) * local->texels, H = (local->dem_h - 1) * local->texels;
    /* each source's pieces near the rectangle (within every grid's pad and
     * a metre: a piece that meets it, and one of equal fingerprint, lies
     * there), from its bins */
    double grow = grid_pad(local);
    for (size_t k = 0; !r && k < ns; k++) {
        src[k] = k == 0 ? (old->base ? old->base : old) : old->patch[k - 1].grid;
        grow = fmax(grow, grid_pad(src[k]));
    }
    grow += 1.0;
    for (size_t k = 0; !r && k < ns; k++) {
        if (!src[k]->edit || src[k]->edit->over) r = RS_ERR_NOMEM;
        else r = near_items(ctx, src[k]->edit, rect.x0 * pix - grow, rect.y0 * pix - grow, rect.x1 * pix + grow,
                            rect.y1 * pix + grow, &near[k], &nk[k], &ks[k]);
        if (!r && !(cs[k] = run_counts(ctx, ks[k], nk[k]))) r = RS_ERR_NOMEM;
        if (!r) fills |= src[k]->edit->fills;
    }
    if (!r && el) fills |= el->fills;
    if (!r && (!el || el->over)) r = RS_ERR_LIMIT;
    keydir dl, *ds = rs__calloc(ctx, ns, sizeof *ds);
    memset(&dl, 0, sizeof dl);
    if (!r && !ds) r = RS_ERR_NOMEM;
    if (!r && !keydir_make(ctx, &dl, kl, el->n)) r = RS_ERR_NOMEM;
    for (size_t k = 0; !r && k < ns; k++)
        if (!keydir_make(ctx, &ds[k], ks[k], nk[k])) r = RS_ERR_NOMEM;
    int ok = 1;
    /* (the rectangle a source draws in: the base everywhere) */
    #define SRC_RECT(k) ((k) == 0 ? &rect : &old->patch[(k) - 1].rect)
    const double pad_l = grid_pad(local);
    for (size_t i = 0; !r && ok && i < el->n; i++) {
        const rs__edit_item *q = &el->it[i];
        if (!meets(q, pad_l, &rect, pix)) continue;
        /* (known: every source that draws some of it has it; one that
         * lacks it is hidden there by a later patch) */
        int known = 1, any = 0, core = q->kind == RS__EI_CORE;
        for (size_t k = 0; k < ns; k++) {
            if (!meets(q, pad_l, SRC_RECT(k), pix)) continue;
            size_t cnt;
            int kind = kind_of(&ds[k], src[k]->edit, q->h, &cnt);
            if (kind >= 0) {
                any = 1;
                if (cnt != cl[i]) known = 0; /* (drawn more or fewer times) */
            } else if (!hidden(q, pad_l, &rect, SRC_RECT(k), k + 1 < ns ? old->patch + k : NULL, ns - 1 - k, pix)) known = 0;
            core &= kind == RS__EI_CORE || kind < 0;
        }
        known &= any;
        /* (an unchanged road's core stays wholly road of one colour under
         * changed surfaces where no road has a fill: diff's rule, a core
         * only where it was one in every grid that drew it) */
        if (known) ok = !core || core_spans(ctx, &C, q, pix, W, H);
        else ok = piece_spans(ctx, &S, &Ssf, q, pad_l, pix, W, H);
    }
    for (size_t k = 0; !r && ok && k < ns; k++) {
        const rs__grid_edit *e = src[k]->edit;
        double pad = grid_pad(src[k]);
        for (size_t ii = 0; ok && ii < nk[k]; ii++) {
            const rs__edit_item *q = &e->it[near[k][ii]];
            if (!meets(q, pad, &rect, pix) || !meets(q, pad, SRC_RECT(k), pix) ||
                count_of(&dl, q->h) == cs[k][ii])
                continue;
            if (hidden(q, pad, &rect, SRC_RECT(k), k + 1 < ns ? old->patch + k : NULL, ns - 1 - k, pix)) continue;
            ok = piece_spans(ctx, &S, &Ssf, q, pad, pix, W, H);
        }
    }
    #undef SRC_RECT
    if (!r && ok && !fills) {
        spans_norm(&Ssf);
        spans_norm(&C);
        ok = spans_minus(ctx, &Ssf, &C, &S);
    } else
        for (size_t k = 0; !r && ok && k < Ssf.n; k++) ok = span_push(ctx, &S, Ssf.v[k].y, Ssf.v[k].x0, Ssf.v[k].x1);
    if (!r && !ok) r = RS_ERR_NOMEM;
    if (Ssf.over) S.over = 1;
    /* within the rectangle (pieces reach out of it; nothing changed there) */
    spans R, in;
    memset(&R, 0, sizeof R);
    memset(&in, 0, sizeof in);
    if (!r && !S.over) {
        spans out_of;
        memset(&out_of, 0, sizeof out_of);
        spans_norm(&S);
        for (uint32_t y = rect.y0; ok && y < rect.y1; y++) ok = span_push(ctx, &R, y, rect.x0, rect.x1);
        /* S within R: S less (S less R) */
        if (ok) ok = spans_minus(ctx, &S, &R, &out_of);
        spans_norm(&out_of);
        if (ok) ok = spans_minus(ctx, &S, &out_of, &in);
        rs__free(ctx, out_of.v);
        if (!ok) r = RS_ERR_NOMEM;
    }
    if (r == RS_ERR_LIMIT || (!r && (S.over || in.over))) {
        /* (no pieces, or too many runs: the rectangle itself) */
        r = RS_OK;
        *out = rs__alloc_array(ctx, 1, sizeof **out);
        if (!*out) r = RS_ERR_NOMEM;
        else (*out)[0] = rect, *nout = 1;
    } else if (!r) r = spans_to_rects(ctx, &in, out, nout);
    for (size_t k = 0; ds && k < ns; k++) rs__free(ctx, ds[k].start);
    rs__free(ctx, ds);
    rs__free(ctx, dl.start);
    for (size_t k = 0; ks && k < ns; k++) rs__free(ctx, ks[k]);
    for (size_t k = 0; near && k < ns; k++) rs__free(ctx, near[k]);
    for (size_t k = 0; cs && k < ns; k++) rs__free(ctx, cs[k]);
    rs__free(ctx, cs);
    rs__free(ctx, cl);
    rs__free(ctx, ks);
    rs__free(ctx, near);
    rs__free(ctx, nk);
    rs__free(ctx, src);
    rs__free(ctx, kl);
    rs__free(ctx, S.v);
    rs__free(ctx, Ssf.v);
    rs__free(ctx, C.v);
    rs__free(ctx, R.v);
    rs__free(ctx, in.v);
    return r;
}

rs_result rs_road_grid_update(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *opts,
                              const rs_road_grid *old, rs_road_grid **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_road_grid_update: out is NULL");
    *out = NULL;
    if (!dem || !roads || !old)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_road_grid_update: %s is NULL",
                        !dem ? "dem" : !roads ? "roads" : "old");
    rs_splat_options o;
    rs_result r = rs__splat_defaults(ctx, opts, &o);
    if (r) return r;
    if (old->dem_w != dem->width || old->dem_h != dem->height)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_road_grid_update: the old grid is for a %u x %u DEM, this one is %u x %u", old->dem_w,
                        old->dem_h, dem->width, dem->height);
    if (old->frame.cell_size != dem->frame.cell_size || old->frame.origin_x != dem->frame.origin_x ||
        old->frame.origin_y != dem->frame.origin_y)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_road_grid_update: the old grid's frame (cell size %g, origin %g, %g) is not the DEM's "
                        "(%g, %g, %g)", old->frame.cell_size, old->frame.origin_x, old->frame.origin_y,
                        dem->frame.cell_size, dem->frame.origin_x, dem->frame.origin_y);
    if (old->texels != o.texels)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_road_grid_update: the old grid has %u texels, the options %u",
                        old->texels, o.texels);
    if (old->edges != o.coverage.edges || old->opts.buffer != o.grid.buffer || old->opts.road_cell != o.grid.road_cell)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_road_grid_update: the old grid's edges %d, buffer %d, road cell %g are not the options' "
                        "(%d, %d, %g)", (int)old->edges, (int)old->opts.buffer, old->opts.road_cell,
                        (int)o.coverage.edges, (int)o.grid.buffer, o.grid.road_cell);
    if (!old->edit)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_road_grid_update: the old grid keeps no edit pieces (build it with opts->grid.edits = 1)");
    rs_road_grid *g = NULL;
    o.grid.edits = 1;
    /* the edited part alone when the edit allows (lib/scene/grid_patch.c) */
    r = rs__grid_update_patched(ctx, dem, roads, &o, old, &g);
    if (r || g) {
        if (!r) rs__ok(ctx);
        *out = g;
        return r;
    }
    r = rs_road_grid_build(ctx, dem, roads, &o, &g);
    if (r) return r;
    /* a patched old grid: its pieces are its base's, and its patches
     * draw otherwise inside their rectangles */
    if (!old->npatch) r = diff(ctx, old, g, NULL, &g->edit->dirty, &g->edit->ndirty);
    else {
        /* a patched old grid: its base's pieces, and inside each patch that patch's */
        rs_pixel_rect all = { 0, 0, (old->dem_w - 1) * old->texels, (old->dem_h - 1) * old->texels };
        r = rs__patch_candidates(ctx, old, g, all, &g->edit->dirty, &g->edit->ndirty);
    }
    if (!r) r = rs__dirty_render(ctx, dem, &o, old, g, &g->edit->dirty, &g->edit->ndirty);
    if (r) {
        rs_road_grid_free(ctx, g);
        return r;
    }
    size_t extra = g->edit->ndirty * sizeof *g->edit->dirty;
    g->edit->bytes += extra;
    g->stats.bytes += extra;
    *out = g;
    rs__ok(ctx);
    return RS_OK;
}

size_t rs_road_grid_patch_count(const rs_road_grid *grid)
{
    /* (the local grids: one update's rectangles share one) */
    size_t n = 0;
    for (size_t k = 0; grid && k < grid->npatch; k++) {
        size_t i = 0;
        while (i < k && grid->patch[i].grid != grid->patch[k].grid) i++;
        n += i == k;
    }
    return n;
}

size_t rs_road_grid_dirty(const rs_road_grid *grid, rs_pixel_rect *rects, size_t cap)
{
    if (!grid || !grid->edit) return 0;
    const rs_pixel_rect *d = grid->base ? grid->dirty : grid->edit->dirty;
    size_t n = grid->base ? grid->ndirty : grid->edit->ndirty;
    if (rects)
        for (size_t k = 0; k < n && k < cap; k++) rects[k] = d[k];
    return n;
}

/* Distance from point (px, py) to the box. */
static double box_dist(double px, double py, double x0, double y0, double x1, double y1)
{
    double dx = px < x0 ? x0 - px : px > x1 ? px - x1 : 0, dy = py < y0 ? y0 - py : py > y1 ? py - y1 : 0;
    return hypot(dx, dy);
}

static double seg_dist(double px, double py, double ax, double ay, double bx, double by)
{
    double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy, t = 0;
    if (l2 > 0) t = fmax(0, fmin(1, ((px - ax) * dx + (py - ay) * dy) / l2));
    return hypot(px - (ax + t * dx), py - (ay + t * dy));
}

int rs__capsule_meets_box(double ax, double ay, double bx, double by, double r, double x0, double y0, double x1,
                          double y1)
{
    if (fmin(ax, bx) - r > x1 || fmax(ax, bx) + r < x0 || fmin(ay, by) - r > y1 || fmax(ay, by) + r < y0) return 0;
    /* the segment crosses the box, or one of them comes within r */
    double t0, t1;
    builder b;
    memset(&b, 0, sizeof b);
    b.mx0 = x0, b.my0 = y0, b.mx1 = x1, b.my1 = y1;
    if (clip_box(&b, ax, ay, bx, by, 0, &t0, &t1)) return 1;
    double d = fmin(box_dist(ax, ay, x0, y0, x1, y1), box_dist(bx, by, x0, y0, x1, y1));
    const double cx[4] = { x0, x1, x1, x0 }, cy[4] = { y0, y0, y1, y1 };
    for (int k = 0; k < 4; k++) d = fmin(d, seg_dist(cx[k], cy[k], ax, ay, bx, by));
    return d <= r;
}

/* Whether the item's region meets the box [x0, x1] x [y0, y1]. */
static int item_meets(const rs__edit_item *it, double x0, double y0, double x1, double y1)
{
    if (it->r < 0) {
        double bx0, by0, bx1, by1;
        item_box(it, 0, &bx0, &by0, &bx1, &by1);
        return !(bx1 < x0 || bx0 > x1 || by1 < y0 || by0 > y1);
    }
    return rs__capsule_meets_box(it->ax, it->ay, it->bx, it->by, it->r, x0, y0, x1, y1);
}

int rs_road_grid_rect_has_roads(const rs_road_grid *grid, uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1)
{
    if (!grid) return 0;
    if (x0 >= x1 || y0 >= y1) return 0;
    /* a patched grid: each patch's grid inside its rectangle (later over
     * earlier), the base's pieces for the whole rectangle (they may still
     * hold a road the patches took away: a 1 may find no road pixel) */
    for (size_t k = 0; k < grid->npatch; k++) {
        const rs_pixel_rect *R = &grid->patch[k].rect;
        uint32_t a0 = x0 > R->x0 ? x0 : R->x0, b0 = y0 > R->y0 ? y0 : R->y0;
        uint32_t a1 = x1 < R->x1 ? x1 : R->x1, b1 = y1 < R->y1 ? y1 : R->y1;
        if (a0 < a1 && b0 < b1 && rs_road_grid_rect_has_roads(grid->patch[k].grid, a0, b0, a1, b1)) return 1;
    }
    const rs__grid_edit *e = grid->edit;
    if (!e || e->over || !e->bstart) return 1;
    double pix = grid->frame.cell_size / grid->texels, pad = grid_pad(grid);
    double X0 = x0 * pix - pad, Y0 = y0 * pix - pad, X1 = x1 * pix + pad, Y1 = y1 * pix + pad;
    uint32_t i0 = bin_of(X0, e->bin, e->bw), i1 = bin_of(X1, e->bin, e->bw);
    uint32_t j0 = bin_of(Y0, e->bin, e->bh), j1 = bin_of(Y1, e->bin, e->bh);
    for (uint32_t j = j0; j <= j1; j++)
        for (uint32_t i = i0; i <= i1; i++) {
            size_t c = (size_t)j * e->bw + i;
            for (uint32_t k = e->bstart[c]; k < e->bstart[c + 1]; k++)
                if (item_meets(&e->it[e->bitem[k]], X0, Y0, X1, Y1)) return 1;
        }
    return 0;
}
