/* ROAM with frame coherence (seed 004, after Duchaineau 1997): the mesh is
 * kept from one update to the next and adapted by a split queue (leaves,
 * highest priority first) and a merge queue (diamonds, lowest priority
 * first). See docs/roam.md, "Frame-coherent updates". */
#include "roam.h"

#include <float.h>
#include <math.h>
#include <string.h>
#ifdef ROAM_UPDATE_DEBUG
#include <stdio.h>
#endif

/* A queue entry: a leaf (split queue) or a diamond named by one of its two
 * parents (merge queue), with its priority. Entries are never removed
 * when a split or merge elsewhere invalidates them: they are checked when
 * they come to the top (the node's corners name the triangle, so a node
 * index reused from the free list is not mistaken for the old one). */
typedef struct qent {
    double p;
    uint32_t node;
    uint16_t pos, ax, ay, bx, by;
} qent;

struct roam_queue {
    qent *a;
    size_t n, cap;
    int max;            /* 1: max-heap (splits), 0: min-heap (merges) */
};

static int above(const struct roam_queue *q, const qent *x, const qent *y)
{
    return q->max ? x->p > y->p : x->p < y->p;
}

static void sift_down(struct roam_queue *q, size_t i)
{
    qent *a = q->a;
    for (;;) {
        size_t l = 2 * i + 1, b = i;
        if (l < q->n && above(q, &a[l], &a[b])) b = l;
        if (l + 1 < q->n && above(q, &a[l + 1], &a[b])) b = l + 1;
        if (b == i) return;
        qent t = a[i]; a[i] = a[b]; a[b] = t;
        i = b;
    }
}

/* Append without ordering (rs_roam_update heapifies after the scan). */
static int q_append(rs_ctx *ctx, struct roam_queue *q, const qent *e)
{
    if (q->n == q->cap) {
        size_t nc = q->cap ? 2 * q->cap : 4096;
        qent *na = rs__realloc(ctx, q->a, nc * sizeof *na);
        if (!na) return 0;
        q->a = na;
        q->cap = nc;
    }
    q->a[q->n++] = *e;
    return 1;
}

static int q_push(rs_ctx *ctx, struct roam_queue *q, const qent *e)
{
    if (!q_append(ctx, q, e)) return 0;
    qent *a = q->a;
    for (size_t i = q->n - 1; i > 0;) {
        size_t p = (i - 1) / 2;
        if (!above(q, &a[i], &a[p])) break;
        qent t = a[i]; a[i] = a[p]; a[p] = t;
        i = p;
    }
    return 1;
}

static void q_pop(struct roam_queue *q)
{
    q->a[0] = q->a[--q->n];
    sift_down(q, 0);
}

static void q_heapify(struct roam_queue *q)
{
    for (size_t i = q->n / 2; i-- > 0;) sift_down(q, i);
}

/* The visibility side of the scan cache. A frustum plane's value at a
 * fixed point c changes between two views by at most |d eye| +
 * |d normal| |c - eye|, so after the eye has travelled T and the frustum
 * normals have turned by R (L->odo and L->rot since the scan; R sums each
 * update's largest normal change) an item whose sphere centre was within
 * vd of the eye has moved by at most T + R (vd + T) against every plane,
 * and its visibility (its sphere against the five planes) cannot have
 * changed while that is below m, its distance from changing sides. A
 * share a of m for the travel makes two readings: T < a m (folded into
 * the odometer's recheck reading) and R < (1 - a) m / (vd + a m) (the
 * turn's). Any share is safe; the one that makes both readings come due
 * together at the last update's pace (travel and turn per update) puts
 * the next look furthest away. */

/* State of one update. */
typedef struct upd {
    rs_ctx *ctx;
    rs_roam *L;
    const view_params *v;
    const unsigned char *vis;
    double tol;
    int all;            /* triangle target: queue everything, not only what crosses tol */
    int full;           /* scan every cluster, whatever its cache says */
    double mtol;        /* merges: both parents at or below this (tol / MERGE_HYSTERESIS) */
    double thr;         /* the threshold item_prio_t measures the slack against */
    int track;          /* scanning: keep `slack` */
    double slack;       /* how far the eye may move before an item seen so far
                           in the node under scan crosses the tolerance (metres) */
    double vtr, vrot;   /* the items seen so far in the node under scan: the
                           smallest travel and turn allowances (above) */
    double trate, rrate; /* travel and turn of this update (the pace) */
    double rrot;        /* smallest turn reading of the subtrees seen so far */
    int vtrack;         /* scanning a node partly in view: keep vtr, vrot */
    double ctr, crt;    /* scanning a node wholly in or out of view: its class's
                           travel and turn readings (node_class) */
    double rctr;        /* smallest travel reading of the subtrees seen so far,
                           their classes' included */
    int inview;         /* scanning a node wholly in view: no item is culled */
    int nomem;
} upd;

/* A margin m against every plane, of points within dc of the eye, as a
 * travel allowance tr and a turn allowance rt (the share above; vd = dc
 * rounded up). */
static void margin_split(const upd *u, double m, double dc, double *tr, double *rt)
{
    if (m < 0.0) m = 0.0;
    double vd = dc * (1.0 + 1e-9) + 1e-9, pace = u->trate + u->rrate * vd;
    double a = pace > 0.0 ? u->trate / pace : 0.5;
    if (a < 0.05) a = 0.05;
    if (a > 0.95) a = 0.95;
    *tr = a * m;
    *rt = (1.0 - a) * m / (vd + *tr);
}

/* view_dist, and in a scan the item's visibility allowances into u->vtr,
 * u->vrot (items off the map or straddling its edge do not depend on the
 * view; a culled patch's items are scanned again when it comes into view). */
static int view_dist_track(const upd *u, const tri *t, uint32_t patch, double *dist, double *vtr, double *vrt)
{
    const rs_roam *L = u->L;
    const view_params *v = u->v;
    int cls = tri_class(L, t);
    if (cls != NODE_ON) return cls == NODE_STRADDLES;
    if (!u->vis[patch]) return 0;
    double c[3], r;
    tri_sphere(L, t, patch, c, &r);
    int vis = 1;
    double m = INFINITY, am = 0.0;
    for (int p = 0; p < v->nplanes; p++) {
        const double *pl = v->planes[p];
        double a = pl[0] * c[0] + pl[1] * c[1] + pl[2] * c[2] + pl[3];
        if (a < -r) vis = 0; /* sphere_visible's test */
        if (a + r < m) { m = a + r; am = a; }
    }
    /* visible: the nearest plane must pass the sphere; culled: the plane it
     * is furthest outside must come back (less a margin for the rounding) */
    m = fabs(m) - 1e-9 * (fabs(am) + r + 1.0);
    double dx = c[0] - v->eye[0], dy = c[1] - v->eye[1], dz = c[2] - v->eye[2];
    double dc = sqrt(dx * dx + dy * dy + dz * dz);
    /* travel below a m and turn below (1 - a) m / (vd + a m) keep
     * T + R (vd + T) below m (vd = dc, rounded up) */
    margin_split(u, m, dc, vtr, vrt);
    double dst = dc - r;
    double floor_d = 1e-3 * L->cs;
    *dist = dst < floor_d ? floor_d : dst;
    return vis ? 2 : 3;
}

/* view_dist for an item under a node wholly in view (node_class 1): its
 * sphere is inside the frustum, only its distance is needed. */
static int view_dist_inview(const upd *u, const tri *t, uint32_t patch, double *dist)
{
    const rs_roam *L = u->L;
    const view_params *v = u->v;
    int cls = tri_class(L, t);
    if (cls != NODE_ON) return cls == NODE_STRADDLES;
    double c[3], r;
    tri_sphere(L, t, patch, c, &r);
    double dx = c[0] - v->eye[0], dy = c[1] - v->eye[1], dz = c[2] - v->eye[2];
    double dst = sqrt(dx * dx + dy * dy + dz * dz) - r;
    double floor_d = 1e-3 * L->cs;
    *dist = dst < floor_d ? floor_d : dst;
    return 2;
}

/* Priority of (node, pos) as a leaf (view_prio), its triangle t given or
 * (NULL) worked out; in a scan, also how far its distance is from the one
 * where it would cross the tolerance. */
static double item_prio_t(upd *u, uint32_t node, uint32_t pos, const tri *tk)
{
    tri t;
    uint32_t slot, patch;
    double d;
    const rs_roam *L = u->L;
    if (tk) {
        t = *tk;
        slot = pos >= 2 ? rs__roam_imp_slot(L, &L->nodes[node], pos) : rs__roam_err_slot(L, &L->nodes[node]);
        patch = L->nodes[node].e == NIL ? 0 : L->nodes[node].e >> L->elog;
    } else rs__roam_item_tri(L, node, pos, &t, &slot, &patch);
    double vtr = INFINITY, vrt = INFINITY;
    int k = u->vtrack ? view_dist_track(u, &t, patch, &d, &vtr, &vrt)
          : u->inview ? view_dist_inview(u, &t, patch, &d) : view_dist(L, &t, patch, u->v, u->vis, &d);
    if (k < 2) return k ? INFINITY : 0.0;
    float e = rs__roam_slot_err(u->L, slot, &t);
    if (!(e > 0.0f)) return 0.0; /* flat: never splits, whatever the distance */
    double ek = (double)e * L->zs * u->v->k;
    if (u->track) {
        /* a culled item's too: the distance at which it would cross the
         * threshold if it were visible */
        double sl = fabs(d - ek / u->thr);
        if (sl < u->slack) u->slack = sl;
        /* its side of the frustum matters only while its priority in
         * view is above the threshold: below it, culled (0) and visible
         * decide alike (no split, and no bar to a merge), and the slack
         * above says when that may change */
        if (ek / d > u->thr) {
            if (vtr < u->vtr) u->vtr = vtr;
            if (vrt < u->vrot) u->vrot = vrt;
        }
    }
    return k == 2 ? ek / d : 0.0;
}

static void fill_ent(const rs_roam *L, qent *e, double p, uint32_t node, uint32_t pos)
{
    const roam_node *nd = &L->nodes[node];
    e->p = p; e->node = node; e->pos = (uint16_t)pos;
    e->ax = nd->ax; e->ay = nd->ay; e->bx = nd->bx; e->by = nd->by;
}

static int same_node(const rs_roam *L, const qent *e)
{
    const roam_node *nd = &L->nodes[e->node];
    return nd->ax == e->ax && nd->ay == e->ay && nd->bx == e->bx && nd->by == e->by;
}

/* Is the entry still a leaf that can split? */
static int leaf_valid(const rs_roam *L, const qent *e)
{
    const roam_node *nd = &L->nodes[e->node];
    if (!same_node(L, e)) return 0;
    if (e->pos == 0) return nd->lc == NIL && nd->e != NIL;
    if (nd->lc != IMPL || (nd->rc & SPLIT_BIT(e->pos))) return 0;
    return e->pos < 4 || (nd->rc & SPLIT_BIT(e->pos >> 1u));
}

/* Queue leaf (node, pos) for a split when its priority calls for one. */
static void offer_leaf_t(upd *u, uint32_t node, uint32_t pos, int build, const tri *t)
{
    u->thr = u->tol;
    double p = item_prio_t(u, node, pos, t);
    if (!u->all && !(p > u->tol)) return;
    qent e;
    fill_ent(u->L, &e, p, node, pos);
    if (!(build ? q_append(u->ctx, u->L->qs, &e) : q_push(u->ctx, u->L->qs, &e))) u->nomem = 1;
}

/* Queue the diamond of (node, pos) for a merge when it can merge and its
 * priority (the larger of its two parents': the error once merged) allows.
 * blk: when (node, pos) is an implicit position of a block being scanned
 * whole (offer_block), the triangles of its positions in the mesh. */
static void offer_diamond_t(upd *u, uint32_t node, uint32_t pos, int build, const tri *t, const tri *blk)
{
    uint32_t N, pp;
    if (!rs__roam_mergeable(u->L, node, pos, &N, &pp)) return;
    /* a full scan of a triangle target sees each diamond once; the
     * tolerance's scans see it from both sides, as the two clusters that
     * hold its parents may be scanned in different frames, but once when
     * both parents are in the block under scan */
    if (build && N == node && pp < pos && (u->all || blk)) return;
    if (build && u->all && N != NIL && N < node) return;
    u->thr = u->mtol;
    double save = u->slack;
    u->slack = INFINITY;
    double p = item_prio_t(u, node, pos, t), sp = u->slack;
    if (!u->all && p > u->mtol) {
        /* it cannot merge until this parent's priority falls: the
         * partner's does not matter (and is not worked out) */
        u->slack = save < sp ? save : sp;
        return;
    }
    if (N != NIL) {
        u->slack = INFINITY;
        double q = item_prio_t(u, N, pp, blk && N == node ? &blk[pp] : NULL);
        if (!u->all && q > u->mtol) {
            u->slack = save < u->slack ? save : u->slack;
            return;
        }
        if (u->slack < sp) sp = u->slack;
        if (q > p) p = q;
    }
    u->slack = save < sp ? save : sp;
    qent e;
    fill_ent(u->L, &e, p, node, pos);
    if (!(build ? q_append(u->ctx, u->L->qm, &e) : q_push(u->ctx, u->L->qm, &e))) u->nomem = 1;
}

static void offer_leaf(upd *u, uint32_t node, uint32_t pos, int build)
{
    offer_leaf_t(u, node, pos, build, NULL);
}

static void offer_diamond(upd *u, uint32_t node, uint32_t pos, int build)
{
    offer_diamond_t(u, node, pos, build, NULL, NULL);
}

/* The leaves of block r below its split positions (cell halves excluded),
 * and with `diamonds` its diamonds too: the positions' triangles worked
 * out once, top down. */
static void offer_block(upd *u, uint32_t r, int build, int diamonds)
{
    const rs_roam *L = u->L;
    uint32_t rc = L->nodes[r].rc;
    tri pt[1 << IMPL_DEPTH];
    node_tri(L, &L->nodes[r], &pt[1]);
    for (uint32_t pos = 2; pos < L->ncut; pos++) {
        if (pos >= 4 && !(rc & SPLIT_BIT(pos >> 1u))) continue; /* not in the mesh */
        child_tri(&pt[pos >> 1u], (int)(pos & 1u), &pt[pos]);
    }
    for (uint32_t pos = 2; pos < L->ncut; pos++) {
        if (pos >= 4 && !(rc & SPLIT_BIT(pos >> 1u))) continue;
        if (!(rc & SPLIT_BIT(pos))) offer_leaf_t(u, r, pos, build, &pt[pos]);
        else if (diamonds) offer_diamond_t(u, r, pos, build, &pt[pos], pt);
    }
    if (diamonds) offer_diamond_t(u, r, 1, build, &pt[1], NULL);
}

/* A turn reading as stored: rounded down (a reading too early is safe). */
static float rot_reading(double rr)
{
    /* rr (1 - 2^-22) rounded to float is at most rr (the float's half ulp
     * is 2^-24 of it); a millimetre in 4 km early */
    if (rr > 0.0) return rr < FLT_MAX ? (float)(rr * (1.0 - 0x1p-22)) : rr == INFINITY ? INFINITY : FLT_MAX;
    if (rr <= -FLT_MAX) return -INFINITY;
    float rf = (float)rr;
    if ((double)rf > rr) rf = nextafterf(rf, -INFINITY);
    return rf;
}

/* Odometer readings are stored as floats from L->odo_base, rounded down
 * (-1: scan at the next update). */
static float reading_put(const rs_roam *L, double r)
{
    if (r < 0.0) return -1.0f;
    float f = rot_reading(r - L->odo_base);
    return f < 0.0f ? 0.0f : f;
}

static double reading_get(const rs_roam *L, float f)
{
    return f < 0.0f ? -1.0 : L->odo_base + (double)f;
}

/* A node's place against the view: 0 when its items are all
 * culled, 1 when they are all in the frustum, 2 in between. An item's
 * bounding sphere (tri_sphere) is centred on its centroid at the middle
 * of the patch's height range, so its centre lies in the cluster's
 * triangle lifted to that height, and its radius is at most the cluster's
 * and at least half the height range: all items are visible when the
 * lifted triangle's corners are inside every plane or outside by less
 * than that half range, all culled when they are further outside one
 * than the cluster's radius (or the patch is culled). */
#define CLS_UNKNOWN SCAN_NO_CLASS
/* Also the class's own readings (issue 31, third session): the lifted
 * corners' plane values move by at most T + R (vd + T) (above), so the
 * class holds while the odometer stays below *ctr and the turn below
 * *crt: for "all visible" the margin is the smallest lo + hz over the
 * planes, for "all culled" -r - hi of the plane that culls. (+inf for
 * a culled patch, which is scanned in full when it comes back, and for
 * "in between", which has its items' readings.) */
static int node_class(upd *u, uint32_t i, double *ctr, double *crt)
{
    rs_roam *L = u->L;
    const roam_node *nd = &L->nodes[i];
    *ctr = *crt = INFINITY;
    if (nd->e == NIL) { /* no class readings: looked at again every time */
        L->c2read[2 * (size_t)i] = -1.0f;
        return 2;
    }
    uint32_t patch = nd->e >> L->elog;
    if (!u->vis[patch]) return 0;
    tri t;
    node_tri(L, nd, &t);
    double c[3], r;
    tri_sphere(L, &t, patch, c, &r);
    double hz = 0.5 * ((double)L->pzmax[patch] - (double)L->pzmin[patch]) * L->zs;
    double cs = L->cs;
    double x0 = t.ax * cs, x1 = t.bx * cs, x2 = t.cx * cs, y0 = t.ay * cs, y1 = t.by * cs, y2 = t.cy * cs;
    int part = 0, cls = 1, np = u->v->nplanes;
    double m = INFINITY, mout = -INFINITY, mkeep = INFINITY;
    for (int p = 0; p < np; p++) {
        const double *pl = u->v->planes[p];
        double a = pl[0], b = pl[1], base = pl[2] * c[2] + pl[3];
        double s0 = a * x0 + b * y0 + base, s1 = a * x1 + b * y1 + base, s2 = a * x2 + b * y2 + base;
        double lo = s0 < s1 ? s0 : s1, hi = s0 < s1 ? s1 : s0;
        if (s2 < lo) lo = s2;
        if (s2 > hi) hi = s2;
        if (hi < -r) { cls = 0; m = -r - hi; break; }
        if (lo < -hz) part = 1;
        if (lo + hz < m) m = lo + hz;
        /* in between: a corner stays further out than hz of the plane it is
         * furthest out of, and no plane culls it */
        if (-hz - lo > mout) mout = -hz - lo;
        if (hi + r < mkeep) mkeep = hi + r;
    }
    if (cls == 1 && part) {
        cls = 2;
        m = mout < mkeep ? mout : mkeep;
    }
    /* the farthest lifted corner, and a margin for the rounding */
    const double *e = u->v->eye;
    double dz = c[2] - e[2], v2 = 0.0;
    double xs[3] = { x0, x1, x2 }, ys[3] = { y0, y1, y2 };
    for (int k = 0; k < 3; k++) {
        double dx = xs[k] - e[0], dy = ys[k] - e[1], d = dx * dx + dy * dy + dz * dz;
        if (d > v2) v2 = d;
    }
    double vd = sqrt(v2);
    m -= 1e-9 * (vd + r + 1.0);
    double tr, rt;
    margin_split(u, m, vd, &tr, &rt);
    double eps = 1e-9 * (1.0 + L->odo);
    double ct = L->odo + tr * (1.0 - 1e-9) - eps, cr = L->rot + rt * (1.0 - 1e-9) - 1e-9 * (1.0 + L->rot);
    if (cls == 2) {
        /* kept apart: a node in between has its items' readings, and its
         * children their own classes; these only spare node_class when
         * its items are due (walk) */
        L->c2read[2 * (size_t)i] = reading_put(L, ct);
        L->c2read[2 * (size_t)i + 1] = rot_reading(cr);
        return 2;
    }
    *ctr = ct;
    *crt = cr;
    return cls;
}

static double walk(upd *u, uint32_t i, int pcls);

/* The items at and below node i: its leaves and its diamonds. Returns the
 * smallest recheck reading of the children's subtrees (+inf: none). */
static double walk_items(upd *u, uint32_t i, int cls)
{
    roam_node *n = u->L->nodes;
    uint32_t lc = n[i].lc;
    if (lc == NIL) {
        if (n[i].e != NIL) offer_leaf(u, i, 0, 1);
    } else if (lc == IMPL) {
        n[i].rc &= ~QUEUED;
        offer_block(u, i, 1, 1);
    } else {
        offer_diamond(u, i, 0, 1);
        double a = walk(u, lc, cls), b = walk(u, n[i].rc, cls);
        return a < b ? a : b;
    }
    return INFINITY;
}

/* Depth-first over the tree under node i, skipping a subtree when nothing
 * in it can have crossed the tolerance or changed sides of the frustum
 * since the last update (which completed): nothing under it changed (a
 * split or merge marks the node and its ancestors), the eye has moved less
 * than the smallest slack its items had at their last scan (the odometer
 * is below its recheck reading), and either the node is wholly in view
 * (or out of it) now as then, or (a node partly in view) the frustum has
 * moved too little for an item under it to change sides (the turn reading,
 * above). Returns the subtree's recheck reading (-1: scan it every update)
 * and folds its turn reading into u->rrot. A child's triangle lies in its
 * parent's, so it has the class of a parent wholly in or out. */
static double walk(upd *u, uint32_t i, int pcls)
{
    rs_roam *L = u->L;
    if (u->all) { walk_items(u, i, 2); return -1.0; }
    struct roam_scan *cs = &L->cscan[i];
    double rc = reading_get(L, cs->rc), irc, rr = cs->rot;
    int cls = pcls; /* CLS_UNKNOWN until needed */
    /* the class's readings: an ancestor's when the class is inherited */
    double ctr = INFINITY, crt = INFINITY;
    if (cls != CLS_UNKNOWN) { ctr = u->ctr; crt = u->crt; }
    if (!u->full && rc >= 0.0) {
        if (L->odo < rc && L->rot < rr) {
            if (rr < u->rrot) u->rrot = rr;
            if (rc < u->rctr) u->rctr = rc;
            return reading_get(L, cs->irc);
        }
        if (cs->cls != 2) {
            irc = reading_get(L, cs->irc);
            if (cls == CLS_UNKNOWN) cls = node_class(u, i, &ctr, &crt);
            if (cls == cs->cls && (cls == 0 || L->odo < irc)) {
                /* its items are as at their scan (culled ones have no
                 * readings); the class holds until this view's readings */
                rc = cls == 0 || ctr < irc ? ctr : irc;
                cs->rc = reading_put(L, rc);
                cs->rot = rot_reading(crt);
                if (crt < u->rrot) u->rrot = crt;
                if (rc < u->rctr) u->rctr = rc;
                return irc;
            }
        }
    }
    /* in between while its class's readings hold (they do not depend on
     * what changed under it: a split or merge only marks the node's
     * subtree readings; a new node has no class) */
    if (!u->full && cls == CLS_UNKNOWN && cs->cls == 2 && L->odo < reading_get(L, L->c2read[2 * (size_t)i])
        && L->rot < (double)L->c2read[2 * (size_t)i + 1])
        cls = 2;
    if (cls == CLS_UNKNOWN) cls = node_class(u, i, &ctr, &crt);
    double save = u->slack, svtr = u->vtr, svrot = u->vrot, srot = u->rrot, srctr = u->rctr;
    double sctr = u->ctr, scrt = u->crt;
    int svt = u->vtrack, siv = u->inview;
    u->slack = INFINITY;
    u->vtr = INFINITY;
    u->vrot = INFINITY;
    /* a node wholly in or out of view relies on its class (its children
     * inherit it, with its readings); the items of one in between keep a
     * bound on their sides */
    u->vtrack = cls == 2;
    u->inview = cls == 1;
    u->rrot = INFINITY;
    u->rctr = INFINITY;
    u->ctr = ctr; u->crt = crt;
    double sub = walk_items(u, i, cls == 2 ? CLS_UNKNOWN : cls);
    u->ctr = sctr; u->crt = scrt;
    /* a margin for the rounding of the distances */
    double eps = 1e-9 * (1.0 + L->odo);
    irc = L->odo + u->slack * (1.0 - 1e-9) - eps;
    if (sub < irc) irc = sub;
    rr = u->rrot;
    double cf = u->rctr; /* the children's class readings */
    if (cls == 2) {
        double ro = L->odo + u->vtr * (1.0 - 1e-9) - eps;
        double rt = L->rot + u->vrot * (1.0 - 1e-9) - 1e-9 * (1.0 + L->rot);
        if (ro < irc) irc = ro;
        if (rt < rr) rr = rt;
    } else {
        if (ctr < cf) cf = ctr;
        if (crt < rr) rr = crt;
    }
    rc = cf < irc ? cf : irc;
    cs->rc = reading_put(L, rc);
    cs->irc = reading_put(L, irc);
    cs->rot = rot_reading(rr);
    cs->cls = (unsigned char)cls;
    u->slack = save; u->vtr = svtr; u->vrot = svrot; u->vtrack = svt; u->inview = siv;
    u->rrot = rr < srot ? rr : srot;
    u->rctr = rc < srctr ? rc : srctr;
    return irc;
}

/* The leaves and diamonds of the current mesh that may have crossed the
 * tolerance (every one of them for a triangle target), queued. */
static void scan_mesh(upd *u)
{
    rs_roam *L = u->L;
    u->track = !u->all;
    u->rrot = INFINITY;
    u->rctr = INFINITY;
    int full = u->full;
    for (uint32_t p = 0; p < L->npx * L->npy; p++) {
        /* a stop leaves the scan partial: the update then ends undone,
         * and the next one scans in full (full_next) */
        if ((p & 15) == 15 && rs__roam_poll(L)) break;
        /* a patch that came into view or left it (its items were not
         * tracked while it was culled) is looked at in full */
        u->full = full || u->vis[p] != L->pvis[p];
        L->pvis[p] = u->vis[p];
        walk(u, 2 * p, CLS_UNKNOWN); /* the roots */
        walk(u, 2 * p + 1, CLS_UNKNOWN);
    }
    u->full = full;
    u->track = 0;
    q_heapify(L->qs);
    q_heapify(L->qm);
}

/* The leaves a split left on L->stack (new explicit nodes, blocks with new
 * implicit leaves), queued. */
static void drain_stack(upd *u)
{
    rs_roam *L = u->L;
    roam_node *n = L->nodes;
    while (L->sp) {
        uint32_t i = L->stack[--L->sp];
        if (i & TAG) {
            i &= ~TAG;
            n[i].rc &= ~QUEUED;
            offer_block(u, i, 0, 0);
        } else if (n[i].lc == NIL && n[i].e != NIL) offer_leaf(u, i, 0, 0);
    }
}

/* Top of a queue after dropping the entries that no longer name a leaf
 * (splits) or a mergeable diamond (merges); NULL when empty. */
static const qent *top_split(rs_roam *L)
{
    struct roam_queue *q = L->qs;
    while (q->n && !leaf_valid(L, &q->a[0])) q_pop(q);
    return q->n ? &q->a[0] : NULL;
}

static const qent *top_merge(rs_roam *L)
{
    struct roam_queue *q = L->qm;
    uint32_t N, pp;
    while (q->n && !(same_node(L, &q->a[0]) && rs__roam_mergeable(L, q->a[0].node, q->a[0].pos, &N, &pp))) q_pop(q);
    return q->n ? &q->a[0] : NULL;
}

/* Split the top of the split queue; 0 when the pool cannot hold it. */
static int do_split(upd *u)
{
    rs_roam *L = u->L;
    qent e = L->qs->a[0];
    q_pop(L->qs);
    L->sp = 0;
    if (rs__roam_split_leaf(L, e.node, e.pos) != 0) {
        L->sp = 0;
        L->exhausted = 1;
        return 0;
    }
    drain_stack(u);
    /* the new diamond (this leaf and its partner) can merge back */
    if (u->all) offer_diamond(u, e.node, e.pos == 0 && L->nodes[e.node].lc == IMPL ? 1u : e.pos, 0);
    return 1;
}

static void do_merge(upd *u)
{
    rs_roam *L = u->L;
    qent e = L->qm->a[0];
    q_pop(L->qm);
    uint32_t N, pp, pn, ppos;
    rs__roam_mergeable(L, e.node, e.pos, &N, &pp);
    rs__roam_merge(L, e.node, e.pos);
    /* the two parents are leaves again, and their own parents' diamonds
     * may have become mergeable */
    uint32_t nodes[2] = { e.node, N }, poss[2] = { e.pos, pp };
    for (int k = 0; k < 2; k++) {
        if (nodes[k] == NIL) continue;
        uint32_t lpos = poss[k] == 1 ? 0u : poss[k]; /* a merged block is an explicit leaf */
        if (u->all) offer_leaf(u, nodes[k], lpos, 0);
        if (rs__roam_item_parent(L, nodes[k], poss[k], &pn, &ppos)) offer_diamond(u, pn, ppos, 0);
    }
}

/* ---- pool compaction ---- */

/* Compact once the nodes taken from the free list since the last time are
 * 3/10 of the live ones: 3 times in the 600 updates of either drive,
 * each a few milliseconds cold (1/10 compacted 10 times as often for the
 * same mean, with more frames above 2 ms). */
#define COMPACT_TENTHS 3u
#define ODO_REBASE 4096.0

/* Give the pairs under node i the next indices, depth first, lc's subtree
 * before rc's: the order in which walk() visits them. The depth is at most
 * the tree's (2 log2 P + 1 levels). */
static void order_pairs(const rs_roam *L, uint32_t i, uint32_t *map, uint32_t *next)
{
    const roam_node *n = L->nodes;
    uint32_t lc = n[i].lc, rc = n[i].rc;
    if (lc == NIL || lc == IMPL || lc == FREE) return;
    if (lc >= L->base_count) { map[lc] = *next; map[lc + 1] = *next + 1; *next += 2; }
    order_pairs(L, lc, map, next);
    order_pairs(L, rc, map, next);
}

static uint32_t remap(const rs_roam *L, const uint32_t *map, uint32_t x)
{
    return x == NIL || x < L->base_count ? x : map[x];
}

/* Renumber the pool's live nodes in the scan's order and drop the free
 * list. Splits take nodes from wherever merges freed them, so after a few
 * hundred updates the nodes one scan visits are scattered over the pool
 * and every one is a cache miss; in walk order, a scan reads the node and
 * scan arrays forwards and siblings share lines. Only node numbers change
 * (links, parents and scan records move with their nodes; the base mesh
 * keeps its numbers), so the mesh and every later decision are the same;
 * extraction, which lists leaves in node order, lists them in this order.
 * The refinement stack, empty between calls, holds the map. */
static void compact_pool(rs_roam *L)
{
    roam_node *n = L->nodes;
    uint32_t *map = L->stack, b = L->base_count, next = b;
    for (uint32_t i = b; i < L->used; i++) map[i] = NIL;
    for (uint32_t p = 0; p < 2 * L->npx * L->npy; p++) order_pairs(L, p, map, &next);
    uint32_t live = next;
    for (uint32_t i = b; i < L->used; i++)
        if (map[i] == NIL) map[i] = next++; /* free nodes fill the rest */
    for (uint32_t i = 0; i < L->used; i++) {
        roam_node *nd = &n[i];
        if (i >= b && nd->lc == FREE) continue;
        if (nd->lc != NIL && nd->lc != IMPL) { nd->lc = remap(L, map, nd->lc); nd->rc = remap(L, map, nd->rc); }
        nd->base = remap(L, map, nd->base);
        nd->left = remap(L, map, nd->left);
        nd->right = remap(L, map, nd->right);
        L->par[i] = remap(L, map, L->par[i]);
    }
    /* move every node to its number, cycle by cycle */
    for (uint32_t i = b; i < L->used; i++)
        while (map[i] != i) {
            uint32_t j = map[i];
            roam_node tn = n[i]; n[i] = n[j]; n[j] = tn;
            struct roam_scan ts = L->cscan[i]; L->cscan[i] = L->cscan[j]; L->cscan[j] = ts;
            float *ci = L->c2read + 2 * (size_t)i, *cj = L->c2read + 2 * (size_t)j, t0 = ci[0], t1 = ci[1];
            ci[0] = cj[0]; ci[1] = cj[1]; cj[0] = t0; cj[1] = t1;
            uint32_t tp = L->par[i]; L->par[i] = L->par[j]; L->par[j] = tp;
            map[i] = map[j]; map[j] = j;
        }
    L->used = live;
    L->free_head = NIL;
    L->nfree = 0;
    L->moved = 0;
}

static rs_result ensure_state(rs_ctx *ctx, rs_roam *L)
{
    if (!L->par) {
        uint32_t *par = rs__alloc_array(ctx, L->cap, sizeof *par);
        struct roam_scan *cs = rs__alloc_array(ctx, L->cap, sizeof *cs);
        unsigned char *pv = rs__calloc(ctx, (size_t)L->npx * L->npy, 1);
        float *c2 = rs__alloc_array(ctx, 2 * (size_t)L->cap, sizeof *c2);
        if (!par || !cs || !pv || !c2) {
            rs__free(ctx, par); rs__free(ctx, cs); rs__free(ctx, pv); rs__free(ctx, c2);
            return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for the parent links of %u nodes", L->cap);
        }
        roam_node *n = L->nodes;
        for (uint32_t i = 0; i < L->used; i++) { par[i] = NIL; cs[i].rc = cs[i].irc = -1.0f; cs[i].cls = SCAN_NO_CLASS; }
        for (uint32_t i = 0; i < L->used; i++)
            if (n[i].lc != NIL && n[i].lc != IMPL && n[i].lc != FREE) par[n[i].lc] = par[n[i].rc] = i;
        L->par = par; L->cscan = cs; L->pvis = pv; L->c2read = c2;
        L->full_next = 1;
        L->bytes += (uint64_t)L->cap * (sizeof *par + sizeof *cs + 2 * sizeof *c2) + (uint64_t)L->npx * L->npy;
    }
    if (!L->qs) {
        L->qs = rs__calloc(ctx, 1, sizeof *L->qs);
        L->qm = rs__calloc(ctx, 1, sizeof *L->qm);
        if (!L->qs || !L->qm) return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for the update queues");
        L->qs->max = 1;
    }
    return RS_OK;
}

void rs__roam_update_free(rs_ctx *ctx, rs_roam *L)
{
    rs__free(ctx, L->par);
    rs__free(ctx, L->cscan);
    rs__free(ctx, L->c2read);
    rs__free(ctx, L->pvis);
    if (L->qs) rs__free(ctx, L->qs->a);
    if (L->qm) rs__free(ctx, L->qm->a);
    rs__free(ctx, L->qs);
    rs__free(ctx, L->qm);
}

/* The default rs_roam_view.merge_hysteresis: a fixed tolerance merges a
 * diamond only when both parents are within tol / 1.25. The items between
 * the two thresholds are stable both ways, so far fewer cross one per
 * metre of eye travel (the seed's hysteresis); the split side, hence the
 * error bound, is unchanged. 1.25 rather than 1.1 (session 13): on the
 * fractal drive the update's p99 fell from 1.98-2.01 to 1.73-1.80 ms
 * (alternating runs) for 0.83 % more triangles than a rebuild at most
 * (was 0.70 %; docs/roam.md). */
#define MERGE_HYSTERESIS 1.25

/* A triangle target accepts the carried tolerance's mesh within 1.5 % of
 * the target (the seed's full loop, which lands within 1 %, costs a scan
 * of every leaf and diamond: at a fixed tolerance the count drifts by a
 * few tenths of a percent per frame on a moving camera). */
#define TARGET_BAND 0.015

/* Safety net when no budget is given: a triangle target's exchanges of a
 * split for a merge could in principle cycle (the bounds are not monotone
 * down the tree). */
#define UNBOUNDED_OPS_PER_NODE 8u

/* Operations of a triangle target's loop once it has reached the target
 * (trades and moves back into the band): at most this many, or a
 * sixteenth of the triangles when more. A split forces its neighbours'
 * splits, whose diamonds may merge at lower priorities than the split's,
 * so the trades can cycle (the roam fuzzer: 99 -> 105 -> ... -> 100 -> 99
 * on a 100-triangle target, eleven operations a turn, until the op limit
 * of the pool: 0.4 s an update). Past the cap the loop goes on to the
 * next count within the band (a cycle passes through it), at most as many
 * operations again. The drives' updates take at most 83. */
#define TARGET_FINE_OPS 1024u

/* Every leaf above the tolerance splits, then every diamond whose two
 * parents are within it merges (docs/roam.md: the rebuild's mesh, but for
 * a split node whose own bound exceeds the tolerance under an ancestor
 * whose bound does not). 1 when complete. */
/* A poll every 2048 steps of the passes (rs__roam_poll): a stop ends the
 * pass as a spent budget does. */
static int stop_now(rs_roam *L, uint32_t *steps)
{
    return L->cancelled || ((++*steps & 2047u) == 0 && rs__roam_poll(L));
}

static int tolerance_pass(upd *u, uint64_t limit, uint64_t *ops)
{
    rs_roam *L = u->L;
    uint32_t steps = 0;
    while (!u->nomem && *ops < limit && !stop_now(L, &steps) && top_split(L) != NULL) {
        if (!do_split(u)) break;
        ++*ops;
    }
    while (!u->nomem && *ops < limit && !stop_now(L, &steps) && top_merge(L) != NULL) {
        do_merge(u);
        ++*ops;
    }
    return *ops < limit && !u->nomem && !L->exhausted && !L->cancelled;
}

/* The seed's loop over every leaf and diamond: merge while above the
 * target, split while below (to the target itself, so the next update's
 * tolerance pass lands inside the band), then trade the highest split for
 * the lowest merge while the split's priority is the larger and the count
 * stays within 1 %; a step back into the band that lands beyond its other
 * side ends the pass there, and so do TARGET_FINE_OPS operations after the
 * target was reached. 1 when complete. */
static int target_pass(upd *u, double target, uint64_t limit, uint64_t *ops)
{
    rs_roam *L = u->L;
    double lo = target - target / 100.0, hi = target + target / 100.0;
    int reached = 0;
    uint32_t steps = 0;
    uint64_t fine = 0; /* operations since the target was reached */
    for (;;) {
        if (u->nomem || *ops >= limit || stop_now(L, &steps)) return 0;
        if (reached) { /* (past the cap: at the next count within the band, or at twice the cap) */
            uint64_t cap = TARGET_FINE_OPS > L->tris / 16u ? TARGET_FINE_OPS : L->tris / 16u;
            if (fine >= cap && ((L->tris >= lo && L->tris <= hi) || fine >= 2 * cap)) return 1;
            fine++;
        }
        const qent *s = top_split(L), *m = top_merge(L);
        if (!reached && L->tris > target) {
            if (!m) return 1;
            do_merge(u);
            if (L->tris <= target) reached = 1;
        } else if (!reached && L->tris < target) {
            if (!s || !(s->p > 0.0) || L->exhausted) return 1;
            if (!do_split(u)) continue;
            if (L->tris >= target) reached = 1;
        } else if (L->tris > hi) {
            if (!m) return 1;
            do_merge(u);
            /* over the band to below it: a split back would undo this
             * merge, and the next merge that split (a band narrower than
             * one step: 95 <-> 97 around a target of 96 until the op
             * limit, 0.4 s an update, found by the roam fuzzer) */
            if (L->tris < lo) { ++*ops; return 1; }
        } else if (L->tris < lo) {
            if (!s || !(s->p > 0.0) || L->exhausted) return 1;
            if (!do_split(u)) continue;
            if (L->tris > hi) { ++*ops; return 1; } /* (over the band to above it: the same) */
        } else if (s && m && s->p > m->p && !L->exhausted) {
            reached = 1;
            if (L->tris <= target) { if (!do_split(u)) continue; }
            else do_merge(u);
        } else return 1;
        ++*ops;
    }
}

static void scan_fresh(upd *u)
{
    u->L->qs->n = u->L->qm->n = 0;
    u->L->sp = 0;
    scan_mesh(u);
}

static rs_result update_run(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw, uint32_t budget);

/* Progress: pool nodes taken by splits (polls every few thousand split and
 * merge operations). A cancelled update stops as a spent budget does: the
 * mesh valid and crack-free, stats.update_done 0, the next update goes on. */
rs_result rs_roam_update(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw_in, uint32_t budget)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    rs_roam_view vw;
    rs_result r = rs__roam_view_in(ctx, L, vw_in, "rs_roam_update", &vw);
    if (r != RS_OK) return r;
    rs__progress pg;
    rs_ctx *saved;
    rs__roam_progress_begin(ctx, L, &pg, L->cap - L->base_count, &saved);
    return rs__roam_progress_end(ctx, L, &pg, update_run(ctx, L, &vw, budget), saved);
}

static rs_result update_run(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw, uint32_t budget)
{
    rs_result r = ensure_state(ctx, L);
    if (r != RS_OK) return r;
    view_params v;
    unsigned char visbuf[256], *vis;
    if ((r = rs__roam_view_begin(ctx, L, vw, &v, visbuf, sizeof visbuf, &vis)) != RS_OK) return r;
    upd u;
    memset(&u, 0, sizeof u);
    u.ctx = ctx; u.L = L; u.v = &v; u.vis = vis;
    u.tol = vw->pixel_error > 0.0 ? vw->pixel_error : 1.0;
    /* a triangle target starts from the tolerance the last update ended
     * at (the seed's gFrameVariance) */
    if (vw->target_triangles && L->tol > 0.0 && isfinite(L->tol)) u.tol = L->tol;
    v.tol = u.tol;
    u.mtol = vw->target_triangles ? u.tol : u.tol / (vw->merge_hysteresis > 0.0 ? vw->merge_hysteresis : MERGE_HYSTERESIS);
    u.full = L->full_next || v.k != L->last_k || u.tol != L->last_tol || u.mtol != L->last_mtol;
    double ex = v.eye[0] - L->last_eye[0], ey = v.eye[1] - L->last_eye[1], ez = v.eye[2] - L->last_eye[2];
    L->odo += sqrt(ex * ex + ey * ey + ez * ez);
    double turn = 0.0;
    for (int p = 0; p < 5; p++) {
        double nx = v.planes[p][0] - L->last_n[p][0], ny = v.planes[p][1] - L->last_n[p][1];
        double nz = v.planes[p][2] - L->last_n[p][2], d = sqrt(nx * nx + ny * ny + nz * nz);
        if (d > turn) turn = d;
        L->last_n[p][0] = v.planes[p][0]; L->last_n[p][1] = v.planes[p][1]; L->last_n[p][2] = v.planes[p][2];
    }
    L->rot += turn * (1.0 + 1e-9);
    /* the scan records' float readings keep millimetres within 4 km of
     * their base: past that, a new base and a full scan */
    if (L->odo - L->odo_base > ODO_REBASE) { L->odo_base = L->odo; u.full = 1; }
    u.trate = sqrt(ex * ex + ey * ey + ez * ez);
    u.rrate = turn;

    L->gen++;
    L->exhausted = 0;
    /* renumber once many live nodes came from the free list (docs/roam.md) */
    if (L->moved > (L->used - L->base_count - L->nfree) / 10u * COMPACT_TENTHS) compact_pool(L);
    uint64_t limit = budget ? budget : (uint64_t)UNBOUNDED_OPS_PER_NODE * L->cap + 1024;
    uint64_t ops = 0;
    int done, fixed;
    if (!vw->target_triangles && !budget && L->used == L->base_count) {
        /* no pool node in use (the first update, or one after a rebuild
         * of nothing): the tolerance pass would split the base mesh up to
         * the rebuild's mesh (the coarsest within the tolerance, so none
         * of its diamonds can merge) one heap operation at a time;
         * rs_roam_frame's depth-first refinement makes the same mesh
         * several times faster (40 -> 8 ms on the fractal drive). Then
         * the scan of every cluster at this view, which fills the scan
         * records (and finds nothing to split or merge), so that the
         * next update is incremental: the work of the first full scan
         * belongs to the update that built the mesh, not to the next. */
        rs__roam_reset_mesh(L);
        refine_params rp = { 0.0, 0, &v, vis, 0 };
        rs__roam_refine(L, &rp);
        ops = L->tris - L->base_tris; /* a split adds a triangle on the map */
        done = fixed = 0;
        if (!L->exhausted && !L->cancelled) {
            u.full = 1;
            scan_fresh(&u);
            done = tolerance_pass(&u, limit, &ops);
            fixed = done;
        }
    } else {
        scan_fresh(&u);
        done = tolerance_pass(&u, limit, &ops);
        fixed = done;
    }
    if (vw->target_triangles && done && !L->cancelled) {
        double target = vw->target_triangles;
        if (fabs((double)L->tris - target) > TARGET_BAND * target) {
            /* off the target: every leaf and diamond into the queues */
            u.all = 1;
            u.full = 1;
            scan_fresh(&u);
            done = target_pass(&u, target, limit, &ops);
            fixed = 0;
            /* a tolerance between the largest split and the smallest merge
             * priority left keeps this mesh at the next update */
            const qent *s = top_split(L), *m = top_merge(L);
            double ps = s ? s->p : 0.0;
            u.tol = m && m->p > ps && ps > 0.0 ? sqrt(ps * m->p) : ps > 0.0 ? ps : u.tol;
        }
    }
    if (vis != visbuf) rs__free(ctx, vis);
    /* the cached scans assume a completed update at this tolerance */
    L->full_next = !fixed || u.nomem;
    memcpy(L->last_eye, v.eye, sizeof v.eye);
    L->last_k = v.k;
    L->last_tol = u.tol;
    L->last_mtol = u.mtol;
    L->update_ops = (uint32_t)(ops > UINT32_MAX ? UINT32_MAX : ops);
    L->update_done = done;
    L->frame_passes = 1;
    L->threshold = u.tol;
    L->tol = u.tol;
    if (u.nomem) return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for the update queues");
    if (L->exhausted)
        return rs__fail(ctx, RS_ERR_POOL_EXHAUSTED, "ROAM: pool of %u nodes ran out in an update "
                        "(mesh valid but coarser: %u triangles)", L->cap - L->base_count, L->tris);
    rs__ok(ctx);
    return RS_OK;
}

#ifdef ROAM_UPDATE_DEBUG
int rs__roam_debug_check(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw);
int rs__roam_debug_check(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw)
{
    view_params v;
    unsigned char visbuf[256], *vis;
    rs__roam_view_begin(ctx, L, vw, &v, visbuf, sizeof visbuf, &vis);
    upd u;
    memset(&u, 0, sizeof u);
    u.ctx = ctx; u.L = L; u.v = &v; u.vis = vis;
    u.tol = vw->pixel_error > 0.0 ? vw->pixel_error : 1.0;
    roam_node *n = L->nodes;
    int bad = 0;
    for (uint32_t i = 0; i < L->used; i++) {
        uint32_t N, pp, lc = n[i].lc;
        if (lc == FREE) continue;
        if (lc == NIL) {
            if (n[i].e != NIL && item_prio_t(&u, i, 0, NULL) > u.tol) { fprintf(stderr, "leaf %u wants split\n", i); bad++; }
            continue;
        }
        if (lc == IMPL) {
            uint32_t rc = n[i].rc;
            for (uint32_t pos = 2; pos < L->ncut; pos++)
                if (!(rc & SPLIT_BIT(pos)) && (pos < 4 || (rc & SPLIT_BIT(pos >> 1u))) && item_prio_t(&u, i, pos, NULL) > u.tol) {
                    fprintf(stderr, "imp leaf %u/%u wants split\n", i, pos); bad++; }
        }
        for (uint32_t pos = lc == IMPL ? 1u : 0u; pos < (lc == IMPL ? L->ncut : 1u); pos++) {
            if (!rs__roam_mergeable(L, i, pos, &N, &pp)) continue;
            double p = item_prio_t(&u, i, pos, NULL), q = N != NIL ? item_prio_t(&u, N, pp, NULL) : 0;
            if (!(p > u.tol) && !(q > u.tol)) { fprintf(stderr, "missed merge node %u pos %u (lc %u) partner %u/%u prio %g %g\n", i, pos, lc, N, pp, p, q); bad++; }
        }
    }
    if (vis != visbuf) rs__free(ctx, vis);
    return bad;
}
#endif
