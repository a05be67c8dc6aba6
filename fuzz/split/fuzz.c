/* libFuzzer target: a road split into records draws as the road whole
 * (issue 27 target 1: lines, dashes, strips, markings, caps; no pixel off
 * by more than 8/255). One road of 2..6 points (turning at most 60 degrees
 * at a vertex, never within its width of itself: a road, not a knot) on a
 * 31 x 23 m map of 1 m cells at 8 texels (0.125 m pixels), with a class,
 * lanes and optionally
 * one-way (its attributes on every record), drawn as one record and as
 * records split at 1..4 points inside its segments (every other record
 * reversed when it is two-way with an even lane count), analytic edges,
 * the class styles with their automatic markings.
 *
 * Input (short input reads as zero bytes):
 *   0     flags: bits 0-2 class, bit 3 one-way, bits 4-5 lanes - 1, bit 6
 *         reverse some records, bit 7 the US profile
 *   1     points - 2 (mod 5)    2  width: 2 + b / 16 m
 *   then  2 bytes a point (x: b * 30 / 255 m, y: b * 22 / 255 m)
 *   then  splits - 1 (mod 4), and 2 bytes a split: its segment (mod the
 *         count) and where in it ((b + 1) / 257 of its length)
 *   then  crumbs: 0 none, else b * 4 more cuts every (b' + 1) / 2560 m
 *         from (b'' / 256) m on (records of at most 0.1 m: a road cut into
 *         crumbs, docs/network.md "Degenerate records")
 * Findings (abort): a pixel of the split drawing more than 8/255 from the
 * whole one in a colour channel, or a result code other than RS_OK for
 * the whole road when the split one succeeds (or the reverse). */
#include "roadsplat.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define REQUIRE(c) do { if (!(c)) abort(); } while (0)
#define DW 32
#define DH 24
#define TEX 8

typedef struct reader {
    const uint8_t *p;
    size_t n, i;
} reader;

static uint8_t next(reader *r)
{
    return r->i < r->n ? r->p[r->i++] : 0;
}

static double pt_seg(const double *p, const double *s)
{
    double dx = s[2] - s[0], dy = s[3] - s[1], l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((p[0] - s[0]) * dx + (p[1] - s[1]) * dy) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(p[0] - s[0] - t * dx, p[1] - s[1] - t * dy);
}

/* Distance between segments a (a[0..3]) and b (b[0..3]); 0 when they cross. */
static double seg_seg_dist(const double *a, const double *b)
{
    double d1 = (a[2] - a[0]) * (b[1] - a[1]) - (a[3] - a[1]) * (b[0] - a[0]);
    double d2 = (a[2] - a[0]) * (b[3] - a[1]) - (a[3] - a[1]) * (b[2] - a[0]);
    double d3 = (b[2] - b[0]) * (a[1] - b[1]) - (b[3] - b[1]) * (a[0] - b[0]);
    double d4 = (b[2] - b[0]) * (a[3] - b[1]) - (b[3] - b[1]) * (a[2] - b[0]);
    if (((d1 < 0) != (d2 < 0)) && ((d3 < 0) != (d4 < 0))) return 0;
    double m = fmin(pt_seg(a, b), pt_seg(a + 2, b));
    return fmin(m, fmin(pt_seg(b, a), pt_seg(b + 2, a)));
}

static const char *const classes[8] = { "primary",     "secondary", "tertiary", "residential",
                                        "unclassified", "service",   "living_street", "trunk" };

/* One record of np points pts (reversed when rev) with the road's
 * attributes. */
static rs_result add_one(rs_ctx *ctx, rs_roads *roads, const double *pts, size_t np, int rev, double width,
                         const char *cls, const char *lanes, int oneway)
{
    double q[2 * 16];
    for (size_t i = 0; i < np; i++) {
        size_t j = rev ? np - 1 - i : i;
        q[2 * i] = pts[2 * j], q[2 * i + 1] = pts[2 * j + 1];
    }
    rs_result r = rs_roads_add(ctx, roads, "r", width, q, np);
    size_t id = rs_roads_count(roads) - 1;
    if (!r) r = rs_roads_set_attr(ctx, roads, id, "class", cls);
    if (!r) r = rs_roads_set_attr(ctx, roads, id, "lanes", lanes);
    if (!r && oneway) r = rs_roads_set_attr(ctx, roads, id, "oneway", "yes");
    return r;
}

/* The road's records into `roads`: cut points (segment seg[k], fraction
 * f[k], sorted along the road) split it; rev reverses every other record. */
static rs_result add_records(rs_ctx *ctx, rs_roads *roads, const double *xy, size_t n, double width,
                             const size_t *seg, const double *f, size_t ncut, int rev, const char *cls,
                             const char *lanes, int oneway)
{
    double pts[2 * 16];
    size_t m = 0, c = 0, rec = 0;
    pts[m++] = xy[0], pts[m++] = xy[1];
    for (size_t k = 0; k + 1 < n; k++) {
        for (; c < ncut && seg[c] == k; c++) {
            double x = xy[2 * k] + f[c] * (xy[2 * k + 2] - xy[2 * k]), y = xy[2 * k + 1] + f[c] * (xy[2 * k + 3] - xy[2 * k + 1]);
            pts[m++] = x, pts[m++] = y;
            /* a record ends here; the next starts here */
            rs_result r = add_one(ctx, roads, pts, m / 2, rev && (rec & 1), width, cls, lanes, oneway);
            if (r) return r;
            rec++;
            m = 0;
            pts[m++] = x, pts[m++] = y;
        }
        pts[m++] = xy[2 * k + 2], pts[m++] = xy[2 * k + 3];
    }
    return add_one(ctx, roads, pts, m / 2, rev && (rec & 1), width, cls, lanes, oneway);
}

static rs_result draw(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, int us, uint8_t **rgba, uint32_t *w,
                      uint32_t *h)
{
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = TEX;
    o.style.profile = us ? RS_PROFILE_MUTCD : RS_PROFILE_RMS;
    rs_splatter *s = NULL;
    rs_result r = rs_splatter_create(ctx, dem, roads, NULL, &o, &s);
    if (!r) {
        rs_splatter_size(s, w, h);
        *rgba = malloc((size_t)*w * *h * 4);
        REQUIRE(*rgba);
        r = rs_splat_window(ctx, s, 0, 0, *w, *h, *rgba, (size_t)*w * 4, NULL, 0, NULL);
    }
    rs_splatter_free(ctx, s);
    return r;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    reader rd = { data, size, 0 };
    uint8_t flags = next(&rd);
    size_t n = 2 + next(&rd) % 5;
    double width = 2 + next(&rd) / 16.0, xy[12];
    for (size_t k = 0; k < n; k++) xy[2 * k] = next(&rd) * 30.0 / 255, xy[2 * k + 1] = next(&rd) * 22.0 / 255;
    size_t ncut = 1 + next(&rd) % 4, seg[4 + 1020];
    double f[4 + 1020];
    for (size_t c = 0; c < ncut; c++) {
        seg[c] = next(&rd) % (n - 1);
        f[c] = (next(&rd) + 1) / 257.0;
    }
    /* crumbs: evenly spaced cuts by arc length (inside segments) */
    size_t ncrumb = 4 * (size_t)next(&rd);
    double step = (next(&rd) + 1) / 2560.0, at0 = next(&rd) / 256.0;
    for (size_t c = 0, k = 0; c < ncrumb; c++) {
        double at = at0 + (double)(c + 1) * step, acc = 0;
        for (k = 0; k + 1 < n; k++) {
            double l = hypot(xy[2 * k + 2] - xy[2 * k], xy[2 * k + 3] - xy[2 * k + 1]);
            if (at < acc + l) break;
            acc += l;
        }
        if (k + 1 >= n) break;
        double l = hypot(xy[2 * k + 2] - xy[2 * k], xy[2 * k + 3] - xy[2 * k + 1]), fr = (at - acc) / l;
        if (!(fr > 0 && fr < 1)) continue;
        seg[ncut] = k, f[ncut] = fr, ncut++;
    }
    /* sorted along the road (insertion sort) */
    for (size_t a = 1; a < ncut; a++)
        for (size_t b = a; b > 0 && (seg[b] < seg[b - 1] || (seg[b] == seg[b - 1] && f[b] < f[b - 1])); b--) {
            size_t ts = seg[b];
            double tf = f[b];
            seg[b] = seg[b - 1], f[b] = f[b - 1];
            seg[b - 1] = ts, f[b - 1] = tf;
        }
    /* the same cut twice is one cut */
    size_t m = 0;
    for (size_t c = 0; c < ncut; c++)
        if (!m || seg[c] != seg[m - 1] || f[c] != f[m - 1]) seg[m] = seg[c], f[m] = f[c], m++;
    ncut = m;
    /* a segment of zero length has nowhere to cut */
    for (size_t c = 0; c < ncut; c++)
        if (xy[2 * seg[c]] == xy[2 * seg[c] + 2] && xy[2 * seg[c] + 1] == xy[2 * seg[c] + 3]) return 0;
    /* A road, not a knot: turns of at most 60 degrees at its vertices and
     * no part of it within its width of a part two or more segments away
     * (a road folded over itself has lines that cross its own surface,
     * where which stroke a piece belongs to decides; issue 27 target 1 is
     * about straight and curved roads) */
    for (size_t k = 1; k + 1 < n; k++) {
        double ux = xy[2 * k] - xy[2 * k - 2], uy = xy[2 * k + 1] - xy[2 * k - 1];
        double vx = xy[2 * k + 2] - xy[2 * k], vy = xy[2 * k + 3] - xy[2 * k + 1];
        double lu = hypot(ux, uy), lv = hypot(vx, vy);
        if (!(lu > 0 && lv > 0) || (ux * vx + uy * vy) < 0.5 * lu * lv) return 0;
    }
    for (size_t a = 0; a + 1 < n; a++)
        for (size_t b = a + 2; b + 1 < n; b++)
            if (seg_seg_dist(xy + 2 * a, xy + 2 * b) < width) return 0;
    const char *cls = classes[flags & 7];
    const char lanes[2] = { (char)('1' + ((flags >> 4) & 3)), 0 };
    /* a reversed record of a one-way road, or of an odd lane count (which
     * lanes go forward depends on the record's direction, as in OSM), is
     * another road: reversed records only with an even count both ways */
    int oneway = (flags >> 3) & 1, rev = !oneway && ((flags >> 4) & 1) && ((flags >> 6) & 1), us = flags >> 7;

    rs_ctx *ctx = NULL;
    REQUIRE(rs_ctx_create(NULL, NULL, &ctx) == RS_OK);
    static float z[DW * DH];
    rs_dem *dem = NULL;
    rs_dem_frame fr = { 1, 1, 0, 0 };
    REQUIRE(rs_dem_create(ctx, DW, DH, z, &dem) == RS_OK && rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    rs_roads *whole = NULL, *split = NULL;
    REQUIRE(rs_roads_create(ctx, &whole) == RS_OK && rs_roads_create(ctx, &split) == RS_OK);
    rs_result ra = add_records(ctx, whole, xy, n, width, seg, f, 0, 0, cls, lanes, oneway);
    rs_result rb = add_records(ctx, split, xy, n, width, seg, f, ncut, rev, cls, lanes, oneway);
    uint8_t *a = NULL, *b = NULL;
    uint32_t w = 0, h = 0;
    if (!ra && !rb) {
        ra = draw(ctx, dem, whole, us, &a, &w, &h);
        rb = draw(ctx, dem, split, us, &b, &w, &h);
        REQUIRE((ra == RS_OK) == (rb == RS_OK));
        if (!ra && !rb)
            for (size_t p = 0; p < (size_t)w * h * 4; p++) REQUIRE(abs((int)a[p] - (int)b[p]) <= 8);
    }
    free(a);
    free(b);
    rs_roads_free(ctx, whole);
    rs_roads_free(ctx, split);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    return 0;
}
