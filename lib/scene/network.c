/* The road network (issue 27; docs/network.md): nodes, legs and strokes of
 * a road set.
 *
 * - Points of different roads (or of one road far apart along it) within
 *   the tolerance are one node: the points sorted by the Z-order key of
 *   their cells (8 tolerances), union-find over the pairs they give. A node needs a road
 *   end or two such points; the node's points of one road within twice the
 *   tolerance along it are one pass of that road through the node.
 * - A road end within the tolerance of another road's segment (away from
 *   its points) is a T: that road passes through the end's node.
 * - Legs: a pass at a road's start or end gives one leg, an interior pass
 *   two (forward and backward).
 * - Strokes: a road's end leg and another road's start leg at one node
 *   continue each other when the roads draw alike (width, class, lanes,
 *   oneway, area, style, junction) and the node has degree 2, or the pair
 *   deflects less than 30 degrees and neither leg has another such pair.
 *
 * Everything is ordered by road and point index, so the result does not
 * depend on the cells or on memory addresses. */
#include "network.h"
#include "road_local.h"
#include "grid_edit.h"
#include "lanes.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX
#define MAX_DEFLECTION (RS__PI / 6) /* a stroke through a junction turns less than this */
#define SHORT_CHAIN 16

int rs__class_rank(rs_road_class c)
{
    switch (c) {
    case RS_CLASS_MOTORWAY: return 9;
    case RS_CLASS_TRUNK: return 8;
    case RS_CLASS_PRIMARY: return 7;
    case RS_CLASS_SECONDARY: return 6;
    case RS_CLASS_TERTIARY: return 5;
    case RS_CLASS_RESIDENTIAL: return 4;
    case RS_CLASS_SERVICE: return 3;
    case RS_CLASS_TRACK: return 2;
    case RS_CLASS_PATH: case RS_CLASS_FOOTWAY: case RS_CLASS_CYCLEWAY: return 1;
    default: return 0;
    }
}

static int attr_is(const rs_roads *roads, size_t r, const char *key, const char *v1, const char *v2)
{
    const char *v = rs_roads_get_attr(roads, r, key);
    return v && (strcmp(v, v1) == 0 || (v2 && strcmp(v, v2) == 0));
}

int rs__road_priority(const rs_roads *roads, size_t r)
{
    rs_road_info info;
    int pr = rs_roads_get_info(roads, r, &info) == RS_OK ? rs__class_rank(info.road_class)
                                                          : rs__class_rank(RS_CLASS_NONE);
    if (attr_is(roads, r, "priority_road", "designated", "yes_unposted")) pr += 10;
    if (attr_is(roads, r, "junction", "roundabout", NULL)) pr += 20;
    return pr;
}

rs_oneway rs__road_oneway(const rs_roads *roads, size_t r, const rs_road_info *in)
{
    if (in->oneway == RS_ONEWAY_NONE && attr_is(roads, r, "junction", "roundabout", "circular")) return RS_ONEWAY_YES;
    return in->oneway;
}

int rs__road_level(const rs_roads *roads, size_t r)
{
    const char *v = rs_roads_get_attr(roads, r, "layer");
    if (v) {
        char *end;
        long n = strtol(v, &end, 10);
        /* (strtol's range: within -100 .. 100, errno need not be read) */
        return end != v && *end == '\0' && n >= -100 && n <= 100 ? (int)n : 0;
    }
    const char *b = rs_roads_get_attr(roads, r, "bridge");
    return b && strcmp(b, "no") ? 1 : 0;
}

int rs__road_rank(const rs_roads *roads, size_t r)
{
    return RS__LEVEL_RANK * rs__road_level(roads, r) + rs__road_priority(roads, r);
}

int rs__rank_level(int rank)
{
    return rank >= 0 ? rank / RS__LEVEL_RANK : -((RS__LEVEL_RANK - 1 - rank) / RS__LEVEL_RANK);
}

rs_result rs__road_priorities(rs_ctx *ctx, const rs_roads *roads, int **out)
{
    size_t n = rs_roads_count(roads);
    int *p = rs__alloc_array(ctx, n ? n : 1, sizeof *p), differ = 0;
    *out = NULL;
    if (!p) return RS_ERR_NOMEM;
    for (size_t i = 0; i < n; i++) {
        if (rs__tick(ctx, 0)) {
            rs__free(ctx, p);
            return RS_ERR_CANCELLED;
        }
        p[i] = rs__road_rank(roads, i);
        differ |= p[i] != p[0];
    }
    if (differ) *out = p;
    else rs__free(ctx, p);
    return RS_OK;
}

int rs__class_non_car(rs_road_class c)
{
    return c == RS_CLASS_PATH || c == RS_CLASS_FOOTWAY || c == RS_CLASS_CYCLEWAY;
}

int rs__road_non_car(const rs_roads *roads, size_t r)
{
    rs_road_info info;
    return rs_roads_get_info(roads, r, &info) == RS_OK && rs__class_non_car(info.road_class);
}

/* ---- points sorted by cell in Z order: a cell's points are one run ---- */

/* A point with what the pair tests read of it, so a candidate costs one
 * cache line, not one per array. */
typedef struct pt_entry {
    double x, y;
    uint32_t id, road;
} pt_entry;

/* The points sorted by the Z-order (Morton) key of their cell, so the
 * points of a cell are one run and the runs of neighbouring cells lie
 * close together in memory: the build reads them in space order, where
 * hash buckets (until this) put neighbouring cells at random places, a
 * cache miss per probe once the table outgrows the cache. A key cell is
 * 2^extra cells a side (extra > 0 only when the points span more than 2^32
 * cells: huge coordinates; the pair tests are exact, so a coarser cell
 * only adds candidates). A directory of 2^k blocks of keys (about one
 * point each) finds a cell's run: its block, then a short search. */
typedef struct pt_cells {
    double cell;
    int64_t lo[2], hi[2]; /* the lowest and highest cell of the points, x and y */
    unsigned extra;       /* a key cell is 2^extra cells a side */
    unsigned dshift;      /* a key's directory block: key >> dshift */
    size_t count;
    uint64_t *key;        /* per entry, ascending */
    pt_entry *ent;        /* the points in key order (ids ascending within a key) */
    uint32_t *dir;        /* the first entry of each directory block, and count */
    uint64_t *occ;        /* a bit per eighth of a directory block (8 per point: in the cache,
                             and in space order): a clear bit says the cell is empty, before
                             its block is read */
    unsigned oshift;      /* a key's bit: key >> oshift */
    /* dense (cells_dense): a grid of nx x ny cells from lo, row by row; the
     * points of cell (x, y) are ent[start[y nx + x] .. start[y nx + x + 1]),
     * so the cells x0 .. x1 of a row are one run (key, dir, occ unused) */
    int dense;
    uint64_t nx;
    uint32_t *start;      /* nx ny + 2 */
    int mul;              /* the points' cells: cell numbers by x * inv (cell_mul), not x / cell */
    double inv;           /* 1 / cell */
} pt_cells;

/* floor(x / cell) clamped to +-4.6e18 (NaN: the low end); floor by the
 * integer conversion (floor is a libm call: a tenth of a small build) */
static inline int64_t cell_clamp(double t)
{
    if (!(t > -4.6e18)) return (int64_t)-4.6e18; /* (also catches -inf) */
    if (!(t < 4.6e18)) return (int64_t)4.6e18;
    int64_t i = (int64_t)t; /* (toward zero) */
    return i - (t < (double)i);
}

static int64_t cell_of(double x, double cell) { return cell_clamp(x / cell); }

/* The cell of x in H: for the points' cells x * (1 / cell), a multiply for
 * a divide (the points' cells, their bounds and the discs' reach all take
 * this one function, and any monotone one finds every pair: the tests are
 * exact); the road ends' cells divide, as the T walk's rows do. */
static inline int64_t hcell(const pt_cells *H, double x)
{
    return H->mul ? cell_clamp(x * H->inv) : cell_clamp(x / H->cell);
}


/* Reads by id at random places are asked for this many steps ahead
 * (rs__prefetch): at 10^5 records the arrays are beyond the cache, and a
 * gather by id waits on memory for each point otherwise. */
#define AHEAD 8
/* The same in the counting sort's passes, which do little for each point:
 * further ahead, as more points go by in a memory latency. */
#define CAHEAD 24

/* The low 32 bits of v, spread to the even bits. */
static uint64_t spread32(uint64_t v)
{
    v &= 0xFFFFFFFFull;
    v = (v | v << 16) & 0x0000FFFF0000FFFFull;
    v = (v | v << 8) & 0x00FF00FF00FF00FFull;
    v = (v | v << 4) & 0x0F0F0F0F0F0F0F0Full;
    v = (v | v << 2) & 0x3333333333333333ull;
    v = (v | v << 1) & 0x5555555555555555ull;
    return v;
}

static uint64_t zkey(uint64_t kx, uint64_t ky) { return spread32(kx) | spread32(ky) << 1; }

/* The key cells (axis 0: x, 1: y) of the cells a .. b: *ka .. *kb; 0 when
 * none holds a point. */
static int key_range(const pt_cells *H, int axis, int64_t a, int64_t b, uint64_t *ka, uint64_t *kb)
{
    if (!H->count || b < H->lo[axis] || a > H->hi[axis]) return 0;
    if (a < H->lo[axis]) a = H->lo[axis];
    if (b > H->hi[axis]) b = H->hi[axis];
    *ka = ((uint64_t)a - (uint64_t)H->lo[axis]) >> H->extra;
    *kb = ((uint64_t)b - (uint64_t)H->lo[axis]) >> H->extra;
    return 1;
}


/* The run of entries of key cell (kx, ky): *a .. *b - 1. */
static void run_of(const pt_cells *H, uint64_t kx, uint64_t ky, uint32_t *a, uint32_t *b)
{
    uint64_t k = zkey(kx, ky), blk = k >> H->dshift, o = k >> H->oshift;
    if (!(H->occ[o >> 6] >> (o & 63) & 1)) {
        *a = *b = 0;
        return;
    }
    uint32_t l = H->dir[blk], r = H->dir[blk + 1], e = r;
    if (l == r) {
        *a = *b = l;
        return;
    }
    while (r - l > 8) { /* (a crowded block: a binary search) */
        uint32_t m = l + (r - l) / 2;
        if (H->key[m] < k) l = m + 1;
        else r = m;
    }
    while (l < e && H->key[l] < k) l++;
    *a = l;
    while (l < e && H->key[l] == k) l++;
    *b = l;
}

/* Digits of 11 bits up to 2^18 points, else of 8: a scatter to 2048
 * places outruns the TLB once the arrays are several megabytes (measured:
 * 8-bit digits 5 % faster at 5 10^5 points, 11-bit ones faster at 10^5
 * and below: one pass fewer). */
#define RADIX_MAXBITS 11
#define RADIX_DIGITS 8

/* The kept points' count and bounding box, made where they are marked or
 * with the pass that finds cluster_points' largest coordinate (a pass over
 * the points fewer for each sort; bad: a coordinate is not finite, and the
 * box unknown). */
typedef struct pt_box {
    size_t count;
    double x0, x1, y0, y1;
    int bad;
} pt_box;

static void box_init(pt_box *b)
{
    b->count = 0;
    b->x0 = b->y0 = DBL_MAX, b->x1 = b->y1 = -DBL_MAX;
    b->bad = 0;
}

static void box_add(pt_box *b, const double *p)
{
    double x = p[0], y = p[1];
    b->count++;
    if (!(x >= -DBL_MAX && x <= DBL_MAX && y >= -DBL_MAX && y <= DBL_MAX)) b->bad = 1;
    b->x0 = x < b->x0 ? x : b->x0, b->x1 = x > b->x1 ? x : b->x1;
    b->y0 = y < b->y0 ? y : b->y0, b->y1 = y > b->y1 ? y : b->y1;
}

/* The dense grid (H->dense) when it is small: a counting sort by cell,
 * two passes over the points in id order (no random gather, no radix
 * passes, a run found by two reads). The cells are `cell` wide, or with
 * coarsen as wide as it takes for about two cells a point (the points'
 * cells: a disc of the tolerance still reaches few cells, and the pair
 * tests are exact, so a coarser cell only adds candidates), unless the
 * points crowd: then, or when the box would take too many cells (sparse
 * points, huge or non-finite coordinates), 0 (*res RS_OK) and nothing is
 * made. */
static int cells_dense(rs_ctx *ctx, pt_cells *H, const double *xy, const uint32_t *vroad,
                       const uint8_t *keep, size_t n, double cell, int coarsen, const pt_box *box, rs_result *res)
{
    size_t count = H->count;
    *res = RS_OK;
    if (!count || count >= (1u << 30) || box->bad) return 0; /* (NaN, inf) */
    double x0 = box->x0, x1 = box->x1, y0 = box->y0, y1 = box->y1;
    double most = coarsen == 1 ? 2.0 * (double)count + 16 : 8.0 * (double)count + 4096, c = cell;
    if (most > 2147483647.0) most = 2147483647.0; /* (cell numbers are 32-bit) */
    if (coarsen) {
        double a = (x1 - x0) * (y1 - y0) / most, l = ((x1 - x0) + (y1 - y0)) / most;
        if (a > c * c) c = sqrt(a);
        if (l > c) c = l;
        if (!(c >= cell)) c = cell;
    }
    int64_t lx = 0, ly = 0;
    double nx = 0, ny = 0;
    for (int tries = 0;; tries++) {
        H->cell = c, H->inv = 1 / c;
        lx = hcell(H, x0), ly = hcell(H, y0);
        nx = (double)(hcell(H, x1) - lx) + 1, ny = (double)(hcell(H, y1) - ly) + 1;
        if (nx * ny <= most) break;
        if (!coarsen || tries > 60 || !(c * 1.25 <= 1e300)) {
            H->cell = cell, H->inv = 1 / cell;
            return 0;
        }
        c *= 1.25;
    }
    size_t cells = (size_t)(nx * ny);
    H->start = rs__calloc(ctx, cells + 2, sizeof *H->start);
    H->ent = rs__alloc_array(ctx, count, sizeof *H->ent);
    uint32_t *cid = rs__alloc_array(ctx, count, sizeof *cid);
    if (!H->start || !H->ent || !cid) {
        rs__free(ctx, cid);
        H->cell = cell, H->inv = 1 / cell;
        *res = RS_ERR_NOMEM;
        return 0;
    }
    uint64_t w = (uint64_t)nx;
    for (size_t i = 0, k = 0; i < n; i++) {
        if ((i & 65535) == 0 && rs__poll(ctx)) { *res = RS_ERR_CANCELLED; break; }
        if (keep && !keep[i]) continue;
        uint64_t cx = (uint64_t)(hcell(H, xy[2 * i]) - lx), cy = (uint64_t)(hcell(H, xy[2 * i + 1]) - ly);
        uint32_t q = (uint32_t)(cy * w + cx);
        /* the count CAHEAD points later, its line asked for now: in id order
         * the cells of one road's points are rows apart (a random place) */
        rs__prefetch(H->start + q + 2);
        if (k >= CAHEAD) H->start[cid[k - CAHEAD] + 2]++;
        cid[k++] = q;
    }
    for (size_t k = count > CAHEAD ? count - CAHEAD : 0; k < count && !*res; k++) H->start[cid[k] + 2]++;
    /* crowded points (many in few cells: a pair test for every two in a
     * cell) take the Z-order cells of the given size instead */
    double pairs = 0;
    for (size_t j = 2; j < cells + 2; j++) {
        pairs += (double)H->start[j] * H->start[j];
        H->start[j] += H->start[j - 1];
    }
    if (!*res && c > cell && pairs > 16.0 * (double)count + 1024) {
        H->cell = cell, H->inv = 1 / cell;
        rs__free(ctx, cid);
        rs__free(ctx, H->start);
        rs__free(ctx, H->ent);
        H->start = NULL, H->ent = NULL;
        return 0;
    }
    for (size_t i = 0, k = 0; i < n && !*res; i++) {
        if ((i & 65535) == 0 && rs__poll(ctx)) { *res = RS_ERR_CANCELLED; break; }
        if (keep && !keep[i]) continue;
        if (k + 2 * CAHEAD < count) rs__prefetch(H->start + cid[k + 2 * CAHEAD] + 1);
        if (k + CAHEAD < count) rs__prefetch(H->ent + H->start[cid[k + CAHEAD] + 1]);
        pt_entry *e = &H->ent[H->start[cid[k++] + 1]++];
        e->x = xy[2 * i], e->y = xy[2 * i + 1];
        e->id = (uint32_t)i, e->road = vroad[i];
    }
    rs__free(ctx, cid);
    H->dense = 1;
    H->cell = c;
    H->nx = w;
    H->lo[0] = lx, H->lo[1] = ly;
    H->hi[0] = lx + (int64_t)w - 1, H->hi[1] = ly + (int64_t)ny - 1;
    return 1;
}

/* Sort the points xy[2 id] (arc length s[id], road vroad[id]) of the ids
 * for which keep[id] (NULL: all) by their cells: the dense grid when it
 * can be made (cells_dense; coarsen: 1 the points' cells, 2 the road ends'
 * ones may be wider), else by their cells' keys: a stable LSD radix sort
 * (digits that all keys share are skipped). Either way ids ascend within a
 * cell; linear in the points, every pass a stream. */
static rs_result cells_build(rs_ctx *ctx, pt_cells *H, const double *xy, const uint32_t *vroad,
                             const uint8_t *keep, size_t n, double cell, int coarsen, const pt_box *box)
{
    size_t count = box->count;
    memset(H, 0, sizeof *H);
    H->cell = cell;
    H->inv = 1 / cell;
    H->mul = coarsen == 1;
    H->count = count;
    rs_result dres;
    if (cells_dense(ctx, H, xy, vroad, keep, n, cell, coarsen, box, &dres) || dres) return dres;
    size_t m = count ? count : 1;
    uint64_t ndir = 1;
    while (ndir < (uint64_t)count && ndir < (1ull << 31)) ndir *= 2;
    H->key = rs__alloc_array(ctx, m, sizeof *H->key);
    H->ent = rs__alloc_array(ctx, m, sizeof *H->ent);
    H->dir = rs__alloc_array(ctx, (size_t)ndir + 1, sizeof *H->dir);
    H->occ = rs__calloc(ctx, (size_t)(ndir / 8 + 1), sizeof *H->occ); /* (8 ndir bits) */
    uint64_t *k2 = rs__alloc_array(ctx, m, sizeof *k2);
    uint32_t *ia = rs__alloc_array(ctx, m, sizeof *ia), *ib = rs__alloc_array(ctx, m, sizeof *ib);
    uint32_t *hist = rs__calloc(ctx, (size_t)RADIX_DIGITS << RADIX_MAXBITS, sizeof *hist);
    rs_result res = RS_ERR_NOMEM;
    if (!H->key || !H->ent || !H->dir || !H->occ || !k2 || !ia || !ib || !hist) goto done;
    /* cells (x in key, y in k2) and their bounds */
    int64_t lo[2] = { INT64_MAX, INT64_MAX }, hi[2] = { INT64_MIN, INT64_MIN };
    for (size_t i = 0, k = 0; i < n; i++) {
        if ((i & 65535) == 0 && rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto done; }
        if (keep && !keep[i]) continue;
        int64_t cx = hcell(H, xy[2 * i]), cy = hcell(H, xy[2 * i + 1]);
        lo[0] = cx < lo[0] ? cx : lo[0], hi[0] = cx > hi[0] ? cx : hi[0];
        lo[1] = cy < lo[1] ? cy : lo[1], hi[1] = cy > hi[1] ? cy : hi[1];
        H->key[k] = (uint64_t)cx, k2[k] = (uint64_t)cy, ia[k++] = (uint32_t)i;
    }
    if (count) {
        uint64_t span = (uint64_t)hi[0] - (uint64_t)lo[0], sy = (uint64_t)hi[1] - (uint64_t)lo[1];
        span = sy > span ? sy : span;
        while ((span >> H->extra) > 0xFFFFFFFFull) H->extra++;
        memcpy(H->lo, lo, sizeof lo);
        memcpy(H->hi, hi, sizeof hi);
    }
    uint64_t *ka = H->key, *kb = k2;
    unsigned bits = 0; /* key bits: twice those of the largest key cell */
    while (bits < 32 && ((uint64_t)(count ? (uint64_t)hi[0] - (uint64_t)lo[0] : 0) >> H->extra >> bits ||
                         (uint64_t)(count ? (uint64_t)hi[1] - (uint64_t)lo[1] : 0) >> H->extra >> bits))
        bits++;
    unsigned rb = count <= 262144 ? 11 : 8;
    int ndig = (int)((2 * bits + rb - 1) / rb);
    for (size_t k = 0; k < count; k++) {
        if ((k & 65535) == 0 && rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto done; }
        uint64_t key = zkey((H->key[k] - (uint64_t)lo[0]) >> H->extra, (k2[k] - (uint64_t)lo[1]) >> H->extra);
        ka[k] = key;
        for (int d = 0; d < ndig; d++) hist[((size_t)d << RADIX_MAXBITS) + (key >> (d * rb) & ((1u << rb) - 1))]++;
    }
    for (int d = 0; d < ndig && count; d++) {
        uint32_t *h = hist + ((size_t)d << RADIX_MAXBITS);
        unsigned sh = (unsigned)d * rb;
        if (h[ka[0] >> sh & ((1u << rb) - 1)] == count) continue; /* all keys share this digit */
        if (rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto done; } /* (a pass: ~5 ms at 10^6 points) */
        uint32_t at = 0;
        for (size_t j = 0; j < (1u << rb); j++) {
            uint32_t c = h[j];
            h[j] = at;
            at += c;
        }
        for (size_t k = 0; k < count; k++) {
            uint32_t q = h[ka[k] >> sh & ((1u << rb) - 1)]++;
            kb[q] = ka[k], ib[q] = ia[k];
        }
        uint64_t *tk = ka;
        ka = kb, kb = tk;
        uint32_t *ti = ia;
        ia = ib, ib = ti;
    }
    if (ka != H->key) memcpy(H->key, ka, count * sizeof *ka);
    for (size_t k = 0; k < count; k++) {
        if ((k & 65535) == 0 && rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto done; }
        uint32_t i = ia[k];
        if (k + AHEAD < count) {
            uint32_t f = ia[k + AHEAD];
            rs__prefetch(xy + 2 * (size_t)f);
            rs__prefetch(vroad + f);
        }
        pt_entry *e = &H->ent[k];
        e->x = xy[2 * (size_t)i], e->y = xy[2 * (size_t)i + 1];
        e->id = i, e->road = vroad[i];
    }
    /* the directory: blocks of keys, about one point each */
    uint64_t top = count ? H->key[count - 1] : 0;
    while ((top >> H->dshift) >= ndir) H->dshift++;
    H->oshift = H->dshift >= 3 ? H->dshift - 3 : 0;
    for (size_t k = 0; k < count; k++) {
        uint64_t o = H->key[k] >> H->oshift;
        H->occ[o >> 6] |= 1ull << (o & 63);
    }
    for (uint64_t b = 0, k = 0; b <= ndir; b++) {
        while (k < count && (H->key[k] >> H->dshift) < b) k++;
        H->dir[b] = (uint32_t)k;
    }
    res = RS_OK;
done:
    rs__free(ctx, k2);
    rs__free(ctx, ia);
    rs__free(ctx, ib);
    rs__free(ctx, hist);
    return res;
}

static void cells_free(rs_ctx *ctx, pt_cells *H)
{
    rs__free(ctx, H->key);
    rs__free(ctx, H->ent);
    rs__free(ctx, H->dir);
    rs__free(ctx, H->occ);
    rs__free(ctx, H->start);
    memset(H, 0, sizeof *H);
}

/* The cells of H that a disc of radius r around p can reach: x cells
 * c[0] .. c[1], y cells c[2] .. c[3]. The radius grows by the rounding of
 * p's coordinates so the cells of all points within r are in (cell_of is
 * monotone). */
static void disc_cells(const pt_cells *H, const double *p, double r, int64_t c[4])
{
    for (int k = 0; k < 2; k++) {
        double m = r * (1 + 1e-9) + fabs(p[k]) * (4 * DBL_EPSILON); /* (not 4 fabs(p): overflow) */
        if (!isfinite(p[k])) m = 0; /* (its own clamped cell) */
        /* a margin past +-DBL_MAX would give an infinite end: clamped to
         * the largest finite coordinate, not to the last cell (4.6e18
         * cells to probe from a point at -1.8e308) */
        double lo = p[k] - m, hi = p[k] + m;
        if (isfinite(p[k])) {
            lo = lo >= -DBL_MAX ? lo : -DBL_MAX;
            hi = hi <= DBL_MAX ? hi : DBL_MAX;
        }
        c[2 * k] = hcell(H, lo);
        c[2 * k + 1] = hcell(H, hi);
    }
}

/* ---- build state ---- */

/* What a road's legs and stroke links read of it, gathered once in road
 * order: the nodes visit roads in random order, and the road set's records,
 * attributes and strings are several cache lines apart. */
typedef struct road_look {
    double width;
    const char *style, *junction;
    uint32_t lanes;
    int16_t priority;     /* class rank + 10 priority_road + 20 roundabout */
    uint8_t road_class, link, oneway, area;
    uint8_t two_way;      /* a record drawn against its points is the same road */
    uint8_t roundabout;
    uint32_t first, last; /* its first and last point (global ids) */
    uint32_t last_run;    /* the first point of its last point's run (rep[last]: in the look, where
                             the passes read it, not at a random place of rep) */
    double length;        /* arc length at its last point */
} road_look;

/* (40 bytes: at 10^5 records the passes are tens of megabytes, sorted
 * by a scatter) */
typedef struct pass {
    uint32_t road, v0, v1; /* first and last point (global ids) of the road at the node */
    uint32_t seg;          /* a T: the segment; NONE for a pass through points */
    uint32_t node;
    uint8_t first, last;   /* v0 is the road's first point, v1 its last (not a T) */
    double s;              /* a T: the arc length of the nearest point; else of v0 */
    double x;              /* a pass through points: the arc length at v1; a T: its distance */
} pass;

/* A pass's arc length at v1 (a T: s) and a T's distance (points: 0). */
static double pass_s1(const pass *p) { return p->seg == NONE ? p->x : p->s; }

typedef struct build {
    rs_ctx *ctx;
    const rs_roads *roads;
    size_t nroads, nv;
    double tol;
    size_t *voff;      /* nroads + 1: the points of road r are voff[r] .. voff[r+1]-1 */
    uint32_t *vroad;   /* per point */
    const double *xy;  /* per point: the road set's array, or xy_own */
    double *xy_own, *s;
    uint32_t *rep;     /* per point: the first of its run of equal consecutive points */
    uint32_t *parent;  /* union-find over points */
    uint8_t *live;     /* per road: longer than twice the tolerance */
    road_look *look;   /* per road */
    struct surf_rd *srd; /* per road: what surface_tees reads of it (copied from look, which is freed first) */
    int8_t *level;     /* per road: rs__road_level (-100 .. 100), read once, not per candidate T */
    uint8_t *inhash;   /* per point: a live road's point that starts its run */
    uint32_t *nodeof;  /* per point: its group's node, or NONE (set for the roots, then for every
                          point from its root: the passes after read it once, not parent and
                          then nodeof at a second random place) */
    pass *ps;          /* the T passes (by node after node_lists) */
    size_t nps, cps;
    uint32_t *pstart, *pids, *tstart; /* node_lists */
    size_t nlegs;      /* node_lists: at most this many legs (two a point, one at a road end, two a T) */
    pass *buf;         /* one node's passes */
    size_t cbuf;
    uint32_t *ctl;     /* per node: its controls from point attributes (NULL: none) */
    uint32_t *short_at; /* pairs (short record, the node its ends are at), for link_short_ends */
    size_t nshort;
    /* chains (chain_short_runs; NULL when no run of short records is
     * made live there): per road, its chain (the id of a
     * record in it; a road in none: itself), the chain's arc length at the
     * road's first point when crev is 0, at its last when 1 */
    uint32_t *cid;
    double *cs0, *ctot; /* ctot: per chain id, a ring's length (0: the chain has two ends) */
    uint8_t *crev;
    uint32_t *cpart;    /* with chains: per road end, the end of the chain's next record there, or NONE */
    uint8_t *jend;      /* per road of a chain: bit 0, its first point is a joint of the chain (two
                           records' ends exactly there, no other), bit 1 its last */
} build;

static uint32_t find(uint32_t *parent, uint32_t v)
{
    uint32_t r = v;
    while (parent[r] != r) r = parent[r];
    while (parent[v] != r) {
        uint32_t n = parent[v];
        parent[v] = r;
        v = n;
    }
    return r;
}

static void unite(uint32_t *parent, uint32_t a, uint32_t b)
{
    a = find(parent, a);
    b = find(parent, b);
    if (a < b) parent[b] = a; /* the root is the lowest point: deterministic */
    else if (b < a) parent[a] = b;
}

/* unite for the places of cluster_points: the root is the place of the
 * lower point (ids differ), so a group's root holds its lowest point. */
static void unite_places(uint32_t *up, const pt_entry *ent, uint32_t a, uint32_t b)
{
    a = find(up, a);
    b = find(up, b);
    if (a == b) return;
    if (ent[a].id < ent[b].id) up[b] = a;
    else up[a] = b;
}

static int near2(const double *a, const double *b, double tol)
{
    double dx = a[0] - b[0], dy = a[1] - b[1];
    return dx * dx + dy * dy <= tol * tol;
}

/* Road r's arc length s as the arc length along its chain. */
static double chain_pos(const build *B, uint32_t r, double s)
{
    return B->crev[r] ? B->cs0[r] + (B->look[r].length - s) : B->cs0[r] + s;
}

/* Places at arc length sa of road ra and sb of rb are one place of one
 * road (no node joins them): within twice the tolerance along the road,
 * or with chains along the chain (around a ring the shorter way), except
 * where two records' ends are the same point (`same`), which their chain
 * joins there. */
static int one_place(const build *B, uint32_t ra, double sa, uint32_t rb, double sb, int same)
{
    if (!B->cid) return ra == rb && fabs(sa - sb) <= 2 * B->tol;
    uint32_t c = B->cid[ra];
    if (c != B->cid[rb] || (ra != rb && same)) return 0;
    double d = fabs(chain_pos(B, ra, sa) - chain_pos(B, rb, sb));
    if (B->ctot[c] > 0 && B->ctot[c] - d < d) d = B->ctot[c] - d;
    return d <= 2 * B->tol;
}

/* Point v is a joint of a chain (chain_short_runs): one record's end
 * where the next one starts, no node of other streets. */
static int chain_joint(const build *B, uint32_t v)
{
    uint32_t r = B->vroad[v];
    if (!B->jend[r]) return 0;
    return ((B->jend[r] & 1) && v == B->voff[r]) || ((B->jend[r] & 2) && v == B->rep[B->voff[r + 1] - 1]);
}

static rs_result push_pass(build *B, const pass *p)
{
    if (B->nps == B->cps) {
        size_t nc = B->cps ? 2 * B->cps : 64, bytes;
        if (!rs__mul_size(nc, sizeof *B->ps, &bytes)) return RS_ERR_NOMEM;
        pass *np = rs__realloc(B->ctx, B->ps, bytes);
        if (!np) return RS_ERR_NOMEM;
        B->ps = np;
        B->cps = nc;
    }
    B->ps[B->nps++] = *p;
    return RS_OK;
}

/* Road ends near the inside of other roads' segments: T passes. */
static rs_result find_tees(build *B)
{
    size_t nseg = 0;
    double total = 0;
    for (size_t r = 0; r < B->nroads; r++)
        if (B->live[r]) {
            nseg += B->voff[r + 1] - B->voff[r] - 1;
            total += B->s[B->voff[r + 1] - 1];
        }
    /* end points sorted in cells of a mean segment (at least 4
     * tolerances): walking every segment's cells stays linear (half or
     * twice that measured within 5 % on the 10^5 lattice) */
    double g = nseg ? total / (double)nseg : 1;
    if (!(g >= 4 * B->tol)) g = 4 * B->tol;
    if (!(g <= 1e300)) g = 1e300;
    uint8_t *isend = rs__calloc(B->ctx, B->nv ? B->nv : 1, 1);
    if (!isend) return RS_ERR_NOMEM;
    pt_box box;
    box_init(&box);
    for (size_t r = 0; r < B->nroads; r++)
        if (B->live[r]) {
            size_t e0 = B->voff[r], e1 = B->rep[B->voff[r + 1] - 1];
            isend[e0] = 1;
            box_add(&box, B->xy + 2 * e0);
            if (e1 != e0) {
                isend[e1] = 1;
                box_add(&box, B->xy + 2 * e1);
            }
        }
    pt_cells H;
    rs_result res = cells_build(B->ctx, &H, B->xy, B->vroad, isend, B->nv, g, 2, &box);
    g = H.cell; /* (dense cells may be wider) */
    if (res) goto done;
    double tol = B->tol;
    /* The roads in the order of their first points in the cells (each
     * live road's first point is an end there, once): a road's segments
     * walk cells near the last road's, so the ends they read are mostly in
     * the cache, where in road order a street lattice's vertical roads
     * crossed every row of cells once per column, 3x the time a segment of
     * its horizontal ones took (the walk at 10^5 records about 10 % faster,
     * at 10^4 5 % slower). The roads' own points are read at random places
     * instead, asked for a few ends ahead. The passes found are the same in
     * another order, and their order does not count: passes that
     * sort_passes finds equal are equal in every field. */
    for (size_t q0 = 0; q0 < H.count && !res; q0++) {
        if ((q0 & 1023) == 0 && rs__poll(B->ctx)) { /* (10^5 roads, 2 10^5 ends: ~0.2 s) */
            res = RS_ERR_CANCELLED;
            break;
        }
        if (q0 + AHEAD < H.count) {
            const pt_entry *f = &H.ent[q0 + AHEAD];
            rs__prefetch(B->voff + f->road);
            rs__prefetch(B->xy + 2 * (size_t)f->id); /* (a road's points: 3 lines, up to 9 points) */
            if (f->id + 4 < B->nv) rs__prefetch(B->xy + 2 * (size_t)f->id + 8);
            if (f->id + 8 < B->nv) rs__prefetch(B->xy + 2 * (size_t)f->id + 16);
            rs__prefetch(B->rep + f->id);
        }
        size_t r = H.ent[q0].road;
        if (H.ent[q0].id != B->voff[r]) continue; /* (a last point) */
        for (size_t k = B->voff[r]; k + 1 < B->voff[r + 1] && !res; k++) {
            size_t k1 = k + 1;
            if (B->rep[k1] != k1) continue; /* a repeated point: no segment */
            uint32_t a = B->rep[k];
            const double *pa = B->xy + 2 * a, *pb = B->xy + 2 * k1;
            double dx = pb[0] - pa[0], dy = pb[1] - pa[1], dd = dx * dx + dy * dy;
            if (!(dd > 0) || !isfinite(dd)) continue;
            double ymin = rs__fmin(pa[1], pb[1]) - tol, ymax = rs__fmax(pa[1], pb[1]) + tol;
            int64_t r0 = cell_of(ymin, g), r1 = cell_of(ymax, g);
            /* a box of at most 3 x 3 dense cells: all of it (most segments;
             * clipping each row cost more than the ends it skips) */
            int64_t bc0 = cell_of(rs__fmin(pa[0], pb[0]) - tol, g), bc1 = cell_of(rs__fmax(pa[0], pb[0]) + tol, g);
            int whole = H.dense && r1 - r0 < 3 && bc1 - bc0 < 3;
            for (int64_t cy = r0; cy <= r1 && !res; cy++) {
                int64_t c0 = bc0, c1 = bc1;
                if (!whole) {
                    double y0 = rs__fmax((double)cy * g, ymin) - tol, y1 = rs__fmin((double)(cy + 1) * g, ymax) + tol;
                    double t0 = 0, t1 = 1;
                    if (dy != 0) {
                        t0 = (y0 - pa[1]) / dy;
                        t1 = (y1 - pa[1]) / dy;
                        if (t0 > t1) { double q = t0; t0 = t1; t1 = q; }
                        t0 = rs__fmax(t0, 0), t1 = rs__fmin(t1, 1);
                        if (t0 > t1) continue;
                    }
                    double xa = pa[0] + t0 * dx, xb = pa[0] + t1 * dx;
                    c0 = cell_of(rs__fmin(xa, xb) - tol, g), c1 = cell_of(rs__fmax(xa, xb) + tol, g);
                }
                uint64_t kx0, kx1, ky, ky1;
                if (!key_range(&H, 1, cy, cy, &ky, &ky1) || !key_range(&H, 0, c0, c1, &kx0, &kx1)) continue;
                for (uint64_t kx = kx0; kx <= kx1 && !res; kx++) {
                    uint32_t qa, qb;
                    if (H.dense) { /* (the row's cells kx0 .. kx1: one run) */
                        qa = H.start[ky * H.nx + kx0], qb = H.start[ky * H.nx + kx1 + 1];
                        kx = kx1;
                    } else
                        run_of(&H, kx, ky, &qa, &qb);
                    for (uint32_t q = qa; q < qb; q++) {
                        uint32_t e = H.ent[q].id;
                        /* (the entry's own point first: it passes over most ends
                         * without reading the end's road at a random place) */
                        const double *pe = &H.ent[q].x; /* (a key cell of 2^extra cells: a T found twice merges) */
                        double num = (pe[0] - pa[0]) * dx + (pe[1] - pa[1]) * dy;
                        /* (num <= 0 or >= dd gives u <= 0 or >= 1 after rounding too: most
                         * candidates, a segment's own and joined ends, go without a divide) */
                        if (!(num > 0 && num < dd)) continue;
                        double u = num / dd;
                        if (!(u > 0 && u < 1)) continue; /* beyond the segment: the points' business */
                        double qx = pa[0] + u * dx, qy = pa[1] + u * dy, ex = pe[0] - qx, ey = pe[1] - qy;
                        double e2 = ex * ex + ey * ey;
                        if (!(e2 <= 4 * tol * tol)) continue; /* (sqrt(e2) > tol: no sqrt) */
                        double dist = sqrt(e2);
                        if (!(dist <= tol)) continue;
                        if (B->cid && chain_joint(B, e)) continue; /* (inside its street: no end on another) */
                        uint32_t nd = B->nodeof[e]; /* (an end: its group is a node) */
                        if (B->nodeof[a] == nd || B->nodeof[k1] == nd) continue; /* (one group: one node) */
                        double s = B->s[a] + u * (B->s[k1] - B->s[a]);
                        if ((B->cid || B->vroad[e] == r) && one_place(B, (uint32_t)r, s, B->vroad[e], B->s[e], 0))
                            continue;
                        /* (an end on a road of another level, a bridge's
                         * line over it: they do not meet) */
                        if (B->level[r] != B->level[B->vroad[e]]) continue;
                        pass p = { (uint32_t)r, a, (uint32_t)k1, (uint32_t)(k - B->voff[r]), nd, 0, 0, s, dist };
                        if ((res = push_pass(B, &p)) != RS_OK) break;
                    }
                }
            }
        }
    }
done:
    cells_free(B->ctx, &H);
    rs__free(B->ctx, isend);
    return res;
}

static int pass_cmp(const void *pa, const void *pb)
{
    const pass *a = pa, *b = pb;
    if (a->node != b->node) return a->node < b->node ? -1 : 1;
    if (a->road != b->road) return a->road < b->road ? -1 : 1;
    if (a->s != b->s) return a->s < b->s ? -1 : 1;
    if (a->seg != b->seg) return a->seg < b->seg ? -1 : 1; /* (a pass through points has seg NONE: last) */
    if (a->x != b->x) return a->x < b->x ? -1 : 1; /* (a T: its distance; points: s1 = s here) */
    return 0;
}

/* Sort k passes by pass_cmp: an insertion sort (stable) for the few of
 * most nodes, where qsort's call and comparisons through a pointer cost
 * more than the sorting; qsort beyond, as before (glibc's is a merge sort:
 * stable, so the order is the same either way). */
static void sort_passes(pass *P, size_t k)
{
    if (k > 16) {
        qsort(P, k, sizeof *P, pass_cmp);
        return;
    }
    for (size_t i = 1; i < k; i++) {
        pass t = P[i];
        size_t j = i;
        for (; j > 0 && pass_cmp(&P[j - 1], &t) > 0; j--) P[j] = P[j - 1];
        P[j] = t;
    }
}

/* The pass of point v (a hashed point) through its node nd. */
static void point_pass(const build *B, size_t v, uint32_t nd, pass *p)
{
    const road_look *lk = &B->look[B->vroad[v]];
    pass q = { B->vroad[v], (uint32_t)v, (uint32_t)v, NONE, nd, v == lk->first, v == lk->last_run, B->s[v], B->s[v] };
    *p = q;
}

/* Each node's points (ascending: B->pstart, B->pids) and its T passes (in
 * the order found: B->ps by node, B->tstart), by two counting sorts. The
 * passes through points are made node by node from these (no array of
 * them: 40 bytes a point at a node, tens of megabytes at 10^5 records). */
static rs_result node_lists(build *B, size_t nn)
{
    size_t np = 0;
    B->pstart = rs__calloc(B->ctx, nn + 2, sizeof *B->pstart);
    B->tstart = rs__calloc(B->ctx, nn + 2, sizeof *B->tstart);
    if (!B->pstart || !B->tstart) return RS_ERR_NOMEM;
    size_t nlegs = 2 * B->nps;
    /* (nodes by point: at random places; asked for CAHEAD points ahead) */
    for (size_t v = 0; v < B->nv; v++)
        if (B->inhash[v]) {
            if (v + CAHEAD < B->nv && B->nodeof[v + CAHEAD] != NONE) rs__prefetch(B->pstart + B->nodeof[v + CAHEAD] + 2);
            uint32_t nd = B->nodeof[v];
            if (nd != NONE) {
                const road_look *lk = &B->look[B->vroad[v]];
                unsigned f = v == lk->first, l = v == lk->last_run;
                B->pstart[nd + 2]++, np++;
                nlegs += f || l ? f + l : 2; /* (as the legs below; a merged pass has no more) */
            }
        }
    B->nlegs = nlegs;
    pass *tp = B->nps ? rs__alloc_array(B->ctx, B->nps, sizeof *tp) : NULL;
    B->pids = rs__alloc_array(B->ctx, np ? np : 1, sizeof *B->pids);
    if ((B->nps && !tp) || !B->pids) {
        rs__free(B->ctx, tp);
        return RS_ERR_NOMEM;
    }
    for (size_t i = 0; i < nn; i++) B->pstart[i + 2] += B->pstart[i + 1];
    for (size_t v = 0; v < B->nv; v++)
        if (B->inhash[v]) {
            uint32_t nd = B->nodeof[v], na;
            if (v + 2 * CAHEAD < B->nv && (na = B->nodeof[v + 2 * CAHEAD]) != NONE) rs__prefetch(B->pstart + na + 1);
            if (v + CAHEAD < B->nv && (na = B->nodeof[v + CAHEAD]) != NONE) rs__prefetch(B->pids + B->pstart[na + 1]);
            if (nd != NONE) B->pids[B->pstart[nd + 1]++] = (uint32_t)v;
        }
    for (size_t i = 0; i < B->nps; i++) B->tstart[B->ps[i].node + 2]++;
    for (size_t i = 0; i < nn; i++) B->tstart[i + 2] += B->tstart[i + 1];
    for (size_t i = 0; i < B->nps; i++) tp[B->tstart[B->ps[i].node + 1]++] = B->ps[i];
    rs__free(B->ctx, B->ps);
    B->ps = tp;
    return RS_OK;
}

/* Node nd's passes in B->buf, sorted by pass_cmp (the passes through its
 * points in point order, then its T passes in the order found, as a stable
 * sort of all passes by node would give them to qsort), then merged:
 * points of one road in one run; a T beside a pass of its road, or found
 * twice, is dropped. Returns their count (RS_ERR_NOMEM: (size_t)-1). */
static size_t node_passes(build *B, uint32_t nd)
{
    size_t a = B->pstart[nd], b = B->pstart[nd + 1], ta = B->tstart[nd], tb = B->tstart[nd + 1];
    size_t k = b - a + tb - ta, bytes;
    if (k > B->cbuf) {
        size_t nc = k > 2 * B->cbuf ? k : 2 * B->cbuf;
        pass *nb = rs__mul_size(nc, sizeof *nb, &bytes) ? rs__realloc(B->ctx, B->buf, bytes) : NULL;
        if (!nb) return (size_t)-1;
        B->buf = nb;
        B->cbuf = nc;
    }
    pass *P = B->buf;
    for (size_t i = a; i < b; i++) point_pass(B, B->pids[i], nd, &P[i - a]);
    if (tb > ta) memcpy(P + (b - a), B->ps + ta, (tb - ta) * sizeof *P);
    if (k > 1) sort_passes(P, k);
    size_t np = 0;
    double tol = B->tol;
    for (size_t i = 0; i < k; i++) {
        pass *p = &P[i];
        if (np > 0) {
            pass *q = &P[np - 1];
            if (q->road == p->road && p->s - pass_s1(q) <= 2 * tol) {
                if (p->seg == NONE && q->seg == NONE) q->v1 = p->v1, q->x = p->x, q->last = p->last;
                else if (q->seg != NONE && p->seg == NONE) *q = *p; /* points win over a T */
                else if (q->seg != NONE && p->x < q->x) *q = *p; /* (two T: the nearer) */
                continue;
            }
        }
        P[np++] = *p;
    }
    /* A chain (chain_short_runs) that has a record end here goes on from
     * it: its other passes within twice the tolerance along it (its points
     * near the end, a T on its segments) are that one place (a road cut
     * where a side road ends, 0.046 m past one of its vertices: the side
     * road's end joined the vertex too, a pass of another record) */
    if (B->cid && np > 2) {
        size_t m = 0;
        for (size_t i = 0; i < np; i++) {
            const pass *p = &P[i];
            int drop = 0;
            if (p->seg != NONE || (!p->first && !p->last))
                for (size_t j = 0; j < np && !drop; j++) {
                    const pass *q = &P[j];
                    if (q->road == p->road || q->seg != NONE || !(q->first || q->last) ||
                        B->cid[q->road] != B->cid[p->road])
                        continue;
                    double at = chain_pos(B, q->road, q->first ? 0 : B->look[q->road].length);
                    drop = fabs(chain_pos(B, p->road, p->s) - at) <= 2 * tol;
                }
            if (!drop) P[m++] = *p;
        }
        np = m;
    }
    return np;
}

static int leg_cmp(const void *pa, const void *pb)
{
    const rs_network_leg *a = pa, *b = pb;
    if (a->angle != b->angle) return a->angle < b->angle ? -1 : 1;
    if (a->road != b->road) return a->road < b->road ? -1 : 1;
    if (a->kind != b->kind) return a->kind < b->kind ? -1 : 1;
    if (a->s != b->s) return a->s < b->s ? -1 : 1;
    return 0;
}

/* The legs of a node sorted by leg_cmp, as sort_passes. */
static void sort_legs(rs_network_leg *L, size_t k)
{
    if (k > 16) {
        qsort(L, k, sizeof *L, leg_cmp);
        return;
    }
    for (size_t i = 1; i < k; i++) {
        rs_network_leg t = L[i];
        size_t j = i;
        for (; j > 0 && leg_cmp(&L[j - 1], &t) > 0; j--) L[j] = L[j - 1];
        L[j] = t;
    }
}

/* A node's d legs: major = of the highest priority there. */
static void mark_major(rs_network_leg *L, uint32_t d)
{
    int best = -1;
    for (uint32_t k = 0; k < d; k++) best = L[k].priority > best ? L[k].priority : best;
    for (uint32_t k = 0; k < d; k++) L[k].major = L[k].priority == best;
}

/* The one pair of record-end legs among a node's d legs going on within
 * 30 degrees of straight (RS__STRAIGHT_COS), of two records: 1 with *a, *b
 * when there is exactly one such pair, else 0. */
int rs__straight_pair(const rs_network_leg *L, uint32_t d, const rs_network_leg **a, const rs_network_leg **b)
{
    int pairs = 0;
    for (uint32_t i = 0; i < d; i++)
        for (uint32_t j = i + 1; j < d; j++) {
            if (!rs__is_end_leg(&L[i]) || !rs__is_end_leg(&L[j]) || L[i].road == L[j].road) continue;
            double c = cos(L[i].angle) * cos(L[j].angle) + sin(L[i].angle) * sin(L[j].angle);
            if (!(c < -RS__STRAIGHT_COS)) continue;
            pairs++;
            *a = &L[i], *b = &L[j];
        }
    return pairs == 1;
}

/* Direction away from node position c along road r from point v, forward
 * (+1) or backward (-1): towards the first point beyond the tolerance. */
static double leg_angle(const build *B, const road_look *lk, const double *c, uint32_t v, int dir)
{
    size_t lo = lk->first, hi = lk->last, w = v;
    for (int hops = 0;;) {
        if (dir > 0 ? w >= hi : w <= lo) {
            /* a chain's record ends within the tolerance: on along the
             * chain (a record of a few millimetres seen from a node at a
             * vertex 0.046 m away pointed the wrong way) */
            uint32_t r = B->vroad[w], f = B->cpart ? B->cpart[2 * r + (dir > 0)] : NONE;
            if (f == NONE || hops++ == SHORT_CHAIN) break;
            const road_look *q = &B->look[f / 2];
            lo = q->first, hi = q->last;
            w = f & 1 ? hi : lo;
            dir = f & 1 ? -1 : 1;
            continue;
        }
        w = dir > 0 ? w + 1 : w - 1;
        if (!near2(B->xy + 2 * w, c, B->tol)) break;
    }
    double dx = B->xy[2 * w] - c[0], dy = B->xy[2 * w + 1] - c[1];
    if (dx == 0 && dy == 0) return 0;
    return atan2(dy, dx);
}

static int str_eq(const char *a, const char *b) { return a == b || (a && b && strcmp(a, b) == 0); }

/* Road r's look (the record exists: r < the road count). */
static void look_of(const rs_roads *roads, size_t r, road_look *L)
{
    rs_road_info in;
    memset(&in, 0, sizeof in);
    memset(L, 0, sizeof *L);
    rs_roads_get(roads, r, NULL, &L->width, NULL, NULL);
    if (rs_roads_get_info(roads, r, &in) != RS_OK) in.road_class = RS_CLASS_NONE, in.oneway = RS_ONEWAY_NONE;
    L->style = in.style;
    L->junction = rs_roads_get_attr(roads, r, "junction");
    const char *pv = rs_roads_get_attr(roads, r, "priority_road");
    L->lanes = in.lanes;
    L->road_class = (uint8_t)in.road_class;
    L->link = (uint8_t)in.link;
    L->oneway = (uint8_t)in.oneway;
    L->area = (uint8_t)in.area;
    L->two_way = rs__lanes_oneway(in.road_class, rs__road_oneway(roads, r, &in)) == 0;
    /* rs__road_priority from what is read above (it reads the record's
     * info and attributes again: a tenth of a small build's loading) */
    L->roundabout = L->junction && strcmp(L->junction, "roundabout") == 0;
    L->priority = (int16_t)(rs__class_rank(in.road_class) +
                            (pv && (strcmp(pv, "designated") == 0 || strcmp(pv, "yes_unposted") == 0) ? 10 : 0) +
                            (L->roundabout ? 20 : 0));
}

/* Roads a and b draw alike: one may continue the other in a stroke. */
static int draw_alike(const road_look *a, const road_look *b)
{
    return a->width == b->width && a->road_class == b->road_class && a->link == b->link && a->lanes == b->lanes &&
           a->oneway == b->oneway && a->area == b->area && str_eq(a->style, b->style) && str_eq(a->junction, b->junction);
}

static double wrap_angle(double a)
{
    while (a > RS__PI) a -= 2 * RS__PI;
    while (a < -RS__PI) a += 2 * RS__PI;
    return a;
}

/* Can road ends a and b (start or end legs, other roads) continue each
 * other: they draw alike and keep the direction of travel (an end meets a
 * start), or both roads are two-way. */
static int ends_fit(const build *B, const rs_network_leg *a, const rs_network_leg *b)
{
    if (a->road == b->road || !draw_alike(&B->look[a->road], &B->look[b->road])) return 0;
    return a->kind != b->kind || B->look[a->road].two_way;
}

/* Road end e's point (2 r: its first, 2 r + 1: its last). */
static const double *end_point(const build *B, uint32_t e)
{
    uint32_t r = e / 2;
    return B->xy + 2 * (size_t)(e & 1 ? B->voff[r + 1] - 1 : B->voff[r]);
}

/* The direction of road end e's own segment away from its end point (the
 * first point that differs); 0 when the record has none (all one point). */
static int end_dir(const build *B, uint32_t e, double *ang)
{
    uint32_t r = e / 2;
    size_t v0 = B->voff[r], v1 = B->voff[r + 1];
    const double *p = end_point(B, e);
    for (size_t k = 1; k < v1 - v0; k++) {
        const double *q = B->xy + 2 * (e & 1 ? v1 - 1 - k : v0 + k);
        if (q[0] != p[0] || q[1] != p[1]) {
            *ang = atan2(q[1] - p[1], q[0] - p[0]);
            return 1;
        }
    }
    return 0;
}

/* The direction of a road end's own segment away from the node (its
 * first or last point to the nearest point of another place; a road end
 * of one place: the leg's angle). */
static double end_angle(const build *B, const rs_network_leg *L)
{
    double a;
    return end_dir(B, rs__leg_end(L), &a) ? a : L->angle;
}

/* Two end legs at a junction that may continue each other: y leaves
 * within MAX_DEFLECTION of straight on from x, and they are a record's own
 * two ends or ends that fit (ends_fit). */
static int junction_pair(const build *B, const rs_network_leg *x, const rs_network_leg *y)
{
    return rs__is_end_leg(x) && rs__is_end_leg(y) && fabs(wrap_angle(y->angle - x->angle - RS__PI)) < MAX_DEFLECTION &&
           (x->road == y->road ? x->kind != y->kind : ends_fit(B, x, y));
}

/* Pair the road ends at a node (its d legs L, sorted) into strokes:
 * link[2 r + e] is the road end (2 q + f; e, f: 0 start, 1 end) that road
 * r's end e continues into. */
static void link_node(const build *B, const rs_network_leg *L, uint32_t d, uint32_t *link)
{
    if (d == 2) {
        /* two ends: one stroke when they continue each other (a ring's
         * own two ends at any angle; two records only with a small
         * deflection, as the issue's rule and the GPU export's have it:
         * a corner is where a line's pattern may start anew). The legs'
         * angles look past the tolerance, so a record cut within it of a
         * sharp vertex had the corner's deflection there: the end
         * segments' own directions count too (fuzz/split) */
        if (rs__is_end_leg(&L[0]) && rs__is_end_leg(&L[1]) &&
            (L[0].road == L[1].road
                 ? L[0].kind != L[1].kind
                 : ends_fit(B, &L[0], &L[1]) &&
                       (fabs(wrap_angle(L[1].angle - L[0].angle - RS__PI)) < MAX_DEFLECTION ||
                        fabs(wrap_angle(end_angle(B, &L[1]) - end_angle(B, &L[0]) - RS__PI)) < MAX_DEFLECTION))) {
            uint32_t ea = rs__leg_end(&L[0]), eb = rs__leg_end(&L[1]);
            link[ea] = eb;
            link[eb] = ea;
        }
        return;
    }
    /* a junction: pairs that deflect little, taken when neither end has
     * another; a record's own two ends too (a ring drawn as one closed way
     * with a side road at its first point: until 6 December 2026 it was no
     * ring there, its ends free, so the side road was no T and cut the
     * ring's far edge line, and its lines ended square at the seam) */
    for (uint32_t a = 0; a < d; a++) {
        if (!rs__is_end_leg(&L[a])) continue;
        uint32_t match = NONE, count = 0;
        for (uint32_t b = 0; b < d; b++)
            if (b != a && junction_pair(B, &L[a], &L[b])) match = b, count++;
        if (count != 1 || match < a) continue; /* (each pair once, from its first leg) */
        uint32_t back = 0;
        for (uint32_t c = 0; c < d; c++)
            if (c != match && junction_pair(B, &L[c], &L[match])) back++;
        if (back != 1) continue;
        uint32_t ea = rs__leg_end(&L[a]), eb = rs__leg_end(&L[match]);
        link[ea] = eb;
        link[eb] = ea;
    }
}

/* Short records (bridge_short) go into the strokes they lie on, so a
 * stroke's points are the unsplit road's, its vertices inside them too.
 * At a node whose one leg is a record's free end, or whose two legs are
 * record ends linked to each other, a chain of short records is walked
 * from the first end: each step takes the short record (drawing alike,
 * keeping the direction of travel unless two-way; the lowest of several)
 * with an end exactly at the last one's far end, and enters it there. At
 * a free end the chain goes as far as it runs; between two ends only a
 * chain that arrives exactly at the second end's point is put between
 * them. Without it, the lines stopped up to 0.1 m short of a road's end,
 * and a bend inside short records was cut off (a 14.75 m road's edge line
 * moved by 0.1 m: docs/network.md "Degenerate records"; fuzz/split). At
 * most SHORT_CHAIN records a chain (each step scans the node's short
 * records). short_at: pairs (record, node). */

static int cmp_short(const void *pa, const void *pb)
{
    const uint32_t *a = pa, *b = pb;
    if (a[1] != b[1]) return a[1] < b[1] ? -1 : 1;
    return (a[0] > b[0]) - (a[0] < b[0]);
}

/* The chain from road end `from` (of record q) over the short records
 * short_at[a..b) into chain[] (the ends entered); its length. */
static size_t short_chain(const build *B, const rs_network *N, const uint32_t *short_at, size_t a, size_t b,
                          uint32_t q, uint32_t from, uint32_t *chain)
{
    size_t m = 0;
    uint32_t at = from;
    while (m < SHORT_CHAIN) {
        const double *p = end_point(B, at);
        int leaving_end = at & 1;
        uint32_t best = NONE;
        for (size_t k = a; k < b && best == NONE; k++) {
            uint32_t r = short_at[2 * k];
            if (N->link[2 * r] != NONE || N->link[2 * r + 1] != NONE || !draw_alike(&B->look[q], &B->look[r]))
                continue;
            int used = 0;
            for (size_t j = 0; j < m; j++) used |= chain[j] / 2 == r;
            if (used) continue;
            for (uint32_t f = 0; f < 2 && best == NONE; f++) {
                const double *e = end_point(B, 2 * r + f);
                if (e[0] != p[0] || e[1] != p[1]) continue;
                if (leaving_end == (int)f && !B->look[q].two_way) continue; /* an end meets a start */
                best = 2 * r + f;
            }
        }
        if (best == NONE) break;
        chain[m++] = best;
        at = best ^ 1; /* leaves by its other end */
    }
    return m;
}

/* Road ends a and b, meeting at one point, go on straight enough there
 * (their own segments; one without a direction goes on). */
static int joint_straight(const build *B, uint32_t a, uint32_t b)
{
    double da, db;
    if (!end_dir(B, a, &da) || !end_dir(B, b, &db)) return 1;
    return fabs(wrap_angle(db - da - RS__PI)) < MAX_DEFLECTION;
}

static void link_short_ends(const build *B, rs_network *N, uint32_t *short_at, size_t nshort)
{
    if (nshort > 1) qsort(short_at, nshort, 2 * sizeof *short_at, cmp_short);
    uint32_t chain[SHORT_CHAIN];
    for (size_t a = 0, b; a < nshort; a = b) {
        uint32_t nd = short_at[2 * a + 1];
        for (b = a + 1; b < nshort && short_at[2 * b + 1] == nd; b++) {}
        uint32_t d = N->leg_start[nd + 1] - N->leg_start[nd];
        const rs_network_leg *L = &N->leg[N->leg_start[nd]];
        if (d < 1 || d > 2 || !rs__is_end_leg(&L[0]) || (d == 2 && !rs__is_end_leg(&L[1]))) continue;
        uint32_t e0 = rs__leg_end(&L[0]), e1 = NONE;
        /* two ends link_node left apart (the legs' angles see the corner a
         * short record holds): they go on through the chain when every
         * joint of it is straight, as the road unsplit has no corner at its
         * own vertex (a 39-degree bend inside a record of 0.02 m: fuzz/split) */
        int through = 0;
        if (d == 2) {
            e1 = rs__leg_end(&L[1]);
            if (N->link[e0] != e1) {
                if (N->link[e0] != NONE || N->link[e1] != NONE || !ends_fit(B, &L[0], &L[1])) continue;
                through = 1;
            }
        } else if (N->link[e0] != NONE)
            continue;
        size_t m = short_chain(B, N, short_at, a, b, L[0].road, e0, chain);
        if (d == 2) {
            /* it must arrive at e1, which it then meets as e1's road meets it */
            while (m > 0) {
                uint32_t out = chain[m - 1] ^ 1;
                const double *p = end_point(B, out), *t = end_point(B, e1);
                if (p[0] == t[0] && p[1] == t[1] && ((out & 1) != (e1 & 1) || B->look[L[0].road].two_way)) break;
                m--;
            }
            if (m == 0) continue;
            int straight = 1;
            for (size_t k = 0; through && k <= m && straight; k++)
                straight = joint_straight(B, k ? chain[k - 1] ^ 1 : e0, k < m ? chain[k] : e1);
            if (!straight) continue;
        }
        uint32_t at = e0;
        for (size_t k = 0; k < m; k++) {
            N->link[at] = chain[k];
            N->link[chain[k]] = at;
            at = chain[k] ^ 1;
        }
        if (d == 2) {
            N->link[at] = e1;
            N->link[e1] = at;
        }
    }
}

/* Walk a stroke from road r entered at its end e (0: start, 1: end): the
 * roads in order, each with its direction; returns the last road and the
 * end it leaves by (*out_end). Stops at a free end or back at `stop`. */
static uint32_t walk_stroke(const uint32_t *link, uint32_t r, uint32_t e, uint32_t stop, uint32_t *out_end)
{
    for (;;) {
        uint32_t x = 2 * r + (1 - e), nx = link[x];
        if (nx == NONE || nx / 2 == stop) {
            *out_end = 1 - e;
            return r;
        }
        r = nx / 2;
        e = nx % 2;
    }
}

/* Number the strokes by their first record and lay out their arc lengths.
 * A stroke runs from the terminal record whose free end is its start (the
 * direction of travel), else from the lower of its two terminal records;
 * a ring from its lowest record, along it. */
static void number_strokes(rs_network *N, uint32_t *link, uint8_t *seen)
{
    size_t n = N->nroads, k = 0, at = 0;
    memset(seen, 0, n);
    for (int rings = 0; rings < 2; rings++)
        for (size_t r0 = 0; r0 < n; r0++) {
            if (seen[r0]) continue;
            uint32_t head = (uint32_t)r0, e_in = 0;
            if (!rings) {
                /* a path: r0 has a free end (the other terminal is higher) */
                int free0 = link[2 * r0] == NONE, free1 = link[2 * r0 + 1] == NONE;
                if (!free0 && !free1) continue; /* on a ring: the second round */
                uint32_t tend = 0, t = free0 ? walk_stroke(link, (uint32_t)r0, 0, NONE, &tend)
                                            : walk_stroke(link, (uint32_t)r0, 1, NONE, &tend);
                /* r0 enters by its free end; the other terminal leaves by tend */
                e_in = free0 ? 0 : 1;
                if (e_in == 1 && tend == 0) head = t, e_in = 0; /* the other terminal starts the travel */
            } else {
                /* a ring: open it before r0 */
                uint32_t x = link[2 * r0];
                link[x] = NONE;
                link[2 * r0] = NONE;
            }
            N->stroke_start[k] = (uint32_t)at;
            N->closed[k] = (uint8_t)rings;
            double s = 0;
            uint32_t r = head, e = e_in, prev = NONE;
            for (;;) {
                seen[r] = 1;
                N->stroke_of[r] = (uint32_t)k;
                N->rev[r] = (uint8_t)e;
                N->s_off[r] = e ? s + N->length[r] : s;
                s += N->length[r];
                N->prev[r] = prev;
                N->next[r] = NONE;
                if (prev != NONE) N->next[prev] = r;
                N->stroke_roads[at++] = r;
                uint32_t nx = link[2 * r + (1 - e)];
                if (nx == NONE) break;
                prev = r;
                r = nx / 2;
                e = nx % 2;
            }
            for (size_t q = N->stroke_start[k]; q < at; q++) N->s_len[N->stroke_roads[q]] = rings ? INFINITY : s;
            k++;
        }
    N->stroke_start[k] = (uint32_t)at;
    N->nstrokes = k;
}

/* ---- road ends inside another road's surface ---- */

/* A free end (its node has no other leg) inside another street's surface:
 * within its half width (plus the tolerance) of its centreline, further
 * than the tolerance (between its edge and its centre line, or past the
 * centre line short of the far edge). Hand-drawn roads end at the kerb or
 * inside a lane as often as on the centre line; as free ends their round
 * caps bulged past the far edge, their surfaces cut the through road's
 * centre line and their give-way lines stood up to a half width early or late.
 * Such an end meets the street in a T at the nearest point of its
 * centreline (docs/network.md "Ends inside a surface"): its node gets the
 * through record's two legs there, as a T within the tolerance has, and
 * keeps the end point as its position. Found after the strokes, so a
 * street's own records never hold its end (whole or split anywhere, the
 * same), and a footway, path or cycleway holds no car road's end. */
typedef struct surf_end {
    uint32_t node, road, stroke;
    int non_car;
    int level; /* rs__road_level of its road (INT_MIN: not read yet): it meets a street of its level only */
    double x, y;   /* the end point */
    uint32_t q, k; /* the nearest: record q's segment k (NONE: none) */
    double u, d;   /* the point's parameter on it (0 .. 1) and squared distance */
} surf_end;

/* What surface_tees reads of a record, copied from its look before the
 * looks are freed (they are most of the build's memory that the stroke
 * arrays reuse: kept whole, a 10^5-record lattice's builds faulted 9,000
 * more pages each): its width, rs__road_priority, rs__road_non_car and
 * junction=roundabout. Read here, not from the road set at random records
 * (10^5 cache misses). */
typedef struct surf_rd {
    double width;
    int16_t priority;
    uint8_t non_car, roundabout;
} surf_rd;

static size_t surf_cell(double v, double v0, double ic, size_t n)
{
    double t = (v - v0) * ic; /* (ic = 1 / the cell: any monotone map finds the same candidates) */
    if (!(t >= 0)) return 0;
    if (t >= (double)(n - 1)) return n - 1;
    return (size_t)t;
}

/* surf_test's first test, inline where the segments walk the ends' cells
 * (most ends in a cell lie beyond the reach: a call with fifteen
 * arguments each was most of the walk) */
static inline int surf_line_near(const double *xy, const double *pa, double dx, double dy, double dd, double reach2)
{
    double cr = (xy[0] - pa[0]) * dy - (xy[1] - pa[1]) * dx;
    return !(cr * cr > reach2 * dd * (1 + 1e-9));
}

/* Candidate end f (at xy, a copy of f->x, f->y in the cells' order)
 * against segment k (points pa, pb = pa + 2) of record q of stroke sq
 * (its points qxy, qnp of them): its nearest point first, from the copy
 * (most candidates lie beyond the reach: f is read only within it; at
 * 10^5 roads the ends are megabytes, read out of order) */
static void surf_test(const rs_roads *roads, const rs_network *N, surf_end *fe, const uint32_t *id, const double *xy,
                      uint32_t q, uint32_t sq, const double *qxy, size_t qnp, uint32_t k, const double *pa, double dx,
                      double dy, double dd, double reach2, int *q_non_car, int *q_level)
{
    /* farther than the reach from the segment's line, by a margin far
     * above the roundings: farther from the segment too (most ends
     * tested; no division) */
    double cr = (xy[0] - pa[0]) * dy - (xy[1] - pa[1]) * dx;
    if (cr * cr > reach2 * dd * (1 + 1e-9)) return;
    double u = ((xy[0] - pa[0]) * dx + (xy[1] - pa[1]) * dy) / dd;
    u = u > 0 ? (u < 1 ? u : 1) : 0;
    double ex = xy[0] - (pa[0] + u * dx), ey = xy[1] - (pa[1] + u * dy), d2 = ex * ex + ey * ey;
    if (!(d2 <= reach2)) return;
    surf_end *f = &fe[*id];
    /* (of equals the lowest record and segment, whatever the walk's order) */
    if (!(d2 < f->d || (d2 == f->d && (q < f->q || (q == f->q && k < f->k))))) return;
    if (f->stroke == sq) return;
    /* (a street ending under a bridge is not at a T with it) */
    if (*q_level == INT_MIN) *q_level = rs__road_level(roads, q);
    if (f->level == INT_MIN) f->level = rs__road_level(roads, f->road);
    if (*q_level != f->level) return;
    if (!f->non_car) { /* (read only here: a record's info is tens of ns of attribute lookups) */
        if (*q_non_car < 0) *q_non_car = rs__road_non_car(roads, q);
        if (*q_non_car) return;
    }
    /* (the record's own end, where its street does not go on: the end
     * lies beyond the street, two ends near each other, no T; a ring's
     * seam is no end) */
    const double *first = qxy, *last = qxy + 2 * (qnp - 1), *pb = pa + 2;
    int ring = N->closed[sq];
    if (u == 0 && pa[0] == first[0] && pa[1] == first[1] && N->link[2 * q] == NONE && !ring) return;
    if (u == 1 && pb[0] == last[0] && pb[1] == last[1] && N->link[2 * q + 1] == NONE && !ring) return;
    f->q = q, f->k = k, f->u = u, f->d = d2;
}

/* Direction of the segment k of a record (its points xy, np of them), or
 * of its nearest non-empty one towards `step` (+1, -1) when that side is
 * asked for and exists. */
static double surf_angle(const double *xy, size_t np, uint32_t k, int step, int reverse)
{
    size_t nseg = np - 1;
    for (size_t j = k;;) {
        const double *pa = xy + 2 * j, *pb = pa + 2;
        double dx = pb[0] - pa[0], dy = pb[1] - pa[1];
        if (dx != 0 || dy != 0) return reverse ? atan2(-dy, -dx) : atan2(dy, dx);
        if (step > 0 ? j + 1 >= nseg : j == 0) break;
        j = step > 0 ? j + 1 : j - 1;
    }
    return 0;
}

/* The two legs of street q (its points qxy, qnp of them; the arc lengths
 * s0, s1 at the ends of its segment k; rs__road_priority of it) at end f,
 * which lies inside it. */
static void surf_legs(const surf_end *f, const double *qxy, size_t qnp, double s0, double s1, int priority,
                      rs_network_leg T[2])
{
    memset(T, 0, 2 * sizeof *T);
    T[0].road = f->q;
    T[0].segment = f->k;
    T[0].s = s0 + f->u * (s1 - s0);
    T[0].priority = priority;
    T[1] = T[0];
    T[0].kind = RS_LEG_FORWARD;
    T[0].angle = surf_angle(qxy, qnp, f->u == 1 && f->k + 1 < qnp - 1 ? f->k + 1 : f->k, 1, 0);
    T[1].kind = RS_LEG_BACKWARD;
    T[1].angle = surf_angle(qxy, qnp, f->u == 0 && f->k > 0 ? f->k - 1 : f->k, -1, 1);
}

/* A node whose d legs L now hold a street's two (roundabout: its
 * junction=roundabout): sorted, its major legs, degree and kind, a
 * roundabout's control. */
static void surf_node(int roundabout, rs_network_node *node, rs_network_leg *L, uint32_t d)
{
    sort_legs(L, d);
    mark_major(L, d);
    node->degree = d;
    node->kind = RS_NODE_JUNCTION;
    if (roundabout) node->control |= RS_NODE_ROUNDABOUT;
}

/* The reach of record q (of width w) for surface_tees: its half width plus
 * the tolerance; 0 for a record with no surface to hold an end (no longer
 * than two tolerances, no wider, or of no finite width). */
static double surf_reach(const rs_network *N, size_t q, double w, double tol)
{
    double hw = 0.5 * w;
    if (!(N->length[q] > 2 * tol) || !(hw > tol) || !(hw <= 1e300)) return 0;
    return hw + tol;
}

/* surf_reach of record q of `roads` (an update: no build's looks) */
static double road_reach(const rs_roads *roads, const rs_network *N, size_t q, double tol)
{
    double w = 0;
    rs_roads_get(roads, q, NULL, &w, NULL, NULL);
    return surf_reach(N, q, w, tol);
}

static rs_result surface_tees(build *B, rs_network *N)
{
    rs_ctx *ctx = B->ctx;
    const double tol = B->tol;
    size_t nf = 0;
    if (rs__poll(ctx)) return RS_ERR_CANCELLED;
    for (size_t nd = 0; nd < N->nnodes; nd++) {
        const rs_network_leg *L = N->leg + N->leg_start[nd];
        nf += N->leg_start[nd + 1] - N->leg_start[nd] == 1 && rs__is_end_leg(L) && N->length[L->road] > 2 * tol;
    }
    if (!nf) return RS_OK;
    surf_end *fe = rs__alloc_array(ctx, nf, sizeof *fe);
    if (!fe) return RS_ERR_NOMEM;
    double bx0 = INFINITY, by0 = INFINITY, bx1 = -INFINITY, by1 = -INFINITY;
    size_t m = 0;
    for (size_t nd = 0; nd < N->nnodes; nd++) {
        const rs_network_leg *L = N->leg + N->leg_start[nd];
        if (N->leg_start[nd + 1] - N->leg_start[nd] != 1 || !rs__is_end_leg(L) || !(N->length[L->road] > 2 * tol))
            continue;
        const double *p = B->xy + 2 * (L->kind == RS_LEG_START ? B->voff[L->road] : B->voff[L->road + 1] - 1);
        if (!isfinite(p[0]) || !isfinite(p[1])) continue;
        surf_end *f = &fe[m++];
        f->node = (uint32_t)nd, f->road = L->road, f->stroke = N->stroke_of[L->road];
        f->non_car = B->srd[L->road].non_car;
        f->level = B->level[L->road];
        f->x = p[0], f->y = p[1], f->q = f->k = NONE, f->u = 0, f->d = INFINITY;
        bx0 = fmin(bx0, p[0]), by0 = fmin(by0, p[1]), bx1 = fmax(bx1, p[0]), by1 = fmax(by1, p[1]);
    }
    /* the records' reaches, read once (the mean below and the walk) */
    double *reach = rs__alloc_array(ctx, B->nroads ? B->nroads : 1, sizeof *reach);
    if (!reach) {
        rs__free(ctx, fe);
        return RS_ERR_NOMEM;
    }
    for (size_t q = 0; q < B->nroads; q++) reach[q] = surf_reach(N, q, B->srd[q].width, tol);
    /* the ends in a grid of about one a cell (at most 4 a cell more cells), counting sorted */
    size_t nx = 1, ny = 1;
    double wx = bx1 - bx0, wy = by1 - by0, c = sqrt(wx * wy / (4.0 * (double)(m ? m : 1)));
    if (!(c > 0)) c = fmax(wx, wy) / (double)(m ? m : 1);
    if (!(c > 0) || !isfinite(c) || !isfinite(wx) || !isfinite(wy)) c = INFINITY;
    if (isfinite(c)) {
        /* cells no smaller than the records' mean reach: dense ends would
         * otherwise make a segment walk more rows and cells the more ends
         * there are (10^5 city roads: 7 rows a segment). The tests made,
         * and so the result, do not depend on the cells. */
        double rsum = 0, cap = 16 * c;
        size_t rn = 0;
        for (size_t q = 0; q < B->nroads; q++) {
            double rq = reach[q];
            if (!(rq > 0)) continue;
            rsum += rq < cap ? rq : cap;
            rn++;
        }
        if (rn && rsum / (double)rn > c) c = rsum / (double)rn;
    }
    while (isfinite(c)) {
        double fx = floor(wx / c) + 1, fy = floor(wy / c) + 1;
        if (fx * fy <= 4.0 * 4 * (double)m + 4) {
            nx = (size_t)fx, ny = (size_t)fy;
            break;
        }
        c *= 2;
    }
    uint32_t *start = rs__calloc(ctx, nx * ny + 2, sizeof *start), *ids = rs__alloc_array(ctx, m ? m : 1, sizeof *ids);
    double *cxy = rs__alloc_array(ctx, m ? m : 1, 2 * sizeof *cxy); /* the ends' points in ids' order */
    rs_result res = start && ids && cxy ? RS_OK : RS_ERR_NOMEM;
    const double ic = 1 / c;
    for (size_t i = 0; i < m && !res; i++) start[surf_cell(fe[i].y, by0, ic, ny) * nx + surf_cell(fe[i].x, bx0, ic, nx) + 2]++;
    for (size_t i = 0; i < nx * ny && !res; i++) start[i + 2] += start[i + 1];
    for (size_t i = 0; i < m && !res; i++)
        ids[start[surf_cell(fe[i].y, by0, ic, ny) * nx + surf_cell(fe[i].x, bx0, ic, nx) + 1]++] = (uint32_t)i;
    for (size_t i = 0; i < m && !res; i++) cxy[2 * i] = fe[ids[i]].x, cxy[2 * i + 1] = fe[ids[i]].y;
    /* every segment of every record with a surface, over the cells its
     * capsule reaches, row by row */
    for (size_t q = 0; q < B->nroads && !res && m; q++) {
        if ((q & 4095) == 0 && rs__poll(ctx)) {
            res = RS_ERR_CANCELLED;
            break;
        }
        double rq = reach[q];
        if (!(rq > 0)) continue;
        int qnc = B->srd[q].non_car, qlv = B->level[q];
        uint32_t sq = N->stroke_of[q];
        double reach2 = rq * rq; /* (the cells within the reach, not the half width alone) */
        size_t qnp = B->voff[q + 1] - B->voff[q], nseg = qnp - 1;
        const double *qxy = B->xy + 2 * B->voff[q];
        for (size_t k = 0; k < nseg; k++) {
            const double *pa = qxy + 2 * k, *pb = pa + 2;
            /* (ternaries, not fmin / fmax: library calls, most of a
             * segment's cost; a NaN fails the box test) */
            double xmin = pa[0] < pb[0] ? pa[0] : pb[0], xmax = pa[0] < pb[0] ? pb[0] : pa[0];
            double ymin = pa[1] < pb[1] ? pa[1] : pb[1], ymax = pa[1] < pb[1] ? pb[1] : pa[1];
            xmin -= rq, xmax += rq, ymin -= rq, ymax += rq;
            if (!(xmax >= bx0 && xmin <= bx1 && ymax >= by0 && ymin <= by1)) continue;
            size_t r0 = surf_cell(ymin, by0, ic, ny), r1 = surf_cell(ymax, by0, ic, ny);
            size_t b0 = surf_cell(xmin, bx0, ic, nx), b1 = surf_cell(xmax, bx0, ic, nx);
            double dx = pb[0] - pa[0], dy = pb[1] - pa[1], dd = dx * dx + dy * dy;
            if (!(dd > 0) || !(dd <= DBL_MAX)) continue;
            /* a box of at most 9 cells: all of it (most segments at 10^5 city
             * roads; clipping each row cost more than the ends it skips) */
            if ((r1 - r0 + 1) * (b1 - b0 + 1) <= 9) {
                for (size_t cy = r0; cy <= r1; cy++)
                    for (uint32_t i = start[cy * nx + b0], ie = start[cy * nx + b1 + 1]; i < ie; i++)
                        if (surf_line_near(cxy + 2 * i, pa, dx, dy, dd, reach2))
                            surf_test(B->roads, N, fe, ids + i, cxy + 2 * i, (uint32_t)q, sq, qxy, qnp, (uint32_t)k, pa, dx,
                                      dy, dd, reach2, &qnc, &qlv);
                continue;
            }
            for (size_t cy = r0; cy <= r1; cy++) {
                /* the segment's part within the reach of the row (the outer rows reach on) */
                double lo = cy == 0 ? -INFINITY : by0 + (double)cy * c, hi = cy + 1 == ny ? INFINITY : by0 + (double)(cy + 1) * c;
                double t0 = 0, t1 = 1;
                if (dy != 0) {
                    t0 = (rs__fmax(lo, ymin + rq) - rq - pa[1]) / dy, t1 = (rs__fmin(hi, ymax - rq) + rq - pa[1]) / dy;
                    if (t0 > t1) { double t = t0; t0 = t1; t1 = t; }
                    t0 = rs__fmax(t0, 0), t1 = rs__fmin(t1, 1);
                    if (t0 > t1) continue;
                }
                double xa = pa[0] + t0 * dx, xb = pa[0] + t1 * dx;
                size_t c0 = surf_cell(rs__fmin(xa, xb) - rq, bx0, ic, nx), c1 = surf_cell(rs__fmax(xa, xb) + rq, bx0, ic, nx);
                for (uint32_t i = start[cy * nx + c0], ie = start[cy * nx + c1 + 1]; i < ie; i++)
                    if (surf_line_near(cxy + 2 * i, pa, dx, dy, dd, reach2))
                        surf_test(B->roads, N, fe, ids + i, cxy + 2 * i, (uint32_t)q, sq, qxy, qnp, (uint32_t)k, pa, dx, dy,
                                  dd, reach2, &qnc, &qlv);
            }
        }
    }
    size_t add = 0;
    for (size_t i = 0; i < m; i++) add += fe[i].q != NONE;
    /* the nodes' legs moved up in place, from the last node down, the two
     * through legs added at theirs (fe is in node order): a second leg
     * array was megabytes of fresh pages at 10^5 roads */
    if (!res && add) {
        size_t bytes;
        rs_network_leg *leg = NULL;
        if (!rs__mul_size(N->nlegs + 2 * add, sizeof *leg, &bytes) || !(leg = rs__realloc(ctx, N->leg, bytes)))
            res = RS_ERR_NOMEM;
        else
            N->leg = leg;
        size_t nl = N->nlegs + 2 * add, j = m;
        uint32_t b = (uint32_t)N->nlegs; /* (the old end of node nd's legs) */
        if (!res) N->leg_start[N->nnodes] = (uint32_t)nl;
        for (size_t nd = N->nnodes; nd-- > 0 && !res;) {
            if ((nd & 4095) == 0 && rs__poll(ctx)) { /* (the network is dropped: leg_start half made is no matter) */
                res = RS_ERR_CANCELLED;
                break;
            }
            uint32_t a = N->leg_start[nd];
            while (j > 0 && fe[j - 1].node > nd) j--;
            const surf_end *f = j > 0 && fe[j - 1].node == nd && fe[j - 1].q != NONE ? &fe[j - 1] : NULL;
            if (f) {
                nl -= 2;
                size_t pa = B->voff[f->q] + f->k;
                surf_legs(f, B->xy + 2 * B->voff[f->q], B->voff[f->q + 1] - B->voff[f->q], B->s[pa], B->s[pa + 1],
                          B->srd[f->q].priority, leg + nl);
            }
            nl -= b - a;
            if (nl != a) memmove(leg + nl, leg + a, (b - a) * sizeof *leg);
            N->leg_start[nd] = (uint32_t)nl;
            if (f) {
                surf_node(B->srd[f->q].roundabout, &N->node[nd], leg + nl, (uint32_t)(b - a + 2));
                N->node_surf[nd] = 1;
            }
            b = a;
        }
        if (!res) N->nlegs += 2 * add;
    }
    rs__free(ctx, reach);
    rs__free(ctx, start);
    rs__free(ctx, ids);
    rs__free(ctx, cxy);
    rs__free(ctx, fe);
    return res;
}

static void build_free(build *B)
{
    rs_ctx *ctx = B->ctx;
    rs__free(ctx, B->voff);
    rs__free(ctx, B->vroad);
    rs__free(ctx, B->xy_own);
    rs__free(ctx, B->s);
    rs__free(ctx, B->rep);
    rs__free(ctx, B->parent);
    rs__free(ctx, B->live);
    rs__free(ctx, B->look);
    rs__free(ctx, B->srd);
    rs__free(ctx, B->level);
    rs__free(ctx, B->inhash);
    rs__free(ctx, B->nodeof);
    rs__free(ctx, B->ps);
    rs__free(ctx, B->pstart);
    rs__free(ctx, B->pids);
    rs__free(ctx, B->tstart);
    rs__free(ctx, B->buf);
    rs__free(ctx, B->ctl);
    rs__free(ctx, B->short_at);
    rs__free(ctx, B->cid);
    rs__free(ctx, B->cs0);
    rs__free(ctx, B->ctot);
    rs__free(ctx, B->crev);
    rs__free(ctx, B->jend);
    rs__free(ctx, B->cpart);
}

void rs_network_free(rs_ctx *ctx, rs_network *net)
{
    if (!net) return;
    rs__free(ctx, net->node);
    rs__free(ctx, net->leg_start);
    rs__free(ctx, net->leg);
    rs__free(ctx, net->stroke_of);
    rs__free(ctx, net->s_off);
    rs__free(ctx, net->length);
    rs__free(ctx, net->s_len);
    rs__free(ctx, net->prev);
    rs__free(ctx, net->next);
    rs__free(ctx, net->stroke_start);
    rs__free(ctx, net->stroke_roads);
    rs__free(ctx, net->closed);
    rs__free(ctx, net->rev);
    rs__free(ctx, net->link);
    rs__free(ctx, net->s_base);
    rs__free(ctx, net->node_key);
    rs__free(ctx, net->node_rad);
    rs__free(ctx, net->node_surf);
    rs__free(ctx, net);
}

/* The per-record stroke arrays of N for m records (at least 1) and
 * `starts` stroke starts: 1, or 0 when one could not be allocated (those
 * that were are N's: rs_network_free). */
static int stroke_arrays(rs_ctx *ctx, rs_network *N, size_t m, size_t starts)
{
    N->stroke_of = rs__alloc_array(ctx, m, sizeof *N->stroke_of);
    N->s_off = rs__alloc_array(ctx, m, sizeof *N->s_off);
    N->length = rs__alloc_array(ctx, m, sizeof *N->length);
    N->s_len = rs__alloc_array(ctx, m, sizeof *N->s_len);
    N->prev = rs__alloc_array(ctx, m, sizeof *N->prev);
    N->next = rs__alloc_array(ctx, m, sizeof *N->next);
    N->stroke_start = rs__alloc_array(ctx, starts, sizeof *N->stroke_start);
    N->stroke_roads = rs__alloc_array(ctx, m, sizeof *N->stroke_roads);
    N->closed = rs__calloc(ctx, m, 1);
    N->rev = rs__calloc(ctx, m, 1);
    return N->stroke_of && N->s_off && N->length && N->s_len && N->prev && N->next && N->stroke_start && N->stroke_roads &&
           N->closed && N->rev;
}

/* The memory N holds. */
static size_t bytes_of(const rs_network *N)
{
    return sizeof *N + N->nnodes * sizeof *N->node + (N->nnodes + 1) * sizeof *N->leg_start +
           N->nlegs * sizeof *N->leg +
           N->nroads * (sizeof *N->stroke_of + sizeof *N->s_off + sizeof *N->length + sizeof *N->s_len + sizeof *N->prev +
                        sizeof *N->next + sizeof *N->stroke_start + sizeof *N->stroke_roads + 2 + 2 * sizeof *N->link) +
           (N->node_key ? N->nnodes * (sizeof *N->node_key + sizeof *N->node_rad + sizeof *N->node_surf) : 0);
}

/* ---- the strokes' arc lengths in a map's frame ---- */

/* Stroke k's records' bases into out. */
static void stroke_base(const rs_network *N, const rs_roads *roads, const rs__local_frame *F, size_t k, double *out)
{
    double acc = 0;
    for (uint32_t e = N->stroke_start[k]; e < N->stroke_start[k + 1]; e++) {
        uint32_t r = N->stroke_roads[e];
        const double *xy = NULL;
        size_t np = 0;
        rs_roads_get(roads, r, NULL, NULL, &xy, &np);
        out[r] = acc;
        /* (as rs__road_local_walk sums a record: equal points once) */
        double len = 0, qx = 0, qy = 0;
        for (size_t i = 0; i < np; i++) {
            double px, py;
            rs__local_point(F, xy, i, &px, &py);
            if (i > 0 && !(px == qx && py == qy)) len = rs__arc_add(len, rs__arc_len(qx, qy, px, py));
            qx = px, qy = py;
        }
        acc = rs__arc_add(acc, len);
    }
}

rs_result rs__stroke_bases(rs_ctx *ctx, const rs_network *N, const rs_roads *roads, double origin_x, double origin_y,
                           double cell_size, const uint32_t *ids, size_t n, double *out)
{
    rs__local_frame F = rs__local_frame_of(origin_x, origin_y, cell_size);
    if (!ids) {
        for (size_t k = 0; k < N->nstrokes; k++) {
            if ((k & 2047) == 0 && rs__poll(ctx)) return RS_ERR_CANCELLED; /* (10^5 roads: ~25 ms in all) */
            stroke_base(N, roads, &F, k, out);
        }
        return RS_OK;
    }
    /* (the strokes of ids once each: out is NaN where not made yet) */
    for (size_t r = 0; r < N->nroads; r++) out[r] = NAN;
    for (size_t i = 0; i < n; i++) {
        if ((i & 2047) == 0 && rs__poll(ctx)) return RS_ERR_CANCELLED;
        if (ids[i] < N->nroads && out[ids[i]] != out[ids[i]]) stroke_base(N, roads, &F, N->stroke_of[ids[i]], out);
    }
    return RS_OK;
}

/* ---- a part of the network ---- */

rs_result rs__network_subset(rs_ctx *ctx, const rs_network *N, const double *bases, const uint32_t *ids, size_t n,
                             rs_network **out)
{
    *out = NULL;
    rs_network *S = rs__calloc(ctx, 1, sizeof *S);
    uint32_t *map = rs__alloc_array(ctx, N->nroads ? N->nroads : 1, sizeof *map);
    size_t m = n ? n : 1;
    rs_result res = RS_ERR_NOMEM;
    if (!S || !map) goto fail;
    for (size_t r = 0; r < N->nroads; r++) map[r] = NONE;
    for (size_t i = 0; i < n; i++) {
        if (ids[i] >= N->nroads || (i && ids[i] <= ids[i - 1])) {
            res = RS_ERR_INVALID_ARG;
            goto fail;
        }
        map[ids[i]] = (uint32_t)i;
    }
    S->nroads = n;
    S->tol = N->tol;
    /* nodes with a kept leg, in their order; their kept legs in theirs (in
     * one pass over the whole network's legs: the arrays grow) */
    size_t nn = 0, cnode = 0, cstart = 0, cleg = 0;
    S->link = rs__alloc_array(ctx, 2 * m, sizeof *S->link);
    if (!S->link || !stroke_arrays(ctx, S, m, m + 1)) goto fail;
    size_t at = 0;
    for (size_t d = 0; d < N->nnodes; d++) {
        size_t a = at;
        for (uint32_t l = N->leg_start[d]; l < N->leg_start[d + 1]; l++) {
            uint32_t rd = map[N->leg[l].road];
            if (rd == NONE) continue;
            void *arr = S->leg;
            if ((res = rs__grow(ctx, &arr, at, &cleg, sizeof *S->leg, 64, UINT32_MAX)) != RS_OK) goto fail;
            S->leg = arr;
            S->leg[at] = N->leg[l];
            S->leg[at++].road = rd;
        }
        if (at == a) continue;
        void *an = S->node, *as = S->leg_start;
        if ((res = rs__grow(ctx, &an, nn, &cnode, sizeof *S->node, 32, UINT32_MAX)) != RS_OK) goto fail;
        S->node = an;
        if ((res = rs__grow(ctx, &as, nn + 1, &cstart, sizeof *S->leg_start, 33, UINT32_MAX)) != RS_OK) goto fail;
        S->leg_start = as;
        S->leg_start[nn] = (uint32_t)a;
        S->node[nn] = N->node[d];
        uint32_t deg = (uint32_t)(at - a);
        if (deg != N->leg_start[d + 1] - N->leg_start[d]) {
            /* a node whose other roads are not kept: what the network of the kept roads says there */
            S->node[nn].degree = deg;
            S->node[nn].kind = deg <= 1 ? RS_NODE_END : deg == 2 ? RS_NODE_CONTINUATION : RS_NODE_JUNCTION;
            mark_major(S->leg + a, deg);
        }
        nn++;
    }
    {
        void *as = S->leg_start;
        if ((res = rs__grow(ctx, &as, nn, &cstart, sizeof *S->leg_start, 1, UINT32_MAX)) != RS_OK) goto fail;
        S->leg_start = as;
    }
    res = RS_ERR_NOMEM; /* (the failures below) */
    if (!S->node && !(S->node = rs__alloc_array(ctx, 1, sizeof *S->node))) goto fail;
    if (!S->leg && !(S->leg = rs__alloc_array(ctx, 1, sizeof *S->leg))) goto fail;
    S->leg_start[nn] = (uint32_t)at;
    S->nnodes = nn;
    S->nlegs = at;
    if (!bases) bases = N->s_base;
    if (bases && !(S->s_base = rs__alloc_array(ctx, m, sizeof *S->s_base))) goto fail;
    /* per record; links to records not kept end the stroke there */
    for (size_t i = 0; i < n; i++) {
        uint32_t r = ids[i];
        if (S->s_base) S->s_base[i] = bases[r];
        S->s_off[i] = N->s_off[r];
        S->length[i] = N->length[r];
        S->s_len[i] = N->s_len[r];
        S->rev[i] = N->rev[r];
        S->prev[i] = N->prev[r] == NONE ? NONE : map[N->prev[r]];
        S->next[i] = N->next[r] == NONE ? NONE : map[N->next[r]];
        for (int e = 0; e < 2; e++) {
            uint32_t t = N->link[2 * r + e];
            S->link[2 * i + e] = t == NONE || map[t / 2] == NONE ? NONE : 2 * map[t / 2] + t % 2;
        }
    }
    /* the strokes in their order, each cut into its runs of kept records;
     * only a ring kept whole stays closed */
    size_t k = 0;
    at = 0;
    for (size_t st = 0; st < N->nstrokes; st++) {
        uint32_t a = N->stroke_start[st], b = N->stroke_start[st + 1];
        int whole = 1;
        for (uint32_t e = a; e < b; e++) whole &= map[N->stroke_roads[e]] != NONE;
        int open = 0;
        for (uint32_t e = a; e < b; e++) {
            uint32_t i = map[N->stroke_roads[e]];
            if (i == NONE) {
                if (open) k++;
                open = 0;
                continue;
            }
            if (!open) {
                S->stroke_start[k] = (uint32_t)at;
                S->closed[k] = (uint8_t)(whole && N->closed[st]);
                open = 1;
            }
            S->stroke_of[i] = (uint32_t)k;
            S->stroke_roads[at++] = i;
        }
        if (open) k++;
    }
    S->stroke_start[k] = (uint32_t)at;
    S->nstrokes = k;
    S->bytes = bytes_of(S);
    rs__free(ctx, map);
    *out = S;
    return RS_OK;
fail:
    rs__free(ctx, map);
    rs_network_free(ctx, S);
    return res == RS_ERR_INVALID_ARG ? rs__fail(ctx, res, "network subset: record ids not ascending or out of range")
           : res == RS_ERR_CANCELLED ? rs__fail(ctx, res, "cancelled")
                                     : rs__fail(ctx, res, "network subset: out of memory");
}

/* Points, arc lengths, runs of repeated points, live roads. */
static rs_result load_points(build *B)
{
    size_t n = B->nroads, nv = 0;
    B->voff = rs__alloc_array(B->ctx, n + 1, sizeof *B->voff);
    B->live = rs__calloc(B->ctx, n ? n : 1, 1);
    B->look = rs__alloc_array(B->ctx, n ? n : 1, sizeof *B->look);
    B->level = rs__alloc_array(B->ctx, n ? n : 1, sizeof *B->level);
    if (!B->voff || !B->live || !B->look || !B->level) return RS_ERR_NOMEM;
    for (size_t r = 0; r < n; r++) {
        if (rs__tick(B->ctx, 0)) return RS_ERR_CANCELLED; /* (10^5 roads' looks: ~20 ms) */
        size_t np = 0;
        rs_roads_get(B->roads, r, NULL, NULL, NULL, &np);
        look_of(B->roads, r, &B->look[r]);
        B->level[r] = (int8_t)rs__road_level(B->roads, r);
        B->voff[r] = nv;
        nv += np;
    }
    B->voff[n] = nv;
    if (nv >= UINT32_MAX) return RS_ERR_LIMIT;
    B->nv = nv;
    size_t m = nv ? nv : 1;
    B->vroad = rs__alloc_array(B->ctx, m, sizeof *B->vroad);
    /* the road set keeps its points in one array in road order: read them
     * there when they are (no copy), else copy them */
    const double *base = NULL;
    if (n > 0) rs_roads_get(B->roads, 0, NULL, NULL, &base, NULL);
    for (size_t r = 0; base && r < n; r++) {
        const double *xy = NULL;
        rs_roads_get(B->roads, r, NULL, NULL, &xy, NULL);
        if (xy != base + 2 * B->voff[r]) base = NULL;
    }
    B->xy = base;
    if (!base && !(B->xy_own = rs__alloc_array(B->ctx, m, 2 * sizeof *B->xy_own))) return RS_ERR_NOMEM;
    if (!base) B->xy = B->xy_own;
    B->s = rs__alloc_array(B->ctx, m, sizeof *B->s);
    B->rep = rs__alloc_array(B->ctx, m, sizeof *B->rep);
    B->parent = rs__alloc_array(B->ctx, m, sizeof *B->parent);
    B->inhash = rs__calloc(B->ctx, m, 1);
    B->nodeof = rs__alloc_array(B->ctx, m, sizeof *B->nodeof);
    if (!B->vroad || !B->s || !B->rep || !B->parent || !B->inhash || !B->nodeof) return RS_ERR_NOMEM;
    for (size_t r = 0; r < n; r++) {
        if (rs__tick(B->ctx, 0)) return RS_ERR_CANCELLED;
        const double *xy = NULL;
        size_t np = 0, v0 = B->voff[r];
        rs_roads_get(B->roads, r, NULL, NULL, &xy, &np);
        if (B->xy_own) memcpy(B->xy_own + 2 * v0, xy, np * 2 * sizeof *xy);
        double s = 0;
        for (size_t k = 0; k < np; k++) {
            size_t v = v0 + k;
            B->vroad[v] = (uint32_t)r;
            B->parent[v] = (uint32_t)v;
            B->nodeof[v] = NONE;
            int repeat = k > 0 && xy[2 * k] == xy[2 * k - 2] && xy[2 * k + 1] == xy[2 * k - 1];
            B->rep[v] = repeat ? B->rep[v - 1] : (uint32_t)v;
            if (k > 0) /* summed as the road field and the line symbols sum it */
                s = rs__arc_add(s, rs__arc_len(xy[2 * k - 2], xy[2 * k - 1], xy[2 * k], xy[2 * k + 1]));
            B->s[v] = s;
        }
        B->live[r] = np >= 2 && s > 2 * B->tol;
        B->look[r].first = (uint32_t)v0;
        B->look[r].last = (uint32_t)(np ? v0 + np - 1 : v0);
        B->look[r].last_run = np ? B->rep[B->look[r].last] : (uint32_t)v0;
        B->look[r].length = s;
        for (size_t k = 0; k < np; k++) B->inhash[v0 + k] = B->live[r] && B->rep[v0 + k] == v0 + k;
        /* a short record's two ends join the places they meet (bridge_short) */
        if (!B->live[r] && np >= 2 && B->rep[v0 + np - 1] != v0) B->inhash[v0] = B->inhash[B->rep[v0 + np - 1]] = 1;
    }
    return RS_OK;
}

/* Union the hashed points (B->inhash: the run starts of live roads)
 * within the tolerance of each other: B->parent of every point is then the
 * lowest point of its group (flat). The pairs are joined by their places
 * in the sorted cells (mostly one run: in the cache), not by point (ids
 * far apart: a cache miss per step), then each point is given its group's
 * lowest id. */
static rs_result cluster_points(build *B)
{
    /* cells of 8 tolerances: a point's disc mostly stays in its own cell;
     * at least 2^-40 of the largest coordinate, so a disc's rounding
     * margin spans at most 2 cells a side (else 1e18 m coordinates made a
     * point probe millions of cells) */
    double tol = B->tol, big = 0;
    pt_box box; /* (and the points' box, in the same pass) */
    box_init(&box);
    for (size_t v = 0; v < B->nv; v++)
        if (B->inhash[v]) {
            double ax = fabs(B->xy[2 * v]), ay = fabs(B->xy[2 * v + 1]);
            if (ax > big && ax <= DBL_MAX) big = ax;
            if (ay > big && ay <= DBL_MAX) big = ay;
            box_add(&box, B->xy + 2 * v);
        }
    double cell = fmax(8 * tol, big * 0x1p-40);
    pt_cells H;
    rs_result res = cells_build(B->ctx, &H, B->xy, B->vroad, B->inhash, B->nv, cell, 1, &box);
    size_t count = H.count;
    /* union-find of places, a group's root its place of the lowest point
     * (unite_places): that point is the group's, with no array of them */
    uint32_t *up = res ? NULL : rs__alloc_array(B->ctx, count ? count : 1, sizeof *up);
    if (!up) {
        cells_free(B->ctx, &H);
        return res ? res : RS_ERR_NOMEM;
    }
    for (size_t i = 0; i < count; i++) up[i] = (uint32_t)i;
    /* points in key order: the cells they probe are mostly their own run,
     * else close by (the union does not depend on the order) */
    for (size_t i = 0; i < count; i++) {
        if ((i & 16383) == 0 && rs__poll(B->ctx)) { /* (10^6 points: ~0.1 s) */
            cells_free(B->ctx, &H);
            rs__free(B->ctx, up);
            return RS_ERR_CANCELLED;
        }
        const pt_entry *e = &H.ent[i];
        int64_t c[4];
        uint64_t kx0, kx1, ky0, ky1, own = H.dense ? 0 : H.key[i];
        disc_cells(&H, &e->x, tol, c);
        if (!key_range(&H, 0, c[0], c[1], &kx0, &kx1) || !key_range(&H, 1, c[2], c[3], &ky0, &ky1)) continue;
        for (uint64_t ky = ky0; ky <= ky1; ky++)
            for (uint64_t kx = kx0; kx <= kx1; kx++) {
                uint32_t qa, qb;
                if (H.dense) { /* (the row's cells: one run; ids below e's are skipped below) */
                    qa = H.start[ky * H.nx + kx0], qb = H.start[ky * H.nx + kx1 + 1];
                    kx = kx1;
                } else if (zkey(kx, ky) == own) { /* its own run: from i on (lower entries have lower ids) */
                    qa = (uint32_t)i + 1;
                    for (qb = qa; qb < count && H.key[qb] == own; qb++) {}
                } else
                    run_of(&H, kx, ky, &qa, &qb);
                for (uint32_t q = qa; q < qb; q++) {
                    const pt_entry *f = &H.ent[q];
                    if (f->id <= e->id || !near2(&e->x, &f->x, tol)) continue;
                    if ((B->cid || f->road == e->road) &&
                        one_place(B, e->road, B->s[e->id], f->road, B->s[f->id], e->x == f->x && e->y == f->y))
                        continue; /* one place of one road: no node */
                    if (B->cid && B->cid[e->road] != B->cid[f->road] && (chain_joint(B, e->id) || chain_joint(B, f->id)))
                        continue; /* (a joint of a chain is inside its street, as its points are) */
                    unite_places(up, H.ent, (uint32_t)i, q);
                }
            }
    }
    for (size_t i = 0; i < count; i++) {
        uint32_t v = H.ent[i].id, l = H.ent[find(up, (uint32_t)i)].id;
        if (i + CAHEAD < count) rs__prefetch(B->parent + H.ent[i + CAHEAD].id); /* (by id: at random places) */
        if (l != v) B->parent[v] = l;
    }
    rs__free(B->ctx, up);
    cells_free(B->ctx, &H);
    return RS_OK;
}

/* network_build's flags: no ends inside surfaces (rs__network_update finds
 * them with the whole map's strokes); no network (*out NULL, RS_OK) when a
 * record is short (its chains reach as far as they run). */
#define NB_NO_SURF 1u
#define NB_NO_SHORT 2u
static rs_result network_build(rs_ctx *ctx, const rs_roads *roads, const rs_network_options *opts, unsigned flags,
                               rs_network **out);

/* Record r is short (no legs: bridge_short joins its two ends), of two
 * places. */
static int short_record(const build *B, size_t r)
{
    size_t v0 = B->voff[r], v1 = B->voff[r + 1];
    return !B->live[r] && v1 - v0 >= 2 && B->rep[v1 - 1] != v0;
}

static uint64_t end_hash(const double *p)
{
    double x = p[0] == 0 ? 0.0 : p[0], y = p[1] == 0 ? 0.0 : p[1]; /* (-0 is 0) */
    uint64_t a, b;
    memcpy(&a, &x, sizeof a);
    memcpy(&b, &y, sizeof b);
    uint64_t h = a * 0x9E3779B97F4A7C15u ^ (b + 0x632BE59BD9B4E019u) * 0xC2B2AE3D27D4EB4Fu;
    return h ^ h >> 29;
}

/* Runs of short records (each at most twice the tolerance) that a longer
 * record goes on from, or longer than twice the tolerance in all, or of
 * more than SHORT_CHAIN records: a road cut into crumbs (every record at
 * most 0.1 m; 240 records on a 24 m road) had all its ends joined into one
 * point by bridge_short, so it was points only and drew no lines; a short
 * record between a T's through records near the side road's end joined
 * the T's node and made a loop of its neighbour (184/255, fuzz/split
 * matrix). Such a run's records are live (legs at each end, strokes
 * through them), and the records chained to them (two records' ends at
 * exactly one point, no other end there, drawing alike and keeping the
 * direction of travel) are one road for the rule that two places of one
 * road within twice the tolerance are no node (one_place): along the
 * chain. A record's own two ends 0.02 m apart, and the ends of the records
 * beside it, are then no node; each shared end is one. A run alone and
 * no longer than twice the tolerance is a road of that length: points
 * only, as the road whole (bridge_short). No short record, or no such
 * run: nothing is made (B->cid stays NULL). */
static rs_result chain_short_runs(build *B)
{
    size_t n = B->nroads, nshort = 0;
    for (size_t r = 0; r < n && !nshort; r++) nshort += short_record(B, r);
    if (!nshort) return RS_OK;
    size_t ne = 2 * n, cap = 16;
    while (cap < 2 * ne) cap *= 2;
    uint32_t *tab = rs__alloc_array(B->ctx, cap, sizeof *tab), *next = rs__alloc_array(B->ctx, ne, sizeof *next);
    uint32_t *partner = rs__alloc_array(B->ctx, ne, sizeof *partner), *run = rs__alloc_array(B->ctx, n, sizeof *run);
    uint8_t *mark = rs__calloc(B->ctx, n, 1);
    rs_result res = RS_OK;
    if (!tab || !next || !partner || !run || !mark) {
        res = RS_ERR_NOMEM;
        goto done;
    }
    /* the record ends at each exact point: lists by hash slot */
    for (size_t i = 0; i < cap; i++) tab[i] = NONE;
    for (size_t e = 0; e < ne; e++) {
        size_t r = e / 2, v0 = B->voff[r], v1 = B->voff[r + 1];
        next[e] = partner[e] = NONE;
        if (v1 - v0 < 2 || B->rep[v1 - 1] == v0) continue;
        const double *p = end_point(B, (uint32_t)e);
        if (!isfinite(p[0]) || !isfinite(p[1])) continue;
        size_t h = (size_t)(end_hash(p) & (cap - 1));
        next[e] = tab[h];
        tab[h] = (uint32_t)e;
    }
    /* partners: exactly two ends at a point (of a slot's list, the ends at
     * that point), of two records that continue each other */
    for (size_t h = 0; h < cap; h++)
        for (uint32_t e = tab[h]; e != NONE; e = next[e]) {
            const double *p = end_point(B, e);
            uint32_t other = NONE, count = 0;
            for (uint32_t f = tab[h]; f != NONE && count < 3; f = next[f]) {
                const double *q = end_point(B, f);
                if (q[0] != p[0] || q[1] != p[1]) continue;
                count++;
                if (f != e) other = f;
            }
            if (count != 2 || other / 2 == e / 2) continue;
            const road_look *a = &B->look[e / 2], *b = &B->look[other / 2];
            if (draw_alike(a, b) && ((e & 1) != (other & 1) || a->two_way)) partner[e] = other;
        }
    /* the runs of short records; mark 2: a record of a long run */
    int any = 0;
    for (size_t r = 0; r < n; r++) {
        if (mark[r] || !short_record(B, r)) continue;
        size_t cnt = 0;
        double len = B->look[r].length;
        int beside_long = 0; /* (a record of more than 2 tol goes on from the run) */
        mark[r] = 1;
        run[cnt++] = (uint32_t)r;
        for (uint32_t side = 0; side < 2; side++)
            for (uint32_t e = 2 * (uint32_t)r + side, f; (f = partner[e]) != NONE; e = f ^ 1) {
                uint32_t q = f / 2;
                int sq = short_record(B, q);
                if (!sq) beside_long |= B->live[q];
                if (mark[q] || !sq) break;
                mark[q] = 1;
                run[cnt++] = q;
                len += B->look[q].length;
            }
        if (beside_long || len > 2 * B->tol || cnt > SHORT_CHAIN) {
            for (size_t i = 0; i < cnt; i++) mark[run[i]] = 2;
            any = 1;
        }
    }
    if (!any) goto done;
    B->cid = rs__alloc_array(B->ctx, n, sizeof *B->cid);
    B->cs0 = rs__calloc(B->ctx, n, sizeof *B->cs0);
    B->ctot = rs__calloc(B->ctx, n, sizeof *B->ctot);
    B->crev = rs__calloc(B->ctx, n, 1);
    B->jend = rs__calloc(B->ctx, n, 1);
    if (!B->cid || !B->cs0 || !B->ctot || !B->crev || !B->jend) {
        res = RS_ERR_NOMEM;
        goto done;
    }
    for (size_t r = 0; r < n; r++) B->cid[r] = (uint32_t)r;
    /* the chains through long runs, from their first record (a ring: from
     * the run's record met first), numbered by it */
    for (size_t r = 0; r < n; r++) {
        if ((mark[r] & 3) != 2 || (mark[r] & 4)) continue;
        uint32_t c = (uint32_t)r, ein = 2 * (uint32_t)r; /* (the record, the end it is entered by) */
        int ring = 0;
        for (size_t steps = 0; steps < n; steps++) {
            uint32_t f = partner[ein];
            if (f == NONE) break;
            if (f / 2 == r) {
                ring = 1;
                c = (uint32_t)r, ein = 2 * (uint32_t)r;
                break;
            }
            c = f / 2, ein = f ^ 1;
        }
        double acc = 0;
        uint32_t id = c;
        for (uint32_t cur = c, e = ein;;) {
            B->cid[cur] = id;
            B->jend[cur] = (uint8_t)((partner[2 * cur] != NONE) | (partner[2 * cur + 1] != NONE) << 1);
            B->crev[cur] = (uint8_t)(e & 1);
            B->cs0[cur] = acc;
            mark[cur] |= 4;
            acc += B->look[cur].length;
            uint32_t f = partner[e ^ 1];
            if (f == NONE || (mark[f / 2] & 4)) break;
            cur = f / 2, e = f;
        }
        B->ctot[id] = ring ? acc : 0;
    }
    /* the long runs' records are live, every place of them in the hash */
    for (size_t r = 0; r < n; r++) {
        if ((mark[r] & 3) != 2) continue;
        B->live[r] = 1;
        for (size_t v = B->voff[r]; v < B->voff[r + 1]; v++) B->inhash[v] = B->rep[v] == v;
    }
done:
    rs__free(B->ctx, tab);
    rs__free(B->ctx, next);
    if (B->cid) B->cpart = partner; /* (kept for leg_angle) */
    else rs__free(B->ctx, partner);
    rs__free(B->ctx, run);
    rs__free(B->ctx, mark);
    return res;
}

/* A record no longer than twice the tolerance (no legs: docs/network.md
 * "Degenerate records") is a point of the network: the places at its two
 * ends are one, so the records it sits between meet there and may continue
 * each other across it (a road split 0.08 m apart broke its stroke there:
 * its lines stopped short on both sides; fuzz/split). After
 * cluster_points, whose hash held its two ends: join them, take them out
 * of the hash (they make no node and no leg), and root every group at its
 * lowest point of a live record (nodes are numbered by those). */
static rs_result bridge_short(build *B)
{
    int any = 0;
    for (size_t r = 0; r < B->nroads; r++) {
        size_t v0 = B->voff[r], v1 = B->voff[r + 1];
        if (B->live[r] || v1 - v0 < 2 || B->rep[v1 - 1] == v0) continue;
        unite(B->parent, (uint32_t)v0, B->rep[v1 - 1]);
        B->inhash[v0] = B->inhash[B->rep[v1 - 1]] = 0;
        any = 1;
    }
    if (!any) return RS_OK;
    size_t m = B->nv ? B->nv : 1;
    uint32_t *root = rs__alloc_array(B->ctx, m, sizeof *root), *low = rs__alloc_array(B->ctx, m, sizeof *low);
    if (!root || !low) {
        rs__free(B->ctx, root);
        rs__free(B->ctx, low);
        return RS_ERR_NOMEM;
    }
    for (size_t v = 0; v < B->nv; v++) root[v] = find(B->parent, (uint32_t)v), low[v] = NONE;
    for (size_t v = 0; v < B->nv; v++) /* ascending: the first live one is the lowest */
        if (B->inhash[v] && low[root[v]] == NONE) low[root[v]] = (uint32_t)v;
    for (size_t v = 0; v < B->nv; v++) B->parent[v] = low[root[v]] != NONE ? low[root[v]] : root[v];
    rs__free(B->ctx, root);
    rs__free(B->ctx, low);
    return RS_OK;
}

/* Progress: the stages poll (rs__poll); done is 0 of 1 until the end. */
rs_result rs_network_build(rs_ctx *ctx, const rs_roads *roads, const rs_network_options *opts, rs_network **out)
{
    if (!ctx) return network_build(ctx, roads, opts, 0, out);
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, 1, 1);
    return rs__progress_end(ctx, &pg, network_build(ctx, roads, opts, 0, out));
}

static rs_result network_build(rs_ctx *ctx, const rs_roads *roads, const rs_network_options *opts, unsigned flags,
                               rs_network **out)
{
    if (!out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "network: out is NULL");
    *out = NULL;
    if (!roads) return rs__fail(ctx, RS_ERR_INVALID_ARG, "network: roads is NULL");
    rs_network_options no;
    rs_result rc = RS__OPTS_IN(ctx, opts, &no, rs_network_options);
    if (rc) return rc;
    double tol = no.tolerance != 0 ? no.tolerance : RS__NETWORK_TOL;
    if (!(tol >= 1e-9 && tol <= 1000))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "network: tolerance %g must be 1e-9..1000 metres (0: 0.05)", tol);
    build B;
    memset(&B, 0, sizeof B);
    B.ctx = ctx;
    B.roads = roads;
    B.nroads = rs_roads_count(roads);
    B.tol = tol;
    if (B.nroads >= UINT32_MAX) return rs__fail(ctx, RS_ERR_LIMIT, "network: too many roads");
    rs_network *N = rs__calloc(ctx, 1, sizeof *N);
    rs_result res = RS_OK;
    if (!N) return rs__fail(ctx, RS_ERR_NOMEM, "network: out of memory");
    N->nroads = B.nroads;
    N->tol = tol;
    size_t n = B.nroads, m = n ? n : 1;
    if ((res = load_points(&B)) != RS_OK || (res = rs__poll(ctx) ? RS_ERR_CANCELLED : RS_OK) != RS_OK)
        goto fail;
    for (size_t r = 0; r < n && !N->any_short; r++) N->any_short = short_record(&B, r);
    if ((flags & NB_NO_SHORT) && N->any_short) {
        build_free(&B);
        rs_network_free(ctx, N);
        return RS_OK;
    }
    if ((res = chain_short_runs(&B)) != RS_OK || (res = cluster_points(&B)) != RS_OK ||
        (res = bridge_short(&B)) != RS_OK ||
        (res = rs__poll(ctx) ? RS_ERR_CANCELLED : RS_OK) != RS_OK)
        goto fail;

    /* (the union-find is flat: parent[v] is the lowest point of v's group) */
    /* nodes: groups holding a road end or two places of roads. Every union
     * joined two places, so a group of two or more points is one; a group
     * of one is when it is a road's end. */
    for (size_t v = 0; v < B.nv; v++)
        if (B.parent[v] != v) B.nodeof[B.parent[v]] = 0;
    for (size_t r = 0; r < n; r++) {
        if (!B.live[r]) continue;
        B.nodeof[B.parent[B.voff[r]]] = 0;
        B.nodeof[B.parent[B.rep[B.voff[r + 1] - 1]]] = 0;
    }
    /* numbered by their roots in point order, and every point given its
     * root's node (a root below it is numbered by then; a root above it,
     * only where bridge_short re-rooted a group, in a second pass) */
    size_t nn = 0;
    int later = 0;
    for (size_t v = 0; v < B.nv; v++) {
        uint32_t p = B.parent[v];
        if (v + CAHEAD < B.nv) rs__prefetch(B.nodeof + B.parent[v + CAHEAD]); /* (a root: at a random place) */
        if (p == v) B.nodeof[v] = B.inhash[v] && B.nodeof[v] == 0 ? (uint32_t)nn++ : NONE;
        else if (p < v) B.nodeof[v] = B.nodeof[p];
        else later = 1;
    }
    for (size_t v = 0; later && v < B.nv; v++) /* (the roots are not written: flat) */
        if (B.parent[v] > v) B.nodeof[v] = B.nodeof[B.parent[v]];
    rs__free(ctx, B.parent); /* (the groups are their nodes from here on) */
    B.parent = NULL;
    N->nnodes = nn;
    if (rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto fail; }
    if ((res = find_tees(&B)) != RS_OK) goto fail;
    if (rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto fail; }
    if ((res = node_lists(&B, nn)) != RS_OK) goto fail;
    if (rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto fail; }
    /* legs: at most B.nlegs (the array shrinks to its count below). The
     * build's arrays are freed as soon as they are done with (the point
     * groups after the controls, which are read here, before the legs) and
     * the stroke arrays made after the legs, so the legs (the largest
     * array, 40 bytes each) are written beside few others: the peak heap of
     * the 10^5-record lattice 67.6 -> 59.3 MB. A smaller peak is less memory
     * to fault in again: the allocator hands back a heap top above its trim
     * threshold on free, and the next build faults it in page by page
     * (glibc: twice the largest block freed, at most 64 MB). */
    size_t nl = B.nlegs;
    /* controls from point attributes at a node's points (into ctl, when
     * there are any: the nodes are made after the point arrays are freed) */
    size_t npa = rs_roads_point_attr_count(roads);
    if (npa && !(B.ctl = rs__calloc(ctx, nn ? nn : 1, sizeof *B.ctl))) {
        res = RS_ERR_NOMEM;
        goto fail;
    }
    for (size_t k = 0; k < npa; k++) {
        size_t r = 0, pt = 0;
        const char *key = NULL, *val = NULL;
        if (rs_roads_point_attr_at(roads, k, &r, &pt, &key, &val) != RS_OK || r >= n || !B.live[r] ||
            pt >= B.voff[r + 1] - B.voff[r])
            continue;
        uint32_t nd = B.nodeof[B.rep[B.voff[r] + pt]];
        if (nd == NONE) continue;
        uint32_t f = 0;
        if (strcmp(key, "highway") == 0)
            f = strcmp(val, "stop") == 0 ? RS_NODE_STOP : strcmp(val, "give_way") == 0 ? RS_NODE_GIVE_WAY
                : strcmp(val, "traffic_signals") == 0 ? RS_NODE_SIGNALS : 0;
        else if (strcmp(key, "crossing") == 0)
            f = RS_NODE_CROSSING;
        B.ctl[nd] |= f;
    }
    /* short records and the node their (joined) ends are at, for link_short_ends */
    for (int fill = 0; fill < 2; fill++) { /* (count, then fill) */
        size_t k = 0;
        for (size_t r = 0; r < n; r++) {
            uint32_t nd = !B.live[r] && B.voff[r + 1] - B.voff[r] >= 2 ? B.nodeof[B.voff[r]] : NONE;
            if (nd == NONE) continue;
            if (fill) B.short_at[2 * k] = (uint32_t)r, B.short_at[2 * k + 1] = nd;
            k++;
        }
        B.nshort = k;
        if (fill || !k) break;
        if (!(B.short_at = rs__alloc_array(ctx, 2 * k, sizeof *B.short_at))) {
            res = RS_ERR_NOMEM;
            goto fail;
        }
    }
    rs__free(ctx, B.nodeof), rs__free(ctx, B.inhash), rs__free(ctx, B.rep);
    B.nodeof = NULL, B.inhash = NULL, B.rep = NULL;
    /* the network's arrays after those frees: the nodes in their room (not
     * zeroed: the legs write every node whole, and its leg start). The
     * 10^5 lattice's peak heap 65 -> 58 MB: below glibc's trim threshold
     * (twice its mmap threshold, 63 MB once the 30 MB leg array was freed),
     * so a repeated build finds its memory in place (above it: 15,000 page
     * faults a build, the heap top given back on free and faulted in again) */
    N->leg = rs__alloc_array(ctx, nl ? nl : 1, sizeof *N->leg);
    N->node = rs__alloc_array(ctx, nn ? nn : 1, sizeof *N->node);
    N->leg_start = rs__alloc_array(ctx, nn + 1, sizeof *N->leg_start);
    N->link = rs__alloc_array(ctx, 2 * m, sizeof *N->link);
    N->node_key = rs__alloc_array(ctx, nn ? nn : 1, sizeof *N->node_key);
    N->node_rad = rs__alloc_array(ctx, nn ? nn : 1, sizeof *N->node_rad);
    N->node_surf = rs__calloc(ctx, nn ? nn : 1, 1);
    if (!N->leg || !N->node || !N->leg_start || !N->link || !N->node_key || !N->node_rad || !N->node_surf) {
        res = RS_ERR_NOMEM;
        goto fail;
    }
    for (size_t e = 0; e < 2 * n; e++) N->link[e] = NONE;
    nl = 0;
    for (uint32_t nd = 0; nd < nn; nd++) {
        if ((nd & 4095) == 0 && rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto fail; }
        /* (the points of a node a few ahead: by id, at random places, but for
         * its lowest: the nodes' lowest points ascend, read in order) */
        if (nd + AHEAD < nn)
            for (uint32_t q = B.pstart[nd + AHEAD] + 1, qe = B.pstart[nd + AHEAD + 1]; q < qe && q < B.pstart[nd + AHEAD] + 4; q++) {
                uint32_t v = B.pids[q];
                rs__prefetch(B.vroad + v);
                rs__prefetch(B.s + v);
                /* (the lines of v - 1 .. v + 1, which the legs' directions read: the
                 * neighbour's was a miss one time in two; v > 0, not the lowest) */
                rs__prefetch(B.xy + 2 * (size_t)v - 2);
                rs__prefetch(B.xy + 2 * (size_t)v + 2);
            }
        if (nd + AHEAD / 2 < nn) /* (their roads, half as far ahead: the ids are in the cache by now) */
            for (uint32_t q = B.pstart[nd + AHEAD / 2] + 1, qe = B.pstart[nd + AHEAD / 2 + 1]; q < qe && q < B.pstart[nd + AHEAD / 2] + 4; q++)
                rs__prefetch(B.look + B.vroad[B.pids[q]]);
        size_t np = node_passes(&B, nd);
        if (np == (size_t)-1) { res = RS_ERR_NOMEM; goto fail; }
        uint32_t v = B.pids[B.pstart[nd]]; /* its lowest point (a node holds a point) */
        rs_network_node ndo;
        memset(&ndo, 0, sizeof ndo);
        ndo.control = B.ctl ? B.ctl[nd] : 0;
        ndo.x = B.xy[2 * (size_t)v];
        ndo.y = B.xy[2 * (size_t)v + 1];
        const double *c = &ndo.x;
        N->node_key[nd] = (uint64_t)B.vroad[v] << 32 | (uint64_t)(v - B.voff[B.vroad[v]]);
        double rad = 0;
        for (uint32_t q = B.pstart[nd] + 1; q < B.pstart[nd + 1]; q++)
            rad = fmax(rad, hypot(B.xy[2 * (size_t)B.pids[q]] - c[0], B.xy[2 * (size_t)B.pids[q] + 1] - c[1]));
        N->node_rad[nd] = (float)rad < rad ? nextafterf((float)rad, INFINITY) : (float)rad;
        N->leg_start[nd] = (uint32_t)nl;
        for (size_t j = 0; j < np; j++) {
            const pass *p = &B.buf[j];
            size_t r = p->road;
            const road_look *lk = &B.look[r];
            int pr = lk->priority;
            if (lk->roundabout) ndo.control |= RS_NODE_ROUNDABOUT;
            rs_network_leg L;
            memset(&L, 0, sizeof L);
            L.road = (uint32_t)r;
            L.priority = pr;
            if (p->seg != NONE) { /* a T on segment seg: the segment's own direction */
                L.segment = p->seg;
                L.s = p->s;
                double dx = B.xy[2 * p->v1] - B.xy[2 * p->v0], dy = B.xy[2 * p->v1 + 1] - B.xy[2 * p->v0 + 1];
                L.kind = RS_LEG_FORWARD;
                L.angle = atan2(dy, dx);
                N->leg[nl++] = L;
                L.kind = RS_LEG_BACKWARD;
                L.angle = atan2(-dy, -dx);
                N->leg[nl++] = L;
                continue;
            }
            if (p->first) {
                L.kind = RS_LEG_START, L.segment = 0, L.s = 0, L.angle = leg_angle(&B, lk, c, p->v1, 1);
                N->leg[nl++] = L;
            }
            if (p->last) {
                L.kind = RS_LEG_END, L.segment = lk->last - lk->first, L.s = lk->length;
                L.angle = leg_angle(&B, lk, c, p->v0, -1);
                N->leg[nl++] = L;
            }
            if (!p->first && !p->last) {
                L.segment = p->v0 - lk->first, L.s = p->s;
                L.kind = RS_LEG_FORWARD, L.angle = leg_angle(&B, lk, c, p->v1, 1);
                N->leg[nl++] = L;
                L.kind = RS_LEG_BACKWARD, L.angle = leg_angle(&B, lk, c, p->v0, -1);
                N->leg[nl++] = L;
            }
        }
        /* the node's legs by angle, its major legs and its stroke pairs,
         * while its legs are in the cache */
        rs_network_leg *L = N->leg + N->leg_start[nd];
        uint32_t d = (uint32_t)(nl - N->leg_start[nd]);
        if (d > 1) sort_legs(L, d);
        mark_major(L, d);
        ndo.degree = d;
        ndo.kind = d <= 1 ? RS_NODE_END : d == 2 ? RS_NODE_CONTINUATION : RS_NODE_JUNCTION;
        memcpy(&N->node[nd], &ndo, sizeof ndo);
        link_node(&B, L, d, N->link);
    }
    /* every qualifying node got legs (it holds a live road's point) */
    N->leg_start[nn] = (uint32_t)nl;
    N->nlegs = nl;
    link_short_ends(&B, N, B.short_at, B.nshort);
    rs__free(ctx, B.short_at);
    B.short_at = NULL;
    if (nl) { /* (shrinking: cannot fail but may) */
        rs_network_leg *lg = rs__realloc(ctx, N->leg, nl * sizeof *lg);
        if (lg) N->leg = lg;
    }
    if (!(flags & NB_NO_SURF)) {
        if (!(B.srd = rs__alloc_array(ctx, n ? n : 1, sizeof *B.srd))) {
            res = RS_ERR_NOMEM;
            goto fail;
        }
        for (size_t r = 0; r < n; r++) {
            const road_look *lk = &B.look[r];
            B.srd[r].width = lk->width, B.srd[r].priority = lk->priority;
            B.srd[r].non_car = (uint8_t)rs__class_non_car((rs_road_class)lk->road_class);
            B.srd[r].roundabout = lk->roundabout;
        }
    }
    rs__free(ctx, B.pids), rs__free(ctx, B.pstart), rs__free(ctx, B.tstart), rs__free(ctx, B.ps);
    rs__free(ctx, B.buf), rs__free(ctx, B.look), rs__free(ctx, B.vroad);
    B.pids = B.pstart = B.tstart = B.vroad = NULL, B.ps = B.buf = NULL, B.look = NULL;
    if (!stroke_arrays(ctx, N, m, n + 1)) {
        res = RS_ERR_NOMEM;
        goto fail;
    }
    /* strokes (their links are made above, node by node) */
    for (size_t r = 0; r < n; r++) {
        N->prev[r] = N->next[r] = NONE;
        N->length[r] = B.voff[r + 1] > B.voff[r] ? B.s[B.voff[r + 1] - 1] : 0;
    }
    number_strokes(N, N->link, B.live); /* (live is no longer needed: scratch) */
    if (!(flags & NB_NO_SURF) && (res = surface_tees(&B, N)) != RS_OK) goto fail;
    N->bytes = bytes_of(N);
    build_free(&B);
    *out = N;
    rs__ok(ctx);
    return RS_OK;
fail:
    build_free(&B);
    rs_network_free(ctx, N);
    if (res == RS_ERR_LIMIT) return rs__fail(ctx, res, "network: more than 2^32 points");
    if (res == RS_ERR_CANCELLED) return rs__fail(ctx, res, "cancelled");
    return rs__fail(ctx, RS_ERR_NOMEM, "network: out of memory");
}

size_t rs__network_bytes(const rs_network *net) { return net ? net->bytes : 0; }

size_t rs_network_road_count(const rs_network *net) { return net ? net->nroads : 0; }

size_t rs_network_node_count(const rs_network *net) { return net ? net->nnodes : 0; }

rs_result rs_network_get_node(const rs_network *net, size_t i, rs_network_node *out)
{
    if (!net || !out || i >= net->nnodes) return RS_ERR_INVALID_ARG;
    *out = net->node[i];
    return RS_OK;
}

rs_result rs_network_get_leg(const rs_network *net, size_t node, size_t k, rs_network_leg *out)
{
    if (!net || !out || node >= net->nnodes || k >= net->leg_start[node + 1] - net->leg_start[node])
        return RS_ERR_INVALID_ARG;
    *out = net->leg[net->leg_start[node] + k];
    return RS_OK;
}

size_t rs_network_stroke_count(const rs_network *net) { return net ? net->nstrokes : 0; }

rs_result rs_network_road_stroke(const rs_network *net, size_t road, rs_road_stroke *out)
{
    if (!net || !out || road >= net->nroads) return RS_ERR_INVALID_ARG;
    out->stroke = net->stroke_of[road];
    out->s_offset = net->s_off[road];
    out->length = net->length[road];
    out->prev = net->prev[road];
    out->next = net->next[road];
    out->closed = net->closed[net->stroke_of[road]];
    out->reversed = net->rev[road];
    return RS_OK;
}

size_t rs_network_stroke_roads(const rs_network *net, size_t k, uint32_t *roads, size_t cap)
{
    if (!net || k >= net->nstrokes) return 0;
    size_t a = net->stroke_start[k], b = net->stroke_start[k + 1];
    for (size_t i = a; i < b && i - a < cap && roads; i++) roads[i - a] = net->stroke_roads[i];
    return b - a;
}

/* Where leg k's left edge meets the next leg's right edge (gap g from k to
 * the next, counter-clockwise): the distances along the two legs from the
 * node, from P + hk Lk + t uk = P - hn Ln + s un (L: the left normal);
 * none (0) unless 0 < g < pi, where the edges diverge or run parallel. */
static void area_corner(double hk, double hn, double g, double *t, double *s)
{
    double sg = sin(g), cg = cos(g);
    *t = *s = 0;
    if (!(sg > 1e-9) || !(g < 3.14159265358979323846)) return;
    *t = (hn + hk * cg) / sg;
    *s = (hk + hn * cg) / sg;
}

/* The half width of leg L's road (finite, >= 0). */
static double area_half_width(const rs_roads *roads, const rs_network_leg *L)
{
    double w = 0;
    rs_roads_get(roads, L->road, NULL, &w, NULL, NULL);
    double h = 0.5 * w;
    return h > 0 && h < 1e15 ? h : 0;
}

size_t rs_network_junction_area(const rs_network *net, const rs_roads *roads, size_t node, double *xy, size_t cap,
                                double *trim)
{
    if (!net || !roads || node >= net->nnodes || rs_roads_count(roads) != net->nroads) return 0;
    const rs_network_leg *L = net->leg + net->leg_start[node];
    const size_t d = net->leg_start[node + 1] - net->leg_start[node];
    if (d < 3) return 0;
    const double two_pi = 2 * 3.14159265358979323846, px = net->node[node].x, py = net->node[node].y;
    size_t n = 0;
    double lx = 0, ly = 0, fx = 0, fy = 0; /* the last and the first point */
    /* corners of neighbouring legs that coincide (an edge meeting the
     * next one where both legs end) are one point, within rounding */
    const double eps = 1e-9 * (1 + fabs(px) + fabs(py)) + 1e-6 * net->tol;
    for (size_t k = 0; k < d; k++) {
        size_t kp = k ? k - 1 : d - 1, kn = k + 1 < d ? k + 1 : 0;
        double h = area_half_width(roads, &L[k]), hp = area_half_width(roads, &L[kp]),
               hn = area_half_width(roads, &L[kn]);
        /* how far the leg runs from the node: its record's length before or after it */
        double len = net->length[L[k].road];
        double room = L[k].kind == RS_LEG_BACKWARD ? L[k].s : L[k].kind == RS_LEG_FORWARD ? len - L[k].s : len;
        /* gaps to the neighbours, counter-clockwise (legs are sorted by angle) */
        double gp = L[k].angle - L[kp].angle, gn = L[kn].angle - L[k].angle;
        if (k == 0) gp += two_pi;
        if (k + 1 == d) gn += two_pi;
        double t_next, s_next, t_prev, s_prev;
        area_corner(h, hn, gn, &t_next, &s_next);  /* this leg's left corner */
        area_corner(hp, h, gp, &t_prev, &s_prev);  /* this leg's right corner */
        double tr = t_next > s_prev ? t_next : s_prev;
        tr = tr > 0 && room > 0 ? (tr < room ? tr : room) : 0;
        if (trim) trim[k] = tr;
        double ux = cos(L[k].angle), uy = sin(L[k].angle), cx = px + tr * ux, cy = py + tr * uy;
        /* the right corner, then the left one (counter-clockwise) */
        double pt[2][2] = { { cx + h * uy, cy - h * ux }, { cx - h * uy, cy + h * ux } };
        for (int c = 0; c < 2; c++) {
            if (n > 0 && fabs(pt[c][0] - lx) <= eps && fabs(pt[c][1] - ly) <= eps) continue;
            if (k + 1 == d && c == 1 && n > 0 && fabs(pt[c][0] - fx) <= eps && fabs(pt[c][1] - fy) <= eps) continue;
            if (xy && n < cap) xy[2 * n] = pt[c][0], xy[2 * n + 1] = pt[c][1];
            if (n == 0) fx = pt[c][0], fy = pt[c][1];
            lx = pt[c][0], ly = pt[c][1];
            n++;
        }
    }
    return n;
}

/* ---- the network after an edit ---- */

static int in_box(const double *b, double x, double y) { return x >= b[0] && x <= b[2] && y >= b[1] && y <= b[3]; }

static void grown(double *o, const double *b, double g)
{
    o[0] = b[0] - g, o[1] = b[1] - g, o[2] = b[2] + g, o[3] = b[3] + g;
}

/* The square of half side r around (x, y) meets box b / lies inside it. */
static int square_meets(const double *b, double x, double y, double r)
{
    return x + r >= b[0] && x - r <= b[2] && y + r >= b[1] && y - r <= b[3];
}

static int square_inside(const double *b, double x, double y, double r)
{
    return x - r >= b[0] && x + r <= b[2] && y - r >= b[1] && y + r <= b[3];
}

/* N's links with the seams of its rings joined again (number_strokes cut
 * each ring before its first record), into link (2 nroads). */
static void uncut_links(const rs_network *N, uint32_t *link)
{
    memcpy(link, N->link, 2 * N->nroads * sizeof *link);
    for (size_t k = 0; k < N->nstrokes; k++) {
        if (!N->closed[k]) continue;
        uint32_t h = N->stroke_roads[N->stroke_start[k]], t = N->stroke_roads[N->stroke_start[k + 1] - 1];
        uint32_t x = 2 * t + 1 - N->rev[t];
        link[2 * h] = x;
        link[x] = 2 * h;
    }
}

static int leg_eq(const rs_network_leg *a, const rs_network_leg *b)
{
    return a->road == b->road && a->kind == b->kind && a->segment == b->segment && a->s == b->s &&
           a->angle == b->angle && a->priority == b->priority && a->major == b->major;
}

/* A node's legs after the edit, where its end inside a surface changed. */
typedef struct re_node {
    uint32_t node, degree, control;
    uint8_t surf;
    rs_network_leg leg[3];
} re_node;

/* The point of the road's end at leg L (a start or an end leg). */
static const double *leg_point(const rs_roads *roads, const rs_network_leg *L)
{
    const double *exy;
    size_t enp;
    rs_roads_get(roads, L->road, NULL, NULL, &exy, &enp);
    return exy + 2 * (L->kind == RS_LEG_START ? 0 : enp - 1);
}

/* The free end of node nd of N (the network of `roads`; its one leg L, an
 * end leg of a record longer than two tolerances) inside the surface of
 * the nearest street: into *o (its legs, control and surface flag), from
 * the roads cand[0..nc) (NULL: all, ascending; `box`: per road, its
 * points' box). `control`: the node's control without the street's. */
static void free_end(const rs_roads *roads, const rs_network *N, const double *box, const uint32_t *cand, size_t nc,
                     uint32_t nd, const rs_network_leg *L, uint32_t control, re_node *o)
{
    const double tol = N->tol;
    surf_end f;
    memset(&f, 0, sizeof f);
    const double *p = leg_point(roads, L);
    f.node = nd, f.road = L->road, f.stroke = N->stroke_of[L->road];
    f.non_car = rs__road_non_car(roads, L->road);
    f.level = INT_MIN;
    f.x = p[0], f.y = p[1], f.q = f.k = NONE, f.u = 0, f.d = INFINITY;
    double pt[2] = { p[0], p[1] };
    uint32_t zero = 0;
    for (size_t c = 0; c < nc && isfinite(pt[0]) && isfinite(pt[1]); c++) {
        uint32_t q = cand ? cand[c] : (uint32_t)c;
        double rq = road_reach(roads, N, q, tol), reach2 = rq * rq;
        if (!(rq > 0) || !square_meets(box + 4 * (size_t)q, pt[0], pt[1], rq)) continue;
        const double *qxy;
        size_t qnp;
        rs_roads_get(roads, q, NULL, NULL, &qxy, &qnp);
        int qnc = -1, qlv = INT_MIN;
        for (size_t k = 0; k + 1 < qnp; k++) {
            const double *pa = qxy + 2 * k, *pb = pa + 2;
            double dx = pb[0] - pa[0], dy = pb[1] - pa[1], dd = dx * dx + dy * dy;
            if (!(dd > 0) || !(dd <= DBL_MAX)) continue;
            surf_test(roads, N, &f, &zero, pt, q, N->stroke_of[q], qxy, qnp, (uint32_t)k, pa, dx, dy, dd, reach2, &qnc, &qlv);
        }
    }
    o->node = nd;
    o->leg[0] = *L;
    o->leg[0].major = 1;
    o->degree = 1;
    o->control = control;
    o->surf = 0;
    if (f.q == NONE) return;
    const double *qxy;
    size_t qnp;
    rs_roads_get(roads, f.q, NULL, NULL, &qxy, &qnp);
    double s = 0, s0 = 0, s1 = 0; /* (summed as load_points sums them) */
    for (size_t k = 1; k <= f.k + 1; k++) {
        s = rs__arc_add(s, rs__arc_len(qxy[2 * k - 2], qxy[2 * k - 1], qxy[2 * k], qxy[2 * k + 1]));
        if (k == f.k) s0 = s;
        if (k == f.k + 1) s1 = s;
    }
    surf_legs(&f, qxy, qnp, s0, s1, rs__road_priority(roads, f.q), o->leg + 1);
    rs_network_node node;
    memset(&node, 0, sizeof node);
    node.control = control;
    surf_node(attr_is(roads, f.q, "junction", "roundabout", NULL), &node, o->leg, 3);
    o->degree = 3;
    o->control = node.control;
    o->surf = 1;
}

/* Node nd of N holds a free end for surface_tees (base: its legs without
 * a street's it ends inside): its end leg, else NULL. */
static const rs_network_leg *free_end_leg(const rs_network *N, const rs_network_leg *L, uint32_t d, int surf)
{
    if (d != (surf ? 3u : 1u)) return NULL;
    for (uint32_t k = 0; k < d; k++)
        if (rs__is_end_leg(&L[k])) return N->length[L[k].road] > 2 * N->tol ? &L[k] : NULL;
    return NULL;
}

rs_result rs__network_update(rs_ctx *ctx, const rs_roads *roads, const rs_network *N0, const uint32_t *m_old,
                             const uint32_t *m_new, const double *box, const double *zone, double reach,
                             rs_network **out)
{
    *out = NULL;
    const size_t nn = rs_roads_count(roads), no = N0->nroads, m = nn ? nn : 1;
    const double tol = N0->tol, G = reach + tol + 1.0;
    /* (a short record anywhere: a build with one joins places and chains
     * records across the map, bridge_short and chain_short_runs, and found
     * other T's away from it: fuzz/network) */
    if (!N0->node_key || N0->any_short || nn >= UINT32_MAX / 2 || !(G >= 0 && G <= 1e12)) return RS_OK;
    /* Zt: the nodes there are made anew from the roads in Za; a node
     * elsewhere with a point near the changed roads (Zn) is none the
     * network can keep or take: the whole build */
    double Zt[4], Za[4], Zn[4], Zc[4];
    grown(Zt, zone, G);
    grown(Za, zone, 3 * G);
    grown(Zn, zone, tol + 0.5);
    grown(Zc, Zt, G);
    rs_result res = RS_OK;
    int ok = 0;
    rs_roads *sub = NULL;
    rs_network *NA = NULL, *N = NULL;
    uint32_t *ids = rs__alloc_array(ctx, m, sizeof *ids), *amap = rs__alloc_array(ctx, m, sizeof *amap);
    uint32_t *l0 = rs__alloc_array(ctx, 2 * (no ? no : 1), sizeof *l0), *la = NULL;
    uint8_t *ends = rs__calloc(ctx, 2 * m, 1), *scratch = rs__calloc(ctx, m, 1);
    re_node *rep = NULL;
    size_t nrep = 0, crep = 0;
    if (!ids || !amap || !l0 || !ends || !scratch) goto nomem;
    /* (coordinates beyond 10^12 m: a build's rounding there finds ends
     * inside surfaces no box around the roads holds, fuzz/network) */
    const double big = 1e12;
    if (zone[0] <= zone[2] && !(fabs(zone[0]) <= big && fabs(zone[1]) <= big && fabs(zone[2]) <= big &&
                                fabs(zone[3]) <= big))
        goto done;
    size_t na = 0;
    for (size_t j = 0; j < nn; j++) {
        amap[j] = NONE;
        const double *b = box + 4 * j;
        if (b[0] <= b[2] && !(fabs(b[0]) <= big && fabs(b[1]) <= big && fabs(b[2]) <= big && fabs(b[3]) <= big))
            goto done;
        if (m_new[j] != NONE && (b[0] > Za[2] || b[2] < Za[0] || b[1] > Za[3] || b[3] < Za[1])) continue;
        const double *xy;
        size_t np;
        rs_roads_get(roads, j, NULL, NULL, &xy, &np);
        int in = m_new[j] == NONE;
        for (size_t k = 0; !in && k < np; k++) {
            const double *a = xy + 2 * k, *c = xy + 2 * (k + 1 < np ? k + 1 : k);
            in = rs__capsule_meets_box(a[0], a[1], c[0], c[1], 0, Za[0], Za[1], Za[2], Za[3]);
        }
        if (in) amap[j] = (uint32_t)na, ids[na++] = (uint32_t)j;
    }
    if (na > nn / 2 + 16) goto done; /* (most of the map: the whole build) */
    if (na) {
        rs_network_options opt;
        memset(&opt, 0, sizeof opt);
        opt.tolerance = tol;
        if ((res = rs__roads_subset(ctx, roads, ids, na, &sub)) != RS_OK ||
            (res = network_build(ctx, sub, &opt, NB_NO_SURF | NB_NO_SHORT, &NA)) != RS_OK)
            goto done;
        if (!NA) goto done; /* (a short record near the edit) */
    }
    /* the nodes kept and taken, and their legs: room for all of both (each
     * node is checked as the merge below comes to it) */
    size_t nodes = N0->nnodes + (NA ? NA->nnodes : 0), legs = N0->nlegs + (NA ? NA->nlegs : 0);
    if (nodes >= UINT32_MAX || legs + 4 >= UINT32_MAX) goto done;
    if (!(N = rs__calloc(ctx, 1, sizeof *N))) goto nomem;
    N->nroads = nn;
    N->tol = tol;
    N->node = rs__alloc_array(ctx, nodes ? nodes : 1, sizeof *N->node);
    N->leg_start = rs__alloc_array(ctx, nodes + 1, sizeof *N->leg_start);
    N->leg = rs__alloc_array(ctx, legs ? legs : 1, sizeof *N->leg);
    N->link = rs__alloc_array(ctx, 2 * m, sizeof *N->link);
    N->node_key = rs__alloc_array(ctx, nodes ? nodes : 1, sizeof *N->node_key);
    N->node_rad = rs__alloc_array(ctx, nodes ? nodes : 1, sizeof *N->node_rad);
    N->node_surf = rs__calloc(ctx, nodes ? nodes : 1, 1);
    if (!N->node || !N->leg_start || !N->leg || !N->link || !N->node_key || !N->node_rad || !N->node_surf ||
        !stroke_arrays(ctx, N, m, nn + 1))
        goto nomem;
    /* merged in the order of their lowest points (the road order is kept:
     * the numbering a build of the new roads gives) */
    {
        size_t d0 = 0, da = 0, nd = 0, nl = 0, nA = NA ? NA->nnodes : 0;
        for (;;) {
            /* an old node is made anew inside Zt; kept outside it, where
             * it must be finite and clear of Zn, its roads all still there
             * (below). A local node is taken inside Zt, whole inside Zc;
             * outside Zt it must be clear of Zn. */
            for (; d0 < N0->nnodes; d0++) {
                const rs_network_node *v = &N0->node[d0];
                if (!isfinite(v->x) || !isfinite(v->y)) goto done;
                if (!in_box(Zt, v->x, v->y)) break;
            }
            if (d0 < N0->nnodes && (!(N0->node_rad[d0] >= 0) || square_meets(Zn, N0->node[d0].x, N0->node[d0].y, N0->node_rad[d0])))
                goto done;
            for (; da < nA; da++) {
                const rs_network_node *v = &NA->node[da];
                if (!isfinite(v->x) || !isfinite(v->y) || !(NA->node_rad[da] >= 0)) goto done;
                if (in_box(Zt, v->x, v->y)) break;
                if (square_meets(Zn, v->x, v->y, NA->node_rad[da])) goto done;
            }
            if (da < nA && !square_inside(Zc, NA->node[da].x, NA->node[da].y, NA->node_rad[da])) goto done;
            if (d0 == N0->nnodes && da == nA) break;
            uint64_t k0 = UINT64_MAX, ka = UINT64_MAX;
            if (d0 < N0->nnodes) {
                uint32_t r = m_old[N0->node_key[d0] >> 32];
                if (r == NONE) goto done;
                k0 = (uint64_t)r << 32 | (N0->node_key[d0] & 0xffffffffu);
            }
            if (da < nA) ka = (uint64_t)ids[NA->node_key[da] >> 32] << 32 | (NA->node_key[da] & 0xffffffffu);
            if (k0 == ka) goto done;
            const rs_network *S = k0 < ka ? N0 : NA;
            size_t d = k0 < ka ? d0++ : da++;
            const uint32_t *map = S == N0 ? m_old : ids;
            N->node[nd] = S->node[d];
            N->node_key[nd] = k0 < ka ? k0 : ka;
            N->node_rad[nd] = S->node_rad[d];
            N->node_surf[nd] = S->node_surf[d];
            N->leg_start[nd] = (uint32_t)nl;
            /* (the node's legs in one copy: a struct copy a leg was a
             * string move, most of the merge) */
            uint32_t g0 = S->leg_start[d], g1 = S->leg_start[d + 1];
            if (g1 > g0) memcpy(&N->leg[nl], &S->leg[g0], (size_t)(g1 - g0) * sizeof *N->leg);
            for (uint32_t l = g0; l < g1; l++) {
                /* (read from the source: a field just stored by the copy's
                 * wide stores is read back past store forwarding) */
                const rs_network_leg *L = &S->leg[l];
                uint32_t rd = map[L->road];
                if (rd == NONE) goto done; /* (a kept node of a road gone) */
                N->leg[nl++].road = rd;
                if (!rs__is_end_leg(L)) continue;
                uint32_t e = 2 * rd + (L->kind == RS_LEG_END); /* (rs__leg_end of the new leg) */
                if (ends[e]) goto done; /* (an end at two nodes) */
                ends[e] = 1;
            }
            nd++;
        }
        N->leg_start[nd] = (uint32_t)nl;
        N->nnodes = nd;
        N->nlegs = nl;
    }
    /* every end that has a leg in the old network or the local one has one
     * (the kept nodes' ends are marked above) */
    for (size_t d = 0; d < N0->nnodes; d++) {
        if (!in_box(Zt, N0->node[d].x, N0->node[d].y)) continue;
        for (uint32_t l = N0->leg_start[d]; l < N0->leg_start[d + 1]; l++) {
            const rs_network_leg *L = &N0->leg[l];
            if (rs__is_end_leg(L) && m_old[L->road] != NONE && !ends[2 * m_old[L->road] + (L->kind == RS_LEG_END)])
                goto done;
        }
    }
    for (size_t d = 0; NA && d < NA->nnodes; d++)
        for (uint32_t l = NA->leg_start[d]; l < NA->leg_start[d + 1]; l++) {
            const rs_network_leg *L = &NA->leg[l];
            if (rs__is_end_leg(L) && !ends[2 * ids[L->road] + (L->kind == RS_LEG_END)]) goto done;
        }
    /* the links: the old ones, those at the nodes made anew from the local
     * network's; then the strokes as a build numbers them */
    uncut_links(N0, l0);
    if (NA) {
        if (!(la = rs__alloc_array(ctx, 2 * NA->nroads, sizeof *la))) goto nomem;
        uncut_links(NA, la);
    }
    for (size_t j = 0; j < nn; j++) {
        uint32_t i = m_new[j];
        N->prev[j] = N->next[j] = NONE;
        N->length[j] = i != NONE ? N0->length[i] : NA->length[amap[j]];
        for (int e = 0; e < 2; e++) {
            uint32_t x = i == NONE ? NONE : l0[2 * i + e];
            N->link[2 * j + e] = x == NONE ? NONE : m_old[x / 2] == NONE ? NONE - 1 : 2 * m_old[x / 2] + x % 2;
        }
    }
    for (size_t d = 0; NA && d < NA->nnodes; d++) {
        if (!in_box(Zt, NA->node[d].x, NA->node[d].y)) continue;
        for (uint32_t l = NA->leg_start[d]; l < NA->leg_start[d + 1]; l++) {
            const rs_network_leg *L = &NA->leg[l];
            if (!rs__is_end_leg(L)) continue;
            uint32_t x = la[rs__leg_end(L)];
            N->link[2 * ids[L->road] + (L->kind == RS_LEG_END)] = x == NONE ? NONE : 2 * ids[x / 2] + x % 2;
        }
    }
    for (size_t e = 0; e < 2 * nn; e++) {
        uint32_t x = N->link[e];
        if (x != NONE && (x >= 2 * nn || N->link[x] != e)) goto done; /* (a removed road's, or one-sided) */
    }
    number_strokes(N, N->link, scratch);
    /* the free ends inside a street's surface: at the nodes made anew; at
     * the kept nodes whose end or a street near it changed strokes (the
     * rule reads the strokes, rings and free ends of both) */
    {
        uint8_t *dq = scratch; /* per road: in a stroke that changed */
        memset(dq, 0, nn);
        double db[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
        size_t nd_q = 0;
        for (size_t k = 0; k < N->nstrokes; k++) {
            uint32_t a = N->stroke_start[k], b = N->stroke_start[k + 1];
            uint32_t i0 = m_new[N->stroke_roads[a]];
            int ch = i0 == NONE;
            uint32_t s0 = ch ? 0 : N0->stroke_of[i0];
            ch = ch || N0->stroke_start[s0 + 1] - N0->stroke_start[s0] != b - a || N0->closed[s0] != N->closed[k];
            for (uint32_t e = a; e < b && !ch; e++) {
                uint32_t j = N->stroke_roads[e], i = m_new[j];
                ch = i == NONE || N0->stroke_of[i] != s0;
                for (int f = 0; f < 2 && !ch; f++) {
                    uint32_t x = N0->link[2 * i + f];
                    ch = (x == NONE ? NONE : 2 * m_old[x / 2] + x % 2) != N->link[2 * j + f];
                }
            }
            for (uint32_t e = a; e < b && ch; e++) {
                uint32_t j = N->stroke_roads[e];
                dq[j] = 1, nd_q++;
                db[0] = fmin(db[0], box[4 * j]), db[1] = fmin(db[1], box[4 * j + 1]);
                db[2] = fmax(db[2], box[4 * j + 2]), db[3] = fmax(db[3], box[4 * j + 3]);
            }
        }
        uint32_t *dl = nd_q ? rs__alloc_array(ctx, nd_q, sizeof *dl) : NULL;
        if (nd_q && !dl) goto nomem;
        for (size_t j = 0, k = 0; j < nn && nd_q; j++)
            if (dq[j]) dl[k++] = (uint32_t)j;
        double dg[4];
        grown(dg, db, G);
        /* the nodes whose free end is tested again, in node order (bit 31:
         * made anew); the kept ones test only the roads whose reach meets
         * the box of their end points (the same roads pass, in the same
         * order: a 21 m road's move tested every road of the map from each
         * kept end near its stroke) */
        uint32_t *todo = NULL, *kc = NULL;
        size_t ntodo = 0, ctodo = 0, nkc = 0;
        double pb[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
        for (uint32_t d = 0; d < N->nnodes; d++) {
            const rs_network_leg *L = N->leg + N->leg_start[d];
            uint32_t deg = N->leg_start[d + 1] - N->leg_start[d];
            const rs_network_node *v = &N->node[d];
            int fresh = in_box(Zt, v->x, v->y);
            const rs_network_leg *E = free_end_leg(N, L, deg, N->node_surf[d]);
            if (!E) continue;
            if (!fresh) {
                /* kept: the same unless its stroke or a street's near it changed */
                int near = dq[E->road];
                for (size_t k = 0; !near && k < nd_q && in_box(dg, v->x, v->y); k++)
                    near = square_meets(box + 4 * (size_t)dl[k], v->x, v->y, G);
                if (!near) continue;
                const double *p = leg_point(roads, E);
                if (isfinite(p[0]) && isfinite(p[1])) {
                    pb[0] = fmin(pb[0], p[0]), pb[1] = fmin(pb[1], p[1]);
                    pb[2] = fmax(pb[2], p[0]), pb[3] = fmax(pb[3], p[1]);
                }
            }
            void *arr = todo;
            if ((res = rs__grow(ctx, &arr, ntodo, &ctodo, sizeof *todo, 16, SIZE_MAX / sizeof *todo)) != RS_OK) {
                rs__free(ctx, todo);
                rs__free(ctx, dl);
                goto done;
            }
            todo = arr;
            todo[ntodo++] = d | (fresh ? 0x80000000u : 0);
        }
        if (pb[0] <= pb[2]) {
            if (!(kc = rs__alloc_array(ctx, m, sizeof *kc))) {
                rs__free(ctx, todo);
                rs__free(ctx, dl);
                goto nomem;
            }
            for (size_t q = 0; q < nn; q++) {
                /* (square_meets of an end point in pb: rounding is monotone) */
                double rq = road_reach(roads, N, q, tol);
                const double *b = box + 4 * q;
                if (rq > 0 && pb[2] + rq >= b[0] && pb[0] - rq <= b[2] && pb[3] + rq >= b[1] && pb[1] - rq <= b[3])
                    kc[nkc++] = (uint32_t)q;
            }
        }
        for (size_t t = 0; t < ntodo; t++) {
            uint32_t d = todo[t] & 0x7FFFFFFFu;
            int fresh = (todo[t] >> 31) != 0;
            const rs_network_leg *L = N->leg + N->leg_start[d];
            uint32_t deg = N->leg_start[d + 1] - N->leg_start[d];
            const rs_network_node *v = &N->node[d];
            const rs_network_leg *E = free_end_leg(N, L, deg, N->node_surf[d]);
            void *arr = rep;
            if ((res = rs__grow(ctx, &arr, nrep, &crep, sizeof *rep, 16, SIZE_MAX / sizeof *rep)) != RS_OK) {
                rs__free(ctx, todo);
                rs__free(ctx, kc);
                rs__free(ctx, dl);
                goto done;
            }
            rep = arr;
            re_node *o = &rep[nrep];
            uint32_t ctl = (v->control & ~(uint32_t)RS_NODE_ROUNDABOUT);
            const char *jc = rs_roads_get_attr(roads, E->road, "junction");
            if (jc && strcmp(jc, "roundabout") == 0) ctl |= RS_NODE_ROUNDABOUT;
            free_end(roads, N, box, fresh ? ids : kc, fresh ? na : nkc, d, E, ctl, o);
            int same = o->degree == deg && o->control == v->control && o->surf == N->node_surf[d];
            for (uint32_t k = 0; k < deg && same; k++) same = leg_eq(&o->leg[k], &L[k]);
            nrep += !same;
        }
        rs__free(ctx, todo);
        rs__free(ctx, kc);
        rs__free(ctx, dl);
    }
    if (nrep) { /* the changed nodes' legs in place (rep is in node order) */
        size_t nl = N->nlegs;
        for (size_t k = 0; k < nrep; k++) {
            nl += rep[k].degree;
            nl -= N->leg_start[rep[k].node + 1] - N->leg_start[rep[k].node];
        }
        rs_network_leg *leg = rs__alloc_array(ctx, nl ? nl : 1, sizeof *leg);
        if (!leg) goto nomem;
        /* (the nodes between two changed ones in one copy, their starts
         * moved by the legs the changed ones before them gained or lost) */
        size_t at = 0;
        uint32_t d0 = 0;
        for (size_t k = 0; k <= nrep; k++) {
            uint32_t d1 = k < nrep ? rep[k].node : (uint32_t)N->nnodes;
            uint32_t a = N->leg_start[d0], b = N->leg_start[d1];
            if (b > a) memcpy(leg + at, N->leg + a, (size_t)(b - a) * sizeof *leg);
            const uint32_t delta = (uint32_t)at - a; /* (mod 2^32: the starts stay below nl) */
            for (uint32_t d = d0; d < d1; d++) N->leg_start[d] += delta;
            at += b - a;
            if (k == nrep) break;
            uint32_t d = d1; /* (its old legs skipped; the next run reads the old starts after it) */
            N->leg_start[d] = (uint32_t)at;
            memcpy(leg + at, rep[k].leg, rep[k].degree * sizeof *leg);
            at += rep[k].degree;
            N->node[d].degree = rep[k].degree;
            N->node[d].kind = rep[k].degree <= 1 ? RS_NODE_END : RS_NODE_JUNCTION;
            N->node[d].control = rep[k].control;
            N->node_surf[d] = rep[k].surf;
            d0 = d + 1;
        }
        N->leg_start[N->nnodes] = (uint32_t)at;
        rs__free(ctx, N->leg);
        N->leg = leg;
        N->nlegs = at;
    }
    N->bytes = bytes_of(N);
    ok = 1;
    goto done;
nomem:
    res = RS_ERR_NOMEM;
done:
    if (ok && !res) *out = N;
    else rs_network_free(ctx, N);
    rs_network_free(ctx, NA);
    rs_roads_free(ctx, sub);
    rs__free(ctx, ids);
    rs__free(ctx, amap);
    rs__free(ctx, l0);
    rs__free(ctx, la);
    rs__free(ctx, ends);
    rs__free(ctx, scratch);
    rs__free(ctx, rep);
    return res ? rs__fail(ctx, res, res == RS_ERR_CANCELLED ? "cancelled" : "network update: out of memory") : RS_OK;
}

int rs__network_equal(const rs_network *a, const rs_network *b)
{
    if (a->nroads != b->nroads || a->nnodes != b->nnodes || a->nlegs != b->nlegs || a->nstrokes != b->nstrokes ||
        a->tol != b->tol || (!a->node_key) != (!b->node_key))
        return 0;
    for (size_t d = 0; d < a->nnodes; d++) {
        const rs_network_node *p = &a->node[d], *q = &b->node[d];
        if (p->x != q->x || p->y != q->y || p->degree != q->degree || p->kind != q->kind || p->control != q->control ||
            a->leg_start[d] != b->leg_start[d])
            return 0;
        if (a->node_key && (a->node_key[d] != b->node_key[d] || a->node_rad[d] != b->node_rad[d] ||
                            a->node_surf[d] != b->node_surf[d]))
            return 0;
    }
    if (a->leg_start[a->nnodes] != b->leg_start[b->nnodes]) return 0;
    for (size_t l = 0; l < a->nlegs; l++)
        if (!leg_eq(&a->leg[l], &b->leg[l])) return 0;
    size_t n = a->nroads;
    if (memcmp(a->stroke_start, b->stroke_start, (a->nstrokes + 1) * sizeof *a->stroke_start) ||
        memcmp(a->closed, b->closed, a->nstrokes) || memcmp(a->stroke_of, b->stroke_of, n * sizeof *a->stroke_of) ||
        memcmp(a->s_off, b->s_off, n * sizeof *a->s_off) || memcmp(a->length, b->length, n * sizeof *a->length) ||
        memcmp(a->s_len, b->s_len, n * sizeof *a->s_len) ||
        memcmp(a->prev, b->prev, n * sizeof *a->prev) || memcmp(a->next, b->next, n * sizeof *a->next) ||
        memcmp(a->stroke_roads, b->stroke_roads, n * sizeof *a->stroke_roads) || memcmp(a->rev, b->rev, n) ||
        memcmp(a->link, b->link, 2 * n * sizeof *a->link))
        return 0;
    return 1;
}
