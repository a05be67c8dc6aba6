/* Private: the ROAM terrain mesher, shared by lib/roam*.c (which file
 * holds what: docs/roam.md, "Source files"). A Landscape of patches, each
 * two bintree roots, with nodes from a fixed pool linked by 32-bit indices
 * (the seed's five links). Design notes and the reasons behind the
 * choices: docs/roam.md. */
#ifndef RS_ROAM_H
#define RS_ROAM_H
#include "dem.h"

#include <math.h>
#include <string.h>

#define NIL 0xFFFFFFFFu
/* The finest levels are implicit: a split node at the "block level" (legs^2
 * = 2^dq, dq = min(IMPL_DEPTH, 2 log2 P)) gets lc = IMPL and keeps in rc the
 * state of its subtree of dq levels, by heap position inside the block (the
 * block is position 1, the children of position p are 2p and 2p + 1;
 * positions >= 2^dq are cell halves, never split): a split bit and a tested
 * bit per position 2 .. 2^dq - 1, and QUEUED while a stack entry asks for
 * its untested leaves. See docs/roam.md. */
#define IMPL 0xFFFFFFFEu
/* lc of a pool node on the free list (rs_roam_update's merges); its rc is
 * the next free pair (nodes come and go in pairs: lc, lc + 1) */
#define FREE 0xFFFFFFFDu
#define IMPL_DEPTH 4
#if IMPL_DEPTH > 4
#error "the split and tested bits of positions 2..15 fill rc (see TESTED_BIT)"
#endif
#define SPLIT_BIT(pos) (1u << ((pos) - 2u))
#define TESTED_BIT(pos) (1u << ((pos) + 12u))   /* positions 2..15 -> bits 14..27 */
#define QUEUED 0x80000000u
#define TAG 0x80000000u           /* stack entry: a block with untested implicit leaves */

/* A node's cached scan (rs_roam_update): one record, so that looking at a
 * node costs one cache line besides the node's. */
struct roam_scan {
    float rc;       /* odometer reading (L->odo - L->odo_base, rounded down) at
                       which its subtree must be scanned again (-1: at the
                       next update) */
    float irc;      /* the same for its items alone, without the readings of
                       its class (a node wholly in or out of view whose class
                       is checked again is scanned only when this is due) */
    float rot;      /* turn reading (L->rot, rounded down) at which an item
                       under it may change sides of the frustum */
    unsigned char cls; /* its class against the view at its last scan
                          (SCAN_NO_CLASS: none yet) */
};
#define SCAN_NO_CLASS 3

typedef struct roam_node {
    uint32_t lc, rc;                /* children (NIL for a leaf) */
    uint32_t base, left, right;     /* neighbours across base / left leg / right leg */
    uint32_t e;                     /* error slot: patch * epp + heap index (roots are
                                       2 and 3); NIL for cell halves (patches of 1 cell) */
    uint16_t ax, ay, bx, by;        /* apex and left base corner; the right corner
                                       is apex + rot90(left - apex) */
} roam_node;

struct rs_roam {
    uint32_t w, hgt, cw, ch;        /* samples and cells */
    double cs, zs;
    float zabs;                     /* largest |height| of the valid samples (DEM units) */
    const float *z;                 /* heights in DEM units, nodata filled */
    float *zown;                    /* owned copy when the DEM had nodata */
    uint32_t plog, P, npx, npy;
    uint32_t dq, ncut;              /* implicit levels below a block node; 2^dq */
    unsigned char pwhere[1 << IMPL_DEPTH], ppos[2][1 << IMPL_DEPTH]; /* rs__roam_build_partner_table */
    uint32_t below[1 << IMPL_DEPTH]; /* SPLIT_BITs of the positions under each position */
    /* Corners (apex, left, right) and hypotenuse midpoint of every position
     * down to the cell halves, in units of block leg / 2^(dq/2) along the
     * block's legs: a sample's key is then an affine function of
     * these (emit_block_on, lib/roam/roam_extract.c). */
    unsigned char pgeo[2 << IMPL_DEPTH][8];
    uint32_t scan, scan_pos;        /* block whose implicit leaves rs__roam_refine() is testing
                                       (NIL: none), and the position it splits */
    int scan_dirty;                 /* a forced split gave it new leaves behind the scan */
    size_t epp;                     /* error entries per patch (P^2) */
    uint32_t elog;                  /* log2(epp) */
    size_t nerr;                    /* entries of err */
    float *err;                     /* per patch, by heap index; NaN = not computed yet */
    unsigned char *eready;          /* per chunk of ERR_CHUNK entries: 1 once the chunk
                                       holds real entries (NaN-filled on its first
                                       write); entries of a chunk still at 0 are NaN */
    int err_empty;                  /* every entry of err is NaN, and stays so until the
                                       end of the refinement pass under way (each node is
                                       tested at most once per pass) */
    float *pzmin, *pzmax;           /* per patch height range (DEM units), view mode only */
    int zrange_ok;                  /* pzmin / pzmax are those of z */
    unsigned char *pin;             /* per patch: 1 when it lies wholly on the map */
    roam_node *nodes, *base_copy;
    uint32_t *stack, sp;            /* refinement stack (2 cap entries: each node is
                                       pushed at most once per pass as a leaf and once
                                       tagged, for its implicit children) */
    uint32_t base_count, cap, used; /* cap = base_count + pool */
    uint32_t base_tris, tris;
    int exhausted;
    /* progress (rs__roam_progress_begin): the running call's context, to
     * poll from the refinement and update loops (NULL: none); a poll asked
     * to stop (the mesh is left valid, as when the pool runs out); the
     * nodes in use at the last poll */
    rs_ctx *pctx;
    int cancelled;
    uint32_t polled_used;
    /* Extraction's vertex set: one bit per sample, rows padded to whole
     * 64-bit words (wpr words per row); a summary bit per word that has a
     * bit set; the set bits before each word (vertex numbering by rank). */
    uint64_t *vbits, *vsum;
    uint32_t *vrank;
    uint32_t wpr;
    size_t nwords, nsum;
    uint32_t *smap;                 /* 2(w+h): skirt vertex of a border sample */
    double threshold;
    double err_stop;                /* error mode: rs__roam_err_stop of the threshold */
    float *ucol, *vrow;             /* texture u of each column, v of each row */
    double tol;                     /* view mode: tolerance carried between frames */
    uint32_t frame_passes, culled;
    uint64_t bytes;
    /* Frame-coherent updates (lib/roam/roam_update.c), allocated by the first
     * rs_roam_update (but pgen, at creation): the parent of every node
     * (kept by split() once allocated), the free list of node pairs that
     * merges gave back, the two queues, and a generation per patch. */
    uint32_t *par;
    uint32_t free_head, nfree;      /* first free pair (NIL: none), free nodes */
    uint32_t moved;                 /* nodes split() took from the free list since the last compaction
                                       (compact_pool, lib/roam/roam_update.c) */
    struct roam_queue *qs, *qm;     /* split queue (max-heap), merge queue (min-heap) */
    uint32_t *pgen;                 /* per patch: generation of its leaves (the value of
                                       gen when they last changed) */
    /* Upload units (docs/roam.md, "Upload units"): the subtrees of each
     * patch at depth udepth below its roots, upp = 2^(udepth + 1) per patch,
     * unit = patch * upp + (heap index at depth udepth) - upp; a leaf above
     * that depth belongs to the unit of its leftmost descendant. */
    uint32_t udepth, upp, usize;    /* depth, units per patch, unit square side (cells) */
    uint32_t *ugen;                 /* per unit: generation of its leaves */
    struct roam_scan *cscan;        /* per node: its cached scan (lib/roam/roam_update.c) */
    float *c2read;                  /* per node, 2 floats: while partly in view at its last
                                       scan, the odometer and turn readings until which it
                                       stays so (node_class, lib/roam/roam_update.c) */
    unsigned char *pvis;            /* per patch: visible at the last update */
    double odo_base;                /* odometer at which the scan records' readings start
                                       (floats: rebased, with a full scan, every 4 km) */
    double odo, rot;                /* camera travel (metres) and turn (the sum of the
                                       largest frustum normal change per update) */
    double last_eye[3], last_n[5][3], last_k, last_tol, last_mtol; /* the view of the last scan */
    int full_next;                  /* the next update scans every cluster */
    uint32_t gen;                   /* generation counter (bumped per change) */
    uint32_t update_ops;            /* split/merge operations of the last update */
    int update_done;                /* the last update reached its goal (not cut by the budget) */
};

static inline uint32_t pos_depth(uint32_t pos) /* pos >= 1 */
{
#if defined(__GNUC__)
    return 31u - (uint32_t)__builtin_clz(pos);
#else
    uint32_t d = 0;
    while (pos >> (d + 1)) d++;
    return d;
#endif
}

/* Record that the leaves of node changed (it was split, or merged): the
 * generations of its patch (rs_roam_patch_generation) and of its upload
 * units (rs_roam_unit_generation: its own unit, or for a node above the
 * units' depth the units of its leftmost descendants through either child,
 * where it and its two children belong), and the cached scans of the node
 * and its ancestors (lib/roam/roam_update.c; an ancestor of a node to scan
 * is marked already, so the walk up stops there). */
static inline void touch_patch(rs_roam *L, uint32_t node)
{
    uint32_t e = L->nodes[node].e;
    if (e == NIL) { /* cell halves of 1-cell patches: never split */
        L->pgen[0] = L->ugen[0] = L->gen;
    } else {
        uint32_t patch = e >> L->elog, h = e & (uint32_t)(L->epp - 1), d = pos_depth(h) - 1u;
        uint32_t *ug = L->ugen + (size_t)patch * L->upp; /* heap index upp + k: ug[k] */
        L->pgen[patch] = L->gen;
        if (d >= L->udepth) ug[(h >> (d - L->udepth)) - L->upp] = L->gen;
        else {
            uint32_t sh = L->udepth - d;
            ug[(h << sh) - L->upp] = L->gen;
            ug[((2u * h + 1u) << (sh - 1u)) - L->upp] = L->gen;
        }
    }
    if (L->par)
        for (uint32_t c = node; c != NIL && L->cscan[c].rc >= 0.0f; c = L->par[c]) L->cscan[c].rc = -1.0f;
}

/* Nodes the pool can still give. */
static inline uint32_t pool_avail(const rs_roam *L) { return L->cap - L->used + L->nfree; }

/* The error cache is initialised a chunk (4 KiB) at a time, when the first
 * bound in it is stored: a coarse mesh stores a few thousand bounds and
 * touches a few pages instead of the whole array (2 MB for 1025^2). */
#define ERR_CHUNK_LOG 10
#define ERR_CHUNK (1u << ERR_CHUNK_LOG)

/* Cached bound of `slot` (NaN: none). */
static inline float err_get(const rs_roam *L, uint32_t slot)
{
    return L->eready[slot >> ERR_CHUNK_LOG] ? L->err[slot] : NAN;
}

static inline void err_put(rs_roam *L, uint32_t slot, float v)
{
    size_t c = slot >> ERR_CHUNK_LOG;
    if (!L->eready[c]) {
        size_t n = L->nerr - c * ERR_CHUNK < ERR_CHUNK ? L->nerr - c * ERR_CHUNK : ERR_CHUNK;
        memset(L->err + c * ERR_CHUNK, 0xFF, n * sizeof(float)); /* NaN */
        L->eready[c] = 1;
    }
    L->err[slot] = v;
}

/* ---- geometry helpers -------------------------------------------------- */

static inline void node_corner(const roam_node *n, int *cx, int *cy)
{
    *cx = (int)n->ax - ((int)n->by - (int)n->ay);
    *cy = (int)n->ay + ((int)n->bx - (int)n->ax);
}

/* A triangle by its corners: apex a, left b, right c = a + rot90(b - a);
 * `on` = its patch lies wholly on the map (no edge tests needed). */
typedef struct tri { int ax, ay, bx, by, cx, cy, on; } tri;

static inline void node_tri(const rs_roam *L, const roam_node *n, tri *t)
{
    t->ax = n->ax; t->ay = n->ay; t->bx = n->bx; t->by = n->by;
    node_corner(n, &t->cx, &t->cy);
    t->on = n->e != NIL && L->pin[n->e >> L->elog];
}

/* Child k of t as split() makes it: k = 0 (apex m, left a, right b), k = 1
 * (apex m, left c, right a), m the midpoint of the hypotenuse b-c. */
static inline void child_tri(const tri *t, int k, tri *o)
{
    int mx = (t->bx + t->cx) / 2, my = (t->by + t->cy) / 2;
    o->ax = mx; o->ay = my; o->on = t->on;
    if (k == 0) { o->bx = t->ax; o->by = t->ay; o->cx = t->bx; o->cy = t->by; }
    else { o->bx = t->cx; o->by = t->cy; o->cx = t->ax; o->cy = t->ay; }
}

static inline int inside_xy(const rs_roam *L, int ax, int ay, int bx, int by, int cx, int cy)
{
    int mx = ax > bx ? ax : bx, my = ay > by ? ay : by;
    if (cx > mx) mx = cx;
    if (cy > my) my = cy;
    return mx <= (int)L->cw && my <= (int)L->ch;
}

/* Where a node lies against the map: wholly off it, straddling its edge, or on it. */
enum { NODE_ON = 0, NODE_OUTSIDE = 1, NODE_STRADDLES = 2 };

static inline int tri_class(const rs_roam *L, const tri *t)
{
    if (t->on) return NODE_ON;
    int minx = t->ax < t->bx ? t->ax : t->bx, miny = t->ay < t->by ? t->ay : t->by;
    if (t->cx < minx) minx = t->cx;
    if (t->cy < miny) miny = t->cy;
    if (minx >= (int)L->cw || miny >= (int)L->ch) return NODE_OUTSIDE;
    return inside_xy(L, t->ax, t->ay, t->bx, t->by, t->cx, t->cy) ? NODE_ON : NODE_STRADDLES;
}

static inline int tri_inside(const rs_roam *L, const tri *t)
{
    if (t->on) return 1;
    return inside_xy(L, t->ax, t->ay, t->bx, t->by, t->cx, t->cy);
}

/* The per-patch height ranges of the current heights (lib/roam/roam.c), once
 * per DEM: only view frames need them. */
void rs__roam_patch_ranges(rs_roam *L);

/* ---- error bounds (lib/roam/roam_bounds.c) ---------------------------------- */

/* The error terms of a legs-2-sqrt-2 triangle S = (a, b, c) and of its
 * whole implicit subtree, from its nine samples read once: the children
 * R0 = (m, a, b), R1 = (m, c, a) share S's leg-midpoint terms and the
 * sample i halfway from a to m, and each grandchild's only term is one of
 * its parent's (the plane through a triangle's hypotenuse ends gives its
 * midpoint's error whatever the apex). */
typedef struct s_terms {
    int have;
    tri S;
    float s, r[2], q[2][2];
} s_terms;

/* The terms of o->S (o->have set). */
void rs__roam_load_s_terms(const rs_roam *L, s_terms *o);
/* Error bound of a triangle wholly on the map (DEM units). */
float rs__roam_on_map_err(const rs_roam *L, const tri *t);
/* Error bound of a triangle (DEM units): ERR_OUTSIDE (< 0) off the map,
 * +inf when it straddles the map edge. */
float rs__roam_compute_err(const rs_roam *L, const tri *t);
/* Cache slot of an explicit node, of implicit position pos of block node n
 * (NIL: not cached). */
uint32_t rs__roam_err_slot(const rs_roam *L, const roam_node *n);
uint32_t rs__roam_imp_slot(const rs_roam *L, const roam_node *n, uint32_t pos);
/* Error bound of triangle t with cache slot `slot`, computed on first use;
 * of an explicit node (0 for cell halves). */
float rs__roam_slot_err(rs_roam *L, uint32_t slot, const tri *t);
float rs__roam_node_err(rs_roam *L, const roam_node *n, const tri *t);
/* Refinement's decision in error mode: bound of t above max_error (metres),
 * possibly found without computing the whole bound; L->err_stop must be
 * rs__roam_err_stop(max_error, L->zs). */
int rs__roam_err_above(rs_roam *L, uint32_t slot, const tri *t, double max_error);
double rs__roam_err_stop(double max_error, double zs);

/* ---- bintree, implicit levels, refinement (lib/roam/roam_tree.c) ------------ */

typedef struct view_params {
    double eye[3], f[3], planes[5][4]; /* inward unit normals + offset */
    int nplanes;
    double k;    /* pixels per metre at distance 1 */
    double tol;  /* pixels */
    double zmid_scale;
} view_params;

typedef struct refine_params {
    double max_error;          /* metres (error mode) */
    int border_only;           /* split only triangles straddling the map edge */
    const view_params *view;   /* NULL: error mode */
    const unsigned char *vis;  /* view mode: per patch, 0 = culled (only border splits) */
    uint32_t stop_above;       /* abandon when tris exceeds this (0: never) */
} refine_params;

static inline int sphere_visible(const view_params *v, const double c[3], double r)
{
    for (int p = 0; p < v->nplanes; p++) {
        const double *pl = v->planes[p];
        if (pl[0] * c[0] + pl[1] * c[1] + pl[2] * c[2] + pl[3] < -r) return 0;
    }
    return 1;
}

/* Bounding sphere of triangle t of patch `patch`: centre at its centroid
 * and the middle of the patch's height range, radius over its corners and
 * that range (metres). */
static inline void tri_sphere(const rs_roam *L, const tri *t, uint32_t patch, double c[3], double *r)
{
    int cx = t->cx, cy = t->cy;
    double cs = L->cs;
    double gx = (t->ax + t->bx + cx) / 3.0, gy = (t->ay + t->by + cy) / 3.0;
    double r2 = 0.0, d;
    d = (t->ax - gx) * (t->ax - gx) + (t->ay - gy) * (t->ay - gy); if (d > r2) r2 = d;
    d = (t->bx - gx) * (t->bx - gx) + (t->by - gy) * (t->by - gy); if (d > r2) r2 = d;
    d = (cx - gx) * (cx - gx) + (cy - gy) * (cy - gy); if (d > r2) r2 = d;
    double zlo = (double)L->pzmin[patch] * L->zs, zhi = (double)L->pzmax[patch] * L->zs;
    double hz = 0.5 * (zhi - zlo);
    c[0] = gx * cs; c[1] = gy * cs; c[2] = 0.5 * (zlo + zhi);
    *r = sqrt(r2 * cs * cs + hz * hz);
}

/* The distance part of a leaf's view priority: 0 when the leaf never needs
 * a split (off the map, culled), 1 when it straddles the map edge (must
 * split), 2 with *dist = distance from the eye to its bounding sphere (the
 * triangle's xy extent and the patch's height range), floored. */
static inline int view_dist(const rs_roam *L, const tri *t, uint32_t patch, const view_params *v,
                            const unsigned char *vis, double *dist)
{
    int cls = tri_class(L, t);
    if (cls != NODE_ON) return cls == NODE_STRADDLES;
    if (vis && !vis[patch]) return 0;
    double c[3], r;
    tri_sphere(L, t, patch, c, &r);
    if (!sphere_visible(v, c, r)) return 0;
    double dx = c[0] - v->eye[0], dy = c[1] - v->eye[1], dz = c[2] - v->eye[2];
    double dst = sqrt(dx * dx + dy * dy + dz * dz) - r;
    double floor_d = 1e-3 * L->cs;
    *dist = dst < floor_d ? floor_d : dst;
    return 2;
}

/* A leaf's priority in view mode: its error bound (cached in `slot`)
 * projected at its nearest distance to the eye, in pixels; 0 when it
 * never needs a split (off the map, culled, flat), +inf when it straddles
 * the map edge. A split is wanted when this exceeds the tolerance. */
static inline double view_prio(rs_roam *L, uint32_t slot, const tri *t, uint32_t patch,
                               const view_params *v, const unsigned char *vis)
{
    double dist;
    int k = view_dist(L, t, patch, v, vis, &dist);
    if (k != 2) return k ? INFINITY : 0.0;
    /* the error is computed last: culled nodes never need it */
    float e = rs__roam_slot_err(L, slot, t);
    if (!(e > 0.0f)) return 0.0; /* flat */
    return (double)e * L->zs * v->k / dist;
}

/* The implicit levels' tables of L (pwhere, ppos, pgeo, below) from dq. */
void rs__roam_build_partner_table(rs_roam *L);
/* Back to the base mesh. */
void rs__roam_reset_mesh(rs_roam *L);
/* Refine the current mesh by rp's rule until no leaf wants a split or the
 * pool runs out (L->exhausted); 1 when abandoned for rp->stop_above. */
int rs__roam_refine(rs_roam *L, const refine_params *rp);
/* Frame-coherent updates (lib/roam/roam_tree.c for the bintree side). A leaf or
 * diamond is named by (node, pos): pos 0 an explicit node, pos 1 a block
 * node as a whole, pos >= 2 an implicit position of block `node`. */
/* Split leaf (node, pos) with its forced splits; -1 (nothing done) when
 * the pool cannot hold the worst case. New leaves go on L->stack. */
int rs__roam_split_leaf(rs_roam *L, uint32_t node, uint32_t pos);
/* Is (node, pos) a split triangle whose diamond (it and its base partner)
 * can merge: both split into two leaves each, pool nodes (not the base
 * mesh)? *partner / *ppos name the partner (NIL at the border). */
int rs__roam_mergeable(const rs_roam *L, uint32_t node, uint32_t pos, uint32_t *partner, uint32_t *ppos);
/* Merge the diamond of (node, pos) (rs__roam_mergeable said yes). */
void rs__roam_merge(rs_roam *L, uint32_t node, uint32_t pos);
/* Triangle, cache slot and patch of (node, pos). */
void rs__roam_item_tri(const rs_roam *L, uint32_t node, uint32_t pos, tri *t, uint32_t *slot, uint32_t *patch);
/* The parent of (node, pos) as a (node, pos) pair; 0 at a root. */
int rs__roam_item_parent(const rs_roam *L, uint32_t node, uint32_t pos, uint32_t *pn, uint32_t *ppos);

/* The view of a frame (lib/roam/roam_view.c): projection and frustum planes,
 * the patch height ranges, and per patch 1 when visible (*vis is visbuf
 * when nbuf is enough, else allocated: the caller frees it). */
/* A ROAM call's view (rs_roam_frame, rs_roam_update) in this header's
 * layout (the ABI rule), RS_ERR_INVALID_ARG naming `call` for NULLs. */
rs_result rs__roam_view_in(rs_ctx *ctx, const rs_roam *L, const rs_roam_view *vw_in, const char *call,
                           rs_roam_view *vw);
rs_result rs__roam_view_begin(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw, view_params *v,
                              unsigned char *visbuf, size_t nbuf, unsigned char **vis);
/* Free what the first rs_roam_update allocated (lib/roam/roam_update.c). */
void rs__roam_update_free(rs_ctx *ctx, rs_roam *L);
/* A ROAM call's progress (rs__progress_begin with the context's callback,
 * `total` units: pool nodes taken by splits): the loops poll through
 * L->pctx (rs__roam_poll) every few thousand steps. end: RS_ERR_CANCELLED
 * when a poll asked to stop (the mesh valid and crack-free, as the loop
 * left it), else r. *saved keeps an enclosing call's pctx. */
void rs__roam_progress_begin(rs_ctx *ctx, rs_roam *L, rs__progress *pg, uint64_t total, rs_ctx **saved);
rs_result rs__roam_progress_end(rs_ctx *ctx, rs_roam *L, rs__progress *pg, rs_result r, rs_ctx *saved);
/* From a loop, every ROAM_POLL_STEPS steps: 1 when the call is to stop
 * (L->cancelled set). */
#define ROAM_POLL_STEPS 8192u
int rs__roam_poll(rs_roam *L);

/* Largest error bound over the leaves on the map (metres). */
double rs__roam_leaves_max_bound(const rs_roam *L);
#endif
