/* OpenDRIVE reference-line geometry (lib/input/odr_geom.h, docs/opendrive.md). */
#include "odr_geom.h"

#include <complex.h>
#include <float.h>
#include <math.h>

/* ---- Fresnel integrals ------------------------------------------------------
 * Small |x|: the power series of the complex integral int_0^x exp(i pi t^2/2),
 * whose terms (i pi x^2/2)^k / k! x / (2k+1) alternate between C and S.
 * Large |x|: a continued fraction for the complementary error function, as
 * in the classic Lentz evaluation (the series cancels there, the fraction
 * converges fast). Both reach about 1e-15 absolute; tests/test_odr_geom.c
 * checks them against Gauss-Legendre quadrature. */
void rs__fresnel(double x, double *c, double *s)
{
    double ax = fabs(x);
    double cc, ss;
    if (ax < 1.5) {
        double z = RS__PI / 2 * ax * ax, term = ax; /* (z^k / k!) ax */
        cc = 0;
        ss = 0;
        for (int k = 0; k < 60; k++) {
            double t = term / (2 * k + 1);
            switch (k & 3) {
            case 0: cc += t; break;
            case 1: ss += t; break;
            case 2: cc -= t; break;
            default: ss -= t; break;
            }
            term *= z / (k + 1);
            if (term < 1e-18 * (cc > 0 ? cc : 1e-300) && k > 2) break;
        }
    } else {
        const double pix2 = RS__PI * ax * ax;
        double complex b = 1.0 - I * pix2, cf = 1e300, d = 1.0 / b, h = d;
        double n = -1;
        for (int k = 2; k < 1000; k++) {
            n += 2;
            double a = -n * (n + 1);
            b += 4.0;
            d = 1.0 / (a * d + b);
            cf = b + a / cf;
            double complex del = cf * d;
            h *= del;
            if (fabs(creal(del) - 1.0) + fabs(cimag(del)) < 1e-16) break;
        }
        h *= ax - I * ax;
        /* the phase pi x^2 / 2 reduced exactly in whole turns of 2 pi would
         * need more than double; its rounding is below the result's error
         * for |x| < 1e4, and callers stay there (docs/opendrive.md) */
        double complex cs = (0.5 + 0.5 * I) * (1.0 - (cos(0.5 * pix2) + I * sin(0.5 * pix2)) * h);
        cc = creal(cs);
        ss = cimag(cs);
    }
    *c = x < 0 ? -cc : cc;
    *s = x < 0 ? -ss : ss;
}

/* ---- Gauss-Legendre, 8 points on [-1, 1] --------------------------------- */
static const double gl_x[4] = { 0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363 };
static const double gl_w[4] = { 0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763 };

/* int_0^ds exp(i (k0 u + c u^2 / 2)) du, by composite Gauss-Legendre with
 * pieces over which the phase turns at most 1/4 rad (exact to rounding for
 * this smooth integrand). */
static double complex phase_integral_gl(double k0, double c, double ds)
{
    double turn = fabs(k0) * ds + fabs(c) * ds * ds / 2;
    double m = ceil(turn / 0.25);
    if (m < 1) m = 1;
    if (m > 1e6) m = 1e6;
    double h = ds / m;
    double complex sum = 0;
    for (double p = 0; p < m; p++) {
        double mid = (p + 0.5) * h, half = h / 2;
        for (int q = 0; q < 4; q++)
            for (int sg = -1; sg <= 1; sg += 2) {
                double u = mid + sg * half * gl_x[q];
                double ph = k0 * u + c * u * u / 2;
                sum += gl_w[q] * half * (cos(ph) + I * sin(ph));
            }
    }
    return sum;
}

/* The same integral through Fresnel integrals: k0 u + c u^2/2 =
 * (c/2)(u + k0/c)^2 - k0^2/(2c); with a = sqrt(|c|/pi), tau = a (u + k0/c)
 * the integral is exp(-i k0^2/(2c)) / a [dC + i sgn(c) dS] over tau. */
static double complex phase_integral_fresnel(double k0, double c, double ds)
{
    double a = sqrt(fabs(c) / RS__PI), t0 = k0 / c;
    double ca, sa, cb, sb;
    rs__fresnel(a * t0, &ca, &sa);
    rs__fresnel(a * (t0 + ds), &cb, &sb);
    double sg = c > 0 ? 1 : -1, ph = -k0 * k0 / (2 * c);
    double complex v = ((cb - ca) + I * sg * (sb - sa)) / a;
    return (cos(ph) + I * sin(ph)) * v;
}

/* Spiral from curvature k0 with dk/ds = c: int_0^ds exp(i theta(u)) du
 * relative to the start heading. The Fresnel form loses digits when the
 * clothoid's origin is far away (|k0/c| large: two nearly equal Fresnel
 * values scaled by 1/a) or its argument is large; there the quadrature,
 * exact for this smooth integrand, is used instead. */
static double complex spiral_integral(double k0, double c, double ds)
{
    if (c != 0) { /* a spiral of constant curvature is an arc: no 1/c */
        double a = sqrt(fabs(c) / RS__PI), tmax = fabs(k0 / c) + ds;
        if (a * tmax < 50 && 1 / a < 1e6) return phase_integral_fresnel(k0, c, ds);
    }
    return phase_integral_gl(k0, c, ds);
}

/* ---- poly3 arc length ------------------------------------------------------ */
static double poly3_dv(const rs__odr_geom *g, double u)
{
    return g->b + u * (2 * g->c + 3 * g->d * u);
}

/* int_0^u sqrt(1 + v'(w)^2) dw, composite Gauss-Legendre (16 pieces: v' is
 * quadratic, the integrand smooth; error far below 1e-9 m for the
 * coefficient range rs__odr_geom_valid admits). */
static double poly3_length(const rs__odr_geom *g, double u)
{
    const int m = 16;
    double h = u / m, sum = 0;
    for (int p = 0; p < m; p++) {
        double mid = (p + 0.5) * h, half = h / 2;
        for (int q = 0; q < 4; q++)
            for (int sg = -1; sg <= 1; sg += 2) {
                double dv = poly3_dv(g, mid + sg * half * gl_x[q]);
                sum += gl_w[q] * half * sqrt(1 + dv * dv);
            }
    }
    return sum;
}

/* u with poly3_length(u) = ds: Newton from u = ds (the length grows at
 * least as fast as u, so the iteration is monotone from the right side). */
static double poly3_u(const rs__odr_geom *g, double ds)
{
    double u = ds;
    for (int it = 0; it < 50; it++) {
        double f = poly3_length(g, u) - ds, dv = poly3_dv(g, u);
        double step = f / sqrt(1 + dv * dv);
        u -= step;
        if (u < 0) u = 0;
        if (fabs(step) < 1e-12 * (1 + fabs(u))) break;
    }
    return u;
}

void rs__odr_geom_eval(const rs__odr_geom *g, double ds, double *x, double *y, double *hdg)
{
    if (!(ds > 0)) ds = 0;
    if (ds > g->length) ds = g->length;
    const double ch = cos(g->hdg), sh = sin(g->hdg);
    double u = 0, v = 0, dh = 0;
    switch (g->kind) {
    case RS__ODR_LINE:
        u = ds;
        break;
    case RS__ODR_ARC: {
        double k = g->curv, half = k * ds / 2;
        /* chord 2 sin(k ds / 2) / k at half the turn: no 1/k cancellation */
        double chord = fabs(half) < 1e-8 ? ds * (1 - half * half / 6) : 2 * sin(half) / k;
        u = chord * cos(half);
        v = chord * sin(half);
        dh = k * ds;
        break;
    }
    case RS__ODR_SPIRAL: {
        double k0 = g->curv_start, c = (g->curv_end - g->curv_start) / g->length;
        double complex z = spiral_integral(k0, c, ds);
        u = creal(z);
        v = cimag(z);
        dh = k0 * ds + c * ds * ds / 2;
        break;
    }
    case RS__ODR_POLY3: {
        double uu = poly3_u(g, ds);
        u = uu;
        v = g->a + uu * (g->b + uu * (g->c + uu * g->d));
        dh = atan(poly3_dv(g, uu));
        break;
    }
    case RS__ODR_PARAMPOLY3: {
        double p = g->normalized ? ds / g->length : ds;
        u = g->au + p * (g->bu + p * (g->cu + p * g->du));
        v = g->av + p * (g->bv + p * (g->cv + p * g->dv));
        double du = g->bu + p * (2 * g->cu + 3 * g->du * p), dv = g->bv + p * (2 * g->cv + 3 * g->dv * p);
        dh = du == 0 && dv == 0 ? 0 : atan2(dv, du);
        break;
    }
    }
    *x = g->x + u * ch - v * sh;
    *y = g->y + u * sh + v * ch;
    *hdg = g->hdg + dh;
}

static int finite_all(const double *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

int rs__odr_geom_valid(const rs__odr_geom *g)
{
    const double pos[5] = { g->s, g->x, g->y, g->hdg, g->length };
    if (!finite_all(pos, 5) || !(g->length > 0) || g->length > 1e7 || fabs(g->x) > 1e9 || fabs(g->y) > 1e9 ||
        fabs(g->hdg) > 1e6)
        return 0;
    switch (g->kind) {
    case RS__ODR_LINE: return 1;
    case RS__ODR_ARC: return isfinite(g->curv) && fabs(g->curv) <= 1e4;
    case RS__ODR_SPIRAL:
        return isfinite(g->curv_start) && isfinite(g->curv_end) && fabs(g->curv_start) <= 1e4 &&
               fabs(g->curv_end) <= 1e4;
    case RS__ODR_POLY3: {
        const double k[4] = { g->a, g->b, g->c, g->d };
        /* the slope must stay where the arc-length integral and its
         * inversion are exact: |v'| <= 1e4 over the record */
        if (!finite_all(k, 4)) return 0;
        double L = g->length, worst = fabs(g->b) + 2 * fabs(g->c) * L + 3 * fabs(g->d) * L * L;
        return worst <= 1e4 && fabs(g->a) <= 1e9;
    }
    case RS__ODR_PARAMPOLY3: {
        const double k[8] = { g->au, g->bu, g->cu, g->du, g->av, g->bv, g->cv, g->dv };
        if (!finite_all(k, 8)) return 0;
        double P = g->normalized ? 1 : g->length, big = 0;
        for (int i = 0; i < 2; i++) {
            const double *q = k + 4 * i;
            double m = fabs(q[0]) + fabs(q[1]) * P + fabs(q[2]) * P * P + fabs(q[3]) * P * P * P;
            if (m > big) big = m;
        }
        return big <= 1e9;
    }
    }
    return 0;
}

/* ---- a road's reference line ---------------------------------------------- */
static size_t record_at(const rs__odr_line *L, double s)
{
    size_t lo = 0, hi = L->n;
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (L->g[mid].s <= s) lo = mid;
        else hi = mid;
    }
    return lo;
}

void rs__odr_line_eval(const rs__odr_line *L, double s, double *x, double *y, double *hdg)
{
    const rs__odr_geom *g = &L->g[record_at(L, s)];
    rs__odr_geom_eval(g, s - g->s, x, y, hdg);
}

static void offset_point(const rs__odr_line *L, double s, rs__odr_offset_fn t, void *user, double *p)
{
    double x, y, h;
    rs__odr_line_eval(L, s, &x, &y, &h);
    double off = t ? t(s, user) : 0;
    p[0] = x - off * sin(h);
    p[1] = y + off * cos(h);
    p[2] = s;
}

static double chord_distance(const double *a, const double *b, const double *p)
{
    double dx = b[0] - a[0], dy = b[1] - a[1], l2 = dx * dx + dy * dy;
    double wx = p[0] - a[0], wy = p[1] - a[1];
    double u = l2 > 0 ? (wx * dx + wy * dy) / l2 : 0;
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    return hypot(wx - u * dx, wy - u * dy);
}

typedef struct sample_out {
    rs_ctx *ctx;
    double *v;
    size_t n, cap, max;
} sample_out;

static rs_result push(sample_out *o, const double *p)
{
    if (o->n >= o->max) return rs__fail(o->ctx, RS_ERR_LIMIT, "OpenDRIVE sampling needs more than %zu points", o->max);
    if (o->n == o->cap) {
        size_t cap = o->cap ? 2 * o->cap : 64;
        double *v = rs__realloc(o->ctx, o->v, cap * 3 * sizeof *v);
        if (!v) return rs__fail(o->ctx, RS_ERR_NOMEM, "out of memory for %zu OpenDRIVE samples", cap);
        o->v = v;
        o->cap = cap;
    }
    for (int k = 0; k < 3; k++) o->v[3 * o->n + (size_t)k] = p[k];
    o->n++;
    return RS_OK;
}

/* Samples (sa, sb] after the caller pushed the point at sa: refine until the
 * quarter points lie within tol of the chord (explicit stack, depth <= 48). */
static rs_result sample_span(sample_out *o, const rs__odr_line *L, double sa, double sb, rs__odr_offset_fn t,
                             void *user, double tol)
{
    struct { double s0, s1; int depth; } st[64];
    int top = 0;
    st[top].s0 = sa;
    st[top].s1 = sb;
    st[top].depth = 0;
    top++;
    while (top > 0) {
        top--;
        double s0 = st[top].s0, s1 = st[top].s1;
        int depth = st[top].depth;
        double a[3], b[3], q[3];
        offset_point(L, s0, t, user, a);
        offset_point(L, s1, t, user, b);
        int fine = depth >= 48;
        for (int k = 1; k <= 3 && !fine; k++) {
            offset_point(L, s0 + (s1 - s0) * k / 4, t, user, q);
            if (chord_distance(a, b, q) > tol) break;
            if (k == 3) fine = 1;
        }
        if (fine) {
            rs_result r = push(o, b);
            if (r != RS_OK) return r;
            continue;
        }
        double mid = s0 + (s1 - s0) / 2;
        /* right half below the left one: the left is done first */
        st[top].s0 = mid; st[top].s1 = s1; st[top].depth = depth + 1; top++;
        st[top].s0 = s0; st[top].s1 = mid; st[top].depth = depth + 1; top++;
    }
    return RS_OK;
}

rs_result rs__odr_sample(rs_ctx *ctx, const rs__odr_line *L, double s0, double s1, rs__odr_offset_fn t, void *user,
                         double tol, size_t max_points, double **xys, size_t *n)
{
    *xys = NULL;
    *n = 0;
    if (!L || L->n == 0 || !(s1 > s0) || !(tol > 0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "OpenDRIVE sampling: empty line, range or tolerance");
    sample_out o = { ctx, NULL, 0, 0, max_points ? max_points : 1 };
    double p[3];
    offset_point(L, s0, t, user, p);
    rs_result r = push(&o, p);
    /* spans: record boundaries inside (s0, s1), and at most 8 m each (a
     * lane polynomial or a poly3 may bend twice within a long span, which
     * quarter points alone could miss) */
    double a = s0;
    size_t i = record_at(L, s0);
    while (r == RS_OK && a < s1) {
        double b = i + 1 < L->n && L->g[i + 1].s < s1 ? L->g[i + 1].s : s1;
        if (b <= a) { i++; continue; }
        double len = b - a;
        double pieces = ceil(len / 8);
        for (double k = 1; k <= pieces && r == RS_OK; k++) {
            double e = k == pieces ? b : a + len * k / pieces;
            double st0 = a + len * (k - 1) / pieces;
            r = sample_span(&o, L, st0, e, t, user, tol);
        }
        a = b;
        i++;
    }
    if (r != RS_OK) {
        rs__free(ctx, o.v);
        return r;
    }
    *xys = o.v;
    *n = o.n;
    return RS_OK;
}
