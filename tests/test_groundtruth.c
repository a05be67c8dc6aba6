/* Tests of the ruler itself (groundtruth.c) and of the scene generators
 * (scenes.c), against values derived by hand for simple geometry. */
#include "harness.h"
#include "groundtruth.h"
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#define PI 3.14159265358979323846

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

static double overlap(double a0, double a1, double b0, double b1)
{
    double l = a0 > b0 ? a0 : b0, h = a1 < b1 ? a1 : b1;
    return h > l ? h - l : 0;
}

static float *image(const sc_scene *s, unsigned T, size_t *pw, size_t *ph)
{
    *pw = (size_t)(s->w - 1) * T;
    *ph = (size_t)(s->h - 1) * T;
    return calloc(*pw * *ph, sizeof(float));
}

static double sum_area(const float *G, size_t n, double p)
{
    double a = 0;
    size_t i;
    for (i = 0; i < n; i++) a += G[i];
    return a * p * p;
}

/* Distance from x to the nearest multiple of step. */
static double to_grid(double x, double step)
{
    double f = x / step - floor(x / step);
    return (f < 0.5 ? f : 1 - f) * step;
}

/* Axis-aligned roads: coverage is the 1-D overlap, exactly. */
static void test_axis_aligned(void)
{
    sc_scene s;
    unsigned T = 4;
    size_t pw, ph, px, py;
    float *G;
    double p, a = 10.13, b = 17.61, maxerr = 0;
    double xy[4];
    sc_scene_init(&s, 41, 31, 1.0);
    p = s.cell_size / T;
    xy[0] = 0.5 * (a + b); xy[1] = -5; xy[2] = xy[0]; xy[3] = 40;
    sc_add_road(&s, b - a, xy, 2);
    G = image(&s, T, &pw, &ph);
    CHECK(gt_coverage(&s, T, G) == 0);
    for (py = 0; py < ph; py++)
        for (px = 0; px < pw; px++) {
            double e = fabs(G[py * pw + px] - overlap(px * p, (px + 1) * p, a, b) / p);
            if (e > maxerr) maxerr = e;
        }
    CHECKF(maxerr < 1e-6, "vertical road: max |G - exact| = %g", maxerr);
    sc_scene_free(&s);
    free(G);

    /* horizontal: the y direction is the integrated one */
    sc_scene_init(&s, 41, 31, 1.0);
    xy[0] = -5; xy[1] = 0.5 * (a + b); xy[2] = 50; xy[3] = xy[1];
    sc_add_road(&s, b - a, xy, 2);
    G = image(&s, T, &pw, &ph);
    CHECK(gt_coverage(&s, T, G) == 0);
    maxerr = 0;
    for (py = 0; py < ph; py++)
        for (px = 0; px < pw; px++) {
            double e = fabs(G[py * pw + px] - overlap(py * p, (py + 1) * p, a, b) / p);
            if (e > maxerr) maxerr = e;
        }
    CHECKF(maxerr < 1e-6, "horizontal road: max |G - exact| = %g", maxerr);
    /* every pixel is exactly 0 or 1 away from the two edge rows */
    CHECK(G[0] == 0.0f && G[(size_t)(14 / p) * pw + 7] == 1.0f);
    sc_scene_free(&s);
    free(G);
}

/* A straight road with round caps at 45 and 30 degrees: area 2 r len + pi r^2,
 * outline 2 len + 2 pi r. */
static void test_sloped_road_area(void)
{
    double angles[2] = {PI / 4, PI / 6};
    int k;
    for (k = 0; k < 2; k++) {
        sc_scene s;
        unsigned T = 5;
        size_t pw, ph;
        float *G;
        double p, r = 3.3, len = 31.7, area, L;
        sc_scene_init(&s, 61, 51, 1.0);
        p = s.cell_size / T;
        sc_road_straight(&s, angles[k], len, 2 * r);
        G = image(&s, T, &pw, &ph);
        CHECK(gt_coverage(&s, T, G) == 0);
        area = sum_area(G, pw * ph, p);
        CHECKF(fabs(area / (2 * r * len + PI * r * r) - 1) < 1e-6, "angle %g: area %.9g expected %.9g", angles[k],
               area, 2 * r * len + PI * r * r);
        L = gt_outline_length(&s, T);
        CHECK_NEAR(L, 2 * len + 2 * PI * r, 1e-6);
        sc_scene_free(&s);
        free(G);
    }
}

/* A 64-point polyline arc: each joint of turning angle b adds the outer wedge
 * r^2 b / 2 and loses the inner overlap r^2 tan(b/2); its outline gains the
 * outer arc r b and loses 2 r tan(b/2) on the inner side. */
static void test_arc_area(void)
{
    sc_scene s;
    unsigned T = 4;
    size_t pw, ph, n = 64;
    float *G;
    double p, R = 30, r = 4, sweep = 2.2, beta = sweep / (double)(n - 1), seg = 2 * R * sin(beta / 2), area, want, L,
              wantL;
    sc_scene_init(&s, 81, 81, 1.0);
    p = s.cell_size / T;
    sc_road_arc(&s, 40, 40, R, 0.3, 0.3 + sweep, 2 * r, n);
    G = image(&s, T, &pw, &ph);
    CHECK(gt_coverage(&s, T, G) == 0);
    area = sum_area(G, pw * ph, p);
    want = 2 * r * seg * (double)(n - 1) + PI * r * r + (double)(n - 2) * (r * r * beta / 2 - r * r * tan(beta / 2));
    CHECKF(fabs(area / want - 1) < 1e-6, "arc area %.9g expected %.9g", area, want);
    L = gt_outline_length(&s, T);
    wantL = 2 * seg * (double)(n - 1) + 2 * PI * r + (double)(n - 2) * (r * beta - 2 * r * tan(beta / 2));
    CHECK_NEAR(L, wantL, 1e-6);
    sc_scene_free(&s);
    free(G);
}

/* Outline inside the image only; a crossing removes 2r from each of the four
 * sides; a duplicate road adds nothing. */
static void test_outline(void)
{
    sc_scene s;
    double xy[4], r = 2.5, ex, ey;
    sc_scene_init(&s, 51, 41, 2.0);
    ex = sc_extent_x(&s);
    ey = sc_extent_y(&s);
    xy[0] = 33.3; xy[1] = -10; xy[2] = 33.3; xy[3] = ey + 10;
    sc_add_road(&s, 2 * r, xy, 2);
    CHECK_NEAR(gt_outline_length(&s, 4), 2 * ey, 1e-6);
    xy[0] = -10; xy[1] = 41.1; xy[2] = ex + 10; xy[3] = 41.1;
    sc_add_road(&s, 2 * r, xy, 2);
    CHECK_NEAR(gt_outline_length(&s, 4), 2 * ey + 2 * ex - 8 * r, 1e-6);
    sc_add_road(&s, 2 * r, xy, 2); /* the same road again */
    CHECK_NEAR(gt_outline_length(&s, 4), 2 * ey + 2 * ex - 8 * r, 1e-6);
    /* a road ending inside the map: one cap */
    sc_scene_free(&s);
    sc_scene_init(&s, 51, 41, 2.0);
    xy[0] = 20; xy[1] = 30; xy[2] = -20; xy[3] = 30;
    sc_add_road(&s, 2 * r, xy, 2);
    CHECK_NEAR(gt_outline_length(&s, 4), 2 * 20 + PI * r, 1e-6);
    sc_scene_free(&s);
}

/* Junction grid: nx + ny streets with round caps crossing in nx*ny X
 * junctions; each crossing double-counts a (2r)^2 square of area and removes
 * 2r from each of the four sides it cuts. A road leaving the map ends
 * outside it, and its G is 1 along its centreline away from the edges. */
static void test_grid_and_leaving(void)
{
    sc_scene s;
    unsigned T = 4, nx = 3, ny = 2;
    size_t pw, ph, k, i, bad = 0;
    float *G;
    double p, r = 2.3, m = 7.3, lv, lh, area, want, L, wantL, *q;
    sc_scene_init(&s, 81, 61, 1.0);
    p = s.cell_size / T;
    CHECK(sc_road_grid(&s, nx, ny, 2 * r, m) == 0);
    CHECK_EQ_INT(s.nroads, nx + ny);
    lv = sc_extent_y(&s) - 2 * m;
    lh = sc_extent_x(&s) - 2 * m;
    G = image(&s, T, &pw, &ph);
    CHECK(gt_coverage(&s, T, G) == 0);
    area = sum_area(G, pw * ph, p);
    want = nx * (2 * r * lv + PI * r * r) + ny * (2 * r * lh + PI * r * r) - nx * ny * 4 * r * r;
    CHECKF(fabs(area / want - 1) < 1e-6, "grid area %.9g expected %.9g", area, want);
    L = gt_outline_length(&s, T);
    wantL = nx * (2 * lv + 2 * PI * r) + ny * (2 * lh + 2 * PI * r) - nx * ny * 8 * r;
    CHECK_NEAR(L, wantL, 1e-6);
    sc_scene_free(&s);
    free(G);

    sc_scene_init(&s, 81, 61, 1.0);
    CHECK(sc_road_leaving(&s, 0.4, 5, 20) == 0);
    q = s.roads[0].xy + 2 * (s.roads[0].n - 1);
    CHECK(q[0] > sc_extent_x(&s) + 5 || q[1] > sc_extent_y(&s) + 5); /* outside, bottom-right */
    G = image(&s, T, &pw, &ph);
    CHECK(gt_coverage(&s, T, G) == 0);
    for (k = 0; k + 1 < s.roads[0].n; k++) /* sample the centreline */
        for (i = 0; i <= 50; i++) {
            const double *a = s.roads[0].xy + 2 * k;
            double x = a[0] + (a[2] - a[0]) * i / 50.0, y = a[1] + (a[3] - a[1]) * i / 50.0;
            if (x < 3 || y < 3 || x > sc_extent_x(&s) - 3 || y > sc_extent_y(&s) - 3) continue;
            if (G[(size_t)(y / p) * pw + (size_t)(x / p)] != 1.0f) bad++;
        }
    CHECK(bad == 0);
    sc_scene_free(&s);
    free(G);
}

/* Vertical road through the whole map at a random sub-pixel position. Per
 * edge and unit length, the hard raster's |R - G| is the distance from the
 * edge to the nearest pixel boundary (the centre decides the whole pixel),
 * and the cell buffer's is the distance to the nearest DEM cell boundary. */
static void test_references(void)
{
    sc_rng g;
    int trial;
    sc_rng_seed(&g, 12345);
    for (trial = 0; trial < 6; trial++) {
        sc_scene s;
        unsigned T = 4;
        size_t pw, ph;
        float *R;
        double p, xy[4], w = sc_rng_range(&g, 5.5, 12), xc = sc_rng_range(&g, 30, 60), want;
        gt_result res;
        sc_scene_init(&s, 101, 41, 1.0);
        p = s.cell_size / T;
        xy[0] = xc; xy[1] = -3; xy[2] = xc; xy[3] = 43;
        sc_add_road(&s, w, xy, 2);
        R = image(&s, T, &pw, &ph);
        CHECK(gt_hard_raster(&s, T, R) == 0);
        CHECK(gt_edge_error(&s, T, R, &res) == 0);
        want = 0.5 * (to_grid(xc - w / 2, p) + to_grid(xc + w / 2, p));
        CHECKF(fabs(res.edge_error - want) < 1e-6, "hard raster %.9g expected %.9g", res.edge_error, want);
        CHECK_NEAR(res.outline, 2 * sc_extent_y(&s), 1e-6);
        /* the drawn edge sits on a pixel boundary: displacement = that distance */
        CHECK(res.max_disp <= p / 2 + 1e-9);
        CHECK(gt_cell_buffer(&s, T, R) == 0);
        CHECK(gt_edge_error(&s, T, R, &res) == 0);
        want = 0.5 * (to_grid(xc - w / 2, s.cell_size) + to_grid(xc + w / 2, s.cell_size));
        CHECKF(fabs(res.edge_error - want) < 1e-6, "cell buffer %.9g expected %.9g", res.edge_error, want);
        sc_scene_free(&s);
        free(R);
    }
}

/* R = G scores 0; G shifted one pixel right scores p sin(theta) for a road at
 * angle theta leaving through the top and bottom edges (each row's G profile
 * rises 0 -> 1 and falls 1 -> 0 once, so sum |G(x) - G(x-1)| = 2 per row). */
static void test_identity_and_shift(void)
{
    sc_scene s;
    unsigned T = 4;
    size_t pw, ph, px, py;
    float *G, *R;
    double p, th = PI / 3;
    gt_result res;
    sc_scene_init(&s, 61, 41, 1.0);
    p = s.cell_size / T;
    sc_road_straight(&s, th, 200, 6.5);
    G = image(&s, T, &pw, &ph);
    R = image(&s, T, &pw, &ph);
    CHECK(gt_coverage(&s, T, G) == 0);
    CHECK(gt_edge_error(&s, T, G, &res) == 0);
    CHECK(res.edge_error == 0);
    CHECK(res.contour_points > 2 * ph);
    CHECKF(res.max_disp < 0.15 * p, "max disp of G itself %g", res.max_disp);
    for (py = 0; py < ph; py++)
        for (px = 0; px < pw; px++) R[py * pw + px] = px ? G[py * pw + px - 1] : 0.0f;
    CHECK(gt_edge_error_g(&s, T, G, -1, R, &res) == 0);
    CHECKF(fabs(res.edge_error / (p * sin(th)) - 1) < 1e-9, "shift: %.9g expected %.9g", res.edge_error, p * sin(th));
    CHECK_NEAR(res.outline, 2 * sc_extent_y(&s) / sin(th), 1e-6);
    CHECKF(res.max_disp > 0.8 * p * sin(th) && res.max_disp < 1.2 * p, "shift max disp %g", res.max_disp);
    sc_scene_free(&s);
    free(G);
    free(R);
}

/* sd is exact outside, and far points fall back to the ring search. */
static void test_signed_distance(void)
{
    sc_scene s;
    gt_index *ix;
    double xy[4] = {10, 10, 30, 10};
    sc_scene_init(&s, 201, 201, 1.0);
    sc_add_road(&s, 4, xy, 2);
    ix = gt_index_new(&s, 0.5);
    CHECK(ix != NULL);
    CHECK_NEAR(gt_signed_distance(ix, 20, 10), -2, 1e-12);
    CHECK_NEAR(gt_signed_distance(ix, 20, 15), 3, 1e-12);
    CHECK_NEAR(gt_signed_distance(ix, 190, 190), sqrt(160.0 * 160 + 180 * 180) - 2, 1e-9);
    CHECK_NEAR(gt_signed_distance(ix, -50, 10), 58, 1e-9); /* off the grid */
    gt_index_free(ix);
    sc_scene_free(&s);
}

static void test_generators(void)
{
    sc_scene a, b;
    float *z;
    size_t i, same = 1, n = 1025 * 1025;
    float lo = 1e30f, hi = -1e30f;
    sc_rng r1, r2;
    sc_rng_seed(&r1, 7);
    sc_rng_seed(&r2, 7);
    CHECK(sc_rng_u64(&r1) == sc_rng_u64(&r2));
    CHECK(sc_rng_unit(&r1) < 1.0);

    z = malloc(n * sizeof *z);
    sc_dem_fractal(z, 1025, 1025, 3, 0.5);
    for (i = 0; i < n; i++) { if (z[i] < lo) lo = z[i]; if (z[i] > hi) hi = z[i]; }
    CHECK(lo == 0.0f && hi == 65535.0f);
    sc_dem_checker(z, 4, 3, 1);
    CHECK(z[0] == 0 && z[1] == 65535 && z[4] == 65535 && z[5] == 0);
    sc_dem_spike(z, 5, 5, 10, 65535, 2, 3);
    CHECK(z[13] == 65535 && z[12] == 10);
    sc_dem_ridge(z, 9, 9, 0, 2, 1000);
    CHECK(z[4 * 9 + 0] == 1000 && z[3 * 9 + 5] == 500 && z[0] == 0);
    free(z);

    CHECK(sc_city(&a, 160, 120, 5, 90, 42) == 0);
    CHECK(sc_city(&b, 160, 120, 5, 90, 42) == 0);
    CHECK(a.nroads == b.nroads && a.nroads >= 60 && a.nroads <= 120);
    for (i = 0; i < a.nroads && same; i++)
        same = a.roads[i].n == b.roads[i].n && a.roads[i].width == b.roads[i].width &&
               memcmp(a.roads[i].xy, b.roads[i].xy, 2 * a.roads[i].n * sizeof(double)) == 0;
    CHECK(same && memcmp(a.z, b.z, (size_t)a.w * a.h * sizeof(float)) == 0);
    for (i = 0; i < a.nroads; i++) CHECK(a.roads[i].width >= 4 && a.roads[i].width <= 14);
    sc_scene_free(&b);
    CHECK(sc_city(&b, 160, 120, 5, 90, 43) == 0);
    CHECK(b.nroads != a.nroads || memcmp(a.roads[0].xy, b.roads[0].xy, 2 * sizeof(double)) != 0);
    sc_scene_free(&b);

    /* writers round-trip */
    {
        char path[] = "/tmp/rs_gt_XXXXXX";
        int fd = mkstemp(path);
        FILE *f;
        unsigned char hdr[32];
        float zz[6] = {0, 1, 256, 65535, 70000, -3};
        CHECK(fd >= 0);
        if (fd >= 0) close(fd);
        CHECK(sc_write_pgm16(path, 3, 2, zz) == 0);
        f = fopen(path, "rb");
        CHECK(f && fread(hdr, 1, 25, f) == 25);
        if (f) fclose(f);
        CHECK(memcmp(hdr, "P5\n3 2\n65535\n", 13) == 0);
        /* big-endian, rounded, clamped: 0, 1, 256, 65535, 65535, 0 */
        CHECK(hdr[13] == 0 && hdr[14] == 0 && hdr[15] == 0 && hdr[16] == 1 && hdr[17] == 1 && hdr[18] == 0);
        CHECK(hdr[19] == 255 && hdr[20] == 255 && hdr[21] == 255 && hdr[22] == 255 && hdr[23] == 0 && hdr[24] == 0);

        CHECK(sc_write_roads(path, &a, "made by test\nsecond line") == 0);
        f = fopen(path, "r");
        if (f) {
            char line[256], name[64];
            size_t road = 0, pt = 0, bad = 0, comments = 0;
            double w, x, y;
            while (fgets(line, sizeof line, f)) {
                if (line[0] == '#') comments++;
                else if (sscanf(line, "road %63s width %lf", name, &w) == 2) {
                    if (road >= a.nroads || w != a.roads[road].width) bad++;
                    pt = 0;
                } else if (strncmp(line, "end", 3) == 0) {
                    if (road < a.nroads && pt != a.roads[road].n) bad++;
                    road++;
                } else if (sscanf(line, "%lf %lf", &x, &y) == 2) {
                    if (road >= a.nroads || pt >= a.roads[road].n || x != a.roads[road].xy[2 * pt] ||
                        y != a.roads[road].xy[2 * pt + 1])
                        bad++;
                    pt++;
                } else
                    bad++;
            }
            fclose(f);
            CHECK(bad == 0 && road == a.nroads && comments == 2);
        } else
            CHECK(f != NULL);
        remove(path);
    }
    sc_scene_free(&a);
}

/* The reference numbers on the city scene (400 x 350, 5 m, T = 4):
 * a perfect hard raster ~0.32 m (p/4 = 0.3125 for p = 1.25 m: each edge is on
 * average a quarter pixel from the nearest pixel boundary), a 5 m cell
 * buffer ~1.2 m (5/4 = 1.25 for straight edges; junction corners and
 * narrow roads move it). Measured for seed 1: 0.3077 m and 1.2087 m (seeds
 * 2-4: 0.305-0.306 m and 1.202-1.209 m; printed on stdout). The ranges below
 * bracket that loosely; they fail if the ruler or the scene drifts. */
static void test_city_references(void)
{
    sc_scene s;
    unsigned T = 4;
    size_t pw, ph;
    float *G, *R;
    double t0, tcov, L;
    gt_result hr, cb;
    CHECK(sc_city_default(&s, 1) == 0);
    G = image(&s, T, &pw, &ph);
    R = image(&s, T, &pw, &ph);
    t0 = now_s();
    CHECK(gt_coverage(&s, T, G) == 0);
    tcov = now_s() - t0;
    t0 = now_s();
    L = gt_outline_length(&s, T);
    printf("city: %zu roads, %zux%zu px, coverage %.2f s, outline %.1f m in %.2f s\n", s.nroads, pw, ph, tcov, L,
           now_s() - t0);
    CHECK(gt_hard_raster(&s, T, R) == 0);
    CHECK(gt_edge_error_g(&s, T, G, L, R, &hr) == 0);
    CHECK(gt_cell_buffer(&s, T, R) == 0);
    CHECK(gt_edge_error_g(&s, T, G, L, R, &cb) == 0);
    printf("city: hard raster edge error %.4f m (max %.3f m), cell buffer %.4f m (max %.3f m)\n", hr.edge_error,
           hr.max_disp, cb.edge_error, cb.max_disp);
    CHECKF(hr.edge_error > 0.29 && hr.edge_error < 0.34, "hard raster %g", hr.edge_error);
    CHECKF(cb.edge_error > 1.0 && cb.edge_error < 1.4, "cell buffer %g", cb.edge_error);
    /* the hard raster's contour is the midpoint of two centres on either side
     * of the outline, so it is within p/2 of it */
    CHECK(hr.max_disp <= 0.625 + 1e-9);
    sc_scene_free(&s);
    free(G);
    free(R);
}

int main(void)
{
    test_axis_aligned();
    test_sloped_road_area();
    test_arc_area();
    test_outline();
    test_grid_and_leaving();
    test_references();
    test_identity_and_shift();
    test_signed_distance();
    test_generators();
    test_city_references();
    return th_finish("test_groundtruth");
}
