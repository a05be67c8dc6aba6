/* The network after an edit, updated in place (rs__network_update,
 * lib/scene/network.c; docs/network.md "After an edit"): on a 1000-road
 * city, chains of edits (a road removed, added, moved, reclassed; added
 * ones ending on other roads, inside their surfaces, or closed as rings),
 * each update against a network built anew, array by array; a ring broken
 * far from an end that lies inside it near its seam (the end's T goes:
 * the rule reads the ring); a short record near the edit or far from it
 * (declined); and that most edits are updated, not declined. */
#include "roadsplat.h"
#include "harness.h"
#include "internal.h"
#include "network.h"
#include "scene_splat.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX

static rs_ctx *ctx;
static uint64_t rng = 0x9E3779B97F4A7C15ull;

static double rnd(void)
{
    rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
    return (double)(rng >> 11) * (1.0 / 9007199254740992.0);
}

/* Per road: its points' box (4 doubles), the widest road into *w. */
static double *boxes(const rs_roads *R, double *w)
{
    size_t n = rs_roads_count(R);
    double *b = malloc((n ? n : 1) * 4 * sizeof *b);
    if (!b) return NULL;
    for (size_t i = 0; i < n; i++) {
        const double *xy;
        size_t np;
        double wi;
        rs_roads_get(R, i, NULL, &wi, &xy, &np);
        if (wi > *w) *w = wi;
        b[4 * i] = b[4 * i + 1] = INFINITY, b[4 * i + 2] = b[4 * i + 3] = -INFINITY;
        for (size_t k = 0; k < np; k++) {
            b[4 * i] = fmin(b[4 * i], xy[2 * k]), b[4 * i + 1] = fmin(b[4 * i + 1], xy[2 * k + 1]);
            b[4 * i + 2] = fmax(b[4 * i + 2], xy[2 * k]), b[4 * i + 3] = fmax(b[4 * i + 3], xy[2 * k + 1]);
        }
    }
    return b;
}

static void grow_box(double *z, const double *b)
{
    z[0] = fmin(z[0], b[0]), z[1] = fmin(z[1], b[1]), z[2] = fmax(z[2], b[2]), z[3] = fmax(z[3], b[3]);
}

typedef struct tally {
    int updates, spliced, differ;
} tally;

/* *net (the network of the roads before; old_w their widest) updated to
 * `roads` (m_old, m_new; zone: the changed roads' box), against a build:
 * the build replaces *net. Returns whether the update was made (not
 * declined). */
static int step(const rs_roads *roads, rs_network **net, double old_w, const uint32_t *m_old, const uint32_t *m_new,
                const double *zone, tally *T)
{
    double w = old_w;
    double *b = boxes(roads, &w);
    rs_network *u = NULL, *fresh = NULL;
    int made = 0;
    CHECK(b != NULL);
    rs_result r = b ? rs__network_update(ctx, roads, *net, m_old, m_new, b, zone, 0.5 * w, &u) : RS_ERR_NOMEM;
    CHECKF(r == RS_OK, "update: %s", rs_ctx_message(ctx));
    CHECK(rs_network_build(ctx, roads, NULL, &fresh) == RS_OK);
    T->updates++;
    if (u && fresh) {
        made = 1;
        T->spliced++;
        T->differ += !rs__network_equal(u, fresh);
    }
    rs_network_free(ctx, u);
    rs_network_free(ctx, *net);
    *net = fresh;
    free(b);
    return made;
}

/* A random road near (x, y): 2 to 5 points, 10 to 40 m steps. */
static size_t random_road(double x, double y, double *xy)
{
    size_t n = 2 + (size_t)(rnd() * 4);
    double a = rnd() * 6.283185307179586;
    for (size_t k = 0; k < n; k++) {
        xy[2 * k] = x, xy[2 * k + 1] = y;
        a += (rnd() - 0.5) * 0.8;
        double l = 10 + 30 * rnd();
        x += l * cos(a), y += l * sin(a);
    }
    return n;
}

/* Chains of edits on the city; every update against a build. */
static void test_city_edits(void)
{
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_network *net = NULL;
    int ok = ss_city_of(ctx, 161, 141, 1000, 3, 1, &sc, &dem, &roads) == 0 && rs_network_build(ctx, roads, NULL, &net) == RS_OK;
    CHECK(ok);
    double W = sc_extent_x(&sc), H = sc_extent_y(&sc);
    static const char *const cls[] = { "primary", "secondary", "residential", "service" };
    tally T = { 0, 0, 0 };
    int kinds[6] = { 0 };
    for (int e = 0; ok && e < 120; e++) {
        size_t n = rs_roads_count(roads), r = (size_t)(rnd() * (double)n);
        double ow = 0, *ob = boxes(roads, &ow), zone[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
        uint32_t *m_old = malloc((n + 1) * sizeof *m_old), *m_new = malloc((n + 1) * sizeof *m_new);
        ok = ob && m_old && m_new;
        CHECK(ok);
        if (!ok) break;
        for (size_t i = 0; i <= n; i++) m_old[i] = m_new[i] = (uint32_t)i;
        int kind = e % 6;
        double xy[2 * 8];
        size_t np;
        if (kind == 0) { /* removed */
            ok = rs_roads_remove(ctx, roads, r) == RS_OK;
            for (size_t i = 0; i < n; i++) m_old[i] = i < r ? (uint32_t)i : i > r ? (uint32_t)(i - 1) : NONE;
            for (size_t j = 0; j + 1 < n; j++) m_new[j] = j < r ? (uint32_t)j : (uint32_t)(j + 1);
            grow_box(zone, ob + 4 * r);
        } else if (kind == 1 || kind == 2 || kind == 3) { /* added: free, ending on a road, inside its surface, a ring */
            const double *q;
            size_t nq;
            double wq;
            rs_roads_get(roads, r, NULL, &wq, &q, &nq);
            if (kind == 1) {
                np = random_road(0.1 * W + 0.8 * W * rnd(), 0.1 * H + 0.8 * H * rnd(), xy);
            } else {
                /* from a point on road r's first segment: on it, or beside it inside its surface */
                double f = 0.2 + 0.6 * rnd(), px = q[0] + f * (q[2] - q[0]), py = q[1] + f * (q[3] - q[1]);
                double dx = q[2] - q[0], dy = q[3] - q[1], l = hypot(dx, dy);
                double side = kind == 3 && l > 0 ? 0.3 * wq : 0;
                if (l > 0) px += side * -dy / l, py += side * dx / l;
                np = random_road(px, py, xy);
            }
            if (kind == 3 && e % 4 == 3) { /* a ring of 5 points */
                double cx = 0.2 * W + 0.6 * W * rnd(), cy = 0.2 * H + 0.6 * H * rnd();
                np = 6;
                for (size_t k = 0; k < 5; k++)
                    xy[2 * k] = cx + 25 * cos(1.2566 * (double)k), xy[2 * k + 1] = cy + 25 * sin(1.2566 * (double)k);
                xy[10] = xy[0], xy[11] = xy[1];
            }
            ok = rs_roads_add(ctx, roads, "new", 4 + 8 * rnd(), xy, np) == RS_OK &&
                 rs_roads_set_attr(ctx, roads, n, "class", cls[e % 4]) == RS_OK;
            m_new[n] = NONE;
            double b[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
            for (size_t k = 0; k < np; k++)
                b[0] = fmin(b[0], xy[2 * k]), b[1] = fmin(b[1], xy[2 * k + 1]), b[2] = fmax(b[2], xy[2 * k]),
                b[3] = fmax(b[3], xy[2 * k + 1]);
            grow_box(zone, b);
        } else if (kind == 4) { /* moved 5 to 20 m */
            const double *q;
            size_t nq;
            double wq, a = rnd() * 6.283185307179586, d = 5 + 15 * rnd();
            rs_roads_get(roads, r, NULL, &wq, &q, &nq);
            double *p = malloc(2 * nq * sizeof *p);
            ok = p != NULL;
            for (size_t k = 0; ok && k < nq; k++) p[2 * k] = q[2 * k] + d * cos(a), p[2 * k + 1] = q[2 * k + 1] + d * sin(a);
            double b[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
            for (size_t k = 0; ok && k < nq; k++)
                b[0] = fmin(b[0], p[2 * k]), b[1] = fmin(b[1], p[2 * k + 1]), b[2] = fmax(b[2], p[2 * k]),
                b[3] = fmax(b[3], p[2 * k + 1]);
            ok = ok && rs_roads_replace(ctx, roads, r, NULL, wq, p, nq) == RS_OK;
            free(p);
            m_old[r] = m_new[r] = NONE;
            grow_box(zone, ob + 4 * r);
            grow_box(zone, b);
        } else { /* reclassed: its look (strokes) changes, not its place */
            ok = rs_roads_set_attr(ctx, roads, r, "class", cls[(e / 6) % 4]) == RS_OK;
            m_old[r] = m_new[r] = NONE;
            grow_box(zone, ob + 4 * r);
        }
        CHECKF(ok, "edit %d: %s", e, rs_ctx_message(ctx));
        if (ok) kinds[kind] += step(roads, &net, ow, m_old, m_new, zone, &T);
        free(ob);
        free(m_old);
        free(m_new);
    }
    printf("  city: %d edits, %d updated in place (remove %d, add %d, on a road %d, in a surface or a ring %d, "
           "move %d, reclass %d), %d differ from a build\n",
           T.updates, T.spliced, kinds[0], kinds[1], kinds[2], kinds[3], kinds[4], kinds[5], T.differ);
    CHECK(T.differ == 0);
    CHECKF(T.spliced >= T.updates * 9 / 10, "only %d of %d edits updated in place", T.spliced, T.updates);
    rs_network_free(ctx, net);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
}

/* A ring road of 16 records (a circle of 100 m, each record 4 points),
 * a road ending inside its surface beside the ring's seam (the first
 * point of its first record), and edits on the far side of the ring:
 * one of its records removed (the ring opens: the seam is a free end
 * then, and the end beside it is no T) and added back. */
static void test_ring_seam(void)
{
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    const double R = 100, cx = 500, cy = 500;
    for (int k = 0; k < 16; k++) {
        double xy[8];
        for (int j = 0; j < 4; j++) {
            double a = 6.283185307179586 * (k + j / 3.0) / 16;
            xy[2 * j] = cx + R * cos(a), xy[2 * j + 1] = cy + R * sin(a);
        }
        CHECK(rs_roads_add(ctx, roads, "ring", 10, xy, 4) == RS_OK);
    }
    /* from outside, ending 3 m inside the ring's centre line (within its 5 m half width), by the seam */
    double side[4] = { cx + R + 40, cy + 1, cx + R - 3, cy + 1 };
    CHECK(rs_roads_add(ctx, roads, "side", 6, side, 2) == RS_OK);
    rs_network *net = NULL;
    CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK);
    CHECK(net && net->nstrokes == 2 && net->closed[net->stroke_of[0]]);
    size_t n = rs_roads_count(roads);
    tally T = { 0, 0, 0 };
    /* the record opposite the seam (8) removed, then added back (at the end) */
    const double *q;
    size_t nq;
    double wq, ow = 0, *ob = boxes(roads, &ow), zone[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
    rs_roads_get(roads, 8, NULL, &wq, &q, &nq);
    double keep[8];
    memcpy(keep, q, sizeof keep);
    uint32_t m_old[32], m_new[32];
    for (size_t i = 0; i < n; i++) m_old[i] = i < 8 ? (uint32_t)i : i > 8 ? (uint32_t)(i - 1) : NONE;
    for (size_t j = 0; j + 1 < n; j++) m_new[j] = j < 8 ? (uint32_t)j : (uint32_t)(j + 1);
    grow_box(zone, ob + 4 * 8);
    CHECK(rs_roads_remove(ctx, roads, 8) == RS_OK);
    int made = step(roads, &net, ow, m_old, m_new, zone, &T);
    CHECK(made);
    CHECK(net && !net->closed[net->stroke_of[0]]);
    free(ob);
    ow = 0;
    ob = boxes(roads, &ow);
    for (size_t i = 0; i + 1 < n; i++) m_old[i] = (uint32_t)i, m_new[i] = (uint32_t)i;
    m_new[n - 1] = NONE;
    CHECK(rs_roads_add(ctx, roads, "ring", 10, keep, 4) == RS_OK);
    made = step(roads, &net, ow, m_old, m_new, zone, &T);
    CHECK(made);
    free(ob);
    printf("  ring seam: %d edits, %d updated in place, %d differ from a build\n", T.updates, T.spliced, T.differ);
    CHECK(T.differ == 0);
    rs_network_free(ctx, net);
    rs_roads_free(ctx, roads);
}

/* A short record (0.05 m) near an edit or far from it: declined (a build
 * with one joins places and chains records across the map). */
static void test_short_record(void)
{
    for (int near = 0; near < 2; near++) {
        rs_roads *roads = NULL;
        CHECK(rs_roads_create(ctx, &roads) == RS_OK);
        double a[4] = { 0, 0, 100, 0 }, s[4] = { 100, 0, 100.05, 0 }, b[4] = { 100.05, 0, 200, 0 };
        CHECK(rs_roads_add(ctx, roads, "a", 6, a, 2) == RS_OK && rs_roads_add(ctx, roads, "s", 6, s, 2) == RS_OK &&
              rs_roads_add(ctx, roads, "b", 6, b, 2) == RS_OK);
        rs_network *net = NULL;
        CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK);
        double ow = 0, *ob = boxes(roads, &ow);
        double c[4] = { near ? 101 : 1000, near ? 5 : 30, near ? 101 : 1000, near ? 60 : 90 };
        double zone[4] = { c[0], c[1], c[2], c[3] };
        uint32_t m_old[4] = { 0, 1, 2, 3 }, m_new[4] = { 0, 1, 2, NONE };
        CHECK(rs_roads_add(ctx, roads, "c", 6, c, 2) == RS_OK);
        tally T = { 0, 0, 0 };
        int made = step(roads, &net, ow, m_old, m_new, zone, &T);
        CHECKF(!made, "short record %s the edit: updated", near ? "near" : "far from");
        CHECK(T.differ == 0);
        free(ob);
        rs_network_free(ctx, net);
        rs_roads_free(ctx, roads);
    }
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_city_edits();
    test_ring_seam();
    test_short_record();
    rs_ctx_free(ctx);
    return th_finish("test_network_update");
}
