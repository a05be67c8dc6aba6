/* The road network (issue 27, docs/network.md): topology and strokes that
 * do not depend on how a road is split into records, T detection at the
 * tolerance, rings, self-touching roads, degenerate records; and the drawn
 * result of a split road against the unsplit one (lines, dashes, surface
 * images), which must agree to 8/255. */
#include "roadsplat.h"
#include "harness.h"
#include "scene_splat.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;

/* ---- helpers ---- */

static uint64_t rng_state = 0x2545F4914F6CDD1Dull;
static double rnd(void) /* [0, 1) */
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

typedef struct poly {
    double xy[2 * 256];
    size_t n;
} poly;

static double poly_len(const poly *p)
{
    double s = 0;
    for (size_t k = 1; k < p->n; k++) s += hypot(p->xy[2 * k] - p->xy[2 * k - 2], p->xy[2 * k + 1] - p->xy[2 * k - 1]);
    return s;
}

/* Split polyline p at the arc lengths cut[0] < cut[1] < ... (a cut inside a
 * segment inserts the point there; at a vertex it splits there) and add the
 * pieces to roads, each with attributes attr (key=value pairs, NULL
 * ended). Returns the number of records added. */
static size_t add_split_rev(rs_roads *roads, const char *name, double width, const poly *p, const double *cut,
                            size_t ncut, const char *const *attr, unsigned rev_mask);

static size_t add_split(rs_roads *roads, const char *name, double width, const poly *p, const double *cut, size_t ncut,
                        const char *const *attr)
{
    return add_split_rev(roads, name, width, p, cut, ncut, attr, 0);
}

/* Add points xy[0..m/2) as a road, last to first when rev. */
static void add_record(rs_roads *roads, const char *name, double width, double *xy, size_t m, int rev,
                       const char *const *attr)
{
    if (rev)
        for (size_t a = 0, b = m / 2 - 1; a < b; a++, b--) {
            double tx = xy[2 * a], ty = xy[2 * a + 1];
            xy[2 * a] = xy[2 * b], xy[2 * a + 1] = xy[2 * b + 1];
            xy[2 * b] = tx, xy[2 * b + 1] = ty;
        }
    CHECK(rs_roads_add(ctx, roads, name, width, xy, m / 2) == RS_OK);
    for (size_t a = 0; attr && attr[a]; a += 2)
        CHECK(rs_roads_set_attr(ctx, roads, rs_roads_count(roads) - 1, attr[a], attr[a + 1]) == RS_OK);
}

/* add_split with record i drawn against its points when bit i of rev_mask is set. */
static size_t add_split_rev(rs_roads *roads, const char *name, double width, const poly *p, const double *cut,
                            size_t ncut, const char *const *attr, unsigned rev_mask)
{
    double buf[2 * 512];
    size_t m = 0, added = 0, c = 0;
    double s = 0;
    buf[m++] = p->xy[0], buf[m++] = p->xy[1];
    for (size_t k = 1; k < p->n; k++) {
        double ax = p->xy[2 * k - 2], ay = p->xy[2 * k - 1], bx = p->xy[2 * k], by = p->xy[2 * k + 1];
        double l = hypot(bx - ax, by - ay);
        while (c < ncut && cut[c] <= s + l) {
            double f = l > 0 ? (cut[c] - s) / l : 1;
            double x = f >= 1 ? bx : ax + f * (bx - ax), y = f >= 1 ? by : ay + f * (by - ay);
            if (!(x == buf[m - 2] && y == buf[m - 1])) buf[m++] = x, buf[m++] = y;
            if (m >= 4) {
                add_record(roads, name, width, buf, m, added < 32 && ((rev_mask >> added) & 1), attr);
                added++;
                buf[0] = x, buf[1] = y;
                m = 2;
            }
            c++;
        }
        if (!(bx == buf[m - 2] && by == buf[m - 1])) buf[m++] = bx, buf[m++] = by;
        s += l;
    }
    if (m >= 4) {
        add_record(roads, name, width, buf, m, added < 32 && ((rev_mask >> added) & 1), attr);
        added++;
    }
    return added;
}

/* The turn of p at its interior vertex nearest to arc length s, when that
 * vertex is within `near` metres of s (0: none that near). */
static double turn_near(const poly *p, double s, double near)
{
    double acc = 0;
    for (size_t k = 1; k + 1 < p->n; k++) {
        acc += hypot(p->xy[2 * k] - p->xy[2 * k - 2], p->xy[2 * k + 1] - p->xy[2 * k - 1]);
        if (fabs(acc - s) > near) continue;
        double a0 = atan2(p->xy[2 * k + 1] - p->xy[2 * k - 1], p->xy[2 * k] - p->xy[2 * k - 2]);
        double a1 = atan2(p->xy[2 * k + 3] - p->xy[2 * k + 1], p->xy[2 * k + 2] - p->xy[2 * k]);
        double d = fabs(remainder(a1 - a0, 2 * 3.14159265358979323846));
        return d;
    }
    return 0;
}

static void point_at(const poly *p, double s, double *x, double *y)
{
    for (size_t k = 1; k < p->n; k++) {
        double ax = p->xy[2 * k - 2], ay = p->xy[2 * k - 1], bx = p->xy[2 * k], by = p->xy[2 * k + 1];
        double l = hypot(bx - ax, by - ay);
        if (s <= l || k + 1 == p->n) {
            double f = l > 0 ? fmin(s / l, 1) : 0;
            *x = ax + f * (bx - ax), *y = ay + f * (by - ay);
            return;
        }
        s -= l;
    }
    *x = p->xy[0], *y = p->xy[1];
}

static double dist_to(const poly *p, double x, double y)
{
    double best = 1e300;
    for (size_t k = 1; k < p->n; k++) {
        double ax = p->xy[2 * k - 2], ay = p->xy[2 * k - 1], dx = p->xy[2 * k] - ax, dy = p->xy[2 * k + 1] - ay;
        double l2 = dx * dx + dy * dy, u = l2 > 0 ? ((x - ax) * dx + (y - ay) * dy) / l2 : 0;
        u = u < 0 ? 0 : u > 1 ? 1 : u;
        best = fmin(best, hypot(ax + u * dx - x, ay + u * dy - y));
    }
    return best;
}

/* Random cuts along a polyline of length len: k cuts, sorted, at least
 * gap apart and from the ends. */
static size_t random_cuts(double len, size_t k, double gap, double *cut)
{
    size_t n = 0;
    for (size_t tries = 0; n < k && tries < 1000; tries++) {
        double s = gap + rnd() * (len - 2 * gap);
        int ok = 1;
        for (size_t i = 0; i < n; i++) ok &= fabs(cut[i] - s) >= gap;
        if (ok) cut[n++] = s;
    }
    for (size_t i = 1; i < n; i++)
        for (size_t j = i; j > 0 && cut[j - 1] > cut[j]; j--) {
            double t = cut[j];
            cut[j] = cut[j - 1];
            cut[j - 1] = t;
        }
    return n;
}

/* The network's invariants (the fuzz target checks the same). */
static int net_consistent(const rs_network *net, const rs_roads *roads)
{
    size_t n = rs_roads_count(roads), legs = 0;
    int ok = rs_network_road_count(net) == n;
    for (size_t i = 0; i < rs_network_node_count(net); i++) {
        rs_network_node nd;
        ok &= rs_network_get_node(net, i, &nd) == RS_OK && nd.degree >= 1;
        double prev = -10;
        for (size_t k = 0; k < nd.degree; k++) {
            rs_network_leg L;
            ok &= rs_network_get_leg(net, i, k, &L) == RS_OK && L.road < n && L.angle >= prev;
            prev = L.angle;
            legs++;
        }
        rs_network_leg L;
        ok &= rs_network_get_leg(net, i, nd.degree, &L) == RS_ERR_INVALID_ARG;
    }
    /* strokes partition the records; offsets are the sums of lengths before */
    uint8_t *seen = calloc(n + 1, 1);
    uint32_t *recs = malloc((n + 1) * sizeof *recs);
    size_t total = 0;
    for (size_t k = 0; k < rs_network_stroke_count(net); k++) {
        size_t m = rs_network_stroke_roads(net, k, recs, n);
        ok &= m >= 1;
        double s = 0;
        for (size_t i = 0; i < m && i < n; i++) {
            rs_road_stroke st;
            ok &= recs[i] < n && !seen[recs[i]];
            if (recs[i] >= n) continue;
            seen[recs[i]] = 1;
            ok &= rs_network_road_stroke(net, recs[i], &st) == RS_OK && st.stroke == k;
            double s0 = st.reversed ? s + st.length : s; /* (reversed: the stroke's s at its first point) */
            ok &= fabs(st.s_offset - s0) <= 1e-9 * (1 + s0);
            ok &= st.prev == (i ? recs[i - 1] : UINT32_MAX) && st.next == (i + 1 < m ? recs[i + 1] : UINT32_MAX);
            s += st.length;
        }
        total += m;
    }
    ok &= total == n;
    free(seen);
    free(recs);
    return ok;
}

/* ---- topology ---- */

static void test_tee_tolerance(void)
{
    const double tol = 0.05;
    /* (a main road 0.08 m wide: its surface holds no end beyond the
     * tolerance; 7 m wide, an end 1.1 tolerances off is inside it, a T
     * too: docs/network.md "Ends inside a surface") */
    for (int inside = 0; inside < 4; inside++) {
        int wide = inside >= 2;
        double d = inside & 1 ? 0.9 * tol : 1.1 * tol;
        rs_roads *roads = NULL;
        CHECK(rs_roads_create(ctx, &roads) == RS_OK);
        const double main_xy[6] = { 0, 0, 40, 0.001, 100, 0 };
        const double side_xy[4] = { 57.3, 30, 57.3, d };
        CHECK(rs_roads_add(ctx, roads, "main", wide ? 7 : 0.08, main_xy, 3) == RS_OK);
        CHECK(rs_roads_add(ctx, roads, "side", 5, side_xy, 2) == RS_OK);
        rs_network *net = NULL;
        rs_network_options o = { 0, tol };
        CHECK(rs_network_build(ctx, roads, &o, &net) == RS_OK);
        CHECK(net_consistent(net, roads));
        size_t junctions = 0;
        for (size_t i = 0; i < rs_network_node_count(net); i++) {
            rs_network_node nd;
            rs_network_get_node(net, i, &nd);
            if (nd.kind != RS_NODE_JUNCTION) continue;
            junctions++;
            CHECK_EQ_INT(nd.degree, 3);
            CHECK_NEAR(nd.x, 57.3, 1e-12);
            int fwd = 0, back = 0, end = 0;
            for (size_t k = 0; k < nd.degree; k++) {
                rs_network_leg L;
                rs_network_get_leg(net, i, k, &L);
                if (L.road == 0 && L.kind == RS_LEG_FORWARD) {
                    fwd++;
                    CHECK_EQ_INT(L.segment, 1);
                }
                if (L.road == 0 && L.kind == RS_LEG_BACKWARD) back++;
                if (L.road == 1 && L.kind == RS_LEG_END) {
                    end++;
                    CHECK_NEAR(L.angle, 3.14159265358979323846 / 2, 0.01); /* back up the side road: +y */
                }
            }
            CHECK(fwd == 1 && back == 1 && end == 1);
        }
        CHECKF(junctions == (size_t)((inside & 1) || wide), "T at %g x tolerance (main %s): %zu junctions", d / tol,
               wide ? "7 m" : "0.08 m", junctions);
        /* the same at the default tolerance (0.05) */
        rs_network *net2 = NULL;
        CHECK(rs_network_build(ctx, roads, NULL, &net2) == RS_OK);
        CHECK_EQ_INT(rs_network_node_count(net2), rs_network_node_count(net));
        rs_network_free(ctx, net2);
        rs_network_free(ctx, net);
        rs_roads_free(ctx, roads);
    }
    /* bad tolerances */
    rs_roads *roads = NULL;
    rs_network *net = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    rs_network_options bad = { 0, -1 };
    CHECK(rs_network_build(ctx, roads, &bad, &net) == RS_ERR_INVALID_ARG && net == NULL);
    bad.tolerance = NAN;
    CHECK(rs_network_build(ctx, roads, &bad, &net) == RS_ERR_INVALID_ARG && net == NULL);
    CHECK(rs_network_build(ctx, NULL, NULL, &net) == RS_ERR_INVALID_ARG);
    CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK && rs_network_node_count(net) == 0 &&
          rs_network_stroke_count(net) == 0);
    rs_network_free(ctx, net);
    rs_roads_free(ctx, roads);
}

/* Two records meeting end to start with a gap of 0.9 tolerances are one
 * node and one stroke (1.1: two ends), wherever the gap lies among the
 * hash's cells and whichever way it points. On db31fd7 the cells were one
 * tolerance wide and only 2 x 2 were searched: a gap across a cell edge
 * from a point 0.3 tolerances into its cell was missed. */
static void test_end_tolerance(void)
{
    const double tols[2] = { 0.05, 0.7 };
    const double dirs[4][2] = { { 1, 0 }, { 0, 1 }, { -0.6, 0.8 }, { 0.8, -0.6 } };
    int missed = 0, joined_far = 0, cases = 0;
    for (int t = 0; t < 2; t++)
        for (int d = 0; d < 4; d++)
            for (int k = 0; k < 40; k++)
                for (int inside = 0; inside < 2; inside++) {
                    double tol = tols[t], gap = (inside ? 0.9 : 1.1) * tol, ux = dirs[d][0], uy = dirs[d][1];
                    double x0 = 3 + 0.05 * k * tol, y0 = 7 + 0.0371 * k * tol; /* across the cells */
                    double a[4] = { x0 - 20 * ux, y0 - 20 * uy, x0, y0 };
                    double b[4] = { x0 + gap * ux, y0 + gap * uy, x0 + gap * ux + 20 * ux, y0 + gap * uy + 20 * uy };
                    rs_roads *roads = NULL;
                    rs_network *net = NULL;
                    rs_network_options o = { 0, tol };
                    if (rs_roads_create(ctx, &roads) || rs_roads_add(ctx, roads, "r", 5, a, 2) ||
                        rs_roads_add(ctx, roads, "r", 5, b, 2) || rs_network_build(ctx, roads, &o, &net)) {
                        CHECK(0);
                        rs_roads_free(ctx, roads);
                        continue;
                    }
                    size_t nodes = rs_network_node_count(net), strokes = rs_network_stroke_count(net);
                    cases++;
                    if (inside && (nodes != 3 || strokes != 1)) missed++;
                    if (!inside && (nodes != 4 || strokes != 2)) joined_far++;
                    rs_network_free(ctx, net);
                    rs_roads_free(ctx, roads);
                }
    CHECKF(missed == 0 && joined_far == 0, "%d of %d gaps of 0.9 tol not joined, %d of 1.1 tol joined", missed,
           cases / 2, joined_far);
}

/* Random polylines, each split at random places: the same junctions and
 * ends, and one stroke per polyline whose records lie at the cuts. */
static void test_random_splits(void)
{
    enum { NP = 6 };
    for (int trial = 0; trial < 40; trial++) {
        poly P[NP];
        for (int i = 0; i < NP; i++) {
            P[i].n = 2 + (size_t)(rnd() * 12);
            double x = rnd() * 200, y = rnd() * 200, a = rnd() * 2 * 3.14159265358979323846;
            for (size_t k = 0; k < P[i].n; k++) {
                P[i].xy[2 * k] = x, P[i].xy[2 * k + 1] = y;
                a += (rnd() - 0.5) * 2.0;
                double l = 3 + rnd() * 20;
                x += l * cos(a), y += l * sin(a);
            }
        }
        /* some ends on other roads: T on a segment, or at a shared point */
        for (int i = 1; i < NP; i += 2) {
            const poly *q = &P[i - 1];
            size_t k = (size_t)(rnd() * (double)(q->n - 1));
            double f = trial % 3 == 0 ? 0 : 0.3 + 0.4 * rnd();
            P[i].xy[0] = q->xy[2 * k] + f * (q->xy[2 * k + 2] - q->xy[2 * k]);
            P[i].xy[1] = q->xy[2 * k + 1] + f * (q->xy[2 * k + 3] - q->xy[2 * k + 1]);
        }
        rs_roads *whole = NULL, *split = NULL;
        CHECK(rs_roads_create(ctx, &whole) == RS_OK && rs_roads_create(ctx, &split) == RS_OK);
        size_t first[NP + 1];
        double cuts[NP][8];
        size_t ncut[NP];
        for (int i = 0; i < NP; i++) {
            double w = 3 + i; /* different widths: polylines never continue each other */
            add_split(whole, "w", w, &P[i], NULL, 0, NULL);
            ncut[i] = random_cuts(poly_len(&P[i]), 1 + (size_t)(rnd() * 5), 1.0, cuts[i]);
            /* a cut where another polyline crosses would be a T: leave such cuts out */
            size_t kept = 0;
            for (size_t c = 0; c < ncut[i]; c++) {
                double x, y, dmin = 1e300;
                point_at(&P[i], cuts[i][c], &x, &y);
                for (int o = 0; o < NP; o++)
                    if (o != i) dmin = fmin(dmin, dist_to(&P[o], x, y));
                /* a cut at (or within the tolerance of) a vertex where the
                 * polyline turns 30 degrees or more is a corner: a stroke
                 * ends there by the rule (docs/network.md) */
                if (dmin > 0.5 && turn_near(&P[i], cuts[i][c], 0.11) < 3.14159265358979323846 / 6 - 1e-9) cuts[i][kept++] = cuts[i][c];
            }
            ncut[i] = kept;
            first[i] = rs_roads_count(split);
            add_split(split, "s", w, &P[i], cuts[i], ncut[i], NULL);
        }
        first[NP] = rs_roads_count(split);
        rs_network *a = NULL, *b = NULL;
        CHECK(rs_network_build(ctx, whole, NULL, &a) == RS_OK && rs_network_build(ctx, split, NULL, &b) == RS_OK);
        if (!a || !b) break;
        CHECK(net_consistent(a, whole) && net_consistent(b, split));
        /* nodes other than the splits' continuations: the same places and degrees */
        size_t na = 0, nb = 0, unmatched = 0;
        for (size_t i = 0; i < rs_network_node_count(a); i++) {
            rs_network_node x;
            rs_network_get_node(a, i, &x);
            na++;
            int found = 0;
            for (size_t j = 0; j < rs_network_node_count(b) && !found; j++) {
                rs_network_node y;
                rs_network_get_node(b, j, &y);
                found = hypot(x.x - y.x, x.y - y.y) <= 0.05 && x.degree == y.degree && x.kind == y.kind;
            }
            unmatched += !found;
        }
        for (size_t j = 0; j < rs_network_node_count(b); j++) {
            rs_network_node y;
            rs_network_get_node(b, j, &y);
            nb += !(y.kind == RS_NODE_CONTINUATION);
        }
        size_t cont_a = 0;
        for (size_t i = 0; i < rs_network_node_count(a); i++) {
            rs_network_node x;
            rs_network_get_node(a, i, &x);
            cont_a += x.kind == RS_NODE_CONTINUATION;
        }
        CHECKF(unmatched == 0 && na - cont_a == nb, "trial %d: %zu of %zu nodes unmatched, %zu vs %zu", trial,
               unmatched, na, na - cont_a, nb);
        /* strokes: one per polyline, records in order at the cut places */
        CHECK_EQ_INT(rs_network_stroke_count(b), rs_network_stroke_count(a));
        for (int i = 0; i < NP; i++) {
            rs_road_stroke s0, si;
            rs_network_road_stroke(b, first[i], &s0);
            double len = 0;
            for (size_t r = first[i]; r < first[i + 1]; r++) {
                rs_network_road_stroke(b, r, &si);
                CHECKF(si.stroke == s0.stroke, "trial %d polyline %d record %zu: stroke %u, not %u", trial, i,
                       r - first[i], si.stroke, s0.stroke);
                if (r > first[i]) CHECK_NEAR(si.s_offset, cuts[i][r - first[i] - 1], 1e-9);
                len += si.length;
            }
            rs_road_stroke sa;
            rs_network_road_stroke(a, (size_t)i, &sa);
            CHECK_NEAR(len, sa.length, 1e-9);
            CHECK_EQ_INT(rs_network_stroke_roads(b, s0.stroke, NULL, 0), first[i + 1] - first[i]);
        }
        rs_network_free(ctx, a);
        rs_network_free(ctx, b);
        rs_roads_free(ctx, whole);
        rs_roads_free(ctx, split);
    }
}

/* A roundabout split into four records with two side roads: one closed
 * stroke, roundabout nodes whose major legs are the ring's. */
static void test_roundabout(void)
{
    poly ring;
    ring.n = 33;
    for (size_t k = 0; k < ring.n; k++) {
        double a = 2 * 3.14159265358979323846 * (double)(k % 32) / 32;
        ring.xy[2 * k] = 50 + 15 * cos(a), ring.xy[2 * k + 1] = 50 + 15 * sin(a);
    }
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    static const char *const rb[] = { "junction", "roundabout", "class", "tertiary", NULL };
    double L = poly_len(&ring), cuts[3] = { L / 4, L / 2, 3 * L / 4 };
    /* cut at vertices (multiples of 8 of 32) */
    CHECK_EQ_INT(add_split(roads, "ring", 6, &ring, cuts, 3, rb), 4);
    const double in_a[4] = { 100, 50, 65, 50 }, in_b[4] = { 50, 65, 50, 100 };
    CHECK(rs_roads_add(ctx, roads, "a", 6, in_a, 2) == RS_OK);
    CHECK(rs_roads_set_attr(ctx, roads, 4, "class", "primary") == RS_OK);
    CHECK(rs_roads_add(ctx, roads, "b", 6, in_b, 2) == RS_OK);
    rs_network *net = NULL;
    CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK);
    CHECK(net_consistent(net, roads));
    rs_road_stroke st;
    CHECK(rs_network_road_stroke(net, 2, &st) == RS_OK && st.closed);
    CHECK_EQ_INT(rs_network_stroke_roads(net, st.stroke, NULL, 0), 4);
    CHECK_EQ_INT(rs_network_stroke_count(net), 3);
    rs_road_stroke s3;
    rs_network_road_stroke(net, 3, &s3);
    CHECK(s3.next == UINT32_MAX && st.prev == 1); /* the seam: the last record ends the stroke */
    size_t rb_nodes = 0;
    for (size_t i = 0; i < rs_network_node_count(net); i++) {
        rs_network_node nd;
        rs_network_get_node(net, i, &nd);
        if (!(nd.control & RS_NODE_ROUNDABOUT) || nd.degree != 3) continue;
        rb_nodes++;
        for (size_t k = 0; k < nd.degree; k++) {
            rs_network_leg lg;
            rs_network_get_leg(net, i, k, &lg);
            CHECK(lg.major == (lg.road < 4)); /* +20 beats a primary's rank */
        }
    }
    CHECK_EQ_INT(rb_nodes, 2);
    /* the ring unsplit: a closed stroke of one record, a node of degree 2 */
    rs_roads *one = NULL;
    rs_network *n1 = NULL;
    CHECK(rs_roads_create(ctx, &one) == RS_OK);
    add_split(one, "ring", 6, &ring, NULL, 0, rb);
    CHECK(rs_network_build(ctx, one, NULL, &n1) == RS_OK && net_consistent(n1, one));
    CHECK(rs_network_road_stroke(n1, 0, &st) == RS_OK && st.closed && st.prev == UINT32_MAX);
    CHECK_EQ_INT(rs_network_node_count(n1), 1);
    rs_network_free(ctx, n1);
    rs_roads_free(ctx, one);
    rs_network_free(ctx, net);
    rs_roads_free(ctx, roads);
}

/* A road that comes back through one of its own points (a hairpin that
 * touches itself), and node tags. */
static void test_self_touch(void)
{
    const double xy[] = { 0, 0, 10, 0, 20, 0, 20, 10, 10, 10, 10, 0, 10, -10 };
    static const char text[] = "road h width 4\n0 0\n10 0 highway=stop\n20 0\n20 10\n10 10\n10 0\n10 -10\nend\n";
    rs_roads *roads = NULL;
    CHECK(rs_roads_parse(ctx, text, strlen(text), &roads) == RS_OK);
    (void)xy;
    rs_network *net = NULL;
    CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK && net_consistent(net, roads));
    size_t four = 0;
    for (size_t i = 0; i < rs_network_node_count(net); i++) {
        rs_network_node nd;
        rs_network_get_node(net, i, &nd);
        if (nd.degree == 4) {
            four++;
            CHECK(nd.x == 10 && nd.y == 0 && nd.kind == RS_NODE_JUNCTION && (nd.control & RS_NODE_STOP));
            int f = 0, b = 0;
            for (size_t k = 0; k < 4; k++) {
                rs_network_leg L;
                rs_network_get_leg(net, i, k, &L);
                f += L.kind == RS_LEG_FORWARD, b += L.kind == RS_LEG_BACKWARD;
            }
            CHECK(f == 2 && b == 2);
        }
    }
    CHECK_EQ_INT(four, 1);
    CHECK_EQ_INT(rs_network_node_count(net), 3); /* two ends and the touch */
    rs_network_free(ctx, net);
    rs_roads_free(ctx, roads);
}

/* Repeated points, a zero-length record between two halves, a record
 * shorter than the tolerance: no legs for the degenerate ones, and the
 * halves still one stroke. */
static void test_degenerate(void)
{
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    const double a[] = { 0, 0, 0, 0, 10, 0, 10, 0, 20, 0 }, z[] = { 20, 0, 20, 0 }, b[] = { 20, 0, 30, 0, 30, 0 },
                 tiny[] = { 50, 50, 50.01, 50 };
    CHECK(rs_roads_add(ctx, roads, "a", 4, a, 5) == RS_OK);
    CHECK(rs_roads_add(ctx, roads, "z", 4, z, 2) == RS_OK);
    CHECK(rs_roads_add(ctx, roads, "b", 4, b, 3) == RS_OK);
    CHECK(rs_roads_add(ctx, roads, "t", 4, tiny, 2) == RS_OK);
    rs_network *net = NULL;
    CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK && net_consistent(net, roads));
    rs_road_stroke sa, sz, sb, stiny;
    rs_network_road_stroke(net, 0, &sa);
    rs_network_road_stroke(net, 1, &sz);
    rs_network_road_stroke(net, 2, &sb);
    rs_network_road_stroke(net, 3, &stiny);
    CHECK(sa.stroke == sb.stroke && sa.next == 2 && sb.s_offset == 20 && sz.stroke != sa.stroke &&
          stiny.stroke != sa.stroke && sz.length == 0);
    CHECK_EQ_INT(rs_network_node_count(net), 3); /* a's start, a-b, b's end */
    for (size_t i = 0; i < rs_network_node_count(net); i++)
        for (size_t k = 0;; k++) {
            rs_network_leg L;
            if (rs_network_get_leg(net, i, k, &L) != RS_OK) break;
            CHECK(L.road == 0 || L.road == 2);
        }
    rs_network_free(ctx, net);
    rs_roads_free(ctx, roads);
}

/* Allocation failures: every one reported, nothing leaked (the context's
 * allocator counts). */
typedef struct fail_alloc {
    long left, live;
} fail_alloc;
static void *fa_alloc(void *u, size_t n)
{
    fail_alloc *f = u;
    if (f->left-- == 0) return NULL;
    void *p = malloc(n);
    if (p) f->live++;
    return p;
}
static void *fa_realloc(void *u, void *p, size_t n)
{
    fail_alloc *f = u;
    if (f->left-- == 0) return NULL;
    void *q = realloc(p, n);
    if (q && !p) f->live++;
    return q;
}
static void fa_free(void *u, void *p)
{
    fail_alloc *f = u;
    if (p) f->live--;
    free(p);
}

static void test_alloc_failures(void)
{
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    poly P;
    P.n = 20;
    for (size_t k = 0; k < P.n; k++) P.xy[2 * k] = 5.0 * (double)k, P.xy[2 * k + 1] = 0.1 * (double)(k * k);
    double cuts[3] = { 20, 40, 60 };
    add_split(roads, "r", 5, &P, cuts, 3, NULL);
    const double side[4] = { 30, 40, P.xy[12], P.xy[13] };
    CHECK(rs_roads_add(ctx, roads, "s", 3, side, 2) == RS_OK);
    int failed_all = 1, leaked = 0, ok_at = -1;
    for (long k = 0; k < 200 && ok_at < 0; k++) {
        fail_alloc f = { k, 0 };
        rs_allocator al = { fa_alloc, fa_realloc, fa_free, &f };
        rs_ctx *c2 = NULL;
        if (rs_ctx_create(&al, NULL, &c2) != RS_OK) { f.left = k; continue; }
        rs_network *net = NULL;
        rs_result r = rs_network_build(c2, roads, NULL, &net);
        if (r == RS_OK) ok_at = (int)k;
        else failed_all &= r == RS_ERR_NOMEM && net == NULL;
        rs_network_free(c2, net);
        rs_ctx_free(c2);
        leaked |= f.live != 0;
    }
    CHECK(ok_at > 0 && failed_all && !leaked);
    rs_roads_free(ctx, roads);
}

/* ---- drawing: a split road against the unsplit one ---- */

enum { DW = 121, DH = 81, TEX = 4 };

typedef struct image {
    uint32_t w, h;
    uint8_t *rgba;
} image;

static uint8_t strip_px[16 * 64 * 4];

static rs_profile render_profile; /* the built-in styles' standard for render() */

static int render(const rs_roads *roads, const char *styles_text, image *im)
{
    static float z[DW * DH];
    rs_dem *dem = NULL;
    rs_styles *styles = NULL;
    int ok = rs_dem_create(ctx, DW, DH, z, &dem) == RS_OK;
    if (ok && styles_text) ok = rs_styles_parse(ctx, styles_text, strlen(styles_text), &styles) == RS_OK;
    rs_surface_image si = { "strip.png", { 16, 64, strip_px } };
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = TEX;
    o.style.styles = styles;
    o.style.surface_images = &si;
    o.style.surface_image_count = 1;
    o.style.profile = render_profile;
    if (ok) ok = ss_splat_window(ctx, dem, roads, &o, &im->w, &im->h, &im->rgba) == RS_OK;
    rs_styles_free(ctx, styles);
    rs_dem_free(ctx, dem);
    return ok;
}

static int max_diff(const image *a, const image *b, uint32_t *wx, uint32_t *wy)
{
    int worst = 0;
    for (size_t i = 0; i < (size_t)a->w * a->h; i++)
        for (int c = 0; c < 4; c++) {
            int d = abs((int)a->rgba[4 * i + c] - (int)b->rgba[4 * i + c]);
            if (d > worst) worst = d, *wx = (uint32_t)(i % a->w), *wy = (uint32_t)(i / a->w);
        }
    return worst;
}

/* The worst channel difference between whole and split drawn (render; 255
 * when either fails), and where. */
static int draw_diff(const rs_roads *whole, const rs_roads *split, uint32_t *wx, uint32_t *wy)
{
    image w = { 0 }, sp = { 0 };
    int ok = render(whole, NULL, &w) && render(split, NULL, &sp);
    int dd = ok && w.rgba && sp.rgba ? max_diff(&w, &sp, wx, wy) : 255;
    free(w.rgba);
    free(sp.rgba);
    return dd;
}

static void save_ppm(const char *path, const image *im)
{
    FILE *f = getenv("RS_NETWORK_PPM") ? fopen(path, "wb") : NULL;
    if (!f) return;
    fprintf(f, "P6 %u %u 255\n", im->w, im->h);
    for (size_t i = 0; i < (size_t)im->w * im->h; i++) fwrite(im->rgba + 4 * i, 1, 3, f);
    fclose(f);
}

/* A straight road and a curve (an S of two arcs), class=primary (default
 * style: 6/12 m dashed centre line, edge lines; and under the US profile:
 * 10/30 ft), and a dashed style with a surface image, each split at 1..6 random places (inside segments and at
 * points): within 8/255 of the unsplit road everywhere. */
static void test_split_draws_alike(void)
{
    for (size_t i = 0; i < 16 * 64; i++) {
        strip_px[4 * i] = (uint8_t)(40 + 3 * (i / 16)), strip_px[4 * i + 1] = (uint8_t)(60 + 11 * (i % 16));
        strip_px[4 * i + 2] = (uint8_t)(i * 7), strip_px[4 * i + 3] = 255;
    }
    static const char styles[] = "style dashy\n surface strip.png length 7.3\n line 1.2 0.3 #FFFF00 dash 2 1.5 1 3"
                                 "\n line -1.5 0.2 #FFFFFF dash 0.7 0.9 phase 0.3\nend\n";
    poly shapes[2];
    shapes[0].n = 2;
    shapes[0].xy[0] = 3.3, shapes[0].xy[1] = 41.7, shapes[0].xy[2] = 117.1, shapes[0].xy[3] = 37.9;
    poly *c = &shapes[1];
    c->n = 0;
    for (int k = 0; k <= 40; k++) { /* two arcs of radius 25, turning left then right */
        double a = 3.14159265358979323846 * (double)k / 40;
        c->xy[2 * c->n] = 10 + 25 - 25 * cos(a), c->xy[2 * c->n + 1] = 40 - 25 * sin(a) * 0.9;
        c->n++;
    }
    for (int k = 1; k <= 40; k++) {
        double a = 3.14159265358979323846 * (double)k / 40;
        c->xy[2 * c->n] = 60 + 25 - 25 * cos(a), c->xy[2 * c->n + 1] = 40 + 25 * sin(a) * 0.9;
        c->n++;
    }
    static const char *const primary[] = { "class", "primary", NULL }, *const dashy[] = { "style", "dashy", NULL };
    const char *const *attrs[2] = { primary, dashy };
    int worst_all = 0;
    /* st 2: the primary under the US profile (MUTCD 10/30 ft dashes, yellow centre line) */
    for (int shape = 0; shape < 2; shape++)
        for (int st = 0; st < 3; st++) {
            render_profile = st == 2 ? RS_PROFILE_MUTCD : RS_PROFILE_RMS;
            rs_roads *whole = NULL;
            CHECK(rs_roads_create(ctx, &whole) == RS_OK);
            add_split(whole, "r", st == 1 ? 6.5 : 7.5, &shapes[shape], NULL, 0, attrs[st % 2]);
            image ref = { 0 };
            CHECK(render(whole, styles, &ref));
            if (shape == 1 && st == 0) save_ppm("network_whole.ppm", &ref);
            for (int trial = 0; trial < 6; trial++) {
                double cuts[8], len = poly_len(&shapes[shape]);
                size_t nc = random_cuts(len, 1 + (size_t)trial, 2.0, cuts);
                if (shape == 1 && trial % 2) /* some cuts at the curve's points */
                    for (size_t i = 0; i < nc; i++) {
                        double s = 0;
                        for (size_t k = 1; k < shapes[1].n; k++) {
                            double l = hypot(c->xy[2 * k] - c->xy[2 * k - 2], c->xy[2 * k + 1] - c->xy[2 * k - 1]);
                            if (s + l >= cuts[i]) { cuts[i] = s + l; break; }
                            s += l;
                        }
                    }
                rs_roads *split = NULL;
                CHECK(rs_roads_create(ctx, &split) == RS_OK);
                size_t nrec = add_split(split, "r", st == 1 ? 6.5 : 7.5, &shapes[shape], cuts, nc, attrs[st % 2]);
                image im = { 0 };
                CHECK(render(split, styles, &im));
                uint32_t wx = 0, wy = 0;
                int d = im.rgba && ref.rgba ? max_diff(&ref, &im, &wx, &wy) : 255;
                if (d > worst_all) worst_all = d;
                CHECKF(d <= 8, "%s %s split into %zu records: a pixel off by %d/255 at (%u, %u)",
                       shape ? "curve" : "straight", st == 1 ? "dashy" : st ? "primary (US)" : "primary", nrec, d, wx,
                       wy);
                if (shape == 1 && st == 0 && trial == 5) save_ppm("network_split.ppm", &im);
                if (d > 8) {
                    char nm[64];
                    snprintf(nm, sizeof nm, "bad_%d%d%d.ppm", shape, st, trial);
                    save_ppm(nm, &im);
                    snprintf(nm, sizeof nm, "ref_%d%d.ppm", shape, st);
                    save_ppm(nm, &ref);
                    for (size_t i = 0; i < nc; i++) fprintf(stderr, "    cut %zu at s=%.3f\n", i, cuts[i]);
                }
                free(im.rgba);
                rs_roads_free(ctx, split);
            }
            free(ref.rgba);
            rs_roads_free(ctx, whole);
        }
    render_profile = RS_PROFILE_RMS;
    printf("split roads: worst pixel %d/255 against the unsplit road\n", worst_all);
}

/* A T at x = 41.3 on a through road along y = 40 (half width hw), the side
 * road coming from +y: the worst channel difference between a (the
 * through road alone) and b (with the side road) within 6 m of the T in
 * its inner part (within hw - 2.5 m of the centre line), along the far edge
 * line (+-0.5 m) and at the mouth (the near edge's last 0.6 m, 2 m either
 * side of the T). */
static void tee_zones(const image *a, const image *b, double hw, int *inner, int *far_edge, int *mouth)
{
    double keep = hw - 2.0;
    for (uint32_t py = 0; a->rgba && b->rgba && py < a->h; py++)
        for (uint32_t px = 0; px < a->w; px++) {
            double x = (px + 0.5) / TEX, y = (py + 0.5) / TEX;
            if (fabs(x - 41.3) > 6) continue;
            const uint8_t *p = a->rgba + 4 * ((size_t)py * a->w + px), *q = b->rgba + 4 * ((size_t)py * a->w + px);
            int d = 0;
            for (int c = 0; c < 3; c++) d = abs(p[c] - q[c]) > d ? abs(p[c] - q[c]) : d;
            if (fabs(y - 40) <= keep - 0.5) *inner = d > *inner ? d : *inner;
            if (y < 40 - hw + 0.5 && y > 40 - hw - 0.5) *far_edge = d > *far_edge ? d : *far_edge;
            if (y > 40 + hw - 0.6 && y < 40 + hw && fabs(x - 41.3) < 2) *mouth = d > *mouth ? d : *mouth;
        }
}

/* A side road ending on a through road's centre line (a T): the through
 * road's centre line runs on across the junction (the image inside its
 * inner part is the through road's alone), its edge line stops at the side
 * road's mouth, on that side only; split at the T, the same. A side road
 * with the right of way (a higher class) still cuts the other's lines. */
static void test_tee_lines(void)
{
    /* (the T at s = 39.3 of the through road: inside a 6 m dash of its 6/12 m centre line) */
    static const double main_xy[4] = { 2, 40, 118, 40 }, main_a[4] = { 2, 40, 41.3, 40 }, main_b[4] = { 41.3, 40, 118, 40 };
    static const double side_xy[4] = { 41.3, 78, 41.3, 40 };
    for (int variant = 0; variant < 3; variant++) {
        /* 0: primary through, secondary side; 1: the same, the primary split at
         * the T; 2: secondary "through", primary side (the side has the right of way) */
        const char *through = variant == 2 ? "secondary" : "primary", *side = variant == 2 ? "primary" : "secondary";
        double tw = variant == 2 ? 6.5 : 7.5;
        rs_roads *alone = NULL, *tee = NULL;
        CHECK(rs_roads_create(ctx, &alone) == RS_OK && rs_roads_create(ctx, &tee) == RS_OK);
        CHECK(rs_roads_add(ctx, alone, "m", tw, main_xy, 2) == RS_OK);
        CHECK(rs_roads_set_attr(ctx, alone, 0, "class", through) == RS_OK);
        if (variant == 1) {
            CHECK(rs_roads_add(ctx, tee, "m", tw, main_a, 2) == RS_OK && rs_roads_add(ctx, tee, "m", tw, main_b, 2) == RS_OK);
            CHECK(rs_roads_set_attr(ctx, tee, 1, "class", through) == RS_OK);
        } else {
            CHECK(rs_roads_add(ctx, tee, "m", tw, main_xy, 2) == RS_OK);
        }
        CHECK(rs_roads_set_attr(ctx, tee, 0, "class", through) == RS_OK);
        CHECK(rs_roads_add(ctx, tee, "s", variant == 2 ? 7.5 : 6.5, side_xy, 2) == RS_OK);
        CHECK(rs_roads_set_attr(ctx, tee, rs_roads_count(tee) - 1, "class", side) == RS_OK);
        image a = { 0 }, b = { 0 };
        CHECK(render(alone, NULL, &a) && render(tee, NULL, &b));
        if (variant == 0) {
            save_ppm("network_tee_alone.ppm", &a);
            save_ppm("network_tee.ppm", &b);
        }
        int inner = 0, mouth = 0, far_edge = 0;
        tee_zones(&a, &b, tw / 2, &inner, &far_edge, &mouth);
        if (variant < 2) {
            CHECKF(inner <= 8, "T (%s): the through road's inner lines differ by %d/255 from the road alone",
                   variant ? "split at the T" : "one record", inner);
            CHECKF(mouth > 60, "T: the through road's edge line is not interrupted at the mouth (%d/255)", mouth);
        } else {
            CHECKF(inner > 20, "a side road with the right of way does not cut the other's centre line (%d/255)", inner);
        }
        /* (a wider side road's round end pokes beyond a narrower road: not yet) */
        if (variant < 2) CHECKF(far_edge <= 8, "T: the edge line opposite the side road changed (%d/255)", far_edge);
        free(a.rgba);
        free(b.rgba);
        rs_roads_free(ctx, alone);
        rs_roads_free(ctx, tee);
    }
}

/* A road ending inside another street's surface, not on its centre line
 * (docs/network.md "Ends inside a surface"): a T at the nearest point of
 * the centre line. Topology: the node has the through record's two legs
 * there; an end outside the surface, on its own street, or a car road's
 * end in a footway's surface is none. Drawn: the same picture as the side
 * road ending on the centre line (caps trimmed at the far edge, the
 * through road's lines, the give-way line at its edge), which before this
 * had a round cap bulging past a narrow road's far edge, a centre line cut
 * by an equal road's surface and a give-way line up to a half width early. */
static void add_cls(rs_roads *roads, double w, const char *cls, const double *xy, size_t n)
{
    CHECK(rs_roads_add(ctx, roads, "r", w, xy, n) == RS_OK);
    CHECK(rs_roads_set_attr(ctx, roads, rs_roads_count(roads) - 1, "class", cls) == RS_OK);
}

static void test_end_inside_surface(void)
{
    static const struct {
        double ey, tw;
        const char *tcls, *scls;
        int split, junction;
    } C[] = {
        { -3, 12, "primary", "secondary", 0, 1 },   /* between the near edge and the centre line */
        { 2, 12, "primary", "secondary", 0, 1 },    /* past the centre line */
        { -6, 12, "primary", "secondary", 0, 1 },   /* on the edge */
        { -3, 12, "primary", "secondary", 1, 1 },   /* the through road split at the foot */
        { -6.2, 12, "primary", "secondary", 0, 0 }, /* outside it */
        { -1, 3, "footway", "residential", 0, 0 },  /* a footway holds no car road's end */
        { -1, 3, "residential", "footway", 0, 1 },  /* a footway's end on a street */
    };
    for (size_t c = 0; c < sizeof C / sizeof C[0]; c++) {
        rs_roads *roads = NULL;
        CHECK(rs_roads_create(ctx, &roads) == RS_OK);
        const double t_xy[4] = { 0, 0, 100, 0 }, ta[4] = { 0, 0, 50, 0 }, tb[4] = { 50, 0, 100, 0 };
        const double s_xy[4] = { 50, -30, 50, C[c].ey };
        if (C[c].split) {
            add_cls(roads, C[c].tw, C[c].tcls, ta, 2);
            add_cls(roads, C[c].tw, C[c].tcls, tb, 2);
        } else
            add_cls(roads, C[c].tw, C[c].tcls, t_xy, 2);
        add_cls(roads, 6, C[c].scls, s_xy, 2);
        rs_network *net = NULL;
        CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK);
        CHECK(net_consistent(net, roads));
        size_t junctions = 0;
        for (size_t i = 0; net && i < rs_network_node_count(net); i++) {
            rs_network_node nd;
            rs_network_get_node(net, i, &nd);
            if (nd.kind != RS_NODE_JUNCTION) continue;
            junctions++;
            CHECK_EQ_INT(nd.degree, 3);
            CHECK_NEAR(nd.x, 50, 1e-12); /* (the end point) */
            CHECK_NEAR(nd.y, C[c].ey, 1e-12);
            int fwd = 0, back = 0, end = 0;
            for (size_t k = 0; k < nd.degree; k++) {
                rs_network_leg L;
                rs_network_get_leg(net, i, k, &L);
                if (L.kind == RS_LEG_FORWARD || L.kind == RS_LEG_BACKWARD) {
                    CHECK(L.road == 0); /* (split at the foot: the first of equals) */
                    CHECK_NEAR(L.s, 50, 1e-9);
                    CHECK_NEAR(fabs(L.angle), L.kind == RS_LEG_FORWARD ? 0 : 3.14159265358979323846, 1e-12);
                    fwd += L.kind == RS_LEG_FORWARD, back += L.kind == RS_LEG_BACKWARD;
                }
                if (L.kind == RS_LEG_END) end++;
            }
            CHECK(fwd == 1 && back == 1 && end == 1);
        }
        CHECKF(junctions == (size_t)C[c].junction, "end at y = %g in a %s's surface (%s): %zu junctions", C[c].ey,
               C[c].tcls, C[c].scls, junctions);
        rs_network_free(ctx, net);
        rs_roads_free(ctx, roads);
    }
    /* an end as near two streets' centre lines: the lower record holds it,
     * whichever way round the records run (the walk takes them by place:
     * record 0 starts where record 1 ends) */
    for (int flip = 0; flip < 2; flip++) {
        rs_roads *roads = NULL;
        CHECK(rs_roads_create(ctx, &roads) == RS_OK);
        const double a[4] = { 100, 8, 0, 8 }, ar[4] = { 0, 8, 100, 8 }, b[4] = { 0, 0, 100, 0 }, side[4] = { 130, 4, 50, 4 };
        add_cls(roads, 12, "primary", flip ? ar : a, 2);
        add_cls(roads, 12, "primary", b, 2);
        add_cls(roads, 6, "residential", side, 2);
        rs_network *net = NULL;
        CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK);
        size_t held = 0;
        for (size_t i = 0; net && i < rs_network_node_count(net); i++) {
            rs_network_node nd;
            rs_network_get_node(net, i, &nd);
            if (nd.kind != RS_NODE_JUNCTION) continue;
            for (size_t k = 0; k < nd.degree; k++) {
                rs_network_leg L;
                rs_network_get_leg(net, i, k, &L);
                if (L.kind != RS_LEG_FORWARD && L.kind != RS_LEG_BACKWARD) continue;
                CHECKF(L.road == 0, "an end between two streets (flip %d): held by record %u, not the lower", flip,
                       (unsigned)L.road);
                held++;
            }
        }
        CHECKF(held == 2, "an end between two streets (flip %d): %zu through legs", flip, held);
        rs_network_free(ctx, net);
        rs_roads_free(ctx, roads);
    }
    /* its own street: a road folding back into its own surface, whole
     * and split where it goes straight on */
    for (int split = 0; split < 2; split++) {
        rs_roads *roads = NULL;
        CHECK(rs_roads_create(ctx, &roads) == RS_OK);
        const double whole[8] = { 0, 0, 50, 0, 60, 0, 55, -3 }, a[4] = { 0, 0, 50, 0 }, b[6] = { 50, 0, 60, 0, 55, -3 };
        if (split) {
            add_cls(roads, 12, "primary", a, 2);
            add_cls(roads, 12, "primary", b, 3);
        } else
            add_cls(roads, 12, "primary", whole, 4);
        rs_network *net = NULL;
        CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK);
        for (size_t i = 0; net && i < rs_network_node_count(net); i++) {
            rs_network_node nd;
            rs_network_get_node(net, i, &nd);
            CHECKF(nd.kind != RS_NODE_JUNCTION, "a road ending in its own surface (%s) made a junction",
                   split ? "split" : "whole");
        }
        rs_network_free(ctx, net);
        rs_roads_free(ctx, roads);
    }
    /* drawn: the side road coming from y = 78 and ending `off` short of
     * the through road's centre line (y = 40; negative: past it) against
     * the same road ending on it (a side road without the right of way) */
    static const struct {
        const char *tcls, *scls;
        double tw, sw, off;
    } D[] = {
        { "primary", "secondary", 12, 9, 3 },        /* give-way line, the through road's lines */
        { "primary", "secondary", 12, 9, 6 },        /* at the edge */
        { "primary", "secondary", 12, 9, -2.5 },     /* past the centre line */
        { "secondary", "secondary", 9, 9, 3 },       /* an equal road's surface cut the centre line */
        /* (a side road with the right of way draws its lines to its own
         * end point: test_tee_caps checks its cap) */
    };
    for (size_t c = 0; c < sizeof D / sizeof D[0]; c++) {
        rs_roads *on = NULL, *in = NULL;
        CHECK(rs_roads_create(ctx, &on) == RS_OK && rs_roads_create(ctx, &in) == RS_OK);
        const double t_xy[4] = { 2, 40, 118, 40 }, s_on[4] = { 41.3, 78, 41.3, 40 };
        const double s_in[4] = { 41.3, 78, 41.3, 40 + D[c].off };
        add_cls(on, D[c].tw, D[c].tcls, t_xy, 2);
        add_cls(on, D[c].sw, D[c].scls, s_on, 2);
        add_cls(in, D[c].tw, D[c].tcls, t_xy, 2);
        add_cls(in, D[c].sw, D[c].scls, s_in, 2);
        uint32_t wx = 0, wy = 0;
        int d = draw_diff(on, in, &wx, &wy);
        CHECKF(d <= 8, "%s ending %g m short of a %s's centre line: %d/255 from it ending there, at (%u, %u)",
               D[c].scls, D[c].off, D[c].tcls, d, wx, wy);
        rs_roads_free(ctx, on);
        rs_roads_free(ctx, in);
    }
}

/* A T on a street whose records there do not draw alike (lanes=2 west of
 * the T, lanes=4 east: no stroke passes) and a side road of its class: the
 * two record ends going straight on are the through road. Its inner lines
 * run on and its far edge line stays (the image there is the street's
 * alone), its near edge line stops at the mouth; before, the side road's
 * surface cut them all as at a crossing. */
static void test_tee_two_looks(void)
{
    static const double west[4] = { 2, 40, 41.3, 40 }, east[4] = { 41.3, 40, 118, 40 }, side[4] = { 41.3, 78, 41.3, 40 };
    rs_roads *alone = NULL, *tee = NULL;
    CHECK(rs_roads_create(ctx, &alone) == RS_OK && rs_roads_create(ctx, &tee) == RS_OK);
    for (int k = 0; k < 2; k++) {
        rs_roads *r = k ? tee : alone;
        add_cls(r, 9, "secondary", west, 2);
        CHECK(rs_roads_set_attr(ctx, r, rs_roads_count(r) - 1, "lanes", "2") == RS_OK);
        add_cls(r, 9, "secondary", east, 2);
        CHECK(rs_roads_set_attr(ctx, r, rs_roads_count(r) - 1, "lanes", "4") == RS_OK);
    }
    add_cls(tee, 7, "secondary", side, 2);
    image a = { 0 }, b = { 0 };
    CHECK(render(alone, NULL, &a) && render(tee, NULL, &b));
    int inner = 0, mouth = 0, far_edge = 0;
    tee_zones(&a, &b, 4.5, &inner, &far_edge, &mouth);
    printf("T on a street of two looks: inner lines %d/255, far edge %d/255 off the street alone; mouth %d/255\n", inner,
           far_edge, mouth);
    CHECKF(inner <= 8, "T on a street of two looks: its inner lines differ by %d/255 from the street alone", inner);
    CHECKF(far_edge <= 8, "T on a street of two looks: the far edge line changed (%d/255)", far_edge);
    CHECKF(mouth > 60, "T on a street of two looks: the near edge line is not interrupted at the mouth (%d/255)", mouth);
    free(a.rgba);
    free(b.rgba);
    rs_roads_free(ctx, alone);
    rs_roads_free(ctx, tee);
}

/* Two-way records pointing either way (OSM ways need not agree): one
 * stroke in the order along the road, the reversed ones flagged, offsets
 * at their first points; a one-way road's reversed record is not joined;
 * drawn (symmetric default style) within 8/255 of the unsplit road drawn
 * in the stroke's direction. */
static void test_reversed_records(void)
{
    poly c;
    c.n = 0;
    for (int k = 0; k <= 40; k++) {
        double a = 3.14159265358979323846 * (double)k / 40;
        c.xy[2 * c.n] = 15 + 45 - 45 * cos(a), c.xy[2 * c.n + 1] = 60 - 40 * sin(a);
        c.n++;
    }
    static const char *const primary[] = { "class", "primary", NULL }, *const oneway[] = { "class", "primary", "oneway", "yes", NULL };
    double len = poly_len(&c);
    int worst = 0;
    for (int trial = 0; trial < 8; trial++) {
        double cuts[8];
        size_t nc = random_cuts(len, 2 + (size_t)(trial % 4), 3.0, cuts);
        unsigned mask = 1u + 4u * (unsigned)trial; /* the first record and others reversed */
        rs_roads *whole = NULL, *split = NULL, *ow = NULL;
        CHECK(rs_roads_create(ctx, &whole) == RS_OK && rs_roads_create(ctx, &split) == RS_OK &&
              rs_roads_create(ctx, &ow) == RS_OK);
        /* odd trials 10 m wide: the default style's centre line then sits at
         * 8.9e-16 m, which must still count as mirror-symmetric */
        double wd = trial & 1 ? 10.0 : 7.5;
        size_t nrec = add_split_rev(split, "r", wd, &c, cuts, nc, primary, mask);
        add_split_rev(ow, "r", wd, &c, cuts, nc, oneway, mask);
        rs_network *net = NULL, *neto = NULL;
        CHECK(rs_network_build(ctx, split, NULL, &net) == RS_OK && net_consistent(net, split));
        CHECK(rs_network_build(ctx, ow, NULL, &neto) == RS_OK && net_consistent(neto, ow));
        CHECK_EQ_INT(rs_network_stroke_count(net), 1);
        CHECKF(rs_network_stroke_count(neto) > 1, "one-way records pointing both ways joined");
        uint32_t recs[16];
        size_t m = rs_network_stroke_roads(net, 0, recs, 16);
        CHECK_EQ_INT(m, nrec);
        /* the stroke runs from record 0 or from the last record, in order */
        int fwd = m > 0 && recs[0] == 0, in_order = 1;
        for (size_t i = 0; i < m; i++) {
            in_order &= recs[i] == (fwd ? i : m - 1 - i);
            rs_road_stroke st;
            rs_network_road_stroke(net, recs[i], &st);
            in_order &= st.reversed == (int)(((mask >> recs[i]) & 1) ^ (unsigned)!fwd);
        }
        CHECKF(in_order, "trial %d: records out of order or wrongly flagged", trial);
        /* the unsplit road in the stroke's direction (the dashes start at its first point) */
        add_split_rev(whole, "r", wd, &c, NULL, 0, primary, fwd ? 0u : 1u);
        image a = { 0 }, b = { 0 };
        CHECK(render(whole, NULL, &a) && render(split, NULL, &b));
        uint32_t wx = 0, wy = 0;
        int d = a.rgba && b.rgba ? max_diff(&a, &b, &wx, &wy) : 255;
        worst = d > worst ? d : worst;
        CHECKF(d <= 8, "reversed records (trial %d): a pixel off by %d/255 at (%u, %u)", trial, d, wx, wy);
        /* a surface image (asymmetric across the road) runs on along the stroke too */
        static const char strip_style[] = "style strip\n surface strip.png length 7.3\nend\n";
        for (size_t r = 0; r < rs_roads_count(whole); r++) CHECK(rs_roads_set_attr(ctx, whole, r, "style", "strip") == RS_OK);
        for (size_t r = 0; r < rs_roads_count(split); r++) CHECK(rs_roads_set_attr(ctx, split, r, "style", "strip") == RS_OK);
        image ai = { 0 }, bi = { 0 };
        CHECK(render(whole, strip_style, &ai) && render(split, strip_style, &bi));
        int di = ai.rgba && bi.rgba ? max_diff(&ai, &bi, &wx, &wy) : 255;
        worst = di > worst ? di : worst;
        CHECKF(di <= 8, "reversed records, surface image (trial %d): a pixel off by %d/255 at (%u, %u)", trial, di, wx, wy);
        if (di > 8) {
            save_ppm("revi_bad.ppm", &bi);
            save_ppm("revi_ref.ppm", &ai);
        }
        free(ai.rgba);
        free(bi.rgba);
        if (d > 8) {
            save_ppm("rev_bad.ppm", &b);
            save_ppm("rev_ref.ppm", &a);
            for (size_t i = 0; i < nc; i++) fprintf(stderr, "    cut %zu at s=%.3f\n", i, cuts[i]);
        }
        free(a.rgba);
        free(b.rgba);
        rs_network_free(ctx, net);
        rs_network_free(ctx, neto);
        rs_roads_free(ctx, whole);
        rs_roads_free(ctx, split);
        rs_roads_free(ctx, ow);
    }
    printf("reversed records: worst pixel %d/255 against the unsplit road\n", worst);
}

/* Two records meeting end to end form one stroke only when they turn less
 * than 30 degrees there: a corner (a block's sidewalk ring) starts anew, as
 * the GPU export has it (issue 27: "small deflection"). */
static void test_corner_rule(void)
{
    static const double turns[] = { 0, 20, 29, 31, 60, 90 };
    for (size_t i = 0; i < sizeof turns / sizeof *turns; i++) {
        double a = turns[i] * 3.14159265358979323846 / 180;
        const double p0[4] = { 0, 0, 10, 0 }, p1[4] = { 10, 0, 10 + 10 * cos(a), 10 * sin(a) };
        rs_roads *r = NULL;
        rs_network *n = NULL;
        CHECK(rs_roads_create(ctx, &r) == RS_OK && rs_roads_add(ctx, r, "a", 4, p0, 2) == RS_OK &&
              rs_roads_add(ctx, r, "b", 4, p1, 2) == RS_OK && rs_network_build(ctx, r, NULL, &n) == RS_OK);
        if (n) CHECKF((rs_network_stroke_count(n) == 1) == (turns[i] < 30), "a %g degree corner: %zu strokes",
                      turns[i], rs_network_stroke_count(n));
        rs_network_free(ctx, n);
        rs_roads_free(ctx, r);
    }
}

/* A record cut within the tolerance of a sharp vertex (past it, inside the
 * next segment) still continues into the next: the cut is no corner
 * although the legs' angles, taken beyond the tolerance, see one (they
 * made two strokes, and the lines of a wide road were cut at the split:
 * fuzz/split). Cut exactly at the vertex, it is the corner rule's. */
static void test_cut_near_corner(void)
{
    const double a = 150 * 3.14159265358979323846 / 180;
    const double ux = cos(a), uy = sin(a);
    for (int k = 0; k < 4; k++) {
        double d = k == 0 ? 0 : k == 1 ? 0.01 : k == 2 ? 0.04 : 0.2; /* metres past the vertex */
        double p0[6] = { 0, 0, 10, 0, 10 + d * ux, d * uy }, p1[4] = { 10 + d * ux, d * uy, 10 + 10 * ux, 10 * uy };
        rs_roads *r = NULL;
        rs_network *n = NULL;
        CHECK(rs_roads_create(ctx, &r) == RS_OK && rs_roads_add(ctx, r, "a", 4, k ? p0 : p0, k ? 3 : 2) == RS_OK &&
              rs_roads_add(ctx, r, "b", 4, p1, 2) == RS_OK && rs_network_build(ctx, r, NULL, &n) == RS_OK);
        if (n) CHECKF((rs_network_stroke_count(n) == 1) == (k > 0), "cut %g m past a 150 degree corner: %zu strokes", d,
                      rs_network_stroke_count(n));
        rs_network_free(ctx, n);
        rs_roads_free(ctx, r);
    }
}

/* A record no longer than twice the tolerance between two others: they
 * continue each other across it, and it lies in their stroke between
 * them (its points are the road's: a bend inside it stays; its neighbours
 * left a gap in their lines as wide as it: fuzz/split). Its ends meet
 * theirs exactly: a chain, whose joints are nodes of degree 2. */
static void test_short_record_between(void)
{
    const double a[4] = { 0, 0, 10, 0 }, d[4] = { 10, 0, 10.08, 0 }, b[4] = { 10.08, 0, 20, 0 };
    rs_roads *r = NULL;
    rs_network *n = NULL;
    CHECK(rs_roads_create(ctx, &r) == RS_OK && rs_roads_add(ctx, r, "a", 4, a, 2) == RS_OK &&
          rs_roads_add(ctx, r, "d", 4, d, 2) == RS_OK && rs_roads_add(ctx, r, "b", 4, b, 2) == RS_OK &&
          rs_network_build(ctx, r, NULL, &n) == RS_OK);
    if (n) {
        rs_road_stroke sa, sd, sb;
        CHECK(rs_network_road_stroke(n, 0, &sa) == RS_OK && rs_network_road_stroke(n, 1, &sd) == RS_OK &&
              rs_network_road_stroke(n, 2, &sb) == RS_OK);
        CHECKF(sa.stroke == sb.stroke && sa.next == 1 && sb.prev == 1, "a and b: strokes %u, %u", sa.stroke, sb.stroke);
        CHECK(sd.stroke == sa.stroke && sd.prev == 0 && sd.next == 2 && !sd.reversed);
        CHECK(fabs(sd.s_offset - 10) < 1e-9 && fabs(sb.s_offset - 10.08) < 1e-9);
        /* four nodes: the two ends and the two joints (degree 2) */
        CHECK_EQ_INT(rs_network_node_count(n), 4);
        for (size_t i = 0; i < rs_network_node_count(n); i++) {
            rs_network_node nd;
            CHECK(rs_network_get_node(n, i, &nd) == RS_OK && nd.degree <= 2);
        }
    }
    rs_network_free(ctx, n);
    rs_roads_free(ctx, r);
    /* alone, it is no node */
    CHECK(rs_roads_create(ctx, &r) == RS_OK && rs_roads_add(ctx, r, "d", 4, d, 2) == RS_OK &&
          rs_network_build(ctx, r, NULL, &n) == RS_OK);
    if (n) CHECK_EQ_INT(rs_network_node_count(n), 0);
    rs_network_free(ctx, n);
    rs_roads_free(ctx, r);
}

/* A record no longer than twice the tolerance at a road's free end joins
 * the stroke of the record it continues (its lines stopped up to 0.1 m
 * short, the pattern shifted). A wide one-way road turning 20 degrees
 * just before such cuts: the records beyond the bend must not stop the
 * mitre of the bend (across a bridged short record the far joint stood in
 * a straight line and the inner edge line was painted twice: fuzz/split
 * cut-after-vertex-bridged-gap). Each drawn within 8/255 of the road whole. */
static void test_short_record_at_end(void)
{
    const double a[4] = { 3, 40, 60, 40 }, d[4] = { 60, 40, 60.06, 40 };
    rs_roads *r = NULL;
    rs_network *n = NULL;
    CHECK(rs_roads_create(ctx, &r) == RS_OK && rs_roads_add(ctx, r, "a", 7, a, 2) == RS_OK &&
          rs_roads_add(ctx, r, "d", 7, d, 2) == RS_OK && rs_network_build(ctx, r, NULL, &n) == RS_OK);
    if (n) {
        rs_road_stroke sa, sd;
        CHECK(rs_network_road_stroke(n, 0, &sa) == RS_OK && rs_network_road_stroke(n, 1, &sd) == RS_OK);
        CHECKF(sa.stroke == sd.stroke && sa.next == 1 && sd.prev == 0 && !sd.reversed,
               "strokes %u, %u; next %u, prev %u", sa.stroke, sd.stroke, sa.next, sd.prev);
        CHECK(fabs(sd.s_offset - 57) < 1e-9);
    }
    rs_network_free(ctx, n);
    rs_roads_free(ctx, r);
    /* drawn: a straight primary with two short records at either end (cut
     * 0.03 and 0.07 m from its start, 0.09 and 0.04 m from its end), a one-way
     * four-lane road of 10.4 m turning 20 degrees 1.5 m before its end,
     * cut 6 mm, 0.59 m and 0.637 m past the vertex (a short record between) */
    static const char *const primary[] = { "class", "primary", NULL };
    static const char *const oneway4[] = { "class", "primary", "oneway", "yes", "lanes", "4", NULL };
    poly shapes[3];
    shapes[0].n = 2;
    shapes[0].xy[0] = 3.3, shapes[0].xy[1] = 41.7, shapes[0].xy[2] = 117.1, shapes[0].xy[3] = 37.9;
    /* a 45-degree bend inside a record of 0.025 m (cut 0.01 m before it and
     * 0.015 m past it): no corner of the stroke, as unsplit */
    shapes[2].n = 3;
    shapes[2].xy[0] = 10, shapes[2].xy[1] = 20, shapes[2].xy[2] = 50, shapes[2].xy[3] = 20;
    shapes[2].xy[4] = 80, shapes[2].xy[5] = 50;
    shapes[1].n = 3;
    shapes[1].xy[0] = 20, shapes[1].xy[1] = 30, shapes[1].xy[2] = 81.3, shapes[1].xy[3] = 48;
    shapes[1].xy[4] = 81.3 + 1.5 * cos(-0.06), shapes[1].xy[5] = 48 + 1.5 * sin(-0.06);
    double len1 = poly_len(&shapes[1]), vx = len1 - 1.5;
    const double len0 = poly_len(&shapes[0]), cuts0[4] = { 0.03, 0.07, len0 - 0.09, len0 - 0.04 };
    const double cuts1[4] = { 30, vx + 0.006, vx + 0.59, vx + 0.637 };
    const double cuts2[4] = { 12, 39.99, 40.015, 60 };
    for (int prof = 0; prof < 2; prof++)
        for (int shape = 0; shape < 3; shape++) {
            render_profile = prof ? RS_PROFILE_MUTCD : RS_PROFILE_RMS;
            double wd = shape == 1 ? 10.4375 : 7.5;
            const char *const *at = shape == 1 ? oneway4 : primary;
            rs_roads *whole = NULL, *split = NULL;
            CHECK(rs_roads_create(ctx, &whole) == RS_OK && rs_roads_create(ctx, &split) == RS_OK);
            add_split(whole, "r", wd, &shapes[shape], NULL, 0, at);
            size_t nrec = add_split(split, "r", wd, &shapes[shape], shape == 2 ? cuts2 : shape ? cuts1 : cuts0, 4, at);
            CHECK_EQ_INT(nrec, 5);
            uint32_t wx = 0, wy = 0;
            int dd = draw_diff(whole, split, &wx, &wy);
            CHECKF(dd <= 8, "%s (%s): a pixel off by %d/255 at (%u, %u)",
                   shape == 2 ? "a bend inside a short record" : shape ? "short records past a bend"
                                                                     : "two short records at either end",
                   prof ? "MUTCD" : "RMS", dd, wx, wy);
            rs_roads_free(ctx, whole);
            rs_roads_free(ctx, split);
        }
    render_profile = RS_PROFILE_RMS;
}

/* A road cut into crumbs: records of at most twice the tolerance (0.1 m),
 * hundreds of them, which bridge_short joined into one point until a run
 * of them longer than 0.1 m became live records of a chain: each such
 * road is one stroke and draws as unsplit (it drew no lines: 186/255). */
static void test_crumbs_road(void)
{
    static const char *const primary[] = { "class", "primary", NULL };
    static poly shapes[3];
    /* an arc of 24 m (radius 20), a 45-degree bend, a ring of radius 6 m */
    shapes[0].n = 25;
    for (size_t k = 0; k < 25; k++) {
        double a = -0.6 + 1.2 * (double)k / 24;
        shapes[0].xy[2 * k] = 60 + 20 * sin(a), shapes[0].xy[2 * k + 1] = 20 + 20 * cos(a);
    }
    shapes[1].n = 3;
    shapes[1].xy[0] = 20, shapes[1].xy[1] = 20, shapes[1].xy[2] = 32, shapes[1].xy[3] = 20;
    shapes[1].xy[4] = 32 + 12 * cos(0.7853981633974483), shapes[1].xy[5] = 20 + 12 * sin(0.7853981633974483);
    shapes[2].n = 41;
    for (size_t k = 0; k < 41; k++) {
        double a = 2 * 3.14159265358979323846 * (double)(k % 40) / 40;
        shapes[2].xy[2 * k] = 90 + 6 * cos(a), shapes[2].xy[2 * k + 1] = 55 + 6 * sin(a);
    }
    static double cuts[1200];
    for (int shape = 0; shape < 3; shape++)
        for (int kind = 0; kind < 3; kind++) {
            double len = poly_len(&shapes[shape]), s = 0;
            size_t nc = 0;
            rng_state = 0x9E3779B97F4A7C15u + (uint64_t)(3 * shape + kind);
            while (nc < 1200) {
                /* 0: crumbs of 0.08 m; 1: of 0.005 .. 0.1 m; 2: 4 m records with
                 * 30 crumbs of 0.02 m between them */
                double step = kind == 0 ? 0.08 : kind == 1 ? 0.005 + 0.095 * rnd() : (nc % 31 == 0 ? 4 : 0.02);
                if (s + step >= len - 0.01) break;
                s += step;
                cuts[nc++] = s;
            }
            rs_roads *whole = NULL, *split = NULL;
            rs_network *n = NULL;
            CHECK(rs_roads_create(ctx, &whole) == RS_OK && rs_roads_create(ctx, &split) == RS_OK);
            add_split(whole, "r", 7.5, &shapes[shape], NULL, 0, primary);
            size_t nrec = add_split(split, "r", 7.5, &shapes[shape], cuts, nc, primary);
            CHECK(nrec > 100);
            CHECK(rs_network_build(ctx, split, NULL, &n) == RS_OK);
            if (n) {
                rs_road_stroke st;
                size_t other = 0;
                CHECK_EQ_INT(rs_network_stroke_count(n), 1);
                for (size_t r = 0; r < nrec; r++)
                    if (rs_network_road_stroke(n, r, &st) != RS_OK || st.stroke != 0) other++;
                CHECKF(other == 0, "shape %d, cuts %d: %zu of %zu records not in the one stroke", shape, kind, other,
                       nrec);
                CHECK(rs_network_road_stroke(n, 0, &st) == RS_OK && st.closed == (shape == 2));
            }
            rs_network_free(ctx, n);
            for (int prof = 0; prof < 2; prof++) {
                render_profile = prof ? RS_PROFILE_MUTCD : RS_PROFILE_RMS;
                uint32_t wx = 0, wy = 0;
                int dd = draw_diff(whole, split, &wx, &wy);
                CHECKF(dd <= 8, "shape %d cut into %zu records (%s): a pixel off by %d/255 at (%u, %u)", shape, nrec,
                       prof ? "MUTCD" : "RMS", dd, wx, wy);
            }
            rs_roads_free(ctx, whole);
            rs_roads_free(ctx, split);
        }
    render_profile = RS_PROFILE_RMS;
}

/* A road no longer than twice the tolerance draws no lines, and cut into
 * more records than a bridged run takes (16) neither: the run became a
 * chain and its stroke drew the lines of a 0.086 m road (fuzz/split
 * corpus short-road-in-crumbs: a 17.8 m wide trunk in 57 records, 82/255).
 * Cut into 10 or 30 records, as unsplit. */
static void test_crumbs_short_road(void)
{
    static const char *const wide[] = { "class", "primary", "lanes", "4", NULL };
    poly road;
    road.n = 2;
    road.xy[0] = 30, road.xy[1] = 40, road.xy[2] = 30.06, road.xy[3] = 40.06;
    double len = poly_len(&road), cuts[40];
    for (int k = 0; k < 2; k++) {
        size_t nc = k ? 29 : 9;
        for (size_t i = 0; i < nc; i++) cuts[i] = len * (double)(i + 1) / (double)(nc + 1);
        rs_roads *whole = NULL, *split = NULL;
        CHECK(rs_roads_create(ctx, &whole) == RS_OK && rs_roads_create(ctx, &split) == RS_OK);
        add_split(whole, "r", 14, &road, NULL, 0, wide);
        CHECK_EQ_INT(add_split(split, "r", 14, &road, cuts, nc, wide), nc + 1);
        uint32_t wx = 0, wy = 0;
        int dd = draw_diff(whole, split, &wx, &wy);
        CHECKF(dd <= 8, "a %.3f m road in %zu records: a pixel off by %d/255 at (%u, %u)", len, nc + 1, dd, wx, wy);
        rs_roads_free(ctx, whole);
        rs_roads_free(ctx, split);
    }
}

/* A T drawn with its roads split near it (the through road 2 m from the
 * side road's end, the side road 4 m before the through road's centre
 * line, or both cut into many records, 0.03 m crumbs included, also
 * exactly at the T 0.046 m past a vertex; a one-way road with a 0.12 m
 * record at the T) draws as unsplit, automatic give-way lines included:
 * split ends near a junction made a junction of their own (its area hid
 * the give-way line, 196/255), a side road's end near a road cut into
 * crumbs met several of its joints, a 3 mm record's leg pointed the wrong
 * way (issue 27 target 1). Kind 5 is the straight cousin of a curved case
 * where a bridged record made a loop at the T (184/255); straight, it drew
 * alike on the earlier rule too. */
static void test_tee_splits(void)
{
    static const char *const primary[] = { "class", "primary", NULL };
    static const char *const residential[] = { "class", "residential", NULL };
    static poly main_road, side;
    main_road.n = 2;
    main_road.xy[0] = 5, main_road.xy[1] = 30, main_road.xy[2] = 115, main_road.xy[3] = 33;
    double tx = 60.3, ty = 30 + 3 * (tx - 5) / 110; /* on the centre line */
    side.n = 2;
    side.xy[0] = tx - 8, side.xy[1] = ty + 40, side.xy[2] = tx, side.xy[3] = ty;
    double lm = poly_len(&main_road), ls = poly_len(&side), tm = hypot(tx - 5, ty - 30);
    static double cuts[2000];
    /* kind 4: main with a vertex 0.046 m before the T, cut into crumbs and
     * exactly at the T (the node is at the vertex, the records ending at
     * the T lie between it and the vertex) */
    static poly bent;
    double ux = (115 - 5) / lm, uy = (33 - 30) / lm;
    bent.n = 3;
    bent.xy[0] = 5, bent.xy[1] = 30, bent.xy[2] = 5 + (tm - 0.046) * ux, bent.xy[3] = 30 + (tm - 0.046) * uy + 0.002;
    bent.xy[4] = 115, bent.xy[5] = 33;
    double s1 = hypot(bent.xy[2] - 5, bent.xy[3] - 30), l2 = hypot(115 - bent.xy[2], 33 - bent.xy[3]);
    double fT = (tm - s1) / l2; /* (where add_split puts a cut at tm: the side road ends exactly there) */
    double bx = bent.xy[2] + fT * (115 - bent.xy[2]), by = bent.xy[3] + fT * (33 - bent.xy[3]);
    static const char *const oneway[] = { "class", "primary", "oneway", "yes", NULL };
    for (int kind = 0; kind < 6; kind++)
        for (int prof = 0; prof < 2; prof++) {
            const poly *mr = kind == 4 ? &bent : &main_road;
            const char *const *mat = kind == 5 ? oneway : primary;
            static poly sd;
            sd = side;
            if (kind == 4) sd.xy[2] = bx, sd.xy[3] = by;
            rs_roads *whole = NULL, *split = NULL;
            CHECK(rs_roads_create(ctx, &whole) == RS_OK && rs_roads_create(ctx, &split) == RS_OK);
            add_split(whole, "main", 9, mr, NULL, 0, mat);
            add_split(whole, "side", 7, &sd, NULL, 0, residential);
            size_t nc = 0;
            if (kind == 0) cuts[nc++] = tm - 2;
            else if (kind == 2) {
                rng_state = 0x5DEECE66Du;
                for (double at = 0.5 + rnd(); at < lm - 0.5 && nc < 30; at += 0.5 + 3 * rnd()) cuts[nc++] = at;
            } else if (kind == 3 || kind == 4) {
                int at_t = kind == 4;
                for (double at = 0.03; at < lm - 0.03 && nc < 2000; at += 0.03 + 0.004 * (double)(nc % 3)) {
                    if (at_t && at >= tm) cuts[nc++] = tm, at_t = 0;
                    if (at != tm) cuts[nc++] = at;
                }
            } else if (kind == 5) {
                /* a one-way road: a 0.12 m record from just before the T, a
                 * 0.05 m one after it */
                cuts[nc++] = tm - 2.5, cuts[nc++] = tm - 0.037, cuts[nc++] = tm + 0.0817, cuts[nc++] = tm + 0.1317;
                cuts[nc++] = tm + 3;
            }
            add_split(split, "main", 9, mr, cuts, nc, mat);
            double sc[1] = { ls - 4 };
            add_split(split, "side", 7, &sd, kind == 1 || kind == 2 ? sc : NULL, kind == 1 || kind == 2, residential);
            render_profile = prof ? RS_PROFILE_MUTCD : RS_PROFILE_RMS;
            uint32_t wx = 0, wy = 0;
            int dd = draw_diff(whole, split, &wx, &wy);
            CHECKF(dd <= 8, "T, splits %d (%s, %zu records): a pixel off by %d/255 at (%u, %u)", kind,
                   prof ? "MUTCD" : "RMS", rs_roads_count(split), dd, wx, wy);
            rs_roads_free(ctx, whole);
            rs_roads_free(ctx, split);
        }
    render_profile = RS_PROFILE_RMS;
}

/* ---- junction areas (rs_network_junction_area) ---- */

/* The junction node of roads (the one of degree >= 3), or SIZE_MAX. */
static size_t junction_node(const rs_network *net)
{
    for (size_t i = 0; i < rs_network_node_count(net); i++) {
        rs_network_node nd;
        if (rs_network_get_node(net, i, &nd) == RS_OK && nd.degree >= 3) return i;
    }
    return SIZE_MAX;
}

static double shoelace(const double *xy, size_t n)
{
    double a = 0;
    for (size_t k = 0; k < n; k++) {
        size_t j = (k + 1) % n;
        a += xy[2 * k] * xy[2 * j + 1] - xy[2 * j] * xy[2 * k + 1];
    }
    return 0.5 * a;
}

/* Does the polygon hold point (x, y) among its corners (within 1e-7:
 * neighbouring legs' corners within 1e-6 of the tolerance are merged)? */
static int has_corner(const double *xy, size_t n, double x, double y)
{
    for (size_t k = 0; k < n; k++)
        if (fabs(xy[2 * k] - x) < 1e-7 && fabs(xy[2 * k + 1] - y) < 1e-7) return 1;
    return 0;
}

static void test_junction_area(void)
{
    /* an X through a shared point: 6 m along x, 4 m along y: the square
     * where the two surfaces overlap, each leg trimmed by the other's half
     * width */
    for (int tee = 0; tee < 2; tee++) {
        rs_roads *roads = NULL;
        rs_network *net = NULL;
        CHECK(rs_roads_create(ctx, &roads) == RS_OK);
        double a[6] = { -40, 0, 0, 0, 40, 0 }, b[6] = { 0, -40, 0, 0, 0, 40 };
        add_record(roads, "a", 6, a, 6, 0, NULL);
        /* tee: the 4 m road ends on a's centre line from the south (a T on
         * a segment: a has no point there) */
        double a2[4] = { -40, 0, 40, 0 };
        if (tee) {
            rs_roads_free(ctx, roads);
            CHECK(rs_roads_create(ctx, &roads) == RS_OK);
            add_record(roads, "a", 6, a2, 4, 0, NULL);
        }
        add_record(roads, "b", 4, b, tee ? 4 : 6, 0, NULL);
        CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK);
        size_t nd = net ? junction_node(net) : SIZE_MAX;
        CHECK(nd != SIZE_MAX);
        if (nd == SIZE_MAX) {
            rs_network_free(ctx, net);
            rs_roads_free(ctx, roads);
            continue;
        }
        double xy[2 * 8], trim[4] = { -1, -1, -1, -1 };
        size_t n = rs_network_junction_area(net, roads, nd, xy, 8, trim);
        CHECKF(n == 4, "%s: %zu corners (want the 4 of a rectangle)", tee ? "T" : "X", n);
        CHECK(rs_network_junction_area(net, roads, nd, NULL, 0, NULL) == n);
        CHECKF(fabs(shoelace(xy, n < 8 ? n : 8) - 24) < 1e-9, "%s: area %.12g (want 24, counter-clockwise)",
               tee ? "T" : "X", shoelace(xy, n < 8 ? n : 8));
        /* the T: the side road's mouth spans the through road's width, as
         * its trimmed end does (docs/network.md "Ends at a T") */
        CHECK(has_corner(xy, n, 2, -3) && has_corner(xy, n, 2, 3) && has_corner(xy, n, -2, 3) &&
              has_corner(xy, n, -2, -3));
        rs_network_node node;
        CHECK(rs_network_get_node(net, nd, &node) == RS_OK);
        for (uint32_t k = 0; k < node.degree && k < 4; k++) {
            rs_network_leg L;
            CHECK(rs_network_get_leg(net, nd, k, &L) == RS_OK);
            CHECKF(fabs(trim[k] - (L.road == 0 ? 2 : 3)) < 1e-9, "leg %u of road %u: trim %.12g", k, L.road, trim[k]);
        }
        /* a short cap: the count, and only cap points written */
        double few[4] = { 7, 7, 7, 7 };
        CHECK(rs_network_junction_area(net, roads, nd, few, 1, NULL) == n && few[2] == 7 && few[3] == 7);
        /* not a junction, out of range, another road set */
        CHECK(rs_network_junction_area(net, roads, rs_network_node_count(net), xy, 8, NULL) == 0);
        rs_roads *other = NULL;
        CHECK(rs_roads_create(ctx, &other) == RS_OK);
        CHECK(rs_network_junction_area(net, other, nd, xy, 8, NULL) == 0);
        rs_roads_free(ctx, other);
        for (size_t i = 0; i < rs_network_node_count(net); i++) {
            rs_network_node q;
            CHECK(rs_network_get_node(net, i, &q) == RS_OK);
            if (q.degree < 3) CHECK(rs_network_junction_area(net, roads, i, xy, 8, NULL) == 0);
        }
        rs_network_free(ctx, net);
        rs_roads_free(ctx, roads);
    }
    /* random star junctions: 3 to 7 roads ending at the origin at random
     * angles and widths, 60 m long (or, one case in three, 1 to 7 m: then
     * far ends inside other surfaces make more nodes). At every junction
     * node each leg's two corners lie on its edges at its trim, within
     * the length its record runs from the node; at the origin of long
     * roads the polygon turns counter-clockwise (no negative area), has at
     * most twice the degree in corners, and turning the scene turns it */
    size_t bad = 0, cases = 0, nodes = 0;
    for (int it = 0; it < 300; it++) {
        int d = 3 + (int)(rnd() * 5), longs = it % 3 != 0;
        double ang[8], wd[8], len[8], turn = rnd() * 6.283185307179586;
        for (int k = 0; k < d; k++) ang[k] = rnd() * 6.283185307179586, wd[k] = 1 + 14 * rnd(), len[k] = longs ? 60 : 1 + 6 * rnd();
        double area[2] = { 0, 0 };
        size_t cnt[2] = { 0, 0 };
        for (int rot = 0; rot < 2; rot++) {
            rs_roads *roads = NULL;
            rs_network *net = NULL;
            CHECK(rs_roads_create(ctx, &roads) == RS_OK);
            for (int k = 0; k < d; k++) {
                double a = ang[k] + (rot ? turn : 0), xy[4] = { len[k] * cos(a), len[k] * sin(a), 0, 0 };
                add_record(roads, "r", wd[k], xy, 4, 0, NULL);
            }
            CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK);
            for (size_t nd = 0; net && nd < rs_network_node_count(net); nd++) {
                rs_network_node node;
                CHECK(rs_network_get_node(net, nd, &node) == RS_OK);
                if (node.degree < 3 || node.degree > 16) continue;
                double xy[2 * 32], trim[16];
                size_t n = rs_network_junction_area(net, roads, nd, xy, 32, trim);
                nodes++;
                bad += n > 2 * (size_t)node.degree;
                for (uint32_t k = 0; k < node.degree; k++) {
                    rs_network_leg L;
                    CHECK(rs_network_get_leg(net, nd, k, &L) == RS_OK);
                    double h = 0.5 * wd[L.road], ux = cos(L.angle), uy = sin(L.angle);
                    double room = L.kind == RS_LEG_BACKWARD ? L.s : L.kind == RS_LEG_FORWARD ? len[L.road] - L.s : len[L.road];
                    bad += !(trim[k] >= 0 && trim[k] <= room + 1e-9);
                    for (int c = 0; c < 2; c++) {
                        double sg = c ? 1 : -1, cx = node.x + trim[k] * ux - sg * h * uy, cy = node.y + trim[k] * uy + sg * h * ux;
                        bad += !has_corner(xy, n, cx, cy);
                    }
                }
                if (longs && node.x == 0 && node.y == 0 && node.degree == (uint32_t)d) {
                    cnt[rot] = n;
                    area[rot] = shoelace(xy, n);
                    bad += n < 3 || area[rot] < -1e-9;
                }
            }
            rs_network_free(ctx, net);
            rs_roads_free(ctx, roads);
        }
        if (!longs || cnt[0] == 0) continue;
        cases++;
        bad += cnt[0] != cnt[1] || fabs(area[0] - area[1]) > 1e-6 * (1 + fabs(area[0]));
    }
    printf("junction areas: %zu random stars of long roads, %zu junction nodes in all, %zu bad\n", cases, nodes, bad);
    CHECKF(cases > 150 && bad == 0, "junction areas: %zu rules broken (%zu stars, %zu nodes)", bad, cases, nodes);
}

/* Distance from (x, y) to the segment (ax, ay)-(bx, by). */
static double seg_d(double x, double y, double ax, double ay, double bx, double by)
{
    double dx = bx - ax, dy = by - ay, u = ((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy);
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    return hypot(x - ax - u * dx, y - ay - u * dy);
}

/* A T on a bent street: a side road ending where the through road turns
 * by 15 to 40 degrees. The through road's lines within its inner part
 * (hw - 2.5 m of the centre line) run on across the mouth as on a straight
 * one: the image there is the through road's alone. */
static void test_bent_tee_lines(void)
{
    int worst_all = 0;
    for (int bi = 0; bi < 8; bi++)
        for (int rev = 0; rev < 2; rev++) {
            static const double bend[8] = { 15, 40, -20, -35, 0, 0, 0, 0 }, side_deg[8] = { 90, 90, 90, 90, 45, 60, 135, 30 };
            double beta = bend[bi] * 3.14159265358979323846 / 180, sd = side_deg[bi] * 3.14159265358979323846 / 180;
            double side_xy[4] = { 41.3 + 38 * cos(sd), 40 + 38 * sin(sd), 41.3, 40 };
            double xy[6] = { 2, 40, 41.3, 40, 41.3 + 40 * cos(beta), 40 - 40 * sin(beta) };
            if (rev)
                for (int k = 0; k < 2; k++) {
                    double t = xy[k], u = xy[4 + k];
                    xy[k] = u, xy[4 + k] = t;
                }
            rs_roads *alone = NULL, *tee = NULL;
            CHECK(rs_roads_create(ctx, &alone) == RS_OK && rs_roads_create(ctx, &tee) == RS_OK);
            add_cls(alone, 7.5, "primary", xy, 3);
            add_cls(tee, 7.5, "primary", xy, 3);
            add_cls(tee, 6.5, "secondary", side_xy, 2);
            image a = { 0 }, b = { 0 };
            CHECK(render(alone, NULL, &a) && render(tee, NULL, &b));
            int inner = 0, mouth = 0, beyond = 0;
            double keep = 7.5 / 2 - 2.0;
            for (uint32_t py = 0; a.rgba && b.rgba && py < a.h; py++)
                for (uint32_t px = 0; px < a.w; px++) {
                    double x = (px + 0.5) / TEX, y = (py + 0.5) / TEX;
                    if (hypot(x - 41.3, y - 40) > 6) continue;
                    double d = fmin(seg_d(x, y, xy[0], xy[1], xy[2], xy[3]), seg_d(x, y, xy[2], xy[3], xy[4], xy[5]));
                    const uint8_t *p = a.rgba + 4 * ((size_t)py * a.w + px), *q = b.rgba + 4 * ((size_t)py * a.w + px);
                    int dd = 0;
                    for (int c = 0; c < 3; c++) dd = abs(p[c] - q[c]) > dd ? abs(p[c] - q[c]) : dd;
                    /* outside both roads (the side road's strip trimmed at the far edge) */
                    if (d > 7.5 / 2 + 0.25 && seg_d(x, y, side_xy[0], side_xy[1], side_xy[2], side_xy[3]) > 6.5 / 2 + 0.25)
                        beyond = dd > beyond ? dd : beyond;
                    /* the edge line in the side road's mouth (away from its corners) */
                    if (d > 7.5 / 2 - 0.5 && d < 7.5 / 2 - 0.1 &&
                        seg_d(x, y, side_xy[0], side_xy[1], side_xy[2], side_xy[3]) < 6.5 / 2 - 0.75)
                        mouth = dd > mouth ? dd : mouth;
                    if (d > keep - 0.5) continue;
                    inner = dd > inner ? dd : inner;
                }
            printf("T on a street bent by %.0f degrees, side road at %.0f (%s): inner lines differ by %d/255, the "
                   "edge line in the mouth by %d/255, beyond both roads by %d/255\n",
                   bend[bi], side_deg[bi], rev ? "reversed" : "forward", inner, mouth, beyond);
            worst_all = inner > worst_all ? inner : worst_all;
            if (bi == 3 || bi == 7) { /* (RS_NETWORK_PPM: pictures of two of them) */
                char nm[64];
                snprintf(nm, sizeof nm, "network_bent_tee_%d%s.ppm", bi, rev ? "r" : "");
                save_ppm(nm, &b);
            }
            CHECKF(beyond <= 8, "T on a bent street (%.0f, side at %.0f): %d/255 outside both roads", bend[bi],
                   side_deg[bi], beyond);
            CHECKF(mouth > 60, "T on a bent street (%.0f, side at %.0f): the edge line runs on over the mouth (%d/255)",
                   bend[bi], side_deg[bi], mouth);
            free(a.rgba);
            free(b.rgba);
            rs_roads_free(ctx, alone);
            rs_roads_free(ctx, tee);
        }
    CHECKF(worst_all <= 8, "T on a bent street: the through road's inner lines differ by %d/255", worst_all);
}

/* Bridges and layers (docs/network.md "Bridges and layers"): a street
 * ending under a bridge (layer=1, or bridge=yes alone) or over a tunnel's
 * level (layer=-1) meets nothing there, an end on its centre line within
 * the tolerance neither; on one level both are T's. layer= that is not a
 * whole number -100..100 counts as none, bridge=no as no bridge. */
static void test_levels(void)
{
    static const char *const over[] = { " layer=1", " bridge=yes", " layer=-1", " layer=2 bridge=no", "",
                                        " layer=abc", " bridge=no", " layer=1e3" };
    for (size_t v = 0; v < sizeof over / sizeof over[0]; v++) {
        int apart = v < 4;
        for (int on_line = 0; on_line < 2; on_line++) {
            char text[512];
            /* the street ends 2 m inside the 7 m road, or on its centre line */
            snprintf(text, sizeof text,
                     "road b width 7 class=secondary%s\n50 2\n50 58\nend\n"
                     "road s width 6 class=residential\n75 45\n%s 45\nend\n", over[v], on_line ? "50" : "52");
            rs_roads *roads = NULL;
            rs_network *net = NULL;
            CHECK(rs_roads_parse(ctx, text, strlen(text), &roads) == RS_OK);
            CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK && net_consistent(net, roads));
            size_t tees = 0;
            for (size_t i = 0; net && i < rs_network_node_count(net); i++) {
                rs_network_node nd;
                rs_network_get_node(net, i, &nd);
                tees += nd.degree == 3;
            }
            CHECKF(tees == (apart ? 0u : 1u), "'%s', the end %s: %zu T nodes, want %d", over[v],
                   on_line ? "on the centre line" : "inside the surface", tees, apart ? 0 : 1);
            rs_network_free(ctx, net);
            rs_roads_free(ctx, roads);
        }
    }
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_tee_tolerance();
    test_end_tolerance();
    test_random_splits();
    test_roundabout();
    test_self_touch();
    test_degenerate();
    test_alloc_failures();
    test_split_draws_alike();
    test_tee_lines();
    test_end_inside_surface();
    test_tee_two_looks();
    test_reversed_records();
    test_corner_rule();
    test_cut_near_corner();
    test_short_record_between();
    test_short_record_at_end();
    test_crumbs_short_road();
    test_crumbs_road();
    test_tee_splits();
    test_junction_area();
    test_bent_tee_lines();
    test_levels();
    rs_ctx_free(ctx);
    return th_finish("test_network");
}
