/* OpenDRIVE reference-line geometry (lib/input/odr_geom.c, issue 32) against an
 * independent evaluator: composite Simpson integration of the heading with
 * 2*10^5 steps (no Fresnel integrals, no Gauss-Legendre), circles in closed
 * form, poly3 arc length by Simpson and bisection. Positions must agree to
 * 1e-6 m (the bound is 0.02 m); the sampler's polylines must stay
 * within their tolerance of the true curve. */
#include "odr_geom.h"
#include "harness.h"

#include <math.h>
#include <stdlib.h>

static rs_ctx *ctx;

/* ---- the independent evaluator ---------------------------------------------- */
typedef double (*theta_fn)(double u, const void *p);

/* (int_0^s cos theta, int_0^s sin theta) by composite Simpson, n even. */
static void simpson_xy(theta_fn th, const void *p, double s, int n, double *x, double *y)
{
    double h = s / n, sx = 0, sy = 0;
    for (int i = 0; i <= n; i++) {
        double w = (i == 0 || i == n) ? 1 : (i & 1) ? 4 : 2, t = th(i * h, p);
        sx += w * cos(t);
        sy += w * sin(t);
    }
    *x = sx * h / 3;
    *y = sy * h / 3;
}

typedef struct spiral_p { double h, k0, c; } spiral_p;
static double spiral_theta(double u, const void *pp)
{
    const spiral_p *p = pp;
    return p->h + p->k0 * u + p->c * u * u / 2;
}

static double fresnel_c_integrand(double u, const void *p)
{
    (void)p;
    return RS__PI / 2 * u * u;
}

static void test_fresnel(void)
{
    /* C and S are the cos and sin parts of int_0^x exp(i pi t^2 / 2) */
    static const double xs[] = { 0, 0.01, 0.3, 1.0, 1.49, 1.5, 1.51, 2.2, 3.7, 6.0, 11.3, 25.0, -0.7, -4.2 };
    double worst = 0;
    for (size_t i = 0; i < sizeof xs / sizeof *xs; i++) {
        double c, s, rc, rs;
        rs__fresnel(xs[i], &c, &s);
        double ax = fabs(xs[i]);
        simpson_xy(fresnel_c_integrand, NULL, ax, 400000, &rc, &rs);
        if (xs[i] < 0) { rc = -rc; rs = -rs; }
        double e = fmax(fabs(c - rc), fabs(s - rs));
        if (e > worst) worst = e;
        CHECKF(e < 1e-11, "fresnel(%g) = (%.15f, %.15f), Simpson (%.15f, %.15f)", xs[i], c, s, rc, rs);
    }
    /* the limits at infinity: 1/2 each */
    double c, s;
    rs__fresnel(1e3, &c, &s);
    CHECK_NEAR(c, 0.5, 1e-3);
    CHECK_NEAR(s, 0.5, 1e-3);
    printf("fresnel: worst difference to Simpson %.2e\n", worst);
}

static void check_spiral(double h, double k0, double k1, double L)
{
    rs__odr_geom g = { RS__ODR_SPIRAL, 0, 12.5, -7.25, h, L, 0, k0, k1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 };
    CHECK(rs__odr_geom_valid(&g));
    spiral_p p = { h, k0, (k1 - k0) / L };
    double worst = 0, worst_h = 0;
    for (int k = 0; k <= 8; k++) {
        double s = L * k / 8, x, y, hd, rx, ry;
        rs__odr_geom_eval(&g, s, &x, &y, &hd);
        simpson_xy(spiral_theta, &p, s, 200000, &rx, &ry);
        double e = hypot(x - (12.5 + rx), y - (-7.25 + ry));
        if (e > worst) worst = e;
        double eh = fabs(hd - spiral_theta(s, &p));
        if (eh > worst_h) worst_h = eh;
    }
    CHECKF(worst < 1e-6 && worst_h < 1e-12, "spiral k %g..%g over %g m: position error %.3e m, heading %.3e",
           k0, k1, L, worst, worst_h);
}

static void test_spirals(void)
{
    check_spiral(0.3, 0, 0.02, 100);          /* from a straight: the clothoid's origin */
    check_spiral(-1.1, 0.05, -0.05, 80);      /* through an inflection */
    check_spiral(2.0, -0.02, 0, 150);         /* negative rate */
    check_spiral(0.0, 0.1, 0.1000001, 30);    /* nearly an arc: far clothoid origin */
    check_spiral(0.7, 0.001, 0.0012, 1000);   /* long and gentle */
    check_spiral(3.0, 0.2, 0.5, 25);          /* tight */
    check_spiral(0.0, 0, 1e-9, 500);          /* nearly a line */
}

static void test_arc_line(void)
{
    static const double ks[] = { 0.05, -0.013, 1e-9, 2.0 };
    for (size_t i = 0; i < sizeof ks / sizeof *ks; i++) {
        double k = ks[i], h = 0.9, L = 60;
        rs__odr_geom g = { RS__ODR_ARC, 0, 1, 2, h, L, k, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 };
        double worst = 0;
        for (int j = 0; j <= 10; j++) {
            double s = L * j / 10, x, y, hd, rx, ry;
            rs__odr_geom_eval(&g, s, &x, &y, &hd);
            if (fabs(k) > 1e-6) { /* the circle: centre at the left normal, radius 1/k */
                rx = 1 - sin(h) / k + sin(h + k * s) / k;
                ry = 2 + cos(h) / k - cos(h + k * s) / k;
            } else {
                spiral_p p = { h, k, 0 };
                simpson_xy(spiral_theta, &p, s, 20000, &rx, &ry);
                rx += 1;
                ry += 2;
            }
            double e = hypot(x - rx, y - ry);
            if (e > worst) worst = e;
            CHECK_NEAR(hd, h + k * s, 1e-12);
        }
        CHECKF(worst < 1e-9, "arc k = %g: error %.3e m", k, worst);
    }
    rs__odr_geom l = { RS__ODR_LINE, 5, 3, 4, atan2(4, 3), 10, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 };
    double x, y, hd;
    rs__odr_geom_eval(&l, 5, &x, &y, &hd);
    CHECK_NEAR(x, 6, 1e-12);
    CHECK_NEAR(y, 8, 1e-12);
}

/* poly3: the point at arc length s, found independently (Simpson length,
 * bisection on u). */
typedef struct poly_p { double a, b, c, d; } poly_p;
static double poly_len(const poly_p *p, double u)
{
    const int n = 20000;
    double h = u / n, sum = 0;
    for (int i = 0; i <= n; i++) {
        double w = (i == 0 || i == n) ? 1 : (i & 1) ? 4 : 2, t = i * h;
        double dv = p->b + 2 * p->c * t + 3 * p->d * t * t;
        sum += w * sqrt(1 + dv * dv);
    }
    return sum * h / 3;
}

static void test_poly3(void)
{
    const poly_p cases[] = { { 0.5, 0.1, -0.004, 0.00005 }, { 0, 0, 0.01, -0.0002 }, { -1, 0.3, 0, 0 } };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        const poly_p *p = &cases[i];
        const double L = 50, h = -0.4;
        rs__odr_geom g = { RS__ODR_POLY3, 0, 10, 20, h, L, 0, 0, 0, p->a, p->b, p->c, p->d, 0, 0, 0, 0, 0, 0, 0, 0, 0 };
        CHECK(rs__odr_geom_valid(&g));
        double worst = 0;
        for (int j = 0; j <= 5; j++) {
            double s = L * j / 5, lo = 0, hi = s;
            while (hi - lo > 1e-11) {
                double mid = (lo + hi) / 2;
                if (poly_len(p, mid) < s) lo = mid;
                else hi = mid;
            }
            double u = (lo + hi) / 2, v = p->a + u * (p->b + u * (p->c + u * p->d));
            double rx = 10 + u * cos(h) - v * sin(h), ry = 20 + u * sin(h) + v * cos(h), x, y, hd;
            rs__odr_geom_eval(&g, s, &x, &y, &hd);
            double e = hypot(x - rx, y - ry);
            if (e > worst) worst = e;
        }
        CHECKF(worst < 1e-7, "poly3 case %zu: error %.3e m", i, worst);
    }
}

/* paramPoly3: normalized and arcLength forms of one curve agree, and p is
 * taken as the file gives it. */
static void test_parampoly3(void)
{
    const double L = 40, au = 0, bu = 1, cu = 0.002, du = -0.00003, av = 0, bv = 0.05, cv = 0.004, dv = -0.00006;
    rs__odr_geom a = { RS__ODR_PARAMPOLY3, 0, -3, 4, 1.2, L, 0, 0, 0, 0, 0, 0, 0, au, bu, cu, du, av, bv, cv, dv, 0 };
    rs__odr_geom n = a;
    n.normalized = 1;
    n.bu = bu * L; n.cu = cu * L * L; n.du = du * L * L * L;
    n.bv = bv * L; n.cv = cv * L * L; n.dv = dv * L * L * L;
    double worst = 0;
    for (int j = 0; j <= 8; j++) {
        double s = L * j / 8, x1, y1, h1, x2, y2, h2;
        rs__odr_geom_eval(&a, s, &x1, &y1, &h1);
        rs__odr_geom_eval(&n, s, &x2, &y2, &h2);
        double e = hypot(x1 - x2, y1 - y2) + fabs(h1 - h2);
        if (e > worst) worst = e;
        double p = s, u = au + p * (bu + p * (cu + p * du)), v = av + p * (bv + p * (cv + p * dv));
        CHECK_NEAR(x1, -3 + u * cos(1.2) - v * sin(1.2), 1e-9);
        CHECK_NEAR(y1, 4 + u * sin(1.2) + v * cos(1.2), 1e-9);
    }
    CHECKF(worst < 1e-9, "paramPoly3 normalized vs arcLength: %.3e", worst);
}

/* ---- sampling ------------------------------------------------------------------ */
static double lane_t(double s, void *user)
{
    (void)user;
    return 3.5 + 0.02 * s - 0.0001 * s * s;
}

static double dist_to_polyline(const double *v, size_t n, double x, double y)
{
    double best = INFINITY;
    for (size_t i = 0; i + 1 < n; i++) {
        const double *a = v + 3 * i, *b = v + 3 * i + 3;
        double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy;
        double u = l2 > 0 ? ((x - a[0]) * dx + (y - a[1]) * dy) / l2 : 0;
        u = u < 0 ? 0 : u > 1 ? 1 : u;
        double d = hypot(x - a[0] - u * dx, y - a[1] - u * dy);
        if (d < best) best = d;
    }
    return best;
}

static void test_sampling(void)
{
    /* a line, a spiral into an arc, a spiral out, a poly3: contiguous */
    rs__odr_geom g[4];
    memset(g, 0, sizeof g);
    g[0].kind = RS__ODR_LINE; g[0].s = 0; g[0].x = 0; g[0].y = 0; g[0].hdg = 0.2; g[0].length = 30;
    double x, y, h;
    rs__odr_geom_eval(&g[0], 30, &x, &y, &h);
    g[1].kind = RS__ODR_SPIRAL; g[1].s = 30; g[1].x = x; g[1].y = y; g[1].hdg = h; g[1].length = 40;
    g[1].curv_start = 0; g[1].curv_end = 0.04;
    rs__odr_geom_eval(&g[1], 40, &x, &y, &h);
    g[2].kind = RS__ODR_ARC; g[2].s = 70; g[2].x = x; g[2].y = y; g[2].hdg = h; g[2].length = 50; g[2].curv = 0.04;
    rs__odr_geom_eval(&g[2], 50, &x, &y, &h);
    g[3].kind = RS__ODR_POLY3; g[3].s = 120; g[3].x = x; g[3].y = y; g[3].hdg = h; g[3].length = 60;
    g[3].c = -0.003; g[3].d = 0.00004;
    rs__odr_line L = { g, 4 };
    for (int t = 0; t < 2; t++) {
        const double tol = t ? 0.002 : 0.02;
        double *v = NULL;
        size_t n = 0;
        CHECK(rs__odr_sample(ctx, &L, 5, 175, lane_t, NULL, tol, 100000, &v, &n) == RS_OK);
        int mono = n > 2, bounds = 0;
        for (size_t i = 0; i + 1 < n; i++) mono &= v[3 * i + 5] > v[3 * i + 2];
        for (size_t i = 0; i < n; i++) bounds += v[3 * i + 2] == 30 || v[3 * i + 2] == 70 || v[3 * i + 2] == 120;
        CHECK(mono);
        CHECKF(bounds == 3, "record boundaries sampled: %d of 3", bounds);
        CHECK(n > 0 && v[2] == 5 && v[3 * (n - 1) + 2] == 175);
        double worst = 0;
        for (int k = 0; k <= 17000; k++) {
            double s = 5 + 170.0 * k / 17000, px, py, ph;
            rs__odr_line_eval(&L, s, &px, &py, &ph);
            double off = lane_t(s, NULL);
            double d = dist_to_polyline(v, n, px - off * sin(ph), py + off * cos(ph));
            if (d > worst) worst = d;
        }
        CHECKF(worst <= tol * 1.01, "sampled lane boundary within %g m of the curve: %.4f (%zu points)", tol, worst, n);
        printf("sampling at %g m: %zu points, worst %.5f m\n", tol, n, worst);
        rs__free(ctx, v);
    }
    /* the point cap */
    double *v = NULL;
    size_t n = 0;
    CHECK(rs__odr_sample(ctx, &L, 0, 180, lane_t, NULL, 1e-6, 50, &v, &n) == RS_ERR_LIMIT && !v && n == 0);
    CHECK(rs__odr_sample(ctx, &L, 10, 10, lane_t, NULL, 0.01, 50, &v, &n) == RS_ERR_INVALID_ARG);
}

static void test_valid(void)
{
    rs__odr_geom g;
    memset(&g, 0, sizeof g);
    g.kind = RS__ODR_LINE;
    g.length = 10;
    CHECK(rs__odr_geom_valid(&g));
    g.length = 0;
    CHECK(!rs__odr_geom_valid(&g));
    g.length = NAN;
    CHECK(!rs__odr_geom_valid(&g));
    g.length = 10;
    g.kind = RS__ODR_SPIRAL;
    g.curv_end = INFINITY;
    CHECK(!rs__odr_geom_valid(&g));
    g.kind = RS__ODR_POLY3;
    g.curv_end = 0;
    g.d = 1e6; /* slope 3e8 at the end: beyond exact arc length */
    CHECK(!rs__odr_geom_valid(&g));
}

/* A spiral whose curvature does not change is an arc (or a line): no
 * division by its zero rate (UBSan's float-divide-by-zero, found by the odr
 * fuzz target). */
static void test_constant_spiral(void)
{
    const double ks[2] = { 0, 0.01 };
    for (int i = 0; i < 2; i++) {
        rs__odr_geom sp = { RS__ODR_SPIRAL, 0, 3, 4, 0.5, 60, 0, ks[i], ks[i], 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 };
        rs__odr_geom arc = { RS__ODR_ARC, 0, 3, 4, 0.5, 60, ks[i], 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 };
        double x0, y0, h0, x1, y1, h1, worst = 0;
        for (double ds = 0; ds <= 60; ds += 7.5) {
            rs__odr_geom_eval(&sp, ds, &x0, &y0, &h0);
            rs__odr_geom_eval(&arc, ds, &x1, &y1, &h1);
            worst = fmax(worst, fmax(hypot(x0 - x1, y0 - y1), fabs(h0 - h1)));
        }
        CHECKF(worst < 1e-9, "curvature %g: spiral %g from the arc", ks[i], worst);
    }
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_fresnel();
    test_spirals();
    test_arc_line();
    test_poly3();
    test_parampoly3();
    test_sampling();
    test_valid();
    test_constant_spiral();
    rs_ctx_free(ctx);
    return th_finish("test_odr_geom");
}
