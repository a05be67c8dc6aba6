/* ROAM terrain mesher: a Landscape of patches, each two bintree roots, with
 * nodes from a fixed pool linked by 32-bit indices (the seed's five links).
 * Design notes and the reasons behind the choices: docs/roam.md. */
#include "dem.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define NIL 0xFFFFFFFFu
#define MAX_PATCH_LOG 14          /* patch side <= 16384 cells: heap index < 2^30 */
#define MAX_SIDE 32768u           /* node coordinates are uint16 */
#define AUTO_POOL_CAP (1u << 21)
#define ERR_OUTSIDE (-1.0f)       /* node entirely off the map: never split for error */
#define FRAME_MAX_PASSES 12
/* The finest levels are implicit: a split node at the "block level" (legs^2
 * = 2^dq, dq = min(IMPL_DEPTH, 2 log2 P)) gets lc = IMPL and keeps in rc the
 * state of its subtree of dq levels, by heap position inside the block (the
 * block is position 1, the children of position p are 2p and 2p + 1;
 * positions >= 2^dq are cell halves, never split): a split bit and a tested
 * bit per position 2 .. 2^dq - 1, and QUEUED while a stack entry asks for
 * its untested leaves. See docs/roam.md. */
#define IMPL 0xFFFFFFFEu
#define IMPL_DEPTH 4
#if IMPL_DEPTH > 4
#error "the split and tested bits of positions 2..15 fill rc (see TESTED_BIT)"
#endif
#define SPLIT_BIT(pos) (1u << ((pos) - 2u))
#define TESTED_BIT(pos) (1u << ((pos) + 12u))   /* positions 2..15 -> bits 14..27 */
#define QUEUED 0x80000000u
#define TAG 0x80000000u           /* stack entry: a block with untested implicit leaves */

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
    unsigned char pwhere[1 << IMPL_DEPTH], ppos[2][1 << IMPL_DEPTH]; /* build_partner_table */
    uint32_t below[1 << IMPL_DEPTH]; /* SPLIT_BITs of the positions under each position */
    /* Corners (apex, left, right) and hypotenuse midpoint of every position
     * down to the cell halves, in units of block leg / 2^(dq/2) along the
     * block's legs: a sample's key is then an affine function of
     * these (emit_block_on). */
    unsigned char pgeo[2 << IMPL_DEPTH][8];
    uint32_t scan, scan_pos;        /* block whose implicit leaves refine() is testing
                                       (NIL: none), and the position it splits */
    int scan_dirty;                 /* a forced split gave it new leaves behind the scan */
    size_t epp;                     /* error entries per patch (P^2) */
    uint32_t elog;                  /* log2(epp) */
    size_t nerr;                    /* entries of err */
    float *err;                     /* per patch, by heap index; NaN = not computed yet */
    float *pzmin, *pzmax;           /* per patch height range (DEM units) */
    unsigned char *pin;             /* per patch: 1 when it lies wholly on the map */
    roam_node *nodes, *base_copy;
    uint32_t *stack, sp;            /* refinement stack (2 cap entries: each node is
                                       pushed at most once per pass as a leaf and once
                                       tagged, for its implicit children) */
    uint32_t base_count, cap, used; /* cap = base_count + pool */
    uint32_t base_tris, tris;
    int exhausted;
    /* Extraction's vertex set: one bit per sample, rows padded to whole
     * 64-bit words (wpr words per row); a summary bit per word that has a
     * bit set; the set bits before each word (vertex numbering by rank). */
    uint64_t *vbits, *vsum;
    uint32_t *vrank;
    uint32_t wpr;
    size_t nwords, nsum;
    uint32_t *smap;                 /* 2(w+h): skirt vertex of a border sample */
    double threshold;
    float *ucol, *vrow;             /* texture u of each column, v of each row */
    double tol;                     /* view mode: tolerance carried between frames */
    uint32_t frame_passes, culled;
    uint64_t bytes;
};

size_t rs_roam_node_bytes(void) { return sizeof(roam_node); }

/* Bits set in v. Bit arithmetic, not __builtin_popcountll: without a
 * popcnt target flag that builtin is a table-driven library call. */
static unsigned popcount64(uint64_t v)
{
    v = v - ((v >> 1) & 0x5555555555555555ull);
    v = (v & 0x3333333333333333ull) + ((v >> 2) & 0x3333333333333333ull);
    v = (v + (v >> 4)) & 0x0F0F0F0F0F0F0F0Full;
    return (unsigned)((v * 0x0101010101010101ull) >> 56);
}

static unsigned lowest_bit(uint64_t v) /* v != 0 */
{
#if defined(__GNUC__)
    return (unsigned)__builtin_ctzll(v);
#else
    unsigned n = 0;
    while (!(v & 1u)) { v >>= 1; n++; }
    return n;
#endif
}

/* ---- geometry helpers -------------------------------------------------- */

static void node_corner(const roam_node *n, int *cx, int *cy)
{
    *cx = (int)n->ax - ((int)n->by - (int)n->ay);
    *cy = (int)n->ay + ((int)n->bx - (int)n->ax);
}

/* A triangle by its corners: apex a, left b, right c = a + rot90(b - a);
 * `on` = its patch lies wholly on the map (no edge tests needed). */
typedef struct tri { int ax, ay, bx, by, cx, cy, on; } tri;

static void node_tri(const rs_roam *L, const roam_node *n, tri *t)
{
    t->ax = n->ax; t->ay = n->ay; t->bx = n->bx; t->by = n->by;
    node_corner(n, &t->cx, &t->cy);
    t->on = n->e != NIL && L->pin[n->e >> L->elog];
}

/* Child k of t as split() makes it: k = 0 (apex m, left a, right b), k = 1
 * (apex m, left c, right a), m the midpoint of the hypotenuse b-c. */
static void child_tri(const tri *t, int k, tri *o)
{
    int mx = (t->bx + t->cx) / 2, my = (t->by + t->cy) / 2;
    o->ax = mx; o->ay = my; o->on = t->on;
    if (k == 0) { o->bx = t->ax; o->by = t->ay; o->cx = t->bx; o->cy = t->by; }
    else { o->bx = t->cx; o->by = t->cy; o->cx = t->ax; o->cy = t->ay; }
}

/* The finest explicit level: its subtree is implicit (IMPL). */
static int is_block(const rs_roam *L, const roam_node *n)
{
    int p = (int)n->bx - (int)n->ax, q = (int)n->by - (int)n->ay;
    return p * p + q * q == (int)L->ncut; /* legs^2 = 2^dq */
}

static uint32_t pos_depth(uint32_t pos) /* pos >= 1 */
{
#if defined(__GNUC__)
    return 31u - (uint32_t)__builtin_clz(pos);
#else
    uint32_t d = 0;
    while (pos >> (d + 1)) d++;
    return d;
#endif
}

static int inside_xy(const rs_roam *L, int ax, int ay, int bx, int by, int cx, int cy)
{
    int mx = ax > bx ? ax : bx, my = ay > by ? ay : by;
    if (cx > mx) mx = cx;
    if (cy > my) my = cy;
    return mx <= (int)L->cw && my <= (int)L->ch;
}

static int node_inside(const rs_roam *L, const roam_node *n)
{
    int cx, cy;
    node_corner(n, &cx, &cy);
    return inside_xy(L, n->ax, n->ay, n->bx, n->by, cx, cy);
}

/* Where a node lies against the map: wholly off it, straddling its edge, or on it. */
enum { NODE_ON = 0, NODE_OUTSIDE = 1, NODE_STRADDLES = 2 };

static int tri_class(const rs_roam *L, const tri *t)
{
    if (t->on) return NODE_ON;
    int minx = t->ax < t->bx ? t->ax : t->bx, miny = t->ay < t->by ? t->ay : t->by;
    if (t->cx < minx) minx = t->cx;
    if (t->cy < miny) miny = t->cy;
    if (minx >= (int)L->cw || miny >= (int)L->ch) return NODE_OUTSIDE;
    return inside_xy(L, t->ax, t->ay, t->bx, t->by, t->cx, t->cy) ? NODE_ON : NODE_STRADDLES;
}

static int tri_inside(const rs_roam *L, const tri *t)
{
    if (t->on) return 1;
    return inside_xy(L, t->ax, t->ay, t->bx, t->by, t->cx, t->cy);
}

/* ---- error bounds -------------------------------------------------------- */

/* max over t in [0, n) of |r[t] - (p0 + g t)|: four independent lanes so the
 * compiler can keep them in vector registers; t is exact in double. */
static double row_max(const float *r, int n, double p0, double g)
{
    double m0 = 0.0, m1 = 0.0, m2 = 0.0, m3 = 0.0, t = 0.0;
    int i = 0;
    for (; i + 4 <= n; i += 4, t += 4.0) {
        double d0 = fabs((double)r[i] - (p0 + g * t));
        double d1 = fabs((double)r[i + 1] - (p0 + g * (t + 1.0)));
        double d2 = fabs((double)r[i + 2] - (p0 + g * (t + 2.0)));
        double d3 = fabs((double)r[i + 3] - (p0 + g * (t + 3.0)));
        m0 = d0 > m0 ? d0 : m0;
        m1 = d1 > m1 ? d1 : m1;
        m2 = d2 > m2 ? d2 : m2;
        m3 = d3 > m3 ? d3 : m3;
    }
    for (; i < n; i++, t += 1.0) {
        double d0 = fabs((double)r[i] - (p0 + g * t));
        m0 = d0 > m0 ? d0 : m0;
    }
    if (m1 > m0) m0 = m1;
    if (m3 > m2) m2 = m3;
    return m0 > m2 ? m0 : m2;
}

/* Max |z - plane| over every sample inside (or on) the triangle, the plane
 * through the three corner heights, in double. Bintree legs are either both
 * on the axes (even levels) or both diagonal (odd levels), so every row of
 * the triangle is one run of samples whose ends are exact integers: the
 * triangle is scanned row by row without divisions or edge tests. */
static double tri_max_error(const rs_roam *L, int ax, int ay, int bx, int by, int cx, int cy)
{
    const float *z = L->z;
    const size_t W = L->w;
    double za = z[(size_t)ay * W + (size_t)ax];
    double zb = z[(size_t)by * W + (size_t)bx];
    double zc = z[(size_t)cy * W + (size_t)cx];
    int p = bx - ax, q = by - ay; /* left leg; the right leg is (-q, p) */
    /* plane gradient; |leg|^2 is a power of two, so inv is exact */
    double inv = 1.0 / (double)(p * p + q * q);
    double db = zb - za, dc = zc - za;
    double gx = (db * p - dc * q) * inv, gy = (db * q + dc * p) * inv;
    double m = 0.0, d;
    if (p == 0 || q == 0) {
        /* right angle at the apex, legs on the axes: row k from the apex
         * runs from the apex column s - k samples along the horizontal leg */
        int hx = q == 0 ? p : -q, vy = q == 0 ? p : q;
        int s = hx > 0 ? hx : -hx, sy = vy > 0 ? 1 : -1;
        for (int k = 0; k <= s; k++) {
            int y = ay + sy * k, n = s - k + 1;
            int lo = hx > 0 ? ax : ax - (s - k);
            double p0 = za + gx * (double)(lo - ax) + gy * (double)(y - ay);
            d = row_max(z + (size_t)y * W + (size_t)lo, n, p0, gx);
            if (d > m) m = d;
        }
    } else if (p == q) {
        /* hypotenuse b-c horizontal; rows from it towards the apex shrink by one at each end */
        int h = p > 0 ? p : -p, sy = q > 0 ? -1 : 1, yh = ay + q;
        int x0 = bx < cx ? bx : cx;
        for (int k = 0; k <= h; k++) {
            int y = yh + sy * k, lo = x0 + k, n = 2 * (h - k) + 1;
            double p0 = za + gx * (double)(lo - ax) + gy * (double)(y - ay);
            d = row_max(z + (size_t)y * W + (size_t)lo, n, p0, gx);
            if (d > m) m = d;
        }
    } else {
        /* hypotenuse vertical at x = ax + p; row y spans h - |y - ay| samples
         * from it towards the apex */
        int h = p > 0 ? p : -p, xh = ax + p;
        for (int y = ay - h; y <= ay + h; y++) {
            int dy = y > ay ? y - ay : ay - y, len = h - dy;
            int lo = p > 0 ? xh - len : xh;
            double p0 = za + gx * (double)(lo - ax) + gy * (double)(y - ay);
            d = row_max(z + (size_t)y * W + (size_t)lo, len + 1, p0, gx);
            if (d > m) m = d;
        }
    }
    return m;
}

/* Round up to float so the stored bound is never below the double one
 * (v >= 0: the next float up is the next bit pattern). */
static float round_up_float(double v)
{
    float f = (float)v;
    if ((double)f < v && f < FLT_MAX) {
        uint32_t u;
        memcpy(&u, &f, sizeof u);
        u++;
        memcpy(&f, &u, sizeof f);
    }
    return f;
}

/* Bound of a triangle whose only non-corner sample is the midpoint of its
 * hypotenuse (x0, y0)-(x1, y1): the legs-sqrt(2) level. */
static float midpoint_err(const rs_roam *L, int x0, int y0, int x1, int y1)
{
    const float *z = L->z;
    size_t W = L->w;
    double d = (double)z[(size_t)((y0 + y1) / 2) * W + (size_t)((x0 + x1) / 2)]
               - 0.5 * ((double)z[(size_t)y0 * W + (size_t)x0] + (double)z[(size_t)y1 * W + (size_t)x1]);
    return round_up_float(fabs(d));
}

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

static void load_s_terms(const rs_roam *L, s_terms *o)
{
    const float *z = L->z;
    const size_t W = L->w;
    const tri *t = &o->S;
#define Z(x, y) ((double)z[(size_t)(y) * W + (size_t)(x)])
    int mx = (t->bx + t->cx) / 2, my = (t->by + t->cy) / 2;
    int ux = (t->cx - t->bx) / 4, uy = (t->cy - t->by) / 4;
    double za = Z(t->ax, t->ay), zb = Z(t->bx, t->by), zc = Z(t->cx, t->cy), zm = Z(mx, my);
    double zla = Z((t->ax + t->bx) / 2, (t->ay + t->by) / 2), zlc = Z((t->ax + t->cx) / 2, (t->ay + t->cy) / 2);
    double zh1 = Z(t->bx + ux, t->by + uy), zh3 = Z(t->cx - ux, t->cy - uy);
    double zi = Z((t->ax + mx) / 2, (t->ay + my) / 2);
#undef Z
    double la = fabs(zla - 0.5 * (za + zb)), lc = fabs(zlc - 0.5 * (za + zc));
    double sm = fabs(zm - 0.5 * (zb + zc));
    double sh1 = fabs(zh1 - (0.75 * zb + 0.25 * zc)), sh3 = fabs(zh3 - (0.25 * zb + 0.75 * zc));
    double si = fabs(zi - 0.5 * (za + 0.5 * (zb + zc)));
    double i = fabs(zi - 0.5 * (zm + za)), h1 = fabs(zh1 - 0.5 * (zm + zb)), h3 = fabs(zh3 - 0.5 * (zm + zc));
    double e = la;
    if (lc > e) e = lc;
    if (sm > e) e = sm;
    if (sh1 > e) e = sh1;
    if (sh3 > e) e = sh3;
    if (si > e) e = si;
    o->s = round_up_float(e);
    o->q[0][0] = round_up_float(i); o->q[0][1] = round_up_float(h1);
    o->q[1][0] = round_up_float(h3); o->q[1][1] = o->q[0][0];
    o->r[0] = round_up_float(la > h1 ? (la > i ? la : i) : (h1 > i ? h1 : i));
    o->r[1] = round_up_float(lc > h3 ? (lc > i ? lc : i) : (h3 > i ? h3 : i));
    o->have = 1;
}

/* Error bound of a triangle wholly on the map (DEM units). The three
 * finest levels with samples inside have closed forms: legs sqrt 2 (the
 * base midpoint), legs 2 on the axes (three edge midpoints), legs 2 sqrt 2
 * (two leg midpoints, three hypotenuse points, and the midpoint of apex and
 * base midpoint). Cell halves have no sample inside. */
static float on_map_err(const rs_roam *L, const tri *t)
{
    const float *z = L->z;
    const size_t W = L->w;
    int ax = t->ax, ay = t->ay, bx = t->bx, by = t->by, cx = t->cx, cy = t->cy;
    int p = bx - ax, q = by - ay, l2 = p * p + q * q;
#define Z(x, y) ((double)z[(size_t)(y) * W + (size_t)(x)])
    if (l2 == 1) return 0.0f;
    if (l2 == 2) return midpoint_err(L, bx, by, cx, cy);
    if (l2 > 8) return round_up_float(tri_max_error(L, ax, ay, bx, by, cx, cy));
    if (l2 == 8) {
        s_terms st;
        st.S = *t;
        load_s_terms(L, &st);
        return st.s;
    }
    double za = Z(ax, ay), zb = Z(bx, by), zc = Z(cx, cy), d, m;
    m = fabs(Z((ax + bx) / 2, (ay + by) / 2) - 0.5 * (za + zb));
    d = fabs(Z((ax + cx) / 2, (ay + cy) / 2) - 0.5 * (za + zc)); if (d > m) m = d;
    d = fabs(Z((bx + cx) / 2, (by + cy) / 2) - 0.5 * (zb + zc)); if (d > m) m = d;
#undef Z
    return round_up_float(m);
}

/* Error bound of a triangle (DEM units): ERR_OUTSIDE off the map, +inf
 * when it straddles the map edge. */
static float compute_err(const rs_roam *L, const tri *t)
{
    int c = tri_class(L, t);
    if (c == NODE_OUTSIDE) return ERR_OUTSIDE;
    if (c == NODE_STRADDLES) return INFINITY;
    return on_map_err(L, t);
}

/* Cache slot of heap index hh in patch `patch`: indices below epp / 2, the
 * levels above the R level (legs 2 on the axes). The R level (three samples
 * besides the corners) and the level below it (one) are cheaper to
 * recompute than to cache. */
static uint32_t slot_of(const rs_roam *L, uint32_t patch, uint32_t hh)
{
    uint32_t half = (uint32_t)(L->epp / 2);
    return hh < half ? patch * half + hh : NIL;
}

static uint32_t err_slot(const rs_roam *L, const roam_node *n)
{
    if (n->e == NIL) return NIL;
    return slot_of(L, n->e >> L->elog, n->e & (uint32_t)(L->epp - 1));
}

/* Slot of implicit position pos of block node n: the heap index continues
 * below the block's (h -> 2h, 2h + 1). */
static uint32_t imp_slot(const rs_roam *L, const roam_node *n, uint32_t pos)
{
    uint32_t d = pos_depth(pos);
    uint32_t hh = ((n->e & (uint32_t)(L->epp - 1)) << d) + pos - (1u << d);
    return slot_of(L, n->e >> L->elog, hh);
}

/* Error bound (DEM units) of triangle t with cache slot `slot` (NIL: not
 * cached), computed on first use: most deep nodes are never asked for at a
 * large threshold. */
static float slot_err(rs_roam *L, uint32_t slot, const tri *t)
{
    if (slot == NIL) return compute_err(L, t);
    float v = L->err[slot];
    if (v != v) {
        v = compute_err(L, t);
        L->err[slot] = v;
    }
    return v;
}

/* Error bound of an explicit node; cell halves have none. */
static float node_err(rs_roam *L, const roam_node *n, const tri *t)
{
    if (n->e == NIL) return 0.0f;
    return slot_err(L, err_slot(L, n), t);
}

/* ---- nodata ---------------------------------------------------------------- */

/* The DEM module's nodata policy (lib/dem.c), into an owned copy. */
static rs_result fill_nodata(rs_ctx *ctx, rs_roam *L, const rs_dem *dem)
{
    float *z;
    rs_result r = rs__dem_fill_nodata(ctx, dem, &z);
    if (r != RS_OK) return r;
    L->zown = z;
    L->z = z;
    return RS_OK;
}

/* ---- bintree --------------------------------------------------------------- */

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

/* Ask refine() to test the untested implicit leaves of block r. */
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
    uint32_t lc = L->used++, rc = L->used++;
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

static void build_partner_table(rs_roam *L)
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

static void reset_mesh(rs_roam *L)
{
    memcpy(L->nodes, L->base_copy, (size_t)L->base_count * sizeof(roam_node));
    L->used = L->base_count;
    L->tris = L->base_tris;
    L->exhausted = 0;
}

/* ---- refinement ------------------------------------------------------------ */

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

static int sphere_visible(const view_params *v, const double c[3], double r)
{
    for (int p = 0; p < v->nplanes; p++) {
        const double *pl = v->planes[p];
        if (pl[0] * c[0] + pl[1] * c[1] + pl[2] * c[2] + pl[3] < -r) return 0;
    }
    return 1;
}

/* Decision for a leaf: triangle t in patch `patch`, its error bound cached
 * in `slot` (NIL: not cached). Cell halves never come here. */
static int wants_split(rs_roam *L, uint32_t slot, const tri *t, uint32_t patch, const refine_params *rp)
{
    if (rp->border_only) return tri_class(L, t) == NODE_STRADDLES;
    if (!rp->view) {
        float e = slot_err(L, slot, t);
        return e == INFINITY || (e > 0.0f && (double)e * L->zs > rp->max_error);
    }
    int cls = tri_class(L, t);
    if (cls != NODE_ON) return cls == NODE_STRADDLES;
    const view_params *v = rp->view;
    if (rp->vis && !rp->vis[patch]) return 0;
    int cx = t->cx, cy = t->cy;
    double cs = L->cs;
    double gx = (t->ax + t->bx + cx) / 3.0, gy = (t->ay + t->by + cy) / 3.0;
    double r2 = 0.0, d;
    d = (t->ax - gx) * (t->ax - gx) + (t->ay - gy) * (t->ay - gy); if (d > r2) r2 = d;
    d = (t->bx - gx) * (t->bx - gx) + (t->by - gy) * (t->by - gy); if (d > r2) r2 = d;
    d = (cx - gx) * (cx - gx) + (cy - gy) * (cy - gy); if (d > r2) r2 = d;
    double zlo = (double)L->pzmin[patch] * L->zs, zhi = (double)L->pzmax[patch] * L->zs;
    double hz = 0.5 * (zhi - zlo);
    double c[3] = { gx * cs, gy * cs, 0.5 * (zlo + zhi) };
    double r = sqrt(r2 * cs * cs + hz * hz);
    if (!sphere_visible(v, c, r)) return 0;
    double dx = c[0] - v->eye[0], dy = c[1] - v->eye[1], dz = c[2] - v->eye[2];
    double dist = sqrt(dx * dx + dy * dy + dz * dz) - r;
    double floor_d = 1e-3 * cs;
    if (dist < floor_d) dist = floor_d;
    /* the error is computed last: culled nodes never need it */
    float e = slot_err(L, slot, t);
    if (!(e > 0.0f)) return 0; /* flat */
    return (double)e * L->zs * v->k / dist > v->tol;
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
                if (!sub) e = on_map_err(L, &u);
                else {
                    if (!sub->have) load_s_terms(L, sub);
                    e = lv == 4 ? sub->s : lv == 3 ? sub->r[k] : sub->q[pos & 1u][k];
                }
                want = e > 0.0f && (double)e * L->zs > rp->max_error;
            } else want = wants_split(L, imp_slot(L, &n[r], c), &u, n[r].e >> L->elog, rp);
            if (want) {
                if (imp_need(L, r, c) > L->cap - L->used) { L->exhausted = 1; return -1; }
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

/* Depth-first refinement with an explicit stack: every explicit node is
 * pushed when it is created (children of forced splits too), and a block
 * whose implicit subtree got untested leaves is pushed once (QUEUED), so
 * each leaf is tested once, and neighbouring triangles are handled close
 * together in time (the DEM rows, error slots and neighbour nodes they
 * touch stay in cache). The split sequence depends only on the DEM and the
 * decision rule, never on the pool size; refinement stops at the first
 * split the pool cannot hold, so the mesh of a larger pool is a refinement
 * of a smaller pool's. Returns 1 when abandoned for stop_above. */
static int refine(rs_roam *L, const refine_params *rp)
{
    roam_node *n = L->nodes;
    uint32_t *st = L->stack;
    L->sp = 0;
    L->scan = NIL;
    for (uint32_t i = L->used; i-- > 0;) { /* node 0 on top */
        if (n[i].lc == NIL) st[L->sp++] = i;
        else if (n[i].lc == IMPL && L->dq > 1) { n[i].rc |= QUEUED; st[L->sp++] = i | TAG; }
    }
    while (L->sp) {
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
        if (!wants_split(L, err_slot(L, &n[i]), &t, n[i].e >> L->elog, rp)) continue;
        uint32_t need = split_need(L, i);
        if (need > L->cap - L->used) { L->exhausted = 1; return 0; }
        split(L, i);
        if (rp->stop_above && L->tris > rp->stop_above) return 1;
    }
    return 0;
}

/* Error bound of triangle t from the cache when it is there, else computed
 * (and not stored: the landscape is const here). */
static float peek_err(const rs_roam *L, uint32_t slot, const tri *t)
{
    float e = slot == NIL ? NAN : L->err[slot];
    return e == e ? e : compute_err(L, t);
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
            e = peek_err(L, imp_slot(L, nd, c), &u);
            if (skip_inf && e == INFINITY) continue;
        }
        if (e > m) m = e;
    }
    return m;
}

/* Largest error bound over the leaves on the map (metres). Computed when
 * the stats are asked for, not after every refinement: it is a scan of
 * every node, and meshing does not need it. */
static double leaves_max_bound(const rs_roam *L)
{
    double mb = 0.0;
    for (uint32_t i = 0; i < L->used; i++) {
        const roam_node *nd = &L->nodes[i];
        tri t;
        node_tri(L, nd, &t);
        float e;
        if (nd->lc == IMPL) e = imp_leaves_max(L, nd, 1, &t, 1, 0);
        else if (nd->lc != NIL || nd->e == NIL || !tri_inside(L, &t)) continue;
        else e = peek_err(L, err_slot(L, nd), &t); /* never tested when the pool ran out first */
        if ((double)e > mb) mb = e;
    }
    return mb * L->zs;
}

/* ---- heights -------------------------------------------------------------------- */

/* Heights must stay finite through the error arithmetic (checked over the
 * valid samples: filled nodata copies one of them). One pass, which also
 * tells whether there is nodata to fill. */
static rs_result check_heights(rs_ctx *ctx, const rs_roam *L, const rs_dem *dem, int *has_nodata, float *zabs)
{
    size_t n = (size_t)L->w * L->hgt;
    float zmax = 0.0f;
    int bad = 0;
    for (size_t i = 0; i < n; i++) {
        float a = fabsf(dem->z[i]);
        if (!(a <= FLT_MAX)) bad = 1; /* NaN or inf */
        else if (a > zmax) zmax = a;
    }
    *has_nodata = bad;
    *zabs = zmax;
    /* In float, where they are kept: error bounds (differences of up to
     * four heights' worth) and the vertices' z = height * z_scale. An
     * infinite bound would split every triangle at any max error. */
    if (!(zmax <= FLT_MAX / 4) || !((double)zmax * L->zs <= FLT_MAX))
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "ROAM: heights up to %g times z_scale %g leave the float range (at most %g, and %g "
                        "before scaling)", zmax, L->zs, (double)FLT_MAX, (double)(FLT_MAX / 4));
    return RS_OK;
}

/* Point the landscape at dem's heights (nodata filled into an owned copy),
 * forget every cached error bound and recompute the per-patch height
 * ranges. On failure the landscape keeps its previous heights. */
static rs_result load_heights(rs_ctx *ctx, rs_roam *L, const rs_dem *dem, int has_nodata)
{
    float *old = L->zown;
    if (has_nodata) {
        L->zown = NULL;
        rs_result r = fill_nodata(ctx, L, dem);
        if (r != RS_OK) { L->zown = old; return r; }
    } else {
        L->zown = NULL;
        L->z = dem->z;
    }
    rs__free(ctx, old);
    memset(L->err, 0xFF, L->nerr * sizeof(float)); /* all NaN: computed on first use */
    size_t W = L->w;
    uint32_t P = L->P;
    for (uint32_t py = 0; py < L->npy; py++)
        for (uint32_t px = 0; px < L->npx; px++) {
            uint32_t p = py * L->npx + px, x0 = px * P, y0 = py * P;
            float lo = INFINITY, hi = -INFINITY;
            uint32_t xe = x0 + P < L->cw ? x0 + P : L->cw, ye = y0 + P < L->ch ? y0 + P : L->ch;
            for (uint32_t y = y0; y <= ye; y++)
                for (uint32_t x = x0; x <= xe; x++) {
                    float v = L->z[(size_t)y * W + x];
                    if (v < lo) lo = v;
                    if (v > hi) hi = v;
                }
            L->pzmin[p] = lo; L->pzmax[p] = hi;
        }
    return RS_OK;
}

rs_result rs_roam_set_dem(rs_ctx *ctx, rs_roam *L, const rs_dem *dem)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!L || !dem) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_set_dem: roam and dem must not be NULL");
    if (dem->width != L->w || dem->height != L->hgt)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_set_dem: DEM is %ux%u, the landscape %ux%u",
                        dem->width, dem->height, L->w, L->hgt);
    if (dem->frame.cell_size != L->cs || dem->frame.z_scale != L->zs)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_roam_set_dem: DEM frame (cell size %g, z-scale %g) differs from the landscape's (%g, %g)",
                        dem->frame.cell_size, dem->frame.z_scale, L->cs, L->zs);
    int has_nodata;
    float zabs;
    rs_result r = check_heights(ctx, L, dem, &has_nodata, &zabs);
    if (r == RS_OK) r = load_heights(ctx, L, dem, has_nodata);
    if (r != RS_OK) return r;
    L->zabs = zabs;
    reset_mesh(L);
    L->threshold = INFINITY;
    L->tol = 0.0;
    L->frame_passes = 0;
    L->culled = 0;
    rs__ok(ctx);
    return RS_OK;
}

/* ---- creation --------------------------------------------------------------- */

static uint32_t choose_patch_log(uint32_t cw, uint32_t ch)
{
    /* Cost: two roots per patch plus the border splits when the map edge cuts
     * through patches (about four triangles per cell of edge). */
    uint32_t best = 0;
    double best_cost = -1.0;
    uint32_t big = cw > ch ? cw : ch;
    for (uint32_t lg = 0; lg <= MAX_PATCH_LOG; lg++) {
        uint32_t P = 1u << lg;
        if (lg > 0 && (P >> 1) >= big) break;
        double nx = (double)((cw + P - 1) / P), ny = (double)((ch + P - 1) / P);
        double cost = 2.0 * nx * ny + ((cw % P) ? 4.0 * ch : 0.0) + ((ch % P) ? 4.0 * cw : 0.0);
        if (best_cost < 0 || cost <= best_cost) { best_cost = cost; best = lg; }
    }
    return best;
}

static void init_roots(rs_roam *L)
{
    roam_node *n = L->nodes;
    uint32_t P = L->P;
    for (uint32_t py = 0; py < L->npy; py++)
        for (uint32_t px = 0; px < L->npx; px++) {
            uint32_t p = py * L->npx + px, r0 = 2 * p, r1 = 2 * p + 1;
            uint32_t x0 = px * P, y0 = py * P;
            roam_node *a = &n[r0], *b = &n[r1];
            a->lc = a->rc = b->lc = b->rc = NIL;
            /* P = 1: the roots are already cell halves */
            a->e = L->plog ? (uint32_t)(p * L->epp + 2) : NIL;
            b->e = L->plog ? (uint32_t)(p * L->epp + 3) : NIL;
            /* root 0: apex top-left, left corner top-right; root 1 mirrors it */
            a->ax = (uint16_t)x0; a->ay = (uint16_t)y0; a->bx = (uint16_t)(x0 + P); a->by = (uint16_t)y0;
            b->ax = (uint16_t)(x0 + P); b->ay = (uint16_t)(y0 + P); b->bx = (uint16_t)x0; b->by = (uint16_t)(y0 + P);
            a->base = r1; b->base = r0;
            a->left = py > 0 ? 2 * (p - L->npx) + 1 : NIL;          /* top edge */
            a->right = px > 0 ? 2 * (p - 1) + 1 : NIL;              /* left edge */
            b->left = py + 1 < L->npy ? 2 * (p + L->npx) : NIL;     /* bottom edge */
            b->right = px + 1 < L->npx ? 2 * (p + 1) : NIL;         /* right edge */
        }
    L->used = 2 * L->npx * L->npy;
    L->tris = 0;
    for (uint32_t i = 0; i < L->used; i++) L->tris += (uint32_t)node_inside(L, &n[i]);
}

void rs_roam_free(rs_ctx *ctx, rs_roam *L)
{
    if (!ctx || !L) return;
    rs__free(ctx, L->zown);
    rs__free(ctx, L->err);
    rs__free(ctx, L->pzmin);
    rs__free(ctx, L->pzmax);
    rs__free(ctx, L->pin);
    rs__free(ctx, L->nodes);
    rs__free(ctx, L->base_copy);
    rs__free(ctx, L->stack);
    rs__free(ctx, L->vrank);
    rs__free(ctx, L->ucol);
    rs__free(ctx, L->vrow);
    rs__free(ctx, L->vbits);
    rs__free(ctx, L->vsum);
    rs__free(ctx, L->smap);
    rs__free(ctx, L);
}

rs_result rs_roam_create(rs_ctx *ctx, const rs_dem *dem, const rs_roam_options *opts, rs_roam **out)
{
    if (out) *out = NULL;
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!dem || !out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_create: dem and out must not be NULL");
    rs_roam_options o;
    if (opts) o = *opts; else memset(&o, 0, sizeof o);
    double cs = dem->frame.cell_size, zs = dem->frame.z_scale;
    if (!(zs > 0.0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM: the DEM's z-scale %g must be > 0 (z is up)", zs);
    uint32_t W = dem->width, H = dem->height;
    if (W < 2 || H < 2)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM: DEM is %ux%u, need at least 2x2 samples", W, H);
    /* Vertices are floats (j*cs, i*cs): every one a normal float, so they
     * stay distinct and exact to float precision, and the map fits. */
    double side = (double)(W > H ? W : H) - 1.0;
    if (cs < FLT_MIN || side * cs > FLT_MAX)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "ROAM: cell_size %g is outside the float range of the vertices (%g .. %g for a %ux%u DEM)",
                        cs, (double)FLT_MIN, FLT_MAX / side, W, H);
    uint32_t side_lim = ctx->limits.max_dem_side < MAX_SIDE ? ctx->limits.max_dem_side : MAX_SIDE;
    if (W > side_lim || H > side_lim)
        return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: DEM %ux%u exceeds the side limit %u", W, H, side_lim);
    uint32_t plog;
    if (o.patch_size) {
        if (o.patch_size & (o.patch_size - 1) || o.patch_size > (1u << MAX_PATCH_LOG))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM: patch_size %u must be a power of two <= %u",
                            o.patch_size, 1u << MAX_PATCH_LOG);
        for (plog = 0; (1u << plog) < o.patch_size; plog++) {}
    } else plog = choose_patch_log(W - 1, H - 1);
    uint32_t P = 1u << plog;
    uint32_t npx = (W - 1 + P - 1) / P, npy = (H - 1 + P - 1) / P;
    if ((uint64_t)npx * P > 65535u || (uint64_t)npy * P > 65535u)
        return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: patch size %u too large for a %ux%u DEM", P, W, H);
    uint64_t npatch = (uint64_t)npx * npy;
    uint64_t epp = (uint64_t)P * P; /* heap indices down to the R level: < P^2 */
    uint64_t nerr;
    if (!rs__mul_u64(npatch, epp, &nerr) || nerr >= ((uint64_t)1 << 32) || 2 * npatch > 0x7FFFFFFFull)
        return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: %llu patches of %u cells need too many error entries",
                        (unsigned long long)npatch, P);
    /* Full refinement: every patch tree down to the block level (the dq
     * finer levels are implicit): 2 + 4 + ... + 2^(2 plog - dq + 1) nodes. */
    uint32_t dq = 2 * plog < IMPL_DEPTH ? 2 * plog : IMPL_DEPTH;
    uint64_t full_nodes = npatch * (((uint64_t)1 << (2 * plog - dq + 2)) - 2);
    uint64_t pool;
    if (o.pool_nodes) pool = o.pool_nodes;
    else if (o.pool_bytes) pool = o.pool_bytes / sizeof(roam_node);
    else {
        pool = full_nodes;
        if (pool > AUTO_POOL_CAP) pool = AUTO_POOL_CAP;
        if (pool > ctx->limits.max_pool_nodes) pool = ctx->limits.max_pool_nodes;
    }
    if (pool > ctx->limits.max_pool_nodes)
        return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: pool of %llu nodes exceeds max_pool_nodes %u",
                        (unsigned long long)pool, ctx->limits.max_pool_nodes);

    rs_roam *L = rs__calloc(ctx, 1, sizeof *L);
    if (!L) return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory");
    L->w = W; L->hgt = H; L->cw = W - 1; L->ch = H - 1;
    L->cs = cs; L->zs = zs;
    L->plog = plog; L->P = P; L->npx = npx; L->npy = npy; L->epp = (size_t)epp;
    L->elog = 2 * plog;
    L->dq = dq; L->ncut = 1u << dq;
    L->scan = NIL;
    build_partner_table(L);
    rs_result r = RS_OK;
    size_t nsamp = (size_t)W * H;
    int has_nodata;
    if ((r = check_heights(ctx, L, dem, &has_nodata, &L->zabs)) != RS_OK) goto fail;
    nerr = (nerr + 1) / 2; /* cached above the R level only (err_slot) */
    L->nerr = (size_t)nerr;
    L->err = rs__alloc_array(ctx, (size_t)nerr, sizeof(float));
    L->pzmin = rs__alloc_array(ctx, (size_t)npatch, sizeof(float));
    L->pzmax = rs__alloc_array(ctx, (size_t)npatch, sizeof(float));
    L->pin = rs__alloc_array(ctx, (size_t)npatch, 1);
    L->wpr = (W + 63) / 64;
    L->nwords = (size_t)L->wpr * H;
    L->nsum = (L->nwords + 63) / 64;
    L->vbits = rs__alloc_array(ctx, L->nwords, sizeof(uint64_t));
    L->vsum = rs__alloc_array(ctx, L->nsum, sizeof(uint64_t));
    L->vrank = rs__alloc_array(ctx, L->nwords, sizeof(uint32_t));
    L->ucol = rs__alloc_array(ctx, W, sizeof(float));
    L->vrow = rs__alloc_array(ctx, H, sizeof(float));
    L->smap = rs__alloc_array(ctx, 2 * ((size_t)W + H), sizeof(uint32_t));
    if (!L->err || !L->pzmin || !L->pzmax || !L->pin || !L->vbits || !L->vsum || !L->vrank || !L->smap || !L->ucol || !L->vrow) {
        r = rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for the error tree (%llu entries)",
                     (unsigned long long)nerr);
        goto fail;
    }
    memset(L->vbits, 0, L->nwords * sizeof(uint64_t));
    memset(L->vsum, 0, L->nsum * sizeof(uint64_t));
    for (uint32_t x = 0; x < W; x++) L->ucol[x] = (float)((double)x / L->cw);
    for (uint32_t y = 0; y < H; y++) L->vrow[y] = (float)((double)y / L->ch);
    memset(L->smap, 0xFF, 2 * ((size_t)W + H) * sizeof(uint32_t));
    if ((r = load_heights(ctx, L, dem, has_nodata)) != RS_OK) goto fail;
    for (uint32_t py = 0; py < npy; py++)
        for (uint32_t px = 0; px < npx; px++)
            L->pin[py * npx + px] = (unsigned char)(px * P + P <= L->cw && py * P + P <= L->ch);
    /* Base mesh: roots plus the splits that stop triangles straddling the map
     * edge. Sized by trial, doubling, before the pool exists. */
    {
        uint64_t roots = 2 * npatch;
        uint64_t bcap = roots + 64;
        refine_params rp = { INFINITY, 1, NULL, NULL, 0 };
        for (;;) {
            if (bcap + pool > 0x7FFFFFF0ull) { /* node indices below TAG */
                r = rs__fail(ctx, RS_ERR_LIMIT, "ROAM: base mesh plus pool exceed 2^32 nodes");
                goto fail;
            }
            roam_node *nn = rs__realloc(ctx, L->nodes, (size_t)bcap * sizeof(roam_node));
            if (!nn) { r = rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for %llu base nodes",
                                    (unsigned long long)bcap); goto fail; }
            L->nodes = nn;
            uint32_t *ns = rs__realloc(ctx, L->stack, 2 * (size_t)bcap * sizeof(uint32_t));
            if (!ns) { r = rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for %llu base nodes",
                                    (unsigned long long)bcap); goto fail; }
            L->stack = ns;
            L->cap = (uint32_t)bcap;
            init_roots(L);
            L->exhausted = 0;
            refine(L, &rp);
            if (!L->exhausted) break;
            bcap *= 2;
        }
        L->base_count = L->used;
        L->base_tris = L->tris;
        size_t total;
        if (!rs__mul_size((size_t)L->base_count + (size_t)pool, sizeof(roam_node), &total)) {
            r = rs__fail(ctx, RS_ERR_LIMIT, "ROAM: pool too large");
            goto fail;
        }
        roam_node *nn = rs__realloc(ctx, L->nodes, total);
        if (nn) L->nodes = nn;
        uint32_t *ns = nn ? rs__realloc(ctx, L->stack, 2 * (total / sizeof(roam_node)) * sizeof(uint32_t)) : NULL;
        if (ns) L->stack = ns;
        L->base_copy = rs__alloc_array(ctx, L->base_count, sizeof(roam_node));
        if (!nn || !ns || !L->base_copy) {
            r = rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for a pool of %llu nodes",
                         (unsigned long long)pool);
            goto fail;
        }
        for (uint32_t i = 0; i < L->base_count; i++) /* keep the split bits only */
            if (L->nodes[i].lc == IMPL) L->nodes[i].rc &= SPLIT_BIT(L->ncut) - 1u;
        memcpy(L->base_copy, L->nodes, (size_t)L->base_count * sizeof(roam_node));
        L->cap = L->base_count + (uint32_t)pool;
    }
    L->bytes = sizeof *L + nerr * sizeof(float) + (uint64_t)npatch * (2 * sizeof(float) + 1)
               + (uint64_t)nsamp * sizeof(float) * (L->zown ? 1 : 0)
               + (uint64_t)L->nwords * (sizeof(uint64_t) + sizeof(uint32_t)) + (uint64_t)L->nsum * sizeof(uint64_t)
               + 2 * ((uint64_t)W + H) * sizeof(uint32_t)
               + ((uint64_t)L->cap + L->base_count) * sizeof(roam_node)
               + 2 * (uint64_t)L->cap * sizeof(uint32_t) + ((uint64_t)W + H) * sizeof(float);
    L->threshold = INFINITY;
    rs__ok(ctx);
    *out = L;
    return RS_OK;
fail:
    rs_roam_free(ctx, L);
    return r;
}

/* ---- modes --------------------------------------------------------------------- */

rs_result rs_roam_refine_error(rs_ctx *ctx, rs_roam *L, double max_error)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!L) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_refine_error: roam is NULL");
    if (!(max_error >= 0.0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM: max_error %g must be >= 0", max_error);
    reset_mesh(L);
    refine_params rp = { max_error, 0, NULL, NULL, 0 };
    refine(L, &rp);
    L->threshold = max_error;
    if (L->exhausted)
        return rs__fail(ctx, RS_ERR_POOL_EXHAUSTED, "ROAM: pool of %u nodes ran out at max error %g m "
                        "(mesh valid but coarser: %u triangles)", L->cap - L->base_count, max_error, L->tris);
    rs__ok(ctx);
    return RS_OK;
}

/* Largest error of a base-mesh leaf: at that threshold nothing splits. */
static float base_max_error(rs_roam *L)
{
    float m = 0.0f;
    for (uint32_t i = 0; i < L->base_count; i++) {
        const roam_node *nd = &L->base_copy[i];
        tri t;
        node_tri(L, nd, &t);
        float e;
        if (nd->lc == IMPL) e = imp_leaves_max(L, nd, 1, &t, 0, 1);
        else if (nd->lc != NIL) continue;
        else e = node_err(L, nd, &t);
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
        reset_mesh(L);
            return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: the base mesh already has %u triangles > %u",
                        L->base_tris, max_triangles);
    }
    /* Smallest error threshold (over float bit patterns, which order like
     * the values for non-negative floats) whose mesh fits the budget. */
    /* The count is monotone in the threshold and the base mesh (<= budget)
     * is what any threshold >= hi gives, so the search finds the smallest
     * threshold that fits. */
    uint32_t lo = 0, hi = float_bits(base_max_error(L));
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        reset_mesh(L);
        refine_params rp = { (double)bits_float(mid) * L->zs, 0, NULL, NULL, max_triangles };
        int over = refine(L, &rp);
        if (!over && L->tris <= max_triangles) hi = mid; else lo = mid + 1;
    }
    return rs_roam_refine_error(ctx, L, (double)bits_float(lo) * L->zs);
}

static rs_result make_view(rs_ctx *ctx, const rs_roam *L, const rs_roam_view *vw, view_params *v)
{
    memset(v, 0, sizeof *v);
    double fov = vw->fov_y == 0.0 ? 60.0 : vw->fov_y;
    double wpx = vw->width ? vw->width : 1280, hpx = vw->height ? vw->height : 720;
    for (int i = 0; i < 3; i++)
        if (!isfinite(vw->eye[i]) || !isfinite(vw->dir[i]))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: eye and dir must be finite");
    if (!(fov > 0.0 && fov < 179.0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: fov_y %g must be in (0, 179) degrees", fov);
    if (!(vw->pixel_error >= 0.0) || !isfinite(vw->pixel_error) || !(vw->far_dist >= 0.0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: pixel_error and far_dist must be >= 0");
    double fl = sqrt(vw->dir[0] * vw->dir[0] + vw->dir[1] * vw->dir[1] + vw->dir[2] * vw->dir[2]);
    if (!(fl > 0.0)) return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: dir must not be zero");
    double f[3] = { vw->dir[0] / fl, vw->dir[1] / fl, vw->dir[2] / fl };
    /* right = f x up(z); looking straight down, take the map's x axis */
    double rt[3] = { f[1], -f[0], 0.0 };
    double rl = sqrt(rt[0] * rt[0] + rt[1] * rt[1]);
    if (rl < 1e-9) { rt[0] = 1; rt[1] = 0; rl = 1; }
    rt[0] /= rl; rt[1] /= rl;
    double up[3] = { rt[1] * f[2] - rt[2] * f[1], rt[2] * f[0] - rt[0] * f[2], rt[0] * f[1] - rt[1] * f[0] };
    double ty = tan(fov * 0.5 * 3.14159265358979323846 / 180.0), tx = ty * wpx / hpx;
    if (!(ty >= 1e-9)) /* a subnormal fov_y: no finite projection */
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: fov_y %g degrees is too small", fov);
    memcpy(v->eye, vw->eye, sizeof v->eye);
    memcpy(v->f, f, sizeof f);
    double sx = sqrt(1 + tx * tx), sy = sqrt(1 + ty * ty);
    double nrm[5][3];
    for (int i = 0; i < 3; i++) {
        nrm[0][i] = (f[i] * tx - rt[i]) / sx;
        nrm[1][i] = (f[i] * tx + rt[i]) / sx;
        nrm[2][i] = (f[i] * ty - up[i]) / sy;
        nrm[3][i] = (f[i] * ty + up[i]) / sy;
        nrm[4][i] = f[i];
    }
    for (int p = 0; p < 5; p++) {
        v->planes[p][0] = nrm[p][0]; v->planes[p][1] = nrm[p][1]; v->planes[p][2] = nrm[p][2];
        v->planes[p][3] = -(nrm[p][0] * vw->eye[0] + nrm[p][1] * vw->eye[1] + nrm[p][2] * vw->eye[2]);
    }
    v->nplanes = 5; /* the far limit is applied per patch */
    v->k = hpx / (2.0 * ty);
    (void)L;
    return RS_OK;
}

static int patch_visible(const rs_roam *L, const view_params *v, uint32_t p, double far_dist)
{
    uint32_t px = p % L->npx, py = p / L->npx;
    double P = L->P, cs = L->cs;
    double x0 = px * P, y0 = py * P;
    double x1 = x0 + P < L->cw ? x0 + P : L->cw, y1 = y0 + P < L->ch ? y0 + P : L->ch;
    double zlo = L->pzmin[p] * L->zs, zhi = L->pzmax[p] * L->zs;
    double c[3] = { 0.5 * (x0 + x1) * cs, 0.5 * (y0 + y1) * cs, 0.5 * (zlo + zhi) };
    double hx = 0.5 * (x1 - x0) * cs, hy = 0.5 * (y1 - y0) * cs, hz = 0.5 * (zhi - zlo);
    double r = sqrt(hx * hx + hy * hy + hz * hz);
    if (!sphere_visible(v, c, r)) return 0;
    if (far_dist > 0.0) {
        double dx = c[0] - v->eye[0], dy = c[1] - v->eye[1], dz = c[2] - v->eye[2];
        if (sqrt(dx * dx + dy * dy + dz * dz) - r > far_dist) return 0;
    }
    return 1;
}

/* One tessellation at tolerance tol; patches outside the frustum keep their
 * roots (only forced splits reach them). */
static void frame_pass(rs_roam *L, const view_params *v0, double tol, const unsigned char *vis)
{
    view_params v = *v0;
    v.tol = tol;
    reset_mesh(L);
    refine_params rp = { 0.0, 0, &v, vis, 0 };
    refine(L, &rp);
}

rs_result rs_roam_frame(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!L || !vw) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_frame: roam and view must not be NULL");
    view_params v;
    rs_result r = make_view(ctx, L, vw, &v);
    if (r != RS_OK) return r;
    uint32_t np = L->npx * L->npy;
    /* visibility per patch, kept in the smap scratch when it is large enough */
    unsigned char visbuf[256];
    unsigned char *vis = visbuf;
    int own = 0;
    if (np > sizeof visbuf) {
        vis = rs__malloc(ctx, np);
        if (!vis) return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for %u patch flags", np);
        own = 1;
    }
    L->culled = 0;
    for (uint32_t p = 0; p < np; p++) {
        vis[p] = (unsigned char)patch_visible(L, &v, p, vw->far_dist);
        if (!vis[p]) L->culled++;
    }
    double tol = vw->pixel_error > 0.0 ? vw->pixel_error : 1.0;
    if (vw->target_triangles && L->tol > 0.0 && isfinite(L->tol)) tol = L->tol; /* gFrameVariance */
    uint32_t passes = 0;
    if (!vw->target_triangles) {
        frame_pass(L, &v, tol, vis);
        passes = 1;
    } else {
        double target = vw->target_triangles;
        double lo_t = 0.0, hi_t = INFINITY;   /* tol giving too many / too few */
        double lo_c = 0.0, hi_c = 0.0;
        double best_tol = tol;
        double best_dev = INFINITY;
        for (passes = 1; passes <= FRAME_MAX_PASSES; passes++) {
            frame_pass(L, &v, tol, vis);
            double c = L->tris, dev = fabs(c - target) / target;
            if (dev < best_dev) { best_dev = dev; best_tol = tol; }
            if (dev <= 0.03) break;
            if (c > target) { lo_t = tol; lo_c = c; } else { hi_t = tol; hi_c = c; }
            if (c < target && L->exhausted) break; /* cannot reach: pool too small */
            double nt;
            if (lo_t > 0.0 && isfinite(hi_t)) {
                /* secant in log-log between the bracket ends, kept inside it */
                double a = log(lo_c) - log(hi_c > 0 ? hi_c : 1), b = log(hi_t) - log(lo_t);
                double s = b > 0 && a > 0 ? (log(lo_c) - log(target)) / a : 0.5;
                if (!(s > 0.05 && s < 0.95)) s = 0.5;
                nt = exp(log(lo_t) + s * b);
            } else {
                /* count grows roughly like tol^-1.5 */
                double ratio = c > 0 ? c / target : 0.01;
                nt = tol * pow(ratio, 1.0 / 1.5);
                if (nt > tol * 16) nt = tol * 16;
                if (nt < tol / 16) nt = tol / 16;
            }
            if (!(nt > 0.0) || !isfinite(nt)) break;
            tol = nt;
        }
        if (passes > FRAME_MAX_PASSES) {
            passes = FRAME_MAX_PASSES + 1;
            frame_pass(L, &v, best_tol, vis);
            tol = best_tol;
        }
        L->tol = tol;
    }
    if (own) rs__free(ctx, vis);
    L->frame_passes = passes;
    L->threshold = tol;
    if (L->exhausted)
        return rs__fail(ctx, RS_ERR_POOL_EXHAUSTED, "ROAM: pool of %u nodes ran out in a frame "
                        "(mesh valid but coarser: %u triangles)", L->cap - L->base_count, L->tris);
    rs__ok(ctx);
    return RS_OK;
}

void rs_roam_get_stats(const rs_roam *L, rs_roam_stats *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    if (!L) return;
    o->width = L->w; o->height = L->hgt;
    o->patch_size = L->P; o->patches_x = L->npx; o->patches_y = L->npy;
    o->base_nodes = L->base_count;
    o->pool_nodes = L->cap - L->base_count;
    o->pool_used = L->used - L->base_count;
    o->pool_exhausted = L->exhausted;
    o->triangles = L->tris;
    o->threshold = L->threshold;
    o->max_error_bound = leaves_max_bound(L);
    o->frame_passes = L->frame_passes;
    o->patches_culled = L->culled;
    o->bytes = L->bytes;
}

/* ---- extraction ------------------------------------------------------------------ */

void rs_roam_mesh_bound(const rs_roam *L, const rs_roam_mesh_options *opts, size_t *max_vertices,
                        size_t *max_indices)
{
    size_t v = 0, i = 0;
    if (L) {
        size_t t = L->tris;
        v = t + 2;
        if (v > (size_t)L->w * L->hgt) v = (size_t)L->w * L->hgt;
        i = 3 * t;
        if (opts && opts->skirt_depth > 0.0) {
            size_t border = 2 * ((size_t)L->cw + L->ch);
            v += border;
            i += 6 * border;
        }
    }
    if (max_vertices) *max_vertices = v;
    if (max_indices) *max_indices = i;
}

/* Horn's gradient, the same the splat's hillshade uses (lib/dem.c). */
static void vertex_normal(const rs_roam *L, int x, int y, float *out)
{
    double dzx, dzy;
    rs__dem_horn(L->z, L->w, L->hgt, L->cs, L->zs, (uint32_t)y, (uint32_t)x, &dzx, &dzy);
    double nx = -dzx, ny = -dzy, nz = 1.0, l = sqrt(nx * nx + ny * ny + nz * nz);
    out[0] = (float)(nx / l); out[1] = (float)(ny / l); out[2] = (float)(nz / l);
}

typedef struct extract_state {
    rs_roam *L;
    float *vtx, *nrm;
    int normals;
    size_t vcap, icap, nv, ni;
    uint32_t *idx;
    uint32_t *samples;  /* optional: sample (row * width + column) of each vertex */
    int overflow;
} extract_state;

/* Pass 1 of extraction: a corner by its padded sample index (row * 64 wpr +
 * column), recorded in the vertex set. Indices are written as these keys
 * and renumbered once the set is complete (number_indices). */
static uint32_t mark_key(const extract_state *s, uint32_t p)
{
    rs_roam *L = s->L;
    L->vbits[p >> 6] |= (uint64_t)1 << (p & 63u);
    L->vsum[p >> 12] |= (uint64_t)1 << ((p >> 6) & 63u);
    return p;
}

static uint32_t mark(const extract_state *s, int x, int y)
{
    return mark_key(s, (uint32_t)y * (s->L->wpr * 64u) + (uint32_t)x);
}

/* One leaf triangle, when it lies on the map; 1 on overflow. */
static int emit_tri(extract_state *s, const tri *t)
{
    if (!tri_inside(s->L, t)) return 0;
    if (s->ni + 3 > s->icap) { s->overflow = 1; return 1; }
    /* apex, right corner, left corner: counter-clockwise seen from above */
    s->idx[s->ni++] = mark(s, t->ax, t->ay);
    s->idx[s->ni++] = mark(s, t->cx, t->cy);
    s->idx[s->ni++] = mark(s, t->bx, t->by);
    return 0;
}

/* The leaves of block nd's implicit subtree below position pos (triangle t). */
static int emit_imp(extract_state *s, const roam_node *nd, uint32_t pos, const tri *t)
{
    for (int k = 0; k < 2; k++) {
        uint32_t c = 2 * pos + (uint32_t)k;
        tri u;
        child_tri(t, k, &u);
        if (c < s->L->ncut && (nd->rc & SPLIT_BIT(c))) {
            if (emit_imp(s, nd, c, &u)) return 1;
        } else if (emit_tri(s, &u)) return 1;
    }
    return 0;
}

/* The same for a block on the map: every corner of a leaf is a
 * corner of the block or the hypotenuse midpoint of a split position, so
 * those are marked once each, and the leaves write their sample keys,
 * affine in the reference geometry pgeo, in the order of emit_imp. */
static int emit_block_on(extract_state *s, const roam_node *nd, const tri *t)
{
    const rs_roam *L = s->L;
    const uint32_t row = L->wpr * 64u;
    const int unit = 1 << (L->dq / 2);
    const uint32_t k0 = (uint32_t)t->ay * row + (uint32_t)t->ax;
    /* key steps along the legs' unit vectors (wrapping arithmetic) */
    const uint32_t kb = (uint32_t)((t->by - t->ay) / unit) * row + (uint32_t)((t->bx - t->ax) / unit);
    const uint32_t kc = (uint32_t)((t->cy - t->ay) / unit) * row + (uint32_t)((t->cx - t->ax) / unit);
#define KEY(u, v) (k0 + (uint32_t)(u) * kb + (uint32_t)(v) * kc)
    const uint32_t split = nd->rc & (SPLIT_BIT(L->ncut) - 1u);
    (void)mark_key(s, KEY(L->pgeo[1][0], L->pgeo[1][1]));
    (void)mark_key(s, KEY(L->pgeo[1][2], L->pgeo[1][3]));
    (void)mark_key(s, KEY(L->pgeo[1][4], L->pgeo[1][5]));
    (void)mark_key(s, KEY(L->pgeo[1][6], L->pgeo[1][7]));
    for (uint32_t m = split; m; m &= m - 1u) {
        const unsigned char *g = L->pgeo[lowest_bit(m) + 2u];
        (void)mark_key(s, KEY(g[6], g[7]));
    }
    uint32_t pos = 2;
    for (;;) {
        if (pos < L->ncut && (split & SPLIT_BIT(pos))) { pos *= 2; continue; }
        if (s->ni + 3 > s->icap) { s->overflow = 1; return 1; }
        const unsigned char *g = L->pgeo[pos];
        uint32_t *o = s->idx + s->ni;
        /* apex, right corner, left corner: counter-clockwise seen from above */
        o[0] = KEY(g[0], g[1]); o[1] = KEY(g[4], g[5]); o[2] = KEY(g[2], g[3]);
        s->ni += 3;
        while ((pos & 1u) && pos > 1) pos >>= 1;
        if (pos == 1) break;
        pos++;
    }
#undef KEY
    return 0;
}

/* Leaves in allocation order (the implicit ones with their block node):
 * one linear pass over the node array (cache friendly; the order is
 * deterministic). */
static void emit_leaves(extract_state *s)
{
    rs_roam *L = s->L;
    const roam_node *nodes = L->nodes;
    for (uint32_t t = 0; t < L->used; t++) {
        const roam_node *nd = &nodes[t];
        uint32_t lc = nd->lc;
        if (lc != NIL && lc != IMPL) continue; /* inner node */
        tri r;
        node_tri(L, nd, &r);
        int stop;
        if (lc == NIL) stop = emit_tri(s, &r);
        else if (r.on) stop = emit_block_on(s, nd, &r);
        else stop = emit_imp(s, nd, 1, &r);
        if (stop) return;
    }
}

/* Pass 2: number the vertex set in row-major order (the rank of each word)
 * and write the vertices, reading the DEM in order. Only words flagged in
 * the summary are visited, so a sparse mesh on a huge map stays cheap.
 * Returns the vertex count; writes nothing when it exceeds vcap. */
static size_t emit_vertices(extract_state *s)
{
    rs_roam *L = s->L;
    size_t n = 0;
    for (size_t g = 0; g < L->nsum; g++)
        for (uint64_t sm = L->vsum[g]; sm; sm &= sm - 1) {
            size_t k = g * 64 + lowest_bit(sm);
            L->vrank[k] = (uint32_t)n;
            n += popcount64(L->vbits[k]);
        }
    if (n > s->vcap) return n;
    size_t v = 0;
    for (size_t g = 0; g < L->nsum; g++)
        for (uint64_t sm = L->vsum[g]; sm; sm &= sm - 1) {
            size_t k = g * 64 + lowest_bit(sm);
            int y = (int)(k / L->wpr), x0 = (int)(k % L->wpr) * 64;
            const float *zr = L->z + (size_t)y * L->w;
            const double py = y * L->cs;
            for (uint64_t b = L->vbits[k]; b; b &= b - 1, v++) {
                int x = x0 + (int)lowest_bit(b);
                float *o = s->vtx + 5 * v;
                o[0] = (float)(x * L->cs);
                o[1] = (float)py;
                o[2] = (float)((double)zr[x] * L->zs);
                o[3] = L->ucol[x];
                o[4] = L->vrow[y];
                if (s->samples) s->samples[v] = (uint32_t)y * L->w + (uint32_t)x;
                if (s->normals) vertex_normal(L, x, y, s->nrm + 3 * v);
            }
        }
    return n;
}

/* Vertex number of sample key p (the vertex set complete and ranked). */
static uint32_t key_vertex(const rs_roam *L, uint32_t p)
{
    uint64_t below = ((uint64_t)1 << (p & 63u)) - 1u;
    return L->vrank[p >> 6] + popcount64(L->vbits[p >> 6] & below);
}

/* Pass 3: sample keys in the first n entries of the index buffer -> vertex numbers. */
static void number_indices(const extract_state *s, size_t n)
{
    uint32_t *ix = s->idx;
    for (size_t i = 0; i < n; i++) ix[i] = key_vertex(s->L, ix[i]);
}

/* Empty the vertex set for the next extraction: only the flagged words. */
static void clear_vertex_set(rs_roam *L)
{
    for (size_t g = 0; g < L->nsum; g++) {
        for (uint64_t sm = L->vsum[g]; sm; sm &= sm - 1) L->vbits[g * 64 + lowest_bit(sm)] = 0;
        L->vsum[g] = 0;
    }
}

/* Border sample -> slot in smap: top row, bottom row, left column, right column. */
static size_t border_slot(const rs_roam *L, int x, int y)
{
    if (y == 0) return (size_t)x;
    if (y == (int)L->ch) return L->w + (size_t)x;
    if (x == 0) return 2 * (size_t)L->w + (size_t)y;
    return 2 * (size_t)L->w + L->hgt + (size_t)y;
}

/* Both keys on the same map border: their sample positions, from the keys
 * (never from the float vertices). */
static int on_same_border(const rs_roam *L, uint32_t kp, uint32_t kq, int *px, int *py, int *qx, int *qy)
{
    uint32_t row = L->wpr * 64u;
    *px = (int)(kp % row); *py = (int)(kp / row);
    *qx = (int)(kq % row); *qy = (int)(kq / row);
    if (*px == *qx && (*px == 0 || *px == (int)L->cw)) return 1;
    if (*py == *qy && (*py == 0 || *py == (int)L->ch)) return 1;
    return 0;
}

static uint32_t skirt_vertex(extract_state *s, uint32_t top, int x, int y, double depth)
{
    rs_roam *L = s->L;
    size_t slot = border_slot(L, x, y);
    if (L->smap[slot] != NIL) return L->smap[slot];
    if (s->nv >= s->vcap) { s->overflow = 1; return 0; }
    float *v = s->vtx + 5 * s->nv;
    memcpy(v, s->vtx + 5 * (size_t)top, 5 * sizeof(float));
    v[2] = (float)((double)v[2] - depth);
    if (s->normals) memcpy(s->nrm + 3 * s->nv, s->nrm + 3 * (size_t)top, 3 * sizeof(float));
    if (s->samples) s->samples[s->nv] = s->samples[top];
    L->smap[slot] = (uint32_t)s->nv;
    return (uint32_t)s->nv++;
}

rs_result rs_roam_extract(rs_ctx *ctx, rs_roam *L, const rs_roam_mesh_options *opts, float *vertices,
                          float *normals, size_t vertex_capacity, uint32_t *indices, size_t index_capacity,
                          size_t *vertex_count, size_t *index_count)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (vertex_count) *vertex_count = 0;
    if (index_count) *index_count = 0;
    if (!L || (!vertices && vertex_capacity) || (!indices && index_capacity))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_extract: roam and buffers must not be NULL");
    rs_roam_mesh_options o;
    if (opts) o = *opts; else memset(&o, 0, sizeof o);
    if (o.normals && !normals)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_extract: normals requested but buffer is NULL");
    if (!(o.skirt_depth >= 0.0) || !isfinite(o.skirt_depth))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_extract: skirt_depth %g must be >= 0", o.skirt_depth);
    if (!((double)L->zabs * L->zs + o.skirt_depth <= FLT_MAX))
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_roam_extract: skirt_depth %g below heights down to -%g leaves the float range (%g)",
                        o.skirt_depth, (double)L->zabs * L->zs, (double)FLT_MAX);
    extract_state s;
    memset(&s, 0, sizeof s);
    s.L = L; s.vtx = vertices; s.nrm = normals; s.normals = o.normals != 0;
    s.vcap = vertex_capacity; s.icap = index_capacity; s.idx = indices;
    s.samples = o.samples;
    emit_leaves(&s);
    if (!s.overflow) {
        s.nv = emit_vertices(&s);
        if (s.nv > s.vcap) s.overflow = 1;
    }
    size_t top_indices = s.ni;
    int top_ok = !s.overflow;
    if (!s.overflow && o.skirt_depth > 0.0) {
        /* the top indices are still sample keys here: the border test reads
         * sample positions from them */
        for (size_t t = 0; t < top_indices && !s.overflow; t += 3)
            for (int e = 0; e < 3 && !s.overflow; e++) {
                uint32_t kp = indices[t + (size_t)e], kq = indices[t + (size_t)(e + 1) % 3];
                int px, py, qx, qy;
                if (!on_same_border(L, kp, kq, &px, &py, &qx, &qy)) continue;
                uint32_t p = key_vertex(L, kp), q = key_vertex(L, kq);
                uint32_t ps = skirt_vertex(&s, p, px, py, o.skirt_depth);
                uint32_t qs = skirt_vertex(&s, q, qx, qy, o.skirt_depth);
                if (s.overflow) break;
                if (s.ni + 6 > s.icap) { s.overflow = 1; break; }
                indices[s.ni++] = p; indices[s.ni++] = ps; indices[s.ni++] = q;
                indices[s.ni++] = q; indices[s.ni++] = ps; indices[s.ni++] = qs;
            }
        memset(L->smap, 0xFF, 2 * ((size_t)L->w + L->hgt) * sizeof(uint32_t));
    }
    if (top_ok) number_indices(&s, top_indices); /* as before skirts existed, even when they overflowed */
    clear_vertex_set(L);
    if (s.overflow) {
        size_t mv, mi;
        rs_roam_mesh_bound(L, &o, &mv, &mi);
        return rs__fail(ctx, RS_ERR_BUFFER_TOO_SMALL,
                        "rs_roam_extract: buffers of %zu vertices / %zu indices too small (bound %zu / %zu)",
                        vertex_capacity, index_capacity, mv, mi);
    }
    if (vertex_count) *vertex_count = s.nv;
    if (index_count) *index_count = s.ni;
    rs__ok(ctx);
    return RS_OK;
}
