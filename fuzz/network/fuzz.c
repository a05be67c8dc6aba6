/* libFuzzer target: rs_network_build on the roads of arbitrary road text,
 * at the default tolerance and at one read from the first byte. Checks the
 * network's invariants: every leg names a valid road and is sorted by
 * angle, degrees and kinds agree, strokes partition the records with
 * consistent prev/next links and s offsets that add up the records'
 * lengths, a second build gives the same network (determinism), and
 * every junction area has at most two corners a leg, none NaN, its trims
 * within the legs' lengths, the same count with and without a buffer.
 * And the network after an edit (rs__network_update, lib/scene/network.c):
 * one road (chosen by the last byte) removed, and added back, the network
 * updated in place from the one before equals one built anew. */
#include "roadsplat.h"
#include "network.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check(const rs_network *net, size_t n)
{
    if (rs_network_road_count(net) != n) abort();
    for (size_t i = 0; i < rs_network_node_count(net); i++) {
        rs_network_node nd;
        if (rs_network_get_node(net, i, &nd) != RS_OK || nd.degree < 1 || !isfinite(nd.x) || !isfinite(nd.y)) abort();
        if (nd.kind != (nd.degree == 1 ? RS_NODE_END : nd.degree == 2 ? RS_NODE_CONTINUATION : RS_NODE_JUNCTION)) abort();
        double prev = -4;
        int majors = 0;
        for (size_t k = 0; k < nd.degree; k++) {
            rs_network_leg L;
            if (rs_network_get_leg(net, i, k, &L) != RS_OK || L.road >= n || !(L.angle >= prev) || !(L.angle <= 3.1416))
                abort();
            rs_road_stroke st;
            if (rs_network_road_stroke(net, L.road, &st) != RS_OK || !(L.s >= 0) || !(L.s <= st.length * (1 + 1e-12)))
                abort();
            prev = L.angle;
            majors += L.major;
        }
        if (majors < 1) abort();
    }
    uint32_t *recs = malloc((n + 1) * sizeof *recs);
    uint8_t *seen = calloc(n + 1, 1);
    if (!recs || !seen) abort();
    size_t total = 0;
    for (size_t k = 0; k < rs_network_stroke_count(net); k++) {
        size_t m = rs_network_stroke_roads(net, k, recs, n);
        if (m < 1 || m > n) abort();
        double s = 0;
        for (size_t i = 0; i < m; i++) {
            rs_road_stroke st;
            if (recs[i] >= n || seen[recs[i]]) abort();
            seen[recs[i]] = 1;
            if (rs_network_road_stroke(net, recs[i], &st) != RS_OK || st.stroke != k) abort();
            if (st.prev != (i ? recs[i - 1] : UINT32_MAX) || st.next != (i + 1 < m ? recs[i + 1] : UINT32_MAX)) abort();
            /* offsets are the sums of the lengths before (monotone); a reversed
             * record's first point is at its far end */
            double s0 = st.reversed ? s + st.length : s;
            if (!(st.s_offset >= s0 * (1 - 1e-12)) || !(st.s_offset <= s0 * (1 + 1e-12)) || !(st.length >= 0)) abort();
            s += st.length;
        }
        total += m;
    }
    if (total != n) abort();
    free(recs);
    free(seen);
}

static void check_areas(const rs_network *net, const rs_roads *roads)
{
    double xy[2 * 64], trim[32];
    for (size_t i = 0; i < rs_network_node_count(net); i++) {
        rs_network_node nd;
        if (rs_network_get_node(net, i, &nd) != RS_OK) abort();
        size_t n0 = rs_network_junction_area(net, roads, i, NULL, 0, NULL);
        if (nd.degree < 3 ? n0 != 0 : n0 > 2 * (size_t)nd.degree) abort();
        if (nd.degree < 3 || nd.degree > 32) continue;
        size_t n = rs_network_junction_area(net, roads, i, xy, 64, trim);
        if (n != n0) abort();
        for (size_t k = 0; k < n; k++)
            if (xy[2 * k] != xy[2 * k] || xy[2 * k + 1] != xy[2 * k + 1]) abort();
        for (uint32_t k = 0; k < nd.degree; k++) {
            rs_network_leg L;
            rs_road_stroke st;
            if (rs_network_get_leg(net, i, k, &L) != RS_OK || rs_network_road_stroke(net, L.road, &st) != RS_OK) abort();
            if (!(trim[k] >= 0) || !(trim[k] <= st.length)) abort();
        }
    }
}

static int same(const rs_network *a, const rs_network *b)
{
    if (rs_network_node_count(a) != rs_network_node_count(b) || rs_network_stroke_count(a) != rs_network_stroke_count(b))
        return 0;
    for (size_t i = 0; i < rs_network_node_count(a); i++) {
        rs_network_node x, y;
        rs_network_get_node(a, i, &x);
        rs_network_get_node(b, i, &y);
        if (x.x != y.x || x.y != y.y || x.degree != y.degree || x.kind != y.kind || x.control != y.control) return 0;
        for (size_t k = 0; k < x.degree; k++) {
            rs_network_leg p, q;
            rs_network_get_leg(a, i, k, &p);
            rs_network_get_leg(b, i, k, &q);
            if (p.road != q.road || p.kind != q.kind || p.segment != q.segment || p.s != q.s || p.angle != q.angle ||
                p.priority != q.priority || p.major != q.major)
                return 0;
        }
    }
    for (size_t r = 0; r < rs_network_road_count(a); r++) {
        rs_road_stroke p, q;
        rs_network_road_stroke(a, r, &p);
        rs_network_road_stroke(b, r, &q);
        /* (fields, not bytes: the structs have padding) */
        if (p.stroke != q.stroke || p.s_offset != q.s_offset || p.length != q.length || p.prev != q.prev ||
            p.next != q.next || p.closed != q.closed || p.reversed != q.reversed)
            return 0;
    }
    return 1;
}

/* Per road of R: its points' box; the widest road. */
static double *boxes(const rs_roads *R, double *wmax)
{
    size_t n = rs_roads_count(R);
    double *b = malloc((n ? n : 1) * 4 * sizeof *b);
    if (!b) abort();
    *wmax = 0;
    for (size_t i = 0; i < n; i++) {
        const double *xy;
        size_t np;
        double w;
        rs_roads_get(R, i, NULL, &w, &xy, &np);
        *wmax = w > *wmax || w != w ? w : *wmax;
        b[4 * i] = b[4 * i + 1] = INFINITY, b[4 * i + 2] = b[4 * i + 3] = -INFINITY;
        for (size_t k = 0; k < np; k++) {
            b[4 * i] = fmin(b[4 * i], xy[2 * k]), b[4 * i + 1] = fmin(b[4 * i + 1], xy[2 * k + 1]);
            b[4 * i + 2] = fmax(b[4 * i + 2], xy[2 * k]), b[4 * i + 3] = fmax(b[4 * i + 3], xy[2 * k + 1]);
        }
    }
    return b;
}

/* Network a of `roads` updated to the roads without road r, and the
 * network of those updated to `roads`: each what a build makes (when the
 * update can; it may decline). */
static void check_update(rs_ctx *ctx, const rs_roads *roads, const rs_network_options *o, const rs_network *a, size_t r)
{
    size_t n = rs_roads_count(roads);
    uint32_t *ids = malloc(n * sizeof *ids), *m_big = malloc(n * sizeof *m_big), *m_less = malloc(n * sizeof *m_less);
    if (!ids || !m_big || !m_less) abort();
    for (size_t i = 0, j = 0; i < n; i++) {
        m_big[i] = i == r ? UINT32_MAX : (uint32_t)j;
        if (i != r) m_less[j] = (uint32_t)i, ids[j++] = (uint32_t)i;
    }
    rs_roads *less = NULL;
    rs_network *b = NULL, *u = NULL;
    double wa, wb, *ba = boxes(roads, &wa), *bb = NULL;
    if (rs__roads_subset(ctx, roads, ids, n - 1, &less) != RS_OK || rs_network_build(ctx, less, o, &b) != RS_OK) abort();
    bb = boxes(less, &wb);
    double w = wa != wa || wb != wb ? NAN : fmax(wa, wb), zone[4];
    memcpy(zone, ba + 4 * r, sizeof zone);
    if (rs__network_update(ctx, less, a, m_big, m_less, bb, zone, 0.5 * w, &u) != RS_OK) abort();
    if (u && !rs__network_equal(u, b)) abort();
    rs_network_free(ctx, u);
    u = NULL;
    if (rs__network_update(ctx, roads, b, m_less, m_big, ba, zone, 0.5 * w, &u) != RS_OK) abort();
    if (u && !rs__network_equal(u, a)) abort();
    rs_network_free(ctx, u);
    rs_network_free(ctx, b);
    rs_roads_free(ctx, less);
    free(ba);
    free(bb);
    free(ids);
    free(m_big);
    free(m_less);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rs_limits lim = { 0 };
    lim.max_points = 20000;
    lim.max_line_length = 4096;
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, &lim, &ctx) != RS_OK) return 0;
    rs_roads *roads = NULL;
    if (rs_roads_parse(ctx, (const char *)data, size, &roads) == RS_OK) {
        /* tolerances 0 (default), then 2^-20 .. 2^5 metres from the first byte */
        double tols[2] = { 0, size ? ldexp(1, (int)(data[0] % 26) - 20) : 1 };
        for (int t = 0; t < 2; t++) {
            rs_network_options o = { 0, tols[t] };
            rs_network *a = NULL, *b = NULL;
            if (rs_network_build(ctx, roads, &o, &a) != RS_OK || rs_network_build(ctx, roads, &o, &b) != RS_OK) abort();
            check(a, rs_roads_count(roads));
            check_areas(a, roads);
            if (!same(a, b)) abort();
            size_t n = rs_roads_count(roads);
            if (n) check_update(ctx, roads, &o, a, data[size - 1] % n);
            rs_network_free(ctx, a);
            rs_network_free(ctx, b);
        }
        rs_roads_free(ctx, roads);
    }
    rs_ctx_free(ctx);
    return 0;
}
