/* Automatic marking placement (issue 14, docs/markings.md "Automatic
 * placement"):
 *
 * - junctions, per street (the network's strokes: a street whole or split
 *   anywhere has the same ones): a free end of street A within B's half
 *   width (+ 0.5 m) of street B's centreline (B's nearest record); a street
 *   passing through a node of the network where another meets it (both
 *   sides approach); a record end its street goes on from, crossed there by
 *   a street the network did not join. Its area on A is the stretch within
 *   B's half width + 0.5 m of the junction; on B, A's half width + 0.5 m;
 *   both on every record of the street they reach.
 * - stop / give-way lines: where A ends at B and A's priority is below B's
 *   (rs__road_priority: the class rank, motorway > trunk > primary >
 *   secondary > tertiary > residential > service > track > path, footway,
 *   cycleway, no class lowest; + 10 for priority_road, + 20 for a
 *   roundabout's ring, so its arms give way), a give-way line (stop line
 *   with `control=stop`) across A's incoming half (the whole width when
 *   one-way), 0.5 m before A's junction area. A closed ring passes through
 *   its own seam: an arm ending on its first point is a junction too.
 * - turn arrows: `turn:lanes=left|through;right|...` (OpenStreetMap, lanes
 *   from left to right) on a road whose end is a junction (OSM: the turns
 *   at the end of the way; none where a way passes through): one arrow per
 *   lane, its tip 6 m before the junction area; the lanes share the
 *   incoming half (the whole width when one-way).
 * - zebra crossings: a `X Y crossing=zebra` point attribute puts a zebra
 *   across the road there (width = road width - 0.4 m).
 *
 * - non-car classes (path, footway, cycleway) get no stop or give-way
 *   lines and no arrows, and make no junctions with other roads: a
 *   footway meeting a street neither gives way nor cuts the street's
 *   markings (issue 28).
 *
 * A placement is dropped when it would spill off its road (|t| + width/2
 * beyond the half width, or past either end) or overlap a junction area. */
#include "markings.h"
#include "network.h"
#include "lanes.h"
#include "atlas.h"

#include <limits.h>
#include <math.h>
#include <string.h>

#define JUNCTION_TOL 0.5   /* metres beyond the other road's half width */
#define LINE_GAP 0.5       /* stop line to junction area */
#define ARROW_GAP 6.0      /* arrow tip to junction area */

typedef struct jn {
    size_t road;
    double s, half; /* centre and half extent of the junction area along the road */
} jn;

typedef struct ctxa {
    rs_ctx *ctx;
    const rs_roads *roads;
    const rs_style_options *so; /* profile, default driving side (may be NULL) */
    rs__line_cut *cuts;         /* where the markings interrupt their road's lines (NULL: not asked) */
    size_t ncut, capcut;
    int want_cuts;
    rs__road_local *rl; /* per road */
    double *box;        /* per road: x0 y0 x1 y1 */
    /* the junction areas in chunks of JN_CHUNK (3 x 10^6 at 10^5 roads:
     * one array doubling to 100 MB copied up to 25 MB at once from the
     * heap, 30-45 ms without a poll) */
    jn **jc;
    size_t nj, capjc;
    /* per road end (2 per road): the record that goes on there (the same
     * street split into records, turning less than 30 degrees), + 1; 0:
     * none. cont_end: that record meets it with its last point. */
    size_t *cont;
    uint8_t *cont_end;
    uint32_t *jstart, *jidx; /* the junctions of road i: jidx[jstart[i] .. jstart[i+1]) (NULL: scan all) */
    const rs_network *net;   /* strokes: the areas and cuts run on across a street's records (set
                                before any junction is looked for) */
    double *slen;            /* per stroke: its length */
} ctxa;

/* Where traffic arrives at a junction along a road: at a free end of its
 * street (the street's last record ends there) or where the street
 * passes through (a node of the network where another street meets it;
 * a street split there passes through too). */
typedef struct approach {
    size_t road;
    double s, half;  /* the junction's arc length on the road, its area's half extent along it */
    int8_t arrive;   /* +1: traffic arrives travelling with the road's points, -1: against them */
    uint8_t minor;   /* it gives way */
    uint8_t end;     /* a free end (the lines' cut runs on beyond it) */
    uint8_t arrows;  /* at a record's end: its turn:lanes arrows (OSM: the turns at the end of the way) */
    double yu[3];    /* how far from the crossing along the road a point at lateral offset -ha, 0, +ha
                        (ha: its half width) clears the streets it gives way to (yield_add; 0: none) */
} approach;

/* A street of half width hb that the approach gives way to, crossing it at
 * the junction: its centre line along (mx, my); the approach leaves the
 * crossing along (wx, wy), its lateral axis (t, + left of the points'
 * direction) is (nx, ny), its half width ha. A point u along and t across
 * clears the street's near edge when u |m x w| >= hb + c t (c: how the
 * offset leans towards the street), so yu samples u + JUNCTION_TOL at t =
 * -ha, 0, ha (the largest of the streets'; the sine no smaller than 0.2).
 * Until 3 December 2026 the stop and give-way lines stood hb +
 * JUNCTION_TOL from the crossing at every angle: at an oblique junction
 * their acute corner stood inside the street, at 30 degrees across its
 * centre line. */
#define YIELD_MIN_SINE 0.2
static void yield_add(approach *q, double ha, double hb, double mx, double my, double wx, double wy, double nx,
                      double ny)
{
    double cw = mx * wy - my * wx, cn = mx * ny - my * nx, sn = fabs(cw);
    if (!(sn >= YIELD_MIN_SINE)) sn = YIELD_MIN_SINE; /* (NaN too) */
    double c = cw >= 0 ? -cn : cn;
    for (int k = 0; k < 3; k++) {
        double t = (k - 1) * ha, u = (hb + c * t) / sn + JUNCTION_TOL;
        if (u > q->yu[k]) q->yu[k] = u;
    }
}

/* yu at lateral offset t (between the samples: their chord, at least the
 * convex largest of lines it samples) */
static double yield_at(const approach *q, double ha, double t)
{
    if (!(ha > 0)) return q->yu[1];
    double f = t / ha;
    if (f < -1) f = -1;
    if (f > 1) f = 1;
    return f < 0 ? q->yu[1] + (q->yu[1] - q->yu[0]) * f : q->yu[1] + (q->yu[2] - q->yu[1]) * f;
}

/* Roads with a segment whose box (grown by the road's half width +
 * JUNCTION_TOL) meets a grid cell, ascending, once, per cell: a road end
 * looks only at the roads of its cell, not at every road (the loop stays
 * in road order and keeps its tests, so the result is the one of the scan
 * over all roads). Segments, not whole roads: a long road's box would put
 * it in the lists of many cells far from it. */
typedef struct road_cells {
    double x0, y0, cw, ch, icw, ich; /* origin, cell size and its inverse */
    size_t gx, gy;
    uint32_t *start, *ids; /* start: gx * gy + 1 */
} road_cells;

/* Room for one more of `n` items of `size` bytes in *arr (capacity *cap,
 * doubled, first `first`; big steps copied in polled pieces: rs__grow). */
static rs_result room_for_one(rs_ctx *ctx, void **arr, size_t n, size_t *cap, size_t size, size_t first)
{
    return rs__grow(ctx, arr, n, cap, size, first, SIZE_MAX / size);
}

#define JN_BITS 14
#define JN_CHUNK ((size_t)1 << JN_BITS)

/* Junction area i. */
static jn *jn_at(const ctxa *A, size_t i)
{
    return &A->jc[i >> JN_BITS][i & (JN_CHUNK - 1)];
}

static rs_result add_jn(ctxa *A, size_t road, double s, double half)
{
    if ((A->nj & (JN_CHUNK - 1)) == 0) {
        size_t k = A->nj >> JN_BITS;
        void *arr = A->jc;
        rs_result g = room_for_one(A->ctx, &arr, k, &A->capjc, sizeof *A->jc, 16);
        if (g) return g;
        A->jc = arr;
        if (!(A->jc[k] = rs__alloc_array(A->ctx, JN_CHUNK, sizeof **A->jc))) return RS_ERR_NOMEM;
    }
    jn *J = jn_at(A, A->nj);
    J->road = road;
    J->s = s;
    J->half = half;
    A->nj++;
    return RS_OK;
}

/* Nearest point of road r to (x, y): distance and arc length. */
/* nearest, and the nearest point itself (*fx, *fy); only segments that
 * may come within `cap` are measured (INFINITY: all; when none is that
 * near, INFINITY and *s_out, *fx, *fy untouched or of a farther one) */
static double nearest_foot_within(const rs__road_local *r, double x, double y, double cap, double *s_out, double *fx,
                                  double *fy)
{
    double best = INFINITY;
    *fx = x, *fy = y;
    for (size_t k = 0; k + 1 < r->n; k++) {
        double dx = r->x[k + 1] - r->x[k], dy = r->y[k + 1] - r->y[k], len = r->s[k + 1] - r->s[k];
        if (!(len > 0)) continue;
        double u = ((x - r->x[k]) * dx + (y - r->y[k]) * dy) / len;
        if (u < 0) u = 0;
        if (u > len) u = len;
        double ex = x - r->x[k] - u * dx / len, ey = y - r->y[k] - u * dy / len;
        /* (hypot is no less than either leg: a segment that cannot win is
         * not measured) */
        double lb = fmax(fabs(ex), fabs(ey));
        if (lb >= best || lb > cap) continue;
        double d = hypot(ex, ey);
        if (d < best) {
            best = d;
            *s_out = r->s[k] + u;
            *fx = x - ex, *fy = y - ey;
        }
    }
    return best;
}

static double nearest_foot(const rs__road_local *r, double x, double y, double *s_out, double *fx, double *fy)
{
    return nearest_foot_within(r, x, y, INFINITY, s_out, fx, fy);
}

static double nearest(const rs__road_local *r, double x, double y, double *s_out)
{
    double fx, fy;
    return nearest_foot(r, x, y, s_out, &fx, &fy);
}

/* nearest when it is no farther than cap (else a value above cap) */
static double nearest_within(const rs__road_local *r, double x, double y, double cap, double *s_out)
{
    double fx, fy;
    return nearest_foot_within(r, x, y, cap, s_out, &fx, &fy);
}

/* Unit direction of road r at arc length s (its segment there, else the
 * nearest of positive length); 0 when it has none. */
static int dir_at(const rs__road_local *r, double s, double *dx, double *dy)
{
    size_t best = SIZE_MAX;
    double bd = INFINITY;
    for (size_t k = 0; k + 1 < r->n; k++) {
        if (!(r->s[k + 1] > r->s[k])) continue;
        double d = s < r->s[k] ? r->s[k] - s : s > r->s[k + 1] ? s - r->s[k + 1] : 0;
        if (d < bd) bd = d, best = k;
    }
    if (best == SIZE_MAX) return 0;
    double ex = r->x[best + 1] - r->x[best], ey = r->y[best + 1] - r->y[best], l = hypot(ex, ey);
    if (!(l > 0)) return 0;
    *dx = ex / l, *dy = ey / l;
    /* at a vertex the street's direction there: the mean of the two
     * segments' (a closed record's first point: its last segment and its
     * first), not the first segment found, which gave an arm at a
     * roundabout's first point its give-way line 0.5 m nearer the ring
     * than an arm at another vertex (until 6 December 2026) */
    size_t nx = SIZE_MAX, m = r->n - 1; /* the other segment there; m segments */
    int closed = r->n > 3 && r->x[0] == r->x[m] && r->y[0] == r->y[m];
    if (s == r->s[best + 1]) /* at its end: the next one (past a closed record's last, its first) */
        for (size_t q = 1; q < m && nx == SIZE_MAX; q++) {
            size_t k = best + q < m ? best + q : closed && best + 1 == m ? best + q - m : SIZE_MAX;
            if (k == SIZE_MAX) break;
            if (r->s[k + 1] > r->s[k]) nx = k;
        }
    else if (s == r->s[best] && best == 0 && closed) /* at the record's first point: its last one */
        for (size_t k = m; k-- > 1 && nx == SIZE_MAX;)
            if (r->s[k + 1] > r->s[k]) nx = k;
    if (nx != SIZE_MAX && nx != best) {
        double fx = r->x[nx + 1] - r->x[nx], fy = r->y[nx + 1] - r->y[nx], fl = hypot(fx, fy);
        double mx = *dx + fx / fl, my = *dy + fy / fl, ml = hypot(mx, my);
        if (fl > 0 && ml > 1e-9) *dx = mx / ml, *dy = my / ml;
    }
    return 1;
}

static int in_junction(const ctxa *A, size_t road, double lo, double hi)
{
    if (A->jstart) {
        for (uint32_t k = A->jstart[road]; k < A->jstart[road + 1]; k++) {
            const jn *J = jn_at(A, A->jidx[k]);
            if (hi > J->s - J->half && lo < J->s + J->half) return 1;
        }
        return 0;
    }
    for (size_t i = 0; i < A->nj; i++) {
        const jn *J = jn_at(A, i);
        if (J->road == road && hi > J->s - J->half && lo < J->s + J->half) return 1;
    }
    return 0;
}

/* Road j is a ring of its own (its first point is its last): it passes
 * through its seam, even where the network left the seam a corner. */
static int ring_record(const ctxa *A, size_t j)
{
    const rs__road_local *b = &A->rl[j];
    return b->n > 2 && b->x[0] == b->x[b->n - 1] && b->y[0] == b->y[b->n - 1];
}

/* Road j's street is a ring (passes through every point of it). */
static int ring_street(const ctxa *A, size_t j)
{
    const rs_network *N = A->net;
    uint32_t k = N->stroke_of[j];
    return N->closed[k] || (N->stroke_start[k + 1] - N->stroke_start[k] == 1 && ring_record(A, j));
}

/* Road r's arc length s along its stroke. */
static double stroke_s(const ctxa *A, size_t r, double s)
{
    const rs_network *N = A->net;
    return N->rev[r] ? N->s_off[r] - s : N->s_off[r] + s;
}

/* Does road r's street run on more than hb both ways from its arc length
 * s (a ring always does)? Measured from r along its neighbours, not from
 * the stroke's start, so that a change of the street far away (its start
 * moved, a record gone) leaves the answer as it was: a proportional
 * update takes a record whose place in its stroke changed as unchanged
 * when it draws no lines (lib/scene/grid_patch.c place_change). */
static int street_passes(const ctxa *A, size_t r, double s, double hb)
{
    if (ring_street(A, r)) return 1;
    const rs_network *N = A->net;
    double len = N->length[r], x = N->rev[r] ? len - s : s; /* (along the stroke from r's start in it) */
    double d = x;
    size_t steps = 0;
    for (uint32_t q = N->prev[r]; d <= hb && q != UINT32_MAX && steps <= N->nroads; q = N->prev[q], steps++)
        d += N->length[q];
    if (!(d > hb)) return 0;
    d = len - x;
    steps = 0;
    for (uint32_t q = N->next[r]; d <= hb && q != UINT32_MAX && steps <= N->nroads; q = N->next[q], steps++)
        d += N->length[q];
    return d > hb;
}

static rs_result add_cut(ctxa *A, size_t road, double s0, double s1, double half);

static rs_result on_record(ctxa *A, uint32_t q, double u0, double u1, int op, double half)
{
    return op ? add_cut(A, q, u0, u1, half) : add_jn(A, q, (u0 + u1) / 2, (u1 - u0) / 2);
}

/* A junction area (op 0: centre (s0 + s1) / 2, half extent (s1 - s0) / 2)
 * or a cut of the lines (op 1, `half` across) over [s0, s1] of road's arc
 * length, on every record of its street that the span reaches, in each
 * one's own arc length (a street split near a junction has its area and
 * cuts on both records: they stopped at the split). A ring's span wraps
 * round its seam. Off a ring the records are placed from road's own
 * start along the stroke (road's span exactly its own), so that where
 * the street starts does not move them. */
static rs_result on_stroke(ctxa *A, size_t road, double s0, double s1, int op, double half)
{
    const rs_network *N = A->net;
    uint32_t k = N->stroke_of[road];
    double L = A->slen[k];
    int wraps = ring_street(A, road) && L > 0;
    if (!wraps) {
        double len = N->length[road], xa = N->rev[road] ? len - s0 : s0, xb = N->rev[road] ? len - s1 : s1;
        double lo = xa < xb ? xa : xb, hi = xa < xb ? xb : xa;
        /* back from road (road itself first), then on from its next;
         * q0: where record q starts along the stroke, from road's start */
        for (int way = 0; way < 2; way++) {
            double q0 = way ? len : 0;
            size_t steps = 0;
            for (uint32_t q = way ? N->next[road] : (uint32_t)road; q != UINT32_MAX && steps <= N->nroads;
                 steps++) {
                double ql = N->length[q];
                if (!way && q != road) q0 -= ql;
                double q1 = q0 + ql;
                if (way ? q0 > hi : q1 < lo) break;
                if (!(hi < q0 || lo > q1)) {
                    double u0, u1;
                    if (q == road) u0 = s0 < s1 ? s0 : s1, u1 = s0 < s1 ? s1 : s0;
                    else u0 = N->rev[q] ? q1 - hi : lo - q0, u1 = N->rev[q] ? q1 - lo : hi - q0;
                    rs_result r = on_record(A, q, u0, u1, op, half);
                    if (r) return r;
                }
                if (way) q0 = q1;
                q = way ? N->next[q] : N->prev[q];
            }
        }
        return RS_OK;
    }
    double a = stroke_s(A, road, s0), b = stroke_s(A, road, s1);
    if (a > b) { double t = a; a = b; b = t; }
    for (int turn = -1; turn <= 1; turn++) {
        double lo = a + turn * L, hi = b + turn * L;
        if (turn && (hi < 0 || lo > L)) continue;
        /* from the road (a wrapped span: from the stroke's last or first
         * record) back while records end at or after lo, on while they
         * start at or before hi (the records' spans follow each other) */
        uint32_t from = turn == 0 ? (uint32_t)road
                        : turn > 0 ? N->stroke_roads[N->stroke_start[k + 1] - 1] : N->stroke_roads[N->stroke_start[k]];
        for (int way = 0; way < 2; way++)
            for (uint32_t q = way ? N->next[from] : from, steps = 0; q != UINT32_MAX && steps <= N->nroads;
                 q = way ? N->next[q] : N->prev[q], steps++) {
                double ql = N->length[q], q0 = N->rev[q] ? N->s_off[q] - ql : N->s_off[q], q1 = q0 + ql;
                if (way ? q0 > hi : q1 < lo) break;
                if (hi < q0 || lo > q1) continue;
                double u0 = N->rev[q] ? N->s_off[q] - hi : lo - N->s_off[q];
                double u1 = N->rev[q] ? N->s_off[q] - lo : hi - N->s_off[q];
                rs_result r = on_record(A, q, u0, u1, op, half);
                if (r) return r;
            }
    }
    return RS_OK;
}

/* Index the junctions by road (in_junction then reads one road's). Out of
 * memory leaves the scan over all. */
static rs_result index_junctions(ctxa *A, size_t nr)
{
    if (A->nj >= UINT32_MAX) return RS_OK;
    A->jstart = rs__calloc(A->ctx, nr + 2, sizeof *A->jstart);
    A->jidx = rs__alloc_array(A->ctx, A->nj ? A->nj : 1, sizeof *A->jidx);
    if (!A->jstart || !A->jidx) {
        rs__free(A->ctx, A->jstart);
        rs__free(A->ctx, A->jidx);
        A->jstart = A->jidx = NULL;
        return RS_OK;
    }
    /* (3 x 10^6 junction areas at 10^5 roads: ~40 ms, polled) */
    for (size_t i = 0; i < A->nj; i++) {
        if ((i & 65535) == 65535 && rs__poll(A->ctx)) return RS_ERR_CANCELLED;
        A->jstart[jn_at(A, i)->road + 2]++;
    }
    for (size_t i = 0; i < nr; i++) A->jstart[i + 2] += A->jstart[i + 1];
    for (size_t i = 0; i < A->nj; i++) {
        if ((i & 65535) == 65535 && rs__poll(A->ctx)) return RS_ERR_CANCELLED;
        A->jidx[A->jstart[jn_at(A, i)->road + 1]++] = (uint32_t)i;
    }
    return RS_OK;
}

/* The grid cell range of [a, b] along one axis (clamped to the grid; ic:
 * the inverse cell size. The cells only narrow the candidates, and a
 * monotone map keeps a point's cell within the range of every interval
 * holding it). */
static void cell_range(double a, double b, double o, double ic, size_t g, size_t *lo, size_t *hi)
{
    double qa = (a - o) * ic, qb = (b - o) * ic;
    *lo = qa > 0 ? (qa < (double)g ? (size_t)qa : g - 1) : 0;
    *hi = qb > 0 ? (qb < (double)g ? (size_t)qb : g - 1) : 0;
}

/* Build the cells of the roads with two or more points. Returns 0 (no
 * grid: scan every road) when a point is not finite, the segments cover
 * too many cells, or memory runs out. */
static int road_cells_build(const ctxa *A, size_t nr, road_cells *G)
{
    memset(G, 0, sizeof *G);
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    size_t m = 0, nseg = 0;
    double wsum = 0;
    for (size_t j = 0; j < nr; j++) {
        const rs__road_local *rl = &A->rl[j];
        if (rl->n < 2) continue;
        for (size_t k = 0; k < rl->n; k++)
            if (!isfinite(rl->x[k]) || !isfinite(rl->y[k])) return 0;
        const double *b = A->box + 4 * j;
        x0 = fmin(x0, b[0]), y0 = fmin(y0, b[1]), x1 = fmax(x1, b[2]), y1 = fmax(y1, b[3]);
        m++;
        nseg += rl->n - 1;
        double w = 0;
        rs_roads_get(A->roads, j, NULL, &w, NULL, NULL);
        wsum += fmin(w, 1e6);
    }
    if (m < 64 || nr >= UINT32_MAX) return 0; /* (few roads: the scan is as fast) */
    size_t g = 1;
    while (g * g < nseg && g < 2048) g++;
    /* cells no smaller than four mean reaches: smaller ones list every
     * segment in dozens of cells (10^5 city roads: 0.2 s). A query reads
     * its point's cell only and keeps what passes the exact tests, in road
     * order, so the cell size changes the work, never the result. */
    double mreach = wsum / (double)m / 2 + JUNCTION_TOL, side = fmax(x1 - x0, y1 - y0);
    if (mreach > 0 && side / (double)g < 4 * mreach) {
        double q = ceil(side / (4 * mreach));
        g = q < 1 ? 1 : q < (double)g ? (size_t)q : g;
    }
    G->gx = G->gy = g;
    G->x0 = x0, G->y0 = y0;
    G->cw = (x1 - x0) / (double)g, G->ch = (y1 - y0) / (double)g;
    if (!(G->cw > 0) || !(G->ch > 0) || !isfinite(G->cw) || !isfinite(G->ch)) return 0;
    G->icw = 1 / G->cw, G->ich = 1 / G->ch;
    G->start = rs__calloc(A->ctx, g * g + 1, sizeof *G->start);
    uint32_t *last = rs__alloc_array(A->ctx, g * g, sizeof *last); /* the last road listed per cell */
    size_t total = 0;
    int ok = G->start && last;
    for (int fill = 0; fill < 2 && ok; fill++) {
        for (size_t c = 0; c < g * g; c++) last[c] = UINT32_MAX;
        for (size_t j = 0; j < nr && ok; j++) {
            /* (polls only: a stop is seen by the caller's next tick) */
            if ((j & 4095) == 4095) (void)rs__poll(A->ctx);
            const rs__road_local *rl = &A->rl[j];
            if (rl->n < 2) continue;
            double w = 0;
            rs_roads_get(A->roads, j, NULL, &w, NULL, NULL);
            /* (grown a little more: the distance test's rounding must not
             * find a road its cell does not list) */
            double reach = (w / 2 + JUNCTION_TOL) * (1 + 1e-9) + 1e-6;
            for (size_t k = 0; k + 1 < rl->n && ok; k++) {
                size_t cx0, cx1, cy0, cy1;
                cell_range(fmin(rl->x[k], rl->x[k + 1]) - reach, fmax(rl->x[k], rl->x[k + 1]) + reach, G->x0, G->icw, g,
                           &cx0, &cx1);
                cell_range(fmin(rl->y[k], rl->y[k + 1]) - reach, fmax(rl->y[k], rl->y[k + 1]) + reach, G->y0, G->ich, g,
                           &cy0, &cy1);
                for (size_t cy = cy0; cy <= cy1 && ok; cy++)
                    for (size_t cx = cx0; cx <= cx1; cx++) {
                        size_t c = cy * g + cx;
                        if (last[c] == (uint32_t)j) continue;
                        last[c] = (uint32_t)j;
                        if (fill) {
                            G->ids[G->start[c]++] = (uint32_t)j;
                        } else {
                            G->start[c + 1]++;
                            if (++total > 64 * nseg + (1u << 20)) ok = 0; /* (huge segments over everything: scan) */
                        }
                    }
            }
        }
        if (!fill && ok) {
            for (size_t c = 0; c < g * g; c++) G->start[c + 1] += G->start[c];
            G->ids = rs__alloc_array(A->ctx, total ? total : 1, sizeof *G->ids);
            ok = G->ids != NULL;
        }
    }
    rs__free(A->ctx, last);
    if (!ok) {
        rs__free(A->ctx, G->start);
        rs__free(A->ctx, G->ids);
        G->start = G->ids = NULL;
        return 0;
    }
    /* (the fill ran each cell's start to its end: step back) */
    for (size_t c = g * g; c > 0; c--) G->start[c] = G->start[c - 1];
    G->start[0] = 0;
    return 1;
}

/* A placement may reach d metres past end e of `road` into the record
 * that goes on there (OSM splits a street anywhere: an arrow 6 m before a
 * junction must not vanish because the way was split 8 m before it),
 * unless that runs past the other record too or into its junction areas.
 * The paint extends the end segment (lib/scene/markings.c), which is the other
 * record's own line on a straight split. */
static int spill_ok(const ctxa *A, size_t road, int e, double d)
{
    size_t c = A->cont ? A->cont[2 * road + e] : 0;
    if (!c) return 0;
    const rs__road_local *o = &A->rl[c - 1];
    double len = o->s[o->n - 1];
    if (!(d <= len)) return 0;
    return A->cont_end[2 * road + e] ? !in_junction(A, c - 1, len - d, len) : !in_junction(A, c - 1, 0, d);
}

/* Push p unless it spills off its road (and the record going on there) or
 * into a junction area. */
static rs_result offer(const ctxa *A, rs__placement *p, rs__placement **pl, size_t *n, size_t *cap)
{
    rs__placement q = *p;
    /* a centre past the record's end is on the record going on there
     * (OSM splits a street anywhere): placed on that one, turned with it
     * when it runs the other way (the paint draws a placement from the
     * stretch of its own record around its centre); a few records at most */
    for (int hop = 0;; hop++) {
        const rs__road_local *r = &A->rl[q.road];
        if (r->n < 2) return RS_OK;
        double total = r->s[r->n - 1];
        if (q.s >= 0 && q.s <= total) {
            /* (measured: rs__markings place drops the others) */
            if (!(q.s + q.length <= RS__ARC_MEASURED)) return RS_OK;
            break;
        }
        int e = q.s > total;
        size_t c = A->cont[2 * q.road + e];
        if (!c || hop == 16) return RS_OK;
        const rs__road_local *o = &A->rl[c - 1];
        if (o->n < 2) return RS_OK;
        double d = e ? q.s - total : -q.s, len = o->s[o->n - 1];
        int same = A->cont_end[2 * q.road + e] != e; /* its end meets our start, or its start our end */
        q.road = c - 1;
        q.s = same ? (e ? d : len - d) : (e ? len - d : d);
        if (!same) {
            q.t = -q.t;
            q.flip = !q.flip;
        }
    }
    const rs__road_local *r = &A->rl[q.road];
    double w, total = r->s[r->n - 1], lo = q.s - q.length / 2, hi = q.s + q.length / 2;
    rs_roads_get(A->roads, q.road, NULL, &w, NULL, NULL);
    if (fabs(q.t) + q.width / 2 > w / 2 + 1e-9) return RS_OK;
    if (lo < 0 && !spill_ok(A, q.road, 0, -lo)) return RS_OK;
    if (hi > total && !spill_ok(A, q.road, 1, hi - total)) return RS_OK;
    if (in_junction(A, q.road, lo, hi)) return RS_OK;
    return rs__placement_push(A->ctx, pl, n, cap, &q);
}

/* The lane and centre lines of `road` stop over s in [s0, s1] within
 * `half` of its centre line: one rectangle per segment the range meets,
 * none past the road's ends (the line symbols apply a stroke's cuts to all
 * its records, docs/network.md: a cut reaching past this record's end
 * would cut the lines of the record that continues it). */
static rs_result add_cut(ctxa *A, size_t road, double s0, double s1, double half)
{
    if (!A->want_cuts || !(half > 0)) return RS_OK;
    /* (no cut where no mark can be placed: rs__markings place) */
    if (!(fabs(s0) <= RS__ARC_MEASURED && fabs(s1) <= RS__ARC_MEASURED)) return RS_OK;
    const rs__road_local *r = &A->rl[road];
    for (size_t k = 0; k + 1 < r->n; k++) {
        double len = r->s[k + 1] - r->s[k], u0 = s0 - r->s[k], u1 = s1 - r->s[k];
        if (!(len > 0) || !(r->s[k] <= RS__ARC_MEASURED)) continue;
        if (u0 < 0) u0 = 0;
        if (u1 > len) u1 = len;
        if (!(u1 > u0)) continue;
        void *arr = A->cuts;
        rs_result g = room_for_one(A->ctx, &arr, A->ncut, &A->capcut, sizeof *A->cuts, 16);
        if (g) return g;
        A->cuts = arr;
        double dx = r->x[k + 1] - r->x[k], dy = r->y[k + 1] - r->y[k], d = hypot(dx, dy);
        rs__line_cut *c = &A->cuts[A->ncut++];
        c->road = (uint32_t)road;
        c->ax = r->x[k];
        c->ay = r->y[k];
        c->ux = dx / d;
        c->uy = dy / d;
        c->u0 = u0;
        c->u1 = u1;
        c->r = half;
    }
    return RS_OK;
}

/* Half the width the cuts take: clear of the outer lanes' edges, where the
 * edge lines lie. */
#define CUT_EDGE_CLEAR 0.3

static double cut_half(const rs_road_lanes *L)
{
    double a = L->lane[0].t_left, b = -L->lane[L->count - 1].t_right;
    return (a < b ? a : b) - CUT_EDGE_CLEAR;
}

/* RS_TURN_* flags to an arrow type name, or NULL (none). Left-hand
 * traffic turns back to the right. */
static const char *arrow_for(uint32_t f, int left_hand)
{
    int left = !!(f & RS_TURN_LEFT), right = !!(f & RS_TURN_RIGHT), through = !!(f & RS_TURN_THROUGH);
    if (f & RS_TURN_REVERSE) return left_hand ? "arrow_uturn_right" : "arrow_uturn";
    if (through && left && !right) return "arrow_straight_left";
    if (through && right && !left) return "arrow_straight_right";
    if (through && !left && !right) return "arrow_straight";
    if (left && !right && !through) return "arrow_left";
    if (right && !left && !through) return "arrow_right";
    return NULL;
}

/* A placement of atlas type ti on road `road` at the type's own size
 * (s, t to be set by the caller). */
static rs__placement sprite_at(const rs_atlas *atlas, long ti, size_t road, int flip)
{
    rs__placement p;
    memset(&p, 0, sizeof p);
    p.type = (uint32_t)ti;
    p.road = road;
    p.length = atlas->t[ti].length;
    p.width = atlas->t[ti].width;
    p.flip = flip;
    return p;
}

/* Elements of atlas type ti (own size), repeated across [t0, t1] with
 * `gap` between them: as many as fit, the run centred in the span. */
static rs_result repeat_across(const ctxa *A, const rs_atlas *atlas, long ti, size_t road, int flip, double s,
                               double t0, double t1, double gap, rs__placement **pl, size_t *n, size_t *cap)
{
    rs__placement p = sprite_at(atlas, ti, road, flip);
    double span = t1 - t0, period = p.width + gap;
    if (!(span >= p.width) || !(period > 0)) return RS_OK;
    double fm = floor((span + gap) / period + 1e-9);
    /* A row of more than 4096 elements is no real road (a 2 km zebra);
     * it also keeps the cast below in range for any width. */
    if (!(fm <= 4096)) return RS_OK;
    size_t m = (size_t)fm;
    double run = (double)m * period - gap, start = t0 + (span - run) / 2;
    p.s = s;
    for (size_t k = 0; k < m; k++) {
        p.t = start + k * period + p.width / 2;
        if (offer(A, &p, pl, n, cap)) return RS_ERR_NOMEM;
    }
    return RS_OK;
}

/* Standard sizes (docs/road-format.md "Marking elements"). */
#define RMS_BLOCK_GAP 0.25   /* Wartelinie: 0.50 m blocks, 0.25 m gaps */
#define MUTCD_TOOTH_GAP 0.1524 /* 3B.16: 6 in between 18 in teeth */
#define ZEBRA_GAP 0.5        /* Fussgaengerueberweg: 0.50 m bars, 0.50 m gaps */
#define ZEBRA_MARGIN 0.2     /* zebra bars stay this far inside the road edges */

/* The lines, arrows and stop or give-way line of one approach. */
static rs_result place_approach(ctxa *A, const rs_atlas *atlas, const approach *ap, rs__placement **pl, size_t *n,
                                size_t *cap)
{
    size_t i = ap->road;
    const rs__road_local *r = &A->rl[i];
    if (r->n < 2) return RS_OK;
    rs_road_lanes L;
    rs_road_lanes_get(A->roads, i, A->so, &L);
    const double hw = L.width / 2;
    const int left_hand = L.side == RS_DRIVING_LEFT, us = A->so && A->so->profile == RS_PROFILE_MUTCD;
    const char *ctrl = rs_roads_get_attr(A->roads, i, "control");
    {
        /* traffic arriving with the points (at a road's last point) has the
         * lanes of direction +1, flip 0 */
        int arrive = ap->arrive, flip = arrive < 0;
        /* the approach: its lanes, out to the kerb on the outer side and to
         * the centre line on the inner side */
        double t0 = INFINITY, t1 = -INFINITY;
        for (uint32_t k = 0; k < L.count; k++) {
            const rs_lane *ln = &L.lane[k];
            double a = ln->t_right, b = ln->t_left;
            if (ln->direction == 0) { /* one lane both ways: its approach half */
                int plus = (arrive > 0) == left_hand;
                a = plus ? 0 : -hw;
                b = plus ? hw : 0;
            } else if (ln->direction != arrive) continue;
            else {
                if (k == 0) b = hw;
                if (k + 1 == L.count) a = -hw;
            }
            if (a < t0) t0 = a;
            if (b > t1) t1 = b;
        }
        if (!(t1 > t0)) return RS_OK; /* a one-way road leaving here */
        /* the junction area's near side; at an oblique junction the stop or
         * give-way line and the arrows stand back until the line's corner
         * clears the streets the approach gives way to */
        double need = fmax(yield_at(ap, hw, t0), yield_at(ap, hw, t1));
        double edge = ap->s - arrive * (need > ap->half + 1e-9 ? need : ap->half);
        double dir = -arrive;                    /* away from the junction */
        if (ap->minor) {
            size_t before = *n;
            double lead = 0; /* the line's extent along the road */
            int stop = ctrl && !strcmp(ctrl, "stop");
            long ti = rs_atlas_find(atlas, stop ? "stop_line" : us ? "yield_tooth" : "give_way_block");
            if (ti >= 0 && !stop) {
                /* repeated at its standard size, never stretched */
                double len = atlas->t[ti].length, s = edge + dir * (LINE_GAP + len / 2);
                lead = len;
                if (repeat_across(A, atlas, ti, i, flip, s, t0, t1, us ? MUTCD_TOOTH_GAP : RMS_BLOCK_GAP, pl, n, cap))
                    return RS_ERR_NOMEM;
            } else {
                /* a stop line, or an atlas without the elements: one line across */
                if (ti < 0) ti = rs_atlas_find(atlas, stop ? "stop_line" : "give_way_line");
                if (ti >= 0) {
                    rs__placement p = sprite_at(atlas, ti, i, flip);
                    p.width = t1 - t0;
                    p.s = edge + dir * (LINE_GAP + p.length / 2);
                    p.t = (t0 + t1) / 2;
                    lead = p.length;
                    if (offer(A, &p, pl, n, cap)) return RS_ERR_NOMEM;
                }
            }
            /* the lane and centre lines end at the line's far side from the
             * junction and do not run on into it */
            if (*n > before) {
                /* (past a free end: over the other road too) */
                double near = edge + dir * (LINE_GAP + lead), reach = ap->end ? ap->half + L.width : 0;
                if (on_stroke(A, i, arrive > 0 ? near : ap->s - reach, arrive > 0 ? ap->s + reach : near, 1,
                              cut_half(&L)))
                    return RS_ERR_NOMEM;
            }
        }
        /* turn arrows, centred in their lanes */
        for (uint32_t k = 0; k < L.count && ap->arrows; k++) {
            const rs_lane *ln = &L.lane[k];
            if (ln->direction != arrive || !ln->turn) continue;
            const char *type = arrow_for(ln->turn, left_hand);
            long ti = type ? rs_atlas_find(atlas, type) : -1;
            if (ti < 0) continue;
            double lw = ln->t_left - ln->t_right;
            rs__placement p = sprite_at(atlas, ti, i, flip);
            if (p.width > 0.8 * lw) {
                p.length *= 0.8 * lw / p.width;
                p.width = 0.8 * lw;
            }
            p.s = edge + dir * (ARROW_GAP + p.length / 2);
            p.t = (ln->t_left + ln->t_right) / 2;
            if (offer(A, &p, pl, n, cap)) return RS_ERR_NOMEM;
        }
    }
    return RS_OK;
}

int rs__markings_auto_possible(const rs_roads *roads)
{
    size_t nr = rs_roads_count(roads);
    for (size_t i = 0; i < nr; i++)
        if (rs_roads_get_attr(roads, i, "turn:lanes") || rs_roads_get_attr(roads, i, "turn:lanes:forward") ||
            rs_roads_get_attr(roads, i, "turn:lanes:backward"))
            return 1;
    for (size_t k = 0; k < rs_roads_point_attr_count(roads); k++) {
        const char *key, *v;
        rs_roads_point_attr_at(roads, k, NULL, NULL, &key, &v);
        if (!strcmp(key, "crossing") && !strcmp(v, "zebra")) return 1;
    }
    /* stop lines need a road with a class */
    for (size_t i = 0; i < nr; i++) {
        if (rs__road_priority(roads, i) > 0) return 1;
    }
    return 0;
}

static int approach_cmp(const void *pa, const void *pb)
{
    const approach *a = pa, *b = pb;
    if (a->road != b->road) return a->road < b->road ? -1 : 1;
    if (a->s != b->s) return a->s < b->s ? -1 : 1;
    if (a->arrive != b->arrive) return a->arrive < b->arrive ? -1 : 1;
    if (a->half != b->half) return a->half < b->half ? -1 : 1;
    if (a->minor != b->minor) return a->minor < b->minor ? -1 : 1;
    if (a->arrows != b->arrows) return a->arrows < b->arrows ? -1 : 1;
    return (int)a->end - (int)b->end;
}

/* ap[0 .. n) in approach_cmp's order (*ap replaced), polling as it goes. */
static rs_result sort_approaches(rs_ctx *ctx, approach **ap, size_t n, size_t nr)
{
    size_t *start = rs__calloc(ctx, nr + 2, sizeof *start);
    approach *out = rs__alloc_array(ctx, n, sizeof *out);
    if (!start || !out) {
        rs__free(ctx, start);
        rs__free(ctx, out);
        return RS_ERR_NOMEM;
    }
    const approach *in = *ap;
    rs_result r = RS_OK;
    for (size_t k = 0; k < n; k++) start[in[k].road + 2]++;
    for (size_t i = 0; i < nr; i++) start[i + 2] += start[i + 1];
    for (size_t k = 0; k < n && !r; k++) {
        /* (every 4096: the writes land at random places in fresh pages,
         * 65536 of them took up to 53 ms at 10^5 roads) */
        if ((k & 4095) == 4095 && rs__poll(ctx)) r = RS_ERR_CANCELLED;
        out[start[in[k].road + 1]++] = in[k];
    }
    for (size_t i = 0; i < nr && !r; i++) {
        if ((i & 4095) == 4095 && rs__poll(ctx)) r = RS_ERR_CANCELLED;
        approach *a = out + start[i];
        size_t m = start[i + 1] - start[i];
        for (size_t x = 1; x < m; x++) /* (insertion: a road has a few) */
            for (size_t y = x; y > 0 && approach_cmp(&a[y - 1], &a[y]) > 0; y--) {
                approach t = a[y];
                a[y] = a[y - 1];
                a[y - 1] = t;
            }
    }
    rs__free(ctx, start);
    rs__free(ctx, *ap);
    *ap = out;
    return r;
}

static rs_result auto_core(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_atlas *atlas,
                           const rs_style_options *so, const rs_network *net_in, rs__line_cut **cuts, size_t *ncut,
                           rs__placement **pl, size_t *n, size_t *cap)
{
    size_t nr = rs_roads_count(roads);
    if (!rs__markings_auto_possible(roads)) return RS_OK;
    ctxa A;
    memset(&A, 0, sizeof A);
    A.ctx = ctx;
    A.roads = roads;
    A.so = so;
    A.want_cuts = cuts != NULL;
    double *rl_block = NULL;
    rs_result r = rs__road_local_all(ctx, roads, dem, &A.rl, &rl_block);
    if (r == RS_ERR_NOMEM) return rs__fail(ctx, r, "out of memory placing markings");
    if (r) return r;
    A.box = rs__alloc_array(ctx, nr ? nr : 1, 4 * sizeof(double));
    if (!A.box) r = RS_ERR_NOMEM;
    for (size_t i = 0; i < nr && !r; i++) {
        double *b = A.box + 4 * i;
        b[0] = A.rl[i].x0, b[1] = A.rl[i].y0, b[2] = A.rl[i].x1, b[3] = A.rl[i].y1;
    }
    road_cells G;
    if (!r && rs__poll(ctx)) r = RS_ERR_CANCELLED;
    int grid = !r && road_cells_build(&A, nr, &G);
    /* which records are one street (docs/network.md "Strokes"): the
     * caller's network, else one of our own */
    rs_network *own = NULL;
    const rs_network *net = net_in && rs_network_road_count(net_in) == nr ? net_in : NULL;
    if (!r && !net && (r = rs_network_build(ctx, roads, NULL, &own)) == RS_OK) net = own;
    A.net = r ? NULL : net;
    A.cont = r ? NULL : rs__calloc(ctx, 2 * (nr ? nr : 1), sizeof *A.cont);
    A.cont_end = r || !A.cont ? NULL : rs__calloc(ctx, 2 * (nr ? nr : 1), 1);
    A.slen = r ? NULL : rs__calloc(ctx, net->nstrokes ? net->nstrokes : 1, sizeof *A.slen);
    if (!r && (!A.cont || !A.cont_end || !A.slen)) r = RS_ERR_NOMEM;
    for (size_t i = 0; i < nr && !r; i++) {
        /* the record going on from each end (the network's link: the same
         * street split into records, turning less than 30 degrees) */
        for (int e = 0; e < 2; e++) {
            uint32_t lk = net->link[2 * i + e];
            if (lk == UINT32_MAX) continue;
            A.cont[2 * i + e] = lk / 2 + 1;
            A.cont_end[2 * i + e] = (uint8_t)(lk & 1);
        }
        double hi = net->rev[i] ? net->s_off[i] : net->s_off[i] + net->length[i];
        if (hi > A.slen[net->stroke_of[i]]) A.slen[net->stroke_of[i]] = hi;
    }
    /* per road end: its node (NONE: none); per stroke: its free ends'
     * points (local; NaN: none) */
    uint32_t *endnode = r ? NULL : rs__alloc_array(ctx, 2 * (nr ? nr : 1), sizeof *endnode);
    double *sends = r ? NULL : rs__alloc_array(ctx, net->nstrokes ? net->nstrokes : 1, 4 * sizeof *sends);
    if (!r && (!endnode || !sends)) r = RS_ERR_NOMEM;
    for (size_t k = 0; !r && k < 2 * nr; k++) endnode[k] = UINT32_MAX;
    for (size_t nd = 0; !r && nd < net->nnodes; nd++)
        for (uint32_t k = net->leg_start[nd]; k < net->leg_start[nd + 1]; k++) {
            const rs_network_leg *L = &net->leg[k];
            if (rs__is_end_leg(L)) endnode[rs__leg_end(L)] = (uint32_t)nd;
        }
    for (size_t k = 0; !r && k < net->nstrokes; k++) {
        double *q = sends + 4 * k;
        q[0] = q[1] = q[2] = q[3] = NAN;
        if (net->closed[k]) continue;
        for (int side = 0; side < 2; side++) {
            uint32_t rr = net->stroke_roads[side ? net->stroke_start[k + 1] - 1 : net->stroke_start[k]];
            const rs__road_local *b = &A.rl[rr];
            if (b->n < 1) continue;
            /* the stroke's start is its first record's start (its end when reversed) */
            size_t pi = (side != 0) != (net->rev[rr] != 0) ? b->n - 1 : 0;
            q[2 * side] = b->x[pi], q[2 * side + 1] = b->y[pi];
        }
    }
    approach *ap = NULL;
    size_t nap = 0, capap = 0;
    struct met {
        size_t road;
        double d, s;
        int out; /* not the street's nearest record, or a street that only ends here */
    } *mt = NULL;
    size_t nmt = 0, capmt = 0;
    /* Free ends of streets: an end of road A within B's half width (+ 0.5 m)
     * of B's centreline is a junction when a street passes through there
     * or two or more streets meet it; one other street ending there is
     * that street going on at a corner. Each street met counts once, at the
     * nearest point of its records, and its extent is the street's (a
     * street split near the junction had the area end at the split). */
    for (size_t i = 0; i < nr && !r; i++) {
        const rs__road_local *a = &A.rl[i];
        if (rs__tick(ctx, 1)) {
            r = RS_ERR_CANCELLED;
            break;
        }
        if (a->n < 2) continue;
        double wa;
        rs_road_info ia;
        rs_roads_get(roads, i, NULL, &wa, NULL, NULL);
        rs_roads_get_info(roads, i, &ia);
        if (rs__class_non_car(ia.road_class)) continue; /* no car markings (docs/road-format.md) */
        uint32_t si = net->stroke_of[i];
        int lvi = INT_MIN; /* (its level: read when a street is near) */
        for (int e = 0; e < 2 && !r; e++) {
            /* a record end its street goes on from: only streets crossing
             * it there that the network did not join (no shared point,
             * no leg at its node; a side road split before it reaches the
             * street it ends on meets that one at its free end) */
            int linked = net->link[2 * i + e] != UINT32_MAX;
            uint32_t nd = endnode[2 * i + e];
            size_t pi = e ? a->n - 1 : 0;
            double x = a->x[pi], y = a->y[pi], se = e ? a->s[a->n - 1] : 0;
            const uint32_t *cand = NULL;
            size_t ncand = nr;
            if (grid && isfinite(x) && isfinite(y)) { /* (x, y) is inside every box it could meet: its cell lists them */
                size_t cx, cy, unused;
                cell_range(x, x, G.x0, G.icw, G.gx, &cx, &unused);
                cell_range(y, y, G.y0, G.ich, G.gy, &cy, &unused);
                cand = G.ids + G.start[cy * G.gx + cx];
                ncand = G.start[cy * G.gx + cx + 1] - G.start[cy * G.gx + cx];
            }
            nmt = 0;
            for (size_t c = 0; c < ncand; c++) {
                size_t j = cand ? cand[c] : c;
                /* (the street's own records are no junction) */
                if (j == i || A.rl[j].n < 2 || net->stroke_of[j] == si || rs__road_non_car(roads, j)) continue;
                double wb, s = 0;
                rs_roads_get(roads, j, NULL, &wb, NULL, NULL);
                const double *b = A.box + 4 * j, reach = wb / 2 + JUNCTION_TOL;
                if (x < b[0] - reach || x > b[2] + reach || y < b[1] - reach || y > b[3] + reach) continue;
                double d = nearest_within(&A.rl[j], x, y, reach, &s);
                if (d > reach) continue;
                /* (a street on another level, a bridge over the end: no junction) */
                if (lvi == INT_MIN) lvi = rs__road_level(roads, i);
                if (rs__road_level(roads, j) != lvi) continue;
                if (linked) {
                    int joined = 0;
                    for (uint32_t k = nd == UINT32_MAX ? 0 : net->leg_start[nd]; nd != UINT32_MAX && k < net->leg_start[nd + 1]; k++)
                        joined |= net->stroke_of[net->leg[k].road] == net->stroke_of[j];
                    const double *fe = sends + 4 * si;
                    double unused_s;
                    for (int side = 0; side < 2 && !joined; side++)
                        joined = !isnan(fe[2 * side]) &&
                                 nearest_within(&A.rl[j], fe[2 * side], fe[2 * side + 1], reach, &unused_s) <= reach;
                    if (joined) continue;
                }
                void *arr = mt;
                if ((r = room_for_one(ctx, &arr, nmt, &capmt, sizeof *mt, 16)) != RS_OK) break;
                mt = arr;
                mt[nmt].road = j, mt[nmt].d = d, mt[nmt].s = s, mt[nmt].out = 0;
                nmt++;
            }
            /* per street met, its nearest record (the first of equals) */
            size_t meet = 0;
            int through = 0;
            double hb = wa / 2 + JUNCTION_TOL;
            for (size_t c = 0; c < nmt && !r; c++) {
                uint32_t k = net->stroke_of[mt[c].road];
                size_t best = c;
                for (size_t c2 = 0; c2 < nmt; c2++)
                    if (net->stroke_of[mt[c2].road] == k && (mt[c2].d < mt[best].d || (mt[c2].d == mt[best].d && c2 < best)))
                        best = c2;
                if (best != c) {
                    mt[c].out = 1;
                    continue;
                }
                int passes = street_passes(&A, mt[c].road, mt[c].s, hb);
                if (linked && !passes) {
                    mt[c].out = 1; /* (a street ending here: its own end's business) */
                    continue;
                }
                meet++;
                through |= passes;
            }
            if (r || !(through || (!linked && meet >= 2))) continue;
            /* the junction's centre on A: where A's line meets the
             * nearest street's centre line (an end inside a surface,
             * short of the centre line or past it: docs/network.md "Ends
             * inside a surface"); an end within the tolerance is on it */
            double sc = se;
            size_t near = SIZE_MAX;
            for (size_t c = 0; c < nmt; c++)
                if (!mt[c].out && (near == SIZE_MAX || mt[c].d < mt[near].d)) near = c;
            if (near != SIZE_MAX && mt[near].d > net->tol && a->n >= 2) {
                size_t p0 = e ? a->n - 2 : 1;
                double ux = x - a->x[p0], uy = y - a->y[p0], ul = hypot(ux, uy), fx, fy, unused;
                nearest_foot(&A.rl[mt[near].road], x, y, &unused, &fx, &fy);
                double d = mt[near].d, along = ul > 0 ? ((fx - x) * ux + (fy - y) * uy) / ul : 0;
                if (fabs(along) >= 0.2 * d && d > 0) { /* (at a sine below 0.2: the end itself) */
                    double t = d * d / along, lim = 0;
                    rs_roads_get(roads, mt[near].road, NULL, &lim, NULL, NULL);
                    lim = lim / 2 + JUNCTION_TOL;
                    sc = se + (e ? 1 : -1) * (t > lim ? lim : t < -lim ? -lim : t);
                }
            }
            approach q = { i, sc, 0, (int8_t)(e ? 1 : -1), 0, (uint8_t)!linked, 1, { 0, 0, 0 } };
            /* A's direction from the junction and its lateral axis there */
            double awx = 0, awy = 0;
            {
                size_t p0 = e ? a->n - 2 : 1;
                double ul = hypot(a->x[p0] - x, a->y[p0] - y);
                if (ul > 0) awx = (a->x[p0] - x) / ul, awy = (a->y[p0] - y) / ul;
            }
            double adx = e ? -awx : awx, ady = e ? -awy : awy; /* the points' direction */
            for (size_t c = 0; c < nmt && !r; c++) {
                if (mt[c].out) continue;
                size_t j = mt[c].road;
                double wb;
                rs_roads_get(roads, j, NULL, &wb, NULL, NULL);
                double ha = wb / 2 + JUNCTION_TOL;
                if (ha > q.half) q.half = ha;
                /* the lower priority gives way: class rank, priority_road,
                 * and a roundabout's ring over its arms (StVO 9a, MUTCD 2B.11) */
                if (rs__road_priority(roads, i) < rs__road_priority(roads, j)) {
                    double mx, my;
                    q.minor = 1;
                    if ((awx != 0 || awy != 0) && dir_at(&A.rl[j], mt[c].s, &mx, &my))
                        yield_add(&q, wa / 2, wb / 2, mx, my, awx, awy, ady, -adx);
                }
                r = on_stroke(&A, i, sc - ha, sc + ha, 0, 0);
                if (!r) r = on_stroke(&A, j, mt[c].s - hb, mt[c].s + hb, 0, 0);
            }
            void *arr = ap;
            if (!r) r = room_for_one(ctx, &arr, nap, &capap, sizeof *ap, 64);
            if (r) break;
            ap = arr;
            ap[nap++] = q;
        }
    }
    /* Streets passing through a node of the network where another street
     * meets them (a T on the through road, an X, a street split at a
     * junction): an approach from either side, the area as wide as the
     * widest other street there (+ 0.5 m), giving way to a higher one.
     * The whole street and the street split anywhere are the same. */
    for (size_t nd = 0; nd < net->nnodes && !r; nd++) {
        if ((nd & 4095) == 0 && rs__poll(ctx)) {
            r = RS_ERR_CANCELLED;
            break;
        }
        const rs_network_leg *lg = net->leg + net->leg_start[nd];
        uint32_t deg = net->leg_start[nd + 1] - net->leg_start[nd];
        if (deg < 3) continue;
        for (uint32_t a = 0; a < deg && !r; a++) {
            const rs_network_leg *L = &lg[a];
            if (!rs__leg_passes(net, L)) continue; /* (a free end) */
            if (A.rl[L->road].n < 2 || rs__road_non_car(roads, L->road)) continue;
            uint32_t k = net->stroke_of[L->road];
            double h = 0, wl = 0;
            int pmax = -1, first = 1;
            rs_roads_get(roads, L->road, NULL, &wl, NULL, NULL);
            int8_t arrive = (int8_t)(L->kind == RS_LEG_END || L->kind == RS_LEG_BACKWARD ? 1 : -1);
            double lwx = cos(L->angle), lwy = sin(L->angle);
            double ldx = arrive > 0 ? -lwx : lwx, ldy = arrive > 0 ? -lwy : lwy; /* the points' direction */
            approach q = { L->road, 0, 0, arrive, 0, 0, (uint8_t)rs__is_end_leg(L), { 0, 0, 0 } };
            for (uint32_t b = 0; b < deg; b++) {
                const rs_network_leg *M = &lg[b];
                if (net->stroke_of[M->road] == k) {
                    if (b < a) first = 0; /* (the street's area once a node) */
                    continue;
                }
                if (A.rl[M->road].n < 2 || rs__road_non_car(roads, M->road)) continue;
                double wb;
                rs_roads_get(roads, M->road, NULL, &wb, NULL, NULL);
                if (wb / 2 + JUNCTION_TOL > h) h = wb / 2 + JUNCTION_TOL;
                if (M->priority > pmax) pmax = M->priority;
                if (M->priority > L->priority)
                    yield_add(&q, wl / 2, wb / 2, cos(M->angle), sin(M->angle), lwx, lwy, ldy, -ldx);
            }
            if (pmax < 0) continue; /* no other street */
            const rs__road_local *rl = &A.rl[L->road];
            double total = rl->s[rl->n - 1];
            double sl = L->kind == RS_LEG_START ? 0 : L->kind == RS_LEG_END ? total : L->s < 0 ? 0 : L->s > total ? total : L->s;
            q.s = sl, q.half = h, q.minor = (uint8_t)(L->priority < pmax);
            if (first) r = on_stroke(&A, L->road, sl - h, sl + h, 0, 0);
            void *arr = ap;
            if (!r) r = room_for_one(ctx, &arr, nap, &capap, sizeof *ap, 64);
            if (r) break;
            ap = arr;
            ap[nap++] = q;
        }
    }
    rs__free(ctx, mt);
    rs__free(ctx, endnode);
    rs__free(ctx, sends);
    if (grid) {
        rs__free(ctx, G.start);
        rs__free(ctx, G.ids);
    }
    if (!r && rs__poll(ctx)) r = RS_ERR_CANCELLED;
    if (!r) r = index_junctions(&A, nr);
    if (!r && rs__poll(ctx)) r = RS_ERR_CANCELLED;
    /* placed road by road, along each (a road's ends first to last): a
     * counting sort by road, then each road's few by approach_cmp (one
     * qsort of the approaches of the 10^5-road city took 85 ms
     * without a progress call) */
    if (!r && nap > 1) r = sort_approaches(ctx, &ap, nap, nr);
    for (size_t k = 0; k < nap && !r; k++) {
        if (rs__tick(ctx, 0)) {
            r = RS_ERR_CANCELLED;
            break;
        }
        r = place_approach(&A, atlas, &ap[k], pl, n, cap);
    }
    rs__free(ctx, ap);
    if (!r && rs__poll(ctx)) r = RS_ERR_CANCELLED;
    /* zebras: bars of their standard size repeated across the road (the
     * whole `zebra` sprite stretched to the road when the atlas has no bars) */
    long zb = rs_atlas_find(atlas, "zebra_bar"), zt = rs_atlas_find(atlas, "zebra");
    for (size_t k = 0; k < rs_roads_point_attr_count(roads) && !r && (zt >= 0 || zb >= 0); k++) {
        const char *key, *v;
        size_t ri, pt;
        rs_roads_point_attr_at(roads, k, &ri, &pt, &key, &v);
        if (strcmp(key, "crossing") || strcmp(v, "zebra") || ri >= nr) continue;
        /* the point's arc length: its local position on the road */
        const double *xy;
        size_t np;
        double w;
        rs_roads_get(roads, ri, NULL, &w, &xy, &np);
        if (pt >= np) continue;
        rs__local_frame F = rs__local_frame_of(dem->frame.origin_x, dem->frame.origin_y, dem->frame.cell_size);
        double x, y, s = 0;
        rs__local_point(&F, xy, pt, &x, &y);
        nearest(&A.rl[ri], x, y, &s);
        if (zb >= 0) {
            double m = w / 2 - ZEBRA_MARGIN, len = atlas->t[zb].length;
            size_t before = *n;
            r = repeat_across(&A, atlas, zb, ri, 0, s, -m, m, ZEBRA_GAP, pl, n, cap);
            if (!r && *n > before && A.want_cuts) { /* lane lines are interrupted at the zebra */
                rs_road_lanes L;
                rs_road_lanes_get(roads, ri, so, &L);
                r = add_cut(&A, ri, s - len / 2, s + len / 2, cut_half(&L));
            }
            continue;
        }
        rs__placement p;
        memset(&p, 0, sizeof p);
        p.type = (uint32_t)zt;
        p.road = ri;
        p.s = s;
        p.length = atlas->t[zt].length;
        p.width = w - 0.4;
        if (p.width > 0) r = offer(&A, &p, pl, n, cap);
    }
    if (r == RS_ERR_NOMEM) rs__fail(ctx, r, "out of memory placing markings");
    if (cuts && !r) {
        *cuts = A.cuts;
        *ncut = A.ncut;
        A.cuts = NULL;
    }
    rs__free(ctx, A.cuts);
    rs__free(ctx, rl_block);
    rs__free(ctx, A.rl);
    rs__free(ctx, A.box);
    for (size_t k = 0; A.jc && k < (A.nj + JN_CHUNK - 1) >> JN_BITS; k++) rs__free(ctx, A.jc[k]);
    rs__free(ctx, A.jc);
    rs__free(ctx, A.cont);
    rs_network_free(ctx, own);
    rs__free(ctx, A.cont_end);
    rs__free(ctx, A.jstart);
    rs__free(ctx, A.jidx);
    rs__free(ctx, A.slen);
    (void)rs__poll(ctx); /* (a stop here is seen by the next tick) */
    return r;
}

rs_result rs__markings_auto(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_atlas *atlas,
                            const rs_style_options *so, const rs_network *net, rs__placement **pl, size_t *n,
                            size_t *cap)
{
    return auto_core(ctx, dem, roads, atlas, so, net, NULL, NULL, pl, n, cap);
}

rs_result rs__markings_auto_cuts(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_atlas *atlas,
                                 const rs_style_options *so, const rs_network *net, rs__placement **pl, size_t *n,
                                 size_t *cap, rs__line_cut **cuts, size_t *ncut)
{
    *cuts = NULL; /* (auto_core sets them on success only) */
    *ncut = 0;
    return auto_core(ctx, dem, roads, atlas, so, net, cuts, ncut, pl, n, cap);
}

/* The sizes of the built-in atlas's line and crossing types (tests/tools/
 * atlasgen.c; test_lanes checks them against rs_atlas_default): where the
 * automatic lines go depends on sizes alone, not on the sprites' pixels,
 * so the cuts need no atlas images. */
static const struct {
    const char *name;
    double length, width;
} default_sizes[] = { { "stop_line", 0.5, 3.5 },       { "give_way_line", 0.5, 3.5 }, { "give_way_block", 0.5, 0.5 },
                      { "yield_tooth", 0.6858, 0.4572 }, { "zebra_bar", 4.0, 0.5 },    { "zebra", 4.0, 6.0 } };

static rs_result sizes_atlas(rs_ctx *ctx, rs_atlas *a)
{
    size_t n = sizeof default_sizes / sizeof default_sizes[0];
    a->t = rs__calloc(ctx, n, sizeof *a->t);
    if (!a->t) return RS_ERR_NOMEM;
    for (size_t k = 0; k < n; k++) {
        memcpy(a->t[k].name, default_sizes[k].name, strlen(default_sizes[k].name) + 1);
        a->t[k].length = default_sizes[k].length;
        a->t[k].width = default_sizes[k].width;
    }
    a->n = n;
    return RS_OK;
}

rs_result rs__markings_line_cuts(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                                 const rs_network *net, rs__line_cut **out, size_t *nout)
{
    *out = NULL;
    *nout = 0;
    if (o->markings.disable || o->markings.no_auto || !rs__markings_auto_possible(roads)) return RS_OK;
    rs_atlas own;
    memset(&own, 0, sizeof own);
    const rs_atlas *atlas = o->markings.atlas;
    rs_result r = RS_OK;
    if (!atlas) {
        r = sizes_atlas(ctx, &own);
        atlas = &own;
    }
    rs__placement *pl = NULL;
    size_t n = 0, cap = 0;
    if (!r) r = auto_core(ctx, dem, roads, atlas, &o->style, net, out, nout, &pl, &n, &cap);
    rs__free(ctx, pl);
    rs__free(ctx, own.t);
    (void)rs__poll(ctx); /* (freeing the placements takes a while at 10^5 roads; the next tick sees a stop) */
    if (r == RS_ERR_NOMEM) return rs__fail(ctx, r, "out of memory placing markings");
    return r;
}

rs_result rs__auto_plan_make(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                             const rs_network *net, rs__auto_plan *plan)
{
    memset(plan, 0, sizeof *plan);
    if (o->markings.disable || o->markings.no_auto || !rs__markings_auto_possible(roads)) return RS_OK;
    /* the atlas the markings will place from (the built-in one is loaded
     * once, here, and handed on to them) */
    const rs_atlas *atlas = o->markings.atlas;
    rs_result r = rs__poll(ctx) ? RS_ERR_CANCELLED : RS_OK;
    if (!r && !atlas) {
        r = rs_atlas_default(ctx, &plan->atlas);
        atlas = plan->atlas;
    }
    if (!r)
        r = auto_core(ctx, dem, roads, atlas, &o->style, net, &plan->cuts, &plan->ncuts, &plan->pl, &plan->npl,
                      &plan->cap);
    /* the progress units of the second reader, which no longer runs the rules */
    if (!r && rs__tick(ctx, rs_roads_count(roads))) r = RS_ERR_CANCELLED;
    if (r) {
        rs__auto_plan_free(ctx, plan);
        if (r == RS_ERR_NOMEM) return rs__fail(ctx, r, "out of memory placing markings");
    }
    return r;
}

void rs__auto_plan_free(rs_ctx *ctx, rs__auto_plan *plan)
{
    if (!plan) return;
    rs_atlas_free(ctx, plan->atlas);
    rs__free(ctx, plan->pl);
    rs__free(ctx, plan->cuts);
    memset(plan, 0, sizeof *plan);
}
