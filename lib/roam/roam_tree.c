/* ROAM bintree: splits with their forced splits, the implicit levels below
 * the block nodes (partner table, implicit splits), the depth-first
 * refinement and its decision rule (error, view and border-only), and the
 * error and triangle-count modes (docs/roam.md). */
#include "roam.h"

#include <math.h>
#include <string.h>

/* ---- bintree --------------------------------------------------------------- */

/* The finest explicit level: its subtree is implicit (IMPL). */
static int is_block(const rs_roam *L, const roam_node *n)
{
    int p = (int)n->bx - (int)n->ax, q = (int)n->by - (int)n->ay;
    return p * p + q * q == (int)L->ncut; /* legs^2 = 2^dq */
}

static void relink(roam_node *n, uint32_t nb, uint32_t old, uint32_t now)
{
    if (n[nb].base == old) n[nb].base = now;
    else if (n[nb].left == old) n[nb].left = now;
    else if (n[nb].right == old) n[nb].right = now;
}

/* Nodes a split of leaf t needs, force-splits included (worst case): two
 * per split, none for block nodes (their subtrees are implicit). */
static uint32_t split_need(const rs_roam *L, uint32_t t)
{
    const roam_node *n = L->nodes;
    uint32_t need = 0, cur = t;
    for (;;) {
        uint32_t c = is_block(L, &n[cur]) ? 0u : 2u;
        uint32_t b = n[cur].base;
        if (b == NIL) return need + c;
        if (n[b].base == cur) return need + 2 * c; /* diamond: b is on cur's level */
        need += 2 * c; /* cur and its partner, once b is split */
        cur = b;
    }
}

static int tris_delta(const rs_roam *L, const tri *t)
{
    if (t->on) return 1;
    tri c0, c1;
    child_tri(t, 0, &c0);
    child_tri(t, 1, &c1);
    return tri_inside(L, &c0) + tri_inside(L, &c1) - tri_inside(L, t);
}

/* Ask rs__roam_refine() to test the untested implicit leaves of block r. */
static void queue_block(rs_roam *L, uint32_t r)
{
    roam_node *nd = &L->nodes[r];
    if (nd->rc & QUEUED) return;
    nd->rc |= QUEUED;
    L->stack[L->sp++] = r | TAG;
}

/* Split leaf t, force-splitting its base neighbour first when they do not
 * form a diamond. The caller reserved split_need(t) nodes. */
static void split(rs_roam *L, uint32_t t)
{
    roam_node *n = L->nodes;
    if (n[t].lc != NIL) return;
    if (n[t].base != NIL && n[n[t].base].base != t) split(L, n[t].base);
    touch_patch(L, t);
    if (is_block(L, &n[t])) {
        /* subtree implicit: no nodes, no relinks (neighbours keep pointing
         * at this node); its base partner is on the same level */
        tri tt;
        node_tri(L, &n[t], &tt);
        n[t].lc = IMPL; n[t].rc = 0;
        L->tris += (uint32_t)tris_delta(L, &tt);
        if (L->dq > 1) queue_block(L, t);
        uint32_t b = n[t].base;
        if (b != NIL && n[b].lc == NIL) split(L, b);
        return;
    }
    uint32_t lc;
    if (L->free_head != NIL) { /* a pair a merge gave back */
        lc = L->free_head;
        L->free_head = n[lc].rc;
        L->nfree -= 2;
        L->moved += 2;
    } else {
        lc = L->used;
        L->used += 2;
    }
    uint32_t rc = lc + 1;
    if (L->par) { /* frame-coherent updates: parents, and new clusters unscanned */
        L->par[lc] = L->par[rc] = t;
        L->cscan[lc].rc = L->cscan[rc].rc = -1.0f;
        L->cscan[lc].cls = L->cscan[rc].cls = SCAN_NO_CLASS;
    }
    roam_node *T = &n[t];
    int ax = T->ax, ay = T->ay, bx = T->bx, by = T->by, cx, cy;
    node_corner(T, &cx, &cy);
    uint16_t mx = (uint16_t)((bx + cx) / 2), my = (uint16_t)((by + cy) / 2);
    roam_node *Lc = &n[lc], *Rc = &n[rc];
    Lc->lc = Lc->rc = NIL; Rc->lc = Rc->rc = NIL;
    Lc->base = T->left; Lc->left = rc; Lc->right = NIL;
    Rc->base = T->right; Rc->left = NIL; Rc->right = lc;
    /* heap index h -> 2h, 2h + 1 inside the patch; below the last error
     * level come the cell halves */
    if (T->e != NIL && (T->e & (uint32_t)(L->epp - 1)) < (uint32_t)(L->epp / 2)) {
        uint32_t hh = T->e & (uint32_t)(L->epp - 1);
        Lc->e = T->e + hh; Rc->e = T->e + hh + 1;
    } else Lc->e = Rc->e = NIL;
    Lc->ax = mx; Lc->ay = my; Lc->bx = T->ax; Lc->by = T->ay;
    Rc->ax = mx; Rc->ay = my; Rc->bx = (uint16_t)cx; Rc->by = (uint16_t)cy;
    T->lc = lc; T->rc = rc;
    L->stack[L->sp++] = rc;
    L->stack[L->sp++] = lc;
    if (T->left != NIL) relink(n, T->left, t, lc);
    if (T->right != NIL) relink(n, T->right, t, rc);
    if (T->e != NIL && L->pin[T->e >> L->elog]) L->tris++;
    else L->tris += (uint32_t)(inside_xy(L, mx, my, ax, ay, bx, by) + inside_xy(L, mx, my, cx, cy, ax, ay))
                    - (uint32_t)inside_xy(L, ax, ay, bx, by, cx, cy);
    uint32_t b = T->base;
    if (b != NIL) {
        if (n[b].lc != NIL) {
            n[n[b].lc].right = rc; n[n[b].rc].left = lc;
            n[lc].right = n[b].rc; n[rc].left = n[b].lc;
        } else split(L, b);
    }
}
/* ---- implicit levels ---------------------------------------------------------- */

/* t (a block's triangle) -> the triangle of its implicit position pos. */
static void descend_to(tri *t, uint32_t pos)
{
    for (uint32_t d = pos_depth(pos); d-- > 0;) {
        tri c;
        child_tri(t, (int)((pos >> d) & 1u), &c);
        *t = c;
    }
}

/* Triangle of implicit position pos of block node r (pos 1: the block). */
static void imp_tri(const rs_roam *L, uint32_t r, uint32_t pos, tri *t)
{
    node_tri(L, &L->nodes[r], t);
    descend_to(t, pos);
}

static int collinear(int x0, int y0, int x1, int y1, int px, int py)
{
    return (x1 - x0) * (py - y0) == (y1 - y0) * (px - x0);
}

static int on_edge(int x0, int y0, int x1, int y1, const tri *t)
{
    return collinear(x0, y0, x1, y1, t->bx, t->by) && collinear(x0, y0, x1, y1, t->cx, t->cy);
}

/* Child of triangle u (0 or 1) on whose side the point q2 / 2 lies. */
static int child_toward(const tri *u, int qx2, int qy2)
{
    int mx2 = u->bx + u->cx, my2 = u->by + u->cy;
    int dx = 2 * u->ax - mx2, dy = 2 * u->ay - my2;
    long sb = (long)dx * (2 * u->by - my2) - (long)dy * (2 * u->bx - mx2);
    long sq = (long)dx * (qy2 - my2) - (long)dy * (qx2 - mx2);
    return (sb > 0) == (sq > 0) ? 0 : 1;
}

static void ref_tri(int ax, int ay, int bx, int by, tri *t)
{
    t->ax = ax; t->ay = ay; t->bx = bx; t->by = by;
    t->cx = ax - (by - ay); t->cy = ay + (bx - ax);
    t->on = 1;
}

/* Where the diamond partner of each implicit position lies. Every block's
 * subtree is the same figure up to an isometry and a scale (the right
 * corner is always apex + rot90(left - apex)), so this is worked out once
 * on a reference block B: the partner of position pos is a position of
 * the block across edge pwhere[pos] of B (PW_SELF when the hypotenuse is
 * inside B). The block across an edge is B's image under the point
 * reflection about the edge's midpoint when the edge has the same role
 * (left leg, right leg, hypotenuse) in both blocks, as for diamond
 * partners and leg neighbours in two patches; else (leg neighbours inside
 * a patch) under the reflection across the edge's line, which swaps the
 * roles of the legs. ppos[1][pos] is the partner's position in the first
 * case, ppos[0][pos] in the second (and for PW_SELF, PW_BASE). */
enum { PW_SELF = 0, PW_LEFT = 1, PW_RIGHT = 2, PW_BASE = 3 };

static uint32_t descend_toward(tri N, const tri *t, uint32_t d)
{
    /* a point inside the partner, doubled: its apex 2m - a plus m */
    int qx2 = 3 * ((t->bx + t->cx) / 2) - t->ax, qy2 = 3 * ((t->by + t->cy) / 2) - t->ay;
    uint32_t pp = 1;
    for (uint32_t j = 0; j < d; j++) {
        tri c;
        int k = child_toward(&N, qx2, qy2);
        child_tri(&N, k, &c);
        N = c;
        pp = 2 * pp + (uint32_t)k;
    }
    return pp;
}

void rs__roam_build_partner_table(rs_roam *L)
{
    /* dq is even (min(IMPL_DEPTH, 2 log2 P)): block legs 2^(dq/2) on the axes */
    tri B, M, S;
    ref_tri(0, 0, 1 << (L->dq / 2), 0, &B);
    for (uint32_t pos = 2; pos < L->ncut; pos++) {
        tri t = B;
        uint32_t d = pos_depth(pos);
        descend_to(&t, pos);
        /* M: the mirror image across the edge, S: the point reflection */
        if (on_edge(B.ax, B.ay, B.bx, B.by, &t)) {
            L->pwhere[pos] = PW_LEFT;
            ref_tri(B.ax, B.ay, 2 * B.ax - B.cx, 2 * B.ay - B.cy, &M);
            ref_tri(B.bx, B.by, B.ax, B.ay, &S);
        } else if (on_edge(B.ax, B.ay, B.cx, B.cy, &t)) {
            L->pwhere[pos] = PW_RIGHT;
            ref_tri(B.ax, B.ay, B.cx, B.cy, &M);
            ref_tri(B.cx, B.cy, B.ax + B.cx - B.bx, B.ay + B.cy - B.by, &S);
        } else if (on_edge(B.bx, B.by, B.cx, B.cy, &t)) {
            L->pwhere[pos] = PW_BASE;
            ref_tri(B.bx + B.cx - B.ax, B.by + B.cy - B.ay, B.cx, B.cy, &S);
            M = S;
        } else {
            L->pwhere[pos] = PW_SELF;
            M = S = B;
        }
        L->ppos[0][pos] = (unsigned char)descend_toward(M, &t, d);
        L->ppos[1][pos] = (unsigned char)descend_toward(S, &t, d);
    }
    /* B's apex is 0 and its legs the axes: its positions' coordinates are
     * already in units of the block's legs / 2^(dq/2) */
    for (uint32_t pos = 1; pos < 2 * L->ncut; pos++) {
        tri t = B;
        descend_to(&t, pos);
        unsigned char *g = L->pgeo[pos];
        g[0] = (unsigned char)t.ax; g[1] = (unsigned char)t.ay; g[2] = (unsigned char)t.bx;
        g[3] = (unsigned char)t.by; g[4] = (unsigned char)t.cx; g[5] = (unsigned char)t.cy;
        g[6] = (unsigned char)((t.bx + t.cx) / 2); g[7] = (unsigned char)((t.by + t.cy) / 2);
    }
    for (uint32_t pos = 1; pos < L->ncut; pos++) {
        uint32_t m = 0;
        for (uint32_t c = 2; c < L->ncut; c++) {
            uint32_t a = c;
            while (a > pos) a >>= 1;
            if (a == pos && c != pos) m |= SPLIT_BIT(c);
        }
        L->below[pos] = m;
    }
}

/* The implicit leaves of a block waiting for a test (SPLIT_BIT space):
 * positions above the cell halves whose parent is split (the block's
 * children always) and that are neither split nor tested. */
static uint32_t untested(const rs_roam *L, uint32_t rc)
{
    uint32_t split = rc & (SPLIT_BIT(L->ncut) - 1u);
    /* children of positions 2.. (bit i = position i + 2): bits 2i + 2, 2i + 3 */
    uint32_t x = split & ((1u << (L->ncut / 2 - 2)) - 1u) & 0xFFFFu;
    x = (x | (x << 8)) & 0x00FF00FFu;
    x = (x | (x << 4)) & 0x0F0F0F0Fu;
    x = (x | (x << 2)) & 0x33333333u;
    x = (x | (x << 1)) & 0x55555555u;
    uint32_t kids = (x * 3u) << 2 | 3u;
    return kids & ~split & ~((rc >> 14) & 0x3FFFu) & (SPLIT_BIT(L->ncut) - 1u);
}

/* Block holding the partner of implicit position pos of block r (NIL at
 * the landscape's border), and the partner's position there. */
static uint32_t partner_node(const rs_roam *L, uint32_t r, uint32_t pos, uint32_t *pp)
{
    const roam_node *n = L->nodes;
    uint32_t N;
    int same_role = 0;
    switch (L->pwhere[pos]) {
    case PW_LEFT: N = n[r].left; same_role = N != NIL && n[N].left == r; break;
    case PW_RIGHT: N = n[r].right; same_role = N != NIL && n[N].right == r; break;
    case PW_BASE: N = n[r].base; break;
    default: N = r; break;
    }
    *pp = L->ppos[same_role][pos];
    return N;
}

/* Does position a come before position b in the depth-first order of
 * scan_block (a not inside b's subtree)? Compared at the deeper depth. */
static int pre_before(uint32_t a, uint32_t b)
{
    uint32_t da = pos_depth(a), db = pos_depth(b);
    return da < db ? (a << (db - da)) <= b : a < (b << (da - db));
}

/* Record implicit position pos of block r split: its children are new
 * leaves to test when they are above the cell halves. */
static void imp_mark(rs_roam *L, uint32_t r, uint32_t pos, const tri *t)
{
    L->nodes[r].rc |= SPLIT_BIT(pos);
    L->tris += (uint32_t)tris_delta(L, t);
    touch_patch(L, r);
    if (2 * pos >= L->ncut) return;
    if (r != L->scan) queue_block(L, r);
    else if (pre_before(pos, L->scan_pos)) L->scan_dirty = 1; /* the scan has passed it */
}

/* Split implicit leaf pos (triangle t) of block r with its diamond
 * partner, force-splitting first what the partner needs: an unsplit
 * neighbour block by split(), an unsplit parent of the partner by
 * imp_split() (a leaf's base neighbour is at most one level coarser, so
 * nothing above the parent can be unsplit). The caller reserved
 * imp_need(r, pos) nodes. */
static void imp_split(rs_roam *L, uint32_t r, uint32_t pos, const tri *t)
{
    roam_node *n = L->nodes;
    if (n[r].rc & SPLIT_BIT(pos)) return;
    uint32_t pp, N = partner_node(L, r, pos, &pp);
    if (N != NIL) {
        if (n[N].lc == NIL) split(L, N);
        uint32_t par = pp >> 1;
        if (par > 1 && !(n[N].rc & SPLIT_BIT(par))) {
            tri u;
            imp_tri(L, N, par, &u);
            imp_split(L, N, par, &u);
        }
    }
    imp_mark(L, r, pos, t);
    if (N != NIL) {
        /* the partner: t turned half a turn about its hypotenuse midpoint */
        tri u;
        u.ax = t->bx + t->cx - t->ax; u.ay = t->by + t->cy - t->ay;
        u.bx = t->cx; u.by = t->cy; u.cx = t->bx; u.cy = t->by;
        u.on = N == r ? t->on : (n[N].e != NIL && L->pin[n[N].e >> L->elog]);
        imp_mark(L, N, pp, &u);
    }
}

/* Nodes imp_split(r, pos) may take (worst case): the implicit force chain
 * is free until it reaches an unsplit block, then split_need of that. */
static uint32_t imp_need(const rs_roam *L, uint32_t r, uint32_t pos)
{
    const roam_node *n = L->nodes;
    for (;;) {
        uint32_t pp, N = partner_node(L, r, pos, &pp);
        if (N == NIL) return 0;
        if (n[N].lc == NIL) return split_need(L, N);
        uint32_t par = pp >> 1;
        if (par <= 1 || (n[N].rc & SPLIT_BIT(par))) return 0;
        r = N;
        pos = par;
    }
}

void rs__roam_reset_mesh(rs_roam *L)
{
    memcpy(L->nodes, L->base_copy, (size_t)L->base_count * sizeof(roam_node));
    L->used = L->base_count;
    L->free_head = NIL;
    L->nfree = 0;
    L->tris = L->base_tris;
    L->exhausted = 0;
    /* every patch may have changed */
    L->full_next = 1;
    L->gen++;
    for (uint32_t p = 0; p < L->npx * L->npy; p++) L->pgen[p] = L->gen;
    for (size_t u = 0; u < (size_t)L->npx * L->npy * L->upp; u++) L->ugen[u] = L->gen;
}

/* ---- refinement ------------------------------------------------------------ */

/* Decision for a leaf: triangle t in patch `patch`, its error bound cached
 * in `slot` (NIL: not cached). Cell halves never come here. */
static int wants_split(rs_roam *L, uint32_t slot, const tri *t, uint32_t patch, const refine_params *rp)
{
    if (rp->border_only) return tri_class(L, t) == NODE_STRADDLES;
    if (!rp->view) return rs__roam_err_above(L, slot, t, rp->max_error);
    return view_prio(L, slot, t, patch, rp->view, rp->vis) > rp->view->tol;
}

/* Test the untested implicit leaves of block r below position pos
 * (triangle t, squared legs 2^lv; st: the terms of the legs-2-sqrt-2
 * triangle above it, if any), in depth-first order, skipping subtrees
 * without untested leaves (a block scanned again). Returns 0 to
 * go on, 1 when abandoned for stop_above, -1 when the pool ran out. */
static int scan_block(rs_roam *L, uint32_t r, uint32_t pos, const tri *t, uint32_t lv, s_terms *st,
                      const refine_params *rp)
{
    roam_node *n = L->nodes;
    /* error mode on the map: the implicit levels have closed forms */
    int fast = t->on && !rp->view && !rp->border_only;
    for (int k = 0; k < 2; k++) {
        uint32_t c = 2 * pos + (uint32_t)k;
        if (c >= L->ncut) return 0; /* cell halves */
        tri u;
        child_tri(t, k, &u);
        s_terms cs, *sub = st;
        if (lv == 4) { cs.have = 0; cs.S = u; sub = &cs; }
        if (!(n[r].rc & (SPLIT_BIT(c) | TESTED_BIT(c)))) {
            n[r].rc |= TESTED_BIT(c);
            int want;
            if (fast) {
                float e; /* lv <= dq <= 4: every implicit level has a closed form */
                if (!sub) e = rs__roam_on_map_err(L, &u);
                else {
                    if (!sub->have) rs__roam_load_s_terms(L, sub);
                    e = lv == 4 ? sub->s : lv == 3 ? sub->r[k] : sub->q[pos & 1u][k];
                }
                want = e > 0.0f && (double)e * L->zs > rp->max_error;
            } else want = wants_split(L, rs__roam_imp_slot(L, &n[r], c), &u, n[r].e >> L->elog, rp);
            if (want) {
                if (imp_need(L, r, c) > pool_avail(L)) { L->exhausted = 1; return -1; }
                L->scan_pos = c;
                imp_split(L, r, c, &u);
                if (rp->stop_above && L->tris > rp->stop_above) return 1;
            }
        }
        if ((n[r].rc & SPLIT_BIT(c)) && (untested(L, n[r].rc) & L->below[c])) {
            int res = scan_block(L, r, c, &u, lv - 1, sub, rp);
            if (res) return res;
        }
    }
    return 0;
}

static int refine_loop(rs_roam *L, const refine_params *rp);

/* Depth-first refinement with an explicit stack: every explicit node is
 * pushed when it is created (children of forced splits too), and a block
 * whose implicit subtree got untested leaves is pushed once (QUEUED), so
 * each leaf is tested once, and neighbouring triangles are handled close
 * together in time (the DEM rows, error slots and neighbour nodes they
 * touch stay in cache). The split sequence depends only on the DEM and the
 * decision rule, never on the pool size; refinement stops at the first
 * split the pool cannot hold, so the mesh of a larger pool is a refinement
 * of a smaller pool's. Returns 1 when abandoned for stop_above. */
int rs__roam_refine(rs_roam *L, const refine_params *rp)
{
    roam_node *n = L->nodes;
    uint32_t *st = L->stack;
    L->sp = 0;
    L->scan = NIL;
    /* the passes of a triangle budget's search test the same nodes at
     * other thresholds: they keep every bound they compute */
    if (!rp->view && !rp->border_only)
        L->err_stop = rp->stop_above ? INFINITY : rs__roam_err_stop(rp->max_error, L->zs);
    for (uint32_t i = L->used; i-- > 0;) { /* node 0 on top */
        if (n[i].lc == NIL) st[L->sp++] = i;
        else if (n[i].lc == IMPL && L->dq > 1) { n[i].rc |= QUEUED; st[L->sp++] = i | TAG; }
    }
    int res = refine_loop(L, rp);
    if (!rp->view && !rp->border_only) L->err_empty = 0; /* the bounds this pass computed are cached now */
    return res;
}

/* rs__roam_refine's loop over the stack. A poll that asks to stop leaves
 * the mesh as it is (every split is complete with its forced splits: valid
 * and crack-free, as when the pool runs out) and unqueues what the stack
 * still held. */
static int refine_loop(rs_roam *L, const refine_params *rp)
{
    roam_node *n = L->nodes;
    uint32_t *st = L->stack;
    uint32_t steps = 0;
    while (L->sp) {
        if (++steps == ROAM_POLL_STEPS) {
            steps = 0;
            if (rs__roam_poll(L)) {
                for (uint32_t k = 0; k < L->sp; k++)
                    if (st[k] & TAG) n[st[k] & ~TAG].rc &= ~QUEUED;
                L->sp = 0;
                return 0;
            }
        }
        uint32_t i = st[--L->sp];
        tri t;
        if (i & TAG) {
            i &= ~TAG;
            n[i].rc &= ~QUEUED;
            node_tri(L, &n[i], &t);
            L->scan = i;
            int res = 0;
            while (!res && untested(L, n[i].rc)) {
                L->scan_dirty = 0;
                res = scan_block(L, i, 1, &t, L->dq, NULL, rp);
                if (!L->scan_dirty) break;
            }
            L->scan = NIL;
            if (res < 0) return 0;
            if (res > 0) return 1;
            continue;
        }
        if (n[i].lc != NIL) continue; /* force-split after it was pushed */
        if (n[i].e == NIL) continue;  /* cell halves (patches of one cell) */
        node_tri(L, &n[i], &t);
        if (!wants_split(L, rs__roam_err_slot(L, &n[i]), &t, n[i].e >> L->elog, rp)) continue;
        uint32_t need = split_need(L, i);
        if (need > pool_avail(L)) { L->exhausted = 1; return 0; }
        split(L, i);
        if (rp->stop_above && L->tris > rp->stop_above) return 1;
    }
    return 0;
}

/* Error bound of triangle t from the cache when it is there, else computed
 * (and not stored: the landscape is const here). */
static float peek_err(const rs_roam *L, uint32_t slot, const tri *t)
{
    float e = slot == NIL ? NAN : err_get(L, slot);
    return e == e ? e : rs__roam_compute_err(L, t);
}

/* Largest bound over the unsplit implicit leaves of block nd below
 * position pos (triangle t); cell halves have none. `inside_only`: leaves
 * on the map only; `skip_inf`: leave out +inf (straddling the map edge). */
static float imp_leaves_max(const rs_roam *L, const roam_node *nd, uint32_t pos, const tri *t, int inside_only,
                            int skip_inf)
{
    float m = 0.0f;
    for (int k = 0; k < 2; k++) {
        uint32_t c = 2 * pos + (uint32_t)k;
        if (c >= L->ncut) return m;
        tri u;
        child_tri(t, k, &u);
        float e;
        if (nd->rc & SPLIT_BIT(c)) e = imp_leaves_max(L, nd, c, &u, inside_only, skip_inf);
        else {
            if (inside_only && !tri_inside(L, &u)) continue;
            e = peek_err(L, rs__roam_imp_slot(L, nd, c), &u);
            if (skip_inf && e == INFINITY) continue;
        }
        if (e > m) m = e;
    }
    return m;
}

/* Largest error bound over the leaves on the map (metres). Computed when
 * the stats are asked for, not after every refinement: it is a scan of
 * every node, and meshing does not need it. */
double rs__roam_leaves_max_bound(const rs_roam *L)
{
    double mb = 0.0;
    for (uint32_t i = 0; i < L->used; i++) {
        const roam_node *nd = &L->nodes[i];
        tri t;
        node_tri(L, nd, &t);
        float e;
        if (nd->lc == IMPL) e = imp_leaves_max(L, nd, 1, &t, 1, 0);
        else if (nd->lc != NIL || nd->e == NIL || !tri_inside(L, &t)) continue;
        else e = peek_err(L, rs__roam_err_slot(L, nd), &t); /* never tested when the pool ran out first */
        if ((double)e > mb) mb = e;
    }
    return mb * L->zs;
}

/* ---- modes --------------------------------------------------------------------- */

rs_result rs_roam_refine_error(rs_ctx *ctx, rs_roam *L, double max_error)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!L) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_refine_error: roam is NULL");
    if (!(max_error >= 0.0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM: max_error %g must be >= 0", max_error);
    rs__progress pg;
    rs_ctx *saved;
    rs__roam_progress_begin(ctx, L, &pg, L->cap - L->base_count, &saved);
    rs__roam_reset_mesh(L);
    refine_params rp = { max_error, 0, NULL, NULL, 0 };
    rs__roam_refine(L, &rp);
    L->threshold = max_error;
    rs_result r = RS_OK;
    if (L->exhausted)
        r = rs__fail(ctx, RS_ERR_POOL_EXHAUSTED, "ROAM: pool of %u nodes ran out at max error %g m "
                     "(mesh valid but coarser: %u triangles)", L->cap - L->base_count, max_error, L->tris);
    r = rs__roam_progress_end(ctx, L, &pg, r, saved);
    if (!r) rs__ok(ctx);
    return r;
}

/* Largest error of a base-mesh leaf: at that threshold nothing splits. */
static float base_max_error(rs_roam *L)
{
    float m = 0.0f;
    for (uint32_t i = 0; i < L->base_count; i++) {
        if ((i & 15) == 15 && rs__roam_poll(L)) return 0.0f; /* the first bounds of the map: ~50 ms at 1025^2 */
        const roam_node *nd = &L->base_copy[i];
        tri t;
        node_tri(L, nd, &t);
        float e;
        if (nd->lc == IMPL) e = imp_leaves_max(L, nd, 1, &t, 0, 1);
        else if (nd->lc != NIL) continue;
        else e = rs__roam_node_err(L, nd, &t);
        if (e > m && e != INFINITY) m = e;
    }
    return m;
}

static uint32_t float_bits(float f) { uint32_t u; memcpy(&u, &f, 4); return u; }
static float bits_float(uint32_t u) { float f; memcpy(&f, &u, 4); return f; }

rs_result rs_roam_refine_count(rs_ctx *ctx, rs_roam *L, uint32_t max_triangles)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!L) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_refine_count: roam is NULL");
    if (L->base_tris > max_triangles) {
        rs__roam_reset_mesh(L);
        return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: the base mesh already has %u triangles > %u", L->base_tris,
                        max_triangles);
    }
    /* Smallest error threshold (over float bit patterns, which order like
     * the values for non-negative floats) whose mesh fits the budget. */
    /* The count is monotone in the threshold and the base mesh (<= budget)
     * is what any threshold >= hi gives, so the search finds the smallest
     * threshold that fits. */
    /* progress: each pass's nodes (at most 32 passes and the last one) */
    rs__progress pg;
    rs_ctx *saved;
    rs__roam_progress_begin(ctx, L, &pg, (uint64_t)33 * (L->cap - L->base_count), &saved);
    uint32_t lo = 0, hi = float_bits(base_max_error(L));
    while (lo < hi && !L->cancelled) {
        uint32_t mid = lo + (hi - lo) / 2;
        rs__roam_reset_mesh(L);
        refine_params rp = { (double)bits_float(mid) * L->zs, 0, NULL, NULL, max_triangles };
        int over = rs__roam_refine(L, &rp);
        if (!over && L->tris <= max_triangles) hi = mid; else lo = mid + 1;
    }
    rs_result r = L->cancelled ? RS_OK : rs_roam_refine_error(ctx, L, (double)bits_float(lo) * L->zs);
    if (L->cancelled) rs__roam_reset_mesh(L); /* a trial's mesh may be over the budget */
    return rs__roam_progress_end(ctx, L, &pg, r, saved);
}


/* ---- split and merge by name (rs_roam_update) ------------------------------------ */

void rs__roam_item_tri(const rs_roam *L, uint32_t node, uint32_t pos, tri *t, uint32_t *slot, uint32_t *patch)
{
    const roam_node *nd = &L->nodes[node];
    if (pos >= 2) {
        imp_tri(L, node, pos, t);
        *slot = rs__roam_imp_slot(L, nd, pos);
    } else {
        node_tri(L, nd, t);
        *slot = rs__roam_err_slot(L, nd);
    }
    *patch = nd->e == NIL ? 0 : nd->e >> L->elog;
}

int rs__roam_split_leaf(rs_roam *L, uint32_t node, uint32_t pos)
{
    L->scan = NIL;
    if (pos < 2) {
        if (split_need(L, node) > pool_avail(L)) return -1;
        split(L, node);
        return 0;
    }
    if (imp_need(L, node, pos) > pool_avail(L)) return -1;
    tri t;
    imp_tri(L, node, pos, &t);
    imp_split(L, node, pos, &t);
    return 0;
}

/* Is (node, pos) split into two leaves? */
static int split_into_leaves(const rs_roam *L, uint32_t node, uint32_t pos)
{
    const roam_node *n = L->nodes;
    const roam_node *nd = &n[node];
    if (pos >= 2) {
        if (nd->lc != IMPL || !(nd->rc & SPLIT_BIT(pos))) return 0;
        if (node < L->base_count && L->base_copy[node].lc == IMPL && (L->base_copy[node].rc & SPLIT_BIT(pos)))
            return 0; /* a split of the base mesh */
        return 2 * pos >= L->ncut || !(nd->rc & (SPLIT_BIT(2 * pos) | SPLIT_BIT(2 * pos + 1)));
    }
    if (pos == 1) /* a block whose subtree is just its two children */
        return nd->lc == IMPL && !(nd->rc & (SPLIT_BIT(L->ncut) - 1u))
               && !(node < L->base_count && L->base_copy[node].lc == IMPL);
    if (nd->lc == NIL || nd->lc == IMPL || nd->lc == FREE) return 0;
    return nd->lc >= L->base_count && n[nd->lc].lc == NIL && n[nd->rc].lc == NIL;
}

int rs__roam_mergeable(const rs_roam *L, uint32_t node, uint32_t pos, uint32_t *partner, uint32_t *ppos)
{
    const roam_node *n = L->nodes;
    if (!split_into_leaves(L, node, pos)) return 0;
    uint32_t N, pp;
    if (pos >= 2) N = partner_node(L, node, pos, &pp);
    else { N = n[node].base; pp = pos; }
    *partner = N;
    *ppos = pp;
    if (N == NIL || (N == node && pp == pos)) return 1;
    return split_into_leaves(L, N, pp);
}

static void merge_one(rs_roam *L, uint32_t node, uint32_t pos)
{
    roam_node *n = L->nodes;
    tri t;
    uint32_t slot, patch;
    rs__roam_item_tri(L, node, pos, &t, &slot, &patch);
    L->tris -= (uint32_t)tris_delta(L, &t);
    touch_patch(L, node);
    if (pos >= 2) {
        n[node].rc &= ~SPLIT_BIT(pos);
        return;
    }
    if (pos == 1) { n[node].lc = n[node].rc = NIL; return; }
    uint32_t lc = n[node].lc, rc = n[node].rc;
    /* the children's base neighbours are this node's leg neighbours again */
    uint32_t nl = n[lc].base, nr = n[rc].base;
    if (nl != NIL) relink(n, nl, lc, node);
    if (nr != NIL) relink(n, nr, rc, node);
    n[node].left = nl;
    n[node].right = nr;
    n[node].lc = n[node].rc = NIL;
    n[lc].lc = n[rc].lc = FREE;
    n[lc].rc = L->free_head;
    L->free_head = lc;
    L->nfree += 2;
}

void rs__roam_merge(rs_roam *L, uint32_t node, uint32_t pos)
{
    uint32_t N, pp;
    if (!rs__roam_mergeable(L, node, pos, &N, &pp)) return;
    merge_one(L, node, pos);
    if (N != NIL && !(N == node && pp == pos)) merge_one(L, N, pp);
}

int rs__roam_item_parent(const rs_roam *L, uint32_t node, uint32_t pos, uint32_t *pn, uint32_t *ppos)
{
    if (pos >= 4) { *pn = node; *ppos = pos >> 1; return 1; }
    if (pos >= 2) { *pn = node; *ppos = 1; return 1; }
    uint32_t p = L->par ? L->par[node] : NIL;
    if (p == NIL) return 0;
    *pn = p;
    *ppos = 0; /* a block's children are implicit: explicit parents are never blocks */
    return 1;
}
