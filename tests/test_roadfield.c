/* Road field (lib/scene/roadfield.c): nearest-centreline queries against a brute
 * force over every segment, coverage against the exact ground truth
 * (tests/groundtruth.c), translation and tiling invariance, extreme input,
 * allocation failures. */
#include "harness.h"
#include "fail_alloc.h"
#include "groundtruth.h"
#include "roadfield.h"
#include "roadgrid.h"
#include "scenes.h"
#include "styling.h"

#include <math.h>
#include <stdlib.h>

static rs_ctx *ctx;

/* --- brute force (independent of lib/scene/roadfield.c) ---------------------------- */
typedef struct bf_hit {
    int found;
    size_t road, seg;
    double s, t, dist;
} bf_hit;

/* Local coordinates exactly as the library must make them (rs__local_coord). */
static bf_hit brute_nearest(const rs_roads *roads, double ox, double oy, double cs, double x, double y, double reach)
{
    bf_hit best;
    memset(&best, 0, sizeof best);
    double q = rs__local_quantum(cs);
    for (size_t r = 0; r < rs_roads_count(roads); r++) {
        const double *xy;
        size_t n;
        double w;
        rs_roads_get(roads, r, NULL, &w, &xy, &n);
        double s0 = 0;
        for (size_t k = 0; k + 1 < n; k++) {
            double ax = rs__local_coord(xy[2 * k], ox, q), ay = rs__local_coord(xy[2 * k + 1], oy, q);
            double bx = rs__local_coord(xy[2 * k + 2], ox, q), by = rs__local_coord(xy[2 * k + 3], oy, q);
            double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy, len = sqrt(l2);
            double u = l2 > 0 ? ((x - ax) * dx + (y - ay) * dy) / l2 : 0, qx, qy;
            if (u <= 0) { u = 0; qx = ax; qy = ay; }
            else if (u >= 1) { u = 1; qx = bx; qy = by; }
            else { qx = ax + u * dx; qy = ay + u * dy; }
            double d = hypot(x - qx, y - qy);
            if (d - 0.5 * w <= reach && (!best.found || d < best.dist)) {
                double cross = len > 0 ? ((x - ax) * dy - (y - ay) * dx) / len : 0;
                best.found = 1; best.road = r; best.seg = k; best.dist = d;
                best.s = s0 + u * len;
                best.t = cross >= 0 ? d : -d;
            }
            s0 += len;
        }
    }
    return best;
}

/* --- random scenes --------------------------------------------------------------- */
/* Roads inside and around a W x H map: ordinary polylines, sharp bends
 * (170 degrees), repeated points, and a few roads 1e6 m long. Points are
 * whole millimetres (like the city scene), shifted by (ox, oy). */
static rs_roads *random_roads(sc_rng *g, double W, double H, int nroads, double ox, double oy, sc_scene *sc)
{
    rs_roads *roads = NULL;
    if (rs_roads_create(ctx, &roads)) return NULL;
    double xy[2 * 16], loc[2 * 16];
    for (int r = 0; r < nroads; r++) {
        int kind = (int)(sc_rng_unit(g) * 10);
        size_t n = 2 + (size_t)(sc_rng_unit(g) * 9);
        double width = 0.5 * floor(sc_rng_range(g, 2, 20));
        double x = sc_rng_range(g, -10, W + 10), y = sc_rng_range(g, -10, H + 10);
        double ang = sc_rng_range(g, 0, 2 * RS__PI), step = sc_rng_range(g, 2, 40);
        for (size_t k = 0; k < n; k++) {
            loc[2 * k] = floor(x * 1000 + 0.5) / 1000;
            loc[2 * k + 1] = floor(y * 1000 + 0.5) / 1000;
            if (kind == 0 && k % 3 == 1) continue; /* repeated point: zero-length segment */
            double turn = kind == 1 ? (k % 2 ? 1 : -1) * 170 * RS__PI / 180 : sc_rng_range(g, -1, 1);
            ang += turn;
            double len = kind == 2 ? 1e6 : step;
            x += len * cos(ang);
            y += len * sin(ang);
        }
        if (kind == 2) { /* long road through the map: centre it */
            double mx = 0.5 * (loc[0] + loc[2 * n - 2]) - 0.5 * W, my = 0.5 * (loc[1] + loc[2 * n - 1]) - 0.5 * H;
            for (size_t k = 0; k < n; k++) {
                loc[2 * k] = floor((loc[2 * k] - mx) * 1000 + 0.5) / 1000;
                loc[2 * k + 1] = floor((loc[2 * k + 1] - my) * 1000 + 0.5) / 1000;
            }
        }
        for (size_t k = 0; k < n; k++) { xy[2 * k] = loc[2 * k] + ox; xy[2 * k + 1] = loc[2 * k + 1] + oy; }
        if (rs_roads_add(ctx, roads, NULL, width, xy, n)) { rs_roads_free(ctx, roads); return NULL; }
        if (sc && sc_add_road(sc, width, loc, n)) { rs_roads_free(ctx, roads); return NULL; }
    }
    return roads;
}

static rs__roadfield_params params(double ox, double oy, double cs, double W, double H, double reach, double pix)
{
    rs__roadfield_params p;
    memset(&p, 0, sizeof p);
    p.origin_x = ox; p.origin_y = oy; p.cell_size = cs; p.width_m = W; p.height_m = H;
    p.reach_extra = reach; p.pixel = pix;
    return p;
}

static void test_nearest_brute(void)
{
    sc_rng g;
    sc_rng_seed(&g, 7);
    int queries = 0, bad_found = 0, bad_road = 0, bad_val = 0, found = 0, bad_any = 0;
    uint32_t last_hint = UINT32_MAX;
    for (int scene = 0; scene < 12; scene++) {
        double W = 120, H = 90, cs = 2, ox = scene % 3 == 2 ? 5e6 : 0, oy = scene % 3 == 2 ? -3e6 : 0;
        rs_roads *roads = random_roads(&g, W, H, 12, ox, oy, NULL);
        CHECK(roads != NULL);
        if (!roads) return;
        rs__roadfield_params p = params(ox, oy, cs, W, H, scene % 2 ? 3 : 0, 0.5);
        p.index_cell = scene % 4 == 3 ? 1.5 : 0;
        rs__roadfield *f = NULL;
        CHECK(rs__roadfield_build(ctx, roads, &p, &f) == RS_OK);
        for (int i = 0; f && i < 3000; i++) {
            double x = sc_rng_range(&g, 0, W), y = sc_rng_range(&g, 0, H);
            /* mostly within the lists' reach; every 5th needs neighbour cells,
             * as far as the map (plus the list reach) extends: roads beyond
             * it are not indexed */
            double border = fmin(fmin(x, W - x), fmin(y, H - y));
            double reach = i % 5 ? sc_rng_range(&g, 0, p.reach_extra + 0.35)
                                 : sc_rng_range(&g, 0, fmin(25, border + p.reach_extra));
            bf_hit b = brute_nearest(roads, ox, oy, cs, x, y, reach);
            rs__road_point rp;
            int got = rs__roadfield_nearest(f, x, y, reach, &rp);
            queries++;
            /* the any-road lookups say the same, whatever segment is tried first */
            {
                rs__roadfield_stats st;
                rs__roadfield_get_stats(f, &st);
                uint32_t hs[4] = { UINT32_MAX, last_hint, (uint32_t)sc_rng_range(&g, 0, (double)st.segments + 2),
                                   (uint32_t)st.segments };
                if (rs__roadfield_any_near(f, x, y, reach) != got) bad_any++;
                for (int k = 0; k < 4; k++) {
                    uint32_t h = hs[k];
                    if (rs__roadfield_any_near_hint(f, x, y, reach, &h) != got) bad_any++;
                    if (k == 1) last_hint = h;
                }
            }
            if (got != b.found) { bad_found++; continue; }
            if (!got) continue;
            found++;
            if (rp.road != b.road) { bad_road++; continue; }
            double stol = 1e-6 + 1e-9 * fabs(b.s);
            if (fabs(rp.dist - b.dist) > 1e-6 || fabs(rp.s - b.s) > stol || fabs(rp.t - b.t) > 1e-6) {
                if (bad_val++ < 5)
                    fprintf(stderr, "    (%g,%g) road %u seg %u/%zu: s %.9g/%.9g t %.9g/%.9g d %.9g/%.9g\n", x, y,
                            rp.road, rp.seg, b.seg, rp.s, b.s, rp.t, b.t, rp.dist, b.dist);
            }
        }
        rs__roadfield_free(ctx, f);
        rs_roads_free(ctx, roads);
    }
    printf("nearest: %d queries, %d found a road\n", queries, found);
    CHECK(found > queries / 10);
    CHECK_EQ_INT(bad_found, 0);
    CHECK_EQ_INT(bad_any, 0);
    CHECK_EQ_INT(bad_road, 0);
    CHECK_EQ_INT(bad_val, 0);
}

/* Tie-break and the s/t conventions on a hand-made bend. */
static void test_nearest_conventions(void)
{
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    /* east 20 m, then south (y down) 20 m: a right turn seen on the map */
    double xy[6] = { 10, 10, 30, 10, 30, 30 };
    CHECK(rs_roads_add(ctx, roads, NULL, 4, xy, 3) == RS_OK);
    rs__roadfield_params p = params(0, 0, 1, 50, 50, 0, 1);
    rs__roadfield *f = NULL;
    CHECK(rs__roadfield_build(ctx, roads, &p, &f) == RS_OK);
    rs__road_point rp;
    /* travelling east, left is north (smaller y): t > 0 */
    CHECK(rs__roadfield_nearest(f, 15, 9, 0, &rp) == 1);
    CHECK_EQ_INT(rp.seg, 0);
    CHECK_NEAR(rp.s, 5, 1e-12);
    CHECK_NEAR(rp.t, 1, 1e-12);
    /* outside of the bend (north-east of the vertex): s = 20, |t| = distance to the vertex */
    CHECK(rs__roadfield_nearest(f, 31, 9, 0, &rp) == 1);
    CHECK_NEAR(rp.s, 20, 1e-12);
    CHECK_NEAR(rp.t, sqrt(2), 1e-12);
    CHECK_EQ_INT(rp.seg, 0); /* exact tie between both segments: the lower one */
    /* inside of the bend, either side of the bisector: t continuous, s jumps by 2|t|tan(45) */
    CHECK(rs__roadfield_nearest(f, 28.9, 11.1 - 1e-9, 0, &rp) == 1);
    double s1 = rp.s, t1 = rp.t;
    CHECK(rs__roadfield_nearest(f, 28.9 + 2e-9, 11.1, 0, &rp) == 1);
    CHECK_NEAR(rp.t, t1, 1e-6);
    CHECK_NEAR(rp.s - s1, 2 * fabs(t1), 1e-6);
    CHECK(t1 < 0);
    /* beyond the reach: none; far outside the map: none */
    CHECK(rs__roadfield_nearest(f, 15, 3, 0.5, &rp) == 0);
    CHECK(rs__roadfield_nearest(f, 15, 3, 6, &rp) == 1);
    CHECK(rs__roadfield_nearest(f, -100, 10, 0, &rp) == 0);
    CHECK(rs__roadfield_nearest(f, NAN, 10, 0, &rp) == 0);
    CHECK(rs__roadfield_nearest(f, 15, 10, NAN, &rp) == 0);
    rs__roadfield_free(ctx, f);
    rs_roads_free(ctx, roads);
}

/* --- coverage ---------------------------------------------------------------- */
static double *coverage_image(const rs__roadfield *f, uint32_t w, uint32_t h, double pix)
{
    double *c = malloc((size_t)w * h * sizeof *c);
    if (c) rs__roadfield_coverage(f, 0, 0, w, h, pix, c, w);
    return c;
}

/* Max |R - G| and the SPEC edge error of the coverage of scene `sc`. */
static int compare_gt(const sc_scene *sc, unsigned T, const double *cov, double *maxerr, double *edge)
{
    uint32_t w = (sc->w - 1) * T, h = (sc->h - 1) * T;
    size_t n = (size_t)w * h;
    float *G = malloc(n * sizeof *G), *R = malloc(n * sizeof *R);
    gt_result gr;
    int rc = -1;
    if (G && R && !gt_coverage(sc, T, G)) {
        *maxerr = 0;
        for (size_t i = 0; i < n; i++) {
            R[i] = (float)cov[i];
            if (fabs(cov[i] - G[i]) > *maxerr) *maxerr = fabs(cov[i] - G[i]);
        }
        if (!gt_edge_error_g(sc, T, G, -1, R, &gr)) { *edge = gr.edge_error; rc = 0; }
    }
    free(G);
    free(R);
    return rc;
}

/* Pixels with a weight (R rounded to 16 bits above 0) have a road surface
 * within their half diagonal: the overlays fill a pixel with q > 0
 * without asking the field again when R is its analytic coverage
 * (lib/splat/overlays.c surfaces): count_far counts those without one.
 * test_coverage_random checks random scenes, test_weight_implies_near the
 * city's grid with class styles (T ends trimmed, a casing field beside
 * the road field: rs__roadfield_coverage2), at two pixel sizes. */
static size_t count_far(const rs__roadfield *f, const double *cov, uint32_t w, uint32_t h, double pix, size_t *nroad)
{
    size_t bad = 0;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            double v = cov[(size_t)y * w + x];
            if (!(v * 65535.0 + 0.5 >= 1)) continue; /* q = 0 (rs__coverage_quantise) */
            ++*nroad;
            bad += !rs__roadfield_any_near(f, (x + 0.5) * pix, (y + 0.5) * pix, pix * 0.70710678118654752440);
        }
    return bad;
}

static void test_coverage_random(void)
{
    sc_rng g;
    sc_rng_seed(&g, 11);
    double worst_max = 0, worst_edge = 0;
    size_t far = 0, nroad = 0;
    for (int scene = 0; scene < 6; scene++) {
        sc_scene sc;
        unsigned T = scene % 2 ? 4 : 2;
        CHECK(sc_scene_init(&sc, 61, 46, 2.0) == 0);
        double W = sc_extent_x(&sc), H = sc_extent_y(&sc);
        rs_roads *roads = random_roads(&g, W, H, 10, 0, 0, &sc);
        CHECK(roads != NULL);
        rs__roadfield_params p = params(0, 0, 2.0, W, H, 0, 2.0 / T);
        rs__roadfield *f = NULL;
        CHECK(roads && rs__roadfield_build(ctx, roads, &p, &f) == RS_OK);
        double *cov = f ? coverage_image(f, (sc.w - 1) * T, (sc.h - 1) * T, 2.0 / T) : NULL;
        double mx = 1, edge = 1;
        CHECK(cov && compare_gt(&sc, T, cov, &mx, &edge) == 0);
        if (cov) far += count_far(f, cov, (sc.w - 1) * T, (sc.h - 1) * T, 2.0 / T, &nroad);
        if (mx > worst_max) worst_max = mx;
        if (edge > worst_edge) worst_edge = edge;
        free(cov);
        rs__roadfield_free(ctx, f);
        rs_roads_free(ctx, roads);
        sc_scene_free(&sc);
    }
    printf("coverage, random scenes: max pixel error %.4f, worst edge error %.5f m; %zu of %zu road pixels with "
           "no road within the half diagonal\n", worst_max, worst_edge, far, nroad);
    CHECK(nroad > 10000 && far == 0);
    /* Sub-squares at corners and crossings: a few percent of a pixel at
     * most (docs/roadfield.md); the straight edges are exact. */
    CHECK(worst_max < 0.2);
    CHECK(worst_edge < 0.003);
}

static void test_coverage_city(void)
{
    sc_scene sc;
    const unsigned T = 4;
    CHECK(sc_city_default(&sc, 1) == 0);
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    for (size_t i = 0; i < sc.nroads; i++)
        CHECK(rs_roads_add(ctx, roads, NULL, sc.roads[i].width, sc.roads[i].xy, sc.roads[i].n) == RS_OK);
    double pix = sc.cell_size / T;
    rs__roadfield_params p = params(0, 0, sc.cell_size, sc_extent_x(&sc), sc_extent_y(&sc), 0, pix);
    rs__roadfield *f = NULL;
    CHECK(rs__roadfield_build(ctx, roads, &p, &f) == RS_OK);
    uint32_t w = (sc.w - 1) * T, h = (sc.h - 1) * T;
    double *cov = f ? coverage_image(f, w, h, pix) : NULL;
    double mx = 1, edge = 1;
    CHECK(cov && compare_gt(&sc, T, cov, &mx, &edge) == 0);
    printf("coverage, city T=4: max pixel error %.4f, edge error %.5f m\n", mx, edge);
    CHECK(edge < 0.002); /* the splatter needs <= 0.025 m */
    CHECK(mx < 0.2);
    /* tiling: odd blocks at odd offsets give the same doubles */
    if (cov) {
        double *tile = malloc((size_t)w * h * sizeof *tile);
        CHECK(tile != NULL);
        const uint32_t bw = 37, bh = 23;
        for (uint32_t y = 0; tile && y < h; y += bh)
            for (uint32_t x = 0; x < w; x += bw) {
                uint32_t tw = w - x < bw ? w - x : bw, th = h - y < bh ? h - y : bh;
                rs__roadfield_coverage(f, x, y, tw, th, pix, tile + (size_t)y * w + x, w);
            }
        CHECK(tile && memcmp(tile, cov, (size_t)w * h * sizeof *cov) == 0);
        free(tile);
    }
    /* The many-cell path (pixels larger than the build's pixel hint) gives
     * the same values. */
    rs__roadfield *f2 = NULL;
    p.pixel = 0.3;
    CHECK(rs__roadfield_build(ctx, roads, &p, &f2) == RS_OK);
    if (f2 && cov) {
        uint32_t x0 = 600, y0 = 500, bw = 211, bh = 97;
        double *blk = malloc((size_t)bw * bh * sizeof *blk), md = 0;
        CHECK(blk != NULL);
        if (blk) {
            rs__roadfield_coverage(f2, x0, y0, bw, bh, pix, blk, bw);
            for (uint32_t y = 0; y < bh; y++)
                for (uint32_t x = 0; x < bw; x++)
                    md = fmax(md, fabs(blk[y * bw + x] - cov[(size_t)(y0 + y) * w + x0 + x]));
        }
        CHECK(md == 0);
        free(blk);
    }
    rs__roadfield_free(ctx, f2);
    free(cov);
    rs__roadfield_free(ctx, f);
    rs_roads_free(ctx, roads);
    sc_scene_free(&sc);
}

static void test_weight_implies_near(void)
{
    size_t bad = 0, nroad = 0;
    /* the city with class styles: T ends and casings */
    sc_scene sc;
    CHECK(sc_city_default(&sc, 1) == 0);
    rs_roads *roads = NULL;
    rs_dem *dem = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK && rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) == RS_OK);
    rs_dem_frame fr = { sc.cell_size, 0.01, 0, 0 };
    CHECK(dem && rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    int added = roads != NULL;
    for (size_t i = 0; added && i < sc.nroads; i++)
        added = rs_roads_add(ctx, roads, NULL, sc.roads[i].width, sc.roads[i].xy, sc.roads[i].n) == RS_OK &&
                rs_roads_set_attr(ctx, roads, i, "class", sc_city_class(sc.roads[i].width)) == RS_OK;
    CHECK(added);
    size_t tees = 0;
    for (unsigned T = 2; T <= 4; T += 2) {
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.texels = T;
        rs_road_grid *grid = NULL;
        CHECK(dem && roads && rs_road_grid_build(ctx, dem, roads, &o, &grid) == RS_OK);
        const rs__roadfield *f = grid ? grid->field : NULL, *cg = grid && grid->styling ? grid->styling->casing : NULL;
        CHECK(f != NULL && cg != NULL);
        double pix = sc.cell_size / T;
        uint32_t w = (sc.w - 1) * T, h = (sc.h - 1) * T;
        double *cov = malloc((size_t)w * h * sizeof *cov), *covg = malloc((size_t)w * h * sizeof *covg);
        CHECK(cov && covg);
        if (f && cg && cov && covg) {
            rs__roadfield_stats st;
            rs__roadfield_get_stats(f, &st);
            rs__roadfield_coverage2(f, cg, 0, 0, w, h, pix, cov, covg, w);
            bad += count_far(f, cov, w, h, pix, &nroad);
            bad += count_far(cg, covg, w, h, pix, &nroad);
            tees += st.tees;
        }
        free(cov);
        free(covg);
        rs_road_grid_free(ctx, grid);
    }
    printf("weight implies a road within the half diagonal: %zu of %zu road pixels without (%zu T ends)\n", bad, nroad,
           tees);
    CHECK(nroad > 100000 && tees > 0);
    CHECK(bad == 0);
    rs_dem_free(ctx, dem);
    rs_roads_free(ctx, roads);
    sc_scene_free(&sc);
}

/* Redundant capsules change nothing: the same roads with every point
 * given three times (zero-length segments), driven there and back
 * (retraced segments), and every third road given twice, cover every
 * pixel with the same doubles (the exact one-capsule covers and the
 * joints must not give way to the approximations for several capsules). */
static void test_coverage_redundant(void)
{
    sc_rng g;
    sc_rng_seed(&g, 23);
    for (int scene = 0; scene < 6; scene++) {
        double W = 120, H = 90, cs = 2, pix = scene % 2 ? 0.5 : 1;
        rs_roads *a = random_roads(&g, W, H, 12, 0, 0, NULL), *b = NULL;
        CHECK(a != NULL && rs_roads_create(ctx, &b) == RS_OK);
        if (!a || !b) return;
        for (size_t i = 0; i < rs_roads_count(a); i++) {
            const double *xy;
            size_t n, m = 0;
            double w, pts[2 * 3 * 2 * 16];
            rs_roads_get(a, i, NULL, &w, &xy, &n);
            for (size_t k = 0; k < 2 * n - 1; k++) {
                size_t src = k < n ? k : 2 * n - 2 - k; /* there and back */
                for (int rep = 0; rep < 3; rep++) { pts[2 * m] = xy[2 * src]; pts[2 * m + 1] = xy[2 * src + 1]; m++; }
            }
            CHECK(rs_roads_add(ctx, b, NULL, w, pts, m) == RS_OK);
            if (i % 3 == 0) CHECK(rs_roads_add(ctx, b, NULL, w, xy, n) == RS_OK);
        }
        rs__roadfield_params p = params(0, 0, cs, W, H, 0, pix);
        rs__roadfield *fa = NULL, *fb = NULL, *ft = NULL, *fs = NULL;
        CHECK(rs__roadfield_build(ctx, a, &p, &fa) == RS_OK && rs__roadfield_build(ctx, b, &p, &fb) == RS_OK);
        /* the holder search by the box tree everywhere, and by list scans
         * everywhere, finds the same redundant capsules */
        rs__roadfield_params pt = p, ps = p;
        pt.relation_scan = 1;
        ps.relation_scan = UINT32_MAX;
        CHECK(rs__roadfield_build(ctx, b, &pt, &ft) == RS_OK && rs__roadfield_build(ctx, b, &ps, &fs) == RS_OK);
        if (fa && fb && ft && fs) {
            rs__roadfield_stats sb, st, ss;
            rs__roadfield_get_stats(fb, &sb);
            rs__roadfield_get_stats(ft, &st);
            rs__roadfield_get_stats(fs, &ss);
            CHECK(sb.redundant > 0 && sb.redundant == st.redundant && sb.redundant == ss.redundant);
            uint32_t w = (uint32_t)(W / pix), h = (uint32_t)(H / pix);
            double *ca = coverage_image(fa, w, h, pix), *cb = coverage_image(fb, w, h, pix);
            double *ct = coverage_image(ft, w, h, pix), *cs2 = coverage_image(fs, w, h, pix);
            CHECK(ca && cb && memcmp(ca, cb, (size_t)w * h * sizeof *ca) == 0);
            CHECK(ct && cs2 && memcmp(ca, ct, (size_t)w * h * sizeof *ca) == 0 &&
                  memcmp(ca, cs2, (size_t)w * h * sizeof *ca) == 0);
            free(ca);
            free(cb);
            free(ct);
            free(cs2);
        }
        rs__roadfield_free(ctx, fa);
        rs__roadfield_free(ctx, fb);
        rs__roadfield_free(ctx, ft);
        rs__roadfield_free(ctx, fs);
        rs_roads_free(ctx, a);
        rs_roads_free(ctx, b);
    }
}

/* A scene and its copy moved by 5e6 m (origin moved alike) give the same bytes. */
static void test_translation(void)
{
    sc_rng g1, g2;
    sc_rng_seed(&g1, 99);
    sc_rng_seed(&g2, 99);
    double W = 100, H = 80, cs = 1, pix = 0.5;
    rs_roads *a = random_roads(&g1, W, H, 15, 0, 0, NULL), *b = random_roads(&g2, W, H, 15, 5e6, 5e6, NULL);
    rs__roadfield_params pa = params(0, 0, cs, W, H, 1, pix), pb = params(5e6, 5e6, cs, W, H, 1, pix);
    rs__roadfield *fa = NULL, *fb = NULL;
    CHECK(a && b && rs__roadfield_build(ctx, a, &pa, &fa) == RS_OK && rs__roadfield_build(ctx, b, &pb, &fb) == RS_OK);
    if (fa && fb) {
        uint32_t w = 200, h = 160;
        double *ca = coverage_image(fa, w, h, pix), *cb = coverage_image(fb, w, h, pix);
        CHECK(ca && cb && memcmp(ca, cb, (size_t)w * h * sizeof *ca) == 0);
        free(ca);
        free(cb);
        int same = 1;
        for (int i = 0; i < 2000; i++) {
            double x = sc_rng_range(&g1, 0, W), y = sc_rng_range(&g1, 0, H);
            rs__road_point ra, rb;
            memset(&ra, 0, sizeof ra);
            memset(&rb, 0, sizeof rb);
            int ga = rs__roadfield_nearest(fa, x, y, 1, &ra), gb = rs__roadfield_nearest(fb, x, y, 1, &rb);
            if (ga != gb || memcmp(&ra, &rb, sizeof ra) != 0) same = 0;
        }
        CHECK(same);
    }
    rs__roadfield_free(ctx, fa);
    rs__roadfield_free(ctx, fb);
    rs_roads_free(ctx, a);
    rs_roads_free(ctx, b);
}

/* Absurd but finite input: no crash, no undefined behaviour (the sanitizer
 * build runs this), bounded work. */
static void test_extreme(void)
{
    rs_roads *roads = NULL;
    CHECK(rs_roads_create(ctx, &roads) == RS_OK);
    double far[4] = { -1e300, 4.1, 1e300, 4.1 }, dot[4] = { 3, 3, 3, 3 }, huge[4] = { 1e308, -1e308, -1e308, 1e308 };
    double wide[4] = { 1, 1, 2, 2 };
    CHECK(rs_roads_add(ctx, roads, NULL, 2, far, 2) == RS_OK);
    CHECK(rs_roads_add(ctx, roads, NULL, 1, dot, 2) == RS_OK);
    CHECK(rs_roads_add(ctx, roads, NULL, 1e9, wide, 2) == RS_OK);
    CHECK(rs_roads_add(ctx, roads, NULL, 1e300, huge, 2) == RS_OK);
    rs__roadfield_params p = params(0, 0, 1, 64, 64, 1e300, 0);
    rs__roadfield *f = NULL;
    CHECK(rs__roadfield_build(ctx, roads, &p, &f) == RS_OK);
    rs__roadfield_stats st;
    rs__roadfield_get_stats(f, &st);
    CHECK(st.entries <= (size_t)st.gw * st.gh * 4);
    double c[16 * 16];
    rs__roadfield_coverage(f, 0, 0, 16, 16, 4, c, 16);
    int ones = 1;
    for (int i = 0; i < 256; i++) ones &= c[i] == 1;
    CHECK(ones);
    rs__road_point rp;
    CHECK(rs__roadfield_nearest(f, 3, 3, 0, &rp) == 1);
    CHECK(rs__roadfield_nearest(f, 3, 3, 1e308, &rp) == 1);
    rs__roadfield_coverage(f, 0, 0, 16, 16, 0, c, 16);
    CHECK(c[0] == 0);
    rs__roadfield_coverage(f, 0xFFFFFFF0u, 0xFFFFFFF0u, 16, 16, 1e300, c, 16);
    rs__roadfield_free(ctx, f);
    /* bad parameters */
    p.width_m = NAN;
    CHECK(rs__roadfield_build(ctx, roads, &p, &f) == RS_ERR_INVALID_ARG);
    p = params(0, 0, 0, 10, 10, 0, 0);
    CHECK(rs__roadfield_build(ctx, roads, &p, &f) == RS_ERR_INVALID_ARG);
    /* a huge map with a tiny explicit cell: the cell grows, memory stays bounded */
    p = params(0, 0, 0.01, 1e6, 1e6, 0, 0);
    p.index_cell = 0.01;
    rs_roads *one = NULL;
    double pts[4] = { 10, 10, 20, 10 };
    CHECK(rs_roads_create(ctx, &one) == RS_OK && rs_roads_add(ctx, one, NULL, 3, pts, 2) == RS_OK);
    CHECK(rs__roadfield_build(ctx, one, &p, &f) == RS_OK);
    CHECK(rs__roadfield_bytes(f) < ((size_t)1 << 28));
    CHECK(rs__roadfield_nearest(f, 15, 11, 0, &rp) == 1 && rp.seg == 0 && fabs(rp.t + 1) < 1e-9);
    rs__roadfield_free(ctx, f);
    rs_roads_free(ctx, one);
    /* no roads */
    rs_roads *none = NULL;
    CHECK(rs_roads_create(ctx, &none) == RS_OK);
    p = params(0, 0, 1, 10, 10, 0, 0);
    CHECK(rs__roadfield_build(ctx, none, &p, &f) == RS_OK);
    rs__roadfield_coverage(f, 0, 0, 16, 16, 1, c, 16);
    CHECK(c[0] == 0 && c[255] == 0);
    CHECK(rs__roadfield_nearest(f, 5, 5, 100, &rp) == 0);
    rs__roadfield_free(ctx, f);
    rs_roads_free(ctx, none);
    rs_roads_free(ctx, roads);
}

/* --- casing field: rs__roadfield_widen and the one-pass coverage2 ------------------ */
/* coverage2(f, g) against the two fields' own passes, whole and in
 * windows: R bit for bit; C bit for bit except where R >= 1 - 2^-10 (the
 * skipped joints and crossings); and C against a field built from the
 * widened roads themselves (other cells, other lists: the same areas up to
 * rounding). */
static void test_widen(void)
{
    sc_rng g;
    sc_rng_seed(&g, 23);
    size_t r_diff = 0, c_diff = 0, c_skip = 0, listed = 0, bad_window = 0;
    double worst_built = 0;
    for (int scene = 0; scene < 6; scene++) {
        const double W = 120, H = 90, pix = scene % 2 ? 0.5 : 1.0;
        rs_roads *roads = random_roads(&g, W, H, 14, 0, 0, NULL), *wide = NULL;
        CHECK(roads != NULL && rs_roads_create(ctx, &wide) == RS_OK);
        if (!roads || !wide) return;
        size_t n = rs_roads_count(roads);
        double extra[16];
        for (size_t i = 0; i < n; i++) {
            /* no casing, a thin one, one of a pixel, one of an index cell (the limit) */
            int kind = (int)(sc_rng_unit(&g) * 4);
            extra[i] = kind == 0 ? 0 : kind == 1 ? 0.15 : kind == 2 ? pix : -1;
        }
        rs__roadfield_params p = params(0, 0, 2.0, W, H, 0, pix);
        rs__roadfield *f = NULL, *gw = NULL, *h = NULL;
        CHECK(rs__roadfield_build(ctx, roads, &p, &f) == RS_OK);
        if (!f) return;
        for (size_t i = 0; i < n; i++) {
            if (extra[i] < 0) extra[i] = rs__roadfield_cell(f);
            const double *xy;
            size_t np;
            double w;
            rs_roads_get(roads, i, NULL, &w, &xy, &np);
            CHECK(rs_roads_add(ctx, wide, NULL, w + 2 * extra[i], xy, np) == RS_OK);
        }
        CHECK(rs__roadfield_widen(ctx, f, extra, n, &gw) == RS_OK);
        CHECK(rs__roadfield_build(ctx, wide, &p, &h) == RS_OK);
        uint32_t w = (uint32_t)(W / pix), hh = (uint32_t)(H / pix);
        double *R = coverage_image(f, w, hh, pix), *C = gw ? coverage_image(gw, w, hh, pix) : NULL;
        double *Cb = h ? coverage_image(h, w, hh, pix) : NULL;
        double *R2 = calloc((size_t)w * hh, sizeof *R2), *C2 = calloc((size_t)w * hh, sizeof *C2);
        double *R3 = calloc((size_t)w * hh, sizeof *R3), *C3 = calloc((size_t)w * hh, sizeof *C3);
        CHECK(R && C && Cb && R2 && C2 && R3 && C3);
        if (R && C && Cb && R2 && C2 && R3 && C3) {
            rs__roadfield_coverage2(f, gw, 0, 0, w, hh, pix, R2, C2, w);
            /* windows of odd sizes */
            for (uint32_t y0 = 0; y0 < hh; y0 += 37)
                for (uint32_t x0 = 0; x0 < w; x0 += 53) {
                    uint32_t ww = w - x0 < 53 ? w - x0 : 53, wh = hh - y0 < 37 ? hh - y0 : 37;
                    rs__roadfield_coverage2(f, gw, x0, y0, ww, wh, pix, R3 + (size_t)y0 * w + x0,
                                            C3 + (size_t)y0 * w + x0, w);
                }
            for (size_t i = 0; i < (size_t)w * hh; i++) {
                r_diff += R2[i] != R[i];
                int skip = R[i] >= 1 - 1.0 / 1024;
                c_skip += skip && C2[i] != C[i];
                c_diff += !skip && C2[i] != C[i];
                listed += C[i] != R[i];
                bad_window += R3[i] != R2[i] || C3[i] != C2[i];
                if (!skip && fabs(C[i] - Cb[i]) > worst_built) worst_built = fabs(C[i] - Cb[i]);
            }
        }
        free(R); free(C); free(Cb); free(R2); free(C2); free(R3); free(C3);
        rs__roadfield_free(ctx, f);
        rs__roadfield_free(ctx, gw);
        rs__roadfield_free(ctx, h);
        rs_roads_free(ctx, roads);
        rs_roads_free(ctx, wide);
    }
    printf("widened field: %zu casing pixels; one pass vs own passes: %zu R and %zu C differ (%zu skipped near R = 1); "
           "vs a field of the widened roads: max %.2g\n", listed, r_diff, c_diff, c_skip, worst_built);
    CHECK(listed > 1000);
    CHECK_EQ_INT(r_diff, 0);
    CHECK_EQ_INT(c_diff, 0);
    CHECK_EQ_INT(bad_window, 0);
    CHECK(worst_built < 1e-9);

    /* the widening is refused beyond an index cell, and for a negative or NaN one */
    rs_roads *roads = random_roads(&g, 60, 60, 3, 0, 0, NULL);
    rs__roadfield_params p = params(0, 0, 1, 60, 60, 0, 0.5);
    rs__roadfield *f = NULL, *gw = NULL;
    CHECK(roads && rs__roadfield_build(ctx, roads, &p, &f) == RS_OK);
    if (f) {
        double bad[3][3] = { { 0, 0, 2 * rs__roadfield_cell(f) }, { -0.1, 0, 0 }, { NAN, 0, 0 } };
        for (int k = 0; k < 3; k++) {
            CHECK(rs__roadfield_widen(ctx, f, bad[k], 3, &gw) == RS_ERR_INVALID_ARG);
            CHECK(gw == NULL);
        }
        double few[1] = { 0 };
        CHECK(rs__roadfield_widen(ctx, f, few, 1, &gw) == RS_ERR_INVALID_ARG); /* too few entries */
    }
    rs__roadfield_free(ctx, f);
    rs_roads_free(ctx, roads);
}

/* A field with a window (a patch's local build) against the whole field:
 * the same coverage (plain, widened, coarser pixels) on every pixel of the
 * window and the same nearest answers there up to the window's reach, with
 * T ends; fewer cell entries. */
static void test_window(void)
{
    sc_rng g;
    sc_rng_seed(&g, 41);
    size_t px = 0, bad_cov = 0, bad_wide = 0, bad_coarse = 0, queries = 0, found = 0, bad_query = 0;
    size_t entries_whole = 0, entries_window = 0, tees = 0;
    for (int scene = 0; scene < 24; scene++) {
        const double W = 160, H = 120, pix = scene % 3 == 0 ? 0.5 : scene % 3 == 1 ? 1.0 : 0.25;
        rs_roads *roads = random_roads(&g, W, H, 24, 0, 0, NULL);
        rs_network *net = NULL;
        rs__tee_end *te = NULL;
        size_t nte = 0, n = roads ? rs_roads_count(roads) : 0;
        CHECK(roads && rs_network_build(ctx, roads, NULL, &net) == RS_OK && rs__tee_ends(ctx, roads, net, &te, &nte) == RS_OK);
        if (!roads || !net) return;
        tees += nte;
        /* the window: whole pixels somewhere on the map, 4 to 60 m a side */
        uint32_t w = (uint32_t)(W / pix), h = (uint32_t)(H / pix);
        uint32_t ww = (uint32_t)sc_rng_range(&g, 4 / pix, 60 / pix), wh = (uint32_t)sc_rng_range(&g, 4 / pix, 60 / pix);
        uint32_t x0 = (uint32_t)sc_rng_range(&g, 0, w - ww), y0 = (uint32_t)sc_rng_range(&g, 0, h - wh);
        rs__roadfield_params p = params(0, 0, 2.0, W, H, 0, pix), pw = p;
        pw.window_on = 1;
        pw.window[0] = x0 * pix, pw.window[1] = y0 * pix, pw.window[2] = (x0 + ww) * pix, pw.window[3] = (y0 + wh) * pix;
        pw.window_reach = scene % 2 ? 20 : 3;
        rs__roadfield *f = NULL, *fw = NULL, *gf = NULL, *gw = NULL, *cf = NULL, *cw = NULL;
        CHECK(rs__roadfield_build(ctx, roads, &p, &f) == RS_OK && rs__roadfield_build(ctx, roads, &pw, &fw) == RS_OK);
        if (!f || !fw) return;
        CHECK(rs__roadfield_set_tees(ctx, f, roads, te, nte) == RS_OK && rs__roadfield_set_tees(ctx, fw, roads, te, nte) == RS_OK);
        double extra[32];
        for (size_t i = 0; i < n && i < 32; i++) extra[i] = i % 3 ? 0.3 : rs__roadfield_cell(f);
        CHECK(rs__roadfield_widen(ctx, f, extra, n, &gf) == RS_OK && rs__roadfield_widen(ctx, fw, extra, n, &gw) == RS_OK);
        CHECK(rs__roadfield_repixel(ctx, f, 2 * pix, &cf) == RS_OK && rs__roadfield_repixel(ctx, fw, 2 * pix, &cw) == RS_OK);
        rs__roadfield_stats sa, sb;
        rs__roadfield_get_stats(f, &sa);
        rs__roadfield_get_stats(fw, &sb);
        entries_whole += sa.entries, entries_window += sb.entries;
        CHECK_EQ_INT(sa.segments, sb.segments); /* (every segment kept, some unlisted) */
        size_t m = (size_t)ww * wh;
        double *a = calloc(m, sizeof *a), *b = calloc(m, sizeof *b), *ag = calloc(m, sizeof *ag), *bg = calloc(m, sizeof *bg);
        CHECK(a && b && ag && bg);
        if (a && b && ag && bg && gf && gw && cf && cw) {
            rs__roadfield_coverage(f, x0, y0, ww, wh, pix, a, ww);
            rs__roadfield_coverage(fw, x0, y0, ww, wh, pix, b, ww);
            for (size_t i = 0; i < m; i++) bad_cov += a[i] != b[i];
            rs__roadfield_coverage2(f, gf, x0, y0, ww, wh, pix, a, ag, ww);
            rs__roadfield_coverage2(fw, gw, x0, y0, ww, wh, pix, b, bg, ww);
            for (size_t i = 0; i < m; i++) bad_wide += a[i] != b[i] || ag[i] != bg[i];
            /* the coarser pixels whose centre lies in the window */
            uint32_t cx0 = (x0 + 1) / 2, cy0 = (y0 + 1) / 2, cx1 = (x0 + ww) / 2, cy1 = (y0 + wh) / 2;
            if (cx1 > cx0 && cy1 > cy0) {
                uint32_t cwid = cx1 - cx0, chei = cy1 - cy0;
                rs__roadfield_coverage(cf, cx0, cy0, cwid, chei, 2 * pix, a, cwid);
                rs__roadfield_coverage(cw, cx0, cy0, cwid, chei, 2 * pix, b, cwid);
                for (size_t i = 0; i < (size_t)cwid * chei; i++) bad_coarse += a[i] != b[i];
            }
            px += m;
        }
        free(a), free(b), free(ag), free(bg);
        for (int k = 0; k < 400; k++) {
            double x = pw.window[0] + sc_rng_unit(&g) * (pw.window[2] - pw.window[0]);
            double y = pw.window[1] + sc_rng_unit(&g) * (pw.window[3] - pw.window[1]);
            double reach = sc_rng_range(&g, 0, pw.window_reach);
            rs__road_point ra, rb;
            memset(&ra, 0, sizeof ra), memset(&rb, 0, sizeof rb);
            int ha = rs__roadfield_nearest(f, x, y, reach, &ra), hb = rs__roadfield_nearest(fw, x, y, reach, &rb);
            queries++, found += ha;
            bad_query += ha != hb || memcmp(&ra, &rb, sizeof ra) != 0;
        }
        rs__roadfield_free(ctx, f), rs__roadfield_free(ctx, fw), rs__roadfield_free(ctx, gf);
        rs__roadfield_free(ctx, gw), rs__roadfield_free(ctx, cf), rs__roadfield_free(ctx, cw);
        rs__free(ctx, te);
        rs_network_free(ctx, net);
        rs_roads_free(ctx, roads);
    }
    printf("window: %zu pixels, %zu queries (%zu found), %zu T ends; entries %zu of the whole field's %zu\n", px, queries,
           found, tees, entries_window, entries_whole);
    CHECK(px > 10000 && found > queries / 4 && tees > 0);
    CHECK(entries_window < entries_whole * 3 / 4);
    CHECK_EQ_INT(bad_cov, 0);
    CHECK_EQ_INT(bad_wide, 0);
    CHECK_EQ_INT(bad_coarse, 0);
    CHECK_EQ_INT(bad_query, 0);
}

/* --- allocation failures ----------------------------------------------------------- */

static rs_result alloc_try(rs_ctx *c, void *user, int *wrong)
{
    rs__roadfield_params p = params(0, 0, 1, 60, 60, 0, 0.5);
    rs__roadfield *f = NULL;
    rs_result r = rs__roadfield_build(c, user, &p, &f);
    *wrong = r != RS_OK && f != NULL;
    rs__roadfield_free(c, f);
    return r;
}

static rs_result alloc_tree_try(rs_ctx *c, void *user, int *wrong)
{
    rs__roadfield_params p = params(0, 0, 1, 60, 60, 0, 0.5);
    p.relation_scan = 1;
    rs__roadfield *f = NULL;
    rs_result r = rs__roadfield_build(c, user, &p, &f);
    *wrong = r != RS_OK && f != NULL;
    rs__roadfield_free(c, f);
    return r;
}

typedef struct widen_try_arg {
    const rs__roadfield *f;
    const double *extra;
    size_t n;
} widen_try_arg;

static rs_result widen_try(rs_ctx *c, void *user, int *wrong)
{
    const widen_try_arg *a = user;
    rs__roadfield *g = NULL;
    rs_result r = rs__roadfield_widen(c, a->f, a->extra, a->n, &g);
    *wrong = r != RS_OK && g != NULL;
    rs__roadfield_free(c, g);
    return r;
}

static void test_alloc_failures(void)
{
    sc_rng g;
    sc_rng_seed(&g, 5);
    rs_roads *roads = random_roads(&g, 60, 60, 40, 0, 0, NULL); /* > 64 segments: the array grows */
    CHECK(roads != NULL);
    if (!roads) return;
    fail_sweep fs = fail_alloc_sweep(1000, alloc_try, roads);
    CHECK_SWEEP(fs, 4);
    fs = fail_alloc_sweep(1000, alloc_tree_try, roads); /* the holder tree's allocations too */
    CHECK_SWEEP(fs, 7);
    /* the widened field */
    rs__roadfield_params p = params(0, 0, 1, 60, 60, 0, 0.5);
    rs__roadfield *f = NULL;
    double extra[40];
    for (int i = 0; i < 40; i++) extra[i] = 0.1 * (i % 3);
    CHECK(rs__roadfield_build(ctx, roads, &p, &f) == RS_OK);
    if (f) {
        widen_try_arg a = { f, extra, 40 };
        fs = fail_alloc_sweep(1000, widen_try, &a);
        CHECK_SWEEP(fs, 4);
    }
    rs__roadfield_free(ctx, f);
    rs_roads_free(ctx, roads);
}

/* An allocator that fails only its `target`-th call (1-based). */
typedef struct one_fail { long calls, target, failed, live; } one_fail;
static void *of_malloc(void *u, size_t n)
{
    one_fail *o = u;
    if (++o->calls == o->target) { o->failed = 1; return NULL; }
    void *p = malloc(n);
    if (p) o->live++;
    return p;
}
static void *of_realloc(void *u, void *p, size_t n)
{
    one_fail *o = u;
    if (++o->calls == o->target) { o->failed = 1; return NULL; }
    void *q = realloc(p, n);
    if (q && !p) o->live++;
    return q;
}
static void of_free(void *u, void *p)
{
    one_fail *o = u;
    if (p) o->live--;
    free(p);
}

/* The build records the cells each segment visits in its count pass; when
 * that record cannot grow, the fill does the geometry again: one failed
 * allocation anywhere either fails the build cleanly (RS_ERR_NOMEM, no
 * leak) or gives the same field (the fallback; before it, every failed
 * allocation failed the build). Dense enough for lists of more than 4
 * segments. */
static void test_record_fallback(void)
{
    sc_rng g;
    sc_rng_seed(&g, 31);
    rs_roads *roads = random_roads(&g, 60, 60, 60, 0, 0, NULL);
    CHECK(roads != NULL);
    if (!roads) return;
    rs__roadfield_params p = params(0, 0, 1, 60, 60, 0, 0.5);
    rs__roadfield *ref = NULL;
    CHECK(rs__roadfield_build(ctx, roads, &p, &ref) == RS_OK);
    if (!ref) return;
    rs__roadfield_stats sr;
    rs__roadfield_get_stats(ref, &sr);
    uint32_t w = 120, h = 120;
    double *cr = coverage_image(ref, w, h, 0.5);
    int fallbacks = 0, bad = 0, leaks = 0;
    for (long t = 1; t <= 60 && cr; t++) {
        one_fail o = { 0, t, 0, 0 };
        rs_allocator al = { of_malloc, of_realloc, of_free, &o };
        rs_ctx *c = NULL;
        if (rs_ctx_create(&al, NULL, &c) != RS_OK) continue; /* the context's own allocation */
        rs__roadfield *f = NULL;
        rs_result r = rs__roadfield_build(c, roads, &p, &f);
        if (r == RS_OK && o.failed) {
            fallbacks++;
            rs__roadfield_stats sf;
            rs__roadfield_get_stats(f, &sf);
            double *cf = coverage_image(f, w, h, 0.5);
            if (!cf || sf.entries != sr.entries || sf.redundant != sr.redundant || sf.full_cells != sr.full_cells ||
                memcmp(cf, cr, (size_t)w * h * sizeof *cf) != 0)
                bad++;
            free(cf);
        } else if (r != RS_OK && (r != RS_ERR_NOMEM || f)) bad++;
        rs__roadfield_free(c, f);
        rs_ctx_free(c);
        leaks += o.live != 0;
    }
    printf("record fallback: %d builds succeeded after a failed allocation\n", fallbacks);
    /* the column table (optional: the coverage then finds cells without
     * it) is one allocation a build survives; the record's are the others */
    CHECK(fallbacks > 1);
    CHECK_EQ_INT(bad, 0);
    CHECK_EQ_INT(leaks, 0);
    free(cr);
    rs__roadfield_free(ctx, ref);
    rs_roads_free(ctx, roads);
}

/* The automatic index cell (docs/roadfield.md "Index"): about one segment
 * per cell, between max(DEM cell, half the mean width) and max(that, the
 * mean width). n parallel roads of width 8 m, each of `per` segments,
 * across a W x W map of 1 m DEM cells. */
static double auto_cell(int n, int per, double W)
{
    rs_roads *roads = NULL;
    if (rs_roads_create(ctx, &roads) != RS_OK) return -1;
    double xy[2 * 65];
    for (int i = 0; i < n; i++) {
        double y = W * (i + 0.5) / n;
        for (int k = 0; k <= per; k++) xy[2 * k] = W * k / per, xy[2 * k + 1] = y;
        if (rs_roads_add(ctx, roads, NULL, 8, xy, (size_t)per + 1) != RS_OK) {
            rs_roads_free(ctx, roads);
            return -1;
        }
    }
    rs__roadfield_params p = params(0, 0, 1, W, W, 0, 0.25);
    rs__roadfield *f = NULL;
    double c = -1;
    if (rs__roadfield_build(ctx, roads, &p, &f) == RS_OK) c = rs__roadfield_cell(f);
    rs__roadfield_free(ctx, f);
    rs_roads_free(ctx, roads);
    return c;
}

/* Roads with their network and T ends (rs__tee_ends), for the T tests. */
typedef struct tee_scene {
    rs_roads *roads;
    rs_network *net;
    rs__tee_end *te;
    size_t nte;
} tee_scene;

/* t->roads given (text NULL), or parsed from text: the network and T ends. 1 on success. */
static int tee_scene_of(tee_scene *t, const char *text)
{
    if (text && rs_roads_parse(ctx, text, strlen(text), &t->roads) != RS_OK) return 0;
    return t->roads && rs_network_build(ctx, t->roads, NULL, &t->net) == RS_OK &&
           rs__tee_ends(ctx, t->roads, t->net, &t->te, &t->nte) == RS_OK;
}

static void tee_scene_free(tee_scene *t)
{
    rs__free(ctx, t->te);
    rs_network_free(ctx, t->net);
    rs_roads_free(ctx, t->roads);
    memset(t, 0, sizeof *t);
}

/* A road ending on another with its end point repeated (a zero-length
 * last segment the T clips, as OSM exports have) claims no point beside
 * it: a fill lookup 7 m away finds the filled road under it at every
 * index cell (its zero-length strip took every point short of the clip
 * line as on it, so the answer depended on the cells that listed it:
 * fuzz/edits, 3 December 2026). */
static void test_tee_repeated_point(void)
{
    tee_scene t;
    memset(&t, 0, sizeof t);
    CHECK(tee_scene_of(&t, "road a width 6\n5 5\n570 0\nend\n"
                           "road b width 5\n-2.5 52\n9.5 2\n9.5 2\nend\n"));
    CHECK(t.nte >= 1);
    rs_roads *roads = t.roads;
    const int prio[2] = { 1, 0 };
    const double cells[] = { 2.5, 5, 10.4, 10.5, 16, 40 };
    for (size_t k = 0; k < sizeof cells / sizeof cells[0]; k++) {
        rs__roadfield_params p = params(0, 0, 5, 75, 55, 0, 5.0 / 3);
        p.index_cell = cells[k];
        rs__roadfield *f = NULL;
        rs__road_point q;
        memset(&q, 0, sizeof q);
        CHECK(rs__roadfield_build(ctx, roads, &p, &f) == RS_OK && rs__roadfield_set_tees(ctx, f, roads, t.te, t.nte) == RS_OK);
        CHECKF(rs__roadfield_nearest_ranked(f, 2.5, 2.5, 5.0 / 3 * 0.7071, prio, &q) == 1 && q.road == 0,
               "cell %g: road %u", cells[k], q.road);
        rs__roadfield_free(ctx, f);
    }
    tee_scene_free(&t);
}

/* The ranked lookup at a T does not depend on the index cell: past the
 * corner of a strip cut by an oblique clip line the lower bound of the
 * distance is within reach of points outside the strip's box, which only
 * the cells listing the segment offered. A 4 m road ending inside an 11 m
 * footway at 45 degrees: the pixel (36, 16) at 1.25 m took the service
 * road's (absent) fill, or the footway's, by the automatic cell
 * (fuzz/edits, 6 December 2026). Every pixel of the map, at six cells. */
static void test_tee_corner(void)
{
    tee_scene t;
    memset(&t, 0, sizeof t);
    const char *text = "road a width 11\n12.5 1\n-0.5 46\n55.5 49\nend\n"
                       "road footway width 11\n63.5 35\n35.5 23\n4.5 21\nend\n"
                       "road service width 4\n41.5 22\n-2.5 15\nend\n"
                       "road b width 1\n63.5 4\n12.5 15\nend\n"
                       "road c width 11\n63.5 0\n-0.5 46\n16.5 47\nend\n";
    CHECK(rs_roads_parse(ctx, text, strlen(text), &t.roads) == RS_OK);
    CHECK(rs_roads_set_attr(ctx, t.roads, 1, "class", "footway") == RS_OK);
    CHECK(rs_roads_set_attr(ctx, t.roads, 2, "class", "service") == RS_OK);
    CHECK(tee_scene_of(&t, NULL));
    CHECK(t.nte == 3);
    const int prio[5] = { 0, 1, 3, 0, 0 };
    const double pix = 1.25, cells[] = { 0, 5, 8, 13, 15.2, 16.3333 };
    enum { W = 60, H = 44 };
    static int ref[W * H];
    int bad = 0, first = -1;
    for (size_t c = 0; c < sizeof cells / sizeof cells[0]; c++) {
        rs__roadfield_params p = params(0, 0, 5, 75, 55, 0, pix);
        p.index_cell = cells[c];
        rs__roadfield *f = NULL;
        CHECK(rs__roadfield_build(ctx, t.roads, &p, &f) == RS_OK && rs__roadfield_set_tees(ctx, f, t.roads, t.te, t.nte) == RS_OK);
        for (int k = 0; f && k < W * H; k++) {
            rs__road_point q;
            memset(&q, 0, sizeof q);
            int got = rs__roadfield_nearest_ranked(f, (k % W + 0.5) * pix, (k / W + 0.5) * pix, pix * 0.70710678118654752,
                                                   prio, &q) ? (int)q.road : -1;
            if (c == 0) ref[k] = got;
            else if (got != ref[k] && bad++ == 0) first = k;
        }
        rs__roadfield_free(ctx, f);
    }
    CHECKF(bad == 0, "%d pixel lookups differ between index cells, first (%d, %d)", bad, first % W, first / W);
    /* (the service road's strip corner is 1.16 m from that pixel's centre) */
    CHECKF(ref[16 * W + 36] == 1, "pixel (36, 16) takes road %d", ref[16 * W + 36]);
    tee_scene_free(&t);
}

/* The count pass's record of visited cells grows to what its first
 * segments foretell for all of them (lib/scene/roadfield.c rec_cell), not
 * by doubling alone, whose copies (most of the record's size in all, one
 * of 16 MB at 10^5 roads) run with no progress call (issue 30 target 4).
 * On 3000 even roads the blocks the builds grow keep at most an eighth of
 * the record's bytes (doubling alone: half to all of them); where the
 * first segments foretell too little (tiny ones, then wide roads) or too
 * much (the other way round), the field is the one the fill makes without
 * a record (every realloc refused). */
static void test_record_foretold(void)
{
    for (int scene = 0; scene < 3; scene++) {
        rs_roads *roads = NULL;
        CHECK(rs_roads_create(ctx, &roads) == RS_OK);
        if (!roads) return;
        sc_rng g;
        sc_rng_seed(&g, 77 + scene);
        double xy[2 * 1201];
        int added = 1;
        for (int part = 0; part < 2; part++) {
            int tiny = scene == 0 ? 0 : (part == 0) == (scene == 1);
            if (tiny) { /* 1200 segments of 0.2 m, 0.5 m wide, in a corner */
                for (int k = 0; k <= 1200; k++) xy[2 * k] = 5 + 0.2 * (k % 40), xy[2 * k + 1] = 5 + 0.5 * (k / 40);
                added &= rs_roads_add(ctx, roads, NULL, 0.5, xy, 1201) == RS_OK;
                continue;
            }
            for (int r = 0; r < (scene == 0 ? 3000 : 40); r++) { /* wide roads of 3 segments over the map */
                double x = sc_rng_range(&g, 0, 400), y = sc_rng_range(&g, 0, 400), a = sc_rng_range(&g, 0, 6.28);
                for (int k = 0; k < 4; k++) xy[2 * k] = x + 25 * k * cos(a + 0.3 * k), xy[2 * k + 1] = y + 25 * k * sin(a + 0.3 * k);
                added &= rs_roads_add(ctx, roads, NULL, scene == 0 ? 8 : 30, xy, 4) == RS_OK;
            }
            if (scene == 0) break;
        }
        CHECK(added);
        rs__roadfield_params p = params(0, 0, 1, 400, 400, 0, 1);
        size_alloc a, b;
        memset(&a, 0, sizeof a);
        memset(&b, 0, sizeof b);
        b.no_realloc = 1;
        rs_allocator al = size_alloc_hook(&a), bl = size_alloc_hook(&b);
        rs_ctx *ca = NULL, *cb = NULL;
        CHECK(rs_ctx_create(&al, NULL, &ca) == RS_OK && rs_ctx_create(&bl, NULL, &cb) == RS_OK);
        rs__roadfield *fa = NULL, *fb = NULL;
        CHECK(ca && rs__roadfield_build(ca, roads, &p, &fa) == RS_OK);
        CHECK(cb && rs__roadfield_build(cb, roads, &p, &fb) == RS_OK);
        if (fa && fb) {
            rs__roadfield_stats sa, sb;
            rs__roadfield_get_stats(fa, &sa);
            rs__roadfield_get_stats(fb, &sb);
            CHECK(sa.segments > 1100);
            CHECK(sa.entries == sb.entries && sa.redundant == sb.redundant && sa.full_cells == sb.full_cells);
            double *ia = coverage_image(fa, 400, 400, 1), *ib = coverage_image(fb, 400, 400, 1);
            CHECK(ia && ib && memcmp(ia, ib, (size_t)400 * 400 * sizeof *ia) == 0);
            free(ia);
            free(ib);
            if (scene == 0) {
                printf("record: %zu entries (%zu bytes), growing blocks kept %zu bytes\n", sa.entries, 4 * sa.entries,
                       a.kept);
                CHECK(2 * a.kept <= sa.entries); /* (an eighth of 4 bytes an entry) */
            }
        }
        rs__roadfield_free(ca, fa);
        rs__roadfield_free(cb, fb);
        rs_ctx_free(ca);
        rs_ctx_free(cb);
        CHECK(a.blocks == 0 && b.blocks == 0);
        rs_roads_free(ctx, roads);
    }
}

/* T clips do not depend on the index cell: a record's segments are
 * clipped by its T lines where their trimmed shapes reach past, strips
 * included. A hairpin whose two ends sit on one road: its second T's strip
 * runs back past the first T's line, which clipped it only at coarse
 * cells (pixels 2.5 m from the first T differed: fuzz/edits, 5 December
 * 2026); and the city at T = 1, where one pixel at a T differed at 2 m
 * cells. The whole coverage is the same doubles at every cell. */
static double *tee_coverage(const rs_roads *roads, const rs__tee_end *te, size_t nte, double cs, double W, double H,
                            double pix, double cell, uint32_t w, uint32_t h)
{
    rs__roadfield_params p = params(0, 0, cs, W, H, 0, pix);
    p.index_cell = cell;
    rs__roadfield *f = NULL;
    double *cov = NULL;
    if (rs__roadfield_build(ctx, roads, &p, &f) == RS_OK && rs__roadfield_set_tees(ctx, f, roads, te, nte) == RS_OK)
        cov = coverage_image(f, w, h, pix);
    rs__roadfield_free(ctx, f);
    return cov;
}

static void test_tee_cells(void)
{
    tee_scene t;
    memset(&t, 0, sizeof t);
    CHECK(tee_scene_of(&t, "road a width 3\n28.5 1\n75.5 59\nend\n"
                           "road b width 4\n-2.5 10\n12.5 25\n59.5 13\nend\n"
                           "road hairpin width 11\n11.5 25\n70.5 24\n27.5 21\nend\n"));
    CHECK(t.nte == 2); /* (both hairpin ends on road b) */
    const double cells[] = { 0, 5, 6, 8, 10, 12 };
    double *ref = tee_coverage(t.roads, t.te, t.nte, 5, 315, 235, 2.5, cells[0], 126, 94);
    CHECK(ref != NULL);
    for (size_t k = 1; ref && k < sizeof cells / sizeof cells[0]; k++) {
        double *cov = tee_coverage(t.roads, t.te, t.nte, 5, 315, 235, 2.5, cells[k], 126, 94);
        CHECKF(cov && memcmp(cov, ref, 126 * 94 * sizeof *cov) == 0, "hairpin: cell %g draws otherwise", cells[k]);
        free(cov);
    }
    /* (the first T's mouth: road b's sliver alone beyond its far edge) */
    CHECKF(ref && ref[9 * 126 + 1] == 0 && ref[9 * 126 + 2] < 0.01, "hairpin: %g %g beyond the first T's line",
           ref ? ref[9 * 126 + 1] : -1, ref ? ref[9 * 126 + 2] : -1);
    free(ref);
    tee_scene_free(&t);

    sc_scene sc;
    CHECK(sc_city_default(&sc, 1) == 0);
    CHECK(rs_roads_create(ctx, &t.roads) == RS_OK);
    for (size_t i = 0; i < sc.nroads; i++)
        CHECK(rs_roads_add(ctx, t.roads, NULL, sc.roads[i].width, sc.roads[i].xy, sc.roads[i].n) == RS_OK);
    CHECK(tee_scene_of(&t, NULL));
    uint32_t w = sc.w - 1, h = sc.h - 1;
    const double ccells[] = { 0, 2, 3, 8 };
    ref = tee_coverage(t.roads, t.te, t.nte, sc.cell_size, sc_extent_x(&sc), sc_extent_y(&sc), sc.cell_size, 0, w, h);
    CHECK(ref != NULL);
    for (size_t k = 1; ref && k < sizeof ccells / sizeof ccells[0]; k++) {
        double *cov = tee_coverage(t.roads, t.te, t.nte, sc.cell_size, sc_extent_x(&sc), sc_extent_y(&sc), sc.cell_size,
                                   ccells[k], w, h);
        size_t diff = 0, at = 0;
        for (size_t i = 0; cov && i < (size_t)w * h; i++)
            if (cov[i] != ref[i]) at = diff++ ? at : i;
        CHECKF(cov && diff == 0, "city T=1: cell %g: %zu pixels differ, the first (%zu, %zu)", ccells[k], diff, at % w,
               at / w);
        free(cov);
    }
    free(ref);
    tee_scene_free(&t);
    sc_scene_free(&sc);
}

static void test_auto_cell(void)
{
    CHECK_NEAR(auto_cell(4, 1, 400), 16, 1e-12);                      /* sparse: twice the mean width */
    CHECK_NEAR(auto_cell(300, 15, 400), sqrt(400.0 * 400 / 4500), 1e-9); /* one segment a cell: 6.0 m */
    CHECK_NEAR(auto_cell(200, 64, 100), 4, 1e-12);                     /* dense: half the width */
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_nearest_conventions();
    test_nearest_brute();
    test_translation();
    test_coverage_random();
    test_coverage_city();
    test_weight_implies_near();
    test_coverage_redundant();
    test_widen();
    test_window();
    test_extreme();
    test_alloc_failures();
    test_record_fallback();
    test_record_foretold();
    test_auto_cell();
    test_tee_repeated_point();
    test_tee_cells();
    test_tee_corner();
    rs_ctx_free(ctx);
    return th_finish("test_roadfield");
}
