/* Road field: index grid, nearest-centreline queries and analytic pixel
 * coverage (docs/roadfield.md).
 *
 * Every road is cut into segments ("capsules": the points within the half
 * width of a segment). A uniform grid over the map (plus one cell on every
 * side) lists per cell, in CSR form, the segments whose capsule grown by
 * `reach` (reach_extra + half a pixel diagonal) touches the cell, in
 * ascending segment order. A query at a point then needs exactly one cell's
 * list: an empty list answers "no road" in O(1). */
#include "roadfield.h"
#include "road_local.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include "avx512.h"

#define HALF_SQRT2 0.70710678118654752440
/* Sub-squares per pixel side where a pixel's coverage is not one straight
 * edge (caps, joins, crossings); docs/roadfield.md has the measurements. */
#define SUBDIV 3
/* Distinct segments near one pixel's boundary kept on the stack; more
 * falls back to using every candidate (same result, slower). */
#define NEAR_MAX 32
/* cos of the largest turn joint_cover handles without sub-squares */
#define JOINT_COS 0.94
/* Cell counts: the automatic cell grows until the grid has at most AUTO
 * cells; an explicit cell is grown (never shrunk) to at most MAX cells. */
#define GRID_AUTO_CELLS ((double)(1u << 22))
#define GRID_MAX_CELLS ((double)(1u << 24))
/* rs__roadfield_coverage2: where f's cover is within this of 1, g's
 * complex covers are skipped (below a quarter of an 8-bit level) */
#define CASING_SKIP (1.0 / 1024)

typedef struct rf_seg {
    double ax, ay, bx, by; /* end points, local metres */
    double ux, uy, len;    /* unit direction ((0,0) for a zero-length segment), length */
    double r;              /* half width */
    double s0;             /* arc length of the road at (ax, ay) */
    double tol;            /* distance slack of the row spans (coverage), metres */
    /* coverage constants (docs/roadfield.md): ga >= gb = the larger and the
     * smaller of |ux|, |uy| (gb = 0 below 1e-100), iga = 1/ga, igab =
     * 1/(ga gb) (0 when gb = 0), l1 = |ux| + |uy|; iux, iuy = 1/ux, 1/uy
     * (0 for a component below 1e-100) */
    double ga, gb, iga, igab, l1, iux, iuy;
    uint32_t road, seg;
    /* jnext = 1: segment jpart continues this one (a gentle joint,
     * joint_cover); redundant = 1: the capsule lies within another one
     * (near_keep) */
    uint32_t jpart;
    uint8_t jnext, redundant;
    uint8_t tee; /* bit 0: its start a is a trimmed T end, bit 1: its end b, bit 2: clipped by its
                    record's T end's line (rs__roadfield_set_tees) */
    uint8_t unlisted; /* 1: in no cell list, too far from the field's window (seg_unlisted) */
} rf_seg;

struct rs__roadfield {
    double c, inv_c;   /* index cell (metres) and its inverse */
    uint32_t gw, gh;   /* cells; cell (i, j) spans [(i-1)c, ic) x [(j-1)c, jc) */
    double pixel;      /* largest pixel the one-cell paths are valid for */
    double margin;     /* pixel * sqrt(2)/2 */
    double reach;      /* reach_extra + margin: list reach beyond a half width */
    double reach_extra;
    uint32_t *start;   /* gw*gh + 1 offsets into ids */
    uint32_t *ids;     /* segment indices, ascending per cell */
    uint8_t *full;     /* 1: every pixel whose centre is in the cell is fully road */
    uint32_t *rstart;  /* gh + 1 offsets into rids */
    uint32_t *rids;    /* per grid row: every segment listed in a cell of the row, once */
    float *rbox;       /* per rids entry: x lo, x hi, y lo, y hi of the centreline box grown by
                        * r + tol + margin, rounded outwards (rows with spans only) */
    uint8_t *rspan;    /* per grid row: 1 when the row spans are valid (every segment of moderate size) */
    uint32_t *colpix;  /* gw + 1 entries or NULL: colpix[i] = first pixel index p >= 0 whose centre
                        * (p + 0.5) pixel has cell_of column >= i (colpix[gw]: first outside the
                        * grid), for pixels of exactly `pixel` */
    rf_seg *seg;
    size_t nseg, nent, bytes;
    /* per road + 1 (or NULL): its first segment in seg, the next road's
     * first ending its run (rs__roadfield_build; a T end's segment is
     * found in its road's run, not by a search of the whole array) */
    uint32_t *rfirst;
    size_t nrfirst;
    size_t nonempty, nfull, maxlist;
    size_t nredundant; /* segments with redundant = 1 */
    uint64_t relwork;  /* seg_relations' work units */
    uint32_t relscan;  /* cell lists up to this long are scanned for holders (rs__roadfield_params) */
    /* T ends (rs__roadfield_set_tees): ascending by (segment, end) */
    struct rf_tee *tee;
    size_t ntee;
    uint32_t *tstart, *tids; /* per grid row (gh + 1 offsets): the tees whose box meets the row */
    /* the window (rs__roadfield_params.window): the segments too far from
     * it are kept in seg (every id, joint and T as without it) but listed
     * in no cell */
    int window_on;
    double window[4], window_reach;
    size_t nunlisted;
};

/* fmax and fmin with glibc's values (x on a tie, the other one when one
 * is NaN), inlined: the libm calls were ~7 % of an index build. */
static inline double lm_max(double x, double y) { return x >= y || y != y ? x : y; }
static inline double lm_min(double x, double y) { return x <= y || y != y ? x : y; }

/* A segment's centreline box, from its end points (not stored: 32 bytes a
 * segment were a sixth of the array and of the build's first-touch page
 * faults) */
#define SEG_XMIN(s) lm_min((s)->ax, (s)->bx)
#define SEG_XMAX(s) lm_max((s)->ax, (s)->bx)
#define SEG_YMIN(s) lm_min((s)->ay, (s)->by)
#define SEG_YMAX(s) lm_max((s)->ay, (s)->by)

/* Reads of a segment's data by list order (row lists, holder boxes) jump
 * over arrays of megabytes on a dense map: ask for them a few entries
 * ahead (a hint; no effect on results). */
#define PREFETCH_AHEAD 8

/* floor(v) clamped to [0, n-1]; NaN gives 0. Keeps every cast defined. */
static uint32_t clamp_index(double v, uint32_t n)
{
    if (!(v >= 0)) return 0;
    if (v >= (double)n) return n - 1;
    return (uint32_t)v;
}

/* Grid column/row of a coordinate, or -1 outside the grid. */
static int64_t cell_of(const rs__roadfield *f, double v, uint32_t n)
{
    double k = floor(v * f->inv_c) + 1.0;
    if (!(k >= 0 && k < (double)n)) return -1;
    return (int64_t)k;
}

static double len2(double dx, double dy)
{
    double d2 = dx * dx + dy * dy;
    /* huge coordinates: the square overflows, hypot does not */
    return d2 < 1e300 ? sqrt(d2) : hypot(dx, dy);
}

/* Distance from (x, y) to the segment; *pr = clamped projection (arc length
 * from a), *side = signed offset from the segment's line along its left
 * normal (uy, -ux) (SPEC: + = left of travel). */
static double seg_point(const rf_seg *s, double x, double y, double *pr, double *side)
{
    double wx = x - s->ax, wy = y - s->ay, p = wx * s->ux + wy * s->uy, qx, qy;
    *side = wx * s->uy - wy * s->ux;
    if (!(p > 0)) { p = 0; qx = s->ax; qy = s->ay; }
    else if (p >= s->len) { p = s->len; qx = s->bx; qy = s->by; }
    else { qx = s->ax + p * s->ux; qy = s->ay + p * s->uy; }
    *pr = p;
    return len2(x - qx, y - qy);
}

/* seg_point's distance alone (the same operations: the same double) and
 * the nearest point, inlined: the index build asks it for every cell a
 * segment may touch. */
static inline double seg_near(const rf_seg *s, double x, double y, double *qxo, double *qyo)
{
    double wx = x - s->ax, wy = y - s->ay, p = wx * s->ux + wy * s->uy, qx, qy;
    if (!(p > 0)) { qx = s->ax; qy = s->ay; }
    else if (p >= s->len) { qx = s->bx; qy = s->by; }
    else { qx = s->ax + p * s->ux; qy = s->ay + p * s->uy; }
    *qxo = qx;
    *qyo = qy;
    return len2(x - qx, y - qy);
}

/* seg_near's squared distance (len2 takes its root, or hypot from 1e300) */
static inline double seg_near2(const rf_seg *s, double x, double y, double *qxo, double *qyo)
{
    double wx = x - s->ax, wy = y - s->ay, p = wx * s->ux + wy * s->uy, qx, qy;
    if (!(p > 0)) { qx = s->ax; qy = s->ay; }
    else if (p >= s->len) { qx = s->bx; qy = s->by; }
    else { qx = s->ax + p * s->ux; qy = s->ay + p * s->uy; }
    *qxo = qx;
    *qyo = qy;
    double dx = x - qx, dy = y - qy;
    return dx * dx + dy * dy;
}

static inline double seg_dist(const rf_seg *s, double x, double y)
{
    double qx, qy;
    return seg_near(s, x, y, &qx, &qy);
}

/* ------------------------------------------------------------------------
 * Build
 * ---------------------------------------------------------------------- */

/* Does the rectangle [x0,x1] x [y0,y1] come within R of the segment? */
static int seg_touches_rect(const rf_seg *s, double x0, double y0, double x1, double y1, double R)
{
    if (lm_min(s->ax, s->bx) - R > x1 || lm_max(s->ax, s->bx) + R < x0 || lm_min(s->ay, s->by) - R > y1 ||
        lm_max(s->ay, s->by) + R < y0)
        return 0;
    /* Intersection by separating axes: x and y passed above with R = 0
     * when the bounding boxes overlap; the last axis is the segment normal. */
    int boxes = !(lm_min(s->ax, s->bx) > x1 || lm_max(s->ax, s->bx) < x0 || lm_min(s->ay, s->by) > y1 ||
                  lm_max(s->ay, s->by) < y0);
    if (boxes) {
        double c[4] = { (x0 - s->ax) * s->uy - (y0 - s->ay) * s->ux, (x1 - s->ax) * s->uy - (y0 - s->ay) * s->ux,
                        (x0 - s->ax) * s->uy - (y1 - s->ay) * s->ux, (x1 - s->ax) * s->uy - (y1 - s->ay) * s->ux };
        int pos = c[0] > 0 && c[1] > 0 && c[2] > 0 && c[3] > 0, neg = c[0] < 0 && c[1] < 0 && c[2] < 0 && c[3] < 0;
        if (!pos && !neg) return 1;
    }
    /* Disjoint convex sets: the closest pair has a vertex of one of them. */
    const double px[2] = { s->ax, s->bx }, py[2] = { s->ay, s->by };
    for (int k = 0; k < 2; k++) {
        double dx = lm_max(lm_max(x0 - px[k], px[k] - x1), 0), dy = lm_max(lm_max(y0 - py[k], py[k] - y1), 0);
        if (len2(dx, dy) <= R) return 1;
    }
    return seg_dist(s, x0, y0) <= R || seg_dist(s, x1, y0) <= R || seg_dist(s, x0, y1) <= R ||
           seg_dist(s, x1, y1) <= R;
}

/* Memory a later step may write into instead of allocating its own: the
 * pass-1 record once the lists are filled (4 bytes an entry, ~35 bytes a
 * segment on the city). On 10^5 roads the boxes of the holder search and
 * the row lists' temporaries would otherwise be ~36 MB of fresh pages a
 * build (69 k -> 60 k page faults). */
typedef struct rf_scratch {
    void *p;
    size_t bytes;
} rf_scratch;

typedef struct rf_builder {
    rs__roadfield *f;
    uint32_t *cnt;   /* per cell: count (pass 1), then end cursor (pass 2) */
    uint64_t total;  /* entries so far */
    uint64_t limit;
    uint32_t *cell1; /* pass 2: per segment, a cell that lists it */
    uint64_t work_limit; /* seg_relations' work (rs_limits.max_field_work) */
    int work_over;       /* 1: seg_relations passed work_limit */
    /* Pass 1 records the cells it visits (rec, segment after segment, in
     * visiting order; recend[k] = end of segment k's run), so that pass 2
     * only scatters them instead of doing the geometry again. When memory
     * for the record runs out, norec = 1 and pass 2 recomputes. */
    rs_ctx *ctx;
    uint32_t *rec, *recend;
    size_t nrec, caprec, caprecend;
    /* pass 1, per recorded segment: the first cell it visits whose column
     * and row are even (else its last cell), its cell1 (the holder search
     * then gathers about a quarter of the lists) */
    uint32_t *pref, pcell;
    rf_scratch scratch; /* the record's memory after the fill, freed with the builder */
    size_t seg0, rec0; /* first capacities of recend/pref and of the record (grown by doubling) */
    /* pass 1's segments in all (kept or not; 0: unknown), and those it has
     * gone through, the one at hand included */
    size_t seg_all, seg_pass;
    int norec;
} rf_builder;

/* n * size bytes: from sc when they fit (*own = 0), else newly allocated
 * (*own = 1); NULL when out of memory. */
static void *scratch_take(rs_ctx *ctx, const rf_scratch *sc, size_t n, size_t size, int *own)
{
    size_t bytes;
    *own = 0;
    if (sc && sc->p && rs__mul_size(n, size, &bytes) && bytes <= sc->bytes) return sc->p;
    *own = 1;
    return rs__alloc_array(ctx, n, size);
}

static void rec_drop(rf_builder *b)
{
    rs__free(b->ctx, b->rec);
    rs__free(b->ctx, b->recend);
    rs__free(b->ctx, b->pref);
    b->rec = b->recend = b->pref = NULL;
    b->nrec = b->caprec = b->caprecend = 0;
    b->norec = 1;
}

/* What pass 1's segments so far foretell for the record of all of them
 * (a quarter more; 0 when too few are seen to tell). */
static double rec_foretold(const rf_builder *b)
{
    /* (a field of fewer than 1024 segments grows by doubling: its copies are small) */
    if (b->seg_pass < 256 || b->seg_all < 1024 || b->seg_all <= b->seg_pass) return 0;
    /* (by the segments gone through, kept or not: a map over a part of
     * the roads keeps a part of them, and that part is foretold) */
    double want = (double)b->nrec / (double)b->seg_pass * (double)b->seg_all * 1.25 + 4096;
    /* (at most 64 times the record's room so far: first segments far
     * denser than the rest would ask the allocator for far more than the
     * field needs; past that, the record grows by steps of 64) */
    double room = 64.0 * (double)(b->caprec ? b->caprec : b->rec0);
    if (want > room) want = room;
    return want > (double)b->limit + 1 ? (double)b->limit + 1 : want;
}

/* Room for nc recorded cells: 1, or 0 with the record as it was (no
 * memory, or a stop during the copy: rs__resize copies blocks of 2 to 32
 * MB in polled pieces, and the build's next tick sees the stop). */
static int rec_grow(rf_builder *b, size_t nc)
{
    size_t bytes;
    void *arr = b->rec;
    if (!rs__mul_size(nc, sizeof *b->rec, &bytes) || rs__resize(b->ctx, &arr, b->caprec * sizeof *b->rec, bytes))
        return 0;
    b->rec = arr;
    b->caprec = nc;
    return 1;
}

/* Records one visited cell (pass 1). The record grows by doubling, or to
 * what the segments so far foretell when that is more, and is checked
 * against that at every power of two of segments from 256 on (rec_end):
 * a doubling copies the record so far, and one of 16 MB at 10^5 roads
 * took up to 54 ms into fresh pages under glibc's realloc, with no
 * progress call in it (issue 30 target 4); foretold early, the copies are
 * small (16 kB, 32 kB and 2 MB on the index bench's 10^5 roads), and one
 * of 2 to 32 MB is polled (rec_grow). */
static void rec_cell(rf_builder *b, size_t cell)
{
    if (b->norec) return;
    if (b->nrec == b->caprec) {
        double want = rec_foretold(b);
        size_t dbl = b->caprec ? 2 * b->caprec : b->rec0;
        /* (the foretold size, else a doubling, else pass 2 works without) */
        if (!(want > (double)dbl && rec_grow(b, (size_t)want)) && !rec_grow(b, dbl)) {
            rec_drop(b);
            return;
        }
    }
    b->rec[b->nrec++] = (uint32_t)cell;
}

/* Closes segment k's run of recorded cells (segments are numbered 0, 1, ...). */
static void rec_end(rf_builder *b, size_t k)
{
    if (b->norec) return;
    if (k >= b->caprecend) {
        size_t nc = b->caprecend ? 2 * b->caprecend : b->seg0, bytes;
        uint32_t *nr = rs__mul_size(nc, sizeof *nr, &bytes) ? rs__realloc(b->ctx, b->recend, bytes) : NULL;
        if (nr) b->recend = nr;
        uint32_t *np = nr ? rs__realloc(b->ctx, b->pref, bytes) : NULL;
        if (!np) { rec_drop(b); return; }
        b->pref = np;
        b->caprecend = nc;
    }
    b->recend[k] = (uint32_t)b->nrec;
    b->pref[k] = b->pcell;
    if (((k + 1) & k) == 0) { /* (k + 1 recorded segments, a power of two) */
        /* (only when the last foretelling fell short by its quarter: each
         * growth copies the block) */
        double want = rec_foretold(b);
        if (want > 1.25 * (double)b->caprec) (void)rec_grow(b, (size_t)want); /* (or later, by doubling) */
    }
}

/* Visit every cell whose rectangle comes within s->r + f->reach of the
 * segment. fill = 0: count (and flag full cells); fill = 1: write `id` into
 * the lists (cursors count down); fill = 2: only whether there is one (1 at
 * the first, nothing written). Returns the cells visited, or -1 when the
 * entry limit is passed. */
static double seg_mag(const rf_seg *s);

static int64_t seg_cells(rf_builder *b, const rf_seg *s, int fill, uint32_t id)
{
    rs__roadfield *f = b->f;
    double c = f->c, eps = 1e-6 * c;
    double R = s->r + f->reach + eps;      /* may be huge or inf: only compared */
    double rin = s->r - f->margin - eps;   /* corners within rin: the cell is full */
    double hd = c * HALF_SQRT2 * (1 + 1e-9); /* half the cell diagonal */
    /* R less a slack of 1e-9 of every magnitude in play (NaN or -inf for a
     * huge R: the shortcut then never applies) */
    const double mag = 1 + seg_mag(s) + ((double)f->gw + (double)f->gh + 2) * c;
    double Rsure = R - 1e-9 * (mag + R);
    double gy1 = ((double)f->gh - 1) * c, gx1 = ((double)f->gw - 1) * c;
    /* A cell is whole inside the road only if its centre is within rin -
     * c / 2 (the corner farthest across the nearest point's normal is c /
     * 2 further): the corners are not measured beyond that (plus a slack
     * above the roundings: the same cells come out full). */
    double rfull = rin - 0.5 * c + 1e-9 * (mag + fabs(rin));
    double ylo = lm_max(lm_min(s->ay, s->by) - R, -c), yhi = lm_min(lm_max(s->ay, s->by) + R, gy1);
    double xlo = lm_max(lm_min(s->ax, s->bx) - R, -c), xhi = lm_min(lm_max(s->ax, s->bx) + R, gx1);
    if (!(ylo <= yhi && xlo <= xhi)) return 0;
    uint32_t j0 = clamp_index(ylo * f->inv_c + 1, f->gh), j1 = clamp_index(yhi * f->inv_c + 1, f->gh);
    int64_t visited = 0;
    b->pcell = UINT32_MAX;
    /* most cells are settled by the squared distance, far from both
     * bounds (a relative 1e-12 is far above the roundings: the root would
     * say the same); the rest take the root as before */
    const double out2 = (R + hd) * (R + hd) * (1 + 1e-12), in2 = R * R * (1 - 1e-12);
    for (uint32_t j = j0; j <= j1; j++) {
        double y0 = ((double)j - 1) * c, y1 = (double)j * c;
        /* x extent of the segment within the strip grown by R, then grown by R */
        double sylo = y0 - R, syhi = y1 + R, plo = 0, phi = s->len;
        if (s->uy != 0) {
            double p0 = (sylo - s->ay) / s->uy, p1 = (syhi - s->ay) / s->uy;
            if (p0 > p1) { double tmp = p0; p0 = p1; p1 = tmp; }
            plo = lm_max(plo, p0);
            phi = lm_min(phi, p1);
            if (!(plo <= phi)) continue;
        } else if (!(s->ay >= sylo && s->ay <= syhi)) continue;
        double xa = s->ax + plo * s->ux, xb = plo == phi ? xa : phi >= s->len ? s->bx : s->ax + phi * s->ux;
        double sxlo = lm_max(lm_min(xa, xb) - R, -c), sxhi = lm_min(lm_max(xa, xb) + R, gx1);
        if (!(sxlo <= sxhi)) continue;
        uint32_t i0 = clamp_index(sxlo * f->inv_c + 1, f->gw), i1 = clamp_index(sxhi * f->inv_c + 1, f->gw);
        int64_t before = visited;
        for (uint32_t i = i0; i <= i1; i++) {
            double x0 = ((double)i - 1) * c, x1 = (double)i * c;
            /* the centre's distance settles most cells without the exact
             * test; of the rest, a cell whose box comes within R - slack of
             * the centre's nearest point certainly touches (the exact test
             * would say so: slack is far above its rounding) */
            double qx, qy, cx = x0 + 0.5 * c, cy = y0 + 0.5 * c, d2 = seg_near2(s, cx, cy, &qx, &qy), dc = -1;
            int sure = d2 < 1e300;
            if (sure && d2 > out2) continue;
            if (!(sure && d2 < in2)) {
                dc = len2(cx - qx, cy - qy);
                if (dc > R + hd) continue;
                if (dc > R) {
                    double ex = fabs(cx - qx) - 0.5 * c, ey = fabs(cy - qy) - 0.5 * c;
                    if (!(len2(ex > 0 ? ex : 0, ey > 0 ? ey : 0) <= Rsure) && !seg_touches_rect(s, x0, y0, x1, y1, R))
                        continue;
                }
            }
            size_t cell = (size_t)j * f->gw + i;
            visited++;
            if (fill == 2) return 1;
            if (fill) {
                f->ids[--b->cnt[cell]] = id;
                b->cell1[id] = (uint32_t)cell;
            } else {
                if (++b->total > b->limit) return -1;
                b->cnt[cell]++;
                rec_cell(b, cell);
                if (b->pcell == UINT32_MAX || (b->pcell & 0x80000000u)) /* none even yet */
                    b->pcell = (uint32_t)cell | (((i | j) & 1) ? 0x80000000u : 0);
                if (rin > 0 && !f->full[cell] && dc < 0) dc = sqrt(d2); /* (sure: len2's root) */
                if (rin > 0 && !f->full[cell] &&
                    (dc + hd <= rin || (dc <= rfull && dc <= rin && seg_dist(s, x0, y0) <= rin && seg_dist(s, x1, y0) <= rin &&
                                        seg_dist(s, x0, y1) <= rin && seg_dist(s, x1, y1) <= rin)))
                    f->full[cell] = 1;
            }
        }
        if (!fill && visited > before) f->rstart[j]++; /* the segment is in row j's list */
    }
    return visited;
}

static void seg_set(rf_seg *s, double ax, double ay, double bx, double by, double r, double s0, uint32_t road,
                    uint32_t seg)
{
    /* halves: the difference of two finite coordinates cannot overflow */
    double dxh = 0.5 * bx - 0.5 * ax, dyh = 0.5 * by - 0.5 * ay, lh = hypot(dxh, dyh); /* 2 lh: rs__arc_len */
    s->ax = ax; s->ay = ay; s->bx = bx; s->by = by;
    s->ux = lh > 0 ? dxh / lh : 0;
    s->uy = lh > 0 ? dyh / lh : 0;
    s->len = 2 * lh;
    double aux = fabs(s->ux), auy = fabs(s->uy);
    s->ga = lm_max(aux, auy);
    s->gb = lm_min(aux, auy);
    if (s->gb < 1e-100) s->gb = 0;
    s->iga = s->ga > 0 ? 1 / s->ga : 0;
    s->igab = s->gb > 0 ? 1 / (s->ga * s->gb) : 0;
    s->l1 = aux + auy;
    s->iux = aux >= 1e-100 ? 1 / s->ux : 0;
    s->iuy = auy >= 1e-100 ? 1 / s->uy : 0;
    s->r = r;
    s->s0 = s0;
    s->road = road;
    s->seg = seg;
    s->jnext = 0;
    s->redundant = 0;
    s->jpart = 0;
    s->tee = 0;
    s->unlisted = 0;
}

/* Is segment s too far from f's window to be listed? A pixel of the
 * window reads the lists of its cell, which lies within a cell of the
 * window, and a nearest query within window_reach of it reads the cells
 * that far: a segment listed there comes within its r + reach + cell
 * diagonal (+ the query's reach) of the window. Its centreline's box grown
 * by more than that must miss the window (a NaN or infinite width: listed). */
static int seg_unlisted(const rs__roadfield *f, const rf_seg *s)
{
    if (!f->window_on) return 0;
    double d = s->r + f->reach + 2 * f->c + f->window_reach + 1;
    if (!(d <= 1e300)) return 0;
    return SEG_XMIN(s) - d > f->window[2] || SEG_XMAX(s) + d < f->window[0] || SEG_YMIN(s) - d > f->window[3] ||
           SEG_YMAX(s) + d < f->window[1];
}

void rs__roadfield_free(rs_ctx *ctx, rs__roadfield *f)
{
    if (!ctx || !f) return;
    rs__free(ctx, f->start);
    rs__free(ctx, f->ids);
    rs__free(ctx, f->full);
    rs__free(ctx, f->rstart);
    rs__free(ctx, f->rids);
    rs__free(ctx, f->rbox);
    rs__free(ctx, f->colpix);
    rs__free(ctx, f->rspan);
    rs__free(ctx, f->seg);
    rs__free(ctx, f->rfirst);
    rs__free(ctx, f->tee);
    rs__free(ctx, f->tstart);
    rs__free(ctx, f->tids);
    rs__free(ctx, f);
}

static int finite_nonneg(double v) { return isfinite(v) && v >= 0; }

/* the float next to finite r towards +inf (up = 1) or -inf: nextafterf's
 * answer by the bits (a libm call in the index build's hot loops) */
static float float_step(float r, int up)
{
    uint32_t u;
    memcpy(&u, &r, sizeof u);
    if ((u & 0x7FFFFFFFu) == 0) u = up ? 1u : 0x80000001u; /* +-0: the smallest subnormal */
    else if ((u >> 31) == (uint32_t)!up) u++;               /* away from zero */
    else u--;                                                /* towards zero */
    memcpy(&r, &u, sizeof r);
    return r;
}

/* A float <= v (NaN: -inf) and a float >= v (NaN: +inf); conversions
 * only of values within the float range. */
static float float_down(double v)
{
    if (!(v > -1e38)) return -INFINITY;
    if (v > 1e38) return 1e38f;
    float r = (float)v;
    return (double)r > v ? float_step(r, 0) : r;
}

static float float_up(double v)
{
    if (!(v < 1e38)) return INFINITY;
    if (v < -1e38) return -1e38f;
    float r = (float)v;
    return (double)r < v ? float_step(r, 1) : r;
}

/* Row lists for the coverage: per grid row, every segment of the row's cell
 * lists (each once, in the order first met), and whether the row's spans may be used: every segment
 * has coordinates, length and half width within 1e8 cells, so the spans'
 * rounding errors stay far below the slack `tol` (docs/roadfield.md).
 * Pass 1 counted each row's segments; one pass over the lists fills them,
 * each entry's box copied from the segment's. The pass over the segments
 * before it also sets seg_relations' flags (from `redundant`, a flag per
 * segment) and joint partners. */
__attribute__((noinline)) static rs_result build_rows(rs_ctx *ctx, rs__roadfield *f, const rf_scratch *sc,
                                                     const uint8_t *redundant)
{
    size_t ns = f->nseg ? f->nseg : 1;
    /* per segment: its box (16 bytes), stamp (4) and tol > 0 (1), beside
     * the box rather than in the 152-byte segment; in one block */
    int own = 0;
    float *sbox = scratch_take(ctx, sc, ns, 21, &own);
    uint32_t *stamp = sbox ? (uint32_t *)(void *)(sbox + 4 * ns) : NULL;
    uint8_t *sok = sbox ? (uint8_t *)(stamp + ns) : NULL;
    f->rspan = rs__calloc(ctx, f->gh, 1);
    rs_result res = RS_ERR_NOMEM;
    if (!sbox || !f->rspan) goto done;
    memset(stamp, 0, ns * sizeof *stamp);
    double ext = lm_max((double)f->gw, (double)f->gh) * f->c, lim = 1e8 * f->c;
    size_t after = f->nseg; /* first index past the run of zero-length segments at k + 1 */
    for (size_t k = f->nseg; k-- > 0;) {
        if ((k & 16383) == 0 && rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto done; }
        rf_seg *s = &f->seg[k];
        /* seg_relations' flags and joint partners (last to first, so that a
         * run of zero-length segments is skipped in one step) */
        size_t mp = k + 1;
        s->redundant = redundant[k];
        f->nredundant += redundant[k];
        if (mp < f->nseg && !(f->seg[mp].len > 0) && f->seg[mp].ax == s->bx && f->seg[mp].ay == s->by) mp = after;
        if (mp < f->nseg && mp <= UINT32_MAX) {
            const rf_seg *sb = &f->seg[mp];
            s->jnext = s->bx == sb->ax && s->by == sb->ay && s->r == sb->r && s->len > 0 && sb->len > 0 &&
                       s->ux * sb->ux + s->uy * sb->uy >= JOINT_COS;
            s->jpart = (uint32_t)mp;
        }
        if (s->len > 0) after = k;
        else if (!(k + 1 < f->nseg && !(f->seg[k + 1].len > 0) && f->seg[k + 1].ax == s->ax &&
                   f->seg[k + 1].ay == s->ay))
            after = k + 1;
        double m = lm_max(lm_max(lm_max(fabs(s->ax), fabs(s->ay)), lm_max(fabs(s->bx), fabs(s->by))),
                        lm_max(lm_max(s->len, s->r), ext));
        s->tol = m <= lim ? 1e-6 * (1 + m) : -1; /* NaN or too big: -1 */
        if (s->unlisted) continue; /* (in no row list) */
        sok[k] = s->tol > 0;
        double g = s->r + s->tol + f->margin;
        sbox[4 * k] = float_down(SEG_XMIN(s) - g);
        sbox[4 * k + 1] = float_up(SEG_XMAX(s) + g);
        sbox[4 * k + 2] = float_down(SEG_YMIN(s) - g);
        sbox[4 * k + 3] = float_up(SEG_YMAX(s) + g);
    }
    /* pass 1 counted each row's segments (seg_cells) into rstart */
    uint64_t run = 0;
    for (uint32_t j = 0; j <= f->gh; j++) {
        uint32_t n = j < f->gh ? f->rstart[j] : 0;
        f->rstart[j] = (uint32_t)run;
        run += n;
    }
    f->rids = rs__alloc_array(ctx, run ? (size_t)run : 1, sizeof *f->rids);
    f->rbox = rs__alloc_array(ctx, run ? (size_t)run : 1, 4 * sizeof *f->rbox);
    if (!f->rids || !f->rbox) goto done;
    for (uint32_t j = 0; j < f->gh; j++) {
        if ((j & 7) == 0 && rs__poll(ctx)) { res = RS_ERR_CANCELLED; goto done; }
        int ok = 1;
        uint32_t pos = f->rstart[j];
        /* the row's cell lists are one run of ids, in cell order */
        uint32_t k0 = f->start[(size_t)j * f->gw], k1 = f->start[(size_t)(j + 1) * f->gw];
        for (uint32_t k = k0; k < k1; k++) {
            uint32_t id = f->ids[k];
            if (k + PREFETCH_AHEAD < k1) {
                rs__prefetch(stamp + f->ids[k + PREFETCH_AHEAD]);
                rs__prefetch(sbox + 4 * (size_t)f->ids[k + PREFETCH_AHEAD]);
            }
            if (stamp[id] == j + 1) continue;
            stamp[id] = j + 1;
            f->rids[pos] = id;
            memcpy(f->rbox + 4 * (size_t)pos, sbox + 4 * (size_t)id, 4 * sizeof *sbox);
            ok &= sok[id];
            pos++;
        }
        f->rspan[j] = (uint8_t)ok;
    }
    res = RS_OK;
done:
    if (own) rs__free(ctx, sbox);
    return res;
}

/* Column of the centre of pixel p (pixels of f->pixel), as the coverage
 * computes it: -1 outside the grid. */
static int64_t pixel_col(const rs__roadfield *f, double p)
{
    return cell_of(f, (p + 0.5) * f->pixel, f->gw);
}

/* colpix (optional: left NULL when out of memory or when the pixel indices
 * would not fit): cell_of of pixel centres is non-decreasing in the pixel
 * index until it leaves the grid, so each column's first pixel is found by
 * an estimate and exact checks. */
static void build_colpix(rs_ctx *ctx, rs__roadfield *f)
{
    double last = (double)(f->gw - 1) * f->c / f->pixel + 2;
    if (!(last < 4e9)) return;
    uint32_t *cp = rs__alloc_array(ctx, (size_t)f->gw + 1, sizeof *cp);
    if (!cp) return;
    cp[0] = cp[1] = 0; /* centres are > 0: column 1 or more */
    for (uint32_t i = 2; i <= f->gw; i++) {
        /* first p with pixel_col(p) >= i, or outside (-1) once past the grid */
        double est = ceil((double)(i - 1) * f->c / f->pixel - 0.5), pl = cp[i - 1];
        double p = est > pl ? est : pl;
        while (p > pl) {
            int64_t c = pixel_col(f, p - 1);
            if (c >= 0 && c < (int64_t)i) break;
            p--;
        }
        for (;;) {
            int64_t c = pixel_col(f, p);
            if (c < 0 || c >= (int64_t)i) break;
            p++;
        }
        cp[i] = (uint32_t)p;
    }
    f->colpix = cp;
}

/* A segment with an end far from the map (1e300 m away, or just 1e7 m for
 * a map of 1 m cells) would have the coverage work with |p - a| huge and
 * lose every digit that matters: such a segment is cut to the disc around
 * the map that its capsule can reach. The cut points are built from the
 * disc's centre, so they keep full precision however far A and B are (as
 * lib/scene/roadgrid.c does). *along is how far the new A lies along the segment
 * from the old one (for the arc length). Returns 0 when nothing is left.
 * Segments within `far` of the map's box are left exactly as they are. Also
 * the GPU export's cut (lib/gpu/gpu_export.c), with a nearer `far` for float. */
int rs__clip_far(double *ax, double *ay, double *bx, double *by, double w, double h, double pad, double far,
                 double *along)
{
    *along = 0;
    if (lm_min(*ax, *bx) >= -far && lm_max(*ax, *bx) <= w + far && lm_min(*ay, *by) >= -far && lm_max(*ay, *by) <= h + far)
        return 1;
    int a_in = *ax >= -far && *ax <= w + far && *ay >= -far && *ay <= h + far;
    int b_in = *bx >= -far && *bx <= w + far && *by >= -far && *by <= h + far;
    double dxh = 0.5 * *bx - 0.5 * *ax, dyh = 0.5 * *by - 0.5 * *ay, lh = hypot(dxh, dyh);
    if (!(lh > 0) || !isfinite(lh)) return fabs(*ax - 0.5 * w) <= 0.5 * w + pad && fabs(*ay - 0.5 * h) <= 0.5 * h + pad;
    double ux = dxh / lh, uy = dyh / lh, cx = 0.5 * w, cy = 0.5 * h;
    double rad = 0.5 * hypot(w, h) + pad, huge = 1e6 * (w + h + 2 * pad);
    /* one end near, the other past a million map sizes: cut from the near
     * end (a slanted road from 10^20 m missed its own end by metres) */
    if (a_in != b_in && !(fabs(a_in ? *bx - cx : *ax - cx) <= huge && fabs(a_in ? *by - cy : *ay - cy) <= huge))
        return rs__cut_far_end(ax, ay, bx, by, a_in, ux, uy, lm_min(2 * lh, DBL_MAX), cx, cy, rad, along);
    double ex = cx - *ax, ey = cy - *ay;
    double dist = -uy * ex + ux * ey; /* signed distance of the centre from the line */
    if (!(fabs(dist) <= rad)) return 0;
    double px = cx + uy * dist, py = cy - ux * dist; /* foot of the perpendicular */
    /* (each end's place along the line from its own coordinates: 2 lh - sc
     * lost every digit when A was far and B near) */
    double sc = ex * ux + ey * uy, t0 = -sc, t1 = (*bx - cx) * ux + (*by - cy) * uy;
    if (t0 < -rad) t0 = -rad;
    if (t1 > rad) t1 = rad;
    if (!(t0 <= t1)) return 0;
    *along = sc + t0;
    *ax = px + t0 * ux;
    *ay = py + t0 * uy;
    *bx = px + t1 * ux;
    *by = py + t1 * uy;
    return 1;
}

/* Does capsule s lie within capsule t (up to a rounding slack)? The
 * distance to a segment is convex, so it is enough that both ends of s are
 * within t's half width minus s's. */
static int capsule_within(const rf_seg *s, const rf_seg *t)
{
    double m = lm_max(lm_max(fabs(t->ax), fabs(t->ay)), lm_max(fabs(s->ax), fabs(s->ay)));
    double room = t->r - s->r + 1e-9 * (1 + m + t->len + t->r);
    return room >= 0 && seg_dist(t, s->ax, s->ay) <= room && seg_dist(t, s->bx, s->by) <= room;
}

/* Holder search (seg_relations). A cell list up to this long is scanned;
 * a segment whose list is longer asks a box tree over the segments of the
 * long lists instead, so many short segments sharing cells (10^6 points on
 * a 100 m road) cost n log n, not n times the list. Both ways find the same
 * holders. */
#define RELATION_SCAN_AUTO 256
#define HOLDER_LEAF 8

typedef struct rf_box { double xlo, ylo, xhi, yhi; } rf_box;

/* Boxes that decide holders before capsule_within: if capsule k lies
 * within capsule j (capsule_within(k, j), slack included), then k's "inner"
 * box lies within j's "outer" box. Outer: j's centreline box grown by r_j
 * plus twice capsule_within's slack bound for j; inner: k's centreline box
 * grown by r_k minus twice the slack's share of k (|k's coordinates| <=
 * M_k). The doubled slack covers rounding. */
static double seg_mag(const rf_seg *s)
{
    return lm_max(lm_max(fabs(s->ax), fabs(s->ay)), lm_max(fabs(s->bx), fabs(s->by)));
}

static rf_box outer_box(const rf_seg *s)
{
    double g = s->r + 2e-9 * (1 + seg_mag(s) + s->len + s->r);
    rf_box b = { SEG_XMIN(s) - g, SEG_YMIN(s) - g, SEG_XMAX(s) + g, SEG_YMAX(s) + g };
    return b;
}

static rf_box inner_box(const rf_seg *s)
{
    double h = s->r - 2e-9 * seg_mag(s);
    rf_box b = { SEG_XMIN(s) - h, SEG_YMIN(s) - h, SEG_XMAX(s) + h, SEG_YMAX(s) + h };
    return b;
}

static int box_holds(const rf_box *o, const rf_box *in)
{
    return o->xlo <= in->xlo && o->ylo <= in->ylo && o->xhi >= in->xhi && o->yhi >= in->yhi;
}

/* The same boxes as floats for the list scan, outer ones rounded outwards
 * and inner ones inwards (so "outer holds inner" can only pass more often
 * than in doubles), stored (xlo, ylo, -xhi, -yhi): o holds q when o <= q
 * in all four lanes, one SSE compare. NaN bounds become infinities that
 * always pass; capsule_within then decides. */
typedef struct rf_fbox { float v[4]; } rf_fbox;

static rf_fbox fbox_outer(const rf_seg *s)
{
    rf_box b = outer_box(s);
    rf_fbox r = { { float_down(b.xlo), float_down(b.ylo), -float_up(b.xhi), -float_up(b.yhi) } };
    return r;
}

static rf_fbox fbox_inner(const rf_seg *s)
{
    rf_box b = inner_box(s);
    rf_fbox r = { { float_up(b.xlo), float_up(b.ylo), -float_down(b.xhi), -float_down(b.yhi) } };
    return r;
}


typedef struct rf_holders {
    uint32_t *ids;  /* segments of the long lists, in Morton order of their centres */
    rf_box *box;    /* outer box per ids entry */
    rf_box *node;   /* 2 * nleaf_p2 nodes: 1 = root, leaf l at nleaf_p2 + l (items l*LEAF..) */
    size_t n, p2;
    uint64_t work, limit; /* work units (list entries scanned, tree nodes and items visited) */
} rf_holders;

typedef struct rf_key { uint64_t key; uint32_t id; } rf_key;

static int cmp_key(const void *x, const void *y)
{
    const rf_key *a = x, *b = y;
    if (a->key != b->key) return a->key < b->key ? -1 : 1;
    return a->id < b->id ? -1 : a->id > b->id;
}

/* Interleave the bits of x (even) and y (odd). */
static uint64_t morton(uint32_t x, uint32_t y)
{
    uint64_t k = 0;
    for (int i = 0; i < 32; i++) k |= (uint64_t)((x >> i) & 1) << (2 * i) | (uint64_t)((y >> i) & 1) << (2 * i + 1);
    return k;
}

static uint32_t morton_coord(double v, double lo, double span)
{
    double q = (v - lo) / span * 4294967295.0;
    if (!(q > 0)) return 0;
    return q >= 4294967295.0 ? 0xFFFFFFFFu : (uint32_t)q;
}

static void holders_free(rs_ctx *ctx, rf_holders *h)
{
    rs__free(ctx, h->ids);
    rs__free(ctx, h->box);
    rs__free(ctx, h->node);
}

/* The tree over every segment of a list longer than f->relscan. */
static rs_result holders_build(rs_ctx *ctx, const rs__roadfield *f, rf_holders *h)
{
    size_t ncell = (size_t)f->gw * f->gh, n = 0;
    uint8_t *in = rs__calloc(ctx, f->nseg ? f->nseg : 1, 1);
    if (!in) return RS_ERR_NOMEM;
    for (size_t c = 0; c < ncell; c++)
        if (f->start[c + 1] - f->start[c] > f->relscan)
            for (uint32_t i = f->start[c]; i < f->start[c + 1]; i++) {
                n += !in[f->ids[i]];
                in[f->ids[i]] = 1;
            }
    rf_key *keys = rs__alloc_array(ctx, n ? n : 1, sizeof *keys);
    size_t nleaf = (n + HOLDER_LEAF - 1) / HOLDER_LEAF, p2 = 1;
    while (p2 < nleaf) p2 *= 2;
    h->ids = rs__alloc_array(ctx, n ? n : 1, sizeof *h->ids);
    h->box = rs__alloc_array(ctx, n ? n : 1, sizeof *h->box);
    h->node = rs__alloc_array(ctx, 2 * p2, sizeof *h->node);
    if (!keys || !h->ids || !h->box || !h->node) {
        rs__free(ctx, in);
        rs__free(ctx, keys);
        return RS_ERR_NOMEM;
    }
    double lo = -f->c, spanx = ((double)f->gw + 1) * f->c, spany = ((double)f->gh + 1) * f->c;
    size_t m = 0;
    for (size_t k = 0; k < f->nseg; k++) {
        if ((k & 16383) == 0 && rs__poll(ctx)) {
            rs__free(ctx, in);
            rs__free(ctx, keys);
            return RS_ERR_CANCELLED;
        }
        if (!in[k]) continue;
        const rf_seg *s = &f->seg[k];
        keys[m].key = morton(morton_coord(0.5 * SEG_XMIN(s) + 0.5 * SEG_XMAX(s), lo, spanx),
                             morton_coord(0.5 * SEG_YMIN(s) + 0.5 * SEG_YMAX(s), lo, spany));
        keys[m++].id = (uint32_t)k;
    }
    rs__free(ctx, in);
    if (n > 1) qsort(keys, n, sizeof *keys, cmp_key);
    for (size_t i = 0; i < n; i++) {
        h->ids[i] = keys[i].id;
        h->box[i] = outer_box(&f->seg[keys[i].id]);
    }
    rs__free(ctx, keys);
    h->n = n;
    h->p2 = p2;
    for (size_t l = 0; l < p2; l++) {
        rf_box u = { INFINITY, INFINITY, -INFINITY, -INFINITY };
        for (size_t i = l * HOLDER_LEAF; i < n && i < (l + 1) * HOLDER_LEAF; i++) {
            const rf_box *b = &h->box[i];
            u.xlo = lm_min(u.xlo, b->xlo);
            u.ylo = lm_min(u.ylo, b->ylo);
            u.xhi = lm_max(u.xhi, b->xhi);
            u.yhi = lm_max(u.yhi, b->yhi);
        }
        h->node[p2 + l] = u;
    }
    for (size_t i = p2; i-- > 1;) {
        const rf_box *a = &h->node[2 * i], *b = &h->node[2 * i + 1];
        rf_box u = { lm_min(a->xlo, b->xlo), lm_min(a->ylo, b->ylo), lm_max(a->xhi, b->xhi), lm_max(a->yhi, b->yhi) };
        h->node[i] = u;
    }
    return RS_OK;
}

static int cmp_u64(const void *pa, const void *pb)
{
    uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;
    return (a > b) - (a < b);
}

/* Is segment j in the (ascending) list of cell? */
static int listed(const rs__roadfield *f, size_t cell, uint32_t j)
{
    uint32_t lo = f->start[cell], hi = f->start[cell + 1];
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (f->ids[mid] < j) lo = mid + 1;
        else hi = mid;
    }
    return lo < f->start[cell + 1] && f->ids[lo] == j;
}

/* Does j make k redundant (the rule of seg_relations)? */
static int holds(const rs__roadfield *f, size_t k, uint32_t j)
{
    const rf_seg *sa = &f->seg[k];
    if (j == k || !capsule_within(sa, &f->seg[j])) return 0;
    return j < k || !capsule_within(&f->seg[j], sa);
}

/* Is segment k redundant: held by a segment of cell's list? 1, 0, or -1
 * when the work limit is passed. */
static int redundant_of(const rs__roadfield *f, rf_holders *h, size_t k, size_t cell)
{
    uint32_t a = f->start[cell], b = f->start[cell + 1];
    if (b - a <= f->relscan || !h->node) {
        h->work += b - a;
        if (h->work > h->limit) return -1;
        for (uint32_t i = a; i < b; i++)
            if (holds(f, k, f->ids[i])) return 1;
        return 0;
    }
    rf_box q = inner_box(&f->seg[k]);
    size_t stack[130], sp = 0;
    stack[sp++] = 1;
    while (sp) {
        size_t nd = stack[--sp];
        if (++h->work > h->limit) return -1;
        if (!box_holds(&h->node[nd], &q)) continue;
        if (nd < h->p2) {
            stack[sp++] = 2 * nd + 1;
            stack[sp++] = 2 * nd;
            continue;
        }
        size_t l = nd - h->p2;
        for (size_t i = l * HOLDER_LEAF; i < h->n && i < (l + 1) * HOLDER_LEAF; i++) {
            uint32_t j = h->ids[i];
            h->work++;
            if (box_holds(&h->box[i], &q) && j != k && listed(f, cell, j) && holds(f, k, j)) return 1;
        }
    }
    return 0;
}

/* holder_scan's ring of candidate pairs waiting for their segments */
#define PAIR_RING 16

/* k's flag, ORed with whether j holds it (nothing to ask once it is set) */
static void pair_settle(const rs__roadfield *f, uint8_t *redundant, uint32_t k, uint32_t j)
{
    if (!redundant[k] && holds(f, k, j)) redundant[k] = 1;
}

/* Index of the first of the n gathered boxes (four float arrays, padded
 * to a multiple of 4) from `from` on that holds q, or n when none. */
static uint32_t fbox_next(const float *const *g, uint32_t from, uint32_t n, const rf_fbox *q)
{
#if defined(__SSE2__)
    __m128 q0 = _mm_set1_ps(q->v[0]), q1 = _mm_set1_ps(q->v[1]), q2 = _mm_set1_ps(q->v[2]),
           q3 = _mm_set1_ps(q->v[3]);
    uint32_t e = from & ~3u;
    for (; e < n; e += 4) {
        __m128 m = _mm_and_ps(_mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(g[0] + e), q0), _mm_cmple_ps(_mm_loadu_ps(g[1] + e), q1)),
                              _mm_and_ps(_mm_cmple_ps(_mm_loadu_ps(g[2] + e), q2), _mm_cmple_ps(_mm_loadu_ps(g[3] + e), q3)));
        int bits = _mm_movemask_ps(m);
        for (uint32_t t = 0; bits && t < 4; t++)
            if (bits >> t & 1 && e + t >= from) return e + t < n ? e + t : n;
    }
    return n;
#else
    for (uint32_t e = from; e < n; e++)
        if (g[0][e] <= q->v[0] && g[1][e] <= q->v[1] && g[2][e] <= q->v[2] && g[3][e] <= q->v[3]) return e;
    return n;
#endif
}

#ifdef RS_AVX512_DISPATCH
/* fbox_next sixteen boxes a step where the CPU has AVX-512 (the same
 * answer: the first index from `from` on whose four lanes all compare <=).
 * On a dense map every segment walks a list of ~60 boxes to its end (its
 * own box passes, a real holder is rare), so the walk is what grows with
 * the density (docs/speed.md). The gathered arrays are padded with
 * FBOX_PAD infinities past n. */
RS_AVX512 static uint32_t fbox_next16(const float *const *g, uint32_t from, uint32_t n, const rf_fbox *q)
{
    __m512 q0 = _mm512_set1_ps(q->v[0]), q1 = _mm512_set1_ps(q->v[1]), q2 = _mm512_set1_ps(q->v[2]),
           q3 = _mm512_set1_ps(q->v[3]);
    for (uint32_t e = from & ~15u; e < n; e += 16) {
        __mmask16 m = _mm512_cmp_ps_mask(_mm512_loadu_ps(g[0] + e), q0, _CMP_LE_OQ);
        m = _mm512_mask_cmp_ps_mask(m, _mm512_loadu_ps(g[1] + e), q1, _CMP_LE_OQ);
        m = _mm512_mask_cmp_ps_mask(m, _mm512_loadu_ps(g[2] + e), q2, _CMP_LE_OQ);
        m = _mm512_mask_cmp_ps_mask(m, _mm512_loadu_ps(g[3] + e), q3, _CMP_LE_OQ);
        uint32_t bits = (uint32_t)m;
        if (e < from) bits &= ~0u << (from - e);
        if (bits) {
            uint32_t t = e + (uint32_t)__builtin_ctz(bits);
            return t < n ? t : n;
        }
    }
    return n;
}
#endif

#ifdef RS_AVX2_DISPATCH
/* fbox_next16's eight-lane form where the CPU has AVX2 but not AVX-512
 * (the same answer; the padding covers its reads too). */
RS_AVX2 static uint32_t fbox_next8(const float *const *g, uint32_t from, uint32_t n, const rf_fbox *q)
{
    __m256 q0 = _mm256_set1_ps(q->v[0]), q1 = _mm256_set1_ps(q->v[1]), q2 = _mm256_set1_ps(q->v[2]),
           q3 = _mm256_set1_ps(q->v[3]);
    for (uint32_t e = from & ~7u; e < n; e += 8) {
        __m256 m = _mm256_and_ps(_mm256_cmp_ps(_mm256_loadu_ps(g[0] + e), q0, _CMP_LE_OQ),
                                 _mm256_cmp_ps(_mm256_loadu_ps(g[1] + e), q1, _CMP_LE_OQ));
        m = _mm256_and_ps(m, _mm256_and_ps(_mm256_cmp_ps(_mm256_loadu_ps(g[2] + e), q2, _CMP_LE_OQ),
                                           _mm256_cmp_ps(_mm256_loadu_ps(g[3] + e), q3, _CMP_LE_OQ)));
        uint32_t bits = (uint32_t)_mm256_movemask_ps(m);
        if (e < from) bits &= ~0u << (from - e);
        if (bits) {
            uint32_t t = e + (uint32_t)__builtin_ctz(bits);
            return t < n ? t : n;
        }
    }
    return n;
}
#endif
#define FBOX_PAD 16

/* The next box holding q from `from` on (fbox_next16 when `wide` is 1,
 * fbox_next8 when 2). */
static uint32_t fbox_find(int wide, const float *const *g, uint32_t from, uint32_t n, const rf_fbox *q)
{
#ifdef RS_AVX512_DISPATCH
    if (wide == 1) return fbox_next16(g, from, n, q);
#endif
#ifdef RS_AVX2_DISPATCH
    if (wide == 2) return fbox_next8(g, from, n, q);
#endif
    (void)wide;
    return fbox_next(g, from, n, q);
}

/* Redundancy of every segment (seg_relations): the segments are taken
 * cell by cell (those whose cell1 is the cell), so a short list's float
 * boxes are gathered once and scanned, four at a time, by every segment
 * that asks that list; only boxes that hold the segment's inner box go on
 * to capsule_within (the lists of a dense map hold ~60 segments: the scan
 * loaded each one's 184 bytes before). Same flags and work units as asking
 * redundant_of per segment. */
__attribute__((noinline)) static rs_result holder_scan(rs_ctx *ctx, rs__roadfield *f, const uint32_t *cell1, rf_holders *h, uint8_t *redundant,
                                                      const rf_scratch *sc)
{
    size_t ncell = (size_t)f->gw * f->gh, cap = (f->maxlist < f->relscan ? f->maxlist : f->relscan) + FBOX_PAD;
#if defined(RS_AVX2_DISPATCH)
    const int wide = rs__avx512_ok() ? 1 : rs__avx2_ok() ? 2 : 0;
#elif defined(RS_AVX512_DISPATCH)
    const int wide = rs__avx512_ok();
#else
    const int wide = 0;
#endif
    size_t ns = f->nseg ? f->nseg : 1;
    /* outer and inner boxes of every segment (ob[2k], ob[2k+1]): 32 bytes
     * read where each segment's 152 were; then the segments by cell1
     * (counting sort: who asks which list), in one block */
    int own = 0;
    rf_fbox *ob = scratch_take(ctx, sc, ns, 2 * sizeof *ob + sizeof(uint32_t), &own);
    uint32_t *order = ob ? (uint32_t *)(void *)(ob + 2 * ns) : NULL;
    float *gb = rs__alloc_array(ctx, cap, 4 * sizeof *gb);
    /* (few segments on many cells, a local build's: the segments sorted by
     * cell, the cells with none passed over; the same order and flags.
     * Unlisted segments are in no list: not redundant, not asked) */
    const size_t nlisted = f->nseg - f->nunlisted;
    const int sparse = (uint64_t)nlisted * 16 < ncell;
    uint32_t *first = sparse ? NULL : rs__calloc(ctx, ncell + 1, sizeof *first);
    uint64_t *key = sparse ? rs__alloc_array(ctx, ns, sizeof *key) : NULL;
    if (!ob || !gb || (!sparse && !first) || (sparse && !key)) {
        if (own) rs__free(ctx, ob);
        rs__free(ctx, gb);
        rs__free(ctx, first);
        rs__free(ctx, key);
        return RS_ERR_NOMEM;
    }
    if (sparse) {
        for (size_t k = 0, i = 0; k < f->nseg; k++)
            if (!f->seg[k].unlisted) key[i++] = (uint64_t)cell1[k] << 32 | k;
        if (nlisted > 1) qsort(key, nlisted, sizeof *key, cmp_u64);
        for (size_t k = 0; k < nlisted; k++) order[k] = (uint32_t)key[k];
    } else {
        /* (the unlisted ones left out: `order` holds the listed, by cell;
         * reading a flag is no cost when there are none) */
        for (size_t k = 0; k < f->nseg; k++)
            if (!f->nunlisted || !f->seg[k].unlisted) first[cell1[k] + 1]++;
        for (size_t c = 0; c < ncell; c++) first[c + 1] += first[c];
        for (size_t k = 0; k < f->nseg; k++)
            if (!f->nunlisted || !f->seg[k].unlisted) order[first[cell1[k]]++] = (uint32_t)k;
        for (size_t c = ncell; c > 0; c--) first[c] = first[c - 1];
        first[0] = 0;
    }
    const float *g[4] = { gb, gb + cap, gb + 2 * cap, gb + 3 * cap };
    /* A box that passes is a real holder candidate; its capsule test reads
     * two segments far apart in memory (a dense map's segments fill
     * hundreds of MB), so it waits in a ring while both are fetched and a
     * segment's flag is the OR of its candidates' answers: the same flags,
     * since holds() depends on the pair alone. A segment's walk stops once
     * an answer says it is held (a ring's worth of pairs after its holder
     * at most; the work units count its whole list either way). */
    uint32_t pk[PAIR_RING], pj[PAIR_RING];
    size_t np = 0;
    rs_result res = RS_OK;
    for (size_t k = 0; k < f->nseg; k++) {
        if ((k & 16383) == 0 && rs__poll(ctx)) { res = RS_ERR_CANCELLED; break; }
        if (f->nunlisted && f->seg[k].unlisted) { /* (its boxes never read) */
            redundant[k] = 0;
            continue;
        }
        ob[2 * k] = fbox_outer(&f->seg[k]);
        ob[2 * k + 1] = fbox_inner(&f->seg[k]);
    }
    for (size_t c = 0, at = 0; c < ncell && res == RS_OK; c++) {
        uint32_t i0, i1;
        if (sparse) { /* (the next cell that is some segment's first) */
            if (at == nlisted) break;
            c = (size_t)(key[at] >> 32);
            for (i1 = (uint32_t)at; i1 < nlisted && (size_t)(key[i1] >> 32) == c; i1++) {}
            i0 = (uint32_t)at, at = i1;
        } else
            i0 = first[c], i1 = first[c + 1];
        uint32_t a = f->start[c], b = f->start[c + 1], n = b - a;
        int gathered = 0;
        if ((c & 63) == 0 && rs__poll(ctx)) { res = RS_ERR_CANCELLED; break; } /* (10^5 roads: ~0.1 s in all) */
        for (uint32_t i = i0; i < i1; i++) {
            uint32_t k = order[i];
            int red = 0;
            redundant[k] = 0;
            if (n > f->relscan && h->node) {
                red = redundant_of(f, h, k, c);
            } else {
                h->work += n;
                if (h->work > h->limit) { res = RS_ERR_LIMIT; break; }
                if (!gathered) {
                    for (uint32_t e = 0; e < n; e++) {
                        if (e + PREFETCH_AHEAD < n) rs__prefetch(&ob[2 * (size_t)f->ids[a + e + PREFETCH_AHEAD]]);
                        for (int l = 0; l < 4; l++) gb[l * cap + e] = ob[2 * (size_t)f->ids[a + e]].v[l];
                    }
                    for (uint32_t e = n; e < n + FBOX_PAD; e++)
                        for (int l = 0; l < 4; l++) gb[l * cap + e] = INFINITY;
                    gathered = 1;
                }
                const rf_fbox *q = &ob[2 * (size_t)k + 1];
                for (uint32_t e = fbox_find(wide, g, 0, n, q); e < n; e = fbox_find(wide, g, e + 1, n, q)) {
                    uint32_t j = f->ids[a + e];
                    if (j == k) continue;
                    if (redundant[k]) break; /* (a holder settled already: at most a ring's worth asked in vain) */
                    size_t slot = np++ % PAIR_RING;
                    if (np > PAIR_RING) pair_settle(f, redundant, pk[slot], pj[slot]);
                    rs__prefetch(&f->seg[j]);
                    rs__prefetch((const char *)&f->seg[j] + 63);
                    rs__prefetch(&f->seg[k]);
                    rs__prefetch((const char *)&f->seg[k] + 63);
                    pk[slot] = (uint32_t)k, pj[slot] = j;
                }
                continue;
            }
            if (red < 0) { res = RS_ERR_LIMIT; break; }
            redundant[k] = (uint8_t)red;
        }
    }
    /* the candidates still waiting */
    for (size_t t = np > PAIR_RING ? np - PAIR_RING : 0; res == RS_OK && t < np; t++)
        pair_settle(f, redundant, pk[t % PAIR_RING], pj[t % PAIR_RING]);
    if (own) rs__free(ctx, ob);
    rs__free(ctx, gb);
    rs__free(ctx, first);
    rs__free(ctx, key);
    return res;
}

/* Per segment: its gentle-joint partner (the next segment of positive
 * length, past zero-length ones at the shared point: consecutive segments
 * of a road, or the first of the next road when it starts where this one
 * ends with the same width), and whether its capsule is redundant: within
 * another one (repeated points, retraced segments, a road given twice;
 * of two equal capsules the later one). A redundant capsule never changes
 * the union, and leaving it out of a pixel's near set keeps the cover the
 * same as without it (the exact one-capsule covers would otherwise give
 * way to the approximations for several). The capsule that holds it is in
 * the same cell lists (its reach is at least as large) and is near or
 * deep wherever the redundant one is near (docs/roadfield.md). Here the
 * holders, into *red_out (a flag per segment, the caller's to free);
 * build_rows' pass over the segments writes the flags and finds the
 * partners (one pass over a dense map's hundreds of MB of segments, not
 * two), last to first so that a run of zero-length segments is skipped in
 * one step (a million repeated points cost a million steps). RS_ERR_LIMIT
 * when the holder search passes the work limit (h->limit). */
static rs_result seg_relations(rs_ctx *ctx, rs__roadfield *f, const uint32_t *cell1, rf_holders *h, const rf_scratch *sc,
                               uint8_t **red_out)
{
    *red_out = NULL;
    if (f->maxlist > f->relscan) {
        rs_result r = holders_build(ctx, f, h);
        if (r != RS_OK) return r;
    }
    /* the holder is listed wherever this one is (its grown capsule is larger);
     * the flags land in the segments in build_rows' pass */
    uint8_t *redundant = rs__alloc_array(ctx, f->nseg ? f->nseg : 1, 1);
    if (!redundant) return RS_ERR_NOMEM;
    rs_result r = rs__poll(ctx) ? RS_ERR_CANCELLED : holder_scan(ctx, f, cell1, h, redundant, sc);
    if (r != RS_OK) {
        rs__free(ctx, redundant);
        return r;
    }
    h->work += f->nseg; /* the joint partners (set by build_rows): one step each */
    *red_out = redundant;
    return RS_OK;
}

/* The index from the counts in b (pass 1, seg_cells with fill = 0, run
 * over f->seg): offsets, lists, segment relations, row lists, colpix. */
static rs_result index_finish(rs_ctx *ctx, rs__roadfield *f, rf_builder *b, size_t cap_seg)
{
    size_t ncell = (size_t)f->gw * f->gh;
    rs_result res;
    /* Counts to end offsets; pass 2 fills each list from its end, visiting
     * segments last to first, so every list comes out ascending. */
    uint64_t run = 0;
    for (uint32_t j = 0; j < f->gh; j++) {
        size_t i0 = (size_t)j * f->gw, i1 = i0 + f->gw;
        if ((j & 255) == 255 && rs__poll(ctx)) return RS_ERR_CANCELLED; /* (10^7 cells at 10^5 roads) */
        if (!f->rstart[j]) { /* (a row no segment reaches: its cells are empty) */
            for (size_t i = i0; i < i1; i++) f->start[i] = (uint32_t)run;
            continue;
        }
        for (size_t i = i0; i < i1; i++) {
            if (f->start[i]) f->nonempty++;
            if (f->start[i] > f->maxlist) f->maxlist = f->start[i];
            if (f->full[i]) f->nfull++;
            run += f->start[i];
            f->start[i] = (uint32_t)run;
        }
    }
    f->start[ncell] = (uint32_t)run;
    f->nent = (size_t)run;
    f->ids = rs__alloc_array(ctx, f->nent ? f->nent : 1, sizeof *f->ids);
    if (!f->ids) return RS_ERR_NOMEM;
    b->cell1 = rs__alloc_array(ctx, f->nseg ? f->nseg : 1, sizeof *b->cell1);
    if (!b->cell1) return RS_ERR_NOMEM;
    if (!b->norec && b->rec) {
        /* a poll every 2048 entries: the first writes into the fresh ids
         * fault its pages in, up to one a write where the segments are
         * spread over the map (the casing field at 10^5 roads: 58 ms for
         * the first 65536 entries, ~7 us a page on the test host) */
        size_t since = 0;
        for (size_t k = f->nseg; k-- > 0;) {
            uint32_t a = k ? b->recend[k - 1] : 0, e = b->recend[k];
            if ((since += e - a + 1) >= 2048) {
                since = 0;
                if (rs__poll(ctx)) return RS_ERR_CANCELLED;
            }
            for (uint32_t i = e; i-- > a;) {
                if (i >= PREFETCH_AHEAD) rs__prefetch(f->ids + b->cnt[b->rec[i - PREFETCH_AHEAD]] - 1);
                f->ids[--b->cnt[b->rec[i]]] = (uint32_t)k;
            }
            b->cell1[k] = e > a ? b->pref[k] & 0x7FFFFFFFu : 0;
        }
    } else {
        for (size_t k = f->nseg; k-- > 0;) {
            if ((k & 2047) == 0 && rs__poll(ctx)) return RS_ERR_CANCELLED;
            b->cell1[k] = 0;
            if (!f->seg[k].unlisted) seg_cells(b, &f->seg[k], 1, (uint32_t)k);
        }
    }
    /* the record is read: its memory serves the relations and the row lists */
    if (!b->norec && b->rec) {
        b->scratch.p = b->rec;
        b->scratch.bytes = b->caprec * sizeof *b->rec;
        b->rec = NULL;
    }
    rec_drop(b);
    if (rs__poll(ctx)) return RS_ERR_CANCELLED;
    rf_holders h;
    memset(&h, 0, sizeof h);
    h.limit = b->work_limit;
    uint8_t *redundant = NULL;
    res = seg_relations(ctx, f, b->cell1, &h, &b->scratch, &redundant);
    holders_free(ctx, &h);
    f->relwork = h.work;
    rs__free(ctx, b->cell1);
    b->cell1 = NULL;
    if (res == RS_ERR_LIMIT) b->work_over = 1;
    if (res == RS_OK && rs__poll(ctx)) res = RS_ERR_CANCELLED;
    if (res != RS_OK) {
        rs__free(ctx, redundant);
        return res;
    }
    res = build_rows(ctx, f, &b->scratch, redundant);
    rs__free(ctx, redundant);
    if (res != RS_OK) return res;
    rs__free(ctx, b->scratch.p);
    b->scratch.p = NULL;
    b->scratch.bytes = 0;
    if (rs__poll(ctx)) return RS_ERR_CANCELLED;
    build_colpix(ctx, f);
    f->bytes = sizeof *f + (ncell + 1) * sizeof *f->start + ncell + f->nent * sizeof *f->ids +
               cap_seg * sizeof(rf_seg) + ((size_t)f->gh + 1) * sizeof *f->rstart + f->gh +
               (size_t)f->rstart[f->gh] * (sizeof *f->rids + 4 * sizeof *f->rbox) +
               (f->colpix ? ((size_t)f->gw + 1) * sizeof *f->colpix : 0) + f->nrfirst * sizeof *f->rfirst;
    return RS_OK;
}

/* A builder for field f: the entry and work limits of ctx, an empty record. */
static void builder_init(rf_builder *b, rs_ctx *ctx, rs__roadfield *f)
{
    memset(b, 0, sizeof *b);
    b->f = f;
    b->ctx = ctx;
    b->limit = UINT32_MAX - 1u;
    if (ctx->limits.max_road_cells && ctx->limits.max_road_cells < b->limit) b->limit = ctx->limits.max_road_cells;
    b->work_limit = ctx->limits.max_field_work;
    b->seg0 = 64;
    b->rec0 = 4096;
}

/* A failed build or widening: frees what was made, says why. */
static rs_result build_fail(rs_ctx *ctx, rs__roadfield *f, rf_builder *b, rs_result res)
{
    rs__free(ctx, b->cell1);
    rs__free(ctx, b->scratch.p);
    rec_drop(b);
    rs__roadfield_free(ctx, f);
    if (res == RS_ERR_NOMEM) return rs__fail(ctx, res, "roadfield: out of memory");
    if (res == RS_ERR_CANCELLED) return rs__fail(ctx, res, "cancelled");
    if (b->work_over)
        return rs__fail(ctx, res,
                        "road field: comparing the segments that share index cells takes more than %llu steps "
                        "(too many road segments in one place; the budget is rs_limits.max_field_work)",
                        (unsigned long long)b->work_limit);
    return rs__fail(ctx, res, "roadfield: more than %llu index entries (roads too wide or too many for the map)",
                    (unsigned long long)b->limit);
}

/* c doubled until the grid over p's map has at most cap cells */
static double grown_cell(double c, const rs__roadfield_params *p, double cap)
{
    while ((ceil(p->width_m / c) + 2) * (ceil(p->height_m / c) + 2) > cap) c *= 2;
    return c;
}

double rs__roadfield_cell_for(const rs_roads *roads, const rs__roadfield_params *p)
{
    size_t nroads = rs_roads_count(roads);
    /* Index cell: about one segment per cell over the map (short lists, few
     * cells per segment), at least the DEM cell and half the mean road
     * width, at most twice the mean width (wider cells are rarely whole
     * inside a road: their pixels lose the full-cell path; the lists'
     * savings outweigh it up to about twice); doubled until the grid is
     * small. A pixel's value does not depend on the cell (the lists only
     * narrow the candidates): the city's 1000 roads take 15.3 m cells
     * (docs/roadfield.md "Index"). (Until 3 December 2026 at most the mean
     * width: a repeated end point clipped at a T took every point short of
     * its clip line as on its surface, so a fill lookup depended on which
     * cells listed it; fixed in tee_sd.) */
    double c = p->index_cell, cap = GRID_MAX_CELLS;
    if (c == 0) {
        double wsum = 0, nseg = 0;
        for (size_t i = 0; i < nroads; i++) {
            double w = 0;
            size_t np = 0;
            rs_roads_get(roads, i, NULL, &w, NULL, &np);
            wsum += lm_min(w, 1e12) / (double)nroads;
            nseg += np > 1 ? (double)(np - 1) : 0;
        }
        double lo = lm_max(p->cell_size, 0.5 * wsum), hi = lm_max(lo, 2 * wsum);
        double even = nseg > 0 ? sqrt(p->width_m * p->height_m / nseg) : hi;
        c = even < lo || !(even == even) ? lo : even > hi ? hi : even;
        cap = GRID_AUTO_CELLS;
    }
    return grown_cell(c, p, cap);
}

double rs__roadfield_cell_most(const rs__roadfield_params *p, double widest)
{
    /* cell_for's automatic cell starts at most at hi for roads no wider
     * than `widest`. Doubled from there, it stops below twice grown(hi):
     * the cell before its last doubling left too many cells, so it was
     * below grown(hi), which leaves few enough */
    double hi = lm_max(lm_max(p->cell_size, 0.5 * widest), 2 * widest);
    return 2 * grown_cell(hi, p, GRID_AUTO_CELLS);
}

rs_result rs__roadfield_build(rs_ctx *ctx, const rs_roads *roads, const rs__roadfield_params *p,
                              rs__roadfield **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out || !roads || !p) return rs__fail(ctx, RS_ERR_INVALID_ARG, "roadfield: NULL argument");
    *out = NULL;
    if (!isfinite(p->origin_x) || !isfinite(p->origin_y) || !(p->cell_size > 0) || !isfinite(p->cell_size) ||
        !finite_nonneg(p->width_m) || !finite_nonneg(p->height_m) || !finite_nonneg(p->reach_extra) ||
        !finite_nonneg(p->index_cell) || !finite_nonneg(p->pixel))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "roadfield: bad parameters");
    size_t nroads = rs_roads_count(roads);
    if (nroads > UINT32_MAX) return rs__fail(ctx, RS_ERR_LIMIT, "roadfield: too many roads");

    double c = rs__roadfield_cell_for(roads, p);

    rs__roadfield *f = rs__calloc(ctx, 1, sizeof *f);
    if (!f) return rs__fail(ctx, RS_ERR_NOMEM, "roadfield: out of memory");
    f->c = c;
    f->inv_c = 1.0 / c;
    f->gw = (uint32_t)(ceil(p->width_m / c) + 2);
    f->gh = (uint32_t)(ceil(p->height_m / c) + 2);
    f->pixel = p->pixel > 0 ? p->pixel : p->cell_size;
    f->margin = f->pixel * HALF_SQRT2;
    f->reach_extra = p->reach_extra;
    f->reach = p->reach_extra + f->margin;
    f->relscan = p->relation_scan ? p->relation_scan : RELATION_SCAN_AUTO;
    if (p->window_on) {
        f->window_on = 1;
        memcpy(f->window, p->window, sizeof f->window);
        f->window_reach = p->window_reach;
    }
    size_t ncell = (size_t)f->gw * f->gh;
    rf_builder b;
    builder_init(&b, ctx, f);
    f->start = rs__alloc_array(ctx, ncell + 1, sizeof *f->start);
    f->full = rs__calloc(ctx, ncell, 1);
    f->rstart = rs__calloc(ctx, (size_t)f->gh + 1, sizeof *f->rstart);
    rs_result res = RS_OK;
    size_t cap_seg = 0;
    if (!f->start || !f->full || !f->rstart) { res = RS_ERR_NOMEM; goto fail; }
    memset(f->start, 0, (ncell + 1) * sizeof *f->start);
    b.cnt = f->start;

    /* The segments' array sized once from the roads' segment count (an
     * upper bound: off-map segments are dropped, and the array shrinks at
     * the end). Growing it by doubling copied up to ~200 MB at a time on
     * big scenes, a stall no progress call could break. */
    {
        size_t want = 0;
        for (size_t ri = 0; ri < nroads; ri++) {
            size_t n = 0;
            rs_roads_get(roads, ri, NULL, NULL, NULL, &n);
            want += n > 1 ? n - 1 : n;
            if (want > UINT32_MAX) break;
        }
        if (want > UINT32_MAX) want = UINT32_MAX;
        if (want > 0) {
            if (!(f->seg = rs__alloc_array(ctx, want, sizeof(rf_seg)))) {
                res = RS_ERR_NOMEM;
                goto fail;
            }
            cap_seg = want;
            if (want > b.seg0) b.seg0 = want;
            b.seg_all = want;
        }
    }

    /* Pass 1: local coordinates, arc lengths, counts; keep the segments
     * that reach the grid. */
    rs__local_frame F = rs__local_frame_of(p->origin_x, p->origin_y, p->cell_size);
    /* (a derived field has none: road_end_seg then searches the whole array) */
    if (!(f->rfirst = rs__alloc_array(ctx, nroads + 1, sizeof *f->rfirst))) {
        res = RS_ERR_NOMEM;
        goto fail;
    }
    f->nrfirst = nroads + 1;
    for (size_t ri = 0; ri < nroads; ri++) {
        double w = 0;
        const double *xy = NULL;
        size_t n = 0;
        f->rfirst[ri] = (uint32_t)f->nseg;
        rs_roads_get(roads, ri, NULL, &w, &xy, &n);
        if (rs__tick(ctx, 1)) { res = RS_ERR_CANCELLED; goto fail; }
        if (n == 0) continue;
        if (n - 1 > UINT32_MAX) { res = RS_ERR_LIMIT; goto fail; }
        double ax, ay;
        rs__local_point(&F, xy, 0, &ax, &ay);
        double s = 0;
        size_t nseg = n > 1 ? n - 1 : 1; /* a single point is one zero-length segment */
        for (size_t k = 0; k < nseg; k++) {
            b.seg_pass++;
            double bx = ax, by = ay;
            if (n > 1) rs__local_point(&F, xy, k + 1, &bx, &by);
            rf_seg sg;
            double cax = ax, cay = ay, cbx = bx, cby = by, along = 0;
            /* the reach of this capsule beyond the map, with room to spare */
            double pad = 2 * (lm_min(0.5 * w, 1e15) + f->reach) + c;
            /* Within a million map sizes the digits lost are below 1e-9 of a
             * pixel: such segments are kept as given (and the nearest-road
             * ties stay those of the exact geometry). */
            int keep = rs__clip_far(&cax, &cay, &cbx, &cby, p->width_m, p->height_m, pad,
                                    1e6 * (p->width_m + p->height_m + 2 * pad), &along);
            if (along == 0 && cax == ax && cay == ay && cbx == bx && cby == by) {
                seg_set(&sg, ax, ay, bx, by, 0.5 * w, s, (uint32_t)ri, (uint32_t)k);
                s = rs__arc_add(s, sg.len); /* (sg.len is rs__arc_len of the segment) */
            } else {
                seg_set(&sg, cax, cay, cbx, cby, 0.5 * w, lm_min(s + along, DBL_MAX), (uint32_t)ri, (uint32_t)k);
                s = rs__arc_add(s, rs__arc_len(ax, ay, bx, by));
            }
            ax = bx;
            ay = by;
            if (!keep) continue;
            /* (an unlisted segment is kept where a whole field keeps it:
             * when it reaches a cell) */
            sg.unlisted = (uint8_t)seg_unlisted(f, &sg);
            int64_t v = seg_cells(&b, &sg, sg.unlisted ? 2 : 0, 0);
            f->nunlisted += sg.unlisted && v > 0;
            if (v < 0) { res = RS_ERR_LIMIT; goto fail; }
            if (v == 0) continue;
            if (f->nseg == cap_seg) {
                size_t nc = cap_seg ? 2 * cap_seg : b.seg0, bytes;
                if (nc > UINT32_MAX || !rs__mul_size(nc, sizeof(rf_seg), &bytes)) { res = RS_ERR_LIMIT; goto fail; }
                rf_seg *ns = rs__realloc(ctx, f->seg, bytes);
                if (!ns) { res = RS_ERR_NOMEM; goto fail; }
                f->seg = ns;
                cap_seg = nc;
            }
            f->seg[f->nseg++] = sg;
            rec_end(&b, f->nseg - 1);
        }
    }
    f->rfirst[nroads] = (uint32_t)f->nseg;
    if (f->nseg < cap_seg / 2) {
        /* most segments lay off the map: give the rest back */
        rf_seg *ns = rs__realloc(ctx, f->seg, (f->nseg ? f->nseg : 1) * sizeof(rf_seg));
        if (ns) {
            f->seg = ns;
            cap_seg = f->nseg ? f->nseg : 1;
        }
    }
    if ((res = index_finish(ctx, f, &b, cap_seg)) != RS_OK) goto fail;
    *out = f;
    rs__ok(ctx);
    return RS_OK;
fail:
    return build_fail(ctx, f, &b, res);
}

static rs_result tees_widen(rs_ctx *ctx, rs__roadfield *f, const rs__roadfield *src, const double *extra,
                           size_t nroads);

/* src's segments (the same ids) widened by extra[road] (NULL: none) and
 * indexed for pixels up to `pixel` (0: src's). */
static rs_result derive(rs_ctx *ctx, const rs__roadfield *src, const double *extra, size_t nroads, double pixel,
                        rs__roadfield **out)
{
    *out = NULL;
    rs__roadfield *f = rs__calloc(ctx, 1, sizeof *f);
    if (!f) return rs__fail(ctx, RS_ERR_NOMEM, "roadfield: out of memory");
    f->c = src->c;
    f->inv_c = src->inv_c;
    f->gw = src->gw;
    f->gh = src->gh;
    f->pixel = pixel > 0 ? pixel : src->pixel;
    f->margin = pixel > 0 ? f->pixel * HALF_SQRT2 : src->margin;
    f->reach_extra = src->reach_extra;
    f->reach = pixel > 0 ? f->reach_extra + f->margin : src->reach;
    f->relscan = src->relscan;
    f->window_on = src->window_on;
    memcpy(f->window, src->window, sizeof f->window);
    f->window_reach = src->window_reach;
    size_t ncell = (size_t)f->gw * f->gh;
    rf_builder b;
    builder_init(&b, ctx, f);
    /* the widened lists hold at least the source's entries */
    b.rec0 = src->nent + src->nent / 4 > 4096 ? src->nent + src->nent / 4 : 4096;
    b.seg_all = src->nseg;
    rs_result res = RS_OK;
    f->start = rs__calloc(ctx, ncell + 1, sizeof *f->start);
    f->full = rs__calloc(ctx, ncell, 1);
    f->seg = rs__alloc_array(ctx, src->nseg ? src->nseg : 1, sizeof *f->seg);
    f->rstart = rs__calloc(ctx, (size_t)f->gh + 1, sizeof *f->rstart);
    if (!f->start || !f->full || !f->seg || !f->rstart) { res = RS_ERR_NOMEM; goto fail; }
    b.cnt = f->start;
    f->nseg = src->nseg;
    /* the same segments in the same order (the ids of both fields agree),
     * each grown by its road's extra half width; the index anew */
    for (size_t k = 0; k < f->nseg; k++) {
        rf_seg *sg = &f->seg[k];
        b.seg_pass = k + 1;
        if (rs__tick(ctx, 0)) { res = RS_ERR_CANCELLED; goto fail; }
        *sg = src->seg[k];
        if (extra) sg->r += extra[sg->road];
        sg->tee = 0; /* (tees_widen marks them by this field's shapes) */
        sg->jnext = 0;
        sg->jpart = 0;
        sg->redundant = 0;
        sg->unlisted = (uint8_t)seg_unlisted(f, sg); /* (by its own width and reach) */
        f->nunlisted += sg->unlisted;
        if (sg->unlisted) b.pcell = UINT32_MAX;
        else if (seg_cells(&b, sg, 0, 0) < 0) { res = RS_ERR_LIMIT; goto fail; }
        rec_end(&b, k);
    }
    if ((res = index_finish(ctx, f, &b, f->nseg)) != RS_OK) goto fail;
    if ((res = tees_widen(ctx, f, src, extra, nroads)) != RS_OK) {
        rs__roadfield_free(ctx, f);
        return rs__fail(ctx, res, res == RS_ERR_CANCELLED ? "cancelled" : "roadfield: out of memory");
    }
    *out = f;
    rs__ok(ctx);
    return RS_OK;
fail:
    return build_fail(ctx, f, &b, res);
}

rs_result rs__roadfield_widen(rs_ctx *ctx, const rs__roadfield *src, const double *extra, size_t nroads,
                              rs__roadfield **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out || !src || !extra) return rs__fail(ctx, RS_ERR_INVALID_ARG, "roadfield: NULL argument");
    *out = NULL;
    for (size_t k = 0; k < src->nseg; k++) {
        uint32_t road = src->seg[k].road;
        if (road >= nroads || !(extra[road] >= 0 && extra[road] <= src->c))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "roadfield: widening of road %lu must be 0..%g m",
                            (unsigned long)road, src->c);
    }
    return derive(ctx, src, extra, nroads, 0, out);
}

rs_result rs__roadfield_repixel(rs_ctx *ctx, const rs__roadfield *src, double pixel, rs__roadfield **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out || !src) return rs__fail(ctx, RS_ERR_INVALID_ARG, "roadfield: NULL argument");
    *out = NULL;
    if (!(pixel > 0) || !isfinite(pixel)) return rs__fail(ctx, RS_ERR_INVALID_ARG, "roadfield: bad pixel %g", pixel);
    return derive(ctx, src, NULL, 0, pixel, out);
}

size_t rs__roadfield_bytes(const rs__roadfield *f) { return f ? f->bytes : 0; }

double rs__roadfield_cell(const rs__roadfield *f) { return f ? f->c : 0; }

double rs__roadfield_pixel(const rs__roadfield *f) { return f ? f->pixel : 0; }

rs__roadfield_params rs__roadfield_params_for_dem(const rs_dem *dem, uint32_t texels)
{
    rs__roadfield_params p;
    memset(&p, 0, sizeof p);
    p.origin_x = dem->frame.origin_x;
    p.origin_y = dem->frame.origin_y;
    p.cell_size = dem->frame.cell_size;
    p.width_m = (double)(dem->width - 1) * dem->frame.cell_size;
    p.height_m = (double)(dem->height - 1) * dem->frame.cell_size;
    p.pixel = dem->frame.cell_size / texels;
    return p;
}

void rs__roadfield_get_stats(const rs__roadfield *f, rs__roadfield_stats *out)
{
    if (!out) return;
    memset(out, 0, sizeof *out);
    if (!f) return;
    out->index_cell = f->c;
    out->gw = f->gw;
    out->gh = f->gh;
    out->segments = f->nseg;
    out->entries = f->nent;
    out->nonempty_cells = f->nonempty;
    out->full_cells = f->nfull;
    out->max_list = f->maxlist;
    out->redundant = f->nredundant;
    out->relation_work = f->relwork;
    out->tees = f->ntee;
}

/* ------------------------------------------------------------------------
 * Queries. A query point's candidates are the lists of a rectangle of
 * cells [i0,i1] x [j0,j1]: one cell when the wanted reach is within the
 * lists' reach, else every cell the reach can touch (a segment may then be
 * seen twice: harmless for a minimum and a maximum).
 * ---------------------------------------------------------------------- */
typedef struct rf_cells { uint32_t i0, i1, j0, j1; } rf_cells;

/* Cells overlapping [x-d, x+d] x [y-d, y+d]; 0 when none. */
static int cells_around(const rs__roadfield *f, double x, double y, double d, rf_cells *cr)
{
    double c = f->c, lo_x = x - d, hi_x = x + d, lo_y = y - d, hi_y = y + d;
    double gx1 = ((double)f->gw - 1) * c, gy1 = ((double)f->gh - 1) * c;
    if (!(hi_x >= -c && lo_x <= gx1 && hi_y >= -c && lo_y <= gy1)) return 0;
    cr->i0 = clamp_index(floor(lo_x * f->inv_c) + 1, f->gw);
    cr->i1 = clamp_index(floor(hi_x * f->inv_c) + 1, f->gw);
    cr->j0 = clamp_index(floor(lo_y * f->inv_c) + 1, f->gh);
    cr->j1 = clamp_index(floor(hi_y * f->inv_c) + 1, f->gh);
    return 1;
}

/* ---- T ends (docs/network.md "Ends at a T") ----
 * A record end on a road passing through its node has no round cap: its
 * end segment's strip runs on, flat, to the through road's far edge line
 * n.p = c and stops there (c = n.E + R: E the end point, R the through
 * road's half width, n its normal pointing across from the leg). The
 * normal coverage pass computes the union of the capsules; every pixel
 * where the trimmed shape and the capsule of a T segment may differ
 * (neither both certainly outside nor both certainly inside) is then
 * computed again from the shapes of all segments near it: per sub-row
 * the exact union of their intervals on the row (each shape is at most
 * three convex pieces), TEE_ROWS rows (midpoint rule across). */
#define TEE_ROWS 16
#define TEE_IV_MAX 256

typedef struct rf_tee {
    uint32_t seg;          /* the leg's end segment */
    int end;               /* 1: the segment's b is the T end, 0: its a; 2: no end of it, only the
                              clip line (another segment of the record reaching past it) */
    double nx, ny;         /* the through road's normal, from the leg across */
    double cE, R;          /* n.E, the through road's half width */
    double c;              /* cE + R: keep n.p <= c */
    uint32_t through;      /* the road it ends on */
    double G;              /* how far that road's shape in this field reaches past c
                              (a widened field: its casing's width; else 0) */
    double box[4];         /* x0, x1, y0, y1 (local metres): where the trimmed shape and the capsule differ */
    uint32_t row0;         /* the first grid row of box */
    uint8_t live;          /* 0: an end-2 clip line the segment's shape (its strips included) does not
                              reach past: it changes nothing and is left out everywhere (tees_finish) */
} rf_tee;

int rs__roadfield_rows_have(const rs__roadfield *f, double y0, double y1)
{
    if (!f || !(y0 <= y1)) return 0;
    /* the index rows the band meets, clamped to the grid (a point beyond it
     * is in the nearest row's lists) */
    double a = floor(y0 * f->inv_c) + 1.0, b = floor(y1 * f->inv_c) + 1.0, top = (double)f->gh - 1;
    a = a > 0 ? (a < top ? a : top) : 0;
    b = b > 0 ? (b < top ? b : top) : 0;
    for (uint32_t j = (uint32_t)a; j <= (uint32_t)b; j++)
        if (f->rstart[j] != f->rstart[j + 1] || (f->ntee && f->tstart[j] != f->tstart[j + 1])) return 1;
    return 0;
}

void rs__roadfield_bounds(const rs__roadfield *f, double box[4])
{
    box[0] = box[2] = INFINITY;
    box[1] = box[3] = -INFINITY;
    for (size_t k = 0; f && k < f->nseg; k++) {
        const rf_seg *s = &f->seg[k];
        box[0] = lm_min(box[0], lm_min(s->ax, s->bx) - s->r), box[1] = lm_max(box[1], lm_max(s->ax, s->bx) + s->r);
        box[2] = lm_min(box[2], lm_min(s->ay, s->by) - s->r), box[3] = lm_max(box[3], lm_max(s->ay, s->by) + s->r);
    }
    /* a trimmed end's strip reaches past its capsule */
    for (size_t k = 0; f && k < f->ntee; k++) {
        const double *b = f->tee[k].box;
        box[0] = lm_min(box[0], b[0]), box[1] = lm_max(box[1], b[1]);
        box[2] = lm_min(box[2], b[2]), box[3] = lm_max(box[3], b[3]);
    }
}

/* The tees of segment s (those of f->tee with seg == id): [*i0, *i1). */
static void tees_of(const rs__roadfield *f, uint32_t id, size_t *i0, size_t *i1)
{
    size_t lo = 0, hi = f->ntee;
    while (lo < hi) {
        size_t m = lo + (hi - lo) / 2;
        if (f->tee[m].seg < id) lo = m + 1;
        else hi = m;
    }
    *i0 = lo;
    while (lo < f->ntee && f->tee[lo].seg == id) lo++;
    *i1 = lo;
}

/* The trimmed shape of segment s as a lower bound of its signed distance
 * (exact depth inside): the strip cut by its clip lines, an end normal at
 * an untrimmed end, and the end disc there. Its tees: f->tee[i0, i1). */
static double tee_sd_at(const rs__roadfield *f, const rf_seg *s, size_t i0, size_t i1, double x, double y)
{
    double wx = x - s->ax, wy = y - s->ay, u = wx * s->ux + wy * s->uy, t = wx * s->uy - wy * s->ux;
    /* a zero-length segment (a repeated end point the T clips) has no
     * strip, as shape_of says: its t is 0 everywhere, which made every
     * point short of the clip line "on" it (fuzz/edits: a road's fill
     * taken by a repeated point's T 7 m away, in the cells that listed it) */
    double sd = s->len > 0 ? fabs(t) - s->r : INFINITY, disc = INFINITY, hmax = -INFINITY;
    int cut[2] = { 0, 0 };
    for (size_t k = i0; k < i1; k++) {
        const rf_tee *T = &f->tee[k];
        if (!T->live) continue;
        hmax = lm_max(hmax, x * T->nx + y * T->ny - T->c);
        if (T->end < 2) cut[T->end] = 1;
    }
    sd = lm_max(sd, hmax);
    if (!cut[0]) {
        sd = lm_max(sd, -u);
        disc = lm_min(disc, len2(wx, wy) - s->r);
    }
    if (!cut[1]) {
        sd = lm_max(sd, u - s->len);
        disc = lm_min(disc, len2(x - s->bx, y - s->by) - s->r);
    }
    return lm_min(sd, lm_max(disc, hmax));
}

/* tee_sd with s's tees found here (tee_sd_at: a caller that asks about
 * one segment many times finds them once) */
static double tee_sd(const rs__roadfield *f, const rf_seg *s, double x, double y)
{
    size_t i0, i1;
    tees_of(f, (uint32_t)(s - f->seg), &i0, &i1);
    return tee_sd_at(f, s, i0, i1, x, y);
}

/* A segment's shape for the rows, as bounds linear in the row's y: the
 * strip's (its sides, the normals of untrimmed ends; for rows within
 * [ylo, yhi]) and the clip lines' (on every piece), x >= a + b y (lo) or
 * x <= a + b y (hi); the discs of untrimmed ends. */
typedef struct rf_shape {
    double sa[6], sb[6]; /* bounds: the strip's [0, nstrip), then the clip lines' */
    int8_t shi[6];       /* 1: x <= a + b y, 0: x >= a + b y */
    int nstrip, nclip, ndisc, strip;
    double ylo, yhi;     /* the strip's rows */
    double cyl, cyh;     /* every piece's rows (clip lines along x) */
    double disc[2][3];   /* x, y, r */
} rf_shape;

/* The bound g.(p - o) <= v (g = (gx, gy)) on a row: x <= or >= a + b y;
 * gx = 0 narrows the rows [ylo, yhi] instead. Returns 1 when it is a bound. */
static int shape_bound(rf_shape *sh, int k, double gx, double gy, double ox, double oy, double v)
{
    if (gx == 0) {
        /* gy (y - oy) <= v */
        if (gy > 0) sh->yhi = lm_min(sh->yhi, oy + v / gy);
        else if (gy < 0) sh->ylo = lm_max(sh->ylo, oy + v / gy);
        else if (v < 0) sh->ylo = INFINITY;
        return 0;
    }
    /* x = ox + (v - gy (y - oy)) / gx */
    sh->sa[k] = ox + (v + gy * oy) / gx;
    sh->sb[k] = -gy / gx;
    sh->shi[k] = gx > 0;
    return 1;
}

/* s's shape; its tees f->tee[i0, i1) (none read when s->tee is 0) */
static void shape_of_at(const rs__roadfield *f, const rf_seg *s, size_t i0, size_t i1, rf_shape *sh)
{
    int cut[2] = { 0, 0 };
    double cl[2][3];
    int nh = 0;
    if (s->tee) {
        for (size_t k = i0; k < i1 && nh < 2; k++) {
            if (!f->tee[k].live) continue;
            cl[nh][0] = f->tee[k].nx, cl[nh][1] = f->tee[k].ny, cl[nh][2] = f->tee[k].c;
            if (f->tee[k].end < 2) cut[f->tee[k].end] = 1;
            nh++;
        }
    }
    sh->ylo = -INFINITY, sh->yhi = INFINITY;
    sh->strip = s->len > 0;
    sh->nstrip = 0;
    if (sh->strip) {
        /* g.(p - a) <= v: the sides |t| <= r, u >= 0, u <= len */
        double g[4][3] = { { s->uy, -s->ux, s->r }, { -s->uy, s->ux, s->r }, { -s->ux, -s->uy, 0 },
                           { s->ux, s->uy, s->len } };
        for (int k = 0; k < 4; k++) {
            if ((k == 2 && cut[0]) || (k == 3 && cut[1])) continue;
            sh->nstrip += shape_bound(sh, sh->nstrip, g[k][0], g[k][1], s->ax, s->ay, g[k][2]);
        }
    }
    double ylo = sh->ylo, yhi = sh->yhi; /* the strip's rows; the clip lines' apply to every piece */
    sh->nclip = 0;
    sh->ylo = -INFINITY, sh->yhi = INFINITY;
    for (int j = 0; j < nh; j++) sh->nclip += shape_bound(sh, sh->nstrip + sh->nclip, cl[j][0], cl[j][1], 0, 0, cl[j][2]);
    /* the clip lines' rows (a clip line along x) narrow every piece */
    sh->cyl = sh->ylo, sh->cyh = sh->yhi;
    sh->ylo = lm_max(ylo, sh->cyl), sh->yhi = lm_min(yhi, sh->cyh);
    sh->ndisc = 0;
    for (int e = 0; e < 2; e++) {
        if (cut[e] || (e && !(s->len > 0))) continue;
        double *d = sh->disc[sh->ndisc++];
        d[0] = e ? s->bx : s->ax, d[1] = e ? s->by : s->ay, d[2] = s->r;
    }
}

static void shape_of(const rs__roadfield *f, const rf_seg *s, rf_shape *sh)
{
    size_t i0 = 0, i1 = 0;
    if (s->tee) tees_of(f, (uint32_t)(s - f->seg), &i0, &i1);
    shape_of_at(f, s, i0, i1, sh);
}

/* The shape on the row y, x relative to x0, clipped to [0, pix], appended
 * to iv (pairs); returns the new count. */
static size_t shape_row(const rf_shape *sh, double y, double x0, double pix, double *iv, size_t n)
{
    double lo[3], hi[3];
    int np = 0;
    if (!(y >= sh->cyl && y <= sh->cyh)) return n;
    for (int k = 0; k < sh->ndisc; k++) {
        double dy = y - sh->disc[k][1], q = sh->disc[k][2] * sh->disc[k][2] - dy * dy;
        if (!(q >= 0)) continue;
        q = sqrt(q);
        lo[np] = sh->disc[k][0] - q, hi[np] = sh->disc[k][0] + q;
        np++;
    }
    if (sh->strip && y >= sh->ylo && y <= sh->yhi) {
        double l = -INFINITY, h = INFINITY;
        for (int k = 0; k < sh->nstrip; k++) {
            double x = sh->sa[k] + sh->sb[k] * y;
            if (sh->shi[k]) h = lm_min(h, x);
            else l = lm_max(l, x);
        }
        lo[np] = l, hi[np] = h;
        np++;
    }
    for (int k = 0; k < np; k++) {
        double l = lo[k], h = hi[k];
        for (int j = sh->nstrip; j < sh->nstrip + sh->nclip; j++) {
            double x = sh->sa[j] + sh->sb[j] * y;
            if (sh->shi[j]) h = lm_min(h, x);
            else l = lm_max(l, x);
        }
        l = lm_max(l - x0, 0), h = lm_min(h - x0, pix);
        if (!(h > l)) continue;
        iv[2 * n] = l, iv[2 * n + 1] = h;
        n++;
    }
    return n;
}

/* Length of the union of n intervals (sorted here). */
static double union_len(double *iv, size_t n)
{
    for (size_t i = 1; i < n; i++) {
        double l = iv[2 * i], h = iv[2 * i + 1];
        size_t j = i;
        while (j > 0 && (iv[2 * j - 2] > l || (iv[2 * j - 2] == l && iv[2 * j - 1] > h))) {
            iv[2 * j] = iv[2 * j - 2], iv[2 * j + 1] = iv[2 * j - 1];
            j--;
        }
        iv[2 * j] = l, iv[2 * j + 1] = h;
    }
    double sum = 0, cl = 0, ch = -1;
    for (size_t i = 0; i < n; i++) {
        if (iv[2 * i] > ch) {
            if (ch > cl) sum += ch - cl;
            cl = iv[2 * i], ch = iv[2 * i + 1];
        } else ch = lm_max(ch, iv[2 * i + 1]);
    }
    if (ch > cl) sum += ch - cl;
    return sum;
}

/* Merges iv into disjoint intervals (when the buffer fills). */
static size_t union_compact(double *iv, size_t n)
{
    union_len(iv, n); /* sorts */
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        if (m && iv[2 * i] <= iv[2 * m - 1]) iv[2 * m - 1] = lm_max(iv[2 * m - 1], iv[2 * i + 1]);
        else iv[2 * m] = iv[2 * i], iv[2 * m + 1] = iv[2 * i + 1], m++;
    }
    return m;
}

#if defined(__SSE2__)
/* A shape on all TEE_ROWS sub-rows of a pixel at once, two rows a register:
 * per piece p (its discs, then its strip: shape_row's order) the interval
 * lo[p][k], hi[p][k] on row k and ok[p][k] = 1 where shape_row emits it,
 * with shape_row's operations lane by lane (so the same doubles). */
typedef struct rf_rows {
    double lo[3][TEE_ROWS], hi[3][TEE_ROWS];
    uint8_t ok[3][TEE_ROWS];
    int np;
} rf_rows;

/* lm_max and lm_min lane by lane */
static inline __m128d rows_max(__m128d x, __m128d y)
{
    __m128d m = _mm_or_pd(_mm_cmpge_pd(x, y), _mm_cmpunord_pd(y, y));
    return _mm_or_pd(_mm_and_pd(m, x), _mm_andnot_pd(m, y));
}
static inline __m128d rows_min(__m128d x, __m128d y)
{
    __m128d m = _mm_or_pd(_mm_cmple_pd(x, y), _mm_cmpunord_pd(y, y));
    return _mm_or_pd(_mm_and_pd(m, x), _mm_andnot_pd(m, y));
}

static void shape_rows(const rf_shape *sh, double y0, double x0, double pix, rf_rows *R)
{
    const __m128d zero = _mm_setzero_pd(), vpix = _mm_set1_pd(pix), vx0 = _mm_set1_pd(x0);
    const int np = sh->ndisc + (sh->strip ? 1 : 0);
    R->np = np;
    for (int k = 0; k < TEE_ROWS; k += 2) {
        const __m128d y = _mm_set_pd(y0 + ((double)(k + 1) + 0.5) * (pix / TEE_ROWS), y0 + ((double)k + 0.5) * (pix / TEE_ROWS));
        const __m128d rowok = _mm_and_pd(_mm_cmpge_pd(y, _mm_set1_pd(sh->cyl)), _mm_cmple_pd(y, _mm_set1_pd(sh->cyh)));
        for (int p = 0; p < np; p++) {
            __m128d l, h, ok;
            if (p < sh->ndisc) {
                const double *d = sh->disc[p];
                __m128d dy = _mm_sub_pd(y, _mm_set1_pd(d[1]));
                __m128d q = _mm_sub_pd(_mm_set1_pd(d[2] * d[2]), _mm_mul_pd(dy, dy));
                ok = _mm_and_pd(rowok, _mm_cmpge_pd(q, zero));
                q = _mm_sqrt_pd(_mm_and_pd(ok, q)); /* (0 where the row misses the disc) */
                l = _mm_sub_pd(_mm_set1_pd(d[0]), q);
                h = _mm_add_pd(_mm_set1_pd(d[0]), q);
            } else {
                ok = _mm_and_pd(rowok, _mm_and_pd(_mm_cmpge_pd(y, _mm_set1_pd(sh->ylo)), _mm_cmple_pd(y, _mm_set1_pd(sh->yhi))));
                l = _mm_set1_pd(-INFINITY);
                h = _mm_set1_pd(INFINITY);
                for (int j = 0; j < sh->nstrip; j++) {
                    __m128d x = _mm_add_pd(_mm_set1_pd(sh->sa[j]), _mm_mul_pd(_mm_set1_pd(sh->sb[j]), y));
                    if (sh->shi[j]) h = rows_min(h, x);
                    else l = rows_max(l, x);
                }
            }
            for (int j = sh->nstrip; j < sh->nstrip + sh->nclip; j++) {
                __m128d x = _mm_add_pd(_mm_set1_pd(sh->sa[j]), _mm_mul_pd(_mm_set1_pd(sh->sb[j]), y));
                if (sh->shi[j]) h = rows_min(h, x);
                else l = rows_max(l, x);
            }
            l = rows_max(_mm_sub_pd(l, vx0), zero);
            h = rows_min(_mm_sub_pd(h, vx0), vpix);
            ok = _mm_and_pd(ok, _mm_cmpgt_pd(h, l));
            _mm_storeu_pd(&R->lo[p][k], l);
            _mm_storeu_pd(&R->hi[p][k], h);
            const int m = _mm_movemask_pd(ok);
            R->ok[p][k] = (uint8_t)(m & 1);
            R->ok[p][k + 1] = (uint8_t)(m >> 1);
        }
    }
}
#endif

static size_t shape_add(const rf_shape *sh, double y, double x0, double pix, double *iv, size_t n)
{
    if (n + 3 > TEE_IV_MAX) n = union_compact(iv, n);
    if (n + 3 > TEE_IV_MAX) return n; /* 250 disjoint pieces of roads in one pixel row: drops the rest */
    return shape_row(sh, y, x0, pix, iv, n);
}

static size_t seg_add(const rs__roadfield *f, const rf_seg *s, double y, double x0, double pix, double *iv, size_t n)
{
    rf_shape sh;
    shape_of(f, s, &sh);
    return shape_add(&sh, y, x0, pix, iv, n);
}

/* Coverage of pixel (px, py) of side pix from every shape near it: the
 * segments of the cells the pixel meets and the T segments whose box it
 * meets, those within the pixel's half diagonal of it (a T segment by the
 * lower bound tee_sd) kept; one certainly holding the pixel gives 1. */
#define TEE_NEAR_MAX 64
#define TEE_CAND_MAX 24 /* a T box's candidates held with their shapes (rf_tcand: 224 bytes each, twice on
                           tee_pass's stack); more: the pixels read the lists */
#define TEE_ROWS_NEAR 8 /* tee_rows takes up to this many shapes all rows at once (rf_rows: 6.5 KB) */

/* A candidate of tee_pixel with what every pixel asks of it, found once
 * per T box: its tees and its shape. */
typedef struct rf_tcand {
    const rf_seg *s;
    size_t i0, i1; /* f->tee[i0, i1): its tees (none when s->tee is 0) */
    rf_shape sh;   /* shape_of */
} rf_tcand;

/* The union of the near shapes over the pixel's TEE_ROWS sub-rows,
 * averaged: near[nn] (all = 0), or every segment the lists give. */
static double tee_rows(const rs__roadfield *f, double x0, double y0, double pix, const rf_shape *const *near, size_t nn,
                       int all)
{
    double iv[2 * TEE_IV_MAX], acc = 0;
#if defined(__SSE2__)
    if (!all && nn <= TEE_ROWS_NEAR) {
        /* every shape on all the rows first (nn shapes give at most 3 nn
         * intervals a row: shape_add never compacts), then each row's
         * intervals in shape_row's order */
        rf_rows R[TEE_ROWS_NEAR];
        for (size_t q = 0; q < nn; q++) shape_rows(near[q], y0, x0, pix, &R[q]);
        for (int k = 0; k < TEE_ROWS; k++) {
            size_t n = 0;
            for (size_t q = 0; q < nn; q++)
                for (int p = 0; p < R[q].np; p++)
                    if (R[q].ok[p][k]) iv[2 * n] = R[q].lo[p][k], iv[2 * n + 1] = R[q].hi[p][k], n++;
            acc += union_len(iv, n) / pix;
        }
        return acc / TEE_ROWS;
    }
#endif
    double x1 = x0 + pix, y1 = y0 + pix;
    uint32_t i0 = clamp_index(floor(x0 * f->inv_c) + 1, f->gw), i1 = clamp_index(floor(x1 * f->inv_c) + 1, f->gw);
    uint32_t j0 = clamp_index(floor(y0 * f->inv_c) + 1, f->gh), j1 = clamp_index(floor(y1 * f->inv_c) + 1, f->gh);
    for (int k = 0; k < TEE_ROWS; k++) {
        double y = y0 + ((double)k + 0.5) * (pix / TEE_ROWS);
        size_t n = 0;
        if (!all)
            for (size_t q = 0; q < nn; q++) n = shape_add(near[q], y, x0, pix, iv, n);
        else {
            for (uint32_t j = j0; j <= j1; j++)
                for (uint32_t i = i0; i <= i1; i++) {
                    size_t cell = (size_t)j * f->gw + i;
                    for (uint32_t e2 = f->start[cell]; e2 < f->start[cell + 1]; e2++)
                        n = seg_add(f, &f->seg[f->ids[e2]], y, x0, pix, iv, n);
                }
            for (uint32_t j = j0; j <= j1; j++)
                for (uint32_t e2 = f->tstart[j]; e2 < f->tstart[j + 1]; e2++) {
                    const rf_tee *T = &f->tee[f->tids[e2]];
                    if (x1 < T->box[0] || x0 > T->box[1] || y1 < T->box[2] || y0 > T->box[3]) continue;
                    n = seg_add(f, &f->seg[T->seg], y, x0, pix, iv, n);
                }
        }
        acc += union_len(iv, n) / pix;
    }
    return acc / TEE_ROWS;
}

/* tee_pixel from the lists of the cells and T boxes the pixel meets. */
static double tee_pixel_lists(const rs__roadfield *f, uint32_t px, uint32_t py, double pix)
{
    double x0 = (double)px * pix, y0 = (double)py * pix, x1 = x0 + pix, y1 = y0 + pix;
    double cx = x0 + 0.5 * pix, cy = y0 + 0.5 * pix, e = pix * HALF_SQRT2, slack = 1e-9 * (1 + fabs(cx) + fabs(cy));
    uint32_t i0 = clamp_index(floor(x0 * f->inv_c) + 1, f->gw), i1 = clamp_index(floor(x1 * f->inv_c) + 1, f->gw);
    uint32_t j0 = clamp_index(floor(y0 * f->inv_c) + 1, f->gh), j1 = clamp_index(floor(y1 * f->inv_c) + 1, f->gh);
    rf_shape own[TEE_NEAR_MAX];
    const rf_shape *near[TEE_NEAR_MAX];
    size_t nn = 0;
    int all = 0; /* more than TEE_NEAR_MAX near: every listed segment takes part */
    for (int pass = 0; pass < 2; pass++)
        for (uint32_t j = j0; j <= j1; j++) {
            uint32_t a = pass ? f->tstart[j] : 0, b = pass ? f->tstart[j + 1] : 0;
            for (uint32_t i = pass ? i1 : i0; i <= i1; i++) {
                size_t cell = (size_t)j * f->gw + i;
                if (!pass) a = f->start[cell], b = f->start[cell + 1];
                for (uint32_t k = a; k < b; k++) {
                    const rf_seg *s;
                    if (pass) {
                        const rf_tee *T = &f->tee[f->tids[k]];
                        if (x1 < T->box[0] || x0 > T->box[1] || y1 < T->box[2] || y0 > T->box[3]) continue;
                        s = &f->seg[T->seg];
                    } else
                        s = &f->seg[f->ids[k]];
                    double sd = s->tee ? tee_sd(f, s, cx, cy) : seg_dist(s, cx, cy) - s->r;
                    if (sd <= -e - slack) return 1;
                    if (!(sd < e + slack)) continue;
                    if (nn < TEE_NEAR_MAX) {
                        shape_of(f, s, &own[nn]);
                        near[nn] = &own[nn];
                        nn++;
                    } else
                        all = 1;
                }
            }
        }
    return tee_rows(f, x0, y0, pix, near, nn, all);
}

/* The same from cand[ncand], a superset of the segments near the pixel
 * (tee_candidates: the near set tee_pixel_lists finds, in the same order,
 * so the same doubles). */
static double tee_pixel(const rs__roadfield *f, uint32_t px, uint32_t py, double pix, const rf_tcand *cand,
                        size_t ncand)
{
    double x0 = (double)px * pix, y0 = (double)py * pix;
    double cx = x0 + 0.5 * pix, cy = y0 + 0.5 * pix, e = pix * HALF_SQRT2, slack = 1e-9 * (1 + fabs(cx) + fabs(cy));
    const rf_shape *near[TEE_NEAR_MAX];
    size_t nn = 0;
    for (size_t k = 0; k < ncand; k++) {
        const rf_seg *s = cand[k].s;
        double sd = s->tee ? tee_sd_at(f, s, cand[k].i0, cand[k].i1, cx, cy) : seg_dist(s, cx, cy) - s->r;
        if (sd <= -e - slack) return 1;
        if (sd < e + slack) near[nn++] = &cand[k].sh; /* ncand <= TEE_CAND_MAX <= TEE_NEAR_MAX */
    }
    return tee_rows(f, x0, y0, pix, near, nn, 0);
}

/* The segments whose shape may come within e of the box [x0, x1] x [y0,
 * y1] (by their centreline boxes grown by r + e, a T segment's by its T
 * box), each once, into cand with their tees and shapes; 0 when more than
 * TEE_CAND_MAX (the pixels then read the lists themselves). */
static size_t tee_candidates(const rs__roadfield *f, double x0, double y0, double x1, double y1, double e,
                             rf_tcand *cand)
{
    uint32_t i0 = clamp_index(floor(x0 * f->inv_c) + 1, f->gw), i1 = clamp_index(floor(x1 * f->inv_c) + 1, f->gw);
    uint32_t j0 = clamp_index(floor(y0 * f->inv_c) + 1, f->gh), j1 = clamp_index(floor(y1 * f->inv_c) + 1, f->gh);
    size_t n = 0;
    for (uint32_t j = j0; j <= j1; j++) {
        for (uint32_t i = i0; i <= i1; i++) {
            size_t cell = (size_t)j * f->gw + i;
            for (uint32_t k = f->start[cell]; k < f->start[cell + 1]; k++) {
                const rf_seg *s = &f->seg[f->ids[k]];
                double g = s->r + e + s->tol;
                if (!s->tee && (SEG_XMAX(s) + g < x0 || SEG_XMIN(s) - g > x1 || SEG_YMAX(s) + g < y0 || SEG_YMIN(s) - g > y1)) continue;
                size_t q = 0;
                while (q < n && cand[q].s != s) q++;
                if (q < n) continue;
                if (n == TEE_CAND_MAX) return 0;
                cand[n++].s = s;
            }
        }
        for (uint32_t k = f->tstart[j]; k < f->tstart[j + 1]; k++) {
            const rf_tee *T = &f->tee[f->tids[k]];
            if (x1 < T->box[0] || x0 > T->box[1] || y1 < T->box[2] || y0 > T->box[3]) continue;
            const rf_seg *s = &f->seg[T->seg];
            size_t q = 0;
            while (q < n && cand[q].s != s) q++;
            if (q < n) continue;
            if (n == TEE_CAND_MAX) return 0;
            cand[n++].s = s;
        }
    }
    for (size_t q = 0; q < n; q++) { /* what each pixel asks of them, once */
        rf_tcand *c = &cand[q];
        c->i0 = c->i1 = 0;
        if (c->s->tee) tees_of(f, (uint32_t)(c->s - f->seg), &c->i0, &c->i1);
        shape_of_at(f, c->s, c->i0, c->i1, &c->sh);
    }
    return n;
}

/* A capsule that stays on the near side of T's clip line (a side road no
 * wider than the road it ends on, near square) loses nothing there; the
 * flat strip's corners it gains lie on the through road's own surface, so
 * the union is the same: nothing to compute again (most T ends of a city).
 * In a casing field the through road's shape reaches G past the line: what
 * the trimming cuts off within G is still covered. */
static int tee_end_unchanged(const rf_tee *T, const rf_seg *s, double e)
{
    return lm_max(T->nx * s->ax + T->ny * s->ay, T->nx * s->bx + T->ny * s->by) + s->r - T->c <= T->G - e;
}

/* Is the pixel centred at (cx, cy) (half diagonal e) within e of the edge
 * of s's capsule or of its trimmed shape (certainly inside or outside both
 * otherwise)? Its tees: f->tee[i0, i1). */
static int tee_near_edge(const rs__roadfield *f, const rf_seg *s, size_t i0, size_t i1, double cx, double cy, double e)
{
    double dc = seg_dist(s, cx, cy) - s->r, dt = tee_sd_at(f, s, i0, i1, cx, cy);
    return !((dc >= e && dt >= e) || (dc <= -e && dt <= -e));
}

/* Does pixel centre (cx, cy), within e of it, lie where T's trimmed shape
 * and its capsule may differ? They differ only beyond the clip line (the
 * capsule's part there) and past the record's end (the flat strip's
 * corners): not for a pixel square on the near side of the line and before
 * the end (T->end's side only: another clip of the segment is its own
 * entry). The same for a field and its widening (same line, same end). */
static int tee_may_differ(const rf_tee *T, const rf_seg *s, double cx, double cy, double e)
{
    if (T->nx * cx + T->ny * cy > T->c - e - 1e-9 * (1 + fabs(T->c))) return 1;
    double u = (cx - s->ax) * s->ux + (cy - s->ay) * s->uy, m = e + 1e-9 * (1 + s->len);
    if (T->end == 2) return 0;
    return T->end == 1 ? u > s->len - m : u < m;
}

/* The pixels of [px0, px0+w) x [py0, py0+h) where a T segment's trimmed
 * shape and its capsule may differ, computed again (tee_pixel) into out.
 * Depends only on the pixel: any block gives the same doubles.
 *
 * Pixels where the shapes cannot differ (tee_may_differ) keep their
 * first, exact values. With g (f's widening, rs__roadfield_widen: the same
 * T ends in the same order; NULL: f alone) both fields are done together,
 * into out and outg: a pixel is computed again in both when either needs
 * it, so R and C come from the same rule (the casing's share of a pixel
 * divides by 1 - R: an exact R beside a midpoint C, or the reverse, would
 * show). */
static void tee_pass(const rs__roadfield *f, const rs__roadfield *g, uint32_t px0, uint32_t py0, uint32_t w,
                     uint32_t h, double pix, double *out, double *outg, size_t stride)
{
    if (!f || !f->ntee) return;
    const rs__roadfield *lists = g ? g : f; /* g's boxes hold f's */
    rf_tcand cand[TEE_CAND_MAX], candg[TEE_CAND_MAX];
    double e = pix * HALF_SQRT2, by0 = (double)py0 * pix, by1 = ((double)py0 + h) * pix;
    double bx0 = (double)px0 * pix, bx1 = ((double)px0 + w) * pix;
    uint32_t j0 = clamp_index(floor(by0 * lists->inv_c) + 1, lists->gh);
    uint32_t j1 = clamp_index(floor(by1 * lists->inv_c) + 1, lists->gh);
    for (uint32_t j = j0; j <= j1; j++)
        for (uint32_t m = lists->tstart[j]; m < lists->tstart[j + 1]; m++) {
            const uint32_t ti = lists->tids[m];
            const rf_tee *Tf = &f->tee[ti], *Tg = g ? &g->tee[ti] : NULL;
            if (lists->tee[ti].row0 != j && j != j0) continue; /* once per call */
            double box[4] = { Tf->box[0], Tf->box[1], Tf->box[2], Tf->box[3] };
            if (Tg) /* the union of both boxes */
                box[0] = lm_min(box[0], Tg->box[0]), box[1] = lm_max(box[1], Tg->box[1]),
                box[2] = lm_min(box[2], Tg->box[2]), box[3] = lm_max(box[3], Tg->box[3]);
            if (box[1] < bx0 || box[0] > bx1 || box[3] < by0 || box[2] > by1) continue;
            /* the pixels whose square meets the box */
            double xa = lm_max(floor(box[0] / pix) - (double)px0, 0), xb = lm_min(floor(box[1] / pix) - (double)px0, (double)w - 1);
            double ya = lm_max(floor(box[2] / pix) - (double)py0, 0), yb = lm_min(floor(box[3] / pix) - (double)py0, (double)h - 1);
            if (!(xa <= xb && ya <= yb)) continue;
            uint32_t ka = (uint32_t)xa, kb = (uint32_t)xb, ra = (uint32_t)ya, rb = (uint32_t)yb;
            const rf_seg *sf = &f->seg[Tf->seg], *sg = Tg ? &g->seg[Tg->seg] : NULL;
            int need_f = Tf->live && !tee_end_unchanged(Tf, sf, e), need_g = Tg && Tg->live && !tee_end_unchanged(Tg, sg, e);
            if (!need_f && !need_g) continue;
            size_t fi0, fi1, gi0 = 0, gi1 = 0;
            tees_of(f, Tf->seg, &fi0, &fi1);
            if (Tg) tees_of(g, Tg->seg, &gi0, &gi1);
            double qx0 = lm_max(box[0], bx0) - pix, qx1 = lm_min(box[1], bx1) + pix;
            double qy0 = lm_max(box[2], by0) - pix, qy1 = lm_min(box[3], by1) + pix;
            size_t nc = 0, ncg = 0;
            int have = 0;
            for (uint32_t r = ra; r <= rb; r++)
                for (uint32_t k = ka; k <= kb; k++) {
                    double cx = ((double)px0 + k + 0.5) * pix, cy = ((double)py0 + r + 0.5) * pix;
                    /* (f alone too: a pixel computed again there took
                     * tee_pixel's value for the exact one, so R was not
                     * the same with and without a casing field: fuzz/edits) */
                    if (!tee_may_differ(Tf, sf, cx, cy, e)) continue;
                    if (!(need_f && tee_near_edge(f, sf, fi0, fi1, cx, cy, e)) &&
                        !(need_g && tee_near_edge(g, sg, gi0, gi1, cx, cy, e)))
                        continue;
                    if (!have) { /* the segments that can come near a pixel of the box here, once */
                        nc = tee_candidates(f, qx0, qy0, qx1, qy1, e, cand);
                        if (g) ncg = tee_candidates(g, qx0, qy0, qx1, qy1, e, candg);
                        have = 1;
                    }
                    out[(size_t)r * stride + k] =
                        nc ? tee_pixel(f, px0 + k, py0 + r, pix, cand, nc) : tee_pixel_lists(f, px0 + k, py0 + r, pix);
                    if (g)
                        outg[(size_t)r * stride + k] = ncg ? tee_pixel(g, px0 + k, py0 + r, pix, candg, ncg)
                                                           : tee_pixel_lists(g, px0 + k, py0 + r, pix);
                }
        }
}

/* How far along normal (nx, ny) a capsule comes, and a box (x0, x1, y0, y1):
 * how far a segment's trimmed shape reaches past a T line is the larger of
 * its capsule's and its own T strips' boxes' (set_tees, tees_finish). */
static double capsule_far(const rf_seg *q, double nx, double ny)
{
    return lm_max(nx * q->ax + ny * q->ay, nx * q->bx + ny * q->by) + q->r;
}

static double box_far(const double *b, double nx, double ny)
{
    return nx * (nx > 0 ? b[1] : b[0]) + ny * (ny > 0 ? b[3] : b[2]);
}

/* Box where the trimmed shape of T's segment and its capsule differ: the
 * end disc and the strip from where the clip line cuts its near side to
 * where it cuts its far side (u along the segment towards the end,
 * measured from the end point). */
static void tee_box(const rs__roadfield *f, rf_tee *T)
{
    const rf_seg *s = &f->seg[T->seg];
    if (T->end == 2) {
        /* the capsule's part beyond the line: its centreline where n.p >= c - r, grown by r */
        double fa = T->nx * s->ax + T->ny * s->ay, fb = T->nx * s->bx + T->ny * s->by, lo = T->c - s->r;
        double t0 = 0, t1 = 1;
        if (fa < lo && fb < lo) t0 = t1 = fa >= fb ? 0 : 1; /* (not reaching: a point) */
        else if (fa < lo) t0 = (lo - fa) / (fb - fa);
        else if (fb < lo) t1 = (lo - fa) / (fb - fa);
        double xa = s->ax + t0 * (s->bx - s->ax), ya = s->ay + t0 * (s->by - s->ay);
        double xb = s->ax + t1 * (s->bx - s->ax), yb = s->ay + t1 * (s->by - s->ay);
        double m = f->margin + s->r + 1e-9 * (1 + fabs(xa) + fabs(ya) + fabs(xb) + fabs(yb) + s->r);
        T->box[0] = lm_min(xa, xb) - m, T->box[1] = lm_max(xa, xb) + m;
        T->box[2] = lm_min(ya, yb) - m, T->box[3] = lm_max(ya, yb) + m;
        return;
    }
    double ex = T->end ? s->bx : s->ax, ey = T->end ? s->by : s->ay;
    double dx = T->end ? s->ux : -s->ux, dy = T->end ? s->uy : -s->uy; /* towards the end */
    double sn = T->nx * dx + T->ny * dy, cs = fabs(T->nx * dy - T->ny * dx), r = s->r;
    double reach = T->c - (T->nx * ex + T->ny * ey); /* the clip line's distance beyond E */
    double ua = (reach - r * cs) / sn, ub = (reach + r * cs) / sn;
    ua = lm_max(lm_min(ua, 0), -s->len);
    ub = lm_max(ub, 0);
    double b[4] = { ex - r, ex + r, ey - r, ey + r };
    for (int k = 0; k < 4; k++) {
        double u = k & 1 ? ub : ua, t = k & 2 ? r : -r;
        double x = ex + u * dx + t * dy, y = ey + u * dy - t * dx;
        b[0] = lm_min(b[0], x), b[1] = lm_max(b[1], x), b[2] = lm_min(b[2], y), b[3] = lm_max(b[3], y);
    }
    double m = f->margin + 1e-9 * (1 + fabs(ex) + fabs(ey) + r + fabs(ub));
    T->box[0] = b[0] - m, T->box[1] = b[1] + m, T->box[2] = b[2] - m, T->box[3] = b[3] + m;
}

/* f->tee holds ntee entries (seg, end, n, cE, R): sorts them, drops a
 * second clip of one segment end (and repeated clip-only entries), flags
 * the segments and builds the boxes and row lists. */
static rs_result tees_finish(rs_ctx *ctx, rs__roadfield *f)
{
    /* by segment, then end (0, 1, 2); keyed: the entries are 104 bytes */
    uint64_t *key = rs__alloc_array(ctx, f->ntee ? f->ntee : 1, sizeof *key);
    if (!key) return RS_ERR_NOMEM;
    for (size_t i = 0; i < f->ntee; i++) key[i] = (uint64_t)f->tee[i].seg << 2 | (uint64_t)f->tee[i].end;
    rs_result sr = rs__sort_keyed(ctx, f->tee, f->ntee, sizeof *f->tee, key);
    rs__free(ctx, key);
    if (sr) return sr;
    size_t m = 0;
    for (size_t i = 0; i < f->ntee; i++) {
        const rf_tee *a = &f->tee[m ? m - 1 : 0], *b = &f->tee[i];
        if (m && a->seg == b->seg && a->end == b->end && (a->end < 2 || (a->nx == b->nx && a->ny == b->ny && a->cE == b->cE)))
            continue;
        f->tee[m++] = f->tee[i];
    }
    f->ntee = m;
    size_t total = 0;
    f->tstart = rs__calloc(ctx, (size_t)f->gh + 1, sizeof *f->tstart);
    if (!f->tstart) return RS_ERR_NOMEM;
    for (size_t i = 0; i < m; i++) {
        rf_tee *T = &f->tee[i];
        T->c = T->cE + T->R;
        tee_box(f, T);
    }
    /* an end-2 line is live where the segment's shape reaches past it:
     * its capsule, or a strip of its own T ends (before it: by end) */
    for (size_t i = 0, g0 = 0; i < m; i++) {
        rf_tee *T = &f->tee[i];
        if (i == 0 || T->seg != f->tee[i - 1].seg) g0 = i;
        T->live = 1;
        if (T->end == 2) {
            double far = capsule_far(&f->seg[T->seg], T->nx, T->ny);
            for (size_t k = g0; k < i; k++)
                if (f->tee[k].end < 2) far = lm_max(far, box_far(f->tee[k].box, T->nx, T->ny));
            T->live = !(far - T->c <= 0); /* (NaN: live) */
        }
        if (T->live) f->seg[T->seg].tee |= (uint8_t)(T->end == 2 ? 4 : T->end ? 2 : 1);
    }
    for (size_t i = 0; i < m; i++) {
        if ((i & 16383) == 16383 && rs__poll(ctx)) return RS_ERR_CANCELLED;
        rf_tee *T = &f->tee[i];
        uint32_t r0 = clamp_index(floor(T->box[2] * f->inv_c) + 1, f->gh), r1 = clamp_index(floor(T->box[3] * f->inv_c) + 1, f->gh);
        T->row0 = r0;
        for (uint32_t r = r0; r <= r1; r++) f->tstart[r + 1]++;
        total += r1 - r0 + 1;
    }
    for (uint32_t r = 0; r < f->gh; r++) f->tstart[r + 1] += f->tstart[r];
    f->tids = rs__alloc_array(ctx, total ? total : 1, sizeof *f->tids);
    uint32_t *pos = rs__alloc_array(ctx, f->gh ? f->gh : 1, sizeof *pos);
    if (!f->tids || !pos) {
        rs__free(ctx, pos);
        return RS_ERR_NOMEM;
    }
    memcpy(pos, f->tstart, f->gh * sizeof *pos);
    for (size_t i = 0; i < m; i++) {
        if ((i & 16383) == 16383 && rs__poll(ctx)) {
            rs__free(ctx, pos);
            return RS_ERR_CANCELLED;
        }
        uint32_t r1 = clamp_index(floor(f->tee[i].box[3] * f->inv_c) + 1, f->gh);
        for (uint32_t r = f->tee[i].row0; r <= r1; r++) f->tids[pos[r]++] = (uint32_t)i;
    }
    rs__free(ctx, pos);
    f->bytes += m * sizeof *f->tee + ((size_t)f->gh + 1 + total) * sizeof *f->tids;
    return RS_OK;
}

/* The field segment of road `road` at its first (end 0) or last (end 1)
 * segment of positive length; NULL when that one is not in the field. */
size_t rs__end_segment(const double *xy, size_t np, int end)
{
    if (np < 2) return SIZE_MAX;
    size_t k = end ? np - 2 : 0;
    /* past repeated points (a zero-length segment at the end) */
    while (xy[2 * k] == xy[2 * k + 2] && xy[2 * k + 1] == xy[2 * k + 3]) {
        if (end ? k == 0 : k + 2 >= np) return SIZE_MAX;
        k = end ? k - 1 : k + 1;
    }
    return k;
}

static const rf_seg *road_end_seg(const rs__roadfield *f, const rs_roads *roads, uint32_t road, int end)
{
    const double *xy = NULL;
    size_t np = 0;
    rs_roads_get(roads, road, NULL, NULL, &xy, &np);
    size_t k = rs__end_segment(xy, np, end);
    if (k == SIZE_MAX) return NULL;
    size_t lo = 0, hi = f->nseg;
    if (f->rfirst && road + 1 < f->nrfirst) lo = f->rfirst[road], hi = f->rfirst[road + 1];
    const size_t run_end = hi;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        const rf_seg *s = &f->seg[mid];
        if (s->road < road || (s->road == road && s->seg < k)) lo = mid + 1;
        else hi = mid;
    }
    if (lo == run_end || f->seg[lo].road != road || f->seg[lo].seg != k || !(f->seg[lo].len > 0)) return NULL;
    return &f->seg[lo];
}

/* A T end's strip: where its end segment's trimmed shape runs past the
 * end point (the strip goes on to the clip line: at a slant, one edge
 * reaches far), as tee_box's box. */
typedef struct rf_strip {
    uint32_t seg;
    double box[4]; /* x0, x1, y0, y1 */
} rf_strip;

static int cmp_strip(const void *pa, const void *pb)
{
    const rf_strip *a = pa, *b = pb;
    return (a->seg > b->seg) - (a->seg < b->seg);
}

/* How far past the line n.p = c the segment's trimmed shape comes: its
 * capsule, and the strips of its own T ends (st[0..ns), by segment) */
static double past_line(const rf_seg *q, uint32_t k, const rf_strip *st, size_t ns, double nx, double ny, double c)
{
    double far = capsule_far(q, nx, ny);
    size_t lo = 0, hi = ns;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (st[mid].seg < k) lo = mid + 1;
        else hi = mid;
    }
    for (; lo < ns && st[lo].seg == k; lo++) far = lm_max(far, box_far(st[lo].box, nx, ny));
    return far - c;
}

/* A T end's segment (UINT32_MAX: none, tee_end_of) and n.E there */
typedef struct rf_tee_at {
    uint32_t seg;
    double cE;
} rf_tee_at;

/* The end segment of T end t whose strip reaches its clip line going
 * along it (NULL: no T is made there), and n.E into *cE. */
static const rf_seg *tee_end_of(const rs__roadfield *f, const rs_roads *roads, const rs__tee_end *t, double *cE)
{
    const rf_seg *s = road_end_seg(f, roads, t->road, t->end);
    if (!s || !(s->r > 0)) return NULL;
    double dx = t->end ? s->ux : -s->ux, dy = t->end ? s->uy : -s->uy;
    if (!(t->nx * dx + t->ny * dy > 0.1)) return NULL;
    *cE = t->nx * (t->end ? s->bx : s->ax) + t->ny * (t->end ? s->by : s->ay);
    return s;
}

rs_result rs__roadfield_set_tees(rs_ctx *ctx, rs__roadfield *f, const rs_roads *roads, const rs__tee_end *tees,
                                 size_t n)
{
    if (!f || !n || f->ntee) return RS_OK;
    size_t m = 0, cap = 0, ns = 0;
    /* every T end's strip first: a record's other segments are clipped
     * by its T lines where their shapes, strips included, reach past
     * (a hairpin's second T strip reached back past the first T's line:
     * without it, whether that clip was made depended on the index cell,
     * and so did the pixels there: fuzz/edits) */
    rf_strip *st = rs__alloc_array(ctx, n, sizeof *st);
    /* each end's segment and n.E, found once for both passes (the search
     * reads the road set and the segments at random places: at 10^5 roads
     * a miss each) */
    rf_tee_at *at = rs__alloc_array(ctx, n, sizeof *at);
    if (!st || !at) {
        rs__free(ctx, st);
        rs__free(ctx, at);
        return RS_ERR_NOMEM;
    }
    for (size_t i = 0; i < n; i++) {
        if ((i & 4095) == 0 && rs__poll(ctx)) { /* (10^5 roads: ~20 ms in all) */
            rs__free(ctx, st);
            rs__free(ctx, at);
            return RS_ERR_CANCELLED;
        }
        const rs__tee_end *t = &tees[i];
        double cE = 0;
        const rf_seg *s = tee_end_of(f, roads, t, &cE);
        at[i].seg = s ? (uint32_t)(s - f->seg) : UINT32_MAX;
        at[i].cE = cE;
        if (!s) continue;
        rf_tee T;
        memset(&T, 0, sizeof T);
        T.seg = (uint32_t)(s - f->seg);
        T.end = t->end;
        T.nx = t->nx, T.ny = t->ny;
        T.c = cE + t->far;
        tee_box(f, &T);
        st[ns].seg = T.seg;
        memcpy(st[ns].box, T.box, sizeof T.box);
        ns++;
    }
    /* (rs__sort: it polls, where a qsort of 10^5 strips could not be stopped) */
    rs_result sr = ns > 1 ? rs__sort(ctx, st, ns, sizeof *st, cmp_strip) : RS_OK;
    if (sr) {
        rs__free(ctx, st);
        rs__free(ctx, at);
        return sr;
    }
    for (size_t i = 0; i < n; i++) {
        if ((i & 511) == 0 && rs__poll(ctx)) {
            rs__free(ctx, st);
            rs__free(ctx, at);
            return RS_ERR_CANCELLED; /* (a T's clips: ~5 us) */
        }
        const rs__tee_end *t = &tees[i];
        const double cE = at[i].cE;
        if (at[i].seg == UINT32_MAX) continue; /* (the strip must reach the clip line: tee_end_of) */
        const rf_seg *s = &f->seg[at[i].seg];
        /* the record's segments: its end segment trimmed, and clipped
         * those whose trimmed shape reaches past the line: the
         * zero-length ones at the end, and from the end along the record
         * up to the first that does not reach it. (Every such segment of
         * the record once: a record that left the T and crossed the
         * through road again further on lost all of itself beyond the
         * line there; fuzz/edits.) The walk goes by the shapes alone; a
         * segment it reaches within an index cell of the line is clipped
         * too (a no-op for its shape, and the lines of a field widened by
         * up to a cell: a casing, widen), so no pixel depends on the cell. */
        const size_t ks = (size_t)(s - f->seg);
        size_t k0 = ks, k1 = ks + 1;
        while (k0 > 0 && f->seg[k0 - 1].road == t->road) k0--;
        while (k1 < f->nseg && f->seg[k1].road == t->road) k1++;
        const size_t nout = t->end ? k1 - ks - 1 : ks - k0, nin = t->end ? ks - k0 + 1 : k1 - ks;
        for (size_t step = 0; step < nout + nin; step++) {
            /* first the segments past the end segment (beyond the end
             * point: zero-length), then the end segment and inwards */
            size_t k = step < nout ? (t->end ? ks + 1 + step : ks - 1 - step)
                                   : (t->end ? ks - (step - nout) : ks + (step - nout));
            const rf_seg *q = &f->seg[k];
            int end = q == s ? t->end : 2;
            if (end == 2) {
                double past = past_line(q, (uint32_t)k, st, ns, t->nx, t->ny, cE + t->far);
                if (!(past > 0)) { /* (NaN: the walk ends, as before) */
                    if (!(past + f->c > 0)) {
                        if (step < nout) continue;
                        break;
                    }
                    if (step >= nout) { /* (clipped, then the walk ends here) */
                        step = nout + nin - 1;
                    }
                }
            }
            if (m == cap) {
                size_t nc = cap ? 2 * cap : n + 8, bytes;
                rf_tee *nt = rs__mul_size(nc, sizeof *f->tee, &bytes) ? rs__realloc(ctx, f->tee, bytes) : NULL;
                if (!nt) {
                    rs__free(ctx, f->tee);
                    rs__free(ctx, st);
                    rs__free(ctx, at);
                    f->tee = NULL;
                    return RS_ERR_NOMEM;
                }
                f->tee = nt;
                cap = nc;
            }
            rf_tee *T = &f->tee[m++];
            T->seg = (uint32_t)k;
            T->end = end;
            T->nx = t->nx, T->ny = t->ny;
            T->cE = cE;
            T->R = t->far;
            T->through = t->through;
            T->G = t->grow >= 0 && t->grow <= 1e300 ? t->grow : 0; /* NaN, inf: 0 */
        }
    }
    rs__free(ctx, st);
    rs__free(ctx, at);
    if (!m) {
        rs__free(ctx, f->tee);
        f->tee = NULL;
        return RS_OK;
    }
    f->ntee = m;
    rs_result r = rs__poll(ctx) ? RS_ERR_CANCELLED : tees_finish(ctx, f);
    if (r != RS_OK) {
        rs__free(ctx, f->tee), rs__free(ctx, f->tstart), rs__free(ctx, f->tids);
        f->tee = NULL, f->tstart = f->tids = NULL, f->ntee = 0;
        for (size_t k = 0; k < f->nseg; k++) f->seg[k].tee = 0;
    }
    return r;
}

/* widen: the source's tees; a casing stops at the through road's surface
 * edge too (beyond it lies the through road's own casing, extra[through]
 * wide: G) */
static rs_result tees_widen(rs_ctx *ctx, rs__roadfield *f, const rs__roadfield *src, const double *extra,
                           size_t nroads)
{
    if (!src->ntee) return RS_OK;
    f->tee = rs__alloc_array(ctx, src->ntee, sizeof *f->tee);
    if (!f->tee) return RS_ERR_NOMEM;
    memcpy(f->tee, src->tee, src->ntee * sizeof *f->tee);
    f->ntee = src->ntee;
    for (size_t i = 0; i < f->ntee && extra; i++) {
        rf_tee *T = &f->tee[i];
        T->G = T->through < nroads ? src->tee[i].G + extra[T->through] : src->tee[i].G;
    }
    return tees_finish(ctx, f);
}

/* The nearest query at a T segment: 0 when (x, y) lies beyond its clip
 * line by more than reach (skip it), 2 when it lies within reach of the
 * trimmed shape and inside one of its strips' boxes (take it even beyond
 * the capsule: the strip's corners), else 1. Distances stay those to the
 * centreline (the ranking as before). tee_sd is a lower bound of the
 * distance: past a strip's corner it is within reach of points up to
 * reach / sin(half the corner's angle) away, outside the box (the strip
 * grown by the margin), where only the cells listing the segment found
 * them. Whether a pixel took that road's fill then depended on the index
 * cell (fuzz/edits: an acute T on a footway); outside the box the shape
 * is further than the margin, the pixel's half diagonal. */
static int tee_near(const rs__roadfield *f, const rf_seg *s, double x, double y, double reach)
{
    size_t i0, i1;
    tees_of(f, (uint32_t)(s - f->seg), &i0, &i1);
    for (size_t k = i0; k < i1; k++)
        if (f->tee[k].live && !(x * f->tee[k].nx + y * f->tee[k].ny - f->tee[k].c <= reach)) return 0;
    if (!(tee_sd_at(f, s, i0, i1, x, y) <= reach)) return 1;
    for (size_t k = i0; k < i1; k++) {
        const double *b = f->tee[k].box;
        if (f->tee[k].end < 2 && x >= b[0] && x <= b[1] && y >= b[2] && y <= b[3]) return 2;
    }
    return 1;
}

int rs__roadfield_nearest(const rs__roadfield *f, double x, double y, double reach, rs__road_point *out)
{
    return rs__roadfield_nearest_ranked(f, x, y, reach, NULL, out);
}

/* The nearest query; out NULL: whether any segment passes its tests (the
 * first one ends the scan). */
/* Does segment s's surface (its capsule, or a trimmed T end's strip) hold
 * (x, y), at distance d from its centre line (seg_point's)? The fill
 * lookups' test. */
static int surface_holds(const rs__roadfield *f, const rf_seg *s, double x, double y, double d)
{
    return s->tee ? tee_sd(f, s, x, y) <= 0 : d <= s->r;
}

static int nearest_scan(const rs__roadfield *f, double x, double y, double reach, const int *prio,
                        const double *only, rs__road_point *out, uint32_t *hit)
{
    if (!f || !(reach >= 0)) return 0;
    int64_t ci = cell_of(f, x, f->gw), cj = cell_of(f, y, f->gh);
    if (ci < 0 || cj < 0) return 0;
    rf_cells cr = { (uint32_t)ci, (uint32_t)ci, (uint32_t)cj, (uint32_t)cj };
    if (reach > f->reach && !cells_around(f, x, y, reach - f->reach + 1e-6 * f->c, &cr)) return 0;
    const rf_seg *best = NULL;
    double bd = 0, bpr = 0, bside = 0;
    int bk = INT_MIN; /* with priorities: the best one's priority when (x, y) is on its surface */
    for (uint32_t j = cr.j0; j <= cr.j1; j++)
        for (uint32_t i = cr.i0; i <= cr.i1; i++) {
            size_t cell = (size_t)j * f->gw + i;
            for (uint32_t k = f->start[cell]; k < f->start[cell + 1]; k++) {
                const rf_seg *s = &f->seg[f->ids[k]];
                if (only && !(only[s->road] > 0)) continue;
                double pr, side, d = seg_point(s, x, y, &pr, &side);
                int tn = s->tee ? tee_near(f, s, x, y, reach) : 1;
                if (!tn || (tn == 1 && !(d - s->r <= reach))) continue;
                if (!out) {
                    if (hit) *hit = f->ids[k];
                    return 1;
                }
                int key = !prio ? INT_MIN : surface_holds(f, s, x, y, d) ? prio[s->road] : INT_MIN;
                /* segments are numbered in (road, seg) order */
                if (!best || key > bk || (key == bk && (d < bd || (d == bd && s < best)))) {
                    best = s; bd = d; bpr = pr; bside = side; bk = key;
                }
            }
        }
    /* a trimmed strip reaches past its capsule, so past its cells' lists */
    for (uint32_t m = f->ntee ? f->tstart[cj] : 0; f->ntee && m < f->tstart[cj + 1]; m++) {
        const rf_tee *T = &f->tee[f->tids[m]];
        if (x < T->box[0] || x > T->box[1] || y < T->box[2] || y > T->box[3]) continue;
        const rf_seg *s = &f->seg[T->seg];
        if (only && !(only[s->road] > 0)) continue;
        double pr, side, d = seg_point(s, x, y, &pr, &side);
        int tn = tee_near(f, s, x, y, reach);
        if (!tn || (tn == 1 && !(d - s->r <= reach))) continue;
        if (!out) return 1;
        int key = !prio ? INT_MIN : tee_sd(f, s, x, y) <= 0 ? prio[s->road] : INT_MIN;
        if (!best || key > bk || (key == bk && (d < bd || (d == bd && s < best)))) {
            best = s; bd = d; bpr = pr; bside = side; bk = key;
        }
    }
    if (!best) return 0;
    out->road = best->road;
    out->seg = best->seg;
    out->s = best->s0 + bpr;
    if (!(out->s <= DBL_MAX)) out->s = DBL_MAX; /* arc lengths saturate (see the build) */
    out->t = bside >= 0 ? bd : -bd;
    out->dist = bd;
    out->half_width = best->r;
    return 1;
}

int rs__roadfield_held_above(const rs__roadfield *f, double x, double y, const int32_t *lv, const uint32_t *stroke,
                             int32_t level, uint32_t st)
{
    if (!f) return 0;
    int64_t ci = cell_of(f, x, f->gw), cj = cell_of(f, y, f->gh);
    if (ci < 0 || cj < 0) return 0;
    /* (a surface holding the point is in its cell's list: the lists reach
     * past every capsule; nearest_scan's key, reach 0) */
    size_t cell = (size_t)cj * f->gw + (size_t)ci;
    for (uint32_t k = f->start[cell]; k < f->start[cell + 1]; k++) {
        const rf_seg *s = &f->seg[f->ids[k]];
        if (!(lv[s->road] > level) || stroke[s->road] == st) continue;
        double pr, side, d = seg_point(s, x, y, &pr, &side);
        if (surface_holds(f, s, x, y, d)) return 1;
    }
    /* a trimmed strip reaches past its capsule, so past its cells' lists */
    for (uint32_t m = f->ntee ? f->tstart[cj] : 0; f->ntee && m < f->tstart[cj + 1]; m++) {
        const rf_tee *T = &f->tee[f->tids[m]];
        if (x < T->box[0] || x > T->box[1] || y < T->box[2] || y > T->box[3]) continue;
        const rf_seg *s = &f->seg[T->seg];
        if (!(lv[s->road] > level) || stroke[s->road] == st) continue;
        if (tee_sd(f, s, x, y) <= 0) return 1;
    }
    return 0;
}

int rs__roadfield_nearest_ranked(const rs__roadfield *f, double x, double y, double reach, const int *prio,
                                 rs__road_point *out)
{
    return out ? nearest_scan(f, x, y, reach, prio, NULL, out, NULL) : 0;
}

int rs__roadfield_nearest_of(const rs__roadfield *f, double x, double y, double reach, const double *only,
                             rs__road_point *out)
{
    return out ? nearest_scan(f, x, y, reach, NULL, only, out, NULL) : 0;
}

int rs__roadfield_any_near(const rs__roadfield *f, double x, double y, double reach)
{
    return nearest_scan(f, x, y, reach, NULL, NULL, NULL, NULL);
}

int rs__roadfield_any_near_hint(const rs__roadfield *f, double x, double y, double reach, uint32_t *hint)
{
    if (!f || !(reach >= 0) || cell_of(f, x, f->gw) < 0 || cell_of(f, y, f->gh) < 0) return 0;
    /* A segment without a T trim whose surface is within reach of (x, y)
     * is in the lists nearest_scan reads (its capsule grown by the
     * lists' reach, with their slack, meets the cells it scans): the
     * answer is the same whichever one is found first. */
    const rf_seg *s = *hint < f->nseg ? &f->seg[*hint] : NULL;
    if (s && !s->tee && seg_dist(s, x, y) - s->r <= reach) return 1; /* seg_point's distance: the scan's test */
    return nearest_scan(f, x, y, reach, NULL, NULL, NULL, hint);
}

/* Fraction of a square of side `side` centred at the origin where
 * x*gx + y*gy <= h, for a unit (gx, gy): the CDF of the sum of two uniform
 * variables on [-a, a] and [-b, b] (a trapezoid), a >= b. */
static double halfplane(double gx, double gy, double side, double h)
{
    double a = 0.5 * side * fabs(gx), b = 0.5 * side * fabs(gy);
    if (a < b) { double tmp = a; a = b; b = tmp; }
    double x = fabs(h), lo; /* lo = fraction where u <= -|h| */
    if (x >= a + b) lo = 0;
    else if (x >= a - b) { double w = a + b - x; lo = w * w / (8 * a * b); }
    else lo = 0.5 * (a - x) / a;
    return h < 0 ? lo : 1 - lo;
}

/* A square size for the coverage: side, half diagonal e, and the
 * constants of the band cover (hs = side/2, iside = 1/side, c2 =
 * 1/(2 side^2)); set once per call by px_set, so a pixel's value depends
 * only on the pixel size. */
typedef struct rf_px { double side, e, hs, iside, c2; } rf_px;

static void px_set(rf_px *q, double side)
{
    q->side = side;
    q->e = side * HALF_SQRT2;
    q->hs = 0.5 * side;
    q->iside = 1 / side;
    q->c2 = 1 / (2 * side * side);
}

/* x >= y ? a : b and max(w, 0) without a branch (the covers' cases depend
 * on the data and are badly predicted); either way the same doubles. */
#if defined(__SSE2__)
static double rf_ge(double x, double y, double a, double b)
{
    __m128d m = _mm_cmpge_sd(_mm_set_sd(x), _mm_set_sd(y));
    return _mm_cvtsd_f64(_mm_or_pd(_mm_and_pd(m, _mm_set_sd(a)), _mm_andnot_pd(m, _mm_set_sd(b))));
}
static double rf_if(int c, double a, double b)
{
    __m128d m = _mm_castsi128_pd(_mm_set1_epi32(-(c != 0)));
    return _mm_cvtsd_f64(_mm_or_pd(_mm_and_pd(m, _mm_set_sd(a)), _mm_andnot_pd(m, _mm_set_sd(b))));
}
/* a > b ? a : b */
static double rf_max(double a, double b) { return _mm_cvtsd_f64(_mm_max_sd(_mm_set_sd(a), _mm_set_sd(b))); }
static double rf_pos(double w) { return _mm_cvtsd_f64(_mm_max_sd(_mm_set_sd(w), _mm_setzero_pd())); }
static double rf_neg(double w) { return _mm_cvtsd_f64(_mm_min_sd(_mm_set_sd(w), _mm_setzero_pd())); }
#else
static double rf_ge(double x, double y, double a, double b) { return x >= y ? a : b; }
static double rf_if(int c, double a, double b) { return c ? a : b; }
static double rf_max(double a, double b) { return a > b ? a : b; }
static double rf_pos(double w) { return w > 0 ? w : 0; }
static double rf_neg(double w) { return w < 0 ? w : 0; }
#endif

/* halfplane() for the segment's own normal, without divisions: a = hs ga,
 * b = hs gb, apb = a + b (the caller's), x = |h| >= 0. Returns lo (the
 * fraction where u <= -x): 0 for x >= a + b, w^2/(8ab) = w^2 c2 igab with
 * w = a + b - x for x >= a - b, else (a-x)/(2a) = 1/2 - x iside iga.
 * Without branches: w is clamped at 0, so the quadratic piece gives the 0. */
static double band_lo(const rf_seg *s, const rf_px *q, double a, double b, double apb, double x)
{
    double w = apb - x, lin = 0.5 - x * (q->iside * s->iga);
    w = rf_pos(w);
    return rf_ge(x, a - b, w * w * (q->c2 * s->igab), lin);
}

/* Coverage of the square (side q->side) whose centre is at signed offset t
 * from the segment's line, inside the segment's slab, by the band |t| <= r:
 * the fraction between two parallel lines, each the CDF of the sum of two
 * uniform variables (a trapezoid, closed form). The caller has settled
 * |t| <= r - e (1) and |t| >= r + e (0). The far edge (offset -r - at, never
 * above 0) usually misses the square: its term is then exactly 0. */
static double band_cover(const rf_seg *s, const rf_px *q, double t)
{
    double a = q->hs * s->ga, b = q->hs * s->gb, apb = a + b, at = fabs(t), h = s->r - at;
    double lo = band_lo(s, q, a, b, apb, fabs(h));
    return rf_ge(h, 0, 1 - lo, lo) - band_lo(s, q, a, b, apb, at + s->r);
}

/* The band's cover of a square in the slab at offset t: 0 when clear
 * (|t| - r >= e), 1 when deep (|t| + e <= r), else band_cover; chosen
 * without a branch. */
static double band_value(const rf_seg *s, const rf_px *q, double t)
{
    double at = fabs(t);
    return rf_ge(at - s->r, q->e, 0, rf_ge(s->r, at + q->e, 1, band_cover(s, q, t)));
}

#if defined(__SSE2__)
#define RF_SEL(m, a, b) _mm_or_pd(_mm_and_pd((m), (a)), _mm_andnot_pd((m), (b)))
#define RF_PAIR(s0, s1, field) _mm_set_pd((s1)->field, (s0)->field)
static __m128d rf_abs2(__m128d v) { return _mm_andnot_pd(_mm_set1_pd(-0.0), v); }

/* band_lo for the two lanes: x >= 0, k1 = iside iga, k2 = c2 igab */
static __m128d band_lo2(__m128d amb, __m128d apb, __m128d k1, __m128d k2, __m128d x)
{
    __m128d w = _mm_max_pd(_mm_sub_pd(apb, x), _mm_setzero_pd());
    __m128d lin = _mm_sub_pd(_mm_set1_pd(0.5), _mm_mul_pd(x, k1));
    return RF_SEL(_mm_cmpge_pd(x, amb), _mm_mul_pd(_mm_mul_pd(w, w), k2), lin);
}

/* band_value of two squares: lane 0 of s0 at offset t[0], lane 1 of s1 at
 * t[1]; the same arithmetic as band_value lane by lane (the same doubles). */
static __m128d band_value2(const rf_seg *s0, const rf_seg *s1, const rf_px *q, __m128d t)
{
    __m128d hs = _mm_set1_pd(q->hs), e = _mm_set1_pd(q->e), r = RF_PAIR(s0, s1, r);
    __m128d a = _mm_mul_pd(hs, RF_PAIR(s0, s1, ga)), b = _mm_mul_pd(hs, RF_PAIR(s0, s1, gb));
    __m128d apb = _mm_add_pd(a, b), amb = _mm_sub_pd(a, b);
    __m128d k1 = _mm_mul_pd(_mm_set1_pd(q->iside), RF_PAIR(s0, s1, iga));
    __m128d k2 = _mm_mul_pd(_mm_set1_pd(q->c2), RF_PAIR(s0, s1, igab));
    __m128d at = rf_abs2(t), h = _mm_sub_pd(r, at), one = _mm_set1_pd(1);
    __m128d lo = band_lo2(amb, apb, k1, k2, rf_abs2(h));
    __m128d bc = _mm_sub_pd(RF_SEL(_mm_cmpge_pd(h, _mm_setzero_pd()), _mm_sub_pd(one, lo), lo),
                            band_lo2(amb, apb, k1, k2, _mm_add_pd(at, r)));
    __m128d v = RF_SEL(_mm_cmpge_pd(r, _mm_add_pd(at, e)), one, bc);
    return _mm_andnot_pd(_mm_cmpge_pd(_mm_sub_pd(at, r), e), v);
}
#endif

/* Coverage of the square centred (x, y) of size q by one capsule: exact
 * when the square lies within the segment's slab (the band |t| <= r cut by
 * straight lines), otherwise the half-plane of the distance field
 * linearised at the centre (caps and vertices, where the edge is an arc). */
static double capsule_cover(const rf_seg *s, double x, double y, const rf_px *q)
{
    double wx = x - s->ax, wy = y - s->ay, pr = wx * s->ux + wy * s->uy, qx, qy, e = q->e;
    double hp = q->hs * s->l1;
    if (s->len > 0 && pr - hp >= 0 && pr + hp <= s->len) {
        double t = wx * s->uy - wy * s->ux, at = fabs(t);
        if (at - s->r >= e) return 0;
        if (at + e <= s->r) return 1;
        return band_cover(s, q, t);
    }
    if (!(pr > 0)) { qx = s->ax; qy = s->ay; }
    else if (pr >= s->len) { qx = s->bx; qy = s->by; }
    else { qx = s->ax + pr * s->ux; qy = s->ay + pr * s->uy; }
    double dx = x - qx, dy = y - qy, d2 = dx * dx + dy * dy, ro = s->r + e, ri = s->r - e;
    /* squared distances settle most squares without the root */
    if (d2 < 1e300 && (d2 >= ro * ro || (ri > 0 && d2 <= ri * ri))) return d2 >= ro * ro ? 0 : 1;
    double d = len2(dx, dy), D = d - s->r;
    if (D >= e) return 0;
    if (D <= -e) return 1;
    if (!(d > 0)) return 1; /* centre on the centreline, so D = -r > -e: a tiny road; rare */
    return halfplane(dx / d, dy / d, q->side, -D);
}

/* The near capsules of a pixel with seg_eval's results. */
typedef struct rf_near {
    uint32_t id[NEAR_MAX];
    double p[NEAR_MAX], t[NEAR_MAX]; /* the centre's projection on the segment (from a) and offset t */
    int slab[NEAR_MAX];              /* 1: the pixel lies in the segment's slab */
    int n, many;
} rf_near;

/* Classifies the capsule against the pixel centred (x, y) of size q:
 * 2 = deep (d <= r - e), 0 = clear (d >= r + e), 1 = near. In the slab (all
 * of the pixel projects into the segment) by the offset t from the line,
 * else by the squared distance to the nearest centreline point (no root).
 * Fills slot n of nr (p, t, slab). Both ways are computed and one is
 * chosen without a branch (which way applies depends on the data). */
static int seg_eval(const rf_seg *s, double x, double y, const rf_px *q, rf_near *nr, int n)
{
    double wx = x - s->ax, wy = y - s->ay, pr = wx * s->ux + wy * s->uy, e = q->e, hp = q->hs * s->l1;
    double t = wx * s->uy - wy * s->ux, at = fabs(t);
    int slab = (s->len > 0) & (pr - hp >= 0) & (pr + hp <= s->len);
    int cs = at - s->r >= e ? 0 : at + e <= s->r ? 2 : 1;
    /* the nearest centreline point is dp past an end along the segment (at
     * most one of the terms is not 0) and t off its line; a zero-length
     * segment: the point itself */
    double dp = rf_neg(pr) + rf_pos(pr - s->len), dx = rf_if(s->len > 0, dp, wx), dy = rf_if(s->len > 0, t, wy);
    double d2 = dx * dx + dy * dy, ro = s->r + e, ri = s->r - e;
    int cn = d2 >= ro * ro ? 0 : (((ri > 0) & (d2 <= ri * ri)) ? 2 : 1);
    if (!(d2 < 1e300)) {
        double D = hypot(dx, dy) - s->r;
        cn = D >= e ? 0 : D <= -e ? 2 : 1;
    }
    nr->p[n] = pr;
    nr->t[n] = t;
    nr->slab[n] = slab;
    return slab ? cs : cn;
}

/* seg_eval of two segments (the common two-candidate pixel) into slots n,
 * n + 1; their classes in *c0, *c1. */
#if defined(__SSE2__)
static void seg_eval2(const rf_seg *s0, const rf_seg *s1, double x, double y, const rf_px *q, rf_near *nr, int n,
                      int *c0, int *c1)
{
    __m128d ux = RF_PAIR(s0, s1, ux), uy = RF_PAIR(s0, s1, uy), len = RF_PAIR(s0, s1, len), r = RF_PAIR(s0, s1, r);
    __m128d e = _mm_set1_pd(q->e), zero = _mm_setzero_pd();
    __m128d wx = _mm_sub_pd(_mm_set1_pd(x), RF_PAIR(s0, s1, ax)), wy = _mm_sub_pd(_mm_set1_pd(y), RF_PAIR(s0, s1, ay));
    __m128d pr = _mm_add_pd(_mm_mul_pd(wx, ux), _mm_mul_pd(wy, uy));
    __m128d t = _mm_sub_pd(_mm_mul_pd(wx, uy), _mm_mul_pd(wy, ux)), at = rf_abs2(t);
    __m128d hp = _mm_mul_pd(_mm_set1_pd(q->hs), RF_PAIR(s0, s1, l1)), pos = _mm_cmpgt_pd(len, zero);
    __m128d slab = _mm_and_pd(_mm_and_pd(pos, _mm_cmpge_pd(_mm_sub_pd(pr, hp), zero)),
                              _mm_cmple_pd(_mm_add_pd(pr, hp), len));
    __m128d sclear = _mm_cmpge_pd(_mm_sub_pd(at, r), e), sdeep = _mm_cmple_pd(_mm_add_pd(at, e), r);
    __m128d dp = _mm_add_pd(_mm_min_pd(pr, zero), _mm_max_pd(_mm_sub_pd(pr, len), zero));
    __m128d dx = RF_SEL(pos, dp, wx), dy = RF_SEL(pos, t, wy);
    __m128d d2 = _mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), ro = _mm_add_pd(r, e), ri = _mm_sub_pd(r, e);
    __m128d nclear = _mm_cmpge_pd(d2, _mm_mul_pd(ro, ro));
    __m128d ndeep = _mm_and_pd(_mm_cmpgt_pd(ri, zero), _mm_cmple_pd(d2, _mm_mul_pd(ri, ri)));
    if (_mm_movemask_pd(_mm_cmplt_pd(d2, _mm_set1_pd(1e300))) != 3) {
        /* huge distances: the scalar way (hypot) */
        *c0 = seg_eval(s0, x, y, q, nr, n);
        *c1 = seg_eval(s1, x, y, q, nr, n + 1);
        return;
    }
    int ms = _mm_movemask_pd(slab), mc = _mm_movemask_pd(RF_SEL(slab, sclear, nclear));
    int md = _mm_movemask_pd(RF_SEL(slab, sdeep, ndeep));
    _mm_storeu_pd(nr->p + n, pr);
    _mm_storeu_pd(nr->t + n, t);
    nr->slab[n] = ms & 1;
    nr->slab[n + 1] = ms >> 1;
    /* clear and deep never hold together */
    *c0 = (md & 1) ? 2 : (mc & 1) ? 0 : 1;
    *c1 = (md & 2) ? 2 : (mc & 2) ? 0 : 1;
}
#else
static void seg_eval2(const rf_seg *s0, const rf_seg *s1, double x, double y, const rf_px *q, rf_near *nr, int n,
                      int *c0, int *c1)
{
    *c0 = seg_eval(s0, x, y, q, nr, n);
    *c1 = seg_eval(s1, x, y, q, nr, n + 1);
}
#endif

/* capsule_cover's value for a near capsule from seg_eval's results (the
 * exact band in the slab, else the linearised distance). */
static double near_value(const rf_seg *s, const rf_px *q, int slab, double u, double v)
{
    if (slab) return band_cover(s, q, u);
    double d = len2(u, v), Dd = d - s->r;
    if (Dd >= q->e) return 0;  /* rounding at the threshold */
    if (Dd <= -q->e) return 1;
    return d > 0 ? halfplane(u / d, v / d, q->side, -Dd) : 1; /* d = 0: a tiny road; rare */
}

/* A pixel near only two consecutive segments a, b of one road with a
 * gentle turn (the common case on curves; rf_seg.jnext), its centre not
 * beyond the far ends: the road edge in the pixel is two nearly collinear
 * lines joined by a short arc around the shared vertex V. On the inner
 * side of the turn the road is the union of the two half-planes (the max
 * of their exact covers); on the outer side the edge is the tangent at the
 * nearest boundary point: a's edge line while the centre projects into a,
 * b's while it projects into b, else (the fan at V) the tangent to the arc.
 * The error is second order in the turn angle (docs/roadfield.md). ia, ib:
 * the slots of a and b in nr. */
static double joint_cover(const rf_seg *a, const rf_seg *b, const rf_near *nr, int ia, int ib, const rf_px *q,
                          double cx, double cy)
{
    double pa = nr->p[ia], ta = nr->t[ia], pb = nr->p[ib], ca, cb;
#if defined(__SSE2__)
    double c[2];
    _mm_storeu_pd(c, band_value2(a, b, q, _mm_set_pd(nr->t[ib], ta)));
    ca = c[0];
    cb = c[1];
#else
    ca = band_value(a, q, ta);
    cb = band_value(b, q, nr->t[ib]);
#endif
    double turn = b->ux * a->uy - b->uy * a->ux;
    int inner = ta * turn > 0;
    /* the fan (rare): its own way; else chosen without a branch */
    if (!inner & !(pa < a->len) & !(pb > 0)) return near_value(a, q, 0, cx - a->bx, cy - a->by);
    return rf_if(inner, rf_max(ca, cb), rf_if(pa < a->len, ca, cb));
}

/* Evaluates capsule id against the pixel and adds it to nr when near
 * (each once). Returns 1 when the pixel is deep inside it. */
static int near_eval(const rs__roadfield *f, rf_near *nr, uint32_t id, double cx, double cy, const rf_px *q)
{
    for (int m = 0; m < nr->n; m++)
        if (nr->id[m] == id) return 0;
    int n = nr->n < NEAR_MAX ? nr->n : NEAR_MAX - 1; /* past NEAR_MAX: scratch slot */
    int c = seg_eval(&f->seg[id], cx, cy, q, nr, n);
    if (c == 2) return 1;
    if (c && !f->seg[id].redundant) {
        if (nr->n < NEAR_MAX) nr->id[nr->n++] = id;
        else nr->many = 1;
    }
    return 0;
}

static double sub_cover(const rs__roadfield *f, const rf_near *nr, const rf_cells *cr, double cx, double cy,
                        const rf_px *qs);

/* Exact area of one capsule in a square where its boundary is not one
 * straight line (road ends, and squares reaching past a segment's end
 * normal): the normals at a and b cut the plane into the disc side of a,
 * the band and the disc side of b; the square's part in each is a convex
 * polygon (rf_poly, Sutherland-Hodgman), whose area inside the disc or the
 * band is summed. */
typedef struct rf_poly {
    int n;
    double x[16], y[16]; /* counter-clockwise; the square clipped by at most HP_MAX lines, +1 for poly_clip */
} rf_poly;

static void poly_square(rf_poly *P, double hs)
{
    P->n = 4;
    P->x[0] = -hs; P->y[0] = -hs;
    P->x[1] = hs;  P->y[1] = -hs;
    P->x[2] = hs;  P->y[2] = hs;
    P->x[3] = -hs; P->y[3] = hs;
}

/* Keeps the part of P where g0 + gx x + gy y <= 0. Every vertex is
 * written and kept or not by advancing the count (which case holds depends
 * on the data; branches would be mispredicted). */
static void poly_clip(const rf_poly *P, rf_poly *o, double gx, double gy, double g0)
{
    o->n = 0;
    if (P->n == 0) return;
    double gp = g0 + gx * P->x[P->n - 1] + gy * P->y[P->n - 1];
    for (int k = 0, kp = P->n - 1; k < P->n; kp = k, k++) {
        double gk = g0 + gx * P->x[k] + gy * P->y[k];
        int in = !(gk > 0), cross = in != !(gp > 0);
        /* gp and gk differ in sign when the point is kept (no division by
         * 0); otherwise 1 stands in for the difference */
        double w = gp / rf_if(cross, gp - gk, 1);
        o->x[o->n] = P->x[kp] + w * (P->x[k] - P->x[kp]);
        o->y[o->n] = P->y[kp] + w * (P->y[k] - P->y[kp]);
        o->n += cross;
        o->x[o->n] = P->x[k];
        o->y[o->n] = P->y[k];
        o->n += in;
        gp = gk;
    }
}

static double poly_area(const rf_poly *P)
{
    double a = 0;
    for (int k = 0, kp = P->n - 1; k < P->n; kp = k, k++) a += P->x[kp] * P->y[k] - P->x[k] * P->y[kp];
    return 0.5 * a;
}

/* Signed area of the part of the triangle (0, P, Q) inside the disc of
 * radius r about 0: the chord of PQ inside the circle as a triangle, the
 * rest as circular sectors. */
static double tri_disc(double px, double py, double qx, double qy, double r)
{
    double dx = qx - px, dy = qy - py, a = dx * dx + dy * dy, r2 = 0.5 * r * r;
    if (!(a > 0)) return 0;
    double b = px * dx + py * dy, c = px * px + py * py - r * r, disc = b * b - a * c, s1 = 1, s2 = 0;
    if (disc > 0) {
        double sq = sqrt(disc);
        s1 = (-b - sq) / a;
        s2 = (-b + sq) / a;
        if (s1 < 0) s1 = 0;
        if (s2 > 1) s2 = 1;
    }
    if (!(s1 < s2)) return r2 * atan2(px * qy - py * qx, px * qx + py * qy);
    double m1x = px + s1 * dx, m1y = py + s1 * dy, m2x = px + s2 * dx, m2y = py + s2 * dy;
    double area = 0.5 * (m1x * m2y - m1y * m2x);
    if (s1 > 0) area += r2 * atan2(px * m1y - py * m1x, px * m1x + py * m1y);
    if (s2 < 1) area += r2 * atan2(m2x * qy - m2y * qx, m2x * qx + m2y * qy);
    return area;
}

/* Area of P inside the disc of radius r about (ox, oy). */
static double poly_disc(const rf_poly *P, double ox, double oy, double r)
{
    double a = 0;
    for (int k = 0, kp = P->n - 1; k < P->n; kp = k, k++)
        a += tri_disc(P->x[kp] - ox, P->y[kp] - oy, P->x[k] - ox, P->y[k] - oy, r);
    return a;
}

/* Crossings of straight roads, and of roads with gentle joints: within
 * the pixel every road is one or two half-planes, so the uncovered part is
 * the intersection of their complements, a convex polygon: the square
 * clipped by each edge line, area by the shoelace formula. A near capsule
 * with the pixel in its slab and only its nearer edge crossing the pixel
 * gives its edge line. A gentle joint (rf_seg.jnext, both segments near,
 * as joint_cover) gives both edge lines on the inner side of the turn
 * (exact) and on the outer side the tangent joint_cover takes. The lines
 * are clipped in the order of their segments, so the rounding never
 * depends on the order the candidates were found in. Returns -1 when a
 * capsule does not qualify (or there are more than HP_MAX lines). */
#define HP_MAX 8
static double halfplanes_cover(const rs__roadfield *f, const rf_near *nr, const rf_px *q, double cx, double cy)
{
    /* line k: outside its road where g0 + gx X + gy Y > 0 (square coordinates) */
    double g0[HP_MAX], gx[HP_MAX], gy[HP_MAX], hs = q->hs;
    uint64_t key[HP_MAX];
    uint32_t used = 0;
    int nl = 0;
#define RF_LINE(s, t, kk)                                                                                        \
    do {                                                                                                         \
        double sg_ = (t) >= 0 ? 1 : -1;                                                                          \
        if (nl == HP_MAX) return -1;                                                                             \
        g0[nl] = sg_ * (t) - (s)->r; gx[nl] = sg_ * (s)->uy; gy[nl] = -sg_ * (s)->ux; key[nl++] = (kk);          \
    } while (0)
    for (int m = 0; m < nr->n; m++) {
        const rf_seg *a = &f->seg[nr->id[m]];
        if (!a->jnext || (used >> m & 1u)) continue;
        int m2 = 0;
        while (m2 < nr->n && nr->id[m2] != a->jpart) m2++;
        if (m2 == nr->n || (used >> m2 & 1u)) continue;
        const rf_seg *b = &f->seg[nr->id[m2]];
        if (!(a->r >= 2 * q->e && nr->p[m] >= hs * a->l1 && nr->p[m2] + hs * b->l1 <= b->len)) continue;
        used |= 1u << m | 1u << m2;
        uint64_t k0 = 2 * (uint64_t)nr->id[m];
        if (nr->t[m] * (b->ux * a->uy - b->uy * a->ux) > 0) {
            RF_LINE(a, nr->t[m], k0);
            RF_LINE(b, nr->t[m2], k0 + 1);
        } else if (nr->p[m] < a->len) RF_LINE(a, nr->t[m], k0);
        else if (nr->p[m2] > 0) RF_LINE(b, nr->t[m2], k0);
        else {
            /* the fan at the shared vertex: the tangent to the arc */
            double dx = cx - a->bx, dy = cy - a->by, d = len2(dx, dy);
            if (!(d > 0) || nl == HP_MAX) return -1;
            g0[nl] = d - a->r; gx[nl] = dx / d; gy[nl] = dy / d; key[nl++] = k0;
        }
    }
    for (int m = 0; m < nr->n; m++) {
        const rf_seg *s = &f->seg[nr->id[m]];
        if (used >> m & 1u) continue;
        if (!nr->slab[m] || fabs(nr->t[m]) + s->r < hs * (s->ga + s->gb)) return -1;
        RF_LINE(s, nr->t[m], 2 * (uint64_t)nr->id[m]);
    }
#undef RF_LINE
    int ord[HP_MAX];
    for (int m = 0; m < nl; m++) {
        int k = m;
        for (; k > 0 && key[ord[k - 1]] > key[m]; k--) ord[k] = ord[k - 1];
        ord[k] = m;
    }
    rf_poly P[2];
    int cur = 0;
    poly_square(&P[0], hs);
    /* poly_clip keeps g <= 0: the outside of each road is -g <= 0 */
    for (int j = 0; j < nl; j++, cur ^= 1) poly_clip(&P[cur], &P[cur ^ 1], -gx[ord[j]], -gy[ord[j]], -g0[ord[j]]);
    double v = 1 - poly_area(&P[cur]) * (q->iside * q->iside);
    return v < 0 ? 0 : v > 1 ? 1 : v;
}

/* The pixel centred (cx, cy) has projection pr on s (from a) and offset t. */
static double cap_cover(const rf_seg *s, const rf_px *q, double cx, double cy, double pr, double t)
{
    double hs = q->hs, hp = hs * s->l1, area = 0;
    rf_poly P, D, E;
    poly_square(&P, hs);
    if (!(s->len > 0)) {
        area = poly_disc(&P, s->ax - cx, s->ay - cy, s->r);
    } else {
        /* in square coordinates (X, Y): projection pr + X ux + Y uy, offset t + X uy - Y ux */
        if (pr - hp < 0) {
            poly_clip(&P, &D, s->ux, s->uy, pr);
            area += poly_disc(&D, s->ax - cx, s->ay - cy, s->r);
        }
        if (pr + hp > s->len) {
            poly_clip(&P, &D, -s->ux, -s->uy, s->len - pr);
            area += poly_disc(&D, s->bx - cx, s->by - cy, s->r);
        }
        if (pr + hp > 0 && pr - hp < s->len) {
            poly_clip(&P, &D, -s->ux, -s->uy, -pr);
            poly_clip(&D, &E, s->ux, s->uy, pr - s->len);
            poly_clip(&E, &D, s->uy, -s->ux, t - s->r);
            poly_clip(&D, &E, -s->uy, s->ux, -t - s->r);
            area += poly_area(&E);
        }
    }
    double v = area * (q->iside * q->iside);
    return v < 0 ? 0 : v > 1 ? 1 : v;
}

/* Coverage of the pixel from its near capsules `nr` (none deep); `cr`: the
 * cells whose lists hold every candidate (used when nr->many). */
static double near_cover(const rs__roadfield *f, const rf_near *nr, const rf_cells *cr, double cx, double cy,
                         const rf_px *q, const rf_px *qs)
{
    if (nr->n == 0 || nr->many) return nr->n ? sub_cover(f, nr, cr, cx, cy, qs) : 0;
    /* one boundary: exact if straight within the pixel */
    if (nr->n == 1) {
        const rf_seg *s = &f->seg[nr->id[0]];
        return nr->slab[0] ? band_cover(s, q, nr->t[0]) : cap_cover(s, q, cx, cy, nr->p[0], nr->t[0]);
    }
    if (nr->n == 2) {
        int ia = nr->id[0] < nr->id[1] ? 0 : 1, ib = 1 - ia;
        const rf_seg *a = &f->seg[nr->id[ia]], *b = &f->seg[nr->id[ib]];
        if (a->jnext && nr->id[ib] == a->jpart && a->r >= 2 * q->e && nr->p[ia] >= q->hs * a->l1 &&
            nr->p[ib] + q->hs * b->l1 <= b->len)
            return joint_cover(a, b, nr, ia, ib, q, cx, cy);
    }
    double v = halfplanes_cover(f, nr, q, cx, cy);
    return v >= 0 ? v : sub_cover(f, nr, cr, cx, cy, qs);
}

/* capsule_cover for a segment of positive length, from the square centre's
 * projection pr on the segment (from a) and offset t from its line: the
 * nearest centreline point and the distance follow from (pr, t) alone. */
static double cover_local(const rf_seg *s, const rf_px *q, double pr, double t)
{
    double e = q->e, hp = q->hs * s->l1;
    if (pr - hp >= 0 && pr + hp <= s->len) {
        double at = fabs(t);
        if (at - s->r >= e) return 0;
        if (at + e <= s->r) return 1;
        return band_cover(s, q, t);
    }
    double dp = pr > 0 ? (pr >= s->len ? pr - s->len : 0) : pr, d2 = dp * dp + t * t, ro = s->r + e, ri = s->r - e;
    if (d2 < 1e300 && (d2 >= ro * ro || (ri > 0 && d2 <= ri * ri))) return d2 >= ro * ro ? 0 : 1;
    double d = len2(dp, t), D = d - s->r;
    if (D >= e) return 0;
    if (D <= -e) return 1;
    if (!(d > 0)) return 1; /* centre on the centreline, so D = -r > -e: a tiny road; rare */
    double id = 1 / d;
    return halfplane((dp * s->ux + t * s->uy) * id, (dp * s->uy - t * s->ux) * id, q->side, -D);
}

/* Corners, arcs, crossings: sub-squares (size qs), each covered by its best
 * capsule among the near ones `nr` (or every candidate of the cells `cr`
 * when nr->many). */
static double sub_cover(const rs__roadfield *f, const rf_near *nr, const rf_cells *cr, double cx, double cy,
                        const rf_px *qs)
{
    double ps = qs->side, acc = 0;
    if (!nr->many) {
        /* per capsule: (pr, t) at the pixel centre and their steps per sub-square */
        double P[NEAR_MAX], T[NEAR_MAX], Px[NEAR_MAX], Py[NEAR_MAX], Tx[NEAR_MAX], Ty[NEAR_MAX];
        for (int m = 0; m < nr->n; m++) {
            const rf_seg *s = &f->seg[nr->id[m]];
            double wx = cx - s->ax, wy = cy - s->ay;
            P[m] = wx * s->ux + wy * s->uy;
            T[m] = wx * s->uy - wy * s->ux;
            Px[m] = ps * s->ux;
            Py[m] = ps * s->uy;
            Tx[m] = ps * s->uy;
            Ty[m] = -ps * s->ux;
        }
        for (int sy = 0; sy < SUBDIV; sy++)
            for (int sx = 0; sx < SUBDIV; sx++) {
                double ox = (double)sx - 0.5 * (SUBDIV - 1), oy = (double)sy - 0.5 * (SUBDIV - 1), best = 0;
                for (int m = 0; m < nr->n && best < 1; m++) {
                    const rf_seg *s = &f->seg[nr->id[m]];
                    double v = s->len > 0 ? cover_local(s, qs, P[m] + ox * Px[m] + oy * Py[m], T[m] + ox * Tx[m] + oy * Ty[m])
                                          : capsule_cover(s, cx + ox * ps, cy + oy * ps, qs);
                    if (v > best) best = v;
                }
                acc += best;
            }
        return acc / (SUBDIV * SUBDIV);
    }
    for (int sy = 0; sy < SUBDIV; sy++)
        for (int sx = 0; sx < SUBDIV; sx++) {
            double x = cx + ((double)sx - 0.5 * (SUBDIV - 1)) * ps, y = cy + ((double)sy - 0.5 * (SUBDIV - 1)) * ps;
            double best = 0;
            for (uint32_t j = cr->j0; j <= cr->j1; j++)
                for (uint32_t i = cr->i0; i <= cr->i1; i++) {
                    size_t cell = (size_t)j * f->gw + i;
                    for (uint32_t k = f->start[cell]; k < f->start[cell + 1] && best < 1; k++) {
                        double v = capsule_cover(&f->seg[f->ids[k]], x, y, qs);
                        if (v > best) best = v;
                    }
                }
            acc += best;
        }
    return acc / (SUBDIV * SUBDIV);
}

/* Coverage of pixel centred (cx, cy) of side pix by the union of the
 * capsules listed in the cells `cr`. */
static double pixel_cover(const rs__roadfield *f, const rf_cells *cr, double cx, double cy, const rf_px *q,
                          const rf_px *qs)
{
    rf_near nr;
    nr.n = nr.many = 0;
    for (uint32_t j = cr->j0; j <= cr->j1; j++)
        for (uint32_t i = cr->i0; i <= cr->i1; i++) {
            size_t cell = (size_t)j * f->gw + i;
            for (uint32_t k = f->start[cell]; k < f->start[cell + 1]; k++)
                if (near_eval(f, &nr, f->ids[k], cx, cy, q)) return 1;
        }
    return near_cover(f, &nr, cr, cx, cy, q, qs);
}

#define RF_MIN(a, b) ((a) < (b) ? (a) : (b))
#define RF_MAX(a, b) ((a) > (b) ? (a) : (b))

/* The x intervals where the horizontal line y = cy meets the capsule of
 * segment s grown to radius ro (*olo, *ohi) and shrunk to radius ri
 * (*ilo, *ihi): each the hull of the line's pieces in the two end discs
 * and in the band |t| <= rho between the end normals (a capsule is
 * convex). Bit 0 of the result: the outer interval is not empty; bit 1:
 * the inner one. ri <= ro. */
#if defined(__SSE2__)
/* SSE2: lane 0 the outer radius, lane 1 the inner; both end discs at once;
 * every case chosen by masks, not branches (the row decides which pieces
 * exist, unpredictably). The same intervals up to rounding, far below the
 * spans' slack tol. */
static int capsule_spans(const rf_seg *s, double cy, double ro, double ri, double *olo, double *ohi, double *ilo,
                         double *ihi)
{
    const __m128d inf = _mm_set1_pd(HUGE_VAL), ninf = _mm_set1_pd(-HUGE_VAL), zero = _mm_setzero_pd();
    __m128d rho = _mm_set_pd(ri, ro), rho2 = _mm_mul_pd(rho, rho);
    /* lane 1 (inner) exists only for ri >= 0 */
    __m128d use = _mm_cmpge_pd(rho, zero);
    double dya = cy - s->ay, dyb = cy - s->by;
    __m128d lo = inf, hi = ninf;
    /* end discs: |dy| <= rho gives the chord x +- sqrt(rho^2 - dy^2) */
    __m128d da = _mm_set1_pd(dya * dya), db = _mm_set1_pd(dyb * dyb);
    __m128d ma = _mm_and_pd(use, _mm_cmple_pd(da, rho2)), mb = _mm_and_pd(use, _mm_cmple_pd(db, rho2));
    __m128d qa = _mm_sqrt_pd(_mm_max_pd(_mm_sub_pd(rho2, da), zero));
    __m128d qb = _mm_sqrt_pd(_mm_max_pd(_mm_sub_pd(rho2, db), zero));
    __m128d xa = _mm_set1_pd(s->ax), xb = _mm_set1_pd(s->bx);
    lo = _mm_or_pd(_mm_and_pd(ma, _mm_sub_pd(xa, qa)), _mm_andnot_pd(ma, lo));
    hi = _mm_or_pd(_mm_and_pd(ma, _mm_add_pd(xa, qa)), _mm_andnot_pd(ma, hi));
    lo = _mm_min_pd(lo, _mm_or_pd(_mm_and_pd(mb, _mm_sub_pd(xb, qb)), _mm_andnot_pd(mb, inf)));
    hi = _mm_max_pd(hi, _mm_or_pd(_mm_and_pd(mb, _mm_add_pd(xb, qb)), _mm_andnot_pd(mb, ninf)));
    if (s->len > 0) {
        /* u = x - ax: p = u ux + dy uy in [0, len], t = u uy - dy ux in [-rho, rho] */
        double pl = -HUGE_VAL, ph = HUGE_VAL, t0 = dya * s->ux, p0 = dya * s->uy;
        if (s->iux != 0) {
            double u1 = -p0 * s->iux, u2 = (s->len - p0) * s->iux;
            pl = RF_MIN(u1, u2);
            ph = RF_MAX(u1, u2);
        } else if (p0 < 0 || p0 > s->len) pl = HUGE_VAL;
        __m128d ul, uh;
        if (s->iuy != 0) {
            __m128d iy = _mm_set1_pd(s->iuy), t = _mm_set1_pd(t0);
            __m128d u1 = _mm_mul_pd(_mm_sub_pd(t, rho), iy), u2 = _mm_mul_pd(_mm_add_pd(t, rho), iy);
            ul = _mm_max_pd(_mm_set1_pd(pl), _mm_min_pd(u1, u2));
            uh = _mm_min_pd(_mm_set1_pd(ph), _mm_max_pd(u1, u2));
        } else {
            /* parallel to the row: all of [pl, ph] when |t0| <= rho */
            __m128d in = _mm_cmple_pd(_mm_set1_pd(fabs(t0)), rho);
            ul = _mm_or_pd(_mm_and_pd(in, _mm_set1_pd(pl)), _mm_andnot_pd(in, inf));
            uh = _mm_or_pd(_mm_and_pd(in, _mm_set1_pd(ph)), _mm_andnot_pd(in, ninf));
        }
        __m128d mband = _mm_and_pd(use, _mm_cmple_pd(ul, uh));
        lo = _mm_min_pd(lo, _mm_or_pd(_mm_and_pd(mband, _mm_add_pd(xa, ul)), _mm_andnot_pd(mband, inf)));
        hi = _mm_max_pd(hi, _mm_or_pd(_mm_and_pd(mband, _mm_add_pd(xa, uh)), _mm_andnot_pd(mband, ninf)));
    }
    double l[2], h[2];
    _mm_storeu_pd(l, lo);
    _mm_storeu_pd(h, hi);
    *olo = l[0]; *ohi = h[0]; *ilo = l[1]; *ihi = h[1];
    return (l[0] <= h[0]) | (l[1] <= h[1]) << 1;
}

/* capsule_spans as pixel ranges of the row (centre of pixel k at (a + k)
 * pix), clipped to [k0, k1]: k[0..1] the outer (near) span, k[2..3] the
 * inner (deep) one when ri > 0; bit 0 / bit 1: not empty. Both lanes at
 * once and without branches: the values are clamped to [k0, k1 + 1] and
 * [k0 - 1, k1] first (an empty span then has k_lo > k_hi), ceil and floor
 * by truncation of non-negative values; the same ranges as span_pixels. */
static int capsule_pixels(const rf_seg *s, double cy, double ro, double ri, double a, double ipix, uint32_t k0,
                          uint32_t k1, int32_t *k)
{
    double olo, ohi, ilo, ihi;
    capsule_spans(s, cy, ro, ri, &olo, &ohi, &ilo, &ihi);
    __m128d va = _mm_set1_pd(a), vi = _mm_set1_pd(ipix), one = _mm_set1_pd(1);
    __m128d vl = _mm_sub_pd(_mm_mul_pd(_mm_set_pd(ilo, olo), vi), va);
    __m128d vh = _mm_sub_pd(_mm_mul_pd(_mm_set_pd(ihi, ohi), vi), va);
    vl = _mm_min_pd(_mm_max_pd(vl, _mm_set1_pd((double)k0)), _mm_set1_pd((double)k1 + 1));
    vh = _mm_min_pd(_mm_max_pd(vh, _mm_set1_pd((double)k0 - 1)), _mm_set1_pd((double)k1));
    __m128i tl = _mm_cvttpd_epi32(vl); /* ceil(vl) = trunc + (trunc < vl) */
    __m128d up = _mm_cmplt_pd(_mm_cvtepi32_pd(tl), vl);
    tl = _mm_sub_epi32(tl, _mm_shuffle_epi32(_mm_castpd_si128(up), _MM_SHUFFLE(3, 3, 2, 0)));
    __m128i th = _mm_sub_epi32(_mm_cvttpd_epi32(_mm_add_pd(vh, one)), _mm_set1_epi32(1)); /* floor(vh), vh >= -1 */
    int32_t t[4], u[4];
    _mm_storeu_si128((__m128i *)t, tl);
    _mm_storeu_si128((__m128i *)u, th);
    k[0] = t[0]; k[1] = u[0]; k[2] = t[1]; k[3] = u[1];
    return (k[0] <= k[1]) | ((k[2] <= k[3]) & (ri > 0)) << 1;
}
#else
static int capsule_spans(const rf_seg *s, double cy, double ro, double ri, double *olo, double *ohi, double *ilo,
                         double *ihi)
{
    double ol = HUGE_VAL, oh = -HUGE_VAL, il = HUGE_VAL, ih = -HUGE_VAL;
    double dy = cy - s->ay, dyb = cy - s->by, ady = fabs(dy), adyb = fabs(dyb), q;
    if (ady <= ro) {
        q = sqrt(ro * ro - dy * dy); ol = s->ax - q; oh = s->ax + q;
        if (ady <= ri) { q = sqrt(ri * ri - dy * dy); il = s->ax - q; ih = s->ax + q; }
    }
    if (adyb <= ro) {
        q = sqrt(ro * ro - dyb * dyb); ol = RF_MIN(ol, s->bx - q); oh = RF_MAX(oh, s->bx + q);
        if (adyb <= ri) { q = sqrt(ri * ri - dyb * dyb); il = RF_MIN(il, s->bx - q); ih = RF_MAX(ih, s->bx + q); }
    }
    if (s->len > 0) {
        /* u = x - ax: p = u ux + dy uy in [0, len], t = u uy - dy ux in [-rho, rho] */
        double pl = -HUGE_VAL, ph = HUGE_VAL, t0 = dy * s->ux, p0 = dy * s->uy;
        if (s->iux != 0) {
            double u1 = -p0 * s->iux, u2 = (s->len - p0) * s->iux;
            pl = RF_MIN(u1, u2);
            ph = RF_MAX(u1, u2);
        } else if (p0 < 0 || p0 > s->len) pl = HUGE_VAL;
        if (pl <= ph) {
            if (s->iuy != 0) {
                double iy = s->iuy, u1 = (t0 - ro) * iy, u2 = (t0 + ro) * iy;
                double ul = RF_MAX(pl, RF_MIN(u1, u2)), uh = RF_MIN(ph, RF_MAX(u1, u2));
                if (ul <= uh) { ol = RF_MIN(ol, s->ax + ul); oh = RF_MAX(oh, s->ax + uh); }
                u1 = (t0 - ri) * iy;
                u2 = (t0 + ri) * iy;
                ul = RF_MAX(pl, RF_MIN(u1, u2));
                uh = RF_MIN(ph, RF_MAX(u1, u2));
                if (ri >= 0 && ul <= uh) { il = RF_MIN(il, s->ax + ul); ih = RF_MAX(ih, s->ax + uh); }
            } else {
                double at = fabs(t0);
                if (at <= ro) { ol = RF_MIN(ol, s->ax + pl); oh = RF_MAX(oh, s->ax + ph); }
                if (at <= ri) { il = RF_MIN(il, s->ax + pl); ih = RF_MAX(ih, s->ax + ph); }
            }
        }
    }
    *olo = ol; *ohi = oh; *ilo = il; *ihi = ih;
    return (ol <= oh) | (il <= ih) << 1;
}
#endif

#if !defined(__SSE2__)
/* Pixels [k0, k1] of a row whose centres lie in [lo, hi]: centre of pixel k
 * is (a + k) pix. Returns 0 when none. */
static int span_pixels(double lo, double hi, double a, double ipix, uint32_t k0, uint32_t k1, uint32_t *kl,
                       uint32_t *kh)
{
    /* ceil and floor by truncation: the values are clamped into [k0, k1] first */
    double vl = lo * ipix - a, vh = hi * ipix - a;
    if (!(vl <= (double)k1 && vh >= (double)k0 && vl <= vh)) return 0;
    uint32_t il = k0, ih = k1;
    if (vl > (double)k0) { il = (uint32_t)vl; il += (double)il < vl; }
    if (vh < (double)k1) ih = (uint32_t)vh;
    if (il > ih) return 0;
    *kl = il;
    *kh = ih;
    return 1;
}

static int capsule_pixels(const rf_seg *s, double cy, double ro, double ri, double a, double ipix, uint32_t k0,
                          uint32_t k1, int32_t *k)
{
    double olo, ohi, ilo, ihi;
    uint32_t kl, kh, il, ih;
    int got = capsule_spans(s, cy, ro, ri, &olo, &ohi, &ilo, &ihi), r = 0;
    if ((got & 1) && span_pixels(olo, ohi, a, ipix, k0, k1, &kl, &kh)) {
        k[0] = (int32_t)kl; k[1] = (int32_t)kh; r = 1;
    }
    if (ri > 0 && (got & 2) && span_pixels(ilo, ihi, a, ipix, k0, k1, &il, &ih)) {
        k[2] = (int32_t)il; k[3] = (int32_t)ih; r |= 2;
    }
    return r;
}
#endif

/* Candidates kept per pixel by the row spans (a power of 2); more falls
 * back to the cell scan. */
#define SPAN_CAND 4
enum { CHUNK = 1024, ACT_MAX = 1024, PAINT_RUN = 2 /* paint_run unrolls 2 */, FILL_RUN = 8 /* fill_one: 8 */ };

typedef struct rf_rowbuf {
    /* candidates per pixel; slots CHUNK.. CHUNK + PAINT_RUN - 1 take the
     * unused stores of paint_run (never listed, never read) */
    uint8_t cnt[CHUNK + PAINT_RUN];
    uint32_t cand[CHUNK + PAINT_RUN][SPAN_CAND];
    /* runs of pixels with the same cell column: run m is pixels
     * [rk[m], rk[m+1]) in cell column rc[m] (UINT32_MAX: outside the grid) */
    uint32_t rc[CHUNK], nrun;
    uint16_t rk[CHUNK + 1];
    /* per grid row (cached while consecutive pixel rows share it): runs
     * needing per-pixel work, full runs, their pixel range [k0, k1], and the
     * row-list entries whose box meets that range in x (nact = UINT32_MAX:
     * more than ACT_MAX meet it, check them all) */
    uint32_t crow, ntodo, nfull, nfullg, k0, k1, nact;
    uint16_t todo[CHUNK], fullr[CHUNK], fullg[CHUNK];
    uint32_t act[ACT_MAX], sel[ACT_MAX];
    /* pixels of the current row with at least one candidate (cnt > 0), in
     * the order first painted; cnt is zero again after each row */
    uint32_t npl;
    uint16_t pl[CHUNK + 1];
    /* the painted pixels still to compute: one candidate (l1), more (lm,
     * with their counts lc) */
    uint16_t l1[CHUNK], lm[CHUNK];
    uint8_t lc[CHUNK];
} rf_rowbuf;

/* Adds candidate id to pixels [x, y] of the row (none when y < x) and
 * lists the pixels that get their first one; returns the new list length.
 * Runs are mostly a pixel or two: up to PAINT_RUN pixels take a fixed
 * number of stores, the unused ones into spare slots, so no loop exit
 * depends on the data (such branches are mispredicted). */
static uint32_t paint_run(rf_rowbuf *rb, uint32_t npl, int64_t x, int64_t y, uint32_t id)
{
    /* a slot past SPAN_CAND is never read (the pixel scans its cell) */
#define RF_SLOT(j)                                                                                               \
    do {                                                                                                         \
        uint32_t v_ = x + (j) <= y, i_ = (uint32_t)(x + (j));                                                   \
        i_ += ((uint32_t)(CHUNK + (j)) - i_) & (v_ - 1u); /* unused: the spare slot, no branch */                \
        uint8_t c_ = rb->cnt[i_];                                                                                \
        rb->pl[npl] = (uint16_t)i_;                                                                              \
        npl += (uint32_t)(v_ & (c_ == 0));                                                                       \
        rb->cand[i_][c_ & (SPAN_CAND - 1)] = id;                                                                 \
        rb->cnt[i_] = (uint8_t)(c_ + (c_ <= SPAN_CAND));                                                         \
    } while (0)
    RF_SLOT(0); RF_SLOT(1);
#undef RF_SLOT
    for (int64_t k = x + PAINT_RUN; k <= y; k++) {
        uint8_t c = rb->cnt[k];
        rb->pl[npl] = (uint16_t)k;
        npl += c == 0;
        rb->cand[k][c & (SPAN_CAND - 1)] = id;
        rb->cnt[k] = (uint8_t)(c + (c <= SPAN_CAND));
    }
    return npl;
}

/* o[il..ih] = 1 (il <= ih); short runs by a fixed number of stores (the
 * last ones repeated), as in paint_run: with SSE2 eight pair stores inside
 * the run (up to 16 pixels), else eight single ones. */
static void fill_one(double *o, int64_t il, int64_t ih)
{
#if defined(__SSE2__)
    if (ih - il < 2 * FILL_RUN) {
        o[il] = 1;
        o[ih] = 1;
        if (ih - il >= 2) {
            const __m128d one = _mm_set1_pd(1);
            int64_t last = ih - 1;
#define RF_TWO(j) _mm_storeu_pd(o + (il + 2 * (j) <= last ? il + 2 * (j) : last), one)
            RF_TWO(0); RF_TWO(1); RF_TWO(2); RF_TWO(3); RF_TWO(4); RF_TWO(5); RF_TWO(6); RF_TWO(7);
#undef RF_TWO
        }
        return;
    }
#else
    if (ih - il < FILL_RUN) {
#define RF_ONE(j) o[il + (j) <= ih ? il + (j) : ih] = 1
        RF_ONE(0); RF_ONE(1); RF_ONE(2); RF_ONE(3); RF_ONE(4); RF_ONE(5); RF_ONE(6); RF_ONE(7);
#undef RF_ONE
        return;
    }
#endif
    for (int64_t k = il; k <= ih; k++) o[k] = 1;
}

/* Cell column of pixel k of the chunk (the run holding it; k is in a run). */
static uint32_t run_col(const rf_rowbuf *rb, uint32_t k)
{
    uint32_t lo = 0, hi = rb->nrun; /* rk[lo] <= k < rk[hi] */
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (rb->rk[mid] <= k) lo = mid;
        else hi = mid;
    }
    return rb->rc[lo];
}

/* A pixel with one candidate: band_value when the pixel is in its slab,
 * else it joins the list lm (cap_cover and the others). Returns lm's new
 * length. With a second field g (the same segments, wider: coverage2),
 * og[k] gets g's band_value too, unless already 1 (a full cell of g). */
static uint32_t one_cand(const rs__roadfield *f, const rs__roadfield *g, rf_rowbuf *rb, uint32_t k, double a,
                         double cy, const rf_px *q, double *o, double *og, uint32_t nm)
{
    double cx = (a + (double)k) * q->side;
    uint32_t id = rb->cand[k][0];
    const rf_seg *s = &f->seg[id];
    double wx = cx - s->ax, wy = cy - s->ay, pr = wx * s->ux + wy * s->uy, hp = q->hs * s->l1;
    if (s->len > 0 && pr - hp >= 0 && pr + hp <= s->len) {
        double t = wx * s->uy - wy * s->ux;
        o[k] = band_value(s, q, t);
        if (g && og[k] != 1) og[k] = band_value(&g->seg[id], q, t);
        return nm;
    }
    rb->lm[nm] = (uint16_t)k;
    rb->lc[nm] = 1;
    return nm + 1;
}

/* The cover of pixel k with c candidates (not all in one slab, or more
 * than one): the near ones by seg_eval, then near_cover; the cell scan
 * (pixel_cover) past SPAN_CAND candidates. */
static double cand_cover(const rs__roadfield *f, const rf_rowbuf *rb, uint32_t k, uint8_t c, uint32_t row,
                         double cx, double cy, const rf_px *q, const rf_px *qs)
{
    if (c > SPAN_CAND) {
        uint32_t col = run_col(rb, k);
        rf_cells cr = { col, col, row, row };
        return pixel_cover(f, &cr, cx, cy, q, qs);
    }
    /* the candidates are distinct segments: no duplicate check */
    rf_near nr;
    int n = 0, deep = 0;
    uint8_t j = 0;
    if (c == 2) {
        /* the common case (joints, crossings): both in one go */
        uint32_t i0 = rb->cand[k][0], i1 = rb->cand[k][1];
        int c0, c1;
        seg_eval2(&f->seg[i0], &f->seg[i1], cx, cy, q, &nr, 0, &c0, &c1);
        deep = (c0 == 2) | (c1 == 2);
        int keep0 = (c0 == 1) & !f->seg[i0].redundant, keep1 = (c1 == 1) & !f->seg[i1].redundant;
        /* a first candidate not kept: the second's results move to slot 0 */
        nr.id[0] = keep0 ? i0 : i1;
        nr.p[0] = keep0 ? nr.p[0] : nr.p[1];
        nr.t[0] = keep0 ? nr.t[0] : nr.t[1];
        nr.slab[0] = keep0 ? nr.slab[0] : nr.slab[1];
        nr.id[1] = i1;
        n = keep0 + keep1;
        j = c;
    }
    for (; j < c; j++) {
        uint32_t id = rb->cand[k][j];
        int cl = seg_eval(&f->seg[id], cx, cy, q, &nr, n);
        deep |= cl == 2;
        nr.id[n] = id;
        n += (cl == 1) & !f->seg[id].redundant;
    }
    nr.n = n;
    nr.many = 0;
    /* the cells are read only when nr.many */
    return deep ? 1 : near_cover(f, &nr, NULL, cx, cy, q, qs);
}

/* One pixel row of a chunk, one-cell path. Pixels in empty cells are 0, in
 * full cells 1. For the rest, every segment of the grid row gives two
 * spans along the row: where the pixel centre is certainly deep inside
 * (radius r - e - tol) and where it may be near (radius r + e + tol). A
 * deep pixel is 1, a pixel in no near span is 0, and the others classify
 * only their few candidates exactly (seg_class, as the cell scan does).
 * tol is far above the rounding of the spans, so this equals the scan of
 * the pixel's cell list (docs/roadfield.md): a pixel's value never depends
 * on the block.
 * With a second field g (rs__roadfield_widen of f: the same segments and
 * grid, radii at least f's), og gets g's coverage in the same pass: the
 * rows list g's segments (near spans of g's radii list every pixel either
 * field needs), deep spans and full cells are f's (deep or full in f is so
 * in g), cells full only in g are 1 in og, and every listed pixel is
 * evaluated with both fields' segments. Each output equals its field's
 * own pass: a pixel's candidates are a superset of that pass's, and the
 * extra ones classify as clear (docs/roadfield.md). */
static void cover_row(const rs__roadfield *f, const rs__roadfield *g, rf_rowbuf *rb, double a, uint32_t row,
                      double cy, const rf_px *q, const rf_px *qs, double *o, double *og)
{
    double pix = q->side, e = q->e;
    const rs__roadfield *L = g ? g : f; /* the lists */
    if (rb->crow != row) {
        size_t base = (size_t)row * f->gw;
        uint32_t k0 = UINT32_MAX, k1 = 0, ntodo = 0, nfull = 0, nfullg = 0;
        /* runs of empty, full and other cells, listed without a branch (a
         * run outside the grid reads cell `base`, and counts as empty) */
        for (uint32_t m = 0; m < rb->nrun; m++) {
            uint32_t in = rb->rc[m] != UINT32_MAX;
            size_t cell = base + (in ? rb->rc[m] : 0);
            uint32_t some = in & (L->start[cell] != L->start[cell + 1]), full = some & (f->full[cell] != 0);
            rb->fullr[nfull] = (uint16_t)m;
            nfull += full;
            rb->fullg[nfullg] = (uint16_t)m;
            nfullg += g ? some & !full & (g->full[cell] != 0) : 0;
            rb->todo[ntodo] = (uint16_t)m;
            ntodo += some & !full;
        }
        /* the runs are in pixel order: the first and the last todo run */
        if (ntodo) {
            k0 = rb->rk[rb->todo[0]];
            k1 = rb->rk[rb->todo[ntodo - 1] + 1] - 1;
        }
        rb->crow = row;
        rb->ntodo = ntodo;
        rb->nfull = nfull;
        rb->nfullg = nfullg;
        rb->k0 = k0;
        rb->k1 = k1;
        rb->nact = UINT32_MAX;
        if (ntodo && L->rspan[row] && f->rspan[row]) {
            /* (a long row list, as a whole map's is, still has few entries
             * in a narrow window: a dirty render's, a tile's) */
            double xlo = (a + (double)k0) * pix, xhi = (a + (double)k1) * pix;
            uint32_t n = 0;
            for (uint32_t m = L->rstart[row]; m < L->rstart[row + 1]; m++) {
                const float *bx = L->rbox + 4 * (size_t)m;
                if (xhi < bx[0] || xlo > bx[1]) continue;
                if (n == ACT_MAX) {
                    n = UINT32_MAX;
                    break;
                }
                rb->act[n++] = m;
            }
            rb->nact = n;
        }
    }
    uint32_t k0 = rb->k0, k1 = rb->k1, ntodo = rb->ntodo;
    memset(o, 0, rb->rk[rb->nrun] * sizeof *o);
    for (uint32_t t = 0; t < rb->nfull; t++)
        for (uint32_t k = rb->rk[rb->fullr[t]]; k < rb->rk[rb->fullr[t] + 1]; k++) o[k] = 1;
    if (g) {
        memcpy(og, o, rb->rk[rb->nrun] * sizeof *o);
        for (uint32_t t = 0; t < rb->nfullg; t++)
            for (uint32_t k = rb->rk[rb->fullg[t]]; k < rb->rk[rb->fullg[t] + 1]; k++) og[k] = 1;
    }
    if (!ntodo) return;
    if (!L->rspan[row] || !f->rspan[row]) {
        for (uint32_t t = 0; t < ntodo; t++) {
            uint32_t m = rb->todo[t];
            rf_cells cr = { rb->rc[m], rb->rc[m], row, row };
            for (uint32_t k = rb->rk[m]; k < rb->rk[m + 1]; k++) {
                o[k] = pixel_cover(f, &cr, (a + (double)k) * pix, cy, q, qs);
                if (g && og[k] != 1) og[k] = pixel_cover(g, &cr, (a + (double)k) * pix, cy, q, qs);
            }
        }
        return;
    }
    double xlo = (a + (double)k0) * pix, xhi = (a + (double)k1) * pix, ipix = 1 / pix;
    uint32_t nent = rb->nact, npl = 0;
    const uint32_t *list = NULL;
    if (nent != UINT32_MAX) {
        /* the entries of act meet [xlo, xhi] already: those whose box (grown
         * by margin >= e) meets this pixel row, listed without a branch */
        uint32_t n = 0;
        for (uint32_t j = 0; j < nent; j++) {
            const float *bx = L->rbox + 4 * (size_t)rb->act[j];
            rb->sel[n] = rb->act[j];
            n += (uint32_t)(!(cy < bx[2]) & !(cy > bx[3]));
        }
        nent = n;
        list = rb->sel;
    } else
        nent = L->rstart[row + 1] - L->rstart[row];
    for (uint32_t j = 0; j < nent; j++) {
        uint32_t m;
        if (list) m = list[j];
        else {
            m = L->rstart[row] + j;
            const float *bx = L->rbox + 4 * (size_t)m;
            if (cy < bx[2] || cy > bx[3] || xhi < bx[0] || xlo > bx[1]) continue;
        }
        uint32_t id = L->rids[m];
        const rf_seg *s = &f->seg[id], *sl = &L->seg[id];
        double ro = sl->r + e + sl->tol, ri = s->r - e - s->tol;
        int32_t kk[4];
        int got = capsule_pixels(s, cy, ro, ri, a, ipix, k0, k1, kk);
        if (!(got & 1)) continue;
        /* deep pixels are 1 at once (a deep pixel's cell lists the segment,
         * so it is in a todo or full run) and need no candidate: paint the
         * near span minus the deep one */
        if (got & 2) {
            fill_one(o, kk[2], kk[3]);
            if (g) fill_one(og, kk[2], kk[3]);
            npl = paint_run(rb, npl, kk[0], (int64_t)kk[2] - 1, id);
            npl = paint_run(rb, npl, (int64_t)kk[3] + 1, kk[1], id);
        } else
            npl = paint_run(rb, npl, kk[0], kk[1], id);
    }
    /* the painted pixels: 1 (deep in some capsule, or a full cell) stay;
     * the others are listed by their number of candidates (no branch) */
    uint32_t n1 = 0, nm = 0;
    for (uint32_t t = 0; t < npl; t++) {
        uint32_t k = rb->pl[t];
        uint8_t c = rb->cnt[k];
        int todo = o[k] != 1;
        rb->cnt[k] = 0;
        rb->l1[n1] = (uint16_t)k;
        n1 += (uint32_t)(todo & (c == 1));
        rb->lm[nm] = (uint16_t)k;
        rb->lc[nm] = c;
        nm += (uint32_t)(todo & (c != 1));
    }
    /* one candidate with the pixel in its slab (most edge pixels):
     * seg_eval's slab branch and band_value, same arithmetic */
    uint32_t t = 0;
#if defined(__SSE2__)
    for (; t + 1 < n1; t += 2) {
        /* two pixels at once when both are in their slabs */
        uint32_t p0 = rb->l1[t], p1 = rb->l1[t + 1];
        const rf_seg *s0 = &f->seg[rb->cand[p0][0]], *s1 = &f->seg[rb->cand[p1][0]];
        __m128d ux = RF_PAIR(s0, s1, ux), uy = RF_PAIR(s0, s1, uy), len = RF_PAIR(s0, s1, len), zero = _mm_setzero_pd();
        __m128d wx = _mm_sub_pd(_mm_mul_pd(_mm_set_pd(a + (double)p1, a + (double)p0), _mm_set1_pd(pix)),
                                RF_PAIR(s0, s1, ax));
        __m128d wy = _mm_sub_pd(_mm_set1_pd(cy), RF_PAIR(s0, s1, ay));
        __m128d pr = _mm_add_pd(_mm_mul_pd(wx, ux), _mm_mul_pd(wy, uy));
        __m128d hp = _mm_mul_pd(_mm_set1_pd(q->hs), RF_PAIR(s0, s1, l1));
        __m128d slab = _mm_and_pd(_mm_and_pd(_mm_cmpgt_pd(len, zero), _mm_cmpge_pd(_mm_sub_pd(pr, hp), zero)),
                                  _mm_cmple_pd(_mm_add_pd(pr, hp), len));
        if (_mm_movemask_pd(slab) == 3) {
            double v[2];
            __m128d tt = _mm_sub_pd(_mm_mul_pd(wx, uy), _mm_mul_pd(wy, ux));
            _mm_storeu_pd(v, band_value2(s0, s1, q, tt));
            o[p0] = v[0];
            o[p1] = v[1];
            if (g) {
                _mm_storeu_pd(v, band_value2(&g->seg[rb->cand[p0][0]], &g->seg[rb->cand[p1][0]], q, tt));
                if (og[p0] != 1) og[p0] = v[0];
                if (og[p1] != 1) og[p1] = v[1];
            }
        } else {
            /* not both (rare): one by one */
            nm = one_cand(f, g, rb, p0, a, cy, q, o, og, nm);
            nm = one_cand(f, g, rb, p1, a, cy, q, o, og, nm);
        }
    }
#endif
    for (; t < n1; t++) nm = one_cand(f, g, rb, rb->l1[t], a, cy, q, o, og, nm);
    for (t = 0; t < nm; t++) {
        uint32_t k = rb->lm[t];
        uint8_t c = rb->lc[t];
        double cx = (a + (double)k) * pix;
        o[k] = cand_cover(f, rb, k, c, row, cx, cy, q, qs);
        /* g is the casing field: a pixel that f covers to within
         * CASING_SKIP shows no casing the output can hold, so its costly
         * cover (joints, crossings) is not needed: og = o */
        if (g && og[k] != 1) og[k] = o[k] >= 1 - CASING_SKIP ? o[k] : cand_cover(g, rb, k, c, row, cx, cy, q, qs);
    }
}

static void coverage(const rs__roadfield *f, const rs__roadfield *g, uint32_t px0, uint32_t py0, uint32_t w,
                     uint32_t h, double pix, double *out, double *outg, size_t stride)
{
    if (!(pix > 0) || !isfinite(pix)) {
        for (uint32_t y = 0; y < h; y++) {
            memset(out + (size_t)y * stride, 0, w * sizeof *out);
            if (g) memset(outg + (size_t)y * stride, 0, w * sizeof *out);
        }
        return;
    }
    rf_px q, qs; /* the pixel and its sub-squares */
    px_set(&q, pix);
    px_set(&qs, pix / SUBDIV);
    /* One cell's list suffices when half the pixel diagonal is within the
     * lists' margin; then empty cells are 0 and full cells 1 at once. */
    if (pix <= f->pixel) {
        rf_rowbuf rb;
        double ipix = 1 / pix;
        for (uint32_t x0 = 0; x0 < w; x0 += CHUNK) {
            uint32_t n = w - x0 < CHUNK ? w - x0 : CHUNK;
            /* centre of pixel k of the chunk: (a + k) pix */
            double a = (double)px0 + (double)x0 + 0.5;
            rb.nrun = 0;
            rb.crow = UINT32_MAX;
            memset(rb.cnt, 0, sizeof rb.cnt);
            /* cell_of of every pixel centre, as runs: it is monotone in k
             * inside the grid, so a run's end is estimated from the cell's
             * right edge and then checked with cell_of itself (exact) */
            uint64_t p0 = (uint64_t)px0 + x0;
            if (f->colpix && pix == f->pixel && p0 + n <= f->colpix[f->gw]) {
                /* the field's table: the same cells, no per-pixel cell_of */
                int64_t c = cell_of(f, (a + 0.0) * pix, f->gw);
                for (uint32_t k = 0; k < n; c++) {
                    uint64_t e1 = f->colpix[c + 1];
                    uint32_t kn = e1 - p0 >= n ? n : (uint32_t)(e1 - p0);
                    if (kn > k) {
                        rb.rc[rb.nrun] = (uint32_t)c;
                        rb.rk[rb.nrun++] = (uint16_t)k;
                        k = kn;
                    }
                }
            } else
            for (uint32_t k = 0; k < n;) {
                int64_t c = cell_of(f, (a + (double)k) * pix, f->gw);
                uint32_t cc = c < 0 ? UINT32_MAX : (uint32_t)c, kn = k + 1;
                if (c >= 0) {
                    double est = ceil((double)c * f->c * ipix - a); /* first centre at or past the right edge */
                    kn = est >= (double)n ? n : est <= (double)(k + 1) ? k + 1 : (uint32_t)est;
                    while (kn > k + 1 && cell_of(f, (a + (double)(kn - 1)) * pix, f->gw) != c) kn--;
                    while (kn < n && cell_of(f, (a + (double)kn) * pix, f->gw) == c) kn++;
                }
                if (rb.nrun == 0 || cc != rb.rc[rb.nrun - 1]) {
                    rb.rc[rb.nrun] = cc;
                    rb.rk[rb.nrun++] = (uint16_t)k;
                }
                k = kn;
            }
            rb.rk[rb.nrun] = (uint16_t)n;
            for (uint32_t y = 0; y < h; y++) {
                double cy = ((double)py0 + (double)y + 0.5) * pix;
                double *o = out + (size_t)y * stride + x0, *og = g ? outg + (size_t)y * stride + x0 : NULL;
                int64_t row = cell_of(f, cy, f->gh);
                if (row >= 0) cover_row(f, g, &rb, a, (uint32_t)row, cy, &q, &qs, o, og);
                else {
                    memset(o, 0, n * sizeof *o);
                    if (g) memset(og, 0, n * sizeof *o);
                }
            }
        }
        return;
    }
    for (uint32_t y = 0; y < h; y++) {
        double cy = ((double)py0 + (double)y + 0.5) * pix, *o = out + (size_t)y * stride;
        for (uint32_t k = 0; k < w; k++) {
            double cx = ((double)px0 + (double)k + 0.5) * pix;
            rf_cells cr;
            int any = cells_around(f, cx, cy, 0.5 * pix + 1e-6 * f->c, &cr);
            o[k] = any ? pixel_cover(f, &cr, cx, cy, &q, &qs) : 0;
            if (g) outg[(size_t)y * stride + k] = any ? pixel_cover(g, &cr, cx, cy, &q, &qs) : 0;
        }
    }
}

void rs__roadfield_coverage(const rs__roadfield *f, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h,
                            double pix, double *out, size_t stride)
{
    if (!f || !out || !w || !h) return;
    coverage(f, NULL, px0, py0, w, h, pix, out, NULL, stride);
    tee_pass(f, NULL, px0, py0, w, h, pix, out, NULL, stride);
}

void rs__roadfield_coverage2(const rs__roadfield *f, const rs__roadfield *g, uint32_t px0, uint32_t py0,
                             uint32_t w, uint32_t h, double pix, double *out, double *outg, size_t stride)
{
    if (!f || !out || !w || !h) return;
    if (!g || !outg) {
        coverage(f, NULL, px0, py0, w, h, pix, out, NULL, stride);
        tee_pass(f, NULL, px0, py0, w, h, pix, out, NULL, stride);
        return;
    }
    coverage(f, g, px0, py0, w, h, pix, out, outg, stride);
    if (f->ntee && g->ntee == f->ntee) {
        tee_pass(f, g, px0, py0, w, h, pix, out, outg, stride);
        return;
    }
    tee_pass(f, NULL, px0, py0, w, h, pix, out, NULL, stride);
    tee_pass(g, NULL, px0, py0, w, h, pix, outg, NULL, stride);
}
