/* Seams between two landscapes on DEM tiles that share an edge row or
 * column: rs_roam_stitch splits border leaves of each until both have the
 * same vertices on the shared edge (docs/roam.md, "Seams between tiles"). */
#include "roam.h"

#include <string.h>

/* The edge as a line: points (s, c) (horizontal) or (c, s) (vertical). */
typedef struct edge_line {
    int vertical;
    int c;          /* the fixed coordinate */
    uint32_t len;   /* cells along the edge */
} edge_line;

/* Coordinate of corner (x, y) along the edge, -1 when off its line. */
static int along(const edge_line *e, int x, int y)
{
    if (e->vertical) return x == e->c ? y : -1;
    return y == e->c ? x : -1;
}

/* The patches along the edge, in order (count in *n). */
static uint32_t edge_patch(const rs_roam *L, const edge_line *e, uint32_t k)
{
    if (e->vertical) return k * L->npx + (e->c == 0 ? 0 : L->npx - 1);
    return (e->c == 0 ? 0 : (L->npy - 1) * L->npx) + k;
}

/* Walk the leaves touching the edge under triangle t (node, implicit
 * position pos; pos 0 for an explicit node): mark their corners on the
 * edge in `mark` when `find` < 0; else return 1 with *fn, *fp naming the
 * first leaf whose edge on the line holds point `find` strictly inside. */
static int walk_edge(const rs_roam *L, const edge_line *e, uint32_t node, uint32_t pos, const tri *t,
                     unsigned char *mark, int find, uint32_t *fn, uint32_t *fp)
{
    int s[3] = { along(e, t->ax, t->ay), along(e, t->bx, t->by), along(e, t->cx, t->cy) };
    if (s[0] < 0 && s[1] < 0 && s[2] < 0) return 0; /* the map lies on one side of its edge */
    const roam_node *nd = &L->nodes[node];
    int leaf;
    if (pos >= 2) leaf = pos >= L->ncut || !(nd->rc & SPLIT_BIT(pos));
    else leaf = nd->lc == NIL;
    if (leaf) {
        if (find < 0) {
            for (int k = 0; k < 3; k++)
                if (s[k] >= 0) mark[s[k]] = 1;
            return 0;
        }
        for (int a = 0; a < 3; a++)
            for (int b = a + 1; b < 3; b++)
                if (s[a] >= 0 && s[b] >= 0 && ((s[a] < find && find < s[b]) || (s[b] < find && find < s[a]))) {
                    *fn = node;
                    *fp = pos;
                    return 1;
                }
        return 0;
    }
    for (int k = 0; k < 2; k++) {
        tri u;
        child_tri(t, k, &u);
        int r;
        if (pos >= 2) r = walk_edge(L, e, node, 2 * pos + (uint32_t)k, &u, mark, find, fn, fp);
        else if (nd->lc == IMPL) r = walk_edge(L, e, node, 2u + (uint32_t)k, &u, mark, find, fn, fp);
        else r = walk_edge(L, e, k ? nd->rc : nd->lc, 0, &u, mark, find, fn, fp);
        if (r) return r;
    }
    return 0;
}

/* walk_edge over the patches k0..k1 along the edge (clamped). */
static int walk_patch_range(const rs_roam *L, const edge_line *e, uint32_t k0, uint32_t k1, unsigned char *mark,
                            int find, uint32_t *fn, uint32_t *fp)
{
    uint32_t np = e->vertical ? L->npy : L->npx;
    if (k1 >= np) k1 = np - 1;
    for (uint32_t k = k0; k <= k1; k++) {
        uint32_t p = edge_patch(L, e, k);
        for (uint32_t r = 2 * p; r < 2 * p + 2; r++) {
            tri t;
            node_tri(L, &L->nodes[r], &t);
            if (walk_edge(L, e, r, 0, &t, mark, find, fn, fp)) return 1;
        }
    }
    return 0;
}

static int walk_patches(const rs_roam *L, const edge_line *e, unsigned char *mark, int find, uint32_t *fn,
                        uint32_t *fp)
{
    return walk_patch_range(L, e, 0, UINT32_MAX, mark, find, fn, fp);
}

static int edge_of(const rs_roam *L, int which, edge_line *e)
{
    switch (which) {
    case RS_ROAM_EDGE_TOP: e->vertical = 0; e->c = 0; e->len = L->cw; return 1;
    case RS_ROAM_EDGE_BOTTOM: e->vertical = 0; e->c = (int)L->ch; e->len = L->cw; return L->ch % L->P == 0;
    case RS_ROAM_EDGE_LEFT: e->vertical = 1; e->c = 0; e->len = L->ch; return 1;
    case RS_ROAM_EDGE_RIGHT: e->vertical = 1; e->c = (int)L->cw; e->len = L->ch; return L->cw % L->P == 0;
    default: return 0;
    }
}

/* Split L's leaves on edge e until every point marked in `want` is a
 * vertex; 0 when the pool ran short, -1 when a progress poll said stop
 * (the meshes valid, the seam open). The leaf holding point s lies in the
 * patch of s (its neighbours are walked too, for a point on a patch
 * corner); after its splits only those patches' marks are made again (a
 * forced split further away only adds vertices: a later point already a
 * vertex is found in no leaf). */
static int add_vertices(rs_ctx *ctx, rs_roam *L, const edge_line *e, const unsigned char *want, unsigned char *have)
{
    memset(have, 0, e->len + 1u);
    walk_patches(L, e, have, -1, NULL, NULL);
    uint32_t done = 0;
    for (uint32_t s = 0; s <= e->len; s++) {
        if (!want[s] || have[s]) continue;
        if ((++done & 63u) == 0 && rs__poll(ctx)) return -1;
        uint32_t fn, fp, k = s / L->P, k0 = k ? k - 1 : 0;
        while (walk_patch_range(L, e, k0, k + 1, NULL, (int)s, &fn, &fp)) {
            L->sp = 0;
            if (rs__roam_split_leaf(L, fn, fp) != 0) { L->sp = 0; return 0; }
            /* the split's new leaves are not queued for anything here */
            for (uint32_t i = 0; i < L->sp; i++)
                if (L->stack[i] & TAG) L->nodes[L->stack[i] & ~TAG].rc &= ~QUEUED;
            L->sp = 0;
        }
        walk_patch_range(L, e, k0, k + 1, have, -1, NULL, NULL);
    }
    return 1;
}

static rs_result stitch(rs_ctx *ctx, rs_roam *a, int edge_a, rs_roam *b, int edge_b)
{
    if (!a || !b || a == b) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_stitch: two landscapes needed");
    edge_line ea, eb;
    if (!edge_of(a, edge_a, &ea) || !edge_of(b, edge_b, &eb))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_stitch: edge %d / %d is not an edge on the patch grid "
                        "(right and bottom edges need a cell count that is a multiple of the patch size)", edge_a, edge_b);
    if (ea.len != eb.len || a->P != b->P)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_stitch: edges of %u and %u cells, patches of %u and %u",
                        ea.len, eb.len, a->P, b->P);
    unsigned char *buf = rs__malloc(ctx, 4 * ((size_t)ea.len + 1));
    if (!buf) return rs__fail(ctx, RS_ERR_NOMEM, "rs_roam_stitch: out of memory");
    unsigned char *ma = buf, *mb = ma + ea.len + 1, *ha = mb + ea.len + 1, *hb = ha + ea.len + 1;
    a->gen++;
    b->gen++;
    int ok = 1;
    /* both edges subdivide the same dyadic hierarchy, so the union of the
     * two vertex sets is reached by splits alone, in one round */
    memset(ma, 0, ea.len + 1u);
    memset(mb, 0, ea.len + 1u);
    walk_patches(a, &ea, ma, -1, NULL, NULL);
    walk_patches(b, &eb, mb, -1, NULL, NULL);
    ok = add_vertices(ctx, b, &eb, ma, hb);
    if (ok == 1) ok = add_vertices(ctx, a, &ea, hb, ha);
    if (ok == 1) { /* the marks as a whole (the splits' marks were made again patch by patch) */
        memset(ha, 0, ea.len + 1u);
        memset(hb, 0, ea.len + 1u);
        walk_patches(a, &ea, ha, -1, NULL, NULL);
        walk_patches(b, &eb, hb, -1, NULL, NULL);
    }
    int same = ok == 1 && memcmp(ha, hb, ea.len + 1u) == 0;
    rs__free(ctx, buf);
    if (ok < 0) return RS_ERR_CANCELLED; /* (the message: rs__progress_end) */
    if (!ok)
        return rs__fail(ctx, RS_ERR_POOL_EXHAUSTED, "rs_roam_stitch: the pool ran out (meshes valid, seam open)");
    if (!same) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_stitch: the edges do not share a subdivision");
    rs__ok(ctx);
    return RS_OK;
}

/* Progress: the context's callback (rs_ctx_set_progress), a poll every 64
 * points split in; a stop leaves both meshes valid and the seam open. */
rs_result rs_roam_stitch(rs_ctx *ctx, rs_roam *a, int edge_a, rs_roam *b, int edge_b)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, 1, 1);
    return rs__progress_end(ctx, &pg, stitch(ctx, a, edge_a, b, edge_b));
}
